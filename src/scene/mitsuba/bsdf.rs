//! Mitsuba BSDFs mapped onto caustic's materials (`docs/mitsuba.md` lists what maps exactly and
//! what is approximated, with a warning). Parameters, defaults and conventions follow the
//! Mitsuba 3 plugin reference: reflecting BSDFs are one-sided unless wrapped in `twosided`,
//! rough ones default to Beckmann with alpha 0.1, glass defaults to bk7 in air.

use super::Build;
use super::plugins::PluginKind;
use super::props::{Cx, Props};
use super::xml::El;
use crate::material::conductors::ComplexIor;
use crate::material::microfacet::{Distribution, Microfacet};
use crate::material::{Classic, ClassicKind, Material, Param, Plain, Roughness, Wrapper, conductors};
use crate::material::{GivenSpectra, SpectrumId};
use crate::math::Color;
use crate::scene::SceneError;
use crate::spectrum::SpectrumUse::{Reflectance, Unbounded};

/// Mitsuba's default BSDF: diffuse with reflectance 0.5 (one-sided).
pub(super) fn default_diffuse() -> Material {
    Material::one_sided(Plain::Diffuse { reflectance: Param::Const(Color::splat(0.5)) })
}

/// Fresnel reflectance at normal incidence for relative index `eta`.
fn f0(eta: f32) -> f32 {
    ((eta - 1.0) / (eta + 1.0)).powi(2)
}

/// Mitsuba's default index of glass (bk7) and of the polypropylene of plastics, and of air.
const BK7: f32 = 1.5046;
const POLYPROPYLENE: f32 = 1.49;
const AIR: f32 = 1.000277;

impl<'a> Cx<'a> {
    /// Builds the material of a `<bsdf>` element (cached per element); returns its index.
    pub(super) fn material(&mut self, el: &'a El, b: &mut Build) -> Result<u32, SceneError> {
        self.material_at(el, b, 0)
    }

    fn material_at(&mut self, el: &'a El, b: &mut Build, depth: usize) -> Result<u32, SceneError> {
        let key = el as *const El as usize;
        if let Some(&i) = b.bsdf_cache.get(&key) {
            return Ok(i);
        }
        let m = self.bsdf(el, b, depth)?;
        let given = std::mem::replace(&mut self.bsdf_given, GivenSpectra::NONE);
        let name = match self.attr(el, "id")? {
            Some((id, _)) => id,
            None => format!("(bsdf {})", b.geometry.material_count() + 1),
        };
        let i = b.geometry.add_material(name, m);
        b.geometry.set_material_spectra(i, given);
        b.bsdf_cache.insert(key, i);
        Ok(i)
    }

    /// The BSDF Mitsuba gives a shape without one: diffuse 0.5, or black diffuse when the
    /// shape emits (so an area light without a BSDF reflects nothing).
    pub(super) fn default_material(&self, b: &mut Build, emits: bool) -> u32 {
        if let Some(i) = if emits { b.default_emitter_material } else { b.default_material } {
            return i;
        }
        let (name, m) = if emits {
            (
                "(default black diffuse of an emitter)",
                Material::one_sided(Plain::Diffuse { reflectance: Param::Const(Color::ZERO) }),
            )
        } else {
            ("(default diffuse)", default_diffuse())
        };
        let i = b.geometry.add_material(name, m);
        if emits {
            b.default_emitter_material = Some(i)
        } else {
            b.default_material = Some(i)
        }
        i
    }

    /// The nested BSDFs of a wrapper, in the order written.
    fn nested(&mut self, p: &Props<'a>, b: &mut Build, depth: usize) -> Result<Vec<u32>, SceneError> {
        let inner = self.object(p, None, "bsdf");
        inner.iter().map(|(el, _)| self.material_at(el, b, depth + 1)).collect()
    }

    /// A wrapper's one nested BSDF.
    fn one_nested(&mut self, p: &Props<'a>, b: &mut Build, depth: usize) -> Result<u32, SceneError> {
        match self.nested(p, b, depth)?.as_slice() {
            [m] => Ok(*m),
            [] => Err(self.err(p.el, format!("`{}` needs a nested <bsdf>", p.kind))),
            _ => Err(self.err(p.el, format!("`{}` takes one nested <bsdf>", p.kind))),
        }
    }

