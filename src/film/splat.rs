//! Contributions that land on any pixel (light tracing's connections to the camera; later the
//! splats of bidirectional methods), summed exactly as the film's own samples are, so an image
//! with splats is still the same bit for bit on any thread count, in any split of its work into
//! passes, shards and resumed runs.
//!
//! Any thread may add to any pixel, so each pixel's channel is a set of atomic integer sums:
//! a splat's fixed-point value (`fixed`, 48 fractional bits, at most 2^94 in magnitude) is cut
//! into three 32-bit digits, and each digit is added to a 64-bit atomic of its own, positive and
//! negative values apart (filters with negative lobes splat negative weights). Integer addition
//! is associative, so the order in which splats arrive does not matter, and `drain` rebuilds the
//! exact sums. Each atomic holds at most 2^32 digit additions before it could overflow, so the
//! film is drained at least every `MAX_SPLATS_PER_DRAIN` splats per pixel (callers drain after
//! every `DRAIN_PATHS` light paths, each splatting at most `MAX_SPLATS_PER_PATH` times).

use super::filter::FilterTable;
use super::fixed::{FixedRgb, add_rgb, to_fixed};
use super::{Film, Layers};
use crate::math::{Color, Vec2};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// Most splats a pixel may receive between drains.
pub const MAX_SPLATS_PER_DRAIN: u64 = 1 << 31;

/// Most splats one light path may make (its vertices connected to the camera, and its start).
pub const MAX_SPLATS_PER_PATH: u64 = 1 << 10;

/// Light paths a light tracer traces between drains: fewer than `MAX_SPLATS_PER_DRAIN` splats
/// can then land on one pixel.
pub const DRAIN_PATHS: u64 = 1 << 20;

const _: () = assert!(DRAIN_PATHS * MAX_SPLATS_PER_PATH < MAX_SPLATS_PER_DRAIN);

/// One channel's exact sum: three digits of the magnitudes of the positive and of the negative
/// values added.
#[derive(Debug, Default)]
struct ExactSum {
    pos: [AtomicU64; 3],
    neg: [AtomicU64; 3],
}

impl ExactSum {
    #[inline]
    fn add(&self, v: i128) {
        if v == 0 {
            return;
        }
        let (digits, m) = if v > 0 { (&self.pos, v as u128) } else { (&self.neg, v.unsigned_abs()) };
        for (k, d) in digits.iter().enumerate() {
            let digit = ((m >> (32 * k)) & 0xffff_ffff) as u64;
            if digit != 0 {
                d.fetch_add(digit, Ordering::Relaxed);
            }
        }
    }

    /// The sum so far, and zero for the next. Only digits read as nonzero are swapped: most
    /// are zero (the negative ones, and the top ones), and a swap is a locked instruction where
    /// a load is a plain one. A digit added to while this runs keeps the addition for the next
    /// take either way; callers take when no splats arrive.
    fn take(&self) -> i128 {
        let take = |d: &AtomicU64| if d.load(Ordering::Relaxed) == 0 { 0 } else { d.swap(0, Ordering::Relaxed) };
        let value = |digits: &[AtomicU64; 3]| -> i128 {
            digits.iter().enumerate().map(|(k, d)| (take(d) as i128) << (32 * k)).sum()
        };
        value(&self.pos) - value(&self.neg)
    }

    fn clear(&self) {
        for d in self.pos.iter().chain(&self.neg) {
            d.store(0, Ordering::Relaxed);
        }
    }
}

/// The splats of a render (see the module docs): one exact sum per channel of every pixel of the
/// image, and of each layer's when layers are kept.
pub struct SplatFilm {
    /// The image (a window of the full film): its size and its top-left pixel in the film.
    width: u32,
    height: u32,
    origin: (u32, u32),
    filter: FilterTable,
    /// Per pixel: the total's three channels, then each layer's (4 x 3) when layers are kept
    /// (the total is summed on its own, as the film sums camera samples, so the image is the
    /// same bit for bit with layers or without).
    sums: Vec<ExactSum>,
    layers: bool,
}

impl SplatFilm {
    /// Splats for an image of `width` x `height` pixels whose top-left pixel is `origin` in the
    /// full film, reconstructed with `filter`.
    pub fn new(width: u32, height: u32, origin: (u32, u32), filter: FilterTable, layers: bool) -> Self {
        let per_pixel = if layers { 15 } else { 3 };
        let sums = (0..width as usize * height as usize * per_pixel).map(|_| ExactSum::default()).collect();
        SplatFilm { width, height, origin, filter, sums, layers }
    }

