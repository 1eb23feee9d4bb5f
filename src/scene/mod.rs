//! Scenes: files turned into plain data ([`desc::SceneDescription`], by the loaders `native`
//! for caustic's TOML format and `mitsuba` for Mitsuba 3 XML), assembled by one
//! [`builder::SceneBuilder`] into the runtime [`Scene`] the integrators trace rays against.
//! Nothing here knows about integrators or the render loop.

pub mod builder;
mod de;
pub mod desc;
pub mod environment;
pub mod error;
pub mod footprint;
pub mod mitsuba;
pub mod native;
#[cfg(test)]
pub(crate) mod test_scenes;
pub mod volume_file;

pub use desc::{BuiltScene, LoadOptions, SceneDescription};
pub use error::SceneError;
pub use footprint::{FileBudget, FileKind};

use crate::accel::{Bvh, Instances};
use crate::camera::Camera;
use crate::geometry::{Aabb, Hit, Ray};
use crate::light::{Light, LightPicker};
use crate::material::Materials;
use crate::material::bsdf::Bsdf;
use crate::math::{Color, Vec3};
use crate::shape::{CompactShape, SurfacePoint, TriangleMesh};
use std::path::Path;

/// Reads a scene file: Mitsuba 3 XML for `.xml`, caustic's TOML format otherwise.
pub fn load_scene(path: &Path, options: &LoadOptions) -> Result<SceneDescription, SceneError> {
    load_scene_within(path, options, &FileBudget::unlimited())
}

/// `load_scene` reporting every file it reads to `files` before reading it (the scene file
/// first), which stops the load with `SceneError::Memory` when the next file, generated mesh or
/// instance would not fit in its limit. Afterwards `files` holds the scene's estimated footprint.
pub fn load_scene_within(
    path: &Path,
    options: &LoadOptions,
    files: &FileBudget,
) -> Result<SceneDescription, SceneError> {
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("xml")) {
        return mitsuba::load_mitsuba(path, options, files);
    }
    files.open(path, FileKind::Scene)?;
    let text = std::fs::read_to_string(path)
        .map_err(|source| SceneError::Read { path: path.display().to_string(), source })?;
    let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
    native::load_toml_str(&text, &path.display().to_string(), &base, files, &options.defines, &options.sets)
}

/// The two scene formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneFormat {
    /// caustic's own (docs/scene-format.md).
    Toml,
    /// Mitsuba 3 XML.
    Mitsuba,
}

/// `load_scene_within` for a scene given as `text` in `format` (the Python module's
/// `load_string`): `name` is used in messages and the files it names resolve against `base`.
pub fn load_scene_text_within(
    text: &str,
    format: SceneFormat,
    name: &str,
    base: &Path,
    options: &LoadOptions,
    files: &FileBudget,
) -> Result<SceneDescription, SceneError> {
    match format {
        SceneFormat::Mitsuba => mitsuba::load_mitsuba_text(text, name, base, options, files),
        SceneFormat::Toml => native::load_toml_str(text, name, base, files, &options.defines, &options.sets),
    }
}

/// Reads a scene in caustic's TOML format from `text`; `name` is used in messages and mesh
/// paths resolve against `base`.
pub fn load_scene_str(text: &str, name: &str, base: &Path) -> Result<SceneDescription, SceneError> {
    load_scene_str_with(text, name, base, &LoadOptions::default())
}

/// `load_scene_str` with `-D` parameters and `--set` values.
pub fn load_scene_str_with(
    text: &str,
    name: &str,
    base: &Path,
    options: &LoadOptions,
) -> Result<SceneDescription, SceneError> {
    native::load_toml_str(text, name, base, &FileBudget::unlimited(), &options.defines, &options.sets)
}

