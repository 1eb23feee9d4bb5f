//! The options of a render: every value the command line may give in place of the scene file's,
//! written once. [`Options`] is read by clap (`caustic render`'s flags, flattened into
//! `RenderArgs`) and by serde (the same keys as a table, the photon options nested as TOML's
//! `[render.photon]` is), and [`IntegratorKind`] is the one list of integrators for both.
//!
//! An option is one field here. The compiler then asks for it where it is used: fields are
//! destructured without `..` where options meet a scene (`SceneDescription::apply`), where the
//! TOML loader reads `[render]` (`RenderDesc::options`), where they become a farm shard's
//! arguments (`RenderArgs::to_args` in `main.rs`) and where the render identity is built from the
//! description they made (`RenderId::new`), so a new option does not compile until it is wired
//! (pbrt-v4's `ParameterDictionary` and Mitsuba 3's `Properties` report unused parameters for the
//! same reason).

use crate::film::aov::AovList;
use crate::film::filter::Filter;
use crate::sampling::SamplerKind;
use serde::{Deserialize, Deserializer};

/// Declares [`IntegratorKind`] and its [`IntegratorKind::ALL`] from one list of variants, so an
/// integrator is written once here (each with its one-line `--help` description) plus the
/// `match`es the compiler then asks for.
macro_rules! integrator_kinds {
    ($($(#[$attr:meta])* $variant:ident,)+) => {
        /// Which integrator renders the image: `--integrator NAME` on the command line,
        /// `integrator = "NAME"` in a TOML scene (the lowercase variant name in both).
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum, serde::Deserialize)]
        #[serde(rename_all = "lowercase")]
        pub enum IntegratorKind {
            $($(#[$attr])* $variant,)+
        }

        impl IntegratorKind {
            /// Every integrator, in the order declared.
            pub const ALL: [IntegratorKind; [$(stringify!($variant)),+].len()] = [$(IntegratorKind::$variant),+];
        }
    };
}

integrator_kinds! {
    /// Classic Whitted ray tracing with the seed report's Phong model: fast, no indirect light
    #[default]
    Whitted,
    /// Path tracing with next-event estimation and MIS: unbiased reference, noisy caustics
    Path,
    /// Volumetric path tracing: the path tracer through participating media (fog, smoke); `path` switches to it when the scene has media
    Volpath,
    /// Photon mapping (Jensen): caustic and global maps, final gathering; caustics from point lights
    Photon,
    /// Stochastic progressive photon mapping: converges to the exact image, caustics included
    Sppm,
    /// Light tracing (Mitsuba's ptracer): paths from the lights connected to the camera; caustics on diffuse surfaces, nothing seen in mirrors or glass
    Light,
    /// Bidirectional path tracing: camera and light paths joined by every technique with MIS; caustics on diffuse surfaces, glossy paths
    Bdpt,
    /// Vertex connection and merging: bidirectional path tracing plus photon merging under MIS, progressive; caustics everywhere, seen in mirrors too
    Vcm,
}

impl IntegratorKind {
    /// Whether the integrator renders progressively, an open-ended number of iterations of one
    /// sample per pixel each (its default sample pattern is Sobol's: `SamplerDesc::resolved_kind`).
    pub fn is_progressive(self) -> bool {
        matches!(self, IntegratorKind::Sppm | IntegratorKind::Vcm)
    }
}

impl IntegratorKind {
    /// Whether the integrator renders in spectral mode (`--spectral`); the others (Whitted's
    /// Phong model, which is defined on colours) refuse it.
    pub fn renders_spectrally(self) -> bool {
        match self {
            IntegratorKind::Path
            | IntegratorKind::Volpath
            | IntegratorKind::Photon
            | IntegratorKind::Sppm
            | IntegratorKind::Light
            | IntegratorKind::Bdpt
            | IntegratorKind::Vcm => true,
            IntegratorKind::Whitted => false,
        }
    }

    /// Whether the integrator renders participating media (the others render a scene with media
    /// as if its media were not there, and the render says so).
    pub fn renders_media(self) -> bool {
        matches!(self, IntegratorKind::Path | IntegratorKind::Volpath | IntegratorKind::Photon | IntegratorKind::Sppm)
    }

    /// The name on the command line and in scene files.
    pub fn name(self) -> &'static str {
        match self {
            IntegratorKind::Whitted => "whitted",
            IntegratorKind::Path => "path",
            IntegratorKind::Volpath => "volpath",
            IntegratorKind::Photon => "photon",
            IntegratorKind::Sppm => "sppm",
            IntegratorKind::Light => "light",
            IntegratorKind::Bdpt => "bdpt",
            IntegratorKind::Vcm => "vcm",
        }
    }
}

impl std::str::FromStr for IntegratorKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        IntegratorKind::ALL.into_iter().find(|k| k.name() == s).ok_or_else(|| {
            let names: Vec<&str> = IntegratorKind::ALL.iter().map(|k| k.name()).collect();
            let (last, rest) = names.split_last().expect("there are integrators");
            format!("unknown integrator `{s}` (expected {} or {last})", rest.join(", "))
        })
    }
}

