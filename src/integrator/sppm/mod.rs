//! Stochastic progressive photon mapping (Hachisuka, Ogaki and Jensen 2008; Hachisuka and Jensen
//! 2009): converges to the correct image with bounded memory, and renders what a path tracer
//! cannot, such as caustics from a point light seen directly and through glass.
//!
//! Each iteration runs three passes:
//! 1. `visible_points`: one camera sample per pixel (pixel jitter and lens re-sampled every
//!    iteration) follows mirrors and glass to the first non-specular surface, adds emitted and
//!    directly sampled light there, and leaves a visible point (position, BSDF, throughput);
//! 2. `photon_pass`: photons from the lights, stored where they land on diffuse surfaces after at
//!    least one bounce (direct light is already counted: their first hits are not stored), in a
//!    hash grid whose cells are twice the mean search radius;
//! 3. `update_statistics`: every pixel collects the photons within its radius r and updates its
//!    photon count N, radius r and flux tau with alpha = 2/3 (Hachisuka 2008 eq. 6-7 and 9-10).
//!
//! By default (no `photons_per_iter` given: docs/scene-format.md, "What SPPM does by default")
//! the photons per iteration follow the measured error budget (`PhotonBudget`), and each pixel
//! keeps two progressive estimates: photons whose light may still be focused (those that came
//! only through mirrors, glass and glossy surfaces) within its radius r, and the other photons (smooth indirect light, whose estimate
//! within r is blotchy) within a disc `INDIRECT_REACH` times wider. Each disc has its own photon
//! count, radius and flux and shrinks by the photons it takes (Hachisuka 2008's update applied
//! to each), so each converges as SPPM does, and their sum to the image.
//!
//! Pixels query the photons (rather than photons the pixels), so every pixel sums its photons in
//! a fixed order and the image is the same for any thread count. Memory is the per-pixel state
//! plus one iteration's visible points and photons, whatever the number of iterations.
//!
//! Iterations are the sample indices of the shared render driver, which runs them in passes and
//! owns the time limit, cancellation, checkpoints and progress. Layers follow the camera path's
//! sampled lobes as in every integrator (`integrator::layers`).

mod budget;
mod grid;
mod media;
mod point;

use super::camera_walk::{CameraWalk, Stop, VertexSlot};
use super::lighting::direct_light;
use crate::film::{Film, Image, Layers};
use crate::geometry::Hit;
use crate::material::bsdf::Bsdf;
use crate::material::bxdf::Transport;
use crate::math::{Color, PackedColor, Vec3, luminance};
use crate::photon::PhotonHits;
use crate::photon::trace::{self, PhotonHit, Watch};
use crate::render::{Driver, PassOutcome, RayStats, RenderControl, RenderOutput, RenderSettings};
use crate::sampling::Sampler;
use crate::sampling::hash_seed;
use crate::scene::Scene;
use crate::scene::desc::IntegratorDesc;
use crate::spectrum::Wavelengths;
use budget::{IterationCosts, PhotonBudget, fixed_square};
use grid::PhotonGrid;
use point::{PointSurface, VisiblePoint, gather};
use rayon::iter::Either;
use rayon::prelude::*;
use std::cell::{Cell, RefCell};
use std::f32::consts::PI;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};

/// SPPM settings.
#[derive(Clone, Debug, PartialEq)]
pub struct SppmConfig {
    /// Photons emitted per iteration (the first iteration's when `adaptive_photons`).
    pub photons_per_iter: u64,
    /// Photons per iteration follow the error budget (`PhotonBudget`), between a sixteenth and
    /// four times `photons_per_iter`: what SPPM does unless the scene or the command line sets
    /// the number.
    pub adaptive_photons: bool,
    /// Photons that met a diffuse surface or a medium on their way are gathered into a second
    /// estimate whose disc starts this many times wider than the pixel's radius and shrinks by
    /// its own photons (`PixelStats`); 1 keeps one disc for all photons (the classic algorithm).
    pub indirect_reach: f32,
    /// Search radius every pixel starts with; `None` derives it per pixel (see `initial_radius`).
    pub initial_radius: Option<f32>,
    /// Fraction of new photons kept (Hachisuka 2008): 2/3.
    pub alpha: f32,
    /// Depth limit in bounces: specular bounces are followed from the camera while the next
    /// surface is still within it.
    pub max_depth: u32,
    /// The offset rays leave surfaces with (`IntegratorDesc::ray_bias`).
    pub ray_bias: f32,
    /// Spectral mode: camera paths and photons carry wavelengths (see `camera_sample`).
    pub spectral: bool,
}

