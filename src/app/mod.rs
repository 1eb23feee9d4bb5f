//! The `render` command as a library function: load, check the output, render on a pool of the
//! requested size, write the image (or, for a render-farm shard, its partial image). `main.rs`
//! only parses arguments and reports errors.

mod farm;
mod shard;

pub use farm::{SlurmOptions, farm_slurm, merge_files};

use crate::display::DisplayTarget;
use crate::farm::FarmError;
use crate::farm::shard::{Shard, ShardSpec};
use crate::film::aov::AovKind;
use crate::film::output::{
    ColourSpace, Format, OutputError, aov_path, check_writable, layer_path, write_exr_channels, write_image_in,
};
use crate::film::{BYTES_PER_PIXEL, Film, LAYER_BYTES_PER_PIXEL, LAYER_NAMES};
use crate::integrator::Integrator;
use crate::options::{IntegratorKind, Options};
use crate::progress::Display;
use crate::render::{CheckpointFn, Meter, RenderControl, RenderSettings, RenderStats};
use crate::scene::desc::{IntegratorDesc, LoadInfo};
use crate::scene::footprint::Footprint;
use crate::scene::{FileBudget, LoadOptions, Scene, SceneDescription, SceneError, load_scene, load_scene_within};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Duration;

#[derive(Clone, Debug, Default)]
pub struct RenderOptions {
    pub scene: PathBuf,
    /// Output image; defaults to the scene's file name with `.png` in the current folder.
    pub output: Option<PathBuf>,
    /// The command line's options, each replacing the scene file's value when given.
    pub overrides: Options,
    /// How the file is read (`-D` parameters, `--set` values, `--strict`).
    pub load: LoadOptions,
    /// Worker threads; all cores when `None`.
    pub threads: Option<usize>,
    pub time_limit: Option<Duration>,
    pub checkpoint: Option<Duration>,
    pub quiet: bool,
    /// Write the four light layers next to the output.
    pub layers: bool,
    /// Memory budget for photon maps in bytes (default: half the machine's memory).
    pub max_memory: Option<u64>,
    /// Render only this shard of the samples, to a partial image (see `farm`).
    pub shard: Option<ShardSpec>,
}

#[derive(Debug, thiserror::Error)]
pub enum AppError {
    /// A scene that could not be loaded (one that would not fit in memory is `SceneMemory`).
    #[error(transparent)]
    Scene(SceneError),
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
    #[error(
        "loading the scene would need about {need_mib} MiB ({detail}), more than the {limit_mib} MiB \
         allowed; raise --max-memory if the machine has it"
    )]
    SceneMemory { need_mib: u64, limit_mib: u64, detail: String },
    #[error("interrupted: wrote `{path}` with {samples} samples per pixel")]
    Interrupted { path: String, samples: u32 },
    /// A shard stopped early: its finished samples are saved and a rerun continues from them.
    #[error(
        "interrupted: saved `{path}` holding samples {held} of shard {shard}; run the same command again to resume"
    )]
    ShardInterrupted { path: String, held: String, shard: String },
    #[error("--shard: {0}")]
    Shard(String),
    #[error(transparent)]
    Farm(#[from] FarmError),
    /// Stopped before a complete pass: nothing is written, so a previous image stays as it was.
    #[error(
        "interrupted before the first complete pass: `{path}` was not written{}",
        if *existed { " and is left as it was" } else { "" }
    )]
    InterruptedEarly { path: String, existed: bool },
    /// A render kept in memory (not written to a file) was stopped before a complete pass.
    #[error("interrupted before the first complete pass")]
    Cancelled,
}

impl From<SceneError> for AppError {
    /// A load stopped by the memory limit becomes `SceneMemory`, with the limit's option named.
    fn from(e: SceneError) -> Self {
        match e {
            SceneError::Memory(o) => AppError::SceneMemory {
                need_mib: o.need.div_ceil(1 << 20),
                limit_mib: o.limit >> 20,
                detail: format!("{} would add about {} MiB and was not read", o.what, o.bytes.div_ceil(1 << 20)),
            },
            e => AppError::Scene(e),
        }
    }
}

