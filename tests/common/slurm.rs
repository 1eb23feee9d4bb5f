//! A real one-node Slurm cluster, started by a test in a temporary folder and stopped when it is dropped.
//!
//! `SlurmCluster::start` runs `munged`, `slurmctld` and `slurmd` as root, with their own munge key and socket,
//! generated `slurm.conf`, state, spool, pid and log files, all under one temporary folder, and on free TCP
//! ports, so that a Slurm the machine already runs is never touched. Where it cannot run (not root, Slurm or
//! munge not installed) it prints why and returns `Ok(None)` so that the test can skip; with
//! `CAUSTIC_REQUIRE_SLURM=1` (set by CI) that is an error instead. It never installs anything: CI installs
//! the Debian 12 packages with `apt-get install -y slurm-wlm munge` (the daemons come from `slurmctld`,
//! `slurmd`, `slurm-client` and `munge`, which `slurm-wlm` pulls in).
//!
//! # What was verified with Slurm 22.05.8 and munge 0.5.15 (Debian 12, 2 cores, cgroup v1 host, as root)
//!
//! Start-up and shut-down:
//! - `munged -F --force --key-file --socket --pid-file --log-file --seed-file` runs with everything in the temp
//!   folder. The folder holding the socket must be executable by all (munged refuses otherwise: "Socket is
//!   inaccessible: execute permissions for all required"), so the folders are made 0755 and the key 0400.
//!   In the foreground munged logs to stderr, not to `--log-file`. `--force` is passed so that a stale socket
//!   or a parent folder munged finds too open does not stop a throwaway test daemon.
//! - `slurmctld -D -i` and `slurmd -D -N <node>` with `SLURM_CONF` in their environment need no cgroup.conf with
//!   `ProctrackType=proctrack/linuxproc`, `TaskPlugin=task/none` and `JobAcctGatherType=jobacct_gather/none`.
//!   `AuthInfo=socket=...` points both daemons and every client at our munged. `SlurmctldHost` must be the
//!   host's short name (otherwise slurmctld stops: "This host (vm/vm) not a valid controller"); `(127.0.0.1)`
//!   and `NodeAddr=127.0.0.1` spare any name resolution. With the node named after the host, slurmd would
//!   find its node line without `-N`; it is passed anyway to say which line is ours. The node line copies
//!   `slurmd -C` (boards, sockets, cores, threads, memory): with only `CPUs=` slurmd logs that it "reconfigured
//!   socket/core boundaries".
//! - Harmless log noise: "mpi/pmix_v4: can not load PMIx library" and "Could not open ... state file".
//! - Start until the node is idle takes about 1.3 s; stop (SIGTERM, wait, sweep) 0.2-0.4 s, also with a job
//!   running. A machine's own munged (default socket) and slurmctld (port 6817, /etc/slurm/slurm.conf) running
//!   at the same time were not disturbed, nor did they disturb the test clusters.
//! - `slurmstepd` and job processes outlive a stopped `slurmd`, so `Drop` also kills every process whose
//!   environment holds our `SLURM_CONF` (slurmstepd and job processes have it even with `--export=NONE`).
//!
//! Jobs (all on this machine, so the temp folder is the shared file system):
//! - `sbatch --parsable --array=0-3 --requeue task.sh` runs the 4 tasks, 2 at a time on 2 cores, each with
//!   `SLURM_ARRAY_TASK_ID`, `SLURM_ARRAY_JOB_ID` and its own `SLURM_JOB_ID`; `--output=dir/task-%A_%a.out` lands in
//!   the temp folder. Without `--output` the default `slurm-%j.out` is written in the submitting process's
//!   current folder, which `command`/`run` set to the temp folder.
//! - `sbatch --parsable --dependency=afterok:<array job id> merge.sh` starts once every task has completed with
//!   exit 0. If any task fails, `DependencyParameters=kill_invalid_depend` cancels the dependent job (state
//!   CANCELLED) instead of leaving it pending forever with reason DependencyNeverSatisfied.
//! - `sbatch --wait` works: it returns when the job ends, with the job's exit code (for `--array=0-2` exiting
//!   with the task id: 2, the highest; sbatch(1) says 1 for a job killed by a signal). It polls the controller
//!   every 2 s or so, which a trivial job's `sbatch --wait` took; `wait_job` polls `squeue` every 0.25 s.
//! - `sacct` does not work without slurmdbd ("Slurm accounting storage is disabled"). Final states come from
//!   `JobCompType=jobcomp/filetxt`, one line per ended run in `jobcomp.txt`, which `wait_job` reads.
//!
//! Requeue and preemption (`KillWait=5`, `AuthInfo=...,cred_expire=5`):
//! - `scontrol requeue <array job id>_<task id>` of a running task: slurmstepd sends SIGCONT and SIGTERM to the
//!   whole job (the batch shell and its children; bash prints "Terminated" for a killed child) and the output
//!   gets "*** JOB n ON node CANCELLED AT ... DUE TO JOB REQUEUE ***". A job still alive `KillWait` seconds
//!   later gets SIGKILL. Whatever the script then exits with (0 or 143 from a SIGTERM trap, or SIGKILL), the
//!   task is requeued: it goes back to PENDING with reason BeginTime, keeps its job id, runs again from the start
//!   of its script with `SLURM_RESTART_COUNT=1` (unset on the first run), and `--open-mode=append` keeps the
//!   first run's output (the default truncates it). jobcomp.txt records the interrupted run as JobState=PENDING
//!   with ExitCode=0:0 whatever the exit status was, then the final run.
//! - A requeued job may not start again before `cred_expire + 1` seconds (default 120 s, hence cred_expire=5
//!   here) and the scheduler only notices that at its next pass (default every 60 s, hence `sched_interval=1`):
//!   from `scontrol requeue` to the rerun took 7 s for a job that exits on SIGTERM and 11 s for one that
//!   ignores it (KillWait, then 6 s).
//! - `--requeue` is not needed for `scontrol requeue` or preemption while `JobRequeue=1` (the default); it is
//!   needed on clusters with `JobRequeue=0`. A job submitted with `--no-requeue` cannot be requeued.
//! - Preemption (`PreemptType=preempt/partition_prio`, `PreemptMode=REQUEUE`): a job in partition `urgent`
//!   (PriorityTier=10) that needs cores held by jobs of the default partition `main` requeues one of them
//!   ("preempted JobId=4_0(5) has been requeued to reclaim resources"); the victim sees exactly what
//!   `scontrol requeue` does (SIGCONT + SIGTERM, SIGKILL after KillWait, "DUE TO PREEMPTION", JobState=PREEMPTED
//!   in jobcomp.txt). The urgent job started once the victim was gone (5 s, KillWait, for a victim ignoring
//!   SIGTERM) and the victim reran 5 s after that.
//! - No exit code requeues a job by default: exit 75 gives FAILED, ExitCode=75:0 (and 143 gives FAILED,
//!   ExitCode=143:0). Only a site's `RequeueExit=75` (tested through `start_with`) makes Slurm requeue on that
//!   exit code: the task reran 6 s later with `SLURM_RESTART_COUNT=1`. The portable way for a job to ask
//!   for its own requeue is `scontrol requeue $SLURM_JOB_ID` from inside it (returns 0; the job is then
//!   killed as above and rerun); on SIGTERM a job should just save its work and exit, Slurm requeues it anyway.
//!
//! # Pitfalls
//! - Unix socket paths are limited to 108 bytes: munge's socket and slurmd's per-step sockets live under the
//!   temp folder, so a long `TMPDIR` makes the cluster fall back to `/tmp`.
//! - Client commands read `SLURM_*`/`SBATCH_*` variables: a test run inside a Slurm job would leak its own job's
//!   settings into `sbatch`, so `command` removes them before setting `SLURM_CONF`.
//! - Processes a job leaves behind after daemonising escape proctrack/linuxproc (it follows the process tree).
//! - Two cores mean two jobs at a time: clusters started by parallel tests each get their own ports and
//!   folders and work, but compete for the cores.
//! - A test process killed outright (SIGKILL, a harness timeout) cannot drop its cluster: the next `start`
//!   kills the daemons and jobs of clusters whose starting process is gone and removes their folders.
//! - A dependent `afterok` job of an array with a failed task is cancelled only once the whole array has ended.
//! - Jobs run with the submitting command's environment, where the renderer is not on PATH: job scripts should
//!   name it by its absolute path (`env!("CARGO_BIN_EXE_caustic")`). A renderer that calls `sbatch` itself
//!   should be started through `command`, so that it and its jobs get our `SLURM_CONF`.
//!
//! # Smoke test
//! ```ignore
//! #[test]
//! fn slurm_array_and_merge() {
//!     let cluster = match common::slurm::SlurmCluster::start("smoke") {
//!         Ok(Some(cluster)) => cluster,
//!         Ok(None) => return, // start() said why it skips.
//!         Err(e) => panic!("{e}"),
//!     };
//!     let dir = cluster.dir().display().to_string();
//!     let task = format!("echo $SLURM_ARRAY_TASK_ID > {dir}/task-$SLURM_ARRAY_TASK_ID.txt");
//!     let array = cluster.submit(&["--array=0-3", "--requeue", "--wrap", &task]).unwrap();
//!     let merge = cluster.submit(&[&format!("--dependency=afterok:{array}"), "--wrap", "true"]).unwrap();
//!     let tasks = cluster.wait_job(&array, std::time::Duration::from_secs(60)).unwrap();
//!     assert_eq!(tasks.iter().filter(|t| t.is_success()).count(), 4);
//!     let merged = cluster.wait_job(&merge, std::time::Duration::from_secs(60)).unwrap();
//!     assert!(merged.iter().all(|m| m.is_success()));
//! }
//! ```
#![allow(dead_code)]

