//! Texture images: PNG, JPEG, BMP, TGA, OpenEXR, Radiance HDR and PFM files read into linear
//! float texels, with the channel and colour rules of Mitsuba 3's `bitmap` texture.
//!
//! - Grey and grey+alpha give 1 channel; RGB, RGBA and palette images give 3. Alpha is dropped,
//!   not premultiplied.
//! - 8- and 16-bit formats hold sRGB-encoded values: integers are divided by their maximum (255,
//!   65535, 31 for 5-bit TGA/BMP fields) and decoded with the exact sRGB EOTF, unless `raw`.
//!   Float formats are linear and `raw` changes nothing. PNG `gAMA`/`iCCP` chunks and JPEG ICC
//!   profiles are ignored, as the rule above leaves no room for them.
//! - Row 0 is the top row of the picture, whatever order the file stores its rows in.
//!
//! Departure from Mitsuba 3: 16-bit values are decoded with the exact curve, through a table of
//! all 65536 values; Mitsuba's 16-bit conversion approximates the curve (0x8000 gives 0.213989
//! there, 0.2140482 here). 8-bit values agree exactly (128 gives 0.2158605 in both).
//!
//! Decoders: the `png` and `exr` crates (already used to write images), `zune-jpeg` for JPEG,
//! and our own readers for the small formats (BMP, TGA, Radiance HDR, PFM). The choice was
//! measured: compile time and decode speed are in BENCHMARKS.md, "Texture decoders (issue 11)".
//!
//! Every file is untrusted: a malformed, truncated or hostile file gives an [`ImageError`] naming
//! the file, never a panic, and the declared size is checked against [`MAX_TEXELS`] (and the
//! file's length, where the format bounds how much a byte can hold) before texels are allocated.

mod bmp;
mod jpeg;
mod openexr;
mod pfm;
mod png;
mod radiance;
mod tga;

#[cfg(test)]
mod test_writers;
#[cfg(test)]
mod tests;

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::LazyLock;

/// Largest image accepted, in texels (width x height); refused before any pixel memory is allocated.
pub const MAX_TEXELS: u64 = 1 << 28;

/// Linear texels of an image, row 0 = the top row of the file, `channels` values per texel.
#[derive(Clone, Debug, PartialEq)]
pub struct TexImage {
    pub width: u32,
    pub height: u32,
    /// 1 (grey) or 3 (RGB).
    pub channels: u32,
    /// Row-major, `width * height * channels` values.
    pub texels: Vec<f32>,
}

impl TexImage {
    /// The `channels` values of the texel in column `x` of row `y` (row 0 at the top).
    ///
    /// Panics if `x >= width` or `y >= height`: texture lookups clamp or wrap first.
    pub fn texel(&self, x: u32, y: u32) -> &[f32] {
        assert!(x < self.width && y < self.height, "texel ({x}, {y}) outside a {}x{} image", self.width, self.height);
        let c = self.channels as usize;
        let start = (y as usize * self.width as usize + x as usize) * c;
        &self.texels[start..start + c]
    }

    /// A black image whose declared size has been checked: at least one texel, at most
    /// [`MAX_TEXELS`]. Decoders call this before allocating anything of the image's size.
    fn allocate(width: u64, height: u64, channels: u32) -> Result<TexImage, Problem> {
        if width == 0 || height == 0 {
            return Err(Problem::Damaged(format!("the image has no texels ({width} x {height})")));
        }
        if width.saturating_mul(height) > MAX_TEXELS {
            return Err(Problem::TooLarge { width, height });
        }
        let len = (width * height) as usize * channels as usize;
        Ok(TexImage { width: width as u32, height: height as u32, channels, texels: vec![0.0; len] })
    }

    /// The texels of row `y` (row 0 at the top), for decoders to fill.
    fn row_mut(&mut self, y: u32) -> &mut [f32] {
        let row_len = self.width as usize * self.channels as usize;
        &mut self.texels[y as usize * row_len..(y as usize + 1) * row_len]
    }
}

/// The file formats read, recognised by their magic bytes (TGA, which has none, by its
/// extension or its version 2 footer).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    Png,
    Jpeg,
    Bmp,
    Tga,
    OpenExr,
    RadianceHdr,
    Pfm,
}

impl fmt::Display for ImageFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ImageFormat::Png => "PNG",
            ImageFormat::Jpeg => "JPEG",
            ImageFormat::Bmp => "BMP",
            ImageFormat::Tga => "TGA",
            ImageFormat::OpenExr => "OpenEXR",
            ImageFormat::RadianceHdr => "Radiance HDR",
            ImageFormat::Pfm => "PFM",
        })
    }
}

