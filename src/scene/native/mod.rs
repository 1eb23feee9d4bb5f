//! Reads a TOML scene file (format in `docs/scene-format.md`) into a [`SceneDescription`].
//!
//! The document is parsed once into a tree that keeps every value's position. Tagged tables
//! (materials, lights and objects, chosen by `type`) are dispatched by hand, their keys checked
//! against the keys that kind accepts, and the rest deserialized with serde from that tree, so
//! every error, even one found by a validating type deep inside, points at its line and column.
//! Loading runs in named steps, one per section: render settings, camera, materials, lights,
//! objects. `[render]`'s options are applied over the defaults by `SceneDescription::apply`, as
//! the command line's are over the file's.

mod camera;
mod materials;
mod media;
mod objects;
mod params;
mod schema;
mod set;
mod spectra;

pub use set::{ALIASES, key_path, parse_set};

use super::SceneError;
use super::builder::SceneBuilder;
use super::desc::{IntegratorDesc, SamplerDesc, SceneDescription};
use super::footprint::FileBudget;
use crate::material::Material;
use crate::math::Color;
use materials::MaterialNames;
use schema::RenderDesc;
use serde::Deserialize;
use std::collections::HashMap;
use std::ops::Range;
use std::path::Path;
use toml::Spanned;
use toml::de::{DeString, DeTable, DeValue, ValueDeserializer};

/// The top-level sections of a scene file.
const SECTION_NAMES: &[&str] =
    &["parameters", "render", "camera", "textures", "materials", "media", "lights", "groups", "objects"];

/// Default image size when the file gives none.
const DEFAULT_SIZE: (u32, u32) = (640, 480);

/// Loads a TOML scene from `text`; `name` is used in messages and mesh paths resolve against
/// `base`; `defines` are the `-D name=value` given for its `$name` parameters and `sets` the
/// `--set KEY=VALUE` put in place of its keys' values. Every mesh and image is reported to
/// `files` before it is read.
pub fn load_toml_str<'a>(
    text: &'a str,
    name: &'a str,
    base: &'a Path,
    files: &'a FileBudget,
    defines: &'a [(String, String)],
    sets: &'a [(String, String)],
) -> Result<SceneDescription, SceneError> {
    let plain = Cx { path: name, text, base, files, substituted: &[], placed: &[] };
    let mut sections = plain.sections()?;
    let substituted = params::substitute(&plain, &mut sections, defines)?;
    // After the parameters: a --set value is taken as written, and wins over a `$name` there.
    let placed = set::apply(&plain, &mut sections, sets)?;
    let cx = Cx { substituted: &substituted, placed: &placed, ..plain };
    let render: RenderDesc = match sections.remove("render") {
        Some(v) => cx.de(v)?,
        None => RenderDesc::default(),
    };
    let mut camera_section = sections.remove("camera");
    let camera_medium = take_key(&mut camera_section, "medium");
    let camera = cx.camera(camera_section)?;
    let mut geometry = SceneBuilder::with_files(files.clone());
    let textures = cx.textures(sections.remove("textures"), &mut geometry)?;
    let materials = cx.materials(sections.remove("materials"), &textures, &mut geometry)?;
    let media = cx.media(sections.remove("media"), &mut geometry)?;
    if let Some(v) = camera_medium {
        let span = v.span();
        let name = match v.into_inner() {
            DeValue::String(n) => Spanned::new(span, n.to_string()),
            _ => return Err(cx.at(span, "`medium` must be the name of a [media.NAME] table")),
        };
        let m = cx.medium_named(&media, &name)?;
        geometry.set_camera_medium(m);
    }
    if let Some(v) = sections.remove("lights") {
        cx.lights(v, &mut geometry)?;
    }
    // The old `background` colour is a constant environment light.
    if let Some(b) = render.background.as_ref().filter(|b| b.get_ref().0 != Color::ZERO) {
        let env = crate::light::Environment::constant(b.get_ref().0);
        geometry.set_environment(env).map_err(|_| {
            cx.at(b.span(), "`background` is a constant environment light and [[lights]] has one too: keep one of them")
        })?;
    }
    let groups = match sections.remove("groups") {
        Some(v) => cx.groups(v, &materials, &media, &mut geometry)?,
        None => Default::default(),
    };
    if let Some(v) = sections.remove("objects") {
        cx.objects(v, &materials, &textures, &media, &groups, &mut geometry)?;
    }
    let mut options = render.options();
    if let Some(a) = &render.aov {
        let list = crate::film::aov::AovList::parse(a.get_ref()).map_err(|m| cx.at(a.span(), m))?;
        options.aov = Some(list);
    }
    let (width, height) = (options.width.unwrap_or(DEFAULT_SIZE.0), options.height.unwrap_or(DEFAULT_SIZE.1));
    let film = cx.film(&render, width, height)?;
    let mut desc = SceneDescription {
        name: name.to_string(),
        geometry,
        camera,
        width,
        height,
        film,
        sampler: SamplerDesc::default(),
        integrator: IntegratorDesc {
            ambient: render.ambient.map_or(Color::ZERO, |c| c.0),
            ray_bias: render.ray_bias.map(|b| b.0),
            transparent_shadows: render.transparent_shadows.unwrap_or(true),
            ..IntegratorDesc::default()
        },
        warnings: Vec::new(),
    };
    // The file's options over the defaults, as the command line's go over the file's: the sampler
    // and integrator are described in one place.
    desc.apply(&options);
    Ok(desc)
}

