//! Building a light's parts (cached by key), laying out its vertex buffer and merging its parts
//! into the stencil pass's draw calls, each with its depth clip.

use super::{
    CachedPart, FitKey, Layout, LightVolumeDraws, PartRange, Piece, PieceChoices, PieceId,
    VolumeDraw, VolumeDrawError, VolumeStats, VolumeUpload, settings,
};
use crate::geometry::Aabb;
use crate::options::ShadowVolumeOptions;
use crate::plan::clipped::{ClipTest, block_bounds};
use crate::plan::depth_bounds::{DepthBound, EMPTY_RANGE, MAX_PLANES, range_union};
use crate::plan::occlusion::DepthPyramid;
use crate::plan::scissor::Scissor;
use crate::plan::{CameraSetup, LightPlan};
use crate::shadow::volume::{self, CasterGroups, Counting};
use glam::Mat4;
use std::collections::{HashMap, HashSet};
use std::hash::{DefaultHasher, Hash, Hasher};

/// The clip-space planes beyond which a depth-pass part's fragments cannot change a count
/// inside `rect`: they change counts only in front of the stored depth, so nothing behind a
/// bound on it there matters (the volume's sides running on behind the walls). Zero (no
/// clipping) where no bound is nearer than the far plane. Depth-fail parts get none: their
/// counts change behind the stored depth.
fn depth_clip(
    depth: &DepthPyramid,
    camera: &CameraSetup,
    rect: &Scissor,
    planes: usize,
) -> [[f32; 4]; MAX_PLANES] {
    DepthBound::fit(depth, camera, rect, planes).map_or([[0.0; 4]; MAX_PLANES], |b| b.clip_planes())
}

/// What one part's geometry depends on: the light, the build settings, its counting (caps) and
/// its caster's transform. A moving model changes only its own parts' keys.
fn part_key(
    light: glam::Vec3,
    o: &ShadowVolumeOptions,
    p: &Piece,
    model: &Mat4,
    receivers: u64,
) -> u64 {
    let mut h = DefaultHasher::new();
    receivers.hash(&mut h);
    light.to_array().map(f32::to_bits).hash(&mut h);
    (
        o.edge_rule as u8,
        o.extrusion as u8,
        o.finite_distance.to_bits(),
        o.facing_epsilon.to_bits(),
        p.group,
        p.id,
        p.subset_key,
        p.counting as u8,
    )
        .hash(&mut h);
    model.to_cols_array().map(f32::to_bits).hash(&mut h);
    h.finish()
}

/// Consecutive parts merged into draw calls where their counting, transform and rectangle agree
/// and their vertices are adjacent.
pub(super) fn draws_of(parts: &[PartRange]) -> Vec<VolumeDraw> {
    let mut draws: Vec<VolumeDraw> = Vec::new();
    for p in parts.iter().filter(|p| p.drawn()) {
        let (first, count) = p.elements.unwrap_or((p.first, p.sides + p.caps));
        let indexed = p.elements.is_some();
        match draws.last_mut() {
            Some(d)
                if d.counting == p.counting
                    && d.model == p.model
                    && d.scissor == p.scissor
                    && d.depth_clip == p.depth_clip
                    && d.depth_bounds == p.depth_bounds
                    && d.indexed == indexed
                    && d.first + d.count == first =>
            {
                d.count += count;
            }
            _ => draws.push(VolumeDraw {
                counting: p.counting,
                model: p.model,
                first,
                count,
                indexed,
                scissor: p.scissor,
                depth_clip: p.depth_clip,
                depth_bounds: p.depth_bounds,
            }),
        }
    }
    draws
}

/// Every draw and index stays inside what is uploaded (llvmpipe reads past a buffer
/// unchecked).
pub(super) fn check_bounds(
    light: usize,
    draws: &[VolumeDraw],
    indices: &[u32],
    vertices: usize,
) -> Result<(), VolumeDrawError> {
    let uploaded = |d: &VolumeDraw| if d.indexed { indices.len() } else { vertices };
    if let Some(d) = draws
        .iter()
        .find(|d| (d.first + d.count) as usize > uploaded(d))
    {
        return Err(VolumeDrawError::DrawPastBuffer {
            light,
            end: d.first + d.count,
            uploaded: uploaded(d),
        });
    }
    if indices.iter().any(|&i| i as usize >= vertices) {
        return Err(VolumeDrawError::IndexPastBuffer { light, vertices });
    }
    Ok(())
}

