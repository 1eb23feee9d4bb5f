//! Mitsuba shapes: rectangles, cubes, spheres, disks, cylinders and OBJ/PLY/serialized meshes,
//! with their nested area emitters and BSDFs; shape groups and their instances.

use super::Build;
use super::plugins::PluginKind;
use super::props::Cx;
use super::xml::El;
use crate::geometry::Transform;
use crate::math::{Color, Vec3};
use crate::scene::builder::SceneBuilder;
use crate::scene::{FileKind, SceneError};
use crate::shape::mesh::MeshFormat;
use crate::shape::{Cylinder, Disk, Quad, Shape, Sphere, TriangleMesh, box_faces, transformed_quad};

impl<'a> Cx<'a> {
    /// Reads a shape and adds its geometry (or, for an emitting shape, its area lights).
    pub(super) fn shape(&mut self, el: &'a El, b: &mut Build) -> Result<(), SceneError> {
        let p = self.props(el)?;
        match p.kind.as_str() {
            "shapegroup" => return self.shapegroup(el, b).map(|_| ()),
            "instance" => return self.instance(el, b),
            _ => {}
        }
        let to_world = self.transform(&p, "to_world")?.map_or(Transform::IDENTITY, |x| x.t);
        let flip = self.boolean(&p, "flip_normals")?.unwrap_or(false);

        // A nested area emitter.
        let emitters = self.object(&p, None, "emitter");
        let mut radiance = None;
        // The emitter's radiance given as a spectrum (for spectral mode).
        let mut spectrum = None;
        let first_light = b.geometry.light_count();
        for &(eel, at) in &emitters {
            let ep = self.props(eel)?;
            if ep.kind != "area" {
                return Err(
                    self.err(at, format!("an emitter inside a shape must be type=\"area\", found `{}`", ep.kind))
                );
            }
            if radiance.is_some() {
                return Err(self.err(at, "a shape can have only one area emitter"));
            }
            if b.geometry.in_group() {
                return Err(self.err(
                    at,
                    "emitters inside a shapegroup are not supported (Mitsuba refuses them too: instancing of emitters)",
                ));
            }
            self.given_spectrum = None;
            let param = self.color_param_for(&ep, "radiance", b, crate::spectrum::SpectrumUse::Emission)?;
            spectrum = self.given_spectrum.take();
            radiance = Some(match param {
                None => (Color::ONE, None),
                Some(crate::material::Param::Const(c)) => (c, None),
                Some(crate::material::Param::Texture(t)) => {
                    if let crate::texture::Texture::MeshAttribute { name, .. } = &b.geometry.textures()[t as usize] {
                        return Err(self.err(at, format!("mesh attribute `{name}` cannot be emitted radiance here")));
                    }
                    (Color::ONE, Some(t))
                }
            });
            self.finish(&ep)?;
        }
        // Material: a nested or referenced <bsdf>, or Mitsuba's default. A `null` BSDF is an
        // invisible surface: only its emission (if any) is kept.
        let bsdfs = self.object(&p, None, "bsdf");
        if bsdfs.len() > 1 {
            self.warn(bsdfs[1].1, "a shape has one BSDF: the first is used")?;
        }
        let bsdf_el = bsdfs.first().map(|b| b.0);
        let is_null = match bsdf_el {
            Some(bel) => self.attr(bel, "type")?.is_some_and(|t| t.0 == "null"),
            None => false,
        };
        // The media inside and outside the shape: its material carries them. A `null` shape
        // that bounds a medium is an invisible surface; without media it is left out.
        let interface = self.medium_interface(&p, b)?;
        let material = match bsdf_el {
            _ if is_null => interface.map(|_| b.geometry.null_material()),
            Some(bel) => Some(self.material(bel, b)?),
            None => Some(self.default_material(b, radiance.is_some())),
        };
        let material = match (material, interface) {
            (Some(m), Some(i)) => Some(b.geometry.with_interface(m, i)),
            (m, _) => m,
        };
        // Other nested objects are reported by `finish`.

        let kind = p.kind.clone();
        // Shapes that can emit (a light each when the shape has an area emitter).
        let mut emitters_out: Vec<Shape> = Vec::new();
        // An emitting mesh: a light per triangle.
        let mut emitting_mesh = None;
        // Shapes that cannot emit yet.
        let mut plain_out: Vec<Shape> = Vec::new();
        let mut mesh_out = None;
        // A signed distance grid: its voxels and the transform from its index space.
        let mut sdf_out = None;
        match kind.as_str() {
            "sdfgrid" => {
                if radiance.is_some() {
                    return Err(self.err(el, "an sdfgrid cannot be an area emitter (nor can it in Mitsuba)"));
                }
                if b.geometry.in_group() {
                    return Err(self.err(
                        el,
                        "an sdfgrid inside a shapegroup is not supported: instance the sdfgrid's group instead",
                    ));
                }
                let (file, fel) = self
                    .string(&p, "filename")?
                    .ok_or_else(|| self.err(el, "an sdfgrid needs <string name=\"filename\" value=\"...vol\"/> (a `grid` tensor is Python-only)"))?;
                let path = self.resolve_file(fel, &file)?;
                self.files.open(&path, FileKind::Volume)?;
                let bytes = std::fs::read(&path)
                    .map_err(|e| self.err(fel, format!("cannot read `{}`: {e}", path.display())))?;
                let grid = crate::shape::sdf::parse_vol(&bytes)
                    .map_err(|e| self.err(fel, format!("SDF grid `{}`: {e}", path.display())))?;
                match self.string(&p, "normals")? {
                    None => self.warn(el, "sdfgrid `smooth` normals (Mitsuba's default) are approximated by the analytic ones here: give <string name=\"normals\" value=\"analytic\"/> to match Mitsuba exactly")?,
                    Some((n, _)) if n == "analytic" => {}
                    Some((n, nel)) if n == "smooth" => self.warn(nel, "sdfgrid `smooth` normals are approximated by the analytic ones here")?,
                    Some((n, nel)) => return Err(self.err(nel, format!("sdfgrid `normals` must be `analytic` or `smooth`, found `{n}`"))),
                }
                let voxels: Vec<Shape> = grid.voxels().map(Shape::SdfVoxel).collect();
                if voxels.is_empty() {
                    return Err(self.err(
                        el,
                        format!("SDF grid `{file}` has no voxel the surface passes through (no value changes sign)"),
                    ));
                }
                let index_to_object = Transform::scale(Vec3::new(
                    1.0 / (grid.nx - 1) as f32,
                    1.0 / (grid.ny - 1) as f32,
                    1.0 / (grid.nz - 1) as f32,
                ));
                sdf_out = Some((voxels, index_to_object.then(to_world)));
            }
            "rectangle" => {
                let (c, e1, e2) = (Vec3::new(-1.0, -1.0, 0.0), Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 2.0, 0.0));
                let q =
                    if flip { transformed_quad(&to_world, c, e2, e1) } else { transformed_quad(&to_world, c, e1, e2) };
                let q = q.ok_or_else(|| self.err(el, "rectangle has no area after its to_world transform"))?;
                emitters_out.push(Shape::Quad(q));
            }
            "cube" => {
                for (c, e1, e2) in box_faces(Vec3::splat(-1.0), Vec3::ONE) {
                    let q = if flip {
                        transformed_quad(&to_world, c, e2, e1)
                    } else {
                        transformed_quad(&to_world, c, e1, e2)
                    };
                    let q = q.ok_or_else(|| self.err(el, "cube is degenerate after its to_world transform"))?;
                    emitters_out.push(Shape::Quad(q));
                }
            }
            "sphere" => {
                let center = self.point(&p, "center")?.unwrap_or(Vec3::ZERO);
                let radius = self.float(&p, "radius")?.unwrap_or(1.0);
                if !(radius > 0.0) {
                    return Err(self.err(el, format!("sphere radius must be positive, found {radius}")));
                }
                if !to_world.is_similarity() {
                    return Err(self.err(el, "a sphere's to_world can only translate, rotate and scale uniformly"));
                }
                if flip {
                    self.warn(el, "flip_normals on a sphere is not supported and is ignored")?;
                }
                let (sphere, proper) = Sphere::transformed(&to_world, center, radius);
                let (c, r) = (sphere.center, sphere.radius);
                if !(r > 0.0 && r.is_finite() && c.is_finite()) {
                    return Err(self.err(el, "sphere is degenerate after its to_world transform"));
                }
                if !proper {
                    self.warn(el, "a mirroring to_world on a sphere: its texture coordinates are not mirrored")?;
                }
                emitters_out.push(Shape::Sphere(sphere));
            }
            "disk" => {
                let d = Disk::from_transform(&to_world, flip)
                    .ok_or_else(|| self.err(el, "disk has no area after its to_world transform"))?;
                if radiance.is_some() {
                    emitters_out.push(Shape::Disk(d));
                } else {
                    plain_out.push(Shape::Disk(d));
                }
            }
            "cylinder" => {
                let p0 = self.point(&p, "p0")?.unwrap_or(Vec3::ZERO);
                let p1 = self.point(&p, "p1")?.unwrap_or(Vec3::Z);
                let radius = self.float(&p, "radius")?.unwrap_or(1.0);
                let (c, uneven) =
                    Cylinder::from_mitsuba(p0, p1, radius, &to_world, flip).map_err(|e| self.err(el, e))?;
                if let Some(w) = uneven {
                    self.warn(el, w)?;
                }
                if radiance.is_some() {
                    emitters_out.push(Shape::Cylinder(c));
                } else {
                    plain_out.push(Shape::Cylinder(c));
                }
            }
            "obj" | "ply" | "serialized" => {
                let (name, face_normals);
                let mesh = {
                    let (file, fel) = self.string(&p, "filename")?.ok_or_else(|| {
                        self.err(el, format!("a `{kind}` shape needs <string name=\"filename\" value=\"...\"/>"))
                    })?;
                    let path = self.resolve_file(fel, &file)?;
                    name = file.clone();
                    let format = match kind.as_str() {
                        "obj" => MeshFormat::Obj,
                        "ply" => MeshFormat::Ply,
                        _ => MeshFormat::Serialized,
                    };
                    let index = match format {
                        MeshFormat::Serialized => match self.integer(&p, "shape_index")? {
                            None => 0,
                            Some((i, iel)) => u32::try_from(i).map_err(|_| {
                                self.err(iel, format!("shape_index must be a whole number from 0, found {i}"))
                            })?,
                        },
                        MeshFormat::Obj | MeshFormat::Ply => 0,
                    };
                    self.files.open(&path, FileKind::Mesh(format))?;
                    let loaded = match format {
                        MeshFormat::Obj => TriangleMesh::load_obj(&path),
                        MeshFormat::Ply => crate::shape::mesh::load_ply(&path),
                        // The file's own face-normals flag (0x0010) is not used: Mitsuba 3.9.1
                        // ignores it too, whatever its format description says.
                        MeshFormat::Serialized => crate::shape::mesh::load_serialized(&path, index).map(|s| s.mesh),
                    };
                    let mut mesh = loaded.map_err(|e| self.err(fel, e.to_string()))?;
                    face_normals = self.boolean(&p, "face_normals")? == Some(true);
                    if face_normals {
                        mesh.normals = None;
                    }
                    // Our OBJ reader flips v as Mitsuba does by default; PLY is read as it is.
                    let flipped_on_read = kind == "obj";
                    if let Some(flip) = self.boolean(&p, "flip_tex_coords")?
                        && flip != flipped_on_read
                        && let Some(uvs) = &mut mesh.uvs
                    {
                        for t in uvs {
                            t.y = 1.0 - t.y;
                        }
                    }
                    mesh
                };
                let mut mesh = mesh.transformed(&to_world);
                if (to_world.m.determinant() < 0.0) != flip {
                    for t in &mut mesh.indices {
                        t.swap(1, 2);
                    }
                }
                if flip && let Some(ns) = &mut mesh.normals {
                    for n in ns {
                        *n = -*n;
                    }
                }
                if mesh.positions.iter().any(|v| !v.is_finite()) {
                    return Err(self.err(el, "mesh has non-finite vertices after its to_world transform"));
                }
                // Mitsuba computes smooth vertex normals unless `face_normals` is set.
                if !face_normals {
                    mesh.ensure_vertex_normals();
                }
                // An emitting mesh is a light per triangle (one parallelogram stays one quad
                // light, as the native format writes it).
                if let Some((_, texture)) = radiance {
                    // A textured parallelogram keeps its triangles: they carry its uv.
                    let quad = if texture.is_some() && mesh.uvs.is_some() { None } else { parallelogram(&mesh) };
                    match quad {
                        Some(q) => emitters_out.push(Shape::Quad(q)),
                        None if SceneBuilder::mesh_can_emit(&mesh) => emitting_mesh = Some(mesh),
                        None => return Err(self.err(el, "an emitting mesh has no triangle with an area")),
                    }
                } else {
                    mesh_out = Some((mesh, name));
                }
            }
            other => {
                self.unsupported(el, PluginKind::Shape, other, " and is skipped")?;
                for u in &p.used {
                    u.set(true);
                }
                self.finish(&p)?;
                return Ok(());
            }
        }

