//! `cargo bench --bench ray_batches`: would tracing rays eight at a time (a wavefront core, SIMD
//! across rays, as Mitsuba 3's LLVM variants do) find closest hits faster than our one ray at a
//! time? Issue 29 asked for the choice to be made by measurement.
//!
//! Scene: the diffuse Cornell box of `scenes/mitsuba/cornell-box.xml` (18 quads, which the BVH
//! tests through a flat scan of their boxes). Rays: about 900,000 incoherent rays shaped like
//! a path tracer's bounces, from points on the walls and boxes into random directions on the
//! side they face.
//!
//! - `one at a time`: `Bvh::intersect_tree`, what the renderer runs (box scan, then the quads
//!   whose boxes the ray enters).
//! - `eight rays at a time`: the same quad test (`shape::intersect_quad`, operation for
//!   operation) on eight rays at once in lanes, every quad for every ray, as a wavefront core
//!   with no culling per ray would. Compiled once for the build's target (SSE2) and once with
//!   AVX2 (eight lanes in one register), run when the processor has it.
//! - `one ray, eight quads at a time`: the other way round (SIMD across primitives, what the
//!   packets of `accel::packet` do four at a time for scenes of up to 8 primitives), AVX2, with
//!   a branch-free choice of the closest lane.
//!
//! Before timing, every ray's closest hit from the lanes is checked against the renderer's; they
//! may differ only where two quads meet and their distances agree within 1e-6 (the scan skips a
//! quad whose box it enters an ulp after the hit), or the bench panics. Each figure is the best
//! of five rounds, in nanoseconds per ray, on the bench's one thread.

use caustic::geometry::Ray;
use caustic::shape::{Shape, intersect_quad};
use std::hint::black_box;
use std::time::Instant;

const LANES: usize = 8;

/// One quad's constants, as `intersect_quad` makes them (`c = e1 x e2` and `1 / |c|^2`).
#[derive(Clone, Copy)]
struct LaneQuad {
    p0: [f32; 3],
    e1: [f32; 3],
    e2: [f32; 3],
    c: [f32; 3],
    inv: f32,
}

/// Eight rays, an array per coordinate, and their closest hits so far.
struct RayLanes {
    o: [[f32; LANES]; 3],
    d: [[f32; LANES]; 3],
    t: [f32; LANES],
    quad: [u32; LANES],
}

impl RayLanes {
    fn new(rays: &[Ray]) -> Self {
        let mut r =
            RayLanes { o: [[0.0; LANES]; 3], d: [[0.0; LANES]; 3], t: [f32::INFINITY; LANES], quad: [u32::MAX; LANES] };
        for (l, ray) in rays.iter().enumerate() {
            for a in 0..3 {
                r.o[a][l] = ray.o[a];
                r.d[a][l] = ray.d[a];
            }
        }
        r
    }
}

/// `intersect_quad` for every quad on every lane, written branch-free so the lanes vectorise.
#[inline(always)]
fn closest_in_lanes(quads: &[LaneQuad], r: &mut RayLanes) {
    for (qi, q) in quads.iter().enumerate() {
        let [c0, c1, c2] = q.c;
        let [p0x, p0y, p0z] = q.p0;
        let [e1x, e1y, e1z] = q.e1;
        let [e2x, e2y, e2z] = q.e2;
        for l in 0..LANES {
            let (o, d) = ([r.o[0][l], r.o[1][l], r.o[2][l]], [r.d[0][l], r.d[1][l], r.d[2][l]]);
            let denom = c0 * d[0] + c1 * d[1] + c2 * d[2];
            let t = (c0 * (p0x - o[0]) + c1 * (p0y - o[1]) + c2 * (p0z - o[2])) / denom;
            let qx = (o[0] + d[0] * t) - p0x;
            let qy = (o[1] + d[1] * t) - p0y;
            let qz = (o[2] + d[2] * t) - p0z;
            let u = (c0 * (qy * e2z - e2y * qz) + c1 * (qz * e2x - e2z * qx) + c2 * (qx * e2y - e2x * qy)) * q.inv;
            let v = (c0 * (e1y * qz - qy * e1z) + c1 * (e1z * qx - qz * e1x) + c2 * (e1x * qy - qx * e1y)) * q.inv;
            let hit = (denom != 0.0) & (t > 0.0) & (t < r.t[l]) & (0.0..=1.0).contains(&u) & (0.0..=1.0).contains(&v);
            r.t[l] = if hit { t } else { r.t[l] };
            r.quad[l] = if hit { qi as u32 } else { r.quad[l] };
        }
    }
}

