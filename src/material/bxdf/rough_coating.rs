//! A rough plastic's coating (Mitsuba 3's `roughplastic`): microfacet reflection of a rough
//! dielectric, with no transmission lobe (light entering the coating is the base's). Chosen
//! against the base in proportion to what the coating does not transmit (its table).

use super::{BxdfSample, CoatingTable, Lobe, LobeFlags, Transport, reflect_about};
use crate::material::fresnel::{fresnel_dielectric, fresnel_diffuse_reflectance};
use crate::material::microfacet::Microfacet;
use crate::math::{Color, Vec2, Vec3};

#[derive(Clone, Copy, Debug)]
pub struct RoughCoating {
    pub mf: Microfacet,
    pub eta: f32,
    pub scale: Color,
    pub table: &'static CoatingTable,
}

impl PartialEq for RoughCoating {
    fn eq(&self, o: &Self) -> bool {
        self.mf == o.mf && self.eta == o.eta && self.scale == o.scale && std::ptr::eq(self.table, o.table)
    }
}

impl Lobe for RoughCoating {
    #[inline]
    fn lifted(self, wl: &crate::spectrum::Wavelengths, _eta_ratio: f32) -> Self {
        RoughCoating { scale: wl.reflectance(self.scale), ..self }
    }

    const DIRECTIONAL: bool = true;

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
        self.scale.mean()
    }

    #[inline]
    fn selection(&self, wo: Vec3) -> f32 {
        1.0 - self.table.transmittance(wo.z)
    }

    /// Fresnel reflectance of a coating averaged over directions is about its F_dr.
    #[inline]
    fn mean_albedo(&self) -> f32 {
        self.scale.mean() * fresnel_diffuse_reflectance(self.eta)
    }

    #[inline]
    fn lambert_albedo(&self) -> Option<Color> {
        None
    }

    #[inline]
    fn scaled(self, w: f32) -> Self {
        RoughCoating { scale: self.scale * Color::splat(w), ..self }
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
        let fr = fresnel_dielectric(wo.dot(h), self.eta);
        self.scale * (fr * d * self.mf.g(wo, wi, h) / (4.0 * wo.z * wi.z))
    }

    #[inline]
    fn pdf(&self, wo: Vec3, wi: Vec3, _mode: Transport) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let h = (wo + wi).normalize_or_zero();
        let ih = wi.dot(h);
        if !(wo.dot(h) > 0.0 && ih > 0.0) {
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
        let weight = self.scale * (fresnel_dielectric(om, self.eta) * self.mf.g1(wi, m));
        (pdf > 0.0).then_some(BxdfSample { wi, weight, pdf, flags: LobeFlags::GLOSSY_REFLECTION })
    }
}
