//! Light tracing (Veach 1997 sec. 10.2, the "t = 1" strategy of bidirectional path tracing;
//! Mitsuba 3's `ptracer`, pbrt-v4's `LightPathIntegrator`): paths start at the lights and every
//! vertex with a non-delta part is connected to the camera (`Camera::sample_wi`), its light
//! splatted on the pixel the connection lands in (`film::splat`). Points of area lights and
//! directions of the environment are connected to the camera too, so emitters seen directly
//! appear; delta lights (points, spots, directional) cannot be seen, as in Mitsuba. What the
//! camera sees in mirrors and glass needs a delta camera vertex, which no light path can
//! connect to: those pixels stay dark (the path tracer renders them).
//!
//! One sample index is one light path per pixel of the full film (crop windows included), so a
//! pixel's value is the sum of the contributions that landed in it over the samples per pixel
//! (the camera's importance is normalised over the full film). Light path `k` of index `i` draws
//! its numbers from a stream seeded by (seed, i x pixels + k), and the splats are summed exactly,
//! so the image is the same for any thread count and any split into passes, shards and resumes.
//!
//! Spectral mode (`crate::spectrum::lanes`): each light path draws its own wavelengths first
//! from its stream, lifts the light's emission to them and the BSDFs it meets (keeping only the
//! hero past dispersive glass, as photons do: `photon::trace`), and each splat's lanes are
//! turned into linear sRGB through the CIE functions before they reach the film, as the path
//! tracer's samples are.
//!
//! Layers (`integrator::layers`): a connection from the first surface light reaches is `DIRECT`,
//! one from a surface reached through mirrors and glass only `CAUSTIC`, any other `INDIRECT`;
//! emitters seen directly are `DIRECT`. Nothing is `SPECULAR` (see above).

use super::lighting::visibility;
use crate::camera::Projection;
use crate::film::splat::{DRAIN_PATHS, MAX_SPLATS_PER_PATH, SplatFilm};
use crate::film::{CAUSTIC, DIRECT, Film, INDIRECT, Layers};
use crate::geometry::RayOrigin;
use crate::light::Light;
use crate::material::bxdf::Transport;
use crate::math::{Color, Vec3};
use crate::render::{Driver, PassOutcome, RayStats, RenderControl, RenderOutput, RenderSettings};
use crate::sampling::{Rng32, hash_seed};
use crate::scene::Scene;
use crate::spectrum::Wavelengths;
use rayon::prelude::*;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};

/// Light paths traced together by one worker.
const CHUNK: u64 = 1024;

/// The stream light paths draw from (kept apart from the camera's and the photons').
const LIGHT_STREAM: u64 = 0x004c_4947_4854;

// A path splats at its start and once per vertex, at most one per bounce the depth limit allows.
const _: () = assert!(crate::scene::desc::MAX_DEPTH_LIMIT as u64 + 2 <= MAX_SPLATS_PER_PATH);

pub struct LightTracer {
    /// Longest path in bounces (0 = emitters only, 1 = direct light only), as the path tracer's.
    pub max_depth: u32,
    /// The offset rays leave surfaces with (`IntegratorDesc::ray_bias`).
    pub ray_bias: f32,
    /// Spectral mode (`crate::spectrum::lanes`); RGB otherwise.
    pub spectral: bool,
}

/// Bytes a light-traced render of `pixels` pixels needs beside its film: the splat film and the
/// film a pass accumulates into.
pub fn estimated_bytes(pixels: u64, layers: bool) -> u64 {
    let film = crate::film::BYTES_PER_PIXEL + if layers { crate::film::LAYER_BYTES_PER_PIXEL } else { 0 };
    SplatFilm::bytes(pixels, layers) + pixels * film
}

impl LightTracer {
    /// Renders sample indices up to `settings.spp` (or until the time limit) after those `film`
    /// holds (from `settings.first_sample`).
    pub fn render(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        control: &RenderControl,
        film: Film,
    ) -> RenderOutput {
        let (film, stats) = super::render_splatted(
            settings,
            control,
            film,
            ("light", "samples per pixel"),
            |driver, splats, film, range| self.pass(scene, driver, splats, film, range),
        );
        RenderOutput::from_film(film, stats)
    }

