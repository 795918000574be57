//! Draws a frame's plan with GL, stage by stage ([`FrameRun`]): owns the programs, the scene's
//! GPU copy, the framebuffer and the shadow maps. The order of the stages, and the planner the
//! stages between them consult, are the frame's run's (the `run` module): this layer decides
//! nothing, it draws what the plan and the resolved settings say. Masks and the G-buffer, when
//! asked for, come from the frame itself (the base pass writes the G-buffer, the lit passes
//! record their decisions) and are read after it, untimed.

use super::caps::{self, Caps};
use super::debug;
use super::depth_reduce::DepthReducer;
use super::extrusion::{ExtrudedDraw, Extrusions};
use super::fixed::{self, FixedFunction};
use super::fragments::{FragmentBuffers, LightFragmentDraw};
use super::gather::Gather;
use super::id_tables::IdTables;
use super::legacy::Legacy;
use super::passes::lit::{LitShadow, Marks, ShadowBinding};
use super::passes::shadow_map::{DepthTarget, copies_from_frame, copy_depth};
use super::passes::{self, PassContext, set_scissor};
use super::priority_mips;
use super::program::{Program, ProgramError, sources};
use super::record::DecisionRecord;
use super::shadow_maps::{MapKey, ShadowMaps};
use super::syncs::{self, SyncKind};
use super::target::{Framebuffer, GBufferTarget, MaskTarget};
use super::timing::PassTimer;
use super::upload::GpuScene;
use super::volumes::{LightVolumes, VolumeBuffers};
use crate::frame::{CacheStats, Syncs};
use crate::frame::{Frame, HybridStats, Step, StepKind};
use crate::images::{GBuffer, GBufferPicks, Mask, MaskValue, Rgba, StencilImage};
use crate::options::{
    Compare, CompareResult, DepthBits, Filter, MapBuffer, Outside, StencilPasses, StencilWrap,
    Technique, TexgenSpace, VolumeShading,
};
use crate::plan::map_memory;
use crate::plan::occlusion::DepthPyramid;
use crate::plan::pass::{PassId, Stage};
use crate::plan::scissor::Scissor;
use crate::plan::settings::PassSettings;
use crate::plan::volume_draws::{LightVolumeDraws, VolumeStats};
use crate::plan::{LightPlan, Plan};
use crate::scene::Scene;
use crate::shadow::views::ViewKind;
use crate::shadow::volume::CasterGroups;
use crate::truth::subdivision::Geometry;
use glow::HasContext;
use std::collections::HashMap;
use std::ops::ControlFlow;
use std::rc::Rc;
use std::sync::Arc;
use std::time::Instant;
use thiserror::Error;

/// Whether a frame goes on, or stopped after a walkthrough step with the frame so far.
pub(crate) type Flow<T> = Result<ControlFlow<Frame, T>, RenderError>;

/// Goes on with the value, or passes the stopped frame up.
macro_rules! go_on {
    ($flow:expr) => {
        match $flow? {
            ControlFlow::Continue(v) => v,
            ControlFlow::Break(frame) => return Ok(ControlFlow::Break(frame)),
        }
    };
}

mod lights;
mod maps;
mod measure;
mod programs;
mod record;
mod volumes;

use maps::{MapPass, draw_maps, fixed_maps, lit_passes};
pub use programs::FILL_SHADE;
use programs::{LitVariant, Programs, lit_defines};
use record::RecordedLight;

