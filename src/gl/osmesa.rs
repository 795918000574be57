//! Headless GL through Mesa's off-screen library, loaded at run time (`libOSMesa.so.8` from
//! Debian's `libosmesa6`), for machines where EGL is missing or fails.
//!
//! Like the EGL path it renders only into our own framebuffer objects; the buffer OSMesa needs
//! for its default framebuffer is kept tiny.

use libloading::Library;
use std::ffi::{CStr, c_char, c_int, c_uint, c_void};

// From GL/osmesa.h (Mesa 22).
const OSMESA_FORMAT: c_int = 0x22;
const OSMESA_RGBA: c_int = 0x1908; // GL_RGBA
const OSMESA_DEPTH_BITS: c_int = 0x30;
const OSMESA_STENCIL_BITS: c_int = 0x31;
const OSMESA_PROFILE: c_int = 0x33;
const OSMESA_CORE_PROFILE: c_int = 0x34;
const OSMESA_COMPAT_PROFILE: c_int = 0x35;
const OSMESA_CONTEXT_MAJOR_VERSION: c_int = 0x36;
const OSMESA_CONTEXT_MINOR_VERSION: c_int = 0x37;
const GL_UNSIGNED_BYTE: c_uint = 0x1401;

type OsMesaContext = *mut c_void;
type CreateContextAttribs = unsafe extern "C" fn(*const c_int, OsMesaContext) -> OsMesaContext;
type MakeCurrent = unsafe extern "C" fn(OsMesaContext, *mut c_void, c_uint, c_int, c_int) -> u8;
type GetProcAddress = unsafe extern "C" fn(*const c_char) -> *const c_void;
type DestroyContext = unsafe extern "C" fn(OsMesaContext);
type GetCurrentContext = unsafe extern "C" fn() -> OsMesaContext;

/// Library names tried in order.
pub const LIBRARY_NAMES: [&str; 3] = ["libOSMesa.so.8", "libOSMesa.so.6", "libOSMesa.so"];
const BUFFER_SIDE: usize = 16;

/// Keeps the library, the context and its buffer alive while GL is in use.
pub struct OsMesaHolder {
    context: OsMesaContext,
    make_current: MakeCurrent,
    current: GetCurrentContext,
    get_proc: GetProcAddress,
    destroy: DestroyContext,
    _buffer: Vec<u8>,
    // Dropped last: the function pointers above point into it.
    _library: Library,
}

impl OsMesaHolder {
    /// The address of GL function `name` (for entry points glow lacks: the legacy calls).
    pub fn proc_address(&self, name: &CStr) -> *const c_void {
        // SAFETY: OSMesaGetProcAddress takes a NUL-terminated name; the library is loaded.
        unsafe { (self.get_proc)(name.as_ptr()) }
    }
}

impl Drop for OsMesaHolder {
    fn drop(&mut self) {
        // SAFETY: the context was created by this library and is destroyed once; it is
        // released first where it is current on this thread (OSMesaMakeCurrent(NULL, NULL)
        // unbinds), as the EGL path does (see `egl::release`).
        unsafe {
            if (self.current)() == self.context {
                (self.make_current)(std::ptr::null_mut(), std::ptr::null_mut(), 0, 0, 0);
            }
            (self.destroy)(self.context)
        };
    }
}

pub struct OsMesaContextBundle {
    pub holder: OsMesaHolder,
    pub gl: glow::Context,
    pub device: String,
}

fn load_library(override_path: Option<&str>) -> Result<(Library, String), String> {
    let names: Vec<String> = match override_path {
        Some(p) => vec![p.to_string()],
        None => LIBRARY_NAMES.iter().map(|s| s.to_string()).collect(),
    };
    let mut errors = Vec::new();
    for name in names {
        // SAFETY: loading Mesa runs its initialisers, which have no preconditions.
        match unsafe { Library::new(&name) } {
            Ok(lib) => return Ok((lib, name)),
            Err(e) => errors.push(format!("{name}: {e}")),
        }
    }
    Err(format!("libOSMesa not found ({})", errors.join("; ")))
}

