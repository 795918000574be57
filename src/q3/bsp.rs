//! IBSP version 46, the Quake 3 map format: 17 lumps, every one validated.
//!
//! Validation covers the header, every lump's placement (inside the file, a multiple of its record
//! size) and every index one record holds into another lump, so later stages can index without
//! checks. Errors name the lump, the record and the offending value. Nothing is allocated beyond
//! what the lump sizes imply, so a hostile header cannot request more memory than the file holds.
//! Node children must come after their parent (q3map writes nodes in pre-order), which makes every
//! tree walk finite.
//!
//! One defect of shipped maps is repaired instead of rejected and reported in `Bsp::warnings`:
//! a surface's fog number outside the fogs lump (shadowlab draws no fog).

use super::bytes::{array_at, f32_at, i32_at, ivec3_at, name_at, vec3_at};
pub use crate::scene::vis::{Leaf, Node, Plane, Vis};
use thiserror::Error;

pub const LUMP_NAMES: [&str; 17] = [
    "entities",
    "shaders",
    "planes",
    "nodes",
    "leafs",
    "leafsurfaces",
    "leafbrushes",
    "models",
    "brushes",
    "brushsides",
    "drawverts",
    "drawindexes",
    "fogs",
    "surfaces",
    "lightmaps",
    "lightgrid",
    "visibility",
];
const RECORD_SIZES: [usize; 17] = [
    1, 72, 16, 36, 48, 4, 4, 40, 12, 8, 44, 4, 72, 104, 49152, 8, 1,
];
const HEADER_BYTES: usize = 8 + 17 * 8;
/// Side of a lightmap page in texels.
pub const LIGHTMAP_SIDE: usize = 128;

#[derive(Debug, Error, PartialEq)]
pub enum BspError {
    #[error("file is {0} bytes, smaller than the {HEADER_BYTES}-byte header")]
    TooSmall(usize),
    #[error("magic is {0:?}, not \"IBSP\"")]
    BadMagic([u8; 4]),
    #[error("version {0}, only 46 (Quake 3) is supported")]
    BadVersion(i32),
    #[error("lump {lump}: offset {offset} length {length} is outside the {file_len}-byte file")]
    LumpOutOfFile {
        lump: &'static str,
        offset: i64,
        length: i64,
        file_len: usize,
    },
    #[error("lump {lump}: length {length} is not a multiple of its {record}-byte record")]
    LumpNotMultiple {
        lump: &'static str,
        length: usize,
        record: usize,
    },
    #[error("lump {lump}, record {record}: {field} = {value} is out of range (0..{limit})")]
    IndexOutOfRange {
        lump: &'static str,
        record: usize,
        field: &'static str,
        value: i64,
        limit: i64,
    },
    #[error("lump {lump}, record {record}: {field} = {value} is invalid: {why}")]
    Invalid {
        lump: &'static str,
        record: usize,
        field: &'static str,
        value: i64,
        why: &'static str,
    },
    #[error("lump {lump}, record {record}: {field} is not a finite number")]
    NotFinite {
        lump: &'static str,
        record: usize,
        field: &'static str,
    },
}

