//! Benchmarks: frame time and accuracy of each configuration of a sweep, in one run.
//!
//! Each configuration renders `warmup` frames, then `frames` measured frames along the camera path
//! (cycled), round-robin with the other configurations (`BenchSettings::interleave`) or one after
//! another. Its frame time is reported absolutely and as a ratio to the same options with shadows
//! off (technique = none), measured in the same run. Its error is measured on the path's first
//! frame against the exact reference (computed once per view and light and reused by every
//! configuration), and on every frame of the path against the sampled reference
//! (`truth::sampled`, `estimate.samples` pixels per light), in an untimed pass after the timing.

use crate::frame::{CacheStats, Frame, Syncs};
use crate::options::{OptionError, Options, Technique};
use crate::plan::PlanStats;
use crate::plan::fallback::Fallback;
use crate::plan::volume_draws::VolumeStats;
use crate::presets::{Difference, Preset};
use crate::report::store::RowStore;
use crate::run::{FrameRequest, Prepared, RenderError, Renderer};
use crate::scene::Scene;
use crate::scene::path::PathKey;
use crate::truth::{Counts, Reference};
use indicatif::ProgressBar;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, HashMap};
use std::time::Instant;

mod error;
mod follow;
mod interleave;
mod kept;
mod sampled;
mod stats;

pub use error::{Capture, View};
use error::{Errored, FrameError};
pub use kept::Kept;
pub use sampled::{LightOnPath, SampledFrame, SampledPath};

pub use stats::{Median, MsStats};
use stats::{frame_ratios, median, stats};

/// Frames timed pass by pass for each configuration's breakdown (after its measured frames).
pub const PASS_FRAMES: usize = 3;

/// `enough_seconds` where `tune` and `reproduce` set it: a frame of 1.5 s or more is measured
/// once, one of 0.5 s or less three times.
pub const ENOUGH_SECONDS: f64 = 1.5;

/// How frames are taken.
#[derive(Debug, Clone)]
pub struct BenchSettings {
    pub warmup: usize,
    pub frames: usize,
    /// Camera poses, cycled through by the measured frames.
    pub path: Vec<PathKey>,
    pub progress: bool,
    /// Time the configurations and their baselines round-robin, each on its own renderer (one
    /// frame of each in turn), so that a slow drift of the machine's speed falls on all of them
    /// alike and the ratios hold; else one configuration after another on one renderer.
    pub interleave: bool,
    /// Time `PASS_FRAMES` more frames pass by pass for each configuration's breakdown
    /// (`pass_ms`); `tune`'s cheap rungs go without.
    pub breakdown: bool,
    /// Also time the path drawn back to back with frames in flight (`pipelined_ms`);
    /// `tune`'s rungs, which rank by latency and error alone, go without (0 in their rows).
    pub pipelined: bool,
    /// Play the scene's motion (players, moving lights): frame `i` of the path is posed at
    /// `i / path::FRAME_RATE_HZ` seconds. Off, the scene stands as loaded (its pose at 0).
    pub motion: bool,
    /// Sample every n-th measured frame against the sampled reference (1: every frame).
    pub sample_every: usize,
    /// With `interleave`: the MiB the round-robin renderers may hold together (maps, volumes
    /// and fragments, as an earlier bench of the same options measured them, else the first
    /// frame's planned maps); the configurations are then timed a group at a time (each with
    /// its baseline), the renderers of one group dropped before the next is made. None: all
    /// at once.
    pub memory_mb: Option<f32>,
    /// On a still path (one pose, nothing moving): a configuration's measured frames stop
    /// once they add up to this many seconds (one frame at least), and its pipelined and
    /// per-pass frames are as many. A frame that takes seconds is its own long sample (the
    /// scheduling noise the median of several guards against is milliseconds); frames of
    /// tens of milliseconds are all taken. None: always `frames`.
    pub enough_seconds: Option<f64>,
}

impl BenchSettings {
    /// Whether every measured frame is the same frame: one camera pose, and the scene standing
    /// (motion off, or nothing in it moves).
    fn is_still(&self, scene: &Scene) -> bool {
        self.path.len() == 1 && !self.scene_moves(scene)
    }

    /// Whether the measured frames pose `scene` at their own times and something in it moves.
    fn scene_moves(&self, scene: &Scene) -> bool {
        self.motion && !scene.motion.is_still()
    }

    /// Whether `taken` frames adding up to `ms` are enough of a configuration's measured
    /// frames (`frames`, or fewer on a still path past `enough_seconds`).
    fn enough(&self, scene: &Scene, taken: usize, ms: f64) -> bool {
        taken >= self.frames.max(1)
            || (taken > 0
                && self.is_still(scene)
                && self.enough_seconds.is_some_and(|s| ms >= s * 1e3))
    }

    /// Poses `scene` for frame `i` of the path, at `i / FRAME_RATE_HZ` seconds; without
    /// `motion` it stays as loaded.
    fn pose(&self, scene: &mut Scene, i: usize) {
        if self.motion {
            scene.pose_at(i as f64 / crate::scene::path::FRAME_RATE_HZ);
        }
    }

