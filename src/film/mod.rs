//! The film accumulates radiance samples per pixel; `Image` is the finished linear picture.
//!
//! Sums are exact integers (see [`fixed`]): the image is the same bit for bit whatever the
//! thread count, the split of samples into passes, a checkpoint and resume in between, or the
//! machines a render farm spreads the samples over. The film is stored tile by tile so that each
//! tile is owned by one worker while it renders.

pub mod aov;
pub mod filter;
pub mod fixed;
pub mod output;
pub mod splat;

use crate::math::Color;
use aov::{AovKind, AovList};
use fixed::{FixedRgb, add_rgb, mean, to_fixed, to_fixed_rgb};

/// The light arriving along a camera ray, split by where it came from. The parts sum to the
/// pixel's value:
/// - `DIRECT`: emission seen directly and light sampled at the first non-specular surface;
/// - `SPECULAR`: everything seen through mirrors and glass (camera paths starting with S+);
/// - `CAUSTIC`: light reaching the first non-specular surface through mirrors and glass (L S+ D);
/// - `INDIRECT`: light reaching it after at least one more non-specular bounce.
pub type Layers = [Color; 4];
pub const DIRECT: usize = 0;
pub const SPECULAR: usize = 1;
pub const CAUSTIC: usize = 2;
pub const INDIRECT: usize = 3;
pub const LAYER_NAMES: [&str; 4] = ["direct", "specular", "caustic", "indirect"];

pub const TILE_SIZE: u32 = 16;

/// Bytes the film keeps per pixel, without and with the four layers.
pub const BYTES_PER_PIXEL: u64 = 48 + 4;
pub const LAYER_BYTES_PER_PIXEL: u64 = 4 * 48;

/// A window of the film, in pixels: what a cropped render computes (Mitsuba's `crop_offset_x/y`,
/// `crop_width/height`). The image is the window; the camera still spans the whole film.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Crop {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

impl Crop {
    /// The whole of a `width` x `height` film.
    pub fn full(width: u32, height: u32) -> Self {
        Crop { x: 0, y: 0, width, height }
    }

    /// Whether the window lies inside a `width` x `height` film and is not empty.
    pub fn fits(&self, width: u32, height: u32) -> bool {
        self.width > 0
            && self.height > 0
            && self.x as u64 + self.width as u64 <= width as u64
            && self.y as u64 + self.height as u64 <= height as u64
    }

    /// The same window of the film resized from `from` to `to` (width, height): the edges scale
    /// and round outwards, so the window still covers what it covered.
    pub fn rescaled(&self, from: (u32, u32), to: (u32, u32)) -> Self {
        let axis = |x: u32, w: u32, from: u32, to: u32| {
            let s = to as f64 / from as f64;
            let x0 = ((x as f64 * s).floor() as u32).min(to.saturating_sub(1));
            let x1 = (((x + w) as f64 * s).ceil() as u32).clamp(x0 + 1, to);
            (x0, x1 - x0)
        };
        let (x, width) = axis(self.x, self.width, from.0, to.0);
        let (y, height) = axis(self.y, self.height, from.1, to.1);
        Crop { x, y, width, height }
    }
}

/// A rectangle of pixels with its accumulated sums.
#[derive(Clone, Debug, PartialEq)]
pub struct Tile {
    pub x0: u32,
    pub y0: u32,
    pub width: u32,
    pub height: u32,
    /// Exact per-pixel sums of the samples.
    pub sum: Vec<FixedRgb>,
    /// Samples taken per pixel (non-finite ones count as black).
    pub count: Vec<u32>,
    /// Per-pixel sums of the four layers (empty when layers are not wanted).
    pub layers: Vec<[FixedRgb; 4]>,
    /// Per-pixel sums of the AOVs (`film::aov`), `aov_stride` per pixel: the first `aov_hits`
    /// are first-hit values, the rest the sums of squares of the samples' RGB (for `variance`).
    pub aov: Vec<i128>,
    pub aov_stride: u32,
    pub aov_hits: u32,
}

