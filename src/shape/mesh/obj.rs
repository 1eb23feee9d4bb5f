//! OBJ meshes, read by our own line reader straight into the mesh's arrays.
//!
//! `v`, `vt`, `vn` and `f` lines are read (polygons fanned from their first corner, negative
//! indices counted back from the end, as the format says); everything else (`o`, `g`, `s`,
//! `usemtl`, `mtllib`, `l`, `p`, comments) is skipped, and every object and group of the file
//! goes into one mesh, as Mitsuba's OBJ reader does.
//!
//! Most files number texture coordinates and normals as their positions (`f 3/3/3` or `f 3//3`)
//! or give none; their faces then index the positions directly and nothing else is kept. Only
//! when a corner's `vt` or `vn` index differs from its position's is each distinct
//! (v, vt, vn) triple made a vertex of its own, through a hash map: reading then peaks at 69
//! bytes per triangle on the 5 M-triangle knot with its normals numbered apart, against 23 when
//! they are not (the file's lists, the triangles' normal indices and the map, freed before
//! the BVH is built, whose own peak is 91; BENCHMARKS.md, "Big meshes"). Numbers with at most 7 significant digits and a small exponent are converted
//! exactly by Clinger's fast path (an integer over a power of ten, both exact in f32); others go
//! through the standard library's correctly rounded parser.

use super::{MeshError, TriangleMesh};
use crate::math::{Vec2, Vec3};
use std::collections::HashMap;
use std::io::{BufRead, Read};
use std::path::Path;

const NONE: u32 = u32::MAX;

/// Reads an OBJ file into one triangulated mesh. Vertex normals and texture coordinates are
/// kept when every face corner has them (v flipped, as Mitsuba does).
pub fn load_obj(path: &Path) -> Result<TriangleMesh, MeshError> {
    let shown = path.display().to_string();
    let file = std::fs::File::open(path).map_err(|e| MeshError::Read {
        path: shown.clone(),
        format: "OBJ",
        message: e.to_string(),
    })?;
    let size = file.metadata().map_or(1 << 20, |m| m.len());
    read_obj(std::io::BufReader::with_capacity(size.clamp(1 << 13, 1 << 20) as usize, file)).map_err(|e| match e {
        ObjError::Io(e) => MeshError::Read { path: shown, format: "OBJ", message: e.to_string() },
        ObjError::Bad(message) => MeshError::Invalid { path: shown, format: "OBJ", message },
    })
}

/// Reads an OBJ mesh from memory (tests and the fuzz target).
pub fn parse_obj(bytes: &[u8]) -> Result<TriangleMesh, String> {
    read_obj(bytes).map_err(|e| match e {
        ObjError::Io(e) => e.to_string(),
        ObjError::Bad(m) => m,
    })
}

enum ObjError {
    Io(std::io::Error),
    Bad(String),
}

/// The file's lists and the faces read so far.
#[derive(Default)]
struct Reader {
    positions: Vec<Vec3>,
    texcoords: Vec<Vec2>,
    normals: Vec<Vec3>,
    /// Position indices of each triangle.
    tris: Vec<[u32; 3]>,
    /// Texture-coordinate and normal indices of each triangle, kept from the first corner whose
    /// index differs from its position's (earlier triangles' are their position indices).
    tri_vt: Option<Vec<[u32; 3]>>,
    tri_vn: Option<Vec<[u32; 3]>>,
    /// Whether every corner so far has a texture coordinate, and a normal.
    all_vt: bool,
    all_vn: bool,
}

