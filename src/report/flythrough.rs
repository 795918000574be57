//! Recorded flythroughs: a camera that walks through a map like a player (on the floor, at eye
//! height, at running speed), turning away from walls and looking around as it goes, for the
//! benchmark paths of `assets/paths/`. GL-free: it feels its way with the exact reference's
//! rays and keeps inside the map's BSP leaves. Deterministic: a seed gives one path.

use crate::scene::path::{FRAME_RATE_HZ, PathKey};
use crate::scene::{Camera, Scene};
use crate::truth::Reference;
use glam::{DVec3, Vec3};

/// How the walker walks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WalkSettings {
    /// Length of the path in seconds (frames at [`FRAME_RATE_HZ`]).
    pub seconds: f64,
    /// Units per second (Quake 3 runs at 320; 250 is a brisk walk through a map).
    pub speed: f32,
    /// Eye height above the floor (Quake 3: 24 to the origin, 26 more to the eye).
    pub eye_height: f32,
    /// Most turn of the walking direction per second, in degrees.
    pub turn_rate: f32,
    /// How far ahead a wall makes it turn.
    pub lookahead: f32,
    pub seed: u64,
}

impl Default for WalkSettings {
    fn default() -> Self {
        WalkSettings {
            seconds: 60.0,
            speed: 250.0,
            eye_height: 50.0,
            turn_rate: 150.0,
            lookahead: 160.0,
            seed: 1,
        }
    }
}

/// Why no flythrough could be made.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum FlythroughError {
    #[error("no floor within 512 units below the start at {0:?}")]
    NoFloor(Vec3),
    #[error("the walk got stuck at {0:?}: no direction is open")]
    Stuck(Vec3),
}

/// The reference's answer to "how far can one see from `from` along `dir`" (up to `max`).
fn clearance(reference: &Reference, from: Vec3, dir: Vec3, max: f32) -> f32 {
    reference
        .nearest_hit(from.as_dvec3(), dir.as_dvec3().normalize(), f64::from(max))
        .map_or(max, |b| b.distance as f32)
}

/// The floor's height under `p`, within 512 units.
fn floor_under(reference: &Reference, p: Vec3) -> Option<f32> {
    reference
        .nearest_hit(p.as_dvec3(), DVec3::NEG_Z, 512.0)
        .map(|b| p.z - b.distance as f32)
}

fn heading(yaw_deg: f32) -> Vec3 {
    let y = yaw_deg.to_radians();
    Vec3::new(y.cos(), y.sin(), 0.0)
}

/// Whether `p` is inside the map (in a BSP leaf with a cluster; always for scenes without one).
fn inside(scene: &Scene, p: Vec3) -> bool {
    scene.world.as_ref().is_none_or(|w| w.cluster_at(p) >= 0)
}

/// A walk from `start` through `scene`: one pose per frame.
pub fn walk(
    scene: &Scene,
    reference: &Reference,
    start: &Camera,
    settings: &WalkSettings,
) -> Result<Vec<PathKey>, FlythroughError> {
    let frames = (settings.seconds * FRAME_RATE_HZ).round().max(1.0) as usize;
    let dt = (1.0 / FRAME_RATE_HZ) as f32;
    let mut rng = fastrand::Rng::with_seed(settings.seed);
    let mut floor =
        floor_under(reference, start.position).ok_or(FlythroughError::NoFloor(start.position))?;
    let mut feet = Vec3::new(start.position.x, start.position.y, floor);
    let mut eye_z = start.position.z;
    let mut walking = start.yaw_deg;
    // The wandering the walker wants besides avoiding walls, degrees per second.
    let mut wander = 0.0f32;
    let mut stuck = 0;
    let mut keys = Vec::with_capacity(frames);
    for i in 0..frames {
        let t = i as f32 * dt;
        // Look around while walking: the view swings about the walking direction.
        let look = 25.0 * (t * 0.9).sin() + 10.0 * (t * 2.3).sin();
        let pitch = -4.0 + 6.0 * (t * 0.7).sin();
        keys.push(PathKey {
            position: Vec3::new(feet.x, feet.y, eye_z),
            yaw_deg: (walking + look).rem_euclid(360.0),
            pitch_deg: pitch,
        });

        // Steer: the open direction nearest to where it wanders, at chest height.
        wander = (wander + (rng.f32() - 0.5) * 40.0).clamp(-60.0, 60.0);
        let chest = feet + Vec3::Z * 40.0;
        let wanted = walking + wander * dt;
        let mut best: Option<(f32, f32)> = None;
        for k in 0u32..24 {
            let off = if k % 2 == 0 { 1.0 } else { -1.0 } * 15.0 * k.div_ceil(2) as f32;
            let yaw = wanted + off;
            let open = clearance(reference, chest, heading(yaw), settings.lookahead);
            if open >= settings.lookahead * 0.99 {
                best = Some((yaw, open));
                break;
            }
            if best.is_none_or(|(_, o)| open > o) {
                best = Some((yaw, open));
            }
        }
        let (target, _) = best.unwrap_or((walking + 180.0, 0.0));
        let diff = (target - walking + 180.0).rem_euclid(360.0) - 180.0;
        let most = settings.turn_rate * dt;
        walking += diff.clamp(-most, most);

        // Step, if the way is open, there is a floor not far below and it stays in the map.
        let dir = heading(walking);
        let step = settings.speed * dt;
        let knee = feet + Vec3::Z * 28.0;
        let next = feet + dir * step;
        let next_floor = floor_under(reference, next + Vec3::Z * 48.0);
        let ok = clearance(reference, knee, dir, step + 16.0) > step + 15.0
            && next_floor.is_some_and(|f| f > floor - 96.0)
            && inside(scene, next + Vec3::Z * settings.eye_height);
        match (ok, next_floor) {
            (true, Some(f)) => {
                feet = Vec3::new(next.x, next.y, f);
                floor = f;
                stuck = 0;
            }
            _ => {
                // Blocked: turn away harder, and give up after a long while stuck.
                walking += if rng.bool() { 45.0 } else { -45.0 };
                stuck += 1;
                if stuck > 200 {
                    return Err(FlythroughError::Stuck(feet));
                }
            }
        }
        // The eye follows steps and stairs smoothly.
        eye_z += (floor + settings.eye_height - eye_z) * 0.5;
    }
    Ok(keys)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;

    #[test]
    fn walks_the_builtin_room_on_its_floor_without_leaving_it() {
        let scene = builtin::default_scene();
        let reference = Reference::build(&scene);
        let bounds = scene.bounds();
        let start = Camera {
            position: Vec3::new(bounds.center().x, bounds.center().y, bounds.min.z + 50.0),
            ..scene.camera
        };
        let settings = WalkSettings {
            seconds: 10.0,
            speed: 100.0,
            ..WalkSettings::default()
        };
        let keys = walk(&scene, &reference, &start, &settings).unwrap();
        assert_eq!(keys.len(), 200);
        let moved: f32 = keys
            .windows(2)
            .map(|w| w[0].position.distance(w[1].position))
            .sum();
        assert!(moved > 300.0, "it walks ({moved} units)");
        for k in &keys {
            let p = k.position;
            assert!(
                p.cmpge(bounds.min).all() && p.cmple(bounds.max).all(),
                "{p:?} is outside the room"
            );
        }
        // The same seed walks the same path.
        assert_eq!(walk(&scene, &reference, &start, &settings).unwrap(), keys);
    }
}
