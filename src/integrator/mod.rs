//! Integrators: each turns the scene into an image. The ray integrators (Whitted, path, photon)
//! compute radiance along one camera ray at a time and run in the shared tile loop; SPPM is a
//! multi-pass method with its own passes in the same driver. [`Integrator::new`] is the one place
//! an integrator is made from the scene's description.

pub mod bdpt;
pub mod camera_walk;
pub mod layers;
pub mod light;
pub mod lighting;
pub mod path;
pub mod photon;
pub(crate) mod sphere_bounds;
pub mod sppm;
pub mod vcm;
pub mod volpath;
pub mod whitted;

pub use bdpt::Bdpt;
pub use light::LightTracer;
pub use path::PathTracer;
pub use photon::PhotonIntegrator;
pub use sppm::Sppm;
pub use vcm::Vcm;
pub use volpath::VolPathTracer;
pub use whitted::Whitted;

use crate::film::Film;
use crate::film::splat::SplatFilm;
use crate::options::IntegratorKind;
use crate::render::{Driver, PassOutcome, RenderControl, RenderOutput, RenderSettings, RenderStats, render_rays_from};
use crate::scene::Scene;
use crate::scene::desc::IntegratorDesc;
use std::cell::RefCell;
use std::ops::Range;

/// One of caustic's integrators, ready to render.
pub enum Integrator {
    Whitted(Whitted),
    Path(PathTracer),
    VolPath(VolPathTracer),
    Photon(Box<PhotonIntegrator>),
    Sppm(Sppm),
    Light(LightTracer),
    Bdpt(Bdpt),
    Vcm(Vcm),
}

/// The render was stopped (Ctrl-C) while an integrator was being made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cancelled;

impl Integrator {
    /// What making this integrator prepared, for the summary's list of phases.
    pub fn preparation_name(&self) -> &'static str {
        match self {
            Integrator::Photon(_) => "photon maps",
            Integrator::Whitted(_)
            | Integrator::Path(_)
            | Integrator::VolPath(_)
            | Integrator::Sppm(_)
            | Integrator::Light(_)
            | Integrator::Bdpt(_)
            | Integrator::Vcm(_) => "set-up",
        }
    }

    /// Makes the integrator `desc` asks for (photon maps are traced and built here, each phase
    /// reported to `control.progress`); `Err(Cancelled)` soon after `control.cancel` is set.
    pub fn new(
        desc: &IntegratorDesc,
        scene: &Scene,
        settings: &RenderSettings,
        control: &RenderControl,
    ) -> Result<Self, Cancelled> {
        let depth = desc.depth_limit(desc.kind);
        Ok(match desc.kind {
            IntegratorKind::Whitted => Integrator::Whitted(Whitted::new(scene, desc)),
            // The path tracer knows no media: a scene with media is the volumetric one's.
            IntegratorKind::Path if !scene.has_media() => Integrator::Path(PathTracer {
                max_depth: depth,
                ray_bias: desc.ray_bias(scene),
                spectral: desc.spectral,
            }),
            IntegratorKind::Path | IntegratorKind::Volpath => Integrator::VolPath(VolPathTracer {
                max_depth: depth,
                ray_bias: desc.ray_bias(scene),
                spectral: desc.spectral,
            }),
            IntegratorKind::Photon => {
                let config = photon::PhotonConfig::new(&desc.photon, desc, scene, settings.seed);
                let pm = PhotonIntegrator::build_watched(scene, config, control.cancel, control.progress)
                    .ok_or(Cancelled)?;
                Integrator::Photon(Box::new(pm))
            }
            IntegratorKind::Light => Integrator::Light(LightTracer {
                max_depth: depth,
                ray_bias: desc.ray_bias(scene),
                spectral: desc.spectral,
            }),
            IntegratorKind::Sppm => Integrator::Sppm(Sppm::new(sppm::SppmConfig::new(desc, scene, settings.pixels()))),
            IntegratorKind::Bdpt => {
                Integrator::Bdpt(Bdpt { max_depth: depth, ray_bias: desc.ray_bias(scene), spectral: desc.spectral })
            }
            IntegratorKind::Vcm => Integrator::Vcm(Vcm::new(desc, scene, settings)),
        })
    }

    pub fn kind(&self) -> IntegratorKind {
        match self {
            Integrator::Whitted(_) => IntegratorKind::Whitted,
            Integrator::Path(_) => IntegratorKind::Path,
            Integrator::VolPath(_) => IntegratorKind::Volpath,
            Integrator::Photon(_) => IntegratorKind::Photon,
            Integrator::Sppm(_) => IntegratorKind::Sppm,
            Integrator::Light(_) => IntegratorKind::Light,
            Integrator::Bdpt(_) => IntegratorKind::Bdpt,
            Integrator::Vcm(_) => IntegratorKind::Vcm,
        }
    }

    /// Renders the image (and its layers when `settings.layers`).
    pub fn render(&self, scene: &Scene, settings: &RenderSettings, control: &RenderControl) -> RenderOutput {
        self.render_from(scene, settings, control, settings.new_film())
    }

    /// Continues a render from `film`, which holds what an earlier run of the same render (from
    /// `settings.first_sample`) finished: the remaining samples of each pixel for the ray
    /// integrators, bit for bit as if never stopped; for SPPM, the remaining iterations as an
    /// independent run combined with the earlier one by iteration count.
    pub fn render_from(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        control: &RenderControl,
        film: Film,
    ) -> RenderOutput {
        // The pixels of SPPM, the light tracer, bidirectional path tracing and VCM are not sums
        // of camera samples alone: their first-hit AOVs are added afterwards, for the sample
        // indices the render took.
        let before: Vec<Vec<u32>> = film.tiles.iter().map(|t| t.count.clone()).collect();
        let mut out = match self {
            Integrator::Whitted(i) => return render_rays_from(scene, i, settings, control, film),
            Integrator::Path(i) => return render_rays_from(scene, i, settings, control, film),
            Integrator::VolPath(i) => return render_rays_from(scene, i, settings, control, film),
            Integrator::Photon(i) => return render_rays_from(scene, i.as_ref(), settings, control, film),
            Integrator::Sppm(i) => i.render(scene, settings, control, film),
            Integrator::Light(i) => i.render(scene, settings, control, film),
            Integrator::Bdpt(i) => i.render(scene, settings, control, film),
            Integrator::Vcm(i) => i.render(scene, settings, control, film),
        };
        crate::render::aov::add_first_hits(scene, settings, &mut out.film, &before);
        out
    }
}

