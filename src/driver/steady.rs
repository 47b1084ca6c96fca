//! Steady rolling in the θ-referential (Eulerian/ALE) description (the paper's
//! Figs. 2–8).
//!
//! The mesh stays in space and material flows through it along the reference circles. The
//! unknown is the motion χ(X) = X + u(X) of the material point that is at the referential
//! position X (numbering and positions as the transient mode's extracted field, so the two can
//! be compared node by node). The residual is the [`crate::physics::SolidModel`] one with the
//! inertia term −ω² ∫ ρ0 ∂θχ · ∂θη (the paper's B), plus the contact element of
//! [`crate::contact`] with [`SlipKinematics::Steady`](crate::contact::SlipKinematics::Steady): normal compliance with damping on
//! δ̇ = −ω ∂θχ2 and friction on the slip w = ω ∂θχ1 − v0. With friction or damping the tangent
//! is unsymmetric (LU). The friction slip takes ∂θu from nodal five-point θ-differences along
//! the contact boundary, interpolated over each facet ([`crate::contact::steady_slip`],
//! [`SolidSystem::enable_steady_slip`]): the facet-wise derivative jumps at the facet ends, and
//! in the stick zone, where the exact slip is below the regularisation ε, that jump switched the
//! friction traction between +μ t_n and −μ t_n inside every facet.
//!
//! The transient mode's objective strain-rate damping (`time.strain_rate_damping`, S_v = η Ė)
//! is in the steady residual too, discretized as in the transient mode: Ė = sym(Fᵀ ∇v_h) with
//! v_h the interpolant of the nodal velocities v_a = ω ∂θχ(X_a), taken by five-point
//! differences along the node rings, or by cell averages on a mesh without rings
//! ([`crate::physics::NodalThetaDerivative`], [`SolidSystem::enable_steady_viscosity`]). (The
//! elementwise gradient of ω ∂θχ_h, which is discontinuous across the radial cell edges,
//! converged to a different solution: 1.7 % in the field and 1 % in the hub force at 20 rad/s
//! on the paper's cylinder, whatever the mesh.) The nodal derivative couples a cell with its
//! neighbours' neighbours. Three Newton matrices (`[solver] damping_tangent`,
//! [`super::SteadyDampingTangent`]): matrix-free keeps the undamped sparsity (each cell
//! linearises its velocities with its own derivative) and Newton takes the exact step by
//! GMRES with the rest of the tangent applied matrix-free ([`crate::solver::krylov`]); banded
//! (ring meshes, the default from 60,000 equations) assembles three-point ring differences,
//! one node passage beyond the cells, and leaves less to GMRES (1–9 products per iteration
//! instead of 4–42 at 66k–1M DOFs); assembled puts the whole coupling in the matrix (a direct
//! solve, used by continuation). Measured costs are in the README.
//!
//! # Procedure
//!
//! 1. At the scene's ω (and v0), the road is brought in by load stepping (displacement control:
//!    H = Ro − λ DISP; load control: P = λ P, H unknown) from the undeformed state. If that
//!    fails, [`super::steady_recovery`] tries homotopies (κ, ε, ω from benign values to the
//!    scene's) before giving up; what it did is in the solve's
//!    [`SolveReports`](super::steady_report::SolveReports).
//!
//!    Known hard case, measured: with normal damping and `l_n = 0` the traction of a point
//!    entering the patch (δ̇ > 0) jumps from 0 to b_n δ̇ at first contact. The discrete steady
//!    branch then consists of pieces that end in non-smooth folds, with gaps in between that
//!    none of the pieces found reaches (`oden_hollow_cylinder`, 3 × 64: stepping ω up stops
//!    at 37.8495 rad/s, stepping down from 38.71 stops at 38.586, so ω = 38 has no solution on
//!    either piece; κ/G = 1e4 likewise lies between 1.362e6 and 2.092e6 psi on the κ path).
//!    A recovery cannot solve a target in such a gap; `l_n > 0` (damping vanishing at first
//!    contact) or `b_n = 0` closes them (the direct solves at 38 rad/s and κ/G = 1e4 then
//!    converge).
//! 2. Free rolling / given torque ([`solve_torque`]): the road speed v0 is adjusted by a
//!    safeguarded secant iteration until the hub torque equals the target; each evaluation is a
//!    Newton solve from the previous state. Given creep: free rolling first (v0_free, rolling
//!    radius R_e = v0_free / ω), then the creep ξ = (v0 − ω R_e) / (ω R_e) = v0 / v0_free − 1 is
//!    reached by natural-parameter steps ([`step_parameter`], [`SteadyParameter::Creep`]). The
//!    scene selects these with `motion.control` (see [`super::steady_solve::apply_control`]).
//! 3. Optionally, Riks–Crisfield continuation ([`crate::solver::continuation`]) in ω, the hub
//!    load or the penetration. In ω the road speed follows v0 = (v0 / ω)_start · ω (constant
//!    ratio: the creep stays put while the speed changes).

