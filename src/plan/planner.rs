//! The planner: every per-frame decision, and the caches they are made from. The GL layer asks
//! it for a frame's [`Plan`], reads back the depth it asks for, and draws the volume draws it
//! prepares; it keeps nothing of its own that changes what is drawn.
//!
//! Caches are keyed by what they are made from: the caster groups by the scene's revision
//! (which every change to its surfaces bumps), the depth by what the base pass draws it from,
//! the volume draws by their inputs.

use super::Plan;
use super::auto::{AutoMemory, CostSource};
use super::kept_frusta::KeptFrusta;
use super::occlusion::DepthPyramid;
use super::pass::PassTime;
use super::volume_draws::{Ahead, LightVolumeDraws, PieceChoices, VolumeDrawError, VolumePlanner};
use super::{CameraSetup, LightPlan};
use crate::options::{Candidate, Options};
use crate::scene::{Camera, Scene};
use crate::shadow::volume::CasterGroups;
use crate::truth::sampled::LightSample;
use std::sync::Arc;

/// Everything the base pass's depth is drawn from, so that a frame with the same as the last
/// one has the same depth without reading it back (`plan.reuse_depth`): the camera (view,
/// projection, size), which surfaces are drawn, where the models stand and their poses, the
/// depth format and the form it is read in. Materials, textures and geometry are the loaded
/// scene's, which a new scene replaces together with the depth kept ([`Planner::forget`]).
#[derive(Debug, Clone, PartialEq)]
struct DepthInputs {
    camera: CameraSetup,
    visible: Vec<bool>,
    models: Vec<(glam::Mat4, u64)>,
    float_depth: bool,
    reduced: bool,
}

/// What the planner needs of the frame's depth after the base pass.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DepthNeed {
    /// Nothing: no light's volumes read it this frame.
    None,
    /// The last depth read holds: the base pass drew the same (`plan.reuse_depth`).
    Reuse,
    /// Read it back, reduced to 4×4 block maxima by a shader when `reduced`
    /// (`plan.reduce_depth`), and hand it to [`Planner::take_depth`].
    Read { reduced: bool },
}

/// The depth read for the planner, and which depth it is.
#[derive(Default)]
struct DepthMemory {
    last: Option<DepthPyramid>,
    /// What `last` was drawn from.
    inputs: Option<DepthInputs>,
    /// Advanced whenever the depth read differs from the last (see
    /// `PieceChoices::depth_generation`).
    generation: u64,
    /// This frame's inputs, until the depth is taken.
    pending: Option<DepthInputs>,
    /// Whether this frame's volumes may read `last`.
    usable: bool,
}

/// The planner's state across frames.
#[derive(Default)]
pub struct Planner {
    memory: AutoMemory,
    /// Frusta of static omni lights kept across frames (`plan.keep_frusta`).
    kept_frusta: KeptFrusta,
    /// Each planned light and the technique (and buffer) it ran with in the last frame.
    ran: Vec<(usize, Candidate)>,
    /// The scene's caster groups and the revision they were built from.
    casters: Option<(u64, Arc<CasterGroups>)>,
    volumes: VolumePlanner,
    depth: DepthMemory,
    /// Caster groups built since [`Planner::take_groups_rebuilt`].
    groups_rebuilt: usize,
}

impl Planner {
    /// Forgets everything learnt from the last scene (where costs come from is kept).
    pub fn forget(&mut self) {
        let source = self.memory.cost_source().clone();
        *self = Planner::default();
        self.memory.set_cost_source(source);
    }

    /// Drops the frusta kept across frames (`plan.keep_frusta`).
    pub fn forget_kept_frusta(&mut self) {
        self.kept_frusta = KeptFrusta::default();
    }

    /// What `technique = auto` has measured so far.
    pub fn memory(&self) -> &AutoMemory {
        &self.memory
    }

    /// Where `technique = auto` takes its costs from (measured unless a caller supplies them).
    pub fn set_cost_source(&mut self, source: CostSource) {
        self.memory.set_cost_source(source);
    }

    /// Notes what each light of a frame ran with, and learns from the frame's pass times
    /// where it was timed pass by pass (`passes`), for `technique = auto`. A frame timed whole
    /// (bench's) still says what ran: the errors sampled from it are that candidate's.
    pub fn record_frame(&mut self, plan: &Plan, passes: Option<&[PassTime]>) {
        self.ran = plan
            .lights
            .iter()
            .map(|l| {
                let candidate = Candidate {
                    technique: l.technique,
                    buffer: l.buffer,
                    size: l.map_size,
                };
                (l.light, candidate)
            })
            .collect();
        match passes {
            Some(passes) => self.memory.record(passes, &self.ran),
            None => self.memory.note_ran(&self.ran),
        }
    }

    /// Each planned light of the last frame and the candidate it ran with.
    pub fn ran(&self) -> &[(usize, Candidate)] {
        &self.ran
    }

