//! Stochastic progressive photon mapping converges to the path tracer's image, renders caustics
//! from a point light, and keeps its memory bounded.

mod common;

use caustic::app::LoadedScene;
use caustic::film::Image;
use caustic::integrator::sppm::{Sppm, SppmConfig};
use caustic::math::luminance;
use caustic::options::{IntegratorKind, Options};
use caustic::render::{RenderControl, RenderStats};

fn sppm(s: &LoadedScene, iterations: u32, photons: u64) -> (Image, RenderStats) {
    let (image, stats, _) = sppm_with(s, iterations, photons, false);
    (image, stats)
}

/// An SPPM render starting at `photons` per iteration, adaptive or not; also returns the mean
/// photons per iteration.
fn sppm_with(s: &LoadedScene, iterations: u32, photons: u64, adaptive: bool) -> (Image, RenderStats, f64) {
    let mut settings = s.settings.clone();
    settings.spp = iterations;
    let config = SppmConfig {
        photons_per_iter: photons,
        adaptive_photons: adaptive,
        indirect_reach: if adaptive { caustic::integrator::sppm::INDIRECT_REACH } else { 1.0 },
        initial_radius: None,
        alpha: 2.0 / 3.0,
        max_depth: s.integrator.depth_limit(IntegratorKind::Sppm),
        ray_bias: common::bias(s),
        spectral: s.integrator.spectral,
    };
    let sppm = Sppm::new(config);
    let out = sppm.render(
        &s.scene,
        &settings,
        &RenderControl::uncancelled(),
        caustic::film::Film::new(settings.width, settings.height, settings.layers),
    );
    (out.image, out.stats, sppm.mean_photons_per_iter())
}

#[test]
fn sppm_converges_to_the_path_tracer_on_the_diffuse_cornell_box() {
    let size = Options { width: Some(48), height: Some(48), seed: Some(5), ..Default::default() };
    let reference = {
        let r = common::bundled("11-cornell-area.toml", &Options { spp: Some(2048), ..size.clone() });
        common::render_with(&r, &common::path_tracer(&r, 12))
    };
    let s = common::bundled("11-cornell-area.toml", &size);
    let (early, _) = sppm(&s, 16, 20_000);
    let (late, _) = sppm(&s, 256, 20_000);
    let (e_early, e_late) = (early.rmse(&reference), late.rmse(&reference));
    // 16 times the iterations: the error must fall clearly (measured: about 0.09 -> 0.01).
    assert!(e_late < 0.5 * e_early, "RMSE after 16 iterations {e_early}, after 256 {e_late}");
    let (l_ref, l) = (luminance(reference.mean()), luminance(late.mean()));
    assert!((l - l_ref).abs() < 0.01 * l_ref, "mean luminance {l} vs path tracer {l_ref}");
}

#[test]
fn adaptive_photons_converge_to_the_path_tracer_and_do_not_depend_on_threads() {
    let size = Options { width: Some(48), height: Some(48), seed: Some(5), ..Default::default() };
    let reference = {
        let r = common::bundled("11-cornell-area.toml", &Options { spp: Some(2048), ..size.clone() });
        common::render_with(&r, &common::path_tracer(&r, 12))
    };
    let s = common::bundled("11-cornell-area.toml", &size);
    let pixels = 48 * 48;
    let on = |threads: usize, iterations: u32| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| sppm_with(&s, iterations, pixels, true))
    };
    let (one, _, photons_one) = on(1, 24);
    let (three, _, photons_three) = on(3, 24);
    assert!(one.pixels == three.pixels, "1 and 3 threads differ");
    assert_eq!(photons_one, photons_three);
    // The number moved from the first iteration's (this box's direct light, an area light's
    // soft shadows, is most of its variance: fewer photons).
    assert!(photons_one != pixels as f64, "photons per iteration stayed at {photons_one}");
    let (early, _, _) = on(2, 16);
    let (late, _, _) = on(2, 256);
    let (e_early, e_late) = (early.rmse(&reference), late.rmse(&reference));
    assert!(e_late < 0.5 * e_early, "RMSE after 16 iterations {e_early}, after 256 {e_late}");
    let (l_ref, l) = (luminance(reference.mean()), luminance(late.mean()));
    assert!((l - l_ref).abs() < 0.01 * l_ref, "mean luminance {l} vs path tracer {l_ref}");
}

#[test]
fn sppm_renders_and_converges_the_point_light_caustic() {
    let s = common::bundled(
        "13-cornell-caustics.toml",
        &Options { width: Some(64), height: Some(64), seed: Some(9), ..Default::default() },
    );
    let (long, _) = sppm(&s, 512, 40_000);
    let (a, _) = sppm(&s, 16, 40_000);
    let (b, _) = sppm(&s, 128, 40_000);
    let (ea, eb) = (a.rmse(&long), b.rmse(&long));
    assert!(eb < 0.7 * ea, "RMSE against a long run: 16 iterations {ea}, 128 iterations {eb}");
    // The caustic under the glass sphere (windows as in the photon-mapping test).
    let mean = |img: &Image, x0: u32, x1: u32, y0: u32, y1: u32| {
        let mut sum = 0.0;
        for y in y0..y1 {
            for x in x0..x1 {
                sum += luminance(img.get(x, y));
            }
        }
        sum / ((x1 - x0) * (y1 - y0)) as f32
    };
    let ratio = mean(&b, 39, 45, 57, 59) / mean(&b, 12, 28, 59, 62);
    assert!(ratio >= 2.0, "caustic only {ratio} x as bright as the floor around it");
}

#[test]
fn sppm_memory_does_not_grow_with_iterations() {
    let s =
        common::bundled("11-cornell-area.toml", &Options { width: Some(32), height: Some(32), ..Default::default() });
    let (_, ten) = sppm(&s, 10, 10_000);
    let (_, hundred) = sppm(&s, 100, 10_000);
    let (m10, m100) = (ten.memory_bytes as f64, hundred.memory_bytes as f64);
    assert!(m10 > 0.0);
    assert!((m100 - m10).abs() < 0.1 * m10, "working memory {m10} bytes after 10 iterations, {m100} after 100");
}
