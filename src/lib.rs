//! caustic: a CPU ray tracer for light that bends and bounces.
//!
//! See `ARCHITECTURE.md` for the map of modules and what each may depend on.

// `!(x > 0.0)` is used on purpose: unlike `x <= 0.0` it is also true for NaN, which is exactly
// what input validation and degenerate-geometry checks must reject.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod accel;
pub mod app;
pub mod bench;
pub mod camera;
pub mod cli;
pub mod display;
pub mod farm;
pub mod film;
pub mod geometry;
pub mod integrator;
pub mod light;
pub mod material;
pub mod math;
pub mod medium;
pub mod options;
pub mod photon;
pub mod progress;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod shape;
pub mod spectrum;
pub mod texture;
pub mod volume;
