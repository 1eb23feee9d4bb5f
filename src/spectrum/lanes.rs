//! Spectral mode's wavelengths, carried in the four lanes of `Color`: in a spectral render a
//! path's throughput and radiance are the existing `Color` values, each lane holding the value
//! at one of the path's wavelengths instead of a colour channel. Everything the integrators do
//! to colours (products, sums, Russian roulette on the largest lane, the layers) then works on
//! spectra unchanged, and the RGB mode keeps its code and its images bit for bit.
//!
//! Four wavelengths per path, as Wilkie et al. (2014) and pbrt-v4 carry: `Color` is a `Vec4`
//! whose fourth lane an RGB colour fills with a copy of its red, which every lane-wise operation
//! keeps exact, so that the largest and smallest lane, finiteness and equality see what they saw
//! on three channels (`math::color`); the channel sums and means stay over three. The RGB mode
//! costs no more for it: fewer instructions (one SSE operation where a `Vec3` did three), and
//! the stored arrays of colours that are RGB in either mode (SPPM's pixels and visible points,
//! photon hits, photon mapping's irradiance records) keep 12 bytes a colour as `PackedColor`,
//! VCM's light vertices keep their size with `PackedLanes` (BENCHMARKS.md, "Four wavelengths per
//! path"). The hero-rotated wavelengths (u, u + 1/4, u + 1/2, u + 3/4 through the visible
//! distribution's inverse CDF) stratify the spectrum more finely than three did: on one path's
//! estimate of a white furnace's colour (D65 light; `sampled.rs`'s tests), the standard
//! deviation is (0.151, 0.031, 0.579) against (0.418, 0.072, 0.877) with three, more than the
//! sqrt(4/3) that independent samples would give.
//!
//! Scene values become spectra where they enter the path: reflectances through
//! [`super::RgbAlbedoSpectrum`]'s table (greys exactly), unbounded values (conductors' eta and
//! k) as [`super::RgbUnboundedSpectrum`], emission as [`super::RgbIlluminantSpectrum`] (times
//! D65, so white light stays white). Values the scene gave as spectra are evaluated as they
//! are instead: named metals' measured eta and k (`material::conductors`), emitted spectra
//! ([`super::EmissionSpectrum`], through `Scene::emission_in`). The film receives the Monte Carlo estimate of the sample's
//! CIE XYZ, each lane divided by its wavelength's pdf, mapped to linear sRGB ([`Wavelengths::to_srgb`]).
//!
//! At a dispersive interface the path keeps only its hero wavelength: the lanes of the other
//! three would follow a direction they cannot take. [`Wavelengths::terminate_secondary`] returns
//! the factor (4, 0, 0, 0) that the throughput is multiplied by once, so that the hero alone
//! stands for the four from there on while the light found before the interface keeps all four.
//! Bidirectional methods join two subpaths at one set of wavelengths; when both crossed a
//! dispersive interface, each throughput holds the factor and the joined path takes it once
//! ([`joined`]).

use super::rgb::{RgbToSpectrumTable, SigmoidPolynomial};
use super::sampled::{LAMBDA_MAX, LAMBDA_MIN, cie_xyz, d65, xyz_to_color};
use crate::math::Color;
use std::cell::RefCell;

/// Wavelengths per path in spectral mode: one per lane of `Color`.
pub const LANES: usize = 4;

/// The visible-light distribution's inverse CDF constants (see `sampled.rs`).
const VISIBLE_A: f32 = 0.0072;
const VISIBLE_MU: f32 = 538.0;
const TANH_LO: f32 = -0.856_910_63;
const TANH_HI: f32 = 0.970_591_35;
const VISIBLE_NORM: f32 = VISIBLE_A / (TANH_HI - TANH_LO);

/// The CIE Y normalisation the conversion scales by (`cie_tables.rs`'s).
const Y_NORMALIZATION: f32 = super::cie_tables::CIE_Y_NORMALIZATION as f32;

