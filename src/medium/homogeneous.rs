//! A homogeneous medium: the same extinction `sigma_t` and single-scattering albedo everywhere
//! (Mitsuba 3's `homogeneous`). Per colour channel, so free-flight distances are sampled by the
//! one-sample spectral MIS of pbrt-v4's and Mitsuba 3's `volpathmis`: a channel is chosen in
//! proportion to the path's throughput, a distance is drawn from that channel's exponential,
//! and the estimate is divided by the mixture of all channels' densities (the balance heuristic
//! over channels), which is unbiased in every channel whichever was chosen. In a homogeneous
//! medium the exponential is sampled exactly, so no majorant (null collisions) is needed.

use super::phase::Phase;
use crate::math::Color;
use crate::spectrum::Wavelengths;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Homogeneous {
    /// Extinction coefficient per unit length, per channel (>= 0).
    pub sigma_t: Color,
    /// Single-scattering albedo sigma_s / sigma_t, per channel, in [0, 1].
    pub albedo: Color,
    pub phase: Phase,
}

/// What free-flight sampling along a ray found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MediumSample {
    /// The distance along the ray: a scattering point when `scattered`, else the end of the
    /// segment.
    pub t: f32,
    pub scattered: bool,
    /// The factor the path throughput is multiplied by: sigma_s T(t) / pdf(t) at a scattering
    /// point, T(t_max) / P(no collision before t_max) when the segment is passed.
    pub weight: Color,
    /// The weight without the scattering coefficient: T(t) / pdf(t) at a scattering point (what
    /// a density estimate of in-scattered light there is multiplied by), `weight` otherwise.
    pub tr_over_pdf: Color,
}

impl Homogeneous {
    /// A medium from its extinction and albedo; an error names what is wrong with them.
    pub fn new(sigma_t: Color, albedo: Color, phase: Phase) -> Result<Self, String> {
        for (c, v) in [sigma_t.r(), sigma_t.g(), sigma_t.b()].into_iter().enumerate() {
            if !(v >= 0.0) || !v.is_finite() {
                return Err(format!("sigma_t must be finite and >= 0 in every channel, found {v} in channel {c}"));
            }
        }
        for (c, v) in [albedo.r(), albedo.g(), albedo.b()].into_iter().enumerate() {
            if !(0.0..=1.0).contains(&v) {
                return Err(format!("albedo must be in [0, 1] in every channel, found {v} in channel {c}"));
            }
        }
        if let Phase::HenyeyGreenstein { g } = phase
            && !(g > -1.0 && g < 1.0)
        {
            return Err(format!("the Henyey-Greenstein `g` must be in (-1, 1), found {g}"));
        }
        Ok(Homogeneous { sigma_t, albedo, phase })
    }

    /// The scattering coefficient sigma_s = albedo sigma_t.
    #[inline]
    pub fn sigma_s(&self) -> Color {
        self.albedo * self.sigma_t
    }

    /// The medium at the path's wavelengths (spectral mode), or itself (RGB): the extinction
    /// lifted as an unbounded spectrum, the albedo as a reflectance (`Wavelengths`). The lanes
    /// are then wavelengths, and everything below (the channel choice by throughput, the
    /// mixture over lanes) applies to them unchanged: each lane's estimate is unbiased for its
    /// own wavelength whichever lane was chosen, which is all the film's per-wavelength
    /// division by the wavelength pdfs needs (Mitsuba 3's spectral `volpathmis` does the same).
    #[inline]
    pub fn at(&self, wl: Option<&Wavelengths>) -> Homogeneous {
        match wl {
            None => *self,
            Some(wl) => {
                Homogeneous { sigma_t: wl.unbounded(self.sigma_t), albedo: wl.reflectance(self.albedo), ..*self }
            }
        }
    }

    /// Beer-Lambert transmittance exp(-sigma_t t) over a distance `t` (which may be infinite: a
    /// channel without extinction then passes everything).
    #[inline]
    pub fn transmittance(&self, t: f32) -> Color {
        self.sigma_t.map(|s| if s > 0.0 { (-s * t).exp() } else { 1.0 })
    }

