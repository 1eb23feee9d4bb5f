//! Camera importance tests: We integrates to 1 over the full film, `sample_wi` inverts
//! `generate_ray`, the sampled directions follow `pdf_we` and `sample_wi`'s pdf by chi-square,
//! nothing off the film or behind the camera has importance, and light tracing an emitter that
//! fills the view gives its radiance in every part of the film.

use std::f32::consts::PI;

use super::super::*;
use crate::math::Frame;
use crate::sampling::Rng32;
use crate::sampling::chi2::{Chi2Config, chi2_directions};
use crate::sampling::warp::{concentric_disk, concentric_disk_inverse, uniform_cone};
use glam::Mat3;

fn look_at(lens_radius: f32, focal_distance: f32, fov: f32, width: u32, height: u32) -> Camera {
    let (eye, target) = (Vec3::new(1.0, 2.0, 5.0), Vec3::new(-0.5, 0.7, 0.3));
    Camera::new(eye, target, Vec3::Y, ViewPlane::Fov(fov), width, height, lens_radius, focal_distance)
}

/// A perspective camera in a tilted Mitsuba frame (image x along -x), with a principal-point
/// offset, on a non-square film.
fn shifted_pinhole() -> Camera {
    let z = Vec3::new(0.3, -0.2, 1.0).normalize();
    let f = Frame::from_z(z);
    CameraDesc {
        placement: Placement::Frame { origin: Vec3::new(0.5, -1.0, 2.0), x: f.x, y: f.y, z },
        fov: FieldOfView::Angle { degrees: 65.0, axis: FovAxis::X },
        lens_radius: 0.0,
        focal_distance: 1.0,
        principal_point: Vec2::new(0.1, -0.15),
    }
    .build(200, 120)
}

fn shifted_thin_lens() -> Camera {
    CameraDesc {
        placement: Placement::LookAt { eye: Vec3::new(-1.0, 0.5, 2.0), target: Vec3::new(0.0, 0.0, -3.0), up: Vec3::Y },
        fov: FieldOfView::Angle { degrees: 50.0, axis: FovAxis::Diagonal },
        lens_radius: 0.2,
        focal_distance: 3.0,
        principal_point: Vec2::new(-0.2, 0.1),
    }
    .build(150, 250)
}

/// A wide aperture close to the plane in focus, so that the lens subtends a wide cone from
/// points near that plane.
fn wide_thin_lens() -> Camera {
    look_at(0.5, 1.2, 60.0, 160, 120)
}

fn orthographic() -> Camera {
    CameraDesc {
        placement: Placement::LookAt { eye: Vec3::new(1.0, 2.0, 3.0), target: Vec3::new(4.0, 2.0, -1.0), up: Vec3::Y },
        fov: FieldOfView::Orthographic { size: 6.0, axis: FovAxis::X },
        lens_radius: 0.0,
        focal_distance: 1.0,
        principal_point: Vec2::ZERO,
    }
    .build(120, 80)
}

/// Mitsuba's orthographic sensor with a scaled and sheared `to_world`: the rays are not
/// perpendicular to the view plane.
fn sheared_orthographic() -> Camera {
    CameraDesc {
        placement: Placement::Frame {
            origin: Vec3::new(1.0, 2.0, 3.0),
            x: Vec3::new(2.0, 0.0, 0.2),
            y: Vec3::new(0.5, 3.0, 0.0),
            z: Vec3::new(0.3, 0.1, 4.0),
        },
        fov: FieldOfView::Orthographic { size: 2.0, axis: FovAxis::X },
        lens_radius: 0.0,
        focal_distance: 1.0,
        principal_point: Vec2::ZERO,
    }
    .build(200, 100)
}

fn cameras() -> Vec<(&'static str, Camera)> {
    let suffern = Camera::new(
        Vec3::new(0.0, 1.0, 5.0),
        Vec3::new(0.3, 1.2, 0.0),
        Vec3::Y,
        ViewPlane::Distance(300.0),
        200,
        150,
        0.0,
        1.0,
    );
    vec![
        ("pinhole", look_at(0.0, 1.0, 40.0, 320, 240)),
        ("thin lens", look_at(0.3, 4.0, 40.0, 320, 240)),
        ("shifted non-square pinhole", shifted_pinhole()),
        ("shifted non-square thin lens", shifted_thin_lens()),
        ("wide thin lens", wide_thin_lens()),
        ("view-distance pinhole", suffern),
        ("orthographic", orthographic()),
        ("sheared orthographic", sheared_orthographic()),
    ]
}

