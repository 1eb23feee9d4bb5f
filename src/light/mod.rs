//! Light sources, in physical units. A closed set of `Copy` variants; each can be sampled from a
//! shading point (`sample`, for shadow rays and next-event estimation, with `pdf_li` its density
//! for multiple importance sampling) and can start a path of light (`sample_le`, for photons,
//! light tracing and bidirectional methods, with `pdf_le` its densities). A light reads its own
//! textures (a spot's or projector's projected image, an area light's radiance texture) from the
//! scene's textures it is given: no sample leaves without them. Area lights
//! belong to an emitting primitive, which knows its light by index (`Primitive::light`), and
//! sample through a copy of that primitive's shape (`Shape::sample_towards`). Environment lights (`environment`:
//! a map or a constant) surround the scene; they and directional lights send their photons in
//! through a `PhotonDisk` covering the scene (`disk`).
//!
//! Units: point and spot intensity in W/sr, directional irradiance in W/m^2, area-light radiance
//! in W/(m^2 sr); scene lengths count as metres. The classic Whitted integrator reads the same
//! values as the seed report's "light intensity" (colour x intensity, falling off as 1/d^2).

mod disk;
mod environment;

pub use disk::{PLANE_REACH, PhotonDisk};
pub use environment::{EnvMap, Environment};

use crate::geometry::Ray;
use crate::math::{Color, Frame, Vec2, Vec3, luminance};
use crate::sampling::warp::{cosine_hemisphere, uniform_cone, uniform_sphere};
use crate::shape::Shape;
use crate::texture::Texture;
use std::f32::consts::PI;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// Isotropic point light; `intensity` is colour x intensity in W/sr.
    Point { position: Vec3, intensity: Color },
    /// A point light emitting into a cone around its frame's z axis, as Mitsuba 3's `spot`: full
    /// intensity within the beam width, then fading linearly in angle to zero at the cutoff
    /// angle, optionally through a texture projected onto the square circumscribing the cone.
    Spot(Spot),
    /// Mitsuba 3's `projector`: a pinhole that projects a texture (irradiance on a virtual image
    /// plane at distance 1 along its z axis) like a perspective camera in reverse.
    Projector(Projector),
    /// Light from infinitely far away; `direction` is the unit direction the light travels,
    /// `irradiance` what a surface facing it receives. Its photons enter through `disk` (set when
    /// the scene is built), which also gives its power.
    Directional { direction: Vec3, irradiance: Color, disk: PhotonDisk },
    /// A shape emitting from its front side (the side its normals point to): `radiance`, times
    /// the texture at the point's uv when it has one (Mitsuba's `area` emitter with a radiance
    /// texture). The shape is a copy of the emitting primitive's.
    Area { shape: Shape, radiance: Color, texture: Option<EmissionTexture> },
    /// Light from every direction at infinity: an environment map or a constant radiance, seen
    /// by rays that leave the scene.
    Environment(Environment),
}

/// A texture that modulates an area light's radiance, with its mean over uv (the light's power
/// is its untextured power times the mean).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmissionTexture {
    pub texture: u32,
    pub mean: Color,
    /// A triangle's vertex texture coordinates (a mesh's; `TRIANGLE_UV` when it has none).
    pub vertex_uv: [Vec2; 3],
}

impl EmissionTexture {
    /// Texture coordinates of the point of `shape` whose own surface coordinates are `uv`
    /// (`Hit::uv`, `SurfaceSample::uv`): a triangle's vertex coordinates interpolated by its
    /// barycentrics, `uv` itself on every other shape.
    #[inline]
    pub fn uv(&self, shape: &Shape, uv: Vec2) -> Vec2 {
        match shape {
            Shape::Triangle(_) => {
                let t = &self.vertex_uv;
                t[0] * (1.0 - uv.x - uv.y) + t[1] * uv.x + t[2] * uv.y
            }
            Shape::Sphere(_)
            | Shape::Quad(_)
            | Shape::Disk(_)
            | Shape::Cylinder(_)
            | Shape::Plane(_)
            | Shape::SdfVoxel(_) => uv,
        }
    }
}

/// No texture: a spot light of uniform intensity.
pub const NO_TEXTURE: u32 = u32::MAX;

/// A spot light (see [`Light::Spot`]); angles in radians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spot {
    pub position: Vec3,
    /// z: the direction the light shines; x and y orient the projected texture.
    pub frame: Frame,
    /// Intensity on the axis, W/sr.
    pub intensity: Color,
    pub cos_cutoff: f32,
    pub cos_beam: f32,
    pub cutoff: f32,
    /// cutoff - beam width.
    pub transition: f32,
    pub tan_cutoff: f32,
    /// Texture index in the scene's textures, or [`NO_TEXTURE`].
    pub texture: u32,
}

