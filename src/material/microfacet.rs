//! Microfacet normal distributions, Beckmann and GGX (Trowbridge-Reitz), computed as Mitsuba 3.9.1
//! does (`include/mitsuba/render/microfacet.h`, `MicrofacetDistribution`): the distribution D(m)
//! of Walter et al. 2007 ("Microfacet models for refraction through rough surfaces"), Smith's
//! masking G1 in its separable form G = G1(wi) G1(wo) (Beckmann's G1 by Walter et al.'s rational
//! fit), visible-normal sampling after Heitz and d'Eon 2014 ("Importance sampling microfacet-based
//! BSDFs using the distribution of visible normals") with Heitz 2018 ("Sampling the GGX
//! distribution of visible normals", in Mitsuba's concentric-disk variant) for GGX and Jakob 2014
//! ("An improved visible normal sampling routine for the Beckmann distribution") for Beckmann, and
//! the classic sampling of D(m) cos θm.
//!
//! Everything works in the local shading frame: z is the shading normal, x the tangent along
//! dp/du (so `alpha_u` is the roughness along dp/du), y = z × x, as in Mitsuba's `sh_frame`.
//!
//! The distributions and the mapping from (wi, u) to m are Mitsuba's; `tests.rs` checks values
//! and samples against vectors from Mitsuba itself (`scripts/microfacet_vectors.py`: sampled
//! normals agree to 1.3e-5). Departures in the arithmetic, with what they change:
//! - Beckmann visible sampling inverts its slope CDF in f64 (Mitsuba: f32). The unknown x lives in
//!   the erf domain, where grazing incidence and small u.x put it within 1e-6 or less of -1; f32
//!   resolves x there only to 6e-8, and erfinv multiplies an error in x by (sqrt(pi)/2) e^(slope^2)
//!   (8e3 at slope 3). Mitsuba's f32 normals land up to 1.5e-5 from the f64 ones at u.x = 1e-4
//!   and up to 1.9e-4 at u.x = 1e-5, at 80 to 89 degrees (`microfacet_vectors.py --report`).
//! - The sines of the elevation angles are computed from the sine side (the x and y of the
//!   stretched wi; tan^2 θm when sampling D cos θm) rather than as sqrt(1 - cos^2), which in f32
//!   cannot resolve angles below about 3e-4 radians.
//! - GGX visible sampling floors the unit-roughness normal's z at 1e-7, which Mitsuba lets reach 0
//!   (and the normal NaN) when u lies on the edge of the unit square (see `ggx_visible_slope`).
//!
//! Kept from Mitsuba on purpose, so that samples match its own: the Beckmann inversion's three
//! Newton steps, which leave up to 3e-6 of probability misplaced at the upper end of the slopes
//! (`tests.rs` measures it), and the fitted Beckmann G1, which makes `pdf_visible` integrate to
//! within 0.35% of 1 rather than to 1 (see there). `lambda` has no counterpart in Mitsuba; it is
//! the Λ whose 1 / (1 + Λ) is exactly `g1`.

pub mod erf;

use crate::math::{Vec2, Vec3};
use crate::sampling::warp::concentric_disk;
use erf::{FRAC_1_SQRT_PI, erf, erfinv};
use std::f32::consts::{FRAC_1_PI, TAU};

/// The shape of the microfacet slope distribution.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Distribution {
    /// Gaussian slopes (Beckmann 1963): short tails. Mitsuba's default.
    Beckmann,
    /// GGX / Trowbridge-Reitz (Walter et al. 2007): long tails, the glow around highlights.
    Ggx,
}

/// A microfacet distribution in the local shading frame (z = normal, x = the dp/du tangent).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Microfacet {
    pub distribution: Distribution,
    /// Roughness along x (the dp/du tangent).
    pub alpha_u: f32,
    /// Roughness along y.
    pub alpha_v: f32,
}

/// The smallest roughness Mitsuba allows (it advises a smooth model instead); D then peaks at
/// 1 / (pi 1e-8) = 3e7, far from overflowing f32.
const MIN_ALPHA: f32 = 1e-4;

/// Mitsuba keeps the unit square samples of the Beckmann inversion this far from 0 and 1, where
/// ln(u.x) and erfinv(2 u.y - 1) diverge; it cuts a probability of about 2e-6 from the slopes' tails.
const BECKMANN_SAMPLE_MARGIN: f32 = 1e-6;

