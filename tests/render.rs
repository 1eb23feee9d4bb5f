//! Whole renders: determinism across thread counts, every bundled scene to PNG and EXR.

mod common;

use caustic::app::{RenderOptions, render_file};
use caustic::film::Image;
use caustic::film::output::read_exr;
use caustic::options::{IntegratorKind, Options, PhotonOptions};
use caustic::scene::LoadOptions;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

fn scenes() -> Vec<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    v.sort();
    v
}

fn render_with_threads(path: &std::path::Path, threads: usize, o: &Options) -> Image {
    let o = Options { integrator: Some(IntegratorKind::Whitted), ..o.clone() };
    let loaded = caustic::app::load(path, &LoadOptions::default(), &o).unwrap();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| loaded.render().image)
}

#[test]
fn same_seed_gives_identical_image_on_1_and_2_threads() {
    let o = Options { width: Some(96), height: Some(72), spp_axis: Some(3), seed: Some(7), ..Default::default() };
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/06-fresnel-glass.toml");
    let a = render_with_threads(&path, 1, &o);
    let b = render_with_threads(&path, 2, &o);
    assert!(
        a.pixels.iter().zip(&b.pixels).all(|(x, y)| x.to_array().map(f32::to_bits) == y.to_array().map(f32::to_bits))
    );
    // A different seed changes the jitter, so the image differs: the test can fail.
    let c = render_with_threads(&path, 2, &Options { seed: Some(8), ..o.clone() });
    assert_ne!(a, c);
}

/// Renders `scene` through the command-line path (`render_file`) with `threads` workers.
fn render_cli(scene: &str, integrator: &str, threads: usize, out: &std::path::Path) -> Image {
    let opts = RenderOptions {
        scene: PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes").join(scene),
        output: Some(out.to_path_buf()),
        overrides: Options {
            width: Some(40),
            height: Some(40),
            spp: Some(4),
            seed: Some(11),
            integrator: Some(integrator.parse().unwrap()),
            photon: PhotonOptions {
                photons: Some(50_000),
                caustic_photons: Some(20_000),
                gather: Some(4),
                ..Default::default()
            },
            ..Default::default()
        },
        threads: Some(threads),
        quiet: true,
        ..Default::default()
    };
    render_file(&opts, &AtomicBool::new(false)).unwrap();
    read_exr(out).unwrap()
}

#[test]
fn every_integrator_is_bit_identical_on_1_2_and_8_threads() {
    let dir = common::scratch("threads");
    for integrator in ["whitted", "path", "photon", "sppm"] {
        let a = render_cli("13-cornell-caustics.toml", integrator, 1, &dir.join(format!("{integrator}-1.exr")));
        assert!(a.mean().max_element() > 0.0, "{integrator}: black image");
        for threads in [2, 8] {
            let b = render_cli(
                "13-cornell-caustics.toml",
                integrator,
                threads,
                &dir.join(format!("{integrator}-{threads}.exr")),
            );
            let same = a
                .pixels
                .iter()
                .zip(&b.pixels)
                .all(|(x, y)| x.to_array().map(f32::to_bits) == y.to_array().map(f32::to_bits));
            assert!(same, "{integrator}: images differ between 1 and {threads} threads");
        }
    }
}

#[test]
fn every_bundled_scene_renders_to_png_and_exr_without_nan() {
    let out = common::scratch("scenes");
    let all = scenes();
    assert!(all.len() >= 6, "expected the example scenes, found {}", all.len());
    for scene in all {
        let stem = scene.file_stem().unwrap().to_string_lossy().into_owned();
        for ext in ["png", "exr"] {
            let output = out.join(format!("{stem}.{ext}"));
            let opts = RenderOptions {
                scene: scene.clone(),
                output: Some(output.clone()),
                overrides: Options { width: Some(64), height: Some(48), spp: Some(2), ..Default::default() },
                quiet: true,
                ..Default::default()
            };
            let summary =
                render_file(&opts, &AtomicBool::new(false)).unwrap_or_else(|e| panic!("{}: {e}", scene.display()));
            assert_eq!(summary.stats.nonfinite_samples, 0, "{stem}");
            assert!(std::fs::metadata(&output).unwrap().len() > 0);
            if ext == "exr" {
                let img = read_exr(&output).unwrap();
                assert_eq!((img.width, img.height), (64, 48));
                assert!(img.pixels.iter().all(|p| p.is_finite()), "{stem}: non-finite pixel");
                assert!(img.mean().max_element() > 0.0, "{stem}: black image");
            }
        }
    }
}

#[test]
fn thin_lens_with_zero_radius_renders_the_pinhole_image_bit_for_bit() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/06-fresnel-glass.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let lens = text.replace("fov = 45", "fov = 45\nlens_radius = 0.0\nfocal_distance = 2.5");
    assert_ne!(text, lens);
    let o = Options { width: Some(64), height: Some(48), spp: Some(4), ..Default::default() };
    let render_text =
        |t: &str| caustic::app::load_toml_str(t, "lens.toml", path.parent().unwrap(), &o).unwrap().render().image;
    let (a, b) = (render_text(&text), render_text(&lens));
    assert!(
        a.pixels.iter().zip(&b.pixels).all(|(x, y)| x.to_array().map(f32::to_bits) == y.to_array().map(f32::to_bits))
    );
    // A real lens changes the image (so the comparison above can fail).
    let blurred = render_text(&text.replace("fov = 45", "fov = 45\nlens_radius = 0.2\nfocal_distance = 2.5"));
    assert_ne!(a, blurred);
}

/// Issue 30, item 7: `--filter` (one of the render's options) renders what the scene file's
/// `filter` key renders, bit for bit, and over the file's own filter.
#[test]
fn the_command_line_filter_is_the_scene_files_filter() {
    let scene = |filter: &str| {
        format!(
            "[render]\nwidth = 24\nheight = 18\nspp = 4\n{filter}\n[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\n\
             [[lights]]\ntype = \"point\"\nposition = [2, 3, 4]\nintensity = 20\n\
             [[objects]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n"
        )
    };
    let render = |text: &str, o: &Options| {
        caustic::app::load_toml_str(text, "f.toml", std::path::Path::new("."), o).unwrap().render().image
    };
    let none = Options::default();
    let mitchell = caustic::film::filter::Filter::Mitchell { b: 0.5, c: 0.25 };
    let from_file = render(&scene("filter = { type = \"mitchell\", B = 0.5, C = 0.25 }"), &none);
    let from_option = render(&scene(""), &Options { filter: Some(mitchell), ..none.clone() });
    let over_file = render(&scene("filter = \"lanczos\""), &Options { filter: Some(mitchell), ..none.clone() });
    let boxed = render(&scene(""), &none);
    assert_eq!(from_file, from_option);
    assert_eq!(from_file, over_file);
    assert_ne!(from_file, boxed, "the filter changes the image: the test can fail");
}