/// The four wavelengths (nm) of a path in spectral mode and their pdfs (per nm); lane 0 is the
/// hero.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wavelengths {
    lambda: [f32; LANES],
    pdf: [f32; LANES],
    /// Only the hero is left (see `terminate_secondary`).
    hero_only: bool,
}

impl Wavelengths {
    /// The wavelengths for `u` in [0, 1): the hero at `u`, the others at u + 1/4, u + 1/2 and
    /// u + 3/4 (mod 1), through the visible-light distribution.
    pub fn sample(u: f32) -> Self {
        let mut lambda = [0.0; LANES];
        let mut pdf = [0.0; LANES];
        for i in 0..LANES {
            let mut ui = u + i as f32 / LANES as f32;
            if ui >= 1.0 {
                ui -= 1.0;
            }
            // The inverse CDF, lambda = MU + atanh(x) / A, with atanh written as one logarithm,
            // and the pdf from x itself: NORM / cosh^2(atanh x) = NORM (1 - x^2). (About 500
            // instructions a path less than `atanh` and `visible_pdf`; the two agree to 1e-6.)
            let x = TANH_LO + ui * (TANH_HI - TANH_LO);
            let l = VISIBLE_MU + 0.5 * ((1.0 + x) / (1.0 - x)).ln() / VISIBLE_A;
            (lambda[i], pdf[i]) = (l.clamp(LAMBDA_MIN, LAMBDA_MAX), VISIBLE_NORM * (1.0 - x * x));
        }
        Wavelengths { lambda, pdf, hero_only: false }
    }

    /// Every lane at the one wavelength `lambda` (nm), with pdf 1: for tests that trace a
    /// single wavelength.
    pub fn single(lambda: f32) -> Self {
        Wavelengths { lambda: [lambda; LANES], pdf: [1.0; LANES], hero_only: false }
    }

    /// Wavelength `i` (0 is the hero).
    #[inline(always)]
    pub fn lambda(&self, i: usize) -> f32 {
        self.lambda[i]
    }

    /// The hero wavelength.
    #[inline(always)]
    pub fn hero(&self) -> f32 {
        self.lambda[0]
    }

    /// `f` at each wavelength, one per lane.
    #[inline(always)]
    pub fn map(&self, f: impl Fn(f32) -> f32) -> Color {
        Color::from_lanes(self.lambda.map(f))
    }

    /// A reflectance or transmittance colour (clamped to [0, 1]) as its smooth spectrum at the
    /// lanes' wavelengths. Greys are exact constants; other colours come from the table.
    #[inline]
    pub fn reflectance(&self, c: Color) -> Color {
        if c.r() == c.g() && c.g() == c.b() {
            return Color::splat(c.r().clamp(0.0, 1.0));
        }
        self.polynomial(coefficients(c.to_array()))
    }

    /// A colour whose channels may exceed 1 (a conductor's eta and k, a medium's coefficients):
    /// twice its largest channel times the spectrum of the colour over that.
    #[inline]
    pub fn unbounded(&self, c: Color) -> Color {
        if c.r() == c.g() && c.g() == c.b() {
            return Color::splat(c.r().max(0.0));
        }
        let c = c.max(Color::ZERO);
        let m = c.max_element();
        if !(m > 0.0) {
            return Color::ZERO;
        }
        let scale = 2.0 * m;
        self.polynomial(coefficients((c / scale).to_array())) * scale
    }

    /// An emitted colour (radiance, intensity, irradiance) as a spectrum: the unbounded
    /// spectrum times D65, so that RGB (1, 1, 1) is D65 and renders white.
    #[inline]
    pub fn illuminant(&self, c: Color) -> Color {
        if c == Color::ZERO {
            return c;
        }
        self.unbounded(c) * self.map(d65)
    }

    /// The precomputed polynomial `p` at the lanes' wavelengths.
    #[inline]
    pub fn polynomial(&self, p: SigmoidPolynomial) -> Color {
        self.map(|l| p.eval(l))
    }

