//! Surface materials: the seed report's classic model (`classic`) and the BSDFs of Mitsuba 3
//! (smooth and rough conductors, dielectrics and plastics, with textured parameters), plus the
//! wrappers that modify another material (two-sided, bump and normal maps, masks, blends).
//!
//! A material evaluates at a hit to `bsdf::Lobes` (a few `bxdf` lobes), placed in the hit's
//! shading frame as a `bsdf::Bsdf`; `set::Materials` holds a scene's materials and textures and
//! does that resolution.

pub mod bsdf;
pub mod bxdf;
pub mod classic;
pub mod conductors;
pub mod fresnel;
pub mod microfacet;
pub mod set;

pub use classic::{Classic, ClassicKind};
pub use set::Materials;

use crate::math::{Color, Vec2};
use crate::texture::Texture;
use bsdf::Lobes;
use bxdf::{
    Bxdf, CoatingTable, Conductor, Dielectric, FresnelMirror, Lambert, PlasticDiffuse, RoughCoating, RoughConductor,
    RoughDielectric, RoughPlasticDiffuse,
};
use fresnel::fresnel_diffuse_reflectance;
use microfacet::{Distribution, Microfacet};

/// A parameter that is a constant or read from a texture (an index into the scene's textures).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Param<T> {
    Const(T),
    Texture(u32),
}

pub type ColorParam = Param<Color>;
pub type FloatParam = Param<f32>;

impl ColorParam {
    #[inline]
    pub fn at(&self, uv: Vec2, textures: &[Texture]) -> Color {
        match *self {
            Param::Const(c) => c,
            Param::Texture(t) => textures[t as usize].eval(uv),
        }
    }

    /// The mean over the surface (constants as they are, textures by their mean).
    pub fn mean(&self, textures: &[Texture]) -> Color {
        match *self {
            Param::Const(c) => c,
            Param::Texture(t) => textures[t as usize].mean(),
        }
    }
}

impl FloatParam {
    /// The value at `uv`; a texture read as a scalar (`Texture::eval_1`).
    #[inline]
    pub fn at(&self, uv: Vec2, textures: &[Texture]) -> f32 {
        match *self {
            Param::Const(v) => v,
            Param::Texture(t) => textures[t as usize].eval_1(uv),
        }
    }
}

impl<T> Param<T> {
    pub fn is_texture(&self) -> bool {
        matches!(self, Param::Texture(_))
    }
}

/// Roughness of a microfacet material: a distribution and its alphas along dp/du and dp/dv.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Roughness {
    pub distribution: Distribution,
    pub alpha_u: FloatParam,
    pub alpha_v: FloatParam,
}

impl Roughness {
    #[inline]
    fn at(&self, uv: Vec2, textures: &[Texture]) -> Microfacet {
        Microfacet::new(self.distribution, self.alpha_u.at(uv, textures), self.alpha_v.at(uv, textures))
    }

    fn is_textured(&self) -> bool {
        self.alpha_u.is_texture() || self.alpha_v.is_texture()
    }
}

/// What a material is. Indices name other materials of the same scene (always earlier ones, so
/// wrappers cannot form cycles) or textures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Model {
    /// The seed report's model; its lobes are `Classic::lobes`.
    Classic(Classic),
    /// Lambertian reflection (Mitsuba `diffuse`).
    Diffuse { reflectance: ColorParam },
    /// A smooth metal with complex index eta + i k per channel (Mitsuba `conductor`).
    Conductor { eta: Color, k: Color, specular: ColorParam },
    /// A rough metal (Mitsuba `roughconductor`).
    RoughConductor { roughness: Roughness, eta: Color, k: Color, specular: ColorParam },
    /// Smooth glass of relative index `eta` = inside / outside (Mitsuba `dielectric`).
    Dielectric { eta: f32, reflectance: ColorParam, transmittance: ColorParam },
    /// Frosted glass (Mitsuba `roughdielectric`).
    RoughDielectric { roughness: Roughness, eta: f32, reflectance: ColorParam, transmittance: ColorParam },
    /// A smooth dielectric coating over a diffuse base (Mitsuba `plastic`).
    Plastic { diffuse: ColorParam, specular: ColorParam, eta: f32, nonlinear: bool, diffuse_mean: f32 },
    /// A rough coating over a diffuse base (Mitsuba `roughplastic`; scalar roughness only).
    RoughPlastic {
        microfacet: Microfacet,
        diffuse: ColorParam,
        specular: ColorParam,
        eta: f32,
        nonlinear: bool,
        diffuse_mean: f32,
        table: &'static CoatingTable,
    },
    /// Material `front` on the outward side and `back` on the other (Mitsuba `twosided`).
    TwoSided { front: u32, back: u32 },
    /// `inner` with its shading normal tilted by the gradient of a height texture (Mitsuba
    /// `bumpmap`; a bitmap texture).
    BumpMap { height: u32, scale: f32, inner: u32 },
    /// `inner` with its shading normal read from a tangent-space normal map (Mitsuba
    /// `normalmap`).
    NormalMap { normals: u32, inner: u32 },
    /// `inner` where opaque, straight through elsewhere (Mitsuba `mask`).
    Mask { opacity: FloatParam, inner: u32 },
    /// (1 - weight) `first` + weight `second` (Mitsuba `blendbsdf`).
    Blend { weight: FloatParam, first: u32, second: u32 },
}

