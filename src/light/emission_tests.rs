//! Emission sampling tests: for every kind of light, `Light::sample_le` draws its rays from the
//! densities `Light::pdf_le` reports, and each ray's flux is what its own numbers say.
//!
//! - Directions: chi-square over the sphere (`chi2_directions`) against pdf_le's direction
//!   density, on a grid whose pole is the light's axis where it has one (spot, projector, an
//!   environment map's poles) so that narrow cones and the map's 1 / sin theta poles are resolved.
//!   Flat area lights are tested in world space (one normal for every point); on a sphere and a
//!   cylinder each direction is first expressed in a frame about its own point's normal (built by
//!   the test, not the sampler's) and compared with pdf_le's density about one reference normal:
//!   the conditional density is the same cosine at every point, and the per-sample checks below
//!   hold pdf_le to it at the sampled normals themselves. A directional light's direction is a
//!   delta: every ray must have the light's direction, with pdf_le's direction density 0.
//! - Positions: chi-square (`chi2_cells`) of the sampled origins on each shape's own 2-D
//!   parameterisation (a quad's, a sphere's and a cylinder's (u, v), a triangle's barycentrics on
//!   a grid of small triangles, a disk's (r^2, phi) in its local unit disk), the expected counts
//!   being pdf_le's position density integrated with the area element over each cell; and for
//!   lights at infinity of the ray's crossing point with the photon disk, in rings (uniform in
//!   rho^2 on the core, in ln rho beyond it) times sectors, against pdf_le's position density
//!   (`PhotonDisk::pdf_ray`). Cells reach past the support, so points where the
//!   density is zero fail the test.
//! - Every sample: pdf_le(ray, n) equals the sample's (pdf_pos, pdf_dir) (a delta part reports 1
//!   in the sample and 0 in pdf_le), and flux = le |cos| / (pdf_pos pdf_dir), cos = 1 for lights
//!   without a surface. Samples whose densities disagree only because pdf_le jumps within a hair of
//!   the ray (an environment map's cell edge, the rim of a photon disk's core) or that leave a
//!   surface at grazing angles are counted as degenerate and must be rare.
//!
//! The chi-square tests count as one suite of `CHI2_TESTS` for the Sidak correction (pbrt-v4
//! `src/pbrt/bsdfs_test.cpp`, Mitsuba 3 `chi2.py`).

use super::*;
use crate::geometry::Transform;
use crate::sampling::Rng32;
use crate::sampling::chi2::{Chi2Config, Chi2Stats, chi2_cells, chi2_directions};
use crate::shape::{Cylinder, Disk, Quad, Sphere, TRIANGLE_UV, Triangle};
use glam::Affine2;

/// Chi-square tests in this file, for the Sidak correction.
const CHI2_TESTS: usize = 20;
/// Samples per chi-square test.
const SAMPLES: usize = 500_000;
/// Largest relative difference between a sample's densities and pdf_le's, and between its flux
/// and le |cos| / (pdf_pos pdf_dir), for a sample leaving its surface at cos 1 (divided by cos
/// otherwise: the cosine is worked out once in the sampler's frame and once from the ray).
const PDF_TOLERANCE: f64 = 1e-4;
const FLUX_TOLERANCE: f64 = 1e-5;
/// Cosine below which a ray leaving a surface is grazing: its direction density is nearly 0.
const GRAZING: f32 = 1e-3;
/// Largest share of degenerate samples.
const DEGENERATE_SHARE: f64 = 1e-4;
const TAU_64: f64 = std::f64::consts::TAU;

/// The texture every textured light here reads: a checkerboard of two colours, four squares
/// across, so that le and flux vary from sample to sample.
fn textures() -> Vec<Texture> {
    vec![Texture::Checkerboard {
        color0: Color::new(0.2, 0.6, 1.0),
        color1: Color::new(1.5, 1.0, 0.3),
        to_uv: Affine2::from_scale(Vec2::splat(4.0)),
    }]
}

fn checker() -> Option<EmissionTexture> {
    let mean = textures()[0].mean();
    Some(EmissionTexture { texture: 0, mean, vertex_uv: TRIANGLE_UV })
}

fn area_light(shape: Shape) -> Light {
    Light::Area { shape, radiance: Color::new(1.5, 1.0, 0.5), texture: checker() }
}

fn relative(a: f64, b: f64) -> f64 {
    if a == b { 0.0 } else { (a - b).abs() / a.abs().max(b.abs()) }
}

/// What kind of densities a light has: (delta position, delta direction, emits from a surface).
fn kind(light: &Light) -> (bool, bool, bool) {
    match light {
        Light::Point { .. } | Light::Spot(_) | Light::Projector(_) => (true, false, false),
        Light::Directional { .. } => (false, true, false),
        Light::Area { .. } => (false, false, true),
        Light::Environment(_) => (false, false, false),
    }
}

