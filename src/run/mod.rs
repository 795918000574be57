//! A frame's run: the options resolved for this GL (the fallbacks for what it lacks, the cost
//! profile), the plan made, the GL's stages called in order with the planner consulted between
//! them, and the frame's pass times handed back to the planner. The one place the order of a
//! frame lives; the GL layer (`gl::Drawer`) draws each stage as the plan says and decides
//! nothing, the planner (`plan::planner`) decides and draws nothing.
//!
//! Order (paper 3.1): every shadow-mapped light's views into their maps; the unlit world; the
//! depth the planner reads back (software profile) or reuses; each volume light's draws made
//! and uploaded; the subdivided lights' fragments; each light's additive pass.

use crate::frame::Frame;
use crate::gl::Drawer;
use crate::gl::caps::Caps;
use crate::gl::legacy::Legacy;
use crate::gl::renderer::FrameRun;
use crate::gl::syncs::{self, Fence};
use crate::images::{GBufferPicks, Rgba};
use crate::options::{Options, Technique};
use crate::plan::auto::{AutoMemory, CostSource};
use crate::plan::fallback::Fallback;
use crate::plan::pass::{PassId, Stage};
use crate::plan::planner::{DepthNeed, Planner};
use crate::plan::settings::PassSettings;
use crate::plan::{Plan, fallback, fixed_function, profile};
use crate::scene::{Camera, Scene};
use crate::truth::sampled::LightSample;
use std::ops::ControlFlow;
use std::rc::Rc;
use std::sync::Arc;
use std::time::Instant;

pub use crate::gl::{FrameRequest, FrameTexture, Overlays, RenderError};

/// Counts of what a renderer keeps across frames ([`Renderer::held`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Held {
    /// Shadow-map and ID-buffer textures, and the bytes they hold together (what
    /// `shadow_map.budget_mb` bounds).
    pub map_textures: usize,
    pub map_bytes: u64,
    /// Volume parts built and kept for the frames that draw them again.
    pub volume_parts: usize,
    /// Bytes of the volumes held: the parts' CPU copies and every light's GPU buffers.
    pub volume_bytes: u64,
    /// Depth-pass parts' clip planes fitted to the last depth buffer.
    pub depth_fits: usize,
    /// Bytes of the subdivided lights' shadowed fragments on the GPU.
    pub fragment_bytes: u64,
}

impl Held {
    /// Bytes of everything counted: maps, volumes and fragments.
    pub fn bytes(&self) -> u64 {
        self.map_bytes + self.volume_bytes + self.fragment_bytes
    }
}

/// What [`Renderer::prepare`] readied.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Prepared {
    /// Lights whose kept volumes were built ahead, their parts and vertices.
    pub lights: usize,
    pub volume_parts: usize,
    pub volume_vertices: usize,
    /// Wall time, building and uploading.
    pub ms: f64,
}

/// Plans and draws frames: the planner and what it keeps across frames (costs for `auto`,
/// caster groups, the depth it read, volume draws), and the GL side that draws.
pub struct Renderer {
    drawer: Drawer,
    planner: Planner,
}

/// Goes on with the value, or returns the frame a walkthrough step stopped.
macro_rules! or_stopped {
    ($flow:expr) => {
        match $flow? {
            ControlFlow::Continue(v) => v,
            ControlFlow::Break(frame) => return Ok((frame, 0.0)),
        }
    };
}

impl Renderer {
    /// Compiles the programs and probes the GL for a frame of `width`×`height`.
    pub fn new(gl: Arc<glow::Context>, width: u32, height: u32) -> Result<Renderer, RenderError> {
        Ok(Renderer::with(Drawer::new(gl, width, height)?))
    }

    /// A second renderer on this one's context that takes its probed capabilities rather than
    /// probing again: the timer-query check's verdict can differ from one probe to the next
    /// on llvmpipe, and renderers compared in one run must time their passes alike.
    pub fn sibling(&self, width: u32, height: u32) -> Result<Renderer, RenderError> {
        Ok(Renderer::with(self.drawer.sibling(width, height)?))
    }

    /// [`Renderer::sibling`] with `scene` (the one this renderer has loaded) loaded, sharing
    /// this one's textures and lightmaps: renderers compared side by side on one scene hold
    /// its images once.
    pub fn sibling_with_scene(
        &self,
        width: u32,
        height: u32,
        scene: &Scene,
    ) -> Result<Renderer, RenderError> {
        let mut drawer = self.drawer.sibling(width, height)?;
        drawer.load_scene_beside(scene, &self.drawer)?;
        Ok(Renderer::with(drawer))
    }

    fn with(drawer: Drawer) -> Renderer {
        Renderer {
            drawer,
            planner: Planner::default(),
        }
    }

