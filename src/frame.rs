//! What rendering one frame produces: the image, and how long each pass took.

use crate::images::{GBuffer, Mask, Rgba, StencilImage};
use crate::plan::pass::{PassId, PassTime};
use glam::{Mat4, Vec3};
use serde::Serialize;
use std::path::Path;

/// What a step of a frame does (the walkthrough steps through them).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StepKind {
    /// Draw the casters' depth from a light (one view or cube face).
    LightView,
    /// Copy the depth buffer into the shadow map texture.
    DepthCopy,
    /// The unlit world: depth and baked light.
    Base,
    /// Count a light's shadow volumes into the stencil buffer.
    Stencil,
    /// Mark a light's shadowed fragments of the subdivision into the stencil buffer.
    Fragments,
    /// The hybrid's computation mask (and counts) in the stencil: where the map decides.
    ComputationMask,
    /// A light's additive pass.
    Lit,
    /// The fill quad that darkens where the stencil is set.
    Fill,
}

/// One executed step of a frame.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Step {
    pub kind: StepKind,
    pub light: Option<usize>,
    /// The shadow-map view (spot, six-spot face) or cube face, for light views and copies.
    pub face: Option<usize>,
    /// The technique the light's step runs under (resolved: never `auto`).
    pub technique: Option<crate::options::Technique>,
}

/// Where the CPU waited for the GPU while making a frame: each one drains a GPU's pipeline
/// (on a CPU rasteriser the work runs there anyway, so they cost little). Counted from the
/// frame's call to its return, including what the caller asked for (pixels, masks, stepping).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct Syncs {
    /// Pixels or texels read into memory (`glReadPixels`, `glGetTexImage`).
    pub read_backs: u32,
    /// `glFinish`.
    pub finishes: u32,
    /// Query results read (`GL_QUERY_RESULT`: timer and sample queries).
    pub query_reads: u32,
    /// Fences waited on (`glClientWaitSync`).
    pub fence_waits: u32,
    /// `glGetError`: most drivers finish the commands queued before they can answer.
    pub error_checks: u32,
}

impl Syncs {
    pub fn total(&self) -> u32 {
        self.read_backs + self.finishes + self.query_reads + self.fence_waits + self.error_checks
    }

    /// The counts in words, e.g. "3 (1 read-back, 1 finish, 1 error check)".
    pub fn describe(&self) -> String {
        let kinds = [
            (self.read_backs, "read-back"),
            (self.finishes, "finish"),
            (self.query_reads, "query read"),
            (self.fence_waits, "fence wait"),
            (self.error_checks, "error check"),
        ];
        let named: Vec<String> = kinds
            .iter()
            .filter(|(n, _)| *n > 0)
            .map(|(n, what)| match (n, *what) {
                (1, w) => format!("1 {w}"),
                (n, "finish") => format!("{n} finishes"),
                (n, w) => format!("{n} {w}s"),
            })
            .collect();
        match named.is_empty() {
            true => "0".into(),
            false => format!("{} ({})", self.total(), named.join(", ")),
        }
    }

    /// What was counted after `before` was taken.
    pub fn since(&self, before: &Syncs) -> Syncs {
        Syncs {
            read_backs: self.read_backs.wrapping_sub(before.read_backs),
            finishes: self.finishes.wrapping_sub(before.finishes),
            query_reads: self.query_reads.wrapping_sub(before.query_reads),
            fence_waits: self.fence_waits.wrapping_sub(before.fence_waits),
            error_checks: self.error_checks.wrapping_sub(before.error_checks),
        }
    }
}

/// What the frame reused from earlier frames.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, serde::Deserialize)]
pub struct CacheStats {
    /// Shadow maps (views: a spot, a face of six spots, a cube) whose content was made this
    /// frame in any way: drawn whole, or from their static map (the two counts below).
    pub maps_rendered: usize,
    pub maps_reused: usize,
    /// Static maps (a view's casters that do not move) drawn, each then copied into its map
    /// with the moving models drawn over the copy (`LightPlan::view_static_keys`).
    pub maps_static_drawn: usize,
    /// Maps made from their kept static map: copied, and only the moving models drawn.
    pub maps_models_only: usize,
    /// The planner's depth taken from the last frame, not read back: the base pass drew the
    /// same thing (`plan.reuse_depth`).
    pub depth_reused: bool,
    pub volume_parts_built: usize,
    pub volume_parts_reused: usize,
    /// Shadow-volume caster groups (the world's, each model's) built for this frame: all of
    /// them for a new scene, then only those of models whose vertices moved (animation).
    pub caster_groups_built: usize,
    /// Models whose vertices were uploaded again before the frame (animation).
    pub models_uploaded: usize,
    /// Caster groups whose GPU extrusion meshes were built and uploaded for this frame (their
    /// first use, or their model's new pose).
    pub extrusions_uploaded: usize,
    /// Subdivided lights whose fragments were built or read from the disk cache and uploaded
    /// for this frame (their first frame, or a change of the light or its geometry), and
    /// the shadowed fragment triangles they drew.
    pub subdivisions_renewed: usize,
    pub fragment_triangles: usize,
    /// Surface draw calls of the timed frame's passes (maps, base, lit): surfaces of one
    /// state whose indices follow on are drawn as one (`gl::upload::Merge`).
    pub surface_draws: usize,
}