#[derive(Debug, Error)]
pub enum RenderError {
    #[error(transparent)]
    Program(#[from] ProgramError),
    #[error("GL: {0}")]
    Gl(String),
    #[error("no scene is loaded")]
    NoScene,
    #[error("{0}")]
    Unsupported(String),
    #[error(transparent)]
    VolumeDraws(#[from] crate::plan::volume_draws::VolumeDrawError),
    #[error(transparent)]
    Fragments(#[from] super::fragments::FragmentError),
}

/// What a frame should produce besides its image and timings.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FrameRequest {
    /// The G-buffer and each light's decision mask, read untimed after the frame (whose base
    /// pass writes the G-buffer, a little dearer for it): a light's lit pass records its
    /// decisions as it shades (`gl::record`), read back after the frame; a light it cannot
    /// record (hybrid, the fill shading, the legacy pipeline, beyond the record's budget)
    /// gets its mask drawn again, right after the work it reads (its counted stencil, maps
    /// drawn just before its pass) or after the frame.
    pub masks: bool,
    /// Draw every light's mask again rather than read what its lit pass recorded: the
    /// masks as they were made before the record, to check it against.
    pub masks_drawn_again: bool,
    /// With masks: leave the G-buffer on the GPU (`Frame::gbuffer` is None) for
    /// [`Drawer::gbuffer_at`] to read where a sampler picks, unless a mask needs it whole
    /// (the legacy pipeline's).
    pub gbuffer_kept: bool,
    /// Stop after this step (walkthrough): the frame then holds the steps so far and the
    /// buffer the step wrote as `step_image`.
    pub stop_after: Option<usize>,
    /// Read this light's stencil counts right after its volume pass.
    pub stencil_of: Option<usize>,
    /// Debug drawing over the finished frame (untimed).
    pub overlays: Overlays,
    /// Time the frame only, not each pass, where per-pass times need glFinish between passes
    /// (no timer queries, e.g. llvmpipe): benchmarks take frame times this way.
    pub frame_only: bool,
    /// Leave the frame's image on the GPU: nothing is read back and nothing waits for the GL
    /// (`Frame::image` is empty, `frame_ms` ends at submission); the viewer presents the
    /// frame's colour buffer, `bench` waits on a fence of its own. Masks, a stencil read or a
    /// walkthrough step still read what they ask for.
    pub image_on_gpu: bool,
    /// Take the GPU passes' times without waiting for them (with timer queries): those of the
    /// latest earlier frame whose queries are done (`Frame::passes_frames_ago` says how far
    /// back), as the viewer's timings do. The CPU clock (no trusted queries) is unaffected.
    /// `technique = auto` learns from them as from this frame's (for a frame or two after a
    /// light changes technique, from its old one's passes).
    pub pass_times_later: bool,
}

/// Debug drawing over a frame.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Overlays {
    /// Shadow volumes, translucent: depth-fail parts red, depth-pass parts green.
    pub volumes: bool,
    /// The silhouette edges the volumes were extruded from, yellow.
    pub silhouettes: bool,
    /// The shadow map's texel grid on lit receivers.
    pub texel_grid: bool,
    /// Whose volumes and silhouettes to draw: one light, or every light when `None`.
    pub light: Option<usize>,
}

/// Records the steps of a frame and says when to stop.
struct Stepper {
    stop: Option<usize>,
    steps: Vec<Step>,
}

impl Stepper {
    /// Records a step; true when it is the one to stop after.
    fn record(&mut self, kind: StepKind, lp: Option<&LightPlan>, face: Option<usize>) -> bool {
        self.steps.push(Step {
            kind,
            light: lp.map(|l| l.light),
            face,
            technique: lp.map(|l| l.technique),
        });
        self.stop == Some(self.steps.len() - 1)
    }
}

/// The texture a shadow-map view was rendered into in the last frame.
#[derive(Debug, Clone, Copy)]
struct LastMap {
    light: usize,
    view: usize,
    texture: glow::Texture,
    /// The ID buffer's colour, shown instead of the depth.
    ids: Option<glow::Texture>,
    cube: bool,
    size: u32,
}

/// The GL side of the renderer: draws what a frame's plan says, stage by stage.
pub struct Drawer {
    gl: Arc<glow::Context>,
    pub caps: Caps,
    programs: Programs,
    target: Framebuffer,
    gpu: Option<GpuScene>,
    timer: PassTimer,
    shadow_maps: ShadowMaps,
    /// Per-triangle ID and priority tables (`shadow_map.buffer`).
    id_tables: IdTables,
    /// Every light's shadow-volume buffers.
    volume_buffers: VolumeBuffers,
    /// Caster groups' meshes for volumes the GPU extrudes.
    extrusions: Extrusions,
    /// Every subdivided light's shadowed fragments (`technique = subdivision`).
    fragments: FragmentBuffers,
    /// Created on the first frame that asks for masks.
    measure_targets: Option<(GBufferTarget, MaskTarget)>,
    /// The layers lit passes record their decisions into, when masks are asked for.
    record: Option<DecisionRecord>,
    /// Reads the G-buffer at picked pixels (`gbuffer_at`).
    gather: Option<Gather>,
    /// Core profile draws need a bound VAO even without attributes (full-screen triangles).
    empty_vao: glow::VertexArray,
    /// Created on the first frame that reduces its depth for the planner.
    depth_reducer: Option<DepthReducer>,
    /// The shadow-map views of the last frame, for the depth-map debug view.
    last_maps: Vec<LastMap>,
    /// The legacy entry points, on a compatibility-profile context (`gl.pipeline =
    /// fixed_function`).
    fixed: Option<FixedFunction>,
    /// Where maps drawn between lights' passes are copied from (`Plan::maps_per_light` with
    /// `shadow_map.depth_source = copy`); made on first use.
    map_scratch: Option<Framebuffer>,
}

/// The frame's colour buffer as a texture ([`Drawer::frame_texture`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameTexture {
    pub texture: glow::Texture,
    pub width: u32,
    pub height: u32,
    /// The texture's own size (larger where shadow maps are copied from the frame).
    pub alloc: (u32, u32),
}

