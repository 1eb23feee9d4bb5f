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
        ("unknown key", with_cam("[render]\nwidht = 3\n"), "unknown key `widht` (did you mean `width`?)", 5),
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
        (
            "missing spectrum file",
            with_cam("[materials.m]\ntype = \"diffuse\"\ncolor = { spectrum = \"no/such.spd\" }\n"),
            "spectrum file `",
            6,
        ),
        (
            "spectrum pair of one number",
            with_cam("[materials.m]\ntype = \"diffuse\"\ncolor = { spectrum = [[400], [500, 1]] }\n"),
            "a spectrum",
            6,
        ),
        (
            "spectrum wavelengths out of order",
            with_cam("[[lights]]\ntype = \"point\"\ncolor = { spectrum = [[500, 1], [400, 1]] }\n"),
            "wavelengths must increase",
            6,
        ),
        ("cold black body", with_cam("[[lights]]\ntype = \"point\"\ncolor = { blackbody = -5 }\n"), "kelvin", 6),
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
        // Each load its own folder: the tests run at the same time, and a mesh copied over while
        // another load reads it would be read cut short.
        static N: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
        let n = N.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("caustic-params-{}-{n}", std::process::id()));
        std::fs::create_dir_all(dir.join("meshes")).unwrap();
        let blob = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/meshes/blob.ply");
        std::fs::copy(&blob, dir.join("meshes/blob.ply")).unwrap();
        std::fs::copy(&blob, dir.join("meshes/other.ply")).unwrap();
        let path = dir.join(format!("p{n}.toml"));
        std::fs::write(&path, text).unwrap();
        let o = LoadOptions {
            defines: defines.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect(),
            ..Default::default()
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

/// Issue 30, item 7 (`--set`): any key of a TOML scene by its path, put into the file's tree
/// before it is read, so the value meets the checks a value written in the file meets; an error
/// about it names the `--set`, not a line of the file.
mod set {
    use caustic::app::prepare;
    use caustic::options::Options;
    use caustic::scene::{LoadOptions, SceneError, load_scene_str_with};
    use std::path::Path;

    /// A glass ball and an area light (light samples count) on a floor: the keys the tests change.
    const SCENE: &str = "[render]\nwidth = 24\nheight = 18\nspp = 1\nintegrator = \"whitted\"\n\
[camera]\neye = [0, 1, 4]\nlook_at = [0, 0.5, 0]\nfov = 40\n\
[materials.glass]\ntype = \"dielectric\"\nior = 1.5\n\
[materials.floor]\ntype = \"diffuse\"\ncolor = [0.8, 0.7, 0.6]\n\
[[lights]]\ntype = \"area\"\ncorner = [-0.5, 3, -0.5]\nedge1 = [1, 0, 0]\nedge2 = [0, 0, 1]\nintensity = 20\n\
[[objects]]\ntype = \"plane\"\nmaterial = \"floor\"\n\
[[objects]]\ntype = \"sphere\"\ncenter = [0, 0.5, 0]\nradius = 0.5\nmaterial = \"glass\"\n";

    fn with_sets(text: &str, sets: &[(&str, &str)]) -> Result<caustic::app::LoadedScene, SceneError> {
        let lo = LoadOptions {
            sets: sets.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect(),
            ..Default::default()
        };
        let desc = load_scene_str_with(text, "s.toml", Path::new(env!("CARGO_MANIFEST_DIR")), &lo)?;
        prepare(desc, &Options::default())
    }

    fn err(sets: &[(&str, &str)]) -> SceneError {
        match with_sets(SCENE, sets) {
            Ok(_) => panic!("{sets:?} loaded"),
            Err(e) => e,
        }
    }

    /// The examples render exactly as the file with those values written in it.
    #[test]
    fn set_values_render_as_the_file_with_them_written() {
        let sets = [
            ("render.spp", "4"),
            ("integrator.light_samples", "4"),
            ("film.filter", "gaussian"),
            ("materials.glass.ior", "1.6"),
            ("camera.fov", "30"),
            ("sampler.seed", "7"),
        ];
        let written = SCENE
            .replace("spp = 1\n", "spp = 4\nlight_samples = 4\nfilter = \"gaussian\"\nseed = 7\n")
            .replace("ior = 1.5", "ior = 1.6")
            .replace("fov = 40", "fov = 30");
        let by_set = with_sets(SCENE, &sets).unwrap();
        let by_file = with_sets(&written, &[]).unwrap();
        let plain = with_sets(SCENE, &[]).unwrap();
        assert_eq!(by_set.settings.spp, 4);
        assert_eq!(by_set.integrator.light_samples, 4);
        assert_eq!(by_set.settings.seed, 7);
        assert_eq!(by_set.settings, by_file.settings);
        let (a, b) = (by_set.render().image, by_file.render().image);
        assert_eq!(a.pixels, b.pixels, "--set and the same values written in the file render alike");
        assert_ne!(a.pixels, plain.render().image.pixels, "the values change the image");
    }

    /// Later `--set`s of a key win, a `--set` wins over a `$name` parameter there, a key the
    /// file lacks is added, a list entry is picked by its index, and a section the file lacks is
    /// made.
    #[test]
    fn set_adds_replaces_and_indexes() {
        let s = with_sets(SCENE, &[("render.spp", "2"), ("sampler.spp", "3")]).unwrap();
        assert_eq!(s.settings.spp, 3);
        let param = SCENE.replace("spp = 1\n", "spp = \"$n\"\n").replace("[render]", "[parameters]\nn = 5\n[render]");
        assert_eq!(with_sets(&param, &[("render.spp", "6")]).unwrap().settings.spp, 6);
        let s = with_sets(SCENE, &[("render.max_depth", "2"), ("integrator", "path")]).unwrap();
        assert_eq!((s.integrator.max_depth, s.integrator.kind.name()), (Some(2), "path"));
        let wider = with_sets(SCENE, &[("objects.1.radius", "0.9")]).unwrap();
        assert!(wider.scene.bounds().max.x > 0.85, "{:?}", wider.scene.bounds());
        let no_render = SCENE.replace("[render]\nwidth = 24\nheight = 18\nspp = 1\nintegrator = \"whitted\"\n", "");
        let s = with_sets(&no_render, &[("film.width", "10"), ("render.photon.gather", "0")]).unwrap();
        assert_eq!((s.settings.width, s.integrator.photon.gather), (10, Some(0)));
        // A filter with parameters as --filter spells it, or as a TOML table.
        let tent = caustic::film::filter::Filter::Tent { radius: 1.5 };
        assert_eq!(with_sets(SCENE, &[("film.filter", "tent:radius=1.5")]).unwrap().settings.filter.filter, tent);
        let table = with_sets(SCENE, &[("film.filter", "{ type = \"tent\", radius = 1.5 }")]).unwrap();
        assert_eq!(table.settings.filter.filter, tent);
    }

    #[test]
    fn set_errors_name_the_set_with_the_files_words() {
        let cases: [(&[(&str, &str)], &str); 10] = [
            (&[("render.spq", "4")], "--set render.spq=4: unknown key `spq` (did you mean `spp`?)"),
            (&[("render.spp", "x")], "--set render.spp=x: expected a whole number of 0 or more, found the text \"x\""),
            (
                &[("integrator.light_sample", "4")],
                "unknown key `light_sample` of integrator (did you mean `light_samples`?)",
            ),
            (&[("film.filter", "gausian")], "unknown filter `gausian` (did you mean `gaussian`?)"),
            (
                &[("materials.glas.ior", "1.6")],
                "no material named `glas` (defined: floor, glass); did you mean `glass`?",
            ),
            (&[("materials.glass.ior", "-1")], "--set materials.glass.ior=-1: expected a positive number, found -1"),
            (&[("materials.glass.iorr", "1")], "unknown key `iorr` for a dielectric material (did you mean `ior`?)"),
            (&[("objects.5.radius", "1")], "`objects` has 2 entries (0 to 1): it has no entry 5"),
            (&[("camera.fvo", "30")], "--set camera.fvo=30: unknown key `fvo` (did you mean `fov`?)"),
            (&[("rendr.spp", "4")], "unknown section `rendr` (did you mean `render`?)"),
        ];
        for (sets, words) in cases {
            let e = err(sets);
            let text = e.to_string();
            assert!(text.starts_with("s.toml: --set ") && text.contains(words), "{sets:?}: {text}");
            // Not a position in the file: the value came from the command line.
            assert_eq!(e.location(), None, "{text}");
        }
        // A value written in the file still gets its line.
        let e = match with_sets(&SCENE.replace("radius = 0.5", "radius = -0.5"), &[("render.spp", "2")]) {
            Ok(_) => panic!("a negative radius loaded"),
            Err(e) => e,
        };
        assert_eq!(e.location().map(|l| l.0), Some(SCENE.lines().position(|l| l == "radius = 0.5").unwrap() + 1));
    }
}
