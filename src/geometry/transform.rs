//! Affine transforms for placing objects: translate, rotate about an axis, scale, composed in order.

use crate::math::Vec3;
use glam::{Mat3, Mat4, Quat};

/// An affine transform with its inverse-transpose kept for normals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    pub m: Mat4,
    normal_m: Mat3,
}

impl Default for Transform {
    fn default() -> Self {
        Transform::IDENTITY
    }
}

impl Transform {
    pub const IDENTITY: Transform = Transform { m: Mat4::IDENTITY, normal_m: Mat3::IDENTITY };

    pub fn from_mat4(m: Mat4) -> Self {
        let normal_m = Mat3::from_mat4(m).inverse().transpose();
        Transform { m, normal_m }
    }

    pub fn translate(t: Vec3) -> Self {
        Self::from_mat4(Mat4::from_translation(t))
    }

    /// Rotation by `degrees` about unit `axis`, counter-clockwise looking down the axis.
    pub fn rotate(axis: Vec3, degrees: f32) -> Self {
        Self::from_mat4(Mat4::from_quat(Quat::from_axis_angle(axis.normalize(), degrees.to_radians())))
    }

    /// Mitsuba 3's `<rotate>`: the axis-angle matrix c I + (1 - c) a a^T + s [a]x built from
    /// the axis as written, not normalised (a longer axis also scales, as in Mitsuba; a unit axis
    /// gives `rotate`).
    pub fn rotate_as_written(axis: Vec3, degrees: f32) -> Self {
        // A unit axis (nearly every scene) takes `rotate`'s rounding, so a Mitsuba scene and its
        // native twin build the same transform bit for bit.
        if (axis.length_squared() - 1.0).abs() < 1e-6 {
            return Self::rotate(axis, degrees);
        }
        let (s, c) = degrees.to_radians().sin_cos();
        let a = axis;
        let cross =
            glam::Mat3::from_cols(Vec3::new(0.0, a.z, -a.y), Vec3::new(-a.z, 0.0, a.x), Vec3::new(a.y, -a.x, 0.0));
        let outer = glam::Mat3::from_cols(a * a.x, a * a.y, a * a.z);
        let m = glam::Mat3::IDENTITY * c + outer * (1.0 - c) + cross * s;
        Self::from_mat4(Mat4::from_mat3(m))
    }

    pub fn scale(s: Vec3) -> Self {
        Self::from_mat4(Mat4::from_scale(s))
    }

    /// `self` applied first, then `next`.
    pub fn then(self, next: Transform) -> Self {
        Self::from_mat4(next.m * self.m)
    }

    #[inline]
    pub fn point(&self, p: Vec3) -> Vec3 {
        self.m.transform_point3(p)
    }

    #[inline]
    pub fn vector(&self, v: Vec3) -> Vec3 {
        self.m.transform_vector3(v)
    }

    /// Transforms a normal (by the inverse transpose); the result is not normalised.
    #[inline]
    pub fn normal(&self, n: Vec3) -> Vec3 {
        self.normal_m * n
    }

    /// Scale factors along the three axes if the linear part is a rotation times a scale
    /// (lengths of the transformed basis vectors).
    pub fn axis_scales(&self) -> Vec3 {
        Vec3::new(self.vector(Vec3::X).length(), self.vector(Vec3::Y).length(), self.vector(Vec3::Z).length())
    }

    /// True when the linear part is invertible and finite.
    pub fn is_valid(&self) -> bool {
        let det = Mat3::from_mat4(self.m).determinant();
        self.m.is_finite() && det.is_finite() && det.abs() > 1e-12
    }

    /// True when the transform preserves angles (a similarity: rotation, uniform scale, translation).
    pub fn is_similarity(&self) -> bool {
        let s = self.axis_scales();
        let x = self.vector(Vec3::X);
        let y = self.vector(Vec3::Y);
        let z = self.vector(Vec3::Z);
        let tol = 1e-4 * s.max_element();
        (s.x - s.y).abs() < tol
            && (s.y - s.z).abs() < tol
            && x.dot(y).abs() < tol * s.x
            && y.dot(z).abs() < tol * s.x
            && x.dot(z).abs() < tol * s.x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compose_in_order() {
        let t = Transform::scale(Vec3::splat(2.0)).then(Transform::translate(Vec3::X));
        assert!(t.point(Vec3::ONE).abs_diff_eq(Vec3::new(3.0, 2.0, 2.0), 1e-6));
        let r = Transform::rotate(Vec3::Y, 90.0);
        assert!(r.point(Vec3::X).abs_diff_eq(-Vec3::Z, 1e-6));
    }

    #[test]
    fn normals_stay_perpendicular_under_nonuniform_scale() {
        let t = Transform::scale(Vec3::new(1.0, 4.0, 1.0));
        let tangent = Vec3::new(1.0, 1.0, 0.0);
        let n = Vec3::new(1.0, -1.0, 0.0);
        assert!(t.vector(tangent).dot(t.normal(n)).abs() < 1e-6);
        assert!(!t.is_similarity());
        assert!(Transform::rotate(Vec3::Z, 33.0).is_similarity());
    }

    /// Mitsuba 3 (scalar_rgb, 3.x) prints these matrices for `ScalarTransform4f().rotate(axis,
    /// angle)`: the axis is used as written.
    #[test]
    fn rotate_as_written_matches_mitsuba() {
        // A general axis of length 1.42 (rows as Mitsuba prints them).
        let t = Transform::rotate_as_written(Vec3::new(0.3, -1.2, 0.7), 37.0);
        let rows = [
            [0.8167583, -0.4937617, -0.6798914],
            [0.3487793, 1.0886004, -0.3496907],
            [0.7644646, 0.0113983, 0.8973041],
        ];
        for (i, row) in rows.iter().enumerate() {
            for (j, &v) in row.iter().enumerate() {
                assert!((t.m.col(j)[i] - v).abs() < 1e-6, "({i}, {j}): {} vs {v}", t.m.col(j)[i]);
            }
        }
        let t = Transform::rotate_as_written(Vec3::new(2.0, 0.0, 0.0), 90.0);
        let want = Mat4::from_cols_array_2d(&[
            [4.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, 2.0, 0.0],
            [0.0, -2.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ]);
        assert!(t.m.abs_diff_eq(want, 1e-6), "{:?}", t.m);
    }
}
