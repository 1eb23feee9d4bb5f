//! The render loop: passes of samples over the whole image, tiles spread over all cores with
//! rayon, a progress bar with ETA, time budgets, checkpoints and clean interruption.

use crate::film::{Film, Image, Tile};
use crate::integrator::{Integrator, RayStats};
use crate::math::Vec2;
use crate::sampling::{Sampler, SamplerKind};
use crate::scene::Scene;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// How samples are taken; fixed before the render starts.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel to take (the cap when a time budget is also given).
    pub spp: u32,
    /// Strata per axis of the jittered sampler (N of the N x N pattern).
    pub strata: u32,
    pub seed: u64,
    pub sampler: SamplerKind,
    /// With anti-aliasing off, every ray goes through the pixel centre (only the lens is sampled).
    pub antialias: bool,
    /// Stop starting new passes after this long.
    pub time_limit: Option<Duration>,
    /// Call the checkpoint callback at least this often.
    pub checkpoint: Option<Duration>,
    pub progress: bool,
    /// Also accumulate the direct, specular, caustic and indirect layers.
    pub layers: bool,
}

/// What a finished (or stopped) render reports.
#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    pub wall: Duration,
    pub rays: RayStats,
    /// Samples per pixel in the image (every pixel has at least this many).
    pub samples_per_pixel: u32,
    pub passes: u32,
    /// Samples dropped because the integrator returned NaN or infinity.
    pub nonfinite_samples: u64,
    /// The render was stopped by the cancel flag before reaching its sample count.
    pub interrupted: bool,
    /// Largest working memory an iteration needed, in bytes (measured by SPPM; 0 elsewhere).
    pub memory_bytes: u64,
}

impl RenderStats {
    pub fn mrays_per_second(&self) -> f64 {
        self.rays.total() as f64 / self.wall.as_secs_f64().max(1e-9) / 1e6
    }
}

/// Receives the image so far and its samples per pixel.
pub type CheckpointFn<'a> = &'a (dyn Fn(&Image, u32) + Sync);

/// Hooks into a running render.
pub struct RenderControl<'a> {
    /// Set (e.g. by Ctrl-C) to stop after the tiles in flight.
    pub cancel: &'a AtomicBool,
    /// Receives the current image every `checkpoint` interval.
    pub on_checkpoint: Option<CheckpointFn<'a>>,
}

/// Renders `scene` with `integrator`. Runs on the current rayon pool (the caller chooses the
/// thread count by installing a pool).
pub fn render<I: Integrator>(
    scene: &Scene,
    integrator: &I,
    settings: &RenderSettings,
    control: &RenderControl,
) -> (Image, RenderStats) {
    let (film, stats) = render_film(scene, integrator, settings, control);
    (film.image(), stats)
}

