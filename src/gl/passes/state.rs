//! The fixed-function state a pass draws with, as one value set whole at the pass's start, so
//! that no pass depends on what the one before it left. Stencil operations, face culling,
//! depth clamping and clip distances stay with the passes that change them within a draw.

use glow::HasContext;

/// Depth test and writes, colour writes, blending, the stencil test and polygon offset.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DrawState {
    pub color_write: bool,
    pub depth_write: bool,
    /// The depth comparison (`glow::LESS`, ...); None: no depth test.
    pub depth_test: Option<u32>,
    /// Blend factors (source, destination); None: no blending.
    pub blend: Option<(u32, u32)>,
    /// Whether the stencil test is on (its function is the pass's).
    pub stencil_test: bool,
    /// glPolygonOffset (factor, units); None: off.
    pub polygon_offset: Option<(f32, f32)>,
}

impl DrawState {
    /// Opaque geometry laying down colour and depth: the unlit world, the G-buffer.
    pub const OPAQUE: DrawState = DrawState {
        color_write: true,
        depth_write: true,
        depth_test: Some(glow::LESS),
        blend: None,
        stencil_test: false,
        polygon_offset: None,
    };

    /// Geometry drawn again over the laid-down depth without writing it (lit passes,
    /// overlays).
    pub const OVER_DEPTH: DrawState = DrawState {
        color_write: true,
        depth_write: false,
        depth_test: Some(glow::LEQUAL),
        blend: None,
        stencil_test: false,
        polygon_offset: None,
    };

    /// Sets every field's state.
    pub fn apply(&self, gl: &glow::Context) {
        let on = |cap, enabled: bool| {
            // SAFETY: switching one capability.
            unsafe {
                if enabled {
                    gl.enable(cap)
                } else {
                    gl.disable(cap)
                }
            }
        };
        // SAFETY: fixed-function state only.
        unsafe {
            gl.color_mask(
                self.color_write,
                self.color_write,
                self.color_write,
                self.color_write,
            );
            gl.depth_mask(self.depth_write);
            if let Some(func) = self.depth_test {
                gl.depth_func(func);
            }
            if let Some((src, dst)) = self.blend {
                gl.blend_func(src, dst);
            }
            if let Some((factor, units)) = self.polygon_offset {
                gl.polygon_offset(factor, units);
            }
        }
        on(glow::DEPTH_TEST, self.depth_test.is_some());
        on(glow::BLEND, self.blend.is_some());
        on(glow::STENCIL_TEST, self.stencil_test);
        on(glow::POLYGON_OFFSET_FILL, self.polygon_offset.is_some());
    }
}
