//! The lobes of Mitsuba 3's `principled` BSDF (Burley's "Physically Based Shading at Disney",
//! 2012, as Mitsuba implements it): a sum of three lobes whose values add up to Mitsuba's.
//!
//! - `PrincipledDiffuse`: Burley's diffuse with retro-reflection, blended towards the
//!   Hanrahan-Krueger "fake subsurface" by `flatness`, plus the sheen; sampled by the cosine.
//! - `PrincipledSpecular`: GGX reflection with the principled Fresnel term (a blend of the
//!   dielectric Fresnel, a metallic Schlick term of the base colour and a tinted dielectric
//!   Schlick term) and, with `spec_trans`, rough refraction tinted by the square root of the base
//!   colour; seen from inside, dielectric reflection weighted by the transmission share and the
//!   same tinted refraction. Sampled through the visible normals, choosing reflection or refraction
//!   by the Fresnel weights as Mitsuba does.
//! - `PrincipledClearcoat`: a GTR1 lobe with a Schlick Fresnel of F0 = 0.04 and GGX masking of
//!   roughness 0.25.
//!
//! Mitsuba's quirks are kept so that images match: the sheen has no 1/pi, and the clearcoat's
//! value is 0.25 clearcoat F D G with no 1 / (4 cos cos) (its `eval` multiplies by the cosine
//! only). Conventions as in `bxdf`: `wo` towards the viewer on the +z side, `f` without the
//! cosine.

use super::{BxdfSample, Lobe, LobeFlags, Transport, half_vector, reflect_about};
use crate::material::fresnel::{fresnel_dielectric, refract};
use crate::material::microfacet::Microfacet;
use crate::math::{Color, Vec2, Vec3, luminance};
use crate::sampling::warp::cosine_hemisphere;
use std::f32::consts::{FRAC_1_PI, PI};

/// (1 - cos)^5, with the cosine clamped to [0, 1].
#[inline]
fn schlick_weight(cos: f32) -> f32 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    let m2 = m * m;
    m2 * m2 * m
}

/// Schlick's Fresnel with normal-incidence reflectance `r0` for a facet seen at cosine `cos`
/// (>= 0) on a surface of relative index `eta`: from the transmitted cosine when `eta` < 1.
#[inline]
fn schlick(r0: Color, cos: f32, eta: f32) -> Color {
    let w = if eta > 1.0 {
        schlick_weight(cos.abs())
    } else {
        let cos_t2 = 1.0 - (1.0 - cos * cos) / (eta * eta);
        schlick_weight(cos_t2.max(0.0).sqrt())
    };
    r0 + (Color::ONE - r0) * w
}

/// The normal-incidence reflectance of an interface of relative index `eta`.
#[inline]
fn r0_of(eta: f32) -> f32 {
    ((eta - 1.0) / (eta + 1.0)).powi(2)
}

/// `base / luminance(base)`, or white for a black base: the hue a tint leans towards.
#[inline]
pub fn tint_of(base: Color) -> Color {
    let lum = luminance(base);
    if lum > 0.0 { base / lum } else { Color::ONE }
}

/// Diffuse, retro-reflection, fake subsurface and sheen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrincipledDiffuse {
    /// (1 - metallic) (1 - spec_trans) times the base colour.
    pub color: Color,
    /// (1 - metallic) (1 - spec_trans): how often the lobe is sampled, as in Mitsuba.
    pub weight: f32,
    pub roughness: f32,
    pub flatness: f32,
    /// sheen (1 - metallic) times the sheen's tint.
    pub sheen: Color,
}

impl Lobe for PrincipledDiffuse {
    #[inline]
    fn lifted(self, wl: &crate::spectrum::Wavelengths, _eta_ratio: f32) -> Self {
        PrincipledDiffuse { color: wl.reflectance(self.color), sheen: wl.reflectance(self.sheen), ..self }
    }

    #[inline]
    fn flags(&self) -> LobeFlags {
        LobeFlags::DIFFUSE_REFLECTION
    }

