//! A rough dielectric interface (frosted glass), as Mitsuba 3's `roughdielectric`: microfacets
//! that are smooth dielectrics, reflecting and refracting by the Fresnel equations (Walter et al.
//! 2007), sampled through the normals visible from `wo`.
//!
//! In the local frame `wo` is on the +z side (the viewer's); `eta` is the index of the other side
//! over the viewer's. Refracted radiance is scaled by 1 / eta^2 in radiance transport, not for
//! photons (importance).

use super::{BxdfSample, Lobe, LobeFlags, Transport, colour_weight, half_vector, reflect_about};
use crate::material::fresnel::{fresnel_dielectric, refract};
use crate::material::microfacet::Microfacet;
use crate::math::{Color, Vec2, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughDielectric {
    pub mf: Microfacet,
    pub eta: f32,
    /// Mitsuba's `specular_reflectance` and `specular_transmittance`.
    pub r: Color,
    pub t: Color,
}

impl Lobe for RoughDielectric {
    #[inline]
    fn lifted(self, wl: &crate::spectrum::Wavelengths, eta_ratio: f32) -> Self {
        RoughDielectric { eta: self.eta * eta_ratio, r: wl.reflectance(self.r), t: wl.reflectance(self.t), ..self }
    }

    #[inline]
    fn flags(&self) -> LobeFlags {
        LobeFlags::GLOSSY_REFLECTION | LobeFlags::GLOSSY_TRANSMISSION
    }

    #[inline]
    fn is_isotropic(&self) -> bool {
        self.mf.is_isotropic()
    }

    #[inline]
    fn sampling_weight(&self) -> f32 {
        colour_weight(self.r.max(self.t))
    }

    #[inline]
    fn mean_albedo(&self) -> f32 {
        self.r.max(self.t).mean()
    }

    #[inline]
    fn lambert_albedo(&self) -> Option<Color> {
        None
    }

    #[inline]
    fn scaled(self, w: f32) -> Self {
        let c = Color::splat(w);
        RoughDielectric { r: self.r * c, t: self.t * c, ..self }
    }

    #[inline]
    fn f(&self, wo: Vec3, wi: Vec3, mode: Transport) -> Color {
        if wo.z <= 0.0 || wi.z == 0.0 {
            return Color::ZERO;
        }
        let reflect = wi.z > 0.0;
        let h = half_vector(wo, wi, self.eta, reflect);
        let d = self.mf.d(h);
        if !(d > 0.0) {
            return Color::ZERO;
        }
        let (oh, ih) = (wo.dot(h), wi.dot(h));
        // Both directions must see the facet from the side they are on.
        if !(oh > 0.0) || ih * wi.z <= 0.0 {
            return Color::ZERO;
        }
        let g = self.mf.g(wo, wi, h);
        let fr = fresnel_dielectric(oh, self.eta);
        if reflect {
            return self.r * (fr * d * g / (4.0 * wo.z * wi.z));
        }
        let denom = oh + self.eta * ih;
        let mut v = (1.0 - fr) * d * g * (oh * ih).abs() / (wo.z * wi.z.abs() * denom * denom);
        if mode == Transport::Importance {
            v *= self.eta * self.eta;
        }
        self.t * v
    }

    #[inline]
    fn pdf(&self, wo: Vec3, wi: Vec3, _mode: Transport) -> f32 {
        if wo.z <= 0.0 || wi.z == 0.0 {
            return 0.0;
        }
        let reflect = wi.z > 0.0;
        let h = half_vector(wo, wi, self.eta, reflect);
        let (oh, ih) = (wo.dot(h), wi.dot(h));
        if !(oh > 0.0) || ih * wi.z <= 0.0 {
            return 0.0;
        }
        let fr = fresnel_dielectric(oh, self.eta);
        let pm = self.mf.pdf_visible(wo, h);
        if reflect {
            pm * fr / (4.0 * ih)
        } else {
            let denom = oh + self.eta * ih;
            pm * (1.0 - fr) * self.eta * self.eta * ih.abs() / (denom * denom)
        }
    }

    /// `uc` chooses reflection (with probability F) or refraction, `u` the facet.
    #[inline]
    fn sample(&self, wo: Vec3, uc: f32, u: Vec2, mode: Transport) -> Option<BxdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let m = self.mf.sample_visible(wo, u);
        let om = wo.dot(m);
        if !(om > 0.0) {
            return None;
        }
        let pm = self.mf.pdf_visible(wo, m);
        let fr = fresnel_dielectric(om, self.eta);
        if uc < fr {
            let wi = reflect_about(wo, m);
            if !(wi.z > 0.0) {
                return None;
            }
            let pdf = pm * fr / (4.0 * om);
            let weight = self.r * self.mf.g1(wi, m);
            return (pdf > 0.0).then_some(BxdfSample { wi, weight, pdf, flags: LobeFlags::GLOSSY_REFLECTION });
        }
        let wi = refract(-wo, m, self.eta)?;
        if !(wi.z < 0.0) {
            return None;
        }
        let im = wi.dot(m);
        let denom = om + self.eta * im;
        let pdf = pm * (1.0 - fr) * self.eta * self.eta * im.abs() / (denom * denom);
        let scale = if mode == Transport::Radiance { 1.0 / (self.eta * self.eta) } else { 1.0 };
        let weight = self.t * (self.mf.g1(wi, m) * scale);
        (pdf > 0.0).then_some(BxdfSample { wi, weight, pdf, flags: LobeFlags::GLOSSY_TRANSMISSION })
    }
}
