//! What loading a scene will cost in memory, estimated before anything big is read: the files
//! a scene names (meshes, textures, environment maps) are measured from their headers (PLY
//! element counts, image sizes) or, where the format has no such header (OBJ), by counting its
//! face lines without keeping them, and instances are counted from the scene text. `caustic
//! render` refuses a scene whose estimate exceeds `--max-memory` before loading it.
//!
//! The estimate is of the peak resident memory while loading, which is when the BVH's leaves
//! are made: the mesh, its primitives, the BVH's nodes and leaf shapes (the build records,
//! freed just before, take less). The PLY and OBJ readers stream into the mesh's arrays and need nothing
//! per triangle beyond them, so reading never peaks higher.

use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};

/// Peak bytes per triangle while a scene is loaded: its indices in the mesh (12), its 8-byte
/// primitive (mesh and triangle indices), the BVH's 40-byte leaf shape and node share (about
/// 19); the 32-byte build records are freed before the nodes are joined and the leaves made
/// (measured on the 5 M-triangle knot: 91 bytes per triangle with its vertices, BENCHMARKS.md
/// "Big meshes: 8-byte primitives").
pub const BYTES_PER_TRIANGLE: u64 = 80;
/// Bytes per mesh vertex kept (position and normal; uv when the file has them).
pub const BYTES_PER_VERTEX: u64 = 24;
/// Bytes per instance: two transforms, bounds and the top-level BVH's share.
pub const BYTES_PER_INSTANCE: u64 = 160;

/// The estimated memory of a scene's big parts, with the files it measured.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Footprint {
    pub meshes: u64,
    pub textures: u64,
    pub instances: u64,
    /// Each file measured and its estimated bytes (0 for a file that could not be measured:
    /// loading it reports the problem).
    pub files: Vec<(PathBuf, u64)>,
}

impl Footprint {
    pub fn total(&self) -> u64 {
        self.meshes.saturating_add(self.textures).saturating_add(self.instances)
    }

    fn mesh(&mut self, path: PathBuf) {
        let bytes = mesh_bytes(&path).unwrap_or(0);
        self.meshes = self.meshes.saturating_add(bytes);
        self.files.push((path, bytes));
    }

    fn image(&mut self, path: PathBuf) {
        let bytes = image_size(&path).map_or(0, |(w, h)| w.saturating_mul(h).saturating_mul(12));
        self.textures = self.textures.saturating_add(bytes);
        self.files.push((path, bytes));
    }
}

/// Estimates the footprint of the scene file `path` (Mitsuba XML or caustic TOML) with the
/// Mitsuba parameters `defines`. Anything it cannot read counts as nothing: the loader reports
/// the problem properly.
pub fn estimate(path: &Path, defines: &[(String, String)]) -> Footprint {
    let mut f = Footprint::default();
    let Ok(text) = std::fs::read_to_string(path) else { return f };
    let base = path.parent().unwrap_or(Path::new(""));
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("xml")) {
        xml_files(&text, base, defines, &mut f, 0);
    } else {
        toml_files(&text, base, &mut f);
    }
    f
}

/// Meshes, images and instances named in Mitsuba XML (includes followed, 8 deep at most).
fn xml_files(text: &str, base: &Path, defines: &[(String, String)], f: &mut Footprint, depth: usize) {
    let Ok(doc) = roxmltree::Document::parse(text) else { return };
    // `<default>` values, overridden by the command line's `-D`.
    let mut params: Vec<(String, String)> = doc
        .descendants()
        .filter(|n| n.has_tag_name("default"))
        .filter_map(|n| Some((n.attribute("name")?.to_string(), n.attribute("value")?.to_string())))
        .collect();
    params.extend(defines.iter().cloned());
    let resolve = |v: &str| {
        let mut v = v.to_string();
        for (name, value) in params.iter().rev() {
            v = v.replace(&format!("${name}"), value);
        }
        v
    };
    let mut dirs = vec![base.to_path_buf()];
    dirs.extend(
        doc.descendants().filter(|n| n.has_tag_name("path")).filter_map(|n| n.attribute("value")).map(|v| base.join(v)),
    );
    let find = |file: &str| dirs.iter().map(|d| d.join(file)).find(|p| p.exists()).unwrap_or_else(|| base.join(file));
    for n in doc.descendants() {
        let kind = n.attribute("type").unwrap_or("");
        if n.has_tag_name("shape") && kind == "instance" {
            f.instances = f.instances.saturating_add(BYTES_PER_INSTANCE);
        }
        if n.has_tag_name("include") && depth < 8 {
            if let Some(file) = n.attribute("filename") {
                let p = find(&resolve(file));
                if let Ok(t) = std::fs::read_to_string(&p) {
                    xml_files(&t, p.parent().unwrap_or(base), defines, f, depth + 1);
                }
            }
            continue;
        }
        let filename = || {
            n.children()
                .find(|c| c.has_tag_name("string") && c.attribute("name") == Some("filename"))
                .and_then(|c| c.attribute("value"))
                .map(|v| find(&resolve(v)))
        };
        match (n.tag_name().name(), kind) {
            ("shape", "obj" | "ply" | "serialized") => {
                if let Some(p) = filename() {
                    f.mesh(p);
                }
            }
            ("texture", "bitmap") | ("emitter", "envmap") => {
                if let Some(p) = filename() {
                    f.image(p);
                }
            }
            _ => {}
        }
    }
}

