//! The `[camera]` section of a TOML scene and the film keys of `[render]`: `crop`, `filter` and
//! `sample_border` (see `docs/scene-format.md`).

use super::Cx;
use super::schema::{CameraTable, RenderDesc};
use crate::camera::{CameraDesc, FieldOfView, FovAxis, Placement};
use crate::film::Crop;
use crate::film::filter::Filter;
use crate::math::{Vec2, Vec3};
use crate::scene::SceneError;
use crate::scene::de::{Finite, Positive};
use crate::scene::desc::FilmDesc;
use serde::Deserialize;
use serde::de::{Deserializer, Error, MapAccess, Visitor, value::MapAccessDeserializer};
use toml::Spanned;
use toml::de::DeValue;

/// `filter = "gaussian"`, or a table with the filter's `type` and parameters.
pub struct FilterSpec(pub Filter);

/// The keys of a filter table.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FilterKeys {
    #[serde(rename = "type")]
    kind: String,
    radius: Option<Positive>,
    stddev: Option<Positive>,
    #[serde(rename = "B", alias = "b")]
    b: Option<Finite>,
    #[serde(rename = "C", alias = "c")]
    c: Option<Finite>,
    lobes: Option<u32>,
}

/// Each filter's parameters, as Mitsuba names them.
const FILTER_KEYS: &[(&str, &[&str])] = &[
    ("box", &[]),
    ("tent", &["radius"]),
    ("gaussian", &["stddev"]),
    ("mitchell", &["B", "C"]),
    ("catmullrom", &[]),
    ("lanczos", &["lobes"]),
];

impl FilterKeys {
    fn filter<E: Error>(self) -> Result<Filter, E> {
        let Some((kind, allowed)) = FILTER_KEYS.iter().find(|k| k.0 == self.kind) else {
            let names: Vec<&str> = FILTER_KEYS.iter().map(|k| k.0).collect();
            let hint = crate::scene::mitsuba::closest(&self.kind, names.iter().copied())
                .map_or(String::new(), |k| format!(" (did you mean `{k}`?)"));
            return Err(E::custom(format!(
                "unknown filter `{}`{hint}; expected one of: {}",
                self.kind,
                names.join(", ")
            )));
        };
        let given = [
            ("radius", self.radius.is_some()),
            ("stddev", self.stddev.is_some()),
            ("B", self.b.is_some()),
            ("C", self.c.is_some()),
            ("lobes", self.lobes.is_some()),
        ];
        if let Some((key, _)) = given.iter().find(|(k, g)| *g && !allowed.contains(k)) {
            let takes = if allowed.is_empty() { "no parameters".to_string() } else { allowed.join(", ") };
            return Err(E::custom(format!("a {kind} filter has no `{key}` (it takes {takes})")));
        }
        let filter = match *kind {
            "box" => Filter::Box,
            "tent" => Filter::Tent { radius: self.radius.map_or(1.0, |r| r.0) },
            "gaussian" => Filter::Gaussian { stddev: self.stddev.map_or(0.5, |s| s.0) },
            "mitchell" => {
                Filter::Mitchell { b: self.b.map_or(1.0 / 3.0, |b| b.0), c: self.c.map_or(1.0 / 3.0, |c| c.0) }
            }
            "catmullrom" => Filter::Mitchell { b: 0.0, c: 0.5 },
            _ => Filter::Lanczos { lobes: self.lobes.unwrap_or(3) },
        };
        filter.check().map_err(E::custom)?;
        Ok(filter)
    }
}

impl<'de> Deserialize<'de> for FilterSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = FilterSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(
                    "a filter name such as \"gaussian\", or a table such as { type = \"gaussian\", stddev = 0.5 }",
                )
            }
            fn visit_str<E: Error>(self, name: &str) -> Result<FilterSpec, E> {
                // Parameters after a colon, as `--filter` takes them (`gaussian:stddev=0.3`).
                if name.contains(':') {
                    return Filter::parse(name).map(FilterSpec).map_err(E::custom);
                }
                let keys =
                    FilterKeys { kind: name.to_string(), radius: None, stddev: None, b: None, c: None, lobes: None };
                keys.filter().map(FilterSpec)
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<FilterSpec, A::Error> {
                FilterKeys::deserialize(MapAccessDeserializer::new(map))?.filter().map(FilterSpec)
            }
        }
        d.deserialize_any(V)
    }
}

/// `crop = { x = 100, y = 50, width = 64, height = 32 }`: the window of the image to render.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CropSpec {
    #[serde(default)]
    x: u32,
    #[serde(default)]
    y: u32,
    width: u32,
    height: u32,
}

