//! The Mitsuba sensor (perspective, thinlens, orthographic) with its film (size, crop window,
//! reconstruction filter) and sampler: camera, image and sample count.

use super::plugins::PluginKind;
use super::props::{Cx, Props};
use super::xml::El;
use crate::camera::{CameraDesc, FieldOfView, FovAxis, Placement};
use crate::film::Crop;
use crate::film::filter::Filter;
use crate::geometry::Transform;
use crate::math::{Vec2, Vec3};
use crate::sampling::SamplerKind;
use crate::scene::SceneError;
use crate::scene::desc::{FilmDesc, MAX_SIDE, SamplerDesc};

/// What the sensor, its film and its sampler describe.
pub(super) struct SensorOut<'a> {
    pub camera: CameraDesc,
    /// The medium the sensor sits in, built by the caller.
    pub medium: Option<&'a El>,
    pub width: u32,
    pub height: u32,
    pub film: FilmDesc,
    pub sampler: SamplerDesc,
}

impl<'a> Cx<'a> {
    pub(super) fn sensor(&mut self, sensor: Option<&'a El>, root: &'a El) -> Result<SensorOut<'a>, SceneError> {
        let Some(el) = sensor else {
            return Err(self
                .err(root, "the scene has no <sensor>: add <sensor type=\"perspective\"> with a to_world transform"));
        };
        let p = self.props(el)?;
        let thin = match p.kind.as_str() {
            "perspective" => false,
            "thinlens" => true,
            "orthographic" => return self.orthographic(el, &p),
            other => {
                let message = super::plugins::unknown(PluginKind::Sensor, other).unwrap_or_else(|| {
                    format!("sensor `{other}` is not supported; expected perspective, thinlens or orthographic")
                });
                return Err(self.err(el, message));
            }
        };
        let (width, height, film) = self.film(&p)?;
        let sampler = self.sampler(&p)?;

        let fov = self.float(&p, "fov")?;
        let focal_length = self.string(&p, "focal_length")?;
        let axis_given = self.string(&p, "fov_axis")?;
        let (degrees, axis) = match (fov, &focal_length) {
            (Some(_), Some(_)) => return Err(self.err(el, "give either `fov` or `focal_length`, not both")),
            (Some(f), None) => {
                let axis = match &axis_given {
                    None => FovAxis::X,
                    Some((a, at)) => match a.to_ascii_lowercase().as_str() {
                        "x" => FovAxis::X,
                        "y" => FovAxis::Y,
                        "diagonal" => FovAxis::Diagonal,
                        "smaller" => FovAxis::Smaller,
                        "larger" => FovAxis::Larger,
                        other => {
                            return Err(self.err(
                                at,
                                format!("fov_axis must be x, y, diagonal, smaller or larger, found `{other}`"),
                            ));
                        }
                    },
                };
                (f as f64, axis)
            }
            (None, fl) => {
                let (s, at) = fl.clone().unwrap_or(("50mm".into(), el));
                let v =
                    s.trim().trim_end_matches("mm").trim().parse::<f64>().ok().filter(|v| *v > 0.0 && v.is_finite());
                let Some(v) = v else {
                    return Err(self.err(at, format!("focal_length must be of the form 50mm, found `{s}`")));
                };
                // 35 mm film equivalent: the focal length gives the angle of the film diagonal.
                ((36.0f64.hypot(24.0) / (2.0 * v)).atan().to_degrees() * 2.0, FovAxis::Diagonal)
            }
        };
        if !(degrees > 0.0 && degrees < 180.0) {
            return Err(self.err(el, format!("fov must be between 0 and 180 degrees, found {degrees}")));
        }

        let (lens_radius, focus) = if thin {
            let r = self
                .float(&p, "aperture_radius")?
                .ok_or_else(|| self.err(el, "a thinlens sensor needs <float name=\"aperture_radius\">"))?;
            if r < 0.0 {
                return Err(self.err(el, format!("aperture_radius must be 0 or more, found {r}")));
            }
            (r, self.float(&p, "focus_distance")?)
        } else {
            (0.0, None)
        };
        let far_clip = self.float(&p, "far_clip")?.unwrap_or(1e4);
        let _ = self.float(&p, "near_clip")?;
        let focus = focus.unwrap_or(far_clip);
        if !(focus > 0.0) {
            return Err(self.err(el, format!("focus_distance must be positive, found {focus}")));
        }
        for name in ["shutter_open", "shutter_close"] {
            let _ = self.float(&p, name)?;
        }