/// Meshes and images named in a caustic TOML scene: `file` keys of objects, textures and lights.
fn toml_files(text: &str, base: &Path, f: &mut Footprint) {
    let Ok(doc) = text.parse::<toml::Table>() else { return };
    let file_of = |v: &toml::Value| v.get("file").and_then(|p| p.as_str()).map(|p| base.join(p));
    for o in doc.get("objects").and_then(|v| v.as_array()).into_iter().flatten() {
        match o.get("type").and_then(|t| t.as_str()) {
            Some("instance") => f.instances = f.instances.saturating_add(BYTES_PER_INSTANCE),
            Some("torus_knot") => f.meshes = f.meshes.saturating_add(knot_bytes(o)),
            _ => {
                if let Some(p) = file_of(o) {
                    f.mesh(p);
                }
            }
        }
    }
    for (_, group) in doc.get("groups").and_then(|v| v.as_table()).into_iter().flatten() {
        for o in group.get("objects").and_then(|v| v.as_array()).into_iter().flatten() {
            if o.get("type").and_then(|t| t.as_str()) == Some("torus_knot") {
                f.meshes = f.meshes.saturating_add(knot_bytes(o));
            } else if let Some(p) = file_of(o) {
                f.mesh(p);
            }
        }
    }
    for (_, t) in doc.get("textures").and_then(|v| v.as_table()).into_iter().flatten() {
        if let Some(p) = file_of(t) {
            f.image(p);
        }
    }
    for l in doc.get("lights").and_then(|v| v.as_array()).into_iter().flatten() {
        if let Some(p) = file_of(l) {
            f.image(p);
        }
    }
}

/// A generated torus knot's bytes: `segments` x `sides` vertices, twice as many triangles
/// (the defaults of `scene::native`).
fn knot_bytes(o: &toml::Value) -> u64 {
    let get = |k: &str, d: u64| o.get(k).and_then(|v| v.as_integer()).map_or(d, |v| v.max(0) as u64);
    let vertices = get("segments", 256).saturating_mul(get("sides", 32));
    vertices.saturating_mul(BYTES_PER_VERTEX).saturating_add(vertices.saturating_mul(2 * BYTES_PER_TRIANGLE))
}

/// A mesh file's peak bytes while loaded: from a PLY header's element counts, an OBJ's `v`
/// and `f` lines (polygons of n vertices count n - 2 triangles), or a Mitsuba serialized file's
/// size (compressed about 3:1).
pub fn mesh_bytes(path: &Path) -> Option<u64> {
    let ext = path.extension()?.to_str()?.to_ascii_lowercase();
    let (vertices, triangles) = match ext.as_str() {
        "ply" => ply_counts(path)?,
        "obj" => obj_counts(path)?,
        _ => {
            let size = std::fs::metadata(path).ok()?.len();
            // Serialized: 12-byte positions and normals, 8-byte uv, 12-byte faces, compressed.
            (size * 3 / 44, size * 3 / 22)
        }
    };
    Some(vertices.saturating_mul(BYTES_PER_VERTEX).saturating_add(triangles.saturating_mul(BYTES_PER_TRIANGLE)))
}

