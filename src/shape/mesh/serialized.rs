//! Mitsuba's `serialized` meshes: a little-endian file of one or more meshes, each a 4-byte
//! header (0x041C, format version 3 or 4) followed by a zlib stream holding flags, (version 4)
//! a name, counts, positions, optional normals, texture coordinates and colours in single or
//! double precision, and 32-bit triangle indices; the file ends with the offset of every mesh
//! (64-bit in version 4, 32-bit in version 3) and their count.
//!
//! Every byte is untrusted. Counts are checked against what the compressed data could possibly
//! hold (deflate expands at most 1032 times) before anything is allocated; the table at the end
//! must be consistent and each mesh's stream must end exactly where the next mesh (or the
//! table) starts, with its checksum verified, so a file cut or damaged anywhere is an error,
//! never a panic or a silently shorter mesh.

use super::{MeshError, TriangleMesh};
use crate::math::{Vec2, Vec3};
use flate2::bufread::ZlibDecoder;
use std::io::Read;
use std::path::Path;

const MAGIC: u16 = 0x041C;
const HAS_NORMALS: u32 = 0x0001;
const HAS_TEXCOORDS: u32 = 0x0002;
const HAS_COLORS: u32 = 0x0008;
const FACE_NORMALS: u32 = 0x0010;
const DOUBLE_PRECISION: u32 = 0x2000;
/// Deflate cannot expand data by more than this factor (a 258-byte match costs two bits).
const MAX_EXPANSION: u64 = 1032;
/// Longest mesh name read (a damaged stream need not contain a terminating zero soon).
const MAX_NAME: usize = 1 << 16;
/// Most vertices or triangles in one mesh (indices are 32-bit; 2^31 keeps sizes in range).
const MAX_COUNT: u64 = 1 << 31;

/// One mesh of a `serialized` file.
#[derive(Debug)]
pub struct Serialized {
    pub mesh: TriangleMesh,
    /// The file asks for flat shading (flag 0x0010). Mitsuba 3.9.1 ignores this flag (only the
    /// shape's `face_normals` parameter flattens a mesh), and so does our Mitsuba loader.
    pub face_normals: bool,
    /// The mesh's name (version 4 files; empty otherwise).
    pub name: String,
    /// Meshes in the file.
    pub count: u32,
}

/// Reads mesh `shape_index` of a `serialized` file.
pub fn load_serialized(path: &Path, shape_index: u32) -> Result<Serialized, MeshError> {
    let shown = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| MeshError::Read {
        path: shown.clone(),
        format: "serialized",
        message: e.to_string(),
    })?;
    parse_serialized(&bytes, shape_index).map_err(|message| MeshError::Invalid {
        path: shown,
        format: "serialized",
        message,
    })
}

fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(b.get(at..at.checked_add(2)?)?.try_into().ok()?))
}

fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(at..at.checked_add(4)?)?.try_into().ok()?))
}

fn u64_at(b: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(b.get(at..at.checked_add(8)?)?.try_into().ok()?))
}

/// The format version of the mesh header at `at`.
fn header(b: &[u8], at: usize) -> Result<u16, String> {
    match (u16_at(b, at), u16_at(b, at + 2)) {
        (Some(MAGIC), Some(v @ (3 | 4))) => Ok(v),
        (Some(MAGIC), Some(v)) => Err(format!("format version {v} is not supported (Mitsuba writes 3 or 4)")),
        (Some(_), Some(_)) => Err("not a Mitsuba serialized mesh (the file does not start with 0x041C)".into()),
        _ => Err("the file is too short to be a serialized mesh".into()),
    }
}

