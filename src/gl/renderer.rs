//! Executes a frame's plan with GL: owns the programs, the scene's GPU copy, the framebuffer and
//! the shadow maps, runs the passes in the paper's order and returns a [`Frame`].
//!
//! Order (paper 3.1): for each shadow-mapped light, its views into depth textures (drawn into the
//! frame's depth buffer and copied, or rendered straight into the texture); then the unlit world;
//! then each light's additive pass. Masks and the G-buffer, when asked for, are drawn after the
//! timed frame.

use super::caps::{self, Caps};
use super::debug;
use super::depth_reduce::DepthReducer;
use super::extrusion::{ExtrudedDraw, Extrusions};
use super::fixed::{self, FixedFunction};
use super::fragments::{FragmentBuffers, LightFragmentDraw};
use super::id_tables::IdTables;
use super::legacy::Legacy;
use super::passes::lit::{LitShadow, ShadowBinding};
use super::passes::shadow_map::{DepthTarget, copies_from_frame, copy_depth};
use super::passes::{self, PassContext, set_scissor};
use super::priority_mips;
use super::program::{Program, ProgramError, sources};
use super::shadow_maps::{MapKey, ShadowMaps};
use super::syncs::{self, SyncKind};
use super::target::{Framebuffer, GBufferTarget, MaskTarget};
use super::timing::PassTimer;
use super::upload::GpuScene;
use super::volumes::{LightVolumes, VolumeBuffers};
use crate::frame::{CacheStats, Syncs};
use crate::frame::{Frame, HybridStats, Step, StepKind};
use crate::geometry::projection::cube_face_view;
use crate::images::{GBuffer, Mask, MaskValue, Rgba, StencilImage};
use crate::options::{
    Compare, CompareResult, DepthBits, Filter, MapBuffer, Options, Outside, Pipeline,
    StencilPasses, StencilWrap, Technique, TexgenSpace, VolumeShading,
};
use crate::plan::auto::AutoMemory;
use crate::plan::occlusion::DepthPyramid;
use crate::plan::pass::{PassId, Stage};
use crate::plan::planner::{DepthNeed, Planner};
use crate::plan::scissor::Scissor;
use crate::plan::volume_draws::VolumeStats;
use crate::plan::{LightPlan, Plan};
use crate::plan::{fallback, fixed_function, profile};
use crate::scene::{Camera, Scene};
use crate::shadow::views::ViewKind;
use crate::truth::subdivision::Geometry;
use glow::HasContext;
use std::collections::HashMap;
use std::ops::ControlFlow;
use std::rc::Rc;
use std::sync::Arc;
use std::time::Instant;
use thiserror::Error;

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
    /// The G-buffer and each light's decision mask (drawn after the timed frame).
    pub masks: bool,
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

/// The `#define`s of the lit program for these options: with a shadow-map lookup (`shadow_map`,
/// from a cube map when `cube`) or without, writing light or the mask.
fn lit_defines(options: &Options, v: LitVariant, texel_grid: bool) -> Vec<&'static str> {
    let LitVariant {
        shadow_map,
        cube,
        six,
        mask,
        hybrid,
        warp_depth,
        buffer,
    } = v;
    let mut d = Vec::new();
    if shadow_map {
        d.extend(buffer_defines(buffer, options.shadow_map.id_edge_filter));
        if buffer == MapBuffer::Priority && options.shadow_map.priority_mipmap && !cube {
            d.push("PRIORITY_MIPMAP");
        }
    }
    if hybrid {
        d.push("HYBRID");
    }
    if warp_depth {
        d.push("WARP_DEPTH");
    }
    if shadow_map {
        if six {
            d.push("SIX_SPOTS");
        }
        if texel_grid && !mask {
            d.push("TEXEL_GRID");
        }
        let o = &options.shadow_map;
        d.push("SHADOW_MAP");
        if cube {
            d.push("SHADOW_CUBE");
        }
        if o.compare == Compare::Shader {
            d.push("COMPARE_SHADER");
        }
        match o.filter {
            Filter::Nearest => {}
            Filter::Hw2x2 => d.push("FILTER_HW2X2"),
            Filter::Pcf3x3 => d.push("FILTER_PCF3"),
            Filter::Pcf => d.push("FILTER_PCFN"),
        }
        match o.outside {
            Outside::Clamp => {}
            Outside::Range => d.push("OUTSIDE_RANGE"),
            Outside::ClipPlanes => d.push("CLIP_PLANES"),
        }
        if o.depth_bits != DepthBits::D32f {
            d.push("REF_CLAMP");
        }
        if o.texgen == TexgenSpace::Fragment && !cube {
            d.push("TEXGEN_FRAGMENT");
        }
        if o.result == CompareResult::Alpha {
            d.push("RESULT_ALPHA");
        }
    }
    if mask {
        d.push("MASK_OUTPUT");
    }
    d
}

/// The `#define`s of an ID or priority buffer, for the depth and lit programs alike.
fn buffer_defines(buffer: MapBuffer, edge_filter: bool) -> Vec<&'static str> {
    match buffer {
        MapBuffer::Depth => vec![],
        MapBuffer::Id if edge_filter => vec!["ID_TABLE", "BUFFER_ID", "ID_EDGE_FILTER"],
        MapBuffer::Id => vec!["ID_TABLE", "BUFFER_ID"],
        MapBuffer::Priority => vec!["ID_TABLE", "BUFFER_PRIORITY"],
        MapBuffer::PriorityDepth => vec!["ID_TABLE", "BUFFER_PRIORITY_DEPTH"],
    }
}

/// Which lit program a pass needs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct LitVariant {
    /// With a shadow-map lookup...
    shadow_map: bool,
    /// ...into one cube map...
    cube: bool,
    /// ...or into an omni light's six spot maps at once.
    six: bool,
    /// Writing the decision mask instead of light.
    mask: bool,
    /// Chan & Durand's hybrid (with `shadow_map`).
    hybrid: bool,
    /// The compared depth from the light's own view (trapezoidal maps).
    warp_depth: bool,
    /// What the maps store (`shadow_map.buffer`; depth for every technique but shadow_map).
    buffer: MapBuffer,
}

impl LitVariant {
    /// Without a shadow map: lit (or `mask`) as the stencil says.
    fn plain(mask: bool) -> LitVariant {
        LitVariant {
            shadow_map: false,
            cube: false,
            six: false,
            mask,
            hybrid: false,
            warp_depth: false,
            buffer: MapBuffer::Depth,
        }
    }
}

/// Bestimt and Freitag's fill colour (their 0x00E0E0E0 with DESTCOLOR blending).
pub const FILL_SHADE: f32 = 224.0 / 255.0;

struct Programs {
    unlit: Program,
    gbuffer: Program,
    depth: Program,
    /// The depth pass storing another matrix's depth than it draws with (trapezoidal maps).
    depth_warp: Program,
    volume: passes::stencil::VolumePrograms,
    /// The subdivision's shadowed fragments into the stencil.
    fragments: Program,
    fill: Program,
    /// The depth's 4×4 block maxima for the planner.
    depth_reduce: Program,
    /// A priority buffer's mip levels (`shadow_map.priority_mipmap`).
    priority_mips: Program,
    /// Volumes and silhouettes drawn over the frame (debug overlay).
    debug_volume: Program,
    /// Lit programs by their define set, compiled on first use.
    lit: HashMap<String, Program>,
    /// Depth programs of ID and priority buffers, compiled on first use.
    depth_buffers: HashMap<MapBuffer, Program>,
}

