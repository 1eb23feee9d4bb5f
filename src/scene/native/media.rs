//! The `[media.NAME]` section of a TOML scene: participating media, which objects bound with
//! `interior` / `exterior` and the camera may sit in (`[camera] medium`).

use super::Cx;
use super::schema::TransformOp;
use crate::geometry::Transform;
use crate::math::Color;
use crate::medium::{Heterogeneous, Homogeneous, Medium, MediumInterface, Phase, Volume, VolumeData};
use crate::scene::SceneError;
use crate::scene::builder::SceneBuilder;
use crate::scene::de::{Finite, NonNegative, Rgb};
use crate::scene::footprint::FileKind;
use serde::Deserialize;
use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use std::collections::HashMap;
use std::path::PathBuf;
use toml::Spanned;
use toml::de::DeValue;

/// Each kind of medium and its keys.
pub const MEDIUM_KINDS: &[(&str, &[&str])] = &[
    ("homogeneous", &["sigma_t", "albedo", "sigma_a", "sigma_s", "scale", "phase", "g"]),
    ("heterogeneous", &["sigma_t", "albedo", "scale", "phase", "g", "transform"]),
];

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct HeterogeneousDesc {
    sigma_t: Option<VolumeValue>,
    albedo: Option<VolumeValue>,
    scale: Option<NonNegative>,
    phase: Option<Spanned<String>>,
    g: Option<Spanned<Finite>>,
    transform: Option<Vec<TransformOp>>,
}

/// A heterogeneous medium's quantity: a number, an `[r, g, b]`, or `{ file = "x.vol" }`.
enum VolumeValue {
    Constant(Color),
    File(PathBuf),
}

