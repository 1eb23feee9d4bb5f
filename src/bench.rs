//! Fixed benchmark scenes and throughput measurements, shared by `caustic bench` and
//! `cargo bench`. The scenes are compiled in, so the numbers never depend on files on disk.

use crate::accel::Bvh;
use crate::app::{LoadedScene, load_toml_str};
use crate::geometry::{Aabb, NO_LIGHT, Ray};
use crate::math::{Vec2, Vec3};
use crate::options::Options;
use crate::render::RenderStats;
use crate::shape::{Primitive, Shape, TriangleMesh};
use rayon::prelude::*;
use std::path::Path;
use std::time::{Duration, Instant};

pub mod meshes;

/// A 102,400-triangle torus knot filling a 1024 x 1024 frame.
pub const MESH_SCENE: &str = include_str!("../benches/scenes/mesh.toml");
/// The bundled 100k-triangle example scene (torus knot on a floor, between two spheres).
pub const KNOT_EXAMPLE: &str = include_str!("../scenes/07-torus-knot.toml");
/// The Cornell box with a point light (photon-tracing throughput).
pub const CORNELL_POINT: &str = include_str!("../scenes/12-cornell-point.toml");
/// 512 x 512, 4 x 4 spp, max_depth 6 (five reflections or refractions), mirror and Fresnel-glass
/// spheres, two point lights.
pub const WHITTED_SCENE: &str = include_str!("../benches/scenes/whitted.toml");

/// Segments and sides of the knot the instancing benchmark copies: 2 x 320 x 16 = 10,240
/// triangles.
const INSTANCED_KNOT: (u32, u32) = (320, 16);

/// The instancing benchmark scene: `side` x `side` copies of a 10,240-triangle torus knot on a
/// grid (3 units apart), each turned about y and scaled by 0.8 to 1.2, on a floor plane, seen
/// from above at 1024 x 1024 with a point light and the path tracer. `flat` writes every copy
/// out as its own knot instead of as an instance of one group (the same geometry).
pub fn instances_scene(side: u32, flat: bool) -> String {
    let extent = 3.0 * side as f32;
    let (segments, sides) = INSTANCED_KNOT;
    let mut s = format!(
        r#"# Benchmark: {n} copies of a 10,240-triangle torus knot ({how}), written by caustic::bench::instances_scene.
[render]
width = 1024
height = 1024
spp = 4
integrator = "path"
max_depth = 3

[camera]
eye = [{cx}, {ey}, {ez}]
look_at = [{cx}, 0, {cz}]
fov = 50

[materials.knot]
type = "diffuse"
color = [0.8, 0.55, 0.25]
[materials.floor]
type = "diffuse"
color = [0.5, 0.5, 0.5]

[[lights]]
type = "point"
position = [{cx}, {ly}, {cz}]
intensity = {li}

[[objects]]
type = "plane"
point = [0, -0.6, 0]
material = "floor"
"#,
        n = side * side,
        how = if flat { "each its own mesh" } else { "instances of one group" },
        cx = extent / 2.0 - 1.5,
        cz = extent / 2.0 - 1.5,
        ey = 0.75 * extent + 2.0,
        ez = extent * 1.25 + 2.0,
        ly = extent + 5.0,
        li = extent * extent * 2.0 + 50.0,
    );
    let knot =
        format!("type = \"torus_knot\"\nsegments = {segments}\nsides = {sides}\ntube = 0.3\nmaterial = \"knot\"\n");
    if !flat {
        s += &format!("\n[[groups.knot.objects]]\n{knot}");
    }
    for i in 0..side * side {
        let (x, z) = ((i % side) as f32 * 3.0, (i / side) as f32 * 3.0);
        let (angle, scale) = ((i * 37) % 360, 0.8 + 0.4 * ((i * 7) % 11) as f32 / 10.0);
        let t = format!(
            "transform = [{{ scale = {scale} }}, {{ rotate = {{ axis = [0, 1, 0], degrees = {angle} }} }}, {{ translate = [{x}, 0, {z}] }}]"
        );
        s += &if flat {
            format!("\n[[objects]]\n{knot}{t}\n")
        } else {
            format!("\n[[objects]]\ntype = \"instance\"\ngroup = \"knot\"\n{t}\n")
        };
    }
    s
}

/// The generated benchmark scenes, by file name, for `caustic bench --write-scenes`.
pub fn generated_scenes() -> Vec<(&'static str, String)> {
    vec![
        ("instances-10000.toml", instances_scene(100, false)),
        ("instances-100.toml", instances_scene(10, false)),
        ("flat-100.toml", instances_scene(10, true)),
    ]
}

