//! Volumetric path tracing: the path tracer with participating media (Mitsuba 3's `volpath` /
//! `volpathmis`, pbrt-v4's `VolPathIntegrator`).
//!
//! Each segment of a path through a medium is sampled for a free flight (`Medium::
//! sample_distance`: a colour channel chosen by the throughput, the distance by that channel's
//! exponential, weighted by the mixture over channels, so RGB extinction stays unbiased). A
//! scattering point in a medium is a vertex like a surface's, with the phase function for a
//! BSDF: next-event estimation there and at surfaces goes through `lighting::light_sample_at`
//! with the shadow ray's transmittance through media and `null` boundaries
//! (`lighting::transmittance_through_media`), weighted against phase or BSDF sampling by the
//! power heuristic on the directional densities (the two strategies' weights sum to one for
//! every path, so the estimate is unbiased; the free-flight probabilities are left out of the
//! weights). Invisible surfaces (`null` BSDFs, masks' transparent parts) are passed without
//! counting as a bounce and without forgetting the last vertex, whose density the MIS weight of
//! an emitter met after them needs. Russian roulette after three bounces, as the path tracer.
//!
//! Spectral mode (`crate::spectrum::lanes`) as in the path tracer: the lanes carry the path's
//! wavelengths, BSDFs and lights are lifted where the path meets them, and so are the media
//! (`Medium::sample_distance` and `transmittance` with the wavelengths). The free-flight
//! sampling's choice of a lane by throughput and its mixture over lanes need no change: they
//! make each lane's estimate unbiased for that lane, whatever the lanes stand for.

use super::layers::LayerPath;
use super::lighting::{bsdf_scatter, emission_found, light_sample_at, transmittance_through_media, visibility};
use crate::film::Layers;
use crate::geometry::{NO_MEDIUM, Ray, RayOrigin};
use crate::material::bxdf::Transport;
use crate::math::{Color, Vec2, Vec3};
use crate::medium::Phase;
use crate::render::{RayIntegrator, RayStats};
use crate::sampling::{Rng32, Sampler};
use crate::scene::Scene;
use crate::spectrum::Wavelengths;

/// The tag of the side stream (`Sampler::side_stream`) heterogeneous media draw from.
pub const TRACKING_STREAM: u64 = 0x7472_6163_6b69_6e67;

pub struct VolPathTracer {
    /// Longest path in bounces, medium scattering included (0 = emitters only).
    pub max_depth: u32,
    /// The offset rays leave surfaces with (`IntegratorDesc::ray_bias`).
    pub ray_bias: f32,
    /// Spectral mode (`crate::spectrum::lanes`); RGB otherwise.
    pub spectral: bool,
}

impl VolPathTracer {
    /// One light sample at a point `p` of medium `medium` scattering by `phase` towards `wo`.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn medium_direct(
        &self,
        scene: &Scene,
        p: Vec3,
        wo: Vec3,
        medium: u32,
        phase: &Phase,
        u_pick: f32,
        u: Vec2,
        tracking: &mut Rng32,
        wl: Option<&Wavelengths>,
        stats: &mut RayStats,
    ) -> Color {
        let Some((li, p_pick)) = scene.direct_picker.pick(u_pick) else { return Color::ZERO };
        let from = RayOrigin { p, p_error: Vec3::ZERO, ng: Vec3::ZERO };
        light_sample_at(
            scene,
            li,
            p_pick,
            p,
            u,
            true,
            wl,
            |wi, _| {
                let v = phase.p(wo, wi);
                (Color::splat(v), 1.0, v)
            },
            |wi, dist| (1.0, transmittance_through_media(scene, from, wi, dist, medium, 0.0, tracking, wl, stats)),
        )
    }
}

impl RayIntegrator for VolPathTracer {
    type Scratch = ();

