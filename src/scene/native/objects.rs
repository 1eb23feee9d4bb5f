//! The `[[lights]]` and `[[objects]]` sections of a TOML scene: each entry checked and added to
//! the scene builder.

use super::Cx;
use super::materials::{MaterialNames, TextureNames};
use super::media::MediumNames;
use super::schema::{self, LightDesc, ObjectDesc, TransformOp};
use crate::geometry::Transform;
use crate::light::{Environment, Light, NO_TEXTURE, PhotonDisk, Spot};
use crate::math::{Color, Vec3};
use crate::scene::SceneError;
use crate::scene::builder::SceneBuilder;
use crate::scene::environment::environment_map;
use crate::scene::footprint::FileKind;
use crate::shape::mesh::MeshFormat;
use crate::shape::{Cylinder, Disk, Plane, Shape, Sphere, TriangleMesh, box_faces, transformed_quad};
use crate::texture::image::load_image;
use std::collections::HashMap;
use std::ops::Range;
use toml::Spanned;
use toml::de::DeValue;

/// Largest procedural mesh, in triangles.
const MAX_GENERATED_TRIANGLES: u64 = 50_000_000;

impl<'a> Cx<'a> {
    /// Step 4: lights, in the order written.
    pub(super) fn lights(&self, value: Spanned<DeValue<'a>>, geometry: &mut SceneBuilder) -> Result<(), SceneError> {
        for value in self.array(value, "lights")? {
            let span = value.span();
            let (kind, value) = self.tagged(value, "light", schema::LIGHT_KINDS)?;
            if kind == "area" {
                self.check_area_keys(&value)?;
            }
            let d: LightDesc = self.de(value)?;
            self.light(kind, &d, span, geometry)?;
        }
        Ok(())
    }

    /// An area light takes the keys of its shape only: a key of the other shape is an error at
    /// its place, not silently ignored.
    fn check_area_keys(&self, value: &Spanned<DeValue<'a>>) -> Result<(), SceneError> {
        let DeValue::Table(table) = value.get_ref() else { return Ok(()) };
        let shape = table.get("shape").and_then(|v| v.get_ref().as_str()).unwrap_or("quad");
        let (own, other): (&[&str], &[&str]) = match shape {
            "sphere" => (schema::AREA_SPHERE_KEYS, schema::AREA_QUAD_KEYS),
            "quad" => (schema::AREA_QUAD_KEYS, schema::AREA_SPHERE_KEYS),
            _ => return Ok(()),
        };
        for key in table.keys() {
            let k: &str = key.get_ref();
            if other.contains(&k) && !own.contains(&k) {
                return Err(self.at(
                    key.span(),
                    format!(
                        "`{k}` is not a key of a {shape} area light; it takes: shape, {}, transform, color, intensity",
                        own.join(", ")
                    ),
                ));
            }
        }
        Ok(())
    }

