//! Each light's shadow-volume geometry on the GPU, rebuilt only when something it depends on
//! changed (the light, a caster's transform, the build settings, the counting of a part) unless
//! caching is off.

use crate::options::ShadowVolumeOptions;
use crate::plan::{LightPlan, VolumePart};
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
    /// CPU time of the last build (silhouettes and extrusion).
    pub build_ms: f64,
    /// Whether this frame rebuilt the volumes (false: reused from the cache).
    pub rebuilt: bool,
}

/// One part's vertex ranges in the light's buffer.
#[derive(Debug, Clone, Copy)]
pub struct PartRange {
    pub part: VolumePart,
    pub model: Mat4,
    pub first: i32,
    pub sides: i32,
    pub caps: i32,
}

pub struct LightVolumes {
    key: u64,
    pub vao: glow::VertexArray,
    vbo: glow::Buffer,
    pub parts: Vec<PartRange>,
    pub stats: VolumeStats,
}

#[derive(Default)]
pub struct VolumeCache {
    lights: HashMap<usize, LightVolumes>,
}

fn settings(o: &ShadowVolumeOptions) -> VolumeSettings {
    VolumeSettings {
        rule: o.edge_rule,
        extrusion: o.extrusion,
        finite_distance: o.finite_distance,
        facing_epsilon: o.facing_epsilon,
    }
}

fn key(scene: &Scene, lp: &LightPlan, o: &ShadowVolumeOptions) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    let l = &scene.lights[lp.light];
    l.position.to_array().map(f32::to_bits).hash(&mut h);
    (
        o.edge_rule as u8,
        o.extrusion as u8,
        o.finite_distance.to_bits(),
        o.facing_epsilon.to_bits(),
    )
        .hash(&mut h);
    let groups = scene.caster_groups();
    for p in &lp.volumes {
        (p.group, p.component, p.counting as u8).hash(&mut h);
        volume::group_transform(scene, groups.groups[p.group].owner)
            .to_cols_array()
            .map(f32::to_bits)
            .hash(&mut h);
    }
    h.finish()
}

impl VolumeCache {
    /// The light's volumes, rebuilt if needed (always when `caching` is off).
    pub fn prepare(
        &mut self,
        gl: &glow::Context,
        scene: &Scene,
        lp: &LightPlan,
        o: &ShadowVolumeOptions,
    ) -> Result<&LightVolumes, String> {
        let k = key(scene, lp, o);
        let fresh = match self.lights.get(&lp.light) {
            Some(v) => o.caching && v.key == k,
            None => false,
        };
        if fresh {
            let v = self.lights.get_mut(&lp.light).expect("checked above");
            v.stats.rebuilt = false;
            return Ok(v);
        }
        let start = Instant::now();
        let groups = scene.caster_groups();
        let s = settings(o);
        let light_world = scene.lights[lp.light].position;
        let mut vertices: Vec<[f32; 4]> = Vec::new();
        let mut parts = Vec::new();
        let mut stats = VolumeStats {
            light: lp.light,
            rebuilt: true,
            ..VolumeStats::default()
        };
        for p in &lp.volumes {
            let group = &groups.groups[p.group];
            let model = volume::group_transform(scene, group.owner);
            let light_local = model.inverse().transform_point3(light_world).as_dvec3();
            let with_caps = p.counting == Counting::ZFail;
            let mesh = volume::build_volume(group, p.component, light_local, &s, with_caps);
            stats.triangles_tested += group.components[p.component].triangles.len();
            match p.counting {
                Counting::ZFail => stats.zfail_parts += 1,
                Counting::ZPass => stats.zpass_parts += 1,
            }
            if mesh.vertices.is_empty() {
                continue;
            }
            stats.quads += mesh.quads;
            stats.cap_triangles += mesh.cap_vertices / 3;
            parts.push(PartRange {
                part: *p,
                model,
                first: vertices.len() as i32,
                sides: mesh.side_vertices as i32,
                caps: mesh.cap_vertices as i32,
            });
            vertices.extend_from_slice(&mesh.vertices);
        }
        stats.build_ms = start.elapsed().as_secs_f64() * 1e3;
        let (vao, vbo) = match self.lights.remove(&lp.light) {
            Some(old) => (old.vao, old.vbo),
            // SAFETY: a vertex array and a buffer of our own, kept for this light.
            None => unsafe { (gl.create_vertex_array()?, gl.create_buffer()?) },
        };
        // SAFETY: uploads plain f32 vertices; attribute 0 is a vec4 position.
        unsafe {
            gl.bind_vertex_array(Some(vao));
            gl.bind_buffer(glow::ARRAY_BUFFER, Some(vbo));
            let bytes = std::slice::from_raw_parts(
                vertices.as_ptr() as *const u8,
                std::mem::size_of_val(vertices.as_slice()),
            );
            gl.buffer_data_u8_slice(glow::ARRAY_BUFFER, bytes, glow::DYNAMIC_DRAW);
            gl.enable_vertex_attrib_array(0);
            gl.vertex_attrib_pointer_f32(0, 4, glow::FLOAT, false, 16, 0);
            gl.bind_vertex_array(None);
            gl.bind_buffer(glow::ARRAY_BUFFER, None);
        }
        self.lights.insert(
            lp.light,
            LightVolumes {
                key: k,
                vao,
                vbo,
                parts,
                stats,
            },
        );
        Ok(&self.lights[&lp.light])
    }

    /// The light's volumes as last prepared.
    pub fn get(&self, light: usize) -> Option<&LightVolumes> {
        self.lights.get(&light)
    }

    /// GL objects held (vertex arrays and buffers), for leak checks.
    pub fn object_count(&self) -> usize {
        self.lights.len() * 2
    }

    pub fn delete(&mut self, gl: &glow::Context) {
        for (_, v) in self.lights.drain() {
            // SAFETY: our own objects, deleted once.
            unsafe {
                gl.delete_vertex_array(v.vao);
                gl.delete_buffer(v.vbo);
            }
        }
    }
}
