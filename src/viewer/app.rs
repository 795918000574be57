//! The viewer's window: winit event loop, GL context, egui interface.

use super::error_job::ErrorJob;
use super::script::{self, ViewMode};
use super::state::{Pending, ViewerState};
use super::ui;
use crate::frame::Frame;
use crate::gl::debug;
use crate::gl::window::{WindowGl, open_window_gl};
use crate::images::Rgba;
use crate::options::Options;
use crate::run::{RenderError, Renderer};
use crate::scene::Scene;
use egui::{Pos2, Rect};
use glow::HasContext;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::window::WindowId;

#[derive(Debug, thiserror::Error)]
pub enum ViewerError {
    #[error("cannot open the viewer's window: {0}")]
    Window(String),
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error("script: {0}")]
    Script(String),
    #[error("{path}: {message}")]
    Write { path: String, message: String },
}

/// What the viewer opens with.
pub struct ViewerSettings {
    pub scene: Scene,
    pub options: Options,
    pub script: Vec<script::Command>,
    /// Window size in pixels.
    pub window: (u32, u32),
}

/// Everything that exists once the window does.
struct Running {
    // Field order: dropped top to bottom, the GL users before the context and window.
    egui: egui_glow::EguiGlow,
    renderer: Renderer,
    textures: ui::Textures,
    gl: Arc<glow::Context>,
    window: WindowGl,
    last: Instant,
    frame: Option<Frame>,
    /// The frame's GL texture as registered with egui (see `show_frame_texture`).
    native_frame: Option<(glow::Texture, egui::TextureId)>,
    view_size: [u32; 2],
    vsync: bool,
}

struct App {
    settings: Option<ViewerSettings>,
    state: Option<ViewerState>,
    running: Option<Running>,
    error: Option<ViewerError>,
}

fn colour_image(img: &Rgba) -> egui::ColorImage {
    egui::ColorImage::from_rgba_unmultiplied([img.width as usize, img.height as usize], &img.data)
}

fn show(ctx: &egui::Context, slot: &mut Option<egui::TextureHandle>, name: &str, img: &Rgba) {
    let image = colour_image(img);
    match slot {
        Some(t) => t.set(image, egui::TextureOptions::NEAREST),
        None => *slot = Some(ctx.load_texture(name, image, egui::TextureOptions::NEAREST)),
    }
}

/// The window's back buffer as an image (what the screen shows after the swap).
fn read_window(gl: &glow::Context, width: u32, height: u32) -> Rgba {
    Rgba {
        width,
        height,
        data: crate::gl::target::read_pixels(
            gl,
            None,
            Some(glow::BACK),
            (width, height),
            (glow::RGBA, glow::UNSIGNED_BYTE),
            4,
        ),
    }
}

fn save(img: &Rgba, path: &Path) -> Result<(), ViewerError> {
    img.save(path).map_err(|e| ViewerError::Write {
        path: path.display().to_string(),
        message: e.to_string(),
    })
}

impl App {
    fn start(&mut self, event_loop: &ActiveEventLoop) -> Result<(), ViewerError> {
        let settings = self.settings.take().expect("started once");
        let (w, h) = settings.window;
        let (window, gl) =
            open_window_gl(event_loop, "shadowlab", w, h, true).map_err(ViewerError::Window)?;
        let gl = Arc::new(gl);
        let mut renderer = Renderer::new(gl.clone(), w.max(16), h.max(16))?;
        renderer.load_scene(&settings.scene)?;
        renderer.prepare(&settings.scene, &settings.options)?;
        let egui = egui_glow::EguiGlow::new(event_loop, gl.clone(), None, None, true);
        let _ = window.set_vsync(true);
        self.state = Some(ViewerState::new(
            settings.scene,
            settings.options,
            settings.script,
        ));
        self.running = Some(Running {
            egui,
            renderer,
            textures: ui::Textures::default(),
            gl,
            window,
            last: Instant::now(),
            frame: None,
            native_frame: None,
            view_size: [w.saturating_sub(340).max(16), h.max(16)],
            vsync: true,
        });
        Ok(())
    }

