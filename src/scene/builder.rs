//! The one place a scene is assembled: both loaders add materials, shapes, meshes and lights
//! here, and `finish` turns them into a [`Scene`] with its BVH.
//!
//! Area-light primitives are added after all other geometry, whatever the order in the file, so
//! a TOML scene and its Mitsuba twin give the same primitives in the same order (and so the same
//! image bit for bit).

use super::SceneError;
use super::desc::{LoadInfo, MeshInfo};
use super::footprint::{FileBudget, OverBudget};
use super::{Scene, SceneObject};
use crate::accel::{Bvh, Instance, Instances};
use crate::camera::Camera;
use crate::geometry::{Aabb, NO_LIGHT, Transform};
use crate::light::{EmissionTexture, Environment, Light, LightPicker, PhotonDisk};
use crate::material::{GivenSpectra, GivenSpectrum, Material, Materials, Param, SpectrumId, Wrapper};
use crate::math::{Color, Vec2, Vec3};
use crate::medium::{Medium, MediumInterface};
use crate::shape::{Plane, Primitive, Primitives, Shape, TRIANGLE_UV, Triangle, TriangleMesh};
use crate::spectrum::EmissionSpectrum;
use crate::texture::Texture;
use std::time::Instant;

/// Geometry, materials and lights collected while a scene file is read.
#[derive(Clone, Default)]
pub struct SceneBuilder {
    materials: Vec<Material>,
    material_names: Vec<String>,
    textures: Vec<Texture>,
    prims: Primitives,
    /// The infinite planes added (also primitives), for the photon disk.
    planes: Vec<Plane>,
    meshes: Vec<TriangleMesh>,
    lights: Vec<Light>,
    /// The environment (map or constant), added after all other lights by `finish`.
    environment: Option<Environment>,
    /// Primitives of area lights, placed after all other primitives by `finish`.
    area_prims: Primitives,
    /// Every object added outside groups: its bounding sphere and material.
    objects: Vec<SceneObject>,
    triangles: usize,
    degenerate_triangles: usize,
    /// The hook the loader reports the files it reads to (shared with it): the builder counts
    /// the meshes it is asked to generate and the instances it places there, and takes the
    /// scene's list of files from it.
    files: FileBudget,
    mesh_info: Vec<MeshInfo>,
    /// Primitives of each group of instanced geometry, in the group's own space.
    groups: Vec<Primitives>,
    /// The group objects and meshes go to (between `begin_group` and `end_group`).
    open_group: Option<usize>,
    instances: Vec<Instance>,
    /// Participating media, referred to by index from interfaces and the camera.
    media: Vec<Medium>,
    /// The media interface of each material (`None`: crossing it keeps the ray's medium).
    interfaces: Vec<Option<MediumInterface>>,
    /// The materials made by `with_interface`: (material, interface) to the copy's index.
    interface_copies: Vec<((u32, MediumInterface), u32)>,
    /// The index of the invisible boundary material (`null_material`), once made.
    null_material: Option<u32>,
    /// The medium the camera sits in (vacuum when `None`).
    camera_medium: Option<u32>,
    /// Emitted spectra kept as given, for spectral mode, and the lights that emit them:
    /// (first light, end, spectrum), `usize::MAX` as the first light for the environment.
    spectra: Vec<EmissionSpectrum>,
    spectrum_users: Vec<(usize, usize, u32)>,
    /// Reflectance-like spectra kept as given, for spectral mode, and by material the ones its
    /// constant colours use (`Materials::with_spectra`; materials past the end have none).
    given_spectra: Vec<GivenSpectrum>,
    material_spectra: Vec<GivenSpectra>,
}

impl SceneBuilder {
    pub fn new() -> Self {
        Self::default()
    }

    /// A builder counting against `files`, the hook its loader reports files to.
    pub fn with_files(files: FileBudget) -> Self {
        SceneBuilder { files, ..Self::default() }
    }

    /// Every file the scene was read from so far, once each, in the order first read.
    pub fn files(&self) -> Vec<std::path::PathBuf> {
        self.files.files()
    }

    /// Counts a mesh of `vertices` and `triangles` a loader is about to generate (`name`: what
    /// it is), before it is made; refused when it would not fit in the memory allowed.
    pub fn reserve_generated_mesh(&mut self, name: &str, vertices: u64, triangles: u64) -> Result<(), OverBudget> {
        self.files.generated_mesh(name, vertices, triangles)
    }

    /// Adds a material; returns its index.
    pub fn add_material(&mut self, name: impl Into<String>, m: Material) -> u32 {
        self.materials.push(m);
        self.material_names.push(name.into());
        self.interfaces.push(None);
        (self.materials.len() - 1) as u32
    }

