//! Index of refraction as a function of wavelength, for dispersive dielectrics: Cauchy's and
//! Sellmeier's formulas and a table of named glasses and crystals.
//!
//! Both formulas take the wavelength in micrometres, as catalogues state their coefficients:
//! Cauchy n = A + B / l^2 + C / l^4; Sellmeier n^2 = 1 + sum_i B_i l^2 / (l^2 - C_i), C_i in
//! um^2. The reference wavelength is the helium d line, 587.5618 nm, where catalogues give n_d;
//! the Abbe number V_d = (n_d - 1) / (n_F - n_C) uses the hydrogen F (486.1327 nm) and C
//! (656.2725 nm) lines.
//!
//! The named materials and Mitsuba's single numbers: the RGB mode reads Mitsuba's `int_ior`
//! names (`src/scene/mitsuba/props.rs`, values from Hecht's *Optics* at about 589 nm) and keeps
//! them, so that RGB renders match Mitsuba. Its numbers are not all n_d of these formulas, and
//! the spectral table does not try to reproduce them:
//!
//! | name here      | n_d (formula) | Mitsuba name and number | difference |
//! |----------------|---------------|-------------------------|------------|
//! | `bk7`          | 1.5168        | `bk7` 1.5046            | -0.0122 (Mitsuba's is BK7 near 1.2 um, not n_d) |
//! | `fused silica` | 1.4585        | `fused quartz` 1.458    | -0.0005    |
//! | `dense flint`  | 1.7847        | none                    |            |
//! | `diamond`      | 2.4175        | `diamond` 2.419         | +0.0015    |
//! | `water`        | 1.3334        | `water` 1.3330          | -0.0004    |
//!
//! (checked by `tests::mitsuba_numbers_differ_as_documented`).

/// The helium d, hydrogen F and hydrogen C lines, nm.
pub const LAMBDA_D: f32 = 587.5618;
pub const LAMBDA_F: f32 = 486.1327;
pub const LAMBDA_C: f32 = 656.2725;

/// An index of refraction over wavelength. Small and `Copy`; evaluation allocates nothing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Dispersion {
    /// The same index at every wavelength (not dispersive).
    Constant(f32),
    /// n = a + b / l^2 + c / l^4, l in um.
    Cauchy { a: f32, b: f32, c: f32 },
    /// n^2 = 1 + sum_i b_i l^2 / (l^2 - c_i), l in um, c_i in um^2. Glass catalogues give three
    /// terms; the fourth (zero for them) is for water's four-term fit.
    Sellmeier { b: [f32; 4], c: [f32; 4] },
}

/// What is wrong with dispersion coefficients (user input).
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum DispersionError {
    #[error("dispersion coefficients must be finite numbers")]
    NotFinite,
    #[error("the index of refraction must be at least 1 over 360-830 nm, but it is {n} at {lambda} nm")]
    BelowOne { n: f32, lambda: f32 },
    #[error("a Sellmeier term has a resonance (C = {0} um^2) inside 360-830 nm")]
    Resonance(f32),
    #[error("a Sellmeier formula takes 1 to 4 (B, C) pairs, found {0}")]
    Terms(usize),
    #[error("unknown glass `{0}`; known: bk7, fused silica, dense flint, diamond, water")]
    UnknownName(String),
}

impl Dispersion {
    /// Cauchy's formula, checked to give n >= 1 over the visible range.
    pub fn cauchy(a: f32, b: f32, c: f32) -> Result<Dispersion, DispersionError> {
        Dispersion::Cauchy { a, b, c }.checked(&[a, b, c])
    }

    /// Sellmeier's formula with 1 to 4 (B, C) terms, checked to have no resonance in, and n >= 1
    /// over, the visible range.
    pub fn sellmeier(b: &[f32], c: &[f32]) -> Result<Dispersion, DispersionError> {
        if b.len() != c.len() || b.is_empty() || b.len() > 4 {
            return Err(DispersionError::Terms(b.len().max(c.len())));
        }
        if let Some(&ci) = c.iter().find(|&&ci| (0.36f32 * 0.36..=0.83 * 0.83).contains(&ci)) {
            return Err(DispersionError::Resonance(ci));
        }
        let (mut bb, mut cc) = ([0.0; 4], [0.0; 4]);
        bb[..b.len()].copy_from_slice(b);
        cc[..c.len()].copy_from_slice(c);
        Dispersion::Sellmeier { b: bb, c: cc }.checked(&[b, c].concat())
    }