        if !plain_out.is_empty() && radiance.is_some() {
            self.warn(el, format!("area emitters on `{kind}` shapes are not supported yet: this shape does not emit"))?;
            radiance = None;
        }
        let Some(material) = material else {
            // A `null` BSDF: nothing to see, only the emission (if any).
            if let Some((radiance, texture)) = radiance {
                b.geometry.add_area_lights(emitters_out, radiance, texture, None);
                if let Some(mesh) = &emitting_mesh {
                    b.geometry.add_mesh_area_lights(mesh, radiance, texture, None);
                }
                b.geometry.keep_emission_spectrum(Some(first_light), spectrum, radiance);
            }
            return self.finish(&p);
        };
        let attributes = b.geometry.mesh_attributes_read(material);
        if !attributes.is_empty() {
            let names = attributes.join("`, `");
            if radiance.is_some() {
                return Err(self.err(el, format!("an emitting shape's BSDF cannot read mesh attributes (`{names}`)")));
            }
            if b.geometry.in_group() {
                return Err(self.err(el, format!("mesh attributes (`{names}`) are not supported inside a shapegroup")));
            }
            let Some((mesh, mesh_name)) = &mesh_out else {
                return Err(self.err(
                    el,
                    format!("a `{kind}` shape has no mesh attributes: `{names}` needs a PLY mesh that has them"),
                ));
            };
            for want in &attributes {
                if !mesh.attributes.iter().any(|a| &a.name == want) {
                    let have: Vec<&str> = mesh.attributes.iter().map(|a| a.name.as_str()).collect();
                    let have = if have.is_empty() { "none".to_string() } else { have.join(", ") };
                    return Err(self.err(el, format!("mesh `{mesh_name}` has no attribute `{want}` (it has: {have})")));
                }
            }
        }
        // A grid's voxels, in a group of their own placed by the grid's transform.
        if let Some((voxels, to_world)) = sdf_out {
            let group = b.geometry.begin_group().map_err(|e| self.err(el, e))?;
            b.geometry.add_object(voxels, material);
            b.geometry.end_group();
            b.geometry.add_instance(group, &to_world).map_err(|e| e.placed(|m| self.err(el, m)))?;
            return self.finish(&p);
        }
        let m = *b.geometry.material(material);
        if let Some((radiance, texture)) = radiance {
            // The emitter's surface keeps its BSDF (Mitsuba lights reflect too); a black one is
            // exactly our plain emitter material.
            let reflects = match m.model {
                crate::material::Model::Wrapper(_) => true,
                crate::material::Model::Plain(p) => !p
                    .lobes(
                        true,
                        crate::texture::TexPoint::uv(crate::math::Vec2::ZERO),
                        b.geometry.textures(),
                        &crate::material::GivenSpectra::NONE,
                    )
                    .is_empty(),
            };
            // The emitter's surface is a copy of its BSDF: it keeps the BSDF's spectra.
            let spectra = if reflects { b.geometry.material_spectra(material) } else { Default::default() };
            let surface = b.geometry.add_area_lights(emitters_out, radiance, texture, reflects.then_some(m));
            b.geometry.set_material_spectra(surface, spectra);
            if let Some(mesh) = &emitting_mesh {
                let surface = b.geometry.add_mesh_area_lights(mesh, radiance, texture, reflects.then_some(m));
                b.geometry.set_material_spectra(surface, spectra);
            }
            b.geometry.keep_emission_spectrum(Some(first_light), spectrum, radiance);
            return self.finish(&p);
        }
        if let Some((mesh, mesh_name)) = mesh_out {
            b.geometry.add_mesh(mesh, material, &mesh_name);
        }
        if !emitters_out.is_empty() {
            b.geometry.add_object(emitters_out, material);
        }
        if !plain_out.is_empty() {
            b.geometry.add_object(plain_out, material);
        }
        self.finish(&p)
    }

    /// Builds a `shapegroup` (once, however many instances refer to it) and returns its group
    /// index. Its shapes keep their own BSDFs; it is not rendered by itself.
    fn shapegroup(&mut self, el: &'a El, b: &mut Build) -> Result<u32, SceneError> {
        let key = el as *const El as usize;
        if let Some(&g) = b.group_cache.get(&key) {
            return Ok(g);
        }
        if b.geometry.in_group() {
            return Err(self.err(el, "a shapegroup cannot be inside another shapegroup (Mitsuba refuses that too)"));
        }
        let p = self.props(el)?;
        let group = b.geometry.begin_group().map_err(|e| self.err(el, e))?;
        for (child, _) in self.object(&p, None, "shape") {
            self.shape(child, b)?;
        }
        b.geometry.end_group();
        self.finish(&p)?;
        if b.geometry.group_len(group) == 0 {
            self.warn(el, "this shapegroup holds no shape caustic renders: its instances show nothing")?;
        }
        b.group_cache.insert(key, group);
        Ok(group)
    }

    /// An `instance`: a referenced `shapegroup` placed by `to_world`.
    fn instance(&mut self, el: &'a El, b: &mut Build) -> Result<(), SceneError> {
        if b.geometry.in_group() {
            return Err(self.err(el, "an instance cannot be inside a shapegroup (Mitsuba does not nest instancing)"));
        }
        let p = self.props(el)?;
        let to_world = self.transform(&p, "to_world")?.map_or(Transform::IDENTITY, |x| x.t);
        let groups = self.object(&p, None, "shape");
        let [(group_el, at)] = groups.as_slice() else {
            return Err(self.err(
                el,
                "an instance needs exactly one shapegroup: <ref id=\"...\"/> naming a <shape type=\"shapegroup\">",
            ));
        };
        if self.attr(group_el, "type")?.is_none_or(|t| t.0 != "shapegroup") {
            return Err(self.err(at, "an instance must refer to a <shape type=\"shapegroup\">"));
        }
        let group = self.shapegroup(group_el, b)?;
        b.geometry.add_instance(group, &to_world).map_err(|e| e.placed(|m| self.err(el, m)))?;
        self.finish(&p)
    }
}

