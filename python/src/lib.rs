//! `caustic._native`: the Rust half of the Python package. It loads scenes into a [`Scene`]
//! (the scene as read, before options are applied), renders them through the same function the
//! command line renders a file with (`caustic::app::render_scene`), merges partial images and
//! runs the command line itself; `python/caustic/__init__.py` turns its buffers into numpy
//! arrays and gives the functions their Python signatures and docstrings.

mod options;
mod run;

use caustic::app::{AppError, RenderOptions, render_scene, system_memory};
use caustic::film::output::{read_exr, write_image};
use caustic::film::{Film, Image, LAYER_NAMES};
use caustic::math::Color;
use caustic::render::Meter;
use caustic::scene::footprint::Footprint;
use caustic::scene::{FileBudget, LoadOptions, SceneDescription, SceneError as LoadError, SceneFormat};
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyKeyboardInterrupt, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyByteArray, PyBytes, PyDict};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

create_exception!(caustic, CausticError, PyException, "An error caustic reports (as the command line would).");
create_exception!(
    caustic,
    SceneError,
    CausticError,
    "A scene that cannot be loaded or built; `file`, `line`, `column` (None when the error has no \
     place in the file) and `message` say where and what, and str() is the command line's text."
);

/// A scene as read from its file or text, before any option is applied: each render applies its
/// options to a copy and builds that, as `caustic render` does.
#[pyclass(module = "caustic", frozen)]
struct Scene {
    desc: SceneDescription,
    footprint: Footprint,
    load: LoadOptions,
    warnings: Vec<String>,
}

#[pymethods]
impl Scene {
    /// The scene file (or the name given to `load_string`).
    #[getter]
    fn name(&self) -> &str {
        &self.desc.name
    }

    /// The image width the scene asks for.
    #[getter]
    fn width(&self) -> u32 {
        self.desc.width
    }

    /// The image height the scene asks for.
    #[getter]
    fn height(&self) -> u32 {
        self.desc.height
    }

    /// The integrator the scene asks for.
    #[getter]
    fn integrator(&self) -> &'static str {
        self.desc.integrator.kind.name()
    }

    /// Every file the scene was read from: the scene file first, then meshes, textures, includes.
    #[getter]
    fn files(&self) -> Vec<PathBuf> {
        self.desc.files()
    }

    /// What the loader could not render exactly, each `file:line:col: message`.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    fn __repr__(&self) -> String {
        format!(
            "<caustic.Scene '{}' {}x{}, {} integrator>",
            self.desc.name,
            self.desc.width,
            self.desc.height,
            self.desc.integrator.kind.name()
        )
    }
}

/// A scene error as `caustic.SceneError`, its place as attributes.
fn scene_error(py: Python<'_>, e: &LoadError) -> PyErr {
    let (file, line, column) = match e {
        LoadError::At { path, line, column, .. } => (Some(path.clone()), Some(*line), Some(*column)),
        LoadError::File { path, .. } | LoadError::Read { path, .. } => (Some(path.clone()), None, None),
        LoadError::Memory(_) => (None, None, None),
    };
    let err = SceneError::new_err(e.to_string());
    let value = err.value(py);
    // Setting attributes on a fresh exception object fails only if Python is out of memory,
    // and the exception is still the right one without them.
    let _ = value.setattr("file", file);
    let _ = value.setattr("line", line);
    let _ = value.setattr("column", column);
    let _ = value.setattr("message", e.message());
    err
}

fn app_error(py: Python<'_>, e: AppError) -> PyErr {
    match e {
        AppError::Scene(e) => scene_error(py, &e),
        e => CausticError::new_err(e.to_string()),
    }
}

fn scene_of(
    py: Python<'_>,
    desc: Result<SceneDescription, LoadError>,
    files: &FileBudget,
    load: LoadOptions,
) -> PyResult<Scene> {
    match desc {
        Ok(mut desc) => {
            // Said once, at load, rather than at every render of a sweep.
            let warnings = std::mem::take(&mut desc.warnings);
            Ok(Scene { desc, footprint: files.footprint(), load, warnings })
        }
        Err(LoadError::Memory(o)) => Err(app_error(py, AppError::from(LoadError::Memory(o)))),
        Err(e) => Err(scene_error(py, &e)),
    }
}

