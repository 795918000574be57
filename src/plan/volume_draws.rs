//! Each light's shadow-volume draws, decided on the CPU: which pieces are drawn, merged and
//! culled, the rectangle and depth clip of each, which triangles are left out, how the vertex
//! buffer is laid out and which draw calls the stencil pass makes. The GL layer uploads what
//! [`LightVolumeDraws::upload`] holds and makes the draw calls; it decides nothing.
//!
//! Parts are rebuilt only when something they depend on changed (the light, a caster's
//! transform, the build settings, the counting, the receivers their shadow reaches) unless
//! caching is off; a light's draws are kept whole while nothing they are made from changed
//! (`plan.reuse_volume_draws`).
//!
//! Vocabulary (used throughout `plan/` and `shadow/volume.rs`):
//! - a **caster group** holds one owner's casting triangles (the world, or one model), welded;
//! - a **component** is a connected set of a group's triangles; a **chunk** is a spatial cut
//!   of a component into at most `CHUNK_TRIANGLES` (the planner culls chunks, the paper's
//!   frame extrudes whole components);
//! - a **piece** is what one volume is extruded from: a component, a chunk, or chunks merged
//!   (`plan.merge_pieces`);
//! - a **part** is a piece with its counting: a piece split by `plan.split_counting` gives two
//!   parts (its triangles near the near plane, depth-fail; the rest, depth-pass);
//! - a **draw** is one draw call of the stencil pass over consecutive parts.

use crate::geometry::Aabb;
use crate::options::{ShadowVolumeOptions, VolumeCasters};
use crate::plan::clipped::{ClipTest, block_bounds};
use crate::plan::depth_bounds::{
    DepthBound, DepthRange, EMPTY_RANGE, MAX_PLANES, range_union, window_depth_range,
};
use crate::plan::merge::{KeptChunk, merged_spans};
use crate::plan::occlusion::DepthPyramid;
use crate::plan::scissor::{Scissor, points_scissor};
use crate::plan::{CameraSetup, LightPlan, PartTriangles};
use crate::scene::Scene;
use crate::shadow::volume::{self, CasterGroups, Counting, PieceRef, VolumeSettings};
use glam::Mat4;
use serde::Serialize;
use std::borrow::Cow;
use std::collections::{HashMap, HashSet};
use std::hash::{DefaultHasher, Hash, Hasher};
use std::time::Instant;
use thiserror::Error;

/// A light's draws would read past what is uploaded (a bug in the layout, caught before GL
/// reads out of bounds: llvmpipe does not check).
#[derive(Debug, Error, PartialEq)]
pub enum VolumeDrawError {
    #[error("light {light}: a volume draw ends at {end} past the {uploaded} uploaded")]
    DrawPastBuffer {
        light: usize,
        end: i32,
        uploaded: usize,
    },
    #[error("light {light}: a volume index points past the {vertices} vertices uploaded")]
    IndexPastBuffer { light: usize, vertices: usize },
}

