//! Which boxes the camera can see any part of, judged from the frame's depth buffer after the
//! base pass: a CPU copy of the hierarchical-Z test a GPU does per tile. A receiver whose box is
//! wholly behind what the camera sees holds no visible pixel, so no shadow volume has to reach
//! it; casters whose shadow reaches only such receivers then drop out (see `shadow::volume`).

use super::CameraSetup;
use super::scissor::{Projection, Scissor, project};
use crate::geometry::Aabb;

/// How far (in window depth) a box must lie behind the depth buffer to count as hidden: a few
/// hundred steps of a 24-bit buffer, against rounding in the rasterised depth and in the box's
/// projection.
pub(crate) const DEPTH_MARGIN: f32 = 1.0 / (1 << 16) as f32;

/// Max-depth mip chain of a depth image (window depth, 0 near .. 1 far).
#[derive(Debug)]
pub struct DepthPyramid {
    /// The image's size in pixels.
    width: usize,
    height: usize,
    /// The finest level held: 0 for the image itself, k for the maxima of its 2^k×2^k blocks
    /// (reduced on the GPU, see `gl::depth_reduce`).
    first: usize,
    /// Level `first + i` is `levels[i]`. Level 0 is the image (rows bottom-up, as GL's window
    /// coordinates); level k+1 holds the maximum of each 2×2 block of level k (edges padded by
    /// repetition).
    levels: Vec<Level>,
}

#[derive(Debug)]
struct Level {
    width: usize,
    height: usize,
    max: Vec<f32>,
    /// The same over pixels that show a surface (nearer than the far plane, where the clear
    /// left 1.0: sky, holes); [`NO_SURFACE`] where none does.
    surface: Vec<f32>,
}

/// A texel of [`Level::surface`] without any surface pixel under it.
const NO_SURFACE: f32 = f32::NEG_INFINITY;

impl Level {
    fn at(&self, x: usize, y: usize) -> f32 {
        self.max[y * self.width + x]
    }
}

/// Pixels `x.0..=x.1`, `y.0..=y.1` (GL window coordinates) and a bound on the depth they hold.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DepthBlock {
    pub x: (usize, usize),
    pub y: (usize, usize),
    pub max: f32,
    /// A bound on the depth of the pixels that show a surface (nearer than the far plane);
    /// None where every pixel shows the clear.
    pub surface: Option<f32>,
}

