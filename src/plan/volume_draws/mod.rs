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
//! Vocabulary (used throughout `plan/` and `shadow/volume`):
//! - a **caster group** holds one owner's casting triangles (the world, or one model), welded;
//! - a **component** is a connected set of a group's triangles; a **chunk** is a spatial cut
//!   of a component into at most `CHUNK_TRIANGLES` (the planner culls chunks, the paper's
//!   frame extrudes whole components);
//! - a **piece** is what one volume is extruded from: a component, a chunk, or chunks merged
//!   (`plan.merge_pieces`);
//! - a **part** is a piece with its counting: a piece split by `plan.split_counting` gives two
//!   parts (its triangles near the near plane, depth-fail; the rest, depth-pass);
//! - a **draw** is one draw call of the stencil pass over consecutive parts.

mod ahead;
mod parts;
mod pieces;
mod upload;

pub use ahead::Ahead;
pub use upload::{PartId, Span, VertexSpan, VolumeUpload};

use parts::{check_bounds, draws_of};
use pieces::{merge, plan_pieces, visible_receivers};

use crate::geometry::Aabb;
use crate::options::{ShadowVolumeOptions, VolumeCasters};
use crate::plan::depth_bounds::{DepthRange, MAX_PLANES};
use crate::plan::occlusion::DepthPyramid;
use crate::plan::scissor::Scissor;
use crate::plan::{CameraSetup, LightPlan};
use crate::scene::Scene;
use crate::shadow::volume::{self, CasterGroups, Counting, PieceRef, VolumeSettings};
use glam::Mat4;
use serde::Serialize;
use std::borrow::Cow;
use std::collections::HashMap;
use std::hash::Hash;
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
    #[error("light {light}: a volume part laid out is held neither on the CPU nor in its buffer")]
    PartNotHeld { light: usize },
}

/// What one light's volumes cost, for stats and reports.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, serde::Deserialize)]
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
    /// Parts copied on the GPU from their old place in the light's buffer into its new
    /// layout (their CPU copies were given up: `shadow_volume.relayout_on_gpu`).
    #[serde(default)]
    pub parts_moved: usize,
    /// The last frame's draws, drawn as they were: nothing they are made from changed
    /// (`plan.reuse_volume_draws`); the other counts are theirs.
    pub draws_reused: bool,
}

/// Which triangles of a caster group one drawn piece holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
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

