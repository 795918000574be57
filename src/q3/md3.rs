//! MD3 models (Quake 3's vertex-animated meshes), their `.skin` files and player
//! `animation.cfg`, and the assembly of a player from its lower, upper and head models via tags.
//!
//! GL-free. Malformed input never panics: every count, offset and float is checked before it is
//! used or allocated for, and each failure is a specific [`Md3Error`].

use super::bytes::{self, array_at, f32_at, i16_at, i32_at, name_at, u16_at};
use crate::geometry::Aabb;
use crate::scene::Vertex;
use glam::{Mat3, Mat4, Vec3};
use thiserror::Error;

// Limits on the header and surface counts: real models stay far below them, so anything above
// is a corrupt file rather than a big model.
/// Most frames a model may have.
pub const MAX_FRAMES: usize = 1024;
/// Most tags per frame.
pub const MAX_TAGS: usize = 16;
/// Most surfaces per model.
pub const MAX_SURFACES: usize = 32;
/// Most vertices per surface.
pub const MAX_VERTS: usize = 4096;
/// Most triangles per surface.
pub const MAX_TRIANGLES: usize = 8192;
/// Most shaders per surface.
pub const MAX_SHADERS: usize = 256;

const MAGIC: [u8; 4] = *b"IDP3";
const VERSION: i32 = 15;
const NAME_LEN: usize = 64;
const HEADER_SIZE: usize = 108;
const SURFACE_HEADER_SIZE: usize = 108;
const FRAME_SIZE: usize = 56;
const TAG_SIZE: usize = 112;
const SHADER_SIZE: usize = 68;
const TRIANGLE_SIZE: usize = 12;
const ST_SIZE: usize = 8;
const XYZ_NORMAL_SIZE: usize = 8;
/// Vertex positions are stored as i16 in units of 1/64.
const XYZ_SCALE: f32 = 1.0 / 64.0;

/// Why an MD3, or a player's `animation.cfg`, could not be loaded or placed.
#[derive(Debug, Error, PartialEq)]
pub enum Md3Error {
    /// A record runs past the end of the data holding it (the file, or its surface record).
    #[error("{what}: {needed} bytes at offset {offset} run past the end at {len}")]
    Truncated {
        what: String,
        offset: usize,
        needed: usize,
        len: usize,
    },
    #[error("{what}: bad magic {found:?}, expected \"IDP3\"")]
    BadMagic { what: String, found: [u8; 4] },
    #[error("unsupported MD3 version {0} (expected 15)")]
    BadVersion(i32),
    #[error("{what} = {value} is outside 0..={max}")]
    CountOutOfRange {
        what: String,
        value: i32,
        max: usize,
    },
    /// An offset (or a surface's record size) outside the range it must lie in.
    #[error("{what} = {offset} is outside {min}..={max}")]
    OffsetOutOfRange {
        what: String,
        offset: i64,
        min: usize,
        max: usize,
    },
    #[error("surface {surface} has {found} frames, the model has {expected}")]
    FrameCountMismatch {
        surface: usize,
        found: i32,
        expected: usize,
    },
    #[error("surface {surface} triangle {triangle}: vertex index {index} is not below {verts}")]
    IndexOutOfRange {
        surface: usize,
        triangle: usize,
        index: i64,
        verts: usize,
    },
    #[error("{what}: value is not finite")]
    NonFinite { what: String },
    #[error("{part}: frame {frame} is out of range (the model has {frames})")]
    FrameOutOfRange {
        part: String,
        frame: usize,
        frames: usize,
    },
    #[error("{part}: no tag named `{tag}`")]
    MissingTag { part: String, tag: String },
    #[error("animation.cfg line {line}: {reason}")]
    AnimationSyntax { line: usize, reason: String },
    #[error("animation.cfg has {found} animations, needs at least {needed}")]
    AnimationMissing { found: usize, needed: usize },
}

/// One animation frame's bounds, as stored in the file.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    pub name: String,
    pub mins: Vec3,
    pub maxs: Vec3,
    pub local_origin: Vec3,
    pub radius: f32,
}

impl Frame {
    pub fn bounds(&self) -> Aabb {
        Aabb {
            min: self.mins,
            max: self.maxs,
        }
    }
}

/// An attachment point of one frame: an origin and three axis vectors.
#[derive(Debug, Clone, PartialEq)]
pub struct Tag {
    pub name: String,
    pub origin: Vec3,
    pub axis: [Vec3; 3],
}

impl Tag {
    /// The tag's origin and axes, as the scene's motion mixes them.
    pub fn key(&self) -> crate::scene::motion::TagKey {
        crate::scene::motion::TagKey {
            origin: self.origin,
            axis: self.axis,
        }
    }

    /// The tag's frame as a transform from the attached model's space into this model's space:
    /// columns are the three axes and the origin.
    pub fn matrix(&self) -> Mat4 {
        self.key().matrix()
    }
}

/// One mesh of a model, with every frame's vertices.
#[derive(Debug, Clone, PartialEq)]
pub struct Surface {
    pub name: String,
    pub shaders: Vec<String>,
    /// As stored: Quake 3's clockwise front faces (see [`place_model`]).
    pub triangles: Vec<[u32; 3]>,
    /// Texture coordinates, one per vertex (shared by all frames).
    pub st: Vec<[f32; 2]>,
    /// Frame-major: `positions[frame * num_verts + v]`.
    pub positions: Vec<Vec3>,
    /// Frame-major, like `positions`; unit length.
    pub normals: Vec<Vec3>,
    pub num_verts: usize,
}

impl Surface {
    /// The positions of one frame, if the surface has it.
    pub fn frame_positions(&self, frame: usize) -> Option<&[Vec3]> {
        frame_slice(&self.positions, frame, self.num_verts)
    }
    pub fn frame_normals(&self, frame: usize) -> Option<&[Vec3]> {
        frame_slice(&self.normals, frame, self.num_verts)
    }
}

fn frame_slice(all: &[Vec3], frame: usize, n: usize) -> Option<&[Vec3]> {
    let start = frame.checked_mul(n)?;
    all.get(start..start.checked_add(n)?)
}

/// A parsed MD3 model.
#[derive(Debug, Clone, PartialEq)]
pub struct Md3 {
    pub name: String,
    pub frames: Vec<Frame>,
    /// The tag names, in the order of each frame's tags.
    pub tag_names: Vec<String>,
    /// Frame-major: `tags[frame * tag_names.len() + t]`.
    pub tags: Vec<Tag>,
    pub surfaces: Vec<Surface>,
}

impl Md3 {
    pub fn num_frames(&self) -> usize {
        self.frames.len()
    }

    /// The tag called `name` in `frame`, if both exist.
    pub fn tag(&self, frame: usize, name: &str) -> Option<&Tag> {
        let t = self.tag_names.iter().position(|n| n == name)?;
        let i = frame.checked_mul(self.tag_names.len())?.checked_add(t)?;
        self.tags.get(i)
    }
}

// The little-endian readers of `bytes` read inside slices whose bounds `region` checked.
fn vec3_at(b: &[u8], at: usize) -> Vec3 {
    Vec3::from_array(bytes::vec3_at(b, at))
}

/// The `count` records of `size` bytes at `offset` inside `container`, which starts at file offset
/// `base`; errors name `what`.
fn region<'a>(
    container: &'a [u8],
    base: usize,
    what: &str,
    offset: i64,
    count: usize,
    size: usize,
) -> Result<&'a [u8], Md3Error> {
    let len = container.len();
    let start = usize::try_from(offset)
        .ok()
        .filter(|&s| s <= len)
        .ok_or_else(|| Md3Error::OffsetOutOfRange {
            what: format!("{what} offset"),
            offset,
            min: 0,
            max: len,
        })?;
    let needed = count.saturating_mul(size);
    container
        .get(start..)
        .and_then(|rest| rest.get(..needed))
        .ok_or_else(|| Md3Error::Truncated {
            what: what.to_string(),
            offset: base + start,
            needed,
            len: base + len,
        })
}

fn count(what: &str, value: i32, max: usize) -> Result<usize, Md3Error> {
    usize::try_from(value)
        .ok()
        .filter(|&v| v <= max)
        .ok_or_else(|| Md3Error::CountOutOfRange {
            what: what.to_string(),
            value,
            max,
        })
}

