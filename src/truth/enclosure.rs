//! Lights that sit inside or behind geometry. Quake 3 maps are not closed: faces nobody can see
//! (caulk, faces against other brushes) are not compiled, and light fixtures are often detail
//! brushes around the entity light. A light that sees the *back* of a face in most directions
//! is enclosed: the exact reference shadows everything behind those faces, while the paper's
//! techniques, which draw or extrude only faces turned toward the light, light it.

use super::reference::Reference;
use crate::scene::{Light, LightKind, Scene};
use glam::DVec3;

/// Directions sampled around each light (a spot light keeps those inside its cone).
pub const DIRECTIONS: usize = 512;

/// What the rays leaving a light first hit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Enclosure {
    /// Directions cast (inside the cone for a spot light).
    pub directions: usize,
    /// Rays whose first hit within the light's radius is a face turned away from the light.
    pub back_faces: usize,
    /// Rays whose first hit is a face turned toward the light.
    pub front_faces: usize,
}

impl Enclosure {
    /// Enclosed: more than half the directions end on the back of a face.
    pub fn enclosed(&self) -> bool {
        2 * self.back_faces > self.directions
    }

    /// Worth a warning: at least a tenth of the rays that hit something hit a back face.
    pub fn sees_backs(&self) -> bool {
        self.back_faces > 0 && 10 * self.back_faces >= self.back_faces + self.front_faces
    }
}

/// Evenly spread unit directions (a Fibonacci sphere).
fn directions(n: usize) -> impl Iterator<Item = DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n).map(move |i| {
        let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let a = golden * i as f64;
        DVec3::new(r * a.cos(), r * a.sin(), z)
    })
}

/// Casts rays from the light over the directions it lights, out to its radius.
pub fn enclosure(reference: &Reference, light: &Light) -> Enclosure {
    let from = light.position.as_dvec3();
    let lit = |d: &DVec3| match light.kind {
        LightKind::Spot {
            direction,
            cutoff_deg,
        } => d.dot(direction.as_dvec3()) >= (cutoff_deg as f64).to_radians().cos(),
        LightKind::Omni => true,
    };
    let mut e = Enclosure::default();
    for dir in directions(DIRECTIONS).filter(lit) {
        e.directions += 1;
        match reference.nearest_hit(from, dir, light.radius as f64) {
            Some(hit) if hit.faces_light => e.front_faces += 1,
            Some(_) => e.back_faces += 1,
            None => {}
        }
    }
    e
}

/// A warning for each light that sees the backs of faces (see [`Enclosure::sees_backs`]).
pub fn warnings(scene: &Scene, reference: &Reference) -> Vec<String> {
    scene
        .lights
        .iter()
        .filter_map(|l| {
            let e = enclosure(reference, l);
            e.sees_backs().then(|| {
                format!(
                    "light `{}` sees the backs of faces in {} of the {} directions that hit \
                     something: it sits inside, behind or outside geometry, and the techniques \
                     will light what those faces shadow (Quake 3 maps are not closed)",
                    l.name,
                    e.back_faces,
                    e.back_faces + e.front_faces
                )
            })
        })
        .collect()
}

/// [`warnings`] with the scene's reference built for them (none, and no reference, without
/// lights).
pub fn scene_warnings(scene: &Scene) -> Vec<String> {
    if scene.lights.is_empty() {
        return Vec::new();
    }
    warnings(scene, &Reference::build(scene))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;
    use glam::Vec3;

    #[test]
    fn directions_are_unit_and_balanced() {
        let d: Vec<DVec3> = directions(DIRECTIONS).collect();
        assert!(d.iter().all(|v| (v.length() - 1.0).abs() < 1e-12));
        // Evenly spread: the mean direction is near zero and each octant gets its eighth.
        let sum: DVec3 = d.iter().sum();
        assert!(sum.length() < 0.01 * DIRECTIONS as f64, "{sum:?}");
        for octant in 0..8 {
            let sign = |bit: usize, v: f64| (octant >> bit & 1 == 1) == (v >= 0.0);
            let n = d
                .iter()
                .filter(|v| sign(0, v.x) && sign(1, v.y) && sign(2, v.z))
                .count();
            assert!(
                n.abs_diff(DIRECTIONS / 8) <= DIRECTIONS / 80,
                "octant {octant}: {n}"
            );
        }
    }

    #[test]
    fn a_light_inside_a_box_is_enclosed_and_one_outside_is_not() {
        let scene = builtin::default_scene();
        let reference = Reference::build(&scene);
        let outside = enclosure(&reference, &scene.lights[1]);
        assert!(!outside.enclosed() && !outside.sees_backs(), "{outside:?}");
        // The spot's cone: about (1 - cos 38°) / 2 of the sphere.
        let spot = enclosure(&reference, &scene.lights[0]);
        assert!((50..=60).contains(&spot.directions), "{spot:?}");
        assert_eq!(spot.front_faces, spot.directions);
        // The built-in scene's box: a light at its centre sees only the insides of its faces.
        let mut inside = scene.lights[1].clone();
        inside.position = Vec3::new(-98.0, -8.0, 32.0);
        inside.radius = 1000.0;
        let e = enclosure(&reference, &inside);
        assert_eq!((e.back_faces, e.front_faces), (DIRECTIONS, 0), "{e:?}");
    }
}
