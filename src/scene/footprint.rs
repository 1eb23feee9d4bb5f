//! What loading a scene costs in memory, counted while it is loaded. Both loaders report every
//! file they read to one [`FileBudget`] (the hook) before they open it for its contents: the
//! scene file and its includes (counted as nothing), meshes and images (textures, environment
//! maps). The hook measures each file from its header (PLY element counts, image sizes) or, where
//! the format has no such header (OBJ), by counting its face lines without keeping them; the
//! scene builder counts the meshes it is asked to generate (the torus knot) and the instances it
//! places, before they are made. When the running total would pass the limit, the load stops with
//! [`OverBudget`] naming what did not fit, before that file is read. The files listed are also
//! the scene's files for a render's identity (`LoadInfo::files`), so the two cannot disagree.
//!
//! The estimate is of the peak resident memory while loading, which is when the BVH's leaves
//! are made: the mesh, its primitives, the BVH's nodes and leaf shapes (the build records,
//! freed just before, take less). The PLY and OBJ readers stream into the mesh's arrays and need nothing
//! per triangle beyond them, so reading never peaks higher.

use crate::shape::mesh::MeshFormat;
use std::collections::HashMap;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};

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
/// Bytes per texel of a decoded image (three 32-bit floats).
pub const BYTES_PER_TEXEL: u64 = 12;

/// What a file is read as, which says how it is measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileKind {
    /// The scene file itself (counted as nothing: it is small and freed after loading).
    Scene,
    /// A file the scene includes (Mitsuba's `<include>`; counted as nothing).
    Include,
    /// A spectrum data file (Mitsuba's `.spd`; counted as nothing: it becomes one colour).
    Spectrum,
    /// A grid of signed distances (Mitsuba's `.vol` for `sdfgrid`): counted at 16 times its size
    /// (its voxels become primitives).
    Volume,
    /// A grid of a participating medium's values (Mitsuba's `.vol` for `gridvolume`): held as
    /// its 32-bit values, about its size, and a majorant grid of at most 16^3 values.
    MediumGrid,
    /// A mesh, read in this format (the loader's choice, not the file name's).
    Mesh(MeshFormat),
    /// An image: a bitmap texture or an environment map.
    Image,
}

/// One file a scene read.
#[derive(Clone, Debug, PartialEq)]
pub struct FileRead {
    pub path: PathBuf,
    pub kind: FileKind,
    /// Estimated peak bytes of one read of it (0 for the scene and includes, and for a file that
    /// could not be measured: loading it reports the problem).
    pub bytes: u64,
}

/// The estimated memory of a scene's big parts, with the files it read.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Footprint {
    pub meshes: u64,
    pub textures: u64,
    pub instances: u64,
    /// Every file read, once each, in the order first read (a file read twice, as two meshes or
    /// as an image decoded two ways, is counted twice but listed once).
    pub files: Vec<FileRead>,
}

impl Footprint {
    pub fn total(&self) -> u64 {
        self.meshes.saturating_add(self.textures).saturating_add(self.instances)
    }

    /// The files' paths, in the order first read.
    pub fn paths(&self) -> Vec<PathBuf> {
        self.files.iter().map(|f| f.path.clone()).collect()
    }
}

/// The load stopped: `what` would have brought the estimate to `need` bytes, over `limit`.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error(
    "{what} would bring loading the scene to about {} MiB (adding {} MiB), more than the {} MiB allowed",
    need.div_ceil(1 << 20),
    bytes.div_ceil(1 << 20),
    limit >> 20
)]
pub struct OverBudget {
    /// What did not fit: a file (`` `path` ``), a generated mesh or an instance.
    pub what: String,
    /// Its estimated bytes.
    pub bytes: u64,
    /// The estimate with it.
    pub need: u64,
    pub limit: u64,
}

/// The hook the loaders report every file to before reading it, and the scene builder every
/// mesh it generates and instance it places. Clones share one ledger: the loader's context, the
/// builder and whoever asked for the load (`caustic render`, for its log) see the same totals.
/// Calls are per file or per instance, never per triangle. One budget serves one load.
#[derive(Clone, Debug, Default)]
pub struct FileBudget(Arc<Mutex<Ledger>>);

#[derive(Debug)]
struct Ledger {
    limit: u64,
    footprint: Footprint,
    /// Index in `footprint.files` of each path read, so a file is measured and listed once.
    index: HashMap<PathBuf, usize>,
}

impl Default for Ledger {
    fn default() -> Self {
        Ledger { limit: u64::MAX, footprint: Footprint::default(), index: HashMap::new() }
    }
}

/// Which total a charge adds to.
#[derive(Clone, Copy)]
enum Part {
    Meshes,
    Textures,
    Instances,
}

