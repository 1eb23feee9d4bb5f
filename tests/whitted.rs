//! The Whitted integrator against analytic values: irradiance under a point light, shadows,
//! mirrors and glass.

mod common;

use caustic::geometry::Ray;
use caustic::integrator::Whitted;
use caustic::math::{Color, Vec3};
use caustic::render::{RayIntegrator, RayStats};
use caustic::sampling::{Sampler, SamplerKind};
use caustic::scene::desc::IntegratorDesc;

fn radiance(s: &caustic::app::LoadedScene, ray: Ray, depth: u32) -> Color {
    radiance_counted(s, ray, depth, 0.0, 0).0
}

/// Radiance with adaptive depth control at `bailout` (sample `index` of the random stream), and
/// the rays it took.
fn radiance_counted(
    s: &caustic::app::LoadedScene,
    ray: Ray,
    depth: u32,
    bailout: f32,
    index: u32,
) -> (Color, RayStats) {
    let mut sampler = Sampler::new(SamplerKind::Jittered, 0, 0, 0, index, 1);
    let mut stats = RayStats::default();
    let desc =
        IntegratorDesc { max_depth: Some(depth), light_samples: 16, adc_bailout: bailout, ..s.integrator.clone() };
    let l = Whitted::new(&s.scene, &desc).radiance(&s.scene, &ray, &mut sampler, &mut (), &mut stats);
    (l.iter().sum(), stats)
}

const PLANE_UNDER_LIGHT: &str = r#"
[camera]
eye = [0, 5, 5]
look_at = [0, 0, 0]
[materials.white]
type = "diffuse"
color = [1, 0.5, 0.25]
ka = 0
kd = 0.7
[[lights]]
type = "point"
position = [1, 3, -0.5]
intensity = 10
[[objects]]
type = "plane"
material = "white"
"#;

#[test]
fn diffuse_plane_receives_kd_i_cos_over_d2() {
    let s = common::scene(PLANE_UNDER_LIGHT);
    let light = Vec3::new(1.0, 3.0, -0.5);
    for target in [Vec3::new(0.0, 0.0, 0.0), Vec3::new(-2.0, 0.0, 1.5), Vec3::new(3.0, 0.0, -4.0)] {
        let eye = Vec3::new(0.3, 2.0, 4.0);
        let ray = Ray::new(eye, (target - eye).normalize());
        let c = radiance(&s, ray, 1);
        let to_light = light - target;
        let d2 = to_light.length_squared();
        let cos = to_light.normalize().y;
        let expected = Color::new(1.0, 0.5, 0.25) * 0.7 * 10.0 * cos / d2;
        assert!((c - expected).abs().max_element() <= 1e-4 * expected.max_element(), "at {target}: {c} vs {expected}");
    }
}

#[test]
fn shadow_ray_blocked_and_unblocked() {
    let text = format!(
        "{PLANE_UNDER_LIGHT}\n[[objects]]\ntype = \"sphere\"\ncenter = [0.5, 1.5, -0.25]\nradius = 0.3\nmaterial = \"white\"\n"
    );
    let s = common::scene(&text);
    let eye = Vec3::new(0.0, 2.0, 4.0);
    // The sphere sits halfway between the light and the origin: the origin is in shadow.
    let shadowed = radiance(&s, Ray::new(eye, (Vec3::ZERO - eye).normalize()), 1);
    assert_eq!(shadowed, Color::ZERO);
    // A point off to the side sees the light.
    let lit_target = Vec3::new(-2.0, 0.0, 1.5);
    let lit = radiance(&s, Ray::new(eye, (lit_target - eye).normalize()), 1);
    assert!(lit.r() > 0.1, "{lit}");
    // A blocker beyond the light does not cast a shadow.
    let beyond = format!(
        "{PLANE_UNDER_LIGHT}\n[[objects]]\ntype = \"sphere\"\ncenter = [1.5, 4.5, -0.75]\nradius = 0.3\nmaterial = \"white\"\n"
    );
    let s2 = common::scene(&beyond);
    let c = radiance(&s2, Ray::new(eye, (Vec3::ZERO - eye).normalize()), 1);
    assert!(c.r() > 0.1, "a sphere behind the light shadowed the floor: {c}");
}

#[test]
fn mirror_reflects_background_weighted_by_kr() {
    let s = common::scene(
        r#"
[render]
background = [0.2, 0.4, 0.6]
[camera]
eye = [0, 0, 5]
look_at = [0, 0, 0]
[materials.mirror]
type = "reflective"
kd = 0
ka = 0
kr = 0.75
[[objects]]
type = "quad"
corner = [-1, -1, 0]
edge1 = [2, 0, 0]
edge2 = [0, 2, 0]
material = "mirror"
"#,
    );
    let c = radiance(&s, Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z), 4);
    assert!((c - Color::new(0.2, 0.4, 0.6) * 0.75).abs().max_element() < 1e-6, "{c}");
    // With one bounce (direct light only) the recursion is cut: no reflection.
    assert_eq!(radiance(&s, Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z), 1), Color::ZERO);
}

