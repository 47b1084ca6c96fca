//! The `tread` program: turn a validated [`Scene`] into a model, run its analysis, write the
//! outputs (summary.json, CSV) and report.
//!
//! Output files in the run directory:
//! * `summary.json` — always written, also when the solve fails (then `converged = false`,
//!   `error` says why and `results` hold the last converged load step);
//! * `profile.csv` — ring averages of u_r, σ_r, σ_θ, σ_rθ at the radial Gauss points;
//! * `nodes.csv` — reference position and displacement of every node;
//! * `convergence.csv` — the Newton convergence table of every load step;
//! * the recorder's sinks chosen by `[output] sinks` (see [`crate::io::record`] and
//!   [`build_recorders`]): `history.csv`, `fields.pvd` + `fields/*.vtu`, `run.mcap`, `run.rrd`,
//!   PNG plots; plus a progress bar on stderr unless `quiet`.
//!
//! An interrupt (Ctrl-C) stops the solve at a step boundary; every sink is finished and
//! summary.json says `converged = false`, `"error": "interrupted"`; [`run`] then returns
//! [`AppError::Interrupted`] (exit status 130).

use crate::contact::laws::{CoulombLinear, CoulombTanh, OdenMartins, RateDependent};
use crate::contact::{Clamp, ContactModel, FacetRule, Friction, NormalCompliance};
use crate::driver::indentation;
use crate::driver::spinning;
use crate::driver::system::Loading;
use crate::driver::tables;
use crate::driver::SolidSystem;
use crate::io::output::{ensure_dir, sanitize, write_csv, write_json, OutputError};
use crate::io::record::{self, Recorder, Recorders, RunEnd, RunMeta};
use crate::io::scene::{
    ClampKind, ContactQuadrature, Formulation, FrictionParams, LinearChoice, MaterialParams, Mode,
    Scene, Sink, DEFAULT_CLAMP_WIDTH_OVER_G,
};
use crate::material::{
    Hyperelastic, Material, MooneyRivlin, MooneyRivlinIncompressible, NeoHookean,
};
use crate::math::Mat2;
use crate::mesh::{annulus, AnnulusSpec};
use crate::physics::{PressureMode, SolidModel};
use crate::solver::stepping::{StepOptions, StepReport};
use crate::solver::{LinearKind, NewtonOptions, SolveError};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Debug, thiserror::Error)]
pub enum AppError {
    #[error("{0}")]
    Output(#[from] OutputError),
    #[error("the solve failed: {0} (partial results written to {1})")]
    Solve(SolveError, PathBuf),
    #[error("scene: {0}")]
    Unsupported(String),
    #[error("interrupted: the logs up to the last step are written to {0}")]
    Interrupted(PathBuf),
    /// A computation other than a Newton solve failed (e.g. the stick-slip integrator).
    #[error("{0} (partial results written to {1})")]
    Failed(String, PathBuf),
    /// The output folder cannot be used (not writable, locked by another run, …).
    #[error("output folder {0}: {1}")]
    OutDir(PathBuf, String),
    /// The scene would need more memory than allowed.
    #[error("{0}")]
    TooBig(String),
}

impl AppError {
    /// Process exit status: 130 interrupted, 1 the computation failed, 2 invalid input (scene,
    /// flags, a model too large for the memory limit), 3 an output file or folder cannot be
    /// written.
    pub fn exit_code(&self) -> u8 {
        match self {
            AppError::Interrupted(_) => 130,
            AppError::Solve(..) | AppError::Failed(..) => 1,
            AppError::Output(_) | AppError::OutDir(..) => 3,
            AppError::Unsupported(_) | AppError::TooBig(_) => 2,
        }
    }
}

#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    pub out_dir: PathBuf,
    /// Print the Newton convergence table.
    pub verbose: bool,
    /// No progress bar.
    pub quiet: bool,
}