#[derive(Debug, Clone, PartialEq)]
pub struct BspShader {
    pub name: String,
    pub surface_flags: i32,
    pub content_flags: i32,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Model {
    pub mins: [f32; 3],
    pub maxs: [f32; 3],
    pub first_surface: u32,
    pub num_surfaces: u32,
    pub first_brush: u32,
    pub num_brushes: u32,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Brush {
    pub first_side: u32,
    pub num_sides: u32,
    pub shader: u32,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BrushSide {
    pub plane: u32,
    pub shader: u32,
}

#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DrawVert {
    pub position: [f32; 3],
    pub st: [f32; 2],
    pub lightmap: [f32; 2],
    pub normal: [f32; 3],
    pub color: [u8; 4],
}

#[derive(Debug, Clone, PartialEq)]
pub struct Fog {
    pub name: String,
    pub brush: i32,
    pub visible_side: i32,
}

/// Quake 3's four face types.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SurfaceType {
    Planar,
    Patch,
    TriangleSoup,
    Flare,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Surface {
    pub shader: u32,
    /// -1: no fog.
    pub fog: i32,
    pub kind: SurfaceType,
    pub first_vert: u32,
    pub num_verts: u32,
    pub first_index: u32,
    pub num_indexes: u32,
    /// < 0: no lightmap (vertex lit or fullbright).
    pub lightmap: i32,
    pub lightmap_origin: [f32; 3],
    pub lightmap_vecs: [[f32; 3]; 3],
    pub patch_width: u32,
    pub patch_height: u32,
}

impl Surface {
    pub fn lightmap_index(&self) -> Option<usize> {
        (self.lightmap >= 0).then_some(self.lightmap as usize)
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct Bsp {
    pub entities: String,
    pub shaders: Vec<BspShader>,
    pub planes: Vec<Plane>,
    pub nodes: Vec<Node>,
    pub leafs: Vec<Leaf>,
    pub leaf_surfaces: Vec<u32>,
    pub leaf_brushes: Vec<u32>,
    pub models: Vec<Model>,
    pub brushes: Vec<Brush>,
    pub brush_sides: Vec<BrushSide>,
    pub vertices: Vec<DrawVert>,
    pub indexes: Vec<u32>,
    pub fogs: Vec<Fog>,
    pub surfaces: Vec<Surface>,
    /// RGB pages of LIGHTMAP_SIDE² texels.
    pub lightmaps: Vec<Vec<u8>>,
    pub light_grid: Vec<[u8; 8]>,
    /// Absent when the map was compiled without vis.
    pub vis: Option<Vis>,
    /// Defects repaired instead of rejected, each a documented fallback (see [`parse`]).
    pub warnings: Vec<String>,
}

/// A lump's bytes and its record count.
struct Lump<'a> {
    id: usize,
    data: &'a [u8],
}

impl<'a> Lump<'a> {
    fn count(&self) -> usize {
        self.data.len() / RECORD_SIZES[self.id]
    }
    fn record(&self, i: usize) -> &'a [u8] {
        let r = RECORD_SIZES[self.id];
        &self.data[i * r..(i + 1) * r]
    }
    /// Parses every record with `f`.
    fn parse<T>(
        &self,
        mut f: impl FnMut(usize, &[u8]) -> Result<T, BspError>,
    ) -> Result<Vec<T>, BspError> {
        let mut v = Vec::with_capacity(self.count());
        for i in 0..self.count() {
            v.push(f(i, self.record(i))?);
        }
        Ok(v)
    }
}

fn range_err(
    lump: &'static str,
    record: usize,
    field: &'static str,
    value: i64,
    limit: usize,
) -> BspError {
    BspError::IndexOutOfRange {
        lump,
        record,
        field,
        value,
        limit: limit as i64,
    }
}

/// `value` in 0..limit.
fn index(
    lump: &'static str,
    record: usize,
    field: &'static str,
    value: i32,
    limit: usize,
) -> Result<u32, BspError> {
    if value < 0 || value as i64 >= limit as i64 {
        return Err(range_err(lump, record, field, value as i64, limit));
    }
    Ok(value as u32)
}

/// `first..first + count` inside 0..limit.
fn span(
    lump: &'static str,
    record: usize,
    field: &'static str,
    first: i32,
    count: i32,
    limit: usize,
) -> Result<(u32, u32), BspError> {
    if first < 0 || first as i64 > limit as i64 {
        return Err(range_err(lump, record, field, first as i64, limit + 1));
    }
    if count < 0 || first as i64 + count as i64 > limit as i64 {
        return Err(BspError::IndexOutOfRange {
            lump,
            record,
            field,
            value: first as i64 + count as i64,
            limit: limit as i64 + 1,
        });
    }
    Ok((first as u32, count as u32))
}

fn finite(
    lump: &'static str,
    record: usize,
    field: &'static str,
    v: &[f32],
) -> Result<(), BspError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(BspError::NotFinite {
            lump,
            record,
            field,
        })
    }
}

// Lump ids, in file order (see `LUMP_NAMES`).
const ENTITIES: usize = 0;
const SHADERS: usize = 1;
const PLANES: usize = 2;
const NODES: usize = 3;
const LEAFS: usize = 4;
const LEAF_SURFACES: usize = 5;
const LEAF_BRUSHES: usize = 6;
const MODELS: usize = 7;
const BRUSHES: usize = 8;
const BRUSH_SIDES: usize = 9;
const DRAW_VERTS: usize = 10;
const DRAW_INDEXES: usize = 11;
const FOGS: usize = 12;
const SURFACES: usize = 13;
const LIGHTMAPS: usize = 14;
const LIGHT_GRID: usize = 15;
const VISIBILITY: usize = 16;

