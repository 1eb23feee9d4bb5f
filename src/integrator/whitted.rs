//! Whitted ray tracing with the seed report's illumination model (eq. 1-8):
//!
//! I = k_a I_a + sum over lights of [k_d (N . L) + k_s (R . V)^n] L_light * visibility
//!     + k_r S + k_t T
//!
//! with shadow rays for visibility, mirror reflection S (eq. 3), refraction T (eq. 4) with the
//! normal flipped and the indices swapped when the ray leaves the object, total internal
//! reflection sending everything into S, and Fresnel weights (eq. 5-8) for dielectrics.
//! The medium outside every object is air (index 1).

use super::lighting::transmittance;
use crate::film::{DIRECT, Layers, SPECULAR};
use crate::geometry::{Hit, Ray};
use crate::light::Light;
use crate::material::classic::classic_view;
use crate::material::fresnel::{fresnel_dielectric, reflect, refract};
use crate::material::{Classic, ClassicKind};
use crate::math::{Color, Vec3};
use crate::options::IntegratorKind;
use crate::render::{RayIntegrator, RayStats};
use crate::sampling::Sampler;
use crate::scene::Scene;
use crate::scene::desc::IntegratorDesc;

pub struct Whitted {
    /// What each material of the scene is shaded with: the classic model, or the nearest
    /// classic reading of a physical one (`material::classic::classic_view`).
    classic: Vec<Classic>,
    /// Some material transmits light, so shadow rays look for transparent surfaces.
    any_transmissive: bool,
    /// The most bounces a path may have (see `IntegratorDesc::max_depth`): the surface a ray
    /// meets at recursion depth r is bounce r + 1, lit by the lights when r + 1 <= max_depth,
    /// and reflection and refraction recurse while r + 1 < max_depth.
    pub max_depth: u32,
    /// Shadow rays per area light at each shading point.
    pub area_samples: u32,
    /// Adaptive depth control (Hall and Greenberg 1983; POV-Ray's `adc_bailout`): a reflected
    /// or refracted ray whose weight in the pixel (the product of the reflection and
    /// transmission coefficients along its path, and of 1 / probability for each roulette it
    /// survived) is below this goes on only with probability weight / `adc_bailout`, and then
    /// counts 1 / probability as much (Russian roulette, Arvo and Kirk 1990); so does a shadow
    /// ray, its weight the path's times the surface's reflectance towards the viewer (k_d cos +
    /// highlight). The image's expected value is unchanged; the rays that could add little to
    /// it are mostly not traced. 0 ends no ray by roulette.
    pub adc_bailout: f32,
    /// Ambient light I_a of seed eq. 1.
    pub ambient: Color,
    /// Whether transparent objects let (attenuated) light through to shadow rays.
    pub transparent_shadows: bool,
    /// The offset rays leave surfaces with (`IntegratorDesc::ray_bias`).
    pub ray_bias: f32,
}

impl Whitted {
    /// The integrator `desc` describes for `scene`.
    pub fn new(scene: &Scene, desc: &IntegratorDesc) -> Self {
        let classic: Vec<Classic> =
            (0..scene.materials.len() as u32).map(|m| classic_view(&scene.materials, m)).collect();
        let any_transmissive = classic.iter().any(Classic::transmits);
        Whitted {
            classic,
            any_transmissive,
            max_depth: desc.depth_limit(IntegratorKind::Whitted),
            area_samples: desc.light_samples,
            adc_bailout: desc.adc_bailout,
            ambient: desc.ambient,
            transparent_shadows: desc.transparent_shadows,
            ray_bias: desc.ray_bias(scene),
        }
    }

    /// The classic material hit `h` is shaded with, its texture applied.
    #[inline(always)]
    fn classic(&self, scene: &Scene, h: &Hit) -> Classic {
        let c = self.classic[h.material as usize];
        match c.color_texture {
            Some(t) => Classic { color: scene.materials.textures[t as usize].eval(h.uv()), ..c },
            None => c,
        }
    }
}

impl RayIntegrator for Whitted {
    type Scratch = ();

    /// Layers: the local shading of the first surface is `DIRECT`, what its reflection and
    /// refraction bring is `SPECULAR`.
    fn radiance(&self, scene: &Scene, ray: &Ray, sampler: &mut Sampler, _: &mut (), stats: &mut RayStats) -> Layers {
        let mut layers = [Color::ZERO; 4];
        (layers[DIRECT], layers[SPECULAR]) = self.trace(scene, ray, 0, 1.0, sampler, stats);
        layers
    }
}

