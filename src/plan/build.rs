//! How a [`Plan`] is built, step by step: the camera, what is visible, the frame's casters and
//! receivers, then each enabled light: culled, or given a technique and its shadow work.

use super::auto::{self, AutoMemory};
use super::kept_frusta::KeptFrusta;
use super::scissor::{self, Scissor};
use super::{CameraSetup, LightPlan, PartTriangles, Plan, PlanStats, VolumePart, cull};
use crate::geometry::{Aabb, Frustum};
use crate::options::{
    Candidate, CountingMode, GpuExtrusion, MapBuffer, ModelShadows, OmniMode, Options, Outside,
    Pipeline, ShadowMapOptions, ShadowVolumeOptions, StencilPasses, Technique, VolumeCasters,
    VolumeProjection, Warp,
};
use crate::scene::{Camera, Light, LightKind, Scene, SurfaceOwner};
use crate::shadow::frusta;
use crate::shadow::views::{Rect, ShadowView, ViewKind, shadow_views};
use crate::shadow::volume::{self, CasterGroup, CasterGroups, Counting, PieceRef};
use crate::shadow::warp::{self, WarpInput};
use crate::truth::subdivision::Geometry;
use glam::{Mat4, Vec3};

/// How far (in the face's image plane) a receiver may reach past a kept frustum's rectangle:
/// within the one-texel margin of any map of up to 2048 texels (`plan.keep_frusta`).
const KEEP_SLACK: f32 = 1.0 / 2048.0;
/// The smallest map one of several frusta gets (`shadow_map.omni = frusta`).
const MIN_FRUSTUM_SIZE: u32 = 32;
/// The largest, unless `shadow_map.size` is larger: at most four times its side (GL 3.3
/// guarantees 1024; the GL layer refuses a map past GL_MAX_TEXTURE_SIZE).
const MAX_FRUSTUM_SIZE: u32 = 4096;

