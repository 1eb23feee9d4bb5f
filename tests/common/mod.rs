//! Helpers shared by the integration tests.
#![allow(dead_code)]

use caustic::scene::{Overrides, load::LoadedScene, load_scene_str};
use std::path::Path;

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
