//! The partial image a shard writes: an OpenEXR file that any viewer opens (its RGB channels,
//! and `direct.R` etc. for layers, hold the mean so far), with what merging needs beside it:
//!
//! - `caustic.count`: samples per pixel taken (u32), and `caustic.sum.R0` .. `caustic.sum.B3`:
//!   each pixel's exact sum (see `film::fixed`) as the four 32-bit words of an `i128`, least
//!   significant first; the same per layer as `caustic.direct.R0` etc.;
//! - header attributes: `caustic.format`, `caustic.render` (the render's identity),
//!   `caustic.shard` (`I/N`), `caustic.range` (the shard's sample indices `a..b`),
//!   `caustic.sums` (`exact`, or `runs` for independent progressive runs such as SPPM's) and
//!   `caustic.checksum` (of the counts and sums, so a damaged file is refused, never read).
//!
//! A pixel holding `c` samples holds the shard's indices `a .. a + c`: a shard that stops early
//! (preemption, Ctrl-C) saves the samples it finished and continues from there when run again.

use super::FarmError;
use super::identity::RenderId;
use super::shard::Shard;
use crate::film::aov::AovList;
use crate::film::{Film, LAYER_NAMES};
use exr::prelude::*;
use std::ops::Range;
use std::path::Path;
use std::result::Result;
use xxhash_rust::xxh3::Xxh3;

const FORMAT: &str = "caustic partial image 1";
const RGB: [&str; 3] = ["R", "G", "B"];

/// How a partial's sums combine with others.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SumKind {
    /// Sums of samples: merged sums are the one-machine render's, bit for bit.
    Exact,
    /// Each shard is an independent progressive run (SPPM) whose sum is its image times its
    /// iterations: merging weights runs by their iterations.
    Runs,
}

impl SumKind {
    fn name(self) -> &'static str {
        match self {
            SumKind::Exact => "exact",
            SumKind::Runs => "runs",
        }
    }
}

/// Everything a partial image says about itself besides its pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct PartialHeader {
    pub id: RenderId,
    pub shard: Shard,
    /// The sample indices the shard is to take.
    pub range: Range<u32>,
    pub sums: SumKind,
    pub width: u32,
    pub height: u32,
    pub layers: bool,
    /// The AOVs it holds sums for (the identity's `aovs`).
    pub aovs: AovList,
}

/// A partial image read back: its header and film.
pub struct Partial {
    pub header: PartialHeader,
    pub film: Film,
}

fn part_err(path: &Path, message: impl std::fmt::Display) -> FarmError {
    FarmError::Part { path: path.display().to_string(), message: message.to_string() }
}

fn text(s: &str) -> AttributeValue {
    AttributeValue::Text(Text::from_slice_unchecked(s.as_bytes()))
}

/// Channel names of the sums: `prefix` + R0..B3.
fn sum_names(prefix: &str) -> Vec<String> {
    RGB.iter().flat_map(|c| (0..4).map(move |w| format!("{prefix}{c}{w}"))).collect()
}

/// Hashes u32 words as little-endian bytes, a block at a time.
fn hash_words(h: &mut Xxh3, words: &[u32]) {
    let mut buf = [0u8; 4096];
    for chunk in words.chunks(1024) {
        for (b, w) in buf.chunks_exact_mut(4).zip(chunk) {
            b.copy_from_slice(&w.to_le_bytes());
        }
        h.update(&buf[..chunk.len() * 4]);
    }
}

/// The film's pixels in row order: counts, the 12 sum words, and for each layer 12 more.
struct Columns {
    count: Vec<u32>,
    sums: Vec<Vec<u32>>,
    layers: Vec<Vec<Vec<u32>>>,
    /// Four words per summed AOV channel (`AovList::sum_names`), channel by channel.
    aov: Vec<Vec<u32>>,
}

/// Channel names of the AOV sums: `caustic.aov.` + the channel + the word 0..3.
fn aov_sum_names(aovs: &AovList) -> Vec<String> {
    aovs.sum_names().iter().flat_map(|c| (0..4).map(move |w| format!("caustic.aov.{c}{w}"))).collect()
}

fn checksum(c: &Columns) -> u64 {
    let mut h = Xxh3::new();
    hash_words(&mut h, &c.count);
    for w in c.sums.iter().chain(c.layers.iter().flatten()).chain(&c.aov) {
        hash_words(&mut h, w);
    }
    h.digest()
}

