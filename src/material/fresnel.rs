//! Reflection, refraction and the Fresnel equations for dielectrics (seed eq. 3-8).
//!
//! Conventions: `i` is the incident direction, pointing *towards* the surface; `n` is a unit
//! normal on the side the ray arrives from (so `n . i < 0`); `eta` is the relative index of
//! refraction n_t / n_i (the medium entered over the medium left). When a ray leaves a medium the
//! caller flips the normal and inverts `eta`, as the seed report prescribes.

use crate::math::Vec3;

/// Mirror direction, seed eq. 3: R = I - 2 (N . I) N.
#[inline]
pub fn reflect(i: Vec3, n: Vec3) -> Vec3 {
    i - 2.0 * n.dot(i) * n
}

/// Refracted direction by Snell's law (seed eq. 4, written for eta = n_t / n_i):
/// T = I / eta + (cos_i / eta - cos_t) N with cos_i = |N . I|.
/// Returns `None` on total internal reflection (cos_t would be imaginary).
#[inline]
pub fn refract(i: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = -n.dot(i);
    let inv = 1.0 / eta;
    let sin2_t = inv * inv * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(i * inv + n * (inv * cos_i - cos_t))
}

/// The two Fresnel amplitude coefficients (seed eq. 5 and 6) for |cos_i| and relative index eta,
/// or `None` on total internal reflection.
#[inline]
pub fn fresnel_amplitudes(cos_i: f32, eta: f32) -> Option<(f32, f32)> {
    let cos_i = cos_i.abs().min(1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let r_par = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    Some((r_par, r_perp))
}

/// Fraction of light reflected by a smooth dielectric, k_s of seed eq. 7; 1 under total internal
/// reflection. The transmitted fraction is 1 - k_s (eq. 8).
#[inline]
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    match fresnel_amplitudes(cos_i, eta) {
        Some((r_par, r_perp)) => 0.5 * (r_par * r_par + r_perp * r_perp),
        None => 1.0,
    }
}