        let xform = self.transform(&p, "to_world")?;
        let placement = match xform.as_ref().and_then(|x| x.lookat) {
            Some((eye, target, up)) => Placement::LookAt { eye, target, up },
            None => {
                let t = xform.as_ref().map_or(Transform::IDENTITY, |x| x.t);
                let origin = t.point(Vec3::ZERO);
                let (x, y, z) = (t.vector(Vec3::X), t.vector(Vec3::Y), t.vector(Vec3::Z));
                let orthonormal = [x, y, z].iter().all(|v| (v.length() - 1.0).abs() < 1e-3)
                    && x.dot(y).abs() < 1e-3
                    && y.dot(z).abs() < 1e-3
                    && z.dot(x).abs() < 1e-3;
                if !orthonormal {
                    return Err(self.err(el, "the sensor's to_world must only rotate and translate (Mitsuba does not allow scaling a camera)"));
                }
                Placement::Frame { origin, x, y, z }
            }
        };
        // Mitsuba reads the offsets on perspective sensors only; a thin lens shifts the same way.
        let principal_point = Vec2::new(
            self.float(&p, "principal_point_offset_x")?.unwrap_or(0.0),
            self.float(&p, "principal_point_offset_y")?.unwrap_or(0.0),
        );
        let medium = self.sensor_medium(&p)?;
        self.finish(&p)?;
        let camera = CameraDesc {
            placement,
            fov: FieldOfView::Angle { degrees, axis },
            lens_radius,
            focal_distance: focus,
            principal_point,
        };
        Ok(SensorOut { camera, medium, width, height, film, sampler })
    }

    /// The `<medium>` nested in (or referenced by) the sensor.
    fn sensor_medium(&self, p: &Props<'a>) -> Result<Option<&'a El>, SceneError> {
        let media = self.object(p, None, "medium");
        Ok(media.first().map(|m| m.0))
    }

    /// Mitsuba's `orthographic` sensor: its view is [-1, 1] across the film's width in the
    /// `to_world` frame, whose scale (allowed here, unlike for the other sensors) sets the
    /// extent. Rays start on the camera's plane (Mitsuba: on the near-clip plane).
    fn orthographic(&mut self, el: &'a El, p: &Props<'a>) -> Result<SensorOut<'a>, SceneError> {
        let (width, height, film) = self.film(p)?;
        let sampler = self.sampler(p)?;
        for name in ["near_clip", "far_clip", "shutter_open", "shutter_close"] {
            let _ = self.float(p, name)?;
        }
        let xform = self.transform(p, "to_world")?;
        let placement = match xform.as_ref().and_then(|x| x.lookat) {
            Some((eye, target, up)) => Placement::LookAt { eye, target, up },
            None => {
                let t = xform.as_ref().map_or(Transform::IDENTITY, |x| x.t);
                let (x, y, z) = (t.vector(Vec3::X), t.vector(Vec3::Y), t.vector(Vec3::Z));
                if !(z.length() > 0.0 && x.cross(y).length() > 0.0) {
                    return Err(self.err(el, "the orthographic sensor's to_world flattens the view"));
                }
                Placement::Frame { origin: t.point(Vec3::ZERO), x, y, z }
            }
        };
        let medium = self.sensor_medium(p)?;
        self.finish(p)?;
        let camera = CameraDesc {
            placement,
            fov: FieldOfView::Orthographic { size: 2.0, axis: FovAxis::X },
            lens_radius: 0.0,
            focal_distance: 1.0,
            principal_point: Vec2::ZERO,
        };
        Ok(SensorOut { camera, medium, width, height, film, sampler })
    }

    /// The film's size (Mitsuba's default 768 x 576), crop window and reconstruction filter
    /// (Mitsuba's default: Gaussian); its output settings do not change values.
    fn film(&mut self, p: &Props<'a>) -> Result<(u32, u32, FilmDesc), SceneError> {
        let (mut width, mut height) = (768u32, 576u32);
        let mut film = FilmDesc { filter: Filter::MITSUBA_DEFAULT, ..FilmDesc::default() };
        let films = self.object(p, None, "film");
        let Some(&(fel, _)) = films.first() else { return Ok((width, height, film)) };
        let fp = self.props(fel)?;
        if fp.kind != "hdrfilm" && fp.kind != "specfilm" {
            self.unsupported(fel, PluginKind::Film, &fp.kind, "; it is treated as hdrfilm")?;
        }
        for (name, v) in [("width", &mut width), ("height", &mut height)] {
            if let Some((x, xel)) = self.integer(&fp, name)? {
                if !(1..=MAX_SIDE as i64).contains(&x) {
                    return Err(self.err(xel, format!("film {name} must be 1 to {MAX_SIDE}, found {x}")));
                }
                *v = x as u32;
            }
        }
        // The crop window, as Mitsuba reads it: the size defaults to the whole film (so an offset
        // alone does not fit).
        let mut crop = [0u32, 0, width, height];
        let mut cropped = false;
        for (k, name) in ["crop_offset_x", "crop_offset_y", "crop_width", "crop_height"].iter().enumerate() {
            if let Some((v, vel)) = self.integer(&fp, name)? {
                if !(0..=MAX_SIDE as i64).contains(&v) {
                    return Err(self.err(vel, format!("film {name} must be 0 to {MAX_SIDE}, found {v}")));
                }
                crop[k] = v as u32;
                cropped = true;
            }
        }
        if cropped {
            let c = Crop { x: crop[0], y: crop[1], width: crop[2], height: crop[3] };
            if !c.fits(width, height) {
                return Err(self.err(
                    fel,
                    format!(
                        "the crop window ({} x {} at {}, {}) must be non-empty and inside the {width} x {height} film",
                        c.width, c.height, c.x, c.y
                    ),
                ));
            }
            film.crop = Some(c);
        }
        film.sample_border = self.boolean(&fp, "sample_border")?.unwrap_or(false);
        // Output-format settings do not change the rendered values.
        for name in ["file_format", "pixel_format", "component_format", "banner", "high_quality_edges", "compensate"] {
            let _ = self.prop(&fp, name);
        }
        let filters = self.object(&fp, None, "rfilter");
        if let Some(&(rel, _)) = filters.first() {
            film.filter = self.rfilter(rel)?;
        }
        self.finish(&fp)?;
        Ok((width, height, film))
    }

    /// A reconstruction filter with Mitsuba's parameters and defaults.
    fn rfilter(&mut self, el: &'a El) -> Result<Filter, SceneError> {
        let p = self.props(el)?;
        let number = |cx: &Self, name: &str, default: f32| -> Result<f32, SceneError> {
            Ok(cx.float(&p, name)?.unwrap_or(default))
        };
        let filter = match p.kind.as_str() {
            "box" => Filter::Box,
            "tent" => Filter::Tent { radius: number(self, "radius", 1.0)? },
            "gaussian" => Filter::Gaussian { stddev: number(self, "stddev", 0.5)? },
            "mitchell" => Filter::Mitchell { b: number(self, "B", 1.0 / 3.0)?, c: number(self, "C", 1.0 / 3.0)? },
            "catmullrom" => Filter::Mitchell { b: 0.0, c: 0.5 },
            "lanczos" => match self.integer(&p, "lobes")? {
                None => Filter::Lanczos { lobes: 3 },
                Some((n, _)) if (1..=crate::film::filter::MAX_RADIUS as i64).contains(&n) => {
                    Filter::Lanczos { lobes: n as u32 }
                }
                Some((n, nel)) => return Err(self.err(nel, format!("lanczos lobes must be 1 to 64, found {n}"))),
            },
            other => {
                self.unsupported(el, PluginKind::Filter, other, "; Mitsuba's default (gaussian) is used")?;
                for u in &p.used {
                    u.set(true);
                }
                Filter::MITSUBA_DEFAULT
            }
        };
        filter.check().map_err(|m| self.err(el, m))?;
        self.finish(&p)?;
        Ok(filter)
    }

    /// The sampler's kind, sample count (Mitsuba's default 4) and seed.
    fn sampler(&mut self, p: &Props<'a>) -> Result<SamplerDesc, SceneError> {
        let mut desc = SamplerDesc { spp: Some(4), ..SamplerDesc::default() };
        let Some(&(sel, _)) = self.object(p, None, "sampler").first() else { return Ok(desc) };
        let sp = self.props(sel)?;
        desc.kind = match sp.kind.as_str() {
            // Independent samples are Mitsuba's plainest pattern: the renderer's own choice
            // (`SamplerDesc::resolved_kind`) serves the author at least as well.
            "independent" => None,
            "stratified" | "multijitter" | "orthogonal" => Some(SamplerKind::Jittered),
            "ldsampler" => Some(SamplerKind::Sobol),
            other => {
                self.unsupported(sel, PluginKind::Sampler, other, "; the default pattern is used")?;
                None
            }
        };
        if let Some((n, nel)) = self.integer(&sp, "sample_count")? {
            if !(1..=u32::MAX as i64).contains(&n) {
                return Err(self.err(nel, format!("sample_count must be at least 1, found {n}")));
            }
            desc.spp = Some(n as u32);
        }
        if let Some((s, sel2)) = self.integer(&sp, "seed")? {
            if s < 0 {
                return Err(self.err(sel2, format!("seed must be 0 or more, found {s}")));
            }
            desc.seed = s as u64;
        }
        let _ = self.boolean(&sp, "jitter")?;
        let _ = self.integer(&sp, "dimension")?;
        let _ = self.integer(&sp, "strength")?;
        self.finish(&sp)?;
        Ok(desc)
    }
}
