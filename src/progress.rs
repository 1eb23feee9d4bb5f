//! Progress of a render on stderr, across its phases (loading, photon tracing, map building,
//! precomputation, render passes, SPPM iterations). On a terminal: one bar for the whole render,
//! with the current phase and an ETA for all that is left, and each phase's line (what it did,
//! how long it took) printed above the bar as the phase ends, so the lines stay on the screen.
//! Off a terminal (a log file, a batch job): only those lines, one per phase, so logs stay
//! short and readable.
//!
//! The ETA ([`seconds_left`]) adds up the phases still to come. A render is planned (the
//! integrator estimates each phase's cost in a unit common to its phases, roughly rays) once the
//! scene is loaded. The phase running estimates its own remainder from its progress once it is
//! a few percent done; phases not started yet are their estimated cost times the seconds per
//! unit the finished phases actually took, so a machine's speed and most of the estimates'
//! error cancel. Under a time budget the render passes end at the budget.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// Where a phase is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhaseState {
    Planned,
    Running,
    Finished,
}

/// A phase as the ETA sees it.
#[derive(Clone, Debug, PartialEq)]
pub struct Phase {
    pub name: String,
    /// Estimated cost in the render's common unit (0: not estimated).
    pub weight: f64,
    /// Units of work in the phase (0: unknown) and how many are done.
    pub total: u64,
    pub done: u64,
    /// Seconds spent in it so far (all of it once finished).
    pub seconds: f64,
    pub state: PhaseState,
    /// It stops when the time budget is used (the render passes under `--time`).
    pub until_deadline: bool,
}

impl Phase {
    /// A phase not started yet.
    pub fn planned(name: &str, weight: f64) -> Self {
        Phase {
            name: name.to_string(),
            weight,
            total: 0,
            done: 0,
            seconds: 0.0,
            state: PhaseState::Planned,
            until_deadline: false,
        }
    }

    /// The share of its work done, when it has a known amount of work.
    fn fraction(&self) -> Option<f64> {
        (self.total > 0).then(|| (self.done as f64 / self.total as f64).min(1.0))
    }
}

/// A running phase's own progress is trusted for its remainder from this share of it on (before,
/// the first chunks' speed says little: caches warm up, threads start).
const OWN_ESTIMATE_FROM: f64 = 0.05;

/// Seconds until the last of `phases` ends, or `None` while nothing says how fast this render
/// goes; `deadline` is the time left of the budget, when there is one. See the module docs.
pub fn seconds_left(phases: &[Phase], deadline: Option<f64>) -> Option<f64> {
    let finished = phases.iter().filter(|p| p.state == PhaseState::Finished && p.weight > 0.0 && p.weight.is_finite());
    let (seconds, weight) = finished.fold((0.0, 0.0), |(s, w), p| (s + p.seconds, w + p.weight));
    // Seconds per unit of estimated cost: from what finished, else from the running phase.
    let rate = if weight > 0.0 && seconds > 0.0 {
        Some(seconds / weight)
    } else {
        phases.iter().find(|p| p.state == PhaseState::Running).and_then(|p| {
            let f = p.fraction().filter(|&f| f >= OWN_ESTIMATE_FROM)?;
            (p.weight > 0.0 && p.weight.is_finite()).then(|| p.seconds / (f * p.weight))
        })
    };
    let mut left = 0.0f64;
    for p in phases {
        let estimate = match p.state {
            PhaseState::Finished => continue,
            PhaseState::Running => match (p.fraction().filter(|&f| f >= OWN_ESTIMATE_FROM), rate) {
                (Some(f), _) => p.seconds * (1.0 - f) / f,
                (None, Some(r)) if p.weight > 0.0 => (p.weight * r - p.seconds).max(0.0),
                _ => f64::INFINITY,
            },
            PhaseState::Planned => match rate {
                Some(r) if p.weight > 0.0 => p.weight * r,
                _ => f64::INFINITY,
            },
        };
        let estimate = match (p.until_deadline, deadline) {
            // It stops at the budget, or earlier when its work is done.
            (true, Some(d)) => estimate.min((d - left).max(0.0)),
            _ => estimate,
        };
        left += estimate;
    }
    left.is_finite().then_some(left)
}

