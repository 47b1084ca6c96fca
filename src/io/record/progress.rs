//! Progress bar on stderr (indicatif), as a [`Recorder`]: it listens to `run_started`, `step`,
//! `step_rejected` and `run_finished` and never asks for views, so it costs nothing per step
//! beyond a redraw (rate-limited by indicatif). The bar is drawn only when stderr is a terminal;
//! `--quiet` leaves it out.
//!
//! Load stepping shows the load factor λ; a time-stepping driver (`RunMeta::time_name` =
//! `"time"`) shows the simulated time against `time_end`, the revolutions (when
//! `revolution_period` is given), the steps and the steps per second:
//!
//! ```text
//! ⠙ [00:00:12] ████████░░░░░░░░ ETA 00:00:36  t = 1.250e-1 / 5.000e-1  rev 2.98  step 1250  104.2 steps/s
//! ```
//!
//! The ETA is indicatif's estimate of the time left to the end of the bar (`time_end`, or
//! λ = 1) at the recent rate: an upper bound for a transient run, which stops as soon as
//! steady rolling is reached.

use super::{RecordError, Recorder, RejectedStep, RunEnd, RunMeta, StepInfo};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::time::Instant;

const TICKS: u64 = 1000;

/// The bar's layout: spinner, elapsed time, bar, time left at the recent rate, message.
const TEMPLATE: &str = "{spinner} [{elapsed_precise}] {bar:30} ETA {eta_precise} {msg}";

pub struct Progress {
    bar: Option<ProgressBar>,
    time_end: f64,
    period: Option<f64>,
    load_factor: bool,
    start: Instant,
    rejected: u64,
}

impl Default for Progress {
    fn default() -> Self {
        Self::new()
    }
}

impl Progress {
    pub fn new() -> Self {
        Self {
            bar: None,
            time_end: 1.0,
            period: None,
            load_factor: true,
            start: Instant::now(),
            rejected: 0,
        }
    }

    /// The status line of a step (also usable without a bar, e.g. in logs).
    pub fn message(&self, info: &StepInfo) -> String {
        let secs = self.start.elapsed().as_secs_f64();
        let rate = if secs > 0.0 {
            (info.index + 1) as f64 / secs
        } else {
            0.0
        };
        let cut = if self.rejected > 0 {
            format!("  cut-backs {}", self.rejected)
        } else {
            String::new()
        };
        if self.load_factor {
            format!(
                "λ = {:.4}  step {}  Newton {}{cut}  {rate:.1} steps/s",
                info.time,
                info.index + 1,
                info.newton_iterations
            )
        } else {
            let rev = self
                .period
                .filter(|p| *p > 0.0)
                .map(|p| format!("  rev {:.2}", info.time / p))
                .unwrap_or_default();
            format!(
                "t = {:.3e} / {:.3e}{rev}  step {}{cut}  {rate:.1} steps/s",
                info.time,
                self.time_end,
                info.index + 1
            )
        }
    }
}

impl Recorder for Progress {
    fn run_started(&mut self, meta: &RunMeta) {
        self.time_end = if meta.time_end > 0.0 {
            meta.time_end
        } else {
            1.0
        };
        self.period = meta.revolution_period;
        self.load_factor = meta.time_name == "load_factor";
        self.start = Instant::now();
        let bar = ProgressBar::with_draw_target(Some(TICKS), ProgressDrawTarget::stderr());
        let style =
            ProgressStyle::with_template(TEMPLATE).unwrap_or_else(|_| ProgressStyle::default_bar());
        bar.set_style(style);
        bar.set_message(format!("{}: starting", meta.scene_name));
        self.bar = Some(bar);
    }
    fn step(&mut self, info: &StepInfo, _view: Option<&super::StepView>) {
        let msg = self.message(info);
        if let Some(bar) = &self.bar {
            let f = (info.time / self.time_end).clamp(0.0, 1.0);
            bar.set_position((f * TICKS as f64).round() as u64);
            bar.set_message(msg);
        }
    }
    fn step_rejected(&mut self, _s: &RejectedStep) {
        self.rejected += 1;
    }
    fn run_finished(&mut self, _end: &RunEnd) -> Vec<RecordError> {
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
        Vec::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The layout parses (an invalid template would silently fall back to the default bar,
    /// which has no ETA) and shows the time left.
    #[test]
    fn template_parses_and_shows_the_eta() {
        assert!(ProgressStyle::with_template(TEMPLATE).is_ok());
        assert!(TEMPLATE.contains("{eta_precise}"));
        assert!(ProgressStyle::with_template("{spinner} {bar:30 {msg}").is_err());
    }

    #[test]
    fn time_stepping_message_shows_time_revolutions_and_rate() {
        let mut p = Progress::new();
        p.load_factor = false;
        p.time_end = 0.5;
        p.period = Some(0.1);
        let info = StepInfo {
            index: 99,
            time: 0.25,
            dt: 0.0025,
            newton_iterations: 3,
            residual: 1e-11,
            is_final: false,
        };
        let m = p.message(&info);
        assert!(
            m.starts_with("t = 2.500e-1 / 5.000e-1  rev 2.50  step 100"),
            "{m}"
        );
        assert!(m.ends_with("steps/s"), "{m}");
        p.load_factor = true;
        assert!(p
            .message(&info)
            .starts_with("λ = 0.2500  step 100  Newton 3"));
    }
}
