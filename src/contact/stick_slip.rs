//! The stick–slip oscillator of the paper's §4 ("non-classical friction laws"): a one-degree-of-
//! freedom check of the friction laws of [`super::laws`] against the classical closed form.
//!
//! # Model
//!
//! A block of mass m is tied to a fixed wall by a spring of stiffness k and pressed with a normal
//! force N onto a belt that moves at constant speed v_b > 0. With x the block position (x = 0:
//! spring relaxed; +x is the belt direction), v = ẋ and the slip of the block relative to the belt
//! w = v − v_b (the project's convention w = ẋ1 − v0),
//!
//! m ẍ + k x = F(w),   F(w) = N · t(w),   t = `law.eval(w, 1.0, 0.0).t` = −μ(|w|) φ_ε(w),
//!
//! so F is the friction force on the block and opposes the slip. It is integrated as the
//! first-order system in y = (x, w): ẋ = w + v_b, m ẇ = F(w) − k x, with diffsol's
//! variable-order BDF (the regularised problem is stiff: ∂F/∂w ≈ −μ N/ε in stick). The Jacobian
//! [[0, 1], [−k/m, N t'(w)/m]] is supplied analytically from the law's `d_w`.
//!
//! Why w and not v as unknown: F varies on the velocity scale ε, and in stick |w| = O(ε) ≪ v_b.
//! The integrator's error weight for a velocity unknown v is atol + rtol |v| ≈ rtol v_b, blind
//! to errors of order ε once ε < rtol v_b; for w it is atol_w + rtol |w|, and atol_w is capped
//! at ε/10 ([`W_ATOL_PER_EPS`]). The same caution applies to any implicit integrator of a body
//! with regularised friction: the error control must resolve slip velocities of order ε.
//!
//! Only the Coulomb-type laws (`CoulombTanh`, `CoulombLinear`, `RateDependent`) apply: the
//! compliance-type `OdenMartins` law needs a penetration, which this model does not have, and
//! `None` gives no friction at all; both are rejected with [`StickSlipError::UnsupportedLaw`].
//!
//! # Stick and slip
//!
//! A state is called *stick* when |w| < `stick_threshold` · v_b and *slip* otherwise. With a
//! regularised law "stick" is a slow creep with |w| of a few ε, so the threshold must be well
//! above ε/v_b ([`StickSlipSpec::suggested_stick_threshold`] gives max(0.01, 20 ε/v_b)).
//! Transition times are located to round-off by bisection on diffsol's interpolant inside the
//! step where the phase changes; extrema of x (v = 0) likewise.
//! The measured period is the mean time between successive stick→slip transitions, skipping
//! the first interval (the start-up transient); the amplitude is max x − min x over the last
//! complete cycle (between the last two stick→slip transitions).
//!
//! # Closed form (ε → 0, exact static/kinetic Coulomb law)
//!
//! See [`closed_form_cycle`]. With Ω = √(k/m), d = (μ_s − μ_k) N/k, a = v_b/Ω,
//! A = √(d² + a²), α = atan(a/d) ∈ (0, π/2]:
//!
//! - stick: the block rides the belt (v = v_b) from x = x_k − d to x_s = μ_s N/k = x_k + d,
//!   where the spring force reaches the static limit: t_stick = 2d/v_b;
//! - slip: kinetic friction +μ_k N (w < 0) gives a harmonic arc about x_k = μ_k N/k,
//!   x − x_k = A cos θ, v = −AΩ sin θ, starting at θ = −α (x − x_k = d, v = v_b) and ending
//!   when v returns to v_b at θ = π + α (x − x_k = −d): t_slip = (π + 2α)/Ω;
//! - period T = 2d/v_b + (π + 2α)/Ω, x_max = x_k + A (at θ = 0), x_min = x_k − A (θ = π),
//!   amplitude 2A.
//!
//! Units: any consistent set (mass, length, time); N and k x are forces, v_b a velocity, μ
//! dimensionless.

use std::panic::{catch_unwind, AssertUnwindSafe};

use diffsol::{FaerLU, FaerMat, OdeBuilder, OdeSolverMethod, OdeSolverStopReason, Vector};
use serde::{Deserialize, Serialize};

use super::laws::{Friction, FrictionKind, FrictionLaw, LawError};

/// Hard cap on the number of integrator steps (a guard against step-size collapse).
pub const MAX_STEPS: usize = 5_000_000;

/// Cap of the absolute tolerance on the slip w, as a multiple of the law's ε (see the module
/// docs): atol_w = min(atol, W_ATOL_PER_EPS · ε).
pub const W_ATOL_PER_EPS: f64 = 0.1;

/// Newton convergence failures allowed within one step before the run is abandoned.
pub const NEWTON_FAILS_PER_STEP: usize = 50;