    /// Adds a participating medium; returns its index (what interfaces and the camera name).
    pub fn add_medium(&mut self, m: Medium) -> u32 {
        self.media.push(m);
        (self.media.len() - 1) as u32
    }

    pub fn media(&self) -> &[Medium] {
        &self.media
    }

    /// Material `material` with media `interface` on its two sides: a copy of it that carries
    /// the interface (media belong to shapes, materials are shared, so each (material,
    /// interface) pair is one material of the scene).
    pub fn with_interface(&mut self, material: u32, interface: MediumInterface) -> u32 {
        if let Some(&(_, m)) = self.interface_copies.iter().find(|(k, _)| *k == (material, interface)) {
            return m;
        }
        let name = self.material_names[material as usize].clone();
        let copy = self.add_material(name, self.materials[material as usize]);
        self.set_material_spectra(copy, self.material_spectra(material));
        self.interfaces[copy as usize] = Some(interface);
        self.interface_copies.push(((material, interface), copy));
        copy
    }

    /// The invisible surface (Mitsuba's `null` BSDF): light passes straight through it, so it
    /// only bounds a medium. A mask of opacity 0, made once.
    pub fn null_material(&mut self) -> u32 {
        if let Some(m) = self.null_material {
            return m;
        }
        let inner = self.add_material("(null inside)", Material::black());
        let m = self.add_material("null", Material::two_sided(Wrapper::Mask { opacity: Param::Const(0.0), inner }));
        self.null_material = Some(m);
        m
    }

    /// Places the camera in medium `m`.
    pub fn set_camera_medium(&mut self, m: u32) {
        self.camera_medium = Some(m);
    }

    /// Adds a texture; returns its index.
    pub fn add_texture(&mut self, t: Texture) -> u32 {
        self.textures.push(t);
        (self.textures.len() - 1) as u32
    }

    pub fn textures(&self) -> &[Texture] {
        &self.textures
    }

    pub fn material(&self, index: u32) -> &Material {
        &self.materials[index as usize]
    }

    /// The names of the mesh attributes material `m` reads (through the materials it wraps too).
    pub fn mesh_attributes_read(&self, m: u32) -> Vec<String> {
        let model = &self.materials[m as usize].model;
        let mut names: Vec<String> = model
            .params()
            .iter()
            .filter_map(|p| p.texture())
            .filter_map(|t| match &self.textures[t as usize] {
                Texture::MeshAttribute { name, .. } => Some(name.clone()),
                _ => None,
            })
            .collect();
        for c in model.children() {
            names.extend(self.mesh_attributes_read(c));
        }
        names.sort();
        names.dedup();
        names
    }

    pub fn material_count(&self) -> usize {
        self.materials.len()
    }

    /// Starts a group of instanced geometry: objects and meshes added until `end_group` belong
    /// to it, in its own space, and appear only where `add_instance` places it. Groups do not
    /// nest. Returns the group's index.
    pub fn begin_group(&mut self) -> Result<u32, String> {
        if self.open_group.is_some() {
            return Err("groups of instanced shapes cannot be nested".into());
        }
        self.groups.push(Primitives::new());
        self.open_group = Some(self.groups.len() - 1);
        Ok((self.groups.len() - 1) as u32)
    }

    pub fn end_group(&mut self) {
        self.open_group = None;
    }

    /// True between `begin_group` and `end_group`.
    pub fn in_group(&self) -> bool {
        self.open_group.is_some()
    }

    /// Number of primitives in group `group`.
    pub fn group_len(&self, group: u32) -> usize {
        self.groups.get(group as usize).map_or(0, Primitives::len)
    }

    /// Places group `group` in the scene, moved by `t`, once the instance fits in the memory
    /// allowed.
    pub fn add_instance(&mut self, group: u32, t: &Transform) -> Result<(), InstanceError> {
        if group as usize >= self.groups.len() {
            return Err(InstanceError::Invalid(format!("no group {group}")));
        }
        let inst = Instance::new(group, t)
            .ok_or_else(|| InstanceError::Invalid("an instance's transform is singular or not finite".into()))?;
        self.files.instance().map_err(InstanceError::Memory)?;
        self.instances.push(inst);
        Ok(())
    }

    /// Where objects go now: the open group or the scene.
    fn target(&mut self) -> &mut Primitives {
        match self.open_group {
            Some(g) => &mut self.groups[g],
            None => &mut self.prims,
        }
    }