/// `1m 05s`, `12s`: the ETA's form.
fn short_duration(seconds: f64) -> String {
    let s = seconds.round() as u64;
    match s {
        0..60 => format!("{s}s"),
        60..3600 => format!("{}m {:02}s", s / 60, s % 60),
        _ => format!("{}h {:02}m", s / 3600, s % 3600 / 60),
    }
}

/// Positions of the bar: per mille of the render's time.
const BAR_LENGTH: u64 = 1000;

/// The phases of the render and when the display started.
struct State {
    phases: Vec<Phase>,
    /// When the running phase started.
    phase_start: Instant,
    start: Instant,
    budget: Option<Duration>,
    /// The bar's last position, kept while the ETA is unknown.
    position: u64,
    /// When work done last moved the bar: a phase's many small steps move it a few times a second.
    moved: Instant,
    /// The phases to come are known (`Display::plan`).
    planned: bool,
}

impl State {
    /// The running phase's seconds brought up to now.
    fn now(&mut self) {
        let t = self.phase_start.elapsed().as_secs_f64();
        if let Some(p) = self.phases.iter_mut().find(|p| p.state == PhaseState::Running) {
            p.seconds = t;
        }
    }

    fn left(&mut self) -> Option<f64> {
        // Between phases before the plan (after loading) nothing says what is to come.
        if self.phases.iter().all(|p| p.state == PhaseState::Finished) {
            return None;
        }
        self.now();
        let deadline = self.budget.map(|b| b.as_secs_f64() - self.start.elapsed().as_secs_f64());
        seconds_left(&self.phases, deadline)
    }

    /// The bar's position: the share of the render's time gone, or while that is unknown, the
    /// share of the phases finished.
    fn position(&mut self) -> u64 {
        let elapsed = self.start.elapsed().as_secs_f64();
        if let Some(left) = self.left() {
            self.position = ((elapsed / (elapsed + left).max(1e-9)) * BAR_LENGTH as f64) as u64;
        }
        self.position.min(BAR_LENGTH)
    }

    /// `cache (5/6)`: the running phase (between two, the next) and, once the render is
    /// planned, where it is in the plan.
    fn prefix(&self) -> String {
        let n = self.phases.len();
        let at = |state: PhaseState| self.phases.iter().position(|p| p.state == state);
        match at(PhaseState::Running).or_else(|| at(PhaseState::Planned)).or(n.checked_sub(1)) {
            Some(i) if self.planned => format!("{} ({}/{n})", self.phases[i].name, i + 1),
            Some(i) => self.phases[i].name.clone(),
            None => String::new(),
        }
    }
}

struct Shared {
    /// Drawn on a terminal; hidden otherwise.
    bar: ProgressBar,
    terminal: bool,
    state: Arc<Mutex<State>>,
}

impl Shared {
    fn state(&self) -> MutexGuard<'_, State> {
        // A panic elsewhere while the lock was held leaves numbers that are still numbers.
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Moves the bar to where the render is. The bar draws (and reads the state for its ETA)
    /// inside these calls, so the state's lock is never held across them.
    fn redraw(&self) {
        if !self.terminal {
            return;
        }
        let (position, prefix) = {
            let mut s = self.state();
            (s.position(), s.prefix())
        };
        self.bar.set_prefix(prefix);
        self.bar.set_position(position);
    }

    /// A line above the bar (on a terminal), or on its own.
    fn line(&self, text: &str) {
        if self.terminal {
            self.bar.println(text);
        } else {
            eprintln!("{text}");
        }
    }
}

/// The progress display of one render: hidden, or shown on stderr (see the module docs).
pub struct Display {
    shared: Option<Arc<Shared>>,
}

impl Display {
    /// Shows nothing (and makes no lines).
    pub const fn hidden() -> Self {
        Display { shared: None }
    }

