//! Integrators: turn a camera ray into radiance. The render loop is generic over `Integrator`,
//! so each integrator's inner calls are monomorphised and inlined.

pub mod whitted;

pub use whitted::Whitted;

use crate::geometry::Ray;
use crate::math::Color;
use crate::sampling::Sampler;
use crate::scene::Scene;

/// Rays traced, counted per tile and summed, so counting costs no atomics per ray.
#[derive(Clone, Copy, Debug, Default)]
pub struct RayStats {
    /// Camera and secondary rays.
    pub rays: u64,
    /// Shadow rays (each transparent surface crossed counts as one more).
    pub shadow_rays: u64,
}

impl RayStats {
    pub fn add(&mut self, o: &RayStats) {
        self.rays += o.rays;
        self.shadow_rays += o.shadow_rays;
    }

    pub fn total(&self) -> u64 {
        self.rays + self.shadow_rays
    }
}

pub trait Integrator: Sync {
    /// Radiance arriving along `ray` (towards its origin). Must not allocate or lock.
    fn radiance(&self, scene: &Scene, ray: &Ray, sampler: &mut Sampler, stats: &mut RayStats) -> Color;
}

/// Everything that configures an integrator, from the scene file and the command line.
#[derive(Clone, Debug, PartialEq)]
pub struct IntegratorConfig {
    pub kind: IntegratorKind,
    /// Depth limit: reflection/refraction recursion (Whitted, photon) or path length (path).
    pub max_depth: u32,
    /// Shadow rays per area light at each shading point (Whitted and photon mapping).
    pub light_samples: u32,
}

impl Default for IntegratorConfig {
    fn default() -> Self {
        IntegratorConfig { kind: IntegratorKind::Whitted, max_depth: 5, light_samples: 16 }
    }
}

/// Which integrator renders the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum IntegratorKind {
    /// Classic Whitted ray tracing with the seed report's Phong model.
    #[default]
    Whitted,
}

impl std::str::FromStr for IntegratorKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "whitted" => Ok(IntegratorKind::Whitted),
            _ => Err(format!("unknown integrator `{s}` (expected `whitted`)")),
        }
    }
}