fn read_obj<R: BufRead>(mut input: R) -> Result<TriangleMesh, ObjError> {
    let mut r = Reader { all_vt: true, all_vn: true, ..Reader::default() };
    let mut line = Vec::with_capacity(256);
    let mut corners: Vec<[u32; 3]> = Vec::with_capacity(16);
    let mut line_no = 0u64;
    loop {
        line.clear();
        // Lines are read whole; a 1 MiB line is not an OBJ line.
        let n = input.by_ref().take(1 << 20).read_until(b'\n', &mut line).map_err(ObjError::Io)?;
        if n == 0 {
            break;
        }
        line_no += 1;
        let at = |m: &str| ObjError::Bad(format!("line {line_no}: {m}"));
        let mut words = line.split(|b| b.is_ascii_whitespace()).filter(|w| !w.is_empty());
        let Some(key) = words.next() else { continue };
        match key {
            b"v" => {
                let p = three(&mut words).ok_or_else(|| at("a vertex position (v) is not three numbers"))?;
                if !p.is_finite() {
                    return Err(at("a vertex position (v) is not finite"));
                }
                r.positions.push(p);
            }
            b"vn" => r.normals.push(three(&mut words).ok_or_else(|| at("a vertex normal (vn) is not three numbers"))?),
            b"vt" => {
                let u = words.next().and_then(number).ok_or_else(|| at("a texture coordinate (vt) is not a number"))?;
                let v = match words.next() {
                    Some(w) => number(w).ok_or_else(|| at("a texture coordinate (vt) is not a number"))?,
                    None => 0.0,
                };
                // OBJ's v runs up an image; Mitsuba's OBJ reader flips it (`flip_tex_coords`).
                r.texcoords.push(Vec2::new(u, 1.0 - v));
            }
            b"f" => {
                corners.clear();
                for w in words {
                    corners.push(r.corner(w).map_err(|m| at(&m))?);
                }
                if corners.len() < 3 {
                    return Err(at("a face has fewer than three vertices"));
                }
                for k in 1..corners.len() - 1 {
                    r.push([corners[0], corners[k], corners[k + 1]]);
                }
            }
            _ => {}
        }
    }
    r.finish()
}

/// Three numbers (more are ignored: `v x y z w` or vertex colours).
fn three<'a>(words: &mut impl Iterator<Item = &'a [u8]>) -> Option<Vec3> {
    Some(Vec3::new(number(words.next()?)?, number(words.next()?)?, number(words.next()?)?))
}

/// A decimal number as f32, correctly rounded.
#[inline]
pub(crate) fn number(w: &[u8]) -> Option<f32> {
    fast_number(w).or_else(|| std::str::from_utf8(w).ok()?.parse().ok())
}

/// Clinger's fast path: `[-+]digits[.digits][e[-+]digits]` with at most 7 significant digits
/// and a power of ten within 10^±10 is an exact f32 integer times or over an exact power of
/// ten, so one multiplication or division rounds it correctly. Anything else is `None`.
#[inline]
fn fast_number(w: &[u8]) -> Option<f32> {
    const POW10: [f32; 11] = [1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10];
    let (neg, mut i) = match w.first()? {
        b'-' => (true, 1),
        b'+' => (false, 1),
        _ => (false, 0),
    };
    let (mut mantissa, mut digits, mut exp) = (0u32, 0u32, 0i32);
    let mut any = false;
    while let Some(&c) = w.get(i).filter(|c| c.is_ascii_digit()) {
        any = true;
        if mantissa > 0 || c != b'0' {
            digits += 1;
        }
        mantissa = mantissa.wrapping_mul(10).wrapping_add((c - b'0') as u32);
        i += 1;
    }
    if w.get(i) == Some(&b'.') {
        i += 1;
        while let Some(&c) = w.get(i).filter(|c| c.is_ascii_digit()) {
            any = true;
            if mantissa > 0 || c != b'0' {
                digits += 1;
            }
            mantissa = mantissa.wrapping_mul(10).wrapping_add((c - b'0') as u32);
            exp -= 1;
            i += 1;
        }
    }
    if !any || digits > 7 {
        return None;
    }
    if matches!(w.get(i), Some(b'e' | b'E')) {
        i += 1;
        let (eneg, start) = match w.get(i) {
            Some(b'-') => (true, i + 1),
            Some(b'+') => (false, i + 1),
            _ => (false, i),
        };
        i = start;
        let mut e = 0i32;
        while let Some(&c) = w.get(i).filter(|c| c.is_ascii_digit()) {
            e = (e * 10 + (c - b'0') as i32).min(1000);
            i += 1;
        }
        if i == start {
            return None;
        }
        exp += if eneg { -e } else { e };
    }
    if i != w.len() || exp.unsigned_abs() > 10 {
        return None;
    }
    let m = mantissa as f32;
    let v = if exp >= 0 { m * POW10[exp as usize] } else { m / POW10[(-exp) as usize] };
    // A product past 2^24 * 10^10 cannot happen: 7 digits times 10^10 < f32::MAX.
    Some(if neg { -v } else { v })
}

/// A 1-based (or negative, from the end) OBJ index into a list of `len`, as a 0-based index.
fn index(w: &[u8], len: usize, what: &str) -> Result<u32, String> {
    let text = std::str::from_utf8(w).unwrap_or("?");
    let i: i64 = text.parse().map_err(|_| format!("a face's {what} index `{text}` is not a whole number"))?;
    let k = if i > 0 { i - 1 } else { len as i64 + i };
    if i == 0 || k < 0 || k >= len as i64 {
        return Err(format!("a face refers to {what} {i} of {len}"));
    }
    Ok(k as u32)
}

