//! Spectral mode in participating media (issue 31): the volumetric path tracer against Mitsuba 3's
//! `scalar_spectral` volpath on three media scenes (tests/data/spectral_media, rendered by
//! scripts/make_spectral_media_refs.py), photon mapping and SPPM against spectral volpath, and
//! the same image on any thread count.

mod common;

use caustic::film::Image;
use caustic::options::{IntegratorKind, Options, PhotonOptions};
use common::mitsuba_refs::References;
use std::sync::LazyLock;

static REFS: LazyLock<References> = LazyLock::new(|| References::new("spectral_media"));

fn render(case: &str, spp: u32, o: Options) -> Image {
    render_at(case, 64, spp, o)
}

/// `case` rendered spectrally at `res` x `res`.
fn render_at(case: &str, res: u32, spp: u32, o: Options) -> Image {
    REFS.load(case, res, spp, &Options { spectral: Some(true), ..o }).render().image
}

fn mean(img: &Image) -> [f64; 3] {
    let mut m = [0.0f64; 3];
    for p in &img.pixels {
        for (k, v) in p.to_array().iter().enumerate() {
            m[k] += f64::from(*v);
        }
    }
    m.map(|v| v / img.pixels.len() as f64)
}

/// Spectral volpath against Mitsuba's `scalar_spectral` volpath: each channel's mean within 1%
/// and the per-pixel RMSE within 1.25x of what the noise of both images predicts (our two
/// renders, seeds 1 and 2, give ours; the manifest Mitsuba's). A homogeneous chromatic fog under
/// an area light above a floor, the heterogeneous RGB grids of `hetero_rgb`, and a fog around an
/// emitter.
#[test]
fn volpath_matches_mitsuba_scalar_spectral_in_media() {
    let mut failures = Vec::new();
    for (case, spp) in [("cube_area", 128), ("hetero_rgb", 128), ("emitter_inside", 128)] {
        let o = |seed| Options { seed: Some(seed), integrator: Some(IntegratorKind::Volpath), ..Options::default() };
        let (a, b) = (render(case, spp, o(1)), render(case, spp, o(2)));
        let (_, ratio, line) = REFS.judge(case, &a, &b);
        let (ours, theirs) = ([mean(&a), mean(&b)], mean(&REFS.reference(case)));
        let rel: Vec<f64> = (0..3).map(|k| (ours[0][k] + ours[1][k]) / 2.0 / theirs[k] - 1.0).collect();
        eprintln!("{case}: per-channel mean {:+.2}% {:+.2}% {:+.2}%", rel[0] * 100.0, rel[1] * 100.0, rel[2] * 100.0);
        if ratio >= 1.25 || rel.iter().any(|r| r.abs() >= 0.01) {
            failures.push(format!("{line}; per channel {rel:?}"));
        }
    }
    assert!(failures.is_empty(), "differ from Mitsuba's scalar_spectral:\n{}", failures.join("\n"));
}

fn assert_close(what: &str, a: [f64; 3], b: [f64; 3], tolerance: f64) {
    let ratio: Vec<f64> = (0..3).map(|k| a[k] / b[k]).collect();
    eprintln!("{what}: {a:?} against {b:?}, ratio {ratio:?}");
    for r in ratio {
        assert!((r - 1.0).abs() < tolerance, "{what}: ratio {r}");
    }
}

/// Spectral photon mapping and SPPM agree with spectral volpath in media: each channel's mean
/// within 3%, on the homogeneous fog cube and on the heterogeneous RGB grids (32 x 32; SPPM with
/// the photons per iteration of 64 x 64's default).
#[test]
fn photon_and_sppm_agree_with_volpath_in_media() {
    for case in ["cube_area", "hetero_rgb"] {
        let kind = |k| Options { integrator: Some(k), seed: Some(1), ..Options::default() };
        let volpath = mean(&render_at(case, 32, 512, kind(IntegratorKind::Volpath)));
        let sppm = Options {
            photon: PhotonOptions { photons_per_iter: Some(4096), ..Default::default() },
            ..kind(IntegratorKind::Sppm)
        };
        let sppm = mean(&render_at(case, 32, 128, sppm));
        assert_close(&format!("{case}: sppm / volpath"), sppm, volpath, 0.03);
        let photon = Options {
            photon: PhotonOptions { photons: Some(500_000), ..Default::default() },
            ..kind(IntegratorKind::Photon)
        };
        let photon = mean(&render_at(case, 32, 16, photon));
        assert_close(&format!("{case}: photon / volpath"), photon, volpath, 0.03);
    }
}