fn check_finite(values: &[f32], what: impl FnOnce() -> String) -> Result<(), Md3Error> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(Md3Error::NonFinite { what: what() })
    }
}

/// The unit normal of an MD3 vertex: the high byte is the latitude, the low byte the longitude,
/// each in steps of 2π/255.
pub fn decode_normal(encoded: u16) -> Vec3 {
    let step = std::f64::consts::TAU / 255.0;
    let lat = f64::from(encoded >> 8) * step;
    let lng = f64::from(encoded & 0xff) * step;
    Vec3::new(
        (lat.cos() * lng.sin()) as f32,
        (lat.sin() * lng.sin()) as f32,
        lng.cos() as f32,
    )
}

/// Parses an MD3 file, validating every count, offset, index and float.
pub fn parse(data: &[u8]) -> Result<Md3, Md3Error> {
    let len = data.len();
    let truncated_header = || Md3Error::Truncated {
        what: "header".to_string(),
        offset: 0,
        needed: HEADER_SIZE,
        len,
    };
    if len < 4 {
        return Err(truncated_header());
    }
    let magic: [u8; 4] = array_at(data, 0);
    if magic != MAGIC {
        return Err(Md3Error::BadMagic {
            what: "header".to_string(),
            found: magic,
        });
    }
    let header = data.get(..HEADER_SIZE).ok_or_else(truncated_header)?;
    let version = i32_at(header, 4);
    if version != VERSION {
        return Err(Md3Error::BadVersion(version));
    }
    let name = name_at(header, 8, NAME_LEN);
    // 72: flags, unused.
    let num_frames = count("numFrames", i32_at(header, 76), MAX_FRAMES)?;
    let num_tags = count("numTags", i32_at(header, 80), MAX_TAGS)?;
    let num_surfaces = count("numSurfaces", i32_at(header, 84), MAX_SURFACES)?;
    // 88: numSkins, unused by the format.
    let ofs_frames = i64::from(i32_at(header, 92));
    let ofs_tags = i64::from(i32_at(header, 96));
    let ofs_surfaces = i64::from(i32_at(header, 100));
    let ofs_end = i64::from(i32_at(header, 104));

    let frame_bytes = region(data, 0, "frames", ofs_frames, num_frames, FRAME_SIZE)?;
    let mut frames = Vec::with_capacity(num_frames);
    for (i, f) in frame_bytes.chunks_exact(FRAME_SIZE).enumerate() {
        let frame = Frame {
            mins: vec3_at(f, 0),
            maxs: vec3_at(f, 12),
            local_origin: vec3_at(f, 24),
            radius: f32_at(f, 36),
            name: name_at(f, 40, 16),
        };
        let values = [frame.mins, frame.maxs, frame.local_origin];
        check_finite(&[frame.radius], || format!("frame {i} radius"))?;
        check_finite(&values.map(|v| v.to_array()).concat(), || {
            format!("frame {i} bounds")
        })?;
        frames.push(frame);
    }

    let tag_bytes = region(data, 0, "tags", ofs_tags, num_frames * num_tags, TAG_SIZE)?;
    let mut tags = Vec::with_capacity(num_frames * num_tags);
    for (i, t) in tag_bytes.chunks_exact(TAG_SIZE).enumerate() {
        let tag = Tag {
            name: name_at(t, 0, NAME_LEN),
            origin: vec3_at(t, 64),
            axis: [vec3_at(t, 76), vec3_at(t, 88), vec3_at(t, 100)],
        };
        let values = [tag.origin, tag.axis[0], tag.axis[1], tag.axis[2]];
        check_finite(&values.map(|v| v.to_array()).concat(), || {
            let (frame, n) = (i / num_tags.max(1), i % num_tags.max(1));
            format!("tag {n} (`{}`) of frame {frame}", tag.name)
        })?;
        tags.push(tag);
    }
    let tag_names = tags.iter().take(num_tags).map(|t| t.name.clone()).collect();

    let mut surfaces = Vec::with_capacity(num_surfaces);
    let mut start = ofs_surfaces;
    for index in 0..num_surfaces {
        let (surface, size) = parse_surface(data, start, index, num_frames)?;
        surfaces.push(surface);
        start += size as i64;
    }

    if ofs_end < HEADER_SIZE as i64 || ofs_end > len as i64 {
        return Err(Md3Error::OffsetOutOfRange {
            what: "ofsEnd".to_string(),
            offset: ofs_end,
            min: HEADER_SIZE,
            max: len,
        });
    }

    Ok(Md3 {
        name,
        frames,
        tag_names,
        tags,
        surfaces,
    })
}

/// Surface `surface`'s triangles, each index checked against its `num_verts` vertices.
fn parse_triangles(
    bytes: &[u8],
    surface: usize,
    num_verts: usize,
) -> Result<Vec<[u32; 3]>, Md3Error> {
    let mut triangles = Vec::with_capacity(bytes.len() / TRIANGLE_SIZE);
    for (t, c) in bytes.chunks_exact(TRIANGLE_SIZE).enumerate() {
        let mut tri = [0u32; 3];
        for (k, out) in tri.iter_mut().enumerate() {
            let i = i32_at(c, 4 * k);
            *out = u32::try_from(i)
                .ok()
                .filter(|&i| (i as usize) < num_verts)
                .ok_or(Md3Error::IndexOutOfRange {
                    surface,
                    triangle: t,
                    index: i64::from(i),
                    verts: num_verts,
                })?;
        }
        triangles.push(tri);
    }
    Ok(triangles)
}

/// Texture coordinates, each finite.
fn parse_st(bytes: &[u8], label: &str) -> Result<Vec<[f32; 2]>, Md3Error> {
    let mut st = Vec::with_capacity(bytes.len() / ST_SIZE);
    for (v, c) in bytes.chunks_exact(ST_SIZE).enumerate() {
        let uv = [f32_at(c, 0), f32_at(c, 4)];
        check_finite(&uv, || format!("{label} st {v}"))?;
        st.push(uv);
    }
    Ok(st)
}

/// Positions (fixed point, 1/64 unit) and normals (latitude and longitude bytes) of every
/// frame's vertices.
fn parse_xyz_normals(bytes: &[u8]) -> (Vec<Vec3>, Vec<Vec3>) {
    bytes
        .chunks_exact(XYZ_NORMAL_SIZE)
        .map(|c| {
            let coord = |at| f32::from(i16_at(c, at)) * XYZ_SCALE;
            (
                Vec3::new(coord(0), coord(2), coord(4)),
                decode_normal(u16_at(c, 6)),
            )
        })
        .unzip()
}

