//! `cargo bench --bench bvh_compare`: our 4-wide BVH (`ours`), the binary BVH it replaced
//! (`old`, kept in `bvh_compare/binary.rs`) and obvhs 0.4 (PLOC BVH2 and the 8-wide compressed
//! CWBVH), issues #2 and #15. Scene: the 102,400-triangle torus knot of `MESH_SCENE`.
//!
//! - Build time: `Bvh::build` against obvhs's presets. Both build on rayon (2 threads here).
//!   The obvhs figures include permuting the triangles into leaf order, which our build also does.
//!   `build_*_5m`: the same knot with 5,120,000 triangles (segments = 80,000).
//! - Traversal: closest hit, and every variant calls OUR watertight `intersect_triangle` on
//!   triangles stored in leaf order (no index indirection), so only the tree and its traversal
//!   differ. "camera" = the 1024 x 1024 pinhole rays through pixel centres of `MESH_SCENE`;
//!   "incoherent" = 1M rays with random origins inside the knot's bounding box and random
//!   directions. `_1t` runs on the bench thread; `_2t` uses rayon over 1024-ray rows.
//!   The `items/s` column is rays per second. For the obvhs traversals `P = 0` is the tree built
//!   with `fast_build()`, `P = 1` with `medium_build()`.
//!
//! - Occlusion (`occluded_*`): the incoherent rays as shadow rays, any hit within `SHADOW_T`
//!   (a quarter of the knot box's diagonal), stopping at the first hit.
//!
//! - `BVH_CPU_TIME=5 cargo bench --bench bvh_compare -- NOTHING`: the one-thread table by CPU
//!   time, interleaved (see `cpu_time_table`), for a machine shared with other work.
//!
//! Before the benchmarks run, every ray is traced through every tree and the hit count and each
//! closest distance (relative 1e-5) must agree with ours, and every tree must agree on which
//! shadow rays are blocked, or the binary panics.

#[path = "bvh_compare/binary.rs"]
mod binary;

use caustic::accel::Bvh;
use caustic::bench::{MESH_SCENE, incoherent_rays, knot_primitives, load};
use caustic::geometry::{Aabb, Ray};
use caustic::math::{Vec2, Vec3, Vec3A};
use caustic::shape::{Primitive, RayShear, Shape, intersect_triangle};
use divan::counter::ItemsCount;
use obvhs::BvhBuildParams;
use obvhs::bvh2::Bvh2;
use obvhs::bvh2::builder::build_bvh2_from_tris;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::ray::RayHit;
use rayon::prelude::*;
use std::sync::LazyLock;
use std::time::Duration;

const ROW: usize = 1024;
const N_INCOHERENT: usize = 1 << 20;

fn main() {
    let d = &*DATA;
    println!(
        "torus knot: {} triangles; our BVH {} 4-wide nodes ({:.1} bytes per triangle), old binary BVH {} nodes; obvhs BVH2 fast/medium {}/{} nodes, CWBVH fast/medium {}/{} nodes",
        d.prims.len(),
        d.ours.node_count(),
        d.ours.node_bytes() as f64 / d.prims.len() as f64,
        d.old.node_count(),
        d.bvh2[0].0.nodes.len(),
        d.bvh2[1].0.nodes.len(),
        d.cwbvh[0].0.nodes.len(),
        d.cwbvh[1].0.nodes.len()
    );
    for (name, rays) in [("camera", &d.camera), ("incoherent", &d.incoherent)] {
        check(name, rays, d);
    }
    check_occlusion(d);
    if let Some(reps) = std::env::var("BVH_CPU_TIME").ok().and_then(|s| s.parse().ok()) {
        cpu_time_table(d, reps);
    }
    divan::main();
}

/// One thread's CPU time in nanoseconds (Linux), or `None`.
fn thread_cpu_ns() -> Option<u64> {
    std::fs::read_to_string("/proc/thread-self/schedstat").ok()?.split_whitespace().next()?.parse().ok()
}

