//! Mitsuba 3 scene import: reads a scene written in Mitsuba's XML format into the same
//! [`SceneDescription`] the TOML loader produces, so any of our integrators can render it.
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
//! that remembers where each element and attribute came from (`xml`), and the scene is then
//! built from that tree with `$name` parameters substituted and `<ref>`s resolved on the way
//! (`props`), one file per kind of object: `bsdf`, `shapes`, `emitters`, `sensor`, `transform`.

mod bsdf;
mod emitters;
mod media;
mod plugins;
mod props;
mod sensor;
mod set;
mod shapes;
mod spectrum;
mod texture;
mod transform;
mod xml;

use super::SceneError;
use super::builder::SceneBuilder;
use super::desc::{IntegratorDesc, LoadOptions, SceneDescription};
use super::footprint::{FileBudget, FileKind};
use crate::options::IntegratorKind;
use plugins::PluginKind;
use props::Cx;
pub(crate) use props::{closest, next_parameter};
use std::collections::HashMap;
use std::path::Path;
use xml::{El, Resolver, Src};

/// Loads a Mitsuba 3 XML scene file, reporting it and every file it reads to `files` before
/// reading it. Its warnings are in the description's `warnings`.
pub fn load_mitsuba(path: &Path, options: &LoadOptions, files: &FileBudget) -> Result<SceneDescription, SceneError> {
    files.open(path, FileKind::Scene)?;
    let text = std::fs::read_to_string(path)
        .map_err(|source| SceneError::Read { path: path.display().to_string(), source })?;
    let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
    load_mitsuba_text(&text, &path.display().to_string(), &base, options, files)
}

/// Loads a Mitsuba scene from `text`; `name` is used in messages, and files (meshes, includes)
/// resolve against `base`.
pub fn load_mitsuba_str(
    text: &str,
    name: &str,
    base: &Path,
    options: &LoadOptions,
) -> Result<SceneDescription, SceneError> {
    load_mitsuba_text(text, name, base, options, &FileBudget::unlimited())
}

/// `load_mitsuba_str` reporting every file it reads (includes, meshes, images) to `files`.
pub fn load_mitsuba_text(
    text: &str,
    name: &str,
    base: &Path,
    options: &LoadOptions,
    files: &FileBudget,
) -> Result<SceneDescription, SceneError> {
    let mut srcs = vec![Src {
        name: name.to_string(),
        text: text.to_string(),
        resolver: Resolver::for_scene(base),
        from_set: false,
    }];
    let mut root = xml::parse_source(&mut srcs, 0, 0, files)?;
    set::apply(&mut root, &mut srcs, &options.sets)?;
    let root = root;
    let mut cx = Cx {
        srcs: &srcs,
        defines: HashMap::new(),
        ids: HashMap::new(),
        warnings: Vec::new(),
        strict: options.strict,
        aovs: Default::default(),
        files,
        given_spectrum: None,
        bsdf_given: crate::material::GivenSpectra::NONE,
    };
    for (k, v) in &options.defines {
        cx.defines.insert(k.clone(), v.clone());
    }
    check_defines_used(&root, &srcs, options)?;
    let mut desc = cx.build(&root)?;
    desc.warnings = cx.warnings;
    Ok(desc)
}

/// A `-D name=value` that no `$name` of the scene (its includes too) refers to is an error
/// listing the scene's parameters, as Mitsuba refuses "unused parameters": a misspelt name would
/// otherwise render with the default without a word.
fn check_defines_used(root: &El, srcs: &[Src], options: &LoadOptions) -> Result<(), SceneError> {
    if options.defines.is_empty() {
        return Ok(());
    }
    let mut referenced: Vec<String> = Vec::new();
    let mut stack = vec![root];
    while let Some(el) = stack.pop() {
        for a in &el.attrs {
            let mut rest = a.value.as_str();
            while let Some((_, key, after)) = props::next_parameter(rest) {
                referenced.push(key.to_string());
                rest = after;
            }
        }
        stack.extend(el.children.iter());
    }
    referenced.sort();
    referenced.dedup();
    let unused: Vec<&str> =
        options.defines.iter().map(|(k, _)| k.as_str()).filter(|k| !referenced.iter().any(|r| r == k)).collect();
    if unused.is_empty() {
        return Ok(());
    }
    let list = |v: &[&str]| v.iter().map(|k| format!("`{k}`")).collect::<Vec<_>>().join(", ");
    let known: Vec<&str> = referenced.iter().map(String::as_str).filter(|r| !r.is_empty()).collect();
    let hint = unused
        .iter()
        .filter_map(|u| props::closest(u, known.iter().copied()).map(|k| format!(" (did you mean `{k}` for `{u}`?)")))
        .collect::<String>();
    let message = format!(
        "-D {} is not a parameter of this scene{hint}; its parameters are: {}",
        list(&unused),
        if known.is_empty() { "none".to_string() } else { list(&known) }
    );
    Err(SceneError::File { path: srcs[0].name.clone(), message })
}