    fn light(
        &self,
        kind: &str,
        d: &LightDesc,
        span: Range<usize>,
        geometry: &mut SceneBuilder,
    ) -> Result<(), SceneError> {
        let (color, spectrum) = self.emitted(d.color.as_ref())?;
        let color = color.unwrap_or(Color::ONE);
        let power = color * d.intensity.map_or(1.0, |i| i.0);
        let first = geometry.light_count();
        match kind {
            "point" => {
                geometry.add_light(Light::Point { position: d.position.map_or(Vec3::ZERO, |p| p.0), intensity: power })
            }
            "spot" => {
                let position = d.position.map_or(Vec3::ZERO, |p| p.0);
                let direction = match (d.direction, d.look_at) {
                    (Some(_), Some(_)) => {
                        return Err(self.at(span, "give either `direction` or `look_at`, not both"));
                    }
                    (Some(dir), None) => dir.0,
                    (None, Some(t)) => (t.0 - position)
                        .try_normalize()
                        .ok_or_else(|| self.at(span.clone(), "spot light `look_at` is the light's own position"))?,
                    (None, None) => -Vec3::Y,
                };
                let angle = d.angle.map_or(30.0, |a| a.0);
                let falloff = d.falloff.map_or(angle * 0.75, |a| a.0);
                if angle > 90.0 || falloff > angle {
                    return Err(self.at(
                        span,
                        format!(
                            "spot light needs falloff <= angle <= 90 degrees (got falloff {falloff}, angle {angle})"
                        ),
                    ));
                }
                // The texture's up is +y (or +z for a spot shining straight up or down), as a
                // camera's: image x runs along up x direction.
                let up = if direction.cross(Vec3::Y).length_squared() > 1e-6 { Vec3::Y } else { Vec3::Z };
                let x = up.cross(direction).normalize();
                let frame = crate::math::Frame { x, y: direction.cross(x), z: direction };
                geometry.add_light(Light::Spot(Spot::new(position, frame, power, angle, falloff, NO_TEXTURE)));
            }
            "directional" => geometry.add_light(Light::Directional {
                direction: d.direction.map_or(-Vec3::Y, |p| p.0),
                irradiance: power,
                disk: PhotonDisk::default(),
            }),
            "constant" => {
                geometry.set_environment(Environment::constant(power)).map_err(|e| self.at(span, e))?;
            }
            "envmap" => {
                let Some(file) = &d.file else {
                    return Err(self.at(span, "an envmap light needs `file`, the lat-long image (EXR, HDR, PNG...)"));
                };
                let path = self.base.join(file.get_ref());
                self.files.open(&path, FileKind::Image)?;
                let image = load_image(&path, false).map_err(|e| self.at(file.span(), e.to_string()))?;
                let transform = self.transform(&d.transform, span.clone())?;
                let env = environment_map(&image, d.scale.map_or(1.0, |s| s.0), &transform)
                    .map_err(|e| self.at(span.clone(), e))?;
                geometry.set_environment(env).map_err(|e| self.at(span, e))?;
            }
            _ => {
                let transform = self.transform(&d.transform, span.clone())?;
                let emitter = match d.shape.as_deref().unwrap_or("quad") {
                    "quad" => {
                        // Default: a 1 x 1 square facing down, as a ceiling light.
                        let corner = d.corner.map_or(Vec3::new(-0.5, 0.0, -0.5), |p| p.0);
                        let e1 = d.edge1.map_or(Vec3::new(1.0, 0.0, 0.0), |p| p.0);
                        let e2 = d.edge2.map_or(Vec3::new(0.0, 0.0, 1.0), |p| p.0);
                        let q = transformed_quad(&transform, corner, e1, e2).ok_or_else(|| {
                            self.at(span.clone(), "area light quad edges are parallel or zero: it has no area")
                        })?;
                        Shape::Quad(q)
                    }
                    "sphere" => {
                        if !transform.is_similarity() {
                            return Err(
                                self.at(span, "a spherical light can only be translated, rotated and scaled uniformly")
                            );
                        }
                        let center = d.center.map_or(Vec3::ZERO, |p| p.0);
                        Shape::Sphere(Sphere::transformed(&transform, center, d.radius.map_or(0.5, |r| r.0)).0)
                    }
                    other => {
                        return Err(
                            self.at(span, format!("unknown area light shape `{other}`; expected quad or sphere"))
                        );
                    }
                };
                geometry.add_area_light(emitter, power, None);
            }
        }
        geometry.keep_emission_spectrum((kind != "constant").then_some(first), spectrum, color);
        Ok(())
    }

    /// Step 5a: groups of objects placed by instances (`[groups.NAME]` with `objects`), each
    /// built once in its own space. Returns their indices by name.
    pub(super) fn groups(
        &self,
        value: Spanned<DeValue<'a>>,
        names: &MaterialNames,
        media: &MediumNames,
        geometry: &mut SceneBuilder,
    ) -> Result<HashMap<String, u32>, SceneError> {
        let span = value.span();
        let DeValue::Table(table) = value.into_inner() else {
            return Err(self.at(span, "`groups` must be a table of named groups ([groups.NAME] with `objects`)"));
        };
        let mut out = HashMap::new();
        for (name, value) in table {
            let name_span = name.span();
            let name = name.get_ref().to_string();
            let span = value.span();
            let DeValue::Table(mut group) = value.into_inner() else {
                return Err(self.at(span, format!("group `{name}` must be a table holding `objects`")));
            };
            if let Some(key) = group.keys().find(|k| k.get_ref() != "objects") {
                return Err(self.at(
                    key.span(),
                    format!("unknown key `{}` in group `{name}`; a group holds only `objects`", key.get_ref()),
                ));
            }
            let Some(objects) = group.remove("objects") else {
                return Err(self.at(name_span, format!("group `{name}` has no `objects` ([[groups.{name}.objects]])")));
            };
            let index = geometry.begin_group().map_err(|e| self.at(span.clone(), e))?;
            for value in self.array(objects, "objects")? {
                self.object_entry(value, names, &TextureNames::new(), media, None, geometry)?;
            }
            geometry.end_group();
            if geometry.group_len(index) == 0 {
                return Err(self.at(name_span, format!("group `{name}` has no objects")));
            }
            out.insert(name, index);
        }
        Ok(out)
    }

