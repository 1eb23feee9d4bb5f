//! Photon mapping (Jensen 1996; Jensen 2001, "A practical guide to global illumination using
//! photon mapping", sec. 4): two photon maps built before rendering, then for each camera ray
//! - mirrors and glass are followed by ray tracing, and so are glossy
//!   surfaces without a diffuse part (rough metal and glass): their direct light comes from
//!   shadow rays, the rest by following one sampled direction (Jensen's Monte Carlo ray tracing
//!   of specular and glossy reflection);
//! - at a surface with a diffuse part (or a glossy one where the depth limit is reached), direct
//!   light comes from shadow rays (several per area light), caustics from the caustic map with a
//!   cone filter, and indirect light from final gathering: rays sampled from the BSDF's
//!   non-delta part whose hits read the global map. With zero gather rays the global map is read
//!   at the surface itself (a fast preview, as the seed report did). All of these use the whole
//!   BSDF, glossy coatings included. A mirror or glass part of the same material (or a mask's
//!   transparent part) is then followed further, so mixed materials keep their reflections.
//!
//! Radiance estimate (Jensen 2001 eq. 4.6): L = sum over the k nearest photons within a maximum
//! radius of f(wo, wi_p) Phi_p / (pi r^2), r the k-th photon's distance, or the maximum radius
//! where fewer than k lie within it (sparse photons, as far out on a floor plane: the distance
//! of the farthest of a few would overestimate), counting only photons arriving on the surface's
//! side and lying near its tangent plane (a disc-shaped search), so walls meeting at a corner do
//! not leak light into each other. Everything is in physical units; nothing is scaled by hand.
//!
//! Participating media (`media`): a volume photon map beside the two, light samples at the
//! camera path's scattering points, and final-gather rays that scatter in media.
//!
//! Depth: a photon remembers how often it scattered, and an estimate at bounce b of a camera
//! path counts only photons of at most `max_depth - b` bounces, so every light path keeps to
//! the limit the path tracer keeps to (`trace::photon_depth_limit`).

use super::camera_walk::{CameraWalk, Stop, VertexSlot};
use super::lighting::EveryLight;
use crate::film::Layers;
use crate::geometry::{Hit, Ray};
use crate::material::bsdf::Bsdf;
use crate::material::bxdf::Transport;
use crate::math::{Color, PackedColor, Vec3};
use crate::options::PhotonOptions;
use crate::photon::trace::{self, PhotonPass, Watch};
use crate::photon::{Gathered, Photon, PhotonMap};
use crate::progress::Display;
use crate::render::{RayIntegrator, RayStats};
use crate::sampling::Sampler;
use crate::sampling::warp::cosine_hemisphere;
use crate::scene::Scene;
use crate::scene::desc::IntegratorDesc;
use crate::spectrum::Wavelengths;
use std::f32::consts::PI;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

mod fill;
pub mod irradiance_cache;
mod media;
mod records;

pub use media::DEFAULT_VOLUME_K;

use irradiance_cache::{GatherSample, IrradianceCache};
use records::precompute_irradiance;

/// Settings of the photon-mapping integrator.
#[derive(Clone, Debug, PartialEq)]
pub struct PhotonConfig {
    /// Photons emitted for the global map.
    pub photons: u64,
    /// Caustic photons to store (emission goes on until this many are stored or the cap).
    pub caustic_photons: u64,
    /// At most this many photons are emitted for the caustic map.
    pub caustic_cap: u64,
    /// Final-gather rays per camera sample; 0 reads the global map directly.
    pub gather_rays: u32,
    /// Irradiance cache error threshold `a` (Ward's); 0 turns the cache off.
    pub cache_error: f32,
    /// Final-gather rays per irradiance record.
    pub cache_rays: u32,
    /// Photons per radiance estimate (global map).
    pub gather_k: usize,
    /// Photons per caustic estimate.
    pub caustic_k: usize,
    /// Largest search radius of a global estimate (scene units).
    pub max_radius: f32,
    /// Largest search radius of a caustic estimate.
    pub caustic_radius: f32,
    /// Photons per volume radiance estimate (scenes with media).
    pub volume_k: usize,
    /// Largest search radius of a volume estimate; 0 until the volume map is built, which sets
    /// the default from its photons' spacing (`media`).
    pub volume_radius: f32,
    /// Cone filter constant k >= 1 (Jensen 2001 eq. 4.8).
    pub cone_k: f32,
    /// Shadow rays per area light at each shading point.
    pub light_samples: u32,
    /// Depth limit in bounces: specular bounces are followed from the camera while the next
    /// surface is still within it.
    pub max_depth: u32,
    pub seed: u64,
    /// The offset rays leave surfaces with (`IntegratorDesc::ray_bias`).
    pub ray_bias: f32,
    /// Spectral mode: photons and camera paths carry wavelengths; the maps hold XYZ.
    pub spectral: bool,
}

