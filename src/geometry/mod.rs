//! Rays, bounding boxes, affine transforms and the surface hit record.

mod aabb;
mod hit;
mod ray;
mod transform;

pub use aabb::Aabb;
pub use hit::{Hit, NO_LIGHT, SurfaceParam};
pub use ray::{NO_MEDIUM, Ray, RayOrigin};
pub use transform::Transform;
