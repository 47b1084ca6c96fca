//! The transient (dynamic Lagrangian) mode of the three-dimensional wheel: the one-step loop of
//! [`super::transient::integrate`] on [`Solid3DSystem`], the integrators that have a 3D scheme
//! (`generalized_alpha`, `hht_alpha`, `central_difference`), until rolling is steady.
//!
//! * The hub turns about the axle x3 at ω(t) (ramped by `motion.ramp`), the road is pressed in
//!   (`road.disp`, or under load control `road.load` with the road height a massless unknown;
//!   either ramped by `road.ramp`) and moves at v0(t) in its plane,
//!   turned by the slip angle α (`road.slip_angle`) from the start: the road velocity is
//!   V = v0(t) (cos α, −sin α), so the lateral slip ramps in with the speed. The camber
//!   (`road.camber`) tilts the road plane from the start, before the press-in.
//! * The contact's normal damping acts on δ̇ of the material velocity and the friction on the
//!   slip v − V, as in plane strain.
//! * Steady state: at every node passage (the body turned by one cell angle of the revolved
//!   mesh) the material field is re-indexed along the node rings to the referential one and
//!   compared with the last passage's, with all six hub loads (see
//!   [`super::transient::SteadyMonitor`]); their average over the last passage is the steady
//!   load (`results.transient.hub_loads_passage_mean`, the road's loads on the body at the hub
//!   centre in the road frame, as the steady mode's `results.hub_loads`).
//!
//! Outputs: as the other 3D modes (`steps.csv` with the time in `load_factor`, field outputs
//! every `[output] every` steps), plus `history.csv` (per accepted step: t, hub angle and
//! speed, the six hub reactions in the wheel frame) and `steady_field_3d.csv` (the referential
//! field of the last passage: node, X, u).

use super::results::{HubLoads3D, Transient3DResults};
use super::transient::registry::Integrate;
use super::transient::{integrate, Kinematics, Transient, TransientReport};
use crate::io::output::write_csv;
use crate::io::scene::{MassKind, Scene};
use crate::model::Solid3DSystem;
use crate::setup::AppError;
use crate::solver::{LinearKind, NewtonOptions, SolveError, StepInfo};
use std::path::Path;

/// What [`integrate_3d`] gives back: the system at the last accepted step, its velocity
/// field (full vector), the referential field of the last node passage (3 per node; none
/// before the first passage), the results, and how the integration ended.
pub struct Transient3DRun {
    pub sys: Solid3DSystem,
    pub velocity: Vec<f64>,
    pub steady_field: Option<Vec<f64>>,
    pub results: Transient3DResults,
    pub outcome: Result<(), SolveError>,
}

/// One row of `history.csv`.
#[derive(Clone, Copy, Debug)]
struct HistoryRow {
    t: f64,
    phi: f64,
    omega: f64,
    loads: [f64; 6],
    iterations: usize,
}

/// The transient's kinematics of the scene, with the 3D road's first-touch height.
pub fn kinematics_3d(scene: &Scene, sys: &Solid3DSystem) -> Kinematics {
    let mut kin = super::transient_run::kinematics(scene);
    if let Some(rc) = &sys.contact {
        kin.h_touch = rc.h_touch;
    }
    kin
}

