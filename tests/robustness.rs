//! Robustness properties (see FUZZING.md): the loaders never panic on any input, and rays spawned
//! from a hit never re-hit their own surface at any scale.
//!
//! Case counts are fixed so the suite stays fast (16,000 loader inputs and 1,000 + 300
//! self-intersection cases per run); `ROBUSTNESS_SCALE=N` multiplies every count for long runs.
//! Failure persistence is off: a failure found here becomes a named regression test at the end
//! of this file instead.

use caustic::accel::Bvh;
use caustic::app::{LoadedScene, load_toml_str, prepare};
use caustic::geometry::Ray;
use caustic::light::Light;
use caustic::math::{Vec2, Vec3};
use caustic::options::Options;
use caustic::scene::LoadOptions;
use caustic::shape::{Primitive, Quad, RayShear, Shape, Sphere, Triangle, TriangleMesh};
use proptest::prelude::*;
use proptest::test_runner::Config as ProptestConfig;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

// ---------------------------------------------------------------------------------------------
// Shared helpers
// ---------------------------------------------------------------------------------------------

/// `n` cases, times `ROBUSTNESS_SCALE` (default 1) for long runs.
fn scaled(n: u32) -> u32 {
    let k = std::env::var("ROBUSTNESS_SCALE").ok().and_then(|s| s.parse::<u32>().ok()).unwrap_or(1).max(1);
    n.saturating_mul(k)
}

fn config(cases: u32) -> ProptestConfig {
    ProptestConfig { cases: scaled(cases), failure_persistence: None, ..ProptestConfig::default() }
}

/// A folder with a few mesh files that generated scenes refer to (valid, broken, non-finite).
fn mesh_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let d = std::env::temp_dir().join(format!("caustic-robustness-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let files = [
            ("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
            (
                "quad.obj",
                "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nf 1//1 2//2 3//3 4//4\n",
            ),
            ("degenerate.obj", "v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\nv 5 5 5\nf 4 4 4\n"),
            ("nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
            ("huge.obj", "v 3e38 0 0\nv -3e38 0 0\nv 0 3e38 0\nf 1 2 3\n"),
            ("zero_normals.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 0\nvn 0 0 0\nvn 0 0 0\nf 1//1 2//2 3//3\n"),
            ("bad_index.obj", "v 0 0 0\nv 1 0 0\nf 1 2 9\n"),
            ("empty.obj", ""),
        ];
        for (name, text) in files {
            std::fs::write(d.join(name), text).unwrap();
        }
        d
    })
}

/// A scratch file path unique to one test (tests run on parallel threads).
fn scratch_file(name: &str) -> PathBuf {
    mesh_dir().join(name)
}

/// Loads `text`; a panic fails the property. An accepted scene must be usable: finite bounds
/// (or none), finite light power, and camera rays that trace without panicking.
fn load_and_check(text: &str) -> Result<(), TestCaseError> {
    let Ok(loaded) = load_toml_str(text, "fuzz.toml", mesh_dir(), &Options::default()) else {
        return Ok(());
    };
    check_loaded(&loaded).map_err(|m| TestCaseError::fail(format!("{m}\n--- scene ---\n{text}")))
}