impl LightVolumeDraws {
    /// The last frame's draws, drawn as they were: nothing they are made from changed.
    pub(super) fn keep_last_draws(&mut self) {
        let s = &mut self.stats;
        s.parts_reused += s.parts_built;
        s.parts_built = 0;
        s.rebuilt = false;
        s.build_ms = 0.0;
        s.draws_reused = true;
        self.upload = VolumeUpload::default();
    }

    /// Builds the parts whose key changed and drops those no longer drawn; returns each
    /// piece's key. `(light, options, culling, truncate)`: the light in world space, the
    /// volume options, whether receivers are known (caster culling) and
    /// `plan.truncate_volumes`.
    pub(super) fn build_parts(
        &mut self,
        groups: &CasterGroups,
        pieces: &[Piece],
        local_boxes: &HashMap<usize, (Vec<Aabb>, Vec<u64>)>,
        (light, o, culling, truncate): (glam::Vec3, &ShadowVolumeOptions, bool, bool),
        stats: &mut VolumeStats,
    ) -> Vec<u64> {
        let s = settings(o);
        let mut keys = Vec::with_capacity(pieces.len());
        for p in pieces {
            let group = &groups.groups[p.group];
            let (boxes, box_hashes) = &local_boxes[&p.group];
            let receivers_key = {
                let mut h = DefaultHasher::new();
                // A reshaped model's pieces are new triangles.
                group.pose.hash(&mut h);
                culling.hash(&mut h);
                truncate.hash(&mut h);
                p.local_radius.to_bits().hash(&mut h);
                for &i in &p.near {
                    box_hashes[i as usize].hash(&mut h);
                }
                h.finish()
            };
            let key = part_key(light, o, p, &p.model, receivers_key);
            let cached = self
                .meshes
                .get(&(p.group, p.id))
                .is_some_and(|c| o.caching && c.key == key);
            if cached {
                stats.parts_reused += 1;
            } else {
                let near: Vec<Aabb> = p.near.iter().map(|&i| boxes[i as usize]).collect();
                let cull = culling.then_some(volume::ReceiverCull {
                    boxes: &near,
                    radius: p.local_radius,
                    // An explicit finite extrusion (the paper's option) is the user's to see.
                    truncate: truncate && o.extrusion == volume::Extrusion::Infinite,
                });
                let piece = p.triangles(group);
                let mesh = volume::build_volume_of(
                    group,
                    &piece,
                    p.light_local.as_dvec3(),
                    &s,
                    p.counting == Counting::ZFail,
                    cull,
                );
                stats.triangles_culled += mesh.culled;
                stats.triangles_tested += piece.triangles.len();
                stats.parts_built += 1;
                let blocks = block_bounds(&mesh.vertices);
                self.meshes
                    .insert((p.group, p.id), CachedPart { key, mesh, blocks });
            }
            match p.counting {
                Counting::ZFail => stats.zfail_parts += 1,
                Counting::ZPass => stats.zpass_parts += 1,
            }
            keys.push(key);
        }
        // Parts no longer drawn are dropped: the cache holds this frame's parts only.
        let wanted: HashSet<(usize, PieceId)> = pieces.iter().map(|p| (p.group, p.id)).collect();
        self.meshes.retain(|k, _| wanted.contains(k));
        keys
    }

