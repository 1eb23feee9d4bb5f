use super::*;
use crate::options::Options;
use crate::sampling::{Rng32, hash_seed};

/// A closed box with a small ceiling light and a block on the floor: indirect light everywhere,
/// corners and contact edges where it changes fast.
const BOX: &str = r#"
[render]
width = 48
height = 48
max_depth = 6

[camera]
eye = [0.5, 0.5, -1.4]
look_at = [0.5, 0.5, 0.5]
fov = 45

[materials.white]
type = "diffuse"
color = [0.7, 0.7, 0.7]
kd = 1

[materials.red]
type = "diffuse"
color = [0.7, 0.1, 0.1]
kd = 1

[[lights]]
type = "area"
shape = "quad"
corner = [0.4, 0.999, 0.4]
edge1 = [0.2, 0, 0]
edge2 = [0, 0, 0.2]
intensity = 20

[[objects]]
type = "quad"
corner = [0, 0, 0]
edge1 = [0, 0, 1]
edge2 = [1, 0, 0]
material = "white"

[[objects]]
type = "quad"
corner = [0, 1, 0]
edge1 = [1, 0, 0]
edge2 = [0, 0, 1]
material = "white"

[[objects]]
type = "quad"
corner = [0, 0, 1]
edge1 = [0, 1, 0]
edge2 = [1, 0, 0]
material = "white"

[[objects]]
type = "quad"
corner = [1, 0, 0]
edge1 = [0, 0, 1]
edge2 = [0, 1, 0]
material = "red"

[[objects]]
type = "quad"
corner = [0, 0, 0]
edge1 = [0, 1, 0]
edge2 = [0, 0, 1]
material = "white"

[[objects]]
type = "sphere"
center = [0.35, 0.2, 0.6]
radius = 0.2
material = "white"
"#;

fn box_scene() -> (Scene, IntegratorDesc) {
    let mut desc = crate::scene::load_scene_str(BOX, "box.toml", std::path::Path::new(".")).unwrap();
    desc.apply(&Options::default());
    let built = desc.build().unwrap();
    (built.scene, built.integrator)
}

fn integrator(scene: &Scene, desc: &IntegratorDesc, a: f32, rays: u32) -> PhotonIntegrator {
    let o = PhotonOptions {
        photons: Some(100_000),
        caustic_photons: Some(0),
        irradiance_cache: Some(a),
        cache_rays: Some(rays),
        ..Default::default()
    };
    PhotonIntegrator::build(scene, PhotonConfig::new(&o, desc, scene, 5))
}

/// Every pixel's first diffuse hit: the cache's interpolation against a record made right
/// there (the uncached gather, with many rays so its own noise is small). Ward's error bound
/// is first order in `a`: the interpolation error is a fraction of a of E on average, and
/// rarely more than a.
#[test]
fn the_cache_reproduces_the_gather_within_its_error_bound() {
    let (scene, desc) = box_scene();
    let a = 0.25;
    let pm = integrator(&scene, &desc, a, 1024);
    assert!(pm.cache().len() > 20, "{} records", pm.cache().len());
    let mut scratch = Gathered::new(64);
    let (mut sum_rel, mut count, mut over, mut misses) = (0.0f64, 0, 0, 0);
    // Pixels off the image's axes of symmetry: a pixel centre hitting the exact edge where two
    // walls meet makes a degenerate gather (rays start on the other wall's plane and slip past
    // it), with or without the cache.
    for y in (2..48).step_by(3) {
        for x in (2..48).step_by(3) {
            let mut rng = Rng32::new(hash_seed(&[77, x, y]));
            let Some(c) = pm.first_diffuse(&scene, x as u32, y as u32, &mut rng) else { continue };
            let Some(e) = pm.cache.lookup(c.hit.p, c.bsdf.normal(), c.bounce) else {
                misses += 1;
                continue;
            };
            let exact = pm.record_at(&scene, &c, &mut rng, &mut scratch).e;
            let (e, exact) = (crate::math::luminance(e) as f64, crate::math::luminance(exact) as f64);
            let rel = (e - exact).abs() / exact;
            sum_rel += rel;
            count += 1;
            if rel > a as f64 {
                over += 1;
                eprintln!("pixel ({x}, {y}) at {:?} n {:?}: cache {e:.4} gather {exact:.4}", c.hit.p, c.bsdf.normal());
            }
        }
    }
    let mean_rel = sum_rel / count as f64;
    eprintln!("{count} points, {misses} misses, mean relative error {mean_rel:.4}, {over} beyond a");
    assert!(count > 150 && misses * 20 < count, "{count} looked up, {misses} missed");
    assert!(mean_rel < 0.25 * a as f64, "mean relative error {mean_rel}");
    assert!(over * 50 <= count, "{over} of {count} beyond a");
}

/// The cache is filled in a fixed order: the same records on one thread and on two.
#[test]
fn the_cache_is_the_same_on_any_thread_count() {
    let (scene, desc) = box_scene();
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let two = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    let a = one.install(|| integrator(&scene, &desc, 0.3, 128));
    let b = two.install(|| integrator(&scene, &desc, 0.3, 128));
    assert!(!a.cache().is_empty());
    assert_eq!(a.cache().records(), b.cache().records());
}

/// With the cache off, no records; with gathering off, none either (the map is read directly).
#[test]
fn the_cache_is_off_when_asked_or_when_not_gathering() {
    let (scene, desc) = box_scene();
    assert!(integrator(&scene, &desc, 0.0, 128).cache().is_empty());
    let o = PhotonOptions { photons: Some(20_000), gather: Some(0), ..Default::default() };
    assert!(PhotonIntegrator::build(&scene, PhotonConfig::new(&o, &desc, &scene, 5)).cache().is_empty());
}