/// Hard cap on the number of output samples.
pub const MAX_SAMPLES: usize = 10_000_000;

/// Errors of the stick–slip oscillator.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StickSlipError {
    /// A parameter of [`StickSlipSpec`] or of the closed form is out of range.
    #[error("stick-slip parameter `{name}` = {value} is invalid: {reason}")]
    InvalidParameter {
        /// Field name.
        name: &'static str,
        /// Offending value.
        value: f64,
        /// What is required.
        reason: &'static str,
    },
    /// The friction law's own parameters are invalid.
    #[error("stick-slip friction law: {0}")]
    Law(#[from] LawError),
    /// The friction law cannot be used here (needs a penetration, or there is no friction).
    #[error(
        "friction law `{0}` is not supported by the stick-slip oscillator (use {list})",
        list = supported_law_list()
    )]
    UnsupportedLaw(&'static str),
    /// diffsol returned an error (step-size collapse, Newton failure, ...).
    #[error("diffsol failed at t = {t}: {message}")]
    Solver {
        /// Last time reached.
        t: f64,
        /// diffsol's message.
        message: String,
    },
    /// diffsol panicked (e.g. a failed factorization); the panic was caught.
    #[error("diffsol panicked: {0}")]
    SolverPanic(String),
    /// The solution became NaN or infinite.
    #[error("non-finite state (x = {x}, v = {v}) at t = {t}")]
    NonFinite {
        /// Time.
        t: f64,
        /// Position.
        x: f64,
        /// Velocity.
        v: f64,
    },
    /// More than [`MAX_STEPS`] steps were needed.
    #[error("step limit of {MAX_STEPS} reached at t = {t}")]
    StepLimit {
        /// Time reached.
        t: f64,
    },
}

/// Input of the stick–slip oscillator (plain data; the scene layer fills it).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StickSlipSpec {
    /// Block mass m > 0.
    pub mass: f64,
    /// Spring stiffness k > 0.
    pub stiffness: f64,
    /// Normal force N ≥ 0 pressing the block onto the belt.
    pub normal_force: f64,
    /// Belt speed v_b > 0.
    pub belt_speed: f64,
    /// End time (> 0; the start time is 0).
    pub t_end: f64,
    /// Relative tolerance of the integrator.
    pub rtol: f64,
    /// Absolute tolerance of the integrator, for x and for w = v − v_b; the latter is capped at
    /// [`W_ATOL_PER_EPS`] · ε.
    pub atol: f64,
    /// Friction law (Coulomb type only).
    pub friction: Friction,
    /// Initial position x(0).
    pub x0: f64,
    /// Initial velocity v(0) (v_b: start stuck to the belt).
    pub v0: f64,
    /// Interval between output samples (> 0).
    pub output_interval: f64,
    /// Stick threshold **relative to v_b** (dimensionless, in (0, 1)): stick when
    /// |w| < threshold · v_b. See [`StickSlipSpec::suggested_stick_threshold`].
    pub stick_threshold: f64,
}

/// Stick or slip (see the module docs for the threshold).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Phase {
    /// |w| < threshold · v_b.
    Stick,
    /// |w| ≥ threshold · v_b.
    Slip,
}

/// One output sample of the time history.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StickSlipSample {
    /// Time.
    pub t: f64,
    /// Block position.
    pub x: f64,
    /// Block velocity.
    pub v: f64,
    /// Friction force on the block F = N t(v − v_b).
    pub friction_force: f64,
    /// Stick or slip.
    pub phase: Phase,
}

/// Work statistics read from diffsol (`OdeSolverMethod::get_statistics`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct SolverStats {
    /// Accepted steps (`number_of_steps`).
    pub steps: usize,
    /// Newton iterations (`number_of_nonlinear_solver_iterations`).
    pub newton_iterations: usize,
    /// Jacobian evaluations + LU factorizations (`number_of_linear_solver_setups`).
    pub factorizations: usize,
    /// Steps rejected by the local error test (`number_of_error_test_failures`).
    pub error_test_failures: usize,
    /// Newton convergence failures (`number_of_nonlinear_solver_fails`).
    pub newton_failures: usize,
}

/// Output of [`simulate`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StickSlipResult {
    /// Time history at the output interval (t = 0, Δ, 2Δ, ... ≤ t_end).
    pub samples: Vec<StickSlipSample>,
    /// Times of the stick→slip transitions.
    pub stick_to_slip: Vec<f64>,
    /// Times of the slip→stick transitions.
    pub slip_to_stick: Vec<f64>,
    /// Mean time between successive stick→slip transitions, skipping the first interval
    /// (None with fewer than three stick→slip transitions).
    pub period: Option<f64>,
    /// max − min of the intervals averaged into `period`.
    pub period_spread: Option<f64>,
    /// Largest x over the last complete cycle.
    pub x_max: Option<f64>,
    /// Smallest x over the last complete cycle.
    pub x_min: Option<f64>,
    /// x_max − x_min over the last complete cycle.
    pub amplitude: Option<f64>,
    /// Duration of the stick phase in the last complete cycle.
    pub stick_time: Option<f64>,
    /// Duration of the slip phase in the last complete cycle.
    pub slip_time: Option<f64>,
    /// diffsol work statistics.
    pub stats: SolverStats,
}

