//! Chi-square goodness-of-fit test for direction samplers: it draws many directions from a sampler, bins them on a
//! (theta, phi) grid over the sphere, integrates the sampler's claimed solid-angle density over the same cells, and
//! checks that the counts agree with the density. `chi2_cells` runs the same comparison on cells the caller has
//! binned and integrated itself, for samplers of other domains (points of a shape, of a disk).
//!
//! Sources: the overall test, the pooling of cells with small expected counts and the nested adaptive Simpson
//! integration of the density follow pbrt-v4's `src/pbrt/bsdfs_test.cpp`; the Sidak correction for suites of tests
//! and the shape of the diagnostics follow Mitsuba 3's `mitsuba/python/chi2.py`; the regularized incomplete gamma
//! function uses the series / continued-fraction split of Numerical Recipes (`gammq`, section 6.2), with a Lanczos
//! approximation for `ln_gamma`. The code here is written anew for this crate and is self-contained (only `glam`).

use glam::{Vec2, Vec3};
use std::f64::consts::{PI, TAU};
use std::fmt::Write as _;

/// Settings of one chi-square test.
///
/// `phi_res` defaults to `2 * theta_res` only through [`Default`] and [`Chi2Config::with_theta_res`]; when changing
/// `theta_res` with struct-update syntax, set `phi_res` as well.
#[derive(Clone, Debug, PartialEq)]
pub struct Chi2Config {
    /// Number of cells along theta, the angle from +z in [0, pi].
    pub theta_res: usize,
    /// Number of cells along phi, the azimuth in [0, 2 pi).
    pub phi_res: usize,
    /// Number of calls to the sampler; failed samples (`None`) count towards it as missing mass.
    pub samples: usize,
    /// Cells whose expected count is below this are pooled together.
    pub min_expected: f64,
    /// Probability of wrongly rejecting a correct sampler, for the whole suite of `tests` tests.
    pub significance: f64,
    /// Number of tests run in the same suite, used for the Sidak correction of `significance`.
    pub tests: usize,
    /// Seed of the random numbers fed to the sampler.
    pub seed: u64,
}

impl Default for Chi2Config {
    fn default() -> Self {
        Self::with_theta_res(10)
    }
}

impl Chi2Config {
    /// The default configuration with `theta_res` cells along theta and twice as many along phi.
    pub fn with_theta_res(theta_res: usize) -> Self {
        Self {
            theta_res,
            phi_res: 2 * theta_res,
            samples: 1_000_000,
            min_expected: 5.0,
            significance: 0.01,
            tests: 1,
            seed: 0x00c0_ffee_5eed_1234,
        }
    }
}

/// Results of a chi-square test (returned when it passes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Chi2Stats {
    /// Sum of (observed - expected)^2 / expected over the cells, after pooling.
    pub statistic: f64,
    /// Degrees of freedom: cells used after pooling, minus one.
    pub dof: usize,
    /// Probability that a correct sampler gives a statistic at least this large.
    pub p_value: f64,
    /// Number of grid cells merged into the single pooled cell (0 when nothing was pooled).
    pub cells_pooled: usize,
    /// Integral of the pdf over the whole sphere (at most 1, less when the sampler may fail).
    pub pdf_integral: f64,
    /// Per-test significance level after the Sidak correction; the test fails when `p_value < alpha`.
    pub alpha: f64,
}

