//! Scattering lobes: a closed set of small `Copy` BxDFs, each working in the local shading frame
//! (z = shading normal, on the side the light leaves towards the viewer for two-sided surfaces).
//!
//! Contract (pbrt-v4 `BxDF`, Mitsuba 3 `BSDF`): directions point away from the surface and are
//! unit vectors in the local frame; `wo` is towards the viewer (or where a photon came from), `wi`
//! the other direction. `f` excludes the cosine; `pdf` is per unit solid angle of `wi` and is 0
//! for delta lobes; `sample` returns the Monte Carlo weight f |cos wi| / pdf directly, and for a
//! delta lobe its discrete probability as `pdf`. Transport mode: radiance refracting into a denser
//! medium is scaled by 1 / eta^2, importance (photon flux) is not.

mod conductor;
mod plastic;
mod rough_dielectric;

pub use conductor::{Conductor, RoughConductor, reflect_about};
pub use plastic::{CoatingTable, FresnelMirror, PlasticDiffuse, RoughCoating, RoughPlasticDiffuse};
pub use rough_dielectric::RoughDielectric;

use super::fresnel::fresnel_dielectric;
use crate::math::{Color, Frame, Vec2, Vec3, luminance};
use crate::sampling::warp::cosine_hemisphere;
use std::f32::consts::{FRAC_1_PI, PI};

/// Which way light flows along the path being traced: camera paths carry radiance, photon paths
/// carry flux (importance). Refraction scales radiance by 1/eta^2 but not flux.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transport {
    Radiance,
    Importance,
}

/// Kinds of scattering, as bits: reflection or transmission, diffuse, glossy or specular.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct LobeFlags(u8);

impl LobeFlags {
    pub const NONE: LobeFlags = LobeFlags(0);
    pub const REFLECTION: LobeFlags = LobeFlags(1);
    pub const TRANSMISSION: LobeFlags = LobeFlags(2);
    pub const DIFFUSE: LobeFlags = LobeFlags(4);
    pub const GLOSSY: LobeFlags = LobeFlags(8);
    pub const SPECULAR: LobeFlags = LobeFlags(16);
    pub const DIFFUSE_REFLECTION: LobeFlags = LobeFlags(1 | 4);
    pub const GLOSSY_REFLECTION: LobeFlags = LobeFlags(1 | 8);
    pub const SPECULAR_REFLECTION: LobeFlags = LobeFlags(1 | 16);
    pub const SPECULAR_TRANSMISSION: LobeFlags = LobeFlags(2 | 16);
    pub const GLOSSY_TRANSMISSION: LobeFlags = LobeFlags(2 | 8);
    /// Straight through without scattering (the transparent part of a `mask`).
    pub const NULL: LobeFlags = LobeFlags(32);

    /// True when every bit of `other` is set.
    #[inline]
    pub fn contains(self, other: LobeFlags) -> bool {
        self.0 & other.0 == other.0
    }

    /// True when any bit of `other` is set.
    #[inline]
    pub fn intersects(self, other: LobeFlags) -> bool {
        self.0 & other.0 != 0
    }

    /// A delta direction: specular scattering or passing straight through.
    #[inline]
    pub fn is_specular(self) -> bool {
        self.intersects(LobeFlags(16 | 32))
    }

    #[inline]
    pub fn is_null(self) -> bool {
        self.intersects(LobeFlags::NULL)
    }

    #[inline]
    pub fn is_diffuse(self) -> bool {
        self.intersects(LobeFlags::DIFFUSE)
    }

    #[inline]
    pub fn is_glossy(self) -> bool {
        self.intersects(LobeFlags::GLOSSY)
    }

    #[inline]
    pub fn is_transmission(self) -> bool {
        self.intersects(LobeFlags::TRANSMISSION)
    }
}

impl std::ops::BitOr for LobeFlags {
    type Output = LobeFlags;
    fn bitor(self, o: LobeFlags) -> LobeFlags {
        LobeFlags(self.0 | o.0)
    }
}

impl std::ops::BitOrAssign for LobeFlags {
    fn bitor_assign(&mut self, o: LobeFlags) {
        self.0 |= o.0;
    }
}

