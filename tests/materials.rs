//! Materials and textures against Mitsuba 3: every scene of tests/data/materials rendered by our
//! path tracer and compared with Mitsuba's own image of it (mean luminance within 1%, per-pixel
//! RMSE within what the two images' noise predicts), the textured quads pixel for pixel, and the
//! photon and SPPM integrators against the same references (mean luminance within 3%).
//!
//! The references and their sample counts and noise are listed in tests/data/materials/MANIFEST.md
//! (scripts/make_material_refs.py renders them; scripts/make_material_scenes.py writes the scenes).

use caustic::app::LoadedScene;
use caustic::film::Image;
use caustic::film::output::read_exr;
use caustic::math::luminance;
use caustic::scene::desc::IntegratorKind;
use caustic::scene::{LoadOptions, Overrides};
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::LazyLock;

fn dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/materials")
}

/// Mitsuba's noise per case (the RMS per-pixel standard deviation of its image), from MANIFEST.md.
static REFERENCE_NOISE: LazyLock<HashMap<String, f64>> = LazyLock::new(|| {
    let text = std::fs::read_to_string(dir().join("MANIFEST.md")).expect("MANIFEST.md");
    let mut noise = HashMap::new();
    for line in text.lines().filter(|l| l.starts_with("| `")) {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        // | case | integrator | size | spp | s | mean R, G, B | mean lum. | noise | object share |
        let case = cells[1].trim_matches('`').to_string();
        noise.insert(case, cells[8].parse::<f64>().expect("noise column"));
    }
    noise
});

fn load(case: &str, res: u32, spp: u32, o: &Overrides) -> LoadedScene {
    let defines = vec![("res".to_string(), res.to_string()), ("spp".to_string(), spp.to_string())];
    let path = dir().join(format!("{case}.xml"));
    caustic::app::load(&path, &LoadOptions { defines, strict: true }, o)
        .unwrap_or_else(|e| panic!("{case} failed to load: {e}"))
}

fn render(case: &str, res: u32, spp: u32, seed: u64, integrator: Option<IntegratorKind>) -> Image {
    let o = Overrides { seed: Some(seed), integrator, ..Default::default() };
    load(case, res, spp, &o).render().image
}

fn reference(case: &str) -> Image {
    read_exr(&dir().join(format!("{case}.exr"))).unwrap_or_else(|e| panic!("{case}: reference: {e}"))
}

fn mean_luminance(img: &Image) -> f64 {
    img.pixels.iter().map(|&c| luminance(c) as f64).sum::<f64>() / img.pixels.len() as f64
}

fn rmse(a: &Image, b: &Image) -> f64 {
    assert_eq!((a.width, a.height), (b.width, b.height));
    let s: f64 = a.pixels.iter().zip(&b.pixels).map(|(x, y)| (*x - *y).length_squared() as f64 / 3.0).sum();
    (s / a.pixels.len() as f64).sqrt()
}

/// Renders `case` with the path tracer (two seeds, for our noise) and compares with Mitsuba;
/// returns a failure message or None.
fn compare_with_mitsuba(case: &str, res: u32, spp: u32) -> Option<String> {
    let reference = reference(case);
    let (a, b) = (render(case, res, spp, 1, None), render(case, res, spp, 2, None));
    let noise = rmse(&a, &b) / 2f64.sqrt();
    let ref_noise = REFERENCE_NOISE[case];
    let expected = (noise * noise + ref_noise * ref_noise).sqrt();
    let (ours, theirs) = ((mean_luminance(&a) + mean_luminance(&b)) / 2.0, mean_luminance(&reference));
    let rel = ours / theirs - 1.0;
    let err = rmse(&a, &reference);
    let line = format!(
        "{case:38} mean {ours:.5} vs {theirs:.5} ({:+.2}%), rmse {err:.5} vs {expected:.5} from noise ({:.2}x)",
        rel * 100.0,
        err / expected
    );
    eprintln!("{line}");
    (rel.abs() >= 0.01 || err >= 1.25 * expected).then_some(line)
}

