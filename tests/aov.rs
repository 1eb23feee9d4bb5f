//! AOVs (issue 30, item 10): first-hit values against the scene's geometry, variance and sample
//! counts, the same images on any thread count, exact farm merges, every integrator, and
//! Mitsuba's `aov` integrator.

mod common;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn caustic() -> Command {
    Command::new(env!("CARGO_BIN_EXE_caustic"))
}

/// A red diffuse sphere of radius 1 at the origin seen from z = 5, lit by a point light.
const SCENE: &str = "[render]\nwidth = 32\nheight = 24\nspp = 8\n\
[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov = 40\n\
[materials.red]\ntype = \"diffuse\"\ncolor = [0.8, 0.2, 0.1]\nkd = 1\n\
[[lights]]\ntype = \"point\"\nposition = [2, 3, 4]\nintensity = 20\n\
[[objects]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"red\"\n";

/// Every float channel of an EXR file by name (all of them, u32 sums included as floats).
fn channels(path: &Path) -> HashMap<String, Vec<f32>> {
    use exr::prelude::*;
    let image = read().no_deep_data().largest_resolution_level().all_channels().first_valid_layer().all_attributes();
    let image = image.from_file(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    image
        .layer_data
        .channel_data
        .list
        .iter()
        .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
        .collect()
}

fn render(dir: &Path, scene: &str, out: &str, args: &[&str]) -> PathBuf {
    let path = dir.join("scene.toml");
    std::fs::write(&path, scene).unwrap();
    let output = dir.join(out);
    let r = caustic().arg("render").arg(&path).arg("-o").arg(&output).arg("-q").args(args).output().unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    output
}

const ALL: &str = "albedo,normal,depth,position,uv,variance,spp";

#[test]
fn first_hit_aovs_describe_what_the_camera_sees() {
    let dir = common::scratch("aov-values");
    let out = render(&dir, SCENE, "a.exr", &["--aov", ALL, "--no-antialias", "--integrator", "path"]);
    let c = channels(&out);
    for name in [
        "R",
        "G",
        "B",
        "albedo.R",
        "albedo.G",
        "albedo.B",
        "normal.X",
        "normal.Y",
        "normal.Z",
        "depth.T",
        "position.X",
        "position.Y",
        "position.Z",
        "uv.U",
        "uv.V",
        "variance.R",
        "variance.G",
        "variance.B",
        "spp.N",
    ] {
        assert!(c.contains_key(name), "no channel {name}: {:?}", c.keys().collect::<Vec<_>>());
    }
    // The pixel at the middle of the 32 x 24 image looks at the sphere's nearest point: a ray
    // through the pixel centre (16.5, 12.5) is almost the view axis.
    let p = 12 * 32 + 16;
    let near = |a: f32, b: f32, tol: f32| (a - b).abs() < tol;
    assert!(near(c["depth.T"][p], 4.0, 0.01), "depth {}", c["depth.T"][p]);
    assert!(near(c["position.Z"][p], 1.0, 0.01) && near(c["normal.Z"][p], 1.0, 0.01));
    assert!(near(c["albedo.R"][p], 0.8, 1e-6) && near(c["albedo.G"][p], 0.2, 1e-6), "{}", c["albedo.R"][p]);
    // A corner pixel sees nothing: every first-hit value is zero there.
    for name in ["depth.T", "position.X", "normal.Z", "albedo.R", "uv.U"] {
        assert_eq!(c[name][0], 0.0, "{name} at a pixel that sees nothing");
    }
    assert!(c["spp.N"].iter().all(|&n| n == 8.0));
    // Variance: zero where every sample sees the same black background, positive somewhere on
    // the lit sphere (the path tracer's light paths differ between samples).
    assert_eq!(c["variance.R"][0], 0.0);
    assert!(c["variance.R"].iter().any(|&v| v > 0.0));
    assert!(c["variance.R"].iter().all(|&v| v >= 0.0 && v.is_finite()));
}

#[test]
fn variance_is_the_variance_of_the_pixel_mean() {
    // Estimated from two renders with different seeds: the spread of their pixel values around
    // each other matches the variance AOV's prediction (2 x variance of the mean), on average
    // over the image. Rays through pixel centres and a light sampled by area: the samples of a
    // pixel are independent (stratified pixel positions would make the pixel's error smaller
    // than independent samples' variance says).
    let dir = common::scratch("aov-variance");
    let scene = "[render]\nwidth = 32\nheight = 24\nspp = 16\n\
[camera]\neye = [0, 2, 4]\nlook_at = [0, 0, 0]\n\
[[lights]]\ntype = \"area\"\ncorner = [-1, 2, -1]\nedge1 = [2, 0, 0]\nedge2 = [0, 0, 2]\nintensity = 5\n\
[[objects]]\ntype = \"plane\"\n\
[[objects]]\ntype = \"sphere\"\ncenter = [0, 0.5, 0]\nradius = 0.5\n";
    let run = |seed: &str, name: &str| {
        let args = ["--aov", "variance", "--integrator", "path", "--no-antialias", "--seed", seed];
        channels(&render(&dir, scene, name, &args))
    };
    let (a, b) = (run("1", "a.exr"), run("2", "b.exr"));
    let diff2: f64 = a["R"].iter().zip(&b["R"]).map(|(x, y)| ((x - y) as f64).powi(2)).sum();
    let predicted: f64 = a["variance.R"].iter().zip(&b["variance.R"]).map(|(x, y)| (x + y) as f64).sum();
    let ratio = diff2 / predicted;
    assert!((0.7..1.3).contains(&ratio), "measured spread / predicted = {ratio}");
}

#[test]
fn aovs_are_the_same_on_any_thread_count_and_beside_a_png() {
    let dir = common::scratch("aov-threads");
    let one = channels(&render(&dir, SCENE, "one.exr", &["--aov", ALL, "--threads", "1"]));
    let two = render(&dir, SCENE, "two.png", &["--aov", ALL, "--threads", "2"]);
    let beside = channels(&two.with_extension("aovs.exr"));
    for (name, values) in &beside {
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(values), bits(&one[name]), "{name} differs between 1 and 2 threads");
    }
    assert_eq!(beside.len(), 16, "{:?}", beside.keys().collect::<Vec<_>>());
}

