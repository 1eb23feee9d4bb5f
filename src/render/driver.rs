//! The progressive loop every integrator runs in: passes of sample indices until the sample
//! count is reached, the time budget is used or the render is cancelled, with checkpoints and
//! progress in between. A pass is whatever the integrator does for a range of sample indices
//! over the whole image (camera samples over tiles, or SPPM iterations). With a display server
//! the picture goes to the image viewer after the first pass, every `display::INTERVAL` after
//! that and at the end, so every integrator can be watched as it converges.

use super::{RayStats, RenderControl, RenderSettings, RenderStats};
use crate::display::{Frame, Viewer};
use crate::film::{Film, LAYER_NAMES};
use crate::progress::Progress;
use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// How a pass ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PassOutcome {
    /// Every sample of the range was taken.
    Complete,
    /// The cancel flag stopped it part-way: the first `taken` samples of the range were taken at
    /// every pixel (an SPPM pass keeps the iterations it finished), the rest partly or not.
    Interrupted { taken: u32 },
}

/// Runs a render's passes and keeps its statistics; shared by reference with the passes.
pub struct Driver<'a> {
    pub settings: &'a RenderSettings,
    control: &'a RenderControl<'a>,
    start: Instant,
    progress: Progress,
    rays: AtomicU64,
    shadow_rays: AtomicU64,
    nonfinite: AtomicU64,
    samples: &'static str,
    /// The sample index the first pass starts at.
    first: u32,
    /// Sends the picture to the image viewer (`--display-server`).
    viewer: Option<Viewer>,
}

impl<'a> Driver<'a> {
    /// A driver for sample indices `first..settings.spp`, whose passes together do
    /// `units_per_sample` units of work per sample index (pixels, for progress); `phase` names it
    /// in the progress display and `samples` says what one sample index is ("samples per pixel",
    /// "iterations").
    pub fn new(
        settings: &'a RenderSettings,
        control: &'a RenderControl<'a>,
        phase: &str,
        samples: &'static str,
        units_per_sample: u64,
        first: u32,
    ) -> Self {
        let first = first.min(settings.spp);
        let total =
            if settings.spp == u32::MAX { 0 } else { units_per_sample.saturating_mul((settings.spp - first) as u64) };
        let progress = control.progress.phase(phase, total);
        if let Some(m) = control.meter {
            m.start(total);
        }

        Driver {
            settings,
            control,
            start: Instant::now(),
            progress,
            rays: AtomicU64::new(0),
            shadow_rays: AtomicU64::new(0),
            nonfinite: AtomicU64::new(0),
            samples,
            first,
            viewer: settings.display.as_ref().map(Viewer::start),
        }
    }

    /// True once the render has been asked to stop.
    #[inline]
    pub fn cancelled(&self) -> bool {
        self.control.cancel.load(Ordering::Relaxed)
    }