impl SppmConfig {
    /// Settings from the scene's description, for an image of `pixels` pixels of `scene`.
    pub fn new(desc: &IntegratorDesc, scene: &Scene, pixels: u64) -> Self {
        SppmConfig {
            photons_per_iter: desc.photon.photons_per_iter.unwrap_or(pixels).max(1),
            adaptive_photons: desc.photon.photons_per_iter.is_none(),
            // (Not in media: the photon budget measures the surface estimate's variance only, and with
            // the wide disc it would cut the photons the volume estimate needs: RMSE against
            // Mitsuba 0.020 -> 0.039 on tests/media.rs's cube under an area light.)
            indirect_reach: if desc.photon.photons_per_iter.is_none() && !scene.has_media() {
                INDIRECT_REACH
            } else {
                1.0
            },
            initial_radius: desc.photon.initial_radius,
            alpha: 2.0 / 3.0,
            max_depth: desc.depth_limit(desc.kind),
            ray_bias: desc.ray_bias(scene),
            spectral: desc.spectral,
        }
    }

    /// The most photons an iteration may emit.
    pub fn max_photons_per_iter(&self) -> u64 {
        if self.adaptive_photons {
            self.photons_per_iter.saturating_mul(PhotonBudget::MAX_FACTOR)
        } else {
            self.photons_per_iter
        }
    }
}

/// How much wider than the pixel's radius the disc of indirect photons starts in SPPM's default
/// policy (BENCHMARKS.md, issue 32, has the measurement that chose it).
pub const INDIRECT_REACH: f32 = 3.0;

/// The SPPM integrator.
pub struct Sppm {
    pub config: SppmConfig,
    /// Photons emitted by the last render over all its iterations, and its iterations (for the
    /// report).
    emitted: AtomicU64,
    iterations: AtomicU64,
    /// The volume radius of the last render's first and last iterations (f32 bits; 0 without
    /// media), for the report.
    volume_radius: [AtomicU32; 2],
}

/// Working memory of an SPPM render of `pixels` pixels and `photons_per_iter` photons per
/// iteration (photons are stored up to a few times each as they bounce).
pub fn estimated_bytes(pixels: u64, photons_per_iter: u64, layers: bool) -> u64 {
    let layer_bytes = if layers { std::mem::size_of::<PixelLayers>() } else { 0 };
    // (The wide disc counted whether or not the render has one.)
    let per_pixel = (std::mem::size_of::<PixelStats>()
        + std::mem::size_of::<Disc>()
        + std::mem::size_of::<Option<VisiblePoint>>()
        + layer_bytes) as u64;
    let per_photon = 3 * (std::mem::size_of::<PhotonHit>() + std::mem::size_of::<(Vec3, u32)>() + 4) as u64;
    pixels.saturating_mul(per_pixel).saturating_add(photons_per_iter.saturating_mul(per_photon))
}

/// One progressive density estimate of a pixel: its photon count, radius and flux.
#[derive(Clone, Copy, Debug, Default)]
pub struct Disc {
    /// Accumulated photon count N (fractional after the alpha reduction).
    pub n: f32,
    /// Current search radius; 0 until the pixel has had a visible point (or when unused).
    pub r: f32,
    /// Accumulated flux tau (already rescaled to the current radius); RGB in either mode.
    pub tau: PackedColor,
}

impl Disc {
    /// The progressive radiance estimate update for one iteration in which `m` photons within
    /// radius r brought flux `phi` (Hachisuka 2008 eq. 6, 7, 9 and 10): keep a fraction alpha of
    /// the new photons, shrink the disc so its density matches, and scale the flux to the
    /// new disc.
    /// Returns the factor the accumulated flux was scaled by (1 without photons).
    pub fn update(&mut self, m: u32, phi: Color, alpha: f32) -> f32 {
        if m == 0 {
            return 1.0;
        }
        let m = m as f32;
        let n_new = self.n + alpha * m;
        let ratio = n_new / (self.n + m);
        self.tau = ((self.tau.get() + phi) * ratio).into();
        self.r *= ratio.sqrt();
        self.n = n_new;
        ratio
    }