/// Creates a current context with OSMesa, from `library` if given, else from the standard
/// library names: GL 3.3 core, or with `compatibility` a compatibility-profile context of at
/// least GL 3.0 (Mesa gives its highest), where the legacy calls stay available.
pub fn create(library: Option<&str>, compatibility: bool) -> Result<OsMesaContextBundle, String> {
    let (library, name) = load_library(library)?;
    // SAFETY: the symbol types match GL/osmesa.h.
    let (create_attribs, make_current, get_proc, destroy, current) = unsafe {
        let c: libloading::Symbol<CreateContextAttribs> = library
            .get(b"OSMesaCreateContextAttribs\0")
            .map_err(|e| format!("{name} lacks OSMesaCreateContextAttribs: {e}"))?;
        let m: libloading::Symbol<MakeCurrent> = library
            .get(b"OSMesaMakeCurrent\0")
            .map_err(|e| format!("{name} lacks OSMesaMakeCurrent: {e}"))?;
        let g: libloading::Symbol<GetProcAddress> = library
            .get(b"OSMesaGetProcAddress\0")
            .map_err(|e| format!("{name} lacks OSMesaGetProcAddress: {e}"))?;
        let d: libloading::Symbol<DestroyContext> = library
            .get(b"OSMesaDestroyContext\0")
            .map_err(|e| format!("{name} lacks OSMesaDestroyContext: {e}"))?;
        let cur: libloading::Symbol<GetCurrentContext> = library
            .get(b"OSMesaGetCurrentContext\0")
            .map_err(|e| format!("{name} lacks OSMesaGetCurrentContext: {e}"))?;
        (*c, *m, *g, *d, *cur)
    };
    let (profile, minor, what) = if compatibility {
        (
            OSMESA_COMPAT_PROFILE,
            0,
            "a GL compatibility-profile context",
        )
    } else {
        (OSMESA_CORE_PROFILE, 3, "a GL 3.3 core context")
    };
    let attributes: [c_int; 13] = [
        OSMESA_FORMAT,
        OSMESA_RGBA,
        OSMESA_DEPTH_BITS,
        24,
        OSMESA_STENCIL_BITS,
        8,
        OSMESA_PROFILE,
        profile,
        OSMESA_CONTEXT_MAJOR_VERSION,
        3,
        OSMESA_CONTEXT_MINOR_VERSION,
        minor,
        0,
    ];
    // SAFETY: the attribute list is zero-terminated; no share context.
    let context = unsafe { create_attribs(attributes.as_ptr(), std::ptr::null_mut()) };
    if context.is_null() {
        return Err(format!("{name}: OSMesaCreateContextAttribs refused {what}"));
    }
    let mut buffer = vec![0u8; BUFFER_SIDE * BUFFER_SIDE * 4];
    // SAFETY: the buffer holds BUFFER_SIDE² RGBA8 pixels; the holder below keeps it alive.
    let ok = unsafe {
        make_current(
            context,
            buffer.as_mut_ptr().cast(),
            GL_UNSIGNED_BYTE,
            BUFFER_SIDE as c_int,
            BUFFER_SIDE as c_int,
        )
    };
    // From here on the holder owns the context, so every early return destroys it.
    let holder = OsMesaHolder {
        context,
        make_current,
        current,
        get_proc,
        destroy,
        _buffer: buffer,
        _library: library,
    };
    if ok == 0 {
        return Err(format!("{name}: OSMesaMakeCurrent failed"));
    }
    // SAFETY: the context is current; OSMesaGetProcAddress takes a NUL-terminated name.
    let gl = unsafe { glow::Context::from_loader_function_cstr(|n: &CStr| holder.proc_address(n)) };
    // glow lacks glDepthBoundsEXT: loaded while the loader is at hand.
    super::depth_bounds_ext::load_for_current(|n| holder.proc_address(n));
    Ok(OsMesaContextBundle {
        holder,
        gl,
        device: format!("OSMesa ({name})"),
    })
}