/// The sinks of `[output] sinks` writing into `out_dir` (each with decimation `[output]
/// every`), plus the progress bar unless `quiet`. Returns warnings (a sink not available in
/// this build).
pub fn build_recorders(scene: &Scene, out_dir: &Path, quiet: bool) -> (Recorders, Vec<String>) {
    let mut r = Recorders::new();
    #[cfg_attr(feature = "rerun", allow(unused_mut))]
    let mut warnings = Vec::new();
    let every = scene.output.every;
    for sink in &scene.output.sinks {
        match sink {
            Sink::Summary => {}
            // Scalars at every step: decimating them aliases with the node passages.
            Sink::Csv => r.push(Box::new(record::csv::CsvSink::new(out_dir)), 1),
            Sink::Vtu => r.push(
                Box::new(record::vtu::VtuSink::with_format(
                    out_dir,
                    scene.output.vtu_format,
                )),
                every,
            ),
            Sink::Mcap => r.push(Box::new(record::mcap::McapSink::new(out_dir)), every),
            Sink::Png => r.push(Box::new(record::png::PngSink::new(out_dir)), every),
            #[cfg(feature = "rerun")]
            Sink::Rerun => r.push(Box::new(record::rrd::RrdSink::new(out_dir)), every),
            #[cfg(not(feature = "rerun"))]
            Sink::Rerun => warnings.push(
                "output sink \"rerun\" skipped: this build has no `rerun` feature".to_string(),
            ),
        }
    }
    // The increment status file is always written (one short line per increment).
    r.push(Box::new(record::sta::StaSink::new(out_dir)), 1);
    if !quiet {
        r.push(Box::new(record::progress::Progress::new()), 1);
    }
    (r, warnings)
}

/// Finish the recorder and report sink errors as warnings (logging never fails a run).
fn finish_recorders(rec: &mut dyn Recorder, end: &RunEnd) {
    for e in rec.run_finished(end) {
        eprintln!("tread: warning: {e}");
    }
}

/// Turn the outcome of a solve into the run's result (interrupts first).
fn solve_outcome(
    solve: Result<(), SolveError>,
    outcome: RunOutcome,
) -> Result<RunOutcome, AppError> {
    match solve {
        Ok(()) => Ok(outcome),
        Err(SolveError::Interrupted { .. }) => Err(AppError::Interrupted(outcome.out_dir)),
        Err(e) => Err(AppError::Solve(e, outcome.out_dir)),
    }
}

/// Default output directory of a scene: `out/<scene name>/`.
pub fn default_out_dir(scene: &Scene) -> PathBuf {
    Path::new("out").join(&scene.scene.name)
}

/// Material law and pressure treatment of a scene.
pub fn build_material(scene: &Scene) -> Result<(Material, PressureMode), AppError> {
    build_material_spec(&scene.material)
}

/// Material law and pressure treatment of one `[material]` (or `[[material]]` entry).
pub fn build_material_spec(
    spec: &crate::io::scene::MaterialSpec,
) -> Result<(Material, PressureMode), AppError> {
    let params = spec.params().ok_or_else(|| {
        AppError::Unsupported(
            "material: a parameter required by `material.model` is missing".into(),
        )
    })?;
    Ok(match params {
        MaterialParams::NeoHookean { mu, lambda } => (
            Material::NeoHookean(NeoHookean::new(mu, lambda)),
            PressureMode::None,
        ),
        MaterialParams::MooneyRivlin { c1, c2, kappa } => (
            Material::MooneyRivlin(MooneyRivlin::new(c1, c2, kappa)),
            PressureMode::None,
        ),
        MaterialParams::MooneyRivlinIncompressible {
            c1,
            c2,
            formulation,
            kappa,
        } => {
            let mat = MooneyRivlinIncompressible::new(c1, c2);
            // The unconstrained W is not stress free at F = I; the reference pressure p0 makes it so.
            let p0 = 0.5 * mat.stress(&Mat2::zeros()).trace();
            let mode = match (formulation, kappa) {
                (Formulation::Perturbed, Some(kappa)) => PressureMode::Perturbed { kappa, p0 },
                _ => PressureMode::Exact { p0 },
            };
            (Material::MooneyRivlinIncompressible(mat), mode)
        }
    })
}

/// Build the solid system (mesh, material, dofs, pattern) of a scene.
pub fn build_system(scene: &Scene) -> Result<SolidSystem, AppError> {
    let model = build_model(scene)?;
    if scene.analysis.mode == Mode::Static {
        let contact = build_contact(scene, &model)?;
        return Ok(SolidSystem::with_contact(model, contact));
    }
    Ok(SolidSystem::new(model, "hub"))
}