/// Below this squared sine (4 x 2^-24, Mitsuba's `Frame3f::sincos_phi`) the stretched incident
/// direction counts as normal and its azimuth as 0, rather than as 0/0.
const NORMAL_SIN_THETA_2: f32 = 2.0 * f32::EPSILON;

/// The floor of the z of a GGX visible normal in the unit-roughness frame (see `ggx_visible_slope`).
const MIN_NORMAL_Z: f32 = 1e-7;

impl Microfacet {
    /// Clamps both alphas to at least 1e-4 as Mitsuba does.
    #[inline]
    pub fn new(distribution: Distribution, alpha_u: f32, alpha_v: f32) -> Self {
        Microfacet { distribution, alpha_u: alpha_u.max(MIN_ALPHA), alpha_v: alpha_v.max(MIN_ALPHA) }
    }

    #[inline]
    pub fn is_isotropic(&self) -> bool {
        self.alpha_u == self.alpha_v
    }

    /// D(m), the density of microfacet normals per unit projected area: ∫ D(m) cos θm dω = 1.
    /// 0 when D·cos θm <= 1e-20 (m.z <= 0 included), as in Mitsuba, which guards what is computed
    /// from D further on against underflowed and non-finite values.
    #[inline]
    pub fn d(&self, m: Vec3) -> f32 {
        let cos_theta_2 = m.z * m.z;
        let x = m.x / self.alpha_u;
        let y = m.y / self.alpha_v;
        let result = match self.distribution {
            Distribution::Beckmann => {
                (-(x * x + y * y) / cos_theta_2).exp()
                    / (std::f32::consts::PI * self.alpha_u * self.alpha_v * cos_theta_2 * cos_theta_2)
            }
            Distribution::Ggx => {
                let s = x * x + y * y + cos_theta_2;
                FRAC_1_PI / (self.alpha_u * self.alpha_v * s * s)
            }
        };
        // Written so that NaN (0/0 at m.z = 0) also gives 0.
        if result * m.z > 1e-20 { result } else { 0.0 }
    }

    /// alpha(φ)^2 tan^2 θ of a direction, the one number Smith's Λ depends on; infinite at v.z = 0.
    #[inline]
    fn alpha_tan_2(&self, v: Vec3) -> f32 {
        let x = self.alpha_u * v.x;
        let y = self.alpha_v * v.y;
        (x * x + y * y) / (v.z * v.z)
    }

    /// Smith's Λ(v) for this distribution (for anyone needing the height-correlated form later).
    ///
    /// It is the Λ of Mitsuba's `smith_g1`: 1 / (1 + Λ(v)) equals `g1(v, m)` for any m facing v.
    /// For GGX that is the exact (sqrt(1 + α² tan² θ) - 1) / 2. For Beckmann it is the rational fit
    /// (1 - 1.259 a + 0.396 a²) / (3.535 a + 2.181 a²), a = 1 / (α tan θ), and 0 for a >= 1.6
    /// (as pbrt-v3's `BeckmannDistribution::Lambda`): 1 / (1 + Λ) is within 0.35% of the exact
    /// one, (erf(a) - 1) / 2 + exp(-a²) / (2 a sqrt(pi)), and dips to -6e-5 just below a = 1.6,
    /// where Mitsuba's G1 slightly exceeds 1. Even in v, and +infinity at grazing (v.z = 0).
    #[inline]
    pub fn lambda(&self, v: Vec3) -> f32 {
        let t = self.alpha_tan_2(v);
        if t.is_infinite() {
            return f32::INFINITY;
        }
        match self.distribution {
            Distribution::Beckmann => {
                let a = 1.0 / t.sqrt();
                if a >= 1.6 { 0.0 } else { (1.0 - 1.259 * a + 0.396 * a * a) / (3.535 * a + 2.181 * a * a) }
            }
            // (sqrt(1 + t) - 1) / 2 without the cancellation at small t.
            Distribution::Ggx => 0.5 * t / (1.0 + (1.0 + t).sqrt()),
        }
    }

    /// Mitsuba's smith_g1: G1(v, m), 0 when (v·m)(v.z) <= 0.
    ///
    /// The fraction of microfacets with normal m visible from direction v; 1 at v = +-z, and 0 for
    /// a facet seen from behind (v·m and v.z of opposite signs) or a grazing v.
    #[inline]
    pub fn g1(&self, v: Vec3, m: Vec3) -> f32 {
        if v.dot(m) * v.z <= 0.0 {
            return 0.0;
        }
        let t = self.alpha_tan_2(v);
        if t == 0.0 {
            return 1.0;
        }
        match self.distribution {
            Distribution::Beckmann => {
                let a = 1.0 / t.sqrt();
                if a >= 1.6 { 1.0 } else { (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a) }
            }
            Distribution::Ggx => 2.0 / (1.0 + (1.0 + t).sqrt()),
        }
    }

