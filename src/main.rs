//! The `caustic` command line: parses arguments and hands them to the library.

use anyhow::{Context, Result};
use caustic::app::{AppError, RenderOptions, SlurmOptions, farm_slurm, merge_files, render_file};
use caustic::farm::shard::ShardSpec;
use caustic::sampling::SamplerKind;
use caustic::scene::desc::{IntegratorKind, PhotonOptions};
use caustic::scene::{LoadOptions, Overrides};
use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// caustic: a CPU ray tracer for light that bends and bounces.
#[derive(Parser)]
#[command(version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene file to a PNG (8-bit sRGB) or EXR (32-bit float linear) image.
    Render(Box<RenderArgs>),
    /// Merge the partial images of a render's shards (`render --shard`) into its image.
    Merge(MergeArgs),
    /// Split a render over a cluster's scheduler: shards as an array job, then a merge job.
    #[command(subcommand)]
    Farm(FarmCommand),
    /// Render the built-in benchmark scenes and print rays per second.
    Bench(BenchArgs),
}

#[derive(clap::Args)]
struct MergeArgs {
    /// The partial images (the `-o` files of `caustic render --shard I/N`).
    #[arg(required = true, value_name = "PART")]
    parts: Vec<PathBuf>,
    /// The merged image, .png or .exr (with --layers parts, its layers are written beside it).
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,
    /// Write the image of the samples the parts hold even when some are missing.
    #[arg(long)]
    allow_partial: bool,
    /// No summary on stderr.
    #[arg(short, long)]
    quiet: bool,
}

#[derive(Subcommand)]
enum FarmCommand {
    /// Submit to Slurm: an array job of shards (requeued on preemption) and a merge job that
    /// waits for it. The scene, its files, caustic and the output must be on a file system that
    /// every node shares.
    Slurm(Box<SlurmArgs>),
}

#[derive(clap::Args)]
struct SlurmArgs {
    #[command(flatten)]
    render: RenderArgs,
    /// Number of shards (array tasks) to split the samples into.
    #[arg(long, value_name = "N")]
    shards: u32,
    /// Slurm partition for both jobs.
    #[arg(long, value_name = "NAME")]
    partition: Option<String>,
    /// Slurm time limit of each job (sbatch --time), e.g. 2:00:00.
    #[arg(long, value_name = "TIME")]
    time_limit: Option<String>,
    /// One more sbatch option for both jobs, e.g. --sbatch-arg=--account=lab (repeatable).
    #[arg(long = "sbatch-arg", value_name = "ARG", allow_hyphen_values = true)]
    sbatch_arg: Vec<String>,
    /// Wait for the jobs, report their progress and whether the merge succeeded.
    #[arg(long)]
    wait: bool,
    /// Write the scripts next to the output but do not submit them.
    #[arg(long)]
    dry_run: bool,
}

#[derive(clap::Args)]
struct BenchArgs {
    /// Worker threads [default: all cores].
    #[arg(long, value_name = "N")]
    threads: Option<usize>,
    /// Runs of each benchmark; the best is reported.
    #[arg(long, default_value_t = 3, value_name = "N")]
    repeats: u32,
    /// Write the generated benchmark scenes (10,000 instances of a knot, 100 instanced and
    /// flattened) into this folder and exit, to render them with `caustic render`.
    #[arg(long, value_name = "DIR")]
    write_scenes: Option<PathBuf>,
}

