//! PFM (portable float map), read by hand: `PF` (RGB) or `Pf` (grey) 32-bit floats.
//!
//! Layout: three whitespace-separated text fields after the magic (width, height, scale), one
//! whitespace byte, then the rows, bottom row first. A negative scale means little-endian
//! floats, a positive one big-endian; its magnitude is ignored, as most readers do.

use super::{Problem, TexImage};

pub(super) fn decode(bytes: &[u8]) -> Result<TexImage, Problem> {
    let channels = if bytes[1] == b'F' { 3 } else { 1 };
    let mut pos = 2;
    let mut fields = [""; 3];
    for field in &mut fields {
        let start = pos + bytes[pos..].iter().take_while(|b| b.is_ascii_whitespace()).count();
        if start == pos {
            return Err(Problem::Damaged("no whitespace between the header's fields".into()));
        }
        let len = bytes[start..].iter().take_while(|b| !b.is_ascii_whitespace()).take(64).count();
        *field = std::str::from_utf8(&bytes[start..start + len])
            .map_err(|_| Problem::Damaged("the header is not text".into()))?;
        pos = start + len;
        if pos == bytes.len() {
            return Err(Problem::Truncated("the file ends in its header".into()));
        }
    }
    if !bytes[pos].is_ascii_whitespace() {
        return Err(Problem::Damaged(format!("the header field `{}...` is too long", fields[2])));
    }
    let data = &bytes[pos + 1..];
    let number = |what: &str, text: &str| {
        text.parse::<u64>().map_err(|_| Problem::Damaged(format!("the {what} `{text}` is not a whole number")))
    };
    let (width, height) = (number("width", fields[0])?, number("height", fields[1])?);
    let scale: f32 = fields[2]
        .parse()
        .ok()
        .filter(|s: &f32| s.is_finite() && *s != 0.0)
        .ok_or_else(|| Problem::Damaged(format!("the scale `{}` is not a finite non-zero number", fields[2])))?;
    let little_endian = scale < 0.0;
    let row_bytes = width.saturating_mul(channels as u64 * 4);
    if width.saturating_mul(height) <= super::MAX_TEXELS && (data.len() as u64) < row_bytes * height {
        return Err(Problem::ends_in_row_from_bottom(data.len() as u64 / row_bytes.max(1), height));
    }
    let mut image = TexImage::allocate(width, height, channels)?;
    for (stored_row, row) in data.chunks_exact(row_bytes as usize).take(height as usize).enumerate() {
        let y = (height - 1 - stored_row as u64) as u32;
        for (value, b) in image.row_mut(y).iter_mut().zip(row.chunks_exact(4)) {
            let b = [b[0], b[1], b[2], b[3]];
            *value = if little_endian { f32::from_le_bytes(b) } else { f32::from_be_bytes(b) };
        }
    }
    Ok(image)
}
