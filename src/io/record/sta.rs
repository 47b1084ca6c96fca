//! Increment status file `run.sta` (in the manner of Abaqus's `.sta`): one line per attempted
//! increment, written and flushed as the run goes, so `tail -f run.sta` follows a long run and
//! an interrupted or killed run leaves every finished line readable.
//!
//! Plain text: lines starting with `#` are comments (a header naming the run and the columns,
//! and the closing line); the others are whitespace-separated columns
//!
//! | column | meaning |
//! |---|---|
//! | `step` | index of the accepted step (0, 1, 2, …); a rejected attempt carries the index the step would have had |
//! | `attempt` | 1 for the first try of a step, 2, 3, … after each cut-back |
//! | `status` | `accepted`, or `cutback` (the attempt failed and is retried with a smaller increment) |
//! | `time` | simulated time (s, or the scene's time unit) in a transient; the load factor λ (dimensionless) in load stepping; the continuation parameter in a continuation |
//! | `dt` | increment of `time` of the attempt |
//! | `newton` | Newton iterations of the attempt (`-` when unknown: a cut-back attempt whose solver failed before reporting them) |
//! | `residual` | largest relative residual ‖R_f‖/‖R_f⁰‖ over the fields at the last Newton iteration (dimensionless; `-` when unknown) |
//! | `cutbacks` | cut-backs of this step so far (`attempt − 1`) |
//! | `rejected` | rejected attempts of the whole run so far |
//! | `newton_total` | Newton iterations of the whole run so far, those of rejected attempts included |
//!
//! A `cutback` line ends with `# reason`. Numbers are written so they read back exactly. Between
//! steps, `#` lines say what the run is doing when it is not taking steps of its own (the steady
//! mode's recovery strategies: each strategy as it starts, each of its homotopy steps, its end).

use super::{
    NewtonIteration, RecordError, Recorder, RejectedStep, RunEnd, RunMeta, StepInfo, StepView,
};
use crate::io::output::fmt_num;
use std::io::Write as _;
use std::path::{Path, PathBuf};

/// Name of the status file in the output folder.
pub const FILE_NAME: &str = "run.sta";

/// The column names of a data line, in order.
pub const COLUMNS: [&str; 10] = [
    "step",
    "attempt",
    "status",
    "time",
    "dt",
    "newton",
    "residual",
    "cutbacks",
    "rejected",
    "newton_total",
];

pub struct StaSink {
    path: PathBuf,
    file: Option<std::fs::File>,
    error: Option<RecordError>,
    /// Newton iterations (None: none reported yet) and last residual seen for the attempt in
    /// progress.
    iterations: Option<usize>,
    residual: f64,
    /// Cut-backs of the step in progress.
    cutbacks: usize,
    rejected: usize,
    newton_total: usize,
}

impl StaSink {
    /// Writes `run.sta` into `dir`.
    pub fn new(dir: &Path) -> Self {
        Self {
            path: dir.join(FILE_NAME),
            file: None,
            error: None,
            iterations: None,
            residual: f64::NAN,
            cutbacks: 0,
            rejected: 0,
            newton_total: 0,
        }
    }

    fn write(&mut self, text: &str) {
        if self.error.is_some() {
            return;
        }
        let Some(f) = self.file.as_mut() else { return };
        // One write per line: a killed run leaves whole lines only (bar a full disk).
        if let Err(e) = f.write_all(text.as_bytes()).and_then(|_| f.flush()) {
            self.error = Some(RecordError::new("sta", &self.path, e));
        }
    }

    fn line(
        &self,
        step: u64,
        status: &str,
        time: f64,
        dt: f64,
        newton: Option<usize>,
        residual: f64,
    ) -> String {
        format!(
            "{:>6} {:>7} {:<8} {:>24} {:>24} {:>6} {:>24} {:>8} {:>8} {:>12}",
            step,
            self.cutbacks + 1,
            status,
            fmt_num(time),
            fmt_num(dt),
            // Unknown figures are `-`, never NaN.
            newton.map_or_else(|| "-".to_string(), |n| n.to_string()),
            if residual.is_finite() {
                fmt_num(residual)
            } else {
                "-".to_string()
            },
            self.cutbacks,
            self.rejected,
            self.newton_total
        )
    }
}

impl Recorder for StaSink {
    fn run_started(&mut self, meta: &RunMeta) {
        match std::fs::File::create(&self.path) {
            Ok(f) => self.file = Some(f),
            Err(e) => {
                self.error = Some(RecordError::new("sta", &self.path, e));
                return;
            }
        }
        let time = if meta.time_name == "load_factor" {
            "load factor (dimensionless)"
        } else {
            "simulated time (s)"
        };
        let head = format!(
            "# tread increment status: scene \"{}\", mode {}, tread {}\n\
             # time = {time}; dt = its increment; newton = Newton iterations of the attempt;\n\
             # residual = largest relative residual over the fields at the last iteration;\n\
             # cutbacks = cut-backs of this step so far; rejected, newton_total = run totals\n\
             # {:>4} {:>7} {:<8} {:>24} {:>24} {:>6} {:>24} {:>8} {:>8} {:>12}\n",
            meta.scene_name,
            meta.mode,
            meta.version,
            COLUMNS[0],
            COLUMNS[1],
            COLUMNS[2],
            COLUMNS[3],
            COLUMNS[4],
            COLUMNS[5],
            COLUMNS[6],
            COLUMNS[7],
            COLUMNS[8],
            COLUMNS[9],
        );
        self.write(&head);
    }

