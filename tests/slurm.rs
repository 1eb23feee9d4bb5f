//! Render farm on a real one-node Slurm cluster (issue 14): `caustic farm slurm --wait` renders
//! 4 shards and merges them into the local render's image bit for bit, and a shard requeued
//! (`scontrol requeue`, what preemption does) while it renders resumes and still merges exactly.
//! Skips (saying why) where Slurm cannot run; CI sets CAUSTIC_REQUIRE_SLURM=1 to make that fail.

mod common;

use common::slurm::SlurmCluster;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

const EXE: &str = env!("CARGO_BIN_EXE_caustic");

fn cluster(name: &str) -> Option<SlurmCluster> {
    match SlurmCluster::start(name) {
        Ok(c) => c,
        Err(e) => panic!("{e}"),
    }
}

fn scene() -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/13-cornell-caustics.toml").display().to_string()
}

fn bits(path: &Path) -> Vec<[u32; 3]> {
    caustic::film::output::read_exr(path).unwrap().pixels.iter().map(|c| c.to_array().map(f32::to_bits)).collect()
}

/// Renders locally (no Slurm) with `args` to `out`.
fn local(args: &[&str], out: &Path) {
    let o = Command::new(EXE).arg("render").arg(scene()).args(args).arg("-q").arg("-o").arg(out).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

fn output(o: std::process::Output, what: &str, c: &SlurmCluster) -> String {
    let text = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "{what} failed:\n{text}\n{}", c.logs());
    text
}

#[test]
fn farm_slurm_renders_shards_and_merges_bit_for_bit() {
    let Some(c) = cluster("farm") else { return };
    // A folder name with a space and a quote: the scripts must carry it through.
    let dir = c.dir().join("renders of 'today'");
    std::fs::create_dir_all(&dir).unwrap();
    let args = ["--integrator", "photon", "--width", "40", "--height", "32", "--spp", "9", "--photons", "5000"];
    let single = dir.join("single.exr");
    local(&args, &single);
    let out = dir.join("farm out.exr");
    let t = Instant::now();
    let o = c
        .command(EXE)
        .args(["farm", "slurm", &scene(), "--shards", "4", "--wait", "-o"])
        .arg(&out)
        .args(args)
        .output()
        .unwrap();
    let text = output(o, "caustic farm slurm --wait", &c);
    eprintln!("farm of 4 shards took {:.1} s:\n{text}", t.elapsed().as_secs_f64());
    assert!(text.contains("submitted array job") && text.contains("merged image"), "{text}");
    assert!(bits(&out) == bits(&single), "the farm's image differs from the local render");
    // The scripts stay next to the output for the user to read and resubmit.
    let farm = dir.join("farm out.exr.farm");
    for f in ["array.sh", "merge.sh", "submit.sh", "parts/part-3.exr", "logs/shard-0.log", "logs/merge.log"] {
        assert!(farm.join(f).exists(), "{f} is missing");
    }
}

#[test]
fn a_requeued_shard_resumes_and_the_merge_stays_exact() {
    let Some(c) = cluster("requeue") else { return };
    let dir = c.dir().join("preempt");
    std::fs::create_dir_all(&dir).unwrap();
    let args = ["--integrator", "path", "--width", "128", "--height", "128", "--spp", "400", "--checkpoint", "0.3"];
    let out = dir.join("out.exr");
    let o =
        c.command(EXE).args(["farm", "slurm", &scene(), "--shards", "4", "-o"]).arg(&out).args(args).output().unwrap();
    let text = output(o, "caustic farm slurm", &c);
    // "submitted array job A (4 shards) and merge job M"
    let words: Vec<&str> = text.split_whitespace().collect();
    let after = |w: &str| words.iter().position(|x| *x == w).map(|i| words[i + 1].to_string()).unwrap();
    let (array, merge) = (after("job"), words[words.iter().position(|x| *x == "merge").unwrap() + 2].to_string());
    // Requeue shard 0 once its first checkpoint shows it rendering.
    let part0 = dir.join("out.exr.farm/parts/part-0.exr");
    let deadline = Instant::now() + Duration::from_secs(120);
    while !part0.exists() {
        assert!(Instant::now() < deadline, "shard 0 never checkpointed:\n{}", c.logs());
        std::thread::sleep(Duration::from_millis(50));
    }
    let held = caustic::farm::partial::read_partial(&part0).unwrap().film.min_samples();
    assert!(held < 100, "shard 0 finished before the requeue ({held} samples): the test proves nothing");
    c.run("scontrol", &["requeue", &format!("{array}_0")]).unwrap();
    let merged = c.wait_job(&merge, Duration::from_secs(300)).unwrap();
    assert!(merged.iter().all(|m| m.is_success()), "merge: {merged:?}\n{}", c.logs());
    let log = std::fs::read_to_string(dir.join("out.exr.farm/logs/shard-0.log")).unwrap();
    assert!(log.contains("SIGTERM") && log.contains("resuming shard 0/4"), "shard 0's log:\n{log}");
    let single = dir.join("single.exr");
    local(&args, &single);
    assert!(bits(&out) == bits(&single), "the requeued render differs from the local one");
}