fn check_loaded(loaded: &LoadedScene) -> Result<(), String> {
    let scene = &loaded.scene;
    // Overflows the property tests once found (the `regression_*` tests at the end) are now
    // rejected by the loader, so an accepted scene must pass every check.
    let known = |m: String| Err(m);
    let b = scene.bounds();
    if !(b.is_empty() || b.min.is_finite() && b.max.is_finite()) {
        known(format!("accepted scene has non-finite bounds {b:?}"))?;
    }
    for (i, l) in scene.lights.iter().enumerate() {
        let p = l.power();
        if !p.is_finite() {
            known(format!("accepted light {i} has non-finite power {p}: {l:?}"))?;
        }
        if let Light::Area { shape, .. } = l {
            let a = shape.area();
            if !(a > 0.0 && a.is_finite()) {
                known(format!("accepted area light {i} has area {a}: {l:?}"))?;
            }
        }
    }
    // A few camera rays, each intersected: no panic, and every hit is a finite point.
    let (w, h) = (loaded.settings.width as f32, loaded.settings.height as f32);
    for raster in [Vec2::new(0.5 * w, 0.5 * h), Vec2::ZERO, Vec2::new(w, h), Vec2::new(0.3 * w, 0.8 * h)] {
        let ray = scene.camera.generate_ray(raster, Vec2::new(0.5, 0.5));
        if !(ray.o.is_finite() && ray.d.is_finite() && (ray.d.length() - 1.0).abs() < 1e-3) {
            known(format!("camera ray {ray:?} for raster {raster} is not a finite unit ray"))?;
            continue;
        }
        if let Some(hit) = scene.intersect(&ray, f32::INFINITY)
            && !(hit.p.is_finite() && hit.t > 0.0)
        {
            known(format!("camera ray {ray:?} hit at non-finite point {hit:?}"))?;
        }
        let _ = scene.occluded(&ray, f32::INFINITY);
    }
    // Filtered camera samples at the image's corners (truncated at the window's edges): finite,
    // non-zero weights.
    let settings = &loaded.settings;
    for (x, y) in [(0, 0), (settings.width - 1, settings.height - 1)] {
        for index in 0..4 {
            let (_, _, weight) = settings.camera_sample(scene, x, y, index);
            if !(weight.is_finite() && weight != 0.0) {
                known(format!("camera sample {index} of pixel ({x}, {y}) has weight {weight}"))?;
            }
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Scene TOML generator: well-formed documents with random sections, keys and values
// ---------------------------------------------------------------------------------------------

fn fmt_f64(v: f64) -> String {
    if v.is_nan() {
        "nan".into()
    } else if v.is_infinite() {
        if v > 0.0 { "inf".into() } else { "-inf".into() }
    } else {
        // Debug keeps a decimal point or exponent, which TOML reads as a float.
        format!("{v:?}")
    }
}

/// A TOML number, mostly ordinary, sometimes special: NaN, infinities, negative zero, values
/// beyond f32 or f64, subnormals, integers that overflow i64.
fn number() -> BoxedStrategy<String> {
    prop_oneof![
        6 => (-4i32..=4).prop_map(|i| i.to_string()),
        6 => (-10.0f64..10.0).prop_map(fmt_f64),
        2 => (-45.0f64..39.0, any::<bool>()).prop_map(|(e, neg)| fmt_f64(if neg { -1.0 } else { 1.0 } * 10f64.powf(e))),
        2 => prop::sample::select(vec![
            "nan", "+nan", "-nan", "inf", "+inf", "-inf", "0.0", "-0.0", "0", "1e39", "-1e39", "3.4028235e38",
            "3.4028236e38", "1e308", "1.7976931348623157e308", "1e-45", "1e-46", "5e-324", "9223372036854775807",
            "99999999999999999999", "-9223372036854775808", "1e-8", "1e8", "0x10", "0o7", "0b1", "1_000",
        ]).prop_map(str::to_string),
        1 => any::<f64>().prop_map(fmt_f64),
    ]
    .boxed()
}

/// A whole number (counts, sizes, seeds), sometimes zero, negative, huge or a float.
fn whole() -> BoxedStrategy<String> {
    prop_oneof![
        8 => (0u32..20).prop_map(|i| i.to_string()),
        2 => prop::sample::select(vec![
            "0", "-1", "1.0", "65536", "65537", "4096", "4097", "4294967295", "4294967296", "18446744073709551615",
            "1000", "1001", "nan", "1e3", "\"4\"",
        ]).prop_map(str::to_string),
    ]
    .boxed()
}

/// Three numbers, with coordinates often repeated (so eye == look_at, parallel edges, zero
/// vectors and collinear points come up), or an array of the wrong length.
fn vec3() -> BoxedStrategy<String> {
    let coord = prop_oneof![3 => prop::sample::select(vec!["0", "1", "-1", "2", "0.5"]).prop_map(str::to_string), 2 => number()];
    prop_oneof![
        10 => (coord.clone(), coord.clone(), coord).prop_map(|(a, b, c)| format!("[{a}, {b}, {c}]")),
        1 => prop::sample::select(vec!["[]", "[1]", "[1, 2]", "[1, 2, 3, 4]", "[0, 0, 0]", "[[1], 2, 3]", "[\"a\", 1, 2]", "1", "\"up\""])
            .prop_map(str::to_string),
    ]
    .boxed()
}

/// A number the loader accepts for a key of `range`, extremes included: ordinary values, and
/// now and then the largest or smallest floats (so accepted scenes can still overflow).
fn valid_number(range: Range) -> BoxedStrategy<String> {
    let extreme_pos =
        prop::sample::select(vec!["3.4028234e38", "1e38", "1e30", "1e20", "1e-20", "1e-38", "1e-45", "1e-30"])
            .prop_map(str::to_string);
    match range {
        Range::Any => prop_oneof![
            8 => prop::sample::select(vec!["0", "1", "-1", "2", "0.5", "-3", "10"]).prop_map(str::to_string),
            4 => (-10.0f64..10.0).prop_map(fmt_f64),
            1 => extreme_pos.prop_map(|s| s.to_string()),
            1 => prop::sample::select(vec!["-3.4028234e38", "-1e30", "-1e-45", "-0.0"]).prop_map(str::to_string),
        ]
        .boxed(),
        Range::Positive => prop_oneof![
            8 => prop::sample::select(vec!["1", "2", "0.5", "0.25", "10"]).prop_map(str::to_string),
            4 => (0.01f64..10.0).prop_map(fmt_f64),
            1 => extreme_pos,
        ]
        .boxed(),
        Range::NonNegative => prop_oneof![
            8 => prop::sample::select(vec!["0", "1", "2", "0.5", "0.0"]).prop_map(str::to_string),
            4 => (0.0f64..10.0).prop_map(fmt_f64),
            1 => extreme_pos,
        ]
        .boxed(),
        Range::Unit => prop_oneof![
            4 => prop::sample::select(vec!["0", "1", "0.5", "0.0", "1.0"]).prop_map(str::to_string),
            4 => (0.0f64..=1.0).prop_map(fmt_f64),
            1 => Just("1e-45".to_string()),
        ]
        .boxed(),
        Range::Degrees => prop_oneof![
            4 => prop::sample::select(vec!["1", "30", "45", "60", "89.9", "90", "179.9"]).prop_map(str::to_string),
            4 => (0.001f64..180.0).prop_map(fmt_f64),
            1 => Just("1e-45".to_string()),
        ]
        .boxed(),
    }
}

#[derive(Clone, Copy, Debug)]
enum Range {
    Any,
    Positive,
    NonNegative,
    Unit,
    Degrees,
}

/// An accepted direction: three ordinary numbers, one of them at least 0.5. (Extreme components
/// make the loader's normalisation overflow or underflow; `value_for` covers those as wrong values.)
fn valid_direction() -> BoxedStrategy<String> {
    (-10.0f64..10.0, -10.0f64..10.0, 0.5f64..10.0, 0usize..3, any::<bool>())
        .prop_map(|(a, b, c, k, neg)| {
            let mut v = [a, b, if neg { -c } else { c }];
            v.rotate_left(k);
            format!("[{}, {}, {}]", fmt_f64(v[0]), fmt_f64(v[1]), fmt_f64(v[2]))
        })
        .boxed()
}

/// Three accepted numbers in `range`.
fn valid_vec3(range: Range) -> BoxedStrategy<String> {
    (valid_number(range), valid_number(range), valid_number(range))
        .prop_map(|(a, b, c)| format!("[{a}, {b}, {c}]"))
        .boxed()
}

/// A value of any type (for keys given the wrong type, or unknown keys).
fn any_value() -> BoxedStrategy<String> {
    let leaf = prop_oneof![
        number(),
        vec3(),
        "[a-z_]{0,8}".prop_map(|s| format!("{s:?}")),
        prop::sample::select(vec![
            "true",
            "false",
            "\"\"",
            "\"\\u0000\"",
            "'''x'''",
            "1979-05-27T07:32:00Z",
            "{}",
            "[]"
        ])
        .prop_map(str::to_string),
    ];
    leaf.prop_recursive(3, 12, 4, |inner| {
        prop_oneof![
            prop::collection::vec(inner.clone(), 0..4).prop_map(|v| format!("[{}]", v.join(", "))),
            prop::collection::vec(("[a-z]{1,6}", inner), 0..3).prop_map(|kv| {
                let kv: Vec<String> = kv.into_iter().enumerate().map(|(i, (k, v))| format!("{k}{i} = {v}")).collect();
                format!("{{ {} }}", kv.join(", "))
            }),
        ]
    })
    .boxed()
}

/// A transform list, up to 16 operations deep: mostly valid ones (with extreme scales and
/// offsets that can overflow), sometimes singular, non-finite or malformed ones.
fn transform(noisy: bool) -> BoxedStrategy<String> {
    let scale = prop_oneof![
        3 => valid_number(Range::Positive),
        1 => valid_number(Range::Positive).prop_map(|s| format!("-{s}")),
        2 => (valid_number(Range::Positive), valid_number(Range::Positive), valid_number(Range::Positive))
            .prop_map(|(a, b, c)| format!("[{a}, -{b}, {c}]")),
    ];
    let noise = if noisy { 1 } else { 0 };
    let op = prop_oneof![
        12 => valid_vec3(Range::Any).prop_map(|v| format!("{{ translate = {v} }}")),
        12 => (valid_direction(), valid_number(Range::Any))
            .prop_map(|(a, d)| format!("{{ rotate = {{ axis = {a}, degrees = {d} }} }}")),
        12 => scale.prop_map(|s| format!("{{ scale = {s} }}")),
        noise => vec3().prop_map(|v| format!("{{ translate = {v} }}")),
        noise => (vec3(), number()).prop_map(|(a, d)| format!("{{ rotate = {{ axis = {a}, degrees = {d} }} }}")),
        noise => prop_oneof![number(), vec3()].prop_map(|s| format!("{{ scale = {s} }}")),
        noise => any_value(),
        noise => (vec3(), vec3()).prop_map(|(a, b)| format!("{{ translate = {a}, scale = {b} }}")),
    ];
    prop_oneof![6 => prop::collection::vec(op.clone(), 0..4), 1 => prop::collection::vec(op, 4..16)]
        .prop_map(|ops| format!("[{}]", ops.join(", ")))
        .boxed()
}

const MATERIAL_NAMES: &[&str] = &["a", "b", "glass", "mirror"];
const MESH_FILES: &[&str] = &[
    "tri.obj",
    "quad.obj",
    "degenerate.obj",
    "nan.obj",
    "huge.obj",
    "zero_normals.obj",
    "bad_index.obj",
    "empty.obj",
    "missing.obj",
    "",
    ".",
    "..",
];

/// `Some` with probability `p` (which may be 0, unlike `prop::option::weighted`).
fn maybe<S: Strategy + 'static>(p: f64, s: S) -> BoxedStrategy<Option<S::Value>>
where
    S::Value: Clone,
{
    if p > 0.0 { prop::option::weighted(p, s).boxed() } else { Just(None).boxed() }
}

/// A value suited to `key`: one the loader accepts (extremes included), or, when `noisy`, now and
/// then a wrong one of the right type (NaN, negative, zero vector, ...) or anything at all.
fn value_for(key: &'static str, noisy: bool) -> BoxedStrategy<String> {
    let str_of = |v: Vec<&'static str>| prop::sample::select(v).prop_map(str::to_string).boxed();
    let (valid, wrong): (BoxedStrategy<String>, BoxedStrategy<String>) = match key {
        "up" | "direction" | "normal" => (valid_direction(), prop_oneof![vec3(), valid_vec3(Range::Any)].boxed()),
        "eye" | "look_at" | "focus_on" | "position" | "center" | "point" | "corner" | "edge1" | "edge2" | "min"
        | "max" | "p0" | "p1" => (valid_vec3(Range::Any), vec3()),
        "color" | "background" | "ambient" => {
            (prop_oneof![3 => valid_vec3(Range::NonNegative), 1 => valid_number(Range::NonNegative)].boxed(), vec3())
        }
        // Mesh resolution stays small: up to 50 million triangles are allowed and would take
        // seconds and gigabytes each.
        "segments" | "sides" => (
            (3u32..12).prop_map(|i| i.to_string()).boxed(),
            str_of(vec!["0", "2", "-1", "1.0", "4294967295", "100000000"]),
        ),
        "width" | "height" | "spp" | "spp_axis" | "max_depth" | "seed" | "light_samples" | "p" | "q" | "photons"
        | "caustic_photons" | "gather" | "gather_k" | "caustic_k" | "volume_k" => {
            (prop_oneof![4 => (1u32..12).prop_map(|i| i.to_string()), 1 => whole()].boxed(), whole())
        }
        "transform" => (transform(noisy), any_value()),
        "material" => (prop::sample::select(MATERIAL_NAMES).prop_map(|s| format!("{s:?}")).boxed(), any_value()),
        "file" => (
            prop::sample::select(if noisy { MESH_FILES } else { &MESH_FILES[..6] })
                .prop_map(|s| format!("{s:?}"))
                .boxed(),
            any_value(),
        ),
        "shape" => (str_of(vec!["\"quad\"", "\"sphere\""]), str_of(vec!["\"disk\"", "1", "\"\""])),
        "group" => (str_of(vec!["\"g\""]), str_of(vec!["\"h\"", "1", "\"\""])),
        "integrator" => (str_of(vec!["\"whitted\"", "\"path\"", "\"photon\""]), str_of(vec!["\"bdpt\"", "0"])),
        "sampler" => (str_of(vec!["\"jittered\"", "\"sobol\""]), str_of(vec!["\"halton\"", "0"])),
        "antialias" | "transparent_shadows" | "sample_border" => {
            (str_of(vec!["true", "false"]), str_of(vec!["1", "\"yes\""]))
        }
        "filter" => (
            str_of(vec![
                "\"box\"",
                "\"gaussian\"",
                "\"catmullrom\"",
                "{ type = \"mitchell\", B = 0.5, C = 0.25 }",
                "{ type = \"lanczos\", lobes = 5 }",
                "{ type = \"tent\", radius = 0.01 }",
                "{ type = \"gaussian\", stddev = 16 }",
            ]),
            str_of(vec![
                "\"sinc\"",
                "{ type = \"mitchell\", B = 9 }",
                "{ type = \"tent\", radius = 1e30 }",
                "{ type = \"gaussian\", stddev = 1e-40 }",
                "{ type = \"lanczos\", lobes = 4294967295 }",
                "{ lobes = 3 }",
                "1",
            ]),
        ),
        "crop" => (
            str_of(vec!["{ width = 1, height = 1 }", "{ x = 1, y = 1, width = 2, height = 3 }"]),
            str_of(vec![
                "{ x = -1, width = 1, height = 1 }",
                "{ width = 0, height = 1 }",
                "{ x = 4294967295, y = 4294967295, width = 4294967295, height = 4294967295 }",
                "[0, 0, 1, 1]",
            ]),
        ),
        "projection" => (str_of(vec!["\"perspective\"", "\"orthographic\""]), str_of(vec!["\"fisheye\"", "2"])),
        "principal_point_offset" => (
            str_of(vec!["[0.1, -0.2]", "[0, 0]", "[-1e30, 1e30]", "[3e38, 0]"]),
            str_of(vec!["[0.1]", "[\"a\", 1]", "0.5"]),
        ),
        "radius" | "fov" | "ior" | "tube" | "view_distance" | "focal_distance" | "max_radius" | "caustic_radius"
        | "volume_radius" | "view_width" | "view_height" => {
            (valid_number(if key == "fov" { Range::Degrees } else { Range::Positive }), number())
        }
        "angle" | "falloff" => (valid_number(Range::Degrees), number()),
        "kr" | "kt" => (valid_number(Range::Unit), number()),
        // ka, kd, ks, exponent, intensity, lens_radius, ray_bias, degrees, ...
        _ => (valid_number(Range::NonNegative), number()),
    };
    if noisy { prop_oneof![60 => valid, 1 => wrong, 1 => any_value()].boxed() } else { valid }
}

/// `key = value` lines for a table whose keys come from `keys`, plus (when `noisy`) now and then
/// an unknown key.
fn entries(keys: &'static [&'static str], noisy: bool) -> BoxedStrategy<Vec<String>> {
    let known = prop::sample::subsequence(keys, 0..=keys.len()).prop_flat_map(move |ks| {
        ks.into_iter().map(|k| value_for(k, noisy).prop_map(move |v| format!("{k} = {v}"))).collect::<Vec<_>>()
    });
    let unknown = prop::collection::vec(("[a-z_]{1,8}", any_value()).prop_map(|(k, v)| format!("{k} = {v}")), 0..2);
    (known, maybe(if noisy { 0.03 } else { 0.0 }, unknown))
        .prop_map(|(mut e, u)| {
            e.extend(u.into_iter().flatten());
            e
        })
        .boxed()
}

const RENDER_KEYS: &[&str] = &[
    "width",
    "height",
    "spp_axis",
    "spp",
    "max_depth",
    "seed",
    "integrator",
    "sampler",
    "antialias",
    "background",
    "ambient",
    "ray_bias",
    "transparent_shadows",
    "light_samples",
    "filter",
    "crop",
    "sample_border",
];
const PHOTON_KEYS: &[&str] = &[
    "photons",
    "caustic_photons",
    "gather",
    "gather_k",
    "caustic_k",
    "max_radius",
    "caustic_radius",
    "volume_k",
    "volume_radius",
];
const CAMERA_KEYS: &[&str] = &[
    "eye",
    "look_at",
    "up",
    "fov",
    "view_distance",
    "lens_radius",
    "focal_distance",
    "focus_on",
    "projection",
    "view_width",
    "view_height",
    "principal_point_offset",
];
const MATERIAL_KEYS: &[&str] = &["color", "ka", "kd", "ks", "exponent", "kr", "kt", "ior"];
const LIGHT_KEYS: &[&str] = &[
    "position",
    "direction",
    "look_at",
    "angle",
    "falloff",
    "color",
    "intensity",
    "shape",
    "corner",
    "edge1",
    "edge2",
    "center",
    "radius",
    "transform",
];
const OBJECT_KEYS: &[&str] = &[
    "material",
    "transform",
    "center",
    "radius",
    "point",
    "normal",
    "corner",
    "edge1",
    "edge2",
    "min",
    "max",
    "file",
    "p",
    "q",
    "tube",
    "segments",
    "sides",
    "p0",
    "p1",
    "group",
];

/// Keys each tagged kind accepts (so most generated tables get past the key check).
fn kind_keys(kind: &str) -> &'static [&'static str] {
    match kind {
        "diffuse" => &["color", "ka", "kd", "ks", "exponent"],
        "reflective" => &["color", "ka", "kd", "ks", "exponent", "kr"],
        "transparent" => &["color", "ka", "kd", "ks", "exponent", "kr", "kt", "ior"],
        "dielectric" => &["color", "ka", "kd", "ks", "exponent", "ior"],
        "point" => &["position", "color", "intensity"],
        "spot" => &["position", "direction", "look_at", "angle", "falloff", "color", "intensity"],
        "directional" => &["direction", "color", "intensity"],
        "area" => &["shape", "corner", "edge1", "edge2", "center", "radius", "transform", "color", "intensity"],
        "sphere" => &["material", "transform", "center", "radius"],
        "plane" => &["material", "transform", "point", "normal"],
        "quad" => &["material", "transform", "corner", "edge1", "edge2"],
        "box" => &["material", "transform", "min", "max"],
        "mesh" => &["material", "transform", "file"],
        "torus_knot" => &["material", "transform", "p", "q", "radius", "tube", "segments", "sides"],
        "cylinder" => &["material", "transform", "p0", "p1", "radius"],
        "disk" => &["material", "transform", "center", "normal", "radius"],
        "instance" => &["group", "transform"],
        _ => &[],
    }
}

/// A tagged table body: `type = KIND` and keys for that kind, the keys a kind requires always
/// present; when `noisy`, the type is sometimes missing or wrong and the keys those of any kind.
fn tagged(kinds: &'static [&'static str], all_keys: &'static [&'static str], noisy: bool) -> BoxedStrategy<String> {
    let kind = if noisy {
        prop_oneof![
            30 => prop::sample::select(kinds).prop_map(|k| Some(format!("{k:?}"))),
            1 => Just(None),
            1 => any_value().prop_map(Some),
        ]
        .boxed()
    } else {
        prop::sample::select(kinds).prop_map(|k| Some(format!("{k:?}"))).boxed()
    };
    (kind, maybe(if noisy { 0.05 } else { 0.0 }, Just(())).prop_map(|m| m.is_some()))
        .prop_flat_map(move |(k, mixed)| {
            let keys = match &k {
                Some(s) if !mixed => kind_keys(s.trim_matches('"')),
                _ => all_keys,
            };
            let keys = if keys.is_empty() { all_keys } else { keys };
            let needs_file = !noisy && k.as_deref() == Some("\"mesh\"");
            (entries(keys, noisy), prop::sample::select(&MESH_FILES[..6])).prop_map(move |(mut e, file)| {
                if let Some(k) = &k {
                    e.insert(0, format!("type = {k}"));
                }
                if needs_file && !e.iter().any(|l| l.starts_with("file")) {
                    e.push(format!("file = {file:?}"));
                }
                e.join("\n")
            })
        })
        .boxed()
}

