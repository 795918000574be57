//! A still light's kept volumes built before the light is first seen (`plan.build_ahead`): the
//! first sight of a room then builds nothing, where it would otherwise build every piece its
//! lights draw there in one frame.

use super::pieces::light_in_group;
use super::{Piece, PieceId, VolumeDrawError, VolumePlanner, VolumeStats};
use crate::options::ShadowVolumeOptions;
use crate::plan::cull;
use crate::scene::{Scene, SurfaceOwner};
use crate::shadow::volume::{CasterGroups, Counting};
use std::collections::HashMap;

/// What building one light's volumes ahead made.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Ahead {
    pub light: usize,
    /// Parts built.
    pub parts: usize,
    /// Vertices its buffer holds (all its kept parts).
    pub vertices: usize,
}

impl VolumePlanner {
    /// Builds the kept parts of still light `light`: every chunk of the world within its
    /// range whose shadow meets a receiver there, as a frame planning that chunk would build
    /// it (the same key: such a frame reuses it), and readies the whole kept region of the
    /// light's buffer for upload ([`LightVolumeDraws::upload`]), so that the frame uploads
    /// only what follows it. `truncate`: `plan.truncate_volumes`. An error is a layout bug:
    /// the light is then best forgotten.
    pub fn prepare_ahead(
        &mut self,
        scene: &Scene,
        groups: &CasterGroups,
        light: usize,
        o: &ShadowVolumeOptions,
        truncate: bool,
    ) -> Result<Ahead, VolumeDrawError> {
        self.clock += 1;
        let lv = self.lights.entry(light).or_default();
        lv.light = light;
        let l = &scene.lights[light];
        lv.light_at = Some((l.position, l.radius));
        lv.range.update(scene, light);
        let pieces = world_pieces_in_range(scene, groups, light, &lv.range.boxes);
        let mut stats = VolumeStats::default();
        lv.build_parts(
            groups,
            &pieces,
            &HashMap::new(),
            (l.position, o, true, truncate),
            (self.clock, &mut stats),
        );
        let vertices = lv.ready_kept_region()?;
        Ok(Ahead {
            light,
            parts: stats.parts_built,
            vertices,
        })
    }

    /// Vertices of every light's kept parts together (what `shadow_volume.kept_mb` bounds).
    pub fn kept_vertices(&self) -> usize {
        self.lights
            .values()
            .flat_map(|l| l.meshes.values())
            .filter(|c| c.kept)
            .map(|c| c.len())
            .sum()
    }

    /// The light's upload was made: its vertices need not be held for it any longer, and the
    /// CPU copies of its parts may be given up or evicted.
    pub fn uploaded(&mut self, light: usize) {
        if let Some(lv) = self.lights.get_mut(&light) {
            lv.upload_made();
        }
    }
}

/// Every chunk of the world within the light's range whose shadow meets one of `boxes` (its
/// range receivers), as a kept piece: any chunk a frame plans for the light is among them.
fn world_pieces_in_range(
    scene: &Scene,
    groups: &CasterGroups,
    light: usize,
    boxes: &[crate::geometry::Aabb],
) -> Vec<Piece> {
    let l = &scene.lights[light];
    let mut pieces = Vec::new();
    for (gi, g) in groups.groups.iter().enumerate() {
        if g.owner != SurfaceOwner::World {
            continue;
        }
        let (model, light_local, local_radius) = light_in_group(scene, g, light);
        for (ci, chunk) in g.chunks.iter().enumerate() {
            let bounds = chunk.bounds.transformed(&model);
            let shadow = cull::shadow_bounds(&bounds, l.position, l.radius);
            if !cull::sphere_meets_aabb(l.position, l.radius, &bounds)
                || !boxes.iter().any(|b| b.intersects(&shadow))
            {
                continue;
            }
            pieces.push(Piece {
                group: gi,
                id: PieceId::Chunks(ci, ci + 1),
                // Kept parts hold both caps: the counting is the frame's choice of draw.
                counting: Counting::ZFail,
                model,
                light_local,
                local_radius,
                near: Vec::new(),
                rect: None,
                depth_range: None,
                subset: None,
                subset_key: 0,
                kept: true,
            });
        }
    }
    pieces
}