impl Ledger {
    /// Adds `bytes` to `part`, or refuses when the total would pass the limit.
    fn charge(&mut self, part: Part, bytes: u64, what: impl FnOnce() -> String) -> Result<(), OverBudget> {
        let need = self.footprint.total().saturating_add(bytes);
        if need > self.limit {
            return Err(OverBudget { what: what(), bytes, need, limit: self.limit });
        }
        let f = &mut self.footprint;
        let total = match part {
            Part::Meshes => &mut f.meshes,
            Part::Textures => &mut f.textures,
            Part::Instances => &mut f.instances,
        };
        *total = total.saturating_add(bytes);
        Ok(())
    }
}

impl FileBudget {
    /// A budget of `limit` bytes.
    pub fn new(limit: u64) -> Self {
        FileBudget(Arc::new(Mutex::new(Ledger { limit, ..Ledger::default() })))
    }

    /// A budget without a limit: it only lists and measures (what `Default` gives).
    pub fn unlimited() -> Self {
        Self::default()
    }

    fn ledger(&self) -> MutexGuard<'_, Ledger> {
        // Nothing panics while the ledger is held, but a poisoned one is still consistent.
        self.0.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Called by a loader just before it reads `path` as `kind`: measures the file (once per
    /// path), adds its bytes and lists it, or refuses when it would not fit (it is then not
    /// listed, and must not be read).
    pub fn open(&self, path: &Path, kind: FileKind) -> Result<(), OverBudget> {
        let mut ledger = self.ledger();
        let known = ledger.index.get(path).map(|&i| &ledger.footprint.files[i]);
        let listed = known.is_some();
        let bytes = match known {
            Some(f) if f.kind == kind => f.bytes,
            _ => measure(path, kind),
        };
        let what = || format!("`{}`", path.display());
        match kind {
            FileKind::Scene | FileKind::Include | FileKind::Spectrum => {}
            FileKind::Mesh(_) => ledger.charge(Part::Meshes, bytes, what)?,
            FileKind::Image => ledger.charge(Part::Textures, bytes, what)?,
            FileKind::Volume => ledger.charge(Part::Meshes, bytes, what)?,
            FileKind::MediumGrid => ledger.charge(Part::Textures, bytes, what)?,
        }
        if !listed {
            let i = ledger.footprint.files.len();
            ledger.index.insert(path.to_path_buf(), i);
            ledger.footprint.files.push(FileRead { path: path.to_path_buf(), kind, bytes });
        }
        Ok(())
    }

    /// Called by the builder before it generates a mesh of `vertices` and `triangles` (`name`
    /// says what it is, for the refusal).
    pub fn generated_mesh(&self, name: &str, vertices: u64, triangles: u64) -> Result<(), OverBudget> {
        let bytes = mesh_estimate(vertices, triangles);
        self.ledger().charge(Part::Meshes, bytes, || format!("a {name} of {triangles} triangles"))
    }

    /// Called by the builder before it places an instance.
    pub fn instance(&self) -> Result<(), OverBudget> {
        let mut ledger = self.ledger();
        let n = ledger.footprint.instances / BYTES_PER_INSTANCE + 1;
        ledger.charge(Part::Instances, BYTES_PER_INSTANCE, || format!("instance {n}"))
    }

    /// The totals and files so far.
    pub fn footprint(&self) -> Footprint {
        self.ledger().footprint.clone()
    }

    /// The files read so far, once each, in the order first read.
    pub fn files(&self) -> Vec<PathBuf> {
        self.ledger().footprint.paths()
    }
}

/// A file's estimated peak bytes as `kind`; 0 for what is not counted or cannot be measured.
fn measure(path: &Path, kind: FileKind) -> u64 {
    match kind {
        FileKind::Scene | FileKind::Include | FileKind::Spectrum => 0,
        FileKind::Mesh(format) => mesh_bytes(path, format).unwrap_or(0),
        FileKind::Image => image_size(path).map_or(0, |(w, h)| w.saturating_mul(h).saturating_mul(BYTES_PER_TEXEL)),
        // At most one 40-byte voxel (and its BVH share) per 4-byte value: an upper bound.
        FileKind::Volume => std::fs::metadata(path).map_or(0, |m| m.len().saturating_mul(16)),
        FileKind::MediumGrid => std::fs::metadata(path).map_or(0, |m| m.len().saturating_add(4 * 16 * 16 * 16)),
    }
}

/// A mesh file's peak bytes while loaded as `format`: from a PLY header's element counts, an
/// OBJ's `v` and `f` lines (polygons of n vertices count n - 2 triangles), or a Mitsuba
/// serialized file's size (compressed about 3:1).
pub fn mesh_bytes(path: &Path, format: MeshFormat) -> Option<u64> {
    let (vertices, triangles) = match format {
        MeshFormat::Ply => ply_counts(path)?,
        MeshFormat::Obj => obj_counts(path)?,
        MeshFormat::Serialized => {
            let size = std::fs::metadata(path).ok()?.len().saturating_mul(3);
            // 12-byte positions and normals, 8-byte uv, 12-byte faces, compressed.
            (size / 44, size / 22)
        }
    };
    Some(mesh_estimate(vertices, triangles))
}

/// Peak bytes of a mesh of `vertices` and `triangles` while loaded.
fn mesh_estimate(vertices: u64, triangles: u64) -> u64 {
    vertices.saturating_mul(BYTES_PER_VERTEX).saturating_add(triangles.saturating_mul(BYTES_PER_TRIANGLE))
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

    const FORMATS: [MeshFormat; 3] = [MeshFormat::Obj, MeshFormat::Ply, MeshFormat::Serialized];

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

    /// The footprint of loading the scene file `path` without a limit.
    fn loaded(path: &str) -> Footprint {
        let files = FileBudget::unlimited();
        crate::scene::load_scene_within(&data(path), &Default::default(), &files).unwrap();
        files.footprint()
    }

    #[test]
    fn scenes_count_what_they_read() {
        let f = loaded("tests/data/emitters/cornell_mesh.xml");
        assert_eq!(
            f.files.iter().map(|r| r.kind).collect::<Vec<_>>(),
            [FileKind::Scene, FileKind::Mesh(MeshFormat::Obj)]
        );
        assert_eq!(f.meshes, 162 * BYTES_PER_VERTEX + 320 * BYTES_PER_TRIANGLE);
        let f = loaded("scenes/07-torus-knot.toml");
        assert_eq!(f.meshes, 1600 * 32 * (BYTES_PER_VERTEX + 2 * BYTES_PER_TRIANGLE));
        // A medium's grid is held as its values (and a small majorant grid), not as primitives.
        let f = loaded("tests/data/media/hetero_blob.xml");
        let vol = std::fs::metadata(data("tests/data/media/hetero_blob.vol")).unwrap().len();
        assert_eq!((f.meshes, f.textures), (0, vol + 4 * 16 * 16 * 16), "{f:?}");
        assert_eq!(f.files.iter().filter(|r| r.kind == FileKind::MediumGrid).count(), 1);
        let f = loaded("scenes/15-materials.toml");
        assert!(
            f.textures > 0 && f.files[0].kind == FileKind::Scene && f.files[1..].iter().all(|r| r.bytes > 0),
            "{f:?}"
        );
    }

    /// The ledger: a file is measured and listed once however often it is read, but counted for
    /// each read; a refused file is neither counted nor listed; what is counted as nothing never
    /// fails, even with no room left.
    #[test]
    fn the_budget_counts_each_read_and_lists_each_file_once() {
        let ply = data("scenes/mitsuba/meshes/icosphere.ply");
        let one = 162 * BYTES_PER_VERTEX + 320 * BYTES_PER_TRIANGLE;
        let files = FileBudget::new(2 * one);
        files.open(Path::new("scene.xml"), FileKind::Scene).unwrap();
        files.open(&ply, FileKind::Mesh(MeshFormat::Ply)).unwrap();
        files.open(&ply, FileKind::Mesh(MeshFormat::Ply)).unwrap();
        assert_eq!(files.footprint().meshes, 2 * one);
        let err = files.open(&ply, FileKind::Mesh(MeshFormat::Ply)).unwrap_err();
        assert_eq!(err, OverBudget { what: format!("`{}`", ply.display()), bytes: one, need: 3 * one, limit: 2 * one });
        assert!(err.to_string().contains("icosphere.ply") && err.to_string().contains("MiB allowed"), "{err}");
        files.open(Path::new("part.xml"), FileKind::Include).unwrap();
        assert!(files.instance().is_err() && files.generated_mesh("torus_knot", 3, 1).is_err());
        assert_eq!(files.files(), [PathBuf::from("scene.xml"), ply, PathBuf::from("part.xml")]);
        assert_eq!(files.footprint().total(), 2 * one);
        // A file that cannot be measured counts as nothing: its loader reports the problem.
        let missing = Path::new("no/such/mesh.ply");
        files.open(missing, FileKind::Mesh(MeshFormat::Ply)).unwrap();
        assert_eq!(files.footprint().files.last().map(|f| f.bytes), Some(0));
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
                    for format in FORMATS {
                        let _ = mesh_bytes(&p, format);
                    }
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
                for format in FORMATS {
                    let _ = mesh_bytes(&p, format);
                }
            }
        }
        std::fs::remove_dir_all(&dir).ok();
    }
}
