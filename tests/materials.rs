//! Materials and textures against Mitsuba 3: every scene of tests/data/materials rendered by our
//! path tracer and compared with Mitsuba's own image of it (mean luminance within 1%, per-pixel
//! RMSE within what the two images' noise predicts), the textured quads pixel for pixel, and the
//! photon and SPPM integrators against the same references (mean luminance within 3%).
//!
//! The references and their sample counts and noise are listed in tests/data/materials/MANIFEST.md
//! (scripts/make_material_refs.py renders them; scripts/make_material_scenes.py writes the scenes).

mod common;

use caustic::options::IntegratorKind;
use common::mitsuba_refs::References;
use std::sync::LazyLock;

static REFS: LazyLock<References> = LazyLock::new(|| References::new("materials"));

fn check_all(cases: &[(&str, u32)], res: u32) {
    REFS.check_all(cases, res);
}

/// Each material under a point light (its BSDF evaluated by next-event estimation) and under a
/// 3 x 3 rectangular area light (its sampling and MIS weights).
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
        failures.extend(REFS.compare_mean(case, 64, photon_spp, IntegratorKind::Photon, 0.03));
        failures.extend(REFS.compare_mean(case, 64, sppm_spp, IntegratorKind::Sppm, 0.03));
    }
    assert!(failures.is_empty(), "photon mapping or SPPM lose light:\n{}", failures.join("\n"));
}

/// Blends nest: a blend of a blend and a diffuse, all of albedo 0.8, is a diffuse of albedo 0.8.
/// A convex sphere under a constant environment of radiance 1, lit directly (max_depth 2), then
/// reflects exactly its albedo at every pixel that sees it.
#[test]
fn nested_blends_keep_every_part() {
    let text = r#"<scene version="3.0.0">
        <integrator type="path"><integer name="max_depth" value="2"/></integrator>
        <sensor type="perspective"><float name="fov" value="20"/>
            <transform name="to_world"><lookat origin="0, 0, 8" target="0, 0, 0" up="0, 1, 0"/></transform>
            <sampler type="independent"><integer name="sample_count" value="4096"/></sampler>
            <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film>
        </sensor>
        <bsdf type="diffuse" id="d"><rgb name="reflectance" value="0.8"/></bsdf>
        <bsdf type="blendbsdf" id="inner"><float name="weight" value="0.3"/><ref id="d"/><ref id="d"/></bsdf>
        <shape type="sphere"><bsdf type="twosided"><bsdf type="blendbsdf"><float name="weight" value="0.6"/>
            <ref id="inner"/><bsdf type="diffuse"><rgb name="reflectance" value="0.8"/></bsdf></bsdf></bsdf></shape>
        <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
    </scene>"#;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let desc = caustic::scene::mitsuba::load_mitsuba_str(text, "nested.xml", root, &Default::default()).unwrap();
    let image = caustic::app::prepare(desc, &Default::default()).unwrap().render().image;
    // The 4 x 4 centre pixels see only the sphere.
    for y in 2..6 {
        for x in 2..6 {
            let c = image.get(x, y);
            assert!((c - caustic::math::Color::splat(0.8)).abs().max_element() < 0.01, "pixel ({x}, {y}): {c}");
        }
    }
}
