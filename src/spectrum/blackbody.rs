//! Black-body emission (Planck's law) at sampled wavelengths, in Mitsuba 3's units and range
//! (its `blackbody` spectrum): spectral radiance in W / (m^2 sr nm), unnormalised, zero outside
//! [lambda_min, lambda_max] (360-830 nm by default). pbrt-v4 instead divides by the peak value;
//! caustic follows Mitsuba so that Mitsuba scenes keep their brightness.

use super::planck;
use super::sampled::{LAMBDA_MAX, LAMBDA_MIN};

/// Wien's displacement constant b (CODATA 2018), m K: the peak of Planck's law in wavelength
/// is at b / T.
pub const WIEN_B: f64 = 2.897_771_955e-3;

/// What is wrong with a black body's parameters (user input).
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum BlackbodyError {
    #[error("a black body needs a positive, finite temperature in kelvin, found {0}")]
    Temperature(f32),
    #[error("a black body's wavelength range must be 0 < lambda_min < lambda_max, found {0}..{1} nm")]
    Range(f32, f32),
}

/// A black body at a temperature, emitting over a wavelength range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Blackbody {
    kelvin: f32,
    lambda_min: f32,
    lambda_max: f32,
}

impl Blackbody {
    /// Over 360-830 nm, Mitsuba's default range.
    pub fn new(kelvin: f32) -> Result<Blackbody, BlackbodyError> {
        Self::with_range(kelvin, LAMBDA_MIN, LAMBDA_MAX)
    }

    pub fn with_range(kelvin: f32, lambda_min: f32, lambda_max: f32) -> Result<Blackbody, BlackbodyError> {
        if !(kelvin.is_finite() && kelvin > 0.0) {
            return Err(BlackbodyError::Temperature(kelvin));
        }
        if !(lambda_min.is_finite() && lambda_max.is_finite() && lambda_min > 0.0 && lambda_max > lambda_min) {
            return Err(BlackbodyError::Range(lambda_min, lambda_max));
        }
        Ok(Blackbody { kelvin, lambda_min, lambda_max })
    }

    pub fn kelvin(&self) -> f32 {
        self.kelvin
    }

    /// Where the spectrum peaks (Wien), nm; it may lie outside the emitted range.
    pub fn peak_wavelength(&self) -> f32 {
        (WIEN_B / self.kelvin as f64 * 1e9) as f32
    }

    /// Spectral radiance at `lambda` nm, W / (m^2 sr nm); zero outside the range. Evaluated in
    /// f64: the exponent's argument reaches ~1e3 for cold bodies at short wavelengths.
    #[inline]
    pub fn eval(&self, lambda: f32) -> f32 {
        if !(self.lambda_min..=self.lambda_max).contains(&lambda) {
            return 0.0;
        }
        planck(self.kelvin as f64, lambda as f64) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Planck's law written out here (h, c, k from CODATA 2018, exact SI values): the
    /// renderer's radiance per nm must match it. Mitsuba's CODATA 2014 constants differ by up to
    /// 1.3e-5 relative where the exponent is large (1000 K at 360 nm).
    fn closed_form(t: f64, nm: f64) -> f64 {
        let (h, c, k) = (6.626_070_15e-34, 299_792_458.0, 1.380_649e-23);
        let l = nm * 1e-9;
        2.0 * h * c * c / l.powi(5) / ((h * c / (l * k * t)).exp() - 1.0) * 1e-9
    }

    #[test]
    fn matches_plancks_law_in_mitsubas_units() {
        for t in [1000.0f32, 2700.0, 5000.0, 6500.0, 12000.0] {
            let b = Blackbody::new(t).unwrap();
            for nm in [360.0f32, 450.0, 555.0, 700.0, 830.0] {
                let want = closed_form(t as f64, nm as f64);
                assert!((b.eval(nm) as f64 / want - 1.0).abs() < 3e-5, "{t} K at {nm} nm: {} vs {want}", b.eval(nm));
            }
        }
        // A spot value: 5000 K at 500 nm is 1.2106e4 W / (m^2 sr nm) (2hc^2 / l^5 / (e^x - 1)).
        assert!((Blackbody::new(5000.0).unwrap().eval(500.0) / 1.2106e4 - 1.0).abs() < 1e-3);
        let narrow = Blackbody::with_range(5000.0, 400.0, 700.0).unwrap();
        assert_eq!((narrow.eval(399.0), narrow.eval(701.0)), (0.0, 0.0));
    }

    /// The maximum over wavelength sits where Wien's displacement law puts it, for bodies
    /// whose peak is in the visible range.
    #[test]
    fn peaks_at_wiens_wavelength() {
        for t in [3700.0f32, 4500.0, 5600.0, 6500.0, 7500.0] {
            let b = Blackbody::new(t).unwrap();
            let peak = b.peak_wavelength();
            let argmax =
                (0..=47_000).map(|i| 360.0 + i as f32 * 0.01).max_by(|x, y| b.eval(*x).total_cmp(&b.eval(*y))).unwrap();
            assert!((argmax - peak).abs() < 0.1, "{t} K: max at {argmax}, Wien {peak}");
            assert!(b.eval(peak * 0.99) < b.eval(peak) && b.eval(peak * 1.01) < b.eval(peak));
        }
    }

    #[test]
    fn bad_parameters_are_refused() {
        assert_eq!(Blackbody::new(0.0), Err(BlackbodyError::Temperature(0.0)));
        assert!(Blackbody::new(f32::NAN).is_err());
        assert_eq!(Blackbody::with_range(5000.0, 700.0, 400.0), Err(BlackbodyError::Range(700.0, 400.0)));
        assert!(Blackbody::with_range(5000.0, 0.0, 400.0).is_err());
    }
}
