//! `caustic merge`: adds the partial images of a render's shards into its image.
//!
//! Exact parts (Whitted, path, photon) hold integer sums of samples, so the merged film, and
//! the image made from it, are bit for bit the one-machine render's. Parts of progressive runs
//! (SPPM) are combined as probabilistic progressive photon mapping combines its passes (Knaus
//! and Zwicker 2011): each run's image is an estimate whose bias shrinks as that run's radii
//! shrink, and the merged image is their mean weighted by iterations. Its noise falls with the
//! total number of iterations; its bias is that of one run of a shard's length, so it converges
//! to the exact image as the iterations per shard grow.

use super::FarmError;
use super::partial::{PartialHeader, SumKind, read_header, read_partial};
use crate::film::Film;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// What a merge found.
#[derive(Clone, Debug, PartialEq)]
pub struct MergeReport {
    pub parts: usize,
    /// Samples per pixel of the whole render.
    pub total: u32,
    /// Fewest and most samples any pixel of the merged image has.
    pub min_samples: u32,
    pub max_samples: u32,
    /// The samples no part holds, described for the user (empty when complete).
    pub missing: Vec<String>,
    pub sums: SumKind,
    /// The render asked for XYZ colour channels (the identity's `xyz`).
    pub xyz: bool,
}

fn refused(msg: String) -> FarmError {
    FarmError::Refused(msg)
}

fn show(p: &Path) -> String {
    format!("`{}`", p.display())
}

fn range(r: &Range<u32>) -> String {
    format!("{}..{}", r.start, r.end)
}

/// Checks that the parts belong to one render and do not overlap; returns them sorted by range.
fn check_headers(parts: &[(PathBuf, PartialHeader)]) -> Result<Vec<usize>, FarmError> {
    let (first_path, first) = &parts[0];
    for (path, h) in &parts[1..] {
        if let Some(d) = first.id.difference(&h.id) {
            return Err(refused(format!(
                "{} and {} are parts of different renders: `{}` is {} in {} and {} in {}",
                show(first_path),
                show(path),
                d.field,
                d.left,
                show(first_path),
                d.right,
                show(path)
            )));
        }
        if h.sums != first.sums {
            return Err(refused(format!("{} and {} hold different kinds of sums", show(first_path), show(path))));
        }
    }
    let mut order: Vec<usize> = (0..parts.len()).collect();
    order.sort_by_key(|&i| (parts[i].1.range.start, parts[i].1.range.end));
    let mut last: Option<usize> = None;
    for &i in &order {
        let (path, h) = &parts[i];
        if h.range.is_empty() {
            continue;
        }
        if let Some(l) = last {
            let (lp, lh) = &parts[l];
            if h.range.start < lh.range.end {
                let both = h.range.start..h.range.end.min(lh.range.end);
                let what = if lp == path {
                    format!("{} is given twice", show(path))
                } else {
                    format!(
                        "{} (shard {}, samples {}) and {} (shard {}, samples {}) overlap",
                        show(lp),
                        lh.shard,
                        range(&lh.range),
                        show(path),
                        h.shard,
                        range(&h.range)
                    )
                };
                return Err(refused(format!("{what}: samples {} would be counted twice", range(&both))));
            }
        }
        last = Some(i);
    }
    Ok(order)
}

/// Merges the partial images `paths` into one film. Refuses parts of different renders,
/// overlapping parts, damaged files and, unless `allow_partial`, missing samples.
pub fn merge(paths: &[PathBuf], allow_partial: bool) -> Result<(Film, MergeReport), FarmError> {
    if paths.is_empty() {
        return Err(refused("no parts to merge".into()));
    }
    let parts: Vec<(PathBuf, PartialHeader)> =
        paths.iter().map(|p| Ok((p.clone(), read_header(p)?))).collect::<Result<_, FarmError>>()?;
    let order = check_headers(&parts)?;
    let first = &parts[0].1;
    let total: u32 = first.id.get("samples").and_then(|s| s.parse().ok()).unwrap_or(0);
    let mut film = Film::new(first.width, first.height, first.layers).with_aovs(&first.aovs);
    let mut missing = Vec::new();
    let mut covered = 0u32;
    for &i in &order {
        let (path, h) = &parts[i];
        if h.range.start > covered {
            missing.push(format!("samples {} (no part holds them)", range(&(covered..h.range.start))));
        }
        let part = read_partial(path)?;
        if part.header != *h {
            return Err(FarmError::Part {
                path: path.display().to_string(),
                message: "changed while it was being merged".into(),
            });
        }
        let (lo, hi) = (part.film.min_samples(), part.film.max_samples());
        if lo < h.range.len() as u32 {
            let gap = h.range.start + lo..h.range.end;
            let short = part.film.tiles.iter().flat_map(|t| &t.count).filter(|&&c| c < h.range.len() as u32).count();
            let pixels = h.width as usize * h.height as usize;
            missing.push(if hi == lo {
                format!("samples {} ({} stopped early: it holds {} of {})", range(&gap), show(path), lo, h.range.len())
            } else {
                format!(
                    "samples {} in {short} of {pixels} pixels ({} stopped early: it holds {} to {} of {})",
                    range(&gap),
                    show(path),
                    lo,
                    hi,
                    h.range.len()
                )
            });
        }
        film.add(&part.film);
        covered = covered.max(h.range.end);
    }
    if covered < total {
        missing.push(format!("samples {} (no part holds them)", range(&(covered..total))));
    }
    if !missing.is_empty() && !allow_partial {
        return Err(refused(format!(
            "the parts do not hold every sample of the render's {total}: missing {}; run the missing or \
             unfinished shards again (they resume where they stopped), or merge what there is with \
             --allow-partial",
            missing.join("; ")
        )));
    }
    let report = MergeReport {
        parts: parts.len(),
        total,
        min_samples: film.min_samples(),
        max_samples: film.max_samples(),
        missing,
        sums: first.sums,
        xyz: first.id.get("xyz") == Some("true"),
    };
    Ok((film, report))
}
