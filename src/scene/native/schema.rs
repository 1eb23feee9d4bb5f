//! The shapes of the TOML scene format's tables (see `docs/scene-format.md`): serde types with
//! validating values, and the keys each `type` of material, light and object accepts.

use super::camera::{CropSpec, FilterSpec};
use crate::options::{IntegratorKind, Options, PhotonOptions};
use crate::sampling::SamplerKind;
use crate::scene::de::{
    ColorOrTexture, ColorSpec, Direction, Finite, NonNegative, NumberOrTexture, Pair, Point, Positive, Rgb, Scale, Unit,
};
use serde::Deserialize;
use std::path::PathBuf;
use toml::Spanned;

pub const MATERIAL_KINDS: &[(&str, &[&str])] = &[
    ("diffuse", &["color", "ka", "kd", "ks", "exponent"]),
    ("reflective", &["color", "ka", "kd", "ks", "exponent", "kr"]),
    ("transparent", &["color", "ka", "kd", "ks", "exponent", "kr", "kt", "ior", "dispersion"]),
    ("dielectric", &["color", "ka", "kd", "ks", "exponent", "ior", "dispersion"]),
    ("conductor", &["metal", "eta", "k", "specular", "two_sided"]),
    ("roughconductor", &["metal", "eta", "k", "specular", "two_sided", "distribution", "alpha", "alpha_u", "alpha_v"]),
    ("roughdielectric", &["ior", "dispersion", "distribution", "alpha", "alpha_u", "alpha_v"]),
    ("plastic", &["color", "specular", "ior", "nonlinear", "two_sided"]),
    ("roughplastic", &["color", "specular", "ior", "nonlinear", "two_sided", "distribution", "alpha"]),
    ("bumpmap", &["material", "texture", "scale"]),
    ("normalmap", &["material", "texture"]),
    ("mask", &["material", "opacity"]),
    ("blend", &["first", "second", "weight"]),
    ("twosided", &["front", "back"]),
    ("null", &[]),
    (
        "principled",
        &[
            "color",
            "roughness",
            "anisotropic",
            "metallic",
            "spec_trans",
            "spec_tint",
            "sheen",
            "sheen_tint",
            "clearcoat",
            "clearcoat_gloss",
            "flatness",
            "ior",
        ],
    ),
    (
        "principledthin",
        &[
            "color",
            "roughness",
            "anisotropic",
            "spec_trans",
            "spec_tint",
            "sheen",
            "sheen_tint",
            "flatness",
            "diff_trans",
            "ior",
        ],
    ),
];

pub const TEXTURE_KINDS: &[(&str, &[&str])] = &[
    ("bitmap", &["file", "filter", "wrap", "raw", "scale", "offset", "rotate"]),
    ("checkerboard", &["color0", "color1", "scale", "offset", "rotate"]),
];

pub const LIGHT_KINDS: &[(&str, &[&str])] = &[
    ("point", &["position", "color", "intensity"]),
    ("spot", &["position", "direction", "look_at", "angle", "falloff", "color", "intensity"]),
    ("directional", &["direction", "color", "intensity"]),
    ("area", &["shape", "corner", "edge1", "edge2", "center", "radius", "transform", "color", "intensity"]),
    ("envmap", &["file", "scale", "transform"]),
    ("constant", &["color", "intensity"]),
];

/// The keys only a quad or only a sphere area light takes.
pub const AREA_QUAD_KEYS: &[&str] = &["corner", "edge1", "edge2"];
pub const AREA_SPHERE_KEYS: &[&str] = &["center", "radius"];

pub const OBJECT_KINDS: &[(&str, &[&str])] = &[
    ("sphere", &["material", "interior", "exterior", "transform", "emission", "emission_texture", "center", "radius"]),
    ("plane", &["material", "interior", "exterior", "transform", "point", "normal"]),
    (
        "quad",
        &["material", "interior", "exterior", "transform", "emission", "emission_texture", "corner", "edge1", "edge2"],
    ),
    ("box", &["material", "interior", "exterior", "transform", "emission", "emission_texture", "min", "max"]),
    (
        "mesh",
        &["material", "interior", "exterior", "transform", "emission", "emission_texture", "file", "face_normals"],
    ),
    (
        "torus_knot",
        &[
            "material",
            "interior",
            "exterior",
            "transform",
            "emission",
            "emission_texture",
            "p",
            "q",
            "radius",
            "tube",
            "segments",
            "sides",
        ],
    ),
    (
        "cylinder",
        &["material", "interior", "exterior", "transform", "emission", "emission_texture", "p0", "p1", "radius"],
    ),
    (
        "disk",
        &[
            "material",
            "interior",
            "exterior",
            "transform",
            "emission",
            "emission_texture",
            "center",
            "normal",
            "radius",
        ],
    ),
    ("instance", &["group", "transform"]),
];