impl PhotonConfig {
    /// Photon bounces the precomputed irradiance records hold: what the depth limit leaves at
    /// a final-gather hit seen from a camera ray's first surface (bounce 2), the common case.
    /// A gather hit deeper in the camera path, which allows fewer, reads the photons instead.
    pub fn record_depth(&self) -> u32 {
        trace::photon_depth_limit(self.max_depth, 2).unwrap_or(0)
    }

    /// Full settings for `scene`: radii default to fractions of the scene's size (so any scene
    /// scale works), counts to values that render the bundled Cornell boxes cleanly.
    pub fn new(o: &PhotonOptions, desc: &IntegratorDesc, scene: &Scene, seed: u64) -> Self {
        let b = scene.bounds();
        let diag = if b.is_empty() || !b.diagonal().is_finite() { 1.0 } else { b.diagonal() };
        let caustic_photons = o.caustic_photons.unwrap_or(200_000);
        PhotonConfig {
            photons: o.photons.unwrap_or(500_000),
            caustic_photons,
            caustic_cap: caustic_photons.saturating_mul(200).max(1_000_000),
            gather_rays: o.gather.unwrap_or(16),
            cache_error: o.irradiance_cache.unwrap_or(DEFAULT_CACHE_ERROR).max(0.0),
            cache_rays: o.cache_rays.unwrap_or(DEFAULT_CACHE_RAYS).max(16),
            gather_k: o.gather_k.unwrap_or(64).max(1),
            caustic_k: o.caustic_k.unwrap_or(64).max(1),
            max_radius: o.max_radius.unwrap_or(0.05 * diag),
            caustic_radius: o.caustic_radius.unwrap_or(0.02 * diag),
            volume_k: o.volume_k.unwrap_or(DEFAULT_VOLUME_K).max(1),
            volume_radius: o.volume_radius.unwrap_or(0.0),
            cone_k: 1.1,
            light_samples: desc.light_samples,
            max_depth: desc.depth_limit(desc.kind),
            seed,
            ray_bias: desc.ray_bias(scene),
            spectral: desc.spectral,
        }
    }
}

impl PhotonConfig {
    /// The phases of `build_watched` and the render, each with its cost in about rays traced
    /// (`integrator::plan`), for `camera_samples` samples. The factors are rough, set from the
    /// phases' times on the walkthrough's scene (`scenes/14-first-scene.toml`): a global photon
    /// traces about two rays, an emitted caustic photon three; a map costs about a ray per photon
    /// and an irradiance record (one per four stored photons) about twelve; a cache record's
    /// rays cost about three each (each reads the irradiance records where it lands), and a
    /// render sample its camera ray, most of its shadow rays and, without the cache, its gather
    /// rays.
    pub fn plan(&self, scene: &Scene, camera_samples: f64) -> Vec<(&'static str, f64)> {
        let (photons, caustic) = (self.photons as f64, self.caustic_photons as f64);
        let mut phases = vec![
            ("photons", 2.0 * photons),
            ("caustics", 3.0 * caustic),
            ("maps", photons + caustic),
            ("gather", 3.0 * photons),
        ];
        let cached = self.cache_error > 0.0 && self.gather_rays > 0;
        let pixels = f64::from(scene.camera.width) * f64::from(scene.camera.height);
        if cached {
            // Records cover a disc whose radius scales with the threshold: about 27 pixels each
            // at the default 0.25 on the walkthrough's scene, at most one per pixel.
            let records = (pixels * 0.0023 / (self.cache_error * self.cache_error) as f64).min(pixels);
            phases.push(("cache", 3.0 * records * f64::from(self.cache_rays)));
        }
        let per_light = f64::from(self.light_samples);
        let shadow: f64 =
            scene.lights.iter().map(|l| if l.is_delta() { 1.0 } else { per_light }).sum::<f64>().min(4.0 * per_light);
        let gather = if cached { 0.0 } else { 2.0 * f64::from(self.gather_rays) };
        phases.push(("render", camera_samples * (1.0 + 0.7 * shadow + gather)));
        phases
    }
}

