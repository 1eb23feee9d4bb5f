//! `--set KEY=VALUE` on a TOML scene: any key of the file by its dotted path (`render.spp=4`,
//! `materials.glass.ior=1.6`, `objects.0.radius=2`, `camera.eye=[0, 1, 5]`), put into the parsed
//! tree before anything is read from it, so the value meets every check a value written in the
//! file meets (unknown keys with a did-you-mean, types in the scene's words, ranges, names of
//! materials). pbrt-v4 and Mitsuba 3 users look for the render's settings under `integrator`,
//! `film` and `sampler`; TOML keeps them in `[render]`, so those three names are other names for
//! `[render]` keys ([`ALIASES`]).
//!
//! The value is read as a TOML value (`4`, `1.6`, `[0, 1, 5]`, `true`, `{ type = "tent" }`), or
//! as text when it is not one (`film.filter=gaussian`), as `-D` values are. It takes a position
//! past the end of the file's text, one per `--set`, so an error about it names the `--set`
//! (`--set render.spp=x: expected a whole number ...`) instead of a line of the file.

use super::Cx;
use super::params::respan;
use crate::scene::SceneError;
use crate::scene::mitsuba::closest;
use std::borrow::Cow;
use std::collections::HashMap;
use std::ops::Range;
use toml::Spanned;
use toml::de::{DeTable, DeValue};

/// Where each `--set` was put: the position standing for it and its text, `--set KEY=VALUE`.
pub(super) type Placed = Vec<(Range<usize>, String)>;

/// The sections a key path may start with (`parameters` are given with `-D`).
const SECTIONS: &[&str] = &["render", "camera", "textures", "materials", "lights", "groups", "objects"];

/// The names under which pbrt-v4 and Mitsuba 3 group a render's settings, each with its keys and
/// the `[render]` key (a path below `[render]`) it stands for. `integrator` and `sampler` alone
/// are the integrator and the sample pattern (`--set integrator=path`).
pub const ALIASES: &[(&str, &[(&str, &str)])] = &[
    (
        "integrator",
        &[
            ("type", "integrator"),
            ("max_depth", "max_depth"),
            ("light_samples", "light_samples"),
            ("adc_bailout", "adc_bailout"),
            ("ambient", "ambient"),
            ("transparent_shadows", "transparent_shadows"),
            ("ray_bias", "ray_bias"),
            ("spectral", "spectral"),
            ("photons", "photon.photons"),
            ("caustic_photons", "photon.caustic_photons"),
            ("gather", "photon.gather"),
            ("gather_k", "photon.gather_k"),
            ("irradiance_cache", "photon.irradiance_cache"),
            ("cache_rays", "photon.cache_rays"),
            ("caustic_k", "photon.caustic_k"),
            ("max_radius", "photon.max_radius"),
            ("caustic_radius", "photon.caustic_radius"),
            ("volume_k", "photon.volume_k"),
            ("volume_radius", "photon.volume_radius"),
            ("photons_per_iter", "photon.photons_per_iter"),
            ("initial_radius", "photon.initial_radius"),
        ],
    ),
    (
        "film",
        &[
            ("width", "width"),
            ("height", "height"),
            ("filter", "filter"),
            ("crop", "crop"),
            ("sample_border", "sample_border"),
            ("aov", "aov"),
            ("xyz", "xyz"),
        ],
    ),
    (
        "sampler",
        &[("type", "sampler"), ("spp", "spp"), ("spp_axis", "spp_axis"), ("seed", "seed"), ("antialias", "antialias")],
    ),
];

