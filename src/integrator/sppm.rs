//! Stochastic progressive photon mapping (Hachisuka, Ogaki and Jensen 2008; Hachisuka and Jensen
//! 2009): converges to the correct image with bounded memory, and renders what a path tracer
//! cannot, such as caustics from a point light seen directly and through glass.
//!
//! Each iteration runs three passes:
//! 1. `visible_points`: one camera sample per pixel (pixel jitter and lens re-sampled every
//!    iteration) follows mirrors and glass to the first non-specular surface, adds emitted and
//!    directly sampled light there, and leaves a visible point (position, BSDF, throughput);
//! 2. `photon_pass`: photons from the lights, stored where they land on diffuse surfaces after at
//!    least one bounce (direct light is already counted), in a hash grid whose cells are as large
//!    as the largest search radius;
//! 3. `update_statistics`: every pixel collects the photons within its radius r and updates its
//!    photon count N, radius r and flux tau with alpha = 2/3 (Hachisuka 2008 eq. 6-7 and 9-10).
//!
//! Pixels query the photons (rather than photons the pixels), so every pixel sums its photons in
//! a fixed order and the image is the same for any thread count. Memory is the per-pixel state
//! plus one iteration's visible points and photons, whatever the number of iterations.

use super::RayStats;
use super::path::direct_light;
use crate::film::Image;
use crate::material::bsdf::{Bsdf, Transport};
use crate::math::{Color, Vec2, Vec3};
use crate::photon::trace::{self, DIRECT, PhotonHit};
use crate::render::{RenderControl, RenderSettings, RenderStats};
use crate::sampling::{Sampler, hash_seed};
use crate::scene::Scene;
use rayon::prelude::*;
use std::f32::consts::PI;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// SPPM settings.
#[derive(Clone, Debug, PartialEq)]
pub struct SppmConfig {
    /// Photons emitted per iteration.
    pub photons_per_iter: u64,
    /// Search radius every pixel starts with; `None` derives it per pixel (see `initial_radius`).
    pub initial_radius: Option<f32>,
    /// Fraction of new photons kept (Hachisuka 2008): 2/3.
    pub alpha: f32,
    /// Specular bounces followed from the camera.
    pub max_depth: u32,
}

/// Working memory of an SPPM render of `pixels` pixels and `photons_per_iter` photons per
/// iteration (photons are stored up to a few times each as they bounce).
pub fn estimated_bytes(pixels: u64, photons_per_iter: u64) -> u64 {
    let per_pixel = (std::mem::size_of::<PixelStats>() + std::mem::size_of::<Option<VisiblePoint>>()) as u64;
    let per_photon = 3 * (std::mem::size_of::<PhotonHit>() + std::mem::size_of::<(u64, u32)>() + 4) as u64;
    pixels.saturating_mul(per_pixel).saturating_add(photons_per_iter.saturating_mul(per_photon))
}

/// What one pixel has gathered so far.
#[derive(Clone, Copy, Debug, Default)]
pub struct PixelStats {
    /// Sum over iterations of emitted and direct light.
    pub ld: Color,
    /// Accumulated photon count N (fractional after the alpha reduction).
    pub n: f32,
    /// Current search radius; 0 until the pixel has had a visible point.
    pub r: f32,
    /// Accumulated flux tau (already rescaled to the current radius).
    pub tau: Color,
}

impl PixelStats {
    /// The progressive radiance estimate update for one iteration in which `m` photons within
    /// radius r brought flux `phi` (Hachisuka 2008 eq. 6, 7, 9 and 10): keep a fraction alpha of
    /// the new photons, shrink the disc so its density matches, and scale the flux to the
    /// new disc.
    pub fn update(&mut self, m: u32, phi: Color, alpha: f32) {
        if m == 0 {
            return;
        }
        let m = m as f32;
        let n_new = self.n + alpha * m;
        let ratio = n_new / (self.n + m);
        self.tau = (self.tau + phi) * ratio;
        self.r *= ratio.sqrt();
        self.n = n_new;
    }