/// The file being loaded, for error positions, and the hook the files it names are reported to.
struct Cx<'a> {
    path: &'a str,
    text: &'a str,
    base: &'a Path,
    files: &'a FileBudget,
    /// Where `$name` parameters were put, so that an error about one names it.
    substituted: &'a [(Range<usize>, String)],
    /// Where `--set` values were put (past the end of the text) and the `--set` each was.
    placed: &'a [(Range<usize>, String)],
}

impl<'a> Cx<'a> {
    fn at(&self, span: Range<usize>, message: impl Into<String>) -> SceneError {
        // A --set value has no line: the error names the --set instead.
        if let Some((_, set)) = self.placed.iter().find(|(s, _)| s.contains(&span.start)) {
            return SceneError::File { path: self.path.to_string(), message: format!("{set}: {}", message.into()) };
        }
        SceneError::at(self.path, self.text, span, message)
    }

    fn toml(&self, e: toml::de::Error) -> SceneError {
        let span = e.span().unwrap_or(0..0);
        let mut message = plain_words(e.message().trim_end());
        if message.contains("wanted exactly 1 element") {
            message.push_str(" (each transform entry holds one operation: translate, rotate or scale)");
        }
        if let Some((_, name)) = self.substituted.iter().find(|(s, _)| s.start <= span.start && span.end <= s.end) {
            message.push_str(&format!(" (the value of parameter `${name}`)"));
        }
        self.at(span, message)
    }

    fn de<'i, T: Deserialize<'i>>(&self, v: Spanned<DeValue<'i>>) -> Result<T, SceneError> {
        T::deserialize(ValueDeserializer::from(v)).map_err(|e| self.toml(e))
    }

