//! Building a light's parts (cached by key), laying out its vertex buffer and merging its parts
//! into the stencil pass's draw calls, each with its depth clip.

use super::{
    CachedPart, FitKey, Layout, LightVolumeDraws, PartRange, Piece, PieceChoices, PieceId,
    VolumeDraw, VolumeDrawError, VolumeStats, VolumeUpload, hash_box, settings,
};
use crate::geometry::Aabb;
use crate::options::ShadowVolumeOptions;
use crate::plan::clipped::{ClipTest, block_bounds};
use crate::plan::depth_bounds::{DepthBound, DepthRange, EMPTY_RANGE, MAX_PLANES, range_union};
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
    // A kept part holds both caps: its counting is a choice of draw.
    let caps = if p.kept { 2 } else { p.counting as u8 };
    let mut h = DefaultHasher::new();
    receivers.hash(&mut h);
    light.to_array().map(f32::to_bits).hash(&mut h);
    (
        o.edge_rule as u8,
        o.extrusion as u8,
        o.finite_distance.to_bits(),
        o.facing_epsilon.to_bits(),
        o.cull_whole_planes,
        p.group,
        p.id,
        p.subset_key,
        caps,
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
        s.parts_moved = 0;
        s.rebuilt = false;
        s.build_ms = 0.0;
        s.draws_reused = true;
        self.upload = VolumeUpload::default();
    }

    /// Builds the parts whose key changed and drops the unkept ones no longer drawn; returns
    /// each piece's key. `(light, options, culling, truncate)`: the light in world space, the
    /// volume options, whether receivers are known (caster culling) and
    /// `plan.truncate_volumes`; `clock` dates the parts used.
    pub(super) fn build_parts(
        &mut self,
        groups: &CasterGroups,
        pieces: &[Piece],
        local_boxes: &HashMap<usize, (Vec<Aabb>, Vec<u64>)>,
        (light, o, culling, truncate): (glam::Vec3, &ShadowVolumeOptions, bool, bool),
        (clock, stats): (u64, &mut VolumeStats),
    ) -> Vec<u64> {
        let mut keys = Vec::with_capacity(pieces.len());
        // The range receivers in each group's space, made when a kept part needs them.
        let mut range_local: HashMap<usize, Vec<Aabb>> = HashMap::new();
        for p in pieces {
            let group = &groups.groups[p.group];
            let base = part_key(light, o, p, &p.model, 0);
            // A kept part's boxes (of the range) are needed for its key; an unkept part's (in
            // view) are hashed by index and collected only when it is built.
            let (near, receivers_key) = if p.kept {
                let unchanged = self.meshes.get(&(p.group, p.id)).is_some_and(|c| {
                    o.caching && c.kept && c.base == base && c.range == self.range.hash && c.held()
                });
                if unchanged {
                    let c = self.meshes.get_mut(&(p.group, p.id)).expect("just found");
                    c.used = clock;
                    stats.parts_reused += 1;
                    count_part(p, stats);
                    keys.push(c.key);
                    continue;
                }
                let boxes = range_local.entry(p.group).or_insert_with(|| {
                    let to_local = p.model.inverse();
                    self.range
                        .boxes
                        .iter()
                        .map(|b| b.transformed(&to_local))
                        .collect()
                });
                let (near, key) = near_boxes(boxes, p, group);
                (Some(near), key)
            } else {
                let box_hashes = &local_boxes[&p.group].1;
                let mut h = DefaultHasher::new();
                for &i in &p.near {
                    box_hashes[i as usize].hash(&mut h);
                }
                (None, h.finish())
            };
            let receivers_key = {
                let mut h = DefaultHasher::new();
                // A reshaped model's pieces are new triangles.
                group.pose.hash(&mut h);
                culling.hash(&mut h);
                truncate.hash(&mut h);
                p.local_radius.to_bits().hash(&mut h);
                receivers_key.hash(&mut h);
                h.finish()
            };
            let key = part_key(light, o, p, &p.model, receivers_key);
            let cached = self.meshes.get_mut(&(p.group, p.id));
            match cached {
                Some(c) if o.caching && c.key == key && c.held() => {
                    c.used = clock;
                    c.range = self.range.hash;
                    stats.parts_reused += 1;
                }
                _ => {
                    let near = near.unwrap_or_else(|| {
                        let boxes = &local_boxes[&p.group].0;
                        p.near.iter().map(|&i| boxes[i as usize]).collect()
                    });
                    let part = build_part(group, p, &near, (o, culling, truncate), stats);
                    self.meshes.insert(
                        (p.group, p.id),
                        CachedPart {
                            key,
                            blocks: block_bounds(&part.vertices),
                            vertices: part.vertices.len(),
                            at: None,
                            mesh: part,
                            kept: p.kept,
                            base,
                            range: self.range.hash,
                            used: clock,
                        },
                    );
                }
            }
            count_part(p, stats);
            keys.push(key);
        }
        // Unkept parts no longer drawn are dropped; kept ones wait for eviction.
        let wanted: HashSet<(usize, PieceId)> = pieces.iter().map(|p| (p.group, p.id)).collect();
        self.meshes.retain(|k, c| c.kept || wanted.contains(k));
        keys
    }

    /// The buffer layout: the kept parts first, drawn or not, in a fixed order, so that while
    /// none is built or evicted the region stays as uploaded; then the others, depth-fail
    /// first, each group's together, so that runs of parts can share a draw call. Each drawn
    /// part's depth clip and, under `plan.cull_clipped`, the triangles it keeps.
    pub(super) fn lay_out(
        &self,
        pieces: &[Piece],
        keys: &[u64],
        lp: &LightPlan,
        choices: &PieceChoices,
        fits: &mut HashMap<FitKey, [[f32; 4]; MAX_PLANES]>,
        stats: &mut VolumeStats,
    ) -> Layout {
        let mut placing = Placing::new();
        let planned_kept: HashMap<(usize, PieceId), usize> = pieces
            .iter()
            .enumerate()
            .filter(|(_, p)| p.kept)
            .map(|(i, p)| ((p.group, p.id), i))
            .collect();
        let kept = self.kept_region();
        for id in &kept.meshes {
            let cached = &self.meshes[id];
            match planned_kept.get(id) {
                Some(&i) => placing.place(&pieces[i], cached, lp, choices, fits, stats),
                None => placing.skip(*id, cached),
            }
        }
        let (kept_vertices, kept_meshes) = (placing.total, placing.order.len());
        let mut others: Vec<_> = pieces.iter().zip(keys).filter(|(p, _)| !p.kept).collect();
        others.sort_by_key(|(p, _)| (p.counting != Counting::ZFail, p.group));
        let mut layout = DefaultHasher::new();
        for (p, key) in others {
            key.hash(&mut layout);
            let cached = &self.meshes[&(p.group, p.id)];
            placing.place(p, cached, lp, choices, fits, stats);
        }
        placing.total.hash(&mut layout);
        kept.hash.hash(&mut layout);
        placing.finish(stats);
        Layout {
            parts: placing.parts,
            indices: placing.indices,
            order: placing.order,
            vertex_count: placing.total,
            hash: layout.finish(),
            kept_vertices,
            kept_meshes,
            kept_hash: kept.hash,
        }
    }

    /// The kept meshes in buffer order (a fixed one: by group and piece), with a hash of their
    /// keys in that order and their vertices.
    pub(super) fn kept_region(&self) -> KeptRegion {
        let mut meshes: Vec<(usize, PieceId)> = self
            .meshes
            .iter()
            .filter(|(_, c)| c.kept)
            .map(|(k, _)| *k)
            .collect();
        meshes.sort_unstable();
        let mut h = DefaultHasher::new();
        let mut vertices = 0;
        for id in &meshes {
            let cached = &self.meshes[id];
            cached.key.hash(&mut h);
            vertices += cached.len();
        }
        vertices.hash(&mut h);
        KeptRegion {
            meshes,
            vertices,
            hash: h.finish(),
        }
    }
}