#[derive(clap::Args, Clone, Debug, PartialEq)]
struct RenderArgs {
    /// Scene file: TOML (see docs/scene-format.md) or Mitsuba 3 XML (.xml).
    scene: PathBuf,
    /// Output image, .png or .exr [default: the scene's name with .png, in the current folder].
    #[arg(short, long, value_name = "FILE")]
    output: Option<PathBuf>,
    /// Image width in pixels (overrides the scene).
    #[arg(long, value_name = "W")]
    width: Option<u32>,
    /// Image height in pixels (overrides the scene).
    #[arg(long, value_name = "H")]
    height: Option<u32>,
    /// Samples per pixel axis: N gives N x N jittered samples per pixel (overrides the scene).
    #[arg(long, value_name = "N")]
    spp_axis: Option<u32>,
    /// Total samples per pixel, any count (overrides --spp-axis and the scene).
    #[arg(long, value_name = "N", visible_alias = "samples")]
    spp: Option<u32>,
    /// The most bounces a path may have: 1 is direct light only, each more adds a reflection or
    /// refraction (overrides the scene).
    #[arg(long, value_name = "D")]
    max_depth: Option<u32>,
    /// Whitted: reflected, refracted and shadow rays of less weight in the pixel than this go
    /// on by Russian roulette (POV-Ray's adc_bailout; 0 ends none) [default: 1/255].
    #[arg(long, value_name = "W", value_parser = unit_interval)]
    adc_bailout: Option<f32>,
    /// Worker threads [default: all cores].
    #[arg(long, value_name = "N")]
    threads: Option<usize>,
    /// Seed of all random sampling; the same seed gives the same image on any thread count.
    #[arg(long, value_name = "S")]
    seed: Option<u64>,
    /// The rendering algorithm (overrides the scene).
    #[arg(long, value_name = "NAME", value_enum)]
    integrator: Option<IntegratorArg>,
    /// Sample pattern: jittered or sobol.
    #[arg(long, value_name = "NAME")]
    sampler: Option<SamplerKind>,
    /// Trace every ray through the pixel centre (only the lens is sampled).
    #[arg(long)]
    no_antialias: bool,
    /// Photons emitted for the global photon map (photon integrator).
    #[arg(long, value_name = "N")]
    photons: Option<u64>,
    /// Caustic photons to store (photon integrator; 0 disables caustics).
    #[arg(long, value_name = "N")]
    caustic_photons: Option<u64>,
    /// Final-gather rays per sample; 0 reads the global photon map directly (fast preview).
    #[arg(long, value_name = "N")]
    gather: Option<u32>,
    /// Photons per radiance estimate.
    #[arg(long, value_name = "K")]
    gather_k: Option<usize>,
    /// Irradiance cache error threshold (Ward's a): indirect diffuse light is interpolated
    /// between final gathers made before rendering where it is smooth; smaller is more accurate
    /// and slower; 0 turns the cache off and gathers at every sample [default: 0.25; see
    /// docs/scene-format.md for what it trades].
    #[arg(long, value_name = "A")]
    irradiance_cache: Option<f32>,
    /// Final-gather rays per irradiance-cache record [default: 512].
    #[arg(long, value_name = "N")]
    cache_rays: Option<u32>,
    /// Largest radius of a radiance estimate, in scene units [default: 5% of the scene's size].
    #[arg(long, value_name = "R")]
    max_radius: Option<f32>,
    /// SPPM iterations (the same as --spp for sppm: one sample per pixel per iteration).
    #[arg(long, value_name = "N")]
    iterations: Option<u32>,
    /// SPPM photons per iteration [default: one per pixel].
    #[arg(long, value_name = "N")]
    photons_per_iter: Option<u64>,
    /// SPPM starting search radius in scene units [default: about two pixel footprints].
    #[arg(long, value_name = "R")]
    initial_radius: Option<f32>,
    /// Also write the direct, specular, caustic and indirect parts as OUT.direct.EXT etc.
    #[arg(long)]
    layers: bool,
    /// Refuse to render when photon maps would need more memory than this, in MiB
    /// [default: half of the machine's memory].
    #[arg(long, value_name = "MIB")]
    max_memory: Option<u64>,
    /// Stop starting new passes after this many seconds and write the image so far.
    #[arg(long, value_name = "SECONDS")]
    time: Option<f64>,
    /// Rewrite the output image every this many seconds during the render.
    #[arg(long, value_name = "SECONDS")]
    checkpoint: Option<f64>,
    /// No progress bar or summary on stderr.
    #[arg(short, long)]
    quiet: bool,
    /// Render shard I of N of the samples (counting from 0) to a partial image (.exr) for
    /// `caustic merge`; `auto/N` takes I from SLURM_ARRAY_TASK_ID, JOB_COMPLETION_INDEX or
    /// AWS_BATCH_JOB_ARRAY_INDEX. Run again after a stop, it resumes.
    #[arg(long, value_name = "I/N")]
    shard: Option<ShardSpec>,
    /// Mitsuba scenes: give parameter `$NAME` the value VALUE (repeatable; wins over <default>).
    #[arg(short = 'D', value_name = "NAME=VALUE", value_parser = parse_define)]
    define: Vec<(String, String)>,
    /// Mitsuba scenes: treat every unsupported part as an error instead of a warning.
    #[arg(long)]
    strict: bool,
}

/// The integrators, as the command line offers them (each with its one-line description).
#[derive(Clone, Copy, Debug, PartialEq, clap::ValueEnum)]
enum IntegratorArg {
    /// Classic Whitted ray tracing with the seed report's Phong model: fast, no indirect light
    Whitted,
    /// Path tracing with next-event estimation and MIS: unbiased reference, noisy caustics
    Path,
    /// Photon mapping (Jensen): caustic and global maps, final gathering; caustics from point lights
    Photon,
    /// Stochastic progressive photon mapping: converges to the exact image, caustics included
    Sppm,
}

impl From<IntegratorArg> for IntegratorKind {
    fn from(a: IntegratorArg) -> Self {
        match a {
            IntegratorArg::Whitted => IntegratorKind::Whitted,
            IntegratorArg::Path => IntegratorKind::Path,
            IntegratorArg::Photon => IntegratorKind::Photon,
            IntegratorArg::Sppm => IntegratorKind::Sppm,
        }
    }
}