/// Why an image could not be read. Every message starts with the file: "`path`: ...".
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    #[error("`{}`: no such file", path.display())]
    Missing { path: PathBuf },
    #[error("`{}`: cannot be read: {source}", path.display())]
    Unreadable { path: PathBuf, source: std::io::Error },
    #[error("`{}`: not an image caustic can read: {detail}", path.display())]
    UnknownFormat { path: PathBuf, detail: String },
    #[error("`{}`: truncated {format} file: {detail}", path.display())]
    Truncated { path: PathBuf, format: ImageFormat, detail: String },
    #[error("`{}`: damaged {format} file: {detail}", path.display())]
    Damaged { path: PathBuf, format: ImageFormat, detail: String },
    #[error("`{}`: unsupported {format} variant: {detail}", path.display())]
    Unsupported { path: PathBuf, format: ImageFormat, detail: String },
    #[error("`{}`: a {width} x {height} {format} image is too large (at most {MAX_TEXELS} texels)", path.display())]
    TooLarge { path: PathBuf, format: ImageFormat, width: u64, height: u64 },
}

/// What a format's decoder found wrong; [`decode_image`] adds the file's path and format.
#[derive(Debug)]
enum Problem {
    Truncated(String),
    Damaged(String),
    Unsupported(String),
    TooLarge { width: u64, height: u64 },
}

impl Problem {
    /// The file ends inside row `row` (0-based, in the order the file stores rows) of `height`.
    fn ends_in_row(row: u64, height: u64) -> Problem {
        Problem::Truncated(format!("the file ends in row {} of {height}", row + 1))
    }

    /// The same for formats that store the bottom row first.
    fn ends_in_row_from_bottom(row: u64, height: u64) -> Problem {
        Problem::Truncated(format!("the file ends in row {} of {height}, counted from the bottom", row + 1))
    }

    fn into_error(self, path: &Path, format: ImageFormat) -> ImageError {
        let path = path.to_path_buf();
        match self {
            Problem::Truncated(detail) => ImageError::Truncated { path, format, detail },
            Problem::Damaged(detail) => ImageError::Damaged { path, format, detail },
            Problem::Unsupported(detail) => ImageError::Unsupported { path, format, detail },
            Problem::TooLarge { width, height } => ImageError::TooLarge { path, format, width, height },
        }
    }
}

/// Reads an image file. 8- and 16-bit formats (PNG, JPEG, BMP, TGA) hold sRGB-encoded values
/// and are decoded with the exact sRGB EOTF (c <= 0.04045 ? c/12.92 : ((c+0.055)/1.055)^2.4) unless
/// `raw`; float formats (OpenEXR, Radiance .hdr RGBE, PFM) are linear and `raw` changes nothing.
pub fn load_image(path: &Path, raw: bool) -> Result<TexImage, ImageError> {
    let bytes = std::fs::read(path).map_err(|source| match source.kind() {
        std::io::ErrorKind::NotFound => ImageError::Missing { path: path.to_path_buf() },
        _ => ImageError::Unreadable { path: path.to_path_buf(), source },
    })?;
    decode_image(&bytes, path, raw)
}

/// The same from the file's bytes (`path` only names it in messages and gives the extension as a hint);
/// the format is recognised by its magic bytes first.
pub fn decode_image(bytes: &[u8], path: &Path, raw: bool) -> Result<TexImage, ImageError> {
    let format = recognise(bytes, path)?;
    let decoded = match format {
        ImageFormat::Png => png::decode(bytes, raw),
        ImageFormat::Jpeg => jpeg::decode(bytes, raw),
        ImageFormat::Bmp => bmp::decode(bytes, raw),
        ImageFormat::Tga => tga::decode(bytes, raw),
        ImageFormat::OpenExr => openexr::decode(bytes),
        ImageFormat::RadianceHdr => radiance::decode(bytes),
        ImageFormat::Pfm => pfm::decode(bytes),
    };
    decoded.map_err(|problem| problem.into_error(path, format))
}

/// The format of `bytes`: magic bytes first, then the extension for TGA (which has no magic).
fn recognise(bytes: &[u8], path: &Path) -> Result<ImageFormat, ImageError> {
    let unknown = |detail: String| ImageError::UnknownFormat { path: path.to_path_buf(), detail };
    if bytes.is_empty() {
        return Err(unknown("the file is empty".into()));
    }
    let magic: [(&[u8], ImageFormat); 7] = [
        (b"\x89PNG\r\n\x1a\n", ImageFormat::Png),
        (b"\xff\xd8\xff", ImageFormat::Jpeg),
        (b"v/1\x01", ImageFormat::OpenExr),
        (b"#?", ImageFormat::RadianceHdr),
        (b"PF", ImageFormat::Pfm),
        (b"Pf", ImageFormat::Pfm),
        (b"BM", ImageFormat::Bmp),
    ];
    if let Some(&(_, format)) = magic.iter().find(|(m, _)| bytes.starts_with(m)) {
        return Ok(format);
    }
    let extension = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    if matches!(extension.as_str(), "tga" | "tpic" | "icb" | "vda" | "vst") || tga::has_footer(bytes) {
        return Ok(ImageFormat::Tga);
    }
    let claimed = match extension.as_str() {
        "png" => Some(ImageFormat::Png),
        "jpg" | "jpeg" | "jpe" | "jfif" => Some(ImageFormat::Jpeg),
        "bmp" | "dib" => Some(ImageFormat::Bmp),
        "exr" => Some(ImageFormat::OpenExr),
        "hdr" | "rgbe" | "pic" => Some(ImageFormat::RadianceHdr),
        "pfm" => Some(ImageFormat::Pfm),
        _ => None,
    };
    Err(unknown(match claimed {
        Some(format) => format!("its name says {format} but it does not start like a {format} file"),
        None => "it is none of PNG, JPEG, BMP, TGA, OpenEXR, Radiance HDR or PFM".into(),
    }))
}

