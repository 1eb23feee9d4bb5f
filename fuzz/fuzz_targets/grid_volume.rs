//! Fuzzes the one `.vol` grid reader (`caustic::volume::parse_vol`, behind Mitsuba's
//! `gridvolume` and `sdfgrid`) and the heterogeneous medium built from what it accepts: any
//! bytes are a grid or an error, never a panic; an accepted grid's lookups are finite, and a
//! medium made of it (when its values are in range) tracks rays to finite estimates.
#![no_main]

use caustic::geometry::{Ray, Transform};
use caustic::math::{Color, Vec3};
use caustic::medium::{Heterogeneous, Phase, Volume, VolumeData};
use caustic::sampling::Rng32;
use caustic::volume::{VolShape, parse_vol};
use libfuzzer_sys::fuzz_target;
use std::sync::Arc;

fuzz_target!(|data: &[u8]| {
    let Ok(grid) = parse_vol(data, VolShape::MEDIUM) else { return };
    assert_eq!(grid.values.len(), grid.nx * grid.ny * grid.nz * grid.channels);
    for p in [Vec3::ZERO, Vec3::splat(0.37), Vec3::ONE, Vec3::new(-2.0, 0.5, 9.0)] {
        assert!(grid.eval(p).is_finite() || grid.values.iter().any(|v| v.abs() > 1e30));
    }
    // A medium needs sigma_t >= 0 (and small enough not to overflow the majorants).
    let sigma_t = Volume::placed(VolumeData::Grid(Arc::new(grid)), &Transform::IDENTITY);
    let Ok(m) = Heterogeneous::new(sigma_t, Volume::constant(Color::splat(0.5)), 1.0, Phase::Isotropic) else { return };
    if m.majorant().values.iter().any(|&v| v > 1e3) {
        return;
    }
    let mut rng = Rng32::new(1);
    let ray = Ray::new(Vec3::new(-0.5, 0.3, 0.2), Vec3::new(1.0, 0.2, 0.3).normalize());
    let tr = m.transmittance(&ray, 10.0, &mut rng);
    assert!(tr.is_finite() && tr.min_element() >= 0.0, "{tr:?}");
    let s = m.sample_distance(&ray, 10.0, Color::ONE, 0.5, &mut rng);
    assert!(s.weight.is_finite() && s.t <= 10.0, "{s:?}");
});
