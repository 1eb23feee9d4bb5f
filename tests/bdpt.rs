//! Bidirectional path tracing (`--integrator bdpt`): the furnace's closed forms, a diffuse plane
//! under a point light against its formula, thin-lens and orthographic cameras and wrapped
//! materials (bump map, mask) against the path tracer, and the image bit for bit the same on
//! any thread count with splats. The consistency matrix (`tests/consistency.rs`) compares it
//! with the path tracer for every material and light.

mod common;

use caustic::app::LoadedScene;
use caustic::film::Image;
use caustic::math::luminance;
use caustic::options::{IntegratorKind, Options};

fn render(s: &LoadedScene, threads: usize) -> caustic::render::RenderOutput {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| s.render())
}

fn bdpt(text: &str, spp: u32, seed: u64) -> LoadedScene {
    let o = Options { integrator: Some(IntegratorKind::Bdpt), spp: Some(spp), seed: Some(seed), ..Default::default() };
    common::scene_with(text, &o)
}

fn mean(img: &Image) -> f64 {
    luminance(img.mean()) as f64
}

#[test]
fn furnace_has_radiance_one_with_all_bounces_and_one_half_direct() {
    let mut s = bdpt(&common::point_light_furnace(200), 64, 1);
    s.settings.layers = true;
    let out = render(&s, 2);
    let (gi, direct) = (mean(&out.image), mean(&out.layers[caustic::film::DIRECT]));
    assert!((gi - 1.0).abs() < 0.03, "all bounces: {gi}");
    assert!((direct - 0.5).abs() < 0.015, "direct layer: {direct}");
    let direct_only = mean(&render(&bdpt(&common::point_light_furnace(1), 64, 2), 2).image);
    assert!((direct_only - 0.5).abs() < 0.015, "max_depth 1: {direct_only}");
}

#[test]
fn a_diffuse_plane_under_a_point_light_has_the_radiance_of_the_formula() {
    // As the light tracer's test (`common::PointLitFloor`): direct light only (light samples
    // and light tracing, weighted), the image's mean against the formula averaged over 8 x 8
    // points of each pixel.
    let floor = common::PointLitFloor::DEFAULT;
    let s = bdpt(&floor.text("bdpt"), 256, 3);
    let img = render(&s, 2).image;
    let expected = floor.image_mean(&s.scene.camera, 8);
    let mean = img.pixels.iter().map(|c| c.g() as f64).sum::<f64>() / img.pixels.len() as f64;
    assert!((mean - expected).abs() < 0.005 * expected, "{mean} vs the formula's {expected}");
}

/// A rough gold sphere and a glass one on a floor under a spot light and an area light, with a
/// Gaussian pixel filter (whose splats reach neighbouring pixels); `CAMERA` is replaced.
const SCENE: &str = r#"
[render]
width = 32
height = 24
max_depth = 6
filter = { type = "gaussian" }

CAMERA

[materials.floor]
type = "roughplastic"
color = [0.5, 0.5, 0.45]
alpha = 0.3

[materials.gold]
type = "roughconductor"
metal = "Au"
alpha = 0.2

[materials.glass]
type = "dielectric"
ior = 1.5

[[objects]]
type = "quad"
corner = [-3, 0, 3]
edge1 = [6, 0, 0]
edge2 = [0, 0, -6]
material = "floor"

[[objects]]
type = "sphere"
center = [-0.7, 0.5, 0]
radius = 0.5
material = "gold"

[[objects]]
type = "sphere"
center = [0.7, 0.5, 0]
radius = 0.5
material = "glass"

[[lights]]
type = "spot"
position = [1.5, 3, 2]
look_at = [0, 0, 0]
angle = 40
falloff = 25
intensity = 25

[[lights]]
type = "area"
corner = [-0.5, 2.5, -0.5]
edge1 = [1, 0, 0]
edge2 = [0, 0, 1]
intensity = 4

[[lights]]
type = "constant"
color = [0.2, 0.25, 0.3]
"#;

const PINHOLE: &str = "[camera]\neye = [0, 1.6, 4.5]\nlook_at = [0, 0.5, 0]\nfov = 45";

fn bits(img: &Image) -> Vec<[u32; 3]> {
    img.pixels.iter().map(|c| c.to_array().map(f32::to_bits)).collect()
}

#[test]
fn the_image_and_its_layers_are_the_same_on_any_thread_count() {
    let mut s = bdpt(&SCENE.replace("CAMERA", PINHOLE), 4, 5);
    s.settings.layers = true;
    let one = render(&s, 1);
    assert!(mean(&one.image) > 0.0, "nothing rendered");
    for threads in [2, 8] {
        let other = render(&s, threads);
        assert!(bits(&other.image) == bits(&one.image), "{threads} threads differ from one");
        for (a, b) in one.layers.iter().zip(&other.layers) {
            assert!(bits(a) == bits(b), "a layer differs on {threads} threads");
        }
    }
}

