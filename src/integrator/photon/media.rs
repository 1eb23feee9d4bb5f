//! Photon mapping in participating media (Jensen and Christensen 1998, "Efficient simulation of
//! light transport in scenes with participating media using photon maps"): the global pass also
//! stores the photons scattered in media (`trace::Store::Volume`) in a third kd-tree, the volume
//! photon map, and the light a medium scatters towards the camera at a point x is
//! - single scattering, light reaching x from the lights through media and `null` boundaries
//!   only, by light samples (every light in turn, as at surfaces: `EveryLight`) with the
//!   transmittance along the shadow ray;
//! - everything else from the volume map: light that scattered before (in the medium or at a
//!   surface) and the volumetric caustic (light focused into the medium by glass and mirrors).
//!
//! A volume photon of depth 0 (no scattering event before it: it came from the light through
//! `null` boundaries only) is exactly what a light sample at its position counts, so those are
//! left out at camera vertices and every other photon is counted; final-gather rays that
//! scatter in a medium read all of them (the light samples are the camera vertex's, not theirs).
//!
//! Volume radiance estimate (Jensen and Christensen eq. 11): L = sum over the k nearest volume
//! photons within a maximum radius of p(wo, wi_p) Phi_p / (4/3 pi r^3), r the k-th photon's
//! distance, whose photon is then left out (given r_k, the k - 1 inside are uniform in the ball:
//! k - 1 over its volume estimates a Poisson density without bias, k over it by k / (k - 1)), or
//! the maximum radius where fewer than k lie within it. The photons' flux holds the scattering
//! coefficient (they are stored where they scatter), so the estimate is sigma_s times the
//! in-scattered radiance, what the camera path's free-flight weight T / pdf multiplies. The
//! surfaces near x cut the ball (`SphereBounds`, as in SPPM): photons beyond their tangent
//! planes are left out and the estimate divides by the volume of what is left, so the fog near
//! its boundary is not darkened by the part of the ball outside it.
//!
//! Defaults: k = `DEFAULT_VOLUME_K`; the maximum radius is `RADIUS_FACTOR` times the median
//! k-nearest radius measured at `RADIUS_PROBES` photons spread through the map (in the scale of
//! the photon spacing wherever the medium is, however far it extends: an unbounded fog filling a
//! room has no extent of its own), so only photons much sparser than the typical ones (the
//! fringe of a medium, a beam's surroundings) are gathered within the fixed sphere.
//!
//! Camera paths march through homogeneous media (`CameraWalk::with_march`: `MARCH_STEPS`
//! stratified points per segment, each with its light samples and volume estimate) rather than
//! take one free-flight sample per segment as SPPM and the volumetric path tracer do. Measured
//! on tests/data/media/cube_area.xml at 64 x 64 (500,000 photons, seed 1; the noise is the RMSE
//! against the same photon maps at 1024 samples of free flights, its own noise taken out; CPU
//! time of the render phase):
//!
//! | camera media sampling     | spp | CPU s | noise  | noise x sqrt(s) |
//! |---------------------------|-----|-------|--------|-----------------|
//! | one free flight           |  64 | 1.07  | 0.0062 | 0.0064          |
//! | one free flight           | 256 | 5.23  | 0.0023 | 0.0053          |
//! | 4 steps                   |  16 | 1.47  | 0.0039 | 0.0047          |
//! | 8 steps                   |  16 | 2.92  | 0.0020 | 0.0034          |
//! | 8 steps                   |  32 | 5.13  | 0.0014 | 0.0031          |
//! | 16 steps                  |  16 | 5.07  | 0.0012 | 0.0027          |
//! | 16 steps by optical depth |  16 | 4.54  | 0.0009 | 0.0019          |
//!
//! (Steps of equal length, but the last: strata of equal probability under free-flight sampling,
//! as built.) At equal time, 16 steps have half the noise of free flights or less (load about 5
//! on two cores: CPU time, not wall time): a free flight in a thin medium
//! mostly passes through without a vertex, and one that stops leaves the surface behind it
//! unseen, while every marched segment estimates both. Heterogeneous media and segments into the
//! sky take free flights (`CameraWalk`'s notes), and so do final-gather rays, which are many.

use super::PhotonIntegrator;
use crate::geometry::{Hit, RayOrigin};
use crate::integrator::camera_walk::MediumVertex;
use crate::integrator::lighting::{bsdf_scatter, light_sample_at, transmittance_through_media};
use crate::integrator::sphere_bounds::SphereBounds;
use crate::material::bsdf::Bsdf;
use crate::math::{Color, Vec2, Vec3};
use crate::medium::Phase;
use crate::photon::trace::{self, PhotonHit};
use crate::photon::{Gathered, Photon, PhotonMap};
use crate::render::RayStats;
use crate::sampling::Rng32;
use crate::scene::Scene;
use crate::spectrum::Wavelengths;

/// Medium vertices per camera segment through a homogeneous medium (see the notes).
pub const MARCH_STEPS: u32 = 16;

/// Volume photons per estimate by default (`--volume-k`).
pub const DEFAULT_VOLUME_K: usize = 64;
/// The default maximum radius is this many times the typical k-nearest radius.
const RADIUS_FACTOR: f32 = 2.0;
/// Photons at which the typical k-nearest radius is measured.
const RADIUS_PROBES: usize = 256;