/// What one view's depth pass draws into and reads.
#[derive(Clone, Copy)]
struct MapBuffers {
    depth: glow::Texture,
    /// The ID buffer's colour texture.
    ids: Option<glow::Texture>,
    /// The per-triangle table of ID and priority buffers.
    table: Option<glow::Texture>,
    buffer: MapBuffer,
}

/// One shadow-mapped view's texture, by light plan and view index.
pub(crate) struct ViewMap {
    plan_index: usize,
    view_index: usize,
    /// What the lit pass reads: the depth texture, or the ID buffer's colour.
    texture: glow::Texture,
    /// The per-triangle table of ID and priority buffers.
    table: Option<glow::Texture>,
}

impl Drawer {
    /// Compiles the programs and probes the GL for a frame of `width`×`height`.
    pub fn new(gl: Arc<glow::Context>, width: u32, height: u32) -> Result<Drawer, RenderError> {
        let target = Framebuffer::new(&gl, width, height).map_err(RenderError::Gl)?;
        let caps = caps::probe(&gl, target.depth_stencil_bits(&gl));
        Self::with_caps(gl, target, caps)
    }

    /// A second renderer on this one's context that takes its probed capabilities rather than
    /// probing again: the timer-query check's verdict can differ from one probe to the next
    /// on llvmpipe, and renderers compared in one run must time their passes alike.
    pub fn sibling(&self, width: u32, height: u32) -> Result<Drawer, RenderError> {
        let target = Framebuffer::new(&self.gl, width, height).map_err(RenderError::Gl)?;
        Self::with_caps(self.gl.clone(), target, self.caps.clone())
    }

    fn with_caps(
        gl: Arc<glow::Context>,
        target: Framebuffer,
        caps: caps::Caps,
    ) -> Result<Drawer, RenderError> {
        let programs = Programs::new(&gl)?;
        // SAFETY: creating an empty vertex array object.
        let empty_vao = unsafe { gl.create_vertex_array() }.map_err(RenderError::Gl)?;
        let timer = PassTimer::new(caps.has("timer_query"));
        Ok(Drawer {
            gl,
            caps,
            programs,
            target,
            gpu: None,
            timer,
            shadow_maps: ShadowMaps::default(),
            id_tables: IdTables::default(),
            volume_buffers: VolumeBuffers::default(),
            extrusions: Extrusions::default(),
            fragments: FragmentBuffers::default(),
            measure_targets: None,
            record: None,
            gather: None,
            empty_vao,
            depth_reducer: None,
            last_maps: Vec::new(),
            fixed: None,
            map_scratch: None,
        })
    }

    /// Lets frames with `gl.pipeline = fixed_function` draw through `legacy` (loaded from this
    /// renderer's context, which must be a compatibility profile).
    pub fn use_legacy(&mut self, legacy: Rc<Legacy>) -> Result<(), RenderError> {
        legacy.check(&self.gl).map_err(RenderError::Unsupported)?;
        if let Some(old) = self.fixed.take() {
            old.delete(&self.gl);
        }
        self.fixed = Some(FixedFunction::new(&self.gl, legacy).map_err(RenderError::Gl)?);
        Ok(())
    }

    pub fn gl(&self) -> &glow::Context {
        &self.gl
    }

    /// A shared handle to the context (for callers that outlive a borrow of the renderer).
    pub fn gl_handle(&self) -> Arc<glow::Context> {
        self.gl.clone()
    }

    /// Depth textures currently allocated for shadow maps.
    pub fn shadow_map_textures(&self) -> usize {
        self.shadow_maps.texture_count()
    }

    /// Deletes what frames kept for later frames (maps, volume buffers, extruded meshes,
    /// fragments): the next frame makes what it needs afresh. The scene stays loaded.
    pub fn release_kept(&mut self) {
        // The next frame sets the maps' budget again.
        self.shadow_maps.delete(&self.gl);
        self.shadow_maps = ShadowMaps::default();
        self.delete_volume_work();
    }

    /// Bytes the shadow-map textures hold together.
    pub fn shadow_map_bytes(&self) -> u64 {
        self.shadow_maps.bytes()
    }

    /// Bytes of every light's shadow-volume buffers.
    pub fn volume_buffer_bytes(&self) -> u64 {
        self.volume_buffers.bytes()
    }

    /// Bytes of the subdivided lights' fragment buffers.
    pub fn fragment_bytes(&self) -> u64 {
        self.fragments.bytes()
    }