/// Mitsuba's `max_depth` and the element that gave it.
type Depth<'a> = (i64, &'a El);

/// The state while the scene's objects are read.
struct Build {
    geometry: SceneBuilder,
    /// Material index of each `<bsdf>` element already built (by address).
    bsdf_cache: HashMap<usize, u32>,
    /// Texture index of each `<texture>` element already built (by address).
    texture_cache: HashMap<usize, u32>,
    /// Images read so far, by file and decoding (`raw`), shared between textures.
    images: HashMap<(std::path::PathBuf, bool), std::sync::Arc<crate::texture::image::TexImage>>,
    default_material: Option<u32>,
    /// Black diffuse, the default BSDF of an emitting shape.
    default_emitter_material: Option<u32>,
    /// Group index of each `shapegroup` element already built (by address).
    group_cache: HashMap<usize, u32>,
    /// Medium index of each `<medium>` element already built (by address).
    medium_cache: HashMap<usize, u32>,
}

impl<'a> Cx<'a> {
    fn build(&mut self, root: &'a El) -> Result<SceneDescription, SceneError> {
        self.check_version(root)?;
        self.index(root)?;
        let mut b = Build {
            geometry: SceneBuilder::with_files(self.files.clone()),
            bsdf_cache: HashMap::new(),
            texture_cache: HashMap::new(),
            images: HashMap::new(),
            default_material: None,
            default_emitter_material: None,
            group_cache: HashMap::new(),
            medium_cache: HashMap::new(),
        };
        let mut sensor: Option<&'a El> = None;
        let mut integrator: Option<&'a El> = None;
        for child in &root.children {
            match child.tag.as_str() {
                // Read with the XML: `<path>` folders are in the resolver already.
                "default" | "path" => {}
                "shape" => self.shape(child, &mut b)?,
                "emitter" => self.emitter(child, &mut b)?,
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
                // Media are used through references (from shapes and the sensor); an unreferenced
                // one is built anyway, so that its errors are reported.
                "medium" => {
                    if self.attr(child, "id")?.is_none() {
                        self.warn(child, "a top-level <medium> without an id is never used")?;
                    }
                    self.medium(child, &mut b)?;
                }
                "phase" | "volume" => {
                    let kind = self.attr(child, "type")?.map_or(String::new(), |t| t.0);
                    let plugins = if child.tag == "phase" { PluginKind::Phase } else { PluginKind::Volume };
                    if let Some(message) = plugins::unknown(plugins, &kind) {
                        return Err(self.err(child, message));
                    }
                    if self.attr(child, "id")?.is_none() {
                        self.warn(child, format!("a top-level <{}> without an id is never used", child.tag))?;
                    }
                }
                other => {
                    return Err(self.err(
                        child,
                        format!("unknown element <{other}> in <scene>; expected shape, bsdf, emitter, sensor, integrator, texture, default, path or include"),
                    ));
                }
            }
        }
        let (kind, depth) = match integrator {
            Some(el) => self.integrator(el)?,
            None => (IntegratorKind::Path, None),
        };
        let max_depth = self.caustic_max_depth(depth)?;
        let sensor = self.sensor(sensor, root)?;
        if let Some(el) = sensor.medium {
            let m = self.medium(el, &mut b)?;
            b.geometry.set_camera_medium(m);
        }
        Ok(SceneDescription {
            name: self.srcs[0].name.clone(),
            geometry: b.geometry,
            camera: sensor.camera,
            width: sensor.width,
            height: sensor.height,
            film: super::desc::FilmDesc { aovs: std::mem::take(&mut self.aovs), ..sensor.film },
            sampler: sensor.sampler,
            integrator: IntegratorDesc { kind, max_depth, ..IntegratorDesc::default() },
            warnings: Vec::new(),
        })
    }

    fn check_version(&mut self, root: &'a El) -> Result<(), SceneError> {
        let Some((v, span)) = self.attr(root, "version")? else {
            return Err(self.err(root, "<scene> needs a `version` attribute, e.g. version=\"3.0.0\""));
        };
        match v.split('.').next().and_then(|m| m.trim().parse::<u32>().ok()) {
            None => Err(self.err_span(root, span, format!("expected a version such as 3.0.0, found `{v}`"))),
            Some(m) if m < 2 => self.warn(root, format!("scene version {v} is older than Mitsuba 2: names such as toWorld or intIOR are not recognised; upgrade the file with Mitsuba's converter")),
            _ => Ok(()),
        }
    }

