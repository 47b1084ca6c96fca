//! Riks–Crisfield arc-length continuation of R(x, λ) = 0 in a scalar parameter λ (ω, a load,
//! a penetration), with bordered solves on one factorization per iteration, step-size control
//! from the Newton iteration count, and detection of limit and bifurcation points.
//!
//! # Arc length
//!
//! Increments from the last converged point (x_n, λ_n) are measured in the scaled norm
//!
//! ```text
//! ‖(Δx, Δλ)‖² = ‖Δx‖² / x_s² + Δλ² / λ_s²
//! ```
//!
//! (x_s, λ_s: [`ContinuationOptions::x_scale`], [`ContinuationOptions::lambda_scale`]; ‖Δx‖ over
//! the equations of field 0, the displacements: pressures and global unknowns have other units
//! and are left out), and every step has ‖(Δx, Δλ)‖ = Δs (Crisfield's spherical constraint).
//!
//! * **Predictor**: tangent t = −K⁻¹ R_λ at the converged point (K = ∂R/∂x, R_λ = ∂R/∂λ by a
//!   central difference of the residual in λ: two residual-only assemblies), scaled to length
//!   Δs and oriented to make a positive scaled inner product with the previous step (so the
//!   branch is followed through limit points, where λ turns back).
//! * **Corrector**: per iteration one assembly of R and K, one factorization and two solves
//!   a = −K⁻¹R, b = −K⁻¹R_λ (the bordered system solved by block elimination);
//!   δx = a + δλ b with δλ a root of the quadratic spherical constraint; of the two roots the
//!   one whose new increment makes the smaller angle with the old one (Crisfield). Complex
//!   roots fall back to the linearised (Riks) constraint.
//! * **Step control**: after a converged step Δs ← Δs · clamp(√(N_d / N), 0.5, 2) (N iterations,
//!   N_d = `desired_iterations`), within [ds_min, ds_max]. A failed step (no convergence in
//!   `max_iterations`, inadmissible state, singular solve) restores the last point and halves Δs,
//!   at most `max_cutbacks` times in a row.
//!
//! # Special points
//!
//! * **Limit point**: the λ-component of the predictor changes sign between consecutive steps
//!   (λ turns back). Its λ is estimated by the extremum of the parabola through the last three
//!   points.
//! * **Bifurcation point**: the number of negative eigenvalues of K (its inertia, from faer's
//!   LBLᵀ when K is symmetric) or the sign of det K changes between consecutive converged points
//!   while λ keeps its direction (located at the midpoint of the step for an inertia change). det K sign is taken from the factorization when it is known
//!   (Cholesky; LU of a symmetric matrix, via faer's LBLᵀ, see [`super::linear`]). For an
//!   unsymmetric tangent (friction, normal damping) faer's LU does not expose its pivots, so a
//!   **test function** is used instead: the Rayleigh-quotient estimate g = 1 / (cᵀ K⁻¹ c) of the
//!   eigenvalue of K of smallest modulus, with c refined by three steps of inverse iteration per
//!   converged point (c ← K⁻¹c / ‖K⁻¹c‖, three extra solves on the factorization already
//!   there). A real eigenvalue crossing zero changes the sign of g (and of det K). **Limit**:
//!   the iteration follows the mode that was smallest; an eigenvalue that comes down fast from
//!   far away (as standing-wave modes do) can cross zero before the iteration has switched to
//!   it, so g can miss a crossing that the inertia count sees (observed on the spinning
//!   annulus). Treat g as a hint; the inertia / det sign, when available, is authoritative. The point is located
//!   by linear interpolation of g (or of the signed log-determinant). Both are reported in the
//!   branch table ([`BranchPoint::det_sign`], [`BranchPoint::test_function`]).
//! * **Branch switching** ([`ContinuationOptions::switch_branch`]): at the first bifurcation
//!   detected, the path leaves the branch it was on. At the converged point just past the
//!   crossing the null mode φ of K is estimated by inverse iteration (the eigenvector of the
//!   eigenvalue of smallest modulus, which is the one that crossed), its part along the
//!   branch's unit tangent t is removed in the scaled inner product, d = (φ, 0) − ⟨(φ, 0), t⟩ t,
//!   and the next predictor goes along d / ‖d‖ instead of t. The spherical corrector then lands
//!   on the bifurcating branch (a pitchfork's second branch meets that sphere near the
//!   predictor; the old branch meets it only at ±t). The first point of the new branch is
//!   marked [`PointKind::Switched`]; the path does not switch again.
//! - **Jumps past limit points** ([`ContinuationOptions::stop_at_limit`],
//!   [`Continuation::run_with_jumps`]): where λ turns back before the target, the caller's
//!   direct solve looks for a state beyond the limit (another sheet of solutions, e.g. the
//!   steady mode's first-solve path at λ_limit + Δλ); the path goes on from it toward the
//!   target, its first point marked [`PointKind::Jump`]. If it finds none, the state is
//!   restored and the path follows the branch back (at most four tries per run).
//! - **Tangents with a matrix-free part** ([`NonlinearSystem::has_tangent_correction`]: the
//!   steady damping's coupling beyond the cells, a viscoelastic ring history): every solve
//!   (tangent, corrector, test function) is made with the exact tangent by GMRES
//!   preconditioned with the assembled factorization. The det sign and the inertia count are
//!   those of the assembled part only; g uses the exact tangent.

use super::linear::{LinearKind, SparseSolver};
use super::newton::{convergence_reference, NonlinearSystem, SolveError};
use std::time::Instant;

/// x ← K⁻¹ x with K the exact tangent: the assembled factorization `lu`, followed, when the
/// system has a matrix-free part ([`NonlinearSystem::has_tangent_correction`]), by GMRES on
/// the exact tangent to the relative residual `rtol` (see [`super::krylov`]).
fn exact_solve<S: NonlinearSystem + ?Sized>(
    sys: &mut S,
    lu: &mut SparseSolver,
    x: &mut [f64],
    rtol: f64,
) -> Result<(), SolveError> {
    if !sys.has_tangent_correction() {
        lu.solve_in_place(x)?;
        return Ok(());
    }
    let b = x.to_vec();
    lu.solve_in_place(x)?;
    let st = super::krylov::gmres(sys, lu, &b, x, rtol, 40, 200, false)?;
    if st.rel_residual.is_nan() || st.rel_residual > 10.0 * rtol.max(1e-8) {
        sys.tangent_correction_stalled();
        return Err(SolveError::KrylovStalled {
            products: st.iterations,
            reached: st.rel_residual,
            asked: rtol,
        });
    }
    Ok(())
}

/// A nonlinear system with a scalar parameter λ.
pub trait ParametricSystem: NonlinearSystem {
    fn parameter(&self) -> f64;
    fn set_parameter(&mut self, lambda: f64);
}

