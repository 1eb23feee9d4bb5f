//! Pinhole and thin-lens cameras in the seed report's formulation (eq. 9-11; Suffern ch. 9-10).
//!
//! The camera looks down -w with u to the right and v up. The view plane sits at distance `d`
//! from the eye; a pixel sample maps to (p_sx, p_sy) on it. With a lens of radius > 0, that point
//! maps to p = p_s f / d on the focal plane at distance f, and the ray runs from a point l on the
//! lens disk towards p: every lens sample of one pixel sample meets at p, so the focal plane is
//! sharp and everything else is blurred by the circle of confusion.

use crate::geometry::Ray;
use crate::math::{Vec2, Vec3};
use crate::sampling::warp::concentric_disk;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub u: Vec3,
    pub v: Vec3,
    pub w: Vec3,
    /// Distance from the eye to the view plane.
    pub d: f32,
    /// Size of one pixel on the view plane.
    pub pixel_size: f32,
    pub width: u32,
    pub height: u32,
    /// Radius of the lens; 0 is a pinhole.
    pub lens_radius: f32,
    /// Distance from the lens to the plane in focus.
    pub focal_distance: f32,
}

/// How the field of view is given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ViewPlane {
    /// Vertical field of view in degrees.
    Fov(f32),
    /// View-plane distance in pixel units (Suffern's d, with a pixel size of 1).
    Distance(f32),
}

/// Which extent of the image a field-of-view angle spans (Mitsuba's `fov_axis`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FovAxis {
    X,
    Y,
    Diagonal,
    /// The smaller of the two sides.
    Smaller,
    /// The larger of the two sides.
    Larger,
}

/// The field of view as a scene describes it; angles are resolved against the final image size
/// (which the command line may change), so a horizontal angle stays horizontal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FieldOfView {
    Angle {
        degrees: f64,
        axis: FovAxis,
    },
    /// Suffern's view-plane distance in pixel units.
    ViewDistance(f32),
}

/// Where the camera is and which way it looks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Placement {
    /// At `eye`, looking at `target`, with `up` giving the image's vertical.
    LookAt { eye: Vec3, target: Vec3, up: Vec3 },
    /// An orthonormal frame: looking along `z` with `y` up; the image's x axis runs along -`x`
    /// (Mitsuba's sensor convention, which also keeps a mirroring frame mirrored).
    Frame { origin: Vec3, x: Vec3, y: Vec3, z: Vec3 },
}

/// A camera as a scene file describes it; `build` makes the camera for an image size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraDesc {
    pub placement: Placement,
    pub fov: FieldOfView,
    pub lens_radius: f32,
    pub focal_distance: f32,
}

impl CameraDesc {
    /// The camera for a `width` x `height` image.
    pub fn build(&self, width: u32, height: u32) -> Camera {
        let aspect = width as f64 / height as f64;
        let (view, horizontal_tan) = match self.fov {
            FieldOfView::ViewDistance(d) => (ViewPlane::Distance(d), None),
            FieldOfView::Angle { degrees, axis } => {
                let axis = match axis {
                    FovAxis::Smaller if aspect > 1.0 => FovAxis::Y,
                    FovAxis::Smaller => FovAxis::X,
                    FovAxis::Larger if aspect > 1.0 => FovAxis::X,
                    FovAxis::Larger => FovAxis::Y,
                    a => a,
                };
                // An angle along y is our own convention; any other is turned into the tangent
                // of half the horizontal angle, which fixes the pixel size.
                let vertical = axis == FovAxis::Y || (axis == FovAxis::X && width == height);
                if vertical {
                    (ViewPlane::Fov(degrees as f32), None)
                } else {
                    let half = (degrees.to_radians() * 0.5).tan();
                    let tan_x = match axis {
                        FovAxis::X => half,
                        _ => half / (1.0 + 1.0 / (aspect * aspect)).sqrt(),
                    };
                    let fov_y = (2.0 * (tan_x / aspect).atan()).to_degrees() as f32;
                    (ViewPlane::Fov(fov_y), Some(tan_x))
                }
            }
        };
        let (lens, focus) = (self.lens_radius, self.focal_distance);
        let mut camera = match self.placement {
            Placement::LookAt { eye, target, up } => Camera::new(eye, target, up, view, width, height, lens, focus),
            Placement::Frame { origin, x, y, z } => {
                let mut c = Camera::new(origin, origin + z, y, view, width, height, lens, focus);
                c.u = -x.normalize();
                c
            }
        };
        if let Some(tan_x) = horizontal_tan {
            camera.pixel_size = (2.0 * tan_x / width as f64) as f32 * camera.d;
        }
        camera
    }
}