use std::fmt::Write as _;
use std::fs;
use std::io::{Read, Write};
use std::net::TcpListener;
use std::os::unix::fs::{OpenOptionsExt, PermissionsExt};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::mpsc;
use std::thread;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

/// Set to `1` (as CI does) to make a cluster that cannot run here an error instead of a skip.
pub const REQUIRE_ENV: &str = "CAUSTIC_REQUIRE_SLURM";

/// The default partition; jobs in it can be preempted (requeued) by jobs in `URGENT_PARTITION`.
pub const MAIN_PARTITION: &str = "main";
/// A partition of higher priority tier over the same node, to test preemption.
pub const URGENT_PARTITION: &str = "urgent";

/// The whole start must stay short; the node is usually idle after 1-2 s.
const START_TIMEOUT: Duration = Duration::from_secs(15);
/// Client commands answer within Slurm's MessageTimeout (10 s) unless the controller is gone.
const CLIENT_TIMEOUT: Duration = Duration::from_secs(30);
/// How long a daemon gets to exit after SIGTERM before SIGKILL.
const STOP_TIMEOUT: Duration = Duration::from_secs(10);
/// Keeps Unix socket paths (limit 108 bytes) short enough with slurmd's per-step socket names appended.
const MAX_DIR_LEN: usize = 60;

