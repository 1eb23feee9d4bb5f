//! JPEG through `zune-jpeg` (baseline and progressive, grey, colour and CMYK), in strict mode.
//!
//! Two checks of our own come first: the file must reach its end-of-image marker (zune-jpeg
//! fills a cut-off scan with grey, and a cut file must be an error), and the declared size must
//! fit the file's length, since a few hundred bytes can declare 65535 x 65535 pixels.

use zune_core::bytestream::ZCursor;
use zune_core::colorspace::ColorSpace;
use zune_core::options::DecoderOptions;
use zune_jpeg::JpegDecoder;
use zune_jpeg::errors::DecodeErrors;

use super::{Problem, TexImage, Transfer};

/// Texels one byte of entropy-coded data can hold at most: a Huffman code is at least one bit
/// and codes one 8 x 8 block of one component.
const TEXELS_PER_BYTE: u64 = 8 * 64;

pub(super) fn decode(bytes: &[u8], raw: bool) -> Result<TexImage, Problem> {
    let scan_start = first_scan(bytes)?;
    if !bytes[scan_start..].windows(2).any(|w| w == [0xff, 0xd9]) {
        return Err(Problem::Truncated("the file ends before its end-of-image marker".into()));
    }
    let options = DecoderOptions::default()
        .set_strict_mode(true)
        .set_max_width(usize::from(u16::MAX))
        .set_max_height(usize::from(u16::MAX));
    let mut decoder = JpegDecoder::new_with_options(ZCursor::new(bytes), options);
    decoder.decode_headers().map_err(problem)?;
    let (width, height) = decoder.dimensions().map(|(w, h)| (w as u64, h as u64)).unwrap_or((0, 0));
    let grey = matches!(decoder.input_colorspace(), Some(ColorSpace::Luma | ColorSpace::LumaA));
    let wanted = if grey { ColorSpace::Luma } else { ColorSpace::RGB };
    decoder.set_options(options.jpeg_set_out_colorspace(wanted));
    let entropy_bytes = (bytes.len() - scan_start) as u64;
    if width.saturating_mul(height) <= super::MAX_TEXELS && width * height > TEXELS_PER_BYTE * entropy_bytes {
        return Err(Problem::Truncated(format!(
            "it declares {width} x {height} pixels, more than its {} bytes can hold",
            bytes.len()
        )));
    }
    let (samples, channels) = match decoder.output_colorspace() {
        Some(ColorSpace::Luma) => (1, 1),
        Some(ColorSpace::LumaA) => (2, 1),
        Some(ColorSpace::RGB) => (3, 3),
        Some(ColorSpace::RGBA) => (4, 3),
        other => return Err(Problem::Unsupported(format!("output colour space {other:?}"))),
    };
    let mut image = TexImage::allocate(width, height, channels)?;
    let size = decoder.output_buffer_size().ok_or(Problem::TooLarge { width, height })?;
    let mut pixels = vec![0u8; size];
    decoder.decode_into(&mut pixels).map_err(problem)?;
    let transfer = Transfer::new(raw);
    match samples {
        1 => transfer.u8_texels::<1, 1>(&pixels, &mut image.texels),
        2 => transfer.u8_texels::<2, 1>(&pixels, &mut image.texels),
        3 => transfer.u8_texels::<3, 3>(&pixels, &mut image.texels),
        _ => transfer.u8_texels::<4, 3>(&pixels, &mut image.texels),
    }
    Ok(image)
}

/// Where the first scan's data starts: the marker segments before it are walked by their
/// lengths, so an embedded thumbnail (which has its own scan and end marker) is skipped whole.
fn first_scan(bytes: &[u8]) -> Result<usize, Problem> {
    let mut pos = 2; // after the start-of-image marker
    loop {
        // Markers may be preceded by any number of 0xff fill bytes.
        while bytes.get(pos) == Some(&0xff) && bytes.get(pos + 1) == Some(&0xff) {
            pos += 1;
        }
        let (Some(&0xff), Some(&marker)) = (bytes.get(pos), bytes.get(pos + 1)) else {
            return match bytes.get(pos + 1) {
                None => Err(Problem::Truncated("the file ends before its first scan".into())),
                Some(_) => Err(Problem::Damaged(format!("no marker at byte {pos} of the header"))),
            };
        };
        let Some(length) = bytes.get(pos + 2..pos + 4).map(|b| u16::from_be_bytes([b[0], b[1]]) as usize) else {
            return Err(Problem::Truncated("the file ends before its first scan".into()));
        };
        if length < 2 {
            return Err(Problem::Damaged(format!("a header segment of length {length} at byte {pos}")));
        }
        pos += 2 + length;
        if marker == 0xda {
            return if pos <= bytes.len() {
                Ok(pos)
            } else {
                Err(Problem::Truncated("the file ends in the first scan's header".into()))
            };
        }
    }
}

/// zune-jpeg's error, said in our words.
fn problem(e: DecodeErrors) -> Problem {
    match e {
        DecodeErrors::Unsupported(scheme) => Problem::Unsupported(format!("{scheme:?}")),
        DecodeErrors::ExhaustedData => Problem::Truncated("the file ends inside the image data".into()),
        DecodeErrors::LargeDimensions(n) => Problem::Unsupported(format!("a side of {n} pixels")),
        other => Problem::Damaged(format!("{other}")),
    }
}
