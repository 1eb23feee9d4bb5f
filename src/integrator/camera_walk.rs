//! The camera walk photon mapping and SPPM share (Jensen 2001 sec. 9; pbrt-v4's SPPM visible
//! points): from the camera through mirrors and glass, and through glossy surfaces without a
//! diffuse part (rough metal and glass, followed by ray tracing), to the next surface whose
//! light the integrator estimates from photons. On the way it adds the light emitted at what it
//! meets and, at every surface with a non-delta part, the direct light the integrator's own
//! estimator gives; the layers follow the lobes sampled (`LayerPath`). What happens at the
//! vertex, and whether the path goes on through a delta part there, is the integrator's.

use super::layers::LayerPath;
use crate::geometry::{Hit, Ray};
use crate::material::bsdf::{Bsdf, BsdfSample};
use crate::material::bxdf::Transport;
use crate::math::{Color, Vec3};
use crate::render::RayStats;
use crate::sampling::Sampler;
use crate::scene::Scene;

/// A camera path being walked.
#[derive(Clone, Copy, Debug)]
pub struct CameraWalk {
    pub ray: Ray,
    /// The path's throughput so far.
    pub beta: Color,
    pub layer: LayerPath,
    /// A glossy bounce was sampled on the way.
    pub glossy_prefix: bool,
    /// Distance travelled from the camera.
    pub dist: f32,
    /// The last bounce was glossy and its direct light came from a light sample: a light hit now
    /// would count it twice.
    lit_by_light_sample: bool,
    /// Surfaces met so far.
    depth: u32,
}

/// A surface the walk stopped at, whose light the integrator estimates.
pub struct WalkVertex<'s> {
    pub hit: Hit,
    pub bsdf: Bsdf<'s>,
    /// Towards the viewer.
    pub wo: Vec3,
    /// Its bounce in the camera path (1 for the first surface).
    pub bounce: u32,
    /// The depth limit allows no bounce after it.
    pub last: bool,
}

impl CameraWalk {
    /// A walk along camera ray `ray` of throughput `beta` (the sample's filter weight).
    pub fn new(ray: Ray, beta: Color) -> Self {
        CameraWalk {
            ray,
            beta,
            layer: LayerPath::CAMERA,
            glossy_prefix: false,
            dist: 0.0,
            lit_by_light_sample: false,
            depth: 0,
        }
    }

    /// Walks to the next vertex (see the module docs) within `max_depth` bounces, spawning rays
    /// with offset `bias`: light emitted on the way (the environment, emitters) goes to
    /// `add(layer, light)`, and so does `direct(hit, bsdf, wo, sampler, stats)` times the
    /// throughput at every surface with a non-delta part. `None` when the path ends first.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub fn next_vertex<'s>(
        &mut self,
        scene: &'s Scene,
        max_depth: u32,
        bias: f32,
        sampler: &mut Sampler,
        stats: &mut RayStats,
        mut add: impl FnMut(usize, Color),
        mut direct: impl FnMut(&Hit, &Bsdf, Vec3, &mut Sampler, &mut RayStats) -> Color,
    ) -> Option<WalkVertex<'s>> {
        loop {
            stats.rays += 1;
            let Some(hit) = scene.intersect(&self.ray, f32::INFINITY) else {
                if !self.lit_by_light_sample {
                    add(self.layer.emitted(), self.beta * scene.environment(self.ray.d));
                }
                return None;
            };
            self.dist += hit.t;
            let wo = -self.ray.d;
            if hit.is_emitter() {
                if hit.is_front(self.ray.d) && !self.lit_by_light_sample {
                    add(self.layer.emitted(), self.beta * scene.emitted(&hit, wo));
                }
                // A reflecting emitter (one with a BSDF) also reflects.
                if scene.bsdf(&hit, wo).is_black() {
                    return None;
                }
            }
            // This surface is bounce depth + 1: lit only within the depth limit.
            let depth = self.depth;
            self.depth += 1;
            if depth >= max_depth {
                return None;
            }
            let bsdf = scene.bsdf(&hit, wo);
            let last = depth + 1 >= max_depth;
            if bsdf.is_specular_only() {
                if last {
                    return None;
                }
                let s = bsdf.sample(wo, sampler.next_1d(), sampler.next_2d(), Transport::Radiance)?;
                self.follow_delta(&hit, &s, bias);
                continue;
            }
            add(self.layer.direct(), self.beta * direct(&hit, &bsdf, wo, sampler, stats));
            if bsdf.is_glossy_only() && !last {
                // Ray-traced glossy reflection: one sampled direction carries the rest.
                let s = bsdf.sample(wo, sampler.next_1d(), sampler.next_2d(), Transport::Radiance)?;
                let delta = s.flags.is_specular();
                self.beta *= s.weight;
                self.layer.bounce(delta);
                self.lit_by_light_sample = !delta;
                self.glossy_prefix |= !delta;
                self.ray = hit.spawn(s.wi, bias);
                continue;
            }
            return Some(WalkVertex { hit, bsdf, wo, bounce: depth + 1, last });
        }
    }

    /// Goes on from `hit` through the delta (mirror, glass, straight-through) sample `s`.
    #[inline]
    pub fn follow_delta(&mut self, hit: &Hit, s: &BsdfSample, bias: f32) {
        self.beta *= s.weight;
        self.layer.bounce(true);
        self.lit_by_light_sample = false;
        self.ray = hit.spawn(s.wi, bias);
    }
}