    #[inline]
    fn is_isotropic(&self) -> bool {
        true
    }

    #[inline]
    fn sampling_weight(&self) -> f32 {
        self.weight
    }

    #[inline]
    fn mean_albedo(&self) -> f32 {
        (self.color.mean() + 0.25 * self.sheen.mean()).clamp(1e-3, 1.0)
    }

    #[inline]
    fn lambert_albedo(&self) -> Option<Color> {
        None
    }

    #[inline]
    fn scaled(self, w: f32) -> Self {
        PrincipledDiffuse { color: self.color * w, sheen: self.sheen * w, weight: self.weight * w, ..self }
    }

    #[inline]
    fn f(&self, wo: Vec3, wi: Vec3, _mode: Transport) -> Color {
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return Color::ZERO;
        }
        let (fo, fi) = (schlick_weight(wi.z), schlick_weight(wo.z));
        let diffuse = (1.0 - 0.5 * fi) * (1.0 - 0.5 * fo);
        let h = (wo + wi).normalize_or_zero();
        let cos_d = h.dot(wi);
        let rr = 2.0 * self.roughness * cos_d * cos_d;
        let retro = rr * (fo + fi + fo * fi * (rr - 1.0));
        let mut shape = diffuse + retro;
        if self.flatness != 0.0 {
            let fss90 = 0.5 * rr;
            let fss = (1.0 + (fss90 - 1.0) * fo) * (1.0 + (fss90 - 1.0) * fi);
            let subsurface = 1.25 * (fss * (1.0 / (wi.z + wo.z) - 0.5) + 0.5);
            shape += (subsurface - shape) * self.flatness;
        }
        self.color * (FRAC_1_PI * shape) + self.sheen * schlick_weight(cos_d.abs())
    }

    #[inline]
    fn pdf(&self, wo: Vec3, wi: Vec3, _mode: Transport) -> f32 {
        if wo.z > 0.0 && wi.z > 0.0 { wi.z * FRAC_1_PI } else { 0.0 }
    }

    #[inline]
    fn sample(&self, wo: Vec3, _uc: f32, u: Vec2, mode: Transport) -> Option<BxdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = cosine_hemisphere(u);
        let pdf = wi.z * FRAC_1_PI;
        (pdf > 0.0).then(|| BxdfSample {
            wi,
            weight: self.f(wo, wi, mode) * (wi.z / pdf),
            pdf,
            flags: LobeFlags::DIFFUSE_REFLECTION,
        })
    }
}

/// The main specular lobe: reflection and, with a transmission share, refraction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrincipledSpecular {
    pub mf: Microfacet,
    /// The relative index of the side `wi` refracts into over the viewer's.
    pub eta: f32,
    pub base: Color,
    pub metallic: f32,
    pub spec_tint: f32,
    /// (1 - metallic) spec_trans: the share of light refracted.
    pub trans: f32,
    /// Seen from inside: no metallic or tinted reflection, the dielectric's weighted by `trans`.
    pub inside: bool,
    /// A blend's share (1 otherwise).
    pub scale: f32,
}

impl PrincipledSpecular {
    /// The reflectance of a facet seen at cosine `cos` whose dielectric reflectance is `fd`.
    #[inline]
    fn reflectance(&self, fd: f32, cos: f32) -> Color {
        if self.inside {
            return Color::splat(self.trans * fd);
        }
        let mut f = Color::splat((1.0 - self.metallic) * (1.0 - self.spec_tint) * fd);
        if self.metallic > 0.0 {
            f += schlick(self.base, cos, self.eta) * self.metallic;
        }
        if self.spec_tint > 0.0 {
            let r0 = tint_of(self.base) * r0_of(self.eta);
            f += schlick(r0, cos, self.eta) * ((1.0 - self.metallic) * self.spec_tint);
        }
        f
    }

