//! Tests of the microfacet distributions: D and the visible normals integrate to one (by
//! quadrature), the weak white furnace, chi-square tests of both samplers against their densities,
//! agreement with vectors from Mitsuba 3.9.1 (`scripts/microfacet_vectors.py`), convergence of the
//! Beckmann inversion, Smith's Λ, and erf / erfinv against values from mpmath.

use super::erf::{FRAC_1_SQRT_PI, erf, erfc, erfinv};
use super::*;
use crate::sampling::Rng32;
use crate::sampling::chi2::{Chi2Config, chi2_directions};
use std::f64::consts::TAU as TAU_F64;

mod mitsuba_vectors;

use mitsuba_vectors::VECTORS;

const DISTRIBUTIONS: [Distribution; 2] = [Distribution::Beckmann, Distribution::Ggx];

/// Roughness pairs (alpha_u, alpha_v) from 0.05 to 1, isotropic and anisotropic both ways.
const ALPHAS: [(f32, f32); 8] =
    [(0.05, 0.05), (0.1, 0.1), (0.3, 0.3), (0.6, 0.6), (1.0, 1.0), (0.05, 0.5), (1.0, 0.2), (0.3, 0.08)];

/// The unit direction at polar angle `theta` and azimuth `phi`, in degrees.
fn direction(theta: f32, phi: f32) -> Vec3 {
    let (theta, phi) = (f64::from(theta).to_radians(), f64::from(phi).to_radians());
    Vec3::new((theta.sin() * phi.cos()) as f32, (theta.sin() * phi.sin()) as f32, theta.cos() as f32)
}

/// Incident directions for the integrals: normal, oblique and grazing, at assorted azimuths.
fn incident_directions() -> [Vec3; 5] {
    [direction(0.0, 0.0), direction(30.0, 20.0), direction(60.0, 135.0), direction(80.0, -60.0), direction(89.0, 200.0)]
}

/// ∫ f(m) dω over the upper hemisphere by the trapezoidal rule in v = ln tan θ (step `step`) and
/// in φ (`phi_steps` points). With τ = tan θ = e^v, dω = τ² (1 + τ²)^(-3/2) dv dφ: a peak at
/// tan θ ~ α gets as many points for α = 0.05 as for α = 1, and the integrands here fall off
/// exponentially in v at both ends (as τ² below the peak, as 1/τ or faster above), where the
/// rule converges geometrically for smooth integrands (as step² across kinks, such as wi·m = 0).
fn hemisphere_integral(f: impl Fn(Vec3) -> f64, alpha_min: f32, alpha_max: f32, step: f64, phi_steps: usize) -> f64 {
    let (v0, v1) = (f64::from(alpha_min).ln() - 16.0, f64::from(alpha_max).ln() + 32.0);
    let n_v = ((v1 - v0) / step).ceil() as usize;
    let h = (v1 - v0) / n_v as f64;
    let dphi = TAU_F64 / phi_steps as f64;
    let azimuths: Vec<(f64, f64)> = (0..phi_steps).map(|j| ((j as f64 + 0.5) * dphi).sin_cos()).collect();
    let mut total = 0.0;
    for i in 0..=n_v {
        let tau = (v0 + i as f64 * h).exp();
        let cos_theta = 1.0 / (1.0 + tau * tau).sqrt();
        let sin_theta = tau * cos_theta;
        let ring: f64 = azimuths
            .iter()
            .map(|&(sin_phi, cos_phi)| {
                f(Vec3::new((sin_theta * cos_phi) as f32, (sin_theta * sin_phi) as f32, cos_theta as f32))
            })
            .sum();
        total += tau * tau * cos_theta.powi(3) * ring;
    }
    total * h * dphi
}

/// The exact Smith Λ of the Beckmann distribution, (erf(a) - 1) / 2 + exp(-a²) / (2 a sqrt(pi))
/// with a = 1 / (α tan θ) (Walter et al. 2007; Heitz 2014, "Understanding the masking-shadowing
/// function in microfacet-based BRDFs").
fn beckmann_lambda_exact(mf: &Microfacet, v: Vec3) -> f64 {
    let (x, y) = (f64::from(mf.alpha_u * v.x), f64::from(mf.alpha_v * v.y));
    let a = f64::from(v.z).abs() / (x * x + y * y).sqrt();
    if a.is_infinite() {
        return 0.0;
    }
    -0.5 * erfc(a) + (-a * a).exp() / (2.0 * a) * FRAC_1_SQRT_PI
}

