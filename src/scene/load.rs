//! Reads a TOML scene file (format in `docs/scene-format.md`) and builds the `Scene` and the
//! `RenderSettings`, with command-line overrides applied.
//!
//! The document is parsed once into a tree that keeps every value's position. Tagged tables
//! (materials, lights and objects, chosen by `type`) are dispatched by hand, their keys checked
//! against the keys that kind accepts, and the rest deserialized with serde from that tree, so
//! every error, even one found by a validating type deep inside, points at its line and column.

use super::de::{Direction, Finite, NonNegative, Point, Positive, Rgb, Scale, Unit};
use super::{Scene, SceneError};
use crate::accel::Bvh;
use crate::camera::{Camera, ViewPlane};
use crate::geometry::Transform;
use crate::integrator::{IntegratorConfig, IntegratorKind};
use crate::light::{Emitter, Light};
use crate::material::{Material, MaterialKind};
use crate::math::{Color, Vec3};
use crate::render::RenderSettings;
use crate::sampling::SamplerKind;
use crate::shape::{Plane, Primitive, Quad, Shape, Sphere, TriangleMesh};
use serde::Deserialize;
use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use toml::Spanned;
use toml::de::{DeString, DeTable, DeValue, ValueDeserializer};

/// Largest image side accepted, and largest pixel count (about 268 megapixels).
const MAX_SIDE: u32 = 1 << 16;
const MAX_PIXELS: u64 = 1 << 28;
/// Largest procedural mesh, in triangles.
const MAX_GENERATED_TRIANGLES: u64 = 50_000_000;

/// Settings given on the command line; each replaces the scene file's value when present.
#[derive(Clone, Debug, Default)]
pub struct Overrides {
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub spp_axis: Option<u32>,
    pub spp: Option<u32>,
    pub max_depth: Option<u32>,
    pub seed: Option<u64>,
    pub integrator: Option<IntegratorKind>,
    pub sampler: Option<SamplerKind>,
    pub antialias: Option<bool>,
    pub photon: crate::integrator::PhotonOptions,
    /// `-D name=value`: values of `$name` parameters in Mitsuba scenes (they win over `<default>`).
    pub defines: Vec<(String, String)>,
    /// Unsupported parts of a Mitsuba scene are errors instead of warnings.
    pub strict: bool,
}

/// Everything a loaded scene file describes.
pub struct LoadedScene {
    pub scene: Scene,
    pub settings: RenderSettings,
    pub integrator: IntegratorConfig,
    pub info: LoadInfo,
}

/// Facts about the loaded geometry, for the log.
#[derive(Clone, Debug, Default)]
pub struct LoadInfo {
    pub primitives: usize,
    pub triangles: usize,
    pub degenerate_triangles: usize,
    pub bvh_nodes: usize,
    pub bvh_build: Duration,
}

pub fn load_scene(path: &Path, overrides: &Overrides) -> Result<LoadedScene, SceneError> {
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("xml")) {
        return super::mitsuba::load_mitsuba(path, overrides);
    }
    let text = std::fs::read_to_string(path)
        .map_err(|source| SceneError::Read { path: path.display().to_string(), source })?;
    let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
    load_scene_str(&text, &path.display().to_string(), &base, overrides)
}

