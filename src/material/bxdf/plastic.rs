//! Plastics: a dielectric coating over a diffuse base, as Mitsuba 3's `plastic` and
//! `roughplastic`. Each is two lobes: the coating's reflection (a Fresnel-weighted mirror, or a
//! rough dielectric microfacet reflection) and the base's diffuse light, which enters and leaves
//! through the coating (times its transmittance both ways and 1/eta^2) after any number of
//! bounces inside it (the d / (1 - F_dr) factor, or Mitsuba's `nonlinear` d / (1 - d F_dr)).
//!
//! The lobes are chosen in proportion to Mitsuba's weights: the coating's by its Fresnel
//! reflectance in the viewing direction, the base's by the coating's transmittance.

use super::conductor::reflect_about;
use super::{BxdfSample, LobeFlags};
use crate::material::fresnel::{fresnel_dielectric, refract};
use crate::material::microfacet::{Distribution, Microfacet};
use crate::math::{Color, Vec2, Vec3};
use crate::sampling::warp::cosine_hemisphere;
use std::collections::HashMap;
use std::f32::consts::FRAC_1_PI;
use std::sync::{Mutex, OnceLock};

/// The smooth coating: mirror reflection weighted by the dielectric Fresnel reflectance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FresnelMirror {
    pub eta: f32,
    pub scale: Color,
}

/// The base of a smooth plastic, seen through the coating: f = d (1 - F(wo)) (1 - F(wi)) / pi,
/// with `d` already divided by eta^2 and by the internal-reflection term.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlasticDiffuse {
    pub d: Color,
    pub eta: f32,
    /// Mean of the base's reflectance as given: its sampling weight against the coating's.
    pub d_mean: f32,
}

/// The rough coating: microfacet reflection of a rough dielectric (no transmission lobe: light
/// entering the coating is the base's). The table gives its transmittance, which sets how often
/// it is chosen against the base.
#[derive(Clone, Copy, Debug)]
pub struct RoughCoating {
    pub mf: Microfacet,
    pub eta: f32,
    pub scale: Color,
    pub table: &'static CoatingTable,
}

impl PartialEq for RoughCoating {
    fn eq(&self, o: &Self) -> bool {
        self.mf == o.mf && self.eta == o.eta && self.scale == o.scale && std::ptr::eq(self.table, o.table)
    }
}

/// The base of a rough plastic: f = d T(cos wo) T(cos wi) / pi with T the rough coating's
/// transmittance, from a table made once per roughness and index.
#[derive(Clone, Copy, Debug)]
pub struct RoughPlasticDiffuse {
    pub d: Color,
    pub table: &'static CoatingTable,
    pub d_mean: f32,
}

impl PartialEq for RoughPlasticDiffuse {
    fn eq(&self, o: &Self) -> bool {
        self.d == o.d && std::ptr::eq(self.table, o.table) && self.d_mean == o.d_mean
    }
}

impl FresnelMirror {
    #[inline]
    pub fn sample(&self, wo: Vec3) -> Option<BxdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let weight = self.scale * fresnel_dielectric(wo.z, self.eta);
        Some(BxdfSample { wi: Vec3::new(-wo.x, -wo.y, wo.z), weight, pdf: 1.0, flags: LobeFlags::SPECULAR_REFLECTION })
    }
}

impl PlasticDiffuse {
    #[inline]
    pub fn f(&self, wo: Vec3, wi: Vec3) -> Color {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Color::ZERO;
        }
        let t = (1.0 - fresnel_dielectric(wo.z, self.eta)) * (1.0 - fresnel_dielectric(wi.z, self.eta));
        self.d * (t * FRAC_1_PI)
    }

    #[inline]
    pub fn sample(&self, wo: Vec3, u: Vec2) -> Option<BxdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = cosine_hemisphere(u);
        let pdf = wi.z * FRAC_1_PI;
        (pdf > 0.0).then(|| BxdfSample {
            wi,
            weight: self.f(wo, wi) / FRAC_1_PI,
            pdf,
            flags: LobeFlags::DIFFUSE_REFLECTION,
        })
    }
}

impl RoughCoating {
    #[inline]
    pub fn f(&self, wo: Vec3, wi: Vec3) -> Color {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Color::ZERO;
        }
        let h = (wo + wi).normalize_or_zero();
        let d = self.mf.d(h);
        if !(d > 0.0) {
            return Color::ZERO;
        }
        let fr = fresnel_dielectric(wo.dot(h), self.eta);
        self.scale * (fr * d * self.mf.g(wo, wi, h) / (4.0 * wo.z * wi.z))
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let h = (wo + wi).normalize_or_zero();
        let ih = wi.dot(h);
        if !(wo.dot(h) > 0.0 && ih > 0.0) {
            return 0.0;
        }
        self.mf.pdf_visible(wo, h) / (4.0 * ih)
    }

    #[inline]
    pub fn sample(&self, wo: Vec3, u: Vec2) -> Option<BxdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let m = self.mf.sample_visible(wo, u);
        let om = wo.dot(m);
        let wi = reflect_about(wo, m);
        if !(wi.z > 0.0 && om > 0.0) {
            return None;
        }
        let pdf = self.mf.pdf_visible(wo, m) / (4.0 * om);
        let weight = self.scale * (fresnel_dielectric(om, self.eta) * self.mf.g1(wi, m));
        (pdf > 0.0).then_some(BxdfSample { wi, weight, pdf, flags: LobeFlags::GLOSSY_REFLECTION })
    }
}

