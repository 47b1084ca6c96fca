//! Driver of the `transient` mode: build the model, the kinematics and the integrator from the
//! scene, integrate until steady (or t_end) with a progress bar, and write the outputs:
//! summary.json (`results.time_to_steady`, `revolutions`, `steps`, `steady`, hub forces, torque
//! and contact patch under the indentation keys; `control`, `omega_steady` (hub angular speed at
//! the end of the run: at the steady passage when stopping at steady; the prescribed ω under
//! speed control, the computed one under torque control), `applied_torque`, `rolling_radius` =
//! v0 / ω, `contact_moment` (moment of the contact tractions about the hub centre),
//! `steady_change_omega`, `hub_force_x_passage_mean`, `hub_force_y_passage_mean`,
//! `hub_torque_passage_mean`: the hub loads averaged over the last node passage, see
//! [`crate::driver::transient::SteadyMonitor::passage_mean`]; null before two passages),
//! `passages.csv` (per node passage: changes of the referential field,
//! hub force, torque and hub speed, and the hub force, torque and speed), `contact.csv`
//! (final tractions) and `steady_field.csv` (the referential field extracted at the last node
//! passage, see [`crate::driver::transient::SteadyMonitor`]).
//!
//! Recording ([`crate::io::record`]): every accepted time step is a recorder step (time = t);
//! its view (decimated by `[output] every`) has the nodal stresses of u_n, the contact samples,
//! the hub loads, the strain and kinetic energy (consistent mass) and the scalars `phi` (hub
//! angle) and `revolutions`; `history.csv` is the CSV sink's time history. The first node passage
//! at which the state is steady sends `steady_reached`. Ctrl-C stops at a step boundary.
//!
//! `steady_field.csv` format (shared with the steady mode): one row per referential node,
//! `ring, pos, X1, X2, u1, u2`, where (X1, X2) is the referential (spatial) node position and
//! u = χ − X the displacement of the material point that sits there.

use super::envelope::{conclude, RunClock, RunEnvelope};
use super::frame::{nodal_stress_full_at, recovered_fields};
use super::results::{
    MeshInfo, ModeSummary, RunStats, Summary, Terms, TransientResults, TransientSummary,
    TransientTerms,
};
use super::tables;
use super::transient::ode_first_order::OdeTolerances;
use super::transient::registry::Integrate;
use super::transient::{Kinematics, Ramp, Scheme, Setup, TimeOptions, Transient, TransientReport};
use crate::contact::ContactModel;
use crate::driver::results::RunOutcome;
use crate::io::output::{ensure_dir, write_csv, write_json};
use crate::io::record::{
    self, Energy, HubLoads, Recorder, RejectedStep, SteadyReached, StepInfo, StepView,
};
use crate::io::scene::{Control, IntegratorName, MassKind, Scene, Sink, TimeSpec};
use crate::model::system::SolidSystem;
use crate::setup::{build_contact, build_model, AppError, RunOptions};
use crate::solver::stepping::final_residual;
use crate::solver::{LinearKind, SolveError};
use std::time::Instant;

