//! Axis-aligned bounding boxes.

use crate::math::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Aabb::EMPTY
    }
}

impl Aabb {
    /// The empty box: the identity of `union`.
    pub const EMPTY: Aabb = Aabb { min: Vec3::splat(f32::INFINITY), max: Vec3::splat(f32::NEG_INFINITY) };
    /// All of space (the bounds of an unbounded shape such as a plane).
    pub const INFINITE: Aabb = Aabb { min: Vec3::splat(f32::NEG_INFINITY), max: Vec3::splat(f32::INFINITY) };

    pub fn from_points(points: &[Vec3]) -> Self {
        points.iter().fold(Aabb::EMPTY, |b, &p| b.grow(p))
    }

    #[inline]
    pub fn grow(self, p: Vec3) -> Self {
        Aabb { min: self.min.min(p), max: self.max.max(p) }
    }

    #[inline]
    pub fn union(self, o: Aabb) -> Self {
        Aabb { min: self.min.min(o.min), max: self.max.max(o.max) }
    }

    #[inline]
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    #[inline]
    pub fn extent(&self) -> Vec3 {
        if self.is_empty() { Vec3::ZERO } else { self.max - self.min }
    }

    #[inline]
    pub fn centroid(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Half the surface area (enough for the SAH, which only compares ratios).
    #[inline]
    pub fn half_area(&self) -> f32 {
        let e = self.extent();
        e.x * e.y + e.y * e.z + e.z * e.x
    }

    #[inline]
    pub fn diagonal(&self) -> f32 {
        self.extent().length()
    }

    /// Index (0, 1, 2) of the longest axis.
    pub fn max_axis(&self) -> usize {
        let e = self.extent();
        if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        }
    }

    /// Bounding sphere (centre, radius) of the box.
    pub fn bounding_sphere(&self) -> (Vec3, f32) {
        (self.centroid(), self.diagonal() * 0.5)
    }
}
