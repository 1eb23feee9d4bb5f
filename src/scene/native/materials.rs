//! The `[textures]` and `[materials]` sections of a TOML scene: textures by name, the seed
//! report's classic materials, Mitsuba's physically based ones, and wrappers that name other
//! materials (in any order in the file; cycles are an error).

use super::Cx;
use super::schema::{self, DispersionFormula, DispersionSpec, MaterialDesc, TextureDesc};
use super::spectra::{MaterialSpectra, keep_material};
use crate::material::conductors::ComplexIor;
use crate::material::microfacet::{Distribution, Microfacet};
use crate::material::{
    Classic, ClassicKind, ColorParam, FloatParam, Material, Param, Plain, Principled, PrincipledThin, Roughness,
    Wrapper, conductors,
};
use crate::math::{Color, Vec2};
use crate::scene::SceneError;
use crate::scene::builder::SceneBuilder;
use crate::scene::de::{ColorOrTexture, NumberOrTexture};
use crate::scene::footprint::FileKind;
use crate::spectrum::Dispersion;
use crate::spectrum::{SampledSpectrum, SpectrumUse};
use crate::texture::image::{TexImage, load_image};
use crate::texture::{Bitmap, Filter, Texture, Wrap};
use glam::Affine2;
use std::collections::HashMap;
use std::ops::Range;
use std::path::PathBuf;
use std::sync::Arc;
use toml::Spanned;
use toml::de::DeValue;

/// Material indices by name, with a default material made on first use.
pub(super) struct MaterialNames {
    pub index: HashMap<String, u32>,
    pub names: Vec<String>,
    pub default: std::cell::Cell<Option<u32>>,
}

/// Texture indices by name.
pub(super) type TextureNames = HashMap<String, u32>;

/// A material waiting to be built: its kind, description and where it is.
struct Pending {
    name: String,
    kind: &'static str,
    desc: MaterialDesc,
    span: Range<usize>,
}

impl<'a> Cx<'a> {
    /// Step 3a: named textures.
    pub(super) fn textures(
        &self,
        value: Option<Spanned<DeValue<'a>>>,
        geometry: &mut SceneBuilder,
    ) -> Result<TextureNames, SceneError> {
        let mut names = TextureNames::new();
        let Some(v) = value else { return Ok(names) };
        let span = v.span();
        let DeValue::Table(table) = v.into_inner() else {
            return Err(self.at(span, "`textures` must be a table of named textures ([textures.NAME])"));
        };
        let mut images: HashMap<(PathBuf, bool), Arc<TexImage>> = HashMap::new();
        for (name, value) in table {
            let span = value.span();
            let (kind, value) = self.tagged(value, "texture", schema::TEXTURE_KINDS)?;
            let d: TextureDesc = self.de(value)?;
            let to_uv = to_uv(&d);
            let t = match kind {
                "bitmap" => {
                    let file = d.file.as_ref().ok_or_else(|| self.at(span.clone(), "a bitmap texture needs `file`"))?;
                    let path = self.base.join(file.get_ref());
                    let raw = d.raw.unwrap_or(false);
                    let image = match images.get(&(path.clone(), raw)) {
                        Some(i) => i.clone(),
                        None => {
                            self.files.open(&path, FileKind::Image)?;
                            let i = Arc::new(load_image(&path, raw).map_err(|e| self.at(file.span(), e.to_string()))?);
                            images.insert((path, raw), i.clone());
                            i
                        }
                    };
                    let filter = match d.filter.as_ref().map(|s| (s.get_ref().as_str(), s.span())) {
                        None | Some(("bilinear", _)) => Filter::Bilinear,
                        Some(("nearest", _)) => Filter::Nearest,
                        Some((other, at)) => {
                            return Err(self.at(at, format!("filter must be `bilinear` or `nearest`, found `{other}`")));
                        }
                    };
                    let wrap = match d.wrap.as_ref().map(|s| (s.get_ref().as_str(), s.span())) {
                        None | Some(("repeat", _)) => Wrap::Repeat,
                        Some(("mirror", _)) => Wrap::Mirror,
                        Some(("clamp", _)) => Wrap::Clamp,
                        Some((other, at)) => {
                            return Err(
                                self.at(at, format!("wrap must be `repeat`, `mirror` or `clamp`, found `{other}`"))
                            );
                        }
                    };
                    Texture::Bitmap(Bitmap { image, filter, wrap, to_uv })
                }
                _ => Texture::Checkerboard {
                    color0: d.color0.map_or(Color::splat(0.4), |c| c.0),
                    color1: d.color1.map_or(Color::splat(0.2), |c| c.0),
                    to_uv,
                },
            };
            let i = geometry.add_texture(t);
            names.insert(name.get_ref().to_string(), i);
        }
        Ok(names)
    }

