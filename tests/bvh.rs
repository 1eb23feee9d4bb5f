//! The BVH returns exactly the nearest hit that a brute-force loop over all primitives finds.

use caustic::accel::Bvh;
use caustic::geometry::Ray;
use caustic::math::Vec3;
use caustic::sampling::{Rng32, warp::uniform_sphere};
use caustic::shape::{Primitive, Quad, RayShear, Shape, Sphere, Triangle};

fn random_scene(rng: &mut Rng32) -> Vec<Primitive> {
    let mut prims = Vec::new();
    let v = |rng: &mut Rng32| Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 20.0 - 10.0;
    for i in 0..5000 {
        let shape = match i % 10 {
            0..=5 => {
                let c = v(rng);
                let s = 0.2 + rng.uniform();
                let a = c + (v(rng) * 0.1) * s;
                let b = c + (v(rng) * 0.1) * s;
                Shape::Triangle(Triangle::new(c, a, b))
            }
            6..=8 => Shape::Sphere(Sphere::new(v(rng), 0.05 + 0.4 * rng.uniform())),
            _ => match Quad::new(v(rng), v(rng) * 0.05, v(rng) * 0.05) {
                Some(q) => Shape::Quad(q),
                None => continue,
            },
        };
        prims.push(Primitive { shape, material: i, light: caustic::geometry::NO_LIGHT });
    }
    prims
}

#[test]
fn bvh_matches_brute_force_on_10000_rays() {
    let mut rng = Rng32::new(2024);
    let prims = random_scene(&mut rng);
    let bvh = Bvh::build(prims.clone(), &[]);
    assert_eq!(bvh.len(), prims.len());
    let mut hits = 0;
    for _ in 0..10_000 {
        let o = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 30.0 - 15.0;
        let ray = Ray::new(o, uniform_sphere(rng.uniform2()));
        let shear = RayShear::new(&ray);
        let mut best: Option<(f32, u32)> = None;
        for p in &prims {
            if let Some(h) = p.shape.intersect(&ray, &shear, best.map_or(f32::INFINITY, |b| b.0)) {
                best = Some((h.t, p.material));
            }
        }
        let got = bvh.intersect(&ray, f32::INFINITY).map(|(i, h)| (h.t, bvh.material_light(i).0));
        assert_eq!(got, best, "ray {ray:?}");
        assert_eq!(bvh.occluded(&ray, f32::INFINITY), best.is_some());
        if let Some((t, _)) = best {
            // Shadow rays stop just short of the hit, and see it just beyond.
            assert!(!bvh.occluded(&ray, t * 0.999));
            assert!(bvh.occluded(&ray, t * 1.001));
            hits += 1;
        }
    }
    assert!(hits > 1000, "too few hits ({hits}) to mean anything");
}