impl Spot {
    /// A spot at `position` shining along `frame.z`, with angles in degrees (0 <= beam <= cutoff
    /// <= 90 checked by the loaders).
    pub fn new(position: Vec3, frame: Frame, intensity: Color, cutoff_deg: f32, beam_deg: f32, texture: u32) -> Spot {
        let (cutoff, beam) = (cutoff_deg.to_radians(), beam_deg.to_radians());
        Spot {
            position,
            frame,
            intensity,
            cos_cutoff: cutoff.cos(),
            cos_beam: beam.cos(),
            cutoff,
            transition: cutoff - beam,
            tan_cutoff: cutoff.tan(),
            texture,
        }
    }

    /// Mitsuba's fall-off for a direction at cos `cos_theta` from the axis: 1 inside the beam,
    /// linear in the angle from the beam width to the cutoff, 0 beyond.
    #[inline]
    pub fn falloff(&self, cos_theta: f32) -> f32 {
        if !(cos_theta > self.cos_cutoff) {
            0.0
        } else if cos_theta >= self.cos_beam {
            1.0
        } else {
            ((self.cutoff - cos_theta.min(1.0).acos()) / self.transition).clamp(0.0, 1.0)
        }
    }

    /// The texture coordinates of a direction leaving the light (local frame), as Mitsuba maps
    /// them: the square circumscribing the cutoff cone, local +y towards v = 0.
    #[inline]
    fn uv(&self, local: Vec3) -> Vec2 {
        let k = 0.5 / (local.z * self.tan_cutoff);
        Vec2::new(0.5 + local.x * k, 0.5 + local.y * k)
    }
}

/// A projector (see [`Light::Projector`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projector {
    pub position: Vec3,
    /// z: the optical axis; image x runs along -x, image y (v = 0 at the top) along -y.
    pub frame: Frame,
    /// pi x scale: the intensity on the axis of a texel of irradiance 1 (W/sr).
    pub intensity: Color,
    /// Half-extent of the image plane at distance 1: tan(fov_x / 2) and tan(fov_y / 2).
    pub tan_x: f32,
    pub tan_y: f32,
    /// Texture index, or [`NO_TEXTURE`] for irradiance 1 everywhere.
    pub texture: u32,
    /// The texture's mean (1 without one): the share of the image plane's power it passes.
    pub mean: Color,
}

impl Projector {
    /// (uv, local direction) of a direction leaving the projector, `None` outside its image.
    #[inline]
    fn uv(&self, d: Vec3) -> Option<(Vec2, Vec3)> {
        let local = self.frame.to_local(d);
        if !(local.z > 0.0) {
            return None;
        }
        let (x, y) = (local.x / local.z, local.y / local.z);
        let uv = Vec2::new(0.5 - 0.5 * x / self.tan_x, 0.5 - 0.5 * y / self.tan_y);
        (uv.cmpge(Vec2::ZERO).all() && uv.cmple(Vec2::ONE).all()).then_some((uv, local))
    }

    /// Area of the image plane at distance 1.
    fn plane_area(&self) -> f32 {
        4.0 * self.tan_x * self.tan_y
    }
}

/// Light arriving at a point from one light sample: its contribution to a Monte Carlo estimate
/// is `f * radiance * |cos| / pdf`.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit direction from the shading point towards the light.
    pub wi: Vec3,
    /// Distance to the sampled light point along `wi` (infinite for directional lights).
    pub dist: f32,
    /// Radiance arriving along `wi`; for delta lights, the light's intensity over the squared
    /// distance (or a directional light's irradiance), which acts as radiance with a delta density.
    pub radiance: Color,
    /// Solid-angle density of the sample; 1 for delta lights.
    pub pdf: f32,
    /// The light is a delta light (point, spot, directional): no ray can hit it, so it takes no
    /// part in multiple importance sampling.
    pub delta: bool,
}

/// A sample of a delta light: no area, so no density.
#[inline(always)]
fn delta_sample(wi: Vec3, dist: f32, radiance: Color) -> LightSample {
    LightSample { wi, dist, radiance, pdf: 1.0, delta: true }
}

/// Light from a point light at `position` arriving at `p`: inverse-square fall-off.
#[inline(always)]
fn point_sample(position: Vec3, intensity: Color, p: Vec3) -> Option<LightSample> {
    let v = position - p;
    let d2 = v.length_squared();
    if !(d2 > 0.0) {
        return None;
    }
    let dist = d2.sqrt();
    Some(delta_sample(v / dist, dist, intensity / d2))
}

impl LightSample {
    /// The sample's Monte Carlo weight: radiance / pdf.
    #[inline]
    pub fn weight(&self) -> Color {
        self.radiance / self.pdf
    }
}

