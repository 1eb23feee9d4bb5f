//! Truevision TGA, read by hand: true-colour (15/16/24/32-bit), grey (8-bit, or 16-bit with
//! alpha) and colour-mapped images, uncompressed or run-length encoded, in any of the four
//! corner orders.
//!
//! Layout (Truevision TGA File Format Specification 2.0): an 18-byte header, an image ID, the
//! colour map, then pixels; bottom row first unless bit 5 of the descriptor is set. RLE packets
//! are a count byte (high bit: one pixel repeated, else that many literal pixels) and may run
//! across rows, so the pixels are decoded as one stream.

use super::{Bytes, Problem, TexImage, Transfer};

/// The signature ending a version 2 file; the only magic TGA has.
const FOOTER: &[u8] = b"TRUEVISION-XFILE.\0";

pub(super) fn has_footer(bytes: &[u8]) -> bool {
    bytes.ends_with(FOOTER)
}

#[derive(Clone, Copy, PartialEq)]
enum Kind {
    ColourMapped,
    TrueColour,
    Grey,
}

pub(super) fn decode(bytes: &[u8], raw: bool) -> Result<TexImage, Problem> {
    let header_ends = || Problem::Truncated("the file ends in its header".into());
    let mut file = Bytes::new(bytes);
    let header = file.take(18).ok_or_else(header_ends)?;
    let field16 = |at: usize| u16::from_le_bytes([header[at], header[at + 1]]);
    let (id_length, has_map, image_type) = (header[0], header[1], header[2]);
    let (map_first, map_length, map_entry_bits) = (field16(3), field16(5), header[7]);
    let (width, height, pixel_bits, descriptor) = (field16(12) as u64, field16(14) as u64, header[16], header[17]);
    let (kind, rle) = match image_type {
        1 => (Kind::ColourMapped, false),
        2 => (Kind::TrueColour, false),
        3 => (Kind::Grey, false),
        9 => (Kind::ColourMapped, true),
        10 => (Kind::TrueColour, true),
        11 => (Kind::Grey, true),
        0 => return Err(Problem::Damaged("the header says there is no image data (type 0)".into())),
        other => return Err(Problem::Unsupported(format!("image type {other}"))),
    };
    let pixel_bytes = match (kind, pixel_bits) {
        (Kind::ColourMapped, 8) | (Kind::Grey, 8) => 1,
        (Kind::ColourMapped, 16) | (Kind::Grey, 16) | (Kind::TrueColour, 15 | 16) => 2,
        (Kind::TrueColour, 24) => 3,
        (Kind::TrueColour, 32) => 4,
        (_, bits) => return Err(Problem::Unsupported(format!("{bits} bits per pixel in this image type"))),
    };
    file.take(id_length as usize).ok_or_else(header_ends)?;
    let map_bytes = match map_entry_bits {
        15 | 16 => 2,
        24 => 3,
        32 => 4,
        _ if has_map == 0 => 0,
        bits => return Err(Problem::Unsupported(format!("colour map entries of {bits} bits"))),
    };
    let map = if has_map != 0 {
        let table = file
            .take(map_length as usize * map_bytes)
            .ok_or_else(|| Problem::Truncated("the file ends in its colour map".into()))?;
        table.chunks_exact(map_bytes).map(|entry| colour_of(entry, map_entry_bits)).collect()
    } else {
        Vec::new()
    };
    if kind == Kind::ColourMapped && map.is_empty() {
        return Err(Problem::Damaged("a colour-mapped image without a colour map".into()));
    }

    // Size checks before allocating: a raw image needs all its bytes, and an RLE packet of
    // 1 + pixel_bytes bytes codes at most 128 pixels.
    let texels = width.saturating_mul(height);
    let available = file.remaining() as u64;
    if texels <= super::MAX_TEXELS {
        let needed = if rle { texels.div_ceil(128) * (1 + pixel_bytes) } else { texels * pixel_bytes };
        if available < needed {
            let rows_done = if rle { 0 } else { available / (width * pixel_bytes) };
            return Err(if rle {
                Problem::Truncated(format!(
                    "it declares {width} x {height} pixels, more than its {} bytes can hold",
                    bytes.len()
                ))
            } else if descriptor & 0x20 != 0 {
                Problem::ends_in_row(rows_done, height)
            } else {
                Problem::ends_in_row_from_bottom(rows_done, height)
            });
        }
    }
    let channels = if kind == Kind::Grey { 1 } else { 3 };
    let mut image = TexImage::allocate(width, height, channels)?;
    let transfer = Transfer::new(raw);
    let map_texels: Vec<[f32; 3]> = map.iter().map(|entry: &[Channel; 3]| entry.map(|c| c.value(&transfer))).collect();
    let (right_to_left, top_down) = (descriptor & 0x10 != 0, descriptor & 0x20 != 0);
    let pixel_bytes = pixel_bytes as usize;
    let mut pixels = PixelStream { file, rle, pixel_bytes, run_left: 0, literal_left: 0, run: &[] };
    let mut stored = vec![0u8; width as usize * pixel_bytes];
    for stored_row in 0..height {
        if !pixels.fill_row(&mut stored) {
            return Err(if top_down {
                Problem::ends_in_row(stored_row, height)
            } else {
                Problem::ends_in_row_from_bottom(stored_row, height)
            });
        }
        if right_to_left {
            reverse_pixels(&mut stored, pixel_bytes);
        }
        let y = if top_down { stored_row } else { height - 1 - stored_row };
        let out = image.row_mut(y as u32);
        match (kind, pixel_bits) {
            (Kind::Grey, 8) => transfer.u8_texels::<1, 1>(&stored, out),
            (Kind::Grey, _) => transfer.u8_texels::<2, 1>(&stored, out),
            (Kind::TrueColour, 24) => transfer.bgr_texels::<3>(&stored, out),
            (Kind::TrueColour, 32) => transfer.bgr_texels::<4>(&stored, out),
            (Kind::TrueColour, _) => {
                for (pixel, texel) in stored.chunks_exact(2).zip(out.chunks_exact_mut(3)) {
                    texel.copy_from_slice(&colour_of(pixel, pixel_bits).map(|c| c.value(&transfer)));
                }
            }
            (Kind::ColourMapped, _) => {
                for (pixel, texel) in stored.chunks_exact(pixel_bytes).zip(out.chunks_exact_mut(3)) {
                    let index = if pixel_bytes == 1 { pixel[0] as usize } else { field(pixel) as usize };
                    let entry =
                        index.checked_sub(map_first as usize).and_then(|i| map_texels.get(i)).ok_or_else(|| {
                            Problem::Damaged(format!(
                                "colour index {index} outside the map ({map_first} + {})",
                                map.len()
                            ))
                        })?;
                    texel.copy_from_slice(entry);
                }
            }
        }
    }
    Ok(image)
}

