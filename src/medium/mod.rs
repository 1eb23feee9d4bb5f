//! Participating media: fog, smoke, murky water (Mitsuba 3's media). A medium fills the space
//! inside or outside shapes; a ray carries the index of the medium it travels through
//! (`Ray::medium`, `NO_MEDIUM` for vacuum), and crossing a shape that has a
//! [`MediumInterface`] (a `null` boundary or glass) changes it. Media are a closed set, as
//! shapes and lights are: an enum whose methods forward to each kind's file.

pub mod heterogeneous;
pub mod homogeneous;
pub mod phase;

pub use heterogeneous::{Heterogeneous, Volume, VolumeData};
pub use homogeneous::{Homogeneous, MediumSample};
pub use phase::{Phase, PhaseSample};

use crate::geometry::{NO_MEDIUM, Ray};
use crate::math::{Color, Vec3};
use crate::sampling::Rng32;
use crate::spectrum::Wavelengths;

/// A medium. Not `Copy`: a heterogeneous one shares its grids (`Arc`), and media are only ever
/// borrowed from the scene.
///
/// Every query takes the ray (a unit direction for the homogeneous kind, whose distances are
/// t itself) and a random stream for the kinds whose estimates draw a varying count of numbers
/// (heterogeneous: one per tentative collision). The homogeneous kind draws nothing from it, so
/// its images are the same bit for bit as before the stream existed.
// A heterogeneous medium is a few hundred bytes (two placed volumes); a scene holds a handful of
// media and rays borrow them, so the size costs nothing per ray.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq)]
pub enum Medium {
    Homogeneous(Homogeneous),
    Heterogeneous(Heterogeneous),
}

impl Medium {
    #[inline]
    pub fn phase(&self) -> &Phase {
        match self {
            Medium::Homogeneous(m) => &m.phase,
            Medium::Heterogeneous(m) => &m.phase,
        }
    }

    /// The transmittance along `ray` from t = 0 to `t_max` (an unbiased estimate where the
    /// medium varies), at the path's wavelengths in spectral mode (`wl`).
    #[inline]
    pub fn transmittance(&self, ray: &Ray, t_max: f32, rng: &mut Rng32, wl: Option<&Wavelengths>) -> Color {
        match self {
            Medium::Homogeneous(m) => m.at(wl).transmittance(t_max),
            Medium::Heterogeneous(m) => m.transmittance(ray, t_max, rng, wl),
        }
    }

    /// Free-flight sampling along `ray` up to `t_max` for light carried with throughput `beta`
    /// (see `Homogeneous::sample_distance` for the weights): `u_channel` and `u` are the
    /// sampler's numbers, `rng` gives any further ones. In spectral mode (`wl`) the lanes of
    /// `beta` and of the weights are the path's wavelengths, and the medium's coefficients are
    /// lifted to them.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub fn sample_distance(
        &self,
        ray: &Ray,
        t_max: f32,
        beta: Color,
        u_channel: f32,
        u: f32,
        rng: &mut Rng32,
        wl: Option<&Wavelengths>,
    ) -> MediumSample {
        match self {
            Medium::Homogeneous(m) => {
                let lanes = if wl.is_some() { crate::spectrum::LANES } else { 3 };
                m.at(wl).sample_distance(t_max, beta, u_channel, u, lanes)
            }
            Medium::Heterogeneous(m) => m.sample_distance(ray, t_max, beta, u, rng, wl),
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
