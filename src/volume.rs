//! Grids of values in Mitsuba's binary `.vol` format, the files behind Mitsuba 3's `gridvolume`
//! (a medium's density or albedo) and `sdfgrid` (a signed distance field): one reader for both,
//! and the trilinear lookup of a `gridvolume`.
//!
//! The format (Mitsuba 3, src/volumes/grid.cpp, "Volume file format"): the bytes `VOL`, version
//! byte 3, then little-endian 32-bit integers for the encoding (1: dense 32-bit floats), the x,
//! y and z resolutions and the channel count, a bounding box of six floats (x, y, z minimum,
//! then maximum), then the values, x fastest and the channels of a texel innermost:
//! `values[((z * ny + y) * nx + x) * channels + c]`.
//!
//! A `gridvolume` spans the unit cube [0, 1]^3 of its own space (its `to_world` places it) with
//! texel centres at (i + 0.5) / n, as a texture's: a lookup at u along an axis of n texels
//! blends texels floor(u n - 0.5) and the next by the fraction of u n - 0.5, indices clamped
//! to the grid (Mitsuba's default `wrap_mode`, clamp), so the outer half texel holds the edge
//! value. Checked in Mitsuba 3's src/volumes/grid.cpp: the lookup point is the world point
//! mapped by the inverse of `to_world`, and `interpolate_spectral` weights the eight texels the
//! texture fetches by the fractions of `fmadd(p, res, -0.5)` after `floor`.

use crate::math::{Color, Vec3};

/// Largest side of a grid that is read (an SDF voxel packs its cell index into 10 bits per axis;
/// a medium grid of 1024^3 floats is already 4 GiB).
pub const MAX_GRID_SIDE: usize = 1024;

/// What is wrong with a `.vol` grid file.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("{0}")]
pub struct VolError(pub String);

/// What a reader of `.vol` files accepts: the channel counts, the smallest resolution along each
/// axis, and what a grid is called in its error messages ("an SDF grid").
#[derive(Clone, Copy, Debug)]
pub struct VolShape {
    pub channels: &'static [usize],
    pub min_side: usize,
    pub what: &'static str,
}

impl VolShape {
    /// A medium's `gridvolume`: 1 channel (a grey density or albedo) or 3 (RGB).
    pub const MEDIUM: VolShape = VolShape { channels: &[1, 3], min_side: 1, what: "a grid volume" };
}

/// A grid read from a `.vol` file: values as stored (see the module's notes for the order).
#[derive(Clone, Debug, PartialEq)]
pub struct VolGrid {
    pub nx: usize,
    pub ny: usize,
    pub nz: usize,
    pub channels: usize,
    /// The bounding box the file records: x, y, z minimum, then maximum (Mitsuba reads it only
    /// with `use_grid_bbox`).
    pub bbox: [f32; 6],
    pub values: Vec<f32>,
}

/// Reads a `.vol` file's bytes into a grid of the shape `shape` accepts; every value is finite.
/// Errors say what is wrong (not which file: the loaders add that).
pub fn parse_vol(bytes: &[u8], shape: VolShape) -> Result<VolGrid, VolError> {
    let err = |m: String| Err(VolError(m));
    if bytes.len() < 48 {
        return err(format!("a .vol file has a 48-byte header; this one has {} bytes in all", bytes.len()));
    }
    if &bytes[0..3] != b"VOL" {
        return err("not a Mitsuba .vol file (it does not start with `VOL`)".into());
    }
    if bytes[3] != 3 {
        return err(format!("version {} of the .vol format is not supported (expected 3)", bytes[3]));
    }
    let int = |at: usize| i32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    let float = |at: usize| f32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    let encoding = int(4);
    if encoding != 1 {
        return err(format!("encoding {encoding} is not supported (expected 1: 32-bit floats)"));
    }
    let (x, y, z, channels) = (int(8), int(12), int(16), int(20));
    if !shape.channels.iter().any(|&c| c as i64 == i64::from(channels)) {
        let allowed = shape.channels.iter().map(|c| c.to_string()).collect::<Vec<_>>().join(" or ");
        let plural = if shape.channels == [1] { "" } else { "s" };
        return err(format!("{} has {allowed} channel{plural}; this file has {channels}", shape.what));
    }
    for (axis, n) in [("x", x), ("y", y), ("z", z)] {
        if !(shape.min_side as i64..=MAX_GRID_SIDE as i64).contains(&i64::from(n)) {
            return err(format!("the {axis} resolution must be {} to {MAX_GRID_SIDE}, found {n}", shape.min_side));
        }
    }
    let (nx, ny, nz, channels) = (x as usize, y as usize, z as usize, channels as usize);
    let count = nx * ny * nz * channels;
    let data = &bytes[48..];
    if data.len() as u64 != 4 * count as u64 {
        let per = if channels == 1 { String::new() } else { format!(" of {channels} channels") };
        return err(format!(
            "a {nx} x {ny} x {nz} grid{per} holds {} bytes of values; the file has {} (cut short or padded?)",
            4 * count as u64,
            data.len()
        ));
    }
    let values: Vec<f32> = data.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        let (texel, c) = (i / channels, i % channels);
        let (tx, ty, tz) = (texel % nx, texel / nx % ny, texel / (nx * ny));
        let at = if channels == 1 { String::new() } else { format!(", channel {c}") };
        return err(format!("value {i} of the grid (texel {tx}, {ty}, {tz}{at}) is not a finite number"));
    }
    let bbox = std::array::from_fn(|k| float(24 + 4 * k));
    Ok(VolGrid { nx, ny, nz, channels, bbox, values })
}

