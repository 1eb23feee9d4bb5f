//! The BSDF at a surface point: a weighted sum of up to `MAX_LOBES` lobes (`bxdf`) in the hit's
//! shading frame, oriented to the side the viewer is on. The physical integrators (path tracing,
//! photon mapping, SPPM) scatter through it; the Whitted integrator keeps the seed report's
//! classic model.
//!
//! Directions are in world space and point away from the surface; `wo` towards the viewer (or
//! where a photon came from), `wi` the other direction. Densities are per unit solid angle.
//! Sampling picks a lobe in proportion to its sampling weight; a non-delta sample is weighted
//! by the whole BSDF's value and density (so lobes combine like one mixture), a delta sample by
//! its own lobe over the probability of having picked it.

use super::bxdf::{Bxdf, BxdfSample, LobeFlags, Transport};
use crate::math::{Color, Frame, Vec2, Vec3};

/// Most lobes a BSDF holds.
pub const MAX_LOBES: usize = 4;

/// A sampled direction with its Monte Carlo weight.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    pub wi: Vec3,
    /// f |cos| / pdf: the throughput multiplier of this sample.
    pub weight: Color,
    /// Density of `wi` (0 for delta samples, whose density is a delta).
    pub pdf: f32,
    pub flags: LobeFlags,
}

/// The lobes of a material at a hit, with their sampling weights: what a material evaluates to
/// before it is placed in a shading frame. Materials without textures give the same lobes at
/// every hit, so the scene makes them once per material and side.
#[derive(Clone, Copy, Debug)]
pub struct Lobes {
    lobes: [Bxdf; MAX_LOBES],
    /// Sampling weight of each lobe for camera paths (luminance of its albedo).
    weights: [f32; MAX_LOBES],
    /// Sampling weight of each lobe for photons (its albedo averaged over the channels).
    photon_weights: [f32; MAX_LOBES],
    total: f32,
    photon_total: f32,
    count: u8,
    flags: LobeFlags,
    /// Every lobe is isotropic (see `Bxdf::is_isotropic`).
    isotropic: bool,
}

impl Default for Lobes {
    fn default() -> Self {
        let none = Bxdf::Lambert(super::bxdf::Lambert { r: Color::ZERO });
        Lobes {
            lobes: [none; MAX_LOBES],
            weights: [0.0; MAX_LOBES],
            photon_weights: [0.0; MAX_LOBES],
            total: 0.0,
            photon_total: 0.0,
            count: 0,
            flags: LobeFlags::NONE,
            isotropic: true,
        }
    }
}

impl Lobes {
    /// Adds a lobe; lobes that never scatter (zero sampling weight) are left out.
    #[inline]
    pub fn add(&mut self, lobe: Bxdf) {
        let w = lobe.sampling_weight();
        if !(w > 0.0) || self.count as usize >= MAX_LOBES {
            return;
        }
        let i = self.count as usize;
        self.lobes[i] = lobe;
        self.weights[i] = w;
        self.photon_weights[i] = lobe.mean_albedo().max(w * 1e-3);
        self.total += w;
        self.photon_total += self.photon_weights[i];
        self.count += 1;
        self.flags |= lobe.flags();
        self.isotropic &= lobe.is_isotropic();
    }

    /// True when every lobe is isotropic: the BSDF's frame then needs only the normal.
    #[inline]
    pub fn is_isotropic(&self) -> bool {
        self.isotropic
    }

    #[inline]
    fn as_slice(&self) -> &[Bxdf] {
        &self.lobes[..self.count as usize]
    }
}

/// A material's scattering at one hit: its lobes in the hit's shading frame, oriented to the
/// side the viewer is on.
#[derive(Clone, Copy, Debug)]
pub struct Bsdf {
    /// Shading frame; z is the shading normal on the side of `wo`.
    frame: Frame,
    /// Geometric normal on the same side.
    ng: Vec3,
    lobes: Lobes,
}

/// True when `wo` is on the outward side of a surface with geometric normal `ng` (a BSDF is
/// made for the side the viewer is on: `Bsdf::new` and the material's lobes must agree).
#[inline]
pub fn front_side(wo: Vec3, ng: Vec3) -> bool {
    wo.dot(ng) >= 0.0
}

impl Bsdf {
    /// The BSDF with `lobes` in `frame` (shading frame of the hit, z = shading normal) with
    /// geometric normal `ng`, both outward; they are turned to the viewer's side when `front`
    /// (see `front_side`) is false (two-sided surfaces).
    #[inline]
    pub fn new(frame: Frame, ng: Vec3, front: bool, lobes: Lobes) -> Self {
        let (frame, ng) = if front { (frame, ng) } else { (frame.flipped(), -ng) };
        Bsdf { frame, ng, lobes }
    }

    #[inline]
    fn lobes(&self) -> &[Bxdf] {
        self.lobes.as_slice()
    }

    /// The shading normal on the viewer's side.
    #[inline]
    pub fn normal(&self) -> Vec3 {
        self.frame.z
    }

    /// Every kind of scattering the BSDF has.
    #[inline]
    pub fn flags(&self) -> LobeFlags {
        self.lobes.flags
    }

    /// True when the surface has a diffuse lobe.
    #[inline]
    pub fn has_diffuse(&self) -> bool {
        self.lobes.flags.is_diffuse()
    }

    /// True when every lobe is a delta (mirror, glass) or there is none: nothing to shade with
    /// light samples.
    #[inline]
    pub fn is_specular_only(&self) -> bool {
        !self.lobes.flags.intersects(LobeFlags::DIFFUSE | LobeFlags::GLOSSY)
    }

    /// Albedo of the diffuse lobes.
    pub fn diffuse_albedo(&self) -> Color {
        self.lobes()
            .iter()
            .map(|l| match l {
                Bxdf::Lambert(b) => b.r,
                _ => Color::ZERO,
            })
            .sum()
    }

