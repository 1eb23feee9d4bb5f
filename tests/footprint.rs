//! The files a scene reads: both loaders report each one to the file hook (`FileBudget`) before
//! reading it, so the list a render's identity hashes and the memory estimate come from one pass,
//! and a scene that would not fit stops at the file that does not fit, before reading it.

mod common;

use caustic::options::Options;
use caustic::scene::footprint::{BYTES_PER_TRIANGLE, BYTES_PER_VERTEX, FileKind, OverBudget};
use caustic::scene::{FileBudget, LoadOptions, SceneError, load_scene_within};
use caustic::shape::mesh::MeshFormat;
use std::path::{Path, PathBuf};

fn data(p: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(p)
}

/// A scratch folder holding a mesh, two images and a header-only PLY of 30 M triangles (whose
/// data is missing: reading it would fail, so a load that stops with the memory error did not).
fn folder(name: &str) -> PathBuf {
    let dir = common::scratch(name);
    for (from, to) in [
        ("scenes/mitsuba/meshes/icosphere.ply", "ball.ply"),
        ("tests/data/materials/textures/palette5x3.png", "tex.png"),
        ("tests/data/materials/textures/palette5x3.hdr", "sky.hdr"),
        ("tests/data/materials/textures/tiles.png", "eta.png"),
    ] {
        std::fs::copy(data(from), dir.join(to)).unwrap();
    }
    std::fs::write(
        dir.join("huge.ply"),
        "ply\nformat binary_little_endian 1.0\nelement vertex 15000000\nproperty float x\nproperty float y\n\
         property float z\nelement face 30000000\nproperty list uchar int vertex_indices\nend_header\n",
    )
    .unwrap();
    dir
}

const BALL: u64 = 162 * BYTES_PER_VERTEX + 320 * BYTES_PER_TRIANGLE;

/// Both loaders list exactly the files a scene reads, once each in the order first read (the
/// scene file, includes, meshes, textures, the environment map; a mesh used twice once, and a
/// Mitsuba texture read only for its mean, which the list missed before), and the built scene's
/// `LoadInfo::files` is the same list.
#[test]
fn both_loaders_list_exactly_the_files_a_scene_reads() {
    let dir = folder("footprint-lists");
    let toml = dir.join("scene.toml");
    std::fs::write(
        &toml,
        r#"[camera]
eye = [0, 0, 5]
look_at = [0, 0, 0]
[textures.t]
type = "bitmap"
file = "tex.png"
[textures.raw]
type = "bitmap"
file = "tex.png"
raw = true
[materials.m]
type = "diffuse"
color = "t"
[materials.n]
type = "diffuse"
color = "raw"
[[lights]]
type = "envmap"
file = "sky.hdr"
[[objects]]
type = "mesh"
file = "ball.ply"
material = "m"
[[objects]]
type = "torus_knot"
segments = 8
sides = 4
[[objects]]
type = "mesh"
file = "ball.ply"
material = "n"
"#,
    )
    .unwrap();
    let files = FileBudget::unlimited();
    let desc = load_scene_within(&toml, &LoadOptions::default(), &files).unwrap();
    let expected = [toml.clone(), dir.join("tex.png"), dir.join("sky.hdr"), dir.join("ball.ply")];
    assert_eq!(desc.files(), expected);
    let f = files.footprint();
    let kinds: Vec<FileKind> = f.files.iter().map(|r| r.kind).collect();
    assert_eq!(kinds, [FileKind::Scene, FileKind::Image, FileKind::Image, FileKind::Mesh(MeshFormat::Ply)]);
    // Each read counts: the mesh twice, the image decoded two ways twice, and the knot.
    assert_eq!(f.meshes, 2 * BALL + 32 * BYTES_PER_VERTEX + 64 * BYTES_PER_TRIANGLE);
    assert_eq!(f.textures, 2 * 15 * 12 + 15 * 12);
    let loaded = caustic::app::prepare(desc, &Options::default()).unwrap();
    assert_eq!(loaded.info.files, expected);

    let xml = dir.join("scene.xml");
    std::fs::write(
        dir.join("part.xml"),
        r#"<scene version="3.0.0">
    <shape type="ply"><string name="filename" value="ball.ply"/><ref id="m"/></shape>
</scene>"#,
    )
    .unwrap();
    std::fs::write(
        &xml,
        r#"<scene version="3.0.0">
    <bsdf type="diffuse" id="m">
        <texture type="bitmap" name="reflectance"><string name="filename" value="tex.png"/></texture>
    </bsdf>
    <include filename="part.xml"/>
    <shape type="ply">
        <string name="filename" value="ball.ply"/>
        <bsdf type="conductor">
            <texture type="bitmap" name="eta"><string name="filename" value="eta.png"/></texture>
        </bsdf>
    </shape>
    <emitter type="envmap"><string name="filename" value="sky.hdr"/></emitter>
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
    </sensor>
</scene>"#,
    )
    .unwrap();
    let files = FileBudget::unlimited();
    let desc = load_scene_within(&xml, &LoadOptions::default(), &files).unwrap();
    let expected = [
        xml,
        dir.join("part.xml"),
        dir.join("tex.png"),
        dir.join("ball.ply"),
        dir.join("eta.png"),
        dir.join("sky.hdr"),
    ];
    assert_eq!(desc.files(), expected);
    let kinds: Vec<FileKind> = files.footprint().files.iter().map(|r| r.kind).collect();
    assert_eq!(
        kinds,
        [
            FileKind::Scene,
            FileKind::Include,
            FileKind::Image,
            FileKind::Mesh(MeshFormat::Ply),
            FileKind::Image,
            FileKind::Image
        ]
    );
    assert_eq!(files.footprint().meshes, 2 * BALL);
    let loaded = caustic::app::prepare(desc, &Options::default()).unwrap();
    assert_eq!(loaded.info.files, expected);
}