fn lanes_baseline(quads: &[LaneQuad], r: &mut RayLanes) {
    closest_in_lanes(quads, r)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn lanes_avx2(quads: &[LaneQuad], r: &mut RayLanes) {
    closest_in_lanes(quads, r)
}

/// Closest hits of all `rays` (a multiple of eight) through `kernel`, into `t` and `quad`.
fn trace_lanes(
    quads: &[LaneQuad],
    rays: &[Ray],
    kernel: impl Fn(&[LaneQuad], &mut RayLanes),
    t: &mut [f32],
    quad: &mut [u32],
) {
    for ((chunk, t), quad) in rays.chunks_exact(LANES).zip(t.chunks_exact_mut(LANES)).zip(quad.chunks_exact_mut(LANES))
    {
        let mut r = RayLanes::new(chunk);
        kernel(quads, &mut r);
        t.copy_from_slice(&r.t);
        quad.copy_from_slice(&r.quad);
        // What a hit needs besides its distance, (u, v), from the winning quad's own test (the
        // lanes keep only the distance and the quad: keeping u and v too made them slower).
        for (ray, &i) in chunk.iter().zip(&r.quad) {
            if let Some(q) = quads.get(i as usize) {
                black_box(intersect_quad(q.p0.into(), q.e1.into(), q.e2.into(), ray, f32::INFINITY));
            }
        }
    }
}

fn main() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/mitsuba/cornell-box.xml");
    let desc = caustic::scene::load_scene(&path, &Default::default()).expect("the bundled Cornell box loads");
    let scene = desc.build().expect("the bundled Cornell box builds").scene;
    let bvh = &scene.bvh;
    let quads: Vec<LaneQuad> = (0..bvh.len())
        .map(|i| match bvh.prims().get(i, &scene.meshes).shape {
            Shape::Quad(q) => {
                let c = q.e1.cross(q.e2);
                LaneQuad {
                    p0: q.p0.into(),
                    e1: q.e1.into(),
                    e2: q.e2.into(),
                    c: c.into(),
                    inv: 1.0 / c.length_squared(),
                }
            }
            _ => panic!("the Cornell box is made of quads"),
        })
        .collect();
    // Bounce-like rays: from where random rays meet the surfaces, into random directions on
    // the side the ray came from.
    let seeds = caustic::bench::incoherent_rays(bvh.bounds(), 1 << 20);
    let mut rays: Vec<Ray> = seeds
        .iter()
        .enumerate()
        .filter_map(|(k, r)| {
            let h = scene.intersect(r, f32::INFINITY)?;
            let n = if h.ng.dot(r.d) < 0.0 { h.ng } else { -h.ng };
            let d = seeds[(k * 7 + 3) % seeds.len()].d;
            Some(h.origin().spawn(if d.dot(n) < 0.0 { -d } else { d }, 1e-4))
        })
        .collect();
    rays.truncate(rays.len() / LANES * LANES);
    let avx2 = cfg!(target_arch = "x86_64") && std::arch::is_x86_feature_detected!("avx2");
    println!("{} quads, {} rays; AVX2 {}", quads.len(), rays.len(), if avx2 { "present" } else { "absent" });

    let (mut t, mut quad) = (vec![0.0f32; rays.len()], vec![0u32; rays.len()]);
    trace_lanes(&quads, &rays, lanes_baseline, &mut t, &mut quad);
    let mut near_ties = 0;
    for (k, ray) in rays.iter().enumerate() {
        let (i, ht) = bvh.intersect_tree(ray, f32::INFINITY).map_or((u32::MAX, f32::INFINITY), |(i, h)| (i, h.t));
        if (i, ht.to_bits()) != (quad[k], t[k].to_bits()) {
            assert!(
                (ht - t[k]).abs() <= 1e-6 * ht.max(1.0),
                "ray {k}: lanes found quad {} at {}, the scan {i} at {ht}",
                quad[k],
                t[k]
            );
            near_ties += 1;
        }
    }
    println!("closest hits agree but for {near_ties} near-ties where two quads meet");

    let best_of = |f: &mut dyn FnMut()| {
        (0..5)
            .map(|_| {
                let t0 = Instant::now();
                f();
                t0.elapsed().as_secs_f64() / rays.len() as f64 * 1e9
            })
            .fold(f64::INFINITY, f64::min)
    };
    let one = best_of(&mut || {
        for r in &rays {
            black_box(bvh.intersect_tree(black_box(r), f32::INFINITY));
        }
    });
    let base = best_of(&mut || trace_lanes(&quads, black_box(&rays), lanes_baseline, &mut t, &mut quad));
    println!("one ray at a time (flat scan):         {one:6.1} ns/ray");
    println!("eight rays at a time, build's target:  {base:6.1} ns/ray");
    #[cfg(target_arch = "x86_64")]
    if avx2 {
        // SAFETY: the processor has AVX2 (checked above).
        let kernel = |q: &[LaneQuad], r: &mut RayLanes| unsafe { lanes_avx2(q, r) };
        let wide = best_of(&mut || trace_lanes(&quads, black_box(&rays), kernel, &mut t, &mut quad));
        println!("eight rays at a time, AVX2:            {wide:6.1} ns/ray");
        let rows = QuadRows::new(&quads);
        let mut found = vec![0u32; rays.len()];
        // SAFETY: the processor has AVX2.
        unsafe { rows_avx2(&rows, &rays, &mut found) };
        let differ = rays
            .iter()
            .zip(&found)
            .filter(|(r, f)| bvh.intersect_tree(r, f32::INFINITY).map_or(u32::MAX, |h| h.0) != **f)
            .count();
        assert!(differ == near_ties, "eight quads at a time: {differ} closest hits differ from the scan's");
        // SAFETY: as above.
        let across = best_of(&mut || unsafe { rows_avx2(&rows, black_box(&rays), &mut found) });
        println!("one ray, eight quads at a time, AVX2:  {across:6.1} ns/ray");
    }
}

