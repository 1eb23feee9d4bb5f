//! A scene as its file describes it: plain data, before anything is built from it.
//!
//! Both loaders (TOML and Mitsuba XML) produce a [`SceneDescription`]: the geometry, materials
//! and lights collected in a [`SceneBuilder`], the camera, the film, the sampler, and the
//! integrator *as described* (its kind and options). [`Options`] (the TOML loader's `[render]`
//! keys over the defaults, then the command line's over the file's) are applied to it by one
//! function, [`SceneDescription::apply`], and it is then built into a runtime [`Scene`] with its
//! BVH by [`SceneDescription::build`]. The integrators read this description; nothing here knows
//! how they work (pbrt-v4's `BasicScene` plays the same part).

use super::builder::SceneBuilder;
use super::{Scene, SceneError};
use crate::camera::CameraDesc;
use crate::film::Crop;
use crate::film::filter::Filter;
use crate::math::Color;
use crate::options::{IntegratorKind, MAX_LIGHT_SAMPLES, Options, PhotonOptions};
use crate::sampling::SamplerKind;
use std::time::Duration;

/// Largest image side accepted, and largest pixel count (about 268 megapixels).
pub const MAX_SIDE: u32 = 1 << 16;
pub const MAX_PIXELS: u64 = 1 << 28;
/// Largest depth limit a scene or the command line may ask for; also what "unlimited" means for
/// integrators that end paths by Russian roulette.
pub const MAX_DEPTH_LIMIT: u32 = 1000;
/// The depth limit when a scene gives none: five reflections or refractions after the first
/// surface, as the seed report's examples use.
pub const DEFAULT_MAX_DEPTH: u32 = 6;
/// Most strata per axis of the jittered sampler.
pub const MAX_STRATA: u32 = 4096;

/// The integrator as the scene file describes it.
#[derive(Clone, Debug, PartialEq)]
pub struct IntegratorDesc {
    pub kind: IntegratorKind,
    /// The most bounces (surface interactions) a path may have from the camera to a light, in
    /// every integrator: 0 shows only what emits, 1 adds direct lighting, and each further one
    /// adds a reflection or refraction (pbrt-v4's `maxdepth`; Mitsuba's `max_depth` is one
    /// more). `None` is unlimited (see [`IntegratorDesc::depth_limit`]).
    pub max_depth: Option<u32>,
    /// Shadow rays per area light at each shading point (Whitted and photon mapping).
    pub light_samples: u32,
    /// The Whitted integrator's adaptive depth control: reflected, refracted and shadow rays of
    /// less weight in the pixel go on by Russian roulette (see `Whitted::adc_bailout`).
    pub adc_bailout: f32,
    pub photon: PhotonOptions,
    /// Ambient light I_a of seed eq. 1 (the Whitted integrator's).
    pub ambient: Color,
    /// Whether transparent objects let (attenuated) light through to the Whitted integrator's
    /// shadow rays.
    pub transparent_shadows: bool,
    /// Extra offset of spawned rays along their direction (the seed report's bias), in scene
    /// units, for every integrator; `None`: 1e-6 x the scene's diagonal (`ray_bias`).
    pub ray_bias: Option<f32>,
    /// Spectral rendering (`crate::spectrum::lanes`) instead of RGB.
    pub spectral: bool,
}

/// POV-Ray's default `adc_bailout`: one step of an 8-bit pixel.
pub const DEFAULT_ADC_BAILOUT: f32 = 1.0 / 255.0;

impl Default for IntegratorDesc {
    fn default() -> Self {
        IntegratorDesc {
            kind: IntegratorKind::Whitted,
            max_depth: Some(DEFAULT_MAX_DEPTH),
            light_samples: 16,
            adc_bailout: DEFAULT_ADC_BAILOUT,
            photon: PhotonOptions::default(),
            ambient: Color::ZERO,
            transparent_shadows: true,
            ray_bias: None,
            spectral: false,
        }
    }
}

impl IntegratorDesc {
    /// The depth limit `kind` works with: the given one, or for "unlimited" the largest limit
    /// (Russian roulette ends paths long before it), except for the Whitted integrator, whose
    /// recursion branches at every glass surface and so keeps the default.
    /// The ray offset rays leaving surfaces of `scene` take: the given one, or 1e-6 of the
    /// diagonal of the scene's bounded geometry (0 for a scene without any).
    pub fn ray_bias(&self, scene: &Scene) -> f32 {
        self.ray_bias.unwrap_or_else(|| {
            let b = scene.bounds();
            let diag = if b.is_empty() { 0.0 } else { b.diagonal() };
            if diag.is_finite() { diag * 1e-6 } else { 0.0 }
        })
    }

