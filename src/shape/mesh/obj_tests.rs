//! The OBJ reader against tobj (the reader it replaced) on generated files, corner by corner:
//! the same triangles in the same order with the same positions, normals and texture
//! coordinates; its number parser against the standard library's; and clear errors.

use super::*;
use proptest::prelude::*;

/// A face corner as a renderer sees it: position, uv, normal.
type Corner = (Vec3, Option<Vec2>, Option<Vec3>);

/// Each triangle's corners.
fn corners(m: &TriangleMesh) -> Vec<[Corner; 3]> {
    m.indices
        .iter()
        .map(|t| {
            t.map(|i| {
                let i = i as usize;
                (m.positions[i], m.uvs.as_ref().map(|u| u[i]), m.normals.as_ref().map(|n| n[i]))
            })
        })
        .collect()
}

/// What tobj made of the same text, as the loader used it before (one object).
fn tobj_mesh(text: &str) -> Option<TriangleMesh> {
    let opts = tobj::LoadOptions { single_index: true, triangulate: true, ignore_points: true, ignore_lines: true };
    let (models, _) = tobj::load_obj_buf(&mut text.as_bytes(), &opts, |_| Ok(Default::default())).ok()?;
    let m = &models.first()?.mesh;
    let n = m.positions.len() / 3;
    Some(TriangleMesh {
        positions: m.positions.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect(),
        normals: (m.normals.len() == 3 * n)
            .then(|| m.normals.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect()),
        uvs: (m.texcoords.len() == 2 * n)
            .then(|| m.texcoords.chunks_exact(2).map(|c| Vec2::new(c[0], 1.0 - c[1])).collect()),
        indices: m.indices.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        attributes: Vec::new(),
    })
}

#[derive(Clone, Debug)]
struct Spec {
    positions: Vec<[f32; 3]>,
    texcoords: Vec<[f32; 2]>,
    normals: Vec<[f32; 3]>,
    /// Corners as (v, vt, vn) 0-based.
    faces: Vec<Vec<(usize, usize, usize)>>,
    /// 0: `v`, 1: `v//vn`, 2: `v/vt/vn`, 3: `v/vt`.
    style: usize,
    negative: bool,
}

fn spec() -> impl Strategy<Value = Spec> {
    let coord = prop_oneof![-1e4f32..1e4, -1.0f32..1.0, (-30i32..30).prop_map(|e| 1.37f32 * 10f32.powi(e))];
    (3usize..30, 0usize..4, any::<bool>(), any::<bool>())
        .prop_flat_map(move |(n, style, same, negative)| {
            let corner = (0..n, 0..n, 0..n).prop_map(move |(v, t, k)| if same { (v, v, v) } else { (v, t, k) });
            (
                proptest::collection::vec([coord.clone(), coord.clone(), coord.clone()], n),
                proptest::collection::vec([-2.0f32..2.0, -2.0f32..2.0], n),
                proptest::collection::vec([-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0], n),
                proptest::collection::vec(proptest::collection::vec(corner, 3..6), 1..20),
                Just((style, negative)),
            )
        })
        .prop_map(|(positions, texcoords, normals, faces, (style, negative))| Spec {
            positions,
            texcoords,
            normals,
            faces,
            style,
            negative,
        })
}

