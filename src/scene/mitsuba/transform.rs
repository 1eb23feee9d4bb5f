//! Mitsuba `<transform>` elements: translate, rotate, scale, matrix and lookat, composed in the
//! order written.

use super::props::{Cx, Props, Xform};
use super::xml::El;
use crate::geometry::Transform;
use crate::math::Vec3;
use crate::scene::SceneError;
use glam::{Mat4, Vec4};

impl<'a> Cx<'a> {
    /// Reads a `<transform>` element: its operations composed in the order written.
    pub(super) fn transform_of(&self, el: &El) -> Result<Xform, SceneError> {
        if el.tag != "transform" {
            return Err(self.err(el, format!("expected a <transform>, found <{}>", el.tag)));
        }
        let mut t = Transform::IDENTITY;
        let mut lookat = None;
        let n_ops = el.children.len();
        for op in &el.children {
            let next = match op.tag.as_str() {
                "translate" => Transform::translate(self.vec3_of(op)?),
                "scale" => {
                    let s = if let Some((v, span)) = self.attr(op, "value")? {
                        let xs = self.parse_list(op, &v, span.clone())?;
                        match xs.as_slice() {
                            [s] => Vec3::splat(*s),
                            [x, y, z] => Vec3::new(*x, *y, *z),
                            _ => {
                                return Err(self.err_span(
                                    op,
                                    span,
                                    format!("<scale> needs 1 or 3 values, found {}", xs.len()),
                                ));
                            }
                        }
                    } else {
                        let mut s = [1.0f32; 3];
                        for (k, axis) in ["x", "y", "z"].iter().enumerate() {
                            if let Some((v, span)) = self.attr(op, axis)? {
                                s[k] = self.parse_f32(op, &v, span)?;
                            }
                        }
                        Vec3::from(s)
                    };
                    Transform::scale(s)
                }
                "rotate" => {
                    let axis = self.vec3_of(op)?;
                    let (a, span) = self.required_attr(op, "angle")?;
                    let angle = self.parse_f32(op, &a, span)?;
                    if axis.length_squared() == 0.0 {
                        return Err(self.err(op, "<rotate> needs a non-zero axis (x, y, z or value)"));
                    }
                    // Mitsuba uses the axis as written (a longer axis also scales).
                    Transform::rotate_as_written(axis, angle)
                }
                "matrix" => {
                    let (v, span) = self.value(op)?;
                    let xs = self.parse_list(op, &v, span.clone())?;
                    let m = match xs.len() {
                        16 => Mat4::from_cols_slice(&xs).transpose(),
                        9 => {
                            let r = |i: usize| Vec4::new(xs[i], xs[i + 1], xs[i + 2], 0.0);
                            Mat4::from_cols(r(0), r(3), r(6), Vec4::W).transpose()
                        }
                        n => {
                            return Err(self.err_span(
                                op,
                                span,
                                format!("<matrix> needs 16 values (a 4x4 matrix, row by row) or 9, found {n}"),
                            ));
                        }
                    };
                    Transform::from_mat4(m)
                }
                "lookat" => {
                    let read = |name: &str, required: bool| -> Result<Option<Vec3>, SceneError> {
                        match self.attr(op, name)? {
                            Some((v, span)) => {
                                let xs = self.parse_list(op, &v, span.clone())?;
                                match xs.as_slice() {
                                    [x, y, z] => Ok(Some(Vec3::new(*x, *y, *z))),
                                    _ => Err(self.err_span(
                                        op,
                                        span,
                                        format!("lookat `{name}` needs 3 values, found {}", xs.len()),
                                    )),
                                }
                            }
                            None if required => Err(self.err(op, format!("<lookat> needs `{name}`"))),
                            None => Ok(None),
                        }
                    };
                    let origin = read("origin", true)?.unwrap_or_default();
                    let target = read("target", true)?.unwrap_or_default();
                    let dir = (target - origin).normalize_or_zero();
                    if dir == Vec3::ZERO || !dir.is_finite() {
                        return Err(self.err(op, "<lookat> origin and target are the same point"));
                    }
                    let up = match read("up", false)? {
                        Some(u) => u,
                        None => dir.any_orthonormal_vector(),
                    };
                    let left = up.cross(dir);
                    if !(left.length() > 1e-6 * up.length()) {
                        return Err(self.err(op, "<lookat> `up` is parallel to the viewing direction"));
                    }
                    let left = left.normalize();
                    let new_up = dir.cross(left);
                    if n_ops == 1 {
                        lookat = Some((origin, target, up));
                    }
                    Transform::from_mat4(Mat4::from_cols(
                        left.extend(0.0),
                        new_up.extend(0.0),
                        dir.extend(0.0),
                        origin.extend(1.0),
                    ))
                }
                other => {
                    return Err(self.err(
                        op,
                        format!(
                            "unknown transform operation <{other}>; expected translate, rotate, scale, matrix or lookat"
                        ),
                    ));
                }
            };
            t = t.then(next);
        }
        if !t.is_valid() {
            return Err(self.err(el, "transform is singular or not finite"));
        }
        Ok(Xform { t, lookat })
    }

    pub(super) fn transform(&self, p: &Props<'a>, name: &str) -> Result<Option<Xform>, SceneError> {
        let Some(el) = self.prop(p, name) else { return Ok(None) };
        self.transform_of(el).map(Some)
    }
}
