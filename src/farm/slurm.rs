//! `caustic farm slurm`: one array job of shards and one merge job that waits for it.
//!
//! The scripts are written next to the output, in `OUT.farm/`, so a user can read, edit and
//! resubmit them (`sh OUT.farm/submit.sh`):
//! - `array.sh` renders shard `$SLURM_ARRAY_TASK_ID` to `parts/part-I.exr`;
//! - `merge.sh` merges the parts into the output;
//! - `submit.sh` submits both with `sbatch`: the array with `--requeue` (a preempted shard saves
//!   its finished samples, exits and resumes when Slurm runs it again) and the merge with
//!   `--dependency=afterok` (it starts once every shard has succeeded) and
//!   `--kill-on-invalid-dep=yes` (it is cancelled if a shard fails);
//! - `logs/` receives each shard's and the merge's output.
//!
//! Every path and argument is quoted for the POSIX shell, so names with spaces, quotes or other
//! metacharacters arrive intact. Nodes must share the file system holding the scene, its files,
//! the caustic binary and the output.

use super::FarmError;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// What to submit.
#[derive(Clone, Debug)]
pub struct FarmPlan {
    /// The caustic binary the jobs run (absolute).
    pub exe: PathBuf,
    /// The scene file (absolute).
    pub scene: PathBuf,
    /// The merged image (absolute).
    pub output: PathBuf,
    pub shards: u32,
    /// Render options passed to every shard as they are (after the scene).
    pub render_args: Vec<String>,
    pub partition: Option<String>,
    /// Slurm's `--time` for each shard and for the merge.
    pub time_limit: Option<String>,
    /// More `sbatch` options for both jobs, each one argument (`--account=lab`).
    pub sbatch_args: Vec<String>,
}

/// The files a plan is written to.
#[derive(Clone, Debug)]
pub struct FarmFiles {
    pub dir: PathBuf,
    pub array_script: PathBuf,
    pub merge_script: PathBuf,
    pub submit_script: PathBuf,
    pub logs: PathBuf,
    pub parts: Vec<PathBuf>,
    /// The `sbatch` arguments of the array job and of the merge job (the merge's dependency is
    /// added at submission, once the array's id is known).
    pub array_sbatch: Vec<String>,
    pub merge_sbatch: Vec<String>,
}

/// `s` quoted for the POSIX shell: as it is when it holds only characters the shell leaves
/// alone, otherwise in single quotes (a single quote inside becomes `'\''`).
pub fn shell_quote(s: &str) -> String {
    let plain = |c: char| c.is_ascii_alphanumeric() || "-_./=:,+@%".contains(c);
    if !s.is_empty() && s.chars().all(plain) { s.to_string() } else { format!("'{}'", s.replace('\'', "'\\''")) }
}

fn line(args: &[String]) -> String {
    args.iter().map(|a| shell_quote(a)).collect::<Vec<_>>().join(" ")
}

/// `%` starts a Slurm file-name pattern (`%a`, `%j`): a literal one is written `%%`.
fn slurm_pattern_literal(p: &Path) -> String {
    p.display().to_string().replace('%', "%%")
}

fn io_err(path: &Path, e: std::io::Error) -> FarmError {
    FarmError::Scheduler(format!("cannot write `{}`: {e}", path.display()))
}

/// The folder next to `output` that holds the scripts, parts and logs.
pub fn farm_dir(output: &Path) -> PathBuf {
    let name = output.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "render".into());
    output.with_file_name(format!("{name}.farm"))
}

