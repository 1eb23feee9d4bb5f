//! Signed distance fields sampled on a grid (Mitsuba 3's `sdfgrid`): the surface is the zero set
//! of the trilinear interpolant of the grid's values, found per voxel as the first root of the
//! cubic the interpolant is along a ray (Hansson-Söderlund, Evans and Akenine-Möller, "Ray
//! Tracing of Signed Distance Function Grids", JCGT 2022), bracketed at the cubic's turning
//! points and refined by Newton steps safeguarded by bisection.
//!
//! Each voxel the surface passes through is a primitive of its own, in the grid's index space
//! (voxel (i, j, k) spans [i, i+1] x [j, j+1] x [k, k+1]); the loaders put a grid's voxels in a
//! shape group and place it with an instance whose transform maps index space to the world, so
//! a voxel needs only its eight corner values and its cell (40 bytes, as a triangle).

use super::{PrimHit, SurfacePoint};
use crate::geometry::{Aabb, Ray, SurfaceParam};
use crate::math::float::gamma;
use crate::math::{Vec2, Vec3};

/// Largest grid side: a voxel's cell index packs into 10 bits per axis.
pub use crate::volume::MAX_GRID_SIDE;

/// Newton iterations stop when the step is below this, in ray parameter units (Mitsuba's).
const SOLVE_EPSILON: f32 = 1e-5;
const SOLVE_MAX_ITERATIONS: u32 = 50;

/// A grid of signed distances: `nx * ny * nz` values, x fastest, covering [0, 1]^3 with the
/// first and last samples on the faces (sample i at i / (n - 1)).
#[derive(Clone, Debug, PartialEq)]
pub struct SdfGrid {
    pub nx: usize,
    pub ny: usize,
    pub nz: usize,
    pub values: Vec<f32>,
}

impl SdfGrid {
    #[inline]
    fn at(&self, x: usize, y: usize, z: usize) -> f32 {
        self.values[(z * self.ny + y) * self.nx + x]
    }

    /// The voxels the surface passes through (corner values of both signs, or a zero).
    pub fn voxels(&self) -> impl Iterator<Item = SdfVoxel> + '_ {
        let cells = (0..self.nz.saturating_sub(1)).flat_map(move |z| {
            (0..self.ny.saturating_sub(1)).flat_map(move |y| (0..self.nx - 1).map(move |x| (x, y, z)))
        });
        cells.filter_map(move |(x, y, z)| {
            let corners: [f32; 8] = std::array::from_fn(|i| self.at(x + (i & 1), y + ((i >> 1) & 1), z + (i >> 2)));
            let (lo, hi) = corners.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), &v| (l.min(v), h.max(v)));
            (lo <= 0.0 && hi >= 0.0).then(|| SdfVoxel::new(corners, [x as u32, y as u32, z as u32]))
        })
    }
}

/// One voxel of a grid: its corner values, indexed x + 2y + 4z from the lower corner, and its
/// cell index packed 10 bits per axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SdfVoxel {
    pub corners: [f32; 8],
    cell: u32,
}

impl SdfVoxel {
    pub fn new(corners: [f32; 8], cell: [u32; 3]) -> Self {
        debug_assert!(cell.iter().all(|&c| (c as usize) < MAX_GRID_SIDE));
        SdfVoxel { corners, cell: cell[0] | (cell[1] << 10) | (cell[2] << 20) }
    }

    /// The lower corner of the voxel in index space.
    #[inline]
    pub fn origin(&self) -> Vec3 {
        let c = self.cell;
        Vec3::new((c & 1023) as f32, ((c >> 10) & 1023) as f32, (c >> 20) as f32)
    }

    pub fn bounds(&self) -> Aabb {
        let o = self.origin();
        Aabb { min: o, max: o + Vec3::ONE }
    }

    /// The trilinear interpolant at `p` in the voxel's own [0, 1]^3.
    #[inline]
    fn value(&self, p: Vec3) -> f32 {
        let s = &self.corners;
        let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
        let y0 = lerp(lerp(s[0], s[1], p.x), lerp(s[2], s[3], p.x), p.y);
        let y1 = lerp(lerp(s[4], s[5], p.x), lerp(s[6], s[7], p.x), p.y);
        lerp(y0, y1, p.z)
    }

