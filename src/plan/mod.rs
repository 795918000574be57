//! Per-frame decisions, free of GL: which camera, which surfaces, which lights and which passes.
//!
//! The GL layer executes a [`Plan`] and decides nothing about *what* to draw.

pub mod frustum;

use crate::options::{CountingMode, Options, Technique, VolumeProjection};
use crate::q3::vis::VisStats;
use crate::scene::{Aabb, Camera, Scene, SurfaceOwner};
use crate::shadow::projection;
use crate::shadow::views::{ShadowView, shadow_views};
use crate::shadow::volume::{self, Counting};
use frustum::Frustum;
use glam::{Mat3, Mat4, Vec3};
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

/// One caster component's volume for one light.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VolumePart {
    /// Index into the scene's caster groups.
    pub group: usize,
    pub component: usize,
    pub counting: Counting,
}

/// One light's work this frame.
#[derive(Debug, Clone, PartialEq)]
pub struct LightPlan {
    /// Index into `Scene::lights`.
    pub light: usize,
    pub technique: Technique,
    /// Position among this frame's shadowed lights: the paper grows the polygon offset with it.
    pub order: usize,
    /// Shadow-map views (shadow mapping only).
    pub views: Vec<ShadowView>,
    /// Volume parts (shadow volumes only).
    pub volumes: Vec<VolumePart>,
}

/// What the plan decided, for stats overlays and bench JSON.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct PlanStats {
    pub surfaces: usize,
    pub surfaces_visible: usize,
    pub triangles_visible: usize,
    /// BSP visibility of Quake 3 worlds.
    pub vis: Option<VisStats>,
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
    pub stats: PlanStats,
}

impl Plan {
    /// The plan for the scene's own camera.
    pub fn build(scene: &Scene, options: &Options) -> Plan {
        Plan::build_at(scene, &scene.camera, options)
    }

    /// The plan for `camera` (a camera path's frame, the viewer's camera).
    pub fn build_at(scene: &Scene, camera: &Camera, options: &Options) -> Plan {
        let n = scene.lights.len();
        let uses_volumes = options.uses(n, Technique::ShadowVolume);
        let camera = if uses_volumes {
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
            .then(|| Frustum::from_view_proj(&camera.view_proj));
        let mut visible = vec![false; scene.surfaces.len()];
        let mut stats = PlanStats {
            surfaces: scene.surfaces.len(),
            ..PlanStats::default()
        };
        match &scene.world {
            // Quake 3 worlds: the PVS and frustum tests of the paper's base renderer.
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
        let casters: Vec<bool> = scene
            .surfaces
            .iter()
            .map(|s| {
                let m = &scene.materials[s.material];
                m.visible && m.casts_shadows
            })
            .collect();
        let caster_bounds: Vec<Aabb> = match options.uses(n, Technique::ShadowMap) {
            false => Vec::new(),
            true => scene
                .surfaces
                .iter()
                .zip(&casters)
                .filter(|(_, c)| **c)
                .map(|(s, _)| s.bounds)
                .collect(),
        };
        // Shadow-volume casters, with their world bounds (for the depth-pass safety test).
        let groups = uses_volumes.then(|| scene.caster_groups());
        let components: Vec<(usize, usize, Aabb)> = groups
            .iter()
            .flat_map(|g| g.groups.iter().enumerate())
            .flat_map(|(gi, g)| {
                let t = volume::group_transform(scene, g.owner);
                g.components
                    .iter()
                    .enumerate()
                    .map(move |(ci, c)| (gi, ci, c.bounds.transformed(&t)))
            })
            .collect();
        let eye = camera.position;
        let near = scene.camera.near;
        let lights = (0..scene.lights.len())
            .filter(|&i| options.light_enabled(i))
            .enumerate()
            .map(|(order, light)| {
                let l = &scene.lights[light];
                let technique = options.technique_for(light);
                LightPlan {
                    light,
                    technique,
                    order,
                    views: match technique {
                        Technique::ShadowMap => {
                            shadow_views(l, &caster_bounds, &options.shadow_map)
                        }
                        _ => Vec::new(),
                    },
                    volumes: match technique {
                        Technique::ShadowVolume => components
                            .iter()
                            .map(|&(group, component, bounds)| VolumePart {
                                group,
                                component,
                                counting: match options.shadow_volume.counting {
                                    CountingMode::Zfail => Counting::ZFail,
                                    CountingMode::Zpass => Counting::ZPass,
                                    CountingMode::Auto => {
                                        if volume::potentially_inside_shadow(
                                            &bounds, eye, l.position, near,
                                        ) {
                                            Counting::ZFail
                                        } else {
                                            Counting::ZPass
                                        }
                                    }
                                },
                            })
                            .collect(),
                        _ => Vec::new(),
                    },
                }
            })
            .collect();
        Plan {
            camera,
            visible,
            casters,
            lights,
            stats,
        }
    }
}

/// Inverse transpose of the upper 3x3: transforms normals of a model with scaling.
pub fn normal_matrix(model: &Mat4) -> Mat3 {
    Mat3::from_mat4(*model).inverse().transpose()
}