    /// The flux `tau` of this disc as radiance after `iterations` iterations (photon flux
    /// already divided by the number emitted per iteration).
    pub fn radiance(&self, tau: Color, iterations: u32) -> Color {
        if self.r > 0.0 { tau / (iterations.max(1) as f32 * PI * self.r * self.r) } else { Color::ZERO }
    }
}

/// What one pixel has gathered so far.
#[derive(Clone, Copy, Debug, Default)]
pub struct PixelStats {
    /// Sum over iterations of emitted and direct light (RGB in either mode).
    pub ld: PackedColor,
    /// The estimate within the pixel's radius: every photon with `indirect_reach` 1, focused
    /// photons only otherwise. (The wide disc's estimate is kept apart, in `State::wide`, so
    /// that the classic algorithm's memory stays as it was.)
    pub near: Disc,
}

impl PixelStats {
    /// Radiance after `iterations` iterations, with the pixel's wide disc if it has one.
    pub fn radiance(&self, wide: Option<&Disc>, iterations: u32) -> Color {
        let it = iterations.max(1) as f32;
        let l = self.ld.get() / it + self.near.radiance(self.near.tau.get(), iterations);
        match wide {
            Some(w) => l + w.radiance(w.tau.get(), iterations),
            None => l,
        }
    }
}

/// A pixel's light split into layers (kept only when layers are asked for): emitted and
/// directly sampled light, and the accumulated flux of each disc (never `DIRECT`: first hits
/// are not gathered), each flux part rescaled with its disc like the disc's `tau`.
#[derive(Clone, Copy, Debug, Default)]
struct PixelLayers {
    ld: Layers,
    near: Layers,
    wide: Layers,
}

/// What one iteration's camera sample of a pixel found, besides its visible point (written
/// straight into the pixel's slot: moved out through a return value, it was copied twice).
struct CameraSample {
    /// Emitted and directly sampled light, in all and by layer.
    ld: Color,
    ld_layers: Layers,
    /// With a visible point, its distance from the camera (for a pixel's first radius).
    dist: Option<f32>,
}

impl Sppm {
    pub fn new(config: SppmConfig) -> Self {
        Sppm {
            config,
            emitted: AtomicU64::new(0),
            iterations: AtomicU64::new(0),
            volume_radius: [AtomicU32::new(0), AtomicU32::new(0)],
        }
    }

    /// Mean photons per iteration of the last render.
    pub fn mean_photons_per_iter(&self) -> f64 {
        self.emitted.load(Ordering::Relaxed) as f64 / self.iterations.load(Ordering::Relaxed).max(1) as f64
    }

    /// The volume radius of the last render's first and last iterations (`None` without media).
    pub fn volume_radius(&self) -> Option<(f32, f32)> {
        let [a, b] = self.volume_radius.each_ref().map(|r| f32::from_bits(r.load(Ordering::Relaxed)));
        (a > 0.0).then_some((a, b))
    }

