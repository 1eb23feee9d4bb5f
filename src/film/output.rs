//! Writing images: 8-bit sRGB PNG (clamped) or 32-bit float linear OpenEXR, chosen by extension.
//! An EXR's colour channels are linear sRGB (R, G, B), or on request (`--xyz`) CIE 1931 XYZ
//! (X, Y, Z): the film's linear sRGB values times the sRGB-to-XYZ matrix, negative values kept.
//! The matrix is the exact inverse of the one spectral mode converts XYZ to sRGB with
//! (`spectrum::XYZ_TO_SRGB`), so a spectral render's XYZ comes back to float rounding.
//!
//! Files are written to a temporary name in the destination folder and renamed over the target,
//! so a crash or error never leaves a truncated image (and never destroys a previous one).

use super::Image;
use crate::math::Color;
use std::fs;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("output `{0}`: unsupported extension (use .png or .exr)")]
    Extension(String),
    #[error("output `{0}`: XYZ channels (--xyz) need an .exr output; a PNG is always sRGB")]
    XyzPng(String),
    #[error("cannot write `{path}`: {message}")]
    Write { path: String, message: String },
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Png,
    Exr,
}

impl Format {
    pub fn from_path(path: &Path) -> Result<Self, OutputError> {
        match path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).as_deref() {
            Some("png") => Ok(Format::Png),
            Some("exr") => Ok(Format::Exr),
            _ => Err(OutputError::Extension(path.display().to_string())),
        }
    }
}

/// What an EXR's colour channels hold.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ColourSpace {
    /// Linear sRGB, channels R, G, B (the default).
    #[default]
    LinearSrgb,
    /// CIE 1931 XYZ, channels X, Y, Z.
    Xyz,
}

impl ColourSpace {
    /// `Xyz` when `xyz`, else `LinearSrgb`.
    pub fn xyz_if(xyz: bool) -> Self {
        if xyz { ColourSpace::Xyz } else { ColourSpace::LinearSrgb }
    }

    /// The names of the colour channels.
    pub fn channel_names(self) -> [&'static str; 3] {
        match self {
            ColourSpace::LinearSrgb => ["R", "G", "B"],
            ColourSpace::Xyz => ["X", "Y", "Z"],
        }
    }

    /// A linear sRGB colour in this space.
    #[inline]
    pub fn convert(self, c: Color) -> [f32; 3] {
        match self {
            ColourSpace::LinearSrgb => c.to_array(),
            ColourSpace::Xyz => {
                let m = srgb_to_xyz();
                let c = c.to_array().map(f64::from);
                m.map(|row| (row[0] * c[0] + row[1] * c[1] + row[2] * c[2]) as f32)
            }
        }
    }

    /// An error when this space cannot be written to `path` (XYZ to a PNG).
    pub fn check(self, path: &Path) -> Result<(), OutputError> {
        if self == ColourSpace::Xyz && Format::from_path(path)? == Format::Png {
            return Err(OutputError::XyzPng(path.display().to_string()));
        }
        Ok(())
    }
}

/// Linear sRGB to CIE XYZ (rows): the inverse of `XYZ_TO_SRGB`, in double precision.
pub fn srgb_to_xyz() -> [[f64; 3]; 3] {
    let m = crate::spectrum::XYZ_TO_SRGB;
    let cof = |r: usize, c: usize| {
        let (r0, r1) = ((r + 1) % 3, (r + 2) % 3);
        let (c0, c1) = ((c + 1) % 3, (c + 2) % 3);
        m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0]
    };
    let det = m[0][0] * cof(0, 0) + m[0][1] * cof(0, 1) + m[0][2] * cof(0, 2);
    // The inverse is the transposed cofactor matrix over the determinant.
    std::array::from_fn(|r| std::array::from_fn(|c| cof(c, r) / det))
}

/// The sRGB transfer function applied to a linear value, clamped to [0, 1].
#[inline]
pub fn linear_to_srgb(v: f32) -> f32 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 }
}

/// `out.png` -> `out.direct.png` for layer `direct`.
pub fn layer_path(output: &Path, layer: &str) -> PathBuf {
    let stem = output.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let ext = output.extension().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    output.with_file_name(format!("{stem}.{layer}.{ext}"))
}

fn temp_path(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let ext = path.extension().map(|e| e.to_string_lossy().into_owned()).unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp.{ext}", std::process::id()))
}

fn write_err(path: &Path, e: impl std::fmt::Display) -> OutputError {
    OutputError::Write { path: path.display().to_string(), message: e.to_string() }
}

/// Checks, before rendering, that `path` has a known extension and that its folder accepts a new
/// file, by creating and removing the temporary file the final write will use.
pub fn check_writable(path: &Path) -> Result<Format, OutputError> {
    let format = Format::from_path(path)?;
    if path.is_dir() {
        return Err(write_err(path, "it is a directory"));
    }
    let tmp = temp_path(path);
    fs::File::create(&tmp).map_err(|e| write_err(path, e))?;
    let _ = fs::remove_file(&tmp);
    Ok(format)
}

/// Writes `img` to `path` atomically (temporary file, then rename).
pub fn write_image(img: &Image, path: &Path) -> Result<(), OutputError> {
    write_image_in(img, path, ColourSpace::LinearSrgb)
}

