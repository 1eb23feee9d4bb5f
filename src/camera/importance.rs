//! Camera importance for light tracing and bidirectional methods: the importance We of a ray
//! leaving the camera, the densities with which `generate_ray` produces it, and the connection of
//! a scene point to the lens. Sources: pbrt-v4's `PerspectiveCamera::We`, `PDF_We` and
//! `SampleWi` (src/pbrt/cameras.cpp; the derivation is pbrt-v3 sec. 16.1.1) and Mitsuba 3's
//! `PerspectiveCamera::sample_direction` and `importance` (src/sensors/perspective.cpp). Mitsuba
//! 3's thin lens and orthographic sensors define none; the orthographic case follows
//! Mitsuba 0.6's `OrthographicCamera::sampleDirect` (src/sensors/orthographic.cpp).
//!
//! Normalisation, which the light tracer relies on: We is normalised over the FULL film (not a
//! crop window, not pbrt's sample bounds widened by the filter), so that
//! ∫_lens ∫_Ω We(p, ω) |cos θ| dω dA(p) = 1, θ being the angle to the camera axis -w. A pixel's
//! value is then (sum of β f |cos| importance / pdf over the connections that land in it) / spp,
//! with one light path traced per pixel sample of the full film (W H spp paths in all).
//!
//! - Perspective: We = 1 / (A lens_area cos⁴θ), where A = W H pixel_size² / d² is the full film's
//!   area on the plane at distance 1 along the axis and lens_area = π r² (1 for a pinhole, whose
//!   position is a delta, as in pbrt-v4). `generate_ray` at uniform film positions and lens
//!   points gives rays of density pdf_pos pdf_dir = (1 / lens_area) (1 / (A cos³θ)) = We cos θ.
//! - Orthographic: the direction is a delta (-w), so We(p, ω) = importance δ(ω + w) with
//!   importance = 1 / A_beam, where A_beam = W H pixel_size² |(u × v) · w| is the film's area
//!   across the rays (its view-plane area |u × v| W H pixel_size² times the cosine θ_p between
//!   the rays and the plane's normal); then ∫_plane ∫_Ω We |cos θ| dω dA = importance |cos θ_p|
//!   view-plane area = 1, θ measured from the plane's normal. A connection contributes
//!   β f |cos| importance, with pdf = 1 and no 1 / dist² (Mitsuba 0.6 returns 1 / view-plane
//!   area, the same unless the frame is sheared). `pdf_we` gives pdf_pos = 1 / view-plane area
//!   and pdf_dir = 1, the weight of the delta (as pdf_pos = 1 is for the pinhole), so
//!   pdf_pos pdf_dir = importance |cos θ_p|.
//!
//! Everything is computed on the fly from the camera's public fields (a few cross and dot
//! products), so no field is added and `desc` may keep changing `u` and `pixel_size` after
//! `Camera::new`. Raster positions come from the dual basis of (u, v, w), so they invert
//! `generate_ray` exactly for any frame: Mitsuba's mirrored ones and the scaled or sheared
//! orthographic ones.

use std::f32::consts::PI;

use super::{Camera, Projection};
use crate::geometry::Ray;
use crate::math::{Vec2, Vec3};
use crate::sampling::warp::concentric_disk;

#[cfg(test)]
mod tests;

/// What connecting a point to the camera gives (light tracing's "t = 1" strategy, pbrt-v4's
/// `CameraWiSample`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraWi {
    /// Unit direction from the reference point towards the lens point.
    pub wi: Vec3,
    /// Distance from the reference point to the lens point.
    pub dist: f32,
    /// The point on the lens: the eye for a pinhole, the view-plane point for an orthographic
    /// camera.
    pub p_lens: Vec3,
    /// The camera's forward axis (-w), the lens's normal.
    pub n_lens: Vec3,
    /// Where the ray lands, in pixels of the full film (x right, y down), as `generate_ray` takes
    /// them.
    pub raster: Vec2,
    /// We of the ray from `p_lens` towards the reference point (see the module header).
    pub importance: f32,
    /// Density of the sample as a solid angle at the reference point,
    /// dist² / (|cos θ_lens| lens_area); 1 for an orthographic camera, whose direction is a delta.
    pub pdf: f32,
    /// The camera's position (pinhole) or direction (orthographic) is a delta: a light path can
    /// never reach the lens by chance (the strategy with no camera vertex has density 0).
    pub delta: bool,
}

/// Coordinates of vectors in a camera's (u, v, w), by the dual basis: `q = x u + y v + z w`.
struct DualFrame([Vec3; 3]);