/// Environment variable prefixes Slurm's clients read as options; they are removed from client commands.
const SLURM_ENV_PREFIXES: [&str; 7] = ["SLURM_", "SBATCH_", "SQUEUE_", "SALLOC_", "SRUN_", "SINFO_", "SCONTROL_"];

/// The programs that must be installed; the daemons are in /usr/sbin, which a test's PATH may lack.
const REQUIRED_PROGRAMS: [&str; 7] = ["munged", "slurmctld", "slurmd", "sbatch", "squeue", "scontrol", "sinfo"];

/// Makes the folders of clusters started in one process distinct.
static COUNTER: AtomicU32 = AtomicU32::new(0);

/// How one run of a job or array task ended, as Slurm's job completion log recorded it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct JobOutcome {
    /// Slurm's own id of the job or task (an array task has its own, distinct from the array's).
    pub job_id: String,
    /// The task's index for an array task.
    pub array_task_id: Option<u32>,
    /// COMPLETED, FAILED, CANCELLED, TIMEOUT, PREEMPTED, NODE_FAIL, OUT_OF_MEMORY...
    pub state: String,
    /// `exit status:signal`, e.g. `0:0`, `3:0`, `0:9`.
    pub exit_code: String,
}

impl JobOutcome {
    /// True for a run that ended normally with exit status 0.
    pub fn is_success(&self) -> bool {
        self.state == "COMPLETED" && self.exit_code == "0:0"
    }
}

/// A daemon this cluster started, stopped by `Drop`.
struct Daemon {
    name: &'static str,
    child: Child,
}

/// A running one-node Slurm cluster whose files all live in one temporary folder.
pub struct SlurmCluster {
    dir: PathBuf,
    conf: PathBuf,
    node: String,
    /// Behind a mutex so that `&self` methods can notice a daemon that died.
    daemons: Mutex<Vec<Daemon>>,
    /// Left in place after a failed start or a panicking test, so that its logs can be read.
    keep_dir: bool,
}

impl SlurmCluster {
    /// Starts a cluster named after `name` (used in its folder's name), or returns `Ok(None)` after printing why
    /// Slurm cannot run here, unless `CAUSTIC_REQUIRE_SLURM=1`, which turns that into an error.
    pub fn start(name: &str) -> Result<Option<SlurmCluster>, String> {
        Self::start_with(name, "")
    }

    /// Like `start`, with extra `slurm.conf` lines (e.g. `RequeueExit=75`); a key given again overrides ours
    /// (slurmctld then logs "specified more than once, latest value used").
    pub fn start_with(name: &str, extra_conf: &str) -> Result<Option<SlurmCluster>, String> {
        if let Some(reason) = why_unsupported() {
            if std::env::var(REQUIRE_ENV).is_ok_and(|v| v == "1") {
                return Err(format!("Slurm cluster for {name:?} cannot run: {reason} ({REQUIRE_ENV}=1)"));
            }
            eprintln!("skipping Slurm cluster test {name:?}: {reason} (set {REQUIRE_ENV}=1 to fail instead)");
            return Ok(None);
        }
        reap_orphans();
        let dir = cluster_dir(name)?;
        let mut cluster = SlurmCluster {
            conf: dir.join("slurm.conf"),
            dir,
            node: String::new(),
            daemons: Mutex::new(Vec::new()),
            keep_dir: false,
        };
        // On error the cluster is dropped here, which stops whatever had been started.
        match cluster.boot(extra_conf) {
            Ok(()) => Ok(Some(cluster)),
            Err(e) => {
                cluster.keep_dir = true;
                Err(format!("Slurm cluster in {} failed to start: {e}\n{}", cluster.dir.display(), cluster.logs()))
            }
        }
    }

    /// The temporary folder: job scripts, their outputs and the cluster's files (shared by all jobs).
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The generated `slurm.conf`.
    pub fn conf_path(&self) -> &Path {
        &self.conf
    }

    /// The node's name (the host's short name).
    pub fn node(&self) -> &str {
        &self.node
    }

    /// The variables a Slurm client needs on top of an environment cleared of `SLURM_*`-like options.
    pub fn env(&self) -> Vec<(String, String)> {
        vec![("SLURM_CONF".to_string(), self.conf.display().to_string())]
    }