fn check_all(cases: &[(&str, u32)], res: u32) {
    let failures: Vec<String> = cases.iter().filter_map(|&(case, spp)| compare_with_mitsuba(case, res, spp)).collect();
    assert!(failures.is_empty(), "differ from Mitsuba:\n{}", failures.join("\n"));
}

/// Each material under a point light (its BSDF evaluated by next-event estimation) and under a
/// spherical area light (its sampling and MIS weights).
const SPHERE_CASES: &[&str] = &[
    "blendbsdf",
    "bumpmap",
    "conductor_au",
    "conductor_etak",
    "conductor_none",
    "dielectric",
    "diffuse_bitmap",
    "diffuse_checker",
    "mask",
    "normalmap",
    "onesided",
    "plastic",
    "plastic_nonlinear",
    "roughconductor_alpha_tex",
    "roughconductor_beckmann_aniso",
    "roughconductor_ggx",
    "roughdielectric_beckmann",
    "roughdielectric_ggx",
    "roughplastic_beckmann",
    "roughplastic_ggx",
    "twosided",
];

fn spp_for(case: &str) -> u32 {
    if case.starts_with("dielectric") || case.starts_with("roughdielectric") { 1024 } else { 256 }
}

#[test]
fn materials_under_a_point_light_match_mitsuba() {
    let cases: Vec<(String, u32)> = SPHERE_CASES.iter().map(|c| (format!("{c}_point"), spp_for(c))).collect();
    check_all(&cases.iter().map(|(c, s)| (c.as_str(), *s)).collect::<Vec<_>>(), 64);
}

#[test]
fn materials_under_an_area_light_match_mitsuba() {
    let cases: Vec<(String, u32)> = SPHERE_CASES.iter().map(|c| (format!("{c}_area"), spp_for(c))).collect();
    check_all(&cases.iter().map(|(c, s)| (c.as_str(), *s)).collect::<Vec<_>>(), 64);
}

/// Every image format, filter and wrap mode on a quad that fills the view: each pixel is the
/// texture averaged over its footprint, so the images agree pixel for pixel.
#[test]
fn textured_quads_match_mitsuba_pixel_for_pixel() {
    let cases = [
        "quad_png8",
        "quad_png16",
        "quad_jpeg",
        "quad_bmp",
        "quad_tga",
        "quad_exr",
        "quad_hdr",
        "quad_pfm",
        "quad_repeat_bilinear",
        "quad_clamp_bilinear",
        "quad_mirror_nearest",
    ];
    check_all(&cases.map(|c| (c, 64)), 128);
}

/// Photon mapping and SPPM carry the light of these materials too: their mean luminance is
/// within 3% of Mitsuba's (photon mapping with final gathering at 16 samples per pixel, SPPM
/// with enough iterations for its radius to shrink below the glossy highlights' size).
#[test]
fn photon_mapping_and_sppm_agree_with_mitsuba_on_materials() {
    // (case, photon spp, SPPM iterations)
    let cases = [
        ("roughconductor_ggx_area", 16, 256),
        ("roughplastic_ggx_point", 16, 256),
        ("plastic_point", 16, 256),
        ("blendbsdf_point", 16, 512),
        ("mask_point", 16, 256),
        ("roughdielectric_ggx_point", 32, 1024),
        ("diffuse_checker_area", 16, 256),
    ];
    let mut failures = Vec::new();
    for (case, photon_spp, sppm_spp) in cases {
        let theirs = mean_luminance(&reference(case));
        for (kind, spp) in [(IntegratorKind::Photon, photon_spp), (IntegratorKind::Sppm, sppm_spp)] {
            let ours = mean_luminance(&render(case, 64, spp, 1, Some(kind)));
            let rel = ours / theirs - 1.0;
            let line = format!("{case:30} {kind:?}: {ours:.5} vs Mitsuba {theirs:.5} ({:+.2}%)", rel * 100.0);
            eprintln!("{line}");
            if rel.abs() >= 0.03 {
                failures.push(line);
            }
        }
    }
    assert!(failures.is_empty(), "photon mapping or SPPM lose light:\n{}", failures.join("\n"));
}