#[derive(Clone, Debug)]
pub struct ContinuationOptions {
    /// Stop once λ has passed this value (in the direction of travel).
    pub target: f64,
    /// Initial direction of λ: +1 or −1.
    pub direction: f64,
    /// Initial, smallest and largest arc length (scaled units, see the module docs).
    pub ds0: f64,
    pub ds_min: f64,
    pub ds_max: f64,
    pub x_scale: f64,
    pub lambda_scale: f64,
    pub max_steps: usize,
    pub max_iterations: usize,
    pub desired_iterations: usize,
    pub max_cutbacks: usize,
    /// Relative residual tolerance per field, against the system's reference norms.
    pub tol: f64,
    /// Bifurcation test function by inverse iteration when det K is not available.
    pub test_function: bool,
    /// Leave the branch at the first bifurcation detected, along the null mode (see the
    /// module docs).
    pub switch_branch: bool,
    /// Stop at a limit point that turns the path back before the target (instead of following
    /// the branch back): [`ContinuationReport::limit_stop`] says where, and the caller may
    /// jump to another sheet of solutions beyond it and continue from there.
    pub stop_at_limit: bool,
    pub verbose: bool,
}

impl Default for ContinuationOptions {
    fn default() -> Self {
        Self {
            target: 1.0,
            direction: 1.0,
            ds0: 0.1,
            ds_min: 1e-6,
            ds_max: 1.0,
            x_scale: 1.0,
            lambda_scale: 1.0,
            max_steps: 200,
            max_iterations: 12,
            desired_iterations: 4,
            max_cutbacks: 8,
            tol: 1e-8,
            test_function: true,
            switch_branch: false,
            stop_at_limit: false,
            verbose: false,
        }
    }
}

/// What a converged point is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PointKind {
    Start,
    Regular,
    /// λ turned back between the previous point and this one.
    LimitPoint,
    /// det K (or the test function) changed sign between the previous point and this one
    /// without λ turning back.
    Bifurcation,
    /// The first point on the branch entered by branch switching
    /// ([`ContinuationOptions::switch_branch`]).
    Switched,
    /// The first point after a jump past a limit point onto another sheet of solutions (a
    /// direct solve beyond the limit; see [`ContinuationOptions::stop_at_limit`]).
    Jump,
}

/// One converged point of the branch.
#[derive(Clone, Debug, serde::Serialize)]
pub struct BranchPoint {
    pub step: usize,
    pub lambda: f64,
    pub kind: PointKind,
    /// Corrector iterations of this step (0 for the start).
    pub iterations: usize,
    pub cutbacks: usize,
    /// Arc length of this step (scaled units).
    pub ds: f64,
    /// dλ/ds of the predictor that left this point.
    pub dlambda_ds: f64,
    /// Sign of det K at the point (+1, −1; NaN when not available, see the module docs).
    pub det_sign: f64,
    /// log|det K| when known (NaN otherwise).
    pub log_abs_det: f64,
    /// Number of negative eigenvalues of K (inertia, from the LBLᵀ factorization of a
    /// symmetric K; NaN when not available). Standing-wave modes of a rotationally symmetric
    /// mesh come in (cos, sin) pairs, which cross zero together without changing det K's
    /// sign: this count sees them.
    pub negative_eigenvalues: f64,
    /// Smallest-modulus eigenvalue estimate of K (test function; NaN when off).
    pub test_function: f64,
    /// Wall time of the step (s) and of one factorization + solve at this point (s).
    pub wall_time_s: f64,
    pub factor_solve_s: f64,
}

/// A detected special point, located between two converged points.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SpecialPoint {
    pub kind: PointKind,
    /// Estimated parameter value.
    pub lambda: f64,
    /// Step after which it was detected.
    pub step: usize,
    /// What detected it: "dlambda_sign", "negative_eigenvalues", "det_sign" or "test_function".
    pub detected_by: &'static str,
}

#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct ContinuationReport {
    pub points: Vec<BranchPoint>,
    pub special: Vec<SpecialPoint>,
    pub total_iterations: usize,
    pub cutbacks: usize,
    pub assemblies: usize,
    pub factorizations: usize,
    /// Why the continuation stopped.
    pub stop_reason: String,
    /// The point after which the path switched branches
    /// ([`ContinuationOptions::switch_branch`]; `None`: it did not).
    pub switched_at: Option<usize>,
    /// With [`ContinuationOptions::stop_at_limit`]: the estimated λ of the limit point at which
    /// the path stopped because the branch turned back before the target.
    pub limit_stop: Option<f64>,
    /// Jumps past limit points, in order.
    pub jumps: Vec<LimitJump>,
    /// λ of the limit points past which no jump found a steady solution.
    pub failed_jumps: Vec<f64>,
}

/// A jump of the path past a limit point onto another sheet of solutions
/// ([`Continuation::run_with_jumps`]).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct LimitJump {
    /// Step of the first point after the jump ([`PointKind::Jump`]).
    pub step: usize,
    /// Estimated λ of the limit point, and the λ the jump landed at.
    pub limit: f64,
    pub landed: f64,
}

/// Arc-length continuation driver (owns the sparse solver and the work vectors).
pub struct Continuation {
    pub opts: ContinuationOptions,
    solver: SparseSolver,
    refs: Vec<f64>,
    r_lambda: Vec<f64>,
    a: Vec<f64>,
    b: Vec<f64>,
    tu: Vec<f64>,
    /// Tangent of the previous point (orientation of the new one).
    prev_tu: Vec<f64>,
    du: Vec<f64>,
    c: Vec<f64>,
    z: Vec<f64>,
    saved: Vec<f64>,
    saved_tmp: Vec<f64>,
    /// The report up to the failure when [`Self::run`] returns an error.
    pub partial: Option<ContinuationReport>,
    /// 1 for the equations of field 0 (displacements), 0 for the others (pressures, global
    /// unknowns): the arc length is measured on the displacements and λ.
    weight: Vec<f64>,
}

/// The direct solve past a limit point of [`Continuation::run_with_jumps`]: given the system
/// and λ of the limit point, a converged state beyond it and its Newton iterations, or `None`.
pub type JumpFn<'a, S> = &'a mut dyn FnMut(&mut S, f64) -> Option<usize>;

/// Jumps past limit points tried in one run ([`Continuation::run_with_jumps`]).
const MAX_JUMPS: usize = 4;

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

impl Continuation {
    pub fn new<S: ParametricSystem>(
        sys: &S,
        kind: LinearKind,
        opts: ContinuationOptions,
    ) -> Result<Self, SolveError> {
        let (cp, ri) = sys.pattern();
        let n = sys.n_eq();
        let mut solver = SparseSolver::new(n, cp, ri, kind)?;
        solver.set_track_determinant(true);
        // A deterministic, non-special start vector for the inverse iteration.
        let mut c: Vec<f64> = (0..n)
            .map(|i| 1.0 + 0.5 * ((i as f64) * 0.618_033_988_749_895).fract())
            .collect();
        let cn = dot(&c, &c).sqrt().max(f64::MIN_POSITIVE);
        c.iter_mut().for_each(|v| *v /= cn);
        Ok(Self {
            opts,
            solver,
            refs: sys.reference_norms(),
            r_lambda: vec![0.0; n],
            a: vec![0.0; n],
            b: vec![0.0; n],
            tu: vec![0.0; n],
            prev_tu: vec![0.0; n],
            du: vec![0.0; n],
            c,
            z: vec![0.0; n],
            saved: Vec::new(),
            saved_tmp: Vec::new(),
            partial: None,
            weight: sys
                .fields()
                .iter()
                .map(|&f| if f == 0 { 1.0 } else { 0.0 })
                .collect(),
        })
    }