/// Parses the surface record at file offset `start`; returns it and the record's size.
fn parse_surface(
    data: &[u8],
    start: i64,
    index: usize,
    num_frames: usize,
) -> Result<(Surface, usize), Md3Error> {
    let label = format!("surface {index}");
    let header = region(
        data,
        0,
        &format!("{label} header"),
        start,
        1,
        SURFACE_HEADER_SIZE,
    )?;
    // `region` accepted it, so it is a valid file offset.
    let start = start as usize;
    let magic: [u8; 4] = array_at(header, 0);
    if magic != MAGIC {
        return Err(Md3Error::BadMagic {
            what: label,
            found: magic,
        });
    }
    let name = name_at(header, 4, NAME_LEN);
    // 68: flags, unused.
    let frames = i32_at(header, 72);
    if usize::try_from(frames).ok() != Some(num_frames) {
        return Err(Md3Error::FrameCountMismatch {
            surface: index,
            found: frames,
            expected: num_frames,
        });
    }
    let num_shaders = count(
        &format!("{label} numShaders"),
        i32_at(header, 76),
        MAX_SHADERS,
    )?;
    let num_verts = count(&format!("{label} numVerts"), i32_at(header, 80), MAX_VERTS)?;
    let num_triangles = count(
        &format!("{label} numTriangles"),
        i32_at(header, 84),
        MAX_TRIANGLES,
    )?;
    let ofs_triangles = i64::from(i32_at(header, 88));
    let ofs_shaders = i64::from(i32_at(header, 92));
    let ofs_st = i64::from(i32_at(header, 96));
    let ofs_xyz = i64::from(i32_at(header, 100));
    let ofs_end = i32_at(header, 104);

    // The record must at least hold its header; it may not run past the file.
    let size = usize::try_from(ofs_end)
        .ok()
        .filter(|&s| s >= SURFACE_HEADER_SIZE)
        .ok_or_else(|| Md3Error::OffsetOutOfRange {
            what: format!("{label} ofsEnd"),
            offset: i64::from(ofs_end),
            min: SURFACE_HEADER_SIZE,
            max: data.len() - start,
        })?;
    let record = region(data, 0, &label, start as i64, 1, size)?;

    let tri_bytes = region(
        record,
        start,
        &format!("{label} triangles"),
        ofs_triangles,
        num_triangles,
        TRIANGLE_SIZE,
    )?;
    let triangles = parse_triangles(tri_bytes, index, num_verts)?;

    let shader_bytes = region(
        record,
        start,
        &format!("{label} shaders"),
        ofs_shaders,
        num_shaders,
        SHADER_SIZE,
    )?;
    let shaders = shader_bytes
        .chunks_exact(SHADER_SIZE)
        .map(|c| name_at(c, 0, NAME_LEN))
        .collect();

    let st_bytes = region(
        record,
        start,
        &format!("{label} st"),
        ofs_st,
        num_verts,
        ST_SIZE,
    )?;
    let st = parse_st(st_bytes, &label)?;

    let xyz_bytes = region(
        record,
        start,
        &format!("{label} xyzNormals"),
        ofs_xyz,
        num_frames * num_verts,
        XYZ_NORMAL_SIZE,
    )?;
    let (positions, normals) = parse_xyz_normals(xyz_bytes);

    let surface = Surface {
        name,
        shaders,
        triangles,
        st,
        positions,
        normals,
        num_verts,
    };
    Ok((surface, size))
}

/// A model surface placed in the scene: vertices in the placing transform's space, ready for
/// upload as a triangle list.
#[derive(Debug, Clone, PartialEq)]
pub struct PlacedSurface {
    /// Which model it came from: "lower", "upper", "head", or the model name for [`place_model`].
    pub part: String,
    pub surface_name: String,
    /// The surface's first shader name; empty when it has none (a skin usually supplies it).
    pub shader: String,
    pub vertices: Vec<Vertex>,
    /// Counter-clockwise front faces.
    pub indices: Vec<u32>,
}

impl PlacedSurface {
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(self.vertices.iter().map(Vertex::pos))
    }
}

/// Places every surface of `md3` at `frame` through `transform`; `part` of each result is the
/// model's name.
pub fn place_model(
    md3: &Md3,
    frame: usize,
    transform: Mat4,
) -> Result<Vec<PlacedSurface>, Md3Error> {
    place_part(md3, &md3.name, frame, transform)
}

fn place_part(
    md3: &Md3,
    part: &str,
    frame: usize,
    transform: Mat4,
) -> Result<Vec<PlacedSurface>, Md3Error> {
    let out_of_range = |frames| Md3Error::FrameOutOfRange {
        part: part.to_string(),
        frame,
        frames,
    };
    if frame >= md3.num_frames() {
        return Err(out_of_range(md3.num_frames()));
    }
    // Normals go through the inverse-transpose so that scaled tags keep them perpendicular; a
    // singular transform has none, and its normals become zero.
    let linear = Mat3::from_mat4(transform);
    let det = linear.determinant();
    let normal_matrix = if det != 0.0 && det.is_finite() {
        linear.inverse().transpose()
    } else {
        Mat3::ZERO
    };

    let mut placed = Vec::with_capacity(md3.surfaces.len());
    for (s, surface) in md3.surfaces.iter().enumerate() {
        let frames_here = surface.positions.len() / surface.num_verts.max(1);
        let positions = surface
            .frame_positions(frame)
            .ok_or_else(|| out_of_range(frames_here))?;
        let normals = surface
            .frame_normals(frame)
            .ok_or_else(|| out_of_range(frames_here))?;
        let vertices = positions
            .iter()
            .zip(normals)
            .enumerate()
            .map(|(v, (&p, &n))| {
                let uv = surface.st.get(v).copied().unwrap_or([0.0, 0.0]);
                Vertex::new(
                    transform.transform_point3(p),
                    (normal_matrix * n).normalize_or_zero(),
                    uv,
                )
            })
            .collect();
        let mut indices = Vec::with_capacity(surface.triangles.len() * 3);
        for (t, &[a, b, c]) in surface.triangles.iter().enumerate() {
            if let Some(&bad) = [a, b, c].iter().find(|&&i| i as usize >= surface.num_verts) {
                return Err(Md3Error::IndexOutOfRange {
                    surface: s,
                    triangle: t,
                    index: i64::from(bad),
                    verts: surface.num_verts,
                });
            }
            // Quake 3 models use clockwise front faces, shadowlab counter-clockwise: swapping
            // the last two corners flips the winding without moving the triangle.
            indices.extend_from_slice(&[a, c, b]);
        }
        placed.push(PlacedSurface {
            part: part.to_string(),
            surface_name: surface.name.clone(),
            shader: surface.shaders.first().cloned().unwrap_or_default(),
            vertices,
            indices,
        });
    }
    Ok(placed)
}

fn find_tag<'a>(md3: &'a Md3, part: &str, frame: usize, name: &str) -> Result<&'a Tag, Md3Error> {
    if frame >= md3.num_frames() {
        return Err(Md3Error::FrameOutOfRange {
            part: part.to_string(),
            frame,
            frames: md3.num_frames(),
        });
    }
    md3.tag(frame, name).ok_or_else(|| Md3Error::MissingTag {
        part: part.to_string(),
        tag: name.to_string(),
    })
}

/// Assembles a player: `lower` at the origin in `legs_frame`, `upper` on lower's `tag_torso` in
/// `torso_frame`, `head` (frame 0) on upper's `tag_head`. Each child's transform is its parent's
/// transform times the tag's matrix.
pub fn assemble_player(
    lower: &Md3,
    upper: &Md3,
    head: &Md3,
    legs_frame: usize,
    torso_frame: usize,
) -> Result<Vec<PlacedSurface>, Md3Error> {
    let lower_transform = Mat4::IDENTITY;
    let mut placed = place_part(lower, "lower", legs_frame, lower_transform)?;
    let torso = find_tag(lower, "lower", legs_frame, "tag_torso")?;
    let upper_transform = lower_transform * torso.matrix();
    placed.extend(place_part(upper, "upper", torso_frame, upper_transform)?);
    let head_tag = find_tag(upper, "upper", torso_frame, "tag_head")?;
    let head_transform = upper_transform * head_tag.matrix();
    placed.extend(place_part(head, "head", 0, head_transform)?);
    Ok(placed)
}

/// A `.skin` file: which texture each surface of a model uses.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Skin {
    /// (surface name lowercased, texture path), in file order, one per surface.
    pub entries: Vec<(String, String)>,
}

impl Skin {
    /// The texture for `surface` (case-insensitive).
    pub fn shader_for(&self, surface: &str) -> Option<&str> {
        self.entries
            .iter()
            .find(|(name, _)| name.eq_ignore_ascii_case(surface))
            .map(|(_, path)| path.as_str())
    }
}

/// Parses a `.skin` file: `surface,path` lines. Tag lines (`tag_*`), empty paths and lines
/// without a comma are skipped; a later line for a surface replaces an earlier one.
pub fn parse_skin(text: &str) -> Skin {
    let mut skin = Skin::default();
    for line in text.lines() {
        let Some((surface, path)) = line.split_once(',') else {
            continue;
        };
        let surface = surface.trim().to_ascii_lowercase();
        let path = path.trim();
        if surface.is_empty() || path.is_empty() || surface.starts_with("tag_") {
            continue;
        }
        match skin.entries.iter_mut().find(|(name, _)| *name == surface) {
            Some(entry) => entry.1 = path.to_string(),
            None => skin.entries.push((surface, path.to_string())),
        }
    }
    skin
}

