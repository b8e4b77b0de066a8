//! Progress bars for long steps, drawn on stderr with indicatif.
//!
//! A [`Bar`] is drawn only when stderr is a terminal (never in pipes, CI logs or tests), so
//! `--json` output on stdout stays one clean document. Library code never prints: a bar is
//! attached as an observer ([`hystcomp_identify::Observer`] here; other long steps can feed
//! [`Bar::set_length`], [`Bar::set_position`] and [`Bar::set_message`] directly).

use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// One progress bar on stderr: a label, a bar, `position/length`, the elapsed time and a
/// message.
#[derive(Debug)]
pub struct Bar {
    bar: ProgressBar,
}

impl Bar {
    /// A bar of `length` steps labelled `label`, drawn on stderr when it is a terminal.
    pub fn new(label: &str, length: u64) -> Self {
        Self::with_target(label, length, ProgressDrawTarget::stderr())
    }

    /// A bar that never draws (e.g. for `--quiet`).
    pub fn hidden() -> Self {
        Self::with_target("", 0, ProgressDrawTarget::hidden())
    }

    fn with_target(label: &str, length: u64, target: ProgressDrawTarget) -> Self {
        let bar = ProgressBar::with_draw_target(Some(length), target);
        let style = ProgressStyle::with_template(
            "{prefix:>12} [{bar:30}] {pos}/{len} {elapsed_precise} {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ");
        bar.set_style(style);
        bar.set_prefix(label.to_owned());
        bar.enable_steady_tick(Duration::from_millis(200));
        Bar { bar }
    }

    /// Whether the bar draws at all.
    pub fn is_visible(&self) -> bool {
        !self.bar.is_hidden()
    }

    /// A new label (e.g. the next stage of a long command).
    pub fn set_label(&self, label: &str) {
        self.bar.set_prefix(label.to_owned());
    }

    /// The number of steps.
    pub fn set_length(&self, length: u64) {
        self.bar.set_length(length);
    }

    /// The steps done.
    pub fn set_position(&self, position: u64) {
        self.bar.set_position(position);
    }

    /// The text after the bar.
    pub fn set_message(&self, message: impl Into<String>) {
        self.bar.set_message(message.into());
    }

    /// Removes the bar from the terminal.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

impl Drop for Bar {
    fn drop(&mut self) {
        if !self.bar.is_finished() {
            self.bar.finish_and_clear();
        }
    }
}

/// The bar follows a solver: iterations as steps, the best RMS error (in % of the output
/// range, since the problem is normalised by it) as the message.
impl hystcomp_identify::Observer for Bar {
    fn begin(&mut self, label: &str) {
        self.set_label(label);
        self.set_position(0);
    }

    fn observe(&mut self, progress: &hystcomp_identify::Progress) {
        self.set_length(progress.iterations as u64);
        self.set_position(progress.iteration as u64);
        let feasible = if progress.best_violation > 0.0 {
            " (infeasible)"
        } else {
            ""
        };
        self.set_message(format!(
            "best RMS {:.4} %{feasible}",
            100.0 * progress.best_cost
        ));
    }
}
