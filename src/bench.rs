//! Fixed benchmark scenes and throughput measurements, shared by `caustic bench` and
//! `cargo bench`. The scenes are compiled in, so the numbers never depend on files on disk.

use crate::app::{LoadedScene, load_toml_str};
use crate::geometry::Ray;
use crate::math::Vec2;
use crate::render::RenderStats;
use crate::scene::Overrides;
use rayon::prelude::*;
use std::path::Path;
use std::time::{Duration, Instant};

/// A 102,400-triangle torus knot filling a 1024 x 1024 frame.
pub const MESH_SCENE: &str = include_str!("../benches/scenes/mesh.toml");
/// The bundled 100k-triangle example scene (torus knot on a floor, between two spheres).
pub const KNOT_EXAMPLE: &str = include_str!("../scenes/07-torus-knot.toml");
/// The Cornell box with a point light (photon-tracing throughput).
pub const CORNELL_POINT: &str = include_str!("../scenes/12-cornell-point.toml");
/// 512 x 512, 4 x 4 spp, max_depth 6 (five reflections or refractions), mirror and Fresnel-glass
/// spheres, two point lights.
pub const WHITTED_SCENE: &str = include_str!("../benches/scenes/whitted.toml");

pub fn load(text: &str, name: &str) -> LoadedScene {
    load_sized(text, name, &Overrides::default())
}

fn load_sized(text: &str, name: &str, o: &Overrides) -> LoadedScene {
    match load_toml_str(text, name, Path::new("."), o) {
        Ok(s) => s,
        Err(e) => panic!("built-in benchmark scene {name} is invalid: {e}"),
    }
}

/// One camera ray per pixel through the centre, closest hit only (no shading), in parallel over
/// rows. Returns (rays, hits, wall time).
pub fn primary_rays(s: &LoadedScene) -> (u64, u64, Duration) {
    let cam = &s.scene.camera;
    let start = Instant::now();
    let hits: u64 = (0..cam.height)
        .into_par_iter()
        .map(|y| {
            let mut hits = 0u64;
            for x in 0..cam.width {
                let ray: Ray = cam.generate_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5), Vec2::splat(0.5));
                hits += s.scene.intersect(&ray, f32::INFINITY).is_some() as u64;
            }
            hits
        })
        .sum();
    (cam.width as u64 * cam.height as u64, hits, start.elapsed())
}

/// A full Whitted render of a loaded scene with its own settings.
pub fn whitted_render(s: &LoadedScene) -> RenderStats {
    s.render().stats
}

/// Prints a line, ignoring a closed stdout (e.g. piped into `head`).
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

/// Runs every benchmark `repeats` times and prints the best figures.
pub fn run_all(repeats: u32) {
    let threads = rayon::current_num_threads();
    say!("caustic bench: {threads} threads, best of {repeats}");

    let t0 = Instant::now();
    let mesh = load(MESH_SCENE, "bench:mesh");
    say!(
        "mesh scene: {} triangles, load + BVH build {:.3} s (BVH build alone {:.3} s, {} nodes)",
        mesh.info.triangles,
        t0.elapsed().as_secs_f64(),
        mesh.info.bvh_build.as_secs_f64(),
        mesh.info.bvh_nodes
    );
    let best = (0..repeats).map(|_| primary_rays(&mesh)).min_by_key(|r| r.2).unwrap_or_default();
    say!(
        "primary rays (mesh, 1024x1024, closest hit, no shading): {:.2} Mrays/s ({} hits of {} rays, {:.3} s)",
        best.0 as f64 / best.2.as_secs_f64() / 1e6,
        best.1,
        best.0,
        best.2.as_secs_f64()
    );

    let size = Overrides { width: Some(1920), height: Some(1440), ..Default::default() };
    let knot = load_sized(KNOT_EXAMPLE, "scenes/07-torus-knot.toml", &size);
    let best = (0..repeats).map(|_| primary_rays(&knot)).min_by_key(|r| r.2).unwrap_or_default();
    say!(
        "primary rays (scenes/07-torus-knot.toml at 1920x1440, closest hit incl. its floor plane): {:.2} Mrays/s ({:.3} s)",
        best.0 as f64 / best.2.as_secs_f64() / 1e6,
        best.2.as_secs_f64()
    );

    let cornell = load(CORNELL_POINT, "scenes/12-cornell-point.toml");
    let n = 1_000_000;
    let best = (0..repeats)
        .map(|r| {
            let t = Instant::now();
            let pass =
                crate::photon::trace::trace_global(&cornell.scene, n, r as u64, crate::photon::trace::Watch::none());
            (t.elapsed(), pass.hits.len())
        })
        .min_by_key(|r| r.0)
        .unwrap_or_default();
    say!(
        "photon tracing (Cornell box, point light, 1M photons emitted): {:.2} M photons/s emitted, {} stored ({:.2} M stored/s), {:.3} s",
        n as f64 / best.0.as_secs_f64() / 1e6,
        best.1,
        best.1 as f64 / best.0.as_secs_f64() / 1e6,
        best.0.as_secs_f64()
    );

    let whitted = load(WHITTED_SCENE, "bench:whitted");
    let best = (0..repeats).map(|_| whitted_render(&whitted)).min_by_key(|r| r.wall).unwrap_or_default();
    say!(
        "whitted render (512x512, 16 spp, 5 reflections): {:.3} s wall, {} rays ({} shadow), {:.2} Mrays/s",
        best.wall.as_secs_f64(),
        best.rays.total(),
        best.rays.shadow_rays,
        best.mrays_per_second()
    );
}
