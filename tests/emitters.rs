//! Emitters as Mitsuba 3 has them: emitting meshes and spheres (their power and the irradiance
//! they give against the formulas), reflecting emitters, spot lights with Mitsuba's fall-off and a
//! projected texture, and projectors; our images against Mitsuba's (tests/data/emitters,
//! scripts/make_emitter_refs.py), and photon mapping and SPPM against the same references.

mod common;

use caustic::geometry::Ray;
use caustic::light::Light;
use caustic::math::Vec3;
use caustic::options::{IntegratorKind, Options};
use caustic::scene::LoadOptions;
use common::mitsuba_refs::References;
use std::f64::consts::PI;
use std::path::Path;
use std::sync::LazyLock;

static REFS: LazyLock<References> = LazyLock::new(|| References::new("emitters"));

fn xml(body: &str) -> caustic::app::LoadedScene {
    let text = format!(
        r#"<scene version="3.0.0"><sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>{body}</scene>"#
    );
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let desc = caustic::scene::mitsuba::load_mitsuba_str(&text, "case.xml", root, &LoadOptions::default())
        .unwrap_or_else(|e| panic!("{e}"));
    caustic::app::prepare(desc, &Options::default()).unwrap()
}

/// Irradiance at `p` on a surface facing `n`, by sampling every light of the scene (`n_samples`
/// each, no occlusion: the probes look at the light through empty space).
fn irradiance(s: &caustic::app::LoadedScene, p: Vec3, n: Vec3, n_samples: u32) -> f64 {
    let scene = &s.scene;
    let mut rng = caustic::sampling::Rng32::new(5);
    let mut sum = 0.0;
    for _ in 0..n_samples {
        let u = rng.uniform();
        let Some((i, prob)) = scene.light_picker.pick(u) else { continue };
        let Some(ls) = scene.lights[i].sample(p, rng.uniform2(), scene.textures()) else { continue };
        let cos = ls.wi.dot(n).max(0.0) as f64;
        sum += caustic::math::luminance(ls.weight()) as f64 * cos / prob as f64;
    }
    sum / n_samples as f64
}

#[test]
fn an_emitting_sphere_gives_the_irradiance_of_the_formula() {
    // A sphere of radius r and radiance L seen from distance d on its axis: E = pi L r^2 / d^2.
    let s = xml(r#"<shape type="sphere"><float name="radius" value="0.5"/><point name="center" x="0" y="0" z="3"/>
        <emitter type="area"><rgb name="radiance" value="2"/></emitter></shape>"#);
    let e = irradiance(&s, Vec3::ZERO, Vec3::Z, 200_000);
    let exact = PI * 2.0 * 0.25 / 9.0;
    assert!((e - exact).abs() < 0.005 * exact, "{e} vs {exact}");
    let power: f64 = s.scene.lights.iter().map(|l| l.power().r() as f64).sum();
    let exact_power = PI * 2.0 * 4.0 * PI * 0.25;
    assert!((power - exact_power).abs() < 1e-4 * exact_power, "{power} vs {exact_power}");
}

#[test]
fn an_emitting_mesh_has_the_power_and_irradiance_of_the_formula() {
    // The icosphere OBJ (320 triangles) as an emitter: its power is pi L times its area, and a
    // distant probe sees it as a point source of intensity L x its projected area.
    let s = xml(r#"<shape type="obj"><string name="filename" value="scenes/mitsuba/meshes/icosphere.obj"/>
        <transform name="to_world"><scale value="0.5"/><translate z="4"/></transform>
        <emitter type="area"><rgb name="radiance" value="3"/></emitter></shape>"#);
    let mesh = caustic::shape::TriangleMesh::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/mitsuba/meshes/icosphere.obj"),
    )
    .unwrap();
    let area: f64 = mesh
        .indices
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3() * 0.5);
            0.5 * (b - a).cross(c - a).length()
        })
        .sum();
    assert_eq!(s.scene.lights.len(), mesh.indices.len());
    let power: f64 = s.scene.lights.iter().map(|l| l.power().r() as f64).sum();
    assert!((power - PI * 3.0 * area).abs() < 1e-4 * power, "{power} vs {}", PI * 3.0 * area);
    // Photons leave it with the same total power.
    let (mut flux, n) = (0.0f64, 200_000);
    let mut rng = caustic::sampling::Rng32::new(7);
    for _ in 0..n {
        let (i, prob) = s.scene.light_picker.pick(rng.uniform()).unwrap();
        let e = s.scene.lights[i].sample_le(rng.uniform2(), rng.uniform2(), s.scene.textures()).unwrap();
        flux += e.flux.r() as f64 / prob as f64;
    }
    flux /= n as f64;
    assert!((flux - power).abs() < 0.005 * power, "photons carry {flux}, power {power}");
    // Far away (d = 400 radii) the irradiance is L x projected area / d^2; the icosphere's
    // projected area along z is measured by sampling its silhouette.
    let far = Vec3::new(0.0, 0.0, 4.0 - 200.0);
    let e = irradiance(&s, far, Vec3::Z, 400_000);
    let projected: f64 = mesh
        .indices
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3() * 0.5);
            (0.5 * (b - a).cross(c - a).z).abs()
        })
        .sum::<f64>()
        / 2.0;
    let exact = 3.0 * projected / (200.0f64 * 200.0);
    assert!((e - exact).abs() < 0.01 * exact, "{e} vs {exact}");
}