/// Default irradiance cache error threshold (`--irradiance-cache`; 0 turns the cache off).
pub const DEFAULT_CACHE_ERROR: f32 = 0.25;
/// Default final-gather rays per irradiance record (`--cache-rays`).
pub const DEFAULT_CACHE_RAYS: u32 = 512;

/// What building the maps did, for the log.
#[derive(Clone, Debug, Default)]
pub struct PhotonStats {
    pub global_emitted: u64,
    pub global_stored: usize,
    pub caustic_emitted: u64,
    pub caustic_stored: usize,
    pub caustic_capped: bool,
    pub trace_time: Duration,
    pub build_time: Duration,
    pub global_bytes: usize,
    pub caustic_bytes: usize,
    /// Photons in the volume map (scenes with media).
    pub volume_stored: usize,
    /// Irradiance records made before rendering, and the time they took.
    pub cache_records: usize,
    pub cache_time: Duration,
}

pub struct PhotonIntegrator {
    pub config: PhotonConfig,
    global: PhotonMap,
    caustic: PhotonMap,
    /// Photons scattered in media (empty without media).
    volume: PhotonMap,
    /// Irradiance precomputed at a subset of the global photons (Christensen 1999): records
    /// whose `direction` is the surface normal. Final-gather rays read the nearest record
    /// instead of making a full radiance estimate.
    irradiance: PhotonMap,
    /// Each record's irradiance (in the map's order) from photons of at most
    /// `PhotonConfig::record_depth() - j` bounces, for 1 <= j < `RECORD_LEVELS` (j = 0 is the
    /// record's own power): a gather hit deeper in the camera path allows photons fewer bounces.
    irradiance_levels: Vec<[PackedColor; RECORD_LEVELS - 1]>,
    /// Irradiance cache over the camera's first diffuse hits (empty when off or when gathering
    /// is off): filled once before rendering, then only read.
    cache: IrradianceCache,
    /// Direct light: every light in turn, `light_samples` for each area light.
    lights: EveryLight,
    pub stats: PhotonStats,
}

/// One global photon in this many gets a precomputed irradiance record.
const IRRADIANCE_STRIDE: usize = 4;
/// Depth limits each record holds an irradiance for: gather hits at camera bounces 2 to 5.
const RECORD_LEVELS: usize = 4;

/// Bytes a map of `n` photons needs, for the memory check made before tracing.
pub fn estimated_map_bytes(n: u64) -> u64 {
    // The photon record plus the tree's index and slack for the temporary unpacked hits.
    n * (std::mem::size_of::<Photon>() as u64 + 8 + std::mem::size_of::<trace::PhotonHit>() as u64)
}

/// Bytes the depth levels of `n` precomputed irradiance records need beside their map, at the
/// peak (the levels kept and those computed before the first moves into the records).
pub fn estimated_record_level_bytes(n: u64) -> u64 {
    n * (std::mem::size_of::<[PackedColor; RECORD_LEVELS]>() + std::mem::size_of::<[PackedColor; RECORD_LEVELS - 1]>())
        as u64
}

fn to_photons(pass: &PhotonPass) -> Vec<Photon> {
    pass.hits.iter().map(|h| Photon::new(h.p, h.dir, h.flux.get(), trace::packed_flags(h))).collect()
}

impl PhotonIntegrator {
    /// Traces both photon passes and builds the maps (no progress shown, never cancelled).
    pub fn build(scene: &Scene, config: PhotonConfig) -> Self {
        let never = AtomicBool::new(false);
        Self::build_watched(scene, config, &never, &Display::hidden()).unwrap_or_else(|| unreachable!("not cancelled"))
    }