impl Reader {
    /// A face corner `v`, `v/vt`, `v//vn` or `v/vt/vn` as (v, vt, vn) indices (`NONE` for none).
    fn corner(&self, w: &[u8]) -> Result<[u32; 3], String> {
        let mut parts = w.splitn(3, |&b| b == b'/');
        let v = index(parts.next().unwrap_or(b""), self.positions.len(), "vertex")?;
        let vt = match parts.next() {
            Some(t) if !t.is_empty() => index(t, self.texcoords.len(), "texture coordinate")?,
            _ => NONE,
        };
        let vn = match parts.next() {
            Some(n) if !n.is_empty() => index(n, self.normals.len(), "normal")?,
            _ => NONE,
        };
        Ok([v, vt, vn])
    }

    fn push(&mut self, c: [[u32; 3]; 3]) {
        let (p, t, n) = (c.map(|c| c[0]), c.map(|c| c[1]), c.map(|c| c[2]));
        self.all_vt &= t.iter().all(|&i| i != NONE);
        self.all_vn &= n.iter().all(|&i| i != NONE);
        Self::note(&mut self.tri_vt, &self.tris, self.all_vt && t != p, t);
        Self::note(&mut self.tri_vn, &self.tris, self.all_vn && n != p, n);
        self.tris.push(p);
    }

    /// Records a triangle's attribute indices once any differs from its position indices.
    fn note(list: &mut Option<Vec<[u32; 3]>>, tris: &Vec<[u32; 3]>, differs: bool, idx: [u32; 3]) {
        if list.is_none() && differs {
            let mut l = Vec::with_capacity(tris.capacity());
            l.extend_from_slice(tris);
            *list = Some(l);
        }
        if let Some(l) = list {
            l.push(idx);
        }
    }

    fn finish(self) -> Result<TriangleMesh, ObjError> {
        if self.tris.is_empty() {
            return Err(ObjError::Bad("it has no faces (f lines)".into()));
        }
        let tri_vt = if self.all_vt { self.tri_vt } else { None };
        let tri_vn = if self.all_vn { self.tri_vn } else { None };
        if tri_vt.is_none() && tri_vn.is_none() {
            // Attributes numbered as the positions: index the positions directly.
            let n = self.positions.len();
            fn fit<T: Copy + Default>(keep: bool, mut list: Vec<T>, n: usize) -> Option<Vec<T>> {
                keep.then(|| {
                    list.resize(n, T::default());
                    list.shrink_to_fit();
                    list
                })
            }
            let mut mesh = TriangleMesh {
                uvs: fit(self.all_vt, self.texcoords, n),
                normals: fit(self.all_vn, self.normals, n),
                positions: self.positions,
                indices: self.tris,
                attributes: Vec::new(),
            };
            mesh.shrink_to_fit();
            return Ok(mesh);
        }
        // Distinct (v, vt, vn) triples become vertices, numbered in order of first use; most
        // files have about one per position.
        let n = self.positions.len();
        let mut map: HashMap<[u32; 3], u32> = HashMap::with_capacity(n);
        let mut mesh = TriangleMesh {
            uvs: self.all_vt.then(|| Vec::with_capacity(n)),
            normals: self.all_vn.then(|| Vec::with_capacity(n)),
            indices: Vec::with_capacity(self.tris.len()),
            positions: Vec::with_capacity(n),
            attributes: Vec::new(),
        };
        for (k, p) in self.tris.iter().enumerate() {
            let t = tri_vt.as_ref().map_or(*p, |l| l[k]);
            let n = tri_vn.as_ref().map_or(*p, |l| l[k]);
            let mut out = [0u32; 3];
            for c in 0..3 {
                let key = [p[c], if self.all_vt { t[c] } else { NONE }, if self.all_vn { n[c] } else { NONE }];
                out[c] = *map.entry(key).or_insert_with(|| {
                    mesh.positions.push(self.positions[key[0] as usize]);
                    if let Some(uvs) = &mut mesh.uvs {
                        uvs.push(self.texcoords[key[1] as usize]);
                    }
                    if let Some(ns) = &mut mesh.normals {
                        ns.push(self.normals[key[2] as usize]);
                    }
                    (mesh.positions.len() - 1) as u32
                });
            }
            mesh.indices.push(out);
        }
        mesh.shrink_to_fit();
        Ok(mesh)
    }
}

#[cfg(test)]
#[path = "obj_tests.rs"]
mod tests;