/// The road contact of a scene (`[road]`, `[contact]`, `[friction]`).
pub fn build_contact(scene: &Scene, model: &SolidModel) -> Result<ContactModel, AppError> {
    let (Some(road), Some(cs)) = (&scene.road, &scene.contact) else {
        return Err(AppError::Unsupported(
            "mode \"static\" needs the [road] and [contact] sections".into(),
        ));
    };
    let clamp = match cs.clamp {
        ClampKind::Hard => Clamp::Hard,
        ClampKind::Smooth => Clamp::Smooth {
            width: cs.clamp_width.unwrap_or_else(|| {
                DEFAULT_CLAMP_WIDTH_OVER_G * model.material.small_strain_shear_modulus()
            }),
        },
    };
    let normal = NormalCompliance::new(cs.c_n, cs.m_n, cs.b_n, cs.l_n).with_clamp(clamp);
    let friction = match scene.friction.params() {
        None => {
            return Err(AppError::Unsupported(
                "friction: a parameter required by `friction.law` is missing".into(),
            ))
        }
        Some(FrictionParams::None) => Friction::None,
        Some(FrictionParams::CoulombTanh { mu, eps }) => {
            Friction::CoulombTanh(CoulombTanh::new(mu, eps))
        }
        Some(FrictionParams::CoulombLinear { mu, eps }) => {
            Friction::CoulombLinear(CoulombLinear::new(mu, eps))
        }
        Some(FrictionParams::RateDependent {
            mu_s,
            mu_k,
            v_s,
            eps,
        }) => Friction::RateDependent(RateDependent::new(mu_s, mu_k, v_s, eps)),
        Some(FrictionParams::OdenMartins { c_t, m_t, eps }) => {
            Friction::OdenMartins(OdenMartins::new(c_t, m_t, eps))
        }
    };
    let rule = match cs.quadrature {
        ContactQuadrature::Gauss => FacetRule::Gauss(cs.points),
        ContactQuadrature::Lobatto => FacetRule::Lobatto(cs.points),
    };
    let ro = scene.geometry.ro;
    // Load control starts with a small penetration (1e-3 Ro) so that the road-height equation
    // has a non-zero tangent; displacement control starts at first touch (H = Ro).
    let (h0, load) = match road.load {
        Some(_) => (ro * (1.0 - 1e-3), Some(0.0)),
        None => (ro, None),
    };
    Ok(ContactModel::new(
        &model.mesh,
        h0,
        road.v0,
        normal,
        friction,
        rule,
        load,
    ))
}

/// Mesh, material and solid model of a scene.
pub fn build_model(scene: &Scene) -> Result<SolidModel, AppError> {
    let ms = &scene.mesh;
    let (material, pressure) = build_material(scene)?;
    if !matches!(pressure, PressureMode::None) && ms.order != 2 {
        return Err(AppError::Unsupported(format!(
            "mesh.order = {}: incompressible materials need order = 2 (Q2 displacements with P1 pressures)",
            ms.order
        )));
    }
    if let Some(file) = &ms.file {
        return build_model_from_file(scene, file, material, pressure);
    }
    let mut mesh = annulus(&AnnulusSpec {
        ri: scene.geometry.ri,
        ro: scene.geometry.ro,
        n_r: ms.n_r,
        n_theta: ms.n_theta,
        degree: ms.order,
        grading_r: ms.grading_r,
        grading_theta: ms.grading_theta,
    });
    // Isoparametric cells: nodes on the exact circles, rigid motions represented exactly
    // (objectivity; see `Mesh::make_isoparametric`).
    mesh.make_isoparametric();
    let mut model = SolidModel::new(mesh, material, scene.material.rho, pressure);
    if let Some(vs) = &scene.material.viscoelastic {
        let ve = vs
            .build()
            .map_err(|e| AppError::Unsupported(format!("material.viscoelastic: {e}")))?;
        check_viscoelastic_mode(scene)?;
        model.set_viscoelastic(ve);
    }
    Ok(model)
}

