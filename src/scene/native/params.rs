//! `$name` parameters of a TOML scene, as Mitsuba's XML has them: `[parameters]` gives each a
//! default, `-D name=value` on the command line replaces it, and a string value elsewhere in
//! the file that is exactly `"$name"` becomes the parameter's value with its TOML type (so
//! `spp = "$spp"` is a whole number); a `$name` inside a longer string is replaced by the
//! value's text (`file = "meshes/$mesh.ply"`). The values then go through the same checks as
//! any written in the file, and an error about one names the parameter.
//!
//! A `-D` value is read as a TOML value (`4`, `1.5`, `[1, 0, 0]`, `true`), or as text when it is
//! not one (`-D mesh=bunny`); it must have the type of the parameter's default (a number for a
//! number, a list for a list); the key it fills then checks it as any value written there. A `-D` the scene never refers to is an error listing the
//! scene's parameters with a did-you-mean, as Mitsuba refuses unused parameters.

use super::Cx;
use crate::scene::SceneError;
use std::collections::HashMap;
use std::ops::Range;
use toml::Spanned;
use toml::de::DeValue;

/// Where a substituted value came from, for messages: the value's span in the file and the
/// parameter's name.
pub(super) type Substituted = Vec<(Range<usize>, String)>;

/// Replaces every `$name` in `sections` (all but `parameters`, which it reads the defaults
/// from) by its value, `defines` winning over the defaults. Returns where values were put.
pub(super) fn substitute<'a>(
    cx: &Cx,
    sections: &mut HashMap<&'static str, Spanned<DeValue<'a>>>,
    defines: &'a [(String, String)],
) -> Result<Substituted, SceneError> {
    let mut values: HashMap<String, Spanned<DeValue<'a>>> = HashMap::new();
    if let Some(p) = sections.remove("parameters") {
        let span = p.span();
        let DeValue::Table(table) = p.into_inner() else {
            return Err(cx.at(span, "[parameters] must be a table of name = default value"));
        };
        for (k, v) in table {
            let name: &str = k.get_ref();
            if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
                return Err(cx.at(k.span(), format!("parameter name `{name}` must be letters, digits and _")));
            }
            values.insert(name.to_string(), v);
        }
    }
    let declared: Vec<String> = values.keys().cloned().collect();
    for (name, text) in defines {
        // A TOML value, or the text itself when it is not one (`-D mesh=bunny`).
        let given = DeValue::parse(text)
            .map(|v| v.into_inner())
            .unwrap_or_else(|_| DeValue::String(std::borrow::Cow::Borrowed(text.as_str())));
        if let Some(default) = values.get(name)
            && let Some(expected) = mismatch(default.get_ref(), &given)
        {
            let line = cx.text[..default.span().start.min(cx.text.len())].matches('\n').count() + 1;
            return Err(SceneError::File {
                path: cx.path.to_string(),
                message: format!(
                    "-D {name}={text}: `${name}` is {expected} in this scene (its default, line {line}), found {}",
                    describe(&given)
                ),
            });
        }
        values.insert(name.clone(), Spanned::new(0..0, given));
    }
    let mut used: Vec<String> = Vec::new();
    let mut substituted = Substituted::new();
    for v in sections.values_mut() {
        walk(cx, v, &values, &mut used, &mut substituted)?;
    }
    let unused: Vec<&str> = defines.iter().map(|(k, _)| k.as_str()).filter(|k| !used.iter().any(|u| u == k)).collect();
    if !unused.is_empty() {
        let mut known: Vec<&str> = declared.iter().map(String::as_str).chain(used.iter().map(String::as_str)).collect();
        known.sort();
        known.dedup();
        let list = |v: &[&str]| v.iter().map(|k| format!("`{k}`")).collect::<Vec<_>>().join(", ");
        let hint = unused
            .iter()
            .filter_map(|u| {
                crate::scene::mitsuba::closest(u, known.iter().copied())
                    .map(|k| format!(" (did you mean `{k}` for `{u}`?)"))
            })
            .collect::<String>();
        return Err(SceneError::File {
            path: cx.path.to_string(),
            message: format!(
                "-D {} is not a parameter of this scene{hint}; its parameters are: {} (a TOML scene declares them in [parameters] and uses them as \"$name\")",
                list(&unused),
                if known.is_empty() { "none".to_string() } else { list(&known) }
            ),
        });
    }
    Ok(substituted)
}

