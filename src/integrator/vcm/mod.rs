//! Vertex connection and merging (Georgiev, Křivánek, Davidovič and Slusallek 2012; the same
//! combination as Hachisuka, Pantaleoni and Jensen's unified path sampling): bidirectional path
//! tracing (`integrator::bdpt`) plus vertex merging, photon mapping's density estimation seen as
//! one more technique, all weighted by multiple importance sampling through the partial weights
//! dVCM, dVC and dVM (`bdpt::mis`, Georgiev's technical report; SmallVCM's `VertexCM`).
//!
//! Each iteration (one sample index) runs two passes:
//! 1. `light_pass`: one light subpath per pixel of the image, or per m pixels as the light
//!    budget's pilot chose (`LightBudget`); each vertex with a non-delta part is connected to
//!    the camera (splatted; not the first hit, whose direct light is next-event estimation's,
//!    `bdpt::mis`) and stored, in path order;
//! 2. `camera_pass`: each pixel's camera subpath takes every technique of bidirectional path
//!    tracing with the light subpath of its own index (SmallVCM's pairing; with one light path
//!    per m pixels, in one iteration of m) and, at each vertex
//!    with a non-delta part, merges with every stored vertex within the iteration's radius for
//!    that vertex's light (`photon::grid`, a hashed grid of cells twice the wider radius), each
//!    merge weighted against the connections that make the same path.
//!
//! Two radii (`mis::Reach`): light that came only through mirrors and glass (caustics) merges
//! within the narrow one, light after a diffuse or glossy bounce within one `wide_reach` times
//! wider, and light straight from the light not at all (next-event estimation's). Both shrink
//! as progressive photon mapping's radius does (Knaus and Zwicker 2011; SmallVCM): iteration i
//! merges within r_i = r_0 (i + 1)^((alpha - 1) / 2) with alpha = 0.75, so the bias of merging
//! vanishes while its variance stays bounded. r_0 is `--initial-radius` or `FOCUSED_SCALE`
//! times what SPPM starts a pixel with (about two pixel footprints at the first hit, within
//! 0.05% and 2% of the scene's size), taken at the median of a grid of camera rays: the
//! weights need one radius per iteration and kind of light for the whole image.
//!
//! An iteration's image is an estimate of its own (camera paths' light and splats, exact
//! fixed-point sums in the `SplatFilm`), and a render is their mean: iteration i always has
//! radius r_i and draws its numbers from (seed, i), so images are bit-identical on any thread
//! count, a checkpoint resumes exactly, and a farm's shards, each taking a block of
//! iterations, merge into the one-machine image bit for bit (SPPM's shards restart their radii;
//! these need not, as every iteration knows its own).
//!
//! Spectral mode: one set of wavelengths per iteration, carried by all its light and camera
//! paths (`Context::wl`). A merge joins a camera vertex with light vertices of other paths, and
//! the estimate is the camera path's throughput times theirs at the same wavelengths, which
//! holds only if every path the camera vertex may meet was traced at its wavelengths: per-path
//! wavelengths would merge each camera path with the few light paths that happened to share
//! them, none in practice. (SPPM's alternative, photons that store CIE XYZ, multiplies the
//! visible point's BSDF in RGB with a spectrum reduced to three numbers: a product of
//! spectra that is not the spectral product, where VCM's merges are then weighted against
//! connections that are spectral; sharing keeps every technique the same estimator.) The
//! iteration's hero is u_i = frac(o + i phi / 4), a golden-ratio sequence over the global
//! iteration index offset by a hash of the seed (`iteration_wavelengths`, which says why a quarter): a pure function of
//! (seed, i), so shards, resumes and thread counts give the same images, and N iterations cover
//! the spectrum with the low discrepancy of that sequence (4N wavelengths with the lanes), where
//! independent draws would leave the image-wide colour of a render of few iterations as noisy
//! as one path's. Paths through dispersive glass keep the hero alone (`bdpt::strategy`), and
//! light enters the film as linear sRGB; the light budget's pilot measures the sRGB luminance.

use super::bdpt::mis::{self, Reach};
use super::bdpt::strategy::{self, Context, LightVertex};
use super::bdpt::subpath;
use crate::film::splat::{DRAIN_PATHS, SplatFilm};
use crate::film::{Film, Layers};
use crate::material::bxdf::Transport;
use crate::math::luminance;
use crate::math::{Color, Vec2, Vec3};
use crate::photon::grid::HashGrid;
use crate::render::{Driver, PassOutcome, RayStats, RenderControl, RenderOutput, RenderSettings};
use crate::sampling::{Rng32, hash_seed};
use crate::scene::Scene;
use crate::scene::desc::IntegratorDesc;
use crate::spectrum::{Wavelengths, joined};
use rayon::prelude::*;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};