/// Parses and validates a whole IBSP v46 file.
pub fn parse(file: &[u8]) -> Result<Bsp, BspError> {
    let l = lumps(file)?;
    let entities = name_at(l[ENTITIES].data, 0, l[ENTITIES].data.len());
    let shaders = shaders(&l[SHADERS]);
    let planes = planes(&l[PLANES])?;
    let nodes = nodes(&l)?;
    // Visibility comes before leafs so their clusters can be checked against it.
    let vis = vis(l[VISIBILITY].data)?;
    let leafs = leafs(&l, vis.as_ref().map(|v| v.num_clusters as usize))?;
    let leaf_surfaces = l[LEAF_SURFACES].parse(|i, r| {
        index(
            "leafsurfaces",
            i,
            "surface",
            i32_at(r, 0),
            l[SURFACES].count(),
        )
    })?;
    let leaf_brushes = l[LEAF_BRUSHES]
        .parse(|i, r| index("leafbrushes", i, "brush", i32_at(r, 0), l[BRUSHES].count()))?;
    let models = models(&l)?;
    let brushes = brushes(&l)?;
    let brush_sides = brush_sides(&l)?;
    let vertices = vertices(&l[DRAW_VERTS])?;
    let indexes = indexes(&l)?;
    let fogs = fogs(&l)?;
    let mut warnings = Vec::new();
    let surfaces = surfaces(&l, &mut warnings)?;
    check_mesh_indexes(&surfaces, &indexes)?;
    let lightmaps = (0..l[LIGHTMAPS].count())
        .map(|i| l[LIGHTMAPS].record(i).to_vec())
        .collect();
    let light_grid = l[LIGHT_GRID].parse(|_, r| Ok(array_at(r, 0)))?;

    Ok(Bsp {
        entities,
        shaders,
        planes,
        nodes,
        leafs,
        leaf_surfaces,
        leaf_brushes,
        models,
        brushes,
        brush_sides,
        vertices,
        indexes,
        fogs,
        surfaces,
        lightmaps,
        light_grid,
        vis,
        warnings,
    })
}

/// Checks the header and cuts the file into its 17 lumps, each inside the file and a whole
/// number of records.
fn lumps(file: &[u8]) -> Result<Vec<Lump<'_>>, BspError> {
    if file.len() < HEADER_BYTES {
        return Err(BspError::TooSmall(file.len()));
    }
    let magic: [u8; 4] = array_at(file, 0);
    if &magic != b"IBSP" {
        return Err(BspError::BadMagic(magic));
    }
    let version = i32_at(file, 4);
    if version != 46 {
        return Err(BspError::BadVersion(version));
    }
    let mut lumps = Vec::with_capacity(17);
    for id in 0..17 {
        let offset = i32_at(file, 8 + id * 8) as i64;
        let length = i32_at(file, 12 + id * 8) as i64;
        if offset < 0 || length < 0 || offset + length > file.len() as i64 {
            return Err(BspError::LumpOutOfFile {
                lump: LUMP_NAMES[id],
                offset,
                length,
                file_len: file.len(),
            });
        }
        let (o, l) = (offset as usize, length as usize);
        if l % RECORD_SIZES[id] != 0 {
            return Err(BspError::LumpNotMultiple {
                lump: LUMP_NAMES[id],
                length: l,
                record: RECORD_SIZES[id],
            });
        }
        lumps.push(Lump {
            id,
            data: &file[o..o + l],
        });
    }
    Ok(lumps)
}

fn shaders(lump: &Lump) -> Vec<BspShader> {
    (0..lump.count())
        .map(|i| {
            let r = lump.record(i);
            BspShader {
                name: name_at(r, 0, 64),
                surface_flags: i32_at(r, 64),
                content_flags: i32_at(r, 68),
            }
        })
        .collect()
}

fn planes(lump: &Lump) -> Result<Vec<Plane>, BspError> {
    lump.parse(|i, r| {
        let p = Plane {
            normal: vec3_at(r, 0),
            dist: f32_at(r, 12),
        };
        finite(
            "planes",
            i,
            "normal/dist",
            &[p.normal[0], p.normal[1], p.normal[2], p.dist],
        )?;
        Ok(p)
    })
}

fn nodes(l: &[Lump]) -> Result<Vec<Node>, BspError> {
    let (n_planes, n_nodes, n_leafs) = (l[PLANES].count(), l[NODES].count(), l[LEAFS].count());
    l[NODES].parse(|i, r| {
        let plane = index("nodes", i, "plane", i32_at(r, 0), n_planes)?;
        let children = [i32_at(r, 4), i32_at(r, 8)];
        for (c, field) in children.iter().zip(["children[0]", "children[1]"]) {
            if *c >= 0 {
                index("nodes", i, field, *c, n_nodes)?;
                if *c as usize <= i {
                    return Err(BspError::Invalid {
                        lump: "nodes",
                        record: i,
                        field,
                        value: *c as i64,
                        why: "a child node must come after its parent",
                    });
                }
            } else {
                index("nodes", i, field, -(c + 1), n_leafs)?;
            }
        }
        Ok(Node {
            plane,
            children,
            mins: ivec3_at(r, 12),
            maxs: ivec3_at(r, 24),
        })
    })
}

