//! Executes a frame's plan with GL: owns the programs, the scene's GPU copy, the framebuffer and
//! the shadow maps, runs the passes in the paper's order and returns a [`Frame`].
//!
//! Order (paper 3.1): for each shadow-mapped light, its views into depth textures (drawn into the
//! frame's depth buffer and copied, or rendered straight into the texture); then the unlit world;
//! then each light's additive pass. Masks and the G-buffer, when asked for, are drawn after the
//! timed frame.

use super::caps::{self, Caps};
use super::debug;
use super::depth_reduce::{DepthInputs, DepthReducer};
use super::passes::lit::{LitShadow, ShadowBinding};
use super::passes::shadow_map::{DepthTarget, copies_from_frame, copy_depth};
use super::passes::{self, PassContext, set_scissor};
use super::program::{Program, ProgramError, sources};
use super::shadow_maps::ShadowMaps;
use super::target::{Framebuffer, GBufferTarget, MaskTarget};
use super::timing::PassTimer;
use super::upload::GpuScene;
use super::volumes::{PieceChoices, VolumeCache, VolumeStats};
use crate::frame::CacheStats;
use crate::frame::{Frame, GBuffer, Mask, Rgba, StencilImage, Step, StepKind};
use crate::options::{
    Compare, CompareResult, DepthBits, Filter, Options, Outside, StencilPasses, StencilWrap,
    Technique, VolumeShading,
};
use crate::plan::auto::CostMemory;
use crate::plan::occlusion::DepthPyramid;
use crate::plan::scissor::Scissor;
use crate::plan::{LightPlan, Plan};
use crate::scene::{Camera, Scene};
use crate::shadow::projection::cube_face_view;
use crate::shadow::views::ViewKind;
use glow::HasContext;
use std::collections::HashMap;
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
    } = v;
    let mut d = Vec::new();
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
        if o.result == CompareResult::Alpha {
            d.push("RESULT_ALPHA");
        }
    }
    if mask {
        d.push("MASK_OUTPUT");
    }
    d
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
}

/// Bestimt and Freitag's fill colour (their 0x00E0E0E0 with DESTCOLOR blending).
pub const FILL_SHADE: f32 = 224.0 / 255.0;

struct Programs {
    unlit: Program,
    gbuffer: Program,
    depth: Program,
    volume: Program,
    fill: Program,
    /// The depth's 4×4 block maxima for the planner.
    depth_reduce: Program,
    /// Volumes and silhouettes drawn over the frame (debug overlay).
    debug_volume: Program,
    /// Lit programs by their define set, compiled on first use.
    lit: HashMap<String, Program>,
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
            volume: Program::new(
                gl,
                "volume",
                sources::VOLUME_VERT,
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
            debug_volume: Program::new(
                gl,
                "debug_volume",
                sources::DEBUG_VOLUME_VERT,
                Some(sources::DEBUG_VOLUME_FRAG),
                &[],
            )?,
            lit: HashMap::new(),
        })
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
            &self.volume,
            &self.fill,
            &self.depth_reduce,
            &self.debug_volume,
        ] {
            p.delete(gl);
        }
        for p in self.lit.values() {
            p.delete(gl);
        }
        self.lit.clear();
    }
}

pub struct Renderer {
    gl: Arc<glow::Context>,
    pub caps: Caps,
    programs: Programs,
    target: Framebuffer,
    gpu: Option<GpuScene>,
    timer: PassTimer,
    shadow_maps: ShadowMaps,
    volumes: VolumeCache,
    /// Created on the first frame that asks for masks.
    measure_targets: Option<(GBufferTarget, MaskTarget)>,
    /// Core profile draws need a bound VAO even without attributes (full-screen triangles).
    empty_vao: glow::VertexArray,
    /// Created on the first frame that reduces its depth for the planner.
    depth_reducer: Option<DepthReducer>,
    /// The last depth read for the planner: a frame whose depth is the same keeps the fits
    /// and draws made for it.
    last_depth: Option<DepthPyramid>,
    /// Advanced whenever the depth read differs from `last_depth` (see
    /// `PieceChoices::depth_generation`).
    depth_generation: u64,
    /// What `last_depth` was drawn from (`plan.reuse_depth`).
    depth_inputs: Option<DepthInputs>,
    /// The shadow-map views of the last frame, for the depth-map debug view.
    last_maps: Vec<LastMap>,
    /// Each light's measured cost per technique, for `technique = auto`.
    costs: CostMemory,
}