/// Loads a scene from `text`; `name` is used in messages and mesh paths resolve against `base`.
pub fn load_scene_str(text: &str, name: &str, base: &Path, overrides: &Overrides) -> Result<LoadedScene, SceneError> {
    let cx = Cx { path: name, text, base };
    let doc = DeTable::parse(text).map_err(|e| cx.toml(e))?;
    let doc_span = doc.span();
    let mut sections: HashMap<&str, Spanned<DeValue>> = HashMap::new();
    for (key, value) in doc.into_inner() {
        let k: &str = key.get_ref();
        match k {
            "render" | "camera" | "materials" | "lights" | "objects" => {
                let k = match k {
                    "render" => "render",
                    "camera" => "camera",
                    "materials" => "materials",
                    "lights" => "lights",
                    _ => "objects",
                };
                sections.insert(k, value);
            }
            other => {
                return Err(cx.at(
                    key.span(),
                    format!("unknown section `{other}`; expected one of render, camera, materials, lights, objects"),
                ));
            }
        }
    }

    let render: RenderDesc = match sections.remove("render") {
        Some(v) => cx.de(v)?,
        None => RenderDesc::default(),
    };
    let camera_value =
        sections.remove("camera").ok_or_else(|| cx.at(doc_span.start..doc_span.start, "missing [camera] section"))?;
    let camera_span = camera_value.span();
    let camera_desc: CameraDesc = cx.de(camera_value)?;

    // Materials, by name.
    let mut materials = Vec::new();
    let mut material_names = Vec::new();
    let mut material_index: HashMap<String, u32> = HashMap::new();
    if let Some(v) = sections.remove("materials") {
        let span = v.span();
        let DeValue::Table(table) = v.into_inner() else {
            return Err(cx.at(span, "`materials` must be a table of named materials ([materials.NAME])"));
        };
        for (name, value) in table {
            let (kind, value) = cx.tagged(value, "material", MATERIAL_KINDS)?;
            let desc: MaterialDesc = cx.de(value)?;
            material_index.insert(name.get_ref().to_string(), materials.len() as u32);
            material_names.push(name.get_ref().to_string());
            materials.push(desc.build(kind));
        }
    }

    // Lights are read now and built after the objects: area lights add primitives, and
    // directional lights need the scene's bounds.
    let mut light_descs = Vec::new();
    if let Some(v) = sections.remove("lights") {
        for value in cx.array(v, "lights")? {
            let span = value.span();
            let (kind, value) = cx.tagged(value, "light", LIGHT_KINDS)?;
            let d: LightDesc = cx.de(value)?;
            light_descs.push((kind, d, span));
        }
    }

    // Objects.
    let mut prims: Vec<Primitive> = Vec::new();
    let mut planes = Vec::new();
    let mut meshes: Vec<TriangleMesh> = Vec::new();
    let mut info = LoadInfo::default();
    let mut specular_targets = Vec::new();
    if let Some(v) = sections.remove("objects") {
        for value in cx.array(v, "objects")? {
            let table_span = value.span();
            let (kind, value) = cx.tagged(value, "object", OBJECT_KINDS)?;
            let d: ObjectDesc = cx.de(value)?;
            let material = match &d.material {
                None => default_material(&mut materials, &mut material_names, &mut material_index),
                Some(name) => *material_index.get(name.get_ref().as_str()).ok_or_else(|| {
                    let mut known: Vec<&str> = material_names.iter().map(String::as_str).collect();
                    known.sort();
                    cx.at(
                        name.span(),
                        format!(
                            "no material named `{}` (defined: {})",
                            name.get_ref(),
                            if known.is_empty() { "none".into() } else { known.join(", ") }
                        ),
                    )
                })?,
            };
            let transform = d.transform(&cx, table_span.clone())?;
            let first_prim = prims.len();
            match kind {
                "sphere" => {
                    let center = transform.point(d.center.map_or(Vec3::ZERO, |p| p.0));
                    if !transform.is_similarity() {
                        return Err(cx.at(table_span, "a sphere can only be translated, rotated and scaled uniformly; use a mesh for an ellipsoid"));
                    }
                    let radius = d.radius.map_or(1.0, |r| r.0) * transform.axis_scales().x;
                    if !(radius > 0.0 && radius.is_finite() && center.is_finite()) {
                        return Err(cx.at(table_span, "sphere is degenerate after its transform"));
                    }
                    prims.push(Primitive { shape: Shape::Sphere(Sphere::new(center, radius)), material });
                }
                "plane" => {
                    let point = transform.point(d.point.map_or(Vec3::ZERO, |p| p.0));
                    let normal = transform.normal(d.normal.map_or(Vec3::Y, |n| n.0)).normalize_or_zero();
                    if normal == Vec3::ZERO || !point.is_finite() {
                        return Err(cx.at(table_span, "plane is degenerate after its transform"));
                    }
                    planes.push((Plane { point, normal }, material));
                }
                "quad" => {
                    let corner = d.corner.map_or(Vec3::new(-1.0, 0.0, 1.0), |p| p.0);
                    let e1 = d.edge1.map_or(Vec3::new(2.0, 0.0, 0.0), |p| p.0);
                    let e2 = d.edge2.map_or(Vec3::new(0.0, 0.0, -2.0), |p| p.0);
                    let q = transformed_quad(&transform, corner, e1, e2)
                        .ok_or_else(|| cx.at(table_span, "quad edges are parallel or zero: it has no area"))?;
                    prims.push(Primitive { shape: Shape::Quad(q), material });
                }
                "box" => {
                    let min = d.min.map_or(Vec3::splat(-1.0), |p| p.0);
                    let max = d.max.map_or(Vec3::splat(1.0), |p| p.0);
                    if !(min.cmplt(max).all()) {
                        return Err(
                            cx.at(table_span, format!("box `min` {min} must be below `max` {max} on every axis"))
                        );
                    }
                    for (c, e1, e2) in box_faces(min, max) {
                        let q = transformed_quad(&transform, c, e1, e2)
                            .ok_or_else(|| cx.at(table_span.clone(), "box is degenerate after its transform"))?;
                        prims.push(Primitive { shape: Shape::Quad(q), material });
                    }
                }
                "mesh" | "torus_knot" => {
                    let mesh = if kind == "mesh" {
                        let file = d
                            .file
                            .as_ref()
                            .ok_or_else(|| cx.at(table_span.clone(), "a mesh needs `file` (an OBJ file)"))?;
                        let path = cx.base.join(file.get_ref());
                        TriangleMesh::load_obj(&path).map_err(|e| cx.at(file.span(), e.to_string()))?
                    } else {
                        let (segments, sides) = (d.segments.unwrap_or(256), d.sides.unwrap_or(32));
                        if segments < 3 || sides < 3 || 2 * segments as u64 * sides as u64 > MAX_GENERATED_TRIANGLES {
                            return Err(cx.at(table_span, format!("torus_knot needs segments >= 3 and sides >= 3 and at most {MAX_GENERATED_TRIANGLES} triangles")));
                        }
                        let (p, q) = (d.p.unwrap_or(2), d.q.unwrap_or(3));
                        if p == 0 || q == 0 || p > 1000 || q > 1000 {
                            return Err(cx.at(table_span, "torus_knot p and q must be from 1 to 1000"));
                        }
                        TriangleMesh::torus_knot(
                            p,
                            q,
                            d.radius.map_or(1.0, |r| r.0),
                            d.tube.map_or(0.25, |t| t.0),
                            segments,
                            sides,
                        )
                    };
                    let mut mesh = mesh.transformed(&transform);
                    if transform.m.determinant() < 0.0 {
                        // A mirroring transform reverses winding; swap to keep the outward side.
                        for t in &mut mesh.indices {
                            t.swap(1, 2);
                        }
                    }
                    if mesh.positions.iter().any(|p| !p.is_finite()) {
                        return Err(cx.at(table_span, "mesh has non-finite vertices after its transform"));
                    }
                    let id = meshes.len() as u32;
                    let (tris, skipped) = mesh.triangles(id);
                    info.triangles += tris.len();
                    info.degenerate_triangles += skipped;
                    prims.extend(tris.into_iter().map(|t| Primitive { shape: Shape::Triangle(t), material }));
                    meshes.push(mesh);
                }
                _ => unreachable!("kind checked by tagged()"),
            }
            if materials[material as usize].is_specular() && prims.len() > first_prim {
                let b = prims[first_prim..].iter().fold(crate::geometry::Aabb::EMPTY, |b, p| b.union(p.shape.bounds()));
                specular_targets.push(match prims[first_prim].shape {
                    Shape::Sphere(s) if prims.len() == first_prim + 1 => (s.center, s.radius),
                    _ => b.bounding_sphere(),
                });
            }
        }
    }

    // Area lights become emitting primitives with a material of their own.
    let mut lights = Vec::new();
    for (kind, d, span) in &light_descs {
        let power = d.color.map_or(Color::ONE, |c| c.0) * d.intensity.map_or(1.0, |i| i.0);
        let light_index = lights.len() as u32;
        lights.push(match *kind {
            "point" => Light::Point { position: d.position.map_or(Vec3::ZERO, |p| p.0), intensity: power },
            "spot" => {
                let position = d.position.map_or(Vec3::ZERO, |p| p.0);
                let direction = match (d.direction, d.look_at) {
                    (Some(_), Some(_)) => {
                        return Err(cx.at(span.clone(), "give either `direction` or `look_at`, not both"));
                    }
                    (Some(dir), None) => dir.0,
                    (None, Some(t)) => (t.0 - position)
                        .try_normalize()
                        .ok_or_else(|| cx.at(span.clone(), "spot light `look_at` is the light's own position"))?,
                    (None, None) => -Vec3::Y,
                };
                let angle = d.angle.map_or(30.0, |a| a.0);
                let falloff = d.falloff.map_or(angle * 0.75, |a| a.0);
                if angle > 90.0 || falloff > angle {
                    return Err(cx.at(
                        span.clone(),
                        format!(
                            "spot light needs falloff <= angle <= 90 degrees (got falloff {falloff}, angle {angle})"
                        ),
                    ));
                }
                Light::Spot {
                    position,
                    direction,
                    intensity: power,
                    cos_total: angle.to_radians().cos(),
                    cos_falloff: falloff.to_radians().cos(),
                }
            }
            "directional" => Light::Directional {
                direction: d.direction.map_or(-Vec3::Y, |p| p.0),
                irradiance: power,
                scene_center: Vec3::ZERO,
                scene_radius: 0.0,
            },
            _ => {
                let transform = transform_of(&d.transform, &cx, span.clone())?;
                let material = materials.len() as u32;
                materials.push(Material::emitter(power, light_index));
                material_names.push(format!("(area light {})", light_index + 1));
                let prim = prims.len() as u32;
                let emitter = match d.shape.as_deref().unwrap_or("quad") {
                    "quad" => {
                        // Default: a 1 x 1 square facing down, as a ceiling light.
                        let corner = d.corner.map_or(Vec3::new(-0.5, 0.0, -0.5), |p| p.0);
                        let e1 = d.edge1.map_or(Vec3::new(1.0, 0.0, 0.0), |p| p.0);
                        let e2 = d.edge2.map_or(Vec3::new(0.0, 0.0, 1.0), |p| p.0);
                        let q = transformed_quad(&transform, corner, e1, e2).ok_or_else(|| {
                            cx.at(span.clone(), "area light quad edges are parallel or zero: it has no area")
                        })?;
                        prims.push(Primitive { shape: Shape::Quad(q), material });
                        Emitter::Quad(q)
                    }
                    "sphere" => {
                        if !transform.is_similarity() {
                            return Err(cx.at(
                                span.clone(),
                                "a spherical light can only be translated, rotated and scaled uniformly",
                            ));
                        }
                        let center = transform.point(d.center.map_or(Vec3::ZERO, |p| p.0));
                        let radius = d.radius.map_or(0.5, |r| r.0) * transform.axis_scales().x;
                        let s = Sphere::new(center, radius);
                        prims.push(Primitive { shape: Shape::Sphere(s), material });
                        Emitter::Sphere(s)
                    }
                    other => {
                        return Err(
                            cx.at(span.clone(), format!("unknown area light shape `{other}`; expected quad or sphere"))
                        );
                    }
                };
                Light::Area { emitter, radiance: power, prim }
            }
        });
    }

    // Settings: scene values, then command-line overrides, then checks.
    let width = overrides.width.unwrap_or(render.width.unwrap_or(640));
    let height = overrides.height.unwrap_or(render.height.unwrap_or(480));
    if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE || width as u64 * height as u64 > MAX_PIXELS {
        return Err(SceneError::File {
            path: name.to_string(),
            message: format!(
                "image size {width} x {height} is out of range (each side 1 to {MAX_SIDE}, at most {MAX_PIXELS} pixels)"
            ),
        });
    }
    let lens_radius = camera_desc.lens_radius.map_or(0.0, |r| r.0);
    let antialias = overrides.antialias.or(render.antialias).unwrap_or(true);
    // A sample count on the command line replaces both of the file's (`--spp-axis 2` means 4
    // samples even where the file says `spp = 16`).
    let cli_samples = overrides.spp.is_some() || overrides.spp_axis.is_some();
    let spp_axis = if cli_samples { overrides.spp_axis } else { render.spp_axis };
    let spp_given = if cli_samples { overrides.spp } else { render.spp };
    let (spp, strata) = match (spp_given, spp_axis) {
        (Some(spp), _) => (spp, spp_axis.unwrap_or((spp as f64).sqrt() as u32)),
        (None, Some(n)) => (n.saturating_mul(n), n),
        // The seed report's default for a lens without anti-aliasing: 8 x 8 lens samples.
        (None, None) if !antialias && lens_radius > 0.0 => (64, 8),
        // Without anti-aliasing or a lens every sample would be the same ray.
        (None, None) if !antialias => (1, 1),
        (None, None) => (4, 2),
    };
    if spp == 0 || strata == 0 || strata > 4096 {
        return Err(SceneError::File {
            path: name.to_string(),
            message: format!(
                "samples per pixel must be at least 1 (got spp {spp}, samples per axis {strata}; at most 4096 per axis)"
            ),
        });
    }
    let max_depth = overrides.max_depth.or(render.max_depth).unwrap_or(5);
    if max_depth > 1000 {
        return Err(SceneError::File {
            path: name.to_string(),
            message: format!("max_depth {max_depth} is too large (at most 1000)"),
        });
    }

    let photon = render.photon.overridden_by(&overrides.photon);
    for (name, v) in [("max_radius", photon.max_radius), ("caustic_radius", photon.caustic_radius)] {
        if let Some(r) = v
            && !(r > 0.0 && r.is_finite())
        {
            return Err(SceneError::File {
                path: cx.path.to_string(),
                message: format!("photon {name} must be a positive number, got {r}"),
            });
        }
    }
    let camera = camera_desc.build(&cx, camera_span, width, height)?;
    let t0 = Instant::now();
    let bvh = Bvh::build(prims);
    info.bvh_build = t0.elapsed();
    info.primitives = bvh.prims.len();
    info.bvh_nodes = bvh.node_count();
    let bounds = bvh.bounds();
    let diag = if bounds.is_empty() { 0.0 } else { bounds.diagonal() };
    let (scene_center, scene_radius) = if bounds.is_empty() { (Vec3::ZERO, 1.0) } else { bounds.bounding_sphere() };
    for l in &mut lights {
        if let Light::Directional { scene_center: c, scene_radius: r, .. } = l {
            // Planes are unbounded: the bounding sphere of the finite geometry (at least the
            // camera's surroundings) is where photons from the sun are useful.
            *c = scene_center;
            *r = scene_radius.max(1e-3);
        }
    }
    let any_transmissive = materials.iter().any(Material::transmits);
    let scene = Scene {
        bvh,
        planes,
        meshes,
        materials,
        material_names,
        light_picker: crate::light::LightPicker::new(&lights),
        lights,
        camera,
        background: render.background.map_or(Color::ZERO, |c| c.0),
        ambient: render.ambient.map_or(Color::ZERO, |c| c.0),
        // Error-bound offsets already keep rays off their own surface; the seed's bias along the
        // direction is kept as a tiny margin relative to the scene size.
        ray_bias: render.ray_bias.map_or(if diag.is_finite() { diag * 1e-6 } else { 0.0 }, |b| b.0),
        transparent_shadows: render.transparent_shadows.unwrap_or(true),
        any_transmissive,
        specular_targets,
    };
    let settings = RenderSettings {
        width,
        height,
        spp,
        strata,
        seed: overrides.seed.or(render.seed).unwrap_or(0),
        sampler: overrides.sampler.or(render.sampler).unwrap_or_default(),
        antialias,
        time_limit: None,
        checkpoint: None,
        progress: false,
        layers: false,
    };
    scene.check_usable().map_err(|message| SceneError::File { path: name.to_string(), message })?;
    Ok(LoadedScene {
        scene,
        settings,
        integrator: IntegratorConfig {
            kind: overrides.integrator.or(render.integrator).unwrap_or_default(),
            max_depth,
            light_samples: render.light_samples.unwrap_or(16).clamp(1, 4096),
            photon,
        },
        info,
    })
}