/// What ∫ D(m) G1(v, m) max(0, v·m) dm / cos θv comes to: 1 for GGX, whose G1 is exactly
/// 1 / (1 + Λ); for Beckmann, Mitsuba's fitted G1 times the exact 1 + Λ, since ∫ D max(0, v·m) dm
/// = cos θv (1 + Λ(v)) by the definition of Λ.
fn projected_area_ratio(mf: &Microfacet, v: Vec3) -> f64 {
    match mf.distribution {
        Distribution::Ggx => 1.0,
        Distribution::Beckmann => f64::from(mf.g1(v, Vec3::Z)) * (1.0 + beckmann_lambda_exact(mf, v)),
    }
}

#[test]
fn d_cos_integrates_to_one() {
    for distribution in DISTRIBUTIONS {
        for (alpha_u, alpha_v) in ALPHAS {
            let mf = Microfacet::new(distribution, alpha_u, alpha_v);
            let integral = hemisphere_integral(
                |m| f64::from(mf.d(m)) * f64::from(m.z),
                alpha_u.min(alpha_v),
                alpha_u.max(alpha_v),
                0.02,
                1024,
            );
            assert!((integral - 1.0).abs() < 1e-5, "∫ D cos θm dω = {integral} for {mf:?}");
            // pdf_all is the same density.
            let integral = hemisphere_integral(|m| f64::from(mf.pdf_all(m)), alpha_u.min(alpha_v), 1.0, 0.02, 1024);
            assert!((integral - 1.0).abs() < 1e-5, "∫ pdf_all dω = {integral} for {mf:?}");
        }
    }
}

/// Roughness pairs for the integrals over visible normals (five incident directions each).
const VISIBLE_ALPHAS: [(f32, f32); 5] = [(0.1, 0.1), (0.5, 0.5), (1.0, 1.0), (0.05, 0.4), (0.8, 0.2)];

#[test]
fn visible_normals_integrate_to_one() {
    for distribution in DISTRIBUTIONS {
        for (alpha_u, alpha_v) in VISIBLE_ALPHAS {
            let mf = Microfacet::new(distribution, alpha_u, alpha_v);
            for wi in incident_directions() {
                let integral = hemisphere_integral(
                    |m| f64::from(mf.pdf_visible(wi, m)),
                    alpha_u.min(alpha_v),
                    alpha_u.max(alpha_v),
                    0.02,
                    512,
                );
                let expected = projected_area_ratio(&mf, wi);
                assert!(
                    (integral - expected).abs() < 1e-5,
                    "∫ pdf_visible dω = {integral}, expected {expected}, for {mf:?}, wi {wi}"
                );
                // Beckmann's fitted G1 keeps it within 0.35% of 1.
                assert!((integral - 1.0).abs() < 0.0035, "∫ pdf_visible dω = {integral} for {mf:?}, wi {wi}");
            }
        }
    }
}

#[test]
fn weak_white_furnace() {
    // ∫ G1(wo, m) max(0, wo·m) D(m) dm = cos θo: the projected area of the visible microfacets
    // is that of the macrosurface (Heitz 2014). Exact for GGX; Beckmann's fitted G1
    // makes it hold within the fit's 0.35%.
    for distribution in DISTRIBUTIONS {
        for (alpha_u, alpha_v) in VISIBLE_ALPHAS {
            let mf = Microfacet::new(distribution, alpha_u, alpha_v);
            for wo in incident_directions() {
                let integral = hemisphere_integral(
                    |m| f64::from(mf.g1(wo, m) * wo.dot(m).max(0.0) * mf.d(m)),
                    alpha_u.min(alpha_v),
                    alpha_u.max(alpha_v),
                    0.02,
                    512,
                );
                let cos_theta = f64::from(wo.z);
                let expected = cos_theta * projected_area_ratio(&mf, wo);
                assert!(
                    (integral - expected).abs() < 1e-5 * cos_theta,
                    "weak furnace: {integral}, expected {expected}, for {mf:?}, wo {wo}"
                );
                assert!(
                    (integral / cos_theta - 1.0).abs() < 0.0035,
                    "weak furnace: {integral} vs cos θo = {cos_theta}, for {mf:?}, wo {wo}"
                );
            }
        }
    }
}