    /// Step 3b: named materials. Plain ones are added first, then wrappers once what they name
    /// exists.
    pub(super) fn materials(
        &self,
        value: Option<Spanned<DeValue<'a>>>,
        textures: &TextureNames,
        geometry: &mut SceneBuilder,
    ) -> Result<MaterialNames, SceneError> {
        let mut names = MaterialNames { index: HashMap::new(), names: Vec::new(), default: std::cell::Cell::new(None) };
        let Some(v) = value else { return Ok(names) };
        let span = v.span();
        let DeValue::Table(table) = v.into_inner() else {
            return Err(self.at(span, "`materials` must be a table of named materials ([materials.NAME])"));
        };
        let mut pending = Vec::new();
        for (name, value) in table {
            let span = value.span();
            let (kind, value) = self.tagged(value, "material", schema::MATERIAL_KINDS)?;
            let desc: MaterialDesc = self.de(value)?;
            pending.push(Pending { name: name.get_ref().to_string(), kind, desc, span });
        }
        // Each round adds every material whose references are all built; a round that adds
        // nothing leaves only materials that refer to each other.
        while !pending.is_empty() {
            let before = pending.len();
            let mut rest = Vec::new();
            for p in pending {
                if self.references(&p).iter().all(|r| names.index.contains_key(r.get_ref())) {
                    // The invisible surface that bounds a medium: one for the scene.
                    let i = if p.kind == "null" {
                        geometry.null_material()
                    } else {
                        let mut spectra = MaterialSpectra::default();
                        let m = self.material(&p, textures, &names, geometry, &mut spectra)?;
                        let i = geometry.add_material(p.name.clone(), m);
                        keep_material(geometry, i, spectra);
                        i
                    };
                    names.index.insert(p.name.clone(), i);
                    names.names.push(p.name);
                } else {
                    rest.push(p);
                }
            }
            if rest.len() == before {
                let p = &rest[0];
                let missing: Vec<&Spanned<String>> =
                    self.references(p).into_iter().filter(|r| !names.index.contains_key(r.get_ref())).collect();
                let all: Vec<&str> = rest.iter().map(|p| p.name.as_str()).collect();
                let r = missing[0];
                return Err(if all.contains(&r.get_ref().as_str()) {
                    self.at(r.span(), format!("materials refer to each other in a cycle: {}", all.join(", ")))
                } else {
                    let known = all.iter().copied().chain(names.names.iter().map(String::as_str)).collect();
                    self.at(r.span(), super::no_such("material", r.get_ref(), known))
                });
            }
            pending = rest;
        }
        Ok(names)
    }

