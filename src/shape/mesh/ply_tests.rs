//! The PLY reader against files written here in every layout it accepts (ASCII, binary little-
//! and big-endian, any index and count types, extra properties and elements), the bundled
//! meshes, and damaged files: every truncation, random edits and lying headers are errors,
//! never panics or huge allocations.

use super::*;
use proptest::prelude::*;

#[derive(Clone, Debug)]
struct Spec {
    positions: Vec<[f32; 3]>,
    normals: bool,
    /// Index into the texture-coordinate names, when there are uv.
    uv_names: Option<usize>,
    faces: Vec<Vec<u32>>,
    format: usize,
    /// (count type, index type) of the face list.
    list_types: (&'static str, &'static str),
    /// An extra uchar property on vertices and an int on faces, and an `edge` element.
    extras: bool,
}

const UV_NAMES: [(&str, &str); 3] = [("u", "v"), ("texture_u", "texture_v"), ("s", "t")];

fn put(out: &mut Vec<u8>, ty: &str, v: f64, format: usize) {
    let big = format == 2;
    macro_rules! b {
        ($x:expr) => {
            out.extend(if big { $x.to_be_bytes() } else { $x.to_le_bytes() })
        };
    }
    match (format, ty) {
        (0, "float") => out.extend(format!("{} ", v as f32).bytes()),
        (0, "double") => out.extend(format!("{v} ").bytes()),
        (0, _) => out.extend(format!("{} ", v as i64).bytes()),
        (_, "uchar") => out.push(v as u8),
        (_, "ushort") => b!(v as u16),
        (_, "int") => b!(v as i32),
        (_, "uint") => b!(v as u32),
        (_, "float") => b!(v as f32),
        (_, "double") => b!(v),
        _ => unreachable!(),
    }
}

fn write(s: &Spec) -> Vec<u8> {
    let fmt = ["ascii", "binary_little_endian", "binary_big_endian"][s.format];
    let mut h = format!("ply\nformat {fmt} 1.0\ncomment written by ply_tests\n");
    if s.extras {
        h += "element edge 2\nproperty int vertex1\nproperty list uchar int stuff\n";
    }
    h += &format!("element vertex {}\nproperty float x\n", s.positions.len());
    if s.extras {
        h += "property uchar red\n";
    }
    h += "property double y\nproperty float z\n";
    if s.normals {
        h += "property float nx\nproperty float ny\nproperty float nz\n";
    }
    if let Some(k) = s.uv_names {
        h += &format!("property float {}\nproperty float {}\n", UV_NAMES[k].0, UV_NAMES[k].1);
    }
    h += &format!("element face {}\n", s.faces.len());
    if s.extras {
        h += "property int flags\n";
    }
    h += &format!("property list {} {} vertex_indices\nend_header\n", s.list_types.0, s.list_types.1);
    let mut out = h.into_bytes();
    let nl = |out: &mut Vec<u8>| {
        if s.format == 0 {
            out.push(b'\n')
        }
    };
    if s.extras {
        for _ in 0..2 {
            put(&mut out, "int", 7.0, s.format);
            put(&mut out, "uchar", 2.0, s.format);
            put(&mut out, "int", 1.0, s.format);
            put(&mut out, "int", 2.0, s.format);
            nl(&mut out);
        }
    }
    for (i, p) in s.positions.iter().enumerate() {
        put(&mut out, "float", p[0] as f64, s.format);
        if s.extras {
            put(&mut out, "uchar", 200.0, s.format);
        }
        put(&mut out, "double", p[1] as f64, s.format);
        put(&mut out, "float", p[2] as f64, s.format);
        if s.normals {
            for c in normal(i) {
                put(&mut out, "float", c as f64, s.format);
            }
        }
        if s.uv_names.is_some() {
            put(&mut out, "float", uv(i)[0] as f64, s.format);
            put(&mut out, "float", uv(i)[1] as f64, s.format);
        }
        nl(&mut out);
    }
    for f in &s.faces {
        if s.extras {
            put(&mut out, "int", -3.0, s.format);
        }
        put(&mut out, s.list_types.0, f.len() as f64, s.format);
        for &i in f {
            put(&mut out, s.list_types.1, i as f64, s.format);
        }
        nl(&mut out);
    }
    out
}

