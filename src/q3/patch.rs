//! Quadratic Bezier patches (paper 2.3), tessellated once at load with a fixed level.
//!
//! A patch is a grid of `width × height` control points (both odd); every 3×3 block sharing its
//! border rows is one biquadratic segment, split into `level × level` quads.
//!
//! Crack-free by construction: a vertex on a patch border depends only on that border's three
//! control points, and it is computed in the same floating-point operations whichever patch, and
//! whichever direction, evaluates it. For parameter `k/L` both `t = k/L` and `s = (L-k)/L` are
//! computed from integers, the basis is `(s·s, 2·(s·t), t·t)`, and the three terms are summed as
//! `(b0·P0 + b2·P2) + b1·P1`; reversing the direction swaps `s` with `t` and `P0` with `P2`,
//! which leaves every operation's operands the same. At a border `s = 1, t = 0` exactly, so the
//! inner sum collapses to the border row bit for bit.

use super::bsp::DrawVert;
use thiserror::Error;

/// Most quads per segment side accepted (Quake 3 never needs more than 16).
pub const MAX_LEVEL: u32 = 64;
/// Most vertices one patch may tessellate to. Quake 3's own grids stop at 65 × 65; this leaves
/// room for high levels on big patches, but a 255 × 255 grid at level 64 (66 million vertices,
/// gigabytes and tens of seconds) is refused instead of built.
pub const MAX_VERTICES: usize = 1 << 20;

#[derive(Debug, Error, PartialEq)]
pub enum PatchError {
    #[error("patch size {0}x{1}: sides must be odd and at least 3")]
    BadSize(usize, usize),
    #[error("patch has {got} control points, {width}x{height} needs {needed}")]
    WrongCount {
        width: usize,
        height: usize,
        got: usize,
        needed: usize,
    },
    #[error("tessellation level {0} is outside 1..={MAX_LEVEL}")]
    BadLevel(u32),
    #[error(
        "patch {width}x{height} at level {level} makes {vertices} vertices, more than {MAX_VERTICES}"
    )]
    TooManyVertices {
        width: usize,
        height: usize,
        level: u32,
        vertices: usize,
    },
}

/// One tessellated vertex (f64 evaluation rounded once to f32).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PatchVertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub st: [f32; 2],
    pub lightmap: [f32; 2],
}

/// The tessellated patch: a `columns × rows` vertex grid and its triangles.
#[derive(Debug, Clone, PartialEq)]
pub struct Tessellation {
    pub columns: usize,
    pub rows: usize,
    pub vertices: Vec<PatchVertex>,
    pub indices: Vec<u32>,
}

fn basis(k: u32, level: u32) -> [f64; 3] {
    let t = k as f64 / level as f64;
    let s = (level - k) as f64 / level as f64;
    [s * s, 2.0 * (s * t), t * t]
}

/// `(b0·p0 + b2·p2) + b1·p1` component-wise, the order that makes edges symmetric.
fn blend<const N: usize>(b: &[f64; 3], p: [[f64; N]; 3]) -> [f64; N] {
    let mut out = [0.0; N];
    for i in 0..N {
        out[i] = (b[0] * p[0][i] + b[2] * p[2][i]) + b[1] * p[1][i];
    }
    out
}

fn attrs(v: &DrawVert) -> [f64; 10] {
    let f = |x: f32| if x.is_finite() { x as f64 } else { 0.0 };
    [
        v.position[0] as f64,
        v.position[1] as f64,
        v.position[2] as f64,
        f(v.normal[0]),
        f(v.normal[1]),
        f(v.normal[2]),
        f(v.st[0]),
        f(v.st[1]),
        f(v.lightmap[0]),
        f(v.lightmap[1]),
    ]
}

