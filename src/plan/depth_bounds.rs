//! A depth bounds test for a shadow-volume draw without `EXT_depth_bounds_test`: a few clip
//! planes under which the depth buffer lies within the draw's rectangle. A depth-pass volume
//! fragment farther than the stored depth fails the depth test and changes no count, so the
//! draw may be clipped at any surface that stays behind every stored depth there; the closer
//! that surface, the fewer fragments are rasterised only to fail.
//!
//! One constant plane (the farthest depth in the rectangle) is what `plan.depth_clip` did at
//! first. A surface seen at a slant, or a room's corner, spans a wide range of depth within one
//! rectangle; a tilted plane follows it. For a planar surface window depth is an affine function
//! of the screen position, so planes fitted to it can lie close to it everywhere, and the least
//! of several planes follows a concave depth image (the walls of a room seen from inside).
//!
//! Where the GL has `EXT_depth_bounds_test` the planner uses it instead ([`window_depth_range`]):
//! that test reads the depth already stored at the pixel, not the volume fragment's, so its
//! bound is the window-depth range of the receivers a part's shadow can reach. A pixel whose
//! stored depth lies outside shows a surface outside every such receiver: the part's closed
//! volume does not hold it, its counts there cancel, so dropping all of them changes nothing.

use super::CameraSetup;
use super::occlusion::{DEPTH_MARGIN, DepthBlock, DepthPyramid};
use super::scissor::Scissor;
use glam::{Mat4, Vec3};

/// Clip planes one draw may use (gl_ClipDistance[0..]): GL 3.3 guarantees eight.
pub const MAX_PLANES: usize = 4;

/// How many texels of the depth pyramid a rectangle is judged by along its longer side: finer
/// is tighter and costs more CPU per draw (at most about 17² blocks).
const BLOCKS_SPAN: usize = 16;

/// The smallest rectangle, in pixels, that gets fitted planes; a smaller one gets the farthest
/// depth alone. On the benchmark scenes' spawn views the fits below this size saved under 0.5%
/// of the volume fragments (oa_dm3 7.90 → 7.93 million without them) for about a tenth to a
/// third of the per-frame piece work.
const MIN_FIT_AREA: u64 = 64 * 64;

/// The smallest block side, in pixels, a rectangle is judged by: a small rectangle holds few
/// fragments to save, so it gets fewer, coarser blocks rather than up to `BLOCKS_SPAN`² fine
/// ones (the fit's cost grows with the blocks).
const MIN_BLOCK_PIXELS: usize = 4;

/// The grids (columns, rows) over the rectangle whose every cell gets a fitted plane: the
/// whole, its halves both ways, its quarters and ninths.
const GRIDS: [(usize, usize); 5] = [(1, 1), (2, 1), (1, 2), (2, 2), (3, 3)];
/// A grid every one of `GRIDS` divides evenly.
const FINE: usize = 6;

/// `d <= a·u + b·v + c` over window depth `d` at NDC position (`u`, `v`).
type Plane = [f64; 3];

/// An upper bound on the depth buffer over a rectangle: the least of some planes, each above
/// every pixel centre's stored depth there (plus a rounding margin).
#[derive(Debug, Clone, PartialEq)]
pub struct DepthBound {
    planes: Vec<Plane>,
}

/// How many blocks along its longer side `rect` is judged by.
fn blocks_span(rect: &Scissor) -> usize {
    let side = rect.width.max(rect.height).max(0) as usize;
    (side / MIN_BLOCK_PIXELS).clamp(2, BLOCKS_SPAN)
}

/// One block of pixels: its corner pixel centres and centre in NDC, its pixel count and the
/// bound on its depth.
struct Sample {
    corners: [(f64, f64); 4],
    centre: (f64, f64),
    weight: f64,
    max: f64,
}