    /// Keeps only the hero (a dispersive interface): the factor to multiply the throughput by,
    /// (4, 0, 0, 0), the first time; `None` once the secondary wavelengths are gone.
    #[inline]
    pub fn terminate_secondary(&mut self) -> Option<Color> {
        if self.hero_only {
            return None;
        }
        self.hero_only = true;
        let mut factor = [0.0; LANES];
        factor[0] = LANES as f32;
        Some(Color::from_lanes(factor))
    }

    /// True once `terminate_secondary` has been called.
    #[inline]
    pub fn secondary_terminated(&self) -> bool {
        self.hero_only
    }

    /// The Monte Carlo estimate of the CIE XYZ of spectral radiance `v` (one value per lane):
    /// the average of v_i xyz-bar(lambda_i) / pdf_i, scaled by the Y normalisation.
    pub fn to_xyz(&self, v: Color) -> [f32; 3] {
        let mut xyz = [0.0f32; 3];
        for ((value, lambda), pdf) in v.lanes().into_iter().zip(self.lambda).zip(self.pdf) {
            if value == 0.0 || !(pdf > 0.0) {
                continue;
            }
            let bar = cie_xyz(lambda);
            let w = value / pdf;
            for k in 0..3 {
                xyz[k] += w * bar[k];
            }
        }
        xyz.map(|c| c * (Y_NORMALIZATION / LANES as f32))
    }

    /// A path's throughput `beta` (one value per lane) as an RGB colour: the colour of white
    /// (D65) light through it, exact (the lanes' common value) while it is grey. For light the
    /// path meets as RGB (photon estimates), which the throughput then weights as a colour.
    #[inline]
    pub fn throughput_to_srgb(&self, beta: Color) -> Color {
        let [a, b, c, d] = beta.lanes();
        if a == b && b == c && c == d && !self.hero_only {
            return beta;
        }
        self.to_srgb(beta * self.map(d65))
    }

    /// Spectral radiance `v` as linear sRGB (unclamped).
    #[inline]
    pub fn to_srgb(&self, v: Color) -> Color {
        if v == Color::ZERO {
            return v;
        }
        xyz_to_color(self.to_xyz(v))
    }
}

/// A path joined from two subpaths traced at the same wavelengths (a connection or a merge of
/// bidirectional methods), `c` the product of both throughputs: when both subpaths kept only the
/// hero, each throughput holds `terminate_secondary`'s factor and `c` the square of it, so the
/// joined path, which is one path through dispersive interfaces, is brought back to one factor.
/// Otherwise (one of them, or neither, terminated) `c` is the joined path's as it is. Never both
/// in RGB mode, so RGB paths are untouched.
#[inline(always)]
pub fn joined(c: Color, a_hero_only: bool, b_hero_only: bool) -> Color {
    if a_hero_only && b_hero_only { c * (1.0 / LANES as f32) } else { c }
}

/// Slots of each thread's memo of table lookups.
const MEMO_SLOTS: usize = 64;

thread_local! {
    /// The last colours looked up in the table by this thread, by a hash of their bits: a
    /// scene's constant colours (an untextured material's reflectance, a light's radiance) are
    /// met again and again, and the table's trilinear lookup (about 100 instructions) is then
    /// done once per thread instead of at every hit. A pure function of the colour either way,
    /// so images do not depend on which thread met what first.
    static MEMO: RefCell<[([u32; 3], SigmoidPolynomial); MEMO_SLOTS]> =
        RefCell::new([([u32::MAX; 3], SigmoidPolynomial::constant(0.0)); MEMO_SLOTS]);
}

