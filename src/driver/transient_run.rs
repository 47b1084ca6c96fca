//! Driver of the `transient` mode: build the model, the kinematics and the integrator from the
//! scene, integrate until steady (or t_end) with a progress line, and write the outputs:
//! summary.json (`results.time_to_steady`, `revolutions`, `steps`, `steady`, hub forces, torque
//! and contact patch under the indentation keys), `history.csv` (hub forces and torque per
//! step), `passages.csv` (per node passage: changes of the referential field, hub force and
//! torque, and the hub force and torque), `contact.csv` (final tractions) and `steady_field.csv` (the referential field
//! extracted at the last node passage, see [`crate::driver::transient::SteadyMonitor`]).
//!
//! `steady_field.csv` format (shared with the steady mode): one row per referential node,
//! `ring, pos, X1, X2, u1, u2`, where (X1, X2) is the referential (spatial) node position and
//! u = χ − X the displacement of the material point that sits there.

use super::system::SolidSystem;
use super::transient::{integrate, GenAlpha, Kinematics, Ramp, Scheme, TimeOptions, Transient};
use crate::app::{build_contact, build_model, linear_kind_for, AppError, RunOptions, RunOutcome};
use crate::contact::ContactModel;
use crate::io::output::{ensure_dir, sanitize, write_csv, write_json};
use crate::io::scene::{IntegratorName, MassKind, Scene};
use crate::solver::NewtonOptions;
use std::time::Instant;

