//! Fuzzes the `.spd` spectrum reader and the colour conversion of what it accepts: any text is
//! a spectrum with finite, increasing wavelengths (whose colour is finite) or an error, never a
//! panic.
#![no_main]

use caustic::spectrum::{SpectrumUse, parse_spd};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    if let Ok(s) = parse_spd(&text) {
        assert!(s.wavelengths().windows(2).all(|w| w[0] < w[1]));
        for usage in [SpectrumUse::Reflectance, SpectrumUse::Unbounded, SpectrumUse::Emission] {
            let (c, _) = s.to_srgb(usage);
            assert!(c.is_finite() || s.values().iter().any(|v| v.abs() > 1e30), "{c} from {s:?}");
        }
    }
});