/// A scene document: sections in the usual order, each present or not. Without `noisy`, every
/// value is one the loader accepts on its own (extremes included), so about half the documents
/// load and the checks on accepted scenes get exercised; with it, wrong values, types and keys.
fn scene_doc(noisy: bool) -> BoxedStrategy<String> {
    let render = prop::option::weighted(0.5, entries(RENDER_KEYS, noisy));
    let photon = prop::option::weighted(0.1, entries(PHOTON_KEYS, noisy));
    let noise = if noisy { 1 } else { 0 };
    let camera = prop_oneof![
        // Mostly a usable camera, so the rest of the document gets loaded.
        20 => entries(&["fov", "up", "lens_radius", "focal_distance", "principal_point_offset"], noisy).prop_map(|mut e| {
            e.insert(0, "eye = [0, 1, 5]\nlook_at = [0, 0, 0]".to_string());
            Some(e)
        }),
        3 => (valid_vec3(Range::Any), valid_vec3(Range::Any), entries(&["fov", "view_distance", "up", "lens_radius", "focus_on", "projection", "view_width"], noisy))
            .prop_map(|(eye, at, mut e)| {
                e.insert(0, format!("eye = {eye}\nlook_at = {at}"));
                Some(e)
            }),
        noise => entries(CAMERA_KEYS, noisy).prop_map(Some),
        noise => Just(None),
    ];
    // Distinct names (a repeated table is a TOML error, which the mutations cover).
    // Without noise every name is defined, so objects find their material.
    let min_materials = if noisy { 0 } else { MATERIAL_NAMES.len() };
    let materials =
        prop::sample::subsequence(MATERIAL_NAMES, min_materials..=MATERIAL_NAMES.len()).prop_flat_map(move |names| {
            names
                .into_iter()
                .map(|n| {
                    tagged(&["diffuse", "reflective", "transparent", "dielectric"], MATERIAL_KEYS, noisy)
                        .prop_map(move |b| (n, b))
                })
                .collect::<Vec<_>>()
        });
    let lights = prop::collection::vec(tagged(&["point", "spot", "directional", "area"], LIGHT_KEYS, noisy), 0..4);
    let objects = prop::collection::vec(
        tagged(
            &["sphere", "plane", "quad", "box", "mesh", "torus_knot", "cylinder", "disk", "instance"],
            OBJECT_KEYS,
            noisy,
        ),
        0..6,
    );
    // Objects of group `g`, which instances name (planes and instances only when noisy).
    let group_kinds: &'static [&'static str] = if noisy {
        &["sphere", "plane", "quad", "box", "mesh", "torus_knot", "cylinder", "disk", "instance"]
    } else {
        &["sphere", "quad", "box", "mesh", "torus_knot", "cylinder", "disk"]
    };
    let groups = prop::collection::vec(tagged(group_kinds, OBJECT_KEYS, noisy), 0..3);
    let extra = maybe(if noisy { 0.02 } else { 0.0 }, "[a-z]{1,8}");
    (render, photon, camera, materials, lights, (groups, objects), extra)
        .prop_map(|(render, photon, camera, materials, lights, (groups, objects), extra)| {
            let mut s = String::new();
            if let Some(r) = render {
                s += &format!("[render]\n{}\n", r.join("\n"));
            }
            if let Some(p) = photon {
                s += &format!("[render.photon]\n{}\n", p.join("\n"));
            }
            if let Some(c) = camera {
                s += &format!("[camera]\n{}\n", c.join("\n"));
            }
            for (name, body) in materials {
                s += &format!("[materials.{name}]\n{body}\n");
            }
            for l in lights {
                s += &format!("[[lights]]\n{l}\n");
            }
            for g in groups {
                s += &format!("[[groups.g.objects]]\n{g}\n");
            }
            for o in objects {
                s += &format!("[[objects]]\n{o}\n");
            }
            if let Some(x) = extra {
                s += &format!("[{x}]\n");
            }
            s
        })
        .boxed()
}

