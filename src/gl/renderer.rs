//! Executes a frame's plan with GL: owns the programs, the scene's GPU copy and the framebuffer,
//! runs the passes in the paper's order and returns a [`Frame`].

use super::caps::{self, Caps};
use super::passes::{self, PassContext};
use super::program::{Program, ProgramError, sources};
use super::target::{Framebuffer, GBufferTarget, MaskTarget};
use super::timing::PassTimer;
use super::upload::GpuScene;
use crate::frame::{Frame, GBuffer, Mask};
use crate::options::Options;
use crate::plan::Plan;
use crate::scene::{Camera, Scene};
use glow::HasContext;
use std::sync::Arc;
use std::time::Instant;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum RenderError {
    #[error(transparent)]
    Program(#[from] ProgramError),
    #[error("GL: {0}")]
    Gl(String),
    #[error("no scene is loaded")]
    NoScene,
}

struct Programs {
    unlit: Program,
    lit: Program,
    lit_mask: Program,
    gbuffer: Program,
    blit: Program,
}

impl Programs {
    fn new(gl: &glow::Context) -> Result<Programs, ProgramError> {
        Ok(Programs {
            unlit: Program::new(
                gl,
                "unlit",
                sources::WORLD_VERT,
                Some(sources::UNLIT_FRAG),
                &[],
            )?,
            lit: Program::new(gl, "lit", sources::WORLD_VERT, Some(sources::LIT_FRAG), &[])?,
            lit_mask: Program::new(
                gl,
                "lit_mask",
                sources::WORLD_VERT,
                Some(sources::LIT_FRAG),
                &["MASK_OUTPUT"],
            )?,
            gbuffer: Program::new(
                gl,
                "gbuffer",
                sources::WORLD_VERT,
                Some(sources::GBUFFER_FRAG),
                &[],
            )?,
            blit: Program::new(
                gl,
                "blit",
                sources::FULLSCREEN_VERT,
                Some(sources::BLIT_FRAG),
                &[],
            )?,
        })
    }
    fn delete(&self, gl: &glow::Context) {
        for p in [
            &self.unlit,
            &self.lit,
            &self.lit_mask,
            &self.gbuffer,
            &self.blit,
        ] {
            p.delete(gl);
        }
    }
}

/// What a frame should produce besides its image and timings.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FrameRequest {
    /// The G-buffer and each light's decision mask (drawn after the timed frame).
    pub masks: bool,
}

pub struct Renderer {
    gl: Arc<glow::Context>,
    pub caps: Caps,
    programs: Programs,
    target: Framebuffer,
    gpu: Option<GpuScene>,
    timer: PassTimer,
    /// Created on the first frame that asks for masks.
    measure_targets: Option<(GBufferTarget, MaskTarget)>,
    /// Core profile draws need a bound VAO even without attributes (full-screen triangles).
    empty_vao: glow::VertexArray,
}

impl Renderer {
    /// Compiles the programs and probes the GL for a frame of `width`×`height`.
    pub fn new(gl: Arc<glow::Context>, width: u32, height: u32) -> Result<Renderer, RenderError> {
        let target = Framebuffer::new(&gl, width, height).map_err(RenderError::Gl)?;
        let caps = caps::probe(&gl, target.depth_stencil_bits(&gl));
        let programs = Programs::new(&gl)?;
        // SAFETY: creating an empty vertex array object.
        let empty_vao = unsafe { gl.create_vertex_array() }.map_err(RenderError::Gl)?;
        let timer = PassTimer::new(caps.has("timer_query"));
        Ok(Renderer {
            gl,
            caps,
            programs,
            target,
            gpu: None,
            timer,
            measure_targets: None,
            empty_vao,
        })
    }

    pub fn gl(&self) -> &glow::Context {
        &self.gl
    }

    /// Uploads a scene, replacing the previous one.
    pub fn load_scene(&mut self, scene: &Scene) -> Result<(), RenderError> {
        if let Some(old) = self.gpu.take() {
            old.delete(&self.gl);
        }
        let gpu = GpuScene::new(&self.gl, scene, self.caps.max_texture_size.max(1) as u32)
            .map_err(RenderError::Gl)?;
        self.gpu = Some(gpu);
        Ok(())
    }

    fn ensure_size(&mut self, width: u32, height: u32) -> Result<(), RenderError> {
        if self.target.width != width || self.target.height != height {
            let new = Framebuffer::new(&self.gl, width, height).map_err(RenderError::Gl)?;
            self.target.delete(&self.gl);
            self.target = new;
            if let Some((g, m)) = self.measure_targets.take() {
                g.delete(&self.gl);
                m.delete(&self.gl);
            }
        }
        Ok(())
    }

    /// Plans and renders one frame of `scene` (which must be the loaded one).
    pub fn render(&mut self, scene: &Scene, options: &Options) -> Result<Frame, RenderError> {
        self.render_with(scene, options, FrameRequest::default())
    }

    /// Plans and renders one frame, with what `request` asks for besides the image.
    pub fn render_with(
        &mut self,
        scene: &Scene,
        options: &Options,
        request: FrameRequest,
    ) -> Result<Frame, RenderError> {
        self.render_at(scene, &scene.camera, options, request)
    }

    /// Plans and renders one frame seen from `camera` instead of the scene's camera.
    pub fn render_at(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        options: &Options,
        request: FrameRequest,
    ) -> Result<Frame, RenderError> {
        let plan = Plan::build_at(scene, camera, options);
        self.execute(scene, &plan, options, request)
    }

