use super::*;

/// splitmix64, enough randomness for test point sets.
struct TestRng(u64);

impl TestRng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    fn uniform(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    fn vec3(&mut self) -> Vec3 {
        Vec3::new(self.uniform(), self.uniform(), self.uniform())
    }
}

fn photons_at(points: &[Vec3]) -> Vec<Photon> {
    points.iter().map(|&p| Photon::new(p, Vec3::Z, Color::ONE, 0)).collect()
}

/// Sorted squared distances of the k nearest within max_r2, by brute force.
fn brute_force(points: &[Vec3], q: Vec3, k: usize, max_r2: f32) -> Vec<f32> {
    let mut d: Vec<f32> = points.iter().map(|p| p.distance_squared(q)).filter(|&d2| d2 <= max_r2).collect();
    d.sort_by(f32::total_cmp);
    d.truncate(k);
    d
}

/// Checks gathers against brute force for the given queries: same sorted distances (so ties
/// may pick different photons), indices that point at photons at those distances, and the
/// returned radius equal to the largest distance; with the default leaf size and with small
/// leaves, which make deep trees from few photons.
fn check_against_brute_force(points: &[Vec3], queries: &[Vec3], k: usize, max_r2: f32) {
    for leaf_size in [LEAF_SIZE, 2, 5] {
        let map = PhotonMap::build_with_leaf_size(photons_at(points), leaf_size, &Default::default()).unwrap();
        check_map_against_brute_force(&map, points, queries, k, max_r2);
    }
}

fn check_map_against_brute_force(map: &PhotonMap, points: &[Vec3], queries: &[Vec3], k: usize, max_r2: f32) {
    assert_eq!(map.len(), points.len());
    let mut out = Gathered::new(k);
    for &q in queries {
        let (found, radius2) = map.gather(q, k, max_r2, &mut out);
        let mut got: Vec<f32> = found.iter().map(|e| e.0).collect();
        for &(d2, i) in found {
            assert_eq!(map.photon(i).position().distance_squared(q), d2);
        }
        let mut indices: Vec<u32> = found.iter().map(|e| e.1).collect();
        indices.sort_unstable();
        indices.dedup();
        assert_eq!(indices.len(), found.len(), "a photon was returned twice");
        got.sort_by(f32::total_cmp);
        let want = brute_force(points, q, k, max_r2);
        assert_eq!(got, want, "query {q} k {k} max_r2 {max_r2}");
        assert_eq!(radius2, want.last().copied().unwrap_or(0.0));
        assert_eq!(out.radius2(), radius2);
    }
}

#[test]
fn knn_matches_brute_force_on_random_points() {
    let mut rng = TestRng(1);
    for n in [1, 2, 7, 8, 9, 17, 100, 1000, 5000] {
        let points: Vec<Vec3> = (0..n).map(|_| rng.vec3()).collect();
        let queries: Vec<Vec3> = (0..50).map(|_| rng.vec3() * 1.2 - 0.1).collect();
        for (k, max_r2) in [(1, f32::INFINITY), (10, 0.01), (50, 0.02), (50, f32::INFINITY), (200, 0.05)] {
            check_against_brute_force(&points, &queries, k, max_r2);
        }
    }
}

#[test]
fn knn_on_a_flat_wall() {
    // Every photon has y = 0 exactly, like photons stored on a Cornell-box wall.
    let mut rng = TestRng(2);
    let points: Vec<Vec3> = (0..20_000).map(|_| Vec3::new(rng.uniform(), 0.0, rng.uniform())).collect();
    let queries: Vec<Vec3> =
        (0..200).map(|i| Vec3::new(rng.uniform(), if i % 2 == 0 { 0.0 } else { 0.01 }, rng.uniform())).collect();
    check_against_brute_force(&points, &queries, 50, 0.001);
    check_against_brute_force(&points, &queries, 20, f32::INFINITY);
}

#[test]
fn knn_with_many_exact_duplicates() {
    let mut rng = TestRng(3);
    let sites: Vec<Vec3> = (0..40).map(|_| rng.vec3()).collect();
    let mut points: Vec<Vec3> = (0..10_000).map(|i| sites[i % sites.len()]).collect();
    points.extend((0..3000).map(|_| rng.vec3()));
    points.extend(std::iter::repeat_n(Vec3::splat(0.5), 2000));
    let mut queries: Vec<Vec3> = (0..100).map(|_| rng.vec3()).collect();
    queries.extend_from_slice(&sites[..10]);
    queries.push(Vec3::splat(0.5));
    check_against_brute_force(&points, &queries, 50, 0.01);
    check_against_brute_force(&points, &queries, 300, 0.05);
}

