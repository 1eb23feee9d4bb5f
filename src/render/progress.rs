//! Progress of a render phase on stderr: a bar with an ETA on a terminal, measured in work
//! units, or in seconds of the time budget when the render has one.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::time::{Duration, Instant};

/// One phase's progress (photon tracing, rendering passes, ...).
pub struct Progress {
    bar: ProgressBar,
    /// With a time budget the bar shows elapsed time against it, not work done.
    budget: Option<Duration>,
    start: Instant,
}

impl Progress {
    /// A progress display for `total` units of work named `phase`; hidden unless `enabled` and
    /// stderr is a terminal. With a `budget`, progress is the time used of it.
    pub fn new(enabled: bool, phase: &str, total: u64, budget: Option<Duration>) -> Self {
        let start = Instant::now();
        if !enabled || !std::io::stderr().is_terminal() {
            return Progress { bar: ProgressBar::hidden(), budget, start };
        }
        let len = match budget {
            Some(b) => b.as_millis() as u64,
            None => total,
        };
        let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
        let template = format!("{phase:>8} [{{elapsed_precise}}] {{wide_bar}} {{percent:>3}}%  ETA {{eta}}");
        bar.set_style(ProgressStyle::with_template(&template).unwrap_or_else(|_| ProgressStyle::default_bar()));
        Progress { bar, budget, start }
    }

    /// Records `n` more units done.
    pub fn inc(&self, n: u64) {
        match self.budget {
            Some(b) => self.bar.set_position(self.start.elapsed().min(b).as_millis() as u64),
            None => self.bar.inc(n),
        }
    }

    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