pub fn run(scene: &Scene, opts: &RunOptions) -> Result<RunOutcome, AppError> {
    let t0 = Instant::now();
    ensure_dir(&opts.out_dir)?;
    let Some(ts) = &scene.time else {
        return Err(AppError::Unsupported(
            "mode \"transient\" needs the [time] section".into(),
        ));
    };
    if ts.steady_only() {
        return Err(AppError::Unsupported(
            "mode \"transient\" needs time.dt and time.t_end (this scene's [time] is a steady \
             scene's, without them)"
                .into(),
        ));
    }
    let integrator = ts.integrator;
    let scheme = integrator.scheme(ts.rho_inf);
    let mut model = build_model(scene)?;
    model.strain_rate_damping = ts.strain_rate_damping;
    let sys = match (&scene.road, &scene.contact) {
        (Some(_), Some(_)) => {
            let c = build_contact(scene, &model)?;
            SolidSystem::with_contact(model, c)
        }
        _ => SolidSystem::new(model, "hub"),
    };
    let kin = kinematics(scene);
    let lumped = ts.effective_mass() == MassKind::Lumped;
    let mut tr = Transient::new(sys, scheme.clone(), kin, lumped);
    let torque_control = scene.motion.control == Control::Torque;
    let plan = crate::setup::solve_plan(scene, &tr.sys).verbose(opts.verbose);
    let kind = if torque_control {
        // The φ row and column make the tangent indefinite-looking to Cholesky in general.
        LinearKind::Lu
    } else {
        plan.kind
    };
    if torque_control {
        // The φ coupling block holds a cell's dofs plus φ; with the exact Q2/P1 pressure that
        // is 22 > MAX_LOCAL local dofs (and the pressure rows would need the φ column too).
        if tr.sys.dofs.per_cell > 0 {
            return Err(AppError::Unsupported(
                "motion.control = \"torque\" does not support the exact incompressible formulation (use material.formulation = \"perturbed\" or a compressible model)".into(),
            ));
        }
        if !integrator.torque_control() {
            return Err(AppError::Unsupported(format!(
                "motion.control = \"torque\" needs time.integrator = {}",
                IntegratorName::quoted_with(IntegratorName::torque_control)
            )));
        }
        tr.enable_torque_control(
            scene.motion.hub_inertia,
            Ramp {
                target: scene.motion.torque,
                time: scene.motion.ramp,
            },
            scene.motion.omega,
        );
        // Start: hub and body in rigid spin at omega (no contact yet: the road is at first touch).
        if scene.motion.omega > 0.0 {
            if let Err(e) = tr.start_rigid_spin(scene.motion.omega, kind, None) {
                // Nothing was integrated: the summary says why, so that the folder is not empty.
                let summary = Summary::new(
                    &scene.scene.name,
                    scene.analysis.mode.to_string(),
                    tr.sys.n_dofs(),
                    false,
                    ModeSummary::Transient(TransientSummary {
                        run: RunStats {
                            newton_iterations: 0,
                            wall_time_s: t0.elapsed().as_secs_f64(),
                            error: Some(format!(
                                "the initial rigid spin at omega = {} rad/s failed: {e}",
                                crate::io::output::fmt_num(scene.motion.omega)
                            )),
                        },
                        warnings: Vec::new(),
                        results: None,
                        terms: None,
                        mesh: None,
                    }),
                )
                .to_json();
                write_json(&opts.out_dir.join("summary.json"), &summary)?;
                return Err(AppError::Solve(e, opts.out_dir.clone()));
            }
        }
    }
    let time_opts = time_options(ts, lumped);
    let newton_opts = plan.newton.clone();
    let clock = RunClock {
        mesh: Some(&tr.sys.model.mesh),
        time_name: "time",
        time_end: time_opts.t_end,
    };
    let mut env = RunEnvelope::open(scene, opts, clock, reach_warning(ts, &scheme))?;
    let recorders = &mut env.recorders;
    let (mut t_prev, mut its_prev, mut rejections_seen) = (0.0, 0usize, 0usize);
    let on_step = |tr: &Transient, rep: &TransientReport| {
        let index = rep.steps.saturating_sub(1) as u64;
        for r in rep.rejections.iter().skip(rejections_seen) {
            recorders.step_rejected(&RejectedStep {
                index,
                time: r.time,
                dt: r.dt,
                reason: &r.reason,
                newton_iterations: r.newton_iterations,
                residual: r.residual,
            });
        }
        rejections_seen = rep.rejections.len();
        record::emit_newton_table(
            recorders,
            index,
            tr.state.t,
            &tr.last_table,
            crate::solver::NonlinearSystem::field_names(tr),
        );
        let info = StepInfo {
            index,
            time: tr.state.t,
            dt: tr.state.t - t_prev,
            newton_iterations: rep.newton_iterations - its_prev,
            residual: final_residual(&tr.last_table),
            // The integration loop's own end conditions.
            is_final: tr.state.t >= time_opts.t_end - 1e-12 * time_opts.t_end
                || rep.steps >= time_opts.max_steps
                || (rep.steady && time_opts.stop_at_steady),
        };
        t_prev = tr.state.t;
        its_prev = rep.newton_iterations;
        if !recorders.wants_view(&info) {
            recorders.step(&info, None);
            return;
        }
        let snap = tr.snapshot();
        let ns = nodal_stress_full_at(&tr.sys, &tr.state.u);
        let (recovered, indicator) =
            recovered_fields(&tr.sys, &tr.state.u, recorders.wants_fields(&info));
        let contact = tr.contact_samples(&tr.state.u, &tr.state.v);
        let scalars = [("phi", snap.phi), ("revolutions", rep.revolutions)];
        let view = StepView {
            mesh: Some(&tr.sys.model.mesh),
            x: &tr.state.u,
            stress: &ns.in_plane,
            sigma_33: &ns.sigma_33,
            stress_recovered: &recovered,
            error_indicator: &indicator,
            pressure: &ns.pressure,
            contact: &contact,
            hub: Some(HubLoads {
                force: [snap.hub_force_x, snap.hub_force_y],
                torque: snap.hub_torque,
            }),
            energy: Some(Energy {
                strain: snap.strain_energy,
                kinetic: snap.kinetic_energy,
            }),
            road_height: tr.sys.road_height(),
            omega: tr.omega_now(),
            scalars: &scalars,
        };
        recorders.step(&info, Some(&view));
    };
    let setup = Setup {
        time: time_opts.clone(),
        newton: newton_opts,
        linear: kind,
        ode_tol: OdeTolerances::from_scene(
            ts.error_tol,
            scene.geometry.ro,
            scene.motion.omega,
            ts.t_end,
        ),
    };
    let mut on_step = on_step;
    let res = integrator.integrate(&mut tr, &setup, &mut on_step);
    let wall = t0.elapsed().as_secs_f64();
    let (rep, err) = match res {
        Ok(r) => (r, None),
        Err((e, r)) => (r, Some(e)),
    };
    if let (true, Some(field)) = (rep.steady, tr.steady_field.as_ref()) {
        record_steady_field(&tr, &rep, field, recorders);
    }
    let samples = tr.contact_samples(&tr.state.u, &tr.state.v);
    let tot = ContactModel::totals(&samples);
    let (f, m) = tr.hub_reaction();
    let omega_hub = tr.omega_now();
    let v0_end = tr.kin.v0.value(tr.state.t);
    let results = TransientResults {
        control: scene.motion.control.as_str().to_string(),
        omega_steady: omega_hub,
        applied_torque: tr.applied_torque(tr.state.t),
        rolling_radius: if omega_hub != 0.0 {
            v0_end / omega_hub
        } else {
            f64::NAN
        },
        contact_moment: tot.moment,
        time_to_steady: rep.time_to_steady,
        revolutions: rep.revolutions,
        steps: rep.steps,
        rejected_steps: rep.rejected,
        steady: rep.steady,
        final_time: rep.final_time,
        node_passages: rep.passages,
        steady_change_field: rep.last_change[0],
        steady_change_force: rep.last_change[1],
        steady_change_torque: rep.last_change[2],
        steady_change_omega: rep.last_change[3],
        dt_min_used: rep.dt_min_used,
        dt_max_used: rep.dt_max_used,
        hub_force_x: f[0],
        hub_force_y: f[1],
        hub_torque: m,
        hub_force_x_passage_mean: rep.passage_mean.map(|p| p[0]),
        hub_force_y_passage_mean: rep.passage_mean.map(|p| p[1]),
        hub_torque_passage_mean: rep.passage_mean.map(|p| p[2]),
        contact_x_min: tot.x_min,
        contact_x_max: tot.x_max,
        max_pressure: tot.max_pressure,
        contact_force_x: tot.force_x,
        contact_force_y: tot.force_y,
        contact_centroid: tot.centroid,
        contact_half_width_moment: 2.0 * tot.pressure_second_moment.sqrt(),
        integrator: integrator.as_str().to_string(),
        mass: if lumped { "lumped" } else { "consistent" }.to_string(),
        viscous_energy: tr.viscous.map(Box::new),
    };
    let friction = tr
        .sys
        .contact
        .as_ref()
        .is_some_and(|c| c.friction.is_active());
    let damping = tr
        .sys
        .contact
        .as_ref()
        .is_some_and(|c| c.normal.has_damping());
    let converged = err.is_none();
    let mut warnings: Vec<String> = Vec::new();
    if converged && !rep.steady {
        warnings.push(format!(
            "steady rolling was not reached by t = {} s ({} node passages, {}; steady_tol = {}): the results are those of the last time step",
            crate::io::output::fmt_num(rep.final_time),
            rep.passages,
            match rep.last_change.iter().copied().fold(0.0, f64::max) {
                c if c.is_finite() => format!("last relative change {}", crate::io::output::fmt_num(c)),
                _ => "no change over a node passage measured yet".to_string(),
            },
            crate::io::output::fmt_num(ts.steady_tol),
        ));
    }
    if let Some(ve) = tr.viscous.filter(|v| v.energy_created) {
        warnings.push(format!(
            "the viscous overstress created energy: cumulative dissipation {} at t = {} s (work {}, stored {}); results.viscous_energy has the balance",
            crate::io::output::fmt_num(ve.min_dissipated),
            crate::io::output::fmt_num(ve.min_dissipated_time),
            crate::io::output::fmt_num(ve.work),
            crate::io::output::fmt_num(ve.stored),
        ));
    }
    for w in &warnings {
        eprintln!("tread: warning: {w}");
    }
    // The summary keeps those printed at the start too (the run's and the recorders').
    let warnings: Vec<String> = env.warnings.iter().cloned().chain(warnings).collect();
    let typed = Summary::new(
        &scene.scene.name,
        scene.analysis.mode.to_string(),
        tr.sys.n_dofs(),
        converged,
        ModeSummary::Transient(TransientSummary {
            run: RunStats {
                newton_iterations: rep.newton_iterations,
                wall_time_s: wall,
                error: err.as_ref().map(|e| e.to_string()),
            },
            warnings,
            results: Some(results),
            terms: Some(TransientTerms {
                common: Terms {
                    friction,
                    normal_damping: damping,
                    inertia: true,
                    history: tr.sys.model.viscoelastic.is_some(),
                    pressure: tr.sys.dofs.per_cell > 0,
                    contact_facets_per_iteration: tr.sys.mean_facets_per_assembly(),
                },
                strain_rate_damping: tr.sys.model.strain_rate_damping > 0.0,
            }),
            mesh: Some(MeshInfo {
                n_r: scene.mesh.n_r,
                n_theta: scene.mesh.n_theta,
                order: scene.mesh.order,
                nodes: tr.sys.model.mesh.n_nodes(),
                cells: tr.sys.model.mesh.n_cells(),
            }),
        }),
    );
    let interrupted = matches!(err, Some(SolveError::Interrupted { .. }));
    let error = err.as_ref().map(|e| e.to_string());
    let summary = env.finish(
        &typed,
        rep.steps as u64,
        wall,
        error.as_deref(),
        interrupted,
    )?;
    if scene.output.has(Sink::Csv) {
        write_csv(
            &opts.out_dir.join("passages.csv"),
            &[
                "t",
                "change_field",
                "change_force",
                "change_torque",
                "hub_force_x",
                "hub_force_y",
                "hub_torque",
                "omega",
                "change_omega",
            ],
            rep.passage_log.iter().map(|r| r.to_vec()),
        )?;
        tables::write_contact_csv(&opts.out_dir.join("contact.csv"), &samples)?;
        if let Some(field) = tr.steady_field.as_ref() {
            tables::write_referential_field_csv(
                &opts.out_dir.join("steady_field.csv"),
                &tr.sys.model.mesh,
                field,
            )?;
        }
    }
    let steady_text = match rep.time_to_steady {
        Some(t) if rep.steady => format!("steady rolling reached at t = {t:.4e} s"),
        _ => "steady rolling NOT reached".to_string(),
    };
    let headline = vec![format!(
        "t = {:.4e} s, {:.3} revolutions, {} steps, {steady_text}; hub force = ({:.6e}, {:.6e}), torque = {:.4e}, contact patch x1 in [{:.4}, {:.4}]",
        rep.final_time, rep.revolutions, rep.steps, f[0], f[1], m, tot.x_min, tot.x_max
    )];
    let field = tr
        .steady_field
        .as_ref()
        .and_then(|u| u.get(..2 * tr.sys.model.mesh.n_nodes()))
        .map(<[f64]>::to_vec);
    conclude(
        err.map_or(Ok(()), Err),
        RunOutcome {
            summary,
            typed,
            field,
            history: tr.steady_history.clone(),
            contact: samples.clone(),
            out_dir: opts.out_dir.clone(),
            converged,
            headline,
        },
    )
}