/// What one light's volumes cost, for stats and reports.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct VolumeStats {
    pub light: usize,
    /// Side quads drawn.
    pub quads: usize,
    /// Cap triangles drawn (front and back caps of depth-fail parts).
    pub cap_triangles: usize,
    pub zfail_parts: usize,
    pub zpass_parts: usize,
    /// Caster triangles whose facing was tested when building.
    pub triangles_tested: usize,
    /// Facing triangles left out: their shadow reaches no receiver in view (planner).
    pub triangles_culled: usize,
    /// CPU time of the last build (silhouettes and extrusion).
    pub build_ms: f64,
    /// Whether this frame rebuilt any part (false: all reused from the cache).
    pub rebuilt: bool,
    /// Parts not drawn this frame: the receivers their shadow reaches are off the light's
    /// screen rectangle (`plan.piece_scissor`).
    pub parts_offscreen: usize,
    /// Receivers no volume has to reach: the depth buffer hides their boxes
    /// (`plan.occlusion`).
    pub receivers_hidden: usize,
    /// Parts ending just past their receivers rather than at infinity
    /// (`plan.truncate_volumes`).
    pub parts_truncated: usize,
    /// Drawn depth-pass parts clipped at the farthest depth of their rectangle
    /// (`plan.depth_clip`).
    pub parts_depth_clipped: usize,
    /// Drawn parts restricted by `EXT_depth_bounds_test` to the window-depth range of the
    /// receivers their shadow reaches (`plan.depth_bounds_test`, where the GL has it).
    pub parts_depth_bounded: usize,
    /// The window-depth range of the receivers the drawn parts' shadows reach, all parts
    /// together (what `EXT_depth_bounds_test` is given part by part); computed whenever the
    /// receivers are known, so that its meaning can be checked where the test is missing.
    /// None: a drawn part has none (receivers unknown, test off).
    pub depth_range: Option<DepthRange>,
    /// Depth-pass parts whose clip planes were fitted before, for this rectangle and this
    /// depth buffer: by an earlier frame with the same depth (`plan.reuse_depth_fits`), or
    /// for another part or light of this frame.
    pub depth_fits_reused: usize,
    /// Triangles of those parts left out of the draw because one clip plane rejects all
    /// three corners (`plan.cull_clipped`); a part left with none is not drawn. `quads` and
    /// `cap_triangles` count the drawn parts' triangles before this.
    pub triangles_clipped: usize,
    /// Parts with triangles to draw: not off screen, not left empty by the build or by
    /// `plan.cull_clipped`.
    pub parts_drawn: usize,
    /// Mean share of the screen a drawn part's stencil draw is scissored to (1 without
    /// `plan.piece_scissor`).
    pub part_scissor_fraction: f64,
    /// Planned chunks drawn inside a merged piece (`plan.merge_pieces`), and the merged pieces
    /// they make up.
    pub chunks_merged: usize,
    pub merged_parts: usize,
    /// Parts built this frame, and parts reused from earlier frames.
    pub parts_built: usize,
    pub parts_reused: usize,
    /// The last frame's draws, drawn as they were: nothing they are made from changed
    /// (`plan.reuse_volume_draws`); the other counts are theirs.
    pub draws_reused: bool,
}

/// Which triangles of a caster group one drawn piece holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PieceId {
    /// A whole connected component (the paper's frame, without `plan.cull_casters`).
    Component(usize),
    /// The chunks `first..end`: one chunk, or neighbours merged (`plan.merge_pieces`).
    Chunks(usize, usize),
    /// Part of a chunk or component split by counting (`plan.split_counting`): its triangles
    /// near the near plane, or the rest.
    Split { of: PieceRef, near_plane: bool },
}

/// One part's vertex ranges in the light's buffer.
#[derive(Debug, Clone, Copy)]
pub struct PartRange {
    pub group: usize,
    pub piece: PieceId,
    pub counting: Counting,
    pub model: Mat4,
    pub first: i32,
    pub sides: i32,
    pub caps: i32,
    /// Where its stencil draw may change counts (None: the light's rectangle).
    pub scissor: Option<Scissor>,
    /// A clip-space plane its stencil draw is clipped to (`gl_ClipDistance`; zero: none).
    pub depth_clip: [[f32; 4]; MAX_PLANES],
    /// The window-depth range the depth already stored at a pixel must lie in for its draw
    /// to change the pixel's count (`EXT_depth_bounds_test`; None: no test).
    pub depth_bounds: Option<DepthRange>,
    /// The triangles the clip planes leave anything of, as (first, count) in the light's
    /// index buffer (`plan.cull_clipped`); None: all of them, straight from the vertices.
    pub elements: Option<(i32, i32)>,
}

