//! Cameras: the seed report's pinhole and thin lens (eq. 9-11; Suffern ch. 9-10) and Mitsuba 3's
//! orthographic sensor, with Mitsuba's principal-point offset.
//!
//! The camera looks down -w with u to the right and v up. A raster position (x right, y down, in
//! pixels of the full film) maps to (p_sx, p_sy) on the view plane. A perspective camera's view
//! plane sits at distance `d` from the eye: with a pinhole the ray runs from the eye through that
//! point; with a lens of radius > 0 the point maps to p = p_s f / d on the focal plane at distance
//! f and the ray runs from a point l on the lens disk towards p, so every lens sample of one pixel
//! sample meets at p. An orthographic camera's rays all run along -w from the view-plane point
//! itself; its u and v may be longer than 1 (a Mitsuba `to_world` with a scale sets the extent).
//!
//! `desc` holds the camera as a scene file describes it and its build for an image size;
//! `importance` the camera's importance for light tracing and bidirectional methods.

mod desc;
mod importance;
#[cfg(test)]
mod tests;

pub use desc::{CameraDesc, FieldOfView, FovAxis, Placement};
pub use importance::CameraWi;

use crate::geometry::Ray;
use crate::math::{Vec2, Vec3};
use crate::sampling::warp::concentric_disk;

/// How rays leave the camera.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Projection {
    /// From the eye (or a lens point) through the view plane.
    #[default]
    Perspective,
    /// Parallel rays along -w, one from each view-plane point.
    Orthographic,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub projection: Projection,
    pub eye: Vec3,
    /// Image right and up, per unit of the view plane (unit vectors, except for an orthographic
    /// camera whose frame is scaled).
    pub u: Vec3,
    pub v: Vec3,
    /// Opposite the viewing direction (unit length).
    pub w: Vec3,
    /// Distance from the eye to the view plane (perspective).
    pub d: f32,
    /// Size of one pixel on the view plane.
    pub pixel_size: f32,
    /// The full film, in pixels (a crop renders a window of it).
    pub width: u32,
    pub height: u32,
    /// Radius of the lens; 0 is a pinhole.
    pub lens_radius: f32,
    /// Distance from the lens to the plane in focus.
    pub focal_distance: f32,
    /// Added to every raster position, in pixels: Mitsuba's principal-point offset times the film
    /// size (positive x moves the view right, positive y down).
    pub shift: Vec2,
}

/// How the field of view is given to [`Camera::new`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ViewPlane {
    /// Vertical field of view in degrees.
    Fov(f32),
    /// View-plane distance in pixel units (Suffern's d, with a pixel size of 1).
    Distance(f32),
}

impl Camera {
    /// A perspective camera at `eye` looking at `look_at`. The caller guarantees
    /// `eye != look_at`, `up` not parallel to the view direction and a valid view plane (the
    /// scene loader checks these).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        eye: Vec3,
        look_at: Vec3,
        up: Vec3,
        view: ViewPlane,
        width: u32,
        height: u32,
        lens_radius: f32,
        focal_distance: f32,
    ) -> Self {
        let w = (eye - look_at).normalize();
        let u = up.cross(w).normalize();
        let v = w.cross(u);
        let (d, pixel_size) = match view {
            ViewPlane::Fov(deg) => {
                let d = 1.0;
                (d, 2.0 * d * (deg.to_radians() * 0.5).tan() / height as f32)
            }
            ViewPlane::Distance(d) => (d, 1.0),
        };
        Camera {
            projection: Projection::Perspective,
            eye,
            u,
            v,
            w,
            d,
            pixel_size,
            width,
            height,
            lens_radius,
            focal_distance,
            shift: Vec2::ZERO,
        }
    }

    /// Point on the view plane (p_sx, p_sy) for a raster position (x right, y down, in pixels).
    #[inline]
    pub fn view_plane_point(&self, raster: Vec2) -> Vec2 {
        let raster = raster + self.shift;
        Vec2::new(
            (raster.x - 0.5 * self.width as f32) * self.pixel_size,
            (0.5 * self.height as f32 - raster.y) * self.pixel_size,
        )
    }

    /// Whether `generate_ray` reads its lens sample (a thin lens of non-zero radius).
    #[inline]
    pub fn uses_lens(&self) -> bool {
        self.projection != Projection::Orthographic && self.lens_radius > 0.0
    }

    /// The ray for raster position `raster` and lens sample `lens` in [0,1)^2.
    /// With a zero lens radius this is exactly the pinhole ray, whatever `lens` is.
    #[inline]
    pub fn generate_ray(&self, raster: Vec2, lens: Vec2) -> Ray {
        let ps = self.view_plane_point(raster);
        if self.projection == Projection::Orthographic {
            return Ray::new(self.eye + ps.x * self.u + ps.y * self.v, -self.w);
        }
        if self.lens_radius <= 0.0 {
            let dir = ps.x * self.u + ps.y * self.v - self.d * self.w;
            return Ray::new(self.eye, dir.normalize());
        }
        // Seed eq. 9-10: the point on the focal plane.
        let p = ps * (self.focal_distance / self.d);
        let l = concentric_disk(lens) * self.lens_radius;
        // Seed eq. 11.
        let dir = (p.x - l.x) * self.u + (p.y - l.y) * self.v - self.focal_distance * self.w;
        Ray::new(self.eye + l.x * self.u + l.y * self.v, dir.normalize())
    }

    /// The width of one pixel's footprint on a surface at distance `dist` facing the camera.
    pub fn footprint(&self, dist: f32) -> f32 {
        match self.projection {
            Projection::Perspective => dist * self.pixel_size / self.d,
            Projection::Orthographic => self.pixel_size * self.u.length().max(self.v.length()),
        }
    }
}
