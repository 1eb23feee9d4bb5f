//! What makes two partial images parts of the same render: the caustic version, a hash of the
//! scene file and of every file it reads, the integrator, the seed, the total sample count and
//! every option that changes the image. Partial files carry it; `merge` compares it field by
//! field so that a refusal names what differs.

use crate::render::RenderSettings;
use crate::scene::desc::IntegratorDesc;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use xxhash_rust::xxh3::Xxh3;

/// The fields identifying a render, in a fixed order, as `(name, value)` text.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RenderId {
    pub fields: Vec<(String, String)>,
}

/// Where two identities first differ.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Difference {
    pub field: String,
    /// The field's value in each (`(absent)` when one lacks it).
    pub left: String,
    pub right: String,
}

impl RenderId {
    /// The identity of a render of the scene whose files are `files` (scene file first, then
    /// everything it reads), with `-D` parameters `defines`, integrator `integrator` and settings
    /// `settings` (the whole render's: `first_sample` is not part of it).
    pub fn new(
        files: &[PathBuf],
        defines: &[(String, String)],
        integrator: &IntegratorDesc,
        settings: &RenderSettings,
    ) -> std::io::Result<Self> {
        let p = &integrator.photon;
        let opt = |v: Option<String>| v.unwrap_or_else(|| "default".into());
        let mut fields: Vec<(String, String)> = vec![
            ("version".into(), env!("CARGO_PKG_VERSION").into()),
            ("scene".into(), format!("{:016x}", hash_files(files)?)),
            ("integrator".into(), integrator.kind.name().into()),
            ("seed".into(), settings.seed.to_string()),
            ("samples".into(), settings.spp.to_string()),
            ("width".into(), settings.width.to_string()),
            ("height".into(), settings.height.to_string()),
            ("layers".into(), settings.layers.to_string()),
            ("strata".into(), settings.strata.to_string()),
            ("sampler".into(), format!("{:?}", settings.sampler).to_lowercase()),
            ("antialias".into(), settings.antialias.to_string()),
            ("max_depth".into(), opt(integrator.max_depth.map(|d| d.to_string()))),
            ("light_samples".into(), integrator.light_samples.to_string()),
            ("adc_bailout".into(), format!("{:?}", integrator.adc_bailout)),
            ("photons".into(), opt(p.photons.map(|v| v.to_string()))),
            ("caustic_photons".into(), opt(p.caustic_photons.map(|v| v.to_string()))),
            ("gather".into(), opt(p.gather.map(|v| v.to_string()))),
            ("gather_k".into(), opt(p.gather_k.map(|v| v.to_string()))),
            ("irradiance_cache".into(), opt(p.irradiance_cache.map(|v| format!("{v:?}")))),
            ("cache_rays".into(), opt(p.cache_rays.map(|v| v.to_string()))),
            ("caustic_k".into(), opt(p.caustic_k.map(|v| v.to_string()))),
            ("max_radius".into(), opt(p.max_radius.map(|v| format!("{v:?}")))),
            ("caustic_radius".into(), opt(p.caustic_radius.map(|v| format!("{v:?}")))),
            ("photons_per_iter".into(), opt(p.photons_per_iter.map(|v| v.to_string()))),
            ("initial_radius".into(), opt(p.initial_radius.map(|v| format!("{v:?}")))),
        ];
        let mut defines = defines.to_vec();
        defines.sort();
        for (k, v) in defines {
            fields.push((format!("-D {k}"), v));
        }
        Ok(RenderId { fields })
    }

    pub fn get(&self, name: &str) -> Option<&str> {
        self.fields.iter().find(|(k, _)| k == name).map(|(_, v)| v.as_str())
    }

    /// The first field in which `self` and `other` differ, if any.
    pub fn difference(&self, other: &RenderId) -> Option<Difference> {
        let absent = || "(absent)".to_string();
        let names = self.fields.iter().map(|(k, _)| k).chain(other.fields.iter().map(|(k, _)| k));
        for name in names {
            let (a, b) = (self.get(name), other.get(name));
            if a != b {
                return Some(Difference {
                    field: name.clone(),
                    left: a.map_or_else(absent, str::to_string),
                    right: b.map_or_else(absent, str::to_string),
                });
            }
        }
        None
    }

