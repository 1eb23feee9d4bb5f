//! Geometry as Mitsuba 3 has it: analytic cylinders and disks, instancing (a two-level BVH),
//! `serialized` meshes and `<path>` folders.
//!
//! Analytic hits through whole scenes (distance, normal, uv), instanced scenes against the same
//! geometry written out shape by shape (the same image up to rounding), Mitsuba's own renders of
//! the scenes in tests/data/geometry (mean luminance within 1%, RMSE within 1.25 times the noise
//! both images predict; see tests/data/geometry/MANIFEST.md and scripts/make_geometry_refs.py),
//! the memory of a million instances, and the loaders' errors.

mod common;

use common::mitsuba_refs::{References, mean_luminance, rmse};

use caustic::app::LoadedScene;
use caustic::geometry::{Hit, Ray, Transform};
use caustic::math::{Vec2, Vec3};
use caustic::options::{IntegratorKind, Options};
use caustic::scene::LoadOptions;
use caustic::scene::builder::SceneBuilder;
use caustic::shape::TriangleMesh;
use std::path::PathBuf;
use std::sync::LazyLock;

static REFS: LazyLock<References> = LazyLock::new(|| References::new("geometry"));

fn dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/geometry")
}

fn hit(s: &LoadedScene, o: Vec3, d: Vec3) -> Option<Hit> {
    s.scene.intersect(&Ray::new(o, d.normalize()), f32::INFINITY)
}

const CAMERA: &str = "[camera]\neye = [0, 2, 8]\nlook_at = [0, 0, 0]\n";

/// A cylinder, a disk, and the same cylinder instanced: exact distances, normals and uv.
#[test]
fn cylinder_and_disk_hits_are_analytic() {
    let text = format!(
        r#"{CAMERA}
[[objects]]
type = "cylinder"
p0 = [0, 0, 0]
p1 = [0, 2, 0]
radius = 0.5

[[objects]]
type = "disk"
center = [3, 1, 0]
normal = [0, 0, 1]
radius = 0.8

[[groups.tube.objects]]
type = "cylinder"
radius = 0.5
p1 = [0, 2, 0]

[[objects]]
type = "instance"
group = "tube"
transform = [{{ rotate = {{ axis = [0, 1, 0], degrees = 90 }} }}, {{ translate = [-3, 0, 0] }}]
"#
    );
    let s = common::scene(&text);
    assert_eq!((s.info.instances, s.info.instance_groups), (1, 1));
    // The tube, axis +y from the origin: its local frame (Mitsuba's, from the axis) has x = +x
    // and y = -z, so u = 0 faces +x and u = 1/4 faces -z.
    let h = hit(&s, Vec3::new(5.0, 0.5, 0.0), -Vec3::X).unwrap();
    assert!((h.t - 4.5).abs() < 1e-5 && h.ng.abs_diff_eq(Vec3::X, 1e-6), "{} {}", h.t, h.ng);
    assert!(h.uv().abs_diff_eq(Vec2::new(0.0, 0.25), 1e-6), "{}", h.uv());
    let h = hit(&s, Vec3::new(0.0, 1.5, -5.0), Vec3::Z).unwrap();
    assert!((h.t - 4.5).abs() < 1e-5 && h.ng.abs_diff_eq(-Vec3::Z, 1e-6));
    assert!(h.uv().abs_diff_eq(Vec2::new(0.25, 0.75), 1e-6), "{}", h.uv());
    assert!(h.dpdv().abs_diff_eq(Vec3::new(0.0, 2.0, 0.0), 1e-6));
    assert!(h.dpdu().abs_diff_eq(Vec3::new(-std::f32::consts::PI, 0.0, 0.0), 1e-5), "{}", h.dpdu());
    // From inside (through the open top): the far wall, its normal still outward.
    let h = hit(&s, Vec3::new(0.0, 3.0, 0.0), Vec3::new(0.3, -1.0, 0.0)).unwrap();
    let x = 0.5;
    assert!((h.p.x - x).abs() < 1e-5 && (h.p.y - (3.0 - x / 0.3)).abs() < 1e-4, "{}", h.p);
    assert!(h.ng.abs_diff_eq(Vec3::X, 1e-5));
    // The disk facing +z at (3, 1, 0): its local x is Frame::from_z(+z).x = +x.
    let h = hit(&s, Vec3::new(3.4, 1.4, 4.0), -Vec3::Z).unwrap();
    assert!((h.t - 4.0).abs() < 1e-5 && h.ng == Vec3::Z);
    let r = (0.4f32 * 0.4 * 2.0).sqrt() / 0.8;
    assert!(h.uv().abs_diff_eq(Vec2::new(r, 0.125), 1e-5), "{}", h.uv());
    assert!(hit(&s, Vec3::new(3.7, 1.7, 4.0), -Vec3::Z).is_none());
    // The instance: the same tube turned 90 degrees about its axis (y) and moved to x = -3.
    // The turn takes local +x to -z and local y (= -z) to -x: u = 1/4 faces -x.
    let h = hit(&s, Vec3::new(-8.0, 0.5, 0.0), Vec3::X).unwrap();
    assert!((h.t - 4.5).abs() < 1e-5 && h.ng.abs_diff_eq(-Vec3::X, 1e-5), "{} {}", h.t, h.ng);
    assert!(h.uv().abs_diff_eq(Vec2::new(0.25, 0.25), 1e-5), "{}", h.uv());
    assert!(h.dpdu().abs_diff_eq(Vec3::new(0.0, 0.0, std::f32::consts::PI), 1e-5), "{}", h.dpdu());
}

