//! Splitting at glass: both directions of a smooth dielectric at once, for walks that follow
//! the reflection and the refraction both instead of picking one (`bdpt::subpath`).

use super::{Bsdf, BsdfSample};
use crate::material::bxdf::{Bxdf, Transport};
use crate::math::{Vec2, Vec3};

impl Bsdf<'_> {
    /// Both directions of a smooth dielectric (the BSDF is one opaque `Dielectric` lobe): the
    /// reflection and the refraction `sample` picks between with probabilities F and 1 - F,
    /// each weighted by that probability, so that the two together are the whole scattered
    /// light with no choice left to chance (a camera path splits at glass, `bdpt::subpath`).
    /// One direction when the other is never picked (total internal reflection); `None` for any
    /// other BSDF.
    pub fn dielectric_split(&self, wo: Vec3, mode: Transport) -> Option<[Option<BsdfSample>; 2]> {
        let (1, true, Bxdf::Dielectric(_)) = (self.lobes.count, self.opacity >= 1.0, &self.lobes.lobes[0]) else {
            return None;
        };
        // The lobe reflects when uc < F: uc = 0 reflects unless F = 0, and the largest uc
        // below 1 refracts unless F rounds to 1.
        let branch = |uc: f32| {
            let (s, _) = self.sample_any_lobe(&self.lobes.weights, self.lobes.total, wo, uc, Vec2::ZERO, mode)?;
            Some((s.flags, BsdfSample { wi: s.wi, weight: s.weight * s.pdf, pdf: 0.0, flags: s.flags }))
        };
        let (reflected, refracted) = (branch(0.0), branch(1.0 - f32::EPSILON / 2.0));
        Some(match (reflected, refracted) {
            (Some((fa, a)), Some((fb, b))) if fa != fb => [Some(a), Some(b)],
            (a, b) => [a.or(b).map(|(_, s)| s), None],
        })
    }
}