    /// Renders iterations up to `settings.spp` (or until the time limit), one camera sample per
    /// pixel per iteration, as a run of its own after the iterations `prior` holds (none for a
    /// new render); the result is `prior` plus this run, each weighted by its iterations.
    pub fn render(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        control: &RenderControl,
        prior: Film,
    ) -> RenderOutput {
        let n_pixels = settings.pixels() as usize;
        let state = RefCell::new(State {
            pixels: vec![PixelStats::default(); n_pixels],
            wide: Vec::new(),
            points: Vec::new(),
            hits: PhotonHits::default(),
            grid: PhotonGrid::build(&mut PhotonHits::default(), 1.0, Vec3::ZERO),
            layers: if settings.layers { vec![PixelLayers::default(); n_pixels] } else { Vec::new() },
            peak_bytes: 0,
            budget: PhotonBudget::new(&self.config),
            volume_r1: match self.config.initial_radius {
                Some(r) => r,
                None if scene.has_media() => {
                    let seed = hash_seed(&[settings.seed, VOLUME_PILOT_SEED]);
                    let c = &self.config;
                    media::first_volume_radius(scene, c.photons_per_iter, seed, c.ray_bias)
                }
                None => 0.0,
            },
        });
        let iterations = Cell::new(0u32);
        // A render-farm shard runs iterations `first_sample..spp` as a progressive run of its
        // own (fresh radii, its own photon seeds); see `farm` for how shards combine.
        let first = settings.first_sample.saturating_add(prior.min_samples());
        let mut driver = Driver::new(settings, control, "sppm", "iterations", settings.pixels(), first);
        let combined = |film: Film| {
            let mut all = prior.clone();
            all.add(&film);
            all
        };
        let mut stats = driver.run(
            |driver, range| {
                let mut state = state.borrow_mut();
                let start = range.start;
                for it in range {
                    if driver.cancelled() || !self.iteration(scene, driver, &mut state, it, iterations.get()) {
                        return PassOutcome::Interrupted { taken: it - start };
                    }
                    iterations.set(iterations.get() + 1);
                }
                PassOutcome::Complete
            },
            |f| f(&combined(state.borrow().film(settings, iterations.get()))),
        );
        let state = state.into_inner();
        let it = iterations.get();
        self.emitted.store(state.budget.emitted, Ordering::Relaxed);
        self.iterations.store(u64::from(it), Ordering::Relaxed);
        stats.memory_bytes = state.peak_bytes as u64;
        let film = combined(state.film(settings, it));
        stats.samples_per_pixel = film.min_samples();
        RenderOutput::from_film(film, stats)
    }

