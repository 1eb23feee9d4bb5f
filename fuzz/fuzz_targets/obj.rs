//! Fuzzes the OBJ loader (`TriangleMesh::load_obj`, our line reader): any file must load or be
//! rejected, never panic, and an accepted mesh has in-range indices and finite vertices.
#![no_main]

use caustic::shape::TriangleMesh;
use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;
use std::sync::OnceLock;

fn path() -> &'static PathBuf {
    static P: OnceLock<PathBuf> = OnceLock::new();
    P.get_or_init(|| std::env::temp_dir().join(format!("caustic-fuzz-obj-{}.obj", std::process::id())))
}

fuzz_target!(|data: &[u8]| {
    std::fs::write(path(), data).unwrap();
    let Ok(mesh) = TriangleMesh::load_obj(path()) else { return };
    let n = mesh.positions.len();
    assert!(!mesh.indices.is_empty());
    assert!(mesh.indices.iter().all(|t| t.iter().all(|&i| (i as usize) < n)), "index out of range");
    assert!(mesh.positions.iter().all(|p| p.is_finite()), "non-finite vertex");
    if let Some(ns) = &mesh.normals {
        assert_eq!(ns.len(), n);
    }
    let (tris, _) = mesh.triangles(0);
    for t in tris.iter().take(64) {
        let _ = mesh.shading_normal(t.index as usize, 0.2, 0.3, 0.5);
    }
});
