//! Participating media: fog, smoke, murky water (Mitsuba 3's media). A medium fills the space
//! inside or outside shapes; a ray carries the index of the medium it travels through
//! (`Ray::medium`, `NO_MEDIUM` for vacuum), and crossing a shape that has a
//! [`MediumInterface`] (a `null` boundary or glass) changes it. Media are a closed set, as
//! shapes and lights are: an enum whose methods forward to each kind's file.

pub mod homogeneous;
pub mod phase;

pub use homogeneous::{Homogeneous, MediumSample};
pub use phase::{Phase, PhaseSample};

use crate::geometry::NO_MEDIUM;
use crate::math::{Color, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Medium {
    Homogeneous(Homogeneous),
}

impl Medium {
    #[inline]
    pub fn phase(&self) -> &Phase {
        match self {
            Medium::Homogeneous(m) => &m.phase,
        }
    }

    /// The transmittance over distance `t` along a ray.
    #[inline]
    pub fn transmittance(&self, t: f32) -> Color {
        match self {
            Medium::Homogeneous(m) => m.transmittance(t),
        }
    }

    /// Free-flight sampling along a segment of length `t_max` for light carried with
    /// throughput `beta` (see `Homogeneous::sample_distance`).
    #[inline]
    pub fn sample_distance(&self, t_max: f32, beta: Color, u_channel: f32, u: f32) -> MediumSample {
        match self {
            Medium::Homogeneous(m) => m.sample_distance(t_max, beta, u_channel, u),
        }
    }
}

/// The media on the two sides of a surface: `inside` (against the geometric normal) and
/// `outside` (where the normal points), each an index into the scene's media or `NO_MEDIUM`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct MediumInterface {
    pub inside: u32,
    pub outside: u32,
}

impl MediumInterface {
    pub const NONE: MediumInterface = MediumInterface { inside: NO_MEDIUM, outside: NO_MEDIUM };

    /// The medium a ray leaving the surface in direction `d` enters (`ng` the geometric normal).
    #[inline]
    pub fn toward(&self, d: Vec3, ng: Vec3) -> u32 {
        if d.dot(ng) > 0.0 { self.outside } else { self.inside }
    }
}