/// The start of every mesh and where the table of offsets begins, from the end of the file.
fn table(b: &[u8], version: u16) -> Result<(Vec<usize>, usize), String> {
    let damaged = "the table of meshes at the end of the file is missing or damaged (is the file cut short?)";
    let count = b.len().checked_sub(4).and_then(|at| u32_at(b, at)).ok_or(damaged)? as usize;
    let width = if version == 4 { 8 } else { 4 };
    let size = count.checked_mul(width).and_then(|s| s.checked_add(4)).ok_or(damaged)?;
    if count == 0 || size > b.len() {
        return Err(damaged.into());
    }
    let start = b.len() - size;
    let mut offsets = Vec::with_capacity(count);
    for k in 0..count {
        let at = start + k * width;
        let off = if version == 4 { u64_at(b, at) } else { u32_at(b, at).map(u64::from) }.ok_or(damaged)?;
        let off = usize::try_from(off).map_err(|_| damaged)?;
        // Offsets start at zero and increase, each leaving room for a header before the table.
        let prev = offsets.last().map(|&p: &usize| p + 4);
        if (k == 0 && off != 0) || prev.is_some_and(|p| off < p) || off.checked_add(4).is_none_or(|e| e > start) {
            return Err(damaged.into());
        }
        offsets.push(off);
    }
    Ok((offsets, start))
}

/// What a damaged or cut zlib stream means to a user.
fn stream_error(e: std::io::Error) -> String {
    if e.kind() == std::io::ErrorKind::UnexpectedEof {
        "the compressed mesh data ends early (is the file cut short?)".into()
    } else {
        format!("the compressed mesh data is damaged ({e})")
    }
}

/// Reads `n` numbers of `size` bytes each (4: f32, 8: f64) from the stream, in chunks, so the
/// only allocation is the result (whose size the caller has checked).
fn read_floats(z: &mut impl Read, n: usize, double: bool) -> Result<Vec<f32>, String> {
    let size = if double { 8 } else { 4 };
    let mut out = Vec::with_capacity(n);
    let mut buf = [0u8; 1 << 14];
    let mut left = n;
    while left > 0 {
        let k = left.min(buf.len() / size);
        let chunk = &mut buf[..k * size];
        z.read_exact(chunk).map_err(stream_error)?;
        if double {
            out.extend(chunk.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().unwrap_or_default()) as f32));
        } else {
            out.extend(chunk.chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().unwrap_or_default())));
        }
        left -= k;
    }
    Ok(out)
}

fn read_u32s(z: &mut impl Read, n: usize) -> Result<Vec<u32>, String> {
    let mut out = Vec::with_capacity(n);
    let mut buf = [0u8; 1 << 14];
    let mut left = n;
    while left > 0 {
        let k = left.min(buf.len() / 4);
        let chunk = &mut buf[..k * 4];
        z.read_exact(chunk).map_err(stream_error)?;
        out.extend(chunk.chunks_exact(4).map(|c| u32::from_le_bytes(c.try_into().unwrap_or_default())));
        left -= k;
    }
    Ok(out)
}

/// Skips `n` bytes of the stream.
fn skip(z: &mut impl Read, n: u64) -> Result<(), String> {
    let got = std::io::copy(&mut z.take(n), &mut std::io::sink()).map_err(stream_error)?;
    if got < n { Err(stream_error(std::io::ErrorKind::UnexpectedEof.into())) } else { Ok(()) }
}

/// Vectors of `dim` floats each from a flat list, refusing values that are not finite.
fn vectors<const D: usize>(flat: &[f32], what: &str) -> Result<Vec<[f32; D]>, String> {
    let mut out = Vec::with_capacity(flat.len() / D);
    for (i, c) in flat.chunks_exact(D).enumerate() {
        if c.iter().any(|x| !x.is_finite()) {
            return Err(format!("{what} of vertex {i} is not finite"));
        }
        out.push(std::array::from_fn(|k| c[k]));
    }
    Ok(out)
}

