//! The run of a three-dimensional scene (`mesh.dimension = 3`): static indentation
//! (displacement or load control, with or without friction, [`super::indentation3d`]),
//! steady spinning ([`super::spinning3d`]) and steady rolling with a slip angle
//! ([`super::steady3d`]) of the solid that [`crate::setup::build_system_3d`]
//! builds, with the outputs of the plane-strain runs where they apply. Files in the run
//! directory:
//!
//! * `summary.json` — always (also when the solve fails: `converged = false`, `error` says
//!   why, `results` hold the last accepted load step): the [`Solid3DSummary`] (contact force
//!   and moment components, the named hub loads, road height, penetration, iterations, DOFs,
//!   wall time);
//! * sink `csv`: `steps.csv` (one row per accepted load step: force and moment components), `nodes.csv` (reference
//!   position and displacement of every node), `convergence.csv` (the Newton table of
//!   every load step) and, with contact, `contact.csv` (one row per facet quadrature point of
//!   the final state: `cell, face, x1, x2, x3, penetration, t_n, t_1, t_3, slip_1, slip_3,
//!   stick, dA0`; the slip is the load-stepping pseudo-time rate over the last step, in the
//!   steady mode the slip velocity w = ω ∂θχ − V);
//! * sinks `vtu`, `mcap`, `rerun`: `hex.pvd` + `hex/step_*.vtu`, `hex.mcap`, `hex.rrd` through
//!   [`HexOutputs`], every `[output] every` accepted steps and the last one. PNG plots are not
//!   drawn in three dimensions (the scene refuses an explicit `"png"`; the default list skips
//!   it).
//!
//! Output problems (a full disk) are warnings, listed in `summary.json` under
//! `incomplete_outputs` as the plane-strain runs do; an interrupt stops the load stepping at a
//! step boundary (exit status 130). Forces are totals over the width (not per unit thickness).

use super::envelope::conclude;
use super::indentation3d::solve_indentation_3d;
use super::results::{
    BranchRow3D, ContinuationSummary, HubLoads3D, RunOutcome, RunStats, Solid3DMesh,
    Solid3DResults, Solid3DSummary, SolidSolver, Summary,
};
use super::spinning3d::solve_spinning_3d;
use super::steady3d::{
    apply_control_3d, follow_path_3d, solve_steady_3d_nested, Path3DParameter, SteadyPath3D,
};
use super::transient::body3d::contact_samples_3d;
use super::transient3d::{deformation_measures, integrate_3d};
use crate::contact::facet3d::ContactTotals3D;
use crate::io::output::{ensure_dir, write_csv, write_json, OutputError};
use crate::io::record::hex_out::{FootprintState, HexOutputOptions, HexOutputs, HexState};
use crate::io::record::png::Units;
use crate::io::record::{self, RecordError};
use crate::io::scene::{Control, Mode, Scene, Sink};
use crate::mesh::hex_mesh::HexMesh;
use crate::model::Solid3DSystem;
use crate::setup::{build_system_3d, linear_kind_3d, solver_options, AppError, RunOptions};
use crate::solver::continuation::BranchPoint;
use crate::solver::stepping::StepReport;
use crate::solver::{IterationRecord, StepInfo, StepObserver};
use crate::solver::{LinearKind, SolveError};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What a three-dimensional run records of each accepted step.
#[derive(Clone, Copy, Debug, Default)]
struct StepRow {
    index: u64,
    lambda: f64,
    iterations: usize,
    road_height: f64,
    totals: ContactTotals3D,
    u_r_outer_mean: f64,
}

/// The step observer of a three-dimensional run: the per-step rows, the Newton tables and the
/// hexahedral field outputs.
struct Run3DObserver {
    rows: Vec<StepRow>,
    convergence: Vec<Vec<f64>>,
    hex: Option<HexOutputs>,
    every: u64,
    errors: Vec<RecordError>,
    /// The contact totals of the last accepted step (evaluated at its converged state).
    last: StepRow,
}

