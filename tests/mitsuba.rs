//! Mitsuba 3 scene import: each example scene in scenes/mitsuba/ against its hand-written native
//! twin (bit-identical images), our path tracer against an image rendered by Mitsuba itself,
//! Mitsuba's conventions (camera, fov axis, depth, transforms), and a table of malformed inputs
//! that must each give an error naming the problem, file and line.

use caustic::app::{LoadedScene, prepare};
use caustic::film::Image;
use caustic::film::output::read_exr;
use caustic::math::{Color, Vec2, Vec3, luminance};
use caustic::options::{IntegratorKind, Options, PhotonOptions};
use caustic::scene::mitsuba::load_mitsuba_str;
use caustic::scene::{LoadOptions, SceneError};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn load(rel: &str, o: &Options) -> LoadedScene {
    load_with(rel, &LoadOptions::default(), o)
}

fn load_with(rel: &str, lo: &LoadOptions, o: &Options) -> LoadedScene {
    let path = root().join(rel);
    caustic::app::load(&path, lo, o).unwrap_or_else(|e| panic!("{rel} failed to load: {e}"))
}

/// Loads Mitsuba XML text as the file `case.xml` in `base`, with its warnings.
fn xml_opts(text: &str, base: &Path, lo: &LoadOptions, o: &Options) -> Result<(LoadedScene, Vec<String>), SceneError> {
    let mut s = prepare(load_mitsuba_str(text, "case.xml", base, lo)?, o)?;
    let warnings = std::mem::take(&mut s.warnings);
    Ok((s, warnings))
}

fn xml_in(text: &str, base: &Path, o: &Options) -> Result<(LoadedScene, Vec<String>), SceneError> {
    xml_opts(text, base, &LoadOptions::default(), o)
}

fn xml(text: &str) -> (LoadedScene, Vec<String>) {
    xml_in(text, &root(), &Options::default()).unwrap_or_else(|e| panic!("scene failed to load: {e}"))
}

fn render_with(s: &LoadedScene) -> Image {
    s.render().image
}

fn mean_luminance(img: &Image) -> f64 {
    img.pixels.iter().map(|&c| luminance(c) as f64).sum::<f64>() / img.pixels.len() as f64
}

fn rmse(a: &Image, b: &Image) -> f64 {
    assert_eq!((a.width, a.height), (b.width, b.height));
    let s: f64 = a.pixels.iter().zip(&b.pixels).map(|(&x, &y)| ((x - y) * (x - y)).sum() as f64 / 3.0).sum();
    (s / a.pixels.len() as f64).sqrt()
}

/// A scene with the usual scaffolding around `body`.
fn wrap(body: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film>
    </sensor>
{body}
</scene>"#
    )
}

// ---------------------------------------------------------------------------------------------
// Each example against its native twin
// ---------------------------------------------------------------------------------------------

const PAIRS: &[&str] = &["cornell-box", "glass-point", "thinlens", "ply-mesh"];

#[test]
fn every_example_renders_bit_identically_to_its_native_twin() {
    for name in PAIRS {
        let o = Options { width: Some(32), height: Some(32), spp: Some(4), seed: Some(3), ..Default::default() };
        let x = load(&format!("scenes/mitsuba/{name}.xml"), &o);
        let t = load(&format!("scenes/mitsuba/{name}.toml"), &o);
        let mut camera = x.scene.camera;
        if camera.lens_radius == 0.0 {
            // A pinhole has no focal plane (Mitsuba's default focus is the far clip, ours the
            // look-at distance); nothing else may differ.
            camera.focal_distance = t.scene.camera.focal_distance;
        }
        assert_eq!(camera, t.scene.camera, "{name}: camera");
        assert_eq!(x.scene.lights, t.scene.lights, "{name}: lights");
        assert_eq!(x.scene.bvh.len(), t.scene.bvh.len(), "{name}: primitives");
        assert_eq!(x.scene.environment, t.scene.environment, "{name}: environment");
        assert_eq!(x.integrator, t.integrator, "{name}: integrator");
        assert_eq!(x.settings.spp, t.settings.spp);
        // The examples name the box filter, the TOML default (docs/mitsuba.md).
        assert_eq!(x.settings.filter, t.settings.filter, "{name}: filter");
        let (a, b) = (render_with(&x), render_with(&t));
        assert!(mean_luminance(&a) > 1e-3, "{name}: image is black");
        assert!(a.pixels == b.pixels, "{name}: images differ (rmse {})", rmse(&a, &b));
    }
}

#[test]
fn the_cornell_box_is_identical_with_every_integrator() {
    for kind in [IntegratorKind::Whitted, IntegratorKind::Photon] {
        let o = Options {
            width: Some(24),
            height: Some(24),
            spp: Some(2),
            integrator: Some(kind),
            photon: PhotonOptions {
                photons: Some(20_000),
                caustic_photons: Some(0),
                gather: Some(2),
                ..Default::default()
            },
            ..Default::default()
        };
        let x = load("scenes/mitsuba/cornell-box.xml", &o);
        let t = load("scenes/mitsuba/cornell-box.toml", &o);
        // Mitsuba's max_depth 9 is 8 bounces, for every integrator.
        assert_eq!((x.integrator.max_depth, t.integrator.max_depth), (Some(8), Some(8)));
        let (a, b) = (render_with(&x), render_with(&t));
        assert!(mean_luminance(&a) > 1e-3);
        assert!(a.pixels == b.pixels, "{kind:?}: images differ (rmse {})", rmse(&a, &b));
    }
}

