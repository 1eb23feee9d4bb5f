//! Irradiance caching for the final gather (Ward, Rubinstein and Clear 1988; gradients after Ward
//! and Heckbert 1992, "Irradiance gradients"; the forms used here are those of Jarosz, Křivánek
//! et al., "Practical global illumination with irradiance caching", SIGGRAPH 2008 course).
//!
//! A record holds the indirect irradiance E at a point of a Lambertian surface, measured by a
//! stratified final gather of M x N cosine-distributed rays, with its rotational and translational
//! gradients and its validity radius R (the harmonic mean of the gather rays' hit distances,
//! clamped to a range of pixel footprints and limited by the translational gradient). Elsewhere E
//! is interpolated from the records whose error
//!
//!   eps_i(x, n) = |x - x_i| / R_i + sqrt(1 - n . n_i)
//!
//! is below the threshold `a`, weighted by 1/eps_i - 1/a (Tabellion and Lamorlette 2004: weights
//! fall to zero at the edge of a record's reach, so no seams), each extrapolated by its
//! gradients. Records only ever hold the indirect diffuse part; direct light and caustics stay
//! per sample. A point no record reaches is gathered per sample as before, so the cache only
//! ever replaces a gather by an interpolation where a record is close.
//!
//! Determinism: the cache is filled before rendering by `fill` (photon.rs) in a fixed order and
//! only read afterwards; lookups sum their records in a fixed order (cell by cell, by index).

use crate::math::{Color, Frame, Vec3};
use std::collections::HashMap;
use std::f32::consts::PI;

/// A record is created where no record reaches with an error below this fraction of `a`, so
/// records overlap and every lookup interpolates a few of them.
pub const COVER: f32 = 0.7;

/// One irradiance record.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Record {
    pub p: Vec3,
    pub n: Vec3,
    /// Irradiance (W/m^2) of the indirect light arriving over the hemisphere of `n`.
    pub e: Color,
    /// Validity radius (scene units).
    pub r: f32,
    /// Per colour channel, in world space: the rotational gradient (E at a normal n is
    /// E + (n_i x n) . grad_r to first order) and the translational one (E + (x - x_i) . grad_t).
    pub grad_r: [Vec3; 3],
    pub grad_t: [Vec3; 3],
    /// The camera bounce it was made at: its gathers read photons of the bounces the depth
    /// limit leaves there, so it serves only points at the same bounce.
    pub bounce: u32,
}

impl Record {
    /// The record's error at (p, n): `None` where it is not valid at all (the normal turned more
    /// than 90 degrees, or the point in front of the record, where the record cannot see what
    /// lights it).
    #[inline]
    pub fn error(&self, p: Vec3, n: Vec3) -> Option<f32> {
        let d = p - self.p;
        let cos = n.dot(self.n);
        if cos <= 0.0 {
            return None;
        }
        // Ward's test: points in front of the record see light it could not.
        if d.dot(n + self.n) * 0.5 < -0.05 * self.r {
            return None;
        }
        Some(d.length() / self.r + (1.0 - cos).max(0.0).sqrt())
    }

    /// E extrapolated to (p, n) by the gradients (first order), never negative.
    #[inline]
    pub fn extrapolate(&self, p: Vec3, n: Vec3) -> Color {
        let d = p - self.p;
        let axis = self.n.cross(n);
        let ch = |c: usize| (self.e[c] + axis.dot(self.grad_r[c]) + d.dot(self.grad_t[c])).max(0.0);
        Color::new(ch(0), ch(1), ch(2))
    }
}

/// The radiance a gather ray brought back and the distance to the first surface it hit
/// (infinite when it left the scene).
#[derive(Clone, Copy, Debug)]
pub struct GatherSample {
    pub l: Color,
    pub dist: f32,
}

/// Strata of a record's gather: `m` in theta, `n` in phi (Ward's N ~ pi M), about `rays` in all.
pub fn strata(rays: u32) -> (usize, usize) {
    let m = ((rays as f32 / PI).sqrt().round() as usize).max(2);
    let n = ((rays as f32 / m as f32).round() as usize).max(3);
    (m, n)
}

/// Direction of stratum (j, k) of an `m` x `n` cosine-weighted stratification, jittered by `u`,
/// in the local frame (z the normal), with its theta's sine and cosine.
#[inline]
pub fn stratum_direction(j: usize, k: usize, m: usize, n: usize, u: (f32, f32)) -> Vec3 {
    let s2 = (j as f32 + u.0) / m as f32;
    let (sin_t, cos_t) = (s2.sqrt(), (1.0 - s2).max(0.0).sqrt());
    let phi = 2.0 * PI * (k as f32 + u.1) / n as f32;
    Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t)
}