#[test]
fn shards_merge_to_the_one_machine_aovs_bit_for_bit() {
    let dir = common::scratch("aov-farm");
    for integrator in ["path", "sppm"] {
        let whole = channels(&render(&dir, SCENE, "whole.exr", &["--aov", ALL, "--integrator", integrator]));
        let mut parts = Vec::new();
        for i in 0..2 {
            let shard = format!("{i}/2");
            let name = format!("part{i}.exr");
            parts.push(render(&dir, SCENE, &name, &["--aov", ALL, "--integrator", integrator, "--shard", &shard]));
        }
        let merged = dir.join("merged.exr");
        let r = caustic().arg("merge").args(&parts).arg("-o").arg(&merged).arg("-q").output().unwrap();
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        let merged = channels(&merged);
        let exact = ["albedo.R", "normal.Y", "depth.T", "position.X", "uv.V", "spp.N"];
        let names: Vec<&str> = if integrator == "path" {
            exact.iter().copied().chain(["variance.G", "R"]).collect()
        } else {
            exact.to_vec()
        };
        for name in names {
            assert_eq!(merged[name], whole[name], "{integrator}: merged {name} is not the one-machine render's");
        }
        // A part with other AOVs does not merge with these.
        let other =
            render(&dir, SCENE, "other.exr", &["--aov", "albedo", "--integrator", integrator, "--shard", "1/2"]);
        let r = caustic().arg("merge").arg(&parts[0]).arg(&other).arg("-o").arg(dir.join("m.exr")).output().unwrap();
        assert!(!r.status.success());
        assert!(String::from_utf8_lossy(&r.stderr).contains("aovs"), "{}", String::from_utf8_lossy(&r.stderr));
    }
}

#[test]
fn every_integrator_gives_the_same_first_hit_aovs() {
    // The AOVs come from the camera samples, which every integrator draws alike from one sample
    // pattern (named here: the progressive integrators default to another).
    let dir = common::scratch("aov-integrators");
    let of = |integrator: &str| {
        let name = format!("{integrator}.exr");
        let args = ["--aov", "albedo,depth,normal", "--integrator", integrator, "--sampler", "sobol"];
        channels(&render(&dir, SCENE, &name, &args))
    };
    let path = of("path");
    for integrator in ["whitted", "photon", "sppm", "light"] {
        let other = of(integrator);
        for name in ["albedo.R", "depth.T", "normal.X"] {
            assert_eq!(other[name], path[name], "{integrator}'s {name} differs from the path tracer's");
        }
    }
}

#[test]
fn mitsubas_aov_integrator_writes_its_channels() {
    let dir = common::scratch("aov-mitsuba");
    let xml = r#"<scene version="3.0.0">
    <integrator type="aov">
        <string name="aovs" value="dd.y:depth,nn:sh_normal,pi:prim_index"/>
        <integrator type="path"/>
    </integrator>
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="12"/></film>
        <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
    </sensor>
    <shape type="sphere"><bsdf type="diffuse"/></shape>
    <emitter type="constant"/>
</scene>"#;
    let path = dir.join("aov.xml");
    std::fs::write(&path, xml).unwrap();
    let out = dir.join("aov.exr");
    let r = caustic().arg("render").arg(&path).arg("-o").arg(&out).output().unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(String::from_utf8_lossy(&r.stderr).contains("`prim_index` AOV is not supported"));
    let c = channels(&out);
    assert!(c.contains_key("dd.y.T") && c.contains_key("nn.X") && !c.keys().any(|k| k.starts_with("pi")));
    assert!(c["dd.y.T"].iter().any(|&d| (3.9..4.2).contains(&d)), "{:?}", c["dd.y.T"]);
}
