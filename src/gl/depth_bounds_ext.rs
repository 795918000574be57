//! `EXT_depth_bounds_test`'s one entry point, which glow lacks: `glDepthBoundsEXT`, loaded by
//! name from the context's loader while a context creator has it at hand.
//!
//! The test (enabled with `GL_DEPTH_BOUNDS_TEST_EXT`) discards a fragment when the depth
//! *already stored* in the depth buffer at its pixel lies outside [zmin, zmax]; the fragment's
//! own depth plays no part. The planner decides where it is used (`plan.depth_bounds_test`,
//! `plan::depth_bounds::window_depth_range`); the stencil pass applies what the plan says.
//!
//! Each creator makes its context current on the calling thread and no code here switches
//! contexts afterwards, so the entry point is kept per thread for the context made current
//! last: the one the capability probe and the passes then run on.

use glow::HasContext;
use std::cell::Cell;
use std::ffi::{CStr, c_void};

/// GL_DEPTH_BOUNDS_TEST_EXT: the capability `glEnable` switches the test on with.
pub const DEPTH_BOUNDS_TEST_EXT: u32 = 0x8890;
/// GL_DEPTH_BOUNDS_EXT: the current bounds, as `glGetDoublev` reads them.
pub const DEPTH_BOUNDS_EXT: u32 = 0x8891;

/// `void glDepthBoundsEXT(GLclampd zmin, GLclampd zmax)`.
type DepthBoundsFn = unsafe extern "system" fn(f64, f64);

/// The loaded entry point of one context.
#[derive(Clone, Copy, Debug)]
pub struct DepthBoundsExt {
    depth_bounds: DepthBoundsFn,
}

thread_local! {
    /// The entry point for the context made current last on this thread (None: the loader
    /// returned none).
    static CURRENT: Cell<Option<DepthBoundsExt>> = const { Cell::new(None) };
}

/// Loads `glDepthBoundsEXT` with `loader` (the loader glow was made with) for the context just
/// made current on this thread. A pointer is not a promise that the extension works: the probe
/// also requires it in the extension string.
pub fn load_for_current(mut loader: impl FnMut(&CStr) -> *const c_void) {
    let p = loader(c"glDepthBoundsEXT");
    let ext = (!p.is_null()).then(|| DepthBoundsExt {
        // SAFETY: a non-null pointer the GL's loader gave for this name has this signature.
        depth_bounds: unsafe { std::mem::transmute::<*const c_void, DepthBoundsFn>(p) },
    });
    CURRENT.with(|c| c.set(ext));
}

/// The entry point of the context current on this thread, if its loader gave one.
pub fn current() -> Option<DepthBoundsExt> {
    CURRENT.with(Cell::get)
}

impl DepthBoundsExt {
    /// Enables the test with bounds [zmin, zmax] (window depth, zmin <= zmax).
    ///
    /// # Safety
    /// `gl` is the current context, and it has `GL_EXT_depth_bounds_test`.
    pub unsafe fn enable(&self, gl: &glow::Context, [zmin, zmax]: [f32; 2]) {
        // SAFETY: the caller's promise; the arguments are plain numbers.
        unsafe {
            (self.depth_bounds)(zmin as f64, zmax as f64);
            gl.enable(DEPTH_BOUNDS_TEST_EXT);
        }
    }

    /// Disables the test.
    ///
    /// # Safety
    /// As for [`DepthBoundsExt::enable`].
    pub unsafe fn disable(&self, gl: &glow::Context) {
        // SAFETY: the caller's promise.
        unsafe { gl.disable(DEPTH_BOUNDS_TEST_EXT) }
    }
}
