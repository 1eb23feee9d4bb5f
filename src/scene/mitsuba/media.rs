//! Mitsuba 3's participating media: `<medium type="homogeneous">` with its `<phase>`
//! (`isotropic`, `hg`, `rayleigh`), nested in a shape as `interior` / `exterior` or in the
//! sensor, or declared at the top with an id and referenced. Each `<medium>` element becomes one
//! medium of the scene however often it is referenced.

use super::Build;
use super::plugins::PluginKind;
use super::props::{Cx, Props};
use super::xml::El;
use crate::math::Color;
use crate::medium::{Homogeneous, Medium, MediumInterface, Phase};
use crate::scene::SceneError;
use crate::spectrum::SpectrumUse;

impl<'a> Cx<'a> {
    /// The medium of a `<medium>` element (built once per element); returns its index.
    pub(super) fn medium(&mut self, el: &'a El, b: &mut Build) -> Result<u32, SceneError> {
        let key = el as *const El as usize;
        if let Some(&i) = b.medium_cache.get(&key) {
            return Ok(i);
        }
        let p = self.props(el)?;
        let medium = match p.kind.as_str() {
            "homogeneous" => self.homogeneous(el, &p)?,
            other => {
                let message = super::plugins::unknown(PluginKind::Medium, other)
                    .unwrap_or_else(|| format!("medium `{other}` is not supported yet; expected homogeneous"));
                return Err(self.err(el, message));
            }
        };
        self.finish(&p)?;
        let i = b.geometry.add_medium(medium);
        b.medium_cache.insert(key, i);
        Ok(i)
    }

    fn homogeneous(&mut self, el: &'a El, p: &Props<'a>) -> Result<Medium, SceneError> {
        let sigma_t = self.medium_color(p, "sigma_t")?;
        let sigma_a = self.medium_color(p, "sigma_a")?;
        let sigma_s = self.medium_color(p, "sigma_s")?;
        let albedo = self.medium_color(p, "albedo")?;
        let scale = self.float(p, "scale")?.unwrap_or(1.0);
        // How lights are sampled from inside the medium does not change the image.
        let _ = self.boolean(p, "sample_emitters")?;
        if !(scale >= 0.0) {
            return Err(self.err(el, format!("medium `scale` must be >= 0, found {scale}")));
        }
        let (sigma_t, albedo) = match (sigma_t, albedo, sigma_a, sigma_s) {
            (st, al, None, None) => (st.unwrap_or(Color::ONE), al.unwrap_or(Color::splat(0.75))),
            (None, None, a, s) => {
                let (a, s) = (a.unwrap_or(Color::ZERO), s.unwrap_or(Color::ZERO));
                for (name, c) in [("sigma_a", a), ("sigma_s", s)] {
                    if !(c.min_element() >= 0.0) {
                        return Err(self.err(el, format!("medium `{name}` must be >= 0 in every channel, found {c}")));
                    }
                }
                let t = a + s;
                let ratio = |s: f32, t: f32| if t > 0.0 { s / t } else { 0.0 };
                (t, Color::new(ratio(s.r(), t.r()), ratio(s.g(), t.g()), ratio(s.b(), t.b())))
            }
            _ => {
                return Err(
                    self.err(el, "give a medium either sigma_t and albedo, or sigma_a and sigma_s, not a mix of them")
                );
            }
        };
        let phase = self.phase(p)?;
        let m = Homogeneous::new(sigma_t * scale, albedo, phase).map_err(|e| self.err(el, format!("medium: {e}")))?;
        Ok(Medium::Homogeneous(m))
    }