    fn redraw(&mut self) -> Result<(), ViewerError> {
        let (Some(r), Some(state)) = (self.running.as_mut(), self.state.as_mut()) else {
            return Ok(());
        };
        r.advance(state)?;
        r.render_frame(state)?;
        poll_error_job(state);
        let depth_images = r.update_textures(state);

        // The interface.
        let frame = r.frame.as_ref();
        let textures = &r.textures;
        let mut view_size = r.view_size;
        r.egui.run(&r.window.window, |ui| {
            view_size = ui::draw(ui, state, frame, textures, depth_images);
        });
        r.view_size = view_size;
        let size = r.window.window.inner_size();
        // SAFETY: the default framebuffer of the window; state for egui's painter.
        unsafe {
            r.gl.bind_framebuffer(glow::FRAMEBUFFER, None);
            r.gl.viewport(0, 0, size.width as i32, size.height as i32);
            r.gl.disable(glow::SCISSOR_TEST);
            r.gl.clear_color(0.08, 0.08, 0.09, 1.0);
            r.gl.clear(glow::COLOR_BUFFER_BIT | glow::DEPTH_BUFFER_BIT | glow::STENCIL_BUFFER_BIT);
        }
        r.egui.paint(&r.window.window);
        for p in std::mem::take(&mut state.pending) {
            match p {
                Pending::Screenshot(path) => {
                    save(&read_window(&r.gl, size.width, size.height), &path)?;
                    state.status = format!("saved {}", path.display());
                }
                Pending::Frame(path) => {
                    if let Some(f) = &r.frame {
                        save(&f.image, &path)?;
                    }
                }
            }
        }
        r.window.swap().map_err(ViewerError::Window)?;
        if r.vsync != state.vsync {
            r.vsync = state.vsync;
            if let Err(e) = r.window.set_vsync(state.vsync) {
                state.status = e;
            }
        }
        Ok(())
    }
}

impl Running {
    /// Moves time on: the script's next commands, the camera and the scene's motion, and the
    /// scene uploaded again where it changed.
    fn advance(&mut self, state: &mut ViewerState) -> Result<(), ViewerError> {
        let now = Instant::now();
        let dt = (now - self.last).as_secs_f32();
        self.last = now;
        state.run_script().map_err(ViewerError::Script)?;
        state.advance_camera(dt);
        // A script's frames step the motion evenly, so that what it captures does not depend on
        // how fast frames come.
        let motion_dt = if state.scripted() {
            super::state::MotionClock::STEP
        } else {
            f64::from(dt)
        };
        state.advance_motion(motion_dt, 0);
        if state.needs_upload {
            self.renderer.load_scene(&state.scene)?;
            self.renderer.prepare(&state.scene, &state.options)?;
            state.live_error.reset();
            state.needs_upload = false;
        }
        Ok(())
    }

    /// Renders the frame (with the masks live error sampling or the error view asks for) and
    /// starts the error view's job on it.
    fn render_frame(&mut self, state: &mut ViewerState) -> Result<(), ViewerError> {
        // At the size the view had last time.
        let mut options = state.options.clone();
        options.width = self.view_size[0];
        options.height = self.view_size[1];
        let mut request = state.request();
        let budget = f64::from(options.estimate.budget);
        let live =
            state.walkthrough.is_none() && state.live_error.wants_masks(&state.scene, budget);
        request.masks |= live;
        let start = Instant::now();
        match self
            .renderer
            .render_at(&state.scene, &state.camera, &options, request)
        {
            Ok(frame) => {
                // Masks are drawn after the timed frame: the rest of the call is their cost.
                let masks_ms = start.elapsed().as_secs_f64() * 1e3 - frame.frame_ms;
                let mut sampling_ms = None;
                let sampled = live
                    .then(|| {
                        let l = &mut state.live_error;
                        l.sample(&state.scene, &frame, &mut self.renderer, &options)
                    })
                    .flatten();
                if let Some(s) = sampled {
                    self.renderer.record_errors(&s.per_light, &options);
                    sampling_ms = Some(masks_ms.max(0.0) + state.live_error.trace_ms);
                }
                state.live_error.spend(frame.frame_ms, sampling_ms);
                if request.masks && state.view == ViewMode::Error && state.error_job.is_none() {
                    state.error_job = Some(ErrorJob::start(
                        state.scene.clone(),
                        &frame,
                        state.frame_key(),
                    ));
                }
                state.frame_done(frame.frame_ms, &frame.steps);
                self.frame = Some(frame);
            }
            // A refused option (a map larger than the GL allows): say so, keep the last frame.
            Err(e @ RenderError::Unsupported(_)) => state.status = e.to_string(),
            Err(e) => return Err(e.into()),
        }
        Ok(())
    }

