//! The run envelope that every analysis mode shares (static, spinning, steady, transient,
//! stick-slip): what a run does around its solve.
//!
//! 1. [`RunEnvelope::open`]: create the output folder, build the recorders of the scene's
//!    `[output] sinks`, print every warning (`tread: warning: …` on stderr) and start the
//!    recorders with the run's metadata (scene, mode, resolved scene TOML, version, mesh, what
//!    the step "time" means and where it ends).
//! 2. The mode's solve, which reports its steps to [`RunEnvelope::recorders`].
//! 3. [`RunEnvelope::finish`]: finish the recorders with the run's end (converged, interrupted,
//!    error, steps, wall time, the summary) and write `summary.json` from the typed
//!    [`Summary`]. A failed or interrupted run writes it too, with what it reached. Outputs a
//!    recorder could not complete (disk full, …) are listed in its `incomplete_outputs` (sink,
//!    path, error); the key is absent when every output is complete.
//! 4. The mode writes its tables, then [`conclude`] turns the solve's result into the run's:
//!    `Ok(RunOutcome)`, [`AppError::Interrupted`] (exit status 130) or [`AppError::Solve`]
//!    (exit status 1), both naming the output folder that holds the partial results.

use crate::driver::results::RunOutcome;
use crate::io::output::{ensure_dir, write_json};
use crate::io::record::{self, Recorder, Recorders, RunEnd, RunMeta};
use crate::io::scene::Scene;
use crate::mesh::Mesh;
use crate::setup::{build_recorders, AppError, RunOptions};
use crate::solver::SolveError;
use std::path::PathBuf;

use super::results::Summary;

/// How the recorders count progress: the meaning of a step's "time" and where the run ends.
#[derive(Clone, Copy, Debug)]
pub struct RunClock<'a> {
    /// The reference mesh (None for models without one, e.g. stick-slip).
    pub mesh: Option<&'a Mesh>,
    /// `"load_factor"` (load stepping) or `"time"` (seconds).
    pub time_name: &'a str,
    /// Value of that time at which the run ends.
    pub time_end: f64,
}

/// The output folder and the recorders of one run (see the module docs).
pub struct RunEnvelope {
    pub out_dir: PathBuf,
    pub recorders: Recorders,
    /// Every warning printed at the start (the mode's, then the recorders').
    pub warnings: Vec<String>,
}

impl RunEnvelope {
    /// Create the output folder and start the recorders; `warnings` (the mode's own) are
    /// printed with those of the recorders.
    pub fn open(
        scene: &Scene,
        opts: &RunOptions,
        clock: RunClock,
        mut warnings: Vec<String>,
    ) -> Result<Self, AppError> {
        ensure_dir(&opts.out_dir)?;
        let (mut recorders, w) = build_recorders(scene, &opts.out_dir, opts.quiet);
        warnings.extend(w);
        for w in &warnings {
            eprintln!("tread: warning: {w}");
        }
        let scene_toml = scene.to_toml_string();
        let mode = scene.analysis.mode.to_string();
        let omega = scene.motion.omega;
        recorders.run_started(&RunMeta {
            scene_name: &scene.scene.name,
            mode: &mode,
            scene_toml: &scene_toml,
            version: env!("CARGO_PKG_VERSION"),
            features: record::build_features(),
            mesh: clock.mesh,
            time_name: clock.time_name,
            time_end: clock.time_end,
            // Only a body with a mesh spins (not the stick-slip oscillator).
            revolution_period: (omega > 0.0 && clock.mesh.is_some())
                .then(|| 2.0 * std::f64::consts::PI / omega),
        });
        Ok(Self {
            out_dir: opts.out_dir.clone(),
            recorders,
            warnings,
        })
    }

    /// Finish the recorders (their errors are warnings: logging never fails a run) and write
    /// `summary.json`. Returns the summary as written.
    pub fn finish(
        &mut self,
        typed: &Summary,
        steps: u64,
        wall_time_s: f64,
        error: Option<&str>,
        interrupted: bool,
    ) -> Result<serde_json::Value, AppError> {
        let mut summary = typed.to_json();
        let errors = self.recorders.run_finished(&RunEnd {
            converged: typed.converged,
            interrupted,
            error,
            steps,
            wall_time_s,
            summary: Some(&summary),
        });
        for e in &errors {
            eprintln!("tread: warning: {e}");
        }
        // Outputs a sink could not finish (a full disk, a removed folder): named, so that a
        // converged run's summary never vouches for a file that is missing or cut short.
        if !errors.is_empty() {
            if let Some(m) = summary.as_object_mut() {
                let list: Vec<serde_json::Value> = errors
                    .iter()
                    .map(|e| {
                        serde_json::json!({
                            "sink": e.sink,
                            "path": e.path.display().to_string(),
                            "error": e.message,
                        })
                    })
                    .collect();
                m.insert("incomplete_outputs".into(), serde_json::Value::Array(list));
            }
        }
        write_json(&self.out_dir.join("summary.json"), &summary)?;
        Ok(summary)
    }
}

/// The run's result from its solve's: the outcome, or the interruption or failure with the
/// output folder that holds the partial results.
pub fn conclude(
    solve: Result<(), SolveError>,
    outcome: RunOutcome,
) -> Result<RunOutcome, AppError> {
    match solve {
        Ok(()) => Ok(outcome),
        Err(SolveError::Interrupted { .. }) => Err(AppError::Interrupted(outcome.out_dir)),
        Err(e) => Err(AppError::Solve(e, outcome.out_dir)),
    }
}
