//! Per-frame decisions, free of GL: which camera, which surfaces, which lights and which passes.
//!
//! The GL layer executes a [`Plan`] and decides nothing about *what* to draw.

pub mod auto;
pub mod clipped;
pub mod cull;
pub mod depth_bounds;
pub mod merge;
pub mod occlusion;
pub mod pass;
pub mod planner;
pub mod scissor;
pub mod volume_draws;

use crate::geometry::{Aabb, Frustum, projection};
use crate::options::{
    CountingMode, OmniMode, Options, ShadowMapOptions, StencilPasses, Technique, VolumeProjection,
};
use crate::scene::vis::VisStats;
use crate::scene::{Camera, Scene, SurfaceOwner};
use crate::shadow::views::{ShadowView, ViewKind, shadow_views};
use crate::shadow::volume::{self, CasterGroups, Counting};
use auto::CostMemory;
use glam::{Mat3, Mat4, Vec3};
use scissor::Scissor;
use serde::Serialize;

/// The camera as the passes use it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraSetup {
    pub position: Vec3,
    pub view: Mat4,
    pub projection: Mat4,
    pub view_proj: Mat4,
    pub width: u32,
    pub height: u32,
}

/// Lengyel's epsilon in the Doom 3 form of the infinite projection (third row -0.999).
pub const DOOM3_EPSILON: f32 = 0.001;

impl CameraSetup {
    /// The paper's camera: far plane at infinity (section 4.1), so nothing is ever far-clipped.
    pub fn new(c: &Camera, width: u32, height: u32) -> CameraSetup {
        CameraSetup::with_projection(c, width, height, VolumeProjection::Infinite, 0.0)
    }

    /// A camera with the shadow-volume projection choice; `scene_far` is the finite far plane of
    /// the depth-clamp form.
    pub fn with_projection(
        c: &Camera,
        width: u32,
        height: u32,
        kind: VolumeProjection,
        scene_far: f32,
    ) -> CameraSetup {
        let aspect = width as f32 / height as f32;
        let view = c.view();
        let fov = c.fov_y(aspect);
        let projection = match kind {
            VolumeProjection::Infinite => projection::perspective_infinite(fov, aspect, c.near),
            VolumeProjection::InfiniteEpsilon => {
                projection::perspective_infinite_epsilon(fov, aspect, c.near, DOOM3_EPSILON)
            }
            VolumeProjection::DepthClamp => {
                projection::perspective(fov, aspect, c.near, scene_far.max(c.near * 2.0))
            }
        };
        CameraSetup {
            position: c.position,
            view,
            projection,
            view_proj: projection * view,
            width,
            height,
        }
    }
}

/// One caster piece's volume for one light.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VolumePart {
    /// Index into the scene's caster groups.
    pub group: usize,
    /// Index into the group's components, or its chunks when `chunked`.
    pub component: usize,
    /// Whether the piece is a chunk (the planner culls chunks; the paper's frame extrudes
    /// whole components).
    pub chunked: bool,
    pub counting: Counting,
    /// Which of the piece's triangles the part holds.
    pub triangles: PartTriangles,
}

/// The triangles of a piece one volume part holds (`plan.split_counting`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PartTriangles {
    /// The whole piece.
    All,
    /// The facing triangles whose shadow may hold part of the near plane:
    /// `LightPlan::near_plane_triangles[i]`.
    NearPlane(usize),
    /// The piece less those.
    Rest(usize),
}