    fn radiance(&self, scene: &Scene, ray: &Ray, sampler: &mut Sampler, _: &mut (), stats: &mut RayStats) -> Layers {
        let mut layers = [Color::ZERO; 4];
        let mut beta = Color::ONE;
        // In spectral mode the wavelengths take the first dimension after the camera's.
        let mut wl = self.spectral.then(|| Wavelengths::sample(sampler.next_1d()));
        let mut ray = *ray;
        if ray.medium == NO_MEDIUM {
            ray.medium = scene.camera_medium;
        }
        let mut specular_bounce = true;
        let mut prev_pdf = 0.0f32;
        let mut prev_p = ray.o;
        let mut depth = 0;
        let mut layer = LayerPath::CAMERA;
        let has_media = scene.has_media();
        // Numbers for heterogeneous media's tracking, whose count varies: a stream of the pixel
        // sample's own, so the sampler's dimensions stay where they were.
        let mut tracking = sampler.side_stream(TRACKING_STREAM);
        loop {
            stats.rays += 1;
            let hit = scene.intersect(&ray, f32::INFINITY);
            if ray.medium != NO_MEDIUM {
                let medium = &scene.media[ray.medium as usize];
                let t_max = hit.as_ref().map_or(f32::INFINITY, |h| h.t);
                let ms = medium.sample_distance(
                    &ray,
                    t_max,
                    beta,
                    sampler.next_1d(),
                    sampler.next_1d(),
                    &mut tracking,
                    wl.as_ref(),
                );
                beta *= ms.weight;
                if beta == Color::ZERO || !beta.is_finite() {
                    break;
                }
                if ms.scattered {
                    if depth >= self.max_depth {
                        break;
                    }
                    let p = ray.at(ms.t);
                    let wo = -ray.d;
                    let phase = *medium.phase();
                    let (u_pick, u) = (sampler.next_1d(), sampler.next_2d());
                    layers[layer.other_photons()] += beta
                        * self.medium_direct(
                            scene,
                            p,
                            wo,
                            ray.medium,
                            &phase,
                            u_pick,
                            u,
                            &mut tracking,
                            wl.as_ref(),
                            stats,
                        );
                    let s = phase.sample(wo, sampler.next_2d());
                    layer.scatter_in_medium();
                    specular_bounce = false;
                    prev_pdf = s.pdf;
                    prev_p = p;
                    depth += 1;
                    if !self.survives(&mut beta, depth, sampler) {
                        break;
                    }
                    ray = Ray { o: p, d: s.wi, medium: ray.medium };
                    continue;
                }
            }
            if let Some((le, w, li)) = emission_found(scene, ray.d, hit.as_ref(), prev_p, prev_pdf, specular_bounce) {
                layers[layer.emitted()] += beta * scene.emission_in(le, li, wl.as_ref()) * w;
            }
            // The ray leaves the scene.
            let Some(hit) = &hit else { break };
            let wo = -ray.d;
            let bsdf = scene.bsdf_for(hit, wo, wl.as_mut(), &mut beta);
            if bsdf.is_invisible() {
                // A medium's boundary: straight on, into the medium beyond, not a bounce.
                let medium = scene.medium_after(hit, ray.d, ray.medium);
                ray = hit.spawn(ray.d, self.ray_bias);
                ray.medium = medium;
                continue;
            }
            if depth >= self.max_depth {
                break;
            }
            if !bsdf.is_specular_only() {
                let (u_pick, u) = (sampler.next_1d(), sampler.next_2d());
                if let Some((li, p_pick)) = scene.direct_picker.pick(u_pick) {
                    let bias = self.ray_bias;
                    let direct = light_sample_at(
                        scene,
                        li,
                        p_pick,
                        hit.p,
                        u,
                        true,
                        wl.as_ref(),
                        |wi, mis| bsdf_scatter(&bsdf, wo, wi, mis),
                        |wi, dist| {
                            if has_media {
                                let medium = scene.medium_after(hit, wi, ray.medium);
                                let tr = transmittance_through_media(
                                    scene,
                                    hit.origin(),
                                    wi,
                                    dist,
                                    medium,
                                    bias,
                                    &mut tracking,
                                    wl.as_ref(),
                                    stats,
                                );
                                (1.0, tr)
                            } else {
                                (visibility(scene, hit.origin(), wi, dist, bias, stats), Color::ONE)
                            }
                        },
                    );
                    layers[layer.direct()] += beta * direct;
                }
            }
            let uc = sampler.next_1d();
            let u = sampler.next_2d();
            let Some(s) = bsdf.sample(wo, uc, u, Transport::Radiance) else { break };
            beta *= s.weight;
            let medium = scene.medium_after(hit, s.wi, ray.medium);
            if s.flags.is_null() {
                // A mask's transparent part: passed like a null boundary.
                ray = hit.spawn(s.wi, self.ray_bias);
                ray.medium = medium;
                continue;
            }
            specular_bounce = s.flags.is_specular();
            layer.bounce(specular_bounce);
            prev_pdf = s.pdf;
            prev_p = hit.p;
            depth += 1;
            if !self.survives(&mut beta, depth, sampler) {
                break;
            }
            ray = hit.spawn(s.wi, self.ray_bias);
            ray.medium = medium;
        }
        if let Some(wl) = &wl {
            layers = layers.map(|l| wl.to_srgb(l));
        }
        layers
    }
}

impl VolPathTracer {
    /// Russian roulette after three bounces on the throughput; false when the path ends.
    #[inline]
    fn survives(&self, beta: &mut Color, depth: u32, sampler: &mut Sampler) -> bool {
        if depth >= 3 {
            let survive = beta.max_element().min(0.95);
            if sampler.rng().uniform() >= survive {
                return false;
            }
            *beta /= survive;
        }
        beta.is_finite() && *beta != Color::ZERO
    }
}