/// Send the steady state to the recorder: the referential field extracted at the last node
/// passage (`steady_field`, displacement u = χ − X of the material point at each reference node,
/// hub rotation removed) with its nodal stresses, the contact samples and hub loads of the last
/// step (both spatial, so already steady), and the passage-mean hub loads.
fn record_steady_field(
    tr: &Transient,
    rep: &TransientReport,
    field: &[f64],
    recorders: &mut dyn Recorder,
) {
    let mut x = tr.state.u.clone();
    let n = field.len().min(x.len());
    x[..n].copy_from_slice(&field[..n]);
    let ns = nodal_stress_full_at(&tr.sys, &x);
    let (recovered, indicator) = recovered_fields(&tr.sys, &x, true);
    let contact = tr.contact_samples(&tr.state.u, &tr.state.v);
    let snap = tr.snapshot();
    let mean = rep
        .passage_mean
        .unwrap_or([snap.hub_force_x, snap.hub_force_y, snap.hub_torque]);
    let view = StepView {
        mesh: Some(&tr.sys.model.mesh),
        x: &x,
        stress: &ns.in_plane,
        sigma_33: &ns.sigma_33,
        stress_recovered: &recovered,
        error_indicator: &indicator,
        pressure: &ns.pressure,
        contact: &contact,
        hub: Some(HubLoads {
            force: [mean[0], mean[1]],
            torque: mean[2],
        }),
        energy: None,
        road_height: tr.sys.road_height(),
        omega: tr.omega_now(),
        scalars: &[],
    };
    let results = [
        ("hub_force_x", mean[0]),
        ("hub_force_y", mean[1]),
        ("hub_torque", mean[2]),
        ("revolutions", rep.revolutions),
    ];
    recorders.steady_reached(
        &SteadyReached {
            time: rep.time_to_steady.unwrap_or(tr.state.t),
            change: rep.last_change.iter().copied().fold(0.0, f64::max),
            results: &results,
        },
        &view,
    );
}