/// A scene material: what it is and whether its back scatters like its front.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    pub model: Model,
    /// Seen from behind (against the outward normal) a one-sided material is black, as
    /// Mitsuba's reflecting BSDFs are; glass and the classic model are always two-sided.
    pub two_sided: bool,
}

impl From<Classic> for Material {
    fn from(c: Classic) -> Self {
        Material { model: Model::Classic(c), two_sided: true }
    }
}

impl Default for Material {
    fn default() -> Self {
        Classic::default().into()
    }
}

impl Material {
    /// A one-sided material of model `model` (Mitsuba's default for reflecting BSDFs).
    pub fn one_sided(model: Model) -> Self {
        Material { model, two_sided: false }
    }

    /// A material of model `model` that scatters the same on both sides.
    pub fn two_sided(model: Model) -> Self {
        Material { model, two_sided: true }
    }

    /// A surface that reflects nothing (the surface of a plain area light).
    pub fn black() -> Self {
        Classic::black().into()
    }

    /// A smooth plastic with Mitsuba's parameters; `diffuse_mean` is the mean of the base's
    /// reflectance over the surface (it sets how often the coating is sampled).
    pub fn plastic(
        diffuse: ColorParam,
        specular: ColorParam,
        eta: f32,
        nonlinear: bool,
        textures: &[Texture],
    ) -> Model {
        let d = diffuse.mean(textures);
        Model::Plastic { diffuse, specular, eta, nonlinear, diffuse_mean: d.mean() }
    }

    /// A rough plastic (its coating's transmittance table is made here, once per roughness and
    /// index).
    pub fn rough_plastic(
        microfacet: Microfacet,
        diffuse: ColorParam,
        specular: ColorParam,
        eta: f32,
        nonlinear: bool,
        textures: &[Texture],
    ) -> Model {
        let d = diffuse.mean(textures);
        let table = CoatingTable::shared(microfacet, eta);
        Model::RoughPlastic { microfacet, diffuse, specular, eta, nonlinear, diffuse_mean: d.mean(), table }
    }
}

impl Model {
    /// True when the model's lobes depend on the surface point (a textured parameter).
    pub fn is_textured(&self) -> bool {
        match self {
            Model::Classic(c) => c.color_texture.is_some(),
            Model::Diffuse { reflectance } => reflectance.is_texture(),
            Model::Conductor { specular, .. } => specular.is_texture(),
            Model::RoughConductor { roughness, specular, .. } => roughness.is_textured() || specular.is_texture(),
            Model::Dielectric { reflectance, transmittance, .. } => {
                reflectance.is_texture() || transmittance.is_texture()
            }
            Model::RoughDielectric { roughness, reflectance, transmittance, .. } => {
                roughness.is_textured() || reflectance.is_texture() || transmittance.is_texture()
            }
            Model::Plastic { diffuse, specular, .. } | Model::RoughPlastic { diffuse, specular, .. } => {
                diffuse.is_texture() || specular.is_texture()
            }
            Model::TwoSided { .. }
            | Model::BumpMap { .. }
            | Model::NormalMap { .. }
            | Model::Mask { .. }
            | Model::Blend { .. } => true,
        }
    }

    /// The materials a wrapper refers to.
    pub fn children(&self) -> Vec<u32> {
        match *self {
            Model::TwoSided { front, back } => vec![front, back],
            Model::BumpMap { inner, .. } | Model::NormalMap { inner, .. } | Model::Mask { inner, .. } => vec![inner],
            Model::Blend { first, second, .. } => vec![first, second],
            _ => Vec::new(),
        }
    }