/// What a finished render reports.
pub struct Summary {
    /// The file written (a shard's partial image), or `None` for a render kept in memory.
    pub output: Option<PathBuf>,
    pub stats: RenderStats,
    /// The render itself, when it was kept in memory rather than written.
    pub render: Option<crate::render::RenderOutput>,
}

/// Default output path for a scene file: its stem with `.png`, in the current folder.
pub fn default_output(scene: &Path) -> PathBuf {
    let stem = scene.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "render".into());
    PathBuf::from(format!("{stem}.png"))
}

/// A scene loaded, with the command-line overrides applied and built: ready to render.
pub struct LoadedScene {
    pub scene: Scene,
    pub settings: RenderSettings,
    pub integrator: IntegratorDesc,
    pub info: LoadInfo,
    /// What the loader could not render exactly, each `file:line:col: message`.
    pub warnings: Vec<String>,
}

/// Loads a scene file, applies `overrides` over its values (`SceneDescription::apply`) and builds
/// the scene.
pub fn load(path: &Path, options: &LoadOptions, overrides: &Options) -> Result<LoadedScene, SceneError> {
    prepare(load_scene(path, options)?, overrides)
}

/// `load` for a scene in caustic's TOML format given as text (`name` in messages, mesh paths
/// relative to `base`).
pub fn load_toml_str(text: &str, name: &str, base: &Path, overrides: &Options) -> Result<LoadedScene, SceneError> {
    prepare(crate::scene::load_scene_str(text, name, base)?, overrides)
}

/// Applies the overrides to a description and builds it.
pub fn prepare(mut desc: SceneDescription, overrides: &Options) -> Result<LoadedScene, SceneError> {
    desc.apply(overrides);
    let warnings = std::mem::take(&mut desc.warnings);
    // Shown under the scene's name unless the render names it after its output.
    let display = overrides.display_server.clone().map(|address| DisplayTarget { address, name: desc.name.clone() });
    let built = desc.build()?;
    Ok(LoadedScene {
        settings: RenderSettings { display, ..RenderSettings::new(&built.sampling) },
        scene: built.scene,
        integrator: built.integrator,
        info: built.info,
        warnings,
    })
}

impl LoadedScene {
    /// Renders with the scene's own integrator and settings (no time limit, progress or
    /// cancellation).
    pub fn render(&self) -> crate::render::RenderOutput {
        let control = RenderControl::uncancelled();
        match Integrator::new(&self.integrator, &self.scene, &self.settings, &control) {
            Ok(integrator) => integrator.render(&self.scene, &self.settings, &control),
            Err(_) => unreachable!("the flag of an uncancelled render is never set"),
        }
    }
}