    /// A command for `program` (a Slurm client by name, or any program such as the renderer that calls them)
    /// with the cluster's environment and the temp folder as current folder.
    pub fn command(&self, program: &str) -> Command {
        let path = find_program(program).unwrap_or_else(|| PathBuf::from(program));
        let mut cmd = Command::new(path);
        for (key, _) in std::env::vars_os() {
            if key.to_str().is_some_and(|k| SLURM_ENV_PREFIXES.iter().any(|p| k.starts_with(p))) {
                cmd.env_remove(key);
            }
        }
        cmd.envs(self.env()).current_dir(&self.dir);
        cmd
    }

    /// Runs a Slurm client command; returns its stdout, or an error with its stderr.
    pub fn run(&self, program: &str, args: &[&str]) -> Result<String, String> {
        self.run_timeout(program, args, CLIENT_TIMEOUT)
    }

    /// Like `run` with a chosen timeout, for commands that wait (e.g. `sbatch --wait`).
    pub fn run_timeout(&self, program: &str, args: &[&str], timeout: Duration) -> Result<String, String> {
        let mut cmd = self.command(program);
        cmd.args(args);
        let (status, stdout, stderr) = run_with_timeout(cmd, timeout)?;
        if status.success() {
            Ok(stdout)
        } else {
            Err(format!("{program} {args:?} failed ({status})\nstderr: {}\nstdout: {}", stderr.trim(), stdout.trim()))
        }
    }

    /// Submits a batch job with `sbatch --parsable <args>` and returns its job id.
    pub fn submit(&self, args: &[&str]) -> Result<String, String> {
        let mut full = vec!["--parsable"];
        full.extend_from_slice(args);
        let out = self.run("sbatch", &full)?;
        // `--parsable` prints `id` or `id;cluster`.
        let id = out.trim().split(';').next().unwrap_or("").to_string();
        if id.is_empty() || !id.chars().all(|c| c.is_ascii_digit()) {
            return Err(format!("sbatch {args:?} printed no job id: {out:?}"));
        }
        Ok(id)
    }

    /// Waits until the job (for an array id: all its tasks; `id_task` for one task) has left the queue, then
    /// returns the final outcome of each of its tasks from the job completion log (a requeued task's last run;
    /// empty if none was recorded, e.g. for an id that never existed). Fails at `timeout`, with the queue and
    /// the daemons' logs in the message, or as soon as a daemon has died.
    pub fn wait_job(&self, job_id: &str, timeout: Duration) -> Result<Vec<JobOutcome>, String> {
        let deadline = Instant::now() + timeout;
        loop {
            self.check_daemons()?;
            let mut cmd = self.command("squeue");
            cmd.args(["-h", "-j", job_id, "-o", "%i %T %r"]);
            // A job purged after MinJobAge is unknown to squeue, which is as good as gone. Other failures (a
            // busy controller timing out) are retried until the deadline, as long as the daemons live.
            let queued = match run_with_timeout(cmd, CLIENT_TIMEOUT) {
                Ok((status, stdout, _)) if status.success() => stdout.trim().to_string(),
                Ok((_, _, stderr)) if stderr.contains("Invalid job id") => String::new(),
                Ok((status, _, stderr)) => format!("(squeue failed ({status}): {})", stderr.trim()),
                Err(e) => format!("({e})"),
            };
            if queued.is_empty() {
                return self.outcomes(job_id);
            }
            if Instant::now() >= deadline {
                let show = self.run("scontrol", &["show", "job", job_id]).unwrap_or_else(|e| e);
                return Err(format!("job {job_id} still queued after {timeout:?}:\n{queued}\n{show}\n{}", self.logs()));
            }
            thread::sleep(Duration::from_millis(250));
        }
    }

    /// The final outcome of each task of `job_id` (`id`, or `id_task`) recorded so far in the job completion log.
    pub fn outcomes(&self, job_id: &str) -> Result<Vec<JobOutcome>, String> {
        let (array_id, task) = match job_id.split_once('_') {
            Some((array, task)) => {
                (array, Some(task.parse::<u32>().map_err(|e| format!("bad array task id {job_id:?}: {e}"))?))
            }
            None => (job_id, None),
        };
        let path = self.dir.join("log/jobcomp.txt");
        let text = match fs::read_to_string(&path) {
            Ok(text) => text,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
            Err(e) => return Err(format!("cannot read {}: {e}", path.display())),
        };
        let mut outcomes: Vec<JobOutcome> = Vec::new();
        for line in text.lines() {
            let field = |key: &str| line.split_whitespace().find_map(|kv| kv.strip_prefix(key)?.strip_prefix('='));
            let (Some(id), Some(state)) = (field("JobId"), field("JobState")) else { continue };
            let array_task_id = field("ArrayTaskId").and_then(|t| t.parse().ok());
            let ours = match field("ArrayJobId") {
                Some(array) => array == array_id && (task.is_none() || task == array_task_id),
                None => id == array_id && task.is_none(),
            };
            if !ours {
                continue;
            }
            let outcome = JobOutcome {
                job_id: id.to_string(),
                array_task_id,
                state: state.to_string(),
                exit_code: field("ExitCode").unwrap_or("").to_string(),
            };
            // A requeued run keeps its job id; the log is in time order, so the last line is the final run.
            match outcomes.iter_mut().find(|o| o.job_id == outcome.job_id) {
                Some(previous) => *previous = outcome,
                None => outcomes.push(outcome),
            }
        }
        outcomes.sort_by_key(|o| o.array_task_id);
        Ok(outcomes)
    }

