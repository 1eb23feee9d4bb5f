//! The error function, its complement and its inverse in f64, for the Beckmann distribution's
//! visible-normal sampling (`super::Microfacet::sample_visible`) and for its exact Smith Λ.
//!
//! Each function is split into a few pieces, each a polynomial fitted by Chebyshev interpolation
//! at 40 digits (`scripts/erf_coefficients.py`, with mpmath) in a variable scaled to [-1, 1], so
//! Horner's rule is well conditioned; the split points and variables follow the usual shapes of
//! these functions (erf(x)/x in x^2 near 0, exp(x^2) erfc(x) further out, and erfinv(y)/y in
//! w = -ln(1 - y^2) or sqrt(w), as in Giles 2011, "Approximating the erfinv function").
//!
//! Accuracy, measured against mpmath on 20000 points each (and tested in `tests.rs`): the fits
//! are exact to 1e-17 and their f64 evaluation to about 2e-16 (see the notes on the tables).
//! `erf` is within 2.1e-16 relative everywhere; `erfc` within 9e-16 relative for x < 26 (the worst
//! just below x = 1, where it is 1 - erf), after which it turns subnormal and then 0 from x = 27;
//! `erfinv` is within 3.8e-16 relative for every f64 in (-1, 1), up to the last one below 1.
//! `erfinv` stays relatively accurate next to +-1 because it reads 1 - |y| from exact
//! arithmetic: that is what the Beckmann sampler computes in f64 for.

/// erf(x). Odd; exactly +-1 for |x| >= 6 (erfc(6) = 2e-17 is below half an ulp of 1); NaN for NaN.
#[inline]
pub fn erf(x: f64) -> f64 {
    let a = x.abs();
    if a < 1.0 {
        x * horner(&ERF_SMALL, x * x)
    } else if a < 6.0 {
        // A plain exp(-x^2) suffices here: its rounding error (up to 4e-15 relative) scales erfc,
        // which is at most 0.16, far below the ulp of erf.
        (1.0 - (-a * a).exp() * scaled_erfc(a)).copysign(x)
    } else if a.is_nan() {
        x
    } else {
        1.0f64.copysign(x)
    }
}

/// erfc(x) = 1 - erf(x), without the cancellation of the subtraction for large x (relative error
/// below 1e-15 for x < 26; 0 from x = 27, where it underflows).
#[inline]
pub fn erfc(x: f64) -> f64 {
    if x >= 27.0 {
        // exp(-729) underflows.
        0.0
    } else if x >= 1.0 {
        exp_minus_square(x) * scaled_erfc(x)
    } else if x > -1.0 {
        1.0 - x * horner(&ERF_SMALL, x * x)
    } else if x > -6.0 {
        // erfc(x) = 2 - erfc(-x) lies in (1, 2) and loses nothing.
        2.0 - exp_minus_square(x) * scaled_erfc(-x)
    } else if x.is_nan() {
        x
    } else {
        // erfc(-x) < 2e-17 is below half an ulp of 2.
        2.0
    }
}

/// exp(x^2) erfc(x) for x >= 1 (or NaN), a smooth function falling like 1 / (x sqrt(pi)).
#[inline]
fn scaled_erfc(x: f64) -> f64 {
    if x < 2.5 {
        horner(&ERFC_MIDDLE, (x - 1.75) * (1.0 / 0.75))
    } else {
        horner(&ERFC_TAIL, 1.0 / (x * x) * (1.0 / 0.08) - 1.0) / x
    }
}

/// exp(-x^2) without the rounding of x^2 (whose relative error x^2 * 1.1e-16 would reach 8e-14 at
/// x = 27): x is split into a 26-bit head h, whose square is exact, and the rest l, so that
/// x^2 = h^2 + l (x + h) with a second term too small for its rounding to matter.
#[inline]
fn exp_minus_square(x: f64) -> f64 {
    let head = f64::from_bits(x.to_bits() & 0xffff_ffff_f800_0000);
    let rest = x - head;
    (-head * head).exp() * (-rest * (x + head)).exp()
}

