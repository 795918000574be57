//! What a light's vertex buffer must receive for its layout, and where each part lies in the
//! buffer once the upload is made. A part whose CPU copy was given up
//! (`shadow_volume.relayout_on_gpu`) is copied on the GPU from where it lay.

use super::{CachedPart, Layout, LightVolumeDraws, PieceId, VolumeDrawError};
use std::collections::HashMap;

/// A part in the planner's caches: its caster group and piece.
pub type PartId = (usize, PieceId);

/// The buffers a light's draws need this frame (None: what was uploaded before still holds).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct VolumeUpload {
    /// The parts whose vertices go into the buffer, in buffer order from vertex `at` on:
    /// every part's, or those after the kept parts when only the others changed
    /// ([`LightVolumeDraws::upload_spans`] gives their vertices). Named, not copied: a copy
    /// of every light's volumes for the upload was a third of the paper's frame's memory
    /// (oa_dm3: 515 MB beside the meshes' 764 MB).
    pub spans: Option<Vec<Span>>,
    pub at: usize,
    /// Allocate a new vertex buffer for this many vertices first: moved spans are copied
    /// from the old one, which is then deleted.
    pub allocate: Option<usize>,
    /// The index list of the parts drawn through one (`plan.cull_clipped`).
    pub indices: Option<Vec<u32>>,
}

/// Where one part's vertices come from when the buffer is written.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Span {
    /// Written from the part's CPU copy.
    Written(PartId),
    /// Already in the light's buffer from vertex `from` on (its CPU copy given up): copied
    /// into the new buffer, or left where it lies when the buffer is not allocated again
    /// (the planner then places it at `from`).
    Moved { from: usize, vertices: usize },
}

/// One span's vertices as the GL layer writes them.
pub enum VertexSpan<'a> {
    Written(&'a [[f32; 4]]),
    Moved { from: usize, vertices: usize },
}

/// What [`LightVolumeDraws::upload_for`] decides: spans written from vertex `at` on, the
/// buffer allocated for `allocate` vertices first.
pub(super) struct VertexUpload {
    pub spans: Vec<Span>,
    pub at: usize,
    pub allocate: Option<usize>,
}

/// The vertices a light's buffer is allocated for when it must hold `vertices`: room to grow,
/// so that a kept part seen for the first time does not reallocate it every frame.
pub(super) fn with_headroom(vertices: usize) -> usize {
    vertices + vertices / 4 + 1024
}

impl CachedPart {
    /// Vertices of the part, held on the CPU or not.
    pub(super) fn len(&self) -> usize {
        self.vertices
    }

    /// Whether the CPU holds the part's vertices.
    pub(super) fn on_cpu(&self) -> bool {
        self.mesh.vertices.len() == self.vertices
    }

    /// Whether the part can be drawn without building it again: on the CPU, or in the
    /// light's buffer.
    pub(super) fn held(&self) -> bool {
        self.on_cpu() || self.at.is_some()
    }
}

impl LightVolumeDraws {
    /// The upload's spans, in buffer order from `upload.at` on; None when nothing is to be
    /// uploaded.
    pub fn upload_spans(&self) -> Option<impl Iterator<Item = VertexSpan<'_>>> {
        let spans = self.upload.spans.as_ref()?;
        Some(spans.iter().map(|s| match *s {
            Span::Written(id) => VertexSpan::Written(self.meshes[&id].mesh.vertices.as_slice()),
            Span::Moved { from, vertices } => VertexSpan::Moved { from, vertices },
        }))
    }

    /// What to upload for `layout`: nothing while the buffer holds it; the vertices after the
    /// kept region while that region is as uploaded, the buffer is large enough and every
    /// part given up on the CPU lies where the layout places it; else the whole buffer,
    /// allocated with room to grow (a kept part seen for the first time then does not
    /// reallocate it every frame).
    pub(super) fn upload_for(
        &mut self,
        layout: &Layout,
        rebuilt: bool,
    ) -> Result<Option<VertexUpload>, VolumeDrawError> {
        let kept_same = layout.kept_hash == self.kept_layout;
        let changed = layout.hash != self.layout || rebuilt;
        let tail = &layout.order[layout.kept_meshes..];
        let in_place = !changed || self.all_in_place(tail, layout.kept_vertices);
        let upload = if !kept_same || layout.vertex_count > self.capacity || !in_place {
            let allocate = with_headroom(layout.vertex_count);
            self.capacity = allocate;
            Some(VertexUpload {
                spans: self.spans(&layout.order)?,
                at: 0,
                allocate: Some(allocate),
            })
        } else if changed {
            Some(VertexUpload {
                spans: self.spans(tail)?,
                at: layout.kept_vertices,
                allocate: None,
            })
        } else {
            None
        };
        if upload.is_some() {
            self.placed = placed(&layout.order, |id| self.meshes[id].len());
        }
        self.kept_layout = layout.kept_hash;
        self.layout = layout.hash;
        Ok(upload)
    }

    /// Whether every part of `order` (placed from vertex `at` on) whose CPU copy is given up
    /// lies where it would be placed.
    fn all_in_place(&self, order: &[PartId], mut at: usize) -> bool {
        order.iter().all(|id| {
            let c = &self.meshes[id];
            let here = c.on_cpu() || c.at == Some(at);
            at += c.len();
            here
        })
    }

    /// The spans of `order`.
    fn spans(&self, order: &[PartId]) -> Result<Vec<Span>, VolumeDrawError> {
        order
            .iter()
            .map(|id| {
                let c = &self.meshes[id];
                match (c.on_cpu(), c.at) {
                    (true, _) => Ok(Span::Written(*id)),
                    (false, Some(from)) => Ok(Span::Moved {
                        from,
                        vertices: c.len(),
                    }),
                    (false, None) => Err(VolumeDrawError::PartNotHeld { light: self.light }),
                }
            })
            .collect()
    }

    /// The upload was made: each part placed lies where the layout put it, the others'
    /// places are overwritten (a part held nowhere else is dropped).
    pub(super) fn upload_made(&mut self) {
        if self.upload.spans.is_some() {
            let placed: HashMap<PartId, usize> =
                std::mem::take(&mut self.placed).into_iter().collect();
            self.meshes.retain(|id, c| {
                c.at = placed.get(id).copied();
                c.held()
            });
        }
        self.upload = VolumeUpload::default();
    }

    /// The upload of the whole kept region, allocated with room for the parts a frame adds
    /// after it, noted as what the buffer holds; returns its vertices.
    pub(super) fn ready_kept_region(&mut self) -> Result<usize, VolumeDrawError> {
        let kept = self.kept_region();
        let allocate = with_headroom(kept.vertices);
        let spans = self.spans(&kept.meshes)?;
        self.placed = placed(&kept.meshes, |id| self.meshes[id].len());
        self.kept_layout = kept.hash;
        self.capacity = allocate;
        // No frame's layout yet: the first frame writes what follows the kept region.
        self.layout = 0;
        self.upload = VolumeUpload {
            spans: Some(spans),
            at: 0,
            allocate: Some(allocate),
            indices: None,
        };
        Ok(kept.vertices)
    }
}

/// Each part of `order` with the vertex it starts at, laid one after another from 0.
fn placed(order: &[PartId], len: impl Fn(&PartId) -> usize) -> Vec<(PartId, usize)> {
    let mut at = 0;
    order
        .iter()
        .map(|id| {
            let here = at;
            at += len(id);
            (*id, here)
        })
        .collect()
}
