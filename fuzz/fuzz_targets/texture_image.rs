//! Fuzz target: `texture::image::decode_image` on arbitrary bytes, read both as sRGB and raw.
//! Every input must give an image of the declared size or an error, never a panic. The first
//! byte picks the file name, so the extension hint (TGA has no magic bytes) is fuzzed too.
#![no_main]

use std::path::Path;

use caustic::texture::image::{MAX_TEXELS, decode_image};
use libfuzzer_sys::fuzz_target;

const NAMES: [&str; 8] = ["t.png", "t.jpg", "t.bmp", "t.tga", "t.exr", "t.hdr", "t.pfm", "t.bin"];

fuzz_target!(|data: &[u8]| {
    let Some((&pick, bytes)) = data.split_first() else { return };
    let path = Path::new(NAMES[pick as usize % NAMES.len()]);
    for raw in [false, true] {
        if let Ok(image) = decode_image(bytes, path, raw) {
            assert!(image.channels == 1 || image.channels == 3);
            assert!(image.width as u64 * image.height as u64 <= MAX_TEXELS);
            assert_eq!(image.texels.len(), image.width as usize * image.height as usize * image.channels as usize);
        }
    }
});
