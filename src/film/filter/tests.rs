//! Filters against Mitsuba's values, their normalisation, and the sampler against its density
//! (chi-square), whole and truncated at a window's edge.

use super::*;
use crate::sampling::Rng32;
use crate::sampling::chi2::chi2_p_value;

const ALL: [Filter; 8] = [
    Filter::Box,
    Filter::Tent { radius: 1.0 },
    Filter::Tent { radius: 1.7 },
    Filter::Gaussian { stddev: 0.5 },
    Filter::Gaussian { stddev: 0.3 },
    Filter::Mitchell { b: 1.0 / 3.0, c: 1.0 / 3.0 },
    Filter::Mitchell { b: 0.0, c: 0.5 },
    Filter::Lanczos { lobes: 3 },
];

#[test]
fn functions_and_tables_match_mitsubas_values() {
    // mitsuba-conventions sec. 5.6-5.7, printed by Mitsuba 3.9.1.
    let tent = FilterTable::new(Filter::Tent { radius: 1.0 });
    for (x, w) in [(0.2, 25.0), (0.4, 19.0), (0.5, 16.0), (0.6, 13.0), (0.8, 7.0)] {
        assert!((tent.eval(x) - w / 31.0).abs() < 1e-12 && (tent.eval(-x) - w / 31.0).abs() < 1e-12, "tent {x}");
    }
    let g = Filter::Gaussian { stddev: 0.5 };
    assert_eq!(g.radius(), 2.0);
    for (x, v) in
        [(0.0, 0.999247), (0.25, 0.882167), (0.5, 0.606423), (0.75, 0.324243), (1.0, 0.134960), (1.5, 0.010758)]
    {
        // Mitsuba 3.9.1 evaluates a polynomial fit of the exponential.
        assert!((g.eval(x) - v).abs() < 1e-3, "gaussian {x}: {} vs {v}", g.eval(x));
    }
    assert_eq!(g.eval(2.0), 0.0);
    let m = Filter::Mitchell { b: 1.0 / 3.0, c: 1.0 / 3.0 };
    for (x, v) in [(0.0, 0.888889), (1.0, 0.055556), (1.5, -0.034722), (2.0, 0.0)] {
        assert!((m.eval(x) - v).abs() < 1e-6, "mitchell {x}: {}", m.eval(x));
    }
    let l = Filter::Lanczos { lobes: 3 };
    for (x, v) in [(0.0, 1.0), (0.5, 0.607927), (1.5, -0.135095), (3.0, 0.0)] {
        assert!((l.eval(x) - v).abs() < 1e-6, "lanczos {x}: {}", l.eval(x));
    }
    // The table holds f(i r / 31) over [i r / 31, (i + 1) r / 31), symmetric about 0.
    for f in ALL {
        let t = FilterTable::new(f);
        let r = f.radius();
        for i in 0..STEPS {
            let x = (i as f64 + 0.5) * r / STEPS as f64;
            assert!((t.eval(x) - f.eval(i as f64 * r / STEPS as f64)).abs() < 1e-12, "{f:?} step {i}");
            assert_eq!(t.eval(-x), t.eval(x));
        }
        assert_eq!(t.eval(r * 1.001), 0.0);
    }
}

/// The mean sample weight of pixel (x, y) over 1024 x 1024 jittered strata of the pixel sample
/// (unbiased; only the few strata that straddle a change of sign add noise, about 1e-4), checking
/// that every sample stays inside the window and the support.
fn mean_weight(t: &FilterTable, x: u32, y: u32, window: &Window) -> f64 {
    let (m, r) = (1024, t.filter.radius() as f32);
    let mut rng = Rng32::new(9);
    let mut sum = 0.0f64;
    for i in 0..m {
        for j in 0..m {
            let u = (Vec2::new(i as f32, j as f32) + rng.uniform2()) / m as f32;
            let (offset, w) = t.sample(u, x, y, window);
            let p = Vec2::new(x as f32, y as f32) + offset;
            let inside = p.x >= window.x0 as f32
                && p.x <= window.x1 as f32
                && p.y >= window.y0 as f32
                && p.y <= window.y1 as f32;
            let d = (offset - Vec2::splat(0.5)).abs();
            assert!(inside && d.x <= r && d.y <= r, "{:?}: sample at {p}", t.filter);
            sum += w as f64;
        }
    }
    sum / (m * m) as f64
}

