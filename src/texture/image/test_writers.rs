//! Small writers of test images (PNG and OpenEXR through their crates; PFM, Radiance HDR, TGA
//! and BMP by hand) for the texture reader's tests.

/// A PNG of `data` (big-endian 16-bit samples), optionally Adam7-free palette.
pub(super) fn write_png(
    width: u32,
    height: u32,
    color: ::png::ColorType,
    depth: ::png::BitDepth,
    data: &[u8],
) -> Vec<u8> {
    write_png_with(width, height, color, depth, data, None)
}

pub(super) fn write_png_with(
    width: u32,
    height: u32,
    color: ::png::ColorType,
    depth: ::png::BitDepth,
    data: &[u8],
    palette: Option<Vec<u8>>,
) -> Vec<u8> {
    let mut out = Vec::new();
    {
        let mut encoder = ::png::Encoder::new(&mut out, width, height);
        encoder.set_color(color);
        encoder.set_depth(depth);
        if let Some(palette) = palette {
            encoder.set_palette(palette);
        }
        let mut writer = encoder.write_header().unwrap();
        writer.write_image_data(data).unwrap();
    }
    out
}

/// A PFM of `texels` (row 0 at the top), stored bottom row first as the format wants.
pub(super) fn write_pfm(width: u32, height: u32, channels: u32, texels: &[f32], little_endian: bool) -> Vec<u8> {
    let magic = if channels == 3 { "PF" } else { "Pf" };
    let scale = if little_endian { "-1.0" } else { "1.0" };
    let mut out = format!("{magic}\n{width} {height}\n{scale}\n").into_bytes();
    let row_len = (width * channels) as usize;
    for row in texels.chunks_exact(row_len).rev() {
        for v in row {
            out.extend(if little_endian { v.to_le_bytes() } else { v.to_be_bytes() });
        }
    }
    out
}

#[derive(Clone, Copy, Debug)]
pub(super) enum HdrEncoding {
    Flat,
    OldRle,
    NewRle,
}

/// A Radiance HDR of RGBE pixels (row 0 at the top, `-Y H +X W`).
pub(super) fn write_hdr(width: u32, height: u32, pixels: &[[u8; 4]], encoding: HdrEncoding) -> Vec<u8> {
    let mut out =
        format!("#?RADIANCE\n# caustic test\nFORMAT=32-bit_rle_rgbe\n\n-Y {height} +X {width}\n").into_bytes();
    for row in pixels.chunks_exact(width as usize) {
        match encoding {
            HdrEncoding::Flat => row.iter().for_each(|p| out.extend(p)),
            HdrEncoding::OldRle => {
                // Repeats of the previous pixel, in counts below 256 so no shift is needed.
                let mut x = 0;
                while x < row.len() {
                    out.extend(row[x]);
                    let mut n = 0;
                    while x + 1 + n < row.len() && row[x + 1 + n] == row[x] && n < 255 {
                        n += 1;
                    }
                    if n > 0 {
                        out.extend([1, 1, 1, n as u8]);
                    }
                    x += 1 + n;
                }
            }
            HdrEncoding::NewRle => {
                out.extend([2, 2, (width >> 8) as u8, width as u8]);
                for c in 0..4 {
                    let values: Vec<u8> = row.iter().map(|p| p[c]).collect();
                    let mut x = 0;
                    while x < values.len() {
                        let run = values[x..].iter().take(127).take_while(|&&v| v == values[x]).count();
                        if run >= 3 {
                            out.extend([128 + run as u8, values[x]]);
                            x += run;
                        } else {
                            let n = (values.len() - x).min(128);
                            out.push(n as u8);
                            out.extend(&values[x..x + n]);
                            x += n;
                        }
                    }
                }
            }
        }
    }
    out
}

