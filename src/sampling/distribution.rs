//! Piecewise-constant distributions on [0, 1) and [0, 1)^2, sampled by inverting their CDFs
//! (pbrt-v4 `PiecewiseConstant1D` / `PiecewiseConstant2D`, PBR 4th ed. sec. A.5): a 2-D
//! distribution is a marginal over rows and one conditional per row. Everything is allocated when
//! a distribution is made; sampling and density lookups allocate nothing.
//!
//! Densities are with respect to the unit interval or square: a cell of value `f` has density
//! `f / integral`, where the integral is the mean of the cells. A function that is zero
//! everywhere samples uniformly, so a sample is always available and its density positive.

use glam::Vec2;

/// Largest f32 below 1: samples stay inside [0, 1).
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// A piecewise-constant density over [0, 1) with `n` equal cells.
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution1D {
    /// The cell values (negative and non-finite values read as 0).
    func: Vec<f32>,
    /// `n + 1` values, 0 first and 1 last.
    cdf: Vec<f32>,
    /// Mean of `func` (the integral over [0, 1)); 0 for a zero function.
    integral: f32,
}

impl Distribution1D {
    /// The distribution proportional to `func` (at least one cell).
    pub fn new(func: &[f32]) -> Self {
        assert!(!func.is_empty(), "a distribution needs at least one cell");
        let func: Vec<f32> = func.iter().map(|&f| if f.is_finite() && f > 0.0 { f } else { 0.0 }).collect();
        let n = func.len();
        // Running sums in f64, so long rows of tiny values keep their proportions.
        let mut sums = Vec::with_capacity(n + 1);
        let mut acc = 0.0f64;
        sums.push(0.0);
        for &f in &func {
            acc += f as f64;
            sums.push(acc);
        }
        let total = acc;
        let cdf = if total > 0.0 {
            let mut c: Vec<f32> = sums.iter().map(|&s| (s / total) as f32).collect();
            c[n] = 1.0;
            c
        } else {
            (0..=n).map(|i| i as f32 / n as f32).collect()
        };
        Distribution1D { func, cdf, integral: (total / n as f64) as f32 }
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.func.len()
    }

    pub fn is_empty(&self) -> bool {
        self.func.is_empty()
    }

    /// Integral of the function over [0, 1) (the mean of its cells).
    pub fn integral(&self) -> f32 {
        self.integral
    }

    /// Value of cell `i`.
    pub fn value(&self, i: usize) -> f32 {
        self.func[i]
    }

    /// Density of cell `i`.
    #[inline]
    fn cell_pdf(&self, i: usize) -> f32 {
        if self.integral > 0.0 { self.func[i] / self.integral } else { 1.0 }
    }

    /// A point in [0, 1) for the uniform number `u`: (point, density, cell).
    #[inline]
    pub fn sample(&self, u: f32) -> (f32, f32, usize) {
        let n = self.func.len();
        // The last cell whose start is at or below u; cells of zero width are skipped because
        // the next cell starts at the same value.
        let i = self.cdf.partition_point(|&c| c <= u).clamp(1, n) - 1;
        let width = self.cdf[i + 1] - self.cdf[i];
        let du = if width > 0.0 { ((u - self.cdf[i]) / width).clamp(0.0, 1.0) } else { 0.0 };
        let x = ((i as f32 + du) / n as f32).min(ONE_MINUS_EPSILON);
        (x, self.cell_pdf(i), i)
    }

    /// Density at `x` in [0, 1) (clamped into the domain).
    #[inline]
    pub fn pdf(&self, x: f32) -> f32 {
        self.cell_pdf(self.cell_of(x))
    }

    #[inline]
    fn cell_of(&self, x: f32) -> usize {
        let n = self.func.len();
        if x > 0.0 { ((x * n as f32) as usize).min(n - 1) } else { 0 }
    }
}

/// A piecewise-constant density over [0, 1)^2 on a grid of `nu` x `nv` cells.
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution2D {
    /// One distribution over u per row.
    conditional: Vec<Distribution1D>,
    /// The rows' integrals as a distribution over v.
    marginal: Distribution1D,
}

impl Distribution2D {
    /// The distribution proportional to `func`, row-major: `func[v * nu + u]`.
    pub fn new(func: &[f32], nu: usize, nv: usize) -> Self {
        assert!(nu > 0 && nv > 0 && func.len() == nu * nv, "a {nu} x {nv} grid needs {} values", nu * nv);
        let conditional: Vec<Distribution1D> = func.chunks_exact(nu).map(Distribution1D::new).collect();
        let rows: Vec<f32> = conditional.iter().map(Distribution1D::integral).collect();
        Distribution2D { marginal: Distribution1D::new(&rows), conditional }
    }

    /// Cells along u and along v.
    pub fn size(&self) -> (usize, usize) {
        (self.conditional[0].len(), self.conditional.len())
    }

    /// Integral of the function over the unit square.
    pub fn integral(&self) -> f32 {
        self.marginal.integral()
    }

    /// A point in [0, 1)^2 for the uniform numbers `u` (u.y picks the row, u.x the column) and
    /// its density.
    #[inline]
    pub fn sample(&self, u: Vec2) -> (Vec2, f32) {
        let (v, pdf_v, row) = self.marginal.sample(u.y);
        let (x, pdf_u, _) = self.conditional[row].sample(u.x);
        (Vec2::new(x, v), pdf_v * pdf_u)
    }

    /// Density at `p` (clamped into the unit square).
    #[inline]
    pub fn pdf(&self, p: Vec2) -> f32 {
        let row = self.marginal.cell_of(p.y);
        self.marginal.cell_pdf(row) * self.conditional[row].pdf(p.x)
    }

    /// Bytes held, for memory estimates.
    pub fn memory_bytes(&self) -> usize {
        let (nu, nv) = self.size();
        (nu * nv * 2 + nv * 3 + 2) * std::mem::size_of::<f32>() + nv * std::mem::size_of::<Distribution1D>()
    }
}

#[cfg(test)]
mod tests;
