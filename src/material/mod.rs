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
// Generated data: one long line per spectrum.
#[rustfmt::skip]
mod conductor_spectra;
pub mod conductors;
pub mod fresnel;
pub mod given;
pub mod microfacet;
pub mod set;

pub use classic::{Classic, ClassicKind};
pub use given::{GivenSpectra, GivenSpectrum, SpectrumId};
pub use set::Materials;

use crate::math::Color;
use crate::texture::{TexPoint, Texture};
use bsdf::Lobes;
use bxdf::{
    Bxdf, CoatingTable, Conductor, Dielectric, DiffuseTransmission, FresnelMirror, Lambert, PlasticDiffuse,
    PrincipledClearcoat, PrincipledDiffuse, PrincipledSpecular, RoughCoating, RoughConductor, RoughDielectric,
    RoughPlasticDiffuse, ThinSpecular, tint_of,
};
use conductors::ComplexIor;
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
    pub fn at(&self, at: TexPoint<'_>, textures: &[Texture]) -> Color {
        match *self {
            Param::Const(c) => c,
            Param::Texture(t) => textures[t as usize].eval_at(at),
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
    pub fn at(&self, at: TexPoint<'_>, textures: &[Texture]) -> f32 {
        match *self {
            Param::Const(v) => v,
            Param::Texture(t) => textures[t as usize].eval_1_at(at),
        }
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
    fn at(&self, at: TexPoint<'_>, textures: &[Texture]) -> Microfacet {
        Microfacet::new(self.distribution, self.alpha_u.at(at, textures), self.alpha_v.at(at, textures))
    }
}

/// What a material is: a plain model, whose lobes it gives at a hit, or a wrapper, which
/// changes another material (always an earlier one of the same scene, so wrappers cannot form
/// cycles). `Materials` walks the wrappers at a hit to the plain model they end in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Model {
    Plain(Plain),
    Wrapper(Wrapper),
}

impl From<Plain> for Model {
    fn from(p: Plain) -> Self {
        Model::Plain(p)
    }
}

impl From<Wrapper> for Model {
    fn from(w: Wrapper) -> Self {
        Model::Wrapper(w)
    }
}

/// A model that scatters light itself: its parameters are constants or textures (indices into
/// the scene's textures).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Plain {
    /// The seed report's model; its lobes are `Classic::lobes`.
    Classic(Classic),
    /// Lambertian reflection (Mitsuba `diffuse`).
    Diffuse { reflectance: ColorParam },
    /// A smooth metal with complex index eta + i k (Mitsuba `conductor`).
    Conductor { ior: ComplexIor, specular: ColorParam },
    /// A rough metal (Mitsuba `roughconductor`).
    RoughConductor { roughness: Roughness, ior: ComplexIor, specular: ColorParam },
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
    /// Mitsuba 3's Disney-style `principled` BSDF.
    Principled(Principled),
    /// Mitsuba 3's `principledthin`: the same for a thin sheet (leaves, paper, cloth).
    PrincipledThin(PrincipledThin),
}

/// The parameters of Mitsuba 3's `principledthin` BSDF; as `Principled`, every one may be a
/// texture. `diff_trans` runs from 0 to 2, as in Mitsuba.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrincipledThin {
    pub base_color: ColorParam,
    pub roughness: FloatParam,
    pub anisotropic: FloatParam,
    pub spec_trans: FloatParam,
    pub spec_tint: FloatParam,
    pub sheen: FloatParam,
    pub sheen_tint: FloatParam,
    pub flatness: FloatParam,
    pub diff_trans: FloatParam,
    pub eta: FloatParam,
}

impl Default for PrincipledThin {
    fn default() -> Self {
        let zero = Param::Const(0.0);
        PrincipledThin {
            base_color: Param::Const(Color::splat(0.5)),
            roughness: Param::Const(0.5),
            anisotropic: zero,
            spec_trans: zero,
            spec_tint: zero,
            sheen: zero,
            sheen_tint: zero,
            flatness: zero,
            diff_trans: zero,
            eta: Param::Const(1.5),
        }
    }
}

