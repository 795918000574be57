//! `plan.profile`: the machine the planner's decisions are weighed for. On a CPU rasteriser
//! (`software`) fill is dear and a read-back cheap, so the decisions that read the frame's depth
//! back to save fill pay; on a pipelined GPU (`gpu`) the same read-back stalls the whole
//! pipeline mid-frame, so no decision reads anything back and a frame never waits on the GL.
//!
//! | decision | software | gpu | why |
//! |---|---|---|---|
//! | `plan.occlusion` (depth read after the base pass) | on | off | the read-back stalls a GPU |
//! | `plan.depth_clip` (clip planes fitted to that depth) | on | off | needs the same read-back |
//! | `plan.depth_bounds_test` | on | on | the GL's own test reads no depth back |
//! | `plan.keep_volumes` (still lights' pieces built against their range, kept) | off | on | longer, unmerged volumes: more fill, less CPU (docs/motion.md) |
//! | `shadow_volume.gpu_extrusion = auto` | `none` | `moving` | a vertex shader on llvmpipe runs on the CPU too |
//! | `gl.lights_per_fence` (a fence and a wait every few lights) | as set | 0 | a CPU rasteriser's queue grows with the frame; a GPU driver bounds its own |
//!
//! Every other decision costs CPU work only and is the same under both.

use crate::options::{GpuExtrusion, Options, Profile};

/// The profile `auto` stands for on this GL: `software` where the renderer is a CPU rasteriser.
pub fn effective(profile: Profile, software_renderer: bool) -> Profile {
    match profile {
        Profile::Auto if software_renderer => Profile::Software,
        Profile::Auto => Profile::Gpu,
        p => p,
    }
}

/// The options with the decisions their profile turns off turned off, and `plan.profile` set to the
/// profile it stood for (never `auto`).
pub fn resolve(mut o: Options, software_renderer: bool) -> Options {
    o.plan.profile = effective(o.plan.profile, software_renderer);
    let gpu = o.plan.profile == Profile::Gpu;
    if gpu {
        o.plan.occlusion = false;
        o.plan.depth_clip = false;
        o.gl.lights_per_fence = 0;
    } else {
        o.plan.keep_volumes = false;
    }
    if o.shadow_volume.gpu_extrusion == GpuExtrusion::Auto {
        o.shadow_volume.gpu_extrusion = if gpu {
            GpuExtrusion::Moving
        } else {
            GpuExtrusion::None
        };
    }
    o
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_follows_the_renderer_and_gpu_turns_off_every_read_back() {
        let o = Options::default();
        let soft = resolve(o.clone(), true);
        assert_eq!(soft.plan.profile, Profile::Software);
        assert!(soft.plan.occlusion && soft.plan.depth_clip && !soft.plan.keep_volumes);
        assert_eq!(soft.shadow_volume.gpu_extrusion, GpuExtrusion::None);
        let gpu = resolve(o.clone(), false);
        assert_eq!(gpu.plan.profile, Profile::Gpu);
        assert!(!gpu.plan.occlusion && !gpu.plan.depth_clip && gpu.plan.depth_bounds_test);
        assert!(gpu.plan.keep_volumes);
        assert_eq!((soft.gl.lights_per_fence, gpu.gl.lights_per_fence), (8, 0));
        assert_eq!(gpu.shadow_volume.gpu_extrusion, GpuExtrusion::Moving);
        let mut forced = o.clone();
        forced.plan.profile = Profile::Gpu;
        assert!(!resolve(forced.clone(), true).plan.occlusion);
        forced.plan.profile = Profile::Software;
        assert!(resolve(forced, false).plan.depth_clip);
    }
}