    /// The last lines of each daemon's log, for error messages.
    pub fn logs(&self) -> String {
        let mut out = String::new();
        for name in ["munged.out", "slurmctld.log", "slurmd.log", "slurmctld.out", "slurmd.out"] {
            let path = self.dir.join("log").join(name);
            let Ok(text) = fs::read_to_string(&path) else { continue };
            let lines: Vec<&str> = text.lines().collect();
            let _ = writeln!(out, "--- {} (last lines)", path.display());
            for line in &lines[lines.len().saturating_sub(15)..] {
                let _ = writeln!(out, "{line}");
            }
        }
        out
    }

    /// Fails if one of the daemons has exited, which would otherwise show as a long timeout.
    pub fn check_daemons(&self) -> Result<(), String> {
        let mut daemons = self.daemons.lock().map_err(|_| "daemon list poisoned".to_string())?;
        for daemon in daemons.iter_mut() {
            match daemon.child.try_wait() {
                Ok(None) => {}
                Ok(Some(status)) => return Err(format!("{} exited ({status})\n{}", daemon.name, self.logs())),
                Err(e) => return Err(format!("cannot check {}: {e}", daemon.name)),
            }
        }
        Ok(())
    }

    /// Writes the key and configuration, starts the daemons and waits until the node is idle.
    fn boot(&mut self, extra_conf: &str) -> Result<(), String> {
        let deadline = Instant::now() + START_TIMEOUT;
        for sub in ["munge", "munge-key", "state", "spool", "log"] {
            let path = self.dir.join(sub);
            fs::create_dir_all(&path).map_err(|e| format!("cannot create {}: {e}", path.display()))?;
        }
        // munged wants its socket's folder (and parents) executable by all and its key private.
        for (sub, mode) in [("", 0o755), ("munge", 0o755), ("munge-key", 0o700), ("log", 0o755)] {
            let path = self.dir.join(sub);
            fs::set_permissions(&path, fs::Permissions::from_mode(mode))
                .map_err(|e| format!("cannot chmod {}: {e}", path.display()))?;
        }
        let key = self.dir.join("munge-key/munge.key");
        write_munge_key(&key)?;
        self.node = short_hostname()?;
        let hardware = node_hardware()?;
        let (ctld_port, slurmd_port) = free_ports()?;
        let conf = self.conf_text(&hardware, ctld_port, slurmd_port, extra_conf);
        fs::write(&self.conf, conf).map_err(|e| format!("cannot write {}: {e}", self.conf.display()))?;
        // An empty plugin stack keeps the machine's /etc/slurm/plugstack.conf (SPANK plugins) out.
        let plugstack = self.dir.join("plugstack.conf");
        fs::write(&plugstack, "").map_err(|e| format!("cannot write {}: {e}", plugstack.display()))?;

        let munge = self.dir.join("munge");
        let socket = munge.join("munge.sock");
        self.spawn(
            "munged",
            &[
                "-F".to_string(),
                "--force".to_string(),
                format!("--key-file={}", key.display()),
                format!("--socket={}", socket.display()),
                format!("--pid-file={}", munge.join("munged.pid").display()),
                format!("--log-file={}", self.dir.join("log/munged.log").display()),
                format!("--seed-file={}", munge.join("munged.seed").display()),
                "--num-threads=4".to_string(),
            ],
        )?;
        self.wait_until(deadline, "munged's socket", || Ok(socket.exists()))?;

        self.spawn("slurmctld", &["-D".to_string(), "-i".to_string()])?;
        // slurmd registers at start, so it is started once the controller answers.
        self.wait_until(deadline, "slurmctld to answer", || Ok(self.node_state().is_some()))?;
        self.spawn("slurmd", &["-D".to_string(), "-N".to_string(), self.node.clone()])?;
        self.wait_until(deadline, "the node to be idle", || Ok(self.node_state().is_some_and(|s| s == "idle")))
    }

    /// The node's state as `sinfo` prints it (`idle`, `unk*`, `down*`...), or None while slurmctld is not up.
    fn node_state(&self) -> Option<String> {
        let mut cmd = self.command("sinfo");
        cmd.args(["-h", "-n", &self.node, "-o", "%t"]);
        match run_with_timeout(cmd, Duration::from_secs(5)) {
            Ok((status, stdout, _)) if status.success() => stdout.lines().next().map(|s| s.trim().to_string()),
            _ => None,
        }
    }

    /// Polls `ready` until it holds, failing at `deadline` or as soon as a daemon has died.
    fn wait_until(
        &self,
        deadline: Instant,
        what: &str,
        mut ready: impl FnMut() -> Result<bool, String>,
    ) -> Result<(), String> {
        loop {
            self.check_daemons()?;
            if ready()? {
                return Ok(());
            }
            if Instant::now() >= deadline {
                return Err(format!("timed out waiting for {what}"));
            }
            thread::sleep(Duration::from_millis(100));
        }
    }

