//! The consistency matrix: every material kind crossed with every light kind in a small scene (a
//! sphere of the material on a grey floor), rendered by the path tracer, photon mapping, SPPM,
//! the light tracer, bidirectional path tracing and vertex connection and merging.
//! Photon mapping and SPPM must carry all the light the path tracer carries: their mean
//! luminance agrees with the path tracer's within 2% (3% for glass, whose caustics make every
//! integrator noisier), or within the noise the renders measure if that is larger, and so does
//! each `--layers` layer (the layers follow the same rule in every integrator:
//! `integrator::layers`). Caustics of point, spot and directional lights through smooth mirrors
//! and glass cannot be rendered by the path tracer: there photon mapping and SPPM are compared
//! with each other. Bidirectional path tracing and vertex connection and merging agree with the
//! path tracer in every cell, image and layers, and with SPPM on the caustics the path tracer
//! cannot render (VCM also where they are seen through mirrors and glass, which merging renders).

mod common;

use caustic::app::LoadedScene;
use caustic::film::Image;
use caustic::math::luminance;
use caustic::options::{IntegratorKind, Options, PhotonOptions};

const MATERIALS: &[(&str, &str)] = &[
    (
        "diffuse",
        r#"type = "diffuse"
color = [0.7, 0.6, 0.5]
kd = 1"#,
    ),
    (
        "phong",
        r#"type = "diffuse"
color = [0.7, 0.6, 0.5]
kd = 0.2
ks = 0.6
exponent = 30"#,
    ),
    (
        "diffuse_mirror",
        r#"type = "reflective"
color = [0.7, 0.6, 0.5]
kd = 0.4
kr = 0.5"#,
    ),
    (
        "mirror",
        r#"type = "reflective"
kd = 0
ka = 0
kr = 0.9"#,
    ),
    (
        "glass",
        r#"type = "dielectric"
ior = 1.5"#,
    ),
    (
        "roughconductor",
        r#"type = "roughconductor"
metal = "Au"
alpha = 0.25"#,
    ),
    (
        "roughdielectric",
        r#"type = "roughdielectric"
ior = 1.5
alpha = 0.25"#,
    ),
    (
        "plastic",
        r#"type = "plastic"
color = [0.6, 0.1, 0.05]"#,
    ),
    (
        "roughplastic",
        r#"type = "roughplastic"
color = [0.1, 0.2, 0.6]
alpha = 0.2"#,
    ),
    (
        "textured",
        r#"type = "diffuse"
color = "checks"
kd = 1"#,
    ),
    (
        "principled",
        r#"type = "principled"
color = [0.7, 0.4, 0.3]
roughness = 0.35
metallic = 0.2
spec_trans = 0.3
sheen = 0.4
clearcoat = 0.5"#,
    ),
    (
        "principledthin",
        r#"type = "principledthin"
color = [0.3, 0.6, 0.3]
roughness = 0.4
spec_trans = 0.3
diff_trans = 0.8
sheen = 0.3"#,
    ),
];

/// (name, TOML of the lights, whether the floor is an infinite plane)
const LIGHTS: &[(&str, &str, bool)] = &[
    (
        "point",
        r#"[[lights]]
type = "point"
position = [1.5, 3, 2]
intensity = 12"#,
        false,
    ),
    (
        "spot",
        r#"[[lights]]
type = "spot"
position = [1.5, 3, 2]
look_at = [0, 0, 0]
angle = 40
falloff = 25
intensity = 25"#,
        false,
    ),
    (
        "directional",
        r#"[[lights]]
type = "directional"
direction = [-0.3, -1, -0.4]
intensity = 1.5"#,
        false,
    ),
    (
        "directional_plane",
        r#"[[lights]]
type = "directional"
direction = [-0.3, -1, -0.4]
intensity = 1.5"#,
        true,
    ),
    (
        "quad",
        r#"[[lights]]
type = "area"
corner = [-0.5, 2.5, -0.5]
edge1 = [1, 0, 0]
edge2 = [0, 0, 1]
intensity = 10"#,
        false,
    ),
    (
        "sphere",
        r#"[[lights]]
type = "area"
shape = "sphere"
center = [1.2, 3.0, 0.5]
radius = 0.3
intensity = 12"#,
        false,
    ),
    (
        "mesh",
        r#"[[objects]]
type = "mesh"
file = "scenes/mitsuba/meshes/icosphere.obj"
transform = [{ scale = 0.3 }, { translate = [-1.2, 3.0, 0.5] }]
emission = 12"#,
        false,
    ),
    (
        "envmap",
        r#"[[lights]]
type = "envmap"
file = "tests/data/lights/sky.exr"
scale = 1.0"#,
        false,
    ),
    (
        "constant",
        r#"[[lights]]
type = "constant"
color = [0.6, 0.7, 0.9]
intensity = 1"#,
        false,
    ),
];