/// Splits `KEY=VALUE` at the first `=` outside quotes (a quoted name may hold one) and checks
/// that KEY is a dotted path of names: what `--set` takes on the command line.
pub fn parse_set(arg: &str) -> Result<(String, String), String> {
    let mut quote: Option<char> = None;
    let split = arg.char_indices().find(|&(_, c)| {
        match (quote, c) {
            (None, '"' | '\'') => quote = Some(c),
            (Some(q), c) if c == q => quote = None,
            _ => {}
        }
        quote.is_none() && c == '='
    });
    let Some((at, _)) = split else {
        return Err(format!(
            "expected KEY=VALUE (a key path such as render.spp or materials.glass.ior), found `{arg}`"
        ));
    };
    let (key, value) = (arg[..at].trim(), &arg[at + 1..]);
    key_path(key)?;
    Ok((key.to_string(), value.to_string()))
}

/// The names of a dotted key path, quoted as TOML quotes them where a name has spaces or dots
/// (`materials."frosted glass".alpha`).
pub fn key_path(key: &str) -> Result<Vec<String>, String> {
    let bad = || {
        format!(
            "`{key}` is not a key path: names joined by dots, e.g. render.spp or materials.glass.ior (quote a name that has spaces or dots: materials.\"frosted glass\".alpha)"
        )
    };
    // The key parsed as TOML parses the key of `KEY = 0`: dotted keys make nested tables.
    let doc = format!("{key} = 0");
    let table = DeTable::parse(&doc).map_err(|_| bad())?.into_inner();
    let mut path = Vec::new();
    let mut level = &table;
    loop {
        let mut entries = level.iter();
        let (Some((k, v)), None) = (entries.next(), entries.next()) else { return Err(bad()) };
        path.push(k.get_ref().to_string());
        match v.get_ref() {
            DeValue::Table(t) => level = t,
            _ => return Ok(path),
        }
    }
}

/// Puts every `--set` of `sets` into `sections`, later ones over earlier ones. Returns the
/// positions given to them, for `Cx::at`.
pub(super) fn apply<'a>(
    cx: &Cx,
    sections: &mut HashMap<&'static str, Spanned<DeValue<'a>>>,
    sets: &'a [(String, String)],
) -> Result<Placed, SceneError> {
    let mut placed = Placed::new();
    for (i, (key, text)) in sets.iter().enumerate() {
        let what = format!("--set {key}={text}");
        let fail =
            |message: String| SceneError::File { path: cx.path.to_string(), message: format!("{what}: {message}") };
        // One byte past the end of the text per `--set`: never a position in the file.
        let at = cx.text.len() + 1 + i;
        let span = at..at + 1;
        let path = resolve(&key_path(key).map_err(&fail)?).map_err(&fail)?;
        let value = DeValue::parse(text)
            .map(|v| v.into_inner())
            .unwrap_or_else(|_| DeValue::String(Cow::Borrowed(text.as_str())));
        let value = respan(value, &span);
        let section = SECTIONS.iter().copied().find(|s| *s == path[0]).expect("resolve checked the section");
        // A section the file lacks starts empty: a table, or a list for `[[lights]]` and
        // `[[objects]]` (which then has no entry to change).
        let root = sections.entry(section).or_insert_with(|| {
            let empty = match section {
                "lights" | "objects" => DeValue::Array(toml::de::DeArray::new()),
                _ => DeValue::Table(DeTable::new()),
            };
            Spanned::new(span.clone(), empty)
        });
        if let Some(name) = path.get(1)
            && matches!(section, "textures" | "materials" | "groups")
        {
            // Named tables are made by the file: a --set changes one, never makes one without its
            // `type`.
            let kind = &section[..section.len() - 1];
            let names: Vec<String> = match root.get_ref() {
                DeValue::Table(t) => t.keys().map(|k| k.get_ref().to_string()).collect(),
                _ => Vec::new(),
            };
            if !names.contains(name) {
                return Err(fail(super::no_such(kind, name, names.iter().map(String::as_str).collect())));
            }
        }
        place(root, &path[1..], value, &span, &path[0]).map_err(&fail)?;
        placed.push((span, what));
    }
    Ok(placed)
}

