//! The owned XML tree of a Mitsuba scene: each element and attribute remembers the file and the
//! byte range it came from, `<include>`s are expanded, and nesting is bounded. Relative file
//! names are looked up as Mitsuba 3's file resolver does (`Resolver`).

use crate::scene::SceneError;
use crate::scene::footprint::{FileBudget, FileKind};
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Nested `<include>`s deeper than this are taken for a cycle.
const MAX_INCLUDE_DEPTH: usize = 16;
/// Elements nested deeper than this are refused (a real scene needs fewer than ten levels); the
/// tree is walked recursively, so without a bound a hostile file could exhaust the stack.
pub(super) const MAX_NESTING: usize = 256;

/// One source file (the scene or an included file).
pub(super) struct Src {
    pub name: String,
    pub text: String,
    /// The folders relative names in this file are looked up in while it is parsed: its own
    /// folder, its `<path>`s and those of the files that include it.
    pub resolver: Resolver,
    /// A `--set` value (`name` is the `--set`, `text` its value) rather than a file: errors about
    /// it name the `--set` and have no line.
    pub from_set: bool,
}

/// Mitsuba 3's file resolver: an ordered list of folders, the first that holds a relative name
/// wins. Each file parses with a copy of its includer's list with its own folder put first,
/// and a `<path>` puts its folder first from there on. Objects are built after parsing with
/// the list of the scene file itself (its `<path>`s newest first, its folder, the working
/// folder): so a mesh named in an included file is looked up from the scene's folder, and a
/// `<path>` inside an included file serves only that file's own includes and spectrum files.
#[derive(Clone, Debug, Default)]
pub(super) struct Resolver {
    dirs: Vec<PathBuf>,
}

impl Resolver {
    /// The resolver of a scene read from `dir` (its folder, then the working folder).
    pub fn for_scene(dir: &Path) -> Resolver {
        let mut dirs = vec![dir.to_path_buf()];
        if let Ok(cwd) = std::env::current_dir()
            && cwd != dir
        {
            dirs.push(cwd);
        }
        Resolver { dirs }
    }

    /// This resolver with `dir` searched first.
    pub fn prepend(&mut self, dir: PathBuf) {
        self.dirs.insert(0, dir);
    }

    /// The existing file or folder `name` refers to.
    pub fn resolve(&self, name: &str) -> Option<PathBuf> {
        let rel = Path::new(name);
        if rel.is_absolute() {
            return rel.exists().then(|| rel.to_path_buf());
        }
        self.dirs.iter().map(|d| d.join(rel)).find(|p| p.exists())
    }

    /// The folders searched, for messages.
    pub fn searched(&self) -> String {
        let names: Vec<String> = self.dirs.iter().map(|d| format!("`{}`", d.display())).collect();
        names.join(", ")
    }
}

/// An XML element with the places of its parts.
pub(super) struct El {
    pub tag: String,
    pub attrs: Vec<Attr>,
    pub children: Vec<El>,
    /// Index of the source file in `srcs`.
    pub src: usize,
    /// Byte range of the tag name in the start tag.
    pub span: Range<usize>,
}

pub(super) struct Attr {
    pub name: String,
    pub value: String,
    /// Byte range of the value (without quotes).
    pub span: Range<usize>,
}

