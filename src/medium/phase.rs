//! Phase functions: how a medium scatters light in direction, per steradian (Mitsuba 3's
//! `isotropic`, `hg` and `rayleigh`). Conventions as for BSDFs: `wo` and `wi` both point away
//! from the scattering point, `wo` towards the viewer and `wi` towards the light, so light going
//! straight on has `wo . wi = -1` (forward scattering, favoured by `g > 0`). A phase function is
//! normalised over the sphere and is its own sampling density, so a sampled direction has
//! weight 1.

use crate::math::{Frame, Vec2, Vec3};
use crate::sampling::warp::uniform_sphere;
use std::f32::consts::PI;

const INV_FOUR_PI: f32 = 1.0 / (4.0 * PI);

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Phase {
    /// The same in every direction, 1 / (4 pi).
    Isotropic,
    /// Henyey-Greenstein with mean cosine `g` in (-1, 1) (Henyey and Greenstein 1941).
    HenyeyGreenstein { g: f32 },
    /// Rayleigh scattering by particles much smaller than the wavelength: 3 (1 + cos^2) / (16 pi).
    Rayleigh,
}

/// A direction sampled from a phase function; its density is the phase function's value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhaseSample {
    pub wi: Vec3,
    pub pdf: f32,
}

impl Phase {
    /// The phase function's value (and density) for the pair (`wo`, `wi`).
    #[inline]
    pub fn p(&self, wo: Vec3, wi: Vec3) -> f32 {
        let cos = wo.dot(wi);
        match *self {
            Phase::Isotropic => INV_FOUR_PI,
            Phase::HenyeyGreenstein { g } => henyey_greenstein(cos, g),
            Phase::Rayleigh => 3.0 / (16.0 * PI) * (1.0 + cos * cos),
        }
    }

    /// Samples `wi` given `wo`, exactly in proportion to `p`.
    #[inline]
    pub fn sample(&self, wo: Vec3, u: Vec2) -> PhaseSample {
        let cos = match *self {
            Phase::Isotropic => {
                let wi = uniform_sphere(u);
                return PhaseSample { wi, pdf: INV_FOUR_PI };
            }
            Phase::HenyeyGreenstein { g } => {
                // The inverse of the cumulative distribution of cos(theta) measured from the
                // direction light travels on, -wo.
                let mu = if g.abs() < 1e-3 {
                    1.0 - 2.0 * u.x
                } else {
                    let s = (1.0 - g * g) / (1.0 + g - 2.0 * g * u.x);
                    (1.0 + g * g - s * s) / (2.0 * g)
                };
                -mu.clamp(-1.0, 1.0)
            }
            Phase::Rayleigh => {
                // cos^3 + 3 cos + (4 - 8u) = 0 has one real root (Cardano).
                let q = 4.0 - 8.0 * u.x;
                let r = (q * q / 4.0 + 1.0).sqrt();
                (-q / 2.0 + r).cbrt() + (-q / 2.0 - r).cbrt()
            }
        }
        .clamp(-1.0, 1.0);
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let phi = 2.0 * PI * u.y;
        let frame = Frame::from_z(wo);
        let wi = frame.to_world(Vec3::new(sin * phi.cos(), sin * phi.sin(), cos)).normalize();
        PhaseSample { wi, pdf: self.p(wo, wi) }
    }

    /// The mean cosine between the direction light arrives in and the one it leaves in.
    pub fn mean_cosine(&self) -> f32 {
        match *self {
            Phase::Isotropic | Phase::Rayleigh => 0.0,
            Phase::HenyeyGreenstein { g } => g,
        }
    }
}

/// Henyey-Greenstein's density for `cos` = wo . wi (so forward scattering is cos = -1).
#[inline]
fn henyey_greenstein(cos: f32, g: f32) -> f32 {
    let denom = 1.0 + g * g + 2.0 * g * cos;
    INV_FOUR_PI * (1.0 - g * g) / (denom * denom.max(1e-12).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::chi2::{Chi2Config, chi2_directions};

    fn phases() -> Vec<(&'static str, Phase)> {
        vec![
            ("isotropic", Phase::Isotropic),
            ("hg 0.7", Phase::HenyeyGreenstein { g: 0.7 }),
            ("hg -0.4", Phase::HenyeyGreenstein { g: -0.4 }),
            ("hg 0", Phase::HenyeyGreenstein { g: 0.0 }),
            ("rayleigh", Phase::Rayleigh),
        ]
    }

    #[test]
    fn samplers_match_their_densities() {
        let wo = Vec3::new(0.3, -0.5, 0.81).normalize();
        let n = phases().len();
        for (name, phase) in phases() {
            let config = Chi2Config { tests: n, samples: 400_000, ..Chi2Config::default() };
            chi2_directions(name, |u, _| Some(phase.sample(wo, u).wi), |wi| phase.p(wo, wi), &config)
                .unwrap_or_else(|e| panic!("{e}"));
        }
    }

    #[test]
    fn sampled_density_is_the_value_and_mean_cosine_is_g() {
        let wo = Vec3::new(0.0, 0.6, 0.8);
        for (_, phase) in phases() {
            let mut rng = crate::sampling::Rng32::new(7);
            let (mut mean, n) = (0.0f64, 200_000);
            for _ in 0..n {
                let s = phase.sample(wo, rng.uniform2());
                assert!((s.pdf - phase.p(wo, s.wi)).abs() <= 1e-4 * s.pdf, "{phase:?}");
                assert!((s.wi.length() - 1.0).abs() < 1e-4);
                // The cosine between where light travelled (-wi) and where it goes (wo).
                mean += f64::from(-s.wi.dot(wo));
            }
            mean /= f64::from(n);
            assert!((mean - f64::from(phase.mean_cosine())).abs() < 0.01, "{phase:?}: mean cosine {mean}");
        }
    }
}
