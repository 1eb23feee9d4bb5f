//! Every malformed scene gives an error naming the problem and its place, never a panic.

mod common;

use caustic::app::{load as load_file, load_toml_str};
use caustic::options::Options;
use caustic::scene::{LoadOptions, SceneError};
use std::path::Path;

const CAMERA: &str = "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\n";

fn load(text: &str) -> Result<(), SceneError> {
    load_toml_str(text, "bad.toml", Path::new(env!("CARGO_MANIFEST_DIR")), &Options::default()).map(|_| ())
}

/// (name, scene text, words the message must contain, line the error must point at)
fn cases() -> Vec<(&'static str, String, &'static str, usize)> {
    let with_cam = |s: &str| format!("{CAMERA}{s}");
    vec![
        ("syntax error", with_cam("[render\nwidth = 3\n"), "", 4),
        ("unknown section", with_cam("[rendr]\nwidth = 3\n"), "unknown section `rendr`", 4),
        ("unknown key", with_cam("[render]\nwidht = 3\n"), "widht", 5),
        (
            "wrong type",
            with_cam("[render]\nwidth = \"big\"\n"),
            "expected a whole number of 0 or more, found the text \"big\"",
            5,
        ),
        ("negative integer", with_cam("[render]\nheight = -4\n"), "-4", 5),
        ("adc_bailout above 1", with_cam("[render]\nmax_depth = 4\nadc_bailout = 2\n"), "from 0 to 1", 6),
        ("NaN colour", with_cam("[render]\nbackground = [nan, 0, 0]\n"), "finite", 5),
        ("infinite point", "[camera]\neye = [0, inf, 5]\nlook_at = [0, 0, 0]\n".into(), "finite", 2),
        ("missing camera", "[render]\nwidth = 10\n".into(), "missing [camera]", 1),
        ("eye equals look_at", "[camera]\neye = [1, 1, 1]\nlook_at = [1, 1, 1]\n".into(), "same point", 1),
        ("up parallel", "[camera]\neye = [0, 5, 0]\nlook_at = [0, 0, 0]\n".into(), "parallel", 1),
        ("zero direction", with_cam("[[lights]]\ntype = \"directional\"\ndirection = [0, 0, 0]\n"), "zero-length", 6),
        ("negative radius", with_cam("[[objects]]\ntype = \"sphere\"\nradius = -1\n"), "positive", 6),
        ("NaN radius", with_cam("[[objects]]\ntype = \"sphere\"\nradius = nan\n"), "finite", 6),
        ("unknown object type", with_cam("[[objects]]\ntype = \"cone\"\n"), "unknown object type `cone`", 5),
        ("missing type", with_cam("[[objects]]\nradius = 1\n"), "no `type`", 4),
        (
            "key of another shape",
            with_cam("[[objects]]\ntype = \"box\"\nradius = 1\n"),
            "unknown key `radius` for a box",
            6,
        ),
        (
            "missing material",
            with_cam("[[objects]]\ntype = \"sphere\"\nmaterial = \"gold\"\n"),
            "no material named `gold`",
            6,
        ),
        (
            "missing mesh file",
            with_cam("[[objects]]\ntype = \"mesh\"\nfile = \"no/such/file.obj\"\n"),
            "no/such/file.obj",
            6,
        ),
        ("mesh without file", with_cam("[[objects]]\ntype = \"mesh\"\n"), "needs `file`", 4),
        ("kr out of range", with_cam("[materials.m]\ntype = \"reflective\"\nkr = 1.5\n"), "from 0 to 1", 6),
        ("ior on diffuse", with_cam("[materials.m]\ntype = \"diffuse\"\nior = 1.5\n"), "unknown key `ior`", 6),
        ("zero ior", with_cam("[materials.m]\ntype = \"dielectric\"\nior = 0\n"), "positive", 6),
        ("bad transform op", with_cam("[[objects]]\ntype = \"sphere\"\ntransform = [{ shear = 2 }]\n"), "shear", 6),
        ("zero scale", with_cam("[[objects]]\ntype = \"sphere\"\ntransform = [{ scale = 0 }]\n"), "non-zero", 6),
        (
            "non-uniform sphere scale",
            with_cam("[[objects]]\ntype = \"sphere\"\ntransform = [{ scale = [1, 2, 1] }]\n"),
            "ellipsoid",
            4,
        ),
        ("inverted box", with_cam("[[objects]]\ntype = \"box\"\nmin = [1, 0, 0]\nmax = [0, 1, 1]\n"), "below", 4),
        (
            "degenerate quad",
            with_cam("[[objects]]\ntype = \"quad\"\nedge1 = [1, 0, 0]\nedge2 = [2, 0, 0]\n"),
            "no area",
            4,
        ),
        ("fov too wide", "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov = 180\n".into(), "180", 1),
        ("focus behind", "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\nfocus_on = [0, 0, 9]\n".into(), "front", 1),
        ("bad lights array", format!("lights = 3\n{CAMERA}"), "array", 1),
        ("huge number", with_cam("[[objects]]\ntype = \"sphere\"\nradius = 1e300\n"), "too large", 6),
        (
            "torus knot too big",
            with_cam("[[objects]]\ntype = \"torus_knot\"\nsegments = 100000\nsides = 100000\n"),
            "at most",
            4,
        ),
    ]
}