fn columns(film: &Film) -> Columns {
    let n = (film.width * film.height) as usize;
    let layers = film.has_layers();
    let mut c = Columns {
        count: vec![0; n],
        sums: vec![vec![0; n]; 12],
        layers: if layers { vec![vec![vec![0; n]; 12]; 4] } else { Vec::new() },
        aov: vec![vec![0; n]; 4 * film.aovs.summed_channels()],
    };
    let split = |out: &mut [Vec<u32>], p: usize, sum: &[i128; 3]| {
        for (ch, v) in sum.iter().enumerate() {
            let bits = *v as u128;
            for w in 0..4 {
                out[ch * 4 + w][p] = (bits >> (32 * w)) as u32;
            }
        }
    };
    for t in &film.tiles {
        for j in 0..t.height {
            for i in 0..t.width {
                let k = (j * t.width + i) as usize;
                let p = ((t.y0 + j) * film.width + t.x0 + i) as usize;
                c.count[p] = t.count[k];
                split(&mut c.sums, p, &t.sum[k]);
                if let Some(l) = t.layers.get(k) {
                    for (out, sum) in c.layers.iter_mut().zip(l) {
                        split(out, p, sum);
                    }
                }
                let stride = t.aov_stride as usize;
                for (ch, v) in t.aov[k * stride..(k + 1) * stride].iter().enumerate() {
                    for w in 0..4 {
                        c.aov[ch * 4 + w][p] = ((*v as u128) >> (32 * w)) as u32;
                    }
                }
            }
        }
    }
    c
}