/// The exact limit cycle of the static/kinetic Coulomb law (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ClosedFormCycle {
    /// Period T = t_stick + t_slip.
    pub period: f64,
    /// Stick time 2d/v_b.
    pub stick_time: f64,
    /// Slip time (π + 2α)/Ω.
    pub slip_time: f64,
    /// Largest position x_k + A.
    pub x_max: f64,
    /// Smallest position x_k − A.
    pub x_min: f64,
    /// x_max − x_min = 2A.
    pub amplitude: f64,
}

fn invalid(name: &'static str, value: f64, reason: &'static str) -> StickSlipError {
    StickSlipError::InvalidParameter {
        name,
        value,
        reason,
    }
}

fn require(
    name: &'static str,
    value: f64,
    ok: bool,
    reason: &'static str,
) -> Result<(), StickSlipError> {
    if ok && value.is_finite() {
        Ok(())
    } else {
        Err(invalid(name, value, reason))
    }
}

/// The limit cycle of the block on the belt for the exact static/kinetic Coulomb law
/// (static coefficient μ_s, kinetic μ_k), the ε → 0 limit of the regularised laws.
///
/// Derivation (module docs): stick from x_k − d to x_k + d at v = v_b, then the harmonic slip
/// arc x − x_k = A cos θ, θ ∈ [−α, π + α], with x_k = μ_k N/k, d = (μ_s − μ_k)N/k,
/// A = √(d² + (v_b/Ω)²), tan α = v_b/(Ω d).
///
/// Conditions for this to be the exact cycle:
/// - μ_s ≥ μ_k ≥ 0, N > 0, v_b > 0, m > 0, k > 0 (else an error is returned). With μ_s = μ_k the
///   stick phase shrinks to an instant (d = 0, α = π/2) and the "cycle" is the harmonic orbit
///   that grazes the belt speed, T = 2π/Ω.
/// - Throughout the slip arc w = v − v_b < 0 (|sin θ| < sin α on the parts where v > 0), so the
///   kinetic force keeps its sign, although the block moves backwards (v < 0, |w| > v_b) for
///   θ ∈ (0, π). A law whose coefficient depends on |w| (finite v_s in
///   [`super::laws::RateDependent`]) does not give a constant μ_k along the arc; the formula then
///   holds only up to O(v_s/v_b)-type corrections.
/// - At the end of the arc the block can stick: the spring force k(x_k − d) = (2μ_k − μ_s)N lies
///   within ±μ_s N exactly because 0 ≤ μ_k ≤ μ_s.
/// - The cycle is reached from states that stick at some time (e.g. v(0) = v_b with
///   |k x(0)| ≤ μ_s N). With a rate-independent μ_k the slip motion is conservative, so a
///   block that starts slipping on an orbit about x_k with Ω·√((x−x_k)² + (v/Ω)²) < v_b never
///   sticks and never reaches this cycle; a velocity-weakening law (μ_s > μ_k, finite v_s) pumps
///   energy into such an orbit and reaches it eventually.
pub fn closed_form_cycle(
    mass: f64,
    stiffness: f64,
    normal_force: f64,
    belt_speed: f64,
    mu_s: f64,
    mu_k: f64,
) -> Result<ClosedFormCycle, StickSlipError> {
    require("mass", mass, mass > 0.0, "must be > 0")?;
    require("stiffness", stiffness, stiffness > 0.0, "must be > 0")?;
    require(
        "normal_force",
        normal_force,
        normal_force > 0.0,
        "must be > 0",
    )?;
    require("belt_speed", belt_speed, belt_speed > 0.0, "must be > 0")?;
    require("mu_k", mu_k, mu_k >= 0.0, "must be >= 0")?;
    require("mu_s", mu_s, mu_s >= mu_k, "must be >= mu_k")?;
    let omega = (stiffness / mass).sqrt();
    let x_k = mu_k * normal_force / stiffness;
    let d = (mu_s - mu_k) * normal_force / stiffness;
    let a = belt_speed / omega;
    let amp = d.hypot(a);
    let alpha = a.atan2(d);
    let stick_time = 2.0 * d / belt_speed;
    let slip_time = (std::f64::consts::PI + 2.0 * alpha) / omega;
    Ok(ClosedFormCycle {
        period: stick_time + slip_time,
        stick_time,
        slip_time,
        x_max: x_k + amp,
        x_min: x_k - amp,
        amplitude: 2.0 * amp,
    })
}