/// The bundled example scenes (the torus knot made small), as seeds for mutation.
fn example_scenes() -> Vec<String> {
    vec![
        include_str!("../scenes/01-reflection-unequal.toml").to_string(),
        include_str!("../scenes/06-fresnel-glass.toml").to_string(),
        include_str!("../scenes/07-torus-knot.toml")
            .replace("segments = 1600", "segments = 16")
            .replace("sides = 32", "sides = 6"),
        include_str!("../scenes/08-dof-red-focus.toml").to_string(),
        include_str!("../scenes/11-cornell-area.toml").to_string(),
        include_str!("../scenes/13-cornell-caustics.toml").to_string(),
    ]
}

#[derive(Clone, Debug)]
enum Mutation {
    Replace(prop::sample::Index, char),
    Insert(prop::sample::Index, char),
    Delete(prop::sample::Index),
    Truncate(prop::sample::Index),
    DuplicateLine(prop::sample::Index),
    DeleteLine(prop::sample::Index),
}

/// Characters that matter to TOML and to numbers, plus a few arbitrary ones.
fn mutation_char() -> BoxedStrategy<char> {
    prop_oneof![
        4 => prop::sample::select("[]{}=\"',.#\n-+0123456789eE_ \tnaif".chars().collect::<Vec<_>>()),
        1 => any::<char>(),
    ]
    .boxed()
}