#[test]
fn weights_integrate_to_one() {
    for f in ALL {
        let t = FilterTable::new(f);
        let r = f.radius();
        // The normalised 2-D filter f(x) f(y) / (∫f)^2, integrated by the midpoint rule on a grid
        // much finer than the table's steps.
        let n = 31 * 2 * 16;
        let h = 2.0 * r / n as f64;
        let one_d: f64 = (0..n).map(|i| t.eval(-r + (i as f64 + 0.5) * h) * h).sum();
        let total = one_d * one_d / (t.integral(-r, r) * t.integral(-r, r));
        assert!((total - 1.0).abs() < 1e-9, "{f:?}: {total}");
        // The steps hold each bin's inner end value, so the table's integral exceeds the smooth
        // function's by about one step times (f(0) - f(r)) (the two sides' telescoping sums), and
        // otherwise agrees with it.
        let smooth: f64 = (0..n).map(|i| f.eval(-r + (i as f64 + 0.5) * h) * h).sum();
        let step = r / STEPS as f64;
        let excess = if f == Filter::Box { 0.0 } else { step * (f.eval(0.0) - f.eval(r)) };
        assert!((one_d - smooth - excess).abs() < 0.01 * one_d, "{f:?}: smooth {smooth}, table {one_d}");
        // The sampler's weights have mean 1 (the estimator of a constant image is exact in
        // expectation): ∫ sign(f) W |f| / ∫|f| = ∫f / ∫f.
        let mean = mean_weight(&t, 10, 10, &Window::UNBOUNDED);
        assert!((mean - 1.0).abs() < 1e-3, "{f:?}: mean weight {mean}");
    }
}

#[test]
fn weights_near_a_window_edge_are_normalised_by_the_part_inside() {
    // A pixel whose centre is 0.5 from the window's left edge: samples only inside, and the
    // mean weight is still 1.
    let window = Window { x0: 0.0, y0: 0.0, x1: 100.0, y1: 100.0 };
    for f in ALL {
        let mean = mean_weight(&FilterTable::new(f), 0, 1, &window);
        assert!((mean - 1.0).abs() < 1e-3, "{f:?}: mean weight {mean}");
    }
}

#[test]
fn box_keeps_the_pixel_sample_and_far_pixels_ignore_the_window() {
    let b = FilterTable::new(Filter::Box);
    let mut rng = Rng32::new(1);
    let window = Window { x0: 3.0, y0: 4.0, x1: 9.0, y1: 10.0 };
    for _ in 0..100 {
        let u = rng.uniform2();
        assert_eq!(b.sample(u, 3, 4, &window), (u, 1.0));
    }
    // A pixel at least the radius from every edge samples as if there were no window: a crop
    // gives the full image's pixels bit for bit.
    let g = FilterTable::new(Filter::MITSUBA_DEFAULT);
    let window = Window { x0: 10.0, y0: 10.0, x1: 30.0, y1: 30.0 };
    for _ in 0..1000 {
        let u = rng.uniform2();
        assert_eq!(g.sample(u, 15, 27, &window), g.sample(u, 15, 27, &Window::UNBOUNDED));
    }
}

/// Chi-square of `n` samples of the 2-D sampler for pixel (x, y) in `window` against the
/// product of the truncated |f| densities, on a `cells` x `cells` grid over the support.
fn chi2(f: Filter, x: u32, y: u32, window: &Window, n: usize, cells: usize) -> f64 {
    let t = FilterTable::new(f);
    let r = f.radius();
    let (cx, cy) = (x as f64 + 0.5, y as f64 + 0.5);
    let (lx, hx) = ((window.x0 - cx).max(-r), (window.x1 - cx).min(r));
    let (ly, hy) = ((window.y0 - cy).max(-r), (window.y1 - cy).min(r));
    let h = 2.0 * r / cells as f64;
    let cell = |i: usize| (-r + i as f64 * h, -r + (i + 1) as f64 * h);
    let mut observed = vec![0u64; cells * cells];
    let mut rng = Rng32::new(17);
    for _ in 0..n {
        let (offset, _) = t.sample(rng.uniform2(), x, y, window);
        let dx = offset.x as f64 - 0.5;
        let dy = offset.y as f64 - 0.5;
        assert!(dx >= lx - 1e-6 && dx <= hx + 1e-6 && dy >= ly - 1e-6 && dy <= hy + 1e-6, "{f:?}: ({dx}, {dy})");
        let i = (((dx + r) / h) as usize).min(cells - 1);
        let j = (((dy + r) / h) as usize).min(cells - 1);
        observed[j * cells + i] += 1;
    }
    let (ax, ay) = (t.abs_integral(lx, hx), t.abs_integral(ly, hy));
    let mass = |(a, b): (f64, f64), lo: f64, hi: f64| t.abs_integral(a.max(lo), b.min(hi)).max(0.0);
    let (mut stat, mut dof) = (0.0, 0usize);
    let (mut pool_o, mut pool_e) = (0.0, 0.0);
    for j in 0..cells {
        for i in 0..cells {
            let e = n as f64 * mass(cell(i), lx, hx) / ax * mass(cell(j), ly, hy) / ay;
            let o = observed[j * cells + i] as f64;
            if e == 0.0 {
                assert_eq!(o, 0.0, "{f:?}: samples where the density is 0 (cell {i}, {j})");
            } else if e < 5.0 {
                pool_o += o;
                pool_e += e;
            } else {
                stat += (o - e) * (o - e) / e;
                dof += 1;
            }
        }
    }
    if pool_e > 0.0 {
        stat += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        dof += 1;
    }
    chi2_p_value(stat, dof - 1)
}