/// Paths traced together by one worker (light paths, or pixels' camera paths).
const CHUNK: u64 = 256;

/// The stream light subpaths draw from (apart from bidirectional path tracing's).
const LIGHT_STREAM: u64 = 0x5643_4d4c_4947;

/// The stream a spectral render's wavelength offset is drawn from (`iteration_wavelengths`).
const WAVELENGTH_STREAM: u64 = 0x5643_4d57_4156;

/// Radius reduction of progressive photon mapping (SmallVCM's default).
pub const DEFAULT_ALPHA: f32 = 0.75;

/// The default merge radii over SPPM's initial radius (`scene_radius`): light focused by mirrors
/// and glass within the narrow one, light after a diffuse or glossy bounce, which varies slowly,
/// within the wide one (`mis::Reach`; as SPPM gathers its indirect photons in a wider disc,
/// `sppm::INDIRECT_REACH`). Measured on the caustic box at equal time (BENCHMARKS.md, 12-05):
/// one radius of 1x read 0.0080, these 0.0060; narrower caustics blur less and wider indirect
/// light is less noisy, and past them noise and bias take over (0.5x and 2x read 0.0066-0.0067).
pub const FOCUSED_SCALE: f32 = 0.7;
/// The wide radius over SPPM's initial radius (`FOCUSED_SCALE` has the measurement).
pub const SPREAD_SCALE: f32 = 1.5;

/// Camera rays per image axis that pick the initial radius.
const RADIUS_PROBES: u32 = 16;

/// VCM settings.
#[derive(Clone, Debug, PartialEq)]
pub struct VcmConfig {
    /// Longest path in bounces, as the path tracer's.
    pub max_depth: u32,
    /// The offset rays leave surfaces with (`IntegratorDesc::ray_bias`).
    pub ray_bias: f32,
    /// Merge radius of the first iteration for focused light (`mis::Reach`).
    pub initial_radius: f32,
    /// Radius reduction: r_i = r_0 (i + 1)^((alpha - 1) / 2).
    pub alpha: f32,
    /// The wide radius over the narrow one (`SPREAD_SCALE / FOCUSED_SCALE`; 1 merges all light
    /// alike).
    pub wide_reach: f32,
    /// One light path per this many camera paths (`LightBudget`); `None` chooses it.
    pub light_divisor: Option<u32>,
    /// Spectral mode (`crate::spectrum::lanes`; the module header); RGB otherwise.
    pub spectral: bool,
    /// Merge only at each camera path's first non-delta vertex (`MisFactors::merge_first_only`).
    /// Off: measured on 12-04 (BENCHMARKS.md), it lowered the caustic box's error 0.0085 ->
    /// 0.0077 and the materials scene's 0.0106 -> 0.0097 but raised the sky-lit scene's 0.0214
    /// -> 0.0256, so it waits for a per-scene choice.
    pub merge_first_only: bool,
}

impl VcmConfig {
    /// Settings from the scene's description for `scene` rendered with `settings`.
    pub fn new(desc: &IntegratorDesc, scene: &Scene, settings: &RenderSettings) -> Self {
        VcmConfig {
            max_depth: desc.depth_limit(desc.kind),
            ray_bias: desc.ray_bias(scene),
            initial_radius: desc.photon.initial_radius.unwrap_or_else(|| FOCUSED_SCALE * scene_radius(scene, settings)),
            alpha: DEFAULT_ALPHA,
            wide_reach: SPREAD_SCALE / FOCUSED_SCALE,
            light_divisor: None,
            spectral: desc.spectral,
            merge_first_only: false,
        }
    }

    /// The merge radius of iteration `i` (from 0).
    pub fn radius(&self, i: u32) -> f32 {
        self.initial_radius * ((i as f64 + 1.0).powf((self.alpha as f64 - 1.0) / 2.0)) as f32
    }
}

/// The wavelengths every path of iteration `it` carries in spectral mode (the module header):
/// the hero at u = frac(o + it phi / 4), o from the seed.
///
/// Why phi / 4 and not the plain golden-ratio sequence's 1 / phi: the four lanes sit at u,
/// u + 1/4, u + 1/2 and u + 3/4, a set that repeats when u moves by a quarter, so what the lanes
/// average sees only 4u mod 1, which advances by phi mod 1 = 1 / phi per iteration: the
/// golden-ratio sequence itself, the Weyl sequence of least discrepancy. (With a step of
/// 1 / phi, 4u advances by 0.472, a poorer sequence.) On a test integrand peaked as the CIE
/// z-bar (Wyman et al.'s fit) over the visible distribution, the lanes' mean error, rms over
/// 500 offsets, is 0.145% against 0.183% at 256 iterations and 0.026% against 0.049% at 1024;
/// the hero alone (paths through dispersive glass), itself a Weyl sequence of step 0.405,
/// errs more at 256 iterations (1.35% against 0.91%) and about as much at 1024 (0.25% against
/// 0.22%).
pub fn iteration_wavelengths(seed: u64, it: u32) -> Wavelengths {
    const GOLDEN_STEP: f64 = 1.618_033_988_749_895 / crate::spectrum::LANES as f64;
    let offset = (hash_seed(&[seed, WAVELENGTH_STREAM]) >> 11) as f64 / (1u64 << 53) as f64;
    let u = (offset + f64::from(it) * GOLDEN_STEP).fract() as f32;
    // Rounding to f32 may reach 1.
    Wavelengths::sample(if u < 1.0 { u } else { 0.0 })
}