    /// The BSDF's value for the pair (no cosine): the non-delta lobes of the kind the geometry
    /// gives (reflection when `wi` is on the viewer's side of the surface).
    #[inline]
    pub fn f(&self, wo: Vec3, wi: Vec3, mode: Transport) -> Color {
        let kind = if wi.dot(self.ng) > 0.0 { LobeFlags::REFLECTION } else { LobeFlags::TRANSMISSION };
        let (wo_l, wi_l) = (self.frame.to_local(wo), self.frame.to_local(wi));
        let mut f = Color::ZERO;
        for lobe in self.lobes() {
            if lobe.flags().intersects(kind) && !lobe.flags().is_specular() {
                f += lobe.f(wo_l, wi_l, mode);
            }
        }
        f
    }

    /// Density with which `sample` picks `wi` through its non-delta lobes.
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3, mode: Transport) -> f32 {
        let total = self.lobes.total;
        if !(total > 0.0) {
            return 0.0;
        }
        let kind = if wi.dot(self.ng) > 0.0 { LobeFlags::REFLECTION } else { LobeFlags::TRANSMISSION };
        let (wo_l, wi_l) = (self.frame.to_local(wo), self.frame.to_local(wi));
        let mut pdf = 0.0;
        for (lobe, w) in self.lobes().iter().zip(&self.lobes.weights) {
            if lobe.flags().intersects(kind) && !lobe.flags().is_specular() {
                pdf += w / total * lobe.pdf(wo_l, wi_l, mode);
            }
        }
        pdf
    }

    /// Picks a lobe in proportion to its sampling weight and samples it: (the lobe's sample in
    /// world space, the probability of the lobe). `uc` chooses the lobe and, rescaled, reflection
    /// or transmission within it; `u` the direction.
    #[inline(always)]
    fn sample_any_lobe(
        &self,
        weights: &[f32; MAX_LOBES],
        total: f32,
        wo: Vec3,
        uc: f32,
        u: Vec2,
        mode: Transport,
    ) -> Option<(BxdfSample, f32)> {
        let n = self.lobes.count as usize;
        if !(total > 0.0) {
            return None;
        }
        let (k, p_lobe, uc_lobe) = if n == 1 {
            (0, 1.0, uc)
        } else {
            let mut x = uc * total;
            let mut k = n - 1;
            for (i, &w) in weights[..n].iter().enumerate() {
                if x < w {
                    k = i;
                    break;
                }
                x -= w;
            }
            (k, weights[k] / total, (x / weights[k]).clamp(0.0, 1.0 - f32::EPSILON / 2.0))
        };
        let lobe = &self.lobes.lobes[k];
        // A Lambertian lobe samples without looking at wo: only its side is needed.
        let wo_l = match lobe {
            Bxdf::Lambert(_) => Vec3::new(0.0, 0.0, wo.dot(self.frame.z)),
            _ => self.frame.to_local(wo),
        };
        if wo_l.z <= 0.0 && !self.lobes.flags.is_transmission() {
            // Seen from below the shading normal, a surface that only reflects has nothing to give.
            return None;
        }
        let mut s = lobe.sample(wo_l, uc_lobe, u, mode)?;
        s.wi = self.frame.to_world(s.wi);
        // The side the direction leaves to must agree with the geometry, not only the shading
        // normal, or light would leak through the surface.
        let reflected = s.wi.dot(self.ng) > 0.0;
        if reflected == s.flags.is_transmission() {
            return None;
        }
        Some((s, p_lobe))
    }

    /// Samples a direction for a camera path. A non-delta sample is weighted by the whole BSDF
    /// (all non-delta lobes' values over their combined density, as one mixture), a delta sample
    /// by its lobe over the probability of having picked it.
    #[inline]
    pub fn sample(&self, wo: Vec3, uc: f32, u: Vec2, mode: Transport) -> Option<BsdfSample> {
        let (s, p_lobe) = self.sample_any_lobe(&self.lobes.weights, self.lobes.total, wo, uc, u, mode)?;
        let wi = s.wi;
        if s.flags.is_specular() {
            return Some(BsdfSample { wi, weight: s.weight / p_lobe, pdf: 0.0, flags: s.flags });
        }
        let pdf = self.pdf(wo, wi, mode);
        if !(pdf > 0.0) {
            return None;
        }
        let weight = self.f(wo, wi, mode) * (wi.dot(self.frame.z) / pdf);
        Some(BsdfSample { wi, weight, pdf, flags: s.flags })
    }

    /// Samples a direction for a photon: a lobe picked in proportion to its mean albedo,
    /// weighted by that lobe alone (its f |cos| / pdf over the probability of picking it),
    /// which is unbiased too. The weight's mean over the channels is then the BSDF's total mean
    /// albedo, so after Russian roulette on it a photon keeps its power, as Jensen's
    /// lobe-by-albedo roulette keeps it: photons of nearly equal power make the density
    /// estimate quiet, where the mixture weight of `sample` would brighten the photons a sharp
    /// glossy lobe overlapping a diffuse one sends.
    #[inline]
    pub fn sample_lobe(&self, wo: Vec3, uc: f32, u: Vec2, mode: Transport) -> Option<BsdfSample> {
        let (s, p_lobe) = self.sample_any_lobe(&self.lobes.photon_weights, self.lobes.photon_total, wo, uc, u, mode)?;
        let pdf = if s.flags.is_specular() { 0.0 } else { s.pdf * p_lobe };
        Some(BsdfSample { wi: s.wi, weight: s.weight / p_lobe, pdf, flags: s.flags })
    }
}

#[cfg(test)]
mod tests;
