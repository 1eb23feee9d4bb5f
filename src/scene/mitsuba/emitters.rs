//! Mitsuba emitters outside shapes: point, spot, directional, and the environment lights
//! constant and envmap.

use super::Build;
use super::props::Cx;
use super::xml::El;
use crate::geometry::Transform;
use crate::light::{Environment, Light, PhotonDisk};
use crate::math::{Color, Vec3};
use crate::scene::SceneError;
use crate::scene::environment::environment_map;
use crate::texture::image::load_image;

impl<'a> Cx<'a> {
    /// Reads a top-level emitter.
    pub(super) fn emitter(&mut self, el: &'a El, b: &mut Build) -> Result<(), SceneError> {
        let p = self.props(el)?;
        match p.kind.as_str() {
            "point" => {
                let intensity = self.color(&p, "intensity")?.unwrap_or(Color::ONE);
                let position = match (self.point(&p, "position")?, self.transform(&p, "to_world")?) {
                    (Some(_), Some(_)) => return Err(self.err(el, "give either `position` or `to_world`, not both")),
                    (Some(pos), None) => pos,
                    (None, Some(x)) => x.t.point(Vec3::ZERO),
                    (None, None) => Vec3::ZERO,
                };
                b.geometry.add_light(Light::Point { position, intensity });
            }
            "spot" => {
                let intensity = self.color(&p, "intensity")?.unwrap_or(Color::ONE);
                let x = self.transform(&p, "to_world")?.map_or(Transform::IDENTITY, |x| x.t);
                let cutoff = self.float(&p, "cutoff_angle")?.unwrap_or(20.0);
                let beam = self.float(&p, "beam_width")?.unwrap_or(cutoff * 0.75);
                if !(cutoff > 0.0 && cutoff <= 90.0 && beam >= 0.0 && beam <= cutoff) {
                    return Err(self.err(el, format!("spot needs 0 <= beam_width <= cutoff_angle <= 90 degrees (got beam_width {beam}, cutoff_angle {cutoff})")));
                }
                if !self.object(&p, Some("texture"), "texture").is_empty() {
                    self.warn(el, "spot light textures are not supported and are ignored")?;
                }
                let direction = x.vector(Vec3::Z).normalize_or_zero();
                if direction == Vec3::ZERO {
                    return Err(self.err(el, "spot light to_world has no +z direction"));
                }
                b.geometry.add_light(Light::Spot {
                    position: x.point(Vec3::ZERO),
                    direction,
                    intensity,
                    cos_total: cutoff.to_radians().cos(),
                    cos_falloff: beam.to_radians().cos(),
                });
            }
            "directional" => {
                let irradiance = self.color(&p, "irradiance")?.unwrap_or(Color::ONE);
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
            }
            "constant" => {
                let radiance = self.color(&p, "radiance")?.unwrap_or(Color::ONE);
                b.geometry.set_environment(Environment::constant(radiance)).map_err(|e| self.err(el, e))?;
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
                let path = self.src(fel).base.join(&file);
                let image = load_image(&path, false).map_err(|e| self.err(fel, e.to_string()))?;
                b.geometry.note_file(&path);
                let env = environment_map(&image, scale, &x).map_err(|e| self.err(el, e))?;
                b.geometry.set_environment(env).map_err(|e| self.err(el, e))?;
            }
            "area" => return Err(self.err(el, "an area emitter must be nested inside a <shape>")),
            other => {
                self.warn(el, format!("emitter `{other}` is not supported and is skipped"))?;
                for u in &p.used {
                    u.set(true);
                }
            }
        }
        self.finish(&p)?;
        Ok(())
    }
}
