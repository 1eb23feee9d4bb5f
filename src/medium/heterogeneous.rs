//! A heterogeneous medium (Mitsuba 3's `heterogeneous`): extinction `sigma_t` and albedo that
//! vary in space, each a grid (`gridvolume`, a `.vol` file, looked up trilinearly) or a
//! constant, with `scale` multiplying the extinction.
//!
//! Where the medium is: the unit cube of the extinction's volume placed by its `to_world` (a
//! constant extinction's volume too, as in Mitsuba, where the medium is the box of the
//! extinction's volume); outside it the density is 0. Mitsuba clips rays to the axis-aligned
//! box of that cube's (0, 0, 0) and (1, 1, 1) corners; for a grid that is only scaled and moved
//! it is the same cube, for a rotated one we take the rotated cube itself. The albedo's volume
//! has a `to_world` of its own and clamps to its edges, as Mitsuba's does.
//!
//! Sampling works in the extinction's unit cube, where a ray keeps its parameter t (its
//! direction is transformed, not normalised):
//! - a coarse majorant grid (`MajorantGrid`, at most 16 cells per axis) holds for each cell the
//!   largest extinction any trilinear lookup in it can give (the largest texel, over every
//!   channel, of the texels whose footprint reaches the cell), times `scale`; a ray walks its
//!   cells with a 3-D DDA (Amanatides and Woo 1987; pbrt-v4's `DDAMajorantIterator` does the
//!   same for its majorant grid), each cell a segment of constant majorant;
//! - free flights are delta tracking against that piecewise-constant majorant (Woodcock et al.
//!   1965): tentative collisions at exponential steps of the segment's majorant, each a real
//!   collision or a null one;
//! - RGB extinction: the grey majorant bounds every channel, and the choice between a real and
//!   a null collision is the spectral tracking of Kutz et al. 2017 ("Spectral and Decomposition
//!   Tracking for Rendering Heterogeneous Volumes", sec. 4, the history-aware probabilities): a
//!   real collision with probability sum_c w_c sigma_t,c / (majorant sum_c w_c), `w` the
//!   path's throughput times the weights so far, and each event weighted per channel by its
//!   coefficient over majorant times probability (sigma_s at a real collision, majorant -
//!   sigma_t at a null one). Every channel stays unbiased, and the probabilities follow the
//!   channels the path still carries, as the homogeneous kind's channel choice by throughput
//!   does; with a grey extinction it is plain delta tracking (weights 1 and the albedo);
//! - shadow rays estimate transmittance by ratio tracking (Cramer 1978; Novák et al. 2014): the
//!   product of (1 - sigma_t / majorant) over the tentative collisions, with Russian roulette
//!   once every channel is below 0.1.
//!
//! The number of tentative collisions varies, so the numbers come from a random stream the
//! caller passes (`Rng32`), seeded per path or photon, never per thread: renders stay the same
//! for any thread count. The first step of a free flight uses the caller's sample `u`.

use super::homogeneous::MediumSample;
use super::phase::Phase;
use crate::geometry::{Ray, Transform};
use crate::math::{Color, Vec3};
use crate::sampling::Rng32;
use crate::spectrum::{LANES, Wavelengths};
use crate::volume::{VolGrid, texel_range};
use std::sync::Arc;

/// The most cells of the majorant grid along an axis.
pub const MAJORANT_CELLS: usize = 16;

/// Ratio tracking plays Russian roulette once every channel's transmittance is below this.
const ROULETTE_BELOW: f32 = 0.1;

/// A quantity of a medium that may vary in space: one value everywhere, or a grid.
#[derive(Clone, Debug, PartialEq)]
pub enum VolumeData {
    Constant(Color),
    Grid(Arc<VolGrid>),
}

/// A `VolumeData` placed in the world: `to_local` maps the world to its unit cube.
#[derive(Clone, Debug, PartialEq)]
pub struct Volume {
    pub data: VolumeData,
    pub to_local: Transform,
}

impl Volume {
    pub fn constant(c: Color) -> Self {
        Volume { data: VolumeData::Constant(c), to_local: Transform::IDENTITY }
    }

    /// A volume placed by `to_world` (which maps its unit cube to the world; must be valid).
    pub fn placed(data: VolumeData, to_world: &Transform) -> Self {
        Volume { data, to_local: Transform::from_mat4(to_world.m.inverse()) }
    }

    /// The value at `p` in the volume's unit cube.
    #[inline]
    pub fn eval_local(&self, p: Vec3) -> Color {
        match &self.data {
            VolumeData::Constant(c) => *c,
            VolumeData::Grid(g) => g.eval(p),
        }
    }

