//! Headless GL through EGL's device platform: no display, no window, no environment variables.
//! Three kinds of context ([`Kind`]): desktop GL 3.3 core, desktop GL compatibility profile (for
//! the legacy fixed-function calls), or OpenGL ES 3.0 (the chain's step after desktop GL).
//!
//! A hardware device is preferred; the software device (`EGL_MESA_device_software`, llvmpipe) is
//! the fallback. The context is surfaceless and renders only into our own framebuffer objects.

use glutin::api::egl::{context::PossiblyCurrentContext, device::Device, display::Display};
use glutin::config::{Api, ConfigSurfaceTypes, ConfigTemplateBuilder};
use glutin::context::{ContextApi, ContextAttributesBuilder, GlProfile, Version};
use glutin::display::GlDisplay;
use std::ffi::CStr;

const SOFTWARE_DEVICE_EXTENSION: &str = "EGL_MESA_device_software";

/// Keeps the EGL display and context alive while GL is in use; on drop releases the context
/// from this thread, then destroys it.
pub struct EglHolder {
    context: Option<PossiblyCurrentContext>,
    display: Display,
}

impl Drop for EglHolder {
    fn drop(&mut self) {
        if let Some(context) = self.context.take() {
            release(context);
        }
    }
}

/// Makes `context` not current (only where it is current on this thread: releasing is
/// thread-wide and would unbind another context) and destroys it. A context destroyed while
/// current stays alive, still current, until its thread exits, and the thread-exit cleanup
/// of such a context crashed test threads (SIGSEGV) when each test ends on its own thread.
fn release(context: PossiblyCurrentContext) {
    use glutin::context::PossiblyCurrentGlContext;
    if context.is_current() {
        // An error leaves nothing to undo: the context is destroyed on drop either way.
        let _ = context.make_not_current();
    }
}

/// Which API and profile to ask EGL for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// Desktop OpenGL 3.3, core profile.
    Core,
    /// Desktop OpenGL 3.0 or later, compatibility profile: the legacy calls (glAlphaFunc,
    /// glTexGen, ...) stay available. 3.0 is the lowest version asked for, so that a driver
    /// that offers only 3.0 compatibility still qualifies; Mesa gives its highest (4.5).
    Compatibility,
    /// OpenGL ES 3.0 (a driver may give a later, compatible 3.x).
    Es3,
}

impl Kind {
    fn describe(self) -> &'static str {
        match self {
            Kind::Core => "a GL 3.3 core context",
            Kind::Compatibility => "a GL compatibility-profile context",
            Kind::Es3 => "an OpenGL ES 3.0 context",
        }
    }
}

/// A current surfaceless context of one [`Kind`] on the best EGL device.
pub struct EglContext {
    pub holder: EglHolder,
    pub gl: glow::Context,
    /// Which device was used, e.g. "software (EGL_MESA_device_software)".
    pub device: String,
}

impl EglHolder {
    /// The address of GL function `name` (for entry points glow lacks: the legacy calls).
    pub fn proc_address(&self, name: &CStr) -> *const std::ffi::c_void {
        self.display.get_proc_address(name)
    }
}

fn describe(device: &Device) -> String {
    let kind = if device.extensions().contains(SOFTWARE_DEVICE_EXTENSION) {
        "software"
    } else {
        "hardware"
    };
    let node = device
        .drm_render_device_node_path()
        .or(device.drm_device_node_path())
        .map(|p| p.display().to_string());
    match (device.name(), node) {
        (Some(n), _) => format!("{kind} device {n}"),
        (None, Some(p)) => format!("{kind} device {p}"),
        (None, None) => format!("{kind} device"),
    }
}

fn create_on(device: &Device, kind: Kind) -> Result<EglContext, String> {
    // SAFETY: the device comes from query_devices; no native display handle is passed.
    let display = unsafe { Display::with_device(device, None) }.map_err(|e| e.to_string())?;
    let (api, context_api, profile) = match kind {
        Kind::Core => (
            Api::OPENGL,
            ContextApi::OpenGl(Some(Version::new(3, 3))),
            Some(GlProfile::Core),
        ),
        Kind::Compatibility => (
            Api::OPENGL,
            ContextApi::OpenGl(Some(Version::new(3, 0))),
            Some(GlProfile::Compatibility),
        ),
        Kind::Es3 => (Api::GLES3, ContextApi::Gles(Some(Version::new(3, 0))), None),
    };
    let template = ConfigTemplateBuilder::new()
        .with_api(api)
        .with_surface_type(ConfigSurfaceTypes::empty())
        .build();
    // SAFETY: the template is plain data.
    let config = unsafe { display.find_configs(template) }
        .map_err(|e| format!("no EGL config: {e}"))?
        .next()
        .ok_or_else(|| format!("no EGL config for {}", kind.describe()))?;
    let mut builder = ContextAttributesBuilder::new().with_context_api(context_api);
    if let Some(p) = profile {
        builder = builder.with_profile(p);
    }
    let attributes = builder.build(None);
    // SAFETY: no raw window handle is involved.
    let context = unsafe { display.create_context(&config, &attributes) }
        .map_err(|e| format!("cannot create {}: {e}", kind.describe()))?;
    let context = context
        .make_current_surfaceless()
        .map_err(|e| format!("cannot make the context current without a surface: {e}"))?;
    // SAFETY: the context is current on this thread; the loader returns its entry points.
    let gl = unsafe {
        glow::Context::from_loader_function_cstr(|name: &CStr| display.get_proc_address(name))
    };
    // glow lacks glDepthBoundsEXT: loaded while the loader is at hand.
    super::depth_bounds_ext::load_for_current(|name| display.get_proc_address(name));
    Ok(EglContext {
        holder: EglHolder {
            context: Some(context),
            display,
        },
        gl,
        device: describe(device),
    })
}

/// Creates a context of `kind`, trying hardware devices first, then software ones. Errors list
/// every device tried and why it failed.
pub fn create(kind: Kind) -> Result<EglContext, String> {
    let devices: Vec<Device> = Device::query_devices()
        .map_err(|e| format!("EGL devices cannot be listed ({e}); is libEGL installed?"))?
        .collect();
    if devices.is_empty() {
        return Err("EGL lists no devices".to_string());
    }
    let (software, hardware): (Vec<_>, Vec<_>) = devices
        .into_iter()
        .partition(|d| d.extensions().contains(SOFTWARE_DEVICE_EXTENSION));
    let mut failures = Vec::new();
    for device in hardware.iter().chain(software.iter()) {
        match create_on(device, kind) {
            Ok(c) => return Ok(c),
            Err(e) => failures.push(format!("{}: {e}", describe(device))),
        }
    }
    Err(failures.join("; "))
}