/// Checks `sample` against its claimed solid-angle density `pdf` with a chi-square test.
///
/// `sample` maps a 2-D and a 1-D uniform number in [0, 1) to a unit direction, or `None` when the sample fails
/// (which counts as missing mass and is allowed as long as `pdf` integrates to correspondingly less than one).
///
/// The test fails when a direction is not a finite unit vector, when `pdf` integrates to more than one (beyond
/// 1e-3), when more than `1 + samples / 1e6` samples land in cells where `pdf` integrates to zero, or when the
/// p-value of the chi-square statistic is below the Sidak-corrected significance.
///
/// Outcome details on failure: a readable report (the observed and expected tables, pooled cells, statistic,
/// p-value).
pub fn chi2_directions(
    name: &str,
    mut sample: impl FnMut(Vec2, f32) -> Option<Vec3>,
    pdf: impl Fn(Vec3) -> f32,
    config: &Chi2Config,
) -> Result<Chi2Stats, String> {
    validate(name, config)?;
    let grid = Grid { theta_res: config.theta_res, phi_res: config.phi_res };
    let alpha = sidak_alpha(config.significance, config.tests);

    // Integrate the density first: a density that is negative, not finite or integrates to more than one makes
    // the comparison meaningless, so it is reported on its own.
    let mut probability = vec![0.0; grid.cells()];
    for (index, p) in probability.iter_mut().enumerate() {
        let (row, col) = grid.row_col(index);
        *p = integrate_cell(&pdf, &grid, row, col);
        if !p.is_finite() || *p < 0.0 {
            return Err(format!(
                "chi2 test '{name}': the pdf integrates to {p} over {}; it must be finite and non-negative",
                grid.describe(row, col)
            ));
        }
    }
    let pdf_integral: f64 = probability.iter().sum();
    if pdf_integral > 1.0 + 1e-3 {
        return Err(format!(
            "chi2 test '{name}': the pdf integrates to {pdf_integral:.6} over the sphere, more than 1; \
             it is not a normalized density"
        ));
    }
    let expected: Vec<f64> = probability.iter().map(|p| p * config.samples as f64).collect();

    let observed = histogram(name, &mut sample, &grid, config)?;

    // Samples in cells where the density is (numerically) zero cannot be explained by chance, with one exception:
    // f32 rounding puts a direction exactly on the edge of a density's support with a probability of about 2^-24
    // per sample (a cos^n sampler returns z = 0 when it draws u = 0, and its pdf is 0 there), which would make a
    // correct sampler fail for about one seed in sixteen at a million samples. So a handful of such samples, 1 plus
    // one per million, is let through and left out of the statistic; pbrt-v4 lets through 1e-5 of the samples per
    // cell, which would hide more.
    let zero_cells: Vec<usize> = (0..grid.cells()).filter(|&i| is_zero(expected[i]) && observed[i] > 0).collect();
    let in_zero_cells: u64 = zero_cells.iter().map(|&i| observed[i]).sum();
    let tolerated = 1 + config.samples as u64 / 1_000_000;
    if in_zero_cells > tolerated {
        let worst = zero_cells.iter().copied().max_by_key(|&i| (observed[i], std::cmp::Reverse(i))).unwrap_or(0);
        let (row, col) = grid.row_col(worst);
        let mut report = format!(
            "chi2 test '{name}' failed: {in_zero_cells} samples (at most {tolerated} tolerated) fell in {} cell(s) \
             where the pdf integrates to 0: the sampler produces directions of zero density; the worst is {} \
             with {} samples\n",
            zero_cells.len(),
            grid.describe(row, col),
            observed[worst]
        );
        write_tables(&mut report, &grid, &observed, &expected);
        return Err(report);
    }

    let pooled = pool_and_sum(&observed, &expected, config.min_expected);
    if pooled.cells_used < 2 {
        let mut report = format!(
            "chi2 test '{name}': only {} cell(s) left after pooling cells with expected count below {}; \
             use more samples or fewer cells\n",
            pooled.cells_used, config.min_expected
        );
        write_tables(&mut report, &grid, &observed, &expected);
        return Err(report);
    }
    let dof = pooled.cells_used - 1;
    let p_value = chi2_p_value(pooled.statistic, dof);
    let stats =
        Chi2Stats { statistic: pooled.statistic, dof, p_value, cells_pooled: pooled.cells_pooled, pdf_integral, alpha };

    // A NaN p-value (from a NaN statistic) must fail too.
    if p_value.is_nan() || p_value < alpha {
        let pooling = if pooled.cells_pooled == 0 {
            "no cells pooled".to_string()
        } else {
            format!(
                "{} cells pooled into one (observed {} vs expected {:.1})",
                pooled.cells_pooled, pooled.pooled_observed, pooled.pooled_expected
            )
        };
        let mut report = format!(
            "chi2 test '{name}' failed: p-value {p_value:.3e} < alpha {alpha:.3e} (significance {}, {} test(s))\n\
             statistic {:.2}, dof {dof}, {pooling}, pdf integral {pdf_integral:.6}, {} samples\n",
            config.significance, config.tests, pooled.statistic, config.samples
        );
        write_tables(&mut report, &grid, &observed, &expected);
        return Err(report);
    }
    Ok(stats)
}

