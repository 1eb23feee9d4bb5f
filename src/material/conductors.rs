//! Complex indices of refraction of conductors by name, as Mitsuba 3 uses them. RGB mode takes
//! the colours of `TABLE`: the spectral data of Mitsuba's `data/ior` files reduced to linear sRGB
//! (negative channels clamped to 0), read from Mitsuba 3.9.1 (`scalar_rgb`) for each named
//! material. Spectral mode evaluates the measured spectra themselves (`conductor_spectra.rs`,
//! written by scripts/make_conductor_spectra.py) at each path's wavelengths, linearly between
//! the samples as Mitsuba's `scalar_spectral` does: lifting the colours back to smooth spectra
//! would lose the shape of gold's or copper's absorption edge.
//!
//! One departure: outside a material's measured range Mitsuba's spectra are zero (eta = k = 0,
//! which gives NaN reflectances there); here the nearest measured value holds. Only materials
//! measured over less than 360-830 nm (Li, Se, MgO, d-C, AlSb, ...) meet it.

use super::conductor_spectra::{MEASURED, NAMES};
use crate::math::Color;
use crate::spectrum::{LANES, Wavelengths};

/// A conductor's complex index eta + i k: the colours RGB mode uses and, for a metal given by
/// name, its measured spectra, which spectral mode uses instead.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ComplexIor {
    pub eta: Color,
    pub k: Color,
    pub measured: Option<Measured>,
}

impl ComplexIor {
    /// Given as colours (or a spectrum already turned into one): lifted as unbounded spectra in
    /// spectral mode.
    pub fn rgb(eta: Color, k: Color) -> Self {
        ComplexIor { eta, k, measured: None }
    }
}

/// The measured spectra of a named conductor (an index into `conductor_spectra.rs`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Measured(u8);

impl Measured {
    /// eta and k at the lanes' wavelengths.
    #[inline]
    pub fn at(self, wl: &Wavelengths) -> (Color, Color) {
        let m = &MEASURED[self.0 as usize];
        let mut eta = [0.0; LANES];
        let mut k = [0.0; LANES];
        for i in 0..LANES {
            (eta[i], k[i]) = interpolate(m.lambda, m.eta, m.k, wl.lambda(i));
        }
        (Color::from_lanes(eta), Color::from_lanes(k))
    }

    /// eta and k at `lambda` nm.
    pub fn eval(self, lambda: f32) -> (f32, f32) {
        let m = &MEASURED[self.0 as usize];
        interpolate(m.lambda, m.eta, m.k, lambda)
    }
}

/// Two spectra sampled at the same increasing wavelengths `l`, at `w`: linear between samples,
/// the end values outside them.
#[inline]
fn interpolate(l: &[f32], a: &[f32], b: &[f32], w: f32) -> (f32, f32) {
    let last = l.len() - 1;
    if !(w > l[0]) {
        return (a[0], b[0]);
    }
    if w >= l[last] {
        return (a[last], b[last]);
    }
    // The last sample at or below w.
    let i = l.partition_point(|&x| x <= w) - 1;
    let t = (w - l[i]) / (l[i + 1] - l[i]);
    (a[i] + (a[i + 1] - a[i]) * t, b[i] + (b[i + 1] - b[i]) * t)
}