impl Camera {
    /// A camera at `eye` looking at `look_at`. The caller guarantees `eye != look_at`, `up` not
    /// parallel to the view direction and a valid view plane (the scene loader checks these).
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
        Camera { eye, u, v, w, d, pixel_size, width, height, lens_radius, focal_distance }
    }

    /// Point on the view plane (p_sx, p_sy) for a raster position (x right, y down, in pixels).
    #[inline]
    pub fn view_plane_point(&self, raster: Vec2) -> Vec2 {
        Vec2::new(
            (raster.x - 0.5 * self.width as f32) * self.pixel_size,
            (0.5 * self.height as f32 - raster.y) * self.pixel_size,
        )
    }

    /// The ray for raster position `raster` and lens sample `lens` in [0,1)^2.
    /// With a zero lens radius this is exactly the pinhole ray, whatever `lens` is.
    #[inline]
    pub fn generate_ray(&self, raster: Vec2, lens: Vec2) -> Ray {
        let ps = self.view_plane_point(raster);
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng32;

    fn cam(lens_radius: f32, f: f32) -> Camera {
        Camera::new(
            Vec3::new(0.0, 1.0, 5.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::Y,
            ViewPlane::Fov(40.0),
            320,
            240,
            lens_radius,
            f,
        )
    }

    #[test]
    fn centre_ray_looks_at_target_and_fov_matches() {
        let c = cam(0.0, 1.0);
        let r = c.generate_ray(Vec2::new(160.0, 120.0), Vec2::splat(0.5));
        assert!(r.d.abs_diff_eq(-Vec3::Z, 1e-6));
        let top = c.generate_ray(Vec2::new(160.0, 0.0), Vec2::ZERO);
        let half = top.d.dot(-Vec3::Z).acos().to_degrees();
        assert!((half - 20.0).abs() < 1e-3, "{half}");
        // Raster y grows downwards, world up is +y.
        assert!(top.d.y > 0.0);
    }

    #[test]
    fn zero_lens_radius_is_exactly_pinhole() {
        let a = cam(0.0, 3.0);
        let mut b = cam(0.0, 7.0);
        b.lens_radius = 0.0;
        let mut rng = Rng32::new(3);
        for _ in 0..1000 {
            let p = rng.uniform2() * Vec2::new(320.0, 240.0);
            assert_eq!(a.generate_ray(p, rng.uniform2()), b.generate_ray(p, Vec2::splat(0.5)));
        }
    }

    #[test]
    fn every_lens_sample_meets_at_the_focal_plane_point() {
        let f = 4.0;
        let c = cam(0.3, f);
        let mut rng = Rng32::new(8);
        for _ in 0..100 {
            let raster = rng.uniform2() * Vec2::new(320.0, 240.0);
            let ps = c.view_plane_point(raster);
            let target = c.eye + (ps.x * c.u + ps.y * c.v) * (f / c.d) - f * c.w;
            for _ in 0..16 {
                let r = c.generate_ray(raster, rng.uniform2());
                // Intersect the ray with the focal plane (distance f along -w from the lens).
                let t = f / r.d.dot(-c.w);
                let hit = r.o + r.d * t;
                assert!((hit - target).length() <= 1e-5 * target.length(), "{hit} vs {target}");
            }
        }
    }

    #[test]
    fn circle_of_confusion_matches_thin_lens() {
        // A point q on the axis at depth z is seen through lens point l at the focal-plane point
        // p = l + (q - l) f / z. Find, for each lens sample, the raster position whose camera ray
        // from l passes through q, check that it does, and measure how far the images p spread:
        // the thin-lens circle of confusion on the focal plane has radius r_lens |z - f| / z.
        let f = 5.0;
        let r_lens = 0.25;
        let c = cam(r_lens, f);
        for z in [2.0f32, 3.5, 8.0, 20.0] {
            let q = c.eye - z * c.w;
            let mut max_r = 0.0f32;
            let mut rng = Rng32::new(2);
            for _ in 0..4000 {
                let u = rng.uniform2();
                let l = concentric_disk(u) * r_lens;
                let p = l + (Vec2::ZERO - l) * (f / z);
                let ps = p * (c.d / f);
                let raster =
                    Vec2::new(ps.x / c.pixel_size + 0.5 * c.width as f32, 0.5 * c.height as f32 - ps.y / c.pixel_size);
                let ray = c.generate_ray(raster, u);
                let to_q = q - ray.o;
                let miss = (to_q - ray.d * to_q.dot(ray.d)).length();
                assert!(miss < 1e-4 * z, "camera ray misses the point by {miss}");
                max_r = max_r.max(p.length());
            }
            let expected = r_lens * (z - f).abs() / z;
            assert!((max_r - expected).abs() <= 0.02 * expected, "z={z}: {max_r} vs {expected}");
        }
    }
}