/// A record at `p` with normal `frame.z` from an `m` x `n` stratified gather whose samples are
/// `samples[j * n + k]` with the local directions `dirs[j * n + k]` (from `stratum_direction`).
/// `r_range` clamps the validity radius.
pub fn make_record(
    p: Vec3,
    frame: &Frame,
    m: usize,
    n: usize,
    samples: &[GatherSample],
    dirs: &[Vec3],
    r_range: (f32, f32),
) -> Record {
    debug_assert_eq!(samples.len(), m * n);
    let at = |j: usize, k: usize| samples[j * n + k];
    let mut sum = Color::ZERO;
    let mut inv_dist = 0.0f64;
    for s in samples {
        sum += s.l;
        inv_dist += if s.dist.is_finite() && s.dist > 0.0 { 1.0 / s.dist as f64 } else { 0.0 };
    }
    let e = sum * (PI / (m * n) as f32);

    // Rotational gradient: turning the normal about v_k (perpendicular to the stratum's
    // azimuth) by a small angle changes each sample's cosine weight by -tan(theta) per radian.
    let mut grad_r = [Vec3::ZERO; 3];
    for j in 0..m {
        for k in 0..n {
            let d = dirs[j * n + k];
            let sin_t = (d.x * d.x + d.y * d.y).sqrt();
            if sin_t <= 0.0 || d.z <= 1e-4 {
                continue;
            }
            let tan_t = sin_t / d.z;
            // v_k: the azimuth turned by 90 degrees.
            let v = Vec3::new(-d.y / sin_t, d.x / sin_t, 0.0);
            let l = at(j, k).l;
            for c in 0..3 {
                grad_r[c] += v * (tan_t * l[c]);
            }
        }
    }
    let scale = PI / (m * n) as f32;
    for g in &mut grad_r {
        *g *= scale;
    }

    // Translational gradient: how the cells' solid angles change as the point moves, from the
    // radiance differences across the cell boundaries over the nearer of the two distances.
    let mut grad_t = [Vec3::ZERO; 3];
    let near = |a: GatherSample, b: GatherSample| a.dist.min(b.dist);
    for k in 0..n {
        let phi_c = 2.0 * PI * (k as f32 + 0.5) / n as f32;
        let u_k = Vec3::new(phi_c.cos(), phi_c.sin(), 0.0);
        let phi_b = 2.0 * PI * k as f32 / n as f32;
        let v_k = Vec3::new(-phi_b.sin(), phi_b.cos(), 0.0);
        let prev_k = (k + n - 1) % n;
        let mut acc_u = Color::ZERO;
        let mut acc_v = Color::ZERO;
        for j in 0..m {
            let s = at(j, k);
            if j > 0 {
                // Boundary between theta rows j - 1 and j.
                let s2 = j as f32 / m as f32;
                let w = s2.sqrt() * (1.0 - s2) / near(s, at(j - 1, k));
                acc_u += (s.l - at(j - 1, k).l) * w;
            }
            // Boundary between azimuth columns k - 1 and k.
            let (s_lo, s_hi) = ((j as f32 / m as f32).sqrt(), ((j + 1) as f32 / m as f32).sqrt());
            let w = (s_hi - s_lo) / near(s, at(j, prev_k));
            acc_v += (s.l - at(j, prev_k).l) * w;
        }
        for (c, g) in grad_t.iter_mut().enumerate() {
            *g += u_k * (2.0 * PI / n as f32 * acc_u[c]) + v_k * acc_v[c];
        }
    }

    // Validity radius: the harmonic mean distance, clamped, and no larger than the distance over
    // which the translational gradient would change E by its own size.
    let mut r = if inv_dist > 0.0 { ((m * n) as f64 / inv_dist) as f32 } else { f32::INFINITY };
    let lum = crate::math::luminance(e);
    let grad_lum = grad_t[0] * 0.2126 + grad_t[1] * 0.7152 + grad_t[2] * 0.0722;
    let g = grad_lum.length();
    if g > 0.0 && lum > 0.0 {
        r = r.min(lum / g);
    }
    let clamped = r.clamp(r_range.0, r_range.1.max(r_range.0));
    // A radius raised to the minimum would let the gradient extrapolate past E's own size (next
    // to a corner the gradient is huge): scale it down in proportion (Krivanek et al. 2008), so
    // within the record's reach a R the change stays below a E.
    if clamped > r && r > 0.0 {
        let k = r / clamped;
        for g in &mut grad_t {
            *g *= k;
        }
    } else if clamped > r {
        grad_t = [Vec3::ZERO; 3];
    }
    let r = clamped;
    let world = |v: Vec3| frame.to_world(v);
    Record { p, n: frame.z, e, r, grad_r: grad_r.map(world), grad_t: grad_t.map(world), bounce: 1 }
}

/// The records and a multi-level hash grid over their reach: a record whose reach (radius
/// a R) is r lives on the finest level whose cells are at least 2r wide, in the (at most 8) cells
/// its reach overlaps, so a lookup reads one cell per level.
pub struct IrradianceCache {
    records: Vec<Record>,
    /// Error threshold `a`.
    a: f32,
    base: f32,
    /// Levels holding records (bit l for level l).
    levels: u64,
    cells: HashMap<(u32, i32, i32, i32), (u32, u32), CellHash>,
    ids: Vec<u32>,
}

/// Cells per axis beyond which a coordinate is clamped (keeps keys in i32 for any scene).
const CELL_LIMIT: f32 = 1.0e9;

