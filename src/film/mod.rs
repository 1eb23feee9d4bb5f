//! The film accumulates radiance samples per pixel; `Image` is the finished linear picture.
//!
//! The film is stored tile by tile, so each tile is owned by one worker while it renders and
//! every pixel adds its samples in sample-index order: the sums, and so the image, are the same
//! bit for bit whatever the thread count or the way samples are split into passes.

pub mod output;

use crate::math::Color;

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

/// A rectangle of pixels with its accumulated sums.
pub struct Tile {
    pub x0: u32,
    pub y0: u32,
    pub width: u32,
    pub height: u32,
    pub sum: Vec<Color>,
    /// Samples taken per pixel (non-finite ones count as black).
    pub count: Vec<u32>,
    /// Per-pixel sums of the four layers (empty when layers are not wanted).
    pub layers: Vec<[Color; 4]>,
}

impl Tile {
    /// Adds one sample (its layers) to pixel `k` of the tile. A sample that is not finite counts
    /// as black (as pbrt-v4 does), so the pixel still has the number of samples it was given and
    /// one bad value cannot spoil it; `false` tells the caller to report it.
    #[inline]
    pub fn add(&mut self, k: usize, layers: &Layers) -> bool {
        self.count[k] += 1;
        let c = layers[0] + layers[1] + layers[2] + layers[3];
        if !c.is_finite() {
            return false;
        }
        self.sum[k] += c;
        if let Some(l) = self.layers.get_mut(k) {
            for (acc, v) in l.iter_mut().zip(layers) {
                *acc += *v;
            }
        }
        true
    }
}

pub struct Film {
    pub width: u32,
    pub height: u32,
    pub tiles: Vec<Tile>,
}

impl Film {
    pub fn new(width: u32, height: u32, layers: bool) -> Self {
        let mut tiles = Vec::new();
        for y0 in (0..height).step_by(TILE_SIZE as usize) {
            for x0 in (0..width).step_by(TILE_SIZE as usize) {
                let w = TILE_SIZE.min(width - x0);
                let h = TILE_SIZE.min(height - y0);
                let n = (w * h) as usize;
                let layers = if layers { vec![[Color::ZERO; 4]; n] } else { Vec::new() };
                tiles.push(Tile { x0, y0, width: w, height: h, sum: vec![Color::ZERO; n], count: vec![0; n], layers });
            }
        }
        Film { width, height, tiles }
    }

    /// The average of the samples so far (black where a pixel has none yet).
    pub fn image(&self) -> Image {
        let mut img = Image::new(self.width, self.height);
        for t in &self.tiles {
            for j in 0..t.height {
                for i in 0..t.width {
                    let k = (j * t.width + i) as usize;
                    let c = if t.count[k] > 0 { t.sum[k] / t.count[k] as f32 } else { Color::ZERO };
                    img.set(t.x0 + i, t.y0 + j, c);
                }
            }
        }
        img
    }

    /// The average of layer `layer` (see `integrator::Layers`).
    pub fn layer_image(&self, layer: usize) -> Image {
        let mut img = Image::new(self.width, self.height);
        for t in &self.tiles {
            for j in 0..t.height {
                for i in 0..t.width {
                    let k = (j * t.width + i) as usize;
                    if let Some(l) = t.layers.get(k)
                        && t.count[k] > 0
                    {
                        img.set(t.x0 + i, t.y0 + j, l[layer] / t.count[k] as f32);
                    }
                }
            }
        }
        img
    }

    /// Fewest samples any pixel has.
    pub fn min_samples(&self) -> u32 {
        self.tiles.iter().flat_map(|t| t.count.iter().copied()).min().unwrap_or(0)
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
        (s / self.pixels.len().max(1) as f64).as_vec3()
    }

    /// Root-mean-square difference per channel value against `other` (same size).
    pub fn rmse(&self, other: &Image) -> f64 {
        assert_eq!((self.width, self.height), (other.width, other.height));
        let s: f64 = self.pixels.iter().zip(&other.pixels).map(|(a, b)| (*a - *b).as_dvec3().length_squared()).sum();
        (s / (3 * self.pixels.len()).max(1) as f64).sqrt()
    }
}
