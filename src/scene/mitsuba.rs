//! Mitsuba 3 scene import: reads a scene written in Mitsuba's XML format and builds the same
//! `LoadedScene` the TOML loader builds, so any of our integrators can render it.
//!
//! Conventions follow Mitsuba 3 (its documentation and plugin sources were the reference; no code
//! is copied): transforms compose in the order written, rectangles are the square [-1, 1]^2 at
//! z = 0 facing +z, the sensor looks along +z of its `to_world` frame with +y up and the image's
//! x axis along local -x, `fov` applies to the image's x axis unless `fov_axis` says otherwise,
//! and light units are physical (W/sr, W/(m^2 sr), W/m^2) on both sides, so values are used as
//! they are. What we cannot render is reported as a warning with its file and line (or an error
//! with `--strict`); malformed input is an error with file, line and column, never a panic.
//!
//! The reading is done in two steps: the XML (with its `<include>`s) becomes a small owned tree
//! that remembers where each element and attribute came from, and the scene is then built from
//! that tree with `$name` parameters substituted and `<ref>`s resolved on the way.

use super::load::{LoadInfo, LoadedScene, Overrides, box_faces, transformed_quad};
use super::{Scene, SceneError};
use crate::accel::Bvh;
use crate::camera::{Camera, ViewPlane};
use crate::geometry::{Aabb, Transform};
use crate::integrator::{IntegratorConfig, IntegratorKind};
use crate::light::{Emitter, Light, LightPicker};
use crate::material::{Material, MaterialKind};
use crate::math::{Color, Vec3};
use crate::render::RenderSettings;
use crate::sampling::SamplerKind;
use crate::shape::{Primitive, Quad, Shape, Sphere, TriangleMesh};
use glam::{Mat4, Vec4};
use std::cell::Cell;
use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Nested `<include>`s deeper than this are taken for a cycle.
const MAX_INCLUDE_DEPTH: usize = 16;
/// Triangles in the fan that stands in for a `disk`.
const DISK_SEGMENTS: u32 = 128;
/// Largest image side and pixel count (as the TOML loader).
const MAX_SIDE: u32 = 1 << 16;
const MAX_PIXELS: u64 = 1 << 28;
/// Our depth limit for Mitsuba's `max_depth = -1` (unlimited): Russian roulette ends paths long
/// before this in the path tracer.
const UNLIMITED_PATH_DEPTH: u32 = 1000;
/// The same for the Whitted and photon integrators, whose recursion branches at glass: our TOML
/// default.
const UNLIMITED_RECURSION_DEPTH: u32 = 5;

/// Object (plugin) tags of the format.
const OBJECT_TAGS: &[&str] = &[
    "shape",
    "bsdf",
    "emitter",
    "sensor",
    "film",
    "sampler",
    "integrator",
    "texture",
    "rfilter",
    "medium",
    "phase",
    "volume",
];
/// Property tags of the format.
const PROPERTY_TAGS: &[&str] =
    &["integer", "float", "boolean", "string", "rgb", "point", "vector", "spectrum", "transform"];