    pub fn depth_limit(&self, kind: IntegratorKind) -> u32 {
        match (self.max_depth, kind) {
            (Some(d), _) => d,
            (None, IntegratorKind::Whitted) => DEFAULT_MAX_DEPTH,
            (None, _) => MAX_DEPTH_LIMIT,
        }
    }
}

/// How pixels are sampled, as described (sample counts not yet resolved).
#[derive(Clone, Debug, PartialEq)]
pub struct SamplerDesc {
    /// The sample pattern, when the scene or the command line names one (`None`: chosen by
    /// `Sampling`'s rule, see `SamplerDesc::resolved_kind`).
    pub kind: Option<SamplerKind>,
    /// Total samples per pixel, when given.
    pub spp: Option<u32>,
    /// N of N x N strata, when given.
    pub spp_axis: Option<u32>,
    pub seed: u64,
    /// Without anti-aliasing every ray goes through the pixel centre (only the lens is sampled).
    pub antialias: bool,
}

impl SamplerDesc {
    /// The sample pattern `integrator` renders with. Unless the scene or the command line names
    /// one: Sobol points for the progressive integrators (SPPM and VCM), whose sample count is
    /// open-ended (a time limit, `--spp` iterations, a resumed render), since every prefix of a
    /// Sobol sequence is stratified while jittered sampling stratifies only complete sets of
    /// N x N samples (SPPM at 30 iterations of a 64-sample set: RMSE 0.055 jittered, 0.029
    /// Sobol, on the area-light caustic box against Mitsuba; BENCHMARKS.md); jittered strata
    /// otherwise, and always when samples per axis are given (the seed report's N x N).
    pub fn resolved_kind(&self, integrator: IntegratorKind) -> SamplerKind {
        match self.kind {
            Some(kind) => kind,
            None if self.spp_axis.is_none() && integrator.is_progressive() => SamplerKind::Sobol,
            None => SamplerKind::Jittered,
        }
    }
}

impl Default for SamplerDesc {
    fn default() -> Self {
        SamplerDesc { kind: None, spp: None, spp_axis: None, seed: 0, antialias: true }
    }
}

/// The film as described: which window of it is rendered and how samples make pixels.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct FilmDesc {
    /// Render only this window of the film (`None`: all of it).
    pub crop: Option<Crop>,
    /// The pixel reconstruction filter (native scenes: box; Mitsuba scenes: Mitsuba's default,
    /// a Gaussian, unless they name one).
    pub filter: Filter,
    /// Also take samples outside the window, up to the filter's radius (Mitsuba's
    /// `sample_border`), so that the window's edge pixels are filtered as in the whole image.
    pub sample_border: bool,
    /// The AOVs to write beside the image (Mitsuba's `aov` integrator, `[render] aov`, `--aov`).
    pub aovs: crate::film::aov::AovList,
    /// The EXR's colour channels as CIE XYZ (`[render] xyz`, `--xyz`).
    pub xyz: bool,
}

/// The image and its sampling, resolved: what the render loop needs.
#[derive(Clone, Debug, PartialEq)]
pub struct Sampling {
    /// The whole film (the camera's frame).
    pub width: u32,
    pub height: u32,
    /// The window of the film that is rendered: the image.
    pub crop: Crop,
    pub filter: Filter,
    pub sample_border: bool,
    pub spp: u32,
    /// Strata per axis of the jittered sampler (N of the N x N pattern).
    pub strata: u32,
    pub seed: u64,
    pub sampler: SamplerKind,
    pub antialias: bool,
    pub aovs: crate::film::aov::AovList,
    /// The EXR's colour channels as CIE XYZ.
    pub xyz: bool,
}

/// How a file is read: parameters, values put in place of the file's, strictness.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// `-D name=value`: values of `$name` parameters (they win over a Mitsuba `<default>` or a
    /// TOML `[parameters]` default).
    pub defines: Vec<(String, String)>,
    /// `--set KEY=VALUE`: values put in place of the scene's, by key path (`render.spp`,
    /// `materials.glass.ior`; `scene::native::set`), in the order given.
    pub sets: Vec<(String, String)>,
    /// Unsupported parts of a Mitsuba scene are errors instead of warnings.
    pub strict: bool,
}