/// The modes and integrators that carry a viscoelastic history so far: the transient mode with
/// generalized-α or central difference (history committed per accepted step). The ODE
/// integrators (BDF, SDIRK) would need the internal variables in their state vector; the
/// static, spinning and steady modes would need the relaxed limit or the streamline
/// integration.
fn check_viscoelastic_mode(scene: &Scene) -> Result<(), AppError> {
    if scene.analysis.mode != Mode::Transient {
        return Err(AppError::Unsupported(format!(
            "material.viscoelastic: mode \"{}\" does not support viscoelastic materials yet \
             (use mode = \"transient\")",
            scene.analysis.mode
        )));
    }
    if let Some(ts) = &scene.time {
        if matches!(
            ts.integrator,
            crate::io::scene::IntegratorName::Bdf | crate::io::scene::IntegratorName::Sdirk
        ) {
            return Err(AppError::Unsupported(format!(
                "material.viscoelastic: time.integrator = \"{}\" does not carry a \
                 viscoelastic history; use \"generalized_alpha\" or \"central_difference\"",
                ts.integrator
            )));
        }
    }
    Ok(())
}

/// The model of a scene whose mesh is a Gmsh file (`[mesh] file`), with a material per region
/// when the scene has `[[material]]`.
fn build_model_from_file(
    scene: &Scene,
    file: &str,
    material: Material,
    pressure: PressureMode,
) -> Result<SolidModel, AppError> {
    use crate::io::scene::{DEFAULT_CONTACT_GROUP, DEFAULT_HUB_GROUP};
    use crate::mesh::gmsh::{read_msh, GmshGroups, MeshError};
    let ms = &scene.mesh;
    let groups = GmshGroups {
        hub: ms.hub.clone().unwrap_or_else(|| DEFAULT_HUB_GROUP.into()),
        contact: ms
            .contact
            .clone()
            .unwrap_or_else(|| DEFAULT_CONTACT_GROUP.into()),
        regions: scene.regions.iter().map(|r| r.region.clone()).collect(),
    };
    let bad = |message: String| {
        AppError::Unsupported(
            MeshError {
                file: file.to_string(),
                message,
            }
            .to_string(),
        )
    };
    let mesh = read_msh(Path::new(file), &groups).map_err(|e| bad(e.message))?;
    if !matches!(pressure, PressureMode::None) && mesh.degree.iter().any(|&p| p != 2) {
        return Err(bad(
            "incompressible materials need 9-node quadrilaterals (Q2 displacements with P1 \
             pressures); the file has 4-node ones"
                .into(),
        ));
    }
    // The road is placed from geometry.ro (first touch at H = ro): the mesh must reach it.
    let ro = mesh.outer_radius();
    let ro_scene = scene.geometry.ro;
    if (ro - ro_scene).abs() > 1e-6 * ro_scene.abs().max(f64::MIN_POSITIVE) {
        return Err(bad(format!(
            "the mesh's outer radius (largest |X| of a node) is {ro}, but geometry.ro = {ro_scene}"
        )));
    }
    let mut model = SolidModel::new(mesh, material, scene.material.rho, pressure);
    if !scene.regions.is_empty() {
        let mut regions = Vec::new();
        for r in &scene.regions {
            let (m, p) = build_material_spec(&r.material)?;
            let p0 = match p {
                PressureMode::Exact { p0 } | PressureMode::Perturbed { p0, .. } => p0,
                PressureMode::None => 0.0,
            };
            regions.push(crate::physics::solid::RegionMaterial {
                material: m,
                rho: r.material.rho,
                p0,
            });
        }
        model.set_region_materials(regions);
    }
    Ok(model)
}

/// Linear solver for a scene's system: Cholesky for symmetric positive problems, LU for the
/// exact incompressible saddle point and whenever friction or damping makes the tangent
/// unsymmetric.
pub fn linear_kind(scene: &Scene, sys: &SolidSystem) -> LinearKind {
    match scene.solver.linear {
        LinearChoice::Cholesky => LinearKind::Cholesky,
        LinearChoice::Lu => LinearKind::Lu,
        LinearChoice::Auto => {
            let friction = sys
                .contact
                .as_ref()
                .is_some_and(|c| c.friction.is_active() || c.normal.has_damping());
            if matches!(sys.model.pressure, PressureMode::Exact { .. }) || friction {
                LinearKind::Lu
            } else {
                LinearKind::Cholesky
            }
        }
    }
}

