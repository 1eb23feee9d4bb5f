//! Fuzzes the reader of Mitsuba's `serialized` meshes: any bytes give an error or a mesh whose
//! indices are in range and whose vertices are finite, never a panic. Each input is read as
//! mesh 0 and mesh 1.
#![no_main]

use caustic::shape::mesh::parse_serialized;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    for index in 0..2 {
        if let Ok(s) = parse_serialized(data, index) {
            let n = s.mesh.positions.len();
            assert!(s.mesh.indices.iter().flatten().all(|&i| (i as usize) < n));
            assert!(s.mesh.positions.iter().all(|p| p.is_finite()));
            assert!(s.mesh.normals.as_ref().is_none_or(|v| v.len() == n));
            assert!(s.mesh.uvs.as_ref().is_none_or(|v| v.len() == n));
        }
    }
});