    /// Samples where along a segment of length `t_max` light carried with throughput `beta`
    /// first interacts: `u_channel` chooses the channel (in proportion to `beta`), `u` the
    /// distance. See the module's notes for the weights. (In spectral mode call it on the
    /// medium lifted by `at`.)
    #[inline]
    pub fn sample_distance(&self, t_max: f32, beta: Color, u_channel: f32, u: f32, lanes: usize) -> MediumSample {
        let p = channel_probabilities(beta, lanes);
        let mut c = 0;
        let mut cdf = p[0];
        while c + 1 < lanes && !(u_channel < cdf) {
            c += 1;
            cdf += p[c];
        }
        let s = self.sigma_t[c];
        let t = if s > 0.0 { -(1.0 - u).ln() / s } else { f32::INFINITY };
        if t < t_max {
            let tr = self.transmittance(t);
            let pdf = (p * self.sigma_t * tr).lane_sum(lanes);
            if pdf > 0.0 {
                let tr_over_pdf = tr / pdf;
                return MediumSample { t, scattered: true, weight: self.sigma_s() * tr_over_pdf, tr_over_pdf };
            }
        }
        let tr = self.transmittance(t_max);
        let prob = (p * tr).lane_sum(lanes);
        let weight = if prob > 0.0 { tr / prob } else { Color::ZERO };
        MediumSample { t: t_max, scattered: false, weight, tr_over_pdf: weight }
    }
}

/// The probabilities of choosing each of the first `lanes` lanes (3 channels, or the
/// wavelengths in spectral mode): in proportion to `beta`, uniform when it is zero or not finite.
#[inline]
fn channel_probabilities(beta: Color, lanes: usize) -> Color {
    let b = beta.max(Color::ZERO);
    let sum = b.lane_sum(lanes);
    if sum > 0.0 && sum.is_finite() { b / sum } else { Color::splat(1.0 / lanes as f32) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng32;

    #[test]
    fn hostile_values_are_refused() {
        let ok = Homogeneous::new(Color::ONE, Color::splat(0.5), Phase::Isotropic);
        assert!(ok.is_ok());
        assert!(Homogeneous::new(Color::new(1.0, -1.0, 1.0), Color::ONE, Phase::Isotropic).is_err());
        assert!(Homogeneous::new(Color::new(1.0, f32::NAN, 1.0), Color::ONE, Phase::Isotropic).is_err());
        assert!(Homogeneous::new(Color::splat(f32::INFINITY), Color::ONE, Phase::Isotropic).is_err());
        assert!(Homogeneous::new(Color::ONE, Color::new(0.5, 1.2, 0.5), Phase::Isotropic).is_err());
        assert!(Homogeneous::new(Color::ONE, Color::splat(f32::NAN), Phase::Isotropic).is_err());
        assert!(Homogeneous::new(Color::ONE, Color::ONE, Phase::HenyeyGreenstein { g: 1.0 }).is_err());
    }

    /// The mean of the passing weight over many samples is the Beer-Lambert transmittance in
    /// every channel, whichever channel the throughput favours; and the scattering weights
    /// integrate the in-scattered part: E[weight at scatter] = albedo (1 - T) per channel.
    #[test]
    fn free_flight_estimates_are_unbiased_per_channel() {
        let m = Homogeneous::new(Color::new(0.2, 1.0, 3.0), Color::new(0.9, 0.5, 0.1), Phase::Isotropic).unwrap();
        let t_max = 1.3;
        for beta in [Color::ONE, Color::new(1.0, 0.01, 0.3), Color::new(0.0, 0.0, 2.0)] {
            let mut rng = Rng32::new(11);
            let n = 400_000;
            let (mut pass, mut scatter) = (Color::ZERO, Color::ZERO);
            for _ in 0..n {
                let s = m.sample_distance(t_max, beta, rng.uniform(), rng.uniform(), 3);
                if s.scattered {
                    assert!(s.t < t_max);
                    scatter += s.weight;
                } else {
                    pass += s.weight;
                }
            }
            let (pass, scatter) = (pass / n as f32, scatter / n as f32);
            let tr = m.transmittance(t_max);
            let expected_scatter = m.albedo * (Color::ONE - tr);
            for c in 0..3 {
                if beta[c] == 0.0 {
                    continue;
                }
                let (p, e) = (pass[c], tr[c]);
                assert!((p - e).abs() < 0.01 * e.max(0.05), "beta {beta:?} channel {c}: pass {p} vs {e}");
                let (s, e) = (scatter[c], expected_scatter[c]);
                assert!((s - e).abs() < 0.01 * e.max(0.05), "beta {beta:?} channel {c}: scatter {s} vs {e}");
            }
        }
    }
}