/// Comparisons that disagree at these sample counts, each an open item of issue 13 with what
/// was measured; the test prints them in its table (marked "known") without failing, and fails
/// on every other cell. (light, material, comparison, layer). None is open.
///
/// Closed:
/// - envmap x roughdielectric (photon indirect +19%) and sphere x roughdielectric (SPPM image):
///   photons added their bounces to the camera path's without a limit, so light that bounced
///   inside frosted glass more often than `max_depth` allows reached the image (at 48 x 40 the
///   photon indirect layer was +6.5% against the path tracer at max_depth 8 and +0.9% at 40;
///   now +0.8%).
/// - spot x roughconductor (SPPM indirect +16%), sphere x roughdielectric (SPPM indirect +21%)
///   and mesh x roughdielectric (photon image -3%) were mostly the path tracer's noise: with
///   `PATH_SPP_FACTOR` the matrix reads +1.1%, +1.9% and -0.2%. At 48 x 40 with 4096 paths per
///   pixel, the first agrees within +1.7% (photon) and +0.3% (SPPM); SPPM's indirect layer of
///   the other two still reads +10% and +11% at 512 iterations there: the radius bias of a
///   caustic seen through frosted glass, which falls as the radius shrinks (at 120 x 100 from
///   +9.5% to +6.8% in the sphere's region from 256 to 1024 iterations).
/// - quad x glass (both images +7%) and mesh x diffuse_mirror (photon/SPPM specular -24%) were
///   sampling noise of small features (`SLOW_CELLS`): with 8x the samples of every integrator
///   the images agree within 1% and the specular layer within its bound.
const KNOWN_OPEN: &[(&str, &str, &str, &str)] = &[];

fn scene_text(material: &str, light: &str, plane: bool) -> String {
    let floor = if plane {
        "[[objects]]\ntype = \"plane\"\nmaterial = \"floor\"\n".to_string()
    } else {
        "[[objects]]\ntype = \"quad\"\ncorner = [-3, 0, 3]\nedge1 = [6, 0, 0]\nedge2 = [0, 0, -6]\nmaterial = \"floor\"\n".to_string()
    };
    format!(
        r#"[render]
width = 12
height = 10
max_depth = 8
# One sample pattern for every integrator, so that they start the same camera rays (`SPP`;
# SPPM and VCM would otherwise take Sobol points).
sampler = "jittered"

[camera]
eye = [0, 1.6, 4.5]
look_at = [0, 0.5, 0]
fov = 45

[textures.checks]
type = "checkerboard"
color0 = [0.7, 0.6, 0.5]
color1 = [0.2, 0.3, 0.4]
scale = [4, 4]

[materials.floor]
type = "diffuse"
color = [0.6, 0.6, 0.6]
kd = 1

[materials.test]
{material}

{floor}
[[objects]]
type = "sphere"
center = [0, 0.6, 0]
radius = 0.6
material = "test"

{light}
"#
    )
}

/// Camera samples per pixel of every integrator (SPPM's iterations; the photon integrator
/// gathers 2 rays at each). On mirrors and glass, with the same count and seed the three
/// integrators start the same camera rays, so what a pixel covers (a light's reflection smaller
/// than a pixel in the mirror sphere) is the same in every render and cancels in their
/// difference, which is measured per seed (elsewhere the path tracer takes more samples:
/// `PATH_SPP_FACTOR`).
const SPP: u32 = 48;
/// On materials without a mirror or glass part the path tracer takes this many times the
/// samples: it is the cheapest of the three here, and its noise in the glossy reflections and
/// caustics of small lights (rough metal and glass under a spot, sphere or mesh light) was most
/// of what those comparisons measured.
const PATH_SPP_FACTOR: u32 = 8;
/// Cells whose noise needs more samples of every integrator: the caustic of a small light
/// through glass, which the path tracer finds by chance (quad x glass), and a mesh light's
/// reflection covering part of a pixel in a sphere that is part mirror (mesh x diffuse_mirror).
const SLOW_CELLS: &[(&str, &str)] = &[("quad", "glass"), ("mesh", "diffuse_mirror")];
const SLOW_SPP_FACTOR: u32 = 8;
/// Renders with seeds 11, 12, ...
const RUNS: u64 = 3;