/// Hub and road kinematics of a transient scene: ω, DISP (or the hub load) and v0 ramped in
/// with the scene's ramp times. Under torque control ω is the initial spin (no ramp: the hub
/// starts spinning at omega; `motion.ramp` ramps the torque instead).
/// The step control and stopping options of `[time]` (steps landing on node passages), both
/// dimensions alike.
pub fn time_options(ts: &TimeSpec, lumped: bool) -> TimeOptions {
    TimeOptions {
        dt: ts.dt,
        dt_min: ts.resolved_dt_min(),
        dt_max: ts.resolved_dt_max(),
        t_end: ts.t_end,
        adaptive: ts.adaptive,
        error_tol: ts.error_tol,
        steady_tol: ts.steady_tol,
        stop_at_steady: ts.stop_at_steady,
        max_steps: ts.max_steps,
        lumped,
        land_on_passages: true,
    }
}

pub fn kinematics(scene: &Scene) -> Kinematics {
    let road = scene.road.as_ref();
    let ramp = road.map_or(0.0, |r| r.ramp);
    let omega_ramp = match scene.motion.control {
        Control::Speed => scene.motion.ramp,
        // (free rolling and creep control are steady-mode controls, rejected by validation)
        Control::Torque | Control::FreeRolling | Control::Creep => 0.0,
    };
    Kinematics {
        omega: Ramp {
            target: scene.motion.omega,
            time: omega_ramp,
        },
        disp: road.and_then(|r| r.disp).map(|d| Ramp {
            target: d,
            time: ramp,
        }),
        h_touch: scene.geometry.ro,
        load: road.and_then(|r| r.load).map(|l| Ramp {
            target: l,
            time: ramp,
        }),
        v0: Ramp {
            target: road.map_or(0.0, |r| r.v0),
            time: road.map_or(scene.motion.ramp, |r| r.resolved_v0_ramp(&scene.motion)),
        },
    }
}