/// Everything a light's volume draws are made from: the light's plan, the camera, the depth
/// read back (by its generation), the volume options and the planner's choices, the light and
/// the casters' transforms and poses. While all of it is the same, the draws are what they were.
#[derive(PartialEq)]
struct DrawInputs {
    /// A hash of the plan's fields the draws are made from (not its `reason`, which under
    /// `technique = auto` holds measured times and changes every frame).
    plan: u64,
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
            plan: plan_hash(lp),
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

/// A hash of a box, bit for bit (receiver boxes in the draws' and parts' keys).
fn hash_box(b: &Aabb) -> u64 {
    let mut h = std::hash::DefaultHasher::new();
    [b.min.to_array(), b.max.to_array()]
        .map(|a| a.map(f32::to_bits))
        .hash(&mut h);
    std::hash::Hasher::finish(&h)
}

/// A hash of what a light's draws read of its plan.
fn plan_hash(lp: &LightPlan) -> u64 {
    let mut h = std::hash::DefaultHasher::new();
    (
        lp.light,
        std::mem::discriminant(&lp.technique),
        &lp.near_plane_triangles,
        lp.scissor.map(|s| [s.x, s.y, s.width, s.height]),
    )
        .hash(&mut h);
    for v in &lp.volumes {
        (v.group, v.piece, v.counting as u8, v.triangles).hash(&mut h);
    }
    for b in &lp.volume_receivers {
        hash_box(b).hash(&mut h);
    }
    std::hash::Hasher::finish(&h)
}

struct CachedPart {
    key: u64,
    /// The part's geometry; its vertices are given up (left empty) once the light's buffer
    /// holds them, where `shadow_volume.relayout_on_gpu` and the budget say.
    mesh: volume::VolumeMesh,
    /// Vertices of the mesh, held on the CPU or not.
    vertices: usize,
    /// The vertex the part starts at in the light's buffer, as last uploaded.
    at: Option<usize>,
    /// The boxes of the mesh's blocks of triangles, for `plan.cull_clipped`.
    blocks: Vec<Option<Aabb>>,
    /// Built against the light's whole range with both caps, and kept while not drawn (see
    /// [`Piece::kept`]); `base` is its key without the receivers and `range` the light's range
    /// list it was checked against, so that a frame whose list is unchanged checks nothing
    /// else.
    kept: bool,
    base: u64,
    range: u64,
    /// When it was last planned (the planner's count of prepares), for eviction.
    used: u64,
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
    /// `plan.reuse_volume_draws` (`shadow_volume.caching` on the paper's frame): a light's
    /// draws are kept, and drawn again while nothing they are made from changed.
    pub reuse_draws: bool,
    /// `plan.keep_volumes`: a still light's pieces of still groups are built against its
    /// range and kept (see [`Piece::kept`]).
    pub keep: bool,
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
    /// Built against every receiver in the light's range (not only those in view) with both
    /// caps, so that neither the camera nor the counting changes it, and kept across frames
    /// while not drawn: a still light's piece of a still group, unsplit.
    kept: bool,
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
    /// The light as last prepared (position, radius), and each model group's transform and
    /// pose then: what did not change since is still, and its pieces are kept.
    light_at: Option<(glam::Vec3, f32)>,
    groups_at: HashMap<usize, u64>,
    /// The light's range receivers (world space) and a hash of them.
    range: RangeReceivers,
    /// A hash of the kept region of the buffer (its parts' keys in order), and the vertices
    /// the GPU buffer was last allocated for.
    kept_layout: u64,
    capacity: usize,
    /// Where the pending upload places each part of the layout (applied once it is made).
    placed: Vec<(PartId, usize)>,
}

/// The boxes of every receiver in a light's range, in view or not: kept pieces are built
/// against them. The world's are found once per light position; the models' every frame.
#[derive(Default)]
struct RangeReceivers {
    world_key: Option<u64>,
    world: Vec<Aabb>,
    boxes: Vec<Aabb>,
    hash: u64,
    /// Each model's reach ([`crate::scene::motion::Motion::reach`]), found once: a moving
    /// model stands for it by that box while it stays inside, so that its motion changes
    /// nothing kept.
    reach: Option<Vec<Option<Aabb>>>,
}

/// Every light's volume draws, with the caches they are made from: the planner owns them.
#[derive(Default)]
pub struct VolumePlanner {
    lights: HashMap<usize, LightVolumeDraws>,
    /// Prepares so far: the clock of [`CachedPart::used`].
    clock: u64,
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
    /// The meshes in buffer order (kept parts first, drawn or not), and the vertices of all.
    order: Vec<(usize, PieceId)>,
    vertex_count: usize,
    /// A hash of the parts' keys in order and their length.
    hash: u64,
    /// The kept region: its vertices, its meshes (the first of `order`) and a hash of its
    /// parts' keys in order.
    kept_vertices: usize,
    kept_meshes: usize,
    kept_hash: u64,
}

impl VolumePlanner {
    /// Volume parts kept for later frames, all lights together, depth fits kept, and the
    /// bytes of the parts' vertices the CPU holds.
    pub fn held(&self) -> (usize, usize, u64) {
        let parts = self.lights.values().map(|l| l.meshes.len()).sum();
        let vertices: usize = self
            .lights
            .values()
            .flat_map(|l| l.meshes.values())
            .map(|c| c.mesh.vertices.len())
            .sum();
        let bytes = (vertices * std::mem::size_of::<[f32; 4]>()) as u64;
        (parts, self.fits.len(), bytes)
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
        self.clock += 1;
        let lv = self.lights.entry(lp.light).or_default();
        let start = Instant::now();
        let camera = choices.camera;
        let receivers = visible_receivers(lp, &choices);
        let mut stats = VolumeStats {
            light: lp.light,
            receivers_hidden: lp.volume_receivers.len() - receivers.len(),
            ..VolumeStats::default()
        };
        let mut planned = plan_pieces(scene, groups, lp, &receivers, &choices);
        let culling = !lp.volume_receivers.is_empty();
        lv.mark_kept(scene, groups, &mut planned.pieces, choices.keep);
        if culling && planned.pieces.iter().any(|p| p.kept) {
            lv.range.update(scene, lp.light);
        }
        let drawn_pieces = if choices.merge {
            let whole = lp.scissor.unwrap_or_else(|| Scissor::full(camera));
            merge(planned.pieces, groups, whole, &mut stats)
        } else {
            planned.pieces
        };
        let light_world = scene.lights[lp.light].position;
        let keys = lv.build_parts(
            groups,
            &drawn_pieces,
            &planned.local_boxes,
            (light_world, o, culling, choices.truncate),
            (self.clock, &mut stats),
        );
        // Before the layout: the upload names the laid-out meshes, which must all still be
        // here when the GL layer copies them (this prepare's parts are never evicted).
        self.evict(o, choices.cull_clipped);
        let lv = self.lights.get_mut(&lp.light).expect("made above");
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
        let vertices = lv.upload_for(&layout, stats.rebuilt)?;
        // Without a new buffer a part given up lies where it is: nothing is copied.
        stats.parts_moved = vertices
            .as_ref()
            .filter(|v| v.allocate.is_some())
            .map_or(0, |v| {
                let moved = |s: &&Span| matches!(s, Span::Moved { .. });
                v.spans.iter().filter(moved).count()
            });
        lv.upload = VolumeUpload {
            at: vertices.as_ref().map_or(0, |v| v.at),
            allocate: vertices.as_ref().and_then(|v| v.allocate),
            spans: vertices.map(|v| v.spans),
            indices: (!layout.indices.is_empty()).then_some(layout.indices),
        };
        stats.build_ms = start.elapsed().as_secs_f64() * 1e3;
        lv.draws = draws;
        lv.parts = layout.parts;
        lv.inputs = inputs;
        lv.stats = stats;
        Ok(())
    }

