//! Per-frame decisions, free of GL: which camera, which surfaces, which lights and which passes.
//!
//! The GL layer executes a [`Plan`] and decides nothing about *what* to draw.

pub mod auto;
mod build;
pub mod clipped;
pub mod cull;
pub mod depth_bounds;
pub mod fallback;
pub mod fixed_function;
pub mod kept_frusta;
pub mod map_memory;
pub mod merge;
pub mod occlusion;
pub mod pass;
pub mod planner;
pub mod profile;
pub mod scissor;
pub mod settings;
pub mod volume_draws;

use crate::geometry::{Aabb, projection};
use crate::options::{
    MapBuffer, ModelShadows, Options, StencilPasses, Technique, VolumeProjection,
};
use crate::scene::vis::VisStats;
use crate::scene::{Camera, Scene};
use crate::shadow::views::ShadowView;
use crate::shadow::volume::{CasterGroups, Counting, PieceRef};
use crate::truth::subdivision::Geometry;
use auto::AutoMemory;
use glam::{Mat3, Mat4, Vec3};

/// `options` without the planner's decisions that change pixels by design (another shadow-map
/// form: `plan.omni_cube`, `plan.wide_spot_omni`). Every other decision claims to change no
/// mask pixel beyond the edge band; `shadowlab check` holds it to that by comparing this frame
/// with the planner's off.
pub fn without_pixel_changing_decisions(options: &Options) -> Options {
    let mut o = options.clone();
    o.plan.omni_cube = false;
    o.plan.wide_spot_omni = false;
    o
}
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
    /// The piece of the group (the planner culls chunks; the paper's frame extrudes whole
    /// components).
    pub piece: PieceRef,
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
    /// What its maps store: `shadow_map.buffer` for standard maps unless `auto` chose
    /// otherwise (`shadow_map:id` in `auto_among`); depth for every other technique.
    pub buffer: MapBuffer,
    /// Its maps' own size where `auto` chose one (`shadow_map@1024` in `auto_among`);
    /// None: `shadow_map.size`. Its views carry the size they draw at.
    pub map_size: Option<u32>,
    /// Position among this frame's enabled lights: the paper grows the polygon offset with it.
    pub order: usize,
    /// glPolygonOffset (factor, units) for this light's maps (`shadow_map.offset_*`, grown
    /// with `order`), or None where the offset is off.
    pub map_offset: Option<(f32, f32)>,
    /// Shadow-map views (shadow mapping only).
    pub views: Vec<ShadowView>,
    /// Volume parts (shadow volumes only) the CPU builds.
    pub volumes: Vec<VolumePart>,
    /// Caster groups whose volumes the GPU extrudes (`shadow_volume.gpu_extrusion`), with
    /// their counting.
    pub extruded: Vec<(usize, Counting)>,
    /// Surfaces the lit pass draws: visible receivers the light can reach.
    pub receivers: Vec<u32>,
    /// Of `receivers`, sorted, those whose bounds meet the light's sphere (a hair enlarged):
    /// what a decision mask draws. A fragment of any other is further from the light than
    /// its radius, which the mask's shader discards as unreached, so the mask is the same;
    /// the paper's frame (every surface a receiver) then draws each light's mask from the few
    /// surfaces in its range, not the whole map six times.
    pub mask_receivers: Vec<u32>,
    /// Per shadow-map view, the receivers its lit pass draws (an omni light's six spots: those
    /// in the face's pyramid).
    pub view_receivers: Vec<Vec<u32>>,
    /// Per shadow-map view, the casters drawn into its map.
    pub view_casters: Vec<Vec<u32>>,
    /// Per shadow-map view, what its map depends on; a map drawn with the same key is reused.
    pub view_keys: Vec<Option<u64>>,
    /// Per shadow-map view, the casters of each image it draws: one for a 2D map, a cube's
    /// six faces each with those in its frustum.
    pub view_images: Vec<Vec<ImageCasters>>,
    /// Per shadow-map view made from a static map (its casters that do not move, kept and
    /// copied into the map, the moving ones drawn over the copy), what the static map depends
    /// on; None: the map is drawn whole.
    pub view_static_keys: Vec<Option<u64>>,
    /// Where the light's stencil and lit passes may draw (None: the whole frame).
    pub scissor: Option<Scissor>,
    /// Per shadow-map view, where its lit pass may draw (an omni light's six spots: the face's
    /// part of the light's rectangle; None: the light's rectangle).
    pub view_scissors: Vec<Option<Scissor>>,
    /// An omni light's six spots lit in one pass (each fragment reads its face's map).
    pub merged: bool,
    /// `shadow_map.omni = frusta`: the frusta of the views and what they were chosen for (the
    /// light's position, radius and map options), for [`kept_frusta::KeptFrusta`].
    pub frusta: Option<(u64, Vec<crate::shadow::frusta::FaceFrustum>)>,
    /// The subdivision (`technique = subdivision`): which triangles it cuts; with
    /// [`Geometry::World`] the models' shadows, and the world's on models, are `volumes`.
    pub subdivided: Option<Geometry>,
    /// Shadow volumes: the boxes of the receivers whose counts matter; a facing triangle whose
    /// shadow reaches none of them is left out of its volume (empty: every triangle counts).
    pub volume_receivers: Vec<Aabb>,
    /// Per split piece (`PartTriangles`), its triangles whose shadow may hold part of the
    /// near plane, sorted.
    pub near_plane_triangles: Vec<Vec<u32>>,
    /// How the technique was chosen (`auto`, or why the light needs no shadow work).
    pub reason: String,
}