/// Moves the volume photons out of `hits` (which keeps the surface ones) into photon records:
/// flags 0 and the depth (a volume photon's depth 0 marks it as single scattering).
pub(super) fn split_volume(hits: &mut crate::photon::PhotonHits) -> Vec<Photon> {
    let mut volume = Vec::new();
    hits.retain(|h| {
        let v = h.flags & trace::VOLUME != 0;
        if v {
            let packed = PhotonHit { flags: 0, ..*h };
            volume.push(Photon::new(h.p, h.dir, h.flux.get(), trace::packed_flags(&packed)));
        }
        !v
    });
    volume
}

/// The default maximum radius of a volume estimate over `map` with `k` photons (see the
/// module's notes); 0 for an empty map.
pub(super) fn default_volume_radius(map: &PhotonMap, k: usize) -> f32 {
    if map.is_empty() {
        return 0.0;
    }
    let n = map.len();
    let stride = n.div_ceil(RADIUS_PROBES).max(1);
    let mut g = Gathered::new(k);
    let mut radii: Vec<f32> = (0..n)
        .step_by(stride)
        .map(|i| map.gather(map.photon(i as u32).position(), k, f32::INFINITY, &mut g).1.sqrt())
        .collect();
    radii.sort_by(f32::total_cmp);
    RADIUS_FACTOR * radii[radii.len() / 2]
}

impl PhotonIntegrator {
    /// sigma_s times the radiance scattered towards `wo` at `p` in a medium of phase function
    /// `phase`, from the volume photons of at most `depth` scattering events, depth 0 (single
    /// scattering) only `with_single`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn volume_estimate(
        &self,
        scene: &Scene,
        phase: &Phase,
        p: Vec3,
        wo: Vec3,
        depth: u32,
        with_single: bool,
        u: Vec2,
        scratch: &mut Gathered,
    ) -> Color {
        let (k, max_r) = (self.config.volume_k, self.config.volume_radius);
        if self.volume.is_empty() || !(max_r > 0.0) {
            return Color::ZERO;
        }
        let (found, r2) = self.volume.gather(p, k, max_r * max_r, scratch);
        if found.is_empty() {
            return Color::ZERO;
        }
        // Filled to k: the k-th photon sets the radius and is left out (see the module's notes).
        let (r2, skip) = if found.len() < k { (max_r * max_r, None) } else { (r2, Some(r2)) };
        // The surfaces near p cut the sphere (`SphereBounds`): without, the fog within a radius
        // of its boundary reads dark (-2% to -3% on a fog cube at a million photons).
        let bounds = SphereBounds::probe(scene, p, r2.sqrt(), u);
        let mut skip = skip;
        let mut sum = Color::ZERO;
        for &(d2, i) in found {
            if Some(d2) == skip {
                skip = None;
                continue;
            }
            let ph = self.volume.photon(i);
            let d = trace::packed_depth(ph.flags());
            if d > depth || (d == 0 && !with_single) || !bounds.keeps(ph.position()) {
                continue;
            }
            sum += ph.power() * phase.p(wo, -ph.direction());
        }
        // In spectral mode the photons hold CIE XYZ; the sum converts as any of them.
        self.colour(sum / bounds.volume)
    }

    /// The light scattered towards the camera at medium vertex `v` (see the module's notes),
    /// without the walk's throughput, in two parts: single scattering from the light samples,
    /// already times the vertex's weight (spectral in spectral mode, `wl`), and the volume
    /// photons' estimate, which `v.tr_over_pdf` is still to multiply (RGB in either mode: the
    /// photons are stored as RGB).
    pub(super) fn medium_radiance(
        &self,
        scene: &Scene,
        v: &MediumVertex,
        wl: Option<&Wavelengths>,
        rng: &mut Rng32,
        scratch: &mut Gathered,
        stats: &mut RayStats,
    ) -> (Color, Color) {
        let phase = *scene.media[v.medium as usize].phase();
        let from = RayOrigin { p: v.p, p_error: Vec3::ZERO, ng: Vec3::ZERO };
        let single = self.lights.sum(scene, rng, stats, |light, p_pick, u, rng, stats| {
            light_sample_at(
                scene,
                light,
                p_pick,
                v.p,
                u,
                false,
                wl,
                |wi, _| (Color::splat(phase.p(v.wo, wi)), 1.0, 0.0),
                |wi, dist| (1.0, transmittance_through_media(scene, from, wi, dist, v.medium, 0.0, rng, wl, stats)),
            )
        });
        let depth = trace::photon_depth_limit(self.config.max_depth, v.bounce).unwrap_or(0);
        let multiple = self.volume_estimate(scene, &phase, v.p, v.wo, depth, false, rng.uniform2(), scratch);
        (v.weight * single, multiple)
    }

    /// Direct light at a surface hit reached in medium `medium`: every light in turn, each light
    /// sample's shadow ray through media and `null` boundaries with their transmittance.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn direct_through_media(
        &self,
        scene: &Scene,
        hit: &Hit,
        bsdf: &Bsdf,
        wo: Vec3,
        medium: u32,
        rng: &mut Rng32,
        wl: Option<&Wavelengths>,
        stats: &mut RayStats,
    ) -> Color {
        let bias = self.config.ray_bias;
        self.lights.sum(scene, rng, stats, |light, p_pick, u, rng, stats| {
            light_sample_at(
                scene,
                light,
                p_pick,
                hit.p,
                u,
                false,
                wl,
                |wi, mis| bsdf_scatter(bsdf, wo, wi, mis),
                |wi, dist| {
                    let m = scene.medium_after(hit, wi, medium);
                    (1.0, transmittance_through_media(scene, hit.origin(), wi, dist, m, bias, rng, wl, stats))
                },
            )
        })
    }
}
