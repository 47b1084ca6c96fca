//! The steady mode's first solve and its rolling control: from the undeformed state (or a
//! coarser mesh's steady state, [`steady_nested`]) to the steady state at the scene's ω, v0 and
//! road, with the ε continuation, the damping-tangent fallback and the recovery homotopies of
//! [`steady_recovery`] when the direct press fails; then the torque, free-rolling or creep
//! control of `motion.control` ([`apply_control`]).

use super::results::ControlReport;
use super::spinning;
use super::steady::{press, solve_torque, step_parameter_with, RoadSpeedSystem, SteadyRolling};
use super::steady_nested::{self, CoarseSolved};
use super::steady_recovery;
use super::steady_report::{SolveReports, SteadyFailure};
use crate::io::record::Recorder;
use crate::io::scene::{Control, DampingTangentChoice, Scene};
use crate::model::SteadyDampingTangent;
use crate::setup::scene_loading;
use crate::solver::stepping::StepReport;
use crate::solver::{LinearKind, Newton, NonlinearSystem, SolveError};

/// Solve the steady state at the scene's ω and v0 (pressing stage). `report` collects the
/// load steps. The nested iteration's coarse start, the ε continuation and, when the press
/// fails, the recovery strategies of [`steady_recovery`] are tried in turn; what they did is
/// returned (with the press's error when all failed).
pub fn solve_steady(
    scene: &Scene,
    st: &mut SteadyRolling,
    verbose: bool,
    report: &mut StepReport,
    rec: &mut dyn Recorder,
) -> Result<SolveReports, SteadyFailure> {
    solve_steady_from(scene, st, None, verbose, report, rec)
}

/// [`solve_steady`], with the coarser mesh's steady state solved ahead
/// ([`steady_nested::build_steady_nested`]) when there is one.
pub fn solve_steady_from(
    scene: &Scene,
    st: &mut SteadyRolling,
    ahead: Option<CoarseSolved>,
    verbose: bool,
    report: &mut StepReport,
    rec: &mut dyn Recorder,
) -> Result<SolveReports, SteadyFailure> {
    let mut reports = SolveReports {
        damping_fallback: st.damping_fallback.clone(),
        ..Default::default()
    };
    match first_solve(scene, st, ahead, verbose, report, rec, &mut reports) {
        Ok(()) => Ok(reports),
        Err(error) => Err(SteadyFailure {
            error,
            reports: Box::new(reports),
        }),
    }
}

#[allow(clippy::too_many_arguments)]
fn first_solve(
    scene: &Scene,
    st: &mut SteadyRolling,
    ahead: Option<CoarseSolved>,
    verbose: bool,
    report: &mut StepReport,
    rec: &mut dyn Recorder,
    reports: &mut SolveReports,
) -> Result<(), SolveError> {
    let plan = st.plan.verbose(verbose);
    let (kind, newton_opts, step_opts) = (plan.kind, plan.newton, plan.steps);
    if st.sys.contact.is_none() {
        // No contact: the steady problem is steady spinning.
        return spinning::solve_spinning(
            &mut st.sys,
            scene.motion.omega,
            kind,
            newton_opts,
            &step_opts,
            report,
            rec,
        );
    }
    let loading = scene_loading(scene);
    let mut x_init = Vec::new();
    st.sys.save_state(&mut x_init);
    if let Some(cs) =
        steady_nested::coarse_start(scene, st, ahead, solve_steady_from, verbose, report, rec)?
    {
        let ok = cs.succeeded;
        reports.coarse_start = Some(cs);
        if ok {
            return Ok(());
        }
        st.sys.restore_state(&x_init);
    }
    let eps_leg = steady_recovery::eps_continuation_leg(&steady_recovery::Targets::of(st))
        .filter(|_| scene.solver.eps_continuation);
    if let Some(leg) = eps_leg {
        let a = steady_recovery::continue_in_eps(
            st,
            &leg,
            loading,
            kind,
            &newton_opts,
            &step_opts,
            &x_init,
            report,
            rec,
        )?;
        let ok = a.succeeded;
        if verbose {
            eprintln!(
                "  friction eps continuation {:.3e} -> {:.3e}: {} ({} Newton iterations)",
                leg.from,
                leg.to,
                if ok {
                    "reached"
                } else {
                    "failed, pressing in directly"
                },
                a.newton_iterations
            );
        }
        reports.eps_continuation = Some(a);
        if ok {
            return Ok(());
        }
    }
    let mut first = press(
        st,
        loading,
        kind,
        newton_opts.clone(),
        &step_opts,
        report,
        rec,
    );
    if let Err(e) = &first {
        if !matches!(e, SolveError::Interrupted { .. })
            && matches!(
                st.sys.steady_damping_tangent(),
                Some(SteadyDampingTangent::MatrixFree | SteadyDampingTangent::Banded)
            )
            && scene.solver.damping_tangent == DampingTangentChoice::Auto
        {
            // The matrix-free and banded damping tangents are the fast paths; the assembled
            // one is the robust one. Try it before any homotopy.
            let why = format!(
                "the press with the {} damping tangent failed ({e}); solved again with the \
                 assembled tangent",
                if st.sys.steady_damping_tangent() == Some(SteadyDampingTangent::Banded) {
                    "banded"
                } else {
                    "matrix-free"
                }
            );
            if verbose {
                eprintln!("  {why}");
            }
            st.sys
                .set_steady_damping_tangent(SteadyDampingTangent::Assembled);
            st.sys.restore_state(&x_init);
            reports.damping_fallback = Some(why);
            first = press(
                st,
                loading,
                kind,
                newton_opts.clone(),
                &step_opts,
                report,
                rec,
            );
        }
    }
    match first {
        Ok(()) => Ok(()),
        Err(SolveError::Interrupted { at }) => Err(SolveError::Interrupted { at }),
        Err(e) => {
            // The press-in path at the scene's ω failed: try the homotopies of
            // `steady_recovery` before giving up (their counts go into `report`).
            let r = steady_recovery::recover(
                st,
                loading,
                kind,
                &newton_opts,
                &step_opts,
                &x_init,
                &e,
                report,
                rec,
            )?;
            let ok = r.succeeded();
            reports.recovery = Some(r);
            if ok {
                Ok(())
            } else {
                Err(e)
            }
        }
    }
}

