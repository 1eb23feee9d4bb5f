//! Big-mesh figures for `caustic bench`: how fast the PLY and OBJ readers parse, and the bytes
//! a triangle costs, at the peak of loading and once loaded. A 500k-triangle torus knot is
//! written to a temporary folder as a binary PLY (positions and faces, as scanners write them)
//! and as an OBJ, so the figures never depend on files on disk.

use crate::app::load_toml_str;
use crate::options::Options;
use crate::shape::TriangleMesh;
use crate::shape::mesh::load_ply;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// 2 x 7813 x 32 = 500,032 triangles.
const KNOT: (u32, u32) = (7813, 32);

/// A binary little-endian PLY of the mesh's positions and faces.
pub fn write_ply(mesh: &TriangleMesh, path: &Path) -> std::io::Result<()> {
    let mut w = std::io::BufWriter::with_capacity(1 << 20, std::fs::File::create(path)?);
    write!(
        w,
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.positions.len(),
        mesh.indices.len()
    )?;
    for p in &mesh.positions {
        for c in p.to_array() {
            w.write_all(&c.to_le_bytes())?;
        }
    }
    for t in &mesh.indices {
        w.write_all(&[3])?;
        for i in t {
            w.write_all(&i.to_le_bytes())?;
        }
    }
    w.flush()
}

/// An OBJ of the mesh's positions (six decimals, as exporters write them) and faces.
pub fn write_obj(mesh: &TriangleMesh, path: &Path) -> std::io::Result<()> {
    let mut w = std::io::BufWriter::with_capacity(1 << 20, std::fs::File::create(path)?);
    for p in &mesh.positions {
        writeln!(w, "v {:.6} {:.6} {:.6}", p.x, p.y, p.z)?;
    }
    for t in &mesh.indices {
        writeln!(w, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1)?;
    }
    w.flush()
}

/// A field of /proc/self/status in bytes (VmRSS, VmHWM), when there is one.
pub fn status_bytes(field: &str) -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with(field))?;
    Some(line.split_whitespace().nth(1)?.parse::<u64>().ok()? * 1024)
}

/// Resets the process's peak resident size to its current one (Linux), so a later VmHWM is the
/// peak of what ran since.
pub fn reset_peak() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// The best time of `repeats` runs of `f`.
fn best(repeats: u32, mut f: impl FnMut()) -> Duration {
    (0..repeats.max(1))
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed()
        })
        .min()
        .unwrap_or_default()
}