impl Run3DObserver {
    fn new(scene: &Scene, dir: &Path, mesh: &HexMesh) -> (Self, Vec<String>) {
        let o = &scene.output;
        let mut warnings = Vec::new();
        let rerun = o.has(Sink::Rerun);
        if rerun && !cfg!(feature = "rerun") {
            warnings
                .push("output sink \"rerun\" skipped: this build has no `rerun` feature".into());
        }
        if o.has(Sink::Png) && scene.analysis.mode == Mode::Spinning {
            warnings
                .push("output sink \"png\" skipped: no contact patch to draw when spinning".into());
        }
        let opts = HexOutputOptions {
            vtu: o.has(Sink::Vtu),
            mcap: o.has(Sink::Mcap),
            rerun: rerun && cfg!(feature = "rerun"),
            encoding: crate::io::record::vtu::Encoding {
                format: o.vtu_format,
                compression: o.vtu_compression,
            },
            units: Units::parse(&scene.scene.units),
            displacement_scale: o.displacement_scale,
            colour_by: None,
        };
        let mut errors = Vec::new();
        let hex = if opts.vtu || opts.mcap || opts.rerun {
            match HexOutputs::create(dir, mesh, opts) {
                Ok(h) => Some(h),
                Err(e) => {
                    errors.push(e);
                    None
                }
            }
        } else {
            None
        };
        let obs = Self {
            rows: Vec::new(),
            convergence: Vec::new(),
            hex,
            every: o.every.max(1) as u64,
            errors,
            last: StepRow::default(),
        };
        (obs, warnings)
    }

    fn finish(&mut self) {
        if let Some(h) = self.hex.take() {
            if let Err(e) = h.finish() {
                self.errors.push(e);
            }
        }
    }
}

/// Mean radial displacement Σ u·e_R / n of the nodes of the set `outer`.
fn u_r_outer_mean(sys: &Solid3DSystem) -> f64 {
    let mesh = &sys.solid.mesh;
    let outer = mesh.node_set("outer");
    if outer.is_empty() {
        return f64::NAN;
    }
    let sum: f64 = outer
        .iter()
        .map(|&n| {
            let x = mesh.nodes[n as usize];
            let u = sys.node_displacement(n as usize);
            (u[0] * x[0] + u[1] * x[1]) / x[0].hypot(x[1])
        })
        .sum();
    sum / outer.len() as f64
}

impl StepObserver<Solid3DSystem> for Run3DObserver {
    fn stop_requested(&self) -> bool {
        record::interrupted()
    }
    fn observe_newton(
        &mut self,
        step: u64,
        time: f64,
        table: &[IterationRecord],
        _fields: &'static [&'static str],
    ) {
        for r in table {
            let rel = |k: usize| r.residual_rel.get(k).copied().unwrap_or(0.0);
            self.convergence.push(vec![
                step as f64,
                time,
                r.iteration as f64,
                rel(0),
                rel(1),
                rel(2),
                r.increment_norm,
                r.alpha,
            ]);
        }
    }
    fn observe_accepted(&mut self, sys: &Solid3DSystem, info: &StepInfo) {
        self.observe_state(sys, info, None);
    }
}