/// Parses mesh `shape_index` of a `serialized` file held in `bytes`.
pub fn parse_serialized(bytes: &[u8], shape_index: u32) -> Result<Serialized, String> {
    // The first header's version decides the width of the table, as in Mitsuba.
    let version = header(bytes, 0)?;
    let (offsets, table_start) = table(bytes, version)?;
    let count = offsets.len();
    let index = shape_index as usize;
    if index >= count {
        return Err(format!(
            "shape_index {shape_index} is out of range: the file holds {count} mesh{}",
            if count == 1 { "" } else { "es" }
        ));
    }
    let start = offsets[index];
    let end = offsets.get(index + 1).copied().unwrap_or(table_start);
    header(bytes, start)?;
    let data = &bytes[start + 4..end];
    let mut z = ZlibDecoder::new(data);

    let mut word = [0u8; 4];
    z.read_exact(&mut word).map_err(stream_error)?;
    let flags = u32::from_le_bytes(word);
    let mut name = Vec::new();
    if version == 4 {
        let mut byte = [0u8; 1];
        loop {
            z.read_exact(&mut byte).map_err(stream_error)?;
            if byte[0] == 0 {
                break;
            }
            if name.len() >= MAX_NAME {
                return Err("the mesh name is not terminated (damaged file?)".into());
            }
            name.push(byte[0]);
        }
    }
    let mut counts = [0u8; 16];
    z.read_exact(&mut counts).map_err(stream_error)?;
    let vertices = u64::from_le_bytes(counts[..8].try_into().unwrap_or_default());
    let triangles = u64::from_le_bytes(counts[8..].try_into().unwrap_or_default());
    if vertices == 0 || triangles == 0 {
        return Err(format!("the mesh has {vertices} vertices and {triangles} triangles: nothing to render"));
    }
    if vertices > MAX_COUNT || triangles > MAX_COUNT {
        return Err(format!("{vertices} vertices and {triangles} triangles: more than caustic reads in one mesh"));
    }
    let double = flags & DOUBLE_PRECISION != 0;
    let fsize = if double { 8 } else { 4 };
    let per_vertex: u64 = 3
        + if flags & HAS_NORMALS != 0 { 3 } else { 0 }
        + if flags & HAS_TEXCOORDS != 0 { 2 } else { 0 }
        + if flags & HAS_COLORS != 0 { 3 } else { 0 };
    let need = vertices * per_vertex * fsize + triangles * 12;
    if need > (data.len() as u64).saturating_mul(MAX_EXPANSION) {
        return Err(format!(
            "the header claims {vertices} vertices and {triangles} triangles, more than {} compressed bytes can hold (damaged file?)",
            data.len()
        ));
    }
    let (v, t) = (vertices as usize, triangles as usize);
    let positions = vectors::<3>(&read_floats(&mut z, 3 * v, double)?, "the position")?;
    let normals = if flags & HAS_NORMALS != 0 {
        Some(vectors::<3>(&read_floats(&mut z, 3 * v, double)?, "the normal")?)
    } else {
        None
    };
    let uvs = if flags & HAS_TEXCOORDS != 0 {
        Some(vectors::<2>(&read_floats(&mut z, 2 * v, double)?, "the uv")?)
    } else {
        None
    };
    if flags & HAS_COLORS != 0 {
        skip(&mut z, 3 * vertices * fsize)?;
    }
    let flat = read_u32s(&mut z, 3 * t)?;
    let mut indices = Vec::with_capacity(t);
    for (i, c) in flat.chunks_exact(3).enumerate() {
        if let Some(bad) = c.iter().find(|&&k| k as u64 >= vertices) {
            return Err(format!("triangle {i} refers to vertex {bad} of {vertices}"));
        }
        indices.push([c[0], c[1], c[2]]);
    }
    drop(flat);
    // The stream must end here (checksum verified) and exactly where the next part starts.
    let mut extra = [0u8; 1];
    match z.read(&mut extra) {
        Ok(0) => {}
        Ok(_) => return Err("the compressed mesh data is longer than its header says (damaged file?)".into()),
        Err(e) => return Err(stream_error(e)),
    }
    if !z.get_ref().is_empty() {
        return Err("bytes follow the compressed mesh data where the next mesh or the table should start".into());
    }
    let mesh = TriangleMesh {
        positions: positions.into_iter().map(Vec3::from).collect(),
        normals: normals.map(|n| n.into_iter().map(Vec3::from).collect()),
        uvs: uvs.map(|u| u.into_iter().map(Vec2::from).collect()),
        indices,
        attributes: Vec::new(),
    };
    Ok(Serialized {
        mesh,
        face_normals: flags & FACE_NORMALS != 0,
        name: String::from_utf8_lossy(&name).into_owned(),
        count: count as u32,
    })
}

#[cfg(test)]
mod tests;