pub fn run(scene: &Scene, opts: &RunOptions) -> Result<RunOutcome, AppError> {
    let t0 = Instant::now();
    ensure_dir(&opts.out_dir)?;
    let Some(ts) = &scene.time else {
        return Err(AppError::Unsupported(
            "mode \"transient\" needs the [time] section".into(),
        ));
    };
    let scheme = match ts.integrator {
        IntegratorName::GeneralizedAlpha => Scheme::GeneralizedAlpha(GenAlpha::new(ts.rho_inf)),
        IntegratorName::CentralDifference => Scheme::CentralDifference,
        IntegratorName::Bdf | IntegratorName::Sdirk => {
            return Err(AppError::Unsupported(format!(
                "time.integrator = \"{}\" is not implemented yet (use \"generalized_alpha\" or \"central_difference\")",
                ts.integrator
            )))
        }
    };
    let mut model = build_model(scene)?;
    model.strain_rate_damping = ts.strain_rate_damping;
    let sys = match (&scene.road, &scene.contact) {
        (Some(_), Some(_)) => {
            let c = build_contact(scene, &model)?;
            SolidSystem::with_contact(model, c)
        }
        _ => SolidSystem::new(model, "hub"),
    };
    let road = scene.road.as_ref();
    let ramp = road.map_or(0.0, |r| r.ramp);
    let kin = Kinematics {
        omega: Ramp {
            target: scene.motion.omega,
            time: scene.motion.ramp,
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
    };
    let lumped = ts.effective_mass() == MassKind::Lumped;
    let mut tr = Transient::new(sys, scheme, kin, lumped);
    let kind = linear_kind_for(scene, &tr.sys);
    let time_opts = TimeOptions {
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
    };
    let newton_opts = NewtonOptions {
        tol: scene.solver.tolerance,
        max_iterations: scene.solver.max_iterations,
        line_search: scene.solver.line_search,
        verbose: opts.verbose,
        ..Default::default()
    };
    let mut last_print = Instant::now();
    let mut history: Vec<Vec<f64>> = Vec::new();
    let res = integrate(&mut tr, &time_opts, newton_opts, kind, |tr, rep| {
        if let Some(h) = rep.history.last() {
            let _ = h;
        }
        let (f, m) = tr.hub_reaction();
        history.push(vec![tr.t, tr.kin.phi(tr.t), f[0], f[1], m]);
        if last_print.elapsed().as_secs_f64() > 2.0 {
            last_print = Instant::now();
            let el = t0.elapsed().as_secs_f64();
            eprintln!(
                "  t = {:.5e} s ({:.1} % of t_end), {:.3} revolutions, {} steps ({} rejected), {:.0} steps/s, dt = {:.2e}",
                tr.t,
                100.0 * tr.t / time_opts.t_end,
                rep.revolutions,
                rep.steps,
                rep.rejected,
                rep.steps as f64 / el.max(1e-9),
                tr.dt
            );
        }
    });
    let wall = t0.elapsed().as_secs_f64();
    let (rep, err) = match res {
        Ok(r) => (r, None),
        Err((e, r)) => (r, Some(e)),
    };
    let samples = tr
        .sys
        .contact
        .as_ref()
        .map(|c| c.samples(&tr.sys.model.mesh, &tr.sys.dofs, &tr.un, &tr.vn))
        .unwrap_or_default();
    let tot = ContactModel::totals(&samples);
    let (f, m) = tr.hub_reaction();
    let results = serde_json::json!({
        "time_to_steady": rep.time_to_steady,
        "revolutions": rep.revolutions,
        "steps": rep.steps,
        "rejected_steps": rep.rejected,
        "steady": rep.steady,
        "final_time": rep.final_time,
        "node_passages": rep.passages,
        "steady_change_field": rep.last_change[0],
        "steady_change_force": rep.last_change[1],
        "steady_change_torque": rep.last_change[2],
        "dt_min_used": rep.dt_min_used,
        "dt_max_used": rep.dt_max_used,
        "hub_force_x": f[0],
        "hub_force_y": f[1],
        "hub_torque": m,
        "contact_x_min": tot.x_min,
        "contact_x_max": tot.x_max,
        "max_pressure": tot.max_pressure,
        "contact_force_x": tot.force_x,
        "contact_force_y": tot.force_y,
        "contact_centroid": tot.centroid,
        "contact_half_width_moment": 2.0 * tot.pressure_second_moment.sqrt(),
        "integrator": tr.scheme.name(),
        "mass": if lumped { "lumped" } else { "consistent" },
    });
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
    let mut summary = serde_json::json!({
        "scene": scene.scene.name,
        "mode": scene.analysis.mode.to_string(),
        "dofs": tr.sys.n_dofs(),
        "newton_iterations": rep.newton_iterations,
        "wall_time_s": wall,
        "converged": converged,
        "error": err.as_ref().map(|e| e.to_string()),
        "results": results,
        "terms": {
            "friction": friction,
            "normal_damping": damping,
            "strain_rate_damping": tr.sys.model.strain_rate_damping > 0.0,
            "inertia": true,
            "history": false,
            "pressure": tr.sys.dofs.per_cell > 0,
            "contact_facets_per_iteration": tr.sys.mean_facets_per_assembly(),
        },
        "mesh": {
            "n_r": scene.mesh.n_r, "n_theta": scene.mesh.n_theta, "order": scene.mesh.order,
            "nodes": tr.sys.model.mesh.n_nodes(), "cells": tr.sys.model.mesh.n_cells(),
        },
        "version": env!("CARGO_PKG_VERSION"),
    });
    sanitize(&mut summary);
    write_json(&opts.out_dir.join("summary.json"), &summary)?;
    if scene.output.csv {
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
            ],
            rep.passage_log.iter().map(|r| r.to_vec()),
        )?;
        write_csv(
            &opts.out_dir.join("history.csv"),
            &["t", "phi", "hub_force_x", "hub_force_y", "hub_torque"],
            history.into_iter(),
        )?;
        write_csv(
            &opts.out_dir.join("contact.csv"),
            &[
                "theta",
                "x1",
                "x2",
                "penetration",
                "t_n",
                "t_t",
                "slip_velocity",
                "ds0",
            ],
            samples
                .iter()
                .map(|s| vec![s.theta, s.x1, s.x2, s.delta, s.t_n, s.t_t, s.w, s.ds0]),
        )?;
        if let Some(rl) = tr.sys.model.mesh.rings {
            if let Some(field) = tr.steady_field.as_ref() {
                let mesh = &tr.sys.model.mesh;
                write_csv(
                    &opts.out_dir.join("steady_field.csv"),
                    &["ring", "pos", "X1", "X2", "u1", "u2"],
                    (0..mesh.n_nodes()).map(|n| {
                        vec![
                            (n / rl.per_ring) as f64,
                            (n % rl.per_ring) as f64,
                            mesh.nodes[n][0],
                            mesh.nodes[n][1],
                            field[2 * n],
                            field[2 * n + 1],
                        ]
                    }),
                )?;
            }
        }
    }
    let headline = vec![format!(
        "t = {:.4e} s, {:.3} revolutions, {} steps, steady = {} (at t = {:?}); hub force = ({:.6e}, {:.6e}), torque = {:.4e}, contact patch x1 in [{:.4}, {:.4}]",
        rep.final_time, rep.revolutions, rep.steps, rep.steady, rep.time_to_steady, f[0], f[1], m, tot.x_min, tot.x_max
    )];
    match err {
        None => Ok(RunOutcome {
            summary,
            out_dir: opts.out_dir.clone(),
            converged,
            headline,
        }),
        Some(e) => Err(AppError::Solve(e, opts.out_dir.clone())),
    }
}
