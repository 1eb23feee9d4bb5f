//! Light from infinitely far away in every direction: an environment map (Mitsuba 3 `envmap`) or
//! a constant environment (`constant`). Rays that leave the scene see it, shading points sample
//! it (by luminance times sin theta for a map, uniformly for a constant), and it emits photons
//! through the scene's `PhotonDisk`.
//!
//! Orientation and lookup follow Mitsuba 3.9.1 (`src/emitters/envmap.cpp`): in the map's own
//! frame +y is up, a direction d has u = atan2(d.x, -d.z) / 2 pi and v = acos(d.y) / pi, so the
//! top row is +y, the image's horizontal centre looks down +z and u = 0.25 is +x. Texel column i
//! is centred at u = (i + 0.5) / W (periodic) while row j sits at v = j / (H - 1), so the first
//! and last rows lie on the poles; radiance is bilinear between the four surrounding texels.
//!
//! The texels and the sampling distribution are built once per image and shared as
//! `&'static EnvMap` (interned by content, as plastic's coating tables are), so the light stays a
//! small `Copy` value and a lookup allocates nothing. The distribution is piecewise constant
//! over the W x (H - 1) cells between texel centres, each cell weighted by the exact integral of
//! the bilinear luminance times sin theta over it, so it is positive wherever the radiance is.

use super::EmissionSample;
use super::disk::PhotonDisk;
use crate::math::{Color, Frame, PackedColor, Vec2, Vec3, luminance};
use crate::sampling::distribution::Distribution2D;
use crate::sampling::warp::uniform_sphere;
use std::collections::HashMap;
use std::f32::consts::PI;
use std::sync::{Mutex, OnceLock};

/// The texels of a lat-long environment image and their sampling distribution.
#[derive(Debug)]
pub struct EnvMap {
    width: u32,
    height: u32,
    /// Linear RGB, row-major, row 0 at the top (+y); 12 bytes a texel (`PackedColor`).
    texels: Vec<PackedColor>,
    /// Over (u - 0.5 / W, v) in [0, 1)^2: W x (H - 1) cells.
    distribution: Distribution2D,
    /// Integral of the radiance over the sphere of directions (W/m^2 per unit scale).
    integral: Color,
}

impl PartialEq for EnvMap {
    /// Maps are interned, so two equal maps are the same map.
    fn eq(&self, other: &Self) -> bool {
        std::ptr::eq(self, other)
    }
}

impl EnvMap {
    /// The map of a `width` x `height` image (row 0 at the top); Mitsuba's minimum is 2 x 3.
    pub fn new(width: u32, height: u32, texels: Vec<Color>) -> Result<EnvMap, String> {
        if width < 2 || height < 3 {
            return Err(format!("an environment map needs at least 2 x 3 texels, this one has {width} x {height}"));
        }
        if texels.len() != width as usize * height as usize {
            return Err(format!("{} texels for a {width} x {height} map", texels.len()));
        }
        if let Some(i) = texels.iter().position(|t| !t.is_finite()) {
            let (x, y) = (i % width as usize, i / width as usize);
            return Err(format!("the environment map has a texel that is not a finite number at column {x}, row {y}"));
        }
        let (w, h) = (width as usize, height as usize);
        // Row integrals of sin theta against the linear interpolation between rows j and j + 1:
        // a gets the weight s0 - s1, b the weight s1 (computed in f64: s1 cancels badly).
        let dtheta = std::f64::consts::PI / (h - 1) as f64;
        let weights: Vec<(f64, f64)> = (0..h - 1)
            .map(|j| {
                let (t0, t1) = (j as f64 * dtheta, (j + 1) as f64 * dtheta);
                let s0 = t0.cos() - t1.cos();
                let s1 = -t1.cos() + (t1.sin() - t0.sin()) / dtheta;
                (s0 - s1, s1)
            })
            .collect();
        let lum: Vec<f64> = texels.iter().map(|&c| luminance(c.max(Color::ZERO)) as f64).collect();
        let mut cells = Vec::with_capacity(w * (h - 1));
        let mut integral = [0.0f64; 3];
        for (j, &(wa, wb)) in weights.iter().enumerate() {
            for i in 0..w {
                let i1 = (i + 1) % w;
                let top = 0.5 * (lum[j * w + i] + lum[j * w + i1]);
                let bottom = 0.5 * (lum[(j + 1) * w + i] + lum[(j + 1) * w + i1]);
                cells.push((top * wa + bottom * wb) as f32);
                // Over u the interpolation between columns averages to the column values.
                for (k, acc) in integral.iter_mut().enumerate() {
                    *acc += (texels[j * w + i][k] as f64 * wa + texels[(j + 1) * w + i][k] as f64 * wb)
                        * (2.0 * std::f64::consts::PI / w as f64);
                }
            }
        }
        let distribution = Distribution2D::new(&cells, w, h - 1);
        let integral = Color::new(integral[0] as f32, integral[1] as f32, integral[2] as f32);
        let texels = texels.into_iter().map(PackedColor::from).collect();
        Ok(EnvMap { width, height, texels, distribution, integral })
    }