/// Substitutes the parameters in `v` and everything below it.
fn walk<'a>(
    cx: &Cx,
    v: &mut Spanned<DeValue<'a>>,
    values: &HashMap<String, Spanned<DeValue<'a>>>,
    used: &mut Vec<String>,
    substituted: &mut Substituted,
) -> Result<(), SceneError> {
    let span = v.span();
    match v.get_mut() {
        DeValue::Array(a) => {
            for e in a.iter_mut() {
                walk(cx, e, values, used, substituted)?;
            }
        }
        DeValue::Table(t) => {
            for (_, e) in t.iter_mut() {
                walk(cx, e, values, used, substituted)?;
            }
        }
        DeValue::String(s) if s.contains('$') => {
            let text = s.to_string();
            let value = |name: &str| {
                values.get(name).map(|v| v.get_ref().clone()).ok_or_else(|| {
                    cx.at(
                        span.clone(),
                        format!("parameter `${name}` has no value: give it a default in [parameters] or pass -D {name}=VALUE"),
                    )
                })
            };
            // The whole string one parameter: its value, with its type.
            if let Some(name) = text.strip_prefix('$')
                && !name.is_empty()
                && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
            {
                let new = value(name)?;
                used.push(name.to_string());
                substituted.push((span.clone(), name.to_string()));
                let at = span.clone();
                *v = Spanned::new(span, respan(new, &at));
                return Ok(());
            }
            let mut out = String::new();
            let mut rest = text.as_str();
            while let Some((before, name, after)) = crate::scene::mitsuba::next_parameter(rest) {
                out.push_str(before);
                if name.is_empty() {
                    out.push('$');
                } else {
                    let new = value(name)?;
                    used.push(name.to_string());
                    match &new {
                        DeValue::String(s) => out.push_str(s),
                        DeValue::Integer(i) => out.push_str(&i.to_string()),
                        DeValue::Float(f) => out.push_str(&f.to_string()),
                        DeValue::Boolean(b) => out.push_str(&b.to_string()),
                        other => {
                            return Err(cx.at(
                                span.clone(),
                                format!("parameter `${name}` is {} and cannot be part of a text", describe(other)),
                            ));
                        }
                    }
                    substituted.push((span.clone(), name.to_string()));
                }
                rest = after;
            }
            out.push_str(rest);
            *v = Spanned::new(span, DeValue::String(out.into()));
        }
        _ => {}
    }
    Ok(())
}

/// `v` with every position in it set to `span` (the use site), so errors point there.
pub(super) fn respan<'a>(v: DeValue<'a>, span: &Range<usize>) -> DeValue<'a> {
    match v {
        DeValue::Array(a) => {
            let mut out = toml::de::DeArray::new();
            for e in a {
                out.push(Spanned::new(span.clone(), respan(e.into_inner(), span)));
            }
            DeValue::Array(out)
        }
        DeValue::Table(t) => {
            let mut out = toml::de::DeTable::new();
            for (k, e) in t {
                out.insert(
                    Spanned::new(span.clone(), k.into_inner()),
                    Spanned::new(span.clone(), respan(e.into_inner(), span)),
                );
            }
            DeValue::Table(out)
        }
        other => other,
    }
}

/// What `given` should have been, when its type is not the default's. Numbers are numbers
/// whichever way written (a default of `1` for a radius takes `2.5`); whether one must be whole
/// is the key's to say where it is used.
fn mismatch(default: &DeValue, given: &DeValue) -> Option<&'static str> {
    let ok = match default {
        DeValue::Integer(_) | DeValue::Float(_) => matches!(given, DeValue::Integer(_) | DeValue::Float(_)),
        DeValue::String(_) => matches!(given, DeValue::String(_)),
        DeValue::Boolean(_) => matches!(given, DeValue::Boolean(_)),
        DeValue::Array(_) => matches!(given, DeValue::Array(_)),
        DeValue::Table(_) => matches!(given, DeValue::Table(_)),
        DeValue::Datetime(_) => matches!(given, DeValue::Datetime(_)),
    };
    (!ok).then(|| describe_kind(default))
}

fn describe_kind(v: &DeValue) -> &'static str {
    match v {
        DeValue::Integer(_) | DeValue::Float(_) => "a number",
        DeValue::String(_) => "a text",
        DeValue::Boolean(_) => "true or false",
        DeValue::Array(_) => "a list",
        DeValue::Table(_) => "a table",
        DeValue::Datetime(_) => "a date",
    }
}

fn describe(v: &DeValue) -> String {
    match v {
        DeValue::String(s) => format!("the text \"{s}\""),
        DeValue::Integer(i) => format!("`{i}`"),
        DeValue::Float(f) => format!("`{f}`"),
        DeValue::Boolean(b) => format!("`{b}`"),
        other => describe_kind(other).to_string(),
    }
}