    fn camera(&self, scene: &Scene, i: usize) -> crate::scene::Camera {
        self.path[i % self.path.len()].apply(&scene.camera)
    }
}

/// One point of a sweep.
#[derive(Debug, Clone)]
pub struct BenchConfig {
    /// A name for the configuration; the swept values when absent.
    pub name: Option<String>,
    /// The swept keys and their values, e.g. `shadow_map.size=512`.
    pub swept: BTreeMap<String, String>,
    pub options: Options,
}

impl BenchConfig {
    /// A configuration known by name rather than by swept values.
    pub fn named(name: &str, options: Options) -> BenchConfig {
        BenchConfig {
            name: Some(name.to_string()),
            swept: BTreeMap::new(),
            options,
        }
    }

    pub fn label(&self) -> String {
        if let Some(n) = &self.name {
            return n.clone();
        }
        if self.swept.is_empty() {
            return format!("technique={}", self.options.technique);
        }
        self.swept
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect::<Vec<_>>()
            .join(" ")
    }
}

/// Every combination of the swept values over `base` (the first sweep varies slowest).
pub fn sweep_configs(
    base: &Options,
    sweeps: &[(String, Vec<String>)],
) -> Result<Vec<BenchConfig>, OptionError> {
    let mut configs = vec![BenchConfig {
        name: None,
        swept: BTreeMap::new(),
        options: base.clone(),
    }];
    for (key, values) in sweeps {
        let mut next = Vec::with_capacity(configs.len() * values.len());
        for c in &configs {
            for v in values {
                let mut o = c.options.clone();
                o.set(key, v)?;
                let mut swept = c.swept.clone();
                swept.insert(key.clone(), o.get(key)?);
                next.push(BenchConfig {
                    name: None,
                    swept,
                    options: o,
                });
            }
        }
        configs = next;
    }
    Ok(configs)
}

/// Error against the exact reference, as fractions of receiver pixels.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct ErrorRow {
    pub receiver_pixels: usize,
    pub false_shadow: f64,
    pub false_lit: f64,
    pub total: f64,
    pub total_excl_boundary: f64,
    pub receiver_mismatch: usize,
}

impl From<&Counts> for ErrorRow {
    fn from(c: &Counts) -> Self {
        let r = c.rates();
        ErrorRow {
            receiver_pixels: r.receiver_pixels,
            false_shadow: r.false_shadow,
            false_lit: r.false_lit,
            total: r.total,
            total_excl_boundary: r.total_excl_boundary,
            receiver_mismatch: c.receiver_mismatch,
        }
    }
}

/// One configuration's results (a row of the JSON array).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct BenchRow {
    pub scene: String,
    pub technique: String,
    pub label: String,
    pub swept: BTreeMap<String, String>,
    pub options: Options,
    /// The preset the options equal (`paper`, `default`), if any.
    pub preset: Option<Preset>,
    /// The options that differ from the paper's frame (`--preset paper`), with the paper's
    /// values.
    pub differs_from_paper: Vec<Difference>,
    pub width: u32,
    pub height: u32,
    pub lights: usize,
    pub frames: usize,
    /// Latency: from the call (planning, uploads, submission) to the GL's completion of the
    /// frame, which bench waits for on a fence outside the frame.
    pub frame_ms: MsStats,
    /// Median from the call to its return: the CPU's part of the frame.
    pub submit_ms: Median,
    /// The same per-frame times as `submit_ms` (the call's wall time: resolving the options,
    /// planning, building, uploads and submission, and the frame's own waits for the GPU
    /// where `syncs_per_frame` counts any), with their spread and tail.
    pub cpu_ms: MsStats,
    /// Our own CPU work per frame outside GL calls (options, planning, volume pieces and
    /// builds, GPU extrusion meshes: `Frame::own_ms`), with its spread and tail: what bounds
    /// the frame rate on a GPU however fast it draws.
    pub own_ms: MsStats,
    /// What was readied before the first frame, untimed (`plan.build_ahead`: lights whose
    /// kept volumes were built ahead, with their parts, vertices and milliseconds).
    pub prepared: Prepared,
    /// Bytes the configuration's renderer held after its frames (`Held::bytes`: shadow maps,
    /// volume buffers and their CPU copies, subdivision fragments).
    #[serde(default)]
    pub held_bytes: u64,
    /// Round-robin: the group of renderers it was timed in (`memory_mb`), from 0; None one
    /// after another.
    #[serde(default)]
    pub round_robin_group: Option<usize>,
    /// Milliseconds per frame with up to two frames in flight (throughput): the path drawn
    /// again back to back, bench waiting only for the frame before the one just sent (0 where
    /// `BenchSettings::pipelined` is off, or where one frame was measured: nothing is in
    /// flight beside a single frame).
    pub pipelined_ms: f64,
    pub shadows_off_frame_ms: Median,
    /// The median frame over the shadows-off median frame.
    pub ratio_to_shadows_off: f64,
    /// Frame by frame: each measured frame's latency over the shadows-off frame at the same
    /// path frame ([`frame_ratios`]), the median and 99th percentile (nearest rank) of those
    /// ratios (exactly 1 for a configuration without shadows, its own baseline).
    pub ratio_median: f64,
    pub ratio_p99: f64,
    /// Median milliseconds of each pass over the measured frames; `lights.<stage>` sums a stage
    /// over all lights of a frame.
    pub pass_ms: BTreeMap<String, f64>,
    /// `gpu` (timer queries) or `cpu` (wall time around glFinish).
    pub clock: String,
    pub error: ErrorRow,
    pub error_per_light: Vec<(usize, ErrorRow)>,
    /// Shadow-volume work per light (quads, caps, build time), from the error frame.
    pub volumes: Vec<VolumeStats>,
    /// What the planner decided for the error frame (lights and casters culled, scissor,
    /// counting, `auto`'s choices).
    pub plan: PlanStats,
    /// What the error frame reused from what was made before it (one after another: the
    /// configuration's first frame, after `Renderer::prepare`; round-robin: drawn after the
    /// timing, on the bench's own renderer).
    pub cache: CacheStats,
    /// What the measured frames redid and reused, per frame on average.
    pub redone: Redone,
    /// Where the timed frames waited for the GPU, per frame on average: the frame's own waits,
    /// from its call to its return (bench's fence wait for the latency comes after).
    pub syncs_per_frame: SyncsPerFrame,
    /// Options the GL could not run (or `gl.disable` hid), and what replaced them.
    pub fallbacks: Vec<Fallback>,
    /// The sampled reference on every measured frame of the path (None with shadows off or
    /// `estimate.samples = 0`).
    pub sampled: Option<SampledPath>,
    /// What the lights ran with in the timed frames, in light-frames (a light planned in a
    /// frame is one) by candidate (`shadow_volume`, `shadow_map@1024`, ...): under `auto`,
    /// how often it chose each.
    #[serde(default)]
    pub ran: BTreeMap<String, usize>,
}