    /// Uploads a scene, replacing the previous one.
    pub fn load_scene(&mut self, scene: &Scene) -> Result<(), RenderError> {
        if let Some(old) = self.gpu.take() {
            old.delete(&self.gl);
        }
        let gpu = GpuScene::new(&self.gl, scene, self.caps.max_texture_size.max(1) as u32)
            .map_err(RenderError::Gl)?;
        self.use_scene(gpu);
        Ok(())
    }

    /// Uploads `scene`, which `other` (a renderer on this one's context) has loaded, sharing
    /// its textures and lightmaps rather than copying them.
    pub fn load_scene_beside(&mut self, scene: &Scene, other: &Drawer) -> Result<(), RenderError> {
        let Some(theirs) = other.gpu.as_ref() else {
            return Err(RenderError::NoScene);
        };
        if let Some(old) = self.gpu.take() {
            old.delete(&self.gl);
        }
        let gpu = GpuScene::sharing_images(&self.gl, scene, theirs).map_err(RenderError::Gl)?;
        self.use_scene(gpu);
        Ok(())
    }

    fn use_scene(&mut self, gpu: GpuScene) {
        self.gpu = Some(gpu);
        // Cached maps and volumes belong to the old scene.
        self.shadow_maps.forget();
        self.delete_volume_work();
    }

    /// Deletes the volume buffers, extruded meshes and subdivision fragments frames kept.
    fn delete_volume_work(&mut self) {
        self.volume_buffers.delete(&self.gl);
        self.extrusions.delete(&self.gl);
        self.fragments.delete(&self.gl);
    }

    /// Uploads what a light's volume draws hold for upload, outside a frame
    /// (`Renderer::prepare`).
    pub(crate) fn upload_volume_buffers(
        &mut self,
        draws: &crate::plan::volume_draws::LightVolumeDraws,
    ) -> Result<(), RenderError> {
        self.volume_buffers
            .upload(&self.gl, draws)
            .map_err(RenderError::Gl)
    }

    /// A frame of `width`×`height`, with storage of at least `alloc` and 32F depth if asked.
    fn ensure_target(
        &mut self,
        width: u32,
        height: u32,
        alloc: (u32, u32),
        float_depth: bool,
    ) -> Result<(), RenderError> {
        let t = &self.target;
        let fits = t.width == width
            && t.height == height
            && t.alloc.0 >= alloc.0
            && t.alloc.1 >= alloc.1
            && t.float_depth == float_depth;
        if !fits {
            let new = Framebuffer::with_storage(&self.gl, width, height, alloc, float_depth)
                .map_err(RenderError::Gl)?;
            self.target.delete(&self.gl);
            self.target = new;
            if let Some((g, m)) = self.measure_targets.take() {
                g.delete(&self.gl);
                m.delete(&self.gl);
            }
            if let Some(r) = self.record.take() {
                r.delete(&self.gl);
            }
        }
        Ok(())
    }

    /// A fence after every command sent so far: wait on it to know a frame left on the GPU
    /// (`FrameRequest::image_on_gpu`) is done.
    pub fn fence(&self) -> Result<syncs::Fence, RenderError> {
        syncs::Fence::insert(&self.gl).map_err(RenderError::Gl)
    }

    /// The GL's error flag since the last check, as an error: frames that wait for nothing do
    /// not check it, so a caller drawing many of them checks once after (counted).
    pub fn check_errors(&self) -> Result<(), RenderError> {
        check_errors(&self.gl)
    }