impl PartRange {
    /// False for a part whose rectangle or depth range is empty (its counts can change no
    /// receiver in view) or whose every triangle the clip planes reject.
    pub fn drawn(&self) -> bool {
        self.scissor.is_none_or(|s| s.area() > 0)
            && self.elements.is_none_or(|(_, n)| n > 0)
            && self.depth_bounds.is_none_or(|[lo, hi]| lo <= hi)
    }
}

/// One draw call of the stencil pass: consecutive parts with the same counting, transform and
/// rectangle, whose vertices follow one another in the buffer.
#[derive(Debug, Clone, Copy)]
pub struct VolumeDraw {
    pub counting: Counting,
    pub model: Mat4,
    /// Sides, then (depth-fail) caps, of every part in it: vertices, or with `indexed` the
    /// light's index buffer's entries.
    pub first: i32,
    pub count: i32,
    pub indexed: bool,
    pub scissor: Option<Scissor>,
    pub depth_clip: [[f32; 4]; MAX_PLANES],
    pub depth_bounds: Option<DepthRange>,
}

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

/// Everything a light's volume draws are made from: the light's plan, the camera, the depth
/// read back (by its generation), the volume options and the planner's choices, the light and
/// the casters' transforms and poses. While all of it is the same, the draws are what they were.
#[derive(PartialEq)]
struct DrawInputs {
    plan: LightPlan,
    depth: u64,
    camera: CameraSetup,
    options: ShadowVolumeOptions,
    choices: ([bool; 8], usize),
    light: (glam::Vec3, f32),
    transforms: Vec<(Mat4, u64)>,
}

impl DrawInputs {
    fn of(
        scene: &Scene,
        groups: &CasterGroups,
        lp: &LightPlan,
        o: &ShadowVolumeOptions,
        p: &PieceChoices,
    ) -> Self {
        let light = &scene.lights[lp.light];
        DrawInputs {
            plan: lp.clone(),
            depth: p.depth_generation,
            camera: *p.camera,
            options: o.clone(),
            choices: (
                [
                    p.depth.is_some(),
                    p.occlusion,
                    p.scissor,
                    p.truncate,
                    p.merge,
                    p.cull_clipped,
                    p.reuse_fits,
                    p.depth_bounds,
                ],
                p.depth_clip,
            ),
            light: (light.position, light.radius),
            transforms: lp
                .volumes
                .iter()
                .map(|v| {
                    let g = &groups.groups[v.group];
                    (volume::group_transform(scene, g.owner), g.pose)
                })
                .collect(),
        }
    }
}

struct CachedPart {
    key: u64,
    mesh: volume::VolumeMesh,
    /// The boxes of the mesh's blocks of triangles, for `plan.cull_clipped`.
    blocks: Vec<Option<Aabb>>,
}

/// The planner's per-piece decisions that need the receivers a piece's shadow reaches (known
/// only with `plan.cull_casters`).
#[derive(Debug, Clone, Copy)]
pub struct PieceChoices<'a> {
    pub camera: &'a CameraSetup,
    /// `plan.piece_scissor`: each part gets the screen rectangle of those receivers.
    pub scissor: bool,
    /// `plan.truncate_volumes`: each part ends just past them.
    pub truncate: bool,
    /// The frame's depth after the base pass, when `occlusion` or `depth_clip` reads it.
    pub depth: Option<&'a DepthPyramid>,
    /// `plan.occlusion`: receivers the depth hides are left out.
    pub occlusion: bool,
    /// `plan.depth_clip`: each depth-pass part is clipped behind the depth buffer within its
    /// rectangle by up to this many planes (`plan.depth_clip_planes`; 0: not clipped).
    pub depth_clip: usize,
    /// `plan.merge_pieces`: neighbouring chunks kept alike are drawn as one piece.
    pub merge: bool,
    /// `plan.depth_bounds_test` (where the GL has `EXT_depth_bounds_test`): each part's draw
    /// is restricted to pixels whose stored depth lies in the window-depth range of the
    /// receivers its shadow reaches. It replaces `depth_clip`, the emulation: each part gets
    /// one or the other.
    pub depth_bounds: bool,
    /// `plan.cull_clipped`: a depth-clipped part draws only the triangles its clip planes do
    /// not wholly reject.
    pub cull_clipped: bool,
    /// `plan.reuse_depth_fits`: fits are kept for the next frame (used while its depth is the
    /// same, see [`VolumePlanner::begin_frame`]).
    pub reuse_fits: bool,
    /// `plan.reuse_volume_draws`: a light's draws are kept, and drawn again while nothing they
    /// are made from changed.
    pub reuse_draws: bool,
    /// Which depth `depth` is: a count the renderer advances whenever the depth it reads back
    /// differs from the one it read before, so that draws made from an earlier depth are
    /// never taken for this one's.
    pub depth_generation: u64,
}