fn mutation() -> BoxedStrategy<Mutation> {
    prop_oneof![
        4 => (any::<prop::sample::Index>(), mutation_char()).prop_map(|(i, c)| Mutation::Replace(i, c)),
        3 => (any::<prop::sample::Index>(), mutation_char()).prop_map(|(i, c)| Mutation::Insert(i, c)),
        3 => any::<prop::sample::Index>().prop_map(Mutation::Delete),
        1 => any::<prop::sample::Index>().prop_map(Mutation::Truncate),
        1 => any::<prop::sample::Index>().prop_map(Mutation::DuplicateLine),
        1 => any::<prop::sample::Index>().prop_map(Mutation::DeleteLine),
    ]
    .boxed()
}

fn mutate(text: &str, muts: &[Mutation]) -> String {
    let mut chars: Vec<char> = text.chars().collect();
    for m in muts {
        if chars.is_empty() {
            break;
        }
        match m {
            Mutation::Replace(i, c) => {
                let i = i.index(chars.len());
                chars[i] = *c;
            }
            Mutation::Insert(i, c) => {
                let i = i.index(chars.len() + 1);
                chars.insert(i, *c);
            }
            Mutation::Delete(i) => {
                let i = i.index(chars.len());
                chars.remove(i);
            }
            Mutation::Truncate(i) => {
                let i = i.index(chars.len());
                chars.truncate(i);
            }
            Mutation::DuplicateLine(i) | Mutation::DeleteLine(i) => {
                let s: String = chars.iter().collect();
                let mut lines: Vec<&str> = s.lines().collect();
                if lines.is_empty() {
                    continue;
                }
                let i = i.index(lines.len());
                if matches!(m, Mutation::DuplicateLine(_)) {
                    lines.insert(i, lines[i]);
                } else {
                    lines.remove(i);
                }
                chars = lines.join("\n").chars().collect();
            }
        }
    }
    chars.into_iter().collect()
}

// ---------------------------------------------------------------------------------------------
// Scene loader properties: 2,000 + 2,000 + 3,000 + 3,000 = 10,000 inputs per run
// ---------------------------------------------------------------------------------------------

proptest! {
    // 2,000 cases: arbitrary bytes (as lossy UTF-8).
    #![proptest_config(config(2_000))]
    #[test]
    fn scene_toml_random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..512)) {
        load_and_check(&String::from_utf8_lossy(&bytes))?;
    }
}

proptest! {
    // 2,000 cases: soup of TOML tokens and scene keys, so the parser gets past the first byte.
    #![proptest_config(config(2_000))]
    #[test]
    fn scene_toml_token_soup_never_panics(tokens in prop::collection::vec(prop_oneof![
        prop::sample::select(vec![
            "[", "]", "[[", "]]", "{", "}", "=", ",", ".", "\"", "'", "\n", " ", "#", "camera", "render", "objects",
            "lights", "materials", "type", "sphere", "eye", "look_at", "radius", "transform", "scale", "translate",
            "\"sphere\"", "\"mesh\"", "file", "\"tri.obj\"", "1", "-1", "0", "nan", "inf", "1e39", "[0, 0, 0]",
            "[1, 2, 3]", "\"\"", "true",
        ]).prop_map(str::to_string),
        "[ -~]{1,4}",
    ], 0..80)) {
        load_and_check(&tokens.concat())?;
    }
}

proptest! {
    // 3,000 cases: well-formed documents with random content.
    #![proptest_config(config(3_000))]
    #[test]
    fn scene_toml_generated_never_panics(doc in prop_oneof![scene_doc(false), scene_doc(true)]) {
        load_and_check(&doc)?;
    }
}

proptest! {
    // 3,000 cases: example scenes and generated documents with 1-4 small edits.
    #![proptest_config(config(3_000))]
    #[test]
    fn scene_toml_mutated_never_panics(
        base in prop_oneof![1 => prop::sample::select(example_scenes()), 1 => scene_doc(false)],
        muts in prop::collection::vec(mutation(), 1..5),
    ) {
        load_and_check(&mutate(&base, &muts))?;
    }
}

// ---------------------------------------------------------------------------------------------
// OBJ loader properties: 2,000 + 1,000 = 3,000 inputs per run
// ---------------------------------------------------------------------------------------------

fn obj_index() -> BoxedStrategy<String> {
    prop_oneof![
        6 => (1i64..8).prop_map(|i| i.to_string()),
        2 => (-8i64..0).prop_map(|i| i.to_string()),
        1 => prop::sample::select(vec!["0", "99999999999", "-99999999999", "4294967296", "x", ""]).prop_map(str::to_string),
    ]
    .boxed()
}

fn obj_line() -> BoxedStrategy<String> {
    let vref = prop_oneof![
        4 => obj_index(),
        1 => (obj_index(), obj_index()).prop_map(|(a, b)| format!("{a}/{b}")),
        1 => (obj_index(), obj_index()).prop_map(|(a, b)| format!("{a}//{b}")),
        1 => (obj_index(), obj_index(), obj_index()).prop_map(|(a, b, c)| format!("{a}/{b}/{c}")),
    ];
    prop_oneof![
        8 => prop::collection::vec(number(), 3..=3).prop_map(|v| format!("v {}", v.join(" "))),
        1 => prop::collection::vec(number(), 0..7).prop_map(|v| format!("v {}", v.join(" "))),
        2 => prop::collection::vec(number(), 3..=3).prop_map(|v| format!("vn {}", v.join(" "))),
        1 => prop::collection::vec(number(), 2..=2).prop_map(|v| format!("vt {}", v.join(" "))),
        6 => prop::collection::vec(vref, 0..6).prop_map(|v| format!("f {}", v.join(" "))),
        1 => prop::sample::select(vec![
            "o obj", "g group", "s 1", "s off", "usemtl red", "mtllib missing.mtl", "# comment", "", "l 1 2", "p 1",
            "f", "v", "\\", "f 1 2 3 \\",
        ]).prop_map(str::to_string),
        1 => "[ -~]{0,16}",
    ]
    .boxed()
}

/// Loads `text` as an OBJ file; an accepted mesh must have in-range indices and finite positions.
fn load_obj_and_check(file: &str, text: &str) -> Result<(), TestCaseError> {
    let path = scratch_file(file);
    std::fs::write(&path, text).unwrap();
    let Ok(mesh) = TriangleMesh::load_obj(&path) else {
        return Ok(());
    };
    check_mesh(&mesh).map_err(|m| TestCaseError::fail(format!("{m}\n--- obj ---\n{text}")))
}

fn check_mesh(mesh: &TriangleMesh) -> Result<(), String> {
    let n = mesh.positions.len();
    if mesh.indices.is_empty() {
        return Err("accepted mesh has no triangles".into());
    }
    if let Some(t) = mesh.indices.iter().find(|t| t.iter().any(|&i| i as usize >= n)) {
        return Err(format!("triangle {t:?} indexes past {n} vertices"));
    }
    if let Some(p) = mesh.positions.iter().find(|p| !p.is_finite()) {
        return Err(format!("accepted mesh has non-finite vertex {p}"));
    }
    if let Some(ns) = &mesh.normals
        && ns.len() != n
    {
        return Err(format!("{} normals for {n} vertices", ns.len()));
    }
    // Triangles and shading normals of the accepted mesh can be used without panicking.
    let (tris, _) = mesh.triangles(0);
    for t in tris.iter().take(16) {
        let _ = mesh.shading_normal(t.index as usize, 0.2, 0.3, 0.5);
    }
    Ok(())
}