    /// Readies a frame of `plan` drawn with `settings` (the options resolved for it): its
    /// targets, the programs it needs and the models' poses; its stages are then called in
    /// order (`run`), the measurements the request asks for drawn after them, untimed.
    pub(crate) fn begin_frame<'a>(
        &'a mut self,
        scene: &'a Scene,
        plan: &'a Plan,
        settings: &'a PassSettings,
        request: FrameRequest,
        start: Instant,
    ) -> Result<FrameRun<'a>, RenderError> {
        let copy = self.prepare_targets(plan, settings, request)?;
        let gl_arc = self.gl.clone();
        // Compile what this frame needs before borrowing the programs for the passes.
        let variants = self.lit_variants(&gl_arc, plan, settings, request)?;
        // Animated models' vertices go up before anything draws them.
        let models_uploaded = self
            .gpu
            .as_mut()
            .ok_or(RenderError::NoScene)?
            .sync_models(&gl_arc, scene);
        self.timer.start_frame(!request.frame_only);
        self.last_maps.clear();
        passes::reset_state(&gl_arc);
        let gl: &glow::Context = &self.gl;
        let gpu = self.gpu.as_ref().ok_or(RenderError::NoScene)?;
        Ok(FrameRun {
            ctx: PassContext {
                gl,
                scene,
                gpu,
                plan,
                settings,
            },
            programs: &self.programs,
            variants,
            target: &self.target,
            measure_targets: self.measure_targets.as_ref(),
            record: self
                .record
                .as_ref()
                .filter(|_| request.masks && !request.masks_drawn_again),
            recorded: Vec::new(),
            reach_lights: None,
            timer: &mut self.timer,
            shadow_maps: &mut self.shadow_maps,
            id_tables: &mut self.id_tables,
            volume_buffers: &mut self.volume_buffers,
            extrusions: &mut self.extrusions,
            fragments: &mut self.fragments,
            extruded: HashMap::new(),
            volume_draws: HashMap::new(),
            depth_reducer: &mut self.depth_reducer,
            last_maps: &mut self.last_maps,
            empty_vao: self.empty_vao,
            request,
            copy,
            copy_from: match (plan.maps_per_light, &self.map_scratch) {
                (true, Some(scratch)) => scratch,
                _ => &self.target,
            },
            map_kinds: Vec::new(),
            stepper: Stepper {
                stop: request.stop_after,
                steps: Vec::new(),
            },
            cache: CacheStats {
                models_uploaded,
                ..CacheStats::default()
            },
            draws_before: passes::surface_draws(),
            start,
            volume_stats: Vec::new(),
            own_ms: 0.0,
            fixed: self.fixed.as_ref().filter(|_| settings.fixed_function),
            queue: syncs::LightQueue::new(gl, plan.lights_per_fence),
            masks_in_frame: Vec::new(),
            hybrid_in_frame: Vec::new(),
            masks_in_frame_ms: 0.0,
        })
    }

    /// Whether the legacy pipeline is loaded (`use_legacy`).
    pub fn has_legacy(&self) -> bool {
        self.fixed.is_some()
    }

    /// Lets the frames time passes with timer queries where `allowed` and they work.
    pub fn allow_timer_queries(&mut self, allowed: bool) {
        self.timer.allow_queries(allowed);
    }

    /// Sizes the frame (with room for a shadow map copied from it) and makes the measurement
    /// targets when masks are asked for; returns whether shadow maps are copied from the frame.
    fn prepare_targets(
        &mut self,
        plan: &Plan,
        settings: &PassSettings,
        request: FrameRequest,
    ) -> Result<bool, RenderError> {
        let sm = &settings.shadow_map;
        let copy = plan.any_maps() && copies_from_frame(sm);
        let largest = plan.largest_map();
        let float_depth = copy && sm.depth_bits == DepthBits::D32f;
        // Maps drawn before each light's pass come after the base pass: copies are then made
        // from a framebuffer of their own, of the frame's formats, not from the frame.
        let scratch = copy && plan.maps_per_light;
        let alloc = if copy && !scratch {
            (largest, largest)
        } else {
            (0, 0)
        };
        self.ensure_target(plan.camera.width, plan.camera.height, alloc, float_depth)?;
        if scratch {
            self.ensure_map_scratch(largest, float_depth)?;
        }
        self.shadow_maps.set_budget(plan.map_budget);
        if request.masks && self.measure_targets.is_none() {
            let g = GBufferTarget::new(&self.gl, self.target.width, self.target.height)
                .map_err(RenderError::Gl)?;
            let m = MaskTarget::new(&self.gl, &self.target).map_err(RenderError::Gl)?;
            self.measure_targets = Some((g, m));
        }
        if request.masks && !request.masks_drawn_again && !settings.fixed_function {
            self.ensure_record(plan.lights.len())?;
        }
        Ok(copy)
    }

    /// The G-buffer of the latest frame asked for masks with `gbuffer_kept`, at `pixels`
    /// (row-major, top row first, sorted, each once).
    pub fn gbuffer_at(&mut self, pixels: Vec<u32>) -> Result<GBufferPicks, RenderError> {
        let Some((gtarget, _)) = self.measure_targets.as_ref() else {
            return Err(RenderError::Gl("no G-buffer kept to read".into()));
        };
        let gather =
            Gather::holding(&self.gl, self.gather.take(), pixels.len()).map_err(RenderError::Gl)?;
        let picks = gather.read(&self.gl, &self.programs.gather, gtarget, pixels);
        self.gather = Some(gather);
        Ok(picks)
    }

    /// A record of as many layers as `lights` want (within its budget), the frame's size.
    fn ensure_record(&mut self, lights: usize) -> Result<(), RenderError> {
        let size = (self.target.width, self.target.height);
        let layers = DecisionRecord::layers_for(&self.gl, size, lights);
        let fits = self
            .record
            .as_ref()
            .is_some_and(|r| (r.width, r.height) == size && r.layers >= layers);
        if !fits {
            if let Some(r) = self.record.take() {
                r.delete(&self.gl);
            }
            let r =
                DecisionRecord::new(&self.gl, size.0, size.1, layers).map_err(RenderError::Gl)?;
            self.record = Some(r);
        }
        Ok(())
    }

    /// The framebuffer maps are copied from when they are drawn between lights' passes:
    /// `size`² at least, with the frame's depth format.
    fn ensure_map_scratch(&mut self, size: u32, float_depth: bool) -> Result<(), RenderError> {
        let fits = self
            .map_scratch
            .as_ref()
            .is_some_and(|t| t.width >= size && t.height >= size && t.float_depth == float_depth);
        if !fits {
            let new = Framebuffer::with_storage(&self.gl, size, size, (size, size), float_depth)
                .map_err(RenderError::Gl)?;
            if let Some(old) = self.map_scratch.replace(new) {
                old.delete(&self.gl);
            }
        }
        Ok(())
    }

    /// The lit programs this frame may use, compiled on first use, by variant.
    fn lit_variants(
        &mut self,
        gl: &glow::Context,
        plan: &Plan,
        settings: &PassSettings,
        request: FrameRequest,
    ) -> Result<HashMap<LitVariant, String>, RenderError> {
        let shadow_mapped = plan.any_maps();
        let hybrids = plan.any(Technique::Hybrid);
        let trapezoids = plan.any(Technique::Tsm);
        // The buffers other than depth some light's standard maps store (`auto` may choose
        // one per light).
        let mut buffers: Vec<MapBuffer> = Vec::new();
        for lp in &plan.lights {
            if lp.technique == Technique::ShadowMap
                && lp.buffer != MapBuffer::Depth
                && !buffers.contains(&lp.buffer)
            {
                self.programs.depth_buffer(gl, lp.buffer)?;
                buffers.push(lp.buffer);
            }
        }
        let mut variants = HashMap::new();
        for (shadow_map, cube, six, hybrid, warp_depth) in [
            (false, false, false, false, false),
            (true, false, false, false, false),
            (true, true, false, false, false),
            (true, false, true, false, false),
            (true, false, false, true, false),
            (true, true, false, true, false),
            (true, false, true, true, false),
            (true, false, false, false, true),
            (true, false, true, false, true),
        ] {
            for mask in [false, true] {
                if (shadow_map && !shadow_mapped)
                    || (mask && !request.masks)
                    || (hybrid && !hybrids)
                    || (warp_depth && !trapezoids)
                {
                    continue;
                }
                let v = LitVariant {
                    shadow_map,
                    cube,
                    six,
                    mask,
                    hybrid,
                    warp_depth,
                    buffer: MapBuffer::Depth,
                };
                // ID and priority buffers are read as 2D maps by standard maps only.
                let buffered = shadow_map && !cube && !hybrid && !warp_depth;
                let with_buffers = buffers
                    .iter()
                    .filter(|_| buffered)
                    .map(|&buffer| LitVariant { buffer, ..v });
                for v in std::iter::once(v).chain(with_buffers) {
                    let defines = lit_defines(settings, v, request.overlays.texel_grid);
                    let key = self.programs.lit_variant(gl, &defines)?;
                    variants.insert(v, key);
                }
            }
        }
        Ok(variants)
    }

    /// How many depth images the last frame made for `light`: 1 for a spot, 6 for an omni
    /// light (six spots, or the six faces of its cube), 0 without shadow maps.
    pub fn shadow_map_views(&self, light: usize) -> usize {
        self.last_maps
            .iter()
            .filter(|m| m.light == light)
            .map(|m| if m.cube { 6 } else { 1 })
            .sum()
    }

    /// The last frame's shadow map `k` of `light` (see [`Self::shadow_map_views`]) as grey.
    pub fn shadow_map_image(&self, light: usize, k: usize) -> Option<Rgba> {
        let gl: &glow::Context = &self.gl;
        let mut i = 0;
        for m in self.last_maps.iter().filter(|m| m.light == light) {
            let faces = if m.cube { 6 } else { 1 };
            if k < i + faces {
                let face = m.cube.then_some(k - i);
                if let Some(ids) = m.ids {
                    return Some(debug::id_image(gl, ids, m.size));
                }
                let depth = debug::read_depth_texture(gl, m.texture, face, m.size);
                let _ = m.view;
                return Some(debug::depth_image(&depth, m.size, m.size));
            }
            i += faces;
        }
        None
    }

    /// The last frame's colour texture, for a caller that shows it without reading it back
    /// (bottom row first; the frame fills `width`×`height` of its `alloc`).
    pub fn frame_texture(&self) -> FrameTexture {
        FrameTexture {
            texture: self.target.color,
            width: self.target.width,
            height: self.target.height,
            alloc: self.target.alloc,
        }
    }

    /// Draws the last frame into the default framebuffer of a window, scaled to `width`×`height`.
    pub fn present_to_default(&self, width: u32, height: u32) {
        let gl: &glow::Context = &self.gl;
        let (fw, fh) = self.target.alloc;
        // SAFETY: the default framebuffer exists on window contexts; state is set explicitly.
        unsafe {
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(self.target.fbo));
            gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, None);
            gl.blit_framebuffer(
                0,
                0,
                self.target.width.min(fw) as i32,
                self.target.height.min(fh) as i32,
                0,
                0,
                width as i32,
                height as i32,
                glow::COLOR_BUFFER_BIT,
                glow::LINEAR,
            );
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        }
    }
}