impl Whitted {
    /// What a reflected or refracted ray brings, times its coefficient `k`; `weight` is the
    /// weight of the path up to the surface it leaves. Ends the ray by Russian roulette below
    /// the bailout weight (see `adc_bailout`).
    #[allow(clippy::too_many_arguments)]
    fn secondary(
        &self,
        scene: &Scene,
        ray: &Ray,
        depth: u32,
        weight: f32,
        k: f32,
        sampler: &mut Sampler,
        stats: &mut RayStats,
    ) -> Color {
        let w = weight * k;
        let Some(survive) = self.roulette(w, sampler) else { return Color::ZERO };
        // A ray that survived the roulette counts 1 / survive as much: its weight is the bailout.
        let (local, further) = self.trace(scene, ray, depth, w.max(self.adc_bailout), sampler, stats);
        (k / survive) * (local + further)
    }

    /// Adaptive depth control for a ray of weight `w` in the pixel: `None` when the roulette
    /// ends it, else the probability it went on with (1 at or above the bailout, w / bailout
    /// below it).
    #[inline]
    fn roulette(&self, w: f32, sampler: &mut Sampler) -> Option<f32> {
        if !(w < self.adc_bailout) {
            return Some(1.0);
        }
        let survive = w / self.adc_bailout;
        (sampler.rng().uniform() < survive).then_some(survive)
    }

    /// Radiance along `ray` as (local shading, what reflection and refraction bring); `weight`
    /// is the path's weight in the pixel.
    fn trace(
        &self,
        scene: &Scene,
        ray: &Ray,
        depth: u32,
        weight: f32,
        sampler: &mut Sampler,
        stats: &mut RayStats,
    ) -> (Color, Color) {
        stats.rays += 1;
        // Borrowed where it was returned: moving it out of the option copied it while its
        // stores were in flight, and the copy stalled on them.
        let found = scene.intersect(ray, f32::INFINITY);
        let Some(hit) = &found else {
            return (scene.environment(ray.d), Color::ZERO);
        };
        let m = self.classic(scene, hit);
        let front = hit.is_front(ray.d);
        // Normals on the side the ray arrives from: flipped when the ray is inside the object.
        let (n, ng) = if front { (hit.ns, hit.ng) } else { (-hit.ns, -hit.ng) };
        let wo = -ray.d;

        let mut c = Color::ZERO;
        if hit.is_emitter() && front {
            c += scene.emitted(hit, -ray.d);
        }
        if depth >= self.max_depth {
            return (c, Color::ZERO);
        }
        c += m.color * self.ambient * m.ka;
        if m.kd > 0.0 || m.ks > 0.0 {
            // The seed report's model has no sky light (its ambient term stands for it), and its
            // k_d has no 1/pi: an environment is what rays that leave the scene see, not a light.
            for light in scene.lights.iter().filter(|l| !matches!(l, Light::Environment(_))) {
                // Delta lights need one sample; area lights are averaged over several.
                let n_samples = if light.is_delta() { 1 } else { self.area_samples.max(1) };
                for _ in 0..n_samples {
                    let u = sampler.rng().uniform2();
                    let Some(ls) = light.sample(hit.p, u, scene.textures()) else { continue };
                    let cos = n.dot(ls.wi);
                    if cos <= 0.0 || ng.dot(ls.wi) <= 0.0 {
                        continue;
                    }
                    // Eq. 1: R is the light direction mirrored about N, V the direction to the viewer.
                    let r = reflect(-ls.wi, n);
                    let spec = if m.ks > 0.0 { m.ks * phong_power(r.dot(wo), m.exponent) } else { 0.0 };
                    let reflectance = m.color * (m.kd * cos) + Color::splat(spec);
                    // Glass has no diffuse part, and its highlight is zero away from the mirror
                    // direction: no light to find, so no shadow ray.
                    if reflectance == Color::ZERO {
                        continue;
                    }
                    let Some(survive) = self.roulette(weight * reflectance.max_element(), sampler) else { continue };
                    let vis = self.shadow_transmittance(scene, hit, ls.wi, ls.dist, stats);
                    if vis == 0.0 {
                        continue;
                    }
                    c += reflectance / survive * ls.weight() * vis / n_samples as f32;
                }
            }
        }

        if depth + 1 >= self.max_depth {
            return (c, Color::ZERO);
        }
        let local = c;
        c = Color::ZERO;
        let reflected = |k: f32, sampler: &mut Sampler, stats: &mut RayStats| {
            let d = reflect(ray.d, n);
            self.secondary(scene, &hit.spawn(d, self.ray_bias), depth + 1, weight, k, sampler, stats)
        };
        match m.kind {
            ClassicKind::Diffuse => {}
            ClassicKind::Reflective => {
                if m.kr > 0.0 {
                    c += reflected(m.kr, sampler, stats);
                }
            }
            ClassicKind::Transparent => {
                let eta = if front { m.ior } else { 1.0 / m.ior };
                match refract(ray.d, n, eta) {
                    Some(t) => {
                        if m.kr > 0.0 {
                            c += reflected(m.kr, sampler, stats);
                        }
                        if m.kt > 0.0 {
                            c += self.secondary(
                                scene,
                                &hit.spawn(t, self.ray_bias),
                                depth + 1,
                                weight,
                                m.kt,
                                sampler,
                                stats,
                            );
                        }
                    }
                    // Total internal reflection: the reflection coefficient becomes 1.
                    None => c += reflected(1.0, sampler, stats),
                }
            }
            ClassicKind::Dielectric => {
                let eta = if front { m.ior } else { 1.0 / m.ior };
                let ks = fresnel_dielectric(n.dot(wo), eta);
                c += reflected(ks, sampler, stats);
                if ks < 1.0
                    && let Some(t) = refract(ray.d, n, eta)
                {
                    c += self.secondary(
                        scene,
                        &hit.spawn(t, self.ray_bias),
                        depth + 1,
                        weight,
                        1.0 - ks,
                        sampler,
                        stats,
                    );
                }
            }
        }
        (local, c)
    }
}

