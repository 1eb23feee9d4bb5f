//! The `[media.NAME]` section of a TOML scene: participating media, which objects bound with
//! `interior` / `exterior` and the camera may sit in (`[camera] medium`).

use super::Cx;
use crate::math::Color;
use crate::medium::{Homogeneous, Medium, MediumInterface, Phase};
use crate::scene::SceneError;
use crate::scene::builder::SceneBuilder;
use crate::scene::de::{Finite, NonNegative, Rgb};
use serde::Deserialize;
use std::collections::HashMap;
use toml::Spanned;
use toml::de::DeValue;

/// Each kind of medium and its keys.
pub const MEDIUM_KINDS: &[(&str, &[&str])] =
    &[("homogeneous", &["sigma_t", "albedo", "sigma_a", "sigma_s", "scale", "phase", "g"])];

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
            let (_kind, value) = self.tagged(value, "medium", MEDIUM_KINDS)?;
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
            let phase = match d.phase.as_ref().map(|p| p.get_ref().as_str()) {
                None | Some("isotropic") if d.g.is_none() => Phase::Isotropic,
                None | Some("hg") => Phase::HenyeyGreenstein { g: d.g.as_ref().map_or(0.8, |g| g.get_ref().0) },
                Some("rayleigh") if d.g.is_none() => Phase::Rayleigh,
                Some(other @ ("isotropic" | "rayleigh")) => {
                    let g = d.g.as_ref().expect("g given");
                    return Err(self.at(g.span(), format!("`g` belongs to the hg phase function, not `{other}`")));
                }
                Some(other) => {
                    let p = d.phase.as_ref().expect("phase given");
                    return Err(self.at(
                        p.span(),
                        format!("unknown phase function `{other}`; expected isotropic, hg or rayleigh"),
                    ));
                }
            };
            let scale = d.scale.map_or(1.0, |s| s.0);
            let m = Homogeneous::new(sigma_t * scale, albedo, phase)
                .map_err(|e| self.at(span.clone(), format!("medium `{}`: {e}", name.get_ref())))?;
            let i = geometry.add_medium(Medium::Homogeneous(m));
            names.insert(name.get_ref().to_string(), i);
        }
        Ok(names)
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
