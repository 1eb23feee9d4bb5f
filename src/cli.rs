//! The `caustic` command line: parses arguments and hands them to the library, and reports its
//! errors. It is a function of the library, [`run`], so that the `caustic` binary (`main.rs`)
//! and the Python module (`python -m caustic`) are the same command line. This module is the
//! command line's edge: the one place besides `main.rs` that uses `anyhow`.

use crate::app::{AppError, RenderOptions, SlurmOptions, farm_slurm, merge_files, render_file};
use crate::farm::shard::ShardSpec;
use crate::options::{Options, PhotonOptions};
use crate::scene::LoadOptions;
use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use std::ffi::OsString;
use std::path::PathBuf;
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
    /// What may replace the scene's values (`caustic::options`).
    #[command(flatten)]
    options: Options,
    /// SPPM iterations (the same as --spp for sppm: one sample per pixel per iteration).
    #[arg(long, value_name = "N")]
    iterations: Option<u32>,
    /// Worker threads [default: all cores].
    #[arg(long, value_name = "N")]
    threads: Option<usize>,
    /// Also write the direct, specular, caustic and indirect parts as OUT.direct.EXT etc.
    #[arg(long)]
    layers: bool,
    /// Refuse to render when photon maps would need more memory than this, in MiB
    /// [default: half of the machine's memory].
    #[arg(long, value_name = "MIB")]
    max_memory: Option<u64>,
    /// Stop starting new passes this many seconds after the scene started loading (loading and
    /// preparation such as photon maps count; at least one pass is rendered) and write the image
    /// so far.
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
    /// Give scene parameter `$NAME` the value VALUE (repeatable; wins over a Mitsuba <default> or a
    /// TOML [parameters] default; a name the scene does not use is an error).
    #[arg(short = 'D', value_name = "NAME=VALUE", value_parser = parse_define)]
    define: Vec<(String, String)>,
    /// Put VALUE in place of the scene's value of KEY, a key path: render.spp=4,
    /// materials.glass.ior=1.6, objects.0.radius=2; integrator.*, film.* and sampler.* name
    /// [render] keys (integrator.light_samples=4, film.filter=gaussian); Mitsuba scenes: a
    /// property of an element (integrator.max_depth=4, sensor.film.width=320) (repeatable; checked
    /// as the scene file's values are).
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = crate::scene::native::parse_set)]
    set: Vec<(String, String)>,
    /// Mitsuba scenes: treat every unsupported part as an error instead of a warning.
    #[arg(long)]
    strict: bool,
}

