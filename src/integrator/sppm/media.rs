//! SPPM in scenes with participating media: photons scatter in media and are stored there too
//! (`trace::Store::Media`), and a camera path that scatters in a medium estimates the light
//! scattered towards the camera there from the volume photons around it (Jensen and
//! Christensen 1998's volume radiance estimate: the sum of the photons' flux times the phase
//! function over the sphere's volume), with a radius that shrinks with the iteration as
//! r_i = r_1 i^((alpha - 1) / 3) (Knaus and Zwicker 2011's progressive photon mapping, for a
//! three-dimensional kernel), so the estimate converges to the exact in-scattered light. Every
//! iteration's estimate is independent and goes into the pixel's sum of emitted and direct
//! light, which is averaged over iterations.
//!
//! The camera path is a free flight through media (`Medium::sample_distance`, as the volumetric
//! path tracer samples it): it ends in the medium with the probability of a collision there,
//! or reaches a surface with its throughput weighted by the transmittance, where the visible
//! point is made as without media (direct light by a light sample through media and `null`
//! boundaries; mirrors and glass followed). Volume photons include the first scattering of
//! light from the lights: direct in-scattering comes from them, not from light samples.

use super::grid::PhotonGrid;
use super::point::{PointSurface, Shading, VisiblePoint};
use super::{CameraSample, Sppm};
use crate::geometry::NO_MEDIUM;
use crate::integrator::layers::LayerPath;
use crate::integrator::lighting::{bsdf_scatter, light_sample_at, transmittance_through_media};
use crate::integrator::sphere_bounds::SphereBounds;
use crate::material::bxdf::Transport;
use crate::math::{Color, Vec2, Vec3};
use crate::photon::PhotonHits;
use crate::photon::trace;
use crate::render::{RayStats, RenderSettings};
use crate::scene::Scene;
use crate::spectrum::Wavelengths;

/// Volume photons a gathering sphere holds on average in the first iteration with the default
/// radius: enough that most spheres in lit fog find some (with far fewer, most find none and a
/// rare few find one of great weight: a finite run's mean falls short with bright specks), few
/// enough that the blur is that of a pixel's neighbourhood in the scenes measured.
const PHOTONS_PER_SPHERE: f64 = 2.0;
/// Photons traced to measure the volume photons' density (at most; fewer if an iteration emits
/// fewer).
const PILOT_PHOTONS: u64 = 1 << 16;

/// One iteration's volume photons and the radius they are gathered within.
pub(super) struct VolumePhotons {
    pub grid: PhotonGrid,
    pub hits: PhotonHits,
    pub r: f32,
}

impl VolumePhotons {
    /// Moves the volume photons out of `hits` (which keeps the surface ones) into a grid for
    /// iteration `it` (from 0), whose radius is `r1` shrunk by Knaus and Zwicker's schedule.
    pub fn split(hits: &mut PhotonHits, r1: f32, alpha: f32, it: u32, origin: Vec3) -> Self {
        let mut volume = Vec::new();
        hits.retain(|h| {
            let v = h.flags & trace::VOLUME != 0;
            if v {
                volume.push(*h);
            }
            !v
        });
        let r = r1 * ((it + 1) as f32).powf((alpha - 1.0) / 3.0);
        let mut volume = PhotonHits::from_vec(volume);
        let grid = PhotonGrid::build(&mut volume, 2.0 * r, origin);
        VolumePhotons { grid, hits: volume, r }
    }

    /// The light scattered towards `wo` at `p` in a medium of phase function `phase`, from
    /// photons of at most `max_depth` scattering events. The surfaces near `p` bound the sphere
    /// (`SphereBounds`): photons beyond them are not counted and the volume divided by is the
    /// part of the sphere on `p`'s side. `u` rotates the probe directions.
    fn estimate(
        &self,
        scene: &Scene,
        phase: &crate::medium::Phase,
        p: Vec3,
        wo: Vec3,
        max_depth: u32,
        u: Vec2,
    ) -> Color {
        let bounds = SphereBounds::probe(scene, p, self.r, u);
        let mut sum = Color::ZERO;
        self.grid.for_each_within(p, self.r, |found| {
            let ph = self.grid.photon(&self.hits, found);
            if u32::from(ph.depth) <= max_depth && bounds.keeps(ph.p) {
                sum += ph.flux.get() * phase.p(wo, -ph.dir);
            }
        });
        sum / bounds.volume
    }
}