// ---------------------------------------------------------------------------------------------
// Against Mitsuba itself
// ---------------------------------------------------------------------------------------------

/// tests/data/mitsuba/cornell_ref.exr was rendered by Mitsuba 3.9.1 (scalar_rgb, path tracer,
/// 64 x 64, box filter) from scenes/mitsuba/cornell-box.xml by scripts/mitsuba_reference.py.
const REFERENCE_SPP: f64 = 16384.0;

#[test]
fn cornell_box_matches_mitsubas_own_render() {
    let reference = read_exr(&root().join("tests/data/mitsuba/cornell_ref.exr")).expect("reference EXR");
    assert_eq!((reference.width, reference.height), (64, 64));
    let spp = 256u32;
    let ours = |seed: u64| {
        let o = Options { seed: Some(seed), ..Default::default() };
        let defines = vec![("res".to_string(), "64".to_string()), ("spp".to_string(), spp.to_string())];
        render_with(&load_with(
            "scenes/mitsuba/cornell-box.xml",
            &LoadOptions { defines, strict: false, ..Default::default() },
            &o,
        ))
    };
    let (a, b) = (ours(1), ours(2));
    // Our noise per image, from two independent renders; Mitsuba's from its sample count.
    let noise = rmse(&a, &b) / 2f64.sqrt();
    let ref_noise = noise * (spp as f64 / REFERENCE_SPP).sqrt();
    let expected = (noise * noise + ref_noise * ref_noise).sqrt();
    let (la, lr) = (mean_luminance(&a), mean_luminance(&reference));
    let rel = (la - lr).abs() / lr;
    let err = rmse(&a, &reference);
    eprintln!(
        "mean luminance: ours {la:.5}, Mitsuba {lr:.5} ({:.3}%); rmse {err:.5}, expected from noise {expected:.5}",
        rel * 100.0
    );
    assert!(rel < 0.01, "mean luminance differs by {:.2}%", rel * 100.0);
    assert!(err < 1.2 * expected, "rmse {err} against Mitsuba, noise predicts {expected}");
    // The red wall is on the left, as in Mitsuba's image.
    let column = |img: &Image, x: u32| -> Color {
        (0..img.height).map(|y| img.pixels[(y * img.width + x) as usize]).sum::<Color>()
    };
    let (left, right) = (column(&a, 3), column(&a, 60));
    assert!(left.r() > 3.0 * left.g() && right.g() > 2.0 * right.r(), "left {left}, right {right}");
    let (rl, rr) = (column(&reference, 3), column(&reference, 60));
    assert!(rl.r() > 3.0 * rl.g() && rr.g() > 2.0 * rr.r());
}

// ---------------------------------------------------------------------------------------------
// Conventions
// ---------------------------------------------------------------------------------------------

