//! Mitsuba 3's participating media: `<medium type="homogeneous">` and `<medium
//! type="heterogeneous">` (its `sigma_t` and `albedo` a number, a colour, a `constvolume` or a
//! `gridvolume` read from a `.vol` file, each volume with its own `to_world`) with its `<phase>`
//! (`isotropic`, `hg`, `rayleigh`), nested in a shape as `interior` / `exterior` or in the
//! sensor, or declared at the top with an id and referenced. Each `<medium>` element becomes one
//! medium of the scene however often it is referenced.

use super::Build;
use super::plugins::PluginKind;
use super::props::{Cx, Props};
use super::xml::El;
use crate::geometry::Transform;
use crate::math::Color;
use crate::medium::{Heterogeneous, Volume, VolumeData};
use crate::medium::{Homogeneous, Medium, MediumInterface, Phase};
use crate::scene::SceneError;
use crate::scene::footprint::FileKind;
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
            "heterogeneous" => self.heterogeneous(el, &p)?,
            other => {
                let message = super::plugins::unknown(PluginKind::Medium, other).unwrap_or_else(|| {
                    format!("medium `{other}` is not supported yet; expected homogeneous or heterogeneous")
                });
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

    fn heterogeneous(&mut self, el: &'a El, p: &Props<'a>) -> Result<Medium, SceneError> {
        let sigma_t = self.medium_volume(p, "sigma_t", Color::ONE)?;
        let albedo = self.medium_volume(p, "albedo", Color::splat(0.75))?;
        let scale = self.float(p, "scale")?.unwrap_or(1.0);
        // How lights are sampled from inside the medium does not change the image; Mitsuba's
        // flag for RGB extinction only tells its integrator what to expect.
        let _ = self.boolean(p, "sample_emitters")?;
        let _ = self.boolean(p, "has_spectral_extinction")?;
        let phase = self.phase(p)?;
        let m = Heterogeneous::new(sigma_t, albedo, scale, phase).map_err(|e| self.err(el, format!("medium: {e}")))?;
        Ok(Medium::Heterogeneous(m))
    }

    /// A heterogeneous medium's quantity: a number, `<rgb>` or `<spectrum>`, a `constvolume`,
    /// or a `gridvolume` (its `.vol` file read and checked, errors naming the file); each volume
    /// spans the unit cube of its `to_world`.
    fn medium_volume(&mut self, p: &Props<'a>, name: &str, default: Color) -> Result<Volume, SceneError> {
        if let Some(el) = self.prop(p, name) {
            return Ok(Volume::constant(self.raw_color(el, name)?));
        }
        let Some(&(vol, at)) = self.object(p, Some(name), "volume").first() else {
            return Ok(Volume::constant(default));
        };
        let vp = self.props(vol)?;
        let to_world = self.transform(&vp, "to_world")?.map_or(Transform::IDENTITY, |x| x.t);
        if !to_world.is_valid() {
            return Err(self.err(vol, format!("the `{name}` volume's to_world is singular or not finite")));
        }
        let volume = match vp.kind.as_str() {
            "constvolume" => {
                let c = match self.prop(&vp, "value") {
                    Some(el) => self.raw_color(el, name)?,
                    None => Color::ONE,
                };
                Volume::placed(VolumeData::Constant(c), &to_world)
            }
            "gridvolume" => {
                let (file, fel) = self.string(&vp, "filename")?.ok_or_else(|| {
                    self.err(vol, "a gridvolume needs <string name=\"filename\" value=\"...vol\"/> (a `grid` object is Python-only)")
                })?;
                if let Some((f, fel)) = self.string(&vp, "filter_type")?
                    && f != "trilinear"
                {
                    return Err(
                        self.err(fel, format!("gridvolume `filter_type` `{f}` is not supported; expected trilinear"))
                    );
                }
                if let Some((w, wel)) = self.string(&vp, "wrap_mode")?
                    && w != "clamp"
                {
                    return Err(self.err(wel, format!("gridvolume `wrap_mode` `{w}` is not supported; expected clamp")));
                }
                // Colour conversion (`raw`) and hardware interpolation (`accel`) change nothing
                // in an RGB renderer.
                let _ = self.boolean(&vp, "raw")?;
                let _ = self.boolean(&vp, "accel")?;
                let use_grid_bbox = self.boolean(&vp, "use_grid_bbox")?.unwrap_or(false);
                let path = self.resolve_file(fel, &file)?;
                self.files.open(&path, FileKind::MediumGrid)?;
                let grid = crate::scene::volume_file::load_medium_grid(&path, name).map_err(|e| self.err(fel, e))?;
                let mut to_world = to_world;
                if use_grid_bbox {
                    // The unit cube onto the box the file records, then `to_world`.
                    let b = grid.bbox;
                    let (lo, hi) = (crate::math::Vec3::new(b[0], b[1], b[2]), crate::math::Vec3::new(b[3], b[4], b[5]));
                    let onto = Transform::scale(hi - lo).then(Transform::translate(lo));
                    to_world = onto.then(to_world);
                    if !to_world.is_valid() {
                        return Err(self.err(
                            fel,
                            format!("grid volume `{}`: its bounding box is empty or not finite", path.display()),
                        ));
                    }
                }
                Volume::placed(VolumeData::Grid(grid), &to_world)
            }
            other => {
                let message = super::plugins::unknown(PluginKind::Volume, other).unwrap_or_else(|| {
                    format!("a `{other}` volume is not supported for `{name}`; expected constvolume or gridvolume")
                });
                return Err(self.err(at, message));
            }
        };
        self.finish(&vp)?;
        Ok(volume)
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
