//! The scene on the GPU: one vertex buffer, one index buffer with surfaces sorted by draw state,
//! textures and lightmaps. Built once per scene.

use crate::images::Rgba;
use crate::scene::{BakedLight, Scene, SurfaceOwner, Vertex};
use glow::HasContext;
use std::rc::Rc;

/// A run of indices drawn with one state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DrawItem {
    pub first_index: u32,
    pub index_count: u32,
    pub material: usize,
    pub lightmap: Option<usize>,
    pub baked: BakedLight,
    pub owner: SurfaceOwner,
}

/// What splits a run of surfaces into draws besides their owner and material.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Merge {
    /// Each surface's baked light too: the base pass binds its lightmap and baked mode.
    ByLightmap,
    /// The owner and material alone: the passes that draw light or depth read no lightmap
    /// (a merged item's `lightmap` and `baked` are its first surface's, and mean nothing).
    ByMaterial,
    /// A depth pass's state alone: the owner and the culling, and the material only where it
    /// is alpha-tested (`alpha_test`: the pass tests alpha). Surfaces of other materials
    /// join one draw (its `material` is the first's: its culling, and no alpha test).
    Depth { alpha_test: bool },
}

impl Merge {
    /// Whether surface `b` may join a draw that `a` began, by this merge's state.
    fn joins(self, scene: &Scene, a: &DrawItem, b: &crate::scene::Surface) -> bool {
        match self {
            Merge::ByLightmap => {
                a.material == b.material && a.lightmap == b.lightmap && a.baked == b.baked
            }
            Merge::ByMaterial => a.material == b.material,
            Merge::Depth { alpha_test } => {
                let (ma, mb) = (&scene.materials[a.material], &scene.materials[b.material]);
                let tested = |m: &crate::scene::Material| alpha_test && m.alpha_test.is_some();
                a.material == b.material || (ma.cull == mb.cull && !tested(ma) && !tested(mb))
            }
        }
    }
}

pub struct GpuScene {
    pub vao: glow::VertexArray,
    vbo: glow::Buffer,
    ibo: glow::Buffer,
    /// The scene's images: shared by renderers on one context drawing one scene
    /// ([`GpuScene::sharing_images`]), deleted with the last of them.
    images: Rc<SceneImages>,
    /// Surfaces in draw-state order.
    order: Vec<usize>,
    /// First index of each surface (by scene surface index) in the GPU index buffer.
    gpu_first: Vec<u32>,
    pub index_count: usize,
    /// Per model: the run of vertices its surfaces use and the pose uploaded there.
    models: Vec<(std::ops::Range<usize>, u64)>,
}

/// The run of scene vertices model `m`'s surfaces use (empty without surfaces).
fn model_vertex_run(scene: &Scene, m: usize) -> std::ops::Range<usize> {
    let mut run: Option<(usize, usize)> = None;
    for s in scene
        .surfaces
        .iter()
        .filter(|s| s.owner == SurfaceOwner::Model(m))
    {
        let range = s.first_index as usize..(s.first_index + s.index_count) as usize;
        for &v in &scene.indices[range] {
            let v = v as usize;
            run = Some(run.map_or((v, v + 1), |(a, b)| (a.min(v), b.max(v + 1))));
        }
    }
    run.map_or(0..0, |(a, b)| a..b)
}

fn state_key(scene: &Scene, s: usize) -> (u8, usize, usize, usize, u8) {
    let surf = &scene.surfaces[s];
    let owner = match surf.owner {
        SurfaceOwner::World => (0, 0),
        SurfaceOwner::Model(m) => (1, m),
    };
    (
        owner.0,
        owner.1,
        surf.material,
        surf.lightmap.map_or(0, |l| l + 1),
        surf.baked as u8,
    )
}

