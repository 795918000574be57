//! What the GL can do, probed once after the context is made, and the fallback each missing
//! feature selects.
//!
//! Features are tested by using them (attach a depth texture and check completeness, run a timer
//! query, copy depth) rather than by trusting extension strings alone.
//!
//! On an OpenGL ES context the renderer uses ES 3.0 and GLSL ES 3.00 (whatever 3.x the driver
//! gives), so features ES 3.0 lacks are reported missing unless an ES extension gives them:
//! clip distances (none in GLSL ES 3.00), depth clamp (`GL_EXT_depth_clamp`), timer queries
//! (`GL_EXT_disjoint_timer_query`), depth copies (ES's glCopyTexSubImage2D takes colour only;
//! some drivers accept depth anyway, which is not relied on).

use glow::HasContext;
use serde::Serialize;
use std::collections::BTreeSet;

/// One pipeline feature: whether it works here and, if not, what replaces it.
#[derive(Debug, Clone, Serialize)]
pub struct Feature {
    /// Short stable name, e.g. `timer_query`.
    pub key: &'static str,
    pub supported: bool,
    /// What the probe saw.
    pub detail: String,
    /// What the pipeline does without it.
    pub fallback: &'static str,
}

/// The probe's results.
#[derive(Debug, Clone, Serialize)]
pub struct Caps {
    pub vendor: String,
    pub renderer: String,
    pub version: String,
    pub glsl_version: String,
    pub major: i32,
    pub minor: i32,
    pub profile: &'static str,
    /// Bits of our own framebuffer's depth and stencil attachment.
    pub depth_bits: i32,
    pub stencil_bits: i32,
    pub max_texture_size: i32,
    pub max_cube_map_size: i32,
    pub max_renderbuffer_size: i32,
    pub max_clip_distances: i32,
    pub extension_count: usize,
    pub features: Vec<Feature>,
    #[serde(skip)]
    pub extensions: BTreeSet<String>,
}

impl Caps {
    pub fn has(&self, key: &str) -> bool {
        self.features.iter().any(|f| f.key == key && f.supported)
    }

    /// One line per feature that is missing: the fallback in use.
    pub fn fallbacks(&self) -> Vec<String> {
        self.features
            .iter()
            .filter(|f| !f.supported)
            .map(|f| format!("{}: {} -> {}", f.key, f.detail, f.fallback))
            .collect()
    }

    /// These capabilities with the features `keys` reported missing (`gl.disable`).
    pub fn with_disabled(&self, keys: &[&str]) -> Caps {
        let mut caps = self.clone();
        for f in caps.features.iter_mut().filter(|f| keys.contains(&f.key)) {
            if f.supported {
                f.supported = false;
                f.detail = format!("disabled by gl.disable ({})", f.detail);
            }
        }
        caps
    }

    /// Whether the renderer is Mesa's software rasterizer.
    pub fn is_software(&self) -> bool {
        let r = self.renderer.to_ascii_lowercase();
        r.contains("llvmpipe") || r.contains("softpipe") || r.contains("swrast")
    }
}

fn get_i(gl: &glow::Context, pname: u32) -> i32 {
    // SAFETY: plain state query on a current context.
    unsafe { gl.get_parameter_i32(pname) }
}

fn clear_errors(gl: &glow::Context) {
    // SAFETY: draining the error queue has no side effects beyond that.
    unsafe { while gl.get_error() != glow::NO_ERROR {} }
}

/// Whether a framebuffer with a depth texture of `internal_format` is complete.
fn depth_texture_attachable(gl: &glow::Context, internal_format: u32, ty: u32) -> bool {
    // SAFETY: objects are created, probed and deleted here; bindings are reset to 0.
    unsafe {
        let Ok(tex) = gl.create_texture() else {
            return false;
        };
        gl.bind_texture(glow::TEXTURE_2D, Some(tex));
        gl.tex_image_2d(
            glow::TEXTURE_2D,
            0,
            internal_format as i32,
            16,
            16,
            0,
            glow::DEPTH_COMPONENT,
            ty,
            glow::PixelUnpackData::Slice(None),
        );
        let ok = match gl.create_framebuffer() {
            Ok(fbo) => {
                gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
                gl.framebuffer_texture_2d(
                    glow::FRAMEBUFFER,
                    glow::DEPTH_ATTACHMENT,
                    glow::TEXTURE_2D,
                    Some(tex),
                    0,
                );
                // glDrawBuffers, not glDrawBuffer: ES 3.0 has only the former.
                gl.draw_buffers(&[glow::NONE]);
                gl.read_buffer(glow::NONE);
                let status = gl.check_framebuffer_status(glow::FRAMEBUFFER);
                gl.bind_framebuffer(glow::FRAMEBUFFER, None);
                gl.delete_framebuffer(fbo);
                status == glow::FRAMEBUFFER_COMPLETE
            }
            Err(_) => false,
        };
        gl.bind_texture(glow::TEXTURE_2D, None);
        gl.delete_texture(tex);
        ok && gl.get_error() == glow::NO_ERROR
    }
}