/// Everything a run produced.
#[derive(Debug)]
pub struct RunOutcome {
    pub summary: serde_json::Value,
    pub out_dir: PathBuf,
    pub converged: bool,
    /// Human-readable result lines for the terminal.
    pub headline: Vec<String>,
}

/// Newton and load-stepping options from the scene's `[solver]`.
pub fn solver_options(scene: &Scene, verbose: bool) -> (NewtonOptions, StepOptions) {
    let newton_opts = NewtonOptions {
        tol: scene.solver.tolerance,
        max_iterations: scene.solver.max_iterations,
        line_search: scene.solver.line_search,
        verbose,
        ..Default::default()
    };
    let step_opts = StepOptions {
        initial_steps: scene.solver.load_steps,
        max_cutbacks: scene.solver.max_cutbacks,
        verbose,
    };
    (newton_opts, step_opts)
}

/// Run a scene and write its outputs. A failed solve still writes every output (with the last
/// converged state) and returns `Err(AppError::Solve)`.
pub fn run(scene: &Scene, opts: &RunOptions) -> Result<RunOutcome, AppError> {
    match scene.analysis.mode {
        Mode::Spinning | Mode::Static => run_solid(scene, opts),
        Mode::StickSlip => crate::driver::stick_slip_run::run(scene, opts),
        Mode::Transient => crate::driver::transient_run::run(scene, opts),
        Mode::Steady => crate::driver::steady_run::run(scene, opts),
    }
}