/// A ray leaving a light (`Light::sample_le`): the first vertex of a light path, with what the
/// light sends along it and the densities it was drawn with (pbrt-v4's `LightLeSample`).
#[derive(Clone, Copy, Debug)]
pub struct EmissionSample {
    pub ray: Ray,
    /// Normal at the emission point of an area light (the ray's direction for other lights).
    pub n: Vec3,
    /// What the light sends along the ray, textures applied: radiance (area and environment
    /// lights), intensity (point, spot, projector) or irradiance (directional).
    pub le: Color,
    /// Density of the ray's origin: per unit area on an area light or on the entry disk of a
    /// light at infinity; 1 for a light at a point (a delta position).
    pub pdf_pos: f32,
    /// Density of its direction, per unit solid angle; 1 for a directional light (a delta
    /// direction).
    pub pdf_dir: f32,
    /// le |cos| / (pdf_pos pdf_dir), worked out for each light in closed form: the flux a
    /// photon on this ray carries (before dividing by the number emitted and by the probability
    /// of having chosen the light), and a light path's starting weight.
    pub flux: Color,
}

impl Light {
    /// True for lights no ray can hit (points, spots, directional).
    #[inline]
    pub fn is_delta(&self) -> bool {
        match self {
            Light::Point { .. } | Light::Spot(_) | Light::Projector(_) | Light::Directional { .. } => true,
            Light::Area { .. } | Light::Environment(_) => false,
        }
    }

    /// True for lights at infinity (directional, environment), whose photons enter through a
    /// `PhotonDisk`.
    #[inline]
    pub fn is_infinite(&self) -> bool {
        match self {
            Light::Directional { .. } | Light::Environment(_) => true,
            Light::Point { .. } | Light::Spot(_) | Light::Projector(_) | Light::Area { .. } => false,
        }
    }

    /// Radiance an environment light sends along `-wi` (towards a ray leaving the scene in
    /// direction `wi`); zero for other lights.
    #[inline]
    pub fn environment_radiance(&self, wi: Vec3) -> Color {
        match self {
            Light::Environment(e) => e.radiance(wi),
            Light::Point { .. }
            | Light::Spot(_)
            | Light::Projector(_)
            | Light::Directional { .. }
            | Light::Area { .. } => Color::ZERO,
        }
    }

    /// Intensity (W/sr) a delta-position light sends in direction `d` (unit, leaving it),
    /// before any texture; zero for other lights.
    #[inline]
    pub fn intensity_towards(&self, d: Vec3) -> Color {
        match *self {
            Light::Point { intensity, .. } => intensity,
            Light::Spot(s) => s.intensity * s.falloff(d.dot(s.frame.z)),
            Light::Projector(p) => match p.uv(d) {
                // A texel of the image plane at distance 1 seen at angle a: dw = cos^3 a dA.
                Some((_, local)) => p.intensity / (local.z * local.z * local.z),
                None => Color::ZERO,
            },
            Light::Directional { .. } | Light::Area { .. } | Light::Environment(_) => Color::ZERO,
        }
    }

    /// The texture a spot or projector casts and where direction `d` (leaving the light) reads
    /// it: (texture index, uv).
    #[inline]
    pub fn projection(&self, d: Vec3) -> Option<(u32, Vec2)> {
        match *self {
            Light::Spot(s) if s.texture != NO_TEXTURE => {
                let local = s.frame.to_local(d);
                (local.z > 0.0).then(|| (s.texture, s.uv(local)))
            }
            Light::Projector(p) if p.texture != NO_TEXTURE => p.uv(d).map(|(uv, _)| (p.texture, uv)),
            Light::Spot(_)
            | Light::Projector(_)
            | Light::Point { .. }
            | Light::Directional { .. }
            | Light::Area { .. }
            | Light::Environment(_) => None,
        }
    }

    /// The texture factor of light leaving this light in direction `d` from the point whose
    /// surface coordinates are `uv` (on an area light): an area light's radiance texture there,
    /// the texture a spot or projector casts along `d`, 1 for every other light (and for lights
    /// without a texture). The usual answer, 1 for a light without a texture, is given in the
    /// caller; the lookup is out of line (a call to learn the factor is 1 was 1.5% of the path
    /// tracer's instructions on the Cornell box).
    #[inline(always)]
    pub fn texture_factor(&self, uv: Vec2, d: Vec3, textures: &[Texture]) -> Color {
        match self {
            Light::Area { texture: Some(_), .. } | Light::Spot(_) | Light::Projector(_) => {
                self.texture_lookup(uv, d, textures)
            }
            Light::Area { texture: None, .. }
            | Light::Point { .. }
            | Light::Directional { .. }
            | Light::Environment(_) => Color::ONE,
        }
    }

    /// `texture_factor` of a light that may have a texture.
    #[inline(never)]
    fn texture_lookup(&self, uv: Vec2, d: Vec3, textures: &[Texture]) -> Color {
        match self {
            Light::Area { shape, texture: Some(t), .. } => textures[t.texture as usize].eval(t.uv(shape, uv)),
            Light::Spot(_) | Light::Projector(_) => match self.projection(d) {
                Some((t, uv)) => textures[t as usize].eval(uv),
                None => Color::ONE,
            },
            _ => Color::ONE,
        }
    }