pub fn load(text: &str, name: &str) -> LoadedScene {
    load_sized(text, name, &Options::default())
}

fn load_sized(text: &str, name: &str, o: &Options) -> LoadedScene {
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

/// splitmix64 of a counter, mapped to [0, 1).
fn uniform(i: u64) -> f32 {
    let mut z = i.wrapping_mul(0x9e37_79b9_7f4a_7c15).wrapping_add(0x632b_e59b_d9b4_e019);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
}

/// `n` rays with origins uniform in `b` and directions uniform on the sphere, the same for
/// every run (the incoherent rays of `benches/bvh_compare.rs` and `caustic bench`).
pub fn incoherent_rays(b: Aabb, n: usize) -> Vec<Ray> {
    (0..n as u64)
        .map(|i| {
            let u = |k: u64| uniform(i * 5 + k);
            let o = b.min + (b.max - b.min) * Vec3::new(u(0), u(1), u(2));
            let z = 1.0 - 2.0 * u(3);
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = std::f32::consts::TAU * u(4);
            Ray::new(o, Vec3::new(r * phi.cos(), r * phi.sin(), z))
        })
        .collect()
}

/// Closest hits of `rays` in `s` in parallel over 1024-ray chunks: (hits, wall time).
pub fn trace_rays(s: &LoadedScene, rays: &[Ray]) -> (u64, Duration) {
    let start = Instant::now();
    let hits = rays
        .par_chunks(1024)
        .map(|c| c.iter().filter(|r| s.scene.intersect(r, f32::INFINITY).is_some()).count() as u64)
        .sum();
    (hits, start.elapsed())
}

/// The triangles of a torus knot with `segments` x 32 x 2 triangles, as primitives.
pub fn knot_primitives(segments: u32) -> Vec<Primitive> {
    let mesh = TriangleMesh::torus_knot(2, 3, 1.0, 0.28, segments, 32);
    mesh.triangles(0)
        .0
        .into_iter()
        .map(|t| Primitive { shape: Shape::Triangle(t), material: 0, light: NO_LIGHT })
        .collect()
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
    // First, while the process holds little, so its peak memory is the big mesh's own.
    meshes::run(repeats, |a| say!("{a}"));

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

    let rays = incoherent_rays(mesh.scene.bounds(), 1 << 20);
    let best = (0..repeats).map(|_| trace_rays(&mesh, &rays)).min_by_key(|r| r.1).unwrap_or_default();
    say!(
        "incoherent rays (mesh, 1M fixed-seed rays from inside the knot's box, closest hit): {:.2} Mrays/s ({} hits, {:.3} s)",
        rays.len() as f64 / best.1.as_secs_f64() / 1e6,
        best.0,
        best.1.as_secs_f64()
    );
    drop(rays);

    let prims = knot_primitives(16_000);
    let best = (0..repeats)
        .map(|_| {
            let p = prims.clone();
            let t = Instant::now();
            let bvh = Bvh::build(p, &[]);
            (t.elapsed(), bvh.node_bytes())
        })
        .min_by_key(|r| r.0)
        .unwrap_or_default();
    say!(
        "BVH build ({} triangles, torus knot): {:.2} M triangles/s ({:.3} s), nodes {:.1} bytes per triangle",
        prims.len(),
        prims.len() as f64 / best.0.as_secs_f64() / 1e6,
        best.0.as_secs_f64(),
        best.1 as f64 / prims.len() as f64
    );
    drop(prims);

    let size = Options { width: Some(1920), height: Some(1440), ..Default::default() };
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
            let pass = crate::photon::trace::trace_global(
                &cornell.scene,
                n,
                r as u64,
                cornell.integrator.ray_bias(&cornell.scene),
                crate::photon::trace::Watch::none(),
            );
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

    final_gather(repeats);

    instancing(repeats);

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

/// Final gathering on the point-lit Cornell box at 128 x 128, 4 spp, 16 gather rays per sample
/// over 200k global photons (no caustics): with every sample gathering (rays per second of the
/// render) and with the irradiance cache (its fill and the render).
fn final_gather(repeats: u32) {
    use crate::options::{IntegratorKind, PhotonOptions};
    let run = |a: f32| {
        let photon = PhotonOptions {
            photons: Some(200_000),
            caustic_photons: Some(0),
            gather: Some(16),
            irradiance_cache: Some(a),
            ..Default::default()
        };
        let o = Options {
            width: Some(128),
            height: Some(128),
            spp: Some(4),
            integrator: Some(IntegratorKind::Photon),
            photon,
            ..Default::default()
        };
        let s = load_sized(CORNELL_POINT, "scenes/12-cornell-point.toml", &o);
        let t = Instant::now();
        let stats = s.render().stats;
        (t.elapsed(), stats)
    };
    let best = (0..repeats).map(|_| run(0.0)).min_by_key(|r| r.0).unwrap_or_default();
    say!(
        "final gather (Cornell box, point light, 128x128, 4 spp x 16 gather rays, no cache): {:.2} Mrays/s in the render ({} rays, {:.3} s render, {:.3} s with the maps)",
        best.1.mrays_per_second(),
        best.1.rays.total(),
        best.1.wall.as_secs_f64(),
        best.0.as_secs_f64()
    );
    let best = (0..repeats).map(|_| run(0.25)).min_by_key(|r| r.0).unwrap_or_default();
    say!(
        "final gather with the irradiance cache (the same, a = 0.25): {:.3} s render, {:.3} s with the maps and the cache",
        best.1.wall.as_secs_f64(),
        best.0.as_secs_f64()
    );
}

/// Instancing: 10,000 copies of a 10,240-triangle knot (load, build, memory, primary rays), and
/// primary rays through 100 copies as instances against the same geometry flattened into one
/// BVH, alternating the two so both see the same machine load.
fn instancing(repeats: u32) {
    let t0 = Instant::now();
    let many = load(&instances_scene(100, false), "bench:instances-10000");
    say!(
        "instances: {} copies of a {}-triangle knot, load + build {:.3} s, instances and BVHs {:.1} MB, {} BVH nodes",
        many.info.instances,
        many.info.triangles,
        t0.elapsed().as_secs_f64(),
        many.scene.instances.memory_bytes() as f64 / 1e6,
        many.info.bvh_nodes
    );
    let best = (0..repeats).map(|_| primary_rays(&many)).min_by_key(|r| r.2).unwrap_or_default();
    say!(
        "primary rays (10,000 instances, 1024x1024, {:.0}% of rays on a knot): {:.2} Mrays/s",
        100.0 * knot_share(&many),
        best.0 as f64 / best.2.as_secs_f64() / 1e6,
    );
    drop(many);
    let inst = load(&instances_scene(10, false), "bench:instances-100");
    let t0 = Instant::now();
    let flat = load(&instances_scene(10, true), "bench:flat-100");
    say!(
        "flattened: 100 knots, {} triangles in one BVH, load + build {:.3} s",
        flat.info.triangles,
        t0.elapsed().as_secs_f64()
    );
    let (mut bi, mut bf) = (Duration::MAX, Duration::MAX);
    let mut hits = (0, 0);
    for _ in 0..repeats.max(3) {
        let (_, h, t) = primary_rays(&inst);
        bi = bi.min(t);
        let (_, g, u) = primary_rays(&flat);
        bf = bf.min(u);
        hits = (h, g);
    }
    let rays = inst.scene.camera.width as f64 * inst.scene.camera.height as f64;
    say!(
        "primary rays, 100 knots (1024x1024, {:.0}% of rays on a knot): instanced {:.2} Mrays/s, flattened {:.2} Mrays/s, instanced/flattened time {:.3} (hits {} / {})",
        100.0 * knot_share(&inst),
        rays / bi.as_secs_f64() / 1e6,
        rays / bf.as_secs_f64() / 1e6,
        bi.as_secs_f64() / bf.as_secs_f64(),
        hits.0,
        hits.1
    );
}

/// The share of camera rays (through pixel centres) whose closest hit is on an instance.
fn knot_share(s: &LoadedScene) -> f64 {
    let cam = &s.scene.camera;
    // The knots' material (the floor is a plane of another: planes are numbered with the BVH's
    // primitives, so a primitive index no longer tells them apart).
    let knot = s.scene.materials.names.iter().position(|n| n == "knot").map_or(u32::MAX, |i| i as u32);
    let on: u64 = (0..cam.height)
        .into_par_iter()
        .map(|y| {
            (0..cam.width)
                .filter(|&x| {
                    let ray = cam.generate_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5), Vec2::splat(0.5));
                    s.scene.intersect(&ray, f32::INFINITY).is_some_and(|h| h.material == knot)
                })
                .count() as u64
        })
        .sum();
    on as f64 / (cam.width as f64 * cam.height as f64)
}