/// A direction sampled from one lobe, in the local frame.
#[derive(Clone, Copy, Debug)]
pub struct BxdfSample {
    pub wi: Vec3,
    /// f |cos wi| / pdf.
    pub weight: Color,
    /// Solid-angle density of `wi`, or for a delta lobe the probability of having chosen it.
    pub pdf: f32,
    pub flags: LobeFlags,
}

/// Lambertian reflection: f = r / pi.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lambert {
    pub r: Color,
}

/// Normalised (energy-conserving) Phong reflection around the mirror direction (Lafortune and
/// Willems 1994): f = ks (n + 2) / (2 pi) cos^n(alpha), alpha the angle between wi and the mirror
/// direction of wo.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Phong {
    pub ks: f32,
    pub exponent: f32,
}

/// Perfect mirror reflection with reflectance `r` (seed eq. 3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mirror {
    pub r: Color,
}

/// Perfect refraction (seed eq. 4) with a fixed transmittance `t` (the seed report's
/// `transparent` k_t); `eta` is the index of the side `wi` enters over the side of `wo`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transmission {
    pub t: f32,
    pub eta: f32,
}

/// A smooth dielectric interface: reflection and refraction weighted by the Fresnel equations
/// (seed eq. 5-8), total internal reflection included; `eta` as for `Transmission`. `r` and `t`
/// scale the two (Mitsuba's `specular_reflectance` and `specular_transmittance`, 1 for glass).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dielectric {
    pub eta: f32,
    pub r: Color,
    pub t: Color,
}

impl Dielectric {
    /// Clear glass of relative index `eta`.
    pub fn clear(eta: f32) -> Self {
        Dielectric { eta, r: Color::ONE, t: Color::ONE }
    }
}

/// One scattering lobe.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bxdf {
    Lambert(Lambert),
    Phong(Phong),
    Mirror(Mirror),
    Transmission(Transmission),
    Dielectric(Dielectric),
    Conductor(Conductor),
    RoughConductor(RoughConductor),
    RoughDielectric(RoughDielectric),
    FresnelMirror(FresnelMirror),
    PlasticDiffuse(PlasticDiffuse),
    RoughCoating(RoughCoating),
    RoughPlasticDiffuse(RoughPlasticDiffuse),
}

/// Mirror direction of `w` about the local normal (seed eq. 3 with I = -w).
#[inline]
pub fn reflect_local(w: Vec3) -> Vec3 {
    Vec3::new(-w.x, -w.y, w.z)
}

/// Refracted direction of `wo` (local, on the +z side) into a medium of relative index `eta`
/// (seed eq. 4); `None` under total internal reflection.
#[inline]
pub fn refract_local(wo: Vec3, eta: f32) -> Option<Vec3> {
    super::fresnel::refract(-wo, Vec3::Z, eta)
}

/// A direction around `r` with density proportional to cos^n of the angle to it.
#[inline]
pub fn sample_phong(r: Vec3, exponent: f32, u: Vec2) -> Vec3 {
    let cos_a = u.x.powf(1.0 / (exponent + 1.0));
    let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Frame::from_z(r).to_world(Vec3::new(sin_a * phi.cos(), sin_a * phi.sin(), cos_a))
}

/// The weight with which a lobe of reflectance `c` is chosen for sampling: its luminance, but
/// never below a tenth of its brightest channel (so a saturated colour is still sampled).
#[inline]
pub(crate) fn colour_weight(c: Color) -> f32 {
    luminance(c).max(c.max_element() * 0.1)
}