    /// Total emitted power (W per channel).
    pub fn power(&self) -> Color {
        match *self {
            Light::Point { intensity, .. } => 4.0 * PI * intensity,
            Light::Spot(s) => {
                // 2 pi times the integral of the fall-off times sin(theta) over theta: 1 - cos b
                // inside the beam, and for the linear ramp from b to c
                // ((c - b) cos b + sin b - sin c) / (c - b).
                let b = s.cutoff - s.transition;
                let ramp = if s.transition > 1e-4 {
                    (s.transition * b.cos() + b.sin() - s.cutoff.sin()) / s.transition
                } else {
                    0.0
                };
                s.intensity * 2.0 * PI * ((1.0 - s.cos_beam) + ramp)
            }
            // Untextured power times the texture's mean: the image plane's irradiance integral.
            Light::Projector(p) => p.intensity * p.plane_area() * p.mean,
            Light::Directional { irradiance, disk, .. } => irradiance * disk.area(),
            Light::Area { shape, radiance, texture } => {
                radiance * PI * shape.area() * texture.map_or(Color::ONE, |t| t.mean)
            }
            Light::Environment(e) => e.power(),
        }
    }

    /// Samples light arriving at `p` (textures applied); `u` picks a point on area lights and a
    /// direction of an environment. `None` when `p` receives nothing from this sample (outside a
    /// spot cone, behind an area light, at the light).
    // The point light, the commonest in classic scenes, is inlined into the caller: called out
    // of line, `p` went through memory and its load stalled on the store just before it.
    // Area lights, the physical integrators' commonest, are inlined for the same reason.
    #[inline(always)]
    pub fn sample(&self, p: Vec3, u: Vec2, textures: &[Texture]) -> Option<LightSample> {
        match self {
            Light::Point { position, intensity } => point_sample(*position, *intensity, p),
            Light::Area { shape, radiance, .. } => self.area_sample(shape, *radiance, p, u, textures),
            Light::Spot(_) | Light::Projector(_) | Light::Directional { .. } | Light::Environment(_) => {
                self.sample_other(p, u, textures)
            }
        }
    }

    /// `sample` of an area light of `shape` and `radiance` (its texture read through
    /// `texture_factor`).
    #[inline(always)]
    fn area_sample(
        &self,
        shape: &Shape,
        radiance: Color,
        p: Vec3,
        u: Vec2,
        textures: &[Texture],
    ) -> Option<LightSample> {
        let (s, pdf) = shape.sample_towards(p, u)?;
        let v = s.p - p;
        let d2 = v.length_squared();
        if !(d2 > 0.0) || !(pdf > 0.0) {
            return None;
        }
        let dist = d2.sqrt();
        let wi = v / dist;
        if s.n.dot(-wi) <= 0.0 {
            return None;
        }
        let radiance = radiance * self.texture_factor(s.uv, -wi, textures);
        Some(LightSample { wi, dist, radiance, pdf, delta: false })
    }

    /// `sample`, out of line: every light (`sample` itself answers for point lights).
    #[inline(never)]
    fn sample_other(&self, p: Vec3, u: Vec2, textures: &[Texture]) -> Option<LightSample> {
        match *self {
            Light::Point { position, intensity } => point_sample(position, intensity, p),
            Light::Spot(Spot { position, .. }) | Light::Projector(Projector { position, .. }) => {
                let v = position - p;
                let d2 = v.length_squared();
                if !(d2 > 0.0) {
                    return None;
                }
                let dist = d2.sqrt();
                let wi = v / dist;
                let i = self.intensity_towards(-wi);
                (i.max_element() > 0.0)
                    .then(|| delta_sample(wi, dist, i / d2 * self.texture_factor(Vec2::ZERO, -wi, textures)))
            }
            Light::Directional { direction, irradiance, .. } => {
                Some(delta_sample(-direction, f32::INFINITY, irradiance))
            }
            Light::Area { shape, radiance, .. } => self.area_sample(&shape, radiance, p, u, textures),
            Light::Environment(e) => {
                let (wi, radiance, pdf) = e.sample(u)?;
                Some(LightSample { wi, dist: f32::INFINITY, radiance, pdf, delta: false })
            }
        }
    }

    /// Solid-angle density with which `sample` from `p` would pick the light point `q` (normal
    /// `n`) in direction `wi`; 0 for delta lights. Used for multiple importance sampling.
    #[inline]
    pub fn pdf_li(&self, p: Vec3, q: Vec3, n: Vec3, wi: Vec3) -> f32 {
        match *self {
            Light::Area { shape, .. } => shape.pdf_towards(p, q, n, wi),
            Light::Environment(e) => e.pdf(wi),
            Light::Point { .. } | Light::Spot(_) | Light::Projector(_) | Light::Directional { .. } => 0.0,
        }
    }