    /// The probability of choosing reflection at a facet of dielectric reflectance `fd`
    /// (Mitsuba's lobe probabilities, normalised within this lobe).
    #[inline]
    fn p_reflect(&self, fd: f32) -> f32 {
        if self.inside { fd } else { 1.0 - self.trans * (1.0 - fd) }
    }
}

impl Lobe for PrincipledSpecular {
    #[inline]
    fn lifted(self, wl: &crate::spectrum::Wavelengths, _eta_ratio: f32) -> Self {
        PrincipledSpecular { base: wl.reflectance(self.base), ..self }
    }

    #[inline]
    fn flags(&self) -> LobeFlags {
        if self.trans > 0.0 {
            LobeFlags::GLOSSY_REFLECTION | LobeFlags::GLOSSY_TRANSMISSION
        } else {
            LobeFlags::GLOSSY_REFLECTION
        }
    }

    #[inline]
    fn is_isotropic(&self) -> bool {
        self.mf.is_isotropic()
    }

    #[inline]
    fn sampling_weight(&self) -> f32 {
        self.scale
    }

    #[inline]
    fn mean_albedo(&self) -> f32 {
        let r0 = r0_of(self.eta);
        let reflect = if self.inside {
            self.trans * r0
        } else {
            let tinted = r0 * (1.0 + (tint_of(self.base).mean() - 1.0) * self.spec_tint);
            self.metallic * self.base.mean() + (1.0 - self.metallic) * tinted
        };
        let refract = self.trans * (1.0 - r0) * self.base.mean().sqrt();
        (self.scale * (reflect + refract)).clamp(1e-3, 1.0)
    }

    #[inline]
    fn lambert_albedo(&self) -> Option<Color> {
        None
    }

    #[inline]
    fn scaled(self, w: f32) -> Self {
        PrincipledSpecular { scale: self.scale * w, ..self }
    }

    #[inline]
    fn f(&self, wo: Vec3, wi: Vec3, mode: Transport) -> Color {
        if wo.z <= 0.0 || wi.z == 0.0 {
            return Color::ZERO;
        }
        let reflect = wi.z > 0.0;
        if !reflect && !(self.trans > 0.0) {
            return Color::ZERO;
        }
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
        let fd = fresnel_dielectric(oh, self.eta);
        if reflect {
            return self.reflectance(fd, oh) * (self.scale * d * g / (4.0 * wo.z * wi.z));
        }
        let denom = oh + self.eta * ih;
        let mut v = (1.0 - fd) * d * g * (oh * ih).abs() / (wo.z * wi.z.abs() * denom * denom);
        if mode == Transport::Importance {
            v *= self.eta * self.eta;
        }
        // Tinted by the square root of the base colour on both sides (once in, once out).
        self.base.sqrt() * (self.scale * self.trans * v)
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
        let p = self.p_reflect(fresnel_dielectric(oh, self.eta));
        let pm = self.mf.pdf_visible(wo, h);
        if reflect {
            pm * p / (4.0 * ih)
        } else {
            let denom = oh + self.eta * ih;
            pm * (1.0 - p) * self.eta * self.eta * ih.abs() / (denom * denom)
        }
    }

    /// `u` picks a visible facet, `uc` reflection or refraction at it.
    #[inline]
    fn sample(&self, wo: Vec3, uc: f32, u: Vec2, mode: Transport) -> Option<BxdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let m = self.mf.sample_visible(wo, u);
        if !(wo.dot(m) > 0.0) {
            return None;
        }
        let p = self.p_reflect(fresnel_dielectric(wo.dot(m), self.eta));
        let (wi, flags) = if uc < p {
            (reflect_about(wo, m), LobeFlags::GLOSSY_REFLECTION)
        } else {
            (refract(-wo, m, self.eta)?, LobeFlags::GLOSSY_TRANSMISSION)
        };
        if (flags == LobeFlags::GLOSSY_REFLECTION) != (wi.z > 0.0) {
            return None;
        }
        let pdf = self.pdf(wo, wi, mode);
        (pdf > 0.0).then(|| BxdfSample { wi, weight: self.f(wo, wi, mode) * (wi.z.abs() / pdf), pdf, flags })
    }
}