/// The mean luminance of `text` by `reference` and by
/// bidirectional path tracing agree within `tol` of the reference's, or four standard errors of
/// their difference (runs of seeds 1..=4).
fn agrees_with(reference: IntegratorKind, name: &str, text: &str, (ref_spp, bdpt_spp): (u32, u32), tol: f64) {
    let runs =
        |make: &dyn Fn(u64) -> LoadedScene| (1..=4).map(|seed| mean(&render(&make(seed), 2).image)).collect::<Vec<_>>();
    let reference_scene = |seed| {
        let o = Options { integrator: Some(reference), spp: Some(ref_spp), seed: Some(seed), ..Default::default() };
        common::scene_with(text, &o)
    };
    let p = runs(&reference_scene);
    let b = runs(&|seed| bdpt(text, bdpt_spp, seed + 10));
    let stats = |v: &[f64]| {
        let m = v.iter().sum::<f64>() / v.len() as f64;
        let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() as f64 - 1.0);
        (m, var / v.len() as f64)
    };
    let ((mp, vp), (mb, vb)) = (stats(&p), stats(&b));
    let bound = (tol * mp).max(4.0 * (vp + vb).sqrt());
    let r = reference.name();
    eprintln!(
        "{name}: bdpt {mb:.5} vs {r} {mp:.5} ({:+.2}%, bound {:.2}%)",
        (mb / mp - 1.0) * 100.0,
        bound / mp * 100.0
    );
    assert!((mb - mp).abs() <= bound, "{name}: bdpt {mb} vs {r} {mp} (bound {bound})");
}

#[test]
fn thin_lens_and_orthographic_cameras_agree_with_the_path_tracer() {
    let lens = "[camera]\neye = [0, 1.6, 4.5]\nlook_at = [0, 0.5, 0]\nfov = 45\nlens_radius = 0.15\nfocal_distance = 4";
    let ortho = "[camera]\nprojection = \"orthographic\"\neye = [0, 1.6, 4.5]\nlook_at = [0, 0.5, 0]\nview_height = 4";
    for (name, camera) in [("thin lens", lens), ("orthographic", ortho)] {
        agrees_with(IntegratorKind::Path, name, &SCENE.replace("CAMERA", camera), (64, 16), 0.02);
    }
}

/// A bump-mapped plastic and a normal-mapped metal sphere on a floor under an area light, and
/// `VEIL`: nothing, or a translucent veil between them and the light.
const WRAPPED: &str = r#"
[render]
width = 24
height = 20
max_depth = 8
[camera]
eye = [0, 1.6, 4.5]
look_at = [0, 0.5, 0]
fov = 45
[textures.dimples]
type = "bitmap"
file = "scenes/textures/dimples.png"
raw = true
[textures.hammered]
type = "bitmap"
file = "scenes/textures/hammered.png"
raw = true
scale = [4, 2]
[materials.floor]
type = "diffuse"
color = [0.6, 0.6, 0.6]
kd = 1
[materials.white]
type = "roughplastic"
color = 0.8
alpha = 0.15
[materials.golf]
type = "bumpmap"
material = "white"
texture = "dimples"
scale = 0.03
[materials.silver]
type = "roughconductor"
metal = "Ag"
alpha = 0.1
[materials.hammered]
type = "normalmap"
material = "silver"
texture = "hammered"
[materials.orange]
type = "diffuse"
color = [0.8, 0.4, 0.1]
kd = 1
[materials.veil]
type = "mask"
material = "orange"
opacity = 0.4
[[objects]]
type = "quad"
corner = [-3, 0, 3]
edge1 = [6, 0, 0]
edge2 = [0, 0, -6]
material = "floor"
[[objects]]
type = "sphere"
center = [-0.8, 0.45, 0]
radius = 0.45
material = "golf"
[[objects]]
type = "sphere"
center = [0.8, 0.45, 0]
radius = 0.45
material = "hammered"
VEIL
[[lights]]
type = "area"
corner = [-0.5, 2.5, -0.5]
edge1 = [1, 0, 0]
edge2 = [0, 0, 1]
intensity = 10
"#;

#[test]
fn bump_maps_normal_maps_and_masks_agree_with_the_path_tracer() {
    let veil = "[[objects]]\ntype = \"quad\"\ncorner = [-1.5, 1.6, -1]\nedge1 = [3, 0, 0]\nedge2 = [0, 0, 2]\nmaterial = \"veil\"";
    // The perturbed frames against the path tracer.
    agrees_with(IntegratorKind::Path, "bump and normal maps", &WRAPPED.replace("VEIL", ""), (1024, 256), 0.02);
    // Light through the veil's transparent part, which light paths and shadow rays pass alike.
    agrees_with(IntegratorKind::Path, "mask", &WRAPPED.replace("VEIL", veil), (1024, 256), 0.02);
}

/// A 12 x 12 image by an orthographic camera looking down -z from z = 5, two units high, and
/// clear glass; `parts` adds the objects and lights.
fn orthographic_glass(parts: &str) -> String {
    let header = "[render]\nwidth = 12\nheight = 12\nmax_depth = 6\n[camera]\nprojection = \"orthographic\"\n\
                  eye = [0, 0, 5]\nlook_at = [0, 0, 0]\nview_height = 2\n[materials.glass]\ntype = \"dielectric\"\nior = 1.5\n";
    format!("{header}{parts}")
}

