//! Each light's shadow-volume buffers on the GPU: the planner's
//! [`LightVolumeDraws`](crate::plan::volume_draws::LightVolumeDraws) say what to upload and
//! what to draw; this module holds the buffers and uploads.

use super::upload::{Buffers, buffer_data, buffer_sub_data};
use crate::plan::volume_draws::{LightVolumeDraws, PartRange, VertexSpan, VolumeDraw};
use glow::HasContext;
use std::collections::HashMap;

/// A light's volume draws with the vertex array they read.
#[derive(Clone, Copy)]
pub struct LightVolumes<'a> {
    pub vao: glow::VertexArray,
    /// The buffers the array reads (the fixed-function pipeline points its arrays at them).
    pub vbo: glow::Buffer,
    pub ebo: glow::Buffer,
    pub draws: &'a [VolumeDraw],
    pub parts: &'a [PartRange],
    /// Groups the GPU extrudes (`shadow_volume.gpu_extrusion`).
    pub extruded: &'a [crate::gl::extrusion::ExtrudedDraw],
}

impl LightVolumes<'_> {
    /// Whether anything is counted `counting`.
    pub fn counts(&self, counting: crate::shadow::volume::Counting) -> bool {
        self.draws.iter().any(|d| d.counting == counting)
            || self.extruded.iter().any(|d| d.counting == counting)
    }
}

/// Vertices gathered into one `glBufferSubData` (1 MiB): a light's meshes are thousands of
/// small components, each a call of its own otherwise.
const BATCH_VERTICES: usize = 65536;

/// Small meshes gathered into one write of the bound array buffer, large ones written
/// directly.
struct Batched {
    vertices: Vec<[f32; 4]>,
    /// The vertex the batch starts at.
    at: usize,
}

impl Batched {
    const VERTEX_BYTES: usize = std::mem::size_of::<[f32; 4]>();

    /// Writes `mesh` at vertex `at` (right after what is gathered, or anywhere after a flush).
    fn write(&mut self, gl: &glow::Context, at: usize, mesh: &[[f32; 4]]) {
        if mesh.is_empty() {
            return;
        }
        if self.vertices.len() + mesh.len() > BATCH_VERTICES || self.at + self.vertices.len() != at
        {
            self.flush(gl);
            self.at = at;
        }
        if mesh.len() >= BATCH_VERTICES {
            buffer_sub_data(gl, glow::ARRAY_BUFFER, at * Self::VERTEX_BYTES, mesh);
            self.at = at + mesh.len();
        } else {
            self.vertices.extend_from_slice(mesh);
        }
    }

    fn flush(&mut self, gl: &glow::Context) {
        if !self.vertices.is_empty() {
            buffer_sub_data(
                gl,
                glow::ARRAY_BUFFER,
                self.at * Self::VERTEX_BYTES,
                &self.vertices,
            );
            self.at += self.vertices.len();
            self.vertices.clear();
        }
    }
}

/// Writes `spans` into the bound array buffer from vertex `at` on; a moved span is copied
/// from `old` (the light's buffer before this upload allocated a new one), or, without
/// one, lies where it is.
fn write_spans<'a>(
    gl: &glow::Context,
    mut at: usize,
    spans: impl Iterator<Item = VertexSpan<'a>>,
    old: Option<glow::Buffer>,
) -> Result<(), String> {
    let vertex_bytes = Batched::VERTEX_BYTES;
    let mut batch = Batched {
        vertices: Vec::new(),
        at,
    };
    for span in spans {
        match span {
            VertexSpan::Written(mesh) => {
                batch.write(gl, at, mesh);
                at += mesh.len();
            }
            VertexSpan::Moved { from, vertices } => {
                match old {
                    // SAFETY: copies between two of the light's buffers, within the sizes
                    // the planner allocated them with.
                    Some(old) => unsafe {
                        gl.bind_buffer(glow::COPY_READ_BUFFER, Some(old));
                        gl.copy_buffer_sub_data(
                            glow::COPY_READ_BUFFER,
                            glow::ARRAY_BUFFER,
                            (from * vertex_bytes) as i32,
                            (at * vertex_bytes) as i32,
                            (vertices * vertex_bytes) as i32,
                        );
                        gl.bind_buffer(glow::COPY_READ_BUFFER, None);
                    },
                    None if from == at => {}
                    None => {
                        return Err(format!(
                            "a volume part at vertex {from} moved to {at} within its buffer"
                        ));
                    }
                }
                at += vertices;
            }
        }
    }
    batch.flush(gl);
    Ok(())
}