fn parse_define(s: &str) -> Result<(String, String), String> {
    match s.split_once('=') {
        Some((k, v)) if !k.is_empty() && k.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') => {
            Ok((k.to_string(), v.to_string()))
        }
        _ => Err(format!("expected NAME=VALUE (NAME of letters, digits and _), found `{s}`")),
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
        // Destructured without `..`: a new argument or option does not compile until it is passed
        // on here, or named as one the shards do not take.
        let RenderArgs {
            scene: _,
            output: _,
            options,
            iterations,
            threads,
            layers,
            max_memory,
            time,
            checkpoint,
            quiet,
            shard: _,
            define,
            set,
            strict,
        } = self;
        let Options {
            width,
            height,
            spp_axis,
            spp,
            max_depth,
            adc_bailout,
            seed,
            integrator,
            sampler,
            antialias,
            light_samples,
            filter,
            aov,
            display_server,
            spectral,
            xyz,
            photon,
        } = options;
        let PhotonOptions {
            photons,
            caustic_photons,
            gather,
            gather_k,
            irradiance_cache,
            cache_rays,
            caustic_k,
            max_radius,
            caustic_radius,
            volume_k,
            volume_radius,
            photons_per_iter,
            initial_radius,
        } = photon;
        let mut a: Vec<String> = Vec::new();
        if *spectral == Some(true) {
            a.push("--spectral".into());
        }
        if *xyz == Some(true) {
            a.push("--xyz".into());
        }
        let mut opt = |name: &str, v: Option<String>| {
            if let Some(v) = v {
                a.push(format!("--{name}={v}"));
            }
        };
        opt("width", width.map(|v| v.to_string()));
        opt("height", height.map(|v| v.to_string()));
        opt("spp-axis", spp_axis.map(|v| v.to_string()));
        opt("spp", spp.map(|v| v.to_string()));
        opt("max-depth", max_depth.map(|v| v.to_string()));
        opt("adc-bailout", adc_bailout.map(|v| format!("{v:?}")));
        opt("threads", threads.map(|v| v.to_string()));
        opt("seed", seed.map(|v| v.to_string()));
        opt("integrator", integrator.map(|v| v.name().to_string()));
        opt("sampler", sampler.map(|v| format!("{v:?}").to_lowercase()));
        opt("light-samples", light_samples.map(|v| v.to_string()));
        opt("filter", filter.map(|f| f.spelled()));
        opt("aov", aov.as_ref().map(|a| a.to_string()));
        opt("photons", photons.map(|v| v.to_string()));
        opt("caustic-photons", caustic_photons.map(|v| v.to_string()));
        opt("gather", gather.map(|v| v.to_string()));
        opt("gather-k", gather_k.map(|v| v.to_string()));
        opt("irradiance-cache", irradiance_cache.map(|v| format!("{v:?}")));
        opt("cache-rays", cache_rays.map(|v| v.to_string()));
        opt("max-radius", max_radius.map(|v| format!("{v:?}")));
        opt("caustic-k", caustic_k.map(|v| v.to_string()));
        opt("caustic-radius", caustic_radius.map(|v| format!("{v:?}")));
        opt("volume-k", volume_k.map(|v| v.to_string()));
        opt("volume-radius", volume_radius.map(|v| format!("{v:?}")));
        opt("iterations", iterations.map(|v| v.to_string()));
        opt("photons-per-iter", photons_per_iter.map(|v| v.to_string()));
        opt("initial-radius", initial_radius.map(|v| format!("{v:?}")));
        opt("max-memory", max_memory.map(|v| v.to_string()));
        opt("time", time.map(|v| format!("{v:?}")));
        opt("checkpoint", checkpoint.map(|v| format!("{v:?}")));
        // Each shard shows its part in the viewer (under its partial image's name) when the
        // viewer can be reached from the node it runs on.
        opt("display-server", display_server.clone());
        for (flag, given) in [
            // The command line can only turn anti-aliasing off.
            ("no-antialias", *antialias == Some(false)),
            ("layers", *layers),
            ("quiet", *quiet),
            ("strict", *strict),
        ] {
            if given {
                a.push(format!("--{flag}"));
            }
        }
        for (k, v) in define {
            a.push(format!("-D{k}={v}"));
        }
        for (k, v) in set {
            a.push(format!("--set={k}={v}"));
        }
        a
    }

    fn options(self) -> Result<RenderOptions> {
        let RenderArgs {
            scene,
            output,
            options,
            iterations,
            threads,
            layers,
            max_memory,
            time,
            checkpoint,
            quiet,
            shard,
            define,
            set,
            strict,
        } = self;
        if let (Some(spp), Some(n)) = (options.spp, iterations)
            && spp != n
        {
            anyhow::bail!(
                "--spp {spp} and --iterations {n} ask for different sample counts (for sppm one iteration is one sample per pixel): give one of them"
            );
        }
        Ok(RenderOptions {
            scene,
            output,
            overrides: Options { spp: options.spp.or(iterations), ..options },
            load: LoadOptions { defines: define, sets: set, strict },
            layers,
            max_memory: max_memory.map(|m| m.saturating_mul(1 << 20)),
            threads,
            time_limit: seconds(time, "time")?,
            checkpoint: seconds(checkpoint, "checkpoint")?,
            quiet,
            shard,
        })
    }
}

fn render(args: RenderArgs, cancel: &'static AtomicBool) -> Result<()> {
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
        for (name, text) in crate::bench::generated_scenes() {
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
    builder.build()?.install(|| crate::bench::run_all(args.repeats.max(1)));
    Ok(())
}

/// Runs the command line on `args` (the program's name first) and returns its exit status: 0,
/// 1 for an error, 2 for bad arguments, 130 when interrupted by Ctrl-C and 143 by SIGTERM. It
/// takes over SIGINT and SIGTERM: the first asks the render to stop and write what it has.
pub fn run<I, T>(args: I) -> u8
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let cli = match Cli::try_parse_from(args) {
        Ok(cli) => cli,
        Err(e) => {
            // Help and version go to stdout with status 0, mistakes to stderr with status 2.
            let _ = e.print();
            return e.exit_code().clamp(0, 255) as u8;
        }
    };
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
        Command::Render(args) => render(*args, &CANCEL),
        Command::Merge(args) => merge(args),
        Command::Farm(command) => farm(command, &CANCEL),
        Command::Bench(args) => bench(args),
    };
    match result {
        Ok(()) => 0,
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
                eprintln!("terminated (SIGTERM): {}", describe(&e));
                return 143;
            }
            eprintln!("error: {}", describe(&e));
            if stopped { 130 } else { 1 }
        }
    }
}

/// An error with its chain of causes, each said once: a cause that the message before it
/// already quotes (a library error that names its source) is not repeated.
fn describe(e: &anyhow::Error) -> String {
    let mut text = e.to_string();
    for cause in e.chain().skip(1) {
        let c = cause.to_string();
        if !text.contains(&c) {
            text = format!("{text}: {c}");
        }
    }
    text
}