/// Most shadow rays per light at a shading point (`light_samples`); larger values are clamped.
pub const MAX_LIGHT_SAMPLES: u32 = 4096;

/// Every value the command line may give in place of the scene file's. `None` (or an absent
/// key) keeps the scene's value; `SceneDescription::apply` is where they meet it. Each doc
/// comment is the flag's `--help` text.
#[derive(Clone, Debug, Default, PartialEq, clap::Args, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Options {
    /// Image width in pixels (overrides the scene).
    #[arg(long, value_name = "W")]
    pub width: Option<u32>,
    /// Image height in pixels (overrides the scene).
    #[arg(long, value_name = "H")]
    pub height: Option<u32>,
    /// Samples per pixel axis: N gives N x N jittered samples per pixel (overrides the scene).
    #[arg(long, value_name = "N")]
    pub spp_axis: Option<u32>,
    /// Total samples per pixel, any count (overrides --spp-axis and the scene).
    #[arg(long, value_name = "N", visible_alias = "samples")]
    pub spp: Option<u32>,
    /// The most bounces a path may have: 1 is direct light only, each more adds a reflection or
    /// refraction (overrides the scene).
    #[arg(long, value_name = "D")]
    pub max_depth: Option<u32>,
    /// Whitted: reflected, refracted and shadow rays of less weight in the pixel than this go
    /// on by Russian roulette (POV-Ray's adc_bailout; 0 ends none) [default: 1/255].
    #[arg(long, value_name = "W", value_parser = parse_unit_interval)]
    #[serde(deserialize_with = "deserialize_unit_interval")]
    pub adc_bailout: Option<f32>,
    /// Seed of all random sampling; the same seed gives the same image on any thread count.
    #[arg(long, value_name = "S")]
    pub seed: Option<u64>,
    /// The rendering algorithm (overrides the scene).
    #[arg(long, value_name = "NAME", value_enum)]
    pub integrator: Option<IntegratorKind>,
    /// Sample pattern: jittered or sobol.
    #[arg(long, value_name = "NAME")]
    pub sampler: Option<SamplerKind>,
    /// Trace every ray through the pixel centre (only the lens is sampled).
    // A flag that gives `Some(false)`: the command line can only turn anti-aliasing off.
    #[arg(long = "no-antialias", num_args = 0, default_missing_value = "false")]
    pub antialias: Option<bool>,
    /// Whitted and photon mapping: shadow rays per area light at each shading point (photon
    /// mapping: per environment light too) [default: 16].
    #[arg(long, value_name = "N")]
    pub light_samples: Option<u32>,
    /// Pixel reconstruction filter: box, tent, gaussian, mitchell, catmullrom or lanczos, with
    /// parameters after a colon if wanted (gaussian:stddev=0.3) (overrides the scene).
    #[arg(long, value_name = "NAME", value_parser = Filter::parse)]
    #[serde(deserialize_with = "deserialize_filter")]
    pub filter: Option<Filter>,
    /// Images to write beside the render (AOVs), comma-separated: albedo, normal (sh_normal),
    /// geo_normal, depth, position, uv (of the camera ray's first hit), variance, spp; or
    /// Mitsuba's NAME:TYPE pairs. Extra channels of an .exr output; beside a .png, OUT.aovs.exr.
    #[arg(long, value_name = "LIST", value_parser = AovList::parse)]
    #[serde(deserialize_with = "deserialize_aovs")]
    pub aov: Option<AovList>,
    /// Show the render as it progresses in the tev image viewer listening at HOST:PORT (tev's
    /// default is 127.0.0.1:14158); an unreachable or lost viewer is a warning, not an error.
    #[arg(long, value_name = "HOST:PORT", value_parser = parse_display_server)]
    #[serde(deserialize_with = "deserialize_display_server")]
    pub display_server: Option<String>,

    /// Render spectrally: each path carries wavelengths instead of RGB channels, so that
    /// dispersive glass splits white light (path, volpath, photon and sppm integrators; see
    /// docs/scene-format.md) [default: RGB].
    // A flag that gives `Some(true)`.
    #[arg(long, num_args = 0, default_missing_value = "true")]
    pub spectral: Option<bool>,

    /// Write the EXR image's colour channels as CIE 1931 XYZ (channels X, Y, Z) instead of
    /// linear sRGB (R, G, B), in RGB and spectral mode alike; layers too. An .exr output only
    /// (a PNG is always sRGB).
    // A flag that gives `Some(true)`.
    #[arg(long, num_args = 0, default_missing_value = "true")]
    pub xyz: Option<bool>,

    /// Photon-mapping and SPPM settings (`[render.photon]` in a TOML scene).
    #[command(flatten)]
    pub photon: PhotonOptions,
}