    /// The map of these texels, made once per distinct image and kept for the life of the
    /// process (a renderer loads a handful of environments; each is shared, never copied).
    pub fn shared(width: u32, height: u32, texels: Vec<Color>) -> Result<&'static EnvMap, String> {
        type Key = (u32, u32, u64);
        static MAPS: OnceLock<Mutex<HashMap<Key, Vec<&'static EnvMap>>>> = OnceLock::new();
        let hash = {
            use std::hash::{Hash, Hasher};
            let mut h = std::collections::hash_map::DefaultHasher::new();
            for t in &texels {
                t.to_array().map(f32::to_bits).hash(&mut h);
            }
            h.finish()
        };
        let key = (width, height, hash);
        let mut maps = MAPS.get_or_init(Default::default).lock().unwrap_or_else(|e| e.into_inner());
        let same = maps
            .get(&key)
            .and_then(|v| v.iter().find(|m| m.texels.iter().map(|t| t.get()).eq(texels.iter().copied())).copied());
        if let Some(m) = same {
            return Ok(m);
        }
        let map: &'static EnvMap = Box::leak(Box::new(EnvMap::new(width, height, texels)?));
        maps.entry(key).or_default().push(map);
        Ok(map)
    }

    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Bytes held by the texels and the distribution.
    pub fn memory_bytes(&self) -> usize {
        self.texels.len() * std::mem::size_of::<PackedColor>() + self.distribution.memory_bytes()
    }

    /// Bilinear radiance at (u, v) (Mitsuba's lookup with its half-texel shift in u).
    #[inline]
    pub fn lookup(&self, u: f32, v: f32) -> Color {
        let (w, h) = (self.width as usize, self.height as usize);
        let mut x = u - 0.5 / w as f32;
        x -= x.floor();
        let x = x * w as f32;
        let y = (v * (h - 1) as f32).clamp(0.0, (h - 1) as f32);
        let (x0, y0) = ((x as usize).min(w - 1), (y as usize).min(h - 2));
        let (fx, fy) = (x - x0 as f32, y - y0 as f32);
        let x1 = if x0 + 1 == w { 0 } else { x0 + 1 };
        let row = |r: usize| self.texels[r * w + x0].get() * (1.0 - fx) + self.texels[r * w + x1].get() * fx;
        row(y0) * (1.0 - fy) + row(y0 + 1) * fy
    }
}

/// (u, v) of a direction in the map's frame.
#[inline]
fn direction_to_uv(d: Vec3) -> Vec2 {
    let u = d.x.atan2(-d.z) * (0.5 / PI);
    Vec2::new(u - u.floor(), d.y.clamp(-1.0, 1.0).acos() / PI)
}

/// An environment: a map (scaled) or a constant radiance, turned into the world by `frame`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Environment {
    /// The image, or `None` for a constant environment.
    pub map: Option<&'static EnvMap>,
    /// Radiance of a constant environment; the factor a map's texels are multiplied by.
    pub scale: Color,
    /// The map's frame in the world (its columns are where the map's x, y and z axes point).
    pub frame: Frame,
    /// Where its photons enter the scene (set when the scene is built).
    pub disk: PhotonDisk,
}