/// `BVH_CPU_TIME=N`: Mrays/s on one thread from the thread's CPU time rather than wall time,
/// the variants interleaved and the best of `reps` rounds kept, so that other processes on a
/// shared machine (which steal wall time, not CPU time) disturb the comparison less.
fn cpu_time_table(d: &Data, reps: usize) {
    type Trace<'a> = &'a dyn Fn(&Ray) -> bool;
    let t = d.shadow_t;
    let (cw, cw_tris) = &d.cwbvh[0];
    let rows: [(&str, &[Ray], [Trace; 3]); 3] = [
        (
            "camera, closest hit",
            &d.camera,
            [&|r| ours_t(&d.ours, r).is_finite(), &|r| old_t(&d.old, r).is_finite(), &|r| {
                cwbvh_t(cw, cw_tris, r).is_finite()
            }],
        ),
        (
            "incoherent, closest hit",
            &d.incoherent,
            [&|r| ours_t(&d.ours, r).is_finite(), &|r| old_t(&d.old, r).is_finite(), &|r| {
                cwbvh_t(cw, cw_tris, r).is_finite()
            }],
        ),
        (
            "incoherent, occlusion",
            &d.incoherent,
            [&|r| d.ours.occluded(r, t), &|r| d.old.occluded(r, t), &|r| cwbvh_occluded(cw, cw_tris, r, t)],
        ),
    ];
    let mut best = [[0.0f64; 3]; 3];
    for _ in 0..reps {
        for (row, (_, rays, fs)) in rows.iter().enumerate() {
            for (col, f) in fs.iter().enumerate() {
                let (c0, w0) = (thread_cpu_ns(), std::time::Instant::now());
                divan::black_box(rays.iter().filter(|r| f(r)).count());
                let secs = match (c0, thread_cpu_ns()) {
                    (Some(a), Some(b)) => (b - a) as f64 * 1e-9,
                    _ => w0.elapsed().as_secs_f64(),
                };
                best[row][col] = best[row][col].max(rays.len() as f64 / secs / 1e6);
            }
        }
    }
    println!(
        "one thread, Mrays/s by CPU time, best of {reps} interleaved rounds: ours / old binary / obvhs CWBVH fast"
    );
    for (row, (name, _, _)) in rows.iter().enumerate() {
        let b = best[row];
        println!(
            "  {name}: {:.2} / {:.2} / {:.2} (ours/old {:.2}, ours/CWBVH {:.2})",
            b[0],
            b[1],
            b[2],
            b[0] / b[1],
            b[0] / b[2]
        );
    }
}

fn preset(name: &str) -> BvhBuildParams {
    match name {
        "fastest" => BvhBuildParams::fastest_build(),
        "very_fast" => BvhBuildParams::very_fast_build(),
        "fast" => BvhBuildParams::fast_build(),
        "medium" => BvhBuildParams::medium_build(),
        _ => unreachable!(),
    }
}

/// Presets whose trees are traced (index into `Data::bvh2` / `Data::cwbvh`).
const TRACED: [&str; 2] = ["fast", "medium"];

struct Data {
    prims: Vec<Primitive>,
    old: binary::Bvh,
    otris: Vec<obvhs::triangle::Triangle>,
    ours: Bvh,
    /// Each tree with its triangles permuted into leaf order.
    bvh2: Vec<(Bvh2, Vec<[Vec3; 3]>)>,
    cwbvh: Vec<(CwBvh, Vec<[Vec3; 3]>)>,
    camera: Vec<Ray>,
    incoherent: Vec<Ray>,
    /// Distance limit of the occlusion rays.
    shadow_t: f32,
}

/// The knot of `MESH_SCENE` (1600 segments: 102,400 triangles).
fn knot_prims(segments: u32) -> Vec<Primitive> {
    knot_primitives(segments)
}

fn obvhs_tris(prims: &[Primitive]) -> Vec<obvhs::triangle::Triangle> {
    prims
        .iter()
        .map(|p| match p.shape {
            Shape::Triangle(t) => {
                obvhs::triangle::Triangle { v0: Vec3A::from(t.p[0]), v1: Vec3A::from(t.p[1]), v2: Vec3A::from(t.p[2]) }
            }
            _ => unreachable!(),
        })
        .collect()
}