/// The initial radius SPPM would give the pixels (`sppm::initial_radius`), at the median over a
/// grid of camera rays through the image (those that hit something; the scene's 2% cap when
/// none does).
fn scene_radius(scene: &Scene, settings: &RenderSettings) -> f32 {
    let b = scene.bounds();
    let diag = if b.is_empty() || !b.diagonal().is_finite() { 1.0 } else { b.diagonal() };
    let mut radii = Vec::new();
    for j in 0..RADIUS_PROBES {
        for i in 0..RADIUS_PROBES {
            let raster = Vec2::new(
                settings.origin.0 as f32 + (i as f32 + 0.5) / RADIUS_PROBES as f32 * settings.width as f32,
                settings.origin.1 as f32 + (j as f32 + 0.5) / RADIUS_PROBES as f32 * settings.height as f32,
            );
            let ray = scene.camera.generate_ray(raster, Vec2::splat(0.5));
            if let Some(hit) = scene.intersect(&ray, f32::INFINITY) {
                radii.push(super::sppm::initial_radius(scene, (hit.p - ray.o).length(), diag));
            }
        }
    }
    if radii.is_empty() {
        return 0.02 * diag;
    }
    radii.sort_by(f32::total_cmp);
    radii[radii.len() / 2]
}

/// The VCM integrator.
pub struct Vcm {
    pub config: VcmConfig,
    /// The light budget of the last render (`LightBudget`): camera paths per light path.
    divisor: AtomicU32,
}

/// How many camera paths share one light path (issue 26): tracing a light path per pixel is
/// what VCM needs where light tracing and merging carry the image (caustics seen in glossy
/// surfaces, under the sky through glass), and light it pays for and does not use where the
/// camera-only techniques (emitters hit, next-event estimation) find most of it.
///
/// With one light path per m camera paths (`MisFactors::with_light_fraction`), the techniques of
/// light subpaths get m times fewer samples and cost m times less, and the weights move light
/// towards the camera-only techniques. How much error that trade costs depends on how well the
/// camera-only techniques take over, which no model of the two parts' variances predicted: a
/// model with the variance of light subpaths' techniques growing m times chose m = 1 on the
/// caustic box, where m = 4 has 14% less error at equal time, and m = 8 on the sky-lit scene,
/// where it has 18% more than m = 1. So the pilot measures instead: the render's iterations 0
/// and 1 with one light path per pixel, 2 and 3 with one per `PROBE_DIVISOR` camera paths
/// (`PILOT`). For each pair it takes the variance of one iteration (each pixel's squared
/// difference between the two over 2, capped at the image's 99.9th percentile against fireflies,
/// summed over pixels) times the pair's work (rays, and merges at `MERGE_COST` each); the
/// smaller product, error times time, decides m (1 or `PROBE_DIVISOR`).
///
/// The pilot's iterations are kept in the image when the render starts at iteration 0; every
/// shard and every resumed run renders them to find the same m, so an image is the same whatever
/// the split.
struct LightBudget;

impl LightBudget {
    /// The light paths' share the pilot tries against one light path per pixel.
    const PROBE_DIVISOR: u32 = 4;
    /// Where the pilot caps each pixel's difference between its two iterations.
    const CAP_QUANTILE: f64 = 0.999;
    /// What evaluating one light vertex within the merge radius costs, in rays (estimated: a
    /// BSDF evaluation, a reverse density and a weight, against a ray's traversal).
    const MERGE_COST: f64 = 0.25;

    /// The variance of one iteration summed over the pixels, from two iterations' values per
    /// pixel (any measure of light, here luminance): (a - b)^2 / 2 with |a - b| capped at the
    /// `CAP_QUANTILE` of the image's. Two samples per pixel let one firefly decide an uncapped
    /// sum (a small light's glossy reflection made a pilot read 40,000 times another seed's).
    fn variance(a: &[f32], b: &[f32]) -> f64 {
        let d: Vec<f64> = a
            .iter()
            .zip(b)
            .map(|(&x, &y)| f64::from(x) - f64::from(y))
            .filter(|d| d.is_finite())
            .map(f64::abs)
            .collect();
        let mut sorted = d.clone();
        sorted.sort_by(f64::total_cmp);
        let Some(&cap) = sorted.get((sorted.len().saturating_sub(1) as f64 * Self::CAP_QUANTILE) as usize) else {
            return 0.0;
        };
        d.iter().map(|x| x.min(cap).powi(2) / 2.0).sum()
    }

