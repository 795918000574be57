//! A Quake 3 map as the paper renders it (section 2): the static world (model 0; brush models on
//! request), polygons and meshes from their index lists, Bezier patches tessellated once,
//! billboards ignored, lightmaps brightened the way Quake 3 shows them.

use super::bsp::{self, Bsp, BspError, DrawVert, SurfaceType};
use super::builder::SceneBuilder;
use super::entities::{self, Entity, EntityError, SpawnPoint};
use super::patch::{self, PatchError};
use super::pk3::{Vfs, VfsError};
use crate::geometry::overlap::overlapping_triangles;
use crate::images::Rgba;
use crate::options::Q3Options;
use crate::scene::vis::{BspTree, WorldVis};
use crate::scene::{BakedLight, SurfaceKind, SurfaceOwner, Vertex};
use crate::shadow::edges::{Connectivity, EdgeCounts};
use glam::Vec3;
use serde::Serialize;
use std::sync::Arc;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum MapError {
    #[error(transparent)]
    Vfs(#[from] VfsError),
    #[error("{path}: {source}")]
    Bsp { path: String, source: BspError },
    #[error("{path}: surface {surface}: {source}")]
    Patch {
        path: String,
        surface: usize,
        source: PatchError,
    },
    #[error("{path}: entity lump: {source}")]
    Entities { path: String, source: EntityError },
}

#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct FaceCounts {
    pub polygon: usize,
    pub patch: usize,
    pub mesh: usize,
    pub billboard: usize,
}

#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct TriangleCounts {
    pub polygon: usize,
    pub mesh: usize,
    pub patch: usize,
    pub total: usize,
}

#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct VertexCounts {
    /// Vertices of every face after tessellation, as stored.
    pub raw: usize,
    /// Distinct positions among them.
    pub welded: usize,
}

/// What `shadowlab inspect` reports for a map: every face of the loaded models (world model 0
/// unless brush models are on), drawn or not, after tessellation.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct MapCounts {
    pub map: String,
    pub faces: FaceCounts,
    pub triangles: TriangleCounts,
    pub vertices: VertexCounts,
    /// Shaders the loaded faces use.
    pub shaders: usize,
    pub alpha_tested_shaders: usize,
    pub lightmaps: usize,
    pub leaves: usize,
    pub clusters: usize,
    /// Edges of all those triangles by number of triangles on them.
    pub edges: EdgeCounts,
    /// Triangles drawn (faces whose shader is visible).
    pub drawn_triangles: usize,
    /// Triangles that cast shadows.
    pub caster_triangles: usize,
    /// Drawn planar surfaces whose own triangles overlap, and those triangles: an additive lit
    /// pass adds a light twice where they do (`geometry::overlap`).
    pub overlapping_surfaces: usize,
    pub overlapping_triangles: usize,
    pub patch_level: u32,
}

/// A map loaded into a scene builder, with what else the map file holds.
pub struct MapInfo {
    pub counts: MapCounts,
    pub entities: Vec<Entity>,
    pub spawns: Vec<SpawnPoint>,
    pub warnings: Vec<String>,
}

/// Quake 3's R_ColorShiftLightingBytes: scale by 2^shift, and where a channel would pass 255,
/// scale all three down together so the hue survives.
pub fn shift_color(rgb: [u8; 3], shift: u32) -> [u8; 3] {
    let s = 1u32 << shift.min(8);
    let v = rgb.map(|c| c as u32 * s);
    let max = v[0].max(v[1]).max(v[2]);
    if max > 255 {
        v.map(|c| (c * 255 / max) as u8)
    } else {
        v.map(|c| c as u8)
    }
}

fn lightmap_image(page: &[u8], shift: u32) -> Rgba {
    let mut rgba = Vec::with_capacity(bsp::LIGHTMAP_SIDE * bsp::LIGHTMAP_SIDE * 4);
    for px in page.chunks_exact(3) {
        let c = shift_color([px[0], px[1], px[2]], shift);
        rgba.extend_from_slice(&[c[0], c[1], c[2], 255]);
    }
    Rgba {
        width: bsp::LIGHTMAP_SIDE as u32,
        height: bsp::LIGHTMAP_SIDE as u32,
        data: rgba,
    }
}

fn finite_or(v: f32, default: f32) -> f32 {
    if v.is_finite() { v } else { default }
}

fn vertex_from(v: &DrawVert, shift: u32) -> Vertex {
    let n = Vec3::from_array(v.normal.map(|x| finite_or(x, 0.0)));
    let c = shift_color([v.color[0], v.color[1], v.color[2]], shift);
    Vertex {
        position: v.position,
        normal: n.normalize_or(Vec3::Z).to_array(),
        uv: v.st.map(|x| finite_or(x, 0.0)),
        lightmap_uv: v.lightmap.map(|x| finite_or(x, 0.0)),
        color: [c[0], c[1], c[2], v.color[3]],
    }
}

