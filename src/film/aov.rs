//! Arbitrary output variables (AOVs): images written beside the render, per pixel, with the
//! names and conventions of Mitsuba 3's `aov` integrator where it has them.
//!
//! First-hit AOVs describe what the camera ray meets first (no surface: all zero, as Mitsuba's
//! zeroed interaction): `albedo` (the diffuse reflectance of its material: its Lambertian lobes,
//! 0 for mirrors, glass and metals), `depth` (the distance along the ray, Mitsuba's `si.t`),
//! `position` (world space), `uv`, `sh_normal` (shading normal, also spelled `normal`) and
//! `geo_normal`, each the average over the pixel's camera samples weighted as the image's samples
//! are. Two describe the render itself: `variance` (per colour channel, the variance of the
//! pixel's value as an estimate: the samples' variance over their count, whose square root is
//! the pixel's standard error) and `spp` (the samples the pixel holds).
//!
//! Each is stored as exact fixed-point sums (`fixed`), like the image: a sum per first-hit
//! channel and the sums of squares of the sample values for `variance`, so AOVs are bit-identical
//! on any thread count and merge exactly across a farm's shards.

use std::fmt;

/// The kinds of AOV.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AovKind {
    Albedo,
    Depth,
    Position,
    Uv,
    ShadingNormal,
    GeometricNormal,
    Variance,
    Spp,
}

impl AovKind {
    /// Every kind with its name (Mitsuba's where it has one) and channel suffixes (Mitsuba's).
    const ALL: [(AovKind, &'static str, &'static [&'static str]); 8] = [
        (AovKind::Albedo, "albedo", &["R", "G", "B"]),
        (AovKind::Depth, "depth", &["T"]),
        (AovKind::Position, "position", &["X", "Y", "Z"]),
        (AovKind::Uv, "uv", &["U", "V"]),
        (AovKind::ShadingNormal, "sh_normal", &["X", "Y", "Z"]),
        (AovKind::GeometricNormal, "geo_normal", &["X", "Y", "Z"]),
        (AovKind::Variance, "variance", &["R", "G", "B"]),
        (AovKind::Spp, "spp", &["N"]),
    ];

    /// Mitsuba's AOV types that have no counterpart here (the loader warns about them).
    pub const MITSUBA_ONLY: [&'static str; 7] =
        ["dp_du", "dp_dv", "duv_dx", "duv_dy", "prim_index", "shape_index", "boundary_test"];

    /// The kind called `name` (`normal` is the shading normal).
    pub fn named(name: &str) -> Option<AovKind> {
        let name = if name == "normal" { "sh_normal" } else { name };
        AovKind::ALL.iter().find(|k| k.1 == name).map(|k| k.0)
    }

    pub fn name(self) -> &'static str {
        AovKind::ALL.iter().find(|k| k.0 == self).map_or("", |k| k.1)
    }

    /// The suffixes of its channels.
    pub fn channels(self) -> &'static [&'static str] {
        AovKind::ALL.iter().find(|k| k.0 == self).map_or(&[], |k| k.2)
    }

    /// Whether its value comes from the camera ray's first hit.
    pub fn is_first_hit(self) -> bool {
        !matches!(self, AovKind::Variance | AovKind::Spp)
    }
}

/// One AOV: the name its channels are written under and its kind.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Aov {
    pub name: String,
    pub kind: AovKind,
}

/// The AOVs of a render, in the order asked for.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct AovList(pub Vec<Aov>);

impl AovList {
    /// Reads a list as `--aov` gives it: comma-separated entries, each a kind
    /// (`albedo,normal,depth`) written under its own name, or Mitsuba's `name:kind` pair
    /// (`dd.y:depth,nn:sh_normal`). A name may be given once.
    pub fn parse(text: &str) -> Result<AovList, String> {
        let mut list = Vec::new();
        for entry in text.split(',').map(str::trim).filter(|e| !e.is_empty()) {
            let (name, kind) = entry.split_once(':').unwrap_or((entry, entry));
            let (name, kind) = (name.trim(), kind.trim());
            let Some(k) = AovKind::named(kind) else {
                let names: Vec<&str> = AovKind::ALL.iter().map(|k| k.1).collect();
                let also =
                    if AovKind::MITSUBA_ONLY.contains(&kind) { " (a Mitsuba AOV caustic does not write)" } else { "" };
                return Err(format!("unknown AOV `{kind}`{also}; expected one of: normal, {}", names.join(", ")));
            };
            if name.is_empty() || name.contains(char::is_whitespace) {
                return Err(format!("AOV name `{name}` must be non-empty and without spaces"));
            }
            if list.iter().any(|a: &Aov| a.name == name) {
                return Err(format!("AOV `{name}` is asked for twice"));
            }
            // `normal` alone is written as `normal`, the name asked for.
            list.push(Aov { name: name.to_string(), kind: k });
        }
        if list.is_empty() {
            return Err("expected at least one AOV, e.g. albedo,normal,depth".into());
        }
        Ok(AovList(list))
    }

    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// Whether any AOV comes from the first hit (a render then intersects each camera ray once
    /// more for them).
    pub fn has_first_hit(&self) -> bool {
        self.0.iter().any(|a| a.kind.is_first_hit())
    }