    /// Radiance after `iterations` iterations of photons whose flux was already divided by the
    /// number emitted per iteration.
    pub fn radiance(&self, iterations: u32) -> Color {
        let it = iterations.max(1) as f32;
        let photon = if self.r > 0.0 { self.tau / (it * PI * self.r * self.r) } else { Color::ZERO };
        self.ld / it + photon
    }
}

/// A camera path's first non-specular hit.
#[derive(Clone, Copy)]
struct VisiblePoint {
    p: Vec3,
    wo: Vec3,
    bsdf: Bsdf,
    beta: Color,
    /// Distance travelled from the camera (for the initial radius).
    dist: f32,
}

/// Photons of one iteration sorted into a hash grid: entries sorted by (bucket, cell).
struct PhotonGrid {
    cell: f32,
    origin: Vec3,
    mask: u64,
    /// bucket -> range in `entries`.
    starts: Vec<u32>,
    /// (cell key, photon index)
    entries: Vec<(u64, u32)>,
}

#[inline]
fn cell_key(c: [i32; 3]) -> u64 {
    // Distinct cells get distinct keys for coordinates within +-2^20.
    let m = |v: i32| (v as i64 + (1 << 20)) as u64 & 0x1f_ffff;
    m(c[0]) | m(c[1]) << 21 | m(c[2]) << 42
}

impl PhotonGrid {
    fn build(hits: &[PhotonHit], cell: f32, origin: Vec3) -> Self {
        let size = hits.len().next_power_of_two().max(1);
        let mask = size as u64 - 1;
        let mut entries: Vec<(u64, u32)> =
            hits.par_iter().enumerate().map(|(i, h)| (cell_key(Self::coords(h.p, origin, cell)), i as u32)).collect();
        let bucket = |k: u64| crate::sampling::mix64(k) & mask;
        entries.par_sort_unstable_by_key(|&(k, i)| (bucket(k), k, i));
        let mut starts = vec![0u32; size + 1];
        for &(k, _) in &entries {
            starts[bucket(k) as usize + 1] += 1;
        }
        for b in 0..size {
            starts[b + 1] += starts[b];
        }
        PhotonGrid { cell, origin, mask, starts, entries }
    }

    #[inline]
    fn coords(p: Vec3, origin: Vec3, cell: f32) -> [i32; 3] {
        let c = ((p - origin) / cell).floor();
        [c.x.clamp(-1e6, 1e6) as i32, c.y.clamp(-1e6, 1e6) as i32, c.z.clamp(-1e6, 1e6) as i32]
    }

    /// Calls `f(photon index)` for every photon in the cells overlapping the sphere (p, r), each
    /// once, in a fixed order.
    #[inline]
    fn for_each_near(&self, p: Vec3, r: f32, mut f: impl FnMut(u32)) {
        let lo = Self::coords(p - Vec3::splat(r), self.origin, self.cell);
        let hi = Self::coords(p + Vec3::splat(r), self.origin, self.cell);
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    let key = cell_key([x, y, z]);
                    let b = (crate::sampling::mix64(key) & self.mask) as usize;
                    let range = self.starts[b] as usize..self.starts[b + 1] as usize;
                    for &(k, i) in &self.entries[range] {
                        if k == key {
                            f(i);
                        }
                    }
                }
            }
        }
    }
}

