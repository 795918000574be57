//! Dynamic lights: spot lights (the paper's shadow-map lights) and omni lights.
//!
//! The receiver rule here ([`Light::reaches`]) is the single definition of "this light can light
//! this point"; `shaders/lit.frag` implements the same test, and the exact reference uses this one.

use glam::{DVec3, Vec3};

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LightKind {
    /// A cone around `direction` (unit) with half-angle `cutoff_deg` (GL's spot cutoff is
    /// below 90; up to 180 here: a cone wider than a half-space, see `plan.wide_spot_omni`).
    Spot { direction: Vec3, cutoff_deg: f32 },
    /// Lights every direction.
    Omni,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Light {
    pub name: String,
    pub kind: LightKind,
    pub position: Vec3,
    /// Linear RGB, 1.0 = full brightness at the light.
    pub color: Vec3,
    /// Distance at which the light's contribution reaches zero.
    pub radius: f32,
}

/// Fraction of the cutoff angle at which the cone edge starts to soften.
pub const SPOT_INNER_FRACTION: f32 = 0.8;

/// A surface the light grazes closer than this cosine (0.11°) is no receiver of it: its
/// diffuse term is under half an 8-bit level of the light's colour, so shadowed and lit look
/// the same, and the plane through the light that it lies in is where a shadow volume's sides
/// and a shadow map's depths coincide with it and no rasterization decides exactly
/// (`shadowlab check`'s planner differences on ctf_gate1 were all such pixels).
pub const GRAZING_COSINE: f64 = 1.0 / 512.0;

impl Light {
    pub fn spot(name: &str, position: Vec3, target: Vec3, cutoff_deg: f32, radius: f32) -> Light {
        Light {
            name: name.to_string(),
            kind: LightKind::Spot {
                direction: (target - position).normalize_or(-Vec3::Z),
                cutoff_deg,
            },
            position,
            color: Vec3::ONE,
            radius,
        }
    }

    pub fn omni(name: &str, position: Vec3, radius: f32) -> Light {
        Light {
            name: name.to_string(),
            kind: LightKind::Omni,
            position,
            color: Vec3::ONE,
            radius,
        }
    }

    /// Whether this light reaches a surface point with normal `n` at all: within its radius, in its
    /// cone, and on the lit side of the surface by more than [`GRAZING_COSINE`]. This decides
    /// "receiver" for masks and metrics.
    pub fn reaches(&self, p: DVec3, n: DVec3) -> bool {
        let to_light = self.position.as_dvec3() - p;
        let dist = to_light.length();
        if !(dist > 0.0 && dist < self.radius as f64) {
            return false;
        }
        if n.dot(to_light) <= GRAZING_COSINE * dist * n.length() {
            return false;
        }
        match self.kind {
            LightKind::Omni => true,
            LightKind::Spot {
                direction,
                cutoff_deg,
            } => {
                let cos_angle = (-to_light / dist).dot(direction.as_dvec3().normalize());
                cos_angle > (cutoff_deg as f64).to_radians().cos()
            }
        }
    }

    /// Radiometric falloff with distance, 1 at the light and 0 at `radius` (smooth at both ends).
    pub fn distance_falloff(&self, dist: f32) -> f32 {
        let x = (dist / self.radius).clamp(0.0, 1.0);
        let w = 1.0 - x * x;
        w * w
    }

    /// Cosine of the spot cutoff (-1 for omni lights, so that every direction passes).
    pub fn cos_cutoff(&self) -> f32 {
        match self.kind {
            LightKind::Spot { cutoff_deg, .. } => cutoff_deg.to_radians().cos(),
            LightKind::Omni => -1.0,
        }
    }

    pub fn is_spot(&self) -> bool {
        matches!(self.kind, LightKind::Spot { .. })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spot_reaches_inside_its_cone_only() {
        let l = Light::spot("s", Vec3::new(0.0, 0.0, 100.0), Vec3::ZERO, 30.0, 500.0);
        let up = DVec3::Z;
        assert!(l.reaches(DVec3::ZERO, up));
        // tan(30°)·100 = 57.7: inside at 50, outside at 60.
        assert!(l.reaches(DVec3::new(50.0, 0.0, 0.0), up));
        assert!(!l.reaches(DVec3::new(60.0, 0.0, 0.0), up));
        // Facing away.
        assert!(!l.reaches(DVec3::ZERO, -up));
    }

    #[test]
    fn a_surface_grazed_within_the_grazing_cosine_is_no_receiver() {
        let l = Light::omni("o", Vec3::new(0.0, 0.0, 1.0), 1000.0);
        // The light 1 unit above the plane z = 0: cosine 1/d at distance d.
        let at = |d: f64| DVec3::new((d * d - 1.0).sqrt(), 0.0, 0.0);
        assert!(l.reaches(at(500.0), DVec3::Z));
        assert!(!l.reaches(at(520.0), DVec3::Z));
    }

    #[test]
    fn omni_reaches_within_radius() {
        let l = Light::omni("o", Vec3::ZERO, 100.0);
        assert!(l.reaches(DVec3::new(99.0, 0.0, 0.0), -DVec3::X));
        assert!(!l.reaches(DVec3::new(101.0, 0.0, 0.0), -DVec3::X));
        assert_eq!(l.distance_falloff(0.0), 1.0);
        assert_eq!(l.distance_falloff(100.0), 0.0);
    }
}
