//! Filling the irradiance cache before rendering, in a fixed order so that the image never
//! depends on threads or timing.
//!
//! The camera's first diffuse hits are visited through pixel centres on grids of decreasing
//! stride (16, 8, 4, 2, 1 pixels: each level the pixels the coarser ones did not take), over the
//! whole film whatever the crop, so a crop or a farm shard builds the same cache. On each level,
//! in parallel, every hit that no earlier record reaches (error below `COVER * a`) gets a record
//! from a stratified gather seeded by its pixel; the new records are then accepted in pixel
//! order, dropping those an earlier one of the same level already reaches. A record's gather
//! uses the same rays as the per-sample final gather (`gather_ray`), so the cache interpolates
//! exactly what the gather estimates.

use super::PhotonIntegrator;
use super::irradiance_cache::{COVER, GatherSample, IrradianceCache, Record, make_record, strata, stratum_direction};
use crate::geometry::Hit;
use crate::material::bsdf::Bsdf;
use crate::material::bxdf::Transport;
use crate::math::{Color, Frame, Vec2};
use crate::photon::Gathered;
use crate::photon::trace::Watch;
use crate::progress::Display;
use crate::render::RayStats;
use crate::sampling::{Rng32, hash_seed};
use crate::scene::Scene;
use rayon::prelude::*;
use std::sync::atomic::AtomicBool;

/// Strides of the candidate grids, coarse to fine.
const STRIDES: [u32; 5] = [16, 8, 4, 2, 1];
/// A record's reach (a R) is kept between these many pixel footprints at its camera distance d
/// (no finer than the pixels: corners would otherwise take a record per pixel; no coarser than
/// about a sixth of a 400-pixel image), and each bound at most these fractions of d: on a small
/// image a pixel spans a wide angle, and a record reaching further than a fraction of its own
/// distance would reach points much nearer the camera (a far part of a floor plane, seeing
/// nothing, would darken the floor under the objects).
const MIN_REACH_PX: f32 = 1.5;
const MAX_REACH_PX: f32 = 64.0;
const MIN_REACH_DIST: f32 = 0.05;
const MAX_REACH_DIST: f32 = 0.1;

/// A camera path's first diffuse hit.
pub(super) struct Candidate<'a> {
    pub hit: Hit,
    pub bsdf: Bsdf<'a>,
    /// Length of the camera path to it (through mirrors and glass).
    pub dist: f32,
    /// Its bounce in the camera path (1 for the first surface).
    pub bounce: u32,
    /// The medium the camera path arrived in.
    pub medium: u32,
}