/// The larger of two depths (never NaN), in the form that compiles to one vector instruction
/// (`f32::max` also orders NaN).
fn max(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// The maximum of each 2×2 block of a `width`×`height` image (the last column and row
/// repeated where the size is odd), one row pair at a time so the loop runs over slices.
fn reduce_2x2(image: &[f32], width: usize, height: usize) -> Vec<f32> {
    let (w, h) = (width.div_ceil(2), height.div_ceil(2));
    let mut out = Vec::with_capacity(w * h);
    for y in 0..h {
        let r0 = &image[2 * y * width..][..width];
        let r1 = &image[(2 * y + 1).min(height - 1) * width..][..width];
        let pairs = r0.chunks_exact(2).zip(r1.chunks_exact(2));
        out.extend(pairs.map(|(a, b)| max(max(a[0], a[1]), max(b[0], b[1]))));
        if width % 2 == 1 {
            out.push(max(r0[width - 1], r1[width - 1]));
        }
    }
    out
}

impl DepthPyramid {
    /// From `depth` (`width`×`height` values, top row first, as `read_pixels` gives them).
    /// None when the sizes disagree.
    pub fn from_top_down(depth: &[f32], width: usize, height: usize) -> Option<DepthPyramid> {
        if width == 0 || depth.len() != width * height {
            return None;
        }
        let bottom_up = depth.chunks_exact(width).rev().flatten().copied().collect();
        DepthPyramid::from_bottom_up(bottom_up, width, height)
    }

    /// From `depth` in window coordinates' row order (bottom row first, as GL reads them).
    /// None when the sizes disagree.
    pub fn from_bottom_up(depth: Vec<f32>, width: usize, height: usize) -> Option<DepthPyramid> {
        let surface = depth
            .iter()
            .map(|&d| if d < 1.0 { d } else { -1.0 })
            .collect();
        DepthPyramid::from_level(0, depth, surface, width, height)
    }

    /// From level `first` of a `width`×`height` image's pyramid (bottom row first): the
    /// maximum depth of each 2^first×2^first block (the last column and row of pixels
    /// repeated past the edge), and the maximum over its pixels nearer than the far plane
    /// (negative where none is). None when the sizes disagree.
    pub fn from_level(
        first: usize,
        max: Vec<f32>,
        surface: Vec<f32>,
        width: usize,
        height: usize,
    ) -> Option<DepthPyramid> {
        if width == 0 || height == 0 || first > 16 {
            return None;
        }
        let (w, h) = (width.div_ceil(1 << first), height.div_ceil(1 << first));
        if max.len() != w * h || surface.len() != w * h {
            return None;
        }
        let surface = surface
            .into_iter()
            .map(|d| if d >= 0.0 { d } else { NO_SURFACE })
            .collect();
        let mut levels = vec![Level {
            width: w,
            height: h,
            max,
            surface,
        }];
        while let Some(l) = levels.last().filter(|l| l.width > 1 || l.height > 1) {
            let next = Level {
                width: l.width.div_ceil(2),
                height: l.height.div_ceil(2),
                max: reduce_2x2(&l.max, l.width, l.height),
                surface: reduce_2x2(&l.surface, l.width, l.height),
            };
            levels.push(next);
        }
        Some(DepthPyramid {
            width,
            height,
            first,
            levels,
        })
    }

    /// Whether `other` holds the same image at the same level (so every bound read from
    /// either is the same).
    pub fn same_as(&self, other: &DepthPyramid) -> bool {
        (self.width, self.height, self.first) == (other.width, other.height, other.first)
            && self.levels[0].max == other.levels[0].max
            && self.levels[0].surface == other.levels[0].surface
    }

    /// The finest level held where `pixels` span at most `texels` texels.
    fn level_for(&self, pixels: usize, texels: usize) -> usize {
        let mut k = self.first;
        while k + 1 < self.first + self.levels.len() && (pixels >> k) > texels.max(1) {
            k += 1;
        }
        k
    }

    fn level(&self, k: usize) -> &Level {
        &self.levels[k - self.first]
    }

    /// The largest depth over the pixels `x0..=x1`, `y0..=y1` (GL window coordinates, clamped
    /// to the image), from the level where the rectangle spans at most 4×4 texels.
    fn max_over(&self, x0: usize, y0: usize, x1: usize, y1: usize) -> f32 {
        let (x1, y1) = (x1.min(self.width - 1), y1.min(self.height - 1));
        let k = self.level_for((x1 - x0).max(y1 - y0) + 1, 4);
        let l = self.level(k);
        let mut m = 0.0f32;
        for y in (y0 >> k)..=(y1 >> k).min(l.height - 1) {
            for x in (x0 >> k)..=(x1 >> k).min(l.width - 1) {
                m = m.max(l.at(x, y));
            }
        }
        m
    }

    /// The rectangle `rect` (clipped to the image) as the texels of the finest level where it
    /// spans at most `span` texels each way: each with the pixels of the rectangle it covers
    /// and the largest depth it holds (which may reach past the rectangle: a bound). Empty for
    /// an empty rectangle or one off the image.
    pub fn blocks(&self, rect: &Scissor, span: usize) -> Vec<DepthBlock> {
        let image = Scissor {
            x: 0,
            y: 0,
            width: self.width as i32,
            height: self.height as i32,
        };
        let r = rect.intersect(&image);
        if r.area() == 0 {
            return Vec::new();
        }
        let (x0, y0) = (r.x as usize, r.y as usize);
        let (x1, y1) = (x0 + r.width as usize - 1, y0 + r.height as usize - 1);
        let k = self.level_for((x1 - x0).max(y1 - y0) + 1, span);
        let l = self.level(k);
        let mut blocks = Vec::new();
        for ty in (y0 >> k)..=(y1 >> k).min(l.height - 1) {
            for tx in (x0 >> k)..=(x1 >> k).min(l.width - 1) {
                blocks.push(DepthBlock {
                    x: ((tx << k).max(x0), ((tx + 1) << k).min(x1 + 1) - 1),
                    y: ((ty << k).max(y0), ((ty + 1) << k).min(y1 + 1) - 1),
                    max: l.at(tx, ty),
                    surface: Some(l.surface[ty * l.width + tx]).filter(|&d| d != NO_SURFACE),
                });
            }
        }
        blocks
    }

    /// The largest depth the buffer holds within `rect` (a bound: the pyramid level's texels
    /// may reach past it), plus the rounding margin; None for an empty rectangle or one off the
    /// image.
    pub fn farthest(&self, rect: &Scissor) -> Option<f32> {
        // The texels `max_over` would read: those of the level spanning at most 4×4.
        self.blocks(rect, 4)
            .iter()
            .map(|b| b.max)
            .reduce(f32::max)
            .map(|m| m + DEPTH_MARGIN)
    }

    /// Whether every pixel the box can cover shows a surface in front of the whole box, so no
    /// point of the box is visible. Conservative: a box reaching the camera's near plane, or
    /// whose projection is not bounded, is visible.
    pub fn hides(&self, camera: &CameraSetup, b: &Aabb) -> bool {
        if self.width != camera.width as usize || self.height != camera.height as usize {
            return false;
        }
        let Projection::Bounded { lo, hi, nearest } = project(camera, &b.corners()) else {
            return false;
        };
        if hi.x < -1.0 || hi.y < -1.0 || lo.x > 1.0 || lo.y > 1.0 {
            // Off screen: nothing of it is seen.
            return true;
        }
        let (w, h) = (camera.width as f32, camera.height as f32);
        // Every pixel whose centre the box's projection can cover, one pixel wider each side.
        let px = |v: f32, size: f32| ((v.clamp(-1.0, 1.0) * 0.5 + 0.5) * size).floor();
        let x0 = (px(lo.x, w) - 1.0).max(0.0) as usize;
        let y0 = (px(lo.y, h) - 1.0).max(0.0) as usize;
        let x1 = (px(hi.x, w) + 1.0).max(0.0) as usize;
        let y1 = (px(hi.y, h) + 1.0).max(0.0) as usize;
        nearest > self.max_over(x0, y0, x1, y1) + DEPTH_MARGIN
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Camera;
    use glam::Vec3;

    fn camera() -> CameraSetup {
        CameraSetup::new(
            &Camera::looking_at(Vec3::ZERO, Vec3::new(100.0, 0.0, 0.0)),
            64,
            48,
        )
    }

    /// Window depth of a point straight ahead at distance `d`.
    fn depth_at(c: &CameraSetup, d: f32) -> f32 {
        let clip = c.view_proj * Vec3::new(d, 0.0, 0.0).extend(1.0);
        clip.z / clip.w * 0.5 + 0.5
    }

    fn small_box(center: Vec3) -> Aabb {
        Aabb {
            min: center - 1.0,
            max: center + 1.0,
        }
    }

    #[test]
    fn a_box_behind_a_wall_is_hidden_and_one_before_it_is_not() {
        let c = camera();
        let wall = depth_at(&c, 50.0);
        let p = DepthPyramid::from_top_down(&vec![wall; 64 * 48], 64, 48).unwrap();
        assert!(p.hides(&c, &small_box(Vec3::new(80.0, 0.0, 0.0))));
        assert!(!p.hides(&c, &small_box(Vec3::new(30.0, 0.0, 0.0))));
        // Straddling the wall: part of it is in front.
        assert!(!p.hides(&c, &small_box(Vec3::new(50.5, 0.0, 0.0))));
        // Reaching behind the camera: its projection is unbounded.
        let around = Aabb {
            min: Vec3::splat(-5.0),
            max: Vec3::splat(5.0),
        };
        assert!(!p.hides(&c, &around));
    }

    #[test]
    fn one_far_pixel_in_the_box_rectangle_keeps_it_visible() {
        let c = camera();
        let (wall, far) = (depth_at(&c, 50.0), 1.0);
        // The box's centre projects to the screen's centre, pixel corner (32, 24).
        for (x, y, seen) in [
            (32usize, 24usize, true),
            (0, 0, false),
            (63, 47, false),
            (31, 23, true),
        ] {
            let mut depth = vec![wall; 64 * 48];
            // A hole in the wall where the box projects (the centre of the screen).
            depth[(47 - y) * 64 + x] = far;
            let p = DepthPyramid::from_top_down(&depth, 64, 48).unwrap();
            let ahead = small_box(Vec3::new(80.0, 0.0, 0.0));
            assert_eq!(p.hides(&c, &ahead), !seen, "hole at {x},{y}");
        }
    }

    #[test]
    fn a_pyramid_from_block_maxima_holds_the_full_one_above_them() {
        let (w, h) = (37usize, 23usize);
        // Bottom-up rows; every fifth pixel at the far plane.
        let depth: Vec<f32> = (0..w * h)
            .map(|i| {
                if i % 5 == 0 {
                    1.0
                } else {
                    ((i * 7919) % 1009) as f32 / 1010.0
                }
            })
            .collect();
        let full = DepthPyramid::from_bottom_up(depth.clone(), w, h).unwrap();
        // Level 2 by brute force, as the GPU reduction computes it (edges clamped).
        let (bw, bh) = (w.div_ceil(4), h.div_ceil(4));
        let (mut max, mut surface) = (Vec::new(), Vec::new());
        for by in 0..bh {
            for bx in 0..bw {
                let pixels: Vec<f32> = (0..16)
                    .map(|i| {
                        let (x, y) = ((4 * bx + i % 4).min(w - 1), (4 * by + i / 4).min(h - 1));
                        depth[y * w + x]
                    })
                    .collect();
                max.push(pixels.iter().copied().fold(0.0, f32::max));
                surface.push(
                    pixels
                        .iter()
                        .copied()
                        .filter(|&d| d < 1.0)
                        .fold(-1.0, f32::max),
                );
            }
        }
        let reduced = DepthPyramid::from_level(2, max, surface, w, h).unwrap();
        assert_eq!(reduced.levels.len() + 2, full.levels.len());
        for (a, b) in reduced.levels.iter().zip(&full.levels[2..]) {
            assert_eq!((a.width, a.height), (b.width, b.height));
            assert_eq!(a.max, b.max);
            assert_eq!(a.surface, b.surface);
        }
        // Judged by its coarser levels, every bound still holds.
        assert!(reduced.max_over(3, 4, 3, 4) >= depth[4 * w + 3]);
        assert_eq!(
            reduced
                .blocks(
                    &Scissor {
                        x: 0,
                        y: 0,
                        width: 2,
                        height: 2
                    },
                    16
                )
                .len(),
            1
        );
        // Sizes that disagree are refused.
        assert!(DepthPyramid::from_level(2, vec![0.0; 3], vec![0.0; 3], w, h).is_none());
    }

    #[test]
    fn the_maximum_over_any_rectangle_matches_a_brute_force_scan() {
        let (w, h) = (37usize, 23usize);
        let depth: Vec<f32> = (0..w * h)
            .map(|i| ((i * 7919) % 1009) as f32 / 1009.0)
            .collect();
        let p = DepthPyramid::from_top_down(&depth, w, h).unwrap();
        for (x0, y0, x1, y1) in [
            (0, 0, 36, 22),
            (3, 4, 9, 7),
            (10, 10, 10, 10),
            (20, 0, 36, 5),
        ] {
            let mut brute = 0.0f32;
            for y in y0..=y1 {
                for x in x0..=x1 {
                    brute = brute.max(depth[(h - 1 - y) * w + x]);
                }
            }
            // A coarser level may take in texels just outside: never less than the true max.
            assert!(p.max_over(x0, y0, x1, y1) >= brute);
            if (x0, y0, x1, y1) == (10, 10, 10, 10) {
                assert_eq!(p.max_over(x0, y0, x1, y1), brute);
            }
        }
    }

    #[test]
    fn the_farthest_depth_of_a_rectangle_bounds_its_pixels_and_clips_to_the_image() {
        let (w, h) = (40usize, 30usize);
        // Window rows bottom-up: depth grows with y, so a rectangle's farthest is its top row.
        let top_down: Vec<f32> = (0..w * h).map(|i| (h - 1 - i / w) as f32 / 100.0).collect();
        let p = DepthPyramid::from_top_down(&top_down, w, h).unwrap();
        let rect = |x, y, width, height| Scissor {
            x,
            y,
            width,
            height,
        };
        let single = p.farthest(&rect(5, 7, 1, 1)).unwrap();
        assert!((single - (0.07 + DEPTH_MARGIN)).abs() < 1e-7, "{single}");
        let tall = p.farthest(&rect(2, 3, 4, 10)).unwrap();
        assert!(tall >= 0.12 + DEPTH_MARGIN, "{tall}");
        // Reaching past the image: clamped to it; wholly off it or empty: nothing.
        let past = p.farthest(&rect(-10, 25, 100, 100)).unwrap();
        assert!((past - (0.29 + DEPTH_MARGIN)).abs() < 1e-7, "{past}");
        assert_eq!(p.farthest(&rect(50, 0, 10, 10)), None);
        assert_eq!(p.farthest(&rect(-20, 0, 10, 10)), None);
        assert_eq!(p.farthest(&rect(3, 3, 0, 5)), None);
    }

    #[test]
    fn block_surface_depths_bound_the_surface_pixels_and_skip_the_far_plane() {
        let (w, h) = (53usize, 37usize);
        // Window rows bottom-up; every seventh pixel and a whole corner at the far plane.
        let bottom_up: Vec<f32> = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                if i % 7 == 0 || (x > 40 && y > 25) {
                    1.0
                } else {
                    ((i * 7919) % 1009) as f32 / 1010.0
                }
            })
            .collect();
        let p = DepthPyramid::from_bottom_up(bottom_up.clone(), w, h).unwrap();
        let (mut with, mut without) = (0, 0);
        for (r, span) in [
            (
                Scissor {
                    x: 0,
                    y: 0,
                    width: 53,
                    height: 37,
                },
                4,
            ),
            (
                Scissor {
                    x: 38,
                    y: 20,
                    width: 15,
                    height: 17,
                },
                16,
            ),
            (
                Scissor {
                    x: 3,
                    y: 5,
                    width: 9,
                    height: 6,
                },
                16,
            ),
            (
                Scissor {
                    x: 42,
                    y: 27,
                    width: 11,
                    height: 10,
                },
                2,
            ),
        ] {
            for b in p.blocks(&r, span) {
                let surface = (b.y.0..=b.y.1)
                    .flat_map(|y| (b.x.0..=b.x.1).map(move |x| (x, y)))
                    .map(|(x, y)| bottom_up[y * w + x])
                    .filter(|&d| d < 1.0)
                    .reduce(f32::max);
                match (b.surface, surface) {
                    (Some(bound), Some(truth)) => {
                        assert!(bound >= truth && bound < 1.0, "{bound} < {truth}");
                        with += 1;
                    }
                    // A coarse texel may take in surface pixels just outside the block.
                    (Some(bound), None) => assert!(bound < 1.0),
                    (None, truth) => {
                        assert_eq!(truth, None);
                        without += 1;
                    }
                }
            }
        }
        assert!(with > 10 && without > 0, "{with} {without}");
    }
}