    /// Traces both photon passes and builds the maps, reporting each phase to `progress` (the
    /// phases `plan` lists) and stopping soon after `cancel` is set (then `None`): photon tracing
    /// between chunks of 4096 photons, the maps between levels of the tree, the irradiance
    /// records between chunks.
    pub fn build_watched(scene: &Scene, config: PhotonConfig, cancel: &AtomicBool, progress: &Display) -> Option<Self> {
        let t0 = Instant::now();
        let bar = progress.phase("photons", config.photons);
        let watch = Watch { cancel, progress: Some(&bar) };
        let store = if scene.has_media() { trace::Store::Volume } else { trace::Store::All };
        let mut global = PhotonPass { emitted: config.photons, ..Default::default() };
        trace::trace_global_into(
            scene,
            config.photons,
            config.seed,
            config.ray_bias,
            store,
            trace::spectral_store(config.spectral, true),
            watch,
            &mut global.hits,
        );
        global.cancelled = watch.cancelled();
        let volume_photons = media::split_volume(&mut global.hits);
        bar.finish(&format!(
            "{} global photons traced, {} stored",
            global.emitted,
            global.hits.len() + volume_photons.len()
        ));
        if global.cancelled {
            return None;
        }
        let bar = progress.phase("caustics", config.caustic_cap);
        let caustic = trace::trace_caustic(
            scene,
            &trace::specular_targets(scene),
            config.caustic_photons,
            config.caustic_cap,
            config.seed,
            config.ray_bias,
            trace::spectral_store(config.spectral, true),
            Watch { cancel, progress: Some(&bar) },
        );
        bar.finish(&format!("{} caustic photons traced, {} stored", caustic.emitted, caustic.hits.len()));
        if caustic.cancelled {
            return None;
        }
        let trace_time = t0.elapsed();
        let t1 = Instant::now();
        let bar = progress.phase("maps", 0);
        let (gp, cp) = rayon::join(|| to_photons(&global), || to_photons(&caustic));
        let (global_map, caustic_map) =
            rayon::join(|| PhotonMap::build_cancellable(gp, cancel), || PhotonMap::build_cancellable(cp, cancel));
        let (global_map, caustic_map) = (global_map?, caustic_map?);
        let volume_map = PhotonMap::build_cancellable(volume_photons, cancel)?;
        bar.finish("photon maps built");
        let mut config = config;
        if config.volume_radius <= 0.0 {
            config.volume_radius = media::default_volume_radius(&volume_map, config.volume_k);
        }
        let records = global.hits.len().div_ceil(IRRADIANCE_STRIDE) as u64;
        let bar = progress.phase("gather", records);
        let (irradiance, irradiance_levels) = precompute_irradiance(
            &global.hits,
            &global_map,
            config.gather_k,
            config.max_radius,
            config.record_depth(),
            Watch { cancel, progress: Some(&bar) },
        )?;
        bar.finish(&format!("{records} irradiance records precomputed"));
        let stats = PhotonStats {
            global_emitted: global.emitted,
            global_stored: global_map.len(),
            caustic_emitted: caustic.emitted,
            caustic_stored: caustic_map.len(),
            caustic_capped: caustic.capped,
            trace_time,
            build_time: t1.elapsed(),
            global_bytes: global_map.memory_bytes(),
            caustic_bytes: caustic_map.memory_bytes(),
            volume_stored: volume_map.len(),
            ..Default::default()
        };
        let a = config.cache_error;
        let lights = EveryLight::new(scene, config.light_samples);
        let mut pm = PhotonIntegrator {
            config,
            global: global_map,
            caustic: caustic_map,
            volume: volume_map,
            irradiance,
            irradiance_levels,
            cache: IrradianceCache::empty(a.max(1e-3)),
            lights,
            stats,
        };
        if a > 0.0 && pm.config.gather_rays > 0 {
            let t2 = Instant::now();
            pm.cache = pm.fill_cache(scene, cancel, progress)?;
            pm.stats.cache_records = pm.cache.len();
            pm.stats.cache_time = t2.elapsed();
        }
        Some(pm)
    }

    /// A power or irradiance read from a map as linear sRGB: in spectral mode the maps hold CIE
    /// XYZ (never negative, as the maps' packed powers must be; see the module docs), converted
    /// here; in RGB mode itself.
    #[inline]
    fn colour(&self, c: Color) -> Color {
        if self.config.spectral { crate::spectrum::xyz_to_color(c.to_array()) } else { c }
    }

