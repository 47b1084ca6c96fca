//! The nested iteration of the steady solve (`[solver] coarse_start`): the steady state of the
//! mesh with half the cells in r and θ, solved first (in turn from its own coarser mesh),
//! interpolated to the scene's mesh as Newton's start there. With a second worker in the thread
//! pool each mesh of the hierarchy is built, and its matrix analysed, while the next coarser one
//! is solved ([`build_steady_nested`]).
//!
//! The solve of each coarse mesh is the steady mode's first solve
//! ([`super::steady_solve::solve_steady_from`]); it is passed in as a function so that this
//! module does not import its caller.

use super::steady::{build_steady, press_once, SteadyRolling};
use super::steady_report::{CoarseStart, SolveReports, SteadyFailure};
use crate::io::record::Recorder;
use crate::io::scene::Scene;
use crate::model::SolidSystem;
use crate::setup::AppError;
use crate::solver::stepping::StepReport;
use crate::solver::{LinearKind, NonlinearSystem, SolveError, SparseSolver};
use std::time::Instant;

/// The steady mode's first solve, from an optional coarse state solved ahead.
pub type SolveFn = fn(
    &Scene,
    &mut SteadyRolling,
    Option<CoarseSolved>,
    bool,
    &mut StepReport,
    &mut dyn Recorder,
) -> Result<SolveReports, SteadyFailure>;

/// How a coarse mesh's system is built: with its own coarse state solved ahead, or not.
type BuildFn = fn(&Scene, SolveFn) -> Result<(SteadyRolling, Option<CoarseSolved>), AppError>;

fn build_alone(
    scene: &Scene,
    _solve: SolveFn,
) -> Result<(SteadyRolling, Option<CoarseSolved>), AppError> {
    build_steady(scene).map(|st| (st, None))
}

/// A coarser mesh's steady state for the nested iteration's coarse start: its system (or why
/// it could not be built), the report and outcome of its solve, and the wall times of its
/// set-up and solve.
pub struct CoarseSolved {
    system: Result<Box<SteadyRolling>, String>,
    report: StepReport,
    solved: Result<SolveReports, SteadyFailure>,
    setup_s: f64,
    solve_s: f64,
}

/// The scene on the mesh with half the cells in r and in θ, when [`coarse_start`] applies:
/// `[solver] coarse_start`, a generated annulus with n_r even ≥ 4 and n_theta a multiple of 4
/// ≥ 64 (the coarse mesh keeps n_theta even and ≥ 32).
fn coarse_scene(scene: &Scene) -> Option<Scene> {
    let m = &scene.mesh;
    let applies = scene.solver.coarse_start
        && m.file.is_none()
        && m.n_r >= 4
        && m.n_r.is_multiple_of(2)
        && m.n_theta >= 64
        && m.n_theta.is_multiple_of(4);
    applies.then(|| {
        let mut c = scene.clone();
        c.mesh.n_r /= 2;
        c.mesh.n_theta /= 2;
        c
    })
}

