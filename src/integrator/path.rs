//! Unidirectional path tracing: the reference the photon-mapping integrators are checked against.
//!
//! Next-event estimation at every non-specular vertex (a light chosen in proportion to power),
//! combined with BSDF sampling by multiple importance sampling (power heuristic, Veach 1997) for
//! area and environment lights, and Russian roulette after three bounces. Unbiased up to the depth limit.
//!
//! In spectral mode a path draws its wavelengths from the sampler's first dimension after the
//! camera's and carries one value per wavelength in each lane of its colours
//! (`crate::spectrum::lanes`): BSDFs and lights are lifted where the path meets them, and the
//! layers are converted to linear sRGB when the path ends.

use super::layers::LayerPath;
use super::lighting::{direct_light, emission_found};
use crate::film::Layers;
use crate::geometry::Ray;
use crate::material::bxdf::Transport;
use crate::math::Color;
use crate::render::{RayIntegrator, RayStats};
use crate::sampling::Sampler;
use crate::scene::Scene;
use crate::spectrum::Wavelengths;

pub struct PathTracer {
    /// Longest path in bounces (0 = emitters only, 1 = direct light only).
    pub max_depth: u32,
    /// The offset rays leave surfaces with (`IntegratorDesc::ray_bias`).
    pub ray_bias: f32,
    /// Spectral mode (`crate::spectrum::lanes`); RGB otherwise.
    pub spectral: bool,
}

impl RayIntegrator for PathTracer {
    type Scratch = ();

    fn radiance(&self, scene: &Scene, ray: &Ray, sampler: &mut Sampler, _: &mut (), stats: &mut RayStats) -> Layers {
        let mut layers = [Color::ZERO; 4];
        let mut beta = Color::ONE;
        let mut wl = self.spectral.then(|| Wavelengths::sample(sampler.next_1d()));
        let mut ray = *ray;
        let mut specular_bounce = true;
        let mut prev_pdf = 0.0f32;
        let mut prev_p = ray.o;
        let mut depth = 0;
        // Which layer the light found along the path belongs to.
        let mut layer = LayerPath::CAMERA;
        loop {
            stats.rays += 1;
            let hit = scene.intersect(&ray, f32::INFINITY);
            if let Some((le, w, light)) = emission_found(scene, ray.d, hit.as_ref(), prev_p, prev_pdf, specular_bounce)
            {
                layers[layer.emitted()] += beta * scene.emission_in(le, light, wl.as_ref()) * w;
            }
            // The ray leaves the scene. (The hit is read where the intersection wrote it: a copy
            // of it stalled on those stores, a tenth of this function's time.)
            let Some(hit) = &hit else { break };
            let wo = -ray.d;
            if depth >= self.max_depth {
                break;
            }
            let bsdf = scene.bsdf_for(hit, wo, wl.as_mut(), &mut beta);
            if !bsdf.is_specular_only() {
                let (u_pick, u) = (sampler.next_1d(), sampler.next_2d());
                layers[layer.direct()] +=
                    beta * direct_light(scene, hit, &bsdf, wo, u_pick, u, self.ray_bias, true, wl.as_ref(), stats);
            }
            let uc = sampler.next_1d();
            let u = sampler.next_2d();
            let Some(s) = bsdf.sample(wo, uc, u, Transport::Radiance) else { break };
            beta *= s.weight;
            layer.bounce(s.flags.is_specular());
            depth += 1;
            if s.flags.is_null() {
                // Straight through a mask's transparent part: what the ray meets next is weighed
                // against the light sample of the last vertex that scattered, whose shadow ray
                // passes the mask the same way (by its transmittance). Taken as a mirror bounce,
                // weight 1, that light was counted twice.
                ray = hit.spawn(s.wi, self.ray_bias);
                continue;
            }
            specular_bounce = s.flags.is_specular();
            prev_pdf = s.pdf;
            prev_p = hit.p;
            if depth >= 3 {
                let survive = beta.max_element().min(0.95);
                if sampler.rng().uniform() >= survive {
                    break;
                }
                beta /= survive;
            }
            if !beta.is_finite() || beta == Color::ZERO {
                break;
            }
            ray = hit.spawn(s.wi, self.ray_bias);
        }
        if let Some(wl) = &wl {
            layers = layers.map(|l| wl.to_srgb(l));
        }
        layers
    }
}