/// The first iteration's volume radius when the user gives none: the radius at which a sphere
/// holds `PHOTONS_PER_SPHERE` volume photons of an iteration of `photons_per_iter`, were they
/// spread evenly over the box where nearly all of them lie (the 1st to 99th percentile per axis,
/// within the scene's bounds). It is measured by a pilot photon pass of its own seed, so every
/// shard and every resumed run of a render finds the same radius. A fixed fraction of the scene
/// did not work: a light shaft in a room of haze found almost no photons with it.
pub(super) fn first_volume_radius(scene: &Scene, photons_per_iter: u64, seed: u64, bias: f32) -> f32 {
    let bounds = scene.bounds();
    let diag = if bounds.is_empty() || !bounds.diagonal().is_finite() { 1.0 } else { bounds.diagonal() };
    let fallback = 0.01 * diag;
    let n = photons_per_iter.clamp(1, PILOT_PHOTONS);
    let mut hits = PhotonHits::default();
    let watch = trace::Watch::none();
    trace::trace_global_into(scene, n, seed, bias, trace::Store::Media, trace::PhotonColour::Rgb, watch, &mut hits);
    let bounded = !bounds.is_empty() && bounds.diagonal().is_finite();
    let inside = |p: Vec3| !bounded || (p.cmpge(bounds.min).all() && p.cmple(bounds.max).all());
    let mut axes: [Vec<f32>; 3] = Default::default();
    for h in hits.iter().filter(|h| h.flags & trace::VOLUME != 0 && inside(h.p)) {
        for (axis, v) in axes.iter_mut().zip([h.p.x, h.p.y, h.p.z]) {
            axis.push(v);
        }
    }
    let count = axes[0].len();
    if count < 32 {
        return fallback;
    }
    let mut volume = 1.0f64;
    for axis in &mut axes {
        let lo = percentile(axis, 0.01);
        let hi = percentile(axis, 0.99);
        volume *= f64::from((hi - lo).max(1e-3 * diag));
    }
    // Photons per unit volume in one iteration, and the radius holding the chosen number.
    let density = count as f64 / n as f64 * photons_per_iter as f64 / volume;
    let r = (3.0 * PHOTONS_PER_SPHERE / (4.0 * std::f64::consts::PI * density)).cbrt() as f32;
    r.clamp(5e-4 * diag, 0.1 * diag)
}

/// The `q`-quantile of `values` (reordered in place).
fn percentile(values: &mut [f32], q: f64) -> f32 {
    let k = ((values.len() - 1) as f64 * q).round() as usize;
    *values.select_nth_unstable_by(k, f32::total_cmp).1
}