/// How a light's samples agree with pdf_le and with their own flux, sample by sample.
#[derive(Default)]
struct Agreement {
    samples: u64,
    /// Samples on a jump of pdf_le or grazing their surface (see the module docs).
    degenerate: u64,
    /// The largest relative differences among the other samples.
    worst_pdf: f64,
    worst_flux: f64,
    failed: u64,
    /// The first few failures.
    failures: Vec<String>,
}

impl Agreement {
    fn fail(&mut self, what: String) {
        self.failed += 1;
        if self.failures.len() < 5 {
            self.failures.push(what);
        }
    }

    fn check(&mut self, light: &Light, s: &EmissionSample) {
        self.samples += 1;
        let (delta_pos, delta_dir, surface) = kind(light);
        let (pos, dir) = light.pdf_le(&s.ray, s.n);
        if !((s.ray.d.length() - 1.0).abs() < 1e-5 && (s.n.length() - 1.0).abs() < 1e-5) {
            return self.fail(format!("direction {} or normal {} is not a unit vector", s.ray.d, s.n));
        }
        // Where the ray starts and which way it goes, for lights that fix one or the other.
        let fixed = match *light {
            Light::Point { position, .. }
            | Light::Spot(Spot { position, .. })
            | Light::Projector(Projector { position, .. }) => s.ray.o == position && s.n == s.ray.d,
            Light::Directional { direction, .. } => s.ray.d == direction && s.n == direction,
            // The front side, up to the rounding of a grazing direction.
            Light::Area { .. } => s.n.dot(s.ray.d) > -GRAZING,
            Light::Environment(_) => s.n == s.ray.d,
        };
        if !fixed {
            return self.fail(format!("ray {:?} with normal {} does not leave the light as it should", s.ray, s.n));
        }
        let cos = if surface { s.n.dot(s.ray.d) } else { 1.0 };
        if surface && cos < GRAZING {
            self.degenerate += 1;
            return;
        }
        if delta_pos && !(pos == 0.0 && s.pdf_pos == 1.0) {
            return self.fail(format!("delta position: pdf_le {pos}, sample {}", s.pdf_pos));
        }
        if delta_dir && !(dir == 0.0 && s.pdf_dir == 1.0) {
            return self.fail(format!("delta direction: pdf_le {dir}, sample {}", s.pdf_dir));
        }
        let tolerance = PDF_TOLERANCE / cos as f64;
        let pos_error = if delta_pos { 0.0 } else { relative(pos as f64, s.pdf_pos as f64) };
        let dir_error = if delta_dir { 0.0 } else { relative(dir as f64, s.pdf_dir as f64) };
        if !(s.pdf_pos > 0.0 && s.pdf_dir > 0.0) {
            return self.fail(format!("sample densities ({}, {}) are not positive", s.pdf_pos, s.pdf_dir));
        }
        if pos_error.max(dir_error) > tolerance {
            if jumps_near(light, s, delta_pos, delta_dir) {
                self.degenerate += 1;
                return;
            }
            return self.fail(format!(
                "pdf_le ({pos}, {dir}) but the sample has ({}, {}) at ray {:?}, normal {}",
                s.pdf_pos, s.pdf_dir, s.ray, s.n
            ));
        }
        self.worst_pdf = self.worst_pdf.max(pos_error.max(dir_error) * cos as f64);
        let want = s.le * (cos / (s.pdf_pos * s.pdf_dir));
        let scale = s.flux.max_element().max(want.max_element()) as f64;
        let flux_error = if scale == 0.0 { 0.0 } else { (s.flux - want).abs().max_element() as f64 / scale };
        if !(s.flux.is_finite() && s.le.is_finite() && flux_error <= FLUX_TOLERANCE / cos as f64) {
            return self.fail(format!(
                "flux {} but le {} |cos| {cos} / (pdf_pos {} pdf_dir {}) = {want}",
                s.flux, s.le, s.pdf_pos, s.pdf_dir
            ));
        }
        self.worst_flux = self.worst_flux.max(flux_error * cos as f64);
    }

    /// `Ok` with a summary, or `Err` with what went wrong.
    fn verdict(&self, name: &str) -> Result<String, String> {
        let summary = format!(
            "{} samples, {} degenerate, worst relative pdf error {:.1e}, flux {:.1e} (times cos)",
            self.samples, self.degenerate, self.worst_pdf, self.worst_flux
        );
        if self.failed > 0 {
            return Err(format!(
                "{name}: {} samples disagree with pdf_le or their flux: {:#?}",
                self.failed, self.failures
            ));
        }
        if self.degenerate as f64 > DEGENERATE_SHARE * self.samples as f64 {
            return Err(format!("{name}: too many degenerate samples: {summary}"));
        }
        Ok(summary)
    }
}

