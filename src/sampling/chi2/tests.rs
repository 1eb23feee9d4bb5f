use super::*;
use std::f32::consts::{FRAC_1_PI, FRAC_PI_2, FRAC_PI_4, PI as PI_F32, TAU as TAU_F32};

/// Number of tests below that are expected to pass, for the Sidak correction.
const PASSING_TESTS: usize = 7;

fn config(samples: usize, seed: u64) -> Chi2Config {
    Chi2Config { samples, seed, tests: PASSING_TESTS, ..Chi2Config::default() }
}

fn uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = TAU_F32 * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Shirley-Chiu concentric map of the unit square onto the unit disk.
fn concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o == Vec2::ZERO {
        return Vec2::ZERO;
    }
    let (r, angle) =
        if o.x.abs() > o.y.abs() { (o.x, FRAC_PI_4 * (o.y / o.x)) } else { (o.y, FRAC_PI_2 - FRAC_PI_4 * (o.x / o.y)) };
    r * Vec2::new(angle.cos(), angle.sin())
}

/// Malley's method: project a uniform disk sample up onto the hemisphere.
fn cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

fn cosine_pdf(w: Vec3) -> f32 {
    if w.z > 0.0 { w.z * FRAC_1_PI } else { 0.0 }
}

/// Samples the density proportional to cos^n around +z over the upper hemisphere.
fn power_cosine(u: Vec2, n: f32) -> Vec3 {
    let cos_theta = u.x.powf(1.0 / (n + 1.0));
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let phi = TAU_F32 * u.y;
    Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta)
}

fn power_cosine_pdf(w: Vec3, n: f32) -> f32 {
    if w.z > 0.0 { (n + 1.0) / TAU_F32 * w.z.powf(n) } else { 0.0 }
}

#[test]
fn uniform_sphere_passes() {
    let stats = chi2_directions(
        "uniform sphere",
        |u, _| Some(uniform_sphere(u)),
        |_| 1.0 / (4.0 * PI_F32),
        &config(1_000_000, 1),
    );
    let stats = stats.unwrap_or_else(|report| panic!("{report}"));
    assert_eq!(stats.dof, 199);
    assert_eq!(stats.cells_pooled, 0);
    assert!((stats.pdf_integral - 1.0).abs() < 1e-6, "{stats:?}");
}

#[test]
fn cosine_hemisphere_passes() {
    let stats =
        chi2_directions("cosine hemisphere", |u, _| Some(cosine_hemisphere(u)), cosine_pdf, &config(1_000_000, 2));
    let stats = stats.unwrap_or_else(|report| panic!("{report}"));
    assert!((stats.pdf_integral - 1.0).abs() < 1e-6, "{stats:?}");
    // The 100 cells of the upper hemisphere count; the lower ones have zero density and are left out.
    assert_eq!(stats.dof, 99, "{stats:?}");
}

#[test]
fn cosine_samples_against_uniform_hemisphere_pdf_fail() {
    let uniform_hemisphere_pdf = |w: Vec3| if w.z > 0.0 { 1.0 / TAU_F32 } else { 0.0 };
    let result = chi2_directions(
        "cosine vs uniform hemisphere",
        |u, _| Some(cosine_hemisphere(u)),
        uniform_hemisphere_pdf,
        &config(100_000, 3),
    );
    let report = result.expect_err("a wrong pdf must fail");
    assert!(report.contains("cosine vs uniform hemisphere"), "{report}");
    assert!(report.contains("p-value"), "{report}");
    assert!(report.contains("residuals"), "{report}");
}

#[test]
fn slightly_wrong_exponent_fails() {
    let result = chi2_directions(
        "cos^1.1 samples vs cosine pdf",
        |u, _| Some(power_cosine(u, 1.1)),
        cosine_pdf,
        &config(1_000_000, 4),
    );
    let report = result.expect_err("a slightly wrong sampler must fail");
    assert!(report.contains("failed: p-value"), "{report}");
}

#[test]
fn phong_lobe_passes() {
    let n = 20.0;
    let stats = chi2_directions(
        "phong lobe n = 20",
        |u, _| Some(power_cosine(u, n)),
        |w| power_cosine_pdf(w, n),
        &config(1_000_000, 5),
    );
    let stats = stats.unwrap_or_else(|report| panic!("{report}"));
    assert!((stats.pdf_integral - 1.0).abs() < 1e-5, "{stats:?}");
    // Most cells of the lobe's tail hold almost nothing, so pooling must have happened.
    assert!(stats.cells_pooled > 0, "{stats:?}");
}

