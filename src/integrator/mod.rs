//! Integrators: turn a camera ray into radiance. The render loop is generic over `Integrator`,
//! so each integrator's inner calls are monomorphised and inlined.

pub mod path;
pub mod whitted;

pub use path::PathTracer;
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

/// The light arriving along a camera ray, split by where it came from. The parts sum to the
/// pixel's value:
/// - `DIRECT`: emission seen directly and light sampled at the first non-specular surface;
/// - `SPECULAR`: everything seen through mirrors and glass (camera paths starting with S+);
/// - `CAUSTIC`: light reaching the first non-specular surface through mirrors and glass (L S+ D);
/// - `INDIRECT`: light reaching it after at least one more non-specular bounce.
pub type Layers = [Color; 4];
pub const DIRECT: usize = 0;
pub const SPECULAR: usize = 1;
pub const CAUSTIC: usize = 2;
pub const INDIRECT: usize = 3;
pub const LAYER_NAMES: [&str; 4] = ["direct", "specular", "caustic", "indirect"];

pub trait Integrator: Sync {
    /// Reusable per-worker buffers (created once per tile, so the hot path allocates nothing).
    type Scratch: Default;

    /// Radiance arriving along `ray` (towards its origin), by layer. Must not allocate or lock.
    fn radiance(&self, scene: &Scene, ray: &Ray, sampler: &mut Sampler, scratch: &mut Self::Scratch, stats: &mut RayStats) -> Layers;
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
    /// Unidirectional path tracing with next-event estimation and MIS: the reference.
    Path,
}

impl std::str::FromStr for IntegratorKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "whitted" => Ok(IntegratorKind::Whitted),
            "path" => Ok(IntegratorKind::Path),
            _ => Err(format!("unknown integrator `{s}` (expected whitted, path or photon)")),
        }
    }
}