    /// Step 5b: objects, each with its material, and instances of groups.
    pub(super) fn objects(
        &self,
        value: Spanned<DeValue<'a>>,
        names: &MaterialNames,
        textures: &TextureNames,
        media: &MediumNames,
        groups: &HashMap<String, u32>,
        geometry: &mut SceneBuilder,
    ) -> Result<(), SceneError> {
        for value in self.array(value, "objects")? {
            self.object_entry(value, names, textures, media, Some(groups), geometry)?;
        }
        Ok(())
    }

    /// One `[[objects]]` entry; `groups` is `None` inside a group, where instances and planes
    /// are refused.
    fn object_entry(
        &self,
        value: Spanned<DeValue<'a>>,
        names: &MaterialNames,
        textures: &TextureNames,
        media: &MediumNames,
        groups: Option<&HashMap<String, u32>>,
        geometry: &mut SceneBuilder,
    ) -> Result<(), SceneError> {
        let span = value.span();
        let (kind, value) = self.tagged(value, "object", schema::OBJECT_KINDS)?;
        let d: ObjectDesc = self.de(value)?;
        let transform = self.transform(&d.transform, span.clone())?;
        match (kind, groups) {
            ("instance", Some(groups)) => return self.instance(&d, &transform, span, groups, geometry),
            ("instance", None) => return Err(self.at(span, "a group cannot hold instances (groups do not nest)")),
            ("plane", None) => {
                return Err(self.at(span, "a plane is unbounded and cannot be in a group; put it in [[objects]]"));
            }
            _ => {}
        }
        let material = self.material_of(d.material.as_ref(), names, geometry)?;
        // An object bounding media carries them on its material.
        let material = match self.interface(media, d.interior.as_ref(), d.exterior.as_ref())? {
            Some(i) => geometry.with_interface(material, i),
            None => material,
        };
        let (emission, spectrum) = self.emission(&d, textures)?;
        if emission.is_some() && groups.is_none() {
            return Err(self.at(
                span,
                "an object in a group cannot emit (instanced emitters are not supported, as in Mitsuba): put it in [[objects]]",
            ));
        }
        let first = geometry.light_count();
        self.object(kind, &d, &transform, span, Surface { material, emission }, geometry)?;
        // (A textured emission is lifted texel by texel: its spectrum would stand for one colour.)
        if let Some((color, None)) = emission {
            geometry.keep_emission_spectrum(Some(first), spectrum, color);
        }
        Ok(())
    }

    /// What object `d` emits: `emission` (1 when only a texture is given) times its
    /// `emission_texture`; `None` when it emits nothing.
    /// With it, the spectrum `emission` was written as (for spectral mode).
    fn emission(
        &self,
        d: &ObjectDesc,
        textures: &TextureNames,
    ) -> Result<(Emission, Option<crate::spectrum::SampledSpectrum>), SceneError> {
        let texture = match &d.emission_texture {
            Some(n) => Some(self.texture_index(textures, n.get_ref(), n.span())?),
            None => None,
        };
        let (radiance, spectrum) = self.emitted(d.emission.as_ref())?;
        let emission = match (radiance, texture) {
            (None, None) => None,
            (Some(c), None) => (c.max_element() > 0.0).then_some((c, None)),
            (c, Some(t)) => Some((c.unwrap_or(Color::ONE), Some(t))),
        };
        Ok((emission, spectrum))
    }

    fn instance(
        &self,
        d: &ObjectDesc,
        transform: &Transform,
        span: Range<usize>,
        groups: &HashMap<String, u32>,
        geometry: &mut SceneBuilder,
    ) -> Result<(), SceneError> {
        let Some(name) = &d.group else {
            return Err(self.at(span, "an instance needs `group`, the name of a [groups.NAME] table"));
        };
        let Some(&g) = groups.get(name.get_ref().as_str()) else {
            let known = groups.keys().map(String::as_str).collect();
            return Err(self.at(name.span(), super::no_such("group", name.get_ref(), known)));
        };
        geometry.add_instance(g, transform).map_err(|e| e.placed(|m| self.at(span, m)))
    }