#[test]
fn incomplete_gamma_known_values() {
    // Critical values of the chi-square distribution at the 5 % level.
    assert!((chi2_p_value(3.841, 1) - 0.05).abs() < 1e-3);
    assert!((chi2_p_value(18.307, 10) - 0.05).abs() < 1e-3);
    assert!((chi2_p_value(6.635, 1) - 0.01).abs() < 1e-4);
    assert!((chi2_p_value(124.342, 100) - 0.05).abs() < 1e-4);
    // With 2 degrees of freedom the chi-square survival function is exactly exp(-x / 2); the points cover both
    // the series and the continued-fraction branch.
    for x in [1e-6_f64, 0.1, 0.5, 1.0, 1.999, 2.0, 2.001, 3.0, 10.0, 50.0] {
        let expected = (-0.5 * x).exp();
        assert!((chi2_p_value(x, 2) - expected).abs() < 1e-9, "x = {x}");
    }
    // With 1 degree of freedom Q(1/2, x) = erfc(sqrt(x)); erfc(1) = 0.157299207050285...
    assert!((gamma_q(0.5, 1.0) - 0.157_299_207_050_285_13).abs() < 1e-12);
    assert_eq!(chi2_p_value(0.0, 5), 1.0);
    assert!(chi2_p_value(1e4, 5) < 1e-300);
    // ln Gamma at integers is ln((n - 1)!), and Gamma(1/2) = sqrt(pi).
    assert!((ln_gamma(10.0) - 362_880f64.ln()).abs() < 1e-12);
    assert!((ln_gamma(0.5) - PI.sqrt().ln()).abs() < 1e-12);
    assert!((ln_gamma(0.25) - 3.625_609_908_221_908_f64.ln()).abs() < 1e-12);
}

#[test]
fn sidak_correction() {
    assert!((sidak_alpha(0.01, 1) - 0.01).abs() < 1e-15);
    let alpha = sidak_alpha(0.01, 10);
    assert!((1.0 - (1.0 - alpha).powi(10) - 0.01).abs() < 1e-12);
    assert!(alpha < 0.01 / 9.0 && alpha > 0.01 / 10.0);
}

#[test]
fn failed_samples_count_as_missing_mass() {
    // Half of the samples fail and the pdf integrates to one half: consistent, so the test passes.
    let stats = chi2_directions(
        "half-failing uniform sphere",
        |u, u1| (u1 < 0.5).then(|| uniform_sphere(u)),
        |_| 0.5 / (4.0 * PI_F32),
        &config(200_000, 6),
    );
    let stats = stats.unwrap_or_else(|report| panic!("{report}"));
    assert!((stats.pdf_integral - 0.5).abs() < 1e-6, "{stats:?}");
}

#[test]
fn pdf_integrating_above_one_fails() {
    let result =
        chi2_directions("overweight", |u, _| Some(uniform_sphere(u)), |_| 1.1 / (4.0 * PI_F32), &config(1_000, 7));
    let report = result.expect_err("a pdf integrating to 1.1 must fail");
    assert!(report.contains("1.100000"), "{report}");
}

#[test]
fn samples_where_pdf_is_zero_fail() {
    // Uniform sphere samples against the cosine pdf: the lower hemisphere has zero density.
    let result = chi2_directions("zero density", |u, _| Some(uniform_sphere(u)), cosine_pdf, &config(1_000, 8));
    let report = result.expect_err("samples in zero-density cells must fail");
    assert!(report.contains("zero density") && report.contains("theta row"), "{report}");
}

/// A cosine sampler that returns a direction on the equator, where the cosine pdf is zero, for its first
/// `edge_samples` calls, as f32 rounding makes real samplers do now and then.
fn cosine_with_edge_samples(edge_samples: usize) -> impl FnMut(Vec2, f32) -> Option<Vec3> {
    let mut calls = 0;
    move |u, _| {
        calls += 1;
        Some(if calls <= edge_samples { Vec3::X } else { cosine_hemisphere(u) })
    }
}

#[test]
fn a_rare_sample_on_the_edge_of_the_support_is_tolerated() {
    let result = chi2_directions("one edge sample", cosine_with_edge_samples(1), cosine_pdf, &config(100_000, 10));
    result.unwrap_or_else(|report| panic!("{report}"));
    let result = chi2_directions("two edge samples", cosine_with_edge_samples(2), cosine_pdf, &config(100_000, 10));
    let report = result.expect_err("two samples of zero density in 1e5 must fail");
    assert!(report.contains("at most 1 tolerated"), "{report}");
}

#[test]
fn non_unit_directions_fail() {
    let result =
        chi2_directions("not normalized", |u, _| Some(2.0 * uniform_sphere(u)), |_| 0.25 * FRAC_1_PI, &config(10, 9));
    let report = result.expect_err("non-unit directions must fail");
    assert!(report.contains("unit directions"), "{report}");
    let result =
        chi2_directions("nan", |_, _| Some(Vec3::new(f32::NAN, 0.0, 1.0)), |_| 0.25 * FRAC_1_PI, &config(10, 9));
    assert!(result.is_err());
}