/// erfinv(y), the x with erf(x) = y, for y in [-1, 1]: +-infinity at +-1, NaN outside (and for NaN).
#[inline]
pub fn erfinv(y: f64) -> f64 {
    // (1 - y)(1 + y) rather than 1 - y^2: next to +-1 one factor is exact and the other is
    // close to 2, so w keeps the full relative accuracy of 1 - |y|.
    let w = -((1.0 - y) * (1.0 + y)).ln();
    if w < 6.25 {
        y * horner(&ERFINV_CENTRAL, w * (1.0 / 3.125) - 1.0)
    } else if w < 16.0 {
        y * horner(&ERFINV_TAIL, (w.sqrt() - 3.25) * (1.0 / 0.75))
    } else if w <= 36.1 {
        y * horner(&ERFINV_FAR_TAIL, (w.sqrt() - 5.005) * (1.0 / 1.005))
    } else if y.abs() == 1.0 {
        f64::INFINITY.copysign(y)
    } else {
        // |y| > 1 gives the log of a negative number, NaN in gives NaN; no f64 inside (-1, 1)
        // reaches w > 36.1.
        f64::NAN
    }
}

/// 1 / sqrt(pi), the factor of Beckmann's Λ and of its visible-slope CDF (halving is exact).
pub const FRAC_1_SQRT_PI: f64 = std::f64::consts::FRAC_2_SQRT_PI * 0.5;

/// Evaluates the polynomial with `coefficients` (highest degree first) at `t`, by Horner's rule
/// in t^4 on the four classes of terms by degree mod 4 at once: four independent chains of a
/// quarter of the length, which the processor overlaps (one chain of 25 dependent multiply-adds
/// made `erfinv` a tenth of a VCM render of Beckmann metals; BENCHMARKS.md). The rounding
/// differs from one chain's, not its size: `tests.rs` holds every function to the accuracy the
/// module header gives.
#[inline(always)]
fn horner<const N: usize>(coefficients: &[f64; N], t: f64) -> f64 {
    let t2 = t * t;
    let t4 = t2 * t2;
    // Coefficient i has degree N - 1 - i: those of degree k mod 4 start at index (N - 1 - k) % 4.
    let chain = |k: usize| coefficients[(N + 3 - k) % 4..].iter().step_by(4).fold(0.0, |acc, &c| acc * t4 + c);
    (chain(3) * t + chain(2)) * t2 + (chain(1) * t + chain(0))
}

