#!/bin/sh
# Recreates the texture-decoder measurements of BENCHMARKS.md, "Texture decoders (issue 11)", in a
# scratch directory outside the repository (default /tmp/decoders-bench; nothing here touches the
# caustic build). Needs ImageMagick and cjpeg (`apt-get install imagemagick libjpeg-turbo-progs`).
#   sh scripts/texture_decoders_bench.sh compile   # clean release builds of each candidate set
#   sh scripts/texture_decoders_bench.sh speed     # decode times of 2048 x 2048 files
set -e
repo=$(cd "$(dirname "$0")/.." && pwd)
root=${BENCH_DIR:-/tmp/decoders-bench}
mkdir -p "$root"

variant() { # name, extra dependency lines
  mkdir -p "$root/compile/$1/src"; echo 'fn main() {}' > "$root/compile/$1/src/main.rs"
  printf '[package]\nname = "v-%s"\nversion = "0.0.0"\nedition = "2024"\n[dependencies]\npng = "0.18"\nexr = "1.74"\nthiserror = "2"\n%s\n[profile.release]\ndebug = "line-tables-only"\ncodegen-units = 4\n' "$1" "$2" > "$root/compile/$1/Cargo.toml"
}

case "$1" in
compile)
  variant base ''
  variant image 'image = { version = "0.25", default-features = false, features = ["png", "jpeg", "bmp", "tga", "hdr", "exr"] }'
  variant zune "$(printf 'zune-core = "0.5"\nzune-jpeg = "0.5"\nzune-png = "0.5"\nzune-bmp = "0.5"\nzune-hdr = "0.5"\nzune-ppm = "0.5"')"
  variant zunejpeg "$(printf 'zune-core = "0.5"\nzune-jpeg = "0.5"')"
  variant jpegdecoder 'jpeg-decoder = { version = "0.3", default-features = false }'
  for d in base image zune zunejpeg jpegdecoder; do (cd "$root/compile/$d" && cargo fetch -q); done
  for d in base image zune zunejpeg jpegdecoder; do
    rm -rf "$root/compile/$d/target"
    (cd "$root/compile/$d" && /usr/bin/time -f "$d wall=%e s user=%U s sys=%S s" cargo build --release -q)
  done
  ;;
speed)
  mkdir -p "$root/images" "$root/speed/src"
  cd "$root/images"
  convert -seed 7 -size 2048x2048 plasma:fractal -blur 0x2 -depth 8 src.ppm
  convert src.ppm rgb8.png
  cjpeg -quality 90 src.ppm > baseline.jpg
  cjpeg -quality 90 -progressive src.ppm > progressive.jpg
  convert src.ppm -define bmp:format=bmp3 rgb24.bmp
  convert src.ppm -compress none raw.tga
  convert src.ppm -compress RLE rle.tga
  convert src.ppm rgbe.hdr
  convert src.ppm rgb.pfm
  convert src.ppm half.exr
  cd "$root/speed"
  cat > Cargo.toml <<'TOML'
[package]
name = "decoders-speed"
version = "0.0.0"
edition = "2024"
[dependencies]
png = "0.18"
exr = "1.74"
thiserror = "2"
zune-core = "0.5"
zune-jpeg = "0.5"
zune-png = "0.5"
zune-bmp = "0.5"
zune-hdr = "0.5"
zune-ppm = "0.5"
jpeg-decoder = { version = "0.3", default-features = false }
image = { version = "0.25", default-features = false, features = ["png", "jpeg", "bmp", "tga", "hdr", "exr"] }
[profile.release]
debug = "line-tables-only"
codegen-units = 4
TOML
  sed "s|@REPO@|$repo|" > src/main.rs <<'RUST'
//! Decode speed of texture decoders on ~2048x2048 files: best of N runs, single thread
//! unless the crate threads by itself. "to f32" = decode + conversion to linear f32 texels.
#[path = "@REPO@/src/texture/image/mod.rs"]
#[allow(dead_code)]
mod ours;

use std::path::Path;
use std::time::Instant;
use zune_core::bytestream::ZCursor;

fn best<T>(runs: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::MAX;
    let mut out = None;
    for _ in 0..runs {
        let t = Instant::now();
        let r = f();
        best = best.min(t.elapsed().as_secs_f64());
        out = Some(r);
    }
    (best * 1000.0, out.unwrap())
}

fn to_f32_u8(bytes: &[u8], lut: &[f32; 256]) -> Vec<f32> {
    bytes.iter().map(|&b| lut[b as usize]).collect()
}

