//! GLSL programs: compile the files under `shaders/` with per-variant `#define`s, link, and look
//! uniforms up by name once.
//!
//! The sources are GLSL 3.30 core written to also be GLSL ES 3.00: on a desktop context they get
//! `#version 330 core`, on an ES context `#version 300 es` with precision statements. Where a
//! stage needs what only one has (gl_ClipDistance: desktop only), the header defines
//! `HAS_CLIP_DISTANCE` and the source is guarded by it.

use glow::HasContext;
use std::collections::HashMap;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum ProgramError {
    #[error("shader `{name}` does not compile:\n{log}")]
    Compile { name: String, log: String },
    #[error("program `{name}` does not link:\n{log}")]
    Link { name: String, log: String },
    #[error("GL refused to create a shader object: {0}")]
    Create(String),
}

/// A linked program and its active uniforms.
pub struct Program {
    pub name: String,
    pub raw: glow::Program,
    uniforms: HashMap<String, glow::UniformLocation>,
}

/// Shader sources, embedded at build time so the binary runs from any directory.
pub mod sources {
    pub const COMMON: &str = include_str!("../../shaders/common.glsl");
    pub const WORLD_VERT: &str = include_str!("../../shaders/world.vert");
    pub const UNLIT_FRAG: &str = include_str!("../../shaders/unlit.frag");
    pub const LIT_FRAG: &str = include_str!("../../shaders/lit.frag");
    pub const SHADOW: &str = include_str!("../../shaders/shadow.glsl");
    pub const DEPTH_VERT: &str = include_str!("../../shaders/depth.vert");
    pub const DEPTH_FRAG: &str = include_str!("../../shaders/depth.frag");
    pub const VOLUME_VERT: &str = include_str!("../../shaders/volume.vert");
    pub const VOLUME_GPU_VERT: &str = include_str!("../../shaders/volume_gpu.vert");
    pub const VOLUME_FRAG: &str = include_str!("../../shaders/volume.frag");
    pub const FRAGMENTS_VERT: &str = include_str!("../../shaders/fragments.vert");
    pub const FULLSCREEN_VERT: &str = include_str!("../../shaders/fullscreen.vert");
    pub const FILL_FRAG: &str = include_str!("../../shaders/fill.frag");
    pub const GATHER_VERT: &str = include_str!("../../shaders/gather.vert");
    pub const GATHER_FRAG: &str = include_str!("../../shaders/gather.frag");
    pub const RECORD_REACH_FRAG: &str = include_str!("../../shaders/record_reach.frag");
    pub const DEPTH_REDUCE_FRAG: &str = include_str!("../../shaders/depth_reduce.frag");
    pub const PRIORITY_MIPS_FRAG: &str = include_str!("../../shaders/priority_mips.frag");
    pub const DEBUG_VOLUME_VERT: &str = include_str!("../../shaders/debug_volume.vert");
    pub const DEBUG_VOLUME_FRAG: &str = include_str!("../../shaders/debug_volume.frag");
}

/// The header of every stage on a desktop context.
const DESKTOP_HEADER: &str = "#version 330 core\n#define HAS_CLIP_DISTANCE\n";

/// The header of every stage on an ES context: ES has no default float precision in fragment
/// shaders and none at all for shadow samplers; lowp is the default of the others. highp
/// everywhere keeps the arithmetic the desktop's 32-bit arithmetic.
const ES_HEADER: &str = "#version 300 es
precision highp float;
precision highp int;
precision highp sampler2D;
precision highp sampler2DShadow;
precision highp samplerCube;
precision highp samplerCubeShadow;
";

/// Whether shaders on `gl` have gl_ClipDistance (and GL the CLIP_DISTANCEi switches): desktop
/// GL 3.0 and later do, GLSL ES 3.00 does not.
pub fn has_clip_distances(gl: &glow::Context) -> bool {
    !gl.version().is_embedded
}

/// `#version`, the variant's defines, the shared helpers, then the stage's source.
fn assemble(embedded: bool, defines: &[&str], source: &str) -> String {
    let mut s = String::from(if embedded { ES_HEADER } else { DESKTOP_HEADER });
    for d in defines {
        s.push_str("#define ");
        s.push_str(d);
        s.push('\n');
    }
    s.push_str(sources::COMMON);
    s.push_str("\n#line 1 1\n");
    s.push_str(source);
    s
}

fn compile(
    gl: &glow::Context,
    name: &str,
    stage: u32,
    source: &str,
) -> Result<glow::Shader, ProgramError> {
    // SAFETY: the shader object is created and either returned or deleted.
    unsafe {
        let shader = gl.create_shader(stage).map_err(ProgramError::Create)?;
        gl.shader_source(shader, source);
        gl.compile_shader(shader);
        if !gl.get_shader_compile_status(shader) {
            let log = gl.get_shader_info_log(shader);
            gl.delete_shader(shader);
            return Err(ProgramError::Compile {
                name: name.to_string(),
                log,
            });
        }
        Ok(shader)
    }
}