/// (name, eta, k) per RGB channel.
const TABLE: &[(&str, [f32; 3], [f32; 3])] = &[
    ("Au", [0.143036, 0.375307, 1.44205], [3.983, 2.38556, 1.60336]),
    ("Ag", [0.155276, 0.116728, 0.138388], [4.82835, 3.12222, 2.1469]),
    ("Al", [1.6575, 0.880405, 0.521244], [9.22381, 6.2695, 4.837]),
    ("Cu", [0.201005, 0.92375, 1.10222], [3.91326, 2.45305, 2.14209]),
    ("Cu_palik", [0.213229, 0.919715, 1.10241], [3.92187, 2.45733, 2.13658]),
    ("Cr", [4.36967, 2.91651, 1.6549], [5.20655, 4.23131, 3.7547]),
    ("W", [4.37082, 3.30025, 2.99841], [3.50064, 2.60487, 2.27323]),
    ("Ni_palik", [2.3673, 1.66337, 1.46708], [4.49881, 3.05015, 2.34544]),
    ("Hg", [2.39894, 1.44003, 0.90957], [6.32759, 4.37192, 3.42176]),
    ("Ir", [3.0863, 2.08219, 1.61791], [5.59215, 4.06709, 3.26731]),
    ("Rh", [2.58579, 1.86022, 1.55426], [6.78226, 4.70299, 3.97607]),
    ("Mo", [4.48397, 3.52513, 2.77631], [4.11144, 3.42083, 3.15061]),
    ("Ta", [2.06272, 2.39294, 2.62793], [2.40836, 1.74149, 1.94703]),
    ("TiN", [1.64845, 1.15052, 1.37982], [3.36833, 1.9435, 1.10207]),
    ("Be", [4.18501, 3.18503, 2.78406], [3.83547, 3.01012, 2.86899]),
    ("K", [0.0640432, 0.0464098, 0.0381849], [2.1042, 1.34894, 0.913126]),
    ("Li", [0.265791, 0.195618, 0.220949], [3.54015, 2.31112, 1.66861]),
    ("Na_palik", [0.0602694, 0.0561409, 0.0619884], [3.17927, 2.11249, 1.57904]),
    ("Nb", [3.42007, 2.79009, 2.39563], [3.44139, 2.73767, 2.57975]),
    ("V_palik", [4.27758, 3.51295, 2.76107], [3.4913, 2.88945, 3.11152]),
    ("VC", [3.65757, 2.75274, 2.53267], [3.0683, 2.19869, 1.96319]),
    ("VN", [2.8656, 2.11919, 1.94009], [3.03224, 2.05612, 1.61631]),
    ("TiC", [3.70053, 2.83742, 2.58229], [3.26564, 2.35159, 2.17279]),
    ("HgTe", [4.77904, 3.2312, 2.6599], [1.63161, 1.58081, 1.72929]),
    ("Te", [7.39023, 4.4821, 2.63711], [3.25602, 3.52706, 3.29205]),
    ("Te-e", [7.50891, 4.29643, 2.36999], [5.58393, 4.94721, 3.99759]),
    ("Se", [4.05831, 2.84294, 2.82085], [0.75405, 0.638444, 0.521808]),
    ("Se-e", [5.72285, 4.16574, 4.08134], [0.871136, 1.10516, 1.56532]),
    ("SnTe", [4.52425, 1.98164, 1.28159], [0.0, 0.0, 0.0]),
    ("a-C", [2.94405, 2.22714, 1.96816], [0.887465, 0.799299, 0.81529]),
    ("d-C", [2.70872, 2.31883, 2.2289], [0.0, 0.0, 0.0]),
    ("Cu2O", [3.55177, 2.94987, 2.75188], [0.114207, 0.193897, 0.606134]),
    ("CuO", [3.24754, 2.44781, 2.21022], [0.52109, 0.570031, 0.722179]),
    ("CsI", [2.1449, 1.70232, 1.66243], [0.0, 0.0, 0.0]),
    ("MgO", [2.08958, 1.65072, 1.59488], [0.0, 0.0, 0.0]),
    ("AlAs", [3.6053, 3.23294, 2.21632], [0.000679437, 0.0, 0.00751271]),
    ("AlSb", [0.0, 4.13937, 4.66925], [0.0, 0.0940091, 1.30057]),
    ("SiC", [3.17234, 2.52597, 2.47937], [0.0, 0.0, 0.0]),
    ("ThF4", [1.83071, 1.44223, 1.38765], [0.0, 0.0, 0.0]),
    ("TiO2", [3.45661, 2.80174, 2.90517], [0.000105, 0.0, 0.000653]),
    ("TiO2-e", [3.10656, 2.51317, 2.58244], [2.98e-5, 0.0, 0.000183]),
];

