//! How a [`Plan`] is built, step by step: the camera, what is visible, the frame's casters and
//! receivers, then each enabled light: culled, or given a technique and its shadow work.

mod maps;
mod volumes;

use super::auto::{self, AutoMemory};
use super::kept_frusta::KeptFrusta;
use super::scissor::{self, Scissor};
use super::{CameraSetup, LightPlan, Plan, PlanStats, cull};
use crate::geometry::{Aabb, Frustum};
use crate::options::{
    Candidate, MapBuffer, OmniMode, Options, Outside, ShadowMapOptions, StencilPasses, Technique,
    VolumeProjection,
};
use crate::scene::{Camera, Light, LightKind, Scene, SurfaceOwner};
use crate::shadow::volume::{self, CasterGroup, CasterGroups, PieceRef};
use glam::{Mat4, Vec3};

/// A hash of anything hashable.
fn hash_of(v: impl std::hash::Hash) -> u64 {
    use std::hash::Hasher;
    let mut h = std::collections::hash_map::DefaultHasher::new();
    v.hash(&mut h);
    h.finish()
}

fn mat_bits(m: &Mat4) -> [u32; 16] {
    m.to_cols_array().map(f32::to_bits)
}

/// One caster piece the planner may extrude: its group's index, the piece, its world bounds
/// and its group.
type PieceCandidate<'a> = (usize, PieceRef, Aabb, &'a CasterGroup);

/// What is known of the frame before any light is planned.
struct FrameFacts<'a> {
    scene: &'a Scene,
    options: &'a Options,
    memory: &'a AutoMemory,
    /// Frusta chosen in earlier frames (`plan.keep_frusta`).
    kept: &'a KeptFrusta,
    camera: CameraSetup,
    /// The scene's camera (warped maps fit to it).
    scene_camera: Camera,
    /// The camera frustum without a far plane: volumes reach infinity.
    view_frustum: Frustum,
    near: f32,
    /// Where depth-pass counts start (`plan.near_plane_test`).
    near_quad: [Vec3; 4],
    receivers_in_view: Vec<u32>,
    caster_list: Vec<u32>,
    /// Alpha-tested casters: `auto` and the counting choice treat them apart.
    alpha_caster_bounds: Vec<Aabb>,
    /// Casters' bounds, for fitting shadow-map views.
    caster_bounds: Vec<Aabb>,
    /// Shadow-volume pieces with their world bounds.
    pieces: Vec<PieceCandidate<'a>>,
    map_options: ShadowMapOptions,
    map_options_text: String,
}

impl Plan {
    /// The plan for `camera`, with the costs measured so far (for `technique = auto`) and the
    /// scene's caster groups (needed when [`Plan::needs_casters`]; without them no light
    /// gets volumes).
    pub fn build_with(
        scene: &Scene,
        camera: &Camera,
        options: &Options,
        (memory, kept): (&AutoMemory, &KeptFrusta),
        groups: Option<&CasterGroups>,
    ) -> Plan {
        let camera_setup = camera_for(scene, camera, options);
        let mut stats = PlanStats {
            profile: options.plan.profile.to_string(),
            surfaces: scene.surfaces.len(),
            ..PlanStats::default()
        };
        let visible = visibility(scene, &camera_setup, options, &mut stats);
        let casters: Vec<bool> = scene
            .surfaces
            .iter()
            .map(|s| {
                let m = &scene.materials[s.material];
                m.visible && m.casts_shadows
            })
            .collect();
        let facts = FrameFacts::new(
            scene,
            (camera, camera_setup),
            options,
            (memory, kept),
            (&visible, &casters),
            groups,
        );
        let (lights, culled, scissor_sum) = facts.plan_lights(&mut stats);
        stats.lights_planned = lights.len();
        stats.scissor_fraction = if lights.is_empty() {
            0.0
        } else {
            scissor_sum / lights.len() as f64
        };
        let p = &options.plan;
        let stencil = if p.enabled && p.one_pass_stencil {
            StencilPasses::Separate
        } else {
            options.shadow_volume.stencil
        };
        stats.stencil_passes = match stencil {
            StencilPasses::TwoPass => 2,
            StencilPasses::Separate => 1,
        };
        let mut plan = Plan {
            camera: camera_setup,
            visible,
            casters,
            lights,
            stencil,
            culled,
            maps_per_light: false,
            map_budget: None,
            lights_per_fence: options.gl.lights_per_fence,
            stats,
        };
        // The paper's frame draws every map each frame (no `plan.cache_maps`).
        let (per_light, bytes) =
            super::map_memory::maps_per_light(&plan, &options.shadow_map, !p.enabled);
        plan.maps_per_light = per_light;
        plan.map_budget = super::map_memory::held_bytes(&plan, &options.shadow_map);
        plan.stats.maps_per_light = per_light;
        plan.stats.map_bytes = bytes;
        plan
    }
}

