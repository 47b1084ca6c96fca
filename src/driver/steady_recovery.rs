//! Recovery of a failed steady solve: when pressing the road in at the scene's ω (load stepping
//! with cut-back, [`super::steady::press`]) fails, the steady mode does not give up at once but
//! tries homotopies that start from a benign version of the scene and walk one parameter at a
//! time to the scene's value, each step a Newton solve from the previous solution.
//!
//! # Why
//!
//! The press-in path at a fixed ω is a path in the penetration, not in ω: near the critical
//! speed it is not monotone (ω = 38 rad/s fails on `oden_hollow_cylinder` where 30 and 42 work),
//! although the branch in ω through the same point is regular. A stiff volumetric response
//! (κ/G ≥ 1e4) or a small friction regularisation (ε ≤ 1e-5 v0 near free rolling, where a stick
//! zone forms) makes the Newton basin of the press steps too small. In each case the solution
//! exists and is reachable along another path.
//!
//! # Strategies (tried in this order, each only when it applies)
//!
//! | strategy          | benign start                     | leg(s) to the scene's value        | applies when          |
//! |-------------------|----------------------------------|------------------------------------|-----------------------|
//! | `kappa_homotopy`  | κ_b = 100 G                      | κ: κ_b → κ, geometric steps        | κ > κ_b               |
//! | `eps_homotopy`    | ε_b = 1e-3 v_ref                 | ε: ε_b → ε, geometric steps        | friction on, ε < ε_b  |
//! | `omega_stepping`  | ω = 0 (and v0 = 0)               | ω: 0 → ω, v0 = (v0/ω) ω, linear    | ω ≠ 0                 |
//! | `combined`        | all of the above that apply      | κ, then ω, then ε                  | two or more apply     |
//!
//! G is the small-strain shear modulus, v_ref = max(|v0|, |ω| Ro). κ is the bulk modulus of the
//! compressible Mooney–Rivlin law or the penalty κ of the perturbed incompressible one (the
//! neo-Hookean λ is not walked). Every attempt starts from the undeformed state: the road is
//! pressed in (same load stepping as the direct solve) at the benign values, then each leg
//! walks its homotopy coordinate s ∈ [0, 1] (value = from + s (to − from), or
//! from (to/from)^s for geometric steps): initial Δs = 1/4, ×1.5 after a solve in ≤ 4
//! iterations, halved after a failure (at most `[solver] max_cutbacks` times in a row); the
//! predictor is the secant through the last two solutions (a failed secant predictor is
//! retried once from the last solution before Δs is halved). The last step lands exactly on
//! the scene's value, so the recovered state solves the scene's equations to the scene's
//! tolerance: it is the same solution a successful direct solve would give (when the branch
//! is unique there).
//!
//! The ε leg is also used before any failure: a scene whose ε is below
//! [`EPS_CONTINUATION_OVER_V`] · v_ref is pressed in at that ε and walked down to its own
//! ([`continue_in_eps`], `summary.json`: `solver.eps_continuation`; `[solver] eps_continuation
//! = false` turns it off). Only if that fails does the direct press-in, and then this recovery,
//! follow.
//!
//! An attempt that fails restores the scene's parameters; when every attempt fails the state
//! is put back where the direct solve left it and the direct solve's error stands. What
//! happened is returned as a [`Recovery`] (the steady driver writes it to `summary.json` as
//! `solver.recovery` and prints one line to stderr).

use super::steady::{press, SteadyRolling};
pub use super::steady_report::{
    Attempt, HomotopyParameter, LegReport, Recovery, Spacing, Strategy,
};
use crate::io::record::{self, Recorder};
use crate::model::system::Loading;
use crate::physics::PressureMode;
use crate::solver::stepping::{StepOptions, StepReport};
use crate::solver::{LinearKind, Newton, NewtonOptions, NonlinearSystem, SolveError};
use std::time::Instant;

