//! Mitsuba `<texture>` elements (`bitmap`, `checkerboard`) and the parameters that may be a
//! texture or a constant. Images are read once per file and decoding and shared.

use super::Build;
use super::plugins::PluginKind;
use super::props::{Cx, Props};
use super::xml::El;
use crate::material::{ColorParam, FloatParam, Param};
use crate::math::{Color, Vec2};
use crate::scene::{FileKind, SceneError};
use crate::texture::image::load_image;
use crate::texture::{Bitmap, Filter, Texture, Wrap};
use glam::{Affine2, Mat2};
use std::sync::Arc;

impl<'a> Cx<'a> {
    /// A colour parameter: a constant (`<rgb>`, `<spectrum>`, `<float>`) or a nested texture;
    /// spectra are converted as reflectances.
    pub(super) fn color_param(
        &mut self,
        p: &Props<'a>,
        name: &str,
        b: &mut Build,
    ) -> Result<Option<ColorParam>, SceneError> {
        self.color_param_for(p, name, b, crate::spectrum::SpectrumUse::Reflectance)
    }

    /// `color_param` with spectra converted for `usage`.
    pub(super) fn color_param_for(
        &mut self,
        p: &Props<'a>,
        name: &str,
        b: &mut Build,
        usage: crate::spectrum::SpectrumUse,
    ) -> Result<Option<ColorParam>, SceneError> {
        if let Some(el) = self.prop(p, name) {
            return self.color_of_for(el, name, usage).map(|c| Some(Param::Const(c)));
        }
        if let Some(&(tex, _)) = self.object(p, Some(name), "texture").first() {
            return self.texture(tex, b).map(|t| Some(Param::Texture(t)));
        }
        Ok(None)
    }

    /// `color_param_for`, and the spectrum a constant was given as (`given_id`; none for a
    /// texture, which spectral mode lifts from its colours).
    pub(super) fn color_param_given(
        &mut self,
        p: &Props<'a>,
        name: &str,
        b: &mut Build,
        usage: crate::spectrum::SpectrumUse,
    ) -> Result<(Option<ColorParam>, crate::material::SpectrumId), SceneError> {
        self.given_spectrum = None;
        let param = self.color_param_for(p, name, b, usage)?;
        let id = match param {
            Some(Param::Const(c)) => self.given_id(b, c),
            _ => crate::material::SpectrumId::NONE,
        };
        self.given_spectrum = None;
        Ok((param, id))
    }

    /// A scalar parameter: a number, a colour read as Mitsuba reads it for a scalar (the mean
    /// of its channels), or a nested texture (read with `Texture::eval_1`).
    pub(super) fn float_param(
        &mut self,
        p: &Props<'a>,
        name: &str,
        b: &mut Build,
    ) -> Result<Option<FloatParam>, SceneError> {
        if let Some(el) = self.prop(p, name) {
            let c = self.color_of(el, name)?;
            return Ok(Some(Param::Const(c.mean())));
        }
        if let Some(&(tex, _)) = self.object(p, Some(name), "texture").first() {
            return self.texture(tex, b).map(|t| Some(Param::Texture(t)));
        }
        Ok(None)
    }

    /// Builds the texture of a `<texture>` element (once per element); returns its index.
    pub(super) fn texture(&mut self, el: &'a El, b: &mut Build) -> Result<u32, SceneError> {
        let key = el as *const El as usize;
        if let Some(&i) = b.texture_cache.get(&key) {
            return Ok(i);
        }
        let p = self.props(el)?;
        let t = match p.kind.as_str() {
            "bitmap" => self.bitmap(&p, b)?,
            "checkerboard" => {
                let c0 = self.constant_color(&p, "color0", Color::splat(0.4), b)?;
                let c1 = self.constant_color(&p, "color1", Color::splat(0.2), b)?;
                let to_uv = self.to_uv(&p)?;
                Texture::Checkerboard { color0: c0, color1: c1, to_uv }
            }
            // Values stored on a mesh's vertices or faces (PLY properties), read where a ray
            // hits the mesh; the shapes that use it are checked to have it.
            "mesh_attribute" => {
                let Some((name, _)) = self.string(&p, "name")? else {
                    return Err(self.err(el, "a mesh_attribute texture needs <string name=\"name\" value=\"vertex_color\"/> (or another attribute)"));
                };
                if !(name.starts_with("vertex_") || name.starts_with("face_")) {
                    return Err(self.err(el, format!("mesh attribute `{name}` must start with `vertex_` or `face_`")));
                }
                let scale = self.float(&p, "scale")?.unwrap_or(1.0);
                Texture::MeshAttribute { name, scale }
            }
            other => {
                for u in &p.used {
                    u.set(true);
                }
                self.unsupported(el, PluginKind::Texture, other, ": rendered as grey 0.5")?;
                Texture::Constant(Color::splat(0.5))
            }
        };
        self.finish(&p)?;
        let i = b.geometry.add_texture(t);
        b.texture_cache.insert(key, i);
        Ok(i)
    }