/// Whether GL_TIME_ELAPSED queries run and agree with wall time on a known workload.
///
/// Returns the verdict and what was seen. Queries that report far less GPU time than the wall
/// clock shows for work that must have run between begin and end are not trusted: llvmpipe (Mesa
/// 22) defers rasterization past the query's end and reports microseconds for tens of
/// milliseconds of work, and the first query of a process returns garbage there.
fn timer_query_check(gl: &glow::Context) -> (bool, String) {
    const SIDE: i32 = 1024;
    const CLEARS: usize = 64;
    // SAFETY: a scratch framebuffer and queries are created, used and deleted here.
    unsafe {
        let (Ok(q), Ok(tex), Ok(fbo)) = (
            gl.create_query(),
            gl.create_texture(),
            gl.create_framebuffer(),
        ) else {
            return (false, "query or framebuffer objects unavailable".into());
        };
        super::scratch::bind_target(
            gl,
            (tex, fbo),
            SIDE,
            (glow::RGBA8, glow::RGBA, glow::UNSIGNED_BYTE),
            glow::COLOR_ATTACHMENT0,
        );
        gl.viewport(0, 0, SIDE, SIDE);
        let measure = || {
            gl.finish();
            let t = std::time::Instant::now();
            gl.begin_query(glow::TIME_ELAPSED, q);
            for i in 0..CLEARS {
                gl.clear_color(i as f32 / CLEARS as f32, 0.5, 0.25, 1.0);
                gl.clear(glow::COLOR_BUFFER_BIT);
            }
            gl.end_query(glow::TIME_ELAPSED);
            gl.finish();
            let wall_ms = t.elapsed().as_secs_f64() * 1e3;
            let gpu_ms = gl.get_query_parameter_u64(q, glow::QUERY_RESULT) as f64 / 1e6;
            (gpu_ms, wall_ms)
        };
        let _warm_up = measure();
        // Two measurements must both agree: llvmpipe's deferred queries agree now and then by
        // chance.
        let runs = [measure(), measure()];
        let error = gl.get_error();
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        gl.delete_framebuffer(fbo);
        gl.bind_texture(glow::TEXTURE_2D, None);
        gl.delete_texture(tex);
        gl.delete_query(q);
        if error != glow::NO_ERROR {
            return (false, format!("GL error 0x{error:x} during the check"));
        }
        // Below 2 ms of wall time a fast GPU cannot be told apart from a lying one; trust it.
        let agree = |(gpu_ms, wall_ms): (f64, f64)| {
            wall_ms < 2.0 || (gpu_ms >= 0.25 * wall_ms && gpu_ms <= 4.0 * wall_ms + 1.0)
        };
        let agrees = runs.iter().all(|&r| agree(r));
        let (gpu_ms, wall_ms) = runs[1];
        let detail = format!(
            "GL_TIME_ELAPSED measured {gpu_ms:.3} ms for {CLEARS} clears of {SIDE}x{SIDE} that took {wall_ms:.3} ms of wall time"
        );
        (agrees, detail)
    }
}