    /// Starts a daemon in the foreground with its output in `log/<name>.out`.
    fn spawn(&mut self, name: &'static str, args: &[String]) -> Result<(), String> {
        let program = find_program(name).ok_or_else(|| format!("{name} not found"))?;
        let out_path = self.dir.join("log").join(format!("{name}.out"));
        let out = fs::File::create(&out_path).map_err(|e| format!("cannot create {}: {e}", out_path.display()))?;
        let err = out.try_clone().map_err(|e| format!("cannot reopen {}: {e}", out_path.display()))?;
        let mut cmd = self.command(program.to_str().unwrap_or(name));
        cmd.args(args).stdin(Stdio::null()).stdout(out).stderr(err);
        let child = cmd.spawn().map_err(|e| format!("cannot start {}: {e}", program.display()))?;
        self.daemons.lock().map_err(|_| "daemon list poisoned".to_string())?.push(Daemon { name, child });
        Ok(())
    }

    /// The generated `slurm.conf`.
    fn conf_text(&self, hardware: &str, ctld_port: u16, slurmd_port: u16, extra_conf: &str) -> String {
        let d = self.dir.display();
        let node = &self.node;
        format!(
            "# Generated by caustic's tests for a one-node cluster that lives in {d}.
ClusterName=caustic
SlurmctldHost={node}(127.0.0.1)
SlurmctldPort={ctld_port}
SlurmdPort={slurmd_port}
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
# cred_expire also delays a requeued job's restart (default 120 s).
AuthInfo=socket={d}/munge/munge.sock,cred_expire=5
StateSaveLocation={d}/state
SlurmdSpoolDir={d}/spool
SlurmctldPidFile={d}/slurmctld.pid
SlurmdPidFile={d}/slurmd.pid
SlurmctldLogFile={d}/log/slurmctld.log
SlurmdLogFile={d}/log/slurmd.log
PlugStackConfig={d}/plugstack.conf
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc={d}/log/jobcomp.txt
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
SchedulerParameters=sched_interval=1,bf_interval=1
DependencyParameters=kill_invalid_depend
PreemptType=preempt/partition_prio
PreemptMode=REQUEUE
ReturnToService=2
JobRequeue=1
KillWait=5
MinJobAge=5
InactiveLimit=0
MpiDefault=none
MailProg=/bin/true
{extra_conf}
NodeName={node} NodeAddr=127.0.0.1 {hardware} State=UNKNOWN
PartitionName={MAIN_PARTITION} Nodes={node} Default=YES MaxTime=INFINITE State=UP PriorityTier=1
PartitionName={URGENT_PARTITION} Nodes={node} MaxTime=INFINITE State=UP PriorityTier=10 PreemptMode=OFF
"
        )
    }

    /// Stops slurmd, then slurmctld, kills what jobs left, then stops munged (which the others need until then).
    fn stop(&mut self) {
        // A poisoned lock still holds the children, which must be stopped all the same.
        let daemons = self.daemons.get_mut().unwrap_or_else(|poisoned| poisoned.into_inner());
        for name in ["slurmd", "slurmctld"] {
            if let Some(daemon) = daemons.iter_mut().find(|d| d.name == name) {
                stop_child(daemon);
            }
        }
        // slurmstepd and job processes outlive slurmd; they are ours if their environment has our SLURM_CONF.
        let marker = format!("SLURM_CONF={}", self.conf.display());
        for _ in 0..3 {
            let left = processes_with_env(&marker);
            if left.is_empty() {
                break;
            }
            signal(&left, "KILL");
            thread::sleep(Duration::from_millis(100));
        }
        for daemon in daemons.iter_mut() {
            stop_child(daemon);
        }
    }
}

impl Drop for SlurmCluster {
    fn drop(&mut self) {
        let started = Instant::now();
        self.stop();
        if self.keep_dir || thread::panicking() {
            eprintln!("Slurm cluster stopped in {:?}; its files are kept in {}", started.elapsed(), self.dir.display());
        } else if let Err(e) = fs::remove_dir_all(&self.dir) {
            eprintln!("cannot remove {}: {e}", self.dir.display());
        }
    }
}

/// Sends SIGTERM, waits up to STOP_TIMEOUT, then SIGKILLs and reaps.
fn stop_child(daemon: &mut Daemon) {
    if let Ok(Some(_)) = daemon.child.try_wait() {
        return;
    }
    signal(&[daemon.child.id()], "TERM");
    let deadline = Instant::now() + STOP_TIMEOUT;
    while Instant::now() < deadline {
        if let Ok(Some(_)) = daemon.child.try_wait() {
            return;
        }
        thread::sleep(Duration::from_millis(50));
    }
    eprintln!("{} ignored SIGTERM for {STOP_TIMEOUT:?}; killing it", daemon.name);
    let _ = daemon.child.kill();
    let _ = daemon.child.wait();
}