/// The means of the image and of its direct, specular, caustic and indirect layers.
fn render(s: &str, kind: IntegratorKind, seed: u64, (path_factor, all_factor): (u32, u32)) -> [f64; 5] {
    // Few photons: the scenes are tiny, and the matrix must run in about a minute.
    let photon = PhotonOptions {
        photons: Some(40_000),
        caustic_photons: Some(20_000),
        gather: Some(2),
        photons_per_iter: Some(8_000),
        ..Default::default()
    };
    let spp = all_factor * if kind == IntegratorKind::Path { SPP * path_factor } else { SPP };
    let o = Options { integrator: Some(kind), spp: Some(spp), seed: Some(seed), photon, ..Default::default() };
    let mut loaded: LoadedScene = common::scene_with(s, &o);
    loaded.settings.layers = true;
    let out = loaded.render();
    let mut means = [0.0; 5];
    for (m, img) in means.iter_mut().zip(std::iter::once(&out.image).chain(&out.layers)) {
        *m = mean(img);
    }
    means
}

fn mean(img: &Image) -> f64 {
    img.pixels.iter().map(|&c| luminance(c) as f64).sum::<f64>() / img.pixels.len() as f64
}

/// The mean of `b` over the runs, and the mean difference a - b with its standard error from
/// the per-seed differences (the runs are paired: the same seeds start the same camera rays).
fn difference(a: &[f64], b: &[f64]) -> (f64, f64, f64) {
    let n = a.len() as f64;
    let mean = |v: &[f64]| v.iter().sum::<f64>() / n;
    let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
    let md = mean(&d);
    let var = d.iter().map(|x| (x - md) * (x - md)).sum::<f64>() / (n - 1.0);
    (mean(b), md, (var / n).sqrt())
}

const LAYER_NAMES: [&str; 5] = ["image", "direct", "specular", "caustic", "indirect"];

#[test]
fn photon_mapping_and_sppm_agree_with_the_path_tracer_everywhere() {
    let mut failures = Vec::new();
    let mut table = String::new();
    for (light, light_toml, plane) in LIGHTS {
        for (material, material_toml) in MATERIALS {
            let s = scene_text(material_toml, light_toml, *plane);
            let delta_light = matches!(*light, "point" | "spot" | "directional" | "directional_plane");
            let smooth_specular = matches!(*material, "mirror" | "glass" | "diffuse_mirror" | "plastic");
            let glass = matches!(*material, "glass" | "roughdielectric");
            // Where the camera sees lights through mirrors and glass, every integrator starts the
            // same camera rays so that what a pixel covers cancels (see `SPP`); elsewhere the
            // path tracer takes more samples.
            let factor = (
                if smooth_specular { 1 } else { PATH_SPP_FACTOR },
                if SLOW_CELLS.contains(&(*light, *material)) { SLOW_SPP_FACTOR } else { 1 },
            );
            let runs = |kind| (11..11 + RUNS).map(|seed| render(&s, kind, seed, factor)).collect::<Vec<_>>();
            let (path, photon, sppm) =
                (runs(IntegratorKind::Path), runs(IntegratorKind::Photon), runs(IntegratorKind::Sppm));
            let tol = if glass { 0.03 } else { 0.02 };
            // Compares integrator `a` with `b` on the image and (with `layers`) on each layer. A
            // layer is held to the tolerance of its own mean, or to half the image's tolerance
            // in image units where that is larger (a layer holding 1% of the light need not agree
            // within 2% of itself), or to four standard errors of the difference.
            let mut compare = |name: &str, a: &[[f64; 5]], b: &[[f64; 5]], layers: bool| {
                let mut cells = Vec::new();
                let image_b = b.iter().map(|r| r[0]).sum::<f64>() / b.len() as f64;
                for (j, layer) in LAYER_NAMES.iter().enumerate().take(if layers { 5 } else { 1 }) {
                    let col = |v: &[[f64; 5]]| v.iter().map(|r| r[j]).collect::<Vec<_>>();
                    let (mb, md, err) = difference(&col(a), &col(b));
                    let floor = if j == 0 { 0.0 } else { tol / 2.0 * image_b };
                    let bound = (tol * mb).max(floor).max(4.0 * err);
                    let known = KNOWN_OPEN.contains(&(*light, *material, name, *layer));
                    let mark = if md.abs() <= bound {
                        ""
                    } else if known {
                        " (known)"
                    } else {
                        "!"
                    };
                    if md.abs() > bound && !known {
                        failures.push(format!(
                            "{light} x {material}: {name} {layer} {:.5} vs {mb:.5} ({:+.2}%, bound {bound:.5})",
                            mb + md,
                            md / mb * 100.0
                        ));
                    }
                    if mb > 0.0 {
                        cells.push(format!("{}{:+.1}%{mark}", &layer[..2], md / mb * 100.0));
                    }
                }
                format!("{name} {}", cells.join(" "))
            };
            let row = if delta_light && smooth_specular {
                // Point-light caustics: photon mapping against SPPM.
                compare("photon/sppm", &photon, &sppm, true)
            } else if smooth_specular {
                // Caustics of small lights through smooth mirrors and glass: the path tracer finds
                // them by chance at these sample counts, so it checks the images, and photon
                // mapping and SPPM check each other's layers.
                format!(
                    "{} | {} | {}",
                    compare("photon", &photon, &path, false),
                    compare("sppm", &sppm, &path, false),
                    compare("photon/sppm", &photon, &sppm, true)
                )
            } else {
                format!("{} | {}", compare("photon", &photon, &path, true), compare("sppm", &sppm, &path, true))
            };
            table += &format!("{light:18} {material:16} {row}\n");
        }
    }
    eprintln!("{table}");
    assert!(failures.is_empty(), "integrators disagree:\n{}", failures.join("\n"));
}