/// A warning when `[time] max_steps` steps of the largest size the integrator takes (`dt_max`
/// with adaptive generalized-α steps, else `dt`) cannot reach `t_end`: the run would stop at
/// `max_steps` short of its end time unless it turns steady first.
fn reach_warning(ts: &TimeSpec, scheme: &Scheme) -> Vec<String> {
    if !ts.integrator.bounded_step() {
        return Vec::new();
    }
    let adaptive = ts.adaptive && scheme.estimates_error();
    let (h, key) = match (adaptive, ts.dt_max) {
        (true, Some(h)) => (h, "time.dt_max"),
        (true, None) => (
            ts.resolved_dt_max(),
            "time.dt_max (10 × time.dt unless given)",
        ),
        (false, _) => (ts.dt, "time.dt"),
    };
    let reach = h * ts.max_steps as f64;
    if reach >= ts.t_end {
        return Vec::new();
    }
    vec![format!(
        "time.max_steps = {} steps of at most {key} = {} s reach t = {} s, short of time.t_end = \
         {} s: the run stops at max_steps unless it is steady before (raise the step or time.max_steps)",
        ts.max_steps,
        crate::io::output::fmt_num(h),
        crate::io::output::fmt_num(reach),
        crate::io::output::fmt_num(ts.t_end),
    )]
}
