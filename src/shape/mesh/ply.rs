//! PLY meshes (ASCII and binary, little- and big-endian), read by our own streaming reader.
//!
//! The header is read first and each element's layout fixed from it: where in a record each
//! property we keep sits and what type it is. Records are then decoded straight from a 1 MiB
//! read buffer into the mesh's final arrays, with nothing allocated per element (the general
//! reader it replaced built a hash map per vertex: 765 bytes per triangle at peak, 10 s for
//! 5 M triangles; see BENCHMARKS.md, "Big meshes"). Element counts are checked against the
//! file's size before anything is reserved, so a lying header cannot ask for a huge allocation.

use super::{MeshAttribute, MeshError, TriangleMesh};
use crate::math::{Vec2, Vec3};
use std::io::Read;
use std::path::Path;

/// Faces with more vertices than this are refused (a fan of them is not a face of a mesh).
const MAX_FACE_VERTICES: u64 = 1 << 16;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    /// The value at the start of `b` (at least `size()` bytes).
    #[inline(always)]
    fn decode(self, b: &[u8], big: bool) -> f64 {
        macro_rules! num {
            ($t:ty, $n:expr) => {{
                let a: [u8; $n] = b[..$n].try_into().unwrap();
                (if big { <$t>::from_be_bytes(a) } else { <$t>::from_le_bytes(a) }) as f64
            }};
        }
        match self {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => num!(i16, 2),
            Scalar::U16 => num!(u16, 2),
            Scalar::I32 => num!(i32, 4),
            Scalar::U32 => num!(u32, 4),
            Scalar::F32 => num!(f32, 4),
            Scalar::F64 => num!(f64, 8),
        }
    }

    /// The value as f32 (positions, normals, uv): floats without the trip through f64.
    #[inline(always)]
    fn decode_f32(self, b: &[u8], big: bool) -> f32 {
        if self == Scalar::F32 {
            let a: [u8; 4] = b[..4].try_into().unwrap();
            return if big { f32::from_be_bytes(a) } else { f32::from_le_bytes(a) };
        }
        self.decode(b, big) as f32
    }
}

#[derive(Clone, Debug)]
struct Property {
    name: String,
    /// `Some(count type)` for a list property, whose items are of type `ty`.
    list: Option<Scalar>,
    ty: Scalar,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: u64,
    props: Vec<Property>,
}

impl Element {
    /// Bytes of one binary record when it has no lists.
    fn fixed_size(&self) -> Option<usize> {
        self.props.iter().map(|p| if p.list.is_some() { None } else { Some(p.ty.size()) }).sum()
    }

    /// The fewest bytes one record can take: lists count as empty.
    fn min_size(&self, ascii: bool) -> u64 {
        if ascii {
            // A digit and a separator per value.
            return 2 * self.props.len() as u64;
        }
        self.props.iter().map(|p| p.list.unwrap_or(p.ty).size() as u64).sum()
    }

