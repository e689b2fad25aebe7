//! Progress bars for long jobs: a thin wrapper over `indicatif` that draws on stderr
//! only when stderr is a terminal and the user did not ask for `--quiet`. Library code
//! receives a [`Progress`] and calls [`Progress::inc`]; it never prints otherwise.

//!
//! Without the `cli` feature (no `indicatif`) every bar is hidden.

#[cfg(feature = "cli")]
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
#[cfg(feature = "cli")]
use std::io::IsTerminal;

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

/// A progress bar that may be hidden; all methods are no-ops when hidden.
#[derive(Clone)]
pub struct Progress {
    bar: Option<ProgressBar>,
}

impl Progress {
    /// A bar of `total` steps labelled `label`; hidden when `quiet` or stderr is not a terminal.
    #[cfg(not(feature = "cli"))]
    pub fn new(_total: u64, _label: &str, _quiet: bool) -> Self {
        Progress::hidden()
    }

    /// A bar of `total` steps labelled `label`; hidden when `quiet` or stderr is not a terminal.
    #[cfg(feature = "cli")]
    pub fn new(total: u64, label: &str, quiet: bool) -> Self {
        if quiet || !std::io::stderr().is_terminal() {
            return Progress::hidden();
        }
        let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
        let style = ProgressStyle::with_template("{msg:>12} [{bar:40}] {pos}/{len} {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> ");
        bar.set_style(style);
        bar.set_message(label.to_string());
        Progress { bar: Some(bar) }
    }

    /// A bar that never draws.
    pub fn hidden() -> Self {
        Progress { bar: None }
    }

    /// Whether anything will be drawn.
    pub fn is_visible(&self) -> bool {
        self.bar.is_some()
    }

    /// Advance by `n` steps.
    pub fn inc(&self, n: u64) {
        if let Some(b) = &self.bar {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hidden_with_quiet_or_off_a_terminal() {
        let p = Progress::new(10, "job", true);
        assert!(!p.is_visible());
        p.inc(3);
        p.finish();
        // test runners capture stderr: not a terminal, so hidden even without --quiet
        if !std::io::stderr().is_terminal() {
            assert!(!Progress::new(10, "job", false).is_visible());
        }
    }
}