    /// Adds one object made of `shapes` (a sphere, a quad, the six faces of a box).
    pub fn add_object(&mut self, shapes: impl IntoIterator<Item = Shape>, material: u32) {
        let first = self.target().len();
        for shape in shapes {
            self.target().push(Primitive { shape, material, light: NO_LIGHT });
        }
        self.note_object(first, material);
    }

    /// Adds a triangle mesh (zero-area triangles are skipped and counted); `name` says where it
    /// came from, for the log. Its triangles become primitives that index the mesh (8 bytes
    /// each), with no list of triangles in between.
    pub fn add_mesh(&mut self, mut mesh: TriangleMesh, material: u32, name: &str) {
        let first = self.target().len();
        let id = self.meshes.len() as u32;
        mesh.shrink_to_fit();
        let has_area =
            |idx: &[u32; 3]| Triangle { p: idx.map(|i| mesh.positions[i as usize]), mesh: id, index: 0 }.area() > 0.0;
        let triangles = (0..mesh.indices.len() as u32).filter(|&k| has_area(&mesh.indices[k as usize]));
        match self.open_group {
            Some(g) => self.groups[g].push_mesh(id, material, triangles),
            None => self.prims.push_mesh(id, material, triangles),
        }
        let kept = self.target().len() - first;
        let skipped = mesh.indices.len() - kept;
        self.mesh_info.push(MeshInfo {
            name: name.to_string(),
            triangles: kept,
            bounds: Aabb::from_points(&mesh.positions),
        });
        self.triangles += kept;
        self.degenerate_triangles += skipped;
        self.meshes.push(mesh);
        self.note_object(first, material);
    }

    /// Adds an infinite plane (a primitive the BVH keeps beside its tree).
    pub fn add_plane(&mut self, plane: Plane, material: u32) {
        debug_assert!(self.open_group.is_none(), "loaders refuse planes in instanced groups");
        self.planes.push(plane);
        self.prims.push(Primitive { shape: Shape::Plane(plane), material, light: NO_LIGHT });
    }

    /// Adds a light that has no surface (point, spot, directional).
    pub fn add_light(&mut self, light: Light) {
        self.lights.push(light);
    }

    /// How many lights were added so far (the environment aside).
    pub fn light_count(&self) -> usize {
        self.lights.len()
    }

    /// Spectral mode evaluates `spectrum` for the lights added from light `first` on (the
    /// lights of one emitter), or for the environment when `first` is `None`, instead of
    /// lifting their colour.
    pub fn set_emission_spectrum(&mut self, first: Option<usize>, spectrum: EmissionSpectrum) {
        let end = self.lights.len();
        let id = self.spectra.len() as u32;
        self.spectra.push(spectrum);
        self.spectrum_users.push((first.unwrap_or(usize::MAX), end, id));
    }

    /// `set_emission_spectrum` for a spectrum read from a scene standing for colour `color`
    /// (nothing when there is none, or the colour is black).
    pub fn keep_emission_spectrum(
        &mut self,
        first: Option<usize>,
        spectrum: Option<crate::spectrum::SampledSpectrum>,
        color: crate::math::Color,
    ) {
        if let Some(s) = spectrum.and_then(|s| EmissionSpectrum::new(&s, color)) {
            self.set_emission_spectrum(first, s);
        }
    }

    /// `add_given_spectrum` for a spectrum read from a scene standing for colour `color`; none
    /// when there is no spectrum or the colour is black (the colour is then lifted).
    pub fn keep_given_spectrum(
        &mut self,
        spectrum: Option<&crate::spectrum::SampledSpectrum>,
        color: crate::math::Color,
    ) -> SpectrumId {
        match spectrum.and_then(|s| GivenSpectrum::new(s, color)) {
            Some(s) => self.add_given_spectrum(s),
            None => SpectrumId::NONE,
        }
    }

    /// Keeps a reflectance-like spectrum for spectral mode; returns its index (none when the
    /// table is full: the colour it stands for is then lifted).
    pub fn add_given_spectrum(&mut self, spectrum: GivenSpectrum) -> SpectrumId {
        let id = SpectrumId::new(self.given_spectra.len());
        if !id.is_none() {
            self.given_spectra.push(spectrum);
        }
        id
    }

    /// Spectral mode evaluates the spectra `given` for material `m`'s constant colours.
    pub fn set_material_spectra(&mut self, m: u32, given: GivenSpectra) {
        let m = m as usize;
        if m >= self.material_spectra.len() {
            if given.is_none() {
                return;
            }
            self.material_spectra.resize(m + 1, GivenSpectra::NONE);
        }
        self.material_spectra[m] = given;
    }