    /// The other materials a material names.
    fn references<'p>(&self, p: &'p Pending) -> Vec<&'p Spanned<String>> {
        let d = &p.desc;
        [&d.material, &d.first, &d.second, &d.front, &d.back].into_iter().flatten().collect()
    }

    pub(super) fn texture_index(
        &self,
        textures: &TextureNames,
        name: &str,
        span: Range<usize>,
    ) -> Result<u32, SceneError> {
        textures.get(name).copied().ok_or_else(|| {
            self.at(span, super::no_such("texture", name, textures.keys().map(String::as_str).collect()))
        })
    }

    fn color_param(
        &self,
        v: &Option<Spanned<ColorOrTexture>>,
        default: Color,
        textures: &TextureNames,
    ) -> Result<ColorParam, SceneError> {
        Ok(self.color_param_given(v, default, textures)?.0)
    }

    /// `color_param`, with the spectrum the colour was written as (a reflectance) and that
    /// colour, for spectral mode.
    fn color_param_given(
        &self,
        v: &Option<Spanned<ColorOrTexture>>,
        default: Color,
        textures: &TextureNames,
    ) -> Result<(ColorParam, Option<(SampledSpectrum, Color)>), SceneError> {
        let Some(s) = v else { return Ok((Param::Const(default), None)) };
        Ok(match s.get_ref() {
            ColorOrTexture::Color(c) => (Param::Const(*c), None),
            ColorOrTexture::Spectrum(spec) => {
                let (c, spectrum) = self.spectrum(spec, SpectrumUse::Reflectance, s.span())?;
                (Param::Const(c), Some((spectrum, c)))
            }
            ColorOrTexture::Texture(n) => (Param::Texture(self.texture_index(textures, n, s.span())?), None),
        })
    }

    fn float_param(
        &self,
        v: &Option<Spanned<NumberOrTexture>>,
        default: f32,
        textures: &TextureNames,
    ) -> Result<FloatParam, SceneError> {
        match v {
            None => Ok(Param::Const(default)),
            Some(s) => match s.get_ref() {
                NumberOrTexture::Number(x) => Ok(Param::Const(*x)),
                NumberOrTexture::Texture(n) => Ok(Param::Texture(self.texture_index(textures, n, s.span())?)),
            },
        }
    }

    fn roughness(&self, p: &Pending, textures: &TextureNames) -> Result<Roughness, SceneError> {
        let d = &p.desc;
        let distribution = match d.distribution.as_ref().map(|s| (s.get_ref().as_str(), s.span())) {
            None | Some(("beckmann", _)) => Distribution::Beckmann,
            Some(("ggx", _)) => Distribution::Ggx,
            Some((other, at)) => {
                return Err(self.at(at, format!("distribution must be `beckmann` or `ggx`, found `{other}`")));
            }
        };
        let (alpha_u, alpha_v) = match (&d.alpha, &d.alpha_u, &d.alpha_v) {
            (Some(_), Some(_), _) | (Some(_), _, Some(_)) => {
                return Err(self.at(p.span.clone(), "give either `alpha` or `alpha_u` and `alpha_v`, not both"));
            }
            (None, Some(_), None) | (None, None, Some(_)) => {
                return Err(self.at(p.span.clone(), "an anisotropic roughness needs both `alpha_u` and `alpha_v`"));
            }
            (a, None, None) => {
                let a = self.float_param(a, 0.1, textures)?;
                (a, a)
            }
            (None, u, v) => (self.float_param(u, 0.1, textures)?, self.float_param(v, 0.1, textures)?),
        };
        Ok(Roughness { distribution, alpha_u, alpha_v })
    }

    /// A glass's `dispersion` (`None` without one); giving `ior` too is an error.
    fn dispersion(&self, d: &MaterialDesc) -> Result<Option<Dispersion>, SceneError> {
        let Some(spec) = &d.dispersion else { return Ok(None) };
        let span = spec.span();
        if d.ior.is_some() {
            return Err(self.at(span, "give either `ior` or `dispersion`, not both"));
        }
        let made = match spec.get_ref() {
            DispersionSpec::Name(name) => Dispersion::named(name),
            DispersionSpec::Formula(DispersionFormula { cauchy: Some(c), sellmeier: None }) => match c.as_slice() {
                [a, b] => Dispersion::cauchy(*a, *b, 0.0),
                [a, b, c] => Dispersion::cauchy(*a, *b, *c),
                _ => return Err(self.at(span, "`cauchy` takes [A, B] or [A, B, C] (wavelengths in micrometres)")),
            },
            DispersionSpec::Formula(DispersionFormula { cauchy: None, sellmeier: Some(t) }) => {
                Dispersion::sellmeier(&t.b, &t.c)
            }
            DispersionSpec::Formula(_) => {
                return Err(self.at(span, "give one of `cauchy = [A, B]` or `sellmeier = { b = [...], c = [...] }`"));
            }
        };
        made.map(Some).map_err(|e| self.at(span, e.to_string()))
    }

    fn named(
        &self,
        names: &MaterialNames,
        r: &Option<Spanned<String>>,
        what: &str,
        span: &Range<usize>,
    ) -> Result<u32, SceneError> {
        let r = r.as_ref().ok_or_else(|| self.at(span.clone(), format!("this material needs `{what}`")))?;
        Ok(names.index[r.get_ref()])
    }

    /// Builds one material (whatever it names already exists).
    fn material(
        &self,
        p: &Pending,
        textures: &TextureNames,
        names: &MaterialNames,
        geometry: &SceneBuilder,
        spectra: &mut MaterialSpectra,
    ) -> Result<Material, SceneError> {
        let d = &p.desc;
        let two_sided = d.two_sided.unwrap_or(true);
        let with_sides = |model: Plain| Material { model: model.into(), two_sided, dispersion: None };
        let unit = Param::Const(Color::ONE);
        Ok(match p.kind {
            kind @ ("diffuse" | "reflective" | "transparent" | "dielectric") => {
                let kind = match kind {
                    "diffuse" => ClassicKind::Diffuse,
                    "reflective" => ClassicKind::Reflective,
                    "transparent" => ClassicKind::Transparent,
                    _ => ClassicKind::Dielectric,
                };
                let mut c = classic(d, kind);
                if let (_, Some(s)) = self.color_param_given(&d.color, Color::ONE, textures)? {
                    c.color = s.1;
                    spectra[0] = Some(s);
                }
                if let Some(s) = &d.color
                    && let ColorOrTexture::Texture(n) = s.get_ref()
                {
                    c.color_texture = Some(self.texture_index(textures, n, s.span())?);
                }
                let dispersion = self.dispersion(d)?;
                if let Some(n) = dispersion {
                    c.ior = n.n_d();
                }
                Material { dispersion, ..c.into() }
            }
            "conductor" | "roughconductor" => {
                let ior = match (&d.metal, d.eta, d.k) {
                    (Some(m), None, None) => conductors::lookup(m.get_ref()).ok_or_else(|| {
                        let names: Vec<&str> = conductors::names().collect();
                        self.at(
                            m.span(),
                            format!("unknown metal `{}`; expected one of: {}", m.get_ref(), names.join(", ")),
                        )
                    })?,
                    (Some(m), _, _) => return Err(self.at(m.span(), "give either `metal` or `eta` and `k`, not both")),
                    (None, eta, k) => ComplexIor::rgb(eta.map_or(Color::ZERO, |c| c.0), k.map_or(Color::ONE, |c| c.0)),
                };
                let specular;
                (specular, spectra[0]) = self.color_param_given(&d.specular, Color::ONE, textures)?;
                if p.kind == "conductor" {
                    with_sides(Plain::Conductor { ior, specular })
                } else {
                    with_sides(Plain::RoughConductor { roughness: self.roughness(p, textures)?, ior, specular })
                }
            }
            "roughdielectric" => {
                let dispersion = self.dispersion(d)?;
                let eta = dispersion.map_or_else(|| d.ior.map_or(1.5, |v| v.0), |n| n.n_d());
                if (eta - 1.0).abs() < 1e-7 {
                    return Err(self.at(p.span.clone(), "a rough dielectric needs an `ior` other than 1"));
                }
                let m = Material::two_sided(Plain::RoughDielectric {
                    roughness: self.roughness(p, textures)?,
                    eta,
                    reflectance: unit,
                    transmittance: unit,
                });
                Material { dispersion, ..m }
            }
            "plastic" | "roughplastic" => {
                let (diffuse, given_diffuse) = self.color_param_given(&d.color, Color::splat(0.5), textures)?;
                let (specular, given_specular) = self.color_param_given(&d.specular, Color::ONE, textures)?;
                *spectra = [given_diffuse, given_specular];
                let eta = d.ior.map_or(1.49, |v| v.0);
                let nonlinear = d.nonlinear.unwrap_or(false);
                let tex = geometry.textures();
                if p.kind == "plastic" {
                    with_sides(Material::plastic(diffuse, specular, eta, nonlinear, tex))
                } else {
                    let r = self.roughness(p, textures)?;
                    let (Param::Const(au), Param::Const(av)) = (r.alpha_u, r.alpha_v) else {
                        return Err(
                            self.at(p.span.clone(), "a rough plastic takes a number for `alpha`, not a texture")
                        );
                    };
                    if au != av {
                        return Err(self.at(p.span.clone(), "a rough plastic takes one `alpha` (no anisotropy)"));
                    }
                    let mf = Microfacet::new(r.distribution, au, au);
                    with_sides(Material::rough_plastic(mf, diffuse, specular, eta, nonlinear, tex))
                }
            }
            "bumpmap" => {
                let t = d
                    .texture
                    .as_ref()
                    .ok_or_else(|| self.at(p.span.clone(), "a bump map needs `texture` (heights)"))?;
                let height = self.texture_index(textures, t.get_ref(), t.span())?;
                if !matches!(geometry.textures()[height as usize], Texture::Bitmap(_)) {
                    return Err(self.at(t.span(), "a bump map needs a bitmap texture (only bitmaps have gradients)"));
                }
                let inner = self.named(names, &d.material, "material", &p.span)?;
                Material::two_sided(Wrapper::BumpMap { height, scale: d.scale.map_or(1.0, |v| v.0), inner })
            }
            "normalmap" => {
                let t = d.texture.as_ref().ok_or_else(|| self.at(p.span.clone(), "a normal map needs `texture`"))?;
                let normals = self.texture_index(textures, t.get_ref(), t.span())?;
                let inner = self.named(names, &d.material, "material", &p.span)?;
                Material::two_sided(Wrapper::NormalMap { normals, inner })
            }
            "mask" => {
                let opacity = self.float_param(&d.opacity, 0.5, textures)?;
                let inner = self.named(names, &d.material, "material", &p.span)?;
                Material::two_sided(Wrapper::Mask { opacity, inner })
            }
            "blend" => {
                let weight = self.float_param(&d.weight, 0.5, textures)?;
                let first = self.named(names, &d.first, "first", &p.span)?;
                let second = self.named(names, &d.second, "second", &p.span)?;
                for (key, m) in [("first", first), ("second", second)] {
                    if geometry.material(m).model.is_single_wrapper() {
                        return Err(self.at(
                            p.span.clone(),
                            format!("a blend's `{key}` cannot be a twosided, bumpmap, normalmap or mask material (it would not be applied inside the blend): wrap the blend instead"),
                        ));
                    }
                }
                Material::two_sided(Wrapper::Blend { weight, first, second })
            }
            "twosided" => {
                let front = self.named(names, &d.front, "front", &p.span)?;
                let back = self.named(names, &d.back, "back", &p.span)?;
                Material::two_sided(Wrapper::TwoSided { front, back })
            }
            "principled" => {
                let mut m = Principled::new();
                m.base_color = self.color_param(&d.color, Color::splat(0.5), textures)?;
                m.roughness = self.float_param(&d.roughness, 0.5, textures)?;
                let weights = [
                    (&d.anisotropic, &mut m.anisotropic),
                    (&d.metallic, &mut m.metallic),
                    (&d.spec_trans, &mut m.spec_trans),
                    (&d.spec_tint, &mut m.spec_tint),
                    (&d.sheen, &mut m.sheen),
                    (&d.sheen_tint, &mut m.sheen_tint),
                    (&d.clearcoat, &mut m.clearcoat),
                    (&d.clearcoat_gloss, &mut m.clearcoat_gloss),
                    (&d.flatness, &mut m.flatness),
                ];
                for (v, slot) in weights {
                    *slot = self.float_param(v, 0.0, textures)?;
                }
                m.eta = d.ior.map_or(1.5, |v| v.0);
                if (m.eta - 1.0).abs() < 1e-7 && !matches!(m.spec_trans, Param::Const(t) if t == 0.0) {
                    m.eta = 1.001;
                }
                Material::one_sided(Plain::Principled(m))
            }
            "principledthin" => {
                let mut m = PrincipledThin {
                    base_color: self.color_param(&d.color, Color::splat(0.5), textures)?,
                    roughness: self.float_param(&d.roughness, 0.5, textures)?,
                    eta: Param::Const(d.ior.map_or(1.5, |v| v.0)),
                    ..PrincipledThin::default()
                };
                let weights = [
                    (&d.anisotropic, &mut m.anisotropic),
                    (&d.spec_trans, &mut m.spec_trans),
                    (&d.spec_tint, &mut m.spec_tint),
                    (&d.sheen, &mut m.sheen),
                    (&d.sheen_tint, &mut m.sheen_tint),
                    (&d.flatness, &mut m.flatness),
                    (&d.diff_trans, &mut m.diff_trans),
                ];
                for (v, slot) in weights {
                    *slot = self.float_param(v, 0.0, textures)?;
                }
                Material::two_sided(Plain::PrincipledThin(m))
            }
            other => return Err(self.at(p.span.clone(), format!("unknown material type `{other}`"))),
        })
    }
}