/// The kept region of a light's buffer (see [`LightVolumeDraws::kept_region`]).
pub(super) struct KeptRegion {
    pub meshes: Vec<(usize, PieceId)>,
    pub vertices: usize,
    pub hash: u64,
}

/// The range receiver boxes (in the group's space) that piece `p`'s shadow can reach, and a
/// hash of them.
fn near_boxes(boxes: &[Aabb], p: &Piece, group: &volume::CasterGroup) -> (Vec<Aabb>, u64) {
    let shadow = volume::shadow_bounds(&p.triangles(group).bounds, p.light_local, p.local_radius);
    let near: Vec<Aabb> = boxes
        .iter()
        .filter(|b| b.intersects(&shadow))
        .copied()
        .collect();
    let mut h = DefaultHasher::new();
    for b in &near {
        hash_box(b).hash(&mut h);
    }
    (near, h.finish())
}

/// Builds piece `p`'s volume against the receiver boxes `near` (in the group's space): with
/// both caps when kept, else with those its counting needs.
fn build_part(
    group: &volume::CasterGroup,
    p: &Piece,
    near: &[Aabb],
    (o, culling, truncate): (&ShadowVolumeOptions, bool, bool),
    stats: &mut VolumeStats,
) -> volume::VolumeMesh {
    let cull = culling.then_some(volume::ReceiverCull {
        boxes: near,
        radius: p.local_radius,
        // An explicit finite extrusion (the paper's option) is the user's to see.
        truncate: truncate && o.extrusion == volume::Extrusion::Infinite,
        whole_planes: o.cull_whole_planes,
    });
    let piece = p.triangles(group);
    let mesh = volume::build_volume_of(
        group,
        &piece,
        p.light_local.as_dvec3(),
        &settings(o),
        p.kept || p.counting == Counting::ZFail,
        cull,
    );
    stats.triangles_culled += mesh.culled;
    stats.triangles_tested += piece.triangles.len();
    stats.parts_built += 1;
    mesh
}