impl<'a> Cx<'a> {
    /// The film keys of `[render]`, the crop checked against the image size the file gives.
    pub(super) fn film(&self, render: &RenderDesc, width: u32, height: u32) -> Result<FilmDesc, SceneError> {
        let crop = match &render.crop {
            None => None,
            Some(c) => {
                let s = c.get_ref();
                let crop = Crop { x: s.x, y: s.y, width: s.width, height: s.height };
                if !crop.fits(width, height) {
                    return Err(self.at(
                        c.span(),
                        format!(
                            "the crop window ({} x {} at {}, {}) must be non-empty and inside the {width} x {height} image",
                            s.width, s.height, s.x, s.y
                        ),
                    ));
                }
                Some(crop)
            }
        };
        Ok(FilmDesc {
            crop,
            // The file's `filter` is one of the render's options, applied with them.
            filter: Filter::Box,
            sample_border: render.sample_border.unwrap_or(false),
            // `aov` too is one of the render's options.
            aovs: Default::default(),
            xyz: false,
        })
    }

    /// Step 2: the camera (present: `sections` checked it).
    pub(super) fn camera(&self, value: Option<Spanned<DeValue<'a>>>) -> Result<CameraDesc, SceneError> {
        let Some(value) = value else { return Err(self.at(0..0, "missing [camera] section")) };
        let span = value.span();
        let c: CameraTable = self.de(value)?;
        let (eye, look_at) = (c.eye.0, c.look_at.0);
        let up = c.up.map_or(Vec3::Y, |u| u.0);
        let w = (eye - look_at).normalize_or_zero();
        if w == Vec3::ZERO {
            return Err(self.at(span, "camera `eye` and `look_at` are the same point"));
        }
        if up.cross(w).length() < 1e-6 {
            return Err(self.at(span, "camera `up` is parallel to the viewing direction"));
        }
        let orthographic = match &c.projection {
            None => false,
            Some(p) => match p.get_ref().as_str() {
                "perspective" => false,
                "orthographic" => true,
                other => {
                    return Err(self.at(
                        p.span(),
                        format!("unknown projection `{other}`; expected \"perspective\" or \"orthographic\""),
                    ));
                }
            },
        };
        let principal_point = c.principal_point_offset.map_or(Vec2::ZERO, |p| p.0);
        let placement = Placement::LookAt { eye, target: look_at, up };
        if orthographic {
            let perspective_keys = [
                ("fov", c.fov.is_some()),
                ("view_distance", c.view_distance.is_some()),
                ("lens_radius", c.lens_radius.is_some()),
                ("focal_distance", c.focal_distance.is_some()),
                ("focus_on", c.focus_on.is_some()),
            ];
            if let Some((key, _)) = perspective_keys.iter().find(|k| k.1) {
                return Err(self.at(span, format!("`{key}` does not apply to an orthographic camera")));
            }
            let (size, axis) = match (c.view_width, c.view_height) {
                (Some(w), None) => (w.0, FovAxis::X),
                (None, Some(h)) => (h.0, FovAxis::Y),
                _ => {
                    return Err(self.at(
                        span,
                        "an orthographic camera needs one of `view_width` or `view_height` (the view's size in scene units)",
                    ));
                }
            };
            return Ok(CameraDesc {
                placement,
                fov: FieldOfView::Orthographic { size, axis },
                lens_radius: 0.0,
                focal_distance: (look_at - eye).length(),
                principal_point,
            });
        }
        if c.view_width.is_some() || c.view_height.is_some() {
            return Err(self.at(
                span,
                "`view_width` and `view_height` belong to an orthographic camera (projection = \"orthographic\")",
            ));
        }
        let fov = match (c.fov, c.view_distance) {
            (Some(_), Some(_)) => return Err(self.at(span, "give either `fov` or `view_distance`, not both")),
            (Some(f), None) if f.0 >= 180.0 => {
                return Err(self.at(span, format!("fov must be below 180 degrees, got {}", f.0)));
            }
            (Some(f), None) => FieldOfView::Angle { degrees: f.0 as f64, axis: FovAxis::Y },
            (None, Some(d)) => FieldOfView::ViewDistance(d.0),
            (None, None) => FieldOfView::Angle { degrees: 45.0, axis: FovAxis::Y },
        };
        let focal_distance = match (c.focal_distance, c.focus_on) {
            (Some(_), Some(_)) => return Err(self.at(span, "give either `focal_distance` or `focus_on`, not both")),
            (Some(f), None) => f.0,
            (None, Some(p)) => {
                // Distance of the point from the lens along the viewing axis.
                let f = (p.0 - eye).dot(-w);
                if !(f > 0.0) {
                    return Err(self.at(span, "`focus_on` is not in front of the camera"));
                }
                f
            }
            (None, None) => (look_at - eye).length(),
        };
        Ok(CameraDesc {
            placement,
            fov,
            lens_radius: c.lens_radius.map_or(0.0, |r| r.0),
            focal_distance,
            principal_point,
        })
    }
}