    /// ∂R/∂λ by a central difference (leaves the system evaluated at λ, residual only).
    fn residual_derivative<S: ParametricSystem>(&mut self, sys: &mut S) -> bool {
        let lam = sys.parameter();
        let h = 1e-6 * lam.abs().max(self.opts.lambda_scale);
        sys.set_parameter(lam + h);
        let ok1 = sys.evaluate(false);
        self.r_lambda.copy_from_slice(sys.residual());
        sys.set_parameter(lam - h);
        let ok2 = sys.evaluate(false);
        for (d, r) in self.r_lambda.iter_mut().zip(sys.residual()) {
            *d = (*d - r) / (2.0 * h);
        }
        sys.set_parameter(lam);
        ok1 && ok2 && self.r_lambda.iter().all(|v| v.is_finite())
    }

    /// The corrector's convergence test, Newton's ([`crate::solver::newton`]) without the
    /// round-off bound (the corrector evaluates the residual without the tangent):
    /// ‖R_f‖ ≤ tol · max(‖q_f‖, floor_f) for every field, with q the force scale at the
    /// current evaluation. Returns (converged, largest ‖R_f‖ / ref_f).
    fn converged<S: ParametricSystem>(&self, sys: &S) -> (bool, f64) {
        let refs = convergence_reference(sys, &self.refs);
        let nf = refs.len().max(1);
        let mut norms = vec![0.0; nf];
        for (r, &f) in sys.residual().iter().zip(sys.fields()) {
            let f = (f as usize).min(nf - 1);
            norms[f] += r * r;
        }
        let worst = norms
            .iter()
            .zip(&refs)
            .map(|(n2, r)| n2.sqrt() / r)
            // NaN-propagating maximum: a non-finite residual is never "converged".
            .fold(0.0, |a: f64, b| if b > a || b.is_nan() { b } else { a });
        (worst <= self.opts.tol, worst)
    }

    /// Scaled inner product of two increments.
    fn sdot(&self, x1: &[f64], l1: f64, x2: &[f64], l2: f64) -> f64 {
        let xs2 = self.opts.x_scale * self.opts.x_scale;
        let ls2 = self.opts.lambda_scale * self.opts.lambda_scale;
        self.wdot(x1, x2) / xs2 + l1 * l2 / ls2
    }

    /// Σ w_i a_i b_i (displacement equations only).
    fn wdot(&self, a: &[f64], b: &[f64]) -> f64 {
        a.iter()
            .zip(b)
            .zip(&self.weight)
            .map(|((x, y), w)| w * x * y)
            .sum()
    }

    /// Factorize K at the current (converged) state, record det sign / test function and
    /// compute the unit tangent (tu, tl) in scaled norm. Requires an evaluation with matrix.
    #[allow(clippy::type_complexity)]
    fn tangent<S: ParametricSystem>(
        &mut self,
        sys: &mut S,
    ) -> Result<(f64, f64, f64, f64, f64, f64), SolveError> {
        if !self.residual_derivative(sys) || !sys.evaluate(true) {
            return Err(SolveError::InadmissibleStart);
        }
        let t0 = Instant::now();
        self.solver.factorize(sys.matrix_values())?;
        for (t, r) in self.tu.iter_mut().zip(&self.r_lambda) {
            *t = -r;
        }
        exact_solve(sys, &mut self.solver, &mut self.tu, 1e-10)?;
        let fs = t0.elapsed().as_secs_f64();
        let (sign, logdet) = self.solver.det_sign_log();
        let neg = self
            .solver
            .negative_eigenvalues()
            .map_or(f64::NAN, |n| n as f64);
        let g = if self.opts.test_function {
            self.smallest_mode(sys, 3)?
        } else {
            f64::NAN
        };
        let tl = 1.0;
        let norm = self.sdot(&self.tu, tl, &self.tu, tl).sqrt();
        for t in &mut self.tu {
            *t /= norm;
        }
        Ok((tl / norm, sign, logdet, g, fs, neg))
    }

    /// [`Self::tangent`] at a point without a previous step (the start, the landing of a
    /// jump), oriented so that λ moves toward the target; counts its work in `rep`.
    #[allow(clippy::type_complexity)]
    fn tangent_toward_target<S: ParametricSystem>(
        &mut self,
        sys: &mut S,
        rep: &mut ContinuationReport,
    ) -> Result<(f64, f64, f64, f64, f64, f64), SolveError> {
        let (mut tl, sign, logdet, g, fs, neg) = self.tangent(sys)?;
        rep.factorizations += 1;
        rep.assemblies += 3;
        if tl * self.opts.direction < 0.0 {
            tl = -tl;
            self.tu.iter_mut().for_each(|t| *t = -*t);
        }
        Ok((tl, sign, logdet, g, fs, neg))
    }

    /// `iterations` steps of inverse iteration on the factorized K (exact tangent): `self.c`
    /// becomes the unit estimate of the eigenvector of the eigenvalue of smallest modulus;
    /// returns the Rayleigh-quotient estimate 1 / (cᵀ K⁻¹ c) of that eigenvalue (NaN if the
    /// iteration broke down).
    fn smallest_mode<S: ParametricSystem>(
        &mut self,
        sys: &mut S,
        iterations: usize,
    ) -> Result<f64, SolveError> {
        let mut g = f64::NAN;
        for _ in 0..iterations {
            self.z.copy_from_slice(&self.c);
            exact_solve(sys, &mut self.solver, &mut self.z, 1e-8)?;
            let cz = dot(&self.c, &self.z);
            let zn = dot(&self.z, &self.z).sqrt();
            if !(zn.is_finite() && zn > 0.0) {
                break;
            }
            g = 1.0 / cz;
            for (c, z) in self.c.iter_mut().zip(&self.z) {
                *c = z / zn;
            }
        }
        Ok(g)
    }