/// Sends a signal to processes by pid with the `kill` command (std has no kill(2) for non-children).
fn signal(pids: &[u32], name: &str) {
    if pids.is_empty() {
        return;
    }
    let mut cmd = match find_program("kill") {
        Some(kill) => Command::new(kill),
        // The shell's built-in kill serves where procps is not installed.
        None => {
            let mut sh = Command::new("sh");
            sh.args(["-c", "kill \"$@\"", "sh"]);
            sh
        }
    };
    cmd.arg(format!("-{name}")).args(pids.iter().map(|p| p.to_string()));
    cmd.stdout(Stdio::null()).stderr(Stdio::null());
    let _ = run_with_timeout(cmd, Duration::from_secs(5));
}

/// Pids of processes (other than this one) whose environment contains `entry` exactly.
fn processes_with_env(entry: &str) -> Vec<u32> {
    let me = std::process::id();
    let Ok(proc) = fs::read_dir("/proc") else { return Vec::new() };
    proc.filter_map(|e| e.ok()?.file_name().to_str()?.parse::<u32>().ok())
        .filter(|&pid| pid != me)
        .filter(|pid| {
            fs::read(format!("/proc/{pid}/environ"))
                .is_ok_and(|env| env.split(|&b| b == 0).any(|var| var == entry.as_bytes()))
        })
        .collect()
}

/// Kills the daemons and jobs of clusters whose test process died without dropping them (killed by a timeout,
/// say), and removes their folders: they are recognised by a `SLURM_CONF` in one of our folders, whose name
/// holds the pid of the process that started it.
fn reap_orphans() {
    let Ok(proc) = fs::read_dir("/proc") else { return };
    let mut orphans: Vec<(u32, PathBuf)> = Vec::new();
    for pid in proc.filter_map(|e| e.ok()?.file_name().to_str()?.parse::<u32>().ok()) {
        let Ok(env) = fs::read(format!("/proc/{pid}/environ")) else { continue };
        let Some(conf) = env.split(|&b| b == 0).find_map(|var| var.strip_prefix(b"SLURM_CONF".as_slice())) else {
            continue;
        };
        let Some(dir) = std::str::from_utf8(conf).ok().and_then(|c| c.strip_prefix('=')).map(Path::new) else {
            continue;
        };
        let Some(dir) = dir.parent() else { continue };
        let Some(leaf) = dir.file_name().and_then(|l| l.to_str()) else { continue };
        if !leaf.starts_with("caustic-slurm-") {
            continue;
        }
        // The leaf is caustic-slurm-<name>-<owner pid>-<counter>.
        let owner = leaf.rsplit('-').nth(1).and_then(|p| p.parse::<u32>().ok());
        if owner.is_some_and(|owner| !Path::new(&format!("/proc/{owner}")).exists()) {
            orphans.push((pid, dir.to_path_buf()));
        }
    }
    if orphans.is_empty() {
        return;
    }
    let pids: Vec<u32> = orphans.iter().map(|(pid, _)| *pid).collect();
    eprintln!("killing processes {pids:?} left by Slurm test clusters whose test process is gone");
    signal(&pids, "KILL");
    thread::sleep(Duration::from_millis(200));
    for (_, dir) in orphans {
        let _ = fs::remove_dir_all(dir);
    }
}

/// Why Slurm cannot run here, if it cannot.
fn why_unsupported() -> Option<String> {
    if !cfg!(target_os = "linux") {
        return Some("the test cluster needs Linux".to_string());
    }
    let missing: Vec<&str> = REQUIRED_PROGRAMS.iter().copied().filter(|p| find_program(p).is_none()).collect();
    if !missing.is_empty() {
        return Some(format!("{} not installed (Debian: apt-get install -y slurm-wlm munge)", missing.join(", ")));
    }
    let mut id = Command::new("id");
    id.arg("-u");
    match run_with_timeout(id, Duration::from_secs(5)) {
        Ok((status, out, _)) if status.success() && out.trim() == "0" => None,
        Ok((status, out, _)) if status.success() => Some(format!("not root (uid {})", out.trim())),
        Ok((status, _, err)) => Some(format!("`id -u` failed ({status}): {}", err.trim())),
        Err(e) => Some(format!("cannot run `id -u`: {e}")),
    }
}

/// Finds a program on PATH or in the sbin folders, where Debian puts the daemons.
fn find_program(name: &str) -> Option<PathBuf> {
    if name.contains('/') {
        return Some(PathBuf::from(name));
    }
    let path = std::env::var_os("PATH").unwrap_or_default();
    let sbin = ["/usr/local/sbin", "/usr/local/bin", "/usr/sbin", "/usr/bin", "/sbin", "/bin"].map(PathBuf::from);
    std::env::split_paths(&path)
        .chain(sbin)
        .map(|dir| dir.join(name))
        .find(|candidate| fs::metadata(candidate).is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0))
}