/// κ_b / G: the bulk modulus the κ-homotopy starts from (the scenes' nearly incompressible
/// κ/G = 100 presses in without trouble).
pub const KAPPA_BENIGN_OVER_G: f64 = 100.0;
/// ε_b / v_ref: the regularisation the ε-homotopy starts from.
pub const EPS_BENIGN_OVER_V: f64 = 1e-3;
/// ε_c / v_ref: a scene whose friction regularisation ε is below ε_c is not pressed in at its
/// ε but at ε_c, and ε is then walked down to the scene's value ([`continue_in_eps`]).
pub const EPS_CONTINUATION_OVER_V: f64 = 1e-2;
/// Initial homotopy step Δs of a leg.
const DS0: f64 = 0.25;
/// Smallest Δs before a leg gives up.
const DS_MIN: f64 = 1e-6;
/// Steps per leg before it gives up.
const MAX_LEG_STEPS: usize = 400;

/// One homotopy leg: `parameter` from `from` to `to`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Leg {
    pub parameter: HomotopyParameter,
    pub from: f64,
    pub to: f64,
    pub spacing: Spacing,
}

impl Leg {
    /// The parameter value at homotopy coordinate `s` ∈ [0, 1] (exactly `to` at s = 1).
    pub fn value(&self, s: f64) -> f64 {
        if s >= 1.0 {
            return self.to;
        }
        match self.spacing {
            Spacing::Linear => self.from + s * (self.to - self.from),
            Spacing::Geometric => self.from * (self.to / self.from).powf(s),
        }
    }
}

/// The scene's values of the parameters a homotopy can walk, captured before any change.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Targets {
    pub omega: f64,
    pub v0: f64,
    /// κ when the material has one that [`HomotopyParameter::Kappa`] walks.
    pub kappa: Option<f64>,
    /// ε when friction is active.
    pub eps: Option<f64>,
    /// Small-strain shear modulus G.
    pub shear_modulus: f64,
    pub ro: f64,
}

impl Targets {
    pub fn of(st: &SteadyRolling) -> Self {
        let eps = st
            .sys
            .contact
            .as_ref()
            .filter(|c| c.friction.is_active())
            .and_then(|c| c.friction.eps());
        Self {
            omega: st.omega_signed(),
            v0: st.v0(),
            kappa: kappa_of(st),
            eps,
            shear_modulus: st.sys.model.material.small_strain_shear_modulus(),
            ro: st.ro,
        }
    }

    /// The strategies that apply, in the order they are tried, with their legs.
    pub fn strategies(&self) -> Vec<(Strategy, Vec<Leg>)> {
        let kappa_leg = self.kappa.and_then(|k| {
            let kb = KAPPA_BENIGN_OVER_G * self.shear_modulus;
            (kb > 0.0 && k > kb).then_some(Leg {
                parameter: HomotopyParameter::Kappa,
                from: kb,
                to: k,
                spacing: Spacing::Geometric,
            })
        });
        let v_ref = self.v0.abs().max(self.omega.abs() * self.ro);
        let eps_leg = self.eps.and_then(|e| {
            let eb = EPS_BENIGN_OVER_V * v_ref;
            (e > 0.0 && e < eb).then_some(Leg {
                parameter: HomotopyParameter::Eps,
                from: eb,
                to: e,
                spacing: Spacing::Geometric,
            })
        });
        let omega_leg = (self.omega != 0.0).then_some(Leg {
            parameter: HomotopyParameter::Omega,
            from: 0.0,
            to: self.omega,
            spacing: Spacing::Linear,
        });
        let mut out = Vec::new();
        if let Some(l) = kappa_leg {
            out.push((Strategy::KappaHomotopy, vec![l]));
        }
        if let Some(l) = eps_leg {
            out.push((Strategy::EpsHomotopy, vec![l]));
        }
        if let Some(l) = omega_leg {
            out.push((Strategy::OmegaStepping, vec![l]));
        }
        // κ first (at ω = 0 it is a static problem), then ω, then ε (friction only acts once
        // the body rolls).
        let all: Vec<Leg> = [kappa_leg, omega_leg, eps_leg]
            .into_iter()
            .flatten()
            .collect();
        if all.len() >= 2 {
            out.push((Strategy::Combined, all));
        }
        out
    }
}

fn kappa_of(st: &SteadyRolling) -> Option<f64> {
    match (st.sys.model.pressure, st.sys.model.material) {
        (PressureMode::Perturbed { kappa, .. }, _) => Some(kappa),
        (PressureMode::None, m) => m.param("kappa"),
        _ => None,
    }
}