/// Chi-square tests in this file, for the Sidak correction.
const CHI2_TESTS: usize = 32;
/// Roughness pairs for the chi-square tests: coarse enough that the (theta, phi) grid resolves them.
const CHI2_ALPHAS: [(f32, f32); 4] = [(0.25, 0.25), (0.7, 0.7), (0.1, 0.5), (0.9, 0.3)];

fn chi2_config() -> Chi2Config {
    Chi2Config { theta_res: 36, phi_res: 72, samples: 500_000, tests: CHI2_TESTS, ..Chi2Config::default() }
}

fn chi2_visible(distribution: Distribution) {
    for (alpha_u, alpha_v) in CHI2_ALPHAS {
        let mf = Microfacet::new(distribution, alpha_u, alpha_v);
        for wi in [direction(0.0, 0.0), direction(50.0, 30.0), direction(85.0, -120.0)] {
            // Beckmann's samples follow the exact visible-normal density, which is pdf_visible
            // over its integral (see `pdf_visible`); GGX's integral is 1.
            let scale = (1.0 / projected_area_ratio(&mf, wi)) as f32;
            chi2_directions(
                &format!("sample_visible {mf:?} wi {wi}"),
                |u, _| Some(mf.sample_visible(wi, u)),
                |m| mf.pdf_visible(wi, m) * scale,
                &chi2_config(),
            )
            .unwrap_or_else(|report| panic!("{report}"));
        }
    }
}

#[test]
fn beckmann_visible_sampling_matches_its_pdf() {
    chi2_visible(Distribution::Beckmann);
}

#[test]
fn ggx_visible_sampling_matches_its_pdf() {
    chi2_visible(Distribution::Ggx);
}

#[test]
fn sampling_all_normals_matches_its_pdf() {
    for distribution in DISTRIBUTIONS {
        for (alpha_u, alpha_v) in CHI2_ALPHAS {
            let mf = Microfacet::new(distribution, alpha_u, alpha_v);
            chi2_directions(
                &format!("sample_all {mf:?}"),
                |u, _| Some(mf.sample_all(u)),
                |m| mf.pdf_all(m),
                &chi2_config(),
            )
            .unwrap_or_else(|report| panic!("{report}"));
        }
    }
}

/// One case from Mitsuba 3.9.1 (see `scripts/microfacet_vectors.py` for what each field is).
struct Vector {
    distribution: Distribution,
    alpha_u: f32,
    alpha_v: f32,
    wi: [f32; 3],
    u: [f32; 2],
    m_visible: [f32; 3],
    pdf_visible: f32,
    wo: [f32; 3],
    d: f32,
    g1_wi: f32,
    g1_wo: f32,
    g: f32,
    m_all: [f32; 3],
    pdf_all: f32,
}

/// Relative agreement of values with Mitsuba's: both compute in f32, in different orders (and
/// Mitsuba with fused multiply-adds), which moves D by a few 1e-6 where its exponent is large.
const MITSUBA_VALUE_TOLERANCE: f32 = 1e-4;
/// Agreement of sampled normals with Mitsuba's, as the length of the difference of the unit vectors,
/// that is relative to |m| = 1 (per component it would be meaningless for components near 0). The
/// largest differences, 1e-5 to 1.3e-5, are at u.x = 1e-4, where Mitsuba's f32 loses digits in the
/// Beckmann inversion and in sin θm = sqrt(1 - cos² θm) (see the module notes); a wrong branch or
/// frame moves m by 1e-2 or more.
const MITSUBA_NORMAL_TOLERANCE: f32 = 1e-4;

