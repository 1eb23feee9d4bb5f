//! Fuzzes the Mitsuba 3 XML loader: any input loads or is rejected with an error, never panics.
#![no_main]

use caustic::app::prepare;
use caustic::scene::mitsuba::load_mitsuba_str;
use caustic::options::Options;
use caustic::scene::LoadOptions;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let _ = load_mitsuba_str(text, "fuzz.xml", &std::env::temp_dir(), &LoadOptions::default()).and_then(|d| prepare(d, &Options::default()));
});
