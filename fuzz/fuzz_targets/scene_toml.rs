//! Fuzzes the TOML scene loader: any input must load or be rejected with an error, never panic
//! (cargo fuzz builds with debug assertions, so integer overflow panics too).
#![no_main]

use caustic::math::Vec2;
use caustic::app::load_toml_str;
use caustic::options::Options;
use libfuzzer_sys::fuzz_target;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Mesh files that scenes may refer to by name (`file = "tri.obj"`, ...).
fn mesh_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let d = std::env::temp_dir().join(format!("caustic-fuzz-scene-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        for (name, text) in [
            ("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
            (
                "quad.obj",
                "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nf 1//1 2//2 3//3 4//4\n",
            ),
            ("degenerate.obj", "v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n"),
            ("nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
            ("huge.obj", "v 3e38 0 0\nv -3e38 0 0\nv 0 3e38 0\nf 1 2 3\n"),
            ("zero_normals.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 0\nvn 0 0 0\nvn 0 0 0\nf 1//1 2//2 3//3\n"),
        ] {
            std::fs::write(d.join(name), text).unwrap();
        }
        d
    })
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    // Procedural meshes of up to 50 million triangles are allowed; they take seconds and
    // gigabytes each, which is a limit by design, not a bug: keep inputs that ask for them out.
    if text.contains("segments") && text.contains("sides") && text.len() > 0 {
        let big =
            text.split(|c: char| !c.is_ascii_digit()).any(|n| n.len() >= 4 && n.parse::<u64>().is_ok_and(|v| v > 2000));
        if big {
            return;
        }
    }
    let Ok(loaded) = load_toml_str(text, "fuzz.toml", mesh_dir(), &Options::default()) else { return };
    // Trace a few camera rays through the accepted scene.
    let scene = &loaded.scene;
    let (w, h) = (loaded.settings.width as f32, loaded.settings.height as f32);
    for raster in [Vec2::new(0.5 * w, 0.5 * h), Vec2::ZERO, Vec2::new(w, h)] {
        let ray = scene.camera.generate_ray(raster, Vec2::new(0.5, 0.5));
        let _ = scene.intersect(&ray, f32::INFINITY);
        let _ = scene.occluded(&ray, f32::INFINITY);
    }
    let _ = scene.lights.iter().map(|l| l.power()).count();
});