/// The blocks that show a surface, bounded by their surface pixels' depth: a pixel still at
/// the clear (sky, a hole to the void) has no surface whose count anyone reads, so the bound
/// need not lie above it.
fn samples(blocks: &[DepthBlock], width: u32, height: u32) -> Vec<Sample> {
    let u = |px: usize| (px as f64 + 0.5) / width as f64 * 2.0 - 1.0;
    let v = |py: usize| (py as f64 + 0.5) / height as f64 * 2.0 - 1.0;
    blocks
        .iter()
        .filter_map(|b| {
            let (u0, u1, v0, v1) = (u(b.x.0), u(b.x.1), v(b.y.0), v(b.y.1));
            Some(Sample {
                corners: [(u0, v0), (u1, v0), (u0, v1), (u1, v1)],
                centre: ((u0 + u1) * 0.5, (v0 + v1) * 0.5),
                weight: ((b.x.1 - b.x.0 + 1) * (b.y.1 - b.y.0 + 1)) as f64,
                max: b.surface? as f64 + DEPTH_MARGIN as f64,
            })
        })
        .collect()
}

fn eval(p: &Plane, (u, v): (f64, f64)) -> f64 {
    p[0] * u + p[1] * v + p[2]
}

/// Weighted sums over samples for a least-squares plane: of w, w·u, w·v, w·u², w·u·v, w·v²,
/// w·d, w·u·d, w·v·d. Sums of disjoint sets add up, so the fits of a grid's cells come from
/// the sums of a finer grid's.
#[derive(Debug, Clone, Copy, Default)]
struct Moments([f64; 9]);

impl Moments {
    fn add_sample(&mut self, s: &Sample) {
        let (u, v, w, d) = (s.centre.0, s.centre.1, s.weight, s.max);
        let m = &mut self.0;
        m[0] += w;
        m[1] += w * u;
        m[2] += w * v;
        m[3] += w * u * u;
        m[4] += w * u * v;
        m[5] += w * v * v;
        m[6] += w * d;
        m[7] += w * u * d;
        m[8] += w * v * d;
    }

    fn add(&mut self, o: &Moments) {
        for (a, b) in self.0.iter_mut().zip(o.0) {
            *a += b;
        }
    }

    /// The plane of least weighted squared error; None where the centres are collinear.
    fn plane(&self) -> Option<Plane> {
        let [w, u, v, uu, uv, vv, d, ud, vd] = self.0;
        // Normal equations of [u v 1]·p = d.
        let m = [[uu, uv, u], [uv, vv, v], [u, v, w]];
        let r = [ud, vd, d];
        let det = |m: &[[f64; 3]; 3]| {
            m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
                - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
        };
        let dm = det(&m);
        // Relative to the weight cubed: the determinant's scale.
        if w <= 0.0 || dm.abs() <= 1e-12 * w.powi(3) {
            return None;
        }
        // Cramer's rule: three unknowns.
        let mut p = [0.0; 3];
        for (k, pk) in p.iter_mut().enumerate() {
            let mut mk = m;
            for i in 0..3 {
                mk[i][k] = r[i];
            }
            *pk = det(&mk) / dm;
        }
        p.iter().all(|x| x.is_finite()).then_some(p)
    }
}

/// `p` moved along depth until it lies on or above every sample's bound at each of its corner
/// pixel centres (an affine function's least over a block is at a corner), so above every
/// pixel centre.
fn raised(mut p: Plane, samples: &[Sample]) -> Plane {
    // The corner where the plane is lowest: the low end of each axis it rises along.
    let corner = (p[0] < 0.0) as usize | ((p[1] < 0.0) as usize) << 1;
    let lift = samples
        .iter()
        .map(|s| s.max - eval(&p, s.corners[corner]))
        .fold(f64::NEG_INFINITY, f64::max);
    p[2] += lift;
    p
}

