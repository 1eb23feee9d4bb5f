//! A render-farm shard inside `caustic render --shard I/N`: its block of samples, its render
//! identity, and resuming from the partial image an earlier run of it left.

use super::{AppError, LoadedScene};
use crate::farm::identity::RenderId;
use crate::farm::partial::{PartialHeader, SumKind, read_partial, write_partial};
use crate::farm::shard::Shard;
use crate::film::Film;
use crate::options::IntegratorKind;
use crate::render::RenderSettings;
use crate::scene::LoadOptions;
use std::path::{Path, PathBuf};

/// A shard about to render.
pub struct ShardJob {
    pub header: PartialHeader,
    pub output: PathBuf,
    /// What an earlier run of this shard finished (empty for a new one).
    pub prior: Film,
}

impl ShardJob {
    /// Restricts `settings` (the whole render's) to the shard's samples and picks up the
    /// partial image at `output` when it is an earlier run of the same shard (the scene read with
    /// `load`). `log` receives
    /// what was found.
    pub fn prepare(
        loaded: &LoadedScene,
        load: &LoadOptions,
        settings: &mut RenderSettings,
        shard: Shard,
        output: &Path,
        log: &dyn Fn(&str),
    ) -> Result<Self, AppError> {
        let id = RenderId::new(&loaded.info.files, load, &loaded.integrator, settings)
            .map_err(|e| AppError::Shard(format!("cannot read a scene file to identify the render: {e}")))?;
        let range = shard.range(settings.spp);
        let sums = if loaded.integrator.kind == IntegratorKind::Sppm { SumKind::Runs } else { SumKind::Exact };
        let header = PartialHeader {
            id,
            shard,
            range: range.clone(),
            sums,
            width: settings.width,
            height: settings.height,
            layers: settings.layers,
            aovs: settings.aovs.clone(),
        };
        settings.first_sample = range.start;
        settings.spp = range.end;
        let fresh = || settings.new_film();
        let prior = if output.exists() {
            match read_partial(output) {
                Ok(p) if p.header == header => {
                    let (lo, hi) = (p.film.min_samples(), p.film.max_samples());
                    let held = |n: u32| range.start + n;
                    log(&format!(
                        "resuming shard {shard} from `{}`: it holds samples {}..{}{} of {}..{}",
                        output.display(),
                        range.start,
                        held(lo),
                        if hi > lo { format!(" (to {} in places)", held(hi)) } else { String::new() },
                        range.start,
                        range.end
                    ));
                    p.film
                }
                Ok(p) => {
                    let why = match p.header.id.difference(&header.id) {
                        Some(d) => format!("its `{}` is {}, this render's is {}", d.field, d.left, d.right),
                        None => format!("it is shard {} (samples {:?}), not {shard}", p.header.shard, p.header.range),
                    };
                    eprintln!(
                        "warning: `{}` is a partial image of another render ({why}); starting this shard afresh",
                        output.display()
                    );
                    fresh()
                }
                Err(e) => {
                    eprintln!("warning: {e}; starting this shard afresh and replacing it");
                    fresh()
                }
            }
        } else {
            fresh()
        };
        Ok(ShardJob { header, output: output.to_path_buf(), prior })
    }

    /// Whether the earlier run already finished every sample.
    pub fn complete(&self) -> bool {
        self.prior.min_samples() as usize >= self.header.range.len()
    }

    /// Saves `film` as the shard's partial image.
    pub fn save(&self, film: &Film) -> Result<(), AppError> {
        Ok(write_partial(&self.output, &self.header, film)?)
    }

    /// `a..b` of the samples `film` holds everywhere, for messages.
    pub fn held(&self, film: &Film) -> String {
        let start = self.header.range.start;
        format!("{start}..{}", start + film.min_samples())
    }
}