    fn checked(self, coefficients: &[f32]) -> Result<Dispersion, DispersionError> {
        if !coefficients.iter().all(|v| v.is_finite()) {
            return Err(DispersionError::NotFinite);
        }
        for i in 0..=47 {
            let lambda = 360.0 + 10.0 * i as f32;
            let n = self.eval(lambda);
            if !(n >= 1.0) {
                return Err(DispersionError::BelowOne { n, lambda });
            }
        }
        Ok(self)
    }

    /// A named material from the table in the module doc (case-insensitive).
    pub fn named(name: &str) -> Result<Dispersion, DispersionError> {
        let lower = name.to_ascii_lowercase();
        NAMED
            .iter()
            .find(|(n, _)| *n == lower)
            .map(|(_, d)| *d)
            .ok_or_else(|| DispersionError::UnknownName(name.to_string()))
    }

    /// The index at `lambda` nm.
    #[inline]
    pub fn eval(&self, lambda: f32) -> f32 {
        let l2 = (lambda * 1e-3) * (lambda * 1e-3);
        match *self {
            Dispersion::Constant(n) => n,
            Dispersion::Cauchy { a, b, c } => a + b / l2 + c / (l2 * l2),
            Dispersion::Sellmeier { b, c } => {
                let mut n2 = 1.0;
                for i in 0..4 {
                    n2 += b[i] * l2 / (l2 - c[i]);
                }
                n2.max(0.0).sqrt()
            }
        }
    }

    /// Whether the index changes with wavelength: a refraction through it must keep only the
    /// hero wavelength (`Wavelengths::terminate_secondary`).
    pub fn is_dispersive(&self) -> bool {
        !matches!(self, Dispersion::Constant(_))
    }

    /// n at the d line: the single number an RGB render would use.
    pub fn n_d(&self) -> f32 {
        self.eval(LAMBDA_D)
    }

    /// The Abbe number V_d (infinite for a constant index).
    pub fn abbe_number(&self) -> f32 {
        (self.n_d() - 1.0) / (self.eval(LAMBDA_F) - self.eval(LAMBDA_C))
    }
}

/// Named materials, Sellmeier coefficients as their sources give them (l in um, C in um^2), with
/// all their published digits, more than `f32` keeps.
#[allow(clippy::excessive_precision)]
const NAMED: &[(&str, Dispersion)] = &[
    // Schott N-BK7 borosilicate crown, Schott optical glass data sheet (2014): n_d 1.5168,
    // V_d 64.17.
    (
        "bk7",
        Dispersion::Sellmeier {
            b: [1.039_612_1, 0.231_792_34, 1.010_469_5, 0.0],
            c: [0.006_000_698_7, 0.020_017_914, 103.560_65, 0.0],
        },
    ),
    // Fused silica, I. H. Malitson, "Interspecimen comparison of the refractive index of fused
    // silica", J. Opt. Soc. Am. 55, 1205 (1965), at 20 C: resonances at 0.0684043, 0.1162414
    // and 9.896161 um (squared here); n_d 1.4585, V_d 67.8.
    (
        "fused silica",
        Dispersion::Sellmeier {
            b: [0.696_166_3, 0.407_942_6, 0.897_479_4, 0.0],
            c: [0.004_679_148, 0.013_512_063, 97.934_00, 0.0],
        },
    ),
    // Schott N-SF11 dense flint, Schott optical glass data sheet (2014): n_d 1.78472, V_d 25.68.
    (
        "dense flint",
        Dispersion::Sellmeier {
            b: [1.737_597, 0.313_747_35, 1.898_781, 0.0],
            c: [0.013_188_707, 0.062_306_814, 155.236_29, 0.0],
        },
    ),
    // Diamond, F. Peter, "Ueber Brechungsindizes und Absorptionskonstanten des Diamanten
    // zwischen 644 und 226 mu", Z. Phys. 15, 358 (1923), two-term Sellmeier: n_D 2.417, V_d ~55.
    ("diamond", Dispersion::Sellmeier { b: [0.3306, 4.3356, 0.0, 0.0], c: [0.030_625, 0.011_236, 0.0, 0.0] }),
    // Water at 20 C, M. Daimon and A. Masumura, "Measurement of the refractive index of
    // distilled water from the near-infrared region to the ultraviolet region", Appl. Opt. 46,
    // 3811 (2007), four-term fit: n_D 1.333, V_d ~55.7.
    (
        "water",
        Dispersion::Sellmeier {
            b: [0.568_402_76, 0.172_617_74, 0.020_861_896, 0.113_074_87],
            c: [0.005_101_829_7, 0.018_211_539, 0.026_207_223, 10.697_927],
        },
    ),
];