fn leaf_order(otris: &[obvhs::triangle::Triangle], indices: &[u32]) -> Vec<[Vec3; 3]> {
    indices
        .iter()
        .map(|&i| {
            let t = &otris[i as usize];
            [Vec3::from(t.v0), Vec3::from(t.v1), Vec3::from(t.v2)]
        })
        .collect()
}

fn build_bvh2(otris: &[obvhs::triangle::Triangle], p: BvhBuildParams) -> (Bvh2, Vec<[Vec3; 3]>) {
    let bvh = build_bvh2_from_tris(otris, p, &mut Duration::default());
    let tris = leaf_order(otris, &bvh.primitive_indices);
    (bvh, tris)
}

fn build_cwbvh(otris: &[obvhs::triangle::Triangle], p: BvhBuildParams) -> (CwBvh, Vec<[Vec3; 3]>) {
    let bvh = build_cwbvh_from_tris(otris, p, &mut Duration::default());
    let tris = leaf_order(otris, &bvh.primitive_indices);
    (bvh, tris)
}

static DATA: LazyLock<Data> = LazyLock::new(|| {
    let prims = knot_prims(1600);
    let otris = obvhs_tris(&prims);
    let ours = Bvh::build(prims.clone(), &[]);
    let old = binary::Bvh::build(prims.clone());
    let bvh2 = TRACED.iter().map(|p| build_bvh2(&otris, preset(p))).collect();
    let cwbvh = TRACED.iter().map(|p| build_cwbvh(&otris, preset(p))).collect();

    let scene = load(MESH_SCENE, "mesh");
    let cam = &scene.scene.camera;
    assert_eq!(cam.width as usize, ROW);
    let mut camera = Vec::with_capacity((cam.width * cam.height) as usize);
    for y in 0..cam.height {
        for x in 0..cam.width {
            camera.push(cam.generate_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5), Vec2::splat(0.5)));
        }
    }

    // The knot's exact bounds (the rays of BENCHMARKS.md's tables).
    let b = prims.iter().fold(Aabb::EMPTY, |b, p| b.union(p.shape.bounds()));
    let incoherent = incoherent_rays(b, N_INCOHERENT);
    let shadow_t = 0.25 * (b.max - b.min).length();
    Data { prims, old, otris, ours, bvh2, cwbvh, camera, incoherent, shadow_t }
});

#[inline(always)]
fn ours_t(bvh: &Bvh, ray: &Ray) -> f32 {
    bvh.intersect(ray, f32::INFINITY).map_or(f32::INFINITY, |(_, h)| h.t)
}

#[inline(always)]
fn old_t(bvh: &binary::Bvh, ray: &Ray) -> f32 {
    bvh.intersect(ray, f32::INFINITY).map_or(f32::INFINITY, |(_, h)| h.t)
}

#[inline(always)]
fn cwbvh_occluded(bvh: &CwBvh, tris: &[[Vec3; 3]], ray: &Ray, t_max: f32) -> bool {
    let shear = RayShear::new(ray);
    let o = obvhs::ray::Ray::new(Vec3A::from(ray.o), Vec3A::from(ray.d), 0.0, t_max);
    !bvh.ray_traverse_miss(o, |r, id| intersect_triangle(&tris[id], ray, &shear, r.tmax).map_or(f32::INFINITY, |h| h.t))
}

#[inline(always)]
fn oray(ray: &Ray) -> obvhs::ray::Ray {
    obvhs::ray::Ray::new_inf(Vec3A::from(ray.o), Vec3A::from(ray.d))
}

#[inline(always)]
fn bvh2_t(bvh: &Bvh2, tris: &[[Vec3; 3]], ray: &Ray) -> f32 {
    let shear = RayShear::new(ray);
    let mut hit = RayHit::none();
    if bvh.ray_traverse(oray(ray), &mut hit, |r, id| {
        intersect_triangle(&tris[id], ray, &shear, r.tmax).map_or(f32::INFINITY, |h| h.t)
    }) {
        hit.t
    } else {
        f32::INFINITY
    }
}