/// Writes `film` as the partial image `path` atomically (temporary file, then rename), so a
/// shard killed while writing leaves its previous checkpoint intact.
pub fn write_partial(path: &Path, header: &PartialHeader, film: &Film) -> Result<(), FarmError> {
    let size = (film.width as usize, film.height as usize);
    let cols = columns(film);
    let mut channels: Vec<AnyChannel<FlatSamples>> = Vec::new();
    let mut means = |prefix: &str, img: &crate::film::Image| {
        for (ch, name) in RGB.iter().enumerate() {
            let v: Vec<f32> = img.pixels.iter().map(|c| c.to_array()[ch]).collect();
            channels.push(AnyChannel::new(format!("{prefix}{name}").as_str(), FlatSamples::F32(v)));
        }
    };
    means("", &film.image());
    if film.has_layers() {
        for (k, name) in LAYER_NAMES.iter().enumerate() {
            means(&format!("{name}."), &film.layer_image(k));
        }
    }
    for (name, values) in film.aov_images() {
        channels.push(AnyChannel::new(name.as_str(), FlatSamples::F32(values)));
    }
    let sum = checksum(&cols);
    for (name, words) in aov_sum_names(&film.aovs).into_iter().zip(cols.aov) {
        channels.push(AnyChannel::new(name.as_str(), FlatSamples::U32(words)));
    }
    channels.push(AnyChannel::new("caustic.count", FlatSamples::U32(cols.count)));
    for (name, words) in sum_names("caustic.sum.").into_iter().zip(cols.sums) {
        channels.push(AnyChannel::new(name.as_str(), FlatSamples::U32(words)));
    }
    for (layer, cols) in LAYER_NAMES.iter().zip(cols.layers) {
        for (name, words) in sum_names(&format!("caustic.{layer}.")).into_iter().zip(cols) {
            channels.push(AnyChannel::new(name.as_str(), FlatSamples::U32(words)));
        }
    }
    let mut attributes = LayerAttributes::default();
    let h = header;
    for (k, v) in [
        ("caustic.format", FORMAT.to_string()),
        ("caustic.render", h.id.to_text()),
        ("caustic.shard", h.shard.to_string()),
        ("caustic.range", format!("{}..{}", h.range.start, h.range.end)),
        ("caustic.sums", h.sums.name().to_string()),
        ("caustic.checksum", format!("{sum:016x}")),
    ] {
        attributes.other.insert(Text::from(k), text(&v));
    }
    let layer = Layer::new(size, attributes, Encoding::SMALL_LOSSLESS, AnyChannels::sort(channels.into()));
    let tmp = path.with_file_name(format!(
        ".{}.{}.tmp.exr",
        path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default(),
        std::process::id()
    ));
    let result = Image::from_layer(layer)
        .write()
        .to_file(&tmp)
        .map_err(|e| part_err(path, format!("cannot write: {e}")))
        .and_then(|()| std::fs::rename(&tmp, path).map_err(|e| part_err(path, format!("cannot write: {e}"))));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

fn attribute(attrs: &LayerAttributes, key: &str) -> Option<String> {
    match attrs.other.get(&Text::from(key)) {
        Some(AttributeValue::Text(t)) => Some(String::from_utf8_lossy(t.bytes()).into_owned()),
        _ => None,
    }
}

fn parse_header(path: &Path, attrs: &LayerAttributes, width: usize, height: usize) -> Result<PartialHeader, FarmError> {
    let get = |key: &str| {
        attribute(attrs, key).ok_or_else(|| part_err(path, format!("is damaged: its `{key}` attribute is missing")))
    };
    match attribute(attrs, "caustic.format") {
        Some(f) if f == FORMAT => {}
        Some(f) => {
            return Err(part_err(path, format!("is a partial image of another format (`{f}`, expected `{FORMAT}`)")));
        }
        None => {
            return Err(part_err(
                path,
                "is not a caustic partial image (those are written by `caustic render --shard I/N`)",
            ));
        }
    }
    let damaged = |what: &str| part_err(path, format!("is damaged: bad {what}"));
    let id = RenderId::from_text(&get("caustic.render")?).ok_or_else(|| damaged("render identity"))?;
    let shard = match get("caustic.shard")?.parse::<super::shard::ShardSpec>() {
        Ok(super::shard::ShardSpec::Fixed(s)) => s,
        _ => return Err(damaged("shard")),
    };
    let range = get("caustic.range")?;
    let (a, b) = range.split_once("..").ok_or_else(|| damaged("sample range"))?;
    let range = match (a.parse::<u32>(), b.parse::<u32>()) {
        (Ok(a), Ok(b)) if a <= b => a..b,
        _ => return Err(damaged("sample range")),
    };
    let sums = match get("caustic.sums")?.as_str() {
        "exact" => SumKind::Exact,
        "runs" => SumKind::Runs,
        _ => return Err(damaged("sum kind")),
    };
    let (w, h) = (id.get("width"), id.get("height"));
    if w != Some(&width.to_string()) || h != Some(&height.to_string()) {
        return Err(damaged("size (the pixels do not match the render's size)"));
    }
    let layers = id.get("layers") == Some("true");
    let aovs = match id.get("aovs") {
        None | Some("none") => AovList::default(),
        Some(text) => AovList::parse(text).map_err(|_| damaged("AOV list"))?,
    };
    Ok(PartialHeader { id, shard, range, sums, width: width as u32, height: height as u32, layers, aovs })
}

/// Reads only the header of the partial image `path` (fast: no pixels are decoded).
pub fn read_header(path: &Path) -> Result<PartialHeader, FarmError> {
    let file = std::fs::File::open(path).map_err(|e| part_err(path, read_message(exr::error::Error::Io(e))))?;
    let meta = exr::meta::MetaData::read_from_buffered(std::io::BufReader::new(file), false)
        .map_err(|e| part_err(path, read_message(e)))?;
    let header = meta.headers.first().ok_or_else(|| part_err(path, "has no image in it"))?;
    let size = header.layer_size;
    parse_header(path, &header.own_attributes, size.width(), size.height())
}

fn read_message(e: exr::error::Error) -> String {
    match e {
        exr::error::Error::Io(io) if io.kind() == std::io::ErrorKind::NotFound => "does not exist".into(),
        exr::error::Error::Io(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
            "is truncated (the file ends early)".into()
        }
        e => format!("cannot be read as OpenEXR: {e}"),
    }
}

/// Reads the partial image `path`: header and film, checked against the checksum.
pub fn read_partial(path: &Path) -> Result<Partial, FarmError> {
    let bytes = std::fs::read(path).map_err(|e| part_err(path, read_message(exr::error::Error::Io(e))))?;
    read_partial_bytes(&bytes, path)
}

/// Reads a partial image from the bytes of the file `path` (named in errors).
pub fn read_partial_bytes(bytes: &[u8], path: &Path) -> Result<Partial, FarmError> {
    // The header first: a file that is not a part, or claims an absurd size, is refused before
    // any pixel memory is allocated.
    let meta = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false)
        .map_err(|e| part_err(path, read_message(e)))?;
    let first = meta.headers.first().ok_or_else(|| part_err(path, "has no image in it"))?;
    let size = first.layer_size;
    if size.area() as u64 > crate::scene::desc::MAX_PIXELS {
        return Err(part_err(path, format!("is damaged: it claims {} x {} pixels", size.width(), size.height())));
    }
    parse_header(path, &first.own_attributes, size.width(), size.height())?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| part_err(path, read_message(e)))?;
    let layer = &image.layer_data;
    let (width, height) = (layer.size.width(), layer.size.height());
    let header = parse_header(path, &layer.attributes, width, height)?;
    let n = width * height;
    let channel = |name: &str| -> Result<&Vec<u32>, FarmError> {
        let c = layer.channel_data.list.iter().find(|c| c.name == *name);
        match c.map(|c| &c.sample_data) {
            Some(FlatSamples::U32(v)) if v.len() == n => Ok(v),
            Some(_) => Err(part_err(path, format!("is damaged: channel `{name}` has the wrong type or size"))),
            None => Err(part_err(path, format!("is damaged: channel `{name}` is missing"))),
        }
    };
    let count = channel("caustic.count")?.clone();
    let sums: Vec<Vec<u32>> =
        sum_names("caustic.sum.").iter().map(|s| channel(s).cloned()).collect::<Result<_, _>>()?;
    let mut layers = Vec::new();
    if header.layers {
        for name in LAYER_NAMES {
            let cols =
                sum_names(&format!("caustic.{name}.")).iter().map(|s| channel(s).cloned()).collect::<Result<_, _>>()?;
            layers.push(cols);
        }
    }
    let aov = aov_sum_names(&header.aovs).iter().map(|s| channel(s).cloned()).collect::<Result<_, _>>()?;
    let cols = Columns { count, sums, layers, aov };
    let expected = attribute(&layer.attributes, "caustic.checksum");
    if expected.as_deref() != Some(&format!("{:016x}", checksum(&cols))) {
        return Err(part_err(path, "is damaged: its sums do not match their checksum"));
    }
    let held = header.range.len() as u32;
    if let Some(c) = cols.count.iter().find(|&&c| c > held) {
        return Err(part_err(path, format!("is damaged: a pixel holds {c} samples of a shard of {held}")));
    }
    let film = film_of(&cols, &header);
    Ok(Partial { header, film })
}