/// Checks counts of samples the caller has binned against the probabilities a density gives the same cells, with
/// `chi2_directions`' pooling, tolerance of a few samples in cells of zero probability and Sidak correction: for
/// samplers of other domains than the sphere of directions (a shape's parameter square, the plane of a disk), whose
/// cells the caller lays out and integrates the density over.
///
/// `observed[i]` counts the samples that fell in cell i out of `config.samples` drawn (samples that failed or fell in
/// no cell are missing mass, as in `chi2_directions`), `probability[i]` is the density's integral over cell i. The
/// report of a failure lays the cells out in rows of `columns`. Of `config`, only `samples`, `min_expected`,
/// `significance` and `tests` are read.
pub fn chi2_cells(
    name: &str,
    observed: &[u64],
    probability: &[f64],
    columns: usize,
    config: &Chi2Config,
) -> Result<Chi2Stats, String> {
    validate(name, config)?;
    if observed.len() != probability.len() || observed.is_empty() || columns == 0 {
        return Err(format!(
            "chi2 test '{name}': {} observed counts for {} probabilities in rows of {columns}; \
             they must be as many, at least one, in rows of at least one",
            observed.len(),
            probability.len()
        ));
    }
    let alpha = sidak_alpha(config.significance, config.tests);
    if let Some(i) = probability.iter().position(|p| !p.is_finite() || *p < 0.0) {
        return Err(format!(
            "chi2 test '{name}': the density integrates to {} over cell {i}; it must be finite and non-negative",
            probability[i]
        ));
    }
    let pdf_integral: f64 = probability.iter().sum();
    if pdf_integral > 1.0 + 1e-3 {
        return Err(format!(
            "chi2 test '{name}': the density integrates to {pdf_integral:.6} over the cells, more than 1; \
             it is not a normalized density"
        ));
    }
    let binned: u64 = observed.iter().sum();
    if binned > config.samples as u64 {
        return Err(format!("chi2 test '{name}': {binned} samples binned out of {} drawn", config.samples));
    }
    let expected: Vec<f64> = probability.iter().map(|p| p * config.samples as f64).collect();

    // As in `chi2_directions`: a handful of samples in cells of zero probability is rounding at the edge of the
    // density's support, more is a sampler producing points of zero density.
    let zero_cells: Vec<usize> = (0..expected.len()).filter(|&i| is_zero(expected[i]) && observed[i] > 0).collect();
    let in_zero_cells: u64 = zero_cells.iter().map(|&i| observed[i]).sum();
    let tolerated = 1 + config.samples as u64 / 1_000_000;
    if in_zero_cells > tolerated {
        let worst = zero_cells.iter().copied().max_by_key(|&i| (observed[i], std::cmp::Reverse(i))).unwrap_or(0);
        let mut report = format!(
            "chi2 test '{name}' failed: {in_zero_cells} samples (at most {tolerated} tolerated) fell in {} cell(s) \
             where the density integrates to 0; the worst is cell {worst} (row {}, column {}) with {} samples\n",
            zero_cells.len(),
            worst / columns,
            worst % columns,
            observed[worst]
        );
        write_cell_tables(&mut report, columns, observed, &expected);
        return Err(report);
    }

    let pooled = pool_and_sum(observed, &expected, config.min_expected);
    if pooled.cells_used < 2 {
        let mut report = format!(
            "chi2 test '{name}': only {} cell(s) left after pooling cells with expected count below {}; \
             use more samples or fewer cells\n",
            pooled.cells_used, config.min_expected
        );
        write_cell_tables(&mut report, columns, observed, &expected);
        return Err(report);
    }
    let dof = pooled.cells_used - 1;
    let p_value = chi2_p_value(pooled.statistic, dof);
    let stats =
        Chi2Stats { statistic: pooled.statistic, dof, p_value, cells_pooled: pooled.cells_pooled, pdf_integral, alpha };
    if p_value.is_nan() || p_value < alpha {
        let mut report = format!(
            "chi2 test '{name}' failed: p-value {p_value:.3e} < alpha {alpha:.3e} (significance {}, {} test(s))\n\
             statistic {:.2}, dof {dof}, {} cells pooled, density integral {pdf_integral:.6}, {} samples\n",
            config.significance, config.tests, pooled.statistic, pooled.cells_pooled, config.samples
        );
        write_cell_tables(&mut report, columns, observed, &expected);
        return Err(report);
    }
    Ok(stats)
}