/// Parses source `id` of `srcs` (its resolver already holds its own folder first), expanding
/// `<include>`s (each reported to `files` before it is read) and reading its `<path>`s into its
/// resolver, and returns its `<scene>` element.
pub(super) fn parse_source(srcs: &mut Vec<Src>, id: usize, depth: usize, files: &FileBudget) -> Result<El, SceneError> {
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
    let mut el = convert(root, id, 0).map_err(|node| {
        let start = node.range().start;
        SceneError::at(
            &name,
            &text,
            start..start + 1,
            format!("elements are nested more than {MAX_NESTING} deep; a Mitsuba scene needs only a few levels"),
        )
    })?;
    if el.tag != "scene" {
        return Err(SceneError::at(
            &name,
            &text,
            el.span.clone(),
            format!("the root element must be <scene version=\"3.0.0\">, found <{}>", el.tag),
        ));
    }
    let mut resolver = srcs[id].resolver.clone();
    expand_includes(srcs, &mut el, depth, &mut resolver, files, true)?;
    srcs[id].resolver = resolver;
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

/// Copies an element and its descendants into the owned tree; fails with the first element
/// deeper than `MAX_NESTING`, so every later walk of the tree has bounded recursion.
fn convert<'d, 'i>(node: roxmltree::Node<'d, 'i>, src: usize, depth: usize) -> Result<El, roxmltree::Node<'d, 'i>> {
    if depth >= MAX_NESTING {
        return Err(node);
    }
    let start = node.range().start + 1;
    let tag = node.tag_name().name().to_string();
    let span = start..start + tag.len();
    let attrs = node
        .attributes()
        .map(|a| Attr { name: a.name().to_string(), value: a.value().to_string(), span: a.range_value() })
        .collect();
    let children =
        node.children().filter(|c| c.is_element()).map(|c| convert(c, src, depth + 1)).collect::<Result<_, _>>()?;
    Ok(El { tag, attrs, children, src, span })
}

/// Replaces every `<include filename="..."/>` below `el` by the children of the included scene,
/// and puts the folder of every `<path>` (children of the root only, as in Mitsuba) first in
/// `resolver`; both are looked up through `resolver` as it stands where they appear.
fn expand_includes(
    srcs: &mut Vec<Src>,
    el: &mut El,
    depth: usize,
    resolver: &mut Resolver,
    files: &FileBudget,
    is_root: bool,
) -> Result<(), SceneError> {
    let children = std::mem::take(&mut el.children);
    for mut child in children {
        let src = &srcs[child.src];
        let at = |span: Range<usize>, msg: String| SceneError::at(&src.name, &src.text, span, msg);
        if child.tag == "path" {
            if !is_root {
                return Err(at(child.span.clone(), "<path> must be a child of <scene>".into()));
            }
            resolver.prepend(search_folder(src, &child, resolver)?);
            el.children.push(child);
            continue;
        }
        if child.tag != "include" {
            expand_includes(srcs, &mut child, depth, resolver, files, false)?;
            el.children.push(child);
            continue;
        }
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
        let Some(path) = resolver.resolve(&file.value).filter(|p| p.is_file()) else {
            return Err(at(
                file.span.clone(),
                format!("cannot find included file `{}` (looked in {})", file.value, resolver.searched()),
            ));
        };
        files.open(&path, FileKind::Include)?;
        let text = std::fs::read_to_string(&path)
            .map_err(|e| at(file.span.clone(), format!("cannot read included file `{}`: {e}", path.display())))?;
        let mut own = resolver.clone();
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            own.prepend(dir.to_path_buf());
        }
        srcs.push(Src { name: path.display().to_string(), text, resolver: own, from_set: false });
        let id = srcs.len() - 1;
        let included = parse_source(srcs, id, depth + 1, files)?;
        el.children.extend(included.children);
    }
    Ok(())
}

/// The folder of a `<path value="..."/>`: an absolute folder, or a relative one found through
/// `resolver`; a folder that does not exist is an error, as in Mitsuba.
fn search_folder(src: &Src, el: &El, resolver: &Resolver) -> Result<PathBuf, SceneError> {
    let at = |span: Range<usize>, msg: String| SceneError::at(&src.name, &src.text, span, msg);
    if let Some(a) = el.attrs.iter().find(|a| a.name != "value") {
        return Err(at(a.span.clone(), format!("<path> takes only `value`, found `{}`", a.name)));
    }
    let Some(v) = el.attrs.iter().find(|a| a.name == "value") else {
        return Err(at(el.span.clone(), "<path> needs a folder in `value`".into()));
    };
    if v.value.trim().is_empty() {
        return Err(at(v.span.clone(), "<path> needs a folder in `value`".into()));
    }
    match resolver.resolve(&v.value).filter(|p| p.is_dir()) {
        Some(dir) => Ok(dir),
        None => Err(at(
            v.span.clone(),
            format!("<path> folder `{}` not found (looked in {})", v.value, resolver.searched()),
        )),
    }
}