fn parse_define(s: &str) -> Result<(String, String), String> {
    match s.split_once('=') {
        Some((k, v)) if !k.is_empty() && k.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') => {
            Ok((k.to_string(), v.to_string()))
        }
        _ => Err(format!("expected NAME=VALUE (NAME of letters, digits and _), found `{s}`")),
    }
}

fn unit_interval(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        // + 0.0 makes -0 into 0: a render's identity spells the value out.
        Ok(v) if (0.0..=1.0).contains(&v) => Ok(v + 0.0),
        _ => Err(format!("expected a number from 0 to 1, found `{s}`")),
    }
}

fn seconds(v: Option<f64>, name: &str) -> Result<Option<Duration>> {
    match v {
        None => Ok(None),
        Some(s) if s.is_finite() && s > 0.0 && s < 1e9 => Ok(Some(Duration::from_secs_f64(s))),
        Some(s) => anyhow::bail!("--{name} must be a positive number of seconds, got {s}"),
    }
}

impl RenderArgs {
    /// The options that change what is rendered, as arguments that parse back to them (for the
    /// shards of a farm); the scene, output and shard are left out.
    fn to_args(&self) -> Vec<String> {
        let mut a: Vec<String> = Vec::new();
        let mut opt = |name: &str, v: Option<String>| {
            if let Some(v) = v {
                a.push(format!("--{name}={v}"));
            }
        };
        opt("width", self.width.map(|v| v.to_string()));
        opt("height", self.height.map(|v| v.to_string()));
        opt("spp-axis", self.spp_axis.map(|v| v.to_string()));
        opt("spp", self.spp.map(|v| v.to_string()));
        opt("max-depth", self.max_depth.map(|v| v.to_string()));
        opt("adc-bailout", self.adc_bailout.map(|v| format!("{v:?}")));
        opt("threads", self.threads.map(|v| v.to_string()));
        opt("seed", self.seed.map(|v| v.to_string()));
        opt("integrator", self.integrator.map(|v| format!("{v:?}").to_lowercase()));
        opt("sampler", self.sampler.map(|v| format!("{v:?}").to_lowercase()));
        opt("photons", self.photons.map(|v| v.to_string()));
        opt("caustic-photons", self.caustic_photons.map(|v| v.to_string()));
        opt("gather", self.gather.map(|v| v.to_string()));
        opt("gather-k", self.gather_k.map(|v| v.to_string()));
        opt("irradiance-cache", self.irradiance_cache.map(|v| format!("{v:?}")));
        opt("cache-rays", self.cache_rays.map(|v| v.to_string()));
        opt("max-radius", self.max_radius.map(|v| format!("{v:?}")));
        opt("iterations", self.iterations.map(|v| v.to_string()));
        opt("photons-per-iter", self.photons_per_iter.map(|v| v.to_string()));
        opt("initial-radius", self.initial_radius.map(|v| format!("{v:?}")));
        opt("max-memory", self.max_memory.map(|v| v.to_string()));
        opt("time", self.time.map(|v| format!("{v:?}")));
        opt("checkpoint", self.checkpoint.map(|v| format!("{v:?}")));
        for flag in [
            ("no-antialias", self.no_antialias),
            ("layers", self.layers),
            ("quiet", self.quiet),
            ("strict", self.strict),
        ] {
            if flag.1 {
                a.push(format!("--{}", flag.0));
            }
        }
        for (k, v) in &self.define {
            a.push(format!("-D{k}={v}"));
        }
        a
    }

    fn options(self) -> Result<RenderOptions> {
        let args = self;
        Ok(RenderOptions {
            scene: args.scene,
            output: args.output,
            overrides: Overrides {
                width: args.width,
                height: args.height,
                spp_axis: args.spp_axis,
                spp: args.spp.or(args.iterations),
                max_depth: args.max_depth,
                adc_bailout: args.adc_bailout,
                seed: args.seed,
                integrator: args.integrator.map(IntegratorKind::from),
                sampler: args.sampler,
                antialias: args.no_antialias.then_some(false),
                photon: PhotonOptions {
                    photons: args.photons,
                    caustic_photons: args.caustic_photons,
                    gather: args.gather,
                    gather_k: args.gather_k,
                    irradiance_cache: args.irradiance_cache,
                    cache_rays: args.cache_rays,
                    max_radius: args.max_radius,
                    photons_per_iter: args.photons_per_iter,
                    initial_radius: args.initial_radius,
                    ..Default::default()
                },
            },
            load: LoadOptions { defines: args.define, strict: args.strict },
            layers: args.layers,
            max_memory: args.max_memory.map(|m| m.saturating_mul(1 << 20)),
            threads: args.threads,
            time_limit: seconds(args.time, "time")?,
            checkpoint: seconds(args.checkpoint, "checkpoint")?,
            quiet: args.quiet,
            shard: args.shard,
        })
    }
}

