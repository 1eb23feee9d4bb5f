//! Reading the properties of Mitsuba objects: `$name` substitution, `<ref>`s, typed values
//! (numbers, colours, points, indices of refraction) with their file positions, and reports of
//! what was not read (a warning, or an error with `--strict`).

use super::xml::{Attr, El, Src};
use crate::geometry::Transform;
use crate::math::{Color, Vec3};
use crate::scene::SceneError;
use crate::spectrum::SpectrumUse;
use std::cell::Cell;
use std::collections::HashMap;
use std::ops::Range;

/// Object (plugin) tags of the format.
pub(super) const OBJECT_TAGS: &[&str] = &[
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
pub(super) const PROPERTY_TAGS: &[&str] =
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

/// The reading state: the source files, `$name` parameter values, objects by id, and the
/// warnings so far.
pub(super) struct Cx<'a> {
    pub srcs: &'a [Src],
    pub defines: HashMap<String, String>,
    pub ids: HashMap<String, &'a El>,
    pub warnings: Vec<String>,
    pub strict: bool,
    /// The hook every file is reported to before it is read (shared with the scene builder).
    pub files: &'a crate::scene::FileBudget,
    /// The AOVs an `aov` integrator asks for.
    pub aovs: crate::film::aov::AovList,
    /// The last `<spectrum>` read as a spectrum (not an RGB colour), which the emitter or BSDF
    /// reading it takes (`emission_color`, `given_id`) for spectral mode.
    pub given_spectrum: Option<crate::spectrum::SampledSpectrum>,
    /// The spectra the BSDF just read kept for its constant colours (`bsdf` leaves them here
    /// for `material_at`, which files them under the material's index).
    pub bsdf_given: crate::material::GivenSpectra,
}

/// A transform with, when it is exactly one `lookat`, that lookat's (origin, target, up).
pub(super) struct Xform {
    pub t: Transform,
    pub lookat: Option<(Vec3, Vec3, Vec3)>,
}

/// One entry of an object's body.
pub(super) enum Entry<'a> {
    /// A property element (`<float name=...>` etc.).
    Prop { name: String, el: &'a El },
    /// A nested object or a `<ref>`: `el` is the object itself, `at` where it is used.
    Object { name: Option<String>, el: &'a El, at: &'a El },
}

/// The body of an object element: its properties and nested objects, with a flag per entry
/// saying whether it was read (unread ones are reported).
pub(super) struct Props<'a> {
    pub el: &'a El,
    pub kind: String,
    pub entries: Vec<Entry<'a>>,
    pub used: Vec<Cell<bool>>,
    /// Every property name the reader asked for, to suggest one for a misspelt name.
    pub asked: std::cell::RefCell<Vec<String>>,
}