/// Indices of refraction of Mitsuba's named materials (measured values at about 589 nm, as
/// tabulated in Hecht's *Optics*).
const NAMED_IOR: &[(&str, f32)] = &[
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

/// Loads a Mitsuba 3 XML scene file; warnings are printed to stderr.
pub fn load_mitsuba(path: &Path, overrides: &Overrides) -> Result<LoadedScene, SceneError> {
    let (scene, warnings) = load_mitsuba_with_warnings(path, overrides)?;
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    Ok(scene)
}

/// Loads a Mitsuba 3 XML scene file and returns the warnings (each `file:line:col: message`)
/// instead of printing them.
pub fn load_mitsuba_with_warnings(
    path: &Path,
    overrides: &Overrides,
) -> Result<(LoadedScene, Vec<String>), SceneError> {
    let text = std::fs::read_to_string(path)
        .map_err(|source| SceneError::Read { path: path.display().to_string(), source })?;
    let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
    load_mitsuba_str(&text, &path.display().to_string(), &base, overrides)
}

/// Loads a Mitsuba scene from `text`; `name` is used in messages, and files (meshes, includes)
/// resolve against `base`.
pub fn load_mitsuba_str(
    text: &str,
    name: &str,
    base: &Path,
    overrides: &Overrides,
) -> Result<(LoadedScene, Vec<String>), SceneError> {
    let mut srcs = vec![Src { name: name.to_string(), text: text.to_string(), base: base.to_path_buf() }];
    let root = parse_source(&mut srcs, 0, 0)?;
    let mut cx = Cx {
        srcs: &srcs,
        defines: HashMap::new(),
        ids: HashMap::new(),
        warnings: Vec::new(),
        strict: overrides.strict,
    };
    for (k, v) in &overrides.defines {
        cx.defines.insert(k.clone(), v.clone());
    }
    let scene = cx.build(&root, overrides)?;
    Ok((scene, cx.warnings))
}

// ---------------------------------------------------------------------------------------------
// The owned XML tree
// ---------------------------------------------------------------------------------------------

/// One source file (the scene or an included file).
struct Src {
    name: String,
    text: String,
    base: PathBuf,
}

/// An XML element with the places of its parts.
struct El {
    tag: String,
    attrs: Vec<Attr>,
    children: Vec<El>,
    /// Index of the source file in `srcs`.
    src: usize,
    /// Byte range of the tag name in the start tag.
    span: Range<usize>,
}

struct Attr {
    name: String,
    value: String,
    /// Byte range of the value (without quotes).
    span: Range<usize>,
}

/// Parses source `id` of `srcs`, expanding `<include>`s, and returns its `<scene>` element.
fn parse_source(srcs: &mut Vec<Src>, id: usize, depth: usize) -> Result<El, SceneError> {
    let text = srcs[id].text.clone();
    let name = srcs[id].name.clone();
    let opts = roxmltree::ParsingOptions { allow_dtd: true, ..Default::default() };
    let doc = roxmltree::Document::parse_with_options(&text, opts).map_err(|e| {
        let pos = e.pos();
        let offset = offset_of(&text, pos.row as usize, pos.col as usize);
        let mut message = e.to_string();
        let suffix = format!(" at {}:{}", pos.row, pos.col);
        if let Some(stripped) = message.strip_suffix(&suffix) {
            message = stripped.to_string();
        }
        SceneError::at(&name, &text, offset..offset + 1, format!("malformed XML: {message}"))
    })?;
    let root = doc.root_element();
    let mut el = convert(root, id);
    if el.tag != "scene" {
        return Err(SceneError::at(
            &name,
            &text,
            el.span.clone(),
            format!("the root element must be <scene version=\"3.0.0\">, found <{}>", el.tag),
        ));
    }
    expand_includes(srcs, &mut el, depth)?;
    Ok(el)
}

/// Byte offset of 1-based (row, column in characters).
fn offset_of(text: &str, row: usize, col: usize) -> usize {
    let mut start = 0;
    for _ in 1..row {
        match text[start..].find('\n') {
            Some(i) => start += i + 1,
            None => return text.len(),
        }
    }
    let line = &text[start..];
    start + line.char_indices().nth(col.saturating_sub(1)).map_or(line.len(), |(i, _)| i)
}

fn convert(node: roxmltree::Node, src: usize) -> El {
    let start = node.range().start + 1;
    let tag = node.tag_name().name().to_string();
    let span = start..start + tag.len();
    let attrs = node
        .attributes()
        .map(|a| Attr { name: a.name().to_string(), value: a.value().to_string(), span: a.range_value() })
        .collect();
    let children = node.children().filter(|c| c.is_element()).map(|c| convert(c, src)).collect();
    El { tag, attrs, children, src, span }
}

/// Replaces every `<include filename="..."/>` below `el` by the children of the included scene.
fn expand_includes(srcs: &mut Vec<Src>, el: &mut El, depth: usize) -> Result<(), SceneError> {
    let children = std::mem::take(&mut el.children);
    for mut child in children {
        if child.tag != "include" {
            expand_includes(srcs, &mut child, depth)?;
            el.children.push(child);
            continue;
        }
        let src = &srcs[child.src];
        let at = |span: Range<usize>, msg: String| SceneError::at(&src.name, &src.text, span, msg);
        let Some(file) = child.attrs.iter().find(|a| a.name == "filename") else {
            return Err(at(child.span.clone(), "<include> needs a `filename` attribute".into()));
        };
        if file.value.contains('$') {
            return Err(at(file.span.clone(), "`$` parameters are not supported in <include> file names".into()));
        }
        if depth >= MAX_INCLUDE_DEPTH {
            return Err(at(
                file.span.clone(),
                format!("includes nested more than {MAX_INCLUDE_DEPTH} deep (a cycle?)"),
            ));
        }
        let path = src.base.join(&file.value);
        let text = std::fs::read_to_string(&path)
            .map_err(|e| at(file.span.clone(), format!("cannot read included file `{}`: {e}", path.display())))?;
        let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
        srcs.push(Src { name: path.display().to_string(), text, base });
        let id = srcs.len() - 1;
        let included = parse_source(srcs, id, depth + 1)?;
        el.children.extend(included.children);
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Reading properties
// ---------------------------------------------------------------------------------------------

struct Cx<'a> {
    srcs: &'a [Src],
    defines: HashMap<String, String>,
    ids: HashMap<String, &'a El>,
    warnings: Vec<String>,
    strict: bool,
}

/// A transform with, when it is exactly one `lookat`, that lookat's (origin, target, up).
struct Xform {
    t: Transform,
    lookat: Option<(Vec3, Vec3, Vec3)>,
}

/// One entry of an object's body.
enum Entry<'a> {
    /// A property element (`<float name=...>` etc.).
    Prop { name: String, el: &'a El },
    /// A nested object or a `<ref>`: `el` is the object itself, `at` where it is used.
    Object { name: Option<String>, el: &'a El, at: &'a El },
}

/// The body of an object element: its properties and nested objects, with a flag per entry
/// saying whether it was read (unread ones are reported).
struct Props<'a> {
    el: &'a El,
    kind: String,
    entries: Vec<Entry<'a>>,
    used: Vec<Cell<bool>>,
}

impl<'a> Cx<'a> {
    fn src(&self, el: &El) -> &'a Src {
        &self.srcs[el.src]
    }

    fn err(&self, el: &El, message: impl Into<String>) -> SceneError {
        let s = self.src(el);
        SceneError::at(&s.name, &s.text, el.span.clone(), message)
    }

    fn err_span(&self, el: &El, span: Range<usize>, message: impl Into<String>) -> SceneError {
        let s = self.src(el);
        SceneError::at(&s.name, &s.text, span, message)
    }

    /// Reports something we do not render: a warning, or an error with `--strict`.
    fn warn(&mut self, el: &El, message: impl Into<String>) -> Result<(), SceneError> {
        let message = message.into();
        if self.strict {
            return Err(self.err(el, format!("{message} (an error with --strict)")));
        }
        let s = self.src(el);
        let (line, column) = super::error::line_column(&s.text, el.span.start);
        self.warnings.push(format!("{}:{line}:{column}: {message}", s.name));
        Ok(())
    }

    /// An attribute's value with `$name` parameters substituted.
    fn attr(&self, el: &El, name: &str) -> Result<Option<(String, Range<usize>)>, SceneError> {
        let Some(a) = el.attrs.iter().find(|a| a.name == name) else { return Ok(None) };
        Ok(Some((self.substitute(el, a)?, a.span.clone())))
    }

    fn required_attr(&self, el: &El, name: &str) -> Result<(String, Range<usize>), SceneError> {
        self.attr(el, name)?.ok_or_else(|| self.err(el, format!("<{}> needs a `{name}` attribute", el.tag)))
    }

    fn substitute(&self, el: &El, a: &Attr) -> Result<String, SceneError> {
        if !a.value.contains('$') {
            return Ok(a.value.clone());
        }
        let mut out = String::new();
        let mut rest = a.value.as_str();
        while let Some(i) = rest.find('$') {
            out.push_str(&rest[..i]);
            let after = &rest[i + 1..];
            let len = after.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(after.len());
            let key = &after[..len];
            if key.is_empty() {
                return Err(self.err_span(el, a.span.clone(), "`$` must be followed by a parameter name"));
            }
            match self.defines.get(key) {
                Some(v) => out.push_str(v),
                None => {
                    return Err(self.err_span(
                        el,
                        a.span.clone(),
                        format!("parameter `${key}` has no value: declare <default name=\"{key}\" value=\"...\"/> or pass -D {key}=VALUE"),
                    ));
                }
            }
            rest = &after[len..];
        }
        out.push_str(rest);
        Ok(out)
    }

    /// Collects `<default>`s (command-line values win) and object ids of the whole tree.
    fn index(&mut self, root: &'a El) -> Result<(), SceneError> {
        for child in &root.children {
            if child.tag == "default" {
                let (name, _) = self.required_attr(child, "name")?;
                let (value, _) = self.required_attr(child, "value")?;
                self.defines.entry(name).or_insert(value);
            }
        }
        self.index_ids(root)
    }

    fn index_ids(&mut self, el: &'a El) -> Result<(), SceneError> {
        for child in &el.children {
            if OBJECT_TAGS.contains(&child.tag.as_str())
                && let Some((id, span)) = self.attr(child, "id")?
            {
                if self.ids.contains_key(&id) {
                    return Err(self.err_span(child, span, format!("id `{id}` is used by more than one object")));
                }
                self.ids.insert(id, child);
            }
            self.index_ids(child)?;
        }
        Ok(())
    }

    /// Resolves a `<ref id=.../>`.
    fn resolve(&self, r: &El) -> Result<&'a El, SceneError> {
        let (id, span) = self.required_attr(r, "id")?;
        self.ids.get(&id).copied().ok_or_else(|| {
            let mut known: Vec<&str> = self.ids.keys().map(String::as_str).collect();
            known.sort();
            self.err_span(
                r,
                span,
                format!(
                    "no object with id `{id}` (ids defined: {})",
                    if known.is_empty() { "none".into() } else { known.join(", ") }
                ),
            )
        })
    }

    /// Reads an object element's body.
    fn props(&self, el: &'a El) -> Result<Props<'a>, SceneError> {
        let kind = match self.attr(el, "type")? {
            Some((t, _)) => t,
            None => return Err(self.err(el, format!("<{}> needs a `type` attribute (the plugin name)", el.tag))),
        };
        let mut entries = Vec::new();
        let mut names: HashMap<String, &El> = HashMap::new();
        for child in &el.children {
            let tag = child.tag.as_str();
            let name = self.attr(child, "name")?;
            let entry = if PROPERTY_TAGS.contains(&tag) {
                let (name, _) =
                    name.ok_or_else(|| self.err(child, format!("<{tag}> property needs a `name` attribute")))?;
                Entry::Prop { name, el: child }
            } else if OBJECT_TAGS.contains(&tag) {
                Entry::Object { name: name.map(|n| n.0), el: child, at: child }
            } else if tag == "ref" {
                Entry::Object { name: name.map(|n| n.0), el: self.resolve(child)?, at: child }
            } else {
                return Err(self.err(
                    child,
                    format!(
                        "unknown property type <{tag}>; expected one of: {}, or a nested object ({}) or <ref>",
                        PROPERTY_TAGS.join(", "),
                        OBJECT_TAGS.join(", ")
                    ),
                ));
            };
            let key = match &entry {
                Entry::Prop { name, .. } => Some(name.clone()),
                Entry::Object { name, .. } => name.clone(),
            };
            if let Some(key) = key {
                if names.contains_key(&key) {
                    return Err(self.err(child, format!("property `{key}` is given more than once")));
                }
                names.insert(key, child);
            }
            entries.push(entry);
        }
        let used = entries.iter().map(|_| Cell::new(false)).collect();
        Ok(Props { el, kind, entries, used })
    }

    /// Warns about every entry of `p` nothing read.
    fn finish(&mut self, p: &Props<'a>) -> Result<(), SceneError> {
        for (e, used) in p.entries.iter().zip(&p.used) {
            if used.get() {
                continue;
            }
            match e {
                Entry::Prop { name, el } => {
                    self.warn(
                        el,
                        format!(
                            "property `{name}` of <{} type=\"{}\"> is not supported and is ignored",
                            p.el.tag, p.kind
                        ),
                    )?;
                }
                Entry::Object { el, at, .. } => {
                    let kind = self.attr(el, "type")?.map_or(String::new(), |t| t.0);
                    self.warn(
                        at,
                        format!(
                            "<{} type=\"{kind}\"> inside <{} type=\"{}\"> is not supported and is ignored",
                            el.tag, p.el.tag, p.kind
                        ),
                    )?;
                }
            }
        }
        Ok(())
    }

    // --- typed property getters ---------------------------------------------------------------

    /// The property element named `name`, marked as read.
    fn prop(&self, p: &Props<'a>, name: &str) -> Option<&'a El> {
        p.entries.iter().zip(&p.used).find_map(|(e, used)| match e {
            Entry::Prop { name: n, el } if n == name => {
                used.set(true);
                Some(*el)
            }
            _ => None,
        })
    }

    /// A nested object named `name`, or (when `tag` matches) an unnamed one; marked as read.
    fn object(&self, p: &Props<'a>, name: Option<&str>, tag: &str) -> Vec<(&'a El, &'a El)> {
        let mut out = Vec::new();
        for (e, used) in p.entries.iter().zip(&p.used) {
            if let Entry::Object { name: n, el, at } = e {
                let hit = match (name, n) {
                    (Some(want), Some(n)) => want == n,
                    (Some(_), None) => false,
                    (None, _) => el.tag == tag,
                };
                if hit {
                    used.set(true);
                    out.push((*el, *at));
                }
            }
        }
        out
    }

    fn value(&self, el: &El) -> Result<(String, Range<usize>), SceneError> {
        self.required_attr(el, "value")
    }

    fn wrong_type(&self, el: &El, name: &str, want: &str) -> SceneError {
        self.err(el, format!("property `{name}` must be {want}, found <{}>", el.tag))
    }

    fn parse_f32(&self, el: &El, s: &str, span: Range<usize>) -> Result<f32, SceneError> {
        match s.trim().parse::<f32>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(self.err_span(el, span, format!("expected a number, found `{s}`"))),
        }
    }

    /// Numbers separated by commas and/or spaces.
    fn parse_list(&self, el: &El, s: &str, span: Range<usize>) -> Result<Vec<f32>, SceneError> {
        s.split(|c: char| c == ',' || c.is_whitespace())
            .filter(|t| !t.is_empty())
            .map(|t| self.parse_f32(el, t, span.clone()))
            .collect()
    }

    fn float(&self, p: &Props<'a>, name: &str) -> Result<Option<f32>, SceneError> {
        let Some(el) = self.prop(p, name) else { return Ok(None) };
        if el.tag != "float" && el.tag != "integer" {
            return Err(self.wrong_type(el, name, "a <float>"));
        }
        let (v, span) = self.value(el)?;
        self.parse_f32(el, &v, span).map(Some)
    }

    fn integer(&self, p: &Props<'a>, name: &str) -> Result<Option<(i64, &'a El)>, SceneError> {
        let Some(el) = self.prop(p, name) else { return Ok(None) };
        if el.tag != "integer" {
            return Err(self.wrong_type(el, name, "an <integer>"));
        }
        let (v, span) = self.value(el)?;
        match v.trim().parse::<i64>() {
            Ok(i) => Ok(Some((i, el))),
            Err(_) => Err(self.err_span(el, span, format!("expected a whole number, found `{v}`"))),
        }
    }

    fn boolean(&self, p: &Props<'a>, name: &str) -> Result<Option<bool>, SceneError> {
        let Some(el) = self.prop(p, name) else { return Ok(None) };
        if el.tag != "boolean" {
            return Err(self.wrong_type(el, name, "a <boolean>"));
        }
        let (v, span) = self.value(el)?;
        match v.trim().to_ascii_lowercase().as_str() {
            "true" => Ok(Some(true)),
            "false" => Ok(Some(false)),
            _ => Err(self.err_span(el, span, format!("expected true or false, found `{v}`"))),
        }
    }

    fn string(&self, p: &Props<'a>, name: &str) -> Result<Option<(String, &'a El)>, SceneError> {
        let Some(el) = self.prop(p, name) else { return Ok(None) };
        if el.tag != "string" {
            return Err(self.wrong_type(el, name, "a <string>"));
        }
        Ok(Some((self.value(el)?.0, el)))
    }

    /// A point or vector: `value="x, y, z"` or `x=`, `y=`, `z=` attributes (missing ones 0).
    fn vec3_of(&self, el: &El) -> Result<Vec3, SceneError> {
        if let Some((v, span)) = self.attr(el, "value")? {
            let xs = self.parse_list(el, &v, span.clone())?;
            return match xs.as_slice() {
                [x, y, z] => Ok(Vec3::new(*x, *y, *z)),
                [s] => Ok(Vec3::splat(*s)),
                _ => Err(self.err_span(el, span, format!("<{}> needs 3 values, found {}", el.tag, xs.len()))),
            };
        }
        let mut out = [0.0f32; 3];
        for (k, axis) in ["x", "y", "z"].iter().enumerate() {
            if let Some((v, span)) = self.attr(el, axis)? {
                out[k] = self.parse_f32(el, &v, span)?;
            }
        }
        Ok(Vec3::from(out))
    }

    fn point(&self, p: &Props<'a>, name: &str) -> Result<Option<Vec3>, SceneError> {
        let Some(el) = self.prop(p, name) else { return Ok(None) };
        if el.tag != "point" && el.tag != "vector" {
            return Err(self.wrong_type(el, name, "a <point> or <vector>"));
        }
        self.vec3_of(el).map(Some)
    }

    /// A colour: `<rgb>`, `<spectrum>`, `<float>`, or a texture (whose mean or grey is used).
    fn color(&mut self, p: &Props<'a>, name: &str) -> Result<Option<Color>, SceneError> {
        if let Some(el) = self.prop(p, name) {
            return self.color_of(el, name).map(Some);
        }
        if let Some(&(tex, at)) = self.object(p, Some(name), "texture").first() {
            return self.texture_mean(tex, at).map(Some);
        }
        Ok(None)
    }

    fn color_of(&mut self, el: &'a El, name: &str) -> Result<Color, SceneError> {
        match el.tag.as_str() {
            "float" | "integer" => {
                let (v, span) = self.value(el)?;
                Ok(Color::splat(self.parse_f32(el, &v, span)?))
            }
            "rgb" => {
                let (v, span) = self.value(el)?;
                let xs = self.parse_list(el, &v, span.clone())?;
                let c = match xs.as_slice() {
                    [r, g, b] => Color::new(*r, *g, *b),
                    [s] => Color::splat(*s),
                    _ => {
                        return Err(self.err_span(
                            el,
                            span,
                            format!("<rgb> `{name}` needs 3 values (or 1 for a grey), found {}", xs.len()),
                        ));
                    }
                };
                Ok(c)
            }
            "spectrum" => {
                if let Some((f, span)) = self.attr(el, "filename")? {
                    self.warn(el, format!("spectrum files are not supported (`{f}`): `{name}` is taken as grey 0.5"))?;
                    let _ = span;
                    return Ok(Color::splat(0.5));
                }
                let (v, span) = self.value(el)?;
                if !v.contains(':') {
                    let xs = self.parse_list(el, &v, span.clone())?;
                    return match xs.as_slice() {
                        [s] => Ok(Color::splat(*s)),
                        _ => Err(self.err_span(
                            el,
                            span,
                            format!(
                                "<spectrum> `{name}` needs one value or wavelength:value pairs, found {} values",
                                xs.len()
                            ),
                        )),
                    };
                }
                // Wavelength:value pairs: no colour-matching tables here, so use the mean value
                // over the visible range as a grey.
                let mut pairs = Vec::new();
                for item in v.split(',').map(str::trim).filter(|t| !t.is_empty()) {
                    let Some((l, x)) = item.split_once(':') else {
                        return Err(self.err_span(el, span, format!("expected wavelength:value, found `{item}`")));
                    };
                    pairs.push((self.parse_f32(el, l, span.clone())?, self.parse_f32(el, x, span.clone())?));
                }
                let visible: Vec<f32> =
                    pairs.iter().filter(|(l, _)| (380.0..=780.0).contains(l)).map(|p| p.1).collect();
                let vals = if visible.is_empty() { pairs.iter().map(|p| p.1).collect() } else { visible };
                let mean = vals.iter().sum::<f32>() / vals.len() as f32;
                if vals.iter().any(|&x| (x - mean).abs() > 1e-6 * mean.abs().max(1.0)) {
                    self.warn(
                        el,
                        format!(
                            "wavelength-dependent spectrum `{name}` is approximated by its mean value {mean} (grey)"
                        ),
                    )?;
                }
                Ok(Color::splat(mean))
            }
            _ => Err(self.wrong_type(el, name, "an <rgb>, <spectrum> or <float>")),
        }
    }

    /// Textures are not supported: a checkerboard becomes the mean of its colours, anything
    /// else grey 0.5.
    fn texture_mean(&mut self, tex: &'a El, at: &'a El) -> Result<Color, SceneError> {
        let p = self.props(tex)?;
        let c = if p.kind == "checkerboard" {
            let c0 = self.color(&p, "color0")?.unwrap_or(Color::splat(0.4));
            let c1 = self.color(&p, "color1")?.unwrap_or(Color::splat(0.2));
            for e in p.used.iter() {
                e.set(true);
            }
            (c0 + c1) * 0.5
        } else {
            for e in p.used.iter() {
                e.set(true);
            }
            Color::splat(0.5)
        };
        self.warn(
            at,
            format!("textures are not supported: <texture type=\"{}\"> is replaced by its mean colour {c}", p.kind),
        )?;
        Ok(c)
    }

    /// Reads a `<transform>` element: its operations composed in the order written.
    fn transform_of(&self, el: &El) -> Result<Xform, SceneError> {
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
                    Transform::rotate(axis, angle)
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

    fn transform(&self, p: &Props<'a>, name: &str) -> Result<Option<Xform>, SceneError> {
        let Some(el) = self.prop(p, name) else { return Ok(None) };
        self.transform_of(el).map(Some)
    }

    /// An index of refraction: a number or one of Mitsuba's named materials.
    fn ior(&self, p: &Props<'a>, name: &str, default: f32) -> Result<f32, SceneError> {
        let Some(el) = self.prop(p, name) else { return Ok(default) };
        match el.tag.as_str() {
            "float" | "integer" => {
                let (v, span) = self.value(el)?;
                let x = self.parse_f32(el, &v, span.clone())?;
                if x <= 0.0 {
                    return Err(self.err_span(el, span, format!("`{name}` must be positive, found {x}")));
                }
                Ok(x)
            }
            "string" => {
                let (v, span) = self.value(el)?;
                let key = v.trim().to_ascii_lowercase();
                NAMED_IOR.iter().find(|(n, _)| *n == key).map(|m| m.1).ok_or_else(|| {
                    let names: Vec<&str> = NAMED_IOR.iter().map(|m| m.0).collect();
                    self.err_span(
                        el,
                        span,
                        format!(
                            "unknown material `{v}` for `{name}`; expected a number or one of: {}",
                            names.join(", ")
                        ),
                    )
                })
            }
            _ => Err(self.wrong_type(el, name, "a <float> or a <string> naming a material")),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Building the scene
// ---------------------------------------------------------------------------------------------

/// A light in document order; area lights get their primitive and material after all other
/// geometry, as the TOML loader does, so equivalent scenes give the same primitive order.
enum PendingLight {
    Ready(Light),
    Area { emitter: Emitter, radiance: Color, material: Material },
}

/// Mitsuba's `max_depth` and the element that gave it.
type Depth<'a> = (i64, &'a El);

/// The shared state while building.
struct Build {
    materials: Vec<Material>,
    material_names: Vec<String>,
    /// Material index of each `<bsdf>` element already built (by address).
    bsdf_cache: HashMap<usize, u32>,
    default_material: Option<u32>,
    prims: Vec<Primitive>,
    meshes: Vec<TriangleMesh>,
    lights: Vec<PendingLight>,
    specular_targets: Vec<(Vec3, f32)>,
    background: Color,
    info: LoadInfo,
}

/// Mitsuba's diffuse BSDF in our model: physical albedo kd x colour.
fn diffuse(color: Color) -> Material {
    Material { kind: MaterialKind::Diffuse, color, ka: 0.0, kd: 1.0, ks: 0.0, ..Material::default() }
}

fn mirror(kr: f32) -> Material {
    Material { kind: MaterialKind::Reflective, color: Color::ONE, ka: 0.0, kd: 0.0, ks: 0.0, kr, ..Material::default() }
}

/// Fresnel reflectance at normal incidence for relative index `eta`.
fn f0(eta: f32) -> f32 {
    ((eta - 1.0) / (eta + 1.0)).powi(2)
}

impl<'a> Cx<'a> {
    fn build(&mut self, root: &'a El, overrides: &Overrides) -> Result<LoadedScene, SceneError> {
        match self.attr(root, "version")? {
            None => return Err(self.err(root, "<scene> needs a `version` attribute, e.g. version=\"3.0.0\"")),
            Some((v, span)) => {
                let major = v.split('.').next().and_then(|m| m.trim().parse::<u32>().ok());
                match major {
                    None => {
                        return Err(self.err_span(
                            root,
                            span,
                            format!("expected a version such as 3.0.0, found `{v}`"),
                        ));
                    }
                    Some(m) if m < 2 => {
                        self.warn(root, format!("scene version {v} is older than Mitsuba 2: names such as toWorld or intIOR are not recognised; upgrade the file with Mitsuba's converter"))?;
                    }
                    _ => {}
                }
            }
        }
        self.index(root)?;

        let mut b = Build {
            materials: Vec::new(),
            material_names: Vec::new(),
            bsdf_cache: HashMap::new(),
            default_material: None,
            prims: Vec::new(),
            meshes: Vec::new(),
            lights: Vec::new(),
            specular_targets: Vec::new(),
            background: Color::ZERO,
            info: LoadInfo::default(),
        };
        let mut sensor: Option<&'a El> = None;
        let mut integrator: Option<&'a El> = None;
        let mut constant: Option<&'a El> = None;
        for child in &root.children {
            match child.tag.as_str() {
                "default" => {}
                "shape" => self.shape(child, &mut b)?,
                "emitter" => {
                    if self.emitter(child, &mut b)? {
                        constant = Some(child);
                    }
                }
                "sensor" => {
                    if sensor.is_some() {
                        self.warn(child, "only the first <sensor> is rendered")?;
                    } else {
                        sensor = Some(child);
                    }
                }
                "integrator" => {
                    if integrator.is_some() {
                        self.warn(child, "only the first <integrator> is used")?;
                    } else {
                        integrator = Some(child);
                    }
                }
                // Declarations used through references; unreferenced ones do nothing, as in Mitsuba.
                "bsdf" | "texture" => {
                    if self.attr(child, "id")?.is_none() {
                        self.warn(child, format!("a top-level <{}> without an id is never used", child.tag))?;
                    }
                }
                "film" | "sampler" | "rfilter" => {
                    self.warn(child, format!("a top-level <{}> is ignored: put it inside the <sensor>", child.tag))?;
                }
                "medium" | "phase" | "volume" => {
                    let kind = self.attr(child, "type")?.map_or(String::new(), |t| t.0);
                    self.warn(
                        child,
                        format!("participating media are not supported: <{} type=\"{kind}\"> is ignored", child.tag),
                    )?;
                }
                other => {
                    return Err(self.err(
                        child,
                        format!("unknown element <{other}> in <scene>; expected shape, bsdf, emitter, sensor, integrator, texture, default or include"),
                    ));
                }
            }
        }

        // Integrator: its kind and depth limit.
        let (file_kind, mitsuba_depth) = match integrator {
            Some(el) => self.integrator(el)?,
            None => (IntegratorKind::Path, None),
        };
        let kind = overrides.integrator.unwrap_or(file_kind);
        if kind == IntegratorKind::Photon && b.background != Color::ZERO {
            let el = constant.unwrap_or(root);
            self.warn(el, "the photon-mapping integrator emits no photons from a constant environment: it lights only what the camera and specular paths see directly")?;
        }
        let max_depth = match overrides.max_depth {
            Some(d) => d,
            None => self.map_depth(mitsuba_depth, kind)?,
        };
        if max_depth > UNLIMITED_PATH_DEPTH {
            return Err(self.err(
                integrator.unwrap_or(root),
                format!("max_depth {max_depth} is too large (at most {UNLIMITED_PATH_DEPTH})"),
            ));
        }

        // Sensor, film and sampler.
        let cam = self.sensor(sensor, root, overrides)?;
        let camera = cam.camera;

        // Area lights last, in document order with the other lights.
        let mut lights = Vec::new();
        for pl in std::mem::take(&mut b.lights) {
            let light_index = lights.len() as u32;
            lights.push(match pl {
                PendingLight::Ready(l) => l,
                PendingLight::Area { emitter, radiance, mut material } => {
                    let m = b.materials.len() as u32;
                    material.emission = radiance;
                    material.light = light_index;
                    b.materials.push(material);
                    b.material_names.push(format!("(area light {})", light_index + 1));
                    let prim = b.prims.len() as u32;
                    let shape = match emitter {
                        Emitter::Quad(q) => Shape::Quad(q),
                        Emitter::Sphere(s) => Shape::Sphere(s),
                    };
                    b.prims.push(Primitive { shape, material: m });
                    Light::Area { emitter, radiance, prim }
                }
            });
        }

        let t0 = Instant::now();
        let bvh = Bvh::build(std::mem::take(&mut b.prims));
        b.info.bvh_build = t0.elapsed();
        b.info.primitives = bvh.prims.len();
        b.info.bvh_nodes = bvh.node_count();
        let bounds = bvh.bounds();
        let diag = if bounds.is_empty() { 0.0 } else { bounds.diagonal() };
        let (scene_center, scene_radius) = if bounds.is_empty() { (Vec3::ZERO, 1.0) } else { bounds.bounding_sphere() };
        for l in &mut lights {
            if let Light::Directional { scene_center: c, scene_radius: r, .. } = l {
                *c = scene_center;
                *r = scene_radius.max(1e-3);
            }
        }
        let any_transmissive = b.materials.iter().any(Material::transmits);
        let scene = Scene {
            bvh,
            planes: Vec::new(),
            meshes: b.meshes,
            materials: b.materials,
            material_names: b.material_names,
            light_picker: LightPicker::new(&lights),
            lights,
            camera,
            background: b.background,
            ambient: Color::ZERO,
            ray_bias: if diag.is_finite() { diag * 1e-6 } else { 0.0 },
            transparent_shadows: true,
            any_transmissive,
            specular_targets: b.specular_targets,
        };
        scene.check_usable().map_err(|message| SceneError::File { path: self.srcs[0].name.clone(), message })?;
        Ok(LoadedScene {
            scene,
            settings: cam.settings,
            integrator: IntegratorConfig {
                kind,
                max_depth,
                light_samples: 16,
                photon: crate::integrator::PhotonOptions::default().overridden_by(&overrides.photon),
            },
            info: b.info,
        })
    }

    /// Our depth limit for Mitsuba's `max_depth`. Mitsuba counts path vertices from the camera:
    /// 1 shows only emitters seen directly, 2 adds direct lighting. Our path tracer counts
    /// bounces (0 = emitters only, 1 = direct lighting), so it gets max_depth - 1; the Whitted
    /// and photon integrators count specular bounces before direct lighting, so they get
    /// max_depth - 2.
    fn map_depth(&mut self, depth: Option<Depth<'a>>, kind: IntegratorKind) -> Result<u32, SceneError> {
        let Some((d, el)) = depth else {
            return Ok(if kind == IntegratorKind::Path { UNLIMITED_PATH_DEPTH } else { UNLIMITED_RECURSION_DEPTH });
        };
        if d < -1 {
            return Err(self.err(el, format!("max_depth must be -1 (unlimited) or at least 0, found {d}")));
        }
        if d == -1 {
            return Ok(if kind == IntegratorKind::Path { UNLIMITED_PATH_DEPTH } else { UNLIMITED_RECURSION_DEPTH });
        }
        if d == 0 {
            self.warn(el, "max_depth 0 renders a black image in Mitsuba; here emitters stay visible")?;
        }
        let d = d.min(UNLIMITED_PATH_DEPTH as i64 + 1) as u32;
        Ok(match kind {
            IntegratorKind::Path => d.saturating_sub(1),
            _ => d.saturating_sub(2),
        })
    }

    fn integrator(&mut self, el: &'a El) -> Result<(IntegratorKind, Option<Depth<'a>>), SceneError> {
        let p = self.props(el)?;
        let (kind, depth) = match p.kind.as_str() {
            "path" | "volpath" | "volpathmis" | "prb" | "prb_basic" | "prbvolpath" | "ptracer" => {
                let depth = self.integer(&p, "max_depth")?;
                // Russian roulette only changes noise, not the expected image.
                let _ = self.integer(&p, "rr_depth")?;
                if self.boolean(&p, "hide_emitters")? == Some(true) {
                    self.warn(el, "hide_emitters is not supported: emitters seen directly are rendered")?;
                }
                (IntegratorKind::Path, depth)
            }
            "direct" => {
                for name in ["emitter_samples", "bsdf_samples"] {
                    let _ = self.integer(&p, name)?;
                }
                if self.boolean(&p, "hide_emitters")? == Some(true) {
                    self.warn(el, "hide_emitters is not supported: emitters seen directly are rendered")?;
                }
                // Direct lighting is a path of two vertices.
                (IntegratorKind::Path, Some((2, el)))
            }
            other => {
                self.warn(el, format!("integrator `{other}` is not supported; the path tracer is used"))?;
                for u in &p.used {
                    u.set(true);
                }
                (IntegratorKind::Path, None)
            }
        };
        self.finish(&p)?;
        Ok((kind, depth))
    }

    /// Builds the material of a `<bsdf>` element (cached per element).
    fn material(&mut self, el: &'a El, b: &mut Build) -> Result<u32, SceneError> {
        let key = el as *const El as usize;
        if let Some(&i) = b.bsdf_cache.get(&key) {
            return Ok(i);
        }
        let m = self.bsdf(el, 0)?;
        let i = b.materials.len() as u32;
        b.materials.push(m);
        let name = match self.attr(el, "id")? {
            Some((id, _)) => id,
            None => format!("(bsdf {})", i + 1),
        };
        b.material_names.push(name);
        b.bsdf_cache.insert(key, i);
        Ok(i)
    }

    fn default_material(&self, b: &mut Build) -> u32 {
        if let Some(i) = b.default_material {
            return i;
        }
        let i = b.materials.len() as u32;
        // Mitsuba's default BSDF: diffuse with reflectance 0.5.
        b.materials.push(diffuse(Color::splat(0.5)));
        b.material_names.push("(default diffuse)".into());
        b.default_material = Some(i);
        i
    }

    /// Maps a Mitsuba BSDF to our material.
    fn bsdf(&mut self, el: &'a El, depth: usize) -> Result<Material, SceneError> {
        if depth > 8 {
            return Err(self.err(el, "BSDFs nested too deeply"));
        }
        let p = self.props(el)?;
        let m = match p.kind.as_str() {
            "diffuse" => diffuse(self.color(&p, "reflectance")?.unwrap_or(Color::splat(0.5))),
            "conductor" | "roughconductor" => {
                if p.kind == "roughconductor" {
                    for name in ["alpha", "alpha_u", "alpha_v", "distribution", "sample_visible"] {
                        let _ = self.prop(&p, name);
                    }
                    self.warn(el, "roughconductor is rendered as a smooth mirror (its roughness is ignored)")?;
                }
                let material = self.string(&p, "material")?;
                let (eta, k) = (self.prop(&p, "eta"), self.prop(&p, "k"));
                if let Some((name, at)) = &material
                    && name != "none"
                {
                    self.warn(at, format!("conductor material `{name}` is rendered as a perfect (untinted) mirror"))?;
                } else if eta.is_some() || k.is_some() {
                    self.warn(el, "conductor eta/k are not supported: rendered as a perfect (untinted) mirror")?;
                }
                let kr = match self.color(&p, "specular_reflectance")? {
                    None => 1.0,
                    Some(c) => {
                        let mean = (c.x + c.y + c.z) / 3.0;
                        if c.max_element() - c.min_element() > 1e-6 {
                            self.warn(el, format!("tinted specular_reflectance {c} is taken as its mean {mean}"))?;
                        }
                        mean.clamp(0.0, 1.0)
                    }
                };
                mirror(kr)
            }
            "dielectric" | "roughdielectric" | "thindielectric" => {
                if p.kind == "roughdielectric" {
                    for name in ["alpha", "alpha_u", "alpha_v", "distribution", "sample_visible"] {
                        let _ = self.prop(&p, name);
                    }
                    self.warn(el, "roughdielectric is rendered as smooth glass (its roughness is ignored)")?;
                }
                let int_ior = self.ior(&p, "int_ior", 1.5046)?;
                let ext_ior = self.ior(&p, "ext_ior", 1.000277)?;
                for name in ["specular_reflectance", "specular_transmittance"] {
                    if let Some(c) = self.color(&p, name)?
                        && c != Color::ONE
                    {
                        self.warn(el, format!("`{name}` other than 1 is not supported and is ignored"))?;
                    }
                }
                let eta = int_ior / ext_ior;
                if p.kind == "thindielectric" {
                    // A thin sheet: light passes straight through, and the sheet reflects
                    // R + T^2 R / (1 - R^2) = 2R / (1 + R). We keep its value at normal incidence.
                    let r = f0(eta);
                    let kr = 2.0 * r / (1.0 + r);
                    self.warn(el, format!("thindielectric is approximated with a fixed reflectance {kr:.4} (its value at normal incidence)"))?;
                    Material {
                        kind: MaterialKind::Transparent,
                        color: Color::ONE,
                        ka: 0.0,
                        kd: 0.0,
                        ks: 0.0,
                        kr,
                        kt: 1.0 - kr,
                        ior: 1.0,
                        ..Material::default()
                    }
                } else {
                    Material {
                        kind: MaterialKind::Dielectric,
                        color: Color::ONE,
                        ka: 0.0,
                        kd: 0.0,
                        ks: 0.0,
                        ior: eta,
                        ..Material::default()
                    }
                }
            }
            "plastic" | "roughplastic" => {
                let color = self.color(&p, "diffuse_reflectance")?.unwrap_or(Color::splat(0.5));
                let int_ior = self.ior(&p, "int_ior", 1.49)?;
                let ext_ior = self.ior(&p, "ext_ior", 1.000277)?;
                for name in ["alpha", "distribution", "nonlinear", "sample_visible", "specular_reflectance"] {
                    let _ = self.prop(&p, name);
                }
                if p.kind == "plastic" {
                    let kr = f0(int_ior / ext_ior);
                    self.warn(el, format!("plastic is approximated by a diffuse base with albedo (1 - {kr:.3}) x reflectance and a mirror coat of constant reflectance {kr:.3}"))?;
                    Material {
                        kind: MaterialKind::Reflective,
                        color,
                        ka: 0.0,
                        kd: 1.0 - kr,
                        ks: 0.0,
                        kr,
                        ..Material::default()
                    }
                } else {
                    self.warn(el, "roughplastic is approximated by its diffuse base (the glossy coat is dropped)")?;
                    diffuse(color)
                }
            }
            "twosided" => {
                // Our surfaces reflect the same way on both sides already.
                let inner = self.object(&p, None, "bsdf");
                match inner.as_slice() {
                    [] => return Err(self.err(el, "twosided needs a nested <bsdf>")),
                    [(first, _), rest @ ..] => {
                        if !rest.is_empty() {
                            self.warn(
                                el,
                                "twosided with a different back side is not supported: both sides use the first BSDF",
                            )?;
                        }
                        self.bsdf(first, depth + 1)?
                    }
                }
            }
            other => {
                self.warn(el, format!("BSDF `{other}` is not supported: rendered as grey diffuse (reflectance 0.5)"))?;
                for u in &p.used {
                    u.set(true);
                }
                diffuse(Color::splat(0.5))
            }
        };
        self.finish(&p)?;
        Ok(m)
    }

    /// Reads a shape and adds its geometry (or, for an emitting shape, its area lights).
    fn shape(&mut self, el: &'a El, b: &mut Build) -> Result<(), SceneError> {
        let p = self.props(el)?;
        let to_world = self.transform(&p, "to_world")?.map_or(Transform::IDENTITY, |x| x.t);
        let flip = self.boolean(&p, "flip_normals")?.unwrap_or(false);

        // A nested area emitter.
        let emitters = self.object(&p, None, "emitter");
        let mut radiance = None;
        for &(eel, at) in &emitters {
            let ep = self.props(eel)?;
            if ep.kind != "area" {
                return Err(
                    self.err(at, format!("an emitter inside a shape must be type=\"area\", found `{}`", ep.kind))
                );
            }
            if radiance.is_some() {
                return Err(self.err(at, "a shape can have only one area emitter"));
            }
            radiance = Some(self.color(&ep, "radiance")?.unwrap_or(Color::ONE));
            self.finish(&ep)?;
        }
        // Material: a nested or referenced <bsdf>, or Mitsuba's default. A `null` BSDF is an
        // invisible surface: only its emission (if any) is kept.
        let bsdfs = self.object(&p, None, "bsdf");
        if bsdfs.len() > 1 {
            self.warn(bsdfs[1].1, "a shape has one BSDF: the first is used")?;
        }
        let bsdf_el = bsdfs.first().map(|b| b.0);
        let is_null = match bsdf_el {
            Some(bel) => self.attr(bel, "type")?.is_some_and(|t| t.0 == "null"),
            None => false,
        };
        let material = match bsdf_el {
            _ if is_null => None,
            Some(bel) => Some(self.material(bel, b)?),
            None => Some(self.default_material(b)),
        };
        // Other nested objects (media etc.) are reported by `finish`.

        let first_prim = b.prims.len();
        let kind = p.kind.clone();
        let mut emitters_out: Vec<Emitter> = Vec::new();
        let mut mesh_out = None;
        match kind.as_str() {
            "rectangle" => {
                let (c, e1, e2) = (Vec3::new(-1.0, -1.0, 0.0), Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 2.0, 0.0));
                let q =
                    if flip { transformed_quad(&to_world, c, e2, e1) } else { transformed_quad(&to_world, c, e1, e2) };
                let q = q.ok_or_else(|| self.err(el, "rectangle has no area after its to_world transform"))?;
                emitters_out.push(Emitter::Quad(q));
            }
            "cube" => {
                for (c, e1, e2) in box_faces(Vec3::splat(-1.0), Vec3::ONE) {
                    let q = if flip {
                        transformed_quad(&to_world, c, e2, e1)
                    } else {
                        transformed_quad(&to_world, c, e1, e2)
                    };
                    let q = q.ok_or_else(|| self.err(el, "cube is degenerate after its to_world transform"))?;
                    emitters_out.push(Emitter::Quad(q));
                }
            }
            "sphere" => {
                let center = self.point(&p, "center")?.unwrap_or(Vec3::ZERO);
                let radius = self.float(&p, "radius")?.unwrap_or(1.0);
                if !(radius > 0.0) {
                    return Err(self.err(el, format!("sphere radius must be positive, found {radius}")));
                }
                if !to_world.is_similarity() {
                    return Err(self.err(el, "a sphere's to_world can only translate, rotate and scale uniformly"));
                }
                if flip {
                    self.warn(el, "flip_normals on a sphere is not supported and is ignored")?;
                }
                let c = to_world.point(center);
                let r = radius * to_world.axis_scales().x;
                if !(r > 0.0 && r.is_finite() && c.is_finite()) {
                    return Err(self.err(el, "sphere is degenerate after its to_world transform"));
                }
                emitters_out.push(Emitter::Sphere(Sphere::new(c, r)));
            }
            "obj" | "ply" | "disk" => {
                let mesh = if kind == "disk" {
                    disk_mesh(DISK_SEGMENTS)
                } else {
                    let (file, fel) = self.string(&p, "filename")?.ok_or_else(|| {
                        self.err(el, format!("a `{kind}` shape needs <string name=\"filename\" value=\"...\"/>"))
                    })?;
                    let path = self.src(fel).base.join(&file);
                    let loaded = if kind == "obj" {
                        TriangleMesh::load_obj(&path).map_err(|e| e.to_string())
                    } else {
                        load_ply(&path)
                    };
                    let mut mesh = loaded.map_err(|e| self.err(fel, e))?;
                    if self.boolean(&p, "face_normals")? == Some(true) {
                        mesh.normals = None;
                    }
                    let _ = self.boolean(&p, "flip_tex_coords")?;
                    mesh
                };
                let mut mesh = mesh.transformed(&to_world);
                if (to_world.m.determinant() < 0.0) != flip {
                    for t in &mut mesh.indices {
                        t.swap(1, 2);
                    }
                }
                if flip && let Some(ns) = &mut mesh.normals {
                    for n in ns {
                        *n = -*n;
                    }
                }
                if mesh.positions.iter().any(|v| !v.is_finite()) {
                    return Err(self.err(el, "mesh has non-finite vertices after its to_world transform"));
                }
                // An emitting mesh can be a light here only when it is one parallelogram.
                if radiance.is_some() {
                    match parallelogram(&mesh) {
                        Some(q) => emitters_out.push(Emitter::Quad(q)),
                        None => {
                            self.warn(el, format!("area emitters on `{kind}` shapes are supported only for a single planar parallelogram (two triangles): this shape does not emit"))?;
                            radiance = None;
                        }
                    }
                }
                if emitters_out.is_empty() {
                    mesh_out = Some(mesh);
                }
            }
            other => {
                self.warn(el, format!("shape `{other}` is not supported and is skipped"))?;
                for u in &p.used {
                    u.set(true);
                }
                self.finish(&p)?;
                return Ok(());
            }
        }

        let Some(material) = material else {
            // A `null` BSDF: nothing to see, only the emission (if any).
            if let Some(radiance) = radiance {
                for e in emitters_out {
                    b.lights.push(PendingLight::Area {
                        emitter: e,
                        radiance,
                        material: Material::emitter(radiance, 0),
                    });
                }
            }
            return self.finish(&p);
        };
        let m = b.materials[material as usize];
        if let Some(radiance) = radiance {
            // The emitter's surface keeps its BSDF (Mitsuba lights reflect too); a black one is
            // exactly our plain emitter material.
            let reflects = m.is_specular() || (m.color * m.kd).max_element() > 0.0 || m.ks > 0.0;
            let surface = if reflects { m } else { Material::emitter(radiance, 0) };
            for e in emitters_out {
                b.lights.push(PendingLight::Area { emitter: e, radiance, material: surface });
            }
            return self.finish(&p);
        }
        if let Some(mesh) = mesh_out {
            let id = b.meshes.len() as u32;
            let (tris, skipped) = mesh.triangles(id);
            b.info.triangles += tris.len();
            b.info.degenerate_triangles += skipped;
            b.prims.extend(tris.into_iter().map(|t| Primitive { shape: Shape::Triangle(t), material }));
            b.meshes.push(mesh);
        }
        for e in emitters_out {
            let shape = match e {
                Emitter::Quad(q) => Shape::Quad(q),
                Emitter::Sphere(s) => Shape::Sphere(s),
            };
            b.prims.push(Primitive { shape, material });
        }
        if m.is_specular() && b.prims.len() > first_prim {
            let bb = b.prims[first_prim..].iter().fold(Aabb::EMPTY, |acc, p| acc.union(p.shape.bounds()));
            b.specular_targets.push(match b.prims[first_prim].shape {
                Shape::Sphere(s) if b.prims.len() == first_prim + 1 => (s.center, s.radius),
                _ => bb.bounding_sphere(),
            });
        }
        self.finish(&p)
    }

    /// Reads a top-level emitter; returns true for a constant environment.
    fn emitter(&mut self, el: &'a El, b: &mut Build) -> Result<bool, SceneError> {
        let p = self.props(el)?;
        let mut constant = false;
        match p.kind.as_str() {
            "point" => {
                let intensity = self.color(&p, "intensity")?.unwrap_or(Color::ONE);
                let position = match (self.point(&p, "position")?, self.transform(&p, "to_world")?) {
                    (Some(_), Some(_)) => return Err(self.err(el, "give either `position` or `to_world`, not both")),
                    (Some(pos), None) => pos,
                    (None, Some(x)) => x.t.point(Vec3::ZERO),
                    (None, None) => Vec3::ZERO,
                };
                b.lights.push(PendingLight::Ready(Light::Point { position, intensity }));
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
                b.lights.push(PendingLight::Ready(Light::Spot {
                    position: x.point(Vec3::ZERO),
                    direction,
                    intensity,
                    cos_total: cutoff.to_radians().cos(),
                    cos_falloff: beam.to_radians().cos(),
                }));
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
                b.lights.push(PendingLight::Ready(Light::Directional {
                    direction,
                    irradiance,
                    scene_center: Vec3::ZERO,
                    scene_radius: 0.0,
                }));
            }
            "constant" => {
                b.background += self.color(&p, "radiance")?.unwrap_or(Color::ONE);
                constant = true;
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
        Ok(constant)
    }
}

/// What the sensor, film and sampler give.
struct SensorOut {
    camera: Camera,
    settings: RenderSettings,
}

impl<'a> Cx<'a> {
    fn sensor(&mut self, sensor: Option<&'a El>, root: &'a El, overrides: &Overrides) -> Result<SensorOut, SceneError> {
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
        // Film.
        let (mut width, mut height) = (768u32, 576u32);
        let films = self.object(&p, None, "film");
        if let Some(&(fel, _)) = films.first() {
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
                    self.warn(at, format!("reconstruction filter `{kind}` is not supported: pixels average their samples (a box filter)"))?;
                }
            }
            self.finish(&fp)?;
        }
        // Sampler.
        let mut spp = 4u32;
        let mut seed = 0u64;
        let mut sampler = SamplerKind::Jittered;
        if let Some(&(sel, _)) = self.object(&p, None, "sampler").first() {
            let sp = self.props(sel)?;
            sampler = match sp.kind.as_str() {
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
                spp = n as u32;
            }
            if let Some((s, sel2)) = self.integer(&sp, "seed")? {
                if s < 0 {
                    return Err(self.err(sel2, format!("seed must be 0 or more, found {s}")));
                }
                seed = s as u64;
            }
            let _ = self.boolean(&sp, "jitter")?;
            let _ = self.integer(&sp, "dimension")?;
            let _ = self.integer(&sp, "strength")?;
            self.finish(&sp)?;
        }

        let width = overrides.width.unwrap_or(width);
        let height = overrides.height.unwrap_or(height);
        if width == 0
            || height == 0
            || width > MAX_SIDE
            || height > MAX_SIDE
            || width as u64 * height as u64 > MAX_PIXELS
        {
            return Err(self.err(el, format!("image size {width} x {height} is out of range (each side 1 to {MAX_SIDE}, at most {MAX_PIXELS} pixels)")));
        }
        let aspect = width as f64 / height as f64;

        // Field of view, as the tangent of half the horizontal angle.
        let fov = self.float(&p, "fov")?;
        let focal_length = self.string(&p, "focal_length")?;
        let axis_given = self.string(&p, "fov_axis")?;
        let (fov_deg, axis) = match (fov, &focal_length) {
            (Some(_), Some(_)) => return Err(self.err(el, "give either `fov` or `focal_length`, not both")),
            (Some(f), None) => {
                let axis = axis_given.as_ref().map_or("x".to_string(), |a| a.0.to_ascii_lowercase());
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
                ((36.0f64.hypot(24.0) / (2.0 * v)).atan().to_degrees() * 2.0, "diagonal".to_string())
            }
        };
        if !(fov_deg > 0.0 && fov_deg < 180.0) {
            return Err(self.err(el, format!("fov must be between 0 and 180 degrees, found {fov_deg}")));
        }
        let axis = match axis.as_str() {
            "smaller" => if aspect > 1.0 { "y" } else { "x" }.to_string(),
            "larger" => if aspect > 1.0 { "x" } else { "y" }.to_string(),
            a => a.to_string(),
        };
        let half = (fov_deg.to_radians() * 0.5).tan();
        let tan_x = match axis.as_str() {
            "x" => half,
            "y" => half * aspect,
            "diagonal" => half / (1.0 + 1.0 / (aspect * aspect)).sqrt(),
            other => {
                let at = axis_given.as_ref().map_or(el, |a| a.1);
                return Err(
                    self.err(at, format!("fov_axis must be x, y, diagonal, smaller or larger, found `{other}`"))
                );
            }
        };
        // Our camera takes the vertical angle; pass the given one unchanged when it is vertical.
        let vertical_given = axis == "y" || (axis == "x" && width == height);
        let fov_y = if vertical_given { fov_deg as f32 } else { (2.0 * (tan_x / aspect).atan()).to_degrees() as f32 };

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
        let mut camera = match xform.as_ref().and_then(|x| x.lookat) {
            Some((origin, target, up)) => {
                Camera::new(origin, target, up, ViewPlane::Fov(fov_y), width, height, lens_radius, focus)
            }
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
                let mut c =
                    Camera::new(origin, origin + z, y, ViewPlane::Fov(fov_y), width, height, lens_radius, focus);
                // The image's x axis is local -x; this also keeps a mirroring to_world mirrored.
                c.u = -x.normalize();
                c
            }
        };
        if !vertical_given {
            camera.pixel_size = (2.0 * tan_x / width as f64) as f32 * camera.d;
        }
        self.finish(&p)?;

        // Samples: the sampler's count, unless the command line gives one (as the TOML loader).
        let cli_samples = overrides.spp.is_some() || overrides.spp_axis.is_some();
        let (spp, strata) = if cli_samples {
            match (overrides.spp, overrides.spp_axis) {
                (Some(s), a) => (s, a.unwrap_or((s as f64).sqrt() as u32)),
                (None, Some(n)) => (n.saturating_mul(n), n),
                (None, None) => unreachable!(),
            }
        } else {
            (spp, (spp as f64).sqrt() as u32)
        };
        if spp == 0 || strata == 0 || strata > 4096 {
            return Err(self.err(el, format!("samples per pixel must be at least 1 (got spp {spp}, samples per axis {strata}; at most 4096 per axis)")));
        }
        let settings = RenderSettings {
            width,
            height,
            spp,
            strata,
            seed: overrides.seed.unwrap_or(seed),
            sampler: overrides.sampler.unwrap_or(sampler),
            antialias: overrides.antialias.unwrap_or(true),
            time_limit: None,
            checkpoint: None,
            progress: false,
            layers: false,
        };
        Ok(SensorOut { camera, settings })
    }
}

// ---------------------------------------------------------------------------------------------
// Geometry helpers
// ---------------------------------------------------------------------------------------------

/// The unit disk at z = 0 facing +z as a fan of `n` triangles, its radius enlarged so the
/// polygon has the disk's area (pi).
fn disk_mesh(n: u32) -> TriangleMesh {
    let step = std::f32::consts::TAU / n as f32;
    let r = (std::f32::consts::TAU / (n as f32 * step.sin())).sqrt();
    let mut positions = vec![Vec3::ZERO];
    positions.extend((0..n).map(|i| {
        let a = i as f32 * step;
        Vec3::new(r * a.cos(), r * a.sin(), 0.0)
    }));
    let indices = (0..n).map(|i| [0, 1 + i, 1 + (i + 1) % n]).collect();
    let normals = Some(vec![Vec3::Z; positions.len()]);
    TriangleMesh { positions, normals, indices }
}

/// A mesh of two triangles that form a planar parallelogram, as a quad facing the triangles'
/// side.
fn parallelogram(mesh: &TriangleMesh) -> Option<Quad> {
    if mesh.indices.len() != 2 {
        return None;
    }
    let tri = |k: usize| mesh.indices[k].map(|i| mesh.positions[i as usize]);
    let (a, b) = (tri(0), tri(1));
    let n = (a[1] - a[0]).cross(a[2] - a[0]);
    // The vertex of the second triangle not in the first.
    let extra: Vec<Vec3> = b.iter().copied().filter(|p| !a.contains(p)).collect();
    let [d] = extra.as_slice() else { return None };
    // Find the corner of the first triangle opposite to d: p0 = (sum of the two shared) - d.
    for k in 0..3 {
        let (p, q, r) = (a[k], a[(k + 1) % 3], a[(k + 2) % 3]);
        // p is the corner; q and r are the neighbours; the fourth corner should be q + r - p.
        let fourth = q + r - p;
        let scale = (q - p).length().max((r - p).length());
        if (fourth - *d).length() <= 1e-4 * scale {
            let (e1, e2) = (q - p, r - p);
            return if e1.cross(e2).dot(n) >= 0.0 { Quad::new(p, e1, e2) } else { Quad::new(p, e2, e1) };
        }
    }
    None
}

/// Loads a PLY mesh (ASCII or binary): vertex x, y, z (and nx, ny, nz when present) and faces
/// of any size, fanned into triangles.
fn load_ply(path: &Path) -> Result<TriangleMesh, String> {
    use ply_rs_bw::parser::Parser;
    use ply_rs_bw::ply::{DefaultElement, Property};
    let shown = path.display().to_string();
    let file = std::fs::File::open(path).map_err(|e| format!("cannot read mesh file `{shown}`: {e}"))?;
    let mut reader = std::io::BufReader::new(file);
    let ply = Parser::<DefaultElement>::new()
        .read_ply(&mut reader)
        .map_err(|e| format!("cannot read PLY file `{shown}`: {e}"))?;
    let num = |p: &Property| -> Option<f64> {
        Some(match p {
            Property::Char(v) => *v as f64,
            Property::UChar(v) => *v as f64,
            Property::Short(v) => *v as f64,
            Property::UShort(v) => *v as f64,
            Property::Int(v) => *v as f64,
            Property::UInt(v) => *v as f64,
            Property::Float(v) => *v as f64,
            Property::Double(v) => *v,
            _ => return None,
        })
    };
    let list = |p: &Property| -> Option<Vec<i64>> {
        Some(match p {
            Property::ListChar(v) => v.iter().map(|&x| x as i64).collect(),
            Property::ListUChar(v) => v.iter().map(|&x| x as i64).collect(),
            Property::ListShort(v) => v.iter().map(|&x| x as i64).collect(),
            Property::ListUShort(v) => v.iter().map(|&x| x as i64).collect(),
            Property::ListInt(v) => v.iter().map(|&x| x as i64).collect(),
            Property::ListUInt(v) => v.iter().map(|&x| x as i64).collect(),
            _ => return None,
        })
    };
    let invalid = |m: String| format!("PLY file `{shown}`: {m}");
    let vertices = ply.payload.get("vertex").ok_or_else(|| invalid("no `vertex` element".into()))?;
    let mut positions = Vec::with_capacity(vertices.len());
    let mut normals = Vec::new();
    let has_normals =
        vertices.first().is_some_and(|v| v.contains_key("nx") && v.contains_key("ny") && v.contains_key("nz"));
    for (i, v) in vertices.iter().enumerate() {
        let get = |k: &str| v.get(k).and_then(num);
        let (Some(x), Some(y), Some(z)) = (get("x"), get("y"), get("z")) else {
            return Err(invalid(format!("vertex {i} has no numeric x, y, z")));
        };
        let p = Vec3::new(x as f32, y as f32, z as f32);
        if !p.is_finite() {
            return Err(invalid(format!("vertex {i} is not finite")));
        }
        positions.push(p);
        if has_normals {
            // Normalised when the mesh is transformed.
            normals.push(Vec3::new(
                get("nx").unwrap_or(0.0) as f32,
                get("ny").unwrap_or(0.0) as f32,
                get("nz").unwrap_or(0.0) as f32,
            ));
        }
    }
    let faces = ply.payload.get("face").ok_or_else(|| invalid("no `face` element".into()))?;
    let mut indices = Vec::with_capacity(faces.len());
    for (i, f) in faces.iter().enumerate() {
        let idx = f
            .get("vertex_indices")
            .or_else(|| f.get("vertex_index"))
            .and_then(list)
            .ok_or_else(|| invalid(format!("face {i} has no vertex_indices list")))?;
        if let Some(bad) = idx.iter().find(|&&k| k < 0 || k as usize >= positions.len()) {
            return Err(invalid(format!("face {i} refers to vertex {bad} of {}", positions.len())));
        }
        for k in 1..idx.len().saturating_sub(1) {
            indices.push([idx[0] as u32, idx[k] as u32, idx[k + 1] as u32]);
        }
    }
    if indices.is_empty() {
        return Err(invalid("no triangles".into()));
    }
    Ok(TriangleMesh { positions, normals: has_normals.then_some(normals), indices })
}
