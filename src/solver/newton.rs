//! Newton's method with backtracking line search on a [`NonlinearSystem`].
//!
//! Each iteration: evaluate R and K at the current state, factorize K (numeric only: the
//! symbolic analysis is done once in [`SparseSolver::new`]), solve K Δ = −R, then try the full
//! step; the residual *and* tangent are evaluated at the trial point so an accepted full step
//! costs no extra assembly. If the trial residual is not finite (e.g. J ≤ 0 somewhere) or does
//! not decrease enough (‖R(α)‖ > (1 − 10⁻⁴ α) ‖R(0)‖), the step is halved (residual-only
//! evaluations) down to `min_alpha`.
//!
//! Convergence: for every field f (displacement, pressure, road height, hub angle)
//!
//! ‖R_f‖ ≤ max(tol · ref_f, ρ_f),   ref_f = max(‖q_f‖, floor_f),   ρ_f = ε ‖(|K| m)_f‖,
//!
//! all evaluated at the *current* iterate:
//!
//! * q_i = Σ_e |r_e,i| ([`NonlinearSystem::force_scale`], the assembler's
//!   [`crate::assembly::Assembler::scale`]) is the force flux through equation i: the sum of
//!   the magnitudes of the element forces that meet there. It is the physical force scale of
//!   the state (stresses, inertia, contact tractions), large wherever forces are transmitted
//!   even where they balance. It is *not* the first residual of the solve: with a stiff
//!   contact penalty the first residual of a load step is the penalty force of the new
//!   penetration (c_n = 1e12: ~1e10 for a 90 lbf contact force), and a test relative to it
//!   accepted states several per cent off equilibrium. R is small against q only when the
//!   element forces cancel, so a converged state is in equilibrium whatever the residual was
//!   before.
//! * floor_f ([`NonlinearSystem::reference_norms`]) is a physical force scale of the problem
//!   (a hub load, a centrifugal load, the smaller of a penalty and a body force estimate)
//!   for states whose force flux vanishes (rest, fields such as the cell pressures whose
//!   equations have a single contribution).
//! * ρ_f is the residual's round-off floor: R is computed from values of magnitude m
//!   ([`NonlinearSystem::state_magnitudes`]: |X + u| per displacement, since gaps are
//!   computed from positions), so perturbing them by ε m moves R by up to ε |K| m. Below it
//!   the residual is noise and cannot decrease; a tolerance asking for less is met at that
//!   floor instead of failing (a penalty c_n = 1e12 on the paper's cylinder: ρ ≈ 3e-6 ‖q‖). Observed floors sit
//!   at about 0.1 ρ.
//!
//! Or, when the correction is below the resolution of the state, ‖Δx‖ ≤ `increment_tol` · ‖m‖
//! (‖saved state‖ for a system without magnitudes): the step is applied and the solve stops.
//!
//! A solve that runs out of iterations returns [`SolveError::NotConverged`] with a
//! [`Stagnation`] record (reduction of the residual, its size in units of ρ, how many steps
//! the line search shortened, a condition estimate of K) whose message tells a residual
//! stuck at its round-off floor from a Newton step that does not predict the residual.
//!
//! The table printed (with `verbose`) shows ‖R_f‖ / max(ref_f, ρ_f / tol) (≤ tol: converged),
//! the increment norm and the line-search factor; the returned table
//! ([`IterationRecord`]) keeps ‖R_f‖, ‖R_f‖ / ‖R_f⁰‖, ref_f and ρ_f per iteration.

use super::linear::{LinearError, LinearKind, SparseSolver};
use std::time::Instant;

pub use super::system::NonlinearSystem;

#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    #[error("linear solver: {0}")]
    Linear(#[from] LinearError),
    /// `residual`: the largest ‖R_f‖ / ref_f over the fields (ref_f the physical reference,
    /// see the module docs); `stagnation`: what the iterations looked like (Newton's own
    /// failures).
    #[error("{}", not_converged_text(*.iterations, *.residual, .stagnation.as_ref()))]
    NotConverged {
        iterations: usize,
        residual: f64,
        stagnation: Option<Stagnation>,
    },
    /// The GMRES iteration on a tangent with a matrix-free part did not reach its tolerance.
    #[error("the Newton step's GMRES iteration stalled: relative residual {reached:.2e} after {products} products (asked {asked:.1e}); the assembled part of the tangent is a poor preconditioner here")]
    KrylovStalled {
        products: usize,
        reached: f64,
        asked: f64,
    },
    #[error("line search failed: no step length ≥ {min_alpha} reduced the residual (relative residual {residual:.3e})")]
    LineSearch { min_alpha: f64, residual: f64 },
    #[error("initial state is inadmissible (J ≤ 0 or non-finite residual)")]
    InadmissibleStart,
    /// An explicit (central-difference) step produced an inadmissible or non-finite state.
    #[error("the explicit central-difference step is unstable: the state blew up at t = {t:.6e} (Δt = {dt:.3e}, stable-step estimate {dt_stable:.3e}); reduce time.dt")]
    ExplicitUnstable { t: f64, dt: f64, dt_stable: f64 },
    /// Ctrl-C at a step boundary; `at` is the last converged load factor (or time).
    #[error("interrupted")]
    Interrupted { at: f64 },
    /// A time integrator outside this crate (diffsol) failed at time `t`.
    #[error("time integrator failed at t = {t:.6e}: {message}")]
    Integrator { t: f64, message: String },
    #[error("continuation stopped at parameter {lambda:.6e}: the corrector cycles between the same two points without progress (a non-smooth residual past a limit point)")]
    ContinuationCycles { lambda: f64 },
    /// The arc-length corrector converged, but on the backward intersection of the sphere with
    /// the branch: accepting it would reverse the direction of travel.
    #[error("the arc-length corrector converged backwards at parameter {lambda:.6e} (against the tangent)")]
    ContinuationReversed { lambda: f64 },
    #[error("continuation gave up at parameter {lambda:.6e} after {cutbacks} arc-length cut-backs: {last}")]
    ContinuationStalled {
        lambda: f64,
        cutbacks: usize,
        last: Box<SolveError>,
    },
    /// A cut-back made the step smaller than the round-off of the parameter it steps: a step
    /// that cannot change the parameter is a failure, not progress.
    #[error("the step fell to {step:.3e} at parameter {at:.6e}, below its round-off: no further progress is possible (raise the step floor, e.g. time.dt_min, or lower solver.max_cutbacks)")]
    StepBelowRoundOff { at: f64, step: f64 },
    #[error("load stepping gave up at load factor {lambda:.6} after {cutbacks} cut-backs: {last}")]
    TooManyCutbacks {
        lambda: f64,
        cutbacks: usize,
        last: Box<SolveError>,
    },
    /// The torque or free-rolling control found no road speed with the target hub torque.
    #[error("the rolling control found no road speed with the hub torque {target:.6e}: its trials (road speeds {v_min:.6e} to {v_max:.6e}) reached hub torques from {t_min:.6e} to {t_max:.6e}; a target beyond what friction transmits (about mu |F| Ro) cannot be reached. Last failure: {last}")]
    TorqueUnreachable {
        target: f64,
        v_min: f64,
        v_max: f64,
        t_min: f64,
        t_max: f64,
        last: Box<SolveError>,
    },
}