    /// m from the pilot: for one light path per pixel and for one per `PROBE_DIVISOR` camera
    /// paths, the two iterations' values per pixel and their work.
    fn divisor(one: (&[f32], &[f32], f64), fewer: (&[f32], &[f32], f64)) -> u32 {
        let error_time = |(a, b, work): (&[f32], &[f32], f64)| Self::variance(a, b) * work;
        let (e1, e4) = (error_time(one), error_time(fewer));
        if e4 < e1 { Self::PROBE_DIVISOR } else { 1 }
    }
}

/// Camera paths per light path in each iteration of the pilot (`LightBudget`).
const PILOT: [u32; 4] = [1, 1, LightBudget::PROBE_DIVISOR, LightBudget::PROBE_DIVISOR];
const PILOT_ITERATIONS: u32 = PILOT.len() as u32;

/// What a pilot iteration measures (`LightBudget`).
#[derive(Default)]
struct Probe {
    /// Rays of the iteration's light paths, camera paths, connections and splats.
    rays: u64,
    /// Light vertices within the merge radius of a camera vertex.
    merges: u64,
}

impl Probe {
    fn work(&self) -> f64 {
        self.rays as f64 + self.merges as f64 * LightBudget::MERGE_COST
    }
}

/// Working memory of a VCM render of `pixels` pixels: the light vertices of one iteration (a few
/// per light path) with their grid, the splat film and the film a pass accumulates into.
pub fn estimated_bytes(pixels: u64, layers: bool) -> u64 {
    // About three stored vertices per path, each with its grid entry (position and index), up
    // to two bucket starts (buckets are a power of two at least the count) and its merge record.
    let per_vertex = std::mem::size_of::<LightVertex>() + 16 + 8 + std::mem::size_of::<MergeVertex>();
    let per_path = 3 * per_vertex as u64 + 8;
    super::light::estimated_bytes(pixels, layers) + pixels * per_path
}

/// One iteration's light subpaths: their vertices in path order, and where each path's end.
#[derive(Default)]
struct LightPaths {
    vertices: Vec<LightVertex>,
    /// Path k's vertices are `vertices[ends[k - 1]..ends[k]]` (from 0 for the first).
    ends: Vec<u32>,
    /// The vertices merged (`build_grid`).
    grid: HashGrid,
    /// What a merge reads of each vertex, by grid slot.
    merges: Vec<MergeVertex>,
    /// Scratch: the indices of the vertices merged while the grid is built.
    merged: Vec<u32>,
    peak_bytes: usize,
}

impl LightPaths {
    fn path(&self, k: usize) -> &[LightVertex] {
        let start = if k == 0 { 0 } else { self.ends[k - 1] as usize };
        &self.vertices[start..self.ends[k] as usize]
    }

    /// Sorts the vertices merged (`mis::Reach`: not light straight from the light, next-event
    /// estimation's) into the grid, cells twice the wider radius wide (a query overlaps at most
    /// 2 x 2 x 2 of them). One grid for both radii: a second grid's query cost more than
    /// reading the few focused vertices within the wide radius and leaving out those beyond
    /// the narrow one.
    fn build_grid(&mut self, radius: f32, origin: Vec3) {
        let vertices = &self.vertices;
        self.merged.clear();
        self.merged.extend((0..vertices.len() as u32).filter(|&i| vertices[i as usize].reach() != Reach::Direct));
        let merged = &self.merged;
        let points = |r: std::ops::Range<usize>| merged[r].iter().map(|&i| (vertices[i as usize].hit.p, i));
        self.grid.rebuild(merged.len(), points, 2.0 * radius, origin);
        self.merges.clear();
        self.merges.extend(self.grid.ids().iter().map(|&i| MergeVertex::of(&vertices[i as usize])));
    }

    fn memory_bytes(&self) -> usize {
        self.vertices.capacity() * std::mem::size_of::<LightVertex>()
            + (self.ends.capacity() + self.merged.capacity()) * 4
            + self.grid.memory_bytes()
            + self.merges.capacity() * std::mem::size_of::<MergeVertex>()
    }
}