#[test]
fn agrees_with_mitsuba() {
    let mut failures = Vec::new();
    let mut check = |case: usize, what: &str, ours: f32, theirs: f32| {
        if !((ours - theirs).abs() <= MITSUBA_VALUE_TOLERANCE * theirs.abs()) {
            failures.push(format!("case {case}: {what} = {ours}, Mitsuba {theirs}"));
        }
    };
    let mut worst_normal = 0.0f32;
    let mut normal_failures = Vec::new();
    for (case, v) in VECTORS.iter().enumerate() {
        let mf = Microfacet::new(v.distribution, v.alpha_u, v.alpha_v);
        let (wi, wo, m, m_all) = (Vec3::from(v.wi), Vec3::from(v.wo), Vec3::from(v.m_visible), Vec3::from(v.m_all));
        check(case, "d", mf.d(m), v.d);
        check(case, "g1(wi)", mf.g1(wi, m), v.g1_wi);
        check(case, "g1(wo)", mf.g1(wo, m), v.g1_wo);
        check(case, "g", mf.g(wi, wo, m), v.g);
        check(case, "pdf_visible", mf.pdf_visible(wi, m), v.pdf_visible);
        check(case, "pdf_all", mf.pdf_all(m_all), v.pdf_all);
        let u = Vec2::from(v.u);
        for (what, ours, theirs) in
            [("sample_visible", mf.sample_visible(wi, u), m), ("sample_all", mf.sample_all(u), m_all)]
        {
            let error = (ours - theirs).length();
            worst_normal = worst_normal.max(error);
            if !(error <= MITSUBA_NORMAL_TOLERANCE) {
                normal_failures.push(format!("case {case} ({mf:?}, wi {wi}, u {u}): {what} {ours}, Mitsuba {theirs}"));
            }
        }
    }
    failures.extend(normal_failures);
    assert!(failures.is_empty(), "{} disagreements with Mitsuba:\n{}", failures.len(), failures.join("\n"));
    // The vectors must exercise both the front- and back-facing branches of smith_g1.
    assert!(VECTORS.iter().any(|v| v.g1_wo == 0.0) && VECTORS.iter().any(|v| v.g1_wo > 0.0));
    println!("largest difference of a sampled normal from Mitsuba's: {worst_normal:.2e}");
}

#[test]
fn beckmann_inversion_converges_in_three_newton_steps() {
    // The visible-slope CDF of the unit-roughness Beckmann distribution seen at θ, evaluated at the
    // sampled slope, must return the (clamped) u.x. Mitsuba's three Newton steps from its initial
    // guess (exact at grazing incidence) leave at most 3e-6 of probability misplaced, near θ = 25°
    // and u.x -> 1 where the slope density vanishes at the end of its range, cot θ; in the lower
    // half of u.x, where grazing incidence puts the unknown next to -1, they converge to 4e-10.
    let (mut worst_absolute, mut worst_lower_half) = (0.0f64, 0.0f64);
    let thetas = (0..=180).map(|i| f64::from(i) * 0.5).chain([1e-3, 89.9, 89.999, 89.9999]);
    for theta in thetas {
        let (sin_theta, cos_theta) = theta.to_radians().sin_cos();
        let (tan_theta, cot_theta) = (sin_theta / cos_theta, cos_theta / sin_theta);
        let c = tan_theta * FRAC_1_SQRT_PI;
        let norm = 1.0 + erf(cot_theta) + c * (-cot_theta * cot_theta).exp();
        let uxs = (0..=200).map(|i| i as f32 / 200.0).chain([1e-6, 1e-5, 1e-4, 1e-3, 0.999, 0.9999, 0.99999]);
        for ux in uxs {
            let (slope, _) = beckmann_visible_slope_f64(cos_theta, sin_theta, Vec2::new(ux, 0.5));
            // 1 + erf(slope) as erfc(-slope): no cancellation at slopes far below 0.
            let cdf = (erfc(-slope) + c * (-slope * slope).exp()) / norm;
            let target = f64::from(ux.clamp(BECKMANN_SAMPLE_MARGIN, 1.0 - BECKMANN_SAMPLE_MARGIN));
            let absolute = (cdf - target).abs();
            worst_absolute = worst_absolute.max(absolute);
            assert!(absolute < 4e-6, "θ {theta}°, u.x {ux}: slope {slope}, CDF {cdf} != {target}");
            if ux <= 0.5 {
                let relative = absolute / target;
                worst_lower_half = worst_lower_half.max(relative);
                assert!(relative < 1e-9, "θ {theta}°, u.x {ux}: slope {slope}, CDF {cdf} != {target}");
            }
        }
    }
    println!(
        "Beckmann inversion: CDF off by at most {worst_absolute:.1e}, {worst_lower_half:.1e} relative for u.x <= 0.5"
    );
}