/// Scenes of a few to a few dozen primitives, which skip the tree (all of them in packets up to
/// eight, every box tested in turn up to 32; `Bvh`): the same closest hit, occlusion and set of
/// primitives crossed as brute force, on either side of each size limit.
#[test]
fn small_scenes_match_brute_force() {
    let mut rng = Rng32::new(77);
    for n in [1, 3, 8, 9, 17, 18, 31, 32, 33, 40] {
        // Larger primitives in a smaller box than `random_scene`'s, so rays cross several.
        let prims: Vec<Primitive> = (0..n)
            .map(|i| {
                let v = |rng: &mut Rng32| Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 4.0 - 2.0;
                let shape = match i % 3 {
                    0 => Shape::Quad(Quad::new(v(&mut rng), v(&mut rng), v(&mut rng)).expect("random edges")),
                    1 => Shape::Sphere(Sphere::new(v(&mut rng), 0.1 + 0.4 * rng.uniform())),
                    _ => Shape::Triangle(Triangle::new(v(&mut rng), v(&mut rng), v(&mut rng))),
                };
                Primitive { shape, material: i, light: caustic::geometry::NO_LIGHT }
            })
            .collect();
        let bvh = Bvh::build(prims.clone(), &[]);
        let mut hits = 0;
        for _ in 0..3000 {
            // From anywhere around the primitives towards a point among them.
            let o = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 6.0 - 3.0;
            let towards = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 2.0 - 1.0;
            let ray = Ray::new(o, (towards - o).normalize());
            let shear = RayShear::new(&ray);
            let mut best: Option<(f32, u32)> = None;
            let mut crossed = Vec::new();
            for p in &prims {
                if let Some(h) = p.shape.intersect(&ray, &shear, best.map_or(f32::INFINITY, |b| b.0)) {
                    best = Some((h.t, p.material));
                }
                if p.shape.intersect(&ray, &shear, f32::INFINITY).is_some() {
                    crossed.push(p.material);
                }
            }
            let got = bvh.intersect(&ray, f32::INFINITY).map(|(i, h)| (h.t, bvh.material_light(i).0));
            assert_eq!(got, best, "{n} primitives, ray {ray:?}");
            assert_eq!(bvh.occluded(&ray, f32::INFINITY), best.is_some(), "{n} primitives");
            // A finite end, which prunes boxes entered beyond it (the flat scan's second pass).
            let t_max = 6.0 * rng.uniform();
            let mut within: Option<(f32, u32)> = None;
            for p in &prims {
                if let Some(h) = p.shape.intersect(&ray, &shear, within.map_or(t_max, |b| b.0)) {
                    within = Some((h.t, p.material));
                }
            }
            let got = bvh.intersect(&ray, t_max).map(|(i, h)| (h.t, bvh.material_light(i).0));
            assert_eq!(got, within, "{n} primitives, t_max {t_max}, ray {ray:?}");
            assert_eq!(bvh.occluded(&ray, t_max), within.is_some(), "{n} primitives, t_max {t_max}");
            let mut seen = Vec::new();
            let all = bvh.for_each_crossing(&ray, f32::INFINITY, |i, _| {
                seen.push(bvh.material_light(i).0);
                true
            });
            assert_eq!(all, Some(true));
            seen.sort_unstable();
            seen.dedup();
            crossed.sort_unstable();
            assert_eq!(seen, crossed, "{n} primitives, ray {ray:?}");
            if let Some((t, _)) = best {
                assert!(!bvh.occluded(&ray, t * 0.999));
                assert!(bvh.occluded(&ray, t * 1.001));
                hits += 1;
            }
        }
        assert!(hits > 100 * n.min(10), "{n} primitives: too few hits ({hits}) to mean anything");
    }
}

#[test]
fn degenerate_inputs_build() {
    // Empty, one primitive, and many primitives with the same centroid.
    assert!(Bvh::build(vec![], &[]).intersect(&Ray::new(Vec3::ZERO, Vec3::X), f32::INFINITY).is_none());
    let s = Primitive {
        shape: Shape::Sphere(Sphere::new(Vec3::new(3.0, 0.0, 0.0), 1.0)),
        material: 0,
        light: caustic::geometry::NO_LIGHT,
    };
    let one = Bvh::build(vec![s], &[]);
    assert!((one.intersect(&Ray::new(Vec3::ZERO, Vec3::X), f32::INFINITY).unwrap().1.t - 2.0).abs() < 1e-6);
    let same: Vec<Primitive> = (0..1000)
        .map(|i| Primitive {
            shape: Shape::Sphere(Sphere::new(Vec3::new(3.0, 0.0, 0.0), 1.0 + i as f32 * 1e-3)),
            material: i,
            light: caustic::geometry::NO_LIGHT,
        })
        .collect();
    let bvh = Bvh::build(same, &[]);
    let (i, h) = bvh.intersect(&Ray::new(Vec3::ZERO, Vec3::X), f32::INFINITY).unwrap();
    assert_eq!(bvh.material_light(i).0, 999);
    assert!((h.t - (3.0 - 1.999)).abs() < 1e-5);
}

/// A mesh large enough for every parallel path of the build (parallel and sampled binning,
/// subtrees as tasks): same closest distance and occlusion as brute force.
#[test]
fn large_mesh_matches_brute_force() {
    let prims = caustic::bench::knot_primitives(2400);
    assert!(prims.len() > 150_000);
    let bvh = Bvh::build(prims.clone(), &[]);
    let b = bvh.bounds();
    let rays = caustic::bench::incoherent_rays(b, 300);
    let mut hits = 0;
    for ray in &rays {
        let shear = RayShear::new(ray);
        let mut best = f32::INFINITY;
        for p in &prims {
            if let Some(h) = p.shape.intersect(ray, &shear, best) {
                best = h.t;
            }
        }
        let got = bvh.intersect(ray, f32::INFINITY);
        assert_eq!(got.map_or(f32::INFINITY, |(_, h)| h.t), best, "ray {ray:?}");
        if let Some((i, h)) = got {
            // The index names the primitive that was hit.
            assert_eq!(
                bvh.prims().get(i as usize, &[]).shape.intersect(ray, &shear, f32::INFINITY).map(|g| g.t),
                Some(h.t)
            );
            hits += 1;
        }
        assert_eq!(bvh.occluded(ray, f32::INFINITY), best.is_finite());
    }
    assert!(hits > 100, "{hits}");
}

