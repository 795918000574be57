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
    let c = Probing {
        gl,
        es: gl.version().is_embedded,
        version: (major, minor),
        extensions: &extensions,
    };
    // Before the feature checks, as it always ran: below GL 3.2 the query is an error, which
    // the checks' error handling and the final clear_errors absorb.
    let profile = profile_name(&c);
    // The shaders use gl_ClipDistance only where it is core (see program::has_clip_distances):
    // ES 3.x counts here would come from an extension the shaders do not enable.
    let clip_shaders = super::program::has_clip_distances(gl);
    let max_clip_distances = if clip_shaders {
        get_i(gl, glow::MAX_CLIP_DISTANCES)
    } else {
        0
    };
    let mut features = stencil_and_depth_features(&c);
    features.extend(drawn_features(&c));
    features.extend(depth_texture_features(&c));
    features.extend(shader_features(&c, clip_shaders, max_clip_distances));
    features.push(copy_buffer_feature(&c));
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

/// What the feature checks read: the context, its version and its extensions.
struct Probing<'a> {
    gl: &'a glow::Context,
    es: bool,
    version: (i32, i32),
    extensions: &'a BTreeSet<String>,
}

impl Probing<'_> {
    fn at_least(&self, major: i32, minor: i32) -> bool {
        self.version >= (major, minor)
    }

    fn has_ext(&self, name: &str) -> bool {
        self.extensions.contains(name)
    }
}

fn feature(
    key: &'static str,
    supported: bool,
    detail: impl Into<String>,
    fallback: &'static str,
) -> Feature {
    Feature {
        key,
        supported,
        detail: detail.into(),
        fallback,
    }
}

/// The context's profile: es, core, compatibility (or unknown).
fn profile_name(c: &Probing) -> &'static str {
    if c.es {
        // ES has no profile mask (the query is an error there).
        return "es";
    }
    let mask = get_i(c.gl, glow::CONTEXT_PROFILE_MASK);
    if mask & glow::CONTEXT_CORE_PROFILE_BIT as i32 != 0 {
        "core"
    } else if mask & glow::CONTEXT_COMPATIBILITY_PROFILE_BIT as i32 != 0 {
        "compatibility"
    } else {
        "unknown"
    }
}

/// Copies between buffers, which lay a light's volume buffer out again on the GPU.
fn copy_buffer_feature(c: &Probing) -> Feature {
    feature(
        "copy_buffer",
        c.es || c.at_least(3, 1) || c.has_ext("GL_ARB_copy_buffer"),
        if c.es {
            "glCopyBufferSubData (ES 3.0)"
        } else {
            "glCopyBufferSubData (GL 3.1, GL_ARB_copy_buffer)"
        },
        "the CPU keeps copies of uploaded volume parts (shadow_volume.relayout_on_gpu off)",
    )
}

/// The stencil operations and depth tests shadow volumes use.
fn stencil_and_depth_features(c: &Probing) -> Vec<Feature> {
    // GL_DEPTH_CLAMP_EXT of ES has the same value.
    let depth_clamp = if c.es {
        c.has_ext("GL_EXT_depth_clamp")
    } else {
        c.at_least(3, 2) || c.has_ext("GL_ARB_depth_clamp")
    } && enable_works(c.gl, glow::DEPTH_CLAMP);
    // The extension string and glDepthBoundsEXT loaded (glow has no entry point for it).
    let listed = c.has_ext("GL_EXT_depth_bounds_test");
    let entry = super::depth_bounds_ext::current().is_some();
    vec![
        feature(
            "separate_stencil",
            c.at_least(2, 0),
            "glStencilOpSeparate (GL 2.0)",
            "two stencil passes, back faces then front faces (the paper)",
        ),
        feature(
            "stencil_wrap",
            c.at_least(1, 4) || c.has_ext("GL_EXT_stencil_wrap"),
            "INCR_WRAP / DECR_WRAP (GL 1.4)",
            "saturating INCR / DECR (the paper's card)",
        ),
        feature(
            "depth_clamp",
            depth_clamp,
            if c.es {
                "GL_DEPTH_CLAMP (ES: GL_EXT_depth_clamp)"
            } else {
                "GL_DEPTH_CLAMP (GL 3.2)"
            },
            "infinite far-plane projection instead of depth clamping",
        ),
        feature(
            "depth_bounds",
            listed && entry,
            match (listed, entry) {
                (true, true) => "GL_EXT_depth_bounds_test",
                (true, false) => "GL_EXT_depth_bounds_test listed, glDepthBoundsEXT not loaded",
                _ => "GL_EXT_depth_bounds_test missing",
            },
            "clip planes behind the depth buffer per volume part (plan.depth_clip) and scissors",
        ),
    ]
}