/// A TGA: `kind` 1 (colour-mapped, 24-bit map), 2 (true colour, 24 or 32 bits) or 3 (grey),
/// RLE when `rle`; `stored` are the pixels in the stored order given by `descriptor`.
pub(super) fn write_tga(
    (width, height, kind, bits): (u16, u16, u8, u8),
    rle: bool,
    descriptor: u8,
    map: &[u8],
    stored: &[u8],
) -> Vec<u8> {
    let has_map = !map.is_empty();
    let mut out = vec![0u8; 18];
    out[0] = 3; // an image ID, skipped by the reader
    out[1] = has_map as u8;
    out[2] = kind + if rle { 8 } else { 0 };
    out[5..7].copy_from_slice(&((map.len() / 3) as u16).to_le_bytes());
    out[7] = if has_map { 24 } else { 0 };
    out[12..14].copy_from_slice(&width.to_le_bytes());
    out[14..16].copy_from_slice(&height.to_le_bytes());
    out[16] = bits;
    out[17] = descriptor;
    out.extend(b"id!");
    out.extend(map);
    let pixel_bytes = bits.div_ceil(8) as usize;
    let pixels: Vec<&[u8]> = stored.chunks_exact(pixel_bytes).collect();
    if !rle {
        out.extend(stored);
        return out;
    }
    // Runs of equal pixels, literal packets otherwise; packets cross rows, as the format allows.
    let mut i = 0;
    while i < pixels.len() {
        let run = pixels[i..].iter().take(128).take_while(|p| **p == pixels[i]).count();
        if run >= 2 {
            out.push(0x80 | (run - 1) as u8);
            out.extend(pixels[i]);
            i += run;
        } else {
            let n = (pixels.len() - i).min(128);
            let n = (1..n).find(|&k| pixels.get(i + k + 1) == Some(&pixels[i + k])).unwrap_or(n);
            out.push((n - 1) as u8);
            pixels[i..i + n].iter().for_each(|p| out.extend(*p));
            i += n;
        }
    }
    out
}

/// A BMP with a 40-byte info header: 24-bit BGR, 32-bit BGRX, or 8-bit with `palette` (RGB);
/// `rows` top first, each `width * bytes per pixel` long; stored top-down if `top_down`.
pub(super) fn write_bmp(
    width: u32,
    height: u32,
    bits: u16,
    palette: &[[u8; 3]],
    rows: &[u8],
    top_down: bool,
) -> Vec<u8> {
    let row_len = (width * bits as u32 / 8) as usize;
    let stride = (width as usize * bits as usize).div_ceil(32) * 4;
    let pixel_offset = 14 + 40 + palette.len() * 4;
    let size = pixel_offset + stride * height as usize;
    let mut out = Vec::with_capacity(size);
    out.extend(b"BM");
    out.extend((size as u32).to_le_bytes());
    out.extend([0; 4]);
    out.extend((pixel_offset as u32).to_le_bytes());
    out.extend(40u32.to_le_bytes());
    out.extend((width as i32).to_le_bytes());
    out.extend((if top_down { -(height as i32) } else { height as i32 }).to_le_bytes());
    out.extend(1u16.to_le_bytes());
    out.extend(bits.to_le_bytes());
    out.extend([0; 4]); // BI_RGB
    out.extend(((stride * height as usize) as u32).to_le_bytes());
    out.extend([0; 8]);
    out.extend((palette.len() as u32).to_le_bytes());
    out.extend([0; 4]);
    for [r, g, b] in palette {
        out.extend([*b, *g, *r, 0]);
    }
    let rows: Vec<&[u8]> = rows.chunks_exact(row_len).collect();
    let ordered: Vec<&[u8]> = if top_down { rows } else { rows.into_iter().rev().collect() };
    for row in ordered {
        out.extend(row);
        out.extend(vec![0; stride - row_len]);
    }
    out
}

/// An OpenEXR with the named channels of `samples` (one Vec per channel, row 0 at the top).
pub(super) fn write_exr(width: usize, height: usize, channels: Vec<(&str, exr::image::FlatSamples)>) -> Vec<u8> {
    use exr::prelude::*;
    let list = channels.into_iter().map(|(name, samples)| AnyChannel::new(name, samples)).collect();
    let image = Image::from_channels((width, height), AnyChannels::sort(list));
    let mut out = std::io::Cursor::new(Vec::new());
    image.write().to_buffered(&mut out).unwrap();
    out.into_inner()
}
