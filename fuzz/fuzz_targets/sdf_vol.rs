//! Fuzzes the `.vol` grid reader behind Mitsuba's `sdfgrid` and the voxels of what it accepts:
//! any bytes are a grid or an error, never a panic, and every voxel of an accepted grid can be
//! intersected and shaded.
#![no_main]

use caustic::geometry::Ray;
use caustic::math::Vec3;
use caustic::shape::sdf::parse_vol;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(grid) = parse_vol(data) {
        assert_eq!(grid.values.len(), grid.nx * grid.ny * grid.nz);
        for v in grid.voxels().take(64) {
            let o = v.bounds().min - Vec3::new(0.3, 0.2, 1.0);
            let ray = Ray::new(o, Vec3::new(0.4, 0.3, 1.0).normalize());
            if let Some(h) = v.intersect(&ray, f32::INFINITY) {
                let s = v.surface(&ray, &h);
                assert!(s.p.is_finite() && s.ng.is_finite(), "{s:?}");
            }
        }
    }
});
