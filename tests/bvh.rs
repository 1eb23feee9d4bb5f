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
    let bvh = Bvh::build(prims.clone());
    assert_eq!(bvh.prims.len(), prims.len());
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
        let got = bvh.intersect(&ray, f32::INFINITY).map(|(i, h)| (h.t, bvh.prims[i as usize].material));
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

#[test]
fn degenerate_inputs_build() {
    // Empty, one primitive, and many primitives with the same centroid.
    assert!(Bvh::build(vec![]).intersect(&Ray::new(Vec3::ZERO, Vec3::X), f32::INFINITY).is_none());
    let s = Primitive {
        shape: Shape::Sphere(Sphere::new(Vec3::new(3.0, 0.0, 0.0), 1.0)),
        material: 0,
        light: caustic::geometry::NO_LIGHT,
    };
    let one = Bvh::build(vec![s]);
    assert!((one.intersect(&Ray::new(Vec3::ZERO, Vec3::X), f32::INFINITY).unwrap().1.t - 2.0).abs() < 1e-6);
    let same: Vec<Primitive> = (0..1000)
        .map(|i| Primitive {
            shape: Shape::Sphere(Sphere::new(Vec3::new(3.0, 0.0, 0.0), 1.0 + i as f32 * 1e-3)),
            material: i,
            light: caustic::geometry::NO_LIGHT,
        })
        .collect();
    let bvh = Bvh::build(same);
    let (i, h) = bvh.intersect(&Ray::new(Vec3::ZERO, Vec3::X), f32::INFINITY).unwrap();
    assert_eq!(bvh.prims[i as usize].material, 999);
    assert!((h.t - (3.0 - 1.999)).abs() < 1e-5);
}