/// `write_image` with an EXR's colour channels in `space` (a PNG refuses XYZ).
pub fn write_image_in(img: &Image, path: &Path, space: ColourSpace) -> Result<(), OutputError> {
    let format = Format::from_path(path)?;
    space.check(path)?;
    if space != ColourSpace::LinearSrgb {
        return write_exr_channels((img.width, img.height), Some(img), &[], space, path);
    }
    let tmp = temp_path(path);
    let result = match format {
        Format::Png => write_png(img, &tmp),
        Format::Exr => write_exr(img, &tmp),
    }
    .and_then(|_| fs::rename(&tmp, path).map_err(|e| write_err(path, e)));
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// Writes a `width` x `height` OpenEXR file of float channels atomically: the image `img`'s
/// colour channels in `space` (R, G, B or X, Y, Z) when given, and `extra` (name, values row by
/// row): the AOVs beside an image (`film::aov`), in the image's file or, beside a PNG, in one of
/// their own.
pub fn write_exr_channels(
    (width, height): (u32, u32),
    img: Option<&Image>,
    extra: &[(String, Vec<f32>)],
    space: ColourSpace,
    path: &Path,
) -> Result<(), OutputError> {
    use exr::prelude::*;
    let mut channels: Vec<AnyChannel<FlatSamples>> = Vec::new();
    if let Some(img) = img {
        for (ch, name) in space.channel_names().into_iter().enumerate() {
            let v: Vec<f32> = img.pixels.iter().map(|&c| space.convert(c)[ch]).collect();
            channels.push(AnyChannel::new(name, FlatSamples::F32(v)));
        }
    }
    for (name, values) in extra {
        channels.push(AnyChannel::new(name.as_str(), FlatSamples::F32(values.clone())));
    }
    let size = (width as usize, height as usize);
    let layer =
        Layer::new(size, LayerAttributes::default(), Encoding::SMALL_LOSSLESS, AnyChannels::sort(channels.into()));
    let tmp = temp_path(path);
    let result = exr::image::Image::from_layer(layer)
        .write()
        .to_file(&tmp)
        .map_err(|e| write_err(path, e))
        .and_then(|()| fs::rename(&tmp, path).map_err(|e| write_err(path, e)));
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// Where the AOVs of an image written to `path` go: into the image itself when it is an EXR,
/// else `NAME.aovs.exr` beside it.
pub fn aov_path(path: &Path) -> Option<PathBuf> {
    match Format::from_path(path) {
        Ok(Format::Exr) => None,
        _ => Some(path.with_extension("aovs.exr")),
    }
}

/// 8-bit sRGB bytes of an image, row by row.
pub fn srgb8(img: &Image) -> Vec<u8> {
    img.pixels.iter().flat_map(|c| c.to_array().map(|v| (linear_to_srgb(v) * 255.0 + 0.5) as u8)).collect()
}

fn write_png(img: &Image, path: &Path) -> Result<(), OutputError> {
    let file = fs::File::create(path).map_err(|e| write_err(path, e))?;
    let mut w = BufWriter::new(file);
    let mut enc = png::Encoder::new(&mut w, img.width, img.height);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
    let mut writer = enc.write_header().map_err(|e| write_err(path, e))?;
    writer.write_image_data(&srgb8(img)).map_err(|e| write_err(path, e))?;
    writer.finish().map_err(|e| write_err(path, e))?;
    w.flush().map_err(|e| write_err(path, e))?;
    w.get_ref().sync_all().map_err(|e| write_err(path, e))
}

fn write_exr(img: &Image, path: &Path) -> Result<(), OutputError> {
    use exr::prelude::*;
    let w = img.width as usize;
    let channels = SpecificChannels::rgb(|pos: Vec2<usize>| {
        let c = img.pixels[pos.y() * w + pos.x()];
        (c.r(), c.g(), c.b())
    });
    let image = exr::image::Image::from_channels((img.width as usize, img.height as usize), channels);
    image.write().to_file(path).map_err(|e| write_err(path, e))
}

/// Reads an RGB(A) float EXR back (used by tests and reference comparisons).
pub fn read_exr(path: &Path) -> Result<Image, OutputError> {
    use exr::prelude::read_first_rgba_layer_from_file;
    let image = read_first_rgba_layer_from_file(
        path,
        |res, _| {
            let (w, h) = (res.width(), res.height());
            super::Image::new(w as u32, h as u32)
        },
        |img: &mut super::Image, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            img.set(pos.x() as u32, pos.y() as u32, Color::new(r, g, b));
        },
    )
    .map_err(|e| write_err(path, e))?;
    Ok(image.layer_data.channel_data.pixels)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_curve_endpoints_and_midpoint() {
        assert_eq!(linear_to_srgb(0.0), 0.0);
        assert!((linear_to_srgb(1.0) - 1.0).abs() < 1e-6);
        assert!((linear_to_srgb(0.5) - 0.7354).abs() < 1e-3);
        assert_eq!(linear_to_srgb(7.0), linear_to_srgb(1.0));
        assert_eq!(linear_to_srgb(-1.0), 0.0);
    }

    #[test]
    fn exr_round_trips_and_png_writes() {
        let dir = std::env::temp_dir().join(format!("caustic-out-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let mut img = Image::new(5, 3);
        img.set(4, 2, Color::new(2.5, 0.25, 1e-3));
        let exr = dir.join("a.exr");
        write_image(&img, &exr).unwrap();
        assert_eq!(read_exr(&exr).unwrap(), img);
        let png = dir.join("a.png");
        write_image(&img, &png).unwrap();
        assert!(fs::metadata(&png).unwrap().len() > 0);
        assert!(matches!(check_writable(&dir.join("x.jpg")), Err(OutputError::Extension(_))));
        assert!(check_writable(&dir.join("missing-dir/x.png")).is_err());
        // No temporary files left behind.
        let leftovers = fs::read_dir(&dir)
            .unwrap()
            .filter(|e| e.as_ref().unwrap().file_name().to_string_lossy().contains(".tmp."))
            .count();
        assert_eq!(leftovers, 0);
        fs::remove_dir_all(&dir).unwrap();
    }
}