fn film_of(c: &Columns, h: &PartialHeader) -> Film {
    let mut film = Film::new(h.width, h.height, h.layers).with_aovs(&h.aovs);
    let join = |cols: &[Vec<u32>], p: usize| -> [i128; 3] {
        std::array::from_fn(|ch| (0..4).fold(0u128, |acc, w| acc | (cols[ch * 4 + w][p] as u128) << (32 * w)) as i128)
    };
    let width = h.width;
    for t in &mut film.tiles {
        for j in 0..t.height {
            for i in 0..t.width {
                let k = (j * t.width + i) as usize;
                let p = ((t.y0 + j) * width + t.x0 + i) as usize;
                t.count[k] = c.count[p];
                t.sum[k] = join(&c.sums, p);
                if let Some(l) = t.layers.get_mut(k) {
                    for (acc, cols) in l.iter_mut().zip(&c.layers) {
                        *acc = join(cols, p);
                    }
                }
                let stride = t.aov_stride as usize;
                for (ch, acc) in t.aov[k * stride..(k + 1) * stride].iter_mut().enumerate() {
                    *acc = (0..4).fold(0u128, |a, w| a | (c.aov[ch * 4 + w][p] as u128) << (32 * w)) as i128;
                }
            }
        }
    }
    film
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Color;
    use crate::scene::desc::{IntegratorDesc, Sampling};

    fn header(layers: bool) -> PartialHeader {
        let mut settings = crate::render::RenderSettings::new(&Sampling {
            width: 19,
            height: 17,
            crop: crate::film::Crop::full(19, 17),
            filter: crate::film::filter::Filter::Box,
            sample_border: false,
            spp: 10,
            strata: 1,
            seed: 1,
            sampler: crate::sampling::SamplerKind::Jittered,
            antialias: true,
            aovs: AovList::default(),
            xyz: false,
        });
        settings.layers = layers;
        let id = RenderId::new(&[], &Default::default(), &IntegratorDesc::default(), &settings).unwrap();
        PartialHeader {
            id,
            shard: Shard { index: 1, count: 3 },
            range: 3..6,
            sums: SumKind::Exact,
            width: 19,
            height: 17,
            layers,
            aovs: AovList::default(),
        }
    }

    fn film(layers: bool) -> Film {
        let mut film = Film::new(19, 17, layers);
        for (n, t) in film.tiles.iter_mut().enumerate() {
            for k in 0..t.count.len() {
                let v = (n * 1000 + k) as f32 * 0.37;
                t.add(k, &[Color::new(v, -v, 1e-9), Color::splat(1e5), Color::ZERO, Color::splat(0.25)]);
                if k % 3 == 0 {
                    t.add(k, &[Color::splat(2.0), Color::ZERO, Color::ZERO, Color::ZERO]);
                }
            }
        }
        film
    }

    #[test]
    fn round_trips_exactly_with_and_without_layers() {
        let dir = std::env::temp_dir().join(format!("caustic-partial-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for layers in [false, true] {
            let path = dir.join(format!("p{layers}.exr"));
            let (h, f) = (header(layers), film(layers));
            write_partial(&path, &h, &f).unwrap();
            assert_eq!(read_header(&path).unwrap(), h);
            let p = read_partial(&path).unwrap();
            assert_eq!(p.header, h);
            assert!(p.film == f, "the film changed in the round trip");
            // Any viewer sees the mean in R, G, B.
            let img = crate::film::output::read_exr(&path).unwrap();
            assert_eq!(img, f.image());
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Issue 30, item 10: AOV sums (first-hit values and the sums of squares of `variance`) are
    /// saved and read back exactly, and the checksum covers them.
    #[test]
    fn aov_sums_round_trip_exactly() {
        let aovs = AovList::parse("albedo,dd.y:depth,variance,spp").unwrap();
        let mut h = header(false);
        for (k, v) in &mut h.id.fields {
            if k == "aovs" {
                *v = aovs.to_string();
            }
        }
        h.aovs = aovs.clone();
        let mut f = Film::new(19, 17, false).with_aovs(&aovs);
        for (n, t) in f.tiles.iter_mut().enumerate() {
            for k in 0..t.count.len() {
                let v = (n * 100 + k) as f32 * 0.01;
                t.add(k, &[Color::splat(v), Color::ZERO, Color::ZERO, Color::ZERO]);
                t.add_first_hit(k, &[v, 0.5, -v, 1e3 + v], if k % 2 == 0 { 1.0 } else { -1.25 });
            }
        }
        let bytes = written(&h, &f);
        let p = read_partial_bytes(&bytes, Path::new("aov.exr")).unwrap();
        assert_eq!(p.header, h);
        assert!(p.film == f && p.film.aov_images() == f.aov_images());
        assert!(f.tiles[0].aov.iter().any(|&v| v != 0));
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(200))]
        /// Whatever bytes of a part are changed or cut, reading it never panics, and a read
        /// that succeeds returns exactly the sums and counts that were written (the checksum
        /// guards them; a change elsewhere may only touch the means or the header).
        #[test]
        fn damaged_bytes_are_refused_or_harmless(
            flips in proptest::collection::vec((0.0f64..1.0, 0u8..=255), 0..4),
            keep in 0.0f64..1.2,
        ) {
            let (h, f) = (header(true), film(true));
            let bytes = written(&h, &f);
            let mut bad = bytes.clone();
            for (at, v) in &flips {
                let i = (*at * bad.len() as f64) as usize % bad.len();
                bad[i] ^= v.max(&1);
            }
            bad.truncate(((keep * bytes.len() as f64) as usize).min(bytes.len()));
            if let Ok(p) = read_partial_bytes(&bad, Path::new("fuzzed.exr")) {
                proptest::prop_assert!(p.film == f);
            }
        }
    }

    /// The bytes of a partial image of `film`.
    fn written(h: &PartialHeader, film: &Film) -> Vec<u8> {
        let path = std::env::temp_dir().join(format!(
            "caustic-partial-bytes-{}-{:?}.exr",
            std::process::id(),
            std::thread::current().id()
        ));
        write_partial(&path, h, film).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        bytes
    }

    #[test]
    fn damage_is_refused_with_the_file_named() {
        let dir = std::env::temp_dir().join(format!("caustic-partial-bad-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("p.exr");
        write_partial(&path, &header(false), &film(false)).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        for cut in [10, bytes.len() / 2, bytes.len() - 3] {
            let t = dir.join(format!("cut{cut}.exr"));
            std::fs::write(&t, &bytes[..cut]).unwrap();
            let e = read_partial(&t).err().expect("a truncated file must be refused").to_string();
            assert!(e.contains(&format!("cut{cut}.exr")), "{e}");
        }
        let plain = dir.join("plain.exr");
        crate::film::output::write_image(&crate::film::Image::new(4, 4), &plain).unwrap();
        let e = read_partial(&plain).err().unwrap().to_string();
        assert!(e.contains("not a caustic partial image"), "{e}");
        let e = read_partial(&dir.join("none.exr")).err().unwrap().to_string();
        assert!(e.contains("does not exist"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