#[inline(always)]
fn cwbvh_t(bvh: &CwBvh, tris: &[[Vec3; 3]], ray: &Ray) -> f32 {
    let shear = RayShear::new(ray);
    let mut hit = RayHit::none();
    if bvh.ray_traverse(oray(ray), &mut hit, |r, id| {
        intersect_triangle(&tris[id], ray, &shear, r.tmax).map_or(f32::INFINITY, |h| h.t)
    }) {
        hit.t
    } else {
        f32::INFINITY
    }
}

/// Every tree must return our closest distances, ray by ray.
fn check(name: &str, rays: &[Ray], d: &Data) {
    let reference: Vec<f32> = rays.par_iter().map(|r| ours_t(&d.ours, r)).collect();
    let hits = reference.iter().filter(|t| t.is_finite()).count();
    let compare = |label: String, f: &(dyn Fn(&Ray) -> f32 + Sync)| {
        let ts: Vec<f32> = rays.par_iter().map(f).collect();
        let other_hits = ts.iter().filter(|t| t.is_finite()).count();
        let bad = reference
            .iter()
            .zip(&ts)
            .filter(|(a, b)| {
                if a.is_finite() != b.is_finite() {
                    return true;
                }
                a.is_finite() && (*a - *b).abs() > 1e-5 * a.abs()
            })
            .count();
        println!("check {name} rays, {label}: {other_hits} hits (ours {hits}), {bad} rays disagree");
        assert_eq!(other_hits, hits, "{name} {label}: hit counts differ");
        assert_eq!(bad, 0, "{name} {label}: closest distances differ");
    };
    compare("old binary BVH".into(), &|r| old_t(&d.old, r));
    for (i, p) in TRACED.iter().enumerate() {
        let (bvh, tris) = &d.bvh2[i];
        compare(format!("obvhs BVH2 {p}"), &|r| bvh2_t(bvh, tris, r));
        let (bvh, tris) = &d.cwbvh[i];
        compare(format!("obvhs CWBVH {p}"), &|r| cwbvh_t(bvh, tris, r));
    }
}

/// Every tree must block the same shadow rays, and those are the rays whose closest hit is
/// within the limit.
fn check_occlusion(d: &Data) {
    let t = d.shadow_t;
    let closest: Vec<bool> = d.incoherent.par_iter().map(|r| ours_t(&d.ours, r) < t).collect();
    let blocked = closest.iter().filter(|b| **b).count();
    type Occluded<'a> = &'a (dyn Fn(&Ray) -> bool + Sync);
    let variants: [(&str, Occluded); 3] = [
        ("ours", &|r| d.ours.occluded(r, t)),
        ("old binary BVH", &|r| d.old.occluded(r, t)),
        ("obvhs CWBVH fast", &|r| cwbvh_occluded(&d.cwbvh[0].0, &d.cwbvh[0].1, r, t)),
    ];
    for (label, f) in variants {
        let got: Vec<bool> = d.incoherent.par_iter().map(f).collect();
        let bad = got.iter().zip(&closest).filter(|(a, b)| a != b).count();
        println!(
            "check occlusion rays (t_max {t:.3}), {label}: {blocked} blocked by the closest hit, {bad} rays disagree"
        );
        assert_eq!(bad, 0, "occlusion {label} disagrees");
    }
}

// ---------------------------------------------------------------- build

#[divan::bench(sample_count = 10)]
fn build_ours(bencher: divan::Bencher) {
    let prims = knot_prims(1600);
    bencher.with_inputs(|| prims.clone()).bench_local_values(|p| Bvh::build(p, &[]));
}

#[divan::bench(sample_count = 10)]
fn build_old(bencher: divan::Bencher) {
    let prims = knot_prims(1600);
    bencher.with_inputs(|| prims.clone()).bench_local_values(binary::Bvh::build);
}