fn film(c: &Camera) -> Vec2 {
    Vec2::new(c.width as f32, c.height as f32)
}

fn relative(a: f32, b: f32) -> f32 {
    (a - b).abs() / a.abs().max(b.abs())
}

/// |cos| between an orthographic camera's rays and its view plane's normal.
fn plane_cos(c: &Camera) -> f32 {
    c.u.cross(c.v).normalize().dot(c.w).abs()
}

/// Mean and standard error of `n` draws of `x`.
fn mean_and_error(n: usize, mut x: impl FnMut() -> f64) -> (f64, f64) {
    let (mut sum, mut sum2) = (0.0, 0.0);
    for _ in 0..n {
        let v = x();
        sum += v;
        sum2 += v * v;
    }
    let mean = sum / n as f64;
    (mean, ((sum2 / n as f64 - mean * mean) / n as f64).sqrt())
}

#[test]
fn importance_integrates_to_one_over_the_full_film() {
    for (seed, (name, c)) in cameras().into_iter().enumerate() {
        let mut rng = Rng32::new(41 + seed as u64);
        let (mean, error) = match c.projection {
            // Uniform directions on the hemisphere about the axis (density 1 / 2 pi) from uniform
            // lens points (density 1 / lens area; a pinhole's position is a delta).
            Projection::Perspective => {
                let axis = Frame::from_z(-c.w);
                let lens_area = if c.uses_lens() { PI * c.lens_radius * c.lens_radius } else { 1.0 };
                mean_and_error(1 << 23, || {
                    let local = uniform_cone(rng.uniform2(), 0.0);
                    let l = concentric_disk(rng.uniform2()) * c.lens_radius;
                    let ray = Ray::new(c.eye + l.x * c.u + l.y * c.v, axis.to_world(local));
                    c.we(&ray).map_or(0.0, |(we, _)| f64::from(we * local.z * 2.0 * PI * lens_area))
                })
            }
            // The delta direction leaves the integral over the view plane of We |cos theta_p|:
            // uniform points on a rectangle 1.5 times the film's size each way.
            Projection::Orthographic => {
                let half = film(&c) * c.pixel_size * 0.75;
                let area = 4.0 * half.x * half.y * c.u.cross(c.v).length();
                let cos = plane_cos(&c);
                mean_and_error(1 << 22, || {
                    let ps = (2.0 * rng.uniform2() - Vec2::ONE) * half;
                    let ray = Ray::new(c.eye + ps.x * c.u + ps.y * c.v, -c.w);
                    c.we(&ray).map_or(0.0, |(we, _)| f64::from(we * cos * area))
                })
            }
        };
        eprintln!("{name}: integral of We |cos| = {mean:.5} +- {error:.5}");
        assert!(error < 0.0025, "{name}: standard error {error} too large for a 1% test");
        assert!((mean - 1.0).abs() < 0.01, "{name}: We integrates to {mean} +- {error}, not 1");
    }
}

/// The raster point the line from lens sample `u` through `p` lands on, found by intersecting
/// planes in world space (perspective) or by a matrix inverse (orthographic): another route than
/// `sample_wi`'s. None behind the camera or off the film.
fn raster_by_geometry(c: &Camera, p: Vec3, u: Vec2) -> Option<Vec2> {
    let ps = match c.projection {
        Projection::Perspective => {
            let l = if c.uses_lens() { concentric_disk(u) * c.lens_radius } else { Vec2::ZERO };
            let p_lens = c.eye + l.x * c.u + l.y * c.v;
            let depth = (p - p_lens).dot(-c.w);
            if depth <= 0.0 {
                return None;
            }
            let plane = if c.uses_lens() { c.focal_distance } else { c.d };
            let hit = p_lens + (p - p_lens) * (plane / depth) - c.eye;
            Vec2::new(hit.dot(c.u), hit.dot(c.v)) * (c.d / plane)
        }
        Projection::Orthographic => {
            let q = Mat3::from_cols(c.u, c.v, c.w).inverse() * (p - c.eye);
            if q.z >= 0.0 {
                return None;
            }
            Vec2::new(q.x, q.y)
        }
    };
    let raster = Vec2::new(ps.x / c.pixel_size + 0.5 * film(c).x, 0.5 * film(c).y - ps.y / c.pixel_size) - c.shift;
    let inside = raster.cmpge(Vec2::ZERO).all() && raster.cmplt(film(c)).all();
    inside.then_some(raster)
}