/// Whether the oscillator can use friction law `kind`: any law but `None` that does not need a
/// penetration (the block has none).
pub fn supports(kind: FrictionKind) -> bool {
    kind != FrictionKind::None && !kind.needs_penetration() && !kind.steady_only()
}

/// The keywords of the friction laws the oscillator can use, in registration order.
pub fn supported_laws() -> Vec<&'static str> {
    FrictionKind::ALL
        .iter()
        .filter(|k| supports(**k))
        .map(|k| k.as_str())
        .collect()
}

/// [`supported_laws`] as text: `a, b or c`.
pub fn supported_law_list() -> String {
    let names = supported_laws();
    match names.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        Some((last, _)) => last.to_string(),
        None => String::new(),
    }
}

impl StickSlipSpec {
    /// A stick threshold (relative to v_b) suited to `friction`: max(0.01, 20 ε/v_b), at most 0.5.
    ///
    /// A regularised law "sticks" by creeping at |w| of a few ε (up to ≈ 5ε just before
    /// break-away for the tanh laws), so a threshold below that never reports stick.
    pub fn suggested_stick_threshold(friction: &Friction, belt_speed: f64) -> f64 {
        let eps = friction.eps().unwrap_or(0.0);
        (20.0 * eps / belt_speed.abs()).clamp(0.01, 0.5)
    }

    /// Check every parameter (the first offending one is reported).
    pub fn validate(&self) -> Result<(), StickSlipError> {
        const POS: &str = "must be > 0";
        require("mass", self.mass, self.mass > 0.0, POS)?;
        require("stiffness", self.stiffness, self.stiffness > 0.0, POS)?;
        require(
            "normal_force",
            self.normal_force,
            self.normal_force >= 0.0,
            "must be >= 0",
        )?;
        require("belt_speed", self.belt_speed, self.belt_speed > 0.0, POS)?;
        require("t_end", self.t_end, self.t_end > 0.0, POS)?;
        require("rtol", self.rtol, self.rtol > 0.0, POS)?;
        require("atol", self.atol, self.atol > 0.0, POS)?;
        require("x0", self.x0, true, "must be finite")?;
        require("v0", self.v0, true, "must be finite")?;
        require(
            "output_interval",
            self.output_interval,
            self.output_interval > 0.0 && self.t_end / self.output_interval < MAX_SAMPLES as f64,
            "must be > 0 and give fewer than MAX_SAMPLES samples",
        )?;
        require(
            "stick_threshold",
            self.stick_threshold,
            self.stick_threshold > 0.0 && self.stick_threshold < 1.0,
            "must lie in (0, 1)",
        )?;
        if !supports(self.friction.kind()) {
            return Err(StickSlipError::UnsupportedLaw(self.friction.name()));
        }
        self.friction.validate()?;
        Ok(())
    }

    /// Friction force on the block F(v) = N t(v − v_b) and ∂F/∂v.
    #[inline]
    pub fn friction_force(&self, v: f64) -> (f64, f64) {
        let f = self.friction.eval(v - self.belt_speed, 1.0, 0.0);
        (self.normal_force * f.t, self.normal_force * f.d_w)
    }

    fn phase(&self, v: f64) -> Phase {
        if (v - self.belt_speed).abs() < self.stick_threshold * self.belt_speed {
            Phase::Stick
        } else {
            Phase::Slip
        }
    }
}

/// Integrate the oscillator from t = 0 to `spec.t_end` and measure its cycle.
///
/// Never panics: parameters are validated first and any panic inside diffsol is caught and
/// returned as [`StickSlipError::SolverPanic`].
pub fn simulate(spec: &StickSlipSpec) -> Result<StickSlipResult, StickSlipError> {
    spec.validate()?;
    match catch_unwind(AssertUnwindSafe(|| integrate(spec))) {
        Ok(result) => result,
        Err(payload) => {
            let message = if let Some(s) = payload.downcast_ref::<&str>() {
                (*s).to_string()
            } else if let Some(s) = payload.downcast_ref::<String>() {
                s.clone()
            } else {
                "unknown panic payload".to_string()
            };
            Err(StickSlipError::SolverPanic(message))
        }
    }
}

/// Bisection for a sign change of `g` on [a, b] (g(a), g(b) of opposite sign or zero);
/// returns the end of the final bracket on the `b` side.
fn bisect(
    mut a: f64,
    mut b: f64,
    mut ga: f64,
    mut g: impl FnMut(f64) -> Result<f64, StickSlipError>,
) -> Result<f64, StickSlipError> {
    for _ in 0..80 {
        let m = 0.5 * (a + b);
        if m <= a || m >= b || (b - a) <= 1e-15 * b.abs().max(1.0) {
            break;
        }
        let gm = g(m)?;
        if (gm > 0.0) == (ga > 0.0) && gm != 0.0 {
            a = m;
            ga = gm;
        } else {
            b = m;
        }
    }
    Ok(b)
}