/// The phases making the integrator `desc` asks for and rendering with `settings` go through, in
/// the order they run and named as they report themselves to the progress display, each with
/// its cost estimated in a unit common to them (about a ray traced), for the display's ETA
/// (`progress::Display::plan`). Only the ratios between a render's phases matter: the display
/// prices them with the seconds per unit the finished phases took.
pub fn plan(desc: &IntegratorDesc, scene: &Scene, settings: &RenderSettings) -> Vec<(&'static str, f64)> {
    // A time budget without a sample count renders until the budget, however long that is.
    let samples = if settings.spp == u32::MAX {
        f64::INFINITY
    } else {
        f64::from(settings.spp.saturating_sub(settings.first_sample))
    };
    let camera_samples = settings.pixels() as f64 * samples;
    match desc.kind {
        IntegratorKind::Whitted | IntegratorKind::Path | IntegratorKind::Volpath => vec![("render", camera_samples)],
        IntegratorKind::Light => vec![("light", camera_samples)],
        IntegratorKind::Sppm => vec![("sppm", camera_samples)],
        IntegratorKind::Bdpt => vec![("bdpt", camera_samples)],
        IntegratorKind::Vcm => vec![("vcm", camera_samples)],
        IntegratorKind::Photon => {
            photon::PhotonConfig::new(&desc.photon, desc, scene, settings.seed).plan(scene, camera_samples)
        }
    }
}

/// Bytes the integrator `desc` asks for will allocate for a render with `settings` (photon maps,
/// SPPM state), estimated before any of it is; the film is not included.
pub fn estimated_bytes(desc: &IntegratorDesc, scene: &Scene, settings: &RenderSettings) -> u64 {
    match desc.kind {
        IntegratorKind::Whitted | IntegratorKind::Path | IntegratorKind::Volpath => 0,
        IntegratorKind::Photon => {
            let c = photon::PhotonConfig::new(&desc.photon, desc, scene, settings.seed);
            // Up to four stored bounces per global photon, plus the irradiance records (one per
            // four stored bounces) and their depth levels.
            photon::estimated_map_bytes(c.photons.saturating_mul(5))
                + photon::estimated_record_level_bytes(c.photons)
                + photon::estimated_map_bytes(c.caustic_photons)
        }
        IntegratorKind::Light => light::estimated_bytes(settings.pixels(), settings.layers),
        IntegratorKind::Bdpt => bdpt::estimated_bytes(settings.pixels(), settings.layers),
        IntegratorKind::Vcm => vcm::estimated_bytes(settings.pixels(), settings.layers),
        IntegratorKind::Sppm => {
            let c = sppm::SppmConfig::new(desc, scene, settings.pixels());
            sppm::estimated_bytes(settings.pixels(), c.max_photons_per_iter(), settings.layers)
        }
    }
}

/// Renders through the shared driver with a splat film beside the pixel film, as the integrators
/// whose light paths land on any pixel do (`light`, `bdpt`, `vcm`): `pass` adds sample indices
/// (or iterations) `range` to both, and the driver's progress counts them in `unit`. Returns the
/// film and the stats with its sample count.
pub(crate) fn render_splatted(
    settings: &RenderSettings,
    control: &RenderControl,
    film: Film,
    (name, unit): (&'static str, &'static str),
    mut pass: impl FnMut(&Driver, &SplatFilm, &mut Film, Range<u32>) -> PassOutcome,
) -> (Film, RenderStats) {
    let first = settings.first_sample.saturating_add(film.min_samples());
    let splats = SplatFilm::new(settings.width, settings.height, settings.origin, settings.filter, settings.layers);
    let film = RefCell::new(film);
    let mut driver = Driver::new(settings, control, name, unit, settings.pixels(), first);
    let mut stats =
        driver.run(|driver, range| pass(driver, &splats, &mut film.borrow_mut(), range), |f| f(&film.borrow()));
    let film = film.into_inner();
    stats.samples_per_pixel = film.min_samples();
    (film, stats)
}