/// Writes the scripts of `plan` (see the module notes) and returns where they are.
pub fn write_scripts(plan: &FarmPlan) -> Result<FarmFiles, FarmError> {
    let dir = farm_dir(&plan.output);
    let parts_dir = dir.join("parts");
    let logs = dir.join("logs");
    for d in [&dir, &parts_dir, &logs] {
        std::fs::create_dir_all(d).map_err(|e| io_err(d, e))?;
    }
    let n = plan.shards;
    let parts: Vec<PathBuf> = (0..n).map(|i| parts_dir.join(format!("part-{i}.exr"))).collect();
    let exe = plan.exe.display().to_string();
    let scene = plan.scene.display().to_string();
    let name = format!(
        "caustic-{}",
        plan.output.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "render".into())
    );

    let mut head = vec![format!("--job-name={name}")];
    if let Some(p) = &plan.partition {
        head.push(format!("--partition={p}"));
    }
    if let Some(t) = &plan.time_limit {
        head.push(format!("--time={t}"));
    }
    let array_script = dir.join("array.sh");
    let merge_script = dir.join("merge.sh");
    let mut array_sbatch = head.clone();
    array_sbatch.extend([
        format!("--array=0-{}", n - 1),
        "--requeue".into(),
        "--open-mode=append".into(),
        format!("--output={}", slurm_pattern_literal(&logs.join("shard-")) + "%a.log"),
    ]);
    array_sbatch.extend(plan.sbatch_args.iter().cloned());
    array_sbatch.push(array_script.display().to_string());
    let mut merge_sbatch = head;
    merge_sbatch[0] = format!("--job-name={name}-merge");
    merge_sbatch.extend([
        "--kill-on-invalid-dep=yes".into(),
        format!("--output={}", slurm_pattern_literal(&logs.join("merge.log"))),
    ]);
    merge_sbatch.extend(plan.sbatch_args.iter().cloned());
    merge_sbatch.push(merge_script.display().to_string());

    // The part's name takes the task id from the environment, outside the quotes.
    let part_prefix = shell_quote(&parts_dir.join("part-").display().to_string());
    let mut render = vec![exe.clone(), "render".into(), scene.clone(), "--shard".into(), format!("auto/{n}")];
    render.extend(plan.render_args.iter().cloned());
    let array = format!(
        "#!/bin/sh\n\
         # Shard $SLURM_ARRAY_TASK_ID of {n} of {scene_c}, written by `caustic farm slurm`.\n\
         # Slurm runs it once per array task. On SIGTERM (preemption, scancel, node drain) the shard\n\
         # saves the samples it has finished and exits with 143; run again, it resumes from them.\n\
         exec {render} -o {part_prefix}\"$SLURM_ARRAY_TASK_ID\".exr\n",
        scene_c = scene.replace('\n', " "),
        render = line(&render),
    );
    let mut merge = vec![exe, "merge".into()];
    merge.extend(parts.iter().map(|p| p.display().to_string()));
    merge.extend(["-o".into(), plan.output.display().to_string()]);
    let merge_text = format!(
        "#!/bin/sh\n\
         # Merges the {n} shards into the image; Slurm starts it once every shard has succeeded.\n\
         exec {}\n",
        line(&merge)
    );
    let submit = format!(
        "#!/bin/sh\n\
         # Submits the render as an array job of {n} shards and a merge job that waits for it.\n\
         # Run it again to resubmit: finished shards return at once, unfinished ones resume.\n\
         set -e\n\
         array=$(sbatch --parsable {})\n\
         array=${{array%%;*}}\n\
         merge=$(sbatch --parsable --dependency=afterok:\"$array\" {})\n\
         merge=${{merge%%;*}}\n\
         echo \"submitted array job $array ({n} shards) and merge job $merge\"\n",
        line(&array_sbatch),
        line(&merge_sbatch)
    );
    let submit_script = dir.join("submit.sh");
    for (path, text) in [(&array_script, array), (&merge_script, merge_text), (&submit_script, submit)] {
        std::fs::write(path, text).map_err(|e| io_err(path, e))?;
        make_executable(path);
    }
    Ok(FarmFiles { dir, array_script, merge_script, submit_script, logs, parts, array_sbatch, merge_sbatch })
}

fn make_executable(path: &Path) {
    use std::os::unix::fs::PermissionsExt;
    if let Ok(m) = std::fs::metadata(path) {
        let mut p = m.permissions();
        p.set_mode(p.mode() | 0o111);
        let _ = std::fs::set_permissions(path, p);
    }
}