#[divan::bench(sample_count = 3, sample_size = 1)]
fn build_ours_5m(bencher: divan::Bencher) {
    let prims = knot_prims(80_000);
    bencher
        .counter(ItemsCount::new(prims.len()))
        .with_inputs(|| prims.clone())
        .bench_local_values(|p| Bvh::build(p, &[]));
}

#[divan::bench(sample_count = 3, sample_size = 1)]
fn build_old_5m(bencher: divan::Bencher) {
    let prims = knot_prims(80_000);
    bencher.counter(ItemsCount::new(prims.len())).with_inputs(|| prims.clone()).bench_local_values(binary::Bvh::build);
}

#[divan::bench(sample_count = 10, args = ["fastest", "very_fast", "fast", "medium"])]
fn build_obvhs_bvh2(bencher: divan::Bencher, p: &str) {
    let otris = &DATA.otris;
    bencher.bench_local(|| build_bvh2(divan::black_box(otris), preset(p)));
}

#[divan::bench(sample_count = 10, args = ["fastest", "very_fast", "fast", "medium"])]
fn build_obvhs_cwbvh(bencher: divan::Bencher, p: &str) {
    let otris = &DATA.otris;
    bencher.bench_local(|| build_cwbvh(divan::black_box(otris), preset(p)));
}

// ---------------------------------------------------------------- traversal

fn rays(which: &str) -> &'static [Ray] {
    match which {
        "camera" => &DATA.camera,
        "incoherent" => &DATA.incoherent,
        _ => unreachable!(),
    }
}

fn trace_1t(rays: &[Ray], f: impl Fn(&Ray) -> f32) -> usize {
    rays.iter().filter(|r| f(r).is_finite()).count()
}

fn trace_2t(rays: &[Ray], f: impl Fn(&Ray) -> f32 + Sync) -> usize {
    rays.par_chunks(ROW).map(|row| row.iter().filter(|r| f(r).is_finite()).count()).sum()
}

const RAYS: [&str; 2] = ["camera", "incoherent"];

#[divan::bench(sample_count = 5, sample_size = 1, args = RAYS)]
fn trace_ours_1t(bencher: divan::Bencher, which: &str) {
    let (rays, bvh) = (rays(which), &DATA.ours);
    bencher.counter(ItemsCount::new(rays.len())).bench_local(|| trace_1t(rays, |r| ours_t(bvh, r)));
}

#[divan::bench(sample_count = 5, sample_size = 1, args = RAYS)]
fn trace_ours_2t(bencher: divan::Bencher, which: &str) {
    let (rays, bvh) = (rays(which), &DATA.ours);
    bencher.counter(ItemsCount::new(rays.len())).bench_local(|| trace_2t(rays, |r| ours_t(bvh, r)));
}

#[divan::bench(sample_count = 5, sample_size = 1, args = RAYS)]
fn trace_old_1t(bencher: divan::Bencher, which: &str) {
    let (rays, bvh) = (rays(which), &DATA.old);
    bencher.counter(ItemsCount::new(rays.len())).bench_local(|| trace_1t(rays, |r| old_t(bvh, r)));
}

#[divan::bench(sample_count = 5, sample_size = 1, args = RAYS)]
fn trace_old_2t(bencher: divan::Bencher, which: &str) {
    let (rays, bvh) = (rays(which), &DATA.old);
    bencher.counter(ItemsCount::new(rays.len())).bench_local(|| trace_2t(rays, |r| old_t(bvh, r)));
}

#[divan::bench(sample_count = 5, sample_size = 1, consts = [0, 1], args = RAYS)]
fn trace_obvhs_bvh2_1t<const P: usize>(bencher: divan::Bencher, which: &str) {
    let (rays, (bvh, tris)) = (rays(which), &DATA.bvh2[P]);
    bencher.counter(ItemsCount::new(rays.len())).bench_local(|| trace_1t(rays, |r| bvh2_t(bvh, tris, r)));
}

