//! The `serialized` reader against files written here (both versions and precisions, several
//! meshes), and its robustness: every truncation is an error, damaged and random bytes never
//! panic.

use super::*;
use flate2::Compression;
use flate2::write::ZlibEncoder;
use proptest::prelude::*;
use std::io::Write;

/// What a test mesh holds.
struct Spec {
    positions: Vec<[f64; 3]>,
    normals: Option<Vec<[f64; 3]>>,
    uvs: Option<Vec<[f64; 2]>>,
    colors: bool,
    indices: Vec<[u32; 3]>,
    face_normals: bool,
    name: &'static str,
}

fn quad(z: f64, normals: bool, uvs: bool) -> Spec {
    Spec {
        positions: vec![[0.0, 0.0, z], [1.0, 0.0, z], [1.0, 1.0, z], [0.0, 1.0, z]],
        normals: normals.then(|| vec![[0.0, 0.0, 1.0]; 4]),
        uvs: uvs.then(|| vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 0.25]]),
        colors: false,
        indices: vec![[0, 1, 2], [0, 2, 3]],
        face_normals: false,
        name: "quad",
    }
}

/// A file of `meshes` in format `version` (3 or 4), numbers in double precision or not.
fn write(meshes: &[Spec], version: u16, double: bool) -> Vec<u8> {
    let mut out = Vec::new();
    let mut offsets = Vec::new();
    for m in meshes {
        offsets.push(out.len() as u64);
        out.extend(MAGIC.to_le_bytes());
        out.extend(version.to_le_bytes());
        let mut body = Vec::new();
        let flags = if m.normals.is_some() { HAS_NORMALS } else { 0 }
            | if m.uvs.is_some() { HAS_TEXCOORDS } else { 0 }
            | if m.colors { HAS_COLORS } else { 0 }
            | if m.face_normals { FACE_NORMALS } else { 0 }
            | if double { DOUBLE_PRECISION } else { 0x1000 };
        body.extend(flags.to_le_bytes());
        if version == 4 {
            body.extend(m.name.as_bytes());
            body.push(0);
        }
        body.extend((m.positions.len() as u64).to_le_bytes());
        body.extend((m.indices.len() as u64).to_le_bytes());
        let mut num = |x: f64| {
            if double { body.extend(x.to_le_bytes()) } else { body.extend((x as f32).to_le_bytes()) }
        };
        m.positions.iter().flatten().for_each(|&x| num(x));
        m.normals.iter().flatten().flatten().for_each(|&x| num(x));
        m.uvs.iter().flatten().flatten().for_each(|&x| num(x));
        if m.colors {
            m.positions.iter().flatten().for_each(|_| num(0.5));
        }
        m.indices.iter().flatten().for_each(|&i| body.extend(i.to_le_bytes()));
        let mut z = ZlibEncoder::new(Vec::new(), Compression::default());
        z.write_all(&body).unwrap();
        out.extend(z.finish().unwrap());
    }
    for o in &offsets {
        if version == 4 {
            out.extend(o.to_le_bytes());
        } else {
            out.extend((*o as u32).to_le_bytes());
        }
    }
    out.extend((meshes.len() as u32).to_le_bytes());
    out
}

/// Files of every version and precision, with and without normals, uv, colours.
fn corpus() -> Vec<Vec<u8>> {
    let mut files = Vec::new();
    for version in [3, 4] {
        for double in [false, true] {
            let mut colored = quad(2.0, false, true);
            colored.colors = true;
            files.push(write(&[quad(0.0, true, true), quad(1.0, false, false), colored], version, double));
        }
    }
    files
}