/// The table's coefficients for `rgb` (clamped to [0, 1]), through the thread's memo.
#[inline]
fn coefficients(rgb: [f32; 3]) -> SigmoidPolynomial {
    let rgb = rgb.map(|c| c.clamp(0.0, 1.0));
    let key = rgb.map(f32::to_bits);
    if rgb.iter().any(|c| c.is_nan()) {
        return RgbToSpectrumTable::srgb().lookup(rgb);
    }
    let h = key[0].wrapping_mul(0x9E37_79B1) ^ key[1].wrapping_mul(0x85EB_CA77) ^ key[2].wrapping_mul(0xC2B2_AE3D);
    let slot = (h >> 26) as usize % MEMO_SLOTS;
    MEMO.with(|memo| {
        let mut memo = memo.borrow_mut();
        let entry = &mut memo[slot];
        if entry.0 != key {
            *entry = (key, RgbToSpectrumTable::srgb().lookup(rgb));
        }
        entry.1
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A white furnace's estimate: reflectance 1 under RGB white light, averaged over many
    /// wavelength samples, converts back to white.
    #[test]
    fn white_light_on_white_converts_to_white() {
        let n = 20000;
        let mut sum = Color::ZERO;
        for i in 0..n {
            let wl = Wavelengths::sample((i as f32 + 0.5) / n as f32);
            sum += wl.to_srgb(wl.illuminant(Color::ONE) * wl.reflectance(Color::ONE));
        }
        let mean = sum / n as f32;
        for c in mean.to_array() {
            assert!((c - 1.0).abs() < 2e-3, "{mean:?}");
        }
    }

    /// A coloured emitter converts back to its colour (the uplift's round trip through D65).
    #[test]
    fn coloured_light_round_trips() {
        let n = 20000;
        for rgb in [Color::new(0.8, 0.3, 0.1), Color::new(0.1, 0.5, 0.9), Color::new(3.0, 2.0, 0.5)] {
            let mut sum = Color::ZERO;
            for i in 0..n {
                let wl = Wavelengths::sample((i as f32 + 0.5) / n as f32);
                sum += wl.to_srgb(wl.illuminant(rgb));
            }
            let mean = sum / n as f32;
            for (a, b) in mean.to_array().iter().zip(rgb.to_array()) {
                assert!((a - b).abs() < 1e-2 * b.max(0.3), "{mean:?} vs {rgb:?}");
            }
        }
    }

    /// The cheaper inverse CDF gives the distribution's own pdf.
    #[test]
    fn sampled_pdf_is_the_visible_pdf() {
        for i in 0..1000 {
            let wl = Wavelengths::sample((i as f32 + 0.5) / 1000.0);
            for k in 0..LANES {
                let (l, p) = (wl.lambda[k], wl.pdf[k]);
                let want = super::super::visible_pdf(l);
                assert!((p - want).abs() < 1e-5 * want.max(1e-3), "{l}: {p} against {want}");
            }
        }
    }

    /// The memo returns what the table does.
    #[test]
    fn memo_is_the_table() {
        for rgb in [[0.2, 0.5, 0.9], [0.9, 0.1, 0.1], [0.2, 0.5, 0.9], [1.0, 0.0, 0.5]] {
            assert_eq!(coefficients(rgb), RgbToSpectrumTable::srgb().lookup(rgb));
        }
    }

    /// A path joined from two terminated subpaths carries the factor (4, 0, 0, 0) once.
    #[test]
    fn joined_paths_carry_the_factor_once() {
        let mut a = Wavelengths::sample(0.3);
        let mut b = a;
        let (fa, fb) = (a.terminate_secondary().unwrap(), b.terminate_secondary().unwrap());
        let factor = Color::from_lanes([4.0, 0.0, 0.0, 0.0]);
        assert_eq!(joined(fa * fb, true, true), factor);
        assert_eq!(joined(fa * Color::ONE, true, false), factor);
        assert_eq!(joined(Color::ONE, false, false), Color::ONE);
    }

    #[test]
    fn termination_keeps_the_hero_once() {
        let mut wl = Wavelengths::sample(0.3);
        assert_eq!(wl.terminate_secondary(), Some(Color::from_lanes([4.0, 0.0, 0.0, 0.0])));
        assert_eq!(wl.terminate_secondary(), None);
        assert!(wl.secondary_terminated());
    }
}
