//! PLY meshes (ASCII and binary, little- and big-endian) read with `ply-rs-bw`.

use super::{MeshError, TriangleMesh};
use crate::math::{Vec2, Vec3};
use std::path::Path;

/// Loads a PLY mesh (ASCII or binary): vertex x, y, z (and nx, ny, nz when present) and faces
/// of any size, fanned into triangles.
pub fn load_ply(path: &Path) -> Result<TriangleMesh, MeshError> {
    use ply_rs_bw::parser::Parser;
    use ply_rs_bw::ply::{DefaultElement, Property};
    let shown = path.display().to_string();
    let read = |message: String| MeshError::Read { path: shown.clone(), format: "PLY", message };
    let file = std::fs::File::open(path).map_err(|e| read(e.to_string()))?;
    let mut reader = std::io::BufReader::new(file);
    let ply = Parser::<DefaultElement>::new().read_ply(&mut reader).map_err(|e| read(e.to_string()))?;
    let num = |p: &Property| -> Option<f64> {
        Some(match p {
            Property::Char(v) => *v as f64,
            Property::UChar(v) => *v as f64,
            Property::Short(v) => *v as f64,
            Property::UShort(v) => *v as f64,
            Property::Int(v) => *v as f64,
            Property::UInt(v) => *v as f64,
            Property::Float(v) => *v as f64,
            Property::Double(v) => *v,
            _ => return None,
        })
    };
    let list = |p: &Property| -> Option<Vec<i64>> {
        Some(match p {
            Property::ListChar(v) => v.iter().map(|&x| x as i64).collect(),
            Property::ListUChar(v) => v.iter().map(|&x| x as i64).collect(),
            Property::ListShort(v) => v.iter().map(|&x| x as i64).collect(),
            Property::ListUShort(v) => v.iter().map(|&x| x as i64).collect(),
            Property::ListInt(v) => v.iter().map(|&x| x as i64).collect(),
            Property::ListUInt(v) => v.iter().map(|&x| x as i64).collect(),
            _ => return None,
        })
    };
    let invalid = |message: String| MeshError::Invalid { path: shown.clone(), format: "PLY", message };
    let vertices = ply.payload.get("vertex").ok_or_else(|| invalid("no `vertex` element".into()))?;
    let mut positions = Vec::with_capacity(vertices.len());
    let mut normals = Vec::new();
    let has_normals =
        vertices.first().is_some_and(|v| v.contains_key("nx") && v.contains_key("ny") && v.contains_key("nz"));
    // Texture coordinates go by several names; Mitsuba reads u/v, texture_u/texture_v and s/t.
    let uv_names = [("u", "v"), ("texture_u", "texture_v"), ("s", "t")]
        .into_iter()
        .find(|(u, v)| vertices.first().is_some_and(|e| e.contains_key(*u) && e.contains_key(*v)));
    let mut uvs = Vec::new();
    for (i, v) in vertices.iter().enumerate() {
        let get = |k: &str| v.get(k).and_then(num);
        let (Some(x), Some(y), Some(z)) = (get("x"), get("y"), get("z")) else {
            return Err(invalid(format!("vertex {i} has no numeric x, y, z")));
        };
        let p = Vec3::new(x as f32, y as f32, z as f32);
        if !p.is_finite() {
            return Err(invalid(format!("vertex {i} is not finite")));
        }
        positions.push(p);
        if has_normals {
            // Normalised when the mesh is transformed.
            normals.push(Vec3::new(
                get("nx").unwrap_or(0.0) as f32,
                get("ny").unwrap_or(0.0) as f32,
                get("nz").unwrap_or(0.0) as f32,
            ));
        }
        if let Some((u, v)) = uv_names {
            uvs.push(Vec2::new(get(u).unwrap_or(0.0) as f32, get(v).unwrap_or(0.0) as f32));
        }
    }
    let faces = ply.payload.get("face").ok_or_else(|| invalid("no `face` element".into()))?;
    let mut indices = Vec::with_capacity(faces.len());
    for (i, f) in faces.iter().enumerate() {
        let idx = f
            .get("vertex_indices")
            .or_else(|| f.get("vertex_index"))
            .and_then(list)
            .ok_or_else(|| invalid(format!("face {i} has no vertex_indices list")))?;
        if let Some(bad) = idx.iter().find(|&&k| k < 0 || k as usize >= positions.len()) {
            return Err(invalid(format!("face {i} refers to vertex {bad} of {}", positions.len())));
        }
        for k in 1..idx.len().saturating_sub(1) {
            indices.push([idx[0] as u32, idx[k] as u32, idx[k + 1] as u32]);
        }
    }
    if indices.is_empty() {
        return Err(invalid("it has no faces".into()));
    }
    Ok(TriangleMesh { positions, normals: has_normals.then_some(normals), uvs: uv_names.map(|_| uvs), indices })
}
