//! The `render` command as a library function: load, check the output, render on a pool of the
//! requested size, write the image. `main.rs` only parses arguments and reports errors.

use crate::film::output::{OutputError, check_writable, write_image};
use crate::integrator::{IntegratorKind, PathTracer, Whitted};
use crate::render::{RenderControl, RenderSettings, RenderStats, render};
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
        let (image, stats) = match loaded.integrator.kind {
            IntegratorKind::Whitted => {
                render(&loaded.scene, &Whitted::new(&loaded.integrator), &settings, &control)
            }
            IntegratorKind::Path => {
                render(&loaded.scene, &PathTracer { max_depth: loaded.integrator.max_depth }, &settings, &control)
            }
        };
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