    /// Our depth limit for Mitsuba's `max_depth`. Mitsuba counts the segments of a path from
    /// the camera (1 shows only emitters seen directly, 2 adds direct lighting, -1 is
    /// unlimited); caustic counts its bounces (0 = emitters only, 1 = direct lighting), so it
    /// takes max_depth - 1, and `None` (unlimited) for -1 or when the scene gives none.
    fn caustic_max_depth(&mut self, depth: Option<Depth<'a>>) -> Result<Option<u32>, SceneError> {
        let Some((d, el)) = depth else { return Ok(None) };
        if d < -1 {
            return Err(self.err(el, format!("max_depth must be -1 (unlimited) or at least 0, found {d}")));
        }
        if d == -1 {
            return Ok(None);
        }
        if d == 0 {
            self.warn(el, "max_depth 0 renders a black image in Mitsuba; here emitters stay visible")?;
        }
        let limit = crate::scene::desc::MAX_DEPTH_LIMIT as i64 + 1;
        if d > limit {
            return Err(self.err(el, format!("max_depth {d} is too large (at most {limit})")));
        }
        Ok(Some((d as u32).saturating_sub(1)))
    }

    fn integrator(&mut self, el: &'a El) -> Result<(IntegratorKind, Option<Depth<'a>>), SceneError> {
        let p = self.props(el)?;
        let (kind, depth) = match p.kind.as_str() {
            "path" | "volpath" | "volpathmis" | "prb" | "prb_basic" | "prbvolpath" | "ptracer" => {
                let depth = self.integer(&p, "max_depth")?;
                // Russian roulette only changes noise, not the expected image.
                let _ = self.integer(&p, "rr_depth")?;
                if p.kind == "ptracer" {
                    // How the work is split into passes changes nothing in the image.
                    let _ = self.integer(&p, "samples_per_pass")?;
                }
                if self.boolean(&p, "hide_emitters")? == Some(true) {
                    self.warn(el, "hide_emitters is not supported: emitters seen directly are rendered")?;
                }
                let kind = match p.kind.as_str() {
                    "ptracer" => IntegratorKind::Light,
                    "volpath" | "volpathmis" | "prbvolpath" => IntegratorKind::Volpath,
                    _ => IntegratorKind::Path,
                };
                (kind, depth)
            }
            "direct" => {
                for name in ["emitter_samples", "bsdf_samples"] {
                    let _ = self.integer(&p, name)?;
                }
                if self.boolean(&p, "hide_emitters")? == Some(true) {
                    self.warn(el, "hide_emitters is not supported: emitters seen directly are rendered")?;
                }
                // Direct lighting is a path of two segments.
                (IntegratorKind::Path, Some((2, el)))
            }
            // Wrappers that add channels to the film (moments for variance estimates, AOVs)
            // around the integrators that make the image: the image is the first nested one's.
            "moment" | "aov" => {
                if p.kind == "aov"
                    && let Some((text, at)) = self.string(&p, "aovs")?
                {
                    // Mitsuba's `name:type` pairs, each an AOV written beside the image (the
                    // command line's `--aov` replaces them); types caustic has no counterpart
                    // for are skipped with a warning.
                    let mut kept = Vec::new();
                    for entry in text.split(',').map(str::trim).filter(|e| !e.is_empty()) {
                        let kind = entry.split_once(':').map_or(entry, |(_, k)| k.trim());
                        if crate::film::aov::AovKind::MITSUBA_ONLY.contains(&kind) {
                            self.warn(at, format!("the `{kind}` AOV is not supported and is not written"))?;
                        } else if !entry.contains(':') {
                            return Err(
                                self.err(at, format!("AOV `{entry}`: expected a name:type pair, e.g. dd.y:depth"))
                            );
                        } else {
                            kept.push(entry);
                        }
                    }
                    if !kept.is_empty() {
                        self.aovs = crate::film::aov::AovList::parse(&kept.join(","))
                            .map_err(|m| self.err(at, format!("aovs: {m}")))?;
                    }
                }
                let nested = self.object(&p, None, "integrator");
                let Some(&(inner, _)) = nested.first() else {
                    return Err(self.err(
                        el,
                        format!("a `{}` integrator needs a nested <integrator> that renders the image", p.kind),
                    ));
                };
                if nested.len() > 1 {
                    self.warn(el, format!("only the first of the {} nested integrators is rendered", nested.len()))?;
                }
                self.finish(&p)?;
                return self.integrator(inner);
            }
            other => {
                self.unsupported(el, PluginKind::Integrator, other, "; the path tracer is used")?;
                for u in &p.used {
                    u.set(true);
                }
                (IntegratorKind::Path, None)
            }
        };
        self.finish(&p)?;
        Ok((kind, depth))
    }
}