/// A fit's inputs besides the depth: the rectangle and the planes allowed.
type FitKey = ([i32; 4], usize);

/// How the volumes of `o` are built (the CPU benchmarks build them so too).
pub fn settings(o: &ShadowVolumeOptions) -> VolumeSettings {
    VolumeSettings {
        rule: o.edge_rule,
        extrusion: o.extrusion,
        finite_distance: o.finite_distance,
        facing_epsilon: o.facing_epsilon,
        two_sided: o.casters == VolumeCasters::Both,
    }
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
fn draws_of(parts: &[PartRange]) -> Vec<VolumeDraw> {
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

/// One piece a light's stencil pass draws: a planned part, or planned chunks merged.
struct Piece {
    group: usize,
    id: PieceId,
    counting: Counting,
    /// The group's transform, and the light and its range in the group's space.
    model: Mat4,
    light_local: glam::Vec3,
    local_radius: f32,
    /// The receiver boxes its shadow can reach: indices into the group's `local_boxes`, in
    /// order.
    near: Vec<u32>,
    /// Where its draw may change counts (`plan.piece_scissor`; None: the light's rectangle).
    rect: Option<Scissor>,
    /// The window-depth range of the receiver points its counts can change
    /// (`plan.depth_bounds_test`; None: not tested).
    depth_range: Option<DepthRange>,
    /// A split part's triangles (None: those `id` names), and a hash of them for its key.
    subset: Option<volume::Component>,
    subset_key: u64,
}

impl Piece {
    /// The triangles the piece holds: a split part carries them, the others are named by
    /// their id.
    fn triangles<'a>(&'a self, group: &'a volume::CasterGroup) -> Cow<'a, volume::Component> {
        match (&self.subset, self.id) {
            (Some(subset), _) => Cow::Borrowed(subset),
            (None, PieceId::Chunks(first, end)) if end == first + 1 => {
                Cow::Borrowed(&group.chunks[first])
            }
            (None, PieceId::Chunks(first, end)) => Cow::Owned(group.chunk_span(first, end)),
            (None, PieceId::Component(i)) => Cow::Borrowed(&group.components[i]),
            (None, PieceId::Split { of, .. }) => Cow::Borrowed(group.piece(of)),
        }
    }
}

/// `planned` with the spans of chunks `plan::merge` picks drawn as one piece each (their
/// receivers and rectangles together); the other parts as they were. `whole` stands for the
/// rectangle of a part without one.
fn merge(
    planned: Vec<Piece>,
    groups: &CasterGroups,
    whole: Scissor,
    stats: &mut VolumeStats,
) -> Vec<Piece> {
    let by_chunk: HashMap<(usize, usize), usize> = planned
        .iter()
        .enumerate()
        .filter_map(|(i, p)| match p.id {
            PieceId::Chunks(c, _) => Some(((p.group, c), i)),
            PieceId::Component(_) | PieceId::Split { .. } => None,
        })
        .collect();
    let mut group_ids: Vec<usize> = by_chunk.keys().map(|&(g, _)| g).collect();
    group_ids.sort_unstable();
    group_ids.dedup();
    let mut taken = vec![false; planned.len()];
    let mut out = Vec::new();
    for g in group_ids {
        let spans = merged_spans(&groups.groups[g].chunk_tree, |c| {
            let p = &planned[*by_chunk.get(&(g, c))?];
            let rect = p.rect.unwrap_or(whole);
            (rect.area() > 0).then_some(KeptChunk {
                counting: p.counting,
                rect,
            })
        });
        for (first, end) in spans {
            let members: Vec<&Piece> = (first..end)
                .map(|c| {
                    let i = by_chunk[&(g, c)];
                    taken[i] = true;
                    &planned[i]
                })
                .collect();
            let mut near: Vec<u32> = members
                .iter()
                .flat_map(|m| m.near.iter().copied())
                .collect();
            near.sort_unstable();
            near.dedup();
            let rect = members
                .iter()
                .filter_map(|m| m.rect)
                .reduce(|a, b| a.union(&b));
            let depth_range = members
                .iter()
                .map(|m| m.depth_range)
                .reduce(|a, b| Some(range_union(a?, b?)))
                .flatten();
            stats.chunks_merged += members.len();
            stats.merged_parts += 1;
            let m = members[0];
            out.push(Piece {
                group: g,
                id: PieceId::Chunks(first, end),
                counting: m.counting,
                model: m.model,
                light_local: m.light_local,
                local_radius: m.local_radius,
                near,
                rect,
                depth_range,
                subset: None,
                subset_key: 0,
            });
        }
    }
    out.extend(
        planned
            .into_iter()
            .zip(taken)
            .filter(|(_, t)| !t)
            .map(|(p, _)| p),
    );
    out
}

/// One light's volume draws as last prepared, and what the GL layer must upload for them.
#[derive(Default)]
pub struct LightVolumeDraws {
    pub light: usize,
    pub parts: Vec<PartRange>,
    /// The stencil pass's draw calls over `parts`.
    pub draws: Vec<VolumeDraw>,
    pub stats: VolumeStats,
    /// What this frame must upload before drawing.
    pub upload: VolumeUpload,
    /// Each part's last geometry, by group and piece, with what it was built from.
    meshes: HashMap<(usize, PieceId), CachedPart>,
    /// What the buffer holds: a hash of the written parts' keys in order and their length.
    layout: u64,
    /// What the draws were made from (`plan.reuse_volume_draws`; None: not kept).
    inputs: Option<DrawInputs>,
}

/// The buffers a light's draws need this frame (None: what was uploaded before still holds).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct VolumeUpload {
    /// Every part's vertices in buffer order (`vec4`, w = 0 at infinity).
    pub vertices: Option<Vec<[f32; 4]>>,
    /// The index list of the parts drawn through one (`plan.cull_clipped`).
    pub indices: Option<Vec<u32>>,
}

/// Every light's volume draws, with the caches they are made from: the planner owns them.
#[derive(Default)]
pub struct VolumePlanner {
    lights: HashMap<usize, LightVolumeDraws>,
    /// The depth clip planes fitted since the depth buffer last changed, by rectangle and
    /// plane count (`plan.reuse_depth_fits`): a fit reads nothing else.
    fits: HashMap<FitKey, [[f32; 4]; MAX_PLANES]>,
}

/// The planned pieces of one light, with the receivers' boxes in each caster group's space and
/// a hash of each box.
struct PlannedPieces {
    pieces: Vec<Piece>,
    local_boxes: HashMap<usize, (Vec<Aabb>, Vec<u64>)>,
}

/// The buffer layout of one light's parts, and the index list of those drawn through one.
struct Layout {
    parts: Vec<PartRange>,
    indices: Vec<u32>,
    /// Vertices of every part, in order.
    vertex_count: usize,
    /// A hash of the parts' keys in order and their length.
    hash: u64,
}

fn hash_box(b: &Aabb) -> u64 {
    let mut h = DefaultHasher::new();
    [b.min.to_array(), b.max.to_array()]
        .map(|a| a.map(f32::to_bits))
        .hash(&mut h);
    h.finish()
}

impl VolumePlanner {
    /// Volume parts kept for later frames, all lights together, and depth fits kept.
    pub fn held(&self) -> (usize, usize) {
        let parts = self.lights.values().map(|l| l.meshes.len()).sum();
        (parts, self.fits.len())
    }

    /// Once a frame, before [`VolumePlanner::prepare`]: `same_depth` says the depth buffer
    /// (at the frame's size) is the last frame's, so the fits made for it still hold.
    pub fn begin_frame(&mut self, same_depth: bool) {
        if !same_depth {
            self.fits.clear();
        }
    }

    /// Forgets every light's draws and fits (a new scene).
    pub fn forget(&mut self) {
        self.lights.clear();
        self.fits.clear();
    }

    /// Forgets the light's draws: what the GL layer holds for it may not match them (an
    /// upload failed), so the next frame builds and uploads them afresh.
    pub fn forget_light(&mut self, light: usize) {
        self.lights.remove(&light);
    }

    /// The light's volume draws as last prepared.
    pub fn get(&self, light: usize) -> Option<&LightVolumeDraws> {
        self.lights.get(&light)
    }

    /// The light's volume draws: parts whose key changed are rebuilt (all of them when
    /// `caching` is off), the buffer laid out again when its contents changed.
    pub fn prepare(
        &mut self,
        scene: &Scene,
        groups: &CasterGroups,
        lp: &LightPlan,
        o: &ShadowVolumeOptions,
        choices: PieceChoices,
    ) -> Result<&LightVolumeDraws, VolumeDrawError> {
        let inputs = choices
            .reuse_draws
            .then(|| DrawInputs::of(scene, groups, lp, o, &choices));
        let lv = self.lights.entry(lp.light).or_default();
        lv.light = lp.light;
        if inputs.is_some() && lv.inputs == inputs {
            lv.keep_last_draws();
            return Ok(&self.lights[&lp.light]);
        }
        match self.prepare_again(scene, groups, lp, o, choices, inputs) {
            Ok(()) => Ok(&self.lights[&lp.light]),
            Err(e) => {
                // Nothing of this frame's layout is kept: the next frame lays out afresh.
                self.lights.remove(&lp.light);
                Err(e)
            }
        }
    }

    /// [`VolumePlanner::prepare`] when the light's draws cannot be kept as they were.
    fn prepare_again(
        &mut self,
        scene: &Scene,
        groups: &CasterGroups,
        lp: &LightPlan,
        o: &ShadowVolumeOptions,
        choices: PieceChoices,
        inputs: Option<DrawInputs>,
    ) -> Result<(), VolumeDrawError> {
        let lv = self.lights.entry(lp.light).or_default();
        let start = Instant::now();
        let camera = choices.camera;
        let receivers = visible_receivers(lp, &choices);
        let mut stats = VolumeStats {
            light: lp.light,
            receivers_hidden: lp.volume_receivers.len() - receivers.len(),
            ..VolumeStats::default()
        };
        let planned = plan_pieces(scene, groups, lp, &receivers, &choices);
        let drawn_pieces = if choices.merge {
            let whole = lp.scissor.unwrap_or_else(|| Scissor::full(camera));
            merge(planned.pieces, groups, whole, &mut stats)
        } else {
            planned.pieces
        };
        let light_world = scene.lights[lp.light].position;
        let culling = !lp.volume_receivers.is_empty();
        let keys = lv.build_parts(
            groups,
            &drawn_pieces,
            &planned.local_boxes,
            (light_world, o, culling, choices.truncate),
            &mut stats,
        );
        let layout = lv.lay_out(
            &drawn_pieces,
            &keys,
            lp,
            &choices,
            &mut self.fits,
            &mut stats,
        );
        stats.rebuilt = stats.parts_built > 0;
        let draws = draws_of(&layout.parts);
        check_bounds(lp.light, &draws, &layout.indices, layout.vertex_count)?;
        lv.upload = VolumeUpload {
            vertices: (layout.hash != lv.layout || stats.rebuilt).then(|| lv.vertices(&layout)),
            indices: (!layout.indices.is_empty()).then_some(layout.indices),
        };
        lv.layout = layout.hash;
        stats.build_ms = start.elapsed().as_secs_f64() * 1e3;
        lv.draws = draws;
        lv.parts = layout.parts;
        lv.inputs = inputs;
        lv.stats = stats;
        Ok(())
    }
}

/// The light's receiver boxes that volumes must reach: those the depth does not hide
/// (`plan.occlusion`), or all of them.
fn visible_receivers<'a>(
    lp: &'a LightPlan,
    choices: &PieceChoices,
) -> std::borrow::Cow<'a, [Aabb]> {
    match choices.depth.filter(|_| choices.occlusion) {
        Some(depth) => lp
            .volume_receivers
            .iter()
            .filter(|b| !depth.hides(choices.camera, b))
            .copied()
            .collect(),
        None => lp.volume_receivers.as_slice().into(),
    }
}