/// The camera with the projection the frame's techniques need: the shadow-volume choice
/// (with a far plane past the whole scene for depth clamping) where some light may use
/// volumes, the paper's infinite far plane otherwise.
fn camera_for(scene: &Scene, camera: &Camera, options: &Options) -> CameraSetup {
    if !Plan::needs_casters(scene, options) {
        return CameraSetup::new(camera, options.width, options.height);
    }
    let far = scene
        .bounds()
        .corners()
        .iter()
        .map(|c| c.distance(camera.position))
        .fold(0.0f32, f32::max)
        * 1.01;
    CameraSetup::with_projection(
        camera,
        options.width,
        options.height,
        options.shadow_volume.projection,
        far,
    )
}

/// Per surface, whether camera passes draw it (the PVS and frustum tests of the paper's base
/// renderer for Quake 3 worlds; the frustum for models).
fn visibility(
    scene: &Scene,
    camera: &CameraSetup,
    options: &Options,
    stats: &mut PlanStats,
) -> Vec<bool> {
    let frustum = options
        .culling
        .frustum
        .then(|| Frustum::from_view_proj(&camera.view_proj));
    let mut visible = vec![false; scene.surfaces.len()];
    match &scene.world {
        Some(world) => {
            stats.vis = Some(world.mark_visible(
                camera.position,
                frustum.as_ref(),
                options.culling.pvs,
                &mut visible,
            ));
        }
        None => visible.iter_mut().for_each(|v| *v = true),
    }
    for (i, s) in scene.surfaces.iter().enumerate() {
        if let SurfaceOwner::Model(_) = s.owner {
            visible[i] = frustum
                .as_ref()
                .is_none_or(|f| f.intersects_aabb(&s.bounds));
        }
        visible[i] &= scene.materials[s.material].visible;
        if visible[i] {
            stats.surfaces_visible += 1;
            stats.triangles_visible += s.index_count as usize / 3;
        }
    }
    visible
}

/// Whether a spot's cone is wider than any one frustum `shadow_views` can give it (2 × cutoff,
/// capped at 179°): a cutoff near or past 90° leaves points of the cone outside the map, and
/// those behind the light's plane at q <= 0, which ARB_shadow reads as shadowed.
pub fn spot_exceeds_frustum(light: &Light) -> bool {
    match light.kind {
        LightKind::Spot { cutoff_deg, .. } => 2.0 * cutoff_deg > 179.0,
        LightKind::Omni => false,
    }
}

/// The shadow-map options the planner draws with: under `plan.omni_cube`, where six spots and
/// a cube cover the same directions (no narrowed field of view, no clip planes), an omni
/// light's maps are the faces of one cube map.
fn map_options_of(options: &Options) -> ShadowMapOptions {
    let sm = &options.shadow_map;
    let p = &options.plan;
    if p.enabled
        && p.omni_cube
        && sm.omni == OmniMode::SixSpots
        && sm.fov_scale == 1.0
        && sm.outside != Outside::ClipPlanes
    {
        ShadowMapOptions {
            omni: OmniMode::Cube,
            ..sm.clone()
        }
    } else {
        sm.clone()
    }
}