/// Spectral renders in media are the same bit for bit on one and two threads, for volpath,
/// photon mapping and SPPM (heterogeneous tracking draws from each path's and each photon's own
/// stream).
#[test]
fn spectral_media_images_are_the_same_on_any_thread_count() {
    for kind in [IntegratorKind::Volpath, IntegratorKind::Photon, IntegratorKind::Sppm] {
        let o = Options {
            spectral: Some(true),
            integrator: Some(kind),
            seed: Some(3),
            photon: PhotonOptions { photons: Some(20_000), ..Default::default() },
            ..Options::default()
        };
        let s = REFS.load("hetero_rgb", 16, 4, &o);
        let render = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| s.render().image)
        };
        let (a, b) = (render(1), render(2));
        assert!(a.pixels.iter().zip(&b.pixels).all(|(x, y)| x.to_array() == y.to_array()), "{}", kind.name());
    }
}

/// The float channels of an EXR file by name.
fn exr_channels(path: &std::path::Path) -> std::collections::HashMap<String, Vec<f32>> {
    let image =
        exr::prelude::read_all_flat_layers_from_file(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let layer = &image.layer_data[0];
    layer.channel_data.list.iter().map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect())).collect()
}

/// Renders `scene` (a file) to `output` with `overrides`, quietly on two threads.
fn render_to(scene: &std::path::Path, output: &std::path::Path, overrides: Options, layers: bool) {
    let opts = caustic::app::RenderOptions {
        scene: scene.to_path_buf(),
        output: Some(output.to_path_buf()),
        overrides,
        quiet: true,
        layers,
        threads: Some(2),
        ..Default::default()
    };
    caustic::app::render_file(&opts, &std::sync::atomic::AtomicBool::new(false))
        .unwrap_or_else(|e| panic!("{}: {e}", output.display()));
}

/// `--xyz`: the EXR's X, Y, Z channels are the same render's R, G, B times the sRGB-to-XYZ
/// matrix (to float rounding: 1e-6 relative), in RGB and spectral mode, for the image, its
/// layers, and with AOVs (which keep their own channels).
#[test]
fn xyz_exr_is_the_srgb_exr_times_the_matrix() {
    let dir = common::scratch("xyz-output");
    let scene = REFS.dir.join("cube_area.xml");
    let m = caustic::film::output::srgb_to_xyz();
    for spectral in [false, true] {
        let o = |xyz| Options {
            width: Some(16),
            height: Some(16),
            spp: Some(4),
            seed: Some(5),
            spectral: Some(spectral),
            xyz: Some(xyz),
            aov: Some(caustic::film::aov::AovList::parse("albedo,depth").unwrap()),
            ..Options::default()
        };
        let (srgb, xyz) = (dir.join(format!("srgb-{spectral}.exr")), dir.join(format!("xyz-{spectral}.exr")));
        render_to(&scene, &srgb, o(false), true);
        render_to(&scene, &xyz, o(true), true);
        let files = |p: &std::path::Path| {
            [
                p.to_path_buf(),
                caustic::film::output::layer_path(p, "direct"),
                caustic::film::output::layer_path(p, "indirect"),
            ]
        };
        for (a, b) in files(&srgb).iter().zip(&files(&xyz)) {
            let (a, b) = (exr_channels(a), exr_channels(b));
            assert!(b.contains_key("X") && !b.contains_key("R"), "{:?}", b.keys());
            if a.contains_key("albedo.R") {
                for aov in ["albedo.R", "albedo.G", "albedo.B", "depth.T"] {
                    assert_eq!(a[aov], b[aov], "{aov}");
                }
            }
            let mut nonzero = 0;
            for i in 0..a["R"].len() {
                let rgb = [a["R"][i], a["G"][i], a["B"][i]].map(f64::from);
                nonzero += usize::from(rgb.iter().any(|v| *v != 0.0));
                for (k, name) in ["X", "Y", "Z"].into_iter().enumerate() {
                    let want = m[k][0] * rgb[0] + m[k][1] * rgb[1] + m[k][2] * rgb[2];
                    let got = f64::from(b[name][i]);
                    assert!(
                        (got - want).abs() <= 1e-6 * want.abs().max(1e-3),
                        "spectral {spectral}: {name}[{i}] {got} vs {want}"
                    );
                }
            }
            assert!(nonzero > 0, "an empty image tests nothing");
        }
    }
}

