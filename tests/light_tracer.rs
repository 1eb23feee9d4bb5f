//! The light tracer (`--integrator light`, Mitsuba's `ptracer`): against Mitsuba 3's particle
//! tracer on a scene with one emitter of every kind (tests/data/ptracer,
//! scripts/make_ptracer_refs.py), against the closed form of a diffuse plane under a point
//! light, and its splats summed exactly: the same image on any thread count, and a crop window
//! holds the whole image's pixels.

mod common;

use caustic::film::Image;
use caustic::options::{IntegratorKind, Options};
use common::mitsuba_refs::References;
use std::f64::consts::PI;

#[test]
fn every_kind_of_emitter_matches_mitsubas_particle_tracer() {
    let refs = References::new("ptracer");
    // The scene names `ptracer`: the loader maps it to the light tracer.
    let s = refs.load("all_emitters", 64, 16, &Options::default());
    assert_eq!(s.integrator.kind, IntegratorKind::Light);
    let (a, b) = (refs.render("all_emitters", 64, 1024, 1, None), refs.render("all_emitters", 64, 1024, 2, None));
    let (rel, ratio, line) = refs.judge("all_emitters", &a, &b);
    assert!(rel.abs() < 0.01 && ratio < 1.25, "differs from Mitsuba's ptracer: {line}");
}

fn bits(img: &Image) -> Vec<[u32; 3]> {
    img.pixels.iter().map(|c| c.to_array().map(f32::to_bits)).collect()
}

/// A rough gold sphere and a glass one on a floor under a spot light and an area light, with a
/// Gaussian pixel filter (whose splats reach neighbouring pixels).
const SCENE: &str = r#"
[render]
width = 40
height = 30
max_depth = 6
integrator = "light"
filter = { type = "gaussian" }

[camera]
eye = [0, 1.6, 4.5]
look_at = [0, 0.5, 0]
fov = 45

[materials.floor]
type = "diffuse"
color = [0.6, 0.6, 0.6]

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
"#;

fn render(text: &str, spp: u32, threads: usize) -> Image {
    let s = common::scene_with(text, &Options { spp: Some(spp), seed: Some(3), ..Default::default() });
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| s.render().image)
}

#[test]
fn the_image_is_the_same_on_any_thread_count() {
    let one = bits(&render(SCENE, 8, 1));
    assert!(one.iter().any(|p| p != &[0; 3]), "the light tracer rendered nothing");
    for threads in [2, 8] {
        assert!(bits(&render(SCENE, 8, threads)) == one, "{threads} threads differ from one");
    }
}

#[test]
fn a_crop_holds_the_whole_images_pixels() {
    let whole = render(SCENE, 4, 2);
    let (x0, y0, w, h) = (10, 6, 20, 15);
    let cropped = SCENE.replace(
        "filter = { type = \"gaussian\" }",
        &format!("filter = {{ type = \"gaussian\" }}\ncrop = {{ x = {x0}, y = {y0}, width = {w}, height = {h} }}"),
    );
    let part = render(&cropped, 4, 2);
    assert_eq!((part.width, part.height), (w, h));
    // Light paths cover the full film whatever the window, and each splat lands where it does
    // in the whole image: every pixel of the window is the whole image's, bit for bit.
    for y in 0..h {
        for x in 0..w {
            let (a, b) = (part.get(x, y).to_array(), whole.get(x + x0, y + y0).to_array());
            assert_eq!(a.map(f32::to_bits), b.map(f32::to_bits), "crop pixel ({x}, {y}) differs");
        }
    }
}

#[test]
fn a_diffuse_plane_under_a_point_light_has_the_radiance_of_the_formula() {
    // A Lambertian floor of albedo rho under a point light of intensity I at height hl, direct
    // light only (max_depth 1): a floor point at distance d from the light, seen at cos theta
    // from its normal, has radiance rho / pi * I cos / d^2. The camera looks down at the floor;
    // each pixel's expected value averages the formula over 8 x 8 points of the pixel.
    let (rho, intensity, hl) = (0.5f64, 8.0f64, 2.0f64);
    let text = format!(
        r#"
[render]
width = 12
height = 12
max_depth = 1
integrator = "light"

[camera]
eye = [0, 6, 0]
look_at = [0, 0, 0]
up = [0, 0, -1]
fov = 50

[materials.floor]
type = "diffuse"
color = [{rho}, {rho}, {rho}]
kd = 1

[[objects]]
type = "quad"
corner = [-50, 0, 50]
edge1 = [100, 0, 0]
edge2 = [0, 0, -100]
material = "floor"

[[lights]]
type = "point"
position = [0, {hl}, 0]
intensity = {intensity}
"#
    );
    let img = render(&text, 2048, 2);
    let s = common::scene(&text);
    let cam = &s.scene.camera;
    let mut expected = 0.0;
    for py in 0..12 {
        for px in 0..12 {
            for k in 0..64 {
                let raster = caustic::math::Vec2::new(
                    px as f32 + (k % 8) as f32 / 8.0 + 1.0 / 16.0,
                    py as f32 + (k / 8) as f32 / 8.0 + 1.0 / 16.0,
                );
                let ray = cam.generate_ray(raster, caustic::math::Vec2::splat(0.5));
                let t = -ray.o.y as f64 / ray.d.y as f64;
                let p = ray.o.as_dvec3() + ray.d.as_dvec3() * t;
                let to_light = glam::DVec3::new(0.0, hl, 0.0) - p;
                let d2 = to_light.length_squared();
                expected += rho / PI * intensity * (to_light.y / d2.sqrt()) / d2;
            }
        }
    }
    expected /= 144.0 * 64.0;
    let mean = img.pixels.iter().map(|c| c.g() as f64).sum::<f64>() / img.pixels.len() as f64;
    eprintln!("light-traced floor under a point light: {mean} vs the formula's {expected}");
    assert!((mean - expected).abs() < 0.01 * expected, "{mean} vs {expected}");
}
