//! The `render` command as a library function: load, check the output, render on a pool of the
//! requested size, write the image. `main.rs` only parses arguments and reports errors.

use crate::film::output::{OutputError, check_writable, write_image};
use crate::integrator::{IntegratorKind, LAYER_NAMES, PathTracer, PhotonIntegrator, Whitted};
use crate::render::{RenderControl, RenderSettings, RenderStats, render_layers};
use crate::scene::{Overrides, SceneError, load_scene};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Duration;

#[derive(Clone, Debug, Default)]
pub struct RenderOptions {
    pub scene: PathBuf,
    /// Output image; defaults to the scene's file name with `.png` in the current folder.
    pub output: Option<PathBuf>,
    pub overrides: Overrides,
    /// Worker threads; all cores when `None`.
    pub threads: Option<usize>,
    pub time_limit: Option<Duration>,
    pub checkpoint: Option<Duration>,
    pub quiet: bool,
    /// Write the four light layers next to the output.
    pub layers: bool,
    /// Memory budget for photon maps in bytes (default: half the machine's memory).
    pub max_memory: Option<u64>,
}

#[derive(Debug, thiserror::Error)]
pub enum AppError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Output(#[from] OutputError),
    #[error("cannot start {threads} worker threads: {message}")]
    Threads { threads: usize, message: String },
    #[error("--threads must be at least 1")]
    ZeroThreads,
    #[error(
        "the render would need about {need_mib} MiB, more than the {limit_mib} MiB allowed; \
         use a smaller image, fewer photons (--photons, --caustic-photons, --photons-per-iter) \
         or raise --max-memory"
    )]
    Memory { need_mib: u64, limit_mib: u64 },
    #[error("interrupted: wrote `{path}` with {samples} samples per pixel")]
    Interrupted { path: String, samples: u32 },
}

/// What a finished render reports.
pub struct Summary {
    pub output: PathBuf,
    pub stats: RenderStats,
}

/// Default output path for a scene file: its stem with `.png`, in the current folder.
pub fn default_output(scene: &Path) -> PathBuf {
    let stem = scene.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "render".into());
    PathBuf::from(format!("{stem}.png"))
}

/// Bytes the render of `loaded` with `settings` will allocate: the film (with its layers), the
/// output image, and the integrator's own data (photon maps, SPPM state). Geometry is already
/// loaded by then and is not counted.
pub fn estimate_render_bytes(loaded: &crate::scene::load::LoadedScene, settings: &RenderSettings) -> u64 {
    let pixels = settings.width as u64 * settings.height as u64;
    let per_pixel = 16 + 12 + if settings.layers { 48 + 4 * 12 } else { 0 };
    let film = pixels * per_pixel;
    let integrator = match loaded.integrator.kind {
        IntegratorKind::Whitted | IntegratorKind::Path => 0,
        IntegratorKind::Photon => {
            let c = loaded.integrator.photon.resolve(&loaded.scene, &loaded.integrator, settings.seed);
            // Up to four stored bounces per global photon, plus the irradiance records.
            crate::integrator::photon::estimated_map_bytes(c.photons.saturating_mul(5))
                + crate::integrator::photon::estimated_map_bytes(c.caustic_photons)
        }
        IntegratorKind::Sppm => {
            let c = loaded.integrator.photon.sppm(&loaded.integrator, pixels);
            crate::integrator::sppm::estimated_bytes(pixels, c.photons_per_iter)
        }
    };
    film.saturating_add(integrator)
}

/// `out.png` -> `out.direct.png` for layer `direct`.
pub fn layer_path(output: &Path, layer: &str) -> PathBuf {
    let stem = output.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let ext = output.extension().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    output.with_file_name(format!("{stem}.{layer}.{ext}"))
}

/// Total memory of the machine in bytes (from /proc/meminfo; 8 GiB when unknown).
pub fn system_memory() -> u64 {
    std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|s| {
            let line = s.lines().find(|l| l.starts_with("MemTotal:"))?;
            let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
            Some(kib * 1024)
        })
        .unwrap_or(8 << 30)
}

fn log(quiet: bool, msg: std::fmt::Arguments) {
    if !quiet {
        eprintln!("{msg}");
    }
}