/// One frame being drawn: the parts of the renderer the passes use, and what the frame has
/// produced so far.
pub(crate) struct FrameRun<'a> {
    ctx: PassContext<'a>,
    programs: &'a Programs,
    variants: HashMap<LitVariant, String>,
    target: &'a Framebuffer,
    measure_targets: Option<&'a (GBufferTarget, MaskTarget)>,
    /// Where lit passes record their decisions in this frame (`gl::record`).
    record: Option<&'a DecisionRecord>,
    /// The lights recorded so far, each with its layer.
    recorded: Vec<RecordedLight>,
    /// The lights of the G-buffer's reach bits, in bit order, once a pass wrote it (the base
    /// pass, in a frame asked for masks).
    reach_lights: Option<Vec<usize>>,
    timer: &'a mut PassTimer,
    shadow_maps: &'a mut ShadowMaps,
    id_tables: &'a mut IdTables,
    volume_buffers: &'a mut VolumeBuffers,
    extrusions: &'a mut Extrusions,
    fragments: &'a mut FragmentBuffers,
    /// Per light, the groups the GPU extrudes this frame.
    extruded: HashMap<usize, Vec<ExtrudedDraw>>,
    /// Per light, the volume draws the planner made for this frame (`use_volume_draws`).
    volume_draws: HashMap<usize, &'a LightVolumeDraws>,
    depth_reducer: &'a mut Option<DepthReducer>,
    last_maps: &'a mut Vec<LastMap>,
    empty_vao: glow::VertexArray,
    request: FrameRequest,
    /// Shadow maps are drawn into the frame and copied into their textures.
    copy: bool,
    /// The framebuffer maps are drawn into and copied from when `copy`: the frame's own, or
    /// a scratch one when each light's maps come just before its pass.
    copy_from: &'a Framebuffer,
    /// The kinds of texture the frame's maps were drawn into so far.
    map_kinds: Vec<MapKey>,
    stepper: Stepper,
    cache: CacheStats,
    /// The thread's surface draw count when the frame began.
    draws_before: usize,
    start: Instant,
    volume_stats: Vec<VolumeStats>,
    /// CPU work of the frame outside GL calls done here (the GPU extrusion meshes' builds).
    own_ms: f64,
    /// The legacy pipeline, when the frame draws with it.
    fixed: Option<&'a FixedFunction>,
    /// The bound on lights queued in the GL (`Plan::lights_per_fence`).
    queue: syncs::LightQueue<'a>,
    /// Masks drawn within the frame, right after the work they read (`mask_in_frame`).
    masks_in_frame: Vec<Mask>,
    /// The hybrid lights' stats from their masks drawn within the frame.
    hybrid_in_frame: Vec<HybridStats>,
    /// Milliseconds those took (with the waits of their read-backs), left out of the
    /// frame's time: masks are untimed.
    masks_in_frame_ms: f64,
}