    /// One `name = value` line per field (the form stored in partial files).
    pub fn to_text(&self) -> String {
        let mut s = String::new();
        for (k, v) in &self.fields {
            // Values are single-line: a newline in a `-D` value is written as `\n`.
            let _ = writeln!(s, "{k} = {}", v.replace('\\', "\\\\").replace('\n', "\\n"));
        }
        s
    }

    /// Parses `to_text`'s form; `None` for text that is not in it.
    pub fn from_text(text: &str) -> Option<Self> {
        let mut fields = Vec::new();
        for line in text.lines() {
            let (k, v) = line.split_once(" = ")?;
            let mut value = String::with_capacity(v.len());
            let mut chars = v.chars();
            while let Some(c) = chars.next() {
                if c == '\\' {
                    match chars.next()? {
                        'n' => value.push('\n'),
                        '\\' => value.push('\\'),
                        _ => return None,
                    }
                } else {
                    value.push(c);
                }
            }
            fields.push((k.to_string(), value));
        }
        if fields.is_empty() { None } else { Some(RenderId { fields }) }
    }
}

/// A 64-bit hash of the contents of `files` in order (names are not hashed, so the same scene
/// at another path, as on another node's mount point, hashes the same).
pub fn hash_files(files: &[PathBuf]) -> std::io::Result<u64> {
    let mut h = Xxh3::new();
    for f in files {
        let bytes = read(f)?;
        h.update(&(bytes.len() as u64).to_le_bytes());
        h.update(&bytes);
    }
    Ok(h.digest())
}

fn read(path: &Path) -> std::io::Result<Vec<u8>> {
    std::fs::read(path).map_err(|e| std::io::Error::new(e.kind(), format!("`{}`: {e}", path.display())))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::desc::Sampling;

    fn settings() -> RenderSettings {
        RenderSettings::new(&Sampling {
            width: 8,
            height: 6,
            crop: crate::film::Crop::full(8, 6),
            filter: crate::film::filter::Filter::Box,
            sample_border: false,
            spp: 16,
            strata: 4,
            seed: 3,
            sampler: crate::sampling::SamplerKind::Jittered,
            antialias: true,
        })
    }

    #[test]
    fn text_round_trips_and_differences_name_the_field() {
        let desc = IntegratorDesc::default();
        let defines = vec![("spp".to_string(), "a\nb \\ c".to_string())];
        let a = RenderId::new(&[], &defines, &desc, &settings()).unwrap();
        assert_eq!(RenderId::from_text(&a.to_text()), Some(a.clone()));
        let mut s = settings();
        s.seed = 4;
        let b = RenderId::new(&[], &defines, &desc, &s).unwrap();
        let d = a.difference(&b).unwrap();
        assert_eq!((d.field.as_str(), d.left.as_str(), d.right.as_str()), ("seed", "3", "4"));
        // The first sample of a shard is not part of the identity.
        s.seed = 3;
        s.first_sample = 8;
        assert_eq!(a.difference(&RenderId::new(&[], &defines, &desc, &s).unwrap()), None);
        let c = RenderId::new(&[], &[], &desc, &settings()).unwrap();
        assert_eq!(a.difference(&c).unwrap().field, "-D spp");
        assert_eq!(RenderId::from_text("no separator"), None);
    }

    #[test]
    fn the_scene_hash_follows_contents_not_names() {
        let dir = std::env::temp_dir().join(format!("caustic-id-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (a, b, c) = (dir.join("a.toml"), dir.join("b.toml"), dir.join("c.toml"));
        std::fs::write(&a, "x").unwrap();
        std::fs::write(&b, "x").unwrap();
        std::fs::write(&c, "y").unwrap();
        assert_eq!(hash_files(std::slice::from_ref(&a)).unwrap(), hash_files(std::slice::from_ref(&b)).unwrap());
        assert_ne!(hash_files(std::slice::from_ref(&a)).unwrap(), hash_files(std::slice::from_ref(&c)).unwrap());
        // Moving bytes between files changes the hash.
        std::fs::write(&b, "").unwrap();
        std::fs::write(&c, "xx").unwrap();
        assert_ne!(hash_files(&[a.clone(), a.clone()]).unwrap(), hash_files(&[b, c]).unwrap());
        let err = hash_files(&[dir.join("missing.ply")]).unwrap_err();
        assert!(err.to_string().contains("missing.ply"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