impl VolGrid {
    /// The grid as a `.vol` file's bytes (what `parse_vol` reads back).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut b = Vec::with_capacity(48 + 4 * self.values.len());
        b.extend(b"VOL\x03");
        for v in [1, self.nx, self.ny, self.nz, self.channels] {
            b.extend((v as i32).to_le_bytes());
        }
        for v in self.bbox.iter().chain(&self.values) {
            b.extend(v.to_le_bytes());
        }
        b
    }

    /// The resolution along each axis.
    #[inline]
    pub fn res(&self) -> [usize; 3] {
        [self.nx, self.ny, self.nz]
    }

    /// The first value `ok` refuses, with its texel and channel, for error messages.
    pub fn find(&self, ok: impl Fn(f32) -> bool) -> Option<(f32, [usize; 3], usize)> {
        let i = self.values.iter().position(|&v| !ok(v))?;
        let (texel, c) = (i / self.channels, i % self.channels);
        Some((self.values[i], [texel % self.nx, texel / self.nx % self.ny, texel / (self.nx * self.ny)], c))
    }

    /// Texel (x, y, z) as a colour (a one-channel grid's value in every channel).
    #[inline]
    pub fn texel(&self, x: usize, y: usize, z: usize) -> Color {
        let i = ((z * self.ny + y) * self.nx + x) * self.channels;
        if self.channels == 1 {
            Color::splat(self.values[i])
        } else {
            Color::new(self.values[i], self.values[i + 1], self.values[i + 2])
        }
    }

    /// The trilinear lookup at `p` in the grid's unit cube (texel centres at (i + 0.5) / n,
    /// clamped at the edges; see the module's notes). Points outside the cube get the nearest
    /// edge's values.
    #[inline]
    pub fn eval(&self, p: Vec3) -> Color {
        let (x, fx) = texel_pair(p.x, self.nx);
        let (y, fy) = texel_pair(p.y, self.ny);
        let (z, fz) = texel_pair(p.z, self.nz);
        let lerp = |a: Color, b: Color, f: f32| a * (1.0 - f) + b * f;
        let row = |y: usize, z: usize| lerp(self.texel(x[0], y, z), self.texel(x[1], y, z), fx);
        let plane = |z: usize| lerp(row(y[0], z), row(y[1], z), fy);
        lerp(plane(z[0]), plane(z[1]), fz)
    }

    /// The largest value of any channel over texels `lo..=hi` (per axis, clamped to the grid).
    pub fn max_over(&self, lo: [usize; 3], hi: [usize; 3]) -> f32 {
        let mut m = f32::NEG_INFINITY;
        for z in lo[2]..=hi[2].min(self.nz - 1) {
            for y in lo[1]..=hi[1].min(self.ny - 1) {
                let row = ((z * self.ny + y) * self.nx) * self.channels;
                let (a, b) = (row + lo[0] * self.channels, row + (hi[0].min(self.nx - 1) + 1) * self.channels);
                for &v in &self.values[a..b] {
                    m = m.max(v);
                }
            }
        }
        m
    }
}

/// The two texels a lookup at `u` along an axis of `n` texels blends, and the weight of the
/// second.
#[inline]
fn texel_pair(u: f32, n: usize) -> ([usize; 2], f32) {
    let x = u * n as f32 - 0.5;
    let lo = x.floor();
    // `as` saturates, so far-away points clamp like near ones.
    let last = n as i64 - 1;
    let i = (lo as i64).clamp(-1, last);
    ([i.max(0) as usize, (i + 1).min(last) as usize], x - lo)
}