impl DualFrame {
    #[inline]
    fn coords(&self, q: Vec3) -> Vec3 {
        Vec3::new(q.dot(self.0[0]), q.dot(self.0[1]), q.dot(self.0[2]))
    }
}

impl Camera {
    /// Importance We of a ray leaving the camera (origin on the lens, unit direction), and the
    /// raster point it goes through; None outside the full film or behind the camera.
    ///
    /// Perspective: 1 / (A lens_area cos⁴θ) with the constants of the module header, normalised
    /// so that ∫_lens ∫_Ω We |cos θ| dω dA = 1 over the full film. A pinhole ignores the origin
    /// (its position is a delta at the eye). Orthographic: 1 / A_beam per unit area across the
    /// rays; the direction is taken to be -w (a delta) and only its side is checked, the origin
    /// is projected along w onto the view plane.
    #[inline]
    pub fn we(&self, ray: &Ray) -> Option<(f32, Vec2)> {
        match self.projection {
            Projection::Perspective => {
                let (cos, raster) = self.perspective_raster(ray)?;
                let cos2 = cos * cos;
                Some((1.0 / (self.unit_film_area() * self.lens_area() * cos2 * cos2), raster))
            }
            Projection::Orthographic => {
                let raster = self.orthographic_raster(ray)?;
                Some((1.0 / self.beam_area(), raster))
            }
        }
    }

    /// (pdf_pos, pdf_dir) of `generate_ray` producing `ray` from uniform film positions and lens
    /// samples; (0, 0) outside the full film or behind the camera.
    ///
    /// Perspective: pdf_pos = 1 / lens_area per unit lens area (1 for a pinhole, as pbrt-v4),
    /// pdf_dir = 1 / (A cos³θ) per solid angle, so pdf_pos pdf_dir = We cos θ. Orthographic:
    /// pdf_pos = 1 / view-plane area (|u × v| W H pixel_size²) and pdf_dir = 1, the weight of the
    /// delta direction.
    #[inline]
    pub fn pdf_we(&self, ray: &Ray) -> (f32, f32) {
        match self.projection {
            Projection::Perspective => match self.perspective_raster(ray) {
                Some((cos, _)) => (1.0 / self.lens_area(), 1.0 / (self.unit_film_area() * cos * cos * cos)),
                None => (0.0, 0.0),
            },
            Projection::Orthographic => match self.orthographic_raster(ray) {
                Some(_) => (1.0 / self.view_plane_area(), 1.0),
                None => (0.0, 0.0),
            },
        }
    }

    /// Samples a point on the lens as seen from `p` (`u` in [0,1)^2 picks the lens point, as
    /// `generate_ray`'s lens sample does): None when `p` is behind the camera or projects outside
    /// the full film from that lens point.
    ///
    /// `generate_ray(raster, u)` is the ray from `p_lens` through `p`. A light-path vertex with
    /// throughput β and BSDF value f adds β f |cos| importance / pdf to the pixel at `raster`
    /// (divided by the samples per pixel, see the module header), after a shadow ray over `dist`.
    /// For a perspective camera pdf = dist² / (|cos θ_lens| lens_area) (pbrt-v4); for an
    /// orthographic one the point is projected along w, pdf = 1 and there is no 1 / dist².
    #[inline]
    pub fn sample_wi(&self, p: Vec3, u: Vec2) -> Option<CameraWi> {
        let dual = self.dual_frame();
        match self.projection {
            Projection::Perspective => {
                let lens = if self.uses_lens() { concentric_disk(u) * self.lens_radius } else { Vec2::ZERO };
                let p_lens = self.eye + lens.x * self.u + lens.y * self.v;
                let to_p = p - p_lens;
                let dist2 = to_p.length_squared();
                let dist = dist2.sqrt();
                let cos = -to_p.dot(self.w) / dist;
                if !(cos > 0.0) {
                    return None;
                }
                let raster = self.focus_raster(lens, dual.coords(to_p))?;
                let lens_area = self.lens_area();
                let cos2 = cos * cos;
                Some(CameraWi {
                    wi: -to_p / dist,
                    dist,
                    p_lens,
                    n_lens: -self.w,
                    raster,
                    importance: 1.0 / (self.unit_film_area() * lens_area * cos2 * cos2),
                    pdf: dist2 / (cos * lens_area),
                    delta: !self.uses_lens(),
                })
            }
            Projection::Orthographic => {
                // p - eye = x u + y v + z w: the ray from eye + x u + y v along -w reaches p after
                // -z (w is a unit vector).
                let q = dual.coords(p - self.eye);
                let dist = -q.z;
                if !(dist > 0.0) {
                    return None;
                }
                let raster = self.raster_in_film(Vec2::new(q.x, q.y))?;
                Some(CameraWi {
                    wi: self.w,
                    dist,
                    p_lens: self.eye + q.x * self.u + q.y * self.v,
                    n_lens: -self.w,
                    raster,
                    importance: 1.0 / self.beam_area(),
                    pdf: 1.0,
                    delta: true,
                })
            }
        }
    }