fn run_solid(scene: &Scene, opts: &RunOptions) -> Result<RunOutcome, AppError> {
    let t0 = Instant::now();
    ensure_dir(&opts.out_dir)?;
    let mut sys = build_system(scene)?;
    let kind = linear_kind(scene, &sys);
    let (newton_opts, step_opts) = solver_options(scene, opts.verbose);
    let mut report = StepReport::default();
    let (mut recorders, warnings) = build_recorders(scene, &opts.out_dir, opts.quiet);
    for w in warnings {
        eprintln!("tread: warning: {w}");
    }
    let scene_toml = scene.to_toml_string();
    let mode = scene.analysis.mode.to_string();
    let omega = scene.motion.omega;
    recorders.run_started(&RunMeta {
        scene_name: &scene.scene.name,
        mode: &mode,
        scene_toml: &scene_toml,
        version: env!("CARGO_PKG_VERSION"),
        features: record::build_features(),
        mesh: Some(&sys.model.mesh),
        time_name: "load_factor",
        time_end: 1.0,
        revolution_period: (omega > 0.0).then(|| 2.0 * std::f64::consts::PI / omega),
    });
    let rec: &mut dyn Recorder = &mut recorders;
    let solve = match scene.analysis.mode {
        Mode::Static => {
            sys.loading = match scene.road.as_ref().and_then(|r| r.load) {
                Some(load) => Loading::Load { load },
                None => Loading::Indent {
                    h_touch: scene.geometry.ro,
                    disp: scene.road.as_ref().and_then(|r| r.disp).unwrap_or(0.0),
                },
            };
            indentation::solve_indentation(
                &mut sys,
                kind,
                newton_opts,
                &step_opts,
                &mut report,
                rec,
            )
        }
        _ => spinning::solve_spinning(
            &mut sys,
            scene.motion.omega,
            kind,
            newton_opts,
            &step_opts,
            &mut report,
            rec,
        ),
    };
    let wall = t0.elapsed().as_secs_f64();
    let converged = solve.is_ok();
    let interrupted = matches!(solve, Err(SolveError::Interrupted { .. }));
    let mut headline = Vec::new();
    let results = match scene.analysis.mode {
        Mode::Static => {
            let r = indentation::results(&sys, scene.geometry.ro);
            headline.push(format!(
                "DISP = {:.6e}: hub force = ({:.6e}, {:.6e}), hub torque = {:.3e}, contact patch x1 in [{:.5}, {:.5}], max pressure = {:.6e}",
                r.penetration, r.hub_force_x, r.hub_force_y, r.hub_torque, r.contact_x_min, r.contact_x_max, r.max_pressure
            ));
            serde_json::to_value(r).unwrap_or_default()
        }
        _ => {
            let r = spinning::results(&sys);
            headline.push(format!(
                "omega = {:.6} rad/s: u_r(outer) = {:.6e}, sigma_r(inner) = {:.6e}, sigma_theta(inner) = {:.6e}, sigma_theta(outer) = {:.6e}",
                r.omega, r.u_r_outer, r.sigma_r_inner, r.sigma_theta_inner, r.sigma_theta_outer
            ));
            serde_json::to_value(r).unwrap_or_default()
        }
    };
    let friction = sys.contact.as_ref().is_some_and(|c| c.friction.is_active());
    let mut summary = serde_json::json!({
        "scene": scene.scene.name,
        "mode": scene.analysis.mode.to_string(),
        "dofs": sys.n_dofs(),
        "newton_iterations": report.total_iterations,
        "wall_time_s": wall,
        "converged": converged,
        "error": solve.as_ref().err().map(|e| e.to_string()),
        "results": results,
        "terms": {
            "friction": friction,
            "normal_damping": false,
            "inertia": scene.analysis.mode == Mode::Spinning,
            "history": false,
            "pressure": !matches!(sys.model.pressure, PressureMode::None),
            "contact_facets_per_iteration": sys.mean_facets_per_assembly(),
        },
        "mesh": {
            "n_r": scene.mesh.n_r, "n_theta": scene.mesh.n_theta, "order": scene.mesh.order,
            "nodes": sys.model.mesh.n_nodes(), "cells": sys.model.mesh.n_cells(),
            "pressure_dofs": sys.dofs.per_cell * sys.model.mesh.n_cells(),
        },
        "solver": {
            "linear": format!("{:?}", if report.switched_to_lu { LinearKind::Lu } else { kind }).to_lowercase(),
            "switched_to_lu": report.switched_to_lu,
            "load_steps": report.steps.iter().filter(|s| s.converged).count(),
            "cutbacks": report.cutbacks,
            "threads": rayon::current_num_threads(),
        },
        "version": env!("CARGO_PKG_VERSION"),
    });
    if interrupted {
        summary["solver"]["interrupted_at"] = serde_json::json!(match &solve {
            Err(SolveError::Interrupted { at }) => *at,
            _ => 0.0,
        });
    }
    sanitize(&mut summary);
    let error = solve.as_ref().err().map(|e| e.to_string());
    finish_recorders(
        &mut recorders,
        &RunEnd {
            converged,
            interrupted,
            error: error.as_deref(),
            steps: report.steps.iter().filter(|s| s.converged).count() as u64,
            wall_time_s: wall,
            summary: Some(&summary),
        },
    );
    write_json(&opts.out_dir.join("summary.json"), &summary)?;
    if scene.output.has(Sink::Csv) {
        write_solid_csv(&sys, &report, &opts.out_dir)?;
    }
    solve_outcome(
        solve,
        RunOutcome {
            summary,
            out_dir: opts.out_dir.clone(),
            converged,
            headline,
        },
    )
}

fn write_solid_csv(sys: &SolidSystem, report: &StepReport, dir: &Path) -> Result<(), OutputError> {
    if sys.model.mesh.rings.is_some() && sys.contact.is_none() {
        let prof = spinning::profile(sys);
        write_csv(
            &dir.join("profile.csv"),
            &["r", "u_r", "sigma_r", "sigma_theta", "sigma_r_theta"],
            prof.iter()
                .map(|p| vec![p.r, p.u_r, p.sigma_r, p.sigma_theta, p.sigma_r_theta]),
        )?;
    }
    if sys.contact.is_some() {
        tables::write_contact_csv(&dir.join("contact.csv"), &sys.contact_samples())?;
    }
    tables::write_nodes_csv(&dir.join("nodes.csv"), &sys.model.mesh, &sys.x)?;
    let mut rows = Vec::new();
    for (s, st) in report.steps.iter().enumerate() {
        for r in &st.table {
            let rp = r.residual_rel.get(1).copied().unwrap_or(0.0);
            let rh = r.residual_rel.get(2).copied().unwrap_or(0.0);
            rows.push(vec![
                s as f64,
                st.lambda,
                r.iteration as f64,
                r.residual_rel[0],
                rp,
                rh,
                r.increment_norm,
                r.alpha,
            ]);
        }
    }
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
        rows.into_iter(),
    )
}

