//! Mitsuba emitters outside shapes: point, spot (with its texture), projector, directional, and
//! the environment lights constant and envmap.

use super::Build;
use super::plugins::PluginKind;
use super::props::Cx;
use super::xml::El;
use crate::geometry::Transform;
use crate::light::{Environment, Light, NO_TEXTURE, PhotonDisk, Projector, Spot};
use crate::math::{Color, Frame, Vec3};
use crate::scene::environment::environment_map;
use crate::scene::{FileKind, SceneError};
use crate::spectrum::SpectrumUse;
use crate::texture::image::load_image;

impl<'a> Cx<'a> {
    /// A texture a light casts, read by direction: anything but a mesh attribute, which needs
    /// a surface.
    fn surface_free_texture(&mut self, tex: &'a El, b: &mut Build) -> Result<u32, SceneError> {
        let t = self.texture(tex, b)?;
        if let crate::texture::Texture::MeshAttribute { name, .. } = &b.geometry.textures()[t as usize] {
            return Err(self.err(tex, format!("mesh attribute `{name}` cannot be cast by a light")));
        }
        Ok(t)
    }

    /// Reads a top-level emitter.
    pub(super) fn emitter(&mut self, el: &'a El, b: &mut Build) -> Result<(), SceneError> {
        let p = self.props(el)?;
        // The light this emitter adds (for its spectrum).
        let first = b.geometry.light_count();
        match p.kind.as_str() {
            "point" => {
                let (intensity, spectrum) = self.emission_color(&p, "intensity")?;
                let intensity = intensity.unwrap_or(Color::ONE);
                let position = match (self.point(&p, "position")?, self.transform(&p, "to_world")?) {
                    (Some(_), Some(_)) => return Err(self.err(el, "give either `position` or `to_world`, not both")),
                    (Some(pos), None) => pos,
                    (None, Some(x)) => x.t.point(Vec3::ZERO),
                    (None, None) => Vec3::ZERO,
                };
                b.geometry.add_light(Light::Point { position, intensity });
                b.geometry.keep_emission_spectrum(Some(first), spectrum, intensity);
            }
            "spot" => {
                let (intensity, spectrum) = self.emission_color(&p, "intensity")?;
                let intensity = intensity.unwrap_or(Color::ONE);
                let x = self.transform(&p, "to_world")?.map_or(Transform::IDENTITY, |x| x.t);
                let cutoff = self.float(&p, "cutoff_angle")?.unwrap_or(20.0);
                let beam = self.float(&p, "beam_width")?.unwrap_or(cutoff * 0.75);
                if !(cutoff > 0.0 && cutoff <= 90.0 && beam >= 0.0 && beam <= cutoff) {
                    return Err(self.err(el, format!("spot needs 0 <= beam_width <= cutoff_angle <= 90 degrees (got beam_width {beam}, cutoff_angle {cutoff})")));
                }
                let texture = match self.object(&p, Some("texture"), "texture").first() {
                    Some(&(tex, _)) => self.surface_free_texture(tex, b)?,
                    None => NO_TEXTURE,
                };
                let frame = self.light_frame(el, &x)?;
                b.geometry.add_light(Light::Spot(Spot::new(
                    x.point(Vec3::ZERO),
                    frame,
                    intensity,
                    cutoff,
                    beam,
                    texture,
                )));
                b.geometry.keep_emission_spectrum(Some(first), spectrum, intensity);
            }
            "projector" => {
                let x = self.transform(&p, "to_world")?.map_or(Transform::IDENTITY, |x| x.t);
                let frame = self.light_frame(el, &x)?;
                let scale = self.float(&p, "scale")?.unwrap_or(1.0);
                let (texture, size, mean) = match self.object(&p, Some("irradiance"), "texture").first() {
                    Some(&(tex, _)) => {
                        let t = self.surface_free_texture(tex, b)?;
                        let texture = &b.geometry.textures()[t as usize];
                        (t, texture.resolution().unwrap_or((1, 1)), texture.mean())
                    }
                    None => match self.color_for(&p, "irradiance", SpectrumUse::Emission)? {
                        // A constant irradiance: the texture's value becomes the intensity.
                        Some(c) => (NO_TEXTURE, (1, 1), c),
                        None => (NO_TEXTURE, (1, 1), Color::ONE),
                    },
                };
                let aspect = size.0 as f32 / size.1 as f32;
                let fov = self.float(&p, "fov")?.unwrap_or(50.0);
                if !(fov > 0.0 && fov < 180.0) {
                    return Err(self.err(el, format!("projector fov must be between 0 and 180 degrees, found {fov}")));
                }
                let t = (fov.to_radians() * 0.5).tan();
                let axis = self.string(&p, "fov_axis")?.map(|(s, _)| s);
                // tan of the half-angle along x, from the axis the fov applies to.
                let tan_x = match axis.as_deref().unwrap_or("x") {
                    "x" => t,
                    "y" => t * aspect,
                    "diagonal" => t * aspect / (1.0 + aspect * aspect).sqrt(),
                    "smaller" => {
                        if aspect > 1.0 {
                            t * aspect
                        } else {
                            t
                        }
                    }
                    "larger" => {
                        if aspect > 1.0 {
                            t
                        } else {
                            t * aspect
                        }
                    }
                    other => {
                        return Err(self
                            .err(el, format!("fov_axis must be x, y, diagonal, smaller or larger, found `{other}`")));
                    }
                };
                let constant = if texture == NO_TEXTURE { mean } else { Color::ONE };
                b.geometry.add_light(Light::Projector(Projector {
                    position: x.point(Vec3::ZERO),
                    frame,
                    intensity: constant * (std::f32::consts::PI * scale),
                    tan_x,
                    tan_y: tan_x / aspect,
                    texture,
                    mean: if texture == NO_TEXTURE { Color::ONE } else { mean },
                }));
            }
            "directional" => {
                let (irradiance, spectrum) = self.emission_color(&p, "irradiance")?;
                let irradiance = irradiance.unwrap_or(Color::ONE);
                let direction = match (self.point(&p, "direction")?, self.transform(&p, "to_world")?) {
                    (Some(_), Some(_)) => return Err(self.err(el, "give either `direction` or `to_world`, not both")),
                    (Some(d), None) => d,
                    (None, Some(x)) => x.t.vector(Vec3::Z),
                    (None, None) => Vec3::Z,
                };
                let direction = direction.normalize_or_zero();
                if direction == Vec3::ZERO {
                    return Err(self.err(el, "directional light needs a non-zero direction"));
                }
                b.geometry.add_light(Light::Directional { direction, irradiance, disk: PhotonDisk::default() });
                b.geometry.keep_emission_spectrum(Some(first), spectrum, irradiance);
            }
            "constant" => {
                let (radiance, spectrum) = self.emission_color(&p, "radiance")?;
                let radiance = radiance.unwrap_or(Color::ONE);
                b.geometry.set_environment(Environment::constant(radiance)).map_err(|e| self.err(el, e))?;
                b.geometry.keep_emission_spectrum(None, spectrum, radiance);
            }
            "envmap" => {
                if self.prop(&p, "bitmap").is_some() {
                    return Err(self.err(el, "an envmap needs `filename`; a `bitmap` object is not supported"));
                }
                let (file, fel) = self
                    .string(&p, "filename")?
                    .ok_or_else(|| self.err(el, "an envmap needs <string name=\"filename\" value=\"...\"/>"))?;
                let scale = self.float(&p, "scale")?.unwrap_or(1.0);
                if scale < 0.0 {
                    return Err(self.err(el, format!("envmap `scale` must not be negative (got {scale})")));
                }
                if self.boolean(&p, "mis_compensation")?.unwrap_or(false) {
                    self.warn(el, "`mis_compensation` is not supported: the envmap is sampled by luminance alone")?;
                }
                let x = self.transform(&p, "to_world")?.map_or(Transform::IDENTITY, |x| x.t);
                let path = self.resolve_file(fel, &file)?;
                self.files.open(&path, FileKind::Image)?;
                let image = load_image(&path, false).map_err(|e| self.err(fel, e.to_string()))?;
                let env = environment_map(&image, scale, &x).map_err(|e| self.err(el, e))?;
                b.geometry.set_environment(env).map_err(|e| self.err(el, e))?;
            }
            "area" => return Err(self.err(el, "an area emitter must be nested inside a <shape>")),
            other => {
                self.unsupported(el, PluginKind::Emitter, other, " and is skipped")?;
                for u in &p.used {
                    u.set(true);
                }
            }
        }
        self.finish(&p)?;
        Ok(())
    }

    /// The orthonormal frame of a light's `to_world`: z the direction it shines, x and y its
    /// image axes (Mitsuba's local frame, rotation only).
    fn light_frame(&self, el: &'a El, x: &Transform) -> Result<Frame, SceneError> {
        let z = x.vector(Vec3::Z).normalize_or_zero();
        if z == Vec3::ZERO {
            return Err(self.err(el, "the light's to_world has no +z direction"));
        }
        let f = Frame::from_z_x(z, x.vector(Vec3::X));
        if !f.x.is_finite() || f.x == Vec3::ZERO {
            return Ok(Frame::from_z(z));
        }
        // Keep the handedness of the transform's y axis (a mirroring to_world mirrors the image).
        let y = if f.y.dot(x.vector(Vec3::Y)) < 0.0 { -f.y } else { f.y };
        Ok(Frame { x: f.x, y, z })
    }
}