    /// Radiance an area light sends from the point with normal `n` in direction `w`, its texture
    /// read at the point's surface coordinates `uv` (asked for only then: a sphere's cost an arc
    /// tangent); zero for other lights and behind the surface.
    #[inline]
    pub fn emitted(&self, n: Vec3, w: Vec3, uv: impl FnOnce() -> Vec2, textures: &[Texture]) -> Color {
        match *self {
            Light::Area { shape, radiance, texture } => {
                if !(n.dot(w) > 0.0) {
                    return Color::ZERO;
                }
                match texture {
                    Some(t) => radiance * textures[t.texture as usize].eval(t.uv(&shape, uv())),
                    None => radiance,
                }
            }
            Light::Point { .. }
            | Light::Spot(_)
            | Light::Projector(_)
            | Light::Directional { .. }
            | Light::Environment(_) => Color::ZERO,
        }
    }

    /// Samples a ray of light leaving the light, from its emission distribution (`u_pos` picks
    /// the point on an area light or on the entry disk of a light at infinity, `u_dir` the
    /// direction), with what it carries and both densities (`EmissionSample`). Rays leave area
    /// lights from just outside the sampled point's error bound.
    pub fn sample_le(&self, u_pos: Vec2, u_dir: Vec2, textures: &[Texture]) -> Option<EmissionSample> {
        match *self {
            Light::Point { position, intensity } => {
                let d = uniform_sphere(u_dir);
                let pdf_dir = 0.25 / PI;
                Some(EmissionSample {
                    ray: Ray::new(position, d),
                    n: d,
                    le: intensity,
                    pdf_pos: 1.0,
                    pdf_dir,
                    flux: intensity * 4.0 * PI,
                })
            }
            Light::Spot(s) => {
                let local = uniform_cone(u_dir, s.cos_cutoff);
                let d = s.frame.to_world(local);
                let pdf = 1.0 / (2.0 * PI * (1.0 - s.cos_cutoff));
                let tex = self.texture_factor(Vec2::ZERO, d, textures);
                let falloff = s.falloff(local.z);
                let le = s.intensity * falloff * tex;
                let flux = s.intensity * (falloff / pdf) * tex;
                Some(EmissionSample { ray: Ray::new(s.position, d), n: d, le, pdf_pos: 1.0, pdf_dir: pdf, flux })
            }
            Light::Projector(p) => {
                // A uniform point of the image plane: pdf(d) = 1 / (area cos^3) and
                // intensity(d) = pi scale / cos^3 times the texel, so the flux is pi scale x area
                // times the texel.
                let x = (1.0 - 2.0 * u_dir.x) * p.tan_x;
                let y = (1.0 - 2.0 * u_dir.y) * p.tan_y;
                let local = Vec3::new(x, y, 1.0).normalize();
                let d = p.frame.to_world(local);
                let tex = self.texture_factor(Vec2::ZERO, d, textures);
                let cos3 = local.z * local.z * local.z;
                let le = p.intensity / cos3 * tex;
                let pdf_dir = 1.0 / (p.plane_area() * cos3);
                let flux = p.intensity * p.plane_area() * tex;
                Some(EmissionSample { ray: Ray::new(p.position, d), n: d, le, pdf_pos: 1.0, pdf_dir, flux })
            }
            Light::Directional { direction, irradiance, disk } => {
                let (ray, inv_density) = disk.ray(direction, u_pos)?;
                let flux = irradiance * inv_density;
                Some(EmissionSample {
                    ray,
                    n: direction,
                    le: irradiance,
                    pdf_pos: 1.0 / inv_density,
                    pdf_dir: 1.0,
                    flux,
                })
            }
            Light::Area { shape, radiance, .. } => {
                let s = shape.sample_area(u_pos)?;
                let local = cosine_hemisphere(u_dir);
                let d = Frame::from_z(s.n).to_world(local);
                let ray = Ray::spawn(s.p, s.p_error, s.n, d, 0.0);
                let tex = self.texture_factor(s.uv, d, textures);
                // L cos / (pdf_area * cos / pi) = L * area * pi.
                let flux = radiance * (shape.area() * PI) * tex;
                let le = radiance * tex;
                Some(EmissionSample { ray, n: s.n, le, pdf_pos: 1.0 / shape.area(), pdf_dir: local.z / PI, flux })
            }
            Light::Environment(e) => e.sample_le(u_pos, u_dir),
        }
    }