    /// Bytes a splat film of `pixels` pixels holds.
    pub fn bytes(pixels: u64, layers: bool) -> u64 {
        pixels * if layers { 15 } else { 3 } * std::mem::size_of::<ExactSum>() as u64
    }

    /// Adds `value` (by layer) landing at film position `raster` (full-film pixels, x right, y
    /// down) to the pixels the filter reaches from there. Returns false, adding nothing, when
    /// the value is not finite.
    #[inline]
    pub fn add(&self, raster: Vec2, value: &Layers) -> bool {
        let total = value[0] + value[1] + value[2] + value[3];
        if !total.is_finite() {
            return false;
        }
        let (x, y) = (raster.x as f64 - self.origin.0 as f64, raster.y as f64 - self.origin.1 as f64);
        let r = self.filter.radius();
        let (x0, x1) = (((x - r).floor() as i64).max(0), ((x + r).floor() as i64).min(self.width as i64 - 1));
        let (y0, y1) = (((y - r).floor() as i64).max(0), ((y + r).floor() as i64).min(self.height as i64 - 1));
        for py in y0..=y1 {
            for px in x0..=x1 {
                let w = self.filter.splat_weight(x - (px as f64 + 0.5), y - (py as f64 + 0.5));
                if w == 0.0 {
                    continue;
                }
                let k = (py as usize) * self.width as usize + px as usize;
                let w = w as f32;
                if self.layers {
                    self.add_rgb(k * 15, total * w);
                    for (l, c) in value.iter().enumerate() {
                        if *c != Color::ZERO {
                            self.add_rgb(k * 15 + 3 + l * 3, *c * w);
                        }
                    }
                } else {
                    self.add_rgb(k * 3, total * w);
                }
            }
        }
        true
    }

    /// Adds `value` (by layer) to image pixel (`x`, `y`) alone, with no filter: a camera
    /// sample's own value (bidirectional methods add their camera paths' light here beside the
    /// light paths' splats, so both are summed exactly in one place). Returns false, adding
    /// nothing, when the value is not finite.
    #[inline]
    pub fn add_pixel(&self, x: u32, y: u32, value: &Layers) -> bool {
        let total = value[0] + value[1] + value[2] + value[3];
        if !total.is_finite() {
            return false;
        }
        debug_assert!(x < self.width && y < self.height);
        let k = y as usize * self.width as usize + x as usize;
        if self.layers {
            self.add_rgb(k * 15, total);
            for (l, c) in value.iter().enumerate() {
                if *c != Color::ZERO {
                    self.add_rgb(k * 15 + 3 + l * 3, *c);
                }
            }
        } else {
            self.add_rgb(k * 3, total);
        }
        true
    }

    #[inline]
    fn add_rgb(&self, at: usize, c: Color) {
        for (i, v) in c.to_array().into_iter().enumerate() {
            self.sums[at + i].add(to_fixed(v));
        }
    }

    /// Moves the splats into `film`'s exact sums (the total and, when kept, each layer), leaving
    /// this film empty. `film` is the image's film (same size and layers).
    pub fn drain_into(&self, film: &mut Film) {
        // Tiles on the thread pool: each takes its own pixels' sums (an image's worth of locked
        // swaps ran on one thread between every two passes of VCM).
        film.tiles.par_iter_mut().for_each(|tile| {
            for j in 0..tile.height {
                for i in 0..tile.width {
                    let (x, y) = (tile.x0 + i, tile.y0 + j);
                    let k = (y * self.width + x) as usize;
                    let t = (j * tile.width + i) as usize;
                    let per_pixel = if self.layers { 15 } else { 3 };
                    let sum = |at: usize| -> FixedRgb { std::array::from_fn(|c| self.sums[at + c].take()) };
                    add_rgb(&mut tile.sum[t], &sum(k * per_pixel));
                    if self.layers {
                        for l in 0..4 {
                            let v = sum(k * per_pixel + 3 + l * 3);
                            if let Some(layers) = tile.layers.get_mut(t) {
                                add_rgb(&mut layers[l], &v);
                            }
                        }
                    }
                }
            }
        });
    }

    /// Forgets every splat since the last drain (an interrupted pass).
    pub fn clear(&self) {
        self.sums.iter().for_each(ExactSum::clear);
    }
}
