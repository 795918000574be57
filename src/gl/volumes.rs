//! Each light's shadow-volume geometry on the GPU, rebuilt only when something it depends on
//! changed (the light, a caster's transform, the build settings, the counting of a part) unless
//! caching is off.

use super::upload::buffer_data;
use crate::options::ShadowVolumeOptions;
use crate::plan::clipped::{ClipTest, block_bounds};
use crate::plan::depth_bounds::{DepthBound, MAX_PLANES};
use crate::plan::merge::{KeptChunk, merged_spans};
use crate::plan::occlusion::DepthPyramid;
use crate::plan::scissor::{Scissor, points_scissor};
use crate::plan::{CameraSetup, LightPlan, PartTriangles};
use crate::scene::Aabb;
use crate::scene::Scene;
use crate::shadow::volume::{self, Counting, VolumeSettings};
use glam::Mat4;
use glow::HasContext;
use serde::Serialize;
use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::time::Instant;

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
    /// Depth-pass parts whose clip planes were fitted before, for this rectangle and this
    /// depth buffer: by an earlier frame with the same depth (`plan.reuse_depth_fits`), or
    /// for another part or light of this frame.
    pub depth_fits_reused: usize,
    /// Triangles of those parts left out of the draw because one clip plane rejects all
    /// three corners (`plan.cull_clipped`); a part left with none is not drawn. `quads` and
    /// `cap_triangles` count the drawn parts' triangles before this.
    pub triangles_clipped: usize,
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
    /// Part of a chunk (`chunked`) or component split by counting (`plan.split_counting`):
    /// its triangles near the near plane, or the rest.
    Split {
        index: usize,
        chunked: bool,
        near_plane: bool,
    },
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
    /// The triangles the clip planes leave anything of, as (first, count) in the light's
    /// index buffer (`plan.cull_clipped`); None: all of them, straight from the vertices.
    pub elements: Option<(i32, i32)>,
}