impl Bxdf {
    #[inline]
    pub fn flags(&self) -> LobeFlags {
        match self {
            Bxdf::Lambert(_) => LobeFlags::DIFFUSE_REFLECTION,
            Bxdf::Phong(_) => LobeFlags::GLOSSY_REFLECTION,
            Bxdf::Mirror(_) => LobeFlags::SPECULAR_REFLECTION,
            Bxdf::Transmission(_) => LobeFlags::SPECULAR_TRANSMISSION,
            Bxdf::Dielectric(_) => LobeFlags::SPECULAR_REFLECTION | LobeFlags::SPECULAR_TRANSMISSION,
            Bxdf::Conductor(_) | Bxdf::FresnelMirror(_) => LobeFlags::SPECULAR_REFLECTION,
            Bxdf::RoughConductor(_) | Bxdf::RoughCoating(_) => LobeFlags::GLOSSY_REFLECTION,
            Bxdf::RoughDielectric(_) => LobeFlags::GLOSSY_REFLECTION | LobeFlags::GLOSSY_TRANSMISSION,
            Bxdf::PlasticDiffuse(_) | Bxdf::RoughPlasticDiffuse(_) => LobeFlags::DIFFUSE_REFLECTION,
        }
    }

    /// True when the lobe looks the same however the surface is turned about its normal (all
    /// but anisotropic lobes), so its frame's tangent may be any perpendicular direction.
    #[inline]
    pub fn is_isotropic(&self) -> bool {
        match self {
            Bxdf::RoughConductor(b) => b.mf.is_isotropic(),
            Bxdf::RoughDielectric(b) => b.mf.is_isotropic(),
            Bxdf::RoughCoating(b) => b.mf.is_isotropic(),
            _ => true,
        }
    }

    /// How often this lobe is sampled relative to the others of a mixture: an estimate of its
    /// albedo (1 for a dielectric, which always reflects or transmits everything).
    #[inline]
    pub fn sampling_weight(&self) -> f32 {
        match self {
            Bxdf::Lambert(b) => colour_weight(b.r),
            Bxdf::Phong(b) => b.ks,
            Bxdf::Mirror(b) => colour_weight(b.r),
            Bxdf::Transmission(b) => b.t,
            Bxdf::Dielectric(b) => colour_weight(b.r.max(b.t)),
            Bxdf::Conductor(b) => colour_weight(b.albedo()),
            Bxdf::RoughConductor(b) => colour_weight(b.albedo()),
            Bxdf::RoughDielectric(b) => colour_weight(b.r.max(b.t)),
            // A plastic's two lobes in Mitsuba's proportion: the coating's mean specular
            // reflectance against the base's mean reflectance (then times `selection`).
            Bxdf::FresnelMirror(b) => b.scale.mean(),
            Bxdf::RoughCoating(b) => b.scale.mean(),
            Bxdf::PlasticDiffuse(b) => b.d_mean,
            Bxdf::RoughPlasticDiffuse(b) => b.d_mean,
        }
    }

    /// How much more or less likely the lobe is to be chosen when seen from `wo` (local): a
    /// plastic's coating in proportion to its reflectance, its base to its transmittance.
    #[inline]
    pub fn selection(&self, wo: Vec3) -> f32 {
        match self {
            Bxdf::FresnelMirror(b) => fresnel_dielectric(wo.z, b.eta),
            Bxdf::PlasticDiffuse(b) => 1.0 - fresnel_dielectric(wo.z, b.eta),
            Bxdf::RoughCoating(b) => 1.0 - b.table.transmittance(wo.z),
            Bxdf::RoughPlasticDiffuse(b) => b.table.transmittance(wo.z),
            _ => 1.0,
        }
    }

