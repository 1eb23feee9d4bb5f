//! Light at a surface, for every integrator: the one shadow walk (transmittance along a segment
//! through the surfaces that let light through, with one limit on how many it passes) and
//! direct lighting from the lights (one light chosen by power, with multiple importance sampling
//! against the BSDF when asked, or every light in turn). The Whitted integrator shades with the
//! seed report's classic model and passes its own crossing rule (glass lets `1 - F` through);
//! the physical integrators pass masks' transparent parts.

use crate::geometry::{Hit, RayOrigin};
use crate::light::{Light, LightPicker};
use crate::material::bsdf::Bsdf;
use crate::material::bxdf::Transport;
use crate::math::{Color, Vec2, Vec3};
use crate::render::RayStats;
use crate::scene::{Crossing, Scene};
use crate::spectrum::Wavelengths;

/// The most surfaces a shadow ray passes through (masks, or glass for the Whitted integrator)
/// before it counts as blocked.
pub const MAX_CROSSINGS: usize = 64;

/// The fraction of light that travels from hit `from` a distance `dist` along unit `wi`
/// (infinitely far for a light at infinity), stopping just short of the end so a light's own
/// surface does not shadow it: 0 when a surface that passes nothing is in the way, else the
/// product of what each surface crossed passes (`pass(material, crossing)` in [0, 1]). Without
/// `see_through` (no surface in the scene passes light) it is one occlusion ray. Rays leave
/// surfaces with offset `bias`; each ray traced counts as a shadow ray.
///
/// Transmittance is a product, so the crossings are taken in any order, all from one traversal
/// along the first ray; scenes whose crossings cannot be enumerated that way (instances,
/// cylinders) walk them one closest hit at a time, passing as many.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn transmittance(
    scene: &Scene,
    from: RayOrigin,
    wi: Vec3,
    dist: f32,
    bias: f32,
    see_through: bool,
    stats: &mut RayStats,
    mut pass: impl FnMut(u32, &Crossing) -> f32,
) -> f32 {
    let mut ray = from.spawn(wi, bias);
    // Stop just short of the light so a light's own surface does not shadow it. (`visibility`
    // makes the same first ray and end for its usual case: keep the two alike.)
    let dist = if dist.is_finite() { dist * (1.0 - 1e-4) } else { dist };
    let target = from.p + wi * dist;
    let t_max = |ray: &crate::geometry::Ray| if dist.is_finite() { (target - ray.o).dot(wi) } else { f32::INFINITY };
    stats.shadow_rays += 1;
    if !see_through {
        return if scene.occluded(&ray, t_max(&ray)) { 0.0 } else { 1.0 };
    }
    let mut through = 1.0f32;
    let tm = t_max(&ray);
    if !(tm > 0.0) {
        return through;
    }
    let mut crossings = 0;
    let walked = scene.for_each_crossing(&ray, tm, |material, crossing| {
        crossings += 1;
        through *= pass(material, crossing);
        through != 0.0 && crossings <= MAX_CROSSINGS
    });
    if let Some(all) = walked {
        return if all { through } else { 0.0 };
    }
    // As many crossings pass as in the walk above; a further one blocks.
    for k in 0..=MAX_CROSSINGS {
        if k > 0 {
            stats.shadow_rays += 1;
        }
        let tm = t_max(&ray);
        if !(tm > 0.0) {
            return through;
        }
        let Some(h) = scene.intersect(&ray, tm) else { return through };
        through *= pass(h.material, &Crossing::Hit(&h));
        if through == 0.0 {
            return through;
        }
        ray = h.spawn(wi, bias);
    }
    0.0
}

/// What the physical integrators' shadow rays pass: the transparent part of a mask (1 - its
/// opacity), nothing through any other surface.
#[inline]
pub fn mask_transparency(scene: &Scene, crossing: &Crossing, wi: Vec3) -> f32 {
    let h = crossing.hit();
    scene.materials.transparency(&h, h.is_front(-wi))
}

/// The transmittance a physical integrator's shadow ray sees: through masks' transparent parts.
/// The usual shadow ray (no masks: one occlusion test, `transmittance`'s first lines) is made
/// here with no call, and the walk through masks out of line, so the light sample this inlines
/// into stays small (0.945x the path tracer's time on the Cornell box). The Whitted integrator
/// calls `transmittance` itself: its shadow rays pass glass, and it ran 1.045x as long with the
/// walk out of line.
#[inline(always)]
pub fn visibility(scene: &Scene, from: RayOrigin, wi: Vec3, dist: f32, bias: f32, stats: &mut RayStats) -> f32 {
    if scene.materials.has_masks {
        return visibility_through_masks(scene, from, wi, dist, bias, stats);
    }
    let ray = from.spawn(wi, bias);
    let dist = if dist.is_finite() { dist * (1.0 - 1e-4) } else { dist };
    let t_max = if dist.is_finite() { (from.p + wi * dist - ray.o).dot(wi) } else { f32::INFINITY };
    stats.shadow_rays += 1;
    if scene.occluded(&ray, t_max) { 0.0 } else { 1.0 }
}

