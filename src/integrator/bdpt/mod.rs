//! Bidirectional path tracing (Veach and Guibas 1995, Veach 1997 ch. 10; Lafortune and Willems
//! 1993): each camera sample traces a camera subpath and a light subpath, and joins them by
//! every technique: the camera path hitting an emitter (s = 0), a light sample at each camera
//! vertex (s = 1), each camera vertex connected to each light vertex (s, t >= 2), and each light
//! vertex connected to the camera (t = 1, light tracing, splatted on the pixel it lands in). The
//! techniques are combined by multiple importance sampling with the power heuristic, the weights
//! computed recursively along the subpaths (`mis`, after Georgiev's technical report on vertex
//! connection and merging and SmallVCM), which `integrator::vcm` extends with merging.
//!
//! What each technique can do: delta lights (points, spots, directional) are reached only by
//! light samples and light paths; mirrors and glass only by sampling (a connection needs a
//! non-delta part at both ends); lights at infinity emit through their `PhotonDisk`, so a light
//! path's density covers the scene and the planes within `PLANE_REACH`, and the techniques that
//! need it weigh nothing beyond (the camera paths and light samples carry that light alone).
//! Caustics of point lights seen directly come from light tracing; seen through a mirror or glass
//! (L S+ D S+ E) no technique of bidirectional path tracing can make them (vertex merging can).
//! Paths that only the camera can sample, such as a small light's highlight on glass, are made
//! less noisy by splitting camera paths at glass: both the reflection and the refraction are
//! traced at the first few glass vertices (`subpath::GLASS_SPLITS`), as in VCM.
//!
//! Determinism and splats: sample index i of image pixel k traces its camera path with the
//! pixel's sampler (the same camera rays as the path tracer) and its light path with a stream
//! seeded by (seed, film pixel, i). Camera paths' light (`SplatFilm::add_pixel`) and light
//! tracing's splats (`SplatFilm::add`) are summed exactly, so the image is the same for any
//! thread count, pass split, resume and farm shard, as the light tracer's. Each sample index
//! traces as many light paths as the image has pixels: a crop traces fewer, and its light paths
//! count for the full film's (`Context::light_scale`).
//!
//! Spectral mode: each camera sample draws its wavelengths from the pixel sampler's first
//! dimension after the camera's (as the path tracer does) and both its subpaths carry them
//! (`Context::wl`), so its connections join light and camera at one set of wavelengths; a full
//! path through dispersive glass keeps the hero alone, its factor counted once whichever subpath
//! crossed the glass (`strategy`'s header). Camera paths' light and the splats reach the film as
//! linear sRGB.
//!
//! Layers (`integrator::layers`) follow the full path from the camera: the camera subpath's
//! sampled lobes, a non-delta bounce where the subpaths join, then the light subpath's bounces.

pub mod mis;
pub mod strategy;
pub mod subpath;

#[cfg(test)]
mod tests;

use crate::film::Film;
use crate::film::splat::{DRAIN_PATHS, MAX_SPLATS_PER_PATH, SplatFilm};
use crate::material::bsdf::Bsdf;
use crate::render::{Driver, PassOutcome, RayStats, RenderControl, RenderOutput, RenderSettings};
use crate::sampling::{Rng32, hash_seed};
use crate::scene::Scene;
use crate::spectrum::Wavelengths;
use rayon::prelude::*;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};
use strategy::{Context, LightVertex};

/// Camera samples (each with its light path) traced together by one worker.
const CHUNK: u64 = 256;

/// The stream light subpaths draw from (kept apart from the camera's, the light tracer's and
/// the photons').
const LIGHT_STREAM: u64 = 0x4244_5054_4c49;

// A sample splats once per light vertex (at most one per bounce the depth limit allows) and adds
// its camera path's light once.
const _: () = assert!(crate::scene::desc::MAX_DEPTH_LIMIT as u64 + 2 <= MAX_SPLATS_PER_PATH);

/// The bidirectional path tracer.
pub struct Bdpt {
    /// Longest path in bounces (0 = emitters only, 1 = direct light only), as the path tracer's.
    pub max_depth: u32,
    /// The offset rays leave surfaces with (`IntegratorDesc::ray_bias`).
    pub ray_bias: f32,
    /// Spectral mode (`crate::spectrum::lanes`); RGB otherwise.
    pub spectral: bool,
}

/// Bytes a bidirectional render of `pixels` pixels needs beside its film: the splat film and the
/// film a pass accumulates into (subpaths live in per-worker buffers of a few kilobytes).
pub fn estimated_bytes(pixels: u64, layers: bool) -> u64 {
    super::light::estimated_bytes(pixels, layers)
}

