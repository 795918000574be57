//! Shared helpers of the integration tests: GL on a chosen path, rendering, image comparison.
#![allow(dead_code)]

use shadowlab::frame::Frame;
use shadowlab::gl::{GlContext, Profile, create_context};
use shadowlab::options::{BackendChoice, Options};
use shadowlab::run::Renderer;
use shadowlab::scene::Scene;

/// The standard output of a finished command, which must have succeeded (its error output is
/// the failure message otherwise).
pub fn stdout_of(out: std::process::Output) -> String {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// A context on `backend` with a renderer for `options`' frame size. Panics with the
/// context error (which names the packages to install) if the path cannot start.
pub fn gl_on(backend: BackendChoice, options: &Options) -> (GlContext, Renderer) {
    let ctx = create_context(backend, options.width, options.height, Profile::Core)
        .unwrap_or_else(|e| panic!("{e}"));
    let renderer = Renderer::new(ctx.gl.clone(), options.width, options.height)
        .unwrap_or_else(|e| panic!("{e}"));
    (ctx, renderer)
}

/// A compatibility-profile context on `backend` with a renderer that can draw
/// `gl.pipeline = fixed_function` frames (and shader frames).
pub fn gl_legacy(backend: BackendChoice, options: &Options) -> (GlContext, Renderer) {
    let ctx = create_context(
        backend,
        options.width,
        options.height,
        Profile::Compatibility,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let mut renderer = Renderer::new(ctx.gl.clone(), options.width, options.height)
        .unwrap_or_else(|e| panic!("{e}"));
    let legacy = shadowlab::gl::legacy::Legacy::load(|n| ctx.proc_address(n))
        .unwrap_or_else(|e| panic!("{e}"));
    renderer
        .use_legacy(std::rc::Rc::new(legacy))
        .unwrap_or_else(|e| panic!("{e}"));
    (ctx, renderer)
}

/// Renders one frame of `scene` headless (EGL).
pub fn render(scene: &Scene, options: &Options) -> Frame {
    render_on(BackendChoice::Egl, scene, options)
}

pub fn render_on(backend: BackendChoice, scene: &Scene, options: &Options) -> Frame {
    let (_ctx, mut r) = gl_on(backend, options);
    r.load_scene(scene).unwrap();
    r.render(scene, options).unwrap()
}

/// The rasteriser behind a renderer, as the GL names it (GL_RENDERER and GL_VERSION): two
/// renderers with the same name rasterise alike, pixel for pixel.
pub fn rasteriser(r: &Renderer) -> String {
    let caps = r
        .caps_for(&Options::default())
        .unwrap_or_else(|e| panic!("{e}"));
    format!("{} / {}", caps.renderer, caps.version)
}

/// Asserts that two masks of one light agree as far as the way they were drawn allows:
/// `identical` where one rasteriser drew the same geometry the same way (no pixel may differ);
/// otherwise only within the edge band (`truth::mask_difference`: a pixel from an edge in both
/// masks), where two rasterisers' coverage rules and interpolation, or two ways of drawing
/// (clipped or bounded volumes, hardware or shader compare), may decide apart. Returns the
/// difference for printing.
pub fn assert_masks_agree(
    a: &shadowlab::images::Mask,
    b: &shadowlab::images::Mask,
    identical: bool,
    what: &str,
) -> shadowlab::truth::MaskDifference {
    if !identical {
        return assert_masks_agree_but(a, b, 0, what);
    }
    let d = shadowlab::truth::mask_difference(a, b);
    assert_eq!(d.differing, 0, "{what}: must be identical, {d:?}");
    d
}

/// Isolated pixels two ways of counting one volume on one rasteriser may decide apart:
/// - one-pass against two-pass stencil: the GL decides a triangle's facing from its
///   window-space area, once for culling (two passes) and once for two-sided stencil (one
///   pass), and a rasteriser may round the two apart on a sliver of a volume seen edge-on.
///   Softpipe does on one pixel of the built-in scene's spot (79 369 receivers;
///   `GALLIUM_DRIVER=softpipe`, Mesa 22.3); llvmpipe on none.
/// - parts bounded by `EXT_depth_bounds_test` against parts unbounded or clipped: a part's
///   counts are dropped where the stored depth lies outside its range, which only cancelling
///   counts should be, and softpipe leaves one pixel apart on the built-in scene's light 0 and
///   one each on two of oa_dm1's lights in a frame of the planner's path (tests/planner.rs).
///
/// A wrong stencil operation or depth range changes whole shadows: thousands of pixels.
pub const SLIVER_SPECKS: usize = 4;

/// Asserts that two masks of one light agree outside the edge band but for at most `specks`
/// pixels (see [`SLIVER_SPECKS`]).
pub fn assert_masks_agree_but(
    a: &shadowlab::images::Mask,
    b: &shadowlab::images::Mask,
    specks: usize,
    what: &str,
) -> shadowlab::truth::MaskDifference {
    let d = shadowlab::truth::mask_difference(a, b);
    assert!(
        d.outside_band <= specks,
        "{what}: {} pixels differ beyond the edge band, {specks} allowed ({d:?})",
        d.outside_band
    );
    d
}

/// Renders one frame with masks on `backend`, on a thread of its own (each library's context
/// is current only on the thread that made it); returns it with the rasteriser's name.
pub fn render_masks_on(
    backend: BackendChoice,
    scene: &Scene,
    options: &Options,
) -> (Frame, String) {
    let (scene, options) = (scene.clone(), options.clone());
    std::thread::spawn(move || {
        let (_ctx, mut r) = gl_on(backend, &options);
        r.load_scene(&scene).unwrap();
        let frame = r
            .render_with(
                &scene,
                &options,
                shadowlab::gl::FrameRequest {
                    masks: true,
                    ..shadowlab::gl::FrameRequest::default()
                },
            )
            .unwrap_or_else(|e| panic!("{e}"));
        (frame, rasteriser(&r))
    })
    .join()
    .unwrap()
}

/// Asserts that two frames of one scene, drawn by two renderers on one rasteriser, agree in
/// colour within one step per light's additive pass: softpipe rounds two renderers' passes
/// apart on tile-shaped patches (EGL against EGL in one process too), while one renderer's
/// frames are identical and llvmpipe's are (docs/drivers.md). Masks are compared apart, exactly.
pub fn assert_colours_within_rounding(a: &Frame, b: &Frame, what: &str) {
    let (max, differing) = image_difference(a, b);
    let passes = a.plan_stats.lights_planned.max(1);
    println!("{what}: frames differ by up to {max} on {differing} px");
    assert!(
        usize::from(max) <= passes,
        "{what}: {differing} pixels differ by up to {max} ({passes} light passes)"
    );
}

/// Largest per-channel difference and the number of pixels that differ at all.
pub fn image_difference(a: &Frame, b: &Frame) -> (u8, usize) {
    assert_eq!((a.width(), a.height()), (b.width(), b.height()));
    let mut max = 0u8;
    let mut differing = 0;
    for (pa, pb) in a
        .image
        .data
        .chunks_exact(4)
        .zip(b.image.data.chunks_exact(4))
    {
        let d = pa
            .iter()
            .zip(pb)
            .map(|(x, y)| x.abs_diff(*y))
            .max()
            .unwrap();
        max = max.max(d);
        differing += (d > 0) as usize;
    }
    (max, differing)
}

/// Mean luma over a square of pixels around (x, y).
pub fn mean_luma(f: &Frame, (x, y): (u32, u32), radius: u32) -> f32 {
    let mut sum = 0.0;
    let mut n = 0.0;
    for yy in y.saturating_sub(radius)..(y + radius + 1).min(f.height()) {
        for xx in x.saturating_sub(radius)..(x + radius + 1).min(f.width()) {
            sum += f.luma(xx, yy);
            n += 1.0;
        }
    }
    sum / n
}

/// The OpenArena data folder; fails with the fetch command when the data is absent.
pub fn openarena_data() -> std::path::PathBuf {
    let dir = shadowlab::q3::pk3::data_dir();
    if let Err(e) = shadowlab::q3::pk3::Vfs::open_data_dir(&dir) {
        panic!("{e}\nThis test needs OpenArena's data: run `scripts/fetch-openarena.sh` first.");
    }
    dir
}

/// A map of `shadowlab check`'s data set as it renders it (first spawn, placed lights), and the
/// index of its light `name`.
pub fn check_scene(bsp: &str, name: &str) -> (shadowlab::scene::Scene, usize) {
    let data = openarena_data();
    let (scene, _) = shadowlab::report::check::scene_file(&data, bsp)
        .build(&options_with(&CHECK_SIZE))
        .unwrap_or_else(|e| panic!("{e}"));
    let light = scene
        .lights
        .iter()
        .position(|l| l.name == name)
        .unwrap_or_else(|| panic!("{bsp} has no light {name}"));
    (scene, light)
}

/// `shadowlab check`'s frame size.
pub const CHECK_SIZE: [&str; 2] = ["width=320", "height=240"];

/// Loads a scene file from `assets/scenes/` with default options (no progress bar).
pub fn load_scene_file(name: &str) -> (Scene, shadowlab::scene_file::LoadReport, Options) {
    openarena_data();
    load_asset(&format!("assets/scenes/{name}.toml"))
}

/// Loads a scene file by its path under the repository.
pub fn load_asset(relative: &str) -> (Scene, shadowlab::scene_file::LoadReport, Options) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(relative);
    let loaded =
        shadowlab::scene_file::load::load_file_over(test_options(), &path, |mut options| {
            options.q3.progress = false;
            Ok::<_, std::convert::Infallible>(options)
        })
        .unwrap_or_else(|e| panic!("{e}"));
    (loaded.scene, loaded.report, loaded.options)
}

/// A scene from world-space meshes with their materials, lights and a camera.
pub fn scene_of(
    parts: Vec<(
        shadowlab::scene::shapes::MeshData,
        shadowlab::scene::Material,
    )>,
    lights: Vec<shadowlab::scene::Light>,
    camera: shadowlab::scene::Camera,
) -> Scene {
    let mut scene = Scene::default();
    scene.name = "test".into();
    scene.lights = lights;
    scene.camera = camera;
    for (mesh, material) in parts {
        scene.materials.push(material);
        let m = scene.materials.len() - 1;
        scene.push_surface(
            &mesh.vertices,
            &mesh.indices,
            m,
            shadowlab::scene::SurfaceOwner::World,
            shadowlab::scene::SurfaceKind::Mesh,
        );
    }
    scene
}

/// A horizontal square quad centred at (cx, cy) at height z, facing +Z.
pub fn floor_quad(cx: f32, cy: f32, half: f32, z: f32) -> shadowlab::scene::shapes::MeshData {
    use glam::Vec3;
    let mut m = shadowlab::scene::shapes::MeshData::default();
    m.quad(
        Vec3::new(cx - half, cy - half, z),
        Vec3::new(cx + half, cy - half, z),
        Vec3::new(cx + half, cy + half, z),
        Vec3::new(cx - half, cy + half, z),
        [1.0, 1.0],
    );
    m
}

/// Renders configurations of one scene and view, and measures each against the exact reference
/// (computed once: the G-buffer does not depend on the shadow technique).
pub struct Measurer {
    pub scene: Scene,
    // Dropped before the context its GL objects live in.
    renderer: shadowlab::run::Renderer,
    ctx: shadowlab::gl::GlContext,
    exact: shadowlab::truth::ExactMasks,
}

/// One configuration's result.
pub struct Measured {
    pub frame: Frame,
    pub per_light: Vec<(usize, shadowlab::truth::Counts)>,
    pub total: shadowlab::truth::Counts,
}

impl Measured {
    pub fn light(&self, l: usize) -> shadowlab::truth::Counts {
        self.per_light.iter().find(|(i, _)| *i == l).unwrap().1
    }
    pub fn mask(&self, l: usize) -> &shadowlab::images::Mask {
        self.frame.masks.iter().find(|m| m.light == l).unwrap()
    }
}

impl Measurer {
    pub fn new(scene: Scene, options: &Options) -> Measurer {
        Measurer::on(BackendChoice::Egl, scene, options)
    }

    /// A measurer whose frames render on `backend`.
    pub fn on(backend: BackendChoice, scene: Scene, options: &Options) -> Measurer {
        Self::with_gl(gl_on(backend, options), scene)
    }

    /// A measurer on a compatibility-profile context (both pipelines).
    pub fn legacy(backend: BackendChoice, scene: Scene, options: &Options) -> Measurer {
        Self::with_gl(gl_legacy(backend, options), scene)
    }

    fn with_gl((ctx, mut renderer): (GlContext, Renderer), scene: Scene) -> Measurer {
        renderer.load_scene(&scene).unwrap();
        let reference = shadowlab::truth::Reference::build(&scene);
        Measurer {
            scene,
            ctx,
            renderer,
            exact: shadowlab::truth::ExactMasks::with_reference(reference),
        }
    }

    pub fn context(&self) -> &shadowlab::gl::GlContext {
        &self.ctx
    }

    pub fn renderer(&mut self) -> &mut shadowlab::run::Renderer {
        let _ = &self.ctx;
        &mut self.renderer
    }

    /// Poses the scene's motion at `t` seconds: the exact masks follow, and the reference is
    /// built again when a model moved.
    pub fn pose(&mut self, t: f64) -> shadowlab::scene::motion::Posed {
        let posed = self.scene.pose_at(t);
        if posed.reshaped.is_empty() && posed.moved.is_empty() {
            self.exact.clear();
        } else {
            self.exact = shadowlab::truth::ExactMasks::with_reference(
                shadowlab::truth::Reference::build(&self.scene),
            );
        }
        posed
    }

    /// Moves the camera (the exact masks follow it).
    pub fn set_camera(&mut self, camera: shadowlab::scene::Camera) {
        self.scene.camera = camera;
        self.exact.clear();
    }

    /// The exact mask of light `l` for frames of this size.
    pub fn exact(&self, w: u32, h: u32, l: usize) -> &shadowlab::images::Mask {
        self.exact.get(w, h, l).unwrap()
    }

    pub fn measure(&mut self, options: &Options) -> Measured {
        let frame = self
            .renderer
            .render_with(
                &self.scene,
                options,
                shadowlab::gl::FrameRequest {
                    masks: true,
                    ..shadowlab::gl::FrameRequest::default()
                },
            )
            .unwrap_or_else(|e| panic!("{e}"));
        let g = frame.gbuffer.as_ref().unwrap();
        let m = self.exact.measure(&self.scene, g, &frame.masks);
        // Every bound on an error passes on zero receivers: a frame whose masks hold none where
        // the exact reference has some (a lit pass that drew nothing, as ID buffers on a GL
        // without gl_PrimitiveID did) fails here instead. (A view with no receiver in it has
        // none on either side.)
        assert!(
            m.total.receiver_pixels > 0 || m.total.receiver_mismatch == 0,
            "the masks hold no receiver where the reference has {}: the lit pass drew nothing",
            m.total.receiver_mismatch
        );
        Measured {
            frame,
            per_light: m.per_light,
            total: m.total,
        }
    }
}

/// Whether the GL behind `m` runs ID and priority buffers: they index their per-triangle tables
/// by `gl_PrimitiveID` in fragment shaders, which the capability probe checks by drawing
/// (Mesa 22.3's softpipe draws nothing with it). Where it does not, this asserts the documented
/// fallback instead, for the test that asked: an ID-buffer frame lists `primitive_id` and
/// decides as depth maps do; and says so.
pub fn id_buffers_run_or_fall_back(m: &mut Measurer, what: &str) -> bool {
    let asked = options_with(&["technique=shadow_map", "shadow_map.buffer=id"]);
    let caps = m
        .renderer()
        .caps_for(&asked)
        .unwrap_or_else(|e| panic!("{e}"));
    if caps.has("primitive_id") {
        return true;
    }
    let ids = m.measure(&asked);
    let depth = m.measure(&options_with(&["technique=shadow_map"]));
    assert!(
        ids.frame
            .fallbacks
            .iter()
            .any(|f| f.feature == "primitive_id"),
        "{what}: the primitive_id fallback is not listed: {:?}",
        ids.frame.fallbacks
    );
    for mask in &depth.frame.masks {
        assert_masks_agree(mask, ids.mask(mask.light), true, what);
    }
    println!(
        "{what}: this GL ({}) fails the primitive_id probe ({}): ID buffers fall back to \
         depth maps, checked instead",
        caps.renderer,
        caps.features
            .iter()
            .find(|f| f.key == "primitive_id")
            .map_or("", |f| f.detail.as_str())
    );
    false
}

/// The options the tests are written against: the library's defaults with every light
/// unshadowed (`technique = none`) unless a test sets a technique. (The library's default
/// is `auto`, for people; a test names what it tests.) The planner weighs its decisions for a
/// CPU rasteriser (`plan.profile = software`, which reads the depth back after the base pass)
/// on every driver, so that the tests of those decisions assert the same on a GPU, where
/// `auto` would choose `gpu`; the tests of the `gpu` profile set it.
pub fn test_options() -> Options {
    let mut o = Options {
        technique: shadowlab::options::Technique::None,
        ..Options::default()
    };
    o.plan.profile = shadowlab::options::Profile::Software;
    o
}

/// [`test_options`] with `sets` applied.
pub fn options_with(sets: &[&str]) -> Options {
    let mut o = test_options();
    for s in sets {
        o.set_assignment(s).unwrap_or_else(|e| panic!("{e}"));
    }
    o
}

/// Resident memory of this process.
pub fn rss_bytes() -> u64 {
    let statm = std::fs::read_to_string("/proc/self/statm").unwrap_or_default();
    let pages: u64 = statm
        .split_whitespace()
        .nth(1)
        .and_then(|p| p.parse().ok())
        .unwrap_or(0);
    pages * 4096
}

/// The next GL names the driver hands out for each object type (a leak makes them run away).
pub fn gl_names(gl: &glow::Context) -> [u32; 4] {
    use glow::HasContext;
    // SAFETY: objects created and deleted at once, only to read the names GL assigns.
    unsafe {
        let t = gl.create_texture().unwrap();
        let b = gl.create_buffer().unwrap();
        let f = gl.create_framebuffer().unwrap();
        let v = gl.create_vertex_array().unwrap();
        let names = [t.0.get(), b.0.get(), f.0.get(), v.0.get()];
        gl.delete_texture(t);
        gl.delete_buffer(b);
        gl.delete_framebuffer(f);
        gl.delete_vertex_array(v);
        names
    }
}

/// Pixels whose decisions differ between two masks of one size.
pub fn differing(a: &shadowlab::images::Mask, b: &shadowlab::images::Mask) -> usize {
    a.values
        .iter()
        .zip(&b.values)
        .filter(|(x, y)| x != y)
        .count()
}

/// What a long run must hold flat: the next GL names of each object type and resident memory.
#[derive(Debug, Clone, Copy)]
pub struct Footprint {
    names: [u32; 4],
    rss: u64,
}

impl Footprint {
    pub fn take(gl: &glow::Context) -> Footprint {
        Footprint {
            names: gl_names(gl),
            rss: rss_bytes(),
        }
    }

    /// GL names handed out since `before`, per object type.
    pub fn names_since(&self, before: &Footprint) -> Vec<i64> {
        before
            .names
            .iter()
            .zip(&self.names)
            .map(|(a, b)| *b as i64 - *a as i64)
            .collect()
    }

    /// "RSS a -> b MiB" since `before`.
    pub fn memory_since(&self, before: &Footprint) -> String {
        format!("RSS {} -> {} MiB", before.rss >> 20, self.rss >> 20)
    }

    /// Fewer than 16 new names of any type (a leak of one object per frame makes thousands)
    /// and under 32 MiB more memory (one leaked caster group or vertex copy per frame adds far
    /// more over thousands of frames).
    pub fn assert_flat_since(&self, before: &Footprint) {
        let growth = self.names_since(before);
        assert!(
            growth.iter().all(|g| *g < 16),
            "GL objects leak: {growth:?}"
        );
        assert!(
            self.rss < before.rss + (32 << 20),
            "memory grew from {} to {}",
            before.rss,
            self.rss
        );
    }
}

/// `camera`'s frame of `scene` drawn with masks by `cached` and by `fresh` after it forgot
/// everything (the scene loaded again), under their options; asserts every light's masks
/// equal (`what` names the frame in the message) and returns the cached renderer's frame and
/// how many masks were compared.
pub fn cached_against_fresh(
    (cached, fresh): (&mut Renderer, &mut Renderer),
    (scene, camera): (&Scene, &shadowlab::scene::Camera),
    (cached_options, fresh_options): (&Options, &Options),
    what: &str,
) -> (Frame, usize) {
    let request = shadowlab::gl::FrameRequest {
        masks: true,
        ..Default::default()
    };
    let fa = cached
        .render_at(scene, camera, cached_options, request)
        .unwrap();
    fresh.load_scene(scene).unwrap();
    let fb = fresh
        .render_at(scene, camera, fresh_options, request)
        .unwrap();
    for (ma, mb) in fa.masks.iter().zip(&fb.masks) {
        assert_eq!(
            differing(ma, mb),
            0,
            "{what}, light {}: masks differ",
            ma.light
        );
    }
    let compared = fa.masks.len().min(fb.masks.len());
    (fa, compared)
}