    /// One iteration: visible points, photons, statistics. Returns false when the render was
    /// cancelled during it, leaving every pixel as it was. `done`: iterations this run has
    /// completed (the running means the photon budget measures deviations from).
    fn iteration(&self, scene: &Scene, driver: &Driver, state: &mut State, it: u32, done: u32) -> bool {
        let config = &self.config;
        let settings = driver.settings;
        let w = settings.width;
        let n_pixels = state.pixels.len();
        let diag = {
            let b = scene.bounds();
            if b.is_empty() || !b.diagonal().is_finite() { 1.0 } else { b.diagonal() }
        };
        // Pass 1: photons, without their first hits (direct light is traced below). A Ctrl-C
        // here abandons the iteration before any pixel has changed.
        let seed = hash_seed(&[settings.seed, it as u64]);
        let watch = Watch { cancel: driver.cancel_flag(), progress: None };
        let mut hits = std::mem::take(&mut state.hits);
        let store = if scene.has_media() { trace::Store::Media } else { trace::Store::Indirect };
        let photons = state.budget.photons;
        trace::trace_global_into(
            scene,
            photons,
            seed,
            config.ray_bias,
            store,
            trace::spectral_store(config.spectral, false),
            watch,
            &mut hits,
        );
        if watch.cancelled() {
            return false;
        }
        // With media, the photons scattered in them, gathered by the camera samples below.
        let volume = scene.has_media().then(|| {
            let r1 = state.volume_r1;
            let v = media::VolumePhotons::split(&mut hits, r1, config.alpha, it, scene.bounds().min.min(Vec3::ZERO));
            if done == 0 {
                self.volume_radius[0].store(v.r.to_bits(), Ordering::Relaxed);
            }
            self.volume_radius[1].store(v.r.to_bits(), Ordering::Relaxed);
            v
        });
        // Pass 2: each pixel's camera sample: its emitted and direct light goes into the pixel,
        // and its visible point (a new one gets a radius) into a buffer kept between iterations.
        state.points.resize(n_pixels, None);
        // Ray counts are summed over the pass and recorded once (not an atomic per pixel).
        let prior = done.max(1) as f32;
        let (rays, nonfinite, direct_dev, points) = state
            .pixels
            .par_iter_mut()
            .zip(optional_of(&mut state.layers, n_pixels))
            .zip(state.points.par_iter_mut())
            .enumerate()
            .with_min_len(64)
            .map(|(k, ((px, layers), point))| {
                let mut stats = RayStats::default();
                let xy = (k as u32 % w, k as u32 / w);
                let sample = match &volume {
                    None => self.camera_sample(scene, settings, xy, it, point, &mut stats),
                    Some(v) => self.camera_sample_media(scene, settings, xy, it, v, point, &mut stats),
                };
                let mut nonfinite = 0u64;
                let mut dev = 0;
                if sample.ld.is_finite() {
                    if done > 0 {
                        dev = fixed_square(luminance(sample.ld) - luminance(px.ld.get()) / prior);
                    }
                    px.ld = (px.ld.get() + sample.ld).into();
                    if let Some(l) = layers {
                        for (a, b) in l.ld.iter_mut().zip(sample.ld_layers) {
                            *a += b;
                        }
                    }
                } else {
                    nonfinite = 1;
                }
                if let Some(dist) = sample.dist
                    && px.near.r == 0.0
                {
                    px.near.r = config.initial_radius.unwrap_or_else(|| initial_radius(scene, dist, diag));
                }
                (stats, nonfinite, dev, u64::from(point.is_some()))
            })
            .reduce(
                || (RayStats::default(), 0, 0, 0),
                |(mut a, na, da, pa), (b, nb, db, pb)| {
                    a.add(&b);
                    (a, na + nb, da.saturating_add(db), pa + pb)
                },
            );
        driver.record(&rays, nonfinite, 0);
        let vps = &state.points;
        // The grid's cells are twice the mean radius, so most queries read eight cells: a pixel
        // of a larger radius reads more. Cells as large as the largest radius made every pixel
        // scan photons far out of its reach; cells of the mean radius, 27 cells' scattered
        // reads per pixel (BENCHMARKS.md, issue 29).
        // A pixel's wide disc starts at its first gather, `indirect_reach` times its radius then.
        let reach = config.indirect_reach;
        if reach > 1.0 {
            state.wide.resize(n_pixels, Disc::default());
            for (w, p) in state.wide.iter_mut().zip(&state.pixels) {
                if w.r == 0.0 {
                    w.r = reach * p.near.r;
                }
            }
        }
        let (sum, n) = state.pixels.iter().zip(vps).enumerate().filter(|(_, (_, v))| v.is_some()).fold(
            (0.0f64, 0u64),
            |(s, n), (k, (p, _))| {
                let r = state.wide.get(k).map_or(p.near.r, |w| w.r.max(p.near.r));
                (s + f64::from(r), n + 1)
            },
        );
        let cell = if n > 0 { 2.0 * (sum / n as f64) as f32 } else { 0.0 };
        // Pass 3: each pixel gathers the photons within its radius and updates its statistics.
        let mut bytes = state.pixels.len() * std::mem::size_of::<PixelStats>()
            + state.wide.len() * std::mem::size_of::<Disc>()
            + state.layers.len() * std::mem::size_of::<PixelLayers>()
            + vps.capacity() * std::mem::size_of::<Option<VisiblePoint>>()
            + hits.memory_bytes();
        let mut photon_dev = 0;
        if cell > 0.0 && !hits.is_empty() {
            state.grid.rebuild(&mut hits, cell, scene.bounds().min.min(Vec3::ZERO));
            let grid = &state.grid;
            bytes += grid.memory_bytes();
            let layers = optional_of(&mut state.layers, n_pixels);
            let wide = optional_of(&mut state.wide, n_pixels);
            photon_dev = state
                .pixels
                .par_iter_mut()
                .zip(layers)
                .zip(wide)
                .zip(vps.par_iter())
                .with_min_len(64)
                .map(|(((px, layers), wide), vp)| {
                    let Some(v) = vp else { return 0 };
                    let mut unused = Disc::default();
                    let wide = wide.unwrap_or(&mut unused);
                    let g = gather(scene, v, px.near.r, wide.r, grid, &hits);
                    let beta = v.beta.get();
                    let (g_near, g_wide) = (beta * g.near, beta * g.wide);
                    if !(g_near.is_finite() && g_wide.is_finite()) {
                        driver.record(&RayStats::default(), 1, 0);
                        return 0;
                    }
                    // This iteration's photon estimate against the running one, both over the
                    // discs of the current radii.
                    let dev = if done > 0 {
                        let now = px.near.radiance(g_near, 1) + wide.radiance(g_wide, 1);
                        let mean = px.near.radiance(px.near.tau.get(), 1) + wide.radiance(wide.tau.get(), 1);
                        fixed_square(luminance(now) - luminance(mean) / prior)
                    } else {
                        0
                    };
                    let ratio_near = px.near.update(g.m_near, g_near, config.alpha);
                    let ratio_wide = wide.update(g.m_wide, g_wide, config.alpha);
                    if let Some(l) = layers {
                        let caustic = beta * g.near_caustic;
                        let mut parts = [Color::ZERO; 4];
                        parts[v.layer.caustic_photons()] += caustic;
                        parts[v.layer.other_photons()] += g_near - caustic;
                        for (t, p) in l.near.iter_mut().zip(parts) {
                            *t = (*t + p) * ratio_near;
                        }
                        let mut parts = [Color::ZERO; 4];
                        parts[v.layer.other_photons()] += g_wide;
                        for (t, p) in l.wide.iter_mut().zip(parts) {
                            *t = (*t + p) * ratio_wide;
                        }
                    }
                    dev
                })
                .reduce(|| 0, u64::saturating_add);
        }
        // The camera pass's cost counts a gather as one ray; a photon's, its first ray and one
        // for each stored bounce.
        state.budget.record(
            done > 0,
            IterationCosts {
                direct: direct_dev,
                photon: photon_dev,
                camera_rays: rays.total() + points,
                photon_rays: photons + hits.len() as u64,
                photons,
            },
        );
        state.peak_bytes = state.peak_bytes.max(bytes);
        state.hits = hits;
        driver.record(&RayStats::default(), 0, settings.pixels());
        true
    }