/// What only drawing (or timing) shows: timer queries, gl_PrimitiveID, per-fragment offset.
fn drawn_features(c: &Probing) -> Vec<Feature> {
    let (timer, timer_detail) = if c.es {
        // Same GL_TIME_ELAPSED(_EXT) value and entry points on ES with the extension.
        if c.has_ext("GL_EXT_disjoint_timer_query") {
            timer_query_check(c.gl)
        } else {
            (false, "GL_EXT_disjoint_timer_query missing (ES)".into())
        }
    } else if c.at_least(3, 3) || c.has_ext("GL_ARB_timer_query") {
        timer_query_check(c.gl)
    } else {
        (false, "GL_ARB_timer_query missing".into())
    };
    let (primitive_id, primitive_id_detail) =
        super::primitive_id_probe::primitive_id_works(c.gl, c.es);
    let (offset_per_fragment, offset_detail) = super::offset_probe::offset_per_fragment(c.gl, c.es);
    vec![
        feature(
            "timer_query",
            timer,
            timer_detail,
            "CPU time around glFinish per pass",
        ),
        feature(
            "primitive_id",
            primitive_id,
            primitive_id_detail,
            "depth maps (shadow_map.buffer = depth)",
        ),
        feature(
            "offset_per_fragment",
            offset_per_fragment,
            offset_detail,
            "shadow_map.offset_factor at least 10 for warped maps (psm, tsm) and frusta, which \
             are fitted tightly in depth",
        ),
    ]
}

/// Depth textures: drawn into, read back, copied into, and of floats.
fn depth_texture_features(c: &Probing) -> Vec<Feature> {
    let depth_tex = depth_texture_attachable(c.gl, glow::DEPTH_COMPONENT24, glow::UNSIGNED_INT);
    let float_depth = depth_texture_attachable(c.gl, glow::DEPTH_COMPONENT32F, glow::FLOAT);
    let depth_copy = !c.es && depth_copy_works(c.gl);
    vec![
        feature(
            "render_to_depth_texture",
            depth_tex,
            "framebuffer object with a DEPTH_COMPONENT24 texture",
            "copy from the framebuffer (glCopyTexSubImage2D, the paper)",
        ),
        // ES forbids it by the letter (Mesa's ES accepts it anyway): not relied on there.
        feature(
            "depth_read",
            !c.es,
            if c.es {
                "glReadPixels of depth (ES 3.0 reads colour only)"
            } else {
                "glReadPixels of depth (GL 1.0)"
            },
            "the depth pyramid reduced by a shader and read as colour (plan.reduce_depth)",
        ),
        feature(
            "depth_copy",
            depth_copy,
            if c.es {
                "glCopyTexSubImage2D from a depth buffer (ES 3.0 copies colour only)"
            } else {
                "glCopyTexSubImage2D from a depth buffer (GL 1.1)"
            },
            "render into the depth texture (framebuffer object)",
        ),
        feature(
            "float_depth",
            float_depth,
            "DEPTH_COMPONENT32F textures",
            "24-bit depth",
        ),
    ]
}

/// Clip distances in shaders and the debug callback.
fn shader_features(c: &Probing, clip_shaders: bool, max_clip_distances: i32) -> Vec<Feature> {
    vec![
        feature(
            "clip_distances",
            max_clip_distances >= 6,
            if clip_shaders {
                format!("{max_clip_distances} gl_ClipDistance planes")
            } else {
                "GLSL ES 3.00 has no gl_ClipDistance".into()
            },
            "texgen range test instead of light-frustum clip planes",
        ),
        feature(
            "debug_output",
            c.at_least(4, 3) || c.has_ext("GL_KHR_debug"),
            "KHR_debug message callback",
            "glGetError checks only",
        ),
    ]
}