/// Whether the sample's densities, which differ from pdf_le's at its ray, are what pdf_le gives
/// within a hair of it (the ray turned, or its origin moved, by 1e-6 to 1e-4): the ray sits on a
/// jump of the density (the edge of an environment map's cell, the rim of a photon disk's core, a
/// spot's cutoff) or next to a pole (an environment map's 1 / sin theta), where the sampler's
/// arithmetic and pdf_le's round differently.
fn jumps_near(light: &Light, s: &EmissionSample, delta_pos: bool, delta_dir: bool) -> bool {
    let (pos, dir) = light.pdf_le(&s.ray, s.n);
    let (mut lo, mut hi) = ((pos, dir), (pos, dir));
    let f = Frame::from_z(s.ray.d);
    let reach = 1.0 + s.ray.o.length();
    for h in [1e-6, 1e-5, 1e-4] {
        for t in [f.x, -f.x, f.y, -f.y] {
            let turned = Ray::new(s.ray.o, (s.ray.d + t * h).normalize());
            let moved = Ray::new(s.ray.o + t * (h * reach), s.ray.d);
            for ray in [turned, moved] {
                let (p, d) = light.pdf_le(&ray, s.n);
                lo = (lo.0.min(p), lo.1.min(d));
                hi = (hi.0.max(p), hi.1.max(d));
            }
        }
    }
    let tol = PDF_TOLERANCE as f32;
    let within = |x: f32, lo: f32, hi: f32| x >= lo * (1.0 - tol) && x <= hi * (1.0 + tol);
    (delta_pos || within(s.pdf_pos, lo.0, hi.0)) && (delta_dir || within(s.pdf_dir, lo.1, hi.1))
}

/// Outcomes of a test's cases: each a summary, or a report of what failed; all cases run, then
/// the test fails with every report.
#[derive(Default)]
struct Outcomes(Vec<Result<String, String>>);

impl Outcomes {
    fn chi2(&mut self, name: &str, stats: Result<Chi2Stats, String>, agreement: &Agreement) {
        let outcome = stats.and_then(|st| {
            let line = format!(
                "{name}: p-value {:.4} (alpha {:.1e}), statistic {:.1}, dof {}, {} cells pooled, \
                 density integral {:.5}",
                st.p_value, st.alpha, st.statistic, st.dof, st.cells_pooled, st.pdf_integral
            );
            if (st.pdf_integral - 1.0).abs() > 2e-3 {
                return Err(format!("{line}: the density should integrate to 1"));
            }
            Ok(line)
        });
        self.0.push(outcome);
        self.0.push(agreement.verdict(name).map(|s| format!("{name}: {s}")));
    }

    fn finish(self) {
        let mut failures = Vec::new();
        for outcome in self.0 {
            match outcome {
                Ok(line) => eprintln!("{line}"),
                Err(report) => failures.push(report),
            }
        }
        assert!(failures.is_empty(), "{}", failures.join("\n\n"));
    }
}

fn config(theta_res: usize, phi_res: usize) -> Chi2Config {
    Chi2Config { theta_res, phi_res, samples: SAMPLES, tests: CHI2_TESTS, ..Chi2Config::default() }
}

/// Chi-square of the directions of `light`'s rays, mapped by `to_grid` into the grid's frame
/// (z its pole), against `density` of a grid direction; every sample also goes through
/// `Agreement::check`. The test's (u, u1) pick the direction, a stream seeded by `seed` the point.
fn chi2_ray_directions(
    outcomes: &mut Outcomes,
    name: &str,
    light: &Light,
    config: &Chi2Config,
    seed: u64,
    to_grid: impl Fn(&EmissionSample) -> Vec3,
    density: impl Fn(Vec3) -> f32,
) {
    let textures = textures();
    let mut agreement = Agreement::default();
    let mut rng = Rng32::new(seed);
    let stats = chi2_directions(
        name,
        |u, _| {
            let s = light.sample_le(rng.uniform2(), u, &textures)?;
            agreement.check(light, &s);
            Some(to_grid(&s))
        },
        density,
        config,
    );
    outcomes.chi2(name, stats, &agreement);
}

/// A grid for directions in a frame: samples are seen in it, the density is asked in the world.
fn in_frame(
    light: &Light,
    grid: Frame,
    origin: Vec3,
    n: Vec3,
) -> (impl Fn(&EmissionSample) -> Vec3, impl Fn(Vec3) -> f32 + '_) {
    (move |s: &EmissionSample| grid.to_local(s.ray.d), move |w| light.pdf_le(&Ray::new(origin, grid.to_world(w)), n).1)
}