/// Nested iteration: solve the steady state on the mesh with half the cells in r and θ (by
/// [`solve_steady`], so that mesh starts from its own coarser one in turn), interpolate its
/// displacements (and the road height under load control) to this mesh's nodes, and take
/// Newton at full load from there (one load step, no cut-back). Most of the Newton iterations
/// of a press-in from the undeformed state are spent finding the contact patch with damped
/// steps; on the coarse mesh they are cheap, and from the interpolated state Newton on the
/// fine mesh converges in a few full steps. `None` when it does not apply (see
/// [`coarse_scene`]; also without contact or with cell-owned pressures); otherwise what it
/// did. On failure the state is left for the caller to restore.
#[allow(clippy::too_many_arguments)]
pub(super) fn coarse_start(
    scene: &Scene,
    st: &mut SteadyRolling,
    ahead: Option<CoarseSolved>,
    solve: SolveFn,
    verbose: bool,
    report: &mut StepReport,
    rec: &mut dyn Recorder,
) -> Result<Option<CoarseStart>, SolveError> {
    let Some(coarse) = coarse_scene(scene) else {
        return Ok(None);
    };
    if st.sys.contact.is_none() || st.sys.dofs.per_cell != 0 {
        return Ok(None);
    }
    let name = format!("{}x{}", coarse.mesh.n_r, coarse.mesh.n_theta);
    let mut out = CoarseStart::default();
    let CoarseSolved {
        system,
        report: crep,
        solved,
        setup_s,
        solve_s,
    } = match ahead {
        Some(c) => c,
        None => {
            // With a second worker in the pool, this mesh's symbolic analysis runs alongside
            // the coarse solve (it depends on the sparsity only). One thread makes it after
            // the coarse system is freed, as Newton does: made before, it would add its work
            // arrays to the coarse system's memory (262k DOFs: 5 % more peak memory).
            let kind = st.plan.kind;
            let sys = &st.sys;
            let (c, analysed) = if rayon::current_num_threads() > 1 {
                rayon::join(
                    || solve_coarse(&coarse, build_alone, solve),
                    || analyse(sys, kind),
                )
            } else {
                (solve_coarse(&coarse, build_alone, solve), None)
            };
            st.analysed = analysed;
            c
        }
    };
    let cst = match system {
        Ok(c) => c,
        Err(e) => {
            out.meshes.push(name);
            out.error = Some(format!(
                "the {} mesh could not be built: {e}",
                out.meshes[0]
            ));
            return Ok(Some(out));
        }
    };
    // The coarser meshes' time leaves out this mesh's analysis, which one thread makes after
    // the coarse solve (and more threads alongside it).
    let mut coarse_s = setup_s + solve_s;
    let inner = match &solved {
        Ok(r) => r,
        Err(f) => &*f.reports,
    };
    if let Some(inner) = &inner.coarse_start {
        out.meshes = inner.meshes.clone();
        out.coarse_newton_iterations = inner.coarse_newton_iterations;
    }
    out.meshes.push(name);
    out.coarse_newton_iterations += crep.total_iterations
        + inner.recovery_iterations()
        + inner
            .eps_continuation
            .as_ref()
            .map_or(0, |a| a.newton_iterations);
    if let Err(f) = solved {
        let e = f.error;
        if let SolveError::Interrupted { .. } = e {
            return Err(e);
        }
        out.coarse_wall_time_s = coarse_s;
        out.error = Some(format!(
            "the solve on the {} mesh failed: {e}",
            out.meshes.last().map_or("", |m| m.as_str())
        ));
        return Ok(Some(out));
    }
    let t1 = Instant::now();
    interpolate_state(&cst.sys, &mut st.sys);
    // The coarse system (its matrix, factors, work vectors) is not needed any more: free it
    // before the fine mesh's factorization.
    drop(cst);
    coarse_s += t1.elapsed().as_secs_f64();
    out.coarse_wall_time_s = coarse_s;
    if verbose {
        eprintln!(
            "  started from the steady state on the {} mesh ({} Newton iterations, {:.3} s)",
            out.meshes.join(" -> "),
            out.coarse_newton_iterations,
            out.coarse_wall_time_s
        );
    }
    let mut frep = StepReport::default();
    let res = press_once(scene, st, verbose, &mut frep, rec);
    out.newton_iterations = frep.total_iterations;
    match res {
        Ok(()) => {
            out.succeeded = true;
            report.steps.extend(frep.steps);
            report.total_iterations += frep.total_iterations;
        }
        Err(e @ SolveError::Interrupted { .. }) => return Err(e),
        Err(e) => {
            if verbose {
                eprintln!("  Newton from the interpolated state failed ({e}): pressing in from the undeformed state");
            }
            out.error = Some(format!("Newton from the interpolated state: {e}"));
        }
    }
    Ok(Some(out))
}