    /// The spectra given for material `m`'s constant colours.
    pub fn material_spectra(&self, m: u32) -> GivenSpectra {
        self.material_spectra.get(m as usize).copied().unwrap_or(GivenSpectra::NONE)
    }

    /// Sets the environment light (an environment map or a constant radiance); a scene has at
    /// most one, as in Mitsuba.
    pub fn set_environment(&mut self, env: Environment) -> Result<(), String> {
        if self.environment.is_some() {
            return Err("a scene has at most one environment light (envmap or constant)".into());
        }
        self.environment = Some(env);
        Ok(())
    }

    /// The environment light set so far.
    pub fn environment(&self) -> Option<&Environment> {
        self.environment.as_ref()
    }

    /// Adds an emitting shape: a light and its primitive. `surface` is the BSDF the emitter
    /// reflects with (a reflecting emitter); `None` makes it black.
    pub fn add_area_light(&mut self, shape: Shape, radiance: Color, surface: Option<Material>) {
        self.add_area_lights([shape], radiance, None, surface);
    }

    /// Adds one emitting object made of several surfaces (the faces of a cube): a light per
    /// surface, so light sampling picks among them by power (by area, as they share the
    /// radiance), and one material for all. With a `texture` (an index from `add_texture`) the
    /// radiance is multiplied by it at each point's uv. Returns the index of the material made
    /// for the emitter's surface.
    pub fn add_area_lights(
        &mut self,
        shapes: impl IntoIterator<Item = Shape>,
        radiance: Color,
        texture: Option<u32>,
        surface: Option<Material>,
    ) -> u32 {
        let shapes = shapes.into_iter().map(|s| (s, TRIANGLE_UV));
        self.add_emitters(shapes, radiance, texture, surface)
    }

    /// Adds an emitting triangle mesh: a light per triangle (each emitting from the side its
    /// winding faces, as the mesh's geometric normals do), reading a texture at the mesh's
    /// texture coordinates. Returns the index of the material made for its surface.
    pub fn add_mesh_area_lights(
        &mut self,
        mesh: &TriangleMesh,
        radiance: Color,
        texture: Option<u32>,
        surface: Option<Material>,
    ) -> u32 {
        let triangles = mesh.indices.iter().enumerate().map(|(k, t)| {
            let [p0, p1, p2] = t.map(|i| mesh.positions[i as usize]);
            (Shape::Triangle(Triangle::new(p0, p1, p2)), mesh.vertex_uvs(k).unwrap_or(TRIANGLE_UV))
        });
        self.add_emitters(triangles, radiance, texture, surface)
    }

    /// True when some triangle of `mesh` has an area (can emit).
    pub fn mesh_can_emit(mesh: &TriangleMesh) -> bool {
        mesh.indices.iter().any(|t| {
            let [p0, p1, p2] = t.map(|i| mesh.positions[i as usize]);
            Triangle::new(p0, p1, p2).area() > 0.0
        })
    }

    /// The lights and primitives of emitting shapes, each with the texture coordinates of its
    /// vertices when it is a triangle (read by an emission texture); returns the index of the
    /// material made for their surface.
    fn add_emitters(
        &mut self,
        shapes: impl IntoIterator<Item = (Shape, [Vec2; 3])>,
        radiance: Color,
        texture: Option<u32>,
        surface: Option<Material>,
    ) -> u32 {
        debug_assert!(self.open_group.is_none(), "loaders refuse emitters in instanced groups");
        let first = self.lights.len();
        let m = self.add_material(format!("(area light {})", first + 1), surface.unwrap_or_else(Material::black));
        for (shape, vertex_uv) in shapes {
            if !(shape.area() > 0.0 && shape.is_bounded()) {
                continue;
            }
            let texture =
                texture.map(|t| EmissionTexture { texture: t, mean: self.textures[t as usize].mean(), vertex_uv });
            let light = self.lights.len() as u32;
            self.area_prims.push(Primitive { shape, material: m, light });
            self.lights.push(Light::Area { shape, radiance, texture });
        }
        m
    }

    /// Records the bounding sphere and material of the object whose primitives start at
    /// `first` (objects in groups are known through their instances).
    fn note_object(&mut self, first: usize, material: u32) {
        if self.open_group.is_some() || self.target().len() <= first {
            return;
        }
        let (prims, meshes) = (&self.prims, &self.meshes);
        // A sphere is its own bounding sphere; any other object (or several shapes) the sphere
        // around its primitives' bounds.
        let (center, radius) = if let Shape::Sphere(s) = prims.get(first, meshes).shape
            && prims.len() == first + 1
        {
            (s.center, s.radius)
        } else {
            (first..prims.len()).fold(Aabb::EMPTY, |b, i| b.union(prims.bounds(i, meshes))).bounding_sphere()
        };
        self.objects.push(SceneObject { center, radius, material });
    }

