//! A rough metal (Mitsuba 3's `roughconductor`): a microfacet reflection lobe (Torrance-Sparrow
//! with Smith's separable shadowing, Walter et al. 2007) whose facets are smooth conductors,
//! sampled through the normals visible from `wo` (Heitz 2018). It reflects only on the side the
//! normal faces.

use super::{BxdfSample, Lobe, LobeFlags, Transport, colour_weight, reflect_about};
use crate::material::conductors::Measured;
use crate::material::fresnel::fresnel_conductor_rgb;
use crate::material::microfacet::Microfacet;
use crate::math::{Color, Vec2, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughConductor {
    pub mf: Microfacet,
    pub eta: Color,
    pub k: Color,
    /// A named metal's measured spectra, which spectral mode evaluates instead of lifting
    /// `eta` and `k`.
    pub measured: Option<Measured>,
    pub scale: Color,
}

impl RoughConductor {
    /// Reflectance at normal incidence: the lobe's albedo estimate for sampling.
    #[inline]
    pub fn albedo(&self) -> Color {
        fresnel_conductor_rgb(1.0, self.eta, self.k) * self.scale
    }
}

impl Lobe for RoughConductor {
    #[inline]
    fn lifted(self, wl: &crate::spectrum::Wavelengths, _eta_ratio: f32) -> Self {
        let (eta, k) = match self.measured {
            Some(m) => m.at(wl),
            None => (wl.unbounded(self.eta), wl.unbounded(self.k)),
        };
        RoughConductor { eta, k, measured: None, scale: wl.reflectance(self.scale), ..self }
    }

    #[inline]
    fn flags(&self) -> LobeFlags {
        LobeFlags::GLOSSY_REFLECTION
    }

    #[inline]
    fn is_isotropic(&self) -> bool {
        self.mf.is_isotropic()
    }

    #[inline]
    fn sampling_weight(&self) -> f32 {
        colour_weight(self.albedo())
    }

    #[inline]
    fn mean_albedo(&self) -> f32 {
        self.albedo().mean()
    }

    #[inline]
    fn lambert_albedo(&self) -> Option<Color> {
        None
    }

    #[inline]
    fn scaled(self, w: f32) -> Self {
        RoughConductor { scale: self.scale * Color::splat(w), ..self }
    }

    #[inline]
    fn f(&self, wo: Vec3, wi: Vec3, _mode: Transport) -> Color {
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
    fn pdf(&self, wo: Vec3, wi: Vec3, _mode: Transport) -> f32 {
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
    fn sample(&self, wo: Vec3, _uc: f32, u: Vec2, _mode: Transport) -> Option<BxdfSample> {
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