    /// Maps a Mitsuba BSDF to our material.
    fn bsdf(&mut self, el: &'a El, b: &mut Build, depth: usize) -> Result<Material, SceneError> {
        if depth > crate::material::set::MAX_NESTING {
            return Err(self.err(el, "BSDFs nested too deeply"));
        }
        let p = self.props(el)?;
        let one = Material::one_sided;
        let unit = Param::Const(Color::ONE);
        // The spectra the constant colours were given as (for spectral mode), in the order
        // `GivenSpectra` says.
        let mut given = GivenSpectra::NONE;
        let m = match p.kind.as_str() {
            "diffuse" => {
                let (reflectance, id) = self.color_param_given(&p, "reflectance", b, Reflectance)?;
                given.colors[0] = id;
                one(Plain::Diffuse { reflectance: reflectance.unwrap_or(Param::Const(Color::splat(0.5))) })
            }
            "conductor" | "roughconductor" => {
                let ior;
                (ior, given.eta, given.k) = self.complex_ior(&p, b)?;
                let (specular, id) = self.color_param_given(&p, "specular_reflectance", b, Reflectance)?;
                given.colors[0] = id;
                let specular = specular.unwrap_or(unit);
                if p.kind == "conductor" {
                    one(Plain::Conductor { ior, specular })
                } else {
                    let roughness = self.roughness(&p, b, true)?;
                    one(Plain::RoughConductor { roughness, ior, specular })
                }
            }
            "dielectric" | "roughdielectric" => {
                // A dispersive glass (caustic's extension) refracts by its d-line index in RGB
                // mode and by each path's hero wavelength's in spectral mode.
                let dispersion = self.dispersive_int_ior(&p)?;
                let eta = match dispersion {
                    Some(d) => d.n_d() / self.ior(&p, "ext_ior", AIR)?,
                    None => self.eta(&p, BK7)?,
                };
                let (reflectance, r_id) = self.color_param_given(&p, "specular_reflectance", b, Reflectance)?;
                let (transmittance, t_id) = self.color_param_given(&p, "specular_transmittance", b, Reflectance)?;
                given.colors = [r_id, t_id];
                let (reflectance, transmittance) = (reflectance.unwrap_or(unit), transmittance.unwrap_or(unit));
                let m = if p.kind == "dielectric" {
                    Material::two_sided(Plain::Dielectric { eta, reflectance, transmittance })
                } else {
                    if (eta - 1.0).abs() < 1e-7 {
                        return Err(self.err(el, "roughdielectric needs int_ior and ext_ior to differ"));
                    }
                    let roughness = self.roughness(&p, b, true)?;
                    Material::two_sided(Plain::RoughDielectric { roughness, eta, reflectance, transmittance })
                };
                Material { dispersion, ..m }
            }
            "thindielectric" => {
                let eta = self.eta(&p, BK7)?;
                for name in ["specular_reflectance", "specular_transmittance"] {
                    if let Some(c) = self.color(&p, name)?
                        && c != Color::ONE
                    {
                        self.warn(
                            el,
                            format!("`{name}` other than 1 is not supported on thindielectric and is ignored"),
                        )?;
                    }
                }
                // A thin sheet: light passes straight through, and the sheet reflects
                // R + T^2 R / (1 - R^2) = 2R / (1 + R). We keep its value at normal incidence.
                let r = f0(eta);
                let kr = 2.0 * r / (1.0 + r);
                self.warn(
                    el,
                    format!("thindielectric is approximated with a fixed reflectance {kr:.4} (its value at normal incidence)"),
                )?;
                Classic {
                    kind: ClassicKind::Transparent,
                    color: Color::ONE,
                    ka: 0.0,
                    kd: 0.0,
                    ks: 0.0,
                    kr,
                    kt: 1.0 - kr,
                    ior: 1.0,
                    ..Classic::default()
                }
                .into()
            }
            "plastic" | "roughplastic" => {
                let (diffuse, d_id) = self.color_param_given(&p, "diffuse_reflectance", b, Reflectance)?;
                let (specular, s_id) = self.color_param_given(&p, "specular_reflectance", b, Reflectance)?;
                given.colors = [d_id, s_id];
                let diffuse = diffuse.unwrap_or(Param::Const(Color::splat(0.5)));
                let specular = specular.unwrap_or(unit);
                let eta = self.eta(&p, POLYPROPYLENE)?;
                let nonlinear = self.boolean(&p, "nonlinear")?.unwrap_or(false);
                let textures = b.geometry.textures();
                if p.kind == "plastic" {
                    one(Material::plastic(diffuse, specular, eta, nonlinear, textures))
                } else {
                    let roughness = self.roughness(&p, b, false)?;
                    let Param::Const(alpha) = roughness.alpha_u else {
                        return Err(self.err(el, "roughplastic takes a number for `alpha`, not a texture"));
                    };
                    let mf = Microfacet::new(roughness.distribution, alpha, alpha);
                    let textures = b.geometry.textures();
                    one(Material::rough_plastic(mf, diffuse, specular, eta, nonlinear, textures))
                }
            }
            "principled" => one(Plain::Principled(self.principled(&p, el, b)?)),
            // A sheet: the same from both sides.
            "principledthin" => Material::two_sided(Plain::PrincipledThin(self.principled_thin(&p, b)?)),
            "twosided" => {
                let inner = self.nested(&p, b, depth)?;
                let check = |this: &mut Self, m: u32| -> Result<(), SceneError> {
                    if b_is_glass(b, m) {
                        return Err(this.err(el, "twosided cannot wrap a BSDF that transmits light"));
                    }
                    Ok(())
                };
                match inner.as_slice() {
                    [m] => {
                        check(self, *m)?;
                        given = b.geometry.material_spectra(*m);
                        Material { two_sided: true, ..*b.geometry.material(*m) }
                    }
                    [front, back] => {
                        check(self, *front)?;
                        check(self, *back)?;
                        Material::two_sided(Wrapper::TwoSided { front: *front, back: *back })
                    }
                    [] => return Err(self.err(el, "twosided needs a nested <bsdf>")),
                    _ => return Err(self.err(el, "twosided takes one or two nested <bsdf>s")),
                }
            }
            "bumpmap" => {
                let height = match self.object(&p, None, "texture").as_slice() {
                    [(t, _)] => self.texture(t, b)?,
                    _ => return Err(self.err(el, "bumpmap needs one nested <texture> (the heights)")),
                };
                if !matches!(b.geometry.textures()[height as usize], crate::texture::Texture::Bitmap(_)) {
                    return Err(self.err(el, "bumpmap needs a bitmap texture: only bitmaps have height gradients"));
                }
                let scale = self.float(&p, "scale")?.unwrap_or(1.0);
                self.perturbation_switches(&p)?;
                let inner = self.one_nested(&p, b, depth)?;
                Material::two_sided(Wrapper::BumpMap { height, scale, inner })
            }
            "normalmap" => {
                let normals = match self.object(&p, Some("normalmap"), "texture").first() {
                    Some(&(t, _)) => self.texture(t, b)?,
                    None => return Err(self.err(el, "normalmap needs a nested <texture name=\"normalmap\">")),
                };
                self.perturbation_switches(&p)?;
                let inner = self.one_nested(&p, b, depth)?;
                Material::two_sided(Wrapper::NormalMap { normals, inner })
            }
            "mask" => {
                let opacity = self.float_param(&p, "opacity", b)?.unwrap_or(Param::Const(0.5));
                let inner = self.one_nested(&p, b, depth)?;
                Material::two_sided(Wrapper::Mask { opacity, inner })
            }
            "blendbsdf" => {
                let weight = self
                    .float_param(&p, "weight", b)?
                    .ok_or_else(|| self.err(el, "blendbsdf needs a `weight` (a number or a texture)"))?;
                match self.nested(&p, b, depth)?.as_slice() {
                    [first, second] => {
                        for m in [*first, *second] {
                            if !b.geometry.material(m).model.is_single_wrapper() {
                                continue;
                            }
                            self.warn(
                                el,
                                "a wrapper (twosided, bump/normal map, mask) inside blendbsdf is not applied",
                            )?;
                        }
                        Material::two_sided(Wrapper::Blend { weight, first: *first, second: *second })
                    }
                    _ => return Err(self.err(el, "blendbsdf needs exactly two nested <bsdf>s")),
                }
            }
            other => {
                self.unsupported(el, PluginKind::Bsdf, other, ": rendered as grey diffuse (reflectance 0.5)")?;
                for u in &p.used {
                    u.set(true);
                }
                default_diffuse()
            }
        };
        self.finish(&p)?;
        self.bsdf_given = given;
        Ok(m)
    }

