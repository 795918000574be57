//! What moves in a scene, and the scene posed at a time `t` (seconds): keyframed models (Quake 3
//! players: legs, torso and head hung on each other's tags), models walking a path, and lights
//! that orbit, follow a path or flicker. GL-free; loaders fill it, `bench`, the viewer and the
//! tests pose the scene with [`Motion::pose`] before each frame.
//!
//! Posing writes the moved vertices into the scene, gives each moved model a new
//! [`ModelInstance::pose`](super::ModelInstance) and keeps its surfaces' bounds: the caches
//! downstream (caster groups, shadow maps, volume parts, the GPU's vertices) redo what a model or
//! light touches and keep the rest.

use super::{LightKind, Scene};
use glam::{Mat4, Vec3};
use std::sync::Arc;

/// Which frames of a keyframed part play, Quake 3's way (`animation.cfg`): `frames` frames from
/// `first` at `fps`; after the last, the final `looping` frames repeat (none: it holds the last).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Clip {
    pub first: u32,
    pub frames: u32,
    pub looping: u32,
    pub fps: f32,
    /// Played from the last frame to the first (a negative count in `animation.cfg`).
    pub reversed: bool,
}

/// Two neighbouring key frames and how far the pose is from the first to the second (0..1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KeyPair {
    pub from: usize,
    pub to: usize,
    pub fraction: f32,
}

impl Clip {
    /// One frame held still.
    pub fn still(frame: u32) -> Clip {
        Clip {
            first: frame,
            frames: 1,
            looping: 0,
            fps: 1.0,
            reversed: false,
        }
    }

    /// The clip's n-th frame played (counting on past the end), as a model frame.
    fn frame(&self, n: u64) -> usize {
        let frames = u64::from(self.frames.max(1));
        let looping = u64::from(self.looping.min(self.frames));
        let k = if n < frames {
            n
        } else if looping > 0 {
            frames - looping + (n - frames) % looping
        } else {
            frames - 1
        };
        let k = if self.reversed { frames - 1 - k } else { k };
        self.first as usize + k as usize
    }

    /// The key frames around time `t` (seconds from the clip's start; negative counts as 0).
    pub fn at(&self, t: f64) -> KeyPair {
        let mut played = (t.max(0.0) * f64::from(self.fps.max(0.0))).min(1e15);
        // A time that is a key frame's up to rounding (n / fps * fps) is that key frame.
        if (played - played.round()).abs() < 1e-9 {
            played = played.round();
        }
        let n = played.floor() as u64;
        let fraction = (played - played.floor()) as f32;
        let (from, to) = (self.frame(n), self.frame(n + 1));
        KeyPair {
            from,
            // A held last frame interpolates with itself.
            to,
            fraction: if from == to { 0.0 } else { fraction },
        }
    }
}

/// `a` and `b` mixed: exactly `a` at 0 and exactly `b` at 1, which the tests rely on.
pub fn lerp(a: Vec3, b: Vec3, f: f32) -> Vec3 {
    if f == 0.0 {
        a
    } else if f == 1.0 {
        b
    } else {
        a * (1.0 - f) + b * f
    }
}

/// An attachment point of one key frame: an origin and three axes (MD3 tags).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TagKey {
    pub origin: Vec3,
    pub axis: [Vec3; 3],
}

impl TagKey {
    /// The tag as a transform from the attached part's space into its parent's.
    pub fn matrix(&self) -> Mat4 {
        Mat4::from_cols(
            self.axis[0].extend(0.0),
            self.axis[1].extend(0.0),
            self.axis[2].extend(0.0),
            self.origin.extend(1.0),
        )
    }

    /// Between two keys: origins and axes mixed, the axes made unit again between key frames
    /// (Quake 3's `R_LerpTag`); at a key frame, that key as stored.
    pub fn between(a: &TagKey, b: &TagKey, f: f32) -> TagKey {
        if f == 0.0 || f == 1.0 {
            return if f == 0.0 { *a } else { *b };
        }
        TagKey {
            origin: lerp(a.origin, b.origin, f),
            axis: [0, 1, 2].map(|k| lerp(a.axis[k], b.axis[k], f).normalize_or(a.axis[k])),
        }
    }
}