    fn array<'i>(&self, v: Spanned<DeValue<'i>>, what: &str) -> Result<Vec<Spanned<DeValue<'i>>>, SceneError> {
        let span = v.span();
        match v.into_inner() {
            DeValue::Array(a) => Ok(a.into_iter().collect()),
            _ => Err(self.at(span, format!("`{what}` must be an array of tables ([[{what}]])"))),
        }
    }

    /// Step 1: the top-level sections by name; anything else is an error.
    fn sections(&self) -> Result<HashMap<&'static str, Spanned<DeValue<'a>>>, SceneError> {
        let doc = DeTable::parse(self.text).map_err(|e| self.toml(e))?;
        let doc_span = doc.span();
        let mut sections = HashMap::new();
        for (key, value) in doc.into_inner() {
            let k: &str = key.get_ref();
            let known = SECTION_NAMES.iter().copied().find(|s| *s == k);
            let Some(section) = known else {
                let hint = crate::scene::mitsuba::closest(k, SECTION_NAMES.iter().copied())
                    .map_or(String::new(), |near| format!(" (did you mean `{near}`?)"));
                return Err(self.at(
                    key.span(),
                    format!("unknown section `{k}`{hint}; expected one of {}", SECTION_NAMES.join(", ")),
                ));
            };
            sections.insert(section, value);
        }
        if !sections.contains_key("camera") {
            return Err(self.at(doc_span.start..doc_span.start, "missing [camera] section"));
        }
        Ok(sections)
    }

    /// Splits a table with a `type` key into (kind, the rest), checking the other keys against
    /// those `kinds` allows for that kind.
    fn tagged<'i>(
        &self,
        v: Spanned<DeValue<'i>>,
        what: &str,
        kinds: &[(&'static str, &[&str])],
    ) -> Result<(&'static str, Spanned<DeValue<'i>>), SceneError> {
        let span = v.span();
        let DeValue::Table(mut table) = v.into_inner() else {
            return Err(self.at(span, format!("expected a table describing a {what}")));
        };
        let names: Vec<&str> = kinds.iter().map(|k| k.0).collect();
        let Some(ty) = table.remove("type") else {
            return Err(self.at(span, format!("{what} has no `type`; expected one of: {}", names.join(", "))));
        };
        let ty_span = ty.span();
        let Some(ty_str) = ty.get_ref().as_str() else {
            return Err(self.at(ty_span, format!("`type` must be a string, one of: {}", names.join(", "))));
        };
        let Some((kind, allowed)) = kinds.iter().find(|k| k.0 == ty_str) else {
            let hint = crate::scene::mitsuba::closest(ty_str, names.iter().copied())
                .map_or(String::new(), |near| format!(" (did you mean `{near}`?)"));
            return Err(self
                .at(ty_span, format!("unknown {what} type `{ty_str}`{hint}; expected one of: {}", names.join(", "))));
        };
        for key in table.keys() {
            let k: &DeString = key.get_ref();
            if !allowed.contains(&k.as_ref()) {
                let hint = crate::scene::mitsuba::closest(k, allowed.iter().copied())
                    .map_or(String::new(), |near| format!(" (did you mean `{near}`?)"));
                return Err(self.at(
                    key.span(),
                    format!(
                        "unknown key `{k}` for a {kind} {what}{hint}; expected one of: type, {}",
                        allowed.join(", ")
                    ),
                ));
            }
        }
        Ok((kind, Spanned::new(span, DeValue::Table(table))))
    }

    /// The material an object names (or the default one), with an error listing the names.
    fn material_of(
        &self,
        name: Option<&Spanned<String>>,
        names: &MaterialNames,
        geometry: &mut SceneBuilder,
    ) -> Result<u32, SceneError> {
        let Some(name) = name else {
            if let Some(i) = names.default.get() {
                return Ok(i);
            }
            let i = geometry.add_material("(default)", Material::default());
            names.default.set(Some(i));
            return Ok(i);
        };
        names.index.get(name.get_ref().as_str()).copied().ok_or_else(|| {
            let known = names.names.iter().map(String::as_str).collect();
            self.at(name.span(), no_such("material", name.get_ref(), known))
        })
    }
}

/// Takes key `key` out of a section's table (a key read before the rest of the section).
fn take_key<'a>(section: &mut Option<Spanned<DeValue<'a>>>, key: &str) -> Option<Spanned<DeValue<'a>>> {
    match section.as_mut().map(|s| s.get_mut()) {
        Some(DeValue::Table(t)) => t.remove(key),
        _ => None,
    }
}

/// `no material named `glas` (defined: glass, mirror); did you mean `glass`?`: a name that refers
/// to nothing the file defines.
fn no_such(kind: &str, name: &str, mut known: Vec<&str>) -> String {
    known.sort();
    let hint = crate::scene::mitsuba::closest(name, known.iter().copied())
        .map_or(String::new(), |k| format!("; did you mean `{k}`?"));
    let defined = if known.is_empty() { "none".to_string() } else { known.join(", ") };
    format!("no {kind} named `{name}` (defined: {defined}){hint}")
}

