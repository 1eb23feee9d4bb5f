//! Metals: a smooth conductor (a mirror tinted by the complex Fresnel reflectance) and a rough
//! one (a microfacet reflection lobe), as Mitsuba 3's `conductor` and `roughconductor`.
//! Both reflect only on the side the normal faces.

use super::{BxdfSample, LobeFlags, reflect_local};
use crate::material::fresnel::fresnel_conductor_rgb;
use crate::material::microfacet::Microfacet;
use crate::math::{Color, Vec2, Vec3};

/// A smooth conductor: mirror reflection weighted by the conductor Fresnel term of complex index
/// `eta` + i `k` (per RGB channel), times `scale` (Mitsuba's `specular_reflectance`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor {
    pub eta: Color,
    pub k: Color,
    pub scale: Color,
}

/// A rough conductor: a microfacet reflection lobe (Torrance-Sparrow with Smith's separable
/// shadowing, Walter et al. 2007) whose facets are smooth conductors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughConductor {
    pub mf: Microfacet,
    pub eta: Color,
    pub k: Color,
    pub scale: Color,
}

impl Conductor {
    /// Reflectance at normal incidence: the lobe's albedo estimate for sampling.
    #[inline]
    pub fn albedo(&self) -> Color {
        fresnel_conductor_rgb(1.0, self.eta, self.k) * self.scale
    }

    #[inline]
    pub fn sample(&self, wo: Vec3) -> Option<BxdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let weight = fresnel_conductor_rgb(wo.z, self.eta, self.k) * self.scale;
        Some(BxdfSample { wi: reflect_local(wo), weight, pdf: 1.0, flags: LobeFlags::SPECULAR_REFLECTION })
    }
}

/// The mirror direction of `w` about the facet normal `m`.
#[inline]
pub fn reflect_about(w: Vec3, m: Vec3) -> Vec3 {
    2.0 * w.dot(m) * m - w
}

impl RoughConductor {
    #[inline]
    pub fn albedo(&self) -> Color {
        fresnel_conductor_rgb(1.0, self.eta, self.k) * self.scale
    }

    #[inline]
    pub fn f(&self, wo: Vec3, wi: Vec3) -> Color {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Color::ZERO;
        }
        let h = (wo + wi).normalize_or_zero();
        let d = self.mf.d(h);
        if !(d > 0.0) {
            return Color::ZERO;
        }
        let g = self.mf.g(wo, wi, h);
        let f = fresnel_conductor_rgb(wo.dot(h), self.eta, self.k);
        f * self.scale * (d * g / (4.0 * wo.z * wi.z))
    }

    /// Density of `sample`: visible normals about `wo`, reflected (Jacobian 1 / (4 wo.h)).
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let h = (wo + wi).normalize_or_zero();
        let (oh, ih) = (wo.dot(h), wi.dot(h));
        if !(oh > 0.0 && ih > 0.0) {
            return 0.0;
        }
        self.mf.pdf_visible(wo, h) / (4.0 * ih)
    }

    #[inline]
    pub fn sample(&self, wo: Vec3, u: Vec2) -> Option<BxdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let m = self.mf.sample_visible(wo, u);
        let om = wo.dot(m);
        let wi = reflect_about(wo, m);
        if !(wi.z > 0.0 && om > 0.0) {
            return None;
        }
        let pdf = self.mf.pdf_visible(wo, m) / (4.0 * om);
        if !(pdf > 0.0) {
            return None;
        }
        // f cos / pdf = F G1(wi) (the D and G1(wo) of f and of the density cancel).
        let weight = fresnel_conductor_rgb(om, self.eta, self.k) * self.scale * self.mf.g1(wi, m);
        Some(BxdfSample { wi, weight, pdf, flags: LobeFlags::GLOSSY_REFLECTION })
    }
}