/// Set one parameter of `st` (ω also sets v0 = (v0/ω)_scene · ω, exactly the scene's v0 at the
/// scene's ω).
pub fn set_parameter(st: &mut SteadyRolling, t: &Targets, p: HomotopyParameter, value: f64) {
    match p {
        HomotopyParameter::Omega => {
            let v0 = if value == t.omega {
                t.v0
            } else if t.omega != 0.0 {
                t.v0 / t.omega * value
            } else {
                t.v0
            };
            st.set_omega(value, v0);
        }
        HomotopyParameter::Kappa => {
            if let PressureMode::Perturbed { kappa, .. } = &mut st.sys.model.pressure {
                *kappa = value;
            } else {
                st.sys.model.material.set_param("kappa", value);
            }
        }
        HomotopyParameter::Eps => {
            if let Some(c) = &mut st.sys.contact {
                c.friction.set_eps(value);
            }
        }
    }
}

/// Put every walkable parameter back to the scene's value.
pub fn restore_targets(st: &mut SteadyRolling, t: &Targets) {
    set_parameter(st, t, HomotopyParameter::Omega, t.omega);
    if let Some(k) = t.kappa {
        set_parameter(st, t, HomotopyParameter::Kappa, k);
    }
    if let Some(e) = t.eps {
        set_parameter(st, t, HomotopyParameter::Eps, e);
    }
}

/// Try the strategies of [`Targets::strategies`] after the direct solve failed with
/// `direct_error`. `x_init` is the state the direct solve started from. On success the state
/// of `st` is the steady solution at the scene's parameters; otherwise it is restored to what
/// the direct solve left. The counts of the attempts are added to `report` (iterations,
/// cut-backs). Only an interrupt (Ctrl-C) is returned as an error.
#[allow(clippy::too_many_arguments)]
pub fn recover(
    st: &mut SteadyRolling,
    loading: Loading,
    kind: LinearKind,
    newton_opts: &NewtonOptions,
    step_opts: &StepOptions,
    x_init: &[f64],
    direct_error: &SolveError,
    report: &mut StepReport,
    log: &mut dyn Recorder,
) -> Result<Recovery, SolveError> {
    let t0 = Instant::now();
    let targets = Targets::of(st);
    let mut x_fail = Vec::new();
    st.sys.save_state(&mut x_fail);
    let mut rec = Recovery {
        direct_error: direct_error.to_string(),
        strategy: None,
        attempts: Vec::new(),
        newton_iterations: 0,
        cutbacks: 0,
        wall_time_s: 0.0,
        message: String::new(),
    };
    for (strategy, legs) in targets.strategies() {
        if step_opts.verbose {
            eprintln!("  steady recovery: trying {strategy}");
        }
        log.note(&format!("steady recovery: trying {strategy}"));
        let res = attempt(
            st,
            &targets,
            strategy,
            &legs,
            loading,
            kind,
            newton_opts,
            step_opts,
            x_init,
            log,
        );
        let a = match res {
            Ok(a) | Err(AttemptError::Failed(a)) => a,
            Err(AttemptError::Interrupted(at)) => {
                st.sys.restore_state(&x_fail);
                restore_targets(st, &targets);
                return Err(SolveError::Interrupted { at });
            }
        };
        rec.newton_iterations += a.newton_iterations;
        rec.cutbacks += a.cutbacks();
        report.total_iterations += a.newton_iterations;
        report.cutbacks += a.cutbacks();
        let ok = a.succeeded;
        log.note(&format!(
            "steady recovery: {strategy} {} ({} Newton iterations)",
            if ok { "succeeded" } else { "failed" },
            a.newton_iterations
        ));
        rec.attempts.push(a);
        if ok {
            rec.strategy = Some(strategy);
            break;
        }
        restore_targets(st, &targets);
    }
    if !rec.succeeded() {
        st.sys.restore_state(&x_fail);
        st.sys.x_prev.copy_from_slice(&x_fail);
        restore_targets(st, &targets);
        // Leave the system evaluated at the restored state (reactions, samples).
        st.sys.evaluate(false);
    }
    rec.wall_time_s = t0.elapsed().as_secs_f64();
    rec.message = rec.describe();
    Ok(rec)
}

