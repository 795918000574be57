//! Whether the GL adds the polygon offset to each fragment's depth and clamps it there, as GL
//! says, or to each vertex's, clamping the vertex to [0, 1] before it is interpolated (Mesa
//! 22.3's softpipe, through its draw module). Per vertex, a triangle with a vertex near the far
//! plane loses part of its offset across its whole area, and shadow maps fitted tightly in depth
//! (perspective maps, several frusta per omni light) shadow their own receivers in stripes.
//!
//! The probe draws one triangle with and without a constant offset (units only) into a depth
//! texture and reads the offset back at two pixels: per fragment it is the same at both; per
//! vertex the pixel nearer the vertex that went past 1 gets less.

use super::scratch::{ScratchDraw, TargetSpec};
use glow::HasContext;

const VERTEX: &str = "#version 330 core
layout(location = 0) in vec3 a_position;
void main() {
    gl_Position = vec4(a_position, 1.0);
}";

const FRAGMENT: &str = "#version 330 core
out vec4 o_colour;
void main() {
    o_colour = vec4(1.0);
}";

/// Side of the probe's target in pixels.
const SIDE: i32 = 8;

/// The offset's units: about 0.01 in window depth where one unit is 2^-24 (a 24-bit buffer),
/// which takes the corner at window depth 0.999 past 1 and leaves the probed pixels below it.
const UNITS: f32 = 167_772.0;

/// The triangle: the lower-left half of the viewport, its corner at (-1, -1) near the far
/// plane, the other two at window depth 0.25.
const CORNERS: [f32; 9] = [-1., -1., 0.998, 1., -1., -0.5, -1., 1., -0.5];

/// Two pixels inside the triangle: one far from the deep corner, one nearer it.
const FAR_FROM_CORNER: (i32, i32) = (5, 1);
const NEAR_CORNER: (i32, i32) = (1, 1);

/// Whether the offset holds per fragment, with what was read where not. ES cannot read depth
/// back: there the GL is taken at its word.
pub fn offset_per_fragment(gl: &glow::Context, es: bool) -> (bool, String) {
    if es {
        return (
            true,
            "polygon offset per fragment (not probed: ES reads no depth back)".into(),
        );
    }
    // SAFETY: a scratch program, buffer, vertex array, texture and framebuffer are created,
    // drawn with, read back and deleted here; the bindings they replace are reset to 0.
    unsafe {
        let target = TargetSpec {
            side: SIDE,
            storage: (
                glow::DEPTH_COMPONENT24,
                glow::DEPTH_COMPONENT,
                glow::UNSIGNED_INT,
            ),
            attachment: glow::DEPTH_ATTACHMENT,
        };
        let draw = match ScratchDraw::open(gl, (VERTEX, FRAGMENT), (&CORNERS, 3), &target) {
            Ok(draw) => draw,
            Err(why) => return (false, format!("the polygon offset probe: {why}")),
        };
        gl.draw_buffers(&[glow::NONE]);
        gl.read_buffer(glow::NONE);
        for cap in [
            glow::STENCIL_TEST,
            glow::CULL_FACE,
            glow::SCISSOR_TEST,
            glow::DEPTH_CLAMP,
        ] {
            gl.disable(cap);
        }
        gl.enable(glow::DEPTH_TEST);
        gl.depth_func(glow::ALWAYS);
        gl.depth_mask(true);
        gl.use_program(Some(draw.program));
        let depth = |offset: bool| {
            if offset {
                gl.enable(glow::POLYGON_OFFSET_FILL);
                gl.polygon_offset(0.0, UNITS);
            } else {
                gl.disable(glow::POLYGON_OFFSET_FILL);
            }
            gl.clear_depth(1.0);
            gl.clear(glow::DEPTH_BUFFER_BIT);
            gl.draw_arrays(glow::TRIANGLES, 0, 3);
            draw.read_floats(gl, glow::DEPTH_COMPONENT, 1)
        };
        let plain = depth(false);
        let offset = depth(true);
        let error = gl.get_error();
        gl.disable(glow::POLYGON_OFFSET_FILL);
        gl.depth_func(glow::LESS);
        draw.delete(gl);
        if error != glow::NO_ERROR {
            return (false, format!("GL error 0x{error:x} during the check"));
        }
        judge(&plain, &offset)
    }
}

/// Per fragment, the offset read at both pixels is the same (one constant for the plane);
/// per vertex, the pixel nearer the clamped corner reads less.
fn judge(plain: &[f32], offset: &[f32]) -> (bool, String) {
    let at = |d: &[f32], (x, y): (i32, i32)| d[(y * SIDE + x) as usize];
    let far = at(offset, FAR_FROM_CORNER) - at(plain, FAR_FROM_CORNER);
    let near = at(offset, NEAR_CORNER) - at(plain, NEAR_CORNER);
    if far <= 0.0 {
        return (
            false,
            format!("polygon offset not applied (depth moved by {far:e})"),
        );
    }
    if (far - near).abs() > 0.1 * far {
        return (
            false,
            format!(
                "polygon offset per vertex, clamped before interpolation: {near:.5} near a \
                 vertex past the far plane where {far:.5} elsewhere on the triangle"
            ),
        );
    }
    (
        true,
        format!("polygon offset per fragment, checked by drawing ({far:.5} at both pixels)"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn depths(offset_near_corner: f32) -> (Vec<f32>, Vec<f32>) {
        let plain = vec![0.5; (SIDE * SIDE) as usize];
        let mut offset = vec![0.51; (SIDE * SIDE) as usize];
        let (x, y) = NEAR_CORNER;
        offset[(y * SIDE + x) as usize] = 0.5 + offset_near_corner;
        (plain, offset)
    }

    #[test]
    fn the_judge_takes_one_offset_and_refuses_a_smaller_one_near_the_corner() {
        let (p, o) = depths(0.01);
        assert!(judge(&p, &o).0);
        let (p, o) = depths(0.004);
        let (ok, why) = judge(&p, &o);
        assert!(!ok && why.contains("per vertex"), "{why}");
        let (ok, why) = judge(&p, &p);
        assert!(!ok && why.contains("not applied"), "{why}");
    }
}