/// How a Newton solve that ran out of iterations behaved: the evidence that tells a residual
/// stuck at its round-off floor from a tangent that does not predict the residual.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stagnation {
    /// ‖R‖ / ‖R⁰‖ (all fields) at the last iterate.
    pub reduction: f64,
    /// Largest ‖R_f‖ / (ε ‖(|K| m)_f‖) over the fields: the residual in units of its
    /// round-off floor (NaN when the system gives no state magnitudes).
    pub over_round_off: f64,
    /// Iterations whose Newton step the line search shortened (α < 1).
    pub damped: usize,
    /// ‖Δx‖ / ‖m‖ of the last step taken.
    pub last_increment: f64,
    /// Estimate of the condition number of the tangent at the last iterate (NaN if the
    /// estimate failed).
    pub condition: f64,
}

impl SolveError {
    /// Newton iterations of the failed solve, when the error carries them (Newton ran out of
    /// iterations).
    pub fn newton_iterations(&self) -> Option<usize> {
        match self {
            SolveError::NotConverged { iterations, .. } => Some(*iterations),
            SolveError::TooManyCutbacks { last, .. }
            | SolveError::ContinuationStalled { last, .. } => last.newton_iterations(),
            _ => None,
        }
    }
}

fn not_converged_text(iterations: usize, residual: f64, st: Option<&Stagnation>) -> String {
    let head = format!(
        "Newton did not converge in {iterations} iterations (relative residual {residual:.3e})"
    );
    let Some(st) = st else {
        return head;
    };
    let cond = if st.condition.is_finite() {
        format!("{:.1e}", st.condition)
    } else {
        "unavailable".to_string()
    };
    let facts = format!(
        "the residual is {:.1e} × its round-off floor and {:.3e} × its first value, {} of the {iterations} steps were shortened by the line search, the last step was ‖Δx‖/‖x‖ = {:.1e}, condition estimate {cond}",
        st.over_round_off, st.reduction, st.damped, st.last_increment
    );
    if st.over_round_off <= 10.0 {
        format!(
            "{head}: {facts}: the residual stagnated at its round-off floor (ill-conditioning); the tolerance asks for more than double precision allows with this conditioning"
        )
    } else if 2 * st.damped >= iterations && st.reduction > 1e-3 {
        format!(
            "{head}: {facts}: not a round-off floor but a Newton step that does not predict the residual (a strongly nonlinear or ill-conditioned problem); smaller load or time steps or a better-posed model are needed"
        )
    } else {
        format!("{head}: {facts}")
    }
}

#[derive(Clone, Debug)]
pub struct NewtonOptions {
    pub tol: f64,
    pub max_iterations: usize,
    pub line_search: bool,
    pub min_alpha: f64,
    /// Converged when ‖Δx‖ ≤ increment_tol · ‖m‖ (a correction below the resolution of the
    /// state, see the module docs).
    pub increment_tol: f64,
    /// Print the convergence table to stderr.
    pub verbose: bool,
    /// Largest relative residual asked of the GMRES step when the tangent has a matrix-free
    /// part ([`NonlinearSystem::has_tangent_correction`]; inexact Newton, see
    /// [`Newton::solve`]). Far from the solution the Newton step is shortened by the line
    /// search anyway, so a loose step is as good as an exact one there; near it the forcing
    /// term falls quadratically with the residual. 0.3 took 9–11 Newton iterations and 7–14
    /// GMRES products per iteration on the damped rolling cylinder at 16k and 66k DOFs, against
    /// 11–12 iterations and 13–22 products with 1e-2.
    pub krylov_eta_max: f64,
    /// When the tangent has a matrix-free part, keep the LU factors of the assembled part from
    /// one Newton iteration to the next as GMRES's preconditioner (a lagged preconditioner)
    /// while the last GMRES solve took at most [`REUSE_EXTRA_PRODUCTS`] products more than the
    /// one right after a factorization and the last step was a full one. The Newton step is
    /// still the step on the exact tangent to the forcing term's accuracy, so the convergence
    /// is unchanged; a factorization costs as much as 12 (16k DOFs) to 18 (66k DOFs) GMRES
    /// products. A stalled GMRES with lagged factors refactorizes and tries once more.
    pub reuse_factorization: bool,
    /// When the tangent has a matrix-free part, factorize the assembled part, which only
    /// preconditions GMRES there, in single precision (factorization, factors and
    /// substitutions): half the factors' memory, about half the factorization time and half
    /// the memory traffic of each preconditioner solve, while GMRES forms its residuals in
    /// double precision, so the Newton step and the converged state are those of
    /// double-precision factors to the forcing term's accuracy. A pivot lost to
    /// single-precision round-off makes the linear solver factorize again in double
    /// precision; fresh single-precision factors that precondition poorly make the step be
    /// retried with double-precision factors, kept for the rest of the solve. On the damped
    /// default scene at 66k and 262k DOFs the GMRES products were the same in number, and
    /// the converged loads the same to all printed digits, as with double precision.
    pub single_precision_preconditioner: bool,
    /// Take the Newton steps of a tangent without a matrix-free part by GMRES too: on the
    /// assembled tangent, preconditioned by its LU factors in single precision, kept across
    /// iterations while they precondition well, each step refined to the accuracy of a direct
    /// solve ([`MIXED_ETA`]; in effect iterative refinement of a single-precision direct
    /// solve). Only with a linear solver that factorizes in single precision (the
    /// symmetric-pattern LU); otherwise, and when off, each iteration factorizes in double
    /// precision and solves directly. The scenes' default (`[solver] single_precision`): the
    /// same Newton iterations and states as double precision (the regression summaries agree
    /// to 1e-9), half the factor memory (undamped default scene at 262k DOFs in steady mode:
    /// 615 MB instead of 767 MB peak).
    pub mixed_precision: bool,
}