/// Materials Mitsuba 3.9.1 knows without a `_palik` twin (checked by loading each name there).
const NO_PALIK: [&str; 6] = ["Au", "Ag", "Al", "Cr", "W", "a-C"];

/// The complex index of a named conductor; `none` is Mitsuba's perfect mirror (eta 0, k 1).
/// Names ending in `_palik` that Mitsuba's RGB variants give the same colours as the plain name
/// resolve to those colours; their measured spectra are their own files'.
pub fn lookup(name: &str) -> Option<ComplexIor> {
    if name == "none" {
        return Some(ComplexIor::rgb(Color::ZERO, Color::ONE));
    }
    let find = |n: &str| {
        TABLE.iter().find(|(m, _, _)| *m == n).map(|(_, e, k)| (Color::from_array(*e), Color::from_array(*k)))
    };
    let (eta, k) =
        find(name).or_else(|| name.strip_suffix("_palik").filter(|n| !NO_PALIK.contains(n)).and_then(find))?;
    let measured = NAMES.iter().find(|(n, _)| *n == name).map(|&(_, i)| Measured(i));
    Some(ComplexIor { eta, k, measured })
}

/// Every name `lookup` knows, for error messages.
pub fn names() -> impl Iterator<Item = &'static str> {
    std::iter::once("none").chain(TABLE.iter().map(|(n, _, _)| *n))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gold_and_the_mirror() {
        let gold = lookup("Au").unwrap();
        assert_eq!(gold.eta, Color::new(0.143036, 0.375307, 1.44205));
        assert_eq!(gold.k, Color::new(3.983, 2.38556, 1.60336));
        assert_eq!(lookup("none"), Some(ComplexIor::rgb(Color::ZERO, Color::ONE)));
        let rgb = |n: &str| lookup(n).map(|c| (c.eta, c.k));
        assert_eq!(rgb("TiO2_palik"), rgb("TiO2"));
        assert!(lookup("Ag_palik").is_none() && lookup("Au_palik").is_none());
        assert_ne!(rgb("Cu_palik"), rgb("Cu"));
        assert!(lookup("gold").is_none());
        assert!(names().count() > 30);
    }

    /// Every name of the RGB table has measured spectra, and every name Mitsuba's data has is
    /// in the RGB table (directly or through its `_palik` twin).
    #[test]
    fn every_named_metal_has_its_spectra() {
        for (name, _, _) in TABLE {
            assert!(lookup(name).unwrap().measured.is_some(), "{name}");
        }
        for (name, _) in NAMES {
            assert!(lookup(name).is_some_and(|c| c.measured.is_some()), "{name}");
        }
    }

    /// Gold's measured samples (Mitsuba's data/ior/Au.eta.spd and Au.k.spd) and the linear
    /// interpolation between them; the end values hold outside the measured range.
    #[test]
    fn gold_spectra_interpolate_linearly() {
        let gold = lookup("Au").unwrap().measured.unwrap();
        // The file's samples at 495.9367 and 506.0579 nm.
        let (a, b) = (gold.eval(495.936_7), gold.eval(506.057_86));
        let (eta, k) = gold.eval((495.936_7 + 506.057_86) / 2.0);
        assert!((eta - (a.0 + b.0) / 2.0).abs() < 1e-5 && (k - (a.1 + b.1) / 2.0).abs() < 1e-5);
        // Gold reflects red, absorbs blue: eta falls and k rises from 450 to 650 nm.
        let (blue, red) = (gold.eval(450.0), gold.eval(650.0));
        assert!(blue.0 > 1.0 && red.0 < 0.3 && red.1 > 3.0 && blue.1 < 2.0, "{blue:?} {red:?}");
        assert_eq!(gold.eval(100.0), gold.eval(200.0));
        assert_eq!(gold.eval(1000.0), gold.eval(2000.0));
        let wl = Wavelengths::single(650.0);
        assert_eq!(gold.at(&wl).0, Color::splat(red.0));
    }
}