/// Integrate the 3D scene in time. Takes the system built for the mode
/// ([`crate::setup::build_system_3d`]) and gives it back at the last accepted step, with the
/// run's results (also on failure: then the error says why). Every accepted step goes to
/// `obs` (rows, field outputs at `[output] every`).
#[allow(clippy::too_many_arguments)]
pub fn integrate_3d(
    scene: &Scene,
    sys: Solid3DSystem,
    kind: LinearKind,
    newton: NewtonOptions,
    obs: &mut dyn FnMut(&Solid3DSystem, &[f64], &StepInfo),
    dir: &Path,
    csv: bool,
) -> Result<Transient3DRun, AppError> {
    let Some(ts) = &scene.time else {
        return Err(AppError::Unsupported(
            "mode \"transient\" needs the [time] section".into(),
        ));
    };
    if ts.steady_only() {
        return Err(AppError::Unsupported(
            "mode \"transient\" needs time.dt and time.t_end".into(),
        ));
    }
    let Some(scheme) = ts.integrator.scheme_3d(ts.rho_inf) else {
        return Err(AppError::Unsupported(format!(
            "time.integrator: \"{}\" does not run in three dimensions (use {})",
            ts.integrator,
            crate::solver::integrators::IntegratorName::quoted_with(|i| i.three_d())
        )));
    };
    let mut sys = sys;
    sys.strain_rate_damping = ts.strain_rate_damping;
    let kin = kinematics_3d(scene, &sys);
    let lumped = ts.effective_mass() == MassKind::Lumped;
    let mut tr = Transient::new(sys, scheme, kin, lumped);
    let time_opts = super::transient_run::time_options(ts, lumped);
    let mut rows: Vec<HistoryRow> = Vec::new();
    let mut its_prev = 0usize;
    let mut t_prev = 0.0;
    let on_step = |tr: &Transient<Solid3DSystem>, rep: &TransientReport| {
        let snap = tr.snapshot_light();
        let its = rep.newton_iterations - its_prev;
        its_prev = rep.newton_iterations;
        rows.push(HistoryRow {
            t: tr.state.t,
            phi: snap.phi,
            omega: snap.omega,
            loads: snap.loads,
            iterations: its,
        });
        let info = StepInfo {
            index: rep.steps.saturating_sub(1) as u64,
            time: tr.state.t,
            dt: tr.state.t - t_prev,
            newton_iterations: its,
            residual: crate::solver::stepping::final_residual(&tr.last_table),
            is_final: tr.state.t >= time_opts.t_end - 1e-12 * time_opts.t_end
                || rep.steps >= time_opts.max_steps
                || (rep.steady && time_opts.stop_at_steady),
        };
        t_prev = tr.state.t;
        obs(&tr.sys, &tr.state.v, &info);
    };
    let (rep, res) = match integrate(&mut tr, &time_opts, newton, kind, on_step) {
        Ok(r) => (r, Ok(())),
        Err((e, r)) => (r, Err(e)),
    };
    let frame = tr.sys.contact.as_ref().map(|c| c.surface.frame());
    let mean = rep.passage_mean_loads.and_then(|m| {
        let f = frame?;
        Some(HubLoads3D::new(
            f.components([-m[0], -m[1], -m[2]]),
            f.components([-m[3], -m[4], -m[5]]),
        ))
    });
    let results = Transient3DResults {
        integrator: ts.integrator.to_string(),
        steps: rep.steps,
        rejected: rep.rejected,
        newton_iterations: rep.newton_iterations,
        steady: rep.steady,
        time_to_steady: rep.time_to_steady,
        final_time: rep.final_time,
        revolutions: rep.revolutions,
        passages: rep.passages,
        last_change: [rep.last_change[0], rep.last_change[1], rep.last_change[2]],
        hub_loads_passage_mean: mean,
        dt_min_used: if rep.steps > 0 {
            rep.dt_min_used
        } else {
            f64::NAN
        },
        dt_max_used: rep.dt_max_used,
    };
    if csv {
        write_history(&rows, dir).map_err(AppError::Output)?;
        if let Some(field) = &tr.steady_field {
            write_steady_field(&tr.sys, field, dir).map_err(AppError::Output)?;
        }
    }
    // The system's state is the last accepted step's (the committed state).
    let Transient {
        mut sys,
        state,
        steady_field,
        ..
    } = tr;
    sys.x.copy_from_slice(&state.u);
    Ok(Transient3DRun {
        sys,
        velocity: state.v,
        steady_field,
        results,
        outcome: res,
    })
}

fn write_history(rows: &[HistoryRow], dir: &Path) -> Result<(), crate::io::output::OutputError> {
    write_csv(
        &dir.join("history.csv"),
        &[
            "t",
            "phi",
            "omega",
            "hub_force_1",
            "hub_force_2",
            "hub_force_3",
            "hub_moment_1",
            "hub_moment_2",
            "hub_moment_3",
            "newton_iterations",
        ],
        rows.iter().map(|r| {
            let mut v = vec![r.t, r.phi, r.omega];
            v.extend_from_slice(&r.loads);
            v.push(r.iterations as f64);
            v
        }),
    )
}

fn write_steady_field(
    sys: &Solid3DSystem,
    field: &[f64],
    dir: &Path,
) -> Result<(), crate::io::output::OutputError> {
    let mesh = &sys.solid.mesh;
    write_csv(
        &dir.join("steady_field_3d.csv"),
        &["node", "X1", "X2", "X3", "u1", "u2", "u3"],
        (0..mesh.n_nodes()).map(|n| {
            let x = mesh.nodes[n];
            vec![
                n as f64,
                x[0],
                x[1],
                x[2],
                field[3 * n],
                field[3 * n + 1],
                field[3 * n + 2],
            ]
        }),
    )
}

/// The deformation of the state turned by the hub angle `phi`: the largest nodal
/// |χ − Q(φ) X| and the mean over the `outer` nodes of its radial component (the transient's
/// displacements include the rigid rotation Q(φ) X − X).
pub fn deformation_measures(sys: &Solid3DSystem, phi: f64) -> (f64, f64) {
    let mesh = &sys.solid.mesh;
    let (s, c) = phi.sin_cos();
    let d = |n: usize| {
        let x = mesh.nodes[n];
        let u = sys.node_displacement(n);
        let q = [c * x[0] - s * x[1], s * x[0] + c * x[1], x[2]];
        [
            x[0] + u[0] - q[0],
            x[1] + u[1] - q[1],
            x[2] + u[2] - q[2],
            q[0],
            q[1],
        ]
    };
    let max = (0..mesh.n_nodes())
        .map(|n| {
            let v = d(n);
            (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
        })
        .fold(0.0, f64::max);
    let outer = mesh.node_set("outer");
    let radial = if outer.is_empty() {
        f64::NAN
    } else {
        outer
            .iter()
            .map(|&n| {
                let v = d(n as usize);
                (v[0] * v[3] + v[1] * v[4]) / v[3].hypot(v[4])
            })
            .sum::<f64>()
            / outer.len() as f64
    };
    (max, radial)
}