/// Whether glCopyTexSubImage2D copies a framebuffer's depth into a depth texture (desktop GL
/// 1.1; ES 3.0 copies colour only and raises INVALID_OPERATION).
fn depth_copy_works(gl: &glow::Context) -> bool {
    const SIDE: i32 = 16;
    // SAFETY: scratch textures and a framebuffer are created, used and deleted here; bindings
    // are reset to 0.
    unsafe {
        let (Ok(source), Ok(dest), Ok(fbo)) = (
            gl.create_texture(),
            gl.create_texture(),
            gl.create_framebuffer(),
        ) else {
            return false;
        };
        for t in [source, dest] {
            gl.bind_texture(glow::TEXTURE_2D, Some(t));
            gl.tex_image_2d(
                glow::TEXTURE_2D,
                0,
                glow::DEPTH_COMPONENT24 as i32,
                SIDE,
                SIDE,
                0,
                glow::DEPTH_COMPONENT,
                glow::UNSIGNED_INT,
                glow::PixelUnpackData::Slice(None),
            );
        }
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
        gl.framebuffer_texture_2d(
            glow::FRAMEBUFFER,
            glow::DEPTH_ATTACHMENT,
            glow::TEXTURE_2D,
            Some(source),
            0,
        );
        gl.draw_buffers(&[glow::NONE]);
        gl.read_buffer(glow::NONE);
        let complete = gl.check_framebuffer_status(glow::FRAMEBUFFER) == glow::FRAMEBUFFER_COMPLETE;
        clear_errors(gl);
        // `dest` is still bound.
        gl.copy_tex_sub_image_2d(glow::TEXTURE_2D, 0, 0, 0, 0, 0, SIDE, SIDE);
        let ok = complete && gl.get_error() == glow::NO_ERROR;
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        gl.bind_texture(glow::TEXTURE_2D, None);
        gl.delete_framebuffer(fbo);
        gl.delete_texture(source);
        gl.delete_texture(dest);
        ok
    }
}

/// Whether enabling `cap` raises no error.
fn enable_works(gl: &glow::Context, cap: u32) -> bool {
    // SAFETY: the capability is enabled and immediately disabled again.
    unsafe {
        gl.enable(cap);
        let ok = gl.get_error() == glow::NO_ERROR;
        gl.disable(cap);
        ok
    }
}

