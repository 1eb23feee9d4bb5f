//! SPPM's photon budget: how many photons each iteration emits, from what the last iterations
//! measured (`PhotonBudget`).

use super::SppmConfig;

/// How many photons each iteration emits. With `SppmConfig::adaptive_photons`, the number
/// follows the error budget: every `WINDOW` iterations it is set to the number that makes the
/// error after a given time least, given what the last window measured (all of it the same for
/// any thread count, so the image is too):
/// - the variance of one iteration's direct light (emitted and directly sampled light, from the
///   camera pass) around each pixel's running mean, summed over the pixels: d;
/// - the same of one iteration's photon estimate (the flux gathered within the pixel's radius
///   over its disc): p, at P photons per iteration; it falls as 1/P, so p = s / P;
/// - the cost of the camera pass (its rays, and one more per visible point for its gather):
///   c, and of a photon (its rays: the first, and one per stored bounce): k.
///
/// Each pixel's error after time T is about (d + s/P) (c + k P) / T, least at
/// P = sqrt(s c / (d k)): few photons where direct light's variance dominates (more camera
/// samples, and so more direct-light samples, per second), many where the photons' does. Costs
/// are counted in rays, not seconds, to keep the choice independent of the machine's load and
/// thread count.
pub(super) struct PhotonBudget {
    /// Photons the next iteration emits.
    pub(super) photons: u64,
    adaptive: bool,
    /// Bounds, and the granularity of the number (a 64th of the configured number).
    min: u64,
    max: u64,
    step: u64,
    /// Sums over the current window (variances in the fixed point of `fixed_square`).
    direct: u64,
    photon: u64,
    camera_rays: u64,
    photon_rays: u64,
    photons_traced: u64,
    iterations: u32,
    /// Photons emitted by the run so far.
    pub(super) emitted: u64,
}

impl PhotonBudget {
    pub(super) const WINDOW: u32 = 4;
    pub(super) const MAX_FACTOR: u64 = 4;
    pub(super) const MIN_DIVISOR: u64 = 16;

    pub(super) fn new(config: &SppmConfig) -> Self {
        let p = config.photons_per_iter;
        PhotonBudget {
            photons: p,
            adaptive: config.adaptive_photons,
            min: (p / Self::MIN_DIVISOR).max(1),
            max: p.saturating_mul(Self::MAX_FACTOR),
            step: (p / 64).max(1),
            direct: 0,
            photon: 0,
            camera_rays: 0,
            photon_rays: 0,
            photons_traced: 0,
            iterations: 0,
            emitted: 0,
        }
    }

    /// Records an iteration's measurements (`measured`: false for a run's first iteration,
    /// which has no running means yet) and, at the end of a window, sets the photons of the
    /// next.
    pub(super) fn record(&mut self, measured: bool, m: IterationCosts) {
        self.emitted += m.photons;
        if !self.adaptive || !measured {
            return;
        }
        self.direct = self.direct.saturating_add(m.direct);
        self.photon = self.photon.saturating_add(m.photon);
        self.camera_rays += m.camera_rays;
        self.photon_rays += m.photon_rays;
        self.photons_traced += m.photons;
        self.iterations += 1;
        if self.iterations < Self::WINDOW {
            return;
        }
        let (d, p) = (self.direct as f64, self.photon as f64);
        let mean_photons = self.photons_traced as f64 / f64::from(self.iterations);
        let c = self.camera_rays as f64 / f64::from(self.iterations);
        let k = self.photon_rays as f64 / self.photons_traced.max(1) as f64;
        let best = if d <= 0.0 {
            f64::INFINITY
        } else if p <= 0.0 || k <= 0.0 {
            0.0
        } else {
            (p * mean_photons * c / (d * k)).sqrt()
        };
        // At most a factor of four per window, in steps of `step`.
        let current = self.photons as f64;
        let best = best.clamp(current / 4.0, current * 4.0);
        let rounded = ((best / self.step as f64).round() as u64).saturating_mul(self.step);
        self.photons = rounded.clamp(self.min, self.max);
        *self = PhotonBudget {
            direct: 0,
            photon: 0,
            camera_rays: 0,
            photon_rays: 0,
            photons_traced: 0,
            iterations: 0,
            ..*self
        };
    }
}

/// What one iteration measured for `PhotonBudget`.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct IterationCosts {
    pub(super) direct: u64,
    pub(super) photon: u64,
    pub(super) camera_rays: u64,
    pub(super) photon_rays: u64,
    pub(super) photons: u64,
}

/// A squared deviation in fixed point (2^-32 units, at most 2^40 per pixel), so that sums over
/// pixels are integers whose value does not depend on the order of the additions (a sum in
/// floating point over a parallel reduction would change with the thread count). Saturating
/// sums of non-negative numbers are also order-independent.
#[inline]
pub(super) fn fixed_square(x: f32) -> u64 {
    let v = f64::from(x) * f64::from(x) * 4_294_967_296.0;
    if v.is_finite() { v.min(1_099_511_627_776.0) as u64 } else { 0 }
}