/// Mitsuba's roughness mapping for the principled models: alpha = roughness^2 (at least
/// 0.001), stretched along the tangent by `anisotropic`.
fn principled_alphas(roughness: f32, anisotropic: f32) -> Microfacet {
    let r2 = roughness * roughness;
    let (ax, ay) = if anisotropic == 0.0 {
        (r2.max(0.001), r2.max(0.001))
    } else {
        let aspect = (1.0 - 0.9 * anisotropic).sqrt();
        ((r2 / aspect).max(0.001), (r2 * aspect).max(0.001))
    };
    Microfacet::new(Distribution::Ggx, ax, ay)
}

impl PrincipledThin {
    fn params(&self) -> Vec<AnyParam> {
        use AnyParam::{Color as C, Float as F};
        vec![
            C(self.base_color),
            F(self.roughness),
            F(self.anisotropic),
            F(self.spec_trans),
            F(self.spec_tint),
            F(self.sheen),
            F(self.sheen_tint),
            F(self.flatness),
            F(self.diff_trans),
            F(self.eta),
        ]
    }

    /// The lobes at `at` (the same from both sides: the sheet is symmetric).
    fn lobes(&self, at: TexPoint<'_>, textures: &[Texture], lobes: &mut Lobes) {
        let base = self.base_color.at(at, textures);
        let roughness = self.roughness.at(at, textures);
        let anisotropic = self.anisotropic.at(at, textures);
        let spec_trans = self.spec_trans.at(at, textures);
        let diff_trans = 0.5 * self.diff_trans.at(at, textures);
        let eta = self.eta.at(at, textures);
        let reflect = (1.0 - spec_trans) * (1.0 - diff_trans);
        if spec_trans < 1.0 && diff_trans < 1.0 && reflect > 0.0 {
            let sheen = self.sheen.at(at, textures);
            let sheen = if sheen > 0.0 {
                let t = self.sheen_tint.at(at, textures);
                (Color::ONE + (tint_of(base) - Color::ONE) * t) * (sheen * reflect)
            } else {
                Color::ZERO
            };
            lobes.add(Bxdf::PrincipledDiffuse(PrincipledDiffuse {
                color: base * reflect,
                weight: reflect,
                roughness,
                flatness: self.flatness.at(at, textures),
                sheen,
            }));
        }
        if spec_trans < 1.0 && diff_trans > 0.0 {
            let weight = (1.0 - spec_trans) * diff_trans;
            lobes.add(Bxdf::DiffuseTransmission(DiffuseTransmission { t: base * weight, weight }));
        }
        if spec_trans > 0.0 {
            lobes.add(Bxdf::ThinSpecular(ThinSpecular {
                mf: principled_alphas(roughness, anisotropic),
                mf_through: principled_alphas((0.65 * eta - 0.35) * roughness, anisotropic),
                eta,
                base,
                spec_tint: self.spec_tint.at(at, textures),
                weight: spec_trans,
            }));
        }
    }
}

/// The parameters of Mitsuba 3's `principled` BSDF (its lobes are in `bxdf::principled`);
/// every one but `eta` may be a texture, the scalars read with `eval_1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Principled {
    pub base_color: ColorParam,
    pub roughness: FloatParam,
    pub anisotropic: FloatParam,
    pub metallic: FloatParam,
    pub spec_trans: FloatParam,
    pub spec_tint: FloatParam,
    pub sheen: FloatParam,
    pub sheen_tint: FloatParam,
    pub clearcoat: FloatParam,
    pub clearcoat_gloss: FloatParam,
    pub flatness: FloatParam,
    /// Relative index, inside over outside (Mitsuba's `eta`, or from `specular`).
    pub eta: f32,
}

impl Principled {
    /// Mitsuba's defaults: base colour 0.5, roughness 0.5, every weight 0, eta 1.5 (specular
    /// 0.5).
    pub fn new() -> Principled {
        let zero = Param::Const(0.0);
        Principled {
            base_color: Param::Const(Color::splat(0.5)),
            roughness: Param::Const(0.5),
            anisotropic: zero,
            metallic: zero,
            spec_trans: zero,
            spec_tint: zero,
            sheen: zero,
            sheen_tint: zero,
            clearcoat: zero,
            clearcoat_gloss: zero,
            flatness: zero,
            eta: 1.5,
        }
    }