impl Environment {
    /// A constant environment of radiance `radiance`.
    pub fn constant(radiance: Color) -> Self {
        Environment { map: None, scale: radiance, frame: Frame::from_z(Vec3::Z), disk: PhotonDisk::default() }
    }

    /// An environment map multiplied by `scale`, oriented by the rotation `frame`.
    pub fn map(map: &'static EnvMap, scale: f32, frame: Frame) -> Self {
        Environment { map: Some(map), scale: Color::splat(scale), frame, disk: PhotonDisk::default() }
    }

    /// Radiance arriving from the environment along unit direction `wi` (pointing away from
    /// the scene, towards the environment).
    #[inline]
    pub fn radiance(&self, wi: Vec3) -> Color {
        match self.map {
            None => self.scale,
            Some(m) => {
                let uv = direction_to_uv(self.frame.to_local(wi));
                m.lookup(uv.x, uv.y) * self.scale
            }
        }
    }

    /// A direction towards the environment for the uniform numbers `u`: (direction, radiance,
    /// solid-angle density).
    #[inline]
    pub fn sample(&self, u: Vec2) -> Option<(Vec3, Color, f32)> {
        let Some(m) = self.map else {
            return Some((uniform_sphere(u), self.scale, 0.25 / PI));
        };
        let (p, pdf_uv) = m.distribution.sample(u);
        let theta = p.y * PI;
        let phi = 2.0 * PI * (p.x + 0.5 / m.width as f32);
        let (sin_t, cos_t) = theta.sin_cos();
        if !(sin_t > 0.0 && pdf_uv > 0.0) {
            return None;
        }
        let (sin_p, cos_p) = phi.sin_cos();
        let local = Vec3::new(sin_p * sin_t, cos_t, -cos_p * sin_t);
        let pdf = pdf_uv / (2.0 * PI * PI * sin_t);
        let wi = self.frame.to_world(local);
        // Radiance from the lookup of the direction itself, so `sample` and `radiance` agree.
        Some((wi, self.radiance(wi), pdf))
    }

    /// Solid-angle density with which `sample` picks direction `wi`.
    #[inline]
    pub fn pdf(&self, wi: Vec3) -> f32 {
        let Some(m) = self.map else { return 0.25 / PI };
        let d = self.frame.to_local(wi);
        let sin_t = (d.x * d.x + d.z * d.z).sqrt();
        if !(sin_t > 0.0) {
            return 0.0;
        }
        let uv = direction_to_uv(d);
        let mut u = uv.x - 0.5 / m.width as f32;
        u -= u.floor();
        m.distribution.pdf(Vec2::new(u, uv.y)) / (2.0 * PI * PI * sin_t)
    }

    /// Integral of the radiance over all directions.
    pub fn integral(&self) -> Color {
        match self.map {
            None => self.scale * (4.0 * PI),
            Some(m) => m.integral * self.scale,
        }
    }

    /// Power entering through the photon disk: its area times the integral of the radiance (a
    /// disk of area A perpendicular to the direction w receives L(w) A per unit solid angle).
    pub fn power(&self) -> Color {
        self.integral() * self.disk.area()
    }

    /// A photon: a direction from `sample`, a point of the disk, flux L A_eff / pdf.
    pub fn sample_le(&self, u_pos: Vec2, u_dir: Vec2) -> Option<EmissionSample> {
        let (wi, radiance, pdf) = self.sample(u_dir)?;
        if !(pdf > 0.0) {
            return None;
        }
        let d = -wi;
        let (ray, inv_density) = self.disk.ray(d, u_pos)?;
        let flux = radiance * (inv_density / pdf);
        Some(EmissionSample { ray, n: d, le: radiance, pdf_pos: 1.0 / inv_density, pdf_dir: pdf, flux })
    }
}

#[cfg(test)]
mod tests;