impl Vcm {
    /// Renders iterations up to `settings.spp` (or until the time limit) after those `film`
    /// holds (from `settings.first_sample`).
    pub fn render(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        control: &RenderControl,
        film: Film,
    ) -> RenderOutput {
        let mut paths = LightPaths::default();
        // The light budget, and the pilot's iterations while they wait to be used.
        let mut budget: Option<(u32, Vec<Film>)> = self.config.light_divisor.map(|m| (m.max(1), Vec::new()));
        let (film, mut stats) = crate::integrator::render_splatted(
            settings,
            control,
            film,
            ("vcm", "iterations"),
            |driver, splats, film, range| {
                if budget.is_none() {
                    match self.pilot(scene, driver, splats, &mut paths, range.start == 0) {
                        Some(b) => budget = Some(b),
                        None => return PassOutcome::Interrupted { taken: 0 },
                    }
                }
                let (m, pilot) = budget.as_mut().expect("set above");
                self.pass(scene, driver, splats, &mut paths, film, range, *m, pilot)
            },
        );
        self.divisor.store(budget.map_or(0, |b| b.0), Ordering::Relaxed);
        stats.memory_bytes = paths.peak_bytes as u64;
        RenderOutput::from_film(film, stats)
    }

    /// Runs iterations `range` and adds them to `film`; an interrupted pass keeps the iterations
    /// it finished.
    #[allow(clippy::too_many_arguments)]
    fn pass(
        &self,
        scene: &Scene,
        driver: &Driver,
        splats: &SplatFilm,
        paths: &mut LightPaths,
        film: &mut Film,
        range: Range<u32>,
        m: u32,
        pilot: &mut Vec<Film>,
    ) -> PassOutcome {
        let mut pass = Film::new(film.width, film.height, film.has_layers());
        let mut done = 0;
        for it in range.clone() {
            // The pilot's iterations are the render's first (`LightBudget`).
            if (it as usize) < pilot.len() {
                pass.add(&pilot[it as usize]);
                done += 1;
                continue;
            }
            let divisor = PILOT.get(it as usize).copied().unwrap_or(m);
            if !self.iteration(scene, driver, splats, paths, &mut pass, it, divisor, None, true) {
                splats.clear();
                break;
            }
            done += 1;
        }
        if range.end >= PILOT_ITERATIONS {
            pilot.clear();
        }
        for t in &mut pass.tiles {
            t.count.iter_mut().for_each(|c| *c = done);
        }
        film.add(&pass);
        if done < range.len() as u32 { PassOutcome::Interrupted { taken: done } } else { PassOutcome::Complete }
    }

    /// The light budget (`LightBudget`) from the pilot's iterations (`PILOT`), with their films
    /// when `keep` (the render starts there; otherwise they only measure, and do not count in
    /// the progress). `None` when cancelled.
    fn pilot(
        &self,
        scene: &Scene,
        driver: &Driver,
        splats: &SplatFilm,
        paths: &mut LightPaths,
        keep: bool,
    ) -> Option<(u32, Vec<Film>)> {
        let settings = driver.settings;
        let mut films = Vec::new();
        let mut probes = Vec::new();
        for (it, &m) in PILOT.iter().enumerate() {
            let mut film = Film::new(settings.width, settings.height, settings.layers);
            let mut probe = Probe::default();
            if !self.iteration(scene, driver, splats, paths, &mut film, it as u32, m, Some(&mut probe), keep) {
                splats.clear();
                return None;
            }
            films.push(film);
            probes.push(probe);
        }
        let values: Vec<Vec<f32>> = films
            .iter()
            .map(|f| {
                let mut f = f.clone();
                for t in &mut f.tiles {
                    t.count.iter_mut().for_each(|c| *c = 1);
                }
                f.image().pixels.iter().map(|&c| luminance(c)).collect()
            })
            .collect();
        let m = LightBudget::divisor(
            (&values[0], &values[1], probes[0].work() + probes[1].work()),
            (&values[2], &values[3], probes[2].work() + probes[3].work()),
        );
        Some((m, if keep { films } else { Vec::new() }))
    }