/// Objects for the instancing comparison: a knot, a sphere and a quad with three materials.
const GROUP_OBJECTS: &[(&str, &str)] = &[
    ("torus_knot", r#"segments = 96; sides = 12; radius = 0.8; tube = 0.22; material = "gold""#),
    ("sphere", r#"center = [0, 0.3, 0]; radius = 0.35; material = "blue""#),
    ("quad", r#"corner = [-1, -0.6, 1]; edge1 = [2, 0, 0]; edge2 = [0, 0, -2]; material = "green""#),
];
/// Instance transforms (TOML transform lists); spheres only get similarity transforms.
const PLACEMENTS: &[&str] = &[
    "{ scale = 0.6 }, { rotate = { axis = [1, 0, 0], degrees = 30 } }, { translate = [-1.4, 0.6, 0] }",
    "{ scale = 0.5 }, { rotate = { axis = [0, 1, 1], degrees = -70 } }, { translate = [1.3, 0.7, 0.4] }",
    "{ scale = 0.45 }, { rotate = { axis = [0, 1, 0], degrees = 120 } }, { translate = [0, 0.5, -1.5] }",
    "{ scale = 0.35 }, { translate = [0.2, 1.9, 0.8] }",
];

fn instancing_scenes() -> (String, String) {
    let head = r#"[render]
width = 48
height = 48
integrator = "path"
max_depth = 4
spp = 64

[camera]
eye = [0, 2.2, 3.4]
look_at = [0, 0.8, -0.3]
fov = 55

[materials.gold]
type = "diffuse"
color = [0.8, 0.55, 0.2]
[materials.blue]
type = "plastic"
color = [0.1, 0.2, 0.6]
[materials.green]
type = "diffuse"
color = [0.2, 0.6, 0.25]
[materials.floor]
type = "diffuse"
color = [0.5, 0.5, 0.5]

[[lights]]
type = "point"
position = [2, 6, 4]
intensity = 60

[[lights]]
type = "area"
corner = [-2, 4, -1]
edge1 = [1, 0, 0]
edge2 = [0, 0, 1]
intensity = 20

[[objects]]
type = "plane"
point = [0, -0.4, 0]
material = "floor"
"#;
    let mut instanced = head.to_string();
    for (kind, keys) in GROUP_OBJECTS {
        instanced += &format!("\n[[groups.thing.objects]]\ntype = \"{kind}\"\n{}\n", keys.replace("; ", "\n"));
    }
    let mut flat = head.to_string();
    for p in PLACEMENTS {
        instanced += &format!("\n[[objects]]\ntype = \"instance\"\ngroup = \"thing\"\ntransform = [{p}]\n");
        for (kind, keys) in GROUP_OBJECTS {
            flat += &format!("\n[[objects]]\ntype = \"{kind}\"\n{}\ntransform = [{p}]\n", keys.replace("; ", "\n"));
        }
    }
    (instanced, flat)
}

/// Instanced and flattened renders with the same seed follow the same random numbers, so they
/// differ only where rounding changes a path: far less than the noise of one seed against
/// another. Returns (mean relative difference, rmse between them, the noise).
fn compare_twins(instanced: &LoadedScene, flat: &LoadedScene, other_seed: &LoadedScene) -> (f64, f64, f64) {
    let (a, b) = (instanced.render().image, flat.render().image);
    let c = other_seed.render().image;
    let noise = rmse(&a, &c) / 2f64.sqrt();
    let rel = mean_luminance(&a) / mean_luminance(&b) - 1.0;
    (rel, rmse(&a, &b), noise)
}

#[test]
fn toml_instances_render_as_the_flattened_scene() {
    let (instanced, flat) = instancing_scenes();
    let o = Options::default();
    let (i, f) = (common::scene_with(&instanced, &o), common::scene_with(&flat, &o));
    assert_eq!((i.info.instances, f.info.instances), (4, 0));
    // The group's triangles are stored once.
    assert_eq!(i.info.triangles * 4, f.info.triangles);
    // The instances fill a good part of the view.
    let cam = &i.scene.camera;
    let seen = (0..48 * 48)
        .filter(|k| {
            let r = cam.generate_ray(Vec2::new((k % 48) as f32 + 0.5, (k / 48) as f32 + 0.5), Vec2::splat(0.5));
            i.scene.instances.intersect(&r, f32::INFINITY).is_some()
        })
        .count();
    eprintln!("instances seen by {seen} of {} pixels", 48 * 48);
    assert!(seen > 48 * 48 / 5, "{seen}");
    let other = common::scene_with(&instanced, &Options { seed: Some(7), ..o });
    let (rel, diff, noise) = compare_twins(&i, &f, &other);
    eprintln!("TOML instanced vs flattened: mean {:+.4}%, rmse {diff:.3e} (noise {noise:.3e})", rel * 100.0);
    assert!(rel.abs() < 0.002 && diff < 0.2 * noise, "mean {rel}, rmse {diff} vs noise {noise}");
}

/// Photon mapping and SPPM trace photons through instances too. Caustic photons aim at the
/// instances' bounds rather than at each object's, so the scenes need not agree to rounding;
/// measured: photon mapping differs by 0.004 of its noise, SPPM by 0.09.
#[test]
fn photon_mapping_and_sppm_see_instances_as_the_flattened_scene() {
    let (instanced, flat) = instancing_scenes();
    for (kind, spp) in [(IntegratorKind::Photon, 16), (IntegratorKind::Sppm, 64)] {
        let o = Options { integrator: Some(kind), spp: Some(spp), ..Default::default() };
        let (i, f) = (common::scene_with(&instanced, &o), common::scene_with(&flat, &o));
        let other = common::scene_with(&instanced, &Options { seed: Some(7), ..o });
        let (rel, diff, noise) = compare_twins(&i, &f, &other);
        eprintln!("{kind:?} instanced vs flattened: mean {:+.3}%, rmse {diff:.3e} (noise {noise:.3e})", rel * 100.0);
        assert!(rel.abs() < 0.005 && diff < 0.5 * noise, "{kind:?}: mean {rel}, rmse {diff} vs noise {noise}");
    }
}

#[test]
fn mitsuba_instances_render_as_the_flattened_scene() {
    let (i, f) = (load_xml("instances", 48, 64, 1), load_xml("instances_flat", 48, 64, 1));
    assert_eq!((i.info.instances, i.info.instance_groups, f.info.instances), (6, 2, 0));
    let (rel, diff, noise) = compare_twins(&i, &f, &load_xml("instances", 48, 64, 2));
    eprintln!("Mitsuba instanced vs flattened: mean {:+.4}%, rmse {diff:.3e} (noise {noise:.3e})", rel * 100.0);
    assert!(rel.abs() < 0.002 && diff < 0.2 * noise, "mean {rel}, rmse {diff} vs noise {noise}");
}

// --- Mitsuba references ----------------------------------------------------------------------

fn load_xml(case: &str, res: u32, spp: u32, seed: u64) -> LoadedScene {
    let defines = vec![("res".to_string(), res.to_string()), ("spp".to_string(), spp.to_string())];
    let o = Options { seed: Some(seed), ..Default::default() };
    caustic::app::load(
        &dir().join(format!("{case}.xml")),
        &LoadOptions { defines, strict: true, ..Default::default() },
        &o,
    )
    .unwrap_or_else(|e| panic!("{case} failed to load: {e}"))
}

/// Renders `case` with two seeds and compares with Mitsuba's image; returns a failure or None.
fn compare_with_mitsuba(case: &str, spp: u32) -> Option<String> {
    let (a, b) = (load_xml(case, 64, spp, 1).render().image, load_xml(case, 64, spp, 2).render().image);
    let (rel, ratio, line) = REFS.judge(case, &a, &b);
    (rel.abs() >= 0.01 || ratio >= 1.25).then_some(line)
}

#[test]
fn geometry_scenes_match_mitsuba() {
    let failures: Vec<String> = [("instances", 256), ("cylinder_disk", 256), ("serialized", 256)]
        .into_iter()
        .filter_map(|(case, spp)| compare_with_mitsuba(case, spp))
        .collect();
    assert!(failures.is_empty(), "differ from Mitsuba:\n{}", failures.join("\n"));
}

// --- serialized meshes and <path> -------------------------------------------------------------

/// The committed files (written by the Python script, checked by Mitsuba's reader) read back as
/// written: counts, uv not flipped, the file's face-normals flag.
#[test]
fn committed_serialized_files_read_as_written() {
    let torus = caustic::shape::mesh::load_serialized(&dir().join("meshes/shapes.serialized"), 1).unwrap();
    assert_eq!((torus.count, torus.name.as_str()), (2, "torus"));
    assert_eq!((torus.mesh.positions.len(), torus.mesh.indices.len()), (49 * 25, 2 * 48 * 24));
    let uvs = torus.mesh.uvs.as_ref().unwrap();
    assert_eq!(uvs[1], Vec2::new(0.0, 1.0 / 24.0));
    assert!(torus.mesh.positions[0].abs_diff_eq(Vec3::new(1.35, 0.0, 0.0), 1e-6));
    assert!(!torus.face_normals && torus.mesh.normals.is_some());
    let tet = caustic::shape::mesh::load_serialized(&dir().join("meshes/shapes.serialized"), 0).unwrap();
    assert_eq!((tet.mesh.positions.len(), tet.mesh.indices.len(), tet.name.as_str()), (4, 4, "tetrahedron"));
    let oct = caustic::shape::mesh::load_serialized(&dir().join("meshes/flat_f64_v3.serialized"), 0).unwrap();
    assert!(oct.face_normals && oct.mesh.normals.is_none() && oct.name.is_empty());
    assert_eq!(oct.mesh.positions[5], -Vec3::Z);
    // A TOML `mesh` reads the first mesh of a serialized file.
    let s = common::scene(&format!(
        "{CAMERA}[[objects]]\ntype = \"mesh\"\nfile = \"tests/data/geometry/meshes/shapes.serialized\"\n"
    ));
    assert_eq!(s.info.triangles, 4);
}

fn mitsuba_str(body: &str, base: &std::path::Path) -> Result<caustic::scene::SceneDescription, String> {
    let sensor = r#"<sensor type="perspective"><transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform></sensor>"#;
    let text = format!(r#"<scene version="3.0.0">{sensor}{body}</scene>"#);
    caustic::scene::mitsuba::load_mitsuba_str(&text, "test.xml", base, &LoadOptions::default())
        .map_err(|e| e.to_string())
}

fn built(desc: caustic::scene::SceneDescription) -> LoadedScene {
    caustic::app::prepare(desc, &Options::default()).unwrap()
}

/// The `face_normals` parameter shades a serialized mesh flat, as on the other meshes; without
/// it the mesh gets smooth normals, even when the file's own face-normals flag is set (Mitsuba
/// 3.9.1 ignores that flag: `has_vertex_normals()` is true for flat_f64_v3.serialized).
#[test]
fn face_normals_cover_serialized_meshes() {
    let base = dir();
    let shape = |file: &str, extra: &str| {
        format!(r#"<shape type="serialized"><string name="filename" value="meshes/{file}"/>{extra}</shape>"#)
    };
    for (body, flat) in [
        (shape("flat_f64_v3.serialized", ""), false),
        (shape("flat_f64_v3.serialized", r#"<boolean name="face_normals" value="true"/>"#), true),
        (shape("shapes.serialized", ""), false),
        (shape("shapes.serialized", r#"<boolean name="face_normals" value="true"/>"#), true),
    ] {
        let s = built(mitsuba_str(&body, &base).unwrap());
        let h = hit(&s, Vec3::new(0.11, 0.07, 5.0), -Vec3::Z).unwrap();
        assert_eq!(h.ns.abs_diff_eq(h.ng, 1e-6), flat, "{body}: ns {} ng {}", h.ns, h.ng);
    }
}

/// `<path>` folders are searched newest first, before the scene's own folder, and a relative
/// folder is taken from the scene file's folder (what Mitsuba 3.9.1 does, checked with meshes
/// of the same name in three folders).
#[test]
fn path_elements_add_search_folders() {
    let root = common::scratch("geometry-path");
    for (sub, z) in [("", 1.0), ("a", 2.0), ("b", 3.0)] {
        let d = root.join(sub);
        std::fs::create_dir_all(&d).unwrap();
        let mesh = TriangleMesh {
            positions: vec![Vec3::new(-5.0, -5.0, z), Vec3::new(5.0, -5.0, z), Vec3::new(0.0, 5.0, z)],
            normals: None,
            uvs: None,
            indices: vec![[0, 1, 2]],
            attributes: Vec::new(),
        };
        std::fs::write(d.join("m.obj"), obj_text(&mesh)).unwrap();
    }
    let shape = r#"<shape type="obj"><string name="filename" value="m.obj"/></shape>"#;
    for (paths, z) in [("", 1.0), (r#"<path value="a"/>"#, 2.0), (r#"<path value="a"/><path value="b"/>"#, 3.0)] {
        let s = built(mitsuba_str(&format!("{paths}{shape}"), &root).unwrap());
        assert!((s.scene.bounds().max.z - z).abs() < 1e-6, "{paths}: {:?}", s.scene.bounds());
    }
    // A missing folder is an error, as in Mitsuba ("<path>: folder not found").
    let Err(e) = mitsuba_str(&format!(r#"<path value="nowhere"/>{shape}"#), &root) else {
        panic!("a <path> to a missing folder must be refused")
    };
    let e = e.to_string();
    assert!(e.contains("nowhere") && e.contains("not found") && e.contains("test.xml:1:"), "{e}");
    // `<include>` files are searched in the `<path>` folders before them too.
    std::fs::write(root.join("b").join("inc.xml"), format!(r#"<scene version="3.0.0">{shape}</scene>"#)).unwrap();
    let s = built(mitsuba_str(r#"<path value="b"/><include filename="inc.xml"/>"#, &root).unwrap());
    assert!((s.scene.bounds().max.z - 3.0).abs() < 1e-6, "{:?}", s.scene.bounds());
    let Err(e) = mitsuba_str(r#"<include filename="inc.xml"/><path value="b"/>"#, &root) else {
        panic!("an <include> before its <path> must not be found")
    };
    let e = e.to_string();
    assert!(e.contains("inc.xml"), "{e}");
}

fn obj_text(m: &TriangleMesh) -> String {
    let mut s = String::new();
    for p in &m.positions {
        s += &format!("v {} {} {}\n", p.x, p.y, p.z);
    }
    for t in &m.indices {
        s += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    s
}

// --- errors -----------------------------------------------------------------------------------

#[test]
fn loaders_refuse_what_instancing_cannot_do() {
    let base = dir();
    let sphere = r#"<shape type="sphere"/>"#;
    let lit = r#"<shape type="sphere"><emitter type="area"/></shape>"#;
    for (body, want) in [
        (format!(r#"<shape type="shapegroup" id="g">{lit}</shape><shape type="instance"><ref id="g"/></shape>"#), "emitters inside a shapegroup"),
        (format!(r#"<shape type="shapegroup" id="g"><shape type="shapegroup" id="h">{sphere}</shape></shape>"#), "inside another shapegroup"),
        (r#"<shape type="instance"/>"#.to_string(), "exactly one shapegroup"),
        (format!(r#"<bsdf type="diffuse" id="m"/>{sphere}<shape type="instance"><ref id="m"/></shape>"#), "exactly one shapegroup"),
        (format!(r#"{sphere}<shape type="sphere" id="s"/><shape type="instance"><ref id="s"/></shape>"#), "must refer to a <shape type=\"shapegroup\">"),
        (format!(r#"<shape type="shapegroup" id="g">{sphere}</shape><shape type="instance"><ref id="g"/><transform name="to_world"><scale value="0"/></transform></shape>"#), "singular"),
        (r#"<shape type="serialized"><string name="filename" value="meshes/shapes.serialized"/><integer name="shape_index" value="2"/></shape>"#.to_string(), "out of range: the file holds 2 meshes"),
        (r#"<shape type="serialized"><string name="filename" value="meshes/torus.ply"/></shape>"#.to_string(), "0x041C"),
        (r#"<shape type="cylinder"><float name="radius" value="-1"/></shape>"#.to_string(), "radius must be positive"),
        (r#"<path/>"#.to_string(), "`value`"),
    ] {
        let e = match mitsuba_str(&body, &base).and_then(|d| caustic::app::prepare(d, &Options::default()).map_err(|e| e.to_string())) {
            Ok(_) => panic!("accepted: {body}"),
            Err(e) => e,
        };
        assert!(e.contains(want) && e.contains("test.xml:1:"), "{body}\n  gave: {e}");
    }
    let group = "[groups.g]\nobjects = [{ type = \"sphere\" }]\n";
    for (text, want) in [
        (format!("{group}[[objects]]\ntype = \"instance\"\ngroup = \"h\"\n"), "no group named `h` (defined: g)"),
        ("[[objects]]\ntype = \"instance\"\n".to_string(), "an instance needs `group`"),
        ("[groups.g]\nobjects = [{ type = \"plane\" }]\n".to_string(), "a plane is unbounded"),
        (
            "[groups.g]\nobjects = [{ type = \"sphere\", emission = 2 }]\n".to_string(),
            "an object in a group cannot emit",
        ),
        (format!("{group}[groups.h]\nobjects = [{{ type = \"instance\", group = \"g\" }}]\n"), "cannot hold instances"),
        ("[groups.g]\nobjects = []\n".to_string(), "group `g` has no objects"),
        ("[groups.g]\nshapes = []\n".to_string(), "unknown key `shapes` in group `g`"),
        (
            format!("{group}[[objects]]\ntype = \"instance\"\ngroup = \"g\"\nmaterial = \"x\"\n"),
            "unknown key `material`",
        ),
        (
            "[[objects]]\ntype = \"cylinder\"\ntransform = [{ scale = [2, 1, 1] }]\n".to_string(),
            "uniformly across its axis",
        ),
        ("[[objects]]\ntype = \"cylinder\"\np1 = [0, 0, 0]\n".to_string(), "distinct"),
        ("[[objects]]\ntype = \"disk\"\nnormal = [0, 0, 0]\n".to_string(), "zero-length"),
    ] {
        let full = format!("{CAMERA}{text}");
        let e = match caustic::app::load_toml_str(&full, "test.toml", &base, &Options::default()) {
            Ok(_) => panic!("accepted: {text}"),
            Err(e) => e.to_string(),
        };
        assert!(e.contains(want) && e.contains("test.toml:"), "{text}\n  gave: {e}");
    }
}

// --- memory -----------------------------------------------------------------------------------

/// A million instances of a 10,000-triangle mesh fit in the memory of one mesh plus the
/// transforms (two 3 x 4 matrices each) and the top-level tree, and they are all there.
#[test]
fn a_million_instances_cost_the_transforms_not_the_mesh() {
    let (scene, info) = million_instances(1000);
    assert_eq!(info.instances, 1_000_000);
    let (one, _) = million_instances(1);
    let per_instance = (scene.instances.memory_bytes() - one.instances.memory_bytes()) as f64 / (1e6 - 1.0);
    eprintln!(
        "a million instances: {:.1} MB in all, one: {:.2} MB, {per_instance:.1} bytes per further instance",
        scene.instances.memory_bytes() as f64 / 1e6,
        one.instances.memory_bytes() as f64 / 1e6
    );
    // 100 bytes of transforms and index, and at most two 32-byte nodes of the top-level tree
    // (a binary tree over n instances has fewer than 2n nodes).
    assert!(per_instance <= 100.0 + 64.0, "{per_instance} bytes per instance");
    // A ray along each of a few rows hits the first instance there.
    for k in [0, 500, 999] {
        let z = k as f32 * 3.0;
        let h = scene.intersect(&Ray::new(Vec3::new(-10.0, 0.0, z), Vec3::X), f32::INFINITY).unwrap();
        assert!(h.p.x < 2.0 && (h.p.z - z).abs() < 1.5, "{} for row {k}", h.p);
    }
    assert!(scene.bvh.is_empty() && info.triangles == 10_000);
}

/// `n` x `n` instances of a 10,000-triangle knot on a grid, each turned differently.
fn million_instances(n: usize) -> (caustic::scene::Scene, caustic::scene::desc::LoadInfo) {
    let mut b = SceneBuilder::new();
    let m = b.add_material("m", caustic::material::Material::default());
    let g = b.begin_group().unwrap();
    let mesh = TriangleMesh::torus_knot(2, 3, 1.0, 0.3, 250, 20);
    assert_eq!(mesh.indices.len(), 10_000);
    b.add_mesh(mesh, m, "knot");
    b.end_group();
    for i in 0..n * n {
        let (x, z) = ((i % n) as f32 * 3.0, (i / n) as f32 * 3.0);
        let t = Transform::rotate(Vec3::Y, (i % 360) as f32).then(Transform::translate(Vec3::new(x, 0.0, z)));
        b.add_instance(g, &t).unwrap();
    }
    let cam = caustic::camera::CameraDesc {
        placement: caustic::camera::Placement::LookAt {
            eye: Vec3::new(0.0, 5.0, -10.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
        },
        fov: caustic::camera::FieldOfView::Angle { degrees: 45.0, axis: caustic::camera::FovAxis::Y },
        lens_radius: 0.0,
        focal_distance: 1.0,
        principal_point: caustic::math::Vec2::ZERO,
    }
    .build(4, 4);
    b.finish(cam).unwrap()
}

// --- robust ray origins -------------------------------------------------------------------------

mod spawned {
    use caustic::accel::{Instance, Instances};
    use caustic::geometry::{NO_LIGHT, Ray, Transform};
    use caustic::math::{Vec2, Vec3};
    use caustic::shape::{Cylinder, Disk, Primitive, RayShear, Shape, Triangle};
    use proptest::prelude::*;

    /// A coordinate of magnitude 1e-4 to 1e6, either sign.
    fn coord() -> impl Strategy<Value = f32> {
        (-4.0f32..6.0, any::<bool>()).prop_map(|(e, neg)| if neg { -(10f32.powf(e)) } else { 10f32.powf(e) })
    }

    fn point() -> impl Strategy<Value = Vec3> {
        (coord(), coord(), coord()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    fn unit_from(u: f32, v: f32) -> Vec3 {
        let z = 1.0 - 2.0 * u;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = std::f32::consts::TAU * v;
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }

    /// Spawns rays from the first hit of `ray` on `shape` (through a one-primitive BVH, or an
    /// instance of it under `t`): eight directions, the mirror, straight on and four grazing
    /// ones. `check(cos, spawned ray, t_again)` judges each.
    fn spawn_from(
        shape: Shape,
        instance: Option<&Transform>,
        ray: Ray,
        dirs: &[(f32, f32)],
        mut check: impl FnMut(f32, &Ray, Option<f32>) -> Result<(), TestCaseError>,
    ) -> Result<usize, TestCaseError> {
        let prims = vec![Primitive { shape, material: 0, light: NO_LIGHT }];
        type Trace = Box<dyn Fn(&Ray) -> Option<f32>>;
        let (sp, trace): (_, Trace) = match instance {
            None => {
                let Some(h) = shape.intersect(&ray, &RayShear::new(&ray), f32::INFINITY) else { return Ok(0) };
                let bvh = caustic::accel::Bvh::build(prims, &[]);
                (shape.surface(&ray, &h, &[]), Box::new(move |r: &Ray| bvh.intersect(r, f32::INFINITY).map(|h| h.1.t)))
            }
            Some(t) => {
                let Some(inst) = Instance::new(0, t) else { return Ok(0) };
                let all = Instances::build(vec![prims.into()], vec![inst], &[]);
                let Some(h) = all.intersect(&ray, f32::INFINITY) else { return Ok(0) };
                let sp = all.surface(&h, &[]).0;
                (sp, Box::new(move |r: &Ray| all.intersect(r, f32::INFINITY).map(|h| h.t)))
            }
        };
        let n = sp.ng;
        prop_assert!(sp.p.is_finite() && sp.p_error.is_finite() && n.is_finite(), "{sp:?}");
        let d = ray.d;
        let tangent = n.any_orthonormal_vector();
        let mut ws: Vec<Vec3> = dirs.iter().map(|&(u, v)| unit_from(u, v)).collect();
        ws.push(d - 2.0 * d.dot(n) * n);
        ws.push(d);
        for g in [1e-2f32, 1e-3] {
            ws.push((tangent + n * g).normalize());
            ws.push((tangent - n * g).normalize());
        }
        let mut spawned = 0;
        for w in ws {
            let cos = w.dot(n);
            if cos == 0.0 || !w.is_finite() {
                continue;
            }
            let r = Ray::spawn(sp.p, sp.p_error, n, w, 0.0);
            spawned += 1;
            check(cos, &r, trace(&r)).map_err(|e| {
                TestCaseError::fail(format!("{e}\nfrom p={} (error {}), n={n}, along {w}", sp.p, sp.p_error))
            })?;
        }
        Ok(spawned)
    }

    fn config(cases: u32) -> ProptestConfig {
        ProptestConfig { cases, failure_persistence: None, ..ProptestConfig::default() }
    }

    fn dirs() -> impl Strategy<Value = Vec<(f32, f32)>> {
        prop::collection::vec((0.0f32..1.0, 0.0f32..1.0), 8)
    }

    type Pair = (f32, f32);
    type Triple = (f32, f32, f32);

    fn disk_cases() -> impl Strategy<Value = (Vec3, Triple, Triple, Pair, Triple, Vec<Pair>)> {
        let axis = (0.0f32..1.0, 0.0f32..1.0, -4.0f32..4.0);
        (point(), axis.clone(), axis, (0.0f32..1.0, 0.0f32..1.0), (0.0f32..1.0, 0.0f32..1.0, -3.0f32..6.0), dirs())
    }

    /// A disk is flat: a ray leaving it to either side never meets it again. Returns the rays
    /// spawned.
    fn disk_case(
        (c, a, b, at, from, dirs): (Vec3, Triple, Triple, Pair, Triple, Vec<Pair>),
    ) -> Result<usize, TestCaseError> {
        let (a, b) = (unit_from(a.0, a.1) * 10f32.powf(a.2), unit_from(b.0, b.1) * 10f32.powf(b.2));
        let m = glam::Mat4::from_cols(
            a.extend(0.0),
            b.extend(0.0),
            a.cross(b).normalize_or_zero().extend(0.0),
            c.extend(1.0),
        );
        let Some(disk) = Disk::from_transform(&Transform::from_mat4(m), false) else { return Ok(0) };
        let local = caustic::sampling::warp::concentric_disk(Vec2::new(at.0, at.1)) * 0.98;
        let target = c + a * local.x + b * local.y;
        let o = target + unit_from(from.0, from.1) * 10f32.powf(from.2);
        let ray = Ray::new(o, (target - o).normalize());
        spawn_from(Shape::Disk(disk), None, ray, &dirs, |_, _, t| {
            prop_assert!(t.is_none(), "re-hit at {t:?}");
            Ok(())
        })
    }

    fn cylinder_cases() -> impl Strategy<Value = (Vec3, Triple, f32, Pair, Triple, Vec<Pair>)> {
        (
            point(),
            (0.0f32..1.0, 0.0f32..1.0, -3.0f32..1.0),
            -3.0f32..1.0,
            (0.02f32..0.98, 0.0f32..1.0),
            (0.0f32..1.0, 0.0f32..1.0, -3.0f32..6.0),
            dirs(),
        )
    }

    /// A tube: leaving outwards nothing is hit; going in, the far wall (or nothing, out of an
    /// open end), never the start.
    fn cylinder_case(
        (p0, axis, radius, at, from, dirs): (Vec3, Triple, f32, Pair, Triple, Vec<Pair>),
    ) -> Result<usize, TestCaseError> {
        // Sizes relative to the position, as for spheres in tests/robustness.rs: a tube much
        // thinner than the spacing of floats there cannot be placed.
        let size = p0.abs().max_element();
        let axis = unit_from(axis.0, axis.1) * 10f32.powf(axis.2) * size;
        let r = 10f32.powf(radius) * size;
        let Ok((c, _)) = Cylinder::from_mitsuba(p0, p0 + axis, r, &Transform::IDENTITY, false) else { return Ok(0) };
        let s = c.sample_area(Vec2::new(at.0, at.1));
        let o = s.p + (unit_from(from.0, from.1) + s.n * 1.01) * 10f32.powf(from.2);
        let ray = Ray::new(o, (s.p - o).normalize());
        let e = axis.normalize();
        spawn_from(Shape::Cylinder(c), None, ray, &dirs, |cos, r, t| {
            if cos > 0.0 {
                prop_assert!(t.is_none(), "outward ray re-hit at {t:?}");
            } else if cos < -0.01 {
                // The far wall seen from the surface point, and from the spawned origin (moved
                // off the surface: at grazing angles that lengthens the chord a lot).
                let wp = r.d - e * r.d.dot(e);
                let from_surface = 2.0 * c.radius * -cos / wp.length_squared();
                let q = r.o - c.p0;
                let qp = q - e * q.dot(e);
                let (a, b, cc) = (wp.length_squared(), qp.dot(wp), qp.length_squared() - c.radius * c.radius);
                let from_origin = (-b + (b * b - a * cc).max(0.0).sqrt()) / a;
                prop_assert!(
                    t.is_none_or(|t| t > 0.5 * from_surface && t < 1.5 * from_origin.max(from_surface)),
                    "inward ray: t={t:?}, far wall at {from_surface} ({from_origin} from the spawned origin)"
                );
            }
            Ok(())
        })
    }

    fn instance_cases() -> impl Strategy<Value = (Vec<f32>, Vec3, f32, Pair, Triple, Vec<Pair>)> {
        (
            prop::collection::vec(-3.0f32..3.0, 9),
            point(),
            -3.0f32..3.0,
            (0.0f32..1.0, 0.0f32..1.0),
            (0.0f32..1.0, 0.0f32..1.0, -3.0f32..5.0),
            dirs(),
        )
    }

    /// Instanced triangles under any invertible transform (shears, mirrors, uneven scales, far
    /// translations): rays leaving them never meet them again.
    fn instance_case(
        (m, t, scale, at, from, dirs): (Vec<f32>, Vec3, f32, Pair, Triple, Vec<Pair>),
    ) -> Result<usize, TestCaseError> {
        let lin = glam::Mat3::from_cols_slice(&m) * 10f32.powf(scale);
        if lin.determinant().abs() < 1e-3 * 10f32.powf(3.0 * scale) {
            return Ok(0);
        }
        let tr = Transform::from_mat4(glam::Mat4::from_cols(
            lin.x_axis.extend(0.0),
            lin.y_axis.extend(0.0),
            lin.z_axis.extend(0.0),
            t.extend(1.0),
        ));
        let tri = Triangle::new(Vec3::new(-1.0, -1.0, 0.2), Vec3::new(1.5, -0.5, -0.1), Vec3::new(0.0, 1.0, 0.0));
        let (u, v) = if at.0 + at.1 > 1.0 { (1.0 - at.0, 1.0 - at.1) } else { at };
        let target = tr.point(tri.p[0] * (1.0 - u - v) + tri.p[1] * u + tri.p[2] * v);
        let o = target + unit_from(from.0, from.1) * 10f32.powf(from.2) * 10f32.powf(scale);
        if !(target.is_finite() && o.is_finite()) || (target - o).length() == 0.0 {
            return Ok(0);
        }
        let ray = Ray::new(o, (target - o).normalize());
        spawn_from(Shape::Triangle(tri), Some(&tr), ray, &dirs, |_, _, t| {
            prop_assert!(t.is_none(), "re-hit at {t:?}");
            Ok(())
        })
    }

    proptest! {
        #![proptest_config(config(500))]

        #[test]
        fn rays_leave_disks(case in disk_cases()) {
            disk_case(case)?;
        }

        #[test]
        fn rays_leave_cylinders(case in cylinder_cases()) {
            cylinder_case(case)?;
        }

        #[test]
        fn rays_leave_instanced_triangles(case in instance_cases()) {
            instance_case(case)?;
        }
    }

    /// The properties count only cases whose first ray hits; this checks that most do, with a
    /// fixed seed, so they really test thousands of spawned rays.
    #[test]
    fn spawned_cases_mostly_hit() {
        use proptest::test_runner::TestRunner;
        use std::sync::atomic::{AtomicUsize, Ordering};
        let count = |name: &str, run: &dyn Fn(&mut TestRunner, &AtomicUsize)| {
            let mut runner = TestRunner::new_with_rng(
                config(500),
                proptest::test_runner::TestRng::deterministic_rng(Default::default()),
            );
            let spawned = AtomicUsize::new(0);
            run(&mut runner, &spawned);
            let n = spawned.into_inner();
            eprintln!("{name}: {n} rays spawned in 500 cases");
            assert!(n >= 500 * 6, "{name}: only {n} rays spawned");
        };
        count("disks", &|r, n| {
            r.run(&disk_cases(), |c| {
                disk_case(c).map(|k| {
                    n.fetch_add(k, Ordering::Relaxed);
                })
            })
            .unwrap()
        });
        count("cylinders", &|r, n| {
            r.run(&cylinder_cases(), |c| {
                cylinder_case(c).map(|k| {
                    n.fetch_add(k, Ordering::Relaxed);
                })
            })
            .unwrap()
        });
        count("instanced triangles", &|r, n| {
            r.run(&instance_cases(), |c| {
                instance_case(c).map(|k| {
                    n.fetch_add(k, Ordering::Relaxed);
                })
            })
            .unwrap()
        });
    }
}
