//! Camera tests: the pinhole and thin lens against their geometry, the orthographic camera against
//! Mitsuba's numbers, and the principal-point offset.

use super::*;
use crate::sampling::Rng32;

fn cam(lens_radius: f32, f: f32) -> Camera {
    Camera::new(
        Vec3::new(0.0, 1.0, 5.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::Y,
        ViewPlane::Fov(40.0),
        320,
        240,
        lens_radius,
        f,
    )
}

#[test]
fn centre_ray_looks_at_target_and_fov_matches() {
    let c = cam(0.0, 1.0);
    let r = c.generate_ray(Vec2::new(160.0, 120.0), Vec2::splat(0.5));
    assert!(r.d.abs_diff_eq(-Vec3::Z, 1e-6));
    let top = c.generate_ray(Vec2::new(160.0, 0.0), Vec2::ZERO);
    let half = top.d.dot(-Vec3::Z).acos().to_degrees();
    assert!((half - 20.0).abs() < 1e-3, "{half}");
    // Raster y grows downwards, world up is +y.
    assert!(top.d.y > 0.0);
}

#[test]
fn zero_lens_radius_is_exactly_pinhole() {
    let a = cam(0.0, 3.0);
    let mut b = cam(0.0, 7.0);
    b.lens_radius = 0.0;
    let mut rng = Rng32::new(3);
    for _ in 0..1000 {
        let p = rng.uniform2() * Vec2::new(320.0, 240.0);
        assert_eq!(a.generate_ray(p, rng.uniform2()), b.generate_ray(p, Vec2::splat(0.5)));
    }
}

#[test]
fn every_lens_sample_meets_at_the_focal_plane_point() {
    let f = 4.0;
    let c = cam(0.3, f);
    let mut rng = Rng32::new(8);
    for _ in 0..100 {
        let raster = rng.uniform2() * Vec2::new(320.0, 240.0);
        let ps = c.view_plane_point(raster);
        let target = c.eye + (ps.x * c.u + ps.y * c.v) * (f / c.d) - f * c.w;
        for _ in 0..16 {
            let r = c.generate_ray(raster, rng.uniform2());
            // Intersect the ray with the focal plane (distance f along -w from the lens).
            let t = f / r.d.dot(-c.w);
            let hit = r.o + r.d * t;
            assert!((hit - target).length() <= 1e-5 * target.length(), "{hit} vs {target}");
        }
    }
}

#[test]
fn circle_of_confusion_matches_thin_lens() {
    // A point q on the axis at depth z is seen through lens point l at the focal-plane point
    // p = l + (q - l) f / z. Find, for each lens sample, the raster position whose camera ray
    // from l passes through q, check that it does, and measure how far the images p spread:
    // the thin-lens circle of confusion on the focal plane has radius r_lens |z - f| / z.
    let f = 5.0;
    let r_lens = 0.25;
    let c = cam(r_lens, f);
    for z in [2.0f32, 3.5, 8.0, 20.0] {
        let q = c.eye - z * c.w;
        let mut max_r = 0.0f32;
        let mut rng = Rng32::new(2);
        for _ in 0..4000 {
            let u = rng.uniform2();
            let l = concentric_disk(u) * r_lens;
            let p = l + (Vec2::ZERO - l) * (f / z);
            let ps = p * (c.d / f);
            let raster =
                Vec2::new(ps.x / c.pixel_size + 0.5 * c.width as f32, 0.5 * c.height as f32 - ps.y / c.pixel_size);
            let ray = c.generate_ray(raster, u);
            let to_q = q - ray.o;
            let miss = (to_q - ray.d * to_q.dot(ray.d)).length();
            assert!(miss < 1e-4 * z, "camera ray misses the point by {miss}");
            max_r = max_r.max(p.length());
        }
        let expected = r_lens * (z - f).abs() / z;
        assert!((max_r - expected).abs() <= 0.02 * expected, "z={z}: {max_r} vs {expected}");
    }
}

/// Mitsuba's sensor for a `to_world` of `frame` (columns x, y, z and the origin).
fn mitsuba_ortho(x: Vec3, y: Vec3, z: Vec3, origin: Vec3, width: u32, height: u32) -> Camera {
    CameraDesc {
        placement: Placement::Frame { origin, x, y, z },
        fov: FieldOfView::Orthographic { size: 2.0, axis: FovAxis::X },
        lens_radius: 0.0,
        focal_distance: 1.0,
        principal_point: Vec2::ZERO,
    }
    .build(width, height)
}

#[test]
fn orthographic_rays_are_parallel_and_start_on_the_view_plane() {
    let c = CameraDesc {
        placement: Placement::LookAt { eye: Vec3::new(1.0, 2.0, 3.0), target: Vec3::new(4.0, 2.0, -1.0), up: Vec3::Y },
        fov: FieldOfView::Orthographic { size: 6.0, axis: FovAxis::X },
        lens_radius: 0.0,
        focal_distance: 1.0,
        principal_point: Vec2::ZERO,
    }
    .build(120, 80);
    let dir = (Vec3::new(4.0, 2.0, -1.0) - Vec3::new(1.0, 2.0, 3.0)).normalize();
    let mut rng = Rng32::new(4);
    for _ in 0..1000 {
        let raster = rng.uniform2() * Vec2::new(120.0, 80.0);
        let r = c.generate_ray(raster, rng.uniform2());
        assert!(r.d.abs_diff_eq(dir, 1e-6), "{}", r.d);
        // The origin lies in the plane through the eye facing the view direction.
        assert!((r.o - c.eye).dot(dir).abs() < 1e-5);
    }
    // The film spans 6 units across and 6 x 80 / 120 = 4 units up, in square pixels.
    let corner = |x: f32, y: f32| c.generate_ray(Vec2::new(x, y), Vec2::ZERO).o;
    assert!(((corner(120.0, 0.0) - corner(0.0, 0.0)).length() - 6.0).abs() < 1e-5);
    assert!(((corner(0.0, 80.0) - corner(0.0, 0.0)).length() - 4.0).abs() < 1e-5);
    let centre = corner(60.0, 40.0);
    assert!(centre.abs_diff_eq(c.eye, 1e-5), "{centre}");
    // Image right is the look direction crossed with up; image up is +y.
    assert!((corner(120.0, 40.0) - centre).normalize().abs_diff_eq(dir.cross(Vec3::Y).normalize(), 1e-5));
    assert!((corner(60.0, 0.0) - centre).normalize().abs_diff_eq(Vec3::Y, 1e-5));
    assert_eq!(c.footprint(1.0), c.footprint(100.0));
    assert!((c.footprint(1.0) - 0.05).abs() < 1e-7);
}

#[test]
fn orthographic_extent_follows_the_to_world_scale_as_in_mitsuba() {
    // Mitsuba 3.9.1, 200 x 100 film, to_world = scale(2, 3, 1): the sample at the film's top-left
    // corner starts at local (2, 1.5); unscaled at (1, 0.5) (mitsuba-conventions sec. 5.4).
    let scaled = mitsuba_ortho(Vec3::X * 2.0, Vec3::Y * 3.0, Vec3::Z, Vec3::ZERO, 200, 100);
    let o = scaled.generate_ray(Vec2::ZERO, Vec2::ZERO).o;
    assert!(o.abs_diff_eq(Vec3::new(2.0, 1.5, 0.0), 1e-6), "{o}");
    let plain = mitsuba_ortho(Vec3::X, Vec3::Y, Vec3::Z, Vec3::ZERO, 200, 100);
    assert!(plain.generate_ray(Vec2::ZERO, Vec2::ZERO).o.abs_diff_eq(Vec3::new(1.0, 0.5, 0.0), 1e-6));
    // translate(1, 2, 3) after scale(2, 3, 4): Mitsuba's corners are (3, 3.5) and (-1, 0.5), with
    // the rays along +z whatever the z scale.
    let c = mitsuba_ortho(Vec3::X * 2.0, Vec3::Y * 3.0, Vec3::Z * 4.0, Vec3::new(1.0, 2.0, 3.0), 200, 100);
    let a = c.generate_ray(Vec2::ZERO, Vec2::ZERO);
    let b = c.generate_ray(Vec2::new(200.0, 100.0), Vec2::ZERO);
    assert!(a.o.abs_diff_eq(Vec3::new(3.0, 3.5, 3.0), 1e-5) && b.o.abs_diff_eq(Vec3::new(-1.0, 0.5, 3.0), 1e-5));
    assert!(a.d.abs_diff_eq(Vec3::Z, 1e-7) && b.d.abs_diff_eq(Vec3::Z, 1e-7));
    // Non-uniform scale gives non-square pixels: 4 units across 200 pixels, 6 / 2 = 3 units up 100.
    assert!((c.footprint(1.0) - 3.0 / 100.0).abs() < 1e-7);
}

#[test]
fn principal_point_offset_shifts_the_view_as_mitsuba_does() {
    // Mitsuba 3.9.1: fov 90 along x on a 200 x 100 film, offsets (0.1, 0.2): the centre sample
    // looks along local tan-space (-0.2, -0.2), i.e. 0.2 to the image's right and 0.2 down.
    let desc = |ppo: Vec2| CameraDesc {
        placement: Placement::Frame { origin: Vec3::ZERO, x: Vec3::X, y: Vec3::Y, z: Vec3::Z },
        fov: FieldOfView::Angle { degrees: 90.0, axis: FovAxis::X },
        lens_radius: 0.0,
        focal_distance: 1.0,
        principal_point: ppo,
    };
    let c = desc(Vec2::new(0.1, 0.2)).build(200, 100);
    let d = c.generate_ray(Vec2::new(100.0, 50.0), Vec2::ZERO).d;
    let tan = Vec2::new(d.x / d.z, d.y / d.z);
    assert!(tan.abs_diff_eq(Vec2::new(-0.2, -0.2), 1e-5), "{tan}");
    let corner = c.generate_ray(Vec2::ZERO, Vec2::ZERO).d;
    assert!(Vec2::new(corner.x / corner.z, corner.y / corner.z).abs_diff_eq(Vec2::new(0.8, 0.3), 1e-5));
    // The offset is a shift of the whole image: pixel (x, y) of the shifted camera is pixel
    // (x + 20, y + 20) of the plain one.
    let plain = desc(Vec2::ZERO).build(200, 100);
    for (x, y) in [(0.0, 0.0), (37.5, 12.25), (150.0, 80.0)] {
        let a = c.generate_ray(Vec2::new(x, y), Vec2::ZERO).d;
        let b = plain.generate_ray(Vec2::new(x + 20.0, y + 20.0), Vec2::ZERO).d;
        assert!(a.abs_diff_eq(b, 1e-6), "{a} vs {b}");
    }
}