#[test]
fn glass_sphere_passes_background_by_fresnel_and_conserves_energy() {
    // A clear dielectric sphere against a uniform background: along the axis the ray crosses two
    // surfaces at normal incidence, each reflecting 4%. With a uniform background everything
    // reflected or transmitted ends at the background, so the total must equal it (to the
    // depth limit).
    let s = common::scene(
        r#"
[render]
background = [1, 1, 1]
[camera]
eye = [0, 0, 5]
look_at = [0, 0, 0]
[materials.glass]
type = "dielectric"
ior = 1.5
[[objects]]
type = "sphere"
radius = 1
material = "glass"
"#,
    );
    for y in [0.0f32, 0.3, 0.7, 0.95, 0.999] {
        let c = radiance(&s, Ray::new(Vec3::new(0.0, y, 5.0), -Vec3::Z), 41);
        assert!((c - Color::ONE).abs().max_element() < 1e-3, "offset {y}: {c}");
    }
}

/// The mean of `n` samples of `ray` at adaptive-depth-control `bailout` (in f64, with its
/// standard error), and the camera-and-secondary and shadow rays per sample.
fn roulette_mean(
    s: &caustic::app::LoadedScene,
    ray: Ray,
    depth: u32,
    bailout: f32,
    n: u32,
) -> ([f64; 3], [f64; 3], f64, f64) {
    let (mut sum, mut sum2, mut rays, mut shadow_rays) = ([0.0f64; 3], [0.0f64; 3], 0u64, 0u64);
    for i in 0..n {
        let (c, stats) = radiance_counted(s, ray, depth, bailout, i);
        for (k, v) in c.to_array().into_iter().enumerate() {
            sum[k] += v as f64;
            sum2[k] += v as f64 * v as f64;
        }
        rays += stats.rays;
        shadow_rays += stats.shadow_rays;
    }
    let n = n as f64;
    let mean = sum.map(|v| v / n);
    let std_err = std::array::from_fn(|k| ((sum2[k] / n - mean[k] * mean[k]).max(0.0) / n).sqrt());
    (mean, std_err, rays as f64 / n, shadow_rays as f64 / n)
}

/// Whether `mean` is within four standard errors of `exact` in every channel.
fn within_four_errors(mean: [f64; 3], std_err: [f64; 3], exact: Color) -> bool {
    (0..3).all(|k| (mean[k] - exact[k] as f64).abs() <= 4.0 * std_err[k])
}

/// Adaptive depth control ends rays of little weight (reflected, refracted and shadow rays) by
/// Russian roulette, so it keeps the expected radiance: through a glass sphere over a lit
/// floor, seen off axis so that internal reflections branch, the mean of many samples at a
/// bailout high enough to end most rays matches the radiance with every ray traced, within
/// four standard errors, at fewer rays.
#[test]
fn adaptive_depth_control_keeps_the_mean_with_fewer_rays() {
    let s = common::scene(
        r#"
[render]
background = [0.3, 0.5, 0.8]
[camera]
eye = [0, 1, 5]
look_at = [0, 1, 0]
[materials.glass]
type = "dielectric"
ior = 1.5
[materials.floor]
type = "diffuse"
color = [0.9, 0.6, 0.3]
ka = 0
[[lights]]
type = "point"
position = [2, 5, 3]
intensity = 40
[[objects]]
type = "plane"
material = "floor"
[[objects]]
type = "sphere"
center = [0, 1, 0]
radius = 1
material = "glass"
"#,
    );
    let ray = Ray::new(Vec3::new(0.0, 1.0, 5.0), Vec3::new(0.0, -0.12, -1.0).normalize());
    let depth = 10;
    let (exact, all) = radiance_counted(&s, ray, depth, 0.0, 0);
    let (mean, std_err, rays, shadow_rays) = roulette_mean(&s, ray, depth, 0.2, 20_000);
    assert!(std_err.iter().all(|&e| e > 0.0), "no ray was ended: {std_err:?}");
    assert!(within_four_errors(mean, std_err, exact), "mean {mean:?} vs {exact} (standard error {std_err:?})");
    assert!(rays < 0.6 * all.rays as f64, "{rays} rays per sample, {} with every ray traced", all.rays);
    assert!(shadow_rays < 0.6 * all.shadow_rays as f64, "{shadow_rays} shadow rays per sample, {}", all.shadow_rays);
}

