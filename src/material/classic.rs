//! The seed report's material model (eq. 1-2): ambient k_a, diffuse k_d with a colour, Phong
//! specular k_s with exponent n, mirror reflection k_r, transmission k_t with an index of
//! refraction, and the four kinds the report mixes in one scene. The Whitted integrator shades
//! with it directly; the physical integrators read its lobes.

use super::bsdf::Lobes;
use super::bxdf::{Bxdf, Dielectric, Lambert, Mirror, Phong, Transmission};
use super::fresnel::{fresnel_conductor_rgb, fresnel_dielectric};
use super::{Materials, Model, Param, Plain, SpectrumId, Wrapper};
use crate::math::Color;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClassicKind {
    /// Ambient, diffuse and Phong highlight only.
    Diffuse,
    /// Adds mirror reflection weighted by k_r.
    Reflective,
    /// Adds reflection k_r and refraction k_t with fixed coefficients.
    Transparent,
    /// Reflection and refraction weighted by the Fresnel equations: k_s from eq. 5-7, k_t = 1 - k_s.
    Dielectric,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Classic {
    pub kind: ClassicKind,
    pub color: Color,
    /// A texture (index into the scene's textures) giving `color` over the surface.
    pub color_texture: Option<u32>,
    pub ka: f32,
    pub kd: f32,
    /// Phong highlight coefficient (eq. 1).
    pub ks: f32,
    /// Phong exponent n.
    pub exponent: f32,
    /// Mirror reflection coefficient (Reflective, Transparent).
    pub kr: f32,
    /// Transmission coefficient (Transparent).
    pub kt: f32,
    /// Index of refraction of the inside of the object (Transparent, Dielectric).
    pub ior: f32,
}

impl Default for Classic {
    fn default() -> Self {
        Classic {
            kind: ClassicKind::Diffuse,
            color: Color::splat(0.8),
            color_texture: None,
            ka: 0.1,
            kd: 0.8,
            ks: 0.0,
            exponent: 32.0,
            kr: 0.0,
            kt: 0.0,
            ior: 1.5,
        }
    }
}

impl Classic {
    /// A surface that reflects nothing (the surface of a plain area light).
    pub const BLACK: Classic = Classic {
        kind: ClassicKind::Diffuse,
        color: Color::ZERO,
        color_texture: None,
        ka: 0.0,
        kd: 0.0,
        ks: 0.0,
        exponent: 32.0,
        kr: 0.0,
        kt: 0.0,
        ior: 1.5,
    };

    /// A surface that reflects nothing (the surface of a plain area light).
    pub fn black() -> Self {
        Self::BLACK
    }

    /// True when the material has a perfectly specular (mirror or refracting) part, so light
    /// arriving through it can form caustics.
    pub fn is_specular(&self) -> bool {
        match self.kind {
            ClassicKind::Diffuse => false,
            ClassicKind::Reflective => self.kr > 0.0,
            ClassicKind::Transparent => self.kr > 0.0 || self.kt > 0.0,
            ClassicKind::Dielectric => true,
        }
    }

    /// The material's lobes seen from the outward side (`front`) or the inside: a Lambertian
    /// lobe with albedo k_d x colour, a normalised Phong lobe with k_s, a mirror with k_r, a
    /// fixed-transmittance refraction with k_t (`Transparent`), or the two Fresnel-weighted
    /// lobes of a smooth dielectric. If the lobes' albedos add up to more than one they are
    /// scaled down together, so no surface reflects more than it receives.
    pub fn lobes(&self, front: bool) -> Lobes {
        self.lobes_given(front, SpectrumId::NONE)
    }

    /// `lobes`, with spectrum `color` (spectral mode's) standing for the constant `color` in the
    /// diffuse lobe, whose reflectance is that colour times `kd` and the energy scale.
    pub fn lobes_given(&self, front: bool, color: SpectrumId) -> Lobes {
        let mut lobes = Lobes::default();
        // The index of the side light enters over the side it comes from.
        let eta = if front { self.ior } else { 1.0 / self.ior };
        if self.kind == ClassicKind::Dielectric {
            // A smooth dielectric is only its two Fresnel lobes: the classic model's diffuse and
            // highlight terms on glass have no physical counterpart (highlights of area lights
            // show up in the mirror lobe by themselves).
            lobes.add(Bxdf::Dielectric(Dielectric::clear(eta)));
            return lobes;
        }
        let mut diffuse = self.color * self.kd;
        let mut glossy = self.ks;
        let (mut mirror, mut transmit) = match self.kind {
            ClassicKind::Reflective => (Color::splat(self.kr), 0.0),
            ClassicKind::Transparent => (Color::splat(self.kr), self.kt),
            _ => (Color::ZERO, 0.0),
        };
        // Energy conservation: the lobes share at most all the light.
        let total = (diffuse + Color::splat(glossy) + mirror + Color::splat(transmit)).max_element();
        if total > 1.0 {
            let s = 1.0 / total;
            diffuse *= s;
            glossy *= s;
            mirror *= s;
            transmit *= s;
        }
        lobes.add_given(Bxdf::Lambert(Lambert { r: diffuse }), [color, SpectrumId::NONE, SpectrumId::NONE]);
        lobes.add(Bxdf::Phong(Phong { ks: glossy, exponent: self.exponent }));
        lobes.add(Bxdf::Mirror(Mirror { r: mirror }));
        lobes.add(Bxdf::Transmission(Transmission { t: transmit, eta }));
        lobes
    }

    /// True when light passes through the surface (refraction happens).
    #[inline]
    pub fn transmits(&self) -> bool {
        matches!(self.kind, ClassicKind::Transparent | ClassicKind::Dielectric)
    }
}

/// The Whitted view of material `m` of `materials`: the classic model as it is, and for the
/// others the nearest classic reading (documented in docs/scene-format.md): diffuse colours,
/// mirrors with the normal-incidence reflectance of metals and coatings, Phong highlights of the
/// matching width for rough surfaces, glass as glass. Roughness of glass, textures other than a
/// diffuse colour, masks and bump maps are ignored; a two-sided material reads as its front, a
/// blend as its heavier part.
pub fn classic_view(materials: &Materials, m: u32) -> Classic {
    let textures = &materials.textures;
    let const_or_mean = |p: &Param<Color>| match *p {
        Param::Const(c) => (c, None),
        Param::Texture(t) => (textures[t as usize].mean(), Some(t)),
    };
    let exponent = |alpha: f32| (2.0 / (alpha * alpha).max(1e-4) - 2.0).clamp(1.0, 10_000.0);
    let alpha_of = |p: &Param<f32>| match *p {
        Param::Const(a) => a,
        Param::Texture(t) => textures[t as usize].mean().mean(),
    };
    let base = Classic { ka: 0.0, ks: 0.0, kr: 0.0, kt: 0.0, ..Classic::default() };
    let plain = match materials.list[m as usize].model {
        Model::Plain(p) => p,
        Model::Wrapper(w) => {
            return match w {
                Wrapper::TwoSided { front: inner, .. }
                | Wrapper::BumpMap { inner, .. }
                | Wrapper::NormalMap { inner, .. }
                | Wrapper::Mask { inner, .. } => classic_view(materials, inner),
                Wrapper::Blend { weight, first, second } => {
                    let w = alpha_of(&weight).clamp(0.0, 1.0);
                    classic_view(materials, if w < 0.5 { first } else { second })
                }
            };
        }
    };
    match plain {
        Plain::Classic(c) => c,
        Plain::Diffuse { reflectance } => {
            let (color, color_texture) = const_or_mean(&reflectance);
            Classic { kind: ClassicKind::Diffuse, color, color_texture, kd: 1.0, ..base }
        }
        Plain::Conductor { ior, specular } => {
            let f0 = fresnel_conductor_rgb(1.0, ior.eta, ior.k) * const_or_mean(&specular).0;
            Classic { kind: ClassicKind::Reflective, color: f0, kd: 0.0, kr: f0.mean(), ..base }
        }
        Plain::RoughConductor { roughness, ior, specular } => {
            let f0 = fresnel_conductor_rgb(1.0, ior.eta, ior.k) * const_or_mean(&specular).0;
            let n = exponent(alpha_of(&roughness.alpha_u).max(alpha_of(&roughness.alpha_v)));
            Classic { kind: ClassicKind::Diffuse, color: f0, kd: 0.0, ks: f0.mean(), exponent: n, ..base }
        }
        Plain::Dielectric { eta, .. } | Plain::RoughDielectric { eta, .. } => {
            Classic { kind: ClassicKind::Dielectric, ior: eta, kd: 0.0, ..base }
        }
        Plain::Plastic { diffuse, eta, .. } => {
            let (color, color_texture) = const_or_mean(&diffuse);
            let f0 = fresnel_dielectric(1.0, eta);
            Classic { kind: ClassicKind::Reflective, color, color_texture, kd: 1.0 - f0, kr: f0, ..base }
        }
        Plain::RoughPlastic { microfacet, diffuse, eta, .. } => {
            let (color, color_texture) = const_or_mean(&diffuse);
            let f0 = fresnel_dielectric(1.0, eta);
            let n = exponent(microfacet.alpha_u);
            Classic { kind: ClassicKind::Diffuse, color, color_texture, kd: 1.0 - f0, ks: f0, exponent: n, ..base }
        }
        // Mostly transmitting: glass; otherwise the base colour with a highlight of the
        // metallic and dielectric reflectance at normal incidence.
        Plain::Principled(p) => {
            let (metallic, trans) = (alpha_of(&p.metallic), alpha_of(&p.spec_trans));
            if (1.0 - metallic) * trans > 0.5 {
                return Classic { kind: ClassicKind::Dielectric, ior: p.eta, kd: 0.0, ..base };
            }
            let (color, color_texture) = const_or_mean(&p.base_color);
            let f0 = (1.0 - metallic) * fresnel_dielectric(1.0, p.eta) + metallic * color.mean();
            let roughness = alpha_of(&p.roughness);
            let n = exponent((roughness * roughness).max(0.001));
            let kd = (1.0 - metallic) * (1.0 - trans);
            Classic { kind: ClassicKind::Diffuse, color, color_texture, kd, ks: f0, exponent: n, ..base }
        }
        Plain::PrincipledThin(p) => {
            let (color, color_texture) = const_or_mean(&p.base_color);
            let trans = alpha_of(&p.spec_trans);
            Classic { kind: ClassicKind::Diffuse, color, color_texture, kd: 1.0 - trans, ..base }
        }
    }
}
