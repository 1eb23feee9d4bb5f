//! Environment light tests: Mitsuba's orientation and half-texel lookup, chi-square of the
//! importance sampling against its density (unrotated and rotated), `sample` and `pdf`
//! agreeing, the radiance integral against quadrature, photon flux averaging to the power.

use super::*;
use crate::sampling::Rng32;
use crate::sampling::chi2::{Chi2Config, chi2_directions};

/// A W x H map: a soft gradient, a dark band, and a small very bright "sun".
fn test_texels(w: u32, h: u32) -> Vec<Color> {
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

fn identity() -> Frame {
    Frame { x: Vec3::X, y: Vec3::Y, z: Vec3::Z }
}

fn env(w: u32, h: u32, frame: Frame) -> Environment {
    Environment::map(EnvMap::shared(w, h, test_texels(w, h)).unwrap(), 1.5, frame)
}

#[test]
fn orientation_and_lookup_follow_mitsuba() {
    // An 8 x 5 map whose texel (i, j) holds (i, j, 0): column i is centred at u = (i + 0.5) / 8,
    // row j lies at v = j / 4; +y is row 0, -z is u = 0, +x u = 0.25, +z u = 0.5, -x u = 0.75.
    let texels: Vec<Color> = (0..5).flat_map(|j| (0..8).map(move |i| Color::new(i as f32, j as f32, 0.0))).collect();
    let e = Environment::map(EnvMap::shared(8, 5, texels).unwrap(), 1.0, identity());
    assert_eq!(e.radiance(Vec3::Y).g(), 0.0);
    assert_eq!(e.radiance(-Vec3::Y).g(), 4.0);
    let at = |u: f32, v: f32| {
        let (theta, phi) = (v * PI, u * 2.0 * PI);
        e.radiance(Vec3::new(phi.sin() * theta.sin(), theta.cos(), -phi.cos() * theta.sin()))
    };
    for i in 0..8 {
        let c = at((i as f32 + 0.5) / 8.0, 0.5);
        assert!((c.r() - i as f32).abs() < 1e-3 && (c.g() - 2.0).abs() < 1e-3, "column {i}: {c}");
    }
    // Half way between columns 7 and 0 (the periodic seam), and between rows.
    assert!((at(0.0, 0.5).r() - 3.5).abs() < 1e-3);
    assert!((at(0.5 / 8.0, 0.125).g() - 0.5).abs() < 1e-3);
    // The axes: u = 0.25 is +x (column 1.5 there), u = 0.5 is +z, u = 0.75 is -x.
    assert!((e.radiance(Vec3::X).r() - 1.5).abs() < 1e-3);
    assert!((e.radiance(Vec3::Z).r() - 3.5).abs() < 1e-3);
    assert!((e.radiance(-Vec3::X).r() - 5.5).abs() < 1e-3);
    // A rotated frame looks the map up in its own axes.
    let turned = Environment { frame: Frame { x: Vec3::Z, y: Vec3::Y, z: -Vec3::X }, ..e };
    assert!((turned.radiance(Vec3::Z).r() - e.radiance(Vec3::X).r()).abs() < 1e-4);
    // Maps that are too small, or hold NaN, are refused.
    assert!(EnvMap::new(2, 2, vec![Color::ONE; 4]).is_err());
    assert!(EnvMap::new(2, 3, vec![Color::splat(f32::NAN); 6]).is_err());
}

#[test]
fn identical_images_share_one_map() {
    let a = EnvMap::shared(6, 4, test_texels(6, 4)).unwrap();
    let b = EnvMap::shared(6, 4, test_texels(6, 4)).unwrap();
    assert!(std::ptr::eq(a, b));
    let mut other = test_texels(6, 4);
    other[3] *= 2.0;
    assert!(!std::ptr::eq(a, EnvMap::shared(6, 4, other).unwrap()));
}

#[test]
fn sampling_matches_its_density_by_chi_square() {
    // The density grows as 1 / sin theta towards the map's poles (integrably): the test's grid
    // has its poles on z, so the maps are turned to have theirs there too (the map's +y up
    // along z), then turned about z by 40 degrees.
    let z_up = Frame { x: Vec3::X, y: Vec3::Z, z: -Vec3::Y };
    let (s, c) = 40f32.to_radians().sin_cos();
    let x = Vec3::new(c, s, 0.0);
    let turned = Frame { x, y: Vec3::Z, z: x.cross(Vec3::Z) };
    let cases = [
        ("envmap", env(32, 17, z_up)),
        ("envmap turned", env(32, 17, turned)),
        ("envmap small", env(3, 3, z_up)),
        ("constant", Environment::constant(Color::splat(0.7))),
    ];
    let config = Chi2Config { tests: cases.len(), ..Chi2Config::with_theta_res(24) };
    for (name, e) in cases {
        let stats = chi2_directions(name, |u, _| e.sample(u).map(|s| s.0), |w| e.pdf(w), &config)
            .unwrap_or_else(|report| panic!("{report}"));
        assert!((stats.pdf_integral - 1.0).abs() < 2e-3, "{name}: pdf integrates to {}", stats.pdf_integral);
    }
}

#[test]
fn sample_pdf_and_radiance_agree_with_pdf_and_radiance() {
    let e = env(64, 33, Frame::from_z(Vec3::new(-0.2, 0.9, 0.1).normalize()));
    let mut rng = Rng32::new(21);
    for _ in 0..20_000 {
        let Some((wi, l, pdf)) = e.sample(rng.uniform2()) else { continue };
        assert!((wi.length() - 1.0).abs() < 1e-5);
        let p = e.pdf(wi);
        assert!((pdf - p).abs() <= 2e-3 * pdf, "sample pdf {pdf} vs pdf {p} at {wi}");
        assert_eq!(l, e.radiance(wi));
        // Radiance is positive wherever sampling goes, and the density positive wherever
        // there is radiance (checked the other way below).
        assert!(luminance(l) > 0.0);
    }
    for _ in 0..20_000 {
        let wi = uniform_sphere(rng.uniform2());
        if luminance(e.radiance(wi)) > 0.0 {
            assert!(e.pdf(wi) > 0.0, "radiance {} at {wi} but density 0", e.radiance(wi));
        }
    }
}

#[test]
fn radiance_integral_matches_quadrature_and_monte_carlo() {
    let e = env(24, 13, identity());
    // Estimate the integral of L over the sphere by importance sampling: E[L / pdf].
    let mut rng = Rng32::new(2);
    let n = 400_000;
    let mut sum = Color::ZERO;
    for _ in 0..n {
        if let Some((_, l, pdf)) = e.sample(rng.uniform2()) {
            sum += l / pdf;
        }
    }
    let mc = sum / n as f32;
    // And by a fine uniform grid in (u, v).
    let (nu, nv) = (960, 480);
    let mut grid = Color::ZERO;
    for j in 0..nv {
        let theta = (j as f32 + 0.5) / nv as f32 * PI;
        for i in 0..nu {
            let phi = (i as f32 + 0.5) / nu as f32 * 2.0 * PI;
            let d = Vec3::new(phi.sin() * theta.sin(), theta.cos(), -phi.cos() * theta.sin());
            grid += e.radiance(d) * (theta.sin() * 2.0 * PI * PI / (nu * nv) as f32);
        }
    }
    let exact = e.integral();
    for (name, v) in [("Monte Carlo", mc), ("grid", grid)] {
        assert!((v - exact).abs().max_element() < 0.01 * exact.max_element(), "{name}: {v} vs {exact}");
    }
    let c = Environment::constant(Color::new(1.0, 2.0, 3.0));
    assert!((c.integral() - Color::new(1.0, 2.0, 3.0) * 4.0 * PI).abs().max_element() < 1e-4);
}

#[test]
fn photon_flux_averages_to_power() {
    for planes in [false, true] {
        for mut e in [env(16, 9, identity()), Environment::constant(Color::new(0.5, 1.0, 2.0))] {
            e.disk = PhotonDisk::new(Vec3::new(1.0, 0.0, -2.0), 1.5, planes);
            let mut rng = Rng32::new(13);
            let n = 400_000;
            let mut sum = Color::ZERO;
            for _ in 0..n {
                if let Some(p) = e.sample_le(rng.uniform2(), rng.uniform2()) {
                    assert!((p.ray.d.length() - 1.0).abs() < 1e-5 && p.flux.is_finite());
                    sum += p.flux;
                }
            }
            let mean = sum / n as f32;
            let power = e.power();
            // The flux of the sun's photons varies a lot: 2% on the brightest channel.
            assert!((mean - power).abs().max_element() < 0.02 * power.max_element(), "{mean} vs {power}");
        }
    }
}
