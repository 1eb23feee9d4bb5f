//! Comparisons with Mitsuba 3 reference images: a folder of `<case>.xml` scenes, their
//! references `<case>.exr` and a MANIFEST.md whose table gives each reference's noise (see
//! scripts/make_material_refs.py). Our image must have the same mean luminance (within 1%) and a
//! per-pixel RMSE against the reference within 1.25x of what the two images' noise predicts.

use caustic::app::LoadedScene;
use caustic::film::Image;
use caustic::film::output::read_exr;
use caustic::math::luminance;
use caustic::options::{IntegratorKind, Options};
use caustic::scene::LoadOptions;
use std::collections::HashMap;
use std::path::PathBuf;

pub struct References {
    pub dir: PathBuf,
    /// Mitsuba's noise per case: the RMS per-pixel standard deviation of its image.
    noise: HashMap<String, f64>,
    /// The samples per pixel of each reference.
    spp: HashMap<String, f64>,
}

impl References {
    /// The references in `tests/data/<folder>`.
    pub fn new(folder: &str) -> Self {
        let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(folder);
        let text = std::fs::read_to_string(dir.join("MANIFEST.md")).expect("MANIFEST.md");
        // The reference table's header names its columns; tables further down (results) lack
        // the `noise` column and are skipped.
        let mut noise = HashMap::new();
        let mut spp = HashMap::new();
        let mut column = None;
        let mut spp_column = None;
        for line in text.lines().filter(|l| l.starts_with('|')) {
            let cells: Vec<&str> = line.split('|').map(str::trim).collect();
            if cells.get(1) == Some(&"case") {
                column = cells.iter().position(|c| *c == "noise");
                spp_column = cells.iter().position(|c| *c == "spp");
                continue;
            }
            if let (Some(k), true) = (spp_column, line.starts_with("| `"))
                && let Some(v) = cells.get(k).and_then(|c| c.parse::<f64>().ok())
            {
                spp.insert(cells[1].trim_matches('`').to_string(), v);
            }
            if let (Some(k), true) = (column, line.starts_with("| `"))
                && let Some(v) = cells.get(k).and_then(|c| c.parse::<f64>().ok())
            {
                noise.insert(cells[1].trim_matches('`').to_string(), v);
            }
        }
        References { dir, noise, spp }
    }

    /// Mitsuba's noise for `case` had it been rendered at `spp` samples per pixel (noise falls
    /// as one over the square root of the sample count).
    pub fn noise_at(&self, case: &str, spp: u32) -> f64 {
        self.noise[case] * (self.spp[case] / spp as f64).sqrt()
    }

    pub fn load(&self, case: &str, res: u32, spp: u32, o: &Options) -> LoadedScene {
        let defines = vec![("res".to_string(), res.to_string()), ("spp".to_string(), spp.to_string())];
        let path = self.dir.join(format!("{case}.xml"));
        caustic::app::load(&path, &LoadOptions { defines, strict: true, ..Default::default() }, o)
            .unwrap_or_else(|e| panic!("{case} failed to load: {e}"))
    }

    pub fn render(&self, case: &str, res: u32, spp: u32, seed: u64, integrator: Option<IntegratorKind>) -> Image {
        let o = Options { seed: Some(seed), integrator, ..Default::default() };
        self.load(case, res, spp, &o).render().image
    }

    pub fn reference(&self, case: &str) -> Image {
        read_exr(&self.dir.join(format!("{case}.exr"))).unwrap_or_else(|e| panic!("{case}: reference: {e}"))
    }

    /// Renders `case` with the path tracer (two seeds, for our noise) and compares it with
    /// Mitsuba's image; returns a description of the failure, if any.
    pub fn compare(&self, case: &str, res: u32, spp: u32) -> Option<String> {
        let (a, b) = (self.render(case, res, spp, 1, None), self.render(case, res, spp, 2, None));
        let (rel, ratio, line) = self.judge(case, &a, &b);
        (rel.abs() >= 0.01 || ratio >= 1.25).then_some(line)
    }

    /// Our two renders `a` and `b` of `case` (different seeds) against Mitsuba's image: the
    /// relative difference of mean luminance, the RMSE of `a` over what the noise of both
    /// images predicts, and a line describing both (printed).
    pub fn judge(&self, case: &str, a: &Image, b: &Image) -> (f64, f64, String) {
        let reference = self.reference(case);
        let noise = rmse(a, b) / 2f64.sqrt();
        let ref_noise = self.noise[case];
        let expected = (noise * noise + ref_noise * ref_noise).sqrt();
        let (ours, theirs) = ((mean_luminance(a) + mean_luminance(b)) / 2.0, mean_luminance(&reference));
        let rel = ours / theirs - 1.0;
        let err = rmse(a, &reference);
        let line = format!(
            "{case:38} mean {ours:.5} vs {theirs:.5} ({:+.2}%), rmse {err:.5} vs {expected:.5} from noise ({:.2}x)",
            rel * 100.0,
            err / expected
        );
        eprintln!("{line}");
        (rel, err / expected, line)
    }

    /// `compare` for each (case, spp); panics listing every case that fails.
    pub fn check_all(&self, cases: &[(&str, u32)], res: u32) {
        let failures: Vec<String> = cases.iter().filter_map(|&(case, spp)| self.compare(case, res, spp)).collect();
        assert!(failures.is_empty(), "differ from Mitsuba:\n{}", failures.join("\n"));
    }

    /// Mean luminance of `case` rendered by `kind` against Mitsuba's, within `tolerance`
    /// (relative); returns the failure, if any.
    pub fn compare_mean(&self, case: &str, res: u32, spp: u32, kind: IntegratorKind, tolerance: f64) -> Option<String> {
        let theirs = mean_luminance(&self.reference(case));
        let ours = mean_luminance(&self.render(case, res, spp, 1, Some(kind)));
        let rel = ours / theirs - 1.0;
        let line = format!("{case:30} {kind:?}: {ours:.5} vs Mitsuba {theirs:.5} ({:+.2}%)", rel * 100.0);
        eprintln!("{line}");
        (rel.abs() >= tolerance).then_some(line)
    }
}

pub fn mean_luminance(img: &Image) -> f64 {
    img.pixels.iter().map(|&c| luminance(c) as f64).sum::<f64>() / img.pixels.len() as f64
}

pub fn rmse(a: &Image, b: &Image) -> f64 {
    assert_eq!((a.width, a.height), (b.width, b.height));
    let s: f64 = a.pixels.iter().zip(&b.pixels).map(|(&x, &y)| ((x - y) * (x - y)).sum() as f64 / 3.0).sum();
    (s / a.pixels.len() as f64).sqrt()
}