    /// Outgoing diffuse radiance towards `wo_y` at a final-gather hit from the nearest
    /// precomputed irradiance record facing the same way (L = albedo / pi * E), at the level of
    /// the photon bounces `depth` allows; where photons are too sparse for a record to be near
    /// (far out on a floor plane, whose photons thin out with distance), or where the depth
    /// limit allows fewer bounces than the records' last level (`RECORD_LEVELS`), from the
    /// photons themselves.
    fn gathered_radiance(&self, y: &Hit, by: &Bsdf, wo_y: Vec3, depth: u32, scratch: &mut Gathered) -> Color {
        let c = &self.config;
        let level = c.record_depth().saturating_sub(depth) as usize;
        if level >= RECORD_LEVELS {
            return self.estimate(&self.global, y, by, wo_y, c.gather_k, c.max_radius, 0, depth, None, scratch);
        }
        let r = self.config.max_radius;
        let n = by.normal();
        // Records lie a few photon spacings apart: the nearest few within half the estimate
        // radius always include the right one.
        let (found, _) = self.irradiance.gather(y.p, 4, r * r * 0.25, scratch);
        let best = found
            .iter()
            .filter(|(_, i)| self.irradiance.photon(*i).direction().dot(n) > 0.8)
            .min_by(|a, b| a.0.total_cmp(&b.0));
        match best {
            Some(&(_, i)) => {
                let e = self.colour(match level {
                    0 => self.irradiance.photon(i).power(),
                    _ => self.irradiance_levels[i as usize][level - 1].get(),
                });
                by.diffuse_albedo() * e * std::f32::consts::FRAC_1_PI
            }
            None => self.estimate(&self.global, y, by, wo_y, c.gather_k, c.max_radius, 0, depth, None, scratch),
        }
    }

    /// Radiance leaving `p` towards `wo` estimated from `map` (see the module docs). Photons
    /// with any of the `exclude` flags, or that scattered more than `depth` times, are skipped;
    /// `cone` applies the cone filter.
    #[allow(clippy::too_many_arguments)]
    fn estimate(
        &self,
        map: &PhotonMap,
        hit: &Hit,
        bsdf: &Bsdf,
        wo: Vec3,
        k: usize,
        max_r: f32,
        exclude: u8,
        depth: u32,
        cone: Option<f32>,
        scratch: &mut Gathered,
    ) -> Color {
        if map.is_empty() {
            return Color::ZERO;
        }
        let n = bsdf.normal();
        let (found, r2) = map.gather(hit.p, k, max_r * max_r, scratch);
        if found.is_empty() {
            return Color::ZERO;
        }
        let r2 = disc_radius2(found.len(), k, r2, max_r);
        let r = r2.sqrt();
        // Photons further than this from the tangent plane lie on other surfaces.
        let thickness = 0.25 * r;
        // Light arrives from behind only through a transmitting surface (rough glass); elsewhere
        // photons from behind belong to the other side of a thin object.
        let both_sides = bsdf.flags().is_transmission();
        // A Lambertian BSDF is albedo / pi for every photon arriving in front of both the shading
        // and the geometric surface, 0 otherwise: sum the power and apply it once.
        let lambert = bsdf.lambert_albedo();
        let ng = bsdf.geometric_normal();
        let mut sum = Color::ZERO;
        for &(d2, i) in found {
            let ph = map.photon(i);
            if ph.flags() & exclude != 0 || trace::packed_depth(ph.flags()) > depth {
                continue;
            }
            let dir = ph.direction();
            if (!both_sides && dir.dot(n) >= 0.0) || (ph.position() - hit.p).dot(n).abs() > thickness {
                continue;
            }
            let w = match cone {
                Some(kc) => 1.0 - d2.sqrt() / (kc * r),
                None => 1.0,
            };
            if lambert.is_some() {
                if dir.dot(ng) < 0.0 {
                    sum += ph.power() * w;
                }
            } else {
                sum += bsdf.f(wo, -dir, Transport::Radiance) * self.colour(ph.power()) * w;
            }
        }
        if let Some(albedo) = lambert {
            sum = self.colour(sum) * (albedo * std::f32::consts::FRAC_1_PI);
        }
        let norm = match cone {
            Some(kc) => 1.0 - 2.0 / (3.0 * kc),
            None => 1.0,
        };
        sum / (PI * r2 * norm)
    }