/// One mesh of a keyframed part: where its vertices sit in the scene and every key frame's
/// positions and normals (frame-major, `verts` per frame), in the part's own space.
#[derive(Debug, Clone, PartialEq)]
pub struct KeyedMesh {
    /// The mesh's name in its model (MD3 surface names: `h_head`, `l_legs`, …).
    pub name: String,
    pub first_vertex: usize,
    pub verts: usize,
    pub positions: Arc<[Vec3]>,
    pub normals: Arc<[Vec3]>,
}

impl KeyedMesh {
    pub fn frames(&self) -> usize {
        self.positions.len() / self.verts.max(1)
    }
}

/// One part of a rig: its meshes, the tags others hang on (per tag, one key per frame), the
/// clip it plays and the parent tag it hangs on.
#[derive(Debug, Clone, PartialEq)]
pub struct RigPart {
    pub name: String,
    pub meshes: Vec<KeyedMesh>,
    pub tags: Vec<(String, Vec<TagKey>)>,
    pub clip: Clip,
    /// (parent part, the parent's tag index); None: at the model's origin.
    pub parent: Option<(usize, usize)>,
}

/// A keyframed model: parts, each after its parent (Quake 3 players: lower, upper, head).
#[derive(Debug, Clone, PartialEq)]
pub struct Rig {
    pub model: usize,
    pub parts: Vec<RigPart>,
}

/// One part posed: its transform into model space and its key frames.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PartPose {
    pub transform: Mat4,
    pub keys: KeyPair,
}

impl Rig {
    /// How far from the model's origin any vertex of any key frame can be: each part's
    /// farthest vertex beyond the farthest origins of the tags it hangs on (tags turn, they
    /// do not stretch).
    pub fn radius(&self) -> f32 {
        let mut offsets: Vec<f32> = Vec::with_capacity(self.parts.len());
        let mut radius = 0.0f32;
        for part in &self.parts {
            let offset = match part.parent {
                Some((p, tag)) if p < offsets.len() => {
                    let farthest = self.parts[p].tags.get(tag).map_or(0.0, |(_, keys)| {
                        keys.iter().map(|k| k.origin.length()).fold(0.0, f32::max)
                    });
                    offsets[p] + farthest
                }
                _ => 0.0,
            };
            offsets.push(offset);
            let farthest = part
                .meshes
                .iter()
                .flat_map(|m| m.positions.iter())
                .map(|p| p.length())
                .fold(0.0f32, f32::max);
            radius = radius.max(offset + farthest);
        }
        radius
    }

    /// Every part's transform and key frames at time `t`: a child's transform is its parent's
    /// times the parent's tag, mixed between the parent's key frames.
    pub fn part_poses(&self, t: f64) -> Vec<PartPose> {
        let mut poses: Vec<PartPose> = Vec::with_capacity(self.parts.len());
        for part in &self.parts {
            let keys = part.clip.at(t);
            let transform = match part.parent {
                Some((p, tag)) if p < poses.len() => {
                    let parent = poses[p];
                    let keys_of_tag = self.parts[p].tags.get(tag).map(|(_, k)| k);
                    let tag = keys_of_tag.and_then(|k| {
                        Some(TagKey::between(
                            k.get(parent.keys.from)?,
                            k.get(parent.keys.to)?,
                            parent.keys.fraction,
                        ))
                    });
                    parent.transform * tag.map_or(Mat4::IDENTITY, |t| t.matrix())
                }
                _ => Mat4::IDENTITY,
            };
            poses.push(PartPose { transform, keys });
        }
        poses
    }