impl Run3DObserver {
    /// An accepted state: its row and, at `[output] every`, its field and footprint; the
    /// footprint's slip is the transient's material velocity `velocity` when given.
    fn observe_state(&mut self, sys: &Solid3DSystem, info: &StepInfo, velocity: Option<&[f64]>) {
        // The totals of the last evaluation: the converged state of this step (the friction
        // slip measured over it, before the commit reset the step's start).
        let row = StepRow {
            index: info.index,
            lambda: info.time,
            iterations: info.newton_iterations,
            road_height: sys.road_height().unwrap_or(f64::NAN),
            totals: sys.contact.as_ref().map(|c| c.totals).unwrap_or_default(),
            u_r_outer_mean: u_r_outer_mean(sys),
        };
        self.rows.push(row);
        self.last = row;
        if !info.index.is_multiple_of(self.every) && !info.is_final {
            return;
        }
        if let Some(h) = self.hex.as_mut() {
            let mesh = &sys.solid.mesh;
            let u = &sys.x[..sys.dofs.n_u];
            let state = HexState {
                index: info.index,
                time: info.time,
                u,
                point_fields: &[],
                cell_fields: &[],
            };
            let mut res = h.write_step(mesh, &state);
            if let (Ok(()), true, Some(rc)) = (&res, h.logs_footprint(), sys.contact.as_ref()) {
                let samples = match velocity {
                    Some(v) => contact_samples_3d(sys, &sys.x, v),
                    None => sys.contact_samples(),
                };
                if let Ok(samples) = samples {
                    let fr = rc.surface.frame();
                    res = h.write_footprint(&FootprintState {
                        index: info.index,
                        time: info.time,
                        samples: &samples,
                        e1: [fr.e1[0], fr.e1[1], fr.e1[2]],
                        e3: [fr.e3[0], fr.e3[1], fr.e3[2]],
                    });
                }
            }
            if let Err(e) = res {
                self.errors.push(e);
                // One failure stops the field outputs (the next step would fail alike).
                self.hex = None;
            }
        }
    }
}

