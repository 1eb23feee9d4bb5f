//! Ray-box intersections (boxes are built by the scene loader from six quads) and transforms.

mod common;

use caustic::geometry::Ray;
use caustic::math::Vec3;

const BOX: &str = r#"
[camera]
eye = [0, 0, 5]
look_at = [0, 0, 0]
[[objects]]
type = "box"
min = [-1, -2, -3]
max = [1, 2, 3]
"#;

#[test]
fn box_hit_miss_inside_tangent_behind() {
    let s = common::scene(BOX).scene;
    let hit = |o: Vec3, d: Vec3| s.intersect(&Ray::new(o, d.normalize()), f32::INFINITY);
    // Hit the +z face head-on; its outward normal is +z.
    let h = hit(Vec3::new(0.2, 0.3, 10.0), -Vec3::Z).unwrap();
    assert!((h.t - 7.0).abs() < 1e-5 && h.ng.abs_diff_eq(Vec3::Z, 1e-6));
    // Miss beside it.
    assert!(hit(Vec3::new(1.5, 0.0, 10.0), -Vec3::Z).is_none());
    // From inside: the far wall, seen from its back side.
    let h = hit(Vec3::ZERO, Vec3::X).unwrap();
    assert!((h.t - 1.0).abs() < 1e-6 && h.ng.abs_diff_eq(Vec3::X, 1e-6) && !h.is_front(Vec3::X));
    // Behind the origin: nothing.
    assert!(hit(Vec3::new(0.0, 0.0, 10.0), Vec3::Z).is_none());
    // Tangent along a face (in the plane y = 2): at most an edge hit, never a hit elsewhere.
    if let Some(h) = hit(Vec3::new(0.0, 2.0, 10.0), -Vec3::Z) {
        assert!((h.p.y - 2.0).abs() < 1e-5);
    }
    // Every outward normal points away from the centre.
    for d in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
        let h = hit(d * 20.0, -d).unwrap();
        assert!(h.ng.abs_diff_eq(d, 1e-6), "face {d}: normal {}", h.ng);
    }
}

#[test]
fn mirrored_box_keeps_outward_normals() {
    let s = common::scene(&BOX.replace(
        "max = [1, 2, 3]",
        "max = [1, 2, 3]\ntransform = [{ scale = [-1, 1, 1] }, { rotate = { axis = [0, 1, 0], degrees = 90 } }]",
    ))
    .scene;
    for d in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
        let h = s.intersect(&Ray::new(d * 20.0, -d), f32::INFINITY).unwrap();
        assert!(h.ng.dot(d) > 0.999, "face {d}: normal {}", h.ng);
    }
}

#[test]
fn transformed_sphere_moves_and_scales() {
    let s = common::scene(
        "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\n[[objects]]\ntype = \"sphere\"\ntransform = [{ scale = 2 }, { translate = [0, 0, -10] }]\n",
    )
    .scene;
    let h = s.intersect(&Ray::new(Vec3::ZERO, -Vec3::Z), f32::INFINITY).unwrap();
    assert!((h.t - 8.0).abs() < 1e-5);
}

#[test]
fn obj_mesh_loads_with_smooth_normals() {
    let dir = common::scratch("obj");
    std::fs::write(
        dir.join("tri.obj"),
        "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 1\nvn 0.6 0 0.8\nf 1//1 2//2 3//3\n",
    )
    .unwrap();
    let text = "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\n[[objects]]\ntype = \"mesh\"\nfile = \"tri.obj\"\n";
    let s = caustic::app::load_toml_str(text, "t.toml", &dir, &Default::default()).unwrap().scene;
    let h = s.intersect(&Ray::new(Vec3::new(0.0, 0.99, 5.0), -Vec3::Z), f32::INFINITY).unwrap();
    // Near the third vertex the shading normal leans towards its normal (0.6, 0, 0.8).
    assert!(h.ns.x > 0.5, "{}", h.ns);
    assert!(h.ng.abs_diff_eq(Vec3::Z, 1e-6));
}