/// Renders with SPPM: `settings.spp` iterations (or until the time limit), one camera sample per
/// pixel per iteration.
pub fn render_sppm(
    scene: &Scene,
    config: &SppmConfig,
    settings: &RenderSettings,
    control: &RenderControl,
) -> (Image, RenderStats) {
    let start = Instant::now();
    let (w, h) = (settings.width, settings.height);
    let n_pixels = (w * h) as usize;
    let mut pixels = vec![PixelStats::default(); n_pixels];
    let rays = AtomicU64::new(0);
    let shadow_rays = AtomicU64::new(0);
    let diag = {
        let b = scene.bounds();
        if b.is_empty() || !b.diagonal().is_finite() { 1.0 } else { b.diagonal() }
    };
    let mut iterations = 0u32;
    let mut interrupted = false;
    let mut last_checkpoint = Instant::now();
    let mut peak_bytes = 0usize;
    while iterations < settings.spp {
        if let Some(limit) = settings.time_limit
            && start.elapsed() >= limit
        {
            break;
        }
        if control.cancel.load(Ordering::Relaxed) {
            interrupted = true;
            break;
        }
        let it = iterations;
        // Pass 1: visible points, with emitted and direct light added to each pixel.
        let vps: Vec<Option<VisiblePoint>> = pixels
            .par_iter_mut()
            .enumerate()
            .map(|(k, px)| {
                let mut stats = RayStats::default();
                let vp = visible_point(scene, config, settings, (k as u32 % w, k as u32 / w), it, px, &mut stats);
                rays.fetch_add(stats.rays, Ordering::Relaxed);
                shadow_rays.fetch_add(stats.shadow_rays, Ordering::Relaxed);
                if let Some(v) = &vp
                    && px.r == 0.0
                {
                    px.r = config.initial_radius.unwrap_or_else(|| initial_radius(scene, v.dist, diag));
                }
                vp
            })
            .collect();
        // Pass 2: photons, without their first hits (direct light is traced above).
        let seed = hash_seed(&[settings.seed, it as u64]);
        let pass = trace::trace_global(scene, config.photons_per_iter, seed);
        let hits: Vec<PhotonHit> = pass.hits.into_iter().filter(|h| h.flags & DIRECT == 0).collect();
        let max_r = pixels.iter().map(|p| p.r).fold(0.0f32, f32::max);
        // Pass 3: each pixel gathers the photons within its radius and updates its statistics.
        let mut bytes = pixels.len() * std::mem::size_of::<PixelStats>()
            + vps.capacity() * std::mem::size_of::<Option<VisiblePoint>>()
            + hits.capacity() * std::mem::size_of::<PhotonHit>();
        if max_r > 0.0 && !hits.is_empty() {
            let grid = PhotonGrid::build(&hits, max_r, scene.bounds().min.min(Vec3::ZERO));
            bytes += grid.entries.capacity() * std::mem::size_of::<(u64, u32)>() + grid.starts.capacity() * 4;
            pixels.par_iter_mut().zip(vps.par_iter()).for_each(|(px, vp)| {
                let Some(v) = vp else { return };
                let r2 = px.r * px.r;
                let (mut m, mut phi) = (0u32, Color::ZERO);
                grid.for_each_near(v.p, px.r, |i| {
                    let ph = &hits[i as usize];
                    if (ph.p - v.p).length_squared() > r2 || ph.dir.dot(v.bsdf.normal()) >= 0.0 {
                        return;
                    }
                    let f = v.bsdf.f(v.wo, -ph.dir);
                    if f != Color::ZERO {
                        m += 1;
                        phi += f * ph.flux;
                    }
                });
                px.update(m, v.beta * phi, config.alpha);
            });
        }
        peak_bytes = peak_bytes.max(bytes);
        iterations += 1;
        if let (Some(every), Some(cb)) = (settings.checkpoint, control.on_checkpoint)
            && last_checkpoint.elapsed() >= every
            && iterations < settings.spp
        {
            cb(&image(&pixels, w, h, iterations), iterations);
            last_checkpoint = Instant::now();
        }
    }
    let stats = RenderStats {
        wall: start.elapsed(),
        rays: RayStats { rays: rays.into_inner(), shadow_rays: shadow_rays.into_inner() },
        samples_per_pixel: iterations,
        passes: iterations,
        nonfinite_samples: 0,
        interrupted,
        memory_bytes: peak_bytes as u64,
    };
    (image(&pixels, w, h, iterations), stats)
}

fn image(pixels: &[PixelStats], w: u32, h: u32, iterations: u32) -> Image {
    let mut img = Image::new(w, h);
    for (k, p) in pixels.iter().enumerate() {
        let c = p.radiance(iterations);
        img.pixels[k] = if c.is_finite() { c } else { Color::ZERO };
    }
    img
}

/// A starting radius for a pixel whose first visible point is `dist` from the camera: about two
/// pixel footprints there, kept between 0.05% and 2% of the scene's size so any scene scale works.
fn initial_radius(scene: &Scene, dist: f32, diag: f32) -> f32 {
    let cam = &scene.camera;
    let footprint = dist * cam.pixel_size / cam.d;
    (2.0 * footprint).clamp(5e-4 * diag, 0.02 * diag)
}

