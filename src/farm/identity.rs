//! What makes two partial images parts of the same render: the caustic version, a hash of the
//! scene file and of every file it reads, the integrator, the seed, the total sample count and
//! every option that changes the image. Partial files carry it; `merge` compares it field by
//! field so that a refusal names what differs.

use crate::options::PhotonOptions;
use crate::render::RenderSettings;
use crate::scene::LoadOptions;
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
    /// everything it reads), read with `load` (its `-D` parameters and `--set` values), with
    /// integrator `integrator` and settings `settings` (the whole render's: `first_sample` is
    /// not part of it).
    pub fn new(
        files: &[PathBuf],
        load: &LoadOptions,
        integrator: &IntegratorDesc,
        settings: &RenderSettings,
    ) -> std::io::Result<Self> {
        // What changes the scene as it is read: the parameters and the values put in place of the
        // file's (a `--set` of a material's key shows in no other field). Strictness only turns
        // warnings into errors.
        let LoadOptions { defines, sets, strict: _ } = load;
        // Destructured without `..`: a new field of the description or the settings does not
        // compile until it is part of the identity, or named here as one that leaves the image as
        // it is. The names and the text of the values are those of partial files already written.
        // The Whitted integrator's ambient light and shadows and the ray offset come from the
        // scene file only (hashed in `scene`).
        let IntegratorDesc {
            kind,
            max_depth,
            light_samples,
            adc_bailout,
            photon,
            ambient: _,
            transparent_shadows: _,
            ray_bias: _,
            spectral,
        } = integrator;
        let PhotonOptions {
            photons,
            caustic_photons,
            gather,
            gather_k,
            irradiance_cache,
            cache_rays,
            caustic_k,
            max_radius,
            caustic_radius,
            volume_k,
            volume_radius,
            photons_per_iter,
            initial_radius,
        } = photon;
        let RenderSettings {
            width,
            height,
            // The crop window's place in the film and the window samples may fall in: they come
            // from the scene file's `crop` and `sample_border` (hashed in `scene`) and the film's
            // size. Only the crop's size is compared (`width`, `height`), so two film sizes given
            // by `--width`/`--height` whose rescaled crops round to the same window are not told
            // apart; a field for the film's size would make every partial file written so far
            // refuse to merge. The pixel filter can come from `--filter` too: it is a field.
            origin: _,
            filter,
            window: _,
            spp,
            // Where this shard starts: the shards of one render differ in it.
            first_sample: _,
            strata,
            seed,
            sampler,
            antialias,
            // When to stop and checkpoint: the samples are the same either way (a shard refuses
            // a time limit).
            time_limit: _,
            checkpoint: _,
            // Where the picture is shown while it renders (`--display-server`): the viewer
            // receives copies of the film, which it never changes.
            display: _,

            layers,
            aovs,
            xyz,
        } = settings;
        let opt = |v: Option<String>| v.unwrap_or_else(|| "default".into());
        let mut fields: Vec<(String, String)> = vec![
            ("version".into(), env!("CARGO_PKG_VERSION").into()),
            ("scene".into(), format!("{:016x}", hash_files(files)?)),
            ("integrator".into(), kind.name().into()),
            ("seed".into(), seed.to_string()),
            ("samples".into(), spp.to_string()),
            ("width".into(), width.to_string()),
            ("height".into(), height.to_string()),
            ("layers".into(), layers.to_string()),
            ("strata".into(), strata.to_string()),
            ("sampler".into(), format!("{sampler:?}").to_lowercase()),
            ("antialias".into(), antialias.to_string()),
            ("filter".into(), filter.filter.spelled()),
            ("aovs".into(), if aovs.is_empty() { "none".into() } else { aovs.to_string() }),
            ("max_depth".into(), opt(max_depth.map(|d| d.to_string()))),
            ("light_samples".into(), light_samples.to_string()),
            ("adc_bailout".into(), format!("{adc_bailout:?}")),
            ("photons".into(), opt(photons.map(|v| v.to_string()))),
            ("caustic_photons".into(), opt(caustic_photons.map(|v| v.to_string()))),
            ("gather".into(), opt(gather.map(|v| v.to_string()))),
            ("gather_k".into(), opt(gather_k.map(|v| v.to_string()))),
            ("irradiance_cache".into(), opt(irradiance_cache.map(|v| format!("{v:?}")))),
            ("cache_rays".into(), opt(cache_rays.map(|v| v.to_string()))),
            ("caustic_k".into(), opt(caustic_k.map(|v| v.to_string()))),
            ("max_radius".into(), opt(max_radius.map(|v| format!("{v:?}")))),
            ("caustic_radius".into(), opt(caustic_radius.map(|v| format!("{v:?}")))),
            ("volume_k".into(), opt(volume_k.map(|v| v.to_string()))),
            ("volume_radius".into(), opt(volume_radius.map(|v| format!("{v:?}")))),
            ("photons_per_iter".into(), opt(photons_per_iter.map(|v| v.to_string()))),
            ("initial_radius".into(), opt(initial_radius.map(|v| format!("{v:?}")))),
        ];
        // Named only when on, so that RGB renders keep the identities of partial files written
        // before spectral mode existed.
        if *spectral {
            fields.push(("spectral".into(), "true".into()));
        }
        // The samples are the same either way, but the merge writes the image the render asked
        // for; named only when on, as `spectral`.
        if *xyz {
            fields.push(("xyz".into(), "true".into()));
        }
        let mut defines = defines.to_vec();
        defines.sort();
        for (k, v) in defines {
            fields.push((format!("-D {k}"), v));
        }
        // The value each key ends with (a later --set of a key wins), by key: the order the
        // keys were given in does not change the render.
        let mut last: Vec<(String, String)> = Vec::new();
        for (k, v) in sets {
            last.retain(|(key, _)| key != k);
            last.push((k.clone(), v.clone()));
        }
        last.sort();
        for (k, v) in last {
            fields.push((format!("--set {k}"), v));
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
    use crate::options::{IntegratorKind, Options};
    use crate::sampling::SamplerKind;
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
            aovs: Default::default(),
            xyz: false,
        })
    }

    #[test]
    fn text_round_trips_and_differences_name_the_field() {
        let desc = IntegratorDesc::default();
        let load = LoadOptions { defines: vec![("spp".to_string(), "a\nb \\ c".to_string())], ..Default::default() };
        let a = RenderId::new(&[], &load, &desc, &settings()).unwrap();
        assert_eq!(RenderId::from_text(&a.to_text()), Some(a.clone()));
        let mut s = settings();
        s.seed = 4;
        let b = RenderId::new(&[], &load, &desc, &s).unwrap();
        let d = a.difference(&b).unwrap();
        assert_eq!((d.field.as_str(), d.left.as_str(), d.right.as_str()), ("seed", "3", "4"));
        // The first sample of a shard is not part of the identity.
        s.seed = 3;
        s.first_sample = 8;
        assert_eq!(a.difference(&RenderId::new(&[], &load, &desc, &s).unwrap()), None);
        let c = RenderId::new(&[], &LoadOptions::default(), &desc, &settings()).unwrap();
        assert_eq!(a.difference(&c).unwrap().field, "-D spp");
        assert_eq!(RenderId::from_text("no separator"), None);
    }

    /// Issue 30, item 7: a `--set` of a material's key changes the image and shows in no other
    /// field, so each key's last value is a field; the order the keys are given in is not.
    #[test]
    fn set_values_are_part_of_the_identity() {
        let desc = IntegratorDesc::default();
        let sets = |s: &[(&str, &str)]| LoadOptions {
            sets: s.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect(),
            ..Default::default()
        };
        let id = |s: &[(&str, &str)]| RenderId::new(&[], &sets(s), &desc, &settings()).unwrap();
        let none = id(&[]);
        let glass = id(&[("materials.glass.ior", "1.6")]);
        let d = none.difference(&glass).unwrap();
        assert_eq!(
            (d.field.as_str(), d.left.as_str(), d.right.as_str()),
            ("--set materials.glass.ior", "(absent)", "1.6")
        );
        assert_eq!(RenderId::from_text(&glass.to_text()), Some(glass.clone()));
        let two = id(&[("materials.glass.ior", "1.6"), ("camera.fov", "30")]);
        assert_eq!(two.difference(&id(&[("camera.fov", "30"), ("materials.glass.ior", "1.6")])), None);
        // The later value of a key is the one rendered.
        assert_eq!(id(&[("materials.glass.ior", "1.2"), ("materials.glass.ior", "1.6")]).difference(&glass), None);
        assert!(id(&[("materials.glass.ior", "1.6"), ("materials.glass.ior", "1.2")]).difference(&glass).is_some());
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

    #[test]
    fn every_option_that_changes_the_image_changes_the_identity() {
        let scene = "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\n\n[[objects]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n";
        let id = |o: &Options| {
            let loaded = crate::app::load_toml_str(scene, "id.toml", Path::new("."), o).unwrap();
            RenderId::new(&[], &LoadOptions::default(), &loaded.integrator, &loaded.settings).unwrap()
        };
        // A value for every option, none of them the scene's: built and destructured without
        // `..`, so a new option does not compile until it is tried here too.
        let every = Options {
            width: Some(32),
            height: Some(24),
            spp_axis: Some(3),
            spp: Some(5),
            max_depth: Some(2),
            adc_bailout: Some(0.5),
            seed: Some(9),
            integrator: Some(IntegratorKind::Path),
            sampler: Some(SamplerKind::Sobol),
            antialias: Some(false),
            light_samples: Some(3),
            filter: Some(crate::film::filter::Filter::Gaussian { stddev: 0.3 }),
            aov: Some(crate::film::aov::AovList::parse("albedo").unwrap()),
            display_server: Some("127.0.0.1:14158".into()),
            spectral: Some(true),
            xyz: Some(true),

            photon: PhotonOptions {
                photons: Some(1000),
                caustic_photons: Some(500),
                gather: Some(4),
                gather_k: Some(20),
                irradiance_cache: Some(0.1),
                cache_rays: Some(64),
                caustic_k: Some(8),
                max_radius: Some(0.2),
                caustic_radius: Some(0.1),
                volume_k: Some(16),
                volume_radius: Some(0.3),
                photons_per_iter: Some(300),
                initial_radius: Some(0.05),
            },
        };
        let Options {
            width,
            height,
            spp_axis,
            spp,
            max_depth,
            adc_bailout,
            seed,
            integrator,
            sampler,
            antialias,
            light_samples,
            filter,
            aov,
            display_server,
            spectral,
            xyz,

            photon,
        } = every.clone();
        let PhotonOptions {
            photons,
            caustic_photons,
            gather,
            gather_k,
            irradiance_cache,
            cache_rays,
            caustic_k,
            max_radius,
            caustic_radius,
            volume_k,
            volume_radius,
            photons_per_iter,
            initial_radius,
        } = photon;
        let none = Options::default;
        let photon = |p: PhotonOptions| Options { photon: p, ..none() };
        let nop = PhotonOptions::default;
        let one_each = [
            ("width", Options { width, ..none() }),
            ("height", Options { height, ..none() }),
            ("spp_axis", Options { spp_axis, ..none() }),
            ("spp", Options { spp, ..none() }),
            ("max_depth", Options { max_depth, ..none() }),
            ("adc_bailout", Options { adc_bailout, ..none() }),
            ("seed", Options { seed, ..none() }),
            ("integrator", Options { integrator, ..none() }),
            ("sampler", Options { sampler, ..none() }),
            ("antialias", Options { antialias, ..none() }),
            ("light_samples", Options { light_samples, ..none() }),
            ("filter", Options { filter, ..none() }),
            ("aov", Options { aov, ..none() }),
            // (The default integrator, Whitted's, refuses spectral mode.)
            ("spectral", Options { spectral, integrator, ..none() }),
            // (Not the samples but the image the merge writes.)
            ("xyz", Options { xyz, ..none() }),
            ("photons", photon(PhotonOptions { photons, ..nop() })),
            ("caustic_photons", photon(PhotonOptions { caustic_photons, ..nop() })),
            ("gather", photon(PhotonOptions { gather, ..nop() })),
            ("gather_k", photon(PhotonOptions { gather_k, ..nop() })),
            ("irradiance_cache", photon(PhotonOptions { irradiance_cache, ..nop() })),
            ("cache_rays", photon(PhotonOptions { cache_rays, ..nop() })),
            ("caustic_k", photon(PhotonOptions { caustic_k, ..nop() })),
            ("max_radius", photon(PhotonOptions { max_radius, ..nop() })),
            ("caustic_radius", photon(PhotonOptions { caustic_radius, ..nop() })),
            ("volume_k", photon(PhotonOptions { volume_k, ..nop() })),
            ("volume_radius", photon(PhotonOptions { volume_radius, ..nop() })),
            ("photons_per_iter", photon(PhotonOptions { photons_per_iter, ..nop() })),
            ("initial_radius", photon(PhotonOptions { initial_radius, ..nop() })),
        ];
        let base = id(&none());
        let mut seen = vec![base.clone()];
        for (name, o) in &one_each {
            assert_ne!(o, &none(), "{name} is the scene's own value");
            let other = id(o);
            let d = base.difference(&other);
            assert!(d.is_some(), "renders with and without {name} have the same identity");
            assert!(!seen.contains(&other), "{name} gives the identity of another option");
            seen.push(other);
        }
        assert_ne!(base.difference(&id(&every)), None);
        // Where the picture is shown as it renders changes none of its samples: a shard watched
        // in tev merges with one that was not.
        let shown = Options { display_server, ..none() };
        let loaded = crate::app::load_toml_str(scene, "id.toml", Path::new("."), &shown).unwrap();
        assert!(loaded.settings.display.is_some(), "the display server reaches the render settings");
        assert_eq!(id(&shown), base);
    }
}
