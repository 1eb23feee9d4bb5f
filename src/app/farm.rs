//! The `merge` and `farm slurm` commands as library functions.

use super::{AppError, RenderOptions, default_output, load, log};
use crate::farm::FarmError;
use crate::farm::merge::{MergeReport, merge};
use crate::farm::partial::SumKind;
use crate::farm::shard::MAX_SHARDS;
use crate::farm::slurm::{FarmPlan, submit, wait, write_scripts};
use crate::film::LAYER_NAMES;
use crate::film::output::{ColourSpace, check_writable, layer_path, write_image_in};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Duration;

/// Merges the partial images `parts` into `output` (and its layers, when the parts have them).
pub fn merge_files(
    parts: &[PathBuf],
    output: &Path,
    allow_partial: bool,
    quiet: bool,
) -> Result<MergeReport, AppError> {
    check_writable(output)?;
    let (film, report) = merge(parts, allow_partial)?;
    // The colour channels the render asked for (its identity names `xyz`).
    let space = ColourSpace::xyz_if(report.xyz);
    space.check(output)?;
    if film.has_layers() {
        for (k, name) in LAYER_NAMES.iter().enumerate() {
            write_image_in(&film.layer_image(k), &layer_path(output, name), space)?;
        }
    }
    super::write_outputs(&film.image(), &film, output, space)?;
    let what = match report.sums {
        SumKind::Exact => "samples per pixel",
        SumKind::Runs => "iterations (independent progressive runs, weighted by iterations)",
    };
    if report.missing.is_empty() {
        log(quiet, format_args!("merged {} parts: {} {what} -> {}", report.parts, report.total, output.display()));
    } else {
        eprintln!(
            "warning: merged what the parts hold: {} to {} of {} {what} -> {} (missing {})",
            report.min_samples,
            report.max_samples,
            report.total,
            output.display(),
            report.missing.join("; ")
        );
    }
    Ok(report)
}

/// `caustic farm slurm`: what to render and how to submit it.
#[derive(Clone, Debug, Default)]
pub struct SlurmOptions {
    /// The render (scene, output, overrides) the shards make together.
    pub render: RenderOptions,
    /// The render options as command-line arguments, passed to every shard.
    pub render_args: Vec<String>,
    pub shards: u32,
    pub partition: Option<String>,
    pub time_limit: Option<String>,
    pub sbatch_args: Vec<String>,
    /// Wait for the merge job and report how the jobs went.
    pub wait: bool,
    /// Write the scripts without submitting them.
    pub dry_run: bool,
    /// How often `wait` asks the scheduler.
    pub poll: Option<Duration>,
}

fn absolute(p: &Path) -> Result<PathBuf, AppError> {
    std::path::absolute(p).map_err(|e| AppError::Shard(format!("cannot make `{}` absolute: {e}", p.display())))
}

/// Writes the scripts, submits the jobs and, when asked, waits for them.
pub fn farm_slurm(opts: &SlurmOptions, cancel: &AtomicBool) -> Result<PathBuf, AppError> {
    let r = &opts.render;
    if opts.shards == 0 || opts.shards > MAX_SHARDS {
        return Err(AppError::Shard(format!("--shards must be 1 to {MAX_SHARDS}, got {}", opts.shards)));
    }
    if r.time_limit.is_some() {
        return Err(AppError::Shard(
            "--time cannot be used with a farm: each shard renders a fixed block of samples (give Slurm's \
             limit with --time-limit)"
                .into(),
        ));
    }
    let output = absolute(&r.output.clone().unwrap_or_else(|| default_output(&r.scene)))?;
    check_writable(&output)?;
    let scene = absolute(&r.scene)?;
    // Catch scene errors here rather than in every shard's log.
    let loaded = load(&scene, &r.load, &r.overrides)?;
    let total = loaded.settings.spp;
    if opts.shards > total {
        eprintln!(
            "warning: {} shards for {total} samples per pixel: {} shards have no samples to take",
            opts.shards,
            opts.shards - total
        );
    }
    let exe = std::env::current_exe()
        .map_err(|e| AppError::Shard(format!("cannot find the caustic binary to run in the jobs: {e}")))?;
    let plan = FarmPlan {
        exe,
        scene,
        output: output.clone(),
        shards: opts.shards,
        render_args: opts.render_args.clone(),
        partition: opts.partition.clone(),
        time_limit: opts.time_limit.clone(),
        sbatch_args: opts.sbatch_args.clone(),
    };
    let files = write_scripts(&plan)?;
    let quiet = r.quiet;
    log(
        quiet,
        format_args!(
            "wrote {} (shards), {} (merge) and {} (submits both); parts go to {}",
            files.array_script.display(),
            files.merge_script.display(),
            files.submit_script.display(),
            files.dir.join("parts").display()
        ),
    );
    if opts.dry_run {
        log(quiet, format_args!("not submitted (--dry-run); to submit: sh {}", files.submit_script.display()));
        return Ok(output);
    }
    let (array, merge_job) = submit(&files)?;
    println!("submitted array job {array} ({} shards) and merge job {merge_job}", opts.shards);
    log(
        quiet,
        format_args!(
            "follow with: squeue -j {array},{merge_job}; logs in {}; the image will be {}",
            files.logs.display(),
            output.display()
        ),
    );
    if !opts.wait {
        return Ok(output);
    }
    let start = std::time::Instant::now();
    let poll = opts.poll.unwrap_or(Duration::from_secs(2));
    let outcome = wait(&array, &merge_job, poll, cancel, |line| {
        eprintln!("[{:>6.1} s] {line}", start.elapsed().as_secs_f64());
    })?;
    if outcome.merge_state == "COMPLETED" || (outcome.merge_state == "ENDED" && output.exists()) {
        println!("merged image: {}", output.display());
        return Ok(output);
    }
    let shards = outcome
        .failed_shards
        .iter()
        .map(|(id, state)| {
            let task = id.rsplit('_').next().unwrap_or(id);
            format!(
                "shard {task} {} (log {})",
                state.to_lowercase(),
                files.logs.join(format!("shard-{task}.log")).display()
            )
        })
        .collect::<Vec<_>>();
    Err(AppError::Farm(FarmError::Scheduler(format!(
        "the merge job {merge_job} ended as {}{}; merge log {}",
        outcome.merge_state,
        if shards.is_empty() { String::new() } else { format!(": {}", shards.join(", ")) },
        files.logs.join("merge.log").display()
    ))))
}