/// One light's work this frame.
#[derive(Debug, Clone, PartialEq)]
pub struct LightPlan {
    /// Index into `Scene::lights`.
    pub light: usize,
    /// The technique it runs with (resolved: never `auto`; `none` when it needs no shadow work).
    pub technique: Technique,
    /// Position among this frame's enabled lights: the paper grows the polygon offset with it.
    pub order: usize,
    /// Shadow-map views (shadow mapping only).
    pub views: Vec<ShadowView>,
    /// Volume parts (shadow volumes only).
    pub volumes: Vec<VolumePart>,
    /// Surfaces the lit pass draws: visible receivers the light can reach.
    pub receivers: Vec<u32>,
    /// Per shadow-map view, the receivers its lit pass draws (an omni light's six spots: those
    /// in the face's pyramid).
    pub view_receivers: Vec<Vec<u32>>,
    /// Per shadow-map view, the casters drawn into its map.
    pub view_casters: Vec<Vec<u32>>,
    /// Per shadow-map view, what its map depends on; a map drawn with the same key is reused.
    pub view_keys: Vec<Option<u64>>,
    /// Where the light's stencil and lit passes may draw (None: the whole frame).
    pub scissor: Option<Scissor>,
    /// Per shadow-map view, where its lit pass may draw (an omni light's six spots: the face's
    /// part of the light's rectangle; None: the light's rectangle).
    pub view_scissors: Vec<Option<Scissor>>,
    /// An omni light's six spots lit in one pass (each fragment reads its face's map).
    pub merged: bool,
    /// Shadow volumes: the boxes of the receivers whose counts matter; a facing triangle whose
    /// shadow reaches none of them is left out of its volume (empty: every triangle counts).
    pub volume_receivers: Vec<Aabb>,
    /// Per split piece (`PartTriangles`), its triangles whose shadow may hold part of the
    /// near plane, sorted.
    pub near_plane_triangles: Vec<Vec<u32>>,
    /// How the technique was chosen (`auto`, or why the light needs no shadow work).
    pub reason: String,
}

/// What the plan decided, for stats overlays and bench JSON.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct PlanStats {
    pub surfaces: usize,
    pub surfaces_visible: usize,
    pub triangles_visible: usize,
    /// BSP visibility of Quake 3 worlds.
    pub vis: Option<VisStats>,
    /// Lights `lighting` admits.
    pub lights_enabled: usize,
    /// Lights with passes this frame.
    pub lights_planned: usize,
    /// Lights whose range misses the view frustum or lands off screen.
    pub lights_culled_frustum: usize,
    /// Lights whose range reaches no visible BSP leaf or receiver.
    pub lights_culled_pvs: usize,
    /// Planned lights left without shadow work: no caster in range, or none whose shadow
    /// reaches the view.
    pub lights_without_casters: usize,
    /// Receiver surfaces drawn by lit passes, summed over lights and views, and those the
    /// planner left out.
    pub receivers_drawn: usize,
    pub receivers_culled: usize,
    /// Casters drawn: surfaces into shadow maps (summed over views) plus volume components.
    pub casters_drawn: usize,
    pub casters_culled: usize,
    /// Mean share of the frame inside the planned lights' scissor rectangles.
    pub scissor_fraction: f64,
    pub zpass_parts: usize,
    pub zfail_parts: usize,
    /// Pieces split into a depth-fail and a depth-pass part (`plan.split_counting`; each
    /// counted once more in `zpass_parts` and `zfail_parts`).
    pub split_parts: usize,
    /// Stencil passes per light's volumes: 2 (the paper's culled passes) or 1
    /// (`plan.one_pass_stencil`, or `shadow_volume.stencil = separate`).
    pub stencil_passes: usize,
    /// Per light `auto` decided for: "light i: technique (why)".
    pub choices: Vec<String>,
}

/// Everything the passes need to know for one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    pub camera: CameraSetup,
    /// Per surface: drawn in camera passes.
    pub visible: Vec<bool>,
    /// Per surface: drawn into shadow maps and volumes.
    pub casters: Vec<bool>,
    pub lights: Vec<LightPlan>,
    /// How the stencil pass counts volumes (`shadow_volume.stencil`, or one pass under
    /// `plan.one_pass_stencil`).
    pub stencil: StencilPasses,
    /// Enabled lights the planner culled (their masks are empty).
    pub culled: Vec<usize>,
    pub stats: PlanStats,
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

impl Plan {
    /// Whether some planned light runs `technique`.
    pub fn any(&self, technique: Technique) -> bool {
        self.lights.iter().any(|l| l.technique == technique)
    }