/// The sRGB EOTF: an encoded value in [0, 1] to linear.
fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

/// Integer values to linear texels: a table per bit depth, sRGB-decoded unless raw.
#[derive(Clone, Copy)]
struct Transfer {
    table8: &'static [f32; 256],
    table16: &'static [f32],
    raw: bool,
}

static SRGB8: LazyLock<[f32; 256]> = LazyLock::new(|| std::array::from_fn(|i| srgb_to_linear(i as f64 / 255.0) as f32));
static RAW8: LazyLock<[f32; 256]> = LazyLock::new(|| std::array::from_fn(|i| (i as f64 / 255.0) as f32));
static SRGB16: LazyLock<Vec<f32>> =
    LazyLock::new(|| (0..=u16::MAX).map(|i| srgb_to_linear(i as f64 / 65535.0) as f32).collect());
static RAW16: LazyLock<Vec<f32>> = LazyLock::new(|| (0..=u16::MAX).map(|i| (i as f64 / 65535.0) as f32).collect());

impl Transfer {
    fn new(raw: bool) -> Transfer {
        if raw {
            Transfer { table8: &RAW8, table16: &RAW16, raw }
        } else {
            Transfer { table8: &SRGB8, table16: &SRGB16, raw }
        }
    }

    fn linear_u8(&self, v: u8) -> f32 {
        self.table8[v as usize]
    }

    /// Texels from interleaved 8-bit pixels of `S` samples, keeping the first `C` (alpha is last).
    fn u8_texels<const S: usize, const C: usize>(&self, pixels: &[u8], out: &mut [f32]) {
        for (pixel, texel) in pixels.chunks_exact(S).zip(out.chunks_exact_mut(C)) {
            for c in 0..C {
                texel[c] = self.table8[pixel[c] as usize];
            }
        }
    }

    /// Texels from interleaved big-endian 16-bit pixels of `S` samples, keeping the first `C`.
    fn u16_be_texels<const S: usize, const C: usize>(&self, pixels: &[u8], out: &mut [f32]) {
        for (pixel, texel) in pixels.chunks_exact(2 * S).zip(out.chunks_exact_mut(C)) {
            for c in 0..C {
                texel[c] = self.table16[u16::from_be_bytes([pixel[2 * c], pixel[2 * c + 1]]) as usize];
            }
        }
    }

    /// RGB texels from B, G, R(, X) pixels of `S` bytes, as BMP and TGA store them.
    fn bgr_texels<const S: usize>(&self, pixels: &[u8], out: &mut [f32]) {
        for (pixel, texel) in pixels.chunks_exact(S).zip(out.chunks_exact_mut(3)) {
            texel[0] = self.table8[pixel[2] as usize];
            texel[1] = self.table8[pixel[1] as usize];
            texel[2] = self.table8[pixel[0] as usize];
        }
    }

    /// A value of `bits` bits (1 to 16), divided by its maximum.
    fn linear_bits(&self, v: u32, bits: u32) -> f32 {
        let max = ((1u32 << bits) - 1) as f64;
        let c = (v as f64 / max).min(1.0);
        (if self.raw { c } else { srgb_to_linear(c) }) as f32
    }
}

/// A cursor over the bytes of a file, for the formats read by hand. Reads return `None` at the
/// end of the file; callers turn that into a message saying where the file ended.
struct Bytes<'a> {
    data: &'a [u8],
    pos: usize,
}

impl<'a> Bytes<'a> {
    fn new(data: &'a [u8]) -> Bytes<'a> {
        Bytes { data, pos: 0 }
    }

    fn remaining(&self) -> usize {
        self.data.len() - self.pos
    }

    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let slice = self.data.get(self.pos..self.pos.checked_add(n)?)?;
        self.pos += n;
        Some(slice)
    }

    fn u8(&mut self) -> Option<u8> {
        self.take(1).map(|b| b[0])
    }

    fn u16_le(&mut self) -> Option<u16> {
        self.take(2).map(|b| u16::from_le_bytes([b[0], b[1]]))
    }

    fn u32_le(&mut self) -> Option<u32> {
        self.take(4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    fn i32_le(&mut self) -> Option<i32> {
        self.u32_le().map(|v| v as i32)
    }
}