fn upload_image(
    gl: &glow::Context,
    image: &Rgba,
    mipmaps: bool,
    repeat: bool,
) -> Result<glow::Texture, String> {
    // SAFETY: the image holds width*height RGBA8 texels (checked by the loaders); unpack
    // alignment 1 accepts any width.
    unsafe {
        let tex = gl.create_texture()?;
        gl.bind_texture(glow::TEXTURE_2D, Some(tex));
        gl.pixel_store_i32(glow::UNPACK_ALIGNMENT, 1);
        gl.tex_image_2d(
            glow::TEXTURE_2D,
            0,
            glow::RGBA8 as i32,
            image.width as i32,
            image.height as i32,
            0,
            glow::RGBA,
            glow::UNSIGNED_BYTE,
            glow::PixelUnpackData::Slice(Some(&image.data)),
        );
        let wrap = if repeat {
            glow::REPEAT
        } else {
            glow::CLAMP_TO_EDGE
        } as i32;
        gl.tex_parameter_i32(glow::TEXTURE_2D, glow::TEXTURE_WRAP_S, wrap);
        gl.tex_parameter_i32(glow::TEXTURE_2D, glow::TEXTURE_WRAP_T, wrap);
        gl.tex_parameter_i32(
            glow::TEXTURE_2D,
            glow::TEXTURE_MAG_FILTER,
            glow::LINEAR as i32,
        );
        if mipmaps {
            gl.generate_mipmap(glow::TEXTURE_2D);
            gl.tex_parameter_i32(
                glow::TEXTURE_2D,
                glow::TEXTURE_MIN_FILTER,
                glow::LINEAR_MIPMAP_LINEAR as i32,
            );
        } else {
            gl.tex_parameter_i32(
                glow::TEXTURE_2D,
                glow::TEXTURE_MIN_FILTER,
                glow::LINEAR as i32,
            );
        }
        gl.bind_texture(glow::TEXTURE_2D, None);
        Ok(tex)
    }
}

/// A scene's textures and lightmaps on the GPU.
pub struct SceneImages {
    pub textures: Vec<glow::Texture>,
    pub lightmaps: Vec<glow::Texture>,
    /// Bound where a material has no texture.
    pub white: glow::Texture,
}

impl SceneImages {
    fn upload(gl: &glow::Context, scene: &Scene, max_texture_size: u32) -> Result<Self, String> {
        let fit = |img: &Rgba| -> Rgba {
            if img.width.max(img.height) > max_texture_size || img.width == 0 || img.height == 0 {
                log::warn!(
                    "texture {}x{} exceeds GL_MAX_TEXTURE_SIZE {max_texture_size}; drawing white",
                    img.width,
                    img.height
                );
                Rgba::solid([255, 255, 255, 255])
            } else {
                img.clone()
            }
        };
        let textures = scene
            .textures
            .iter()
            .map(|t| upload_image(gl, &fit(t), true, true))
            .collect::<Result<_, _>>()?;
        let lightmaps = scene
            .lightmaps
            .iter()
            .map(|t| upload_image(gl, &fit(t), false, false))
            .collect::<Result<_, _>>()?;
        let white = upload_image(gl, &Rgba::solid([255, 255, 255, 255]), false, true)?;
        Ok(SceneImages {
            textures,
            lightmaps,
            white,
        })
    }

    fn delete(&self, gl: &glow::Context) {
        // SAFETY: called once, by the last renderer holding them.
        unsafe {
            for t in self.textures.iter().chain(&self.lightmaps) {
                gl.delete_texture(*t);
            }
            gl.delete_texture(self.white);
        }
    }
}

impl GpuScene {
    pub fn new(
        gl: &glow::Context,
        scene: &Scene,
        max_texture_size: u32,
    ) -> Result<GpuScene, String> {
        let images = SceneImages::upload(gl, scene, max_texture_size)?;
        Self::with_images(gl, scene, Rc::new(images))
    }

    /// `scene` uploaded with `other`'s images, which must be `scene`'s (a renderer beside
    /// `other`'s, on its context): its vertices and indices are its own (its models' poses
    /// are its own), its textures and lightmaps, most of a map's memory, are not copied.
    pub fn sharing_images(
        gl: &glow::Context,
        scene: &Scene,
        other: &GpuScene,
    ) -> Result<GpuScene, String> {
        Self::with_images(gl, scene, other.images.clone())
    }

    /// The images this scene's textures and lightmaps are, for its draws.
    pub fn images(&self) -> &SceneImages {
        &self.images
    }

