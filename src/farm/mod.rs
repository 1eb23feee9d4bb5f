//! Rendering on many machines. A render's sample indices are split into shards (`shard`); each
//! shard writes a partial image holding exact per-pixel sums and the identity of its render
//! (`partial`, `identity`); `merge` adds the parts into the image the one-machine render would
//! have made, bit for bit; `slurm` writes and submits the array job and the merge job.
//! caustic brings no scheduler: the shards run wherever the user's scheduler puts them, on a
//! file system that every node shares.

pub mod identity;
pub mod merge;
pub mod partial;
pub mod shard;
pub mod slurm;

#[derive(Debug, thiserror::Error)]
pub enum FarmError {
    /// A partial image that cannot be used: missing, truncated, damaged or of another render.
    #[error("partial image `{path}` {message}")]
    Part { path: String, message: String },
    /// Parts that do not make one render (different renders, overlaps, missing samples).
    #[error("cannot merge: {0}")]
    Refused(String),
    #[error(transparent)]
    Output(#[from] crate::film::output::OutputError),
    /// Submitting to or asking the scheduler failed.
    #[error("{0}")]
    Scheduler(String),
}