#[divan::bench(sample_count = 5, sample_size = 1, consts = [0, 1], args = RAYS)]
fn trace_obvhs_bvh2_2t<const P: usize>(bencher: divan::Bencher, which: &str) {
    let (rays, (bvh, tris)) = (rays(which), &DATA.bvh2[P]);
    bencher.counter(ItemsCount::new(rays.len())).bench_local(|| trace_2t(rays, |r| bvh2_t(bvh, tris, r)));
}

#[divan::bench(sample_count = 5, sample_size = 1, consts = [0, 1], args = RAYS)]
fn trace_obvhs_cwbvh_1t<const P: usize>(bencher: divan::Bencher, which: &str) {
    let (rays, (bvh, tris)) = (rays(which), &DATA.cwbvh[P]);
    bencher.counter(ItemsCount::new(rays.len())).bench_local(|| trace_1t(rays, |r| cwbvh_t(bvh, tris, r)));
}

#[divan::bench(sample_count = 5, sample_size = 1, consts = [0, 1], args = RAYS)]
fn trace_obvhs_cwbvh_2t<const P: usize>(bencher: divan::Bencher, which: &str) {
    let (rays, (bvh, tris)) = (rays(which), &DATA.cwbvh[P]);
    bencher.counter(ItemsCount::new(rays.len())).bench_local(|| trace_2t(rays, |r| cwbvh_t(bvh, tris, r)));
}

// ---------------------------------------------------------------- occlusion

/// Blocked rays: the incoherent rays as shadow rays up to `shadow_t`.
fn occluded_2t(f: impl Fn(&Ray, f32) -> bool + Sync) -> usize {
    let t = DATA.shadow_t;
    DATA.incoherent.par_chunks(ROW).map(|row| row.iter().filter(|r| f(r, t)).count()).sum()
}

fn occluded_1t(f: impl Fn(&Ray, f32) -> bool) -> usize {
    let t = DATA.shadow_t;
    DATA.incoherent.iter().filter(|r| f(r, t)).count()
}

#[divan::bench(sample_count = 5, sample_size = 1)]
fn occluded_ours_1t(bencher: divan::Bencher) {
    let bvh = &DATA.ours;
    bencher.counter(ItemsCount::new(N_INCOHERENT)).bench_local(|| occluded_1t(|r, t| bvh.occluded(r, t)));
}

#[divan::bench(sample_count = 5, sample_size = 1)]
fn occluded_ours_2t(bencher: divan::Bencher) {
    let bvh = &DATA.ours;
    bencher.counter(ItemsCount::new(N_INCOHERENT)).bench_local(|| occluded_2t(|r, t| bvh.occluded(r, t)));
}

#[divan::bench(sample_count = 5, sample_size = 1)]
fn occluded_old_1t(bencher: divan::Bencher) {
    let bvh = &DATA.old;
    bencher.counter(ItemsCount::new(N_INCOHERENT)).bench_local(|| occluded_1t(|r, t| bvh.occluded(r, t)));
}

#[divan::bench(sample_count = 5, sample_size = 1)]
fn occluded_old_2t(bencher: divan::Bencher) {
    let bvh = &DATA.old;
    bencher.counter(ItemsCount::new(N_INCOHERENT)).bench_local(|| occluded_2t(|r, t| bvh.occluded(r, t)));
}

#[divan::bench(sample_count = 5, sample_size = 1)]
fn occluded_obvhs_cwbvh_1t(bencher: divan::Bencher) {
    let (bvh, tris) = &DATA.cwbvh[0];
    bencher.counter(ItemsCount::new(N_INCOHERENT)).bench_local(|| occluded_1t(|r, t| cwbvh_occluded(bvh, tris, r, t)));
}

#[divan::bench(sample_count = 5, sample_size = 1)]
fn occluded_obvhs_cwbvh_2t(bencher: divan::Bencher) {
    let (bvh, tris) = &DATA.cwbvh[0];
    bencher.counter(ItemsCount::new(N_INCOHERENT)).bench_local(|| occluded_2t(|r, t| cwbvh_occluded(bvh, tris, r, t)));
}
