//! Acceleration structures.

pub mod bvh;
pub mod instances;

pub use bvh::Bvh;
pub use instances::{Instance, InstanceHit, Instances};