/// Reverses the order of the pixels of a row stored right to left.
fn reverse_pixels(row: &mut [u8], pixel_bytes: usize) {
    let n = row.len() / pixel_bytes;
    for i in 0..n / 2 {
        for b in 0..pixel_bytes {
            row.swap(i * pixel_bytes + b, (n - 1 - i) * pixel_bytes + b);
        }
    }
}

/// A colour channel as stored: 8-bit, or 5-bit in 15/16-bit pixels.
#[derive(Clone, Copy)]
enum Channel {
    Eight(u8),
    Five(u8),
}

impl Channel {
    fn value(self, transfer: &Transfer) -> f32 {
        match self {
            Channel::Eight(v) => transfer.linear_u8(v),
            Channel::Five(v) => transfer.linear_bits(v as u32, 5),
        }
    }
}

fn field(pixel: &[u8]) -> u16 {
    u16::from_le_bytes([pixel[0], pixel[1]])
}

/// The RGB of a stored colour: BGR(A) bytes, or a 16-bit word of 5-bit fields (ARRRRRGG GGGBBBBB).
fn colour_of(stored: &[u8], bits: u8) -> [Channel; 3] {
    if bits <= 16 {
        let word = field(stored);
        [10, 5, 0].map(|shift| Channel::Five((word >> shift) as u8 & 0x1f))
    } else {
        [Channel::Eight(stored[2]), Channel::Eight(stored[1]), Channel::Eight(stored[0])]
    }
}

/// The pixels of the file in stored order, row by row, expanding RLE packets.
struct PixelStream<'a> {
    file: Bytes<'a>,
    rle: bool,
    pixel_bytes: usize,
    /// Repeats of `run` still to give.
    run_left: usize,
    /// Literal pixels of the current raw packet still to give.
    literal_left: usize,
    run: &'a [u8],
}

impl<'a> PixelStream<'a> {
    /// Fills `row` with the next pixels; false if the file ends first.
    fn fill_row(&mut self, row: &mut [u8]) -> bool {
        if !self.rle {
            return match self.file.take(row.len()) {
                Some(bytes) => {
                    row.copy_from_slice(bytes);
                    true
                }
                None => false,
            };
        }
        // Whole packets at a time: runs are filled, literals copied.
        let mut filled = 0;
        while filled < row.len() {
            if self.run_left == 0 && self.literal_left == 0 {
                let Some(count) = self.file.u8() else { return false };
                let n = (count & 0x7f) as usize + 1;
                if count & 0x80 != 0 {
                    let Some(pixel) = self.file.take(self.pixel_bytes) else { return false };
                    self.run = pixel;
                    self.run_left = n;
                } else {
                    self.literal_left = n;
                }
            }
            let room = (row.len() - filled) / self.pixel_bytes;
            if self.run_left > 0 {
                let n = self.run_left.min(room);
                for pixel in row[filled..filled + n * self.pixel_bytes].chunks_exact_mut(self.pixel_bytes) {
                    pixel.copy_from_slice(self.run);
                }
                self.run_left -= n;
                filled += n * self.pixel_bytes;
            } else {
                let n = self.literal_left.min(room);
                let Some(bytes) = self.file.take(n * self.pixel_bytes) else { return false };
                row[filled..filled + bytes.len()].copy_from_slice(bytes);
                self.literal_left -= n;
                filled += bytes.len();
            }
        }
        true
    }
}