/// Everything a scene file describes.
#[derive(Clone)]
pub struct SceneDescription {
    /// The file, for messages.
    pub name: String,
    pub geometry: SceneBuilder,
    pub camera: CameraDesc,
    /// The film's size (a crop renders a window of it).
    pub width: u32,
    pub height: u32,
    pub film: FilmDesc,
    pub sampler: SamplerDesc,
    pub integrator: IntegratorDesc,
    /// Things the loader could not render exactly, each `file:line:col: message`.
    pub warnings: Vec<String>,
}

/// What the log says about a mesh: a user scaling a scanned model needs its size.
#[derive(Clone, Debug)]
pub struct MeshInfo {
    /// The file it came from (or what made it).
    pub name: String,
    pub triangles: usize,
    /// Bounds after its transform, in scene units.
    pub bounds: crate::geometry::Aabb,
}

/// Facts about the built geometry, for the log.
#[derive(Clone, Debug, Default)]
pub struct LoadInfo {
    pub meshes: Vec<MeshInfo>,
    pub primitives: usize,
    pub triangles: usize,
    pub degenerate_triangles: usize,
    pub bvh_nodes: usize,
    pub bvh_build: Duration,
    /// Every file the scene was read from (see `SceneDescription::files`).
    pub files: Vec<std::path::PathBuf>,
    /// Instances placed and the groups of shapes they place (primitives and triangles of a
    /// group are counted once).
    pub instances: usize,
    pub instance_groups: usize,
}

/// A built scene with its resolved sampling and the integrator it asks for.
pub struct BuiltScene {
    pub scene: Scene,
    pub sampling: Sampling,
    pub integrator: IntegratorDesc,
    pub info: LoadInfo,
}

impl SceneDescription {
    /// Every file the scene was read from, once each in the order first read: the scene file,
    /// files it includes, meshes, textures and the environment map (what a render's identity
    /// hashes). The loaders' file hook (`footprint::FileBudget`) keeps the list.
    pub fn files(&self) -> Vec<std::path::PathBuf> {
        self.geometry.files()
    }

    fn error(&self, message: String) -> SceneError {
        SceneError::File { path: self.name.clone(), message }
    }

    /// Puts every value `o` gives in place of the description's: the one place where options
    /// meet a scene (the command line's, and the TOML loader's `[render]` keys over the defaults).
    pub fn apply(&mut self, o: &Options) {
        // Destructured without `..`: a new option does not compile until it is applied here.
        let Options {
            width,
            height,
            spp_axis,
            spp,
            max_depth,
            adc_bailout,
            seed,
            integrator,
            sampler,
            antialias,
            light_samples,
            filter,
            aov,
            // Not part of the scene: `app` gives it to the render settings (where to show the
            // picture changes nothing in it).
            display_server: _,
            spectral,
            xyz,

            photon,
        } = o.clone();
        let PhotonOptions {
            photons,
            caustic_photons,
            gather,
            gather_k,
            irradiance_cache,
            cache_rays,
            caustic_k,
            max_radius,
            caustic_radius,
            volume_k,
            volume_radius,
            photons_per_iter,
            initial_radius,
        } = photon;
        let before = (self.width, self.height);
        self.width = width.unwrap_or(self.width);
        self.height = height.unwrap_or(self.height);
        // A new image size keeps the crop on the same part of the view.
        let after = (self.width, self.height);
        if let Some(c) = &mut self.film.crop
            && after != before
            && c.fits(before.0, before.1)
            && after.0 > 0
            && after.1 > 0
        {
            *c = c.rescaled(before, after);
        }
        // A sample count on the command line replaces both of the file's (`--spp-axis 2` means 4
        // samples even where the file says `spp = 16`).
        let s = &mut self.sampler;
        if spp.is_some() || spp_axis.is_some() {
            s.spp = spp;
            s.spp_axis = spp_axis;
        }
        s.seed = seed.unwrap_or(s.seed);
        s.kind = sampler.or(s.kind);
        s.antialias = antialias.unwrap_or(s.antialias);
        self.film.filter = filter.unwrap_or(self.film.filter);
        if let Some(aovs) = aov {
            self.film.aovs = aovs;
        }
        self.film.xyz = xyz.unwrap_or(self.film.xyz);
        let i = &mut self.integrator;
        i.kind = integrator.unwrap_or(i.kind);
        i.max_depth = max_depth.or(i.max_depth);
        i.adc_bailout = adc_bailout.unwrap_or(i.adc_bailout);
        i.light_samples = light_samples.map_or(i.light_samples, |n| n.clamp(1, MAX_LIGHT_SAMPLES));
        i.spectral = spectral.unwrap_or(i.spectral);
        let p = &mut i.photon;
        p.photons = photons.or(p.photons);
        p.caustic_photons = caustic_photons.or(p.caustic_photons);
        p.gather = gather.or(p.gather);
        p.gather_k = gather_k.or(p.gather_k);
        p.irradiance_cache = irradiance_cache.or(p.irradiance_cache);
        p.cache_rays = cache_rays.or(p.cache_rays);
        p.caustic_k = caustic_k.or(p.caustic_k);
        p.max_radius = max_radius.or(p.max_radius);
        p.caustic_radius = caustic_radius.or(p.caustic_radius);
        p.volume_k = volume_k.or(p.volume_k);
        p.volume_radius = volume_radius.or(p.volume_radius);
        p.photons_per_iter = photons_per_iter.or(p.photons_per_iter);
        p.initial_radius = initial_radius.or(p.initial_radius);
    }