/// A mesh of two triangles that form a planar parallelogram, as a quad facing the triangles'
/// side.
fn parallelogram(mesh: &TriangleMesh) -> Option<Quad> {
    if mesh.indices.len() != 2 {
        return None;
    }
    let tri = |k: usize| mesh.indices[k].map(|i| mesh.positions[i as usize]);
    let (a, b) = (tri(0), tri(1));
    let n = (a[1] - a[0]).cross(a[2] - a[0]);
    // The vertex of the second triangle not in the first.
    let extra: Vec<Vec3> = b.iter().copied().filter(|p| !a.contains(p)).collect();
    let [d] = extra.as_slice() else { return None };
    // Find the corner of the first triangle opposite to d: p0 = (sum of the two shared) - d.
    for k in 0..3 {
        let (p, q, r) = (a[k], a[(k + 1) % 3], a[(k + 2) % 3]);
        // p is the corner; q and r are the neighbours; the fourth corner should be q + r - p.
        let fourth = q + r - p;
        let scale = (q - p).length().max((r - p).length());
        if (fourth - *d).length() <= 1e-4 * scale {
            let (e1, e2) = (q - p, r - p);
            return if e1.cross(e2).dot(n) >= 0.0 { Quad::new(p, e1, e2) } else { Quad::new(p, e2, e1) };
        }
    }
    None
}