/// Rejects configurations under which the test cannot run, so that they fail loudly instead of passing vacuously.
fn validate(name: &str, config: &Chi2Config) -> Result<(), String> {
    let problem = if config.theta_res == 0 || config.phi_res == 0 {
        Some("theta_res and phi_res must be positive")
    } else if config.samples == 0 {
        Some("samples must be positive")
    } else if config.significance.is_nan() || config.significance <= 0.0 || config.significance >= 1.0 {
        Some("significance must lie in (0, 1)")
    } else if config.min_expected.is_nan() || config.min_expected < 0.0 {
        Some("min_expected must be non-negative")
    } else {
        None
    };
    match problem {
        Some(text) => Err(format!("chi2 test '{name}': invalid configuration {config:?}: {text}")),
        None => Ok(()),
    }
}

/// Sidak correction: the per-test level that keeps the chance of any false rejection among `tests` independent
/// tests at `significance`.
fn sidak_alpha(significance: f64, tests: usize) -> f64 {
    let tests = tests.max(1) as f64;
    1.0 - (1.0 - significance).powf(1.0 / tests)
}

/// The (theta, phi) grid of cells, stored row by row (one row per theta band).
struct Grid {
    theta_res: usize,
    phi_res: usize,
}

impl Grid {
    fn cells(&self) -> usize {
        self.theta_res * self.phi_res
    }

    fn row_col(&self, index: usize) -> (usize, usize) {
        (index / self.phi_res, index % self.phi_res)
    }

    fn theta_step(&self) -> f64 {
        PI / self.theta_res as f64
    }

    fn phi_step(&self) -> f64 {
        TAU / self.phi_res as f64
    }

    /// Index of the cell holding a unit direction. The direction is renormalized in f64 so that f32 rounding of
    /// its length cannot push `acos` out of its domain.
    fn cell_of(&self, dir: Vec3) -> usize {
        let d = dir.as_dvec3().normalize();
        let theta = d.z.clamp(-1.0, 1.0).acos();
        let mut phi = d.y.atan2(d.x);
        if phi < 0.0 {
            phi += TAU;
        }
        // The clamps catch theta == pi and phi rounding up to 2 pi, which belong to the last row and column.
        let row = ((theta / self.theta_step()) as usize).min(self.theta_res - 1);
        let col = ((phi / self.phi_step()) as usize).min(self.phi_res - 1);
        row * self.phi_res + col
    }