#[test]
fn lambda_is_the_lambda_of_g1() {
    let mut rng = Rng32::new(7);
    for distribution in DISTRIBUTIONS {
        for (alpha_u, alpha_v) in ALPHAS {
            let mf = Microfacet::new(distribution, alpha_u, alpha_v);
            for _ in 0..2000 {
                let v = crate::sampling::warp::uniform_sphere(rng.uniform2());
                let lambda = mf.lambda(v);
                assert_eq!(lambda.to_bits(), mf.lambda(-v).to_bits(), "Λ must be even");
                // +z faces v from either side: (v·z) v.z > 0.
                let g1 = mf.g1(v, Vec3::Z);
                assert!(
                    (g1 - 1.0 / (1.0 + lambda)).abs() <= 2e-6 * g1,
                    "{mf:?}, v {v}: g1 {g1} vs 1 / (1 + Λ) = {}",
                    1.0 / (1.0 + lambda)
                );
                let t = f64::from(mf.alpha_tan_2(v));
                match distribution {
                    Distribution::Ggx => {
                        let exact = 0.5 * ((1.0 + t).sqrt() - 1.0);
                        assert!((f64::from(lambda) - exact).abs() <= 1e-5 * exact.max(1e-3), "{mf:?}, v {v}");
                    }
                    Distribution::Beckmann => {
                        // The rational fit of G1 stays within its stated 0.35% of the exact one.
                        let exact = 1.0 / (1.0 + beckmann_lambda_exact(&mf, v));
                        assert!((f64::from(g1) / exact - 1.0).abs() < 0.0035, "{mf:?}, v {v}: {g1} vs {exact}");
                    }
                }
            }
            assert_eq!(mf.lambda(Vec3::X), f32::INFINITY);
            assert_eq!(mf.lambda(Vec3::Z), 0.0);
        }
    }
}

#[test]
fn basic_properties() {
    let mf = Microfacet::new(Distribution::Ggx, 0.0, -1.0);
    assert_eq!((mf.alpha_u, mf.alpha_v), (1e-4, 1e-4), "alphas clamp to 1e-4");
    assert!(mf.is_isotropic());
    assert!(!Microfacet::new(Distribution::Ggx, 0.2, 0.3).is_isotropic());
    for distribution in DISTRIBUTIONS {
        let (alpha_u, alpha_v) = (0.3, 0.7);
        let mf = Microfacet::new(distribution, alpha_u, alpha_v);
        // Both distributions peak at 1 / (pi αu αv) at the normal.
        let peak = 1.0 / (std::f32::consts::PI * alpha_u * alpha_v);
        assert!((mf.d(Vec3::Z) - peak).abs() < 1e-6 * peak);
        // Nothing below or on the horizon, and no NaN there.
        for m in [Vec3::X, -Vec3::Z, Vec3::new(0.6, 0.0, -0.8), Vec3::new(0.0, 1.0, -1e-30)] {
            assert_eq!(mf.d(m), 0.0, "{m}");
        }
        // Anisotropy: a normal tilted along x (alpha_u = 0.3) is rarer than one tilted along y.
        assert!(mf.d(direction(20.0, 0.0)) < mf.d(direction(20.0, 90.0)));
        // Back-facing microfacets and grazing directions are invisible; the normal sees everything.
        let wi = direction(40.0, 10.0);
        let m = direction(70.0, 190.0);
        assert!(wi.dot(m) < 0.0);
        assert_eq!(mf.g1(wi, m), 0.0);
        assert_eq!(mf.g1(Vec3::X, Vec3::Z), 0.0);
        assert_eq!(mf.g1(Vec3::Z, direction(30.0, 0.0)), 1.0);
        assert_eq!(mf.g(wi, Vec3::Z, Vec3::Z), mf.g1(wi, Vec3::Z));
        assert_eq!(mf.pdf_visible(-wi, Vec3::Z), 0.0);
        assert_eq!(mf.pdf_visible(Vec3::new(1.0, 0.0, 0.0), Vec3::Z), 0.0);
    }
}