/// Tessellates a `width × height` control grid (row-major) with `level` quads per segment side.
pub fn tessellate(
    control: &[DrawVert],
    width: usize,
    height: usize,
    level: u32,
) -> Result<Tessellation, PatchError> {
    if width < 3 || height < 3 || width.is_multiple_of(2) || height.is_multiple_of(2) {
        return Err(PatchError::BadSize(width, height));
    }
    if control.len() != width * height {
        return Err(PatchError::WrongCount {
            width,
            height,
            got: control.len(),
            needed: width * height,
        });
    }
    if !(1..=MAX_LEVEL).contains(&level) {
        return Err(PatchError::BadLevel(level));
    }
    let l = level as usize;
    let (seg_x, seg_y) = ((width - 1) / 2, (height - 1) / 2);
    let (columns, rows) = (seg_x * l + 1, seg_y * l + 1);
    // Checked before anything is allocated: the sides and level are each bounded, their product
    // is not.
    let vertices = columns.saturating_mul(rows);
    if vertices > MAX_VERTICES {
        return Err(PatchError::TooManyVertices {
            width,
            height,
            level,
            vertices,
        });
    }
    let ctrl: Vec<[f64; 10]> = control.iter().map(attrs).collect();
    let mut vertices = Vec::with_capacity(columns * rows);
    for gy in 0..rows {
        let sy = (gy / l).min(seg_y - 1);
        let by = basis((gy - sy * l) as u32, level);
        for gx in 0..columns {
            let sx = (gx / l).min(seg_x - 1);
            let bx = basis((gx - sx * l) as u32, level);
            // Evaluate along u (width) in each of the three rows, then along v.
            let row = |b: usize| {
                let base = (2 * sy + b) * width + 2 * sx;
                blend(&bx, [ctrl[base], ctrl[base + 1], ctrl[base + 2]])
            };
            let p = blend(&by, [row(0), row(1), row(2)]);
            let n = [p[3], p[4], p[5]];
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            let normal = if len > 1e-12 {
                [
                    (n[0] / len) as f32,
                    (n[1] / len) as f32,
                    (n[2] / len) as f32,
                ]
            } else {
                [0.0, 0.0, 1.0]
            };
            vertices.push(PatchVertex {
                position: [p[0] as f32, p[1] as f32, p[2] as f32],
                normal,
                st: [p[6] as f32, p[7] as f32],
                lightmap: [p[8] as f32, p[9] as f32],
            });
        }
    }
    // Two triangles per grid quad; the winding is chosen below so that front faces agree with the
    // control normals (which q3map points at the visible side).
    let idx = |x: usize, y: usize| (y * columns + x) as u32;
    let mut indices = Vec::with_capacity((columns - 1) * (rows - 1) * 6);
    for y in 0..rows - 1 {
        for x in 0..columns - 1 {
            let (a, b, c, d) = (idx(x, y), idx(x + 1, y), idx(x + 1, y + 1), idx(x, y + 1));
            indices.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    let mut agreement = 0.0f64;
    for t in indices.chunks_exact(3) {
        let p = |i: u32| {
            let v = &vertices[i as usize];
            glam::DVec3::from_array(v.position.map(|x| x as f64))
        };
        let geometric = (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0]));
        let n = |i: u32| glam::DVec3::from_array(vertices[i as usize].normal.map(|x| x as f64));
        agreement += geometric.dot(n(t[0]) + n(t[1]) + n(t[2]));
    }
    if agreement < 0.0 {
        for t in indices.chunks_exact_mut(3) {
            t.swap(1, 2);
        }
    }
    Ok(Tessellation {
        columns,
        rows,
        vertices,
        indices,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(width: usize, height: usize, f: impl Fn(usize, usize) -> [f32; 3]) -> Vec<DrawVert> {
        let mut v = Vec::new();
        for y in 0..height {
            for x in 0..width {
                v.push(DrawVert {
                    position: f(x, y),
                    normal: [0.0, 0.0, 1.0],
                    st: [x as f32, y as f32],
                    ..DrawVert::default()
                });
            }
        }
        v
    }

    /// A bumpy 5x3 patch with irrational-looking coordinates, so rounding would show.
    fn bumpy(x: usize, y: usize) -> [f32; 3] {
        [
            x as f32 * 13.37 + (y as f32 * 0.7).sin(),
            y as f32 * 7.1 + (x as f32 * 1.3).cos() * 3.0,
            ((x * 7 + y * 3) % 5) as f32 * 2.9 - 1.1,
        ]
    }

    #[test]
    fn corner_control_points_are_interpolated_exactly() {
        let c = grid(5, 3, bumpy);
        for level in [1, 3, 4, 7, 16] {
            let t = tessellate(&c, 5, 3, level).unwrap();
            assert_eq!(
                (t.columns, t.rows),
                (2 * level as usize + 1, level as usize + 1)
            );
            let corner = |x: usize, y: usize| t.vertices[y * t.columns + x].position;
            assert_eq!(corner(0, 0), c[0].position);
            assert_eq!(corner(t.columns - 1, 0), c[4].position);
            assert_eq!(corner(0, t.rows - 1), c[10].position);
            assert_eq!(corner(t.columns - 1, t.rows - 1), c[14].position);
            // The middle control column (x = 2) is a segment corner too.
            assert_eq!(corner(level as usize, 0), c[2].position);
        }
    }

    #[test]
    fn a_flat_patch_stays_flat_and_faces_its_normals() {
        let c = grid(3, 3, |x, y| [x as f32 * 10.0, y as f32 * 10.0, 5.0]);
        let t = tessellate(&c, 3, 3, 4).unwrap();
        assert_eq!(t.indices.len(), 4 * 4 * 6);
        for v in &t.vertices {
            assert_eq!(v.position[2], 5.0);
        }
        for tri in t.indices.chunks_exact(3) {
            let p = |i: u32| glam::Vec3::from_array(t.vertices[i as usize].position);
            let n = (p(tri[1]) - p(tri[0])).cross(p(tri[2]) - p(tri[0]));
            assert!(n.z > 0.0, "front faces follow the +Z control normals");
        }
        // Midpoint of a linear patch in parameter space is the midpoint in space.
        assert_eq!(t.vertices[2 * t.columns + 2].position, [10.0, 10.0, 5.0]);
    }

    #[test]
    fn patches_sharing_an_edge_produce_identical_vertices_along_it() {
        // Patch A: 5 columns; patch B continues from A's last column (x = 4), and patch C shares
        // the same edge but stores it reversed and along its own rows instead of columns.
        let a = grid(5, 3, bumpy);
        let b = grid(3, 3, |x, y| {
            if x == 0 {
                bumpy(4, y)
            } else {
                [60.0 + x as f32 * 9.1, y as f32 * 7.3, 1.7 * x as f32]
            }
        });
        let c = grid(3, 3, |x, y| {
            // Row y = 2 of C is A's edge x = 4 read from its far end: C(x, 2) = A(4, 2 - x).
            if y == 2 {
                bumpy(4, 2 - x)
            } else {
                [80.0 + x as f32, -20.0 - y as f32 * 3.3, 0.4]
            }
        });
        for level in [2, 5, 8] {
            let ta = tessellate(&a, 5, 3, level).unwrap();
            let tb = tessellate(&b, 3, 3, level).unwrap();
            let tc = tessellate(&c, 3, 3, level).unwrap();
            for k in 0..ta.rows {
                let on_a = ta.vertices[k * ta.columns + ta.columns - 1].position;
                let on_b = tb.vertices[k * tb.columns].position;
                let on_c = tc.vertices[(tc.rows - 1) * tc.columns + (tc.columns - 1 - k)].position;
                assert_eq!(on_a, on_b, "level {level} row {k}");
                assert_eq!(on_a, on_c, "level {level} row {k} (reversed edge)");
            }
        }
    }

    #[test]
    fn bad_input_is_rejected() {
        let c = grid(3, 3, bumpy);
        assert_eq!(tessellate(&c, 4, 3, 2), Err(PatchError::BadSize(4, 3)));
        assert_eq!(tessellate(&c, 3, 1, 2), Err(PatchError::BadSize(3, 1)));
        assert!(matches!(
            tessellate(&c[..8], 3, 3, 2),
            Err(PatchError::WrongCount { .. })
        ));
        assert_eq!(tessellate(&c, 3, 3, 0), Err(PatchError::BadLevel(0)));
        assert_eq!(tessellate(&c, 3, 3, 65), Err(PatchError::BadLevel(65)));
    }

    #[test]
    fn a_grid_too_big_to_tessellate_is_refused_before_allocating() {
        let c = vec![DrawVert::default(); 255 * 255];
        assert!(matches!(
            tessellate(&c, 255, 255, 64),
            Err(PatchError::TooManyVertices {
                vertices: 66_080_641,
                ..
            })
        ));
        // The largest grid Quake 3 builds (65 x 65 vertices) is far below the bound.
        assert!(tessellate(&c[..33 * 33], 33, 33, 4).is_ok());
    }
}