use crate::io::record::Recorder;
use crate::io::scene::{DampingTangentChoice, Scene, SteadyHistoryChoice};
use crate::model::system::{Loading, SolidSystem};
use crate::model::SteadyDampingTangent;
use crate::physics::viscoelastic_steady::StreamlineScheme;
use crate::physics::SolidModel;
use crate::setup::{build_contact, build_model, scene_loading, solve_plan, AppError};
use crate::solver::continuation::ParametricSystem;
use crate::solver::stepping::{solve_load_steps, StepOptions, StepReport};
use crate::solver::{
    LinearKind, Newton, NewtonOptions, NonlinearSystem, SolveError, SolvePlan, SparseSolver,
};

/// The parameter of a continuation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SteadyParameter {
    /// Angular speed ω (rad/s), with v0 / ω fixed.
    Omega,
    /// Downward hub load (force per unit thickness; load control).
    Load,
    /// Penetration DISP = Ro − H (displacement control).
    Disp,
    /// Creep ξ = v0 / v0_free − 1 at fixed ω ([`SteadyRolling::v0_free`] must be set).
    Creep,
}

/// A [`SolidSystem`] in steady rolling with one of its data as the parameter λ.
pub struct SteadyRolling {
    pub sys: SolidSystem,
    pub param: SteadyParameter,
    /// v0 / ω kept fixed when ω is the parameter.
    pub v0_per_omega: f64,
    /// Outer radius (H = ro − disp).
    pub ro: f64,
    /// Why the steady damping's tangent the system was built with differs from the one asked
    /// for ([`crate::model::SteadyDampingTangent`]): banded asked for on a mesh without node
    /// rings (matrix-free then). The solve's own switches are in its
    /// [`SolveReports`](super::steady_report::SolveReports).
    pub damping_fallback: Option<String>,
    /// How this system is solved (linear solver, Newton, load steps), decided from the scene
    /// when the system was built ([`steady_on`]; otherwise LU, Newton's default options and
    /// 4 load steps with up to 10 cut-backs, the scene's defaults).
    pub plan: SolvePlan,
    /// Free-rolling road speed at the current ω (zero hub torque), once solved for
    /// ([`solve_torque`] with target 0); the reference of the creep. NaN until then.
    pub v0_free: f64,
    /// A linear solver analysed for this system's matrix ahead of its first Newton solve
    /// (while a coarser mesh was solved, [`super::steady_nested`]), and the wall time of that
    /// analysis: [`press`] takes it when its kind and pattern still match.
    pub analysed: Option<(SparseSolver, f64)>,
}

impl SteadyRolling {
    /// Wrap a system with contact; sets the steady kinematics at angular speed `omega`.
    pub fn new(sys: SolidSystem, omega: f64, ro: f64) -> Self {
        let v0 = sys.contact.as_ref().map_or(0.0, |c| c.v0);
        let mut s = Self {
            sys,
            param: SteadyParameter::Omega,
            v0_per_omega: if omega != 0.0 { v0 / omega } else { 0.0 },
            ro,
            v0_free: f64::NAN,
            damping_fallback: None,
            plan: SolvePlan {
                kind: LinearKind::Lu,
                newton: NewtonOptions::default(),
                steps: StepOptions {
                    initial_steps: 4,
                    max_cutbacks: 10,
                    verbose: false,
                },
            },
            analysed: None,
        };
        s.set_omega(omega, v0);
        s.sys.enable_steady_slip();
        // A degenerate cell map fails the first evaluation anyway (J ≤ 0), with its message.
        let _ = s.sys.enable_steady_viscosity();
        s
    }

    pub fn omega(&self) -> f64 {
        self.sys.model.omega2.max(0.0).sqrt()
    }