#[inline(never)]
fn visibility_through_masks(
    scene: &Scene,
    from: RayOrigin,
    wi: Vec3,
    dist: f32,
    bias: f32,
    stats: &mut RayStats,
) -> f32 {
    transmittance(scene, from, wi, dist, bias, true, stats, |_, c| mask_transparency(scene, c, wi))
}

/// One sample of light `light` (chosen with probability `p_pick`) arriving at hit `hit` (BSDF
/// `bsdf`, viewer towards `wo`): `u` picks the point on the light, a shadow ray checks it, and
/// the light's radiance times the BSDF and cosine over the densities is the estimate. With
/// `mis`, samples of area and environment lights are weighted against BSDF sampling by the power
/// heuristic (BSDF-sampled hits on lights then add the rest).
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn light_sample(
    scene: &Scene,
    light: usize,
    p_pick: f32,
    hit: &Hit,
    bsdf: &Bsdf,
    wo: Vec3,
    u: Vec2,
    bias: f32,
    mis: bool,
    wl: Option<&Wavelengths>,
    stats: &mut RayStats,
) -> Color {
    light_sample_at(
        scene,
        light,
        p_pick,
        hit.p,
        u,
        mis,
        wl,
        |wi, mis| bsdf_scatter(bsdf, wo, wi, mis),
        |wi, dist| (visibility(scene, hit.origin(), wi, dist, bias, stats), Color::ONE),
    )
}

/// What a BSDF scatters from `wi` towards `wo`, in the form `light_sample_at` takes: its
/// value, the cosine, and its density when weighted by MIS.
#[inline(always)]
pub fn bsdf_scatter(bsdf: &Bsdf, wo: Vec3, wi: Vec3, mis: bool) -> (Color, f32, f32) {
    let (f, pdf) =
        if mis { bsdf.eval(wo, wi, Transport::Radiance) } else { (bsdf.f(wo, wi, Transport::Radiance), 0.0) };
    (f, wi.dot(bsdf.normal()).abs(), pdf)
}

/// The one light-sample estimator at a point `p`, a surface's or a medium's: `u` picks a point
/// on `light`; `scatter(wi, mis)` gives what the point scatters from `wi` towards the viewer (a
/// value, a cosine factor, and the density its own sampler would have chosen `wi` with, when
/// `mis`), and `visible(wi, dist)` what reaches it from the light (a fraction and a per-channel
/// transmittance through media). Area and environment lights are weighted against the point's
/// own sampling by the power heuristic when `mis`. In spectral mode (`wl`) the light's colour
/// is lifted to its illuminant spectrum at the path's wavelengths (`scatter` gives lifted
/// values already).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn light_sample_at(
    scene: &Scene,
    light: usize,
    p_pick: f32,
    p: Vec3,
    u: Vec2,
    mis: bool,
    wl: Option<&Wavelengths>,
    scatter: impl FnOnce(Vec3, bool) -> (Color, f32, f32),
    visible: impl FnOnce(Vec3, f32) -> (f32, Color),
) -> Color {
    let li = light as u32;
    let Some(ls) = scene.lights[light].sample(p, u, scene.textures()) else { return Color::ZERO };
    let mis = mis && !ls.delta;
    let (f, cos, scatter_pdf) = scatter(ls.wi, mis);
    if f == Color::ZERO {
        return Color::ZERO;
    }
    let (visible, tr) = visible(ls.wi, ls.dist);
    if !(visible > 0.0) || tr == Color::ZERO {
        return Color::ZERO;
    }
    let w = if mis { power_heuristic(ls.pdf * p_pick, scatter_pdf) } else { 1.0 };
    f * scene.emission_in(ls.weight(), li, wl) * (cos * w * visible / p_pick) * tr
}