fn default_material(materials: &mut Vec<Material>, names: &mut Vec<String>, index: &mut HashMap<String, u32>) -> u32 {
    const NAME: &str = "(default)";
    if let Some(&i) = index.get(NAME) {
        return i;
    }
    let i = materials.len() as u32;
    materials.push(Material::default());
    names.push(NAME.into());
    index.insert(NAME.into(), i);
    i
}

/// Corner and edges of the six faces of a box, each with its normal (e1 x e2) pointing out.
pub(crate) fn box_faces(m: Vec3, mx: Vec3) -> [(Vec3, Vec3, Vec3); 6] {
    let e = mx - m;
    let (ex, ey, ez) = (Vec3::new(e.x, 0.0, 0.0), Vec3::new(0.0, e.y, 0.0), Vec3::new(0.0, 0.0, e.z));
    [
        (m, ez, ey),
        (Vec3::new(mx.x, m.y, m.z), ey, ez),
        (m, ex, ez),
        (Vec3::new(m.x, mx.y, m.z), ez, ex),
        (m, ey, ex),
        (Vec3::new(m.x, m.y, mx.z), ex, ey),
    ]
}

/// A quad moved by `t`; edges are swapped under a mirroring transform so the normal still points
/// to the side the untransformed normal did.
pub(crate) fn transformed_quad(t: &Transform, corner: Vec3, e1: Vec3, e2: Vec3) -> Option<Quad> {
    let (p0, a, b) = (t.point(corner), t.vector(e1), t.vector(e2));
    if t.m.determinant() < 0.0 { Quad::new(p0, b, a) } else { Quad::new(p0, a, b) }
}