/// Relative linear residual asked of each Newton step with [`NewtonOptions::mixed_precision`]
/// on a tangent without a matrix-free part: the accuracy of a direct solve, so that the Newton
/// iteration is that of double precision. Looser steps (the Eisenstat–Walker forcing terms of
/// the matrix-free path) were faster on the rolling cylinder but stalled the static
/// indentation at c_n = 1e12 and κ/G = 1e6, which double precision solves, and took more
/// iterations at κ/G = 1e6 in steady mode.
pub const MIXED_ETA: f64 = 1e-10;

/// GMRES products after which such a step gives up its factors for fresher ones (lagged →
/// fresh single precision → double precision).
pub const MIXED_PRODUCTS: usize = 20;

/// Extra GMRES products (over the count right after a factorization) that a lagged
/// preconditioner may cost before the next iteration refactorizes
/// ([`NewtonOptions::reuse_factorization`]).
pub const REUSE_EXTRA_PRODUCTS: usize = 6;

impl Default for NewtonOptions {
    fn default() -> Self {
        Self {
            tol: 1e-10,
            max_iterations: 25,
            line_search: true,
            min_alpha: 1.0 / 64.0,
            increment_tol: 1e-14,
            verbose: false,
            krylov_eta_max: 0.3,
            reuse_factorization: true,
            single_precision_preconditioner: true,
            mixed_precision: false,
        }
    }
}

/// One row of the convergence table.
#[derive(Clone, Debug, serde::Serialize)]
pub struct IterationRecord {
    pub iteration: usize,
    /// ‖R_f‖ / ‖R_f⁰‖ per field (first iteration of this solve).
    pub residual_rel: Vec<f64>,
    /// ‖R_f‖ per field.
    pub residual_abs: Vec<f64>,
    /// The convergence reference ref_f = max(‖q_f‖, floor_f) per field at this iterate.
    pub reference: Vec<f64>,
    /// The residual's round-off floor ε ‖(|K| m)_f‖ per field at this iterate (converged when
    /// ‖R_f‖ ≤ max(tol · ref_f, round_off_f) for every f).
    pub round_off: Vec<f64>,
    /// ‖Δx‖ of the step taken after this residual (0 for the last row).
    pub increment_norm: f64,
    pub alpha: f64,
}

#[derive(Clone, Debug, Default)]
pub struct NewtonReport {
    pub iterations: usize,
    pub table: Vec<IterationRecord>,
    pub assemblies: usize,
    pub factorizations: usize,
    /// GMRES products with the exact tangent (systems with a
    /// [`NonlinearSystem::tangent_correction`]; 0 otherwise).
    pub krylov_iterations: usize,
    /// Where the solve's wall time went.
    pub timing: NewtonTiming,
}

/// Wall time of one Newton solve by phase, in seconds (what `-v` prints when it converges).
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct NewtonTiming {
    /// Residual and tangent evaluations (assembly), line-search trials included.
    pub evaluate_s: f64,
    /// Numeric factorizations of the assembled tangent.
    pub factorize_s: f64,
    /// Linear solves: triangular solves with the factors, and the GMRES iterations of a
    /// tangent with a matrix-free part.
    pub linear_solve_s: f64,
    /// The whole solve.
    pub total_s: f64,
}

/// Newton solver owning the sparse factorization (symbolic analysis done once).
pub struct Newton {
    pub opts: NewtonOptions,
    solver: SparseSolver,
    dx: Vec<f64>,
    saved: Vec<f64>,
    /// State magnitudes m_j and the per-equation round-off estimate ε Σ_j |K_ij| m_j.
    mag: Vec<f64>,
    noise: Vec<f64>,
}

/// Run `f`, adding its wall time to `acc`.
fn timed<T>(acc: &mut f64, f: impl FnOnce() -> T) -> T {
    let t = Instant::now();
    let out = f();
    *acc += t.elapsed().as_secs_f64();
    out
}

impl Newton {
    pub fn new<S: NonlinearSystem>(
        sys: &S,
        kind: LinearKind,
        opts: NewtonOptions,
    ) -> Result<Self, SolveError> {
        let (cp, ri) = sys.pattern();
        let started = Instant::now();
        let solver = SparseSolver::new(sys.n_eq(), cp, ri, kind)?;
        if opts.verbose {
            eprintln!(
                "         symbolic analysis of {} equations: {:.3} s",
                sys.n_eq(),
                started.elapsed().as_secs_f64()
            );
        }
        Ok(Self::with_solver(sys, solver, opts))
    }

    /// With a solver already analysed for `sys`'s pattern (see [`SparseSolver::has_pattern`]),
    /// e.g. one made while other work ran.
    pub fn with_solver<S: NonlinearSystem>(
        sys: &S,
        mut solver: SparseSolver,
        opts: NewtonOptions,
    ) -> Self {
        // The determinant (an extra LBLᵀ pass for LU) is only needed by continuation.
        solver.set_track_determinant(false);
        Self {
            opts,
            solver,
            dx: vec![0.0; sys.n_eq()],
            saved: Vec::new(),
            mag: Vec::new(),
            noise: Vec::new(),
        }
    }

    pub fn linear_kind(&self) -> LinearKind {
        self.solver.kind()
    }
    pub fn linear_solver(&self) -> &SparseSolver {
        &self.solver
    }

    /// Switch the linear solver (e.g. Cholesky → LU when the tangent loses definiteness).
    pub fn switch_kind<S: NonlinearSystem>(
        &mut self,
        sys: &S,
        kind: LinearKind,
    ) -> Result<(), SolveError> {
        let (cp, ri) = sys.pattern();
        self.solver = SparseSolver::new(sys.n_eq(), cp, ri, kind)?;
        self.solver.set_track_determinant(false);
        Ok(())
    }