#[test]
fn sample_wi_inverts_generate_ray() {
    for (name, c) in cameras() {
        let mut rng = Rng32::new(17);
        let (trials, mut connected) = (4000, 0);
        let (mut worst_miss, mut worst_we, mut worst_pdf) = (0.0f32, 0.0f32, 0.0f32);
        for _ in 0..trials {
            // A point in view from some lens point; seen from another (u), a thin lens may see
            // it off the film.
            let start = c.generate_ray(rng.uniform2() * film(&c), rng.uniform2());
            let p = start.at(0.3 * 100f32.powf(rng.uniform()));
            let u = rng.uniform2();
            let by_geometry = raster_by_geometry(&c, p, u);
            let Some(s) = c.sample_wi(p, u) else {
                assert!(by_geometry.is_none(), "{name}: no connection to {p}, which lands at {by_geometry:?}");
                continue;
            };
            connected += 1;
            let expected = by_geometry.unwrap_or_else(|| panic!("{name}: {p} connected at {} off the film", s.raster));
            assert!((s.raster - expected).abs().max_element() < 2e-3, "{name}: raster {} vs {expected}", s.raster);

            // generate_ray at the returned raster and the same lens sample runs through p.
            let ray = c.generate_ray(s.raster, u);
            let to_p = p - ray.o;
            let miss = (to_p - ray.d * to_p.dot(ray.d)).length() / to_p.length();
            worst_miss = worst_miss.max(miss);
            assert!(miss < 1e-4, "{name}: the ray misses {p} by {miss} of its distance");
            assert!((ray.o - s.p_lens).length() < 1e-5 * (p - c.eye).length().max(1.0));
            assert!((s.dist - to_p.length()).abs() <= 1e-5 * s.dist, "{name}: dist {} vs {}", s.dist, to_p.length());
            assert!((s.wi.length() - 1.0).abs() < 1e-5 && ray.d.dot(s.wi) < -0.99999, "{name}: wi {}", s.wi);
            assert_eq!(s.n_lens, -c.w);

            // The importance is that of the ray, and the pdf follows from pdf_we.
            let (we, raster) = c.we(&ray).unwrap_or_else(|| panic!("{name}: no importance for {ray:?}"));
            worst_we = worst_we.max(relative(we, s.importance));
            assert!(relative(we, s.importance) < 1e-4, "{name}: importance {} vs We {we}", s.importance);
            assert!((raster - s.raster).abs().max_element() < 2e-3, "{name}: We's raster {raster} vs {}", s.raster);
            let (pdf_pos, pdf_dir) = c.pdf_we(&ray);
            let cos = ray.d.dot(s.n_lens);
            match c.projection {
                Projection::Perspective => {
                    let pdf = pdf_pos * s.dist * s.dist / cos;
                    worst_pdf = worst_pdf.max(relative(s.pdf, pdf));
                    assert!(relative(s.pdf, pdf) < 1e-4, "{name}: pdf {} vs {pdf}", s.pdf);
                    // Uniform film and lens sampling has density We cos.
                    assert!(
                        relative(we * cos, pdf_pos * pdf_dir) < 1e-4,
                        "{name}: We cos {} vs {pdf_pos} {pdf_dir}",
                        we * cos
                    );
                    assert_eq!(s.delta, !c.uses_lens(), "{name}");
                }
                Projection::Orthographic => {
                    assert!(s.pdf == 1.0 && s.delta && pdf_dir == 1.0, "{name}: {s:?}, pdf_dir {pdf_dir}");
                    worst_pdf = worst_pdf.max(relative(we * plane_cos(&c), pdf_pos));
                    assert!(relative(we * plane_cos(&c), pdf_pos) < 1e-4, "{name}: We {we} vs pdf_pos {pdf_pos}");
                }
            }
        }
        eprintln!(
            "{name}: {connected} of {trials} connected; worst miss {worst_miss:.1e}, importance {worst_we:.1e}, \
             pdf {worst_pdf:.1e} (relative)"
        );
        assert!(connected >= trials / 2, "{name}: only {connected} of {trials} points connected");
    }
}