    /// `flip_invalid_normals` and `use_shadowing_function`: both on is what we do.
    fn perturbation_switches(&mut self, p: &Props<'a>) -> Result<(), SceneError> {
        for name in ["flip_invalid_normals", "use_shadowing_function"] {
            if self.boolean(p, name)? == Some(false) {
                self.warn(p.el, format!("`{name}` false is not supported: it is taken as true"))?;
            }
        }
        Ok(())
    }

    /// Mitsuba's `principled`: every parameter a number or a texture (scalars read with
    /// `eval_1`), `eta` or `specular` (not both) for the index.
    fn principled(
        &mut self,
        p: &super::props::Props<'a>,
        el: &'a El,
        b: &mut Build,
    ) -> Result<crate::material::Principled, SceneError> {
        let mut m = crate::material::Principled::new();
        if let Some(c) = self.color_param(p, "base_color", b)? {
            m.base_color = c;
        }
        let scalars: [(&str, &mut crate::material::FloatParam); 10] = [
            ("roughness", &mut m.roughness),
            ("anisotropic", &mut m.anisotropic),
            ("metallic", &mut m.metallic),
            ("spec_trans", &mut m.spec_trans),
            ("spec_tint", &mut m.spec_tint),
            ("sheen", &mut m.sheen),
            ("sheen_tint", &mut m.sheen_tint),
            ("clearcoat", &mut m.clearcoat),
            ("clearcoat_gloss", &mut m.clearcoat_gloss),
            ("flatness", &mut m.flatness),
        ];
        for (name, slot) in scalars {
            if let Some(v) = self.float_param(p, name, b)? {
                *slot = v;
            }
        }
        // Sampling rates change the noise only.
        for name in ["main_specular_sampling_rate", "clearcoat_sampling_rate", "diffuse_reflectance_sampling_rate"] {
            let _ = self.float(p, name)?;
        }
        let transmits = !matches!(m.spec_trans, Param::Const(t) if t == 0.0);
        m.eta = match (self.float(p, "eta")?, self.float(p, "specular")?) {
            (Some(_), Some(_)) => return Err(self.err(el, "principled takes `eta` or `specular`, not both")),
            (Some(eta), None) => {
                if !(eta > 0.0) {
                    return Err(self.err(el, format!("principled `eta` must be positive, found {eta}")));
                }
                // An index of 1 refracts nothing, which transmission cannot work with.
                if transmits && eta == 1.0 { 1.001 } else { eta }
            }
            (None, specular) => {
                let mut s = specular.unwrap_or(0.5);
                if !(0.0..12.5).contains(&s) {
                    return Err(self.err(el, format!("principled `specular` must be in [0, 12.5), found {s}")));
                }
                if transmits && s == 0.0 {
                    s = 1e-3;
                }
                crate::material::Principled::eta_of_specular(s)
            }
        };
        Ok(m)
    }