    /// A medium's coefficient as written: a number, an `<rgb>`, a `<spectrum>`, or a
    /// `constvolume` holding one; values outside their range are kept so that the medium's
    /// checks can name them.
    fn medium_color(&mut self, p: &Props<'a>, name: &str) -> Result<Option<Color>, SceneError> {
        if let Some(el) = self.prop(p, name) {
            return self.raw_color(el, name).map(Some);
        }
        let Some(&(vol, at)) = self.object(p, Some(name), "volume").first() else { return Ok(None) };
        let vp = self.props(vol)?;
        if vp.kind != "constvolume" {
            let message = super::plugins::unknown(PluginKind::Volume, &vp.kind).unwrap_or_else(|| {
                format!("a `{}` volume is not supported yet for `{name}`; expected constvolume", vp.kind)
            });
            return Err(self.err(at, message));
        }
        let c = match self.prop(&vp, "value") {
            Some(el) => self.raw_color(el, name)?,
            None => Color::ONE,
        };
        self.finish(&vp)?;
        Ok(Some(c))
    }

    fn raw_color(&mut self, el: &'a El, name: &str) -> Result<Color, SceneError> {
        match el.tag.as_str() {
            "float" | "rgb" => {
                let (v, span) = self.value(el)?;
                let xs: Vec<f32> = v
                    .split(|c: char| c == ',' || c.is_whitespace())
                    .filter(|t| !t.is_empty())
                    .map(|t| {
                        t.trim().parse::<f32>().map_err(|_| {
                            self.err_span(el, span.clone(), format!("`{name}`: expected a number, found `{t}`"))
                        })
                    })
                    .collect::<Result<_, _>>()?;
                match xs.as_slice() {
                    [s] => Ok(Color::splat(*s)),
                    [r, g, b] if el.tag == "rgb" => Ok(Color::new(*r, *g, *b)),
                    _ => Err(self.err_span(el, span, format!("`{name}` needs 1 or 3 values, found {}", xs.len()))),
                }
            }
            _ => self.color_of_for(el, name, SpectrumUse::Unbounded),
        }
    }

    /// The nested `<phase>` (isotropic when there is none).
    fn phase(&mut self, p: &Props<'a>) -> Result<Phase, SceneError> {
        let phases = self.object(p, None, "phase");
        let Some(&(el, _)) = phases.first() else { return Ok(Phase::Isotropic) };
        let pp = self.props(el)?;
        let phase = match pp.kind.as_str() {
            "isotropic" => Phase::Isotropic,
            "rayleigh" => Phase::Rayleigh,
            "hg" => {
                let g = self.float(&pp, "g")?.unwrap_or(0.8);
                if !(g > -1.0 && g < 1.0) {
                    return Err(self.err(el, format!("the hg phase function's `g` must be in (-1, 1), found {g}")));
                }
                Phase::HenyeyGreenstein { g }
            }
            other => {
                let message = super::plugins::unknown(PluginKind::Phase, other).unwrap_or_else(|| {
                    format!("phase function `{other}` is not supported; expected isotropic, hg or rayleigh")
                });
                return Err(self.err(el, message));
            }
        };
        self.finish(&pp)?;
        Ok(phase)
    }

    /// The media a shape bounds (`interior`, `exterior`), when it names any.
    pub(super) fn medium_interface(
        &mut self,
        p: &Props<'a>,
        b: &mut Build,
    ) -> Result<Option<MediumInterface>, SceneError> {
        let mut side = |cx: &mut Self, name: &str| -> Result<Option<u32>, SceneError> {
            let found = cx.object(p, Some(name), "medium");
            match found.first() {
                Some(&(el, at)) => {
                    if el.tag != "medium" {
                        return Err(cx.err(at, format!("`{name}` must be a <medium>, found <{}>", el.tag)));
                    }
                    cx.medium(el, b).map(Some)
                }
                None => Ok(None),
            }
        };
        let inside = side(self, "interior")?;
        let outside = side(self, "exterior")?;
        if inside.is_none() && outside.is_none() {
            return Ok(None);
        }
        let none = crate::geometry::NO_MEDIUM;
        Ok(Some(MediumInterface { inside: inside.unwrap_or(none), outside: outside.unwrap_or(none) }))
    }
}