    /// Dictates `auto`'s choices for the next frames ([`AutoMemory::follow`]).
    pub fn follow(&mut self, choices: &[(usize, Candidate)]) {
        self.memory.follow(choices);
    }

    /// Learns from the last frame's sampled errors, for `technique = auto`.
    pub fn record_errors(&mut self, samples: &[LightSample], options: &Options) {
        self.memory.record_errors(samples, &self.ran, options);
    }

    /// The scene's caster groups, built again only when its surfaces changed; a model whose
    /// pose changed (its vertices moved) has its own group built again, the rest are kept.
    pub fn casters(&mut self, scene: &Scene) -> Arc<CasterGroups> {
        match &self.casters {
            Some((revision, groups)) if *revision == scene.revision() => {
                if groups.posed_as(scene) {
                    return groups.clone();
                }
                let (groups, rebuilt) = groups.reposed(scene);
                self.groups_rebuilt += rebuilt;
                let groups = Arc::new(groups);
                self.casters = Some((scene.revision(), groups.clone()));
                groups
            }
            _ => {
                let groups = Arc::new(CasterGroups::build(scene));
                self.groups_rebuilt += groups.groups.len();
                self.casters = Some((scene.revision(), groups.clone()));
                groups
            }
        }
    }

    /// Caster groups built since the last call (the frame's stats).
    pub fn take_groups_rebuilt(&mut self) -> usize {
        std::mem::take(&mut self.groups_rebuilt)
    }

    /// The plan for `camera`, with the costs measured so far.
    pub fn plan(&mut self, scene: &Scene, camera: &Camera, options: &Options) -> Plan {
        self.memory.note_view(camera);
        let groups = Plan::needs_casters(scene, options).then(|| self.casters(scene));
        let plan = Plan::build_with(
            scene,
            camera,
            options,
            (&self.memory, &self.kept_frusta),
            groups.as_deref(),
        );
        self.kept_frusta.record(
            plan.lights
                .iter()
                .filter_map(|l| l.frusta.clone().map(|(key, f)| (l.light, key, f))),
        );
        plan
    }

    /// What this frame needs of the depth the base pass lays down; `float_depth` says the
    /// frame's depth buffer is 32F.
    pub fn depth_need(
        &mut self,
        scene: &Scene,
        plan: &Plan,
        options: &Options,
        float_depth: bool,
    ) -> DepthNeed {
        let any_volumes = plan.any_volumes();
        let reads_depth = options.plan.occlusion || options.plan.depth_clip;
        self.depth.usable = false;
        self.depth.pending = None;
        if !(any_volumes && options.plan.enabled && reads_depth) {
            return DepthNeed::None;
        }
        let inputs = DepthInputs {
            camera: plan.camera,
            visible: plan.visible.clone(),
            models: scene.models.iter().map(|m| (m.transform, m.pose)).collect(),
            float_depth,
            reduced: options.plan.reduce_depth,
        };
        // The base pass draws what the last depth read was drawn from: it is that depth.
        if options.plan.reuse_depth
            && self.depth.last.is_some()
            && self.depth.inputs.as_ref() == Some(&inputs)
        {
            self.depth.usable = true;
            self.volumes.begin_frame(options.plan.reuse_depth_fits);
            return DepthNeed::Reuse;
        }
        self.depth.pending = Some(inputs);
        DepthNeed::Read {
            reduced: options.plan.reduce_depth,
        }
    }

    /// The depth read back after [`DepthNeed::Read`] (None: it could not be read; the volumes
    /// are then drawn without it, and the last depth stays).
    pub fn take_depth(&mut self, depth: Option<DepthPyramid>, options: &Options) {
        let Some(depth) = depth else {
            return;
        };
        let same = self
            .depth
            .last
            .as_ref()
            .is_some_and(|last| depth.same_as(last));
        // The fits kept are those made for the last depth.
        self.volumes
            .begin_frame(same && options.plan.reuse_depth_fits);
        if !same {
            self.depth.generation += 1;
        }
        self.depth.last = Some(depth);
        self.depth.inputs = self.depth.pending.take();
        self.depth.usable = true;
    }

    /// The light's volume draws for this frame (after the depth, if asked for, was taken).
    pub fn volume_draws(
        &mut self,
        scene: &Scene,
        plan: &Plan,
        lp: &LightPlan,
        options: &Options,
    ) -> Result<&LightVolumeDraws, VolumeDrawError> {
        let groups = self.casters(scene);
        let p = &options.plan;
        let choices = PieceChoices {
            camera: &plan.camera,
            depth: self.depth.last.as_ref().filter(|_| self.depth.usable),
            occlusion: p.occlusion,
            depth_clip: if p.depth_clip {
                p.depth_clip_planes as usize
            } else {
                0
            },
            scissor: p.enabled && p.piece_scissor,
            merge: p.enabled && p.merge_pieces,
            depth_bounds: p.enabled && p.depth_bounds_test,
            cull_clipped: p.enabled && p.cull_clipped,
            reuse_fits: p.reuse_depth_fits,
            // The paper's frame keeps no planner's draws, but `shadow_volume.caching` builds
            // nothing while the light and its casters stand: its draws are kept whole while
            // nothing they are made from changed, else each frame's layout would build again
            // the parts whose CPU copies were given up (oa_dm3: all 15 424, 0.7 s a frame).
            reuse_draws: if p.enabled {
                p.reuse_volume_draws
            } else {
                options.shadow_volume.caching
            },
            keep: p.enabled && p.keep_volumes,
            depth_generation: self.depth.generation,
            truncate: p.enabled && p.truncate_volumes,
        };
        self.volumes
            .prepare(scene, &groups, lp, &options.shadow_volume, choices)
    }