fn normal(i: usize) -> [f32; 3] {
    [i as f32 * 0.5, 1.0, -0.25]
}

fn uv(i: usize) -> [f32; 2] {
    [i as f32 / 8.0, 1.0 - i as f32 / 16.0]
}

fn spec() -> impl Strategy<Value = Spec> {
    let coord = prop_oneof![-1e6f32..1e6, -1.0f32..1.0, Just(0.0f32)];
    (3usize..40, any::<bool>(), proptest::option::of(0usize..3), 0usize..3, 0usize..3, any::<bool>())
        .prop_flat_map(move |(nv, normals, uv_names, format, types, extras)| {
            let face = proptest::collection::vec(0..nv as u32, 0..6);
            (
                proptest::collection::vec([coord.clone(), coord.clone(), coord.clone()], nv),
                proptest::collection::vec(face, 1..30),
                Just((normals, uv_names, format, types, extras)),
            )
        })
        .prop_filter("some face has three vertices", |(_, faces, _)| faces.iter().any(|f| f.len() >= 3))
        .prop_map(|(positions, faces, (normals, uv_names, format, types, extras))| {
            let list_types = [("uchar", "int"), ("uchar", "uint"), ("ushort", "int")][types];
            Spec { positions, normals, uv_names, faces, format, list_types, extras }
        })
}

fn fanned(faces: &[Vec<u32>]) -> Vec<[u32; 3]> {
    let mut out = Vec::new();
    for f in faces {
        fan(f, &mut out);
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    /// Every layout reads back exactly what was written: positions bit for bit, normals and
    /// uv when present, polygons fanned from their first vertex.
    #[test]
    fn written_meshes_read_back(s in spec()) {
        let m = parse_ply(&write(&s)).unwrap();
        let expect: Vec<Vec3> = s.positions.iter().map(|p| Vec3::from_array(*p)).collect();
        prop_assert_eq!(&m.positions, &expect);
        prop_assert_eq!(&m.indices, &fanned(&s.faces));
        prop_assert_eq!(m.normals.is_some(), s.normals);
        if let Some(ns) = &m.normals {
            prop_assert!(ns.iter().enumerate().all(|(i, n)| *n == Vec3::from_array(normal(i))));
        }
        prop_assert_eq!(m.uvs.is_some(), s.uv_names.is_some());
        if let Some(uvs) = &m.uvs {
            prop_assert!(uvs.iter().enumerate().all(|(i, t)| *t == Vec2::from_array(uv(i))));
        }
    }

    /// Random edits of a valid file give a mesh or an error, never a panic.
    #[test]
    fn edited_files_never_panic(s in spec(), edits in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..8)) {
        let mut bytes = write(&s);
        for (at, b) in edits {
            let i = at.index(bytes.len());
            bytes[i] = b;
        }
        if let Ok(m) = parse_ply(&bytes) {
            let n = m.positions.len() as u32;
            prop_assert!(m.indices.iter().flatten().all(|&i| i < n));
            prop_assert!(m.positions.iter().all(|p| p.is_finite()));
        }
    }
}

/// Every cut of a binary file short of its end is an error naming where it ended.
#[test]
fn truncated_binary_files_are_errors() {
    let s = Spec {
        positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]],
        normals: true,
        uv_names: Some(0),
        faces: vec![vec![0, 1, 2], vec![0, 2, 3, 1]],
        format: 1,
        list_types: ("uchar", "int"),
        extras: true,
    };
    let bytes = write(&s);
    assert_eq!(parse_ply(&bytes).unwrap().indices.len(), 3);
    for len in 0..bytes.len() {
        let e = parse_ply(&bytes[..len]).expect_err("a cut file loaded");
        assert!(!e.is_empty());
    }
    let header_end = bytes.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let e = parse_ply(&bytes[..bytes.len() - 1]).unwrap_err();
    assert!(e.contains("cut short"), "{e}");
    let e = parse_ply(&bytes[..header_end + 3]).unwrap_err();
    assert!(e.contains("cut short"), "{e}");
}

