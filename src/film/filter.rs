//! Pixel reconstruction filters as Mitsuba 3 defines them (`src/rfilters/*.cpp`; box, tent,
//! gaussian, mitchell, catmullrom, lanczos), applied by filter importance sampling.
//!
//! A filter is separable: a pixel's value is the integral of the radiance weighted by
//! f(x - c_x) f(y - c_y) around its centre c, divided by the weights' integral. Mitsuba splats
//! each sample into every pixel within the radius; we instead draw each sample's film position
//! around its own pixel's centre with density proportional to |f| and add it to that pixel only,
//! weighted by the sign of the lobe it fell in times the normalisation ∫|f| / ∫f (1 for filters
//! without negative lobes). The expected pixel value is the same, and since a sample still lands
//! in exactly one pixel with a value fixed by (seed, pixel, index), the film's exact sums keep
//! images bit-identical for any thread count, pass split, resume or render-farm shard.
//!
//! Mitsuba's CPU (scalar) variants evaluate a filter through a table of 32 values,
//! f(i r / 31) for i = 0..31, looked up at ⌊|x| 31 / r⌋ (`MI_FILTER_RESOLUTION`); we use the
//! same step function, so our images agree with theirs in expectation, and a step function is
//! sampled exactly by inverting its piecewise-linear CDF (no allocation; a branch-free search of 64
//! edges). The smooth functions differ from the steps by at most about 1% of an edge's
//! contrast after filtering (Gaussian, radius 2).
//!
//! Mitsuba takes samples only inside the rendered window (the crop, unless `sample_border`), so a
//! pixel near its edge is normalised by the part of the filter inside; we draw from |f| truncated
//! to that part and normalise by it likewise.

use crate::math::Vec2;

/// Mitsuba's filter table resolution: steps of radius / 31.
pub const STEPS: usize = 31;
/// Bins of the table over [-r, r].
const BINS: usize = 2 * STEPS;
/// Largest filter radius accepted, in pixels.
pub const MAX_RADIUS: f32 = 64.0;

/// A reconstruction filter and its parameters (Mitsuba's names and defaults).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum Filter {
    /// Each sample counts in its own pixel only: the pixel's plain average.
    #[default]
    Box,
    /// max(0, 1 - |x| / radius); Mitsuba's default radius is 1.
    Tent { radius: f32 },
    /// exp(-x² / 2σ²) minus its value at the radius 4σ; Mitsuba's default (σ = 0.5).
    Gaussian { stddev: f32 },
    /// Mitchell and Netravali's cubic (radius 2); Mitsuba's defaults B = C = 1/3. Catmull-Rom is
    /// B = 0, C = 1/2.
    Mitchell { b: f32, c: f32 },
    /// sinc(x) sinc(x / lobes), radius `lobes`; Mitsuba's default 3 lobes.
    Lanczos { lobes: u32 },
}

impl Filter {
    /// What Mitsuba's `hdrfilm` uses when a scene names no filter.
    pub const MITSUBA_DEFAULT: Filter = Filter::Gaussian { stddev: 0.5 };

    /// The half-width of the filter's support, in pixels.
    pub fn radius(&self) -> f64 {
        match *self {
            Filter::Box => 0.5,
            Filter::Tent { radius } => radius as f64,
            Filter::Gaussian { stddev } => 4.0 * stddev as f64,
            Filter::Mitchell { .. } => 2.0,
            Filter::Lanczos { lobes } => lobes as f64,
        }
    }