    fn describe(&self, row: usize, col: usize) -> String {
        let (dt, dp) = (180.0 / self.theta_res as f64, 360.0 / self.phi_res as f64);
        format!(
            "cell (theta row {row}: [{:.1}, {:.1}) deg, phi column {col}: [{:.1}, {:.1}) deg)",
            row as f64 * dt,
            (row + 1) as f64 * dt,
            col as f64 * dp,
            (col + 1) as f64 * dp
        )
    }
}

/// Draws `config.samples` directions and counts them per cell, failing on directions that are not unit vectors.
fn histogram(
    name: &str,
    sample: &mut impl FnMut(Vec2, f32) -> Option<Vec3>,
    grid: &Grid,
    config: &Chi2Config,
) -> Result<Vec<u64>, String> {
    let mut rng = Pcg32::new(config.seed);
    let mut observed = vec![0u64; grid.cells()];
    for i in 0..config.samples {
        // The draws happen in a fixed order so that a given seed always feeds the sampler the same numbers.
        let u2 = Vec2::new(rng.next_f32(), rng.next_f32());
        let u1 = rng.next_f32();
        let Some(dir) = sample(u2, u1) else { continue };
        if !dir.is_finite() || (dir.length() - 1.0).abs() > 1e-3 {
            return Err(format!(
                "chi2 test '{name}': sample {i} (u = ({}, {}), {u1}) returned {dir:?} with length {}; \
                 the sampler must return finite unit directions",
                u2.x,
                u2.y,
                dir.length()
            ));
        }
        observed[grid.cell_of(dir)] += 1;
    }
    Ok(observed)
}

/// Sub-cells per cell along each axis. Integrating each sub-cell adaptively makes it far less likely that a narrow
/// peak falls between all the points of the first, coarse Simpson estimate and is declared converged as zero.
const SUBDIVISIONS: usize = 4;
/// Relative tolerance of each 1-D adaptive Simpson integral.
const SIMPSON_RELATIVE_TOLERANCE: f64 = 1e-6;
/// Levels of bisection always performed, so that convergence is never judged from the first five points alone.
const SIMPSON_MIN_DEPTH: u32 = 2;
/// Bound on the bisection levels, which bounds the work on discontinuous or peaked densities.
const SIMPSON_MAX_DEPTH: u32 = 7;

/// Probability that `pdf` assigns to one cell: the integral over theta of sin(theta) times the integral over phi
/// of the density, by nested adaptive Simpson rules on a fixed grid of sub-cells.
fn integrate_cell(pdf: &impl Fn(Vec3) -> f32, grid: &Grid, row: usize, col: usize) -> f64 {
    let (dt, dp) = (grid.theta_step() / SUBDIVISIONS as f64, grid.phi_step() / SUBDIVISIONS as f64);
    let (theta0, phi0) = (row as f64 * grid.theta_step(), col as f64 * grid.phi_step());
    let mut total = 0.0;
    for i in 0..SUBDIVISIONS {
        let (t0, t1) = (theta0 + i as f64 * dt, theta0 + (i + 1) as f64 * dt);
        for j in 0..SUBDIVISIONS {
            let (p0, p1) = (phi0 + j as f64 * dp, phi0 + (j + 1) as f64 * dp);
            let over_theta = |theta: f64| {
                let (sin_theta, cos_theta) = theta.sin_cos();
                let over_phi = |phi: f64| {
                    let (sin_phi, cos_phi) = phi.sin_cos();
                    let dir = Vec3::new((sin_theta * cos_phi) as f32, (sin_theta * sin_phi) as f32, cos_theta as f32);
                    f64::from(pdf(dir))
                };
                sin_theta * adaptive_simpson(&over_phi, p0, p1)
            };
            total += adaptive_simpson(&over_theta, t0, t1);
        }
    }
    total
}

