//! Photon maps (Jensen 2001): photon records, the kd-tree they are stored in, and photon tracing.

pub mod grid;
pub mod hits;
pub mod map;
pub mod trace;

pub use hits::{HitIds, PhotonHits};
pub use map::{Gathered, Photon, PhotonMap};
