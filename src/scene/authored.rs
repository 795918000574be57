//! Geometry written directly in scene files (`[[shape]]`): boxes, quads, spheres, tori,
//! cylinders and raw triangles, with a solid colour or an alpha-tested grate texture. The hard
//! cases under `assets/hard/` are built from these.
//!
//! ```toml
//! [[shape]]
//! kind = "box"                 # box | quad | sphere | torus | cylinder | triangles
//! min = [-10, -10, 0]
//! max = [10, 10, 20]
//! color = [0.8, 0.5, 0.2]      # or grate = { cells = 4, bar = 4 } (alpha-tested)
//! two_sided = false
//! casts = true
//! copies = { count = 300, offset = [0, 0, 0.5], grow = 0.01 }   # repeated, each scaled 1 + k grow
//! ```

use super::builtin::grate_image;
use super::shapes::{MeshData, cuboid, cylinder, sphere, torus};
use super::{AlphaFunc, Cull, Material, Scene, SurfaceKind, SurfaceOwner, Vertex};
use crate::images::Rgba;
use glam::Vec3;
use serde::Deserialize;

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum ShapeKind {
    Box,
    Quad,
    Sphere,
    Torus,
    Cylinder,
    Triangles,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GrateSection {
    pub cells: u32,
    pub bar: u32,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CopiesSection {
    pub count: u32,
    pub offset: [f32; 3],
    /// Copy k is scaled by 1 + k·grow about the shape's centre.
    #[serde(default)]
    pub grow: f32,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShapeSection {
    pub kind: ShapeKind,
    pub name: Option<String>,
    pub min: Option<[f32; 3]>,
    pub max: Option<[f32; 3]>,
    /// A quad's corners, counter-clockwise seen from its front.
    pub corners: Option<[[f32; 3]; 4]>,
    /// Raw triangles, counter-clockwise seen from their front.
    pub triangles: Option<Vec<[[f32; 3]; 3]>>,
    pub center: Option<[f32; 3]>,
    pub radius: Option<f32>,
    /// Torus tube radius.
    pub minor: Option<f32>,
    /// Torus tilt about +X, degrees.
    pub tilt: Option<f32>,
    pub height: Option<f32>,
    pub segments: Option<u32>,
    pub rings: Option<u32>,
    pub color: Option<[f32; 3]>,
    pub grate: Option<GrateSection>,
    #[serde(default)]
    pub two_sided: bool,
    #[serde(default = "yes")]
    pub casts: bool,
    pub copies: Option<CopiesSection>,
}

fn yes() -> bool {
    true
}

/// Most copies of one shape, and most segments of a round one.
pub const MAX_COPIES: u32 = 10_000;
pub const MAX_SEGMENTS: u32 = 512;

fn need<T: Copy>(v: Option<T>, what: &str, name: &str) -> Result<T, String> {
    v.ok_or_else(|| format!("[[shape]] {name}: missing `{what}`"))
}

fn finite(v: &[f32], name: &str) -> Result<(), String> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(format!("[[shape]] {name}: numbers must be finite"))
    }
}

impl ShapeSection {
    fn mesh(&self, name: &str) -> Result<MeshData, String> {
        let v3 = |a: [f32; 3]| Vec3::from_array(a);
        let segments = self.segments.unwrap_or(32).clamp(3, MAX_SEGMENTS);
        let rings = self.rings.unwrap_or(16).clamp(2, MAX_SEGMENTS);
        let m = match self.kind {
            ShapeKind::Box => {
                let (a, b) = (need(self.min, "min", name)?, need(self.max, "max", name)?);
                finite(&[a, b].concat(), name)?;
                cuboid(v3(a), v3(b), 32.0)
            }
            ShapeKind::Quad => {
                let c = need(self.corners, "corners", name)?;
                finite(&c.concat(), name)?;
                let mut m = MeshData::default();
                m.quad(v3(c[0]), v3(c[1]), v3(c[2]), v3(c[3]), [1.0, 1.0]);
                m
            }
            ShapeKind::Sphere => {
                let (c, r) = (
                    need(self.center, "center", name)?,
                    need(self.radius, "radius", name)?,
                );
                finite(&[c[0], c[1], c[2], r], name)?;
                sphere(v3(c), r, segments, rings)
            }
            ShapeKind::Torus => {
                let (c, r) = (
                    need(self.center, "center", name)?,
                    need(self.radius, "radius", name)?,
                );
                let minor = need(self.minor, "minor", name)?;
                let tilt = self.tilt.unwrap_or(0.0);
                finite(&[c[0], c[1], c[2], r, minor, tilt], name)?;
                torus(v3(c), r, minor, segments, rings, tilt)
            }
            ShapeKind::Cylinder => {
                let (c, r) = (
                    need(self.center, "center", name)?,
                    need(self.radius, "radius", name)?,
                );
                let h = need(self.height, "height", name)?;
                finite(&[c[0], c[1], c[2], r, h], name)?;
                cylinder(v3(c), r, h, segments)
            }
            ShapeKind::Triangles => {
                let tris = self
                    .triangles
                    .as_ref()
                    .ok_or_else(|| format!("[[shape]] {name}: missing `triangles`"))?;
                let mut m = MeshData::default();
                for t in tris {
                    finite(&t.concat(), name)?;
                    let [a, b, c] = t.map(v3);
                    let n = (b - a).cross(c - a).normalize_or(Vec3::Z);
                    let base = m.vertices.len() as u32;
                    for p in [a, b, c] {
                        m.vertices.push(Vertex::new(p, n, [0.0, 0.0]));
                    }
                    m.indices.extend_from_slice(&[base, base + 1, base + 2]);
                }
                m
            }
        };
        Ok(m)
    }

    fn material(&self, name: &str, scene: &mut Scene) -> Material {
        let image = match (&self.grate, self.color) {
            (Some(g), _) => grate_image(64, g.cells.clamp(1, 32), g.bar.clamp(1, 32)),
            (None, Some(c)) => Rgba::solid([
                (c[0].clamp(0.0, 1.0) * 255.0) as u8,
                (c[1].clamp(0.0, 1.0) * 255.0) as u8,
                (c[2].clamp(0.0, 1.0) * 255.0) as u8,
                255,
            ]),
            (None, None) => Rgba::solid([200, 200, 200, 255]),
        };
        scene.textures.push(image);
        let mut m = Material::opaque(name, Some(scene.textures.len() - 1));
        if self.grate.is_some() {
            m.alpha_test = Some(AlphaFunc::Ge128);
        }
        if self.two_sided {
            m.cull = Cull::None;
        }
        m.casts_shadows = self.casts;
        m
    }

    /// Adds the shape (and its copies) to `scene` as world geometry.
    pub fn add_to(&self, index: usize, scene: &mut Scene) -> Result<(), String> {
        let name = self.name.clone().unwrap_or_else(|| format!("shape{index}"));
        let mesh = self.mesh(&name)?;
        let material = self.material(&name, scene);
        scene.materials.push(material);
        let m = scene.materials.len() - 1;
        let copies = self.copies.as_ref();
        let count = copies.map_or(1, |c| c.count);
        if count == 0 || count > MAX_COPIES {
            return Err(format!("[[shape]] {name}: copies must be 1..={MAX_COPIES}"));
        }
        let center = mesh.vertices.iter().fold(Vec3::ZERO, |s, v| s + v.pos())
            / mesh.vertices.len().max(1) as f32;
        for k in 0..count {
            let (offset, scale) = match copies {
                Some(c) => {
                    finite(&[c.offset[0], c.offset[1], c.offset[2], c.grow], &name)?;
                    (
                        Vec3::from_array(c.offset) * k as f32,
                        1.0 + c.grow * k as f32,
                    )
                }
                None => (Vec3::ZERO, 1.0),
            };
            let vertices: Vec<Vertex> = mesh
                .vertices
                .iter()
                .map(|v| Vertex {
                    position: (center + (v.pos() - center) * scale + offset).to_array(),
                    ..*v
                })
                .collect();
            scene.push_surface(
                &vertices,
                &mesh.indices,
                m,
                SurfaceOwner::World,
                SurfaceKind::Mesh,
            );
        }
        Ok(())
    }
}