/// Sums per-light passes into `lights.<stage>` entries, next to the passes themselves.
pub fn pass_totals(frame: &Frame) -> BTreeMap<String, f64> {
    let mut out = BTreeMap::new();
    for p in &frame.passes {
        *out.entry(p.pass.to_string()).or_insert(0.0) += p.ms;
        if p.pass.light.is_some() {
            *out.entry(p.pass.summed_name()).or_insert(0.0) += p.ms;
        }
    }
    out
}

#[derive(Clone)]
struct Measured {
    /// Latency: from the call to the frame's completion.
    frame_ms: Vec<f64>,
    /// From the call to its return (planning, uploads, submission).
    submit_ms: Vec<f64>,
    /// Our own CPU work outside GL calls.
    own_ms: Vec<f64>,
    /// Milliseconds per frame with up to two frames in flight (0 where not measured).
    pipelined_ms: f64,
    /// What each timed frame redid and reused, summed.
    redone: Redone,
    syncs: SyncsPerFrame,
    passes: BTreeMap<String, Vec<f64>>,
    clock: &'static str,
    /// What was readied before the warm-up frames (`Renderer::prepare`).
    prepared: Prepared,
    /// What the renderer held after the frames (`Held::bytes`).
    held_bytes: u64,
    /// The round-robin group it was timed in.
    group: Option<usize>,
    /// Light-frames by what the light ran with ([`follow::light_frames`]).
    ran: BTreeMap<String, usize>,
}

/// Where the timed frames waited for the GPU ([`Syncs`]), per frame on average.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct SyncsPerFrame {
    /// Every kind below together.
    pub total: f64,
    pub read_backs: f64,
    pub finishes: f64,
    pub query_reads: f64,
    pub fence_waits: f64,
    pub error_checks: f64,
}

impl SyncsPerFrame {
    /// The mean of `frames` frames' counts.
    fn mean(frames: &[Syncs]) -> SyncsPerFrame {
        let n = frames.len().max(1) as f64;
        let sum = |f: fn(&Syncs) -> u32| frames.iter().map(|s| f64::from(f(s))).sum::<f64>() / n;
        SyncsPerFrame {
            total: sum(Syncs::total),
            read_backs: sum(|s| s.read_backs),
            finishes: sum(|s| s.finishes),
            query_reads: sum(|s| s.query_reads),
            fence_waits: sum(|s| s.fence_waits),
            error_checks: sum(|s| s.error_checks),
        }
    }
}