impl Programs {
    fn new(gl: &glow::Context) -> Result<Programs, ProgramError> {
        let world = |name, frag| Program::new(gl, name, sources::WORLD_VERT, Some(frag), &[]);
        Ok(Programs {
            unlit: world("unlit", sources::UNLIT_FRAG)?,
            gbuffer: world("gbuffer", sources::GBUFFER_FRAG)?,
            depth: Program::new(
                gl,
                "depth",
                sources::DEPTH_VERT,
                Some(sources::DEPTH_FRAG),
                &[],
            )?,
            depth_warp: Program::new(
                gl,
                "depth_warp",
                sources::DEPTH_VERT,
                Some(sources::DEPTH_FRAG),
                &["WARP_DEPTH"],
            )?,
            volume: passes::stencil::VolumePrograms {
                built: Program::new(
                    gl,
                    "volume",
                    sources::VOLUME_VERT,
                    Some(sources::VOLUME_FRAG),
                    &[],
                )?,
                extruded: Program::new(
                    gl,
                    "volume_gpu",
                    sources::VOLUME_GPU_VERT,
                    Some(sources::VOLUME_FRAG),
                    &[],
                )?,
            },
            fragments: Program::new(
                gl,
                "fragments",
                sources::FRAGMENTS_VERT,
                Some(sources::VOLUME_FRAG),
                &[],
            )?,
            fill: Program::new(
                gl,
                "fill",
                sources::FULLSCREEN_VERT,
                Some(sources::FILL_FRAG),
                &[],
            )?,
            depth_reduce: Program::new(
                gl,
                "depth_reduce",
                sources::FULLSCREEN_VERT,
                Some(sources::DEPTH_REDUCE_FRAG),
                &[],
            )?,
            priority_mips: Program::new(
                gl,
                "priority_mips",
                sources::FULLSCREEN_VERT,
                Some(sources::PRIORITY_MIPS_FRAG),
                &[],
            )?,
            debug_volume: Program::new(
                gl,
                "debug_volume",
                sources::DEBUG_VOLUME_VERT,
                Some(sources::DEBUG_VOLUME_FRAG),
                &[],
            )?,
            lit: HashMap::new(),
            depth_buffers: HashMap::new(),
        })
    }

    /// Compiles the depth program of `buffer` if needed (none for depth maps).
    fn depth_buffer(&mut self, gl: &glow::Context, buffer: MapBuffer) -> Result<(), ProgramError> {
        if buffer == MapBuffer::Depth || self.depth_buffers.contains_key(&buffer) {
            return Ok(());
        }
        let p = Program::new(
            gl,
            &format!("depth[{buffer}]"),
            sources::DEPTH_VERT,
            Some(sources::DEPTH_FRAG),
            &buffer_defines(buffer, false),
        )?;
        self.depth_buffers.insert(buffer, p);
        Ok(())
    }

    /// Compiles the lit variant for `defines` if needed; returns its key.
    fn lit_variant(
        &mut self,
        gl: &glow::Context,
        defines: &[&str],
    ) -> Result<String, ProgramError> {
        let key = defines.join(" ");
        if !self.lit.contains_key(&key) {
            let fragment = if defines.contains(&"SHADOW_MAP") {
                format!("{}\n{}", sources::SHADOW, sources::LIT_FRAG)
            } else {
                sources::LIT_FRAG.to_string()
            };
            let p = Program::new(
                gl,
                &format!("lit[{key}]"),
                sources::WORLD_VERT,
                Some(&fragment),
                defines,
            )?;
            self.lit.insert(key.clone(), p);
        }
        Ok(key)
    }

    fn delete(&mut self, gl: &glow::Context) {
        for p in [
            &self.unlit,
            &self.gbuffer,
            &self.depth,
            &self.depth_warp,
            &self.volume.built,
            &self.volume.extruded,
            &self.fragments,
            &self.fill,
            &self.depth_reduce,
            &self.priority_mips,
            &self.debug_volume,
        ] {
            p.delete(gl);
        }
        for p in self.depth_buffers.values() {
            p.delete(gl);
        }
        for p in self.lit.values() {
            p.delete(gl);
        }
        self.lit.clear();
    }
}

/// Counts of what a renderer keeps across frames ([`Renderer::held`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Held {
    /// Shadow-map and ID-buffer textures.
    pub map_textures: usize,
    /// Volume parts built and kept for the frames that draw them again.
    pub volume_parts: usize,
    /// Depth-pass parts' clip planes fitted to the last depth buffer.
    pub depth_fits: usize,
}

pub struct Renderer {
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
    /// Core profile draws need a bound VAO even without attributes (full-screen triangles).
    empty_vao: glow::VertexArray,
    /// Created on the first frame that reduces its depth for the planner.
    depth_reducer: Option<DepthReducer>,
    /// The shadow-map views of the last frame, for the depth-map debug view.
    last_maps: Vec<LastMap>,
    /// The planner and what it keeps across frames (costs for `auto`, caster groups, the
    /// depth it read, volume draws).
    planner: Planner,
    /// The legacy entry points, on a compatibility-profile context (`gl.pipeline =
    /// fixed_function`).
    fixed: Option<FixedFunction>,
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
struct ViewMap {
    plan_index: usize,
    view_index: usize,
    /// What the lit pass reads: the depth texture, or the ID buffer's colour.
    texture: glow::Texture,
    /// The per-triangle table of ID and priority buffers.
    table: Option<glow::Texture>,
}

impl Renderer {
    /// Compiles the programs and probes the GL for a frame of `width`×`height`.
    pub fn new(gl: Arc<glow::Context>, width: u32, height: u32) -> Result<Renderer, RenderError> {
        let target = Framebuffer::new(&gl, width, height).map_err(RenderError::Gl)?;
        let caps = caps::probe(&gl, target.depth_stencil_bits(&gl));
        Self::with_caps(gl, target, caps)
    }

    /// A second renderer on this one's context that takes its probed capabilities rather than
    /// probing again: the timer-query check's verdict can differ from one probe to the next
    /// on llvmpipe, and renderers compared in one run must time their passes alike.
    pub fn sibling(&self, width: u32, height: u32) -> Result<Renderer, RenderError> {
        let target = Framebuffer::new(&self.gl, width, height).map_err(RenderError::Gl)?;
        Self::with_caps(self.gl.clone(), target, self.caps.clone())
    }