/// The casters one image of a shadow map draws (a 2D map, or one face of a cube).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ImageCasters {
    /// Drawn into the view's static map where it has one, else into the map: every caster.
    pub base: Vec<u32>,
    /// Drawn over the copy of the static map: the moving models (empty without a static map).
    pub moving: Vec<u32>,
}

impl LightPlan {
    /// Of `receivers` (the light's, or one of its views'), those its decision mask draws.
    pub fn masked(&self, receivers: &[u32]) -> Vec<u32> {
        receivers
            .iter()
            .copied()
            .filter(|s| self.mask_receivers.binary_search(s).is_ok())
            .collect()
    }

    /// Whether the light counts shadow volumes into its stencil: its technique's, or a
    /// subdivided light's for its models.
    pub fn counts_volumes(&self) -> bool {
        self.technique.uses_volumes()
            || (self.technique == Technique::Subdivision
                && !(self.volumes.is_empty() && self.extruded.is_empty()))
    }
}

/// What the plan decided, for stats overlays and bench JSON.
#[derive(Debug, Clone, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct PlanStats {
    /// The machine the decisions were weighed for (`plan.profile` resolved: `software` or
    /// `gpu`).
    pub profile: String,
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
    /// Lights whose range reaches no receiver in view (the PVS and the frustum decide which
    /// surfaces are in view).
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
    /// Per warped view (`psm`, `tsm`): "light i view k: how it was warped", or why it fell
    /// back to a standard map.
    pub warps: Vec<String>,
    /// Views of warped lights that fell back to a standard map.
    pub warp_fallbacks: usize,
    /// Bytes the frame's shadow maps hold together (depth, static and ID textures), as
    /// `shadow_map.budget_mb` counts them.
    pub map_bytes: u64,
    /// They hold more than `shadow_map.budget_mb`: each light's maps are drawn just before its
    /// own pass ([`Plan::maps_per_light`]).
    pub maps_per_light: bool,
    /// Per omni light under `shadow_map.omni = frusta`: "light i: n frusta, t texels (the six
    /// faces' budget b): face/size ...".
    pub frusta: Vec<String>,
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
    /// Each light's maps drawn just before its own pass, into textures the lights share:
    /// the frame's maps together would hold more than `shadow_map.budget_mb`
    /// ([`map_memory`]). Otherwise every light's maps are drawn first (the paper).
    pub maps_per_light: bool,
    /// Bytes the map textures may hold together this frame ([`map_memory::held_bytes`]; None:
    /// no limit).
    pub map_budget: Option<u64>,
    /// Lights sent between two fences, the one before waited for (`gl.lights_per_fence`; 0:
    /// no fence, no wait).
    pub lights_per_fence: u32,
    pub stats: PlanStats,
}

impl Plan {
    /// Whether some planned light runs `technique`.
    pub fn any(&self, technique: Technique) -> bool {
        self.lights.iter().any(|l| l.technique == technique)
    }

    /// Whether some planned light draws shadow maps.
    pub fn any_maps(&self) -> bool {
        self.lights.iter().any(|l| l.technique.uses_maps())
    }

    /// The largest shadow map of the frame's views; 0 without maps.
    pub fn largest_map(&self) -> u32 {
        self.lights
            .iter()
            .filter(|l| l.technique.uses_maps())
            .flat_map(|l| l.views.iter().map(|v| v.map_size()))
            .max()
            .unwrap_or(0)
    }

    /// Whether some planned light counts shadow volumes.
    pub fn any_volumes(&self) -> bool {
        self.lights.iter().any(LightPlan::counts_volumes)
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
            (&AutoMemory::default(), &kept_frusta::KeptFrusta::default()),
            groups.as_ref(),
        )
    }

    /// Whether planning a frame of `scene` under `options` needs its caster groups: some
    /// light may use shadow volumes (a subdivided one for its models').
    pub fn needs_casters(scene: &Scene, options: &Options) -> bool {
        let models_by_volumes = options.subdivision.models == ModelShadows::Volumes;
        options.uses_where(scene.lights.len(), |t| {
            t.uses_volumes()
                || t == Technique::Auto
                || (t == Technique::Subdivision && models_by_volumes)
        })
    }
}

/// Inverse transpose of the upper 3x3: transforms normals of a model with scaling.
pub fn normal_matrix(model: &Mat4) -> Mat3 {
    Mat3::from_mat4(*model).inverse().transpose()
}