impl<'a> FrameRun<'a> {
    /// Ends the frame after its last stage: its pass times, the overlays and, untimed, what
    /// the request asks for besides (the image, masks); waits for the GL only where the caller
    /// wants pixels.
    pub(crate) fn end(
        mut self,
        maps: Vec<ViewMap>,
        stencil: Option<StencilImage>,
    ) -> Result<Frame, RenderError> {
        set_scissor(self.ctx.gl, None);
        let gl = self.ctx.gl;
        let (passes, passes_frames_ago) = match self.request.pass_times_later {
            true => self.timer.finish_later(gl),
            false => (self.timer.finish(gl), 0),
        };
        // Only a caller that wants pixels makes the frame wait: the read-back would anyway.
        let completed = !self.request.image_on_gpu || self.request.masks;
        if completed {
            syncs::finish(gl);
        }
        let frame_ms = self.start.elapsed().as_secs_f64() * 1e3 - self.masks_in_frame_ms;
        let surface_draws = passes::surface_draws().wrapping_sub(self.draws_before);
        self.overlays();
        if completed {
            check_errors(gl)?;
        }
        let (width, height) = (self.target.width, self.target.height);
        let image = match self.request.image_on_gpu {
            true => Rgba {
                width: 0,
                height: 0,
                data: Vec::new(),
            },
            false => self.color_image(),
        };
        let (gbuffer, masks, hybrid) = self.measure(&maps);
        let masks_recorded = match masks.is_empty() {
            true => 0,
            false => self.recorded.len(),
        };
        let plan = self.ctx.plan;
        Ok(Frame {
            image,
            width,
            height,
            completed,
            own_ms: self.own_ms,
            view_proj: plan.camera.view_proj,
            passes,
            passes_frames_ago,
            frame_ms,
            gbuffer,
            masks,
            volumes: self.volume_stats,
            steps: self.stepper.steps,
            step_image: None,
            stencil,
            plan_stats: plan.stats.clone(),
            cache: CacheStats {
                surface_draws,
                ..self.cache
            },
            fallbacks: Vec::new(),
            hybrid,
            masks_recorded,
            syncs: Syncs::default(),
        })
    }