    pub fn has(&self, kind: AovKind) -> bool {
        self.0.iter().any(|a| a.kind == kind)
    }

    /// The list without the AOVs of `kind`.
    pub fn without(&self, kind: AovKind) -> AovList {
        AovList(self.0.iter().filter(|a| a.kind != kind).cloned().collect())
    }

    /// Summed first-hit channels per pixel, in list order.
    pub fn first_hit_channels(&self) -> usize {
        self.0.iter().filter(|a| a.kind.is_first_hit()).map(|a| a.kind.channels().len()).sum()
    }

    /// Summed channels per pixel: the first-hit ones, then three sums of squares for `variance`.
    pub fn summed_channels(&self) -> usize {
        self.first_hit_channels() + if self.has(AovKind::Variance) { 3 } else { 0 }
    }

    /// The names of the summed channels in the order a pixel stores them: first-hit channels
    /// in list order, then the variance's sums of squares.
    pub fn sum_names(&self) -> Vec<String> {
        let names = |a: &Aov| a.kind.channels().iter().map(|c| format!("{}.{c}", a.name)).collect::<Vec<_>>();
        let hits = self.0.iter().filter(|a| a.kind.is_first_hit()).flat_map(names);
        hits.chain(self.0.iter().filter(|a| a.kind == AovKind::Variance).flat_map(names)).collect()
    }

    /// The output channels' names (`albedo.R`, `depth.T`, ...), in list order.
    pub fn channel_names(&self) -> Vec<String> {
        self.0.iter().flat_map(|a| a.kind.channels().iter().map(move |c| format!("{}.{c}", a.name))).collect()
    }

    /// Fills `out` (`first_hit_channels` long) with the first-hit values of `hit`.
    pub fn first_hit_values(&self, hit: &FirstHit, out: &mut [f32]) {
        let mut i = 0;
        for a in &self.0 {
            let v: &[f32] = match a.kind {
                AovKind::Albedo => &hit.albedo,
                AovKind::Depth => std::slice::from_ref(&hit.depth),
                AovKind::Position => &hit.position,
                AovKind::Uv => &hit.uv,
                AovKind::ShadingNormal => &hit.sh_normal,
                AovKind::GeometricNormal => &hit.geo_normal,
                AovKind::Variance | AovKind::Spp => &[],
            };
            out[i..i + v.len()].copy_from_slice(v);
            i += v.len();
        }
    }
}

impl fmt::Display for AovList {
    /// As `parse` reads it back.
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        let entries: Vec<String> = self.0.iter().map(|a| format!("{}:{}", a.name, a.kind.name())).collect();
        f.write_str(&entries.join(","))
    }
}

/// What the camera ray meets first; all zero where it meets nothing.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FirstHit {
    pub albedo: [f32; 3],
    pub depth: f32,
    pub position: [f32; 3],
    pub uv: [f32; 2],
    pub sh_normal: [f32; 3],
    pub geo_normal: [f32; 3],
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_read_as_kinds_or_mitsubas_pairs_and_read_back() {
        let l = AovList::parse("albedo, normal,dd.y:depth,position,uv,variance,spp").unwrap();
        assert_eq!(l.0[1], Aov { name: "normal".into(), kind: AovKind::ShadingNormal });
        assert_eq!(l.0[2], Aov { name: "dd.y".into(), kind: AovKind::Depth });
        assert_eq!(l.first_hit_channels(), 3 + 3 + 1 + 3 + 2);
        assert_eq!(&l.channel_names()[..5], ["albedo.R", "albedo.G", "albedo.B", "normal.X", "normal.Y"]);
        assert!(l.channel_names().contains(&"dd.y.T".to_string()));
        assert_eq!(AovList::parse(&l.to_string()), Ok(l));
        assert!(AovList::parse("albedo,albedo").unwrap_err().contains("twice"));
        let e = AovList::parse("prim_index").unwrap_err();
        assert!(e.contains("a Mitsuba AOV caustic does not write"), "{e}");
        assert!(AovList::parse("").is_err());
    }
}