/// What the measured frames redid and what they took from earlier frames, per frame on
/// average: along a moving path, what motion costs the caches (a still scene redoes nothing
/// after its first frame).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Redone {
    pub frames: usize,
    /// Shadow maps drawn (a light, its view or a caster in it moved) and reused.
    pub maps_rendered: f64,
    pub maps_reused: f64,
    /// Of those drawn: kept static maps drawn again, and maps made from a kept static map
    /// with only the moving models drawn over it.
    pub maps_static_drawn: f64,
    pub maps_models_only: f64,
    /// Volume parts built (the light, a caster, the counting or the receivers their shadow
    /// reaches changed) and reused.
    pub volume_parts_built: f64,
    pub volume_parts_reused: f64,
    /// Caster groups built again (a model's vertices moved: animation).
    pub caster_groups_built: f64,
    /// Models whose vertices went up again (animation).
    pub models_uploaded: f64,
    /// GPU extrusion meshes built and uploaded (`shadow_volume.gpu_extrusion`).
    pub extrusions_uploaded: f64,
    /// Share of frames that took the planner's depth from the frame before.
    pub depth_reused: f64,
    /// Lights subdivided again or read from the disk cache (`technique = subdivision`: the
    /// light or the triangles it cuts moved).
    pub subdivisions_renewed: f64,
    /// Surface draw calls (maps, base, lit passes).
    pub surface_draws: f64,
}

impl Redone {
    fn add(&mut self, c: &CacheStats) {
        self.frames += 1;
        self.maps_rendered += c.maps_rendered as f64;
        self.maps_reused += c.maps_reused as f64;
        self.maps_static_drawn += c.maps_static_drawn as f64;
        self.maps_models_only += c.maps_models_only as f64;
        self.volume_parts_built += c.volume_parts_built as f64;
        self.volume_parts_reused += c.volume_parts_reused as f64;
        self.caster_groups_built += c.caster_groups_built as f64;
        self.models_uploaded += c.models_uploaded as f64;
        self.extrusions_uploaded += c.extrusions_uploaded as f64;
        self.depth_reused += f64::from(u8::from(c.depth_reused));
        self.subdivisions_renewed += c.subdivisions_renewed as f64;
        self.surface_draws += c.surface_draws as f64;
    }

    /// Sums as per-frame means.
    fn per_frame(mut self) -> Redone {
        let n = self.frames.max(1) as f64;
        for v in [
            &mut self.maps_rendered,
            &mut self.maps_reused,
            &mut self.maps_static_drawn,
            &mut self.maps_models_only,
            &mut self.volume_parts_built,
            &mut self.volume_parts_reused,
            &mut self.caster_groups_built,
            &mut self.models_uploaded,
            &mut self.extrusions_uploaded,
            &mut self.depth_reused,
            &mut self.subdivisions_renewed,
            &mut self.surface_draws,
        ] {
            *v /= n;
        }
        self
    }
}

/// The key under which a set of options is timed once.
fn options_key(options: &Options) -> String {
    serde_json::to_string(options).unwrap_or_default()
}

/// One timed frame: its time, what it reused and where it waited.
struct Timed {
    /// From the call to the frame's completion.
    ms: f64,
    /// From the call to its return.
    submit_ms: f64,
    own_ms: f64,
    cache: CacheStats,
    syncs: Syncs,
    /// What each planned light ran with.
    ran: Vec<(usize, crate::options::Candidate)>,
}

/// What a timed frame asks for: no per-pass timing (it would serialise llvmpipe's pipeline,
/// or read queries at the frame's end) and no pixels, so the frame itself waits for nothing.
const TIMED: FrameRequest = FrameRequest {
    masks: false,
    masks_drawn_again: false,
    gbuffer_kept: false,
    stop_after: None,
    stencil_of: None,
    overlays: crate::gl::Overlays {
        volumes: false,
        silhouettes: false,
        texel_grid: false,
        light: None,
    },
    frame_only: true,
    image_on_gpu: true,
    pass_times_later: false,
};

/// One frame's latency: from the call to the GL's completion, which bench waits for on a fence
/// after the frame returned (the frame's own waits, `syncs`, are counted inside the call only).
fn time_frame(
    renderer: &mut Renderer,
    scene: &Scene,
    camera: &crate::scene::Camera,
    options: &Options,
) -> Result<Timed, RenderError> {
    let start = Instant::now();
    let f = renderer.render_at(scene, camera, options, TIMED)?;
    renderer.fence()?.wait(renderer.gl());
    Ok(Timed {
        ms: start.elapsed().as_secs_f64() * 1e3,
        submit_ms: f.frame_ms,
        own_ms: f.own_ms,
        cache: f.cache,
        syncs: f.syncs,
        ran: renderer.ran().to_vec(),
    })
}

/// Milliseconds per frame over the path's frames drawn back to back with up to two in flight:
/// after each frame is sent, bench waits only for the one before it. Throughput, where the
/// latency of `time_frame` serialises the CPU's planning with the GL's drawing.
fn pipelined_ms(
    (renderer, choices): (&mut Renderer, Option<&follow::Choices>),
    scene: &mut Scene,
    settings: &BenchSettings,
    options: &Options,
    frames: usize,
) -> Result<f64, RenderError> {
    let frames = frames.max(1);
    let start = Instant::now();
    let mut in_flight: Option<crate::gl::syncs::Fence> = None;
    for i in 0..frames {
        let camera = settings.frame(scene, (renderer, choices), i);
        renderer.render_at(scene, &camera, options, TIMED)?;
        let fence = renderer.fence()?;
        if let Some(before) = in_flight.replace(fence) {
            before.wait(renderer.gl());
        }
    }
    if let Some(last) = in_flight {
        last.wait(renderer.gl());
    }
    // The timed frames checked no GL error (a check waits): one check covers them all.
    renderer.check_errors()?;
    Ok(start.elapsed().as_secs_f64() * 1e3 / frames as f64)
}