/// Every light's volume buffers.
#[derive(Default)]
pub struct VolumeBuffers {
    lights: HashMap<usize, Buffers>,
    /// Bytes each light's vertex and index buffers were last given.
    sizes: HashMap<usize, (u64, u64)>,
}

impl VolumeBuffers {
    /// Uploads what `draws` asks for into the light's buffers (made on first use). An
    /// allocation makes a new vertex buffer, into which the parts still in the old one are
    /// copied before it is deleted.
    pub fn upload(&mut self, gl: &glow::Context, draws: &LightVolumeDraws) -> Result<(), String> {
        let b = match self.lights.entry(draws.light) {
            std::collections::hash_map::Entry::Occupied(e) => e.into_mut(),
            std::collections::hash_map::Entry::Vacant(e) => e.insert(Buffers::new(gl)?),
        };
        let up = &draws.upload;
        if let Some(spans) = draws.upload_spans() {
            let vertex_bytes = std::mem::size_of::<[f32; 4]>();
            // SAFETY: uploads plain f32 vertices; attribute 0 is a vec4 position. The planner
            // allocates before writing past what the buffer holds (`VolumeUpload::allocate`).
            unsafe {
                gl.bind_vertex_array(Some(b.vao));
                let old = match up.allocate {
                    Some(n) => {
                        let fresh = gl.create_buffer()?;
                        gl.bind_buffer(glow::ARRAY_BUFFER, Some(fresh));
                        self.sizes.entry(draws.light).or_default().0 = (n * vertex_bytes) as u64;
                        gl.buffer_data_size(
                            glow::ARRAY_BUFFER,
                            (n * vertex_bytes) as i32,
                            glow::DYNAMIC_DRAW,
                        );
                        gl.enable_vertex_attrib_array(0);
                        gl.vertex_attrib_pointer_f32(0, 4, glow::FLOAT, false, 16, 0);
                        Some(std::mem::replace(&mut b.vbo, fresh))
                    }
                    None => {
                        gl.bind_buffer(glow::ARRAY_BUFFER, Some(b.vbo));
                        None
                    }
                };
                let written = write_spans(gl, up.at, spans, old);
                gl.bind_vertex_array(None);
                gl.bind_buffer(glow::ARRAY_BUFFER, None);
                if let Some(old) = old {
                    gl.delete_buffer(old);
                }
                written?;
            }
        }
        if let Some(indices) = &draws.upload.indices {
            self.sizes.entry(draws.light).or_default().1 =
                std::mem::size_of_val(&indices[..]) as u64;
            // SAFETY: uploads plain u32 indices into the light's own vertex array's index
            // buffer (bound while the array is, so the array keeps it).
            unsafe {
                gl.bind_vertex_array(Some(b.vao));
                gl.bind_buffer(glow::ELEMENT_ARRAY_BUFFER, Some(b.ebo));
                buffer_data(gl, glow::ELEMENT_ARRAY_BUFFER, indices, glow::STREAM_DRAW);
                gl.bind_vertex_array(None);
                gl.bind_buffer(glow::ELEMENT_ARRAY_BUFFER, None);
            }
        }
        Ok(())
    }

    /// The light's draws with its vertex array, if its buffers exist.
    pub fn with<'a>(
        &self,
        draws: &'a LightVolumeDraws,
        extruded: &'a [crate::gl::extrusion::ExtrudedDraw],
    ) -> Option<LightVolumes<'a>> {
        self.lights.get(&draws.light).map(|b| LightVolumes {
            vao: b.vao,
            vbo: b.vbo,
            ebo: b.ebo,
            draws: &draws.draws,
            parts: &draws.parts,
            extruded,
        })
    }

    /// Bytes the buffers hold together.
    pub fn bytes(&self) -> u64 {
        self.sizes.values().map(|(v, i)| v + i).sum()
    }

    /// GL objects held (vertex arrays and buffers), for leak checks.
    pub fn object_count(&self) -> usize {
        self.lights.len() * 3
    }

    pub fn delete(&mut self, gl: &glow::Context) {
        for (_, b) in self.lights.drain() {
            b.delete(gl);
        }
        self.sizes.clear();
    }
}