    /// A display of a render starting now, shown when `enabled`; `budget` is the time the whole
    /// render may take (`--time`).
    pub fn new(enabled: bool, budget: Option<Duration>) -> Self {
        if !enabled {
            return Display::hidden();
        }
        let terminal = std::io::stderr().is_terminal();
        let now = Instant::now();
        let state = Arc::new(Mutex::new(State {
            phases: Vec::new(),
            phase_start: now,
            start: now,
            budget,
            position: 0,
            moved: now,
            planned: false,
        }));
        let bar = if terminal {
            let bar = ProgressBar::with_draw_target(Some(BAR_LENGTH), ProgressDrawTarget::stderr());
            let eta = {
                let state = Arc::clone(&state);
                move |_: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
                    let left = state.lock().map(|mut s| s.left()).unwrap_or(None);
                    let _ = match left {
                        Some(s) => write!(w, "{}", short_duration(s)),
                        None => write!(w, "?"),
                    };
                }
            };
            let template = "{prefix:>14} [{elapsed_precise}] {wide_bar} {percent:>3}%  ETA {left}";
            let style = ProgressStyle::with_template(template).unwrap_or_else(|_| ProgressStyle::default_bar());
            bar.set_style(style.with_key("left", eta));
            // Redraws the clock and the ETA while a phase reports nothing (loading, map building).
            bar.enable_steady_tick(Duration::from_millis(250));
            bar
        } else {
            ProgressBar::hidden()
        };
        Display { shared: Some(Arc::new(Shared { bar, terminal, state })) }
    }

    /// Whether anything is shown.
    pub fn enabled(&self) -> bool {
        self.shared.is_some()
    }

    /// The phases to come, in order, each with its estimated cost (`integrator::plan`), after
    /// those already run; with a time budget the last one stops at it.
    pub fn plan(&self, phases: &[(&str, f64)]) {
        let Some(sh) = &self.shared else { return };
        {
            let mut s = sh.state();
            s.phases.retain(|p| p.state != PhaseState::Planned);
            s.planned = true;
            let budget = s.budget.is_some();
            let n = phases.len();
            s.phases.extend(phases.iter().enumerate().map(|(i, &(name, weight))| Phase {
                until_deadline: budget && i + 1 == n,
                ..Phase::planned(name, weight)
            }));
        }
        sh.redraw();
    }

    /// Starts the phase `name` (the next planned one of that name, or one more) of `total` units
    /// of work (0: unknown), ending the one running.
    pub fn phase(&self, name: &str, total: u64) -> Progress {
        let Some(sh) = &self.shared else { return Progress { shared: None, index: 0, start: Instant::now() } };
        let index = {
            let mut s = sh.state();
            s.now();
            for p in s.phases.iter_mut().filter(|p| p.state == PhaseState::Running) {
                p.state = PhaseState::Finished;
            }
            let i = match s.phases.iter().position(|p| p.state == PhaseState::Planned && p.name == name) {
                Some(i) => i,
                None => {
                    let i = s.phases.iter().rposition(|p| p.state != PhaseState::Planned).map_or(0, |i| i + 1);
                    s.phases.insert(i, Phase::planned(name, 0.0));
                    i
                }
            };
            // Phases planned before it that did not run (an integrator's optional step) are over.
            for p in s.phases[..i].iter_mut().filter(|p| p.state == PhaseState::Planned) {
                p.state = PhaseState::Finished;
                p.weight = 0.0;
            }
            s.phases[i].state = PhaseState::Running;
            s.phases[i].total = total;
            s.phase_start = Instant::now();
            i
        };
        sh.redraw();
        Progress { shared: Some(Arc::clone(sh)), index, start: Instant::now() }
    }

    /// Writes a line of the render's log (above the bar on a terminal); nothing when hidden.
    pub fn say(&self, text: &str) {
        if let Some(sh) = &self.shared {
            sh.line(text);
        }
    }

    /// Writes a warning, which is shown even when the display is hidden (`--quiet`).
    pub fn warn(&self, text: &str) {
        match &self.shared {
            Some(sh) => sh.line(&format!("warning: {text}")),
            None => eprintln!("warning: {text}"),
        }
    }

    /// The phases so far, for tests and the log.
    pub fn phases(&self) -> Vec<Phase> {
        self.shared.as_ref().map_or_else(Vec::new, |sh| sh.state().phases.clone())
    }
}