    /// Lets frames with `gl.pipeline = fixed_function` draw through `legacy` (loaded from this
    /// renderer's context, which must be a compatibility profile).
    pub fn use_legacy(&mut self, legacy: Rc<Legacy>) -> Result<(), RenderError> {
        self.drawer.use_legacy(legacy)
    }

    pub fn gl(&self) -> &glow::Context {
        self.drawer.gl()
    }

    /// A shared handle to the context (for callers that outlive a borrow of the renderer).
    pub fn gl_handle(&self) -> Arc<glow::Context> {
        self.drawer.gl_handle()
    }

    /// What the GL was probed to have.
    pub fn caps(&self) -> &Caps {
        &self.drawer.caps
    }

    /// Depth textures currently allocated for shadow maps.
    pub fn shadow_map_textures(&self) -> usize {
        self.drawer.shadow_map_textures()
    }

    /// What the renderer keeps across frames, counted: long runs hold these flat.
    pub fn held(&self) -> Held {
        let (volume_parts, depth_fits, copies) = self.planner.held_volumes();
        Held {
            map_textures: self.drawer.shadow_map_textures(),
            map_bytes: self.drawer.shadow_map_bytes(),
            volume_parts,
            volume_bytes: copies + self.drawer.volume_buffer_bytes(),
            depth_fits,
            fragment_bytes: self.drawer.fragment_bytes(),
        }
    }

    /// The G-buffer of the latest frame asked for masks with `FrameRequest::gbuffer_kept`, at
    /// `pixels` (row-major, top row first, sorted, each once): what a sampler reads.
    pub fn gbuffer_at(&mut self, pixels: Vec<u32>) -> Result<GBufferPicks, RenderError> {
        self.drawer.gbuffer_at(pixels)
    }

    /// Drops the frusta static omni lights kept (`plan.keep_frusta`): the next frame chooses
    /// them afresh for its own view.
    pub fn forget_kept_frusta(&mut self) {
        self.planner.forget_kept_frusta();
    }

    /// Drops what frames kept for later frames, on the GPU and in the planner (maps, volumes,
    /// caster groups, `auto`'s measurements): memory falls back to the scene's own, and the
    /// next frame starts as the first after [`Renderer::load_scene`] does. A run measuring
    /// one configuration after another calls it between them, so that none holds what the
    /// ones before it kept.
    pub fn release_kept(&mut self) {
        self.drawer.release_kept();
        self.planner.forget();
        give_back_freed_pages();
    }

    /// Uploads a scene, replacing the previous one; what the planner kept belongs to the old.
    pub fn load_scene(&mut self, scene: &Scene) -> Result<(), RenderError> {
        self.drawer.load_scene(scene)?;
        self.planner.forget();
        Ok(())
    }

    /// Readies what later frames of `scene` (the loaded one) with `options` would otherwise
    /// make the first time they need it: the kept volumes of still shadow-volume lights
    /// (`plan.build_ahead`), built and uploaded. Call it after [`Renderer::load_scene`]; a
    /// frame without it builds each piece when it first draws it.
    pub fn prepare(&mut self, scene: &Scene, options: &Options) -> Result<Prepared, RenderError> {
        let start = Instant::now();
        let options = &self.resolve(options)?.0;
        let lights = self.planner.prepare_ahead(scene, &scene.camera, options);
        for a in &lights {
            if let Some(v) = self.planner.last_volume_draws(a.light)
                && let Err(e) = self.drawer.upload_volume_buffers(v)
            {
                self.planner.forget_volume_draws(a.light);
                return Err(e);
            }
            self.planner.uploaded(a.light);
        }
        Ok(Prepared {
            lights: lights.len(),
            volume_parts: lights.iter().map(|a| a.parts).sum(),
            volume_vertices: lights.iter().map(|a| a.vertices).sum(),
            ms: start.elapsed().as_secs_f64() * 1e3,
        })
    }

    /// `options` as a frame on this GL runs them: the fixed-function choices its GL lacks
    /// replaced (with what was replaced), the profile resolved; and the GL's capabilities less
    /// those `options` disable, which they were resolved against.
    fn resolve(&self, options: &Options) -> Result<(Options, Vec<Fallback>, Caps), RenderError> {
        let caps = self.caps_for(options)?;
        let (options, fallbacks) = fixed_function::resolve_all(options, |f| caps.has(f));
        Ok((
            profile::resolve(options, caps.is_software()),
            fallbacks,
            caps,
        ))
    }

    /// Plans and renders one frame of `scene` (which must be the loaded one).
    pub fn render(&mut self, scene: &Scene, options: &Options) -> Result<Frame, RenderError> {
        self.render_with(scene, options, FrameRequest::default())
    }