    pub fn name(&self) -> &'static str {
        match self {
            Filter::Box => "box",
            Filter::Tent { .. } => "tent",
            Filter::Gaussian { .. } => "gaussian",
            Filter::Mitchell { .. } => "mitchell",
            Filter::Lanczos { .. } => "lanczos",
        }
    }

    /// The filter's function at offset `x` (in pixels) from the pixel centre, as Mitsuba's
    /// `eval` defines it (Mitsuba 3.9.1 approximates the Gaussian's exponential by a polynomial
    /// that agrees within 1e-3).
    pub fn eval(&self, x: f64) -> f64 {
        let a = x.abs();
        match *self {
            Filter::Box => {
                if (-0.5..0.5).contains(&x) {
                    1.0
                } else {
                    0.0
                }
            }
            Filter::Tent { radius } => (1.0 - a / radius as f64).max(0.0),
            Filter::Gaussian { stddev } => {
                let alpha = -1.0 / (2.0 * (stddev as f64).powi(2));
                let r = 4.0 * stddev as f64;
                ((alpha * x * x).exp() - (alpha * r * r).exp()).max(0.0)
            }
            Filter::Mitchell { b, c } => {
                let (b, c) = (b as f64, c as f64);
                let v = if a < 1.0 {
                    (12.0 - 9.0 * b - 6.0 * c) * a * a * a + (-18.0 + 12.0 * b + 6.0 * c) * a * a + (6.0 - 2.0 * b)
                } else if a < 2.0 {
                    (-b - 6.0 * c) * a * a * a
                        + (6.0 * b + 30.0 * c) * a * a
                        + (-12.0 * b - 48.0 * c) * a
                        + (8.0 * b + 24.0 * c)
                } else {
                    0.0
                };
                v / 6.0
            }
            Filter::Lanczos { lobes } => {
                let l = lobes as f64;
                if a >= l {
                    0.0
                } else if a < 1e-4 {
                    1.0
                } else {
                    let px = std::f64::consts::PI * x;
                    let pxl = px / l;
                    (px.sin() * pxl.sin()) / (px * pxl)
                }
            }
        }
    }

    /// The filter called `name` with Mitsuba's default parameters (`catmullrom` is Mitchell's
    /// cubic with B = 0, C = 1/2).
    pub fn named(name: &str) -> Option<Filter> {
        Some(match name {
            "box" => Filter::Box,
            "tent" => Filter::Tent { radius: 1.0 },
            "gaussian" => Filter::Gaussian { stddev: 0.5 },
            "mitchell" => Filter::Mitchell { b: 1.0 / 3.0, c: 1.0 / 3.0 },
            "catmullrom" => Filter::Mitchell { b: 0.0, c: 0.5 },
            "lanczos" => Filter::Lanczos { lobes: 3 },
            _ => return None,
        })
    }

    /// The names `named` knows.
    pub const NAMES: [&'static str; 6] = ["box", "tent", "gaussian", "mitchell", "catmullrom", "lanczos"];

    /// A filter as the command line gives it: a name, optionally with parameters after a colon
    /// (`gaussian`, `gaussian:stddev=0.3`, `mitchell:B=0.5,C=0.25`, `lanczos:lobes=2`), each the
    /// scene format's key of that filter. Checked as a scene's filter is.
    pub fn parse(text: &str) -> Result<Filter, String> {
        let (name, params) = text.split_once(':').unwrap_or((text, ""));
        let mut f = Filter::named(name.trim())
            .ok_or_else(|| format!("unknown filter `{name}`; expected one of: {}", Filter::NAMES.join(", ")))?;
        for param in params.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let (key, value) =
                param.split_once('=').ok_or_else(|| format!("expected KEY=VALUE after `{name}:`, found `{param}`"))?;
            let number = |v: &str| v.trim().parse::<f32>().ok().filter(|x| x.is_finite());
            let bad = || format!("expected a number for `{key}`, found `{value}`");
            match (&mut f, key.trim()) {
                (Filter::Tent { radius }, "radius") => *radius = number(value).ok_or_else(bad)?,
                (Filter::Gaussian { stddev }, "stddev") => *stddev = number(value).ok_or_else(bad)?,
                (Filter::Mitchell { b, .. }, "B" | "b") if name != "catmullrom" => {
                    *b = number(value).ok_or_else(bad)?
                }
                (Filter::Mitchell { c, .. }, "C" | "c") if name != "catmullrom" => {
                    *c = number(value).ok_or_else(bad)?
                }
                (Filter::Lanczos { lobes }, "lobes") => {
                    *lobes = value
                        .trim()
                        .parse()
                        .map_err(|_| format!("expected a whole number for `lobes`, found `{value}`"))?
                }
                (_, key) => {
                    let takes = match name {
                        "tent" => "radius",
                        "gaussian" => "stddev",
                        "mitchell" => "B, C",
                        "lanczos" => "lobes",
                        _ => "no parameters",
                    };
                    return Err(format!("a {name} filter has no `{key}` (it takes {takes})"));
                }
            }
        }
        f.check()?;
        Ok(f)
    }

    /// The filter as `parse` reads it back (for a farm shard's arguments and the render's
    /// identity).
    pub fn spelled(&self) -> String {
        match *self {
            Filter::Box => "box".into(),
            Filter::Tent { radius } => format!("tent:radius={radius:?}"),
            Filter::Gaussian { stddev } => format!("gaussian:stddev={stddev:?}"),
            Filter::Mitchell { b, c } => format!("mitchell:B={b:?},C={c:?}"),
            Filter::Lanczos { lobes } => format!("lanczos:lobes={lobes}"),
        }
    }

    /// Checks the parameters: a positive radius up to [`MAX_RADIUS`], and a filter
    /// whose weights over the smallest window a pixel can be normalised by (its own pixel, up to
    /// the radius on either side) integrate to a clearly positive number.
    pub fn check(&self) -> Result<(), String> {
        match *self {
            Filter::Box => return Ok(()),
            Filter::Tent { radius } if !(radius > 0.0) => {
                return Err(format!("tent filter radius must be positive, found {radius}"));
            }
            Filter::Gaussian { stddev } if !(stddev > 0.0) => {
                return Err(format!("gaussian filter stddev must be positive, found {stddev}"));
            }
            Filter::Mitchell { b, c } if !(b.is_finite() && c.is_finite()) => {
                return Err(format!("mitchell filter B and C must be finite numbers, found {b} and {c}"));
            }
            Filter::Lanczos { lobes: 0 } => {
                return Err("lanczos filter lobes must be at least 1".into());
            }
            _ => {}
        }
        let r = self.radius();
        if !(r <= MAX_RADIUS as f64) {
            return Err(format!("{} filter radius {r} is larger than the {MAX_RADIUS} pixels accepted", self.name()));
        }
        let t = FilterTable::new(*self);
        let low = t.smallest_window_integral();
        if !(low > 1e-3 * t.cdf_abs[BINS]) {
            return Err(format!(
                "{} filter weights integrate to {low:.4} (not clearly positive) over a pixel's \
                 window at an image edge: the pixel cannot be normalised",
                self.name()
            ));
        }
        Ok(())
    }
}

