//! Nonlinear and linear solvers: the [`NonlinearSystem`] trait, sparse direct solvers with the
//! symbolic analysis done once ([`linear`]), Newton with backtracking line search and a
//! per-iteration convergence table ([`newton`]), load stepping with cut-back ([`stepping`]) and
//! Riks–Crisfield arc-length continuation ([`continuation`]). The solvers report to an
//! observer of their own ([`observe::StepObserver`]); they depend on nothing above them.

pub mod continuation;
pub mod integrators;
pub mod krylov;
pub mod linear;
pub mod multifrontal;
pub mod newton;
pub mod observe;
pub mod stepping;
pub mod system;

pub use linear::{LinearError, LinearKind, SparseSolver};
pub use newton::{
    IterationRecord, Newton, NewtonOptions, NewtonReport, NonlinearSystem, SolveError,
};
pub use observe::{RejectedStep, StepInfo, StepObserver};
pub use stepping::{solve_load_steps, StepOptions, StepReport};

/// How a run solves its system, decided once from the scene when the run starts: the linear
/// solver, the Newton options and the load stepping. The drivers take it from the model they
/// are given instead of deriving it again at every solve.
#[derive(Clone, Debug)]
pub struct SolvePlan {
    pub kind: LinearKind,
    pub newton: NewtonOptions,
    pub steps: StepOptions,
}

impl SolvePlan {
    /// The plan with the progress lines of Newton and of the load stepping on or off.
    pub fn verbose(&self, verbose: bool) -> Self {
        let mut p = self.clone();
        p.newton.verbose = verbose;
        p.steps.verbose = verbose;
        p
    }
}