/// Relative tolerance of the torque and free-rolling controls: converged when
/// |T − T_target| ≤ `TORQUE_RTOL` · |F_y| · Ro (hub vertical force times outer radius).
pub const TORQUE_RTOL: f64 = 1e-7;

/// Apply the scene's rolling control after the press-in at `road.v0`:
/// - `speed`: nothing (v0 = `road.v0`);
/// - `torque` / `free_rolling`: v0 solved for hub torque = `motion.torque` / 0
///   ([`solve_torque`], tolerance [`TORQUE_RTOL`]);
/// - `creep`: free rolling first (v0_free, R_e), then v0 = (1 + ξ) v0_free reached by
///   natural-parameter steps in ξ ([`super::steady::step_parameter`]).
pub fn apply_control(
    scene: &Scene,
    st: &mut SteadyRolling,
    verbose: bool,
) -> Result<ControlReport, SolveError> {
    if scene.motion.control == Control::Speed {
        return Ok(speed_control_report());
    }
    let newton_opts = st.plan.verbose(verbose).newton;
    let mut newton = Newton::new(st, LinearKind::Lu, newton_opts)?;
    let scale = st.sys.hub_reaction().0[1].abs() * st.ro;
    let rep = control_road_speed(scene, st, scale, &mut newton)?;
    if rep.v0_free.is_finite() {
        st.v0_free = rep.v0_free;
    }
    Ok(rep)
}

/// The report of the speed control (nothing done).
pub fn speed_control_report() -> ControlReport {
    ControlReport {
        control: Control::Speed.as_str().to_string(),
        v0_free: f64::NAN,
        rolling_radius: f64::NAN,
        creep: f64::NAN,
        ..Default::default()
    }
}

/// The torque, free-rolling and creep controls of [`apply_control`] on any steady rolling
/// system, plane or three-dimensional: `torque_scale` is |F_vertical| · Ro at the press-in
/// state (the torque tolerance is [`TORQUE_RTOL`] times it).
pub fn control_road_speed<S: RoadSpeedSystem>(
    scene: &Scene,
    st: &mut S,
    torque_scale: f64,
    newton: &mut Newton,
) -> Result<ControlReport, SolveError> {
    let control = scene.motion.control;
    let mut rep = speed_control_report();
    rep.control = control.as_str().to_string();
    let target = match control {
        Control::Speed => return Ok(rep),
        Control::Torque => scene.motion.torque,
        Control::FreeRolling | Control::Creep => 0.0,
    };
    rep.target_torque = target;
    let scale = if torque_scale > 0.0 {
        torque_scale
    } else {
        1.0
    };
    rep.torque_tolerance = TORQUE_RTOL * scale;
    let ts = solve_torque(st, target, scale, TORQUE_RTOL, newton, 40)?;
    rep.evaluations = ts.evaluations;
    rep.newton_iterations = ts.newton_iterations;
    rep.history = ts.history;
    if matches!(control, Control::FreeRolling | Control::Creep) {
        rep.v0_free = st.road_speed();
        rep.rolling_radius = rep.v0_free / st.angular_speed();
    }
    if control == Control::Creep && scene.motion.creep != 0.0 {
        let v0_free = rep.v0_free;
        rep.newton_iterations += step_parameter_with(
            st,
            scene.motion.creep,
            newton,
            scene.solver.max_cutbacks,
            |s| s.road_speed() / v0_free - 1.0,
            |s, xi| s.set_road_speed((1.0 + xi) * v0_free),
        )?;
    }
    rep.creep = st.road_speed() / rep.v0_free - 1.0;
    Ok(rep)
}

/// The scene's steady system, with the coarser mesh's steady state solved while it is built
/// when the nested iteration applies and the thread pool has a second worker
/// ([`steady_nested::build_steady_nested`]); pass both to [`solve_steady_from`].
pub fn build_nested(
    scene: &Scene,
) -> Result<(SteadyRolling, Option<CoarseSolved>), crate::setup::AppError> {
    steady_nested::build_steady_nested(scene, solve_steady_from)
}