impl<'de> Deserialize<'de> for VolumeValue {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        const EXPECTED: &str = "a number, [r, g, b] or { file = \"grid.vol\" }";
        impl<'de> Visitor<'de> for V {
            type Value = VolumeValue;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(EXPECTED)
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<VolumeValue, E> {
                finite_colour([v; 3])
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<VolumeValue, E> {
                finite_colour([v as f64; 3])
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<VolumeValue, E> {
                finite_colour([v as f64; 3])
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<VolumeValue, A::Error> {
                let mut c = Vec::new();
                while let Some(x) = seq.next_element::<f64>()? {
                    c.push(x);
                }
                match c.as_slice() {
                    &[r, g, b] => finite_colour([r, g, b]),
                    _ => Err(de::Error::custom(format!("expected {EXPECTED}, found {} numbers", c.len()))),
                }
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<VolumeValue, A::Error> {
                let mut file = None;
                while let Some(key) = map.next_key::<String>()? {
                    if key != "file" {
                        return Err(de::Error::custom(format!(
                            "unknown key `{key}`; a grid is {{ file = \"grid.vol\" }}"
                        )));
                    }
                    file = Some(map.next_value::<PathBuf>()?);
                }
                file.map(VolumeValue::File).ok_or_else(|| de::Error::custom("a grid needs `file`, a .vol file"))
            }
        }
        d.deserialize_any(V)
    }
}

/// A constant quantity, kept as written when finite (the medium's checks name values out of
/// range).
fn finite_colour<E: de::Error>(c: [f64; 3]) -> Result<VolumeValue, E> {
    if let Some(bad) = c.iter().find(|v| !v.is_finite() || v.abs() > f32::MAX as f64) {
        return Err(E::custom(format!("values must be finite numbers, found {bad}")));
    }
    Ok(VolumeValue::Constant(Color::new(c[0] as f32, c[1] as f32, c[2] as f32)))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MediumDesc {
    sigma_t: Option<Rgb>,
    albedo: Option<Rgb>,
    sigma_a: Option<Rgb>,
    sigma_s: Option<Rgb>,
    scale: Option<NonNegative>,
    phase: Option<Spanned<String>>,
    g: Option<Spanned<Finite>>,
}

/// The media of a scene by name.
pub type MediumNames = HashMap<String, u32>;

impl<'a> Cx<'a> {
    /// Step 3c: named media.
    pub(super) fn media(
        &self,
        value: Option<Spanned<DeValue<'a>>>,
        geometry: &mut SceneBuilder,
    ) -> Result<MediumNames, SceneError> {
        let mut names = MediumNames::new();
        let Some(v) = value else { return Ok(names) };
        let span = v.span();
        let DeValue::Table(table) = v.into_inner() else {
            return Err(self.at(span, "`media` must be a table of named media ([media.NAME])"));
        };
        for (name, value) in table {
            let span = value.span();
            let (kind, value) = self.tagged(value, "medium", MEDIUM_KINDS)?;
            if kind == "heterogeneous" {
                let d: HeterogeneousDesc = self.de(value)?;
                let phase = self.phase(d.phase.as_ref(), d.g.as_ref())?;
                let to_world = self.transform(&d.transform, span.clone())?;
                let named = |e: String| self.at(span.clone(), format!("medium `{}`: {e}", name.get_ref()));
                let sigma_t = self.volume(d.sigma_t, "sigma_t", Color::ONE, &to_world, span.clone())?;
                // A constant albedo is the same wherever its volume is placed.
                let albedo = match d.albedo {
                    None => Volume::constant(Color::splat(0.75)),
                    Some(VolumeValue::Constant(c)) => Volume::constant(c),
                    file => self.volume(file, "albedo", Color::splat(0.75), &to_world, span.clone())?,
                };
                let m = Heterogeneous::new(sigma_t, albedo, d.scale.map_or(1.0, |s| s.0), phase).map_err(named)?;
                let i = geometry.add_medium(Medium::Heterogeneous(m));
                names.insert(name.get_ref().to_string(), i);
                continue;
            }
            let d: MediumDesc = self.de(value)?;
            let (sigma_t, albedo) = match (d.sigma_t, d.albedo, d.sigma_a, d.sigma_s) {
                (t, a, None, None) => (t.map_or(Color::ONE, |c| c.0), a.map_or(Color::splat(0.75), |c| c.0)),
                (None, None, a, s) => {
                    let (a, s) = (a.map_or(Color::ZERO, |c| c.0), s.map_or(Color::ZERO, |c| c.0));
                    let t = a + s;
                    let ratio = |s: f32, t: f32| if t > 0.0 { s / t } else { 0.0 };
                    (t, Color::new(ratio(s.r(), t.r()), ratio(s.g(), t.g()), ratio(s.b(), t.b())))
                }
                _ => {
                    return Err(self.at(
                        span,
                        format!(
                            "medium `{}`: give sigma_t and albedo, or sigma_a and sigma_s, not a mix",
                            name.get_ref()
                        ),
                    ));
                }
            };
            let phase = self.phase(d.phase.as_ref(), d.g.as_ref())?;
            let scale = d.scale.map_or(1.0, |s| s.0);
            let m = Homogeneous::new(sigma_t * scale, albedo, phase)
                .map_err(|e| self.at(span.clone(), format!("medium `{}`: {e}", name.get_ref())))?;
            let i = geometry.add_medium(Medium::Homogeneous(m));
            names.insert(name.get_ref().to_string(), i);
        }
        Ok(names)
    }

    /// A medium's phase function from its `phase` and `g` keys.
    fn phase(&self, phase: Option<&Spanned<String>>, g: Option<&Spanned<Finite>>) -> Result<Phase, SceneError> {
        Ok(match phase.map(|p| p.get_ref().as_str()) {
            None | Some("isotropic") if g.is_none() => Phase::Isotropic,
            None | Some("hg") => Phase::HenyeyGreenstein { g: g.map_or(0.8, |g| g.get_ref().0) },
            Some("rayleigh") if g.is_none() => Phase::Rayleigh,
            Some(other @ ("isotropic" | "rayleigh")) => {
                let g = g.expect("g given");
                return Err(self.at(g.span(), format!("`g` belongs to the hg phase function, not `{other}`")));
            }
            Some(other) => {
                let p = phase.expect("phase given");
                return Err(
                    self.at(p.span(), format!("unknown phase function `{other}`; expected isotropic, hg or rayleigh"))
                );
            }
        })
    }

    /// A heterogeneous medium's quantity `name` (`default` when not given) placed by `to_world`:
    /// a constant, or a grid read from its file (relative to the scene's folder), whose errors
    /// name the file.
    fn volume(
        &self,
        value: Option<VolumeValue>,
        name: &str,
        default: Color,
        to_world: &Transform,
        span: std::ops::Range<usize>,
    ) -> Result<Volume, SceneError> {
        let data = match value {
            None => VolumeData::Constant(default),
            Some(VolumeValue::Constant(c)) => VolumeData::Constant(c),
            Some(VolumeValue::File(file)) => {
                let path = self.base.join(file);
                self.files.open(&path, FileKind::MediumGrid)?;
                let grid = crate::scene::volume_file::load_medium_grid(&path, name).map_err(|e| self.at(span, e))?;
                VolumeData::Grid(grid)
            }
        };
        Ok(Volume::placed(data, to_world))
    }

    /// The medium named `name`.
    pub(super) fn medium_named(&self, media: &MediumNames, name: &Spanned<String>) -> Result<u32, SceneError> {
        media.get(name.get_ref().as_str()).copied().ok_or_else(|| {
            let known = media.keys().map(String::as_str).collect();
            self.at(name.span(), super::no_such("medium", name.get_ref(), known))
        })
    }

    /// The media an object bounds, when it names any.
    pub(super) fn interface(
        &self,
        media: &MediumNames,
        interior: Option<&Spanned<String>>,
        exterior: Option<&Spanned<String>>,
    ) -> Result<Option<MediumInterface>, SceneError> {
        if interior.is_none() && exterior.is_none() {
            return Ok(None);
        }
        let side =
            |n: Option<&Spanned<String>>| n.map_or(Ok(crate::geometry::NO_MEDIUM), |n| self.medium_named(media, n));
        Ok(Some(MediumInterface { inside: side(interior)?, outside: side(exterior)? }))
    }
}