/// `[render]`: the render's options (the keys of [`Options`], which the command line can also
/// give) and the scene's own settings, in one table. serde's `flatten` cannot split it (it
/// loses `deny_unknown_fields` and the positions of errors), so the options are listed here too
/// and [`RenderDesc::options`] turns them into `Options`, field by field.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct RenderDesc {
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub spp_axis: Option<u32>,
    pub spp: Option<u32>,
    pub max_depth: Option<u32>,
    pub seed: Option<u64>,
    pub integrator: Option<IntegratorKind>,
    pub sampler: Option<SamplerKind>,
    pub antialias: Option<bool>,
    pub background: Option<Spanned<Rgb>>,
    pub ambient: Option<Rgb>,
    pub ray_bias: Option<NonNegative>,
    pub transparent_shadows: Option<bool>,
    pub light_samples: Option<u32>,
    pub adc_bailout: Option<Unit>,
    /// The film: a window to render, the pixel filter, sampling past the window's edge.
    pub crop: Option<Spanned<CropSpec>>,
    pub filter: Option<FilterSpec>,
    pub sample_border: Option<bool>,
    /// AOVs to write beside the image, as `--aov` takes them.
    pub aov: Option<Spanned<String>>,
    /// Spectral rendering instead of RGB.
    pub spectral: Option<bool>,
    /// The EXR's colour channels as CIE XYZ instead of linear sRGB (`--xyz`).
    pub xyz: Option<bool>,
    /// Photon-mapping settings.
    #[serde(default)]
    pub photon: PhotonOptions,
}