    /// Separable G(wi, wo, m) = G1(wi, m) G1(wo, m) (Mitsuba's choice, not height-correlated).
    #[inline]
    pub fn g(&self, wi: Vec3, wo: Vec3, m: Vec3) -> f32 {
        self.g1(wi, m) * self.g1(wo, m)
    }

    /// Samples a normal from the distribution of normals visible from `wi` (wi.z > 0), as Mitsuba's
    /// `sample` with sample_visible = true: GGX by the Heitz 2018 construction in Mitsuba's variant,
    /// Beckmann by Jakob's numerical inversion. Returns m with m.z > 0.
    ///
    /// The steps: stretch wi to the unit-roughness configuration, sample a slope of the α = 1
    /// distribution seen from there, rotate it to wi's azimuth, unstretch it, and turn the slope
    /// into a normal. The density of m is `pdf_visible(wi, m)`.
    #[inline]
    pub fn sample_visible(&self, wi: Vec3, u: Vec2) -> Vec3 {
        let stretched = Vec3::new(self.alpha_u * wi.x, self.alpha_v * wi.y, wi.z).normalize();
        let sin_theta_2 = stretched.x * stretched.x + stretched.y * stretched.y;
        let (cos_phi, sin_phi, sin_theta) = if sin_theta_2 <= NORMAL_SIN_THETA_2 {
            (1.0, 0.0, sin_theta_2.sqrt())
        } else {
            let sin_theta = sin_theta_2.sqrt();
            ((stretched.x / sin_theta).clamp(-1.0, 1.0), (stretched.y / sin_theta).clamp(-1.0, 1.0), sin_theta)
        };
        let cos_theta = stretched.z;
        let slope = match self.distribution {
            Distribution::Beckmann => beckmann_visible_slope(cos_theta, sin_theta, u),
            Distribution::Ggx => ggx_visible_slope(cos_theta, sin_theta, u),
        };
        let slope_x = (cos_phi * slope.x - sin_phi * slope.y) * self.alpha_u;
        let slope_y = (sin_phi * slope.x + cos_phi * slope.y) * self.alpha_v;
        Vec3::new(-slope_x, -slope_y, 1.0).normalize()
    }

    /// The density of `sample_visible`: D(m) G1(wi, m) |wi·m| / cos θi (0 when wi.z <= 0).
    ///
    /// Per solid angle of m. It integrates to 1 for GGX; for Beckmann to (1 + Λ(wi)) G1(wi) with the
    /// exact Λ and Mitsuba's fitted G1, within 0.35% of 1, while the samples follow the exact
    /// visible-normal distribution (with the exact Λ): Mitsuba's inconsistency, kept.
    #[inline]
    pub fn pdf_visible(&self, wi: Vec3, m: Vec3) -> f32 {
        if wi.z <= 0.0 {
            return 0.0;
        }
        self.d(m) * self.g1(wi, m) * wi.dot(m).abs() / wi.z
    }

    /// Samples a normal from D(m) cos θm (sample_visible = false); its density is `pdf_all(m)`.
    ///
    /// The azimuth follows tan φ = (αv / αu) tan(2π u.y) in the
    /// quadrant of 2π u.y, the elevation inverts the CDF in tan^2 θ for the roughness along φ.
    #[inline]
    pub fn sample_all(&self, u: Vec2) -> Vec3 {
        let (sin_phi, cos_phi, alpha_2) = if self.is_isotropic() {
            let (sin_phi, cos_phi) = (TAU * u.y).sin_cos();
            (sin_phi, cos_phi, self.alpha_u * self.alpha_u)
        } else {
            let ratio = self.alpha_v / self.alpha_u;
            let tan_phi = ratio * (TAU * u.y).tan();
            // cos φ >= 0 for 2π u.y in [-π/2, π/2], that is u.y within 1/4 of 0 or of 1.
            let cos_phi = (1.0 / (tan_phi * tan_phi + 1.0).sqrt()).copysign((u.y - 0.5).abs() - 0.25);
            let sin_phi = cos_phi * tan_phi;
            let (x, y) = (cos_phi / self.alpha_u, sin_phi / self.alpha_v);
            (sin_phi, cos_phi, 1.0 / (x * x + y * y))
        };
        let tan_theta_2 = match self.distribution {
            Distribution::Beckmann => -alpha_2 * (1.0 - u.x).ln(),
            Distribution::Ggx => alpha_2 * u.x / (1.0 - u.x),
        };
        let cos_theta_2 = 1.0 / (1.0 + tan_theta_2);
        // tan^2 θ is infinite at u.x = 1, where m lies on the horizon.
        let sin_theta = if tan_theta_2 < f32::INFINITY { (tan_theta_2 * cos_theta_2).sqrt() } else { 1.0 };
        let cos_theta = cos_theta_2.sqrt();
        Vec3::new(cos_phi * sin_theta, sin_phi * sin_theta, cos_theta)
    }