#[test]
fn same_seed_same_result() {
    let run = |seed| {
        chi2_directions("determinism", |u, _| Some(uniform_sphere(u)), |_| 0.25 * FRAC_1_PI, &config(20_000, seed))
    };
    assert_eq!(run(11), run(11));
    assert_ne!(run(11), run(12));
}

#[test]
fn cell_lookup_handles_poles_and_seam() {
    let grid = Grid { theta_res: 10, phi_res: 20 };
    assert_eq!(grid.cell_of(Vec3::Z), 0);
    // At the poles phi is arbitrary (atan2 of signed zeros may give pi), so only the row is checked.
    assert_eq!(grid.cell_of(-Vec3::Z) / 20, 9);
    // Just below the +x axis, phi is close to 2 pi and belongs to the last column.
    assert_eq!(grid.cell_of(Vec3::new(1.0, -1e-7, -0.01).normalize()), 5 * 20 + 19);
    assert_eq!(grid.cell_of(Vec3::new(-0.01, 1.0, 0.01).normalize()), 4 * 20 + 5);
}

/// Points of [0, 1)^2 with density 4 x y (each coordinate the square root of a uniform number), binned on a
/// 10 x 10 grid, row by row in y, with `keep` deciding which samples are binned at all.
fn binned_4xy(samples: usize, seed: u64, keep: impl Fn(f32) -> bool) -> Vec<u64> {
    let mut rng = Pcg32::new(seed);
    let mut observed = vec![0u64; 100];
    for _ in 0..samples {
        let (x, y, u) = (rng.next_f32().sqrt(), rng.next_f32().sqrt(), rng.next_f32());
        if keep(u) {
            observed[((y * 10.0) as usize).min(9) * 10 + ((x * 10.0) as usize).min(9)] += 1;
        }
    }
    observed
}

/// The integral of `scale` 4 x y over each cell of the 10 x 10 grid: (x1^2 - x0^2) (y1^2 - y0^2).
fn probabilities_4xy(scale: f64) -> Vec<f64> {
    let ring = |i: usize| ((i + 1) as f64 / 10.0).powi(2) - (i as f64 / 10.0).powi(2);
    (0..100).map(|c| scale * ring(c % 10) * ring(c / 10)).collect()
}

#[test]
fn binned_cells_following_their_density_pass() {
    let stats = chi2_cells("4xy", &binned_4xy(200_000, 12, |_| true), &probabilities_4xy(1.0), 10, &config(200_000, 0))
        .unwrap_or_else(|report| panic!("{report}"));
    assert_eq!(stats.dof, 99, "{stats:?}");
    assert!((stats.pdf_integral - 1.0).abs() < 1e-12, "{stats:?}");
    // Samples that fail are missing mass: a third of them, against a density integrating to two thirds.
    let observed = binned_4xy(300_000, 13, |u| u < 2.0 / 3.0);
    let stats = chi2_cells("4xy, a third missing", &observed, &probabilities_4xy(2.0 / 3.0), 10, &config(300_000, 0))
        .unwrap_or_else(|report| panic!("{report}"));
    assert!((stats.pdf_integral - 2.0 / 3.0).abs() < 1e-12, "{stats:?}");
}

#[test]
fn binned_cells_against_a_wrong_density_fail() {
    // The samples against a uniform density, against 4 x y scaled by 0.97, and against 4 x y with cells of zero
    // probability where samples fell.
    let observed = binned_4xy(200_000, 14, |_| true);
    let uniform = vec![0.01; 100];
    let report = chi2_cells("4xy vs uniform", &observed, &uniform, 10, &config(200_000, 0)).expect_err("must fail");
    assert!(report.contains("'4xy vs uniform' failed: p-value") && report.contains("residuals"), "{report}");
    let low = probabilities_4xy(0.97);
    let report = chi2_cells("4xy vs 0.97 4xy", &observed, &low, 10, &config(200_000, 0)).expect_err("must fail");
    assert!(report.contains("failed: p-value"), "{report}");
    let mut holes = probabilities_4xy(1.0);
    holes[55] = 0.0;
    let report = chi2_cells("holes", &observed, &holes, 10, &config(200_000, 0)).expect_err("must fail");
    assert!(report.contains("cell 55 (row 5, column 5)"), "{report}");
    let report =
        chi2_cells("heavy", &observed, &probabilities_4xy(1.1), 10, &config(200_000, 0)).expect_err("must fail");
    assert!(report.contains("1.100000"), "{report}");
    assert!(chi2_cells("short", &observed[..99], &uniform, 10, &config(200_000, 0)).is_err());
    assert!(chi2_cells("too many", &observed, &uniform, 10, &config(1_000, 0)).is_err());
}
