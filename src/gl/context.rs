//! One function gives a current GL 3.3 core context and says which path it took.
//!
//! Paths: `egl` (EGL device platform, surfaceless), `osmesa` (libOSMesa at run time) and `window`
//! (winit + glutin, needs a display). `auto` tries egl, then osmesa. Every path renders into our
//! own framebuffer objects; the window path can also show the result.

use super::{egl, osmesa, window};
use crate::options::BackendChoice;
use std::fmt;
use std::sync::Arc;
use thiserror::Error;

/// The path a context was created on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Backend {
    Window,
    Egl,
    Osmesa,
}

impl Backend {
    pub fn as_str(self) -> &'static str {
        match self {
            Backend::Window => "window",
            Backend::Egl => "egl",
            Backend::Osmesa => "osmesa",
        }
    }
}

impl fmt::Display for Backend {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// What to install on Debian for each path.
pub const INSTALL_HINT: &str = "install the Debian packages libegl1 libegl-mesa0 libgl1-mesa-dri \
(EGL, the default path), libosmesa6 (OSMesa fallback), or xvfb to run the window path without a \
display (`xvfb-run -a shadowlab ...`)";

/// Environment variable naming the OSMesa library to load instead of the standard names.
pub const OSMESA_LIBRARY_ENV: &str = "SHADOWLAB_OSMESA_LIBRARY";

#[derive(Debug, Error)]
pub enum ContextError {
    /// Every path that was tried failed; each entry names the path and its reason.
    #[error("no OpenGL 3.3 core context could be created:\n{}\nTo fix: {INSTALL_HINT}.",
        .0.iter().map(|(b, why)| format!("  {b}: {why}")).collect::<Vec<_>>().join("\n"))]
    Unavailable(Vec<(Backend, String)>),
}

/// What keeps each path's context alive; dropped after `gl`.
enum Holder {
    Egl { _keep: egl::EglHolder },
    Osmesa { _keep: osmesa::OsMesaHolder },
    Window(Box<window::WindowHolder>),
}

/// A current GL context. Field order matters: `gl` is dropped before what keeps it alive.
pub struct GlContext {
    pub gl: Arc<glow::Context>,
    pub backend: Backend,
    /// The device or library behind the context.
    pub device: String,
    /// Paths tried first that failed, with their reasons (for `auto`).
    pub skipped: Vec<(Backend, String)>,
    holder: Holder,
}

impl GlContext {
    /// The window and its event pump, when the context lives in one.
    pub fn window(&mut self) -> Option<&mut window::WindowHolder> {
        match &mut self.holder {
            Holder::Window(w) => Some(w),
            _ => None,
        }
    }
}

/// Wraps a fresh context; debug builds route KHR_debug messages to the log.
fn finish(mut gl: glow::Context) -> Arc<glow::Context> {
    use glow::HasContext;
    if cfg!(debug_assertions) && gl.supported_extensions().contains("GL_KHR_debug") {
        // SAFETY: the callback only logs; the context is current and owned here.
        unsafe {
            gl.enable(glow::DEBUG_OUTPUT);
            gl.debug_message_callback(|_source, ty, id, severity, message| {
                if severity == glow::DEBUG_SEVERITY_NOTIFICATION {
                    log::trace!("GL debug {id}: {message}");
                } else if ty == glow::DEBUG_TYPE_ERROR {
                    log::error!("GL debug {id}: {message}");
                } else {
                    log::debug!("GL debug {id}: {message}");
                }
            });
        }
    }
    Arc::new(gl)
}

fn try_egl() -> Result<GlContext, String> {
    let c = egl::create()?;
    Ok(GlContext {
        gl: finish(c.gl),
        backend: Backend::Egl,
        device: c.device,
        skipped: Vec::new(),
        holder: Holder::Egl { _keep: c.holder },
    })
}

fn try_osmesa() -> Result<GlContext, String> {
    let library = std::env::var(OSMESA_LIBRARY_ENV).ok();
    let c = osmesa::create(library.as_deref())?;
    Ok(GlContext {
        gl: finish(c.gl),
        backend: Backend::Osmesa,
        device: c.device,
        skipped: Vec::new(),
        holder: Holder::Osmesa { _keep: c.holder },
    })
}

fn try_window(width: u32, height: u32) -> Result<GlContext, String> {
    let (holder, gl) = window::create(width, height)?;
    Ok(GlContext {
        gl: finish(gl),
        backend: Backend::Window,
        device: "window".to_string(),
        skipped: Vec::new(),
        holder: Holder::Window(Box::new(holder)),
    })
}

/// Creates a current GL 3.3 core context on the chosen path. `width`×`height` sizes the window
/// of the window path; headless paths ignore it.
pub fn create_context(
    choice: BackendChoice,
    width: u32,
    height: u32,
) -> Result<GlContext, ContextError> {
    let order: &[Backend] = match choice {
        BackendChoice::Auto => &[Backend::Egl, Backend::Osmesa],
        BackendChoice::Egl => &[Backend::Egl],
        BackendChoice::Osmesa => &[Backend::Osmesa],
        BackendChoice::Window => &[Backend::Window],
    };
    let mut failures = Vec::new();
    for &backend in order {
        let attempt = match backend {
            Backend::Egl => try_egl(),
            Backend::Osmesa => try_osmesa(),
            Backend::Window => try_window(width, height),
        };
        match attempt {
            Ok(mut c) => {
                for (b, why) in &failures {
                    log::warn!("{b} path failed, fell back to {}: {why}", c.backend);
                }
                log::info!("GL context: {} on {}", c.backend, c.device);
                c.skipped = failures;
                return Ok(c);
            }
            Err(why) => {
                log::debug!("{backend} path failed: {why}");
                failures.push((backend, why));
            }
        }
    }
    Err(ContextError::Unavailable(failures))
}