    fn lit_program(&self, v: LitVariant) -> &Program {
        &self.programs.lit[&self.variants[&v]]
    }

    /// Records a step; the stopped frame when it is the one to stop after, with the image
    /// `image` makes of the buffer the step wrote.
    fn step(
        &mut self,
        kind: StepKind,
        lp: Option<&LightPlan>,
        face: Option<usize>,
        image: impl FnOnce(&Self) -> Rgba,
    ) -> Flow<()> {
        if !self.stepper.record(kind, lp, face) {
            return Ok(ControlFlow::Continue(()));
        }
        let image = image(self);
        Ok(ControlFlow::Break(self.stopped(image)))
    }

    /// The frame's colour buffer as an image.
    fn color_image(&self) -> Rgba {
        Rgba {
            width: self.target.width,
            height: self.target.height,
            data: self.target.read_rgba(self.ctx.gl),
        }
    }

    /// The frame as it stands after a walkthrough step, with that step's buffer as an image.
    fn stopped(&mut self, image: Rgba) -> Frame {
        let gl = self.ctx.gl;
        let passes = self.timer.finish(gl);
        syncs::finish(gl);
        let plan = self.ctx.plan;
        Frame {
            image: self.color_image(),
            width: self.target.width,
            height: self.target.height,
            completed: true,
            own_ms: 0.0,
            view_proj: plan.camera.view_proj,
            passes,
            passes_frames_ago: 0,
            frame_ms: self.start.elapsed().as_secs_f64() * 1e3,
            gbuffer: None,
            masks: Vec::new(),
            volumes: std::mem::take(&mut self.volume_stats),
            steps: std::mem::take(&mut self.stepper.steps),
            step_image: Some(image),
            stencil: None,
            plan_stats: plan.stats.clone(),
            cache: CacheStats::default(),
            fallbacks: Vec::new(),
            hybrid: Vec::new(),
            masks_recorded: 0,
            syncs: Syncs::default(),
        }
    }
}

/// The fixed-function pipeline's mask marks every receiver fragment it draws (legacy lighting
/// reaches per vertex): pixels whose surface the light does not reach (range, cone, facing,
/// judged as the shader path and the reference judge them) become "not a receiver".
/// The GL's error flag, as the frame's error (counted: most drivers finish the commands queued
/// before they can answer).
fn check_errors(gl: &glow::Context) -> Result<(), RenderError> {
    // SAFETY: error query only.
    let error = unsafe { gl.get_error() };
    syncs::count(SyncKind::ErrorCheck);
    match error {
        glow::NO_ERROR => Ok(()),
        e => Err(RenderError::Gl(format!(
            "the frame raised GL error 0x{e:x}"
        ))),
    }
}

impl Drop for Drawer {
    fn drop(&mut self) {
        let gl_arc = self.gl.clone();
        let gl: &glow::Context = &gl_arc;
        if let Some(g) = self.gpu.take() {
            g.delete(gl);
        }
        self.programs.delete(gl);
        self.target.delete(gl);
        if let Some(t) = self.map_scratch.take() {
            t.delete(gl);
        }
        self.shadow_maps.delete(gl);
        self.id_tables.delete(gl);
        self.volume_buffers.delete(gl);
        self.extrusions.delete(gl);
        self.fragments.delete(gl);
        if let Some((g, m)) = self.measure_targets.take() {
            g.delete(gl);
            m.delete(gl);
        }
        if let Some(r) = self.record.take() {
            r.delete(gl);
        }
        if let Some(g) = self.gather.take() {
            g.delete(gl);
        }
        if let Some(r) = self.depth_reducer.take() {
            r.delete(gl);
        }
        self.timer.delete(gl);
        if let Some(f) = self.fixed.take() {
            f.delete(gl);
        }
        // SAFETY: deleting our own VAO once.
        unsafe { gl.delete_vertex_array(self.empty_vao) };
    }
}