/// Quads eight to a row, a row of eight values per coordinate; unused lanes hold zeros (no
/// normal, so no ray hits them).
struct QuadRows {
    rows: Vec<[[f32; LANES]; 13]>,
}

impl QuadRows {
    fn new(quads: &[LaneQuad]) -> Self {
        let rows = quads
            .chunks(LANES)
            .map(|chunk| {
                let mut row = [[0.0f32; LANES]; 13];
                for (l, q) in chunk.iter().enumerate() {
                    let vals = [q.p0, q.e1, q.e2, q.c].concat();
                    for (k, v) in vals.iter().enumerate() {
                        row[k][l] = *v;
                    }
                    row[12][l] = q.inv;
                }
                row
            })
            .collect();
        QuadRows { rows }
    }
}

/// `ray`'s closest quad and its distance, eight quads at a time.
#[inline(always)]
fn closest_of_row(rows: &QuadRows, ray: &Ray) -> (u32, f32) {
    let (o, d) = (ray.o, ray.d);
    let mut best_t = [f32::INFINITY; LANES];
    let mut best_i = [u32::MAX; LANES];
    for (ri, row) in rows.rows.iter().enumerate() {
        for l in 0..LANES {
            let (p0x, p0y, p0z) = (row[0][l], row[1][l], row[2][l]);
            let (e1x, e1y, e1z) = (row[3][l], row[4][l], row[5][l]);
            let (e2x, e2y, e2z) = (row[6][l], row[7][l], row[8][l]);
            let (c0, c1, c2, inv) = (row[9][l], row[10][l], row[11][l], row[12][l]);
            let denom = c0 * d.x + c1 * d.y + c2 * d.z;
            let t = (c0 * (p0x - o.x) + c1 * (p0y - o.y) + c2 * (p0z - o.z)) / denom;
            let qx = (o.x + d.x * t) - p0x;
            let qy = (o.y + d.y * t) - p0y;
            let qz = (o.z + d.z * t) - p0z;
            let u = (c0 * (qy * e2z - e2y * qz) + c1 * (qz * e2x - e2z * qx) + c2 * (qx * e2y - e2x * qy)) * inv;
            let v = (c0 * (e1y * qz - qy * e1z) + c1 * (e1z * qx - qz * e1x) + c2 * (e1x * qy - qx * e1y)) * inv;
            let hit =
                (denom != 0.0) & (t > 0.0) & (t < best_t[l]) & (0.0..=1.0).contains(&u) & (0.0..=1.0).contains(&v);
            best_t[l] = if hit { t } else { best_t[l] };
            best_i[l] = if hit { (ri * LANES + l) as u32 } else { best_i[l] };
        }
    }
    // Branch-free: the least distance, then the least quad at it.
    let t = best_t.iter().fold(f32::INFINITY, |m, &t| m.min(t));
    let i = (0..LANES).map(|l| if best_t[l] == t { best_i[l] } else { u32::MAX }).fold(u32::MAX, u32::min);
    (i, t)
}

/// The closest quad of every ray in `rays`, into `out`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn rows_avx2(rows: &QuadRows, rays: &[Ray], out: &mut [u32]) {
    for (r, o) in rays.iter().zip(out) {
        *o = closest_of_row(rows, r).0;
    }
}