#[test]
fn point_spot_and_projector_directions_follow_pdf_le() {
    let mut outcomes = Outcomes::default();
    let position = Vec3::new(1.0, 2.0, -0.5);
    let point = Light::Point { position, intensity: Color::new(1.0, 2.0, 3.0) };
    let world = Frame { x: Vec3::X, y: Vec3::Y, z: Vec3::Z };
    let (to_grid, density) = in_frame(&point, world, position, Vec3::Z);
    chi2_ray_directions(&mut outcomes, "point", &point, &config(18, 36), 1, to_grid, density);

    // Tilted spots with a texture; the grid's pole is the spot's axis, its rows ending at the
    // cutoff (5 and 1 degree rows).
    let frame = Frame::from_z_x(Vec3::new(0.3, -1.0, 0.4).normalize(), Vec3::new(1.0, 0.2, 0.0));
    for (name, cutoff, beam, theta_res, phi_res) in
        [("spot 30/20", 30.0, 20.0, 36, 36), ("narrow spot 5/2", 5.0, 2.0, 180, 24)]
    {
        let spot = Light::Spot(Spot::new(position, frame, Color::new(2.0, 3.0, 1.0), cutoff, beam, 0));
        let (to_grid, density) = in_frame(&spot, frame, position, frame.z);
        chi2_ray_directions(&mut outcomes, name, &spot, &config(theta_res, phi_res), 2, to_grid, density);
    }

    // A non-square, tilted projector with a texture.
    let frame = Frame::from_z_x(Vec3::new(-0.2, -0.5, 1.0).normalize(), Vec3::new(1.0, 0.3, 0.0));
    let projector = Light::Projector(Projector {
        position,
        frame,
        intensity: Color::splat(PI * 1.5),
        tan_x: 0.7,
        tan_y: 0.3,
        texture: 0,
        mean: textures()[0].mean(),
    });
    let (to_grid, density) = in_frame(&projector, frame, position, frame.z);
    chi2_ray_directions(&mut outcomes, "projector 0.7 x 0.3", &projector, &config(45, 48), 3, to_grid, density);
    outcomes.finish();
}

/// The area lights: a parallelogram, a triangle, a sphere turned by its transform, an ellipse
/// (a disk scaled unevenly and turned) and a turned cylinder, none aligned with the axes.
fn quad() -> Quad {
    Quad::new(Vec3::new(0.5, 1.0, -1.0), Vec3::new(1.5, 0.3, 0.4), Vec3::new(-0.2, 0.5, 1.2)).unwrap()
}

fn triangle() -> Triangle {
    Triangle::new(Vec3::new(0.2, -0.5, 1.0), Vec3::new(1.7, 0.4, 0.3), Vec3::new(-0.4, 1.1, 0.8))
}

fn sphere() -> Sphere {
    let t = Transform::rotate(Vec3::new(1.0, 2.0, 0.5), 50.0).then(Transform::translate(Vec3::new(-1.0, 0.5, 2.0)));
    let (s, proper) = Sphere::transformed(&t, Vec3::ZERO, 0.7);
    assert!(proper && s.to_local != [0.0, 0.0, 0.0, 1.0]);
    s
}

fn disk() -> Disk {
    let t = Transform::scale(Vec3::new(1.6, 0.9, 1.0))
        .then(Transform::rotate(Vec3::new(1.0, 2.0, -0.5), 40.0))
        .then(Transform::translate(Vec3::new(0.3, -1.0, 2.0)));
    Disk::from_transform(&t, false).unwrap()
}

fn cylinder() -> Cylinder {
    let t = Transform::rotate(Vec3::new(1.0, -1.0, 0.5), 35.0).then(Transform::translate(Vec3::new(1.0, 0.5, -1.0)));
    Cylinder::from_mitsuba(Vec3::new(0.0, 0.0, -0.5), Vec3::new(0.0, 0.0, 1.0), 0.4, &t, false).unwrap().0
}

/// A triangle light with vertex texture coordinates of its own.
fn triangle_light() -> Light {
    let texture = checker()
        .map(|t| EmissionTexture { vertex_uv: [Vec2::new(0.1, 0.2), Vec2::new(0.9, 0.3), Vec2::new(0.4, 1.0)], ..t });
    Light::Area { shape: Shape::Triangle(triangle()), radiance: Color::new(1.5, 1.0, 0.5), texture }
}

#[test]
fn area_light_directions_follow_pdf_le() {
    let mut outcomes = Outcomes::default();
    let world = Frame { x: Vec3::X, y: Vec3::Y, z: Vec3::Z };
    // Flat shapes: one normal, so the directions are tested as they leave, in world space.
    let (q, t, d) = (quad(), triangle(), disk());
    let t_normal = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]).normalize();
    let flat = [
        ("quad", area_light(Shape::Quad(q)), q.p0, q.n),
        ("triangle", triangle_light(), t.p[0], t_normal),
        ("disk", area_light(Shape::Disk(d)), d.center, d.n),
    ];
    for (seed, (name, light, origin, n)) in flat.into_iter().enumerate() {
        let (to_grid, density) = in_frame(&light, world, origin, n);
        chi2_ray_directions(&mut outcomes, name, &light, &config(18, 36), 10 + seed as u64, to_grid, density);
    }
    // Curved shapes: each direction in a frame about its own point's normal.
    let reference = Vec3::new(0.36, 0.48, 0.8);
    let (s, c) = (sphere(), cylinder());
    let curved = [
        ("sphere", area_light(Shape::Sphere(s)), s.center + Vec3::Z * s.radius, Vec3::Z),
        ("cylinder", area_light(Shape::Cylinder(c)), c.p0 + c.x * c.radius, c.x),
    ];
    for (seed, (name, light, origin, n)) in curved.into_iter().enumerate() {
        let local = Frame::from_z_x(n, reference);
        chi2_ray_directions(
            &mut outcomes,
            name,
            &light,
            &config(18, 36),
            20 + seed as u64,
            |s| Frame::from_z_x(s.n, reference).to_local(s.ray.d),
            |w| light.pdf_le(&Ray::new(origin, local.to_world(w)), n).1,
        );
    }
    outcomes.finish();
}