    /// The plan for the scene's own camera.
    pub fn build(scene: &Scene, options: &Options) -> Plan {
        Plan::build_at(scene, &scene.camera, options)
    }

    /// The plan for `camera` (a camera path's frame, the viewer's camera), with the caster
    /// groups built afresh (a [`planner::Planner`] keeps them across frames).
    pub fn build_at(scene: &Scene, camera: &Camera, options: &Options) -> Plan {
        let groups = Plan::needs_casters(scene, options).then(|| CasterGroups::build(scene));
        Plan::build_with(
            scene,
            camera,
            options,
            &CostMemory::default(),
            groups.as_ref(),
        )
    }

    /// Whether planning a frame of `scene` under `options` needs its caster groups: some
    /// light may use shadow volumes.
    pub fn needs_casters(scene: &Scene, options: &Options) -> bool {
        let n = scene.lights.len();
        options.uses(n, Technique::ShadowVolume) || options.uses(n, Technique::Auto)
    }

    /// The plan for `camera`, with the costs measured so far (for `technique = auto`) and the
    /// scene's caster groups (needed when [`Plan::needs_casters`]; without them no light
    /// gets volumes).
    pub fn build_with(
        scene: &Scene,
        camera: &Camera,
        options: &Options,
        memory: &CostMemory,
        groups: Option<&CasterGroups>,
    ) -> Plan {
        let n = scene.lights.len();
        let may = |t: Technique| options.uses(n, t) || options.uses(n, Technique::Auto);
        let uses_volumes = may(Technique::ShadowVolume);
        let camera_setup = if uses_volumes {
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
        } else {
            CameraSetup::new(camera, options.width, options.height)
        };
        let frustum = options
            .culling
            .frustum
            .then(|| Frustum::from_view_proj(&camera_setup.view_proj));
        let mut visible = vec![false; scene.surfaces.len()];
        let mut leaves: Vec<Aabb> = Vec::new();
        let mut stats = PlanStats {
            surfaces: scene.surfaces.len(),
            ..PlanStats::default()
        };
        match &scene.world {
            // Quake 3 worlds: the PVS and frustum tests of the paper's base renderer.
            Some(world) => {
                stats.vis = Some(world.mark_visible(
                    camera_setup.position,
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
        let casters: Vec<bool> = scene
            .surfaces
            .iter()
            .map(|s| {
                let m = &scene.materials[s.material];
                m.visible && m.casts_shadows
            })
            .collect();
        let caster_list: Vec<u32> = (0..casters.len())
            .filter(|&i| casters[i])
            .map(|i| i as u32)
            .collect();
        // Alpha-tested casters: `auto` and the counting choice treat them apart (once per
        // frame, not per light).
        let alpha_caster_bounds: Vec<Aabb> = caster_list
            .iter()
            .map(|&c| &scene.surfaces[c as usize])
            .filter(|s| scene.materials[s.material].alpha_test.is_some())
            .map(|s| s.bounds)
            .collect();
        let caster_bounds: Vec<Aabb> = if may(Technique::ShadowMap) {
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
        // Shadow-volume casters, with their world bounds (for culling and the depth-pass test).
        let groups = groups.filter(|_| uses_volumes);
        let p = &options.plan;
        let on = p.enabled;
        // `plan.omni_cube`: where six spots and a cube cover the same directions (no narrowed
        // field of view, no clip planes), an omni light's maps are the faces of one cube map.
        let sm = &options.shadow_map;
        let map_options = if on
            && p.omni_cube
            && sm.omni == OmniMode::SixSpots
            && sm.fov_scale == 1.0
            && sm.outside != crate::options::Outside::ClipPlanes
        {
            ShadowMapOptions {
                omni: OmniMode::Cube,
                ..sm.clone()
            }
        } else {
            sm.clone()
        };
        let map_options_text = format!("{map_options:?}");
        // The planner culls pieces of at most CHUNK_TRIANGLES; the paper's frame, components.
        let chunked = on && p.cull_casters;
        let components: Vec<(usize, usize, Aabb, &volume::CasterGroup)> = groups
            .iter()
            .flat_map(|g| g.groups.iter().enumerate())
            .flat_map(|(gi, g)| {
                let t = volume::group_transform(scene, g.owner);
                let pieces = if chunked { &g.chunks } else { &g.components };
                pieces
                    .iter()
                    .enumerate()
                    .map(move |(ci, c)| (gi, ci, c.bounds.transformed(&t), g))
            })
            .collect();

        // Culling tests use the camera frustum without a far plane: volumes reach infinity.
        let view_frustum = Frustum::from_view_proj(
            &CameraSetup::new(camera, options.width, options.height).view_proj,
        );
        let eye = camera_setup.position;
        let near = camera.near;
        // Where depth-pass counts start (`plan.near_plane_test`): the near plane's rectangle,
        // grown by a tenth about its centre against rounding in the rasteriser's clipping; under
        // depth clamping nothing is near-clipped, so counts start at the eye.
        let near_quad = if options.shadow_volume.projection == VolumeProjection::DepthClamp {
            [eye; 4]
        } else {
            let inv = camera_setup.view_proj.inverse();
            [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                .map(|(x, y)| inv.project_point3(Vec3::new(x * 1.1, y * 1.1, -1.0)))
        };
        let screen = (camera_setup.width as f64 * camera_setup.height as f64).max(1.0);
        let mut lights = Vec::new();
        let mut culled = Vec::new();
        let mut scissor_sum = 0.0;
        let enabled: Vec<usize> = (0..n).filter(|&i| options.light_enabled(i)).collect();
        stats.lights_enabled = enabled.len();
        for (order, &index) in enabled.iter().enumerate() {
            let l = &scene.lights[index];
            let (pos, radius) = (l.position, l.radius);
            // Light culling: the view frustum, then the visible leaves and receivers.
            if on && p.cull_lights && !cull::sphere_meets_frustum(&view_frustum, pos, radius) {
                stats.lights_culled_frustum += 1;
                culled.push(index);
                continue;
            }
            let receivers: Vec<u32> = if on && p.cull_receivers {
                receivers_in_view
                    .iter()
                    .copied()
                    .filter(|&s| {
                        cull::sphere_meets_aabb(pos, radius, &scene.surfaces[s as usize].bounds)
                    })
                    .collect()
            } else {
                receivers_in_view.clone()
            };
            stats.receivers_culled += receivers_in_view.len() - receivers.len();
            let reaches_leaf = scene.world.is_none()
                || leaves
                    .iter()
                    .any(|b| cull::sphere_meets_aabb(pos, radius, b))
                || receivers
                    .iter()
                    .any(|&s| matches!(scene.surfaces[s as usize].owner, SurfaceOwner::Model(_)));
            let reaches_receiver = !p.cull_receivers || !receivers.is_empty();
            if on && p.cull_lights && !(reaches_leaf && reaches_receiver) {
                stats.lights_culled_pvs += 1;
                culled.push(index);
                continue;
            }
            let scissor = if on && p.scissor {
                match scissor::sphere_scissor(&camera_setup, pos, radius) {
                    Some(s) => Some(s),
                    None => {
                        stats.lights_culled_frustum += 1;
                        culled.push(index);
                        continue;
                    }
                }
            } else {
                None
            };

            // The technique: asked for, or chosen.
            let alpha_casters = || {
                alpha_caster_bounds
                    .iter()
                    .any(|b| cull::sphere_meets_aabb(pos, radius, b))
            };
            let (mut technique, mut reason) = match options.technique_for(index) {
                Technique::Auto => {
                    let c = auto::choose(index, options, memory, alpha_casters());
                    stats
                        .choices
                        .push(format!("light {index}: {} ({})", c.technique, c.reason));
                    (c.technique, c.reason)
                }
                t => (t, String::new()),
            };

            let mut plan = LightPlan {
                light: index,
                technique,
                order,
                views: Vec::new(),
                volumes: Vec::new(),
                receivers,
                view_receivers: Vec::new(),
                view_casters: Vec::new(),
                view_keys: Vec::new(),
                scissor,
                view_scissors: Vec::new(),
                merged: false,
                volume_receivers: Vec::new(),
                near_plane_triangles: Vec::new(),
                reason: String::new(),
            };
            match technique {
                Technique::ShadowMap => {
                    plan.views = shadow_views(l, &caster_bounds, &map_options);
                    let sm_key = hash_of((
                        &map_options_text,
                        order,
                        mat_bits(&Mat4::from_translation(pos)),
                        radius.to_bits(),
                        format!("{:?}", l.kind),
                    ));
                    for view in &plan.views {
                        let view_frustum = (view.kind != ViewKind::Cube)
                            .then(|| Frustum::from_view_proj(&view.view_proj()));
                        let drawn: Vec<u32> = if on && p.cull_casters {
                            caster_list
                                .iter()
                                .copied()
                                .filter(|&c| {
                                    let b = &scene.surfaces[c as usize].bounds;
                                    cull::sphere_meets_aabb(pos, radius, b)
                                        && view_frustum
                                            .as_ref()
                                            .is_none_or(|f| f.intersects_aabb(b))
                                })
                                .collect()
                        } else {
                            caster_list.clone()
                        };
                        stats.casters_drawn += drawn.len();
                        stats.casters_culled += caster_list.len() - drawn.len();
                        let lit: Vec<u32> = match view.kind {
                            ViewKind::Face(f) if on && p.cull_receivers => {
                                let pyramid = cull::face_pyramid(pos, f);
                                plan.receivers
                                    .iter()
                                    .copied()
                                    .filter(|&s| {
                                        pyramid.intersects_aabb(&scene.surfaces[s as usize].bounds)
                                    })
                                    .collect()
                            }
                            _ => plan.receivers.clone(),
                        };
                        let key = (on && p.cache_maps).then(|| {
                            let moving: Vec<[u32; 16]> = drawn
                                .iter()
                                .filter_map(|&c| match scene.surfaces[c as usize].owner {
                                    SurfaceOwner::Model(m) => {
                                        Some(mat_bits(&scene.models[m].transform))
                                    }
                                    SurfaceOwner::World => None,
                                })
                                .collect();
                            hash_of((
                                sm_key,
                                mat_bits(&view.view_proj()),
                                format!("{:?}", view.kind),
                                &drawn,
                                moving,
                            ))
                        });
                        let face_rect = match (view.kind, scissor) {
                            (ViewKind::Face(f), Some(light_rect)) => {
                                Some(scissor::face_scissor(&camera_setup, pos, radius, f).map_or(
                                    Scissor {
                                        width: 0,
                                        height: 0,
                                        ..light_rect
                                    },
                                    |r| r.intersect(&light_rect),
                                ))
                            }
                            _ => scissor,
                        };
                        plan.view_receivers.push(lit);
                        plan.view_casters.push(drawn);
                        plan.view_keys.push(key);
                        plan.view_scissors.push(face_rect);
                    }
                    plan.merged = on
                        && p.merge_faces
                        && options.shadow_map.outside != crate::options::Outside::ClipPlanes
                        && plan.views.len() == 6
                        && plan
                            .views
                            .iter()
                            .all(|v| matches!(v.kind, ViewKind::Face(_)));
                    if on && p.cull_lights && plan.view_casters.iter().all(|c| c.is_empty()) {
                        technique = Technique::None;
                        reason = "no caster in range".into();
                        plan.views.clear();
                        plan.view_receivers.clear();
                        plan.view_casters.clear();
                        plan.view_keys.clear();
                        plan.view_scissors.clear();
                    }
                }
                Technique::ShadowVolume => {
                    // The planner turns depth-fail into auto; a depth-pass asked for stays.
                    let counting_auto = match options.shadow_volume.counting {
                        CountingMode::Auto => true,
                        CountingMode::Zfail => on && p.counting,
                        CountingMode::Zpass => false,
                    };
                    // Receiver boxes: a piece whose shadow meets none of them shadows nothing
                    // in view (Forsyth).
                    let receiver_boxes: Vec<Aabb> = plan
                        .receivers
                        .iter()
                        .map(|&r| scene.surfaces[r as usize].bounds)
                        .collect();
                    for &(group, component, bounds, g) in &components {
                        let keep = !(on && p.cull_casters) || {
                            let shadow = cull::shadow_bounds(&bounds, pos, radius);
                            cull::sphere_meets_aabb(pos, radius, &bounds)
                                && view_frustum.intersects_aabb(&shadow)
                                && receiver_boxes.iter().any(|r| r.intersects(&shadow))
                        };
                        if !keep {
                            stats.casters_culled += 1;
                            continue;
                        }
                        stats.casters_drawn += 1;
                        // Under counting_auto: None when the piece is depth-fail only for
                        // its triangles near the near plane, which are then split off.
                        let counting = if counting_auto {
                            // A ray seen through an alpha-tested caster's holes enters its
                            // volume through the front cap, which depth-pass does not draw.
                            let alpha = g.piece(component, chunked).alpha_tested;
                            let boxed = volume::potentially_inside_shadow(&bounds, eye, pos, near);
                            match (alpha, boxed, on && p.near_plane_test) {
                                (true, _, _) => Some(Counting::ZFail),
                                (false, false, _) => Some(Counting::ZPass),
                                (false, true, false) => Some(Counting::ZFail),
                                (false, true, true) => {
                                    let near_tris = near_plane_triangles(
                                        scene,
                                        g,
                                        (component, chunked),
                                        pos,
                                        &near_quad,
                                        options.shadow_volume.facing_epsilon,
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
                        } else if options.shadow_volume.counting == CountingMode::Zpass {
                            Some(Counting::ZPass)
                        } else {
                            Some(Counting::ZFail)
                        };
                        let part = |counting, triangles| VolumePart {
                            group,
                            component,
                            chunked,
                            counting,
                            triangles,
                        };
                        match counting {
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
                    if on && p.cull_lights && plan.volumes.is_empty() {
                        technique = Technique::None;
                        reason = "no caster whose shadow reaches the view".into();
                    }
                }
                _ => {}
            }
            if technique == Technique::None && !reason.is_empty() {
                stats.lights_without_casters += 1;
            }
            plan.technique = technique;
            plan.reason = reason;
            let lit_passes = match plan.technique {
                Technique::ShadowMap if !plan.merged => {
                    plan.view_receivers.iter().map(Vec::len).sum()
                }
                _ => plan.receivers.len(),
            };
            stats.receivers_drawn += lit_passes;
            scissor_sum += plan.scissor.map_or(1.0, |s| s.area() as f64 / screen);
            lights.push(plan);
        }
        stats.lights_planned = lights.len();
        stats.scissor_fraction = if lights.is_empty() {
            0.0
        } else {
            scissor_sum / lights.len() as f64
        };
        let stencil = if on && p.one_pass_stencil {
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

/// Inverse transpose of the upper 3x3: transforms normals of a model with scaling.
pub fn normal_matrix(model: &Mat4) -> Mat3 {
    Mat3::from_mat4(*model).inverse().transpose()
}

/// `plan.near_plane_test` for one piece (a chunk, or a component when not `chunked`) of caster
/// group `g`: its facing triangles whose shadow from a light at `light` may hold part of the
/// camera's near-plane rectangle `near_quad` (world space), tested in the group's own space;
/// sorted.
fn near_plane_triangles(
    scene: &Scene,
    g: &volume::CasterGroup,
    (index, chunked): (usize, bool),
    light: Vec3,
    near_quad: &[Vec3; 4],
    facing_epsilon: f32,
) -> Vec<u32> {
    let to_local = volume::group_transform(scene, g.owner).inverse();
    let mut near: Vec<u32> = volume::near_plane_triangles(
        g,
        g.piece(index, chunked),
        to_local.transform_point3(light).as_dvec3(),
        &near_quad.map(|q| to_local.transform_point3(q).as_dvec3()),
        facing_epsilon,
    )
    .collect();
    // Sorted once here: both parts of the split look triangles up in it.
    near.sort_unstable();
    near
}