    /// The index of refraction Mitsuba derives from `specular`: the one whose normal-incidence
    /// reflectance is 0.08 specular.
    pub fn eta_of_specular(specular: f32) -> f32 {
        2.0 / (1.0 - (0.08 * specular).sqrt()) - 1.0
    }

    fn params(&self) -> Vec<AnyParam> {
        use AnyParam::{Color as C, Float as F};
        vec![
            C(self.base_color),
            F(self.roughness),
            F(self.anisotropic),
            F(self.metallic),
            F(self.spec_trans),
            F(self.spec_tint),
            F(self.sheen),
            F(self.sheen_tint),
            F(self.clearcoat),
            F(self.clearcoat_gloss),
            F(self.flatness),
        ]
    }

    /// Transmits light (a textured or positive `spec_trans`): both sides are seen.
    fn transmits(&self) -> bool {
        !matches!(self.spec_trans, Param::Const(t) if t <= 0.0)
    }

    /// The lobes at `at`, seen from outside (`front`) or inside.
    fn lobes(&self, front: bool, at: TexPoint<'_>, textures: &[Texture], lobes: &mut Lobes) {
        let base = self.base_color.at(at, textures);
        let roughness = self.roughness.at(at, textures);
        let metallic = self.metallic.at(at, textures);
        let spec_trans = self.spec_trans.at(at, textures);
        let brdf = (1.0 - metallic) * (1.0 - spec_trans);
        let trans = (1.0 - metallic) * spec_trans;
        let mf = principled_alphas(roughness, self.anisotropic.at(at, textures));
        if !front {
            if trans > 0.0 {
                let inside = PrincipledSpecular {
                    mf,
                    eta: 1.0 / self.eta,
                    base,
                    metallic,
                    spec_tint: 0.0,
                    trans,
                    inside: true,
                    scale: 1.0,
                };
                lobes.add(Bxdf::PrincipledSpecular(inside));
            }
            return;
        }
        if brdf > 0.0 {
            let sheen = self.sheen.at(at, textures) * (1.0 - metallic);
            let sheen = if sheen > 0.0 {
                let t = self.sheen_tint.at(at, textures);
                (Color::ONE + (tint_of(base) - Color::ONE) * t) * sheen
            } else {
                Color::ZERO
            };
            lobes.add(Bxdf::PrincipledDiffuse(PrincipledDiffuse {
                color: base * brdf,
                weight: brdf,
                roughness,
                flatness: self.flatness.at(at, textures),
                sheen,
            }));
        }
        lobes.add(Bxdf::PrincipledSpecular(PrincipledSpecular {
            mf,
            eta: self.eta,
            base,
            metallic,
            spec_tint: self.spec_tint.at(at, textures),
            trans,
            inside: false,
            scale: 1.0,
        }));
        let clearcoat = self.clearcoat.at(at, textures);
        if clearcoat > 0.0 {
            let gloss = self.clearcoat_gloss.at(at, textures);
            lobes.add(Bxdf::PrincipledClearcoat(PrincipledClearcoat {
                weight: 0.25 * clearcoat,
                alpha: 0.1 + (0.001 - 0.1) * gloss,
                eta: self.eta,
            }));
        }
    }
}

impl Default for Principled {
    fn default() -> Self {
        Principled::new()
    }
}

/// A model that changes another material (`inner`, `front`, `back`, `first`, `second`: indices of
/// earlier materials).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Wrapper {
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

/// A parameter of either kind, as `Plain::params` and `Wrapper::params` list them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AnyParam {
    Color(ColorParam),
    Float(FloatParam),
}

impl AnyParam {
    /// The texture the parameter reads, if any.
    pub fn texture(&self) -> Option<u32> {
        match *self {
            AnyParam::Color(Param::Texture(t)) | AnyParam::Float(Param::Texture(t)) => Some(t),
            AnyParam::Color(Param::Const(_)) | AnyParam::Float(Param::Const(_)) => None,
        }
    }
}