fn integrate(spec: &StickSlipSpec) -> Result<StickSlipResult, StickSlipError> {
    let s = *spec;
    let (m, k) = (s.mass, s.stiffness);
    let solver_err = |t: f64, e: diffsol::DiffsolError| StickSlipError::Solver {
        t,
        message: e.to_string(),
    };

    // A 2-state system: the closure builder with an analytic Jacobian-vector product is enough
    // (diffsol forms the dense 2×2 Jacobian from J e_1, J e_2). Unknowns (x, w), not (x, v), with
    // atol_w ≤ ε/10: see the module docs (with v as unknown and rtol = 1e-8 the period was off by
    // 5 % at ε = 1e-8 v_b and by 100 % at ε = 1e-9 v_b).
    let vb = s.belt_speed;
    let atol_w = s
        .atol
        .min(W_ATOL_PER_EPS * s.friction.eps().unwrap_or(f64::INFINITY));
    let problem = OdeBuilder::<FaerMat<f64>>::new()
        .t0(0.0)
        .rtol(s.rtol)
        .atol([s.atol, atol_w])
        .rhs_implicit(
            move |y: &[f64], _p: &[f64], _t: f64, dy: &mut [f64]| {
                let f = s.normal_force * s.friction.eval(y[1], 1.0, 0.0).t;
                dy[0] = y[1] + vb;
                dy[1] = (f - k * y[0]) / m;
            },
            move |y: &[f64], _p: &[f64], _t: f64, v: &[f64], jv: &mut [f64]| {
                let df = s.normal_force * s.friction.eval(y[1], 1.0, 0.0).d_w;
                jv[0] = v[1];
                jv[1] = (df * v[1] - k * v[0]) / m;
            },
        )
        .init(
            move |_p: &[f64], _t: f64, y: &mut [f64]| {
                y[0] = s.x0;
                y[1] = s.v0 - vb;
            },
            2,
        )
        .build()
        .map_err(|e| solver_err(0.0, e))?;
    let mut solver = problem
        .bdf::<FaerLU<f64>>()
        .map_err(|e| solver_err(0.0, e))?;
    solver
        .set_stop_time(s.t_end)
        .map_err(|e| solver_err(0.0, e))?;

    let sample = |t: f64, x: f64, v: f64| StickSlipSample {
        t,
        x,
        v,
        friction_force: s.friction_force(v).0,
        phase: s.phase(v),
    };
    let thr = s.stick_threshold * s.belt_speed;
    let stick_gap = |v: f64| (v - s.belt_speed).abs() - thr; // < 0 in stick

    let n_out = (s.t_end / s.output_interval * (1.0 + 1e-12)).floor() as usize + 1;
    let mut samples = Vec::with_capacity(n_out.min(1 << 20));
    samples.push(sample(0.0, s.x0, s.v0));
    let mut next_out = 1;

    let mut stick_to_slip = Vec::new();
    let mut slip_to_stick = Vec::new();
    // (t, x) at every step end and at every interior extremum of x (v = 0)
    let mut track = vec![(0.0, s.x0)];

    let (mut t_prev, mut v_prev) = (0.0, s.v0);
    let mut phase_prev = s.phase(s.v0);
    let mut steps = 0usize;
    loop {
        let reason = solver.step().map_err(|e| solver_err(t_prev, e))?;
        steps += 1;
        let (t, x, v) = {
            let st = solver.state();
            (st.t, st.y.get_index(0), st.y.get_index(1) + vb)
        };
        if !(x.is_finite() && v.is_finite() && t.is_finite()) {
            return Err(StickSlipError::NonFinite { t, x, v });
        }
        let at = |tau: f64| -> Result<(f64, f64), StickSlipError> {
            let y = solver.interpolate(tau).map_err(|e| solver_err(tau, e))?;
            Ok((y.get_index(0), y.get_index(1) + vb))
        };

        // output samples inside (t_prev, t]
        while next_out < n_out {
            let to = (next_out as f64 * s.output_interval).min(s.t_end);
            if to > t {
                break;
            }
            let (xo, vo) = if to == t { (x, v) } else { at(to)? };
            samples.push(sample(to, xo, vo));
            next_out += 1;
        }

        // phase change inside the step: locate |w| = threshold
        let phase = s.phase(v);
        if phase != phase_prev {
            let tc = bisect(t_prev, t, stick_gap(v_prev), |tau| {
                Ok(stick_gap(at(tau)?.1))
            })?;
            match phase {
                Phase::Slip => stick_to_slip.push(tc),
                Phase::Stick => slip_to_stick.push(tc),
            }
        }
        // extremum of x inside the step: locate v = 0
        if (v_prev > 0.0) != (v > 0.0) && v_prev != 0.0 {
            let te = bisect(t_prev, t, v_prev, |tau| Ok(at(tau)?.1))?;
            track.push((te, at(te)?.0));
        }
        track.push((t, x));

        // diffsol 0.18 compares its *cumulative* count of Newton failures over the whole run
        // with `max_nonlinear_solver_failures` (its error-test limit is per step). Newton
        // failures are routine at the stick/slip transitions of a stiff regularised law, so a
        // long run would abort after 50 of them; moving the limit along restores a per-step one.
        let fails = solver.get_statistics().number_of_nonlinear_solver_fails;
        solver.config_mut().maximum_newton_fails = fails + NEWTON_FAILS_PER_STEP;

        t_prev = t;
        v_prev = v;
        phase_prev = phase;
        if reason == OdeSolverStopReason::TstopReached || t >= s.t_end {
            break;
        }
        if steps >= MAX_STEPS {
            return Err(StickSlipError::StepLimit { t });
        }
    }

    let st = solver.get_statistics();
    let stats = SolverStats {
        steps: st.number_of_steps,
        newton_iterations: st.number_of_nonlinear_solver_iterations,
        factorizations: st.number_of_linear_solver_setups,
        error_test_failures: st.number_of_error_test_failures,
        newton_failures: st.number_of_nonlinear_solver_fails,
    };

    let periods: Vec<f64> = stick_to_slip.windows(2).map(|p| p[1] - p[0]).collect();
    let (period, period_spread) = if periods.len() >= 2 {
        let used = &periods[1..];
        let mean = used.iter().sum::<f64>() / used.len() as f64;
        let hi = used.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let lo = used.iter().cloned().fold(f64::INFINITY, f64::min);
        (Some(mean), Some(hi - lo))
    } else {
        (None, None)
    };

    let (mut x_max, mut x_min, mut stick_time, mut slip_time) = (None, None, None, None);
    if let [.., t0, t1] = stick_to_slip[..] {
        let (lo, hi) = track
            .iter()
            .filter(|(t, _)| *t >= t0 && *t <= t1)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &(_, x)| {
                (lo.min(x), hi.max(x))
            });
        if lo <= hi {
            x_max = Some(hi);
            x_min = Some(lo);
        }
        if let Some(&ts) = slip_to_stick.iter().find(|&&ts| ts > t0 && ts < t1) {
            slip_time = Some(ts - t0);
            stick_time = Some(t1 - ts);
        }
    }
    let amplitude = match (x_max, x_min) {
        (Some(hi), Some(lo)) => Some(hi - lo),
        _ => None,
    };

    Ok(StickSlipResult {
        samples,
        stick_to_slip,
        slip_to_stick,
        period,
        period_spread,
        x_max,
        x_min,
        amplitude,
        stick_time,
        slip_time,
        stats,
    })
}