pub fn render_file(opts: &RenderOptions, cancel: &AtomicBool) -> Result<Summary, AppError> {
    let output = opts.output.clone().unwrap_or_else(|| default_output(&opts.scene));
    // Fail on an unusable output before spending any time.
    check_writable(&output)?;
    if opts.threads == Some(0) {
        return Err(AppError::ZeroThreads);
    }
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = opts.threads {
        builder = builder.num_threads(n);
    }
    let pool = builder
        .build()
        .map_err(|e| AppError::Threads { threads: opts.threads.unwrap_or(0), message: e.to_string() })?;
    pool.install(|| {
        let loaded = load_scene(&opts.scene, &opts.overrides)?;
        let info = &loaded.info;
        log(
            opts.quiet,
            format_args!(
                "scene {}: {} primitives ({} triangles{}), {} planes, {} lights; BVH {} nodes in {:.1} ms",
                opts.scene.display(),
                info.primitives,
                info.triangles,
                if info.degenerate_triangles > 0 {
                    format!(", {} degenerate skipped", info.degenerate_triangles)
                } else {
                    String::new()
                },
                loaded.scene.planes.len(),
                loaded.scene.lights.len(),
                info.bvh_nodes,
                info.bvh_build.as_secs_f64() * 1e3,
            ),
        );
        let mut settings: RenderSettings = loaded.settings.clone();
        settings.time_limit = opts.time_limit;
        settings.checkpoint = opts.checkpoint;
        settings.progress = !opts.quiet;
        if opts.time_limit.is_some() && opts.overrides.spp.is_none() && opts.overrides.spp_axis.is_none() {
            // A time budget without a sample count renders until the time is up.
            settings.spp = u32::MAX;
        }
        let checkpoint = |img: &crate::film::Image, spp: u32| match write_image(img, &output) {
            Ok(()) => log(opts.quiet, format_args!("checkpoint: wrote {} ({spp} spp)", output.display())),
            Err(e) => eprintln!("warning: checkpoint failed: {e}"),
        };
        let control = RenderControl { cancel, on_checkpoint: Some(&checkpoint) };
        settings.layers = opts.layers;
        // Everything big the render will allocate, estimated before any of it is.
        let need = estimate_render_bytes(&loaded, &settings);
        let limit = opts.max_memory.unwrap_or_else(|| system_memory() / 2);
        log(opts.quiet, format_args!("memory: about {} MiB needed (limit {} MiB)", need.div_ceil(1 << 20), limit >> 20));
        if need > limit {
            return Err(AppError::Memory { need_mib: need.div_ceil(1 << 20), limit_mib: limit >> 20 });
        }
        let (image, layers, stats) = match loaded.integrator.kind {
            IntegratorKind::Whitted => {
                render_layers(&loaded.scene, &Whitted::new(&loaded.integrator), &settings, &control)
            }
            IntegratorKind::Path => {
                render_layers(&loaded.scene, &PathTracer { max_depth: loaded.integrator.max_depth }, &settings, &control)
            }
            IntegratorKind::Sppm => {
                let pixels = settings.width as u64 * settings.height as u64;
                let config = loaded.integrator.photon.sppm(&loaded.integrator, pixels);
                if opts.layers {
                    eprintln!("warning: --layers is not available with sppm; writing the image only");
                }
                let (img, stats) = crate::integrator::sppm::render_sppm(&loaded.scene, &config, &settings, &control);
                log(
                    opts.quiet,
                    format_args!(
                        "sppm: {} iterations of {} photons, {:.1} iterations/s, working memory {:.1} MiB",
                        stats.passes,
                        config.photons_per_iter,
                        stats.passes as f64 / stats.wall.as_secs_f64().max(1e-9),
                        stats.memory_bytes as f64 / 1048576.0
                    ),
                );
                (img, Vec::new(), stats)
            }
            IntegratorKind::Photon => {
                let config = loaded.integrator.photon.resolve(&loaded.scene, &loaded.integrator, settings.seed);
                log(opts.quiet, format_args!(
                    "photon maps: up to {} global photons (bounces included) and {} caustic photons",
                    config.photons.saturating_mul(4), config.caustic_photons));
                let pm = PhotonIntegrator::build(&loaded.scene, config);
                let s = &pm.stats;
                log(opts.quiet, format_args!(
                    "photons: global {} emitted, {} stored ({:.1} MiB); caustic {} emitted, {} stored ({:.1} MiB){}; traced in {:.2} s, maps built in {:.2} s",
                    s.global_emitted, s.global_stored, s.global_bytes as f64 / 1048576.0,
                    s.caustic_emitted, s.caustic_stored, s.caustic_bytes as f64 / 1048576.0,
                    if s.caustic_capped { " (emission cap reached)" } else { "" },
                    s.trace_time.as_secs_f64(), s.build_time.as_secs_f64()));
                render_layers(&loaded.scene, &pm, &settings, &control)
            }
        };
        for (img, name) in layers.iter().zip(LAYER_NAMES) {
            write_image(img, &layer_path(&output, name))?;
        }
        write_image(&image, &output)?;
        if stats.nonfinite_samples > 0 {
            eprintln!("warning: {} samples were NaN or infinite and were dropped", stats.nonfinite_samples);
        }
        log(
            opts.quiet,
            format_args!(
                "rendered {}x{} at {} spp in {:.2} s: {} rays ({} shadow), {:.2} Mrays/s -> {}",
                settings.width,
                settings.height,
                stats.samples_per_pixel,
                stats.wall.as_secs_f64(),
                stats.rays.total(),
                stats.rays.shadow_rays,
                stats.mrays_per_second(),
                output.display()
            ),
        );
        if stats.interrupted {
            return Err(AppError::Interrupted { path: output.display().to_string(), samples: stats.samples_per_pixel });
        }
        Ok(Summary { output: output.clone(), stats })
    })
}