/// A grey constant (RGB mode: a constant environment seen everywhere) writes X:Y:Z in D65's
/// ratio, (0.95047, 1, 1.08883) times the grey to 1e-4; a white furnace in spectral mode within
/// 1% (its noise and the uplift's error); and a PNG refuses XYZ before rendering.
#[test]
fn grey_is_d65_in_xyz() {
    let dir = common::scratch("xyz-grey");
    // CIE 1931 XYZ of D65 with Y = 1 (its xy chromaticity 0.3127, 0.3290).
    let d65 = [0.3127 / 0.3290, 1.0, (1.0 - 0.3127 - 0.3290) / 0.3290];
    let grey = dir.join("grey.toml");
    std::fs::write(&grey, "[render]\nwidth = 4\nheight = 4\nspp = 1\nintegrator = \"path\"\nbackground = [0.5, 0.5, 0.5]\n[camera]\neye = [0, 0, 0]\nlook_at = [0, 0, 1]\n").unwrap();
    let out = dir.join("grey.exr");
    render_to(&grey, &out, Options { xyz: Some(true), ..Options::default() }, false);
    let c = exr_channels(&out);
    for (k, name) in ["X", "Y", "Z"].into_iter().enumerate() {
        assert_eq!(c[name].len(), 16);
        for &v in &c[name] {
            let v = f64::from(v) / 0.5;
            assert!((v - d65[k]).abs() < 1e-3 * d65[k], "{name}: {v} vs {}", d65[k]);
        }
    }
    let furnace = dir.join("furnace.toml");
    std::fs::write(
        &furnace,
        common::point_light_furnace(64).replace("max_depth = 64", "max_depth = 64\nspp = 256\nintegrator = \"path\""),
    )
    .unwrap();
    let out = dir.join("furnace.exr");
    render_to(&furnace, &out, Options { xyz: Some(true), spectral: Some(true), ..Options::default() }, false);
    let c = exr_channels(&out);
    let mean = ["X", "Y", "Z"].map(|n| c[n].iter().map(|v| f64::from(*v)).sum::<f64>() / c[n].len() as f64);
    eprintln!("spectral furnace in XYZ: {mean:?} (D65 {d65:?})");
    for k in 0..3 {
        assert!((mean[k] / mean[1] / d65[k] - 1.0).abs() < 0.01, "{mean:?}");
    }
    let opts = caustic::app::RenderOptions {
        scene: grey.clone(),
        output: Some(dir.join("grey.png")),
        overrides: Options { xyz: Some(true), ..Options::default() },
        quiet: true,
        ..Default::default()
    };
    let e = match caustic::app::render_file(&opts, &std::sync::atomic::AtomicBool::new(false)) {
        Ok(_) => panic!("a PNG accepted XYZ"),
        Err(e) => e.to_string(),
    };
    assert!(e.contains("XYZ") && e.contains(".exr"), "{e}");
    let png_scene = dir.join("grey-xyz.toml");
    std::fs::write(&png_scene, std::fs::read_to_string(&grey).unwrap().replace("[render]", "[render]\nxyz = true"))
        .unwrap();
    let opts = caustic::app::RenderOptions { scene: png_scene, overrides: Options::default(), ..opts };
    let e = match caustic::app::render_file(&opts, &std::sync::atomic::AtomicBool::new(false)) {
        Ok(_) => panic!("a PNG accepted XYZ"),
        Err(e) => e.to_string(),
    };
    assert!(e.contains("XYZ"), "{e}");
}

/// A farm render asked for XYZ writes XYZ when merged: `--xyz` is part of the render's identity,
/// so `caustic merge` writes the X, Y, Z channels the whole render would have, bit for bit.
#[test]
fn merged_shards_keep_xyz() {
    use caustic::farm::shard::{Shard, ShardSpec};
    let dir = common::scratch("xyz-merge");
    let scene = REFS.dir.join("cube_area.xml");
    let overrides = Options {
        width: Some(12),
        height: Some(12),
        spp: Some(4),
        seed: Some(2),
        spectral: Some(true),
        xyz: Some(true),
        ..Options::default()
    };
    let whole = dir.join("whole.exr");
    render_to(&scene, &whole, overrides.clone(), false);
    let parts: Vec<std::path::PathBuf> = (0..2).map(|i| dir.join(format!("part-{i}.exr"))).collect();
    for (i, part) in parts.iter().enumerate() {
        let opts = caustic::app::RenderOptions {
            scene: scene.clone(),
            output: Some(part.clone()),
            overrides: overrides.clone(),
            quiet: true,
            threads: Some(2),
            shard: Some(ShardSpec::Fixed(Shard { index: i as u32, count: 2 })),
            ..Default::default()
        };
        if let Err(e) = caustic::app::render_file(&opts, &std::sync::atomic::AtomicBool::new(false)) {
            panic!("shard {i}: {e}");
        }
    }
    let merged = dir.join("merged.exr");
    if let Err(e) = caustic::app::merge_files(&parts, &merged, false, true) {
        panic!("merge: {e}");
    }
    let (a, b) = (exr_channels(&whole), exr_channels(&merged));
    for name in ["X", "Y", "Z"] {
        assert_eq!(a[name], b[name], "{name}");
    }
    assert!(!b.contains_key("R"));
    let png = dir.join("merged.png");
    let e = match caustic::app::merge_files(&parts, &png, false, true) {
        Ok(_) => panic!("a PNG accepted XYZ"),
        Err(e) => e.to_string(),
    };
    assert!(e.contains("XYZ"), "{e}");
}
