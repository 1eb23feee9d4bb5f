//! One test per defect found in use, named after its issue; each failed before its fix.

mod common;

use caustic::integrator::path::power_heuristic;

/// Issue 16, defect 2: a path-traced floor plane under an area light dropped samples as NaN.
/// From a point far along the plane, near the horizon, the light subtends a tiny solid angle and
/// its density (about 1e23 per steradian) overflowed when squared in the power heuristic,
/// giving inf / inf.
#[test]
fn issue16_mis_weights_stay_finite_for_huge_densities() {
    assert_eq!(power_heuristic(1e23, 1.0), 1.0);
    assert!(power_heuristic(1.0, 1e23) < 1e-30);
    assert_eq!(power_heuristic(3e38, 3e38), 0.5);
    assert_eq!(power_heuristic(0.0, 0.0), 0.0);
    // Ordinary values keep their meaning.
    assert!((power_heuristic(1.0, 2.0) - 0.2).abs() < 1e-7);
    assert!((power_heuristic(3.0, 1.0) - 0.9).abs() < 1e-7);
}

fn mesh_scene(file: &str, extra: &str) -> String {
    format!(
        "[camera]\neye = [0, 0.3, 4]\nlook_at = [0, 0, 0]\n[[objects]]\ntype = \"mesh\"\nfile = \"{file}\"\n{extra}"
    )
}

fn meshes() -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/mitsuba/meshes")
}

/// Issue 16, defect 3: TOML scenes could not read PLY meshes (binary: "read error", ASCII: "no
/// triangles") and mesh errors did not say the format or the cause.
#[test]
fn issue16_toml_meshes_read_ply_and_errors_name_format_and_cause() {
    for file in ["icosphere.ply", "pyramid_ascii.ply"] {
        let s = caustic::app::load_toml_str(&mesh_scene(file, ""), "m.toml", &meshes(), &Default::default())
            .unwrap_or_else(|e| panic!("{file}: {e}"));
        assert!(s.info.triangles > 0, "{file}: no triangles");
    }
    let missing = caustic::app::load_toml_str(&mesh_scene("bunny.ply", ""), "m.toml", &meshes(), &Default::default())
        .err()
        .unwrap()
        .to_string();
    assert!(missing.contains("PLY") && missing.contains("bunny.ply") && missing.contains("No such file"), "{missing}");
    let dir = common::scratch("badmesh");
    std::fs::write(dir.join("bad.ply"), "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\n")
        .unwrap();
    std::fs::write(dir.join("bad.obj"), "v 0 0 0\nv 1 0 0\nf 1 2 9\n").unwrap();
    std::fs::write(dir.join("mesh.stl"), "solid x\n").unwrap();
    for (file, words) in
        [("bad.ply", ["PLY", "bad.ply"]), ("bad.obj", ["OBJ", "vertex"]), ("mesh.stl", [".obj or .ply", "mesh.stl"])]
    {
        let e = caustic::app::load_toml_str(&mesh_scene(file, ""), "m.toml", &dir, &Default::default())
            .err()
            .unwrap()
            .to_string();
        assert!(e.starts_with("m.toml:6:"), "{e}");
        for w in words {
            assert!(e.contains(w), "`{w}` missing: {e}");
        }
    }
}

/// Issue 16, defect 4: meshes without normals were shaded flat; Mitsuba computes smooth vertex
/// normals unless `face_normals` is set.
#[test]
fn issue16_meshes_without_normals_get_smooth_normals_unless_face_normals() {
    let dir = common::scratch("smooth");
    // Two triangles folded along x = 0: the shared vertices get the angle-weighted mean normal.
    std::fs::write(
        dir.join("fold.obj"),
        "v -1 -1 0\nv 0 -1 0.5\nv 0 1 0.5\nv -1 1 0\nv 1 -1 0\nv 1 1 0\nf 1 2 3\nf 1 3 4\nf 2 5 6\nf 2 6 3\n",
    )
    .unwrap();
    let ray = caustic::geometry::Ray::new(caustic::math::Vec3::new(-0.01, 0.0, 5.0), -caustic::math::Vec3::Z);
    let smooth = caustic::app::load_toml_str(&mesh_scene("fold.obj", ""), "m.toml", &dir, &Default::default()).unwrap();
    let h = smooth.scene.intersect(&ray, f32::INFINITY).unwrap();
    // Near the fold the shading normal has turned towards +z; the face normal has not.
    assert!(h.ns.z > h.ng.z + 0.05, "ns {} ng {}", h.ns, h.ng);
    let flat = caustic::app::load_toml_str(
        &mesh_scene("fold.obj", "face_normals = true\n"),
        "m.toml",
        &dir,
        &Default::default(),
    )
    .unwrap();
    let h = flat.scene.intersect(&ray, f32::INFINITY).unwrap();
    assert_eq!(h.ns, h.ng);
}
