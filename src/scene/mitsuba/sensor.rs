//! The Mitsuba sensor with its film and sampler: camera, image size and sample count.

use super::props::Cx;
use super::xml::El;
use crate::camera::{CameraDesc, FieldOfView, FovAxis, Placement};
use crate::geometry::Transform;
use crate::math::Vec3;
use crate::sampling::SamplerKind;
use crate::scene::SceneError;
use crate::scene::desc::{MAX_SIDE, SamplerDesc};

/// What the sensor, its film and its sampler describe.
pub(super) struct SensorOut {
    pub camera: CameraDesc,
    pub width: u32,
    pub height: u32,
    pub sampler: SamplerDesc,
}

impl<'a> Cx<'a> {
    pub(super) fn sensor(&mut self, sensor: Option<&'a El>, root: &'a El) -> Result<SensorOut, SceneError> {
        let Some(el) = sensor else {
            return Err(self
                .err(root, "the scene has no <sensor>: add <sensor type=\"perspective\"> with a to_world transform"));
        };
        let p = self.props(el)?;
        let thin = match p.kind.as_str() {
            "perspective" => false,
            "thinlens" => true,
            other => {
                return Err(
                    self.err(el, format!("sensor `{other}` is not supported; expected perspective or thinlens"))
                );
            }
        };
        let (width, height) = self.film(&p)?;
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
        self.finish(&p)?;
        let camera =
            CameraDesc { placement, fov: FieldOfView::Angle { degrees, axis }, lens_radius, focal_distance: focus };
        Ok(SensorOut { camera, width, height, sampler })
    }

    /// The film's size (Mitsuba's default 768 x 576); its other settings do not change values.
    fn film(&mut self, p: &super::props::Props<'a>) -> Result<(u32, u32), SceneError> {
        let (mut width, mut height) = (768u32, 576u32);
        let films = self.object(p, None, "film");
        let Some(&(fel, _)) = films.first() else { return Ok((width, height)) };
        let fp = self.props(fel)?;
        if fp.kind != "hdrfilm" && fp.kind != "specfilm" {
            self.warn(fel, format!("film `{}` is treated as hdrfilm", fp.kind))?;
        }
        for (name, v) in [("width", &mut width), ("height", &mut height)] {
            if let Some((x, xel)) = self.integer(&fp, name)? {
                if !(1..=MAX_SIDE as i64).contains(&x) {
                    return Err(self.err(xel, format!("film {name} must be 1 to {MAX_SIDE}, found {x}")));
                }
                *v = x as u32;
            }
        }
        // Output-format settings do not change the rendered values.
        for name in [
            "file_format",
            "pixel_format",
            "component_format",
            "banner",
            "high_quality_edges",
            "sample_border",
            "compensate",
        ] {
            let _ = self.prop(&fp, name);
        }
        for (rel, at) in self.object(&fp, None, "rfilter") {
            let kind = self.attr(rel, "type")?.map_or(String::new(), |t| t.0);
            if kind != "box" {
                self.warn(
                    at,
                    format!(
                        "reconstruction filter `{kind}` is not supported: pixels average their samples (a box filter)"
                    ),
                )?;
            }
        }
        self.finish(&fp)?;
        Ok((width, height))
    }

    /// The sampler's kind, sample count (Mitsuba's default 4) and seed.
    fn sampler(&mut self, p: &super::props::Props<'a>) -> Result<SamplerDesc, SceneError> {
        let mut desc = SamplerDesc { spp: Some(4), ..SamplerDesc::default() };
        let Some(&(sel, _)) = self.object(p, None, "sampler").first() else { return Ok(desc) };
        let sp = self.props(sel)?;
        desc.kind = match sp.kind.as_str() {
            "independent" | "stratified" | "multijitter" | "orthogonal" => SamplerKind::Jittered,
            "ldsampler" => SamplerKind::Sobol,
            other => {
                self.warn(sel, format!("sampler `{other}` is not supported; jittered sampling is used"))?;
                SamplerKind::Jittered
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