impl Drop for Display {
    fn drop(&mut self) {
        if let Some(sh) = &self.shared {
            sh.bar.finish_and_clear();
        }
    }
}

/// One phase's progress: work done, and its end.
pub struct Progress {
    shared: Option<Arc<Shared>>,
    index: usize,
    start: Instant,
}

impl Progress {
    /// Records `n` more units done.
    pub fn inc(&self, n: u64) {
        let Some(sh) = &self.shared else { return };
        let due = {
            let mut s = sh.state();
            s.phases[self.index].done += n;
            let due = s.moved.elapsed() >= Duration::from_millis(50);
            if due {
                s.moved = Instant::now();
            }
            due
        };
        if due {
            sh.redraw();
        }
    }

    /// Ends the phase; `what` says what it did, in its line (`cache: 6392 irradiance-cache
    /// records in 5.46 s`).
    pub fn finish(&self, what: &str) {
        let Some(sh) = &self.shared else { return };
        self.end();
        let name = sh.state().phases[self.index].name.clone();
        sh.line(&format!("{name}: {what} in {:.2} s", self.start.elapsed().as_secs_f64()));
    }

    /// Ends the phase without a line.
    pub fn end(&self) {
        let Some(sh) = &self.shared else { return };
        {
            let mut s = sh.state();
            s.now();
            let p = &mut s.phases[self.index];
            if p.state == PhaseState::Running {
                p.state = PhaseState::Finished;
                p.seconds = self.start.elapsed().as_secs_f64();
            }
        }
        sh.redraw();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn phase(name: &str, weight: f64, state: PhaseState, seconds: f64, done: u64, total: u64) -> Phase {
        Phase { seconds, done, total, state, ..Phase::planned(name, weight) }
    }

    /// Issue 30, item 1: an ETA across the phases of a render, from the running phase's own
    /// progress and the finished phases' seconds per unit of estimated cost.
    #[test]
    fn the_eta_adds_the_phases_left() {
        use PhaseState::{Finished, Planned, Running};
        // Finished: 200 units in 2 s, so 0.01 s a unit (the load, unweighted, does not count).
        let done = [
            phase("load", 0.0, Finished, 5.0, 0, 0),
            phase("photons", 100.0, Finished, 1.0, 100, 100),
            phase("maps", 100.0, Finished, 1.0, 0, 0),
        ];
        let with = |more: &[Phase]| [&done[..], more].concat();
        // Half done in 3 s: 3 s more; then 300 units at 0.01 s.
        let p = with(&[phase("cache", 200.0, Running, 3.0, 500, 1000), phase("render", 300.0, Planned, 0.0, 0, 0)]);
        assert!((seconds_left(&p, None).unwrap() - 6.0).abs() < 1e-9);
        // 1% done says little: the running phase is its cost at the measured rate, less its time.
        let p = with(&[phase("cache", 200.0, Running, 0.5, 10, 1000), phase("render", 300.0, Planned, 0.0, 0, 0)]);
        assert!((seconds_left(&p, None).unwrap() - (1.5 + 3.0)).abs() < 1e-9);
        // A phase that runs longer than estimated is not given negative time.
        let p = with(&[phase("maps2", 100.0, Running, 9.0, 0, 0)]);
        assert_eq!(seconds_left(&p, None), Some(0.0));
        // Nothing finished and the first phase barely begun: no basis for an ETA.
        let first = [phase("photons", 100.0, Running, 0.2, 1, 100), phase("render", 300.0, Planned, 0.0, 0, 0)];
        assert_eq!(seconds_left(&first, None), None);
        // 20% done in 1 s: its own rate (0.05 s a unit) prices the phases to come too.
        let first = [phase("photons", 100.0, Running, 1.0, 20, 100), phase("render", 300.0, Planned, 0.0, 0, 0)];
        assert!((seconds_left(&first, None).unwrap() - (4.0 + 15.0)).abs() < 1e-9);
        assert_eq!(seconds_left(&done, None), Some(0.0));
    }

    /// Under a time budget the render passes end at the budget (or before, when their samples are
    /// done); preparation that runs past it is still counted.
    #[test]
    fn the_render_passes_end_at_the_budget() {
        use PhaseState::{Finished, Planned, Running};
        let render =
            |state, seconds| Phase { until_deadline: true, ..phase("render", f64::INFINITY, state, seconds, 0, 0) };
        let prep = phase("photons", 100.0, Finished, 1.0, 100, 100);
        let cache = phase("cache", 200.0, Running, 1.0, 100, 1000);
        // 9 s of 10 s left: the cache needs 9 s more, and the passes get what remains (none).
        assert!(
            (seconds_left(&[prep.clone(), cache.clone(), render(Planned, 0.0)], Some(9.0)).unwrap() - 9.0).abs() < 1e-9
        );
        // 20 s left: the cache's 9 s, then the passes until the budget.
        assert!((seconds_left(&[prep.clone(), cache, render(Planned, 0.0)], Some(20.0)).unwrap() - 20.0).abs() < 1e-9);
        // Rendering with 4 s of the budget left, however many samples a count would allow.
        assert!((seconds_left(&[prep.clone(), render(Running, 2.0)], Some(4.0)).unwrap() - 4.0).abs() < 1e-9);
        // Past the budget (the first pass still running): nothing left to wait for but the pass.
        assert_eq!(seconds_left(&[prep, render(Running, 2.0)], Some(-0.5)), Some(0.0));
        // Samples that end before the budget end the phase.
        let counted = Phase { until_deadline: true, ..phase("render", 300.0, Running, 2.0, 50, 100) };
        assert!((seconds_left(&[counted], Some(30.0)).unwrap() - 2.0).abs() < 1e-9);
    }

    #[test]
    fn phases_run_in_the_planned_order_and_unplanned_ones_fit_in() {
        let d = Display { shared: None };
        assert!(d.phases().is_empty(), "a hidden display keeps nothing");
        let state = State {
            phases: Vec::new(),
            phase_start: Instant::now(),
            start: Instant::now(),
            budget: Some(Duration::from_secs(5)),
            position: 0,
            moved: Instant::now(),
            planned: false,
        };
        let sh = Arc::new(Shared { bar: ProgressBar::hidden(), terminal: false, state: Arc::new(Mutex::new(state)) });
        let d = Display { shared: Some(sh) };
        let load = d.phase("load", 0);
        load.end();
        d.plan(&[("photons", 10.0), ("gather", 5.0), ("cache", 20.0), ("render", 100.0)]);
        let photons = d.phase("photons", 100);
        photons.inc(40);
        // `gather` did not run (a skipped step); `cache` starts.
        let _cache = d.phase("cache", 7);
        let p = d.phases();
        let names: Vec<&str> = p.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(names, ["load", "photons", "gather", "cache", "render"]);
        let states: Vec<PhaseState> = p.iter().map(|p| p.state).collect();
        use PhaseState::{Finished, Planned, Running};
        assert_eq!(states, [Finished, Finished, Finished, Running, Planned]);
        assert_eq!((p[1].done, p[1].total, p[2].weight, p[3].total), (40, 100, 0.0, 7));
        assert!(p[4].until_deadline && !p[3].until_deadline, "the last planned phase stops at the budget");
        // A phase nobody planned goes after the ones that ran.
        let _extra = d.phase("extra", 0);
        let names: Vec<String> = d.phases().into_iter().map(|p| p.name).collect();
        assert_eq!(names, ["load", "photons", "gather", "cache", "extra", "render"]);
    }

    #[test]
    fn durations_are_short() {
        assert_eq!(short_duration(4.4), "4s");
        assert_eq!(short_duration(65.0), "1m 05s");
        assert_eq!(short_duration(7300.0), "2h 01m");
    }
}
