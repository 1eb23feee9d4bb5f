//! The owned XML tree of a Mitsuba scene: each element and attribute remembers the file and the
//! byte range it came from, `<include>`s are expanded, and nesting is bounded.

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
    pub base: PathBuf,
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

/// Parses source `id` of `srcs`, expanding `<include>`s (each reported to `files` before it is
/// read), and returns its `<scene>` element. `paths` gathers the `<path>` folders met so far in
/// document order (an `<include>` is searched for in them, newest first, as Mitsuba does).
pub(super) fn parse_source(
    srcs: &mut Vec<Src>,
    id: usize,
    depth: usize,
    paths: &mut Vec<PathBuf>,
    files: &FileBudget,
) -> Result<El, SceneError> {
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
    expand_includes(srcs, &mut el, depth, paths, files)?;
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
/// found in the `<path>` folders met before it (newest first), else next to the file naming it.
fn expand_includes(
    srcs: &mut Vec<Src>,
    el: &mut El,
    depth: usize,
    paths: &mut Vec<PathBuf>,
    files: &FileBudget,
) -> Result<(), SceneError> {
    let children = std::mem::take(&mut el.children);
    for mut child in children {
        if child.tag == "path"
            && let Some(v) = child.attrs.iter().find(|a| a.name == "value")
        {
            // Checked (and a missing folder warned about) when the scene is read.
            paths.push(srcs[child.src].base.join(&v.value));
        }
        if child.tag != "include" {
            expand_includes(srcs, &mut child, depth, paths, files)?;
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
        let rel = Path::new(&file.value);
        let path =
            paths.iter().rev().map(|dir| dir.join(rel)).find(|p| p.is_file()).unwrap_or_else(|| src.base.join(rel));
        files.open(&path, FileKind::Include)?;
        let text = std::fs::read_to_string(&path)
            .map_err(|e| at(file.span.clone(), format!("cannot read included file `{}`: {e}", path.display())))?;
        let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
        srcs.push(Src { name: path.display().to_string(), text, base });
        let id = srcs.len() - 1;
        let included = parse_source(srcs, id, depth + 1, paths, files)?;
        el.children.extend(included.children);
    }
    Ok(())
}