    /// Runs the passes of `plan`: the unlit world, then each light's additive pass; then, untimed,
    /// the measurement passes the request asks for.
    pub fn execute(
        &mut self,
        scene: &Scene,
        plan: &Plan,
        options: &Options,
        request: FrameRequest,
    ) -> Result<Frame, RenderError> {
        self.ensure_size(plan.camera.width, plan.camera.height)?;
        if request.masks && self.measure_targets.is_none() {
            let g = GBufferTarget::new(&self.gl, self.target.width, self.target.height)
                .map_err(RenderError::Gl)?;
            let m = MaskTarget::new(&self.gl, &self.target).map_err(RenderError::Gl)?;
            self.measure_targets = Some((g, m));
        }
        let gpu = self.gpu.as_ref().ok_or(RenderError::NoScene)?;
        let gl: &glow::Context = &self.gl;
        let start = Instant::now();
        self.target.bind(gl);
        let ctx = PassContext {
            gl,
            scene,
            gpu,
            plan,
            options,
        };
        self.timer.begin(gl, "base");
        passes::base::draw(&ctx, &self.programs.unlit);
        for lp in &plan.lights {
            self.timer.begin(gl, format!("light{}.lit", lp.light));
            passes::lit::draw(&ctx, &self.programs.lit, lp.light);
        }
        let passes = self.timer.finish(gl);
        // SAFETY: waits for the frame; no state change.
        unsafe { gl.finish() };
        let frame_ms = start.elapsed().as_secs_f64() * 1e3;
        // SAFETY: error query only.
        let error = unsafe { gl.get_error() };
        if error != glow::NO_ERROR {
            return Err(RenderError::Gl(format!(
                "the frame raised GL error 0x{error:x}"
            )));
        }
        let rgba = self.target.read_rgba(gl);
        let (gbuffer, masks) = match (&self.measure_targets, request.masks) {
            (Some((gtarget, mtarget)), true) => {
                gtarget_bind(gl, gtarget);
                passes::gbuffer::draw(&ctx, &self.programs.gbuffer);
                let gbuffer = read_gbuffer(gl, gtarget);
                let mut masks = Vec::with_capacity(plan.lights.len());
                for lp in &plan.lights {
                    mtarget.bind(gl);
                    // SAFETY: clears the mask to "not a receiver"; depth and stencil untouched.
                    unsafe {
                        gl.color_mask(true, true, true, true);
                        gl.clear_color(0.0, 0.0, 0.0, 0.0);
                        gl.clear(glow::COLOR_BUFFER_BIT);
                    }
                    passes::lit::draw_mask(&ctx, &self.programs.lit_mask, lp.light);
                    masks.push(Mask {
                        light: lp.light,
                        width: mtarget.width,
                        height: mtarget.height,
                        values: mtarget.read(gl),
                    });
                }
                (Some(gbuffer), masks)
            }
            _ => (None, Vec::new()),
        };
        Ok(Frame {
            width: self.target.width,
            height: self.target.height,
            rgba,
            view_proj: plan.camera.view_proj,
            passes,
            frame_ms,
            gbuffer,
            masks,
        })
    }

    /// Draws the last frame into the default framebuffer of a window, scaled to `width`×`height`.
    pub fn present_to_default(&self, width: u32, height: u32) {
        let gl: &glow::Context = &self.gl;
        // SAFETY: the default framebuffer exists on window contexts; state is set explicitly.
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
            gl.viewport(0, 0, width as i32, height as i32);
            gl.disable(glow::DEPTH_TEST);
            gl.disable(glow::BLEND);
            gl.disable(glow::STENCIL_TEST);
            gl.disable(glow::CULL_FACE);
            self.programs.blit.bind(gl);
            self.programs.blit.set_i32(gl, "u_source", 0);
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D, Some(self.target.color));
            gl.bind_vertex_array(Some(self.empty_vao));
            gl.draw_arrays(glow::TRIANGLES, 0, 3);
            gl.bind_vertex_array(None);
        }
    }
}

fn gtarget_bind(gl: &glow::Context, t: &GBufferTarget) {
    // SAFETY: the G-buffer framebuffer is complete.
    unsafe {
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(t.fbo));
        gl.viewport(0, 0, t.width as i32, t.height as i32);
    }
}

fn read_gbuffer(gl: &glow::Context, t: &GBufferTarget) -> GBuffer {
    let position = t.read(gl, 0);
    let normal = t.read(gl, 1);
    GBuffer {
        width: t.width,
        height: t.height,
        kind: normal
            .iter()
            .map(|n| n[3].round().clamp(0.0, 2.0) as u8)
            .collect(),
        position: position.iter().map(|p| [p[0], p[1], p[2]]).collect(),
        normal: normal.iter().map(|n| [n[0], n[1], n[2]]).collect(),
    }
}

impl Drop for Renderer {
    fn drop(&mut self) {
        let gl: &glow::Context = &self.gl;
        if let Some(g) = self.gpu.take() {
            g.delete(gl);
        }
        self.programs.delete(gl);
        self.target.delete(gl);
        if let Some((g, m)) = self.measure_targets.take() {
            g.delete(gl);
            m.delete(gl);
        }
        self.timer.delete(gl);
        // SAFETY: deleting our own VAO once.
        unsafe { gl.delete_vertex_array(self.empty_vao) };
    }
}
