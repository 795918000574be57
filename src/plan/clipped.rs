//! Which triangles of a depth-clipped shadow-volume part its clip planes leave anything of.
//!
//! `plan.depth_clip` gives each depth-pass part up to four `gl_ClipDistance` planes behind the
//! depth buffer, and the GL rejects a triangle whose three corners lie beyond one of them. On
//! llvmpipe that rejection comes after the vertex shader and primitive assembly, on the thread
//! that issues the draws; the truncated volumes' far caps and the sides running on behind the
//! walls are mostly such triangles (on oa_dm3 about two thirds of the volume triangles).
//! Testing them here, a block of triangles at a time where its box decides, and drawing the
//! rest through an index list costs a fraction of that.

use super::depth_bounds::MAX_PLANES;
use crate::geometry::Aabb;
use glam::{Mat4, Vec3, Vec4};

/// A corner counts as beyond a plane only when its distance is below minus this share of the
/// distance's terms in absolute value: float rounding on the GPU can then not put it on the
/// kept side, so a rejected triangle is one the GL would have rejected too.
const MARGIN: f32 = 1.0e-5;

/// Triangles per block whose box is tested before its triangles are.
pub const BLOCK_TRIANGLES: usize = 16;

/// The box of each block of [`BLOCK_TRIANGLES`] triangles of a triangle list of homogeneous
/// points; None for a block with a point at infinity (w = 0), whose triangles are tested one
/// by one.
pub fn block_bounds(vertices: &[[f32; 4]]) -> Vec<Option<Aabb>> {
    vertices
        .chunks(3 * BLOCK_TRIANGLES)
        .map(|block| {
            let mut b = Aabb::EMPTY;
            for v in block {
                if v[3] != 1.0 {
                    return None;
                }
                b.extend(Vec3::new(v[0], v[1], v[2]));
            }
            Some(b)
        })
        .collect()
}

/// The planes of one draw, as `gl_ClipDistance[i] = dot(plane, gl_Position)` (zero: none),
/// taken back to the part's own space.
pub struct ClipTest {
    /// Row i: plane i times the part's clip transform (distances in one product).
    distances: Mat4,
    /// The same product of the elements' absolute values: a bound on the absolute sum of the
    /// terms each distance adds up, which the rounding margin scales.
    magnitudes: Mat4,
}

/// What a block's box says of its triangles.
enum Block {
    /// Wholly beyond one plane: every triangle rejected.
    Beyond,
    /// On the kept side of every plane: none rejected.
    Inside,
    /// Each triangle to be tested.
    Mixed,
}

impl ClipTest {
    /// `to_clip` takes the part's vertices to clip space (view-projection times model). None
    /// when no plane is set: every triangle is kept.
    pub fn new(to_clip: Mat4, planes: &[[f32; 4]; MAX_PLANES]) -> Option<ClipTest> {
        if planes.iter().all(|p| *p == [0.0; 4]) {
            return None;
        }
        // Columns are the planes: transposed, its rows (an unset plane's row is zero, a
        // distance never below its margin).
        let rows = Mat4::from_cols_array_2d(planes).transpose();
        let abs = |m: Mat4| {
            Mat4::from_cols(
                m.x_axis.abs(),
                m.y_axis.abs(),
                m.z_axis.abs(),
                m.w_axis.abs(),
            )
        };
        Some(ClipTest {
            distances: rows * to_clip,
            magnitudes: abs(rows) * abs(to_clip),
        })
    }

    /// One bit per plane the homogeneous point `v` lies clearly beyond.
    fn beyond(&self, v: [f32; 4]) -> u32 {
        let v = Vec4::from_array(v);
        let d = self.distances * v;
        let margin = self.magnitudes * v.abs() * MARGIN;
        d.cmplt(-margin).bitmask()
    }

    /// The box's extremes of each distance: beyond one plane with its margin everywhere, or
    /// on the kept side of all of them everywhere.
    fn block(&self, b: &Aabb) -> Block {
        let centre = ((b.min + b.max) * 0.5).extend(1.0);
        let half = ((b.max - b.min) * 0.5).extend(0.0);
        let t = self.distances.transpose();
        let m = self.magnitudes.transpose();
        let reach = centre.abs() + half;
        let mut inside = true;
        for k in 0..4 {
            let (row, mag) = (t.col(k), m.col(k));
            let mid = row.dot(centre);
            let spread = row.abs().dot(half);
            if mid + spread < -MARGIN * mag.dot(reach) {
                return Block::Beyond;
            }
            inside &= mid - spread >= 0.0;
        }
        if inside { Block::Inside } else { Block::Mixed }
    }

