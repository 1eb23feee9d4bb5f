//! Triangle meshes: indexed vertex arrays, read from OBJ, PLY or Mitsuba `serialized` files
//! (`TriangleMesh::load`, the one reader both scene formats use) or generated procedurally.

mod obj;
mod ply;
mod serialized;

pub use obj::parse_obj;
pub use ply::{load_ply, parse_ply};
pub use serialized::{Serialized, load_serialized, parse_serialized};

use super::Triangle;
use crate::geometry::Transform;
use crate::math::{Vec2, Vec3};
use std::path::Path;

#[derive(Clone, Debug, Default)]
pub struct TriangleMesh {
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals, when the file gave them (or a generator computed them).
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex texture coordinates, stored as Mitsuba stores them (v = 0 is the top row of an
    /// image texture; OBJ files are flipped on reading, PLY files are not).
    pub uvs: Option<Vec<Vec2>>,
    pub indices: Vec<[u32; 3]>,
    /// Named per-vertex or per-face values the file gave (PLY colours and other properties),
    /// read by `mesh_attribute` textures.
    pub attributes: Vec<MeshAttribute>,
}

/// A mesh attribute as Mitsuba names it: `vertex_color`, `face_color`, `vertex_<name>` or
/// `face_<name>`, with 1 to 4 values per vertex (interpolated across each triangle) or per
/// triangle (a polygon's value repeated on each of its triangles).
#[derive(Clone, Debug, PartialEq)]
pub struct MeshAttribute {
    pub name: String,
    pub per_face: bool,
    /// Values per vertex or face, 1 to 4.
    pub channels: usize,
    /// `channels` values per vertex or triangle, in order.
    pub values: Vec<f32>,
}

impl MeshAttribute {
    /// The value on triangle `tri` (of `indices`) at barycentrics `b`, as a colour: one channel
    /// is a grey, two give (x, y, 0), a fourth (alpha) is dropped.
    #[inline]
    pub fn eval(&self, indices: &[[u32; 3]], tri: usize, b: [f32; 3]) -> crate::math::Color {
        let c = self.channels;
        let at = |i: usize| -> [f32; 3] {
            let v = &self.values[i * c..i * c + c];
            match c {
                1 => [v[0]; 3],
                2 => [v[0], v[1], 0.0],
                _ => [v[0], v[1], v[2]],
            }
        };
        let v = if self.per_face {
            at(tri)
        } else {
            let t = indices[tri];
            let (a, p, q) = (at(t[0] as usize), at(t[1] as usize), at(t[2] as usize));
            [0, 1, 2].map(|k| a[k] * b[0] + p[k] * b[1] + q[k] * b[2])
        };
        crate::math::Color::new(v[0], v[1], v[2])
    }
}

/// Why a mesh could not be loaded, naming the file, its format and the cause; the scene loader
/// adds the scene file and line.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    #[error("cannot read {format} mesh `{path}`: {message}")]
    Read { path: String, format: &'static str, message: String },
    #[error("{format} mesh `{path}`: {message}")]
    Invalid { path: String, format: &'static str, message: String },
    #[error("mesh `{path}`: unknown format (expected a .obj, .ply or .serialized file)")]
    Format { path: String },
}

/// The mesh formats caustic reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    Obj,
    Ply,
    /// Mitsuba's `serialized` (its first mesh).
    Serialized,
}

impl MeshFormat {
    /// The format a file name's extension names.
    pub fn of(path: &Path) -> Option<Self> {
        match path.extension()?.to_str()?.to_ascii_lowercase().as_str() {
            "obj" => Some(MeshFormat::Obj),
            "ply" => Some(MeshFormat::Ply),
            "serialized" => Some(MeshFormat::Serialized),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            MeshFormat::Obj => "OBJ",
            MeshFormat::Ply => "PLY",
            MeshFormat::Serialized => "serialized",
        }
    }
}

impl TriangleMesh {
    /// Reads an OBJ, PLY or `serialized` file (its first mesh), chosen by its extension.
    pub fn load(path: &Path) -> Result<Self, MeshError> {
        match MeshFormat::of(path) {
            Some(MeshFormat::Obj) => Self::load_obj(path),
            Some(MeshFormat::Ply) => load_ply(path),
            Some(MeshFormat::Serialized) => load_serialized(path, 0).map(|s| s.mesh),
            None => Err(MeshError::Format { path: path.display().to_string() }),
        }
    }