/// Four-point Gauss-Legendre rule over [x0, x1] x [y0, y1]: exact for the constant and smooth
/// densities integrated here over cells whose edges lie on their jumps.
fn gauss2(f: impl Fn(f64, f64) -> f64, (x0, x1): (f64, f64), (y0, y1): (f64, f64)) -> f64 {
    const NODES: [(f64, f64); 4] = [
        (-0.861_136_311_594_052_6, 0.347_854_845_137_453_8),
        (-0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
        (0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
        (0.861_136_311_594_052_6, 0.347_854_845_137_453_8),
    ];
    let (hx, hy) = (0.5 * (x1 - x0), 0.5 * (y1 - y0));
    let mut sum = 0.0;
    for (a, wa) in NODES {
        for (b, wb) in NODES {
            sum += wa * wb * f(x0 + hx * (1.0 + a), y0 + hy * (1.0 + b));
        }
    }
    sum * hx * hy
}

/// A light's position density at a point `p` of its surface with normal `n`, as pdf_le reports it.
fn pdf_pos_at(light: &Light, p: Vec3, n: Vec3) -> f64 {
    light.pdf_le(&Ray::new(p, n), n).0 as f64
}

/// Where a position test bins a sample: a cell, or off the light (a failure, with what is wrong).
enum Bin {
    Cell(usize),
    Off(String),
}

/// Chi-square of the points `light` emits from, binned by `bin` into cells laid out in rows of
/// `columns` whose probabilities are `probability`; every sample also goes through
/// `Agreement::check`.
fn chi2_ray_origins(
    outcomes: &mut Outcomes,
    name: &str,
    light: &Light,
    seed: u64,
    probability: &[f64],
    columns: usize,
    bin: impl Fn(&EmissionSample) -> Bin,
) {
    let textures = textures();
    let mut agreement = Agreement::default();
    let mut rng = Rng32::new(seed);
    let mut observed = vec![0u64; probability.len()];
    for _ in 0..SAMPLES {
        let Some(s) = light.sample_le(rng.uniform2(), rng.uniform2(), &textures) else { continue };
        agreement.check(light, &s);
        match bin(&s) {
            Bin::Cell(i) => observed[i] += 1,
            Bin::Off(why) => agreement.fail(why),
        }
    }
    let config = Chi2Config { samples: SAMPLES, tests: CHI2_TESTS, ..Chi2Config::default() };
    let stats = chi2_cells(name, &observed, probability, columns, &config);
    outcomes.chi2(name, stats, &agreement);
}

/// Cell of a parameter pair in [0, 1]^2 on an nx x ny grid (rows along y), allowing rounding
/// past the edges.
fn square_cell(name: &str, (x, y): (f32, f32), (nx, ny): (usize, usize)) -> Bin {
    let slack = 1e-4;
    if !((-slack..=1.0 + slack).contains(&x) && (-slack..=1.0 + slack).contains(&y)) {
        return Bin::Off(format!("{name}: parameters ({x}, {y}) off the shape"));
    }
    let i = ((x.max(0.0) * nx as f32) as usize).min(nx - 1);
    let j = ((y.max(0.0) * ny as f32) as usize).min(ny - 1);
    Bin::Cell(j * nx + i)
}

/// (x, y) with p - o = a x + b y, for a point p in (or a hair off) the plane of a and b.
fn plane_coordinates(p: Vec3, o: Vec3, a: Vec3, b: Vec3) -> (f32, f32) {
    let (q, m) = (p - o, a.cross(b));
    let inv = 1.0 / m.length_squared();
    (m.dot(q.cross(b)) * inv, m.dot(a.cross(q)) * inv)
}

#[test]
fn area_light_points_follow_pdf_le() {
    let mut outcomes = Outcomes::default();

    // Quad: (u, v) of p0 + u e1 + v e2, area element |e1 x e2|.
    let q = quad();
    let light = area_light(Shape::Quad(q));
    let (nu, nv) = (16, 16);
    let jacobian = q.e1.cross(q.e2).length() as f64;
    let probability: Vec<f64> = (0..nu * nv)
        .map(|c| {
            let (i, j) = ((c % nu) as f64, (c / nu) as f64);
            let at = |u: f64, v: f64| pdf_pos_at(&light, q.p0 + q.e1 * u as f32 + q.e2 * v as f32, q.n) * jacobian;
            gauss2(at, (i / nu as f64, (i + 1.0) / nu as f64), (j / nv as f64, (j + 1.0) / nv as f64))
        })
        .collect();
    chi2_ray_origins(&mut outcomes, "quad points", &light, 30, &probability, nu, |s| {
        square_cell("quad", plane_coordinates(s.ray.o, q.p0, q.e1, q.e2), (nu, nv))
    });

    // Triangle: barycentrics (b1, b2) on a grid of n^2 small triangles (each square of the n x n
    // grid below the diagonal split in two; the halves beyond the diagonal are off the shape),
    // area element 2 area; each small triangle integrated by its edge midpoints.
    let t = triangle();
    let light = triangle_light();
    let n = 12;
    let (e1, e2) = (t.p[1] - t.p[0], t.p[2] - t.p[0]);
    let jacobian = e1.cross(e2).length() as f64;
    let t_normal = e1.cross(e2).normalize();
    let probability: Vec<f64> = (0..2 * n * n)
        .map(|c| {
            let (i, j, upper) = ((c / 2) % n, (c / 2) / n, c % 2 == 1);
            if i + j + usize::from(upper) >= n {
                return 0.0;
            }
            let (x, y) = (i as f64, j as f64);
            let corners = if upper {
                [(x + 1.0, y), (x + 1.0, y + 1.0), (x, y + 1.0)]
            } else {
                [(x, y), (x + 1.0, y), (x, y + 1.0)]
            };
            let at = |(b1, b2): (f64, f64)| {
                let (b1, b2) = (b1 / n as f64, b2 / n as f64);
                pdf_pos_at(&light, t.p[0] + e1 * b1 as f32 + e2 * b2 as f32, t_normal) * jacobian
            };
            let mid = |a: (f64, f64), b: (f64, f64)| ((a.0 + b.0) / 2.0, (a.1 + b.1) / 2.0);
            let [a, b, c] = corners;
            (at(mid(a, b)) + at(mid(b, c)) + at(mid(c, a))) / 3.0 / (2.0 * (n * n) as f64)
        })
        .collect();
    chi2_ray_origins(&mut outcomes, "triangle points", &light, 31, &probability, 2 * n, |s| {
        let (b1, b2) = plane_coordinates(s.ray.o, t.p[0], e1, e2);
        let slack = 1e-4;
        if !(b1 >= -slack && b2 >= -slack && b1 + b2 <= 1.0 + slack) {
            return Bin::Off(format!("triangle: barycentrics ({b1}, {b2}) off the shape"));
        }
        // Points a rounding error past the long edge go back onto it.
        let sum = (b1 + b2).max(1.0);
        let (x, y) = (b1.max(0.0) / sum * n as f32, b2.max(0.0) / sum * n as f32);
        let (i, j) = ((x as usize).min(n - 1), (y as usize).min(n - 1));
        let upper = x - i as f32 + y - j as f32 >= 1.0 && i + j + 1 < n;
        Bin::Cell(2 * (j * n + i) + usize::from(upper))
    });

    // Sphere: its own (u, v) = (phi / 2 pi, theta / pi) in its turned frame, area element
    // 2 pi^2 r^2 sin(pi v).
    let s = sphere();
    let light = area_light(Shape::Sphere(s));
    let to_world = glam::Quat::from_array(s.to_local).inverse();
    let (nu, nv) = (32, 16);
    let r2 = (s.radius * s.radius) as f64;
    let probability: Vec<f64> = (0..nu * nv)
        .map(|c| {
            let (i, j) = ((c % nu) as f64, (c / nu) as f64);
            let at = |u: f64, v: f64| {
                let (sin_t, cos_t) = (std::f64::consts::PI * v).sin_cos();
                let (sin_p, cos_p) = (TAU_64 * u).sin_cos();
                let n = to_world * Vec3::new((sin_t * cos_p) as f32, (sin_t * sin_p) as f32, cos_t as f32);
                pdf_pos_at(&light, s.center + n * s.radius, n) * r2 * 2.0 * std::f64::consts::PI.powi(2) * sin_t
            };
            gauss2(at, (i / nu as f64, (i + 1.0) / nu as f64), (j / nv as f64, (j + 1.0) / nv as f64))
        })
        .collect();
    chi2_ray_origins(&mut outcomes, "sphere points", &light, 32, &probability, nu, |e| {
        let v = e.ray.o - s.center;
        if (v.length() - s.radius).abs() > 1e-4 * s.radius {
            return Bin::Off(format!("sphere: point {} at {} from the centre", e.ray.o, v.length()));
        }
        let uv = s.param(v.normalize()).uv();
        square_cell("sphere", (uv.x, uv.y), (nu, nv))
    });

    // Disk: (r^2, phi) of the point in the local unit disk, area element |a x b| / 2 d(r^2) dphi.
    let d = disk();
    let light = area_light(Shape::Disk(d));
    let (nr, nphi) = (12, 24);
    let jacobian = 0.5 * d.a.cross(d.b).length() as f64;
    let probability: Vec<f64> = (0..nr * nphi)
        .map(|c| {
            let (i, j) = ((c % nphi) as f64, (c / nphi) as f64);
            let at = |phi: f64, r2: f64| {
                let r = r2.sqrt();
                let p = d.center + d.a * (r * phi.cos()) as f32 + d.b * (r * phi.sin()) as f32;
                pdf_pos_at(&light, p, d.n) * jacobian
            };
            gauss2(
                at,
                (i * TAU_64 / nphi as f64, (i + 1.0) * TAU_64 / nphi as f64),
                (j / nr as f64, (j + 1.0) / nr as f64),
            )
        })
        .collect();
    chi2_ray_origins(&mut outcomes, "disk points", &light, 33, &probability, nphi, |s| {
        let (x, y) = plane_coordinates(s.ray.o, d.center, d.a, d.b);
        let phi = y.atan2(x).rem_euclid(std::f32::consts::TAU);
        square_cell("disk", (phi / std::f32::consts::TAU, x * x + y * y), (nphi, nr))
    });

    // Cylinder: (phi / 2 pi, height) about its axis, area element 2 pi r length.
    let c = cylinder();
    let light = area_light(Shape::Cylinder(c));
    let y = c.axis.normalize().cross(c.x);
    let (nu, nv) = (24, 10);
    let jacobian = (TAU_64 * c.radius as f64) * c.axis.length() as f64;
    let probability: Vec<f64> = (0..nu * nv)
        .map(|k| {
            let (i, j) = ((k % nu) as f64, (k / nu) as f64);
            let at = |u: f64, v: f64| {
                let (sin, cos) = (TAU_64 * u).sin_cos();
                let n = c.x * cos as f32 + y * sin as f32;
                pdf_pos_at(&light, c.p0 + c.axis * v as f32 + n * c.radius, n) * jacobian
            };
            gauss2(at, (i / nu as f64, (i + 1.0) / nu as f64), (j / nv as f64, (j + 1.0) / nv as f64))
        })
        .collect();
    chi2_ray_origins(&mut outcomes, "cylinder points", &light, 34, &probability, nu, |s| {
        let w = s.ray.o - c.p0;
        let v = w.dot(c.axis) / c.axis.length_squared();
        let radial = w - c.axis * v;
        if (radial.length() - c.radius).abs() > 1e-4 * c.radius {
            return Bin::Off(format!("cylinder: point {} at {} from the axis", s.ray.o, radial.length()));
        }
        let phi = radial.dot(y).atan2(radial.dot(c.x)).rem_euclid(std::f32::consts::TAU);
        square_cell("cylinder", (phi / std::f32::consts::TAU, v), (nu, nv))
    });
    outcomes.finish();
}

/// A W x H map: a soft gradient, a dark band, and a small very bright "sun" (as the environment
/// tests make theirs).
fn env_texels(w: u32, h: u32) -> Vec<Color> {
    let mut t = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let (fx, fy) = (x as f32 / w as f32, y as f32 / h as f32);
            let mut c = Color::new(0.2 + fx, 0.5 * (1.0 - fy), 0.1 + fy * fy);
            if y == h / 2 {
                c *= 0.0;
            }
            if (x, y) == (w / 3, h / 4) {
                c = Color::new(400.0, 300.0, 200.0);
            }
            t.push(c);
        }
    }
    t
}