    /// Writes the rig's vertices at time `t` into `scene` (model space); returns whether any
    /// changed. Frames a mesh lacks are clamped to its last, so a short part never reads past
    /// its keys.
    fn pose_vertices(&self, scene: &mut Scene, t: f64) -> bool {
        let mut changed = false;
        for (part, pose) in self.parts.iter().zip(self.part_poses(t)) {
            let linear = glam::Mat3::from_mat4(pose.transform);
            let det = linear.determinant();
            let normal_matrix = if det != 0.0 && det.is_finite() {
                linear.inverse().transpose()
            } else {
                glam::Mat3::ZERO
            };
            for mesh in &part.meshes {
                let last = mesh.frames().saturating_sub(1);
                let (a, b) = (pose.keys.from.min(last), pose.keys.to.min(last));
                let n = mesh.verts;
                let end = (mesh.first_vertex + n).min(scene.vertices.len());
                let f = pose.keys.fraction;
                for (k, v) in scene.vertices[mesh.first_vertex..end]
                    .iter_mut()
                    .enumerate()
                {
                    let (Some(&pa), Some(&pb)) =
                        (mesh.positions.get(a * n + k), mesh.positions.get(b * n + k))
                    else {
                        continue;
                    };
                    let (na, nb) = (mesh.normals[a * n + k], mesh.normals[b * n + k]);
                    let normal = if f == 0.0 || f == 1.0 {
                        lerp(na, nb, f)
                    } else {
                        lerp(na, nb, f).normalize_or(na)
                    };
                    let position = pose.transform.transform_point3(lerp(pa, pb, f)).to_array();
                    let normal = (normal_matrix * normal).normalize_or_zero().to_array();
                    changed |= v.position != position || v.normal != normal;
                    v.position = position;
                    v.normal = normal;
                }
            }
        }
        changed
    }
}

/// A closed path of points walked at a constant speed: where along it, and which way, at `t`.
#[derive(Debug, Clone, PartialEq)]
pub struct Route {
    pub points: Vec<Vec3>,
    /// Units per second.
    pub speed: f32,
}

impl Route {
    /// The point `t` seconds along the loop and the unit direction of the leg it is on
    /// (`points[0]` and +X for a route of fewer than two points or no length).
    pub fn at(&self, t: f64) -> (Vec3, Vec3) {
        let first = self.points.first().copied().unwrap_or(Vec3::ZERO);
        let legs: Vec<(Vec3, Vec3, f64)> = self
            .points
            .iter()
            .zip(self.points.iter().cycle().skip(1))
            .map(|(&a, &b)| (a, b, f64::from(a.distance(b))))
            .collect();
        let length: f64 = legs.iter().map(|l| l.2).sum();
        if self.points.len() < 2 || length <= 0.0 || !length.is_finite() {
            return (first, Vec3::X);
        }
        let mut s = (t.max(0.0) * f64::from(self.speed.max(0.0))).rem_euclid(length);
        for (a, b, d) in legs {
            if s <= d && d > 0.0 {
                return (a.lerp(b, (s / d) as f32), (b - a).normalize_or(Vec3::X));
            }
            s -= d;
        }
        (first, Vec3::X)
    }
}

/// A model walking a route, turned to face the way it walks (`yaw_deg` added).
#[derive(Debug, Clone, PartialEq)]
pub struct Walk {
    pub model: usize,
    pub route: Route,
    pub yaw_deg: f32,
}

impl Walk {
    pub fn transform(&self, t: f64) -> Mat4 {
        let (at, dir) = self.route.at(t);
        let yaw = dir.y.atan2(dir.x) + self.yaw_deg.to_radians();
        Mat4::from_translation(at) * Mat4::from_rotation_z(yaw)
    }
}

/// How a light moves.
#[derive(Debug, Clone, PartialEq)]
pub enum LightPath {
    /// A horizontal circle about the vertical line through `centre`, from `start` (where the
    /// light is at t = 0), once every `period` seconds.
    Orbit {
        centre: Vec3,
        start: Vec3,
        period: f32,
    },
    /// Along a closed route.
    Route(Route),
    /// In place, its brightness varying between `1 - amount` and 1 about `rate` times a
    /// second (deterministic: the same `t` gives the same brightness).
    Flicker { amount: f32, rate: f32 },
}

/// A light's motion: its path, where a spot keeps pointing (None: its direction is kept) and
/// the colour it started with (flicker scales it).
#[derive(Debug, Clone, PartialEq)]
pub struct LightMotion {
    pub light: usize,
    pub path: LightPath,
    pub aim: Option<Vec3>,
    pub color: Vec3,
}