#[derive(Debug, Clone)]
pub struct Frame {
    /// The frame's colour buffer, top row first; empty (0×0) where the request left the image
    /// on the GPU (`FrameRequest::image_on_gpu`).
    pub image: Rgba,
    /// The frame's size in pixels (the image's, whether or not it was read back).
    pub width: u32,
    pub height: u32,
    /// World to clip space of the camera that rendered the frame.
    pub view_proj: Mat4,
    pub passes: Vec<PassTime>,
    /// How many frames back the GPU passes' times were taken (0: this frame's;
    /// `FrameRequest::pass_times_later`).
    pub passes_frames_ago: usize,
    /// Wall time from the call (planning, uploads, submission) to the frame's end: its
    /// completion where the frame waited for the GL anyway (`completed`: the caller asked for
    /// pixels), else its submission; a caller that needs completion without pixels waits on
    /// a fence (`Renderer::fence`), as `bench` does for its latency.
    pub frame_ms: f64,
    /// Whether `frame_ms` includes the GL's completion of the frame.
    pub completed: bool,
    /// Our own CPU work in the frame, outside GL calls: resolving the options, planning and
    /// the volume draws' pieces and builds. On llvmpipe `frame_ms` also holds the driver's
    /// vertex work on the calling thread; this does not.
    pub own_ms: f64,
    /// What the camera sees per pixel (when masks were requested).
    pub gbuffer: Option<GBuffer>,
    /// Each planned light's decision per pixel (when masks were requested).
    pub masks: Vec<Mask>,
    /// Shadow-volume work per light (shadow volumes only).
    pub volumes: Vec<crate::plan::volume_draws::VolumeStats>,
    /// The steps executed, in order (all of them unless the request stopped early).
    pub steps: Vec<Step>,
    /// The buffer the last step wrote, as an image, when the request stopped after a step.
    pub step_image: Option<Rgba>,
    /// A light's stencil counts, when the request asked for them.
    pub stencil: Option<StencilImage>,
    /// What the plan decided (visible surfaces, triangles, BSP culling, lights and casters
    /// culled, scissor, counting, auto choices).
    pub plan_stats: crate::plan::PlanStats,
    /// Shadow maps and volume parts drawn afresh or reused.
    pub cache: CacheStats,
    /// Options replaced because the GL lacks (or `gl.disable` hides) a feature they need.
    pub fallbacks: Vec<crate::plan::fallback::Fallback>,
    /// Per hybrid light, what its classification found and what its mask saved (with masks).
    pub hybrid: Vec<HybridStats>,
    /// Of `masks`, those read from what the lights' lit passes recorded (`gl::record`); the
    /// others were drawn again.
    pub masks_recorded: usize,
    /// Where making the frame waited for the GPU.
    pub syncs: Syncs,
}

/// One hybrid light's classification and computation mask, measured after the frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct HybridStats {
    pub light: usize,
    /// Receiver pixels the light reaches.
    pub receiver_pixels: u64,
    /// Of those, the pixels where the map's compares disagree: the volumes decide there.
    pub silhouette_pixels: u64,
    /// Volume fragments that pass the computation mask (GL_SAMPLES_PASSED, depth test off),
    /// and all of them, as plain shadow volumes rasterise them; None where the GL has no
    /// such query.
    pub volume_fragments: Option<u64>,
    pub volume_fragments_unmasked: Option<u64>,
}

impl HybridStats {
    /// Share of the light's receiver pixels classified as silhouette pixels.
    pub fn silhouette_share(&self) -> f64 {
        self.silhouette_pixels as f64 / self.receiver_pixels.max(1) as f64
    }

    /// Volume fragments past the mask as a share of all of them.
    pub fn fragment_share(&self) -> Option<f64> {
        Some(self.volume_fragments? as f64 / self.volume_fragments_unmasked?.max(1) as f64)
    }
}

impl Frame {
    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    pub fn pixel(&self, x: u32, y: u32) -> [u8; 4] {
        self.image.pixel(x, y)
    }

    /// Rec. 709 luma of a pixel, 0..=255.
    pub fn luma(&self, x: u32, y: u32) -> f32 {
        let p = self.pixel(x, y);
        0.2126 * p[0] as f32 + 0.7152 * p[1] as f32 + 0.0722 * p[2] as f32
    }

    /// The pixel (column, row from the top) a world point lands on, if it is in front of the
    /// camera and on screen.
    pub fn project(&self, world: Vec3) -> Option<(u32, u32)> {
        let c = self.view_proj * world.extend(1.0);
        if c.w <= 0.0 {
            return None;
        }
        let ndc = c.truncate() / c.w;
        let x = (ndc.x * 0.5 + 0.5) * self.width() as f32;
        let y = (0.5 - ndc.y * 0.5) * self.height() as f32;
        if x < 0.0 || y < 0.0 || x >= self.width() as f32 || y >= self.height() as f32 {
            return None;
        }
        Some((x as u32, y as u32))
    }

    pub fn save_png(&self, path: &Path) -> Result<(), image::ImageError> {
        self.image.save(path)
    }

    /// Milliseconds of the pass, if it ran.
    pub fn pass_ms(&self, pass: PassId) -> Option<f64> {
        self.passes.iter().find(|p| p.pass == pass).map(|p| p.ms)
    }
}