/// Prints the parse rates of both readers and the bytes per triangle of the knot.
pub fn run(repeats: u32, say: impl Fn(std::fmt::Arguments)) {
    let dir: PathBuf = std::env::temp_dir().join(format!("caustic-bench-meshes-{}", std::process::id()));
    let knot = TriangleMesh::torus_knot(2, 3, 1.5, 0.28, KNOT.0, KNOT.1);
    let (ply, obj) = (dir.join("knot.ply"), dir.join("knot.obj"));
    let written =
        std::fs::create_dir_all(&dir).and_then(|_| write_ply(&knot, &ply)).and_then(|_| write_obj(&knot, &obj));
    if let Err(e) = written {
        say(format_args!("big meshes: cannot write the knot into {}: {e}", dir.display()));
        return;
    }
    let tris = knot.indices.len();
    drop(knot);
    for (path, name) in [(&ply, "PLY (binary)"), (&obj, "OBJ")] {
        let size = std::fs::metadata(path).map_or(0, |m| m.len());
        let t = best(repeats, || {
            let m = if name == "OBJ" { TriangleMesh::load_obj(path) } else { load_ply(path) };
            assert_eq!(m.map(|m| m.indices.len()).ok(), Some(tris), "the bench knot reads back");
        });
        say(format_args!(
            "{name} parse ({tris} triangles, {:.1} MB): {:.0} MB/s, {:.2} M triangles/s ({:.3} s)",
            size as f64 / 1e6,
            size as f64 / t.as_secs_f64() / 1e6,
            tris as f64 / t.as_secs_f64() / 1e6,
            t.as_secs_f64()
        ));
    }
    // The peak of loading the PLY knot as a scene (read, normals, primitives, BVH build), over
    // what the process held before, and the geometry the loaded scene keeps.
    let scene = format!(
        "[camera]\neye = [0, 0, 8]\nlook_at = [0, 0, 0]\n[materials.m]\ntype = \"diffuse\"\n\
         [[objects]]\ntype = \"mesh\"\nfile = \"{}\"\nmaterial = \"m\"\n",
        ply.display()
    );
    let before = status_bytes("VmRSS:");
    let reset = reset_peak();
    let t = Instant::now();
    let loaded = load_toml_str(&scene, "bench:big-mesh", Path::new("."), &Options::default());
    let load_time = t.elapsed();
    let peak = status_bytes("VmHWM:");
    match loaded {
        Ok(s) => {
            let per = |b: u64| b as f64 / s.info.triangles as f64;
            let peak = match (reset, before, peak) {
                (true, Some(b), Some(p)) => format!("{:.0} bytes/triangle at peak", per(p.saturating_sub(b))),
                _ => "peak not measurable here".to_string(),
            };
            say(format_args!(
                "big mesh (PLY knot, {} triangles): load + BVH {:.3} s, {peak}, {:.0} bytes/triangle loaded (mesh, primitives, leaves, nodes)",
                s.info.triangles,
                load_time.as_secs_f64(),
                per(s.scene.geometry_bytes())
            ));
        }
        Err(e) => say(format_args!("big mesh: the knot scene did not load: {e}")),
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Parse rates of big files (`scripts/make_big_knot.py`):
    /// `CAUSTIC_BIG_MESHES=/tmp/caustic-knot cargo test --release --lib big_files_parse_rate -- --ignored --nocapture`.
    #[test]
    #[ignore]
    fn big_files_parse_rate() {
        let Some(dir) = std::env::var_os("CAUSTIC_BIG_MESHES").map(std::path::PathBuf::from) else { return };
        for file in ["knot.ply", "knot.obj", "knot-vn.obj"] {
            let path = dir.join(file);
            let Ok(meta) = std::fs::metadata(&path) else { continue };
            let size = meta.len() as f64;
            // The reader's peak over what it returns: its own temporaries.
            let before = status_bytes("VmRSS:").unwrap_or(0);
            reset_peak();
            let t = std::time::Instant::now();
            let m = TriangleMesh::load(&path).unwrap();
            let s = t.elapsed().as_secs_f64();
            let peak = status_bytes("VmHWM:").unwrap_or(0).saturating_sub(before) as f64;
            let tris = m.indices.len() as f64;
            println!(
                "{file}: {tris} triangles, {} vertices, {:.1} MB in {s:.3} s: {:.0} MB/s; mesh {:.1} bytes/triangle, reading peak {:.1}",
                m.positions.len(),
                size / 1e6,
                size / s / 1e6,
                m.memory_bytes() as f64 / tris,
                peak / tris
            );
        }
        // tobj, the OBJ reader before ours, on the same file (reading it whole, as the loader did).
        let t = std::time::Instant::now();
        let bytes = std::fs::read(dir.join("knot.obj")).unwrap();
        let opts = tobj::LoadOptions { single_index: true, triangulate: true, ignore_points: true, ignore_lines: true };
        let (models, _) = tobj::load_obj_buf(&mut &bytes[..], &opts, |_| Ok(Default::default())).unwrap();
        let s = t.elapsed().as_secs_f64();
        println!(
            "knot.obj with tobj: {} triangles in {s:.3} s: {:.0} MB/s",
            models[0].mesh.indices.len() / 3,
            bytes.len() as f64 / s / 1e6
        );
    }
}