    /// Traces the camera sample of pixel `xy` in iteration `it` to the surface where it makes its
    /// visible point, with the emitted and direct light it finds on the way. Mirrors and glass
    /// are followed, and so are glossy surfaces without a diffuse part (their direct light by a
    /// light sample) except at the last bounce the depth limit allows, where they get the visible
    /// point (pbrt-v4's rule). A surface with both a delta part (mirror, glass, a mask's
    /// transparent part) and a non-delta part makes the visible point with the probability of
    /// the non-delta part and follows the delta part otherwise, each weighted by the inverse of
    /// its probability, so one visible point per sample carries both.
    fn camera_sample(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        (x, y): (u32, u32),
        it: u32,
        point: &mut Option<VisiblePoint>,
        stats: &mut RayStats,
    ) -> CameraSample {
        let config = &self.config;
        *point = None;
        let (mut sampler, ray, weight) = settings.camera_sample(scene, x, y, it);
        // The filter weight scales everything this sample finds (pbrt-v4's SPPM does the same).
        // In spectral mode the wavelengths take the first dimension after the camera's.
        let wl = config.spectral.then(|| Wavelengths::sample(sampler.next_1d()));
        let mut walk = CameraWalk::new(ray, Color::splat(weight)).with_wavelengths(wl);
        let mut ld = Color::ZERO;
        let mut ld_layers = [Color::ZERO; 4];
        let mut slot = VertexSlot::default();
        loop {
            let add = |k: usize, l: Color| {
                ld += l;
                ld_layers[k] += l;
            };
            // (Scenes with media take `camera_sample_media`: no medium is met here.)
            let direct = |hit: &Hit,
                          bsdf: &Bsdf,
                          wo: Vec3,
                          _: u32,
                          wl: Option<&Wavelengths>,
                          sampler: &mut Sampler,
                          stats: &mut RayStats| {
                let (u_pick, u) = (sampler.next_1d(), sampler.next_2d());
                direct_light(scene, hit, bsdf, wo, u_pick, u, config.ray_bias, false, wl, stats)
            };
            let (max_depth, bias) = (config.max_depth, config.ray_bias);
            let v = match walk.next_vertex(scene, max_depth, bias, &mut sampler, stats, add, direct, &mut slot) {
                Some(Stop::Surface(v)) => v,
                Some(Stop::Medium(_)) | None => break,
            };
            let choice = sampler.next_1d();
            let q = if v.bsdf.has_delta() && !v.last { v.bsdf.smooth_fraction(v.wo) } else { 1.0 };
            if choice >= q {
                let sample = v.bsdf.sample_delta(v.wo, sampler.next_1d(), sampler.next_2d(), Transport::Radiance);
                let Some(s) = sample else { break };
                walk.follow_delta(scene, v.hit, &s, config.ray_bias);
                walk.beta /= 1.0 - q;
                continue;
            }
            // This surface is within the depth limit (the walk checked).
            let photon_depth = trace::photon_depth_limit(config.max_depth, v.bounce).unwrap_or(0);
            // The photons' light is RGB: the camera path's filter weights it as a colour.
            let (ld, ld_layers) = (walk.to_rgb(ld), ld_layers.map(|l| walk.to_rgb(l)));
            *point = Some(VisiblePoint {
                surface: PointSurface::of(v.hit, v.bsdf, v.wo, !config.spectral),
                beta: (walk.beta_rgb() / q).into(),
                layer: walk.layer,
                photon_depth: photon_depth.min(u8::MAX.into()) as u8,
            });
            return CameraSample { ld, ld_layers, dist: Some(walk.dist) };
        }
        CameraSample { ld: walk.to_rgb(ld), ld_layers: ld_layers.map(|l| walk.to_rgb(l)), dist: None }
    }
}

