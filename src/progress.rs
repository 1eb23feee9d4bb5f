//! Progress of the phases of a render on stderr (photon tracing, map building, precomputation,
//! render passes, SPPM iterations): on a terminal a bar with an ETA, measured in work units or,
//! under a time budget, in seconds of the budget; otherwise (a log file, a batch job) one line
//! when each phase ends, so logs stay short and readable.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// One phase's progress.
pub struct Progress {
    bar: ProgressBar,
    /// With a time budget the bar shows elapsed time against it, not work done.
    budget: Option<Duration>,
    start: Instant,
    phase: String,
    /// Not a terminal: report the phase in one line when it ends.
    lines: bool,
    done: AtomicU64,
}

impl Progress {
    /// Progress of `total` units of work (0 when unknown) in the phase called `phase`; nothing is
    /// shown unless `enabled`. With a `budget`, progress is the time used of it.
    pub fn new(enabled: bool, phase: &str, total: u64, budget: Option<Duration>) -> Self {
        let start = Instant::now();
        let terminal = std::io::stderr().is_terminal();
        let hidden = Progress {
            bar: ProgressBar::hidden(),
            budget,
            start,
            phase: phase.to_string(),
            lines: enabled && !terminal,
            done: AtomicU64::new(0),
        };
        if !enabled || !terminal {
            return hidden;
        }
        let len = match budget {
            Some(b) => b.as_millis() as u64,
            None => total,
        };
        let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
        let template = if budget.is_some() {
            format!("{phase:>9} [{{elapsed_precise}}] {{wide_bar}} {{percent:>3}}% of the time budget")
        } else {
            format!("{phase:>9} [{{elapsed_precise}}] {{wide_bar}} {{percent:>3}}%  ETA {{eta}}")
        };
        bar.set_style(ProgressStyle::with_template(&template).unwrap_or_else(|_| ProgressStyle::default_bar()));
        Progress { bar, ..hidden }
    }

    /// Records `n` more units done.
    pub fn inc(&self, n: u64) {
        self.done.fetch_add(n, Ordering::Relaxed);
        match self.budget {
            Some(b) => self.bar.set_position(self.start.elapsed().min(b).as_millis() as u64),
            None => self.bar.inc(n),
        }
    }

    /// Ends the phase; `what` describes what it did (for the one line written off a terminal).
    pub fn finish(&self, what: &str) {
        self.bar.finish_and_clear();
        if self.lines {
            eprintln!("{}: {what} in {:.2} s", self.phase, self.start.elapsed().as_secs_f64());
        }
    }
}
