//! Warps from the unit square to other domains, with their densities and inverses
//! (pbrt-v4 sec. A.5; Shirley and Chiu 1997 for the concentric disk).

use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// Concentric map of [0,1)^2 onto the unit disk: area-preserving, and it keeps strata compact.
#[inline]
pub fn concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) =
        if o.x.abs() > o.y.abs() { (o.x, FRAC_PI_4 * (o.y / o.x)) } else { (o.y, FRAC_PI_2 - FRAC_PI_4 * (o.x / o.y)) };
    r * Vec2::new(theta.cos(), theta.sin())
}

/// Inverse of `concentric_disk`.
pub fn concentric_disk_inverse(p: Vec2) -> Vec2 {
    let r = p.length();
    if r == 0.0 {
        return Vec2::splat(0.5);
    }
    let mut theta = p.y.atan2(p.x);
    if theta < -FRAC_PI_4 {
        theta += 2.0 * PI;
    }
    // Each of the four wedges maps from one side pair of the square.
    let (x, y) = if theta < FRAC_PI_4 {
        (r, r * theta / FRAC_PI_4)
    } else if theta < 3.0 * FRAC_PI_4 {
        (r * (FRAC_PI_2 - theta) / FRAC_PI_4, r)
    } else if theta < 5.0 * FRAC_PI_4 {
        (-r, -r * (theta - PI) / FRAC_PI_4)
    } else {
        (-r * (3.0 * FRAC_PI_2 - theta) / FRAC_PI_4, -r)
    };
    (Vec2::new(x, y) + Vec2::ONE) * 0.5
}

