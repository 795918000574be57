//! Each subdivided light's shadowed fragments on the GPU (`technique = subdivision`): built once
//! per light and geometry (the subdivision's content key), drawn every frame into the stencil.

use super::upload::{Buffers, buffer_data};
use crate::scene::{Cull, Scene};
use crate::truth::subdivision::{self, CacheWrite, Geometry, SubdivisionError, SubdivisionStats};
use glow::HasContext;
use std::collections::HashMap;
use std::time::Instant;

/// One light's uploaded fragments and the keys they were built for.
struct LightFragments {
    key: u64,
    /// [`quick_key`] when `key` was last confirmed.
    quick: u64,
    buffers: Buffers,
    marks: [MarkRange; 3],
    stats: SubdivisionStats,
    /// Bytes of its corners on the GPU.
    bytes: u64,
}

/// The corners of one cull mode's fragments in a light's buffer: each is drawn culled as its
/// surface's material is in the unlit pass, so that a one-sided surface seen from behind,
/// which left no depth, marks nothing through it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MarkRange {
    pub cull: Cull,
    pub first: i32,
    pub count: i32,
}

/// What can change a light's subdivision without a new scene revision, cheap to hash: the
/// light's position and range, and when models are cut too each model's transform and pose.
/// While it holds (and the geometry's revision) the content key, which hashes every triangle
/// in range (96 ms a frame for oa_dm3's 64 lights), is not computed again.
fn quick_key(scene: &Scene, light: usize, geometry: Geometry) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    scene.revision().hash(&mut h);
    let l = &scene.lights[light];
    for c in l.position.to_array() {
        c.to_bits().hash(&mut h);
    }
    l.radius.to_bits().hash(&mut h);
    let models = match geometry {
        Geometry::Everything => &scene.models[..],
        Geometry::World => &[],
    };
    (geometry == Geometry::World).hash(&mut h);
    for m in models {
        m.pose.hash(&mut h);
        for c in m.transform.to_cols_array() {
            c.to_bits().hash(&mut h);
        }
    }
    h.finish()
}

/// Whose shadowed fragments are marked: surfaces the lit pass lights and the unlit pass drew
/// opaque and whole. Not translucent ones (no depth of their own), nor alpha-tested ones (their
/// fragments carry no texture coordinates, so they would mark through the holes): those stay
/// lit where shadowed.
fn marked(scene: &Scene, surface: u32, cull: Cull) -> bool {
    let m = &scene.materials[scene.surfaces[surface as usize].material];
    m.receives_light && !m.translucent && m.alpha_test.is_none() && m.cull == cull
}

/// A light's fragments ready to draw: the vertex array (vec4 positions at attribute 0, as the
/// volumes' are), its buffer for the legacy pipeline's arrays, and the corner count.
#[derive(Clone, Copy)]
pub struct LightFragmentDraw {
    pub vao: glow::VertexArray,
    pub vbo: glow::Buffer,
    pub ebo: glow::Buffer,
    pub marks: [MarkRange; 3],
}

impl LightFragmentDraw {
    /// Triangles drawn.
    pub fn triangles(&self) -> usize {
        self.marks.iter().map(|m| m.count as usize / 3).sum()
    }
}

/// What bringing a light's fragments up to date cost.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FragmentsUpdate {
    /// The subdivision's own statistics (build time zero when read from the disk cache).
    pub stats: SubdivisionStats,
    /// Whether the light's fragments were built or read this frame (false: kept from before).
    pub renewed: bool,
    /// Milliseconds spent: the key, and when renewed the build or read and the upload.
    pub ms: f64,
}