/// A glass plane at 45 degrees to the view (its normal (0, 1, 1) / sqrt 2), reflecting the rays
/// to +y and refracting them on into the empty, dark scene.
const GLASS_PLANE: &str = r#"
[[objects]]
type = "quad"
corner = [-3, -3, 3]
edge1 = [6, 0, 0]
edge2 = [0, 6, -6]
material = "glass"
"#;

/// A large area light of radiance 5 above the glass plane, facing down: its reflection.
const LIGHT_ABOVE: &str = r#"
[[lights]]
type = "area"
corner = [-10, 3, -10]
edge1 = [20, 0, 0]
edge2 = [0, 0, 20]
intensity = 5
"#;

/// A large area light of radiance 5 behind the glass plane, facing the refracted rays.
const LIGHT_BEHIND: &str = r#"
[[lights]]
type = "area"
corner = [-20, -20, -4]
edge1 = [40, 0, 0]
edge2 = [0, 40, 0]
intensity = 5
"#;

#[test]
fn a_light_reflected_in_glass_or_seen_through_it_is_met_by_every_camera_sample() {
    // Every camera path splits at the glass (`bdpt::subpath::GLASS_SPLITS`): each pixel is
    // F(45 degrees) x 5 in the mirror case with one sample, where picking reflection by chance
    // would give 0 or 5; through the glass it is (1 - F) x 5 / 1.5^2 (radiance entering glass),
    // from the branch that waits for the reflection's to end.
    let f = caustic::material::fresnel::fresnel_dielectric(std::f32::consts::FRAC_1_SQRT_2, 1.5);
    let mirror = orthographic_glass(&format!("{GLASS_PLANE}{LIGHT_ABOVE}"));
    let window = orthographic_glass(&format!("{GLASS_PLANE}{LIGHT_BEHIND}"));
    for (name, text, expected) in [("mirror", &mirror, f * 5.0), ("window", &window, (1.0 - f) * 5.0 / 2.25)] {
        for integrator in [IntegratorKind::Bdpt, IntegratorKind::Vcm] {
            let o = Options { integrator: Some(integrator), spp: Some(1), seed: Some(3), ..Default::default() };
            let img = render(&common::scene_with(text, &o), 2).image;
            for c in &img.pixels {
                let g = c.g();
                assert!((g - expected).abs() < 1e-4 * expected, "{name}, {integrator:?}: {g} vs {expected}");
            }
        }
    }
}

/// The orthographic camera's rays meet two mirrors that turn them back along -z, then a glass
/// plane at 45 degrees whose reflection is a large area light of radiance 5: the light's
/// reflection in the glass is the camera path's third bounce, where Russian roulette begins.
const PERISCOPE: &str = r#"
[materials.mirror]
type = "reflective"
color = [1, 1, 1]
kd = 0
ka = 0
kr = 1
[[objects]]
type = "quad"
corner = [-3, -1.5, 1.5]
edge1 = [6, 0, 0]
edge2 = [0, 3, -3]
material = "mirror"
[[objects]]
type = "quad"
corner = [-3, 1.5, 1.5]
edge1 = [0, 3, -3]
edge2 = [6, 0, 0]
material = "mirror"
[[objects]]
type = "quad"
corner = [-3, 1.5, -4.5]
edge1 = [6, 0, 0]
edge2 = [0, 3, -3]
material = "glass"
[[lights]]
type = "area"
corner = [-20, 10, -20]
edge1 = [40, 0, 0]
edge2 = [0, 0, 40]
intensity = 5
"#;

#[test]
fn a_split_branch_is_not_ended_by_roulette_for_its_small_weight() {
    // The reflection branch weighs F = 0.05 after the split. Roulette from the third bounce on
    // reads the throughput over the split's factor, as if the branch had been picked by chance,
    // so it survives with probability 0.95 (the cap) and is worth F x 5 / 0.95; read from the
    // weight alone it would survive 5% of the time and be 20 times brighter.
    let f = caustic::material::fresnel::fresnel_dielectric(std::f32::consts::FRAC_1_SQRT_2, 1.5);
    let survivor = f * 5.0 / 0.95;
    for integrator in [IntegratorKind::Bdpt, IntegratorKind::Vcm] {
        let o = Options { integrator: Some(integrator), spp: Some(1), seed: Some(3), ..Default::default() };
        let img = render(&common::scene_with(&orthographic_glass(PERISCOPE), &o), 2).image;
        let mut survived = 0;
        for c in &img.pixels {
            let g = c.g();
            if g != 0.0 {
                assert!((g - survivor).abs() < 1e-4 * survivor, "{integrator:?}: {g} vs {survivor}");
                survived += 1;
            }
        }
        // 95% of 144 pixels expected (binomial standard deviation 2.6 pixels).
        assert!(survived >= 122, "{integrator:?}: {survived} of {} camera paths survived", img.pixels.len());
    }
}
