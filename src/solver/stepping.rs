//! Load stepping with cut-back: drive a load factor λ from 0 to 1, solving each increment with
//! Newton from the previous converged state. A failed increment (no convergence, line-search
//! failure, singular or non-finite linear solve) restores the last converged state and halves
//! the increment; easy increments (≤ 4 iterations) grow it by 1.5×. A Cholesky factorization
//! that finds the tangent indefinite switches the solver to LU once (the spin-softening term
//! can make K − ω² M indefinite) without counting as a cut-back.

use super::linear::{LinearError, LinearKind};
use super::newton::{IterationRecord, Newton, NewtonTiming, NonlinearSystem, SolveError};
use super::observe::{RejectedStep, StepInfo, StepObserver};

/// A system with a scalar load factor.
pub trait LoadedSystem: NonlinearSystem {
    fn set_load(&mut self, lambda: f64);
    /// Called after a converged step (commit history such as the friction reference state).
    fn commit(&mut self) {}
}

#[derive(Clone, Debug)]
pub struct StepOptions {
    pub initial_steps: usize,
    pub max_cutbacks: usize,
    pub verbose: bool,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct StepRecord {
    pub lambda: f64,
    pub iterations: usize,
    pub converged: bool,
    pub table: Vec<IterationRecord>,
    /// Where the step's Newton solve spent its time (zero for a failed attempt; not written to
    /// the outputs, which stay reproducible).
    #[serde(skip)]
    pub timing: NewtonTiming,
}

#[derive(Clone, Debug, Default)]
pub struct StepReport {
    pub steps: Vec<StepRecord>,
    pub total_iterations: usize,
    pub cutbacks: usize,
    pub switched_to_lu: bool,
}

/// Largest relative residual (over fields) of the last row of a Newton table.
pub fn final_residual(table: &[IterationRecord]) -> f64 {
    table
        .last()
        .map_or(0.0, |r| r.residual_rel.iter().copied().fold(0.0, f64::max))
}

/// Drive λ from 0 to 1 (see the module docs); events go to the observer `rec`.
pub fn solve_load_steps<S: LoadedSystem, O: StepObserver<S> + ?Sized>(
    sys: &mut S,
    newton: &mut Newton,
    opts: &StepOptions,
    report: &mut StepReport,
    rec: &mut O,
) -> Result<(), SolveError> {
    let mut lambda = 0.0;
    let mut dl = 1.0 / opts.initial_steps.max(1) as f64;
    let mut saved = Vec::new();
    let mut index: u64 = 0;
    while lambda < 1.0 {
        if rec.stop_requested() {
            return Err(SolveError::Interrupted { at: lambda });
        }
        let target = (lambda + dl).min(1.0);
        if target < 1.0 && super::newton::below_round_off(lambda, 1.0, target - lambda) {
            return Err(SolveError::StepBelowRoundOff {
                at: lambda,
                step: target - lambda,
            });
        }
        sys.save_state(&mut saved);
        sys.set_load(target);
        if opts.verbose {
            eprintln!("  load step λ = {target:.6}");
        }
        match newton.solve(sys) {
            Ok(rep) => {
                rec.observe_newton(index, target, &rep.table, sys.field_names());
                let info = StepInfo {
                    index,
                    time: target,
                    dt: target - lambda,
                    newton_iterations: rep.iterations,
                    residual: final_residual(&rep.table),
                    is_final: target >= 1.0,
                };
                report.total_iterations += rep.iterations;
                report.steps.push(StepRecord {
                    lambda: target,
                    iterations: rep.iterations,
                    converged: true,
                    table: rep.table,
                    timing: rep.timing,
                });
                lambda = target;
                sys.commit();
                let recording = std::time::Instant::now();
                rec.observe_accepted(sys, &info);
                if opts.verbose {
                    eprintln!(
                        "  step recorded in {:.3} s",
                        recording.elapsed().as_secs_f64()
                    );
                }
                index += 1;
                if rep.iterations <= 4 {
                    dl *= 1.5;
                }
            }
            Err(SolveError::Linear(LinearError::NotPositiveDefinite))
                if newton.linear_kind() == LinearKind::Cholesky =>
            {
                if opts.verbose {
                    eprintln!("  tangent not positive definite: switching to sparse LU");
                }
                sys.restore_state(&saved);
                newton.switch_kind(sys, LinearKind::Lu)?;
                report.switched_to_lu = true;
            }
            Err(e) => {
                let reason = e.to_string();
                rec.observe_rejected(&RejectedStep {
                    index,
                    time: target,
                    dt: target - lambda,
                    reason: &reason,
                    newton_iterations: e.newton_iterations(),
                    // The error's residual is relative to the physical reference, not to the
                    // first residual.
                    residual: None,
                });
                report.cutbacks += 1;
                report.steps.push(StepRecord {
                    lambda: target,
                    iterations: 0,
                    converged: false,
                    table: Vec::new(),
                    timing: NewtonTiming::default(),
                });
                sys.restore_state(&saved);
                sys.set_load(lambda);
                if report.cutbacks > opts.max_cutbacks {
                    return Err(SolveError::TooManyCutbacks {
                        lambda,
                        cutbacks: report.cutbacks,
                        last: Box::new(e),
                    });
                }
                if opts.verbose {
                    eprintln!("  step to λ = {target:.6} failed ({e}); cutting back");
                }
                dl *= 0.5;
            }
        }
    }
    Ok(())
}