/// The ε continuation a scene's steady solve starts with, if it needs one: from
/// ε_c = [`EPS_CONTINUATION_OVER_V`] · v_ref down to the scene's ε, geometric steps.
///
/// Why: in the stick zone the regularised law t_T = −μ t_n tanh(w/ε) turns the slip w into a
/// stiff function of the traction (∂t_T/∂w ∝ 1/ε), and Newton converges only from slips
/// within a few ε of the solution. The press-in starts from the undeformed state, where the
/// slip of a rolling body is of the order of the rolling speed, so at ε = 1e-4 v0 it needs
/// hundreds of line-searched iterations and cut-backs. Along a geometric path in ε the stick
/// zone's slip shrinks with ε, each step starts a few ε_k from its solution, and a step takes a
/// few quadratic iterations (the secant predictor extrapolates the slip profile).
pub fn eps_continuation_leg(t: &Targets) -> Option<Leg> {
    let v_ref = t.v0.abs().max(t.omega.abs() * t.ro);
    let e = t.eps?;
    let ec = EPS_CONTINUATION_OVER_V * v_ref;
    (e > 0.0 && e < ec && ec.is_finite()).then_some(Leg {
        parameter: HomotopyParameter::Eps,
        from: ec,
        to: e,
        spacing: Spacing::Geometric,
    })
}

/// Press in at the start of `leg` (an ε continuation, [`eps_continuation_leg`]) and walk it to
/// the scene's ε. On success the state is the steady solution at the scene's parameters. On
/// failure (returned as `Ok` with `succeeded = false`) the parameters are the scene's again
/// and the state is `x_init`, so the caller can press in directly. Only an interrupt (Ctrl-C)
/// is an error.
#[allow(clippy::too_many_arguments)]
pub fn continue_in_eps(
    st: &mut SteadyRolling,
    leg: &Leg,
    loading: Loading,
    kind: LinearKind,
    newton_opts: &NewtonOptions,
    step_opts: &StepOptions,
    x_init: &[f64],
    report: &mut StepReport,
    log: &mut dyn Recorder,
) -> Result<Attempt, SolveError> {
    let targets = Targets::of(st);
    log.note(&format!(
        "friction eps continuation from {:.6e} to {:.6e}",
        leg.from, leg.to
    ));
    let res = attempt(
        st,
        &targets,
        Strategy::EpsHomotopy,
        std::slice::from_ref(leg),
        loading,
        kind,
        newton_opts,
        step_opts,
        x_init,
        log,
    );
    let a = match res {
        Ok(a) | Err(AttemptError::Failed(a)) => a,
        Err(AttemptError::Interrupted(at)) => {
            restore_targets(st, &targets);
            return Err(SolveError::Interrupted { at });
        }
    };
    report.total_iterations += a.newton_iterations;
    report.cutbacks += a.cutbacks();
    if !a.succeeded {
        restore_targets(st, &targets);
        st.sys.restore_state(x_init);
        st.sys.x_prev.copy_from_slice(x_init);
        st.sys.lambda = 0.0;
        st.sys.lambda_prev = 0.0;
    }
    Ok(a)
}

enum AttemptError {
    /// The attempt failed (its report says where).
    Failed(Attempt),
    /// Ctrl-C at the given homotopy coordinate or load factor.
    Interrupted(f64),
}