    /// Loads every object of an OBJ file into one triangulated mesh (`obj`): polygons fanned,
    /// vertex normals and texture coordinates kept when every face corner has them. Material
    /// libraries are not read.
    pub fn load_obj(path: &Path) -> Result<Self, MeshError> {
        obj::load_obj(path)
    }

    /// Gives a mesh without vertex normals smooth ones, as Mitsuba does: each vertex gets the
    /// average of the unit normals of the triangles around it, weighted by their angles at the
    /// vertex (Thuermer and Wuethrich 1998), which does not depend on how a face was split into
    /// triangles. Degenerate triangles add nothing; a vertex with none gets no normal (its
    /// triangles, all degenerate, are never hit). Winding decides the side, as for face normals.
    pub fn ensure_vertex_normals(&mut self) {
        if self.normals.is_some() {
            return;
        }
        let mut normals = vec![Vec3::ZERO; self.positions.len()];
        for tri in &self.indices {
            let p = tri.map(|i| self.positions[i as usize]);
            let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
            if n == Vec3::ZERO {
                continue;
            }
            for k in 0..3 {
                let (a, b) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
                let angle = a.angle_between(b);
                if angle.is_finite() {
                    normals[tri[k] as usize] += n * angle;
                }
            }
        }
        for n in &mut normals {
            *n = n.normalize_or_zero();
        }
        self.normals = Some(normals);
    }

    /// A (p, q) torus knot: a tube of radius `tube` swept along a knot that winds p times around
    /// the axis of a torus of radius `radius` and q times through its hole. It has
    /// 2 * segments * sides triangles and smooth normals, a mesh made by code with no download.
    pub fn torus_knot(p: u32, q: u32, radius: f32, tube: f32, segments: u32, sides: u32) -> Self {
        let (pf, qf) = (p as f32, q as f32);
        let curve = |s: f32| {
            let phi = s * std::f32::consts::TAU;
            let r = radius * (0.6 + 0.4 * (qf * phi).cos());
            Vec3::new(r * (pf * phi).cos(), radius * 0.4 * (qf * phi).sin(), r * (pf * phi).sin())
        };
        let mut positions = Vec::with_capacity((segments * sides) as usize);
        let mut normals = Vec::with_capacity(positions.capacity());
        for i in 0..segments {
            let s = i as f32 / segments as f32;
            let c = curve(s);
            let ds = 1e-4;
            let tangent = (curve(s + ds) - curve(s - ds)).normalize();
            let side = tangent.cross(c + tangent).normalize_or(tangent.any_orthonormal_vector());
            let side = (side - tangent * side.dot(tangent)).normalize();
            let up = tangent.cross(side);
            for j in 0..sides {
                let a = j as f32 / sides as f32 * std::f32::consts::TAU;
                let n = side * a.cos() + up * a.sin();
                positions.push(c + n * tube);
                normals.push(n);
            }
        }
        let mut indices = Vec::with_capacity((2 * segments * sides) as usize);
        for i in 0..segments {
            let i1 = (i + 1) % segments;
            for j in 0..sides {
                let j1 = (j + 1) % sides;
                let v = |a: u32, b: u32| a * sides + b;
                indices.push([v(i, j), v(i1, j), v(i1, j1)]);
                indices.push([v(i, j), v(i1, j1), v(i, j1)]);
            }
        }
        TriangleMesh { positions, normals: Some(normals), uvs: None, indices, attributes: Vec::new() }
    }