#[test]
fn reads_every_version_precision_and_index() {
    for version in [3u16, 4] {
        for double in [false, true] {
            let mut flat = quad(3.0, false, false);
            flat.face_normals = true;
            let mut colored = quad(2.0, true, false);
            colored.colors = true;
            let bytes = write(&[quad(0.5, true, true), flat, colored], version, double);
            let a = parse_serialized(&bytes, 0).unwrap();
            assert_eq!((a.count, a.face_normals), (3, false));
            assert_eq!(a.name, if version == 4 { "quad" } else { "" });
            assert_eq!(a.mesh.positions[2], Vec3::new(1.0, 1.0, 0.5));
            assert_eq!(a.mesh.normals.as_ref().unwrap()[3], Vec3::Z);
            // Texture coordinates as written: no flip.
            assert_eq!(a.mesh.uvs.as_ref().unwrap()[3], Vec2::new(0.0, 0.25));
            assert_eq!(a.mesh.indices, vec![[0, 1, 2], [0, 2, 3]]);
            let b = parse_serialized(&bytes, 1).unwrap();
            assert!(b.face_normals && b.mesh.normals.is_none() && b.mesh.uvs.is_none());
            assert_eq!(b.mesh.positions[0], Vec3::new(0.0, 0.0, 3.0));
            // Colours are skipped.
            let c = parse_serialized(&bytes, 2).unwrap();
            assert_eq!(c.mesh.positions[1], Vec3::new(1.0, 0.0, 2.0));
            assert_eq!(c.mesh.normals.as_ref().unwrap().len(), 4);
            let e = parse_serialized(&bytes, 3).unwrap_err();
            assert!(e.contains("out of range") && e.contains("3 meshes"), "{e}");
        }
    }
}

#[test]
fn bad_content_is_named() {
    let mut bad_index = quad(0.0, false, false);
    bad_index.indices[1][2] = 4;
    let e = parse_serialized(&write(&[bad_index], 4, false), 0).unwrap_err();
    assert!(e.contains("triangle 1 refers to vertex 4 of 4"), "{e}");
    let mut nan = quad(0.0, false, false);
    nan.positions[2][1] = f64::NAN;
    let e = parse_serialized(&write(&[nan], 4, true), 0).unwrap_err();
    assert!(e.contains("vertex 2 is not finite"), "{e}");
    let mut empty = quad(0.0, false, false);
    empty.indices.clear();
    assert!(parse_serialized(&write(&[empty], 4, false), 0).unwrap_err().contains("nothing to render"));
    // A damaged checksum (the last 4 bytes of the stream, before the 12-byte table).
    let mut sum = write(&[quad(0.0, false, false)], 4, false);
    let k = sum.len() - 13;
    sum[k] ^= 1;
    let e = parse_serialized(&sum, 0).unwrap_err();
    assert!(e.contains("damaged"), "{e}");
    let mut wrong = write(&[quad(0.0, false, false)], 4, false);
    wrong[2] = 5;
    assert!(parse_serialized(&wrong, 0).unwrap_err().contains("version 5"));
    wrong[0] = 0;
    assert!(parse_serialized(&wrong, 0).unwrap_err().contains("0x041C"));
}

/// A header claiming a billion vertices in a tiny file is refused before anything is
/// allocated.
#[test]
fn huge_counts_are_refused_before_allocating() {
    let mut body = Vec::new();
    body.extend(0x1000u32.to_le_bytes());
    body.push(0);
    body.extend((1u64 << 30).to_le_bytes());
    body.extend((1u64 << 30).to_le_bytes());
    let mut z = ZlibEncoder::new(Vec::new(), Compression::default());
    z.write_all(&body).unwrap();
    let mut file = vec![0x1C, 0x04, 4, 0];
    file.extend(z.finish().unwrap());
    file.extend(0u64.to_le_bytes());
    file.extend(1u32.to_le_bytes());
    let e = parse_serialized(&file, 0).unwrap_err();
    assert!(e.contains("more than"), "{e}");
}