impl IrradianceCache {
    pub fn new(records: Vec<Record>, a: f32) -> Self {
        let reach = |r: &Record| a * r.r;
        let base = records.iter().map(reach).fold(f32::INFINITY, f32::min);
        let base = if base.is_finite() && base > 0.0 { 2.0 * base } else { 1.0 };
        let mut entries: Vec<((u32, i32, i32, i32), u32)> = Vec::new();
        let mut levels = 0u64;
        for (i, rec) in records.iter().enumerate() {
            let r = reach(rec);
            let mut level = 0u32;
            while base * (1u64 << level) as f32 > 0.0 && base * ((1u64 << level) as f32) < 2.0 * r && level < 63 {
                level += 1;
            }
            levels |= 1 << level;
            let size = base * (1u64 << level) as f32;
            let lo = cell_of(rec.p - Vec3::splat(r), size);
            let hi = cell_of(rec.p + Vec3::splat(r), size);
            for x in lo.0..=hi.0 {
                for y in lo.1..=hi.1 {
                    for z in lo.2..=hi.2 {
                        entries.push(((level, x, y, z), i as u32));
                    }
                }
            }
        }
        entries.sort_unstable();
        let mut cells = HashMap::with_hasher(CellHash);
        let mut ids = Vec::with_capacity(entries.len());
        let mut i = 0;
        while i < entries.len() {
            let key = entries[i].0;
            let start = ids.len() as u32;
            while i < entries.len() && entries[i].0 == key {
                ids.push(entries[i].1);
                i += 1;
            }
            cells.insert(key, (start, ids.len() as u32));
        }
        IrradianceCache { records, a, base, levels, cells, ids }
    }

    pub fn empty(a: f32) -> Self {
        Self::new(Vec::new(), a)
    }

    pub fn len(&self) -> usize {
        self.records.len()
    }

    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }

    pub fn records(&self) -> &[Record] {
        &self.records
    }

    /// Heap bytes held (records and grid), roughly.
    pub fn memory_bytes(&self) -> usize {
        self.records.capacity() * size_of::<Record>() + self.ids.capacity() * 4 + self.cells.capacity() * 32
    }

    /// Calls `f` with each record whose cells hold `p`, in a fixed order.
    #[inline]
    fn for_each_near(&self, p: Vec3, mut f: impl FnMut(&Record)) {
        let mut levels = self.levels;
        while levels != 0 {
            let level = levels.trailing_zeros();
            levels &= levels - 1;
            let c = cell_of(p, self.base * (1u64 << level) as f32);
            if let Some(&(s, e)) = self.cells.get(&(level, c.0, c.1, c.2)) {
                for &i in &self.ids[s as usize..e as usize] {
                    f(&self.records[i as usize]);
                }
            }
        }
    }

    /// Irradiance at (p, n) interpolated from the records within the error threshold, `None`
    /// where there is none. Allocates nothing.
    #[inline]
    pub fn lookup(&self, p: Vec3, n: Vec3, bounce: u32) -> Option<Color> {
        let inv_a = 1.0 / self.a;
        let (mut sum, mut sum_w) = (Color::ZERO, 0.0f32);
        self.for_each_near(p, |rec| {
            if rec.bounce != bounce {
                return;
            }
            let Some(eps) = rec.error(p, n) else { return };
            if eps < self.a {
                let w = 1.0 / eps.max(1e-4) - inv_a;
                sum += rec.extrapolate(p, n) * w;
                sum_w += w;
            }
        });
        (sum_w > 0.0).then(|| sum / sum_w)
    }

    /// True when some record reaches (p, n) with an error below `limit`.
    pub fn covers(&self, p: Vec3, n: Vec3, limit: f32, bounce: u32) -> bool {
        let mut found = false;
        self.for_each_near(p, |rec| {
            found |= rec.bounce == bounce && rec.error(p, n).is_some_and(|e| e < limit);
        });
        found
    }
}

/// A cheap hash for cell keys (std's SipHash showed in profiles): the key's words folded by
/// multiply-xor, finished by a 64-bit mix. Keys are not chosen by users, so no DoS concern.
#[derive(Clone, Copy, Default)]
struct CellHash;

#[derive(Default)]
struct CellHasher(u64);

impl std::hash::BuildHasher for CellHash {
    type Hasher = CellHasher;
    fn build_hasher(&self) -> CellHasher {
        CellHasher(0)
    }
}

impl std::hash::Hasher for CellHasher {
    fn finish(&self) -> u64 {
        let mut x = self.0;
        x ^= x >> 33;
        x = x.wrapping_mul(0xff51_afd7_ed55_8ccd);
        x ^ (x >> 33)
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }
    fn write_u32(&mut self, v: u32) {
        self.write_u64(u64::from(v));
    }
    fn write_i32(&mut self, v: i32) {
        self.write_u64(u64::from(v as u32));
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(23) ^ v).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    }
}

#[inline]
fn cell_of(p: Vec3, size: f32) -> (i32, i32, i32) {
    let c = |v: f32| (v / size).floor().clamp(-CELL_LIMIT, CELL_LIMIT) as i32;
    (c(p.x), c(p.y), c(p.z))
}

#[cfg(test)]
mod tests;