fn write(s: &Spec) -> String {
    let mut out = String::from("# generated\no thing\n");
    let n = s.positions.len();
    for p in &s.positions {
        out += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    for t in &s.texcoords {
        out += &format!("vt {:e} {}\n", t[0], t[1]);
    }
    for v in &s.normals {
        out += &format!("vn {} {} {}\n", v[0], v[1], v[2]);
    }
    out += "s 1\nusemtl x\n";
    let idx = |i: usize| if s.negative { format!("-{}", n - i) } else { (i + 1).to_string() };
    for f in &s.faces {
        out += "f";
        for &(v, t, k) in f {
            out += &match s.style {
                0 => format!(" {}", idx(v)),
                1 => format!(" {}//{}", idx(v), idx(k)),
                2 => format!(" {}/{}/{}", idx(v), idx(t), idx(k)),
                _ => format!(" {}/{}", idx(v), idx(t)),
            };
        }
        out += "\n";
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    /// Corner by corner what tobj read, whichever way the faces index their attributes.
    #[test]
    fn same_corners_as_tobj(s in spec()) {
        let text = write(&s);
        let ours = parse_obj(text.as_bytes()).unwrap();
        let theirs = tobj_mesh(&text).unwrap();
        prop_assert_eq!(corners(&ours), corners(&theirs));
        // Attributes numbered as the positions keep the file's vertices (no dedupe).
        let same = s.faces.iter().flatten().all(|&(v, t, k)| v == t && v == k);
        if same || s.style == 0 {
            prop_assert_eq!(ours.positions.len(), s.positions.len());
        }
    }

    /// The fast path agrees with the standard library bit for bit.
    #[test]
    fn numbers_parse_as_std_does(x in any::<f32>().prop_filter("finite", |x| x.is_finite()), digits in 1usize..10) {
        for text in [format!("{x}"), format!("{x:e}"), format!("{:.*}", digits, x), format!("{:.*e}", digits, x)] {
            let std: f32 = text.parse().unwrap();
            prop_assert_eq!(number(text.as_bytes()).map(f32::to_bits), Some(std.to_bits()), "{}", text);
        }
    }
}

#[test]
fn fast_path_edge_cases() {
    for text in ["0", "-0", "+1", "1.", ".5", "-.25", "1e10", "1.234567e-4", "9999999", "0.0000001", "1E3", "123e-2"] {
        let std: f32 = text.parse().unwrap();
        assert_eq!(fast_number(text.as_bytes()).map(f32::to_bits), Some(std.to_bits()), "{text}");
    }
    for text in ["", "-", ".", "e5", "1e", "1e+", "12345678", "1e11", "1x", "nan", "inf", "1.2.3", "--1"] {
        assert_eq!(fast_number(text.as_bytes()), None, "{text}");
    }
    assert_eq!(number(b"1e-30"), Some(1e-30));
    assert_eq!(number(b"inf"), Some(f32::INFINITY));
}

#[test]
fn errors_name_the_line() {
    for (text, msg) in [
        ("v 0 0 0\nv 1 0 0\nf 1 2 9\n", "line 3: a face refers to vertex 9 of 2"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", "line 4: a face refers to vertex 0 of 3"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", "refers to vertex -4 of 3"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2 3\n", "texture coordinate 1 of 0"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//x 2 3\n", "normal index `x` is not a whole number"),
        ("v 0 0\n", "line 1: a vertex position (v) is not three numbers"),
        ("v 0 0 inf\n", "not finite"),
        ("v 0 0 0\nvt a\n", "line 2: a texture coordinate"),
        ("v 0 0 0\nf 1 1\n", "fewer than three"),
        ("v 0 0 0\n# nothing\n", "no faces"),
    ] {
        let e = parse_obj(text.as_bytes()).unwrap_err();
        assert!(e.contains(msg), "{text:?}: {e}");
    }
}

/// Groups and objects go into one mesh; the bundled files read as tobj read them.
#[test]
fn objects_merge_and_bundled_files_match() {
    let m = parse_obj(b"o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\ng b\nv 0 0 1\nf 1 3 4\n").unwrap();
    assert_eq!((m.positions.len(), m.indices.clone()), (4, vec![[0, 1, 2], [0, 2, 3]]));
    let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/mitsuba/meshes");
    for file in ["icosphere.obj", "pyramid.obj"] {
        let text = std::fs::read_to_string(dir.join(file)).unwrap();
        let ours = load_obj(&dir.join(file)).unwrap();
        assert_eq!(corners(&ours), corners(&tobj_mesh(&text).unwrap()), "{file}");
    }
    let e = load_obj(&dir.join("nope.obj")).unwrap_err().to_string();
    assert!(e.contains("OBJ") && e.contains("nope.obj"), "{e}");
}