    fn object(
        &self,
        kind: &str,
        d: &ObjectDesc,
        transform: &Transform,
        span: Range<usize>,
        surface: Surface,
        geometry: &mut SceneBuilder,
    ) -> Result<(), SceneError> {
        let Surface { material, emission } = surface;
        match kind {
            "sphere" => {
                if !transform.is_similarity() {
                    return Err(self.at(
                        span,
                        "a sphere can only be translated, rotated and scaled uniformly; use a mesh for an ellipsoid",
                    ));
                }
                let center = d.center.map_or(Vec3::ZERO, |p| p.0);
                let (sphere, _) = Sphere::transformed(transform, center, d.radius.map_or(1.0, |r| r.0));
                if !(sphere.radius > 0.0 && sphere.radius.is_finite() && sphere.center.is_finite()) {
                    return Err(self.at(span, "sphere is degenerate after its transform"));
                }
                add_shapes(geometry, vec![Shape::Sphere(sphere)], surface, d);
            }
            "plane" => {
                let point = transform.point(d.point.map_or(Vec3::ZERO, |p| p.0));
                let normal = transform.normal(d.normal.map_or(Vec3::Y, |n| n.0)).normalize_or_zero();
                if normal == Vec3::ZERO || !point.is_finite() {
                    return Err(self.at(span, "plane is degenerate after its transform"));
                }
                geometry.add_plane(Plane::new(point, normal), material);
            }
            "quad" => {
                let corner = d.corner.map_or(Vec3::new(-1.0, 0.0, 1.0), |p| p.0);
                let e1 = d.edge1.map_or(Vec3::new(2.0, 0.0, 0.0), |p| p.0);
                let e2 = d.edge2.map_or(Vec3::new(0.0, 0.0, -2.0), |p| p.0);
                let q = transformed_quad(transform, corner, e1, e2)
                    .ok_or_else(|| self.at(span, "quad edges are parallel or zero: it has no area"))?;
                add_shapes(geometry, vec![Shape::Quad(q)], surface, d);
            }
            "box" => {
                let min = d.min.map_or(Vec3::splat(-1.0), |p| p.0);
                let max = d.max.map_or(Vec3::splat(1.0), |p| p.0);
                if !(min.cmplt(max).all()) {
                    return Err(self.at(span, format!("box `min` {min} must be below `max` {max} on every axis")));
                }
                let mut faces = Vec::with_capacity(6);
                for (c, e1, e2) in box_faces(min, max) {
                    let q = transformed_quad(transform, c, e1, e2)
                        .ok_or_else(|| self.at(span.clone(), "box is degenerate after its transform"))?;
                    faces.push(Shape::Quad(q));
                }
                add_shapes(geometry, faces, surface, d);
            }
            "cylinder" => {
                let p0 = d.p0.map_or(Vec3::ZERO, |p| p.0);
                let p1 = d.p1.map_or(Vec3::Y, |p| p.0);
                let (c, uneven) = Cylinder::from_mitsuba(p0, p1, d.radius.map_or(1.0, |r| r.0), transform, false)
                    .map_err(|e| self.at(span.clone(), e))?;
                if uneven.is_some() {
                    return Err(self.at(
                        span,
                        "a cylinder can only be translated, rotated and scaled uniformly across its axis; use a mesh for an elliptic one",
                    ));
                }
                add_shapes(geometry, vec![Shape::Cylinder(c)], surface, d);
            }
            "disk" => {
                let center = d.center.map_or(Vec3::ZERO, |p| p.0);
                let normal = d.normal.map_or(Vec3::Y, |n| n.0);
                let disk = Disk::facing(center, normal, d.radius.map_or(1.0, |r| r.0), transform)
                    .ok_or_else(|| self.at(span, "disk is degenerate after its transform"))?;
                add_shapes(geometry, vec![Shape::Disk(disk)], surface, d);
            }
            "mesh" | "torus_knot" => {
                let mesh = if kind == "mesh" {
                    let file = d
                        .file
                        .as_ref()
                        .ok_or_else(|| self.at(span.clone(), "a mesh needs `file` (an OBJ, PLY or serialized file)"))?;
                    let path = self.base.join(file.get_ref());
                    // A name of no mesh format is refused by `load` without opening the file.
                    if let Some(format) = MeshFormat::of(&path) {
                        self.files.open(&path, FileKind::Mesh(format))?;
                    }
                    TriangleMesh::load(&path).map_err(|e| self.at(file.span(), e.to_string()))?
                } else {
                    let (segments, sides) = (d.segments.unwrap_or(256), d.sides.unwrap_or(32));
                    if segments < 3 || sides < 3 || 2 * segments as u64 * sides as u64 > MAX_GENERATED_TRIANGLES {
                        return Err(self.at(span, format!("torus_knot needs segments >= 3 and sides >= 3 and at most {MAX_GENERATED_TRIANGLES} triangles")));
                    }
                    let (p, q) = (d.p.unwrap_or(2), d.q.unwrap_or(3));
                    if p == 0 || q == 0 || p > 1000 || q > 1000 {
                        return Err(self.at(span, "torus_knot p and q must be from 1 to 1000"));
                    }
                    let (radius, tube) = (d.radius.map_or(1.0, |r| r.0), d.tube.map_or(0.25, |t| t.0));
                    let vertices = segments as u64 * sides as u64;
                    geometry.reserve_generated_mesh("torus_knot", vertices, 2 * vertices)?;
                    TriangleMesh::torus_knot(p, q, radius, tube, segments, sides)
                };
                let mut mesh = mesh.transformed(transform);
                if transform.m.determinant() < 0.0 {
                    // A mirroring transform reverses winding; swap to keep the outward side.
                    for t in &mut mesh.indices {
                        t.swap(1, 2);
                    }
                }
                if mesh.positions.iter().any(|p| !p.is_finite()) {
                    return Err(self.at(span, "mesh has non-finite vertices after its transform"));
                }
                // Flat faces only when asked; otherwise smooth normals where the file has none.
                if d.face_normals == Some(true) {
                    mesh.normals = None;
                } else {
                    mesh.ensure_vertex_normals();
                }
                let name = match &d.file {
                    Some(f) => f.get_ref().display().to_string(),
                    None => "torus_knot".to_string(),
                };
                match emission {
                    Some((radiance, texture)) => {
                        if !SceneBuilder::mesh_can_emit(&mesh) {
                            return Err(self.at(span, "an emitting mesh has no triangle with an area"));
                        }
                        let surface = d.material.as_ref().map(|_| *geometry.material(material));
                        geometry.add_mesh_area_lights(&mesh, radiance, texture, surface);
                    }
                    None => geometry.add_mesh(mesh, material, &name),
                }
            }
            _ => unreachable!("kind checked by tagged()"),
        }
        Ok(())
    }