proptest! {
    // 2,000 cases: OBJ-like lines (vertices with special numbers, faces with bad indices).
    #![proptest_config(config(2_000))]
    #[test]
    fn obj_generated_never_panics(lines in prop::collection::vec(obj_line(), 0..24)) {
        load_obj_and_check("gen.obj", &lines.join("\n"))?;
    }
}

proptest! {
    // 1,000 cases: random bytes.
    #![proptest_config(config(1_000))]
    #[test]
    fn obj_random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..256)) {
        let path = scratch_file("bytes.obj");
        std::fs::write(&path, &bytes).unwrap();
        if let Ok(mesh) = TriangleMesh::load_obj(&path) {
            check_mesh(&mesh).map_err(TestCaseError::fail)?;
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Self-intersection: spawned rays never re-hit their own surface (1,000 cases, >= 8 rays each)
// ---------------------------------------------------------------------------------------------

/// A coordinate log-uniform in 1e-4..1e6 with a random sign.
fn coord() -> BoxedStrategy<f32> {
    (-4.0f64..6.0, any::<bool>()).prop_map(|(e, neg)| (if neg { -1.0 } else { 1.0 } * 10f64.powf(e)) as f32).boxed()
}

fn point() -> BoxedStrategy<Vec3> {
    (coord(), coord(), coord()).prop_map(|(x, y, z)| Vec3::new(x, y, z)).boxed()
}

fn unit_from(u: f32, v: f32) -> Vec3 {
    let z = 1.0 - 2.0 * u;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * v;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

#[derive(Clone, Debug)]
enum TestShape {
    Triangle([Vec3; 3]),
    /// Centre and radius.
    Sphere(Vec3, f32),
    /// Corner and two edges.
    Quad([Vec3; 3]),
}

impl TestShape {
    fn shape(&self) -> Option<Shape> {
        Some(match *self {
            TestShape::Triangle([a, b, c]) => Shape::Triangle(Triangle::new(a, b, c)),
            TestShape::Sphere(c, r) => Shape::Sphere(Sphere::new(c, r)),
            TestShape::Quad([p, e1, e2]) => Shape::Quad(Quad::new(p, e1, e2)?),
        })
    }

    /// A point on the surface for barycentric-like `(a, b)` in [0, 1)^2.
    fn target(&self, a: f32, b: f32) -> Vec3 {
        match *self {
            TestShape::Triangle([p0, p1, p2]) => {
                let (a, b) = if a + b > 1.0 { (1.0 - a, 1.0 - b) } else { (a, b) };
                p0 * (1.0 - a - b) + p1 * a + p2 * b
            }
            TestShape::Sphere(c, r) => c + unit_from(a, b) * r,
            TestShape::Quad([p, e1, e2]) => p + e1 * a + e2 * b,
        }
    }
}

fn triangle() -> BoxedStrategy<TestShape> {
    (point(), point(), point()).prop_map(|(a, b, c)| TestShape::Triangle([a, b, c])).boxed()
}

/// Centre log-uniform; radius log-uniform too, from 1e-3 to 10 times the centre's largest
/// coordinate (at least 1e-4), so the sphere is thick enough for f32 to resolve.
fn sphere() -> BoxedStrategy<TestShape> {
    (point(), -3.0f64..1.0)
        .prop_map(|(c, e)| TestShape::Sphere(c, ((c.abs().max_element() as f64 * 10f64.powf(e)) as f32).max(1e-4)))
        .boxed()
}

fn quad() -> BoxedStrategy<TestShape> {
    (point(), point(), point()).prop_map(|(p, e1, e2)| TestShape::Quad([p, e1, e2])).boxed()
}

/// Where the first ray comes from: a log-uniform point (pbrt-v4's test), or along a random
/// direction from the target at a log-uniform distance.
#[derive(Clone, Debug)]
enum Origin {
    Point(Vec3),
    FromTarget { u: f32, v: f32, log_dist: f32 },
}

fn origin() -> BoxedStrategy<Origin> {
    prop_oneof![
        point().prop_map(Origin::Point),
        (0.0f32..1.0, 0.0f32..1.0, -4.0f32..6.0).prop_map(|(u, v, log_dist)| Origin::FromTarget { u, v, log_dist }),
    ]
    .boxed()
}

/// Outcome of one case, for the tally printed by the self-intersection tests.
#[derive(Default)]
struct Tally {
    hits: usize,
    spawned: usize,
}

/// Hits `ts` with a ray, spawns rays from the hit in `dirs` (plus the mirror, the continuing
/// direction and grazing ones) and checks none re-hits the surface.
fn check_no_self_hit(
    ts: &TestShape,
    ab: (f32, f32),
    o: &Origin,
    dirs: &[(f32, f32)],
    tally: &mut Tally,
) -> Result<(), TestCaseError> {
    let Some(shape) = ts.shape() else { return Ok(()) };
    let target = ts.target(ab.0, ab.1);
    let o = match *o {
        Origin::Point(p) => p,
        Origin::FromTarget { u, v, log_dist } => target + unit_from(u, v) * 10f32.powf(log_dist),
    };
    let d = (target - o).normalize_or_zero();
    if d == Vec3::ZERO || !d.is_finite() || !target.is_finite() {
        return Ok(());
    }
    let ray = Ray::new(o, d);
    let Some(h) = shape.intersect(&ray, &RayShear::new(&ray), f32::INFINITY) else { return Ok(()) };
    let sp = shape.surface(&ray, &h, &[]);
    tally.hits += 1;
    let n = sp.ng;
    prop_assert!(sp.p.is_finite() && sp.p_error.is_finite() && n.is_finite(), "bad surface point {sp:?}");
    // A single-primitive BVH, as the scene traverses it (compact shapes, box tests).
    let bvh = Bvh::build(vec![Primitive { shape, material: 0, light: caustic::geometry::NO_LIGHT }], &[]);

    let tangent = n.any_orthonormal_vector();
    let mut ws: Vec<Vec3> = dirs.iter().map(|&(u, v)| unit_from(u, v)).collect();
    ws.push(d - 2.0 * d.dot(n) * n); // mirror reflection
    ws.push(d); // straight through (transmission with ior 1)
    for g in [1e-2f32, 1e-3] {
        ws.push((tangent + n * g).normalize());
        ws.push((tangent - n * g).normalize());
    }
    for w in ws {
        let cos = w.dot(n);
        if cos == 0.0 || !w.is_finite() {
            continue;
        }
        let r = Ray::spawn(sp.p, sp.p_error, n, w, 0.0);
        tally.spawned += 1;
        let again = shape.intersect(&r, &RayShear::new(&r), f32::INFINITY);
        let again_bvh = bvh.intersect(&r, f32::INFINITY).map(|(_, h)| h);
        let ctx = || {
            format!(
                "shape {ts:?}\nfirst ray {ray:?} hit t={} at p={} (error {}), ng={n}\nspawned {r:?} (cos {cos})",
                h.t, sp.p, sp.p_error
            )
        };
        match ts {
            TestShape::Triangle(_) | TestShape::Quad(_) => {
                // A plane: a ray leaving it, to either side, never meets it again.
                prop_assert!(again.is_none(), "re-hit at t={:?}\n{}", again.map(|h| h.t), ctx());
                prop_assert!(again_bvh.is_none(), "BVH re-hit at t={:?}\n{}", again_bvh.map(|h| h.t), ctx());
            }
            TestShape::Sphere(_, radius) => {
                if cos > 0.0 {
                    // Leaving a convex surface outwards: nothing to hit.
                    prop_assert!(again.is_none(), "outward ray re-hit at t={:?}\n{}", again.map(|h| h.t), ctx());
                    prop_assert!(
                        again_bvh.is_none(),
                        "BVH: outward ray re-hit at t={:?}\n{}",
                        again_bvh.map(|h| h.t),
                        ctx()
                    );
                } else {
                    // Inwards: the far side, a chord 2 r |cos| away, never the start point. The
                    // chord's length is determined only where the start point's error bound is
                    // small next to the depth the chord reaches below the surface (its sagitta,
                    // chord^2 / 8 r): far from the origin a grazing chord is not (a sphere of
                    // radius 720 at 7e5 with an error of 0.04 has a 14.5-long chord 0.036 deep).
                    let chord = -2.0 * radius * cos;
                    let sagitta = chord * chord / (8.0 * radius);
                    if cos < -0.01 && sagitta > 10.0 * sp.p_error.length() {
                        let t = again.map(|h| h.t);
                        prop_assert!(
                            t.is_some_and(|t| t > 0.5 * chord && t < 1.5 * chord),
                            "inward ray: t={t:?}, chord {chord}\n{}",
                            ctx()
                        );
                        let t = again_bvh.map(|h| h.t);
                        prop_assert!(
                            t.is_some_and(|t| t > 0.5 * chord && t < 1.5 * chord),
                            "BVH inward ray: t={t:?}, chord {chord}\n{}",
                            ctx()
                        );
                    }
                }
            }
        }
    }
    Ok(())
}

fn spawn_dirs() -> BoxedStrategy<Vec<(f32, f32)>> {
    prop::collection::vec((0.0f32..1.0, 0.0f32..1.0), 8..=8).boxed()
}

proptest! {
    // 1,000 cases (half triangles, half spheres), 14 spawned rays per hit.
    #![proptest_config(config(1_000))]
    #[test]
    fn spawned_rays_never_rehit_triangles_or_spheres(
        ts in prop_oneof![triangle(), sphere()],
        ab in (0.0f32..1.0, 0.0f32..1.0),
        o in origin(),
        dirs in spawn_dirs(),
    ) {
        let mut tally = Tally::default();
        check_no_self_hit(&ts, ab, &o, &dirs, &mut tally)?;
    }
}

proptest! {
    // 300 cases: quads (box faces, area lights), same property.
    #![proptest_config(config(300))]
    #[test]
    fn spawned_rays_never_rehit_quads(ts in quad(), ab in (0.0f32..1.0, 0.0f32..1.0), o in origin(), dirs in spawn_dirs()) {
        let mut tally = Tally::default();
        check_no_self_hit(&ts, ab, &o, &dirs, &mut tally)?;
    }
}

/// The property above counts only cases whose first ray hits; this checks that most do, so the
/// 1,000 cases really spawn well over 1,000 rays.
#[test]
fn self_intersection_cases_mostly_hit() {
    use proptest::strategy::ValueTree;
    use proptest::test_runner::TestRunner;
    let mut runner = TestRunner::deterministic();
    let strat = (prop_oneof![triangle(), sphere()], (0.0f32..1.0, 0.0f32..1.0), origin(), spawn_dirs());
    let mut tally = Tally::default();
    for _ in 0..1_000 {
        let (ts, ab, o, dirs) = strat.new_tree(&mut runner).unwrap().current();
        check_no_self_hit(&ts, ab, &o, &dirs, &mut tally).unwrap();
    }
    eprintln!("self-intersection: {} of 1000 first rays hit, {} rays spawned", tally.hits, tally.spawned);
    assert!(tally.hits >= 600 && tally.spawned >= 1_000 * 6, "{} hits, {} spawned", tally.hits, tally.spawned);
}

// ---------------------------------------------------------------------------------------------
// Regression tests: one per failure the properties or the fuzzers found
// ---------------------------------------------------------------------------------------------

/// Loads a regression scene (mesh files from `mesh_dir`).
fn load(text: &str) -> Result<LoadedScene, caustic::scene::SceneError> {
    load_toml_str(text, "regression.toml", mesh_dir(), &Options::default())
}

const CAMERA: &str = "[camera]\neye = [0, 1, 5]\nlook_at = [0, 0, 0]\n";

/// Either rejected, or usable (`check_loaded` with no known issue tolerated).
fn assert_rejected_or_usable(text: &str) {
    let Ok(loaded) = load(text) else { return };
    let scene = &loaded.scene;
    let b = scene.bounds();
    assert!(b.is_empty() || (b.min.is_finite() && b.max.is_finite()), "accepted with bounds {b:?}:\n{text}");
    for l in &scene.lights {
        assert!(l.power().is_finite(), "accepted light with power {}: {l:?}\n{text}", l.power());
        if let Light::Area { shape, .. } = l {
            let a = shape.area();
            assert!(a > 0.0 && a.is_finite(), "accepted area light with area {a}: {l:?}\n{text}");
        }
    }
    let (w, h) = (loaded.settings.width as f32, loaded.settings.height as f32);
    for raster in [Vec2::new(0.5 * w, 0.5 * h), Vec2::ZERO, Vec2::new(w, h)] {
        let ray = scene.camera.generate_ray(raster, Vec2::new(0.5, 0.5));
        assert!(ray.d.is_finite() && (ray.d.length() - 1.0).abs() < 1e-3, "camera ray {ray:?}\n{text}");
        if let Some(hit) = scene.intersect(&ray, f32::INFINITY) {
            assert!(hit.t > 0.0 && hit.p.is_finite(), "camera ray {ray:?} hit {hit:?}\n{text}");
        }
    }
}

/// Found by `scene_toml_generated_never_panics`: colour and intensity are each finite, their
/// product is not, so the light's power (used to pick lights and emit photons) is infinite.
#[test]
fn regression_scene_toml_light_power_overflows_to_infinity() {
    assert_rejected_or_usable(&format!("{CAMERA}[[lights]]\ntype = \"point\"\ncolor = 1e30\nintensity = 1e30\n"));
}

/// Found by `scene_toml_mutated_never_panics`: a spherical area light of radius 1e-45 (any
/// radius below about 1e-19) has zero area; sampling it divides by that area.
#[test]
fn regression_scene_toml_zero_area_sphere_light() {
    assert_rejected_or_usable(&format!(
        "{CAMERA}[[lights]]\ntype = \"area\"\nshape = \"sphere\"\nradius = 1e-45\nintensity = 4\n"
    ));
}

/// Found by `scene_toml_generated_never_panics`: a spherical area light's radius is scaled by
/// its transform without the finiteness check that sphere objects get.
#[test]
fn regression_scene_toml_sphere_light_radius_overflows_in_transform() {
    assert_rejected_or_usable(&format!(
        "{CAMERA}[[lights]]\ntype = \"area\"\nshape = \"sphere\"\nradius = 3e38\ntransform = [{{ scale = 10 }}]\n"
    ));
}

/// Found by `scene_toml_generated_never_panics`: a quad's corner overflows to -inf in its
/// transform; `Quad::new` checks only the edges, so the scene's bounds become infinite.
#[test]
fn regression_scene_toml_quad_corner_overflows_in_transform() {
    assert_rejected_or_usable(&format!(
        "{CAMERA}[[objects]]\ntype = \"quad\"\ncorner = [0, -3.4028234e38, 0]\ntransform = [{{ scale = 10 }}]\n"
    ));
}

/// Found by `scene_toml_generated_never_panics`: with a lens, a focal distance of 1e-38 makes the
/// central camera ray's direction underflow, and normalising it gives NaN.
#[test]
fn regression_scene_toml_tiny_focal_distance_nan_camera_ray() {
    assert_rejected_or_usable(&format!(
        "{CAMERA}lens_radius = 1\nfocal_distance = 1e-38\n[[objects]]\ntype = \"sphere\"\n"
    ));
}

/// Found by `scene_toml_generated_never_panics`: a mesh with vertices near 1.5e38 loads, and a
/// camera ray then "hits" it at t = NaN (the watertight test's products overflow, and a NaN
/// determinant passes every rejection test).
#[test]
fn regression_scene_toml_huge_mesh_nan_hit() {
    assert_rejected_or_usable(&format!(
        "{CAMERA}[[objects]]\ntype = \"mesh\"\nfile = \"huge.obj\"\ntransform = [{{ scale = 0.5 }}]\n"
    ));
}

/// The shape-level half of the above: an intersection never reports a non-finite distance.
#[test]
fn regression_triangle_huge_coordinates_nan_hit() {
    let tri = Shape::Triangle(Triangle::new(
        Vec3::new(1.5e38, 0.0, 0.0),
        Vec3::new(-1.5e38, 0.0, 0.0),
        Vec3::new(0.0, 1.5e38, 0.0),
    ));
    let ray = Ray::new(Vec3::new(0.0, 1.0, 5.0), Vec3::new(0.0, -0.19611613, -0.9805807));
    let h = tri.intersect(&ray, &RayShear::new(&ray), f32::INFINITY);
    assert!(h.is_none_or(|h| h.t.is_finite() && h.t > 0.0), "hit {h:?}");
}

// ---------------------------------------------------------------------------------------------
// Mitsuba XML and PLY loaders (`scene::mitsuba`): 1,500 + 500 + 1,000 = 3,000 inputs per run
// ---------------------------------------------------------------------------------------------

use caustic::scene::mitsuba::load_mitsuba_str;

fn mitsuba_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/mitsuba")
}

fn mitsuba_examples() -> Vec<String> {
    ["cornell-box.xml", "glass-point.xml", "ply-mesh.xml", "thinlens.xml"]
        .iter()
        .map(|f| std::fs::read_to_string(mitsuba_dir().join(f)).unwrap())
        .collect()
}

fn load_mitsuba_and_check(text: &str, base: &Path) -> Result<(), TestCaseError> {
    let Ok(loaded) =
        load_mitsuba_str(text, "fuzz.xml", base, &LoadOptions::default()).and_then(|d| prepare(d, &Options::default()))
    else {
        return Ok(());
    };
    check_loaded(&loaded).map_err(|m| TestCaseError::fail(format!("{m}\n--- scene ---\n{text}")))
}

/// Characters that matter to XML and to Mitsuba's values.
fn xml_mutation() -> BoxedStrategy<Mutation> {
    let c = prop_oneof![
        4 => prop::sample::select("<>/=\"' ,.-+0123456789e$&;!?x\n".chars().collect::<Vec<_>>()),
        1 => any::<char>(),
    ];
    prop_oneof![
        4 => (any::<prop::sample::Index>(), c.clone()).prop_map(|(i, c)| Mutation::Replace(i, c)),
        3 => (any::<prop::sample::Index>(), c).prop_map(|(i, c)| Mutation::Insert(i, c)),
        3 => any::<prop::sample::Index>().prop_map(Mutation::Delete),
        1 => any::<prop::sample::Index>().prop_map(Mutation::Truncate),
        1 => any::<prop::sample::Index>().prop_map(Mutation::DuplicateLine),
        1 => any::<prop::sample::Index>().prop_map(Mutation::DeleteLine),
    ]
    .boxed()
}

proptest! {
    // 1,500 cases: the bundled Mitsuba scenes with 1-4 small edits.
    #![proptest_config(config(1_500))]
    #[test]
    fn mitsuba_xml_mutated_never_panics(
        base in prop::sample::select(mitsuba_examples()),
        muts in prop::collection::vec(xml_mutation(), 1..5),
    ) {
        load_mitsuba_and_check(&mutate(&base, &muts), &mitsuba_dir())?;
    }
}

fn authored_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/authored")
}

/// The scenes written as Mitsuba's authors write them: includes, `<path>`, spectra and `.spd`
/// files, black bodies, mesh attributes, wrapped integrators.
fn authored_examples() -> Vec<String> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(authored_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "xml"))
        .collect();
    files.sort();
    files.iter().map(|f| std::fs::read_to_string(f).unwrap()).collect()
}