/// Bytes the render of `loaded` with `settings` needs: the film (with its layers), the output
/// image, the integrator's own data (photon maps, SPPM state), and the environment map's texels
/// and sampling distribution (loaded already, but as large as a photon map for a big image).
/// Other geometry is already loaded by then and is not counted.
pub fn estimate_render_bytes(loaded: &LoadedScene, settings: &RenderSettings) -> u64 {
    let image = 12;
    let per_pixel = BYTES_PER_PIXEL
        + image
        + if settings.layers { LAYER_BYTES_PER_PIXEL + 4 * image } else { 0 }
        + settings.aovs.summed_channels() as u64 * 16
        + settings.aovs.channel_names().len() as u64 * 4;
    let film = settings.pixels() * per_pixel;
    film.saturating_add(crate::integrator::estimated_bytes(&loaded.integrator, &loaded.scene, settings))
        .saturating_add(loaded.scene.environment_bytes())
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

/// A line of a render's log: above the progress bar on a terminal, nothing with `--quiet`.
fn say(display: &Display, msg: std::fmt::Arguments) {
    if display.enabled() {
        display.say(&msg.to_string());
    }
}

/// Reads `opts.scene` and renders it to `opts.output` (or, with `opts.shard`, renders that shard
/// to its partial image): `caustic render`.
pub fn render_file(opts: &RenderOptions, cancel: &AtomicBool) -> Result<Summary, AppError> {
    let output = opts.output.clone().unwrap_or_else(|| default_output(&opts.scene));
    // Fail on an unusable output before spending any time.
    let format = check_writable(&output)?;
    if opts.shard.is_none() {
        ColourSpace::xyz_if(opts.overrides.xyz == Some(true)).check(&output)?;
    }
    let shard = resolve_shard(opts, format)?;
    thread_pool(opts.threads)?.install(|| {
        // The loaders report each file (and the builder each generated mesh and instance) to the
        // budget before reading it, and the load stops at the first that would not fit.
        let files = FileBudget::new(memory_limit(opts));
        // The summary reports every phase, so its total is the wall time a user measures.
        let started = std::time::Instant::now();
        // One display for the whole run: the load, the integrator's preparation and the passes
        // are its phases, and `--time` counts from here as the bar does.
        let display = Display::new(!opts.quiet, opts.time_limit);
        let load = display.phase("load", 0);
        let desc = load_scene_within(&opts.scene, &opts.load, &files)?;
        load.end();
        let job =
            Job { output: Some(&output), shard, started, footprint: files.footprint(), meter: None, display: &display };
        render_description(desc, opts, job, cancel)
    })
}

/// Renders a scene already read (`footprint`: what reading it counted), as `render_file` renders
/// a file: the Python module's `render` and `render_shard`. With `opts.output` the image (or the
/// shard's partial image) is written there; without, it is returned in the summary. `meter`
/// counts the passes' work while they run.
pub fn render_scene(
    desc: &SceneDescription,
    footprint: Footprint,
    opts: &RenderOptions,
    cancel: &AtomicBool,
    meter: Option<&Meter>,
) -> Result<Summary, AppError> {
    let shard = match &opts.output {
        Some(output) => resolve_shard(opts, check_writable(output)?)?,
        None if opts.shard.is_some() => {
            return Err(AppError::Shard("a shard is written to a partial image: give its path".into()));
        }
        None => None,
    };
    thread_pool(opts.threads)?.install(|| {
        let started = std::time::Instant::now();
        let display = Display::new(!opts.quiet, opts.time_limit);
        let job = Job { output: opts.output.as_deref(), shard, started, footprint, meter, display: &display };
        render_description(desc.clone(), opts, job, cancel)
    })
}

/// The shard `opts` asks for, checked against the output's format and the other options.
fn resolve_shard(opts: &RenderOptions, format: Format) -> Result<Option<Shard>, AppError> {
    let Some(spec) = opts.shard else { return Ok(None) };
    let shard = spec.resolve(|k| std::env::var(k).ok()).map_err(AppError::Shard)?;
    if format != Format::Exr {
        let output = opts.output.clone().unwrap_or_else(|| default_output(&opts.scene));
        return Err(AppError::Shard(format!(
            "a shard writes a partial image, which is OpenEXR: give an output ending in .exr, not `{}`",
            output.display()
        )));
    }
    if opts.time_limit.is_some() {
        return Err(AppError::Shard(
            "--time cannot be combined with --shard: a shard renders a fixed block of samples (a shard that is \
             stopped saves what it finished and resumes when run again)"
                .into(),
        ));
    }
    Ok(Some(shard))
}

/// The worker pool a render runs on: `threads` workers, or the scheduler's CPUs, or all cores.
fn thread_pool(threads: Option<usize>) -> Result<rayon::ThreadPool, AppError> {
    let threads = threads.or_else(scheduler_cpus);
    if threads == Some(0) {
        return Err(AppError::ZeroThreads);
    }
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        builder = builder.num_threads(n);
    }
    builder.build().map_err(|e| AppError::Threads { threads: threads.unwrap_or(0), message: e.to_string() })
}

/// The memory a render may use, in bytes: `--max-memory`, or half of the machine's.
pub fn memory_limit(opts: &RenderOptions) -> u64 {
    opts.max_memory.unwrap_or_else(|| system_memory() / 2)
}