impl DepthBound {
    /// The bound over `rect` from `depth` (the frame's depth after the base pass), of at most
    /// `max_planes` planes chosen greedily among the farthest depth, a plane fitted to the whole
    /// rectangle and planes fitted to its halves, quarters and ninths (each lifted above every
    /// pixel); the farthest depth alone for a rectangle under [`MIN_FIT_AREA`] pixels. None
    /// where nothing in the rectangle is nearer than the far plane (no plane would clip).
    pub fn fit(
        depth: &DepthPyramid,
        camera: &CameraSetup,
        rect: &Scissor,
        max_planes: usize,
    ) -> Option<DepthBound> {
        let samples = samples(
            &depth.blocks(rect, blocks_span(rect)),
            camera.width,
            camera.height,
        );
        let farthest = samples.iter().map(|s| s.max).fold(f64::NAN, f64::max);
        if samples.is_empty() || farthest >= 1.0 || max_planes == 0 {
            return None;
        }
        let mut candidates = vec![[0.0, 0.0, farthest]];
        if rect.area() < MIN_FIT_AREA {
            return Some(DepthBound { planes: candidates });
        }
        // Sums per cell of a FINE×FINE grid over the blocks' centres; each grid of `GRIDS`
        // divides it evenly.
        let (lo, hi) = samples.iter().fold(
            ((f64::MAX, f64::MAX), (f64::MIN, f64::MIN)),
            |(lo, hi), s| {
                (
                    (lo.0.min(s.centre.0), lo.1.min(s.centre.1)),
                    (hi.0.max(s.centre.0), hi.1.max(s.centre.1)),
                )
            },
        );
        let cell_of = |c: f64, lo: f64, hi: f64| {
            let t = if hi > lo { (c - lo) / (hi - lo) } else { 0.0 };
            ((t * FINE as f64) as usize).min(FINE - 1)
        };
        let mut fine = [[Moments::default(); FINE]; FINE];
        for s in &samples {
            let (i, j) = (
                cell_of(s.centre.0, lo.0, hi.0),
                cell_of(s.centre.1, lo.1, hi.1),
            );
            fine[j][i].add_sample(s);
        }
        for (nx, ny) in GRIDS {
            let (sx, sy) = (FINE / nx, FINE / ny);
            for j in 0..ny {
                for i in 0..nx {
                    let mut m = Moments::default();
                    for row in &fine[j * sy..(j + 1) * sy] {
                        for f in &row[i * sx..(i + 1) * sx] {
                            m.add(f);
                        }
                    }
                    if let Some(p) = m.plane() {
                        candidates.push(raised(p, &samples));
                    }
                }
            }
        }
        // Greedy: add the candidate that lowers most what the planes leave of the volume's
        // depth range (the bound at each block's centre, capped at the far plane, times its
        // pixels), while one still does.
        let heights: Vec<Vec<f64>> = candidates
            .iter()
            .map(|c| samples.iter().map(|s| eval(c, s.centre)).collect())
            .collect();
        let mut bound = vec![1.0f64; samples.len()];
        let mut planes: Vec<Plane> = Vec::new();
        while planes.len() < max_planes {
            let gain = |h: &Vec<f64>| -> f64 {
                samples
                    .iter()
                    .zip(h.iter().zip(&bound))
                    .map(|(s, (&h, &b))| (b - h).max(0.0) * s.weight)
                    .sum()
            };
            let Some((best, g)) = heights
                .iter()
                .enumerate()
                .map(|(i, h)| (i, gain(h)))
                .max_by(|a, b| a.1.total_cmp(&b.1))
            else {
                break;
            };
            if g <= 0.0 {
                break;
            }
            planes.push(candidates[best]);
            for (b, &h) in bound.iter_mut().zip(&heights[best]) {
                *b = b.min(h);
            }
        }
        (!planes.is_empty()).then_some(DepthBound { planes })
    }

    /// The bound at NDC position (`u`, `v`).
    pub fn at(&self, u: f32, v: f32) -> f32 {
        self.planes
            .iter()
            .map(|p| eval(p, (u as f64, v as f64)))
            .fold(f64::INFINITY, f64::min) as f32
    }