/// The window samples are taken in, in full-film pixel coordinates: the crop (or the whole
/// film), or unbounded with `sample_border`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Window {
    pub x0: f64,
    pub y0: f64,
    pub x1: f64,
    pub y1: f64,
}

impl Window {
    pub const UNBOUNDED: Window =
        Window { x0: f64::NEG_INFINITY, y0: f64::NEG_INFINITY, x1: f64::INFINITY, y1: f64::INFINITY };
}

/// A filter ready for importance sampling: Mitsuba's step table over [-r, r] in 62 bins and the
/// cumulative integrals of |f| and f at the bin edges. Plain arrays, so it is `Copy`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilterTable {
    pub filter: Filter,
    radius: f64,
    /// Width of one bin: radius / 31.
    step: f64,
    /// The filter's value in each bin, left to right.
    value: [f64; BINS],
    /// ∫|f| and ∫f from -r to each bin edge.
    cdf_abs: [f64; BINS + 1],
    cdf: [f64; BINS + 1],
    /// 1 / |value| per bin (0 for a bin of zero mass): sampling multiplies.
    inv_value: [f64; BINS],
    /// `cdf_abs` padded to 64 entries with +∞, for a branch-free binary search.
    edges: [f64; 64],
    /// Whether any bin is negative (otherwise every weight is 1).
    negative: bool,
    /// ∫|f| / ∫f over the whole support.
    full_weight: f64,
}

