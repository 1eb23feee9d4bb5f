//! Radiance HDR (RGBE), read by hand: flat, old run-length and new (per-channel) run-length
//! scanlines, in the standard `-Y height +X width` orientation (rows from the top).
//!
//! Layout (Ward, "Real Pixels", Graphics Gems II, and the Radiance file format notes): a text
//! header from `#?RADIANCE` to a blank line (`FORMAT=32-bit_rle_rgbe`), a resolution line, then
//! one scanline per row. A texel is a shared exponent E and three mantissas M: M * 2^(E - 136),
//! and 0 when E is 0. `EXPOSURE` lines are ignored: the values are taken as stored.

use super::{Bytes, Problem, TexImage};

/// Longest header accepted; real ones are a few hundred bytes.
const MAX_HEADER_BYTES: usize = 1 << 16;

pub(super) fn decode(bytes: &[u8]) -> Result<TexImage, Problem> {
    let (width, height, data_start) = header(bytes)?;
    let mut file = Bytes::new(&bytes[data_start..]);
    // Each scanline takes at least 4 bytes (one pixel); a new-style one at least its 4-byte
    // marker plus 2 bytes per 127 values of each of the 4 channels.
    let new_style = (8..=0x7fff).contains(&width) && bytes[data_start..].starts_with(&[2, 2]);
    let min_row_bytes = if new_style { 4 + 8 * width.div_ceil(127) } else { 4 };
    if width.saturating_mul(height) <= super::MAX_TEXELS
        && height.saturating_mul(min_row_bytes) > file.remaining() as u64
    {
        return Err(Problem::Truncated(format!(
            "it declares {width} x {height} pixels, more than its {} bytes can hold",
            bytes.len()
        )));
    }
    let mut image = TexImage::allocate(width, height, 3)?;
    let mut scanline = vec![[0u8; 4]; width as usize];
    let scales: [f32; 256] = std::array::from_fn(|e| if e == 0 { 0.0 } else { exp2(e as i32 - 136) });
    for y in 0..height {
        read_scanline(&mut file, &mut scanline).map_err(|e| match e {
            ScanlineError::Ends => Problem::ends_in_row(y, height),
            ScanlineError::Damaged(what) => Problem::Damaged(format!("row {} of {height}: {what}", y + 1)),
        })?;
        for (rgbe, texel) in scanline.iter().zip(image.row_mut(y as u32).chunks_exact_mut(3)) {
            let scale = scales[rgbe[3] as usize];
            for (value, &mantissa) in texel.iter_mut().zip(rgbe) {
                *value = mantissa as f32 * scale;
            }
        }
    }
    Ok(image)
}

/// 2^e as an f32, exact for the exponents of RGBE (-136 to 119; the smallest are subnormal).
fn exp2(e: i32) -> f32 {
    2f64.powi(e) as f32
}

/// Width, height and the offset of the first scanline.
fn header(bytes: &[u8]) -> Result<(u64, u64, usize), Problem> {
    let mut pos = 0;
    let next_line = |pos: &mut usize| -> Result<String, Problem> {
        let rest = &bytes[*pos..bytes.len().min(MAX_HEADER_BYTES)];
        let Some(end) = rest.iter().position(|&b| b == b'\n') else {
            return Err(if bytes.len() > MAX_HEADER_BYTES {
                Problem::Damaged(format!("no end of the header in its first {MAX_HEADER_BYTES} bytes"))
            } else {
                Problem::Truncated("the file ends in its header".into())
            });
        };
        *pos += end + 1;
        Ok(String::from_utf8_lossy(&rest[..end]).trim_end_matches('\r').to_string())
    };
    next_line(&mut pos)?; // "#?RADIANCE" or "#?RGBE"
    loop {
        let line = next_line(&mut pos)?;
        if line.trim().is_empty() {
            break;
        }
        if let Some(format) = line.strip_prefix("FORMAT=") {
            match format.trim() {
                "32-bit_rle_rgbe" => {}
                "32-bit_rle_xyze" => return Err(Problem::Unsupported("XYZE colour (only RGBE is read)".into())),
                other => return Err(Problem::Unsupported(format!("pixel format `{other}`"))),
            }
        }
    }
    let line = next_line(&mut pos)?;
    let words: Vec<&str> = line.split_whitespace().collect();
    let orientation = || {
        Problem::Unsupported(format!(
            "the resolution line `{line}` (only `-Y height +X width`, rows from the top, is read)"
        ))
    };
    let [first, height, second, width] = words[..] else { return Err(orientation()) };
    let (Ok(height), Ok(width)) = (height.parse::<u64>(), width.parse::<u64>()) else { return Err(orientation()) };
    if first != "-Y" || second != "+X" {
        return Err(orientation());
    }
    Ok((width, height, pos))
}

enum ScanlineError {
    Ends,
    Damaged(String),
}

/// Reads one scanline of RGBE pixels in whichever of the three encodings it uses.
fn read_scanline(file: &mut Bytes, out: &mut [[u8; 4]]) -> Result<(), ScanlineError> {
    let width = out.len();
    let start = file.take(4).ok_or(ScanlineError::Ends)?;
    let first = [start[0], start[1], start[2], start[3]];
    if (8..=0x7fff).contains(&width) && first[0] == 2 && first[1] == 2 && first[2] & 0x80 == 0 {
        let declared = (first[2] as usize) << 8 | first[3] as usize;
        if declared != width {
            return Err(ScanlineError::Damaged(format!("the scanline says width {declared}, not {width}")));
        }
        return read_new_rle(file, out);
    }
    // Flat pixels, where (1, 1, 1, n) repeats the previous pixel n times, and n << 8 times
    // after another such repeat (the old run-length encoding).
    let mut x = 0;
    let mut shift = 0;
    let mut pixel = first;
    loop {
        if pixel[..3] == [1, 1, 1] {
            let previous = match x {
                0 => return Err(ScanlineError::Damaged("a run before any pixel".into())),
                _ => out[x - 1],
            };
            let count = (pixel[3] as usize).checked_shl(shift).filter(|_| shift < 32).unwrap_or(usize::MAX);
            if count > width - x {
                return Err(ScanlineError::Damaged("a run passes the end of the scanline".into()));
            }
            out[x..x + count].fill(previous);
            x += count;
            shift += 8;
        } else {
            out[x] = pixel;
            x += 1;
            shift = 0;
        }
        if x == width {
            return Ok(());
        }
        let next = file.take(4).ok_or(ScanlineError::Ends)?;
        pixel = [next[0], next[1], next[2], next[3]];
    }
}

/// The new encoding: each of the 4 components in turn, as runs (count > 128: one byte
/// repeated count - 128 times) and literals (count bytes).
fn read_new_rle(file: &mut Bytes, out: &mut [[u8; 4]]) -> Result<(), ScanlineError> {
    let width = out.len();
    for component in 0..4 {
        let mut x = 0;
        while x < width {
            let count = file.u8().ok_or(ScanlineError::Ends)? as usize;
            let (n, run) = if count > 128 { (count - 128, true) } else { (count, false) };
            if n == 0 || n > width - x {
                return Err(ScanlineError::Damaged(format!("a run of {n} at column {x} of {width}")));
            }
            if run {
                let value = file.u8().ok_or(ScanlineError::Ends)?;
                out[x..x + n].iter_mut().for_each(|p| p[component] = value);
            } else {
                let values = file.take(n).ok_or(ScanlineError::Ends)?;
                out[x..x + n].iter_mut().zip(values).for_each(|(p, &v)| p[component] = v);
            }
            x += n;
        }
    }
    Ok(())
}
