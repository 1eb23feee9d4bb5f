//! Floating-point error bounds and robust ray origins (pbrt-v4, "Managing rounding error").
//!
//! Every intersection reports a conservative bound on the error of its hit point. Spawned rays
//! start just outside that error box, on the side they leave towards, so they never re-hit the
//! surface they start on, whatever the scale of the scene.

use glam::Vec3;

/// Half the distance between 1.0 and the next float: the relative error of one rounded operation.
pub const MACHINE_EPSILON: f32 = f32::EPSILON * 0.5;

/// Bound on the relative error accumulated by `n` rounded operations, gamma_n in pbrt.
#[inline]
pub const fn gamma(n: i32) -> f32 {
    let e = n as f32 * MACHINE_EPSILON;
    e / (1.0 - e)
}

/// The smallest float strictly greater than `v` (for finite `v`).
#[inline(always)]
pub fn next_float_up(v: f32) -> f32 {
    if v.is_infinite() && v > 0.0 {
        return v;
    }
    let v = if v == -0.0 { 0.0 } else { v };
    let bits = v.to_bits();
    let bits = if v >= 0.0 { bits + 1 } else { bits - 1 };
    f32::from_bits(bits)
}

/// The largest float strictly less than `v` (for finite `v`).
#[inline(always)]
pub fn next_float_down(v: f32) -> f32 {
    if v.is_infinite() && v < 0.0 {
        return v;
    }
    let v = if v == 0.0 { -0.0 } else { v };
    let bits = v.to_bits();
    let bits = if v > 0.0 { bits - 1 } else { bits + 1 };
    f32::from_bits(bits)
}

/// Offsets hit point `p` (with absolute error bound `p_error`) along the geometric normal `n`
/// to the side that direction `w` leaves towards, then rounds away from the surface.
// Inlined always: called out of line, its vector arguments went through memory and the
// loads stalled on the stores just before them (a tenth of a Whitted render).
#[inline(always)]
pub fn offset_ray_origin(p: Vec3, p_error: Vec3, n: Vec3, w: Vec3) -> Vec3 {
    let d = n.abs().dot(p_error);
    let mut offset = n * d;
    if w.dot(n) < 0.0 {
        offset = -offset;
    }
    let mut po = p + offset;
    for i in 0..3 {
        if offset[i] > 0.0 {
            po[i] = next_float_up(po[i]);
        } else if offset[i] < 0.0 {
            po[i] = next_float_down(po[i]);
        }
    }
    po
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn next_float_steps_one_ulp() {
        assert!(next_float_up(1.0) > 1.0);
        assert_eq!(next_float_up(1.0), 1.0 + f32::EPSILON);
        assert!(next_float_down(1.0) < 1.0);
        assert!(next_float_up(0.0) > 0.0);
        assert!(next_float_down(0.0) < 0.0);
        assert!(next_float_up(-1.0) > -1.0);
    }

    #[test]
    fn offset_moves_to_the_side_of_w() {
        let p = Vec3::new(1.0, 2.0, 3.0);
        let err = Vec3::splat(1e-4);
        let n = Vec3::Y;
        let up = offset_ray_origin(p, err, n, Vec3::new(0.0, 1.0, 0.0));
        let down = offset_ray_origin(p, err, n, Vec3::new(0.0, -1.0, 0.0));
        assert!(up.y > p.y + 1e-4 * 0.999);
        assert!(down.y < p.y - 1e-4 * 0.999);
    }
}
