//! Python keyword arguments to the one options type, `caustic::options::Options`: the names are
//! those clap gives the command line's flags (`--spp-axis` is `spp_axis`, `--no-antialias` is
//! `antialias=False`), and the values are checked by the type's own serde rules (the rules a
//! TOML `[render]` table is read with), so no option is listed here by hand.

use caustic::options::{Options, PhotonOptions};
use clap::{Args, Command};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyString};
use serde::Deserialize;

/// The option names: every field of `Options` (those of `PhotonOptions` included, which serde
/// reads from a nested `photon` table) as clap names its arguments.
struct Names {
    all: Vec<String>,
    photon: Vec<String>,
}

fn ids(command: Command) -> Vec<String> {
    command.get_arguments().map(|a| a.get_id().as_str().to_string()).collect()
}

fn names() -> Names {
    Names {
        all: ids(Options::augment_args(Command::new("options"))),
        photon: ids(PhotonOptions::augment_args(Command::new("photon"))),
    }
}

/// Every option name, for `caustic.OPTIONS` and the stubs.
pub fn option_names() -> Vec<String> {
    names().all
}

/// Edit distance between two names, for "did you mean".
fn distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let next = (diagonal + usize::from(ca != cb)).min(row[j] + 1).min(row[j + 1] + 1);
            diagonal = row[j + 1];
            row[j + 1] = next;
        }
    }
    row[b.len()]
}

/// The TypeError for an option that does not exist, naming the nearest that does.
fn unknown(function: &str, name: &str, known: &[String]) -> PyErr {
    let nearest = known.iter().min_by_key(|k| distance(name, k));
    match nearest {
        Some(k) if distance(name, k) <= (name.len() / 3).max(2) || k.contains(name) || name.contains(k.as_str()) => {
            let hint = if k == "antialias" { "antialias=False".to_string() } else { format!("'{k}'") };
            PyTypeError::new_err(format!("{function}() got an unknown option '{name}'; did you mean {hint}?"))
        }
        _ => PyTypeError::new_err(format!(
            "{function}() got an unknown option '{name}' (the options are: {})",
            known.join(", ")
        )),
    }
}

/// A Python value as a TOML value: `None` when the value is `None` (the scene's own value).
fn value(name: &str, v: &Bound<'_, PyAny>) -> PyResult<Option<toml::Value>> {
    if v.is_none() {
        return Ok(None);
    }
    if let Ok(b) = v.cast::<PyBool>() {
        return Ok(Some(toml::Value::Boolean(b.is_true())));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(Some(toml::Value::String(v.extract::<String>()?)));
    }
    // Integers first (numpy's too, through __index__), then anything with __float__.
    if v.hasattr("__index__")? {
        return match v.extract::<i64>() {
            Ok(i) => Ok(Some(toml::Value::Integer(i))),
            Err(_) => Err(PyValueError::new_err(format!("option {name}: {v} is too large"))),
        };
    }
    if let Ok(f) = v.extract::<f64>() {
        return Ok(Some(toml::Value::Float(f)));
    }
    Err(PyTypeError::new_err(format!(
        "option {name}: expected a number, a string or True/False, got {}",
        v.get_type().name()?
    )))
}

/// Reads `given` (option name to value) into `Options`, as `function` was called.
pub fn options(function: &str, given: &Bound<'_, PyDict>) -> PyResult<Options> {
    let names = names();
    let mut top = toml::Table::new();
    let mut photon = toml::Table::new();
    for (k, v) in given.iter() {
        let name = k.extract::<String>()?.replace('-', "_");
        if !names.all.contains(&name) {
            return Err(unknown(function, &name, &names.all));
        }
        let Some(v) = value(&name, &v)? else { continue };
        // Checked one at a time first, so that a bad value's message names its option.
        let alone = if names.photon.contains(&name) {
            photon.insert(name.clone(), v.clone());
            toml::Table::from_iter([(
                "photon".to_string(),
                toml::Value::Table(toml::Table::from_iter([(name.clone(), v)])),
            )])
        } else {
            top.insert(name.clone(), v.clone());
            toml::Table::from_iter([(name.clone(), v)])
        };
        if let Err(e) = Options::deserialize(toml::Value::Table(alone)) {
            return Err(PyValueError::new_err(format!("option {name}: {}", e.message().trim())));
        }
    }
    if !photon.is_empty() {
        top.insert("photon".into(), toml::Value::Table(photon));
    }
    Options::deserialize(toml::Value::Table(top)).map_err(|e| PyValueError::new_err(e.message().trim().to_string()))
}