    /// Radiance leaving a final-gather hit `y` towards `wo_y` from photons that scattered at
    /// most `depth` times: from the precomputed irradiance for a Lambertian surface, from a
    /// full estimate of the global map otherwise.
    fn radiance_at_gather_hit(&self, y: &Hit, by: &Bsdf, wo_y: Vec3, depth: u32, scratch: &mut Gathered) -> Color {
        if by.lambert_albedo().is_some() {
            return self.gathered_radiance(y, by, wo_y, depth, scratch);
        }
        let c = &self.config;
        self.estimate(&self.global, y, by, wo_y, c.gather_k, c.max_radius, 0, depth, None, scratch)
    }

    /// Indirect light at a hit by final gathering: rays sampled from the BSDF's non-delta part,
    /// each reading the global map where it lands (after following mirrors and glass). Rays that
    /// reach a light are skipped: direct light and caustics account for those paths.
    #[allow(clippy::too_many_arguments)]
    fn final_gather(
        &self,
        scene: &Scene,
        hit: &Hit,
        bounce: u32,
        bsdf: &Bsdf,
        wo: Vec3,
        medium: u32,
        sampler: &mut Sampler,
        scratch: &mut Gathered,
        stats: &mut RayStats,
    ) -> Color {
        let n = self.config.gather_rays;
        let frame = crate::math::Frame::from_z(bsdf.normal());
        let lambertian = bsdf.lambert_albedo().is_some();
        let mut sum = Color::ZERO;
        for _ in 0..n {
            // A Lambertian surface samples the cosine directly (the same rays as always); any
            // other the non-delta part of its BSDF.
            let (wi, beta) = if lambertian {
                let wi = frame.to_world(cosine_hemisphere(sampler.next_2d()));
                (wi, bsdf.f(wo, wi, Transport::Radiance) * PI)
            } else {
                let Some(s) = bsdf.sample_smooth(wo, sampler.rng().uniform(), sampler.next_2d(), Transport::Radiance)
                else {
                    continue;
                };
                (s.wi, s.weight)
            };
            if beta == Color::ZERO {
                continue;
            }
            sum += beta * self.gather_ray(scene, hit, bounce, wi, medium, sampler.rng(), scratch, stats).l;
        }
        sum / n.max(1) as f32
    }