    /// The interpolant's gradient at `p` in the voxel's own [0, 1]^3.
    #[inline]
    fn gradient(&self, p: Vec3) -> Vec3 {
        let s = &self.corners;
        let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
        let bilerp = |a: f32, b: f32, c: f32, d: f32, u: f32, v: f32| lerp(lerp(a, b, u), lerp(c, d, u), v);
        Vec3::new(
            bilerp(s[1] - s[0], s[3] - s[2], s[5] - s[4], s[7] - s[6], p.y, p.z),
            bilerp(s[2] - s[0], s[3] - s[1], s[6] - s[4], s[7] - s[5], p.x, p.z),
            bilerp(s[4] - s[0], s[5] - s[1], s[6] - s[2], s[7] - s[3], p.x, p.y),
        )
    }

    /// The first crossing of the zero set in (0, t_max) along `ray` (in index space).
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        let o = ray.o - self.origin();
        let inv = ray.d.recip();
        // Slab test against the unit cube; a ray in a face's plane counts as inside.
        let (mut t0, mut t1) = (0.0f32, t_max);
        for a in 0..3 {
            let (n, f) = ((0.0 - o[a]) * inv[a], (1.0 - o[a]) * inv[a]);
            let (n, f) = if n <= f { (n, f) } else { (f, n) };
            if n.is_nan() || f.is_nan() {
                continue;
            }
            t0 = t0.max(n);
            t1 = t1.min(f);
        }
        if !(t0 < t1) {
            return None;
        }
        let clamp = |p: Vec3| p.clamp(Vec3::ZERO, Vec3::ONE);
        let (p0, p1) = (clamp(o + ray.d * t0), clamp(o + ray.d * t1));
        let (f0, f1) = (self.value(p0), self.value(p1));
        // The cubic c0 + c1 s + c2 s^2 + c3 s^3 of the interpolant along p0 + s d.
        let s = &self.corners;
        let (k0, k1, k2) = (s[0], s[1] - s[0], s[2] - s[0]);
        let k3 = s[3] - s[2] - k1;
        let k4 = s[4] - k0;
        let a = s[5] - s[4];
        let k5 = a - k1;
        let k6 = (s[6] - s[4]) - k2;
        let k7 = (s[7] - s[6] - a) - k3;
        let (ox, oy, oz) = (p0.x, p0.y, p0.z);
        let (dx, dy, dz) = (ray.d.x, ray.d.y, ray.d.z);
        let m0 = ox * oy;
        let m1 = dx * dy;
        let m2 = ox * dy + oy * dx;
        let m3 = k5 * oz + k1;
        let m4 = k6 * oz + k2;
        let m5 = k7 * oz + k3;
        let c0 = k4 * oz + k0 + ox * m3 + oy * m4 + m0 * m5;
        let c1 = dx * m3 + dy * m4 + m2 * m5 + dz * (k4 + k5 * ox + k6 * oy + k7 * m0);
        let c2 = m1 * m5 + dz * (k5 * dx + k6 * dy + k7 * m2);
        let c3 = k7 * m1 * dz;
        let t = solve_first_root(t1 - t0, f0, f1, [c0, c1, c2, c3])? + t0;
        (t > 0.0 && t < t_max).then_some(PrimHit { t, u: 0.0, v: 0.0 })
    }

    /// The surface at a hit (index space): the normal is the interpolant's gradient.
    pub fn surface(&self, ray: &Ray, h: &PrimHit) -> SurfacePoint {
        let p = ray.at(h.t);
        let local = (p - self.origin()).clamp(Vec3::ZERO, Vec3::ONE);
        let n = self.gradient(local).normalize_or(Vec3::Z);
        // The root is found to SOLVE_EPSILON along the ray, not reprojected onto the surface.
        let p_error = gamma(7) * p.abs() + ray.d.abs() * (2.0 * SOLVE_EPSILON) + Vec3::splat(1e-5);
        // No texture coordinates (as in Mitsuba); a tangent frame from the normal.
        let dpdu = n.any_orthonormal_vector();
        let dpdv = n.cross(dpdu);
        SurfacePoint { p, p_error, ng: n, ns: n, param: SurfaceParam::Known { uv: Vec2::ZERO, dpdu, dpdv } }
    }
}