    fn with_images(
        gl: &glow::Context,
        scene: &Scene,
        images: Rc<SceneImages>,
    ) -> Result<GpuScene, String> {
        let mut order: Vec<usize> = (0..scene.surfaces.len()).collect();
        order.sort_by_key(|&s| state_key(scene, s));
        let mut indices = Vec::with_capacity(scene.indices.len());
        let mut gpu_first = vec![0u32; scene.surfaces.len()];
        for &s in &order {
            let surf = &scene.surfaces[s];
            gpu_first[s] = indices.len() as u32;
            let range = surf.first_index as usize..(surf.first_index + surf.index_count) as usize;
            indices.extend_from_slice(&scene.indices[range]);
        }
        // SAFETY: buffers are created and filled from slices of plain-old-data vertices.
        unsafe {
            let vao = gl.create_vertex_array()?;
            gl.bind_vertex_array(Some(vao));
            let vbo = gl.create_buffer()?;
            gl.bind_buffer(glow::ARRAY_BUFFER, Some(vbo));
            buffer_data(gl, glow::ARRAY_BUFFER, &scene.vertices, glow::STATIC_DRAW);
            let stride = std::mem::size_of::<Vertex>() as i32;
            let attrs: [(u32, i32, i32); 4] = [(0, 3, 0), (1, 3, 12), (2, 2, 24), (3, 2, 32)];
            for (loc, size, offset) in attrs {
                gl.enable_vertex_attrib_array(loc);
                gl.vertex_attrib_pointer_f32(loc, size, glow::FLOAT, false, stride, offset);
            }
            gl.enable_vertex_attrib_array(4);
            gl.vertex_attrib_pointer_f32(4, 4, glow::UNSIGNED_BYTE, true, stride, 40);
            let ibo = gl.create_buffer()?;
            gl.bind_buffer(glow::ELEMENT_ARRAY_BUFFER, Some(ibo));
            buffer_data(gl, glow::ELEMENT_ARRAY_BUFFER, &indices, glow::STATIC_DRAW);
            gl.bind_vertex_array(None);
            Ok(GpuScene {
                vao,
                vbo,
                ibo,
                images,
                order,
                gpu_first,
                index_count: indices.len(),
                models: (0..scene.models.len())
                    .map(|m| (model_vertex_run(scene, m), scene.models[m].pose))
                    .collect(),
            })
        }
    }

    /// Uploads the vertices of models whose pose changed since they were uploaded (animation);
    /// returns how many models were uploaded.
    pub fn sync_models(&mut self, gl: &glow::Context, scene: &Scene) -> usize {
        let mut uploaded = 0;
        for (m, (run, pose)) in self.models.iter_mut().enumerate() {
            let Some(model) = scene.models.get(m) else {
                continue;
            };
            if model.pose == *pose || run.start == run.end || run.end > scene.vertices.len() {
                continue;
            }
            let bytes = bytes_of(&scene.vertices[run.clone()]);
            // SAFETY: the run lies inside the buffer, which holds every scene vertex.
            unsafe {
                gl.bind_buffer(glow::ARRAY_BUFFER, Some(self.vbo));
                let offset = (run.start * std::mem::size_of::<Vertex>()) as i32;
                gl.buffer_sub_data_u8_slice(glow::ARRAY_BUFFER, offset, bytes);
                gl.bind_buffer(glow::ARRAY_BUFFER, None);
            }
            *pose = model.pose;
            uploaded += 1;
        }
        uploaded
    }

    /// Where surface `s`'s indices start in the GPU index buffer.
    pub fn gpu_first_index(&self, s: usize) -> u32 {
        self.gpu_first[s]
    }

    /// The listed surfaces, merged into as few draws as the state order allows.
    pub fn draw_list_of(&self, scene: &Scene, merge: Merge, surfaces: &[u32]) -> Vec<DrawItem> {
        let mut sorted: Vec<usize> = surfaces.iter().map(|&s| s as usize).collect();
        sorted.sort_unstable_by_key(|&s| self.gpu_first[s]);
        self.merged(scene, merge, sorted)
    }

    /// The surfaces `keep` admits, merged into as few draws as the state order allows.
    pub fn draw_list(
        &self,
        scene: &Scene,
        merge: Merge,
        mut keep: impl FnMut(usize) -> bool,
    ) -> Vec<DrawItem> {
        self.merged(
            scene,
            merge,
            self.order.iter().copied().filter(|&s| keep(s)),
        )
    }

