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

/// A Lambertian floor of albedo `rho` under a point light of `intensity` at height `height`,
/// seen from above on a `size` x `size` film, direct light only (max_depth 1): a floor point at
/// distance d from the light, lit at cos theta, has radiance rho / pi I cos / d^2.
pub struct PointLitFloor {
    pub rho: f64,
    pub intensity: f64,
    pub height: f64,
    pub size: usize,
}

impl PointLitFloor {
    pub const DEFAULT: PointLitFloor = PointLitFloor { rho: 0.5, intensity: 8.0, height: 2.0, size: 12 };

    /// The scene, rendered by `integrator`.
    pub fn text(&self, integrator: &str) -> String {
        let PointLitFloor { rho, intensity, height, size } = self;
        format!(
            r#"
[render]
width = {size}
height = {size}
max_depth = 1
integrator = "{integrator}"
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
position = [0, {height}, 0]
intensity = {intensity}
"#
        )
    }

    /// The formula's radiance averaged over `n` x `n` points of pixel (`px`, `py`) of `camera`.
    pub fn pixel(&self, camera: &caustic::camera::Camera, px: usize, py: usize, n: usize) -> f64 {
        let mut sum = 0.0;
        for k in 0..n * n {
            let raster = caustic::math::Vec2::new(
                px as f32 + ((k % n) as f32 + 0.5) / n as f32,
                py as f32 + ((k / n) as f32 + 0.5) / n as f32,
            );
            let ray = camera.generate_ray(raster, caustic::math::Vec2::splat(0.5));
            let t = -ray.o.y as f64 / ray.d.y as f64;
            let p = ray.o.as_dvec3() + ray.d.as_dvec3() * t;
            let to_light = glam::DVec3::new(0.0, self.height, 0.0) - p;
            let d2 = to_light.length_squared();
            sum += self.rho / std::f64::consts::PI * self.intensity * (to_light.y / d2.sqrt()) / d2;
        }
        sum / (n * n) as f64
    }

    /// `pixel` averaged over the whole film.
    pub fn image_mean(&self, camera: &caustic::camera::Camera, n: usize) -> f64 {
        let s = self.size;
        (0..s * s).map(|k| self.pixel(camera, k % s, k / s, n)).sum::<f64>() / (s * s) as f64
    }
}