/// The first root in [0, len] of the cubic `c` (ascending powers) whose values at the ends are
/// `f0` and `f1`: the interval is cut at the cubic's turning points to the first monotonic piece
/// holding a sign change, then a secant guess is refined by Newton steps kept in the bracket.
fn solve_first_root(len: f32, f0: f32, f1: f32, c: [f32; 4]) -> Option<f32> {
    let eval = |t: f32| ((c[3] * t + c[2]) * t + c[1]) * t + c[0];
    let deriv = |t: f32| (3.0 * c[3] * t + 2.0 * c[2]) * t + c[1];
    let (mut tn, mut tf, mut fnear, mut ffar) = (0.0f32, len, f0, f1);
    // Turning points: roots of 3 c3 t^2 + 2 c2 t + c1, in increasing order (NaN for none).
    let [a, b] = quadratic_roots(3.0 * c[3], 2.0 * c[2], c[1]);
    for r in [a.min(b), a.max(b)] {
        if !(r >= tn && r <= tf) {
            continue;
        }
        let fr = eval(r);
        if fnear * fr <= 0.0 {
            tf = r;
            ffar = fr;
        } else {
            tn = r;
            fnear = fr;
        }
    }
    if !(fnear * ffar <= 0.0) {
        return None;
    }
    let mut t = tn + (tf - tn) * (-fnear / (ffar - fnear));
    if !(t >= tn && t <= tf) {
        t = 0.5 * (tn + tf);
    }
    for _ in 0..SOLVE_MAX_ITERATIONS {
        let ft = eval(t);
        if ft * fnear <= 0.0 {
            tf = t;
        } else {
            tn = t;
        }
        let next = if ft == 0.0 {
            t
        } else {
            let n = t - ft / deriv(t);
            if n > tn && n < tf { n } else { 0.5 * (tn + tf) }
        };
        let done = !((next - t).abs() >= SOLVE_EPSILON);
        t = next;
        if done {
            break;
        }
    }
    t.is_finite().then_some(t)
}

/// The real roots of a t^2 + b t + c, NaN standing for a missing one (a linear equation when a
/// is 0). `min` and `max` of a pair with a NaN give the other root.
fn quadratic_roots(a: f32, b: f32, c: f32) -> [f32; 2] {
    if a == 0.0 {
        let r = if b != 0.0 { -c / b } else { f32::NAN };
        return [r, r];
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return [f32::NAN; 2];
    }
    // The numerically stable pair.
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    if q == 0.0 {
        return [0.0, 0.0];
    }
    [q / a, c / q]
}

pub use crate::volume::VolError;