// Generated by scripts/erf_coefficients.py (mpmath 1.3.0); do not edit by hand.
/// erf(x)/x in s = x^2 for |x| < 1: degree 11; relative errors: fit 8.7e-18, in f64 4.2e-17.
#[allow(clippy::approx_constant)]
const ERF_SMALL: [f64; 12] = [
    -7.795898827002142e-10,
    1.3720064546777686e-08,
    -1.6208483801871705e-07,
    1.6447424703317362e-06,
    -1.492473690741966e-05,
    0.00012055294904839707,
    -0.0008548325975389692,
    0.0052239776071164225,
    -0.02686617064323777,
    0.11283791670945006,
    -0.37612638903183543,
    1.1283791670955126,
];
/// exp(x^2) erfc(x) for 1 <= x < 2.5: degree 18; relative errors: fit 6.7e-18, in f64 1.7e-16.
#[allow(clippy::approx_constant)]
const ERFC_MIDDLE: [f64; 19] = [
    1.691370878456324e-12,
    -9.189420172081477e-12,
    4.093847922889574e-11,
    -2.1212376757225127e-10,
    1.0913862125386419e-09,
    -5.4141292740262066e-09,
    2.6200160920446488e-08,
    -1.236598236632184e-07,
    5.680167343563448e-07,
    -2.5345110647073046e-06,
    1.0962893607629422e-05,
    -4.5856167052362756e-05,
    0.00018495607833968411,
    -0.0007168914456252124,
    0.0026591791241936573,
    -0.009390935492459373,
    0.031367041923986594,
    -0.09823225913586393,
    0.2849722347374364,
];
/// x exp(x^2) erfc(x) in s = 1/x^2 for x >= 2.5: degree 20; relative errors: fit 9.5e-18, in f64 1.7e-16.
#[allow(clippy::approx_constant)]
const ERFC_TAIL: [f64; 21] = [
    5.535532645473946e-12,
    -1.1716224404369269e-11,
    -3.784324322909503e-12,
    5.83359443327414e-12,
    5.811442103172021e-11,
    -1.357241494851904e-10,
    2.448612633381756e-10,
    -6.426163150300312e-10,
    1.8075621077331612e-09,
    -5.0505324852502785e-09,
    1.4728751805057906e-08,
    -4.5334116842909424e-08,
    1.480220316251188e-07,
    -5.17944962059009e-07,
    1.9692797860761e-06,
    -8.292070216759446e-06,
    3.975598621185544e-05,
    -0.00022669010254893228,
    0.0016592352014063224,
    -0.018351285410848493,
    0.5439016215198309,
];
/// erfinv(y)/y in w for w < 6.25: degree 24; relative errors: fit 7.7e-18, in f64 2.3e-16.
#[allow(clippy::approx_constant)]
const ERFINV_CENTRAL: [f64; 25] = [
    -2.7032254091069344e-10,
    7.689312733742569e-10,
    1.5401738716654886e-09,
    -8.562787796742932e-09,
    4.792369996100387e-09,
    3.915473114023045e-08,
    -9.867713140174249e-08,
    -1.0185147576818285e-08,
    5.394320648707009e-07,
    -1.059321402540731e-06,
    -6.83718721812117e-07,
    7.1300572630824496e-06,
    -1.1257319182677936e-05,
    -1.5027710420277575e-05,
    9.33673917780479e-05,
    -0.0001168888399309713,
    -0.0002643936684366174,
    0.0012324855686812834,
    -0.0012716922684373015,
    -0.00413731437741443,
    0.017808361818295655,
    -0.022604447453449802,
    -0.05892256710377784,
    0.7504943200799635,
    1.6536545626831027,
];
/// erfinv(y)/y in sqrt(w) for 6.25 <= w < 16: degree 20; relative errors: fit 1.6e-18, in f64 1.7e-16.
#[allow(clippy::approx_constant)]
const ERFINV_TAIL: [f64; 21] = [
    2.4355543452655723e-11,
    -6.471554767207546e-11,
    -1.179100761769929e-10,
    9.891297510532429e-10,
    -2.4605291139227303e-09,
    -3.6906087078089294e-10,
    2.63990323529153e-08,
    -9.468946844911027e-08,
    9.289338749101434e-08,
    5.264621626938461e-07,
    -2.664793846715906e-06,
    5.127316786334848e-06,
    2.405864805789804e-06,
    -4.7391827316182325e-05,
    0.00016966502197543766,
    -0.00040063569835358583,
    0.0007883078513066945,
    -0.0015825410894073097,
    0.0030211394363747063,
    0.753944225770624,
    3.0838856104922208,
];
/// erfinv(y)/y in sqrt(w) for 16 <= w <= 36.1: degree 18; relative errors: fit 7.1e-18, in f64 1.6e-16.
#[allow(clippy::approx_constant)]
const ERFINV_FAR_TAIL: [f64; 19] = [
    -2.1538713688085182e-11,
    4.4748796433508845e-11,
    7.584876822803962e-11,
    -4.6562362701570175e-10,
    1.3823554923051656e-09,
    -3.6066428361020885e-09,
    8.061351092195895e-09,
    -1.5626643590842678e-08,
    2.9637689564882207e-08,
    -6.916205707196457e-08,
    2.3524555480981256e-07,
    -1.0188859289837075e-06,
    4.627895607275658e-06,
    -2.0040082722510053e-05,
    7.702638881687432e-05,
    -0.00021673389058913278,
    -0.0001433562777342593,
    1.015350556889949,
    4.854957900238093,
];
