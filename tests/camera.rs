//! Cameras and films (issue 12, item 4): the orthographic sensor, principal-point offsets, crop
//! windows and reconstruction filters against Mitsuba 3's own images (tests/data/camera, listed
//! in its MANIFEST.md; scripts/make_camera_refs.py renders them), crops and offsets that are
//! exact sub-windows of the whole image, filtered images that stay bit-identical for any thread
//! count and any split of the samples, and the scene keys with their errors.

mod common;

use common::mitsuba_refs::{References, mean_luminance};

use caustic::app::LoadedScene;
use caustic::film::Image;
use caustic::film::filter::Filter;
use caustic::integrator::Integrator;
use caustic::options::Options;
use caustic::render::RenderControl;
use caustic::scene::LoadOptions;
use caustic::scene::mitsuba::load_mitsuba_str;
use std::path::PathBuf;
use std::sync::LazyLock;

static REFS: LazyLock<References> = LazyLock::new(|| References::new("camera"));

fn dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/camera")
}

/// The XML text of a case.
fn case_text(case: &str) -> String {
    std::fs::read_to_string(dir().join(format!("{case}.xml"))).unwrap_or_else(|e| panic!("{case}: {e}"))
}

fn load_xml(text: &str, spp: u32, o: &Options) -> LoadedScene {
    let lo = LoadOptions { defines: vec![("spp".into(), spp.to_string())], strict: true, ..Default::default() };
    let desc = load_mitsuba_str(text, "case.xml", &dir(), &lo).unwrap_or_else(|e| panic!("{e}"));
    caustic::app::prepare(desc, o).unwrap_or_else(|e| panic!("{e}"))
}

fn render_xml(text: &str, spp: u32, seed: u64) -> Image {
    load_xml(text, spp, &Options { seed: Some(seed), ..Default::default() }).render().image
}

/// Our path tracer's samples per pixel against the 4096 of the references.
const SPP: u32 = 512;

/// Compares our render of `text` (two seeds, for our noise) with `case`'s reference. Returns the
/// relative mean-luminance difference and the RMSE over what the noise predicts.
fn compare(case: &str, text: &str) -> (f64, f64, String) {
    compare_at(case, text, SPP)
}

fn compare_at(case: &str, text: &str, spp: u32) -> (f64, f64, String) {
    REFS.judge(case, &render_xml(text, spp, 1), &render_xml(text, spp, 2))
}

#[test]
fn sensors_films_and_filters_match_mitsuba() {
    let cases = ["ortho", "gaussian", "mitchell", "lanczos", "tent", "crop", "crop_border", "ppo"];
    let failures: Vec<String> = cases
        .iter()
        .filter_map(|case| {
            let (rel, ratio, line) = compare(case, &case_text(case));
            (rel.abs() >= 0.01 || ratio >= 1.25).then_some(line)
        })
        .collect();
    assert!(failures.is_empty(), "differ from Mitsuba:\n{}", failures.join("\n"));
}

#[test]
fn the_filter_visibly_matters_at_this_resolution() {
    // The default-filter scene rendered with a box filter instead is far outside the noise of
    // the Gaussian reference, and so is the Gaussian image against the box filter's: the test
    // above can tell the filters apart.
    let text = case_text("gaussian");
    assert_eq!(load_xml(&text, 1, &Options::default()).settings.filter.filter, Filter::MITSUBA_DEFAULT);
    let boxed = text.replace("</film>", "    <rfilter type=\"box\"/>\n        </film>");
    assert_eq!(load_xml(&boxed, 1, &Options::default()).settings.filter.filter, Filter::Box);
    // At 4x the samples our noise is small next to the filters' difference (the constant sky is
    // a light sampled by shadow rays, which adds noise the reference's background did not have).
    let (_, ratio, _) = compare_at("gaussian", &boxed, 4 * SPP);
    assert!(ratio > 2.0, "a box filter is within {ratio:.2}x the noise of the Gaussian reference");
}

/// Image pixel (x, y) as bits, for exact comparisons.
fn bits(img: &Image, x: u32, y: u32) -> [u32; 3] {
    img.get(x, y).to_array().map(f32::to_bits)
}

