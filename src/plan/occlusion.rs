//! Which boxes the camera can see any part of, judged from the frame's depth buffer after the
//! base pass: a CPU copy of the hierarchical-Z test a GPU does per tile. A receiver whose box is
//! wholly behind what the camera sees holds no visible pixel, so no shadow volume has to reach
//! it; casters whose shadow reaches only such receivers then drop out (see `shadow::volume`).

use super::CameraSetup;
use super::scissor::{Projection, Scissor, project};
use crate::scene::Aabb;

/// How far (in window depth) a box must lie behind the depth buffer to count as hidden: a few
/// hundred steps of a 24-bit buffer, against rounding in the rasterised depth and in the box's
/// projection.
pub(crate) const DEPTH_MARGIN: f32 = 1.0 / (1 << 16) as f32;

/// Max-depth mip chain of a depth image (window depth, 0 near .. 1 far).
#[derive(Debug)]
pub struct DepthPyramid {
    /// Level 0 is the image (rows bottom-up, as GL's window coordinates); level k+1 holds the
    /// maximum of each 2×2 block of level k (edges padded by repetition).
    levels: Vec<Level>,
}

#[derive(Debug)]
struct Level {
    width: usize,
    height: usize,
    max: Vec<f32>,
}

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
}

impl DepthPyramid {
    /// From `depth` (`width`×`height` values, top row first, as `read_pixels` gives them).
    /// None when the sizes disagree.
    pub fn from_top_down(depth: &[f32], width: usize, height: usize) -> Option<DepthPyramid> {
        if width == 0 || height == 0 || depth.len() != width * height {
            return None;
        }
        let mut base = Vec::with_capacity(depth.len());
        for row in depth.chunks_exact(width).rev() {
            base.extend_from_slice(row);
        }
        let mut levels = vec![Level {
            width,
            height,
            max: base,
        }];
        while let Some(l) = levels.last().filter(|l| l.width > 1 || l.height > 1) {
            let (w, h) = (l.width.div_ceil(2), l.height.div_ceil(2));
            let mut max = Vec::with_capacity(w * h);
            for y in 0..h {
                for x in 0..w {
                    let (x0, y0) = (2 * x, 2 * y);
                    let (x1, y1) = ((x0 + 1).min(l.width - 1), (y0 + 1).min(l.height - 1));
                    max.push(
                        l.at(x0, y0)
                            .max(l.at(x1, y0))
                            .max(l.at(x0, y1))
                            .max(l.at(x1, y1)),
                    );
                }
            }
            levels.push(Level {
                width: w,
                height: h,
                max,
            });
        }
        Some(DepthPyramid { levels })
    }

    /// The finest level where `pixels` span at most `texels` texels.
    fn level_for(&self, pixels: usize, texels: usize) -> usize {
        let mut k = 0;
        while k + 1 < self.levels.len() && (pixels >> k) > texels.max(1) {
            k += 1;
        }
        k
    }

    /// The largest depth over the pixels `x0..=x1`, `y0..=y1` (GL window coordinates, clamped
    /// to the image), from the level where the rectangle spans at most 4×4 texels.
    fn max_over(&self, x0: usize, y0: usize, x1: usize, y1: usize) -> f32 {
        let base = &self.levels[0];
        let (x1, y1) = (x1.min(base.width - 1), y1.min(base.height - 1));
        let k = self.level_for((x1 - x0).max(y1 - y0) + 1, 4);
        let l = &self.levels[k];
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
        let base = &self.levels[0];
        let image = Scissor {
            x: 0,
            y: 0,
            width: base.width as i32,
            height: base.height as i32,
        };
        let r = rect.intersect(&image);
        if r.area() == 0 {
            return Vec::new();
        }
        let (x0, y0) = (r.x as usize, r.y as usize);
        let (x1, y1) = (x0 + r.width as usize - 1, y0 + r.height as usize - 1);
        let k = self.level_for((x1 - x0).max(y1 - y0) + 1, span);
        let l = &self.levels[k];
        let mut blocks = Vec::new();
        for ty in (y0 >> k)..=(y1 >> k).min(l.height - 1) {
            for tx in (x0 >> k)..=(x1 >> k).min(l.width - 1) {
                blocks.push(DepthBlock {
                    x: ((tx << k).max(x0), ((tx + 1) << k).min(x1 + 1) - 1),
                    y: ((ty << k).max(y0), ((ty + 1) << k).min(y1 + 1) - 1),
                    max: l.at(tx, ty),
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
        let base = &self.levels[0];
        if base.width != camera.width as usize || base.height != camera.height as usize {
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
}
