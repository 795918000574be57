//! Camera paths for benchmarks and the viewer: the scene's camera held still, a 360° turn in place
//! (DarkPlaces' `timerefresh` protocol: 128 frames), or a recorded file.
//!
//! A recorded path is text, one frame per line: `x y z yaw pitch` (degrees; Quake units); blank
//! lines and `#` comments are ignored.

use super::Camera;
use glam::Vec3;
use std::path::Path;
use thiserror::Error;

/// Path frames per second of scene time: a path's frame `i` shows the scene's motion at
/// `i / FRAME_RATE_HZ` seconds. Quake 3's server runs (and its demos store snapshots) at this
/// rate (`sv_fps 20`), so a minute of walking is 1200 frames.
pub const FRAME_RATE_HZ: f64 = 20.0;

/// Frames of DarkPlaces' `timerefresh`, which turns the view once around in place.
pub const TURN_FRAMES: usize = 128;
/// Most frames a recorded path may hold.
pub const MAX_PATH_FRAMES: usize = 1_000_000;

#[derive(Debug, Error)]
pub enum PathError {
    #[error("{path}: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    #[error("{path}, line {line}: expected `x y z yaw pitch` with finite numbers")]
    Syntax { path: String, line: usize },
    #[error("{path}: no frames")]
    Empty { path: String },
    #[error("{path}: more than {MAX_PATH_FRAMES} frames")]
    TooLong { path: String },
}

/// One frame's camera pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathKey {
    pub position: Vec3,
    pub yaw_deg: f32,
    pub pitch_deg: f32,
}

impl PathKey {
    pub fn of(c: &Camera) -> PathKey {
        PathKey {
            position: c.position,
            yaw_deg: c.yaw_deg,
            pitch_deg: c.pitch_deg,
        }
    }

    /// `base` moved to this pose (field of view and near plane kept).
    pub fn apply(&self, base: &Camera) -> Camera {
        Camera {
            position: self.position,
            yaw_deg: self.yaw_deg,
            pitch_deg: self.pitch_deg,
            ..*base
        }
    }
}

/// `frames` poses of the camera turning once around in place.
pub fn turn(camera: &Camera, frames: usize) -> Vec<PathKey> {
    (0..frames)
        .map(|i| PathKey {
            yaw_deg: camera.yaw_deg + 360.0 * i as f32 / frames as f32,
            ..PathKey::of(camera)
        })
        .collect()
}

/// Parses a recorded path.
pub fn parse(text: &str, name: &str) -> Result<Vec<PathKey>, PathError> {
    let mut keys = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        if keys.len() >= MAX_PATH_FRAMES {
            return Err(PathError::TooLong {
                path: name.to_string(),
            });
        }
        let v: Vec<f32> = line
            .split_whitespace()
            .map(|w| w.parse::<f32>())
            .collect::<Result<_, _>>()
            .ok()
            .filter(|v: &Vec<f32>| v.len() == 5 && v.iter().all(|x| x.is_finite()))
            .ok_or(PathError::Syntax {
                path: name.to_string(),
                line: i + 1,
            })?;
        keys.push(PathKey {
            position: Vec3::new(v[0], v[1], v[2]),
            yaw_deg: v[3],
            pitch_deg: v[4],
        });
    }
    if keys.is_empty() {
        return Err(PathError::Empty {
            path: name.to_string(),
        });
    }
    Ok(keys)
}

pub fn read(path: &Path) -> Result<Vec<PathKey>, PathError> {
    let text = std::fs::read_to_string(path).map_err(|source| PathError::Io {
        path: path.display().to_string(),
        source,
    })?;
    parse(&text, &path.display().to_string())
}

/// The text form of a path, which [`parse`] reads back.
pub fn to_text(keys: &[PathKey]) -> String {
    let mut s = String::from("# shadowlab camera path: x y z yaw pitch\n");
    for k in keys {
        s.push_str(&format!(
            "{} {} {} {} {}\n",
            k.position.x, k.position.y, k.position.z, k.yaw_deg, k.pitch_deg
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn turn_covers_the_circle_once() {
        let c = Camera {
            yaw_deg: 10.0,
            ..Camera::default()
        };
        let t = turn(&c, TURN_FRAMES);
        assert_eq!(t.len(), 128);
        assert_eq!(t[0].yaw_deg, 10.0);
        assert!((t[64].yaw_deg - 190.0).abs() < 1e-4);
        assert!(t.iter().all(|k| k.position == c.position));
    }

    #[test]
    fn text_round_trips_and_errors_name_the_line() {
        let keys = vec![
            PathKey {
                position: Vec3::new(1.5, -2.0, 3.25),
                yaw_deg: 90.0,
                pitch_deg: -10.5,
            },
            PathKey {
                position: Vec3::ZERO,
                yaw_deg: 0.0,
                pitch_deg: 0.0,
            },
        ];
        assert_eq!(parse(&to_text(&keys), "p").unwrap(), keys);
        assert!(matches!(
            parse("1 2 3 4 5\n1 2 nan 4 5\n", "p"),
            Err(PathError::Syntax { line: 2, .. })
        ));
        assert!(matches!(
            parse("# only a comment\n", "p"),
            Err(PathError::Empty { .. })
        ));
        assert!(matches!(
            parse("1 2 3 4\n", "p"),
            Err(PathError::Syntax { line: 1, .. })
        ));
    }
}