#[test]
fn sampling_matches_the_absolute_filter_density() {
    // Eight filters, each whole and cut by a window's corner: 16 tests, Sidak-corrected 1%.
    let alpha = 1.0 - 0.99f64.powf(1.0 / 16.0);
    let cut = Window { x0: 0.0, y0: 0.0, x1: 50.0, y1: 50.0 };
    for f in ALL {
        for (x, y, window) in [(20, 20, Window::UNBOUNDED), (0, 1, cut)] {
            let p = chi2(f, x, y, &window, 400_000, 41);
            assert!(p > alpha, "{f:?} at ({x}, {y}): chi-square p-value {p:.2e}");
        }
    }
}

#[test]
fn bad_parameters_are_refused() {
    for f in ALL {
        assert!(f.check().is_ok(), "{f:?}");
    }
    assert!(Filter::Tent { radius: 0.0 }.check().is_err());
    assert!(Filter::Tent { radius: f32::NAN }.check().is_err());
    assert!(Filter::Gaussian { stddev: -1.0 }.check().is_err());
    assert!(Filter::Gaussian { stddev: 100.0 }.check().unwrap_err().contains("larger"));
    assert!(Filter::Lanczos { lobes: 0 }.check().is_err());
    assert!(Filter::Mitchell { b: f32::INFINITY, c: 0.0 }.check().is_err());
    // B = 6 makes the centre negative: a pixel at an edge cannot be normalised.
    assert!(Filter::Mitchell { b: 6.0, c: 0.0 }.check().unwrap_err().contains("normalised"));
}

#[test]
fn the_branch_free_search_finds_the_bin_partition_point_finds() {
    let mut rng = Rng32::new(3);
    for f in ALL.into_iter().skip(1) {
        let t = FilterTable::new(f);
        let r = f.radius();
        for _ in 0..20_000 {
            let u = rng.uniform();
            let (lo, hi) = if rng.uniform() < 0.5 { (-r, r) } else { (-r * rng.uniform() as f64 - 0.5, r) };
            let (x, _) = t.sample_1d(u, lo, hi);
            // The reference: the same target, its bin by binary search.
            let a = t.cumulative(lo.max(-r), true);
            let target = if lo <= -r { u as f64 * t.cdf_abs[BINS] } else { a + u as f64 * (t.cdf_abs[BINS] - a) };
            let j = t.cdf_abs.partition_point(|c| *c <= target).clamp(1, BINS) - 1;
            let left = -r + j as f64 * t.step;
            assert!(x >= left - 1e-12 && x <= left + t.step + 1e-12, "{f:?}: u {u} gave {x}, bin {j}");
        }
    }
}

/// Issue 30, item 7: the command line's `--filter` names the scene format's filters and
/// parameters, and spells them back as it reads them (a farm shard's arguments).
#[test]
fn command_line_filters_read_back_as_written() {
    assert_eq!(Filter::parse("gaussian"), Ok(Filter::Gaussian { stddev: 0.5 }));
    assert_eq!(Filter::parse("catmullrom"), Ok(Filter::Mitchell { b: 0.0, c: 0.5 }));
    assert_eq!(Filter::parse("mitchell:B=0.5,C=0.25"), Ok(Filter::Mitchell { b: 0.5, c: 0.25 }));
    assert_eq!(Filter::parse("tent:radius=1.5"), Ok(Filter::Tent { radius: 1.5 }));
    for f in ALL {
        assert_eq!(Filter::parse(&f.spelled()), Ok(f), "{}", f.spelled());
    }
    let e = Filter::parse("gauss").unwrap_err();
    assert!(e.contains("unknown filter `gauss`") && e.contains("gaussian"), "{e}");
    let e = Filter::parse("gaussian:radius=2").unwrap_err();
    assert_eq!(e, "a gaussian filter has no `radius` (it takes stddev)");
    let e = Filter::parse("gaussian:stddev=-1").unwrap_err();
    assert!(e.contains("stddev must be positive"), "{e}");
    assert!(Filter::parse("lanczos:lobes=x").is_err());
}
