//! Helpers shared by the integration tests.
#![allow(dead_code)]

use caustic::film::Image;
use caustic::integrator::Integrator;
use caustic::render::{RenderControl, render};
use caustic::scene::{Overrides, load::LoadedScene, load_scene_str};
use std::path::Path;
use std::sync::atomic::AtomicBool;

/// Loads a scene from TOML text (mesh paths relative to the crate root).
pub fn scene(text: &str) -> LoadedScene {
    match load_scene_str(text, "test.toml", Path::new(env!("CARGO_MANIFEST_DIR")), &Overrides::default()) {
        Ok(s) => s,
        Err(e) => panic!("test scene failed to load: {e}"),
    }
}

pub fn scene_with(text: &str, o: &Overrides) -> LoadedScene {
    match load_scene_str(text, "test.toml", Path::new(env!("CARGO_MANIFEST_DIR")), o) {
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
pub fn bundled(name: &str, o: &Overrides) -> LoadedScene {
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name);
    caustic::scene::load_scene(&path, o).unwrap()
}

/// Renders a loaded scene with its own settings and `integrator`.
pub fn render_with<I: Integrator>(s: &LoadedScene, integrator: &I) -> Image {
    let cancel = AtomicBool::new(false);
    render(&s.scene, integrator, &s.settings, &RenderControl { cancel: &cancel, on_checkpoint: None }).0
}
