//! `--set KEY=VALUE` on a Mitsuba scene: KEY names elements from `<scene>` down, then one of
//! their properties, with Mitsuba's own names: `integrator.max_depth=4` (the `<integrator>`'s
//! `max_depth`), `sensor.film.width=320`, `sensor.sampler.sample_count=64`, or from an object's
//! id, `glass.int_ior=1.6` (`<bsdf id="glass">`). The first name is an id or the tag of a child of
//! `<scene>` (the first with that tag); each further one is the tag, id or `name` of a nested
//! object.
//!
//! The property element is put into the tree before anything is read from it, so the value is
//! read and checked as one written in the file. A property the element has keeps its type
//! (`<float>`, `<rgb>`, ...) and gets the value; one it lacks is added as `<integer>`, `<float>`,
//! `<boolean>`, `<rgb>` (three numbers) or `<string>`, from the value's form. Each `--set` is a
//! source of its own named `--set KEY=VALUE`, so an error about its value names it instead of a
//! line, and a property nothing reads (a misspelt name) is an error, not the warning a file's
//! unread property gets: the user asked for it.

use super::xml::{Attr, El, Resolver, Src};
use crate::scene::SceneError;

/// Puts every `--set` of `sets` into the tree under `root`, each as a source of its own in
/// `srcs` (after the files).
pub(super) fn apply(root: &mut El, srcs: &mut Vec<Src>, sets: &[(String, String)]) -> Result<(), SceneError> {
    let scene = srcs[0].name.clone();
    for (key, value) in sets {
        let what = format!("--set {key}={value}");
        let fail = |message: String| SceneError::File { path: scene.clone(), message: format!("{what}: {message}") };
        let path = crate::scene::native::key_path(key).map_err(&fail)?;
        let Some((property, elements)) = path.split_last().filter(|(_, e)| !e.is_empty()) else {
            return Err(fail(format!(
                "name an element and one of its properties, e.g. integrator.{key} or sensor.film.{key}"
            )));
        };
        if property == "type" {
            return Err(fail(
                "`type` is the element's plugin, not a property: --set changes properties (a plugin can be chosen with type=\"$name\" in the file and -D name=...)".into(),
            ));
        }
        let src = srcs.len();
        let el = find(root, elements).map_err(&fail)?;
        let span = 0..value.len();
        let at = |attrs: Vec<Attr>, tag: &str| El {
            tag: tag.to_string(),
            attrs,
            children: Vec::new(),
            src,
            span: span.clone(),
        };
        let name_attr = || Attr { name: "name".into(), value: property.clone(), span: 0..0 };
        let value_attr = || Attr { name: "value".into(), value: value.clone(), span: span.clone() };
        let existing =
            el.children.iter().position(|c| c.attrs.iter().any(|a| a.name == "name" && a.value == *property));
        match existing {
            Some(i) => {
                let old = &el.children[i];
                if !super::props::PROPERTY_TAGS.contains(&old.tag.as_str()) {
                    return Err(fail(format!(
                        "`{property}` is a nested <{}>, not a property: name one of its properties ({key}.NAME)",
                        old.tag
                    )));
                }
                if old.tag == "transform" {
                    return Err(fail(format!("`{property}` is a <transform>, which takes no single value")));
                }
                let tag = old.tag.clone();
                el.children[i] = at(vec![name_attr(), value_attr()], &tag);
            }
            None => {
                if let Some(nested) = el.children.iter().find(|c| c.tag == *property) {
                    return Err(fail(format!(
                        "`{property}` is a nested <{}>, not a property: name one of its properties ({key}.NAME)",
                        nested.tag
                    )));
                }
                let tag = inferred_tag(value);
                el.children.push(at(vec![name_attr(), value_attr()], tag));
            }
        }
        srcs.push(Src { name: what, text: value.clone(), resolver: Resolver::default(), from_set: true });
    }
    Ok(())
}