#[test]
fn a_crop_renders_the_same_pixels_as_the_whole_image() {
    // The crop case without its crop window: the whole 160 x 112 film.
    let crop = case_text("crop");
    let whole: String = crop.lines().filter(|l| !l.contains("crop_")).collect::<Vec<_>>().join("\n");
    let (x0, y0, w, h) = (44, 30, 64, 48);
    for (label, filter) in [
        ("box", "<rfilter type=\"box\"/>"),
        ("gaussian", ""),
        ("mitchell", "<rfilter type=\"mitchell\"/>"),
        ("border", "<boolean name=\"sample_border\" value=\"true\"/>"),
    ] {
        let with = |t: &str| t.replace("</film>", &format!("{filter}</film>"));
        let full = render_xml(&with(&whole), 3, 7);
        let part = render_xml(&with(&crop), 3, 7);
        assert_eq!((part.width, part.height), (w, h));
        // Gaussian and Mitchell filters reach 2 pixels.
        let r = if matches!(label, "box" | "border") { 0 } else { 2 };
        let mut edge_differs = false;
        for y in 0..h {
            for x in 0..w {
                let same = bits(&part, x, y) == bits(&full, x + x0, y + y0);
                let interior = x >= r && y >= r && x + r < w && y + r < h;
                // Pixels at least the filter's radius inside the window are sampled as in the
                // whole image; those nearer the edge are normalised over the window (Mitsuba's
                // `sample_border` false), unless samples may cross it.
                assert!(same || !interior, "{label}: crop pixel ({x}, {y}) differs from the whole image's");
                edge_differs |= !same;
            }
        }
        assert_eq!(edge_differs, r > 0, "{label}: edge pixels");
    }
}

/// A native scene: a grey floor plane and two spheres under two point lights (deterministic for
/// the Whitted integrator: no random numbers but the pixel's), `extra` added to [render] and
/// `camera` to [camera].
fn toml_scene(render: &str, camera: &str) -> String {
    format!(
        r#"[render]
width = 40
height = 30
integrator = "whitted"
spp = 4
{render}

[camera]
eye = [0, 1.5, 6]
look_at = [0, 0.5, 0]
{camera}

[materials.white]
type = "diffuse"
color = 0.8

[materials.red]
type = "diffuse"
color = [0.8, 0.2, 0.1]

[[lights]]
type = "point"
position = [3, 5, 4]
intensity = 40

[[lights]]
type = "point"
position = [-4, 3, 2]
intensity = 15

[[objects]]
type = "plane"
point = [0, 0, 0]
normal = [0, 1, 0]
material = "white"

[[objects]]
type = "sphere"
center = [-0.8, 0.7, 0]
radius = 0.7
material = "red"

[[objects]]
type = "box"
min = [0.4, 0, -0.6]
max = [1.4, 1.2, 0.4]
material = "white"
"#
    )
}

fn render_toml(text: &str, o: &Options) -> Image {
    common::scene_with(text, o).render().image
}

#[test]
fn a_principal_point_offset_shifts_the_image_by_whole_pixels() {
    // Offsets of (0.25, -0.1) on a 40 x 30 film shift the view by (10, -3) pixels. Without
    // anti-aliasing each pixel's ray goes through its centre, so pixel (x, y) of the shifted
    // image is pixel (x + 10, y - 3) of the plain one bit for bit (Whitted with point lights
    // draws no random numbers).
    let o = Options { antialias: Some(false), ..Default::default() };
    let plain = render_toml(&toml_scene("", "fov = 40"), &o);
    let shifted = render_toml(&toml_scene("", "fov = 40\nprincipal_point_offset = [0.25, -0.1]"), &o);
    assert!(mean_luminance(&plain) > 0.01);
    for y in 3..30 {
        for x in 0..30 {
            assert_eq!(bits(&shifted, x, y), bits(&plain, x + 10, y - 3), "pixel ({x}, {y})");
        }
    }
}

#[test]
fn crops_and_offsets_combine_into_exact_windows() {
    // A crop of a render with an offset and a Mitchell filter, with samples allowed past the
    // window, is the same window of the whole render, on any thread count.
    let camera = "fov = 40\nprincipal_point_offset = [0.1, 0.05]";
    let filter = "filter = { type = \"mitchell\", B = 0.5, C = 0.25 }\nsample_border = true";
    let whole = render_toml(&toml_scene(filter, camera), &Options::default());
    let crop = format!("{filter}\ncrop = {{ x = 7, y = 5, width = 20, height = 16 }}");
    let part = render_toml(&toml_scene(&crop, camera), &Options::default());
    for y in 0..16 {
        for x in 0..20 {
            assert_eq!(bits(&part, x, y), bits(&whole, x + 7, y + 5), "pixel ({x}, {y})");
        }
    }
    // A smaller image from the command line keeps the crop on the same part of the view.
    let half = common::scene_with(
        &toml_scene(&crop, camera),
        &Options { width: Some(20), height: Some(15), ..Default::default() },
    );
    assert_eq!((half.settings.width, half.settings.height, half.settings.origin), (11, 9, (3, 2)));
}