/// The uv transform of a texture: scale, then rotation (degrees), then offset.
fn to_uv(d: &TextureDesc) -> Affine2 {
    let scale = d.scale.map_or(Vec2::ONE, |s| s.0);
    let angle = d.rotate.map_or(0.0, |r| r.0.to_radians());
    let offset = d.offset.map_or(Vec2::ZERO, |o| o.0);
    Affine2::from_translation(offset) * Affine2::from_angle(angle) * Affine2::from_scale(scale)
}

/// A material of the seed report's model from its table.
fn classic(desc: &MaterialDesc, kind: ClassicKind) -> Classic {
    let d = Classic::default();
    // Glass defaults to no diffuse term: all its light comes from reflection and refraction.
    let clear = kind == ClassicKind::Dielectric || kind == ClassicKind::Transparent;
    let color = match desc.color.as_ref().map(|c| c.get_ref()) {
        Some(ColorOrTexture::Color(c)) => *c,
        // A texture's colour is looked up per hit, a spectrum's set by the caller.
        Some(ColorOrTexture::Texture(_) | ColorOrTexture::Spectrum(_)) => Color::ONE,
        None if clear => Color::ONE,
        None => d.color,
    };
    Classic {
        kind,
        color,
        color_texture: None,
        ka: desc.ka.map_or(if clear { 0.0 } else { d.ka }, |v| v.0),
        kd: desc.kd.map_or(if clear { 0.0 } else { d.kd }, |v| v.0),
        ks: desc.ks.map_or(d.ks, |v| v.0),
        exponent: desc.exponent.map_or(d.exponent, |v| v.0),
        kr: desc.kr.map_or(
            match kind {
                ClassicKind::Reflective => 0.5,
                ClassicKind::Transparent => 0.1,
                _ => 0.0,
            },
            |v| v.0,
        ),
        kt: desc.kt.map_or(if kind == ClassicKind::Transparent { 0.9 } else { 0.0 }, |v| v.0),
        ior: desc.ior.map_or(d.ior, |v| v.0),
    }
}
