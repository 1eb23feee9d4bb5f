//! Shards: the fixed partition of a render's sample indices among the machines of a farm.
//!
//! Shard `i` of `n` of a render of `S` samples per pixel takes, in every pixel, the sample
//! indices `floor(i S / n) .. floor((i + 1) S / n)`: one contiguous block each, sizes differing
//! by at most one. Every sample's random numbers depend only on (seed, pixel, index), so a shard
//! draws exactly the samples the one-machine render draws for those indices.

use std::ops::Range;

/// The environment variables `--shard auto/N` reads the shard index from, in this order:
/// Slurm array jobs, Kubernetes Indexed Jobs, AWS Batch array jobs.
pub const INDEX_VARIABLES: [&str; 3] = ["SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX", "AWS_BATCH_JOB_ARRAY_INDEX"];

/// Most shards a render may be split into.
pub const MAX_SHARDS: u32 = 100_000;

/// Shard `index` of `count` (0-based).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    pub index: u32,
    pub count: u32,
}

impl Shard {
    /// The sample indices this shard takes of a render of `total` samples per pixel.
    pub fn range(&self, total: u32) -> Range<u32> {
        let at = |i: u32| (i as u64 * total as u64 / self.count as u64) as u32;
        at(self.index)..at(self.index + 1)
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// `--shard` as given: `I/N`, or `auto/N` to take `I` from the scheduler's environment.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShardSpec {
    Fixed(Shard),
    Auto { count: u32 },
}

impl std::str::FromStr for ShardSpec {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("expected I/N (shard I of N, counting from 0) or auto/N, found `{s}`");
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let count: u32 = n.trim().parse().map_err(|_| bad())?;
        if count == 0 || count > MAX_SHARDS {
            return Err(format!("the number of shards must be 1 to {MAX_SHARDS}, found {count}"));
        }
        if i.trim() == "auto" {
            return Ok(ShardSpec::Auto { count });
        }
        let index: u32 = i.trim().parse().map_err(|_| bad())?;
        if index >= count {
            return Err(format!("shard {index} of {count} does not exist: shards count from 0 to {}", count - 1));
        }
        Ok(ShardSpec::Fixed(Shard { index, count }))
    }
}

impl ShardSpec {
    /// The shard, with `auto` resolved from `var` (the environment, or a stand-in for tests).
    pub fn resolve(self, var: impl Fn(&str) -> Option<String>) -> Result<Shard, String> {
        let count = match self {
            ShardSpec::Fixed(s) => return Ok(s),
            ShardSpec::Auto { count } => count,
        };
        let Some((name, value)) = INDEX_VARIABLES.iter().find_map(|&n| var(n).map(|v| (n, v))) else {
            return Err(format!(
                "--shard auto/{count} takes the shard index from {}, and none is set (outside a \
                 scheduler, give it: --shard I/{count})",
                INDEX_VARIABLES.join(", ")
            ));
        };
        let index: u32 =
            value.trim().parse().map_err(|_| format!("{name}=`{value}` is not a shard index (a number from 0)"))?;
        if index >= count {
            return Err(format!(
                "{name}={index}, but the render has {count} shards numbered 0 to {} (submit the array as \
                 --array=0-{})",
                count - 1,
                count - 1
            ));
        }
        Ok(Shard { index, count })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn parses_fixed_and_auto_and_rejects_the_rest() {
        assert_eq!("2/7".parse(), Ok(ShardSpec::Fixed(Shard { index: 2, count: 7 })));
        assert_eq!("auto/4".parse(), Ok(ShardSpec::Auto { count: 4 }));
        for bad in ["", "3", "7/7", "-1/3", "a/3", "1/0", "auto/0", "1/x", "auto/200000"] {
            assert!(bad.parse::<ShardSpec>().is_err(), "{bad}");
        }
    }

    #[test]
    fn auto_reads_the_first_scheduler_variable() {
        let env = |pairs: &'static [(&'static str, &'static str)]| {
            move |k: &str| pairs.iter().find(|(n, _)| *n == k).map(|(_, v)| v.to_string())
        };
        let auto = ShardSpec::Auto { count: 4 };
        assert_eq!(auto.resolve(env(&[("JOB_COMPLETION_INDEX", "3")])), Ok(Shard { index: 3, count: 4 }));
        assert_eq!(
            auto.resolve(env(&[("AWS_BATCH_JOB_ARRAY_INDEX", "1"), ("SLURM_ARRAY_TASK_ID", "2")])),
            Ok(Shard { index: 2, count: 4 })
        );
        let e = auto.resolve(env(&[])).unwrap_err();
        assert!(e.contains("SLURM_ARRAY_TASK_ID") && e.contains("--shard I/4"), "{e}");
        let e = auto.resolve(env(&[("SLURM_ARRAY_TASK_ID", "4")])).unwrap_err();
        assert!(e.contains("--array=0-3"), "{e}");
        assert!(auto.resolve(env(&[("SLURM_ARRAY_TASK_ID", "x")])).is_err());
    }

    proptest! {
        #[test]
        fn shards_partition_the_samples_in_order(total in 0u32..100_000, count in 1u32..200) {
            let mut next = 0;
            for index in 0..count {
                let r = Shard { index, count }.range(total);
                prop_assert_eq!(r.start, next);
                prop_assert!(r.len() as u32 <= total / count + 1 && r.len() as u32 >= total / count);
                next = r.end;
            }
            prop_assert_eq!(next, total);
        }
    }
}
