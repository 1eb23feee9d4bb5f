//! Validating value types for scene files: each rejects what cannot render (NaN, infinity,
//! negative sizes, zero-length directions) while deserializing, so the TOML reader attaches the
//! exact line and column of the bad value to the error.

use crate::math::{Color, Vec3};
use serde::de::{Deserialize, Deserializer, Error};

fn finite<'de, D: Deserializer<'de>>(d: D) -> Result<f32, D::Error> {
    let v = f64::deserialize(d)?;
    if !v.is_finite() {
        return Err(D::Error::custom(format!("expected a finite number, found {v}")));
    }
    if v.abs() > f32::MAX as f64 {
        return Err(D::Error::custom(format!("number {v} is too large")));
    }
    Ok(v as f32)
}

/// Any finite number.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Finite(pub f32);
impl<'de> Deserialize<'de> for Finite {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        finite(d).map(Finite)
    }
}

/// A finite number > 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Positive(pub f32);
impl<'de> Deserialize<'de> for Positive {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = finite(d)?;
        if v > 0.0 { Ok(Positive(v)) } else { Err(D::Error::custom(format!("expected a positive number, found {v}"))) }
    }
}

/// A finite number >= 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NonNegative(pub f32);
impl<'de> Deserialize<'de> for NonNegative {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = finite(d)?;
        if v >= 0.0 { Ok(NonNegative(v)) } else { Err(D::Error::custom(format!("expected a number >= 0, found {v}"))) }
    }
}

/// A number in [0, 1].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Unit(pub f32);
impl<'de> Deserialize<'de> for Unit {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = finite(d)?;
        if (0.0..=1.0).contains(&v) {
            Ok(Unit(v))
        } else {
            Err(D::Error::custom(format!("expected a number from 0 to 1, found {v}")))
        }
    }
}

fn vec3<'de, D: Deserializer<'de>>(d: D) -> Result<Vec3, D::Error> {
    let a = <[f64; 3]>::deserialize(d)?;
    if let Some(bad) = a.iter().find(|v| !v.is_finite() || v.abs() > f32::MAX as f64) {
        return Err(D::Error::custom(format!("expected three finite numbers, found {bad}")));
    }
    Ok(Vec3::new(a[0] as f32, a[1] as f32, a[2] as f32))
}

/// A point or offset: three finite numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point(pub Vec3);
impl<'de> Deserialize<'de> for Point {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        vec3(d).map(Point)
    }
}

/// A direction: three finite numbers, not all zero; normalised.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Direction(pub Vec3);
impl<'de> Deserialize<'de> for Direction {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = vec3(d)?;
        // Scale to the largest component first, so huge vectors do not overflow when squared.
        let m = v.abs().max_element();
        let n = if m > 0.0 { (v / m).normalize_or_zero() } else { Vec3::ZERO };
        if n == Vec3::ZERO || !n.is_finite() {
            return Err(D::Error::custom("expected a direction, found a zero-length vector"));
        }
        Ok(Direction(n))
    }
}

/// An RGB colour: three finite numbers >= 0, or one number for grey.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rgb(pub Color);
impl<'de> Deserialize<'de> for Rgb {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(serde::Deserialize)]
        #[serde(untagged)]
        enum Raw {
            Grey(f64),
            Rgb([f64; 3]),
        }
        let raw =
            Raw::deserialize(d).map_err(|_| D::Error::custom("expected a colour: [r, g, b] or a single number"))?;
        checked_rgb(match raw {
            Raw::Grey(g) => [g; 3],
            Raw::Rgb(a) => a,
        })
        .map(Rgb)
    }
}

/// A spectrum written in a scene file where a colour may be: `{ spectrum = [[nm, value], ...] }`
/// (samples, linear between them), `{ spectrum = "file.spd" }` (a file of wavelength-value lines,
/// found beside the scene) or `{ blackbody = kelvin }` (Planck's law, in Mitsuba's units). RGB
/// mode renders its colour, spectral mode the spectrum itself (docs/scene-format.md).
#[derive(Clone, Debug, PartialEq)]
pub enum SpectrumSpec {
    Samples(Vec<(f64, f64)>),
    File(String),
    Blackbody(f64),
}

/// The table form of a spectrum, before it is checked.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct SpectrumTable {
    spectrum: Option<SpectrumValues>,
    blackbody: Option<f64>,
}

#[derive(serde::Deserialize)]
#[serde(untagged)]
enum SpectrumValues {
    File(String),
    Samples(Vec<[f64; 2]>),
}

const SPECTRUM_FORMS: &str = "{ spectrum = [[nm, value], ...] }, { spectrum = \"file.spd\" } or { blackbody = kelvin }";

impl SpectrumTable {
    fn check<E: Error>(self) -> Result<SpectrumSpec, E> {
        match (self.spectrum, self.blackbody) {
            (Some(SpectrumValues::File(f)), None) => Ok(SpectrumSpec::File(f)),
            (Some(SpectrumValues::Samples(pairs)), None) => {
                if let Some(bad) = pairs.iter().flatten().find(|v| !v.is_finite()) {
                    return Err(E::custom(format!("spectrum values must be finite, found {bad}")));
                }
                Ok(SpectrumSpec::Samples(pairs.into_iter().map(|[w, v]| (w, v)).collect()))
            }
            (None, Some(t)) if t.is_finite() && t > 0.0 => Ok(SpectrumSpec::Blackbody(t)),
            (None, Some(t)) => Err(E::custom(format!("a black body needs a temperature in kelvin > 0, found {t}"))),
            (Some(_), Some(_)) => Err(E::custom("give `spectrum` or `blackbody`, not both")),
            (None, None) => Err(E::custom(format!("a spectrum is written {SPECTRUM_FORMS}"))),
        }
    }
}

