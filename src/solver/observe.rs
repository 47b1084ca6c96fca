//! What the solvers report while they work, and to whom: the [`StepObserver`] trait.
//!
//! The solvers know nothing of files or sinks. Load stepping ([`super::stepping`]) tells its
//! observer about every converged step (with its Newton table), every rejected step, and asks
//! it whether the run should stop; the run's recorder implements the trait (next to the system
//! it records, which alone knows how to build a view of its state), so the events reach every
//! output sink without `solver/` depending on them.
//!
//! Conventions: `time` is the load factor λ ∈ (0, 1] in load stepping and the simulated time
//! in seconds in time stepping; `dt` is its increment from the previous accepted step; residuals
//! are relative (‖R_f‖ / ‖R_f⁰‖ per field, the largest over fields), so dimensionless.

use super::newton::IterationRecord;

/// An accepted step (cheap: sent for every step).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepInfo {
    /// 0, 1, 2, … over accepted steps.
    pub index: u64,
    /// Simulated time, or the load factor λ in load stepping.
    pub time: f64,
    /// Increment of `time` from the previous accepted step.
    pub dt: f64,
    pub newton_iterations: usize,
    /// Largest relative residual (over fields) at the last Newton iteration.
    pub residual: f64,
    /// The last step of the run (λ = 1, t = t_end).
    pub is_final: bool,
}

/// A step that failed and will be retried with a smaller increment (or gives up).
#[derive(Clone, Copy, Debug)]
pub struct RejectedStep<'a> {
    /// Index the step would have had.
    pub index: u64,
    /// Target time (or load factor) of the failed attempt.
    pub time: f64,
    pub dt: f64,
    pub reason: &'a str,
    /// Newton iterations of the attempt, when known.
    pub newton_iterations: Option<usize>,
    /// Largest relative residual over the fields at the attempt's last Newton iteration, when
    /// known.
    pub residual: Option<f64>,
}

/// Receives the events of a solve of a system `S`. Every method has a default that ignores
/// the event (and never asks to stop).
pub trait StepObserver<S: ?Sized> {
    /// Whether the run has been asked to stop; checked before every step.
    fn stop_requested(&self) -> bool {
        false
    }
    /// The Newton table of the converged step `step` at `time`; `fields` names the columns of
    /// [`IterationRecord::residual_rel`].
    fn observe_newton(
        &mut self,
        _step: u64,
        _time: f64,
        _table: &[IterationRecord],
        _fields: &'static [&'static str],
    ) {
    }
    /// An accepted step, after the system committed it: `sys` is the converged state.
    fn observe_accepted(&mut self, _sys: &S, _info: &StepInfo) {}
    /// A failed attempt (the system is restored to the last converged state after this).
    fn observe_rejected(&mut self, _step: &RejectedStep) {}
}

/// An observer that ignores every event and never asks to stop (for any system).
#[derive(Clone, Copy, Debug, Default)]
pub struct NoObserver;

impl<S: ?Sized> StepObserver<S> for NoObserver {}