/// Every draw and index stays inside what is uploaded (llvmpipe reads past a buffer
/// unchecked).
fn check_bounds(
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

/// Each planned part of the light as a piece: its triangles, transform, the receivers its
/// shadow can reach and (`plan.piece_scissor`) its screen rectangle.
fn plan_pieces(
    scene: &Scene,
    groups: &CasterGroups,
    lp: &LightPlan,
    receivers: &[Aabb],
    choices: &PieceChoices,
) -> PlannedPieces {
    let light_world = scene.lights[lp.light].position;
    let radius = scene.lights[lp.light].radius;
    // Without receiver boxes (no caster culling) every part is built whole.
    let culling = !lp.volume_receivers.is_empty();
    let mut local_boxes: HashMap<usize, (Vec<Aabb>, Vec<u64>)> = HashMap::new();
    let mut pieces: Vec<Piece> = Vec::with_capacity(lp.volumes.len());
    for p in &lp.volumes {
        let group = &groups.groups[p.group];
        let model = volume::group_transform(scene, group.owner);
        let to_local = model.inverse();
        let light_local = to_local.transform_point3(light_world);
        let whole = group.piece(p.piece);
        let (id, subset, subset_key) = piece_triangles(lp, p, group, whole);
        let piece = subset.as_ref().unwrap_or(whole);
        let (boxes, _) = local_boxes.entry(p.group).or_insert_with(|| {
            let boxes: Vec<Aabb> = receivers.iter().map(|b| b.transformed(&to_local)).collect();
            let hashes = boxes.iter().map(hash_box).collect();
            (boxes, hashes)
        });
        // The range in the group's space (a scaled model stretches it).
        let stretch = [to_local.x_axis, to_local.y_axis, to_local.z_axis]
            .iter()
            .map(|a| a.truncate().length())
            .fold(0.0f32, f32::max);
        let local_radius = radius * stretch.max(1e-6);
        // The part depends only on the receivers its shadow can reach: a moving receiver
        // rebuilds the parts that shadow it, not the light's whole volume.
        let piece_shadow = volume::shadow_bounds(&piece.bounds, light_local, local_radius);
        let near: Vec<u32> = (0..boxes.len() as u32)
            .filter(|&i| boxes[i as usize].intersects(&piece_shadow))
            .collect();
        let rect = (choices.scissor && culling)
            .then(|| piece_rect(lp, choices.camera, boxes, &near, &piece_shadow, &model));
        // Also without the test, when the receivers are known: for the stats.
        let depth_range = (choices.depth_bounds || culling).then(|| {
            piece_depth_range(
                choices.camera,
                culling.then_some((boxes, &near[..])),
                &piece_shadow,
                &model,
            )
        });
        pieces.push(Piece {
            group: p.group,
            id,
            counting: p.counting,
            model,
            light_local,
            local_radius,
            near,
            rect,
            depth_range,
            subset,
            subset_key,
        });
    }
    PlannedPieces {
        pieces,
        local_boxes,
    }
}

/// Which triangles a planned part holds: its id, the subset of a split part (None: those the
/// id names), and a hash of the subset for its key.
fn piece_triangles(
    lp: &LightPlan,
    p: &crate::plan::VolumePart,
    group: &volume::CasterGroup,
    whole: &volume::Component,
) -> (PieceId, Option<volume::Component>, u64) {
    match p.triangles {
        PartTriangles::All => match p.piece {
            PieceRef::Chunk(i) => (PieceId::Chunks(i, i + 1), None, 0),
            PieceRef::Component(i) => (PieceId::Component(i), None, 0),
        },
        PartTriangles::NearPlane(i) | PartTriangles::Rest(i) => {
            let near_plane = matches!(p.triangles, PartTriangles::NearPlane(_));
            let listed = &lp.near_plane_triangles[i];
            let subset = group.subset(whole, |t| listed.binary_search(&t).is_ok() == near_plane);
            let id = PieceId::Split {
                of: p.piece,
                near_plane,
            };
            let mut h = DefaultHasher::new();
            listed.hash(&mut h);
            (id, Some(subset), h.finish())
        }
    }
}

/// A piece's volume is closed, so its counts cancel wherever the visible surface is outside
/// it: only receiver points in its shadow (within the range, inside `piece_shadow`) can see a
/// change. Their boxes, cut to that shadow, bound where its draw may change counts.
fn piece_rect(
    lp: &LightPlan,
    camera: &CameraSetup,
    boxes: &[Aabb],
    near: &[u32],
    piece_shadow: &Aabb,
    model: &Mat4,
) -> Scissor {
    let light_rect = lp.scissor.unwrap_or_else(|| Scissor::full(camera));
    let mut rect: Option<Scissor> = None;
    for &i in near {
        let cut = boxes[i as usize].intersection(piece_shadow);
        let corners = cut.corners().map(|c| model.transform_point3(c));
        if let Some(r) = points_scissor(camera, &corners).filter(|r| r.area() > 0) {
            rect = Some(rect.map_or(r, |u| u.union(&r)));
        }
    }
    rect.map_or(Scissor::EMPTY, |r| r.intersect(&light_rect))
}

/// The window-depth range of the receiver points a piece's counts can change: those of its
/// receiver boxes (`near`, the boxes in the group's space) inside its shadow, as for
/// [`piece_rect`]; without receiver boxes (no caster culling), its shadow within the light's
/// range, beyond which the lit pass adds nothing. `EXT_depth_bounds_test` compares the depth
/// stored at a pixel with it: a surface outside that range is outside the piece's volume,
/// where its counts cancel, or unlit.
fn piece_depth_range(
    camera: &CameraSetup,
    receivers: Option<(&[Aabb], &[u32])>,
    piece_shadow: &Aabb,
    model: &Mat4,
) -> DepthRange {
    let world = |b: &Aabb| b.corners().map(|c| model.transform_point3(c));
    let range = |b: &Aabb| {
        if b.is_empty() {
            EMPTY_RANGE
        } else {
            window_depth_range(&camera.view, &camera.projection, world(b))
        }
    };
    match receivers {
        Some((boxes, near)) => near
            .iter()
            .map(|&i| range(&boxes[i as usize].intersection(piece_shadow)))
            .fold(EMPTY_RANGE, range_union),
        None => range(piece_shadow),
    }
}

impl LightVolumeDraws {
    /// The last frame's draws, drawn as they were: nothing they are made from changed.
    fn keep_last_draws(&mut self) {
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
    fn build_parts(
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
    fn lay_out(
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
    fn vertices(&self, layout: &Layout) -> Vec<[f32; 4]> {
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