/// One interval of the adaptive Simpson rule with its end and middle values and its Simpson estimate, kept so
/// that no point is evaluated twice.
#[derive(Clone, Copy)]
struct Panel {
    a: f64,
    m: f64,
    b: f64,
    fa: f64,
    fm: f64,
    fb: f64,
    estimate: f64,
}

impl Panel {
    fn new(f: &impl Fn(f64) -> f64, a: f64, b: f64, fa: f64, fb: f64) -> Self {
        let m = 0.5 * (a + b);
        let fm = f(m);
        Self { a, m, b, fa, fm, fb, estimate: (b - a) / 6.0 * (fa + 4.0 * fm + fb) }
    }
}

/// Adaptive Simpson integral of `f` over [a, b] with a tolerance relative to the first estimate.
fn adaptive_simpson(f: &impl Fn(f64) -> f64, a: f64, b: f64) -> f64 {
    let whole = Panel::new(f, a, b, f(a), f(b));
    let tolerance = SIMPSON_RELATIVE_TOLERANCE * whole.estimate.abs();
    refine(f, whole, tolerance, 0)
}

/// Splits `panel` in two and recurses until the halves agree with the whole to within the tolerance (Lyness'
/// criterion, |left + right - whole| <= 15 tolerance), halving the tolerance with each level.
fn refine(f: &impl Fn(f64) -> f64, panel: Panel, tolerance: f64, depth: u32) -> f64 {
    let left = Panel::new(f, panel.a, panel.m, panel.fa, panel.fm);
    let right = Panel::new(f, panel.m, panel.b, panel.fm, panel.fb);
    let halves = left.estimate + right.estimate;
    let converged = depth >= SIMPSON_MIN_DEPTH && (halves - panel.estimate).abs() <= 15.0 * tolerance;
    if converged || depth >= SIMPSON_MAX_DEPTH {
        // Unlike pbrt this skips the Richardson term (halves - whole) / 15: Simpson's weights are positive, so
        // without it a non-negative density can never integrate to a negative expected count, even next to a
        // discontinuity or a peak, where the extrapolation's smoothness assumption does not hold.
        return halves;
    }
    refine(f, left, 0.5 * tolerance, depth + 1) + refine(f, right, 0.5 * tolerance, depth + 1)
}

/// Expected counts below this are treated as zero: a correct sampler puts a sample into such a cell with a
/// probability below one in a million, and a density that is zero in exact arithmetic often integrates to a tiny
/// positive value next to the edge of its support (cos(pi / 2) is 6e-17 in floating point).
const ZERO_EXPECTED: f64 = 1e-6;

fn is_zero(expected: f64) -> bool {
    expected < ZERO_EXPECTED
}

/// The chi-square statistic after pooling, and what the pooling did.
struct Pooled {
    statistic: f64,
    cells_used: usize,
    cells_pooled: usize,
    pooled_observed: u64,
    pooled_expected: f64,
}

/// Pools cells with small expected counts and sums the chi-square statistic, as pbrt does: going through the cells
/// in increasing order of expected count, cells below `min_expected` go into one pooled cell, which keeps taking
/// the next cells until its own expected count reaches `min_expected`; cells with expected count (nearly) zero
/// carry no information and are skipped, along with the few samples tolerated in them.
fn pool_and_sum(observed: &[u64], expected: &[f64], min_expected: f64) -> Pooled {
    let mut order: Vec<usize> = (0..expected.len()).collect();
    order.sort_by(|&i, &j| expected[i].total_cmp(&expected[j]));

    let mut result =
        Pooled { statistic: 0.0, cells_used: 0, cells_pooled: 0, pooled_observed: 0, pooled_expected: 0.0 };
    for &i in &order {
        let (obs, exp) = (observed[i], expected[i]);
        if is_zero(exp) {
            continue;
        }
        let pool_open = result.pooled_expected > 0.0 && result.pooled_expected < min_expected;
        if exp < min_expected || pool_open {
            result.pooled_observed += obs;
            result.pooled_expected += exp;
            result.cells_pooled += 1;
        } else {
            result.statistic += chi2_term(obs, exp);
            result.cells_used += 1;
        }
    }
    if result.cells_pooled > 0 {
        result.statistic += chi2_term(result.pooled_observed, result.pooled_expected);
        result.cells_used += 1;
    }
    result
}