#[test]
fn objects_in_native_scenes_emit_with_their_material() {
    let s = common::scene(
        r#"
[camera]
eye = [0, 0, 5]
look_at = [0, 0, 0]
[materials.white]
type = "diffuse"
color = [1, 1, 1]
kd = 0.5
[[objects]]
type = "sphere"
radius = 0.5
center = [0, 0, -3]
emission = [2, 2, 2]
material = "white"
[[objects]]
type = "box"
min = [2, 2, 2]
max = [3, 3, 3]
emission = 1
"#,
    );
    let lights = &s.scene.lights;
    assert_eq!(lights.len(), 7, "the sphere and six faces");
    assert!(matches!(lights[0], Light::Area { .. }));
    let box_power: f64 = lights[1..].iter().map(|l| l.power().r() as f64).sum();
    assert!((box_power - PI * 6.0).abs() < 1e-4, "{box_power}");
    // The box is behind the probe's surface: only the sphere lights it.
    let e = irradiance(&s, Vec3::ZERO, -Vec3::Z, 200_000);
    let exact = PI * 2.0 * 0.25 / 9.0;
    assert!((e - exact).abs() < 0.01 * exact, "{e} vs {exact}");
    // The sphere reflects with its material; the box (no material) is a plain emitter.
    let bsdf_at = |o: Vec3, d: Vec3| {
        let hit = s.scene.intersect(&Ray::new(o, d), f32::INFINITY).expect("hit");
        assert!(hit.is_emitter());
        s.scene.bsdf(&hit, -d)
    };
    assert!(!bsdf_at(Vec3::ZERO, -Vec3::Z).is_black());
    assert!(bsdf_at(Vec3::new(2.5, 2.5, 5.0), -Vec3::Z).is_black());

    // `emission_texture` multiplies the emission (1 when only the texture is named).
    let s = common::scene(
        r#"
[camera]
eye = [0, 0, 5]
look_at = [0, 0, 0]
[textures.checks]
type = "checkerboard"
color0 = [4, 4, 4]
color1 = [0, 0, 0]
[[objects]]
type = "quad"
corner = [0, 0, 0]
edge1 = [2, 0, 0]
edge2 = [0, 1, 0]
emission_texture = "checks"
[[objects]]
type = "quad"
corner = [0, 0, -1]
edge1 = [2, 0, 0]
edge2 = [0, 1, 0]
emission = 0.5
emission_texture = "checks"
"#,
    );
    let power: Vec<f64> = s.scene.lights.iter().map(|l| l.power().r() as f64).collect();
    assert_eq!(power.len(), 2);
    assert!((power[0] - PI * 2.0 * 2.0).abs() < 1e-4 && (power[1] - PI * 2.0 * 1.0).abs() < 1e-4, "{power:?}");
}

#[test]
fn emitters_match_mitsuba() {
    REFS.check_all(
        &[
            ("cornell_mesh", 256),
            ("spot_ramp", 256),
            ("spot_textured", 256),
            ("projector", 256),
            ("reflecting_emitter", 256),
            ("area_bitmap", 256),
            ("area_checker_sphere", 256),
            ("area_checker_sphere_rotated", 256),
        ],
        64,
    );
}