impl Tile {
    /// Adds one sample (its layers) to pixel `k` of the tile. A sample that is not finite counts
    /// as black (as pbrt-v4 does), so the pixel still has the number of samples it was given and
    /// one bad value cannot spoil it; `false` tells the caller to report it.
    #[inline(always)]
    pub fn add(&mut self, k: usize, layers: &Layers) -> bool {
        self.count[k] += 1;
        let c = layers[0] + layers[1] + layers[2] + layers[3];
        if !c.is_finite() {
            return false;
        }
        add_rgb(&mut self.sum[k], &to_fixed_rgb(c));
        if self.aov_stride > self.aov_hits {
            let at = k * self.aov_stride as usize + self.aov_hits as usize;
            for (acc, v) in self.aov[at..at + 3].iter_mut().zip(c.to_array()) {
                *acc += to_fixed(v * v);
            }
        }
        if let Some(l) = self.layers.get_mut(k) {
            for (acc, v) in l.iter_mut().zip(layers) {
                add_rgb(acc, &to_fixed_rgb(*v));
            }
        }
        true
    }
}

impl Tile {
    /// Adds a camera sample's first-hit AOV values (`AovList::first_hit_values`), weighted as
    /// its radiance was (the filter's sign and normalisation), to pixel `k`.
    #[inline]
    pub fn add_first_hit(&mut self, k: usize, values: &[f32], weight: f32) {
        let at = k * self.aov_stride as usize;
        for (acc, v) in self.aov[at..at + self.aov_hits as usize].iter_mut().zip(values) {
            *acc += to_fixed(v * weight);
        }
    }
}

/// Per-pixel exact sums and sample counts of a render, tile by tile.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    pub tiles: Vec<Tile>,
    /// The AOVs the tiles hold sums for (none unless `with_aovs`).
    pub aovs: AovList,
}

impl Film {
    pub fn new(width: u32, height: u32, layers: bool) -> Self {
        let mut tiles = Vec::new();
        for y0 in (0..height).step_by(TILE_SIZE as usize) {
            for x0 in (0..width).step_by(TILE_SIZE as usize) {
                let w = TILE_SIZE.min(width - x0);
                let h = TILE_SIZE.min(height - y0);
                let n = (w * h) as usize;
                let layers = if layers { vec![[[0; 3]; 4]; n] } else { Vec::new() };
                tiles.push(Tile {
                    x0,
                    y0,
                    width: w,
                    height: h,
                    sum: vec![[0; 3]; n],
                    count: vec![0; n],
                    layers,
                    aov: Vec::new(),
                    aov_stride: 0,
                    aov_hits: 0,
                });
            }
        }
        Film { width, height, tiles, aovs: AovList::default() }
    }

    /// The film with room for the sums of `aovs`, all zero (the film must hold none yet).
    pub fn with_aovs(mut self, aovs: &AovList) -> Self {
        let (stride, hits) = (aovs.summed_channels() as u32, aovs.first_hit_channels() as u32);
        for t in &mut self.tiles {
            t.aov = vec![0; t.count.len() * stride as usize];
            t.aov_stride = stride;
            t.aov_hits = hits;
        }
        self.aovs = aovs.clone();
        self
    }

    /// Each AOV channel's image (`AovList::channel_names` order), row by row: first-hit values
    /// as the mean of the pixel's samples, `variance` as the variance of the pixel's mean
    /// (the samples' unbiased variance over their count; 0 below two samples), `spp` the count.
    pub fn aov_images(&self) -> Vec<(String, Vec<f32>)> {
        let n = (self.width * self.height) as usize;
        let names = self.aovs.channel_names();
        let mut out: Vec<Vec<f32>> = vec![vec![0.0; n]; names.len()];
        let scale = (1u64 << fixed::FRACTION_BITS) as f64;
        for t in &self.tiles {
            for j in 0..t.height {
                for i in 0..t.width {
                    let k = (j * t.width + i) as usize;
                    let p = ((t.y0 + j) * self.width + t.x0 + i) as usize;
                    let count = t.count[k] as f64;
                    let sums = &t.aov[k * t.aov_stride as usize..(k + 1) * t.aov_stride as usize];
                    let (mut hit, mut ch) = (0usize, 0usize);
                    for a in &self.aovs.0 {
                        for c in 0..a.kind.channels().len() {
                            out[ch][p] = match a.kind {
                                AovKind::Spp => t.count[k] as f32,
                                AovKind::Variance => {
                                    let s = t.sum[k][c] as f64 / scale;
                                    let s2 = sums[t.aov_hits as usize + c] as f64 / scale;
                                    if count < 2.0 {
                                        0.0
                                    } else {
                                        ((s2 - s * s / count) / (count * (count - 1.0))).max(0.0) as f32
                                    }
                                }
                                _ => {
                                    hit += 1;
                                    if count > 0.0 { (sums[hit - 1] as f64 / scale / count) as f32 } else { 0.0 }
                                }
                            };
                            ch += 1;
                        }
                    }
                }
            }
        }
        names.into_iter().zip(out).collect()
    }