/// Three finite components >= 0 as a colour.
fn checked_rgb<E: Error>(a: [f64; 3]) -> Result<Color, E> {
    if let Some(bad) = a.iter().find(|v| !v.is_finite() || **v < 0.0 || v.abs() > f32::MAX as f64) {
        return Err(E::custom(format!("colour components must be finite and >= 0, found {bad}")));
    }
    Ok(Color::new(a[0] as f32, a[1] as f32, a[2] as f32))
}

/// A colour or a spectrum as written, before it is checked.
#[derive(serde::Deserialize)]
#[serde(untagged)]
enum RawColour {
    Grey(f64),
    Rgb([f64; 3]),
    Table(SpectrumTable),
}

impl RawColour {
    fn check<E: Error>(self) -> Result<ColorSpec, E> {
        match self {
            RawColour::Grey(g) => checked_rgb([g; 3]).map(ColorSpec::Rgb),
            RawColour::Rgb(a) => checked_rgb(a).map(ColorSpec::Rgb),
            RawColour::Table(t) => t.check().map(ColorSpec::Spectrum),
        }
    }
}

/// A colour or a spectrum (`SpectrumSpec`): what lights and emitting objects take.
#[derive(Clone, Debug, PartialEq)]
pub enum ColorSpec {
    Rgb(Color),
    Spectrum(SpectrumSpec),
}
impl<'de> Deserialize<'de> for ColorSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        RawColour::deserialize(d)
            .map_err(|_| {
                D::Error::custom(format!(
                    "expected a colour ([r, g, b] or a single number) or a spectrum ({SPECTRUM_FORMS})"
                ))
            })?
            .check()
    }
}

/// A colour, a spectrum (`SpectrumSpec`) or the name of a texture giving it.
#[derive(Clone, Debug, PartialEq)]
pub enum ColorOrTexture {
    Color(Color),
    Spectrum(SpectrumSpec),
    Texture(String),
}
impl<'de> Deserialize<'de> for ColorOrTexture {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(serde::Deserialize)]
        #[serde(untagged)]
        enum Raw {
            Name(String),
            Value(RawColour),
        }
        let raw = Raw::deserialize(d).map_err(|_| {
            D::Error::custom(format!(
                "expected a colour ([r, g, b] or a single number), a spectrum ({SPECTRUM_FORMS}) or a texture's name"
            ))
        })?;
        Ok(match raw {
            Raw::Name(n) => ColorOrTexture::Texture(n),
            Raw::Value(v) => match v.check()? {
                ColorSpec::Rgb(c) => ColorOrTexture::Color(c),
                ColorSpec::Spectrum(s) => ColorOrTexture::Spectrum(s),
            },
        })
    }
}

/// A number >= 0 or the name of a texture giving it.
#[derive(Clone, Debug, PartialEq)]
pub enum NumberOrTexture {
    Number(f32),
    Texture(String),
}
impl<'de> Deserialize<'de> for NumberOrTexture {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(serde::Deserialize)]
        #[serde(untagged)]
        enum Raw {
            Name(String),
            Number(f64),
        }
        let raw = Raw::deserialize(d).map_err(|_| D::Error::custom("expected a number or a texture's name"))?;
        match raw {
            Raw::Name(n) => Ok(NumberOrTexture::Texture(n)),
            Raw::Number(v) if v.is_finite() && v >= 0.0 && v <= f32::MAX as f64 => {
                Ok(NumberOrTexture::Number(v as f32))
            }
            Raw::Number(v) => Err(D::Error::custom(format!("expected a finite number >= 0, found {v}"))),
        }
    }
}

/// Two finite numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pair(pub crate::math::Vec2);
impl<'de> Deserialize<'de> for Pair {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let a = <[f64; 2]>::deserialize(d).map_err(|_| D::Error::custom("expected two numbers [u, v]"))?;
        if let Some(bad) = a.iter().find(|v| !v.is_finite() || v.abs() > f32::MAX as f64) {
            return Err(D::Error::custom(format!("expected finite numbers, found {bad}")));
        }
        Ok(Pair(crate::math::Vec2::new(a[0] as f32, a[1] as f32)))
    }
}

/// A per-axis or uniform scale: one number or three, none zero.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scale(pub Vec3);
impl<'de> Deserialize<'de> for Scale {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(serde::Deserialize)]
        #[serde(untagged)]
        enum Raw {
            Uniform(f64),
            Axes([f64; 3]),
        }
        let raw = Raw::deserialize(d).map_err(|_| D::Error::custom("expected a scale: a number or [x, y, z]"))?;
        let a = match raw {
            Raw::Uniform(s) => [s; 3],
            Raw::Axes(a) => a,
        };
        if let Some(bad) = a.iter().find(|v| !v.is_finite() || **v == 0.0 || v.abs() > f32::MAX as f64) {
            return Err(D::Error::custom(format!("scale factors must be finite and non-zero, found {bad}")));
        }
        Ok(Scale(Vec3::new(a[0] as f32, a[1] as f32, a[2] as f32)))
    }
}