/// Light paths per pixel of the light tracer, as a multiple of `SPP` (it is cheap here, and a
/// light path reaches the camera from few of its vertices).
const LIGHT_SPP_FACTOR: u32 = 16;

/// The light tracer against the path tracer in every cell: the light that reaches the camera
/// from the first surface it sees (the image without its specular layer: what the camera sees
/// in mirrors and glass needs a delta camera vertex, which a light path cannot connect to), and
/// each of its direct, caustic and indirect layers. Where the path tracer cannot find caustics
/// (point, spot and directional lights through smooth mirrors and glass) SPPM is the reference.
///
/// Not compared: `directional_plane`, where light paths enter through the photon disk, which
/// covers an infinite floor out to `PLANE_REACH` scene radii and no further; the floor the
/// camera sees beyond it, near the horizon, gets no light from the light tracer (measured at
/// 48 x 40: rows 8-11 at 0.11 against the path tracer's 0.24, every other row within 0.5%;
/// the whole image -6%). The path tracer and photon mapping light it by light samples.
#[test]
fn the_light_tracer_agrees_with_the_path_tracer_where_it_sees_the_surface() {
    let mut failures = Vec::new();
    let mut table = String::new();
    // [seen from the first surface, direct, caustic, indirect]
    let seen = |m: [f64; 5]| [m[1] + m[3] + m[4], m[1], m[3], m[4]];
    for (light, light_toml, plane) in LIGHTS.iter().filter(|(name, _, _)| *name != "directional_plane") {
        for (material, material_toml) in MATERIALS {
            let s = scene_text(material_toml, light_toml, *plane);
            let delta_light = matches!(*light, "point" | "spot" | "directional" | "directional_plane");
            let smooth_specular = matches!(*material, "mirror" | "glass" | "diffuse_mirror" | "plastic");
            let glass = matches!(*material, "glass" | "roughdielectric");
            let slow = if SLOW_CELLS.contains(&(*light, *material)) { SLOW_SPP_FACTOR } else { 1 };
            let (reference_kind, reference_factor) = if delta_light && smooth_specular {
                (IntegratorKind::Sppm, (1, slow))
            } else {
                (IntegratorKind::Path, (PATH_SPP_FACTOR, slow))
            };
            let runs =
                |kind, factor| (11..11 + RUNS).map(|seed| seen(render(&s, kind, seed, factor))).collect::<Vec<_>>();
            let reference = runs(reference_kind, reference_factor);
            let light_runs = runs(IntegratorKind::Light, (1, LIGHT_SPP_FACTOR * slow));
            let tol = if glass { 0.03 } else { 0.02 };
            let image_ref = reference.iter().map(|r| r[0]).sum::<f64>() / reference.len() as f64;
            let mut cells = Vec::new();
            for (j, layer) in ["seen", "direct", "caustic", "indirect"].iter().enumerate() {
                let col = |v: &[[f64; 4]]| v.iter().map(|r| r[j]).collect::<Vec<_>>();
                let (mb, md, err) = difference(&col(&light_runs), &col(&reference));
                // As in the matrix above: a layer to its own tolerance, or half the image's in
                // image units, or four standard errors (here of unpaired runs: the light tracer
                // and its reference share no camera rays).
                let err_a = {
                    let v = col(&light_runs);
                    let m = v.iter().sum::<f64>() / v.len() as f64;
                    (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() as f64 - 1.0) / v.len() as f64).sqrt()
                };
                let err_b = {
                    let v = col(&reference);
                    let m = v.iter().sum::<f64>() / v.len() as f64;
                    (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() as f64 - 1.0) / v.len() as f64).sqrt()
                };
                let err = err.max((err_a * err_a + err_b * err_b).sqrt());
                let floor = if j == 0 { 0.0 } else { tol / 2.0 * image_ref };
                let bound = (tol * mb).max(floor).max(4.0 * err);
                let mark = if md.abs() <= bound { "" } else { "!" };
                if md.abs() > bound {
                    failures.push(format!(
                        "{light} x {material}: light {layer} {:.5} vs {reference_kind:?} {mb:.5} ({:+.2}%, bound {bound:.5})",
                        mb + md,
                        md / mb * 100.0
                    ));
                }
                if mb > 0.0 {
                    cells.push(format!("{}{:+.1}%{mark}", &layer[..2], md / mb * 100.0));
                }
            }
            table += &format!("{light:18} {material:16} light/{} {}\n", reference_kind.name(), cells.join(" "));
        }
    }
    eprintln!("{table}");
    assert!(failures.is_empty(), "the light tracer disagrees:\n{}", failures.join("\n"));
}