/// Build the `coarse` scene's steady system with `build` and solve it (silently, by
/// `solve`: it starts from its own coarser mesh in turn).
fn solve_coarse(coarse: &Scene, build: BuildFn, solve: SolveFn) -> CoarseSolved {
    let t0 = Instant::now();
    let mut report = StepReport::default();
    let (mut cst, ahead) = match build(coarse, solve) {
        Ok(c) => c,
        Err(e) => {
            return CoarseSolved {
                system: Err(e.to_string()),
                report,
                solved: Ok(SolveReports::default()),
                setup_s: t0.elapsed().as_secs_f64(),
                solve_s: 0.0,
            }
        }
    };
    let setup_s = t0.elapsed().as_secs_f64();
    let t = Instant::now();
    let solved = solve(coarse, &mut cst, ahead, false, &mut report, &mut ());
    CoarseSolved {
        system: Ok(Box::new(cst)),
        report,
        solved,
        setup_s,
        solve_s: t.elapsed().as_secs_f64(),
    }
}

/// The symbolic analysis of `sys`'s matrix for a `kind` solver and its wall time (`None` if
/// it fails: Newton then makes and reports it).
fn analyse(sys: &SolidSystem, kind: LinearKind) -> Option<(SparseSolver, f64)> {
    let t = Instant::now();
    let (cp, ri) = sys.pattern();
    SparseSolver::new(sys.n_eq(), cp, ri, kind)
        .ok()
        .map(|s| (s, t.elapsed().as_secs_f64()))
}

/// [`build_steady`], and with more than one thread and a nested iteration ahead
/// ([`coarse_start`]) the coarser mesh's steady state solved in the same time (on the other
/// workers; it is built the same way, so each mesh of the hierarchy is built while the next
/// coarser one is solved), together with this system's symbolic analysis. With one thread, as
/// [`build_steady`]: the coarse solve then runs from the steady solve
/// ([`super::steady_solve::solve_steady`]), before the analysis. `solve` is that solve.
pub fn build_steady_nested(
    scene: &Scene,
    solve: SolveFn,
) -> Result<(SteadyRolling, Option<CoarseSolved>), AppError> {
    let coarse = match coarse_scene(scene) {
        Some(c)
            if rayon::current_num_threads() > 1
                && scene.road.is_some()
                && scene.contact.is_some() =>
        {
            c
        }
        _ => return build_alone(scene, solve),
    };
    let (built, ahead) = rayon::join(
        || {
            build_steady(scene).map(|mut st| {
                st.analysed = analyse(&st.sys, st.plan.kind);
                st
            })
        },
        || solve_coarse(&coarse, build_steady_nested, solve),
    );
    let st = built?;
    let ahead = (st.sys.contact.is_some() && st.sys.dofs.per_cell == 0).then_some(ahead);
    Ok((st, ahead))
}

/// Interpolate the displacements of `from` (another mesh of the same body) at the nodes of
/// `to`, and copy its global unknowns (the road height under load control); fixed dofs of
/// `to` keep their values.
fn interpolate_state(from: &SolidSystem, to: &mut SolidSystem) {
    use crate::assembly::CONSTRAINED;
    use crate::mesh::locate::{locate_points, vector_at};
    let src = &from.model.mesh;
    let mut x = to.x.clone();
    let found = locate_points(src, &to.model.mesh.nodes);
    for (a, &(c, xi, eta)) in found.iter().enumerate() {
        let u = vector_at(src, &from.x, c, xi, eta);
        for (i, &ui) in u.iter().enumerate() {
            if to.dofs.eq[2 * a + i] < CONSTRAINED {
                x[2 * a + i] = ui;
            }
        }
    }
    for k in 0..to.dofs.n_global.min(from.dofs.n_global) {
        x[to.dofs.global(k)] = from.x[from.dofs.global(k)];
    }
    to.restore_state(&x);
}