/// Rays along the axes, with +0 and -0 direction components, starting on the planes of
/// boxes that share faces: every box test must keep the hits brute force finds.
#[test]
fn axis_aligned_rays_on_shared_faces() {
    let mut prims = Vec::new();
    for i in 0..64u32 {
        let c = Vec3::new((i % 4) as f32, ((i / 4) % 4) as f32, (i / 16) as f32);
        // Two triangles on each of the cube's three low faces: the faces of neighbours touch.
        for (a, b) in [(Vec3::X, Vec3::Y), (Vec3::Y, Vec3::Z), (Vec3::Z, Vec3::X)] {
            for t in [Triangle::new(c, c + a, c + a + b), Triangle::new(c, c + a + b, c + b)] {
                prims.push(Primitive { shape: Shape::Triangle(t), material: i, light: caustic::geometry::NO_LIGHT });
            }
        }
    }
    let bvh = Bvh::build(prims.clone(), &[]);
    let mut hits = 0;
    for k in 0..2000u32 {
        let axis = (k % 3) as usize;
        let sign = if k % 6 < 3 { 1.0 } else { -1.0 };
        let zero = if k % 12 < 6 { 0.0 } else { -0.0 };
        let mut d = Vec3::splat(zero);
        d[axis] = sign;
        // Origins on grid planes (the faces), at half steps, and just off them.
        let coord = |j: u32| [0.0, 0.5, 1.0, 1.0 + 1e-7, 2.0 - 1e-7, 3.0, 4.0][(j % 7) as usize] + (j / 7 % 2) as f32;
        let mut o = Vec3::new(coord(k / 3), coord(k / 21 + 1), coord(k / 147 + 2));
        o[axis] = if sign > 0.0 { -1.0 } else { 5.0 };
        let ray = Ray::new(o, d);
        let shear = RayShear::new(&ray);
        let mut best = f32::INFINITY;
        for p in &prims {
            if let Some(h) = p.shape.intersect(&ray, &shear, best) {
                best = h.t;
            }
        }
        let got = bvh.intersect(&ray, f32::INFINITY).map_or(f32::INFINITY, |(_, h)| h.t);
        assert_eq!(got, best, "ray {ray:?}");
        assert_eq!(bvh.occluded(&ray, f32::INFINITY), best.is_finite(), "ray {ray:?}");
        hits += best.is_finite() as u32;
    }
    assert!(hits > 200, "{hits}");
}

/// A primitive with NaN coordinates is never hit and does not spoil the boxes of the others.
#[test]
fn nan_primitive_does_not_hide_the_others() {
    let mut prims: Vec<Primitive> = (0..200)
        .map(|i| Primitive {
            shape: Shape::Sphere(Sphere::new(Vec3::new(i as f32 * 3.0, 0.0, 0.0), 1.0)),
            material: i,
            light: caustic::geometry::NO_LIGHT,
        })
        .collect();
    let nan = Vec3::new(f32::NAN, 0.0, 0.0);
    prims.insert(
        77,
        Primitive {
            shape: Shape::Triangle(Triangle::new(nan, Vec3::Y, Vec3::Z)),
            material: 999,
            light: caustic::geometry::NO_LIGHT,
        },
    );
    let bvh = Bvh::build(prims, &[]);
    assert!(bvh.bounds().min.is_finite() && bvh.bounds().max.is_finite());
    for i in 0..200 {
        let ray = Ray::new(Vec3::new(i as f32 * 3.0, 0.0, 5.0), -Vec3::Z);
        let (k, h) = bvh.intersect(&ray, f32::INFINITY).expect("every sphere is hit");
        assert_eq!(bvh.material_light(k).0, i);
        assert!((h.t - 4.0).abs() < 1e-4);
    }
}