#[test]
fn photon_mapping_and_sppm_carry_mesh_lights_projectors_and_reflecting_emitters() {
    let mut failures = Vec::new();
    for (case, photon_spp, sppm_spp) in [
        ("cornell_mesh", 16, 256),
        ("projector", 16, 256),
        ("reflecting_emitter", 16, 256),
        ("spot_textured", 16, 256),
        ("area_bitmap", 16, 256),
        ("area_checker_sphere", 16, 256),
    ] {
        failures.extend(REFS.compare_mean(case, 64, photon_spp, IntegratorKind::Photon, 0.03));
        failures.extend(REFS.compare_mean(case, 64, sppm_spp, IntegratorKind::Sppm, 0.03));
    }
    assert!(failures.is_empty(), "photon mapping or SPPM lose light:\n{}", failures.join("\n"));
}

#[test]
fn emitting_disks_and_cylinders_give_the_irradiance_of_the_formula() {
    // A disk of radius R facing a point on its axis at distance d: E = pi L R^2 / (R^2 + d^2).
    // Mitsuba's disk faces +z; this one is turned to face -z, towards the probe below it.
    let s = xml(
        r#"<shape type="disk"><transform name="to_world"><scale value="0.8"/><rotate x="1" angle="180"/><translate z="2"/></transform>
        <emitter type="area"><rgb name="radiance" value="3"/></emitter></shape>"#,
    );
    let e = irradiance(&s, Vec3::ZERO, Vec3::Z, 200_000);
    let exact = PI * 3.0 * 0.64 / (0.64 + 4.0);
    assert!((e - exact).abs() < 0.005 * exact, "disk: {e} vs {exact}");
    // Seen from the back it gives nothing.
    assert!(irradiance(&s, Vec3::new(0.0, 0.0, 4.0), -Vec3::Z, 10_000) == 0.0);
    // A cylinder emits from its outer side: its power is pi L x its area 2 pi r h, and a probe
    // on its axis outside it sees none of its outer surface.
    let s = xml(
        r#"<shape type="cylinder"><float name="radius" value="0.5"/><point name="p0" x="0" y="0" z="0"/><point name="p1" x="0" y="0" z="2"/>
        <emitter type="area"><rgb name="radiance" value="2"/></emitter></shape>"#,
    );
    let power: f64 = s.scene.lights.iter().map(|l| l.power().r() as f64).sum();
    let exact_power = PI * 2.0 * (2.0 * PI * 0.5 * 2.0);
    assert!((power - exact_power).abs() < 1e-4 * exact_power, "{power} vs {exact_power}");
    // Beside it, at distance D from the axis, facing it: a long cylinder's irradiance is bounded by
    // that of an infinite one, pi L (r / D); this one (h = 2, D = 1) gives a known fraction of it.
    let e = irradiance(&s, Vec3::new(1.0, 0.0, 1.0), -Vec3::X, 200_000);
    assert!(e > 0.0 && e < PI * 2.0 * 0.5, "cylinder: {e}");
}