/// The environments: a constant one entering through a core-only disk, and a map in a turned
/// frame entering through an extended disk.
fn environments() -> [(&'static str, Environment); 2] {
    let mut constant = Environment::constant(Color::new(0.7, 0.8, 0.9));
    constant.disk = PhotonDisk::new(Vec3::new(0.5, 0.5, -1.0), 2.0, false);
    let frame = Frame::from_z_x(Vec3::new(0.3, 0.8, -0.5).normalize(), Vec3::new(1.0, -0.2, 0.1));
    let mut map = Environment::map(EnvMap::shared(32, 17, env_texels(32, 17)).unwrap(), 1.5, frame);
    map.disk = PhotonDisk::new(Vec3::new(-1.0, 0.5, 2.0), 1.0, true);
    [("constant environment", constant), ("environment map", map)]
}

#[test]
fn environment_directions_follow_pdf_le() {
    let mut outcomes = Outcomes::default();
    for (seed, (name, e)) in environments().into_iter().enumerate() {
        let light = Light::Environment(e);
        // The grid's pole on the map's (its y axis, where the density has its 1 / sin theta
        // poles), turned 17 degrees about it off the map's columns; rows end on the map's.
        let (s, c) = 17f32.to_radians().sin_cos();
        let grid = Frame::from_z_x(e.frame.y, e.frame.z * c + e.frame.x * s);
        let (to_grid, density) = in_frame(&light, grid, e.disk.center, Vec3::Z);
        chi2_ray_directions(&mut outcomes, name, &light, &config(32, 32), 40 + seed as u64, to_grid, density);
    }
    outcomes.finish();
}

/// Cells of a photon disk's plane: rings between `edges` (the last one reaching to infinity, where
/// the density must be 0: integrated out to twice its inner edge) times `sectors` sectors, and
/// their probabilities from `light`'s pdf_le for rays along `d` (rays cross the disk where they
/// pass its centre's perpendicular plane).
fn disk_cells(light: &Light, disk: &PhotonDisk, d: Vec3, edges: &[f32], sectors: usize) -> Vec<f64> {
    let frame = Frame::from_z_x(d, Vec3::new(0.36, 0.48, 0.8));
    let mut probability = Vec::new();
    for ring in 0..edges.len() {
        let r0 = edges[ring] as f64;
        let r1 = edges.get(ring + 1).map_or(2.0 * r0, |&r| r as f64);
        for k in 0..sectors {
            let at = |rho: f64, phi: f64| {
                let q = disk.center + (frame.x * phi.cos() as f32 + frame.y * phi.sin() as f32) * rho as f32;
                // A ray along d through q, starting well before the disk's plane.
                light.pdf_le(&Ray::new(q - d * (3.0 * disk.reach), d), d).0 as f64 * rho
            };
            let step = TAU_64 / sectors as f64;
            probability.push(gauss2(at, (r0, r1), (k as f64 * step, (k + 1) as f64 * step)));
        }
    }
    probability
}

/// The ring edges of a disk: uniform in rho^2 over the core, uniform in ln rho out to its reach,
/// then a few rings beyond.
fn ring_edges(disk: &PhotonDisk) -> Vec<f32> {
    let r = disk.radius;
    let mut edges: Vec<f32> = (0..16).map(|k| r * (k as f32 / 16.0).sqrt()).collect();
    if disk.reach > r * 1.0001 {
        edges.extend((0..24).map(|k| r * (disk.reach / r).powf(k as f32 / 24.0)));
    }
    edges.extend((0..4).map(|k| disk.reach * (1.0 + 0.05 * k as f32)));
    edges
}

/// Chi-square of where the rays of a light at infinity cross its photon disk, in `disk_cells`.
fn chi2_disk_crossings(outcomes: &mut Outcomes, name: &str, light: &Light, disk: PhotonDisk, d: Vec3, seed: u64) {
    let sectors = 24;
    let edges = ring_edges(&disk);
    let probability = disk_cells(light, &disk, d, &edges, sectors);
    chi2_ray_origins(outcomes, name, light, seed, &probability, sectors, |s| {
        let d = s.ray.d;
        let v = s.ray.o - disk.center;
        let off = v - d * v.dot(d);
        let frame = Frame::from_z_x(d, Vec3::new(0.36, 0.48, 0.8));
        let rho = off.length();
        let phi = off.dot(frame.y).atan2(off.dot(frame.x)).rem_euclid(std::f32::consts::TAU);
        let ring = edges.partition_point(|&e| e <= rho).max(1) - 1;
        let sector = ((phi / std::f32::consts::TAU * sectors as f32) as usize).min(sectors - 1);
        Bin::Cell(ring * sectors + sector)
    });
}

#[test]
fn photon_disk_points_follow_pdf_le() {
    let mut outcomes = Outcomes::default();
    // Directional lights: a core-only disk, and one extended to 32 radii (scenes with planes).
    let cases = [
        ("directional, core disk", Vec3::new(0.3, -1.0, 0.2), PhotonDisk::new(Vec3::new(1.0, -2.0, 0.5), 3.0, false)),
        (
            "directional, extended disk",
            Vec3::new(-0.6, -0.7, 0.4),
            PhotonDisk::new(Vec3::new(1.0, -2.0, 0.5), 0.5, true),
        ),
    ];
    for (seed, (name, direction, disk)) in cases.into_iter().enumerate() {
        let direction = direction.normalize();
        let light = Light::Directional { direction, irradiance: Color::new(2.0, 1.5, 1.0), disk };
        chi2_disk_crossings(&mut outcomes, name, &light, disk, direction, 50 + seed as u64);
    }
    // Environments: the constant one through a core-only disk, the map through an extended one.
    for (seed, (name, e)) in environments().into_iter().enumerate() {
        let light = Light::Environment(e);
        let name = format!("{name} disk points");
        chi2_disk_crossings(
            &mut outcomes,
            &name,
            &light,
            e.disk,
            Vec3::new(0.2, 0.3, -0.9).normalize(),
            60 + seed as u64,
        );
    }
    outcomes.finish();
}