impl RenderDesc {
    /// The table's options, to apply over the scene's defaults as the command line's are applied
    /// over the file's (`SceneDescription::apply`).
    pub fn options(&self) -> Options {
        // Destructured without `..`, and `Options` built without it: a new option does not
        // compile until it is read from the file here (or, for a new key of the scene's own, until
        // it is named among those the loader reads itself).
        let RenderDesc {
            width,
            height,
            spp_axis,
            spp,
            max_depth,
            seed,
            integrator,
            sampler,
            antialias,
            background: _,
            ambient: _,
            ray_bias: _,
            transparent_shadows: _,
            light_samples,
            adc_bailout,
            crop: _,
            filter,
            sample_border: _,
            aov: _,
            spectral,
            xyz,
            photon,
        } = self;
        Options {
            width: *width,
            height: *height,
            spp_axis: *spp_axis,
            spp: *spp,
            max_depth: *max_depth,
            // + 0.0 makes -0 into 0: a render's identity spells the value out.
            adc_bailout: adc_bailout.map(|b| b.0 + 0.0),
            seed: *seed,
            integrator: *integrator,
            sampler: *sampler,
            antialias: *antialias,
            light_samples: *light_samples,
            filter: filter.as_ref().map(|f| f.0),
            // Read (with its position for errors) by the loader: `aovs`.
            aov: None,
            // Where a render is shown is the user's choice, not the scene's: a scene file from
            // elsewhere does not open network connections.
            display_server: None,
            spectral: *spectral,
            xyz: *xyz,

            photon: photon.clone(),
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraTable {
    pub eye: Point,
    pub look_at: Point,
    pub up: Option<Direction>,
    pub fov: Option<Positive>,
    pub view_distance: Option<Positive>,
    pub lens_radius: Option<NonNegative>,
    pub focal_distance: Option<Positive>,
    pub focus_on: Option<Point>,
    pub projection: Option<Spanned<String>>,
    pub view_width: Option<Positive>,
    pub view_height: Option<Positive>,
    pub principal_point_offset: Option<Pair>,
}

/// `dispersion = "bk7"`, `dispersion = { cauchy = [A, B] }` (or `[A, B, C]`), or
/// `dispersion = { sellmeier = { b = [...], c = [...] } }`: wavelengths in micrometres.
#[derive(Deserialize)]
#[serde(untagged)]
pub enum DispersionSpec {
    Name(String),
    Formula(DispersionFormula),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DispersionFormula {
    pub cauchy: Option<Vec<f32>>,
    pub sellmeier: Option<SellmeierTerms>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SellmeierTerms {
    pub b: Vec<f32>,
    pub c: Vec<f32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialDesc {
    pub color: Option<Spanned<ColorOrTexture>>,
    pub ka: Option<NonNegative>,
    pub kd: Option<NonNegative>,
    pub ks: Option<NonNegative>,
    pub exponent: Option<NonNegative>,
    pub kr: Option<Unit>,
    pub kt: Option<Unit>,
    pub ior: Option<Positive>,
    /// A glass's index over wavelength (replaces `ior`): a named glass or a formula.
    pub dispersion: Option<Spanned<DispersionSpec>>,
    pub metal: Option<Spanned<String>>,
    pub eta: Option<Rgb>,
    pub k: Option<Rgb>,
    pub specular: Option<Spanned<ColorOrTexture>>,
    pub two_sided: Option<bool>,
    pub distribution: Option<Spanned<String>>,
    pub alpha: Option<Spanned<NumberOrTexture>>,
    pub alpha_u: Option<Spanned<NumberOrTexture>>,
    pub alpha_v: Option<Spanned<NumberOrTexture>>,
    pub nonlinear: Option<bool>,
    pub material: Option<Spanned<String>>,
    pub texture: Option<Spanned<String>>,
    pub scale: Option<Finite>,
    pub opacity: Option<Spanned<NumberOrTexture>>,
    pub first: Option<Spanned<String>>,
    pub second: Option<Spanned<String>>,
    pub weight: Option<Spanned<NumberOrTexture>>,
    pub front: Option<Spanned<String>>,
    pub back: Option<Spanned<String>>,
    // The principled material's weights (Mitsuba's names).
    pub roughness: Option<Spanned<NumberOrTexture>>,
    pub anisotropic: Option<Spanned<NumberOrTexture>>,
    pub metallic: Option<Spanned<NumberOrTexture>>,
    pub spec_trans: Option<Spanned<NumberOrTexture>>,
    pub spec_tint: Option<Spanned<NumberOrTexture>>,
    pub sheen: Option<Spanned<NumberOrTexture>>,
    pub sheen_tint: Option<Spanned<NumberOrTexture>>,
    pub clearcoat: Option<Spanned<NumberOrTexture>>,
    pub clearcoat_gloss: Option<Spanned<NumberOrTexture>>,
    pub flatness: Option<Spanned<NumberOrTexture>>,
    pub diff_trans: Option<Spanned<NumberOrTexture>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TextureDesc {
    pub file: Option<Spanned<PathBuf>>,
    pub filter: Option<Spanned<String>>,
    pub wrap: Option<Spanned<String>>,
    pub raw: Option<bool>,
    pub scale: Option<Pair>,
    pub offset: Option<Pair>,
    pub rotate: Option<Finite>,
    pub color0: Option<Rgb>,
    pub color1: Option<Rgb>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightDesc {
    pub position: Option<Point>,
    pub direction: Option<Direction>,
    pub look_at: Option<Point>,
    /// Spot cone half-angle and the half-angle where the fall-off starts, in degrees.
    pub angle: Option<Positive>,
    pub falloff: Option<NonNegative>,
    pub color: Option<Spanned<ColorSpec>>,
    pub intensity: Option<NonNegative>,
    pub shape: Option<String>,
    pub corner: Option<Point>,
    pub edge1: Option<Point>,
    pub edge2: Option<Point>,
    pub center: Option<Point>,
    pub radius: Option<Positive>,
    pub transform: Option<Vec<TransformOp>>,
    /// Environment map image.
    pub file: Option<Spanned<PathBuf>>,
    pub scale: Option<NonNegative>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename_all = "lowercase")]
pub enum TransformOp {
    Translate(Point),
    Rotate(Rotation),
    Scale(Scale),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rotation {
    pub axis: Direction,
    pub degrees: Finite,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectDesc {
    pub material: Option<Spanned<String>>,
    /// The media inside and outside the object (names of `[media.NAME]` tables).
    pub interior: Option<Spanned<String>>,
    pub exterior: Option<Spanned<String>>,
    pub transform: Option<Vec<TransformOp>>,
    /// Radiance the object's surface emits (W/(m^2 sr)) from its outer side: it becomes an area
    /// light that also reflects with its material.
    pub emission: Option<Spanned<ColorSpec>>,
    /// A texture (named in `[textures]`) the emission is multiplied by, read at the surface's
    /// uv; `emission` defaults to 1 with it.
    pub emission_texture: Option<Spanned<String>>,
    pub center: Option<Point>,
    pub radius: Option<Positive>,
    pub point: Option<Point>,
    pub normal: Option<Direction>,
    pub corner: Option<Point>,
    pub edge1: Option<Point>,
    pub edge2: Option<Point>,
    pub min: Option<Point>,
    pub max: Option<Point>,
    pub file: Option<Spanned<PathBuf>>,
    pub face_normals: Option<bool>,
    pub p: Option<u32>,
    pub q: Option<u32>,
    pub tube: Option<Positive>,
    pub segments: Option<u32>,
    pub sides: Option<u32>,
    pub p0: Option<Point>,
    pub p1: Option<Point>,
    pub group: Option<Spanned<String>>,
}