/// The player animations of Quake 3, in the fixed order of `animation.cfg`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AnimationId {
    BothDeath1,
    BothDead1,
    BothDeath2,
    BothDead2,
    BothDeath3,
    BothDead3,
    TorsoGesture,
    TorsoAttack,
    TorsoAttack2,
    TorsoDrop,
    TorsoRaise,
    TorsoStand,
    TorsoStand2,
    LegsWalkCr,
    LegsWalk,
    LegsRun,
    LegsBack,
    LegsSwim,
    LegsJump,
    LegsLand,
    LegsJumpB,
    LegsLandB,
    LegsIdle,
    LegsIdleCr,
    LegsTurn,
}

/// How many animations an `animation.cfg` must list.
pub const NUM_ANIMATIONS: usize = 25;

impl AnimationId {
    pub const ALL: [AnimationId; NUM_ANIMATIONS] = {
        use AnimationId::*;
        [
            BothDeath1,
            BothDead1,
            BothDeath2,
            BothDead2,
            BothDeath3,
            BothDead3,
            TorsoGesture,
            TorsoAttack,
            TorsoAttack2,
            TorsoDrop,
            TorsoRaise,
            TorsoStand,
            TorsoStand2,
            LegsWalkCr,
            LegsWalk,
            LegsRun,
            LegsBack,
            LegsSwim,
            LegsJump,
            LegsLand,
            LegsJumpB,
            LegsLandB,
            LegsIdle,
            LegsIdleCr,
            LegsTurn,
        ]
    };

    /// The name Quake 3 uses, e.g. `LEGS_IDLE`.
    pub fn name(self) -> &'static str {
        use AnimationId::*;
        match self {
            BothDeath1 => "BOTH_DEATH1",
            BothDead1 => "BOTH_DEAD1",
            BothDeath2 => "BOTH_DEATH2",
            BothDead2 => "BOTH_DEAD2",
            BothDeath3 => "BOTH_DEATH3",
            BothDead3 => "BOTH_DEAD3",
            TorsoGesture => "TORSO_GESTURE",
            TorsoAttack => "TORSO_ATTACK",
            TorsoAttack2 => "TORSO_ATTACK2",
            TorsoDrop => "TORSO_DROP",
            TorsoRaise => "TORSO_RAISE",
            TorsoStand => "TORSO_STAND",
            TorsoStand2 => "TORSO_STAND2",
            LegsWalkCr => "LEGS_WALKCR",
            LegsWalk => "LEGS_WALK",
            LegsRun => "LEGS_RUN",
            LegsBack => "LEGS_BACK",
            LegsSwim => "LEGS_SWIM",
            LegsJump => "LEGS_JUMP",
            LegsLand => "LEGS_LAND",
            LegsJumpB => "LEGS_JUMPB",
            LegsLandB => "LEGS_LANDB",
            LegsIdle => "LEGS_IDLE",
            LegsIdleCr => "LEGS_IDLECR",
            LegsTurn => "LEGS_TURN",
        }
    }

    /// The animation called `short` in scene files: its name without the `LEGS_`, `TORSO_` or
    /// `BOTH_` prefix, any case (`run`, `idle`, `attack`, `stand2`).
    pub fn from_short_name(short: &str) -> Option<AnimationId> {
        AnimationId::ALL.into_iter().find(|id| {
            id.name()
                .split_once('_')
                .is_some_and(|(_, rest)| rest.eq_ignore_ascii_case(short))
        })
    }

    /// Whether it plays on the lower model, whose frames the file numbers after the torso's.
    pub fn is_legs_only(self) -> bool {
        self as usize >= AnimationId::LegsWalkCr as usize
    }
}

/// One animation: a frame range of its model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Animation {
    /// The first frame in the model that plays it (legs frames already corrected).
    pub first_frame: u32,
    pub num_frames: u32,
    pub looping_frames: u32,
    pub fps: u32,
    /// A negative frame count in the file plays the range backwards.
    pub reversed: bool,
}

/// A player's `animation.cfg`.
#[derive(Debug, Clone, PartialEq)]
pub struct AnimationCfg {
    /// At least [`NUM_ANIMATIONS`], in file order; later ones (e.g. Team Arena's) are kept as read.
    animations: Vec<Animation>,
    legs_offset: i64,
}

impl AnimationCfg {
    pub fn get(&self, id: AnimationId) -> &Animation {
        // The parser guarantees at least NUM_ANIMATIONS entries.
        &self.animations[id as usize]
    }
    pub fn animations(&self) -> &[Animation] {
        &self.animations
    }
    /// How many frames the file's legs numbers were shifted down by
    /// (LEGS_WALKCR.first - TORSO_GESTURE.first as written).
    pub fn legs_offset(&self) -> i64 {
        self.legs_offset
    }
    /// The upper model's frame for standing.
    pub fn torso_stand_frame(&self) -> u32 {
        self.get(AnimationId::TorsoStand).first_frame
    }
    /// The lower model's frame for idling.
    pub fn legs_idle_frame(&self) -> u32 {
        self.get(AnimationId::LegsIdle).first_frame
    }
}

const CFG_KEYWORDS: [&str; 5] = ["sex", "headoffset", "footsteps", "fixedtorso", "fixedlegs"];

