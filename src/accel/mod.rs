//! Acceleration structures.

mod build;
pub mod bvh;
pub mod instances;
mod packet;
mod wide;

pub use bvh::Bvh;
pub use instances::{Instance, InstanceHit, Instances};