/// The transmittance from `from` a distance `dist` along unit `wi` (infinite for lights at
/// infinity) for a ray starting in medium `medium`: the product of each medium's transmittance
/// over the segments between surfaces, and of what each surface crossed passes (a `null`
/// boundary or a mask's transparent part; anything else blocks), the medium changing at each
/// crossing of an interface. Surfaces are met one closest hit at a time, since the segments
/// between them must be known in order; at most `MAX_CROSSINGS` of them. A heterogeneous
/// medium's transmittance is estimated (ratio tracking) with numbers from `rng`. In spectral
/// mode (`wl`) the transmittance is at the path's wavelengths.
#[allow(clippy::too_many_arguments)]
pub fn transmittance_through_media(
    scene: &Scene,
    from: RayOrigin,
    wi: Vec3,
    dist: f32,
    medium: u32,
    bias: f32,
    rng: &mut crate::sampling::Rng32,
    wl: Option<&Wavelengths>,
    stats: &mut RayStats,
) -> Color {
    let mut ray = from.spawn(wi, bias);
    ray.medium = medium;
    let dist = if dist.is_finite() { dist * (1.0 - 1e-4) } else { dist };
    let target = from.p + wi * dist;
    let mut tr = Color::ONE;
    for _ in 0..=MAX_CROSSINGS {
        stats.shadow_rays += 1;
        let t_max = if dist.is_finite() { (target - ray.o).dot(wi) } else { f32::INFINITY };
        if !(t_max > 0.0) {
            return tr;
        }
        let hit = scene.intersect(&ray, t_max);
        if ray.medium != crate::geometry::NO_MEDIUM {
            tr *= scene.media[ray.medium as usize].transmittance(&ray, hit.as_ref().map_or(t_max, |h| h.t), rng, wl);
            if tr == Color::ZERO {
                return tr;
            }
        }
        let Some(h) = &hit else { return tr };
        let pass = scene.materials.transparency(h, h.is_front(-wi));
        if !(pass > 0.0) {
            return Color::ZERO;
        }
        tr *= pass;
        let next = scene.medium_after(h, wi, ray.medium);
        ray = h.spawn(wi, bias);
        ray.medium = next;
    }
    Color::ZERO
}

/// Direct light at a hit by one light sample: a light chosen by power (`u_pick`), a point on it
/// (`u`), a shadow ray (see `light_sample`).
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn direct_light(
    scene: &Scene,
    hit: &Hit,
    bsdf: &Bsdf,
    wo: Vec3,
    u_pick: f32,
    u: Vec2,
    bias: f32,
    mis: bool,
    wl: Option<&Wavelengths>,
    stats: &mut RayStats,
) -> Color {
    let Some((li, p_pick)) = scene.direct_picker.pick(u_pick) else { return Color::ZERO };
    light_sample(scene, li, p_pick, hit, bsdf, wo, u, bias, mis, wl, stats)
}

/// Direct light from every light in turn (photon mapping's estimator, Jensen 2001 sec. 9.1):
/// one sample of each delta light and `light_samples` of each area and environment light; a
/// scene with more of those than `LOOPED_AREA_LIGHTS` (an emitting mesh is a light per
/// triangle) takes `light_samples` times that many from them in all, each from a light chosen
/// by power, or it would cost a shadow ray per triangle of every emitting mesh.
pub struct EveryLight {
    light_samples: u32,
    /// With many area and environment lights: their indices and a picker among them by power.
    area_lights: Vec<u32>,
    area_picker: LightPicker,
}

/// Up to this many area and environment lights, `EveryLight` samples each of them.
pub const LOOPED_AREA_LIGHTS: usize = 4;

impl EveryLight {
    pub fn new(scene: &Scene, light_samples: u32) -> Self {
        let area: Vec<u32> = (0..scene.lights.len() as u32).filter(|&i| !scene.lights[i as usize].is_delta()).collect();
        let (area_lights, area_picker) = if area.len() > LOOPED_AREA_LIGHTS {
            let lights: Vec<Light> = area.iter().map(|&i| scene.lights[i as usize]).collect();
            (area, LightPicker::new(&lights))
        } else {
            (Vec::new(), LightPicker::default())
        };
        EveryLight { light_samples: light_samples.max(1), area_lights, area_picker }
    }

    /// The direct light at `hit`, drawing its numbers from `rng` (a point on a light per call,
    /// and a light choice per picked sample).
    #[allow(clippy::too_many_arguments)]
    pub fn estimate(
        &self,
        scene: &Scene,
        hit: &Hit,
        bsdf: &Bsdf,
        wo: Vec3,
        bias: f32,
        rng: &mut crate::sampling::Rng32,
        wl: Option<&Wavelengths>,
        stats: &mut RayStats,
    ) -> Color {
        self.sum(scene, rng, stats, |light, p_pick, u, _, stats| {
            light_sample(scene, light, p_pick, hit, bsdf, wo, u, bias, false, wl, stats)
        })
    }