/// The near plane's rectangle in world space, grown by a tenth about its centre against
/// rounding in the rasteriser's clipping; under depth clamping nothing is near-clipped, so
/// counts start at the eye.
fn near_quad_of(camera: &CameraSetup, options: &Options) -> [Vec3; 4] {
    if options.shadow_volume.projection == VolumeProjection::DepthClamp {
        return [camera.position; 4];
    }
    let inv = camera.view_proj.inverse();
    [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .map(|(x, y)| inv.project_point3(Vec3::new(x * 1.1, y * 1.1, -1.0)))
}

impl<'a> FrameFacts<'a> {
    /// `(camera, setup)`: the scene camera and its setup; `(visible, casters)`: per surface
    /// drawn and casting.
    fn new(
        scene: &'a Scene,
        (camera, setup): (&Camera, CameraSetup),
        options: &'a Options,
        (memory, kept): (&'a AutoMemory, &'a KeptFrusta),
        (visible, casters): (&[bool], &[bool]),
        groups: Option<&'a CasterGroups>,
    ) -> FrameFacts<'a> {
        let n = scene.lights.len();
        let maps_possible = options.uses_where(n, |t| t.uses_maps() || t == Technique::Auto);
        let caster_list: Vec<u32> = (0..casters.len())
            .filter(|&i| casters[i])
            .map(|i| i as u32)
            .collect();
        let alpha_caster_bounds: Vec<Aabb> = caster_list
            .iter()
            .map(|&c| &scene.surfaces[c as usize])
            .filter(|s| scene.materials[s.material].alpha_test.is_some())
            .map(|s| s.bounds)
            .collect();
        let caster_bounds: Vec<Aabb> = if maps_possible {
            caster_list
                .iter()
                .map(|&i| scene.surfaces[i as usize].bounds)
                .collect()
        } else {
            Vec::new()
        };
        let receivers_in_view: Vec<u32> = (0..visible.len())
            .filter(|&i| visible[i] && scene.materials[scene.surfaces[i].material].receives_light)
            .map(|i| i as u32)
            .collect();
        // The planner culls pieces of at most CHUNK_TRIANGLES; the paper's frame, components.
        let chunked = options.plan.enabled && options.plan.cull_casters;
        let groups = groups.filter(|_| Plan::needs_casters(scene, options));
        let pieces: Vec<PieceCandidate> = groups
            .iter()
            .flat_map(|g| g.groups.iter().map(|g| &**g).enumerate())
            .flat_map(|(gi, g)| {
                let t = volume::group_transform(scene, g.owner);
                let pieces = if chunked { &g.chunks } else { &g.components };
                pieces.iter().enumerate().map(move |(ci, c)| {
                    let piece = if chunked {
                        PieceRef::Chunk(ci)
                    } else {
                        PieceRef::Component(ci)
                    };
                    (gi, piece, c.bounds.transformed(&t), g)
                })
            })
            .collect();
        let map_options = map_options_of(options);
        FrameFacts {
            scene,
            options,
            memory,
            kept,
            view_frustum: Frustum::from_view_proj(
                &CameraSetup::new(camera, options.width, options.height).view_proj,
            ),
            near: camera.near,
            near_quad: near_quad_of(&setup, options),
            camera: setup,
            scene_camera: *camera,
            receivers_in_view,
            caster_list,
            alpha_caster_bounds,
            caster_bounds,
            pieces,
            map_options_text: format!("{map_options:?}"),
            map_options,
        }
    }

    /// Whether the planner's decisions are on (`plan.enabled`).
    fn on(&self) -> bool {
        self.options.plan.enabled
    }

    /// Every enabled light planned or culled: the plans, the culled lights and the sum of the
    /// planned lights' scissor shares of the screen.
    fn plan_lights(&self, stats: &mut PlanStats) -> (Vec<LightPlan>, Vec<usize>, f64) {
        let n = self.scene.lights.len();
        let screen = (self.camera.width as f64 * self.camera.height as f64).max(1.0);
        let mut lights = Vec::new();
        let mut culled = Vec::new();
        let mut scissor_sum = 0.0;
        let enabled: Vec<usize> = (0..n).filter(|&i| self.options.light_enabled(i)).collect();
        stats.lights_enabled = enabled.len();
        for (order, &index) in enabled.iter().enumerate() {
            let Some(plan) = self.plan_light(index, order, stats) else {
                culled.push(index);
                continue;
            };
            scissor_sum += plan.scissor.map_or(1.0, |s| s.area() as f64 / screen);
            lights.push(plan);
        }
        (lights, culled, scissor_sum)
    }

    /// Light `index`'s work this frame, or None when it is culled.
    fn plan_light(&self, index: usize, order: usize, stats: &mut PlanStats) -> Option<LightPlan> {
        let (receivers, scissor) = self.cull_light(index, stats)?;
        let mask_receivers = self.in_range(index, &receivers);
        let (chosen, reason) = self.technique_of(index, stats);
        let mut plan = LightPlan {
            light: index,
            technique: chosen.technique,
            buffer: chosen.buffer,
            map_size: chosen.size,
            order,
            map_offset: crate::plan::settings::map_offset(&self.map_options, order),
            views: Vec::new(),
            volumes: Vec::new(),
            extruded: Vec::new(),
            receivers,
            mask_receivers,
            view_receivers: Vec::new(),
            view_casters: Vec::new(),
            view_keys: Vec::new(),
            view_images: Vec::new(),
            view_static_keys: Vec::new(),
            frusta: None,
            scissor,
            view_scissors: Vec::new(),
            merged: false,
            subdivided: None,
            volume_receivers: Vec::new(),
            near_plane_triangles: Vec::new(),
            reason,
        };
        let left_without = match chosen.technique {
            Technique::ShadowMap | Technique::Psm | Technique::Tsm => {
                self.plan_maps(&mut plan, stats)
            }
            Technique::ShadowVolume => self.plan_volumes(&mut plan, stats),
            // The hybrid needs both: its map classifies, its volumes decide at silhouettes.
            Technique::Hybrid => self
                .plan_maps(&mut plan, stats)
                .or_else(|| self.plan_volumes(&mut plan, stats)),
            // Its fragments are the renderer's, per light, built where the light's
            // geometry changed: the plan says which geometry, and the models' volumes.
            Technique::Subdivision => {
                self.plan_subdivision(&mut plan, stats);
                None
            }
            Technique::None | Technique::Auto => None,
        };
        if let Some(why) = left_without {
            plan.technique = Technique::None;
            plan.buffer = MapBuffer::Depth;
            plan.map_size = None;
            plan.reason = why.into();
        }
        if plan.technique == Technique::None && !plan.reason.is_empty() {
            stats.lights_without_casters += 1;
        }
        stats.receivers_drawn += match plan.technique {
            t if t.uses_maps() && !plan.merged => plan.view_receivers.iter().map(Vec::len).sum(),
            _ => plan.receivers.len(),
        };
        Some(plan)
    }

    /// Of `receivers`, sorted, those whose bounds meet light `index`'s sphere enlarged by a
    /// thousandth and one unit: rounding may put an interpolated fragment a hair outside its
    /// surface's box, never that far.
    fn in_range(&self, index: usize, receivers: &[u32]) -> Vec<u32> {
        let l = &self.scene.lights[index];
        let radius = l.radius * 1.001 + 1.0;
        let mut out: Vec<u32> = receivers
            .iter()
            .copied()
            .filter(|&s| {
                cull::sphere_meets_aabb(l.position, radius, &self.scene.surfaces[s as usize].bounds)
            })
            .collect();
        out.sort_unstable();
        out
    }

    /// Light culling: the view frustum, then the receivers in view, then the screen
    /// rectangle. The light's receivers in view and its rectangle, or None: culled.
    fn cull_light(
        &self,
        index: usize,
        stats: &mut PlanStats,
    ) -> Option<(Vec<u32>, Option<Scissor>)> {
        let scene = self.scene;
        let p = &self.options.plan;
        let on = self.on();
        let l = &scene.lights[index];
        let (pos, radius) = (l.position, l.radius);
        if on && p.cull_lights && !cull::sphere_meets_frustum(&self.view_frustum, pos, radius) {
            stats.lights_culled_frustum += 1;
            return None;
        }
        let reaches =
            |s: &u32| cull::sphere_meets_aabb(pos, radius, &scene.surfaces[*s as usize].bounds);
        let receivers: Vec<u32> = if on && p.cull_receivers {
            self.receivers_in_view
                .iter()
                .copied()
                .filter(reaches)
                .collect()
        } else {
            self.receivers_in_view.clone()
        };
        stats.receivers_culled += self.receivers_in_view.len() - receivers.len();
        // A light matters where its range meets a receiver in view. The PVS's visible leaves
        // bound nothing more: a surface is drawn whole where one of its leaves is visible, and
        // ctf_inyard shows parts of a ceiling over leaves outside the camera's PVS, lit by
        // lights whose range meets no visible leaf (172 pixels left unlit; docs/checks.md).
        let reaches_receiver = if on && p.cull_receivers {
            !receivers.is_empty()
        } else {
            receivers.iter().any(reaches)
        };
        if on && p.cull_lights && !reaches_receiver {
            stats.lights_culled_pvs += 1;
            return None;
        }
        if !(on && p.scissor) {
            return Some((receivers, None));
        }
        match scissor::sphere_scissor(&self.camera, pos, radius) {
            Some(s) => Some((receivers, Some(s))),
            None => {
                stats.lights_culled_frustum += 1;
                None
            }
        }
    }

    /// The technique (and map buffer) light `index` runs with: asked for, or chosen by `auto`
    /// (and why).
    fn technique_of(&self, index: usize, stats: &mut PlanStats) -> (Candidate, String) {
        match self.options.technique_for(index) {
            Technique::Auto => {
                let l = &self.scene.lights[index];
                let alpha_casters = self
                    .alpha_caster_bounds
                    .iter()
                    .any(|b| cull::sphere_meets_aabb(l.position, l.radius, b));
                let c = auto::choose(index, self.options, self.memory, alpha_casters);
                stats
                    .choices
                    .push(format!("light {index}: {} ({})", c.candidate, c.reason));
                (c.candidate, c.reason)
            }
            _ => (self.options.candidate_for(index), String::new()),
        }
    }
}