#[derive(Debug, thiserror::Error)]
pub enum FragmentError {
    #[error(transparent)]
    Subdivision(#[from] SubdivisionError),
    #[error("GL: {0}")]
    Gl(String),
    #[error("light {light}: {corners} fragment corners are more than one draw can hold")]
    TooLarge { light: usize, corners: usize },
}

/// Every subdivided light's fragment buffers.
#[derive(Default)]
pub struct FragmentBuffers {
    lights: HashMap<usize, LightFragments>,
}

impl FragmentBuffers {
    /// Makes light `light`'s fragments those of `scene`'s `geometry` as it stands: kept when
    /// the light and the triangles in its range are unchanged, else read from the disk cache
    /// (when there is one) or subdivided, and uploaded.
    pub fn update(
        &mut self,
        gl: &glow::Context,
        scene: &Scene,
        (light, geometry): (usize, Geometry),
    ) -> Result<FragmentsUpdate, FragmentError> {
        let start = Instant::now();
        let kept = |f: &LightFragments| FragmentsUpdate {
            stats: f.stats,
            renewed: false,
            ms: start.elapsed().as_secs_f64() * 1e3,
        };
        let quick = (light < scene.lights.len()).then(|| quick_key(scene, light, geometry));
        if let Some(f) = self.lights.get(&light).filter(|f| Some(f.quick) == quick) {
            return Ok(kept(f));
        }
        let key = subdivision::content_key_of(scene, light, geometry)?;
        let quick = quick.unwrap_or_default();
        if let Some(f) = self.lights.get_mut(&light).filter(|f| f.key == key) {
            // Something moved, but nothing in the light's range.
            f.quick = quick;
            return Ok(kept(f));
        }
        // A light built before with other triangles moved, or something in its range did: its
        // new pose is read if some run wrote it, not written (one file per frame otherwise).
        let write = match self.lights.contains_key(&light) {
            true => CacheWrite::ReadOnly,
            false => CacheWrite::Write,
        };
        let sub = match subdivision::default_cache_dir() {
            Some(dir) => subdivision::subdivide_cached(scene, light, geometry, (&dir, write))?,
            None => subdivision::subdivide_geometry(scene, light, geometry)?,
        };
        let mut corners = Vec::new();
        let mut marks = [Cull::Back, Cull::Front, Cull::None].map(|cull| MarkRange {
            cull,
            first: 0,
            count: 0,
        });
        for m in &mut marks {
            let first = corners.len();
            corners.extend(sub.shadowed_triangles(|s| marked(scene, s, m.cull)));
            let too_large = || FragmentError::TooLarge {
                light,
                corners: corners.len(),
            };
            m.first = i32::try_from(first).map_err(|_| too_large())?;
            m.count = i32::try_from(corners.len() - first).map_err(|_| too_large())?;
        }
        let entry = match self.lights.remove(&light) {
            Some(old) => old.buffers,
            None => Buffers::new(gl).map_err(FragmentError::Gl)?,
        };
        // SAFETY: uploads plain f32 corners into the light's own buffer; attribute 0 is a vec4
        // position, as in the volumes' arrays.
        unsafe {
            gl.bind_vertex_array(Some(entry.vao));
            gl.bind_buffer(glow::ARRAY_BUFFER, Some(entry.vbo));
            buffer_data(gl, glow::ARRAY_BUFFER, &corners, glow::STATIC_DRAW);
            gl.enable_vertex_attrib_array(0);
            gl.vertex_attrib_pointer_f32(0, 4, glow::FLOAT, false, 16, 0);
            gl.bind_vertex_array(None);
            gl.bind_buffer(glow::ARRAY_BUFFER, None);
        }
        self.lights.insert(
            light,
            LightFragments {
                key,
                quick,
                buffers: entry,
                marks,
                stats: sub.stats,
                bytes: std::mem::size_of_val(corners.as_slice()) as u64,
            },
        );
        Ok(FragmentsUpdate {
            stats: sub.stats,
            renewed: true,
            ms: start.elapsed().as_secs_f64() * 1e3,
        })
    }

    /// Light `light`'s fragments to draw, once [`FragmentBuffers::update`] made them.
    pub fn draw_of(&self, light: usize) -> Option<LightFragmentDraw> {
        self.lights.get(&light).map(|f| LightFragmentDraw {
            vao: f.buffers.vao,
            vbo: f.buffers.vbo,
            ebo: f.buffers.ebo,
            marks: f.marks,
        })
    }

    /// Bytes of every light's fragments on the GPU.
    pub fn bytes(&self) -> u64 {
        self.lights.values().map(|f| f.bytes).sum()
    }

    /// GL objects held (vertex arrays and buffers), for leak checks.
    pub fn object_count(&self) -> usize {
        self.lights.len() * 3
    }

    pub fn delete(&mut self, gl: &glow::Context) {
        for (_, f) in self.lights.drain() {
            f.buffers.delete(gl);
        }
    }
}