/// A serde or TOML message in the scene's words rather than Rust's: `invalid type: string "16",
/// expected u32` becomes `expected a whole number, found the text "16"`, and unknown or missing
/// names are all called keys (serde says field, variant or key depending on where they are).
fn plain_words(message: &str) -> String {
    let kind = |rust: &str| -> String {
        match rust.trim() {
            "u8" | "u16" | "u32" | "u64" | "usize" => "a whole number of 0 or more".into(),
            "i8" | "i16" | "i32" | "i64" | "isize" => "a whole number".into(),
            "f32" | "f64" => "a number".into(),
            "a boolean" | "bool" => "true or false".into(),
            "a sequence" => "a list".into(),
            "a map" => "a table".into(),
            other => other.to_string(),
        }
    };
    let found = |serde: &str| -> String {
        let serde = serde.trim();
        if let Some(text) = serde.strip_prefix("string ") {
            return format!("the text {text}");
        }
        for prefix in ["integer ", "floating point ", "boolean "] {
            if let Some(v) = serde.strip_prefix(prefix) {
                return format!("`{}`", v.trim_matches('`'));
            }
        }
        match serde {
            "sequence" => "a list".into(),
            "map" => "a table".into(),
            other => other.to_string(),
        }
    };
    for prefix in ["invalid type: ", "invalid value: "] {
        if let Some(rest) = message.strip_prefix(prefix)
            && let Some((what, expected)) = rest.split_once(", expected ")
        {
            return format!("expected {}, found {}", kind(expected), found(what));
        }
    }
    let message = message
        .replacen("unknown field", "unknown key", 1)
        .replacen("unknown variant", "unknown value", 1)
        .replacen("missing field", "missing key", 1);
    with_did_you_mean(&message)
}

/// serde's `unknown key `spq`, expected one of `width`, `spp`, ...` with the nearest name after
/// the unknown one: `unknown key `spq` (did you mean `spp`?), expected one of ...`.
fn with_did_you_mean(message: &str) -> String {
    for word in ["unknown key `", "unknown value `"] {
        let Some(start) = message.find(word).map(|i| i + word.len()) else { continue };
        let Some(len) = message[start..].find('`') else { continue };
        let name = &message[start..start + len];
        let rest = &message[start + len + 1..];
        let known = rest.split('`').skip(1).step_by(2);
        if let Some(k) = crate::scene::mitsuba::closest(name, known) {
            return format!("{}`{name}` (did you mean `{k}`?){rest}", &message[..start - 1]);
        }
    }
    message.to_string()
}

#[cfg(test)]
mod message_tests {
    use super::plain_words;

    /// Issue 30, item 8: Rust's type names and serde's three words for an unknown name.
    #[test]
    fn messages_use_the_scenes_words() {
        assert_eq!(
            plain_words(r#"invalid type: string "16", expected u32"#),
            r#"expected a whole number of 0 or more, found the text "16""#
        );
        assert_eq!(plain_words("invalid type: integer `3`, expected a boolean"), "expected true or false, found `3`");
        assert_eq!(
            plain_words(r#"invalid type: string "x", expected f64"#),
            r#"expected a number, found the text "x""#
        );
        assert_eq!(plain_words("invalid type: map, expected a sequence"), "expected a list, found a table");
        assert!(plain_words("unknown field `spq`, expected one of `spp`").starts_with("unknown key `spq`"));
        assert!(plain_words("unknown variant `pth`, expected one of `path`").starts_with("unknown value `pth`"));
        assert_eq!(plain_words("missing field `type`"), "missing key `type`");
        // The nearest accepted name, when one is near.
        assert_eq!(
            plain_words("unknown field `spq`, expected one of `width`, `spp`"),
            "unknown key `spq` (did you mean `spp`?), expected one of `width`, `spp`"
        );
        assert_eq!(
            plain_words("unknown field `zzz`, expected one of `width`, `spp`"),
            "unknown key `zzz`, expected one of `width`, `spp`"
        );
    }
}