/// The element `names` leads to from `<scene>`.
fn find<'e>(root: &'e mut El, names: &[String]) -> Result<&'e mut El, String> {
    let objects = super::props::OBJECT_TAGS;
    let (first, rest) = names.split_first().expect("at least one element name");
    let mut el = match find_id(root, first) {
        Some(path) => walk(root, &path),
        None => {
            let Some(i) = root.children.iter().position(|c| c.tag == *first && objects.contains(&c.tag.as_str()))
            else {
                let mut tags: Vec<&str> =
                    root.children.iter().map(|c| c.tag.as_str()).filter(|t| objects.contains(t)).collect();
                tags.sort();
                tags.dedup();
                let hint = super::props::closest(first, tags.iter().copied())
                    .map_or(String::new(), |k| format!(" (did you mean `{k}`?)"));
                return Err(format!(
                    "the scene has no element `{first}`{hint}: the first name is an object's id or the tag of an element of <scene> ({})",
                    tags.join(", ")
                ));
            };
            &mut root.children[i]
        }
    };
    let mut so_far = first.clone();
    for name in rest {
        let attr = |c: &El, a: &str| c.attrs.iter().any(|x| x.name == a && x.value == *name);
        let Some(i) = el
            .children
            .iter()
            .position(|c| objects.contains(&c.tag.as_str()) && (c.tag == *name || attr(c, "id") || attr(c, "name")))
        else {
            let nested: Vec<&str> =
                el.children.iter().map(|c| c.tag.as_str()).filter(|t| objects.contains(t)).collect();
            let hint = super::props::closest(name, nested.iter().copied())
                .map_or(String::new(), |k| format!(" (did you mean `{k}`?)"));
            return Err(format!(
                "<{}> `{so_far}` has no nested `{name}`{hint} ({})",
                el.tag,
                if nested.is_empty() { "it has none".to_string() } else { format!("it has: {}", nested.join(", ")) }
            ));
        };
        el = &mut el.children[i];
        so_far = format!("{so_far}.{name}");
    }
    Ok(el)
}

/// The child indices leading from `el` to the object whose `id` is `id`.
fn find_id(el: &El, id: &str) -> Option<Vec<usize>> {
    for (i, c) in el.children.iter().enumerate() {
        if super::props::OBJECT_TAGS.contains(&c.tag.as_str())
            && c.attrs.iter().any(|a| a.name == "id" && a.value == id)
        {
            return Some(vec![i]);
        }
        if let Some(mut path) = find_id(c, id) {
            path.insert(0, i);
            return Some(path);
        }
    }
    None
}

fn walk<'e>(mut el: &'e mut El, path: &[usize]) -> &'e mut El {
    for &i in path {
        el = &mut el.children[i];
    }
    el
}

/// The property tag for a value the element did not have: its form says what it is.
fn inferred_tag(value: &str) -> &'static str {
    let v = value.trim();
    let numbers: Vec<&str> = v.split(|c: char| c == ',' || c.is_whitespace()).filter(|t| !t.is_empty()).collect();
    let number = |t: &str| t.parse::<f64>().is_ok_and(f64::is_finite);
    if v.parse::<i64>().is_ok() {
        "integer"
    } else if number(v) {
        "float"
    } else if v.eq_ignore_ascii_case("true") || v.eq_ignore_ascii_case("false") {
        "boolean"
    } else if numbers.len() == 3 && numbers.iter().all(|t| number(t)) {
        "rgb"
    } else {
        "string"
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_new_propertys_type_follows_its_value() {
        for (v, tag) in [
            ("4", "integer"),
            ("-1", "integer"),
            ("1.6", "float"),
            ("1e-3", "float"),
            ("true", "boolean"),
            ("0.5, 0.2, 0.1", "rgb"),
            ("0.5 0.2 0.1", "rgb"),
            ("gaussian", "string"),
            ("nan", "string"),
        ] {
            assert_eq!(super::inferred_tag(v), tag, "{v}");
        }
    }
}