fn budget(max_memory_mib: Option<u64>) -> FileBudget {
    FileBudget::new(max_memory_mib.map_or_else(|| system_memory() / 2, |m| m.saturating_mul(1 << 20)))
}

#[pyfunction]
#[pyo3(signature = (path, defines, strict = false, max_memory = None, sets = Vec::new()))]
fn load_file(
    py: Python<'_>,
    path: PathBuf,
    defines: Vec<(String, String)>,
    strict: bool,
    max_memory: Option<u64>,
    sets: Vec<(String, String)>,
) -> PyResult<Scene> {
    let load = LoadOptions { defines, sets, strict };
    let files = budget(max_memory);
    let desc = py.detach(|| caustic::scene::load_scene_within(&path, &load, &files));
    scene_of(py, desc, &files, load)
}

#[pyfunction]
#[pyo3(signature = (text, format, name, base, defines, strict = false, max_memory = None, sets = Vec::new()))]
#[allow(clippy::too_many_arguments)]
fn load_string(
    py: Python<'_>,
    text: &str,
    format: &str,
    name: &str,
    base: PathBuf,
    defines: Vec<(String, String)>,
    strict: bool,
    max_memory: Option<u64>,
    sets: Vec<(String, String)>,
) -> PyResult<Scene> {
    let format = match format {
        "toml" => SceneFormat::Toml,
        "mitsuba" | "xml" => SceneFormat::Mitsuba,
        other => return Err(PyValueError::new_err(format!("format must be \"mitsuba\" or \"toml\", not {other:?}"))),
    };
    let load = LoadOptions { defines, sets, strict };
    let files = budget(max_memory);
    let desc = py.detach(|| caustic::scene::load_scene_text_within(text, format, name, &base, &load, &files));
    scene_of(py, desc, &files, load)
}

/// An image's pixels as native-endian f32 bytes, row by row, three channels each.
fn image_bytes<'py>(py: Python<'py>, img: &Image) -> (u32, u32, Bound<'py, PyByteArray>) {
    let mut bytes = Vec::with_capacity(img.pixels.len() * 12);
    for p in &img.pixels {
        for v in p.to_array() {
            bytes.extend_from_slice(&v.to_ne_bytes());
        }
    }
    (img.width, img.height, PyByteArray::new(py, &bytes))
}

/// The picture and, when it has them, its layers, by name (`image`, `direct`, ...).
fn images<'py>(py: Python<'py>, image: &Image, layers: &[Image]) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    out.set_item("image", image_bytes(py, image))?;
    for (img, name) in layers.iter().zip(LAYER_NAMES) {
        out.set_item(name, image_bytes(py, img))?;
    }
    Ok(out)
}

