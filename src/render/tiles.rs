//! Passes of camera samples for ray integrators: each pass renders a range of sample indices
//! for every pixel, tiles spread over all cores with rayon. Each tile is owned by one worker and
//! every pixel adds its samples in index order, so the image is the same for any thread count
//! and any split into passes.

use super::driver::{Driver, PassOutcome};
use super::{RayIntegrator, RayStats, RenderControl, RenderOutput, RenderSettings};
use crate::film::{Film, Tile};
use crate::scene::Scene;
use rayon::prelude::*;
use std::cell::RefCell;
use std::ops::Range;

/// Renders `scene` with a ray integrator. Runs on the current rayon pool (the caller chooses the
/// thread count by installing a pool).
pub fn render_rays<I: RayIntegrator>(
    scene: &Scene,
    integrator: &I,
    settings: &RenderSettings,
    control: &RenderControl,
) -> RenderOutput {
    // The film is shared between the passes (which write it) and checkpoints (which read it
    // between passes), one after the other on this thread.
    let film = RefCell::new(Film::new(settings.width, settings.height, settings.layers));
    let mut driver = Driver::new(settings, control, "render", "samples per pixel", settings.pixels());
    let mut stats = driver.run(
        |driver, range| render_pass(scene, integrator, driver, &mut film.borrow_mut(), range),
        || {
            let film = film.borrow();
            (film.image(), film.min_samples())
        },
    );
    let film = film.into_inner();
    stats.samples_per_pixel = film.min_samples();
    let layers = (0..if settings.layers { 4 } else { 0 }).map(|k| film.layer_image(k)).collect();
    RenderOutput { image: film.image(), layers, stats }
}

/// Samples `range` of every pixel, tile by tile in parallel.
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
    if interrupted.into_inner() { PassOutcome::Interrupted } else { PassOutcome::Complete }
}

/// Renders samples `range` of every pixel of `tile`, adding them to its sums in index order.
/// Returns the number of non-finite samples dropped.
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
    for j in 0..tile.height {
        for i in 0..tile.width {
            let (x, y) = (tile.x0 + i, tile.y0 + j);
            let k = (j * tile.width + i) as usize;
            for index in range.clone() {
                let (mut sampler, ray) = settings.camera_sample(scene, x, y, index);
                let layers = integrator.radiance(scene, &ray, &mut sampler, &mut scratch, stats);
                if !tile.add(k, &layers) {
                    bad += 1;
                }
            }
        }
    }
    bad
}