/// `frame_ms` with a few frames timed pass by pass for the breakdown; with `choices`, `auto`
/// runs what a sampled run of the path chose ([`follow`]).
fn pass_breakdown(
    (renderer, choices): (&mut Renderer, Option<&follow::Choices>),
    scene: &mut Scene,
    settings: &BenchSettings,
    options: &Options,
    timed: &[Timed],
) -> Result<Measured, RenderError> {
    let mut redone = Redone::default();
    for t in timed {
        redone.add(&t.cache);
    }
    let syncs: Vec<Syncs> = timed.iter().map(|t| t.syncs).collect();
    let mut m = Measured {
        frame_ms: timed.iter().map(|t| t.ms).collect(),
        submit_ms: timed.iter().map(|t| t.submit_ms).collect(),
        own_ms: timed.iter().map(|t| t.own_ms).collect(),
        pipelined_ms: if settings.pipelined && timed.len() > 1 {
            pipelined_ms((renderer, choices), scene, settings, options, timed.len())?
        } else {
            0.0
        },
        redone: redone.per_frame(),
        syncs: SyncsPerFrame::mean(&syncs),
        passes: BTreeMap::new(),
        clock: "cpu",
        prepared: Prepared::default(),
        held_bytes: 0,
        group: None,
        ran: follow::light_frames(timed.iter().flat_map(|t| &t.ran)),
    };
    let frames = if settings.breakdown {
        timed.len().clamp(1, PASS_FRAMES)
    } else {
        0
    };
    for i in 0..frames {
        let camera = settings.frame(scene, (renderer, choices), i);
        let f = renderer.render_at(scene, &camera, options, FrameRequest::default())?;
        for (name, ms) in pass_totals(&f) {
            m.passes.entry(name).or_default().push(ms);
        }
        if f.passes
            .iter()
            .any(|p| p.clock == crate::plan::pass::Clock::Gpu)
        {
            m.clock = "gpu";
        }
    }
    Ok(m)
}

/// Runs a sweep on one loaded scene.
pub struct Bench<'a> {
    renderer: &'a mut Renderer,
    /// The scene, posed at the frame being drawn (a copy: posing writes into it).
    scene: Scene,
    settings: BenchSettings,
    /// Exact masks and errors of the path's first view.
    view: View,
    /// Shadows-off frame times by path frame, measured once per distinct options.
    baselines: HashMap<String, Vec<f64>>,
    /// The reference of a moving scene's current pose, by its models' poses and transforms.
    posed_reference: Option<(ModelsKey, Reference)>,
    /// Rows measured before, by content: a configuration found here is not measured again.
    store: RowStore,
    /// The scene's content as the store's keys name it (empty for a store of this bench only).
    fingerprint: String,
    /// Bytes a renderer held after each configuration's frames (`Held::bytes`), by its
    /// options (their sampling budget aside): what groups round-robin renderers.
    held: HashMap<String, u64>,
    /// Error frames drawn (those the view held are not).
    error_frames: usize,
    /// `auto`'s choices on each sampled path drawn ahead of the timing, by options: what
    /// the timed frames of those options run ([`follow`]).
    choices: HashMap<String, follow::Choices>,
}

/// Where every model stands (its transform's bits) and in which pose.
type ModelsKey = Vec<(u64, [u32; 16])>;

/// Where every model stands and in which pose: what a reference of the casters depends on
/// besides the loaded geometry.
fn models_key(scene: &Scene) -> ModelsKey {
    scene
        .models
        .iter()
        .map(|m| (m.pose, m.transform.to_cols_array().map(f32::to_bits)))
        .collect()
}

