//! The meshes the GPU extrudes shadow volumes from (`shadow_volume.gpu_extrusion`): one per
//! caster group, uploaded once per pose of its owner (the world's once per scene), whatever
//! the lights do. The stencil pass draws them with `shaders/volume_gpu.vert`.

use super::upload::{Buffers, Plain, buffer_data};
use crate::shadow::extrusion::{ExtrusionMesh, ExtrusionVertex, Role};
use crate::shadow::volume::{CasterGroup, Counting};
use glam::{Mat4, Vec3};
use glow::HasContext;
use std::collections::HashMap;

impl Plain for ExtrusionVertex {}

/// One group's mesh on the GPU.
struct Uploaded {
    buffers: Buffers,
    /// What it was built from: the owner's pose, whether sides are doubled (two-sided), and
    /// the triangle count (a new scene's group of the same index differs).
    built_from: (u64, bool, usize),
    /// (first index, count) of the sides, the front cap and the back cap.
    ranges: [(i32, i32); 3],
}

/// One group's volume in one light's stencil pass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExtrudedDraw {
    pub vao: glow::VertexArray,
    /// The group's space to world.
    pub model: Mat4,
    /// The light in the group's space.
    pub light: Vec3,
    pub counting: Counting,
    ranges: [(i32, i32); 3],
}

impl ExtrudedDraw {
    /// (first index, count) of what `role` draws.
    pub fn range(&self, role: Role) -> (i32, i32) {
        match role {
            Role::Sides => self.ranges[0],
            Role::FrontCap => self.ranges[1],
            Role::BackCap => self.ranges[2],
        }
    }
}

/// Every extruded group's mesh, by group index.
#[derive(Default)]
pub struct Extrusions {
    groups: HashMap<usize, Uploaded>,
}

fn attributes(gl: &glow::Context) {
    let stride = std::mem::size_of::<ExtrusionVertex>() as i32;
    // (location, components, float offset): edge a, edge b, role, then the two faces' normal
    // and corners.
    let mut layout = vec![(0u32, 3i32, 0i32), (1, 3, 3), (2, 1, 6)];
    for (face, base) in [(3u32, 7i32), (7, 19)] {
        for k in 0..4 {
            layout.push((face + k as u32, 3, base + 3 * k));
        }
    }
    // SAFETY: attribute pointers into the bound buffer of ExtrusionVertex records.
    unsafe {
        for (loc, size, offset) in layout {
            gl.enable_vertex_attrib_array(loc);
            gl.vertex_attrib_pointer_f32(loc, size, glow::FLOAT, false, stride, offset * 4);
        }
    }
}

impl Extrusions {
    /// Uploads `group`'s mesh (index `index`) unless it is there for this pose already;
    /// returns the milliseconds the CPU spent building it where it uploaded.
    pub fn ensure(
        &mut self,
        gl: &glow::Context,
        index: usize,
        group: &CasterGroup,
        double: bool,
    ) -> Result<Option<f64>, String> {
        let built_from = (group.pose, double, group.connectivity.triangles.len());
        if self
            .groups
            .get(&index)
            .is_some_and(|u| u.built_from == built_from)
        {
            return Ok(None);
        }
        let start = std::time::Instant::now();
        let mesh = ExtrusionMesh::build(group, double);
        let mut indices =
            Vec::with_capacity(mesh.sides.len() + mesh.front_cap.len() + mesh.back_cap.len());
        let mut ranges = [(0, 0); 3];
        for (k, role) in [Role::Sides, Role::FrontCap, Role::BackCap]
            .into_iter()
            .enumerate()
        {
            let list = mesh.indices(role);
            ranges[k] = (indices.len() as i32, list.len() as i32);
            indices.extend_from_slice(list);
        }
        let build_ms = start.elapsed().as_secs_f64() * 1e3;
        // The old buffers are filled again.
        let buffers = match self.groups.remove(&index) {
            Some(u) => u.buffers,
            None => Buffers::new(gl)?,
        };
        // SAFETY: our own buffers, filled from plain data; the index buffer is bound while
        // the array is, so it keeps it.
        unsafe {
            gl.bind_vertex_array(Some(buffers.vao));
            gl.bind_buffer(glow::ARRAY_BUFFER, Some(buffers.vbo));
            buffer_data(gl, glow::ARRAY_BUFFER, &mesh.vertices, glow::DYNAMIC_DRAW);
            attributes(gl);
            gl.bind_buffer(glow::ELEMENT_ARRAY_BUFFER, Some(buffers.ebo));
            buffer_data(gl, glow::ELEMENT_ARRAY_BUFFER, &indices, glow::DYNAMIC_DRAW);
            gl.bind_vertex_array(None);
            gl.bind_buffer(glow::ARRAY_BUFFER, None);
            gl.bind_buffer(glow::ELEMENT_ARRAY_BUFFER, None);
        }
        self.groups.insert(
            index,
            Uploaded {
                buffers,
                built_from,
                ranges,
            },
        );
        Ok(Some(build_ms))
    }

    /// Group `index`'s draw for a light at `light_world`, if its mesh is uploaded.
    pub fn draw_of(
        &self,
        index: usize,
        model: Mat4,
        light_world: Vec3,
        counting: Counting,
    ) -> Option<ExtrudedDraw> {
        let u = self.groups.get(&index)?;
        Some(ExtrudedDraw {
            vao: u.buffers.vao,
            model,
            light: model.inverse().transform_point3(light_world),
            counting,
            ranges: u.ranges,
        })
    }

    pub fn delete(&mut self, gl: &glow::Context) {
        for (_, u) in self.groups.drain() {
            u.buffers.delete(gl);
        }
    }
}