    /// The view's textures: the frame (or the step shown), and the auxiliary image the view
    /// mode asks for. Returns the selected light's shadow-map view count.
    fn update_textures(&mut self, state: &mut ViewerState) -> usize {
        let ctx = self.egui.egui_ctx.clone();
        self.textures.frame = None;
        if let Some(f) = &self.frame {
            match &f.step_image {
                Some(step) => show(&ctx, &mut self.textures.view, "view", step),
                None if f.image.data.is_empty() => self.show_frame_texture(),
                None => show(&ctx, &mut self.textures.view, "view", &f.image),
            }
        }
        let light = state.selected_light;
        let depth_images = self.renderer.shadow_map_views(light);
        let aux: Option<(Rgba, String)> = match state.view {
            ViewMode::Scene => None,
            ViewMode::Depth => self
                .renderer
                .shadow_map_image(light, state.face.min(depth_images.saturating_sub(1)))
                .map(|i| {
                    (
                        i,
                        format!(
                            "light {light}'s shadow map, view {} ({depth_images} views; \
                             brighter: nearer)",
                            state.face.min(depth_images.saturating_sub(1))
                        ),
                    )
                })
                .or_else(|| {
                    state.status = format!("light {light} has no shadow map this frame");
                    None
                }),
            ViewMode::Stencil => self
                .frame
                .as_ref()
                .and_then(|f| f.stencil.as_ref())
                .map(|s| {
                    (
                        debug::stencil_image(&s.values, s.width, s.height, s.wraps),
                        format!(
                            "light {}'s stencil counts (blue 1 … red 8+, magenta negative)",
                            s.light
                        ),
                    )
                }),
            ViewMode::Error => state.current_error().map(|e| {
                (
                    e.image.clone(),
                    "red: false shadow, blue: false lit, yellow: receiver mismatch, greys: correct"
                        .to_string(),
                )
            }),
        };
        match aux {
            Some((img, caption)) => {
                let mut slot = self.textures.aux.take().map(|(t, _)| t);
                show(&ctx, &mut slot, "aux", &img);
                self.textures.aux = slot.map(|t| (t, caption));
            }
            None => self.textures.aux = None,
        }
        depth_images
    }
}

impl Running {
    /// The frame's colour texture handed to egui as it lies on the GPU (registered once, and
    /// again under a new id when a resize made a new one: replacing an id would have egui
    /// delete the old texture, which the renderer owns and has deleted already).
    fn show_frame_texture(&mut self) {
        let t = self.renderer.frame_texture();
        let id = match self.native_frame {
            Some((texture, id)) if texture == t.texture => id,
            _ => self.egui.painter.register_native_texture(t.texture),
        };
        self.native_frame = Some((t.texture, id));
        let (aw, ah) = (t.alloc.0.max(1) as f32, t.alloc.1.max(1) as f32);
        let (u, v) = (t.width as f32 / aw, t.height as f32 / ah);
        // GL's rows run bottom up: the top of the view is the frame's last row.
        let uv = Rect::from_min_max(Pos2::new(0.0, v), Pos2::new(u, 0.0));
        let size = egui::Vec2::new(t.width as f32, t.height as f32);
        self.textures.frame = Some((id, size, uv));
    }
}

/// Takes the error job's result when it has one, and drops the job once it has finished.
fn poll_error_job(state: &mut ViewerState) {
    if let Some(job) = &mut state.error_job
        && let Some(result) = job.poll()
    {
        state.error_result = Some((job.key, result));
    }
    if state.error_job.as_ref().is_some_and(|j| j.finished()) {
        state.error_job = None;
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.running.is_none()
            && self.settings.is_some()
            && let Err(e) = self.start(event_loop)
        {
            self.error = Some(e);
            event_loop.exit();
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(r) = self.running.as_mut() else {
            return;
        };
        match &event {
            WindowEvent::CloseRequested => {
                event_loop.exit();
                return;
            }
            WindowEvent::Resized(size) => r.window.resize(size.width, size.height),
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.redraw() {
                    self.error = Some(e);
                    event_loop.exit();
                }
                if self.state.as_ref().is_some_and(|s| s.quit) {
                    event_loop.exit();
                }
                return;
            }
            _ => {}
        }
        let _ = r.egui.on_window_event(&r.window.window, &event);
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        // Frames are drawn continuously: the timing overlay and the fly camera want them.
        event_loop.set_control_flow(ControlFlow::Poll);
        if let Some(r) = &self.running {
            r.window.window.request_redraw();
        }
    }

    fn exiting(&mut self, _: &ActiveEventLoop) {
        if let Some(r) = self.running.as_mut() {
            r.egui.destroy();
        }
        // What the live error last said, for scripts and whoever closes the window.
        if let Some(state) = self.state.as_ref().filter(|s| s.live_error.on) {
            for (light, e) in state.live_error.lights() {
                println!(
                    "live error: light {light} {} {:.3}% [{:.3}%, {:.3}%] over {} frames",
                    e.technique.map_or("none".into(), |t| t.to_string()),
                    100.0 * e.error.value,
                    100.0 * e.error.low,
                    100.0 * e.error.high,
                    e.frames
                );
            }
        }
    }
}

/// Opens the window and runs until it closes, the script quits, or something fails.
pub fn run(settings: ViewerSettings) -> Result<(), ViewerError> {
    let event_loop = EventLoop::new().map_err(|e| {
        ViewerError::Window(format!(
            "no display ({e}); run under `xvfb-run -a` (package xvfb) without one"
        ))
    })?;
    let mut app = App {
        settings: Some(settings),
        state: None,
        running: None,
        error: None,
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| ViewerError::Window(e.to_string()))?;
    // The GL objects go while the context is still current.
    app.running = None;
    match app.error {
        Some(e) => Err(e),
        None => Ok(()),
    }
}