    /// The lobe with its values (and so its albedo) scaled by `w` in [0, 1]: a blend's share.
    pub fn scaled(self, w: f32) -> Bxdf {
        let c = Color::splat(w);
        match self {
            Bxdf::Lambert(b) => Bxdf::Lambert(Lambert { r: b.r * c }),
            Bxdf::Phong(b) => Bxdf::Phong(Phong { ks: b.ks * w, ..b }),
            Bxdf::Mirror(b) => Bxdf::Mirror(Mirror { r: b.r * c }),
            Bxdf::Transmission(b) => Bxdf::Transmission(Transmission { t: b.t * w, ..b }),
            Bxdf::Dielectric(b) => Bxdf::Dielectric(Dielectric { r: b.r * c, t: b.t * c, ..b }),
            Bxdf::Conductor(b) => Bxdf::Conductor(Conductor { scale: b.scale * c, ..b }),
            Bxdf::RoughConductor(b) => Bxdf::RoughConductor(RoughConductor { scale: b.scale * c, ..b }),
            Bxdf::RoughDielectric(b) => Bxdf::RoughDielectric(RoughDielectric { r: b.r * c, t: b.t * c, ..b }),
            Bxdf::FresnelMirror(b) => Bxdf::FresnelMirror(FresnelMirror { scale: b.scale * c, ..b }),
            Bxdf::PlasticDiffuse(b) => Bxdf::PlasticDiffuse(PlasticDiffuse { d: b.d * c, d_mean: b.d_mean * w, ..b }),
            Bxdf::RoughCoating(b) => Bxdf::RoughCoating(RoughCoating { scale: b.scale * c, ..b }),
            Bxdf::RoughPlasticDiffuse(b) => {
                Bxdf::RoughPlasticDiffuse(RoughPlasticDiffuse { d: b.d * c, d_mean: b.d_mean * w, ..b })
            }
        }
    }

    /// True when the lobe's choice depends on the viewing direction (see `selection`).
    #[inline]
    pub fn directional_selection(&self) -> bool {
        matches!(
            self,
            Bxdf::FresnelMirror(_) | Bxdf::PlasticDiffuse(_) | Bxdf::RoughCoating(_) | Bxdf::RoughPlasticDiffuse(_)
        )
    }

    /// The lobe's albedo averaged over the colour channels (1 for a dielectric): photons pick
    /// lobes in proportion to it, as Jensen's Russian roulette does.
    #[inline]
    pub fn mean_albedo(&self) -> f32 {
        match self {
            Bxdf::Lambert(b) => b.r.mean(),
            Bxdf::Phong(b) => b.ks,
            Bxdf::Mirror(b) => b.r.mean(),
            Bxdf::Transmission(b) => b.t,
            Bxdf::Dielectric(b) => b.r.max(b.t).mean(),
            Bxdf::Conductor(b) => b.albedo().mean(),
            Bxdf::RoughConductor(b) => b.albedo().mean(),
            Bxdf::RoughDielectric(b) => b.r.max(b.t).mean(),
            // Fresnel reflectance of a coating averaged over directions is about its F_dr.
            Bxdf::FresnelMirror(b) => b.scale.mean() * super::fresnel::fresnel_diffuse_reflectance(b.eta),
            Bxdf::RoughCoating(b) => b.scale.mean() * super::fresnel::fresnel_diffuse_reflectance(b.eta),
            Bxdf::PlasticDiffuse(b) => b.d.mean(),
            Bxdf::RoughPlasticDiffuse(b) => b.d.mean(),
        }
    }

    /// The lobe's value for the pair (reflection lobes only where `wi` is above the surface).
    #[inline]
    pub fn f(&self, wo: Vec3, wi: Vec3, mode: Transport) -> Color {
        match self {
            Bxdf::RoughConductor(b) => b.f(wo, wi),
            Bxdf::RoughDielectric(b) => b.f(wo, wi, mode),
            Bxdf::PlasticDiffuse(b) => b.f(wo, wi),
            Bxdf::RoughCoating(b) => b.f(wo, wi),
            Bxdf::RoughPlasticDiffuse(b) => b.f(wo, wi),
            Bxdf::Lambert(b) if wi.z > 0.0 => b.r * FRAC_1_PI,
            Bxdf::Phong(b) if wi.z > 0.0 => {
                let c = reflect_local(wo).dot(wi);
                if c > 0.0 {
                    Color::splat(b.ks * (b.exponent + 2.0) / (2.0 * PI) * c.powf(b.exponent))
                } else {
                    Color::ZERO
                }
            }
            _ => Color::ZERO,
        }
    }