/// Bidirectional path tracing and vertex connection and merging against the path tracer in every
/// cell: the image and each layer, with the path tracer's sample count (they start the same
/// camera rays). Where the path tracer cannot render caustics (point, spot and directional lights
/// through smooth mirrors and glass), SPPM is the reference: for bidirectional path tracing of
/// the light reaching the first surface the camera sees (direct, caustic and indirect layers),
/// its specular layer still being the path tracer's, as neither can connect a caustic seen
/// through a mirror (L S+ D S+ E needs merging); for VCM of the image and every layer (merging
/// renders those caustics as SPPM does). VCM converges as its radius shrinks; at these counts the
/// radius still blurs the caustics of small lights, as SPPM's does.
#[test]
fn bidirectional_methods_agree_with_the_path_tracer_and_sppm_everywhere() {
    let mut failures = Vec::new();
    let mut table = String::new();
    for (light, light_toml, plane) in LIGHTS {
        for (material, material_toml) in MATERIALS {
            let s = scene_text(material_toml, light_toml, *plane);
            let delta_light = matches!(*light, "point" | "spot" | "directional" | "directional_plane");
            let smooth_specular = matches!(*material, "mirror" | "glass" | "diffuse_mirror" | "plastic");
            let caustic_cell = delta_light && smooth_specular;
            let glass = matches!(*material, "glass" | "roughdielectric");
            let slow = if SLOW_CELLS.contains(&(*light, *material)) { SLOW_SPP_FACTOR } else { 1 };
            let runs = |kind, factor| (11..11 + RUNS).map(|seed| render(&s, kind, seed, factor)).collect::<Vec<_>>();
            // Bidirectional methods are cheap at this size: the path tracer's larger count.
            let many = (1, PATH_SPP_FACTOR * slow);
            let path = runs(IntegratorKind::Path, many);
            let bdpt = runs(IntegratorKind::Bdpt, many);
            let (sppm, vcm) = if caustic_cell {
                (runs(IntegratorKind::Sppm, (1, slow)), runs(IntegratorKind::Vcm, (1, slow)))
            } else {
                (Vec::new(), runs(IntegratorKind::Vcm, many))
            };
            let tol = if glass { 0.03 } else { 0.02 };
            let mut row = format!("{light:18} {material:16}");
            for (method, runs) in [("bdpt", &bdpt), ("vcm", &vcm)] {
                let mut cells = Vec::new();
                for (j, layer) in LAYER_NAMES.iter().enumerate() {
                    // The reference of this layer (see the test's comment).
                    let by_sppm = caustic_cell && (method == "vcm" || j != 2);
                    if method == "bdpt" && caustic_cell && j == 0 {
                        continue;
                    }
                    let (name, reference) = if by_sppm { ("sppm", &sppm) } else { ("path", &path) };
                    let image_ref = reference.iter().map(|r| r[0]).sum::<f64>() / reference.len() as f64;
                    let col = |v: &[[f64; 5]]| v.iter().map(|r| r[j]).collect::<Vec<_>>();
                    let (mb, md, err) = difference(&col(runs), &col(reference));
                    // As in the matrix above, but the error is at least that of unpaired runs:
                    // the methods share their camera rays, not their light paths, whose noise
                    // three paired runs can underestimate (as the light tracer's comparison does).
                    let err = err.max(unpaired_error(&col(runs), &col(reference)));
                    let floor = if j == 0 { 0.0 } else { tol / 2.0 * image_ref };
                    let bound = (tol * mb).max(floor).max(4.0 * err);
                    let mark = if md.abs() <= bound { "" } else { "!" };
                    if md.abs() > bound {
                        failures.push(format!(
                            "{light} x {material}: {method} {layer} {:.5} vs {name} {mb:.5} ({:+.2}%, bound {bound:.5})",
                            mb + md,
                            md / mb * 100.0
                        ));
                    }
                    if mb > 0.0 {
                        let by = if by_sppm { "(s)" } else { "" };
                        cells.push(format!("{}{:+.1}%{mark}{by}", &layer[..2], md / mb * 100.0));
                    }
                }
                row += &format!(" | {method} {}", cells.join(" "));
            }
            table += &format!("{row}\n");
        }
    }
    eprintln!("{table}");
    assert!(failures.is_empty(), "bidirectional methods disagree:\n{}", failures.join("\n"));
}

