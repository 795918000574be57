//! Whether `gl_PrimitiveID` works in a fragment shader drawn without a geometry shader, beside
//! an interpolated varying: GLSL 1.50 promises it, and ID and priority buffers
//! (`shadow_map.buffer`) index their per-triangle tables by it. Mesa 22.3's softpipe compiles
//! such a shader and draws nothing right: the probe draws two triangles and reads back what the
//! fragments saw.

use super::scratch::{ScratchDraw, TargetSpec};
use glow::HasContext;

const VERTEX: &str = "#version 330 core
layout(location = 0) in vec2 a_position;
out vec2 v_uv;
void main() {
    v_uv = a_position * 0.5 + 0.5;
    gl_Position = vec4(a_position, 0.0, 1.0);
}";

const FRAGMENT: &str = "#version 330 core
in vec2 v_uv;
out vec4 o_colour;
void main() {
    o_colour = vec4(float(gl_PrimitiveID), v_uv, 1.0);
}";

/// Side of the probe's target in pixels.
const SIDE: i32 = 8;

/// Whether the fragments of two triangles read their own primitive IDs (0 and 1) and the
/// varying as interpolated, with what was seen where not. GLSL ES 3.00 has no `gl_PrimitiveID`:
/// on ES (`es`) nothing is drawn.
pub fn primitive_id_works(gl: &glow::Context, es: bool) -> (bool, String) {
    if es {
        return (
            false,
            "gl_PrimitiveID in fragment shaders (not in GLSL ES 3.00)".into(),
        );
    }
    // SAFETY: a scratch program, buffer, vertex array, texture and framebuffer are created,
    // drawn with, read back and deleted here; the bindings they replace are reset to 0.
    unsafe {
        // Two triangles splitting the square along its diagonal: 0 below it, 1 above.
        let corners: [f32; 12] = [-1., -1., 1., -1., 1., 1., -1., -1., 1., 1., -1., 1.];
        let target = TargetSpec {
            side: SIDE,
            storage: (glow::RGBA32F, glow::RGBA, glow::FLOAT),
            attachment: glow::COLOR_ATTACHMENT0,
        };
        let draw = match ScratchDraw::open(gl, (VERTEX, FRAGMENT), (&corners, 2), &target) {
            Ok(draw) => draw,
            Err(why) => {
                return (
                    false,
                    format!("a fragment shader reading gl_PrimitiveID: {why}"),
                );
            }
        };
        gl.draw_buffers(&[glow::COLOR_ATTACHMENT0]);
        gl.disable(glow::DEPTH_TEST);
        gl.disable(glow::STENCIL_TEST);
        gl.disable(glow::CULL_FACE);
        gl.disable(glow::BLEND);
        gl.disable(glow::SCISSOR_TEST);
        gl.clear_color(-1.0, -1.0, -1.0, 0.0);
        gl.clear(glow::COLOR_BUFFER_BIT);
        gl.use_program(Some(draw.program));
        gl.draw_arrays(glow::TRIANGLES, 0, 6);
        let pixels = draw.read_floats(gl, glow::RGBA, 4);
        let error = gl.get_error();
        draw.delete(gl);
        if error != glow::NO_ERROR {
            return (false, format!("GL error 0x{error:x} during the check"));
        }
        judge(&pixels)
    }
}

/// Checks each pixel centre off the diagonal: its triangle's ID, and the varying within a
/// hundredth of the centre's position.
fn judge(pixels: &[f32]) -> (bool, String) {
    for y in 0..SIDE {
        for x in 0..SIDE {
            if x == y {
                continue;
            }
            let p = &pixels[((y * SIDE + x) * 4) as usize..][..4];
            let id = if x > y { 0.0 } else { 1.0 };
            let u = (x as f32 + 0.5) / SIDE as f32;
            let v = (y as f32 + 0.5) / SIDE as f32;
            if p[0] != id || (p[1] - u).abs() > 0.01 || (p[2] - v).abs() > 0.01 {
                return (
                    false,
                    format!(
                        "gl_PrimitiveID in fragment shaders (GLSL 1.50) reads wrong: pixel \
                         {x},{y} saw ID {} and varying ({:.3}, {:.3}) where {id} and ({u:.3}, \
                         {v:.3}) were drawn",
                        p[0], p[1], p[2]
                    ),
                );
            }
        }
    }
    (
        true,
        "gl_PrimitiveID in fragment shaders (GLSL 1.50), checked by drawing".into(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn drawn(wrong: Option<(i32, i32)>) -> Vec<f32> {
        let mut p = Vec::new();
        for y in 0..SIDE {
            for x in 0..SIDE {
                let id = if x > y { 0.0 } else { 1.0 };
                let id = if wrong == Some((x, y)) { 0.5 } else { id };
                p.extend([
                    id,
                    (x as f32 + 0.5) / SIDE as f32,
                    (y as f32 + 0.5) / SIDE as f32,
                    1.0,
                ]);
            }
        }
        p
    }

    #[test]
    fn the_judge_takes_the_right_ids_and_names_the_first_wrong_pixel() {
        assert!(judge(&drawn(None)).0);
        let (ok, why) = judge(&drawn(Some((5, 2))));
        assert!(!ok);
        assert!(why.contains("pixel 5,2 saw ID 0.5"), "{why}");
        // The diagonal's pixels belong to either triangle.
        assert!(judge(&drawn(Some((3, 3)))).0);
    }
}