    /// Iteration `it` with one light path per `m` camera paths: light paths, their grid, camera
    /// paths; its light is drained into `pass`. `probe` measures it for the light budget;
    /// `count` records its samples in the progress. Returns false, leaving `pass` as it was,
    /// when the render was cancelled during it.
    #[allow(clippy::too_many_arguments)]
    fn iteration(
        &self,
        scene: &Scene,
        driver: &Driver,
        splats: &SplatFilm,
        paths: &mut LightPaths,
        pass: &mut Film,
        it: u32,
        m: u32,
        mut probe: Option<&mut Probe>,
        count: bool,
    ) -> bool {
        let settings = driver.settings;
        let pixels = settings.pixels();
        let radius = self.config.radius(it);
        let full = scene.camera.width as f64 * scene.camera.height as f64;
        // One light path per `m` camera paths: camera path k connects to light path k / m in the
        // iterations where k + it is a multiple of m, so each connects in one iteration of m
        // (and its connections count m times), and every light path is used once.
        let light_paths = pixels.div_ceil(u64::from(m));
        let wide_radius = radius * self.config.wide_reach;
        let factors = mis::MisFactors::with_merging(
            radius as f64,
            wide_radius as f64,
            pixels as f64,
            full / pixels.max(1) as f64,
        )
        .with_light_fraction(1.0 / f64::from(m));
        let factors = mis::MisFactors { merge_first_only: self.config.merge_first_only, ..factors };
        let mut ctx = Context::new(scene, self.config.max_depth, self.config.ray_bias, pixels, Some(factors));
        ctx.light_scale = (full / light_paths.max(1) as f64) as f32;
        ctx.connection_scale = m as f32;
        ctx.wl = self.config.spectral.then(|| iteration_wavelengths(settings.seed, it));
        // The iteration's sums gather here and join the pass only when it is whole.
        let mut sums = Film::new(pass.width, pass.height, pass.has_layers());
        let Some(light_rays) = self.light_pass(&ctx, driver, splats, paths, &mut sums, it, light_paths) else {
            return false;
        };
        if let Some(p) = probe.as_deref_mut() {
            p.rays += light_rays;
        }
        paths.build_grid(radius.max(wide_radius), scene.bounds().min.min(Vec3::ZERO));
        paths.peak_bytes = paths.peak_bytes.max(paths.memory_bytes());
        if !self.camera_pass(&ctx, driver, splats, paths, it, radius, m, probe, count) {
            return false;
        }
        splats.drain_into(&mut sums);
        pass.add(&sums);
        true
    }

    /// Traces the light subpaths of iteration `it`, splatting their connections to the camera
    /// (drained into `sums`, all but the last batch's, which the drain after the camera pass
    /// takes) and keeping their vertices in `paths`.
    #[allow(clippy::too_many_arguments)]
    fn light_pass<'a>(
        &self,
        ctx: &Context<'a>,
        driver: &Driver,
        splats: &SplatFilm,
        paths: &mut LightPaths,
        sums: &mut Film,
        it: u32,
        light_paths: u64,
    ) -> Option<u64> {
        let settings = driver.settings;
        let pixels = light_paths;
        let mut rays = 0;
        let width = settings.width as u64;
        let film_width = ctx.scene.camera.width as u64;
        paths.vertices.clear();
        paths.ends.clear();
        let interrupted = AtomicBool::new(false);
        let mut batch = 0;
        while batch < pixels {
            let batch_end = (batch + DRAIN_PATHS).min(pixels);
            let chunks = (batch_end - batch).div_ceil(CHUNK);
            // Each chunk's vertices and path lengths, joined in chunk order afterwards.
            let traced: Vec<(Vec<LightVertex>, Vec<u32>, RayStats, u64)> = (0..chunks)
                .into_par_iter()
                .map(|c| {
                    // Sized for a few vertices per path: grown vectors were copied again and again.
                    let mut out = (
                        Vec::with_capacity(4 * CHUNK as usize),
                        Vec::with_capacity(CHUNK as usize),
                        RayStats::default(),
                        0u64,
                    );
                    if driver.cancelled() {
                        interrupted.store(true, Ordering::Relaxed);
                        return out;
                    }
                    let (vertices, lengths, stats, bad) = (&mut out.0, &mut out.1, &mut out.2, &mut out.3);
                    let from = batch + c * CHUNK;
                    for k in from..(from + CHUNK).min(batch_end) {
                        let (x, y) = (k % width + settings.origin.0 as u64, k / width + settings.origin.1 as u64);
                        let seed = hash_seed(&[settings.seed, LIGHT_STREAM, y * film_width + x, it as u64]);
                        let mut rng = Rng32::new(seed);
                        let before = vertices.len();
                        subpath::trace_light_path(ctx, &mut rng, stats, |v, bsdf, rng, stats| {
                            if let Some((raster, layers)) =
                                strategy::connect_to_camera(ctx, v, bsdf, rng.uniform2(), stats)
                                && !splats.add(raster, &layers)
                            {
                                *bad += 1;
                            }
                            vertices.push(*v);
                        });
                        lengths.push((vertices.len() - before) as u32);
                    }
                    out
                })
                .collect();
            if interrupted.load(Ordering::Relaxed) {
                return None;
            }
            for (vertices, lengths, stats, bad) in traced {
                rays += stats.total();
                for n in lengths {
                    let end = paths.ends.last().copied().unwrap_or(0) + n;
                    paths.ends.push(end);
                }
                paths.vertices.extend(vertices);
                driver.record(&stats, bad, 0);
            }
            // The last batch's splats wait for the camera pass's drain (`iteration`): one drain
            // of the image per iteration instead of two. A pixel then receives at most
            // `DRAIN_PATHS` light paths' splats and one camera path's value between drains.
            if batch_end < pixels {
                splats.drain_into(sums);
            }
            batch = batch_end;
        }
        Some(rays)
    }

    /// Traces each pixel's camera subpath of iteration `it`, connecting it to the pixel's own
    /// light path and merging it with every light vertex within `radius`; adds it to its pixel.
    #[allow(clippy::too_many_arguments)]
    fn camera_pass(
        &self,
        ctx: &Context,
        driver: &Driver,
        splats: &SplatFilm,
        paths: &LightPaths,
        it: u32,
        radius: f32,
        m: u32,
        probe: Option<&mut Probe>,
        count: bool,
    ) -> bool {
        let radii = (radius, radius * self.config.wide_reach);
        let settings = driver.settings;
        let pixels = settings.pixels();
        let interrupted = AtomicBool::new(false);
        let probing = probe.is_some();
        let counts = (0..pixels.div_ceil(CHUNK)).into_par_iter().map(|c| {
            let mut tally = (0u64, 0u64);
            if driver.cancelled() {
                interrupted.store(true, Ordering::Relaxed);
                return tally;
            }
            let mut stats = RayStats::default();
            // The BSDFs of the pixel's light path (its vertices are read where they are stored).
            let mut own_bsdfs = Vec::new();
            let mut bad = 0;
            let from = c * CHUNK;
            let to = (from + CHUNK).min(pixels);
            for k in from..to {
                let (x, y) = ((k % settings.width as u64) as u32, (k / settings.width as u64) as u32);
                let (mut sampler, ray, weight) = settings.camera_sample(ctx.scene, x, y, it);
                // This pixel's light path, for connections, if it has one in this iteration.
                let own: &[LightVertex] = if (k + u64::from(it)).is_multiple_of(u64::from(m)) {
                    paths.path((k / u64::from(m)) as usize)
                } else {
                    &[]
                };
                own_bsdfs.clear();
                own_bsdfs.extend(own.iter().map(|v| ctx.light_bsdf(v)));
                let mut merges = 0u64;
                let before = stats.total();
                let mut layers =
                    subpath::trace_camera_path(ctx, &mut sampler, ray, own, &own_bsdfs, &mut stats, |x, layers, _| {
                        merges += u64::from(merge(ctx, x, paths, radii, layers))
                    });
                if weight != 1.0 {
                    layers = layers.map(|c| c * weight);
                }
                if !splats.add_pixel(x, y, &layers) {
                    bad += 1;
                }
                if probing {
                    tally.0 += stats.total() - before;
                    tally.1 += merges;
                }
            }
            driver.record(&stats, bad, if count { to - from } else { 0 });
            tally
        });
        let (rays, merges) = counts.reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        if let Some(p) = probe {
            p.rays += rays;
            p.merges += merges;
        }
        !interrupted.load(Ordering::Relaxed)
    }
}