/// Cosine-weighted direction about +z; density cos(theta) / pi.
#[inline]
pub fn cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Uniform direction on the unit sphere; density 1 / (4 pi).
#[inline]
pub fn uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Uniform direction in the cone about +z with cos(half-angle) = `cos_max`;
/// density 1 / (2 pi (1 - cos_max)).
#[inline]
pub fn uniform_cone(u: Vec2, cos_max: f32) -> Vec3 {
    let cos_t = 1.0 - u.x * (1.0 - cos_max);
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::sampling::Rng32;

    /// Pearson chi-square statistic of `observed` counts against `expected` counts, pooling cells
    /// that expect fewer than 5 (as mitsuba's chi2 test does). Returns (statistic, degrees of freedom).
    pub fn chi_square(observed: &[f64], expected: &[f64]) -> (f64, usize) {
        let mut idx: Vec<usize> = (0..observed.len()).collect();
        idx.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
        let (mut stat, mut dof) = (0.0, 0usize);
        let (mut pool_o, mut pool_e) = (0.0, 0.0);
        for i in idx {
            if expected[i] < 5.0 {
                pool_o += observed[i];
                pool_e += expected[i];
                continue;
            }
            stat += (observed[i] - expected[i]).powi(2) / expected[i];
            dof += 1;
        }
        if pool_e > 0.0 {
            stat += (pool_o - pool_e).powi(2) / pool_e;
            dof += 1;
        }
        (stat, dof.saturating_sub(1))
    }

    /// Upper-tail critical value of chi-square with `dof` degrees of freedom for significance
    /// `alpha`, by the Wilson-Hilferty approximation (accurate to ~1% for dof > 30).
    pub fn chi_square_critical(dof: usize, alpha: f64) -> f64 {
        // z quantile by bisection on the normal tail (erfc via a rational approximation).
        let tail = |z: f64| 0.5 * erfc(z / std::f64::consts::SQRT_2);
        let (mut lo, mut hi) = (0.0, 10.0);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if tail(mid) > alpha { lo = mid } else { hi = mid }
        }
        let z = 0.5 * (lo + hi);
        let k = dof as f64;
        let a = 2.0 / (9.0 * k);
        k * (1.0 - a + z * a.sqrt()).powi(3)
    }

    /// Complementary error function (Numerical Recipes erfcc, relative error < 1.2e-7).
    fn erfc(x: f64) -> f64 {
        let z = x.abs();
        let t = 1.0 / (1.0 + 0.5 * z);
        let r = t
            * (-z * z - 1.26551223
                + t * (1.00002368
                    + t * (0.37409196
                        + t * (0.09678418
                            + t * (-0.18628806
                                + t * (0.27886807
                                    + t * (-1.13520398 + t * (1.48851587 + t * (-0.82215223 + t * 0.17087277)))))))))
                .exp();
        if x >= 0.0 { r } else { 2.0 - r }
    }

    /// Chi-square test that points from `warp` are uniform over the unit disk, on a polar grid of
    /// equal-area cells. Returns true when uniformity is not rejected at alpha = 0.01.
    fn disk_uniformity(warp: impl Fn(Vec2) -> Vec2) -> bool {
        let (nr, nphi) = (10usize, 20usize);
        let n = 200_000;
        let mut counts = vec![0.0f64; nr * nphi];
        let mut rng = Rng32::new(1234);
        for _ in 0..n {
            let p = warp(rng.uniform2());
            let r2 = p.length_squared().min(0.999_999);
            // Equal-area rings: ring index from r^2.
            let ir = ((r2 * nr as f32) as usize).min(nr - 1);
            let phi = p.y.atan2(p.x) + PI;
            let ip = ((phi / (2.0 * PI) * nphi as f32) as usize).min(nphi - 1);
            counts[ir * nphi + ip] += 1.0;
        }
        let expected = vec![n as f64 / (nr * nphi) as f64; nr * nphi];
        let (stat, dof) = chi_square(&counts, &expected);
        stat < chi_square_critical(dof, 0.01)
    }

    #[test]
    fn concentric_disk_maps_into_unit_disk_and_round_trips() {
        let mut rng = Rng32::new(99);
        for _ in 0..10_000 {
            let u = rng.uniform2();
            let p = concentric_disk(u);
            assert!(p.length() <= 1.0 + 1e-6);
            let back = concentric_disk_inverse(p);
            assert!(back.abs_diff_eq(u, 2e-4), "{u} -> {p} -> {back}");
        }
        // Corners of the square go to the rim.
        assert!((concentric_disk(Vec2::new(1.0, 0.5)).length() - 1.0).abs() < 1e-6);
        assert!((concentric_disk(Vec2::new(0.5, 0.0)).length() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn concentric_disk_is_uniform_and_a_wrong_map_is_caught() {
        assert!(disk_uniformity(concentric_disk), "concentric map rejected as non-uniform");
        // The naive polar map r = u, theta = 2 pi v crowds the centre: the test must reject it.
        let naive = |u: Vec2| {
            let t = 2.0 * PI * u.y;
            u.x * Vec2::new(t.cos(), t.sin())
        };
        assert!(!disk_uniformity(naive), "chi-square test failed to reject a non-uniform map");
    }

    #[test]
    fn cosine_hemisphere_has_cosine_density() {
        // Mean of cos(theta) under density cos/pi is 2/3.
        let mut rng = Rng32::new(5);
        let n = 200_000;
        let mean: f64 = (0..n).map(|_| cosine_hemisphere(rng.uniform2()).z as f64).sum::<f64>() / n as f64;
        assert!((mean - 2.0 / 3.0).abs() < 0.003, "{mean}");
    }

    #[test]
    fn uniform_sphere_and_cone_are_unit_and_centred() {
        let mut rng = Rng32::new(6);
        let mut sum = Vec3::ZERO;
        for _ in 0..100_000 {
            let d = uniform_sphere(rng.uniform2());
            assert!((d.length() - 1.0).abs() < 1e-5);
            sum += d;
            let c = uniform_cone(rng.uniform2(), 0.9);
            assert!(c.z >= 0.9 - 1e-6);
        }
        assert!(sum.length() / 100_000.0 < 0.01);
    }
}