/// Memory limit for [`check_memory`] set by `--max-memory` (bytes, 0: the machine's available
/// memory).
static MAX_MEMORY: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// Set the memory limit checked by [`check_memory`] (`--max-memory`).
pub fn set_max_memory(bytes: u64) {
    MAX_MEMORY.store(bytes, std::sync::atomic::Ordering::Relaxed);
}

/// The memory limit: `--max-memory`, else the available memory of the machine
/// (`MemAvailable` in /proc/meminfo), else none.
pub fn memory_limit() -> Option<u64> {
    let set = MAX_MEMORY.load(std::sync::atomic::Ordering::Relaxed);
    if set > 0 {
        return Some(set);
    }
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb.saturating_mul(1024))
}

/// Rough peak memory (bytes) of a scene's run, from the mesh size alone (computed in floating
/// point, so absurd sizes do not overflow): the mesh and state vectors, the sparse pattern and
/// values of the tangent (every cell couples its 2 (p+1)² displacement dofs and its pressures),
/// and the sparse L and U factors with 4 n log₂ n entries each (nested-dissection fill of a 2D
/// mesh: about 31/8 n log₂ n). Stick-slip has no mesh.
pub fn estimate_memory(scene: &Scene) -> f64 {
    if scene.analysis.mode == Mode::StickSlip {
        return 0.0;
    }
    let p = scene.mesh.order.max(1) as f64;
    let (nr, nt) = (scene.mesh.n_r as f64, scene.mesh.n_theta as f64);
    let nodes = (p * nr + 1.0) * (p * nt);
    let dofs = 2.0 * nodes;
    let cells = nr * nt;
    let nd = 2.0 * (p + 1.0) * (p + 1.0) + 3.0;
    let nnz = cells * nd * nd;
    let vectors = 40.0 * dofs * 8.0 + nodes * 64.0;
    let matrix = nnz * 16.0;
    let factor = 2.0 * 4.0 * dofs * dofs.max(2.0).log2() * 16.0;
    vectors + matrix + factor
}

/// Refuse a scene whose [`estimate_memory`] exceeds [`memory_limit`], before anything is
/// allocated.
pub fn check_memory(scene: &Scene) -> Result<(), AppError> {
    let need = estimate_memory(scene);
    let Some(limit) = memory_limit() else {
        return Ok(());
    };
    if need.is_finite() && need <= limit as f64 {
        return Ok(());
    }
    let gib = |b: f64| {
        let g = b / (1024.0 * 1024.0 * 1024.0);
        if g < 1e4 {
            format!("{g:.3}")
        } else {
            format!("{g:.2e}")
        }
    };
    Err(AppError::TooBig(format!(
        "the mesh n_r = {}, n_theta = {}, order = {} would need about {} GiB of memory, more than the {} GiB allowed ({}); use a coarser [mesh] or raise --max-memory",
        scene.mesh.n_r,
        scene.mesh.n_theta,
        scene.mesh.order,
        gib(need),
        gib(limit as f64),
        if MAX_MEMORY.load(std::sync::atomic::Ordering::Relaxed) > 0 {
            "--max-memory"
        } else {
            "available memory"
        }
    )))
}

/// Parse a memory size: bytes, or a number with K, M, G or T (powers of 1024), e.g. `2G`.
pub fn parse_memory(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let (num, mult) = match t.chars().last().map(|c| c.to_ascii_uppercase()) {
        Some('K') => (&t[..t.len() - 1], 1u64 << 10),
        Some('M') => (&t[..t.len() - 1], 1 << 20),
        Some('G') => (&t[..t.len() - 1], 1 << 30),
        Some('T') => (&t[..t.len() - 1], 1 << 40),
        _ => (t, 1),
    };
    let v: f64 = num
        .trim()
        .parse()
        .map_err(|_| format!("--max-memory {text:?}: expected bytes or a size like 512M, 2G"))?;
    if !(v.is_finite() && v > 0.0 && v * (mult as f64) < 1.8e19) {
        return Err(format!("--max-memory {text:?}: must be a positive size"));
    }
    Ok((v * mult as f64) as u64)
}