/// One shadow-mapped view's texture, by light plan and view index.
struct ViewMap {
    plan_index: usize,
    view_index: usize,
    texture: glow::Texture,
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
            volumes: VolumeCache::default(),
            measure_targets: None,
            empty_vao,
            depth_reducer: None,
            last_depth: None,
            depth_generation: 0,
            depth_inputs: None,
            last_maps: Vec::new(),
            costs: CostMemory::default(),
        })
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
        self.volumes.delete(&self.gl);
        self.costs = CostMemory::default();
        self.last_depth = None;
        self.depth_inputs = None;
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
        let plan = Plan::build_with(scene, camera, options, &self.costs);
        let frame_only = request.frame_only;
        let frame = self.execute(scene, &plan, options, request)?;
        // Frame-only timing has no per-light passes to learn from.
        if !frame_only {
            let ran: Vec<(usize, Technique)> =
                plan.lights.iter().map(|l| (l.light, l.technique)).collect();
            self.costs.record(&frame.passes, &ran);
        }
        Ok(frame)
    }

    /// What `technique = auto` has measured so far.
    pub fn costs(&self) -> &CostMemory {
        &self.costs
    }

    fn check_support(&self, options: &Options, plan: &Plan) -> Result<(), RenderError> {
        if !plan
            .lights
            .iter()
            .any(|l| l.technique == Technique::ShadowMap)
        {
            return Ok(());
        }
        let o = &options.shadow_map;
        let max = self.caps.max_texture_size.max(1) as u32;
        if o.size > max {
            return Err(RenderError::Unsupported(format!(
                "shadow_map.size = {} exceeds GL_MAX_TEXTURE_SIZE {max}",
                o.size
            )));
        }
        if o.depth_source == crate::options::DepthSource::Fbo
            && !self.caps.has("render_to_depth_texture")
        {
            return Err(RenderError::Unsupported(
                "shadow_map.depth_source = fbo needs render-to-depth-texture; use copy".into(),
            ));
        }
        if o.depth_bits == DepthBits::D32f && !self.caps.has("float_depth") {
            return Err(RenderError::Unsupported(
                "shadow_map.depth_bits = 32f needs float depth textures; use 24".into(),
            ));
        }
        if o.outside == Outside::ClipPlanes && !self.caps.has("clip_distances") {
            return Err(RenderError::Unsupported(
                "shadow_map.outside = clip_planes needs 4 clip distances; use range".into(),
            ));
        }
        Ok(())
    }

    /// Runs the passes of `plan`, then, untimed, the measurement passes the request asks for.
    pub fn execute(
        &mut self,
        scene: &Scene,
        plan: &Plan,
        options: &Options,
        request: FrameRequest,
    ) -> Result<Frame, RenderError> {
        self.check_support(options, plan)?;
        let sm = &options.shadow_map;
        let shadow_mapped = plan
            .lights
            .iter()
            .any(|l| l.technique == Technique::ShadowMap);
        let copy = shadow_mapped && copies_from_frame(sm);
        let alloc = if copy { (sm.size, sm.size) } else { (0, 0) };
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
        // Compile what this frame needs before borrowing the programs for the passes.
        let gl_arc = self.gl.clone();
        let gl: &glow::Context = &gl_arc;
        let mut variants: HashMap<LitVariant, String> = HashMap::new();
        for (shadow_map, cube, six) in [
            (false, false, false),
            (true, false, false),
            (true, true, false),
            (true, false, true),
        ] {
            for mask in [false, true] {
                if (shadow_map && !shadow_mapped) || (mask && !request.masks) {
                    continue;
                }
                let v = LitVariant {
                    shadow_map,
                    cube,
                    six,
                    mask,
                };
                let defines = lit_defines(options, v, request.overlays.texel_grid);
                let key = self.programs.lit_variant(gl, &defines)?;
                variants.insert(v, key);
            }
        }

        self.timer.start_frame(!request.frame_only);
        let start = Instant::now();
        let mut cache = CacheStats::default();
        let mut stepper = Stepper {
            stop: request.stop_after,
            steps: Vec::new(),
        };
        // Whoever drew last (a UI painter in the viewer) may have left state the passes do not
        // set themselves.
        // SAFETY: fixed-function state only.
        unsafe {
            gl.disable(glow::SCISSOR_TEST);
            gl.disable(glow::BLEND);
            gl.disable(glow::STENCIL_TEST);
            gl.disable(glow::FRAMEBUFFER_SRGB);
            gl.color_mask(true, true, true, true);
            gl.depth_mask(true);
            gl.pixel_store_i32(glow::UNPACK_ALIGNMENT, 4);
        }
        self.last_maps.clear();
        if self.gpu.is_none() {
            return Err(RenderError::NoScene);
        }
        let gpu = self.gpu.as_ref().ok_or(RenderError::NoScene)?;
        let ctx = PassContext {
            gl,
            scene,
            gpu,
            plan,
            options,
        };

        // Shadow maps of every shadow-mapped light first (paper 3.1).
        let mut maps: Vec<ViewMap> = Vec::new();
        let fbo = if shadow_mapped && !copy {
            Some(self.shadow_maps.fbo(gl).map_err(RenderError::Gl)?)
        } else {
            None
        };
        for (pi, lp) in plan.lights.iter().enumerate() {
            if lp.technique != Technique::ShadowMap {
                continue;
            }
            for (vi, view) in lp.views.iter().enumerate() {
                let cube = view.kind == ViewKind::Cube;
                let (texture, holds) = self
                    .shadow_maps
                    .slot(gl, lp.light, vi, cube, sm.size, sm.depth_bits)
                    .map_err(RenderError::Gl)?;
                let key = lp.view_keys.get(vi).copied().flatten();
                let casters = lp.view_casters.get(vi).map(Vec::as_slice);
                let faces: Vec<(Option<usize>, glam::Mat4)> = if cube {
                    let eye = scene.lights[lp.light].position;
                    (0..6)
                        .map(|f| (Some(f), view.projection * cube_face_view(eye, f)))
                        .collect()
                } else {
                    vec![(None, view.view_proj())]
                };
                if key.is_some() && holds == key {
                    cache.maps_reused += 1;
                } else {
                    cache.maps_rendered += 1;
                }
                let faces = if key.is_some() && holds == key {
                    Vec::new()
                } else {
                    faces
                };
                for (face, view_proj) in faces {
                    let shown = face.or(Some(vi));
                    let target = match fbo {
                        Some(fbo) => DepthTarget::Fbo { fbo, texture },
                        None => DepthTarget::Copy {
                            frame: &self.target,
                            texture,
                        },
                    };
                    self.timer
                        .begin(gl, format!("light{}.shadow_map", lp.light));
                    passes::shadow_map::render(
                        &ctx,
                        &self.programs.depth,
                        &passes::shadow_map::MapView {
                            view_proj,
                            size: sm.size,
                            cube_face: face,
                            order: lp.order,
                            casters,
                        },
                        &target,
                    );
                    if stepper.record(StepKind::LightView, Some(lp), shown) {
                        let depth = if copy {
                            debug::read_depth(gl, self.target.fbo, sm.size, sm.size)
                        } else {
                            debug::read_depth_texture(gl, texture, face, sm.size)
                        };
                        let image = debug::depth_image(&depth, sm.size, sm.size);
                        return self.stopped(gl, plan, stepper, image, Vec::new(), start);
                    }
                    if copy {
                        self.timer
                            .begin(gl, format!("light{}.depth_copy", lp.light));
                        copy_depth(gl, &self.target, texture, sm.size, face);
                        if stepper.record(StepKind::DepthCopy, Some(lp), shown) {
                            let depth = debug::read_depth_texture(gl, texture, face, sm.size);
                            let image = debug::depth_image(&depth, sm.size, sm.size);
                            return self.stopped(gl, plan, stepper, image, Vec::new(), start);
                        }
                    }
                }
                self.shadow_maps.set_content(lp.light, vi, key);
                ShadowMaps::configure(gl, texture, cube, sm.compare, sm.filter);
                self.last_maps.push(LastMap {
                    light: lp.light,
                    view: vi,
                    texture,
                    cube,
                    size: sm.size,
                });
                maps.push(ViewMap {
                    plan_index: pi,
                    view_index: vi,
                    texture,
                });
            }
        }

        self.timer.begin(gl, "base");
        self.target.bind(gl);
        passes::base::draw(&ctx, &self.programs.unlit);
        if stepper.record(StepKind::Base, None, None) {
            let image = self.color_image(gl);
            return self.stopped(gl, plan, stepper, image, Vec::new(), start);
        }
        // Shadow volumes: built on the CPU (or reused) once the base pass has laid down the
        // depth that `plan.occlusion` judges receivers by.
        let mut volume_stats: Vec<VolumeStats> = Vec::new();
        let any_volumes = plan
            .lights
            .iter()
            .any(|l| l.technique == Technique::ShadowVolume);
        let reads_depth = options.plan.occlusion || options.plan.depth_clip;
        let wants_depth = any_volumes && options.plan.enabled && reads_depth;
        let inputs = wants_depth.then(|| DepthInputs::of(scene, plan, &self.target, options));
        // The base pass drew what the last depth read was drawn from: it is that depth.
        let known = options.plan.reuse_depth
            && inputs.is_some()
            && self.last_depth.is_some()
            && inputs == self.depth_inputs;
        cache.depth_reused = known;
        if known {
            self.timer.end(gl);
        }
        let depth = if wants_depth && !known {
            self.timer.end(gl);
            let t = Instant::now();
            let (w, h) = (self.target.width, self.target.height);
            let pyramid = if options.plan.reduce_depth {
                if !self.depth_reducer.as_ref().is_some_and(|r| r.fits(w, h)) {
                    if let Some(old) = self.depth_reducer.take() {
                        old.delete(gl);
                    }
                    let r = DepthReducer::new(gl, w, h).map_err(RenderError::Gl)?;
                    self.depth_reducer = Some(r);
                }
                let reducer = self.depth_reducer.as_ref().expect("created above");
                reducer.read(
                    gl,
                    &self.programs.depth_reduce,
                    self.empty_vao,
                    &self.target,
                )
            } else {
                let values = debug::read_depth_bottom_up(gl, self.target.fbo, w, h);
                DepthPyramid::from_bottom_up(values, w as usize, h as usize)
            };
            self.timer
                .record_cpu("occlusion", t.elapsed().as_secs_f64() * 1e3);
            self.target.bind(gl);
            pyramid
        } else {
            None
        };
        // Frames that read no depth (other techniques) leave the last one standing.
        let same_depth = known
            || match (&depth, &self.last_depth) {
                (Some(new), Some(last)) => new.same_as(last),
                _ => false,
            };
        let read = known || depth.is_some();
        if known {
            self.volumes.begin_frame(options.plan.reuse_depth_fits);
        } else if read {
            // The fits kept are those made for `last_depth`.
            self.volumes
                .begin_frame(same_depth && options.plan.reuse_depth_fits);
            if !same_depth {
                self.depth_generation += 1;
            }
            self.last_depth = depth;
            self.depth_inputs = inputs;
        }
        let pieces = PieceChoices {
            camera: &plan.camera,
            depth: self.last_depth.as_ref().filter(|_| read),
            occlusion: options.plan.occlusion,
            depth_clip: if options.plan.depth_clip {
                options.plan.depth_clip_planes as usize
            } else {
                0
            },
            scissor: options.plan.enabled && options.plan.piece_scissor,
            merge: options.plan.enabled && options.plan.merge_pieces,
            cull_clipped: options.plan.enabled && options.plan.cull_clipped,
            reuse_fits: options.plan.reuse_depth_fits,
            reuse_draws: options.plan.enabled && options.plan.reuse_volume_draws,
            depth_generation: self.depth_generation,
            truncate: options.plan.enabled && options.plan.truncate_volumes,
        };
        let prepare_start = Instant::now();
        let mut builds_ms = 0.0;
        for lp in plan
            .lights
            .iter()
            .filter(|l| l.technique == Technique::ShadowVolume)
        {
            let v = self
                .volumes
                .prepare(gl, scene, lp, &options.shadow_volume, pieces)
                .map_err(RenderError::Gl)?;
            let build_ms = if v.stats.rebuilt {
                v.stats.build_ms
            } else {
                0.0
            };
            self.timer
                .record_cpu(format!("light{}.volume_build", lp.light), build_ms);
            builds_ms += build_ms;
            cache.volume_parts_built += v.stats.parts_built;
            cache.volume_parts_reused += v.stats.parts_reused;
            volume_stats.push(v.stats);
        }
        if any_volumes {
            // The per-frame decisions on the pieces (receivers, rectangles, merges, depth
            // clips) and the uploads, less the builds timed above.
            let ms = prepare_start.elapsed().as_secs_f64() * 1e3 - builds_ms;
            self.timer.record_cpu("volume_pieces", ms.max(0.0));
        }

        let mut stencil_image = None;
        let lit_program = |shadow_map: bool, cube: bool, six: bool, mask: bool| {
            &self.programs.lit[&variants[&LitVariant {
                shadow_map,
                cube,
                six,
                mask,
            }]]
        };
        let bindings = |pi: usize| -> Vec<(bool, ShadowBinding, &[u32], Option<Scissor>)> {
            let lp = &plan.lights[pi];
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
                        },
                        receivers,
                        rect.or(lp.scissor),
                    )
                })
                .collect()
        };
        let fill = options.shadow_volume.shading == VolumeShading::Fill;
        for (pi, lp) in plan.lights.iter().enumerate() {
            set_scissor(gl, lp.scissor);
            match (lp.technique, self.volumes.get(lp.light)) {
                (Technique::ShadowVolume, Some(v)) => {
                    self.timer.begin(gl, format!("light{}.stencil", lp.light));
                    passes::stencil::draw(&ctx, &self.programs.volume, v, lp.scissor);
                    let wants_stencil = request.stencil_of == Some(lp.light);
                    let stop = stepper.record(StepKind::Stencil, Some(lp), None);
                    if wants_stencil || stop {
                        let (w, h) = (self.target.width, self.target.height);
                        let values = debug::read_stencil(gl, self.target.fbo, w, h);
                        self.target.bind(gl);
                        let wraps = options.shadow_volume.wrap == StencilWrap::Wrap
                            || plan.stencil == StencilPasses::Separate;
                        if stop {
                            let image = debug::stencil_image(&values, w, h, wraps);
                            return self.stopped(gl, plan, stepper, image, volume_stats, start);
                        }
                        stencil_image = Some(StencilImage {
                            light: lp.light,
                            width: w,
                            height: h,
                            values,
                            wraps,
                        });
                    }
                    self.timer.begin(gl, format!("light{}.lit", lp.light));
                    passes::lit::draw(
                        &ctx,
                        lit_program(false, false, false, false),
                        lp,
                        &LitShadow::Stencil { test: !fill },
                        &lp.receivers,
                    );
                    if stepper.record(StepKind::Lit, Some(lp), None) {
                        let image = self.color_image(gl);
                        return self.stopped(gl, plan, stepper, image, volume_stats, start);
                    }
                    if fill {
                        self.timer.begin(gl, format!("light{}.fill", lp.light));
                        passes::stencil::fill(gl, &self.programs.fill, self.empty_vao, FILL_SHADE);
                        if stepper.record(StepKind::Fill, Some(lp), None) {
                            let image = self.color_image(gl);
                            return self.stopped(gl, plan, stepper, image, volume_stats, start);
                        }
                    }
                }
                _ => {
                    self.timer.begin(gl, format!("light{}.lit", lp.light));
                    draw_maps(
                        &ctx,
                        lp,
                        &bindings(pi),
                        |sm, cube, six| lit_program(sm, cube, six, false),
                        false,
                    );
                    if stepper.record(StepKind::Lit, Some(lp), None) {
                        let image = self.color_image(gl);
                        return self.stopped(gl, plan, stepper, image, volume_stats, start);
                    }
                }
            }
        }
        set_scissor(gl, None);
        let passes = self.timer.finish(gl);
        // SAFETY: waits for the frame; no state change.
        unsafe { gl.finish() };
        let frame_ms = start.elapsed().as_secs_f64() * 1e3;
        if request.overlays.volumes || request.overlays.silhouettes {
            self.target.bind(gl);
            let shown = plan
                .lights
                .iter()
                .filter(|lp| request.overlays.light.is_none_or(|l| l == lp.light));
            for lp in shown {
                if let (Technique::ShadowVolume, Some(v)) =
                    (lp.technique, self.volumes.get(lp.light))
                {
                    passes::debug::volumes(
                        &ctx,
                        &self.programs.debug_volume,
                        v,
                        request.overlays.volumes,
                        request.overlays.silhouettes,
                    );
                }
            }
        }
        // SAFETY: error query only.
        let error = unsafe { gl.get_error() };
        if error != glow::NO_ERROR {
            return Err(RenderError::Gl(format!(
                "the frame raised GL error 0x{error:x}"
            )));
        }
        let rgba = self.target.read_rgba(gl);
        let (gbuffer, masks) = match (&self.measure_targets, request.masks) {
            (Some((gtarget, mtarget)), true) => {
                gtarget_bind(gl, gtarget);
                passes::gbuffer::draw(&ctx, &self.programs.gbuffer);
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
                    match (lp.technique, self.volumes.get(lp.light)) {
                        (Technique::ShadowVolume, Some(v)) => {
                            passes::stencil::draw(&ctx, &self.programs.volume, v, lp.scissor);
                            passes::lit::draw_mask(
                                &ctx,
                                lit_program(false, false, false, true),
                                lp,
                                &LitShadow::Stencil { test: true },
                                &lp.receivers,
                            );
                        }
                        _ => draw_maps(
                            &ctx,
                            lp,
                            &bindings(pi),
                            |sm, cube, six| lit_program(sm, cube, six, true),
                            true,
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
                (Some(gbuffer), masks)
            }
            _ => (None, Vec::new()),
        };
        Ok(Frame {
            width: self.target.width,
            height: self.target.height,
            rgba,
            view_proj: plan.camera.view_proj,
            passes,
            frame_ms,
            gbuffer,
            masks,
            volumes: volume_stats,
            steps: stepper.steps,
            step_image: None,
            stencil: stencil_image,
            plan_stats: plan.stats.clone(),
            cache,
        })
    }

    /// The frame's colour buffer as an image.
    fn color_image(&self, gl: &glow::Context) -> Rgba {
        Rgba {
            width: self.target.width,
            height: self.target.height,
            data: self.target.read_rgba(gl),
        }
    }

    /// The frame as it stands after a walkthrough step, with that step's buffer as an image.
    fn stopped(
        &mut self,
        gl: &glow::Context,
        plan: &Plan,
        stepper: Stepper,
        image: Rgba,
        volumes: Vec<VolumeStats>,
        start: Instant,
    ) -> Result<Frame, RenderError> {
        let passes = self.timer.finish(gl);
        // SAFETY: waits for the frame; no state change.
        unsafe { gl.finish() };
        Ok(Frame {
            width: self.target.width,
            height: self.target.height,
            rgba: self.target.read_rgba(gl),
            view_proj: plan.camera.view_proj,
            passes,
            frame_ms: start.elapsed().as_secs_f64() * 1e3,
            gbuffer: None,
            masks: Vec::new(),
            volumes,
            steps: stepper.steps,
            step_image: Some(image),
            stencil: None,
            plan_stats: plan.stats.clone(),
            cache: CacheStats::default(),
        })
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

/// One light's lit (or mask) passes: one per shadow map view, or one without shadows.
fn draw_maps<'p>(
    ctx: &PassContext,
    lp: &LightPlan,
    bindings: &[(bool, ShadowBinding, &[u32], Option<Scissor>)],
    program: impl Fn(bool, bool, bool) -> &'p Program,
    mask: bool,
) {
    let pass = |p: &Program, s: &LitShadow, receivers: &[u32]| {
        if mask {
            passes::lit::draw_mask(ctx, p, lp, s, receivers);
        } else {
            passes::lit::draw(ctx, p, lp, s, receivers);
        }
    };
    if bindings.is_empty() {
        pass(
            program(false, false, false),
            &LitShadow::None,
            &lp.receivers,
        );
    }
    if lp.merged && bindings.len() == 6 {
        let maps: Vec<&ShadowBinding> = bindings.iter().map(|(_, b, _, _)| b).collect();
        pass(
            program(true, false, true),
            &LitShadow::Faces(&maps),
            &lp.receivers,
        );
        return;
    }
    for (cube, b, receivers, rect) in bindings {
        set_scissor(ctx.gl, *rect);
        pass(program(true, *cube, false), &LitShadow::Map(b), receivers);
    }
    set_scissor(ctx.gl, lp.scissor);
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
        self.volumes.delete(gl);
        if let Some((g, m)) = self.measure_targets.take() {
            g.delete(gl);
            m.delete(gl);
        }
        if let Some(r) = self.depth_reducer.take() {
            r.delete(gl);
        }
        self.timer.delete(gl);
        // SAFETY: deleting our own VAO once.
        unsafe { gl.delete_vertex_array(self.empty_vao) };
    }
}