/// Runs a scheduler command and returns its standard output.
fn run(program: &str, args: &[String]) -> Result<String, FarmError> {
    let out = Command::new(program).args(args).output().map_err(|e| {
        FarmError::Scheduler(if e.kind() == std::io::ErrorKind::NotFound {
            format!("`{program}` was not found: run this on a machine where Slurm's commands are installed")
        } else {
            format!("cannot run `{program}`: {e}")
        })
    })?;
    if !out.status.success() {
        return Err(FarmError::Scheduler(format!(
            "`{program} {}` failed ({}): {}",
            line(args),
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        )));
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

/// The job id `sbatch --parsable` printed (`id` or `id;cluster`).
fn job_id(out: &str) -> Result<String, FarmError> {
    let id = out.trim().split(';').next().unwrap_or("").trim().to_string();
    if id.is_empty() || !id.chars().all(|c| c.is_ascii_digit()) {
        return Err(FarmError::Scheduler(format!("sbatch printed `{}` where a job id was expected", out.trim())));
    }
    Ok(id)
}

/// Submits the array job and the merge job; returns their ids.
pub fn submit(files: &FarmFiles) -> Result<(String, String), FarmError> {
    let mut args = vec!["--parsable".to_string()];
    args.extend(files.array_sbatch.iter().cloned());
    let array = job_id(&run("sbatch", &args)?)?;
    let mut args = vec!["--parsable".to_string(), format!("--dependency=afterok:{array}")];
    args.extend(files.merge_sbatch.iter().cloned());
    let merge = job_id(&run("sbatch", &args)?)?;
    Ok((array, merge))
}

/// A job (or array task) as `squeue` lists it.
#[derive(Clone, Debug, PartialEq, Eq)]
struct Listed {
    id: String,
    state: String,
    reason: String,
}

fn list(ids: &str) -> Result<Vec<Listed>, FarmError> {
    let args: Vec<String> = ["-h", "-t", "all", "-j", ids, "-o", "%i|%T|%r"].iter().map(|s| s.to_string()).collect();
    let out = run("squeue", &args)?;
    Ok(out
        .lines()
        .filter_map(|l| {
            let mut f = l.trim().split('|');
            Some(Listed { id: f.next()?.to_string(), state: f.next()?.to_string(), reason: f.next()?.to_string() })
        })
        .collect())
}

const ENDED: [&str; 9] = [
    "COMPLETED",
    "FAILED",
    "CANCELLED",
    "TIMEOUT",
    "NODE_FAIL",
    "OUT_OF_MEMORY",
    "BOOT_FAIL",
    "DEADLINE",
    "SPECIAL_EXIT",
];

/// How the merge job ended, as `wait` reports it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct WaitOutcome {
    pub merge_state: String,
    /// Shards that did not complete, with their state.
    pub failed_shards: Vec<(String, String)>,
}

/// Waits for the merge job `merge` (and reports the shards of array `array` as they progress)
/// until it ends or `stop` is set; `report` receives each new summary line.
pub fn wait(
    array: &str,
    merge: &str,
    poll: Duration,
    stop: &AtomicBool,
    mut report: impl FnMut(&str),
) -> Result<WaitOutcome, FarmError> {
    let mut last = String::new();
    let mut shard_states: std::collections::BTreeMap<String, String> = Default::default();
    loop {
        if stop.load(Ordering::Relaxed) {
            return Err(FarmError::Scheduler(format!(
                "stopped waiting; the jobs keep running (squeue -j {array},{merge}; scancel {array} {merge} to stop them)"
            )));
        }
        let jobs = list(&format!("{array},{merge}"))?;
        let merge_job = jobs.iter().find(|j| j.id == merge);
        // Pending tasks are listed as one line (`A_[2-3]`) until they start; tasks that ended
        // keep their last state even once the controller forgets them.
        shard_states.retain(|id, _| !id.contains('['));
        for j in jobs.iter().filter(|j| j.id.starts_with(&format!("{array}_"))) {
            shard_states.insert(j.id.clone(), j.state.clone());
        }
        let mut counts: std::collections::BTreeMap<&str, usize> = Default::default();
        for (id, s) in &shard_states {
            *counts.entry(s.as_str()).or_default() += task_count(id);
        }
        let shards = counts.iter().map(|(s, n)| format!("{n} {}", s.to_lowercase())).collect::<Vec<_>>().join(", ");
        let summary = match merge_job {
            Some(m) => format!("shards: {shards}; merge: {}", m.state.to_lowercase()),
            None => format!("shards: {shards}; merge: gone from the queue"),
        };
        if summary != last {
            report(&summary);
            last = summary;
        }
        let ended = match merge_job {
            Some(m) if ENDED.contains(&m.state.as_str()) => Some(format!(
                "{}{}",
                m.state,
                if m.reason.is_empty() || m.reason == "None" { String::new() } else { format!(" ({})", m.reason) }
            )),
            Some(_) => None,
            // Purged after the controller's MinJobAge: it ended while we slept.
            None => Some("ENDED".to_string()),
        };
        if let Some(merge_state) = ended {
            let failed_shards =
                shard_states.into_iter().filter(|(_, s)| s != "COMPLETED").collect::<Vec<(String, String)>>();
            return Ok(WaitOutcome { merge_state, failed_shards });
        }
        std::thread::sleep(poll);
    }
}

/// How many array tasks an `squeue` id names: `A_3` is one, `A_[0-3,7%2]` five.
fn task_count(id: &str) -> usize {
    let Some(list) = id.split_once("_[").map(|(_, l)| l.trim_end_matches(']')) else { return 1 };
    let list = list.split('%').next().unwrap_or("");
    list.split(',')
        .map(|r| match r.split_once('-') {
            Some((a, b)) => match (a.parse::<usize>(), b.parse::<usize>()) {
                (Ok(a), Ok(b)) if b >= a => b - a + 1,
                _ => 1,
            },
            None => 1,
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quoting_leaves_plain_words_and_protects_the_rest() {
        assert_eq!(shell_quote("/a/b-c_d.exr"), "/a/b-c_d.exr");
        assert_eq!(shell_quote(""), "''");
        assert_eq!(shell_quote("a b"), "'a b'");
        assert_eq!(shell_quote("it's"), "'it'\\''s'");
        assert_eq!(shell_quote("$HOME;rm -rf *`x`\"\n"), "'$HOME;rm -rf *`x`\"\n'");
        assert_eq!(job_id("123;cluster\n").unwrap(), "123");
        assert_eq!(task_count("12_3"), 1);
        assert_eq!(task_count("12_[0-3,7%2]"), 5);
        assert_eq!(task_count("12_[5]"), 1);
        assert!(job_id("error").is_err());
    }
}