    /// A film holding `n` samples per pixel whose means are `image` and `layers` (the four
    /// layers, or none): how a progressive method whose result is not a sum of samples (SPPM)
    /// stores its image for checkpoints and merging.
    pub fn from_means(image: &Image, layers: &[Image], n: u32) -> Self {
        let mut film = Film::new(image.width, image.height, layers.len() == 4);
        let times = |c: Color| to_fixed_rgb(c).map(|v| v * n as i128);
        for t in &mut film.tiles {
            for j in 0..t.height {
                for i in 0..t.width {
                    let (x, y) = (t.x0 + i, t.y0 + j);
                    let k = (j * t.width + i) as usize;
                    t.sum[k] = times(image.get(x, y));
                    t.count[k] = n;
                    if let Some(l) = t.layers.get_mut(k) {
                        for (acc, img) in l.iter_mut().zip(layers) {
                            *acc = times(img.get(x, y));
                        }
                    }
                }
            }
        }
        film
    }

    pub fn has_layers(&self) -> bool {
        self.tiles.first().is_some_and(|t| !t.layers.is_empty())
    }

    /// Adds another film's samples to this one (same size and layers; checked by the caller).
    pub fn add(&mut self, other: &Film) {
        for (a, b) in self.tiles.iter_mut().zip(&other.tiles) {
            for (s, o) in a.sum.iter_mut().zip(&b.sum) {
                add_rgb(s, o);
            }
            for (c, o) in a.count.iter_mut().zip(&b.count) {
                *c += *o;
            }
            for (l, o) in a.layers.iter_mut().zip(&b.layers) {
                for (s, o) in l.iter_mut().zip(o) {
                    add_rgb(s, o);
                }
            }
            for (s, o) in a.aov.iter_mut().zip(&b.aov) {
                *s += *o;
            }
        }
    }

    /// The average of the samples so far (black where a pixel has none yet).
    pub fn image(&self) -> Image {
        self.image_of(|t, k| mean(&t.sum[k], t.count[k]))
    }

    /// The average of layer `layer` (see [`Layers`]); black when the film keeps no layers.
    pub fn layer_image(&self, layer: usize) -> Image {
        self.image_of(|t, k| t.layers.get(k).map_or(Color::ZERO, |l| mean(&l[layer], t.count[k])))
    }

    fn image_of(&self, value: impl Fn(&Tile, usize) -> Color) -> Image {
        let mut img = Image::new(self.width, self.height);
        for t in &self.tiles {
            for j in 0..t.height {
                for i in 0..t.width {
                    img.set(t.x0 + i, t.y0 + j, value(t, (j * t.width + i) as usize));
                }
            }
        }
        img
    }

    /// Fewest samples any pixel has.
    pub fn min_samples(&self) -> u32 {
        self.tiles.iter().flat_map(|t| t.count.iter().copied()).min().unwrap_or(0)
    }

    /// Most samples any pixel has.
    pub fn max_samples(&self) -> u32 {
        self.tiles.iter().flat_map(|t| t.count.iter().copied()).max().unwrap_or(0)
    }
}

/// A linear-light RGB image, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Color>,
}

impl Image {
    pub fn new(width: u32, height: u32) -> Self {
        Image { width, height, pixels: vec![Color::ZERO; (width * height) as usize] }
    }

    #[inline]
    pub fn get(&self, x: u32, y: u32) -> Color {
        self.pixels[(y * self.width + x) as usize]
    }

    #[inline]
    pub fn set(&mut self, x: u32, y: u32, c: Color) {
        self.pixels[(y * self.width + x) as usize] = c;
    }

    /// Mean of all pixels.
    pub fn mean(&self) -> Color {
        let s: glam::DVec3 = self.pixels.iter().map(|c| c.as_dvec3()).sum();
        Color::from_dvec3(s / self.pixels.len().max(1) as f64)
    }

    /// Root-mean-square difference per channel value against `other` (same size).
    pub fn rmse(&self, other: &Image) -> f64 {
        assert_eq!((self.width, self.height), (other.width, other.height));
        let s: f64 = self.pixels.iter().zip(&other.pixels).map(|(a, b)| (*a - *b).as_dvec3().length_squared()).sum();
        (s / (3 * self.pixels.len()).max(1) as f64).sqrt()
    }
}
