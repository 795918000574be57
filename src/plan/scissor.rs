//! A light's screen rectangle: where its range can land on screen, for glScissor around its
//! stencil and lit passes.

use super::CameraSetup;
use super::cull::range_box;
use glam::Vec3;
use serde::Serialize;

/// A pixel rectangle in GL window coordinates (origin bottom left).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Scissor {
    pub x: i32,
    pub y: i32,
    pub width: i32,
    pub height: i32,
}

impl Scissor {
    pub fn area(&self) -> u64 {
        self.width.max(0) as u64 * self.height.max(0) as u64
    }

    pub fn full(camera: &CameraSetup) -> Scissor {
        Scissor {
            x: 0,
            y: 0,
            width: camera.width as i32,
            height: camera.height as i32,
        }
    }
}

/// The rectangle holding the projection of the ball (`center`, `radius`), one pixel wider on
/// each side; the whole screen when the ball reaches the camera's near plane (its projection is
/// then unbounded); None when it is wholly off screen.
pub fn sphere_scissor(camera: &CameraSetup, center: Vec3, radius: f32) -> Option<Scissor> {
    points_scissor(camera, &range_box(center, radius).corners())
}

/// Where a set of points lands on the camera's screen.
pub enum Projection {
    /// A point lies behind or on the near plane: the hull's projection wraps around.
    Unbounded,
    /// Bounds of the points in normalised device coordinates, and the nearest window depth.
    Bounded {
        lo: glam::Vec2,
        hi: glam::Vec2,
        nearest: f32,
    },
}

/// The NDC bounds and nearest depth of `points` as the camera sees them.
pub fn project(camera: &CameraSetup, points: &[Vec3]) -> Projection {
    let mut lo = glam::Vec2::splat(f32::MAX);
    let mut hi = glam::Vec2::splat(f32::MIN);
    let mut nearest = f32::MAX;
    for c in points {
        let clip = camera.view_proj * c.extend(1.0);
        if clip.w <= 1e-4 || clip.z < -clip.w {
            return Projection::Unbounded;
        }
        let ndc = clip.truncate() / clip.w;
        lo = lo.min(ndc.truncate());
        hi = hi.max(ndc.truncate());
        nearest = nearest.min(ndc.z * 0.5 + 0.5);
    }
    Projection::Bounded { lo, hi, nearest }
}

/// The rectangle holding the projection of the convex hull of `points` (see
/// [`sphere_scissor`]).
pub fn points_scissor(camera: &CameraSetup, points: &[Vec3]) -> Option<Scissor> {
    let full = Scissor::full(camera);
    let Projection::Bounded { lo, hi, .. } = project(camera, points) else {
        return Some(full);
    };
    if hi.x < -1.0 || hi.y < -1.0 || lo.x > 1.0 || lo.y > 1.0 {
        return None;
    }
    let (w, h) = (camera.width as f32, camera.height as f32);
    let x0 = (((lo.x.max(-1.0) * 0.5 + 0.5) * w).floor() as i32 - 1).max(0);
    let y0 = (((lo.y.max(-1.0) * 0.5 + 0.5) * h).floor() as i32 - 1).max(0);
    let x1 = (((hi.x.min(1.0) * 0.5 + 0.5) * w).ceil() as i32 + 1).min(full.width);
    let y1 = (((hi.y.min(1.0) * 0.5 + 0.5) * h).ceil() as i32 + 1).min(full.height);
    Some(Scissor {
        x: x0,
        y: y0,
        width: (x1 - x0).max(0),
        height: (y1 - y0).max(0),
    })
}

impl Scissor {
    pub const EMPTY: Scissor = Scissor {
        x: 0,
        y: 0,
        width: 0,
        height: 0,
    };

    /// The smallest rectangle holding both.
    pub fn union(&self, o: &Scissor) -> Scissor {
        let x0 = self.x.min(o.x);
        let y0 = self.y.min(o.y);
        let x1 = (self.x + self.width).max(o.x + o.width);
        let y1 = (self.y + self.height).max(o.y + o.height);
        Scissor {
            x: x0,
            y: y0,
            width: x1 - x0,
            height: y1 - y0,
        }
    }

    /// The overlap of two rectangles (possibly empty).
    pub fn intersect(&self, o: &Scissor) -> Scissor {
        let x0 = self.x.max(o.x);
        let y0 = self.y.max(o.y);
        let x1 = (self.x + self.width).min(o.x + o.width);
        let y1 = (self.y + self.height).min(o.y + o.height);
        Scissor {
            x: x0,
            y: y0,
            width: (x1 - x0).max(0),
            height: (y1 - y0).max(0),
        }
    }
}

/// The part of the screen an omni light's cube face `f` can light within `radius`: its pyramid
/// within the ball lies in the hull of the light and the face's square at distance `radius`.
pub fn face_scissor(camera: &CameraSetup, light: Vec3, radius: f32, f: usize) -> Option<Scissor> {
    let (a, u, v) = super::cull::face_axes(f);
    let mut points = vec![light];
    for (su, sv) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
        points.push(light + radius * (a + su * u + sv * v));
    }
    points_scissor(camera, &points)
}