/// The file being loaded, for error positions.
struct Cx<'a> {
    path: &'a str,
    text: &'a str,
    base: &'a Path,
}

impl<'a> Cx<'a> {
    fn at(&self, span: Range<usize>, message: impl Into<String>) -> SceneError {
        SceneError::at(self.path, self.text, span, message)
    }

    fn toml(&self, e: toml::de::Error) -> SceneError {
        let span = e.span().unwrap_or(0..0);
        let mut message = e.message().trim_end().to_string();
        if message.contains("wanted exactly 1 element") {
            message.push_str(" (each transform entry holds one operation: translate, rotate or scale)");
        }
        self.at(span, message)
    }

    fn de<'i, T: Deserialize<'i>>(&self, v: Spanned<DeValue<'i>>) -> Result<T, SceneError> {
        T::deserialize(ValueDeserializer::from(v)).map_err(|e| self.toml(e))
    }

    fn array<'i>(&self, v: Spanned<DeValue<'i>>, what: &str) -> Result<Vec<Spanned<DeValue<'i>>>, SceneError> {
        let span = v.span();
        match v.into_inner() {
            DeValue::Array(a) => Ok(a.into_iter().collect()),
            _ => Err(self.at(span, format!("`{what}` must be an array of tables ([[{what}]])"))),
        }
    }

    /// Splits a table with a `type` key into (kind, the rest), checking the other keys against
    /// those `kinds` allows for that kind.
    fn tagged<'i>(
        &self,
        v: Spanned<DeValue<'i>>,
        what: &str,
        kinds: &[(&'static str, &[&str])],
    ) -> Result<(&'static str, Spanned<DeValue<'i>>), SceneError> {
        let span = v.span();
        let DeValue::Table(mut table) = v.into_inner() else {
            return Err(self.at(span, format!("expected a table describing a {what}")));
        };
        let names: Vec<&str> = kinds.iter().map(|k| k.0).collect();
        let Some(ty) = table.remove("type") else {
            return Err(self.at(span, format!("{what} has no `type`; expected one of: {}", names.join(", "))));
        };
        let ty_span = ty.span();
        let Some(ty_str) = ty.get_ref().as_str() else {
            return Err(self.at(ty_span, format!("`type` must be a string, one of: {}", names.join(", "))));
        };
        let Some((kind, allowed)) = kinds.iter().find(|k| k.0 == ty_str) else {
            return Err(
                self.at(ty_span, format!("unknown {what} type `{ty_str}`; expected one of: {}", names.join(", ")))
            );
        };
        for key in table.keys() {
            let k: &DeString = key.get_ref();
            if !allowed.contains(&k.as_ref()) {
                return Err(self.at(
                    key.span(),
                    format!("unknown key `{k}` for a {kind} {what}; expected one of: type, {}", allowed.join(", ")),
                ));
            }
        }
        Ok((kind, Spanned::new(span, DeValue::Table(table))))
    }
}