    /// The value at world point `p`.
    #[inline]
    pub fn eval(&self, p: Vec3) -> Color {
        match &self.data {
            VolumeData::Constant(c) => *c,
            VolumeData::Grid(g) => g.eval(self.to_local.point(p)),
        }
    }
}

/// Checks the values of a medium's quantity: `sigma_t` finite and >= 0, `albedo` in [0, 1];
/// the error names the first value out of range and where it is.
pub fn check_quantity(quantity: &str, data: &VolumeData) -> Result<(), String> {
    let (ok, rule): (fn(f32) -> bool, &str) = match quantity {
        "albedo" => (|v| (0.0..=1.0).contains(&v), "must be in [0, 1]"),
        _ => (|v| v >= 0.0 && v.is_finite(), "must be finite and >= 0"),
    };
    let bad = match data {
        VolumeData::Constant(c) => (0..3).find(|&k| !ok(c[k])).map(|k| format!("{} in channel {k}", c[k])),
        VolumeData::Grid(g) => g.find(ok).map(|(v, [x, y, z], c)| {
            let channel = if g.channels == 1 { String::new() } else { format!(", channel {c}") };
            format!("{v} at texel ({x}, {y}, {z}){channel}")
        }),
    };
    bad.map_or(Ok(()), |bad| Err(format!("{quantity} {rule}, found {bad}")))
}

/// Upper bounds of the extinction over the cells of a coarse grid over the unit cube (already
/// multiplied by `scale`).
#[derive(Clone, Debug, PartialEq)]
pub struct MajorantGrid {
    pub res: [usize; 3],
    pub values: Vec<f32>,
}

impl MajorantGrid {
    /// The majorants of `sigma_t` times `scale`: per cell, the largest texel (any channel) whose
    /// trilinear footprint reaches the cell.
    pub fn new(sigma_t: &VolumeData, scale: f32) -> Self {
        match sigma_t {
            VolumeData::Constant(c) => MajorantGrid { res: [1; 3], values: vec![c.max_element() * scale] },
            VolumeData::Grid(g) => {
                let n = g.res();
                let res = n.map(|n| n.min(MAJORANT_CELLS));
                let mut values = Vec::with_capacity(res[0] * res[1] * res[2]);
                let range = |a: usize, i: usize| {
                    let r = res[a] as f32;
                    texel_range(i as f32 / r, (i + 1) as f32 / r, n[a])
                };
                for z in 0..res[2] {
                    let rz = range(2, z);
                    for y in 0..res[1] {
                        let ry = range(1, y);
                        for x in 0..res[0] {
                            let rx = range(0, x);
                            values.push(g.max_over([rx.0, ry.0, rz.0], [rx.1, ry.1, rz.1]).max(0.0) * scale);
                        }
                    }
                }
                MajorantGrid { res, values }
            }
        }
    }

    /// The cells a ray `o + t d` (in the unit cube's space) crosses between `t0` and `t1`, both
    /// within the cube, as segments of constant majorant.
    #[inline]
    pub fn walk(&self, o: Vec3, d: Vec3, t0: f32, t1: f32) -> MajorantWalk<'_> {
        let p = o + d * t0;
        let mut cell = [0i32; 3];
        let mut step = [0i32; 3];
        let mut next_t = [f32::INFINITY; 3];
        let mut delta_t = [f32::INFINITY; 3];
        for a in 0..3 {
            let n = self.res[a] as i32;
            let r = self.res[a] as f32;
            cell[a] = ((p[a] * r).floor() as i32).clamp(0, n - 1);
            if d[a] > 0.0 {
                step[a] = 1;
                next_t[a] = (t0 + ((cell[a] + 1) as f32 / r - p[a]) / d[a]).max(t0);
                delta_t[a] = 1.0 / (r * d[a]);
            } else if d[a] < 0.0 {
                step[a] = -1;
                next_t[a] = (t0 + (cell[a] as f32 / r - p[a]) / d[a]).max(t0);
                delta_t[a] = -1.0 / (r * d[a]);
            }
        }
        MajorantWalk { grid: self, cell, step, next_t, delta_t, t: t0, t_end: t1, done: !(t0 < t1) }
    }
}

/// A DDA walk through a `MajorantGrid`: yields (t start, t end, majorant) per cell crossed.
pub struct MajorantWalk<'a> {
    grid: &'a MajorantGrid,
    cell: [i32; 3],
    step: [i32; 3],
    next_t: [f32; 3],
    delta_t: [f32; 3],
    t: f32,
    t_end: f32,
    done: bool,
}

