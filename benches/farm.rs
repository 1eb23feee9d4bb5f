//! Render-farm costs on a real one-node Slurm cluster (started like the test suite's, in a
//! temporary folder): the wall time of a render as 1 shard and as 4 shards through
//! `caustic farm slurm --wait`, beside the same render run directly, and the cost of merging the
//! 4 partial images of a 4K (3840 x 2160) render. Needs root and Slurm (skips otherwise).
//!
//!     cargo bench --bench farm

#[path = "../tests/common/slurm.rs"]
mod slurm;

use std::path::Path;
use std::process::Command;
use std::time::Instant;

const EXE: &str = env!("CARGO_BIN_EXE_caustic");

fn scene() -> String {
    format!("{}/scenes/13-cornell-caustics.toml", env!("CARGO_MANIFEST_DIR"))
}

fn run(mut c: Command, what: &str) -> f64 {
    let t = Instant::now();
    let o = c.output().unwrap();
    assert!(o.status.success(), "{what} failed: {}", String::from_utf8_lossy(&o.stderr));
    t.elapsed().as_secs_f64()
}

fn main() {
    let cluster = match slurm::SlurmCluster::start("bench") {
        Ok(Some(c)) => c,
        Ok(None) => return,
        Err(e) => panic!("{e}"),
    };
    let dir = cluster.dir().to_path_buf();
    let render = ["--integrator", "photon", "--width", "256", "--height", "256", "--spp", "32", "--quiet"];
    let mut direct = Command::new(EXE);
    direct.arg("render").arg(scene()).args(render).arg("-o").arg(dir.join("direct.exr"));
    let t_direct = run(direct, "direct render");
    let farm = |shards: u32| {
        let mut c = cluster.command(EXE);
        c.args(["farm", "slurm", &scene(), "--shards", &shards.to_string(), "--wait", "-o"])
            .arg(dir.join(format!("farm{shards}.exr")))
            .args(render);
        run(c, "farm")
    };
    let t1 = farm(1);
    let t4 = farm(4);
    println!("render: 13-cornell-caustics, photon, 256 x 256, 32 spp, one node with 2 cores");
    println!("  direct `caustic render`:          {t_direct:6.2} s");
    println!("  farm slurm, 1 shard  (--wait):    {t1:6.2} s  ({:.2}x direct)", t1 / t_direct);
    println!("  farm slurm, 4 shards (--wait):    {t4:6.2} s  ({:.2}x 1 shard)", t4 / t1);

    // Merge of a 4K render's 4 parts (1 sample each, Whitted: the parts are what is measured).
    let parts: Vec<_> = (0..4).map(|i| dir.join(format!("uhd-{i}.exr"))).collect();
    for (i, p) in parts.iter().enumerate() {
        let mut c = Command::new(EXE);
        c.arg("render")
            .arg(scene())
            .args(["--integrator", "whitted", "--width", "3840", "--height", "2160", "--spp", "4", "--quiet"])
            .args(["--shard", &format!("{i}/4"), "-o"])
            .arg(p);
        run(c, "4K shard");
    }
    let size: u64 = parts.iter().map(|p| std::fs::metadata(p).unwrap().len()).sum();
    let merge = |out: &Path| {
        let mut c = Command::new(EXE);
        c.arg("merge").args(&parts).arg("-q").arg("-o").arg(out);
        run(c, "merge")
    };
    let t_exr = merge(&dir.join("uhd.exr"));
    let t_png = merge(&dir.join("uhd.png"));
    println!("merge of 4 parts of a 3840 x 2160 render ({:.0} MB of parts):", size as f64 / 1e6);
    println!("  to EXR: {t_exr:6.2} s    to PNG: {t_png:6.2} s");
}