/// Reads Mitsuba's binary grid volume format (`crate::volume::parse_vol`, the reader every grid
/// goes through) as an SDF grid: one channel and at least two samples along each axis. The
/// file's bounding box is not used: an SDF grid spans [0, 1]^3 of its object space.
pub fn parse_vol(bytes: &[u8]) -> Result<SdfGrid, VolError> {
    let shape = crate::volume::VolShape { channels: &[1], min_side: 2, what: "an SDF grid" };
    let g = crate::volume::parse_vol(bytes, shape)?;
    Ok(SdfGrid { nx: g.nx, ny: g.ny, nz: g.nz, values: g.values })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A .vol file of `f` sampled on an n^3 grid over [0, 1]^3.
    fn vol(n: usize, f: impl Fn(Vec3) -> f32) -> Vec<u8> {
        let mut b = b"VOL\x03".to_vec();
        for v in [1i32, n as i32, n as i32, n as i32, 1] {
            b.extend(v.to_le_bytes());
        }
        for v in [0f32, 0.0, 0.0, 1.0, 1.0, 1.0] {
            b.extend(v.to_le_bytes());
        }
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let p = Vec3::new(x as f32, y as f32, z as f32) / (n - 1) as f32;
                    b.extend(f(p).to_le_bytes());
                }
            }
        }
        b
    }

    fn sphere(p: Vec3) -> f32 {
        (p - Vec3::splat(0.5)).length() - 0.3
    }

    /// Rays through a grid of a sphere's distance hit it where the sphere is (to the
    /// interpolation's error, a fraction of a cell) with a normal close to the sphere's.
    #[test]
    fn a_sampled_sphere_is_hit_where_the_sphere_is() {
        let n = 32;
        let grid = parse_vol(&vol(n, sphere)).unwrap();
        let voxels: Vec<SdfVoxel> = grid.voxels().collect();
        assert!(!voxels.is_empty() && voxels.len() < (n - 1).pow(3));
        let scale = (n - 1) as f32;
        let mut hits = 0;
        for i in 0..200 {
            let (u, v) = ((i % 20) as f32 / 20.0 - 0.5, (i / 20) as f32 / 10.0 - 0.5);
            let target = Vec3::new(0.5 + 0.25 * u, 0.5 + 0.25 * v, 0.5);
            let o = Vec3::new(target.x, target.y, -1.0);
            // In index space: positions times (n - 1); the direction too, so t is unchanged.
            let ray = Ray::new(o * scale, Vec3::Z * scale);
            let best = voxels
                .iter()
                .filter_map(|vx| vx.intersect(&ray, f32::INFINITY).map(|h| (h, vx)))
                .min_by(|a, b| a.0.t.total_cmp(&b.0.t));
            let exact = {
                let c = Vec3::splat(0.5);
                let d2 = (target.x - c.x).powi(2) + (target.y - c.y).powi(2);
                (d2 < 0.09).then(|| 1.0 + 0.5 - (0.09 - d2).sqrt())
            };
            match (best, exact) {
                (Some((h, vx)), Some(t)) => {
                    hits += 1;
                    assert!((h.t - t).abs() < 0.5 / scale, "ray {i}: t {} vs {t}", h.t);
                    let s = vx.surface(&ray, &h);
                    let want = ((s.p / scale) - Vec3::splat(0.5)).normalize();
                    assert!(s.ng.dot(want) > 0.98, "ray {i}: normal {} vs {want}", s.ng);
                    assert!((vx.value((s.p - vx.origin()).clamp(Vec3::ZERO, Vec3::ONE))).abs() < 1e-4);
                }
                (None, None) => {}
                // Grazing rays may differ by the interpolation.
                (got, want) => {
                    let r = (Vec2::new(target.x, target.y) - Vec2::splat(0.5)).length();
                    assert!(
                        (r - 0.3).abs() < 1.5 / scale,
                        "ray {i} at r {r}: hit {:?} vs exact {want:?}",
                        got.map(|g| g.0.t)
                    );
                }
            }
        }
        assert!(hits > 100, "{hits} hits");
    }

    #[test]
    fn bad_files_are_errors() {
        let good = vol(4, sphere);
        assert!(parse_vol(&good).is_ok());
        let with = |at: usize, v: i32| {
            let mut b = good.clone();
            b[at..at + 4].copy_from_slice(&v.to_le_bytes());
            b
        };
        for (bytes, want) in [
            (good[..40].to_vec(), "48-byte header"),
            (good[..good.len() - 1].to_vec(), "cut short"),
            ([good.clone(), vec![0]].concat(), "padded"),
            (b"VOX\x03".iter().copied().chain(good[4..].iter().copied()).collect(), "not a Mitsuba .vol"),
            (with(4, 2), "encoding 2"),
            (with(8, 1), "x resolution must be 2"),
            (with(12, 5000), "y resolution"),
            (with(20, 3), "1 channel"),
            (with(48, f32::NAN.to_bits() as i32), "not a finite number"),
        ] {
            let e = parse_vol(&bytes).unwrap_err().to_string();
            assert!(e.contains(want), "{want}: {e}");
        }
    }

    proptest! {
        /// Arbitrary bytes are a grid or an error, never a panic; so are bytes after a valid
        /// header.
        #[test]
        fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..600), n in 2usize..5) {
            let _ = parse_vol(&bytes);
            let mut b = vol(n, sphere);
            b.truncate(48);
            b.extend(&bytes);
            if let Ok(g) = parse_vol(&b) {
                prop_assert_eq!(g.values.len(), n * n * n);
            }
        }

        /// Every voxel found holds the surface, and none is missed.
        #[test]
        fn voxels_are_exactly_those_with_a_sign_change(values in prop::collection::vec(-1.0f32..1.0, 27)) {
            let g = SdfGrid { nx: 3, ny: 3, nz: 3, values };
            let found = g.voxels().count();
            let mut want = 0;
            for z in 0..2 { for y in 0..2 { for x in 0..2 {
                let c: Vec<f32> = (0..8).map(|i| g.at(x + (i & 1), y + ((i >> 1) & 1), z + (i >> 2))).collect();
                if c.iter().any(|&v| v <= 0.0) && c.iter().any(|&v| v >= 0.0) { want += 1; }
            }}}
            prop_assert_eq!(found, want);
        }
    }
}