fn main() {
    let dir = std::env::args().nth(1).expect("dir");
    let runs: usize = std::env::args().nth(2).map(|s| s.parse().unwrap()).unwrap_or(5);
    let lut: [f32; 256] = std::array::from_fn(|i| {
        let c = i as f64 / 255.0;
        (if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055f64).powf(2.4) }) as f32
    });
    let read = |name: &str| std::fs::read(Path::new(&dir).join(name)).unwrap();
    let report = |format: &str, decoder: &str, ms: f64, n: usize| {
        println!("| {format} | {decoder} | {ms:.1} | {:.1} |", n as f64 / ms / 1000.0);
    };
    let ours = |name: &str| {
        let bytes = read(name);
        let (ms, img) = best(runs, || ours::decode_image(&bytes, Path::new(name), false).unwrap());
        (ms, img.texels.len())
    };
    let image_crate = |name: &str| {
        let bytes = read(name);
        let (ms, img) = best(runs, || image::load_from_memory_with_format(&bytes, image::ImageFormat::from_path(name).unwrap()).unwrap().into_rgb32f());
        (ms, img.len())
    };
    println!("| format | decoder | ms | M values/s |\n|---|---|---|---|");
    // PNG
    let (ms, n) = ours("rgb8.png"); report("PNG RGB8", "ours: png 0.18 + sRGB LUT", ms, n);
    { let b = read("rgb8.png"); let (ms, n) = best(runs, || { let mut d = zune_png::PngDecoder::new(ZCursor::new(&b)); match d.decode().unwrap() { zune_core::result::DecodingResult::U8(v) => to_f32_u8(&v, &lut).len(), _ => 0 } }); report("PNG RGB8", "zune-png 0.5 + LUT", ms, n); }
    let (ms, n) = image_crate("rgb8.png"); report("PNG RGB8", "image 0.25 (into_rgb32f, no sRGB)", ms, n);
    // JPEG
    for name in ["baseline.jpg", "progressive.jpg"] {
        let (ms, n) = ours(name); report(name, "ours: zune-jpeg 0.5 + LUT", ms, n);
        let b = read(name);
        let (ms, n) = best(runs, || { let mut d = jpeg_decoder::Decoder::new(&b[..]); to_f32_u8(&d.decode().unwrap(), &lut).len() }); report(name, "jpeg-decoder 0.3 + LUT", ms, n);
        let (ms, n) = image_crate(name); report(name, "image 0.25", ms, n);
    }
    // BMP
    let (ms, n) = ours("rgb24.bmp"); report("BMP 24", "ours (hand-written)", ms, n);
    { let b = read("rgb24.bmp"); let (ms, n) = best(runs, || { let mut d = zune_bmp::BmpDecoder::new(ZCursor::new(&b)); to_f32_u8(&d.decode().unwrap(), &lut).len() }); report("BMP 24", "zune-bmp 0.5 + LUT", ms, n); }
    let (ms, n) = image_crate("rgb24.bmp"); report("BMP 24", "image 0.25", ms, n);
    // TGA
    for name in ["raw.tga", "rle.tga"] {
        let (ms, n) = ours(name); report(name, "ours (hand-written)", ms, n);
        let (ms, n) = image_crate(name); report(name, "image 0.25", ms, n);
    }
    // HDR
    let (ms, n) = ours("rgbe.hdr"); report("HDR (new RLE)", "ours (hand-written)", ms, n);
    { let b = read("rgbe.hdr"); let (ms, n) = best(runs, || { let mut d = zune_hdr::HdrDecoder::new(ZCursor::new(&b)); d.decode().unwrap().len() }); report("HDR (new RLE)", "zune-hdr 0.5", ms, n); }
    let (ms, n) = image_crate("rgbe.hdr"); report("HDR (new RLE)", "image 0.25", ms, n);
    // PFM
    let (ms, n) = ours("rgb.pfm"); report("PFM", "ours (hand-written)", ms, n);
    { let b = read("rgb.pfm"); let (ms, n) = best(runs, || { let mut d = zune_ppm::PPMDecoder::new(ZCursor::new(&b)); match d.decode().unwrap() { zune_core::result::DecodingResult::F32(v) => v.len(), _ => 0 } }); report("PFM", "zune-ppm 0.5", ms, n); }
    // EXR
    let (ms, n) = ours("half.exr"); report("EXR half ZIP", "ours: exr 1.74", ms, n);
    let (ms, n) = image_crate("half.exr"); report("EXR half ZIP", "image 0.25 (exr 1.74)", ms, n);
}
RUST
  cargo build --release -q
  ./target/release/decoders-speed "$root/images" 7
  ;;
*) echo "usage: $0 compile|speed" >&2; exit 2 ;;
esac