#[allow(clippy::too_many_arguments)]
fn attempt(
    st: &mut SteadyRolling,
    t: &Targets,
    strategy: Strategy,
    legs: &[Leg],
    loading: Loading,
    kind: LinearKind,
    newton_opts: &NewtonOptions,
    step_opts: &StepOptions,
    x_init: &[f64],
    log: &mut dyn Recorder,
) -> Result<Attempt, AttemptError> {
    let t0 = Instant::now();
    let mut a = Attempt {
        strategy,
        succeeded: false,
        error: None,
        press_steps: 0,
        press_cutbacks: 0,
        legs: Vec::new(),
        newton_iterations: 0,
        wall_time_s: 0.0,
    };
    st.sys.restore_state(x_init);
    st.sys.x_prev.copy_from_slice(x_init);
    st.sys.lambda = 0.0;
    st.sys.lambda_prev = 0.0;
    for l in legs {
        set_parameter(st, t, l.parameter, l.from);
    }
    let mut prep = StepReport::default();
    let pressed = press(
        st,
        loading,
        kind,
        newton_opts.clone(),
        step_opts,
        &mut prep,
        &mut (),
    );
    a.press_steps = prep.steps.iter().filter(|s| s.converged).count();
    a.press_cutbacks = prep.cutbacks;
    a.newton_iterations += prep.total_iterations;
    match pressed {
        Ok(()) => {}
        Err(SolveError::Interrupted { at }) => return Err(AttemptError::Interrupted(at)),
        Err(e) => {
            a.error = Some(format!("press at the benign values: {e}"));
            a.wall_time_s = t0.elapsed().as_secs_f64();
            return Err(AttemptError::Failed(a));
        }
    }
    let mut newton = match Newton::new(st, LinearKind::Lu, newton_opts.clone()) {
        Ok(n) => n,
        Err(e) => {
            a.error = Some(e.to_string());
            return Err(AttemptError::Failed(a));
        }
    };
    for leg in legs {
        let (lr, err) = walk(st, t, leg, &mut newton, step_opts, log)?;
        a.newton_iterations += lr.newton_iterations;
        a.legs.push(lr);
        if let Some(e) = err {
            a.error = Some(e);
            a.wall_time_s = t0.elapsed().as_secs_f64();
            return Err(AttemptError::Failed(a));
        }
    }
    a.succeeded = true;
    a.wall_time_s = t0.elapsed().as_secs_f64();
    Ok(a)
}

