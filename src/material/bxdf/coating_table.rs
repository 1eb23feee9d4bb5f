//! The transmittance table of a rough dielectric coating (Mitsuba 3's `roughplastic`
//! precomputation): how much light a coating of given roughness and index lets through by
//! direction, and how much of the diffuse light inside it the coating reflects back.

use super::reflect_about;
use crate::material::fresnel::{fresnel_dielectric, refract};
use crate::material::microfacet::{Distribution, Microfacet};
use crate::math::{Vec2, Vec3};
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

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
        let (coarse, fine) = (gauss_legendre(32), gauss_legendre(128));
        // The rows are independent and made in parallel (a rough plastic's table, about a
        // million sampled normals, was most of a scene's load time); their sums are taken in
        // row order, so the table is the same on any thread count.
        let rows: Vec<(f32, f64)> = (0..TABLE_SIZE)
            .into_par_iter()
            .map(|j| {
                let mu = (j as f32 / (TABLE_SIZE - 1) as f32).max(1e-6);
                let wi = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
                // Into the coating: (1 - F) G1 of the refracted direction, where it goes through.
                let t = expectation(&coarse, &mf, wi, |m| {
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
                (t, r * mu as f64)
            })
            .collect();
        let mut transmittance = [0.0; TABLE_SIZE];
        let mut reflect_sum = 0.0f64;
        for ((t, r), out) in rows.into_iter().zip(&mut transmittance) {
            *out = t;
            reflect_sum += r;
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
        let lock = || tables.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(&table) = lock().get(&key) {
            return table;
        }
        // Made without holding the lock: `compute` runs on the thread pool, whose workers may be
        // waiting for the lock in other tasks. Two threads making the same table at once keep
        // the first (the same numbers), the other's copy is left unused.
        let table: &'static CoatingTable = Box::leak(Box::new(CoatingTable::compute(mf, eta)));
        lock().entry(key).or_insert(table)
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