#[cfg(test)]
mod tests {
    use super::super::laws::{CoulombLinear, CoulombTanh, OdenMartins, RateDependent};
    use super::*;

    const M: f64 = 1.0;
    const K: f64 = 1.0;
    const N: f64 = 1.0;
    const VB: f64 = 0.1;
    const MU_S: f64 = 0.6;
    const MU_K: f64 = 0.4;

    /// Rate-dependent law whose ε → 0 limit is exactly static/kinetic Coulomb:
    /// v_s = √(ε v_b), so both v_s/v_b and ε/v_s vanish like √(ε/v_b).
    fn coulomb_family(eps: f64) -> Friction {
        Friction::RateDependent(RateDependent::new(MU_S, MU_K, (eps * VB).sqrt(), eps))
    }

    fn spec(friction: Friction) -> StickSlipSpec {
        StickSlipSpec {
            mass: M,
            stiffness: K,
            normal_force: N,
            belt_speed: VB,
            t_end: 50.0,
            rtol: 1e-8,
            atol: 1e-10,
            friction,
            x0: 0.0,
            v0: VB,
            output_interval: 0.05,
            stick_threshold: 0.01,
        }
    }

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    #[test]
    fn closed_form_cycle_is_consistent() {
        let c = closed_form_cycle(M, K, N, VB, MU_S, MU_K).unwrap();
        // d = 0.2, a = 0.1, α = atan(0.5)
        let alpha = 0.5f64.atan();
        assert!((c.stick_time - 4.0).abs() < 1e-14);
        assert!((c.slip_time - (std::f64::consts::PI + 2.0 * alpha)).abs() < 1e-14);
        assert!((c.amplitude - 2.0 * 0.05f64.sqrt()).abs() < 1e-14);
        assert!((c.x_max + c.x_min - 2.0 * MU_K * N / K).abs() < 1e-14);
        // the slip arc ends at x_k − d where the cycle's stick phase starts
        let x_end = (2.0 * MU_K - MU_S) * N / K;
        let x_s = MU_S * N / K;
        assert!((c.stick_time * VB - (x_s - x_end)).abs() < 1e-14);
        // equal coefficients: the harmonic orbit grazing v_b
        let h = closed_form_cycle(2.0, 8.0, 1.0, 0.3, 0.5, 0.5).unwrap();
        assert!((h.period - std::f64::consts::PI).abs() < 1e-14);
        assert_eq!(h.stick_time, 0.0);
        assert!(closed_form_cycle(M, K, N, VB, 0.3, 0.4).is_err());
        assert!(closed_form_cycle(M, K, N, -1.0, 0.6, 0.4).is_err());
        assert!(closed_form_cycle(0.0, K, N, VB, 0.6, 0.4).is_err());
    }