/// The clearcoat: GTR1 facets of roughness `alpha`, Schlick Fresnel of F0 = 0.04.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrincipledClearcoat {
    /// 0.25 clearcoat.
    pub weight: f32,
    /// Between 0.1 (clearcoat_gloss 0) and 0.001 (gloss 1).
    pub alpha: f32,
    /// The material's index (Mitsuba's Schlick term reads it).
    pub eta: f32,
}

impl PrincipledClearcoat {
    /// The GTR1 density of facet normals `m` (per unit projected area).
    #[inline]
    fn d(&self, m: Vec3) -> f32 {
        let a2 = self.alpha * self.alpha;
        let c2 = m.z * m.z;
        let d = (a2 - 1.0) / (PI * a2.ln() * (1.0 + (a2 - 1.0) * c2));
        if d * m.z > 1e-20 { d } else { 0.0 }
    }
}

/// Smith's GGX masking of roughness `alpha` for direction `v` and facet `m`.
#[inline]
fn smith_ggx1(v: Vec3, m: Vec3, alpha: f32) -> f32 {
    if v.dot(m) * v.z <= 0.0 {
        return 0.0;
    }
    if v.z == 1.0 {
        return 1.0;
    }
    let c2 = v.z * v.z;
    let t2 = (1.0 - c2) / c2;
    2.0 / (1.0 + (1.0 + alpha * alpha * t2).sqrt())
}

impl Lobe for PrincipledClearcoat {
    #[inline]
    fn lifted(self, _wl: &crate::spectrum::Wavelengths, _eta_ratio: f32) -> Self {
        self
    }

    #[inline]
    fn flags(&self) -> LobeFlags {
        LobeFlags::GLOSSY_REFLECTION
    }

    #[inline]
    fn is_isotropic(&self) -> bool {
        true
    }

    #[inline]
    fn sampling_weight(&self) -> f32 {
        self.weight
    }

    #[inline]
    fn mean_albedo(&self) -> f32 {
        (0.1 * self.weight).clamp(1e-4, 1.0)
    }

    #[inline]
    fn lambert_albedo(&self) -> Option<Color> {
        None
    }

    #[inline]
    fn scaled(self, w: f32) -> Self {
        PrincipledClearcoat { weight: self.weight * w, ..self }
    }

    #[inline]
    fn f(&self, wo: Vec3, wi: Vec3, _mode: Transport) -> Color {
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return Color::ZERO;
        }
        let h = (wo + wi).normalize_or_zero();
        let oh = wo.dot(h);
        if !(oh > 0.0) {
            return Color::ZERO;
        }
        let fresnel = schlick(Color::splat(0.04), oh, self.eta).r();
        let g = smith_ggx1(wo, h, 0.25) * smith_ggx1(wi, h, 0.25);
        Color::splat(self.weight * fresnel * self.d(h) * g)
    }

    #[inline]
    fn pdf(&self, wo: Vec3, wi: Vec3, _mode: Transport) -> f32 {
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return 0.0;
        }
        let h = (wo + wi).normalize_or_zero();
        let ih = wi.dot(h);
        if !(wo.dot(h) > 0.0 && ih > 0.0) {
            return 0.0;
        }
        h.z * self.d(h) / (4.0 * ih)
    }

    #[inline]
    fn sample(&self, wo: Vec3, _uc: f32, u: Vec2, mode: Transport) -> Option<BxdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let a2 = self.alpha * self.alpha;
        let c2 = (1.0 - a2.powf(1.0 - u.y)) / (1.0 - a2);
        let (s, c) = (c2.clamp(0.0, 1.0), (1.0 - c2).clamp(0.0, 1.0));
        let (sin_phi, cos_phi) = (2.0 * PI * u.x).sin_cos();
        let m = Vec3::new(cos_phi * c.sqrt(), sin_phi * c.sqrt(), s.sqrt());
        let wi = reflect_about(wo, m);
        let pdf = self.pdf(wo, wi, mode);
        (pdf > 0.0).then(|| BxdfSample {
            wi,
            weight: self.f(wo, wi, mode) * (wi.z / pdf),
            pdf,
            flags: LobeFlags::GLOSSY_REFLECTION,
        })
    }
}