/// Photon-mapping and SPPM settings as given; defaults that depend on the scene are filled in
/// when the integrator is built.
#[derive(Clone, Debug, Default, PartialEq, clap::Args, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PhotonOptions {
    /// Photons emitted for the global photon map (photon integrator).
    #[arg(long, value_name = "N")]
    pub photons: Option<u64>,
    /// Caustic photons to store (photon integrator; 0 disables caustics).
    #[arg(long, value_name = "N")]
    pub caustic_photons: Option<u64>,
    /// Final-gather rays per sample; 0 reads the global photon map directly (fast preview).
    #[arg(long, value_name = "N")]
    pub gather: Option<u32>,
    /// Photons per radiance estimate.
    #[arg(long, value_name = "K")]
    pub gather_k: Option<usize>,
    /// Irradiance cache error threshold (Ward's a): indirect diffuse light is interpolated
    /// between final gathers made before rendering where it is smooth; smaller is more accurate
    /// and slower; 0 turns the cache off and gathers at every sample [default: 0.25; see
    /// docs/scene-format.md for what it trades].
    #[arg(long, value_name = "A")]
    pub irradiance_cache: Option<f32>,
    /// Final-gather rays per irradiance-cache record [default: 512].
    #[arg(long, value_name = "N")]
    pub cache_rays: Option<u32>,
    /// Photons per caustic estimate [default: 64].
    #[arg(long, value_name = "K")]
    pub caustic_k: Option<usize>,
    /// Largest radius of a radiance estimate, in scene units [default: 5% of the scene's size].
    #[arg(long, value_name = "R")]
    pub max_radius: Option<f32>,
    /// Largest radius of a caustic estimate, in scene units [default: 2% of the scene's size].
    #[arg(long, value_name = "R")]
    pub caustic_radius: Option<f32>,
    /// Photons per volume radiance estimate in participating media (photon integrator)
    /// [default: 64].
    #[arg(long, value_name = "K")]
    pub volume_k: Option<usize>,
    /// Largest radius of a volume radiance estimate, in scene units [default: twice the
    /// typical distance of the volume photons' k-th nearest neighbour].
    #[arg(long, value_name = "R")]
    pub volume_radius: Option<f32>,
    /// SPPM photons per iteration [default: one per pixel].
    #[arg(long, value_name = "N")]
    pub photons_per_iter: Option<u64>,
    /// SPPM starting search radius, VCM first merge radius, in scene units [default: about two
    /// pixel footprints].
    #[arg(long, value_name = "R")]
    pub initial_radius: Option<f32>,
}

impl Options {
    /// One warning for each option given that the `kind` integrator does not read, naming the
    /// integrators that do (an option that does nothing should say so, not be accepted
    /// silently).
    pub fn unused_by(&self, kind: IntegratorKind) -> Vec<String> {
        use IntegratorKind::{Photon, Sppm, Vcm, Whitted};
        let p = &self.photon;
        let given: [(&str, bool, &[IntegratorKind]); 15] = [
            ("--adc-bailout", self.adc_bailout.is_some(), &[Whitted]),
            ("--light-samples", self.light_samples.is_some(), &[Whitted, Photon]),
            ("--photons", p.photons.is_some(), &[Photon]),
            ("--caustic-photons", p.caustic_photons.is_some(), &[Photon]),
            ("--gather", p.gather.is_some(), &[Photon]),
            ("--gather-k", p.gather_k.is_some(), &[Photon]),
            ("--irradiance-cache", p.irradiance_cache.is_some(), &[Photon]),
            ("--cache-rays", p.cache_rays.is_some(), &[Photon]),
            ("--max-radius", p.max_radius.is_some(), &[Photon]),
            ("--caustic-k", p.caustic_k.is_some(), &[Photon]),
            ("--caustic-radius", p.caustic_radius.is_some(), &[Photon]),
            ("--volume-k", p.volume_k.is_some(), &[Photon]),
            ("--volume-radius", p.volume_radius.is_some(), &[Photon]),
            ("--photons-per-iter", p.photons_per_iter.is_some(), &[Sppm]),
            ("--initial-radius", p.initial_radius.is_some(), &[Sppm, Vcm]),
        ];
        given
            .iter()
            .filter(|(_, set, users)| *set && !users.contains(&kind))
            .map(|(flag, _, users)| {
                let names: Vec<&str> = users.iter().map(|k| k.name()).collect();
                format!("{flag} does nothing with the {} integrator (it is read by: {})", kind.name(), names.join(", "))
            })
            .collect()
    }
}