#[test]
fn select_nearest_keeps_the_k_smallest() {
    let mut rng = TestRng(8);
    for len in [1usize, 2, 16, 17, 50, 132, 1000] {
        for levels in [1u64, 2, 3, 10, 1 << 20] {
            // Distances from `levels` distinct values: one value makes every entry a tie.
            let cands: Vec<(f32, u32)> = (0..len as u32).map(|i| ((rng.next_u64() % levels) as f32, i)).collect();
            let mut sorted: Vec<f32> = cands.iter().map(|e| e.0).collect();
            sorted.sort_by(f32::total_cmp);
            for k in [1, len / 3 + 1, len / 2 + 1, len - len / 4, len] {
                let (mut buf, mut scratch) = (cands.clone(), vec![(0.0, 0); len]);
                let kth = select_nearest(&mut buf, &mut scratch, k);
                let mut got: Vec<f32> = buf[..k].iter().map(|e| e.0).collect();
                got.sort_by(f32::total_cmp);
                assert_eq!(got, sorted[..k], "len {len} levels {levels} k {k}");
                assert_eq!(kth, sorted[k - 1]);
                let mut ids: Vec<u32> = buf[..k].iter().map(|e| e.1).collect();
                ids.sort_unstable();
                ids.dedup();
                assert_eq!(ids.len(), k, "an entry was duplicated");
            }
        }
    }
}

#[test]
fn max_radius_is_respected() {
    let mut rng = TestRng(4);
    let points: Vec<Vec3> = (0..10_000).map(|_| rng.vec3()).collect();
    let map = PhotonMap::build(photons_at(&points));
    let mut out = Gathered::new(50);
    for _ in 0..100 {
        let q = rng.vec3();
        let (found, radius2) = map.gather(q, 50, 0.0004, &mut out);
        assert!(found.len() < 50, "with ~3.4 photons expected, the radius must be the limit");
        assert!(found.iter().all(|e| e.0 <= 0.0004) && radius2 <= 0.0004);
    }
    // A query far from every photon finds nothing.
    let (found, radius2) = map.gather(Vec3::splat(10.0), 50, 1.0, &mut out);
    assert!(found.is_empty() && radius2 == 0.0);
}

#[test]
fn k_larger_than_the_map_returns_every_photon() {
    let mut rng = TestRng(5);
    let points: Vec<Vec3> = (0..37).map(|_| rng.vec3()).collect();
    let map = PhotonMap::build(photons_at(&points));
    let mut out = Gathered::default();
    let (found, _) = map.gather(Vec3::splat(0.5), 1000, f32::INFINITY, &mut out);
    assert_eq!(found.len(), 37);
    check_against_brute_force(&points, &[Vec3::ZERO, Vec3::ONE], 1000, f32::INFINITY);
}

#[test]
fn empty_map_and_degenerate_queries() {
    let map = PhotonMap::build(Vec::new());
    assert!(map.is_empty());
    assert_eq!(map.len(), 0);
    let mut out = Gathered::new(10);
    assert!(map.gather(Vec3::ZERO, 10, 1.0, &mut out).0.is_empty());

    let map = PhotonMap::build(photons_at(&[Vec3::ZERO; 5]));
    assert!(map.gather(Vec3::ZERO, 0, 1.0, &mut out).0.is_empty());
    assert!(map.gather(Vec3::ZERO, 3, f32::NAN, &mut out).0.is_empty());
    assert!(map.gather(Vec3::NAN, 3, 1.0, &mut out).0.is_empty());
    // A zero radius still finds photons exactly at the query point.
    assert_eq!(map.gather(Vec3::ZERO, 3, 0.0, &mut out).0.len(), 3);
}

#[test]
fn gathers_allocate_nothing_after_the_first() {
    let mut rng = TestRng(6);
    let points: Vec<Vec3> = (0..5000).map(|_| rng.vec3()).collect();
    let map = PhotonMap::build(photons_at(&points));
    let mut out = Gathered::new(50);
    let buffer = out.as_slice().as_ptr();
    for _ in 0..100 {
        map.gather(rng.vec3(), 50, f32::INFINITY, &mut out);
    }
    assert_eq!(out.as_slice().as_ptr(), buffer);
}

#[test]
fn photon_packing_round_trips() {
    let mut rng = TestRng(7);
    let mut worst_angle = 0.0f32;
    for i in 0..200_000 {
        // Directions from all over the sphere, plus the poles and the phi = +-pi seam.
        let dir = match i {
            0 => Vec3::Z,
            1 => -Vec3::Z,
            2 => Vec3::new(-1.0, 0.0, 0.0),
            3 => Vec3::new(-1.0, -1e-9, 0.0),
            _ => loop {
                let v = rng.vec3() * 2.0 - 1.0;
                if v.length_squared() <= 1.0 && v.length_squared() > 1e-6 {
                    break v * (1.0 + 10.0 * rng.uniform());
                }
            },
        };
        // Each channel log-uniform over 1e-6..1e6, independently.
        let power = Color::new(
            10f32.powf(12.0 * rng.uniform() - 6.0),
            10f32.powf(12.0 * rng.uniform() - 6.0),
            10f32.powf(12.0 * rng.uniform() - 6.0),
        );
        let p = (rng.vec3() - 0.5) * 10f32.powf(16.0 * rng.uniform() - 8.0);
        let flags = (i % 256) as u8;
        let photon = Photon::new(p, dir, power, flags);
        assert_eq!(photon.position().to_array().map(f32::to_bits), p.to_array().map(f32::to_bits));
        assert_eq!(photon.flags(), flags);
        let got = photon.power();
        for c in 0..3 {
            let rel = (got[c] - power[c]).abs() / power[c];
            assert!(rel <= 1.0 / 256.0 + 1e-6, "power {power} decoded as {got}");
        }
        let d = photon.direction();
        assert!((d.length() - 1.0).abs() < 1e-6);
        let angle = d.dot(dir.normalize()).clamp(-1.0, 1.0).acos().to_degrees();
        worst_angle = worst_angle.max(angle);
    }
    assert!(worst_angle < 0.55, "worst direction error {worst_angle} degrees");
}