/// A scene material: what it is and whether its back scatters like its front.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    pub model: Model,
    /// Seen from behind (against the outward normal) a one-sided material is black, as
    /// Mitsuba's reflecting BSDFs are; glass and the classic model are always two-sided.
    pub two_sided: bool,
    /// A glass's index of refraction over wavelength, when dispersive: its lobes hold the index
    /// at the d line (what the RGB mode renders with), and spectral mode scales it to the path's
    /// hero wavelength (`Materials::dispersion`). `None` for everything else.
    pub dispersion: Option<crate::spectrum::Dispersion>,
}

impl From<Classic> for Material {
    fn from(c: Classic) -> Self {
        Material { model: Model::Plain(Plain::Classic(c)), two_sided: true, dispersion: None }
    }
}

impl Default for Material {
    fn default() -> Self {
        Classic::default().into()
    }
}

impl Material {
    /// A one-sided material of model `model` (Mitsuba's default for reflecting BSDFs).
    pub fn one_sided(model: impl Into<Model>) -> Self {
        Material { model: model.into(), two_sided: false, dispersion: None }
    }

    /// A material of model `model` that scatters the same on both sides.
    pub fn two_sided(model: impl Into<Model>) -> Self {
        Material { model: model.into(), two_sided: true, dispersion: None }
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
    ) -> Plain {
        let d = diffuse.mean(textures);
        Plain::Plastic { diffuse, specular, eta, nonlinear, diffuse_mean: d.mean() }
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
    ) -> Plain {
        let d = diffuse.mean(textures);
        let table = CoatingTable::shared(microfacet, eta);
        Plain::RoughPlastic { microfacet, diffuse, specular, eta, nonlinear, diffuse_mean: d.mean(), table }
    }
}

impl Model {
    /// Every parameter the model reads (the one list of its texture references).
    pub fn params(&self) -> Vec<AnyParam> {
        match self {
            Model::Plain(p) => p.params(),
            Model::Wrapper(w) => w.params(),
        }
    }

    /// True when `test` holds for this model's plain model or, for a wrapper, for any material
    /// it wraps (`material` looks an earlier material's model up by index).
    pub fn any_part(&self, material: &dyn Fn(u32) -> Model, test: &dyn Fn(&Plain) -> bool) -> bool {
        match self {
            Model::Plain(p) => test(p),
            Model::Wrapper(w) => w.children().into_iter().flatten().any(|c| material(c).any_part(material, test)),
        }
    }

    /// True for a wrapper of one material (two-sided, bump map, normal map, mask): what a blend
    /// does not apply to its parts.
    pub fn is_single_wrapper(&self) -> bool {
        matches!(self, Model::Wrapper(w) if w.next(true).is_some())
    }

    /// The materials a wrapper refers to (none for a plain model).
    pub fn children(&self) -> impl Iterator<Item = u32> {
        let refs = match self {
            Model::Plain(_) => [None, None],
            Model::Wrapper(w) => w.children(),
        };
        refs.into_iter().flatten()
    }
}

impl Plain {
    /// Every parameter the model reads.
    pub fn params(&self) -> Vec<AnyParam> {
        use AnyParam::{Color as C, Float as F};
        let rough = |r: &Roughness| [F(r.alpha_u), F(r.alpha_v)];
        match self {
            Plain::Classic(c) => c.color_texture.map(|t| C(Param::Texture(t))).into_iter().collect(),
            Plain::Diffuse { reflectance } => vec![C(*reflectance)],
            Plain::Conductor { specular, .. } => vec![C(*specular)],
            Plain::RoughConductor { roughness, specular, .. } => {
                [rough(roughness).as_slice(), &[C(*specular)]].concat()
            }
            Plain::Dielectric { reflectance, transmittance, .. } => vec![C(*reflectance), C(*transmittance)],
            Plain::RoughDielectric { roughness, reflectance, transmittance, .. } => {
                [rough(roughness).as_slice(), &[C(*reflectance), C(*transmittance)]].concat()
            }
            Plain::Plastic { diffuse, specular, .. } | Plain::RoughPlastic { diffuse, specular, .. } => {
                vec![C(*diffuse), C(*specular)]
            }
            Plain::Principled(p) => p.params(),
            Plain::PrincipledThin(p) => p.params(),
        }
    }