#[pyfunction]
#[pyo3(signature = (scene, options, time = None, threads = None, layers = false, max_memory = None, progress = None, output = None, shard = None))]
#[allow(clippy::too_many_arguments)]
fn render<'py>(
    py: Python<'py>,
    scene: &Bound<'py, Scene>,
    options: &Bound<'py, PyDict>,
    time: Option<f64>,
    threads: Option<usize>,
    layers: bool,
    max_memory: Option<u64>,
    progress: Option<Bound<'py, PyAny>>,
    output: Option<PathBuf>,
    shard: Option<String>,
) -> PyResult<Option<Bound<'py, PyDict>>> {
    let function = if shard.is_some() { "render_shard" } else { "render" };
    let overrides = options::options(function, options)?;
    let time_limit = match time {
        None => None,
        Some(s) if s.is_finite() && s > 0.0 && s < 1e9 => Some(Duration::from_secs_f64(s)),
        Some(s) => return Err(PyValueError::new_err(format!("time must be a positive number of seconds, got {s}"))),
    };
    let shard =
        shard.map(|s| s.parse().map_err(|e: String| PyValueError::new_err(format!("shard: {e}")))).transpose()?;
    let scene = scene.get();
    let opts = RenderOptions {
        scene: PathBuf::from(&scene.desc.name),
        output,
        overrides,
        load: scene.load.clone(),
        threads,
        time_limit,
        checkpoint: None,
        quiet: true,
        layers,
        max_memory: max_memory.map(|m| m.saturating_mul(1 << 20)),
        shard,
    };
    let cancel = AtomicBool::new(false);
    let meter = Meter::default();
    let footprint = scene.footprint.clone();
    let result = run::run(py, progress.as_ref(), &meter, &cancel, || {
        render_scene(&scene.desc, footprint, &opts, &cancel, Some(&meter))
    })?;
    let summary = result.map_err(|e| app_error(py, e))?;
    match summary.render {
        Some(out) if out.stats.interrupted => Err(PyKeyboardInterrupt::new_err("the render was stopped")),
        Some(out) => Ok(Some(images(py, &out.image, &out.layers)?)),
        None => Ok(None),
    }
}

#[pyfunction]
#[pyo3(signature = (parts, allow_partial = false))]
fn merge<'py>(py: Python<'py>, parts: Vec<PathBuf>, allow_partial: bool) -> PyResult<Bound<'py, PyDict>> {
    let merged = py.detach(|| caustic::farm::merge::merge(&parts, allow_partial));
    let (film, _report): (Film, _) = merged.map_err(|e| CausticError::new_err(e.to_string()))?;
    let layers: Vec<Image> =
        if film.has_layers() { (0..LAYER_NAMES.len()).map(|k| film.layer_image(k)).collect() } else { Vec::new() };
    images(py, &film.image(), &layers)
}

#[pyfunction]
fn write(py: Python<'_>, path: PathBuf, width: u32, height: u32, pixels: &Bound<'_, PyBytes>) -> PyResult<()> {
    let bytes = pixels.as_bytes();
    if bytes.len() != width as usize * height as usize * 12 {
        return Err(PyValueError::new_err("the pixel buffer does not hold width x height RGB float32 values"));
    }
    let f = |k: usize| f32::from_ne_bytes(bytes[4 * k..4 * k + 4].try_into().expect("four bytes"));
    let pixels =
        (0..width as usize * height as usize).map(|p| Color::new(f(3 * p), f(3 * p + 1), f(3 * p + 2))).collect();
    let img = Image { width, height, pixels };
    py.detach(|| write_image(&img, &path)).map_err(|e| CausticError::new_err(e.to_string()))
}

#[pyfunction]
fn read<'py>(py: Python<'py>, path: PathBuf) -> PyResult<(u32, u32, Bound<'py, PyByteArray>)> {
    if !path.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr")) {
        return Err(PyValueError::new_err(format!("{}: caustic.read reads OpenEXR (.exr) files", path.display())));
    }
    let img = py.detach(|| read_exr(&path)).map_err(|e| CausticError::new_err(e.to_string()))?;
    Ok(image_bytes(py, &img))
}

/// The command line (`caustic ARGS...`); returns its exit status.
#[pyfunction]
fn main(py: Python<'_>, argv: Vec<String>) -> u8 {
    py.detach(|| caustic::cli::run(argv))
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("CausticError", py.get_type::<CausticError>())?;
    m.add("SceneError", py.get_type::<SceneError>())?;
    m.add_class::<Scene>()?;
    m.add_function(wrap_pyfunction!(load_file, m)?)?;
    m.add_function(wrap_pyfunction!(load_string, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(merge, m)?)?;
    m.add_function(wrap_pyfunction!(write, m)?)?;
    m.add_function(wrap_pyfunction!(read, m)?)?;
    m.add_function(wrap_pyfunction!(main, m)?)?;
    m.add("OPTIONS", options::option_names())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