/// Walk one leg from s = 0 (the current, converged state) to s = 1. Returns the leg's report
/// and, when it gave up, why (the state is then the last converged one).
fn walk(
    st: &mut SteadyRolling,
    t: &Targets,
    leg: &Leg,
    newton: &mut Newton,
    step_opts: &StepOptions,
    log: &mut dyn Recorder,
) -> Result<(LegReport, Option<String>), AttemptError> {
    let mut lr = LegReport {
        parameter: leg.parameter,
        spacing: leg.spacing,
        from: leg.from,
        to: leg.to,
        steps: 0,
        cutbacks: 0,
        newton_iterations: 0,
        reached: leg.from,
    };
    let (mut s, mut ds) = (0.0f64, DS0);
    let mut x_k = Vec::new();
    st.sys.save_state(&mut x_k);
    let mut x_km1 = x_k.clone();
    let mut s_km1 = f64::NAN;
    let mut secant = true;
    let mut in_a_row = 0;
    while s < 1.0 {
        if record::interrupted() {
            st.sys.restore_state(&x_k);
            set_parameter(st, t, leg.parameter, leg.value(s));
            return Err(AttemptError::Interrupted(s));
        }
        if lr.steps >= MAX_LEG_STEPS {
            return Ok((
                lr,
                Some(format!(
                    "{} leg: {MAX_LEG_STEPS} steps without reaching {:.6e} (at {:.6e})",
                    leg.parameter,
                    leg.to,
                    leg.value(s)
                )),
            ));
        }
        let ds_try = ds.min(1.0 - s);
        let s_new = if ds_try >= 1.0 - s { 1.0 } else { s + ds_try };
        st.sys.restore_state(&x_k);
        let use_secant = secant && s_km1.is_finite();
        if use_secant {
            // Secant predictor through the last two solutions (linear in s).
            let r = (s_new - s) / (s - s_km1);
            for ((x, a), b) in st.sys.x.iter_mut().zip(&x_k).zip(&x_km1) {
                *x = a + r * (a - b);
            }
        }
        let value = leg.value(s_new);
        set_parameter(st, t, leg.parameter, value);
        if step_opts.verbose {
            eprintln!(
                "  steady recovery: {} = {value:.6e} (s = {s_new:.4}{})",
                leg.parameter,
                if use_secant { ", secant predictor" } else { "" }
            );
        }
        match newton.solve(st) {
            Ok(r) => {
                log.note(&format!(
                    "steady recovery: {} = {} reached ({} Newton iterations)",
                    leg.parameter,
                    crate::io::output::fmt_num(value),
                    r.iterations
                ));
                lr.newton_iterations += r.iterations;
                lr.steps += 1;
                lr.reached = value;
                std::mem::swap(&mut x_km1, &mut x_k);
                st.sys.save_state(&mut x_k);
                s_km1 = s;
                s = s_new;
                secant = true;
                in_a_row = 0;
                if r.iterations <= 4 {
                    ds *= 1.5;
                }
            }
            Err(e) => {
                if use_secant {
                    // Retry the same step from the last solution before cutting it.
                    secant = false;
                    continue;
                }
                secant = true;
                lr.cutbacks += 1;
                in_a_row += 1;
                ds = 0.5 * ds_try;
                if in_a_row > step_opts.max_cutbacks || ds < DS_MIN {
                    st.sys.restore_state(&x_k);
                    set_parameter(st, t, leg.parameter, leg.value(s));
                    let why = if ds < DS_MIN {
                        // Steps shrank to nothing while the ones before converged: the branch
                        // ends here (a fold, e.g. where a contact point's traction jumps).
                        format!(
                            "no solution found beyond it (steps down to Δs = {DS_MIN:e} failed)"
                        )
                    } else {
                        format!("{in_a_row} cut-backs in a row")
                    };
                    return Ok((
                        lr,
                        Some(format!(
                            "{} leg stopped at {:.8e} on the way from {:.6e} to {:.6e}, {why}; \
                             last failure: {e}",
                            leg.parameter,
                            leg.value(s),
                            leg.from,
                            leg.to
                        )),
                    ));
                }
            }
        }
    }
    Ok((lr, None))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn targets(omega: f64, kappa: Option<f64>, eps: Option<f64>) -> Targets {
        Targets {
            omega,
            v0: omega * 1.9,
            kappa,
            eps,
            shear_modulus: 200.0,
            ro: 2.0,
        }
    }

    #[test]
    fn strategies_apply_only_where_the_scene_is_stiff() {
        let names =
            |t: &Targets| -> Vec<Strategy> { t.strategies().into_iter().map(|(s, _)| s).collect() };
        // The benign scene (κ = 100 G, ε = 0.7 % v0): only ω stepping.
        let t = targets(38.0, Some(2e4), Some(0.5));
        assert_eq!(names(&t), vec![Strategy::OmegaStepping]);
        // Static scene (ω = 0) with a benign material: nothing applies.
        assert!(names(&targets(0.0, Some(2e4), None)).is_empty());
        // Stiff κ and small ε: each alone, then ω, then all three combined.
        let t = targets(10.0, Some(2e6), Some(1e-5));
        assert_eq!(
            names(&t),
            vec![
                Strategy::KappaHomotopy,
                Strategy::EpsHomotopy,
                Strategy::OmegaStepping,
                Strategy::Combined
            ]
        );
        let comb = &t.strategies()[3].1;
        let order: Vec<HomotopyParameter> = comb.iter().map(|l| l.parameter).collect();
        assert_eq!(
            order,
            vec![
                HomotopyParameter::Kappa,
                HomotopyParameter::Omega,
                HomotopyParameter::Eps
            ]
        );
        assert_eq!(comb[0].from, 100.0 * 200.0);
        // v_ref = max(|v0|, |ω| Ro) = 20
        assert!((comb[2].from - 1e-3 * 20.0).abs() < 1e-15);
    }

    #[test]
    fn legs_end_exactly_on_the_target() {
        let g = Leg {
            parameter: HomotopyParameter::Kappa,
            from: 2e4,
            to: 2e8,
            spacing: Spacing::Geometric,
        };
        assert_eq!(g.value(0.0), 2e4);
        assert!((g.value(0.5) - 2e6).abs() < 1e-6);
        assert_eq!(g.value(1.0), 2e8);
        let l = Leg {
            parameter: HomotopyParameter::Omega,
            from: 0.0,
            to: 38.0,
            spacing: Spacing::Linear,
        };
        assert_eq!(l.value(0.25), 9.5);
        assert_eq!(l.value(1.0), 38.0);
    }
}