/// What a merge reads of a light vertex (`LightVertex`'s fields of the same names), kept in the
/// grid's slot order: the vertices a query finds lie together in memory, where reading each from
/// the path-ordered vertices was a cache miss per vertex and half of a caustic box's render.
#[derive(Clone, Copy, Debug)]
struct MergeVertex {
    wo: Vec3,
    beta: Color,
    mis: mis::SubpathMis,
    depth: u32,
    bounces: u32,
    delta_only: bool,
    hero_only: bool,
}

impl MergeVertex {
    fn of(v: &LightVertex) -> Self {
        MergeVertex {
            wo: v.wo,
            beta: v.beta.get(),
            mis: v.mis,
            depth: v.depth,
            bounces: u32::from(v.bounces),
            delta_only: v.delta_only,
            hero_only: v.hero_only,
        }
    }
}

/// Merges camera vertex `x` with every light vertex within the merge radius of its class
/// (`radii`: narrow and wide; the report's eq. 37-39: each merge weighted against the
/// connections and other merges that make the same path), adding the estimate by layer to
/// `layers`. Returns the light vertices found.
fn merge(ctx: &Context, x: &strategy::CameraVertex, paths: &LightPaths, radii: (f32, f32), layers: &mut Layers) -> u32 {
    // Merges only at the camera path's first non-delta vertex (`MisFactors::merge_first_only`).
    if !ctx.factors.merges_at(x.layer.before_x()) {
        return 0;
    }
    let mut candidates = 0;
    let p = x.hit.p;
    // A Lambertian camera vertex samples its `wo` with one density from every direction above
    // it (`Bsdf::pdf_reverse` does not read the other direction there): worked out at the first
    // light vertex above it and kept, the same number `reverse_pdf` would give each.
    let lambertian = x.bsdf.lambert_albedo().is_some();
    // The usual camera vertex, one Lambertian lobe, evaluated without `eval`'s dispatch.
    let one = x.bsdf.one_lambert();
    let ng = x.bsdf.geometric_normal();
    let mut rev_above: Option<f32> = None;
    // The density estimate's kernel (narrow and wide) and the number of light paths.
    let light_paths = paths.ends.len().max(1) as f32;
    let (r2, wide_r2) = (radii.0 * radii.0, radii.1 * radii.1);
    let norms = (1.0 / (std::f32::consts::PI * r2 * light_paths), 1.0 / (std::f32::consts::PI * wide_r2 * light_paths));
    let mut sum = [Color::ZERO; 4];
    paths.grid.for_each_within(p, radii.0.max(radii.1), |found| {
        let y = &paths.merges[found.slot as usize];
        // Focused light within the narrow radius (the grid holds no `Reach::Direct` vertex).
        let focused = Reach::of(y.depth, y.delta_only) == Reach::Focused;
        if focused && found.d2 > r2 {
            return;
        }
        candidates += 1;
        if y.depth + x.depth > ctx.max_depth + 1 {
            return;
        }
        let (f, pdf) = match &one {
            Some(one) => one.eval(y.wo),
            None => x.bsdf.eval(x.wo, y.wo, Transport::Radiance),
        };
        if f == Color::ZERO {
            return;
        }
        let reverse =
            || strategy::reverse_pdf(ctx.scene, x.hit, x.bsdf, x.wo, y.wo, Transport::Importance, ctx.wl.as_ref());
        let rev = if lambertian && y.wo.dot(ng) > 0.0 { *rev_above.get_or_insert_with(reverse) } else { reverse() };
        let (vm, norm) = if focused { (ctx.factors.vm, norms.0) } else { (ctx.factors.vm_wide, norms.1) };
        let w = mis::merge_weight(&x.mis, &y.mis, pdf as f64, rev as f64, vm);
        // Both paths past dispersive glass: the merged path takes the hero's factor once.
        sum[strategy::light_layer(y.bounces, y.delta_only, x.layer, 1)] +=
            joined(f * y.beta * (w as f32 * norm), x.hero_only, y.hero_only);
    });
    for (l, s) in layers.iter_mut().zip(sum) {
        *l += x.beta * s;
    }
    candidates
}

