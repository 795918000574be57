//! The scene: everything a frame needs, on the CPU and free of GL.
//!
//! Loaders (the built-in scene, Quake 3 maps and models, scene files) produce a [`Scene`]; the GL
//! layer uploads it, the exact reference ray-casts it, the shadow-volume code builds edges from it.
//! World space is Quake 3's: Z up, units of about an inch.

pub mod authored;
pub mod builtin;
pub mod camera;
pub mod light;
pub mod motion;
pub mod path;
pub mod shapes;
pub mod vis;

pub use camera::Camera;
pub use light::{Light, LightKind};

use crate::geometry::Aabb;
use crate::images::Rgba;
use glam::{Mat4, Vec3};

/// One vertex of every mesh: the single layout the GL layer uploads.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    /// Texture coordinates of the surface texture.
    pub uv: [f32; 2],
    /// Texture coordinates in the surface's lightmap (unused without one).
    pub lightmap_uv: [f32; 2],
    /// Baked light of vertex-lit Quake 3 surfaces (white elsewhere).
    pub color: [u8; 4],
}

impl Vertex {
    pub fn new(position: Vec3, normal: Vec3, uv: [f32; 2]) -> Self {
        Self {
            position: position.to_array(),
            normal: normal.to_array(),
            uv,
            lightmap_uv: [0.0, 0.0],
            color: [255; 4],
        }
    }
    pub fn pos(&self) -> Vec3 {
        Vec3::from_array(self.position)
    }
}

crate::option_enum! {
    /// Quake 3's alphaFunc: which texels of an alpha-tested surface are kept.
    pub enum AlphaFunc {
        /// Keep alpha > 0.
        Gt0 = "gt0",
        /// Keep alpha < 0.5.
        Lt128 = "lt128",
        /// Keep alpha >= 0.5.
        Ge128 = "ge128",
    }
}

impl AlphaFunc {
    /// Whether a texel with this alpha (0..=255) is kept; the GLSL side does the same test.
    pub fn passes(self, alpha: u8) -> bool {
        match self {
            AlphaFunc::Gt0 => alpha > 0,
            AlphaFunc::Lt128 => alpha < 128,
            AlphaFunc::Ge128 => alpha >= 128,
        }
    }
    /// Code passed to the shaders.
    pub fn code(self) -> i32 {
        match self {
            AlphaFunc::Gt0 => 1,
            AlphaFunc::Lt128 => 2,
            AlphaFunc::Ge128 => 3,
        }
    }
}

/// Face culling a material asks for (Quake 3's `cull`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Cull {
    /// Draw front faces only.
    #[default]
    Back,
    /// Draw back faces only.
    Front,
    /// Draw both sides (`cull none`, `cull disable`, `cull twosided`).
    None,
}

/// How a surface looks and whether it takes part in shadowing.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    pub name: String,
    /// Index into [`Scene::textures`]; `None` draws white.
    pub texture: Option<usize>,
    pub alpha_test: Option<AlphaFunc>,
    pub cull: Cull,
    /// Blended in Quake 3 (glass, fire): drawn, but neither casts nor receives.
    pub translucent: bool,
    /// Casts shadows (false for sky, nodraw, translucent, nonsolid-and-transparent surfaces).
    pub casts_shadows: bool,
    /// Receives dynamic light (false for sky and fullbright surfaces).
    pub receives_light: bool,
    /// Not drawn at all (nodraw, sky when not rendered).
    pub visible: bool,
}

impl Material {
    pub fn opaque(name: &str, texture: Option<usize>) -> Material {
        Material {
            name: name.to_string(),
            texture,
            alpha_test: None,
            cull: Cull::Back,
            translucent: false,
            casts_shadows: true,
            receives_light: true,
            visible: true,
        }
    }
}

/// Where a surface came from: the static world or a model instance.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SurfaceOwner {
    World,
    Model(usize),
}

/// Where a surface's baked (unlit-pass) light comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BakedLight {
    /// The constant ambient level (built-in scenes, models: paper 2.5).
    #[default]
    Constant,
    /// A lightmap page ([`Surface::lightmap`]).
    Lightmap,
    /// The vertex colours (Quake 3's vertex-lit surfaces).
    Vertex,
}