    /// Mitsuba's `principledthin`: every parameter a number or a texture, `eta` included.
    fn principled_thin(
        &mut self,
        p: &super::props::Props<'a>,
        b: &mut Build,
    ) -> Result<crate::material::PrincipledThin, SceneError> {
        let mut m = crate::material::PrincipledThin::default();
        if let Some(c) = self.color_param(p, "base_color", b)? {
            m.base_color = c;
        }
        let scalars: [(&str, &mut crate::material::FloatParam); 9] = [
            ("roughness", &mut m.roughness),
            ("anisotropic", &mut m.anisotropic),
            ("spec_trans", &mut m.spec_trans),
            ("spec_tint", &mut m.spec_tint),
            ("sheen", &mut m.sheen),
            ("sheen_tint", &mut m.sheen_tint),
            ("flatness", &mut m.flatness),
            ("diff_trans", &mut m.diff_trans),
            ("eta", &mut m.eta),
        ];
        for (name, slot) in scalars {
            if let Some(v) = self.float_param(p, name, b)? {
                *slot = v;
            }
        }
        // Sampling rates change the noise only.
        for name in [
            "specular_reflectance_sampling_rate",
            "specular_transmittance_sampling_rate",
            "diffuse_transmittance_sampling_rate",
            "diffuse_reflectance_sampling_rate",
        ] {
            let _ = self.float(p, name)?;
        }
        Ok(m)
    }