/// The path in the file's own sections: `integrator.*`, `film.*` and `sampler.*` become the
/// `[render]` keys they stand for; an unknown section or name is an error with a did-you-mean.
fn resolve(path: &[String]) -> Result<Vec<String>, String> {
    let first = path[0].as_str();
    if SECTIONS.contains(&first) {
        if path.len() == 1 {
            return Err(format!("`{first}` is a section: name a key in it, e.g. {first}.KEY=VALUE"));
        }
        return Ok(path.to_vec());
    }
    if first == "parameters" {
        return Err("parameters take their values from -D NAME=VALUE".into());
    }
    let Some((group, keys)) = ALIASES.iter().find(|(g, _)| *g == first) else {
        let known = SECTIONS.iter().copied().chain(ALIASES.iter().map(|(g, _)| *g));
        let hint = closest(first, known).map_or(String::new(), |k| format!(" (did you mean `{k}`?)"));
        return Err(format!(
            "unknown section `{first}`{hint}; expected one of {}, or {} (names for [render] keys)",
            SECTIONS.join(", "),
            ALIASES.iter().map(|(g, _)| *g).collect::<Vec<_>>().join(", ")
        ));
    };
    let key = match path.get(1) {
        Some(k) => k.as_str(),
        None if keys.iter().any(|(k, _)| *k == "type") => "type",
        None => return Err(format!("`{group}` names [render] keys: give one, e.g. {group}.{}", keys[0].0)),
    };
    let Some((_, target)) = keys.iter().find(|(k, _)| *k == key) else {
        let hint =
            closest(key, keys.iter().map(|(k, _)| *k)).map_or(String::new(), |k| format!(" (did you mean `{k}`?)"));
        return Err(format!("unknown key `{key}` of {group}{hint}; {}", describe(group, keys)));
    };
    let mut out = vec!["render".to_string()];
    out.extend(target.split('.').map(str::to_string));
    out.extend(path.iter().skip(2).cloned());
    Ok(out)
}

/// Puts `value` at `path` below `at` (called `name` in messages), making the tables on the way
/// that are missing. A table's key is inserted or replaced (its key keeps the file's position
/// when it has one); a list's entry is picked by its index from 0.
fn place<'a>(
    at: &mut Spanned<DeValue<'a>>,
    path: &[String],
    value: DeValue<'a>,
    span: &Range<usize>,
    name: &str,
) -> Result<(), String> {
    let Some((key, rest)) = path.split_first() else { unreachable!("a section is followed by a key") };
    let here = format!("{name}.{key}");
    match at.get_mut() {
        DeValue::Table(t) => {
            if rest.is_empty() {
                match t.get_mut(key.as_str()) {
                    Some(v) => *v = Spanned::new(span.clone(), value),
                    None => {
                        t.insert(
                            Spanned::new(span.clone(), Cow::Owned(key.clone())),
                            Spanned::new(span.clone(), value),
                        );
                    }
                }
                return Ok(());
            }
            if t.get(key.as_str()).is_none() {
                let empty = Spanned::new(span.clone(), DeValue::Table(DeTable::new()));
                t.insert(Spanned::new(span.clone(), Cow::Owned(key.clone())), empty);
            }
            let next = t.get_mut(key.as_str()).expect("inserted above");
            place(next, rest, value, span, &here)
        }
        DeValue::Array(a) => {
            let n = a.len();
            let Ok(i) = key.parse::<usize>() else {
                return Err(format!("`{name}` is a list: the name after it is an index from 0 ({name}.0...)"));
            };
            let Some(entry) = a.get_mut(i) else {
                return Err(if n == 0 {
                    format!("`{name}` is empty: it has no entry {i}")
                } else {
                    format!("`{name}` has {n} entries (0 to {}): it has no entry {i}", n - 1)
                });
            };
            if rest.is_empty() {
                *entry = Spanned::new(span.clone(), value);
                return Ok(());
            }
            place(entry, rest, value, span, &here)
        }
        other => Err(format!("`{name}` is {}, which has no `{key}`", kind(other))),
    }
}

