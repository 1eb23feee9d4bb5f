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

/// Issue 10: hits carry uv and dp/du, dp/dv; meshes keep per-vertex uv from OBJ (v flipped as
/// Mitsuba stores it) and PLY.
#[test]
fn hits_carry_uv_and_tangents_from_obj_ply_and_quads() {
    let dir = common::scratch("uv");
    std::fs::write(dir.join("tri.obj"), "v -1 -1 0\nv 1 -1 0\nv -1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n")
        .unwrap();
    std::fs::write(
        dir.join("tri.ply"),
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
         property float u\nproperty float v\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
         -1 -1 0 0 0\n1 -1 0 1 0\n-1 1 0 0 1\n3 0 1 2\n",
    )
    .unwrap();
    let text = "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\n[[objects]]\ntype = \"mesh\"\nfile = \"tri.obj\"\n";
    let s = caustic::app::load_toml_str(text, "t.toml", &dir, &Default::default()).unwrap().scene;
    // At (-0.5, -0.5): barycentrics b1 = 0.25, b2 = 0.25.
    let h = s.intersect(&Ray::new(Vec3::new(-0.5, -0.5, 5.0), -Vec3::Z), f32::INFINITY).unwrap();
    assert!((h.uv().x - 0.25).abs() < 1e-5 && (h.uv().y - 0.75).abs() < 1e-5, "OBJ v is flipped: {}", h.uv());
    // u grows along +x: dp/du = (2, 0, 0); v (flipped) grows along -y.
    assert!(h.dpdu().abs_diff_eq(Vec3::new(2.0, 0.0, 0.0), 1e-5), "{}", h.dpdu());
    assert!(h.dpdv().abs_diff_eq(Vec3::new(0.0, -2.0, 0.0), 1e-5), "{}", h.dpdv());
    // The shading frame follows dp/du.
    assert!(h.shading_frame().x.abs_diff_eq(Vec3::X, 1e-5));
    // PLY (through a Mitsuba scene): u, v as in the file.
    let xml = "<scene version=\"3.0.0\"><sensor type=\"perspective\"><transform name=\"to_world\">\
               <lookat origin=\"0, 0, 5\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform></sensor>\
               <shape type=\"ply\"><string name=\"filename\" value=\"tri.ply\"/></shape></scene>";
    let desc = caustic::scene::mitsuba::load_mitsuba_str(xml, "t.xml", &dir, &Default::default()).unwrap();
    let s = caustic::app::prepare(desc, &Default::default()).unwrap().scene;
    let h = s.intersect(&Ray::new(Vec3::new(-0.5, -0.5, 5.0), -Vec3::Z), f32::INFINITY).unwrap();
    assert!(h.uv().abs_diff_eq(caustic::math::Vec2::new(0.25, 0.25), 1e-5), "PLY uv {}", h.uv());
    // A quad: uv along its edges.
    let text = "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\n[[objects]]\ntype = \"quad\"\n\
                corner = [-1, -1, 0]\nedge1 = [2, 0, 0]\nedge2 = [0, 4, 0]\n";
    let s = caustic::app::load_toml_str(text, "q.toml", &dir, &Default::default()).unwrap().scene;
    let h = s.intersect(&Ray::new(Vec3::new(0.5, 0.0, 5.0), -Vec3::Z), f32::INFINITY).unwrap();
    assert!(h.uv().abs_diff_eq(caustic::math::Vec2::new(0.75, 0.25), 1e-5), "quad uv {}", h.uv());
    assert!(
        h.dpdu().abs_diff_eq(Vec3::new(2.0, 0.0, 0.0), 1e-6) && h.dpdv().abs_diff_eq(Vec3::new(0.0, 4.0, 0.0), 1e-6)
    );
}

/// Issue 10: an emitting primitive knows its light, whatever order the BVH puts primitives in,
/// and light samples give radiance, pdf and whether the light is a delta light separately.
#[test]
fn emitting_primitives_know_their_light_after_the_bvh_reorders_them() {
    let mut text = String::from("[camera]\neye = [0, 0, 30]\nlook_at = [0, 0, 0]\n");
    // Several area lights among many spheres, so the BVH shuffles the primitives.
    for i in 0..5 {
        let x = i as f32 * 4.0 - 8.0;
        text += &format!(
            "[[lights]]\ntype = \"area\"\nshape = \"sphere\"\ncenter = [{x}, 5, 0]\nradius = 0.5\nintensity = {}\n",
            i + 1
        );
    }
    text += "[[lights]]\ntype = \"point\"\nposition = [0, 10, 0]\nintensity = 7\n";
    for i in 0..200 {
        text += &format!("[[objects]]\ntype = \"sphere\"\ncenter = [{}, -5, {}]\nradius = 0.3\n", i % 20, i / 20);
    }
    let s = caustic::app::load_toml_str(&text, "l.toml", std::path::Path::new("."), &Default::default()).unwrap().scene;
    for i in 0..5u32 {
        let x = i as f32 * 4.0 - 8.0;
        let h = s.intersect(&Ray::new(Vec3::new(x, 5.0, 30.0), -Vec3::Z), f32::INFINITY).unwrap();
        assert_eq!(h.light, i, "sphere light {i}");
        let caustic::light::Light::Area { shape: caustic::shape::Shape::Sphere(sp), radiance, .. } =
            s.lights[i as usize]
        else {
            panic!("light {i} is not a spherical area light");
        };
        assert!((sp.center.x - x).abs() < 1e-6 && radiance.r() == (i + 1) as f32);
        assert_eq!(s.emitted(&h, Vec3::Z), radiance);
        // An area-light sample: radiance and a solid-angle pdf, not a delta.
        let ls = s.lights[i as usize]
            .sample(Vec3::new(x, 0.0, 0.0), caustic::math::Vec2::new(0.3, 0.6), s.textures())
            .unwrap();
        assert!(!ls.delta && ls.pdf > 0.0 && ls.radiance == radiance);
    }
    let miss = s.intersect(&Ray::new(Vec3::new(0.0, -5.0, 30.0), -Vec3::Z), f32::INFINITY).unwrap();
    assert_eq!(miss.light, caustic::geometry::NO_LIGHT);
    // A point light: radiance I / d^2 with pdf 1, flagged delta.
    let ls = s.lights[5].sample(Vec3::new(0.0, 6.0, 0.0), caustic::math::Vec2::ZERO, s.textures()).unwrap();
    assert!(ls.delta && ls.pdf == 1.0 && (ls.radiance.r() - 7.0 / 16.0).abs() < 1e-6);
}