#[test]
fn samples_are_finite_upward_unit_normals() {
    // Edges of the unit square (including 1, which sample generators should not produce but may)
    // and extreme roughness and incidence: no NaN, no zero vector, m.z > 0 for visible normals.
    let edges = [0.0, 1e-7, 0.25, 0.5, 0.75, 1.0 - f32::EPSILON / 2.0, 1.0];
    let wis = [Vec3::Z, direction(60.0, 33.0), Vec3::new(1.0, 0.0, 1e-6).normalize(), Vec3::new(-0.6, 0.8, 1e-30)];
    for distribution in DISTRIBUTIONS {
        for (alpha_u, alpha_v) in [(1e-4, 1e-4), (0.01, 0.5), (1.0, 1.0), (3.0, 0.2)] {
            let mf = Microfacet::new(distribution, alpha_u, alpha_v);
            for ux in edges {
                for uy in edges {
                    let u = Vec2::new(ux, uy);
                    for wi in wis {
                        let m = mf.sample_visible(wi, u);
                        assert!(
                            m.is_finite() && m.z > 0.0 && (m.length() - 1.0).abs() < 1e-5,
                            "{mf:?}: sample_visible({wi}, {u}) = {m}"
                        );
                        let pdf = mf.pdf_visible(wi, m);
                        assert!(pdf.is_finite() && pdf >= 0.0, "{mf:?}: pdf_visible({wi}, {m}) = {pdf}");
                    }
                    let m = mf.sample_all(u);
                    assert!(
                        m.is_finite() && m.z >= 0.0 && (m.length() - 1.0).abs() < 1e-5,
                        "{mf:?}: sample_all({u}) = {m}"
                    );
                    assert!(mf.pdf_all(m).is_finite());
                }
            }
        }
    }
}

/// (x, erf(x), erfc(x)), each value the f64 nearest to mpmath's (1.3.0, 40 digits), from
/// `scripts/erf_coefficients.py --test-values`.
const ERF_TABLE: [(f64, f64, f64); 28] = [
    (0.0, 0.0, 1.0),
    (1e-300, 1.1283791670955126e-300, 1.0),
    (1e-10, 1.1283791670955126e-10, 0.999999999887162),
    (1e-05, 1.1283791670579e-05, 0.9999887162083294),
    (0.001, 0.0011283787909692365, 0.9988716212090307),
    (0.1, 0.1124629160182849, 0.887537083981715),
    (0.25, 0.27632639016823696, 0.7236736098317631),
    (0.5, 0.5204998778130465, 0.4795001221869535),
    (0.75, 0.7111556336535151, 0.28884436634648486),
    (0.999, 0.8422852702064969, 0.15771472979350307),
    (1.0, 0.8427007929497149, 0.15729920705028513),
    (1.001, 0.8431154854780762, 0.15688451452192373),
    (1.5, 0.9661051464753108, 0.033894853524689274),
    (2.0, 0.9953222650189527, 0.004677734981047266),
    (2.4999, 0.9995928300996666, 0.0004071699003334514),
    (2.5, 0.999593047982555, 0.0004069520174449589),
    (3.0, 0.9999779095030014, 2.209049699858544e-05),
    (3.5, 0.9999992569016276, 7.430983723414128e-07),
    (4.5, 0.9999999998033839, 1.9661604415428876e-10),
    (5.5, 0.9999999999999927, 7.357847917974398e-15),
    (5.9, 0.9999999999999999, 7.190409783550478e-17),
    (6.0, 1.0, 2.1519736712498913e-17),
    (8.0, 1.0, 1.1224297172982926e-29),
    (15.0, 1.0, 7.212994172451207e-100),
    (26.0, 1.0, 5.663192408856143e-296),
    (-0.3, -0.3286267594591274, 1.3286267594591274),
    (-1.2, -0.9103139782296353, 1.9103139782296354),
    (-3.0, -0.9999779095030014, 1.9999779095030015),
];

/// (y, erfinv(y)), from mpmath 1.3.0 like `ERF_TABLE`; the y next to 1 are 1 - 1e-8, 1 - 1e-12,
/// the largest f64 below 1 and -(1 - 2^-40).
const ERFINV_TABLE: [(f64, f64); 15] = [
    (0.0, 0.0),
    (1e-300, 8.86226925452758e-301),
    (1e-10, 8.862269254527581e-11),
    (0.001, 0.0008862271574665521),
    (0.1, 0.08885599049425769),
    (0.5, 0.4769362762044699),
    (0.9, 1.1630871536766743),
    (0.99, 1.8213863677184494),
    (0.998, 2.1851242191330043),
    (0.9999, 2.75106390571208),
    (0.99999999, 4.052237243268763),
    (0.999999999999, 5.042031898572696),
    (0.9999999999999999, 5.8635847487551676),
    (-0.7, -0.7328690779592167),
    (-0.9999999999990905, -5.05125408524939),
];