impl Program {
    /// Builds a program from a vertex and an optional fragment source (none = depth only).
    pub fn new(
        gl: &glow::Context,
        name: &str,
        vertex: &str,
        fragment: Option<&str>,
        defines: &[&str],
    ) -> Result<Program, ProgramError> {
        let es = gl.version().is_embedded;
        // FRAGMENT_STAGE: helpers only a fragment shader may hold (gl_PrimitiveID's).
        let fragment_defines: Vec<&str> =
            defines.iter().copied().chain(["FRAGMENT_STAGE"]).collect();
        let vs = compile(
            gl,
            name,
            glow::VERTEX_SHADER,
            &assemble(es, defines, vertex),
        )?;
        let fs = match fragment {
            Some(f) => match compile(
                gl,
                name,
                glow::FRAGMENT_SHADER,
                &assemble(es, &fragment_defines, f),
            ) {
                Ok(s) => Some(s),
                Err(e) => {
                    // SAFETY: deleting the shader compiled above.
                    unsafe { gl.delete_shader(vs) };
                    return Err(e);
                }
            },
            None => None,
        };
        // SAFETY: shaders are attached, linked and deleted; the program is returned or deleted.
        unsafe {
            let program = gl.create_program().map_err(ProgramError::Create)?;
            gl.attach_shader(program, vs);
            if let Some(fs) = fs {
                gl.attach_shader(program, fs);
            }
            // Fixed attribute slots: every mesh uses the same vertex layout (gl/upload.rs).
            for (i, a) in ["a_position", "a_normal", "a_uv", "a_lightmap_uv", "a_color"]
                .iter()
                .enumerate()
            {
                gl.bind_attrib_location(program, i as u32, a);
            }
            gl.link_program(program);
            gl.detach_shader(program, vs);
            gl.delete_shader(vs);
            if let Some(fs) = fs {
                gl.detach_shader(program, fs);
                gl.delete_shader(fs);
            }
            if !gl.get_program_link_status(program) {
                let log = gl.get_program_info_log(program);
                gl.delete_program(program);
                return Err(ProgramError::Link {
                    name: name.to_string(),
                    log,
                });
            }
            let mut uniforms = HashMap::new();
            let count = gl.get_active_uniforms(program);
            for i in 0..count {
                if let Some(u) = gl.get_active_uniform(program, i) {
                    // Arrays report `name[0]`: store the base name and every element.
                    let base = u.name.trim_end_matches("[0]").to_string();
                    if let Some(loc) = gl.get_uniform_location(program, &u.name) {
                        uniforms.insert(base.clone(), loc);
                    }
                    if u.size > 1 {
                        for e in 0..u.size {
                            let element = format!("{base}[{e}]");
                            if let Some(loc) = gl.get_uniform_location(program, &element) {
                                uniforms.insert(element, loc);
                            }
                        }
                    }
                }
            }
            Ok(Program {
                name: name.to_string(),
                raw: program,
                uniforms,
            })
        }
    }

    /// The location of an active uniform; `None` if the variant optimised it away.
    pub fn uniform(&self, name: &str) -> Option<&glow::UniformLocation> {
        self.uniforms.get(name)
    }

    pub fn bind(&self, gl: &glow::Context) {
        // SAFETY: the program is linked.
        unsafe { gl.use_program(Some(self.raw)) };
    }

    pub fn set_mat4(&self, gl: &glow::Context, name: &str, m: &glam::Mat4) {
        if let Some(l) = self.uniform(name) {
            // SAFETY: the program is bound by the caller; 16 floats.
            unsafe { gl.uniform_matrix_4_f32_slice(Some(l), false, &m.to_cols_array()) };
        }
    }
    pub fn set_mat3(&self, gl: &glow::Context, name: &str, m: &glam::Mat3) {
        if let Some(l) = self.uniform(name) {
            // SAFETY: as above; 9 floats.
            unsafe { gl.uniform_matrix_3_f32_slice(Some(l), false, &m.to_cols_array()) };
        }
    }
    pub fn set_vec4(&self, gl: &glow::Context, name: &str, v: glam::Vec4) {
        if let Some(l) = self.uniform(name) {
            // SAFETY: as above.
            unsafe { gl.uniform_4_f32(Some(l), v.x, v.y, v.z, v.w) };
        }
    }
    pub fn set_u32(&self, gl: &glow::Context, name: &str, v: u32) {
        if let Some(l) = self.uniform(name) {
            // SAFETY: as above.
            unsafe { gl.uniform_1_u32(Some(l), v) };
        }
    }

    pub fn set_vec3(&self, gl: &glow::Context, name: &str, v: glam::Vec3) {
        if let Some(l) = self.uniform(name) {
            // SAFETY: as above.
            unsafe { gl.uniform_3_f32(Some(l), v.x, v.y, v.z) };
        }
    }
    pub fn set_vec2(&self, gl: &glow::Context, name: &str, v: glam::Vec2) {
        if let Some(l) = self.uniform(name) {
            // SAFETY: as above.
            unsafe { gl.uniform_2_f32(Some(l), v.x, v.y) };
        }
    }
    pub fn set_f32(&self, gl: &glow::Context, name: &str, v: f32) {
        if let Some(l) = self.uniform(name) {
            // SAFETY: as above.
            unsafe { gl.uniform_1_f32(Some(l), v) };
        }
    }
    pub fn set_ivec2(&self, gl: &glow::Context, name: &str, v: [i32; 2]) {
        if let Some(l) = self.uniform(name) {
            // SAFETY: as above.
            unsafe { gl.uniform_2_i32(Some(l), v[0], v[1]) };
        }
    }
    pub fn set_i32(&self, gl: &glow::Context, name: &str, v: i32) {
        if let Some(l) = self.uniform(name) {
            // SAFETY: as above.
            unsafe { gl.uniform_1_i32(Some(l), v) };
        }
    }

    pub fn delete(&self, gl: &glow::Context) {
        // SAFETY: called once when the owner is dropped.
        unsafe { gl.delete_program(self.raw) };
    }
}