    /// Plans and renders one frame, with what `request` asks for besides the image.
    pub fn render_with(
        &mut self,
        scene: &Scene,
        options: &Options,
        request: FrameRequest,
    ) -> Result<Frame, RenderError> {
        self.render_at(scene, &scene.camera, options, request)
    }

    /// Plans and renders one frame seen from `camera` instead of the scene's camera. The
    /// frame's time starts here: resolving the options and planning count.
    pub fn render_at(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        options: &Options,
        request: FrameRequest,
    ) -> Result<Frame, RenderError> {
        let (before, start) = (syncs::counted(), Instant::now());
        let (options, fallbacks, caps) = self.resolve(options)?;
        let options = &options;
        let settings = PassSettings::of(options);
        if settings.fixed_function && !self.drawer.has_legacy() {
            return Err(RenderError::Unsupported(
                "gl.pipeline = fixed_function needs a compatibility-profile context with the \
                 legacy entry points (EGL or OSMesa on Mesa give one; the window path and \
                 OpenGL ES do not)"
                    .into(),
            ));
        }
        self.drawer.allow_timer_queries(caps.has("timer_query"));
        let plan = self.planner.plan(scene, camera, options);
        let planned_ms = start.elapsed().as_secs_f64() * 1e3;
        self.check_support(&settings, &plan)?;
        let (mut frame, volumes_ms) =
            self.draw(scene, &plan, options, &settings, request, start)?;
        frame.own_ms += planned_ms + volumes_ms;
        frame.fallbacks = fallbacks;
        frame.cache.caster_groups_built = self.planner.take_groups_rebuilt();
        // Frame-only timing has no per-light passes to learn from.
        let passes = (!request.frame_only).then_some(frame.passes.as_slice());
        self.planner.record_frame(&plan, passes);
        frame.syncs = syncs::counted().since(&before);
        Ok(frame)
    }

    /// The stages of one frame in order, the planner consulted between them.
    fn draw(
        &mut self,
        scene: &Scene,
        plan: &Plan,
        options: &Options,
        settings: &PassSettings,
        request: FrameRequest,
        start: Instant,
    ) -> Result<(Frame, f64), RenderError> {
        let Renderer { drawer, planner } = self;
        let mut f = drawer.begin_frame(scene, plan, settings, request, start)?;
        // Shadow maps of every shadow-mapped light first (paper 3.1).
        let maps = or_stopped!(f.shadow_map_passes());
        or_stopped!(f.base_pass());
        match planner.depth_need(scene, plan, options, f.float_depth()) {
            DepthNeed::Read { reduced } => {
                let depth = f.depth_for_planner(reduced)?;
                planner.take_depth(depth, options);
            }
            DepthNeed::Reuse => f.depth_reused(),
            DepthNeed::None => {}
        }
        let volumes_ms = volume_draws(&mut f, planner, (scene, plan, options))?;
        f.subdivisions()?;
        let draws = plan
            .lights
            .iter()
            .filter(|lp| lp.counts_volumes())
            .filter_map(|lp| Some((lp.light, planner.last_volume_draws(lp.light)?)))
            .collect();
        f.use_volume_draws(draws);
        let stencil = or_stopped!(f.light_passes(&maps));
        Ok((f.end(maps, stencil)?, volumes_ms))
    }

    /// The probed capabilities less the features `gl.disable` names.
    pub fn caps_for(&self, options: &Options) -> Result<Caps, RenderError> {
        let disabled = fallback::disabled(options).map_err(RenderError::Unsupported)?;
        Ok(self.drawer.caps.with_disabled(&disabled))
    }

    /// The one limit no fallback lifts: a shadow map larger than the GL's textures. (Choices
    /// that need a missing feature were replaced before planning: `plan::fallback`.)
    fn check_support(&self, settings: &PassSettings, plan: &Plan) -> Result<(), RenderError> {
        let size = plan.largest_map();
        let max = self.drawer.caps.max_texture_size.max(1) as u32;
        if plan.any_maps() && size > max {
            return Err(RenderError::Unsupported(format!(
                "a shadow map of {size}x{size} (shadow_map.size, or one of several frusta) \
                 exceeds GL_MAX_TEXTURE_SIZE {max}"
            )));
        }
        if settings.fixed_function {
            for (t, why) in [
                (Technique::Hybrid, "classifies pixels in a shader"),
                (Technique::Tsm, "writes the light's own depth from a shader"),
            ] {
                if plan.any(t) {
                    return Err(RenderError::Unsupported(format!(
                        "technique = {t} {why}: it needs gl.pipeline = shaders"
                    )));
                }
            }
        }
        Ok(())
    }