/// Probes the current context. `fb_depth_stencil` are the bits of our framebuffer's attachment.
pub fn probe(gl: &glow::Context, fb_depth_stencil: (i32, i32)) -> Caps {
    clear_errors(gl);
    // SAFETY: string queries on a current context.
    let (vendor, renderer, version, glsl_version) = unsafe {
        (
            gl.get_parameter_string(glow::VENDOR),
            gl.get_parameter_string(glow::RENDERER),
            gl.get_parameter_string(glow::VERSION),
            gl.get_parameter_string(glow::SHADING_LANGUAGE_VERSION),
        )
    };
    let extensions: BTreeSet<String> = gl.supported_extensions().iter().cloned().collect();
    let (major, minor) = (
        get_i(gl, glow::MAJOR_VERSION),
        get_i(gl, glow::MINOR_VERSION),
    );
    let es = gl.version().is_embedded;
    // ES has no profile mask (the query is an error there).
    let profile_mask = if es {
        0
    } else {
        get_i(gl, glow::CONTEXT_PROFILE_MASK)
    };
    let profile = if es {
        "es"
    } else if profile_mask & glow::CONTEXT_CORE_PROFILE_BIT as i32 != 0 {
        "core"
    } else if profile_mask & glow::CONTEXT_COMPATIBILITY_PROFILE_BIT as i32 != 0 {
        "compatibility"
    } else {
        "unknown"
    };
    let at_least = |ma: i32, mi: i32| (major, minor) >= (ma, mi);
    // The shaders use gl_ClipDistance only where it is core (see program::has_clip_distances):
    // ES 3.x counts here would come from an extension the shaders do not enable.
    let clip_shaders = super::program::has_clip_distances(gl);
    let max_clip_distances = if clip_shaders {
        get_i(gl, glow::MAX_CLIP_DISTANCES)
    } else {
        0
    };
    let has_ext = |e: &str| extensions.contains(e);

    let mut features = Vec::new();
    let mut add = |key, supported, detail: String, fallback| {
        features.push(Feature {
            key,
            supported,
            detail,
            fallback,
        })
    };
    add(
        "separate_stencil",
        at_least(2, 0),
        "glStencilOpSeparate (GL 2.0)".into(),
        "two stencil passes, back faces then front faces (the paper)",
    );
    add(
        "stencil_wrap",
        at_least(1, 4) || has_ext("GL_EXT_stencil_wrap"),
        "INCR_WRAP / DECR_WRAP (GL 1.4)".into(),
        "saturating INCR / DECR (the paper's card)",
    );
    // GL_DEPTH_CLAMP_EXT of ES has the same value.
    let depth_clamp = if es {
        has_ext("GL_EXT_depth_clamp")
    } else {
        at_least(3, 2) || has_ext("GL_ARB_depth_clamp")
    } && enable_works(gl, glow::DEPTH_CLAMP);
    add(
        "depth_clamp",
        depth_clamp,
        if es {
            "GL_DEPTH_CLAMP (ES: GL_EXT_depth_clamp)".into()
        } else {
            "GL_DEPTH_CLAMP (GL 3.2)".into()
        },
        "infinite far-plane projection instead of depth clamping",
    );
    // The extension string and glDepthBoundsEXT loaded (glow has no entry point for it).
    let entry = super::depth_bounds_ext::current().is_some();
    let depth_bounds = has_ext("GL_EXT_depth_bounds_test") && entry;
    add(
        "depth_bounds",
        depth_bounds,
        match (has_ext("GL_EXT_depth_bounds_test"), entry) {
            (true, true) => "GL_EXT_depth_bounds_test".into(),
            (true, false) => "GL_EXT_depth_bounds_test listed, glDepthBoundsEXT not loaded".into(),
            _ => "GL_EXT_depth_bounds_test missing".into(),
        },
        "clip planes behind the depth buffer per volume part (plan.depth_clip) and scissors",
    );
    let (timer, timer_detail) = if es {
        // Same GL_TIME_ELAPSED(_EXT) value and entry points on ES with the extension.
        if has_ext("GL_EXT_disjoint_timer_query") {
            timer_query_check(gl)
        } else {
            (false, "GL_EXT_disjoint_timer_query missing (ES)".into())
        }
    } else if at_least(3, 3) || has_ext("GL_ARB_timer_query") {
        timer_query_check(gl)
    } else {
        (false, "GL_ARB_timer_query missing".into())
    };
    add(
        "timer_query",
        timer,
        timer_detail,
        "CPU time around glFinish per pass",
    );
    let (primitive_id, primitive_id_detail) = super::primitive_id_probe::primitive_id_works(gl, es);
    add(
        "primitive_id",
        primitive_id,
        primitive_id_detail,
        "depth maps (shadow_map.buffer = depth)",
    );
    let (offset_per_fragment, offset_detail) = super::offset_probe::offset_per_fragment(gl, es);
    add(
        "offset_per_fragment",
        offset_per_fragment,
        offset_detail,
        "shadow_map.offset_factor at least 10 for warped maps (psm, tsm) and frusta, which \
         are fitted tightly in depth",
    );
    let depth_tex = depth_texture_attachable(gl, glow::DEPTH_COMPONENT24, glow::UNSIGNED_INT);
    add(
        "render_to_depth_texture",
        depth_tex,
        "framebuffer object with a DEPTH_COMPONENT24 texture".into(),
        "copy from the framebuffer (glCopyTexSubImage2D, the paper)",
    );
    let float_depth = depth_texture_attachable(gl, glow::DEPTH_COMPONENT32F, glow::FLOAT);
    // ES forbids it by the letter (Mesa's ES accepts it anyway): not relied on there.
    add(
        "depth_read",
        !es,
        if es {
            "glReadPixels of depth (ES 3.0 reads colour only)".into()
        } else {
            "glReadPixels of depth (GL 1.0)".into()
        },
        "the depth pyramid reduced by a shader and read as colour (plan.reduce_depth)",
    );
    let depth_copy = !es && depth_copy_works(gl);
    add(
        "depth_copy",
        depth_copy,
        if es {
            "glCopyTexSubImage2D from a depth buffer (ES 3.0 copies colour only)".into()
        } else {
            "glCopyTexSubImage2D from a depth buffer (GL 1.1)".into()
        },
        "render into the depth texture (framebuffer object)",
    );
    add(
        "float_depth",
        float_depth,
        "DEPTH_COMPONENT32F textures".into(),
        "24-bit depth",
    );
    add(
        "clip_distances",
        max_clip_distances >= 6,
        if clip_shaders {
            format!("{max_clip_distances} gl_ClipDistance planes")
        } else {
            "GLSL ES 3.00 has no gl_ClipDistance".into()
        },
        "texgen range test instead of light-frustum clip planes",
    );
    add(
        "debug_output",
        at_least(4, 3) || has_ext("GL_KHR_debug"),
        "KHR_debug message callback".into(),
        "glGetError checks only",
    );
    clear_errors(gl);
    Caps {
        vendor,
        renderer,
        version,
        glsl_version,
        major,
        minor,
        profile,
        depth_bits: fb_depth_stencil.0,
        stencil_bits: fb_depth_stencil.1,
        max_texture_size: get_i(gl, glow::MAX_TEXTURE_SIZE),
        max_cube_map_size: get_i(gl, glow::MAX_CUBE_MAP_TEXTURE_SIZE),
        max_renderbuffer_size: get_i(gl, glow::MAX_RENDERBUFFER_SIZE),
        max_clip_distances,
        extension_count: extensions.len(),
        features,
        extensions,
    }
}
