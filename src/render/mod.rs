//! The render loop shared by every integrator (pbrt-v4's split): the [`Driver`] owns the time
//! limit, cancellation, checkpoints, progress and statistics of a progressive render made of
//! passes; [`render_rays`] runs passes of camera samples over tiles for any [`RayIntegrator`]
//! (a per-ray `radiance`), and multi-pass methods such as SPPM drive their own passes through the
//! same [`Driver`].

pub mod aov;
mod driver;
mod tiles;

pub use driver::{Driver, PassOutcome};
pub use tiles::{render_rays, render_rays_from};

use crate::display::DisplayTarget;
use crate::film::aov::AovList;

use crate::film::filter::{FilterTable, Window};
use crate::film::{Film, Image, Layers};
use crate::geometry::Ray;
use crate::progress::Display;
use crate::sampling::{PixelSampler, Sampler, SamplerKind};
use crate::scene::Scene;
use crate::scene::desc::Sampling;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Duration;

/// How a render runs: the image and its sampling (from the scene description, with overrides)
/// and how long and how visibly to run.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// The image: the film's crop window (the whole film without a crop).
    pub width: u32,
    pub height: u32,
    /// The image's top-left pixel in the film: pixel (x, y) of the image is pixel
    /// (x + origin.0, y + origin.1) of the film, and is sampled as that pixel, so a crop gives
    /// the whole render's pixels.
    pub origin: (u32, u32),
    /// The pixel filter, ready to sample.
    pub filter: FilterTable,
    /// Where samples may fall, in film pixels: the crop, or unbounded with `sample_border`.
    pub window: Window,
    /// Samples per pixel of the whole render (the cap when a time budget is also given).
    pub spp: u32,
    /// The first sample index this run takes: it renders indices `first_sample..spp` (a shard of
    /// a render farm takes a block of them; 0 otherwise).
    pub first_sample: u32,
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
    /// Show the picture in this image viewer as it renders (`--display-server`).
    pub display: Option<DisplayTarget>,

    /// Also accumulate the direct, specular, caustic and indirect layers.
    pub layers: bool,
    /// The AOVs to write beside the image (`film::aov`).
    pub aovs: AovList,
    /// The EXR's colour channels as CIE XYZ instead of linear sRGB (`film::output`).
    pub xyz: bool,
}

impl RenderSettings {
    /// Settings for a scene's resolved sampling, with no time limit, checkpoints or layers.
    pub fn new(s: &Sampling) -> Self {
        let c = s.crop;
        let window = if s.sample_border {
            Window::UNBOUNDED
        } else {
            Window { x0: c.x as f64, y0: c.y as f64, x1: (c.x + c.width) as f64, y1: (c.y + c.height) as f64 }
        };
        RenderSettings {
            width: c.width,
            height: c.height,
            origin: (c.x, c.y),
            filter: FilterTable::new(s.filter),
            window,
            spp: s.spp,
            first_sample: 0,
            strata: s.strata,
            seed: s.seed,
            sampler: s.sampler,
            antialias: s.antialias,
            time_limit: None,
            checkpoint: None,
            display: None,

            layers: false,
            aovs: s.aovs.clone(),
            xyz: s.xyz,
        }
    }

    /// An empty film for this render: its image, the layers and AOVs asked for.
    pub fn new_film(&self) -> Film {
        Film::new(self.width, self.height, self.layers).with_aovs(&self.aovs)
    }

    pub fn pixels(&self) -> u64 {
        self.width as u64 * self.height as u64
    }

    /// The sampler of sample `index` of image pixel (x, y), the camera ray it makes and the
    /// sample's filter weight (1, or ±(∫|f| / ∫f) for a filter with negative lobes): the
    /// sample's value times the weight goes to this pixel. The film position is drawn from the
    /// filter around the pixel's centre (filter importance sampling, `film::filter`).
    #[inline]
    pub fn camera_sample(&self, scene: &Scene, x: u32, y: u32, index: u32) -> (Sampler, Ray, f32) {
        self.camera_sample_of(scene, x, y, &mut self.pixel_sampler(x, y), index)
    }

    /// The samplers of image pixel (x, y), for `camera_sample_of`: what a pixel's samples
    /// share is computed once for all of them.
    #[inline]
    pub fn pixel_sampler(&self, x: u32, y: u32) -> PixelSampler {
        let seed = Sampler::pixel_seed(self.seed, x + self.origin.0, y + self.origin.1);
        PixelSampler::new(self.sampler, seed, self.strata)
    }