/// The standard error of the difference of the means of two independent sets of runs.
fn unpaired_error(a: &[f64], b: &[f64]) -> f64 {
    let var_of_mean = |v: &[f64]| {
        let m = v.iter().sum::<f64>() / v.len() as f64;
        v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() as f64 - 1.0) / v.len() as f64
    };
    (var_of_mean(a) + var_of_mean(b)).sqrt()
}

/// The media row's scene: a `null`-bounded box of fog (forward-scattering, coloured) on a grey
/// floor, holding `inside` (an object's TOML table, material "test"), under `light`.
fn media_scene(inside: &str, material: &str, light: &str, width: u32) -> String {
    format!(
        r#"[render]
width = {width}
height = {height}
max_depth = 12

[camera]
eye = [0, 1.6, 4.5]
look_at = [0, 0.7, 0]
fov = 45

[media.fog]
type = "homogeneous"
sigma_s = [0.9, 0.7, 0.5]
sigma_a = 0.1
phase = "hg"
g = 0.3

[materials.boundary]
type = "null"

[materials.floor]
type = "diffuse"
color = [0.6, 0.6, 0.6]
kd = 1

[materials.test]
{material}

[[objects]]
type = "quad"
corner = [-3, 0, 3]
edge1 = [6, 0, 0]
edge2 = [0, 0, -6]
material = "floor"

[[objects]]
type = "box"
min = [-1.1, 0.01, -1.1]
max = [1.1, 2.0, 1.1]
material = "boundary"
interior = "fog"

{inside}

{light}
"#,
        height = width * 5 / 6
    )
}

/// Mean luminance of `s` rendered by `kind` with `seed`: `spp` camera samples per pixel (SPPM's
/// iterations), `photons` for the photon integrator's global map, `per_iter` for SPPM's.
fn render_media(
    s: &str,
    kind: IntegratorKind,
    seed: u64,
    spp: u32,
    photons: u64,
    per_iter: u64,
    radius: Option<f32>,
) -> f64 {
    let photon = PhotonOptions {
        photons: (kind == IntegratorKind::Photon).then_some(photons),
        // Few caustic photons and gather rays, as in the matrix above: the light through glass
        // is mostly scattered by the fog before it lands, and the runs average the gathers.
        caustic_photons: (kind == IntegratorKind::Photon).then_some(50_000),
        gather: (kind == IntegratorKind::Photon).then_some(4),
        photons_per_iter: (kind == IntegratorKind::Sppm).then_some(per_iter),
        initial_radius: radius.filter(|_| kind == IntegratorKind::Sppm),
        ..Default::default()
    };
    let o = Options { integrator: Some(kind), spp: Some(spp), seed: Some(seed), photon, ..Default::default() };
    mean(&common::scene_with(s, &o).render().image)
}