    /// Appends to `out` the indices (`first` + position) of the triangles in `vertices` (a
    /// triangle list with `bounds` from [`block_bounds`]) that no clip plane wholly rejects;
    /// returns how many were rejected.
    pub fn kept_triangles(
        &self,
        vertices: &[[f32; 4]],
        bounds: &[Option<Aabb>],
        first: u32,
        out: &mut Vec<u32>,
    ) -> usize {
        let mut rejected = 0;
        let blocks = vertices.chunks(3 * BLOCK_TRIANGLES);
        for (k, (block, b)) in blocks.zip(bounds).enumerate() {
            let start = first + (k * 3 * BLOCK_TRIANGLES) as u32;
            let triangles = block.len() / 3;
            match b.as_ref().map_or(Block::Mixed, |b| self.block(b)) {
                Block::Beyond => rejected += triangles,
                Block::Inside => out.extend(start..start + 3 * triangles as u32),
                Block::Mixed => {
                    for (t, tri) in block.chunks_exact(3).enumerate() {
                        if self.beyond(tri[0]) & self.beyond(tri[1]) & self.beyond(tri[2]) != 0 {
                            rejected += 1;
                            continue;
                        }
                        let i = start + 3 * t as u32;
                        out.extend_from_slice(&[i, i + 1, i + 2]);
                    }
                }
            }
        }
        rejected
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Clip space is the vertices' own space; one plane z <= 0.5 (as dot(p, v) >= 0).
    fn test() -> ClipTest {
        let mut planes = [[0.0; 4]; MAX_PLANES];
        planes[1] = [0.0, 0.0, -1.0, 0.5];
        ClipTest::new(Mat4::IDENTITY, &planes).unwrap()
    }

    fn tri(z: [f32; 3]) -> [[f32; 4]; 3] {
        [
            [0.0, 1.0, z[0], 1.0],
            [1.0, 1.0, z[1], 1.0],
            [0.0, 2.0, z[2], 1.0],
        ]
    }

    /// The kept triangles' indices, each triangle tested alone and in blocks with boxes.
    fn kept(t: &ClipTest, vertices: &[[f32; 4]]) -> (usize, Vec<u32>) {
        let mut one_by_one = Vec::new();
        let unboxed = vec![None; vertices.len().div_ceil(3 * BLOCK_TRIANGLES)];
        let rejected = t.kept_triangles(vertices, &unboxed, 0, &mut one_by_one);
        let mut boxed = Vec::new();
        let again = t.kept_triangles(vertices, &block_bounds(vertices), 0, &mut boxed);
        assert_eq!((rejected, &one_by_one), (again, &boxed));
        (rejected, one_by_one)
    }

    #[test]
    fn no_plane_no_test() {
        assert!(ClipTest::new(Mat4::IDENTITY, &[[0.0; 4]; MAX_PLANES]).is_none());
    }

    #[test]
    fn rejects_only_triangles_wholly_beyond_a_plane() {
        let mut vertices = Vec::new();
        vertices.extend(tri([0.9, 0.8, 0.7])); // beyond: rejected
        vertices.extend(tri([0.9, 0.8, 0.4])); // one corner in front: kept
        vertices.extend(tri([0.1, 0.2, 0.3])); // in front: kept
        vertices.extend(tri([0.9, 0.9, 0.5])); // a corner on the plane: kept
        let (rejected, out) = kept(&test(), &vertices);
        assert_eq!(rejected, 1);
        assert_eq!(out, (3..12).collect::<Vec<u32>>());
    }

    #[test]
    fn a_corner_within_rounding_of_the_plane_is_kept() {
        let (rejected, out) = kept(&test(), &tri([0.9, 0.9, 0.5 + 0.5 * MARGIN]));
        assert_eq!((rejected, out.len()), (0, 3));
    }

    #[test]
    fn corners_beyond_different_planes_keep_the_triangle() {
        // x <= 0 and z <= 0.5: each corner is beyond one of them, no plane has all three.
        let mut planes = [[0.0; 4]; MAX_PLANES];
        planes[0] = [-1.0, 0.0, 0.0, 0.0];
        planes[1] = [0.0, 0.0, -1.0, 0.5];
        let t = ClipTest::new(Mat4::IDENTITY, &planes).unwrap();
        let vertices = [
            [1.0, 0.0, 0.0, 1.0],
            [1.0, 0.0, 0.9, 1.0],
            [-1.0, 0.0, 0.9, 1.0],
        ];
        assert_eq!(kept(&t, &vertices).0, 0);
    }

    #[test]
    fn points_at_infinity_are_tested_by_direction() {
        // w = 0: the plane's constant term drops out; z > 0 directions are beyond z <= 0.5.
        let vertices = [
            [0.0, 0.0, 1.0, 0.0],
            [1.0, 0.0, 2.0, 0.0],
            [0.0, 1.0, 0.7, 1.0],
        ];
        assert_eq!(block_bounds(&vertices), vec![None]);
        assert_eq!(kept(&test(), &vertices).0, 1);
    }

    #[test]
    fn whole_blocks_agree_with_their_triangles() {
        // Forty triangles stepping through the plane: blocks wholly beyond, wholly in front
        // and straddling it.
        let vertices: Vec<[f32; 4]> = (0..40)
            .flat_map(|i| {
                let z = -1.0 + i as f32 * 0.05;
                tri([z, z + 0.02, z + 0.04])
            })
            .collect();
        let (rejected, out) = kept(&test(), &vertices);
        // z + 0.04 < 0.5 for i <= 28 (in front), z > 0.5 for i >= 31 (beyond).
        assert_eq!(rejected, 9);
        assert_eq!(out.len(), 3 * 31);
    }
}