    /// Volume parts and depth fits kept for later frames.
    pub fn held_volumes(&self) -> (usize, usize, u64) {
        self.volumes.held()
    }

    /// Builds ahead the kept volumes of every still light that runs shadow volumes
    /// (`plan.build_ahead` with `plan.keep_volumes`; `options` resolved for the GL as a
    /// frame's are), nearest to `camera` first, while the kept parts stay within
    /// `shadow_volume.kept_mb`. Each light's draws then hold the upload of its kept region
    /// ([`Planner::last_volume_draws`]; [`Planner::uploaded`] once made).
    pub fn prepare_ahead(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        options: &Options,
    ) -> Vec<Ahead> {
        let p = &options.plan;
        if !(p.enabled && p.keep_volumes && p.cull_casters && p.build_ahead) {
            return Vec::new();
        }
        let mut lights: Vec<usize> = (0..scene.lights.len())
            .filter(|&l| options.light_enabled(l) && options.technique_for(l).uses_volumes())
            .filter(|&l| !scene.motion.moves_light(l))
            .collect();
        if lights.is_empty() {
            return Vec::new();
        }
        let from = |l: &usize| scene.lights[*l].position.distance_squared(camera.position);
        lights.sort_by(|a, b| from(a).total_cmp(&from(b)));
        let groups = self.casters(scene);
        let vertex_bytes = std::mem::size_of::<[f32; 4]>() as f64;
        let budget = (f64::from(options.shadow_volume.kept_mb) * 1048576.0 / vertex_bytes) as usize;
        let truncate = p.truncate_volumes;
        let mut made = Vec::new();
        for light in lights {
            let made_ahead =
                self.volumes
                    .prepare_ahead(scene, &groups, light, &options.shadow_volume, truncate);
            let Ok(ahead) = made_ahead else {
                // A layout bug: the light is built when first seen, where the frame says so.
                self.volumes.forget_light(light);
                continue;
            };
            if self.volumes.kept_vertices() > budget {
                // Past the budget: this light is built when first seen, as without building ahead.
                self.volumes.forget_light(light);
                break;
            }
            made.push(ahead);
        }
        made
    }

    /// The upload the light's draws asked for ([`Planner::prepare_ahead`]'s or a frame's) was
    /// made: the vertices it named may be given up.
    pub fn uploaded(&mut self, light: usize) {
        self.volumes.uploaded(light);
    }

    /// Forgets the light's volume draws (their upload failed): the next frame makes them
    /// afresh.
    pub fn forget_volume_draws(&mut self, light: usize) {
        self.volumes.forget_light(light);
    }

    /// The light's volume draws as last prepared.
    pub fn last_volume_draws(&self, light: usize) -> Option<&LightVolumeDraws> {
        self.volumes.get(light)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::options::Technique;
    use crate::truth::sampled::{Interval, LightSample};

    /// A frame timed whole (bench's timed frames: no pass times) still says what each light
    /// ran, so that the errors sampled from it count for that candidate. Before, such a frame
    /// left the last timed frame's list: a light planned in none of those (q3dm6ish's light
    /// 10, out of view at the path's first frame) had its errors dropped, and kept the
    /// candidate its constants chose along the whole path.
    #[test]
    fn a_frame_timed_whole_still_says_what_ran() {
        let scene = crate::scene::builtin::default_scene();
        let options = Options {
            technique: Technique::ShadowVolume,
            ..Options::default()
        };
        let mut planner = Planner::default();
        let plan = planner.plan(&scene, &scene.camera, &options);
        let light = plan.lights.first().expect("a planned light").light;
        planner.record_frame(&plan, None);
        let sample = LightSample {
            light,
            receivers: 1000.0,
            samples: 512,
            effective: 512.0,
            exact: false,
            error: Interval::wilson(0.0, 512.0, false),
            alpha_holes: Interval::default(),
        };
        planner.record_errors(&[sample], &options);
        let volumes = Candidate::of(Technique::ShadowVolume, &options);
        assert!(planner.memory().error(light, volumes, &options).is_some());
        assert_eq!(planner.memory().last(light), Some(volumes));
        assert!(!planner.memory().warm(light, volumes), "no cost learnt");
    }
}