    /// The cosine of a perspective camera's ray to the axis and its raster point, None behind the
    /// camera or outside the film.
    #[inline]
    fn perspective_raster(&self, ray: &Ray) -> Option<(f32, Vec2)> {
        let cos = -ray.d.dot(self.w);
        if !(cos > 0.0) {
            return None;
        }
        let dual = self.dual_frame();
        // A pinhole's rays all start at the eye, whatever the origin says.
        let lens = if self.uses_lens() {
            let o = dual.coords(ray.o - self.eye);
            Vec2::new(o.x, o.y)
        } else {
            Vec2::ZERO
        };
        let raster = self.focus_raster(lens, dual.coords(ray.d))?;
        Some((cos, raster))
    }

    /// The raster point of the ray from lens point `lens` (view-plane units, 0 for a pinhole)
    /// along `dir` (camera coordinates, any length): inverts eq. 9-11 of `generate_ray`. Every
    /// ray of one raster point meets the others on the focal plane (the view plane for a
    /// pinhole), so the ray is followed to that depth and the point scaled back to the view plane.
    #[inline]
    fn focus_raster(&self, lens: Vec2, dir: Vec3) -> Option<Vec2> {
        let depth = -dir.z;
        if !(depth > 0.0) {
            return None;
        }
        let plane = if self.uses_lens() { self.focal_distance } else { self.d };
        let on_plane = lens + Vec2::new(dir.x, dir.y) * (plane / depth);
        self.raster_in_film(on_plane * (self.d / plane))
    }

    /// The raster point of an orthographic ray (origin projected along w), None outside the film
    /// or when the ray runs towards +w.
    #[inline]
    fn orthographic_raster(&self, ray: &Ray) -> Option<Vec2> {
        if !(ray.d.dot(self.w) < 0.0) {
            return None;
        }
        let q = self.dual_frame().coords(ray.o - self.eye);
        self.raster_in_film(Vec2::new(q.x, q.y))
    }

    /// Inverse of `view_plane_point`, None outside the full film [0, W) x [0, H).
    #[inline]
    fn raster_in_film(&self, ps: Vec2) -> Option<Vec2> {
        let (width, height) = (self.width as f32, self.height as f32);
        let raster = Vec2::new(
            ps.x / self.pixel_size + 0.5 * width - self.shift.x,
            0.5 * height - ps.y / self.pixel_size - self.shift.y,
        );
        let inside = raster.x >= 0.0 && raster.x < width && raster.y >= 0.0 && raster.y < height;
        inside.then_some(raster)
    }

    /// The dual basis of (u, v, w): dotting with it gives a vector's coordinates in that frame,
    /// exactly even when the frame is mirrored, scaled or sheared.
    #[inline]
    fn dual_frame(&self) -> DualFrame {
        let (a, b, c) = (self.v.cross(self.w), self.w.cross(self.u), self.u.cross(self.v));
        let inv_det = 1.0 / self.u.dot(a);
        DualFrame([a * inv_det, b * inv_det, c * inv_det])
    }

    /// A: the full film's area on the plane at distance 1 along a perspective camera's axis.
    #[inline]
    fn unit_film_area(&self) -> f32 {
        let s = self.pixel_size / self.d;
        self.width as f32 * self.height as f32 * s * s
    }

    /// π r² for a thin lens; 1 for a pinhole, whose position is a delta.
    #[inline]
    fn lens_area(&self) -> f32 {
        if self.uses_lens() { PI * self.lens_radius * self.lens_radius } else { 1.0 }
    }

    /// The orthographic film's area in the world: |u × v| W H pixel_size².
    #[inline]
    fn view_plane_area(&self) -> f32 {
        self.u.cross(self.v).length() * self.pixel_area()
    }

    /// The orthographic film's area across its rays: |(u × v) · w| W H pixel_size².
    #[inline]
    fn beam_area(&self) -> f32 {
        self.u.cross(self.v).dot(self.w).abs() * self.pixel_area()
    }

    /// W H pixel_size², the film's area in view-plane units.
    #[inline]
    fn pixel_area(&self) -> f32 {
        self.width as f32 * self.height as f32 * self.pixel_size * self.pixel_size
    }
}