/// The visibility lump `d`: None when empty (a map compiled without vis).
fn vis(d: &[u8]) -> Result<Option<Vis>, BspError> {
    if d.is_empty() {
        return Ok(None);
    }
    let invalid = |field, value, why| BspError::Invalid {
        lump: "visibility",
        record: 0,
        field,
        value,
        why,
    };
    if d.len() < 8 {
        return Err(invalid(
            "length",
            d.len() as i64,
            "shorter than its 8-byte header",
        ));
    }
    let (nc, cb) = (i32_at(d, 0), i32_at(d, 4));
    if nc < 0 {
        return Err(invalid("numClusters", nc as i64, "negative"));
    }
    if (cb as i64) < (nc as i64 + 7) / 8 {
        return Err(invalid(
            "clusterBytes",
            cb as i64,
            "too small for one bit per cluster",
        ));
    }
    let needed = 8 + nc as u64 * cb as u64;
    if needed > d.len() as u64 {
        return Err(invalid(
            "numClusters*clusterBytes",
            needed as i64,
            "more than the lump holds",
        ));
    }
    Ok(Some(Vis {
        num_clusters: nc as u32,
        cluster_bytes: cb as u32,
        data: d[8..needed as usize].to_vec(),
    }))
}

/// Leafs, their clusters checked against `n_clusters` (None: the map has no vis).
fn leafs(l: &[Lump], n_clusters: Option<usize>) -> Result<Vec<Leaf>, BspError> {
    let (n_leaf_surfaces, n_leaf_brushes) = (l[LEAF_SURFACES].count(), l[LEAF_BRUSHES].count());
    l[LEAFS].parse(|i, r| {
        let cluster = i32_at(r, 0);
        match n_clusters {
            Some(n) if cluster >= 0 => {
                index("leafs", i, "cluster", cluster, n)?;
            }
            _ if cluster < -1 => {
                return Err(range_err(
                    "leafs",
                    i,
                    "cluster",
                    cluster as i64,
                    n_clusters.unwrap_or(0),
                ));
            }
            _ => {}
        }
        let (fs, ns) = span(
            "leafs",
            i,
            "firstLeafSurface/numLeafSurfaces",
            i32_at(r, 32),
            i32_at(r, 36),
            n_leaf_surfaces,
        )?;
        let (fb, nb) = span(
            "leafs",
            i,
            "firstLeafBrush/numLeafBrushes",
            i32_at(r, 40),
            i32_at(r, 44),
            n_leaf_brushes,
        )?;
        Ok(Leaf {
            cluster,
            area: i32_at(r, 4),
            mins: ivec3_at(r, 8),
            maxs: ivec3_at(r, 20),
            first_leaf_surface: fs,
            num_leaf_surfaces: ns,
            first_leaf_brush: fb,
            num_leaf_brushes: nb,
        })
    })
}

fn models(l: &[Lump]) -> Result<Vec<Model>, BspError> {
    let (n_surfaces, n_brushes) = (l[SURFACES].count(), l[BRUSHES].count());
    l[MODELS].parse(|i, r| {
        let (mins, maxs) = (vec3_at(r, 0), vec3_at(r, 12));
        finite("models", i, "mins/maxs", &[mins, maxs].concat())?;
        let (fs, ns) = span(
            "models",
            i,
            "firstSurface/numSurfaces",
            i32_at(r, 24),
            i32_at(r, 28),
            n_surfaces,
        )?;
        let (fb, nb) = span(
            "models",
            i,
            "firstBrush/numBrushes",
            i32_at(r, 32),
            i32_at(r, 36),
            n_brushes,
        )?;
        Ok(Model {
            mins,
            maxs,
            first_surface: fs,
            num_surfaces: ns,
            first_brush: fb,
            num_brushes: nb,
        })
    })
}

fn brushes(l: &[Lump]) -> Result<Vec<Brush>, BspError> {
    let (n_sides, n_shaders) = (l[BRUSH_SIDES].count(), l[SHADERS].count());
    l[BRUSHES].parse(|i, r| {
        let (first_side, num_sides) = span(
            "brushes",
            i,
            "firstSide/numSides",
            i32_at(r, 0),
            i32_at(r, 4),
            n_sides,
        )?;
        Ok(Brush {
            first_side,
            num_sides,
            shader: index("brushes", i, "shader", i32_at(r, 8), n_shaders)?,
        })
    })
}

fn brush_sides(l: &[Lump]) -> Result<Vec<BrushSide>, BspError> {
    let (n_planes, n_shaders) = (l[PLANES].count(), l[SHADERS].count());
    l[BRUSH_SIDES].parse(|i, r| {
        Ok(BrushSide {
            plane: index("brushsides", i, "plane", i32_at(r, 0), n_planes)?,
            shader: index("brushsides", i, "shader", i32_at(r, 4), n_shaders)?,
        })
    })
}