/// A number from 0 to 1, with -0 made 0 (a render's identity spells the value out).
pub fn unit_interval(v: f32) -> Result<f32, String> {
    if (0.0..=1.0).contains(&v) { Ok(v + 0.0) } else { Err(format!("expected a number from 0 to 1, found {v}")) }
}

fn parse_unit_interval(s: &str) -> Result<f32, String> {
    s.parse::<f32>()
        .ok()
        .and_then(|v| unit_interval(v).ok())
        .ok_or_else(|| format!("expected a number from 0 to 1, found `{s}`"))
}

fn deserialize_filter<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Filter>, D::Error> {
    Filter::parse(&String::deserialize(d)?).map(Some).map_err(serde::de::Error::custom)
}

fn deserialize_aovs<'de, D: Deserializer<'de>>(d: D) -> Result<Option<AovList>, D::Error> {
    AovList::parse(&String::deserialize(d)?).map(Some).map_err(serde::de::Error::custom)
}

/// A display server's address: `HOST:PORT` with a port from 1 to 65535 (`[::1]:14158` for an
/// IPv6 address). The host is looked up when the render starts.
pub fn parse_display_server(s: &str) -> Result<String, String> {
    match s.rsplit_once(':') {
        Some((host, port)) if !host.is_empty() && port.parse::<u16>().is_ok_and(|p| p > 0) => Ok(s.to_string()),
        _ => Err(format!("expected HOST:PORT (such as 127.0.0.1:14158), found `{s}`")),
    }
}

fn deserialize_display_server<'de, D: Deserializer<'de>>(d: D) -> Result<Option<String>, D::Error> {
    parse_display_server(&String::deserialize(d)?).map(Some).map_err(serde::de::Error::custom)
}

fn deserialize_unit_interval<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f32>, D::Error> {
    unit_interval(f32::deserialize(d)?).map(Some).map_err(serde::de::Error::custom)
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::ValueEnum;

    /// Issue 30, item 6: `--photons 1000 --integrator sppm` and `--initial-radius` with the path
    /// tracer were accepted without a word.
    #[test]
    fn options_an_integrator_does_not_read_are_named() {
        let o = Options {
            photon: PhotonOptions { photons: Some(1000), initial_radius: Some(0.1), ..Default::default() },
            light_samples: Some(4),
            ..Default::default()
        };
        let sppm = o.unused_by(IntegratorKind::Sppm);
        assert_eq!(sppm.len(), 2, "{sppm:?}");
        assert!(sppm[0].contains("--light-samples") && sppm[0].contains("whitted, photon"), "{sppm:?}");
        assert!(
            sppm[1].contains("--photons does nothing with the sppm integrator (it is read by: photon)"),
            "{sppm:?}"
        );
        let path = o.unused_by(IntegratorKind::Path);
        assert!(path.iter().any(|w| w.contains("--initial-radius") && w.contains("sppm")), "{path:?}");
        assert_eq!(o.unused_by(IntegratorKind::Photon).len(), 1, "only --initial-radius");
        assert!(Options::default().unused_by(IntegratorKind::Light).is_empty());
    }

    #[test]
    fn integrators_are_listed_once_and_named_alike_everywhere() {
        assert_eq!(IntegratorKind::value_variants(), IntegratorKind::ALL);
        for k in IntegratorKind::ALL {
            assert_eq!(k.to_possible_value().unwrap().get_name(), k.name());
            assert_eq!(k.name().parse::<IntegratorKind>(), Ok(k));
            let toml: Options = toml::from_str(&format!("integrator = \"{}\"", k.name())).unwrap();
            assert_eq!(toml.integrator, Some(k));
        }
        let e = "mlt".parse::<IntegratorKind>().unwrap_err();
        assert_eq!(e, "unknown integrator `mlt` (expected whitted, path, volpath, photon, sppm, light, bdpt or vcm)");
    }

    #[test]
    fn options_read_as_a_table_with_the_photon_options_nested() {
        let o: Options =
            toml::from_str("spp = 4\nadc_bailout = -0.0\nantialias = false\n[photon]\ngather = 0\n").unwrap();
        let photon = PhotonOptions { gather: Some(0), ..Default::default() };
        let want =
            Options { spp: Some(4), adc_bailout: Some(0.0), antialias: Some(false), photon, ..Default::default() };
        assert_eq!(o, want);
        assert!(o.adc_bailout.unwrap().is_sign_positive());
        let e = toml::from_str::<Options>("adc_bailout = 2").unwrap_err().to_string();
        assert!(e.contains("expected a number from 0 to 1, found 2"), "{e}");
        let e = toml::from_str::<Options>("widht = 2").unwrap_err().to_string();
        assert!(e.contains("unknown field `widht`"), "{e}");
        let e = toml::from_str::<Options>("[photon]\ngatherr = 2").unwrap_err().to_string();
        assert!(e.contains("unknown field `gatherr`"), "{e}");
    }
}