    /// ω with its sign (as set by [`Self::set_omega`]).
    pub fn omega_signed(&self) -> f64 {
        self.sys.steady_omega.unwrap_or_else(|| self.omega())
    }

    pub fn v0(&self) -> f64 {
        self.sys.contact.as_ref().map_or(0.0, |c| c.v0)
    }

    /// Set ω and v0 (inertia ω², contact kinematics).
    pub fn set_omega(&mut self, omega: f64, v0: f64) {
        self.sys.model.omega2 = omega * omega;
        self.sys.steady_omega = Some(omega);
        if let Some(c) = &mut self.sys.contact {
            c.v0 = v0;
        }
    }

    pub fn set_v0(&mut self, v0: f64) {
        if let Some(c) = &mut self.sys.contact {
            c.v0 = v0;
        }
    }

    /// Hub torque (moment the hub exerts on the body, counter-clockwise positive).
    pub fn hub_torque(&self) -> f64 {
        self.sys.hub_reaction().1
    }

    /// Penetration DISP = Ro − H at the current state.
    pub fn penetration(&self) -> f64 {
        self.ro - self.sys.road_height().unwrap_or(self.ro)
    }

    /// Creep ξ = (v0 − ω R_e) / (ω R_e) = v0 / v0_free − 1, with the free-rolling radius
    /// R_e = v0_free / ω; NaN before free rolling has been solved for.
    pub fn creep(&self) -> f64 {
        self.v0() / self.v0_free - 1.0
    }

    /// Effective rolling radius R_e = v0_free / ω (NaN before free rolling was solved for).
    pub fn rolling_radius(&self) -> f64 {
        self.v0_free / self.omega_signed()
    }
}

impl NonlinearSystem for SteadyRolling {
    crate::solver::system::delegate_nonlinear_system!(sys);
}

impl ParametricSystem for SteadyRolling {
    fn parameter(&self) -> f64 {
        match self.param {
            SteadyParameter::Omega => self.omega(),
            SteadyParameter::Load => self
                .sys
                .contact
                .as_ref()
                .and_then(|c| c.load)
                .unwrap_or(0.0),
            SteadyParameter::Disp => self.ro - self.sys.contact.as_ref().map_or(self.ro, |c| c.h),
            SteadyParameter::Creep => self.creep(),
        }
    }
    fn set_parameter(&mut self, lambda: f64) {
        match self.param {
            SteadyParameter::Omega => {
                let v0 = self.v0_per_omega * lambda;
                self.set_omega(lambda, v0);
            }
            SteadyParameter::Load => {
                if let Some(c) = &mut self.sys.contact {
                    c.load = Some(lambda);
                }
            }
            SteadyParameter::Disp => {
                let ro = self.ro;
                if let Some(c) = &mut self.sys.contact {
                    c.h = ro - lambda;
                }
            }
            SteadyParameter::Creep => {
                let v0 = (1.0 + lambda) * self.v0_free;
                self.set_v0(v0);
            }
        }
    }
}

/// Step 1: bring the road in at the current ω and v0 by load stepping.
pub fn press(
    st: &mut SteadyRolling,
    loading: Loading,
    kind: LinearKind,
    newton_opts: NewtonOptions,
    step_opts: &StepOptions,
    report: &mut StepReport,
    rec: &mut dyn Recorder,
) -> Result<(), SolveError> {
    st.sys.loading = loading;
    if st.sys.contact.is_some() {
        let f = st.sys.contact_force_scale(st.ro);
        st.sys.set_reference_force(f);
    }
    let mut newton = match st.analysed.take() {
        Some((solver, wall))
            if solver.kind() == kind && {
                let (cp, ri) = st.sys.pattern();
                solver.has_pattern(cp, ri)
            } =>
        {
            if newton_opts.verbose {
                eprintln!(
                    "         symbolic analysis of {} equations: {wall:.3} s, made alongside the coarser mesh's solve",
                    st.sys.n_eq()
                );
            }
            Newton::with_solver(&st.sys, solver, newton_opts)
        }
        _ => Newton::new(&st.sys, kind, newton_opts)?,
    };
    solve_load_steps(&mut st.sys, &mut newton, step_opts, report, rec)
}

