//! `[solver]`: Newton with load stepping and cut-backs, the linear solver and threads.

use super::issue::{issue, Issue};
use serde::{Deserialize, Serialize};

keyword_enum! {
    /// Sparse linear solver (`[solver] linear`).
    #[derive(Default)]
    LinearChoice, "linear solver" {
        #[default]
        /// Cholesky when the tangent is symmetric positive definite, LU otherwise.
        Auto => "auto",
        /// Sparse Cholesky (symmetric positive definite tangents only).
        Cholesky => "cholesky",
        /// Sparse LU.
        Lu => "lu",
    }
}

keyword_enum! {
    /// Newton matrix of the steady mode's strain-rate damping (`[solver] damping_tangent`).
    #[derive(Default)]
    DampingTangentChoice, "damping tangent" {
        #[default]
        /// Matrix-free for a single steady solve (falling back to assembled if its GMRES
        /// iteration stalls), assembled for continuation.
        Auto => "auto",
        /// The cells' own sparsity in the matrix, the coupling beyond the cells applied
        /// matrix-free (GMRES): the memory and fill of the undamped problem.
        MatrixFree => "matrix_free",
        /// The whole coupling assembled (wider sparsity, more LU fill): a direct solve.
        Assembled => "assembled",
        /// The coupling of three-point ring differences assembled (one node passage beyond
        /// the cells), the rest matrix-free (GMRES); ring meshes only (others: matrix-free).
        Banded => "banded",
    }
}

keyword_enum! {
    /// Discretisation of the steady viscoelastic history along the streamlines
    /// (`[solver] steady_history`).
    #[derive(Default)]
    SteadyHistoryChoice, "steady history scheme" {
        #[default]
        /// Exact rings on the generated annulus, upwind on any other mesh.
        Auto => "auto",
        /// The internal variables integrated exactly along closed rings of quadrature points
        /// (the generated annulus only).
        Rings => "rings",
        /// Upwind discontinuous Galerkin on the quadrature points: any mesh (Gmsh, refined).
        Upwind => "upwind",
    }
}

/// `[solver]`: Newton with load stepping (in ω² for `spinning`; in the road penetration or the
/// road load for `static`) and cutbacks. In `transient`: the Newton iterations of each implicit
/// time step, a failed step being retried with half the step (`load_steps` unused). Not used by
/// `stick_slip`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SolverSpec {
    /// Relative residual tolerance, in (0, 1).
    pub tolerance: f64,
    /// Newton iterations per load step (>= 1).
    pub max_iterations: usize,
    /// Initial number of load steps (>= 1).
    pub load_steps: usize,
    /// How many times a failed step may be halved.
    pub max_cutbacks: usize,
    pub linear: LinearChoice,
    /// Worker threads; 0 = all cores.
    pub threads: usize,
    /// Backtracking line search on the residual norm.
    pub line_search: bool,
    /// Newton matrix of the steady mode's strain-rate damping.
    pub damping_tangent: DampingTangentChoice,
    /// Matrix-free damping tangent: weight, in (0, 1], of the cells' own θ-derivative with
    /// which the assembled part (GMRES's preconditioner) linearises the velocities; the
    /// Newton step is the exact one whatever the weight.
    pub damping_cell_weight: f64,
    /// Steady mode with friction: a regularisation ε below 1e-2 v_ref is reached by pressing
    /// in at 1e-2 v_ref and walking ε down (false: press in at the scene's ε directly).
    pub eps_continuation: bool,
    /// Steady mode on a generated annulus: start Newton from the steady state of the mesh with
    /// half the cells in r and in θ (itself started the same way), interpolated (false: press
    /// in from the undeformed state).
    pub coarse_start: bool,
    /// Newton's linear solves on single-precision LU factors kept across iterations, refined
    /// by GMRES to the accuracy of a direct solve, in every mode with the sparse LU (false:
    /// double-precision factors throughout, and a direct solve each iteration where the
    /// tangent is assembled whole).
    pub single_precision: bool,
    /// Steady mode with a viscoelastic material: how the internal variables are integrated
    /// along the streamlines.
    pub steady_history: SteadyHistoryChoice,
}

impl Default for SolverSpec {
    fn default() -> Self {
        SolverSpec {
            tolerance: 1e-10,
            max_iterations: 25,
            load_steps: 4,
            max_cutbacks: 10,
            linear: LinearChoice::Auto,
            threads: 0,
            line_search: true,
            damping_tangent: DampingTangentChoice::Auto,
            damping_cell_weight: crate::model::DEFAULT_DAMPING_CELL_WEIGHT,
            eps_continuation: true,
            coarse_start: true,
            single_precision: true,
            steady_history: SteadyHistoryChoice::Auto,
        }
    }
}

/// Largest `solver.max_cutbacks`.
pub const MAX_CUTBACKS: usize = 200;

pub(super) fn validate_solver(s: &SolverSpec, out: &mut Vec<Issue>) {
    if !(s.tolerance.is_finite() && s.tolerance > 0.0 && s.tolerance < 1.0) {
        out.push(issue(
            "solver.tolerance",
            format!("relative tolerance must be in (0, 1), got {}", s.tolerance),
        ));
    }
    if s.max_iterations < 1 {
        out.push(issue("solver.max_iterations", "must be >= 1, got 0"));
    }
    if s.load_steps < 1 {
        out.push(issue("solver.load_steps", "must be >= 1, got 0"));
    }
    if s.max_cutbacks > MAX_CUTBACKS {
        out.push(issue(
            "solver.max_cutbacks",
            format!(
                "must be <= {MAX_CUTBACKS}, got {} (each cut-back halves the step; {MAX_CUTBACKS} \
                 halvings already take any step below the round-off of its parameter)",
                s.max_cutbacks
            ),
        ));
    }
    let w = s.damping_cell_weight;
    if !(w.is_finite() && w > 0.0 && w <= 1.0) {
        out.push(issue(
            "solver.damping_cell_weight",
            format!("must be in (0, 1], got {w}"),
        ));
    }
}