    /// Drops the least recently planned kept parts, of every light, until those kept hold at
    /// most `shadow_volume.kept_mb` of vertices; then gives up CPU copies of uploaded parts
    /// (see `shadow_volume.relayout_on_gpu`): past as much again where `cull_clipped` reads
    /// their triangles, all of them where nothing does. Parts planned by the latest prepare
    /// stay.
    fn evict(&mut self, o: &ShadowVolumeOptions, cull_clipped: bool) {
        let vertex_bytes = std::mem::size_of::<[f32; 4]>();
        let budget = (f64::from(o.kept_mb) * 1048576.0 / vertex_bytes as f64) as usize;
        self.evict_kept(budget);
        if o.relayout_on_gpu {
            self.give_up_copies(if cull_clipped { budget } else { 0 });
        } else {
            self.evict_copies(budget);
        }
    }

    /// Kept parts past `budget` vertices, least recently planned first.
    fn evict_kept(&mut self, budget: usize) {
        self.evict_where(
            budget,
            true,
            |_, c| if c.kept { c.len() } else { 0 },
            |lv, id| {
                lv.meshes.remove(&id);
            },
        );
    }

    /// Unkept parts past `budget` vertices, least recently planned first, among lights whose
    /// upload is made ([`VolumePlanner::uploaded`]): their vertices are in the GPU's buffer,
    /// which draws them as long as the light's draws are kept whole; a later layout builds
    /// them again. Without it the paper's frame held every light's volumes twice (oa_dm3:
    /// 764 MB here beside 645 MB in the buffers).
    fn evict_copies(&mut self, budget: usize) {
        self.evict_where(
            budget,
            true,
            |lv, c| {
                let counted = !c.kept && lv.upload.spans.is_none();
                if counted { c.len() } else { 0 }
            },
            |lv, id| {
                lv.meshes.remove(&id);
            },
        );
    }

    /// The CPU copies of uploaded parts past `budget` vertices given up, least recently
    /// planned first, among lights whose upload is made: the light's buffer holds them, and a
    /// later layout copies them from there (`shadow_volume.relayout_on_gpu`). The latest
    /// prepare's parts too: where it lays them out they are taken from the buffer.
    fn give_up_copies(&mut self, budget: usize) {
        self.evict_where(
            budget,
            false,
            |lv, c| {
                let copy = c.on_cpu() && c.at.is_some() && lv.upload.spans.is_none();
                if copy { c.len() } else { 0 }
            },
            |lv, id| {
                if let Some(c) = lv.meshes.get_mut(&id) {
                    c.mesh.vertices = Vec::new();
                }
            },
        );
    }