fn count_part(p: &Piece, stats: &mut VolumeStats) {
    match p.counting {
        Counting::ZFail => stats.zfail_parts += 1,
        Counting::ZPass => stats.zpass_parts += 1,
    }
}

/// The layout as it is placed, part after part.
struct Placing {
    parts: Vec<PartRange>,
    indices: Vec<u32>,
    order: Vec<(usize, PieceId)>,
    /// Vertices placed so far.
    total: usize,
    drawn: usize,
    scissored: f64,
    depth_range: Option<DepthRange>,
}

impl Placing {
    fn new() -> Placing {
        Placing {
            parts: Vec::new(),
            indices: Vec::new(),
            order: Vec::new(),
            total: 0,
            drawn: 0,
            scissored: 0.0,
            depth_range: Some(EMPTY_RANGE),
        }
    }

    /// A kept mesh not planned this frame: in the buffer, not drawn.
    fn skip(&mut self, id: (usize, PieceId), cached: &CachedPart) {
        self.order.push(id);
        self.total += cached.len();
    }

    /// Piece `p`'s part at the current place: its range (the vertices its counting draws),
    /// depth clip and kept triangles, and the stats of a drawn part.
    fn place(
        &mut self,
        p: &Piece,
        cached: &CachedPart,
        lp: &LightPlan,
        choices: &PieceChoices,
        fits: &mut HashMap<FitKey, [[f32; 4]; MAX_PLANES]>,
        stats: &mut VolumeStats,
    ) {
        let mesh = &cached.mesh;
        let first = self.total;
        self.order.push((p.group, p.id));
        self.total += cached.len();
        if cached.len() == 0 {
            return;
        }
        // Depth-pass draws the sides and a truncated volume's far cap, depth-fail both caps
        // too (the back cap comes first: see `VolumeMesh`).
        let caps = match p.counting {
            Counting::ZFail => mesh.cap_vertices,
            Counting::ZPass if mesh.truncated => mesh.back_cap_vertices,
            Counting::ZPass => 0,
        };
        let mut range = PartRange {
            group: p.group,
            piece: p.id,
            counting: p.counting,
            model: p.model,
            first: first as i32,
            sides: mesh.side_vertices as i32,
            caps: caps as i32,
            scissor: p.rect,
            depth_clip: part_depth_clip(p, lp, choices, fits, stats),
            depth_bounds: p.depth_range.filter(|_| choices.depth_bounds),
            elements: None,
        };
        // A part whose CPU copy was given up is drawn whole (the GL clips the same).
        let test = ClipTest::new(choices.camera.view_proj * p.model, &range.depth_clip)
            .filter(|_| choices.cull_clipped && range.drawn() && cached.on_cpu());
        if let Some(test) = test {
            let start = self.indices.len();
            let drawn = &mesh.vertices[..mesh.side_vertices + caps];
            let rejected =
                test.kept_triangles(drawn, &cached.blocks, first as u32, &mut self.indices);
            if rejected > 0 {
                stats.triangles_clipped += rejected;
                range.elements = Some((start as i32, (self.indices.len() - start) as i32));
            } else {
                // Nothing rejected: the vertices drawn as they are.
                self.indices.truncate(start);
            }
        }
        self.parts.push(range);
        if !range.drawn() {
            if range.elements.is_none() {
                stats.parts_offscreen += 1;
            }
            return;
        }
        self.drawn += 1;
        if mesh.truncated {
            stats.parts_truncated += 1;
        }
        if range.depth_clip != [[0.0; 4]; MAX_PLANES] {
            stats.parts_depth_clipped += 1;
        }
        if range.depth_bounds.is_some() {
            stats.parts_depth_bounded += 1;
        }
        self.depth_range = self
            .depth_range
            .zip(p.depth_range)
            .map(|(a, b)| range_union(a, b));
        self.scissored += p.rect.map_or(1.0, |s| {
            s.area() as f64 / Scissor::full(choices.camera).area().max(1) as f64
        });
        stats.quads += mesh.quads;
        stats.cap_triangles += caps / 3;
    }

    /// The stats of the whole layout.
    fn finish(&self, stats: &mut VolumeStats) {
        stats.depth_range = self.depth_range;
        stats.parts_drawn = self.drawn;
        stats.part_scissor_fraction = if self.drawn == 0 {
            0.0
        } else {
            self.scissored / self.drawn as f64
        };
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