/// Each pixel's element of `v`, or `None` for every pixel when `v` is empty.
fn optional_of<T: Send>(v: &mut [T], n: usize) -> impl IndexedParallelIterator<Item = Option<&mut T>> {
    if v.is_empty() {
        Either::Right((0..n).into_par_iter().map(|_| None))
    } else {
        Either::Left(v.par_iter_mut().map(Some))
    }
}

/// The per-pixel state of a render.
struct State {
    pixels: Vec<PixelStats>,
    /// Each pixel's wide disc (`SppmConfig::indirect_reach`), empty when there is none.
    wide: Vec<Disc>,
    /// This iteration's visible points, one per pixel, and photon grid (buffers kept between
    /// iterations).
    points: Vec<Option<VisiblePoint>>,
    /// This iteration's photons (a buffer kept between iterations).
    hits: PhotonHits,
    grid: PhotonGrid,
    /// Per-pixel layers, empty unless asked for.
    layers: Vec<PixelLayers>,
    peak_bytes: usize,
    budget: PhotonBudget,
    /// The first iteration's volume radius (scenes with media).
    volume_r1: f32,
}

impl State {
    fn image(&self, settings: &RenderSettings, iterations: u32) -> Image {
        let mut img = Image::new(settings.width, settings.height);
        for (k, p) in self.pixels.iter().enumerate() {
            let c = p.radiance(self.wide.get(k), iterations);
            img.pixels[k] = if c.is_finite() { c } else { Color::ZERO };
        }
        img
    }

    fn layer_image(&self, settings: &RenderSettings, iterations: u32, layer: usize) -> Image {
        let mut img = Image::new(settings.width, settings.height);
        let it = iterations.max(1) as f32;
        for (k, (p, l)) in self.pixels.iter().zip(&self.layers).enumerate() {
            let wide = self.wide.get(k).map_or(Color::ZERO, |w| w.radiance(l.wide[layer], iterations));
            let c = l.ld[layer] / it + p.near.radiance(l.near[layer], iterations) + wide;
            img.pixels[k] = if c.is_finite() { c } else { Color::ZERO };
        }
        img
    }

    /// The image (and layers) after `iterations` as a film of that many samples per pixel.
    fn film(&self, settings: &RenderSettings, iterations: u32) -> Film {
        let n = if self.layers.is_empty() { 0 } else { 4 };
        let layers: Vec<Image> = (0..n).map(|k| self.layer_image(settings, iterations, k)).collect();
        Film::from_means(&self.image(settings, iterations), &layers, iterations)
    }
}

/// Tells the pilot photon pass that measures the volume radius (`media::first_volume_radius`)
/// from every iteration's photons.
const VOLUME_PILOT_SEED: u64 = 0x766f_6c75_6d65;