    /// Turn the predictor direction (`self.tu`, `tl`) into the null mode of K with its part
    /// along the current unit tangent removed (scaled inner product), normalized; K must be
    /// factorized at the current point. Returns the new λ-component, or `None` when the mode
    /// is (numerically) the tangent itself.
    fn switch_direction<S: ParametricSystem>(
        &mut self,
        sys: &mut S,
        tl: f64,
    ) -> Result<Option<f64>, SolveError> {
        self.smallest_mode(sys, 6)?;
        // The mode in the arc-length metric: the scaled weight of its displacement part.
        let cn = self.sdot(&self.c, 0.0, &self.c, 0.0).sqrt();
        if !(cn.is_finite() && cn > 0.0) {
            return Ok(None);
        }
        let p = self.sdot(&self.c, 0.0, &self.tu, tl) / cn;
        let mut d: Vec<f64> = self
            .c
            .iter()
            .zip(&self.tu)
            .map(|(c, t)| c / cn - p * t)
            .collect();
        let mut dl = -p * tl;
        let dn = self.sdot(&d, dl, &d, dl).sqrt();
        if !(dn.is_finite() && dn > 1e-6) {
            return Ok(None);
        }
        d.iter_mut().for_each(|v| *v /= dn);
        dl /= dn;
        self.tu.copy_from_slice(&d);
        Ok(Some(dl))
    }

    /// Follow the branch from the current (converged) state of `sys`. `on_point` is called at
    /// the start and after every converged step; it returns `false` to stop (e.g. interrupt).
    pub fn run<S: ParametricSystem>(
        &mut self,
        sys: &mut S,
        on_point: &mut dyn FnMut(&S, &BranchPoint) -> bool,
    ) -> Result<ContinuationReport, SolveError> {
        self.run_with_jumps(sys, on_point, None)
    }