fn run(args: RenderArgs, cancel: &'static AtomicBool) -> Result<()> {
    render_file(&args.options()?, cancel)?;
    Ok(())
}

fn merge(args: MergeArgs) -> Result<()> {
    merge_files(&args.parts, &args.output, args.allow_partial, args.quiet)?;
    Ok(())
}

fn farm(command: FarmCommand, cancel: &'static AtomicBool) -> Result<()> {
    let FarmCommand::Slurm(args) = command;
    let mut render = args.render;
    anyhow::ensure!(render.shard.is_none(), "--shard is chosen by the farm: give --shards N instead");
    // Checkpoints bound what a shard killed without warning (node failure) loses.
    if render.checkpoint.is_none() {
        render.checkpoint = Some(600.0);
    }
    let render_args = render.to_args();
    let opts = SlurmOptions {
        render: render.options()?,
        render_args,
        shards: args.shards,
        partition: args.partition,
        time_limit: args.time_limit,
        sbatch_args: args.sbatch_arg,
        wait: args.wait,
        dry_run: args.dry_run,
        poll: None,
    };
    farm_slurm(&opts, cancel)?;
    Ok(())
}

fn bench(args: BenchArgs) -> Result<()> {
    if let Some(dir) = &args.write_scenes {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        for (name, text) in caustic::bench::generated_scenes() {
            let path = dir.join(name);
            std::fs::write(&path, text).with_context(|| format!("cannot write {}", path.display()))?;
            println!("{}", path.display());
        }
        return Ok(());
    }
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = args.threads {
        anyhow::ensure!(n > 0, "--threads must be at least 1");
        builder = builder.num_threads(n);
    }
    builder.build()?.install(|| caustic::bench::run_all(args.repeats.max(1)));
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    static CANCEL: AtomicBool = AtomicBool::new(false);
    static TERMINATED: AtomicBool = AtomicBool::new(false);
    // First Ctrl-C: finish the tiles in flight and write the image so far. Second: quit now.
    let _ = ctrlc::set_handler(|| {
        if CANCEL.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
        eprintln!(
            "\nstopping: finishing the work in flight, then writing the image if a complete pass is done \
             (Ctrl-C again to quit at once)"
        );
    });
    // SIGTERM (Slurm preemption, scancel, a node drain): stop the same way, so that a shard saves
    // its finished samples, and exit with 143 as a process ended by SIGTERM does. A second
    // SIGTERM quits at once.
    use signal_hook::consts::SIGTERM;
    let _ = signal_hook::flag::register_conditional_shutdown(SIGTERM, 143, &TERMINATED);
    let _ = signal_hook::flag::register(SIGTERM, &TERMINATED);
    let _ = signal_hook::flag::register(SIGTERM, &CANCEL);
    let result = match cli.command {
        Command::Render(args) => run(*args, &CANCEL),
        Command::Merge(args) => merge(args),
        Command::Farm(command) => farm(command, &CANCEL),
        Command::Bench(args) => bench(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let stopped = matches!(
                e.downcast_ref::<AppError>(),
                Some(
                    AppError::Interrupted { .. }
                        | AppError::InterruptedEarly { .. }
                        | AppError::ShardInterrupted { .. }
                )
            );
            if stopped && TERMINATED.load(Ordering::SeqCst) {
                eprintln!("terminated (SIGTERM): {e:#}");
                return ExitCode::from(143);
            }
            eprintln!("error: {e:#}");
            if stopped { ExitCode::from(130) } else { ExitCode::FAILURE }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn render_options_survive_the_trip_through_a_farm_script() {
        let argv = [
            "caustic",
            "render",
            "s.toml",
            "--width=64",
            "--spp",
            "7",
            "--seed",
            "3",
            "--integrator",
            "photon",
            "--sampler",
            "sobol",
            "--photons",
            "1000",
            "--max-radius",
            "0.1",
            "--gather",
            "0",
            "--layers",
            "--no-antialias",
            "-D",
            "name=a b'c",
            "--checkpoint",
            "2.5",
            "--max-depth",
            "4",
            "--adc-bailout",
            "0.004",
        ];
        let Cli { command: Command::Render(args) } = Cli::parse_from(argv) else { panic!() };
        let mut again = vec!["caustic".to_string(), "render".into(), "s.toml".into()];
        again.extend(args.to_args());
        let Cli { command: Command::Render(back) } = Cli::parse_from(&again) else { panic!() };
        assert_eq!(back, args);
    }
}