#[cfg(test)]
mod tests {
    /// Issue 30, item 8: a missing scene file said `No such file or directory (os error 2)`
    /// twice.
    #[test]
    fn causes_are_said_once() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "No such file or directory (os error 2)");
        let e = anyhow::Error::new(crate::scene::SceneError::Read { path: "a.toml".into(), source: io });
        let text = super::describe(&e);
        assert_eq!(text.matches("No such file").count(), 1, "{text}");
        let e = anyhow::anyhow!("inner cause").context("outer");
        assert_eq!(super::describe(&e), "outer: inner cause");
    }

    use super::*;

    #[test]
    fn render_options_survive_the_trip_through_a_farm_script() {
        let argv = [
            "caustic",
            "render",
            "s.toml",
            "-o",
            "out.exr",
            "--width=64",
            "--height",
            "48",
            "--spp-axis",
            "3",
            "--spp",
            "7",
            "--max-depth",
            "4",
            "--adc-bailout",
            "0.004",
            "--seed",
            "3",
            "--integrator",
            "photon",
            "--sampler",
            "sobol",
            "--no-antialias",
            "--light-samples",
            "5",
            "--filter",
            "mitchell:B=0.5,C=0.25",
            "--aov",
            "albedo,dd.y:depth,variance",
            "--photons",
            "1000",
            "--caustic-photons",
            "300",
            "--gather",
            "0",
            "--gather-k",
            "40",
            "--irradiance-cache",
            "0.1",
            "--cache-rays",
            "128",
            "--max-radius",
            "0.1",
            "--photons-per-iter",
            "5000",
            "--initial-radius",
            "0.03",
            "--iterations",
            "9",
            "--threads",
            "2",
            "--layers",
            "--max-memory",
            "512",
            "--time",
            "30",
            "--checkpoint",
            "2.5",
            "-q",
            "--shard",
            "1/4",
            "-D",
            "name=a b'c",
            "--set",
            "materials.\"frosted glass\".alpha=0.3",
            "--set",
            "film.filter=tent:radius=1.5",
            "--strict",
            "--display-server",
            "localhost:14158",
            "--spectral",
            "--xyz",
        ];
        let Cli { command: Command::Render(args) } = Cli::parse_from(argv) else { panic!() };
        // Every argument is given a value of its own above: destructured without `..`, so a new
        // one does not compile until it is given there too.
        let RenderArgs {
            scene: _,
            output,
            options,
            iterations,
            threads,
            layers,
            max_memory,
            time,
            checkpoint,
            quiet,
            shard,
            define,
            set,
            strict,
        } = &*args;
        let Options {
            width,
            height,
            spp_axis,
            spp,
            max_depth,
            adc_bailout,
            seed,
            integrator,
            sampler,
            antialias,
            light_samples,
            filter,
            aov,
            display_server,
            spectral,
            xyz,
            photon,
        } = options;
        let PhotonOptions {
            photons,
            caustic_photons,
            gather,
            gather_k,
            irradiance_cache,
            cache_rays,
            caustic_k: _,
            max_radius,
            caustic_radius: _,
            volume_k: _,
            volume_radius: _,
            photons_per_iter,
            initial_radius,
        } = photon;
        let given = [
            output.is_some(),
            width.is_some(),
            height.is_some(),
            spp_axis.is_some(),
            spp.is_some(),
            max_depth.is_some(),
            adc_bailout.is_some(),
            seed.is_some(),
            integrator.is_some(),
            sampler.is_some(),
            antialias.is_some(),
            light_samples.is_some(),
            filter.is_some(),
            aov.is_some(),
            display_server.is_some(),
            spectral.is_some(),
            xyz.is_some(),
            photons.is_some(),
            caustic_photons.is_some(),
            gather.is_some(),
            gather_k.is_some(),
            irradiance_cache.is_some(),
            cache_rays.is_some(),
            max_radius.is_some(),
            photons_per_iter.is_some(),
            initial_radius.is_some(),
            iterations.is_some(),
            threads.is_some(),
            *layers,
            max_memory.is_some(),
            time.is_some(),
            checkpoint.is_some(),
            *quiet,
            shard.is_some(),
            !define.is_empty(),
            set.len() == 2,
            *strict,
        ];
        assert!(given.iter().all(|&g| g), "{given:?}");
        let mut again = vec!["caustic".to_string(), "render".into(), "s.toml".into()];
        again.extend(args.to_args());
        let Cli { command: Command::Render(back) } = Cli::parse_from(&again) else { panic!() };
        // The output and the shard are each shard's own.
        assert_eq!(*back, RenderArgs { output: None, shard: None, ..(*args).clone() });
    }

    #[test]
    fn adc_bailout_minus_0_is_0() {
        let argv = ["caustic", "render", "s.toml", "--adc-bailout=-0"];
        let Cli { command: Command::Render(args) } = Cli::parse_from(argv) else { panic!() };
        assert_eq!(args.options.adc_bailout.map(f32::to_bits), Some(0.0f32.to_bits()));
    }
}