    /// `camera_sample` with the pixel's samplers (`pixel_sampler`) made once for all its samples.
    #[inline]
    pub fn camera_sample_of(
        &self,
        scene: &Scene,
        x: u32,
        y: u32,
        pixel: &mut PixelSampler,
        index: u32,
    ) -> (Sampler, Ray, f32) {
        let (x, y) = (x + self.origin.0, y + self.origin.1);
        let mut sampler = pixel.sampler(index);
        let jitter = sampler.pixel();
        let (offset, weight) = if self.antialias {
            self.filter.sample(jitter, x, y, &self.window)
        } else {
            (crate::math::Vec2::splat(0.5), 1.0)
        };
        let lens = if scene.camera.uses_lens() {
            sampler.lens()
        } else {
            sampler.skip_lens();
            crate::math::Vec2::ZERO
        };
        let ray = scene.camera.generate_ray(crate::math::Vec2::new(x as f32, y as f32) + offset, lens);
        (sampler, ray, weight)
    }
}

/// Rays traced, counted per tile (or pixel) and summed, so counting costs no atomics per ray.
#[derive(Clone, Copy, Debug, Default)]
pub struct RayStats {
    /// Camera and secondary rays.
    pub rays: u64,
    /// Shadow rays (each transparent surface crossed counts as one more).
    pub shadow_rays: u64,
}

impl RayStats {
    pub fn add(&mut self, o: &RayStats) {
        self.rays += o.rays;
        self.shadow_rays += o.shadow_rays;
    }

    pub fn total(&self) -> u64 {
        self.rays + self.shadow_rays
    }
}

/// An integrator that computes the radiance along one camera ray at a time.
pub trait RayIntegrator: Sync {
    /// Reusable per-worker buffers (created once per tile, so the hot path allocates nothing).
    type Scratch: Default;

    /// Radiance arriving along `ray` (towards its origin), by layer. Must not allocate or lock.
    fn radiance(
        &self,
        scene: &Scene,
        ray: &Ray,
        sampler: &mut Sampler,
        scratch: &mut Self::Scratch,
        stats: &mut RayStats,
    ) -> Layers;
}

/// What a finished (or stopped) render reports.
#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    pub wall: Duration,
    pub rays: RayStats,
    /// Samples per pixel in the image (every pixel has at least this many).
    pub samples_per_pixel: u32,
    pub passes: u32,
    /// Samples that were NaN or infinite, counted as black (the pixel keeps its sample count).
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

/// A finished render: the image, its layers (when asked for), the film they come from and what
/// it took.
pub struct RenderOutput {
    pub image: Image,
    /// The direct, specular, caustic and indirect layers, in that order (empty unless asked).
    pub layers: Vec<Image>,
    /// The exact per-pixel sums behind the image (what a render-farm shard saves).
    pub film: Film,
    pub stats: RenderStats,
}

impl RenderOutput {
    /// The output of a render whose result is `film`.
    pub fn from_film(film: Film, stats: RenderStats) -> Self {
        let layers = (0..if film.has_layers() { 4 } else { 0 }).map(|k| film.layer_image(k)).collect();
        RenderOutput { image: film.image(), layers, film, stats }
    }
}

/// Receives the film so far (its `image()` and `min_samples()` are the picture and its samples
/// per pixel).
pub type CheckpointFn<'a> = &'a (dyn Fn(&Film) + Sync);

/// Hooks into a running render.
pub struct RenderControl<'a> {
    /// Set (e.g. by Ctrl-C) to stop after the tiles in flight.
    pub cancel: &'a AtomicBool,
    /// Receives the current image every `checkpoint` interval.
    pub on_checkpoint: Option<CheckpointFn<'a>>,
    /// Where the phases (making the integrator, the passes) report their progress.
    pub progress: &'a Display,
    /// Counts the render's work for a watcher outside it (the Python module's progress bar).
    pub meter: Option<&'a Meter>,
}

impl<'a> RenderControl<'a> {
    /// No cancellation (the flag is never set), no checkpoints, no progress shown, no meter.
    pub fn uncancelled() -> RenderControl<'static> {
        static NEVER: AtomicBool = AtomicBool::new(false);
        static HIDDEN: Display = Display::hidden();
        RenderControl { cancel: &NEVER, on_checkpoint: None, progress: &HIDDEN, meter: None }
    }
}

/// The work a render's passes have done and have to do, in the units of its progress bar (pixel
/// samples), readable from another thread while it runs.
#[derive(Debug, Default)]
pub struct Meter {
    done: AtomicU64,
    total: AtomicU64,
}

impl Meter {
    /// (units done, units in all); the total is 0 before the passes start and when only a time
    /// budget ends the render.
    pub fn read(&self) -> (u64, u64) {
        (self.done.load(Ordering::Relaxed), self.total.load(Ordering::Relaxed))
    }

    fn start(&self, total: u64) {
        self.done.store(0, Ordering::Relaxed);
        self.total.store(total, Ordering::Relaxed);
    }

    fn add(&self, units: u64) {
        self.done.fetch_add(units, Ordering::Relaxed);
    }
}