    /// Bytes held by the mesh's arrays.
    pub fn memory_bytes(&self) -> usize {
        self.positions.capacity() * size_of::<Vec3>()
            + self.normals.as_ref().map_or(0, |n| n.capacity() * size_of::<Vec3>())
            + self.uvs.as_ref().map_or(0, |u| u.capacity() * size_of::<Vec2>())
            + self.indices.capacity() * size_of::<[u32; 3]>()
            + self.attributes.iter().map(|a| a.values.capacity() * size_of::<f32>()).sum::<usize>()
    }

    /// Gives back spare capacity (a mesh is read once and kept for the whole render).
    pub fn shrink_to_fit(&mut self) {
        self.positions.shrink_to_fit();
        self.indices.shrink_to_fit();
        if let Some(n) = &mut self.normals {
            n.shrink_to_fit();
        }
        if let Some(u) = &mut self.uvs {
            u.shrink_to_fit();
        }
    }

    /// The mesh with positions and normals moved by `t`.
    pub fn transformed(mut self, t: &Transform) -> Self {
        for p in &mut self.positions {
            *p = t.point(*p);
        }
        if let Some(ns) = &mut self.normals {
            for n in ns {
                *n = t.normal(*n).normalize_or_zero();
            }
        }
        self
    }

    /// Interpolated, normalised vertex normal; `None` without normals or where they cancel.
    #[inline]
    pub fn shading_normal(&self, tri: usize, b0: f32, b1: f32, b2: f32) -> Option<Vec3> {
        let ns = self.normals.as_ref()?;
        let [i0, i1, i2] = *self.indices.get(tri)?;
        let n = ns[i0 as usize] * b0 + ns[i1 as usize] * b1 + ns[i2 as usize] * b2;
        let n = n.normalize_or_zero();
        (n != Vec3::ZERO).then_some(n)
    }

    /// Texture coordinates of the three vertices of triangle `tri`, when the mesh has them.
    #[inline]
    pub fn vertex_uvs(&self, tri: usize) -> Option<[Vec2; 3]> {
        let uvs = self.uvs.as_ref()?;
        let [i0, i1, i2] = *self.indices.get(tri)?;
        Some([uvs[i0 as usize], uvs[i1 as usize], uvs[i2 as usize]])
    }

    /// The mesh's triangles for the BVH, tagged with `mesh_id`; zero-area triangles are skipped
    /// (they can never be hit and would only slow traversal). Returns them and the skipped count.
    pub fn triangles(&self, mesh_id: u32) -> (Vec<Triangle>, usize) {
        let mut out = Vec::with_capacity(self.indices.len());
        let mut skipped = 0;
        for (k, idx) in self.indices.iter().enumerate() {
            let p = idx.map(|i| self.positions[i as usize]);
            let t = Triangle { p, mesh: mesh_id, index: k as u32 };
            if t.area() > 0.0 {
                out.push(t);
            } else {
                skipped += 1;
            }
        }
        (out, skipped)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn torus_knot_counts_and_closed_normals() {
        let m = TriangleMesh::torus_knot(2, 3, 1.0, 0.2, 100, 12);
        assert_eq!(m.indices.len(), 2 * 100 * 12);
        assert_eq!(m.positions.len(), 100 * 12);
        let ns = m.normals.as_ref().unwrap();
        assert!(ns.iter().all(|n| (n.length() - 1.0).abs() < 1e-4));
        let (tris, skipped) = m.triangles(0);
        assert_eq!(skipped, 0);
        // Face normals agree with the outward vertex normals.
        let agree = tris
            .iter()
            .filter(|t| {
                let fng = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]);
                let vn = m.shading_normal(t.index as usize, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0).unwrap();
                fng.dot(vn) > 0.0
            })
            .count();
        assert!(agree == tris.len() || agree == 0, "inconsistent winding: {agree} of {}", tris.len());
    }
}
