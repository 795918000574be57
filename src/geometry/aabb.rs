//! Axis-aligned boxes.

use glam::{Mat4, Vec3};

/// Axis-aligned bounds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }
    pub fn extend(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }
    /// Whether the boxes overlap (touching counts); empty boxes meet nothing.
    pub fn intersects(&self, o: &Aabb) -> bool {
        !self.is_empty()
            && !o.is_empty()
            && self.min.cmple(o.max).all()
            && o.min.cmple(self.max).all()
    }

    /// The overlap of two boxes (empty when they do not meet).
    pub fn intersection(&self, o: &Aabb) -> Aabb {
        Aabb {
            min: self.min.max(o.min),
            max: self.max.min(o.max),
        }
    }

    /// The corner furthest along a direction whose components are non-negative where
    /// `positive` is set (a plane's "positive vertex": the box reaches the plane's inner side
    /// iff this corner does).
    pub fn furthest_corner(&self, positive: glam::BVec3) -> Vec3 {
        Vec3::select(positive, self.max, self.min)
    }

    /// Whether `o` lies wholly inside (an empty `o` does).
    pub fn contains(&self, o: &Aabb) -> bool {
        o.is_empty() || (self.min.cmple(o.min).all() && o.max.cmple(self.max).all())
    }

    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }
    pub fn from_points(points: impl IntoIterator<Item = Vec3>) -> Aabb {
        let mut b = Aabb::EMPTY;
        for p in points {
            b.extend(p);
        }
        b
    }
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }
    pub fn corners(&self) -> [Vec3; 8] {
        let (a, b) = (self.min, self.max);
        [
            Vec3::new(a.x, a.y, a.z),
            Vec3::new(b.x, a.y, a.z),
            Vec3::new(a.x, b.y, a.z),
            Vec3::new(b.x, b.y, a.z),
            Vec3::new(a.x, a.y, b.z),
            Vec3::new(b.x, a.y, b.z),
            Vec3::new(a.x, b.y, b.z),
            Vec3::new(b.x, b.y, b.z),
        ]
    }
    pub fn transformed(&self, m: &Mat4) -> Aabb {
        if self.is_empty() {
            return *self;
        }
        Aabb::from_points(self.corners().iter().map(|c| m.transform_point3(*c)))
    }
}