    /// [`Self::run`] with a jump past limit points. With [`ContinuationOptions::stop_at_limit`]
    /// and a `jump`, a limit point that turns the path back before the target calls
    /// `jump(sys, λ_limit)`: it must leave `sys` at a converged state beyond the limit (λ on
    /// the target's side) and return its Newton iterations, or return `None` (the state is then
    /// restored and the path follows the branch back). After a jump the path goes on from the
    /// new state toward the target; its first point has kind [`PointKind::Jump`]. Without a
    /// `jump`, the path stops at such a limit point ([`ContinuationReport::limit_stop`]).
    pub fn run_with_jumps<S: ParametricSystem>(
        &mut self,
        sys: &mut S,
        on_point: &mut dyn FnMut(&S, &BranchPoint) -> bool,
        mut jump: Option<JumpFn<'_, S>>,
    ) -> Result<ContinuationReport, SolveError> {
        let mut rep = ContinuationReport::default();
        let t_start = Instant::now();
        let (tl, sign, logdet, g, fs, neg) = self.tangent_toward_target(sys, &mut rep)?;
        let start = BranchPoint {
            step: 0,
            lambda: sys.parameter(),
            kind: PointKind::Start,
            iterations: 0,
            cutbacks: 0,
            ds: 0.0,
            dlambda_ds: tl,
            det_sign: sign,
            log_abs_det: logdet,
            negative_eigenvalues: neg,
            test_function: g,
            wall_time_s: t_start.elapsed().as_secs_f64(),
            factor_solve_s: fs,
        };
        if !on_point(sys, &start) {
            rep.points.push(start);
            rep.stop_reason = "stopped by the caller".into();
            return Ok(rep);
        }
        rep.points.push(start);
        let mut ds = self.opts.ds0;
        // Previous step increment (for orientation), as the unit tangent to start.
        let (mut prev_sign, mut prev_g, mut prev_logdet, mut prev_neg) = (sign, g, logdet, neg);
        let mut tangent_l = tl;
        // Set once the path has switched branches; the next point is the first of the new one.
        let mut switched = false;
        let mut just_switched = false;
        let mut step = 0;
        let mut jump_attempts = 0;
        while step < self.opts.max_steps {
            step += 1;
            let t0 = Instant::now();
            let lam_n = sys.parameter();
            sys.save_state(&mut self.saved);
            let mut cutbacks = 0;
            let iterations = loop {
                let res = self.corrector(sys, ds, tangent_l, &mut rep).and_then(|it| {
                    // A corrector that lands on the backward intersection of the sphere with
                    // the branch (increment against the tangent) would reverse the direction
                    // of travel: rejected like a failure.
                    let dl = sys.parameter() - lam_n;
                    if self.sdot(&self.tu, tangent_l, &self.du, dl) > 0.0 {
                        Ok(it)
                    } else {
                        Err(SolveError::ContinuationReversed {
                            lambda: sys.parameter(),
                        })
                    }
                });
                match res {
                    Ok(it) => break it,
                    Err(e) => {
                        sys.restore_state(&self.saved);
                        sys.set_parameter(lam_n);
                        cutbacks += 1;
                        rep.cutbacks += 1;
                        ds *= 0.5;
                        if self.opts.verbose {
                            eprintln!("  continuation step {step}: {e}; cut back to ds = {ds:.3e}");
                        }
                        if cutbacks > self.opts.max_cutbacks || ds < self.opts.ds_min {
                            rep.stop_reason = format!(
                                "step {step} failed after {cutbacks} cut-backs at lambda = {lam_n:.6e}: {e}"
                            );
                            self.partial = Some(std::mem::take(&mut rep));
                            return Err(SolveError::ContinuationStalled {
                                lambda: lam_n,
                                cutbacks,
                                last: Box::new(e),
                            });
                        }
                    }
                }
            };
            rep.total_iterations += iterations;
            // Increment of this step (for orientation of the next predictor).
            let lam = sys.parameter();
            let dl = lam - lam_n;
            // The increment in equation numbering is carried by du.
            // Old tangent projected on the chord of the step (for the limit-point estimate).
            let p0 = self.sdot(&self.tu, tangent_l, &self.du, dl) / ds;
            // New tangent at the converged point, oriented along the previous one.
            self.prev_tu.copy_from_slice(&self.tu);
            let (mut ntl, sign, logdet, g, fs, neg) = self.tangent(sys)?;
            rep.factorizations += 1;
            rep.assemblies += 3;
            if self.sdot(&self.tu, ntl, &self.prev_tu, tangent_l) < 0.0 {
                ntl = -ntl;
                self.tu.iter_mut().for_each(|t| *t = -*t);
            }
            let mut kind = PointKind::Regular;
            if ntl * tangent_l < 0.0 {
                kind = PointKind::LimitPoint;
                rep.special.push(SpecialPoint {
                    kind,
                    lambda: {
                        // λ as a graph over the chord: slopes dλ/dσ = t_λ / (t · e).
                        let p1 = self.sdot(&self.tu, ntl, &self.du, dl) / ds;
                        limit_estimate(lam_n, lam, tangent_l / p0, ntl / p1, ds)
                    },
                    step,
                    detected_by: "dlambda_sign",
                });
            } else if neg.is_finite() && prev_neg.is_finite() && neg != prev_neg {
                // The inertia changed: eigenvalues crossed zero (pairs included).
                kind = PointKind::Bifurcation;
                rep.special.push(SpecialPoint {
                    kind,
                    lambda: 0.5 * (lam_n + lam),
                    step,
                    detected_by: "negative_eigenvalues",
                });
            } else if sign.is_finite() && prev_sign.is_finite() && sign * prev_sign < 0.0 {
                kind = PointKind::Bifurcation;
                let l = interpolate_zero(
                    lam_n,
                    lam,
                    prev_sign * prev_logdet.exp().min(1e300),
                    sign * logdet.exp().min(1e300),
                );
                rep.special.push(SpecialPoint {
                    kind,
                    lambda: l,
                    step,
                    detected_by: "det_sign",
                });
            } else if !(sign.is_finite() && prev_sign.is_finite())
                && g.is_finite()
                && prev_g.is_finite()
                && g * prev_g < 0.0
            {
                kind = PointKind::Bifurcation;
                rep.special.push(SpecialPoint {
                    kind,
                    lambda: interpolate_zero(lam_n, lam, prev_g, g),
                    step,
                    detected_by: "test_function",
                });
            }
            if just_switched {
                kind = PointKind::Switched;
                just_switched = false;
            }
            let _ = prev_logdet;
            prev_sign = sign;
            prev_g = g;
            prev_logdet = logdet;
            prev_neg = neg;
            tangent_l = ntl;
            let point = BranchPoint {
                step,
                lambda: lam,
                kind,
                iterations,
                cutbacks,
                ds,
                dlambda_ds: ntl,
                det_sign: sign,
                log_abs_det: logdet,
                negative_eigenvalues: neg,
                test_function: g,
                wall_time_s: t0.elapsed().as_secs_f64(),
                factor_solve_s: fs,
            };
            if self.opts.verbose {
                eprintln!(
                    "  continuation step {step}: lambda = {lam:.6e}, {iterations} iterations, ds = {ds:.3e}, det sign {sign}, g = {g:.3e} ({kind:?})"
                );
            }
            let go_on = on_point(sys, &point);
            rep.points.push(point);
            if !go_on {
                rep.stop_reason = "stopped by the caller".into();
                return Ok(rep);
            }
            // A corrector that keeps landing on the same two points (observed past a limit
            // point of a non-smooth problem) makes no progress: stop and say so.
            let k = rep.points.len();
            if k >= 5 {
                let tol = 1e-9 * self.opts.lambda_scale.max(lam.abs());
                let p = &rep.points;
                if (p[k - 1].lambda - p[k - 3].lambda).abs() < tol
                    && (p[k - 2].lambda - p[k - 4].lambda).abs() < tol
                {
                    rep.stop_reason = format!(
                        "the continuation cycles between lambda = {:.6e} and {:.6e} without progress",
                        p[k - 2].lambda,
                        p[k - 1].lambda
                    );
                    self.partial = Some(std::mem::take(&mut rep));
                    return Err(SolveError::ContinuationCycles { lambda: lam });
                }
            }
            if kind == PointKind::LimitPoint
                && self.opts.stop_at_limit
                && tangent_l * self.opts.direction < 0.0
                && (self.opts.target - lam) * self.opts.direction > 0.0
            {
                let at = rep.special.last().map_or(lam, |s| s.lambda);
                let Some(jump) = jump.as_deref_mut().filter(|_| jump_attempts < MAX_JUMPS) else {
                    rep.limit_stop = Some(at);
                    rep.stop_reason = format!(
                        "limit point at lambda = {at:.6e}: the branch turns back before the target"
                    );
                    if !rep.failed_jumps.is_empty() {
                        rep.stop_reason += &format!(
                            " (no steady solution found past the {} limit points before it, at lambda = {})",
                            rep.failed_jumps.len(),
                            rep.failed_jumps
                                .iter()
                                .map(|l| format!("{l:.6e}"))
                                .collect::<Vec<_>>()
                                .join(", ")
                        );
                    }
                    return Ok(rep);
                };
                jump_attempts += 1;
                let tj = Instant::now();
                sys.save_state(&mut self.saved);
                let landed = jump(sys, at).filter(|_| {
                    (sys.parameter() - at) * self.opts.direction > 0.0
                        && sys.residual().iter().all(|r| r.is_finite())
                });
                match landed {
                    Some(iterations) => {
                        let (jtl, sign, logdet, g, fs, neg) =
                            self.tangent_toward_target(sys, &mut rep)?;
                        step += 1;
                        let point = BranchPoint {
                            step,
                            lambda: sys.parameter(),
                            kind: PointKind::Jump,
                            iterations,
                            cutbacks: 0,
                            ds: 0.0,
                            dlambda_ds: jtl,
                            det_sign: sign,
                            log_abs_det: logdet,
                            negative_eigenvalues: neg,
                            test_function: g,
                            wall_time_s: tj.elapsed().as_secs_f64(),
                            factor_solve_s: fs,
                        };
                        rep.total_iterations += iterations;
                        rep.jumps.push(LimitJump {
                            step,
                            limit: at,
                            landed: point.lambda,
                        });
                        if self.opts.verbose {
                            eprintln!(
                                "  continuation step {step}: jumped past the limit point at lambda = {at:.6e} to lambda = {:.6e}",
                                point.lambda
                            );
                        }
                        let go_on = on_point(sys, &point);
                        rep.points.push(point);
                        if !go_on {
                            rep.stop_reason = "stopped by the caller".into();
                            return Ok(rep);
                        }
                        (prev_sign, prev_g, prev_logdet, prev_neg) = (sign, g, logdet, neg);
                        tangent_l = jtl;
                        ds = self.opts.ds0;
                        continue;
                    }
                    None => {
                        rep.failed_jumps.push(at);
                        sys.restore_state(&self.saved);
                        sys.set_parameter(lam);
                        if self.opts.verbose {
                            eprintln!(
                                "  continuation step {step}: no jump past the limit point at lambda = {at:.6e}; following the branch back"
                            );
                        }
                    }
                }
            }
            if (lam - self.opts.target) * self.opts.direction >= 0.0
                && kind != PointKind::LimitPoint
                && dl * self.opts.direction > 0.0
            {
                rep.stop_reason = format!("target lambda = {} reached", self.opts.target);
                return Ok(rep);
            }
            let f = (self.opts.desired_iterations as f64 / iterations.max(1) as f64)
                .sqrt()
                .clamp(0.5, 2.0);
            ds = (ds * f).clamp(self.opts.ds_min, self.opts.ds_max);
            if kind == PointKind::Bifurcation && self.opts.switch_branch && !switched {
                // K is factorized at this point (by `tangent`).
                match self.switch_direction(sys, tangent_l)? {
                    Some(l) => {
                        tangent_l = l;
                        switched = true;
                        just_switched = true;
                        rep.switched_at = Some(step);
                        if self.opts.verbose {
                            eprintln!("  continuation step {step}: switching branches along the null mode");
                        }
                    }
                    None => {
                        if self.opts.verbose {
                            eprintln!("  continuation step {step}: the null mode is the branch's own tangent; no switch");
                        }
                    }
                }
            }
        }
        rep.stop_reason = format!("max_steps = {} reached", self.opts.max_steps);
        Ok(rep)
    }

