//! Integrators: turn a camera ray into radiance. The render loop is generic over `Integrator`,
//! so each integrator's inner calls are monomorphised and inlined.

pub mod path;
pub mod photon;
pub mod sppm;
pub mod whitted;

pub use path::PathTracer;
pub use photon::PhotonIntegrator;
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
    fn radiance(
        &self,
        scene: &Scene,
        ray: &Ray,
        sampler: &mut Sampler,
        scratch: &mut Self::Scratch,
        stats: &mut RayStats,
    ) -> Layers;
}

/// Everything that configures an integrator, from the scene file and the command line.
#[derive(Clone, Debug, PartialEq)]
pub struct IntegratorConfig {
    pub kind: IntegratorKind,
    /// Depth limit: reflection/refraction recursion (Whitted, photon) or path length (path).
    pub max_depth: u32,
    /// Shadow rays per area light at each shading point (Whitted and photon mapping).
    pub light_samples: u32,
    /// Photon-mapping settings given in the scene or on the command line (`None`: default).
    pub photon: PhotonOptions,
}

/// Photon-mapping settings as given; defaults that depend on the scene are filled in by
/// `PhotonOptions::resolve`.
#[derive(Clone, Debug, Default, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhotonOptions {
    pub photons: Option<u64>,
    pub caustic_photons: Option<u64>,
    pub gather: Option<u32>,
    pub gather_k: Option<usize>,
    pub caustic_k: Option<usize>,
    pub max_radius: Option<f32>,
    pub caustic_radius: Option<f32>,
    /// SPPM: photons per iteration (default: one per pixel).
    pub photons_per_iter: Option<u64>,
    /// SPPM: starting search radius (default: from the pixel footprint and the scene's size).
    pub initial_radius: Option<f32>,
}

impl PhotonOptions {
    /// `self` with every value `other` gives replaced.
    pub fn overridden_by(&self, other: &PhotonOptions) -> PhotonOptions {
        PhotonOptions {
            photons: other.photons.or(self.photons),
            caustic_photons: other.caustic_photons.or(self.caustic_photons),
            gather: other.gather.or(self.gather),
            gather_k: other.gather_k.or(self.gather_k),
            caustic_k: other.caustic_k.or(self.caustic_k),
            max_radius: other.max_radius.or(self.max_radius),
            caustic_radius: other.caustic_radius.or(self.caustic_radius),
            photons_per_iter: other.photons_per_iter.or(self.photons_per_iter),
            initial_radius: other.initial_radius.or(self.initial_radius),
        }
    }

    /// Full settings for `scene`: radii default to fractions of the scene's size (so any scene
    /// scale works), counts to values that render the bundled Cornell boxes cleanly.
    pub fn resolve(&self, scene: &Scene, c: &IntegratorConfig, seed: u64) -> photon::PhotonConfig {
        let b = scene.bounds();
        let diag = if b.is_empty() || !b.diagonal().is_finite() { 1.0 } else { b.diagonal() };
        let caustic_photons = self.caustic_photons.unwrap_or(200_000);
        photon::PhotonConfig {
            photons: self.photons.unwrap_or(500_000),
            caustic_photons,
            caustic_cap: caustic_photons.saturating_mul(200).max(1_000_000),
            gather_rays: self.gather.unwrap_or(16),
            gather_k: self.gather_k.unwrap_or(64).max(1),
            caustic_k: self.caustic_k.unwrap_or(64).max(1),
            max_radius: self.max_radius.unwrap_or(0.05 * diag),
            caustic_radius: self.caustic_radius.unwrap_or(0.02 * diag),
            cone_k: 1.1,
            light_samples: c.light_samples,
            max_depth: c.max_depth,
            seed,
        }
    }
}

impl PhotonOptions {
    /// SPPM settings for an image of `pixels` pixels.
    pub fn sppm(&self, c: &IntegratorConfig, pixels: u64) -> sppm::SppmConfig {
        sppm::SppmConfig {
            photons_per_iter: self.photons_per_iter.unwrap_or(pixels).max(1),
            initial_radius: self.initial_radius,
            alpha: 2.0 / 3.0,
            max_depth: c.max_depth,
        }
    }
}

impl Default for IntegratorConfig {
    fn default() -> Self {
        IntegratorConfig {
            kind: IntegratorKind::Whitted,
            max_depth: 5,
            light_samples: 16,
            photon: PhotonOptions::default(),
        }
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
    /// Photon mapping: global and caustic maps, final gathering (Jensen 2001).
    Photon,
    /// Stochastic progressive photon mapping (Hachisuka and Jensen 2009).
    Sppm,
}

impl std::str::FromStr for IntegratorKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "whitted" => Ok(IntegratorKind::Whitted),
            "path" => Ok(IntegratorKind::Path),
            "photon" => Ok(IntegratorKind::Photon),
            "sppm" => Ok(IntegratorKind::Sppm),
            _ => Err(format!("unknown integrator `{s}` (expected whitted, path, photon or sppm)")),
        }
    }
}