/// Raster points well outside the full film, each side and corner.
fn off_film(c: &Camera, rng: &mut Rng32) -> Vec<Vec2> {
    let mut points: Vec<Vec2> =
        [(-0.3, 0.5), (1.3, 0.5), (0.5, -0.3), (0.5, 1.3), (-0.2, -0.2), (1.1, 1.2), (-0.01, 0.5), (0.5, 1.01)]
            .into_iter()
            .map(|(x, y)| Vec2::new(x, y))
            .collect();
    while points.len() < 200 {
        let q = 3.0 * rng.uniform2() - Vec2::ONE;
        if q.cmplt(Vec2::splat(-0.01)).any() || q.cmpgt(Vec2::splat(1.01)).any() {
            points.push(q);
        }
    }
    points.into_iter().map(|q| q * film(c)).collect()
}

#[test]
fn points_behind_the_camera_or_off_the_film_are_not_connected() {
    for (name, c) in cameras() {
        let mut rng = Rng32::new(5);
        let depth = |ray: &Ray, p: Vec3| (p - ray.o).dot(-c.w);
        for _ in 0..1000 {
            let ray = c.generate_ray(rng.uniform2() * film(&c), rng.uniform2());
            let p = ray.at(0.3 * 100f32.powf(rng.uniform()));
            // Mirrored through the lens plane, and just behind it.
            let behind = p + 2.0 * depth(&ray, p) * c.w;
            let beside = p + 1.001 * depth(&ray, p) * c.w;
            for q in [behind, beside] {
                assert!(c.sample_wi(q, rng.uniform2()).is_none(), "{name}: {q} behind the camera is connected");
            }
        }
        // Points whose every ray lands off the film: on the plane in focus for a thin lens, at
        // any depth for a pinhole or an orthographic camera.
        for raster in off_film(&c, &mut rng) {
            let p = match c.projection {
                Projection::Perspective => {
                    let ps = c.view_plane_point(raster);
                    let scale = if c.uses_lens() { c.focal_distance / c.d } else { 0.2 + 5.0 * rng.uniform() };
                    c.eye + (ps.x * c.u + ps.y * c.v - c.d * c.w) * scale
                }
                Projection::Orthographic => c.generate_ray(raster, Vec2::ZERO).at(0.1 + 10.0 * rng.uniform()),
            };
            for _ in 0..8 {
                let u = rng.uniform2();
                assert!(c.sample_wi(p, u).is_none(), "{name}: {p} off the film at {raster} is connected");
            }
        }
    }
}

#[test]
fn importance_is_zero_off_the_film_and_behind_the_camera() {
    for (name, c) in cameras() {
        let mut rng = Rng32::new(9);
        for raster in off_film(&c, &mut rng) {
            let ray = c.generate_ray(raster, rng.uniform2());
            assert_eq!(c.we(&ray), None, "{name}: importance off the film at {raster}");
            assert_eq!(c.pdf_we(&ray), (0.0, 0.0), "{name}: density off the film at {raster}");
        }
        for _ in 0..1000 {
            let raster = rng.uniform2() * film(&c);
            let ray = c.generate_ray(raster, rng.uniform2());
            let (we, at) = c.we(&ray).unwrap_or_else(|| panic!("{name}: no importance at {raster}"));
            assert!(we > 0.0 && we.is_finite() && (at - raster).abs().max_element() < 2e-3, "{name}: {we} at {at}");
            let (pdf_pos, pdf_dir) = c.pdf_we(&ray);
            assert!(pdf_pos > 0.0 && pdf_dir > 0.0, "{name}: densities {pdf_pos}, {pdf_dir} at {raster}");
            // Backwards, and along the lens plane tilted just behind it (exactly along it the
            // side is a matter of rounding).
            let side = Frame::from_z(c.w);
            let behind = |d: Vec3| (d + 1e-3 * c.w).normalize();
            for d in [-ray.d, behind(side.x), behind(side.y), behind(-side.x)] {
                let turned = Ray::new(ray.o, d);
                assert_eq!(c.we(&turned), None, "{name}: importance along {d}");
                assert_eq!(c.pdf_we(&turned), (0.0, 0.0), "{name}: density along {d}");
            }
        }
    }
}

