//! Statistical tests of the piecewise-constant distributions: chi-square of sampled points
//! against the claimed density (cells and sub-cells, so uniformity inside a cell is checked
//! too), the density a sample reports against `pdf` at its point, normalisation, and the
//! corner cases (zero cells, an all-zero function).

use super::*;
use crate::sampling::Rng32;
use crate::sampling::chi2::chi2_p_value;

/// Chi-square statistic over bins, pooling bins expecting fewer than 5 counts; (statistic, dof).
fn chi_square(observed: &[u64], expected: &[f64]) -> (f64, usize) {
    let (mut stat, mut cells) = (0.0, 0usize);
    let (mut pool_o, mut pool_e) = (0.0, 0.0);
    for (&o, &e) in observed.iter().zip(expected) {
        if e < 5.0 {
            pool_o += o as f64;
            pool_e += e;
        } else {
            stat += (o as f64 - e).powi(2) / e;
            cells += 1;
        }
    }
    if pool_e > 0.0 {
        stat += (pool_o - pool_e).powi(2) / pool_e.max(1e-12);
        cells += 1;
    }
    (stat, cells.saturating_sub(1))
}

/// A lumpy function with zero cells, a tall spike and values over several decades.
fn lumpy(nu: usize, nv: usize) -> Vec<f32> {
    let mut rng = Rng32::new(11);
    (0..nu * nv)
        .map(|i| match i % 7 {
            0 => 0.0,
            3 => 50.0 * rng.uniform(),
            _ => rng.uniform().powi(3) + 0.01,
        })
        .collect()
}

#[test]
fn one_dimensional_samples_follow_the_function() {
    let func = [0.0, 1.0, 3.0, 0.0, 0.0, 0.5, 2.0, 0.0];
    let d = Distribution1D::new(&func);
    assert!((d.integral() - 6.5 / 8.0).abs() < 1e-6);
    let mut rng = Rng32::new(3);
    let n = 400_000;
    // Two bins per cell: the density is flat inside a cell.
    let mut observed = vec![0u64; 16];
    for _ in 0..n {
        let (x, pdf, cell) = d.sample(rng.uniform());
        assert!((0.0..1.0).contains(&x));
        assert_eq!(cell, (x * 8.0) as usize);
        assert!(pdf > 0.0 && (pdf - d.pdf(x)).abs() <= 1e-6 * pdf, "pdf {pdf} vs {}", d.pdf(x));
        observed[(x * 16.0) as usize] += 1;
    }
    let expected: Vec<f64> = (0..16).map(|b| func[b / 2] as f64 / 6.5 / 2.0 * n as f64).collect();
    for b in 0..16 {
        if expected[b] == 0.0 {
            assert_eq!(observed[b], 0, "bin {b} of a zero cell was sampled");
        }
    }
    let (stat, dof) = chi_square(&observed, &expected);
    let p = chi2_p_value(stat, dof);
    assert!(p > 1e-4, "chi-square {stat} with {dof} dof: p = {p}");
}

#[test]
fn a_zero_function_samples_uniformly() {
    let d = Distribution1D::new(&[0.0, 0.0, 0.0, 0.0]);
    assert_eq!(d.integral(), 0.0);
    for (u, x) in [(0.0, 0.0), (0.3, 0.3), (0.99, 0.99)] {
        let (s, pdf, _) = d.sample(u);
        assert!((s - x).abs() < 1e-6 && pdf == 1.0, "{u}: {s} {pdf}");
    }
    // Non-finite and negative values count as zero.
    let d = Distribution1D::new(&[f32::NAN, -1.0, 2.0, f32::INFINITY]);
    assert_eq!(d.sample(0.0).2, 2);
    assert_eq!(d.sample(0.999_999).2, 2);
    assert_eq!(d.pdf(0.1), 0.0);
}

#[test]
fn samples_near_one_stay_below_one() {
    let d = Distribution1D::new(&[1.0, 0.0, 0.0, 1e-30]);
    let (x, _, _) = d.sample(ONE_MINUS_EPSILON);
    assert!(x < 1.0);
    let d2 = Distribution2D::new(&[1.0; 6], 3, 2);
    let (p, _) = d2.sample(Vec2::splat(ONE_MINUS_EPSILON));
    assert!(p.x < 1.0 && p.y < 1.0);
}

#[test]
fn two_dimensional_chi_square_over_cells_and_sub_cells() {
    let (nu, nv) = (13, 7);
    let func = lumpy(nu, nv);
    let d = Distribution2D::new(&func, nu, nv);
    let total: f64 = func.iter().map(|&f| f as f64).sum();
    assert!((d.integral() as f64 - total / (nu * nv) as f64).abs() < 1e-5 * d.integral() as f64);
    // Each cell split into 2 x 2 bins.
    let (bu, bv) = (2 * nu, 2 * nv);
    let n = 1_000_000;
    let mut observed = vec![0u64; bu * bv];
    let mut rng = Rng32::new(5);
    for _ in 0..n {
        let (p, pdf) = d.sample(rng.uniform2());
        assert!((0.0..1.0).contains(&p.x) && (0.0..1.0).contains(&p.y), "{p}");
        let claimed = d.pdf(p);
        assert!(pdf > 0.0 && (pdf - claimed).abs() <= 1e-5 * pdf, "sample pdf {pdf} vs pdf {claimed} at {p}");
        observed[(p.y * bv as f32) as usize * bu + (p.x * bu as f32) as usize] += 1;
    }
    let expected: Vec<f64> =
        (0..bu * bv).map(|b| func[(b / bu / 2) * nu + (b % bu) / 2] as f64 / total / 4.0 * n as f64).collect();
    for b in 0..bu * bv {
        if expected[b] == 0.0 {
            assert_eq!(observed[b], 0, "bin {b} of a zero cell was sampled");
        }
    }
    let (stat, dof) = chi_square(&observed, &expected);
    let p = chi2_p_value(stat, dof);
    assert!(p > 1e-4, "chi-square {stat} with {dof} dof: p = {p}");
}

#[test]
fn two_dimensional_pdf_integrates_to_one() {
    let (nu, nv) = (9, 5);
    let d = Distribution2D::new(&lumpy(nu, nv), nu, nv);
    // The density is constant on cells: integrate at the cell centres.
    let mut sum = 0.0f64;
    for j in 0..nv {
        for i in 0..nu {
            let c = Vec2::new((i as f32 + 0.5) / nu as f32, (j as f32 + 0.5) / nv as f32);
            sum += d.pdf(c) as f64 / (nu * nv) as f64;
        }
    }
    assert!((sum - 1.0).abs() < 1e-5, "{sum}");
    // A row that is all zero is never chosen, and has density 0.
    let mut func = vec![1.0f32; 12];
    func[4..8].fill(0.0);
    let d = Distribution2D::new(&func, 4, 3);
    let mut rng = Rng32::new(8);
    for _ in 0..10_000 {
        let (p, _) = d.sample(rng.uniform2());
        assert!(!(1.0 / 3.0..2.0 / 3.0).contains(&p.y), "{p}");
    }
    assert_eq!(d.pdf(Vec2::new(0.5, 0.5)), 0.0);
}