#[cfg(test)]
mod tests {
    use super::*;

    /// Catalogue n_d and V_d (sources in `NAMED`).
    #[test]
    fn named_glasses_match_their_catalogues() {
        for (name, n_d, v_d, v_tolerance) in [
            ("bk7", 1.5168, 64.17, 0.1),
            ("fused silica", 1.4585, 67.82, 0.2),
            ("dense flint", 1.78472, 25.68, 0.1),
            ("diamond", 2.417, 55.3, 1.0),
            ("water", 1.333, 55.7, 1.0),
        ] {
            let d = Dispersion::named(name).unwrap();
            assert!((d.n_d() - n_d).abs() < 1e-3, "{name}: n_d {} vs {n_d}", d.n_d());
            assert!((d.abbe_number() - v_d).abs() < v_tolerance, "{name}: V_d {} vs {v_d}", d.abbe_number());
            // Normal dispersion: blue bends more than red.
            assert!(d.eval(400.0) > d.eval(550.0) && d.eval(550.0) > d.eval(700.0), "{name}");
            assert!(d.is_dispersive());
        }
        assert_eq!(Dispersion::named("BK7"), Dispersion::named("bk7"));
        assert!(matches!(Dispersion::named("unobtainium"), Err(DispersionError::UnknownName(_))));
    }

    #[test]
    fn mitsuba_numbers_differ_as_documented() {
        for (name, mitsuba, difference) in [
            ("bk7", 1.5046, -0.0122),
            ("fused silica", 1.458, -0.0005),
            ("diamond", 2.419, 0.0015),
            ("water", 1.3330, -0.0004),
        ] {
            let n_d = Dispersion::named(name).unwrap().n_d();
            assert!((mitsuba - n_d - difference).abs() < 1e-4, "{name}: {n_d} vs Mitsuba's {mitsuba}");
        }
    }

    #[test]
    fn cauchy_and_constant_forms() {
        // Cauchy's classic BK7-like fit: A 1.5046, B 0.00420 um^2.
        let d = Dispersion::cauchy(1.5046, 0.004_20, 0.0).unwrap();
        assert!((d.eval(500.0) - (1.5046 + 0.0042 / 0.25)).abs() < 1e-6);
        assert!(d.abbe_number() > 0.0 && d.is_dispersive());
        let c = Dispersion::Constant(1.5);
        assert_eq!((c.eval(400.0), c.eval(800.0), c.is_dispersive()), (1.5, 1.5, false));
        assert!(c.abbe_number().is_infinite());
    }

    #[test]
    #[allow(clippy::excessive_precision)]
    fn bad_coefficients_are_refused() {
        assert_eq!(Dispersion::cauchy(f32::NAN, 0.0, 0.0), Err(DispersionError::NotFinite));
        assert!(matches!(Dispersion::cauchy(0.5, 0.0, 0.0), Err(DispersionError::BelowOne { .. })));
        assert_eq!(Dispersion::sellmeier(&[1.0], &[0.25]), Err(DispersionError::Resonance(0.25)));
        assert_eq!(Dispersion::sellmeier(&[1.0, 2.0], &[0.01]), Err(DispersionError::Terms(2)));
        assert_eq!(Dispersion::sellmeier(&[], &[]), Err(DispersionError::Terms(0)));
        let b = Dispersion::sellmeier(
            &[1.039_612_1, 0.231_792_34, 1.010_469_5],
            &[0.006_000_698_7, 0.020_017_914, 103.560_65],
        );
        assert_eq!(b, Dispersion::named("bk7"));
    }
}