    /// True when the model's lobes depend on the surface point (a textured parameter).
    pub fn is_textured(&self) -> bool {
        self.params().iter().any(|p| p.texture().is_some())
    }

    /// The lobes at texture coordinates `uv`, seen from the outward side (`front`) or the
    /// inside (which matters only for glass: the index is inverted), with the spectra `given`
    /// for the model's constant colours attached to the lobes they colour.
    pub fn lobes(&self, front: bool, at: TexPoint<'_>, textures: &[Texture], given: &GivenSpectra) -> Lobes {
        let mut lobes = Lobes::default();
        let [c0, c1] = given.colors;
        let none = SpectrumId::NONE;
        let side = |eta: f32| if front { eta } else { 1.0 / eta };
        match *self {
            Plain::Classic(c) => {
                return match c.color_texture {
                    Some(t) => Classic { color: textures[t as usize].eval_at(at), ..c }.lobes(front),
                    None => c.lobes_given(front, c0),
                };
            }
            Plain::Diffuse { reflectance } => {
                lobes.add_given(Bxdf::Lambert(Lambert { r: reflectance.at(at, textures) }), [c0, none, none])
            }
            Plain::Conductor { ior, specular } => lobes.add_given(
                Bxdf::Conductor(Conductor {
                    eta: ior.eta,
                    k: ior.k,
                    measured: ior.measured,
                    scale: specular.at(at, textures),
                }),
                [c0, given.eta, given.k],
            ),
            Plain::RoughConductor { roughness, ior, specular } => lobes.add_given(
                Bxdf::RoughConductor(RoughConductor {
                    mf: roughness.at(at, textures),
                    eta: ior.eta,
                    k: ior.k,
                    measured: ior.measured,
                    scale: specular.at(at, textures),
                }),
                [c0, given.eta, given.k],
            ),
            Plain::Dielectric { eta, reflectance, transmittance } => lobes.add_given(
                Bxdf::Dielectric(Dielectric {
                    eta: side(eta),
                    r: reflectance.at(at, textures),
                    t: transmittance.at(at, textures),
                }),
                [c0, c1, none],
            ),
            Plain::RoughDielectric { roughness, eta, reflectance, transmittance } => lobes.add_given(
                Bxdf::RoughDielectric(RoughDielectric {
                    mf: roughness.at(at, textures),
                    eta: side(eta),
                    r: reflectance.at(at, textures),
                    t: transmittance.at(at, textures),
                }),
                [c0, c1, none],
            ),
            Plain::Plastic { diffuse, specular, eta, nonlinear, diffuse_mean } => {
                let d = diffuse.at(at, textures);
                let fdr = fresnel_diffuse_reflectance(1.0 / eta);
                let d = base_through_coating(d, fdr, nonlinear) / (eta * eta);
                let scale = specular.at(at, textures);
                lobes.add_given(Bxdf::FresnelMirror(FresnelMirror { eta, scale }), [c1, none, none]);
                lobes.add_given(
                    Bxdf::PlasticDiffuse(PlasticDiffuse { d, eta, d_mean: diffuse_mean.max(1e-4 * scale.mean()) }),
                    [linear_base(c0, nonlinear), none, none],
                );
            }
            Plain::RoughPlastic { microfacet, diffuse, specular, eta, nonlinear, diffuse_mean, table } => {
                let d = diffuse.at(at, textures);
                let d = base_through_coating(d, table.internal_reflectance, nonlinear) / (eta * eta);
                let scale = specular.at(at, textures);
                lobes.add_given(
                    Bxdf::RoughCoating(RoughCoating { mf: microfacet, eta, scale, table }),
                    [c1, none, none],
                );
                lobes.add_given(
                    Bxdf::RoughPlasticDiffuse(RoughPlasticDiffuse {
                        d,
                        table,
                        d_mean: diffuse_mean.max(1e-4 * scale.mean()),
                    }),
                    [linear_base(c0, nonlinear), none, none],
                );
            }
            Plain::Principled(p) => p.lobes(front, at, textures, &mut lobes),
            Plain::PrincipledThin(p) => p.lobes(at, textures, &mut lobes),
        }
        lobes
    }