    fn field_norms<S: NonlinearSystem>(sys: &S) -> Vec<f64> {
        let mut n = vec![0.0; sys.field_names().len()];
        for (r, &f) in sys.residual().iter().zip(sys.fields()) {
            n[f as usize] += r * r;
        }
        n.iter_mut().for_each(|v| *v = v.sqrt());
        n
    }

    /// Round-off floor of the residual per field at the current evaluation (which must hold
    /// the tangent): ‖ε Σ_j |K_ij| m_j‖ over the equations of each field, with m the system's
    /// [`NonlinearSystem::state_magnitudes`] (zero when it gives none).
    fn round_off<S: NonlinearSystem>(&mut self, sys: &S) -> Vec<f64> {
        let mut out = vec![0.0; sys.field_names().len()];
        sys.state_magnitudes(&mut self.mag);
        let n = sys.n_eq();
        if self.mag.len() != n {
            return out;
        }
        let (cp, ri) = sys.pattern();
        let vals = sys.matrix_values();
        self.noise.clear();
        self.noise.resize(n, 0.0);
        for (j, m) in self.mag.iter().enumerate() {
            for p in cp[j]..cp[j + 1] {
                self.noise[ri[p]] += vals[p].abs() * m;
            }
        }
        for (v, &f) in self.noise.iter().zip(sys.fields()) {
            if let Some(o) = out.get_mut(f as usize) {
                *o += v * v;
            }
        }
        out.iter_mut().for_each(|v| *v = f64::EPSILON * v.sqrt());
        out
    }