#[test]
fn filtered_images_are_bit_identical_for_any_thread_count_and_sample_split() {
    let text = toml_scene("filter = \"lanczos\"\ncrop = { x = 3, y = 2, width = 30, height = 25 }", "fov = 40")
        .replace("\"whitted\"", "\"path\"");
    let s = common::scene_with(&text, &Options { spp: Some(6), ..Default::default() });
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| s.render())
    };
    let one = on(1);
    let three = on(3);
    assert!(one.image.pixels == three.image.pixels, "1 and 3 threads differ");
    // Samples 0..2 and 2..6 rendered apart and added are the whole render, exactly.
    let control = RenderControl::uncancelled();
    let part = |first: u32, spp: u32| {
        let mut settings = s.settings.clone();
        settings.first_sample = first;
        settings.spp = spp;
        let integrator = Integrator::new(&s.integrator, &s.scene, &settings, &control).unwrap();
        integrator.render(&s.scene, &settings, &control).film
    };
    let mut film = part(0, 2);
    film.add(&part(2, 6));
    assert!(film.image().pixels == one.image.pixels, "a split of the samples differs");
}

#[test]
fn orthographic_toml_cameras_span_the_view_they_name() {
    let load = |camera: &str| common::scene(&toml_scene("", camera)).scene.camera;
    let w = load("projection = \"orthographic\"\nview_width = 8");
    let h = load("projection = \"orthographic\"\nview_height = 6");
    // 8 units across 40 pixels, or 6 up 30: the same square pixels.
    assert!((w.pixel_size - 0.2).abs() < 1e-7 && (h.pixel_size - 0.2).abs() < 1e-7);
    assert_eq!(w, h);
    let img = render_toml(&toml_scene("", "projection = \"orthographic\"\nview_width = 8"), &Options::default());
    assert!(mean_luminance(&img) > 0.01);
}

#[test]
fn scene_keys_are_checked_with_their_place() {
    let cases: &[(&str, &str, &str)] = &[
        ("filter = \"sinc\"", "", "unknown filter `sinc`"),
        ("filter = { type = \"tent\", stddev = 1 }", "", "no `stddev`"),
        ("filter = { type = \"gaussian\", stddev = -1 }", "", "positive"),
        ("filter = { type = \"mitchell\", B = 7 }", "", "normalised"),
        ("crop = { x = 30, y = 0, width = 20, height = 10 }", "", "inside the 40 x 30 image"),
        ("crop = { width = 0, height = 10 }", "", "non-empty"),
        ("crop = { width = 5, height = 5, z = 1 }", "", "unknown key `z`"),
        ("", "projection = \"fisheye\"", "unknown projection `fisheye`"),
        ("", "projection = \"orthographic\"", "needs one of `view_width` or `view_height`"),
        ("", "projection = \"orthographic\"\nview_width = 2\nfov = 30", "`fov` does not apply"),
        ("", "view_width = 2", "belong to an orthographic camera"),
        ("", "principal_point_offset = [0.1]", "two numbers"),
    ];
    for (render, camera, want) in cases {
        let text = toml_scene(render, camera);
        let e = caustic::app::load_toml_str(&text, "c.toml", std::path::Path::new("."), &Options::default())
            .err()
            .unwrap_or_else(|| panic!("`{render}{camera}` loaded"))
            .to_string();
        assert!(e.contains(want) && e.starts_with("c.toml:"), "`{render}{camera}`: {e}");
    }
}

#[test]
fn mitsuba_films_read_crops_filters_and_refuse_bad_windows() {
    let film = |body: &str| {
        format!(
            r#"<scene version="3.0.0"><sensor type="perspective"><film type="hdrfilm">
            <integer name="width" value="40"/><integer name="height" value="30"/>{body}</film></sensor></scene>"#
        )
    };
    let load = |text: &str| {
        load_mitsuba_str(text, "f.xml", &dir(), &LoadOptions::default())
            .and_then(|d| caustic::app::prepare(d, &Options::default()))
    };
    let s = load(&film(
        r#"<integer name="crop_offset_x" value="10"/><integer name="crop_width" value="20"/>
        <rfilter type="lanczos"><integer name="lobes" value="2"/></rfilter>"#,
    ))
    .unwrap();
    assert_eq!((s.settings.width, s.settings.height, s.settings.origin), (20, 30, (10, 0)));
    assert_eq!(s.settings.filter.filter, Filter::Lanczos { lobes: 2 });
    assert_eq!(
        load(&film(r#"<rfilter type="catmullrom"/>"#)).unwrap().settings.filter.filter,
        Filter::Mitchell { b: 0.0, c: 0.5 }
    );
    // An offset alone leaves a window as wide as the film, which does not fit (as in Mitsuba).
    let e = load(&film(r#"<integer name="crop_offset_x" value="10"/>"#)).err().unwrap().to_string();
    assert!(e.starts_with("f.xml:1:") && e.contains("crop window"), "{e}");
    let e = load(&film(r#"<rfilter type="gaussian"><float name="stddev" value="0"/></rfilter>"#))
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("stddev must be positive"), "{e}");
}