/// Relative error of `ours` against a reference rounded to f64 (itself off by half an ulp).
fn relative_error(ours: f64, reference: f64) -> f64 {
    if ours == reference { 0.0 } else { ((ours - reference) / reference).abs() }
}

#[test]
fn erf_and_erfc_match_mpmath() {
    for (x, erf_x, erfc_x) in ERF_TABLE {
        assert!(relative_error(erf(x), erf_x) <= 3e-16, "erf({x}) = {:e}, mpmath {erf_x:e}", erf(x));
        assert!(relative_error(erfc(x), erfc_x) <= 1e-15, "erfc({x}) = {:e}, mpmath {erfc_x:e}", erfc(x));
        assert_eq!(erf(-x).to_bits(), (-erf(x)).to_bits(), "erf is odd");
    }
    assert_eq!(erf(f64::INFINITY), 1.0);
    assert_eq!(erf(f64::NEG_INFINITY), -1.0);
    assert_eq!(erfc(f64::INFINITY), 0.0);
    assert_eq!(erfc(f64::NEG_INFINITY), 2.0);
    assert_eq!(erfc(30.0), 0.0);
    assert!(erf(f64::NAN).is_nan() && erfc(f64::NAN).is_nan());
}

#[test]
fn erfinv_matches_mpmath() {
    for (y, erfinv_y) in ERFINV_TABLE {
        let ours = erfinv(y);
        assert!(relative_error(ours, erfinv_y) <= 4e-16, "erfinv({y}) = {ours:e}, mpmath {erfinv_y:e}");
        assert_eq!(erfinv(-y).to_bits(), (-ours).to_bits(), "erfinv is odd");
    }
    assert_eq!(erfinv(1.0), f64::INFINITY);
    assert_eq!(erfinv(-1.0), f64::NEG_INFINITY);
    for y in [1.0 + f64::EPSILON, -2.0, f64::INFINITY, f64::NAN] {
        assert!(erfinv(y).is_nan(), "erfinv({y})");
    }
}

/// The relative error of x as erfinv(y) implied by how far erf(x) lands from y: the miss over
/// erf'(x) x. Next to +-1 the miss is measured on the complement, erfc(|x|) against 1 - |y|,
/// which is exact there, so that the rounding of erf(x) to 1 does not hide it.
fn implied_erfinv_error(y: f64, x: f64) -> f64 {
    let miss = if y.abs() > 0.5 { erfc(x.abs()) - (1.0 - y.abs()) } else { erf(x) - y };
    let derivative = std::f64::consts::FRAC_2_SQRT_PI * (-x * x).exp();
    if miss == 0.0 { 0.0 } else { (miss / (derivative * x)).abs() }
}

#[test]
fn erf_and_erfinv_are_inverse_and_monotone() {
    // Across every piece boundary (erf at x = 1 and 2.5, erfinv at w = 6.25 and 16) and out to the
    // last f64 below 1. The bound allows erfinv's 4e-16 plus what the errors of erf and erfc add
    // to the implied error (up to about as much again near |y| = 0.5).
    let mut previous = (f64::NEG_INFINITY, f64::NEG_INFINITY);
    let mut worst = 0.0f64;
    for i in 0..=200_000 {
        let y = -1.0 + 2.0 * f64::from(i) / 200_000.0;
        let x = erfinv(y);
        if y.abs() < 1.0 && y != 0.0 {
            let error = implied_erfinv_error(y, x);
            worst = worst.max(error);
            assert!(error < 1e-15, "erfinv({y}) = {x}: implied relative error {error:e}");
        }
        assert!(x >= previous.0 && erf(x) >= previous.1, "not monotone at y = {y}");
        previous = (x, erf(x));
    }
    for k in 1..=53 {
        // y = +-(1 - 2^-k), down to the last f64 below 1.
        let y = 1.0 - (-f64::from(k)).exp2();
        for y in [y, -y] {
            let x = erfinv(y);
            let error = implied_erfinv_error(y, x);
            worst = worst.max(error);
            assert!(error < 1e-15, "erfinv({y}) = {x}: implied relative error {error:e}");
        }
    }
    println!("largest relative error of erfinv implied by erf and erfc: {worst:.1e}");
}