    /// Solve from the system's current state. On error the state is left at the last iterate
    /// (the caller restores a saved state if it wants to retry).
    pub fn solve<S: NonlinearSystem>(&mut self, sys: &mut S) -> Result<NewtonReport, SolveError> {
        let mut rep = NewtonReport::default();
        let started = Instant::now();
        let floors = sys.reference_norms();
        let ok = timed(&mut rep.timing.evaluate_s, || sys.evaluate(true));
        if !ok {
            return Err(SolveError::InadmissibleStart);
        }
        rep.assemblies += 1;
        let mut norms = Self::field_norms(sys);
        if norms.iter().any(|v| !v.is_finite()) {
            return Err(SolveError::InadmissibleStart);
        }
        let mut refs = convergence_reference(sys, &floors);
        let mut noise = self.round_off(sys);
        let first_raw = norms.clone();
        let names = sys.field_names();
        if self.opts.verbose {
            let cols: Vec<String> = names
                .iter()
                .map(|n| format!("{:>12}", format!("|R_{n}|/ref")))
                .collect();
            eprintln!("    iter {} {:>12} {:>6}", cols.join(" "), "|dx|", "alpha");
        }
        let total_norm = |n: &[f64]| n.iter().map(|v| v * v).sum::<f64>().sqrt();
        let (mut damped, mut last_increment) = (0, f64::NAN);
        let (mut prev_norm, mut prev_eta): (Option<f64>, f64) = (None, 1.0);
        // Lagged preconditioner bookkeeping (tangents with a matrix-free part only).
        let (mut lu_ready, mut full_step) = (false, false);
        let (mut fresh_products, mut last_products) = (0usize, 0usize);
        // Single-precision factors for the GMRES preconditioner while they precondition well.
        let mut single_ok = self.opts.single_precision_preconditioner;
        for it in 0..=self.opts.max_iterations {
            let rel: Vec<f64> = norms
                .iter()
                .zip(&first_raw)
                .map(|(n, f)| if *f > 0.0 { n / f } else { 0.0 })
                .collect();
            // Effective reference: the physical one, or the round-off floor over tol when that
            // is larger (a tolerance below what the arithmetic can resolve).
            let eff: Vec<f64> = refs
                .iter()
                .zip(&noise)
                .map(|(r, n)| r.max(n / self.opts.tol))
                .collect();
            let worst = norms
                .iter()
                .zip(&eff)
                .map(|(n, r)| n / r)
                .fold(0.0, f64::max);
            let mut rec = IterationRecord {
                iteration: it,
                residual_rel: rel,
                residual_abs: norms.clone(),
                reference: refs.clone(),
                round_off: noise.clone(),
                increment_norm: 0.0,
                alpha: 0.0,
            };
            if worst <= self.opts.tol {
                self.print_row(&rec);
                rep.table.push(rec);
                rep.iterations = it;
                rep.timing.total_s = started.elapsed().as_secs_f64();
                self.print_timing(&rep, sys.n_eq());
                return Ok(rep);
            }
            if it == self.opts.max_iterations {
                self.print_row(&rec);
                rep.table.push(rec);
                let over_round_off = norms
                    .iter()
                    .zip(&noise)
                    .filter(|(_, o)| **o > 0.0)
                    .map(|(n, o)| n / o)
                    .fold(f64::NAN, f64::max);
                let stagnation = Stagnation {
                    reduction: total_norm(&norms) / total_norm(&first_raw).max(f64::MIN_POSITIVE),
                    over_round_off,
                    damped,
                    last_increment,
                    condition: self.condition_estimate(sys).unwrap_or(f64::NAN),
                };
                let relative = norms
                    .iter()
                    .zip(&refs)
                    .map(|(n, r)| n / r)
                    .fold(0.0, f64::max);
                return Err(SolveError::NotConverged {
                    iterations: it,
                    residual: relative,
                    stagnation: Some(stagnation),
                });
            }
            // Newton direction.
            // GMRES on (lagged, single-precision) LU factors: the tangent has a matrix-free
            // part, or mixed precision is asked for and the LU supports it.
            let correction = sys.has_tangent_correction()
                || (self.opts.mixed_precision && self.solver.supports_single_precision());
            let lagged = correction
                && self.opts.reuse_factorization
                && lu_ready
                && full_step
                && last_products <= fresh_products + REUSE_EXTRA_PRODUCTS;
            if !lagged {
                self.factorize(sys, correction && single_ok, &mut rep)?;
                lu_ready = true;
            }
            let (solve_started, factorized_before) = (Instant::now(), rep.timing.factorize_s);
            for (d, r) in self.dx.iter_mut().zip(sys.residual()) {
                *d = -r;
            }
            self.solver.solve_in_place(&mut self.dx)?;
            if correction {
                // The Newton step on K + C by GMRES from the assembled part's step, to a
                // relative residual η (inexact Newton, Eisenstat–Walker's second choice):
                // η_k = 0.9 (‖R_k‖/‖R_k−1‖)², safeguarded by 0.9 η_k−1² while that is large,
                // at most `krylov_eta_max`. The convergence stays superlinear (quadratic in the
                // limit) while the early, far-from-solution steps are cheap; no solve is made
                // finer than the step that reaches a tenth of the tolerance needs (the last
                // step's linear residual then stays ten times below the tolerance; with a
                // thousandth, the last GMRES solve of the damped default scene at 66k DOFs took
                // 52 products instead of 26 for the same converged state to 1e-9). Should the
                // total norm hide one field's residual (one stiff term dominating the
                // convergence reference), the residual test asks for one more iteration.
                let r_now = total_norm(&norms);
                // Mixed precision on a whole assembled tangent: the GMRES iteration only
                // refines the single-precision solve, to the accuracy of a direct one
                // (`MIXED_ETA`); a preconditioner that cannot reach it in `MIXED_PRODUCTS`
                // products is replaced (lagged → fresh → double precision).
                let refinement = !sys.has_tangent_correction();
                let (eta_max, max_products) = if refinement {
                    (MIXED_ETA, MIXED_PRODUCTS)
                } else {
                    (self.opts.krylov_eta_max, 160)
                };
                let mut eta = match prev_norm {
                    Some(rp) if rp > 0.0 => {
                        let e = 0.9 * (r_now / rp).powi(2);
                        let safe = 0.9 * prev_eta * prev_eta;
                        if safe > 0.1 {
                            e.max(safe)
                        } else {
                            e
                        }
                    }
                    _ => eta_max,
                };
                eta = eta
                    .min(eta_max)
                    .max(1e-1 * self.opts.tol / worst)
                    .clamp(1e-10, eta_max);
                prev_norm = Some(r_now);
                prev_eta = eta;
                let b: Vec<f64> = sys.residual().iter().map(|r| -r).collect();
                let poor = |ks: &super::krylov::KrylovStats| {
                    !ks.rel_residual.is_finite() || ks.rel_residual > (10.0 * eta).min(0.5)
                };
                // With lagged factors that no longer precondition: refactorize and retry once.
                let mut fresh = !lagged;
                let ks = loop {
                    let ks = super::krylov::gmres(
                        sys,
                        &mut self.solver,
                        &b,
                        &mut self.dx,
                        eta,
                        40,
                        max_products,
                        fresh,
                    )?;
                    rep.krylov_iterations += ks.iterations;
                    if fresh {
                        fresh_products = ks.iterations;
                    }
                    if !poor(&ks) || (fresh && !self.solver.single_precision_factors()) {
                        break ks;
                    }
                    // Lagged factors: fresh ones. Fresh single-precision ones: double
                    // precision, for the rest of this solve.
                    if fresh {
                        single_ok = false;
                    }
                    self.factorize(sys, single_ok, &mut rep)?;
                    self.dx.copy_from_slice(&b);
                    self.solver.solve_in_place(&mut self.dx)?;
                    fresh = true;
                };
                last_products = ks.iterations;
                // A step far less accurate than asked is still an inexact Newton step when it
                // leaves at most 1 % of the linear residual: Newton then converges linearly
                // (by about that factor per iteration) instead of superlinearly, and the
                // residual test decides convergence as always. (On the damped default scene at
                // 1M DOFs, GMRES stalled at 4.4e-4 where 3.7e-5 was asked.) A step that leaves
                // more, or does not even halve the residual of the linear system, is not a
                // Newton step: stop here rather than wander (the caller may switch to an
                // assembled tangent).
                let unusable =
                    !ks.rel_residual.is_finite() || ks.rel_residual > (10.0 * eta).clamp(1e-2, 0.5);
                if unusable {
                    sys.tangent_correction_stalled();
                    if self.opts.verbose {
                        eprintln!(
                            "         GMRES stalled: {} products, relative residual {:.2e} (asked {eta:.1e})",
                            ks.iterations, ks.rel_residual
                        );
                    }
                    return Err(SolveError::KrylovStalled {
                        products: ks.iterations,
                        reached: ks.rel_residual,
                        asked: eta,
                    });
                }
                if self.opts.verbose {
                    eprintln!(
                        "         GMRES: {} products, relative residual {:.2e} (asked {eta:.1e}){}{}",
                        ks.iterations,
                        ks.rel_residual,
                        if lagged && fresh_products != ks.iterations {
                            ", lagged LU"
                        } else {
                            ""
                        },
                        if poor(&ks) {
                            ", taken as an inexact step"
                        } else {
                            ""
                        }
                    );
                }
            }
            // Less the refactorizations GMRES asked for (factorization time).
            rep.timing.linear_solve_s += solve_started.elapsed().as_secs_f64()
                - (rep.timing.factorize_s - factorized_before);
            rec.increment_norm = self.dx.iter().map(|v| v * v).sum::<f64>().sqrt();
            let r0 = total_norm(&norms);
            sys.save_state(&mut self.saved);
            // Increment criterion: a step at the round-off level of the state means the residual
            // has reached its floor (it can no longer decrease): accept and stop.
            let xnorm = if self.mag.is_empty() {
                self.saved.iter().map(|v| v * v).sum::<f64>().sqrt()
            } else {
                self.mag.iter().map(|v| v * v).sum::<f64>().sqrt()
            };
            last_increment = rec.increment_norm / xnorm.max(f64::MIN_POSITIVE);
            if rec.increment_norm <= self.opts.increment_tol * xnorm.max(f64::MIN_POSITIVE) {
                sys.update(1.0, &self.dx);
                timed(&mut rep.timing.evaluate_s, || sys.evaluate(true));
                rep.assemblies += 1;
                rec.alpha = 1.0;
                self.print_row(&rec);
                rep.table.push(rec);
                rep.iterations = it + 1;
                rep.timing.total_s = started.elapsed().as_secs_f64();
                self.print_timing(&rep, sys.n_eq());
                return Ok(rep);
            }
            let mut alpha = 1.0;
            loop {
                sys.update(alpha, &self.dx);
                let ok = timed(&mut rep.timing.evaluate_s, || sys.evaluate(alpha == 1.0));
                rep.assemblies += 1;
                let trial = Self::field_norms(sys);
                let rt = total_norm(&trial);
                let acceptable = ok && rt.is_finite();
                if self.opts.verbose && alpha < 1.0 {
                    eprintln!("         line search: alpha = {alpha:.4}, admissible = {ok}, |R|/|R0| = {:.4e}", rt / r0);
                }
                if acceptable
                    && (!self.opts.line_search || rt <= (1.0 - 1e-4 * alpha) * r0 || r0 == 0.0)
                {
                    if alpha != 1.0 {
                        // Tangent at the accepted point for the next iteration.
                        timed(&mut rep.timing.evaluate_s, || sys.evaluate(true));
                        rep.assemblies += 1;
                        damped += 1;
                    }
                    full_step = alpha == 1.0;
                    norms = trial;
                    refs = convergence_reference(sys, &floors);
                    noise = self.round_off(sys);
                    break;
                }
                // Accept a full step that is admissible when the line search is off.
                sys.restore_state(&self.saved);
                alpha *= 0.5;
                if alpha < self.opts.min_alpha || (!self.opts.line_search && acceptable) {
                    // Leave the state at the last iterate with a valid evaluation.
                    sys.evaluate(true);
                    rep.assemblies += 1;
                    return Err(SolveError::LineSearch {
                        min_alpha: self.opts.min_alpha,
                        residual: rt / r0.max(f64::MIN_POSITIVE),
                    });
                }
            }
            rec.alpha = alpha;
            self.print_row(&rec);
            rep.table.push(rec);
        }
        unreachable_guard()
    }