    /// The density of `sample_all` per solid angle: D(m) cos θm.
    #[inline]
    pub fn pdf_all(&self, m: Vec3) -> f32 {
        self.d(m) * m.z
    }
}

/// A slope of the GGX distribution with α = 1 visible from a direction at (cos θ, sin θ) with
/// azimuth 0 (Heitz 2018 in Mitsuba's variant): a point of the unit disk (concentric map), squeezed
/// towards the half seen from the side as the direction tilts, is projected onto the hemisphere
/// around the direction, whose normal of the truncated ellipsoid then gives the slope.
#[inline]
fn ggx_visible_slope(cos_theta: f32, sin_theta: f32, u: Vec2) -> Vec2 {
    let p = concentric_disk(u);
    let s = 0.5 * (1.0 + cos_theta);
    let h = (1.0 - p.x * p.x).max(0.0).sqrt();
    let y = h + (p.y - h) * s;
    let z = (1.0 - p.x * p.x - y * y).max(0.0).sqrt();
    // The normal's z in this frame; it is 0 on the silhouette, where u lies on the edge of the unit
    // square (u.x or u.y = 0, one sample in 2^23), and its slope infinite. The floor keeps such
    // samples finite, with m.z > 0 (and D(m) = 0), instead of NaN as in Mitsuba.
    let norm = 1.0 / (sin_theta * y + cos_theta * z).max(MIN_NORMAL_Z);
    Vec2::new((cos_theta * y - sin_theta * z) * norm, p.x * norm)
}

/// A slope of the Beckmann distribution with α = 1 visible from a direction at (cos θ, sin θ) with
/// azimuth 0 (Jakob 2014 as in Mitsuba): the x slope inverts its CDF by Newton's method in the erf
/// domain, x = erf(slope), where the CDF is 1 + x + tan θ / sqrt(pi) exp(-slope^2) up to a
/// normalisation, starting from the exact inverse at grazing incidence; the y slope is Gaussian.
#[inline]
fn beckmann_visible_slope(cos_theta: f32, sin_theta: f32, u: Vec2) -> Vec2 {
    let (x, y) = beckmann_visible_slope_f64(f64::from(cos_theta), f64::from(sin_theta), u);
    Vec2::new(x as f32, y as f32)
}

/// `beckmann_visible_slope` in f64, where it computes (see the module notes: at grazing incidence
/// the unknown lies within 1e-6 of -1, closer than f32 resolves).
#[inline]
fn beckmann_visible_slope_f64(cos_theta: f64, sin_theta: f64, u: Vec2) -> (f64, f64) {
    let u = u.clamp(Vec2::splat(BECKMANN_SAMPLE_MARGIN), Vec2::splat(1.0 - BECKMANN_SAMPLE_MARGIN));
    let (ux, uy) = (f64::from(u.x), f64::from(u.y));
    // At normal incidence tan = 0 and cot = inf; the products below then stay finite (0 * 0).
    let tan_theta = sin_theta / cos_theta;
    let cot_theta = cos_theta / sin_theta;
    let c = tan_theta * FRAC_1_SQRT_PI;
    // The CDF runs over x in [-1, erf(cot θ)].
    let max_x = erf(cot_theta);
    let target = ux * (1.0 + max_x + c * (-cot_theta * cot_theta).exp());
    let mut x = max_x - (max_x + 1.0) * erf((-ux.ln()).sqrt());
    // Mitsuba's three Newton steps; `tests.rs` measures what they leave unconverged.
    for _ in 0..3 {
        let slope = erfinv(x);
        let value = 1.0 + x + c * (-slope * slope).exp() - target;
        let derivative = 1.0 - slope * tan_theta;
        x -= value / derivative;
    }
    (erfinv(x), erfinv(2.0 * uy - 1.0))
}

#[cfg(test)]
mod tests;