/// Loads `bsp_path` from the VFS into `builder` as the world.
pub fn load_map(
    builder: &mut SceneBuilder,
    vfs: &Vfs,
    bsp_path: &str,
    q3: &Q3Options,
) -> Result<MapInfo, MapError> {
    let data = vfs.read(bsp_path)?;
    let bsp = bsp::parse(&data).map_err(|source| MapError::Bsp {
        path: bsp_path.to_string(),
        source,
    })?;
    add_world(builder, &bsp, bsp_path, q3)
}

/// Adds a parsed map's world to `builder`.
pub fn add_world(
    builder: &mut SceneBuilder,
    bsp: &Bsp,
    bsp_path: &str,
    q3: &Q3Options,
) -> Result<MapInfo, MapError> {
    let shift = q3.map_overbright_bits.saturating_sub(q3.overbright_bits);
    let mut faces = Faces {
        lightmap_base: builder.scene.lightmaps.len(),
        surface_map: vec![None; bsp.surfaces.len()],
        shader_material: vec![None; bsp.shaders.len()],
        triangles: Vec::new(),
    };
    builder
        .scene
        .lightmaps
        .extend(bsp.lightmaps.iter().map(|p| lightmap_image(p, shift)));

    let model_range = if q3.brush_models {
        0..bsp.models.len()
    } else {
        0..bsp.models.len().min(1)
    };
    let mut counts = MapCounts {
        map: map_name(bsp_path),
        lightmaps: bsp.lightmaps.len(),
        leaves: bsp.leafs.len(),
        clusters: bsp.vis.as_ref().map_or(0, |v| v.num_clusters as usize),
        patch_level: q3.patch_level,
        ..MapCounts::default()
    };
    for model in &bsp.models[model_range] {
        let range =
            model.first_surface as usize..(model.first_surface + model.num_surfaces) as usize;
        for si in range {
            let geometry = face_geometry(bsp, si, shift, q3, bsp_path, &mut counts)?;
            if let Some(g) = geometry {
                faces.add(builder, bsp, si, g, &mut counts);
            }
        }
    }
    count_totals(&mut counts, builder, &faces);

    builder.scene.world = Some(Arc::new(WorldVis::new(
        BspTree {
            planes: bsp.planes.clone(),
            nodes: bsp.nodes.clone(),
            leafs: bsp.leafs.clone(),
            leaf_surfaces: bsp.leaf_surfaces.clone(),
            vis: bsp.vis.clone(),
        },
        faces.surface_map,
    )));
    let entities =
        entities::parse_entities(&bsp.entities).map_err(|source| MapError::Entities {
            path: bsp_path.to_string(),
            source,
        })?;
    let spawns = entities::spawn_points(&entities);
    Ok(MapInfo {
        counts,
        entities,
        spawns,
        warnings: bsp.warnings.clone(),
    })
}

/// One face's triangles as the scene stores them.
struct FaceGeometry {
    vertices: Vec<Vertex>,
    /// Counter-clockwise.
    indices: Vec<u32>,
    kind: SurfaceKind,
}

/// The geometry of BSP surface `si`, counted in `counts.faces` and `counts.triangles`; None for
/// billboards (flares), which are counted and not loaded.
fn face_geometry(
    bsp: &Bsp,
    si: usize,
    shift: u32,
    q3: &Q3Options,
    bsp_path: &str,
    counts: &mut MapCounts,
) -> Result<Option<FaceGeometry>, MapError> {
    let s = &bsp.surfaces[si];
    let verts = || &bsp.vertices[s.first_vert as usize..(s.first_vert + s.num_verts) as usize];
    let (vertices, indices, kind) =
        match s.kind {
            SurfaceType::Flare => {
                counts.faces.billboard += 1;
                return Ok(None);
            }
            SurfaceType::Planar | SurfaceType::TriangleSoup => {
                let vertices: Vec<Vertex> = verts().iter().map(|v| vertex_from(v, shift)).collect();
                // Quake 3 winds front faces clockwise; shadowlab's are counter-clockwise.
                let mut indices = Vec::with_capacity(s.num_indexes as usize);
                let idx =
                    &bsp.indexes[s.first_index as usize..(s.first_index + s.num_indexes) as usize];
                for t in idx.chunks_exact(3) {
                    indices.extend_from_slice(&[t[0], t[2], t[1]]);
                }
                let kind = if s.kind == SurfaceType::Planar {
                    counts.faces.polygon += 1;
                    counts.triangles.polygon += indices.len() / 3;
                    SurfaceKind::Polygon
                } else {
                    counts.faces.mesh += 1;
                    counts.triangles.mesh += indices.len() / 3;
                    SurfaceKind::Mesh
                };
                (vertices, indices, kind)
            }
            SurfaceType::Patch => {
                let (vertices, indices) = patch_geometry(s, verts(), shift, q3.patch_level)
                    .map_err(|source| MapError::Patch {
                        path: bsp_path.to_string(),
                        surface: si,
                        source,
                    })?;
                counts.faces.patch += 1;
                counts.triangles.patch += indices.len() / 3;
                (vertices, indices, SurfaceKind::Patch)
            }
        };
    Ok(Some(FaceGeometry {
        vertices,
        indices,
        kind,
    }))
}