/// Parses `animation.cfg`: keyword lines and `//` comments are skipped, every other line holds
/// `firstFrame numFrames loopingFrames fps`. Legs animations are renumbered into the lower model.
pub fn parse_animation_cfg(text: &str) -> Result<AnimationCfg, Md3Error> {
    let mut animations = Vec::new();
    let mut lines = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = raw.split_once("//").map_or(raw, |(before, _)| before);
        let mut tokens = line.split_whitespace();
        let Some(first) = tokens.next() else {
            continue;
        };
        if CFG_KEYWORDS.iter().any(|k| first.eq_ignore_ascii_case(k)) {
            continue;
        }
        if first.parse::<i64>().is_err() {
            log::debug!("animation.cfg line {line_no}: skipping unknown keyword `{first}`");
            continue;
        }
        let syntax = |reason: String| Md3Error::AnimationSyntax {
            line: line_no,
            reason,
        };
        let mut numbers = [0i32; 4];
        for (k, token) in std::iter::once(first).chain(tokens).take(4).enumerate() {
            numbers[k] = token
                .parse()
                .map_err(|_| syntax(format!("`{token}` is not an integer")))?;
        }
        if line.split_whitespace().count() < 4 {
            return Err(syntax(
                "expected 4 integers: firstFrame numFrames loopingFrames fps".to_string(),
            ));
        }
        let [first_frame, num_frames, looping, fps] = numbers;
        let non_negative = |name: &str, v: i32| {
            u32::try_from(v).map_err(|_| syntax(format!("{name} {v} is negative")))
        };
        animations.push(Animation {
            first_frame: non_negative("firstFrame", first_frame)?,
            num_frames: num_frames.unsigned_abs(),
            looping_frames: non_negative("loopingFrames", looping)?,
            fps: non_negative("fps", fps)?,
            reversed: num_frames < 0,
        });
        lines.push(line_no);
    }
    if animations.len() < NUM_ANIMATIONS {
        return Err(Md3Error::AnimationMissing {
            found: animations.len(),
            needed: NUM_ANIMATIONS,
        });
    }

    // The file numbers legs frames as if the torso-only animations were in the lower model too.
    let legs_offset = i64::from(animations[AnimationId::LegsWalkCr as usize].first_frame)
        - i64::from(animations[AnimationId::TorsoGesture as usize].first_frame);
    for id in AnimationId::ALL.into_iter().filter(|id| id.is_legs_only()) {
        let anim = &mut animations[id as usize];
        let corrected = i64::from(anim.first_frame) - legs_offset;
        anim.first_frame = u32::try_from(corrected).map_err(|_| Md3Error::AnimationSyntax {
            line: lines[id as usize],
            reason: format!(
                "{} first frame {} minus the legs offset {legs_offset} is negative",
                id.name(),
                anim.first_frame
            ),
        })?;
    }
    Ok(AnimationCfg {
        animations,
        legs_offset,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    // --- A minimal MD3 writer, laying records out in file order. ---

    struct TestSurface {
        name: &'static str,
        frames: i32,
        shaders: Vec<&'static str>,
        triangles: Vec<[i32; 3]>,
        st: Vec<[f32; 2]>,
        num_verts: usize,
        /// Frame-major (x, y, z, encoded normal).
        xyz: Vec<([i16; 3], u16)>,
    }

    /// (mins, maxs, origin, radius, name).
    type TestFrame = ([f32; 3], [f32; 3], [f32; 3], f32, &'static str);
    /// (name, origin, axes).
    type TestTag = (&'static str, [f32; 3], [[f32; 3]; 3]);

    struct TestModel {
        name: &'static str,
        frames: Vec<TestFrame>,
        num_tags: usize,
        /// Frame-major.
        tags: Vec<TestTag>,
        surfaces: Vec<TestSurface>,
    }

    fn put_i32(b: &mut Vec<u8>, v: i32) {
        b.extend_from_slice(&v.to_le_bytes());
    }
    fn put_f32(b: &mut Vec<u8>, v: f32) {
        b.extend_from_slice(&v.to_le_bytes());
    }
    fn put_name(b: &mut Vec<u8>, s: &str, len: usize) {
        let mut field = vec![0u8; len];
        field[..s.len()].copy_from_slice(s.as_bytes());
        b.extend_from_slice(&field);
    }
    fn put_vec(b: &mut Vec<u8>, v: [f32; 3]) {
        v.iter().for_each(|&x| put_f32(b, x));
    }

    impl TestSurface {
        fn to_bytes(&self) -> Vec<u8> {
            let ofs_tri = SURFACE_HEADER_SIZE;
            let ofs_shaders = ofs_tri + TRIANGLE_SIZE * self.triangles.len();
            let ofs_st = ofs_shaders + SHADER_SIZE * self.shaders.len();
            let ofs_xyz = ofs_st + ST_SIZE * self.st.len();
            let ofs_end = ofs_xyz + XYZ_NORMAL_SIZE * self.xyz.len();
            let mut b = Vec::new();
            b.extend_from_slice(b"IDP3");
            put_name(&mut b, self.name, NAME_LEN);
            put_i32(&mut b, 0);
            put_i32(&mut b, self.frames);
            put_i32(&mut b, self.shaders.len() as i32);
            put_i32(&mut b, self.num_verts as i32);
            put_i32(&mut b, self.triangles.len() as i32);
            for ofs in [ofs_tri, ofs_shaders, ofs_st, ofs_xyz, ofs_end] {
                put_i32(&mut b, ofs as i32);
            }
            for t in &self.triangles {
                t.iter().for_each(|&i| put_i32(&mut b, i));
            }
            for (i, s) in self.shaders.iter().enumerate() {
                put_name(&mut b, s, NAME_LEN);
                put_i32(&mut b, i as i32);
            }
            for uv in &self.st {
                uv.iter().for_each(|&x| put_f32(&mut b, x));
            }
            for (p, n) in &self.xyz {
                p.iter().for_each(|c| b.extend_from_slice(&c.to_le_bytes()));
                b.extend_from_slice(&n.to_le_bytes());
            }
            assert_eq!(b.len(), ofs_end);
            b
        }
    }

    impl TestModel {
        fn to_bytes(&self) -> Vec<u8> {
            let ofs_frames = HEADER_SIZE;
            let ofs_tags = ofs_frames + FRAME_SIZE * self.frames.len();
            let ofs_surfaces = ofs_tags + TAG_SIZE * self.tags.len();
            let surfaces: Vec<u8> = self.surfaces.iter().flat_map(|s| s.to_bytes()).collect();
            let ofs_end = ofs_surfaces + surfaces.len();
            let mut b = Vec::new();
            b.extend_from_slice(b"IDP3");
            put_i32(&mut b, 15);
            put_name(&mut b, self.name, NAME_LEN);
            put_i32(&mut b, 0);
            put_i32(&mut b, self.frames.len() as i32);
            put_i32(&mut b, self.num_tags as i32);
            put_i32(&mut b, self.surfaces.len() as i32);
            put_i32(&mut b, 0);
            for ofs in [ofs_frames, ofs_tags, ofs_surfaces, ofs_end] {
                put_i32(&mut b, ofs as i32);
            }
            for (mins, maxs, origin, radius, name) in &self.frames {
                put_vec(&mut b, *mins);
                put_vec(&mut b, *maxs);
                put_vec(&mut b, *origin);
                put_f32(&mut b, *radius);
                put_name(&mut b, name, 16);
            }
            for (name, origin, axes) in &self.tags {
                put_name(&mut b, name, NAME_LEN);
                put_vec(&mut b, *origin);
                axes.iter().for_each(|a| put_vec(&mut b, *a));
            }
            b.extend_from_slice(&surfaces);
            assert_eq!(b.len(), ofs_end);
            b
        }
    }

    const IDENTITY_AXES: [[f32; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    /// 90° about +Z: x → y, y → -x.
    const ROT_Z90: [[f32; 3]; 3] = [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];

    /// 2 frames, 1 tag, 1 surface of 4 vertices and 2 triangles.
    fn sample() -> TestModel {
        TestModel {
            name: "models/test/box.md3",
            frames: vec![
                ([-1.0, -2.0, -3.0], [4.0, 5.0, 6.0], [0.0; 3], 7.5, "first"),
                (
                    [-8.0, 0.0, 0.0],
                    [8.0, 1.0, 2.0],
                    [0.5, 0.0, 0.0],
                    9.25,
                    "second",
                ),
            ],
            num_tags: 1,
            tags: vec![
                ("tag_torso", [1.0, 2.0, 3.0], IDENTITY_AXES),
                ("tag_torso", [10.0, 0.0, 5.0], ROT_Z90),
            ],
            surfaces: vec![TestSurface {
                name: "body",
                frames: 2,
                shaders: vec!["models/test/body.tga"],
                triangles: vec![[0, 1, 2], [2, 1, 3]],
                st: vec![[0.0, 0.0], [1.0, 0.0], [0.25, 0.75], [1.0, 1.0]],
                num_verts: 4,
                xyz: vec![
                    ([64, 0, 0], 0x0000),
                    ([0, 128, 0], 0x0040),
                    ([0, 0, -32], 0x4040),
                    ([100, -200, 300], 0x8080),
                    ([-64, 0, 0], 0x0000),
                    ([0, -128, 0], 0x0000),
                    ([0, 0, 32], 0x0000),
                    ([1, -1, 32767], 0x0000),
                ],
            }],
        }
    }

    /// Compares in f64 so the expectations can carry their full hand-computed precision.
    fn assert_vec(actual: Vec3, expected: [f64; 3], tol: f64) {
        let a = actual.as_dvec3().to_array();
        let err = (0..3)
            .map(|i| (a[i] - expected[i]).abs())
            .fold(0.0, f64::max);
        assert!(err <= tol, "{actual:?} != {expected:?} (tolerance {tol})");
    }

    #[test]
    fn parses_sample_exactly() {
        let md3 = parse(&sample().to_bytes()).unwrap();
        assert_eq!(md3.name, "models/test/box.md3");
        assert_eq!(md3.num_frames(), 2);
        assert_eq!(md3.frames[0].name, "first");
        assert_eq!(md3.frames[0].mins, Vec3::new(-1.0, -2.0, -3.0));
        assert_eq!(md3.frames[0].maxs, Vec3::new(4.0, 5.0, 6.0));
        assert_eq!(md3.frames[0].radius, 7.5);
        assert_eq!(md3.frames[1].name, "second");
        assert_eq!(md3.frames[1].local_origin, Vec3::new(0.5, 0.0, 0.0));
        assert_eq!(md3.frames[1].radius, 9.25);
        assert_eq!(md3.frames[1].bounds().max, Vec3::new(8.0, 1.0, 2.0));

        assert_eq!(md3.tag_names, vec!["tag_torso".to_string()]);
        assert_eq!(md3.tags.len(), 2);
        let t0 = md3.tag(0, "tag_torso").unwrap();
        assert_eq!(t0.origin, Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(t0.axis, [Vec3::X, Vec3::Y, Vec3::Z]);
        let t1 = md3.tag(1, "tag_torso").unwrap();
        assert_eq!(t1.origin, Vec3::new(10.0, 0.0, 5.0));
        assert_eq!(t1.axis, [Vec3::Y, Vec3::NEG_X, Vec3::Z]);
        assert!(md3.tag(2, "tag_torso").is_none());
        assert!(md3.tag(0, "tag_head").is_none());

        assert_eq!(md3.surfaces.len(), 1);
        let s = &md3.surfaces[0];
        assert_eq!(s.name, "body");
        assert_eq!(s.shaders, vec!["models/test/body.tga".to_string()]);
        assert_eq!(s.triangles, vec![[0, 1, 2], [2, 1, 3]]);
        assert_eq!(s.st, vec![[0.0, 0.0], [1.0, 0.0], [0.25, 0.75], [1.0, 1.0]]);
        assert_eq!(s.num_verts, 4);
        assert_eq!(s.positions.len(), 8);
        assert_eq!(
            s.frame_positions(0).unwrap(),
            &[
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(0.0, 2.0, 0.0),
                Vec3::new(0.0, 0.0, -0.5),
                Vec3::new(1.5625, -3.125, 4.6875),
            ]
        );
        assert_eq!(
            s.frame_positions(1).unwrap(),
            &[
                Vec3::new(-1.0, 0.0, 0.0),
                Vec3::new(0.0, -2.0, 0.0),
                Vec3::new(0.0, 0.0, 0.5),
                Vec3::new(0.015625, -0.015625, 32767.0 / 64.0),
            ]
        );
        assert!(s.frame_positions(2).is_none());
        assert_eq!(s.normals[0], Vec3::Z);
        assert_vec(s.normals[1], [0.999_981_03, 0.0, -0.006_159_947], 1e-6);
    }

    #[test]
    fn decodes_normals() {
        // (cos lat · sin lng, sin lat · sin lng, cos lng), angles in steps of 2π/255; the
        // expectations were computed in double precision.
        assert_eq!(decode_normal(0x0000), Vec3::new(0.0, 0.0, 1.0));
        // lat 0, lng 64: angle 64·2π/255 = 1.5769563 rad, sin 0.9999810, cos -0.0061599.
        assert_vec(
            decode_normal(0x0040),
            [0.999_981_027_3, 0.0, -0.006_159_946_6],
            1e-6,
        );
        // lat 64, lng 64.
        assert_vec(
            decode_normal(0x4040),
            [-0.006_159_829_8, 0.999_962_055_1, -0.006_159_946_6],
            1e-6,
        );
        // lat 128, lng 128: angle 3.1539126 rad.
        assert_vec(
            decode_normal(0x8080),
            [0.012_318_724_6, 0.000_151_774_0, -0.999_924_110_1],
            1e-6,
        );
        // lat 0, lng 128.
        assert_vec(
            decode_normal(0x0080),
            [-0.012_319_659_5, 0.0, -0.999_924_110_1],
            1e-6,
        );
        // lat 192, lng 32.
        assert_vec(
            decode_normal(0xC020),
            [0.013_106_741_9, -0.709_160_198_1, 0.704_925_546_9],
            1e-6,
        );
        for e in [0x0000u16, 0x1234, 0xFFFF, 0x80FF] {
            assert!((decode_normal(e).length() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn tag_matrix_places_child_vertex() {
        let tag = Tag {
            name: "tag_torso".to_string(),
            origin: Vec3::new(10.0, 0.0, 5.0),
            axis: [Vec3::Y, Vec3::NEG_X, Vec3::Z],
        };
        let m = tag.matrix();
        assert_vec(m.transform_point3(Vec3::X), [10.0, 1.0, 5.0], 1e-6);
        assert_vec(m.transform_point3(Vec3::Y), [9.0, 0.0, 5.0], 1e-6);

        let md3 = parse(&sample().to_bytes()).unwrap();
        let placed = place_model(&md3, 0, m).unwrap();
        assert_eq!(placed.len(), 1);
        assert_eq!(placed[0].part, "models/test/box.md3");
        let v = &placed[0].vertices;
        // (1,0,0) → (10,1,5); (0,2,0) → (8,0,5).
        assert_vec(v[0].pos(), [10.0, 1.0, 5.0], 1e-6);
        assert_vec(v[1].pos(), [8.0, 0.0, 5.0], 1e-6);
        // Normals rotate too: (0.99998, 0, -0.00616) → (0, 0.99998, -0.00616).
        assert_vec(Vec3::from(v[0].normal), [0.0, 0.0, 1.0], 1e-6);
        assert_vec(
            Vec3::from(v[1].normal),
            [0.0, 0.999_981_027_3, -0.006_159_946_6],
            1e-6,
        );
        assert_eq!(v[2].uv, [0.25, 0.75]);
        assert_eq!(v[2].lightmap_uv, [0.0, 0.0]);
    }

    #[test]
    fn normals_use_inverse_transpose() {
        let md3 = parse(&sample().to_bytes()).unwrap();
        // Stretching x by 2 shrinks normals' x by 2: (0.99998, 0, -0.00616) → (0.49999, 0,
        // -0.00616), length 0.5000285, normalized (0.9999241, 0, -0.0123192).
        let placed = place_model(&md3, 0, Mat4::from_scale(Vec3::new(2.0, 1.0, 1.0))).unwrap();
        let v = &placed[0].vertices;
        assert_vec(v[0].pos(), [2.0, 0.0, 0.0], 1e-6);
        assert_vec(
            Vec3::from(v[1].normal),
            [0.999_924_116, 0.0, -0.012_319_192],
            1e-6,
        );
        // A singular transform gives zero normals instead of NaN.
        let placed = place_model(&md3, 0, Mat4::from_scale(Vec3::new(0.0, 1.0, 1.0))).unwrap();
        assert_eq!(placed[0].vertices[1].normal, [0.0, 0.0, 0.0]);
    }

    #[test]
    fn winding_is_flipped_to_counter_clockwise() {
        let md3 = parse(&sample().to_bytes()).unwrap();
        let placed = place_model(&md3, 1, Mat4::IDENTITY).unwrap();
        assert_eq!(placed[0].indices, vec![0, 2, 1, 2, 3, 1]);
        assert_eq!(placed[0].shader, "models/test/body.tga");
        assert_eq!(placed[0].surface_name, "body");
        assert_vec(placed[0].vertices[0].pos(), [-1.0, 0.0, 0.0], 0.0);
    }

    /// A one-surface, one-frame part with a vertex at (1,0,0) and the given tags.
    fn part(name: &'static str, tags: Vec<TestTag>, frames: usize) -> Md3 {
        let num_tags = tags.len() / frames;
        let model = TestModel {
            name,
            frames: vec![([0.0; 3], [1.0; 3], [0.0; 3], 1.0, "f"); frames],
            num_tags,
            tags,
            surfaces: vec![TestSurface {
                name,
                frames: frames as i32,
                shaders: vec![],
                triangles: vec![[0, 1, 2]],
                st: vec![[0.0, 0.0]; 3],
                num_verts: 3,
                xyz: [([64i16, 0, 0], 0u16), ([0, 64, 0], 0), ([0, 0, 64], 0)].repeat(frames),
            }],
        };
        parse(&model.to_bytes()).unwrap()
    }

    #[test]
    fn assembles_player_through_tags() {
        let lower = part(
            "lower",
            vec![
                ("tag_torso", [0.0, 0.0, 99.0], IDENTITY_AXES),
                ("tag_torso", [10.0, 0.0, 5.0], ROT_Z90),
            ],
            2,
        );
        let upper = part(
            "upper",
            vec![("tag_head", [0.0, 0.0, 20.0], IDENTITY_AXES)],
            1,
        );
        let head = part("head", vec![], 1);
        let placed = assemble_player(&lower, &upper, &head, 1, 0).unwrap();
        let parts: Vec<&str> = placed.iter().map(|p| p.part.as_str()).collect();
        assert_eq!(parts, ["lower", "upper", "head"]);
        assert_eq!(placed[2].shader, "");
        // Lower at identity.
        assert_vec(placed[0].vertices[0].pos(), [1.0, 0.0, 0.0], 0.0);
        // Upper: rotZ90 then + (10,0,5): (1,0,0) → (10,1,5), (0,0,1) → (10,0,6).
        assert_vec(placed[1].vertices[0].pos(), [10.0, 1.0, 5.0], 1e-6);
        assert_vec(placed[1].vertices[2].pos(), [10.0, 0.0, 6.0], 1e-6);
        // Head: (1,0,0) + (0,0,20) = (1,0,20), then rotZ90 + (10,0,5) → (10,1,25).
        assert_vec(placed[2].vertices[0].pos(), [10.0, 1.0, 25.0], 1e-6);
        assert_vec(placed[2].vertices[1].pos(), [9.0, 0.0, 25.0], 1e-6);

        // Legs frame 0 uses the other tag: (1,0,0) + (0,0,99).
        let placed = assemble_player(&lower, &upper, &head, 0, 0).unwrap();
        assert_vec(placed[1].vertices[0].pos(), [1.0, 0.0, 99.0], 1e-6);

        assert_eq!(
            assemble_player(&lower, &upper, &head, 2, 0),
            Err(Md3Error::FrameOutOfRange {
                part: "lower".to_string(),
                frame: 2,
                frames: 2
            })
        );
        assert_eq!(
            assemble_player(&lower, &upper, &head, 0, 1),
            Err(Md3Error::FrameOutOfRange {
                part: "upper".to_string(),
                frame: 1,
                frames: 1
            })
        );
        assert_eq!(
            assemble_player(&upper, &upper, &head, 0, 0),
            Err(Md3Error::MissingTag {
                part: "lower".to_string(),
                tag: "tag_torso".to_string()
            })
        );
        assert_eq!(
            assemble_player(&lower, &head, &head, 0, 0),
            Err(Md3Error::MissingTag {
                part: "upper".to_string(),
                tag: "tag_head".to_string()
            })
        );
        assert!(matches!(
            place_model(&head, 1, Mat4::IDENTITY),
            Err(Md3Error::FrameOutOfRange {
                frame: 1,
                frames: 1,
                ..
            })
        ));
    }

    fn patch_i32(b: &mut [u8], at: usize, v: i32) {
        b[at..at + 4].copy_from_slice(&v.to_le_bytes());
    }

    // Layout of the sample: header 0..108, frames 108..220, tags 220..444, surface 444..740
    // (its triangles at +108, shaders +132, st +200, xyzNormals +232).
    const SURFACE: usize = 444;

    #[test]
    fn sample_layout_is_as_documented() {
        let b = sample().to_bytes();
        assert_eq!(b.len(), 740);
        assert_eq!(&b[SURFACE..SURFACE + 4], b"IDP3");
    }

    #[test]
    fn every_truncation_is_an_error() {
        let b = sample().to_bytes();
        for len in 0..b.len() {
            match parse(&b[..len]) {
                Err(Md3Error::Truncated { .. }) | Err(Md3Error::OffsetOutOfRange { .. }) => {}
                other => panic!("prefix of {len} bytes gave {other:?}"),
            }
        }
        assert_eq!(
            parse(&b[..3]),
            Err(Md3Error::Truncated {
                what: "header".to_string(),
                offset: 0,
                needed: 108,
                len: 3
            })
        );
        assert_eq!(
            parse(&b[..150]),
            Err(Md3Error::Truncated {
                what: "frames".to_string(),
                offset: 108,
                needed: 112,
                len: 150
            })
        );
        assert_eq!(
            parse(&b[..300]),
            Err(Md3Error::Truncated {
                what: "tags".to_string(),
                offset: 220,
                needed: 224,
                len: 300
            })
        );
        assert_eq!(
            parse(&b[..500]),
            Err(Md3Error::Truncated {
                what: "surface 0 header".to_string(),
                offset: 444,
                needed: 108,
                len: 500
            })
        );
        assert_eq!(
            parse(&b[..700]),
            Err(Md3Error::Truncated {
                what: "surface 0".to_string(),
                offset: 444,
                needed: 296,
                len: 700
            })
        );
    }

    #[test]
    fn rejects_bad_magic_and_version() {
        let mut b = sample().to_bytes();
        b[0..4].copy_from_slice(b"IDP2");
        assert_eq!(
            parse(&b),
            Err(Md3Error::BadMagic {
                what: "header".to_string(),
                found: *b"IDP2"
            })
        );
        let mut b = sample().to_bytes();
        patch_i32(&mut b, 4, 16);
        assert_eq!(parse(&b), Err(Md3Error::BadVersion(16)));
        let mut b = sample().to_bytes();
        b[SURFACE..SURFACE + 4].copy_from_slice(b"XXXX");
        assert_eq!(
            parse(&b),
            Err(Md3Error::BadMagic {
                what: "surface 0".to_string(),
                found: *b"XXXX"
            })
        );
    }

    #[test]
    fn rejects_absurd_counts() {
        let cases = [
            (76, 2_000_000_000, "numFrames", MAX_FRAMES),
            (76, -1, "numFrames", MAX_FRAMES),
            (80, 17, "numTags", MAX_TAGS),
            (80, i32::MIN, "numTags", MAX_TAGS),
            (84, 33, "numSurfaces", MAX_SURFACES),
            (84, -5, "numSurfaces", MAX_SURFACES),
            (SURFACE + 76, 257, "surface 0 numShaders", MAX_SHADERS),
            (SURFACE + 80, 4097, "surface 0 numVerts", MAX_VERTS),
            (SURFACE + 84, -3, "surface 0 numTriangles", MAX_TRIANGLES),
            (SURFACE + 84, 8193, "surface 0 numTriangles", MAX_TRIANGLES),
        ];
        for (at, value, what, max) in cases {
            let mut b = sample().to_bytes();
            patch_i32(&mut b, at, value);
            assert_eq!(
                parse(&b),
                Err(Md3Error::CountOutOfRange {
                    what: what.to_string(),
                    value,
                    max
                }),
                "{what} = {value}"
            );
        }
        // In range but more than the file holds: caught before allocating.
        let mut b = sample().to_bytes();
        patch_i32(&mut b, 76, 1000);
        assert!(matches!(parse(&b), Err(Md3Error::Truncated { what, .. }) if what == "frames"));
        let mut b = sample().to_bytes();
        patch_i32(&mut b, SURFACE + 80, 4096);
        assert!(matches!(
            parse(&b),
            Err(Md3Error::Truncated { what, .. }) if what == "surface 0 st"
        ));
    }

    #[test]
    fn rejects_offsets_outside_the_file() {
        let mut b = sample().to_bytes();
        patch_i32(&mut b, 100, 5000);
        assert_eq!(
            parse(&b),
            Err(Md3Error::OffsetOutOfRange {
                what: "surface 0 header offset".to_string(),
                offset: 5000,
                min: 0,
                max: 740
            })
        );
        let mut b = sample().to_bytes();
        patch_i32(&mut b, 92, -8);
        assert!(matches!(
            parse(&b),
            Err(Md3Error::OffsetOutOfRange { offset: -8, .. })
        ));
        // A surface sub-record pointing past its surface record.
        let mut b = sample().to_bytes();
        patch_i32(&mut b, SURFACE + 100, 297);
        assert_eq!(
            parse(&b),
            Err(Md3Error::OffsetOutOfRange {
                what: "surface 0 xyzNormals offset".to_string(),
                offset: 297,
                min: 0,
                max: 296
            })
        );
        let mut b = sample().to_bytes();
        patch_i32(&mut b, SURFACE + 100, 240);
        assert_eq!(
            parse(&b),
            Err(Md3Error::Truncated {
                what: "surface 0 xyzNormals".to_string(),
                offset: SURFACE + 240,
                needed: 64,
                len: 740
            })
        );
        // A surface record smaller than its header, or larger than the file.
        let mut b = sample().to_bytes();
        patch_i32(&mut b, SURFACE + 104, 0);
        assert!(matches!(
            parse(&b),
            Err(Md3Error::OffsetOutOfRange { what, offset: 0, .. }) if what == "surface 0 ofsEnd"
        ));
        let mut b = sample().to_bytes();
        patch_i32(&mut b, SURFACE + 104, 1000);
        assert!(matches!(
            parse(&b),
            Err(Md3Error::Truncated { what, needed: 1000, .. }) if what == "surface 0"
        ));
        // The header's ofsEnd.
        let mut b = sample().to_bytes();
        patch_i32(&mut b, 104, 741);
        assert!(matches!(
            parse(&b),
            Err(Md3Error::OffsetOutOfRange { what, offset: 741, .. }) if what == "ofsEnd"
        ));
    }

    #[test]
    fn rejects_bad_surface_contents() {
        let mut model = sample();
        model.surfaces[0].triangles[1] = [2, 1, 4];
        assert_eq!(
            parse(&model.to_bytes()),
            Err(Md3Error::IndexOutOfRange {
                surface: 0,
                triangle: 1,
                index: 4,
                verts: 4
            })
        );
        let mut model = sample();
        model.surfaces[0].triangles[0] = [-1, 1, 2];
        assert!(matches!(
            parse(&model.to_bytes()),
            Err(Md3Error::IndexOutOfRange { index: -1, .. })
        ));
        let mut model = sample();
        model.surfaces[0].frames = 1;
        assert_eq!(
            parse(&model.to_bytes()),
            Err(Md3Error::FrameCountMismatch {
                surface: 0,
                found: 1,
                expected: 2
            })
        );
        let mut model = sample();
        model.surfaces[0].st[3] = [f32::INFINITY, 0.0];
        assert_eq!(
            parse(&model.to_bytes()),
            Err(Md3Error::NonFinite {
                what: "surface 0 st 3".to_string()
            })
        );
    }

    #[test]
    fn rejects_non_finite_floats() {
        let mut model = sample();
        model.tags[1].1 = [0.0, f32::NAN, 0.0];
        assert_eq!(
            parse(&model.to_bytes()),
            Err(Md3Error::NonFinite {
                what: "tag 0 (`tag_torso`) of frame 1".to_string()
            })
        );
        let mut model = sample();
        model.tags[0].2[2][1] = f32::NAN;
        assert!(matches!(
            parse(&model.to_bytes()),
            Err(Md3Error::NonFinite { .. })
        ));
        let mut model = sample();
        model.frames[1].3 = f32::NEG_INFINITY;
        assert_eq!(
            parse(&model.to_bytes()),
            Err(Md3Error::NonFinite {
                what: "frame 1 radius".to_string()
            })
        );
    }

    #[test]
    fn garbage_never_panics() {
        // Deterministic pseudo-random bytes behind a valid header prefix, and a sample with
        // single bytes overwritten: every outcome must be a value, not a panic.
        let mut seed = 0x1234_5678u32;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            seed
        };
        let valid = sample().to_bytes();
        let mut errors = 0;
        for i in 0..2000 {
            let mut b = valid.clone();
            let at = next() as usize % b.len();
            b[at] = next() as u8;
            if i % 2 == 0 {
                let at = next() as usize % b.len();
                b[at] = next() as u8;
            }
            if parse(&b).is_err() {
                errors += 1;
            }
        }
        // Changed bytes in offsets, counts and names are spread over the file; many are errors.
        assert!(
            errors > 100,
            "only {errors} of 2000 corruptions were errors"
        );
    }

    #[test]
    fn parses_skins() {
        let text = "tag_head,\r\n\
                    h_Head,models/players/test/head.tga\r\n\
                    \n\
                    h_visor , models/players/test/visor.tga  \n\
                    h_empty,\n\
                    no comma here\n\
                    H_HEAD,models/players/test/head_red.tga\n";
        let skin = parse_skin(text);
        assert_eq!(skin.entries.len(), 2);
        assert_eq!(
            skin.shader_for("h_head"),
            Some("models/players/test/head_red.tga")
        );
        assert_eq!(
            skin.shader_for("H_Visor"),
            Some("models/players/test/visor.tga")
        );
        assert_eq!(skin.shader_for("h_empty"), None);
        assert_eq!(skin.shader_for("tag_head"), None);
        assert_eq!(skin.shader_for("missing"), None);
    }

    const SAMPLE_CFG: &str = "// test player animations\r\n\
        sex m\r\n\
        headoffset 0 0 0\n\
        footsteps boot\n\
        fixedtorso\n\
        \n\
        0\t30\t0\t25\t\t// BOTH_DEATH1\n\
        29\t1\t1\t25\n\
        30\t30\t0\t25\n\
        59\t1\t1\t25\n\
        60\t30\t0\t25\n\
        89\t1\t1\t25\n\
        90\t40\t0\t20\t// TORSO_GESTURE\n\
        130\t6\t0\t15\n\
        136\t6\t0\t15\n\
        142\t5\t0\t20\n\
        147\t4\t0\t20\n\
        151\t1\t0\t15\t// TORSO_STAND\n\
        152\t1\t0\t15\n\
        153\t8\t8\t20\t// LEGS_WALKCR\n\
        161\t12\t12\t20\n\
        173\t9\t9\t18\n\
        182\t10\t10\t20\n\
        192\t10\t10\t15\n\
        202\t8\t0\t15\n\
        210\t1\t0\t15\n\
        211\t8\t0\t15\n\
        219\t1\t0\t15\n\
        220\t10\t10\t15\t// LEGS_IDLE\n\
        230\t-10\t10\t15\n\
        240\t7\t7\t15\r\n\
        250\t5\t0\t15\t// an extra (Team Arena) torso animation\n";

    #[test]
    fn parses_animation_cfg() {
        let cfg = parse_animation_cfg(SAMPLE_CFG).unwrap();
        assert_eq!(cfg.animations().len(), 26);
        // LEGS_WALKCR (153) - TORSO_GESTURE (90).
        assert_eq!(cfg.legs_offset(), 63);
        assert_eq!(cfg.torso_stand_frame(), 151);
        // 220 - 63.
        assert_eq!(cfg.legs_idle_frame(), 157);
        assert_eq!(
            *cfg.get(AnimationId::BothDeath1),
            Animation {
                first_frame: 0,
                num_frames: 30,
                looping_frames: 0,
                fps: 25,
                reversed: false
            }
        );
        // Both-models animations keep their numbers; legs ones are shifted.
        assert_eq!(cfg.get(AnimationId::BothDead3).first_frame, 89);
        assert_eq!(cfg.get(AnimationId::TorsoGesture).first_frame, 90);
        assert_eq!(cfg.get(AnimationId::LegsWalkCr).first_frame, 90);
        assert_eq!(
            *cfg.get(AnimationId::LegsRun),
            Animation {
                first_frame: 110,
                num_frames: 9,
                looping_frames: 9,
                fps: 18,
                reversed: false
            }
        );
        let idle_cr = cfg.get(AnimationId::LegsIdleCr);
        assert_eq!((idle_cr.first_frame, idle_cr.num_frames), (167, 10));
        assert!(idle_cr.reversed);
        assert_eq!(cfg.get(AnimationId::LegsTurn).first_frame, 177);
        assert_eq!(cfg.animations()[25].first_frame, 250);
        assert_eq!(AnimationId::LegsIdle.name(), "LEGS_IDLE");
        assert_eq!(AnimationId::ALL[22], AnimationId::LegsIdle);
        assert!(AnimationId::LegsWalkCr.is_legs_only());
        assert!(!AnimationId::TorsoStand2.is_legs_only());
    }

    #[test]
    fn rejects_bad_animation_cfg() {
        let first_24: String = SAMPLE_CFG
            .lines()
            .take(30)
            .map(|l| format!("{l}\n"))
            .collect();
        assert_eq!(
            parse_animation_cfg(&first_24),
            Err(Md3Error::AnimationMissing {
                found: 24,
                needed: 25
            })
        );
        let bad_number = SAMPLE_CFG.replace("142\t5\t0\t20", "142\tfive\t0\t20");
        assert_eq!(
            parse_animation_cfg(&bad_number),
            Err(Md3Error::AnimationSyntax {
                line: 16,
                reason: "`five` is not an integer".to_string()
            })
        );
        let short = SAMPLE_CFG.replace("142\t5\t0\t20", "142\t5");
        assert!(matches!(
            parse_animation_cfg(&short),
            Err(Md3Error::AnimationSyntax { line: 16, .. })
        ));
        let negative_fps = SAMPLE_CFG.replace("142\t5\t0\t20", "142\t5\t0\t-20");
        assert!(matches!(
            parse_animation_cfg(&negative_fps),
            Err(Md3Error::AnimationSyntax { line: 16, .. })
        ));
        // A legs animation numbered below the offset cannot be corrected.
        let too_low = SAMPLE_CFG.replace("220\t10\t10\t15", "20\t10\t10\t15");
        assert!(matches!(
            parse_animation_cfg(&too_low),
            Err(Md3Error::AnimationSyntax { line: 29, .. })
        ));
    }
}