/// The part of the screen one of several frusta of an omni light can light within `radius`
/// (`shadow_map.omni = frusta`): `cell` of the image plane of the face whose view (world to
/// eye) is `face_view`. As for a whole face, the cell's pyramid within the ball lies in the hull
/// of the light and the cell's rectangle at distance `radius` along the face's axis.
pub fn cell_scissor(
    camera: &CameraSetup,
    light: Vec3,
    radius: f32,
    face_view: &glam::Mat4,
    cell: &crate::shadow::views::Rect,
) -> Option<Scissor> {
    let to_world = face_view.inverse();
    let mut points = vec![light];
    for (x, y) in [
        (cell.min.x, cell.min.y),
        (cell.min.x, cell.max.y),
        (cell.max.x, cell.min.y),
        (cell.max.x, cell.max.y),
    ] {
        points.push(to_world.transform_point3(Vec3::new(x, y, -1.0) * radius));
    }
    points_scissor(camera, &points)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Camera;

    /// Every point of a cell's pyramid within the ball projects inside the cell's rectangle,
    /// which is smaller than the whole face's.
    #[test]
    fn a_cell_gets_a_rectangle_holding_its_part_of_the_face() {
        use crate::geometry::projection::cube_face_view;
        use crate::shadow::views::Rect;
        let c = camera();
        let light = Vec3::new(300.0, 40.0, -20.0);
        let radius = 250.0;
        let f = 1; // -X: toward the camera
        let view = cube_face_view(light, f);
        let cell = Rect {
            min: glam::Vec2::new(-0.5, 0.0),
            max: glam::Vec2::new(0.0, 0.5),
        };
        let s = cell_scissor(&c, light, radius, &view, &cell).unwrap();
        let face = face_scissor(&c, light, radius, f).unwrap();
        assert!(s.area() < face.area() / 2, "{s:?} {face:?}");
        let to_world = view.inverse();
        for i in 0..400 {
            let t = i as f32;
            let (x, y) = (
                cell.min.x + (cell.max.x - cell.min.x) * (t * 0.37).fract(),
                cell.min.y + (cell.max.y - cell.min.y) * (t * 0.61).fract(),
            );
            let dir = to_world
                .transform_vector3(Vec3::new(x, y, -1.0))
                .normalize();
            let p = light + dir * radius * (t * 0.13).fract();
            let clip = c.view_proj * p.extend(1.0);
            if clip.w <= 0.0 {
                continue;
            }
            let px = (clip.x / clip.w * 0.5 + 0.5) * 640.0;
            let py = (clip.y / clip.w * 0.5 + 0.5) * 480.0;
            if !(0.0..640.0).contains(&px) || !(0.0..480.0).contains(&py) {
                continue;
            }
            assert!(
                px >= s.x as f32 - 1.0 && px <= (s.x + s.width) as f32 + 1.0,
                "{px} {s:?}"
            );
            assert!(
                py >= s.y as f32 - 1.0 && py <= (s.y + s.height) as f32 + 1.0,
                "{py} {s:?}"
            );
        }
    }

    fn camera() -> CameraSetup {
        CameraSetup::new(
            &Camera::looking_at(Vec3::ZERO, Vec3::new(100.0, 0.0, 0.0)),
            640,
            480,
        )
    }

    #[test]
    fn a_ball_ahead_gets_a_rectangle_holding_its_projection() {
        let c = camera();
        let center = Vec3::new(200.0, 0.0, 0.0);
        let s = sphere_scissor(&c, center, 20.0).unwrap();
        assert!(s.area() > 0 && s.area() < 640 * 480 / 4, "{s:?}");
        // Every point of the ball's surface projects inside.
        for i in 0..200 {
            let a = i as f32 * 0.7;
            let b = i as f32 * 1.3;
            let p = center + 20.0 * Vec3::new(a.cos() * b.sin(), a.sin() * b.sin(), b.cos());
            let clip = c.view_proj * p.extend(1.0);
            let x = (clip.x / clip.w * 0.5 + 0.5) * 640.0;
            let y = (clip.y / clip.w * 0.5 + 0.5) * 480.0;
            assert!(x >= s.x as f32 && x <= (s.x + s.width) as f32, "{x} {s:?}");
            assert!(y >= s.y as f32 && y <= (s.y + s.height) as f32, "{y} {s:?}");
        }
    }

    #[test]
    fn balls_around_the_camera_take_the_screen_and_balls_behind_none() {
        let c = camera();
        assert_eq!(
            sphere_scissor(&c, Vec3::new(5.0, 0.0, 0.0), 50.0),
            Some(Scissor::full(&c))
        );
        // Behind the camera the projection is not bounded: the whole screen (the frustum test,
        // which runs first, culls such lights).
        assert_eq!(
            sphere_scissor(&c, Vec3::new(-500.0, 0.0, 0.0), 50.0),
            Some(Scissor::full(&c))
        );
        assert_eq!(sphere_scissor(&c, Vec3::new(100.0, 900.0, 0.0), 50.0), None);
    }
}