/// A scene whose second mesh would not fit stops there, in either format: the error names that
/// file, the hook saw the first and counted it, and the second was never read (its data is
/// missing, which reading would have reported instead).
#[test]
fn a_mesh_that_would_not_fit_stops_the_load_before_it_is_read() {
    let dir = folder("footprint-second");
    let toml = dir.join("two.toml");
    std::fs::write(
        &toml,
        "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\n[[objects]]\ntype = \"mesh\"\nfile = \"ball.ply\"\n\
         [[objects]]\ntype = \"mesh\"\nfile = \"huge.ply\"\n",
    )
    .unwrap();
    let xml = dir.join("two.xml");
    std::fs::write(
        &xml,
        r#"<scene version="3.0.0">
    <shape type="ply"><string name="filename" value="ball.ply"/></shape>
    <shape type="ply"><string name="filename" value="huge.ply"/></shape>
</scene>"#,
    )
    .unwrap();
    let limit = 64 << 20;
    for scene in [toml, xml] {
        let files = FileBudget::new(limit);
        let err = match load_scene_within(&scene, &LoadOptions::default(), &files) {
            Err(SceneError::Memory(o)) => o,
            Err(e) => panic!("{}: expected the memory error, got {e}", scene.display()),
            Ok(_) => panic!("{}: loaded", scene.display()),
        };
        let huge = 15_000_000 * BYTES_PER_VERTEX + 30_000_000 * BYTES_PER_TRIANGLE;
        let what = format!("`{}`", dir.join("huge.ply").display());
        assert_eq!(err, OverBudget { what, bytes: huge, need: BALL + huge, limit });
        let f = files.footprint();
        assert_eq!(f.paths(), [scene.clone(), dir.join("ball.ply")], "{}", scene.display());
        assert_eq!(f.meshes, BALL);
        // Without a limit the second file is read, and its missing data is the error.
        let e = load_scene_within(&scene, &LoadOptions::default(), &FileBudget::unlimited()).err().unwrap();
        assert!(!matches!(e, SceneError::Memory(_)) && e.to_string().contains("huge.ply"), "{e}");
    }
}

/// Generated meshes and instances are counted by the builder before it makes them.
#[test]
fn generated_meshes_and_instances_count_before_they_are_made() {
    let knot = "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\n[[objects]]\ntype = \"torus_knot\"\n\
                segments = 100000\nsides = 250\n";
    let dir = common::scratch("footprint-generated");
    let path = dir.join("knot.toml");
    std::fs::write(&path, knot).unwrap();
    let files = FileBudget::new(1 << 30);
    match load_scene_within(&path, &LoadOptions::default(), &files) {
        Err(SceneError::Memory(o)) => assert_eq!(o.what, "a torus_knot of 50000000 triangles"),
        other => panic!("expected the memory error, got {:?}", other.err()),
    }
    let mut groups = String::from(
        "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\n[groups.g]\n[[groups.g.objects]]\ntype = \"sphere\"\n",
    );
    for i in 0..10 {
        groups.push_str(&format!(
            "[[objects]]\ntype = \"instance\"\ngroup = \"g\"\ntransform = [{{ translate = [{i}, 0, 0] }}]\n"
        ));
    }
    let path = dir.join("instances.toml");
    std::fs::write(&path, &groups).unwrap();
    let per = caustic::scene::footprint::BYTES_PER_INSTANCE;
    let files = FileBudget::new(4 * per + per / 2);
    match load_scene_within(&path, &LoadOptions::default(), &files) {
        Err(SceneError::Memory(o)) => assert_eq!((o.what.as_str(), o.need), ("instance 5", 5 * per)),
        other => panic!("expected the memory error, got {:?}", other.err()),
    }
    assert_eq!(files.footprint().instances, 4 * per);
    let files = FileBudget::unlimited();
    load_scene_within(&path, &LoadOptions::default(), &files).unwrap();
    assert_eq!(files.footprint().instances, 10 * per);
    assert_eq!(files.files(), [path.as_path()].map(Path::to_path_buf));
}