impl PartRange {
    /// False for a part whose rectangle is empty (its counts can change no receiver in view)
    /// or whose every triangle the clip planes reject.
    pub fn drawn(&self) -> bool {
        self.scissor.is_none_or(|s| s.area() > 0) && self.elements.is_none_or(|(_, n)| n > 0)
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

pub struct LightVolumes {
    pub vao: glow::VertexArray,
    vbo: glow::Buffer,
    pub parts: Vec<PartRange>,
    /// The stencil pass's draw calls over `parts`.
    pub draws: Vec<VolumeDraw>,
    pub stats: VolumeStats,
    /// Each part's last geometry, by group and piece, with what it was built from.
    meshes: HashMap<(usize, PieceId), CachedPart>,
    /// What the buffer holds: a hash of the written parts' keys in order and their length.
    uploaded: u64,
    /// Vertices in the buffer: no draw may reach past them (llvmpipe reads out of bounds
    /// unchecked).
    uploaded_vertices: usize,
    /// This frame's index buffer (`PartRange::elements`), rewritten every frame that has one.
    ebo: glow::Buffer,
    indices: Vec<u32>,
    /// What the draws were made from (`plan.reuse_volume_draws`; None: not kept).
    inputs: Option<DrawInputs>,
}

/// Everything a light's volume draws are made from: the light's plan, the camera, the depth
/// read back (by its generation), the volume options and the planner's choices, the light and
/// the casters' transforms. While all of it is the same, the draws are what they were.
#[derive(PartialEq)]
struct DrawInputs {
    plan: LightPlan,
    depth: u64,
    camera: CameraSetup,
    options: ShadowVolumeOptions,
    choices: ([bool; 7], usize),
    light: (glam::Vec3, f32),
    transforms: Vec<Mat4>,
}

impl DrawInputs {
    fn of(scene: &Scene, lp: &LightPlan, o: &ShadowVolumeOptions, p: &PieceChoices) -> Self {
        let groups = scene.caster_groups();
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
                ],
                p.depth_clip,
            ),
            light: (light.position, light.radius),
            transforms: lp
                .volumes
                .iter()
                .map(|v| volume::group_transform(scene, groups.groups[v.group].owner))
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
    /// `plan.cull_clipped`: a depth-clipped part draws only the triangles its clip planes do
    /// not wholly reject.
    pub cull_clipped: bool,
    /// `plan.reuse_depth_fits`: fits are kept for the next frame (used while its depth is the
    /// same, see [`VolumeCache::begin_frame`]).
    pub reuse_fits: bool,
    /// `plan.reuse_volume_draws`: a light's draws are kept, and drawn again while nothing they
    /// are made from changed.
    pub reuse_draws: bool,
    /// Which depth `depth` is: a count the renderer advances whenever the depth it reads back
    /// differs from the one it read before, so that draws made from an earlier depth are
    /// never taken for this one's.
    pub depth_generation: u64,
}

#[derive(Default)]
pub struct VolumeCache {
    lights: HashMap<usize, LightVolumes>,
    /// The depth clip planes fitted since the depth buffer last changed, by rectangle and
    /// plane count (`plan.reuse_depth_fits`): a fit reads nothing else.
    fits: HashMap<FitKey, [[f32; 4]; MAX_PLANES]>,
}

/// A fit's inputs besides the depth: the rectangle and the planes allowed.
type FitKey = ([i32; 4], usize);

fn settings(o: &ShadowVolumeOptions) -> VolumeSettings {
    VolumeSettings {
        rule: o.edge_rule,
        extrusion: o.extrusion,
        finite_distance: o.finite_distance,
        facing_epsilon: o.facing_epsilon,
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
    let mut h = std::collections::hash_map::DefaultHasher::new();
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
    /// A split part's triangles (None: those `id` names), and a hash of them for its key.
    subset: Option<volume::Component>,
    subset_key: u64,
}

/// `planned` with the spans of chunks `plan::merge` picks drawn as one piece each (their
/// receivers and rectangles together); the other parts as they were. `whole` stands for the
/// rectangle of a part without one.
fn merge(
    planned: Vec<Piece>,
    groups: &volume::CasterGroups,
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

impl VolumeCache {
    /// Once a frame, before [`VolumeCache::prepare`]: `same_depth` says the depth buffer
    /// (at the frame's size) is the last frame's, so the fits made for it still hold.
    pub fn begin_frame(&mut self, same_depth: bool) {
        if !same_depth {
            self.fits.clear();
        }
    }

    /// The light's volumes: parts whose key changed are rebuilt (all of them when `caching` is
    /// off), the buffer re-uploaded when its contents changed.
    pub fn prepare(
        &mut self,
        gl: &glow::Context,
        scene: &Scene,
        lp: &LightPlan,
        o: &ShadowVolumeOptions,
        pieces: PieceChoices,
    ) -> Result<&LightVolumes, String> {
        let inputs = pieces
            .reuse_draws
            .then(|| DrawInputs::of(scene, lp, o, &pieces));
        let unchanged = inputs.is_some()
            && self
                .lights
                .get(&lp.light)
                .is_some_and(|lv| lv.inputs == inputs);
        if unchanged {
            let lv = self.lights.get_mut(&lp.light).expect("checked above");
            let s = &mut lv.stats;
            s.parts_reused += s.parts_built;
            s.parts_built = 0;
            s.rebuilt = false;
            s.build_ms = 0.0;
            s.draws_reused = true;
            return Ok(lv);
        }
        let camera = pieces.camera;
        // Without receiver boxes (no caster culling) every part is built whole.
        let culling = !lp.volume_receivers.is_empty();
        let receivers: std::borrow::Cow<[crate::scene::Aabb]> =
            match pieces.depth.filter(|_| pieces.occlusion) {
                Some(depth) => lp
                    .volume_receivers
                    .iter()
                    .filter(|b| !depth.hides(camera, b))
                    .copied()
                    .collect(),
                None => lp.volume_receivers.as_slice().into(),
            };
        let start = Instant::now();
        let groups = scene.caster_groups();
        let s = settings(o);
        let light_world = scene.lights[lp.light].position;
        let fits = &mut self.fits;
        let lv = match self.lights.entry(lp.light) {
            std::collections::hash_map::Entry::Occupied(e) => e.into_mut(),
            std::collections::hash_map::Entry::Vacant(e) => {
                // SAFETY: a vertex array and a buffer of our own, kept for this light.
                let (vao, vbo, ebo) = unsafe {
                    (
                        gl.create_vertex_array()?,
                        gl.create_buffer()?,
                        gl.create_buffer()?,
                    )
                };
                e.insert(LightVolumes {
                    vao,
                    vbo,
                    ebo,
                    indices: Vec::new(),
                    parts: Vec::new(),
                    draws: Vec::new(),
                    stats: VolumeStats::default(),
                    meshes: HashMap::new(),
                    uploaded: 0,
                    uploaded_vertices: 0,
                    inputs: None,
                })
            }
        };
        let mut stats = VolumeStats {
            light: lp.light,
            receivers_hidden: lp.volume_receivers.len() - receivers.len(),
            ..VolumeStats::default()
        };
        let radius = scene.lights[lp.light].radius;
        // The receivers' boxes in each caster group's space, and a hash of each.
        let mut local_boxes: HashMap<usize, (Vec<Aabb>, Vec<u64>)> = HashMap::new();
        let mut planned: Vec<Piece> = Vec::with_capacity(lp.volumes.len());
        for p in &lp.volumes {
            let group = &groups.groups[p.group];
            let model = volume::group_transform(scene, group.owner);
            let to_local = model.inverse();
            let light_local = to_local.transform_point3(light_world);
            let whole = group.piece(p.component, p.chunked);
            let (id, subset, subset_key) = match p.triangles {
                PartTriangles::All if p.chunked => {
                    (PieceId::Chunks(p.component, p.component + 1), None, 0)
                }
                PartTriangles::All => (PieceId::Component(p.component), None, 0),
                PartTriangles::NearPlane(i) | PartTriangles::Rest(i) => {
                    let near_plane = matches!(p.triangles, PartTriangles::NearPlane(_));
                    let listed = &lp.near_plane_triangles[i];
                    let subset =
                        group.subset(whole, |t| listed.binary_search(&t).is_ok() == near_plane);
                    let id = PieceId::Split {
                        index: p.component,
                        chunked: p.chunked,
                        near_plane,
                    };
                    let mut h = std::collections::hash_map::DefaultHasher::new();
                    listed.hash(&mut h);
                    (id, Some(subset), h.finish())
                }
            };
            let piece = subset.as_ref().unwrap_or(whole);
            let (boxes, _) = local_boxes.entry(p.group).or_insert_with(|| {
                let boxes: Vec<Aabb> = receivers.iter().map(|b| b.transformed(&to_local)).collect();
                let hashes = boxes
                    .iter()
                    .map(|b| {
                        let mut h = std::collections::hash_map::DefaultHasher::new();
                        [b.min.to_array(), b.max.to_array()]
                            .map(|a| a.map(f32::to_bits))
                            .hash(&mut h);
                        h.finish()
                    })
                    .collect();
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
            // A piece's volume is closed, so its counts cancel wherever the visible surface is
            // outside it: only receiver points in its shadow (within the range, inside
            // `piece_shadow`) can see a change. Their boxes, cut to that shadow, bound it.
            let rect = if pieces.scissor && culling {
                let light_rect = lp.scissor.unwrap_or_else(|| Scissor::full(camera));
                let mut rect: Option<Scissor> = None;
                for &i in &near {
                    let cut = boxes[i as usize].intersection(&piece_shadow);
                    let corners = cut.corners().map(|c| model.transform_point3(c));
                    if let Some(r) = points_scissor(camera, &corners).filter(|r| r.area() > 0) {
                        rect = Some(rect.map_or(r, |u| u.union(&r)));
                    }
                }
                Some(rect.map_or(Scissor::EMPTY, |r| r.intersect(&light_rect)))
            } else {
                None
            };
            planned.push(Piece {
                group: p.group,
                id,
                counting: p.counting,
                model,
                light_local,
                local_radius,
                near,
                rect,
                subset,
                subset_key,
            });
        }
        let drawn_pieces = if pieces.merge {
            let whole = lp.scissor.unwrap_or_else(|| Scissor::full(camera));
            merge(planned, &groups, whole, &mut stats)
        } else {
            planned
        };
        let mut keys = Vec::with_capacity(drawn_pieces.len());
        for p in &drawn_pieces {
            let group = &groups.groups[p.group];
            let (boxes, box_hashes) = &local_boxes[&p.group];
            let receivers_key = {
                let mut h = std::collections::hash_map::DefaultHasher::new();
                culling.hash(&mut h);
                pieces.truncate.hash(&mut h);
                p.local_radius.to_bits().hash(&mut h);
                for &i in &p.near {
                    box_hashes[i as usize].hash(&mut h);
                }
                h.finish()
            };
            let key = part_key(light_world, o, p, &p.model, receivers_key);
            let cached = lv
                .meshes
                .get(&(p.group, p.id))
                .is_some_and(|c| o.caching && c.key == key);
            if cached {
                stats.parts_reused += 1;
            } else {
                use std::borrow::Cow;
                // A split part carries its triangles; the others are named by their id.
                let piece: Cow<volume::Component> = match (&p.subset, p.id) {
                    (Some(subset), _) => Cow::Borrowed(subset),
                    (None, PieceId::Chunks(first, end)) if end == first + 1 => {
                        Cow::Borrowed(&group.chunks[first])
                    }
                    (None, PieceId::Chunks(first, end)) => Cow::Owned(group.chunk_span(first, end)),
                    (None, PieceId::Component(i)) => Cow::Borrowed(&group.components[i]),
                    (None, PieceId::Split { index, chunked, .. }) => {
                        Cow::Borrowed(group.piece(index, chunked))
                    }
                };
                let with_caps = p.counting == Counting::ZFail;
                let near: Vec<Aabb> = p.near.iter().map(|&i| boxes[i as usize]).collect();
                let cull = culling.then_some(volume::ReceiverCull {
                    boxes: &near,
                    radius: p.local_radius,
                    // An explicit finite extrusion (the paper's option) is the user's to see.
                    truncate: pieces.truncate && o.extrusion == volume::Extrusion::Infinite,
                });
                let mesh = volume::build_volume_of(
                    group,
                    &piece,
                    p.light_local.as_dvec3(),
                    &s,
                    with_caps,
                    cull,
                );
                stats.triangles_culled += mesh.culled;
                stats.triangles_tested += piece.triangles.len();
                stats.parts_built += 1;
                let blocks = block_bounds(&mesh.vertices);
                lv.meshes
                    .insert((p.group, p.id), CachedPart { key, mesh, blocks });
            }
            match p.counting {
                Counting::ZFail => stats.zfail_parts += 1,
                Counting::ZPass => stats.zpass_parts += 1,
            }
            keys.push(key);
        }
        // Parts no longer drawn are dropped: the cache holds this frame's parts only.
        let wanted: std::collections::HashSet<(usize, PieceId)> =
            drawn_pieces.iter().map(|p| (p.group, p.id)).collect();
        lv.meshes.retain(|k, _| wanted.contains(k));
        let mut parts = Vec::with_capacity(drawn_pieces.len());
        // Vertices the buffer holds before each part.
        let mut total = 0usize;
        let mut scissored = 0.0;
        // Depth-fail parts first, each group's together, so that runs of parts can share a
        // draw call (a depth-pass part has no caps: its sides are all it draws).
        let mut order: Vec<_> = drawn_pieces.iter().zip(keys).collect();
        order.sort_by_key(|(p, _)| (p.counting != Counting::ZFail, p.group));
        // The buffer holds every planned part in this order, so that its layout follows the
        // part keys alone; a part off screen is skipped when drawing, not when uploading (as
        // the camera turns, parts leave and enter the screen with nothing rebuilt).
        let mut layout = std::collections::hash_map::DefaultHasher::new();
        let mut drawn = 0usize;
        let mut indices = std::mem::take(&mut lv.indices);
        indices.clear();
        for (p, key) in order {
            let cached = &lv.meshes[&(p.group, p.id)];
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
                depth_clip: match pieces
                    .depth
                    .filter(|_| pieces.depth_clip > 0 && p.counting == Counting::ZPass)
                {
                    Some(depth) => {
                        let r = p.rect.or(lp.scissor).unwrap_or(Scissor::full(camera));
                        let key = ([r.x, r.y, r.width, r.height], pieces.depth_clip);
                        match fits.get(&key) {
                            Some(planes) => {
                                stats.depth_fits_reused += 1;
                                *planes
                            }
                            None => {
                                let planes = depth_clip(depth, camera, &r, pieces.depth_clip);
                                if pieces.reuse_fits {
                                    fits.insert(key, planes);
                                }
                                planes
                            }
                        }
                    }
                    None => [[0.0; 4]; MAX_PLANES],
                },
                elements: None,
            };
            let test = ClipTest::new(camera.view_proj * p.model, &range.depth_clip)
                .filter(|_| pieces.cull_clipped && range.drawn());
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
            scissored += p.rect.map_or(1.0, |s| {
                s.area() as f64 / Scissor::full(camera).area().max(1) as f64
            });
            stats.quads += mesh.quads;
            stats.cap_triangles += mesh.cap_vertices / 3;
        }
        total.hash(&mut layout);
        let contents = layout.finish();
        stats.rebuilt = stats.parts_built > 0;
        stats.part_scissor_fraction = if drawn == 0 {
            0.0
        } else {
            scissored / drawn as f64
        };
        if contents != lv.uploaded || stats.rebuilt {
            // Gathered only when the buffer must change: unchanged, the parts' ranges hold.
            let mut vertices: Vec<[f32; 4]> = Vec::with_capacity(total);
            for p in &parts {
                vertices.extend_from_slice(&lv.meshes[&(p.group, p.piece)].mesh.vertices);
            }
            // SAFETY: uploads plain f32 vertices; attribute 0 is a vec4 position.
            unsafe {
                gl.bind_vertex_array(Some(lv.vao));
                gl.bind_buffer(glow::ARRAY_BUFFER, Some(lv.vbo));
                buffer_data(gl, glow::ARRAY_BUFFER, &vertices, glow::DYNAMIC_DRAW);
                gl.enable_vertex_attrib_array(0);
                gl.vertex_attrib_pointer_f32(0, 4, glow::FLOAT, false, 16, 0);
                gl.bind_vertex_array(None);
                gl.bind_buffer(glow::ARRAY_BUFFER, None);
            }
            lv.uploaded = contents;
            lv.uploaded_vertices = vertices.len();
        }
        if !indices.is_empty() {
            // SAFETY: uploads plain u32 indices into the light's own vertex array's index
            // buffer (bound while the array is, so the array keeps it).
            unsafe {
                gl.bind_vertex_array(Some(lv.vao));
                gl.bind_buffer(glow::ELEMENT_ARRAY_BUFFER, Some(lv.ebo));
                buffer_data(gl, glow::ELEMENT_ARRAY_BUFFER, &indices, glow::STREAM_DRAW);
                gl.bind_vertex_array(None);
                gl.bind_buffer(glow::ELEMENT_ARRAY_BUFFER, None);
            }
        }
        stats.build_ms = start.elapsed().as_secs_f64() * 1e3;
        let draws = draws_of(&parts);
        // llvmpipe reads past a buffer unchecked: every draw and index must stay inside.
        let uploaded = |d: &VolumeDraw| {
            if d.indexed {
                indices.len()
            } else {
                lv.uploaded_vertices
            }
        };
        if let Some(d) = draws
            .iter()
            .find(|d| (d.first + d.count) as usize > uploaded(d))
        {
            return Err(format!(
                "light {}: a volume draw ends at {} past the {} uploaded",
                lp.light,
                d.first + d.count,
                uploaded(d)
            ));
        }
        if indices.iter().any(|&i| i as usize >= lv.uploaded_vertices) {
            return Err(format!(
                "light {}: a volume index points past the {} vertices uploaded",
                lp.light, lv.uploaded_vertices
            ));
        }
        lv.indices = indices;
        lv.inputs = inputs;
        lv.draws = draws;
        lv.parts = parts;
        lv.stats = stats;
        Ok(&self.lights[&lp.light])
    }

    /// The light's volumes as last prepared.
    pub fn get(&self, light: usize) -> Option<&LightVolumes> {
        self.lights.get(&light)
    }

    /// GL objects held (vertex arrays and buffers), for leak checks.
    pub fn object_count(&self) -> usize {
        self.lights.len() * 3
    }

    pub fn delete(&mut self, gl: &glow::Context) {
        self.fits.clear();
        for (_, v) in self.lights.drain() {
            // SAFETY: our own objects, deleted once.
            unsafe {
                gl.delete_vertex_array(v.vao);
                gl.delete_buffer(v.vbo);
                gl.delete_buffer(v.ebo);
            }
        }
    }
}