    /// A fence after every command sent so far: wait on it to know a frame left on the GPU
    /// (`FrameRequest::image_on_gpu`) is done.
    pub fn fence(&self) -> Result<Fence, RenderError> {
        self.drawer.fence()
    }

    /// The GL's error flag since the last check, as an error: frames that wait for nothing do
    /// not check it, so a caller drawing many of them checks once after (counted).
    pub fn check_errors(&self) -> Result<(), RenderError> {
        self.drawer.check_errors()
    }

    /// What `technique = auto` has measured so far.
    pub fn auto_memory(&self) -> &AutoMemory {
        self.planner.memory()
    }

    /// Where `technique = auto` takes each light's costs from: the frames' pass times
    /// (the default), or costs the caller supplies (tests, a cost model of another machine).
    pub fn set_cost_source(&mut self, source: CostSource) {
        self.planner.set_cost_source(source);
    }

    /// Gives `auto` the last frame's sampled errors (its masks against `truth::sampled`): the
    /// GL layer measures no error itself.
    pub fn record_errors(&mut self, samples: &[LightSample], options: &Options) {
        self.planner.record_errors(samples, options);
    }

    /// Each light the last frame planned and the candidate (technique, buffer, size) it ran
    /// with.
    pub fn ran(&self) -> &[(usize, crate::options::Candidate)] {
        self.planner.ran()
    }

    /// Makes `choices` what `technique = auto` runs its lights with from the next frame on,
    /// in place of judging them (empty: it judges them again).
    pub fn follow(&mut self, choices: &[(usize, crate::options::Candidate)]) {
        self.planner.follow(choices);
    }

    /// How many depth images the last frame made for `light`: 1 for a spot, 6 for an omni
    /// light (six spots, or the six faces of its cube), 0 without shadow maps.
    pub fn shadow_map_views(&self, light: usize) -> usize {
        self.drawer.shadow_map_views(light)
    }

    /// The last frame's shadow map `k` of `light` (see [`Self::shadow_map_views`]) as grey.
    pub fn shadow_map_image(&self, light: usize, k: usize) -> Option<Rgba> {
        self.drawer.shadow_map_image(light, k)
    }

    /// The last frame's colour texture, for a window that shows it without reading it back.
    pub fn frame_texture(&self) -> FrameTexture {
        self.drawer.frame_texture()
    }

    /// Draws the last frame into the default framebuffer of a window, scaled to `width`×`height`.
    pub fn present_to_default(&self, width: u32, height: u32) {
        self.drawer.present_to_default(width, height);
    }
}

/// Each shadow-volume light's draws made by the planner and uploaded; the CPU's per-frame work
/// on the pieces (receivers, rectangles, merges, depth clips) and the uploads timed as one
/// stage, less the parts' builds, timed per light. Returns the planner's share (pieces and
/// builds, outside GL calls).
fn volume_draws(
    f: &mut FrameRun<'_>,
    planner: &mut Planner,
    (scene, plan, options): (&Scene, &Plan, &Options),
) -> Result<f64, RenderError> {
    if !plan.any_volumes() {
        return Ok(0.0);
    }
    let start = Instant::now();
    let mut builds_ms = 0.0;
    let mut planner_ms = 0.0;
    for lp in plan.lights.iter().filter(|l| l.counts_volumes()) {
        let planning = Instant::now();
        let groups = (!lp.extruded.is_empty()).then(|| planner.casters(scene));
        let v = planner.volume_draws(scene, plan, lp, options)?;
        planner_ms += planning.elapsed().as_secs_f64() * 1e3;
        match f.upload_volumes(lp, v, groups.as_deref()) {
            Ok(ms) => {
                builds_ms += ms;
                planner.uploaded(lp.light);
            }
            Err(e) => {
                planner.forget_volume_draws(lp.light);
                return Err(e);
            }
        }
    }
    let ms = start.elapsed().as_secs_f64() * 1e3 - builds_ms;
    f.record_cpu(PassId::frame(Stage::VolumePieces), ms.max(0.0));
    Ok(planner_ms)
}

/// Hands the pages of freed memory back to the system. glibc keeps freed chunks in its heap,
/// and gives back only its top unless asked: a run measuring one configuration after another
/// then holds, beside the next configuration's frames, pages an earlier one freed (oa_dm3's
/// paper's frame of shadow maps, volumes, TSM, hybrid and subdivision one after another:
/// 2.02 GiB peak resident without, 1.96 GiB with). Elsewhere than glibc this does nothing.
fn give_back_freed_pages() {
    // SAFETY: malloc_trim only returns free pages of the allocator's arenas to the system.
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    unsafe {
        libc::malloc_trim(0);
    }
}