    /// One predictor–corrector step of arc length `ds` from the current converged state.
    /// On success the state is the new point and `self.du` the increment (equation numbering).
    fn corrector<S: ParametricSystem>(
        &mut self,
        sys: &mut S,
        ds: f64,
        tl: f64,
        rep: &mut ContinuationReport,
    ) -> Result<usize, SolveError> {
        let lam_n = sys.parameter();
        // Predictor.
        for (d, t) in self.du.iter_mut().zip(&self.tu) {
            *d = ds * t;
        }
        let mut dl = ds * tl;
        sys.update(1.0, &self.du);
        sys.set_parameter(lam_n + dl);
        let xs2 = self.opts.x_scale * self.opts.x_scale;
        let ls2 = self.opts.lambda_scale * self.opts.lambda_scale;
        // Last correction (δx in `a`, δλ) for the backtracking below.
        let mut prev_worst = f64::INFINITY;
        let mut last_dlam = 0.0;
        let mut halvings = 0;
        let mut it = 0;
        while it < self.opts.max_iterations {
            it += 1;
            let ok = sys.evaluate(false);
            rep.assemblies += 1;
            let (conv, worst) = self.converged(sys);
            // Backtracking: a correction that does not reduce the residual (a contact point
            // switching in and out of the patch makes the residual non-smooth and full Newton
            // corrections can cycle) is halved, at most 4 times; the arc-length constraint is
            // restored by the next corrections.
            if it > 1 && (!ok || !worst.is_finite() || worst > prev_worst) && halvings < 4 {
                halvings += 1;
                for v in self.a.iter_mut() {
                    *v *= 0.5;
                }
                last_dlam *= 0.5;
                for (d, a) in self.du.iter_mut().zip(&self.a) {
                    *d -= a;
                }
                dl -= last_dlam;
                sys.update(-1.0, &self.a);
                sys.set_parameter(lam_n + dl);
                it -= 1;
                continue;
            }
            halvings = 0;
            if !ok || !worst.is_finite() {
                return Err(SolveError::InadmissibleStart);
            }
            if conv && it > 1 {
                if !sys.evaluate(true) {
                    return Err(SolveError::InadmissibleStart);
                }
                return Ok(it - 1);
            }
            prev_worst = worst;
            if !self.residual_derivative(sys) || !sys.evaluate(true) {
                return Err(SolveError::InadmissibleStart);
            }
            rep.assemblies += 3;
            self.solver.factorize(sys.matrix_values())?;
            rep.factorizations += 1;
            for (a, r) in self.a.iter_mut().zip(sys.residual()) {
                *a = -r;
            }
            exact_solve(sys, &mut self.solver, &mut self.a, 1e-10)?;
            for (b, r) in self.b.iter_mut().zip(&self.r_lambda) {
                *b = -r;
            }
            exact_solve(sys, &mut self.solver, &mut self.b, 1e-10)?;
            // Quadratic spherical constraint for δλ, with Δx' = Δx + a.
            let mut aa = self.wdot(&self.b, &self.b) / xs2 + 1.0 / ls2;
            let mut bb = 0.0;
            let mut cc = 0.0;
            for i in 0..self.du.len() {
                let dxp = self.du[i] + self.a[i];
                bb += self.weight[i] * dxp * self.b[i];
                cc += self.weight[i] * dxp * dxp;
            }
            bb = 2.0 * (bb / xs2 + dl / ls2);
            cc = cc / xs2 + dl * dl / ls2 - ds * ds;
            if aa <= 0.0 {
                aa = f64::MIN_POSITIVE;
            }
            let disc = bb * bb - 4.0 * aa * cc;
            let dlam = if disc >= 0.0 {
                let sq = disc.sqrt();
                let q = -0.5 * (bb + bb.signum() * sq);
                let r1 = q / aa;
                let r2 = if q != 0.0 { cc / q } else { r1 };
                // Root making the smaller angle with the current increment.
                let cos = |r: f64| {
                    let mut s = 0.0;
                    for i in 0..self.du.len() {
                        s += self.weight[i] * (self.du[i] + self.a[i] + r * self.b[i]) * self.du[i];
                    }
                    s / xs2 + (dl + r) * dl / ls2
                };
                if cos(r1) >= cos(r2) {
                    r1
                } else {
                    r2
                }
            } else {
                // Linearised (Riks) constraint: the correction is orthogonal to the increment.
                let num = ds * ds
                    - (self.wdot(&self.du, &self.du) + self.wdot(&self.du, &self.a)) / xs2
                    - dl * dl / ls2;
                let den = self.wdot(&self.du, &self.b) / xs2 + dl / ls2;
                if den.abs() < f64::MIN_POSITIVE {
                    return Err(SolveError::NotConverged {
                        iterations: it,
                        residual: worst,
                        stagnation: None,
                    });
                }
                num / den
            };
            for i in 0..self.du.len() {
                self.a[i] += dlam * self.b[i];
                self.du[i] += self.a[i];
            }
            dl += dlam;
            last_dlam = dlam;
            sys.update(1.0, &self.a);
            sys.set_parameter(lam_n + dl);
            // Increment criterion (the residual of a field with a tiny reference, e.g. the
            // pressure constraints, can sit at its round-off floor): a correction at the
            // round-off level of the state is convergence.
            let corr = self.wdot(&self.a, &self.a).sqrt();
            let xn = {
                sys.save_state(&mut self.saved_tmp);
                self.saved_tmp.iter().map(|v| v * v).sum::<f64>().sqrt()
            };
            if corr <= 1e-12 * xn.max(self.opts.x_scale)
                && dlam.abs() <= 1e-12 * self.opts.lambda_scale.max((lam_n + dl).abs())
                && worst < 1e-3
            {
                if !sys.evaluate(true) {
                    return Err(SolveError::InadmissibleStart);
                }
                return Ok(it);
            }
            if self.opts.verbose {
                eprintln!("    corrector {it}: residual {worst:.3e}, dlambda {dl:.4e}");
            }
        }
        if !sys.evaluate(true) {
            return Err(SolveError::InadmissibleStart);
        }
        let (conv, worst) = self.converged(sys);
        if conv {
            return Ok(self.opts.max_iterations);
        }
        // A non-finite residual after the last correction is an inadmissible state, as inside
        // the loop (not "not converged with residual NaN").
        if !worst.is_finite() {
            return Err(SolveError::InadmissibleStart);
        }
        Err(SolveError::NotConverged {
            iterations: self.opts.max_iterations,
            residual: worst,
            stagnation: None,
        })
    }
}

/// Zero of the line through (l0, g0), (l1, g1).
fn interpolate_zero(l0: f64, l1: f64, g0: f64, g1: f64) -> f64 {
    if (g1 - g0).abs() > 0.0 && g0.is_finite() && g1.is_finite() {
        l0 - g0 * (l1 - l0) / (g1 - g0)
    } else {
        0.5 * (l0 + l1)
    }
}