/// The stats' line for a light's frusta: how many, their texels against the six faces' budget,
/// and each one's face and map side.
fn frusta_line(
    light: usize,
    views: &[crate::shadow::views::ShadowView],
    o: &ShadowMapOptions,
    kept: bool,
) -> String {
    let texels: u64 = views
        .iter()
        .map(|v| u64::from(v.map_size(o.size)).pow(2))
        .sum();
    let each: Vec<String> = views
        .iter()
        .map(|v| match v.kind {
            ViewKind::Face(f) => format!("{f}:{}", v.map_size(o.size)),
            _ => format!("{}", v.map_size(o.size)),
        })
        .collect();
    format!(
        "light {light}: {} frusta{}, {texels} texels (six faces: {}): {}",
        views.len(),
        if kept { " (kept)" } else { "" },
        6 * u64::from(o.size).pow(2),
        each.join(" ")
    )
}

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
    /// BSP leaves in view (Quake 3 worlds).
    leaves: Vec<Aabb>,
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
            surfaces: scene.surfaces.len(),
            ..PlanStats::default()
        };
        let (visible, leaves) = visibility(scene, &camera_setup, options, &mut stats);
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
            (&visible, &casters, leaves),
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
        Plan {
            camera: camera_setup,
            visible,
            casters,
            lights,
            stencil,
            culled,
            stats,
        }
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
/// renderer for Quake 3 worlds; the frustum for models), and the BSP leaves in view.
fn visibility(
    scene: &Scene,
    camera: &CameraSetup,
    options: &Options,
    stats: &mut PlanStats,
) -> (Vec<bool>, Vec<Aabb>) {
    let frustum = options
        .culling
        .frustum
        .then(|| Frustum::from_view_proj(&camera.view_proj));
    let mut visible = vec![false; scene.surfaces.len()];
    let mut leaves: Vec<Aabb> = Vec::new();
    match &scene.world {
        Some(world) => {
            stats.vis = Some(world.mark_visible(
                camera.position,
                frustum.as_ref(),
                options.culling.pvs,
                &mut visible,
                &mut leaves,
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
    (visible, leaves)
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
    /// `(camera, setup)`: the scene camera and its setup; `(visible, casters, leaves)`: per
    /// surface drawn and casting, and the BSP leaves in view.
    fn new(
        scene: &'a Scene,
        (camera, setup): (&Camera, CameraSetup),
        options: &'a Options,
        (memory, kept): (&'a AutoMemory, &'a KeptFrusta),
        (visible, casters, leaves): (&[bool], &[bool], Vec<Aabb>),
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
            .flat_map(|g| g.groups.iter().enumerate())
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
            leaves,
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
        let (chosen, reason) = self.technique_of(index, stats);
        let mut plan = LightPlan {
            light: index,
            technique: chosen.technique,
            buffer: chosen.buffer,
            order,
            views: Vec::new(),
            volumes: Vec::new(),
            extruded: Vec::new(),
            receivers,
            view_receivers: Vec::new(),
            view_casters: Vec::new(),
            view_keys: Vec::new(),
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

    /// Light culling: the view frustum, then the visible leaves and receivers, then the
    /// screen rectangle. The light's receivers in view and its rectangle, or None: culled.
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
        let receivers: Vec<u32> = if on && p.cull_receivers {
            self.receivers_in_view
                .iter()
                .copied()
                .filter(|&s| {
                    cull::sphere_meets_aabb(pos, radius, &scene.surfaces[s as usize].bounds)
                })
                .collect()
        } else {
            self.receivers_in_view.clone()
        };
        stats.receivers_culled += self.receivers_in_view.len() - receivers.len();
        let reaches_leaf = scene.world.is_none()
            || self
                .leaves
                .iter()
                .any(|b| cull::sphere_meets_aabb(pos, radius, b))
            || receivers
                .iter()
                .any(|&s| matches!(scene.surfaces[s as usize].owner, SurfaceOwner::Model(_)));
        let reaches_receiver = !p.cull_receivers || !receivers.is_empty();
        if on && p.cull_lights && !(reaches_leaf && reaches_receiver) {
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
            t => (Candidate::of(t, self.options), String::new()),
        }
    }
}

impl FrameFacts<'_> {
    /// A shadow-mapped light's views, with per view the casters drawn, the receivers lit, the
    /// key its map is kept by and its rectangle. Some(why) when no view has a caster.
    fn plan_maps(&self, plan: &mut LightPlan, stats: &mut PlanStats) -> Option<&'static str> {
        let l = &self.scene.lights[plan.light];
        let p = &self.options.plan;
        let on = self.on();
        // A spot wider than one frustum covers gets an omni light's views; the lit pass's cone
        // test still bounds its light (`plan.wide_spot_omni`).
        let as_omni;
        let view_light = if on && p.wide_spot_omni && spot_exceeds_frustum(l) {
            as_omni = Light {
                kind: LightKind::Omni,
                ..l.clone()
            };
            &as_omni
        } else {
            l
        };
        // Warped maps are 2D: six spots, never a cube.
        let (six_spots, chosen_buffer);
        let map_options = if plan.technique.warp().is_some() {
            six_spots = ShadowMapOptions {
                omni: OmniMode::SixSpots,
                ..self.options.shadow_map.clone()
            };
            &six_spots
        } else if plan.buffer != self.map_options.buffer {
            // `auto` chose this light's buffer (`shadow_map:id` in `auto_among`).
            chosen_buffer = ShadowMapOptions {
                buffer: plan.buffer,
                ..self.map_options.clone()
            };
            &chosen_buffer
        } else {
            &self.map_options
        };
        plan.views = match map_options.omni {
            OmniMode::Frusta if view_light.kind == LightKind::Omni => {
                let chosen = self.frusta_of(plan.light, view_light, &plan.receivers, map_options);
                let views = chosen.as_ref().map(|(_, frusta, kept)| {
                    let views = frusta::frustum_views(
                        view_light,
                        frusta,
                        &self.caster_bounds,
                        map_options.fit_near_far,
                    );
                    stats
                        .frusta
                        .push(frusta_line(plan.light, &views, map_options, *kept));
                    views
                });
                plan.frusta = chosen.map(|(key, frusta, _)| (key, frusta));
                views
            }
            _ => None,
        }
        .unwrap_or_else(|| shadow_views(view_light, &self.caster_bounds, map_options));
        let light_key = hash_of((
            &self.map_options_text,
            plan.buffer,
            plan.order,
            mat_bits(&Mat4::from_translation(l.position)),
            l.radius.to_bits(),
            format!("{:?}", l.kind),
        ));
        // Several frusta: each receiver's footprint on a face, once for all that face's frusta.
        let mut footprints: [Option<Vec<Option<Rect>>>; 6] = Default::default();
        for vi in 0..plan.views.len() {
            let view = &plan.views[vi];
            let mut drawn = self.map_casters(l, view.kind, &view.view_proj());
            let lit = self.view_receivers(l, view, &plan.receivers, &mut footprints);
            if let Some(kind) = plan.technique.warp() {
                self.warp_view(plan, vi, kind, (&lit, &mut drawn), stats);
            }
            let view = &plan.views[vi];
            stats.casters_drawn += drawn.len();
            stats.casters_culled += self.caster_list.len() - drawn.len();
            let key = (on && p.cache_maps).then(|| self.map_key(light_key, view, &drawn));
            let rect = self.face_rect(l, view, plan.scissor);
            plan.view_receivers.push(lit);
            plan.view_casters.push(drawn);
            plan.view_keys.push(key);
            plan.view_scissors.push(rect);
        }
        plan.merged = self.merges_faces(&plan.views);
        if on && p.cull_lights && plan.view_casters.iter().all(|c| c.is_empty()) {
            plan.views.clear();
            plan.view_receivers.clear();
            plan.view_casters.clear();
            plan.view_keys.clear();
            plan.view_scissors.clear();
            return Some("no caster in range");
        }
        None
    }

    /// The receivers view `view` of light `l` lights: one of several frusta only those in its
    /// cell (`footprints`: each receiver's footprint on a face, found once for all that face's
    /// frusta), a face of six spots those in its pyramid (`plan.cull_receivers`), other views
    /// all of `receivers`.
    fn view_receivers(
        &self,
        l: &Light,
        view: &ShadowView,
        receivers: &[u32],
        footprints: &mut [Option<Vec<Option<Rect>>>; 6],
    ) -> Vec<u32> {
        let (on, p) = (self.on(), &self.options.plan);
        match (view.kind, view.part) {
            // One of several frusta lights only the receivers in its cell.
            (ViewKind::Face(f), Some(part)) => {
                let on_face = footprints[f].get_or_insert_with(|| {
                    receivers
                        .iter()
                        .map(|&s| {
                            let b = &self.scene.surfaces[s as usize].bounds;
                            frusta::footprint(l.position, f, b)
                        })
                        .collect()
                });
                receivers
                    .iter()
                    .zip(on_face.iter())
                    .filter(|(_, r)| r.is_some_and(|r| r.intersection(&part.cell).is_some()))
                    .map(|(&s, _)| s)
                    .collect()
            }
            (ViewKind::Face(f), None) if on && p.cull_receivers => {
                let pyramid = cull::face_pyramid(l.position, f);
                receivers
                    .iter()
                    .copied()
                    .filter(|&s| pyramid.intersects_aabb(&self.scene.surfaces[s as usize].bounds))
                    .collect()
            }
            _ => receivers.to_vec(),
        }
    }

    /// Whether a light's views are six whole cube faces drawn as one merged map
    /// (`plan.merge_faces`; not with clip planes at the maps' edges).
    fn merges_faces(&self, views: &[ShadowView]) -> bool {
        self.on()
            && self.options.plan.merge_faces
            && views.iter().all(|v| v.part.is_none())
            && self.options.shadow_map.outside != Outside::ClipPlanes
            && views.len() == 6
            && views.iter().all(|v| matches!(v.kind, ViewKind::Face(_)))
    }

    /// Several frusta around the receivers in view of omni light `l` (index `index`;
    /// `shadow_map.omni = frusta`), each receiver asking for the screen pixels a world unit
    /// covers at its distance from the camera: the frusta, what they are chosen for (the key
    /// [`KeptFrusta`] keeps them by) and whether they are last frame's, kept
    /// (`plan.keep_frusta`). None where no receiver is beyond the near plane (six faces then).
    fn frusta_of(
        &self,
        index: usize,
        l: &Light,
        receivers: &[u32],
        o: &ShadowMapOptions,
    ) -> Option<(u64, Vec<frusta::FaceFrustum>, bool)> {
        // Pixels per world unit at distance 1: half the height over tan(fovy / 2).
        let pixels = 0.5 * self.camera.height as f32 * self.camera.projection.y_axis.y.abs();
        let eye = frusta::Eye {
            position: self.scene_camera.position,
            pixels,
            near: self.near,
            screen: self.camera.width.max(self.camera.height) as f32,
        };
        let mut needs = Vec::new();
        for &s in receivers {
            frusta::receiver_needs(self.scene.surfaces[s as usize].bounds, &eye, &mut needs);
        }
        let key = hash_of((
            &self.map_options_text,
            mat_bits(&Mat4::from_translation(l.position)),
            l.radius.to_bits(),
            (self.camera.width, self.camera.height),
        ));
        let keep = self.on() && self.options.plan.keep_frusta;
        if let Some(kept) = self.kept.get(index, key).filter(|_| keep)
            && frusta::still_cover(l.position, kept, &needs, KEEP_SLACK)
        {
            return Some((key, kept.to_vec(), true));
        }
        let budget = frusta::Budget {
            texels: 6 * u64::from(o.size).pow(2),
            max_frusta: o.max_frusta as usize,
            min_size: MIN_FRUSTUM_SIZE.min(o.size),
            max_size: o.size.max((4 * o.size).min(MAX_FRUSTUM_SIZE)),
        };
        let chosen = frusta::choose(l.position, &needs, &budget);
        (!chosen.is_empty()).then_some((key, chosen, false))
    }

    /// Replaces view `vi` of a `psm` or `tsm` light by its warp (`shadow::warp`), fitted to the
    /// receivers it lights (`lit`); keeps only the casters the warp can draw (`drawn`). Where
    /// the warp degenerates the standard view stays, and the stats say why.
    fn warp_view(
        &self,
        plan: &mut LightPlan,
        vi: usize,
        kind: Warp,
        (lit, drawn): (&[u32], &mut Vec<u32>),
        stats: &mut PlanStats,
    ) {
        let l = &self.scene.lights[plan.light];
        let bounds = |list: &[u32]| -> Vec<Aabb> {
            list.iter()
                .map(|&s| self.scene.surfaces[s as usize].bounds)
                .collect()
        };
        let (receivers, casters) = (bounds(lit), bounds(drawn));
        let view = &mut plan.views[vi];
        let input = WarpInput {
            camera: &self.scene_camera,
            aspect: self.camera.width as f32 / self.camera.height.max(1) as f32,
            light: l.position,
            standard: view.view_proj(),
            receivers: &receivers,
            casters: &casters,
            reach: Aabb {
                min: l.position - l.radius,
                max: l.position + l.radius,
            },
        };
        let name = plan.technique;
        let which = format!("light {} view {vi}", plan.light);
        match warp::warp(kind, &input, &self.options.psm) {
            Ok(w) => {
                view.view = w.view;
                view.projection = w.projection;
                view.depth_view_proj = w.depth;
                let mut keep = w.casters.iter();
                drawn.retain(|_| *keep.next().expect("one flag per caster"));
                let mut how = format!("{which}: {name}");
                if w.slide > 0.0 {
                    how += &format!(", camera slid back {:.1}", w.slide);
                }
                if w.inverted {
                    how += ", light behind the camera (depth reversed)";
                }
                stats.warps.push(how);
            }
            Err(d) => {
                stats.warp_fallbacks += 1;
                stats.warps.push(format!(
                    "{which}: {name} fell back to a standard map: {}",
                    d.describe()
                ));
            }
        }
    }

    /// The casters one view of light `l` draws: those in its range and view frustum.
    fn map_casters(&self, l: &Light, kind: ViewKind, view_proj: &Mat4) -> Vec<u32> {
        if !(self.on() && self.options.plan.cull_casters) {
            return self.caster_list.clone();
        }
        let view_frustum = (kind != ViewKind::Cube).then(|| Frustum::from_view_proj(view_proj));
        self.caster_list
            .iter()
            .copied()
            .filter(|&c| {
                let b = &self.scene.surfaces[c as usize].bounds;
                cull::sphere_meets_aabb(l.position, l.radius, b)
                    && view_frustum.as_ref().is_none_or(|f| f.intersects_aabb(b))
            })
            .collect()
    }

    /// What a view's map depends on (a map drawn with the same key is reused): the light and
    /// map options, the view, the casters drawn and where the moving ones stand, in which pose.
    fn map_key(
        &self,
        light_key: u64,
        view: &crate::shadow::views::ShadowView,
        drawn: &[u32],
    ) -> u64 {
        let moving: Vec<([u32; 16], u64)> = drawn
            .iter()
            .filter_map(|&c| match self.scene.surfaces[c as usize].owner {
                SurfaceOwner::Model(m) => {
                    let model = &self.scene.models[m];
                    Some((mat_bits(&model.transform), model.pose))
                }
                SurfaceOwner::World => None,
            })
            .collect();
        hash_of((
            light_key,
            mat_bits(&view.view_proj()),
            format!("{:?}", view.kind),
            view.part.map(|p| p.size),
            drawn,
            moving,
        ))
    }

    /// Where a view's lit pass may draw: an omni light's six spots get the face's part of the
    /// light's rectangle, each of several frusta its cell's part; other views the light's
    /// rectangle.
    fn face_rect(
        &self,
        l: &Light,
        view: &crate::shadow::views::ShadowView,
        light_rect: Option<Scissor>,
    ) -> Option<Scissor> {
        let (c, pos, radius) = (&self.camera, l.position, l.radius);
        let part = match (view.kind, view.part) {
            (ViewKind::Face(_), Some(p)) => {
                Some(scissor::cell_scissor(c, pos, radius, &view.view, &p.cell))
            }
            (ViewKind::Face(f), None) => Some(scissor::face_scissor(c, pos, radius, f)),
            _ => None,
        };
        match (part, light_rect) {
            (Some(part), Some(light_rect)) => Some(part.map_or(
                Scissor {
                    width: 0,
                    height: 0,
                    ..light_rect
                },
                |r| r.intersect(&light_rect),
            )),
            _ => light_rect,
        }
    }

    /// A shadow-volume light's parts: each piece whose shadow may reach a receiver in view,
    /// with its counting. Some(why) when none is left.
    fn plan_volumes(&self, plan: &mut LightPlan, stats: &mut PlanStats) -> Option<&'static str> {
        self.volume_parts(plan, stats, false);
        if self.on() && self.options.plan.cull_lights && plan.volumes.is_empty() {
            return Some("no caster whose shadow reaches the view");
        }
        self.hand_to_gpu(plan);
        None
    }

    /// A subdivided light: which triangles are cut and, when the models are not among them
    /// (`subdivision.models = volumes`), the volumes of the models and of the world's pieces
    /// whose shadow may fall on a model (the world's shadows on the world are the marks').
    fn plan_subdivision(&self, plan: &mut LightPlan, stats: &mut PlanStats) {
        let geometry = match self.options.subdivision.models {
            ModelShadows::Volumes => Geometry::World,
            ModelShadows::Subdivided => Geometry::Everything,
        };
        plan.subdivided = Some(geometry);
        if geometry == Geometry::World {
            self.volume_parts(plan, stats, true);
            self.hand_to_gpu(plan);
        }
    }

    /// Pushes the light's volume parts to `plan.volumes`: the pieces whose shadow may meet a
    /// receiver in view; with `world_on_models`, the world's pieces only where it may meet a
    /// model. Culling casters, the receivers' boxes become `plan.volume_receivers`.
    fn volume_parts(&self, plan: &mut LightPlan, stats: &mut PlanStats, world_on_models: bool) {
        let p = &self.options.plan;
        let on = self.on();
        let l = &self.scene.lights[plan.light];
        let is_model = |owner| matches!(owner, SurfaceOwner::Model(_));
        // Receiver boxes: a piece whose shadow meets none of them shadows nothing in view
        // (Forsyth).
        let receiver_boxes: Vec<Aabb> = plan
            .receivers
            .iter()
            .map(|&r| self.scene.surfaces[r as usize].bounds)
            .collect();
        let model_boxes: Vec<Aabb> = plan
            .receivers
            .iter()
            .map(|&r| &self.scene.surfaces[r as usize])
            .filter(|s| world_on_models && is_model(s.owner))
            .map(|s| s.bounds)
            .collect();
        for &(group, piece, bounds, g) in &self.pieces {
            let world_for_models = world_on_models && !is_model(g.owner);
            let boxes = match world_for_models {
                true => &model_boxes,
                false => &receiver_boxes,
            };
            let keep = match on && p.cull_casters {
                // Unculled, every piece; the world's only when some model may be shadowed.
                false => !(world_for_models && model_boxes.is_empty()),
                true => {
                    let shadow = cull::shadow_bounds(&bounds, l.position, l.radius);
                    cull::sphere_meets_aabb(l.position, l.radius, &bounds)
                        && self.view_frustum.intersects_aabb(&shadow)
                        && boxes.iter().any(|r| r.intersects(&shadow))
                }
            };
            if !keep {
                stats.casters_culled += 1;
                continue;
            }
            stats.casters_drawn += 1;
            let part = |counting, triangles| VolumePart {
                group,
                piece,
                counting,
                triangles,
            };
            match self.counting_of(plan, g, piece, &bounds) {
                Some(counting) => {
                    match counting {
                        Counting::ZFail => stats.zfail_parts += 1,
                        Counting::ZPass => stats.zpass_parts += 1,
                    }
                    plan.volumes.push(part(counting, PartTriangles::All));
                }
                None => {
                    let i = plan.near_plane_triangles.len() - 1;
                    stats.split_parts += 1;
                    stats.zfail_parts += 1;
                    stats.zpass_parts += 1;
                    plan.volumes
                        .push(part(Counting::ZFail, PartTriangles::NearPlane(i)));
                    plan.volumes
                        .push(part(Counting::ZPass, PartTriangles::Rest(i)));
                }
            }
        }
        if on && p.cull_casters {
            plan.volume_receivers = receiver_boxes;
        }
    }

    /// Moves the parts of groups the GPU extrudes (`shadow_volume.gpu_extrusion`) out of the
    /// CPU's list: each such group is drawn whole, depth-fail (its pieces the planner culled
    /// are drawn too, and no per-piece test says depth-pass is safe for them).
    fn hand_to_gpu(&self, plan: &mut LightPlan) {
        let o = &self.options;
        let gpu = |owner: SurfaceOwner| match o.shadow_volume.gpu_extrusion {
            GpuExtrusion::None => false,
            GpuExtrusion::Models => matches!(owner, SurfaceOwner::Model(_)),
            GpuExtrusion::All => true,
        };
        // The shader extrudes to infinity only, and needs the shader pipeline.
        if o.shadow_volume.gpu_extrusion == GpuExtrusion::None
            || o.shadow_volume.extrusion != volume::Extrusion::Infinite
            || o.gl.pipeline == Pipeline::FixedFunction
        {
            return;
        }
        // The groups handed over, by index (pieces list each group's pieces in a run).
        let mut extruded_groups: Vec<usize> = Vec::new();
        for &(group, _, _, g) in &self.pieces {
            if gpu(g.owner) && extruded_groups.last() != Some(&group) {
                extruded_groups.push(group);
            }
        }
        let mut kept = Vec::with_capacity(plan.volumes.len());
        for part in std::mem::take(&mut plan.volumes) {
            if !extruded_groups.contains(&part.group) {
                kept.push(part);
                continue;
            }
            if !plan.extruded.iter().any(|(g, _)| *g == part.group) {
                plan.extruded.push((part.group, Counting::ZFail));
            }
        }
        plan.volumes = kept;
    }

    /// How a piece's volume is counted. The planner turns depth-fail into a per-piece choice
    /// (`plan.counting`); a depth-pass asked for stays. None: the piece is depth-fail only for
    /// its triangles near the near plane, which are split off (`plan.split_counting`; their
    /// list is pushed to `plan.near_plane_triangles`).
    fn counting_of(
        &self,
        plan: &mut LightPlan,
        g: &CasterGroup,
        piece: PieceRef,
        bounds: &Aabb,
    ) -> Option<Counting> {
        let p = &self.options.plan;
        let on = self.on();
        let counting_auto = match self.options.shadow_volume.counting {
            CountingMode::Auto => true,
            CountingMode::Zfail => on && p.counting,
            CountingMode::Zpass => false,
        };
        if !counting_auto {
            return Some(match self.options.shadow_volume.counting {
                CountingMode::Zpass => Counting::ZPass,
                _ => Counting::ZFail,
            });
        }
        // A ray seen through an alpha-tested caster's holes enters its volume through the
        // front cap, which depth-pass does not draw; an open surface keeps the paper's
        // depth-fail (see `Component::open`).
        let pos = self.scene.lights[plan.light].position;
        let open = g.piece(piece).open && p.open_depth_fail;
        let see_through = g.piece(piece).alpha_tested || open;
        let boxed = volume::potentially_inside_shadow(bounds, self.camera.position, pos, self.near);
        // The eye within a closed piece's box (grown by the near distance): it may stand
        // inside the caster, whose inner faces are culled, so that rays leave it through its
        // lit faces into the volume, past the front cap depth-pass does not draw, whatever the
        // near plane holds (oa_dm3's flythrough walked through the running player: 16% wrong
        // at frame 448).
        let eye_in_box = !g.piece(piece).open && {
            let e = self.camera.position;
            let grown = self.near;
            e.cmpge(bounds.min - grown).all() && e.cmple(bounds.max + grown).all()
        };
        match (see_through, boxed, on && p.near_plane_test) {
            (true, _, _) => Some(Counting::ZFail),
            (false, false, _) => Some(Counting::ZPass),
            (false, true, false) => Some(Counting::ZFail),
            (false, true, true) if eye_in_box => Some(Counting::ZFail),
            (false, true, true) => {
                let near_tris = near_plane_triangles(
                    self.scene,
                    g,
                    piece,
                    pos,
                    &self.near_quad,
                    &self.options.shadow_volume,
                );
                if near_tris.is_empty() {
                    Some(Counting::ZPass)
                } else if p.split_counting {
                    plan.near_plane_triangles.push(near_tris);
                    None
                } else {
                    Some(Counting::ZFail)
                }
            }
        }
    }
}

/// `plan.near_plane_test` for one piece of caster group `g`: its facing triangles whose shadow from a light at `light` may hold part of the
/// camera's near-plane rectangle `near_quad` (world space), tested in the group's own space;
/// sorted.
fn near_plane_triangles(
    scene: &Scene,
    g: &CasterGroup,
    piece: PieceRef,
    light: Vec3,
    near_quad: &[Vec3; 4],
    o: &ShadowVolumeOptions,
) -> Vec<u32> {
    let to_local = volume::group_transform(scene, g.owner).inverse();
    let mut near: Vec<u32> = volume::near_plane_triangles(
        g,
        g.piece(piece),
        to_local.transform_point3(light).as_dvec3(),
        &near_quad.map(|q| to_local.transform_point3(q).as_dvec3()),
        o.facing_epsilon,
        o.casters == VolumeCasters::Both,
    )
    .collect();
    // Sorted once here: both parts of the split look triangles up in it.
    near.sort_unstable();
    near
}
