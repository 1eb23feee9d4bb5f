//! Windows BMP, read by hand: uncompressed 1/4/8-bit palette and 16/24/32-bit colour (with or
//! without bit-field masks), bottom-up or top-down. RLE compression is refused.
//!
//! Layout (Microsoft's BITMAPFILEHEADER + BITMAPINFOHEADER and its later versions): a 14-byte
//! file header whose last field is the offset of the pixels, an info header starting with its
//! own size, then masks and palette, then rows padded to 4 bytes, bottom row first when the
//! height is positive.

use super::{Bytes, Problem, TexImage, Transfer};

const BI_RGB: u32 = 0;
const BI_BITFIELDS: u32 = 3;
const BI_ALPHABITFIELDS: u32 = 6;

/// How a pixel's bits become colour.
enum Pixels {
    /// Indices into a palette of RGB bytes.
    Palette(Vec<[u8; 3]>),
    /// 24-bit BGR or 32-bit BGRX bytes.
    Bgr,
    Bgrx,
    /// 16- or 32-bit little-endian words with a mask per colour channel.
    Masked([Mask; 3]),
}

/// One colour channel inside a 16- or 32-bit pixel word.
#[derive(Clone, Copy)]
struct Mask {
    shift: u32,
    bits: u32,
}

impl Mask {
    fn new(mask: u32) -> Result<Mask, Problem> {
        let shift = if mask == 0 { 0 } else { mask.trailing_zeros() };
        let run = mask >> shift;
        let bits = run.trailing_ones();
        if bits > 16 || run >> bits != 0 {
            return Err(Problem::Unsupported(format!("the colour mask {mask:#010x} (not one run of at most 16 bits)")));
        }
        Ok(Mask { shift, bits })
    }

    fn value(&self, word: u32, transfer: &Transfer) -> f32 {
        match self.bits {
            0 => 0.0,
            8 => transfer.linear_u8((word >> self.shift) as u8),
            bits => transfer.linear_bits((word >> self.shift) & ((1 << bits) - 1), bits),
        }
    }
}