/// A header promising billions of elements is refused from the file's size, at once, with no
/// allocation for them.
#[test]
fn lying_headers_are_refused_before_allocating() {
    for count in ["4000000000", "18446744073709551615"] {
        for fmt in ["ascii", "binary_little_endian"] {
            let text = format!(
                "ply\nformat {fmt} 1.0\nelement vertex {count}\nproperty float x\nproperty float y\nproperty float z\n\
                 element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n3 0 0 0\n"
            );
            let e = parse_ply(text.as_bytes()).unwrap_err();
            assert!(e.contains("promises"), "{e}");
        }
    }
    // Elements of no properties take no bytes: skipped at once, however many.
    let text = "ply\nformat binary_little_endian 1.0\nelement nothing 18446744073709551615\nelement vertex 3\n\
                property uchar x\nproperty uchar y\nproperty uchar z\nelement face 1\nproperty list uchar uchar vertex_indices\n\
                end_header\n";
    let mut bytes = text.as_bytes().to_vec();
    bytes.extend([0, 0, 0, 1, 0, 0, 0, 1, 0, 3, 0, 1, 2]);
    assert_eq!(parse_ply(&bytes).unwrap().indices, vec![[0, 1, 2]]);
    let e = parse_ply(b"ply\nformat ascii 1.0\nelement vertex 99999999999999999999999\nend_header\n").unwrap_err();
    assert!(e.contains("whole number"), "{e}");
}

#[test]
fn bad_contents_are_clear_errors() {
    let head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
    assert_eq!(parse_ply(format!("{head}3 0 1 2\n").as_bytes()).unwrap().indices, vec![[0, 1, 2]]);
    for (face, msg) in [
        ("3 0 1 3\n", "refers to vertex 3 of 3"),
        ("3 0 -1 2\n", "refers to vertex -1"),
        ("3 0 1.5 2\n", "not a whole number"),
        ("70000 0 1 2\n", "list of 70000"),
        ("3 0 1 x\n", "`x` is not a number"),
        ("2 0 1\n", "no faces"),
    ] {
        let e = parse_ply(format!("{head}{face}").as_bytes()).unwrap_err();
        assert!(e.contains(msg), "{face:?}: {e}");
    }
    let nan = head.replace("1 0 0\n", "nan 0 0\n");
    assert!(parse_ply(format!("{nan}3 0 1 2\n").as_bytes()).unwrap_err().contains("vertex 1 is not finite"));
    for (header, msg) in [
        ("ply\nformat ascii 1.0\nelement face 0\nend_header\n", "no `vertex` element"),
        (
            "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n",
            "no x, y, z",
        ),
        ("ply\nformat xdr 1.0\nend_header\n", "unknown format"),
        ("ply\nformat ascii 1.0\nproperty float x\nend_header\n", "before any element"),
        ("ply\nformat ascii 1.0\nelement vertex 0\nproperty half x\nend_header\n", "unknown type"),
        ("ply\nformat ascii 1.0\n", "no `end_header`"),
        ("PLY\n", "does not start with `ply`"),
    ] {
        let e = parse_ply(header.as_bytes()).unwrap_err();
        assert!(e.contains(msg), "{header:?}: {e}");
    }
}