    /// int_ior / ext_ior (numbers or Mitsuba's named materials).
    fn eta(&self, p: &Props<'a>, int_default: f32) -> Result<f32, SceneError> {
        let int_ior = self.ior(p, "int_ior", int_default)?;
        let ext_ior = self.ior(p, "ext_ior", AIR)?;
        Ok(int_ior / ext_ior)
    }

    /// A conductor's complex index: a named `material` (default `none`: a perfect mirror), or
    /// `eta` and `k` (0 and 1 when missing, as Mitsuba), with the spectra `eta` and `k` were
    /// given as (for spectral mode).
    fn complex_ior(
        &mut self,
        p: &Props<'a>,
        b: &mut Build,
    ) -> Result<(ComplexIor, SpectrumId, SpectrumId), SceneError> {
        let material = self.string(p, "material")?;
        // A spectrum read inside a texture (a checkerboard's colours) is not the value's.
        let mut read = |this: &mut Self, name: &str| -> Result<(Option<Color>, SpectrumId), SceneError> {
            this.given_spectrum = None;
            let c = this.color_for(p, name, Unbounded)?;
            let id = match c {
                Some(c) if this.prop(p, name).is_some() => this.given_id(b, c),
                _ => SpectrumId::NONE,
            };
            this.given_spectrum = None;
            Ok((c, id))
        };
        let (eta, eta_id) = read(self, "eta")?;
        let (k, k_id) = read(self, "k")?;
        let ior = match material {
            Some((name, at)) => {
                if eta.is_some() || k.is_some() {
                    return Err(self.err(at, "give either `material` or `eta` and `k`, not both"));
                }
                conductors::lookup(&name).ok_or_else(|| {
                    let names: Vec<&str> = conductors::names().collect();
                    self.err(at, format!("unknown conductor `{name}`; expected one of: {}", names.join(", ")))
                })
            }
            None => Ok(ComplexIor::rgb(eta.unwrap_or(Color::ZERO), k.unwrap_or(Color::ONE))),
        }?;
        Ok((ior, eta_id, k_id))
    }

    /// `distribution` and `alpha` (or `alpha_u` and `alpha_v` when `anisotropic` is allowed).
    fn roughness(&mut self, p: &Props<'a>, b: &mut Build, anisotropic: bool) -> Result<Roughness, SceneError> {
        let distribution = match self.string(p, "distribution")? {
            None => Distribution::Beckmann,
            Some((s, at)) => match s.as_str() {
                "beckmann" => Distribution::Beckmann,
                "ggx" => Distribution::Ggx,
                _ => return Err(self.err(at, format!("distribution must be `beckmann` or `ggx`, found `{s}`"))),
            },
        };
        // Visible-normal sampling or not changes only the noise.
        let _ = self.prop(p, "sample_visible");
        let alpha = self.float_param(p, "alpha", b)?;
        let (au, av) = if anisotropic {
            (self.float_param(p, "alpha_u", b)?, self.float_param(p, "alpha_v", b)?)
        } else {
            (None, None)
        };
        let (alpha_u, alpha_v) = match (alpha, au, av) {
            (Some(_), Some(_), _) | (Some(_), _, Some(_)) => {
                return Err(self.err(p.el, "give either `alpha` or `alpha_u` and `alpha_v`, not both"));
            }
            (Some(a), None, None) => (a, a),
            (None, Some(u), Some(v)) => (u, v),
            (None, Some(_), None) | (None, None, Some(_)) => {
                return Err(self.err(p.el, "an anisotropic roughness needs both `alpha_u` and `alpha_v`"));
            }
            (None, None, None) => (Param::Const(0.1), Param::Const(0.1)),
        };
        for a in [alpha_u, alpha_v] {
            if let Param::Const(v) = a
                && !(v >= 0.0 && v.is_finite())
            {
                return Err(self.err(p.el, format!("roughness must be a number of at least 0, found {v}")));
            }
        }
        Ok(Roughness { distribution, alpha_u, alpha_v })
    }
}

/// True when material `m` of the scene being built transmits light.
fn b_is_glass(b: &Build, m: u32) -> bool {
    let model = |i: u32| b.geometry.material(i).model;
    model(m).any_part(&model, &Plain::is_glass)
}