    /// The planes in clip space, for `gl_ClipDistance[i] = dot(plane, gl_Position)` (kept where
    /// not negative); zero (clipping nothing) past the last.
    pub fn clip_planes(&self) -> [[f32; 4]; MAX_PLANES] {
        let mut out = [[0.0; 4]; MAX_PLANES];
        for (o, p) in out.iter_mut().zip(&self.planes) {
            // d = z/w·½ + ½ <= a·x/w + b·y/w + c, times 2w (w > 0 in view).
            *o = [
                (2.0 * p[0]) as f32,
                (2.0 * p[1]) as f32,
                -1.0,
                (2.0 * p[2] - 1.0) as f32,
            ];
        }
        out
    }

    pub fn planes(&self) -> usize {
        self.planes.len()
    }
}

/// A range [zmin, zmax] of window depth for `glDepthBoundsEXT`, compared with the depth
/// stored at each pixel; `zmin > zmax` is the empty range (no stored depth lies in it).
pub type DepthRange = [f32; 2];

/// The empty range: the part can change no count that is read.
pub const EMPTY_RANGE: DepthRange = [1.0, 0.0];

/// Window depth (0 near .. 1 far) of a point at eye depth `d > 0` (distance in front of the
/// eye along the view axis) under `projection`, a perspective whose clip z and w depend on the
/// eye z alone. Increasing in `d`.
fn window_depth(projection: &Mat4, d: f64) -> f64 {
    let z = -(projection.z_axis.z as f64) * d + projection.w_axis.z as f64;
    let w = -(projection.z_axis.w as f64) * d + projection.w_axis.w as f64;
    (0.5 * z / w + 0.5).clamp(0.0, 1.0)
}

/// The window-depth range of every point in the convex hull of `points` (world space), padded
/// by the depth rounding margin: a surface point in that hull is stored at a depth within it.
/// Window depth grows with eye depth, which is affine in the position, so the hull's extremes
/// are at its points; a hull reaching the eye's plane starts at 0. [`EMPTY_RANGE`] when every
/// point is behind the eye (nothing there is seen) or there are none.
pub fn window_depth_range(
    view: &Mat4,
    projection: &Mat4,
    points: impl IntoIterator<Item = Vec3>,
) -> DepthRange {
    let (lo, hi) = points
        .into_iter()
        .map(|p| -(view.transform_point3(p).z as f64))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), d| {
            (lo.min(d), hi.max(d))
        });
    // No points (hi is -inf) or every one behind the eye.
    if hi <= 0.0 {
        return EMPTY_RANGE;
    }
    let zmin = if lo > 0.0 {
        window_depth(projection, lo)
    } else {
        0.0
    };
    let zmax = window_depth(projection, hi);
    let m = DEPTH_MARGIN as f64;
    [(zmin - m).max(0.0) as f32, (zmax + m).min(1.0) as f32]
}