/// The bundled meshes: a binary icosphere with normals and an ASCII pyramid with a quad base,
/// and errors from `load_ply` name the file.
#[test]
fn bundled_meshes_and_file_errors() {
    let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/mitsuba/meshes");
    let m = load_ply(&dir.join("icosphere.ply")).unwrap();
    assert_eq!((m.positions.len(), m.indices.len()), (162, 320));
    assert!(m.normals.as_ref().unwrap().iter().all(|n| (n.length() - 1.0).abs() < 1e-3));
    let obj = TriangleMesh::load_obj(&dir.join("icosphere.obj")).unwrap();
    let bounds = |m: &TriangleMesh| crate::geometry::Aabb::from_points(&m.positions);
    assert!(bounds(&m).min.abs_diff_eq(bounds(&obj).min, 1e-5) && bounds(&m).max.abs_diff_eq(bounds(&obj).max, 1e-5));
    let p = load_ply(&dir.join("pyramid_ascii.ply")).unwrap();
    assert_eq!(p.indices.len(), 6);
    let e = load_ply(&dir.join("missing.ply")).unwrap_err().to_string();
    assert!(e.contains("missing.ply") && e.contains("PLY"), "{e}");
    let e = load_ply(&dir.join("icosphere.obj")).unwrap_err().to_string();
    assert!(e.contains("icosphere.obj") && e.contains("does not start with `ply`"), "{e}");
}

/// Extra properties become attributes as Mitsuba 3.9.1 names them (checked with its reader):
/// `red green blue` -> `vertex_color`, `<p>_x <p>_y <p>_z` -> `vertex_<p>`, `<p>_r <p>_g <p>_b`
/// -> `face_<p>_color`, `<p>_0` -> `face_<p>`; a property without a one-letter suffix is skipped;
/// a polygon's values repeat on each of its triangles.
#[test]
fn attributes_are_named_and_grouped_as_mitsuba_names_them() {
    for format in 0..3 {
        let fmt = ["ascii", "binary_little_endian", "binary_big_endian"][format];
        let header = format!(
            "ply\nformat {fmt} 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
             property uchar red\nproperty uchar green\nproperty uchar blue\nproperty float quality\n\
             property float n_x\nproperty float n_y\nproperty float n_z\n\
             element face 2\nproperty list uchar int vertex_indices\nproperty float weight_0\n\
             property float c_r\nproperty float c_g\nproperty float c_b\nend_header\n"
        );
        let mut out = header.into_bytes();
        for i in 0..4 {
            let p = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]][i];
            for v in [p[0], p[1], 0.0] {
                put(&mut out, "float", v, format);
            }
            for c in [10.0 * i as f64, 20.0, 30.0] {
                put(&mut out, "uchar", c, format);
            }
            for v in [0.5, i as f64, 0.0, 1.0] {
                put(&mut out, "float", v, format);
            }
            if format == 0 {
                out.push(b'\n');
            }
        }
        for (f, n) in [(vec![0u32, 1, 2, 3], 0.25), (vec![0, 2, 3], 0.75)] {
            put(&mut out, "uchar", f.len() as f64, format);
            for i in f {
                put(&mut out, "int", i as f64, format);
            }
            for v in [n, 0.1, 0.2, 0.3] {
                put(&mut out, "float", v, format);
            }
            if format == 0 {
                out.push(b'\n');
            }
        }
        let m = parse_ply(&out).unwrap_or_else(|e| panic!("{fmt}: {e}"));
        let names: Vec<(&str, bool, usize)> =
            m.attributes.iter().map(|a| (a.name.as_str(), a.per_face, a.channels)).collect();
        assert_eq!(
            names,
            [("vertex_color", false, 3), ("vertex_n", false, 3), ("face_weight", true, 1), ("face_c_color", true, 3)],
            "{fmt}"
        );
        assert_eq!(m.attributes[0].values[3..6], [10.0, 20.0, 30.0], "{fmt}: raw values, as Mitsuba keeps them");
        // The quad is two triangles, each with its weight; the triangle after them has its own.
        assert_eq!(m.indices.len(), 3);
        assert_eq!(m.attributes[2].values, [0.25, 0.25, 0.75], "{fmt}");
        // Interpolated at the centre of the first triangle (vertices 0, 1, 2).
        let c = m.attributes[1].eval(&m.indices, 0, [1.0 / 3.0; 3]);
        assert!((c.r() - 1.0).abs() < 1e-6 && c.g() == 0.0 && c.b() == 1.0, "{fmt}: {c}");
    }
}