/// Chi-square tests in this file (for the Sidak correction).
const CHI2_TESTS: usize = 5;

/// Rays of `generate_ray` at uniform film points from lens sample `lens`, against `pdf_we`'s
/// direction density, on a grid whose pole is the camera axis.
fn chi2_camera_rays(name: &str, c: &Camera, lens: Vec2, theta_res: usize) {
    let axis = Frame { x: c.u, y: c.v, z: -c.w };
    let origin = c.generate_ray(Vec2::ZERO, lens).o;
    let config = Chi2Config { tests: CHI2_TESTS, ..Chi2Config::with_theta_res(theta_res) };
    let stats = chi2_directions(
        name,
        |u, _| Some(axis.to_local(c.generate_ray(u * film(c), lens).d)),
        |d| c.pdf_we(&Ray::new(origin, axis.to_world(d))).1,
        &config,
    )
    .unwrap_or_else(|report| panic!("{report}"));
    eprintln!("{name}: {stats:?}");
    assert!((stats.pdf_integral - 1.0).abs() < 2e-3, "{name}: pdf_dir integrates to {}", stats.pdf_integral);
}

#[test]
fn camera_ray_directions_follow_pdf_we() {
    chi2_camera_rays("pinhole", &look_at(0.0, 1.0, 40.0, 320, 240), Vec2::ZERO, 60);
    chi2_camera_rays("shifted non-square pinhole", &shifted_pinhole(), Vec2::ZERO, 40);
    // A thin lens's direction density is conditional on the lens point.
    chi2_camera_rays("shifted thin lens, one lens point", &shifted_thin_lens(), Vec2::new(0.85, 0.2), 40);
}

/// Directions `wi` of `sample_wi` from `p` against its pdf, on a grid whose pole points from `p`
/// to the eye. The density of a direction is `sample_wi`'s pdf for the lens sample whose lens
/// point the direction meets (0 off the lens), so where the lens sees `p` off the film both
/// sides are 0 and `pdf_integral` is the visible fraction.
fn chi2_lens_connections(name: &str, c: &Camera, p: Vec3) -> f64 {
    let frame = Frame::from_z((c.eye - p).normalize());
    let density = |wi: Vec3| {
        let t = (c.eye - p).dot(c.w) / wi.dot(c.w);
        if !(t > 0.0) {
            return 0.0;
        }
        let on_lens = p + wi * t - c.eye;
        let l = Vec2::new(on_lens.dot(c.u), on_lens.dot(c.v)) / c.lens_radius;
        if l.length_squared() >= 1.0 {
            return 0.0;
        }
        c.sample_wi(p, concentric_disk_inverse(l)).map_or(0.0, |s| s.pdf)
    };
    let config = Chi2Config { tests: CHI2_TESTS, ..Chi2Config::with_theta_res(48) };
    let stats = chi2_directions(
        name,
        |u, _| c.sample_wi(p, u).map(|s| frame.to_local(s.wi)),
        |d| density(frame.to_world(d)),
        &config,
    )
    .unwrap_or_else(|report| panic!("{report}"));
    eprintln!("{name}: {stats:?}");
    stats.pdf_integral
}

#[test]
fn lens_connections_follow_their_pdf() {
    let c = wide_thin_lens();
    // Near the plane in focus and the film's centre: the whole lens sees the point on the film.
    let p = c.eye - 1.0 * c.w + 0.1 * c.u + 0.05 * c.v;
    let visible = chi2_lens_connections("thin lens, point in view", &c, p);
    assert!((visible - 1.0).abs() < 2e-3, "the density integrates to {visible}");
    // Close to the lens at the film's left edge: part of the lens sees it off the film.
    let ps = c.view_plane_point(Vec2::new(0.02 * c.width as f32, 0.5 * c.height as f32));
    let p = c.eye + (ps.x * c.u + ps.y * c.v - c.d * c.w) * (0.7 / c.d);
    let visible = chi2_lens_connections("thin lens, point at the film's edge", &c, p);
    assert!(visible > 0.2 && visible < 0.8, "the density integrates to {visible}");
}