    /// Estimate of the condition number |λ|max / |λ|min of the tangent at the current
    /// evaluation (10 power iterations with K, 10 inverse iterations with its factorization):
    /// an order of magnitude for the diagnostics of a failed solve. `None` if the tangent cannot
    /// be factorized.
    fn condition_estimate<S: NonlinearSystem>(&mut self, sys: &S) -> Option<f64> {
        self.solver.set_single_precision_factors(false);
        self.solver.factorize(sys.matrix_values()).ok()?;
        let (cp, ri) = sys.pattern();
        let vals = sys.matrix_values();
        let n = sys.n_eq();
        if n == 0 {
            return None;
        }
        let start = |x: &mut Vec<f64>| {
            x.clear();
            x.extend((0..n).map(|i| 1.0 + 0.5 * ((i as f64) * 0.618_033_988_749_895).fract()));
        };
        let normalise = |x: &mut [f64]| {
            let nx = x.iter().map(|v| v * v).sum::<f64>().sqrt();
            if nx > 0.0 && nx.is_finite() {
                x.iter_mut().for_each(|v| *v /= nx);
            }
            nx
        };
        let (mut x, mut y) = (Vec::with_capacity(n), vec![0.0; n]);
        start(&mut x);
        normalise(&mut x);
        let mut lmax = 0.0;
        for _ in 0..10 {
            y.fill(0.0);
            for j in 0..n {
                for p in cp[j]..cp[j + 1] {
                    y[ri[p]] += vals[p] * x[j];
                }
            }
            lmax = normalise(&mut y);
            std::mem::swap(&mut x, &mut y);
        }
        start(&mut x);
        normalise(&mut x);
        let mut inv = 0.0;
        for _ in 0..10 {
            self.solver.solve_in_place(&mut x).ok()?;
            inv = normalise(&mut x);
        }
        let c = lmax * inv;
        c.is_finite().then_some(c)
    }

    /// Factorize the assembled tangent (in single precision when `single`), counted and timed
    /// in `rep`.
    fn factorize<S: NonlinearSystem>(
        &mut self,
        sys: &S,
        single: bool,
        rep: &mut NewtonReport,
    ) -> Result<(), LinearError> {
        self.solver.set_single_precision_factors(single);
        let solver = &mut self.solver;
        timed(&mut rep.timing.factorize_s, || {
            solver.factorize(sys.matrix_values())
        })?;
        rep.factorizations += 1;
        Ok(())
    }

    /// With `verbose`: where a converged solve's time went.
    fn print_timing(&self, rep: &NewtonReport, n_eq: usize) {
        if !self.opts.verbose {
            return;
        }
        let t = &rep.timing;
        eprintln!(
            "         {n_eq} equations, {:.3} s: {} evaluations {:.3} s, {} factorizations {:.3} s, \
             linear solves {:.3} s{}",
            t.total_s,
            rep.assemblies,
            t.evaluate_s,
            rep.factorizations,
            t.factorize_s,
            t.linear_solve_s,
            if rep.krylov_iterations > 0 {
                format!(" ({} GMRES products)", rep.krylov_iterations)
            } else {
                String::new()
            }
        );
    }

    fn print_row(&self, rec: &IterationRecord) {
        if self.opts.verbose {
            let tol = self.opts.tol;
            let cols: Vec<String> = rec
                .residual_abs
                .iter()
                .zip(rec.reference.iter().zip(&rec.round_off))
                .map(|(n, (r, o))| format!("{:>12.3e}", n / r.max(o / tol)))
                .collect();
            eprintln!(
                "    {:>4} {} {:>12.3e} {:>6.3}",
                rec.iteration,
                cols.join(" "),
                rec.increment_norm,
                rec.alpha
            );
        }
    }
}

/// The convergence reference per field at the system's last evaluation:
/// ref_f = max(‖q_f‖, floor_f), with q the system's [`NonlinearSystem::force_scale`] and
/// floor_f its [`NonlinearSystem::reference_norms`] (`floors`).
pub fn convergence_reference<S: NonlinearSystem>(sys: &S, floors: &[f64]) -> Vec<f64> {
    let nf = sys.field_names().len();
    let mut q = vec![0.0; nf];
    for (v, &f) in sys.force_scale().iter().zip(sys.fields()) {
        if let Some(qf) = q.get_mut(f as usize) {
            *qf += v * v;
        }
    }
    q.iter()
        .enumerate()
        .map(|(f, v)| {
            v.sqrt()
                .max(floors.get(f).copied().unwrap_or(0.0))
                .max(f64::MIN_POSITIVE)
        })
        .collect()
}

#[inline]
fn unreachable_guard() -> Result<NewtonReport, SolveError> {
    // The loop above returns on its last iteration; this keeps the function total without a panic.
    Err(SolveError::NotConverged {
        iterations: 0,
        residual: f64::NAN,
        stagnation: None,
    })
}