/// Run a three-dimensional scene and write its outputs (see the module docs).
pub fn run(scene: &Scene, opts: &RunOptions) -> Result<RunOutcome, AppError> {
    let t0 = Instant::now();
    ensure_dir(&opts.out_dir)?;
    let mut sys = build_system_3d(scene)?;
    let kind = linear_kind_3d(scene, &sys);
    let (newton_opts, step_opts) = solver_options(scene, opts.verbose);
    let (mut obs, warnings) = Run3DObserver::new(scene, &opts.out_dir, &sys.solid.mesh);
    for w in &warnings {
        eprintln!("tread: warning: {w}");
    }
    let mut report = StepReport::default();
    let mut control = None;
    let mut coarse_start = None;
    let mut transient = None;
    let mut velocity: Option<Vec<f64>> = None;
    let mut field: Option<Vec<f64>> = None;
    let mut solve = match scene.analysis.mode {
        Mode::Static => solve_indentation_3d(
            &mut sys,
            kind,
            newton_opts,
            &step_opts,
            &mut report,
            &mut obs,
        ),
        Mode::Steady => {
            let (cs, res) = solve_steady_3d_nested(
                scene,
                &mut sys,
                kind,
                newton_opts.clone(),
                &step_opts,
                &mut report,
                &mut obs,
            );
            coarse_start = cs;
            res
        }
        .and_then(|()| {
            if scene.motion.control == Control::Speed {
                return Ok(());
            }
            let rep = apply_control_3d(scene, &mut sys, kind, newton_opts.clone())?;
            report.total_iterations += rep.newton_iterations;
            // The controlled state is the run's final one: one more row, field and
            // footprint at it.
            let last = obs.last;
            obs.observe_accepted(
                &sys,
                &StepInfo {
                    index: last.index + 1,
                    time: 1.0,
                    dt: 0.0,
                    newton_iterations: rep.newton_iterations,
                    residual: 0.0,
                    is_final: true,
                },
            );
            control = Some(rep);
            Ok(())
        }),
        Mode::Transient => {
            let mut feed = |s: &Solid3DSystem, v: &[f64], info: &StepInfo| {
                obs.observe_state(s, info, Some(v));
            };
            let csv = scene.output.has(Sink::Csv);
            let run = integrate_3d(scene, sys, kind, newton_opts, &mut feed, &opts.out_dir, csv)?;
            sys = run.sys;
            report.total_iterations += run.results.newton_iterations;
            transient = Some(run.results);
            velocity = Some(run.velocity);
            field = run.steady_field;
            run.outcome
        }
        _ => solve_spinning_3d(
            &mut sys,
            scene.motion.omega,
            kind,
            newton_opts,
            &step_opts,
            &mut report,
            &mut obs,
        ),
    };
    // `[continuation]` from the first solution: every converged point a row of branch.csv,
    // of steps.csv and a field output.
    let mut branch: Vec<BranchRow3D> = Vec::new();
    let mut cont = None;
    if let (Ok(()), Some(cs)) = (&solve, &scene.continuation) {
        let v0_free = control.as_ref().map_or(f64::NAN, |c| c.v0_free);
        let Some(parameter) = Path3DParameter::of(cs.parameter, v0_free, &sys) else {
            obs.finish();
            return Err(AppError::Unsupported(format!(
                "continuation.parameter: \"{}\" does not apply to this three-dimensional steady \
                 state (slip_angle, camber, omega at ω ≠ 0; creep after motion.control = \
                 \"creep\" or \"free_rolling\"; load under load control, disp under \
                 displacement control)",
                cs.parameter
            )));
        };
        let n0 = obs.last.index;
        let mut on_point = |p: &SteadyPath3D, b: &BranchPoint| {
            let s = &*p.sys;
            if b.step > 0 {
                obs.observe_accepted(
                    s,
                    &StepInfo {
                        index: n0 + b.step as u64,
                        time: b.lambda,
                        dt: 0.0,
                        newton_iterations: b.iterations,
                        residual: 0.0,
                        is_final: false,
                    },
                );
            }
            branch.push(BranchRow3D::new(s, b));
            !record::interrupted()
        };
        let (r, res) = follow_path_3d(scene, cs, parameter, &mut sys, opts.verbose, &mut on_point);
        if let Some(r) = &r {
            report.total_iterations += r.total_iterations;
        }
        cont = r;
        solve = res.and_then(|()| {
            if record::interrupted() {
                Err(SolveError::Interrupted { at: f64::NAN })
            } else {
                Ok(())
            }
        });
    }
    obs.finish();
    let wall = t0.elapsed().as_secs_f64();
    let converged = solve.is_ok();
    let mut results = results_3d(scene, &sys, &obs.last, !obs.rows.is_empty());
    results.control = control;
    if let Some(t) = &transient {
        // The transient's displacements include the rigid rotation: report the deformation.
        let phi = 2.0 * std::f64::consts::PI * t.revolutions;
        (results.max_displacement, results.u_r_outer_mean) = deformation_measures(&sys, phi);
    }
    results.transient = transient;
    results.continuation = cont.as_ref().map(|c| ContinuationSummary::new(scene, c));
    if scene.continuation.is_some() {
        results.branch = Some(branch.clone());
    }
    let linear = if report.switched_to_lu {
        LinearKind::Lu
    } else {
        kind
    };
    let generated = scene.mesh.file.is_none();
    let ms = &scene.mesh;
    let typed = Summary::new(
        &scene.scene.name,
        scene.analysis.mode.to_string(),
        sys.dofs.n_eq,
        converged,
        super::results::ModeSummary::Solid3D(Box::new(Solid3DSummary {
            run: RunStats {
                newton_iterations: report.total_iterations,
                wall_time_s: wall,
                error: solve.as_ref().err().map(|e| e.to_string()),
            },
            results: results.clone(),
            mesh: Solid3DMesh {
                n_r: generated.then_some(ms.n_r),
                n_theta: generated.then_some(ms.n_theta),
                n_z: generated.then_some(ms.resolved_n_z()),
                order: generated.then_some(ms.order),
                width: if generated { ms.width } else { None },
                sides: generated.then(|| ms.resolved_sides().to_string()),
                crown_radius: if generated { ms.crown_radius } else { None },
                nodes: sys.solid.mesh.n_nodes(),
                cells: sys.solid.mesh.n_cells(),
                pressure_dofs: sys.solid.dofs_per_cell() * sys.solid.mesh.n_cells(),
                contact_facets: sys.contact.as_ref().map_or(0, |c| c.surface.facets.len()),
            },
            solver: SolidSolver {
                linear: format!("{linear:?}").to_lowercase(),
                switched_to_lu: report.switched_to_lu,
                load_steps: report.steps.iter().filter(|s| s.converged).count(),
                cutbacks: report.cutbacks,
                threads: rayon::current_num_threads(),
                interrupted_at: match &solve {
                    Err(SolveError::Interrupted { at }) => Some(*at),
                    _ => None,
                },
                coarse_start,
            },
        })),
    );
    if scene.output.has(Sink::Csv) {
        if let Err(e) = write_tables(&sys, &obs, &opts.out_dir) {
            obs.errors
                .push(RecordError::new("csv", opts.out_dir.clone(), e));
        }
        if scene.continuation.is_some() {
            if let Err(e) = write_branch(&branch, &opts.out_dir) {
                obs.errors
                    .push(RecordError::new("csv", opts.out_dir.clone(), e));
            }
        }
    }
    if scene.output.has(Sink::Png) && sys.contact.is_some() {
        write_footprints(
            scene,
            &sys,
            velocity.as_deref(),
            &opts.out_dir,
            &mut obs.errors,
        );
    }
    let mut summary = typed.to_json();
    for e in &obs.errors {
        eprintln!("tread: warning: {e}");
    }
    if !obs.errors.is_empty() {
        if let Some(m) = summary.as_object_mut() {
            let list: Vec<serde_json::Value> = obs
                .errors
                .iter()
                .map(|e| {
                    serde_json::json!({
                        "sink": e.sink,
                        "path": e.path.display().to_string(),
                        "error": e.message,
                    })
                })
                .collect();
            m.insert("incomplete_outputs".into(), serde_json::Value::Array(list));
        }
    }
    write_json(&opts.out_dir.join("summary.json"), &summary)?;
    let headline = vec![headline(scene, &results)];
    if scene.analysis.mode == Mode::Steady && scene.continuation.is_none() {
        field = Some(sys.x[..3 * sys.solid.mesh.n_nodes()].to_vec());
    }
    conclude(
        solve,
        RunOutcome {
            summary,
            typed,
            field,
            history: None,
            contact: Vec::new(),
            out_dir: PathBuf::from(&opts.out_dir),
            converged,
            headline,
        },
    )
}

