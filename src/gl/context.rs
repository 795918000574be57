//! One function gives a current GL context of the profile asked for and says which path it took.
//!
//! Paths: `egl` (EGL device platform, surfaceless, desktop GL), `egl_es` (the same device, OpenGL
//! ES 3.0 with GLSL ES 3.00 shaders), `osmesa` (libOSMesa at run time) and `window` (winit +
//! glutin, needs a display). Every path renders into our own framebuffer objects; the window path
//! can also show the result.
//!
//! `auto` is a chain: for [`Profile::Core`], EGL desktop GL 3.3 core, then EGL OpenGL ES 3.0, then
//! OSMesa 3.3 core; for [`Profile::Compatibility`] (the legacy fixed-function calls), EGL desktop
//! compatibility profile, then OSMesa compatibility profile (ES has no legacy calls). When every
//! step fails the error lists each one's reason. [`FAIL_BACKENDS_ENV`] makes named steps fail on
//! purpose, so that each later step can be exercised on a machine where the first one works.

#[cfg(feature = "window")]
use super::window;
use super::{egl, osmesa};
use crate::options::BackendChoice;
use std::ffi::{CStr, c_void};
use std::fmt;
use std::sync::Arc;
use thiserror::Error;

/// The path a context was created on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Backend {
    Window,
    /// EGL, desktop OpenGL.
    Egl,
    /// EGL, OpenGL ES 3.0.
    EglEs,
    Osmesa,
}

impl Backend {
    pub const ALL: [Backend; 4] = [
        Backend::Window,
        Backend::Egl,
        Backend::EglEs,
        Backend::Osmesa,
    ];

    pub fn as_str(self) -> &'static str {
        match self {
            Backend::Window => "window",
            Backend::Egl => "egl",
            Backend::EglEs => "egl_es",
            Backend::Osmesa => "osmesa",
        }
    }
}

/// The profile a caller needs: the shader pipeline runs on core (or ES); the legacy
/// fixed-function calls need a compatibility profile.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Profile {
    Core,
    Compatibility,
}

/// The API a context holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum GlApi {
    /// Desktop OpenGL 3.3 or later, core profile.
    DesktopCore,
    /// Desktop OpenGL 3.0 or later, compatibility profile (legacy calls available).
    DesktopCompatibility,
    /// OpenGL ES 3.0 or a later 3.x; the renderer uses only what ES 3.0 and its extensions give.
    Es3,
}

impl GlApi {
    pub fn as_str(self) -> &'static str {
        match self {
            GlApi::DesktopCore => "desktop GL core",
            GlApi::DesktopCompatibility => "desktop GL compatibility",
            GlApi::Es3 => "OpenGL ES 3.0",
        }
    }
}

impl fmt::Display for GlApi {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
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

/// Environment variable listing paths (`egl,egl_es,osmesa,window`, comma-separated) that fail on
/// purpose with the reason "failed on purpose", so that `auto`'s later steps can be run and
/// tested where the earlier ones work (e.g. `SHADOWLAB_FAIL_BACKENDS=egl` runs on ES 3.0).
pub const FAIL_BACKENDS_ENV: &str = "SHADOWLAB_FAIL_BACKENDS";

#[derive(Debug, Error)]
pub enum ContextError {
    /// Every path that was tried failed; each entry names the path and its reason.
    /// (The ES 3.0 step of the core chain is listed among the failures.)
    #[error("no OpenGL {} could be created:\n{}\nTo fix: {INSTALL_HINT}.",
        match .profile { Profile::Core => "3.3 core context", Profile::Compatibility => "compatibility-profile context" },
        .failures.iter().map(|(b, why)| format!("  {b}: {why}")).collect::<Vec<_>>().join("\n"))]
    Unavailable {
        profile: Profile,
        failures: Vec<(Backend, String)>,
    },
}

/// What keeps each path's context alive; dropped after `gl`.
enum Holder {
    Egl {
        _keep: egl::EglHolder,
    },
    Osmesa {
        _keep: osmesa::OsMesaHolder,
    },
    #[cfg(feature = "window")]
    Window(Box<window::WindowHolder>),
}

/// A current GL context. Field order matters: `gl` is dropped before what keeps it alive.
pub struct GlContext {
    pub gl: Arc<glow::Context>,
    pub backend: Backend,
    /// The API and profile the context holds.
    pub api: GlApi,
    /// The device or library behind the context.
    pub device: String,
    /// Paths tried first that failed, with their reasons (for `auto`).
    pub skipped: Vec<(Backend, String)>,
    holder: Holder,
}