    /// Builds the BVH and the scene seen through `camera`; fails when materials refer to each
    /// other or to textures wrongly.
    pub fn finish(mut self, camera: Camera) -> Result<(Scene, LoadInfo), String> {
        let materials = Materials::with_spectra(
            self.materials,
            self.material_names,
            self.textures,
            std::mem::take(&mut self.given_spectra),
            std::mem::take(&mut self.material_spectra),
        )?;
        self.prims.append(std::mem::take(&mut self.area_prims));
        let t0 = Instant::now();
        let bvh = Bvh::build(std::mem::take(&mut self.prims), &self.meshes);
        let instances =
            Instances::build(std::mem::take(&mut self.groups), std::mem::take(&mut self.instances), &self.meshes);
        let info = LoadInfo {
            meshes: self.mesh_info,
            primitives: bvh.len() - bvh.unbounded_len(),
            triangles: self.triangles,
            degenerate_triangles: self.degenerate_triangles,
            bvh_nodes: bvh.node_count() + instances.node_count(),
            bvh_build: t0.elapsed(),
            files: self.files.files(),
            instances: instances.len(),
            instance_groups: instances.group_count(),
        };
        let bounds = bvh.bounds().union(instances.bounds());
        let disk = photon_disk(bounds, &self.planes, camera.eye);
        // The environment comes last, so emitting primitives keep their light indices and a
        // scene's lights are in the same order whichever format it was written in.
        let environment = self.environment.map(|e| {
            self.lights.push(Light::Environment(e));
            (self.lights.len() - 1) as u32
        });
        let mut light_spectra = Vec::new();
        if !self.spectra.is_empty() {
            light_spectra = vec![crate::scene::NO_SPECTRUM; self.lights.len()];
            for &(first, end, id) in &self.spectrum_users {
                match (first, environment) {
                    (usize::MAX, Some(env)) => light_spectra[env as usize] = id,
                    (usize::MAX, None) => {}
                    _ => light_spectra[first..end].iter_mut().for_each(|s| *s = id),
                }
            }
        }
        for l in &mut self.lights {
            match l {
                Light::Directional { disk: d, .. } => *d = disk,
                Light::Environment(e) => e.disk = disk,
                Light::Point { .. } | Light::Spot(_) | Light::Projector(_) | Light::Area { .. } => {}
            }
        }
        let scene = Scene {
            bvh,
            instances,
            meshes: self.meshes,
            materials,
            light_picker: LightPicker::new(&self.lights),
            direct_picker: LightPicker::for_direct_light(&self.lights),
            lights: self.lights,
            camera,
            environment,
            objects: self.objects,
            interfaces: if self.interfaces.iter().any(Option::is_some) { self.interfaces } else { Vec::new() },
            media: self.media,
            camera_medium: self.camera_medium.unwrap_or(crate::geometry::NO_MEDIUM),
            emission_spectra: self.spectra,
            light_spectra,
        };
        Ok((scene, info))
    }
}

/// Why an instance was not placed.
#[derive(Debug)]
pub enum InstanceError {
    /// It would not fit in the memory allowed.
    Memory(OverBudget),
    /// Its group or transform is unusable: the loader says where.
    Invalid(String),
}

impl InstanceError {
    /// The scene error, with `at` placing an unusable instance in its file.
    pub fn placed(self, at: impl FnOnce(String) -> SceneError) -> SceneError {
        match self {
            InstanceError::Memory(o) => SceneError::Memory(o),
            InstanceError::Invalid(message) => at(message),
        }
    }
}

/// Where photons from lights at infinity enter: the bounding sphere of the finite geometry,
/// extended over the planes when there are any (`PhotonDisk`). A scene of planes alone centres
/// it under the camera, as wide as the camera is high.
fn photon_disk(bounds: Aabb, planes: &[Plane], eye: Vec3) -> PhotonDisk {
    let (center, radius) = if !bounds.is_empty() && bounds.diagonal().is_finite() {
        bounds.bounding_sphere()
    } else if let Some(p) = planes.first() {
        let h = (eye - p.point).dot(p.normal);
        (eye - p.normal * h, h.abs())
    } else {
        (eye, 1.0)
    };
    let radius = if radius > 0.0 && radius.is_finite() { radius } else { 1.0 };
    PhotonDisk::new(center, radius, !planes.is_empty())
}