fn vertices(lump: &Lump) -> Result<Vec<DrawVert>, BspError> {
    lump.parse(|i, r| {
        let v = DrawVert {
            position: vec3_at(r, 0),
            st: [f32_at(r, 12), f32_at(r, 16)],
            lightmap: [f32_at(r, 20), f32_at(r, 24)],
            normal: vec3_at(r, 28),
            color: array_at(r, 40),
        };
        finite("drawverts", i, "position", &v.position)?;
        // Texture coordinates and normals of unused vertices may be garbage in real maps; they
        // are sanitised where surfaces use them, not rejected.
        Ok(v)
    })
}

/// Draw indexes, only checked non-negative here: they are relative to a surface's first vertex
/// (see [`check_mesh_indexes`]).
fn indexes(l: &[Lump]) -> Result<Vec<u32>, BspError> {
    let n_verts = l[DRAW_VERTS].count();
    l[DRAW_INDEXES].parse(|i, r| {
        let v = i32_at(r, 0);
        if v < 0 {
            return Err(range_err("drawindexes", i, "index", v as i64, n_verts));
        }
        Ok(v as u32)
    })
}

fn fogs(l: &[Lump]) -> Result<Vec<Fog>, BspError> {
    let n_brushes = l[BRUSHES].count();
    l[FOGS].parse(|i, r| {
        let brush = i32_at(r, 64);
        if brush >= 0 {
            index("fogs", i, "brushNum", brush, n_brushes)?;
        }
        Ok(Fog {
            name: name_at(r, 0, 64),
            brush,
            visible_side: i32_at(r, 68),
        })
    })
}

/// Surfaces; a fog number outside the fogs lump is cleared and counted in one warning.
fn surfaces(l: &[Lump], warnings: &mut Vec<String>) -> Result<Vec<Surface>, BspError> {
    let n_fogs = l[FOGS].count();
    let mut bad_fogs = 0usize;
    let surfaces = l[SURFACES].parse(|i, r| {
        let mut fog = i32_at(r, 4);
        if fog < -1 || fog as i64 >= n_fogs as i64 {
            // Fallback: shipped maps (OpenArena's aggressor) reference fogs they lack; shadowlab
            // draws no fog, so the reference is cleared and reported instead of rejecting the map.
            bad_fogs += 1;
            fog = -1;
        }
        surface(l, i, r, fog)
    })?;
    if bad_fogs > 0 {
        warnings.push(format!(
            "{bad_fogs} surfaces name a fog outside the {n_fogs} fogs of the map; their fog is ignored"
        ));
    }
    Ok(surfaces)
}

/// Surface record `i`, its fog already checked.
fn surface(l: &[Lump], i: usize, r: &[u8], fog: i32) -> Result<Surface, BspError> {
    let lump = "surfaces";
    let shader = index(lump, i, "shaderNum", i32_at(r, 0), l[SHADERS].count())?;
    let kind = surface_type(i, i32_at(r, 8))?;
    let (first_vert, num_verts) = span(
        lump,
        i,
        "firstVert/numVerts",
        i32_at(r, 12),
        i32_at(r, 16),
        l[DRAW_VERTS].count(),
    )?;
    let (first_index, num_indexes) = span(
        lump,
        i,
        "firstIndex/numIndexes",
        i32_at(r, 20),
        i32_at(r, 24),
        l[DRAW_INDEXES].count(),
    )?;
    let lightmap = i32_at(r, 28);
    if lightmap >= 0 {
        index(lump, i, "lightmapNum", lightmap, l[LIGHTMAPS].count())?;
    }
    let mut s = Surface {
        shader,
        fog,
        kind,
        first_vert,
        num_verts,
        first_index,
        num_indexes,
        lightmap,
        lightmap_origin: vec3_at(r, 48),
        lightmap_vecs: [vec3_at(r, 60), vec3_at(r, 72), vec3_at(r, 84)],
        patch_width: 0,
        patch_height: 0,
    };
    (s.patch_width, s.patch_height) = surface_shape(&s, i, i32_at(r, 96), i32_at(r, 100))?;
    Ok(s)
}

fn surface_type(i: usize, value: i32) -> Result<SurfaceType, BspError> {
    match value {
        1 => Ok(SurfaceType::Planar),
        2 => Ok(SurfaceType::Patch),
        3 => Ok(SurfaceType::TriangleSoup),
        4 => Ok(SurfaceType::Flare),
        other => Err(BspError::Invalid {
            lump: "surfaces",
            record: i,
            field: "surfaceType",
            value: other as i64,
            why: "not 1 (planar), 2 (patch), 3 (triangle soup) or 4 (flare)",
        }),
    }
}

