//! The light tracer (`--integrator light`, Mitsuba's `ptracer`): against Mitsuba 3's particle
//! tracer on a scene with one emitter of every kind (tests/data/ptracer,
//! scripts/make_ptracer_refs.py), against the closed form of a diffuse plane under a point
//! light, and its splats summed exactly: the same image on any thread count, and a crop window
//! holds the whole image's pixels.

mod common;

use caustic::film::Image;
use caustic::options::{IntegratorKind, Options};
use common::mitsuba_refs::References;

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
    // `common::PointLitFloor`: the image's mean against the formula averaged over 8 x 8 points
    // of each pixel.
    let floor = common::PointLitFloor::DEFAULT;
    let text = floor.text("light");
    let img = render(&text, 2048, 2);
    let expected = floor.image_mean(&common::scene(&text).scene.camera, 8);
    let mean = img.pixels.iter().map(|c| c.g() as f64).sum::<f64>() / img.pixels.len() as f64;
    eprintln!("light-traced floor under a point light: {mean} vs the formula's {expected}");
    assert!((mean - expected).abs() < 0.01 * expected, "{mean} vs {expected}");
}