    /// The buffer layout: depth-fail parts first, each group's together, so that runs of
    /// parts can share a draw call (a depth-pass part has no caps: its sides are all it
    /// draws); each part's depth clip and, under `plan.cull_clipped`, the triangles it keeps.
    pub(super) fn lay_out(
        &self,
        pieces: &[Piece],
        keys: &[u64],
        lp: &LightPlan,
        choices: &PieceChoices,
        fits: &mut HashMap<FitKey, [[f32; 4]; MAX_PLANES]>,
        stats: &mut VolumeStats,
    ) -> Layout {
        let camera = choices.camera;
        let mut parts = Vec::with_capacity(pieces.len());
        // Vertices the buffer holds before each part.
        let mut total = 0usize;
        let mut scissored = 0.0;
        let mut order: Vec<_> = pieces.iter().zip(keys).collect();
        order.sort_by_key(|(p, _)| (p.counting != Counting::ZFail, p.group));
        // The buffer holds every planned part in this order, so that its layout follows the
        // part keys alone; a part off screen is skipped when drawing, not when uploading (as
        // the camera turns, parts leave and enter the screen with nothing rebuilt).
        let mut layout = DefaultHasher::new();
        let mut drawn = 0usize;
        let mut indices = Vec::new();
        let mut depth_range = Some(EMPTY_RANGE);
        for (p, key) in order {
            let cached = &self.meshes[&(p.group, p.id)];
            let mesh = &cached.mesh;
            if mesh.vertices.is_empty() {
                continue;
            }
            let mut range = PartRange {
                group: p.group,
                piece: p.id,
                counting: p.counting,
                model: p.model,
                first: total as i32,
                sides: mesh.side_vertices as i32,
                caps: mesh.cap_vertices as i32,
                scissor: p.rect,
                depth_clip: part_depth_clip(p, lp, choices, fits, stats),
                depth_bounds: p.depth_range.filter(|_| choices.depth_bounds),
                elements: None,
            };
            let test = ClipTest::new(camera.view_proj * p.model, &range.depth_clip)
                .filter(|_| choices.cull_clipped && range.drawn());
            if let Some(test) = test {
                let start = indices.len();
                let rejected =
                    test.kept_triangles(&mesh.vertices, &cached.blocks, total as u32, &mut indices);
                if rejected > 0 {
                    stats.triangles_clipped += rejected;
                    range.elements = Some((start as i32, (indices.len() - start) as i32));
                } else {
                    // Nothing rejected: the vertices drawn as they are.
                    indices.truncate(start);
                }
            }
            key.hash(&mut layout);
            total += mesh.vertices.len();
            parts.push(range);
            if !range.drawn() {
                if range.elements.is_none() {
                    stats.parts_offscreen += 1;
                }
                continue;
            }
            drawn += 1;
            if mesh.truncated {
                stats.parts_truncated += 1;
            }
            if range.depth_clip != [[0.0; 4]; MAX_PLANES] {
                stats.parts_depth_clipped += 1;
            }
            if range.depth_bounds.is_some() {
                stats.parts_depth_bounded += 1;
            }
            depth_range = depth_range
                .zip(p.depth_range)
                .map(|(a, b)| range_union(a, b));
            scissored += p.rect.map_or(1.0, |s| {
                s.area() as f64 / Scissor::full(camera).area().max(1) as f64
            });
            stats.quads += mesh.quads;
            stats.cap_triangles += mesh.cap_vertices / 3;
        }
        total.hash(&mut layout);
        stats.depth_range = depth_range;
        stats.parts_drawn = drawn;
        stats.part_scissor_fraction = if drawn == 0 {
            0.0
        } else {
            scissored / drawn as f64
        };
        Layout {
            parts,
            indices,
            vertex_count: total,
            hash: layout.finish(),
        }
    }

    /// Every part's vertices in the layout's order.
    pub(super) fn vertices(&self, layout: &Layout) -> Vec<[f32; 4]> {
        let mut vertices: Vec<[f32; 4]> = Vec::with_capacity(layout.vertex_count);
        for p in &layout.parts {
            vertices.extend_from_slice(&self.meshes[&(p.group, p.piece)].mesh.vertices);
        }
        vertices
    }
}

/// A depth-pass part's clip planes (`plan.depth_clip`), fitted to the depth in its rectangle
/// or taken from a fit made for the same rectangle and depth (`plan.reuse_depth_fits`).
fn part_depth_clip(
    p: &Piece,
    lp: &LightPlan,
    choices: &PieceChoices,
    fits: &mut HashMap<FitKey, [[f32; 4]; MAX_PLANES]>,
    stats: &mut VolumeStats,
) -> [[f32; 4]; MAX_PLANES] {
    // The depth bounds test, where used, replaces the clip planes (its emulation).
    let depth = choices.depth.filter(|_| {
        choices.depth_clip > 0 && !choices.depth_bounds && p.counting == Counting::ZPass
    });
    let Some(depth) = depth else {
        return [[0.0; 4]; MAX_PLANES];
    };
    let camera = choices.camera;
    let r = p.rect.or(lp.scissor).unwrap_or(Scissor::full(camera));
    let key = ([r.x, r.y, r.width, r.height], choices.depth_clip);
    if let Some(planes) = fits.get(&key) {
        stats.depth_fits_reused += 1;
        return *planes;
    }
    let planes = depth_clip(depth, camera, &r, choices.depth_clip);
    if choices.reuse_fits {
        fits.insert(key, planes);
    }
    planes
}