    /// Densities (position, direction) with which `sample_le` gives `ray`, leaving a point with
    /// normal `n` (area lights); as pbrt-v4's `PDF_Le`, a delta position has position density 0
    /// and a delta direction direction density 0 (what `sample_le` reports as 1 there is a
    /// discrete probability, not a density).
    pub fn pdf_le(&self, ray: &Ray, n: Vec3) -> (f32, f32) {
        match *self {
            Light::Point { .. } => (0.0, 0.25 / PI),
            Light::Spot(s) => {
                let inside = ray.d.dot(s.frame.z) > s.cos_cutoff;
                (0.0, if inside { 1.0 / (2.0 * PI * (1.0 - s.cos_cutoff)) } else { 0.0 })
            }
            Light::Projector(p) => match p.uv(ray.d) {
                Some((_, local)) => (0.0, 1.0 / (p.plane_area() * local.z * local.z * local.z)),
                None => (0.0, 0.0),
            },
            Light::Directional { disk, .. } => (disk.pdf_ray(ray), 0.0),
            Light::Area { shape, .. } => {
                let cos = n.dot(ray.d);
                (1.0 / shape.area(), if cos > 0.0 { cos / PI } else { 0.0 })
            }
            Light::Environment(e) => (e.disk.pdf_ray(ray), e.pdf(-ray.d)),
        }
    }

    /// Weight for choosing this light among others: its power's luminance, counting for lights
    /// at infinity only what enters through the core of their photon disk (the part planes add
    /// would make them crowd out the lights inside the scene).
    pub fn selection_weight(&self) -> f32 {
        let power = match *self {
            Light::Directional { irradiance, disk, .. } => irradiance * disk.core_area(),
            Light::Environment(e) => e.integral() * e.disk.core_area(),
            Light::Point { .. } | Light::Spot(_) | Light::Projector(_) | Light::Area { .. } => self.power(),
        };
        luminance(power).max(0.0)
    }
}