/// Where a render goes and what it has done so far.
struct Job<'a> {
    /// The image file (a shard's partial image), or `None` to return the render in memory.
    output: Option<&'a Path>,
    shard: Option<Shard>,
    /// When loading began: `--time` and the summary count from there.
    started: std::time::Instant,
    /// What loading the scene counted.
    footprint: Footprint,
    meter: Option<&'a Meter>,
    /// Where the run's phases and log lines are shown.
    display: &'a Display,
}

/// Everything after loading: applies the options, builds the scene, checks memory, prepares the
/// integrator, renders, and writes (or returns) the image.
fn render_description(
    desc: SceneDescription,
    opts: &RenderOptions,
    job: Job,
    cancel: &AtomicBool,
) -> Result<Summary, AppError> {
    let Job { output, shard, started, footprint, meter, display } = job;
    let limit = memory_limit(opts);
    let loaded = prepare(desc, &opts.overrides)?;
    let loaded_at = started.elapsed();
    if footprint.total() > 0 {
        say(
            display,
            format_args!(
                "scene files: about {} MiB (meshes {} MiB, textures {} MiB, instances {} MiB)",
                footprint.total().div_ceil(1 << 20),
                footprint.meshes.div_ceil(1 << 20),
                footprint.textures.div_ceil(1 << 20),
                footprint.instances.div_ceil(1 << 20)
            ),
        );
    }
    for w in &loaded.warnings {
        display.warn(w);
    }
    for w in opts.overrides.unused_by(loaded.integrator.kind) {
        display.warn(&w);
    }
    let kind = loaded.integrator.kind;
    if loaded.scene.has_media() && !kind.renders_media() {
        let by: Vec<&str> = IntegratorKind::ALL.iter().filter(|k| k.renders_media()).map(|k| k.name()).collect();
        display.warn(&format!(
            "the {} integrator does not render participating media: the scene's media are left out (they are rendered by: {})",
            kind.name(),
            by.join(", ")
        ));
    }
    let info = &loaded.info;
    for m in &info.meshes {
        let (lo, hi) = (m.bounds.min, m.bounds.max);
        let size = hi - lo;
        say(
            display,
            format_args!(
                "mesh {}: {} triangles, bounds ({:.4}, {:.4}, {:.4}) to ({:.4}, {:.4}, {:.4}), size {:.4} x {:.4} x {:.4}",
                m.name, m.triangles, lo.x, lo.y, lo.z, hi.x, hi.y, hi.z, size.x, size.y, size.z
            ),
        );
    }
    say(
        display,
        format_args!(
            "scene {}: {} primitives ({} triangles{}){}, {} planes, {} lights; BVH {} nodes in {:.1} ms",
            opts.scene.display(),
            info.primitives,
            info.triangles,
            if info.degenerate_triangles > 0 {
                format!(", {} degenerate skipped", info.degenerate_triangles)
            } else {
                String::new()
            },
            if info.instances > 0 {
                format!(", {} instances of {} groups", info.instances, info.instance_groups)
            } else {
                String::new()
            },
            loaded.scene.bvh.unbounded_len(),
            loaded.scene.lights.len(),
            info.bvh_nodes,
            info.bvh_build.as_secs_f64() * 1e3,
        ),
    );
    let mut settings: RenderSettings = loaded.settings.clone();
    // The scene file may ask for XYZ channels too (`[render] xyz`): refused for a PNG before
    // rendering. (A shard writes a partial EXR; its merge checks the final output.)
    if let (Some(output), None) = (output, &opts.shard) {
        ColourSpace::xyz_if(settings.xyz).check(output)?;
    }
    if settings.aovs.has(AovKind::Variance)
        && matches!(
            loaded.integrator.kind,
            IntegratorKind::Sppm | IntegratorKind::Light | IntegratorKind::Bdpt | IntegratorKind::Vcm
        )
    {
        // Their pixels are not means of samples: there is no sample variance to give.
        display.warn(&format!(
            "the variance AOV is not written with the {} integrator (its pixels are not means of \
             camera samples); it is written with whitted, path and photon",
            loaded.integrator.kind.name()
        ));
        settings.aovs = settings.aovs.without(AovKind::Variance);
    }
    settings.time_limit = opts.time_limit;
    settings.checkpoint = opts.checkpoint;
    settings.layers = opts.layers;
    if let (Some(viewer), Some(path)) = (&mut settings.display, output) {
        // The viewer shows the render under its file's name, as a viewer opening the file would.
        viewer.name = path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into());
    }
    if opts.time_limit.is_some() && opts.overrides.spp.is_none() && opts.overrides.spp_axis.is_none() {
        // A time budget without a sample count renders until the time is up.
        settings.spp = u32::MAX;
    }
    let say_line = |m: &str| display.say(m);
    let job = match (shard, output) {
        (Some(s), Some(output)) => {
            Some(shard::ShardJob::prepare(&loaded, &opts.load, &mut settings, s, output, &say_line)?)
        }
        _ => None,
    };
    if let Some(job) = &job
        && job.complete()
    {
        if job.output.exists() {
            say(display, format_args!("shard {} is already complete in `{}`", job.header.shard, job.output.display()));
        } else {
            // A shard of a render with fewer samples than shards has none to take.
            job.save(&job.prior)?;
            say(display, format_args!("shard {} has no samples to take; wrote an empty part", job.header.shard));
        }
        let stats = RenderStats { samples_per_pixel: job.prior.min_samples(), ..RenderStats::default() };
        return Ok(Summary { output: Some(job.output.clone()), stats, render: None });
    }
    // The phases to come and their estimated costs, for the progress bar's ETA.
    display.plan(&crate::integrator::plan(&loaded.integrator, &loaded.scene, &settings));
    let checkpoint_image = |film: &Film| {
        let Some(output) = output else { return };
        match write_image_in(&film.image(), output, ColourSpace::xyz_if(settings.xyz)) {
            Ok(()) => say(display, format_args!("checkpoint: wrote {} ({} spp)", output.display(), film.min_samples())),
            Err(e) => display.warn(&format!("checkpoint failed: {e}")),
        }
    };
    let checkpoint_partial = |film: &Film| {
        if let Some(job) = &job {
            match job.save(film) {
                Ok(()) => say(
                    display,
                    format_args!("checkpoint: saved samples {} in {}", job.held(film), job.output.display()),
                ),
                Err(e) => display.warn(&format!("checkpoint failed: {e}")),
            }
        }
    };
    let on_checkpoint: CheckpointFn = if job.is_some() { &checkpoint_partial } else { &checkpoint_image };
    let control = RenderControl { cancel, on_checkpoint: output.map(|_| on_checkpoint), progress: display, meter };
    // Everything big the render will allocate, estimated before any of it is.
    let mut need = estimate_render_bytes(&loaded, &settings) + loaded.scene.geometry_bytes();
    if job.is_some() {
        // A shard keeps its earlier run's film and writes its partial image from columns.
        let partial = 64 + if settings.layers { 240 } else { 0 };
        need += settings.pixels() * (crate::film::BYTES_PER_PIXEL + partial);
    }
    // Loading peaks higher than the loaded scene (the BVH's build temporaries): the larger
    // of the footprint counted while loading and what rendering holds is the peak.
    say(
        display,
        format_args!(
            "memory: about {} MiB at peak (loading {} MiB; rendering {} MiB, of which the loaded geometry {} MiB; limit {} MiB)",
            need.max(footprint.total()).div_ceil(1 << 20),
            footprint.total().div_ceil(1 << 20),
            need.div_ceil(1 << 20),
            loaded.scene.geometry_bytes().div_ceil(1 << 20),
            limit >> 20
        ),
    );
    if need > limit {
        return Err(AppError::Memory { need_mib: need.div_ceil(1 << 20), limit_mib: limit >> 20 });
    }
    if loaded.integrator.kind == IntegratorKind::Photon {
        let c = crate::integrator::photon::PhotonConfig::new(
            &loaded.integrator.photon,
            &loaded.integrator,
            &loaded.scene,
            settings.seed,
        );
        say(
            display,
            format_args!(
                "photon maps: {} photons emitted for the global map (stored at each diffuse bounce); caustic \
                 photons emitted until {} are stored (at most {} emitted)",
                c.photons, c.caustic_photons, c.caustic_cap
            ),
        );
    }
    let early = || match output {
        Some(path) => AppError::InterruptedEarly { path: path.display().to_string(), existed: path.exists() },
        None => AppError::Cancelled,
    };
    let prepare_from = started.elapsed();
    let Ok(integrator) = Integrator::new(&loaded.integrator, &loaded.scene, &settings, &control) else {
        return Err(early());
    };
    let prepared = started.elapsed() - prepare_from;
    if let Integrator::Photon(pm) = &integrator {
        let s = &pm.stats;
        say(
            display,
            format_args!(
                "photon maps ready: global {1} stored from {0} emitted ({2:.1} MiB); caustic {4} stored from {3} emitted ({5:.1} MiB){6}; traced in {7:.2} s, maps built in {8:.2} s",
                s.global_emitted,
                s.global_stored,
                s.global_bytes as f64 / 1048576.0,
                s.caustic_emitted,
                s.caustic_stored,
                s.caustic_bytes as f64 / 1048576.0,
                if s.caustic_capped { " (emission cap reached)" } else { "" },
                s.trace_time.as_secs_f64(),
                s.build_time.as_secs_f64()
            ),
        );
        if s.volume_stored > 0 {
            say(
                display,
                format_args!(
                    "volume photon map: {} photons; estimates of {} within {:.4}",
                    s.volume_stored, pm.config.volume_k, pm.config.volume_radius
                ),
            );
        }
    }
    let film = match &job {
        Some(job) => job.prior.clone(),
        None => settings.new_film(),
    };
    // `--time` counts from the start of the load, so it bounds the whole run: what is left
    // after loading and preparation goes to the render (at least one pass is rendered).
    let mut render_settings = settings.clone();
    if let Some(limit) = opts.time_limit {
        render_settings.time_limit = Some(limit.saturating_sub(started.elapsed()).max(Duration::from_millis(1)));
    }
    let out = integrator.render_from(&loaded.scene, &render_settings, &control, film);
    let stats = out.stats.clone();
    if let Integrator::Sppm(sppm) = &integrator {
        say(
            display,
            format_args!(
                "sppm took {} iterations of {:.0} photons{}, {:.1} iterations/s,{} working memory {:.1} MiB",
                stats.samples_per_pixel,
                sppm.mean_photons_per_iter(),
                if sppm.config.adaptive_photons { " on average (adaptive)" } else { "" },
                stats.samples_per_pixel as f64 / stats.wall.as_secs_f64().max(1e-9),
                match sppm.volume_radius() {
                    Some((a, b)) => format!(" volume radius {a:.3e} to {b:.3e},"),
                    None => String::new(),
                },
                stats.memory_bytes as f64 / 1048576.0
            ),
        );
    }
    if let Integrator::Vcm(vcm) = &integrator {
        let n = stats.samples_per_pixel;
        let last = settings.first_sample.saturating_add(n).saturating_sub(1);
        say(
            display,
            format_args!(
                "vcm took {n} iterations of {} light paths ({}), {:.1} iterations/s, merge radius {:.3e} to {:.3e}, \
                 working memory {:.1} MiB",
                settings.pixels().div_ceil(u64::from(vcm.light_divisor().max(1))),
                match (vcm.light_divisor(), vcm.config.light_divisor) {
                    (m, None) => format!("one per {m} camera paths after the pilot's four iterations, chosen"),
                    (m, Some(_)) => format!("one per {m} camera paths"),
                },
                n as f64 / stats.wall.as_secs_f64().max(1e-9),
                vcm.config.radius(settings.first_sample),
                vcm.config.radius(last),
                stats.memory_bytes as f64 / 1048576.0
            ),
        );
    }
    if let Some(job) = &job {
        return finish_shard(job, &out.film, &stats, display);
    }
    // An image with fewer than one sample in some pixel is not worth keeping, and must never
    // replace an earlier image: stop without writing.
    if stats.interrupted && stats.samples_per_pixel == 0 {
        return Err(early());
    }
    if let Some(output) = output {
        let space = ColourSpace::xyz_if(settings.xyz);
        for (img, name) in out.layers.iter().zip(LAYER_NAMES) {
            write_image_in(img, &layer_path(output, name), space)?;
        }
        write_outputs(&out.image, &out.film, output, space)?;
    }
    if stats.nonfinite_samples > 0 {
        display.warn(&format!("{} samples were NaN or infinite and counted as black", stats.nonfinite_samples));
    }
    // Preparation: photon maps and their irradiance cache, SPPM's and the light tracer's
    // set-up; nothing for the other integrators.
    let preparation = if prepared.as_secs_f64() >= 0.005 {
        format!(", {} {:.2} s", integrator.preparation_name(), prepared.as_secs_f64())
    } else {
        String::new()
    };
    say(
        display,
        format_args!(
            "rendered {}x{} at {} spp in {:.2} s (load {:.2} s{preparation}, render {:.2} s): {} rays ({} shadow), {:.2} Mrays/s -> {}",
            settings.width,
            settings.height,
            stats.samples_per_pixel,
            started.elapsed().as_secs_f64(),
            loaded_at.as_secs_f64(),
            stats.wall.as_secs_f64(),
            stats.rays.total(),
            stats.rays.shadow_rays,
            stats.mrays_per_second(),
            output.map_or_else(|| "memory".to_string(), |p| p.display().to_string())
        ),
    );
    match output {
        Some(path) if stats.interrupted => {
            Err(AppError::Interrupted { path: path.display().to_string(), samples: stats.samples_per_pixel })
        }
        Some(path) => Ok(Summary { output: Some(path.to_path_buf()), stats, render: None }),
        // Kept in memory: the caller sees `stats.interrupted` and decides.
        None => Ok(Summary { output: None, stats, render: Some(out) }),
    }
}