impl<'a> Cx<'a> {
    pub(super) fn src(&self, el: &El) -> &'a Src {
        &self.srcs[el.src]
    }

    pub(super) fn err(&self, el: &El, message: impl Into<String>) -> SceneError {
        self.err_span(el, el.span.clone(), message)
    }

    pub(super) fn err_span(&self, el: &El, span: Range<usize>, message: impl Into<String>) -> SceneError {
        let s = self.src(el);
        if s.from_set {
            // A `--set` value has no line: the error names the `--set` (the source's name).
            return SceneError::File {
                path: self.srcs[0].name.clone(),
                message: format!("{}: {}", s.name, message.into()),
            };
        }
        SceneError::at(&s.name, &s.text, span, message)
    }

    /// A plugin `name` of `kind` that we do not render: an error when Mitsuba 3 has no such
    /// plugin either (a misspelling, named as the nearest known one), otherwise a warning
    /// saying `instead` (what is rendered in its place), or an error with `--strict`.
    pub(super) fn unsupported(
        &mut self,
        el: &El,
        kind: super::plugins::PluginKind,
        name: &str,
        instead: &str,
    ) -> Result<(), SceneError> {
        if let Some(message) = super::plugins::unknown(kind, name) {
            return Err(self.err(el, message));
        }
        self.warn(el, format!("{} `{name}` is not supported{instead}", kind.word()))
    }

    /// Reports something we do not render: a warning, or an error with `--strict`.
    pub(super) fn warn(&mut self, el: &El, message: impl Into<String>) -> Result<(), SceneError> {
        let message = message.into();
        if self.strict {
            return Err(self.err(el, format!("{message} (an error with --strict)")));
        }
        self.note(el, message);
        Ok(())
    }

    /// A warning about something rendered as Mitsuba renders it (never an error).
    pub(super) fn note(&mut self, el: &El, message: impl Into<String>) {
        let message = message.into();
        let s = self.src(el);
        if s.from_set {
            self.warnings.push(format!("{}: {}: {message}", self.srcs[0].name, s.name));
            return;
        }
        let (line, column) = crate::scene::error::line_column(&s.text, el.span.start);
        self.warnings.push(format!("{}:{line}:{column}: {message}", s.name));
    }

    /// An attribute's value with `$name` parameters substituted.
    pub(super) fn attr(&self, el: &El, name: &str) -> Result<Option<(String, Range<usize>)>, SceneError> {
        let Some(a) = el.attrs.iter().find(|a| a.name == name) else { return Ok(None) };
        Ok(Some((self.substitute(el, a)?, a.span.clone())))
    }

    pub(super) fn required_attr(&self, el: &El, name: &str) -> Result<(String, Range<usize>), SceneError> {
        self.attr(el, name)?.ok_or_else(|| self.err(el, format!("<{}> needs a `{name}` attribute", el.tag)))
    }

    pub(super) fn substitute(&self, el: &El, a: &Attr) -> Result<String, SceneError> {
        if !a.value.contains('$') {
            return Ok(a.value.clone());
        }
        let mut out = String::new();
        let mut rest = a.value.as_str();
        while let Some((before, key, after)) = next_parameter(rest) {
            out.push_str(before);
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
            rest = after;
        }
        out.push_str(rest);
        Ok(out)
    }

    /// The file a relative name in element `el` refers to, looked up as Mitsuba builds objects:
    /// in the scene file's `<path>` folders (newest first), then its folder. A name found
    /// nowhere is an error naming the folders searched.
    pub(super) fn resolve_file(&self, el: &El, name: &str) -> Result<std::path::PathBuf, SceneError> {
        self.srcs[0].resolver.resolve(name).filter(|p| p.is_file()).ok_or_else(|| {
            self.err(el, format!("file `{name}` not found (looked in {})", self.srcs[0].resolver.searched()))
        })
    }

    /// Collects `<default>`s (command-line values win) and object ids of the whole tree.
    pub(super) fn index(&mut self, root: &'a El) -> Result<(), SceneError> {
        for child in &root.children {
            if child.tag == "default" {
                let (name, _) = self.required_attr(child, "name")?;
                let (value, _) = self.required_attr(child, "value")?;
                self.defines.entry(name).or_insert(value);
            }
        }
        self.index_ids(root)
    }

    pub(super) fn index_ids(&mut self, el: &'a El) -> Result<(), SceneError> {
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
    pub(super) fn resolve(&self, r: &El) -> Result<&'a El, SceneError> {
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
    pub(super) fn props(&self, el: &'a El) -> Result<Props<'a>, SceneError> {
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
        Ok(Props { el, kind, entries, used, asked: Default::default() })
    }

    /// Warns about every entry of `p` nothing read.
    pub(super) fn finish(&mut self, p: &Props<'a>) -> Result<(), SceneError> {
        for (e, used) in p.entries.iter().zip(&p.used) {
            if used.get() {
                continue;
            }
            match e {
                Entry::Prop { name, el } => {
                    let asked = p.asked.borrow();
                    let message = match closest(name, asked.iter().map(String::as_str)) {
                        Some(known) => format!(
                            "<{} type=\"{}\"> has no property `{name}` (did you mean `{known}`?); it is ignored",
                            p.el.tag, p.kind
                        ),
                        None => format!(
                            "property `{name}` of <{} type=\"{}\"> is not read by caustic and is ignored",
                            p.el.tag, p.kind
                        ),
                    };
                    drop(asked);
                    if self.src(el).from_set {
                        // Asked for on the command line: reading nothing would say nothing.
                        let message = message.trim_end_matches("; it is ignored").trim_end_matches(" and is ignored");
                        return Err(self.err(el, format!("{message}, so this --set would change nothing")));
                    }
                    self.warn(el, message)?;
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
    pub(super) fn prop(&self, p: &Props<'a>, name: &str) -> Option<&'a El> {
        p.asked.borrow_mut().push(name.to_string());
        p.entries.iter().zip(&p.used).find_map(|(e, used)| match e {
            Entry::Prop { name: n, el } if n == name => {
                used.set(true);
                Some(*el)
            }
            _ => None,
        })
    }

    /// A nested object named `name`, or (when `tag` matches) an unnamed one; marked as read.
    pub(super) fn object(&self, p: &Props<'a>, name: Option<&str>, tag: &str) -> Vec<(&'a El, &'a El)> {
        if let Some(n) = name {
            p.asked.borrow_mut().push(n.to_string());
        }
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

    pub(super) fn value(&self, el: &El) -> Result<(String, Range<usize>), SceneError> {
        self.required_attr(el, "value")
    }

    pub(super) fn wrong_type(&self, el: &El, name: &str, want: &str) -> SceneError {
        self.err(el, format!("property `{name}` must be {want}, found <{}>", el.tag))
    }

    pub(super) fn parse_f32(&self, el: &El, s: &str, span: Range<usize>) -> Result<f32, SceneError> {
        match s.trim().parse::<f32>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(self.err_span(el, span, format!("expected a number, found `{s}`"))),
        }
    }

    /// Numbers separated by commas and/or spaces.
    pub(super) fn parse_list(&self, el: &El, s: &str, span: Range<usize>) -> Result<Vec<f32>, SceneError> {
        s.split(|c: char| c == ',' || c.is_whitespace())
            .filter(|t| !t.is_empty())
            .map(|t| self.parse_f32(el, t, span.clone()))
            .collect()
    }

    pub(super) fn float(&self, p: &Props<'a>, name: &str) -> Result<Option<f32>, SceneError> {
        let Some(el) = self.prop(p, name) else { return Ok(None) };
        if el.tag != "float" && el.tag != "integer" {
            return Err(self.wrong_type(el, name, "a <float>"));
        }
        let (v, span) = self.value(el)?;
        self.parse_f32(el, &v, span).map(Some)
    }

    pub(super) fn integer(&self, p: &Props<'a>, name: &str) -> Result<Option<(i64, &'a El)>, SceneError> {
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

    pub(super) fn boolean(&self, p: &Props<'a>, name: &str) -> Result<Option<bool>, SceneError> {
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

    pub(super) fn string(&self, p: &Props<'a>, name: &str) -> Result<Option<(String, &'a El)>, SceneError> {
        let Some(el) = self.prop(p, name) else { return Ok(None) };
        if el.tag != "string" {
            return Err(self.wrong_type(el, name, "a <string>"));
        }
        Ok(Some((self.value(el)?.0, el)))
    }

    /// A point or vector: `value="x, y, z"` or `x=`, `y=`, `z=` attributes (missing ones 0).
    pub(super) fn vec3_of(&self, el: &El) -> Result<Vec3, SceneError> {
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

    pub(super) fn point(&self, p: &Props<'a>, name: &str) -> Result<Option<Vec3>, SceneError> {
        let Some(el) = self.prop(p, name) else { return Ok(None) };
        if el.tag != "point" && el.tag != "vector" {
            return Err(self.wrong_type(el, name, "a <point> or <vector>"));
        }
        self.vec3_of(el).map(Some)
    }

    /// A colour: `<rgb>`, `<spectrum>`, `<float>`, or a texture (whose mean or grey is used);
    /// spectra are converted as reflectances.
    pub(super) fn color(&mut self, p: &Props<'a>, name: &str) -> Result<Option<Color>, SceneError> {
        self.color_for(p, name, SpectrumUse::Reflectance)
    }

    /// `color`, with spectra converted for `usage`.
    pub(super) fn color_for(
        &mut self,
        p: &Props<'a>,
        name: &str,
        usage: SpectrumUse,
    ) -> Result<Option<Color>, SceneError> {
        if let Some(el) = self.prop(p, name) {
            return self.color_of_for(el, name, usage).map(Some);
        }
        if let Some(&(tex, at)) = self.object(p, Some(name), "texture").first() {
            return self.texture_mean(tex, at).map(Some);
        }
        Ok(None)
    }

    pub(super) fn color_of(&mut self, el: &'a El, name: &str) -> Result<Color, SceneError> {
        self.color_of_for(el, name, SpectrumUse::Reflectance)
    }

    /// The colour of a property element, spectra converted for `usage` as Mitsuba's RGB
    /// variants convert them.
    pub(super) fn color_of_for(&mut self, el: &'a El, name: &str, usage: SpectrumUse) -> Result<Color, SceneError> {
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
            "spectrum" => self.spectrum_color(el, name, usage),
            _ => Err(self.wrong_type(el, name, "an <rgb>, <spectrum> or <float>")),
        }
    }

    /// A texture where only a constant colour can go (a conductor's eta and k, a spectrum that
    /// does not vary over the surface here): its mean colour, with a warning. Images are read
    /// only to take their mean.
    pub(super) fn texture_mean(&mut self, tex: &'a El, at: &'a El) -> Result<Color, SceneError> {
        let p = self.props(tex)?;
        let c = match p.kind.as_str() {
            "checkerboard" => {
                let c0 = self.color(&p, "color0")?.unwrap_or(Color::splat(0.4));
                let c1 = self.color(&p, "color1")?.unwrap_or(Color::splat(0.2));
                (c0 + c1) * 0.5
            }
            "bitmap" => match self.string(&p, "filename")? {
                Some((file, fel)) => {
                    let path = self.resolve_file(fel, &file)?;
                    let raw = self.boolean(&p, "raw")? == Some(true);
                    self.files.open(&path, crate::scene::FileKind::Image)?;
                    let image =
                        crate::texture::image::load_image(&path, raw).map_err(|e| self.err(fel, e.to_string()))?;
                    let t = crate::texture::Texture::Bitmap(crate::texture::Bitmap {
                        image: std::sync::Arc::new(image),
                        filter: crate::texture::Filter::Bilinear,
                        wrap: crate::texture::Wrap::Repeat,
                        to_uv: glam::Affine2::IDENTITY,
                    });
                    t.mean()
                }
                None => return Err(self.err(tex, "a bitmap texture needs <string name=\"filename\" .../>")),
            },
            _ => Color::splat(0.5),
        };
        for e in p.used.iter() {
            e.set(true);
        }
        self.warn(
            at,
            format!("a <texture type=\"{}\"> cannot vary over the surface here: its mean colour {c} is used", p.kind),
        )?;
        Ok(c)
    }

    /// An index of refraction: a number or one of Mitsuba's named materials.
    /// A dispersive glass named by `int_ior`: caustic's extension, a name of
    /// `spectrum::Dispersion`'s table that Mitsuba's own list lacks (`dense flint`, `fused
    /// silica`); `None` for numbers and Mitsuba's names, which keep Mitsuba's single index so
    /// that its scenes render as it renders them.
    pub(super) fn dispersive_int_ior(&self, p: &Props<'a>) -> Result<Option<crate::spectrum::Dispersion>, SceneError> {
        let Some(el) = self.prop(p, "int_ior") else { return Ok(None) };
        if el.tag != "string" {
            return Ok(None);
        }
        let (v, _) = self.value(el)?;
        let key = v.trim().to_ascii_lowercase();
        if NAMED_IOR.iter().any(|(n, _)| *n == key) {
            return Ok(None);
        }
        Ok(crate::spectrum::Dispersion::named(&key).ok())
    }

    pub(super) fn ior(&self, p: &Props<'a>, name: &str, default: f32) -> Result<f32, SceneError> {
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

/// The first `$name` reference in `text`: (the text before it, the name, the text after it);
/// the name is empty for a `$` followed by no name character.
pub(crate) fn next_parameter(text: &str) -> Option<(&str, &str, &str)> {
    let i = text.find('$')?;
    let after = &text[i + 1..];
    let len = after.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(after.len());
    Some((&text[..i], &after[..len], &after[len..]))
}

/// The name among `known` closest to `name` by edit distance, when it is close enough to be a
/// misspelling (at most a third of the name's letters differ, and at least one does).
pub(crate) fn closest<'k>(name: &str, known: impl Iterator<Item = &'k str>) -> Option<&'k str> {
    let limit = (name.chars().count() / 3).max(1);
    known
        .filter(|k| *k != name)
        .map(|k| (edit_distance(name, k), k))
        .filter(|(d, _)| *d <= limit)
        .min_by_key(|(d, _)| *d)
        .map(|(_, k)| k)
}

/// Levenshtein distance, counting a swap of two neighbouring letters as one edit (so `raduis`
/// is one edit from `radius`).
fn edit_distance(a: &str, b: &str) -> usize {
    let (a, b): (Vec<char>, Vec<char>) = (a.chars().collect(), b.chars().collect());
    let mut d = vec![vec![0usize; b.len() + 1]; a.len() + 1];
    for (i, row) in d.iter_mut().enumerate() {
        row[0] = i;
    }
    for (j, cell) in d[0].iter_mut().enumerate() {
        *cell = j;
    }
    for i in 1..=a.len() {
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            d[i][j] = (d[i - 1][j] + 1).min(d[i][j - 1] + 1).min(d[i - 1][j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                d[i][j] = d[i][j].min(d[i - 2][j - 2] + 1);
            }
        }
    }
    d[a.len()][b.len()]
}