#[cfg(test)]
mod emission_tests;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng32;
    use crate::shape::{Quad, Sphere, Triangle};

    #[test]
    fn photon_flux_averages_to_power() {
        let quad = Quad::new(Vec3::ZERO, Vec3::X * 2.0, Vec3::Z * -0.5).unwrap();
        let lights = [
            Light::Point { position: Vec3::ONE, intensity: Color::new(1.0, 2.0, 3.0) },
            Light::Spot(Spot::new(Vec3::ZERO, Frame::from_z(-Vec3::Y), Color::splat(5.0), 60.0, 36.0, NO_TEXTURE)),
            Light::Spot(Spot::new(Vec3::ZERO, Frame::from_z(Vec3::X), Color::splat(2.0), 20.0, 20.0, NO_TEXTURE)),
            Light::Projector(Projector {
                position: Vec3::ONE,
                frame: Frame::from_z(Vec3::Z),
                intensity: Color::splat(PI * 2.0),
                tan_x: 0.7,
                tan_y: 0.4,
                texture: NO_TEXTURE,
                mean: Color::ONE,
            }),
            Light::Directional {
                direction: -Vec3::Y,
                irradiance: Color::splat(2.0),
                disk: PhotonDisk::new(Vec3::ZERO, 3.0, false),
            },
            Light::Directional {
                direction: Vec3::new(0.2, -1.0, 0.4).normalize(),
                irradiance: Color::splat(2.0),
                disk: PhotonDisk::new(Vec3::ONE, 0.5, true),
            },
            Light::Area { shape: Shape::Quad(quad), radiance: Color::splat(4.0), texture: None },
            Light::Area {
                shape: Shape::Triangle(Triangle::new(Vec3::ZERO, Vec3::X * 2.0, Vec3::new(0.3, 1.5, -0.2))),
                radiance: Color::splat(2.5),
                texture: None,
            },
            Light::Area {
                shape: Shape::Sphere(Sphere::new(Vec3::ZERO, 0.5)),
                radiance: Color::splat(1.5),
                texture: None,
            },
        ];
        let mut rng = Rng32::new(3);
        for l in lights {
            // A disk reaching far past the scene carries photons of very unequal flux: more of them.
            let n = if l.is_infinite() { 2_000_000 } else { 200_000 };
            let mut sum = Color::ZERO;
            for _ in 0..n {
                sum += l.sample_le(rng.uniform2(), rng.uniform2(), &[]).unwrap().flux;
            }
            let mean = sum / n as f32;
            let p = l.power();
            assert!((mean - p).abs().max_element() < 0.01 * p.max_element(), "{l:?}: {mean} vs {p}");
        }
    }

    #[test]
    fn spot_falloff_is_mitsubas_linear_ramp_in_angle() {
        // Values Mitsuba 3.9.1 gives (default cutoff 20, beam 15; and cutoff 30, beam 10).
        let frame = Frame::from_z(Vec3::Z);
        let a = Spot::new(Vec3::ZERO, frame, Color::ONE, 20.0, 15.0, NO_TEXTURE);
        let b = Spot::new(Vec3::ZERO, frame, Color::ONE, 30.0, 10.0, NO_TEXTURE);
        let at = |s: &Spot, deg: f32| s.falloff(deg.to_radians().cos());
        for (deg, want) in [(0.0, 1.0), (15.0, 1.0), (16.0, 0.8), (17.5, 0.5), (19.0, 0.2), (19.9, 0.02), (20.0, 0.0)] {
            assert!((at(&a, deg) - want).abs() < 2e-4, "{deg}: {} vs {want}", at(&a, deg));
        }
        for (deg, want) in [(20.0, 0.5), (25.0, 0.25), (29.0, 0.05), (45.0, 0.0)] {
            assert!((at(&b, deg) - want).abs() < 2e-4, "{deg}: {} vs {want}", at(&b, deg));
        }
    }

    #[test]
    fn spot_power_is_the_integral_of_its_falloff() {
        for (cutoff, beam) in [(20.0, 15.0), (60.0, 10.0), (90.0, 0.0), (30.0, 30.0)] {
            let s = Spot::new(Vec3::ZERO, Frame::from_z(Vec3::Y), Color::splat(3.0), cutoff, beam, NO_TEXTURE);
            // Midpoint rule over theta of 2 pi I f(theta) sin(theta).
            let n = 200_000;
            let h = std::f64::consts::PI / n as f64;
            let integral: f64 = (0..n)
                .map(|i| {
                    let t = (i as f64 + 0.5) * h;
                    s.falloff(t.cos() as f32) as f64 * t.sin() * h
                })
                .sum::<f64>()
                * 2.0
                * std::f64::consts::PI
                * 3.0;
            let p = Light::Spot(s).power().r() as f64;
            assert!((p - integral).abs() < 1e-4 * integral, "{cutoff}/{beam}: {p} vs {integral}");
        }
    }

    #[test]
    fn projector_maps_its_image_plane_as_a_camera_does() {
        let p = Projector {
            position: Vec3::ZERO,
            frame: Frame { x: Vec3::X, y: Vec3::Y, z: Vec3::Z },
            intensity: Color::splat(PI),
            tan_x: 0.5,
            tan_y: 0.25,
            texture: 0,
            mean: Color::ONE,
        };
        let light = Light::Projector(p);
        // The axis reads the image centre; local +x is image-left (u = 0), +y the top (v = 0).
        let uv = |d: Vec3| light.projection(d.normalize()).map(|(_, uv)| uv);
        assert!((uv(Vec3::Z).unwrap() - Vec2::splat(0.5)).length() < 1e-6);
        assert!((uv(Vec3::new(0.5, 0.25, 1.0)).unwrap() - Vec2::ZERO).length() < 1e-6);
        assert!((uv(Vec3::new(-0.5, -0.25, 1.0)).unwrap() - Vec2::ONE).length() < 1e-6);
        assert!(uv(Vec3::new(0.6, 0.0, 1.0)).is_none() && uv(-Vec3::Z).is_none());
        // Mitsuba's received value: irradiance x pi x scale / (z_local^2 cos a), z_local the
        // depth along the axis: a point at depth 2, off axis.
        let target = Vec3::new(0.3, -0.2, 2.0);
        let white = [Texture::Constant(Color::ONE)];
        let ls = light.sample(Vec3::ZERO, Vec2::ZERO, &white);
        assert!(ls.is_none(), "the projector's own position receives nothing");
        let seen =
            Light::Projector(Projector { position: -target, ..p }).sample(Vec3::ZERO, Vec2::ZERO, &white).unwrap();
        let cos_a = target.normalize().z;
        let want = PI / (target.z * target.z * cos_a);
        assert!((seen.radiance.r() - want).abs() < 1e-5 * want, "{} vs {want}", seen.radiance.r());
    }

    #[test]
    fn area_light_sampling_integrates_solid_angle() {
        // Sum of 1/pdf over samples estimates the solid angle the light subtends: for a sphere
        // of radius r at distance d it is 2 pi (1 - sqrt(1 - r^2/d^2)); for the quad compare the
        // pdf of sampled points with `pdf`.
        let s = Shape::Sphere(Sphere::new(Vec3::new(0.0, 0.0, -4.0), 1.0));
        let mut rng = Rng32::new(9);
        let p = Vec3::ZERO;
        for _ in 0..1000 {
            let (ss, pdf) = s.sample_towards(p, rng.uniform2()).unwrap();
            let (q, n) = (ss.p, ss.n);
            assert!(((q - Vec3::new(0.0, 0.0, -4.0)).length() - 1.0).abs() < 1e-4);
            let wi = (q - p).normalize();
            assert!((s.pdf_towards(p, q, n, wi) - pdf).abs() < 1e-4 * pdf);
            assert!(n.dot(-wi) >= -1e-3);
        }
        let quad = Shape::Quad(Quad::new(Vec3::new(-1.0, 2.0, -1.0), Vec3::Z * 2.0, Vec3::X * 2.0).unwrap());
        // Facing down (e1 x e2 = z x x = +y... flip check): the quad's normal is +y, so a point
        // below sees its back and gets nothing; a point above is lit.
        assert!(quad.sample_towards(Vec3::ZERO, Vec2::splat(0.5)).is_none());
        let above = Vec3::new(0.0, 5.0, 0.0);
        let mut omega = 0.0f64;
        let n = 100_000;
        for _ in 0..n {
            let (_, pdf) = quad.sample_towards(above, rng.uniform2()).unwrap();
            omega += 1.0 / pdf as f64;
        }
        omega /= n as f64;
        // Solid angle of a 2 x 2 square at distance 3 (centred): 4 asin(a b / sqrt((a^2+d^2)(b^2+d^2))).
        let (a, b, d) = (1.0f64, 1.0f64, 3.0f64);
        let exact = 4.0 * (a * b / ((a * a + d * d) * (b * b + d * d)).sqrt()).asin();
        assert!((omega - exact).abs() < 0.01 * exact, "{omega} vs {exact}");
        // A triangle (facing +y, seen from above) against Van Oosterom and Strackee's formula
        // tan(omega / 2) = |a . (b x c)| / (abc + (a . b) c + (a . c) b + (b . c) a).
        let tri = [Vec3::new(-1.0, 2.0, -1.0), Vec3::new(0.5, 2.0, 1.0), Vec3::new(1.5, 2.0, -0.5)];
        let t = Shape::Triangle(Triangle::new(tri[0], tri[1], tri[2]));
        let mut omega = 0.0f64;
        for _ in 0..n {
            let (s, pdf) = t.sample_towards(above, rng.uniform2()).unwrap();
            let wi = (s.p - above).normalize();
            assert!((t.pdf_towards(above, s.p, s.n, wi) - pdf).abs() <= 1e-3 * pdf);
            omega += 1.0 / pdf as f64;
        }
        omega /= n as f64;
        let [a, b, c] = tri.map(|v| (v - above).as_dvec3());
        let (la, lb, lc) = (a.length(), b.length(), c.length());
        let exact =
            2.0 * (a.dot(b.cross(c)).abs() / (la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la)).atan();
        assert!((omega - exact).abs() < 0.01 * exact, "triangle: {omega} vs {exact}");
    }
}