/// Lambertian transmission (the thin principled BSDF's `diff_trans`): `t / pi` on the far side,
/// sampled by the cosine there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiffuseTransmission {
    pub t: Color,
    /// How often it is sampled: (1 - spec_trans) diff_trans, Mitsuba's probability.
    pub weight: f32,
}

impl Lobe for DiffuseTransmission {
    #[inline]
    fn lifted(self, wl: &crate::spectrum::Wavelengths, _eta_ratio: f32) -> Self {
        DiffuseTransmission { t: wl.reflectance(self.t), ..self }
    }

    #[inline]
    fn flags(&self) -> LobeFlags {
        LobeFlags::TRANSMISSION | LobeFlags::DIFFUSE
    }

    #[inline]
    fn is_isotropic(&self) -> bool {
        true
    }

    #[inline]
    fn sampling_weight(&self) -> f32 {
        self.weight
    }

    #[inline]
    fn mean_albedo(&self) -> f32 {
        self.t.mean()
    }

    #[inline]
    fn lambert_albedo(&self) -> Option<Color> {
        None
    }

    #[inline]
    fn scaled(self, w: f32) -> Self {
        DiffuseTransmission { t: self.t * w, weight: self.weight * w }
    }

    #[inline]
    fn f(&self, wo: Vec3, wi: Vec3, _mode: Transport) -> Color {
        if wo.z > 0.0 && wi.z < 0.0 { self.t * FRAC_1_PI } else { Color::ZERO }
    }

    #[inline]
    fn pdf(&self, wo: Vec3, wi: Vec3, _mode: Transport) -> f32 {
        if wo.z > 0.0 && wi.z < 0.0 { -wi.z * FRAC_1_PI } else { 0.0 }
    }

    #[inline]
    fn sample(&self, wo: Vec3, _uc: f32, u: Vec2, _mode: Transport) -> Option<BxdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let w = cosine_hemisphere(u);
        let wi = Vec3::new(w.x, w.y, -w.z);
        let pdf = w.z * FRAC_1_PI;
        let flags = LobeFlags::TRANSMISSION | LobeFlags::DIFFUSE;
        (pdf > 0.0).then_some(BxdfSample { wi, weight: self.t, pdf, flags })
    }
}

/// The thin principled BSDF's specular part: GGX reflection with the thin Fresnel term and,
/// through the sheet, the mirror image of a reflection off facets of a roughness scaled by the
/// index (Burley 2015), tinted by the base colour; half the samples each, as Mitsuba.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinSpecular {
    pub mf: Microfacet,
    /// The facets seen through the sheet.
    pub mf_through: Microfacet,
    pub eta: f32,
    pub base: Color,
    pub spec_tint: f32,
    /// spec_trans (times a blend's share).
    pub weight: f32,
}

impl ThinSpecular {
    /// The half vector of `wo` and `wi` mirrored to the viewer's side.
    #[inline]
    fn half(wo: Vec3, wi: Vec3) -> Vec3 {
        (wo + Vec3::new(wi.x, wi.y, wi.z.abs())).normalize_or_zero()
    }
}

impl Lobe for ThinSpecular {
    #[inline]
    fn lifted(self, wl: &crate::spectrum::Wavelengths, _eta_ratio: f32) -> Self {
        ThinSpecular { base: wl.reflectance(self.base), ..self }
    }

    #[inline]
    fn flags(&self) -> LobeFlags {
        LobeFlags::GLOSSY_REFLECTION | LobeFlags::GLOSSY_TRANSMISSION
    }