/// Whether a step `step` from `at` (towards an end at `end`) is below the round-off of the
/// parameter: fewer than about four units in the last place of the larger of |at| and |end|, so
/// that `at + step` cannot be told from `at` after a few operations.
pub fn below_round_off(at: f64, end: f64, step: f64) -> bool {
    let scale = at.abs().max(end.abs());
    // Written so that a NaN step counts as below round-off too.
    step.abs().partial_cmp(&(4.0 * f64::EPSILON * scale)) != Some(std::cmp::Ordering::Greater)
        || at + step == at
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::linear::LuOrdering;

    /// R(x) = (K + C) x − b with K block diagonal of 2 × 2 blocks [[1, a], [a, a² + s]]
    /// (assembled; nearly singular, s = 1e-12: in single precision a² + s − a·a is zero, or
    /// off by about 1e-8, ten thousand times the block's small pivot) and C
    /// a weak dense coupling (matrix-free).
    struct NearlySingular {
        col_ptr: Vec<usize>,
        row_idx: Vec<usize>,
        k: Vec<f64>,
        c: Vec<Vec<f64>>,
        b: Vec<f64>,
        x: Vec<f64>,
        r: Vec<f64>,
        fields: Vec<u8>,
    }

    impl NearlySingular {
        fn new(blocks: usize) -> Self {
            let n = 2 * blocks;
            let (mut col_ptr, mut row_idx, mut k) = (vec![0], Vec::new(), Vec::new());
            for blk in 0..blocks {
                let a = 1.0 / 3.0 + 0.0137 * blk as f64;
                let block = [[1.0, a], [a, a * a + 1e-12]];
                for j in 0..2 {
                    for (i, row) in block.iter().enumerate() {
                        row_idx.push(2 * blk + i);
                        k.push(row[j]);
                    }
                    col_ptr.push(row_idx.len());
                }
            }
            let c: Vec<Vec<f64>> = (0..n)
                .map(|i| {
                    (0..n)
                        .map(|j| 1e-12 * ((i * 7 + j * 3) % 11) as f64 / n as f64)
                        .collect()
                })
                .collect();
            let mut s = Self {
                col_ptr,
                row_idx,
                k,
                c,
                b: vec![0.0; n],
                x: vec![0.0; n],
                r: vec![0.0; n],
                fields: vec![0; n],
            };
            // b = (K + C) x* for a moderate x*, so that the residual can reach round-off.
            let xs: Vec<f64> = (0..n).map(|i| (0.7 * i as f64).sin()).collect();
            s.b = s.product(&xs);
            s
        }

        fn product(&self, x: &[f64]) -> Vec<f64> {
            let mut y: Vec<f64> = self
                .c
                .iter()
                .map(|row| row.iter().zip(x).map(|(a, b)| a * b).sum())
                .collect();
            for (j, xj) in x.iter().enumerate() {
                for p in self.col_ptr[j]..self.col_ptr[j + 1] {
                    y[self.row_idx[p]] += self.k[p] * xj;
                }
            }
            y
        }
    }

    impl NonlinearSystem for NearlySingular {
        fn n_eq(&self) -> usize {
            self.x.len()
        }
        fn fields(&self) -> &[u8] {
            &self.fields
        }
        fn field_names(&self) -> &'static [&'static str] {
            &["u"]
        }
        fn reference_norms(&self) -> Vec<f64> {
            vec![self.b.iter().map(|v| v * v).sum::<f64>().sqrt()]
        }
        fn pattern(&self) -> (&[usize], &[usize]) {
            (&self.col_ptr, &self.row_idx)
        }
        fn evaluate(&mut self, _with_matrix: bool) -> bool {
            let y = self.product(&self.x);
            for ((r, y), b) in self.r.iter_mut().zip(y).zip(&self.b) {
                *r = y - b;
            }
            true
        }
        fn residual(&self) -> &[f64] {
            &self.r
        }
        fn matrix_values(&self) -> &[f64] {
            &self.k
        }
        fn update(&mut self, alpha: f64, dx: &[f64]) {
            self.x.iter_mut().zip(dx).for_each(|(x, d)| *x += alpha * d);
        }
        fn save_state(&self, buf: &mut Vec<f64>) {
            buf.clear();
            buf.extend_from_slice(&self.x);
        }
        fn restore_state(&mut self, buf: &[f64]) {
            self.x.copy_from_slice(buf);
        }
        fn has_tangent_correction(&self) -> bool {
            true
        }
        fn tangent_correction(&mut self, v: &[f64], out: &mut [f64]) {
            for (o, row) in out.iter_mut().zip(&self.c) {
                *o += row.iter().zip(v).map(|(a, b)| a * b).sum::<f64>();
            }
        }
    }

    /// Newton on the 150-equation [`NearlySingular`] system, with single-precision
    /// preconditioner factors first or not.
    fn solve_nearly_singular(single: bool) -> (NearlySingular, Newton, NewtonReport) {
        let mut sys = NearlySingular::new(150);
        let opts = NewtonOptions {
            single_precision_preconditioner: single,
            ..Default::default()
        };
        let mut newton = Newton::new(&sys, LinearKind::Lu, opts).unwrap();
        let rep = newton.solve(&mut sys).unwrap();
        (sys, newton, rep)
    }

    /// A single-precision factorization that loses the pivots of a nearly singular assembled
    /// part to round-off (a² + s − a·a is zero in single precision) is redone in double
    /// precision on the same multifrontal LU (not handed to the partial-pivoting LU), and
    /// Newton converges as with double-precision factors from the start.
    #[test]
    fn lost_single_precision_pivots_fall_back_to_double() {
        let solve = |single: bool| {
            let (sys, newton, rep) = solve_nearly_singular(single);
            let err = sys
                .x
                .iter()
                .enumerate()
                .map(|(i, x)| (x - (0.7 * i as f64).sin()).abs())
                .fold(0.0, f64::max);
            let ls = newton.linear_solver();
            (rep, err, ls.single_precision_factors(), ls.lu_ordering())
        };
        let (rep_d, err_d, single_d, ord_d) = solve(false);
        let (rep_s, err_s, single_s, ord_s) = solve(true);
        // (The errors against x* only show the conditioning: κ(K) ≈ 1e12.)
        println!(
            "double: {} iterations, {} products, error {err_d:e}; single first: {} iterations, \
             {} products, error {err_s:e}",
            rep_d.iterations, rep_d.krylov_iterations, rep_s.iterations, rep_s.krylov_iterations
        );
        assert!(
            !single_d && !single_s,
            "double-precision factors at the end"
        );
        assert_eq!(ord_d, Some(LuOrdering::Symmetric));
        assert_eq!(ord_s, Some(LuOrdering::Symmetric));
        assert_eq!(rep_s.iterations, rep_d.iterations);
        assert_eq!(rep_s.krylov_iterations, rep_d.krylov_iterations);
        assert!((err_s - err_d).abs() <= 1e-6 * err_d.max(1e-300));
    }

    /// R(x) = K x + 0.1 x³ − b on a nonsymmetric tridiagonal K (no matrix-free part): the
    /// cubic makes Newton take several steps.
    struct Cubic {
        col_ptr: Vec<usize>,
        row_idx: Vec<usize>,
        k: Vec<f64>,
        kt: Vec<f64>,
        b: Vec<f64>,
        x: Vec<f64>,
        r: Vec<f64>,
        fields: Vec<u8>,
    }

    impl Cubic {
        fn new(n: usize) -> Self {
            let (mut col_ptr, mut row_idx, mut k) = (vec![0], Vec::new(), Vec::new());
            for j in 0..n {
                for i in j.saturating_sub(1)..(j + 2).min(n) {
                    row_idx.push(i);
                    k.push(match i as i64 - j as i64 {
                        0 => 4.0 + 0.01 * j as f64,
                        -1 => -1.3,
                        _ => -0.7,
                    });
                }
                col_ptr.push(row_idx.len());
            }
            let b = (0..n).map(|i| 2.0 + (0.3 * i as f64).sin()).collect();
            Self {
                kt: k.clone(),
                col_ptr,
                row_idx,
                k,
                b,
                x: vec![0.0; n],
                r: vec![0.0; n],
                fields: vec![0; n],
            }
        }
    }

    impl NonlinearSystem for Cubic {
        fn n_eq(&self) -> usize {
            self.x.len()
        }
        fn fields(&self) -> &[u8] {
            &self.fields
        }
        fn field_names(&self) -> &'static [&'static str] {
            &["u"]
        }
        fn reference_norms(&self) -> Vec<f64> {
            vec![self.b.iter().map(|v| v * v).sum::<f64>().sqrt()]
        }
        fn pattern(&self) -> (&[usize], &[usize]) {
            (&self.col_ptr, &self.row_idx)
        }
        fn evaluate(&mut self, with_matrix: bool) -> bool {
            for (r, (x, b)) in self.r.iter_mut().zip(self.x.iter().zip(&self.b)) {
                *r = 0.1 * x * x * x - b;
            }
            for j in 0..self.x.len() {
                for p in self.col_ptr[j]..self.col_ptr[j + 1] {
                    let i = self.row_idx[p];
                    self.r[i] += self.k[p] * self.x[j];
                    if with_matrix {
                        self.kt[p] = self.k[p]
                            + if i == j {
                                0.3 * self.x[j] * self.x[j]
                            } else {
                                0.0
                            };
                    }
                }
            }
            true
        }
        fn residual(&self) -> &[f64] {
            &self.r
        }
        fn matrix_values(&self) -> &[f64] {
            &self.kt
        }
        fn update(&mut self, alpha: f64, dx: &[f64]) {
            self.x.iter_mut().zip(dx).for_each(|(x, d)| *x += alpha * d);
        }
        fn save_state(&self, buf: &mut Vec<f64>) {
            buf.clear();
            buf.extend_from_slice(&self.x);
        }
        fn restore_state(&mut self, buf: &[f64]) {
            self.x.copy_from_slice(buf);
        }
    }

    /// Mixed precision ([`NewtonOptions::mixed_precision`]) on a tangent without a matrix-free
    /// part: GMRES on lagged single-precision LU factors reaches the state of the direct
    /// double-precision solves (to the Newton tolerance) with fewer factorizations; a
    /// Cholesky solver, which has no single-precision factors, keeps the direct solves.
    #[test]
    fn mixed_precision_reaches_the_direct_solution_with_fewer_factorizations() {
        let solve = |kind: LinearKind, mixed: bool| {
            let mut sys = Cubic::new(400);
            let opts = NewtonOptions {
                mixed_precision: mixed,
                ..Default::default()
            };
            let mut newton = Newton::new(&sys, kind, opts).unwrap();
            let rep = newton.solve(&mut sys).unwrap();
            (sys.x, rep)
        };
        let (xd, rd) = solve(LinearKind::Lu, false);
        let (xm, rm) = solve(LinearKind::Lu, true);
        println!(
            "direct: {} iterations, {} factorizations; mixed: {} iterations, {} factorizations, {} products",
            rd.iterations, rd.factorizations, rm.iterations, rm.factorizations, rm.krylov_iterations
        );
        assert!(rd.iterations >= 3, "{} iterations", rd.iterations);
        assert_eq!(rd.krylov_iterations, 0);
        assert!(rm.krylov_iterations > 0);
        assert!(rm.factorizations < rd.factorizations);
        assert!(rm.iterations <= rd.iterations + 1);
        let scale = xd.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let diff = xd
            .iter()
            .zip(&xm)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(diff <= 1e-8 * scale, "max |x_direct - x_mixed| = {diff:e}");
        let (_, rc) = solve(LinearKind::Cholesky, true);
        assert_eq!(rc.krylov_iterations, 0, "Cholesky: direct solves");
    }

    /// The phases of the timing record are disjoint parts of the solve: they add up to at
    /// most its total, each one measured when it ran.
    #[test]
    fn timing_phases_are_parts_of_the_total() {
        // Single-precision factors first: GMRES then refactorizes within the linear solve
        // (the test above), which the record counts as factorization time.
        for single in [false, true] {
            let (_, _, rep) = solve_nearly_singular(single);
            let t = rep.timing;
            let parts = t.evaluate_s + t.factorize_s + t.linear_solve_s;
            assert!(rep.assemblies > 0 && rep.factorizations > 0, "{rep:?}");
            assert!(
                t.evaluate_s > 0.0 && t.factorize_s > 0.0 && t.linear_solve_s > 0.0,
                "{t:?}"
            );
            assert!(parts <= t.total_s * (1.0 + 1e-12), "{t:?}");
        }
    }
}