    fn find(&self, name: &str) -> Option<usize> {
        self.props.iter().position(|p| p.name == name && p.list.is_none())
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Format {
    Ascii,
    Binary { big: bool },
}

struct Header {
    format: Format,
    elements: Vec<Element>,
}

/// Buffered bytes of the file after its header, refilled as records are taken.
struct Source<R> {
    reader: R,
    buf: Vec<u8>,
    pos: usize,
    len: usize,
    eof: bool,
}

impl<R: Read> Source<R> {
    /// A source over `reader`, which holds `size` bytes (the buffer needs no more).
    fn new(reader: R, size: u64) -> Self {
        let cap = size.saturating_add(1).clamp(4096, 1 << 20) as usize;
        Source { reader, buf: vec![0; cap], pos: 0, len: 0, eof: false }
    }

    /// Makes at least `n` bytes (n <= the buffer's size) available at `pos`, unless the file
    /// ends first; returns how many are.
    fn fill(&mut self, n: usize) -> std::io::Result<usize> {
        if self.len - self.pos >= n || self.eof {
            return Ok(self.len - self.pos);
        }
        self.buf.copy_within(self.pos..self.len, 0);
        self.len -= self.pos;
        self.pos = 0;
        while self.len < n && !self.eof {
            match self.reader.read(&mut self.buf[self.len..]) {
                Ok(0) => self.eof = true,
                Ok(k) => self.len += k,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
        Ok(self.len - self.pos)
    }

    /// The next `n` bytes, or `None` at the end of the file.
    #[inline]
    fn take(&mut self, n: usize) -> std::io::Result<Option<&[u8]>> {
        if self.len - self.pos < n && self.fill(n)? < n {
            return Ok(None);
        }
        let at = self.pos;
        self.pos += n;
        Ok(Some(&self.buf[at..at + n]))
    }

    /// The next whitespace-separated word of an ASCII body (at most 256 bytes), or `None`.
    fn word(&mut self) -> std::io::Result<Option<&[u8]>> {
        loop {
            if self.pos == self.len && self.fill(1)? == 0 {
                return Ok(None);
            }
            match self.buf[self.pos..self.len].iter().position(|b| !b.is_ascii_whitespace()) {
                Some(k) => {
                    self.pos += k;
                    break;
                }
                None => self.pos = self.len,
            }
        }
        let end = |s: &Self| s.buf[s.pos..s.len].iter().position(|b| b.is_ascii_whitespace());
        if end(self).is_none() {
            self.fill(257)?;
        }
        let k = end(self).unwrap_or(self.len - self.pos).min(256);
        let at = self.pos;
        self.pos += k;
        Ok(Some(&self.buf[at..at + k]))
    }
}

/// Loads a PLY mesh (ASCII or binary): vertex x, y, z (nx, ny, nz and texture coordinates when
/// present) and faces of any size, fanned into triangles.
pub fn load_ply(path: &Path) -> Result<TriangleMesh, MeshError> {
    let shown = path.display().to_string();
    let read = |message: String| MeshError::Read { path: shown.clone(), format: "PLY", message };
    let invalid = |message: String| MeshError::Invalid { path: shown.clone(), format: "PLY", message };
    let file = std::fs::File::open(path).map_err(|e| read(e.to_string()))?;
    let size = file.metadata().map_err(|e| read(e.to_string()))?.len();
    let mut source = Source::new(file, size);
    let (header, header_len) = read_header(&mut source).map_err(|e| match e {
        HeaderError::Io(e) => read(e.to_string()),
        HeaderError::Bad(m) => invalid(m),
    })?;
    let body = size.saturating_sub(header_len);
    parse_body(&header, body, &mut source).map_err(|e| match e {
        BodyError::Io(e) => read(e.to_string()),
        BodyError::Bad(m) => invalid(m),
    })
}

/// Reads a PLY mesh from memory (the fuzz target and tests).
pub fn parse_ply(bytes: &[u8]) -> Result<TriangleMesh, String> {
    let mut source = Source::new(bytes, bytes.len() as u64);
    let (header, header_len) = read_header(&mut source).map_err(|e| e.to_string())?;
    parse_body(&header, (bytes.len() as u64).saturating_sub(header_len), &mut source).map_err(|e| e.to_string())
}

#[derive(Debug, thiserror::Error)]
enum HeaderError {
    #[error("{0}")]
    Io(#[from] std::io::Error),
    #[error("{0}")]
    Bad(String),
}

type BodyError = HeaderError;

/// Parses the header; returns it and its length in bytes.
fn read_header<R: Read>(src: &mut Source<R>) -> Result<(Header, u64), HeaderError> {
    let bad = |m: String| HeaderError::Bad(m);
    // Headers are short: a megabyte without `end_header` is not a PLY file.
    let avail = src.fill(src.buf.len())?;
    let text = &src.buf[src.pos..src.pos + avail];
    if !text.starts_with(b"ply") {
        return Err(bad("it does not start with `ply`".into()));
    }
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut at = 0usize;
    let mut line_no = 0;
    loop {
        let Some(nl) = text[at..].iter().position(|&b| b == b'\n') else {
            return Err(bad("the header has no `end_header` line".into()));
        };
        let line = String::from_utf8_lossy(&text[at..at + nl]).into_owned();
        at += nl + 1;
        line_no += 1;
        let words: Vec<&str> = line.split_whitespace().collect();
        let here = |m: &str| bad(format!("header line {line_no} (`{}`): {m}", line.trim()));
        match words.as_slice() {
            ["ply"] if line_no == 1 => {}
            ["format", f, _version] => {
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::Binary { big: false },
                    "binary_big_endian" => Format::Binary { big: true },
                    _ => return Err(here("unknown format")),
                })
            }
            ["comment", ..] | ["obj_info", ..] | [] => {}
            ["element", name, count] => {
                let count = count.parse().map_err(|_| here("the count is not a whole number"))?;
                elements.push(Element { name: name.to_string(), count, props: Vec::new() });
            }
            ["property", "list", count_ty, item_ty, name] => {
                let e = elements.last_mut().ok_or_else(|| here("a property before any element"))?;
                let (Some(c), Some(t)) = (Scalar::parse(count_ty), Scalar::parse(item_ty)) else {
                    return Err(here("unknown type"));
                };
                if matches!(c, Scalar::F32 | Scalar::F64) {
                    return Err(here("a list's count must be an integer type"));
                }
                e.props.push(Property { name: name.to_string(), list: Some(c), ty: t });
            }
            ["property", ty, name] => {
                let e = elements.last_mut().ok_or_else(|| here("a property before any element"))?;
                let ty = Scalar::parse(ty).ok_or_else(|| here("unknown type"))?;
                e.props.push(Property { name: name.to_string(), list: None, ty });
            }
            ["end_header"] => break,
            _ => return Err(here("not a PLY header line")),
        }
    }
    src.pos += at;
    let format = format.ok_or_else(|| bad("the header has no `format` line".into()))?;
    Ok((Header { format, elements }, at as u64))
}

/// Where the vertex properties we keep sit: byte offsets in a fixed-size binary record, or
/// value positions in an ASCII line.
struct VertexLayout {
    /// x, y, z, nx, ny, nz, u, v: property index, or `None`.
    slots: [Option<usize>; 8],
    normals: bool,
    uvs: bool,
}

impl VertexLayout {
    fn new(e: &Element) -> Result<Self, String> {
        let (Some(x), Some(y), Some(z)) = (e.find("x"), e.find("y"), e.find("z")) else {
            return Err("the vertex element has no x, y, z properties".into());
        };
        let n = [e.find("nx"), e.find("ny"), e.find("nz")];
        let normals = n.iter().all(Option::is_some);
        // Texture coordinates go by several names; Mitsuba reads u/v, texture_u/texture_v and s/t.
        let uv = [("u", "v"), ("texture_u", "texture_v"), ("s", "t")]
            .into_iter()
            .find_map(|(u, v)| Some((e.find(u)?, e.find(v)?)));
        let mut slots = [Some(x), Some(y), Some(z), None, None, None, None, None];
        if normals {
            slots[3..6].copy_from_slice(&n);
        }
        if let Some((u, v)) = uv {
            slots[6] = Some(u);
            slots[7] = Some(v);
        }
        Ok(VertexLayout { slots, normals, uvs: uv.is_some() })
    }
}

/// Names a property never becomes an attribute under: geometry, and the colour channels
/// (grouped on their own).
const RESERVED: &[&str] = &[
    "x",
    "y",
    "z",
    "nx",
    "ny",
    "nz",
    "u",
    "v",
    "texture_u",
    "texture_v",
    "s",
    "t",
    "r",
    "g",
    "b",
    "a",
    "red",
    "green",
    "blue",
    "alpha",
];

/// Scalar properties of an element grouped into mesh attributes as Mitsuba's PLY reader groups
/// them: `r g b [a]` (or `red green blue [alpha]`) become `<kind>color`; other properties named
/// `<prefix>_<c>`, where consecutive ones with one prefix run through a suffix sequence
/// (`x y z w`, `r g b a`, `0 1 2 3` or `1 2 3 4`), become `<kind><prefix>` with 1 to 3 values
/// (`<kind><prefix>_color` for the `r g b` sequence). Properties that fit no rule are skipped,
/// as Mitsuba skips them (with a warning there). `kind` is `vertex_` or `face_`.
fn attribute_groups(e: &Element, kind: &str) -> Vec<(String, Vec<usize>)> {
    let mut groups = Vec::new();
    let colour = ["r", "g", "b", "a"].map(|n| e.find(n));
    let long = ["red", "green", "blue", "alpha"].map(|n| e.find(n));
    for c in [colour, long] {
        if let [Some(r), Some(g), Some(b), a] = c {
            let mut props = vec![r, g, b];
            props.extend(a);
            groups.push((format!("{kind}color"), props));
            break;
        }
    }
    const SEQUENCES: [[char; 4]; 4] =
        [['x', 'y', 'z', 'w'], ['r', 'g', 'b', 'a'], ['0', '1', '2', '3'], ['1', '2', '3', '4']];
    let mut seen: Vec<String> = Vec::new();
    let mut i = 0;
    while i < e.props.len() {
        let p = &e.props[i];
        let split = p.name.rsplit_once('_').filter(|(_, post)| post.chars().count() == 1);
        let (Some((prefix, post)), None) = (split, p.list) else {
            i += 1;
            continue;
        };
        if RESERVED.contains(&p.name.as_str()) || seen.iter().any(|s| s == prefix) {
            i += 1;
            continue;
        }
        let first = post.chars().next().unwrap_or(' ');
        let Some(seq) = SEQUENCES.iter().position(|s| s[0] == first) else {
            i += 1;
            continue;
        };
        // The run of properties continuing the sequence under the same prefix.
        let mut props = vec![i];
        while props.len() < 4
            && let Some(q) = e.props.get(i + props.len())
            && q.list.is_none()
            && q.name.rsplit_once('_') == Some((prefix, &SEQUENCES[seq][props.len()].to_string()))
        {
            props.push(i + props.len());
        }
        i += props.len();
        seen.push(prefix.to_string());
        if props.len() <= 3 {
            let suffix = if seq == 1 { "_color" } else { "" };
            groups.push((format!("{kind}{prefix}{suffix}"), props));
        }
    }
    groups
}

fn parse_body<R: Read>(h: &Header, body: u64, src: &mut Source<R>) -> Result<TriangleMesh, BodyError> {
    let bad = |m: String| HeaderError::Bad(m);
    let ascii = h.format == Format::Ascii;
    // A lying header cannot make us reserve more than the file could hold.
    let mut need = 0u64;
    for e in &h.elements {
        need = need.saturating_add(e.count.saturating_mul(e.min_size(ascii)));
    }
    if need > body {
        return Err(bad(format!(
            "the header promises at least {need} bytes of elements but only {body} follow it (is the file cut short?)"
        )));
    }
    let vertex = h.elements.iter().position(|e| e.name == "vertex").ok_or_else(|| bad("no `vertex` element".into()))?;
    let face = h.elements.iter().position(|e| e.name == "face").ok_or_else(|| bad("no `face` element".into()))?;
    let layout = VertexLayout::new(&h.elements[vertex]).map_err(bad)?;
    let list = h.elements[face]
        .props
        .iter()
        .position(|p| p.list.is_some() && (p.name == "vertex_indices" || p.name == "vertex_index"))
        .ok_or_else(|| bad("the face element has no vertex_indices list".into()))?;
    let vertex_groups = attribute_groups(&h.elements[vertex], "vertex_");
    let face_groups = attribute_groups(&h.elements[face], "face_");
    let mut mesh = TriangleMesh::default();
    for (k, e) in h.elements.iter().enumerate() {
        let cut = |i: u64| bad(format!("the file ends in element `{}` {i} of {} (is it cut short?)", e.name, e.count));
        if k == vertex {
            read_vertices(e, &layout, &vertex_groups, h.format, src, &mut mesh, cut)?;
        } else if k == face {
            let mut values = vec![Vec::new(); face_groups.len()];
            read_faces(e, list, &face_groups, &mut values, h.format, body, src, &mut mesh.indices, cut)?;
            for ((name, props), values) in face_groups.iter().zip(values) {
                mesh.attributes.push(MeshAttribute {
                    name: name.clone(),
                    per_face: true,
                    channels: props.len(),
                    values,
                });
            }
        } else {
            skip(e, h.format, src, cut)?;
        }
    }
    let n = mesh.positions.len() as u64;
    if let Some((f, bad_index)) = mesh.indices.iter().enumerate().find_map(|(f, t)| {
        let m = *t.iter().max()?;
        (m as u64 >= n).then_some((f, m))
    }) {
        return Err(bad(format!("triangle {f} refers to vertex {bad_index} of {n}")));
    }
    if mesh.indices.is_empty() {
        return Err(bad("it has no faces".into()));
    }
    Ok(mesh)
}

fn read_vertices<R: Read>(
    e: &Element,
    layout: &VertexLayout,
    groups: &[(String, Vec<usize>)],
    format: Format,
    src: &mut Source<R>,
    mesh: &mut TriangleMesh,
    cut: impl Fn(u64) -> BodyError,
) -> Result<(), BodyError> {
    let n = e.count as usize;
    mesh.positions.reserve_exact(n);
    let mut normals = Vec::with_capacity(if layout.normals { n } else { 0 });
    let mut uvs = Vec::with_capacity(if layout.uvs { n } else { 0 });
    let mut v = [0f32; 8];
    // Byte offset of each property in a fixed-size binary record.
    let offsets: Vec<usize> = e
        .props
        .iter()
        .scan(0, |at, p| {
            let o = *at;
            *at += p.ty.size();
            Some(o)
        })
        .collect();
    let fixed = e.fixed_size();
    let mut values = vec![0f64; e.props.len()];
    let mut attributes: Vec<Vec<f32>> = groups.iter().map(|(_, props)| Vec::with_capacity(n * props.len())).collect();
    for i in 0..e.count {
        match (format, fixed) {
            (Format::Binary { big }, Some(size)) => {
                let rec = src.take(size)?.ok_or_else(|| cut(i))?;
                for (s, slot) in layout.slots.iter().enumerate() {
                    if let Some(p) = *slot {
                        v[s] = e.props[p].ty.decode_f32(&rec[offsets[p]..], big);
                    }
                }
                for ((_, props), out) in groups.iter().zip(&mut attributes) {
                    out.extend(props.iter().map(|&p| e.props[p].ty.decode_f32(&rec[offsets[p]..], big)));
                }
            }
            _ => {
                read_record(e, format, src, &mut values, &cut, i)?;
                for (s, slot) in layout.slots.iter().enumerate() {
                    if let Some(p) = *slot {
                        v[s] = values[p] as f32;
                    }
                }
                for ((_, props), out) in groups.iter().zip(&mut attributes) {
                    out.extend(props.iter().map(|&p| values[p] as f32));
                }
            }
        }
        let p = Vec3::new(v[0], v[1], v[2]);
        if !p.is_finite() {
            return Err(HeaderError::Bad(format!("vertex {i} is not finite")));
        }
        mesh.positions.push(p);
        if layout.normals {
            // Normalised when the mesh is transformed.
            normals.push(Vec3::new(v[3], v[4], v[5]));
        }
        if layout.uvs {
            uvs.push(Vec2::new(v[6], v[7]));
        }
    }
    mesh.normals = layout.normals.then_some(normals);
    mesh.uvs = layout.uvs.then_some(uvs);
    for ((name, props), values) in groups.iter().zip(attributes) {
        mesh.attributes.push(MeshAttribute { name: name.clone(), per_face: false, channels: props.len(), values });
    }
    Ok(())
}

/// One record's scalar values (lists are skipped) from an ASCII or variable-size binary body.
fn read_record<R: Read>(
    e: &Element,
    format: Format,
    src: &mut Source<R>,
    values: &mut [f64],
    cut: &impl Fn(u64) -> BodyError,
    i: u64,
) -> Result<(), BodyError> {
    for (k, p) in e.props.iter().enumerate() {
        match p.list {
            None => values[k] = scalar(p.ty, format, src)?.ok_or_else(|| cut(i))?,
            Some(c) => {
                let count = list_count(c, format, src, e, i)?.ok_or_else(|| cut(i))?;
                for _ in 0..count {
                    scalar(p.ty, format, src)?.ok_or_else(|| cut(i))?;
                }
            }
        }
    }
    Ok(())
}

/// The next value of type `ty`, or `None` at the end of the file.
#[inline]
fn scalar<R: Read>(ty: Scalar, format: Format, src: &mut Source<R>) -> Result<Option<f64>, BodyError> {
    match format {
        Format::Binary { big } => Ok(src.take(ty.size())?.map(|b| ty.decode(b, big))),
        Format::Ascii => {
            let Some(w) = src.word()? else { return Ok(None) };
            let text = std::str::from_utf8(w).unwrap_or("?");
            let not_number =
                || HeaderError::Bad(format!("`{}` is not a number", text.chars().take(40).collect::<String>()));
            // Floats parsed at their own precision: one rounding, as a float reader would.
            let v: f64 = if ty == Scalar::F32 {
                text.parse::<f32>().map_err(|_| not_number())? as f64
            } else {
                text.parse().map_err(|_| not_number())?
            };
            if matches!(ty, Scalar::F32 | Scalar::F64) || v.fract() == 0.0 {
                Ok(Some(v))
            } else {
                Err(HeaderError::Bad(format!("`{text}` is not a whole number")))
            }
        }
    }
}

/// A list's length, checked: not negative and not absurdly long.
fn list_count<R: Read>(
    c: Scalar,
    format: Format,
    src: &mut Source<R>,
    e: &Element,
    i: u64,
) -> Result<Option<u64>, BodyError> {
    let Some(n) = scalar(c, format, src)? else { return Ok(None) };
    if !(0.0..=MAX_FACE_VERTICES as f64).contains(&n) {
        return Err(HeaderError::Bad(format!("element `{}` {i} has a list of {n} items", e.name)));
    }
    Ok(Some(n as u64))
}

/// Reads the faces into triangles, and the properties of each attribute group of the face
/// element into `values` (a polygon's values once per triangle it is fanned into).
#[allow(clippy::too_many_arguments)]
fn read_faces<R: Read>(
    e: &Element,
    list: usize,
    groups: &[(String, Vec<usize>)],
    values: &mut [Vec<f32>],
    format: Format,
    body: u64,
    src: &mut Source<R>,
    out: &mut Vec<[u32; 3]>,
    cut: impl Fn(u64) -> BodyError,
) -> Result<(), BodyError> {
    // Reserve for triangles, as many as the bytes left could hold.
    let typical =
        e.props.iter().map(|p| p.list.map_or(0, |c| c.size() + 3 * p.ty.size()).max(p.ty.size())).sum::<usize>();
    out.reserve_exact(e.count.min(body / typical.max(1) as u64 + 1) as usize);
    let bad_index = |i: u64, v: f64| HeaderError::Bad(format!("face {i} refers to vertex {v}"));
    // The common layout, a single `list uchar|int int|uint` per face, decoded directly.
    if let (Format::Binary { big }, [p]) = (format, e.props.as_slice())
        && let Some(c) = p.list
        && matches!(p.ty, Scalar::I32 | Scalar::U32)
    {
        let signed = p.ty == Scalar::I32;
        let mut idx: Vec<u32> = Vec::new();
        for i in 0..e.count {
            let n = src.take(c.size())?.ok_or_else(|| cut(i))?;
            let n = c.decode(n, big);
            if !(0.0..=MAX_FACE_VERTICES as f64).contains(&n) {
                return Err(HeaderError::Bad(format!("face {i} has {n} vertices")));
            }
            let b = src.take(4 * n as usize)?.ok_or_else(|| cut(i))?;
            let word = |k: usize| {
                let a: [u8; 4] = b[4 * k..4 * k + 4].try_into().unwrap();
                if big { u32::from_be_bytes(a) } else { u32::from_le_bytes(a) }
            };
            if n == 3.0 {
                let t = [word(0), word(1), word(2)];
                if signed && t.iter().any(|&v| (v as i32) < 0) {
                    let v = t.iter().map(|&v| v as i32).min().unwrap_or(0);
                    return Err(bad_index(i, v as f64));
                }
                out.push(t);
                continue;
            }
            idx.clear();
            for k in 0..n as usize {
                let v = word(k);
                if signed && (v as i32) < 0 {
                    return Err(bad_index(i, v as i32 as f64));
                }
                idx.push(v);
            }
            fan(&idx, out);
        }
        return Ok(());
    }
    let mut idx: Vec<u32> = Vec::new();
    let mut record = vec![0f32; e.props.len()];
    for i in 0..e.count {
        let before = out.len();
        for (k, p) in e.props.iter().enumerate() {
            match p.list {
                None => {
                    record[k] = scalar(p.ty, format, src)?.ok_or_else(|| cut(i))? as f32;
                }
                Some(c) => {
                    let n = list_count(c, format, src, e, i)?.ok_or_else(|| cut(i))?;
                    idx.clear();
                    for _ in 0..n {
                        let v = scalar(p.ty, format, src)?.ok_or_else(|| cut(i))?;
                        if k == list && !(0.0..u32::MAX as f64).contains(&v) {
                            return Err(bad_index(i, v));
                        }
                        idx.push(v as u32);
                    }
                    if k == list {
                        fan(&idx, out);
                    }
                }
            }
        }
        for _ in before..out.len() {
            for ((_, props), v) in groups.iter().zip(values.iter_mut()) {
                v.extend(props.iter().map(|&p| record[p]));
            }
        }
    }
    Ok(())
}

/// A polygon's triangles, fanned from its first vertex (fewer than three vertices give none).
#[inline]
fn fan(idx: &[u32], out: &mut Vec<[u32; 3]>) {
    for k in 1..idx.len().saturating_sub(1) {
        out.push([idx[0], idx[k], idx[k + 1]]);
    }
}

/// Reads past an element we do not keep.
fn skip<R: Read>(
    e: &Element,
    format: Format,
    src: &mut Source<R>,
    cut: impl Fn(u64) -> BodyError,
) -> Result<(), BodyError> {
    if e.props.is_empty() {
        // Records of nothing take no bytes, however many the header declares.
        return Ok(());
    }
    let mut values = vec![0f64; e.props.len()];
    let fixed = e.fixed_size();
    for i in 0..e.count {
        match (format, fixed) {
            (Format::Binary { .. }, Some(size)) => {
                src.take(size)?.ok_or_else(|| cut(i))?;
            }
            _ => read_record(e, format, src, &mut values, &cut, i)?,
        }
    }
    Ok(())
}

#[cfg(test)]
#[path = "ply_tests.rs"]
mod tests;
