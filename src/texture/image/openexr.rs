//! OpenEXR through the `exr` crate: half, float or uint channels of the first part (layer),
//! largest resolution level. Which channels are read:
//!
//! 1. `R`, `G`, `B` -> 3 channels (alpha and any other channel are ignored);
//! 2. else `Y` -> 1 channel (luminance/chroma files with `RY`, `BY` are refused);
//! 3. else a part with a single channel, whatever its name -> 1 channel;
//! 4. else the first layer prefix holding `prefix.R`, `.G`, `.B` (or `prefix.Y`), in the
//!    file's (alphabetical) channel order.
//!
//! uint values are taken as numbers (an id or a count), not divided by their maximum.

use std::io::Cursor;

use exr::meta::MetaData;
use exr::prelude::{ReadChannels, ReadLayers, ReadSpecificChannel, Vec2, read};

use super::{Problem, TexImage};

/// The largest factor by which OpenEXR's compressions expand data (deflate's limit, rounded up).
const MAX_EXPANSION: u64 = 1100;

pub(super) fn decode(bytes: &[u8]) -> Result<TexImage, Problem> {
    // The header first: the channels are chosen and the size checked before any pixel memory
    // is allocated.
    let meta = MetaData::read_from_buffered(Cursor::new(bytes), false).map_err(problem)?;
    let header = meta.headers.first().ok_or_else(|| Problem::Damaged("the file holds no image".into()))?;
    if header.deep {
        return Err(Problem::Unsupported("deep data".into()));
    }
    let names: Vec<String> = header.channels.list.iter().map(|c| c.name.to_string()).collect();
    let chosen = choose_channels(&names)?;
    let (width, height) = (header.layer_size.width() as u64, header.layer_size.height() as u64);
    if width.saturating_mul(height) > super::MAX_TEXELS {
        return Err(Problem::TooLarge { width, height });
    }
    // Every chunk has an 8-byte entry in the offset table and at least 8 bytes of its own.
    let chunks: usize = meta.headers.iter().map(|h| h.chunk_count).sum();
    if chunks.saturating_mul(16) > bytes.len() {
        return Err(Problem::Truncated(format!("the file is shorter than its {chunks} pixel blocks need")));
    }
    if width == 0 || height == 0 {
        return Err(Problem::Damaged(format!("the image has no texels ({width} x {height})")));
    }
    // No compression OpenEXR offers expands a block by more than deflate's ~1032:1 (RLE, PIZ,
    // PXR24 and B44 by far less), so a header claiming more pixel data than that is damaged: it
    // is refused before the decoder allocates its pixels (a 500-byte file could otherwise ask
    // for gigabytes). Lossy DWA files of flat colour could exceed it; none are known in practice.
    // The decoder also allocates a whole tile (or block) at a time, so a tile size is bounded
    // the same way.
    let limit = (bytes.len() as u64).saturating_mul(MAX_EXPANSION).saturating_add(1 << 20);
    let bpp = header.channels.bytes_per_pixel as u64;
    let raw = width.saturating_mul(height).saturating_mul(bpp);
    let tile = match header.blocks {
        exr::meta::BlockDescription::Tiles(t) => {
            (t.tile_size.width() as u64).saturating_mul(t.tile_size.height() as u64)
        }
        exr::meta::BlockDescription::ScanLines => 0,
    };
    for (what, need) in
        [(format!("{width} x {height} pixels"), raw), ("one tile".to_string(), tile.saturating_mul(bpp))]
    {
        if need > limit {
            return Err(Problem::Truncated(format!(
                "{what} need {need} bytes, more than {} bytes of compressed data can hold",
                bytes.len()
            )));
        }
    }
    let reader = read().no_deep_data().largest_resolution_level().specific_channels();
    let image = match &chosen[..] {
        [r, g, b] => {
            reader
                .required(r.as_str())
                .required(g.as_str())
                .required(b.as_str())
                .collect_pixels(
                    |size, _| new_texels(size, 3),
                    |texels: &mut TexImage, at, (r, g, b): (f32, f32, f32)| set(texels, at, &[r, g, b]),
                )
                .first_valid_layer()
                .all_attributes()
                .from_buffered(Cursor::new(bytes))
                .map_err(problem)?
                .layer_data
                .channel_data
                .pixels
        }
        [y] => {
            reader
                .required(y.as_str())
                .collect_pixels(
                    |size, _| new_texels(size, 1),
                    |texels: &mut TexImage, at, (y,): (f32,)| set(texels, at, &[y]),
                )
                .first_valid_layer()
                .all_attributes()
                .from_buffered(Cursor::new(bytes))
                .map_err(problem)?
                .layer_data
                .channel_data
                .pixels
        }
        _ => return Err(Problem::Unsupported("a channel choice of neither 1 nor 3 channels".into())),
    };
    Ok(image)
}

fn new_texels(size: Vec2<usize>, channels: u32) -> TexImage {
    // The size was checked against MAX_TEXELS from the header, and the reader gives that size.
    TexImage {
        width: size.0 as u32,
        height: size.1 as u32,
        channels,
        texels: vec![0.0; size.area() * channels as usize],
    }
}

fn set(image: &mut TexImage, at: Vec2<usize>, values: &[f32]) {
    let start = (at.1 * image.width as usize + at.0) * values.len();
    if let Some(texel) = image.texels.get_mut(start..start + values.len()) {
        texel.copy_from_slice(values);
    }
}

/// The channel names to read (3 for colour, 1 for grey), by the rules in the module doc.
fn choose_channels(names: &[String]) -> Result<Vec<String>, Problem> {
    let has = |name: &str| names.iter().any(|n| n == name);
    if has("R") && has("G") && has("B") {
        return Ok(vec!["R".into(), "G".into(), "B".into()]);
    }
    if has("RY") || has("BY") {
        return Err(Problem::Unsupported("luminance/chroma channels (RY, BY)".into()));
    }
    if has("Y") {
        return Ok(vec!["Y".into()]);
    }
    if let [only] = names {
        return Ok(vec![only.clone()]);
    }
    for name in names {
        let Some((prefix, _)) = name.rsplit_once('.') else { continue };
        let with = |suffix: &str| format!("{prefix}.{suffix}");
        if has(&with("R")) && has(&with("G")) && has(&with("B")) {
            return Ok(vec![with("R"), with("G"), with("B")]);
        }
        if has(&with("Y")) {
            return Ok(vec![with("Y")]);
        }
    }
    Err(Problem::Unsupported(format!(
        "the channels {} (expected R, G, B, or Y, or a single channel)",
        names.join(", ")
    )))
}

/// The `exr` crate's error, said in our words.
fn problem(e: exr::error::Error) -> Problem {
    match e {
        exr::error::Error::Io(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
            Problem::Truncated("the file ends early".into())
        }
        exr::error::Error::Io(io) => Problem::Damaged(io.to_string()),
        exr::error::Error::NotSupported(what) => Problem::Unsupported(what.to_string()),
        exr::error::Error::Invalid(what) => Problem::Damaged(what.to_string()),
        exr::error::Error::Aborted => Problem::Damaged("reading was aborted".into()),
    }
}
