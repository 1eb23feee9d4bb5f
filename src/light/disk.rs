//! The disk through which photons from lights at infinity (directional, environment, constant)
//! enter the scene: perpendicular to each photon's direction, centred on the scene.
//!
//! Its core is the bounding sphere of the finite geometry (radius `radius`): a photon line that
//! misses it misses everything finite. Infinite planes reach beyond it, and the light they
//! reflect onto the finite geometry (and the light the geometry sends onto them) needs photons
//! there too, so a scene with planes extends the disk to `reach` (`PLANE_REACH` core radii, see
//! `docs/scene-format.md`, "How photons cover infinite planes"): half the photons are spread
//! uniformly over the core, the other half beyond it with a density falling as 1 / rho^2 (a
//! uniform density in log rho), so every distance range gets its share without starving the core.
//! Each photon carries 1 / density, so the estimate is unbiased everywhere inside `reach`.

use crate::geometry::Ray;
use crate::math::{Frame, Vec2, Vec3};
use crate::sampling::warp::concentric_disk;
use std::f32::consts::PI;

/// How far beyond the finite geometry photons cover infinite planes, in bounding radii.
pub const PLANE_REACH: f32 = 32.0;

/// Share of the photons that enter through the core when the disk extends beyond it.
const CORE_SHARE: f32 = 0.5;

/// A disk perpendicular to a photon's direction; see the module docs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PhotonDisk {
    /// Centre of the bounding sphere of the finite geometry.
    pub center: Vec3,
    /// Its radius: the core of the disk.
    pub radius: f32,
    /// Outer radius: `radius` without planes, `PLANE_REACH * radius` with them.
    pub reach: f32,
}

impl PhotonDisk {
    /// A disk covering the sphere (`center`, `radius`), extended to `PLANE_REACH` radii when
    /// the scene has infinite planes.
    pub fn new(center: Vec3, radius: f32, planes: bool) -> Self {
        let reach = if planes { radius * PLANE_REACH } else { radius };
        PhotonDisk { center, radius, reach }
    }

    /// Whether the disk extends beyond its core.
    #[inline]
    fn extended(&self) -> bool {
        self.reach > self.radius * 1.0001
    }

    /// Area of the whole disk: the mean of 1 / density over its photons.
    pub fn area(&self) -> f32 {
        PI * self.reach.max(self.radius) * self.reach.max(self.radius)
    }

    /// Area of the core (what the finite geometry can intercept).
    pub fn core_area(&self) -> f32 {
        PI * self.radius * self.radius
    }

    /// Density (per unit area) of a point `rho` from the centre.
    pub fn density(&self, rho: f32) -> f32 {
        if !self.extended() {
            return if rho <= self.radius { 1.0 / self.core_area() } else { 0.0 };
        }
        if rho < self.radius {
            CORE_SHARE / self.core_area()
        } else if rho <= self.reach {
            (1.0 - CORE_SHARE) / (2.0 * PI * rho * rho * (self.reach / self.radius).ln())
        } else {
            0.0
        }
    }

    /// A point of the disk (in its own 2-D coordinates) and its density.
    pub fn sample(&self, u: Vec2) -> (Vec2, f32) {
        let p = if !self.extended() {
            concentric_disk(u) * self.radius
        } else if u.x < CORE_SHARE {
            concentric_disk(Vec2::new(u.x / CORE_SHARE, u.y)) * self.radius
        } else {
            let t = ((u.x - CORE_SHARE) / (1.0 - CORE_SHARE)).min(1.0);
            let rho = self.radius * (self.reach / self.radius).powf(t);
            let phi = 2.0 * PI * u.y;
            Vec2::new(phi.cos(), phi.sin()) * rho
        };
        (p, self.density(p.length()))
    }

    /// Density (per unit area of the disk) of the point where `ray` crosses it: what
    /// `ray`'s origin was drawn with.
    pub fn pdf_ray(&self, ray: &Ray) -> f32 {
        let v = ray.o - self.center;
        let off = v - ray.d * v.dot(ray.d);
        self.density(off.length())
    }

    /// A photon ray travelling along unit `d` through a sampled point of the disk, starting
    /// before the bounding sphere of the finite geometry, and 1 / density of the point. Lines
    /// that cross infinite planes before that start are moved back by `Scene::photon_entry`.
    pub fn ray(&self, d: Vec3, u: Vec2) -> Option<(Ray, f32)> {
        let (p, density) = self.sample(u);
        if !(density > 0.0) {
            return None;
        }
        let frame = Frame::from_z(d);
        let q = self.center + frame.x * p.x + frame.y * p.y;
        let o = q - d * (self.radius * 1.001);
        Some((Ray::new(o, d), 1.0 / density))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng32;

    #[test]
    fn inverse_density_averages_to_the_area_and_rings_get_their_share() {
        for disk in [PhotonDisk::new(Vec3::ONE, 2.0, false), PhotonDisk::new(Vec3::ZERO, 0.5, true)] {
            let mut rng = Rng32::new(4);
            let n = 400_000;
            let (mut sum, mut inside) = (0.0f64, 0u32);
            // Ring [a, b]: its expected share is the integral of the density over it.
            let (a, b) = (0.8 * disk.reach, 0.9 * disk.reach);
            for _ in 0..n {
                let (p, pdf) = disk.sample(rng.uniform2());
                assert!(p.length() <= disk.reach * 1.0001 && pdf > 0.0);
                assert!((pdf - disk.density(p.length())).abs() <= 1e-6 * pdf);
                sum += 1.0 / pdf as f64;
                inside += u32::from((a..b).contains(&p.length()));
            }
            let area = sum / n as f64;
            assert!((area / disk.area() as f64 - 1.0).abs() < 0.02, "{disk:?}: {area} vs {}", disk.area());
            // Integrate the density over the ring numerically.
            let steps = 1000;
            let expected: f64 = (0..steps)
                .map(|k| {
                    let r = a + (b - a) * (k as f32 + 0.5) / steps as f32;
                    (disk.density(r) * 2.0 * PI * r * (b - a) / steps as f32) as f64
                })
                .sum();
            let share = inside as f64 / n as f64;
            assert!((share - expected).abs() < 4.0 * (expected / n as f64).sqrt() + 1e-4, "{share} vs {expected}");
        }
    }

    #[test]
    fn rays_start_before_the_core_and_pass_through_the_disk() {
        let disk = PhotonDisk::new(Vec3::new(1.0, 2.0, 3.0), 2.0, true);
        let d = Vec3::new(0.3, -1.0, 0.2).normalize();
        let mut rng = Rng32::new(9);
        for _ in 0..1000 {
            let (ray, inv) = disk.ray(d, rng.uniform2()).unwrap();
            assert!(inv > 0.0 && ray.d == d);
            // The origin lies radius behind the disk's plane, within reach of the axis.
            let v = ray.o - disk.center;
            assert!((v.dot(d) + disk.radius * 1.001).abs() < 1e-4);
            assert!((v - d * v.dot(d)).length() <= disk.reach * 1.0001);
        }
    }
}