    #[test]
    fn matches_closed_form_at_small_eps() {
        let exact = closed_form_cycle(M, K, N, VB, MU_S, MU_K).unwrap();
        let r = simulate(&spec(coulomb_family(1e-6 * VB))).unwrap();
        let period = r.period.unwrap();
        let amp = r.amplitude.unwrap();
        eprintln!(
            "eps = 1e-6 v_b: period {period:.6} (exact {:.6}, err {:.2e}), amplitude {amp:.6} (exact {:.6}, err {:.2e}), stick {:?} slip {:?} (exact {:.4} {:.4}), stats {:?}",
            exact.period,
            rel(period, exact.period),
            exact.amplitude,
            rel(amp, exact.amplitude),
            r.stick_time,
            r.slip_time,
            exact.stick_time,
            exact.slip_time,
            r.stats
        );
        assert!(rel(period, exact.period) < 0.01);
        assert!(rel(amp, exact.amplitude) < 0.01);
        assert!(rel(r.x_max.unwrap(), exact.x_max) < 0.01);
        assert!((r.x_min.unwrap() - exact.x_min).abs() < 0.01 * exact.amplitude);
        assert!(r.period_spread.unwrap() < 1e-3 * period);
        assert!(r.stick_to_slip.len() >= 4);
        // output history: regular grid, stick samples ride the belt, friction bounded by μ_s N
        assert_eq!(r.samples.len(), 1001);
        for (i, smp) in r.samples.iter().enumerate() {
            assert!((smp.t - i as f64 * 0.05).abs() < 1e-9);
            assert!(smp.friction_force.abs() <= MU_S * N * (1.0 + 1e-12));
            if smp.phase == Phase::Stick {
                assert!((smp.v - VB).abs() < 0.01 * VB);
            }
        }
        assert!(r.stats.steps > 0 && r.stats.newton_iterations >= r.stats.steps);
        assert!(r.stats.factorizations > 0);
    }

    #[test]
    fn converges_to_closed_form_as_eps_decreases() {
        let exact = closed_form_cycle(M, K, N, VB, MU_S, MU_K).unwrap();
        let mut rows = Vec::new();
        eprintln!("  eps/v_b    v_s/v_b   period err   amplitude err  steps  newton  factor");
        for e in [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10] {
            let mut sp = spec(coulomb_family(e * VB));
            sp.stick_threshold = StickSlipSpec::suggested_stick_threshold(&sp.friction, VB);
            assert!((sp.stick_threshold - (20.0 * e).max(0.01)).abs() < 1e-15);
            let r = simulate(&sp).unwrap();
            let ep = rel(r.period.unwrap(), exact.period);
            let ea = rel(r.amplitude.unwrap(), exact.amplitude);
            eprintln!(
                "  {e:8.0e}  {:8.1e}   {ep:10.3e}   {ea:12.3e}  {:5}  {:6}  {:6}",
                e.sqrt(),
                r.stats.steps,
                r.stats.newton_iterations,
                r.stats.factorizations
            );
            rows.push((ep, ea));
        }
        for w in rows.windows(2) {
            assert!(w[1].0 < w[0].0, "period error did not decrease: {rows:?}");
            assert!(
                w[1].1 < w[0].1,
                "amplitude error did not decrease: {rows:?}"
            );
        }
        // a factor ≈ √10 per decade of ε (errors O(√(ε/v_b))): at least 10³ over eight decades
        let (first, last) = (rows[0], rows[rows.len() - 1]);
        assert!(
            last.0 < 1e-3 * first.0 && last.1 < 1e-3 * first.1,
            "{rows:?}"
        );
        assert!(last.0 < 1e-4 && last.1 < 1e-4, "{rows:?}");
    }

