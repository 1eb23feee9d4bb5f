//! Surface materials in the seed report's model (eq. 1-2): ambient k_a, diffuse k_d with a colour,
//! Phong specular k_s with exponent n, mirror reflection k_r, transmission k_t with an index of
//! refraction, and the four kinds the report mixes in one scene.

pub mod bsdf;
pub mod fresnel;

use crate::math::Color;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaterialKind {
    /// Ambient, diffuse and Phong highlight only.
    Diffuse,
    /// Adds mirror reflection weighted by k_r.
    Reflective,
    /// Adds reflection k_r and refraction k_t with fixed coefficients.
    Transparent,
    /// Reflection and refraction weighted by the Fresnel equations: k_s from eq. 5-7, k_t = 1 - k_s.
    Dielectric,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    pub kind: MaterialKind,
    pub color: Color,
    pub ka: f32,
    pub kd: f32,
    /// Phong highlight coefficient (eq. 1).
    pub ks: f32,
    /// Phong exponent n.
    pub exponent: f32,
    /// Mirror reflection coefficient (Reflective, Transparent).
    pub kr: f32,
    /// Transmission coefficient (Transparent).
    pub kt: f32,
    /// Index of refraction of the inside of the object (Transparent, Dielectric).
    pub ior: f32,
    /// Radiance emitted from the front side (area lights only).
    pub emission: Color,
    /// The area light this material belongs to (`u32::MAX` for none).
    pub light: u32,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            kind: MaterialKind::Diffuse,
            color: Color::splat(0.8),
            ka: 0.1,
            kd: 0.8,
            ks: 0.0,
            exponent: 32.0,
            kr: 0.0,
            kt: 0.0,
            ior: 1.5,
            emission: Color::ZERO,
            light: u32::MAX,
        }
    }
}

impl Material {
    /// The material of an area light's surface: black, emitting `radiance`.
    pub fn emitter(radiance: Color, light: u32) -> Self {
        Material { color: Color::ZERO, ka: 0.0, kd: 0.0, emission: radiance, light, ..Material::default() }
    }

    /// True when the material has a perfectly specular (mirror or refracting) part, so light
    /// arriving through it can form caustics.
    pub fn is_specular(&self) -> bool {
        match self.kind {
            MaterialKind::Diffuse => false,
            MaterialKind::Reflective => self.kr > 0.0,
            MaterialKind::Transparent => self.kr > 0.0 || self.kt > 0.0,
            MaterialKind::Dielectric => true,
        }
    }

    #[inline]
    pub fn is_emitter(&self) -> bool {
        self.light != u32::MAX
    }

    /// True when light passes through the surface (refraction happens).
    #[inline]
    pub fn transmits(&self) -> bool {
        matches!(self.kind, MaterialKind::Transparent | MaterialKind::Dielectric)
    }
}