/// The light tracer's contract end to end: a one-sided Lambertian emitter of radiance 1 filling
/// the view, light-traced with the t = 1 strategy (one emitter point and one lens sample per
/// pixel sample of the full film, each adding L |cos| importance / pdf / p_area to the pixel it
/// lands in, the sums divided by the samples per pixel) gives 1 everywhere. Checked on blocks of
/// pixels, each against its own standard error.
#[test]
fn light_tracing_an_emitter_filling_the_view_gives_its_radiance() {
    const BLOCKS: (usize, usize) = (16, 12);
    for (seed, (name, c)) in cameras().into_iter().enumerate() {
        let mut rng = Rng32::new(70 + seed as u64);
        // A tilted plane three units ahead, facing the camera.
        let centre = c.eye - 3.0 * c.w;
        let n = (c.w + 0.4 * c.u.normalize() + 0.2 * c.v.normalize()).normalize();
        let plane = Frame::from_z(n);
        let hit = |ray: &Ray| {
            let q = ray.at((centre - ray.o).dot(n) / ray.d.dot(n)) - centre;
            Vec2::new(q.dot(plane.x), q.dot(plane.y))
        };
        // The part of the plane the camera sees, from rays along the film's edges.
        let mut half = Vec2::ZERO;
        for i in 0..4000 {
            let t = rng.uniform();
            let edge = [Vec2::new(t, 0.0), Vec2::new(t, 1.0), Vec2::new(0.0, t), Vec2::new(1.0, t)][i % 4];
            let lens = if i % 8 < 4 { rng.uniform2() } else { Vec2::new(rng.uniform(), (i % 2) as f32) };
            half = half.max(hit(&c.generate_ray(edge * film(&c), lens)).abs());
        }
        half *= 1.1;
        let area = 4.0 * half.x * half.y;
        let (mut sum, mut sum2) = (vec![0.0f64; BLOCKS.0 * BLOCKS.1], vec![0.0f64; BLOCKS.0 * BLOCKS.1]);
        // Samples per pixel: enough for about four million paths.
        let spp = (4_000_000 / (c.width * c.height) as usize).max(1);
        let paths = c.width as usize * c.height as usize * spp;
        for _ in 0..paths {
            let a = (2.0 * rng.uniform2() - Vec2::ONE) * half;
            let x = centre + a.x * plane.x + a.y * plane.y;
            let Some(s) = c.sample_wi(x, rng.uniform2()) else { continue };
            let value = f64::from(n.dot(s.wi).max(0.0) * s.importance / s.pdf * area);
            let block = (s.raster / film(&c) * Vec2::new(BLOCKS.0 as f32, BLOCKS.1 as f32)).as_uvec2();
            let index = (block.y as usize).min(BLOCKS.1 - 1) * BLOCKS.0 + (block.x as usize).min(BLOCKS.0 - 1);
            sum[index] += value;
            sum2[index] += value * value;
        }
        // A block's value is the mean of its pixels' values (sums / spp): its sum over spp times
        // its pixels, W H / blocks, which is paths / blocks.
        let norm = paths as f64 / (BLOCKS.0 * BLOCKS.1) as f64;
        let mut worst_z = 0.0f64;
        for (s, s2) in sum.iter().zip(&sum2) {
            let z = (s / norm - 1.0) / (s2.sqrt() / norm);
            worst_z = worst_z.max(z.abs());
        }
        let total: f64 = sum.iter().sum::<f64>() / (norm * sum.len() as f64);
        let total_error = sum2.iter().sum::<f64>().sqrt() / (norm * sum.len() as f64);
        eprintln!("{name}: film mean {total:.5} +- {total_error:.5}, worst block {worst_z:.2} standard errors off");
        assert!(
            (total - 1.0).abs() < 0.01 && total_error < 0.0025,
            "{name}: the film averages {total} +- {total_error}"
        );
        assert!(worst_z < 5.0, "{name}: a block is {worst_z} standard errors away from 1");
    }
}