pub(super) fn decode(bytes: &[u8], raw: bool) -> Result<TexImage, Problem> {
    let header_ends = || Problem::Truncated("the file ends in its header".into());
    let mut file = Bytes::new(bytes);
    file.take(10).ok_or_else(header_ends)?; // "BM", file size, reserved
    let pixel_offset = file.u32_le().ok_or_else(header_ends)? as usize;
    let info_size = file.u32_le().ok_or_else(header_ends)?;
    let (width, height, bits_per_pixel, compression, palette_len) = match info_size {
        12 => {
            // OS/2 BITMAPCOREHEADER: 16-bit sides, no compression, 3-byte palette entries.
            let width = file.u16_le().ok_or_else(header_ends)? as i32;
            let height = file.u16_le().ok_or_else(header_ends)? as i16 as i32;
            file.u16_le().ok_or_else(header_ends)?;
            let bits = file.u16_le().ok_or_else(header_ends)?;
            (width, height, bits, BI_RGB, 0)
        }
        40 | 52 | 56 | 64 | 108 | 124 => {
            let width = file.i32_le().ok_or_else(header_ends)?;
            let height = file.i32_le().ok_or_else(header_ends)?;
            file.u16_le().ok_or_else(header_ends)?; // planes
            let bits = file.u16_le().ok_or_else(header_ends)?;
            let compression = file.u32_le().ok_or_else(header_ends)?;
            file.take(12).ok_or_else(header_ends)?; // image size, resolution
            let colours_used = file.u32_le().ok_or_else(header_ends)?;
            file.u32_le().ok_or_else(header_ends)?; // important colours
            (width, height, bits, compression, colours_used)
        }
        other => return Err(Problem::Unsupported(format!("an info header of {other} bytes"))),
    };
    if width <= 0 || height == 0 {
        return Err(Problem::Damaged(format!("the image has no texels ({width} x {height})")));
    }
    let top_down = height < 0;
    let (width, height) = (width as u64, height.unsigned_abs() as u64);

    // Masks sit inside headers of 52 bytes and more, or just after a 40-byte header.
    let mask_words = match (compression, info_size) {
        (BI_BITFIELDS | BI_ALPHABITFIELDS, 40) => {
            let n = if compression == BI_ALPHABITFIELDS { 4 } else { 3 };
            let masks: Option<Vec<u32>> = (0..n).map(|_| file.u32_le()).collect();
            masks.ok_or_else(header_ends)?
        }
        (BI_BITFIELDS | BI_ALPHABITFIELDS, _) => {
            let masks = bytes.get(14 + 40..14 + 52).ok_or_else(header_ends)?;
            masks.chunks_exact(4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect()
        }
        _ => Vec::new(),
    };
    if info_size != 40 && info_size != 12 {
        file.take(info_size as usize - 40).ok_or_else(header_ends)?;
    }

    let pixels = match (compression, bits_per_pixel) {
        (BI_RGB, 1 | 4 | 8) => {
            let entry_bytes = if info_size == 12 { 3 } else { 4 };
            let max_entries = 1usize << bits_per_pixel;
            let entries = if palette_len == 0 { max_entries } else { (palette_len as usize).min(max_entries) };
            let table = file
                .take(entries * entry_bytes)
                .ok_or_else(|| Problem::Truncated("the file ends in its palette".into()))?;
            Pixels::Palette(table.chunks_exact(entry_bytes).map(|e| [e[2], e[1], e[0]]).collect())
        }
        (BI_RGB, 24) => Pixels::Bgr,
        (BI_RGB, 16) => Pixels::Masked([Mask::new(0x7c00)?, Mask::new(0x03e0)?, Mask::new(0x001f)?]),
        (BI_RGB, 32) => Pixels::Bgrx,
        (BI_BITFIELDS | BI_ALPHABITFIELDS, 16 | 32) => {
            Pixels::Masked([Mask::new(mask_words[0])?, Mask::new(mask_words[1])?, Mask::new(mask_words[2])?])
        }
        (1, _) | (2, _) => return Err(Problem::Unsupported("RLE compression".into())),
        (4, _) | (5, _) => return Err(Problem::Unsupported("embedded JPEG or PNG data".into())),
        (BI_RGB | BI_BITFIELDS | BI_ALPHABITFIELDS, bits) => {
            return Err(Problem::Unsupported(format!("{bits} bits per pixel")));
        }
        (other, _) => return Err(Problem::Unsupported(format!("compression method {other}"))),
    };

    let row_bytes = (width * bits_per_pixel as u64).div_ceil(32) * 4;
    let available = bytes.len().saturating_sub(pixel_offset) as u64;
    if pixel_offset > bytes.len() {
        return Err(Problem::Truncated(format!("the file ends before its pixels (at byte {pixel_offset})")));
    }
    if width.saturating_mul(height) <= super::MAX_TEXELS && available < row_bytes * height {
        let full_rows = available / row_bytes;
        return Err(if top_down {
            Problem::ends_in_row(full_rows, height)
        } else {
            Problem::ends_in_row_from_bottom(full_rows, height)
        });
    }
    let mut image = TexImage::allocate(width, height, 3)?;
    let transfer = Transfer::new(raw);
    let data = &bytes[pixel_offset..];
    for stored_row in 0..height {
        let start = (stored_row * row_bytes) as usize;
        let row = &data[start..start + row_bytes as usize];
        let y = if top_down { stored_row } else { height - 1 - stored_row };
        let out = image.row_mut(y as u32);
        match &pixels {
            Pixels::Palette(table) => {
                let bits = bits_per_pixel as usize;
                for (x, texel) in out.chunks_exact_mut(3).enumerate() {
                    let bit = x * bits;
                    let index = (row[bit / 8] >> (8 - bits - bit % 8)) as usize & ((1 << bits) - 1);
                    let colour = table.get(index).ok_or_else(|| {
                        Problem::Damaged(format!("palette index {index} of a {}-colour palette", table.len()))
                    })?;
                    for (value, &byte) in texel.iter_mut().zip(colour) {
                        *value = transfer.linear_u8(byte);
                    }
                }
            }
            Pixels::Bgr => transfer.bgr_texels::<3>(row, out),
            Pixels::Bgrx => transfer.bgr_texels::<4>(row, out),
            Pixels::Masked(masks) => {
                let word_bytes = bits_per_pixel as usize / 8;
                for (word, texel) in row.chunks_exact(word_bytes).zip(out.chunks_exact_mut(3)) {
                    let word = word.iter().rev().fold(0u32, |acc, &b| acc << 8 | b as u32);
                    for (value, mask) in texel.iter_mut().zip(masks) {
                        *value = mask.value(word, &transfer);
                    }
                }
            }
        }
    }
    Ok(image)
}