/// (R . V)^n of eq. 1 for R . V = `cos`, negative cosines counting as 0. Powers that round to
/// zero are answered without `powf`, whose underflow path took a twentieth of a Whitted render:
/// with t = 1 - cos, ln(cos) <= -(t + t^2/2 + t^3/3), so where n times that bound is below -110
/// the power is below 2^-158 and `powf` returns 0 too.
#[inline]
fn phong_power(cos: f32, n: f32) -> f32 {
    let c = cos.max(0.0);
    let t = 1.0 - c;
    if n * (t + t * t * 0.5 + t * t * t * (1.0 / 3.0)) > 110.0 {
        return 0.0;
    }
    c.powf(n)
}

impl Whitted {
    /// Fraction of a light's contribution that reaches `hit` along `wi` over distance `dist`
    /// (the one shadow walk, `lighting::transmittance`). Opaque surfaces block it; with
    /// `transparent_shadows`, transparent surfaces pass k_t and dielectrics pass 1 - Fresnel
    /// reflectance at each crossing (refraction does not bend shadow rays, so glass casts a
    /// lighter shadow rather than a caustic, which photon mapping renders).
    pub fn shadow_transmittance(&self, scene: &Scene, hit: &Hit, wi: Vec3, dist: f32, stats: &mut RayStats) -> f32 {
        let see_through = self.transparent_shadows && self.any_transmissive;
        transmittance(scene, hit.origin(), wi, dist, self.ray_bias, see_through, stats, |material, crossing| {
            crossing_transmittance(&self.classic[material as usize], wi, || crossing.ng())
        })
    }
}

/// What a shadow ray along `wi` keeps of its light crossing a surface of material `m`: k_t
/// through a transparent one, 1 - Fresnel reflectance through a dielectric (`ng` gives the
/// surface's geometric normal, asked only then), nothing through any other.
#[inline]
fn crossing_transmittance(m: &Classic, wi: Vec3, ng: impl FnOnce() -> Vec3) -> f32 {
    match m.kind {
        ClassicKind::Transparent => m.kt,
        ClassicKind::Dielectric => {
            let ng = ng();
            // Entering when the ray runs against the normal.
            let eta = if wi.dot(ng) < 0.0 { m.ior } else { 1.0 / m.ior };
            1.0 - fresnel_dielectric(ng.dot(wi), eta)
        }
        _ => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::phong_power;

    /// The shortcut agrees with `powf` bit for bit over cosines and exponents, where it answers
    /// and where it does not.
    #[test]
    fn phong_power_is_powf() {
        for n in [0.0f32, 1.0, 2.5, 10.0, 32.0, 100.0, 200.0, 1000.0, 10_000.0] {
            for i in -100..=20_000 {
                let cos = i as f32 / 20_000.0;
                let exact = cos.max(0.0).powf(n);
                assert_eq!(phong_power(cos, n).to_bits(), exact.to_bits(), "cos {cos}, n {n}");
            }
        }
    }
}