#[test]
fn malformed_scenes_report_problem_and_place() {
    for (name, text, words, line) in cases() {
        let err = match std::panic::catch_unwind(|| load(&text)) {
            Ok(Ok(())) => panic!("{name}: scene loaded but should have failed:\n{text}"),
            Ok(Err(e)) => e,
            Err(_) => panic!("{name}: the loader panicked"),
        };
        let shown = err.to_string();
        assert!(shown.contains(words), "{name}: message lacks `{words}`:\n{shown}");
        assert!(shown.starts_with("bad.toml"), "{name}: message does not name the file:\n{shown}");
        if line > 0 {
            assert_eq!(err.location().map(|l| l.0), Some(line), "{name}: wrong line:\n{shown}");
        }
    }
}

#[test]
fn unreadable_files_are_named() {
    let e =
        load_file(Path::new("/definitely/not/here.toml"), &LoadOptions::default(), &Options::default()).err().unwrap();
    assert!(e.to_string().contains("/definitely/not/here.toml"));
    let dir = common::scratch("binary");
    let p = dir.join("binary.toml");
    std::fs::write(&p, [0xffu8, 0xfe, 0x00, 0x41]).unwrap();
    let e = load_file(&p, &LoadOptions::default(), &Options::default()).err().unwrap();
    assert!(e.to_string().contains("binary.toml"), "{e}");
}

#[test]
fn image_size_overrides_are_checked() {
    let o = Options { width: Some(0), ..Default::default() };
    let e = load_toml_str(CAMERA, "x.toml", Path::new("."), &o).err().unwrap();
    assert!(e.to_string().contains("out of range"));
}

/// Issue 30, item 3: `-D name=value` fills `$name` in TOML scenes as in Mitsuba XML: defaults in
/// `[parameters]`, values with the default's type, checked where they are used, and a `-D` the
/// scene never uses refused with its parameters and a did-you-mean.
mod parameters {
    use caustic::scene::{FileBudget, LoadOptions, load_scene_within};

    const SCENE: &str = "[parameters]\nspp = 16\nradius = 1\ncolour = [0.8, 0.2, 0.1]\nmesh = \"blob\"\n\
[render]\nspp = \"$spp\"\n[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\n\
[materials.m]\ntype = \"diffuse\"\ncolor = \"$colour\"\n\
[[objects]]\ntype = \"sphere\"\nradius = \"$radius\"\nmaterial = \"m\"\n\
[[objects]]\ntype = \"mesh\"\nfile = \"meshes/$mesh.ply\"\n";

    fn err(text: &str, defines: &[(&str, &str)]) -> String {
        match load(text, defines) {
            Ok(_) => panic!("loaded"),
            Err(e) => e,
        }
    }

    fn load(text: &str, defines: &[(&str, &str)]) -> Result<caustic::scene::SceneDescription, String> {
        let dir = std::env::temp_dir().join(format!("caustic-params-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("meshes")).unwrap();
        let blob = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/meshes/blob.ply");
        std::fs::copy(&blob, dir.join("meshes/blob.ply")).unwrap();
        std::fs::copy(&blob, dir.join("meshes/other.ply")).unwrap();
        // Each load its own file: the tests run at the same time.
        static N: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
        let n = N.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let path = dir.join(format!("p{n}.toml"));
        std::fs::write(&path, text).unwrap();
        let o = LoadOptions {
            defines: defines.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect(),
            strict: false,
        };
        load_scene_within(&path, &o, &FileBudget::unlimited()).map_err(|e| e.to_string())
    }

    #[test]
    fn defaults_and_defines_fill_parameters_with_their_types() {
        let Ok(d) = load(SCENE, &[]) else { panic!() };
        assert_eq!(d.sampler.spp, Some(16));
        assert!(d.files().iter().any(|f| f.ends_with("meshes/blob.ply")));
        let d = match load(SCENE, &[("spp", "4"), ("mesh", "other"), ("radius", "2.5")]) {
            Ok(d) => d,
            Err(e) => panic!("{e}"),
        };
        assert_eq!(d.sampler.spp, Some(4));
        assert!(d.files().iter().any(|f| f.ends_with("meshes/other.ply")));
    }

    #[test]
    fn wrong_types_and_unknown_names_are_said_in_the_scenes_words() {
        let e = err(SCENE, &[("spp", "abc")]);
        assert!(
            e.contains("-D spp=abc: `$spp` is a number in this scene (its default, line 2), found the text \"abc\""),
            "{e}"
        );
        let e = err(SCENE, &[("spp", "4.5")]);
        assert!(e.contains(":7:7: expected a whole number") && e.contains("(the value of parameter `$spp`)"), "{e}");
        let e = err(SCENE, &[("spq", "4")]);
        assert!(e.contains("-D `spq` is not a parameter of this scene (did you mean `spp` for `spq`?)"), "{e}");
        assert!(e.contains("`colour`, `mesh`, `radius`, `spp`"), "{e}");
        // Checked where it is used, at the use's line, naming the parameter.
        let e = err(&SCENE.replace("radius = 1\n", "radius = -1\n"), &[]);
        assert!(e.contains(".toml:16:") && e.contains("(the value of parameter `$radius`)"), "{e}");
        let e = err(&SCENE.replace("spp = 16\n", ""), &[]);
        assert!(
            e.contains("parameter `$spp` has no value: give it a default in [parameters] or pass -D spp=VALUE"),
            "{e}"
        );
    }
}