/// Chooses lights in proportion to their power (uniformly when none has any), or for direct
/// lighting half by power and half uniformly.
#[derive(Clone, Debug, Default)]
pub struct LightPicker {
    /// Cumulative selection probabilities; the last is 1.
    cdf: Vec<f32>,
    prob: Vec<f32>,
}

impl LightPicker {
    /// In proportion to power: what photon and light-path emission needs (photons of equal
    /// flux).
    pub fn new(lights: &[Light]) -> Self {
        Self::mixed(lights, 0.0)
    }

    /// For next-event estimation: half the choices by power, half uniform. Power alone starves
    /// a light that is weak overall but dominates where it shines (a spot light beside a sky:
    /// the sky's power chose the spot once in hundreds of samples, and its pool of light was a
    /// speckle that 1024 samples per pixel did not smooth, where Mitsuba, choosing uniformly,
    /// was smooth); the uniform half bounds every light's share below by 1 / (2 n).
    pub fn for_direct_light(lights: &[Light]) -> Self {
        Self::mixed(lights, 0.5)
    }

    /// Probabilities (1 - uniform) * power share + uniform / n.
    fn mixed(lights: &[Light], uniform: f32) -> Self {
        let w: Vec<f32> = lights.iter().map(|l| l.selection_weight()).collect();
        let total: f32 = w.iter().sum();
        let even = 1.0 / lights.len().max(1) as f32;
        let prob: Vec<f32> = if total > 0.0 && total.is_finite() {
            w.iter().map(|x| (1.0 - uniform) * (x / total) + uniform * even).collect()
        } else {
            vec![even; lights.len()]
        };
        let mut acc = 0.0;
        let cdf = prob
            .iter()
            .map(|p| {
                acc += p;
                acc
            })
            .collect();
        LightPicker { cdf, prob }
    }

    /// (light index, probability of choosing it) for a uniform number `u`.
    #[inline]
    pub fn pick(&self, u: f32) -> Option<(usize, f32)> {
        if self.cdf.is_empty() {
            return None;
        }
        let i = self.cdf.partition_point(|&c| c <= u).min(self.cdf.len() - 1);
        // Skip zero-probability entries that a rounding edge could land on.
        let i = (i..self.cdf.len()).chain(0..i).find(|&j| self.prob[j] > 0.0)?;
        Some((i, self.prob[i]))
    }

    #[inline]
    pub fn prob(&self, i: usize) -> f32 {
        self.prob.get(i).copied().unwrap_or(0.0)
    }
}
