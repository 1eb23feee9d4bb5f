//! `cargo bench --bench photon_map`: the photon map (Jensen 2001) on 1M photons uniform in the
//! unit cube: build time, and k = 50 gathers within r = 0.025 (~65 photons inside) for 1M
//! queries sorted by a 64^3 cell key, the order of a tile-by-tile final gather, on two threads in
//! chunks with one `Gathered` buffer each. The `items/s` column is gathers per second.

use caustic::math::{Color, Vec3};
use caustic::photon::{Gathered, Photon, PhotonMap};
use rayon::prelude::*;
use std::sync::LazyLock;

const N_PHOTONS: usize = 1_000_000;
const N_QUERIES: usize = 1_000_000;
const K: usize = 50;
/// 1M photons per unit volume put 4/3 pi 0.025^3 1e6 = 65 photons inside this radius.
const RADIUS: f32 = 0.025;
const CHUNK: usize = 1024;

fn main() {
    divan::main();
}

/// splitmix64 of a counter: deterministic points without a dependency.
fn uniform(i: u64) -> f32 {
    let mut z = i.wrapping_mul(0x9e37_79b9_7f4a_7c15).wrapping_add(0x632b_e59b_d9b4_e019);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
}

fn point(i: u64, seed: u64) -> Vec3 {
    let base = (seed << 40) + 3 * i;
    Vec3::new(uniform(base), uniform(base + 1), uniform(base + 2))
}

static PHOTONS: LazyLock<Vec<Photon>> = LazyLock::new(|| {
    (0..N_PHOTONS as u64).map(|i| Photon::new(point(i, 1), -Vec3::Y, Color::splat(1e-6), 0)).collect()
});

static MAP: LazyLock<PhotonMap> = LazyLock::new(|| PhotonMap::build(PHOTONS.clone()));

/// Random queries sorted by their cell in a 64^3 grid.
static QUERIES: LazyLock<Vec<Vec3>> = LazyLock::new(|| {
    let mut queries: Vec<Vec3> = (0..N_QUERIES as u64).map(|i| point(i, 2)).collect();
    let key = |p: &Vec3| {
        let c = (*p * 64.0).as_uvec3().min(glam::UVec3::splat(63));
        (c.z * 64 + c.y) * 64 + c.x
    };
    queries.sort_by_key(key);
    queries
});

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool")
}

/// All queries, chunked over the pool's threads; returns the number of photons found.
fn gather_all(map: &PhotonMap, queries: &[Vec3], max_r2: f32) -> usize {
    queries
        .par_chunks(CHUNK)
        .map(|chunk| {
            let mut out = Gathered::new(K);
            chunk.iter().map(|&q| map.gather(q, K, max_r2, &mut out).0.len()).sum::<usize>()
        })
        .sum()
}

#[divan::bench(sample_count = 5)]
fn build_1m(bencher: divan::Bencher) {
    let pool = pool(2);
    bencher
        .counter(divan::counter::ItemsCount::new(N_PHOTONS))
        .with_inputs(|| PHOTONS.clone())
        .bench_values(|photons| pool.install(|| PhotonMap::build(photons)));
}

#[divan::bench(args = [1, 2], sample_count = 5)]
fn gather_k50_tile_order(bencher: divan::Bencher, threads: usize) {
    let (map, queries, pool) = (&*MAP, &*QUERIES, pool(threads));
    let found = pool.install(|| gather_all(map, queries, RADIUS * RADIUS));
    eprintln!("[photon_map] {threads} thread(s): mean photons per gather {:.2}", found as f64 / N_QUERIES as f64);
    bencher
        .counter(divan::counter::ItemsCount::new(N_QUERIES))
        .bench(|| pool.install(|| gather_all(map, divan::black_box(queries), RADIUS * RADIUS)));
}

/// Unlimited radius: the k limit alone bounds the search, as with a generous maximum radius.
#[divan::bench(sample_count = 5)]
fn gather_k50_unbounded_tile_order(bencher: divan::Bencher) {
    let (map, queries, pool) = (&*MAP, &*QUERIES, pool(2));
    bencher
        .counter(divan::counter::ItemsCount::new(N_QUERIES))
        .bench(|| pool.install(|| gather_all(map, divan::black_box(queries), f32::INFINITY)));
}