    /// Solid-angle density with which `sample` picks `wi` (0 for delta lobes).
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3, _mode: Transport) -> f32 {
        match self {
            Bxdf::RoughConductor(b) => b.pdf(wo, wi),
            Bxdf::RoughDielectric(b) => b.pdf(wo, wi),
            Bxdf::PlasticDiffuse(_) | Bxdf::RoughPlasticDiffuse(_) if wi.z > 0.0 && wo.z > 0.0 => wi.z * FRAC_1_PI,
            Bxdf::RoughCoating(b) => b.pdf(wo, wi),
            Bxdf::Lambert(_) if wi.z > 0.0 => wi.z * FRAC_1_PI,
            Bxdf::Phong(b) if wi.z > 0.0 => {
                let c = reflect_local(wo).dot(wi);
                if c > 0.0 { (b.exponent + 1.0) / (2.0 * PI) * c.powf(b.exponent) } else { 0.0 }
            }
            _ => 0.0,
        }
    }

    /// Samples `wi`: `uc` chooses between reflection and transmission where a lobe has both, `u`
    /// picks the direction.
    #[inline]
    pub fn sample(&self, wo: Vec3, uc: f32, u: Vec2, mode: Transport) -> Option<BxdfSample> {
        match *self {
            Bxdf::Lambert(b) => {
                let wi = cosine_hemisphere(u);
                let pdf = wi.z * FRAC_1_PI;
                (pdf > 0.0).then_some(BxdfSample { wi, weight: b.r, pdf, flags: LobeFlags::DIFFUSE_REFLECTION })
            }
            Bxdf::Phong(_) => {
                let wi = sample_phong(reflect_local(wo), self.phong_exponent(), u);
                let pdf = self.pdf(wo, wi, mode);
                if !(pdf > 0.0) {
                    return None;
                }
                let weight = self.f(wo, wi, mode) * (wi.z / pdf);
                Some(BxdfSample { wi, weight, pdf, flags: LobeFlags::GLOSSY_REFLECTION })
            }
            Bxdf::Mirror(b) => {
                Some(BxdfSample { wi: reflect_local(wo), weight: b.r, pdf: 1.0, flags: LobeFlags::SPECULAR_REFLECTION })
            }
            Bxdf::Transmission(b) => match refract_local(wo, b.eta) {
                Some(wi) => {
                    let scale = if mode == Transport::Radiance { 1.0 / (b.eta * b.eta) } else { 1.0 };
                    Some(BxdfSample {
                        wi,
                        weight: Color::splat(b.t * scale),
                        pdf: 1.0,
                        flags: LobeFlags::SPECULAR_TRANSMISSION,
                    })
                }
                // Total internal reflection: the share k_t that cannot leave is reflected, as the
                // Whitted integrator (and the seed report's fix for its image 5) does.
                None => Some(BxdfSample {
                    wi: reflect_local(wo),
                    weight: Color::splat(b.t),
                    pdf: 1.0,
                    flags: LobeFlags::SPECULAR_REFLECTION,
                }),
            },
            Bxdf::Dielectric(b) => {
                let fr = fresnel_dielectric(wo.z, b.eta);
                if uc < fr {
                    let wi = reflect_local(wo);
                    Some(BxdfSample { wi, weight: b.r, pdf: fr, flags: LobeFlags::SPECULAR_REFLECTION })
                } else {
                    let wi = refract_local(wo, b.eta)?;
                    let scale = if mode == Transport::Radiance { 1.0 / (b.eta * b.eta) } else { 1.0 };
                    Some(BxdfSample { wi, weight: b.t * scale, pdf: 1.0 - fr, flags: LobeFlags::SPECULAR_TRANSMISSION })
                }
            }
            Bxdf::Conductor(b) => b.sample(wo),
            Bxdf::RoughConductor(b) => b.sample(wo, u),
            Bxdf::RoughDielectric(b) => b.sample(wo, uc, u, mode),
            Bxdf::FresnelMirror(b) => b.sample(wo),
            Bxdf::PlasticDiffuse(b) => b.sample(wo, u),
            Bxdf::RoughCoating(b) => b.sample(wo, u),
            Bxdf::RoughPlasticDiffuse(b) => b.sample(wo, u),
        }
    }

    fn phong_exponent(&self) -> f32 {
        match self {
            Bxdf::Phong(b) => b.exponent,
            _ => 0.0,
        }
    }
}