pub struct Scene {
    pub bvh: Bvh,
    /// Instanced groups of shapes and the top-level BVH over their instances.
    pub instances: Instances,
    pub meshes: Vec<TriangleMesh>,
    /// Materials, their names and the textures they read.
    pub materials: Materials,
    pub lights: Vec<Light>,
    /// Chooses a light in proportion to power (photon and light-path emission).
    pub light_picker: LightPicker,
    /// Chooses the light a shading point samples (next-event estimation; see
    /// `LightPicker::for_direct_light`).
    pub direct_picker: LightPicker,
    pub camera: Camera,
    /// Index in `lights` of the environment (map or constant) rays that leave the scene see.
    pub environment: Option<u32>,
    /// The objects the loaders added outside instanced groups (a sphere, a box, a mesh), with
    /// their bounding spheres and materials, for methods that aim at objects (caustic photons).
    pub objects: Vec<SceneObject>,
    /// Participating media (`Ray::medium` indexes them).
    pub media: Vec<crate::medium::Medium>,
    /// The media interface of each material, by material index (empty when no surface bounds
    /// a medium): crossing a surface whose material has one moves a ray into the medium on the
    /// side it leaves towards; crossing any other keeps its medium.
    pub interfaces: Vec<Option<crate::medium::MediumInterface>>,
    /// The medium the camera sits in (`NO_MEDIUM`: vacuum).
    pub camera_medium: u32,
    /// Emitted spectra given as spectra (spectral mode evaluates them as they are).
    pub emission_spectra: Vec<crate::spectrum::EmissionSpectrum>,
    /// Each light's index in `emission_spectra` (`NO_SPECTRUM`: its colour, lifted); empty when
    /// no light has one.
    pub light_spectra: Vec<u32>,
}

/// A light without an emitted spectrum of its own (`Scene::light_spectra`).
pub const NO_SPECTRUM: u32 = u32::MAX;

/// An object of a scene as its file gave it: the bounding sphere of its primitives and its
/// material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneObject {
    pub center: Vec3,
    pub radius: f32,
    pub material: u32,
}

impl Scene {
    /// True when the scene has participating media (rendered by the volumetric path tracer).
    #[inline]
    pub fn has_media(&self) -> bool {
        !self.media.is_empty()
    }

    /// The medium a ray in medium `current` is in after leaving surface `h` in direction `d`.
    #[inline]
    pub fn medium_after(&self, h: &Hit, d: Vec3, current: u32) -> u32 {
        match self.interfaces.get(h.material as usize) {
            Some(Some(i)) => i.toward(d, h.ng),
            _ => current,
        }
    }

    /// The medium at point `p`, found from the first surface bounding a medium that a ray from
    /// `p` along `d` meets (inside it when the ray leaves through it); where no boundary is in
    /// the way, the camera's medium (a scene filled with the medium the camera sits in). Photons
    /// start from lights in the medium this gives.
    pub fn medium_at(&self, p: Vec3, d: Vec3) -> u32 {
        let mut ray = Ray::new(p, d);
        for _ in 0..16 {
            let Some(h) = self.intersect(&ray, f32::INFINITY) else { break };
            if let Some(Some(i)) = self.interfaces.get(h.material as usize) {
                return if d.dot(h.ng) > 0.0 { i.inside } else { i.outside };
            }
            ray = h.spawn(d, 0.0);
        }
        self.camera_medium
    }

    /// The textures materials and lights read.
    #[inline(always)]
    pub fn textures(&self) -> &[crate::texture::Texture] {
        &self.materials.textures
    }

    /// Bounds of all bounded geometry (planes excluded).
    pub fn bounds(&self) -> Aabb {
        self.bvh.bounds().union(self.instances.bounds())
    }