/// Writes the image to `output` (an EXR's colour channels in `space`) and, when the render has
/// AOVs, their channels: in the same file for an EXR, in `NAME.aovs.exr` beside a PNG.
pub fn write_outputs(
    image: &crate::film::Image,
    film: &Film,
    output: &Path,
    space: ColourSpace,
) -> Result<(), OutputError> {
    if film.aovs.is_empty() {
        return write_image_in(image, output, space);
    }
    let channels = film.aov_images();
    let size = (image.width, image.height);
    match aov_path(output) {
        Some(beside) => {
            write_image_in(image, output, space)?;
            write_exr_channels(size, None, &channels, space, &beside)
        }
        None => write_exr_channels(size, Some(image), &channels, space, output),
    }
}

/// The worker threads a scheduler gave this job (`SLURM_CPUS_PER_TASK` inside a Slurm job), used
/// when `--threads` is not given.
fn scheduler_cpus() -> Option<usize> {
    std::env::var_os("SLURM_JOB_ID")?;
    std::env::var("SLURM_CPUS_PER_TASK").ok()?.trim().parse().ok().filter(|&n| n > 0)
}

/// Saves a shard's film (unless it holds nothing new) and says how far it got.
fn finish_shard(
    job: &shard::ShardJob,
    film: &Film,
    stats: &RenderStats,
    display: &Display,
) -> Result<Summary, AppError> {
    let path = job.output.display().to_string();
    let new_samples = film.tiles.iter().flat_map(|t| &t.count).sum::<u32>()
        > job.prior.tiles.iter().flat_map(|t| &t.count).sum::<u32>();
    if new_samples || !job.output.exists() {
        job.save(film)?;
    }
    let held = job.held(film);
    if stats.nonfinite_samples > 0 {
        display.warn(&format!("{} samples were NaN or infinite and counted as black", stats.nonfinite_samples));
    }
    if stats.interrupted {
        return Err(AppError::ShardInterrupted { path, held, shard: job.header.shard.to_string() });
    }
    say(
        display,
        format_args!(
            "shard {} done: samples {held} in {} ({:.2} s, {:.2} Mrays/s)",
            job.header.shard,
            path,
            stats.wall.as_secs_f64(),
            stats.mrays_per_second()
        ),
    );
    Ok(Summary { output: Some(job.output.clone()), stats: stats.clone(), render: None })
}