impl LightMotion {
    /// Whether the light changes place (orbit, route); a flickering one only dims.
    pub fn moves(&self) -> bool {
        !matches!(self.path, LightPath::Flicker { .. })
    }

    /// The light's position at `t`, or None where it does not move.
    pub fn position(&self, t: f64) -> Option<Vec3> {
        match &self.path {
            LightPath::Orbit {
                centre,
                start,
                period,
            } => {
                let turns = if *period > 0.0 && period.is_finite() {
                    (t / f64::from(*period)).fract()
                } else {
                    0.0
                };
                if turns == 0.0 {
                    return Some(*start);
                }
                let a = (turns * std::f64::consts::TAU) as f32;
                let arm = *start - *centre;
                let turned = glam::Quat::from_rotation_z(a) * Vec3::new(arm.x, arm.y, 0.0);
                Some(Vec3::new(centre.x, centre.y, start.z) + turned)
            }
            LightPath::Route(r) => Some(r.at(t).0),
            LightPath::Flicker { .. } => None,
        }
    }

    /// The light's brightness factor at `t` (1 unless it flickers): a sum of two sines of
    /// unrelated rates, so the flicker does not visibly repeat.
    pub fn brightness(&self, t: f64) -> f32 {
        match self.path {
            LightPath::Flicker { amount, rate } => {
                let x = t * f64::from(rate) * std::f64::consts::TAU;
                let wave = 0.5 + 0.25 * (x.sin() + (x * 2.37 + 1.3).sin());
                1.0 - amount.clamp(0.0, 1.0) * wave.clamp(0.0, 1.0) as f32
            }
            _ => 1.0,
        }
    }
}

/// Everything that moves in a scene.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Motion {
    pub rigs: Vec<Rig>,
    pub walks: Vec<Walk>,
    pub lights: Vec<LightMotion>,
}

/// What posing changed: models whose vertices changed (reshaped) or that moved whole, lights
/// that moved (their shadows must be redone) and lights whose colour alone changed (their
/// shadows hold).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Posed {
    pub reshaped: Vec<usize>,
    pub moved: Vec<usize>,
    pub lights_moved: Vec<usize>,
    pub lights_recoloured: Vec<usize>,
}

impl Motion {
    /// Whether light `light` changes place (an orbit or a route; a flicker only dims it).
    pub fn moves_light(&self, light: usize) -> bool {
        self.lights.iter().any(|m| m.light == light && m.moves())
    }

    /// Where model `model` may be while the motion plays: a world box holding it in every
    /// pose (its walk's route grown by its reach about its origin, or that reach about where
    /// it stands). None for a model the motion does not move. What is built against every
    /// receiver a light reaches can take this box for the model and stay as built while it
    /// moves.
    pub fn reach(&self, scene: &Scene, model: usize) -> Option<crate::geometry::Aabb> {
        let rig = self.rigs.iter().find(|r| r.model == model);
        let walk = self.walks.iter().find(|w| w.model == model);
        let m = scene.models.get(model)?;
        if rig.is_none() && walk.is_none() {
            return None;
        }
        let radius = match rig {
            Some(r) => r.radius(),
            None => scene
                .surfaces
                .iter()
                .filter(|s| s.owner == super::SurfaceOwner::Model(model))
                .flat_map(|s| {
                    let run = s.first_index as usize..(s.first_index + s.index_count) as usize;
                    scene.indices.get(run).unwrap_or(&[]).iter()
                })
                .filter_map(|&i| scene.vertices.get(i as usize))
                .map(|v| v.pos().length())
                .fold(0.0f32, f32::max),
        };
        // A walk turns the model about z (no scale); standing, its transform may scale it.
        let (centres, scale) = match walk {
            Some(w) if !w.route.points.is_empty() => (
                crate::geometry::Aabb::from_points(w.route.points.iter().copied()),
                1.0,
            ),
            _ => {
                let origin = m.transform.transform_point3(Vec3::ZERO);
                let t = m.transform;
                let scale = [t.x_axis, t.y_axis, t.z_axis]
                    .iter()
                    .map(|a| a.truncate().length())
                    .fold(0.0f32, f32::max);
                (crate::geometry::Aabb::from_points([origin]), scale)
            }
        };
        // A margin for tags mixed between key frames (unit axes, not quite orthogonal).
        let r = radius * scale * 1.1 + 1.0;
        Some(crate::geometry::Aabb {
            min: centres.min - Vec3::splat(r),
            max: centres.max + Vec3::splat(r),
        })
    }