/// Result of [`solve_torque`].
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct TorqueSolve {
    pub v0: f64,
    pub torque: f64,
    pub evaluations: usize,
    pub newton_iterations: usize,
    /// (v0, torque) of every evaluation.
    pub history: Vec<(f64, f64)>,
    /// Trial speeds whose Newton solve failed (each followed by a halved trial).
    pub failed_trials: usize,
}

/// A steady rolling system whose road speed the rolling controls move: the plane-strain
/// [`SteadyRolling`] and the three-dimensional [`crate::model::Solid3DSystem`].
pub trait RoadSpeedSystem: NonlinearSystem {
    /// The road speed v0.
    fn road_speed(&self) -> f64;
    fn set_road_speed(&mut self, v0: f64);
    /// The torque the hub exerts on the body about the axle +x3 (counter-clockwise positive;
    /// per unit thickness in the plane, total in three dimensions) at the current state.
    fn hub_torque(&self) -> f64;
    /// The rolling speed |ω| Ro: the velocity scale of the secant's first step.
    fn rolling_speed(&self) -> f64;
    /// ω with its sign.
    fn angular_speed(&self) -> f64;
}

impl RoadSpeedSystem for SteadyRolling {
    fn road_speed(&self) -> f64 {
        self.v0()
    }
    fn set_road_speed(&mut self, v0: f64) {
        self.set_v0(v0)
    }
    fn hub_torque(&self) -> f64 {
        SteadyRolling::hub_torque(self)
    }
    fn rolling_speed(&self) -> f64 {
        (self.omega() * self.ro).abs()
    }
    fn angular_speed(&self) -> f64 {
        self.omega_signed()
    }
}

/// Step 2: adjust v0 until the hub torque equals `target` (0 = free rolling), by a secant
/// iteration safeguarded by bisection once the root is bracketed. Converged when
/// |T − target| ≤ `tol` · `torque_scale`.
pub fn solve_torque<S: RoadSpeedSystem>(
    st: &mut S,
    target: f64,
    torque_scale: f64,
    tol: f64,
    newton: &mut Newton,
    max_evaluations: usize,
) -> Result<TorqueSolve, SolveError> {
    let mut out = TorqueSolve::default();
    let mut saved = Vec::new();
    let mut eval = |st: &mut S, v0: f64, out: &mut TorqueSolve| -> Result<f64, SolveError> {
        st.save_state(&mut saved);
        let v_prev = st.road_speed();
        st.set_road_speed(v0);
        match newton.solve(st) {
            Ok(r) => {
                out.newton_iterations += r.iterations;
                out.evaluations += 1;
                let t = st.hub_torque() - target;
                out.history.push((v0, t + target));
                Ok(t)
            }
            Err(e) => {
                st.restore_state(&saved);
                st.set_road_speed(v_prev);
                Err(e)
            }
        }
    };
    // Velocity scale for the first secant step: 1e-3 of the rolling speed.
    let vs = st
        .rolling_speed()
        .max(st.road_speed().abs())
        .max(f64::MIN_POSITIVE);
    let mut a = st.road_speed();
    let mut fa = eval(st, a, &mut out)?;
    if fa.abs() <= tol * torque_scale {
        out.v0 = a;
        out.torque = fa + target;
        return Ok(out);
    }
    let mut b = a + 1e-3 * vs * if fa > 0.0 { 1.0 } else { -1.0 };
    let mut fb = eval(st, b, &mut out)?;
    // Bracket [lo, hi] once the torque has changed sign.
    let mut bracket: Option<(f64, f64, f64, f64)> = None;
    for _ in 0..max_evaluations {
        if fb.abs() <= tol * torque_scale {
            out.v0 = b;
            out.torque = fb + target;
            return Ok(out);
        }
        if fa * fb < 0.0 {
            bracket = Some((a, fa, b, fb));
        }
        let mut c = if fb != fa {
            b - fb * (b - a) / (fb - fa)
        } else {
            b + 1e-3 * vs
        };
        if let Some((lo, flo, hi, fhi)) = bracket {
            let (l, h) = (lo.min(hi), lo.max(hi));
            if !(c > l && c < h) {
                c = 0.5 * (lo + hi);
            }
            let _ = (flo, fhi);
        } else {
            // Limit the secant step to 20 % of the rolling speed.
            let max_step = 0.2 * vs;
            c = b + (c - b).clamp(-max_step, max_step);
        }
        // A trial the Newton solve does not reach from the previous state (a large step into
        // full sliding, say) is halved toward it, a few times, before giving up.
        let mut halvings = 0;
        let fc = loop {
            match eval(st, c, &mut out) {
                Ok(f) => break f,
                Err(SolveError::Interrupted { at }) => return Err(SolveError::Interrupted { at }),
                Err(e) if halvings >= 6 => return Err(unreachable_torque(&out, target, e)),
                Err(_) => {
                    halvings += 1;
                    out.failed_trials += 1;
                    c = b + 0.5 * (c - b);
                }
            }
        };
        if let Some((lo, flo, hi, fhi)) = bracket {
            // Keep the bracket around the root.
            if flo * fc < 0.0 {
                bracket = Some((lo, flo, c, fc));
            } else {
                bracket = Some((c, fc, hi, fhi));
            }
        }
        a = b;
        fa = fb;
        b = c;
        fb = fc;
    }
    Err(unreachable_torque(
        &out,
        target,
        SolveError::NotConverged {
            iterations: out.evaluations,
            residual: fb.abs() / torque_scale.max(f64::MIN_POSITIVE),
            stagnation: None,
        },
    ))
}