/// (vertices, triangles) from a PLY header (faces count as triangles, two for quads is not
/// known before reading them: the estimate assumes triangles).
fn ply_counts(path: &Path) -> Option<(u64, u64)> {
    let mut r = BufReader::new(std::fs::File::open(path).ok()?).take(1 << 20);
    let (mut v, mut t) = (0u64, 0u64);
    let mut line = String::new();
    for _ in 0..1000 {
        line.clear();
        if r.read_line(&mut line).ok()? == 0 {
            break;
        }
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            ["element", "vertex", n] => v = n.parse().ok()?,
            ["element", "face", n] => t = n.parse().ok()?,
            ["end_header"] => return Some((v, t)),
            _ => {}
        }
    }
    None
}

/// (vertices, triangles) of an OBJ file, counted line by line without keeping anything.
fn obj_counts(path: &Path) -> Option<(u64, u64)> {
    let mut r = BufReader::with_capacity(1 << 16, std::fs::File::open(path).ok()?);
    let (mut v, mut t) = (0u64, 0u64);
    let mut line = Vec::new();
    loop {
        line.clear();
        if r.read_until(b'\n', &mut line).ok()? == 0 {
            return Some((v, t));
        }
        if line.starts_with(b"v ") {
            v += 1;
        } else if line.starts_with(b"f ") {
            let corners = line[2..].split(|b| b.is_ascii_whitespace()).filter(|w| !w.is_empty()).count() as u64;
            t += corners.saturating_sub(2);
        }
    }
}