    /// One final-gather ray from `hit` along `wi` (leaving medium `medium`, in which the camera
    /// path arrived): followed through mirrors and glass (at most four bounces), then the
    /// radiance leaving the first other surface read from the global map, times the specular
    /// bounces' weights (and on through that surface's own mirror or glass part, if it has one);
    /// and the distance to the first surface it met. Through a medium it samples a free flight
    /// and, where it scatters, reads the volume map (every volume photon: the light samples at
    /// `hit` count none of that light).
    #[allow(clippy::too_many_arguments)]
    fn gather_ray(
        &self,
        scene: &Scene,
        hit: &Hit,
        bounce: u32,
        wi: Vec3,
        medium: u32,
        rng: &mut crate::sampling::Rng32,
        scratch: &mut Gathered,
        stats: &mut RayStats,
    ) -> GatherSample {
        let has_media = scene.has_media();
        let mut ray = hit.spawn(wi, self.config.ray_bias);
        ray.medium = scene.medium_after(hit, wi, medium);
        let mut beta = Color::ONE;
        let mut dist = f32::INFINITY;
        let mut l = Color::ZERO;
        let mut k = 0;
        // Crossings of `null` boundaries, which are no bounce, are bounded apart.
        let mut crossings = 0;
        while k < 4 {
            // y is bounce `bounce + 1 + k` of the camera path: photons may add what the depth
            // limit leaves.
            let Some(depth) = trace::photon_depth_limit(self.config.max_depth, bounce + 1 + k) else { break };
            stats.rays += 1;
            let found = scene.intersect(&ray, f32::INFINITY);
            if ray.medium != crate::geometry::NO_MEDIUM {
                let m = &scene.media[ray.medium as usize];
                let t_max = found.as_ref().map_or(f32::INFINITY, |h| h.t);
                let (u_channel, u) = (rng.uniform(), rng.uniform());
                // Final gathering is RGB in either mode (the photon maps', the RGB BSDF's light).
                let ms = m.sample_distance(&ray, t_max, beta, u_channel, u, rng, None);
                if ms.scattered {
                    if k == 0 {
                        dist = ms.t;
                    }
                    let est = self.volume_estimate(
                        scene,
                        m.phase(),
                        ray.at(ms.t),
                        -ray.d,
                        depth,
                        true,
                        rng.uniform2(),
                        scratch,
                    );
                    l += beta * ms.tr_over_pdf * est;
                    break;
                }
                beta *= ms.weight;
                if beta == Color::ZERO || !beta.is_finite() {
                    break;
                }
            }
            let Some(y) = found else { break };
            if k == 0 {
                dist = y.t * ray.d.length();
            }
            let wo_y = -ray.d;
            let by = scene.bsdf(&y, wo_y);
            // Emission is direct light or a caustic; what a reflecting emitter reflects is not.
            if by.is_black() {
                break;
            }
            if has_media && by.is_invisible() {
                crossings += 1;
                if crossings > crate::integrator::lighting::MAX_CROSSINGS {
                    break;
                }
                let next = scene.medium_after(&y, ray.d, ray.medium);
                ray = y.spawn(ray.d, self.config.ray_bias);
                ray.medium = next;
                continue;
            }
            k += 1;
            let wi_y = if by.is_specular_only() {
                let Some(s) = by.sample(wo_y, rng.uniform(), rng.uniform2(), Transport::Radiance) else { break };
                beta *= s.weight;
                s.wi
            } else {
                l += beta * self.radiance_at_gather_hit(&y, &by, wo_y, depth, scratch);
                // The mirror or glass part of a mixed material reflects more indirect light.
                if !by.has_delta() {
                    break;
                }
                let Some(s) = by.sample_delta(wo_y, rng.uniform(), rng.uniform2(), Transport::Radiance) else { break };
                beta *= s.weight;
                s.wi
            };
            let next = scene.medium_after(&y, wi_y, ray.medium);
            ray = y.spawn(wi_y, self.config.ray_bias);
            ray.medium = next;
        }
        GatherSample { l, dist }
    }

    /// Indirect light at a hit: interpolated from the irradiance cache where a record reaches a
    /// Lambertian surface, else by a final gather. The cache is read only with `use_cache`: at
    /// points a camera path reached through mirrors and glass alone, where records are made.
    /// After a glossy bounce the path may land anywhere (under a rough glass sphere, say), where
    /// records sized by the pixel footprint seen straight from the camera do not apply.
    #[allow(clippy::too_many_arguments)]
    fn indirect(
        &self,
        scene: &Scene,
        hit: &Hit,
        bounce: u32,
        bsdf: &Bsdf,
        wo: Vec3,
        medium: u32,
        use_cache: bool,
        sampler: &mut Sampler,
        scratch: &mut Gathered,
        stats: &mut RayStats,
    ) -> Color {
        if use_cache
            && !self.cache.is_empty()
            && let Some(albedo) = bsdf.lambert_albedo()
            && let Some(e) = self.cache.lookup(hit.p, bsdf.normal(), bounce)
        {
            return albedo * e * std::f32::consts::FRAC_1_PI;
        }
        self.final_gather(scene, hit, bounce, bsdf, wo, medium, sampler, scratch, stats)
    }
}

/// Squared radius of the disc a density estimate divides by: the distance of the k-th nearest
/// photon when `k` were found, the whole search radius when fewer were. Where photons are sparse
/// (far out on a floor plane) the distance of the farthest of a few found photons would make
/// the estimate far too large (with one photon its expectation is infinite); the photons within
/// a fixed disc estimate its flux without bias.
#[inline]
fn disc_radius2(found: usize, k: usize, r2: f32, max_r: f32) -> f32 {
    if found < k { max_r * max_r } else { r2 }
}

impl RayIntegrator for PhotonIntegrator {
    type Scratch = Gathered;