impl<'a> Bench<'a> {
    pub fn new(renderer: &'a mut Renderer, scene: &Scene, settings: BenchSettings) -> Bench<'a> {
        Bench {
            renderer,
            scene: scene.clone(),
            settings,
            view: View::default(),
            baselines: HashMap::new(),
            posed_reference: None,
            store: RowStore::in_memory(),
            fingerprint: String::new(),
            held: HashMap::new(),
            error_frames: 0,
            choices: HashMap::new(),
        }
    }

    /// The renderer the bench measures on (for other measurements of the same scene).
    pub fn renderer(&mut self) -> &mut Renderer {
        self.renderer
    }

    /// The scene as the bench last posed it.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Error frames this bench drew: one per configuration whose error (with its sample, where
    /// sampled) no earlier bench of the view took.
    pub fn error_frames(&self) -> usize {
        self.error_frames
    }

    /// One configuration's frames on this bench's renderer. With `error` (whether to sample
    /// its masks), its error frame is drawn first, when no earlier bench of the view drew it,
    /// and stands for one warm-up frame: it is the path's first frame, drawn with masks, on
    /// the renderer made ready as the warm-up's would be (one cold frame fewer per
    /// configuration; the paper's frame on oa_dm3 takes 3-40 s).
    fn measure(
        &mut self,
        options: &Options,
        error: Option<bool>,
    ) -> Result<(Measured, Option<Errored>), RenderError> {
        self.settings.pose(&mut self.scene, 0);
        let prepared = self.renderer.prepare(&self.scene, options)?;
        let drew_error = error.is_some_and(|sample| !self.error_is_known(options, sample));
        let warmup = match drew_error {
            true => self.settings.warmup.saturating_sub(1),
            false => self.settings.warmup,
        };
        let errored = match error {
            Some(sample) => Some(self.error(options, sample)?),
            None => None,
        };
        let key = options_key(options);
        // An error frame drawn now taught `auto` on this renderer first; one taken from the
        // view did not. Frames that follow a sampled run's choices need no teaching.
        if !drew_error && !self.choices.contains_key(&key) {
            self.learn_auto(options)?;
        }
        let choices = self.choices.get(&key);
        let (scene, settings) = (&mut self.scene, &self.settings);
        let renderer = &mut *self.renderer;
        for _ in 0..warmup {
            // Sampling the path posed the scene at later frames.
            let camera = settings.frame(scene, (renderer, choices), 0);
            renderer.render_at(scene, &camera, options, FrameRequest::default())?;
        }
        let mut timed: Vec<Timed> = Vec::new();
        let mut ms = 0.0;
        for i in 0.. {
            if settings.enough(scene, i, ms) {
                break;
            }
            let camera = settings.frame(scene, (renderer, choices), i);
            let t = time_frame(renderer, scene, &camera, options)?;
            ms += t.ms;
            timed.push(t);
        }
        let mut m = pass_breakdown((renderer, choices), scene, settings, options, &timed)?;
        renderer.follow(&[]);
        m.prepared = prepared;
        m.held_bytes = self.renderer.held().bytes();
        self.held.insert(error::error_key(options), m.held_bytes);
        // The next configuration starts from the scene alone, not beside this one's maps
        // and volumes (a sweep's memory is then its largest configuration's, not their sum).
        self.renderer.release_kept();
        Ok((m, errored))
    }

    /// `options` with shadows off. The techniques' own groups are reset too: they do nothing
    /// without shadows, so a sweep over them shares one baseline.
    fn shadows_off(options: &Options) -> Options {
        let defaults = Options::default();
        Options {
            technique: Technique::None,
            shadow_map: defaults.shadow_map,
            shadow_volume: defaults.shadow_volume,
            ..options.clone()
        }
    }

    fn baseline_key(options: &Options) -> String {
        options_key(&Self::shadows_off(options))
    }

    /// Frame times of `options` with shadows off, by path frame, measured once per distinct
    /// options.
    fn baseline(&mut self, options: &Options) -> Result<Vec<f64>, RenderError> {
        let key = Self::baseline_key(options);
        if let Some(ms) = self.baselines.get(&key) {
            return Ok(ms.clone());
        }
        let off = Self::shadows_off(options);
        let ms = self.measure(&off, None)?.0.frame_ms;
        self.baselines.insert(key, ms.clone());
        Ok(ms)
    }

    /// A configuration's timed frames, and its shadows-off frames' times by path frame: from
    /// the round-robin timing, or measured now (then with its error, `sample` saying whether
    /// its masks are sampled: [`Bench::measure`]). A configuration without shadows is its own
    /// baseline.
    fn timed(
        &mut self,
        c: &BenchConfig,
        interleaved: &HashMap<String, Measured>,
        sample: bool,
    ) -> Result<(Vec<f64>, Measured, Option<Errored>), RenderError> {
        let own = c.options.technique == Technique::None;
        if self.settings.interleave {
            let m = interleaved[&options_key(&c.options)].clone();
            let off = if own {
                m.frame_ms.clone()
            } else {
                interleaved[&Self::baseline_key(&c.options)]
                    .frame_ms
                    .clone()
            };
            Ok((off, m, None))
        } else if own {
            let (m, errored) = self.measure(&c.options, Some(sample))?;
            let key = Self::baseline_key(&c.options);
            self.baselines.insert(key, m.frame_ms.clone());
            Ok((m.frame_ms.clone(), m, errored))
        } else {
            let off = self.baseline(&c.options)?;
            let (m, errored) = self.measure(&c.options, Some(sample))?;
            Ok((off, m, errored))
        }
    }

    /// Measures every configuration, with a progress bar when the settings ask for one.
    pub fn run(&mut self, configs: &[BenchConfig]) -> Result<Vec<BenchRow>, RenderError> {
        let bar = if self.settings.progress {
            crate::report::progress::bar(configs.len(), "configurations")
        } else {
            ProgressBar::hidden()
        };
        let rows = self.run_with(configs, &bar)?;
        bar.finish_and_clear();
        Ok(rows)
    }

    /// Measures every configuration the store does not hold, advancing the caller's bar by one
    /// per configuration; the rows come back in the configurations' order.
    pub fn run_with(
        &mut self,
        configs: &[BenchConfig],
        bar: &ProgressBar,
    ) -> Result<Vec<BenchRow>, RenderError> {
        let keys: Vec<String> = configs.iter().map(|c| self.row_key(c)).collect();
        let mut kept: Vec<Option<BenchRow>> = keys.iter().map(|k| self.store.get(k)).collect();
        let (todo, todo_keys): (Vec<BenchConfig>, Vec<String>) = configs
            .iter()
            .zip(&keys)
            .zip(&kept)
            .filter(|(_, row)| row.is_none())
            .map(|((c, k), _)| (c.clone(), k.clone()))
            .unzip();
        bar.inc((configs.len() - todo.len()) as u64);
        let mut measured = self.measure_rows(&todo, &todo_keys, bar)?.into_iter();
        let mut rows = Vec::with_capacity(configs.len());
        for (c, row) in configs.iter().zip(&mut kept) {
            let row = match row.take() {
                // Kept under another name (the same options in another section or sweep).
                Some(row) => BenchRow {
                    label: c.label(),
                    swept: c.swept.clone(),
                    ..row
                },
                None => measured.next().expect("a row per configuration measured"),
            };
            rows.push(row);
        }
        Ok(rows)
    }

    /// Measures every configuration given, advancing the bar by one per configuration and
    /// filing each row in the store under its key as soon as it is measured (a run stopped
    /// halfway keeps what it finished).
    fn measure_rows(
        &mut self,
        configs: &[BenchConfig],
        keys: &[String],
        bar: &ProgressBar,
    ) -> Result<Vec<BenchRow>, RenderError> {
        let mut rows = Vec::with_capacity(configs.len());
        let mut sampled_ahead = self.sample_ahead(configs, bar)?;
        let interleaved = if self.settings.interleave {
            self.measure_interleaved(configs, bar)?
        } else {
            HashMap::new()
        };
        for (c, key) in configs.iter().zip(keys) {
            bar.set_message(c.label());
            let sample = c.options.technique != Technique::None && c.options.estimate.samples > 0;
            // On a still path every measured frame is the error frame again: its masks,
            // sampled once, stand for all of them.
            let still = sample && self.path_is_still();
            let (off, m, errored) = self.timed(c, &interleaved, still)?;
            let off_ms = median(&mut off.clone());
            let ratios = stats(&frame_ratios(&m.frame_ms, &off));
            let cpu_ms = stats(&m.submit_ms);
            let (
                FrameError {
                    total,
                    per_light,
                    volumes,
                    plan,
                    cache,
                    fallbacks,
                },
                first_sample,
            ) = match errored {
                Some(errored) => errored,
                None => self.error(&c.options, still)?,
            };
            let frame_ms = stats(&m.frame_ms);
            let sampled = if sample {
                let along_path = first_sample.is_none();
                let ahead = sampled_ahead.remove(&options_key(&c.options));
                let (frames, choices) = match (first_sample, ahead) {
                    (Some(first), _) => (vec![first], Vec::new()),
                    (None, Some(ahead)) => ahead,
                    (None, None) => {
                        bar.set_message(format!("{}: sampled reference along the path", c.label()));
                        self.sample_path(&c.options)?
                    }
                };
                let mut path = SampledPath::new(
                    c.options.estimate.samples,
                    frames,
                    (frame_ms.median, along_path),
                );
                path.count_choices(&choices);
                Some(path)
            } else {
                None
            };
            if self.settings.interleave {
                // The error and sampled frames were drawn here, the timed ones on renderers of
                // their own: the next configuration's error frame starts from the scene alone.
                // A frame without maps keeps the last one's (`ShadowMaps::release_unlike`):
                // six planned configurations of oa_dm3 drew the subdivision's error frame
                // beside a PSM's 512 MiB of maps (peak 1.16 GB; 0.93 GB released).
                self.renderer.release_kept();
            }
            rows.push(BenchRow {
                scene: self.scene.name.clone(),
                technique: c.options.technique.to_string(),
                label: c.label(),
                swept: c.swept.clone(),
                options: c.options.clone(),
                preset: Preset::matching(&c.options),
                differs_from_paper: Preset::Paper.differences(&c.options),
                width: c.options.width,
                height: c.options.height,
                lights: per_light.len(),
                frames: m.frame_ms.len(),
                frame_ms,
                submit_ms: Median {
                    median: cpu_ms.median,
                },
                cpu_ms,
                own_ms: stats(&m.own_ms),
                prepared: m.prepared,
                held_bytes: m.held_bytes,
                round_robin_group: m.group,
                pipelined_ms: m.pipelined_ms,
                shadows_off_frame_ms: Median { median: off_ms },
                ratio_to_shadows_off: if off_ms > 0.0 {
                    frame_ms.median / off_ms
                } else {
                    0.0
                },
                ratio_median: ratios.median,
                ratio_p99: ratios.p99,
                pass_ms: m
                    .passes
                    .into_iter()
                    .map(|(k, mut v)| (k, median(&mut v)))
                    .collect(),
                clock: m.clock.to_string(),
                error: ErrorRow::from(&total),
                error_per_light: per_light
                    .iter()
                    .map(|(l, c)| (*l, ErrorRow::from(c)))
                    .collect(),
                volumes,
                plan,
                cache,
                redone: m.redone,
                syncs_per_frame: m.syncs,
                fallbacks,
                sampled,
                ran: m.ran,
            });
            self.store
                .put(key, rows.last().expect("the row just measured"));
            bar.inc(1);
        }
        Ok(rows)
    }
}

/// A row with a technique, a label, a frame time and an error, everything else empty (unit
/// tests of what reads rows).
#[cfg(test)]
pub(crate) fn test_row(technique: &str, label: &str, ms: f64, error: f64) -> BenchRow {
    BenchRow {
        scene: "s".into(),
        technique: technique.into(),
        label: label.into(),
        swept: BTreeMap::new(),
        options: Options::default(),
        preset: None,
        differs_from_paper: Vec::new(),
        fallbacks: Vec::new(),
        width: 1,
        height: 1,
        lights: 1,
        frames: 1,
        frame_ms: MsStats {
            median: ms,
            min: ms,
            max: ms,
            p95: ms,
            p99: ms,
        },
        submit_ms: Median { median: ms },
        cpu_ms: MsStats::default(),
        own_ms: MsStats::default(),
        prepared: Prepared::default(),
        held_bytes: 0,
        round_robin_group: None,
        pipelined_ms: ms,
        shadows_off_frame_ms: Median { median: 1.0 },
        ratio_to_shadows_off: ms,
        ratio_median: ms,
        ratio_p99: ms,
        pass_ms: BTreeMap::new(),
        clock: "cpu".into(),
        error: ErrorRow {
            total: error,
            ..ErrorRow::default()
        },
        error_per_light: Vec::new(),
        sampled: None,
        ran: BTreeMap::new(),
        volumes: Vec::new(),
        plan: Default::default(),
        cache: Default::default(),
        redone: Redone::default(),
        syncs_per_frame: SyncsPerFrame::default(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sweeps_are_a_cartesian_product_in_order() {
        let configs = sweep_configs(
            &Options::default(),
            &[
                ("width".into(), vec!["320".into(), "640".into()]),
                (
                    "lighting.ambient".into(),
                    vec!["0.1".into(), "0.3".into(), "0.5".into()],
                ),
            ],
        )
        .unwrap();
        assert_eq!(configs.len(), 6);
        assert_eq!(configs[0].options.width, 320);
        assert_eq!(configs[2].options.lighting.ambient, 0.5);
        assert_eq!(configs[3].options.width, 640);
        assert_eq!(configs[4].label(), "lighting.ambient=0.3 width=640");
        assert!(sweep_configs(&Options::default(), &[("nope".into(), vec!["1".into()])]).is_err());
    }

    #[test]
    fn medians_and_stats() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 2.0, 3.0]), 2.5);
        assert_eq!(median(&mut []), 0.0);
        let s = stats(&[5.0, 1.0, 3.0]);
        assert_eq!((s.median, s.min, s.max), (3.0, 1.0, 5.0));
        // 100 frames of 1..=100 ms: the 95th is 95, the 99th 99; one frame is its own tail.
        let hundred: Vec<f64> = (1..=100).rev().map(f64::from).collect();
        let h = stats(&hundred);
        assert_eq!((h.p95, h.p99, h.max), (95.0, 99.0, 100.0));
        assert_eq!(stats(&[7.0]).p99, 7.0);
    }

    /// Ratios are taken path frame by path frame, not median over median: frames of 40, 3, 9,
    /// 16 and 100 ms over shadows-off frames of 40, 1.5, 3, 4 and 1 ms are 1, 2, 3, 4 and 100
    /// times theirs, whose median is 3 and 99th percentile (nearest rank: the 5th of 5) 100,
    /// where the medians' ratio is 16 / 3 and the 99th percentiles' 100 / 40.
    #[test]
    fn ratios_to_shadows_off_are_taken_frame_by_frame() {
        let ratios = frame_ratios(&[40.0, 3.0, 9.0, 16.0, 100.0], &[40.0, 1.5, 3.0, 4.0, 1.0]);
        assert_eq!(ratios, [1.0, 2.0, 3.0, 4.0, 100.0]);
        let s = stats(&ratios);
        assert_eq!((s.median, s.p99), (3.0, 100.0));
        // Shuffled together (the same pairs), the same ratios.
        let shuffled = frame_ratios(&[16.0, 100.0, 40.0, 9.0, 3.0], &[4.0, 1.0, 40.0, 3.0, 1.5]);
        assert_eq!(stats(&shuffled), s);
        // A configuration over itself (shadows off is its own baseline): exactly 1 each.
        let own = [13.7, 0.3, 41.0];
        assert!(frame_ratios(&own, &own).iter().all(|r| *r == 1.0));
        // No positive baseline: 0, not infinity.
        assert_eq!(frame_ratios(&[2.0], &[0.0]), [0.0]);
    }
}
