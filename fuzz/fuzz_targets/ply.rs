//! Fuzzes the PLY reader through a one-shape Mitsuba scene: any file loads or is rejected with
//! an error, never panics.
#![no_main]

use caustic::app::prepare;
use caustic::scene::mitsuba::load_mitsuba_str;
use caustic::options::Options;
use caustic::scene::LoadOptions;
use libfuzzer_sys::fuzz_target;

const SCENE: &str = r#"<scene version="3.0.0"><shape type="ply"><string name="filename" value="fuzz.ply"/></shape></scene>"#;

fuzz_target!(|data: &[u8]| {
    let dir = std::env::temp_dir().join(format!("caustic-fuzz-ply-{}", std::process::id()));
    if std::fs::create_dir_all(&dir).is_err() || std::fs::write(dir.join("fuzz.ply"), data).is_err() {
        return;
    }
    let _ = load_mitsuba_str(SCENE, "fuzz.xml", &dir, &LoadOptions::default()).and_then(|d| prepare(d, &Options::default()));
});