impl Sppm {
    /// `camera_sample` in a scene with media: see the module's notes.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn camera_sample_media(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        (x, y): (u32, u32),
        it: u32,
        volume: &VolumePhotons,
        point: &mut Option<VisiblePoint>,
        stats: &mut RayStats,
    ) -> CameraSample {
        let config = &self.config;
        *point = None;
        let bias = config.ray_bias;
        let (mut sampler, mut ray, weight) = settings.camera_sample(scene, x, y, it);
        // In spectral mode the wavelengths take the first dimension after the camera's, as in
        // `camera_sample`; the light found on the way is spectral (`ld`, `ld_layers`), the
        // volume photons' estimates RGB (`rgb`).
        let mut wl = config.spectral.then(|| Wavelengths::sample(sampler.next_1d()));
        let mut rgb = [Color::ZERO; 4];
        let mut tracking = sampler.side_stream(crate::integrator::volpath::TRACKING_STREAM);
        if ray.medium == NO_MEDIUM {
            ray.medium = scene.camera_medium;
        }
        let mut beta = Color::splat(weight);
        let mut ld = Color::ZERO;
        let mut ld_layers = [Color::ZERO; 4];
        let mut layer = LayerPath::CAMERA;
        let mut depth = 0u32;
        let mut dist = 0.0f32;
        let mut add = |k: usize, l: Color| {
            ld += l;
            ld_layers[k] += l;
        };
        for _ in 0..trace::MAX_BOUNCES * 2 {
            stats.rays += 1;
            let hit = scene.intersect(&ray, f32::INFINITY);
            if ray.medium != NO_MEDIUM {
                let medium = &scene.media[ray.medium as usize];
                let t_max = hit.as_ref().map_or(f32::INFINITY, |h| h.t);
                let (u_channel, u) = (sampler.next_1d(), sampler.next_1d());
                let ms = medium.sample_distance(&ray, t_max, beta, u_channel, u, &mut tracking, wl.as_ref());
                if ms.scattered {
                    // This scattering event is bounce depth + 1.
                    let Some(limit) = trace::photon_depth_limit(config.max_depth, depth + 1) else { break };
                    let l = volume.estimate(scene, medium.phase(), ray.at(ms.t), -ray.d, limit, sampler.next_2d());
                    match &wl {
                        Some(wl) => rgb[layer.other_photons()] += wl.throughput_to_srgb(beta * ms.tr_over_pdf) * l,
                        None => add(layer.other_photons(), beta * ms.tr_over_pdf * l),
                    }
                    break;
                }
                beta *= ms.weight;
                if beta == Color::ZERO || !beta.is_finite() {
                    break;
                }
            }
            let Some(hit) = &hit else {
                add(layer.emitted(), beta * scene.environment_in(ray.d, wl.as_ref()));
                break;
            };
            dist += hit.t;
            let wo = -ray.d;
            if hit.is_emitter() && hit.is_front(ray.d) {
                add(layer.emitted(), beta * scene.emission_in(scene.emitted(hit, wo), hit.light, wl.as_ref()));
            }
            let bsdf = scene.bsdf_for(hit, wo, wl.as_mut(), &mut beta);
            if bsdf.is_invisible() {
                let medium = scene.medium_after(hit, ray.d, ray.medium);
                ray = hit.spawn(ray.d, bias);
                ray.medium = medium;
                continue;
            }
            if bsdf.is_black() || depth >= config.max_depth {
                break;
            }
            let last = depth + 1 >= config.max_depth;
            if bsdf.has_smooth() {
                let (u_pick, u) = (sampler.next_1d(), sampler.next_2d());
                if let Some((li, p_pick)) = scene.direct_picker.pick(u_pick) {
                    let direct = light_sample_at(
                        scene,
                        li,
                        p_pick,
                        hit.p,
                        u,
                        false,
                        wl.as_ref(),
                        |wi, mis| bsdf_scatter(&bsdf, wo, wi, mis),
                        |wi, d| {
                            let m = scene.medium_after(hit, wi, ray.medium);
                            let w = wl.as_ref();
                            let tr = transmittance_through_media(
                                scene,
                                hit.origin(),
                                wi,
                                d,
                                m,
                                bias,
                                &mut tracking,
                                w,
                                stats,
                            );
                            (1.0, tr)
                        },
                    );
                    add(layer.direct(), beta * direct);
                }
            }
            let q = if !bsdf.has_smooth() {
                0.0
            } else if bsdf.has_delta() && !last {
                bsdf.smooth_fraction(wo)
            } else {
                1.0
            };
            if sampler.next_1d() < q {
                let photon_depth = trace::photon_depth_limit(config.max_depth, depth + 1).unwrap_or(0);
                // The photons' light is RGB: the camera path's filter weights it as a colour.
                let beta = match &wl {
                    Some(wl) => wl.throughput_to_srgb(beta),
                    None => beta,
                };
                *point = Some(VisiblePoint {
                    surface: PointSurface::General { at: Shading::of(hit), wo },
                    beta: (beta / q).into(),
                    layer,
                    photon_depth: photon_depth.min(u8::MAX.into()) as u8,
                });
                let (ld, ld_layers) = to_rgb(wl.as_ref(), ld, ld_layers, rgb);
                return CameraSample { ld, ld_layers, dist: Some(dist) };
            }
            if last {
                break;
            }
            let Some(s) = bsdf.sample_delta(wo, sampler.next_1d(), sampler.next_2d(), Transport::Radiance) else {
                break;
            };
            beta *= s.weight / (1.0 - q);
            let medium = scene.medium_after(hit, s.wi, ray.medium);
            if !s.flags.is_null() {
                depth += 1;
                layer.bounce(true);
            }
            ray = hit.spawn(s.wi, bias);
            ray.medium = medium;
        }
        let (ld, ld_layers) = to_rgb(wl.as_ref(), ld, ld_layers, rgb);
        CameraSample { ld, ld_layers, dist: None }
    }
}

/// A camera sample's light as RGB: in spectral mode (`wl`) the spectral light found on the way
/// converted, plus the RGB light from the volume photons (`rgb`, by layer); in RGB mode itself.
fn to_rgb(wl: Option<&Wavelengths>, ld: Color, ld_layers: [Color; 4], rgb: [Color; 4]) -> (Color, [Color; 4]) {
    let Some(wl) = wl else { return (ld, ld_layers) };
    let layers: [Color; 4] = std::array::from_fn(|k| wl.to_srgb(ld_layers[k]) + rgb[k]);
    (layers.iter().copied().sum(), layers)
}