    /// Closest hit in (0, t_max).
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        let mut closest = t_max;
        let mut best = None;
        if let Some((i, h)) = self.bvh.intersect_tree(ray, t_max) {
            closest = h.t;
            best = Some((i, h));
        }
        let mut instanced = None;
        if !self.instances.is_empty()
            && let Some(h) = self.instances.intersect(ray, closest)
        {
            closest = h.t;
            instanced = Some(h);
        }
        // Planes last, so the tree and the instances have pruned `closest` (see
        // `Bvh::intersect_unbounded`).
        if let Some(p) = self.bvh.intersect_unbounded(ray, closest) {
            best = Some(p);
        } else if let Some(h) = instanced {
            let (sp, material, light) = self.instances.surface(&h, &self.meshes);
            return Some(Self::hit(h.t, &sp, material, light, h.prim));
        }
        let (i, h) = best?;
        let sp = self.bvh.surface(i, ray, &h, &self.meshes);
        let (material, light) = self.bvh.material_light(i);
        Some(Self::hit(h.t, &sp, material, light, i))
    }

    /// Calls `visit(material, crossing)` for every surface `ray` crosses in (0, t_max), in no
    /// particular order, until it returns false; returns whether it went through all of them.
    /// `None` for scenes with instances or cylinders, whose crossings callers walk one closest
    /// hit at a time. One traversal instead of one per crossing: a shadow ray through a glass
    /// sphere crosses it twice. A ray exactly along an edge shared by two triangles (or tangent
    /// to a sphere) crosses both (both roots), where a walk of closest hits would count one.
    #[inline]
    pub fn for_each_crossing(
        &self,
        ray: &Ray,
        t_max: f32,
        mut visit: impl FnMut(u32, &Crossing) -> bool,
    ) -> Option<bool> {
        if !self.instances.is_empty() {
            return None;
        }
        self.bvh.for_each_crossing(ray, t_max, |i, hit| {
            let (material, _) = self.bvh.material_light(i);
            visit(material, &Crossing::Traversed { scene: self, ray, hit, prim: i })
        })
    }

    #[inline]
    fn hit(t: f32, sp: &SurfacePoint, material: u32, light: u32, prim: u32) -> Hit {
        Hit { t, p: sp.p, p_error: sp.p_error, ng: sp.ng, ns: sp.ns, param: sp.param, material, light, prim }
    }

    /// Radiance the surface at `h` emits towards `w` (zero unless it is an area light).
    #[inline]
    pub fn emitted(&self, h: &Hit, w: crate::math::Vec3) -> Color {
        match self.lights.get(h.light as usize) {
            Some(light) => light.emitted(h.ng, w, || h.uv(), self.textures()),
            None => Color::ZERO,
        }
    }

    /// Radiance arriving along a ray that leaves the scene in direction `d` (from the
    /// environment light; black without one).
    #[inline]
    pub fn environment(&self, d: crate::math::Vec3) -> Color {
        match self.environment {
            Some(i) => self.lights[i as usize].environment_radiance(d),
            None => Color::ZERO,
        }
    }

    /// `environment(d)` in the mode `wl` says (`emission_in`): the environment's spectrum, or
    /// its colour lifted, at the path's wavelengths in spectral mode.
    #[inline]
    pub fn environment_in(&self, d: crate::math::Vec3, wl: Option<&crate::spectrum::Wavelengths>) -> Color {
        match self.environment {
            Some(i) => self.emission_in(self.lights[i as usize].environment_radiance(d), i, wl),
            None => Color::ZERO,
        }
    }

    /// Bytes held by the geometry: meshes, the BVH (nodes, leaf shapes, primitives), instances.
    pub fn geometry_bytes(&self) -> u64 {
        (self.meshes.iter().map(TriangleMesh::memory_bytes).sum::<usize>()
            + self.bvh.memory_bytes()
            + self.instances.memory_bytes()) as u64
    }

    /// Bytes the environment map holds (texels and sampling distribution); 0 without one.
    pub fn environment_bytes(&self) -> u64 {
        self.environment
            .and_then(|i| match &self.lights[i as usize] {
                Light::Environment(e) => e.map.map(|m| m.memory_bytes() as u64),
                Light::Point { .. }
                | Light::Spot(_)
                | Light::Projector(_)
                | Light::Directional { .. }
                | Light::Area { .. } => None,
            })
            .unwrap_or(0)
    }

    /// The ray of a photon from a light at infinity, moved back along itself so that it starts
    /// before every infinite plane it crosses: light from infinity meets a plane before
    /// anything behind it, whatever the bounds of the finite geometry (`PhotonDisk`) say.
    pub fn photon_entry(&self, ray: Ray) -> Ray {
        let mut t0 = 0.0f32;
        for plane in self.bvh.unbounded() {
            let CompactShape::Plane([point, normal]) = *plane else { continue };
            let denom = normal.dot(ray.d);
            if denom != 0.0 {
                let t = (point - ray.o).dot(normal) / denom;
                if t.is_finite() && t < t0 {
                    t0 = t;
                }
            }
        }
        if t0 < 0.0 {
            // A margin well above the rounding of the origin: starting further back is always
            // safe, as nothing lies behind the first crossing.
            let margin = 1e-3 * -t0 + 1e-4 * (1.0 + ray.o.abs().max_element());
            Ray::new(ray.o + ray.d * (t0 - margin), ray.d)
        } else {
            ray
        }
    }

    /// True when anything blocks the ray in (0, t_max).
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.bvh.occluded(ray, t_max) || (!self.instances.is_empty() && self.instances.occluded(ray, t_max))
    }

    /// Checks what a scene built from finite, in-range values can still get wrong through
    /// overflow: geometry whose bounds are not finite, lights whose power or area is not a
    /// positive finite number, a camera whose rays are not finite. Returns what is wrong.
    pub fn check_usable(&self) -> Result<(), String> {
        let b = self.bounds();
        let finite = b.min.is_finite() && b.max.is_finite() && b.diagonal().is_finite();
        if !(b.is_empty() || finite) {
            return Err("the scene's geometry reaches beyond the range of 32-bit floats (coordinates overflow after transforms)".into());
        }
        for (i, l) in self.lights.iter().enumerate() {
            if !l.power().is_finite() {
                return Err(format!(
                    "light {} is too strong: its power overflows (colour x intensity too large)",
                    i + 1
                ));
            }
            if let Light::Area { shape, .. } = l {
                let a = shape.area();
                if !(a > 0.0 && a.is_finite()) {
                    return Err(format!("area light {} has no usable area (area {a})", i + 1));
                }
            }
        }
        let cam = &self.camera;
        let (w, h) = (cam.width as f32, cam.height as f32);
        for raster in [crate::math::Vec2::new(0.5 * w, 0.5 * h), crate::math::Vec2::ZERO, crate::math::Vec2::new(w, h)]
        {
            for lens in [crate::math::Vec2::splat(0.5), crate::math::Vec2::ZERO, crate::math::Vec2::ONE] {
                let r = cam.generate_ray(raster, lens);
                if !(r.o.is_finite() && r.d.is_finite() && (r.d.length() - 1.0).abs() < 1e-3) {
                    return Err("the camera's rays are not finite (focal distance or view-plane distance too small or too large)".into());
                }
            }
        }
        Ok(())
    }

    /// The BSDF at hit `h` seen from direction `wo` (towards the viewer).
    #[inline(always)]
    pub fn bsdf(&self, h: &Hit, wo: crate::math::Vec3) -> Bsdf<'_> {
        let mesh = if self.materials.reads_mesh_attributes(h.material) { self.mesh_point(h) } else { None };
        self.materials.bsdf(h, wo, mesh)
    }

    /// `bsdf`, in spectral mode (`wl` given) lifted to the path's wavelengths: at a dispersive
    /// glass the path keeps only its hero wavelength from here on, and `beta`, its throughput,
    /// is multiplied by the factor that takes (`Wavelengths::terminate_secondary`). In RGB mode
    /// (`None`) it is `bsdf` exactly.
    #[inline(always)]
    pub fn bsdf_for(
        &self,
        h: &Hit,
        wo: crate::math::Vec3,
        wl: Option<&mut crate::spectrum::Wavelengths>,
        beta: &mut Color,
    ) -> Bsdf<'_> {
        // Inlined so that RGB mode builds the BSDF in its caller's frame (out of line, the
        // returned BSDF was copied: 64 instructions of memcpy per surface hit).
        match wl {
            None => self.bsdf(h, wo),
            Some(wl) => self.bsdf_lifted(h, wo, wl, beta),
        }
    }

    #[inline(never)]
    fn bsdf_lifted(
        &self,
        h: &Hit,
        wo: crate::math::Vec3,
        wl: &mut crate::spectrum::Wavelengths,
        beta: &mut Color,
    ) -> Bsdf<'_> {
        let bsdf = self.bsdf(h, wo);
        let front = crate::material::bsdf::front_side(wo, h.ng);
        let ratio = match self.materials.dispersion(h, front, wl.hero()) {
            Some(r) => {
                if let Some(f) = wl.terminate_secondary() {
                    *beta *= f;
                }
                r
            }
            None => 1.0,
        };
        bsdf.lifted(wl, ratio, &self.materials.spectra)
    }

    /// Light `light`'s emitted colour `le` (radiance, or radiance over a density) in the mode
    /// `wl` says: itself in RGB mode (`None`); in spectral mode the light's spectrum as the
    /// scene gave it, or else its colour's illuminant spectrum, at the path's wavelengths.
    #[inline]
    pub fn emission_in(&self, le: Color, light: u32, wl: Option<&crate::spectrum::Wavelengths>) -> Color {
        let Some(wl) = wl else { return le };
        match self.light_spectra.get(light as usize) {
            Some(&s) if s != NO_SPECTRUM => self.emission_spectra[s as usize].at(le, wl),
            _ => wl.illuminant(le),
        }
    }

    /// Where hit `h` is on a mesh triangle (the mesh, the triangle's index in it, the
    /// barycentrics of the hit point), for mesh attribute textures; `None` off meshes. Only
    /// top-level primitives are looked up: the loaders refuse mesh attributes in shape groups.
    #[cold]
    fn mesh_point(&self, h: &Hit) -> Option<crate::texture::MeshPoint<'_>> {
        if h.prim as usize >= self.bvh.len() {
            return None;
        }
        let crate::shape::Shape::Triangle(t) = self.bvh.prims().get(h.prim as usize, &self.meshes).shape else {
            return None;
        };
        let mesh = self.meshes.get(t.mesh as usize)?;
        let (e1, e2, d) = (t.p[1] - t.p[0], t.p[2] - t.p[0], h.p - t.p[0]);
        let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let (d1, d2) = (d.dot(e1), d.dot(e2));
        let det = d11 * d22 - d12 * d12;
        let (b1, b2) = if det > 0.0 { ((d22 * d1 - d12 * d2) / det, (d11 * d2 - d12 * d1) / det) } else { (0.0, 0.0) };
        Some(crate::texture::MeshPoint { mesh, triangle: t.index, b: [1.0 - b1 - b2, b1, b2] })
    }
}

