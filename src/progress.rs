//! Progress bars for long jobs: a thin wrapper over `indicatif` that draws on stderr
//! only when stderr is a terminal and the user did not ask for `--quiet`. Library code
//! receives a [`Progress`] and calls [`Progress::inc`]; it never prints otherwise.
//!
//! Nothing is drawn for the first [`REVEAL_AFTER`] of a job: a bar appears only on jobs
//! that take longer, whatever their size. A command without steps of its own runs under
//! an [`Activity`] (a spinner with the elapsed time, shown after the same delay); a
//! visible [`Progress`] bar replaces it.

//!
//! Without the `cli` feature (no `indicatif`) every bar is hidden.

#[cfg(feature = "cli")]
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
#[cfg(feature = "cli")]
use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// What draws: `indicatif`'s bar, or nothing without the `cli` feature.
#[cfg(not(feature = "cli"))]
#[derive(Clone)]
struct ProgressBar;
#[cfg(not(feature = "cli"))]
impl ProgressBar {
    fn inc(&self, _: u64) {}
    fn set_message(&self, _: String) {}
    fn finish_and_clear(&self) {}
}

/// The bar of a job whose total is known: its steps, the share done, the time it has run
/// and indicatif's estimate of the time left (the mean time per step so far times the
/// steps left).
pub const BAR_TEMPLATE: &str =
    "{msg:>12} [{bar:40}] {pos}/{len} {percent:>3}% {elapsed} elapsed, ETA {eta}";

/// How long a job runs before its bar or spinner is drawn.
pub const REVEAL_AFTER: Duration = Duration::from_secs(1);

/// The spinner of the running command, while it shows (at most one per process).
static ACTIVITY: Mutex<Option<ProgressBar>> = Mutex::new(None);

#[cfg(feature = "cli")]
fn drawable(quiet: bool) -> bool {
    !quiet && std::io::stderr().is_terminal()
}

/// A progress bar that may be hidden; all methods are no-ops when hidden.
#[derive(Clone)]
pub struct Progress {
    bar: Option<ProgressBar>,
    /// When the job started (read to reveal the bar; unused without the `cli` feature).
    #[cfg_attr(not(feature = "cli"), allow(dead_code))]
    start: Instant,
}

impl Progress {
    /// A bar of `total` steps labelled `label`; hidden when `quiet` or stderr is not a terminal.
    #[cfg(not(feature = "cli"))]
    pub fn new(_total: u64, _label: &str, _quiet: bool) -> Self {
        Progress::hidden()
    }

    /// A bar of `total` steps labelled `label`; hidden when `quiet` or stderr is not a
    /// terminal, and drawn from the first step after [`REVEAL_AFTER`].
    #[cfg(feature = "cli")]
    pub fn new(total: u64, label: &str, quiet: bool) -> Self {
        if !drawable(quiet) {
            return Progress::hidden();
        }
        let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::hidden());
        let style = ProgressStyle::with_template(BAR_TEMPLATE)
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> ");
        bar.set_style(style);
        bar.set_message(label.to_string());
        Progress {
            bar: Some(bar),
            start: Instant::now(),
        }
    }

    /// A bar that never draws.
    pub fn hidden() -> Self {
        Progress {
            bar: None,
            start: Instant::now(),
        }
    }

    /// Whether anything will be drawn (once the job has run [`REVEAL_AFTER`]).
    pub fn is_visible(&self) -> bool {
        self.bar.is_some()
    }

    /// Advance by `n` steps.
    pub fn inc(&self, n: u64) {
        if let Some(b) = &self.bar {
            #[cfg(feature = "cli")]
            if b.is_hidden() && self.start.elapsed() >= REVEAL_AFTER {
                reveal(b);
            }
            b.inc(n);
        }
    }

    /// Change the label.
    pub fn set_label(&self, label: &str) {
        if let Some(b) = &self.bar {
            b.set_message(label.to_string());
        }
    }

    /// Remove the bar from the terminal.
    pub fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}

/// Draw `b` from now on, in place of the command's spinner.
#[cfg(feature = "cli")]
fn reveal(b: &ProgressBar) {
    if let Some(spinner) = ACTIVITY.lock().unwrap_or_else(|p| p.into_inner()).take() {
        spinner.finish_and_clear();
    }
    b.set_draw_target(ProgressDrawTarget::stderr());
}

/// A spinner with the elapsed time for a whole command, drawn on a terminal once the
/// command has run [`REVEAL_AFTER`] (and not while a [`Progress`] bar shows); removed when
/// dropped.
pub struct Activity {
    bar: Option<ProgressBar>,
}

impl Activity {
    /// Start the spinner labelled `label` (nothing with `quiet`, off a terminal or
    /// without the `cli` feature).
    #[cfg(not(feature = "cli"))]
    pub fn start(_label: &str, _quiet: bool) -> Activity {
        Activity { bar: None }
    }

    /// Start the spinner labelled `label` (nothing with `quiet` or off a terminal).
    #[cfg(feature = "cli")]
    pub fn start(label: &str, quiet: bool) -> Activity {
        if !drawable(quiet) {
            return Activity { bar: None };
        }
        let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden());
        let style = ProgressStyle::with_template("{spinner} {msg} {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_spinner());
        bar.set_style(style);
        bar.set_message(label.to_string());
        *ACTIVITY.lock().unwrap_or_else(|p| p.into_inner()) = Some(bar.clone());
        let shown = bar.clone();
        let _ = std::thread::Builder::new()
            .name("mra-activity".into())
            .spawn(move || {
                std::thread::sleep(REVEAL_AFTER);
                let slot = ACTIVITY.lock().unwrap_or_else(|p| p.into_inner());
                // still the command's spinner (not replaced by a bar, not finished)
                if slot
                    .as_ref()
                    .is_some_and(|b| b.is_hidden() && !b.is_finished())
                {
                    shown.set_draw_target(ProgressDrawTarget::stderr());
                    shown.enable_steady_tick(Duration::from_millis(120));
                }
            });
        Activity { bar: Some(bar) }
    }
}

impl Drop for Activity {
    fn drop(&mut self) {
        if let Some(b) = &self.bar {
            let mut slot = ACTIVITY.lock().unwrap_or_else(|p| p.into_inner());
            *slot = None;
            b.finish_and_clear();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hidden_with_quiet_or_off_a_terminal() {
        let p = Progress::new(10, "job", true);
        assert!(!p.is_visible());
        p.inc(3);
        p.finish();
        assert!(Activity::start("job", true).bar.is_none());
        // test runners capture stderr: not a terminal, so hidden even without --quiet
        if !std::io::stderr().is_terminal() {
            assert!(!Progress::new(10, "job", false).is_visible());
            let a = Activity::start("job", false);
            assert!(a.bar.is_none());
        }
    }

    #[cfg(feature = "cli")]
    #[test]
    fn the_bar_shows_the_share_done_and_the_time_left() {
        assert!(BAR_TEMPLATE.contains("{percent:") && BAR_TEMPLATE.contains("{eta}"));
        // the template parses (a bad one would fall back to indicatif's default bar)
        assert!(ProgressStyle::with_template(BAR_TEMPLATE).is_ok());
    }
}