/// The failure of [`solve_torque`] with the range its trials covered.
fn unreachable_torque(out: &TorqueSolve, target: f64, last: SolveError) -> SolveError {
    let range = |f: fn(&(f64, f64)) -> f64| {
        out.history
            .iter()
            .map(f)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            })
    };
    let (v_min, v_max) = range(|h| h.0);
    let (t_min, t_max) = range(|h| h.1);
    SolveError::TorqueUnreachable {
        target,
        v_min,
        v_max,
        t_min,
        t_max,
        last: Box::new(last),
    }
}

/// Move the parameter of `st` (its [`SteadyRolling::param`]) from its current value to `target`
/// by natural-parameter steps: a Newton solve from the previous state at each step; a failed
/// step restores the state and halves the step (at most `max_cutbacks` times in a row, and
/// never below 2^−max_cutbacks of the requested step, so the walk cannot stall); a
/// converged step lets the next one grow by 1.5 up to the whole remaining distance. Returns the
/// Newton iterations spent.
pub fn step_parameter<S: ParametricSystem>(
    st: &mut S,
    target: f64,
    newton: &mut Newton,
    max_cutbacks: usize,
) -> Result<usize, SolveError> {
    step_parameter_with(
        st,
        target,
        newton,
        max_cutbacks,
        S::parameter,
        S::set_parameter,
    )
}

/// [`step_parameter`] with the parameter read by `get` and set by `set`.
pub fn step_parameter_with<S: NonlinearSystem>(
    st: &mut S,
    target: f64,
    newton: &mut Newton,
    max_cutbacks: usize,
    get: impl Fn(&S) -> f64,
    set: impl Fn(&mut S, f64),
) -> Result<usize, SolveError> {
    let mut lambda = get(st);
    let mut step = target - lambda;
    // The smallest step allowed: `max_cutbacks` halvings of the requested one. Without it a
    // residual that is discontinuous just ahead (a node crossing the patch edge with l_n = 0
    // damping) alternates tiny successes (step × 1.5) and failures (step × 0.5) without end.
    let min_step = step.abs() * 0.5f64.powi(max_cutbacks.min(60) as i32);
    let mut iterations = 0;
    let mut cutbacks = 0;
    let mut saved = Vec::new();
    while lambda != target {
        let next = if (target - lambda).abs() <= step.abs() {
            target
        } else {
            lambda + step
        };
        if next != target && crate::solver::newton::below_round_off(lambda, target, next - lambda) {
            return Err(SolveError::StepBelowRoundOff {
                at: lambda,
                step: next - lambda,
            });
        }
        st.save_state(&mut saved);
        set(st, next);
        match newton.solve(st) {
            Ok(r) => {
                iterations += r.iterations;
                lambda = next;
                cutbacks = 0;
                step *= 1.5;
            }
            Err(SolveError::Interrupted { at }) => return Err(SolveError::Interrupted { at }),
            Err(e) => {
                st.restore_state(&saved);
                set(st, lambda);
                cutbacks += 1;
                if cutbacks > max_cutbacks || (0.5 * step).abs() < min_step {
                    return Err(e);
                }
                step *= 0.5;
            }
        }
    }
    Ok(iterations)
}