/// λ at a limit point between two converged points: the extremum of the cubic Hermite
/// interpolant λ(σ) over the chord of the step (σ ∈ [0, ds]) with end slopes dλ/dσ = t0, t1 of
/// opposite signs.
fn limit_estimate(l0: f64, l1: f64, t0: f64, t1: f64, ds: f64) -> f64 {
    // A NaN product (no sign change known) also keeps l1.
    let t01 = t0 * t1;
    if t01.is_nan() || t01 >= 0.0 || ds <= 0.0 {
        return l1;
    }
    // dλ/du of the Hermite cubic (u = s/ds) is A u² + B u + C; its root in (0, 1).
    let a = 6.0 * (l0 - l1) + 3.0 * ds * (t0 + t1);
    let b = 6.0 * (l1 - l0) - ds * (4.0 * t0 + 2.0 * t1);
    let c = ds * t0;
    let mut u = t0 / (t0 - t1);
    if a.abs() > 1e-14 * (b.abs() + c.abs()) {
        let disc = b * b - 4.0 * a * c;
        if disc >= 0.0 {
            let sq = disc.sqrt();
            let roots = [(-b + sq) / (2.0 * a), (-b - sq) / (2.0 * a)];
            if let Some(r) = roots.into_iter().find(|r| (0.0..=1.0).contains(r)) {
                u = r;
            }
        }
    } else if b != 0.0 && (0.0..=1.0).contains(&(-c / b)) {
        u = -c / b;
    }
    let (h00, h10, h01, h11) = (
        2.0 * u.powi(3) - 3.0 * u * u + 1.0,
        u.powi(3) - 2.0 * u * u + u,
        -2.0 * u.powi(3) + 3.0 * u * u,
        u.powi(3) - u * u,
    );
    h00 * l0 + h10 * ds * t0 + h01 * l1 + h11 * ds * t1
}

#[cfg(test)]
mod tests {
    use super::*;

    /// R(x, λ) = x³ − 3x − λ (one equation): limit points at x = ±1, λ = ∓2. Starting at
    /// x = −2 (λ = −2) and increasing λ, the branch passes the limit at λ = 2 (x = −1), turns
    /// back through λ = 0 to the second limit at λ = −2 (x = 1), and goes on to λ = 10.
    struct Cubic {
        x: f64,
        lam: f64,
        r: [f64; 1],
        k: [f64; 1],
    }