    /// The flag that asks the render to stop, for work that checks it itself.
    pub fn cancel_flag(&self) -> &'a std::sync::atomic::AtomicBool {
        self.control.cancel
    }

    /// Adds a worker's counts: rays traced, samples that were NaN or infinite (counted as black), work units done.
    pub fn record(&self, stats: &RayStats, nonfinite: u64, units: u64) {
        self.rays.fetch_add(stats.rays, Ordering::Relaxed);
        self.shadow_rays.fetch_add(stats.shadow_rays, Ordering::Relaxed);
        if nonfinite > 0 {
            self.nonfinite.fetch_add(nonfinite, Ordering::Relaxed);
        }
        if units > 0 {
            self.progress.inc(units);
            if let Some(m) = self.control.meter {
                m.add(units);
            }
        }
    }

    /// Runs `pass` over growing ranges of sample indices until index `settings.spp` is reached,
    /// the time limit is reached or the render is cancelled; `snapshot` hands the film so far to
    /// its argument, for checkpoints. Returns the statistics (`memory_bytes` and
    /// `samples_per_pixel` left at 0).
    pub fn run(
        &mut self,
        mut pass: impl FnMut(&Self, Range<u32>) -> PassOutcome,
        snapshot: impl Fn(&mut dyn FnMut(&Film)),
    ) -> RenderStats {
        let settings = self.settings;
        let mut done = self.first;
        let mut passes = 0u32;
        let mut interrupted = false;
        let mut last_checkpoint = Instant::now();
        let mut last_shown: Option<Instant> = None;
        // Pass sizes grow until a pass takes about `target`, so a stop request, a checkpoint, a
        // picture for the viewer or the end of a time budget is never more than about that far
        // away.
        let progressive = settings.time_limit.is_some() || settings.checkpoint.is_some() || self.viewer.is_some();
        let target = Duration::from_millis(if progressive { 500 } else { 2000 });
        let mut pass_size = 1u32;
        while done < settings.spp {
            if let Some(limit) = settings.time_limit
                && self.start.elapsed() >= limit
            {
                break;
            }
            if self.cancelled() {
                interrupted = true;
                break;
            }
            let n = pass_size.min(settings.spp - done);
            let pass_start = Instant::now();
            if let PassOutcome::Interrupted { taken } = pass(self, done..done + n) {
                // What the pass kept counts, so the summary and the image agree.
                done += taken.min(n);
                interrupted = true;
                break;
            }
            done += n;
            passes += 1;
            let per_sample = pass_start.elapsed().as_secs_f64() / n as f64;
            let mut next = ((target.as_secs_f64() / per_sample.max(1e-9)) as u32).clamp(1, n.saturating_mul(2));
            if let Some(limit) = settings.time_limit {
                // Do not start a pass that would run far past the budget.
                let left = limit.saturating_sub(self.start.elapsed()).as_secs_f64();
                next = next.min(((left / per_sample.max(1e-9)) as u32).max(1));
            }
            pass_size = next;
            if let (Some(every), Some(cb)) = (settings.checkpoint, self.control.on_checkpoint)
                && last_checkpoint.elapsed() >= every
                && done < settings.spp
            {
                snapshot(&mut |film| cb(film));
                last_checkpoint = Instant::now();
            }
            if let Some(viewer) = &self.viewer
                && last_shown.is_none_or(|t| t.elapsed() >= crate::display::INTERVAL)
                && done < settings.spp
            {
                snapshot(&mut |film| viewer.show(frame(film)));
                last_shown = Some(Instant::now());
            }
        }
        if let Some(viewer) = self.viewer.take() {
            // The last picture is the image the render returns; it is sent before the render
            // ends, so the viewer holds what is written.
            snapshot(&mut |film| viewer.show(frame(film)));
            viewer.finish();
        }
        self.progress.finish(&format!("{} {} in {passes} passes", done - self.first, self.samples));
        RenderStats {
            wall: self.start.elapsed(),
            rays: RayStats {
                rays: self.rays.load(Ordering::Relaxed),
                shadow_rays: self.shadow_rays.load(Ordering::Relaxed),
            },
            samples_per_pixel: 0,
            passes,
            nonfinite_samples: self.nonfinite.load(Ordering::Relaxed),
            interrupted,
            memory_bytes: 0,
        }
    }
}

/// The film's picture as the viewer's channels: R, G, B, then each layer's (`direct.R`, ...).
fn frame(film: &Film) -> Frame {
    let mut images = vec![film.image()];
    if film.has_layers() {
        images.extend((0..LAYER_NAMES.len()).map(|k| film.layer_image(k)));
    }
    let names = std::iter::once("").chain(LAYER_NAMES);
    let channels = names
        .take(images.len())
        .flat_map(|layer| {
            ["R", "G", "B"].map(|c| if layer.is_empty() { c.to_string() } else { format!("{layer}.{c}") })
        })
        .collect();
    let mut planes = Vec::with_capacity(images.len() * 3 * (film.width * film.height) as usize);
    for img in &images {
        for c in 0..3 {
            planes.extend(img.pixels.iter().map(|p| p.to_array()[c]));
        }
    }
    Frame { width: film.width, height: film.height, channels, planes }
}