impl FilterTable {
    pub fn new(filter: Filter) -> Self {
        let radius = filter.radius();
        let step = radius / STEPS as f64;
        // Mitsuba's table: value i holds f(i r / 31) for |x| in [i r / 31, (i + 1) r / 31).
        let steps: [f64; STEPS] = std::array::from_fn(|i| filter.eval(i as f64 * step));
        let value: [f64; BINS] =
            std::array::from_fn(|j| if j < STEPS { steps[STEPS - 1 - j] } else { steps[j - STEPS] });
        let mut cdf_abs = [0.0; BINS + 1];
        let mut cdf = [0.0; BINS + 1];
        for j in 0..BINS {
            cdf_abs[j + 1] = cdf_abs[j] + value[j].abs() * step;
            cdf[j + 1] = cdf[j] + value[j] * step;
        }
        let negative = value.iter().any(|v| *v < 0.0);
        let full_weight = if negative { cdf_abs[BINS] / cdf[BINS] } else { 1.0 };
        let edges = std::array::from_fn(|m| if m <= BINS { cdf_abs[m] } else { f64::INFINITY });
        let inv_value = value.map(|v| if v == 0.0 { 0.0 } else { 1.0 / v.abs() });
        FilterTable { filter, radius, step, value, cdf_abs, cdf, inv_value, edges, negative, full_weight }
    }

    /// Half-width of the support, in pixels.
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// The weight a contribution landing at offset (`dx`, `dy`) from a pixel's centre has in
    /// that pixel when contributions are splatted (light tracing): the filter normalised to
    /// integrate to 1, as the pixel's camera samples are weighted by sampling it. The box filter
    /// gives 1 inside the pixel.
    #[inline]
    pub fn splat_weight(&self, dx: f64, dy: f64) -> f64 {
        let total = self.cdf[BINS];
        self.eval(dx) * self.eval(dy) / (total * total)
    }

    /// The filter's value as sampled (Mitsuba's step function) at offset `x` from the centre.
    pub fn eval(&self, x: f64) -> f64 {
        self.bin(x).map_or(0.0, |j| self.value[j])
    }

    /// The bin holding offset `x`, if inside the support.
    fn bin(&self, x: f64) -> Option<usize> {
        let t = (x + self.radius) / self.step;
        (t >= 0.0 && t < BINS as f64).then_some(t as usize)
    }

    /// ∫f (with `abs`: ∫|f|) from -r to `x`, for x in [-r, r].
    fn cumulative(&self, x: f64, abs: bool) -> f64 {
        let x = x.clamp(-self.radius, self.radius);
        let j = (((x + self.radius) / self.step) as usize).min(BINS - 1);
        let left = -self.radius + j as f64 * self.step;
        let (c, v) = if abs { (self.cdf_abs[j], self.value[j].abs()) } else { (self.cdf[j], self.value[j]) };
        c + v * (x - left).max(0.0)
    }

    /// ∫f over [lo, hi] (offsets from the centre, clamped to the support).
    pub fn integral(&self, lo: f64, hi: f64) -> f64 {
        self.cumulative(hi, false) - self.cumulative(lo, false)
    }

    /// ∫|f| over [lo, hi].
    pub fn abs_integral(&self, lo: f64, hi: f64) -> f64 {
        self.cumulative(hi, true) - self.cumulative(lo, true)
    }