#[test]
fn max_depth_counts_segments_as_mitsuba_does() {
    let with = |depth: &str, kind: Option<IntegratorKind>| {
        let text =
            wrap(&format!(r#"<integrator type="path"><integer name="max_depth" value="{depth}"/></integrator>"#));
        let o = Options { integrator: kind, ..Default::default() };
        let i = xml_in(&text, &root(), &o).unwrap().0.integrator;
        i.depth_limit(i.kind)
    };
    assert_eq!(with("2", None), 1, "2 segments = direct light = 1 bounce");
    assert_eq!(with("9", None), 8);
    assert_eq!(with("-1", None), 1000);
    // One meaning for every integrator; "unlimited" keeps Whitted's branching recursion at the
    // default.
    assert_eq!(with("9", Some(IntegratorKind::Whitted)), 8);
    assert_eq!(with("9", Some(IntegratorKind::Photon)), 8);
    assert_eq!(with("-1", Some(IntegratorKind::Whitted)), 6);
    // No integrator: Mitsuba's default path tracer, unlimited.
    let s = xml(&wrap("")).0;
    assert_eq!((s.integrator.kind, s.integrator.max_depth), (IntegratorKind::Path, None));
    // `direct` is a two-segment path.
    assert_eq!(xml(&wrap(r#"<integrator type="direct"/>"#)).0.integrator.max_depth, Some(1));
    // The command line's value is ours, unchanged.
    let o = Options { max_depth: Some(3), ..Default::default() };
    assert_eq!(
        xml_in(&wrap(r#"<integrator type="path"><integer name="max_depth" value="9"/></integrator>"#), &root(), &o)
            .unwrap()
            .0
            .integrator
            .max_depth,
        Some(3)
    );
}

fn sensor_scene(sensor_body: &str, w: u32, h: u32) -> String {
    format!(
        r#"<scene version="3.0.0"><sensor type="perspective">{sensor_body}
        <film type="hdrfilm"><integer name="width" value="{w}"/><integer name="height" value="{h}"/></film>
        </sensor></scene>"#
    )
}

#[test]
fn fov_axis_and_focal_length_follow_mitsuba() {
    // Half-width of the view plane at distance 1, from pixel_size.
    let half_w = |body: &str, w: u32, h: u32| {
        let c = xml(&sensor_scene(body, w, h)).0.scene.camera;
        c.pixel_size * w as f32 * 0.5 / c.d
    };
    let t = |deg: f32| (deg.to_radians() * 0.5).tan();
    let (w, h) = (200, 100);
    assert!((half_w(r#"<float name="fov" value="60"/>"#, w, h) - t(60.0)).abs() < 1e-5, "default axis is x");
    assert!(
        (half_w(r#"<float name="fov" value="60"/><string name="fov_axis" value="y"/>"#, w, h) - 2.0 * t(60.0)).abs()
            < 1e-5
    );
    let diag = half_w(r#"<float name="fov" value="60"/><string name="fov_axis" value="diagonal"/>"#, w, h);
    assert!((diag - t(60.0) * 2.0 / 5f32.sqrt()).abs() < 1e-5, "{diag}");
    assert!(
        (half_w(r#"<float name="fov" value="60"/><string name="fov_axis" value="smaller"/>"#, w, h) - 2.0 * t(60.0))
            .abs()
            < 1e-5
    );
    assert!(
        (half_w(r#"<float name="fov" value="60"/><string name="fov_axis" value="larger"/>"#, w, h) - t(60.0)).abs()
            < 1e-5
    );
    // 50 mm on 35 mm film: the diagonal angle is 2 atan(43.27 / 100).
    let fl = half_w(r#"<string name="focal_length" value="50mm"/>"#, 300, 200);
    let d = 36f32.hypot(24.0) / 100.0;
    assert!((fl - d / (1.0 + 4.0 / 9.0f32).sqrt()).abs() < 1e-5, "{fl}");
}

#[test]
fn camera_looks_along_local_z_with_image_x_along_local_minus_x() {
    // A to_world matrix equal to lookat(origin (1,2,3), target (1,2,-7), up y): the camera looks
    // down -z with +x to the right of the image.
    let m = r#"<transform name="to_world"><matrix value="-1 0 0 1  0 1 0 2  0 0 -1 3  0 0 0 1"/></transform>"#;
    let c = xml(&sensor_scene(&format!(r#"<float name="fov" value="40"/>{m}"#), 32, 32)).0.scene.camera;
    let l = xml(&sensor_scene(
        r#"<float name="fov" value="40"/><transform name="to_world"><lookat origin="1,2,3" target="1,2,-7" up="0,1,0"/></transform>"#,
        32,
        32,
    ))
    .0
    .scene
    .camera;
    assert!(c.eye.abs_diff_eq(Vec3::new(1.0, 2.0, 3.0), 1e-6));
    assert!(c.u.abs_diff_eq(Vec3::X, 1e-6) && c.v.abs_diff_eq(Vec3::Y, 1e-6) && c.w.abs_diff_eq(Vec3::Z, 1e-6));
    assert!(c.u.abs_diff_eq(l.u, 1e-6) && c.v.abs_diff_eq(l.v, 1e-6) && c.w.abs_diff_eq(l.w, 1e-6));
    // A mirroring to_world mirrors the image.
    let mirrored = xml(&sensor_scene(
        r#"<float name="fov" value="40"/><transform name="to_world"><scale x="-1"/><lookat origin="1,2,3" target="1,2,-7" up="0,1,0"/></transform>"#,
        32,
        32,
    ))
    .0
    .scene
    .camera;
    assert!(mirrored.u.abs_diff_eq(-Vec3::X, 1e-6), "{}", mirrored.u);
    // Scaling a camera is refused, as in Mitsuba.
    let e = xml_in(
        &sensor_scene(r#"<transform name="to_world"><scale value="2"/></transform>"#, 8, 8),
        &root(),
        &Options::default(),
    )
    .err()
    .unwrap();
    assert!(e.message().contains("only rotate and translate"), "{e}");
}

#[test]
fn transforms_compose_in_the_order_written() {
    // Scale, then rotate 90 degrees about z, then translate: (1,0,0) -> (2,0,0) -> (0,2,0) -> (0,2,5).
    let (s, _) = xml(&wrap(
        r#"<emitter type="point"><transform name="to_world"><translate x="1"/><scale value="2"/><rotate z="1" angle="90"/><translate z="5"/></transform></emitter>"#,
    ));
    let caustic::light::Light::Point { position, .. } = s.scene.lights[0] else { panic!() };
    assert!(position.abs_diff_eq(Vec3::new(0.0, 2.0, 5.0), 1e-5), "{position}");
}

#[test]
fn rectangles_emit_along_local_z_and_flip_normals_turns_them() {
    let light = |flip: bool| {
        let (s, _) = xml(&wrap(&format!(
            r#"<shape type="rectangle"><boolean name="flip_normals" value="{flip}"/>
               <transform name="to_world"><rotate x="1" angle="90"/><translate y="2"/></transform>
               <emitter type="area"><rgb name="radiance" value="3"/></emitter></shape>"#
        )));
        let caustic::light::Light::Area { shape: caustic::shape::Shape::Quad(q), radiance, .. } = s.scene.lights[0]
        else {
            panic!()
        };
        assert_eq!(radiance, Color::splat(3.0));
        assert!((q.area() - 4.0).abs() < 1e-5);
        q.n
    };
    assert!(light(false).abs_diff_eq(-Vec3::Y, 1e-6), "rotated +z faces down");
    assert!(light(true).abs_diff_eq(Vec3::Y, 1e-6));
}

#[test]
fn materials_map_to_our_model() {
    let (s, warnings) = xml(&wrap(
        r#"<bsdf type="dielectric" id="glass"><string name="int_ior" value="water"/></bsdf>
           <bsdf type="dielectric" id="bk7"/>
           <bsdf type="conductor" id="mirror"/>
           <bsdf type="twosided" id="two"><bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.3, 0.4"/></bsdf></bsdf>
           <shape type="sphere"><ref id="glass"/></shape>
           <shape type="sphere"><ref id="bk7"/></shape>
           <shape type="sphere"><ref id="mirror"/></shape>
           <shape type="sphere"><ref id="two"/></shape>
           <shape type="sphere"/>"#,
    ));
    assert!(warnings.is_empty(), "{warnings:?}");
    let m = |name: &str| {
        let ms = &s.scene.materials;
        let i = ms.names.iter().position(|n| n == name).unwrap_or_else(|| panic!("{name}"));
        ms.list[i]
    };
    use caustic::material::{Model, Param, Plain};
    let eta = |name: &str| match m(name).model {
        Model::Plain(Plain::Dielectric { eta, reflectance, transmittance }) => {
            assert_eq!((reflectance, transmittance), (Param::Const(Color::ONE), Param::Const(Color::ONE)));
            eta
        }
        other => panic!("{name} is {other:?}"),
    };
    assert!((eta("glass") - 1.333 / 1.000277).abs() < 1e-5);
    assert!((eta("bk7") - 1.5046 / 1.000277).abs() < 1e-5);
    // A conductor without a material is Mitsuba's perfect mirror: eta 0, k 1, one-sided.
    let mirror = m("mirror");
    assert_eq!(
        (mirror.model, mirror.two_sided),
        (
            Plain::Conductor {
                ior: caustic::material::conductors::ComplexIor::rgb(Color::ZERO, Color::ONE),
                specular: Param::Const(Color::ONE)
            }
            .into(),
            false
        )
    );
    // `twosided` of one diffuse: the diffuse on both sides; a bare diffuse is one-sided.
    let two = m("two");
    assert_eq!(
        (two.model, two.two_sided),
        (Plain::Diffuse { reflectance: Param::Const(Color::new(0.2, 0.3, 0.4)) }.into(), true)
    );
    let default = m("(default diffuse)");
    assert_eq!(
        (default.model, default.two_sided),
        (Plain::Diffuse { reflectance: Param::Const(Color::splat(0.5)) }.into(), false)
    );
}

#[test]
fn unsupported_parts_warn_with_their_place_or_fail_with_strict() {
    let text = wrap(
        r#"<shape type="bsplinecurve"/>
    <shape type="sphere"><bsdf type="hair"/></shape>
    <shape type="sphere"><bsdf type="diffuse"><texture type="volume" name="reflectance"/></bsdf></shape>
    <shape type="sphere"><bsdf type="measured"/></shape>
    <emitter type="sunsky"/>
    <shape type="sphere"><float name="wobble" value="1"/></shape>"#,
    );
    let (s, warnings) = xml(&text);
    let expect = [
        (7, "shape `bsplinecurve` is not supported"),
        (8, "BSDF `hair` is not supported"),
        (9, "texture `volume` is not supported"),
        (10, "BSDF `measured` is not supported"),
        (11, "emitter `sunsky` is not supported"),
        (12, "property `wobble`"),
    ];
    for (line, what) in expect {
        assert!(
            warnings.iter().any(|w| w.starts_with(&format!("case.xml:{line}:")) && w.contains(what)),
            "no warning `{what}` at line {line}: {warnings:?}"
        );
    }
    // The unknown texture is grey 0.5.
    assert!(
        s.scene
            .materials
            .textures
            .iter()
            .any(|t| matches!(t, caustic::texture::Texture::Constant(c) if *c == Color::splat(0.5)))
    );
    let strict = LoadOptions { strict: true, ..Default::default() };
    let e = xml_opts(&text, &root(), &strict, &Options::default()).err().expect("strict must fail");
    assert!(e.to_string().starts_with("case.xml:7:") && e.message().contains("--strict"), "{e}");
}

#[test]
fn misspelt_plugin_types_are_errors_naming_the_nearest_one() {
    // Mitsuba 3 stops on a type it has no plugin for; so do we (not a warning and exit 0).
    for (body, line, message) in [
        (r#"<shape type="sphre"/>"#, 7, "unknown shape type `sphre` (did you mean `sphere`?)"),
        (
            r#"<shape type="sphere"><bsdf type="dielectrc"/></shape>"#,
            7,
            "unknown BSDF type `dielectrc` (did you mean `dielectric`?)",
        ),
        (r#"<emitter type="pont"/>"#, 7, "unknown emitter type `pont` (did you mean `point`?)"),
        (
            "<shape type=\"sphere\">\n    <bsdf type=\"diffuse\"><texture type=\"bitmp\" name=\"reflectance\"/></bsdf></shape>",
            8,
            "unknown texture type `bitmp` (did you mean `bitmap`?)",
        ),
    ] {
        let e = xml_opts(&wrap(body), &root(), &LoadOptions::default(), &Options::default())
            .err()
            .unwrap_or_else(|| panic!("{body} loaded"));
        assert!(e.to_string().starts_with(&format!("case.xml:{line}:")), "{e}");
        assert_eq!(e.message(), message);
    }
    // A plugin Mitsuba has and we do not render stays a warning.
    let (_, warnings) = xml(&wrap(r#"<shape type="sphere"><bsdf type="hair"/></shape>"#));
    assert!(warnings.iter().any(|w| w.contains("BSDF `hair` is not supported")), "{warnings:?}");
}

#[test]
fn constant_emitter_becomes_an_environment_light() {
    let (s, w) = xml(&wrap(r#"<emitter type="constant"><rgb name="radiance" value="0.1, 0.2, 0.3"/></emitter>"#));
    let env = s.scene.environment.expect("an environment light") as usize;
    assert!(matches!(s.scene.lights[env], caustic::light::Light::Environment(_)));
    assert_eq!(s.scene.environment(Vec3::new(0.3, -0.2, 0.9).normalize()), Color::new(0.1, 0.2, 0.3));
    assert!(w.is_empty());
    // Photon mapping, SPPM and the light tracer start light paths from it too.
    let e = s.scene.lights[env].sample_le(Vec2::new(0.3, 0.7), Vec2::new(0.6, 0.2), s.scene.textures()).unwrap();
    assert!(e.flux.max_element() > 0.0 && e.pdf_pos > 0.0 && e.pdf_dir > 0.0, "{e:?}");
    // A scene has one environment, as in Mitsuba.
    let two = wrap(r#"<emitter type="constant"/><emitter type="constant"/>"#);
    let e = xml_opts(&two, &root(), &LoadOptions::default(), &Options::default()).err().expect("two environments");
    assert!(e.message().contains("at most one environment"), "{e}");
}

#[test]
fn defaults_are_overridden_from_the_command_line() {
    let text = r#"<scene version="3.0.0"><default name="w" value="20"/>
      <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="$w"/><integer name="height" value="$w"/></film></sensor></scene>"#;
    assert_eq!(xml(text).0.settings.width, 20);
    let lo = LoadOptions { defines: vec![("w".into(), "12".into())], ..Default::default() };
    assert_eq!(xml_opts(text, &root(), &lo, &Options::default()).unwrap().0.settings.width, 12);
}

#[test]
fn includes_splice_scenes_and_report_their_own_file() {
    let dir = std::env::temp_dir().join(format!("caustic-mitsuba-include-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    std::fs::write(
        dir.join("sub/light.xml"),
        r#"<scene version="3.0.0"><emitter type="point"><rgb name="intensity" value="7"/></emitter></scene>"#,
    )
    .unwrap();
    std::fs::write(
        dir.join("sub/bad.xml"),
        "<scene version=\"3.0.0\">\n  <shape type=\"sphere\"><ref id=\"missing\"/></shape>\n</scene>",
    )
    .unwrap();
    let (s, _) = xml_in(&wrap(r#"<include filename="sub/light.xml"/>"#), &dir, &Options::default()).unwrap();
    assert_eq!(s.scene.lights.len(), 1);
    let e = xml_in(&wrap(r#"<include filename="sub/bad.xml"/>"#), &dir, &Options::default()).err().unwrap();
    let shown = e.to_string();
    assert!(shown.contains("bad.xml:2:") && shown.contains("missing"), "{shown}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn disks_keep_their_area_and_emitting_obj_parallelograms_become_lights() {
    let (s, _) = xml(&wrap(r#"<shape type="disk"><transform name="to_world"><scale value="2"/></transform></shape>"#));
    let bvh = &s.scene.bvh;
    let area: f32 = (0..bvh.len()).map(|i| bvh.prims().get(i, &s.scene.meshes).shape.area()).sum();
    assert!((area - 4.0 * std::f32::consts::PI).abs() < 1e-3, "{area}");
    let dir = std::env::temp_dir().join(format!("caustic-mitsuba-obj-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("quad.obj"), "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nf 1 4 3 2\n").unwrap();
    let (s, w) = xml_in(
        &wrap(r#"<shape type="obj"><string name="filename" value="quad.obj"/><emitter type="area"><rgb name="radiance" value="5"/></emitter></shape>"#),
        &dir,
        &Options::default(),
    )
    .unwrap();
    assert!(w.is_empty(), "{w:?}");
    let caustic::light::Light::Area { shape: caustic::shape::Shape::Quad(q), .. } = s.scene.lights[0] else { panic!() };
    assert!((q.area() - 1.0).abs() < 1e-6 && q.n.abs_diff_eq(Vec3::Y, 1e-6), "{q:?}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_command_line_renders_xml_with_defines_and_strict() {
    let dir = std::env::temp_dir().join(format!("caustic-mitsuba-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("cb.exr");
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_caustic"))
        .args(["render", "scenes/mitsuba/cornell-box.xml", "-q", "-D", "spp=2", "-D", "res=16", "--strict", "-o"])
        .arg(&out)
        .current_dir(root())
        .status()
        .unwrap();
    assert!(status.success());
    assert_eq!(read_exr(&out).unwrap().width, 16);
    let bad = dir.join("bad.xml");
    std::fs::write(&bad, wrap(r#"<shape type="sphere"><bsdf type="pplastic"/></shape>"#)).unwrap();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_caustic"))
        .args(["render", "-q", "--strict", "-o"])
        .arg(dir.join("bad.png"))
        .arg(&bad)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && stderr.contains("bad.xml:7:") && stderr.contains("pplastic"), "{stderr}");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_caustic"))
        .args(["render", "-q", "--spp", "1", "-o"])
        .arg(dir.join("bad.png"))
        .arg(&bad)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success() && stderr.contains("warning: ") && stderr.contains("bad.xml:7:"), "{stderr}");
    std::fs::remove_dir_all(&dir).ok();
}

// ---------------------------------------------------------------------------------------------
// Malformed input
// ---------------------------------------------------------------------------------------------

/// (what, scene text, line of the error, words the message must contain).
const MALFORMED: &[(&str, &str, usize, &[&str])] = &[
    ("malformed XML", "<scene version=\"3.0.0\">\n  <shape type=\"sphere\">\n</scene>", 3, &["malformed XML"]),
    ("not a scene", "<scone version=\"3.0.0\"/>", 1, &["root element", "<scone>"]),
    ("no version", "<scene>\n</scene>", 1, &["version"]),
    ("bad version", "<scene version=\"three\">\n</scene>", 1, &["version", "three"]),
    (
        "unknown property type",
        "<scene version=\"3.0.0\">\n<shape type=\"sphere\">\n  <color name=\"c\" value=\"1\"/>\n</shape>\n</scene>",
        3,
        &["unknown property type <color>"],
    ),
    ("unknown element", "<scene version=\"3.0.0\">\n  <camera/>\n</scene>", 2, &["unknown element <camera>"]),
    (
        "missing mesh file",
        "<scene version=\"3.0.0\">\n<shape type=\"obj\">\n  <string name=\"filename\" value=\"nope.obj\"/>\n</shape>\n</scene>",
        3,
        &["nope.obj"],
    ),
    (
        "missing ply file",
        "<scene version=\"3.0.0\">\n<shape type=\"ply\">\n  <string name=\"filename\" value=\"nope.ply\"/>\n</shape>\n</scene>",
        3,
        &["nope.ply"],
    ),
    ("no filename", "<scene version=\"3.0.0\">\n<shape type=\"ply\">\n</shape>\n</scene>", 2, &["filename"]),
    (
        "unresolved reference",
        "<scene version=\"3.0.0\">\n<shape type=\"sphere\">\n  <ref id=\"steel\"/>\n</shape>\n</scene>",
        3,
        &["no object with id `steel`"],
    ),
    (
        "duplicate id",
        "<scene version=\"3.0.0\">\n<bsdf type=\"diffuse\" id=\"a\"/>\n<bsdf type=\"diffuse\" id=\"a\"/>\n</scene>",
        3,
        &["id `a`", "more than one"],
    ),
    (
        "rgb value count",
        "<scene version=\"3.0.0\">\n<bsdf type=\"diffuse\" id=\"a\">\n  <rgb name=\"reflectance\" value=\"0.1, 0.2\"/>\n</bsdf>\n<shape type=\"sphere\"><ref id=\"a\"/></shape>\n</scene>",
        3,
        &["needs 3 values", "found 2"],
    ),
    (
        "point value count",
        "<scene version=\"3.0.0\">\n<shape type=\"sphere\">\n  <point name=\"center\" value=\"1, 2\"/>\n</shape>\n</scene>",
        3,
        &["needs 3 values", "found 2"],
    ),
    (
        "matrix value count",
        "<scene version=\"3.0.0\">\n<shape type=\"sphere\">\n  <transform name=\"to_world\">\n    <matrix value=\"1 0 0 0 0 1 0 0 0 0 1 0 0 0 0\"/>\n  </transform>\n</shape>\n</scene>",
        4,
        &["16 values", "found 15"],
    ),
    (
        "lookat value count",
        "<scene version=\"3.0.0\">\n<sensor type=\"perspective\">\n  <transform name=\"to_world\">\n    <lookat origin=\"0, 0\" target=\"0, 0, 1\"/>\n  </transform>\n</sensor>\n</scene>",
        4,
        &["origin", "3 values"],
    ),
    (
        "not a number",
        "<scene version=\"3.0.0\">\n<shape type=\"sphere\">\n  <float name=\"radius\" value=\"big\"/>\n</shape>\n</scene>",
        3,
        &["expected a number", "big"],
    ),
    (
        "not an integer",
        "<scene version=\"3.0.0\">\n<sensor type=\"perspective\">\n  <sampler type=\"independent\">\n    <integer name=\"sample_count\" value=\"4.5\"/>\n  </sampler>\n</sensor>\n</scene>",
        4,
        &["whole number", "4.5"],
    ),
    (
        "not a boolean",
        "<scene version=\"3.0.0\">\n<shape type=\"sphere\">\n  <boolean name=\"flip_normals\" value=\"yes\"/>\n</shape>\n</scene>",
        3,
        &["true or false"],
    ),
    (
        "wrong property type",
        "<scene version=\"3.0.0\">\n<sensor type=\"perspective\">\n  <string name=\"fov\" value=\"40\"/>\n</sensor>\n</scene>",
        3,
        &["`fov`", "<float>", "<string>"],
    ),
    (
        "undefined parameter",
        "<scene version=\"3.0.0\">\n<shape type=\"sphere\">\n  <float name=\"radius\" value=\"$r\"/>\n</shape>\n</scene>",
        3,
        &["$r", "-D r="],
    ),
    (
        "unknown ior name",
        "<scene version=\"3.0.0\">\n<bsdf type=\"dielectric\" id=\"g\">\n  <string name=\"int_ior\" value=\"unobtainium\"/>\n</bsdf>\n<shape type=\"sphere\"><ref id=\"g\"/></shape>\n</scene>",
        3,
        &["unobtainium", "bk7"],
    ),
    ("missing include", "<scene version=\"3.0.0\">\n  <include filename=\"gone.xml\"/>\n</scene>", 2, &["gone.xml"]),
    ("no type", "<scene version=\"3.0.0\">\n  <shape/>\n</scene>", 2, &["`type`"]),
    (
        "area emitter outside a shape",
        "<scene version=\"3.0.0\">\n  <emitter type=\"area\"/>\n</scene>",
        2,
        &["inside a <shape>"],
    ),
    ("no sensor", "<scene version=\"3.0.0\">\n</scene>", 1, &["no <sensor>"]),
    (
        "bad fov_axis",
        "<scene version=\"3.0.0\">\n<sensor type=\"perspective\">\n  <float name=\"fov\" value=\"40\"/>\n  <string name=\"fov_axis\" value=\"z\"/>\n</sensor>\n</scene>",
        4,
        &["fov_axis"],
    ),
    (
        "unknown transform op",
        "<scene version=\"3.0.0\">\n<shape type=\"sphere\">\n  <transform name=\"to_world\">\n    <shear value=\"1\"/>\n  </transform>\n</shape>\n</scene>",
        4,
        &["<shear>"],
    ),
    (
        "property given twice",
        "<scene version=\"3.0.0\">\n<shape type=\"sphere\">\n  <float name=\"radius\" value=\"1\"/>\n  <float name=\"radius\" value=\"2\"/>\n</shape>\n</scene>",
        4,
        &["`radius`", "more than once"],
    ),
    (
        "unsupported sensor",
        "<scene version=\"3.0.0\">\n  <sensor type=\"radiancemeter\"/>\n</scene>",
        2,
        &["radiancemeter"],
    ),
    (
        "sphere scaled unevenly",
        "<scene version=\"3.0.0\">\n<shape type=\"sphere\">\n  <transform name=\"to_world\"><scale x=\"2\"/></transform>\n</shape>\n</scene>",
        2,
        &["uniformly"],
    ),
];

#[test]
fn every_malformed_input_names_the_problem_file_and_line() {
    for (what, text, line, words) in MALFORMED {
        let e = match xml_in(text, &root(), &Options::default()) {
            Ok(_) => panic!("{what}: loaded without error"),
            Err(e) => e,
        };
        let shown = e.to_string();
        assert!(shown.starts_with(&format!("case.xml:{line}:")), "{what}: expected line {line}, got:\n{shown}");
        for w in *words {
            assert!(shown.contains(w), "{what}: `{w}` missing from:\n{shown}");
        }
        // The offending line is quoted.
        assert!(shown.contains(&format!("{line} | ")), "{what}: no snippet in:\n{shown}");
    }
}

#[test]
fn a_missing_scene_file_is_an_error() {
    let e = caustic::app::load(&root().join("scenes/mitsuba/none.xml"), &LoadOptions::default(), &Options::default())
        .err()
        .unwrap();
    assert!(e.to_string().contains("none.xml"), "{e}");
}

/// Issue 10: elements nested thousands deep used to overflow the stack and abort the process.
#[test]
fn deeply_nested_elements_are_an_error_not_a_crash() {
    for depth in [1_000usize, 5_000, 100_000] {
        for tag in ["a", "bsdf"] {
            let text = format!(
                "<scene version=\"3.0.0\">{}{}</scene>",
                format!("<{tag} type=\"diffuse\">").repeat(depth),
                format!("</{tag}>").repeat(depth)
            );
            let e = xml_in(&text, &root(), &Options::default()).err().expect("deep nesting must be refused");
            assert!(e.to_string().contains("nested more than"), "{depth} deep: {e}");
            assert!(e.to_string().starts_with("case.xml:1:"), "{e}");
        }
    }
}

/// Issue 30, item 3: `-D spq=4` (a misspelling of `spp`) rendered with the default without a
/// word; Mitsuba refuses unused parameters. Now an error naming the parameters the scene has,
/// with a did-you-mean; a `-D` on a TOML scene (which has no `$name` parameters) is an error too.
#[test]
fn defines_the_scene_never_uses_are_errors_naming_its_parameters() {
    let text = wrap(
        r#"<default name="spp" value="4"/><default name="res" value="16"/>
    <shape type="sphere"><float name="radius" value="$r"/></shape>"#,
    );
    let lo = |defs: &[(&str, &str)]| LoadOptions {
        defines: defs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect(),
        ..Default::default()
    };
    // Used names load (`r` is used, `spp` and `res` have defaults but are referenced nowhere
    // in this scene, as in Mitsuba, where a default marks nothing as used).
    assert!(xml_opts(&text, &root(), &lo(&[("r", "0.5")]), &Options::default()).is_ok());
    let e = xml_opts(&text, &root(), &lo(&[("r", "0.5"), ("q", "1")]), &Options::default()).err().unwrap().to_string();
    assert!(e.contains("-D `q` is not a parameter of this scene") && e.contains("its parameters are: `r`"), "{e}");
    let used =
        wrap(r#"<default name="spp" value="4"/><shape type="sphere"><float name="radius" value="$spp"/></shape>"#);
    let e = xml_opts(&used, &root(), &lo(&[("spq", "4")]), &Options::default()).err().unwrap().to_string();
    assert!(e.contains("`spq`") && e.contains("did you mean `spp`"), "{e}");
    let toml = root().join("scenes/06-fresnel-glass.toml");
    let e = caustic::scene::load_scene(&toml, &lo(&[("spp", "4")])).err().unwrap().to_string();
    // A TOML scene without parameters refuses a -D the same way (issue 30 item 3: TOML scenes
    // have `$name` parameters now).
    assert!(e.contains("06-fresnel-glass.toml") && e.contains("its parameters are: none"), "{e}");
}

/// Issue 30, item 7 (`--set` on Mitsuba scenes): KEY is elements from `<scene>` down (by tag,
/// or from an object's id) and a property of the last, with Mitsuba's names; the value is read as
/// one written in the file, and an error about it names the `--set`.
#[test]
fn set_changes_a_property_as_if_written_in_the_file() {
    let text = std::fs::read_to_string(root().join("scenes/mitsuba/cornell-box.xml")).unwrap();
    let sets = |s: &[(&str, &str)]| LoadOptions {
        defines: vec![("res".into(), "24".into())],
        sets: s.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect(),
        ..Default::default()
    };
    let load = |text: &str, s: &[(&str, &str)]| xml_opts(text, &root(), &sets(s), &Options::default());
    let set = [
        ("integrator.max_depth", "3"),
        ("sensor.sampler.sample_count", "2"),
        ("white.reflectance", "0.5, 0.4, 0.3"),
        ("sensor.fov", "30"),
        ("sensor.principal_point_offset_x", "0.1"),
    ];
    let written = text
        .replace(r#"<integer name="max_depth" value="9"/>"#, r#"<integer name="max_depth" value="3"/>"#)
        .replace(r#"value="$spp""#, r#"value="2""#)
        .replace(
            r#"<rgb name="reflectance" value="0.73, 0.73, 0.73"/>"#,
            r#"<rgb name="reflectance" value="0.5, 0.4, 0.3"/>"#,
        )
        .replace(r#"<float name="fov" value="39.3"/>"#, r#"<float name="fov" value="30"/>"#)
        .replace(
            r#"<float name="fov" value="30"/>"#,
            r#"<float name="fov" value="30"/><float name="principal_point_offset_x" value="0.1"/>"#,
        );
    let (by_set, _) = load(&text, &set).unwrap_or_else(|e| panic!("{e}"));
    let (by_file, _) = load(&written, &[]).unwrap_or_else(|e| panic!("{e}"));
    // Mitsuba's max_depth 3 is two bounces here.
    assert_eq!((by_set.integrator.max_depth, by_set.settings.spp), (Some(2), 2));
    assert_eq!(by_set.settings, by_file.settings);
    assert_eq!(by_set.render().image.pixels, by_file.render().image.pixels);
    let (plain, _) = load(&text.replace("$spp", "2"), &[]).unwrap();
    assert_ne!(by_set.render().image.pixels, plain.render().image.pixels, "the values change the image");

    let err = |s: &[(&str, &str)]| match load(&text, s) {
        Ok(_) => panic!("{s:?} loaded"),
        Err(e) => {
            assert_eq!(e.location(), None, "{e}");
            e.to_string()
        }
    };
    for (s, words) in [
        (
            ("integrator.max_deth", "4"),
            "--set integrator.max_deth=4: <integrator type=\"path\"> has no property `max_deth` (did you mean `max_depth`?), so this --set would change nothing",
        ),
        (("integrator.max_depth", "2.5"), "--set integrator.max_depth=2.5: expected a whole number, found `2.5`"),
        (("sensor.fov", "wide"), "--set sensor.fov=wide: expected a number, found `wide`"),
        (("sensor.flm.width", "3"), "has no nested `flm` (did you mean `film`?)"),
        (("intgrator.max_depth", "3"), "the scene has no element `intgrator` (did you mean `integrator`?)"),
        (("sensor.film", "3"), "`film` is a nested <film>, not a property"),
        (("max_depth", "3"), "name an element and one of its properties"),
        (("integrator.type", "ptracer"), "`type` is the element's plugin, not a property"),
    ] {
        let e = err(&[s]);
        assert!(e.starts_with("case.xml: --set ") && e.contains(words), "{s:?}: {e}");
    }
}