/// A new empty folder for the cluster, short enough for Unix socket paths.
fn cluster_dir(name: &str) -> Result<PathBuf, String> {
    let clean: String = name.chars().filter(|c| c.is_ascii_alphanumeric() || *c == '-').take(16).collect();
    let leaf = format!("caustic-slurm-{clean}-{}-{}", std::process::id(), COUNTER.fetch_add(1, Ordering::Relaxed));
    let mut dir = std::env::temp_dir().join(&leaf);
    if dir.as_os_str().len() > MAX_DIR_LEN {
        dir = PathBuf::from("/tmp").join(&leaf);
    }
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    Ok(dir)
}

/// Writes a random 1024-byte munge key readable by root only.
fn write_munge_key(path: &Path) -> Result<(), String> {
    let mut key = [0u8; 1024];
    fs::File::open("/dev/urandom")
        .and_then(|mut f| f.read_exact(&mut key))
        .map_err(|e| format!("cannot read /dev/urandom: {e}"))?;
    fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .mode(0o400)
        .open(path)
        .and_then(|mut f| f.write_all(&key))
        .map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// The host's short name, which slurmctld requires as SlurmctldHost.
fn short_hostname() -> Result<String, String> {
    let full = fs::read_to_string("/proc/sys/kernel/hostname")
        .map_err(|e| format!("cannot read /proc/sys/kernel/hostname: {e}"))?;
    let short = full.trim().split('.').next().unwrap_or("").to_string();
    if short.is_empty() { Err("the host has no name".to_string()) } else { Ok(short) }
}

/// The node's hardware as `slurmd -C` reports it, e.g. `CPUs=2 Boards=1 ... RealMemory=24105`.
fn node_hardware() -> Result<String, String> {
    let program = find_program("slurmd").ok_or("slurmd not found")?;
    let mut cmd = Command::new(program);
    cmd.arg("-C");
    let (status, stdout, stderr) = run_with_timeout(cmd, Duration::from_secs(10))?;
    if !status.success() {
        return Err(format!("slurmd -C failed ({status}): {}", stderr.trim()));
    }
    let keys = ["CPUs", "Boards", "SocketsPerBoard", "CoresPerSocket", "ThreadsPerCore", "RealMemory"];
    let line = stdout.lines().find(|l| l.starts_with("NodeName=")).unwrap_or("");
    let fields: Vec<&str> =
        line.split_whitespace().filter(|kv| kv.split_once('=').is_some_and(|(k, _)| keys.contains(&k))).collect();
    if fields.len() != keys.len() {
        return Err(format!("slurmd -C printed an unexpected node line: {stdout:?}"));
    }
    Ok(fields.join(" "))
}

/// Two consecutive TCP ports that are free on all addresses, below Linux's ephemeral range (32768 and up) so
/// that no outgoing connection takes them between this check and the daemons binding them.
fn free_ports() -> Result<(u16, u16), String> {
    let nanos = SystemTime::now().duration_since(UNIX_EPOCH).map(|d| d.subsec_nanos()).unwrap_or(0);
    let seed = nanos ^ std::process::id().wrapping_mul(2_654_435_761);
    let free = |port: u16| TcpListener::bind(("0.0.0.0", port)).is_ok();
    for attempt in 0..200u32 {
        let port = 20000 + (seed.wrapping_add(attempt.wrapping_mul(7919)) % 12000) as u16;
        if free(port) && free(port + 1) {
            return Ok((port, port + 1));
        }
    }
    Err("no two free TCP ports found in 20000-32000".to_string())
}

/// Runs a command with piped output and a deadline (killing it then); returns status, stdout and stderr.
fn run_with_timeout(mut cmd: Command, timeout: Duration) -> Result<(std::process::ExitStatus, String, String), String> {
    let what = format!("{:?}", cmd.get_program());
    cmd.stdin(Stdio::null()).stdout(Stdio::piped()).stderr(Stdio::piped());
    let mut child = cmd.spawn().map_err(|e| format!("cannot run {what}: {e}"))?;
    // Readers on threads keep a chatty command from blocking on a full pipe; channels bound the wait for them
    // in case a grandchild holds the pipe open.
    let reader = |pipe: Option<Box<dyn Read + Send>>| {
        let (tx, rx) = mpsc::channel();
        thread::spawn(move || {
            let mut text = Vec::new();
            if let Some(mut pipe) = pipe {
                let _ = pipe.read_to_end(&mut text);
            }
            let _ = tx.send(String::from_utf8_lossy(&text).into_owned());
        });
        rx
    };
    let out_rx = reader(child.stdout.take().map(|p| Box::new(p) as Box<dyn Read + Send>));
    let err_rx = reader(child.stderr.take().map(|p| Box::new(p) as Box<dyn Read + Send>));
    let deadline = Instant::now() + timeout;
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break status,
            Ok(None) if Instant::now() >= deadline => {
                let _ = child.kill();
                let _ = child.wait();
                return Err(format!("{what} timed out after {timeout:?}"));
            }
            Ok(None) => thread::sleep(Duration::from_millis(20)),
            Err(e) => return Err(format!("cannot wait for {what}: {e}")),
        }
    };
    let stdout = out_rx.recv_timeout(Duration::from_secs(5)).unwrap_or_default();
    let stderr = err_rx.recv_timeout(Duration::from_secs(5)).unwrap_or_default();
    Ok((status, stdout, stderr))
}