#[test]
fn photon_power_edge_cases() {
    let p = |c: Color| Photon::new(Vec3::ZERO, Vec3::Z, c, 0).power();
    assert_eq!(p(Color::ZERO), Color::ZERO);
    assert_eq!(p(Color::new(-1.0, f32::NAN, 1e-20)), Color::ZERO);
    let big = p(Color::new(f32::INFINITY, 1e30, 1.0));
    assert!(big.r() > 1.6e7 && big.r().is_finite() && big.g() == big.r() && big.b() == 1.0);
    // Powers of two and the small end of the range are exact.
    assert_eq!(p(Color::new(0.5, 2f32.powi(-39), 2f32.powi(23))), Color::new(0.5, 2f32.powi(-39), 2f32.powi(23)));
}

#[test]
fn direction_tables_match_std() {
    for (i, [s, c]) in THETA_TABLE.iter().enumerate() {
        let t = (i as f64 + 0.5) * PI / THETA_BINS as f64;
        assert!((f64::from(*s) - t.sin()).abs() < 1e-7 && (f64::from(*c) - t.cos()).abs() < 1e-7);
    }
    for (i, [c, s]) in PHI_TABLE.iter().enumerate() {
        let t = (i as f64 + 0.5) * 2.0 * PI / PHI_BINS as f64 - PI;
        assert!((f64::from(*s) - t.sin()).abs() < 1e-7 && (f64::from(*c) - t.cos()).abs() < 1e-7);
    }
}

#[test]
fn tree_ranges_cover_every_photon_once() {
    // The implicit layout: leaves partition 0..n, and unless the root is the only leaf they
    // hold leaf_size / 2 ..= leaf_size photons.
    for leaf_size in [LEAF_SIZE, 2, 5] {
        for n in [1usize, 9, 16, 17, 100, 1023, 1025, 99_999] {
            let map = PhotonMap::build_with_leaf_size(photons_at(&vec![Vec3::ZERO; n]), leaf_size, &Default::default())
                .unwrap();
            let d = map.depth;
            let smallest = if d == 0 { 1 } else { leaf_size / 2 };
            let mut next = 0;
            for leaf in 0..1usize << d {
                let (start, end) = (range_end(n, leaf, d), range_end(n, leaf + 1, d));
                assert_eq!(start, next);
                assert!((smallest..=leaf_size).contains(&(end - start)), "n {n} leaf {}", end - start);
                next = end;
            }
            assert_eq!(next, n);
        }
    }
}

mod property {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// Coordinates drawn from a few values make many ties and duplicates.
        #[test]
        fn knn_equals_sort(
            coords in prop::collection::vec((0u8..6, 0u8..6, 0u8..6), 1..400),
            query in (0u8..12, 0u8..12, 0u8..12),
            k in 1usize..60,
            max_r2 in prop_oneof![Just(f32::INFINITY), 0.0f32..30.0],
        ) {
            let points: Vec<Vec3> = coords.iter().map(|&(x, y, z)| Vec3::new(x.into(), y.into(), z.into())).collect();
            let q = Vec3::new(query.0.into(), query.1.into(), query.2.into()) * 0.5;
            check_against_brute_force(&points, &[q], k, max_r2);
        }
    }
}

/// Replacing a photon's power keeps its position, direction and flags bit for bit, and the new
/// power reads back as a photon made with it does.
#[test]
fn with_power_changes_only_the_power() {
    let p = Photon::new(Vec3::new(1.0, -2.0, 3.5), Vec3::new(0.3, -0.8, 0.2), Color::new(1.0, 2.0, 3.0), (5 << 2) | 1);
    let q = p.with_power(Color::new(0.25, 7.0, 0.0));
    assert_eq!((q.position(), q.direction(), q.flags()), (p.position(), p.direction(), p.flags()));
    let fresh = Photon::new(p.position(), Vec3::new(0.3, -0.8, 0.2), Color::new(0.25, 7.0, 0.0), 0);
    assert_eq!(q.power(), fresh.power());
}