/// A patch surface tessellated at `level` from its `control` points.
fn patch_geometry(
    s: &bsp::Surface,
    control: &[DrawVert],
    shift: u32,
    level: u32,
) -> Result<(Vec<Vertex>, Vec<u32>), PatchError> {
    let t = patch::tessellate(
        control,
        s.patch_width as usize,
        s.patch_height as usize,
        level,
    )?;
    // Patch vertex colours: the first control point's (patches are lightmapped).
    let color = shift_color(
        [
            control[0].color[0],
            control[0].color[1],
            control[0].color[2],
        ],
        shift,
    );
    let vertices = t
        .vertices
        .iter()
        .map(|v| Vertex {
            position: v.position,
            normal: v.normal,
            uv: v.st,
            lightmap_uv: v.lightmap,
            color: [color[0], color[1], color[2], 255],
        })
        .collect();
    Ok((vertices, t.indices))
}

/// The world's faces as they are added: what the counts and the BSP visibility need of them.
struct Faces {
    /// Index of the map's first lightmap among the scene's.
    lightmap_base: usize,
    /// The scene surface of each BSP surface that is drawn.
    surface_map: Vec<Option<u32>>,
    /// The material of each BSP shader a loaded face uses.
    shader_material: Vec<Option<usize>>,
    /// Every loaded triangle, drawn or not, for the edge and welded-vertex counts.
    triangles: Vec<[Vec3; 3]>,
}

impl Faces {
    /// Adds BSP surface `si` with its geometry `g`: counted always, pushed to the scene when its
    /// material is visible.
    fn add(
        &mut self,
        builder: &mut SceneBuilder,
        bsp: &Bsp,
        si: usize,
        g: FaceGeometry,
        counts: &mut MapCounts,
    ) {
        let s = &bsp.surfaces[si];
        counts.vertices.raw += g.vertices.len();
        for t in g.indices.chunks_exact(3) {
            self.triangles
                .push([0, 1, 2].map(|k| Vec3::from_array(g.vertices[t[k] as usize].position)));
        }
        let shader = &bsp.shaders[s.shader as usize];
        let material = builder.material(
            &shader.name,
            Some((shader.surface_flags, shader.content_flags)),
        );
        self.shader_material[s.shader as usize] = Some(material);
        let m = &builder.scene.materials[material];
        if !m.visible {
            return;
        }
        counts.drawn_triangles += g.indices.len() / 3;
        if g.kind == SurfaceKind::Polygon {
            let first = self.triangles.len() - g.indices.len() / 3;
            let overlapping = overlapping_triangles(&self.triangles[first..]);
            counts.overlapping_surfaces += (overlapping > 0) as usize;
            counts.overlapping_triangles += overlapping;
        }
        if m.casts_shadows {
            counts.caster_triangles += g.indices.len() / 3;
        }
        builder.scene.push_surface(
            &g.vertices,
            &g.indices,
            material,
            SurfaceOwner::World,
            g.kind,
        );
        let surface = builder.scene.surfaces.last_mut().expect("just pushed");
        surface.lightmap = s.lightmap_index().map(|l| l + self.lightmap_base);
        surface.baked = if s.lightmap_index().is_some() {
            BakedLight::Lightmap
        } else {
            BakedLight::Vertex
        };
        self.surface_map[si] = Some(builder.scene.surfaces.len() as u32 - 1);
    }
}

/// The counts that sum over every loaded face: triangle total, shaders, welded vertices, edges.
fn count_totals(counts: &mut MapCounts, builder: &SceneBuilder, faces: &Faces) {
    counts.triangles.total =
        counts.triangles.polygon + counts.triangles.mesh + counts.triangles.patch;
    let used: Vec<usize> = faces.shader_material.iter().flatten().copied().collect();
    counts.shaders = used.len();
    counts.alpha_tested_shaders = used
        .iter()
        .filter(|&&m| builder.scene.materials[m].alpha_test.is_some())
        .count();
    let connectivity = Connectivity::build(faces.triangles.iter().copied());
    counts.vertices.welded = connectivity.positions.len();
    counts.edges = connectivity.counts();
}

/// `maps/oa_dm1.bsp` → `oa_dm1`.
pub fn map_name(path: &str) -> String {
    let file = path.rsplit(['/', '\\']).next().unwrap_or(path);
    file.strip_suffix(".bsp")
        .or_else(|| file.strip_suffix(".BSP"))
        .unwrap_or(file)
        .to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn color_shift_preserves_hue_when_clamping() {
        assert_eq!(shift_color([10, 20, 30], 1), [20, 40, 60]);
        assert_eq!(shift_color([100, 200, 50], 1), [127, 255, 63]);
        assert_eq!(shift_color([255, 255, 255], 2), [255, 255, 255]);
        assert_eq!(shift_color([7, 8, 9], 0), [7, 8, 9]);
    }

    #[test]
    fn map_names() {
        assert_eq!(map_name("maps/oa_dm1.bsp"), "oa_dm1");
        assert_eq!(map_name("oa_dm3"), "oa_dm3");
    }
}