impl Vcm {
    /// Camera paths per light path in the last render (`LightBudget`; 0 before any).
    pub fn light_divisor(&self) -> u32 {
        self.divisor.load(Ordering::Relaxed)
    }

    /// Made for `scene` rendered with `settings` from the description `desc`.
    pub fn new(desc: &IntegratorDesc, scene: &Scene, settings: &RenderSettings) -> Self {
        Vcm { config: VcmConfig::new(desc, scene, settings), divisor: AtomicU32::new(0) }
    }
}

#[cfg(test)]
mod tests {
    use super::LightBudget;
    use crate::sampling::Rng32;

    /// Two iterations' values per pixel: a flat image plus noise of standard deviation `sigma`.
    fn pair(rng: &mut Rng32, n: usize, sigma: f32) -> (Vec<f32>, Vec<f32>) {
        let mut noisy =
            || (0..n).map(|_| 1.0 + sigma * (rng.uniform() + rng.uniform() + rng.uniform() - 1.5) * 2.0).collect();
        (noisy(), noisy())
    }

    #[test]
    fn the_variance_of_an_iteration_is_read_from_two() {
        // The noise, 2 sigma (u1 + u2 + u3 - 1.5), has variance sigma^2 per pixel: summed over
        // the pixels, n sigma^2.
        let mut rng = Rng32::new(3);
        let (a, b) = pair(&mut rng, 40_000, 0.1);
        let v = LightBudget::variance(&a, &b) / 40_000.0;
        assert!((v - 0.01).abs() < 0.0006, "{v}");
        // One firefly does not decide it.
        let mut b = b;
        b[17] = 1e6;
        let w = LightBudget::variance(&a, &b) / 40_000.0;
        assert!((w / v - 1.0).abs() < 0.01, "{w} vs {v}");
    }

    #[test]
    fn fewer_light_paths_are_chosen_when_their_error_times_work_is_smaller() {
        let mut rng = Rng32::new(5);
        let n = 10_000;
        let (a1, b1) = pair(&mut rng, n, 0.1);
        // 1.35 times the variance at half the work: less error x time.
        let (a4, b4) = pair(&mut rng, n, 0.1 * 1.35f32.sqrt());
        assert_eq!(LightBudget::divisor((&a1, &b1, 100.0), (&a4, &b4, 50.0)), LightBudget::PROBE_DIVISOR);
        // Twice the variance at 0.6 of the work: more; one light path per pixel stays.
        let (a4, b4) = pair(&mut rng, n, 0.1 * 2f32.sqrt());
        assert_eq!(LightBudget::divisor((&a1, &b1, 100.0), (&a4, &b4, 60.0)), 1);
    }
}
