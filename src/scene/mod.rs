//! The scene: everything a frame needs, on the CPU and free of GL.
//!
//! Loaders (the built-in scene, Quake 3 maps and models, scene files) produce a [`Scene`]; the GL
//! layer uploads it, the exact reference ray-casts it, the shadow-volume code builds edges from it.
//! World space is Quake 3's: Z up, units of about an inch.

pub mod authored;
pub mod builtin;
pub mod camera;
pub mod file;
pub mod light;
pub mod path;
pub mod shapes;

pub use camera::Camera;
pub use light::{Light, LightKind};

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

/// Axis-aligned bounds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }
    pub fn extend(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }
    /// Whether the boxes overlap (touching counts); empty boxes meet nothing.
    pub fn intersects(&self, o: &Aabb) -> bool {
        !self.is_empty()
            && !o.is_empty()
            && self.min.cmple(o.max).all()
            && o.min.cmple(self.max).all()
    }

    /// The overlap of two boxes (empty when they do not meet).
    pub fn intersection(&self, o: &Aabb) -> Aabb {
        Aabb {
            min: self.min.max(o.min),
            max: self.max.min(o.max),
        }
    }

    /// The corner furthest along a direction whose components are non-negative where
    /// `positive` is set (a plane's "positive vertex": the box reaches the plane's inner side
    /// iff this corner does).
    pub fn furthest_corner(&self, positive: glam::BVec3) -> Vec3 {
        Vec3::select(positive, self.max, self.min)
    }

    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }
    pub fn from_points(points: impl IntoIterator<Item = Vec3>) -> Aabb {
        let mut b = Aabb::EMPTY;
        for p in points {
            b.extend(p);
        }
        b
    }
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }
    pub fn corners(&self) -> [Vec3; 8] {
        let (a, b) = (self.min, self.max);
        [
            Vec3::new(a.x, a.y, a.z),
            Vec3::new(b.x, a.y, a.z),
            Vec3::new(a.x, b.y, a.z),
            Vec3::new(b.x, b.y, a.z),
            Vec3::new(a.x, a.y, b.z),
            Vec3::new(b.x, a.y, b.z),
            Vec3::new(a.x, b.y, b.z),
            Vec3::new(b.x, b.y, b.z),
        ]
    }
    pub fn transformed(&self, m: &Mat4) -> Aabb {
        if self.is_empty() {
            return *self;
        }
        Aabb::from_points(self.corners().iter().map(|c| m.transform_point3(*c)))
    }
}

/// An RGBA8 image held on the CPU (textures, lightmaps).
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    /// Row-major RGBA8, first row at the top (v = 0).
    pub rgba: Vec<u8>,
}

impl Image {
    pub fn solid(rgba: [u8; 4]) -> Image {
        Image {
            width: 1,
            height: 1,
            rgba: rgba.to_vec(),
        }
    }
    /// The texel at texture coordinates (u, v), wrapped, nearest: what the exact reference reads
    /// for alpha-tested surfaces.
    pub fn sample_nearest(&self, u: f32, v: f32) -> [u8; 4] {
        let fx = u - u.floor();
        let fy = v - v.floor();
        let x = ((fx * self.width as f32) as u32).min(self.width - 1);
        let y = ((fy * self.height as f32) as u32).min(self.height - 1);
        let i = ((y * self.width + x) * 4) as usize;
        [
            self.rgba[i],
            self.rgba[i + 1],
            self.rgba[i + 2],
            self.rgba[i + 3],
        ]
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
}

/// A placed model: its surfaces are stored in model space and drawn with `transform`.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelInstance {
    pub name: String,
    pub transform: Mat4,
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
    pub textures: Vec<Image>,
    pub lightmaps: Vec<Image>,
    pub models: Vec<ModelInstance>,
    pub lights: Vec<Light>,
    pub camera: Camera,
    /// Option overrides the scene asks for (`[options]` of a scene file), as a TOML table.
    pub options: toml::Table,
    /// BSP visibility of a Quake 3 world (None for built-in scenes: everything is visible).
    pub world: Option<std::sync::Arc<crate::q3::vis::WorldVis>>,
    /// Shadow-volume connectivity of the casters, built on first use (see [`Scene::caster_groups`]).
    pub caster_cache: std::sync::OnceLock<std::sync::Arc<crate::shadow::volume::CasterGroups>>,
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
        });
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

    /// Welded casters with their edges and components, built once (model transforms are applied
    /// later, so moving a model keeps them valid; adding surfaces must call
    /// [`Scene::invalidate_casters`]).
    pub fn caster_groups(&self) -> std::sync::Arc<crate::shadow::volume::CasterGroups> {
        self.caster_cache
            .get_or_init(|| std::sync::Arc::new(crate::shadow::volume::CasterGroups::build(self)))
            .clone()
    }

    pub fn invalidate_casters(&mut self) {
        self.caster_cache = std::sync::OnceLock::new();
    }

    /// Number of triangles drawn.
    pub fn triangle_count(&self) -> usize {
        self.surfaces
            .iter()
            .map(|s| s.index_count as usize / 3)
            .sum()
    }
}