    /// A colour that must be constant here (a checkerboard's colours): a nested texture is
    /// replaced by its mean, with a warning.
    fn constant_color(
        &mut self,
        p: &Props<'a>,
        name: &str,
        default: Color,
        b: &mut Build,
    ) -> Result<Color, SceneError> {
        match self.color_param(p, name, b)? {
            None => Ok(default),
            Some(Param::Const(c)) => Ok(c),
            Some(Param::Texture(t)) => {
                let c = b.geometry.textures()[t as usize].mean();
                self.warn(p.el, format!("a texture for `{name}` is not supported here: its mean {c} is used"))?;
                Ok(c)
            }
        }
    }

    fn bitmap(&mut self, p: &Props<'a>, b: &mut Build) -> Result<Texture, SceneError> {
        let (file, fel) = self
            .string(p, "filename")?
            .ok_or_else(|| self.err(p.el, "a bitmap texture needs <string name=\"filename\" value=\"...\"/>"))?;
        let raw = self.boolean(p, "raw")?.unwrap_or(false);
        let filter = match self.string(p, "filter_type")? {
            None => Filter::Bilinear,
            Some((s, at)) => match s.as_str() {
                "bilinear" => Filter::Bilinear,
                "nearest" => Filter::Nearest,
                _ => return Err(self.err(at, format!("filter_type must be `bilinear` or `nearest`, found `{s}`"))),
            },
        };
        let wrap = match self.string(p, "wrap_mode")? {
            None => Wrap::Repeat,
            Some((s, at)) => match s.as_str() {
                "repeat" => Wrap::Repeat,
                "mirror" => Wrap::Mirror,
                "clamp" => Wrap::Clamp,
                _ => {
                    return Err(self.err(at, format!("wrap_mode must be `repeat`, `mirror` or `clamp`, found `{s}`")));
                }
            },
        };
        // Storage precision and acceleration switches change nothing we render.
        for name in ["format", "accel"] {
            let _ = self.prop(p, name);
        }
        let to_uv = self.to_uv(p)?;
        let path = self.resolve_file(fel, &file)?;
        let key = (path.clone(), raw);
        let image = match b.images.get(&key) {
            Some(img) => img.clone(),
            None => {
                self.files.open(&path, FileKind::Image)?;
                let img = Arc::new(load_image(&path, raw).map_err(|e| self.err(fel, e.to_string()))?);
                b.images.insert(key, img.clone());
                img
            }
        };
        Ok(Texture::Bitmap(Bitmap { image, filter, wrap, to_uv }))
    }

    /// The `to_uv` transform of a texture: the 2-D affine part of a `<transform>`, which maps
    /// (u, v, 0) as a 4x4 transform does, or (u, v, 1) as a 3x3 `<matrix>` of 9 values does.
    fn to_uv(&self, p: &Props<'a>) -> Result<Affine2, SceneError> {
        let Some(el) = self.prop(p, "to_uv") else { return Ok(Affine2::IDENTITY) };
        let x = self.transform_of(el)?;
        let m = x.t.m;
        let is_3x3 = el.children.len() == 1
            && el.children[0].tag == "matrix"
            && self.attr(&el.children[0], "value")?.is_some_and(|(v, _)| {
                v.split(|c: char| c == ',' || c.is_whitespace()).filter(|s| !s.is_empty()).count() == 9
            });
        // glam matrices are column-major: m.col(j)[i] is row i, column j.
        let linear = Mat2::from_cols(Vec2::new(m.x_axis.x, m.x_axis.y), Vec2::new(m.y_axis.x, m.y_axis.y));
        let translation = if is_3x3 { Vec2::new(m.z_axis.x, m.z_axis.y) } else { Vec2::new(m.w_axis.x, m.w_axis.y) };
        Ok(Affine2::from_mat2_translation(linear, translation))
    }
}