/// What kind of Quake 3 face a world surface was (built-in geometry counts as `Mesh`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SurfaceKind {
    Polygon,
    Patch,
    Mesh,
    Model,
}

/// A run of triangles with one material: `indices[first_index .. first_index + index_count]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Surface {
    pub first_index: u32,
    pub index_count: u32,
    pub material: usize,
    /// Index into [`Scene::lightmaps`], if the surface has one.
    pub lightmap: Option<usize>,
    pub baked: BakedLight,
    pub owner: SurfaceOwner,
    pub kind: SurfaceKind,
    /// World-space bounds (after the owner's transform).
    pub bounds: Aabb,
    /// Two of its triangles cover some area twice (`geometry::overlap::covers_twice`, as
    /// loaded): its lit pass marks the stencil to add a light once (`lighting.light_once`);
    /// other surfaces are lit without stencil writes, which keeps the early depth test.
    pub overlapping: bool,
}

/// A placed model: its surfaces are stored in model space and drawn with `transform`.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelInstance {
    pub name: String,
    pub transform: Mat4,
    /// Which vertices the model holds: a value no other pose had, taken anew whenever its
    /// vertices change ([`Scene::model_reshaped`]), so that what is built from them (its caster
    /// group, its volumes, the maps it is drawn into, the GPU's copy) is kept by it.
    pub pose: u64,
}

impl ModelInstance {
    pub fn new(name: &str, transform: Mat4) -> ModelInstance {
        ModelInstance {
            name: name.to_string(),
            transform,
            pose: next_revision(),
        }
    }
}

/// Everything to render. Vertices of world surfaces are in world space; model surfaces are in their
/// model's space.
#[derive(Debug, Clone, Default)]
pub struct Scene {
    pub name: String,
    pub vertices: Vec<Vertex>,
    pub indices: Vec<u32>,
    pub surfaces: Vec<Surface>,
    pub materials: Vec<Material>,
    pub textures: Vec<Rgba>,
    pub lightmaps: Vec<Rgba>,
    pub models: Vec<ModelInstance>,
    pub lights: Vec<Light>,
    pub camera: Camera,
    /// Option overrides the scene asks for (`[options]` of a scene file), as a TOML table.
    pub options: toml::Table,
    /// BSP visibility of a Quake 3 world (None for built-in scenes: everything is visible).
    pub world: Option<std::sync::Arc<vis::WorldVis>>,
    /// What moves, and how ([`motion::Motion::pose`] poses the scene at a time).
    pub motion: motion::Motion,
    /// Which geometry this is: a value no other scene's geometry had, taken anew whenever
    /// surfaces are added ([`Scene::push_surface`], [`Scene::add_surface`]). Whatever is built
    /// from the geometry (the planner's caster groups) is kept by it.
    revision: u64,
}

/// The source of [`Scene::revision`]s: unique across scenes, so that a cache keyed by one
/// never takes another scene's geometry for its own.
static REVISIONS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