    fn with_caps(
        gl: Arc<glow::Context>,
        target: Framebuffer,
        caps: caps::Caps,
    ) -> Result<Renderer, RenderError> {
        let programs = Programs::new(&gl)?;
        // SAFETY: creating an empty vertex array object.
        let empty_vao = unsafe { gl.create_vertex_array() }.map_err(RenderError::Gl)?;
        let timer = PassTimer::new(caps.has("timer_query"));
        Ok(Renderer {
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
            empty_vao,
            depth_reducer: None,
            last_maps: Vec::new(),
            planner: Planner::default(),
            fixed: None,
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

    /// What the renderer keeps across frames, counted: long runs hold these flat.
    pub fn held(&self) -> Held {
        let (volume_parts, depth_fits) = self.planner.held_volumes();
        Held {
            map_textures: self.shadow_maps.texture_count(),
            volume_parts,
            depth_fits,
        }
    }

    /// Drops the frusta static omni lights kept (`plan.keep_frusta`): the next frame chooses
    /// them afresh for its own view.
    pub fn forget_kept_frusta(&mut self) {
        self.planner.forget_kept_frusta();
    }

    /// Uploads a scene, replacing the previous one.
    pub fn load_scene(&mut self, scene: &Scene) -> Result<(), RenderError> {
        if let Some(old) = self.gpu.take() {
            old.delete(&self.gl);
        }
        let gpu = GpuScene::new(&self.gl, scene, self.caps.max_texture_size.max(1) as u32)
            .map_err(RenderError::Gl)?;
        self.gpu = Some(gpu);
        // Cached maps and volumes belong to the old scene.
        self.shadow_maps.forget();
        self.volume_buffers.delete(&self.gl);
        self.extrusions.delete(&self.gl);
        self.fragments.delete(&self.gl);
        self.planner.forget();
        Ok(())
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
        }
        Ok(())
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

    /// Plans and renders one frame seen from `camera` instead of the scene's camera.
    pub fn render_at(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        options: &Options,
        request: FrameRequest,
    ) -> Result<Frame, RenderError> {
        let (before, start) = (syncs::counted(), Instant::now());
        let caps = self.caps_for(options)?;
        let (options, fallbacks) = fixed_function::resolve_all(options, |f| caps.has(f));
        let options = profile::resolve(&options, caps.is_software());
        if options.gl.pipeline == Pipeline::FixedFunction && self.fixed.is_none() {
            return Err(RenderError::Unsupported(
                "gl.pipeline = fixed_function needs a compatibility-profile context with the \
                 legacy entry points (EGL or OSMesa on Mesa give one; the window path and \
                 OpenGL ES do not)"
                    .into(),
            ));
        }
        self.timer.allow_queries(caps.has("timer_query"));
        let options = &options;
        let plan = self.planner.plan(scene, camera, options);
        let frame_only = request.frame_only;
        let mut frame = self.execute(scene, &plan, options, request, start)?;
        frame.fallbacks = fallbacks;
        frame.cache.caster_groups_built = self.planner.take_groups_rebuilt();
        // Frame-only timing has no per-light passes to learn from.
        if !frame_only {
            self.planner.record_costs(&plan, &frame.passes);
        }
        frame.syncs = syncs::counted().since(&before);
        Ok(frame)
    }

    /// The probed capabilities less the features `gl.disable` names.
    pub fn caps_for(&self, options: &Options) -> Result<Caps, RenderError> {
        let disabled = fallback::disabled(options).map_err(RenderError::Unsupported)?;
        Ok(self.caps.with_disabled(&disabled))
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

    /// What `technique = auto` has measured so far.
    pub fn auto_memory(&self) -> &AutoMemory {
        self.planner.memory()
    }

    /// Where `technique = auto` takes each light's costs from: the frames' pass times
    /// (the default), or costs the caller supplies (tests, a cost model of another machine).
    pub fn set_cost_source(&mut self, source: crate::plan::auto::CostSource) {
        self.planner.set_cost_source(source);
    }

    /// Gives `auto` the last frame's sampled errors (its masks against `truth::sampled`): the
    /// GL layer measures no error itself.
    pub fn record_errors(
        &mut self,
        samples: &[crate::truth::sampled::LightSample],
        options: &Options,
    ) {
        self.planner.record_errors(samples, options);
    }

    /// The one limit no fallback lifts: a shadow map larger than the GL's textures. (Choices
    /// that need a missing feature were replaced before planning: `plan::fallback`.)
    fn check_support(&self, options: &Options, plan: &Plan) -> Result<(), RenderError> {
        let size = plan.largest_map(options.shadow_map.size);
        let max = self.caps.max_texture_size.max(1) as u32;
        if plan.any_maps() && size > max {
            return Err(RenderError::Unsupported(format!(
                "a shadow map of {size}x{size} (shadow_map.size, or one of several frusta) \
                 exceeds GL_MAX_TEXTURE_SIZE {max}"
            )));
        }
        if options.gl.pipeline == Pipeline::FixedFunction {
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

    /// Runs the passes of `plan` (made from `options` with their fallbacks already taken),
    /// then, untimed, the measurement passes the request asks for.
    fn execute(
        &mut self,
        scene: &Scene,
        plan: &Plan,
        options: &Options,
        request: FrameRequest,
        start: Instant,
    ) -> Result<Frame, RenderError> {
        self.check_support(options, plan)?;
        let copy = self.prepare_targets(plan, options, request)?;
        let gl_arc = self.gl.clone();
        let gl: &glow::Context = &gl_arc;
        // Compile what this frame needs before borrowing the programs for the passes.
        let variants = self.lit_variants(gl, plan, options, request)?;
        // Animated models' vertices go up before anything draws them.
        let models_uploaded = self
            .gpu
            .as_mut()
            .ok_or(RenderError::NoScene)?
            .sync_models(gl, scene);
        let gpu = self.gpu.as_ref().ok_or(RenderError::NoScene)?;
        self.timer.start_frame(!request.frame_only);
        self.last_maps.clear();
        passes::reset_state(gl);
        let run = FrameRun {
            ctx: PassContext {
                gl,
                scene,
                gpu,
                plan,
                options,
            },
            programs: &self.programs,
            variants,
            target: &self.target,
            measure_targets: self.measure_targets.as_ref(),
            timer: &mut self.timer,
            shadow_maps: &mut self.shadow_maps,
            id_tables: &mut self.id_tables,
            planner: &mut self.planner,
            volume_buffers: &mut self.volume_buffers,
            extrusions: &mut self.extrusions,
            fragments: &mut self.fragments,
            extruded: HashMap::new(),
            depth_reducer: &mut self.depth_reducer,
            last_maps: &mut self.last_maps,
            empty_vao: self.empty_vao,
            request,
            copy,
            stepper: Stepper {
                stop: request.stop_after,
                steps: Vec::new(),
            },
            cache: CacheStats {
                models_uploaded,
                ..CacheStats::default()
            },
            start,
            volume_stats: Vec::new(),
            fixed: self
                .fixed
                .as_ref()
                .filter(|_| options.gl.pipeline == Pipeline::FixedFunction),
        };
        run.run()
    }

    /// Sizes the frame (with room for a shadow map copied from it) and makes the measurement
    /// targets when masks are asked for; returns whether shadow maps are copied from the frame.
    fn prepare_targets(
        &mut self,
        plan: &Plan,
        options: &Options,
        request: FrameRequest,
    ) -> Result<bool, RenderError> {
        let sm = &options.shadow_map;
        let copy = plan.any_maps() && copies_from_frame(sm);
        let largest = plan.largest_map(sm.size);
        let alloc = if copy { (largest, largest) } else { (0, 0) };
        self.ensure_target(
            plan.camera.width,
            plan.camera.height,
            alloc,
            copy && sm.depth_bits == DepthBits::D32f,
        )?;
        if request.masks && self.measure_targets.is_none() {
            let g = GBufferTarget::new(&self.gl, self.target.width, self.target.height)
                .map_err(RenderError::Gl)?;
            let m = MaskTarget::new(&self.gl, &self.target).map_err(RenderError::Gl)?;
            self.measure_targets = Some((g, m));
        }
        Ok(copy)
    }

    /// The lit programs this frame may use, compiled on first use, by variant.
    fn lit_variants(
        &mut self,
        gl: &glow::Context,
        plan: &Plan,
        options: &Options,
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
                    let defines = lit_defines(options, v, request.overlays.texel_grid);
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

/// Whether a frame goes on, or stopped after a walkthrough step with the frame so far.
type Flow<T> = Result<ControlFlow<Frame, T>, RenderError>;

/// Goes on with the value, or returns the stopped frame as the frame (in
/// [`FrameRun::run`]).
macro_rules! or_stopped {
    ($flow:expr) => {
        match $flow? {
            ControlFlow::Continue(v) => v,
            ControlFlow::Break(frame) => return Ok(frame),
        }
    };
}

/// Goes on with the value, or passes the stopped frame up.
macro_rules! go_on {
    ($flow:expr) => {
        match $flow? {
            ControlFlow::Continue(v) => v,
            ControlFlow::Break(frame) => return Ok(ControlFlow::Break(frame)),
        }
    };
}

/// One frame being drawn: the parts of the renderer the passes use, and what the frame has
/// produced so far.
struct FrameRun<'a> {
    ctx: PassContext<'a>,
    programs: &'a Programs,
    variants: HashMap<LitVariant, String>,
    target: &'a Framebuffer,
    measure_targets: Option<&'a (GBufferTarget, MaskTarget)>,
    timer: &'a mut PassTimer,
    shadow_maps: &'a mut ShadowMaps,
    id_tables: &'a mut IdTables,
    planner: &'a mut Planner,
    volume_buffers: &'a mut VolumeBuffers,
    extrusions: &'a mut Extrusions,
    fragments: &'a mut FragmentBuffers,
    /// Per light, the groups the GPU extrudes this frame.
    extruded: HashMap<usize, Vec<ExtrudedDraw>>,
    depth_reducer: &'a mut Option<DepthReducer>,
    last_maps: &'a mut Vec<LastMap>,
    empty_vao: glow::VertexArray,
    request: FrameRequest,
    /// Shadow maps are drawn into the frame and copied into their textures.
    copy: bool,
    stepper: Stepper,
    cache: CacheStats,
    start: Instant,
    volume_stats: Vec<VolumeStats>,
    /// The legacy pipeline, when the frame draws with it.
    fixed: Option<&'a FixedFunction>,
}

impl<'a> FrameRun<'a> {
    /// The passes in the paper's order, then the untimed overlays and measurements.
    fn run(mut self) -> Result<Frame, RenderError> {
        // Shadow maps of every shadow-mapped light first (paper 3.1).
        let maps = or_stopped!(self.shadow_map_passes());
        or_stopped!(self.base_pass());
        self.volume_draws()?;
        self.subdivisions()?;
        let stencil = or_stopped!(self.light_passes(&maps));
        set_scissor(self.ctx.gl, None);
        let gl = self.ctx.gl;
        let passes = self.timer.finish(gl);
        // Only a caller that wants pixels makes the frame wait: the read-back would anyway.
        let completed = !self.request.image_on_gpu || self.request.masks;
        if completed {
            syncs::finish(gl);
        }
        let frame_ms = self.start.elapsed().as_secs_f64() * 1e3;
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
        let plan = self.ctx.plan;
        Ok(Frame {
            image,
            width,
            height,
            completed,
            view_proj: plan.camera.view_proj,
            passes,
            frame_ms,
            gbuffer,
            masks,
            volumes: self.volume_stats,
            steps: self.stepper.steps,
            step_image: None,
            stencil,
            plan_stats: plan.stats.clone(),
            cache: self.cache,
            fallbacks: Vec::new(),
            hybrid,
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
            view_proj: plan.camera.view_proj,
            passes,
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
            syncs: Syncs::default(),
        }
    }

    /// Every shadow-mapped light's views into their depth textures (drawn again only when
    /// the plan's key for the view changed).
    fn shadow_map_passes(&mut self) -> Flow<Vec<ViewMap>> {
        let (gl, plan) = (self.ctx.gl, self.ctx.plan);
        let sm = &self.ctx.options.shadow_map;
        let mut maps: Vec<ViewMap> = Vec::new();
        let mut kinds: Vec<MapKey> = Vec::new();
        let any_ids = plan
            .lights
            .iter()
            .any(|lp| lp.technique.uses_maps() && lp.buffer == MapBuffer::Id);
        let fbo = if plan.any_maps() && (!self.copy || any_ids) {
            Some(self.shadow_maps.fbo(gl).map_err(RenderError::Gl)?)
        } else {
            None
        };
        for (pi, lp) in plan.lights.iter().enumerate() {
            if !lp.technique.uses_maps() {
                continue;
            }
            let buffer = lp.buffer;
            let (table, table_changed) = self
                .id_tables
                .table(
                    gl,
                    self.ctx.scene,
                    self.ctx.gpu,
                    buffer,
                    sm.id_unit,
                    lp.light,
                )
                .map_err(RenderError::Gl)?;
            // A priority buffer's mip chain (never a cube: priority maps are six spots).
            let mipmapped = buffer == MapBuffer::Priority && sm.priority_mipmap;
            for (vi, view) in lp.views.iter().enumerate() {
                let cube = view.kind == ViewKind::Cube;
                let size = view.map_size(sm.size);
                let kind = MapKey {
                    cube,
                    size,
                    bits: sm.depth_bits,
                    buffer,
                    levels: if mipmapped && !cube {
                        priority_mips::levels(size)
                    } else {
                        1
                    },
                };
                if !kinds.contains(&kind) {
                    kinds.push(kind);
                }
                let (texture, mut holds) = self
                    .shadow_maps
                    .slot(gl, (lp.light, vi), kind)
                    .map_err(RenderError::Gl)?;
                let ids = if buffer == MapBuffer::Id {
                    let (t, fresh) = self
                        .shadow_maps
                        .id_texture(gl, lp.light, vi, size)
                        .map_err(RenderError::Gl)?;
                    if fresh {
                        holds = None;
                    }
                    Some(t)
                } else {
                    None
                };
                // Maps drawn with another table hold other priorities.
                if table_changed {
                    holds = None;
                }
                let key = lp.view_keys.get(vi).copied().flatten();
                let faces: Vec<(Option<usize>, glam::Mat4)> = if key.is_some() && holds == key {
                    self.cache.maps_reused += 1;
                    Vec::new()
                } else {
                    self.cache.maps_rendered += 1;
                    if cube {
                        let eye = self.ctx.scene.lights[lp.light].position;
                        (0..6)
                            .map(|f| (Some(f), view.projection * cube_face_view(eye, f)))
                            .collect()
                    } else {
                        vec![(None, view.view_proj())]
                    }
                };
                let drawn = !faces.is_empty();
                for (face, view_proj) in faces {
                    let buffers = MapBuffers {
                        depth: texture,
                        ids,
                        table,
                        buffer,
                    };
                    go_on!(self.map_face(lp, vi, (face, view_proj), fbo, buffers));
                }
                if drawn && kind.levels > 1 {
                    let mip_fbo = self.shadow_maps.fbo(gl).map_err(RenderError::Gl)?;
                    priority_mips::build(
                        gl,
                        &self.programs.priority_mips,
                        self.empty_vao,
                        mip_fbo,
                        (texture, size, kind.levels),
                    );
                }
                self.shadow_maps.set_content(lp.light, vi, key);
                if ids.is_none() {
                    ShadowMaps::configure(
                        gl,
                        texture,
                        (cube, kind.levels > 1),
                        sm.compare,
                        sm.filter,
                    );
                }
                self.last_maps.push(LastMap {
                    light: lp.light,
                    view: vi,
                    texture,
                    ids,
                    cube,
                    size,
                });
                maps.push(ViewMap {
                    plan_index: pi,
                    view_index: vi,
                    texture: ids.unwrap_or(texture),
                    table,
                });
            }
        }
        self.shadow_maps.release_unlike(gl, &kinds);
        Ok(ControlFlow::Continue(maps))
    }

    /// One view (or cube face) of a light drawn into its map, and copied there from the frame
    /// when maps are copies.
    fn map_face(
        &mut self,
        lp: &LightPlan,
        vi: usize,
        (face, view_proj): (Option<usize>, glam::Mat4),
        fbo: Option<glow::Framebuffer>,
        buffers: MapBuffers,
    ) -> Flow<()> {
        let gl = self.ctx.gl;
        let size = lp.views[vi].map_size(self.ctx.options.shadow_map.size);
        let shown = face.or(Some(vi));
        let texture = buffers.depth;
        // ID buffers are drawn through the FBO: their IDs are colour, the frame's is not theirs.
        let through_fbo = !self.copy || buffers.ids.is_some();
        let target = match fbo {
            Some(fbo) if through_fbo => DepthTarget::Fbo {
                fbo,
                texture,
                colour: buffers.ids,
            },
            _ => DepthTarget::Copy {
                frame: self.target,
                texture,
            },
        };
        self.timer
            .begin(gl, PassId::light(lp.light, Stage::ShadowMap));
        let view = passes::shadow_map::MapView {
            view_proj,
            size,
            cube_face: face,
            order: lp.order,
            casters: lp.view_casters.get(vi).map(Vec::as_slice),
            depth_view_proj: lp.views[vi].depth_view_proj,
            buffer: buffers.buffer,
            table: buffers.table,
            light_position: self.ctx.scene.lights[lp.light].position,
        };
        let depth_program = if view.depth_view_proj.is_some() {
            &self.programs.depth_warp
        } else {
            self.programs
                .depth_buffers
                .get(&buffers.buffer)
                .unwrap_or(&self.programs.depth)
        };
        match self.fixed {
            Some(ff) => fixed::shadow_map::render(&self.ctx, ff, &view, &target),
            None => passes::shadow_map::render(&self.ctx, depth_program, &view, &target),
        }
        let copy = !through_fbo;
        let fbo_of_frame = self.target.fbo;
        go_on!(self.step(StepKind::LightView, Some(lp), shown, |_| {
            // An ID buffer shows its IDs; a priority buffer's depth is its priority ramp.
            if let Some(ids) = buffers.ids {
                return debug::id_image(gl, ids, size);
            }
            let depth = if copy {
                debug::read_depth(gl, fbo_of_frame, size, size)
            } else {
                debug::read_depth_texture(gl, texture, face, size)
            };
            debug::depth_image(&depth, size, size)
        }));
        if copy {
            self.timer
                .begin(gl, PassId::light(lp.light, Stage::DepthCopy));
            copy_depth(gl, self.target, texture, size, face);
            go_on!(self.step(StepKind::DepthCopy, Some(lp), shown, |_| {
                let depth = debug::read_depth_texture(gl, texture, face, size);
                debug::depth_image(&depth, size, size)
            }));
        }
        Ok(ControlFlow::Continue(()))
    }

    /// The unlit world, then the depth the planner asks for.
    fn base_pass(&mut self) -> Flow<()> {
        let gl = self.ctx.gl;
        self.timer.begin(gl, PassId::frame(Stage::Base));
        self.target.bind(gl);
        match self.fixed {
            Some(ff) => fixed::base::draw(&self.ctx, ff),
            None => passes::base::draw(&self.ctx, &self.programs.unlit),
        }
        go_on!(self.step(StepKind::Base, None, None, Self::color_image));
        let need = self.planner.depth_need(
            self.ctx.scene,
            self.ctx.plan,
            self.ctx.options,
            self.target.float_depth,
        );
        self.cache.depth_reused = need == DepthNeed::Reuse;
        if let DepthNeed::Read { reduced } = need {
            self.timer.end(gl);
            let t = Instant::now();
            let depth = self.read_depth(reduced)?;
            self.timer.record_cpu(
                PassId::frame(Stage::Occlusion),
                t.elapsed().as_secs_f64() * 1e3,
            );
            self.target.bind(gl);
            self.planner.take_depth(depth, self.ctx.options);
        } else if need == DepthNeed::Reuse {
            self.timer.end(gl);
        }
        Ok(ControlFlow::Continue(()))
    }

    /// The frame's depth for the planner: reduced by a shader, or read whole.
    fn read_depth(&mut self, reduced: bool) -> Result<Option<DepthPyramid>, RenderError> {
        let gl = self.ctx.gl;
        let (w, h) = (self.target.width, self.target.height);
        if !reduced {
            let values = debug::read_depth_bottom_up(gl, self.target.fbo, w, h);
            return Ok(DepthPyramid::from_bottom_up(values, w as usize, h as usize));
        }
        if !self.depth_reducer.as_ref().is_some_and(|r| r.fits(w, h)) {
            if let Some(old) = self.depth_reducer.take() {
                old.delete(gl);
            }
            let r = DepthReducer::new(gl, w, h).map_err(RenderError::Gl)?;
            *self.depth_reducer = Some(r);
        }
        let reducer = self.depth_reducer.as_ref().expect("created above");
        Ok(reducer.read(gl, &self.programs.depth_reduce, self.empty_vao, self.target))
    }

    /// Each shadow-volume light's draws from the planner, uploaded.
    fn volume_draws(&mut self) -> Result<(), RenderError> {
        let (gl, plan) = (self.ctx.gl, self.ctx.plan);
        if !plan.any_volumes() {
            return Ok(());
        }
        let prepare_start = Instant::now();
        let mut builds_ms = 0.0;
        for lp in plan.lights.iter().filter(|l| l.counts_volumes()) {
            let v = self
                .planner
                .volume_draws(self.ctx.scene, plan, lp, self.ctx.options)?;
            if let Err(e) = self.volume_buffers.upload(gl, v) {
                self.planner.forget_volume_draws(lp.light);
                return Err(RenderError::Gl(e));
            }
            let build_ms = if v.stats.rebuilt {
                v.stats.build_ms
            } else {
                0.0
            };
            self.timer
                .record_cpu(PassId::light(lp.light, Stage::VolumeBuild), build_ms);
            builds_ms += build_ms;
            self.cache.volume_parts_built += v.stats.parts_built;
            self.cache.volume_parts_reused += v.stats.parts_reused;
            self.volume_stats.push(v.stats);
            self.extruded_draws(lp)?;
        }
        // The per-frame decisions on the pieces (receivers, rectangles, merges, depth clips)
        // and the uploads, less the builds timed above.
        let ms = prepare_start.elapsed().as_secs_f64() * 1e3 - builds_ms;
        self.timer
            .record_cpu(PassId::frame(Stage::VolumePieces), ms.max(0.0));
        Ok(())
    }

    /// The light's groups the GPU extrudes: their meshes uploaded where their pose changed, and
    /// their draws for the stencil pass.
    fn extruded_draws(&mut self, lp: &LightPlan) -> Result<(), RenderError> {
        if lp.extruded.is_empty() {
            return Ok(());
        }
        let (gl, scene) = (self.ctx.gl, self.ctx.scene);
        let groups = self.planner.casters(scene);
        let double = self.ctx.options.shadow_volume.casters == crate::options::VolumeCasters::Both;
        let light = scene.lights[lp.light].position;
        let mut draws = Vec::with_capacity(lp.extruded.len());
        for &(g, counting) in &lp.extruded {
            let group = &groups.groups[g];
            if self
                .extrusions
                .ensure(gl, g, group, double)
                .map_err(RenderError::Gl)?
            {
                self.cache.extrusions_uploaded += 1;
            }
            let model = crate::shadow::volume::group_transform(scene, group.owner);
            draws.extend(self.extrusions.draw_of(g, model, light, counting));
        }
        self.extruded.insert(lp.light, draws);
        Ok(())
    }

    /// Each subdivided light's fragments made current (kept while the light and the triangles
    /// in its range stay as they were).
    fn subdivisions(&mut self) -> Result<(), RenderError> {
        let (gl, plan) = (self.ctx.gl, self.ctx.plan);
        if !plan.any(Technique::Subdivision) {
            return Ok(());
        }
        // The pass before is over: the CPU work here is timed on its own.
        self.timer.end(gl);
        for lp in plan.lights.iter() {
            if lp.technique != Technique::Subdivision {
                continue;
            }
            let geometry = lp.subdivided.unwrap_or(Geometry::Everything);
            let update = self
                .fragments
                .update(gl, self.ctx.scene, (lp.light, geometry))?;
            self.timer
                .record_cpu(PassId::light(lp.light, Stage::Subdivision), update.ms);
            self.cache.subdivisions_renewed += usize::from(update.renewed);
            self.cache.fragment_triangles += self
                .fragments
                .draw_of(lp.light)
                .map_or(0, |f| f.triangles());
        }
        Ok(())
    }

    /// The light's shadowed fragments, when it is subdivided this frame.
    fn fragments_of(&self, lp: &LightPlan) -> Option<LightFragmentDraw> {
        (lp.technique == Technique::Subdivision)
            .then(|| self.fragments.draw_of(lp.light))
            .flatten()
    }

    /// The light's volume draws with their buffers, when it has volumes this frame.
    fn volumes_of(&self, lp: &LightPlan) -> Option<LightVolumes<'_>> {
        if !lp.counts_volumes() {
            return None;
        }
        let draws = self.planner.last_volume_draws(lp.light)?;
        let extruded = self.extruded.get(&lp.light).map_or(&[][..], Vec::as_slice);
        self.volume_buffers.with(draws, extruded)
    }

    /// The shadow-map bindings of light `pi`'s lit passes: per view, whether it is a cube,
    /// its map, the receivers it lights and its rectangle.
    fn bindings(
        &self,
        maps: &[ViewMap],
        pi: usize,
    ) -> Vec<(bool, ShadowBinding<'a>, &'a [u32], Option<Scissor>)> {
        let lp: &'a LightPlan = &self.ctx.plan.lights[pi];
        maps.iter()
            .filter(|m| m.plan_index == pi)
            .map(|m| {
                let view = &lp.views[m.view_index];
                let receivers = lp
                    .view_receivers
                    .get(m.view_index)
                    .map_or(lp.receivers.as_slice(), Vec::as_slice);
                let rect = lp.view_scissors.get(m.view_index).copied().flatten();
                (
                    view.kind == ViewKind::Cube,
                    ShadowBinding {
                        view,
                        texture: m.texture,
                        table: m.table,
                    },
                    receivers,
                    rect.or(lp.scissor),
                )
            })
            .collect()
    }

    /// Each planned light's passes: its volumes counted and lit through the stencil, or lit
    /// through its shadow maps (or without shadows). Returns the stencil counts asked for.
    fn light_passes(&mut self, maps: &[ViewMap]) -> Flow<Option<StencilImage>> {
        let plan = self.ctx.plan;
        let mut stencil_image = None;
        for (pi, lp) in plan.lights.iter().enumerate() {
            set_scissor(self.ctx.gl, lp.scissor);
            if lp.technique == Technique::Hybrid {
                if let Some(image) = go_on!(self.hybrid_light(pi, maps)) {
                    stencil_image = Some(image);
                }
            } else if let Some(f) = self.fragments_of(lp) {
                if let Some(image) = go_on!(self.subdivision_light(lp, &f)) {
                    stencil_image = Some(image);
                }
            } else if self.volumes_of(lp).is_some() {
                if let Some(image) = go_on!(self.volume_light(lp)) {
                    stencil_image = Some(image);
                }
            } else {
                self.timer
                    .begin(self.ctx.gl, PassId::light(lp.light, Stage::Lit));
                if self.ctx.options.lighting.light_once {
                    passes::lit::clear_marks(self.ctx.gl);
                }
                let bindings = self.bindings(maps, pi);
                match self.fixed {
                    Some(ff) => fixed_maps(&self.ctx, ff, lp, &bindings, false),
                    None => draw_maps(
                        &self.ctx,
                        lp,
                        &bindings,
                        |v| self.lit_program(v),
                        (MapPass::Lit, false),
                    ),
                }
                go_on!(self.step(StepKind::Lit, Some(lp), None, Self::color_image));
            }
        }
        Ok(ControlFlow::Continue(stencil_image))
    }

    /// Light `lp`'s stencil as it stands, when the request asks for it (`wraps`: its counts
    /// wrapped rather than saturated).
    fn requested_stencil(&self, lp: &LightPlan, wraps: bool) -> Option<StencilImage> {
        let gl = self.ctx.gl;
        (self.request.stencil_of == Some(lp.light)).then(|| {
            let (w, h) = (self.target.width, self.target.height);
            let values = debug::read_stencil(gl, self.target.fbo, w, h);
            self.target.bind(gl);
            StencilImage {
                light: lp.light,
                width: w,
                height: h,
                values,
                wraps,
            }
        })
    }

    /// A hybrid light (Chan & Durand): its computation mask marked from its maps, its volumes
    /// counted where the mask lets them, then one lit pass where the map decides or the count
    /// is zero (`passes::hybrid`). Returns its stencil (mask bit and counts) when the request
    /// asks for it.
    fn hybrid_light(&mut self, pi: usize, maps: &[ViewMap]) -> Flow<Option<StencilImage>> {
        let gl = self.ctx.gl;
        let lp = &self.ctx.plan.lights[pi];
        let masked = self.ctx.options.hybrid.mask;
        let bindings = self.bindings(maps, pi);
        let mark = |run: &Self, overwrite: bool| {
            draw_maps(
                &run.ctx,
                lp,
                &bindings,
                |v| run.lit_program(v),
                (MapPass::Mark { overwrite }, true),
            )
        };
        self.timer
            .begin(gl, PassId::light(lp.light, Stage::Classify));
        if masked {
            passes::lit::clear_marks(gl);
            mark(self, false);
        }
        self.timer
            .begin(gl, PassId::light(lp.light, Stage::Stencil));
        if let Some(v) = self.volumes_of(lp) {
            passes::stencil::draw(&self.ctx, &self.programs.volume, &v, lp.scissor, masked);
        }
        if !masked {
            self.timer
                .begin(gl, PassId::light(lp.light, Stage::Classify));
            mark(self, true);
        }
        let (w, h) = (self.target.width, self.target.height);
        let fbo = self.target.fbo;
        go_on!(self.step(StepKind::ComputationMask, Some(lp), None, |_| {
            debug::stencil_image(&debug::read_stencil(gl, fbo, w, h), w, h, true)
        }));
        let stencil = self.requested_stencil(lp, true);
        self.timer.begin(gl, PassId::light(lp.light, Stage::Lit));
        draw_maps(
            &self.ctx,
            lp,
            &bindings,
            |v| self.lit_program(v),
            (MapPass::Lit, true),
        );
        go_on!(self.step(StepKind::Lit, Some(lp), None, Self::color_image));
        Ok(ControlFlow::Continue(stencil))
    }

    /// A shadow-volume light: its volumes into the stencil, its lit pass where the count is
    /// zero (or everywhere, then the fill quad: `shadow_volume.shading = fill`). Returns its
    /// stencil counts when the request asks for them.
    fn volume_light(&mut self, lp: &LightPlan) -> Flow<Option<StencilImage>> {
        let gl = self.ctx.gl;
        let o = self.ctx.options;
        let fill = o.shadow_volume.shading == VolumeShading::Fill;
        self.timer
            .begin(gl, PassId::light(lp.light, Stage::Stencil));
        self.count_volumes(lp);
        let wraps = self.counts_wrap();
        go_on!(self.stencil_step(StepKind::Stencil, lp, wraps));
        let stencil = self.requested_stencil(lp, wraps);
        go_on!(self.lit_over_stencil(lp, !fill));
        if fill {
            self.timer.begin(gl, PassId::light(lp.light, Stage::Fill));
            match self.fixed {
                Some(ff) => fixed::stencil::fill(gl, ff, FILL_SHADE),
                None => passes::stencil::fill(gl, &self.programs.fill, self.empty_vao, FILL_SHADE),
            }
            go_on!(self.step(StepKind::Fill, Some(lp), None, Self::color_image));
        }
        Ok(ControlFlow::Continue(stencil))
    }

    /// A subdivided light: its models' volumes counted (`subdivision.models = volumes`), its
    /// shadowed fragments marked into the same stencil, its lit pass where the stencil is
    /// zero. Returns its stencil when the request asks for it.
    fn subdivision_light(
        &mut self,
        lp: &LightPlan,
        f: &LightFragmentDraw,
    ) -> Flow<Option<StencilImage>> {
        let gl = self.ctx.gl;
        self.timer
            .begin(gl, PassId::light(lp.light, Stage::Stencil));
        let counted = self.count_volumes(lp);
        let wraps = counted && self.counts_wrap();
        if counted {
            go_on!(self.stencil_step(StepKind::Stencil, lp, wraps));
        }
        self.mark_fragments(f, !counted);
        go_on!(self.stencil_step(StepKind::Fragments, lp, wraps));
        let stencil = self.requested_stencil(lp, wraps);
        go_on!(self.lit_over_stencil(lp, true));
        Ok(ControlFlow::Continue(stencil))
    }

    /// Whether volume counts wrap rather than saturate.
    fn counts_wrap(&self) -> bool {
        self.ctx.options.shadow_volume.wrap == StencilWrap::Wrap
            || self.ctx.plan.stencil == StencilPasses::Separate
    }

    /// The light's volumes counted into the cleared stencil (a subdivided light's: its
    /// models', and the world's on models); false when it has none this frame (the stencil is
    /// left as it was).
    fn count_volumes(&self, lp: &LightPlan) -> bool {
        let Some(v) = self.volumes_of(lp) else {
            return false;
        };
        match self.fixed {
            Some(ff) => fixed::stencil::draw(&self.ctx, ff, &v, lp.scissor),
            None => passes::stencil::draw(&self.ctx, &self.programs.volume, &v, lp.scissor, false),
        }
        true
    }

    /// A subdivided light's shadowed fragments marked into the stencil (cleared first with
    /// `clear`; else over the counts of its volumes).
    fn mark_fragments(&self, f: &LightFragmentDraw, clear: bool) {
        match self.fixed {
            Some(ff) => fixed::stencil::mark_fragments(&self.ctx, ff, f, clear),
            None => passes::stencil::mark_fragments(&self.ctx, &self.programs.fragments, f, clear),
        }
    }

    /// A subdivided light's whole stencil, as its frame leaves it: its volumes counted, then
    /// its fragments marked over them.
    fn subdivision_stencil(&self, lp: &LightPlan, f: &LightFragmentDraw) {
        let counted = self.count_volumes(lp);
        self.mark_fragments(f, !counted);
    }

    /// A walkthrough step showing light `lp`'s stencil as it stands (`wraps`: counts wrapped).
    fn stencil_step(&mut self, kind: StepKind, lp: &LightPlan, wraps: bool) -> Flow<()> {
        let gl = self.ctx.gl;
        let (w, h) = (self.target.width, self.target.height);
        let fbo = self.target.fbo;
        self.step(kind, Some(lp), None, |_| {
            debug::stencil_image(&debug::read_stencil(gl, fbo, w, h), w, h, wraps)
        })
    }

    /// Light `lp`'s lit pass over the stencil its volumes or fragments left (`test`: only
    /// where it is zero; off, everywhere, for the fill variant).
    fn lit_over_stencil(&mut self, lp: &LightPlan, test: bool) -> Flow<()> {
        self.timer
            .begin(self.ctx.gl, PassId::light(lp.light, Stage::Lit));
        let shadow = LitShadow::Stencil { test };
        match self.fixed {
            Some(ff) => fixed::lit::draw(&self.ctx, ff, lp, &shadow, &lp.receivers),
            None => passes::lit::draw(
                &self.ctx,
                self.lit_program(LitVariant::plain(false)),
                lp,
                &shadow,
                &lp.receivers,
            ),
        }
        self.step(StepKind::Lit, Some(lp), None, Self::color_image)
    }

    /// Volumes and silhouettes drawn over the finished frame, when asked for (untimed).
    fn overlays(&self) {
        let o = self.request.overlays;
        if !(o.volumes || o.silhouettes) {
            return;
        }
        self.target.bind(self.ctx.gl);
        let shown = self
            .ctx
            .plan
            .lights
            .iter()
            .filter(|lp| o.light.is_none_or(|l| l == lp.light));
        for lp in shown {
            if let Some(v) = self.volumes_of(lp) {
                passes::debug::volumes(
                    &self.ctx,
                    &self.programs.debug_volume,
                    &v,
                    o.volumes,
                    o.silhouettes,
                );
            }
        }
    }

    /// The G-buffer and each light's decision mask, when the request asks for masks
    /// (untimed, after the frame).
    fn measure(&self, maps: &[ViewMap]) -> (Option<GBuffer>, Vec<Mask>, Vec<HybridStats>) {
        let gl = self.ctx.gl;
        let plan = self.ctx.plan;
        let Some((gtarget, mtarget)) = self.measure_targets.filter(|_| self.request.masks) else {
            return (None, Vec::new(), Vec::new());
        };
        let mut hybrid_stats = Vec::new();
        gtarget_bind(gl, gtarget);
        passes::gbuffer::draw(&self.ctx, &self.programs.gbuffer);
        let gbuffer = read_gbuffer(gl, gtarget);
        let mut masks = Vec::with_capacity(plan.lights.len() + plan.culled.len());
        for (pi, lp) in plan.lights.iter().enumerate() {
            mtarget.bind(gl);
            set_scissor(gl, None);
            // SAFETY: clears the mask to "not a receiver"; depth and stencil untouched.
            unsafe {
                gl.color_mask(true, true, true, true);
                gl.clear_color(0.0, 0.0, 0.0, 0.0);
                gl.clear(glow::COLOR_BUFFER_BIT);
            }
            set_scissor(gl, lp.scissor);
            if let Some(ff) = self.fixed {
                self.fixed_mask(ff, lp, &self.bindings(maps, pi));
                set_scissor(gl, None);
                let mut values = mtarget.read(gl);
                keep_reached(&mut values, &gbuffer, &self.ctx.scene.lights[lp.light]);
                masks.push(Mask {
                    light: lp.light,
                    width: mtarget.width,
                    height: mtarget.height,
                    values,
                });
                continue;
            }
            match self.volumes_of(lp) {
                Some(v) if lp.technique == Technique::Hybrid => {
                    let (stencil, fragments) = self.hybrid_mask(pi, maps, &v, mtarget);
                    set_scissor(gl, None);
                    let values = mtarget.read(gl);
                    hybrid_stats.push(hybrid_stats_of(lp.light, &values, &stencil, fragments));
                    masks.push(Mask {
                        light: lp.light,
                        width: mtarget.width,
                        height: mtarget.height,
                        values,
                    });
                    continue;
                }
                _ if let Some(f) = self.fragments_of(lp) => {
                    self.subdivision_stencil(lp, &f);
                    self.mask_over_stencil(lp);
                }
                Some(_) => {
                    self.count_volumes(lp);
                    self.mask_over_stencil(lp);
                }
                None => draw_maps(
                    &self.ctx,
                    lp,
                    &self.bindings(maps, pi),
                    |v| self.lit_program(v),
                    (MapPass::Mask, false),
                ),
            }
            set_scissor(gl, None);
            masks.push(Mask {
                light: lp.light,
                width: mtarget.width,
                height: mtarget.height,
                values: mtarget.read(gl),
            });
        }
        // Culled lights reach no pixel in view.
        for &light in &plan.culled {
            masks.push(Mask {
                light,
                width: mtarget.width,
                height: mtarget.height,
                values: vec![0; (mtarget.width * mtarget.height) as usize],
            });
        }
        masks.sort_by_key(|m| m.light);
        (Some(gbuffer), masks, hybrid_stats)
    }

    /// Light `lp`'s mask where its stencil is zero, after its volumes or fragments.
    fn mask_over_stencil(&self, lp: &LightPlan) {
        passes::lit::draw_mask(
            &self.ctx,
            self.lit_program(LitVariant::plain(true)),
            lp,
            &LitShadow::Stencil { test: true },
            &lp.receivers,
        );
    }

    /// A hybrid light's mask, drawn as its frame drew it (mask, counts, the decision), with
    /// its volume fragments counted with and without the mask on the way. Returns the
    /// stencil (its top bit: where the map decides) and the two fragment counts.
    fn hybrid_mask(
        &self,
        pi: usize,
        maps: &[ViewMap],
        v: &LightVolumes<'_>,
        mtarget: &MaskTarget,
    ) -> (Vec<u8>, (Option<u64>, Option<u64>)) {
        let gl = self.ctx.gl;
        let lp = &self.ctx.plan.lights[pi];
        let masked = self.ctx.options.hybrid.mask;
        let bindings = self.bindings(maps, pi);
        let pass = |kind| {
            draw_maps(
                &self.ctx,
                lp,
                &bindings,
                |variant| self.lit_program(variant),
                (kind, true),
            )
        };
        let volume = &self.programs.volume;
        let fragments;
        if masked {
            passes::lit::clear_marks(gl);
            pass(MapPass::Mark { overwrite: false });
            fragments = (
                passes::hybrid::volume_fragments(&self.ctx, volume, v, (true, lp.scissor)),
                passes::hybrid::volume_fragments(&self.ctx, volume, v, (false, lp.scissor)),
            );
            passes::stencil::draw(&self.ctx, volume, v, lp.scissor, true);
        } else {
            passes::stencil::draw(&self.ctx, volume, v, lp.scissor, false);
            let all = passes::hybrid::volume_fragments(&self.ctx, volume, v, (false, lp.scissor));
            fragments = (all, all);
            pass(MapPass::Mark { overwrite: true });
        }
        pass(MapPass::Mask);
        let stencil = debug::read_stencil(gl, mtarget.fbo, mtarget.width, mtarget.height);
        mtarget.bind(gl);
        (stencil, fragments)
    }
}

/// Sets the mask of light `lp` from the fixed-function passes: its volumes' counts, or its maps.
impl FrameRun<'_> {
    fn fixed_mask(
        &self,
        ff: &FixedFunction,
        lp: &LightPlan,
        bindings: &[(bool, ShadowBinding, &[u32], Option<Scissor>)],
    ) {
        let shadow = LitShadow::Stencil { test: true };
        match self.volumes_of(lp) {
            _ if let Some(f) = self.fragments_of(lp) => {
                self.subdivision_stencil(lp, &f);
                fixed::lit::draw_mask(&self.ctx, ff, lp, &shadow, &lp.receivers);
            }
            Some(_) => {
                self.count_volumes(lp);
                fixed::lit::draw_mask(&self.ctx, ff, lp, &shadow, &lp.receivers);
            }
            None => fixed_maps(&self.ctx, ff, lp, bindings, true),
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
        e => Err(RenderError::Gl(format!("the frame raised GL error 0x{e:x}"))),
    }
}

fn keep_reached(values: &mut [u8], gbuffer: &GBuffer, light: &crate::scene::Light) {
    for (i, v) in values.iter_mut().enumerate() {
        let reached = gbuffer.is_receiver_surface(i) && {
            let p = glam::Vec3::from_array(gbuffer.position[i]).as_dvec3();
            let n = glam::Vec3::from_array(gbuffer.normal[i]).as_dvec3();
            light.reaches(p, n)
        };
        if !reached {
            *v = MaskValue::NotReceiver as u8;
        }
    }
}

/// The fixed-function lit (or mask) passes of a light: one per shadow map view, or one without
/// shadows.
fn fixed_maps(
    ctx: &PassContext,
    ff: &FixedFunction,
    lp: &LightPlan,
    bindings: &[(bool, ShadowBinding, &[u32], Option<Scissor>)],
    mask: bool,
) {
    let pass = |s: &LitShadow, receivers: &[u32]| {
        if mask {
            fixed::lit::draw_mask(ctx, ff, lp, s, receivers);
        } else {
            fixed::lit::draw(ctx, ff, lp, s, receivers);
        }
    };
    if bindings.is_empty() {
        pass(&LitShadow::None, &lp.receivers);
    }
    for (_, b, receivers, rect) in bindings {
        set_scissor(ctx.gl, *rect);
        pass(&LitShadow::Map(b), receivers);
    }
    set_scissor(ctx.gl, lp.scissor);
}

/// What a light's map passes write.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum MapPass {
    /// Light, added to the frame.
    Lit,
    /// The decision, into the mask target.
    Mask,
    /// The hybrid's computation mask, into the stencil (`overwrite`: over counts).
    Mark { overwrite: bool },
}

/// One light's lit (or mask, or marking) passes: one per shadow map view, one for an omni
/// light's six merged spots, or one without shadows; `hybrid` wraps the maps in
/// `LitShadow::Hybrid`.
fn draw_maps<'p>(
    ctx: &PassContext,
    lp: &LightPlan,
    bindings: &[(bool, ShadowBinding, &[u32], Option<Scissor>)],
    program: impl Fn(LitVariant) -> &'p Program,
    (kind, hybrid): (MapPass, bool),
) {
    let pass = |six: bool, cube: bool, s: &LitShadow, receivers: &[u32]| {
        let shadow_map = !matches!(s, LitShadow::None);
        let v = LitVariant {
            shadow_map,
            cube,
            six,
            mask: kind == MapPass::Mask,
            hybrid,
            warp_depth: shadow_map && lp.technique == Technique::Tsm,
            buffer: if shadow_map {
                lp.buffer
            } else {
                MapBuffer::Depth
            },
        };
        let p = program(v);
        let wrapped;
        let s = if hybrid {
            wrapped = LitShadow::Hybrid(s);
            &wrapped
        } else {
            s
        };
        match kind {
            MapPass::Lit => passes::lit::draw(ctx, p, lp, s, receivers),
            MapPass::Mask => passes::lit::draw_mask(ctx, p, lp, s, receivers),
            MapPass::Mark { overwrite } => {
                passes::hybrid::mark(ctx, p, lp, s, receivers, overwrite)
            }
        }
    };
    if bindings.is_empty() {
        pass(false, false, &LitShadow::None, &lp.receivers);
    }
    if lp.merged && bindings.len() == 6 {
        let maps: Vec<&ShadowBinding> = bindings.iter().map(|(_, b, _, _)| b).collect();
        pass(true, false, &LitShadow::Faces(&maps), &lp.receivers);
        return;
    }
    for (cube, b, receivers, rect) in bindings {
        set_scissor(ctx.gl, *rect);
        pass(false, *cube, &LitShadow::Map(b), receivers);
    }
    set_scissor(ctx.gl, lp.scissor);
}

/// A hybrid light's stats from its mask values and its stencil after the frame's passes.
fn hybrid_stats_of(
    light: usize,
    values: &[u8],
    stencil: &[u8],
    (volume_fragments, volume_fragments_unmasked): (Option<u64>, Option<u64>),
) -> HybridStats {
    let receiver = |v: u8| v == MaskValue::Lit as u8 || v == MaskValue::Shadowed as u8;
    let mut stats = HybridStats {
        light,
        receiver_pixels: 0,
        silhouette_pixels: 0,
        volume_fragments,
        volume_fragments_unmasked,
    };
    for (&v, &s) in values.iter().zip(stencil) {
        if receiver(v) {
            stats.receiver_pixels += 1;
            if s as u32 & passes::lit::MAP_DECIDES == 0 {
                stats.silhouette_pixels += 1;
            }
        }
    }
    stats
}

fn gtarget_bind(gl: &glow::Context, t: &GBufferTarget) {
    // SAFETY: the G-buffer framebuffer is complete.
    unsafe {
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(t.fbo));
        gl.viewport(0, 0, t.width as i32, t.height as i32);
    }
}

fn read_gbuffer(gl: &glow::Context, t: &GBufferTarget) -> GBuffer {
    let position = t.read(gl, 0);
    let normal = t.read(gl, 1);
    GBuffer {
        width: t.width,
        height: t.height,
        kind: normal
            .iter()
            .map(|n| n[3].round().clamp(0.0, 2.0) as u8)
            .collect(),
        position: position.iter().map(|p| [p[0], p[1], p[2]]).collect(),
        normal: normal.iter().map(|n| [n[0], n[1], n[2]]).collect(),
    }
}

impl Drop for Renderer {
    fn drop(&mut self) {
        let gl_arc = self.gl.clone();
        let gl: &glow::Context = &gl_arc;
        if let Some(g) = self.gpu.take() {
            g.delete(gl);
        }
        self.programs.delete(gl);
        self.target.delete(gl);
        self.shadow_maps.delete(gl);
        self.id_tables.delete(gl);
        self.volume_buffers.delete(gl);
        self.extrusions.delete(gl);
        self.fragments.delete(gl);
        if let Some((g, m)) = self.measure_targets.take() {
            g.delete(gl);
            m.delete(gl);
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
