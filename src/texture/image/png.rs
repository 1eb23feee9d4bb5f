//! PNG through the `png` crate: 8/16-bit grey, grey+alpha, RGB, RGBA and palette, interlaced or not.
//! The crate expands palettes, low bit depths and `tRNS`; we drop alpha and apply the transfer.

use std::io::Cursor;

use ::png::{BitDepth, ColorType, Decoder, DecodingError, Transformations};

use super::{Problem, TexImage, Transfer};

/// The most raw image bytes one byte of deflate data can produce (the format's limit is 1032:1),
/// so a small file cannot ask for a huge image.
const DEFLATE_MAX_RATIO: u64 = 1032;

pub(super) fn decode(bytes: &[u8], raw: bool) -> Result<TexImage, Problem> {
    let mut decoder = Decoder::new(Cursor::new(bytes));
    decoder.set_transformations(Transformations::EXPAND);
    decoder.set_ignore_text_chunk(true);
    decoder.set_ignore_iccp_chunk(true);
    let mut reader = decoder.read_info().map_err(|e| problem(e, "its header"))?;
    let info = reader.info();
    let (width, height, interlaced) = (info.width as u64, info.height as u64, info.interlaced);
    let (color, depth) = reader.output_color_type();
    let (samples, channels) = match color {
        ColorType::Grayscale => (1, 1),
        ColorType::GrayscaleAlpha => (2, 1),
        ColorType::Rgb => (3, 3),
        ColorType::Rgba => (4, 3),
        ColorType::Indexed => return Err(Problem::Unsupported("a palette the decoder did not expand".into())),
    };
    let sample_bytes = match depth {
        BitDepth::Eight => 1,
        BitDepth::Sixteen => 2,
        other => return Err(Problem::Unsupported(format!("{other:?}-bit samples after expansion"))),
    };
    let raw_bytes = height.saturating_mul(width.saturating_mul(samples * sample_bytes).saturating_add(1));
    if width.saturating_mul(height) <= super::MAX_TEXELS
        && raw_bytes > DEFLATE_MAX_RATIO.saturating_mul(bytes.len() as u64)
    {
        return Err(Problem::Truncated(format!(
            "it declares {width} x {height} pixels, more than its {} bytes can hold",
            bytes.len()
        )));
    }
    let mut image = TexImage::allocate(width, height, channels)?;
    let transfer = Transfer::new(raw);
    let convert = |row: &[u8], out: &mut [f32]| match (samples, sample_bytes) {
        (1, 1) => transfer.u8_texels::<1, 1>(row, out),
        (2, 1) => transfer.u8_texels::<2, 1>(row, out),
        (3, 1) => transfer.u8_texels::<3, 3>(row, out),
        (4, 1) => transfer.u8_texels::<4, 3>(row, out),
        (1, _) => transfer.u16_be_texels::<1, 1>(row, out),
        (2, _) => transfer.u16_be_texels::<2, 1>(row, out),
        (3, _) => transfer.u16_be_texels::<3, 3>(row, out),
        _ => transfer.u16_be_texels::<4, 3>(row, out),
    };
    if interlaced {
        // Adam7 passes fill the whole picture only at the end, so decode to bytes first.
        let size = reader.output_buffer_size().ok_or(Problem::TooLarge { width, height })?;
        let mut buffer = vec![0u8; size];
        let frame = reader.next_frame(&mut buffer).map_err(|e| problem(e, "its interlaced pixel data"))?;
        for (y, row) in buffer.chunks_exact(frame.line_size).take(height as usize).enumerate() {
            convert(row, image.row_mut(y as u32));
        }
    } else {
        for y in 0..height {
            let where_ = || format!("row {} of {height}", y + 1);
            match reader.next_row().map_err(|e| problem(e, &where_()))? {
                Some(row) => convert(row.data(), image.row_mut(y as u32)),
                None => return Err(Problem::ends_in_row(y, height)),
            }
        }
    }
    reader.finish().map_err(|e| problem(e, "the chunks after the pixels"))?;
    Ok(image)
}

/// The `png` crate's error, said in our words; `place` says where decoding was.
fn problem(e: DecodingError, place: &str) -> Problem {
    match e {
        DecodingError::IoError(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
            Problem::Truncated(format!("the file ends in {place}"))
        }
        DecodingError::IoError(io) => Problem::Damaged(format!("{place}: {io}")),
        DecodingError::Format(e) => Problem::Damaged(format!("{place}: {e}")),
        DecodingError::LimitsExceeded => {
            Problem::Unsupported(format!("{place} needs more memory than the decoder allows for one row or chunk"))
        }
        DecodingError::Parameter(e) => Problem::Damaged(format!("{place}: {e}")),
    }
}