    #[test]
    fn other_coulomb_laws_run_and_rejections() {
        // constant μ: stick until k x = μ N, then the harmonic orbit about μ N / k that grazes the
        // belt speed (the μ_s = μ_k case of the closed form), slowly damped by the regularisation
        for fr in [
            Friction::CoulombTanh(CoulombTanh::new(0.5, 1e-4)),
            Friction::CoulombLinear(CoulombLinear::new(0.5, 1e-4)),
        ] {
            let mut sp = spec(fr);
            sp.t_end = 20.0;
            let r = simulate(&sp).unwrap();
            assert!(!r.stick_to_slip.is_empty(), "{fr:?}");
            // k x reaches μ N at t = 5; |w| then needs a little time to grow to the threshold
            // (≈ √(2 · 0.01 v_b m/(k v_b)) ≈ 0.14 without the regularisation's creep)
            let t_break = r.stick_to_slip[0];
            assert!(t_break > 5.0 && t_break < 5.2, "{:?}", r.stick_to_slip);
            // then a harmonic orbit about μ N/k grazing v_b: back near v_b every 2π/Ω
            for p in r.stick_to_slip.windows(2) {
                assert!((p[1] - p[0] - 2.0 * std::f64::consts::PI).abs() < 0.05);
            }
            for s in &r.samples {
                assert!(s.x.is_finite() && s.v.is_finite());
                assert!(s.friction_force.abs() <= 0.5 * N * (1.0 + 1e-12));
                assert!(s.v <= VB * (1.0 + 1e-6));
            }
        }
        let mut sp = spec(Friction::OdenMartins(OdenMartins::new(1.0, 1.0, 1e-3)));
        assert_eq!(
            simulate(&sp).unwrap_err(),
            StickSlipError::UnsupportedLaw("oden_martins")
        );
        sp.friction = Friction::None;
        assert!(matches!(
            simulate(&sp),
            Err(StickSlipError::UnsupportedLaw("none"))
        ));
        let mut sp = spec(coulomb_family(1e-3));
        sp.mass = -1.0;
        assert!(matches!(
            simulate(&sp),
            Err(StickSlipError::InvalidParameter { name: "mass", .. })
        ));
        let mut sp = spec(coulomb_family(1e-3));
        sp.friction = Friction::RateDependent(RateDependent::new(0.6, 0.4, 0.0, 1e-3));
        assert!(matches!(simulate(&sp), Err(StickSlipError::Law(_))));
        let mut sp = spec(coulomb_family(1e-3));
        sp.rtol = f64::NAN;
        assert!(simulate(&sp).is_err());
    }

    #[test]
    fn solver_failure_is_an_error_not_a_panic() {
        // absurd tolerances force a step-size collapse; must come back as an error
        let mut sp = spec(coulomb_family(1e-10 * VB));
        sp.rtol = 1e-300;
        sp.atol = 1e-300;
        sp.t_end = 1.0;
        match simulate(&sp) {
            Err(StickSlipError::Solver { .. }) | Err(StickSlipError::SolverPanic(_)) => {}
            Err(e) => panic!("unexpected error {e}"),
            Ok(r) => panic!("unexpected success {:?}", r.stats),
        }
    }

    #[test]
    fn friction_force_derivative_is_consistent() {
        // the Jacobian entry N t'(w) handed to diffsol, against central differences
        for e in [1e-2, 1e-4, 1e-6] {
            let sp = spec(coulomb_family(e * VB));
            for v in [VB, VB * (1.0 - 1e-7), VB * (1.0 + 3e-7), 0.0, -0.3, 0.5] {
                let (_, df) = sp.friction_force(v);
                let h = 1e-4 * e * VB;
                let fd = (sp.friction_force(v + h).0 - sp.friction_force(v - h).0) / (2.0 * h);
                assert!(
                    (df - fd).abs() <= 1e-5 * df.abs() + 1e-9,
                    "eps {e} v {v}: {df} vs {fd}"
                );
            }
        }
    }

    #[test]
    fn loose_tolerance_still_resolves_tiny_eps() {
        // ε = 1e-8 v_b with rtol = 1e-6 ≫ ε/v_b: only possible because the unknown is w, with
        // atol_w ≤ ε/10 (with v as unknown this gave a 24 % period error)
        let exact = closed_form_cycle(M, K, N, VB, MU_S, MU_K).unwrap();
        let mut sp = spec(coulomb_family(1e-8 * VB));
        sp.rtol = 1e-6;
        sp.atol = 1e-8;
        let r = simulate(&sp).unwrap();
        let (ep, ea) = (
            rel(r.period.unwrap(), exact.period),
            rel(r.amplitude.unwrap(), exact.amplitude),
        );
        eprintln!("eps = 1e-8 v_b, rtol = 1e-6: period err {ep:.2e}, amplitude err {ea:.2e}");
        assert!(ep < 1e-3 && ea < 1e-3);
    }
}