/// The results of the last accepted step (`accepted`: whether there was one; else the
/// undeformed state's).
fn results_3d(
    scene: &Scene,
    sys: &Solid3DSystem,
    last: &StepRow,
    accepted: bool,
) -> Solid3DResults {
    let n = sys.solid.mesh.n_nodes();
    let max_displacement = (0..n)
        .map(|i| {
            let u = sys.node_displacement(i);
            (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt()
        })
        .fold(0.0, f64::max);
    let t = if accepted {
        last.totals
    } else {
        ContactTotals3D::default()
    };
    let rc = sys.contact.as_ref();
    let h = rc.map(|_| {
        if accepted {
            last.road_height
        } else {
            sys.road_height().unwrap_or(f64::NAN)
        }
    });
    Solid3DResults {
        dimension: 3,
        contact_force: t.force,
        contact_moment: t.moment,
        load: rc.and_then(|c| c.load),
        road_height: h,
        penetration: rc.zip(h).map(|(c, h)| c.h_touch - h),
        contact_area: t.contact_area,
        max_pressure: t.max_pressure,
        max_penetration: t.max_penetration,
        points_in_contact: t.points_in_contact,
        omega: if matches!(
            scene.analysis.mode,
            Mode::Spinning | Mode::Steady | Mode::Transient
        ) {
            scene.motion.omega
        } else {
            0.0
        },
        u_r_outer_mean: u_r_outer_mean(sys),
        max_displacement,
        hub_loads: rc.map(|c| {
            let frame = c.surface.frame();
            HubLoads3D::new(frame.components(t.force), frame.components(t.moment))
        }),
        road_velocity: rc
            .filter(|c| c.steady_omega.is_some())
            .map(|c| [c.surface.v_road[0], c.surface.v_road[1]]),
        slip_angle: matches!(scene.analysis.mode, Mode::Steady | Mode::Transient)
            .then(|| scene.road.as_ref().map_or(0.0, |r| r.slip_angle)),
        v0: rc.filter(|c| c.steady_omega.is_some()).map(|c| c.v0),
        viscous_dissipation: sys
            .steady_history()
            .filter(|_| accepted)
            .and_then(|h| h.dissipation(&sys.solid)),
        control: None,
        continuation: None,
        branch: None,
        transient: None,
    }
}

fn headline(scene: &Scene, r: &Solid3DResults) -> String {
    match scene.analysis.mode {
        Mode::Static => format!(
            "3D: road height H = {:.6e}, penetration = {:.6e}: contact force = ({:.6e}, {:.6e}, {:.6e}), max pressure = {:.6e}",
            r.road_height.unwrap_or(f64::NAN),
            r.penetration.unwrap_or(f64::NAN),
            r.contact_force[0],
            r.contact_force[1],
            r.contact_force[2],
            r.max_pressure
        ),
        Mode::Steady => {
            let h = r
                .hub_loads
                .unwrap_or_else(|| HubLoads3D::new([f64::NAN; 3], [f64::NAN; 3]));
            format!(
                "3D steady rolling: omega = {:.6} rad/s, penetration = {:.6e}: hub forces (longitudinal, vertical, lateral) = ({:.6e}, {:.6e}, {:.6e}), moments (overturning, aligning, axle) = ({:.6e}, {:.6e}, {:.6e})",
                r.omega,
                r.penetration.unwrap_or(f64::NAN),
                h.longitudinal_force,
                h.vertical_force,
                h.lateral_force,
                h.overturning_moment,
                h.aligning_moment,
                h.axle_moment
            )
        }
        Mode::Transient => {
            let t = r.transient.as_ref();
            let h = t
                .and_then(|t| t.hub_loads_passage_mean)
                .or(r.hub_loads)
                .unwrap_or_else(|| HubLoads3D::new([f64::NAN; 3], [f64::NAN; 3]));
            format!(
                "3D transient rolling: t = {:.6} s, {:.3} revolutions, steady: {}: hub forces (longitudinal, vertical, lateral) = ({:.6e}, {:.6e}, {:.6e}), moments (overturning, aligning, axle) = ({:.6e}, {:.6e}, {:.6e}) ({})",
                t.map_or(f64::NAN, |t| t.final_time),
                t.map_or(f64::NAN, |t| t.revolutions),
                t.is_some_and(|t| t.steady),
                h.longitudinal_force,
                h.vertical_force,
                h.lateral_force,
                h.overturning_moment,
                h.aligning_moment,
                h.axle_moment,
                if t.is_some_and(|t| t.hub_loads_passage_mean.is_some()) {
                    "mean over the last node passage"
                } else {
                    "last step"
                }
            )
        }
        _ => format!(
            "3D: omega = {:.6} rad/s: mean u_r(outer) = {:.6e}, max |u| = {:.6e}",
            r.omega, r.u_r_outer_mean, r.max_displacement
        ),
    }
}

/// The footprint maps of the final state (sink `png`): `footprint_pressure.png`,
/// `footprint_traction.png` and, with friction, `footprint_stick_slip.png`
/// ([`crate::io::record::footprint`]).
fn write_footprints(
    scene: &Scene,
    sys: &Solid3DSystem,
    velocity: Option<&[f64]>,
    dir: &Path,
    errors: &mut Vec<RecordError>,
) {
    use crate::io::record::footprint::{footprint_png, FootprintField};
    let samples = match velocity {
        Some(v) => contact_samples_3d(sys, &sys.x, v),
        None => sys.contact_samples(),
    };
    let Ok(samples) = samples else {
        return;
    };
    let units = Units::parse(&scene.scene.units);
    let stress = format!("{}/{}²", units.force, units.length);
    let friction = sys
        .contact
        .as_ref()
        .is_some_and(|c| c.surface.friction.is_active());
    let mut maps = vec![
        (
            "footprint_pressure.png",
            "contact pressure",
            FootprintField::Pressure,
        ),
        (
            "footprint_traction.png",
            "tangential traction (arrows: direction)",
            FootprintField::Traction,
        ),
    ];
    if friction {
        maps.push((
            "footprint_stick_slip.png",
            "stick and slip zones",
            FootprintField::StickSlip,
        ));
    }
    for (file, what, field) in maps {
        let title = format!(
            "{}: {what} over the patch (x1 along the road, x3 across)",
            scene.scene.name
        );
        let path = dir.join(file);
        if let Err(e) = footprint_png(&path, &title, &samples, field, &stress, &units.length) {
            errors.push(RecordError::new("png", path, e));
        }
    }
}

/// `steps.csv`, `nodes.csv` and `convergence.csv`.
/// `branch.csv`: one row per converged point of the continuation.
fn write_branch(rows: &[BranchRow3D], dir: &Path) -> Result<(), OutputError> {
    write_csv(
        &dir.join("branch.csv"),
        &[
            "step",
            "lambda",
            "iterations",
            "slip_angle",
            "camber",
            "v0",
            "road_height",
            "longitudinal_force",
            "vertical_force",
            "lateral_force",
            "overturning_moment",
            "aligning_moment",
            "axle_moment",
            "points_in_contact",
        ],
        rows.iter().map(|r| {
            let h = &r.hub_loads;
            vec![
                r.step as f64,
                r.lambda,
                r.iterations as f64,
                r.slip_angle,
                r.camber,
                r.v0,
                r.road_height,
                h.longitudinal_force,
                h.vertical_force,
                h.lateral_force,
                h.overturning_moment,
                h.aligning_moment,
                h.axle_moment,
                r.points_in_contact as f64,
            ]
        }),
    )
}

fn write_tables(sys: &Solid3DSystem, obs: &Run3DObserver, dir: &Path) -> Result<(), OutputError> {
    write_csv(
        &dir.join("steps.csv"),
        &[
            "step",
            "load_factor",
            "newton_iterations",
            "road_height",
            "contact_force_1",
            "contact_force_2",
            "contact_force_3",
            "contact_moment_1",
            "contact_moment_2",
            "contact_moment_3",
            "max_pressure",
            "points_in_contact",
            "u_r_outer_mean",
        ],
        obs.rows.iter().map(|r| {
            vec![
                r.index as f64,
                r.lambda,
                r.iterations as f64,
                r.road_height,
                r.totals.force[0],
                r.totals.force[1],
                r.totals.force[2],
                r.totals.moment[0],
                r.totals.moment[1],
                r.totals.moment[2],
                r.totals.max_pressure,
                r.totals.points_in_contact as f64,
                r.u_r_outer_mean,
            ]
        }),
    )?;
    let mesh = &sys.solid.mesh;
    write_csv(
        &dir.join("nodes.csv"),
        &["node", "X1", "X2", "X3", "u1", "u2", "u3"],
        (0..mesh.n_nodes()).map(|n| {
            let x = mesh.nodes[n];
            let u = sys.node_displacement(n);
            vec![n as f64, x[0], x[1], x[2], u[0], u[1], u[2]]
        }),
    )?;
    write_csv(
        &dir.join("convergence.csv"),
        &[
            "step",
            "load_factor",
            "iteration",
            "residual_u_rel",
            "residual_p_rel",
            "residual_h_rel",
            "increment_norm",
            "alpha",
        ],
        obs.convergence.iter().cloned(),
    )?;
    if sys.contact.is_none() {
        return Ok(());
    }
    // The samples fail only where the residual failed (a facet map), which a converged or
    // accepted state has not; then the table is left out rather than the run failed.
    let Ok(samples) = sys.contact_samples() else {
        return Ok(());
    };
    write_csv(
        &dir.join("contact.csv"),
        &[
            "cell",
            "face",
            "x1",
            "x2",
            "x3",
            "penetration",
            "t_n",
            "t_1",
            "t_3",
            "slip_1",
            "slip_3",
            "stick",
            "dA0",
        ],
        samples.iter().map(|s| {
            vec![
                f64::from(s.cell),
                f64::from(s.face),
                s.x1,
                s.x2,
                s.x3,
                s.delta,
                s.p,
                s.t1,
                s.t3,
                s.w1,
                s.w3,
                f64::from(u8::from(s.stick)),
                s.da0,
            ]
        }),
    )
}