proptest! {
    // 500 cases: the authored Mitsuba scenes with 1-4 edits.
    #![proptest_config(config(500))]
    #[test]
    fn mitsuba_authored_mutated_never_panics(
        base in prop::sample::select(authored_examples()),
        muts in prop::collection::vec(xml_mutation(), 1..5),
    ) {
        load_mitsuba_and_check(&mutate(&base, &muts), &authored_dir())?;
    }
}

proptest! {
    // 500 cases: arbitrary bytes (as lossy UTF-8).
    #![proptest_config(config(500))]
    #[test]
    fn mitsuba_xml_random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..512)) {
        load_mitsuba_and_check(&String::from_utf8_lossy(&bytes), &mitsuba_dir())?;
    }
}

proptest! {
    // 1,000 cases: the bundled PLY meshes (ASCII and binary) with 1-8 byte edits, loaded through
    // a Mitsuba scene.
    #![proptest_config(config(1_000))]
    #[test]
    fn ply_mutated_never_panics(
        binary in any::<bool>(),
        edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>(), 0u8..4), 1..9),
    ) {
        let file = if binary { "icosphere.ply" } else { "pyramid_ascii.ply" };
        let mut bytes = std::fs::read(mitsuba_dir().join("meshes").join(file)).unwrap();
        for (i, b, op) in edits {
            if bytes.is_empty() {
                break;
            }
            let i = i.index(bytes.len());
            match op {
                0 => bytes[i] = b,
                1 => bytes.insert(i, b),
                2 => { bytes.remove(i); }
                _ => bytes.truncate(i),
            }
        }
        std::fs::write(scratch_file("gen.ply"), &bytes).unwrap();
        let xml = "<scene version=\"3.0.0\"><sensor type=\"perspective\"><transform name=\"to_world\">\
             <lookat origin=\"0, 2, 5\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform></sensor>\
             <shape type=\"ply\"><string name=\"filename\" value=\"gen.ply\"/></shape></scene>";
        load_mitsuba_and_check(xml, mesh_dir())?;
    }
}

/// The PLY property's scene loads the unedited meshes, so its cases reach the PLY parser.
#[test]
fn ply_property_scene_loads_unedited_meshes() {
    for file in ["icosphere.ply", "pyramid_ascii.ply"] {
        std::fs::copy(mitsuba_dir().join("meshes").join(file), scratch_file(&format!("ok-{file}"))).unwrap();
        let xml = format!(
            "<scene version=\"3.0.0\"><sensor type=\"perspective\"><transform name=\"to_world\">\
             <lookat origin=\"0, 2, 5\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform></sensor>\
             <shape type=\"ply\"><string name=\"filename\" value=\"ok-{file}\"/></shape></scene>"
        );
        let r = load_mitsuba_str(&xml, "t.xml", mesh_dir(), &LoadOptions::default())
            .and_then(|d| prepare(d, &Options::default()));
        assert!(r.is_ok(), "{file}: {:?}", r.err().map(|e| e.to_string()));
    }
}