impl Iterator for MajorantWalk<'_> {
    type Item = (f32, f32, f32);

    #[inline]
    fn next(&mut self) -> Option<(f32, f32, f32)> {
        if self.done {
            return None;
        }
        let a = if self.next_t[0] <= self.next_t[1] {
            if self.next_t[0] <= self.next_t[2] { 0 } else { 2 }
        } else if self.next_t[1] <= self.next_t[2] {
            1
        } else {
            2
        };
        let [nx, ny, _] = self.grid.res;
        let [x, y, z] = self.cell.map(|c| c as usize);
        let majorant = self.grid.values[(z * ny + y) * nx + x];
        let start = self.t;
        let end = self.next_t[a].min(self.t_end);
        if self.next_t[a] >= self.t_end {
            self.done = true;
        } else {
            self.cell[a] += self.step[a];
            if self.cell[a] < 0 || self.cell[a] >= self.grid.res[a] as i32 {
                self.done = true;
            }
            self.next_t[a] += self.delta_t[a];
        }
        self.t = end;
        Some((start, end, majorant))
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Heterogeneous {
    /// Extinction per unit length before `scale`, per channel; its volume's unit cube is where
    /// the medium is.
    pub sigma_t: Volume,
    /// Single-scattering albedo in [0, 1].
    pub albedo: Volume,
    pub scale: f32,
    pub phase: Phase,
    majorant: Arc<MajorantGrid>,
    /// What the majorants are multiplied by in spectral mode: 2 where the extinction has a
    /// colour (its unbounded spectrum, twice its largest channel times a sigmoid in [0, 1], can
    /// reach twice the channel the RGB majorant bounds), 1 where it is grey (lifted exactly).
    spectral_majorant: f32,
}

impl Heterogeneous {
    /// A medium from its volumes; an error names the first value out of range.
    pub fn new(sigma_t: Volume, albedo: Volume, scale: f32, phase: Phase) -> Result<Self, String> {
        if !(scale >= 0.0 && scale.is_finite()) {
            return Err(format!("scale must be finite and >= 0, found {scale}"));
        }
        check_quantity("sigma_t", &sigma_t.data)?;
        check_quantity("albedo", &albedo.data)?;
        if let Phase::HenyeyGreenstein { g } = phase
            && !(g > -1.0 && g < 1.0)
        {
            return Err(format!("the Henyey-Greenstein `g` must be in (-1, 1), found {g}"));
        }
        if !sigma_t.to_local.is_valid() || !albedo.to_local.is_valid() {
            return Err("a volume's to_world is singular or not finite".into());
        }
        let majorant = Arc::new(MajorantGrid::new(&sigma_t.data, scale));
        if let Some(m) = majorant.values.iter().find(|m| !m.is_finite()) {
            return Err(format!("sigma_t times scale overflows ({m})"));
        }
        let grey = |c: Color| c.r() == c.g() && c.g() == c.b();
        let spectral_majorant = match &sigma_t.data {
            VolumeData::Constant(c) => grey(*c),
            VolumeData::Grid(g) => g.channels == 1 || g.values.chunks_exact(3).all(|t| t[0] == t[1] && t[1] == t[2]),
        };
        let spectral_majorant = if spectral_majorant { 1.0 } else { 2.0 };
        Ok(Heterogeneous { sigma_t, albedo, scale, phase, majorant, spectral_majorant })
    }

    /// The majorant grid the medium is tracked with.
    pub fn majorant(&self) -> &MajorantGrid {
        &self.majorant
    }

    /// The extinction at `p` in the extinction's unit cube.
    #[inline]
    pub fn sigma_t_local(&self, p: Vec3) -> Color {
        self.sigma_t.eval_local(p) * self.scale
    }

    /// The ray in the extinction's unit cube and the part of [0, `t_max`] inside the cube, when
    /// it is not empty.
    #[inline]
    fn enter(&self, ray: &Ray, t_max: f32) -> Option<(Vec3, Vec3, f32, f32)> {
        let o = self.sigma_t.to_local.point(ray.o);
        let d = self.sigma_t.to_local.vector(ray.d);
        let (mut t0, mut t1) = (0.0f32, t_max);
        for a in 0..3 {
            if d[a] == 0.0 {
                if !(0.0..=1.0).contains(&o[a]) {
                    return None;
                }
                continue;
            }
            let (ta, tb) = (-o[a] / d[a], (1.0 - o[a]) / d[a]);
            let (near, far) = if ta <= tb { (ta, tb) } else { (tb, ta) };
            if near > t0 {
                t0 = near;
            }
            if far < t1 {
                t1 = far;
            }
        }
        (t0 < t1).then_some((o, d, t0, t1))
    }

    /// The extinction at `p` (unit cube), no channel above `majorant` (a lookup can pass the
    /// cell's bound only by rounding); in spectral mode (`wl`) the trilinear lookup's colour
    /// lifted as an unbounded spectrum at the path's wavelengths. (Lifting the looked-up colour,
    /// not each texel as Mitsuba 3's `gridvolume` does, costs one table lookup instead of eight;
    /// the two agree at texel centres and differ by second-order terms between them.)
    #[inline]
    fn sigma_t_below(&self, p: Vec3, majorant: f32, wl: Option<&Wavelengths>) -> Color {
        let s = match wl {
            None => self.sigma_t_local(p),
            Some(wl) => wl.unbounded(self.sigma_t.eval_local(p)) * self.scale,
        };
        s.min_splat(majorant)
    }

    /// The majorant grid's value `m` as the bound of the extinction in the mode `wl` says.
    #[inline]
    fn majorant_in(&self, m: f32, wl: Option<&Wavelengths>) -> f32 {
        if wl.is_some() { m * self.spectral_majorant } else { m }
    }

    /// The transmittance along `ray` over [0, `t_max`], estimated by ratio tracking (unbiased
    /// in every channel), at the path's wavelengths in spectral mode (`wl`).
    pub fn transmittance(&self, ray: &Ray, t_max: f32, rng: &mut Rng32, wl: Option<&Wavelengths>) -> Color {
        let Some((o, d, t0, t1)) = self.enter(ray, t_max) else { return Color::ONE };
        let length = ray.d.length();
        let mut tr = Color::ONE;
        for (start, end, majorant) in self.majorant.walk(o, d, t0, t1) {
            let majorant = self.majorant_in(majorant, wl);
            if !(majorant > 0.0) {
                continue;
            }
            let rate = majorant * length;
            let mut t = start;
            loop {
                t = advance(t, -(1.0 - rng.uniform()).ln() / rate);
                if !(t < end) {
                    break;
                }
                let sigma_t = self.sigma_t_below(o + d * t, majorant, wl);
                tr *= Color::ONE - sigma_t / majorant;
                let m = tr.max_element();
                if m < ROULETTE_BELOW {
                    // Survive with probability m / ROULETTE_BELOW and be scaled up by its inverse.
                    let q = m / ROULETTE_BELOW;
                    if !(q > 0.0) || rng.uniform() >= q {
                        return Color::ZERO;
                    }
                    tr /= q;
                }
            }
        }
        tr
    }

    /// Free-flight sampling along `ray` over [0, `t_max`] for light carried with throughput
    /// `beta` by delta (spectral) tracking; `u` is the first step's number, `rng` gives the rest.
    /// The weights are as `Homogeneous::sample_distance`'s (see the module's notes). In spectral
    /// mode (`wl`) the lanes are the path's wavelengths: the extinction and the albedo are lifted
    /// at each lookup (as an unbounded spectrum and a reflectance) and the tracking probabilities
    /// follow the wavelengths the path carries as they follow colour channels in RGB.
    pub fn sample_distance(
        &self,
        ray: &Ray,
        t_max: f32,
        beta: Color,
        u: f32,
        rng: &mut Rng32,
        wl: Option<&Wavelengths>,
    ) -> MediumSample {
        let pass = |w: Color| MediumSample { t: t_max, scattered: false, weight: w, tr_over_pdf: w };
        let Some((o, d, t0, t1)) = self.enter(ray, t_max) else { return pass(Color::ONE) };
        let length = ray.d.length();
        let mut w = Color::ONE;
        let mut first = Some(u);
        // The lanes the tracking probabilities average over: the channels, or the wavelengths.
        let lanes = if wl.is_some() { LANES } else { 3 };
        for (start, end, majorant) in self.majorant.walk(o, d, t0, t1) {
            let majorant = self.majorant_in(majorant, wl);
            if !(majorant > 0.0) {
                continue;
            }
            let rate = majorant * length;
            let mut t = start;
            loop {
                let u = first.take().unwrap_or_else(|| rng.uniform());
                t = advance(t, -(1.0 - u).ln() / rate);
                if !(t < end) {
                    break;
                }
                let sigma_t = self.sigma_t_below(o + d * t, majorant, wl);
                let carried = (beta * w).max(Color::ZERO);
                let total = carried.lane_sum(lanes);
                let p_real = if total > 0.0 && total.is_finite() {
                    (carried * sigma_t).lane_sum(lanes) / (total * majorant)
                } else {
                    sigma_t.lane_sum(lanes) / (lanes as f32 * majorant)
                }
                .clamp(0.0, 1.0);
                if rng.uniform() < p_real {
                    let tr_over_pdf = w / (majorant * p_real);
                    let albedo = self.albedo.eval(ray.at(t));
                    let albedo = match wl {
                        None => albedo,
                        Some(wl) => wl.reflectance(albedo),
                    };
                    return MediumSample { t, scattered: true, weight: tr_over_pdf * sigma_t * albedo, tr_over_pdf };
                }
                w *= (Color::splat(majorant) - sigma_t) / (majorant * (1.0 - p_real));
                if w == Color::ZERO || !w.is_finite() {
                    return pass(Color::ZERO);
                }
            }
        }
        pass(w)
    }
}

/// `t` moved on by `step`, and at least to the next float: a step below t's rounding would
/// leave it where it is, and the walk would never end.
#[inline]
fn advance(t: f32, step: f32) -> f32 {
    let next = t + step;
    if next > t { next } else { crate::math::float::next_float_up(t) }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: [usize; 3], channels: usize, f: impl Fn(Vec3) -> Color) -> Arc<VolGrid> {
        let mut values = Vec::new();
        for z in 0..n[2] {
            for y in 0..n[1] {
                for x in 0..n[0] {
                    let p = (Vec3::new(x as f32, y as f32, z as f32) + 0.5)
                        / Vec3::new(n[0] as f32, n[1] as f32, n[2] as f32);
                    let c = f(p);
                    values.extend(&[c.r(), c.g(), c.b()][..channels]);
                }
            }
        }
        Arc::new(VolGrid { nx: n[0], ny: n[1], nz: n[2], channels, bbox: [0.0, 0.0, 0.0, 1.0, 1.0, 1.0], values })
    }

    fn blob(p: Vec3) -> Color {
        let r2 = (p - Vec3::new(0.45, 0.5, 0.55)).length_squared();
        Color::new(3.0, 1.5, 0.6) * (-r2 * 12.0).exp()
    }

    /// Every lookup anywhere in a majorant cell is at most the cell's majorant.
    #[test]
    fn majorants_bound_every_lookup() {
        let g = grid([23, 17, 9], 3, |p| blob(p) * (1.0 + (p.x * 40.0).sin()));
        let data = VolumeData::Grid(g.clone());
        let m = MajorantGrid::new(&data, 2.0);
        assert_eq!(m.res, [16, 16, 9]);
        let mut rng = Rng32::new(3);
        for _ in 0..200_000 {
            let p = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform());
            let c = [0, 1, 2].map(|a| ((p[a] * m.res[a] as f32) as usize).min(m.res[a] - 1));
            let bound = m.values[(c[2] * m.res[1] + c[1]) * m.res[0] + c[0]];
            let v = g.eval(p).max_element() * 2.0;
            assert!(v <= bound * (1.0 + 1e-6), "{v} > {bound} at {p}");
        }
    }

    /// The DDA's segments tile [t0, t1] in order, each in the cell the segment's midpoint lies in.
    #[test]
    fn the_walk_tiles_the_ray_through_the_cells() {
        let m = MajorantGrid { res: [4, 3, 5], values: (0..60).map(|i| i as f32).collect() };
        let mut rng = Rng32::new(9);
        for _ in 0..2000 {
            let o = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform());
            let mut d = Vec3::new(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5);
            if rng.uniform() < 0.2 {
                d.y = 0.0;
            }
            let t1 = [0, 1, 2]
                .map(|a| {
                    if d[a] > 0.0 {
                        (1.0 - o[a]) / d[a]
                    } else if d[a] < 0.0 {
                        -o[a] / d[a]
                    } else {
                        f32::INFINITY
                    }
                })
                .into_iter()
                .fold(f32::INFINITY, f32::min);
            let mut t = 0.0;
            for (a, b, v) in m.walk(o, d, 0.0, t1) {
                assert!((a - t).abs() < 1e-5 && b >= a, "segment {a}..{b} after {t}");
                t = b;
                if (b - a) * d.length() > 1e-4 {
                    let p = o + d * (0.5 * (a + b));
                    let c = [0, 1, 2].map(|k| ((p[k] * m.res[k] as f32) as usize).min(m.res[k] - 1));
                    assert_eq!(v, m.values[(c[2] * 3 + c[1]) * 4 + c[0]], "{p}");
                }
            }
            assert!((t - t1).abs() < 1e-4 * t1.max(1.0), "ended at {t} of {t1}");
        }
    }

    fn medium(n: [usize; 3], channels: usize) -> Heterogeneous {
        let to_world =
            Transform::scale(Vec3::new(2.0, 1.0, 1.5)).then(Transform::translate(Vec3::new(-1.0, -0.5, 0.2)));
        let sigma_t = Volume::placed(VolumeData::Grid(grid(n, channels, blob)), &to_world);
        let albedo = Volume::constant(Color::new(0.9, 0.5, 0.2));
        Heterogeneous::new(sigma_t, albedo, 0.8, Phase::Isotropic).unwrap()
    }

    /// The optical depth along a ray by the midpoint rule over many small steps.
    fn optical_depth(m: &Heterogeneous, ray: &Ray, t_max: f32) -> [f64; 3] {
        let steps = 20_000;
        let h = t_max / steps as f32;
        let mut tau = [0.0f64; 3];
        for i in 0..steps {
            let p = ray.at((i as f32 + 0.5) * h);
            let local = m.sigma_t.to_local.point(p);
            if local.cmpge(Vec3::ZERO).all() && local.cmple(Vec3::ONE).all() {
                let s = m.sigma_t_local(local);
                for (c, tau) in tau.iter_mut().enumerate() {
                    *tau += f64::from(s[c] * h);
                }
            }
        }
        tau
    }

    /// Ratio tracking's mean over many estimates is the exact transmittance exp(-tau) (tau by
    /// numerical integration of the trilinear density) within 4 standard errors, per channel.
    #[test]
    fn ratio_tracking_is_unbiased() {
        for channels in [1, 3] {
            let m = medium([12, 9, 7], channels);
            let ray = Ray::new(Vec3::new(-2.0, -0.3, 0.1), Vec3::new(1.0, 0.25, 0.5).normalize());
            let t_max = 3.5;
            let tau = optical_depth(&m, &ray, t_max);
            let mut rng = Rng32::new(5);
            let n = 200_000;
            let (mut sum, mut sum2) = ([0.0f64; 3], [0.0f64; 3]);
            for _ in 0..n {
                let tr = m.transmittance(&ray, t_max, &mut rng, None);
                for c in 0..3 {
                    sum[c] += f64::from(tr[c]);
                    sum2[c] += f64::from(tr[c]).powi(2);
                }
            }
            for c in 0..3 {
                let mean = sum[c] / n as f64;
                let se = ((sum2[c] / n as f64 - mean * mean) / n as f64).sqrt();
                let want = (-tau[c]).exp();
                assert!(want < 0.95 && want > 0.05, "channel {c}: a test ray should cross some medium ({want})");
                assert!(
                    (mean - want).abs() < 4.0 * se + 1e-4,
                    "{channels} ch, channel {c}: {mean} vs {want} (se {se})"
                );
            }
        }
    }

    /// In spectral mode ratio tracking and spectral tracking stay unbiased at the path's
    /// wavelengths: the mean transmittance is exp(-tau) of the lifted extinction, and the
    /// passing and scattering weights average to it and to the lifted albedo times its
    /// complement, within 4 standard errors per lane. The extinction is a saturated red, whose
    /// unbounded spectrum passes its largest channel at long wavelengths: a majorant of the RGB
    /// values alone would clamp it there and fail this.
    #[test]
    fn tracking_is_unbiased_at_the_wavelengths() {
        let to_world =
            Transform::scale(Vec3::new(2.0, 1.0, 1.5)).then(Transform::translate(Vec3::new(-1.0, -0.5, 0.2)));
        let red = |p: Vec3| Color::new(1.2, 0.08, 0.04) * (1.0 + 0.3 * (p.x * 9.0).sin());
        let sigma_t = Volume::placed(VolumeData::Grid(grid([12, 9, 7], 3, red)), &to_world);
        let m =
            Heterogeneous::new(sigma_t, Volume::constant(Color::new(0.9, 0.5, 0.2)), 0.8, Phase::Isotropic).unwrap();
        let ray = Ray::new(Vec3::new(-2.0, -0.3, 0.1), Vec3::new(1.0, 0.25, 0.5).normalize());
        let t_max = 3.5;
        let mut exceeded = false;
        for u in [0.02f32, 0.2, 0.31] {
            let wl = Wavelengths::sample(u);
            // tau per lane of the lifted extinction, by the midpoint rule.
            let steps = 20_000;
            let h = t_max / steps as f32;
            let mut tau = [0.0f64; LANES];
            for i in 0..steps {
                let p = m.sigma_t.to_local.point(ray.at((i as f32 + 0.5) * h));
                if p.cmpge(Vec3::ZERO).all() && p.cmple(Vec3::ONE).all() {
                    let s = wl.unbounded(m.sigma_t.eval_local(p)) * m.scale;
                    exceeded |= s.max_element() > m.sigma_t_local(p).max_element() * 1.05;
                    for (c, tau) in tau.iter_mut().enumerate() {
                        *tau += f64::from(s[c] * h);
                    }
                }
            }
            let albedo = wl.reflectance(Color::new(0.9, 0.5, 0.2));
            let mut rng = Rng32::new(31);
            let n = 200_000;
            // Sums and squares of: ratio tracking, passing weights, scattering weights.
            let mut sums = [[0.0f64; 6]; LANES];
            for _ in 0..n {
                let tr = m.transmittance(&ray, t_max, &mut rng, Some(&wl));
                let u = rng.uniform();
                let s = m.sample_distance(&ray, t_max, Color::new(1.0, 0.3, 0.6), u, &mut rng, Some(&wl));
                let k = if s.scattered { 4 } else { 2 };
                for (c, sum) in sums.iter_mut().enumerate() {
                    let (a, b) = (f64::from(tr[c]), f64::from(s.weight[c]));
                    sum[0] += a;
                    sum[1] += a * a;
                    sum[k] += b;
                    sum[k + 1] += b * b;
                }
            }
            for c in 0..LANES {
                let want_tr = (-tau[c]).exp();
                let want_scatter = f64::from(albedo[c]) * (1.0 - want_tr);
                for (k, want, what) in [(0, want_tr, "ratio"), (2, want_tr, "pass"), (4, want_scatter, "scatter")] {
                    let mean = sums[c][k] / n as f64;
                    let se = ((sums[c][k + 1] / n as f64 - mean * mean) / n as f64).sqrt();
                    assert!(
                        (mean - want).abs() < 4.0 * se + 1e-4,
                        "u {u} lane {c} ({} nm) {what}: {mean} vs {want} (se {se})",
                        wl.lambda(c)
                    );
                }
            }
        }
        assert!(exceeded, "the test needs a lifted extinction above the RGB values somewhere");
    }

    /// Delta tracking's free-flight distances, grey extinction: the distribution of the
    /// scattering distance (albedo 1 makes every real collision a scattering) matches the exact
    /// CDF 1 - exp(-tau(t)) by a Kolmogorov-Smirnov test, and the passing fraction is exp(-tau).
    #[test]
    fn delta_tracking_matches_the_exact_free_flight_distribution() {
        let to_world =
            Transform::scale(Vec3::new(2.0, 1.0, 1.5)).then(Transform::translate(Vec3::new(-1.0, -0.5, 0.2)));
        let g = grid([12, 9, 7], 1, |p| Color::splat(blob(p).r()));
        let sigma_t = Volume::placed(VolumeData::Grid(g), &to_world);
        let m = Heterogeneous::new(sigma_t, Volume::constant(Color::ONE), 0.8, Phase::Isotropic).unwrap();
        let ray = Ray::new(Vec3::new(-2.0, -0.3, 0.1), Vec3::new(1.0, 0.25, 0.5).normalize());
        let t_max = 3.5;
        // tau(t) tabulated by the midpoint rule.
        let steps = 20_000;
        let h = t_max / steps as f32;
        let mut cdf_tau = Vec::with_capacity(steps + 1);
        cdf_tau.push(0.0f64);
        for i in 0..steps {
            let p = m.sigma_t.to_local.point(ray.at((i as f32 + 0.5) * h));
            let inside = p.cmpge(Vec3::ZERO).all() && p.cmple(Vec3::ONE).all();
            let s = if inside { f64::from(m.sigma_t_local(p).r()) } else { 0.0 };
            cdf_tau.push(cdf_tau[i] + s * f64::from(h));
        }
        let cdf = |t: f32| {
            let x = (t / h).clamp(0.0, steps as f32);
            let i = (x as usize).min(steps - 1);
            let tau = cdf_tau[i] + (cdf_tau[i + 1] - cdf_tau[i]) * f64::from(x - i as f32);
            1.0 - (-tau).exp()
        };
        let mut rng = Rng32::new(17);
        let n = 100_000;
        let mut ts = Vec::new();
        for _ in 0..n {
            let u = rng.uniform();
            let s = m.sample_distance(&ray, t_max, Color::ONE, u, &mut rng, None);
            // Grey extinction and albedo 1: plain delta tracking, every weight 1.
            assert!(s.weight.abs_diff_eq(Color::ONE, 1e-4), "{:?}", s.weight);
            if s.scattered {
                ts.push(s.t);
            }
        }
        let p_pass = 1.0 - ts.len() as f64 / n as f64;
        let want_pass = 1.0 - cdf(t_max);
        let se = (want_pass * (1.0 - want_pass) / n as f64).sqrt();
        assert!((p_pass - want_pass).abs() < 4.0 * se, "passing {p_pass} vs {want_pass}");
        // KS on all n samples, passing ones at t_max (a point mass the exact CDF also has).
        ts.sort_by(f32::total_cmp);
        let mut d = 0.0f64;
        for (i, &t) in ts.iter().enumerate() {
            let f = cdf(t);
            d = d.max((f - i as f64 / n as f64).abs()).max(((i + 1) as f64 / n as f64 - f).abs());
        }
        // The 0.1% critical value of the one-sample KS statistic: 1.95 / sqrt(n).
        assert!(d < 1.95 / (n as f64).sqrt(), "KS distance {d}");
    }

    /// With RGB extinction and a throughput favouring some channels, the weights of passing
    /// flights average to each channel's transmittance, and those of scattering to the albedo
    /// times (1 - transmittance) (sigma_s over sigma_t integrated along the ray), within 4
    /// standard errors.
    #[test]
    fn spectral_tracking_is_unbiased_per_channel() {
        let m = medium([12, 9, 7], 3);
        let ray = Ray::new(Vec3::new(-2.0, -0.3, 0.1), Vec3::new(1.0, 0.25, 0.5).normalize());
        let t_max = 3.5;
        let tau = optical_depth(&m, &ray, t_max);
        for beta in [Color::ONE, Color::new(1.0, 0.05, 0.3), Color::new(0.0, 0.0, 2.0)] {
            let mut rng = Rng32::new(23);
            let n = 400_000;
            // Sums and sums of squares of the passing and the scattering weights, per channel.
            let mut sums = [[0.0f64; 4]; 3];
            for _ in 0..n {
                let u = rng.uniform();
                let s = m.sample_distance(&ray, t_max, beta, u, &mut rng, None);
                let k = if s.scattered { 2 } else { 0 };
                for (c, sum) in sums.iter_mut().enumerate() {
                    let w = f64::from(s.weight[c]);
                    sum[k] += w;
                    sum[k + 1] += w * w;
                }
            }
            for c in 0..3 {
                if beta[c] == 0.0 {
                    continue;
                }
                let tr = (-tau[c]).exp();
                let albedo = [0.9, 0.5, 0.2][c];
                for (k, want, what) in [(0, tr, "pass"), (2, albedo * (1.0 - tr), "scatter")] {
                    let mean = sums[c][k] / n as f64;
                    let se = ((sums[c][k + 1] / n as f64 - mean * mean) / n as f64).sqrt();
                    assert!(
                        (mean - want).abs() < 4.0 * se + 1e-4,
                        "beta {beta}: channel {c} {what} {mean} vs {want} (se {se})"
                    );
                }
            }
        }
    }

    #[test]
    fn hostile_values_are_refused() {
        let ok = |s: Volume, a: Volume| Heterogeneous::new(s, a, 1.0, Phase::Isotropic);
        let g =
            |v: f32| Volume::placed(VolumeData::Grid(grid([2, 2, 2], 1, |_| Color::splat(v))), &Transform::IDENTITY);
        assert!(ok(g(1.0), g(0.5)).is_ok());
        let e = ok(g(-1.0), g(0.5)).unwrap_err();
        assert!(e.contains("sigma_t must be finite and >= 0, found -1 at texel (0, 0, 0)"), "{e}");
        let e = ok(g(1.0), g(1.5)).unwrap_err();
        assert!(e.contains("albedo must be in [0, 1], found 1.5"), "{e}");
        assert!(Heterogeneous::new(g(1.0), g(0.5), -1.0, Phase::Isotropic).is_err());
        assert!(Heterogeneous::new(g(1.0), g(0.5), f32::NAN, Phase::Isotropic).is_err());
        assert!(Heterogeneous::new(g(f32::MAX), g(0.5), 10.0, Phase::Isotropic).is_err());
    }
}
