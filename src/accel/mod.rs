//! Acceleration structures.

mod build;
pub mod bvh;
pub mod instances;
mod wide;

pub use bvh::Bvh;
pub use instances::{Instance, InstanceHit, Instances};