/// Checks what surface record `i`'s type requires of its size: a patch's control grid
/// (`pw` x `ph`, returned), whole triangles for polygons and meshes. Other types get (0, 0).
fn surface_shape(s: &Surface, i: usize, pw: i32, ph: i32) -> Result<(u32, u32), BspError> {
    let lump = "surfaces";
    match s.kind {
        SurfaceType::Patch => {
            for (v, field) in [(pw, "patchWidth"), (ph, "patchHeight")] {
                if !(3..=1024).contains(&v) || v % 2 == 0 {
                    return Err(BspError::Invalid {
                        lump,
                        record: i,
                        field,
                        value: v as i64,
                        why: "a patch side must be odd and between 3 and 1024",
                    });
                }
            }
            if pw as i64 * ph as i64 != s.num_verts as i64 {
                return Err(BspError::Invalid {
                    lump,
                    record: i,
                    field: "patchWidth*patchHeight",
                    value: pw as i64 * ph as i64,
                    why: "differs from numVerts",
                });
            }
            Ok((pw as u32, ph as u32))
        }
        SurfaceType::Planar | SurfaceType::TriangleSoup => {
            if !s.num_indexes.is_multiple_of(3) {
                return Err(BspError::Invalid {
                    lump,
                    record: i,
                    field: "numIndexes",
                    value: s.num_indexes as i64,
                    why: "not a multiple of 3",
                });
            }
            Ok((0, 0))
        }
        SurfaceType::Flare => Ok((0, 0)),
    }
}

/// Mesh indices are relative to the surface's first vertex: each must be below its `numVerts`.
fn check_mesh_indexes(surfaces: &[Surface], indexes: &[u32]) -> Result<(), BspError> {
    for (i, s) in surfaces.iter().enumerate() {
        if matches!(s.kind, SurfaceType::Planar | SurfaceType::TriangleSoup) {
            let range = s.first_index as usize..(s.first_index + s.num_indexes) as usize;
            if let Some(&bad) = indexes[range].iter().find(|&&v| v >= s.num_verts) {
                return Err(range_err(
                    "surfaces",
                    i,
                    "drawindex (relative to firstVert)",
                    bad as i64,
                    s.num_verts as usize,
                ));
            }
        }
    }
    Ok(())
}