/// Reflectance of a conductor with complex index of refraction eta + i k at incidence cos_i > 0
/// (the exact formula for unpolarised light; one colour channel). eta = 0, k = 1 reflects
/// everything, which is how Mitsuba's `conductor` without a material is a perfect mirror.
#[inline]
pub fn fresnel_conductor(cos_i: f32, eta: f32, k: f32) -> f32 {
    let c = cos_i.clamp(0.0, 1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let (eta2, k2) = (eta * eta, k * k);
    let t1 = eta2 - k2 - s2;
    let a2b2 = (t1 * t1 + 4.0 * eta2 * k2).max(0.0).sqrt();
    let a = (0.5 * (a2b2 + t1)).max(0.0).sqrt();
    let term1 = a2b2 + c2;
    let term2 = 2.0 * c * a;
    if !(term1 + term2 > 0.0) {
        return 1.0;
    }
    let rs = (term1 - term2) / (term1 + term2);
    let term3 = a2b2 * c2 + s2 * s2;
    let term4 = term2 * s2;
    let rp = if term3 + term4 > 0.0 { rs * (term3 - term4) / (term3 + term4) } else { rs };
    0.5 * (rs + rp)
}

/// `fresnel_conductor` per colour channel (per lane: per wavelength in spectral mode).
#[inline]
pub fn fresnel_conductor_rgb(cos_i: f32, eta: crate::math::Color, k: crate::math::Color) -> crate::math::Color {
    eta.zip_map(k, |eta, k| fresnel_conductor(cos_i, eta, k))
}

/// The hemispherical average of the dielectric Fresnel reflectance for relative index `eta`
/// (polynomial fits: Egan and Hilgeman for eta < 1, d'Eon and Irving otherwise), as a plastic's
/// light bouncing inside its coating sees it.
pub fn fresnel_diffuse_reflectance(eta: f32) -> f32 {
    if eta < 1.0 {
        0.0636 / eta + eta * (-1.4399 * eta + 0.7099) + 0.6681
    } else {
        let x = 1.0 / eta;
        0.919317 + x * (-3.4793 + x * (6.75335 + x * (-7.80989 + x * (4.98554 - 1.36881 * x))))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Frame;
    use crate::sampling::{Rng32, warp::uniform_sphere};

    #[test]
    fn reflect_keeps_angle_and_length() {
        let n = Vec3::Y;
        let i = Vec3::new(1.0, -1.0, 0.0).normalize();
        let r = reflect(i, n);
        assert!(r.abs_diff_eq(Vec3::new(1.0, 1.0, 0.0).normalize(), 1e-6));
        assert!((r.length() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn refract_obeys_snell_both_ways() {
        let mut rng = Rng32::new(11);
        let mut tested = 0;
        for _ in 0..20_000 {
            let n = uniform_sphere(rng.uniform2());
            let mut i = uniform_sphere(rng.uniform2());
            if i.dot(n) > 0.0 {
                i = -i;
            }
            let n1 = 1.0 + 1.5 * rng.uniform();
            let n2 = 1.0 + 1.5 * rng.uniform();
            let sin_i = i.cross(n).length();
            match refract(i, n, n2 / n1) {
                Some(t) => {
                    assert!((t.length() - 1.0).abs() < 1e-4);
                    // Transmitted ray continues through the surface, in the plane of incidence.
                    assert!(t.dot(n) < 0.0);
                    assert!(t.dot(i.cross(n)).abs() < 1e-4);
                    let sin_t = t.cross(n).length();
                    assert!(
                        (n1 * sin_i - n2 * sin_t).abs() < 1e-5 * n1.max(n2) * 4.0,
                        "Snell: {n1} {sin_i} vs {n2} {sin_t}"
                    );
                    tested += 1;
                }
                None => assert!(n1 * sin_i > n2 * 0.9999, "TIR reported below the critical angle"),
            }
        }
        assert!(tested > 10_000);
    }

    #[test]
    fn total_internal_reflection_exactly_beyond_critical_angle() {
        let eta = 1.0 / 1.5; // leaving glass into air
        let critical = (1.0f32 / 1.5).asin();
        let frame = Frame::from_z(Vec3::Z);
        for (angle, expect_tir) in [(critical - 1e-3, false), (critical + 1e-3, true), (1.5, true), (0.1, false)] {
            let i = frame.to_world(Vec3::new(angle.sin(), 0.0, -angle.cos()));
            assert_eq!(refract(i, Vec3::Z, eta).is_none(), expect_tir, "angle {angle}");
            assert_eq!(fresnel_dielectric(angle.cos(), eta) == 1.0, expect_tir);
        }
    }

    #[test]
    fn fresnel_values() {
        // 0.04 at normal incidence for glass.
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        // Grazing incidence reflects everything.
        assert!(fresnel_dielectric(1e-4, 1.5) > 0.999);
        // Brewster's angle: the parallel amplitude vanishes.
        let brewster = 1.5f32.atan();
        let (r_par, r_perp) = fresnel_amplitudes(brewster.cos(), 1.5).unwrap();
        assert!(r_par.abs() < 1e-6, "{r_par}");
        assert!(r_perp.abs() > 0.1);
        // Energy: k_s + k_t = 1 and both within [0, 1]; symmetric in direction of travel.
        for k in 0..=100 {
            let cos_i = k as f32 / 100.0;
            let ks = fresnel_dielectric(cos_i, 1.5);
            let kt = 1.0 - ks;
            assert!((0.0..=1.0).contains(&ks) && (ks + kt - 1.0).abs() < 1e-7);
            // Reciprocity: same reflectance from inside at the matching refracted angle. Near
            // grazing the inside angle nears the critical angle, where F's slope is unbounded and
            // f32 rounding of cos_t dominates, so check from cos_i = 0.1 on.
            if k < 10 {
                continue;
            }
            let sin_t = (1.0 - cos_i * cos_i).sqrt() / 1.5;
            let cos_t = (1.0 - sin_t * sin_t).sqrt();
            let back = fresnel_dielectric(cos_t, 1.0 / 1.5);
            assert!((back - ks).abs() < 1e-5, "cos_i {cos_i}: {ks} vs {back}");
        }
    }

    #[test]
    fn conductor_fresnel_matches_known_values() {
        // Gold at normal incidence (Mitsuba 3's RGB eta and k): ((n-1)^2 + k^2) / ((n+1)^2 + k^2).
        let (eta, k) =
            (crate::math::Color::new(0.143036, 0.375307, 1.44205), crate::math::Color::new(3.983, 2.38556, 1.60336));
        let f = fresnel_conductor_rgb(1.0, eta, k);
        for (v, want) in f.to_array().into_iter().zip([0.96668, 0.80201, 0.32412]) {
            assert!((v - want).abs() < 2e-5, "{v} vs {want}");
        }
        // eta 0, k 1 is a perfect mirror at every angle; grazing incidence reflects everything.
        for c in [1.0, 0.7, 0.2, 0.01] {
            assert!((fresnel_conductor(c, 0.0, 1.0) - 1.0).abs() < 1e-6);
        }
        assert!(fresnel_conductor(0.0, 0.2, 3.0) > 0.999);
        // A conductor with k = 0 is a dielectric.
        for c in [1.0, 0.8, 0.5, 0.1] {
            assert!((fresnel_conductor(c, 1.5, 0.0) - fresnel_dielectric(c, 1.5)).abs() < 1e-5);
        }
    }

    #[test]
    fn diffuse_fresnel_reflectance_matches_mitsubas_plastic() {
        // Mitsuba's plastic prints fdr_int = 0.590479 and fdr_ext = 0.090239 for eta 1.48959.
        let eta = 1.489_587;
        assert!((fresnel_diffuse_reflectance(1.0 / eta) - 0.590479).abs() < 1e-4);
        assert!((fresnel_diffuse_reflectance(eta) - 0.090239).abs() < 1e-4);
    }
}
