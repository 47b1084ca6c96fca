//! The `tread` program: turn a validated [`Scene`] into a model, run its analysis, write the
//! outputs (summary.json, CSV) and report.
//!
//! Output files in the run directory:
//! * `summary.json` — always written, also when the solve fails (then `converged = false`,
//!   `error` says why and `results` hold the last converged load step);
//! * `profile.csv` — ring averages of u_r, σ_r, σ_θ, σ_rθ at the radial Gauss points;
//! * `nodes.csv` — reference position and displacement of every node;
//! * `convergence.csv` — the Newton convergence table of every load step.

use crate::driver::spinning::{self, SpinningResults};
use crate::driver::SolidSystem;
use crate::io::output::{ensure_dir, sanitize, write_csv, write_json, OutputError};
use crate::io::scene::{Formulation, LinearChoice, MaterialParams, Mode, Scene};
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
}

#[derive(Clone, Debug)]
pub struct RunOptions {
    pub out_dir: PathBuf,
    /// Print the Newton convergence table.
    pub verbose: bool,
}

/// Default output directory of a scene: `out/<scene name>/`.
pub fn default_out_dir(scene: &Scene) -> PathBuf {
    Path::new("out").join(&scene.scene.name)
}

/// Material law and pressure treatment of a scene.
pub fn build_material(scene: &Scene) -> Result<(Material, PressureMode), AppError> {
    let params = scene.material.params().ok_or_else(|| {
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
    let ms = &scene.mesh;
    let (material, pressure) = build_material(scene)?;
    if !matches!(pressure, PressureMode::None) && ms.order != 2 {
        return Err(AppError::Unsupported(format!(
            "mesh.order = {}: incompressible materials need order = 2 (Q2 displacements with P1 pressures)",
            ms.order
        )));
    }
    let mesh = annulus(&AnnulusSpec {
        ri: scene.geometry.ri,
        ro: scene.geometry.ro,
        n_r: ms.n_r,
        n_theta: ms.n_theta,
        degree: ms.order,
        grading_r: ms.grading_r,
        grading_theta: ms.grading_theta,
    });
    let model = SolidModel::new(mesh, material, scene.material.rho, pressure);
    Ok(SolidSystem::new(model, "hub"))
}

fn linear_kind(scene: &Scene, sys: &SolidSystem) -> LinearKind {
    match scene.solver.linear {
        LinearChoice::Cholesky => LinearKind::Cholesky,
        LinearChoice::Lu => LinearKind::Lu,
        LinearChoice::Auto => {
            if matches!(sys.model.pressure, PressureMode::Exact { .. }) {
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
    pub results: SpinningResults,
}

/// Run a scene and write its outputs. A failed solve still writes every output (with the last
/// converged state) and returns `Err(AppError::Solve)`.
pub fn run(scene: &Scene, opts: &RunOptions) -> Result<RunOutcome, AppError> {
    let t0 = Instant::now();
    ensure_dir(&opts.out_dir)?;
    let mut sys = build_system(scene)?;
    let kind = linear_kind(scene, &sys);
    let newton_opts = NewtonOptions {
        tol: scene.solver.tolerance,
        max_iterations: scene.solver.max_iterations,
        line_search: scene.solver.line_search,
        verbose: opts.verbose,
        ..Default::default()
    };
    let step_opts = StepOptions {
        initial_steps: scene.solver.load_steps,
        max_cutbacks: scene.solver.max_cutbacks,
        verbose: opts.verbose,
    };
    let mut report = StepReport::default();
    let solve = match scene.analysis.mode {
        Mode::Spinning => spinning::solve_spinning(
            &mut sys,
            scene.motion.omega,
            kind,
            newton_opts,
            &step_opts,
            &mut report,
        ),
    };
    let wall = t0.elapsed().as_secs_f64();
    let res = spinning::results(&sys);
    let converged = solve.is_ok();
    let mut summary = serde_json::json!({
        "scene": scene.scene.name,
        "mode": scene.analysis.mode.to_string(),
        "dofs": sys.n_dofs(),
        "newton_iterations": report.total_iterations,
        "wall_time_s": wall,
        "converged": converged,
        "error": solve.as_ref().err().map(|e| e.to_string()),
        "results": res,
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
    sanitize(&mut summary);
    write_json(&opts.out_dir.join("summary.json"), &summary)?;
    if scene.output.csv {
        let prof = spinning::profile(&sys);
        write_csv(
            &opts.out_dir.join("profile.csv"),
            &["r", "u_r", "sigma_r", "sigma_theta", "sigma_r_theta"],
            prof.iter()
                .map(|p| vec![p.r, p.u_r, p.sigma_r, p.sigma_theta, p.sigma_r_theta]),
        )?;
        let m = &sys.model.mesh;
        write_csv(
            &opts.out_dir.join("nodes.csv"),
            &["node", "X1", "X2", "u1", "u2"],
            (0..m.n_nodes()).map(|n| {
                vec![
                    n as f64,
                    m.nodes[n][0],
                    m.nodes[n][1],
                    sys.x[2 * n],
                    sys.x[2 * n + 1],
                ]
            }),
        )?;
        let mut rows = Vec::new();
        for (s, st) in report.steps.iter().enumerate() {
            for r in &st.table {
                let rp = r.residual_rel.get(1).copied().unwrap_or(0.0);
                rows.push(vec![
                    s as f64,
                    st.lambda,
                    r.iteration as f64,
                    r.residual_rel[0],
                    rp,
                    r.increment_norm,
                    r.alpha,
                ]);
            }
        }
        write_csv(
            &opts.out_dir.join("convergence.csv"),
            &[
                "step",
                "load_factor",
                "iteration",
                "residual_u_rel",
                "residual_p_rel",
                "increment_norm",
                "alpha",
            ],
            rows.into_iter(),
        )?;
    }
    match solve {
        Ok(()) => Ok(RunOutcome {
            summary,
            out_dir: opts.out_dir.clone(),
            converged,
            results: res,
        }),
        Err(e) => Err(AppError::Solve(e, opts.out_dir.clone())),
    }
}