fn chi2_term(observed: u64, expected: f64) -> f64 {
    let diff = observed as f64 - expected;
    diff * diff / expected
}

/// Writes the per-row summary and the observed, expected and residual tables of a failing test.
fn write_tables(report: &mut String, grid: &Grid, observed: &[u64], expected: &[f64]) {
    let dt = 180.0 / grid.theta_res as f64;
    // Writing into a String cannot fail, so the fmt::Results below are ignored on purpose.
    let _ = writeln!(report, "per theta row (columns are phi cells, from phi = 0 upwards):");
    let _ = writeln!(report, "  row  theta [deg]      observed      expected  chi2 of row");
    for row in 0..grid.theta_res {
        let cells = row * grid.phi_res..(row + 1) * grid.phi_res;
        let obs: u64 = observed[cells.clone()].iter().sum();
        let exp: f64 = expected[cells.clone()].iter().sum();
        // A fold from +0 rather than sum(), whose empty sum is -0 and would print as such.
        let chi2 =
            cells.filter(|&i| !is_zero(expected[i])).fold(0.0, |acc, i| acc + chi2_term(observed[i], expected[i]));
        let _ = writeln!(
            report,
            "  {row:>3}  [{:>5.1},{:>6.1})  {obs:>12}  {exp:>12.1}  {chi2:>11.1}",
            row as f64 * dt,
            (row + 1) as f64 * dt
        );
    }
    write_cell_tables(report, grid.phi_res, observed, expected);
}

/// Writes the observed, expected and residual tables of a failing test, in rows of `columns` cells.
fn write_cell_tables(report: &mut String, columns: usize, observed: &[u64], expected: &[f64]) {
    let _ = writeln!(report, "observed counts:");
    for row in observed.chunks(columns) {
        let line: Vec<String> = row.iter().map(|o| format!("{o:>7}")).collect();
        let _ = writeln!(report, "  {}", line.join(" "));
    }
    let _ = writeln!(report, "expected counts:");
    for row in expected.chunks(columns) {
        let line: Vec<String> = row.iter().map(|e| format!("{e:>7.0}")).collect();
        let _ = writeln!(report, "  {}", line.join(" "));
    }
    let _ = writeln!(report, "residuals (observed - expected) / sqrt(expected) ('!' marks samples where pdf = 0):");
    for (obs_row, exp_row) in observed.chunks(columns).zip(expected.chunks(columns)) {
        let line: Vec<String> = obs_row
            .iter()
            .zip(exp_row)
            .map(|(&o, &e)| match (o, !is_zero(e)) {
                (0, false) => format!("{:>7}", "."),
                (_, false) => format!("{:>7}", "!"),
                (_, true) => format!("{:>+7.1}", (o as f64 - e) / e.sqrt()),
            })
            .collect();
        let _ = writeln!(report, "  {}", line.join(" "));
    }
}

/// Probability that a chi-square variable with `dof` degrees of freedom exceeds `statistic`.
pub fn chi2_p_value(statistic: f64, dof: usize) -> f64 {
    gamma_q(0.5 * dof as f64, 0.5 * statistic)
}

/// Regularized upper incomplete gamma function Q(a, x) = Gamma(a, x) / Gamma(a), for a > 0 and x >= 0.
///
/// As in Numerical Recipes, the power series of P = 1 - Q converges fast for x < a + 1 and the continued fraction
/// of Q converges fast otherwise; computing Q directly in the second region keeps its tiny values accurate instead
/// of losing them to cancellation in 1 - P.
pub fn gamma_q(a: f64, x: f64) -> f64 {
    if a.is_nan() || x.is_nan() || a <= 0.0 {
        return f64::NAN;
    }
    if x <= 0.0 {
        return 1.0;
    }
    if x < a + 1.0 { 1.0 - gamma_p_series(a, x) } else { gamma_q_continued_fraction(a, x) }
}