/// A starting radius for a pixel whose first visible point is `dist` from the camera: about two
/// pixel footprints there, kept between 0.05% and 2% of the scene's size so any scene scale works.
pub(crate) fn initial_radius(scene: &Scene, dist: f32, diag: f32) -> f32 {
    let footprint = scene.camera.footprint(dist);
    (2.0 * footprint).clamp(5e-4 * diag, 0.02 * diag)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn photon_budget_follows_the_variances_and_costs() {
        let config = SppmConfig {
            photons_per_iter: 6400,
            adaptive_photons: true,
            indirect_reach: 1.0,
            initial_radius: None,
            alpha: 2.0 / 3.0,
            max_depth: 5,
            ray_bias: 1e-4,
            spectral: false,
        };
        // Windows of iterations measuring direct variance d, photon variance p at the current
        // photons, camera rays c and two rays a photon: the number goes to sqrt(p P c / (d k)),
        // at most four times up or down per window.
        let run = |d: u64, p: u64, c: u64, windows: u32| {
            let mut b = PhotonBudget::new(&config);
            // The first iteration measures nothing.
            b.record(false, IterationCosts { photons: b.photons, ..Default::default() });
            let mut photons = Vec::new();
            for _ in 0..windows * PhotonBudget::WINDOW {
                let n = b.photons;
                // The photon estimate's variance falls as 1 / photons.
                let p = p * 6400 / n;
                let costs = IterationCosts { direct: d, photon: p, camera_rays: c, photon_rays: 2 * n, photons: n };
                b.record(true, costs);
                photons.push(b.photons);
            }
            (photons, b.emitted)
        };
        // Equal variances, camera pass as costly as 3200 photons: P = sqrt(6400 * 6400 / 2).
        let (p, _) = run(1000, 1000, 6400, 1);
        assert_eq!(p[..3], [6400; 3]);
        assert_eq!(p[3], (6400.0 / 2f64.sqrt() / 100.0).round() as u64 * 100);
        // Direct light's variance 100 times the photons': a tenth, 640, in steps of at most 4 and
        // rounded to a 64th of the first number.
        let (p, _) = run(100_000, 1000, 12_800, 3);
        assert_eq!((p[3], p[7], p[11]), (1600, 600, 600));
        // No direct variance: up to the most, four times the first number.
        let (p, emitted) = run(0, 1000, 6400, 2);
        assert_eq!((p[3], p[7]), (25600, 25600));
        assert_eq!(emitted, 6400 * 5 + 25600 * 4);
        // No photon variance: down to the least, a sixteenth.
        let (p, _) = run(1000, 0, 6400, 2);
        assert_eq!((p[3], p[7]), (1600, 400));
        // A fixed number stays fixed.
        let mut b = PhotonBudget::new(&SppmConfig { adaptive_photons: false, ..config.clone() });
        for _ in 0..8 {
            b.record(true, IterationCosts { direct: 1, photon: 1000, camera_rays: 1, photon_rays: 1, photons: 6400 });
        }
        assert_eq!(b.photons, 6400);
    }

    #[test]
    fn update_follows_hachisuka_formulas() {
        // N = 10, r = 1, tau = 5; M = 6 new photons with flux 3, alpha = 2/3:
        // N' = 10 + 4 = 14, r'^2 = r^2 N'/(N + M) = 14/16, tau' = (5 + 3) 14/16 = 7.
        let mut d = Disc { n: 10.0, r: 1.0, tau: Color::splat(5.0).into() };
        d.update(6, Color::splat(3.0), 2.0 / 3.0);
        assert!((d.n - 14.0).abs() < 1e-6);
        assert!((d.r * d.r - 14.0 / 16.0).abs() < 1e-6);
        assert!((d.tau.get().r() - 7.0).abs() < 1e-6);
        // No photons: nothing changes.
        let before = d;
        d.update(0, Color::ZERO, 2.0 / 3.0);
        assert_eq!((d.n, d.r, d.tau), (before.n, before.r, before.tau));
        let mut p = PixelStats { ld: PackedColor::ZERO, near: d };
        // The estimate: tau / (iterations pi r^2) plus the mean direct light.
        p.ld = Color::splat(4.0).into();
        let l = p.radiance(None, 2);
        assert!((l.r() - (2.0 + 7.0 / (2.0 * PI * 14.0 / 16.0))).abs() < 1e-5);
    }
}