/// The texels whose trilinear footprint reaches the interval [a, b] of the unit cube along an
/// axis of `n` texels: every lookup at a point of [a, b] blends texels of this range only.
pub fn texel_range(a: f32, b: f32, n: usize) -> (usize, usize) {
    let last = n as i64 - 1;
    let lo = ((f64::from(a) * n as f64 - 0.5).floor() as i64).clamp(0, last);
    let hi = ((f64::from(b) * n as f64 - 0.5).floor() as i64).clamp(-1, last - 1) + 1;
    (lo as usize, hi as usize)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The bytes of a .vol file of `n` texels holding `values` (channels innermost), which
    /// need not be as many as the header says.
    fn vol_bytes(n: [usize; 3], channels: usize, values: &[f32]) -> Vec<u8> {
        let g = VolGrid {
            nx: n[0],
            ny: n[1],
            nz: n[2],
            channels,
            bbox: [0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
            values: values.to_vec(),
        };
        g.to_bytes()
    }

    #[test]
    fn reads_three_channels_in_order() {
        let values: Vec<f32> = (0..2 * 3 * 4 * 3).map(|i| i as f32).collect();
        let g = parse_vol(&vol_bytes([2, 3, 4], 3, &values), VolShape::MEDIUM).unwrap();
        assert_eq!((g.nx, g.ny, g.nz, g.channels), (2, 3, 4, 3));
        assert_eq!(g.bbox, [0.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
        // Texel (1, 2, 3): ((3 * 3 + 2) * 2 + 1) * 3 = 69.
        assert_eq!(g.texel(1, 2, 3), Color::new(69.0, 70.0, 71.0));
    }

    /// Lookups at texel centres give the texels; half-way between two centres their mean; the
    /// outer half texel the edge value (clamp).
    #[test]
    fn trilinear_lookup_uses_texel_centres() {
        let values = [1.0f32, 3.0, 5.0, 7.0];
        let g = parse_vol(&vol_bytes([4, 1, 1], 1, &values), VolShape::MEDIUM).unwrap();
        let at = |x: f32| g.eval(Vec3::new(x, 0.5, 0.5)).r();
        for (i, v) in values.iter().enumerate() {
            assert_eq!(at((i as f32 + 0.5) / 4.0), *v);
        }
        assert_eq!(at(0.25), 2.0);
        for (x, want) in [(0.0, 1.0), (0.1, 1.0), (1.0, 7.0), (-3.0, 1.0), (0.95, 7.0)] {
            assert!((at(x) - want).abs() < 1e-6, "at {x}: {} vs {want}", at(x));
        }
        assert!((at(0.3) - (3.0 + 2.0 * (0.3 * 4.0 - 1.5))).abs() < 1e-5);
    }

    #[test]
    fn bad_files_are_errors() {
        let good = vol_bytes([2, 2, 2], 3, &[0.5; 24]);
        assert!(parse_vol(&good, VolShape::MEDIUM).is_ok());
        let with = |at: usize, v: i32| {
            let mut b = good.clone();
            b[at..at + 4].copy_from_slice(&v.to_le_bytes());
            b
        };
        for (bytes, want) in [
            (good[..47].to_vec(), "48-byte header"),
            (good[..good.len() - 4].to_vec(), "cut short"),
            ([good.clone(), vec![0]].concat(), "padded"),
            (with(20, 2), "1 or 3 channels; this file has 2"),
            (with(8, 0), "x resolution must be 1 to 1024, found 0"),
            (with(16, -5), "z resolution"),
            (with(12, i32::MAX), "y resolution"),
            (with(48 + 4 * 7, f32::INFINITY.to_bits() as i32), "value 7 of the grid (texel 0, 1, 0, channel 1)"),
        ] {
            let e = parse_vol(&bytes, VolShape::MEDIUM).unwrap_err().to_string();
            assert!(e.contains(want), "{want}: {e}");
        }
    }

    proptest! {
        /// Arbitrary bytes, alone or after a valid header, are a grid or an error, never a
        /// panic; an accepted grid has as many values as its header says, all finite.
        #[test]
        fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..400), channels in 1usize..4) {
            let _ = parse_vol(&bytes, VolShape::MEDIUM);
            let mut b = vol_bytes([2, 3, 1], channels, &[]);
            b.extend(&bytes);
            if let Ok(g) = parse_vol(&b, VolShape::MEDIUM) {
                prop_assert_eq!(g.values.len(), 6 * channels);
                prop_assert!(g.values.iter().all(|v| v.is_finite()));
            }
        }

        /// A lookup anywhere lies between the smallest and largest texel of the range
        /// `texel_range` gives for its point, and a grid's values round-trip through the file.
        #[test]
        fn lookups_stay_within_their_footprint(
            values in prop::collection::vec(0.0f32..10.0, 27),
            p in prop::array::uniform3(-0.2f32..1.2),
        ) {
            let g = parse_vol(&vol_bytes([3, 3, 3], 1, &values), VolShape::MEDIUM).unwrap();
            prop_assert_eq!(&g.values, &values);
            let v = g.eval(Vec3::from(p)).r();
            let r: Vec<(usize, usize)> = (0..3).map(|a| texel_range(p[a], p[a], 3)).collect();
            let hi = g.max_over([r[0].0, r[1].0, r[2].0], [r[0].1, r[1].1, r[2].1]);
            prop_assert!(v <= hi * (1.0 + 1e-6), "{} above {}", v, hi);
            prop_assert!(v >= 0.0);
        }
    }
}