/// Width and height of an image from its header: PNG, JPEG, BMP, TGA, OpenEXR, Radiance HDR
/// and PFM.
pub fn image_size(path: &Path) -> Option<(u64, u64)> {
    let mut head = Vec::new();
    std::fs::File::open(path).ok()?.take(1 << 16).read_to_end(&mut head).ok()?;
    let be32 = |i: usize| head.get(i..i + 4).map(|b| u32::from_be_bytes([b[0], b[1], b[2], b[3]]) as u64);
    let le32 = |i: usize| head.get(i..i + 4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as u64);
    let le16 = |i: usize| head.get(i..i + 2).map(|b| u16::from_le_bytes([b[0], b[1]]) as u64);
    if head.starts_with(b"\x89PNG") {
        return Some((be32(16)?, be32(20)?));
    }
    if head.starts_with(b"\xff\xd8") {
        // The first start-of-frame marker (SOF0-SOF15 but DHT, JPG and DAC) holds the size.
        let mut i = 2;
        while i + 9 < head.len() {
            if head[i] != 0xff {
                return None;
            }
            let marker = head[i + 1];
            let len = u16::from_be_bytes([head[i + 2], head[i + 3]]) as usize;
            if (0xc0..=0xcf).contains(&marker) && !matches!(marker, 0xc4 | 0xc8 | 0xcc) {
                let h = u16::from_be_bytes([head[i + 5], head[i + 6]]) as u64;
                let w = u16::from_be_bytes([head[i + 7], head[i + 8]]) as u64;
                return Some((w, h));
            }
            i += 2 + len;
        }
        return None;
    }
    if head.starts_with(b"BM") {
        return Some((le32(18)?, (le32(22)? as u32 as i32).unsigned_abs() as u64));
    }
    if head.starts_with(b"v/1\x01") {
        let meta = exr::meta::MetaData::read_from_file(path, false).ok()?;
        let h = meta.headers.first()?;
        return Some((h.layer_size.width() as u64, h.layer_size.height() as u64));
    }
    if head.starts_with(b"#?") || head.starts_with(b"PF") || head.starts_with(b"Pf") {
        let text = String::from_utf8_lossy(&head);
        let mut lines = text.lines();
        if head.starts_with(b"#?") {
            // The resolution line: "-Y H +X W" (or another orientation).
            let res = lines.find(|l| l.starts_with(['-', '+']))?;
            let w: Vec<&str> = res.split_whitespace().collect();
            let (a, b): (u64, u64) = (w.get(1)?.parse().ok()?, w.get(3)?.parse().ok()?);
            return Some(if w[0].ends_with('Y') { (b, a) } else { (a, b) });
        }
        let dims: Vec<u64> = lines.nth(1)?.split_whitespace().filter_map(|x| x.parse().ok()).collect();
        return Some((*dims.first()?, *dims.get(1)?));
    }
    let ext = path.extension()?.to_str()?.to_ascii_lowercase();
    if ext == "tga" {
        return Some((le16(12)?, le16(14)?));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn data(p: &str) -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(p)
    }

    #[test]
    fn image_headers_give_their_size() {
        for (file, size) in [
            ("tests/data/materials/textures/palette5x3.png", (5, 3)),
            ("tests/data/materials/textures/palette5x3_16.png", (5, 3)),
            ("tests/data/materials/textures/palette5x3.jpg", (40, 24)),
            ("tests/data/materials/textures/palette5x3.bmp", (5, 3)),
            ("tests/data/materials/textures/palette5x3.tga", (5, 3)),
            ("tests/data/materials/textures/palette5x3.exr", (5, 3)),
            ("tests/data/materials/textures/palette5x3.hdr", (5, 3)),
            ("tests/data/materials/textures/palette5x3.pfm", (5, 3)),
            ("tests/data/materials/textures/tiles.png", (16, 8)),
        ] {
            assert_eq!(image_size(&data(file)), Some(size), "{file}");
        }
    }

    #[test]
    fn mesh_headers_give_their_triangles() {
        // The icosphere: 162 vertices and 320 triangles, as PLY and OBJ.
        assert_eq!(ply_counts(&data("scenes/mitsuba/meshes/icosphere.ply")), Some((162, 320)));
        assert_eq!(obj_counts(&data("scenes/mitsuba/meshes/icosphere.obj")), Some((162, 320)));
    }

    #[test]
    fn scenes_count_what_they_name() {
        let f = estimate(&data("tests/data/emitters/cornell_mesh.xml"), &[]);
        assert_eq!(f.files.len(), 1);
        assert_eq!(f.meshes, 162 * BYTES_PER_VERTEX + 320 * BYTES_PER_TRIANGLE);
        let f = estimate(&data("scenes/07-torus-knot.toml"), &[]);
        assert_eq!(f.meshes, 1600 * 32 * (BYTES_PER_VERTEX + 2 * BYTES_PER_TRIANGLE));
        let f = estimate(&data("scenes/15-materials.toml"), &[]);
        assert!(f.textures > 0 && f.files.iter().all(|(_, b)| *b > 0), "{f:?}");
    }

    /// Header readers see untrusted files: random bytes behind each format's magic, and every
    /// truncation of real files, give a size or `None`, never a panic.
    #[test]
    fn damaged_headers_never_panic() {
        let dir = std::env::temp_dir().join(format!("caustic-footprint-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut rng = crate::sampling::Rng32::new(11);
        let magics: [&[u8]; 8] =
            [b"\x89PNG\r\n\x1a\n", b"\xff\xd8\xff", b"BM", b"v/1\x01", b"#?", b"PF\n", b"ply\n", b""];
        for (i, magic) in magics.iter().enumerate() {
            for n in 0..32 {
                let mut bytes = magic.to_vec();
                let len = rng.next_u32() % 600;
                bytes.extend((0..len).map(|_| rng.next_u32() as u8));
                if n % 2 == 0 {
                    bytes.extend(b"\nend_header\nelement face 3\n-Y 4 +X 5\n");
                }
                for ext in ["png", "ply", "obj", "tga", "hdr"] {
                    let p = dir.join(format!("r{i}.{ext}"));
                    std::fs::write(&p, &bytes).unwrap();
                    let _ = image_size(&p);
                    let _ = mesh_bytes(&p);
                }
            }
        }
        for file in [
            "tests/data/materials/textures/palette5x3.exr",
            "tests/data/materials/textures/palette5x3.jpg",
            "scenes/mitsuba/meshes/icosphere.ply",
        ] {
            let bytes = std::fs::read(data(file)).unwrap();
            let ext = file.rsplit('.').next().unwrap();
            for len in (0..bytes.len().min(1200)).step_by(3) {
                let p = dir.join(format!("cut.{ext}"));
                std::fs::write(&p, &bytes[..len]).unwrap();
                let _ = image_size(&p);
                let _ = mesh_bytes(&p);
            }
        }
        std::fs::remove_dir_all(&dir).ok();
    }
}