    /// A transform list's operations composed in the order listed.
    pub(super) fn transform(
        &self,
        ops: &Option<Vec<TransformOp>>,
        span: Range<usize>,
    ) -> Result<Transform, SceneError> {
        let mut t = Transform::IDENTITY;
        for op in ops.iter().flatten() {
            t = t.then(match op {
                TransformOp::Translate(v) => Transform::translate(v.0),
                TransformOp::Rotate(r) => Transform::rotate(r.axis.0, r.degrees.0),
                TransformOp::Scale(s) => Transform::scale(s.0),
            });
        }
        if !t.is_valid() {
            return Err(self.at(span, "transform is singular or not finite"));
        }
        Ok(t)
    }
}

/// Adds an object's shapes, as area lights when it emits (`emission`): an emitting object
/// reflects with the material it names, and is a plain (black) emitter when it names none.
fn add_shapes(geometry: &mut SceneBuilder, shapes: Vec<Shape>, surface: Surface, d: &ObjectDesc) {
    let Surface { material, emission } = surface;
    let Some((radiance, texture)) = emission else {
        geometry.add_object(shapes, material);
        return;
    };
    let surface = d.material.as_ref().map(|_| *geometry.material(material));
    geometry.add_area_lights(shapes, radiance, texture, surface);
}

/// What an object emits: radiance and an optional texture multiplying it; `None` when dark.
type Emission = Option<(Color, Option<u32>)>;

/// An object's material and what it emits.
#[derive(Clone, Copy)]
struct Surface {
    material: u32,
    emission: Emission,
}
