//! caustic: a CPU ray tracer for light that bends and bounces.
//!
//! See `ARCHITECTURE.md` for the map of modules and what each may depend on.

pub mod accel;
pub mod camera;
pub mod app;
pub mod bench;
pub mod film;
pub mod geometry;
pub mod integrator;
pub mod light;
pub mod material;
pub mod math;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod shape;