/// Textured area lights read their texture at the same surface point whether a light sample
/// picks it or a ray hits it (so next-event estimation, MIS hits and photons agree), on every
/// emitting shape: rectangle, sphere, disk, cylinder and a mesh with its own texture
/// coordinates; and their power is the untextured power times the texture's mean.
#[test]
fn textured_emitters_read_the_same_texture_where_sampled_and_where_hit() {
    let dir = common::scratch("textured-emitters");
    // The square [-1, 1]^2 at z = 0 as two triangles (a parallelogram: the loader keeps its
    // triangles for their uv), and as a fan of four around its centre; uv run over [0, 2] x [0, 1].
    std::fs::write(
        dir.join("quad.obj"),
        "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nvt 0 0\nvt 2 0\nvt 2 1\nvt 0 1\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("fan.obj"),
        "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nv 0 0 0\nvt 0 0\nvt 2 0\nvt 2 1\nvt 0 1\nvt 1 0.5\n\
         f 1/1 2/2 5/5\nf 2/2 3/3 5/5\nf 3/3 4/4 5/5\nf 4/4 1/1 5/5\n",
    )
    .unwrap();
    let checker = r#"<texture type="checkerboard" name="radiance"><rgb name="color0" value="3, 2, 1"/>
        <rgb name="color1" value="0.2, 0.4, 0.8"/><transform name="to_uv"><scale x="5" y="3"/></transform></texture>"#;
    let up = r#"<transform name="to_world"><rotate x="1" angle="180"/><translate z="2"/></transform>"#;
    let shapes = [
        ("rectangle", format!(r#"<shape type="rectangle">{up}<emitter type="area">{checker}</emitter></shape>"#)),
        (
            "sphere",
            format!(
                r#"<shape type="sphere"><point name="center" x="0.3" y="0" z="2"/><emitter type="area">{checker}</emitter></shape>"#
            ),
        ),
        ("disk", format!(r#"<shape type="disk">{up}<emitter type="area">{checker}</emitter></shape>"#)),
        (
            "cylinder",
            format!(
                r#"<shape type="cylinder"><point name="p0" x="-1" y="0" z="2"/><point name="p1" x="1" y="0" z="2"/>
            <float name="radius" value="0.5"/><emitter type="area">{checker}</emitter></shape>"#
            ),
        ),
        (
            "mesh",
            format!(
                r#"<shape type="obj"><string name="filename" value="{}"/>{up}<emitter type="area">{checker}</emitter></shape>"#,
                dir.join("quad.obj").display()
            ),
        ),
        (
            "fan",
            format!(
                r#"<shape type="obj"><string name="filename" value="{}"/>{up}<emitter type="area">{checker}</emitter></shape>"#,
                dir.join("fan.obj").display()
            ),
        ),
    ];
    for (name, body) in shapes {
        let s = xml(&body);
        let scene = &s.scene;
        assert!(scene.lights.iter().all(|l| matches!(l, Light::Area { texture: Some(_), .. })), "{name}");
        let (mut agree, mut total, mut colours) = (0, 0, std::collections::HashSet::new());
        let mut rng = caustic::sampling::Rng32::new(11);
        let p = Vec3::new(0.05, -0.02, 0.0);
        for _ in 0..4000 {
            let (i, _) = scene.light_picker.pick(rng.uniform()).unwrap();
            let Some(ls) = scene.lights[i].sample(p, rng.uniform2(), scene.textures()) else { continue };
            let Some(h) = scene.intersect(&Ray::new(p, ls.wi), f32::INFINITY) else { continue };
            total += 1;
            let seen = scene.emitted(&h, -ls.wi);
            // Where the texture is read: on the rectangle and the mesh (turned over about x, so
            // local (x, y) = (q.x, -q.y)) the uv Mitsuba gives them (an OBJ's v flipped, as
            // Mitsuba's `flip_tex_coords` does by default).
            let (x, y) = (h.p.x, -h.p.y);
            let want_uv = match name {
                "rectangle" => Some(caustic::math::Vec2::new((x + 1.0) / 2.0, (y + 1.0) / 2.0)),
                "mesh" | "fan" => Some(caustic::math::Vec2::new(x + 1.0, 1.0 - (y + 1.0) / 2.0)),
                _ => None,
            };
            let Light::Area { texture: Some(t), .. } = scene.lights[i] else { unreachable!() };
            let want = want_uv.map(|uv| scene.materials.textures[t.texture as usize].eval(uv));
            if (seen - ls.radiance).abs().max_element() < 1e-4
                && want.is_none_or(|w| (w - seen).abs().max_element() < 1e-4)
            {
                agree += 1;
            } else if total < 50 {
                eprintln!("{name}: p {} uv {:?} seen {seen} sampled {} want {want:?}", h.p, h.uv(), ls.radiance);
            }
            colours.insert((ls.radiance.r() * 10.0) as i32);
        }
        // Points within rounding of a check's edge may read the neighbouring check.
        assert!(total > 1000 && agree as f64 >= 0.995 * total as f64, "{name}: {agree} of {total} agree");
        assert_eq!(colours.len(), 2, "{name}: both checks are seen: {colours:?}");
        // Power: the checkerboard's mean (half of each colour) times pi times the area.
        let power: f64 = scene.lights.iter().map(|l| l.power().r() as f64).sum();
        let area: f64 = scene
            .lights
            .iter()
            .map(|l| match l {
                Light::Area { shape, .. } => shape.area() as f64,
                _ => 0.0,
            })
            .sum();
        let exact = PI * area * (3.0 + 0.2) / 2.0;
        assert!((power - exact).abs() < 1e-3 * exact, "{name}: power {power} vs {exact}");
    }
}
