//! GL in a window: winit + glutin (GLX or EGL on X11). Needs a display; `xvfb-run` gives one.
//!
//! [`open_window_gl`] is shared by the viewer (inside its event loop) and by the `window` backend of
//! the headless commands, which pumps a private event loop just long enough to get a window.

use glutin::config::{ConfigTemplateBuilder, GlConfig};
use glutin::context::{
    ContextApi, ContextAttributesBuilder, GlProfile, NotCurrentGlContext, PossiblyCurrentContext,
    PossiblyCurrentGlContext, Version,
};
use glutin::display::{GetGlDisplay, GlDisplay};
use glutin::surface::{GlSurface, Surface, SwapInterval, WindowSurface};
use glutin_winit::{DisplayBuilder, GlWindow};
use raw_window_handle::HasWindowHandle;
use std::ffi::CStr;
use std::num::NonZeroU32;
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::platform::pump_events::EventLoopExtPumpEvents;
use winit::window::{Window, WindowAttributes, WindowId};

/// A window with a current GL context on it.
pub struct WindowGl {
    pub surface: Surface<WindowSurface>,
    pub context: PossiblyCurrentContext,
    // Dropped after the surface and context that refer to it.
    pub window: Window,
}

impl Drop for WindowGl {
    fn drop(&mut self) {
        // Released before it is destroyed, as the EGL path does (see `egl::release`).
        if self.context.is_current() {
            let _ = self.context.make_not_current_in_place();
        }
    }
}

impl WindowGl {
    /// The address of GL function `name` (for entry points glow lacks).
    pub fn proc_address(&self, name: &CStr) -> *const std::ffi::c_void {
        self.context.display().get_proc_address(name)
    }

    /// Shows the back buffer.
    pub fn swap(&self) -> Result<(), String> {
        self.surface
            .swap_buffers(&self.context)
            .map_err(|e| format!("swap_buffers: {e}"))
    }

    pub fn resize(&self, width: u32, height: u32) {
        if let (Some(w), Some(h)) = (NonZeroU32::new(width), NonZeroU32::new(height)) {
            self.surface.resize(&self.context, w, h);
        }
    }

    pub fn set_vsync(&self, on: bool) -> Result<(), String> {
        let interval = if on {
            SwapInterval::Wait(NonZeroU32::MIN)
        } else {
            SwapInterval::DontWait
        };
        self.surface
            .set_swap_interval(&self.context, interval)
            .map_err(|e| format!("swap interval: {e}"))
    }
}

/// Opens a window of `width`×`height` and makes a GL 3.3 core context current on it.
pub fn open_window_gl(
    event_loop: &ActiveEventLoop,
    title: &str,
    width: u32,
    height: u32,
    visible: bool,
) -> Result<(WindowGl, glow::Context), String> {
    let attributes = WindowAttributes::default()
        .with_title(title)
        .with_inner_size(PhysicalSize::new(width, height))
        .with_visible(visible);
    let template = ConfigTemplateBuilder::new()
        .with_depth_size(24)
        .with_stencil_size(8);
    let builder = DisplayBuilder::new().with_window_attributes(Some(attributes));
    // The picker cannot report an empty config list, so a panic there becomes an error here.
    let built = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        builder.build(event_loop, template, |configs| {
            configs
                .min_by_key(|c| c.num_samples())
                .expect("glutin offers at least one config")
        })
    }))
    .map_err(|_| "no GL framebuffer config for this display".to_string())?;
    let (window, config) = built.map_err(|e| format!("cannot open a GL display: {e}"))?;
    let window = window.ok_or("the window was not created")?;
    let raw = window
        .window_handle()
        .map_err(|e| format!("no window handle: {e}"))?
        .as_raw();
    let display = config.display();
    let context_attributes = ContextAttributesBuilder::new()
        .with_context_api(ContextApi::OpenGl(Some(Version::new(3, 3))))
        .with_profile(GlProfile::Core)
        .build(Some(raw));
    // SAFETY: the window handle stays valid while `window` lives, which outlives the context.
    let not_current = unsafe { display.create_context(&config, &context_attributes) }
        .map_err(|e| format!("cannot create a GL 3.3 core context: {e}"))?;
    let surface_attributes = window
        .build_surface_attributes(Default::default())
        .map_err(|e| format!("surface attributes: {e}"))?;
    // SAFETY: as above.
    let surface = unsafe { display.create_window_surface(&config, &surface_attributes) }
        .map_err(|e| format!("cannot create the window surface: {e}"))?;
    let context = not_current
        .make_current(&surface)
        .map_err(|e| format!("cannot make the context current: {e}"))?;
    // SAFETY: the context is current on this thread.
    let gl = unsafe {
        glow::Context::from_loader_function_cstr(|name: &CStr| display.get_proc_address(name))
    };
    // glow lacks glDepthBoundsEXT: loaded while the loader is at hand.
    super::depth_bounds_ext::load_for_current(|name| display.get_proc_address(name));
    Ok((
        WindowGl {
            surface,
            context,
            window,
        },
        gl,
    ))
}

/// Keeps a window, its context and a private event loop alive for the `window` backend.
pub struct WindowHolder {
    pub window: WindowGl,
    event_loop: EventLoop<()>,
}

impl WindowHolder {
    /// Lets the window system deliver pending events (expose, resize) without blocking.
    pub fn pump(&mut self) {
        let mut ignore = Ignore;
        let _ = self
            .event_loop
            .pump_app_events(Some(Duration::ZERO), &mut ignore);
    }
}

struct Ignore;
impl ApplicationHandler for Ignore {
    fn resumed(&mut self, _: &ActiveEventLoop) {}
    fn window_event(&mut self, _: &ActiveEventLoop, _: WindowId, _: WindowEvent) {}
}

struct Opener {
    width: u32,
    height: u32,
    result: Option<Result<(WindowGl, glow::Context), String>>,
}

impl ApplicationHandler for Opener {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.result.is_none() {
            self.result = Some(open_window_gl(
                event_loop,
                "shadowlab",
                self.width,
                self.height,
                true,
            ));
        }
    }
    fn window_event(&mut self, _: &ActiveEventLoop, _: WindowId, _: WindowEvent) {}
}

/// Creates a window and context outside of any application event loop.
pub fn create(width: u32, height: u32) -> Result<(WindowHolder, glow::Context), String> {
    let mut event_loop = EventLoop::new().map_err(|e| {
        format!("cannot connect to a display ({e}); run under `xvfb-run -a` without one")
    })?;
    let mut opener = Opener {
        width,
        height,
        result: None,
    };
    let deadline = Instant::now() + Duration::from_secs(10);
    while opener.result.is_none() && Instant::now() < deadline {
        let _ = event_loop.pump_app_events(Some(Duration::from_millis(10)), &mut opener);
    }
    let (window, gl) = opener
        .result
        .ok_or("the window system did not start the application within 10 s")??;
    Ok((WindowHolder { window, event_loop }, gl))
}