    /// The parts `weight` counts (their vertices; 0: not counted), least recently planned
    /// first, handed to `drop` until those counted hold at most `budget` vertices; with
    /// `spare_latest`, parts planned by the latest prepare stay.
    fn evict_where(
        &mut self,
        budget: usize,
        spare_latest: bool,
        weight: impl Fn(&LightVolumeDraws, &CachedPart) -> usize,
        drop: impl Fn(&mut LightVolumeDraws, PartId),
    ) {
        let weight = &weight;
        let parts = || {
            self.lights.iter().flat_map(move |(&light, lv)| {
                lv.meshes
                    .iter()
                    .map(move |(&id, c)| (c.used, light, id, weight(lv, c)))
                    .filter(|k| k.3 > 0)
            })
        };
        // Within the budget (every frame but those that fill it) nothing is listed or sorted.
        let mut held: usize = parts().map(|k| k.3).sum();
        if held <= budget {
            return;
        }
        let mut listed: Vec<(u64, usize, PartId, usize)> = parts().collect();
        listed.sort_unstable_by_key(|k| (k.0, k.1, k.2));
        for (used, light, id, vertices) in listed {
            if held <= budget || (spare_latest && used >= self.clock) {
                break;
            }
            if let Some(lv) = self.lights.get_mut(&light) {
                drop(lv, id);
                held -= vertices;
            }
        }
    }
}

impl LightVolumeDraws {
    /// Marks the pieces kept: those of a still light (where it was when last prepared, or
    /// never prepared) and of a still group (the world, or a model as it was then), unsplit.
    /// Notes the light and groups as they are now; a light that moved drops its kept parts.
    fn mark_kept(
        &mut self,
        scene: &Scene,
        groups: &CasterGroups,
        pieces: &mut [Piece],
        keep: bool,
    ) {
        let l = &scene.lights[self.light];
        let at = (l.position, l.radius);
        let light_still = self.light_at.is_none_or(|a| a == at);
        if !light_still {
            self.meshes.retain(|_, c| !c.kept);
        }
        self.light_at = Some(at);
        for p in pieces.iter_mut() {
            let g = &groups.groups[p.group];
            let state = match g.owner {
                crate::scene::SurfaceOwner::World => None,
                crate::scene::SurfaceOwner::Model(_) => {
                    let mut h = std::hash::DefaultHasher::new();
                    (p.model.to_cols_array().map(f32::to_bits), g.pose).hash(&mut h);
                    Some(std::hash::Hasher::finish(&h))
                }
            };
            let group_still = match state {
                None => true,
                Some(now) => self.groups_at.insert(p.group, now) == Some(now),
            };
            p.kept = keep && light_still && group_still && !matches!(p.id, PieceId::Split { .. });
        }
    }
}

impl RangeReceivers {
    /// The boxes of every visible surface within the light's range: the world's found again
    /// only when the light moved (or the scene changed), the models' each time.
    fn update(&mut self, scene: &Scene, light: usize) {
        let l = &scene.lights[light];
        let in_range = |s: &&crate::scene::Surface| {
            scene.materials[s.material].visible
                && crate::plan::cull::sphere_meets_aabb(l.position, l.radius, &s.bounds)
        };
        let is_world = |s: &&crate::scene::Surface| s.owner == crate::scene::SurfaceOwner::World;
        let mut h = std::hash::DefaultHasher::new();
        (
            l.position.to_array().map(f32::to_bits),
            l.radius.to_bits(),
            scene.surfaces.len(),
        )
            .hash(&mut h);
        let world_key = std::hash::Hasher::finish(&h);
        if self.world_key != Some(world_key) {
            self.world = scene
                .surfaces
                .iter()
                .filter(is_world)
                .filter(in_range)
                .map(|s| s.bounds)
                .collect();
            self.world_key = Some(world_key);
        }
        self.boxes.clear();
        self.boxes.extend_from_slice(&self.world);
        let reach = self.reach.get_or_insert_with(|| {
            (0..scene.models.len())
                .map(|m| scene.motion.reach(scene, m))
                .collect()
        });
        // A model with surfaces, all inside its reach, is that box; one outside (moved some
        // other way), its surfaces.
        let model_of = |s: &crate::scene::Surface| match s.owner {
            crate::scene::SurfaceOwner::Model(m) => Some(m),
            crate::scene::SurfaceOwner::World => None,
        };
        let (mut has_surfaces, mut strays) = (vec![false; reach.len()], vec![false; reach.len()]);
        for s in &scene.surfaces {
            if let Some(m) = model_of(s).filter(|&m| m < reach.len()) {
                has_surfaces[m] = true;
                strays[m] |= !reach[m].is_some_and(|r| r.contains(&s.bounds));
            }
        }
        let as_reach = |m: usize| m < reach.len() && has_surfaces[m] && !strays[m];
        for (m, r) in reach.iter().enumerate() {
            if let Some(r) = r.filter(|_| as_reach(m))
                && crate::plan::cull::sphere_meets_aabb(l.position, l.radius, &r)
            {
                self.boxes.push(r);
            }
        }
        let by_surfaces = |s: &&crate::scene::Surface| model_of(s).is_some_and(|m| !as_reach(m));
        self.boxes.extend(
            scene
                .surfaces
                .iter()
                .filter(by_surfaces)
                .filter(in_range)
                .map(|s| s.bounds),
        );
        let mut h = std::hash::DefaultHasher::new();
        world_key.hash(&mut h);
        for b in &self.boxes[self.world.len()..] {
            hash_box(b).hash(&mut h);
        }
        self.hash = std::hash::Hasher::finish(&h);
    }
}