    impl NonlinearSystem for Cubic {
        fn n_eq(&self) -> usize {
            1
        }
        fn fields(&self) -> &[u8] {
            &[0]
        }
        fn field_names(&self) -> &'static [&'static str] {
            &["x"]
        }
        fn reference_norms(&self) -> Vec<f64> {
            vec![1.0]
        }
        fn pattern(&self) -> (&[usize], &[usize]) {
            (&[0, 1], &[0])
        }
        fn evaluate(&mut self, _m: bool) -> bool {
            self.r[0] = self.x.powi(3) - 3.0 * self.x - self.lam;
            self.k[0] = 3.0 * self.x * self.x - 3.0;
            true
        }
        fn residual(&self) -> &[f64] {
            &self.r
        }
        fn matrix_values(&self) -> &[f64] {
            &self.k
        }
        fn update(&mut self, alpha: f64, dx: &[f64]) {
            self.x += alpha * dx[0];
        }
        fn save_state(&self, buf: &mut Vec<f64>) {
            buf.clear();
            buf.push(self.x);
        }
        fn restore_state(&mut self, buf: &[f64]) {
            self.x = buf[0];
        }
    }

    impl ParametricSystem for Cubic {
        fn parameter(&self) -> f64 {
            self.lam
        }
        fn set_parameter(&mut self, lambda: f64) {
            self.lam = lambda;
        }
    }

    /// The cubic at (x, λ) = (−2, −2), on its lower sheet.
    fn cubic_start() -> Cubic {
        Cubic {
            x: -2.0,
            lam: -2.0,
            r: [0.0],
            k: [0.0],
        }
    }

    /// From λ = −2 toward λ = 10 in steps of at most 0.25.
    fn cubic_options() -> ContinuationOptions {
        ContinuationOptions {
            target: 10.0,
            ds0: 0.2,
            ds_max: 0.25,
            tol: 1e-12,
            max_steps: 500,
            ..Default::default()
        }
    }

    #[test]
    fn cubic_passes_both_limit_points() {
        let mut sys = cubic_start();
        let opts = cubic_options();
        let mut cont = Continuation::new(&sys, LinearKind::Lu, opts).unwrap();
        let mut xs = Vec::new();
        let rep = cont
            .run(&mut sys, &mut |s: &Cubic, _p| {
                xs.push(s.x);
                true
            })
            .unwrap();
        // Every point is on the curve.
        for (p, x) in rep.points.iter().zip(&xs) {
            assert!(
                (x.powi(3) - 3.0 * x - p.lambda).abs() < 1e-9,
                "off the curve"
            );
        }
        let limits: Vec<f64> = rep
            .special
            .iter()
            .filter(|s| s.kind == PointKind::LimitPoint)
            .map(|s| s.lambda)
            .collect();
        assert_eq!(limits.len(), 2, "{:?}", rep.special);
        assert!(
            (limits[0] - 2.0).abs() < 0.01,
            "first limit at {}",
            limits[0]
        );
        assert!(
            (limits[1] + 2.0).abs() < 0.01,
            "second limit at {}",
            limits[1]
        );
        assert!(sys.lam >= 10.0 && sys.x > 2.0);
        // det K = 3x² − 3 changes sign at both limit points (and these are not bifurcations).
        assert!(rep.special.iter().all(|s| s.kind != PointKind::Bifurcation));
    }

    /// The cubic's S curve with jumps: at the first limit point (λ = 2) a direct solve by
    /// Newton from x = 3 at λ = 2 + 0.5 lands on the upper sheet (x > 1), and the path goes
    /// on from there to the target without the backward sheet (the second limit point is
    /// never reached). A jump that finds nothing (here: refused) leaves the path to follow
    /// the branch back, as without jumps, and is reported.
    #[test]
    fn cubic_jumps_past_its_limit_point() {
        let opts = ContinuationOptions {
            stop_at_limit: true,
            ..cubic_options()
        };
        let mut sys = cubic_start();
        let mut cont = Continuation::new(&sys, LinearKind::Lu, opts.clone()).unwrap();
        let mut xs = Vec::new();
        let mut jump = |s: &mut Cubic, at: f64| {
            s.lam = at + 0.5;
            s.x = 3.0;
            let mut it = 0;
            while (s.x.powi(3) - 3.0 * s.x - s.lam).abs() > 1e-13 && it < 50 {
                s.x -= (s.x.powi(3) - 3.0 * s.x - s.lam) / (3.0 * s.x * s.x - 3.0);
                it += 1;
            }
            Some(it)
        };
        let rep = cont
            .run_with_jumps(
                &mut sys,
                &mut |s: &Cubic, _p| {
                    xs.push(s.x);
                    true
                },
                Some(&mut jump),
            )
            .unwrap();
        for (p, x) in rep.points.iter().zip(&xs) {
            assert!(
                (x.powi(3) - 3.0 * x - p.lambda).abs() < 1e-9,
                "off the curve"
            );
        }
        assert_eq!(rep.jumps.len(), 1, "{:?}", rep.jumps);
        let LimitJump {
            step,
            limit,
            landed,
        } = rep.jumps[0];
        assert!((limit - 2.0).abs() < 0.01, "limit at {limit}");
        assert!((landed - limit - 0.5).abs() < 1e-12);
        let i = rep.points.iter().position(|p| p.step == step).unwrap();
        assert_eq!(rep.points[i].kind, PointKind::Jump);
        assert_eq!(rep.points[i - 1].kind, PointKind::LimitPoint);
        // From the jump on: the upper sheet, λ increasing, no further special point.
        assert!(xs[i..].iter().all(|&x| x > 1.0));
        assert!(rep.points[i..]
            .windows(2)
            .all(|w| w[1].lambda > w[0].lambda));
        assert_eq!(rep.special.len(), 1, "{:?}", rep.special);
        assert!(sys.lam >= 10.0 && sys.x > 2.0, "{} {}", sys.lam, sys.x);
        assert!(rep.stop_reason.contains("target"), "{}", rep.stop_reason);

        // A refused jump: the path follows the branch back through both limit points.
        let mut sys = cubic_start();
        let mut cont = Continuation::new(&sys, LinearKind::Lu, opts.clone()).unwrap();
        let mut refuse = |s: &mut Cubic, _at: f64| {
            s.x = f64::NAN;
            None
        };
        let rep = cont
            .run_with_jumps(&mut sys, &mut |_: &Cubic, _p| true, Some(&mut refuse))
            .unwrap();
        assert!(rep.jumps.is_empty());
        assert_eq!(rep.failed_jumps.len(), 1, "{:?}", rep.failed_jumps);
        assert!(sys.lam >= 10.0 && sys.x > 2.0, "{} {}", sys.lam, sys.x);

        // No jump given: the path stops at the limit point and says where.
        let mut sys = cubic_start();
        let mut cont = Continuation::new(&sys, LinearKind::Lu, opts).unwrap();
        let rep = cont.run(&mut sys, &mut |_: &Cubic, _p| true).unwrap();
        let at = rep.limit_stop.expect("stopped at the limit point");
        assert!((at - 2.0).abs() < 0.01, "{at}");
        assert!(sys.lam < 2.0 + 1e-9, "{}", sys.lam);
    }

    /// A pitchfork: R1 = x1 − λ (the primary response), R2 = x2 (1 − x1) + x2³. On the primary
    /// branch x2 = 0, det K = 1 − λ changes sign at λ = 1, where the branch x2² = λ − 1
    /// bifurcates. Without switching the path stays on x2 = 0 and reports the bifurcation
    /// near λ = 1; with switching every point after the switch lies on x2² = λ − 1, x2 ≠ 0.
    struct Pitchfork {
        x: [f64; 2],
        lam: f64,
        r: [f64; 2],
        k: [f64; 4],
    }

    impl NonlinearSystem for Pitchfork {
        fn n_eq(&self) -> usize {
            2
        }
        fn fields(&self) -> &[u8] {
            &[0, 0]
        }
        fn field_names(&self) -> &'static [&'static str] {
            &["x"]
        }
        fn reference_norms(&self) -> Vec<f64> {
            vec![1.0]
        }
        fn pattern(&self) -> (&[usize], &[usize]) {
            (&[0, 2, 4], &[0, 1, 0, 1])
        }
        fn evaluate(&mut self, _m: bool) -> bool {
            let [x1, x2] = self.x;
            self.r = [x1 - self.lam, x2 * (1.0 - x1) + x2.powi(3)];
            // Column-major: (0,0), (1,0), (0,1), (1,1).
            self.k = [1.0, -x2, 0.0, 1.0 - x1 + 3.0 * x2 * x2];
            true
        }
        fn residual(&self) -> &[f64] {
            &self.r
        }
        fn matrix_values(&self) -> &[f64] {
            &self.k
        }
        fn update(&mut self, alpha: f64, dx: &[f64]) {
            self.x[0] += alpha * dx[0];
            self.x[1] += alpha * dx[1];
        }
        fn save_state(&self, buf: &mut Vec<f64>) {
            buf.clear();
            buf.extend_from_slice(&self.x);
        }
        fn restore_state(&mut self, buf: &[f64]) {
            self.x.copy_from_slice(buf);
        }
    }

    impl ParametricSystem for Pitchfork {
        fn parameter(&self) -> f64 {
            self.lam
        }
        fn set_parameter(&mut self, lambda: f64) {
            self.lam = lambda;
        }
    }

    fn follow_pitchfork(switch_branch: bool) -> (ContinuationReport, Vec<[f64; 2]>) {
        let mut sys = Pitchfork {
            x: [0.3, 0.0],
            lam: 0.3,
            r: [0.0; 2],
            k: [0.0; 4],
        };
        let opts = ContinuationOptions {
            target: 2.0,
            ds0: 0.1,
            ds_max: 0.15,
            tol: 1e-12,
            switch_branch,
            ..Default::default()
        };
        let mut cont = Continuation::new(&sys, LinearKind::Lu, opts).unwrap();
        let mut xs = Vec::new();
        let rep = cont
            .run(&mut sys, &mut |s: &Pitchfork, _p| {
                xs.push(s.x);
                true
            })
            .unwrap();
        (rep, xs)
    }

    #[test]
    fn pitchfork_is_detected_and_switched_onto() {
        let (plain, xs) = follow_pitchfork(false);
        assert!(plain.switched_at.is_none());
        assert!(xs.iter().all(|x| x[1].abs() < 1e-9), "left x2 = 0 unasked");
        let bif: Vec<f64> = plain
            .special
            .iter()
            .filter(|s| s.kind == PointKind::Bifurcation)
            .map(|s| s.lambda)
            .collect();
        assert_eq!(bif.len(), 1, "{:?}", plain.special);
        // Located at the midpoint of the step (inertia change of the symmetric K): within
        // half the largest step.
        assert!((bif[0] - 1.0).abs() < 0.08, "bifurcation at {}", bif[0]);

        let (rep, xs) = follow_pitchfork(true);
        let k = rep.switched_at.expect("switched");
        assert_eq!(rep.points[k].kind, PointKind::Bifurcation);
        assert_eq!(rep.points[k + 1].kind, PointKind::Switched);
        for (p, x) in rep.points.iter().zip(&xs).skip(k + 1) {
            assert!(x[1].abs() > 1e-3, "back on x2 = 0 at lambda = {}", p.lambda);
            assert!(
                (x[1] * x[1] - (p.lambda - 1.0)).abs() < 1e-9,
                "off the bifurcated branch: x2 = {}, lambda = {}",
                x[1],
                p.lambda
            );
        }
        assert!(
            rep.points.last().unwrap().lambda >= 2.0,
            "{}",
            rep.stop_reason
        );
    }
}