/// Shadow rays alone: a dark floor seen directly (no reflected or refracted rays) reflects
/// kd x colour x cos = 0.05 cos towards the viewer, so at bailout 0.2 its shadow ray is traced
/// with probability 0.25 cos and counts four times over; the mean keeps the exact radiance.
#[test]
fn adaptive_depth_control_keeps_the_mean_of_shadow_rays() {
    let s = common::scene(
        r#"
[camera]
eye = [0, 2, 4]
look_at = [0, 0, 0]
[materials.floor]
type = "diffuse"
color = [0.5, 0.5, 0.5]
kd = 0.1
ka = 0
[[lights]]
type = "point"
position = [1, 3, 0]
intensity = 40
[[objects]]
type = "plane"
material = "floor"
"#,
    );
    let eye = Vec3::new(0.0, 2.0, 4.0);
    let target = Vec3::new(0.5, 0.0, 0.5);
    let ray = Ray::new(eye, (target - eye).normalize());
    let cos = (Vec3::new(1.0, 3.0, 0.0) - target).normalize().y as f64;
    let (exact, all) = radiance_counted(&s, ray, 1, 0.0, 0);
    assert_eq!(all.shadow_rays, 1);
    let (mean, std_err, _, shadow_rays) = roulette_mean(&s, ray, 1, 0.2, 20_000);
    assert!(within_four_errors(mean, std_err, exact), "mean {mean:?} vs {exact} (standard error {std_err:?})");
    // Binomial: 20,000 draws of probability 0.25 cos, standard deviation below 0.004.
    let expected = 0.25 * cos;
    assert!((shadow_rays - expected).abs() < 0.015, "{shadow_rays} shadow rays per sample, expected {expected}");
}

#[test]
fn total_internal_reflection_leaves_no_black_ring() {
    // Transparent with fixed coefficients kr + kt = 1 in a uniform white background: with the seed's
    // fix (k_s = 1 under TIR) every path ends in the background and the sphere is invisible.
    let s = common::scene(
        r#"
[render]
background = [1, 1, 1]
[camera]
eye = [0, 0, 5]
look_at = [0, 0, 0]
[materials.glass]
type = "transparent"
ior = 1.5
kr = 0.2
kt = 0.8
[[objects]]
type = "sphere"
radius = 1
material = "glass"
"#,
    );
    let mut darkest = 1.0f32;
    for i in 0..200 {
        let y = i as f32 / 200.0;
        let c = radiance(&s, Ray::new(Vec3::new(0.0, y, 5.0), -Vec3::Z), 61);
        darkest = darkest.min(c.r());
    }
    assert!(darkest > 0.99, "darkest pixel {darkest}: a ring from total internal reflection");
}

/// A shadow ray straight down through the centre of a glass sphere crosses it twice at normal
/// incidence: the floor below gets (1 - F0)^2 of the light (F0 = ((n - 1) / (n + 1))^2), and
/// k_t^2 under a `transparent` sphere. Checked with the one-traversal crossing walk and with the
/// closest-hit walk it falls back to (a cylinder elsewhere in the scene forces it).
#[test]
fn glass_shadows_pass_the_fresnel_product() {
    let light = Vec3::new(0.0, 4.0, 0.0);
    for (glass, expected) in [
        ("type = \"dielectric\"\nior = 1.5", (1.0f32 - 0.04) * (1.0 - 0.04)),
        ("type = \"transparent\"\nkt = 0.7\nkr = 0\nior = 1.5", 0.7 * 0.7),
    ] {
        for cylinder in [false, true] {
            let mut text = format!(
                "[camera]\neye = [0, 5, 5]\nlook_at = [0, 0, 0]\n[materials.floor]\ntype = \"diffuse\"\n\
                 [materials.glass]\n{glass}\n[[lights]]\ntype = \"point\"\nposition = [0, 4, 0]\nintensity = 10\n\
                 [[objects]]\ntype = \"plane\"\nmaterial = \"floor\"\n\
                 [[objects]]\ntype = \"sphere\"\ncenter = [0, 2, 0]\nradius = 0.5\nmaterial = \"glass\"\n"
            );
            if cylinder {
                text += "[[objects]]\ntype = \"cylinder\"\np0 = [5, 0, 5]\np1 = [5, 1, 5]\nradius = 0.2\nmaterial = \"floor\"\n";
            }
            let s = common::scene(&text);
            let hit = s.scene.intersect(&Ray::new(Vec3::new(0.0, 1.0, 0.0), -Vec3::Y), f32::INFINITY).expect("floor");
            let to_light = light - hit.p;
            let mut stats = RayStats::default();
            let desc = IntegratorDesc { adc_bailout: 0.0, ..s.integrator.clone() };
            let t = Whitted::new(&s.scene, &desc).shadow_transmittance(
                &s.scene,
                &hit,
                to_light.normalize(),
                to_light.length(),
                &mut stats,
            );
            assert!((t - expected).abs() < 1e-4, "{glass}, cylinder {cylinder}: {t} vs {expected}");
            // The walk counts one shadow ray; the closest-hit walk one per surface met.
            assert_eq!(stats.shadow_rays, if cylinder { 3 } else { 1 });
        }
    }
}