/// The consistency matrix's media row (issue 27): photon mapping (a volume photon map, light
/// samples in the medium) and SPPM (volume photons, a shrinking radius) against the volumetric
/// path tracer in mean luminance, within 3% or four standard errors of the difference if that
/// is larger, on a box of fog holding a diffuse sphere under an area light and under an
/// environment map. The volumetric caustic of a point-like spot light focused by a glass sphere
/// into the fog (light paths L S+ V, which volpath cannot sample) is compared between photon
/// mapping and SPPM, within 3%.
#[test]
fn photon_mapping_and_sppm_agree_with_volpath_in_media() {
    let sphere = "[[objects]]\ntype = \"sphere\"\ncenter = [0, 0.6, 0]\nradius = 0.45\nmaterial = \"test\"";
    let diffuse = "type = \"diffuse\"\ncolor = [0.7, 0.6, 0.5]\nkd = 1";
    let light = |name: &str| LIGHTS.iter().find(|l| l.0 == name).expect("a light of the matrix").1;
    let glass =
        "[[objects]]\ntype = \"sphere\"\ncenter = [0, 1.4, 0]\nradius = 0.4\nmaterial = \"test\"\nexterior = \"fog\"";
    let spot = "[[lights]]\ntype = \"spot\"\nposition = [0, 3.5, 0]\nlook_at = [0, 0, 0]\nangle = 12\nfalloff = 9\nintensity = 40";
    // SPPM at its default radius in the area-lit cells; in the caustic's, where most of the fog
    // is lit only by the few photons scattered out of the focused cone, its default radius
    // (from the mean density of volume photons) leaves the dim fog noisy for 64 iterations
    // (the bound grows to 7%): a larger one, as a long run's would be after its noise has gone.
    let cells = [
        ("quad", media_scene(sphere, diffuse, light("quad"), 24), true, None),
        ("envmap", media_scene(sphere, diffuse, light("envmap"), 24), true, None),
        ("spot caustic", media_scene(glass, "type = \"dielectric\"\nior = 1.5", spot, 24), false, Some(0.15)),
    ];
    let mut failures = Vec::new();
    let mut table = String::new();
    for (name, s, by_volpath, radius) in &cells {
        let runs = |kind, spp, photons, per_iter| {
            let t = std::time::Instant::now();
            let r = (11..11 + RUNS).map(|seed| render_media(s, kind, seed, spp, photons, per_iter, *radius));
            let r = r.collect::<Vec<_>>();
            eprintln!("{name} {kind:?}: {:.1} s", t.elapsed().as_secs_f64());
            r
        };
        let photon = runs(IntegratorKind::Photon, 16, 1_000_000, 0);
        let sppm = runs(IntegratorKind::Sppm, 64, 0, 40_000);
        let mut compare = |what: &str, a: &[f64], b: &[f64]| {
            let (mb, md, err) = difference(a, b);
            let err = err.max(unpaired_error(a, b));
            let bound = (0.03 * mb).max(4.0 * err);
            let ok = md.abs() <= bound;
            if !ok {
                failures.push(format!(
                    "{name}: {what} {:.5} vs {mb:.5} ({:+.2}%, bound {bound:.5})",
                    mb + md,
                    md / mb * 100.0
                ));
            }
            format!("{what} {:+.2}%{} (bound {:.2}%)", md / mb * 100.0, if ok { "" } else { "!" }, bound / mb * 100.0)
        };
        let row = if *by_volpath {
            let volpath = runs(IntegratorKind::Volpath, 1024, 0, 0);
            format!("{} | {}", compare("photon", &photon, &volpath), compare("sppm", &sppm, &volpath))
        } else {
            compare("photon/sppm", &photon, &sppm)
        };
        table += &format!("media {name:14} {row}\n");
    }
    eprintln!("{table}");
    assert!(failures.is_empty(), "integrators disagree in media:\n{}", failures.join("\n"));
}