/// A worker's light subpath: its vertices and their BSDFs, reused from sample to sample.
#[derive(Default)]
pub struct LightPathBuffer<'a> {
    pub vertices: Vec<LightVertex>,
    pub bsdfs: Vec<Bsdf<'a>>,
}

impl LightPathBuffer<'_> {
    pub fn clear(&mut self) {
        self.vertices.clear();
        self.bsdfs.clear();
    }
}

impl Bdpt {
    /// Renders sample indices up to `settings.spp` (or until the time limit) after those `film`
    /// holds (from `settings.first_sample`).
    pub fn render(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        control: &RenderControl,
        film: Film,
    ) -> RenderOutput {
        let (film, stats) = crate::integrator::render_splatted(
            settings,
            control,
            film,
            ("bdpt", "samples per pixel"),
            |driver, splats, film, range| self.pass(scene, driver, splats, film, range),
        );
        RenderOutput::from_film(film, stats)
    }

    /// Takes sample indices `range` of every pixel and adds them to `film`; an interrupted pass
    /// adds nothing.
    fn pass(
        &self,
        scene: &Scene,
        driver: &Driver,
        splats: &SplatFilm,
        film: &mut Film,
        range: Range<u32>,
    ) -> PassOutcome {
        let settings = driver.settings;
        let pixels = settings.pixels();
        let ctx = Context::new(scene, self.max_depth, self.ray_bias, pixels, None);
        let (start, end) = (range.start as u64 * pixels, range.end as u64 * pixels);
        let mut pass = Film::new(film.width, film.height, film.has_layers());
        let interrupted = AtomicBool::new(false);
        let mut batch = start;
        while batch < end {
            let batch_end = (batch + DRAIN_PATHS).min(end);
            let chunks = (batch_end - batch).div_ceil(CHUNK);
            (0..chunks).into_par_iter().for_each(|c| {
                if driver.cancelled() {
                    interrupted.store(true, Ordering::Relaxed);
                    return;
                }
                let from = batch + c * CHUNK;
                let to = (from + CHUNK).min(batch_end);
                let mut stats = RayStats::default();
                let mut buffer = LightPathBuffer::default();
                let mut nonfinite = 0;
                for sample in from..to {
                    let (index, k) = ((sample / pixels) as u32, sample % pixels);
                    let (x, y) = ((k % settings.width as u64) as u32, (k / settings.width as u64) as u32);
                    nonfinite += self.sample(&ctx, settings, (x, y), index, splats, &mut buffer, &mut stats);
                }
                driver.record(&stats, nonfinite, to - from);
            });
            if interrupted.load(Ordering::Relaxed) {
                splats.clear();
                return PassOutcome::Interrupted { taken: 0 };
            }
            splats.drain_into(&mut pass);
            batch = batch_end;
        }
        for t in &mut pass.tiles {
            t.count.iter_mut().for_each(|c| *c = range.len() as u32);
        }
        film.add(&pass);
        PassOutcome::Complete
    }

    /// Sample `index` of image pixel `(x, y)`: its light subpath (splatting its connections to
    /// the camera) and its camera subpath (added to the pixel). Returns the number of values
    /// left out as not finite.
    #[allow(clippy::too_many_arguments)]
    fn sample<'a>(
        &self,
        ctx: &Context<'a>,
        settings: &RenderSettings,
        (x, y): (u32, u32),
        index: u32,
        splats: &SplatFilm,
        buffer: &mut LightPathBuffer<'a>,
        stats: &mut RayStats,
    ) -> u64 {
        let scene = ctx.scene;
        let (mut sampler, ray, weight) = settings.camera_sample(scene, x, y, index);
        let spectral;
        let ctx = if self.spectral {
            spectral = Context { wl: Some(Wavelengths::sample(sampler.next_1d())), ..*ctx };
            &spectral
        } else {
            ctx
        };
        let film_pixel = (y + settings.origin.1) as u64 * scene.camera.width as u64 + (x + settings.origin.0) as u64;
        let mut rng = Rng32::new(hash_seed(&[settings.seed, LIGHT_STREAM, film_pixel, index as u64]));
        let mut bad = 0;
        buffer.clear();
        subpath::trace_light_path(ctx, &mut rng, stats, |v, bsdf, rng, stats| {
            if let Some((raster, layers)) = strategy::connect_to_camera(ctx, v, bsdf, rng.uniform2(), stats)
                && !splats.add(raster, &layers)
            {
                bad += 1;
            }
            buffer.vertices.push(*v);
            buffer.bsdfs.push(*bsdf);
        });
        let mut layers =
            subpath::trace_camera_path(ctx, &mut sampler, ray, &buffer.vertices, &buffer.bsdfs, stats, |_, _, _| {});
        if weight != 1.0 {
            layers = layers.map(|c| c * weight);
        }
        if !splats.add_pixel(x, y, &layers) {
            bad += 1;
        }
        bad
    }
}