    /// True when the model is glass (transmits light, both sides meaningful).
    #[inline]
    pub fn is_glass(&self) -> bool {
        match self {
            Plain::Classic(c) => c.transmits(),
            Plain::Dielectric { .. } | Plain::RoughDielectric { .. } => true,
            Plain::Principled(p) => p.transmits(),
            // A thin sheet transmits without refracting: the same lobes from both sides.
            Plain::PrincipledThin(_) => false,
            Plain::Diffuse { .. }
            | Plain::Conductor { .. }
            | Plain::RoughConductor { .. }
            | Plain::Plastic { .. }
            | Plain::RoughPlastic { .. } => false,
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
            Plain::Classic(c) => c.is_specular(),
            Plain::Conductor { .. } | Plain::Dielectric { .. } | Plain::Plastic { .. } => true,
            Plain::Diffuse { .. }
            | Plain::RoughConductor { .. }
            | Plain::RoughDielectric { .. }
            | Plain::RoughPlastic { .. }
            | Plain::Principled(_)
            | Plain::PrincipledThin(_) => false,
        }
    }
}

impl Wrapper {
    /// Every parameter the wrapper reads (a bump map's heights and a normal map's normals are
    /// textures read as colours).
    pub fn params(&self) -> Vec<AnyParam> {
        match *self {
            Wrapper::TwoSided { .. } => Vec::new(),
            Wrapper::BumpMap { height, .. } => vec![AnyParam::Color(Param::Texture(height))],
            Wrapper::NormalMap { normals, .. } => vec![AnyParam::Color(Param::Texture(normals))],
            Wrapper::Mask { opacity, .. } => vec![AnyParam::Float(opacity)],
            Wrapper::Blend { weight, .. } => vec![AnyParam::Float(weight)],
        }
    }

    /// The materials the wrapper refers to.
    pub fn children(&self) -> [Option<u32>; 2] {
        match *self {
            Wrapper::TwoSided { front, back } => [Some(front), Some(back)],
            Wrapper::BumpMap { inner, .. } | Wrapper::NormalMap { inner, .. } | Wrapper::Mask { inner, .. } => {
                [Some(inner), None]
            }
            Wrapper::Blend { first, second, .. } => [Some(first), Some(second)],
        }
    }

    /// The one material a walk through the wrapper goes on to when the surface is seen from the
    /// outward side (`front`) or not; `None` for a blend, which has two.
    #[inline]
    pub fn next(&self, front: bool) -> Option<u32> {
        match *self {
            Wrapper::TwoSided { front: a, back: b } => Some(if front { a } else { b }),
            Wrapper::BumpMap { inner, .. } | Wrapper::NormalMap { inner, .. } | Wrapper::Mask { inner, .. } => {
                Some(inner)
            }
            Wrapper::Blend { .. } => None,
        }
    }
}

/// The base's reflectance after the light bouncing between base and coating: d / (1 - F_dr), or
/// Mitsuba's `nonlinear` d / (1 - d F_dr) where each bounce on the base also tints the light.
#[inline]
/// The spectrum of a plastic's base colour where the lobe's colour is that colour times a
/// constant: a nonlinear base's is not (`base_through_coating`), and is lifted from its colour.
fn linear_base(id: SpectrumId, nonlinear: bool) -> SpectrumId {
    if nonlinear { SpectrumId::NONE } else { id }
}

fn base_through_coating(d: Color, fdr: f32, nonlinear: bool) -> Color {
    if nonlinear { d / (Color::ONE - d * fdr) } else { d / (1.0 - fdr) }
}
