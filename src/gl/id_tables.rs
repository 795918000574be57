//! Per-triangle tables for ID and priority buffers (`shadow_map.buffer`), as RGBA32F textures
//! the depth and lit passes read at `u_tri_base + gl_PrimitiveID` (the triangle's place in the
//! GPU index buffer). The IDs and priorities come from `shadow::parts` (GL-free); this only
//! reorders them into the GPU's triangle order, uploads them, and keeps them while their key
//! holds: the ID table per scene geometry, a priority table per light and pose.

use crate::geometry::Aabb;
use crate::gl::upload::GpuScene;
use crate::options::{IdUnit, MapBuffer};
use crate::scene::{Scene, SurfaceOwner};
use crate::shadow::parts;
use glow::HasContext;
use std::collections::HashMap;

/// Texels per table row (`TABLE_WIDTH` in the shaders).
pub const TABLE_WIDTH: usize = 1024;

struct Table {
    key: u64,
    texture: glow::Texture,
}

/// The tables, each kept until its key changes.
#[derive(Default)]
pub struct IdTables {
    /// Each triangle's ID, scene index order, for (scene revision, unit).
    ids: Option<((u64, IdUnit), Vec<u32>, u32)>,
    /// By light (priority buffers) or `usize::MAX` (the ID buffer's one table).
    tables: HashMap<usize, Table>,
    /// Tables uploaded since the last `take_uploads`.
    uploads: usize,
}

fn hash(parts: &[u64]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for p in parts {
        for b in p.to_le_bytes() {
            h ^= b as u64;
            h = h.wrapping_mul(0x100_0000_01b3);
        }
    }
    h
}

impl IdTables {
    /// Each triangle's ID for `unit` (computed once per scene geometry).
    fn ids(&mut self, scene: &Scene, unit: IdUnit) -> (&[u32], u32) {
        let key = (scene.revision(), unit);
        if self.ids.as_ref().is_none_or(|(k, _, _)| *k != key) {
            let (ids, n) = parts::triangle_ids(scene, unit);
            self.ids = Some((key, ids, n));
        }
        let (_, ids, n) = self.ids.as_ref().expect("just set");
        (ids, *n)
    }

    /// The table `buffer` needs for `light`: IDs (one table for every light) or priorities
    /// from the light's position. None for depth maps. The flag says the table changed since
    /// the light's maps were drawn with it: they must be drawn again.
    pub fn table(
        &mut self,
        gl: &glow::Context,
        scene: &Scene,
        gpu: &GpuScene,
        buffer: MapBuffer,
        unit: IdUnit,
        light: usize,
    ) -> Result<(Option<glow::Texture>, bool), String> {
        let slot = match buffer {
            MapBuffer::Depth => return Ok((None, false)),
            MapBuffer::Id => usize::MAX,
            MapBuffer::Priority | MapBuffer::PriorityDepth => light,
        };
        let mut key = vec![scene.revision(), unit as u64, slot as u64];
        if slot != usize::MAX {
            // Ranks depend on the light and on what moves within its range only (a model whose box
            // reaches the range: at worst a table made again that did not need to be).
            let l = &scene.lights[light];
            key.extend(l.position.to_array().map(|c| c.to_bits() as u64));
            key.push(l.radius.to_bits() as u64);
            let boxes = model_boxes(scene);
            key.extend(
                scene
                    .models
                    .iter()
                    .zip(&boxes)
                    .filter(|(_, b)| {
                        !b.is_empty()
                            && l.position.clamp(b.min, b.max).distance(l.position) < l.radius
                    })
                    .map(|(model, _)| model.pose),
            );
        }
        let key = hash(&key);
        if let Some(t) = self.tables.get(&slot)
            && t.key == key
        {
            return Ok((Some(t.texture), false));
        }
        let position = scene.lights.get(light).map(|l| (l.position, l.radius));
        let (ids, units) = self.ids(scene, unit);
        let entries: Vec<[f32; 4]> = match (slot, position) {
            (usize::MAX, _) | (_, None) => {
                ids.iter().map(|&id| [id as f32, 0.0, 0.0, 0.0]).collect()
            }
            (_, Some((at, radius))) => parts::priority_entries(scene, ids, units, at, radius),
        };
        let texels = in_gpu_order(scene, gpu, &entries);
        let texture = match self.tables.remove(&slot) {
            Some(old) => old.texture,
            // SAFETY: a new texture of our own.
            None => unsafe { gl.create_texture()? },
        };
        upload(gl, texture, &texels);
        self.uploads += 1;
        self.tables.insert(slot, Table { key, texture });
        Ok((Some(texture), true))
    }

    /// Tables uploaded since the last call.
    pub fn take_uploads(&mut self) -> usize {
        std::mem::take(&mut self.uploads)
    }

    pub fn delete(&mut self, gl: &glow::Context) {
        for (_, t) in self.tables.drain() {
            // SAFETY: our texture, no longer used.
            unsafe { gl.delete_texture(t.texture) };
        }
        self.ids = None;
    }
}

/// Each model's box: the union of its surfaces' (one pass over the surfaces, not one per
/// model).
fn model_boxes(scene: &Scene) -> Vec<Aabb> {
    let mut boxes = vec![Aabb::EMPTY; scene.models.len()];
    for s in &scene.surfaces {
        if let SurfaceOwner::Model(m) = s.owner
            && let Some(b) = boxes.get_mut(m)
        {
            *b = b.union(&s.bounds);
        }
    }
    boxes
}

/// `entries` (scene index order) moved to the GPU index buffer's triangle order, padded to
/// whole rows.
fn in_gpu_order(scene: &Scene, gpu: &GpuScene, entries: &[[f32; 4]]) -> Vec<[f32; 4]> {
    let triangles = scene.indices.len() / 3;
    let rows = triangles.div_ceil(TABLE_WIDTH).max(1);
    let mut out = vec![[0.0f32; 4]; rows * TABLE_WIDTH];
    for (i, s) in scene.surfaces.iter().enumerate() {
        let from = s.first_index as usize / 3;
        let to = gpu.gpu_first_index(i) as usize / 3;
        let n = s.index_count as usize / 3;
        out[to..to + n].copy_from_slice(&entries[from..from + n]);
    }
    out
}

fn upload(gl: &glow::Context, texture: glow::Texture, texels: &[[f32; 4]]) {
    let rows = texels.len() / TABLE_WIDTH;
    let bytes: Vec<u8> = texels
        .iter()
        .flat_map(|t| t.iter().flat_map(|c| c.to_le_bytes()))
        .collect();
    // SAFETY: storage for our texture from a slice of the stated size.
    unsafe {
        gl.bind_texture(glow::TEXTURE_2D, Some(texture));
        gl.tex_image_2d(
            glow::TEXTURE_2D,
            0,
            glow::RGBA32F as i32,
            TABLE_WIDTH as i32,
            rows as i32,
            0,
            glow::RGBA,
            glow::FLOAT,
            glow::PixelUnpackData::Slice(Some(&bytes)),
        );
        for p in [glow::TEXTURE_MIN_FILTER, glow::TEXTURE_MAG_FILTER] {
            gl.tex_parameter_i32(glow::TEXTURE_2D, p, glow::NEAREST as i32);
        }
        gl.bind_texture(glow::TEXTURE_2D, None);
    }
}