impl RoughPlasticDiffuse {
    #[inline]
    pub fn f(&self, wo: Vec3, wi: Vec3) -> Color {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Color::ZERO;
        }
        self.d * (self.table.transmittance(wo.z) * self.table.transmittance(wi.z) * FRAC_1_PI)
    }

    #[inline]
    pub fn sample(&self, wo: Vec3, u: Vec2) -> Option<BxdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = cosine_hemisphere(u);
        let pdf = wi.z * FRAC_1_PI;
        (pdf > 0.0).then(|| BxdfSample {
            wi,
            weight: self.f(wo, wi) / FRAC_1_PI,
            pdf,
            flags: LobeFlags::DIFFUSE_REFLECTION,
        })
    }
}

/// Entries of the coating's transmittance table over cos theta in [0, 1].
pub const TABLE_SIZE: usize = 64;

/// What a rough coating lets through: its transmittance by the cosine of the direction, and the
/// fraction of diffuse light inside it that it reflects back (for the internal-reflection term).
#[derive(Debug, PartialEq)]
pub struct CoatingTable {
    pub transmittance: [f32; TABLE_SIZE],
    pub internal_reflectance: f32,
}

impl CoatingTable {
    /// Transmittance at cos theta `c`, linearly interpolated.
    #[inline]
    pub fn transmittance(&self, c: f32) -> f32 {
        let x = c.clamp(0.0, 1.0) * (TABLE_SIZE - 1) as f32;
        let i = (x as usize).min(TABLE_SIZE - 2);
        let t = x - i as f32;
        self.transmittance[i] * (1.0 - t) + self.transmittance[i + 1] * t
    }

    /// The table of a coating of microfacets `mf` and relative index `eta` (outside to
    /// inside). Expectations over the visible normals are integrated by Gauss-Legendre
    /// quadrature on the square of sample numbers (Mitsuba 3's rule: 32 x 32 nodes looking into
    /// the coating, 128 x 128 looking out of it, where total internal reflection makes the
    /// integrand rough).
    pub fn compute(mf: Microfacet, eta: f32) -> CoatingTable {
        let mut transmittance = [0.0; TABLE_SIZE];
        let mut reflect_sum = 0.0f64;
        let (coarse, fine) = (gauss_legendre(32), gauss_legendre(128));
        for (j, t) in transmittance.iter_mut().enumerate() {
            let mu = (j as f32 / (TABLE_SIZE - 1) as f32).max(1e-6);
            let wi = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
            // Into the coating: (1 - F) G1 of the refracted direction, where it goes through.
            *t = expectation(&coarse, &mf, wi, |m| {
                let cos = wi.dot(m);
                let Some(wt) = refract(-wi, m, eta) else { return 0.0 };
                if wt.z >= 0.0 {
                    return 0.0;
                }
                (1.0 - fresnel_dielectric(cos, eta)) * mf.g1(wt, m)
            }) as f32;
            // Out of it, seen from inside: F G1 of the reflected direction.
            let r = expectation(&fine, &mf, wi, |m| {
                let wr = reflect_about(wi, m);
                if wr.z <= 0.0 {
                    return 0.0;
                }
                fresnel_dielectric(wi.dot(m), 1.0 / eta) * mf.g1(wr, m)
            });
            reflect_sum += r * mu as f64;
        }
        let internal_reflectance = (2.0 * reflect_sum / TABLE_SIZE as f64) as f32;
        CoatingTable { transmittance, internal_reflectance }
    }

    /// The table for `mf` and `eta`, computed once per distinct pair and shared (tables live
    /// for the whole run, so lobes can point to them without a lifetime).
    pub fn shared(mf: Microfacet, eta: f32) -> &'static CoatingTable {
        type Key = (bool, u32, u32, u32);
        static TABLES: OnceLock<Mutex<HashMap<Key, &'static CoatingTable>>> = OnceLock::new();
        let key = (mf.distribution == Distribution::Ggx, mf.alpha_u.to_bits(), mf.alpha_v.to_bits(), eta.to_bits());
        let tables = TABLES.get_or_init(Default::default);
        let mut tables = tables.lock().unwrap_or_else(|e| e.into_inner());
        tables.entry(key).or_insert_with(|| Box::leak(Box::new(CoatingTable::compute(mf, eta))))
    }
}

/// E[g(m)] over the normals visible from `wi`, by quadrature of the sampling map on the square.
fn expectation(rule: &(Vec<f64>, Vec<f64>), mf: &Microfacet, wi: Vec3, g: impl Fn(Vec3) -> f32) -> f64 {
    let (nodes, weights) = rule;
    let mut sum = 0.0;
    for (x, wx) in nodes.iter().zip(weights) {
        for (y, wy) in nodes.iter().zip(weights) {
            let m = mf.sample_visible(wi, Vec2::new(*x as f32, *y as f32));
            sum += wx * wy * g(m) as f64;
        }
    }
    sum
}

/// Gauss-Legendre nodes and weights of `n` points, mapped to [0, 1] (weights summing to 1).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut nodes = Vec::with_capacity(n);
    let mut weights = Vec::with_capacity(n);
    for i in 0..n {
        // Newton's method on P_n from the Chebyshev estimate of the i-th root.
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let pn = if n == 0 { 1.0 } else { p1 };
            let pn1 = if n == 0 { 0.0 } else { p0 };
            dp = n as f64 * (x * pn - pn1) / (x * x - 1.0);
            let dx = pn / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        nodes.push(0.5 * (1.0 - x));
        weights.push(1.0 / ((1.0 - x * x) * dp * dp));
    }
    (nodes, weights)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        for n in [2, 5, 32, 128] {
            let (x, w) = gauss_legendre(n);
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12, "{n}");
            // Exact for degree 2n - 1 on [0, 1]: the integral of x^k is 1 / (k + 1).
            let k = (2 * n - 1).min(40) as i32;
            let q: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(k)).sum();
            assert!((q - 1.0 / (k as f64 + 1.0)).abs() < 1e-12, "{n}: {q}");
        }
    }
}