fn next_revision() -> u64 {
    REVISIONS.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

impl Scene {
    /// Transform that takes a surface's vertices to world space.
    pub fn surface_transform(&self, s: &Surface) -> Mat4 {
        match s.owner {
            SurfaceOwner::World => Mat4::IDENTITY,
            SurfaceOwner::Model(m) => self.models[m].transform,
        }
    }

    /// World-space bounds of everything drawn.
    pub fn bounds(&self) -> Aabb {
        self.surfaces
            .iter()
            .filter(|s| self.materials[s.material].visible)
            .fold(Aabb::EMPTY, |b, s| b.union(&s.bounds))
    }

    /// Appends a surface from vertices given in its owner's space, computing its world bounds.
    pub fn push_surface(
        &mut self,
        vertices: &[Vertex],
        indices: &[u32],
        material: usize,
        owner: SurfaceOwner,
        kind: SurfaceKind,
    ) {
        let base = self.vertices.len() as u32;
        let first_index = self.indices.len() as u32;
        self.vertices.extend_from_slice(vertices);
        self.indices.extend(indices.iter().map(|i| i + base));
        let local = Aabb::from_points(vertices.iter().map(|v| v.pos()));
        let transform = match owner {
            SurfaceOwner::World => Mat4::IDENTITY,
            SurfaceOwner::Model(m) => self.models[m].transform,
        };
        self.surfaces.push(Surface {
            first_index,
            index_count: indices.len() as u32,
            material,
            lightmap: None,
            baked: BakedLight::Constant,
            owner,
            kind,
            bounds: local.transformed(&transform),
            overlapping: crate::geometry::overlap::covers_twice(&local_triangles(
                vertices, indices,
            )),
        });
        self.touch();
    }

    /// World-space triangles of every surface that casts shadows, with the surface index.
    pub fn caster_triangles(&self) -> impl Iterator<Item = ([Vec3; 3], usize)> + '_ {
        self.surfaces.iter().enumerate().flat_map(move |(si, s)| {
            let m = &self.materials[s.material];
            let take = m.casts_shadows && m.visible;
            let t = self.surface_transform(s);
            let range = if take {
                s.first_index as usize..(s.first_index + s.index_count) as usize
            } else {
                0..0
            };
            self.indices[range].chunks_exact(3).map(move |tri| {
                let p = |i: u32| t.transform_point3(self.vertices[i as usize].pos());
                ([p(tri[0]), p(tri[1]), p(tri[2])], si)
            })
        })
    }

    /// An empty scene called `name`.
    pub fn named(name: &str) -> Scene {
        Scene {
            name: name.to_string(),
            ..Scene::default()
        }
    }

    /// The geometry's revision (see the field).
    pub fn revision(&self) -> u64 {
        self.revision
    }

    /// Appends a surface whose world bounds are already set, and takes a new revision.
    pub fn add_surface(&mut self, surface: Surface) {
        self.surfaces.push(surface);
        self.touch();
    }

    /// Takes a new revision: the geometry changed.
    fn touch(&mut self) {
        self.revision = next_revision();
    }

    /// World bounds of surface `i` under its owner's current transform.
    pub fn surface_bounds(&self, i: usize) -> Aabb {
        let s = &self.surfaces[i];
        let t = self.surface_transform(s);
        let range = s.first_index as usize..(s.first_index + s.index_count) as usize;
        Aabb::from_points(
            self.indices[range]
                .iter()
                .map(|&v| t.transform_point3(self.vertices[v as usize].pos())),
        )
    }

    /// Poses the scene at `t` seconds by its own [`motion`](Scene::motion).
    pub fn pose_at(&mut self, t: f64) -> motion::Posed {
        let motion = std::mem::take(&mut self.motion);
        let posed = motion.pose(self, t);
        self.motion = motion;
        posed
    }

    /// Model `m`'s transform changed: its surfaces' bounds follow.
    pub fn model_moved(&mut self, m: usize) {
        for i in 0..self.surfaces.len() {
            if self.surfaces[i].owner == SurfaceOwner::Model(m) {
                self.surfaces[i].bounds = self.surface_bounds(i);
            }
        }
    }

    /// Model `m`'s vertices changed: its bounds follow and it takes a new pose (see
    /// [`ModelInstance::pose`]), and so do its copies, which share its vertices.
    pub fn model_reshaped(&mut self, m: usize) {
        let runs: Vec<u32> = self
            .surfaces
            .iter()
            .filter(|s| s.owner == SurfaceOwner::Model(m))
            .map(|s| s.first_index)
            .collect();
        let mut sharing: Vec<usize> = self
            .surfaces
            .iter()
            .filter_map(|s| match s.owner {
                SurfaceOwner::Model(o) if runs.contains(&s.first_index) => Some(o),
                _ => None,
            })
            .collect();
        sharing.sort_unstable();
        sharing.dedup();
        for o in sharing {
            self.model_moved(o);
            self.models[o].pose = next_revision();
        }
    }

    /// Number of triangles drawn.
    pub fn triangle_count(&self) -> usize {
        self.surfaces
            .iter()
            .map(|s| s.index_count as usize / 3)
            .sum()
    }
}

/// The triangles of one surface's `indices` into its own `vertices`.
fn local_triangles(vertices: &[Vertex], indices: &[u32]) -> Vec<[Vec3; 3]> {
    indices
        .chunks_exact(3)
        .filter(|t| t.iter().all(|&i| (i as usize) < vertices.len()))
        .map(|t| [0, 1, 2].map(|k| vertices[t[k] as usize].pos()))
        .collect()
}