/// What `group.KEY` stands for, for messages: `integrator.KEY is [render] KEY for max_depth,
/// ...; [render.photon] KEY for photons, ...; integrator.type is [render] integrator`.
fn describe(group: &str, keys: &[(&str, &str)]) -> String {
    let same: Vec<&str> = keys.iter().filter(|(k, t)| k == t).map(|(k, _)| *k).collect();
    let photon: Vec<&str> =
        keys.iter().filter(|(k, t)| t.strip_prefix("photon.") == Some(*k)).map(|(k, _)| *k).collect();
    let mut parts = vec![format!("{group}.KEY is [render] KEY for {}", same.join(", "))];
    if !photon.is_empty() {
        parts.push(format!("[render.photon] KEY for {}", photon.join(", ")));
    }
    for (k, t) in keys.iter().filter(|(k, t)| k != t && t.strip_prefix("photon.") != Some(*k)) {
        parts.push(format!("{group}.{k} is [render] {t}"));
    }
    parts.join("; ")
}

fn kind(v: &DeValue) -> &'static str {
    match v {
        DeValue::Integer(_) | DeValue::Float(_) => "a number",
        DeValue::String(_) => "a text",
        DeValue::Boolean(_) => "true or false",
        DeValue::Datetime(_) => "a date",
        DeValue::Array(_) => "a list",
        DeValue::Table(_) => "a table",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn keys_split_at_the_first_equals_outside_quotes() {
        assert_eq!(parse_set("render.spp=4"), Ok(("render.spp".into(), "4".into())));
        assert_eq!(parse_set("film.filter=tent:radius=1.5"), Ok(("film.filter".into(), "tent:radius=1.5".into())));
        assert_eq!(parse_set("materials.\"a=b\".ior=2"), Ok(("materials.\"a=b\".ior".into(), "2".into())));
        assert_eq!(
            key_path("materials.\"frosted glass\".alpha"),
            Ok(vec!["materials".into(), "frosted glass".into(), "alpha".into()])
        );
        assert_eq!(key_path("objects.0.radius"), Ok(vec!["objects".into(), "0".into(), "radius".into()]));
        for bad in ["render.spp", "=4", "render..spp=4", "render.=4", "a b=1"] {
            assert!(parse_set(bad).is_err(), "{bad}");
        }
    }

    /// Every `integrator.*`, `film.*` and `sampler.*` name stands for a key `[render]` has (a
    /// value of the wrong type is refused as that key's, never as an unknown key), and every
    /// photon option is an `integrator.*` name.
    #[test]
    fn aliases_name_keys_render_has() {
        let scene = "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\n";
        for (group, keys) in ALIASES {
            for (key, _) in *keys {
                let sets = [(format!("{group}.{key}"), "not a value!".to_string())];
                let files = crate::scene::FileBudget::unlimited();
                let e = match super::super::load_toml_str(scene, "a.toml", Path::new("."), &files, &[], &sets) {
                    Ok(_) => panic!("{group}.{key} took text"),
                    Err(e) => e.to_string(),
                };
                assert!(e.contains(&format!("--set {group}.{key}=")) && !e.contains("unknown key"), "{e}");
            }
        }
        // serde lists the photon options in its message about an unknown one.
        let e = toml::from_str::<crate::options::PhotonOptions>("zzz = 1").unwrap_err().to_string();
        let listed: Vec<&str> = e.split('`').skip(3).step_by(2).collect();
        assert!(listed.len() >= 11, "{e}");
        let integrator = ALIASES.iter().find(|(g, _)| *g == "integrator").unwrap().1;
        for key in listed {
            assert!(integrator.contains(&(key, &format!("photon.{key}"))), "integrator.{key} is missing");
        }
    }
}
