//! The camera as a scene file describes it, resolved against the final image size (which the
//! command line may change) by [`CameraDesc::build`].

use super::{Camera, Projection, ViewPlane};
use crate::math::{Vec2, Vec3};

/// Which extent of the image a field-of-view angle (or an orthographic size) spans (Mitsuba's
/// `fov_axis`).
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

/// What the camera sees, as a scene describes it; angles are resolved against the final image
/// size, so a horizontal angle stays horizontal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FieldOfView {
    Angle {
        degrees: f64,
        axis: FovAxis,
    },
    /// Suffern's view-plane distance in pixel units.
    ViewDistance(f32),
    /// An orthographic camera whose view is `size` wide along `axis` (`X`: the image width, `Y`:
    /// its height), in units of the placement's axes (scene units for a `LookAt`).
    Orthographic {
        size: f32,
        axis: FovAxis,
    },
}

/// Where the camera is and which way it looks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Placement {
    /// At `eye`, looking at `target`, with `up` giving the image's vertical.
    LookAt { eye: Vec3, target: Vec3, up: Vec3 },
    /// A frame: looking along `z` with `y` up; the image's x axis runs along -`x` (Mitsuba's
    /// sensor convention, which also keeps a mirroring frame mirrored). Orthonormal for a
    /// perspective camera; an orthographic camera keeps the lengths of `x` and `y` (Mitsuba's
    /// scaled `to_world`), which set its extent.
    Frame { origin: Vec3, x: Vec3, y: Vec3, z: Vec3 },
}

/// A camera as a scene file describes it; `build` makes the camera for an image size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraDesc {
    pub placement: Placement,
    pub fov: FieldOfView,
    pub lens_radius: f32,
    pub focal_distance: f32,
    /// Mitsuba's `principal_point_offset_x/y`: a shift of the image in fractions of the film's
    /// width and height (positive x shows more of the right, positive y more of the bottom).
    pub principal_point: Vec2,
}

impl CameraDesc {
    /// The camera for a `width` x `height` film.
    pub fn build(&self, width: u32, height: u32) -> Camera {
        let mut camera = match self.fov {
            FieldOfView::Orthographic { size, axis } => self.orthographic(size, axis, width, height),
            FieldOfView::ViewDistance(d) => self.perspective(ViewPlane::Distance(d), None, width, height),
            FieldOfView::Angle { degrees, axis } => {
                let (view, horizontal_tan) = angle_view(degrees, axis, width, height);
                self.perspective(view, horizontal_tan, width, height)
            }
        };
        camera.shift = self.principal_point * Vec2::new(width as f32, height as f32);
        camera
    }

    /// A perspective camera; `horizontal_tan`, when given, fixes the pixel size from the tangent
    /// of half the horizontal angle.
    fn perspective(&self, view: ViewPlane, horizontal_tan: Option<f64>, width: u32, height: u32) -> Camera {
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

    /// Mitsuba's orthographic sensor: the view plane is the camera's own plane, `size` wide
    /// along `axis` in units of the frame's axes, with square pixels of that frame.
    fn orthographic(&self, size: f32, axis: FovAxis, width: u32, height: u32) -> Camera {
        let (eye, u, v, w) = match self.placement {
            Placement::LookAt { eye, target, up } => {
                let w = (eye - target).normalize();
                let u = up.cross(w).normalize();
                (eye, u, w.cross(u), w)
            }
            Placement::Frame { origin, x, y, z } => (origin, -x, y, -z.normalize()),
        };
        let across = if axis == FovAxis::Y { height } else { width };
        Camera {
            projection: Projection::Orthographic,
            eye,
            u,
            v,
            w,
            d: 1.0,
            pixel_size: size / across as f32,
            width,
            height,
            lens_radius: 0.0,
            focal_distance: self.focal_distance,
            shift: Vec2::ZERO,
        }
    }
}

/// The view plane of a field-of-view angle along `axis`, and the tangent of half the horizontal
/// angle when the angle is not vertical.
fn angle_view(degrees: f64, axis: FovAxis, width: u32, height: u32) -> (ViewPlane, Option<f64>) {
    let aspect = width as f64 / height as f64;
    let axis = match axis {
        FovAxis::Smaller if aspect > 1.0 => FovAxis::Y,
        FovAxis::Smaller => FovAxis::X,
        FovAxis::Larger if aspect > 1.0 => FovAxis::X,
        FovAxis::Larger => FovAxis::Y,
        a => a,
    };
    // An angle along y is our own convention; any other is turned into the tangent of half the
    // horizontal angle, which fixes the pixel size.
    let vertical = axis == FovAxis::Y || (axis == FovAxis::X && width == height);
    if vertical {
        return (ViewPlane::Fov(degrees as f32), None);
    }
    let half = (degrees.to_radians() * 0.5).tan();
    let tan_x = match axis {
        FovAxis::X => half,
        _ => half / (1.0 + 1.0 / (aspect * aspect)).sqrt(),
    };
    let fov_y = (2.0 * (tan_x / aspect).atan()).to_degrees() as f32;
    (ViewPlane::Fov(fov_y), Some(tan_x))
}