impl PhotonIntegrator {
    /// The camera path through the centre of film pixel (x, y), followed through mirrors and
    /// glass as `radiance` follows it, to its first surface with a Lambertian BSDF that will be
    /// gathered at; `None` when it ends elsewhere.
    pub(super) fn first_diffuse<'s>(&self, scene: &'s Scene, x: u32, y: u32, rng: &mut Rng32) -> Option<Candidate<'s>> {
        let mut ray = scene.camera.generate_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5), Vec2::splat(0.5));
        if ray.medium == crate::geometry::NO_MEDIUM {
            ray.medium = scene.camera_medium;
        }
        let mut dist = 0.0;
        let mut depth = 0;
        // Media are passed through (where records go is all that is chosen here); their
        // `null` boundaries are no bounce.
        let mut crossings = 0;
        loop {
            let hit = scene.intersect(&ray, f32::INFINITY)?;
            dist += hit.t * ray.d.length();
            let wo = -ray.d;
            let bsdf = scene.bsdf(&hit, wo);
            if scene.has_media() && bsdf.is_invisible() {
                crossings += 1;
                if crossings > crate::integrator::lighting::MAX_CROSSINGS {
                    return None;
                }
                let medium = scene.medium_after(&hit, ray.d, ray.medium);
                ray = hit.spawn(ray.d, self.config.ray_bias);
                ray.medium = medium;
                continue;
            }
            if bsdf.is_black() || depth >= self.config.max_depth {
                return None;
            }
            let last = depth + 1 >= self.config.max_depth;
            if bsdf.is_specular_only() {
                if last {
                    return None;
                }
                let s = bsdf.sample(wo, rng.uniform(), rng.uniform2(), Transport::Radiance)?;
                let medium = scene.medium_after(&hit, s.wi, ray.medium);
                ray = hit.spawn(s.wi, self.config.ray_bias);
                ray.medium = medium;
                depth += 1;
                continue;
            }
            let (bounce, medium) = (depth + 1, ray.medium);
            return bsdf.lambert_albedo().is_some().then_some(Candidate { hit, bsdf, dist, bounce, medium });
        }
    }

    /// A record at `c` from a stratified gather of about `cache_rays` rays.
    pub(super) fn record_at(&self, scene: &Scene, c: &Candidate, rng: &mut Rng32, scratch: &mut Gathered) -> Record {
        let (m, n) = strata(self.config.cache_rays);
        let frame = Frame::from_z(c.bsdf.normal());
        let mut samples = Vec::with_capacity(m * n);
        let mut dirs = Vec::with_capacity(m * n);
        let mut stats = RayStats::default();
        for j in 0..m {
            for k in 0..n {
                let d = stratum_direction(j, k, m, n, (rng.uniform(), rng.uniform()));
                let wi = frame.to_world(d);
                dirs.push(d);
                // Below the geometric surface (shading normals): nothing arrives, as in the gather.
                let below = c.bsdf.f(frame.z, wi, Transport::Radiance) == Color::ZERO;
                samples.push(if below {
                    GatherSample { l: Color::ZERO, dist: f32::INFINITY }
                } else {
                    self.gather_ray(scene, &c.hit, c.bounce, wi, c.medium, rng, scratch, &mut stats)
                });
            }
        }
        let a = self.config.cache_error;
        let fp = scene.camera.footprint(c.dist);
        let lo = (MIN_REACH_PX * fp).min(MIN_REACH_DIST * c.dist);
        let hi = (MAX_REACH_PX * fp).min(MAX_REACH_DIST * c.dist);
        let range = (lo / a, hi / a);
        Record { bounce: c.bounce, ..make_record(c.hit.p, &frame, m, n, &samples, &dirs, range) }
    }

    /// Fills the irradiance cache (see the module docs); `None` when cancelled.
    pub(super) fn fill_cache(&self, scene: &Scene, cancel: &AtomicBool, progress: &Display) -> Option<IrradianceCache> {
        let (w, h) = (scene.camera.width, scene.camera.height);
        let a = self.config.cache_error;
        let seed = self.config.seed;
        // Progress counts each grid level alike: the coarse levels have few candidates, but
        // nearly each makes a record (hundreds of rays), and the finest has most of the pixels,
        // nearly all of them covered already (one camera ray each). Counted in pixels, the bar
        // stood at a few percent with most of the time gone.
        const LEVEL_UNITS: u64 = 1 << 20;
        let bar = progress.phase("cache", STRIDES.len() as u64 * LEVEL_UNITS);
        let watch = Watch { cancel, progress: Some(&bar) };
        let mut records: Vec<Record> = Vec::new();
        let mut cache = IrradianceCache::empty(a);
        for (level, &stride) in STRIDES.iter().enumerate() {
            let coarser = if level == 0 { u32::MAX } else { STRIDES[level - 1] };
            let cands: Vec<(u32, u32)> = (0..h)
                .step_by(stride as usize)
                .flat_map(|y| (0..w).step_by(stride as usize).map(move |x| (x, y)))
                .filter(|&(x, y)| level == 0 || x % coarser != 0 || y % coarser != 0)
                .collect();
            let made: Vec<Option<Record>> = cands
                .par_chunks(64)
                .flat_map_iter(|chunk| {
                    let mut scratch = Gathered::new(self.config.gather_k);
                    let out: Vec<Option<Record>> = chunk
                        .iter()
                        .map(|&(x, y)| {
                            if watch.cancelled() {
                                return None;
                            }
                            let mut rng = Rng32::new(hash_seed(&[seed, 0x1c_ac4e, u64::from(x), u64::from(y)]));
                            let c = self.first_diffuse(scene, x, y, &mut rng)?;
                            if cache.covers(c.hit.p, c.bsdf.normal(), COVER * a, c.bounce) {
                                return None;
                            }
                            Some(self.record_at(scene, &c, &mut rng, &mut scratch))
                        })
                        .collect();
                    watch.advance(chunk.len() as u64 * LEVEL_UNITS / cands.len() as u64);
                    out
                })
                .collect();
            if watch.cancelled() {
                return None;
            }
            // Accept in pixel order, skipping what this level's earlier records already reach.
            let first_new = records.len();
            for rec in made.into_iter().flatten() {
                let reached = records[first_new..].iter().any(|o| o.error(rec.p, rec.n).is_some_and(|e| e < COVER * a));
                if !reached {
                    records.push(rec);
                }
            }
            cache = IrradianceCache::new(records.clone(), a);
        }
        bar.finish(&format!("{} irradiance-cache records", records.len()));
        Some(cache)
    }

    /// The cache as filled (for tests).
    #[cfg(test)]
    pub(super) fn cache(&self) -> &IrradianceCache {
        &self.cache
    }
}