impl Bsp {
    /// The leaf containing `p`, walking the node tree from the root (finite: children come after
    /// their parents). A map without nodes has everything in leaf 0.
    pub fn leaf_at(&self, p: [f32; 3]) -> Option<usize> {
        if self.nodes.is_empty() {
            return (!self.leafs.is_empty()).then_some(0);
        }
        let mut node = 0usize;
        loop {
            let n = &self.nodes[node];
            let plane = &self.planes[n.plane as usize];
            let d = plane.normal[0] * p[0] + plane.normal[1] * p[1] + plane.normal[2] * p[2]
                - plane.dist;
            let child = if d >= 0.0 {
                n.children[0]
            } else {
                n.children[1]
            };
            if child < 0 {
                return Some((-(child + 1)) as usize);
            }
            node = child as usize;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A minimal valid map: one square face on one leaf, a second empty leaf, two clusters.
    struct Writer {
        lumps: Vec<Vec<u8>>,
    }

    fn i(v: i32) -> [u8; 4] {
        v.to_le_bytes()
    }
    fn f(v: f32) -> [u8; 4] {
        v.to_le_bytes()
    }

    impl Writer {
        fn valid() -> Writer {
            let mut l = vec![Vec::new(); 17];
            l[0] = b"{\n\"classname\" \"worldspawn\"\n}\n\0".to_vec();
            let mut shader = vec![0u8; 72];
            shader[..15].copy_from_slice(b"textures/a/wall");
            l[1] = shader;
            l[2] = [f(0.0), f(0.0), f(1.0), f(0.0)].concat();
            // Node 0: plane 0, front = leaf 0, back = leaf 1.
            l[3] = [
                i(0),
                i(-1),
                i(-2),
                i(-64),
                i(-64),
                i(-64),
                i(64),
                i(64),
                i(64),
            ]
            .concat();
            l[4] = [
                [
                    i(0),
                    i(0),
                    i(-64),
                    i(-64),
                    i(0),
                    i(64),
                    i(64),
                    i(64),
                    i(0),
                    i(1),
                    i(0),
                    i(1),
                ]
                .concat(),
                [
                    i(1),
                    i(0),
                    i(-64),
                    i(-64),
                    i(-64),
                    i(64),
                    i(64),
                    i(0),
                    i(1),
                    i(0),
                    i(0),
                    i(0),
                ]
                .concat(),
            ]
            .concat();
            l[5] = i(0).to_vec();
            l[6] = i(0).to_vec();
            l[7] = [
                f(-64.0),
                f(-64.0),
                f(-64.0),
                f(64.0),
                f(64.0),
                f(64.0),
                i(0),
                i(1),
                i(0),
                i(1),
            ]
            .concat();
            l[8] = [i(0), i(1), i(0)].concat();
            l[9] = [i(0), i(0)].concat();
            let mut verts = Vec::new();
            for (x, y) in [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0)] {
                verts.extend(
                    [
                        f(x),
                        f(y),
                        f(0.0),
                        f(0.0),
                        f(0.0),
                        f(0.0),
                        f(0.0),
                        f(0.0),
                        f(0.0),
                        f(1.0),
                    ]
                    .concat(),
                );
                verts.extend([255, 255, 255, 255]);
            }
            l[10] = verts;
            l[11] = [i(0), i(1), i(2), i(0), i(2), i(3)].concat();
            let mut surf = [
                i(0),
                i(-1),
                i(1),
                i(0),
                i(4),
                i(0),
                i(6),
                i(0),
                i(0),
                i(0),
                i(0),
                i(0),
            ]
            .concat();
            surf.extend(vec![0u8; 48]);
            surf.extend([i(0), i(0)].concat());
            l[13] = surf;
            l[14] = vec![128u8; 49152];
            l[15] = vec![0u8; 8];
            // Two clusters, one byte each, each seeing both.
            l[16] = [i(2).to_vec(), i(1).to_vec(), vec![0b11, 0b11]].concat();
            Writer { lumps: l }
        }

        fn bytes(&self) -> Vec<u8> {
            let mut out = b"IBSP".to_vec();
            out.extend(i(46));
            let mut offset = 8 + 17 * 8;
            let mut body: Vec<u8> = Vec::new();
            for l in &self.lumps {
                out.extend(i(offset as i32));
                out.extend(i(l.len() as i32));
                body.extend(l);
                offset += l.len();
            }
            out.extend(body);
            out
        }

        /// Overwrites the i32 at `at` in lump `lump`.
        fn set(mut self, lump: usize, at: usize, v: i32) -> Writer {
            self.lumps[lump][at..at + 4].copy_from_slice(&i(v));
            self
        }
    }

    #[test]
    fn the_minimal_map_parses_with_its_values() {
        let b = parse(&Writer::valid().bytes()).unwrap();
        assert_eq!(b.shaders[0].name, "textures/a/wall");
        assert_eq!(b.surfaces.len(), 1);
        assert_eq!(b.surfaces[0].kind, SurfaceType::Planar);
        assert_eq!(b.indexes, vec![0, 1, 2, 0, 2, 3]);
        assert_eq!(b.vertices[2].position, [10.0, 10.0, 0.0]);
        assert_eq!(b.lightmaps.len(), 1);
        let vis = b.vis.as_ref().unwrap();
        assert!(
            vis.visible(0, 1) && vis.visible(1, 0) && !vis.visible(0, 2) && !vis.visible(-1, 0)
        );
        assert_eq!(b.leaf_at([0.0, 0.0, 5.0]), Some(0));
        assert_eq!(b.leaf_at([0.0, 0.0, -5.0]), Some(1));
        assert!(b.warnings.is_empty());
    }

    #[test]
    fn every_truncation_is_an_error_not_a_panic() {
        let full = Writer::valid().bytes();
        for len in 0..full.len() {
            let r = parse(&full[..len]);
            assert!(r.is_err(), "prefix of {len} bytes parsed");
        }
        assert_eq!(parse(&full[..10]), Err(BspError::TooSmall(10)));
    }

    #[test]
    fn header_errors() {
        let mut b = Writer::valid().bytes();
        b[0] = b'X';
        assert!(matches!(parse(&b), Err(BspError::BadMagic(_))));
        let mut b = Writer::valid().bytes();
        b[4..8].copy_from_slice(&i(47));
        assert_eq!(parse(&b), Err(BspError::BadVersion(47)));
        // Lump 13 (surfaces) pointing past the end of the file.
        let mut b = Writer::valid().bytes();
        let len = b.len() as i32;
        b[8 + 13 * 8..12 + 13 * 8].copy_from_slice(&i(len - 50));
        assert!(matches!(
            parse(&b),
            Err(BspError::LumpOutOfFile {
                lump: "surfaces",
                ..
            })
        ));
        // Negative length.
        let mut b = Writer::valid().bytes();
        b[12 + 2 * 8..16 + 2 * 8].copy_from_slice(&i(-16));
        assert!(matches!(
            parse(&b),
            Err(BspError::LumpOutOfFile {
                lump: "planes",
                length: -16,
                ..
            })
        ));
    }

    #[test]
    fn lengths_must_be_whole_records() {
        let mut w = Writer::valid();
        w.lumps[10].pop();
        assert_eq!(
            parse(&w.bytes()),
            Err(BspError::LumpNotMultiple {
                lump: "drawverts",
                length: 175,
                record: 44
            })
        );
    }

    fn index_error(w: Writer) -> (&'static str, &'static str, i64) {
        match parse(&w.bytes()) {
            Err(BspError::IndexOutOfRange {
                lump, field, value, ..
            }) => (lump, field, value),
            other => panic!("expected IndexOutOfRange, got {other:?}"),
        }
    }

    #[test]
    fn out_of_range_indices_name_lump_field_and_value() {
        assert_eq!(
            index_error(Writer::valid().set(13, 0, 5)),
            ("surfaces", "shaderNum", 5)
        );
        assert_eq!(index_error(Writer::valid().set(13, 16, 9)).0, "surfaces");
        assert_eq!(index_error(Writer::valid().set(13, 24, 60)).0, "surfaces");
        assert_eq!(
            index_error(Writer::valid().set(13, 28, 3)),
            ("surfaces", "lightmapNum", 3)
        );
        assert_eq!(
            index_error(Writer::valid().set(11, 8, 4)),
            ("surfaces", "drawindex (relative to firstVert)", 4)
        );
        assert_eq!(
            index_error(Writer::valid().set(3, 0, 7)),
            ("nodes", "plane", 7)
        );
        assert_eq!(
            index_error(Writer::valid().set(3, 4, -9)),
            ("nodes", "children[0]", 8)
        );
        assert_eq!(
            index_error(Writer::valid().set(4, 0, 2)),
            ("leafs", "cluster", 2)
        );
        assert_eq!(index_error(Writer::valid().set(4, 36, 2)).0, "leafs");
        assert_eq!(
            index_error(Writer::valid().set(5, 0, 1)),
            ("leafsurfaces", "surface", 1)
        );
        assert_eq!(index_error(Writer::valid().set(7, 28, 2)).0, "models");
        assert_eq!(
            index_error(Writer::valid().set(9, 4, 1)),
            ("brushsides", "shader", 1)
        );
        assert_eq!(
            index_error(Writer::valid().set(11, 0, -1)),
            ("drawindexes", "index", -1)
        );
    }

    #[test]
    fn invalid_values_and_absurd_counts() {
        let invalid = |w: Writer| match parse(&w.bytes()) {
            Err(BspError::Invalid { lump, field, .. }) => (lump, field),
            other => panic!("expected Invalid, got {other:?}"),
        };
        assert_eq!(
            invalid(Writer::valid().set(13, 8, 9)),
            ("surfaces", "surfaceType")
        );
        // A node child pointing back at itself would make tree walks loop.
        let mut w = Writer::valid();
        let node = w.lumps[3].clone();
        w.lumps[3].extend(node);
        let w = w.set(3, 4, 0).set(3, 36 + 4, -1);
        assert_eq!(invalid(w), ("nodes", "children[0]"));
        // Vis claiming two billion clusters, and too few bytes per cluster.
        assert_eq!(
            invalid(Writer::valid().set(16, 0, 2_000_000_000)).0,
            "visibility"
        );
        assert_eq!(
            invalid(Writer::valid().set(16, 4, 0)),
            ("visibility", "clusterBytes")
        );
        // Patches: even, tiny and absurd sizes, and a size that disagrees with numVerts.
        let patch = |w: i32, h: i32| Writer::valid().set(13, 8, 2).set(13, 96, w).set(13, 100, h);
        assert_eq!(invalid(patch(2, 2)), ("surfaces", "patchWidth"));
        assert_eq!(invalid(patch(3, 1_000_001)), ("surfaces", "patchHeight"));
        assert_eq!(invalid(patch(3, 3)), ("surfaces", "patchWidth*patchHeight"));
        // A NaN vertex.
        let mut w = Writer::valid();
        w.lumps[10][0..4].copy_from_slice(&f(f32::NAN));
        assert!(matches!(
            parse(&w.bytes()),
            Err(BspError::NotFinite {
                lump: "drawverts",
                ..
            })
        ));
    }

    #[test]
    fn a_missing_fog_is_repaired_with_a_warning() {
        let b = parse(&Writer::valid().set(13, 4, 0).bytes()).unwrap();
        assert_eq!(b.surfaces[0].fog, -1);
        assert_eq!(b.warnings.len(), 1);
    }
}