impl GlContext {
    /// The window and its event pump, when the context lives in one.
    #[cfg(feature = "window")]
    pub fn window(&mut self) -> Option<&mut window::WindowHolder> {
        match &mut self.holder {
            Holder::Window(w) => Some(w),
            _ => None,
        }
    }

    /// The address of GL function `name` as the context's own loader gives it (null where it
    /// has none). For the entry points glow does not wrap, such as the legacy calls.
    pub fn proc_address(&self, name: &CStr) -> *const c_void {
        match &self.holder {
            Holder::Egl { _keep } => _keep.proc_address(name),
            Holder::Osmesa { _keep } => _keep.proc_address(name),
            #[cfg(feature = "window")]
            Holder::Window(w) => w.window.proc_address(name),
        }
    }

    /// Whether the legacy calls work here: every one has an address and [`Legacy::check`]
    /// passes (a core or ES context raises INVALID_OPERATION, or has no such function).
    ///
    /// [`Legacy::check`]: crate::gl::legacy::Legacy::check
    pub fn legacy_calls_work(&self) -> Result<(), String> {
        crate::gl::legacy::Legacy::load(|name| self.proc_address(name))?.check(&self.gl)
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

fn try_egl(kind: egl::Kind) -> Result<GlContext, String> {
    let c = egl::create(kind)?;
    let (backend, api) = match kind {
        egl::Kind::Core => (Backend::Egl, GlApi::DesktopCore),
        egl::Kind::Compatibility => (Backend::Egl, GlApi::DesktopCompatibility),
        egl::Kind::Es3 => (Backend::EglEs, GlApi::Es3),
    };
    Ok(GlContext {
        gl: finish(c.gl),
        backend,
        api,
        device: c.device,
        skipped: Vec::new(),
        holder: Holder::Egl { _keep: c.holder },
    })
}

fn try_osmesa(profile: Profile) -> Result<GlContext, String> {
    let library = std::env::var(OSMESA_LIBRARY_ENV).ok();
    let compatibility = profile == Profile::Compatibility;
    let c = osmesa::create(library.as_deref(), compatibility)?;
    Ok(GlContext {
        gl: finish(c.gl),
        backend: Backend::Osmesa,
        api: if compatibility {
            GlApi::DesktopCompatibility
        } else {
            GlApi::DesktopCore
        },
        device: c.device,
        skipped: Vec::new(),
        holder: Holder::Osmesa { _keep: c.holder },
    })
}

#[cfg(not(feature = "window"))]
fn try_window(_: u32, _: u32, _: Profile) -> Result<GlContext, String> {
    Err("built without the `window` feature".into())
}

#[cfg(feature = "window")]
fn try_window(width: u32, height: u32, profile: Profile) -> Result<GlContext, String> {
    if profile == Profile::Compatibility {
        // Said rather than handing out a core context that would refuse the legacy calls.
        return Err(
            "the window path makes only GL 3.3 core contexts, not the compatibility profile \
             asked for (use --backend egl or osmesa)"
                .into(),
        );
    }
    let (holder, gl) = window::create(width, height)?;
    Ok(GlContext {
        gl: finish(gl),
        backend: Backend::Window,
        api: GlApi::DesktopCore,
        device: "window".to_string(),
        skipped: Vec::new(),
        holder: Holder::Window(Box::new(holder)),
    })
}

/// The paths `choice` tries for `profile`, in order.
pub fn chain(choice: BackendChoice, profile: Profile) -> &'static [Backend] {
    match (choice, profile) {
        (BackendChoice::Auto, Profile::Core) => &[Backend::Egl, Backend::EglEs, Backend::Osmesa],
        // ES has no legacy calls: it is no step of the compatibility chain.
        (BackendChoice::Auto, Profile::Compatibility) => &[Backend::Egl, Backend::Osmesa],
        (BackendChoice::Egl, _) => &[Backend::Egl],
        (BackendChoice::EglEs, _) => &[Backend::EglEs],
        (BackendChoice::Osmesa, _) => &[Backend::Osmesa],
        (BackendChoice::Window, _) => &[Backend::Window],
    }
}

/// The paths [`FAIL_BACKENDS_ENV`] names.
fn failing_on_purpose() -> Vec<Backend> {
    let list = std::env::var(FAIL_BACKENDS_ENV).unwrap_or_default();
    list.split(',')
        .map(str::trim)
        .filter_map(|name| Backend::ALL.into_iter().find(|b| b.as_str() == name))
        .collect()
}

/// Each failed path with its reason.
pub type Failures = Vec<(Backend, String)>;

/// Runs `attempt` on each path of `order` until one succeeds: that result, the path, and the
/// failures before it; or every path's failure.
pub fn first_that_works<T>(
    order: &[Backend],
    mut attempt: impl FnMut(Backend) -> Result<T, String>,
) -> Result<(T, Backend, Failures), Failures> {
    let mut failures = Vec::new();
    for &backend in order {
        match attempt(backend) {
            Ok(t) => return Ok((t, backend, failures)),
            Err(why) => {
                log::debug!("{backend} path failed: {why}");
                failures.push((backend, why));
            }
        }
    }
    Err(failures)
}

/// One path's context of `profile`, checked: a compatibility context must take the legacy
/// calls, an ES context must be ES.
fn attempt(backend: Backend, profile: Profile, size: (u32, u32)) -> Result<GlContext, String> {
    use glow::HasContext;
    let c = match (backend, profile) {
        (Backend::Egl, Profile::Core) => try_egl(egl::Kind::Core)?,
        (Backend::Egl, Profile::Compatibility) => try_egl(egl::Kind::Compatibility)?,
        (Backend::EglEs, Profile::Core) => try_egl(egl::Kind::Es3)?,
        (Backend::EglEs, Profile::Compatibility) => {
            return Err("OpenGL ES has no compatibility profile (no legacy calls)".into());
        }
        (Backend::Osmesa, p) => try_osmesa(p)?,
        (Backend::Window, p) => try_window(size.0, size.1, p)?,
    };
    if c.api == GlApi::DesktopCompatibility {
        c.legacy_calls_work()
            .map_err(|e| format!("the compatibility context refuses the legacy calls: {e}"))?;
    }
    if (c.api == GlApi::Es3) != c.gl.version().is_embedded {
        return Err(format!(
            "asked for {} but got \"{}\"",
            c.api,
            c.gl.version().vendor_info
        ));
    }
    Ok(c)
}

/// Creates a current context of `profile` on the chosen path (`auto`: the chain, see the module
/// comment). `width`×`height` sizes the window of the window path; headless paths ignore it.
pub fn create_context(
    choice: BackendChoice,
    width: u32,
    height: u32,
    profile: Profile,
) -> Result<GlContext, ContextError> {
    let on_purpose = failing_on_purpose();
    let result = first_that_works(chain(choice, profile), |backend| {
        if on_purpose.contains(&backend) {
            return Err(format!("failed on purpose ({FAIL_BACKENDS_ENV})"));
        }
        attempt(backend, profile, (width, height))
    });
    match result {
        Ok((mut c, _, failures)) => {
            for (b, why) in &failures {
                log::warn!("{b} path failed, fell back to {}: {why}", c.backend);
            }
            log::info!("GL context: {} ({}) on {}", c.backend, c.api, c.device);
            c.skipped = failures;
            Ok(c)
        }
        Err(failures) => Err(ContextError::Unavailable { profile, failures }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_core_chain_falls_from_desktop_to_es_to_osmesa_and_lists_every_reason() {
        let order = chain(BackendChoice::Auto, Profile::Core);
        assert_eq!(order, [Backend::Egl, Backend::EglEs, Backend::Osmesa]);
        let works = |ok: &'static [Backend]| {
            move |b: Backend| {
                if ok.contains(&b) {
                    Ok(b)
                } else {
                    Err(format!("no {b}"))
                }
            }
        };
        let (_, got, failed) = first_that_works(order, works(&[Backend::EglEs])).unwrap();
        assert_eq!(got, Backend::EglEs);
        assert_eq!(failed, [(Backend::Egl, "no egl".to_string())]);
        let (_, got, failed) = first_that_works(order, works(&[Backend::Osmesa])).unwrap();
        assert_eq!((got, failed.len()), (Backend::Osmesa, 2));
        let all = first_that_works(order, works(&[])).unwrap_err();
        assert_eq!(all.len(), 3);
        let e = ContextError::Unavailable {
            profile: Profile::Core,
            failures: all,
        };
        for b in order {
            assert!(e.to_string().contains(&format!("  {b}: no {b}")), "{e}");
        }
    }

    #[test]
    fn the_compatibility_chain_skips_es() {
        assert_eq!(
            chain(BackendChoice::Auto, Profile::Compatibility),
            [Backend::Egl, Backend::Osmesa]
        );
    }
}