    /// Checks the final values and resolves the sample counts.
    pub fn sampling(&self) -> Result<Sampling, SceneError> {
        let (width, height) = (self.width, self.height);
        if width == 0
            || height == 0
            || width > MAX_SIDE
            || height > MAX_SIDE
            || width as u64 * height as u64 > MAX_PIXELS
        {
            return Err(self.error(format!(
                "image size {width} x {height} is out of range (each side 1 to {MAX_SIDE}, at most {MAX_PIXELS} pixels)"
            )));
        }
        let s = &self.sampler;
        let (spp, strata) = match (s.spp, s.spp_axis) {
            (Some(spp), axis) => (spp, axis.unwrap_or((spp as f64).sqrt() as u32)),
            (None, Some(n)) => (n.saturating_mul(n), n),
            // The seed report's default for a lens without anti-aliasing: 8 x 8 lens samples.
            (None, None) if !s.antialias && self.camera.lens_radius > 0.0 => (64, 8),
            // Without anti-aliasing or a lens every sample would be the same ray.
            (None, None) if !s.antialias => (1, 1),
            (None, None) => (4, 2),
        };
        if spp == 0 || strata == 0 || strata > MAX_STRATA {
            return Err(self.error(format!(
                "samples per pixel must be at least 1 (got spp {spp}, samples per axis {strata}; at most {MAX_STRATA} per axis)"
            )));
        }
        let crop = self.film.crop.unwrap_or(Crop::full(width, height));
        if !crop.fits(width, height) {
            return Err(self.error(format!(
                "the crop window ({} x {} at {}, {}) does not fit in the {width} x {height} film",
                crop.width, crop.height, crop.x, crop.y
            )));
        }
        self.film.filter.check().map_err(|m| self.error(m))?;
        Ok(Sampling {
            width,
            height,
            crop,
            filter: self.film.filter,
            sample_border: self.film.sample_border,
            spp,
            strata,
            seed: s.seed,
            sampler: s.resolved_kind(self.integrator.kind),
            antialias: s.antialias,
            aovs: self.film.aovs.clone(),
            xyz: self.film.xyz,
        })
    }

    /// Builds the runtime scene (BVH included) with the final image size.
    pub fn build(self) -> Result<BuiltScene, SceneError> {
        let sampling = self.sampling()?;
        if let Some(d) = self.integrator.max_depth
            && d > MAX_DEPTH_LIMIT
        {
            return Err(self.error(format!("max_depth {d} is too large (at most {MAX_DEPTH_LIMIT})")));
        }
        for (what, v) in [
            ("max_radius", self.integrator.photon.max_radius),
            ("caustic_radius", self.integrator.photon.caustic_radius),
            ("volume_radius", self.integrator.photon.volume_radius),
        ] {
            if let Some(r) = v
                && !(r > 0.0 && r.is_finite())
            {
                return Err(self.error(format!("photon {what} must be a positive number, got {r}")));
            }
        }
        let kind = self.integrator.kind;
        if self.integrator.spectral && !kind.renders_spectrally() {
            return Err(self.error(format!(
                "the {} integrator does not render spectrally; spectral mode works with path, volpath, photon, sppm, light, bdpt and vcm",
                kind.name()
            )));
        }
        let camera = self.camera.build(sampling.width, sampling.height);
        let (scene, info) =
            self.geometry.finish(camera).map_err(|message| SceneError::File { path: self.name.clone(), message })?;
        scene.check_usable().map_err(|message| SceneError::File { path: self.name.clone(), message })?;
        Ok(BuiltScene { scene, sampling, integrator: self.integrator, info })
    }
}