    pub fn is_still(&self) -> bool {
        self.rigs.is_empty() && self.walks.is_empty() && self.lights.is_empty()
    }

    /// Poses `scene` at time `t`: rigs' vertices, walking models' transforms, lights' positions
    /// and colours. Only what differs from the scene's current state is marked changed.
    pub fn pose(&self, scene: &mut Scene, t: f64) -> Posed {
        let mut posed = Posed::default();
        let (models, lights) = (scene.models.len(), scene.lights.len());
        for rig in self.rigs.iter().filter(|r| r.model < models) {
            if rig.pose_vertices(scene, t) {
                posed.reshaped.push(rig.model);
            }
        }
        for walk in self.walks.iter().filter(|w| w.model < models) {
            let transform = walk.transform(t);
            if scene.models[walk.model].transform != transform {
                scene.models[walk.model].transform = transform;
                posed.moved.push(walk.model);
            }
        }
        for &m in &posed.reshaped {
            scene.model_reshaped(m);
        }
        for &m in posed.moved.iter().filter(|m| !posed.reshaped.contains(m)) {
            scene.model_moved(m);
        }
        for lm in self.lights.iter().filter(|l| l.light < lights) {
            let light = &mut scene.lights[lm.light];
            if let Some(p) = lm.position(t).filter(|p| *p != light.position) {
                light.position = p;
                if let (Some(aim), LightKind::Spot { direction, .. }) = (lm.aim, &mut light.kind) {
                    *direction = (aim - p).normalize_or(*direction);
                }
                posed.lights_moved.push(lm.light);
            }
            let color = lm.color * lm.brightness(t);
            if color != light.color {
                light.color = color;
                posed.lights_recoloured.push(lm.light);
            }
        }
        posed
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{ModelInstance, SurfaceKind, SurfaceOwner, Vertex};

    fn clip(first: u32, frames: u32, looping: u32, fps: f32) -> Clip {
        Clip {
            first,
            frames,
            looping,
            fps,
            reversed: false,
        }
    }

    #[test]
    fn clips_loop_hold_and_reverse_like_quake3() {
        let c = clip(10, 4, 4, 10.0);
        assert_eq!(c.at(0.0).from, 10);
        let k = c.at(0.25);
        assert_eq!((k.from, k.to), (12, 13));
        assert!((k.fraction - 0.5).abs() < 1e-5);
        // Key-frame times are key frames despite rounding: 1/15 s at 15 fps is frame 1.
        let k15 = clip(0, 30, 30, 15.0);
        for n in 0..30u32 {
            let k = k15.at(f64::from(n) / 15.0);
            assert_eq!((k.from, k.fraction), (n as usize, 0.0), "frame {n}");
        }
        // The fourth frame wraps to the first of the loop.
        assert_eq!((c.at(0.35).from, c.at(0.35).to), (13, 10));
        // No looping frames: the last is held.
        let held = clip(0, 3, 0, 10.0).at(10.0);
        assert_eq!((held.from, held.to, held.fraction), (2, 2, 0.0));
        // Looping the last two of five.
        let tail = clip(0, 5, 2, 1.0);
        let frames: Vec<usize> = (0..9).map(|s| tail.at(f64::from(s)).from).collect();
        assert_eq!(frames, vec![0, 1, 2, 3, 4, 3, 4, 3, 4]);
        let rev = Clip {
            reversed: true,
            ..clip(5, 3, 3, 1.0)
        };
        assert_eq!(rev.at(0.0).from, 7);
        assert_eq!(rev.at(2.0).from, 5);
    }

    #[test]
    fn tags_are_exact_at_key_frames_and_unit_between() {
        let a = TagKey {
            origin: Vec3::new(1.0, 2.0, 3.0),
            axis: [Vec3::X, Vec3::Y, Vec3::Z],
        };
        let b = TagKey {
            origin: Vec3::new(3.0, 2.0, 3.0),
            axis: [Vec3::Y, -Vec3::X, Vec3::Z],
        };
        assert_eq!(TagKey::between(&a, &b, 0.0), a);
        assert_eq!(TagKey::between(&a, &b, 1.0), b);
        let mid = TagKey::between(&a, &b, 0.5);
        assert_eq!(mid.origin, Vec3::new(2.0, 2.0, 3.0));
        for axis in mid.axis {
            assert!((axis.length() - 1.0).abs() < 1e-6);
        }
        // Halfway between the X and Y axes: 45°.
        let diagonal = Vec3::new(1.0, 1.0, 0.0).normalize();
        assert!(mid.axis[0].distance(diagonal) < 1e-6);
    }

    /// A two-part rig (a body and a head on its tag), one vertex each, two key frames.
    fn two_part_scene() -> (Scene, Rig) {
        let mut scene = Scene::named("rig");
        scene.models.push(ModelInstance::new("m", Mat4::IDENTITY));
        let v = Vertex::new(Vec3::ZERO, Vec3::Z, [0.0, 0.0]);
        let tri = [v, v, v];
        scene.push_surface(
            &tri,
            &[0, 1, 2],
            0,
            SurfaceOwner::Model(0),
            SurfaceKind::Model,
        );
        scene.push_surface(
            &tri,
            &[0, 1, 2],
            0,
            SurfaceOwner::Model(0),
            SurfaceKind::Model,
        );
        let body_positions: Arc<[Vec3]> = [
            [Vec3::ZERO, Vec3::X, Vec3::Y],
            [Vec3::Z, Vec3::X + Vec3::Z, Vec3::Y + Vec3::Z],
        ]
        .concat()
        .into();
        let head_positions: Arc<[Vec3]> = vec![Vec3::X; 3].into();
        let normals: Arc<[Vec3]> = vec![Vec3::Z; 6].into();
        let tag = |origin: Vec3, axis: [Vec3; 3]| TagKey { origin, axis };
        let rig = Rig {
            model: 0,
            parts: vec![
                RigPart {
                    name: "body".into(),
                    meshes: vec![KeyedMesh {
                        name: "body".into(),
                        first_vertex: 0,
                        verts: 3,
                        positions: body_positions,
                        normals: normals.clone(),
                    }],
                    tags: vec![(
                        "tag_head".into(),
                        vec![
                            tag(Vec3::new(0.0, 0.0, 10.0), [Vec3::X, Vec3::Y, Vec3::Z]),
                            tag(Vec3::new(0.0, 0.0, 20.0), [Vec3::Y, -Vec3::X, Vec3::Z]),
                        ],
                    )],
                    clip: clip(0, 2, 2, 1.0),
                    parent: None,
                },
                RigPart {
                    name: "head".into(),
                    meshes: vec![KeyedMesh {
                        name: "head".into(),
                        first_vertex: 3,
                        verts: 3,
                        positions: head_positions,
                        normals: normals[..3].into(),
                    }],
                    tags: Vec::new(),
                    clip: Clip::still(0),
                    parent: Some((0, 0)),
                },
            ],
        };
        (scene, rig)
    }

    #[test]
    fn rigs_pose_key_frames_exactly_and_children_follow_tags() {
        let (mut scene, rig) = two_part_scene();
        let motion = Motion {
            rigs: vec![rig],
            ..Motion::default()
        };
        let pose0 = scene.models[0].pose;
        motion.pose(&mut scene, 0.0);
        assert_ne!(scene.models[0].pose, pose0, "posing gives a new pose");
        assert_eq!(scene.vertices[1].pos(), Vec3::X);
        assert_eq!(scene.vertices[3].pos(), Vec3::new(1.0, 0.0, 10.0));
        motion.pose(&mut scene, 1.0);
        assert_eq!(scene.vertices[1].pos(), Vec3::X + Vec3::Z);
        // The head's tag turned 90°: its vertex (1,0,0) goes to (0,1,20).
        assert!(scene.vertices[3].pos().distance(Vec3::new(0.0, 1.0, 20.0)) < 1e-6);
        // Halfway: the body's vertex halfway, the head on the tag halfway (45°, z = 15).
        motion.pose(&mut scene, 0.5);
        assert_eq!(scene.vertices[0].pos(), Vec3::new(0.0, 0.0, 0.5));
        let d = std::f32::consts::FRAC_1_SQRT_2;
        assert!(scene.vertices[3].pos().distance(Vec3::new(d, d, 15.0)) < 1e-5);
        // The surfaces' bounds follow the vertices.
        assert!((scene.surfaces[1].bounds.max.z - 15.0).abs() < 1e-5);
    }

    #[test]
    fn routes_walk_a_closed_loop_at_their_speed() {
        let r = Route {
            points: vec![
                Vec3::ZERO,
                Vec3::new(10.0, 0.0, 0.0),
                Vec3::new(10.0, 10.0, 0.0),
            ],
            speed: 5.0,
        };
        assert_eq!(r.at(0.0), (Vec3::ZERO, Vec3::X));
        assert_eq!(r.at(1.0).0, Vec3::new(5.0, 0.0, 0.0));
        assert_eq!(r.at(3.0), (Vec3::new(10.0, 5.0, 0.0), Vec3::Y));
        // The way back is the diagonal; the loop's length is 20 + 10√2.
        let lap = (20.0 + 10.0 * 2f64.sqrt()) / 5.0;
        assert!(r.at(lap).0.distance(Vec3::ZERO) < 1e-4);
        let still = Route {
            points: vec![Vec3::ONE],
            speed: 5.0,
        };
        assert_eq!(still.at(7.0).0, Vec3::ONE);
    }

    #[test]
    fn lights_orbit_aim_and_flicker_and_say_what_changed() {
        let mut scene = Scene::named("lights");
        scene.lights.push(crate::scene::Light::spot(
            "s",
            Vec3::new(10.0, 0.0, 5.0),
            Vec3::ZERO,
            30.0,
            100.0,
        ));
        scene
            .lights
            .push(crate::scene::Light::omni("o", Vec3::ZERO, 100.0));
        let motion = Motion {
            lights: vec![
                LightMotion {
                    light: 0,
                    path: LightPath::Orbit {
                        centre: Vec3::new(0.0, 0.0, 0.0),
                        start: Vec3::new(10.0, 0.0, 5.0),
                        period: 4.0,
                    },
                    aim: Some(Vec3::ZERO),
                    color: Vec3::ONE,
                },
                LightMotion {
                    light: 1,
                    path: LightPath::Flicker {
                        amount: 0.5,
                        rate: 3.0,
                    },
                    aim: None,
                    color: Vec3::ONE,
                },
            ],
            ..Motion::default()
        };
        // At t = 0 the light is where it started, exactly.
        assert!(motion.pose(&mut scene, 0.0).lights_moved.is_empty());
        let posed = motion.pose(&mut scene, 1.0);
        assert!(scene.lights[0].position.distance(Vec3::new(0.0, 10.0, 5.0)) < 1e-4);
        let LightKind::Spot { direction, .. } = scene.lights[0].kind else {
            panic!("a spot stays a spot")
        };
        assert!(direction.distance(Vec3::new(0.0, -10.0, -5.0).normalize()) < 1e-5);
        assert_eq!(posed.lights_moved, vec![0]);
        assert!(posed.lights_recoloured.contains(&1));
        assert_eq!(scene.lights[1].position, Vec3::ZERO);
        let b = scene.lights[1].color.x;
        assert!((0.5..=1.0).contains(&b));
        // Posed again at the same time, nothing changes.
        let again = motion.pose(&mut scene, 1.0);
        assert!(again.lights_moved.is_empty() && again.lights_recoloured.is_empty());
    }
}