/// The smallest range holding both.
pub fn range_union(a: DepthRange, b: DepthRange) -> DepthRange {
    match (a[0] <= a[1], b[0] <= b[1]) {
        (false, _) => b,
        (_, false) => a,
        _ => [a[0].min(b[0]), a[1].max(b[1])],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Camera;
    use glam::{Vec3, Vec4};

    const W: u32 = 96;
    const H: u32 = 64;

    fn camera() -> CameraSetup {
        CameraSetup::new(
            &Camera::looking_at(Vec3::ZERO, Vec3::new(100.0, 0.0, 0.0)),
            W,
            H,
        )
    }

    /// NDC of pixel (x, y)'s centre.
    fn ndc(x: usize, y: usize) -> (f32, f32) {
        (
            (x as f32 + 0.5) / W as f32 * 2.0 - 1.0,
            (y as f32 + 0.5) / H as f32 * 2.0 - 1.0,
        )
    }

    /// The pyramid of `depth(u, v)` sampled at pixel centres (rows bottom-up in `depth`'s
    /// terms, given to the pyramid top row first).
    fn pyramid(depth: impl Fn(f32, f32) -> f32) -> (DepthPyramid, Vec<f32>) {
        let mut bottom_up = Vec::new();
        for y in 0..H as usize {
            for x in 0..W as usize {
                let (u, v) = ndc(x, y);
                bottom_up.push(depth(u, v).clamp(0.0, 1.0));
            }
        }
        let top_down: Vec<f32> = bottom_up
            .chunks_exact(W as usize)
            .rev()
            .flatten()
            .copied()
            .collect();
        let p = DepthPyramid::from_top_down(&top_down, W as usize, H as usize).unwrap();
        (p, bottom_up)
    }

    fn rect(x: i32, y: i32, width: i32, height: i32) -> Scissor {
        Scissor {
            x,
            y,
            width,
            height,
        }
    }

    /// Over the rectangle's pixels that show a surface (nearer than the far plane): the least
    /// of bound − depth, and the mean of it.
    fn gaps(b: &DepthBound, depth: &[f32], r: &Scissor) -> (f32, f32) {
        let (mut least, mut sum, mut n) = (f32::MAX, 0.0, 0);
        for y in r.y.max(0)..(r.y + r.height).min(H as i32) {
            for x in r.x.max(0)..(r.x + r.width).min(W as i32) {
                let d = depth[y as usize * W as usize + x as usize];
                if d >= 1.0 {
                    continue;
                }
                let (u, v) = ndc(x as usize, y as usize);
                let gap = b.at(u, v) - d;
                least = least.min(gap);
                sum += gap;
                n += 1;
            }
        }
        (least, sum / n as f32)
    }

    #[test]
    fn window_depth_ranges_match_hand_computed_depths() {
        // The infinite projection with near plane n: window depth 1 - n/d at eye depth d.
        let cam = camera();
        let n = Camera::looking_at(Vec3::ZERO, Vec3::X).near;
        // Eye at the origin looking down +x: eye depth is x.
        let (view, proj) = (&cam.view, &cam.projection);
        let m = DEPTH_MARGIN;
        let r = window_depth_range(
            view,
            proj,
            [Vec3::new(8.0 * n, 1.0, 0.0), Vec3::new(2.0 * n, -3.0, 2.0)],
        );
        // d = 2n: 1 - 1/2; d = 8n: 1 - 1/8.
        assert!((r[0] - (0.5 - m)).abs() < 1e-6, "{r:?}");
        assert!((r[1] - (0.875 + m)).abs() < 1e-6, "{r:?}");
        // A box around the eye starts at the near end; one behind it is empty.
        let around = window_depth_range(
            view,
            proj,
            [Vec3::new(-1.0, 0.0, 0.0), Vec3::new(4.0 * n, 0.0, 0.0)],
        );
        assert_eq!(around[0], 0.0);
        assert!((around[1] - (0.75 + m)).abs() < 1e-6, "{around:?}");
        let behind = window_depth_range(view, proj, [Vec3::new(-5.0, 1.0, 1.0)]);
        assert_eq!(behind, EMPTY_RANGE);
        assert_eq!(window_depth_range(view, proj, []), EMPTY_RANGE);
        // Unions: empty ranges drop out.
        assert_eq!(range_union(EMPTY_RANGE, [0.2, 0.3]), [0.2, 0.3]);
        assert_eq!(range_union([0.5, 0.6], [0.2, 0.3]), [0.2, 0.6]);
    }

    #[test]
    fn every_point_of_a_box_lies_within_its_range() {
        // Against the projection itself: points of the box taken to window depth.
        let cam = camera();
        let mut seed = 3u32;
        let mut next = move || {
            seed = seed.wrapping_mul(1664525).wrapping_add(1013904223);
            (seed >> 8) as f32 / (1u32 << 24) as f32
        };
        for _ in 0..50 {
            let c = Vec3::new(
                next() * 300.0 - 20.0,
                next() * 100.0 - 50.0,
                next() * 100.0 - 50.0,
            );
            let half = Vec3::new(next(), next(), next()) * 40.0;
            let b = crate::geometry::Aabb {
                min: c - half,
                max: c + half,
            };
            let r = window_depth_range(&cam.view, &cam.projection, b.corners());
            for _ in 0..40 {
                let t = Vec3::new(next(), next(), next());
                let p = b.min + (b.max - b.min) * t;
                let clip = cam.view_proj * p.extend(1.0);
                if clip.w <= 0.0 || clip.z < -clip.w {
                    continue; // behind the eye or nearer than the near plane: never stored
                }
                let d = 0.5 * clip.z / clip.w + 0.5;
                assert!(d >= r[0] && d <= r[1], "{d} outside {r:?} for {p} in {b:?}");
            }
        }
    }

    #[test]
    fn the_bound_lies_above_every_pixel_of_rough_depth_images() {
        let mut seed = 7u32;
        let mut next = move || {
            seed = seed.wrapping_mul(1664525).wrapping_add(1013904223);
            (seed >> 8) as f32 / (1u32 << 24) as f32
        };
        let mut checked = 0;
        for _ in 0..60 {
            // Slanted walls, a pillar in front, a noisy floor and a hole to the far plane.
            let (a, b, c) = (next() - 0.5, next() - 0.5, 0.3 + 0.5 * next());
            let (px, noise) = (next() * 2.0 - 1.0, 0.05 * next());
            let depth = |u: f32, v: f32| {
                let wall = c + 0.2 * a * u + 0.2 * b * v - 0.1 * (u - px).abs();
                let pillar = if (u - px).abs() < 0.1 { 0.2 } else { 1.0 };
                let grain = noise * ((u * 37.0).sin() * (v * 23.0).cos());
                let hole = if u > 0.8 && v > 0.7 {
                    1.0
                } else {
                    wall + grain
                };
                hole.min(pillar)
            };
            let (p, d) = pyramid(depth);
            let x = (next() * W as f32) as i32 - 8;
            let y = (next() * H as f32) as i32 - 8;
            let r = rect(x, y, 1 + (next() * 80.0) as i32, 1 + (next() * 60.0) as i32);
            for planes in 1..=MAX_PLANES {
                let Some(bound) = DepthBound::fit(&p, &camera(), &r, planes) else {
                    continue;
                };
                assert!(bound.planes() <= planes);
                let (least, _) = gaps(&bound, &d, &r);
                // The rounding margin stays (less f32 rounding of the evaluation).
                assert!(
                    least >= DEPTH_MARGIN * 0.5,
                    "{least} in {r:?}, {planes} planes"
                );
                checked += 1;
            }
        }
        assert!(checked > 150, "{checked}");
    }

    #[test]
    fn tilted_planes_follow_a_slanted_wall_and_a_room_corner() {
        let cam = camera();
        let all = rect(0, 0, W as i32, H as i32);
        // A wall seen at a slant: depth affine across the screen.
        let (p, d) = pyramid(|u, v| 0.6 + 0.25 * u + 0.05 * v);
        // The farthest depth alone (what one constant plane leaves).
        let flat = |p: &DepthPyramid| DepthBound {
            planes: vec![[0.0, 0.0, p.farthest(&all).unwrap() as f64]],
        };
        let tilted = DepthBound::fit(&p, &cam, &all, 1).unwrap();
        let (_, flat_gap) = gaps(&flat(&p), &d, &all);
        let (least, tilted_gap) = gaps(&tilted, &d, &all);
        assert!(flat_gap > 0.2, "{flat_gap}");
        // Judged by blocks of 8×8 pixels (their largest depth): above the wall by about the
        // depth a block spans.
        assert!(
            least >= 0.0 && tilted_gap < flat_gap / 4.0,
            "{tilted_gap} vs {flat_gap}"
        );
        // A room's corner: two walls meeting farthest at u = 0.2 (a concave depth image).
        let (p, d) = pyramid(|u, _| 0.9 - 0.3 * (u - 0.2).abs());
        let corner = DepthBound::fit(&p, &cam, &all, MAX_PLANES).unwrap();
        let one = DepthBound::fit(&p, &cam, &all, 1).unwrap();
        let (least, corner_gap) = gaps(&corner, &d, &all);
        let (_, one_gap) = gaps(&one, &d, &all);
        let (_, flat_gap) = gaps(&flat(&p), &d, &all);
        assert!(least >= 0.0 && corner.planes() >= 2);
        assert!(corner_gap < one_gap / 2.0, "{corner_gap} vs {one_gap}");
        assert!(corner_gap < flat_gap / 3.0, "{corner_gap} vs {flat_gap}");
        // A rectangle under MIN_FIT_AREA gets the farthest depth alone.
        let small = DepthBound::fit(&p, &cam, &rect(10, 10, 40, 40), MAX_PLANES).unwrap();
        assert_eq!(small.planes(), 1);
        // Nothing nearer than the far plane: nothing to clip.
        let (p, _) = pyramid(|_, _| 1.0);
        assert_eq!(DepthBound::fit(&p, &cam, &all, MAX_PLANES), None);
    }

    #[test]
    fn pixels_at_the_far_plane_leave_the_bound_free_there() {
        let cam = camera();
        let all = rect(0, 0, W as i32, H as i32);
        // A slanted wall below a horizon, sky (the clear, 1.0) above it.
        let wall = |u: f32, v: f32| if v < 0.2 { 0.5 + 0.2 * u } else { 1.0 };
        let (p, d) = pyramid(wall);
        let bound = DepthBound::fit(&p, &cam, &all, MAX_PLANES).unwrap();
        let (least, mean) = gaps(&bound, &d, &all);
        // Above every wall pixel, and close to it (the wall spans 0.3..0.7).
        assert!(least >= DEPTH_MARGIN * 0.5, "{least}");
        assert!(mean < 0.05, "{mean}");
        // Over the sky the bound is free: here it stays below the far plane.
        let (u, v) = ndc(W as usize / 2, H as usize - 1);
        assert!(bound.at(u, v) < 0.9, "{}", bound.at(u, v));
        // A rectangle wholly in the sky gets no bound.
        let sky = rect(0, H as i32 - 10, W as i32, 10);
        assert_eq!(DepthBound::fit(&p, &cam, &sky, MAX_PLANES), None);
    }

    #[test]
    fn clip_distances_keep_exactly_the_points_under_the_bound() {
        let cam = camera();
        let (p, _) = pyramid(|u, v| 0.7 + 0.2 * u - 0.1 * v * v);
        let bound = DepthBound::fit(&p, &cam, &rect(8, 4, 80, 56), MAX_PLANES).unwrap();
        assert!(bound.planes() >= 2, "{}", bound.planes());
        let planes = bound.clip_planes();
        assert!(planes[bound.planes()..].iter().all(|q| *q == [0.0; 4]));
        let mut kept = 0;
        for i in 0..400 {
            let (u, v) = ndc((i * 7) % W as usize, (i * 13) % H as usize);
            let depth = (i as f32 * 0.618).fract();
            // Any w > 0 gives the same point.
            let w = 1.0 + (i % 5) as f32 * 30.0;
            let clip = Vec4::new(u * w, v * w, (2.0 * depth - 1.0) * w, w);
            let inside = planes.iter().all(|q| Vec4::from_array(*q).dot(clip) >= 0.0);
            let under = depth <= bound.at(u, v);
            // Points within rounding of the bound may go either way.
            if (depth - bound.at(u, v)).abs() > 1e-5 {
                assert_eq!(inside, under, "u {u} v {v} depth {depth}");
            }
            kept += inside as usize;
        }
        assert!(kept > 50 && kept < 350, "{kept}");
    }
}