    fn radiance(
        &self,
        scene: &Scene,
        ray: &Ray,
        sampler: &mut Sampler,
        scratch: &mut Gathered,
        stats: &mut RayStats,
    ) -> Layers {
        let mut layers = [Color::ZERO; 4];
        let c = &self.config;
        let has_media = scene.has_media();
        let mut ray = *ray;
        if ray.medium == crate::geometry::NO_MEDIUM {
            ray.medium = scene.camera_medium;
        }
        // In spectral mode the wavelengths take the first dimension after the camera's; the
        // light found on the way is spectral (`layers`), the photon estimates RGB (`rgb`).
        let wl = c.spectral.then(|| Wavelengths::sample(sampler.next_1d()));
        let mut walk = CameraWalk::new(ray, Color::ONE).with_march(media::MARCH_STEPS).with_wavelengths(wl);
        let mut rgb = [Color::ZERO; 4];
        let mut slot = VertexSlot::default();
        loop {
            let direct = |hit: &Hit,
                          bsdf: &Bsdf,
                          wo: Vec3,
                          medium,
                          wl: Option<&Wavelengths>,
                          sampler: &mut Sampler,
                          stats: &mut RayStats| {
                if has_media {
                    self.direct_through_media(scene, hit, bsdf, wo, medium, sampler.rng(), wl, stats)
                } else {
                    self.lights.estimate(scene, hit, bsdf, wo, c.ray_bias, sampler.rng(), wl, stats)
                }
            };
            let add = |k: usize, l: Color| layers[k] += l;
            let v = match walk.next_vertex(scene, c.max_depth, c.ray_bias, sampler, stats, add, direct, &mut slot) {
                Some(Stop::Surface(v)) => v,
                Some(Stop::Medium(m)) => {
                    // Light scattered in a medium goes where SPPM puts it (`sppm::media`).
                    let (single, multiple) =
                        self.medium_radiance(scene, &m, walk.wavelengths(), sampler.rng(), scratch, stats);
                    let k = walk.layer.other_photons();
                    if c.spectral {
                        // The photons' estimate is RGB: weighted by the path's filter as a colour.
                        layers[k] += walk.beta * single;
                        rgb[k] += walk.rgb_of(walk.beta * m.tr_over_pdf) * multiple;
                    } else {
                        layers[k] += walk.beta * (single + m.tr_over_pdf * multiple);
                    }
                    if m.marching {
                        continue;
                    }
                    break;
                }
                None => break,
            };
            let (hit, wo, layer) = (v.hit, v.wo, walk.layer);
            // The estimates read the RGB BSDF and weight by the path's filter as a colour; in RGB
            // mode these are the vertex's BSDF and the throughput themselves.
            let rgb_bsdf;
            let (bsdf, beta) = if c.spectral {
                rgb_bsdf = scene.bsdf(hit, wo);
                (&rgb_bsdf, walk.beta_rgb())
            } else {
                (v.bsdf, walk.beta)
            };
            let out = if c.spectral { &mut rgb } else { &mut layers };
            let photon_depth = trace::photon_depth_limit(c.max_depth, v.bounce).unwrap_or(0);
            out[layer.caustic_photons()] += beta
                * self.estimate(
                    &self.caustic,
                    hit,
                    bsdf,
                    wo,
                    c.caustic_k,
                    c.caustic_radius,
                    0,
                    photon_depth,
                    Some(c.cone_k),
                    scratch,
                );
            let indirect = if c.gather_rays == 0 {
                self.estimate(
                    &self.global,
                    hit,
                    bsdf,
                    wo,
                    c.gather_k,
                    c.max_radius,
                    trace::DIRECT | trace::CAUSTIC,
                    photon_depth,
                    None,
                    scratch,
                )
            } else {
                // The cache's records (made where camera paths through mirrors and glass land)
                // are not read after a glossy bounce (see `indirect`).
                let medium = walk.medium();
                self.indirect(scene, hit, v.bounce, bsdf, wo, medium, !walk.glossy_prefix, sampler, scratch, stats)
            };
            out[layer.other_photons()] += beta * indirect;
            // The mirror or glass part of a mixed material, or a mask's transparent part.
            if !v.bsdf.has_delta() || v.last {
                break;
            }
            let Some(s) = v.bsdf.sample_delta(wo, sampler.next_1d(), sampler.next_2d(), Transport::Radiance) else {
                break;
            };
            walk.follow_delta(scene, hit, &s, c.ray_bias);
        }
        if c.spectral {
            for (l, r) in layers.iter_mut().zip(rgb) {
                *l = walk.to_rgb(*l) + r;
            }
        }
        layers
    }
}

#[cfg(test)]
mod tests;