    /// Traces the light paths of sample indices `range` and adds them to `film`, every pixel
    /// gaining `range.len()` samples; an interrupted pass adds nothing.
    fn pass(
        &self,
        scene: &Scene,
        driver: &Driver,
        splats: &SplatFilm,
        film: &mut Film,
        range: Range<u32>,
    ) -> PassOutcome {
        let settings = driver.settings;
        let cam = &scene.camera;
        let per_index = cam.width as u64 * cam.height as u64;
        let (start, end) = (range.start as u64 * per_index, range.end as u64 * per_index);
        // The pass's sums gather here and join the film only when the pass is whole.
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
                let mut nonfinite = 0;
                for path in from..to {
                    nonfinite += self.trace(scene, settings.seed, path, splats, &mut stats);
                }
                // Progress in pixels' worth of samples: one pixel's for each of its paths.
                let units = (to - from) * settings.pixels() / per_index.max(1);
                driver.record(&stats, nonfinite, units);
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

    /// Traces light path `index` and splats what it shows the camera; returns the number of
    /// contributions left out as not finite (an infinite light path contributes nothing).
    fn trace(&self, scene: &Scene, seed: u64, index: u64, splats: &SplatFilm, stats: &mut RayStats) -> u64 {
        let mut rng = Rng32::new(hash_seed(&[seed, LIGHT_STREAM, index]));
        // Spectral paths draw their wavelengths before anything else; RGB paths draw nothing more.
        let mut wl = self.spectral.then(|| Wavelengths::sample(rng.uniform()));
        // The lanes' wavelengths as the film reads them (termination does not change them).
        let film_wl = wl;
        let mut bad = 0;
        let mut splat = |raster, layers: &Layers| {
            let converted;
            let layers = match &film_wl {
                Some(wl) => {
                    converted = layers.map(|c| wl.to_srgb(c));
                    &converted
                }
                None => layers,
            };
            if !splats.add(raster, layers) {
                bad += 1;
            }
        };
        let Some((li, p_pick)) = scene.light_picker.pick(rng.uniform()) else { return 0 };
        let light = &scene.lights[li];
        // The light itself, seen directly.
        self.connect_emitter(scene, li, p_pick, wl.as_ref(), &mut rng, stats, &mut splat);
        let Some(e) = light.sample_le(rng.uniform2(), rng.uniform2(), scene.textures()) else { return bad };
        let mut beta = e.flux / p_pick;
        if wl.is_some() {
            beta = scene.emission_in(beta, li as u32, wl.as_ref());
        }
        if !(beta.max_element() > 0.0) || !beta.is_finite() {
            return bad;
        }
        let start = beta.max_element();
        let mut ray = if light.is_infinite() { scene.photon_entry(e.ray) } else { e.ray };
        // Scattering events so far, and whether all of them were delta (mirrors, glass).
        let mut bounces = 0u32;
        let mut delta_only = true;
        loop {
            stats.rays += 1;
            let Some(hit) = scene.intersect(&ray, f32::INFINITY) else { break };
            let wo = -ray.d;
            let bsdf = scene.bsdf_for(&hit, wo, wl.as_mut(), &mut beta);
            if bsdf.is_black() {
                break;
            }
            // Connected to the camera, the vertex is one more bounce of the whole path.
            if bounces + 1 > self.max_depth {
                break;
            }
            if bsdf.has_smooth()
                && let Some(cw) = scene.camera.sample_wi(hit.p, rng.uniform2())
            {
                let f = bsdf.f(wo, cw.wi, Transport::Importance);
                if f != Color::ZERO {
                    let weight = bsdf.shading_normal_correction(wo, cw.wi) * cw.wi.dot(bsdf.normal()).abs();
                    let c = beta * f * (weight * cw.importance / cw.pdf);
                    if c != Color::ZERO && visibility(scene, hit.origin(), cw.wi, cw.dist, self.ray_bias, stats) > 0.0 {
                        let layer = if bounces == 0 {
                            DIRECT
                        } else if delta_only {
                            CAUSTIC
                        } else {
                            INDIRECT
                        };
                        let mut layers = [Color::ZERO; 4];
                        layers[layer] = c;
                        splat(cw.raster, &layers);
                    }
                }
            }
            // A further vertex would be a bounce more than the limit allows.
            if bounces + 2 > self.max_depth {
                break;
            }
            let Some(s) = bsdf.sample(wo, rng.uniform(), rng.uniform2(), Transport::Importance) else { break };
            beta *= s.weight * bsdf.shading_normal_correction(wo, s.wi);
            bounces += 1;
            delta_only &= s.flags.is_specular();
            if bounces >= 3 {
                // Russian roulette on the throughput relative to the light's.
                let survive = (beta.max_element() / start).min(0.95);
                if !(rng.uniform() < survive) {
                    break;
                }
                beta /= survive;
            }
            if !beta.is_finite() || beta == Color::ZERO {
                break;
            }
            ray = hit.spawn(s.wi, self.ray_bias);
        }
        bad
    }

    /// Connects a point of `light` (chosen with probability `p_pick`) to the camera: a point
    /// by area on an area light, a direction of the environment (its radiance seen from the
    /// camera as from infinitely far), nothing for delta lights. Mitsuba's
    /// `sample_visible_emitters`. In spectral mode (`wl`) the emission is lifted to the path's
    /// wavelengths.
    #[allow(clippy::too_many_arguments)]
    fn connect_emitter(
        &self,
        scene: &Scene,
        li: usize,
        p_pick: f32,
        wl: Option<&Wavelengths>,
        rng: &mut Rng32,
        stats: &mut RayStats,
        splat: &mut impl FnMut(crate::math::Vec2, &Layers),
    ) {
        let light = &scene.lights[li];
        let (u_light, u_lens) = (rng.uniform2(), rng.uniform2());
        let textures = scene.textures();
        let (le, raster) = match light {
            Light::Area { shape, .. } => {
                let Some(s) = shape.sample_area(u_light) else { return };
                let Some(cw) = scene.camera.sample_wi(s.p, u_lens) else { return };
                let cos = s.n.dot(cw.wi);
                if !(cos > 0.0) {
                    return;
                }
                let le = light.emitted(s.n, cw.wi, || s.uv, textures);
                let origin = RayOrigin { p: s.p, p_error: s.p_error, ng: s.n };
                if le == Color::ZERO || visibility(scene, origin, cw.wi, cw.dist, self.ray_bias, stats) == 0.0 {
                    return;
                }
                // Area density 1 / area, the lens's solid-angle density seen from the point.
                (
                    scene.emission_in(le, li as u32, wl) * (cos * shape.area() * cw.importance / (cw.pdf * p_pick)),
                    cw.raster,
                )
            }
            // An orthographic camera sees the environment in one direction only, which a sampled
            // direction never is.
            Light::Environment(env) if scene.camera.projection == Projection::Perspective => {
                let Some((wi, radiance, pdf)) = env.sample(u_light) else { return };
                if !(pdf > 0.0) {
                    return;
                }
                // A point far beyond the scene in the sampled direction, as the camera sees it.
                let (center, radius) = scene.bounds().bounding_sphere();
                let reach = if radius.is_finite() { radius + (scene.camera.eye - center).length() } else { 1.0 };
                let dist = 1e3 * reach.max(1.0);
                let far = scene.camera.eye + wi * dist;
                let Some(cw) = scene.camera.sample_wi(far, u_lens) else { return };
                let origin = RayOrigin { p: cw.p_lens, p_error: Vec3::ZERO, ng: wi };
                if visibility(scene, origin, wi, f32::INFINITY, 0.0, stats) == 0.0 {
                    return;
                }
                // Solid angle from the far point's area: dist^2, which the lens's density at
                // that distance divides out.
                (
                    scene.emission_in(radiance, li as u32, wl)
                        * (cw.importance * cw.dist * cw.dist / (cw.pdf * pdf * p_pick)),
                    cw.raster,
                )
            }
            Light::Environment(_)
            | Light::Point { .. }
            | Light::Spot(_)
            | Light::Projector(_)
            | Light::Directional { .. } => return,
        };
        let mut layers = [Color::ZERO; 4];
        layers[DIRECT] = le;
        splat(raster, &layers);
    }
}