    /// The sum over the lights (see the type's docs) of `one(light, p_pick, u, rng, stats)`, one
    /// light sample estimate (`light_sample_at`'s, at a surface or in a medium) with the point
    /// on the light drawn by `u` and any further numbers (a heterogeneous medium's tracking)
    /// from `rng`.
    pub fn sum(
        &self,
        scene: &Scene,
        rng: &mut crate::sampling::Rng32,
        stats: &mut RayStats,
        mut one: impl FnMut(usize, f32, Vec2, &mut crate::sampling::Rng32, &mut RayStats) -> Color,
    ) -> Color {
        let picked = !self.area_lights.is_empty();
        let mut sum = Color::ZERO;
        for (i, light) in scene.lights.iter().enumerate() {
            if picked && !light.is_delta() {
                continue;
            }
            let n_samples = if light.is_delta() { 1 } else { self.light_samples };
            let mut acc = Color::ZERO;
            for _ in 0..n_samples {
                let u = rng.uniform2();
                acc += one(i, 1.0, u, rng, stats);
            }
            sum += acc / n_samples as f32;
        }
        if picked {
            let n_samples = self.light_samples * LOOPED_AREA_LIGHTS as u32;
            let mut acc = Color::ZERO;
            for _ in 0..n_samples {
                let Some((k, p)) = self.area_picker.pick(rng.uniform()) else { break };
                let u = rng.uniform2();
                acc += one(self.area_lights[k] as usize, 1.0, u, rng, stats) / p;
            }
            sum += acc / n_samples as f32;
        }
        sum
    }
}

/// The light a path finds where its ray ends: the environment when it leaves the scene (`hit`
/// None) or an emitter's front side, with the MIS weight against the light sample the last
/// bounce took from `prev_p`, where it sampled the ray with density `prev_pdf` (weight 1 after a
/// mirror or glass bounce, which took none). Returns the radiance and the weight apart, so
/// callers multiply them into the throughput in one order.
#[inline(always)]
pub fn emission_found(
    scene: &Scene,
    ray_d: Vec3,
    hit: Option<&Hit>,
    prev_p: Vec3,
    prev_pdf: f32,
    specular_bounce: bool,
) -> Option<(Color, f32, u32)> {
    let (li, le, light_pdf) = match hit {
        None => {
            let env = scene.environment?;
            let le = scene.lights[env as usize].environment_radiance(ray_d);
            if specular_bounce {
                return Some((le, 1.0, env));
            }
            (env, le, scene.lights[env as usize].pdf_li(prev_p, prev_p, ray_d, ray_d))
        }
        Some(hit) => {
            if !(hit.is_emitter() && hit.is_front(ray_d)) {
                return None;
            }
            let le = scene.emitted(hit, -ray_d);
            if specular_bounce {
                return Some((le, 1.0, hit.light));
            }
            (hit.light, le, scene.lights[hit.light as usize].pdf_li(prev_p, hit.p, hit.ng, ray_d))
        }
    };
    Some((le, power_heuristic(prev_pdf, scene.direct_picker.prob(li as usize) * light_pdf), li))
}

/// Veach's power heuristic (exponent 2) weight of a sample of density `a` against one of `b`.
/// Written as a ratio so that densities whose squares overflow (an area light seen edge-on from
/// a point far along a floor plane has a solid-angle density near 1e23) give 1 or 0, not
/// inf / inf = NaN (issue 16).
#[inline]
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    if !(a > 0.0) {
        return 0.0;
    }
    if a >= b {
        let r = b / a;
        1.0 / (1.0 + r * r)
    } else {
        let r = a / b;
        let r2 = r * r;
        r2 / (1.0 + r2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng32;

    /// `visibility`'s usual shadow ray (a scene without masks) is `transmittance`'s first ray and
    /// occlusion test, made again for speed: the two agree bit for bit, rays counted alike.
    #[test]
    fn visibility_without_masks_is_transmittance() {
        let scene = crate::scene::test_scenes::from_toml(include_str!("../../scenes/11-cornell-area.toml"));
        assert!(!scene.materials.has_masks);
        let mut rng = Rng32::new(5);
        let (mut blocked, mut open) = (0, 0);
        for k in 0..20_000 {
            let p = Vec3::new(rng.uniform() * 5.56, rng.uniform() * 5.49, rng.uniform() * 5.59);
            let ng = Vec3::new(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5).normalize();
            let from = RayOrigin { p, p_error: Vec3::splat(1e-5), ng };
            let wi = Vec3::new(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5).normalize();
            let dist = if k % 10 == 0 { f32::INFINITY } else { 6.0 * rng.uniform() };
            let (mut a, mut b) = (RayStats::default(), RayStats::default());
            let v = visibility(&scene, from, wi, dist, 1e-4, &mut a);
            let t = transmittance(&scene, from, wi, dist, 1e-4, false, &mut b, |_, _| 1.0);
            assert_eq!(v.to_bits(), t.to_bits(), "from {from:?} along {wi:?}, {dist}");
            assert_eq!((a.rays, a.shadow_rays), (b.rays, b.shadow_rays));
            if v == 0.0 { blocked += 1 } else { open += 1 }
        }
        assert!(blocked > 1000 && open > 1000, "blocked {blocked}, open {open}");
    }
}