    /// The lobes of a non-wrapper model at texture coordinates `uv`, seen from the outward side
    /// (`front`) or the inside (which matters only for glass: the index is inverted).
    pub fn lobes(&self, front: bool, uv: Vec2, textures: &[Texture]) -> Lobes {
        let mut lobes = Lobes::default();
        let side = |eta: f32| if front { eta } else { 1.0 / eta };
        match *self {
            Model::Classic(c) => {
                let c = match c.color_texture {
                    Some(t) => Classic { color: textures[t as usize].eval(uv), ..c },
                    None => c,
                };
                return c.lobes(front);
            }
            Model::Diffuse { reflectance } => lobes.add(Bxdf::Lambert(Lambert { r: reflectance.at(uv, textures) })),
            Model::Conductor { eta, k, specular } => {
                lobes.add(Bxdf::Conductor(Conductor { eta, k, scale: specular.at(uv, textures) }))
            }
            Model::RoughConductor { roughness, eta, k, specular } => lobes.add(Bxdf::RoughConductor(RoughConductor {
                mf: roughness.at(uv, textures),
                eta,
                k,
                scale: specular.at(uv, textures),
            })),
            Model::Dielectric { eta, reflectance, transmittance } => lobes.add(Bxdf::Dielectric(Dielectric {
                eta: side(eta),
                r: reflectance.at(uv, textures),
                t: transmittance.at(uv, textures),
            })),
            Model::RoughDielectric { roughness, eta, reflectance, transmittance } => {
                lobes.add(Bxdf::RoughDielectric(RoughDielectric {
                    mf: roughness.at(uv, textures),
                    eta: side(eta),
                    r: reflectance.at(uv, textures),
                    t: transmittance.at(uv, textures),
                }))
            }
            Model::Plastic { diffuse, specular, eta, nonlinear, diffuse_mean } => {
                let d = diffuse.at(uv, textures);
                let fdr = fresnel_diffuse_reflectance(1.0 / eta);
                let d = base_through_coating(d, fdr, nonlinear) / (eta * eta);
                let scale = specular.at(uv, textures);
                lobes.add(Bxdf::FresnelMirror(FresnelMirror { eta, scale }));
                lobes.add(Bxdf::PlasticDiffuse(PlasticDiffuse {
                    d,
                    eta,
                    d_mean: diffuse_mean.max(1e-4 * scale.mean()),
                }));
            }
            Model::RoughPlastic { microfacet, diffuse, specular, eta, nonlinear, diffuse_mean, table } => {
                let d = diffuse.at(uv, textures);
                let d = base_through_coating(d, table.internal_reflectance, nonlinear) / (eta * eta);
                let scale = specular.at(uv, textures);
                lobes.add(Bxdf::RoughCoating(RoughCoating { mf: microfacet, eta, scale, table }));
                lobes.add(Bxdf::RoughPlasticDiffuse(RoughPlasticDiffuse {
                    d,
                    table,
                    d_mean: diffuse_mean.max(1e-4 * scale.mean()),
                }));
            }
            Model::TwoSided { .. }
            | Model::BumpMap { .. }
            | Model::NormalMap { .. }
            | Model::Mask { .. }
            | Model::Blend { .. } => {}
        }
        lobes
    }

    /// True when the model is glass (transmits light, both sides meaningful).
    pub fn is_glass(&self) -> bool {
        match self {
            Model::Classic(c) => c.transmits(),
            Model::Dielectric { .. } | Model::RoughDielectric { .. } => true,
            _ => false,
        }
    }

    /// True when light reflected or refracted by the model can focus into caustics of the
    /// caustic map (L S+ D paths, S a delta bounce): smooth mirrors, metals and glass, and
    /// plastic's smooth coating, where caustic photons are aimed. Rough metal and glass are not:
    /// a caustic photon ends at its first glossy bounce (their focused light is in the global
    /// map), so photons aimed at them were all lost, up to the emission cap (200 times the
    /// photons asked) in a scene whose only shiny object is rough.
    pub fn casts_caustics(&self) -> bool {
        match self {
            Model::Classic(c) => c.is_specular(),
            Model::Conductor { .. } | Model::Dielectric { .. } | Model::Plastic { .. } => true,
            _ => false,
        }
    }
}

/// The base's reflectance after the light bouncing between base and coating: d / (1 - F_dr), or
/// Mitsuba's `nonlinear` d / (1 - d F_dr) where each bounce on the base also tints the light.
#[inline]
fn base_through_coating(d: Color, fdr: f32, nonlinear: bool) -> Color {
    if nonlinear { d / (Color::ONE - d * fdr) } else { d / (1.0 - fdr) }
}