#[test]
fn truncation_at_every_length_is_an_error() {
    for bytes in corpus() {
        for len in 0..bytes.len() {
            for index in 0..3 {
                assert!(
                    parse_serialized(&bytes[..len], index).is_err(),
                    "cut at {len} of {} read as mesh {index}",
                    bytes.len()
                );
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    /// Flipped bytes give an error or a mesh whose indices are in range and whose numbers are
    /// finite; never a panic.
    #[test]
    fn damaged_bytes_never_panic(file in 0usize..4, edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..8), index in 0u32..3) {
        let mut bytes = corpus().swap_remove(file);
        for (at, value) in edits {
            let k = at.index(bytes.len());
            bytes[k] = value;
        }
        if let Ok(s) = parse_serialized(&bytes, index) {
            let n = s.mesh.positions.len() as u32;
            prop_assert!(s.mesh.indices.iter().flatten().all(|&i| i < n));
            prop_assert!(s.mesh.positions.iter().all(|p| p.is_finite()));
        }
    }

    /// Random bytes behind a valid header, with or without a plausible table, never panic.
    #[test]
    fn random_bytes_never_panic(body in prop::collection::vec(any::<u8>(), 0..600), version in 3u16..5, table in any::<bool>()) {
        let mut bytes = vec![0x1C, 0x04];
        bytes.extend(version.to_le_bytes());
        bytes.extend(body);
        if table {
            bytes.extend(if version == 4 { 0u64.to_le_bytes().to_vec() } else { 0u32.to_le_bytes().to_vec() });
            bytes.extend(1u32.to_le_bytes());
        }
        let _ = parse_serialized(&bytes, 0);
    }
}

/// Found by the `serialized` fuzz target: a table whose last offset is 2^64 - 1 passed the
/// check `offset + 4 <= table start` by wrapping around, and mesh 1 was then sliced up to it.
#[test]
fn regression_offset_near_the_largest_integer() {
    let bytes: &[u8] = &[
        0x1c, 0x04, 0x04, 0x00, 0x78, 0x9c, 0xad, 0x90, 0xc9, 0x09, 0x00, 0x20, 0x10, 0x03, 0xc7, 0xa3, 0x10, 0x3b,
        0xb1, 0x16, 0xc1, 0x06, 0x7c, 0xd8, 0xa7, 0xa5, 0x58, 0x82, 0xd7, 0xc3, 0x97, 0x07, 0x62, 0x60, 0x59, 0x92,
        0x40, 0x08, 0x51, 0x06, 0x42, 0x74, 0x1e, 0xcd, 0x80, 0xe4, 0x06, 0xd9, 0xee, 0xf4, 0x93, 0xff, 0x9a, 0xfb,
        0x5b, 0x5f, 0xf5, 0x4d, 0x9d, 0x0b, 0xe6, 0x1e, 0xed, 0xab, 0x7a, 0x05, 0x69, 0x4b, 0x0f, 0xf1, 0x1c, 0x04,
        0x04, 0x00, 0x78, 0x9c, 0x8d, 0x8d, 0xc9, 0x09, 0x00, 0x20, 0x0c, 0x04, 0xc7, 0xa3, 0x10, 0x3b, 0xb1, 0x16,
        0xc1, 0x06, 0x7c, 0xd8, 0xb7, 0x25, 0xa8, 0xf8, 0x30, 0x8f, 0x84, 0x0c, 0x2c, 0x03, 0xcb, 0xc2, 0x52, 0x60,
        0xcc, 0xd6, 0xc9, 0x3c, 0x22, 0x16, 0xeb, 0x4a, 0x6b, 0xbd, 0x6f, 0x17, 0xbe, 0xbf, 0xeb, 0x74, 0xb2, 0x01,
        0x48, 0x12, 0x0b, 0x52, 0x1c, 0x04, 0x04, 0x00, 0x78, 0x9c, 0xb5, 0x90, 0xcb, 0x0d, 0x00, 0x10, 0x10, 0x44,
        0xc7, 0xe7, 0xa4, 0x00, 0x00, 0x00, 0xca, 0x44, 0x03, 0x0e, 0xfa, 0x54, 0x82, 0x12, 0x94, 0x80, 0x10, 0xcc,
        0x66, 0x0f, 0xec, 0x3e, 0x3a, 0x45, 0x9b, 0x0a, 0x60, 0x96, 0x19, 0xb0, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
        0x00, 0x00, 0x46, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff,
        0x03, 0x00, 0x00, 0x00,
    ];
    for index in 0..3 {
        let e = parse_serialized(bytes, index).unwrap_err();
        assert!(e.contains("table of meshes"), "{e}");
    }
}

/// Writes the seed corpus of the `serialized` fuzz target into `$SERIALIZED_CORPUS`.
#[test]
#[ignore]
fn write_fuzz_corpus() {
    let Ok(dir) = std::env::var("SERIALIZED_CORPUS") else { return };
    std::fs::create_dir_all(&dir).unwrap();
    for (k, bytes) in corpus().into_iter().enumerate() {
        std::fs::write(std::path::Path::new(&dir).join(format!("mesh{k}.serialized")), bytes).unwrap();
    }
}
