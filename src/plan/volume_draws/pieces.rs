//! Which pieces a light's volumes are drawn as: each planned part with the receivers its
//! shadow reaches, its rectangle and depth range, and neighbouring chunks merged.

use super::{Piece, PieceChoices, PieceId, PlannedPieces, VolumeStats, hash_box};
use crate::geometry::Aabb;
use crate::plan::depth_bounds::{DepthRange, EMPTY_RANGE, range_union, window_depth_range};
use crate::plan::merge::{KeptChunk, merged_spans};
use crate::plan::scissor::{Scissor, points_scissor};
use crate::plan::{CameraSetup, LightPlan, PartTriangles};
use crate::scene::Scene;
use crate::shadow::volume::{self, CasterGroups, PieceRef};
use glam::Mat4;
use std::collections::HashMap;
use std::hash::{DefaultHasher, Hash, Hasher};

/// `planned` with the spans of chunks `plan::merge` picks drawn as one piece each (their
/// receivers and rectangles together); the other parts as they were. `whole` stands for the
/// rectangle of a part without one.
pub(super) fn merge(
    planned: Vec<Piece>,
    groups: &CasterGroups,
    whole: Scissor,
    stats: &mut VolumeStats,
) -> Vec<Piece> {
    let by_chunk: HashMap<(usize, usize), usize> = planned
        .iter()
        .enumerate()
        .filter_map(|(i, p)| match p.id {
            // Kept pieces are drawn as built: merged spans change with the camera.
            PieceId::Chunks(c, _) if !p.kept => Some(((p.group, c), i)),
            PieceId::Chunks(..) => None,
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
                kept: false,
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

/// The light's receiver boxes that volumes must reach: those the depth does not hide
/// (`plan.occlusion`), or all of them.
pub(super) fn visible_receivers<'a>(
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

/// Each planned part of the light as a piece: its triangles, transform, the receivers its
/// shadow can reach and (`plan.piece_scissor`) its screen rectangle.
pub(super) fn plan_pieces(
    scene: &Scene,
    groups: &CasterGroups,
    lp: &LightPlan,
    receivers: &[Aabb],
    choices: &PieceChoices,
) -> PlannedPieces {
    // Without receiver boxes (no caster culling) every part is built whole.
    let culling = !lp.volume_receivers.is_empty();
    let mut local_boxes: HashMap<usize, (Vec<Aabb>, Vec<u64>)> = HashMap::new();
    let mut pieces: Vec<Piece> = Vec::with_capacity(lp.volumes.len());
    for p in &lp.volumes {
        let group = &groups.groups[p.group];
        let (model, light_local, local_radius) = light_in_group(scene, group, lp.light);
        let to_local = model.inverse();
        let whole = group.piece(p.piece);
        let (id, subset, subset_key) = piece_triangles(lp, p, group, whole);
        let piece = subset.as_ref().unwrap_or(whole);
        let (boxes, _) = local_boxes.entry(p.group).or_insert_with(|| {
            let boxes: Vec<Aabb> = receivers.iter().map(|b| b.transformed(&to_local)).collect();
            let hashes = boxes.iter().map(hash_box).collect();
            (boxes, hashes)
        });
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
            // Decided with what the light and group were last frame (`mark_kept`).
            kept: false,
        });
    }
    PlannedPieces {
        pieces,
        local_boxes,
    }
}

/// The group's transform, and the light and its range in the group's space (a scaled model
/// stretches the range).
pub(super) fn light_in_group(
    scene: &Scene,
    group: &volume::CasterGroup,
    light: usize,
) -> (Mat4, glam::Vec3, f32) {
    let l = &scene.lights[light];
    let model = volume::group_transform(scene, group.owner);
    let to_local = model.inverse();
    let stretch = [to_local.x_axis, to_local.y_axis, to_local.z_axis]
        .iter()
        .map(|a| a.truncate().length())
        .fold(0.0f32, f32::max);
    let local_radius = l.radius * stretch.max(1e-6);
    (model, to_local.transform_point3(l.position), local_radius)
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
