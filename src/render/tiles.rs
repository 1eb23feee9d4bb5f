//! Passes of camera samples for ray integrators: each pass brings every pixel up to a sample
//! index, tiles spread over all cores with rayon. The film's sums are exact, so the image is the
//! same for any thread count, any split into passes and any resumption of a saved film.

use super::driver::{Driver, PassOutcome};
use super::{RayIntegrator, RayStats, RenderControl, RenderOutput, RenderSettings};
use crate::film::{Film, Tile};
use crate::geometry::Ray;
use crate::sampling::Sampler;
use crate::scene::Scene;
use rayon::prelude::*;
use std::cell::RefCell;
use std::ops::Range;

/// Camera samples made together before they are traced (see `render_tile`).
const CAMERA_BATCH: usize = 4;

/// Renders `scene` with a ray integrator. Runs on the current rayon pool (the caller chooses the
/// thread count by installing a pool).
pub fn render_rays<I: RayIntegrator>(
    scene: &Scene,
    integrator: &I,
    settings: &RenderSettings,
    control: &RenderControl,
) -> RenderOutput {
    let film = settings.new_film();
    render_rays_from(scene, integrator, settings, control, film)
}

/// Continues a render whose film holds, in each pixel, the samples from `settings.first_sample`
/// up to its count (a checkpoint of an interrupted run): takes each pixel's remaining samples.
pub fn render_rays_from<I: RayIntegrator>(
    scene: &Scene,
    integrator: &I,
    settings: &RenderSettings,
    control: &RenderControl,
    film: Film,
) -> RenderOutput {
    let first = settings.first_sample.saturating_add(film.min_samples());
    // The film is shared between the passes (which write it) and checkpoints (which read it
    // between passes), one after the other on this thread.
    let film = RefCell::new(film);
    let mut driver = Driver::new(settings, control, "render", "samples per pixel", settings.pixels(), first);
    let mut stats = driver.run(
        |driver, range| render_pass(scene, integrator, driver, &mut film.borrow_mut(), range),
        |f| f(&film.borrow()),
    );
    let film = film.into_inner();
    stats.samples_per_pixel = film.min_samples();
    RenderOutput::from_film(film, stats)
}

/// Brings every pixel up to sample index `range.end`, tile by tile in parallel.
fn render_pass<I: RayIntegrator>(
    scene: &Scene,
    integrator: &I,
    driver: &Driver,
    film: &mut Film,
    range: Range<u32>,
) -> PassOutcome {
    let interrupted = std::sync::atomic::AtomicBool::new(false);
    film.tiles.par_iter_mut().for_each(|tile| {
        if driver.cancelled() {
            interrupted.store(true, std::sync::atomic::Ordering::Relaxed);
            return;
        }
        let mut stats = RayStats::default();
        let bad = render_tile(scene, integrator, driver.settings, tile, range.clone(), &mut stats);
        driver.record(&stats, bad, tile.width as u64 * tile.height as u64 * range.len() as u64);
    });
    if interrupted.into_inner() { PassOutcome::Interrupted { taken: 0 } } else { PassOutcome::Complete }
}

/// Renders the samples of every pixel of `tile` from the pixel's next index up to `range.end`
/// (the pass's range, unless a resumed film left the pixel further on). Returns the number of
/// non-finite samples (counted as black).
fn render_tile<I: RayIntegrator>(
    scene: &Scene,
    integrator: &I,
    settings: &RenderSettings,
    tile: &mut Tile,
    range: Range<u32>,
    stats: &mut RayStats,
) -> u64 {
    let mut bad = 0;
    let mut scratch = I::Scratch::default();
    // First-hit AOVs, when asked for: one more intersection per camera sample.
    let aovs = &settings.aovs;
    let first_hits = tile.aov_hits > 0;
    let mut values = [0.0f32; super::aov::MAX_FIRST_HIT_CHANNELS];
    for j in 0..tile.height {
        for i in 0..tile.width {
            let (x, y) = (tile.x0 + i, tile.y0 + j);
            let k = (j * tile.width + i) as usize;
            let next = settings.first_sample.saturating_add(tile.count[k]);
            let mut pixel = settings.pixel_sampler(x, y);
            let mut trace = |(mut sampler, ray, weight): (Sampler, Ray, f32)| {
                if first_hits {
                    aovs.first_hit_values(&super::aov::first_hit(scene, &ray), &mut values);
                    tile.add_first_hit(k, &values, weight);
                }
                let mut layers = integrator.radiance(scene, &ray, &mut sampler, &mut scratch, stats);
                if weight != 1.0 {
                    layers = layers.map(|c| c * weight);
                }
                if !tile.add(k, &layers) {
                    bad += 1;
                }
            };
            // Camera samples are made a batch at a time before any is traced: each is a chain
            // of dependent steps (hashes, seeding, the ray's normalisation), and made side by
            // side they overlap, where one at a time each waited on its own chain.
            let mut index = next;
            while range.end.saturating_sub(index) >= CAMERA_BATCH as u32 {
                let batch: [_; CAMERA_BATCH] =
                    std::array::from_fn(|b| settings.camera_sample_of(scene, x, y, &mut pixel, index + b as u32));
                batch.into_iter().for_each(&mut trace);
                index += CAMERA_BATCH as u32;
            }
            for index in index..range.end {
                trace(settings.camera_sample_of(scene, x, y, &mut pixel, index));
            }
        }
    }
    bad
}