    #[inline]
    fn is_isotropic(&self) -> bool {
        self.mf.is_isotropic() && self.mf_through.is_isotropic()
    }

    #[inline]
    fn sampling_weight(&self) -> f32 {
        self.weight
    }

    #[inline]
    fn mean_albedo(&self) -> f32 {
        (self.weight * (r0_of(self.eta) + (1.0 - r0_of(self.eta)) * self.base.mean())).clamp(1e-3, 1.0)
    }

    #[inline]
    fn lambert_albedo(&self) -> Option<Color> {
        None
    }

    #[inline]
    fn scaled(self, w: f32) -> Self {
        ThinSpecular { weight: self.weight * w, ..self }
    }

    #[inline]
    fn f(&self, wo: Vec3, wi: Vec3, _mode: Transport) -> Color {
        if wo.z <= 0.0 || wi.z == 0.0 {
            return Color::ZERO;
        }
        let h = Self::half(wo, wi);
        let (oh, ih) = (wo.dot(h), wi.dot(h));
        let fd = fresnel_dielectric(oh, self.eta);
        if wi.z > 0.0 {
            if !(oh > 0.0 && ih > 0.0) {
                return Color::ZERO;
            }
            let mut fresnel = Color::splat(fd);
            if self.spec_tint > 0.0 {
                let schlick_part = schlick(tint_of(self.base) * r0_of(self.eta), oh, self.eta);
                fresnel = fresnel + (schlick_part - fresnel) * self.spec_tint;
            }
            let dg = self.mf.d(h) * self.mf.g(wo, wi, h);
            return fresnel * (self.weight * dg / (4.0 * wo.z * wi.z));
        }
        // Through the sheet: the facet must face the viewer and turn away from `wi`.
        if !(oh > 0.0 && ih < 0.0) {
            return Color::ZERO;
        }
        let dg = self.mf_through.d(h) * self.mf_through.g(wo, wi, h);
        self.base * (self.weight * (1.0 - fd) * dg / (4.0 * wo.z * wi.z.abs()))
    }

    #[inline]
    fn pdf(&self, wo: Vec3, wi: Vec3, _mode: Transport) -> f32 {
        if wo.z <= 0.0 || wi.z == 0.0 {
            return 0.0;
        }
        let h = Self::half(wo, wi);
        let (oh, ih) = (wo.dot(h), wi.dot(h));
        let mirrored = Vec3::new(wi.x, wi.y, wi.z.abs());
        let jacobian = 1.0 / (4.0 * mirrored.dot(h).abs());
        if wi.z > 0.0 {
            if !(oh > 0.0 && ih > 0.0) {
                return 0.0;
            }
            0.5 * self.mf.pdf_visible(wo, h) * jacobian
        } else {
            if !(oh > 0.0 && ih < 0.0) {
                return 0.0;
            }
            0.5 * self.mf_through.pdf_visible(wo, h) * jacobian
        }
    }

    /// `uc` chooses reflection or transmission (half each), `u` the facet.
    #[inline]
    fn sample(&self, wo: Vec3, uc: f32, u: Vec2, mode: Transport) -> Option<BxdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let (wi, flags) = if uc < 0.5 {
            (reflect_about(wo, self.mf.sample_visible(wo, u)), LobeFlags::GLOSSY_REFLECTION)
        } else {
            let r = reflect_about(wo, self.mf_through.sample_visible(wo, u));
            (Vec3::new(r.x, r.y, -r.z), LobeFlags::GLOSSY_TRANSMISSION)
        };
        if (flags == LobeFlags::GLOSSY_REFLECTION) != (wi.z > 0.0) {
            return None;
        }
        let pdf = self.pdf(wo, wi, mode);
        (pdf > 0.0).then(|| BxdfSample { wi, weight: self.f(wo, wi, mode) * (wi.z.abs() / pdf), pdf, flags })
    }
}