/// Traces the camera sample of pixel `xy` in iteration `it` to its first non-specular surface,
/// adding emitted and direct light to `px.ld`.
fn visible_point(
    scene: &Scene,
    config: &SppmConfig,
    settings: &RenderSettings,
    (x, y): (u32, u32),
    it: u32,
    px: &mut PixelStats,
    stats: &mut RayStats,
) -> Option<VisiblePoint> {
    let mut sampler = Sampler::new(settings.sampler, settings.seed, x, y, it, settings.strata);
    let jitter = sampler.pixel();
    let offset = if settings.antialias { jitter } else { Vec2::splat(0.5) };
    let lens = sampler.lens();
    let mut ray = scene.camera.generate_ray(Vec2::new(x as f32, y as f32) + offset, lens);
    let mut beta = Color::ONE;
    let mut dist = 0.0;
    for depth in 0..=config.max_depth {
        stats.rays += 1;
        let Some(hit) = scene.intersect(&ray, f32::INFINITY) else {
            px.ld += beta * scene.background;
            return None;
        };
        dist += hit.t;
        let m = scene.material(&hit);
        let wo = -ray.d;
        if m.is_emitter() {
            if hit.is_front(ray.d) {
                px.ld += beta * m.emission;
            }
            return None;
        }
        let bsdf = Bsdf::new(m, hit.ns, hit.ng, wo);
        if bsdf.is_specular_only() {
            if depth == config.max_depth {
                return None;
            }
            let s = bsdf.sample(wo, sampler.next_1d(), sampler.next_2d(), Transport::Radiance)?;
            beta *= s.weight;
            ray = scene.spawn(&hit, s.wi);
            continue;
        }
        px.ld += beta * direct_light(scene, &hit, &bsdf, wo, &mut sampler, stats, false);
        return Some(VisiblePoint { p: hit.p, wo, bsdf, beta, dist });
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn update_follows_hachisuka_formulas() {
        // N = 10, r = 1, tau = 5; M = 6 new photons with flux 3, alpha = 2/3:
        // N' = 10 + 4 = 14, r'^2 = r^2 N'/(N + M) = 14/16, tau' = (5 + 3) 14/16 = 7.
        let mut p = PixelStats { ld: Color::ZERO, n: 10.0, r: 1.0, tau: Color::splat(5.0) };
        p.update(6, Color::splat(3.0), 2.0 / 3.0);
        assert!((p.n - 14.0).abs() < 1e-6);
        assert!((p.r * p.r - 14.0 / 16.0).abs() < 1e-6);
        assert!((p.tau.x - 7.0).abs() < 1e-6);
        // No photons: nothing changes.
        let before = p;
        p.update(0, Color::ZERO, 2.0 / 3.0);
        assert_eq!((p.n, p.r, p.tau), (before.n, before.r, before.tau));
        // The estimate: tau / (iterations pi r^2) plus the mean direct light.
        p.ld = Color::splat(4.0);
        let l = p.radiance(2);
        assert!((l.x - (2.0 + 7.0 / (2.0 * PI * 14.0 / 16.0))).abs() < 1e-5);
    }

    #[test]
    fn grid_finds_each_nearby_photon_once() {
        let mut rng = crate::sampling::Rng32::new(1);
        let hits: Vec<PhotonHit> = (0..5000)
            .map(|_| PhotonHit {
                p: Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 4.0 - 2.0,
                dir: -Vec3::Y,
                flux: Color::ONE,
                flags: 0,
                n: Vec3::Y,
            })
            .collect();
        let r = 0.3;
        let grid = PhotonGrid::build(&hits, r, Vec3::splat(-2.0));
        for _ in 0..200 {
            let q = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 4.0 - 2.0;
            let mut found = Vec::new();
            grid.for_each_near(q, r, |i| {
                if (hits[i as usize].p - q).length() <= r {
                    found.push(i)
                }
            });
            let mut brute: Vec<u32> =
                (0..hits.len() as u32).filter(|&i| (hits[i as usize].p - q).length() <= r).collect();
            found.sort();
            brute.sort();
            assert_eq!(found, brute);
        }
    }
}