fn render_film<I: Integrator>(
    scene: &Scene,
    integrator: &I,
    settings: &RenderSettings,
    control: &RenderControl,
) -> (Film, RenderStats) {
    let start = Instant::now();
    let mut film = Film::new(settings.width, settings.height, settings.layers);
    let pixels = settings.width as u64 * settings.height as u64;
    let bar = progress_bar(settings, pixels);

    let rays = AtomicU64::new(0);
    let shadow_rays = AtomicU64::new(0);
    let nonfinite = AtomicU64::new(0);
    let mut done = 0u32;
    let mut passes = 0u32;
    let mut interrupted = false;
    let mut last_checkpoint = Instant::now();
    // Pass sizes grow until a pass takes about `target`, so a stop request, a checkpoint or the
    // end of a time budget is never more than about that far away.
    let progressive = settings.time_limit.is_some() || settings.checkpoint.is_some();
    let target = Duration::from_millis(if progressive { 500 } else { 2000 });
    let mut pass_size = 1u32;

    while done < settings.spp {
        if let Some(limit) = settings.time_limit
            && start.elapsed() >= limit
        {
            break;
        }
        if control.cancel.load(Ordering::Relaxed) {
            interrupted = true;
            break;
        }
        let n = pass_size.min(settings.spp - done);
        let pass_start = Instant::now();
        let range = done..done + n;
        let cancelled = AtomicBool::new(false);
        film.tiles.par_iter_mut().for_each(|tile| {
            if control.cancel.load(Ordering::Relaxed) {
                cancelled.store(true, Ordering::Relaxed);
                return;
            }
            let mut stats = RayStats::default();
            let bad = render_tile(scene, integrator, settings, tile, range.clone(), &mut stats);
            rays.fetch_add(stats.rays, Ordering::Relaxed);
            shadow_rays.fetch_add(stats.shadow_rays, Ordering::Relaxed);
            nonfinite.fetch_add(bad, Ordering::Relaxed);
            bar.inc(tile.width as u64 * tile.height as u64 * n as u64);
        });
        if cancelled.load(Ordering::Relaxed) {
            interrupted = true;
            break;
        }
        done += n;
        passes += 1;
        let took = pass_start.elapsed();
        let per_sample = took.as_secs_f64() / n as f64;
        let mut next = ((target.as_secs_f64() / per_sample.max(1e-9)) as u32).clamp(1, n.saturating_mul(2));
        if let Some(limit) = settings.time_limit {
            // Do not start a pass that would run far past the budget.
            let left = limit.saturating_sub(start.elapsed()).as_secs_f64();
            next = next.min(((left / per_sample.max(1e-9)) as u32).max(1));
        }
        pass_size = next;
        if let (Some(every), Some(cb)) = (settings.checkpoint, control.on_checkpoint)
            && last_checkpoint.elapsed() >= every
            && done < settings.spp
        {
            cb(&film.image(), film.min_samples());
            last_checkpoint = Instant::now();
        }
    }
    bar.finish_and_clear();
    let stats = RenderStats {
        wall: start.elapsed(),
        rays: RayStats { rays: rays.into_inner(), shadow_rays: shadow_rays.into_inner() },
        samples_per_pixel: film.min_samples(),
        passes,
        nonfinite_samples: nonfinite.into_inner(),
        interrupted,
        memory_bytes: 0,
    };
    (film, stats)
}

/// Like `render`, but also returns the four layer images (empty unless `settings.layers`).
pub fn render_layers<I: Integrator>(
    scene: &Scene,
    integrator: &I,
    settings: &RenderSettings,
    control: &RenderControl,
) -> (Image, Vec<Image>, RenderStats) {
    let (film, stats) = render_film(scene, integrator, settings, control);
    let layers = (0..if settings.layers { 4 } else { 0 }).map(|k| film.layer_image(k)).collect();
    (film.image(), layers, stats)
}

/// Renders samples `range` of every pixel of `tile`, adding them to its sums in index order.
/// Returns the number of non-finite samples dropped.
fn render_tile<I: Integrator>(
    scene: &Scene,
    integrator: &I,
    settings: &RenderSettings,
    tile: &mut Tile,
    range: std::ops::Range<u32>,
    stats: &mut RayStats,
) -> u64 {
    let mut bad = 0;
    let mut scratch = I::Scratch::default();
    for j in 0..tile.height {
        for i in 0..tile.width {
            let (x, y) = (tile.x0 + i, tile.y0 + j);
            let k = (j * tile.width + i) as usize;
            for index in range.clone() {
                let mut sampler = Sampler::new(settings.sampler, settings.seed, x, y, index, settings.strata);
                let jitter = sampler.pixel();
                let offset = if settings.antialias { jitter } else { Vec2::splat(0.5) };
                let lens = sampler.lens();
                let ray = scene.camera.generate_ray(Vec2::new(x as f32, y as f32) + offset, lens);
                let layers = integrator.radiance(scene, &ray, &mut sampler, &mut scratch, stats);
                let c = layers[0] + layers[1] + layers[2] + layers[3];
                if c.is_finite() {
                    tile.sum[k] += c;
                    tile.count[k] += 1;
                    if let Some(l) = tile.layers.get_mut(k) {
                        for (acc, v) in l.iter_mut().zip(layers) {
                            *acc += v;
                        }
                    }
                } else {
                    bad += 1;
                }
            }
        }
    }
    bad
}

fn progress_bar(settings: &RenderSettings, pixels: u64) -> ProgressBar {
    use std::io::IsTerminal;
    if !settings.progress || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let total = if settings.time_limit.is_some() && settings.spp == u32::MAX {
        0
    } else {
        pixels.saturating_mul(settings.spp as u64)
    };
    let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
    let style = ProgressStyle::with_template("{spinner} [{elapsed_precise}] {wide_bar} {percent}%  ETA {eta}")
        .unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style);
    bar
}