    /// `surfaces` in the order given, each joining the previous draw when its state matches and
    /// its indices follow on.
    fn merged(
        &self,
        scene: &Scene,
        merge: Merge,
        surfaces: impl IntoIterator<Item = usize>,
    ) -> Vec<DrawItem> {
        let mut items: Vec<DrawItem> = Vec::new();
        for s in surfaces {
            let surf = &scene.surfaces[s];
            let first = self.gpu_first[s];
            if let Some(last) = items.last_mut()
                && last.owner == surf.owner
                && last.first_index + last.index_count == first
                && merge.joins(scene, last, surf)
            {
                last.index_count += surf.index_count;
                continue;
            }
            items.push(DrawItem {
                first_index: first,
                index_count: surf.index_count,
                material: surf.material,
                lightmap: surf.lightmap,
                baked: surf.baked,
                owner: surf.owner,
            });
        }
        items
    }

    /// The vertex and index buffers, for the fixed-function pipeline's client arrays.
    pub fn buffers(&self) -> (glow::Buffer, glow::Buffer) {
        (self.vbo, self.ibo)
    }

    pub fn texture_for(&self, scene: &Scene, material: usize) -> glow::Texture {
        scene.materials[material]
            .texture
            .and_then(|t| self.images.textures.get(t).copied())
            .unwrap_or(self.images.white)
    }

    /// Deletes the buffers, and the images unless another renderer still shares them.
    pub fn delete(self, gl: &glow::Context) {
        // SAFETY: called once by the owner.
        unsafe {
            gl.delete_vertex_array(self.vao);
            gl.delete_buffer(self.vbo);
            gl.delete_buffer(self.ibo);
        }
        if let Ok(images) = Rc::try_unwrap(self.images) {
            images.delete(gl);
        }
    }
}

/// Data a GL buffer may hold as its bytes: `repr(C)` or primitive, without padding.
pub(crate) trait Plain: Copy {}
impl Plain for u32 {}
impl Plain for f32 {}
impl Plain for [f32; 4] {}
impl Plain for Vertex {}

/// `data` as the bytes a GL buffer takes.
pub(crate) fn bytes_of<T: Plain>(data: &[T]) -> &[u8] {
    // SAFETY: T has no padding (see `Plain`), so every byte of the slice is initialised.
    unsafe { std::slice::from_raw_parts(data.as_ptr() as *const u8, std::mem::size_of_val(data)) }
}

/// Fills the buffer bound to `target` with `data`.
pub(crate) fn buffer_data<T: Plain>(gl: &glow::Context, target: u32, data: &[T], usage: u32) {
    // SAFETY: a plain upload into the bound buffer.
    unsafe { gl.buffer_data_u8_slice(target, bytes_of(data), usage) }
}

/// Writes `data` into the bound buffer from byte `offset` on (the buffer is large enough).
pub(crate) fn buffer_sub_data<T: Plain>(
    gl: &glow::Context,
    target: u32,
    offset: usize,
    data: &[T],
) {
    // SAFETY: a plain upload into the bound buffer, within the size it was allocated with.
    unsafe { gl.buffer_sub_data_u8_slice(target, offset as i32, bytes_of(data)) }
}

/// A vertex array with its vertex buffer and index buffer: one light's volumes (`gl::volumes`),
/// one caster group's extrusion mesh (`gl::extrusion`).
pub(crate) struct Buffers {
    pub vao: glow::VertexArray,
    pub vbo: glow::Buffer,
    pub ebo: glow::Buffer,
}

impl Buffers {
    pub fn new(gl: &glow::Context) -> Result<Buffers, String> {
        // SAFETY: a vertex array and two buffers of our own.
        unsafe {
            Ok(Buffers {
                vao: gl.create_vertex_array()?,
                vbo: gl.create_buffer()?,
                ebo: gl.create_buffer()?,
            })
        }
    }

    pub fn delete(&self, gl: &glow::Context) {
        // SAFETY: our own objects, deleted once (their owner is dropped with them).
        unsafe {
            gl.delete_vertex_array(self.vao);
            gl.delete_buffer(self.vbo);
            gl.delete_buffer(self.ebo);
        }
    }
}