/// Iteration cap of the series and the continued fraction; both converge in far fewer steps (about sqrt(a)
/// times a small constant) for the arguments chi-square tests produce.
const GAMMA_MAX_ITERATIONS: usize = 10_000;

/// ln(x^a e^-x / Gamma(a)), the prefactor shared by the series and the continued fraction, in logs to avoid
/// overflow for large a or x.
fn gamma_log_prefactor(a: f64, x: f64) -> f64 {
    a * x.ln() - x - ln_gamma(a)
}

/// P(a, x) by its power series: P = x^a e^-x / Gamma(a + 1) * sum_n x^n / ((a + 1) ... (a + n)).
fn gamma_p_series(a: f64, x: f64) -> f64 {
    let mut term = 1.0 / a;
    let mut sum = term;
    let mut denominator = a;
    for _ in 0..GAMMA_MAX_ITERATIONS {
        denominator += 1.0;
        term *= x / denominator;
        sum += term;
        if term.abs() < sum.abs() * f64::EPSILON {
            break;
        }
    }
    sum * gamma_log_prefactor(a, x).exp()
}

/// Q(a, x) by its continued fraction, evaluated with the modified Lentz method, which needs no a priori choice of
/// the number of terms and guards against zero denominators with a tiny value.
fn gamma_q_continued_fraction(a: f64, x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    let mut b = x + 1.0 - a;
    let mut c = 1.0 / TINY;
    let mut d = 1.0 / b;
    let mut h = d;
    for i in 1..GAMMA_MAX_ITERATIONS {
        let i = i as f64;
        let an = -i * (i - a);
        b += 2.0;
        d = an * d + b;
        if d.abs() < TINY {
            d = TINY;
        }
        c = b + an / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        let delta = d * c;
        h *= delta;
        if (delta - 1.0).abs() < f64::EPSILON {
            break;
        }
    }
    gamma_log_prefactor(a, x).exp() * h
}

/// ln Gamma(x) for x > 0 by the Lanczos approximation with g = 7 and nine coefficients (relative error around
/// 1e-15); arguments below 1/2 go through the reflection formula, where the approximation is less accurate.
pub fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const COEFFICIENTS: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Gamma(x) Gamma(1 - x) = pi / sin(pi x).
        return (PI / (PI * x).sin()).abs().ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut series = COEFFICIENTS[0];
    for (k, &c) in COEFFICIENTS.iter().enumerate().skip(1) {
        series += c / (x + k as f64);
    }
    let t = x + G + 0.5;
    0.5 * TAU.ln() + (x + 0.5) * t.ln() - t + series.ln()
}

/// PCG32 (O'Neill 2014, XSH-RR output), kept here so that the test depends on nothing but its seed.
struct Pcg32 {
    state: u64,
    increment: u64,
}

impl Pcg32 {
    const MULTIPLIER: u64 = 6_364_136_223_846_793_005;
    /// PCG's default stream; any odd increment would do.
    const INCREMENT: u64 = 1_442_695_040_888_963_407;

    fn new(seed: u64) -> Self {
        // The reference seeding: step once from zero, add the seed, step again, so that nearby seeds diverge.
        let mut rng = Self { state: 0, increment: Self::INCREMENT };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(seed);
        rng.next_u32();
        rng
    }

    fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(Self::MULTIPLIER).wrapping_add(self.increment);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        xorshifted.rotate_right((old >> 59) as u32)
    }

    /// Uniform in [0, 1): the top 24 bits fill the f32 mantissa exactly, so 1.0 is never returned.
    fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }
}

#[cfg(test)]
mod tests;