/// A surface a ray crosses: one found by `Scene::for_each_crossing` (its surface worked out only
/// when asked: a shadow ray stopped by an opaque surface, or passing a `transparent` one, needs
/// none) or a closest hit.
pub enum Crossing<'a> {
    Traversed {
        scene: &'a Scene,
        ray: &'a Ray,
        hit: crate::shape::PrimHit,
        /// The primitive crossed (an index into the BVH's primitives).
        prim: u32,
    },
    Hit(&'a Hit),
}

impl Crossing<'_> {
    /// The geometric normal a closest hit there reports (`Hit::ng`).
    #[inline]
    pub fn ng(&self) -> Vec3 {
        match self {
            Crossing::Traversed { scene, ray, hit, prim } => scene.bvh.surface(*prim, ray, hit, &scene.meshes).ng,
            Crossing::Hit(h) => h.ng,
        }
    }

    /// The whole surface interaction there, as a closest hit reports it.
    #[inline]
    pub fn hit(&self) -> Hit {
        match self {
            Crossing::Traversed { scene, ray, hit, prim } => {
                let sp = scene.bvh.surface(*prim, ray, hit, &scene.meshes);
                let (material, light) = scene.bvh.material_light(*prim);
                Scene::hit(hit.t, &sp, material, light, *prim)
            }
            Crossing::Hit(h) => **h,
        }
    }
}