    /// The smallest ∫f over the windows a pixel can be normalised by: from its own half-pixel
    /// [-1/2, 1/2] out to anywhere up to the radius on either side.
    fn smallest_window_integral(&self) -> f64 {
        let (r, h) = (self.radius, self.radius.min(0.5));
        let edges = |from: f64, to: f64| {
            (0..=BINS).map(move |j| -r + j as f64 * self.step).filter(move |x| *x >= from && *x <= to)
        };
        let min_right = edges(h, r).chain([h]).map(|x| self.cumulative(x, false)).fold(f64::INFINITY, f64::min);
        let max_left = edges(-r, -h).chain([-h]).map(|x| self.cumulative(x, false)).fold(f64::NEG_INFINITY, f64::max);
        min_right - max_left
    }

    /// An offset from the pixel centre in [lo, hi] (within [-r, r]) drawn with density
    /// proportional to |f| from the uniform `u`, with the sign of f there. The full support
    /// maps `u` through the CDF alone, so a pixel far from the window's edge gets the same
    /// offset whatever the window.
    #[inline]
    pub fn sample_1d(&self, u: f32, lo: f64, hi: f64) -> (f64, f64) {
        let (lo, hi) = (lo.max(-self.radius), hi.min(self.radius));
        let full = lo <= -self.radius && hi >= self.radius;
        let target = if full {
            u as f64 * self.cdf_abs[BINS]
        } else {
            let a = self.cumulative(lo, true);
            a + u as f64 * (self.cumulative(hi, true) - a)
        };
        // The last bin with cdf[j] <= target (so target < cdf[j + 1]; bins of zero mass are
        // never chosen): six halvings over the 64 padded edges, each a conditional move rather
        // than a branch (a branchy search cost a few percent of a simple path-traced render).
        let mut j = 0;
        for half in [32, 16, 8, 4, 2, 1] {
            j = if self.edges[j + half] <= target { j + half } else { j };
        }
        let mut j = j.min(BINS - 1);
        while self.value[j] == 0.0 && j > 0 {
            j -= 1;
        }
        let left = -self.radius + j as f64 * self.step;
        let x = left + (target - self.cdf_abs[j]) * self.inv_value[j];
        // Rounding may put x a hair outside its bin or the window; the window wins.
        let x = x.clamp(left, left + self.step).max(lo).min(hi);
        (x, if self.value[j] < 0.0 { -1.0 } else { 1.0 })
    }

    /// ∫|f| / ∫f over [lo, hi]: the weight magnitude of a sample drawn there.
    #[inline]
    fn norm(&self, lo: f64, hi: f64) -> f64 {
        if lo <= -self.radius && hi >= self.radius {
            self.full_weight
        } else {
            self.abs_integral(lo, hi) / self.integral(lo, hi)
        }
    }

    /// The film position of pixel sample `u` of pixel (x, y) (full-film coordinates), relative
    /// to the pixel's corner, and the sample's weight; samples stay inside `window`. The box
    /// filter keeps `u` itself (the pixel's plain average, bit for bit as without a filter).
    #[inline]
    pub fn sample(&self, u: Vec2, x: u32, y: u32, window: &Window) -> (Vec2, f32) {
        if self.filter == Filter::Box {
            return (u, 1.0);
        }
        let (cx, cy) = (x as f64 + 0.5, y as f64 + 0.5);
        let (lx, hx) = (window.x0 - cx, window.x1 - cx);
        let (ly, hy) = (window.y0 - cy, window.y1 - cy);
        let (dx, sx) = self.sample_1d(u.x, lx, hx);
        let (dy, sy) = self.sample_1d(u.y, ly, hy);
        let offset = Vec2::new((0.5 + dx) as f32, (0.5 + dy) as f32);
        if !self.negative {
            return (offset, 1.0);
        }
        let w = sx
            * sy
            * self.norm(lx.max(-self.radius), hx.min(self.radius))
            * self.norm(ly.max(-self.radius), hy.min(self.radius));
        (offset, w as f32)
    }
}

#[cfg(test)]
mod tests;
