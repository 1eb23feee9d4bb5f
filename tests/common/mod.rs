//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod mitsuba_refs;
pub mod slurm;

use caustic::app::{LoadedScene, load, load_toml_str};
use caustic::film::Image;
use caustic::options::Options;
use caustic::render::{RayIntegrator, RenderControl, render_rays};
use caustic::scene::LoadOptions;
use std::path::Path;

/// Loads a scene from TOML text (mesh paths relative to the crate root).
pub fn scene(text: &str) -> LoadedScene {
    scene_with(text, &Options::default())
}

pub fn scene_with(text: &str, o: &Options) -> LoadedScene {
    match load_toml_str(text, "test.toml", Path::new(env!("CARGO_MANIFEST_DIR")), o) {
        Ok(s) => s,
        Err(e) => panic!("test scene failed to load: {e}"),
    }
}

/// A fresh scratch folder under the system temp dir.
pub fn scratch(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("caustic-test-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Loads a bundled scene from `scenes/` with overrides.
pub fn bundled(name: &str, o: &Options) -> LoadedScene {
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name);
    load(&path, &LoadOptions::default(), o).unwrap()
}

/// Renders a loaded scene with its own settings and a ray integrator made by the test.
/// The path tracer of depth limit `max_depth` for scene `s` (with its ray offset).
#[allow(dead_code)]
pub fn path_tracer(s: &LoadedScene, max_depth: u32) -> caustic::integrator::PathTracer {
    caustic::integrator::PathTracer {
        max_depth,
        ray_bias: s.integrator.ray_bias(&s.scene),
        spectral: s.integrator.spectral,
    }
}

/// The offset rays leave surfaces of scene `s` with.
#[allow(dead_code)]
pub fn bias(s: &LoadedScene) -> f32 {
    s.integrator.ray_bias(&s.scene)
}

pub fn render_with<I: RayIntegrator>(s: &LoadedScene, integrator: &I) -> Image {
    render_rays(&s.scene, integrator, &s.settings, &RenderControl::uncancelled()).image
}

/// A closed diffuse sphere of albedo 0.5 and radius 1 around a point light of intensity pi, seen
/// from its centre: radiance 0.5 from direct light, 1 with all bounces (0.5 / (1 - 0.5)).
pub fn point_light_furnace(max_depth: u32) -> String {
    format!(
        r#"
[render]
width = 8
height = 8
max_depth = {max_depth}
[camera]
eye = [0, 0, 0]
look_at = [0, 0, 1]
fov = 60
[materials.grey]
type = "diffuse"
color = [1, 1, 1]
kd = 0.5
[[lights]]
type = "point"
position = [0, 0, 0]
intensity = 3.14159265
[[objects]]
type = "sphere"
radius = 1
material = "grey"
"#
    )
}