const MATERIAL_KINDS: &[(&str, &[&str])] = &[
    ("diffuse", &["color", "ka", "kd", "ks", "exponent"]),
    ("reflective", &["color", "ka", "kd", "ks", "exponent", "kr"]),
    ("transparent", &["color", "ka", "kd", "ks", "exponent", "kr", "kt", "ior"]),
    ("dielectric", &["color", "ka", "kd", "ks", "exponent", "ior"]),
];

const LIGHT_KINDS: &[(&str, &[&str])] = &[
    ("point", &["position", "color", "intensity"]),
    ("spot", &["position", "direction", "look_at", "angle", "falloff", "color", "intensity"]),
    ("directional", &["direction", "color", "intensity"]),
    ("area", &["shape", "corner", "edge1", "edge2", "center", "radius", "transform", "color", "intensity"]),
];

const OBJECT_KINDS: &[(&str, &[&str])] = &[
    ("sphere", &["material", "transform", "center", "radius"]),
    ("plane", &["material", "transform", "point", "normal"]),
    ("quad", &["material", "transform", "corner", "edge1", "edge2"]),
    ("box", &["material", "transform", "min", "max"]),
    ("mesh", &["material", "transform", "file"]),
    ("torus_knot", &["material", "transform", "p", "q", "radius", "tube", "segments", "sides"]),
];

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RenderDesc {
    width: Option<u32>,
    height: Option<u32>,
    spp_axis: Option<u32>,
    spp: Option<u32>,
    max_depth: Option<u32>,
    seed: Option<u64>,
    integrator: Option<IntegratorKind>,
    sampler: Option<SamplerKind>,
    antialias: Option<bool>,
    background: Option<Rgb>,
    ambient: Option<Rgb>,
    ray_bias: Option<NonNegative>,
    transparent_shadows: Option<bool>,
    light_samples: Option<u32>,
    /// Photon-mapping settings.
    #[serde(default)]
    photon: crate::integrator::PhotonOptions,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraDesc {
    eye: Point,
    look_at: Point,
    up: Option<Direction>,
    fov: Option<Positive>,
    view_distance: Option<Positive>,
    lens_radius: Option<NonNegative>,
    focal_distance: Option<Positive>,
    focus_on: Option<Point>,
}

impl CameraDesc {
    fn build(&self, cx: &Cx, span: Range<usize>, width: u32, height: u32) -> Result<Camera, SceneError> {
        let (eye, look_at) = (self.eye.0, self.look_at.0);
        let up = self.up.map_or(Vec3::Y, |u| u.0);
        let w = (eye - look_at).normalize_or_zero();
        if w == Vec3::ZERO {
            return Err(cx.at(span, "camera `eye` and `look_at` are the same point"));
        }
        if up.cross(w).length() < 1e-6 {
            return Err(cx.at(span, "camera `up` is parallel to the viewing direction"));
        }
        let view = match (self.fov, self.view_distance) {
            (Some(_), Some(_)) => return Err(cx.at(span, "give either `fov` or `view_distance`, not both")),
            (Some(f), None) if f.0 >= 180.0 => {
                return Err(cx.at(span, format!("fov must be below 180 degrees, got {}", f.0)));
            }
            (Some(f), None) => ViewPlane::Fov(f.0),
            (None, Some(d)) => ViewPlane::Distance(d.0),
            (None, None) => ViewPlane::Fov(45.0),
        };
        let focal_distance = match (self.focal_distance, self.focus_on) {
            (Some(_), Some(_)) => return Err(cx.at(span, "give either `focal_distance` or `focus_on`, not both")),
            (Some(f), None) => f.0,
            (None, Some(p)) => {
                // Distance of the point from the lens along the viewing axis.
                let f = (p.0 - eye).dot(-w);
                if !(f > 0.0) {
                    return Err(cx.at(span, "`focus_on` is not in front of the camera"));
                }
                f
            }
            (None, None) => (look_at - eye).length(),
        };
        Ok(Camera::new(eye, look_at, up, view, width, height, self.lens_radius.map_or(0.0, |r| r.0), focal_distance))
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialDesc {
    color: Option<Rgb>,
    ka: Option<NonNegative>,
    kd: Option<NonNegative>,
    ks: Option<NonNegative>,
    exponent: Option<NonNegative>,
    kr: Option<Unit>,
    kt: Option<Unit>,
    ior: Option<Positive>,
}

impl MaterialDesc {
    fn build(&self, kind: &str) -> Material {
        let d = Material::default();
        let kind = match kind {
            "diffuse" => MaterialKind::Diffuse,
            "reflective" => MaterialKind::Reflective,
            "transparent" => MaterialKind::Transparent,
            _ => MaterialKind::Dielectric,
        };
        // Glass defaults to no diffuse term: all its light comes from reflection and refraction.
        let clear = kind == MaterialKind::Dielectric || kind == MaterialKind::Transparent;
        Material {
            kind,
            color: self.color.map_or(if clear { Color::ONE } else { d.color }, |c| c.0),
            ka: self.ka.map_or(if clear { 0.0 } else { d.ka }, |v| v.0),
            kd: self.kd.map_or(if clear { 0.0 } else { d.kd }, |v| v.0),
            ks: self.ks.map_or(d.ks, |v| v.0),
            exponent: self.exponent.map_or(d.exponent, |v| v.0),
            kr: self.kr.map_or(
                match kind {
                    MaterialKind::Reflective => 0.5,
                    MaterialKind::Transparent => 0.1,
                    _ => 0.0,
                },
                |v| v.0,
            ),
            kt: self.kt.map_or(if kind == MaterialKind::Transparent { 0.9 } else { 0.0 }, |v| v.0),
            ior: self.ior.map_or(d.ior, |v| v.0),
            ..d
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightDesc {
    position: Option<Point>,
    direction: Option<Direction>,
    look_at: Option<Point>,
    /// Spot cone half-angle and the half-angle where the fall-off starts, in degrees.
    angle: Option<Positive>,
    falloff: Option<NonNegative>,
    color: Option<Rgb>,
    intensity: Option<NonNegative>,
    shape: Option<String>,
    corner: Option<Point>,
    edge1: Option<Point>,
    edge2: Option<Point>,
    center: Option<Point>,
    radius: Option<Positive>,
    transform: Option<Vec<TransformOp>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename_all = "lowercase")]
enum TransformOp {
    Translate(Point),
    Rotate(Rotation),
    Scale(Scale),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Rotation {
    axis: Direction,
    degrees: Finite,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectDesc {
    material: Option<Spanned<String>>,
    transform: Option<Vec<TransformOp>>,
    center: Option<Point>,
    radius: Option<Positive>,
    point: Option<Point>,
    normal: Option<Direction>,
    corner: Option<Point>,
    edge1: Option<Point>,
    edge2: Option<Point>,
    min: Option<Point>,
    max: Option<Point>,
    file: Option<Spanned<PathBuf>>,
    p: Option<u32>,
    q: Option<u32>,
    tube: Option<Positive>,
    segments: Option<u32>,
    sides: Option<u32>,
}

impl ObjectDesc {
    fn transform(&self, cx: &Cx, span: Range<usize>) -> Result<Transform, SceneError> {
        transform_of(&self.transform, cx, span)
    }
}

/// A transform list's operations composed in the order listed.
fn transform_of(ops: &Option<Vec<TransformOp>>, cx: &Cx, span: Range<usize>) -> Result<Transform, SceneError> {
    let mut t = Transform::IDENTITY;
    for op in ops.iter().flatten() {
        t = t.then(match op {
            TransformOp::Translate(v) => Transform::translate(v.0),
            TransformOp::Rotate(r) => Transform::rotate(r.axis.0, r.degrees.0),
            TransformOp::Scale(s) => Transform::scale(s.0),
        });
    }
    if !t.is_valid() {
        return Err(cx.at(span, "transform is singular or not finite"));
    }
    Ok(t)
}