/// Build the steady system of a scene (contact when `[road]` and `[contact]` are given).
pub fn build_steady(scene: &Scene) -> Result<SteadyRolling, AppError> {
    steady_on(scene, build_model(scene)?)
}

/// The scene's steady system on `model`, whose mesh may differ from the scene's (an adaptively
/// refined one).
pub fn steady_on(scene: &Scene, mut model: SolidModel) -> Result<SteadyRolling, AppError> {
    model.strain_rate_damping = scene.time.as_ref().map_or(0.0, |t| t.strain_rate_damping);
    let mut sys = match (&scene.road, &scene.contact) {
        (Some(_), Some(_)) => {
            let mut c = build_contact(scene, &model)?;
            // The steady slip's contact elements before the assembler is built (otherwise
            // `SteadyRolling::new` builds it a second time for them).
            if c.friction.is_active() {
                c.enable_steady_slip(&model.mesh);
            }
            // The assembler once its blocks are final (below).
            SolidSystem::with_contact_deferred(model, c)
        }
        _ => SolidSystem::new(model, "hub"),
    };
    let scheme = match scene.solver.steady_history {
        SteadyHistoryChoice::Auto => StreamlineScheme::Auto,
        SteadyHistoryChoice::Rings => StreamlineScheme::Rings,
        SteadyHistoryChoice::Upwind => StreamlineScheme::Upwind,
    };
    sys.enable_steady_viscoelastic(scheme)
        .map_err(|e| AppError::Unsupported(format!("solver.steady_history: {e}")))?;
    let mut st = SteadyRolling::new(sys, scene.motion.omega, scene.geometry.ro);
    st.sys
        .set_steady_damping_cell_weight(scene.solver.damping_cell_weight);
    match scene.solver.damping_tangent {
        DampingTangentChoice::Assembled => st
            .sys
            .set_steady_damping_tangent(SteadyDampingTangent::Assembled),
        DampingTangentChoice::Banded => st
            .sys
            .set_steady_damping_tangent(SteadyDampingTangent::Banded),
        DampingTangentChoice::Auto if st.sys.n_eq() >= BANDED_MIN_EQUATIONS => st
            .sys
            .set_steady_damping_tangent(SteadyDampingTangent::Banded),
        DampingTangentChoice::Auto | DampingTangentChoice::MatrixFree => {}
    }
    if scene.solver.damping_tangent == DampingTangentChoice::Banded
        && st.sys.steady_damping_tangent() == Some(SteadyDampingTangent::MatrixFree)
    {
        // The three-point ring differences need node rings (a generated annulus).
        let why = "solver.damping_tangent = \"banded\" needs a mesh with node rings (a generated \
                   annulus); this mesh has none, so the matrix-free damping tangent is used"
            .to_string();
        eprintln!("tread: warning: {why}");
        st.damping_fallback = Some(why);
    }
    st.sys.finish_assembly();
    st.plan = solve_plan(scene, &st.sys);
    Ok(st)
}

/// From this many equations on, `[solver] damping_tangent = "auto"` takes the banded damping
/// tangent (three-point ring differences in the matrix) on ring meshes; below, matrix-free.
/// Measured on the damped default scene, one thread: the banded solve took 2.79 s against
/// 3.18 s at 65,536 DOFs and 13.1 s against 25.4 s at 262,144 (GMRES 1–7 products per Newton
/// iteration instead of 4–42), 2.09 s against 1.97 s at 49,152 and 0.31 s against 0.18 s at
/// 8,192 (the wider pattern's set-up and factorization do not pay there); it holds about twice
/// the LU memory.
pub const BANDED_MIN_EQUATIONS: usize = 60_000;

/// Newton at the full load from the current state (an interpolated steady state), without
/// load steps or cutbacks; the load steps and iterations go into `report`.
pub fn press_once(
    scene: &Scene,
    st: &mut SteadyRolling,
    verbose: bool,
    report: &mut StepReport,
    rec: &mut dyn Recorder,
) -> Result<(), SolveError> {
    let plan = st.plan.verbose(verbose);
    let once = StepOptions {
        initial_steps: 1,
        max_cutbacks: 0,
        verbose,
    };
    press(
        st,
        scene_loading(scene),
        plan.kind,
        plan.newton,
        &once,
        report,
        rec,
    )
}
