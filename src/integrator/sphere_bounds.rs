//! A gathering sphere of a volume radiance estimate (SPPM's and photon mapping's in media), cut
//! by the surfaces near its centre.

use crate::geometry::Ray;
use crate::math::{Frame, Vec2, Vec3};
use crate::sampling::warp::uniform_sphere;
use crate::scene::Scene;
use std::f32::consts::PI;

/// The surfaces that cut a gathering sphere, seen as planes. Without them the volume estimate
/// is too dark within a radius of a medium's boundary (the sphere holds photons over part of its
/// volume only; -7% on a fog cube at the default radius) and too bright beside a thin wall
/// with lit fog behind it (a light shaft's window wall). Rays from the centre in 14 directions
/// (a cube's faces and corners, rotated at random) find the surfaces within the radius; each
/// hit's tangent plane excludes the photons beyond it, and the volume divided by is that of the
/// part of the sphere left: exact for one plane (the sphere less a cap), by quadrature over
/// directions for several (the region is star-shaped from the centre: its volume is the
/// integral of d^3 / 3 over directions, d the distance to the nearest plane or the radius), as
/// caps overlap at corners and where a curved object gives several planes. Exact for a flat
/// boundary, and as the radius shrinks every boundary looks flat, so the estimate still
/// converges.
pub(crate) struct SphereBounds {
    planes: [(Vec3, f32); PROBES],
    count: usize,
    pub volume: f32,
}

/// Probe rays per gathering sphere.
const PROBES: usize = 14;

/// The directions of `SphereBounds::star_volume`'s quadrature: 128 evenly spread over the
/// sphere (a spherical Fibonacci set).
static QUADRATURE: std::sync::LazyLock<[Vec3; 128]> = std::sync::LazyLock::new(|| {
    let golden = PI * (3.0 - 5f32.sqrt());
    std::array::from_fn(|k| {
        let z = 1.0 - (2 * k + 1) as f32 / 128.0;
        let s = (1.0 - z * z).max(0.0).sqrt();
        let (sin, cos) = (golden * k as f32).sin_cos();
        Vec3::new(s * cos, s * sin, z)
    })
});

impl SphereBounds {
    pub fn probe(scene: &Scene, p: Vec3, r: f32, u: Vec2) -> SphereBounds {
        const C: f32 = 0.577_350_26; // 1 / sqrt(3)
        const DIRS: [Vec3; PROBES] = [
            Vec3::X,
            Vec3::NEG_X,
            Vec3::Y,
            Vec3::NEG_Y,
            Vec3::Z,
            Vec3::NEG_Z,
            Vec3::new(C, C, C),
            Vec3::new(C, C, -C),
            Vec3::new(C, -C, C),
            Vec3::new(C, -C, -C),
            Vec3::new(-C, C, C),
            Vec3::new(-C, C, -C),
            Vec3::new(-C, -C, C),
            Vec3::new(-C, -C, -C),
        ];
        let frame = Frame::from_z(uniform_sphere(u));
        let mut bounds = SphereBounds { planes: [(Vec3::ZERO, 0.0); PROBES], count: 0, volume: 0.0 };
        let sphere = 4.0 / 3.0 * PI * r * r * r;
        for d in DIRS {
            let Some(hit) = scene.intersect(&Ray::new(p, frame.to_world(d)), r) else { continue };
            // The plane through the hit, its normal towards p; h is p's distance from it.
            let n = if (p - hit.p).dot(hit.ng) < 0.0 { -hit.ng } else { hit.ng };
            let h = (p - hit.p).dot(n).max(0.0);
            let seen = bounds.planes[..bounds.count]
                .iter()
                .any(|&(m, c)| m.dot(n) > 0.995 && (p.dot(m) - c - h).abs() < 0.02 * r);
            if seen || h >= r {
                continue;
            }
            bounds.planes[bounds.count] = (n, p.dot(n) - h);
            bounds.count += 1;
        }
        bounds.volume = match bounds.count {
            0 => sphere,
            1 => {
                let h = p.dot(bounds.planes[0].0) - bounds.planes[0].1;
                sphere - PI * (r - h) * (r - h) * (2.0 * r + h) / 3.0
            }
            _ => bounds.star_volume(p, r),
        };
        bounds.volume = bounds.volume.max(0.05 * sphere);
        bounds
    }

    /// The volume of the sphere's part on the centre's side of every plane, by a quadrature
    /// over `QUADRATURE`'s directions.
    fn star_volume(&self, p: Vec3, r: f32) -> f32 {
        let mut sum = 0.0;
        for w in QUADRATURE.iter() {
            let mut d = r;
            for &(n, c) in &self.planes[..self.count] {
                let toward = -w.dot(n);
                if toward > 0.0 {
                    d = d.min((p.dot(n) - c) / toward);
                }
            }
            sum += d * d * d;
        }
        4.0 * PI / QUADRATURE.len() as f32 * sum / 3.0
    }

    /// Whether a photon at `q` is on the centre's side of every plane.
    #[inline]
    pub fn keeps(&self, q: Vec3) -> bool {
        self.planes[..self.count].iter().all(|&(n, c)| q.dot(n) > c)
    }
}