    fn note(&mut self, text: &str) {
        self.write(&format!("# {}\n", text.replace('\n', " ")));
    }

    fn newton_iteration(&mut self, it: &NewtonIteration) {
        self.iterations = Some(self.iterations.unwrap_or(0).max(it.iteration));
        self.residual = it.residual_rel.iter().copied().fold(f64::NAN, f64::max);
    }

    fn step_rejected(&mut self, s: &RejectedStep) {
        // The attempt's own figures where the solver reports them, else those of its Newton
        // iterations seen so far.
        if s.newton_iterations.is_some() {
            self.iterations = s.newton_iterations;
        }
        if let Some(r) = s.residual {
            self.residual = r;
        }
        self.rejected += 1;
        self.newton_total += self.iterations.unwrap_or(0);
        let reason = s.reason.replace('\n', " ");
        let text = format!(
            "{}  # {reason}\n",
            self.line(
                s.index,
                "cutback",
                s.time,
                s.dt,
                self.iterations,
                self.residual
            )
        );
        self.write(&text);
        self.cutbacks += 1;
        self.iterations = None;
        self.residual = f64::NAN;
    }

    fn step(&mut self, info: &StepInfo, _view: Option<&StepView>) {
        let newton = if info.newton_iterations > 0 {
            info.newton_iterations
        } else {
            self.iterations.unwrap_or(0)
        };
        let residual = if info.residual > 0.0 || self.residual.is_nan() {
            info.residual
        } else {
            self.residual
        };
        self.newton_total += newton;
        let text = format!(
            "{}\n",
            self.line(
                info.index,
                "accepted",
                info.time,
                info.dt,
                Some(newton),
                residual
            )
        );
        self.write(&text);
        self.cutbacks = 0;
        self.iterations = None;
        self.residual = f64::NAN;
    }

    fn run_finished(&mut self, end: &RunEnd) -> Vec<RecordError> {
        let status = if end.interrupted {
            "interrupted".to_string()
        } else if let Some(e) = end.error {
            format!("failed: {}", e.replace('\n', " "))
        } else if end.converged {
            "completed".to_string()
        } else {
            "ended without convergence".to_string()
        };
        let text = format!(
            "# {status}: {} accepted steps, {} rejected attempts, {} Newton iterations, wall time {:.3} s\n",
            end.steps, self.rejected, self.newton_total, end.wall_time_s
        );
        self.write(&text);
        self.file = None;
        self.error.take().into_iter().collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rejected(newton_iterations: Option<usize>, residual: Option<f64>) -> RejectedStep<'static> {
        RejectedStep {
            index: 0,
            time: 0.5,
            dt: 0.5,
            reason: "test",
            newton_iterations,
            residual,
        }
    }

    #[test]
    fn unknown_figures_are_dashes_and_known_ones_are_counted() {
        let dir = std::env::temp_dir().join(format!("tread-sta-unit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut sink = StaSink::new(&dir);
        sink.run_started(&RunMeta {
            scene_name: "unit",
            mode: "static",
            scene_toml: "",
            version: "0",
            features: "",
            mesh: None,
            time_name: "load_factor",
            time_end: 1.0,
            revolution_period: None,
        });
        // A solver failure that reports nothing, then one that reports its figures, then the
        // accepted attempt.
        sink.step_rejected(&rejected(None, None));
        sink.step_rejected(&rejected(Some(7), Some(2.5e-3)));
        sink.step(
            &StepInfo {
                index: 0,
                time: 0.25,
                dt: 0.25,
                newton_iterations: 3,
                residual: 1e-11,
                is_final: true,
            },
            None,
        );
        let errors = sink.run_finished(&RunEnd {
            converged: true,
            interrupted: false,
            error: None,
            steps: 1,
            wall_time_s: 0.0,
            summary: None,
        });
        assert!(errors.is_empty());
        let text = std::fs::read_to_string(dir.join(FILE_NAME)).unwrap();
        std::fs::remove_dir_all(&dir).ok();
        let rows: Vec<Vec<&str>> = text
            .lines()
            .filter(|l| !l.starts_with('#'))
            .map(|l| l.split('#').next().unwrap().split_whitespace().collect())
            .collect();
        assert_eq!(rows.len(), 3, "{text}");
        assert!(!text.contains("NaN") && !text.contains("inf"), "{text}");
        // step attempt status time dt newton residual cutbacks rejected newton_total
        assert_eq!(
            rows[0][1..],
            ["1", "cutback", "0.5", "0.5", "-", "-", "0", "1", "0"]
        );
        assert_eq!(
            rows[1][1..],
            ["2", "cutback", "0.5", "0.5", "7", "0.0025", "1", "2", "7"]
        );
        assert_eq!(
            rows[2][1..],
            ["3", "accepted", "0.25", "0.25", "3", "1e-11", "2", "2", "10"]
        );
    }
}
