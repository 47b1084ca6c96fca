//! The `tread` program: turn a validated [`Scene`] into a model, run its analysis, write the
//! outputs (summary.json, CSV) and report. [`run`] dispatches on the analysis mode to the
//! drivers; the translation of a scene into a model, options and sinks is [`crate::setup`]'s
//! (re-exported here), which the drivers use without depending on this module.
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

use crate::driver::envelope::{conclude, RunClock, RunEnvelope};
use crate::driver::indentation;
use crate::driver::results::{
    MeshInfo, ModeSummary, RunStats, SolidMesh, SolidResults, SolidSolver, SolidSummary, Summary,
    Terms,
};
use crate::driver::spinning;
use crate::driver::tables;
use crate::io::output::{ensure_dir, write_csv, OutputError};
use crate::io::record::Recorder;
use crate::io::scene::{Mode, Scene, Sink};
use crate::model::SolidSystem;
use crate::physics::PressureMode;
use crate::solver::stepping::StepReport;
use crate::solver::{LinearKind, SolveError};
use std::path::{Path, PathBuf};
use std::time::Instant;

pub use crate::driver::results::RunOutcome;
pub use crate::setup::{
    build_contact, build_material, build_material_spec, build_model, build_recorders, build_system,
    AppError, RunOptions,
};

/// Default output directory of a scene: `out/<scene name>/`.
pub fn default_out_dir(scene: &Scene) -> PathBuf {
    Path::new("out").join(&scene.scene.name)
}

/// Run a scene and write its outputs. A failed solve still writes every output (with the last
/// converged state) and returns `Err(AppError::Solve)`.
pub fn run(scene: &Scene, opts: &RunOptions) -> Result<RunOutcome, AppError> {
    if scene.mesh.is_3d() {
        return crate::driver::run3d::run(scene, opts);
    }
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
    let plan = crate::setup::solve_plan(scene, &sys).verbose(opts.verbose);
    let (kind, newton_opts, step_opts) = (plan.kind, plan.newton, plan.steps);
    let mut report = StepReport::default();
    let clock = RunClock {
        mesh: Some(&sys.model.mesh),
        time_name: "load_factor",
        time_end: 1.0,
    };
    let mut env = RunEnvelope::open(scene, opts, clock, Vec::new())?;
    let rec: &mut dyn Recorder = &mut env.recorders;
    let solve = match scene.analysis.mode {
        Mode::Static => {
            sys.loading = crate::setup::scene_loading(scene);
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
            SolidResults::Static(r)
        }
        _ => {
            let r = spinning::results(&sys);
            headline.push(format!(
                "omega = {:.6} rad/s: u_r(outer) = {:.6e}, sigma_r(inner) = {:.6e}, sigma_theta(inner) = {:.6e}, sigma_theta(outer) = {:.6e}",
                r.omega, r.u_r_outer, r.sigma_r_inner, r.sigma_theta_inner, r.sigma_theta_outer
            ));
            SolidResults::Spinning(r)
        }
    };
    let friction = sys.contact.as_ref().is_some_and(|c| c.friction.is_active());
    let linear = if report.switched_to_lu {
        LinearKind::Lu
    } else {
        kind
    };
    let typed = Summary::new(
        &scene.scene.name,
        scene.analysis.mode.to_string(),
        sys.n_dofs(),
        converged,
        ModeSummary::Solid(SolidSummary {
            run: RunStats {
                newton_iterations: report.total_iterations,
                wall_time_s: wall,
                error: solve.as_ref().err().map(|e| e.to_string()),
            },
            results,
            terms: Terms {
                friction,
                normal_damping: false,
                inertia: scene.analysis.mode == Mode::Spinning,
                history: false,
                pressure: !matches!(sys.model.pressure, PressureMode::None),
                contact_facets_per_iteration: sys.mean_facets_per_assembly(),
            },
            mesh: SolidMesh {
                common: MeshInfo {
                    n_r: scene.mesh.n_r,
                    n_theta: scene.mesh.n_theta,
                    order: scene.mesh.order,
                    nodes: sys.model.mesh.n_nodes(),
                    cells: sys.model.mesh.n_cells(),
                },
                pressure_dofs: sys.dofs.per_cell * sys.model.mesh.n_cells(),
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
                coarse_start: None,
            },
        }),
    );
    let error = solve.as_ref().err().map(|e| e.to_string());
    let steps = report.steps.iter().filter(|s| s.converged).count() as u64;
    let summary = env.finish(&typed, steps, wall, error.as_deref(), interrupted)?;
    if scene.output.has(Sink::Csv) {
        write_solid_csv(&sys, &report, &opts.out_dir)?;
    }
    conclude(
        solve,
        RunOutcome {
            summary,
            typed,
            field: None,
            history: None,
            contact: sys.contact_samples(),
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
    if scene.mesh.is_3d() {
        return estimate_memory_3d(scene);
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

/// [`estimate_memory`] of a three-dimensional scene: the generated wheel's nodes
/// (p n_r + 1)(p n_θ)(p n_z + 1), three dofs each, every cell coupling its 3 (p+1)³ + 4 dofs,
/// and sparse L and U factors with 8 n^{4/3} entries each (nested-dissection fill of a 3D
/// mesh). A mesh file's size is not known before it is read (the reader bounds the file).
fn estimate_memory_3d(scene: &Scene) -> f64 {
    if scene.mesh.file.is_some() {
        return 0.0;
    }
    let p = scene.mesh.order.max(1) as f64;
    let (nr, nt, nz) = (
        scene.mesh.n_r as f64,
        scene.mesh.n_theta as f64,
        scene.mesh.resolved_n_z() as f64,
    );
    let nodes = (p * nr + 1.0) * (p * nt) * (p * nz + 1.0);
    let dofs = 3.0 * nodes;
    let cells = nr * nt * nz;
    let nd = 3.0 * (p + 1.0).powi(3) + 4.0;
    let matrix = cells * nd * nd * 16.0;
    let vectors = 40.0 * dofs * 8.0 + nodes * 96.0;
    let factor = 2.0 * 8.0 * dofs.powf(4.0 / 3.0) * 16.0;
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
    let n_z = if scene.mesh.is_3d() {
        format!(", n_z = {}", scene.mesh.resolved_n_z())
    } else {
        String::new()
    };
    Err(AppError::TooBig(format!(
        "the mesh n_r = {}, n_theta = {}{n_z}, order = {} would need about {} GiB of memory, more than the {} GiB allowed ({}); use a coarser [mesh] or raise --max-memory",
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

/// Every check a run makes before it solves, without solving or writing anything: the memory
/// estimate, the mesh (generated, or read from `mesh.file` and checked cell by cell), the material
/// and its mode, and the road contact of a static scene. `tread check` runs this, so that a scene
/// it passes is refused by `tread run` only by the solve itself; `tread run` runs it before it
/// creates the output folder.
pub fn preflight(scene: &Scene) -> Result<(), AppError> {
    check_memory(scene)?;
    if scene.analysis.mode == Mode::StickSlip {
        return Ok(());
    }
    if scene.mesh.is_3d() {
        let mesh = crate::setup::build_hex_mesh(scene)?;
        if scene.analysis.mode == Mode::Static {
            crate::setup::build_contact_3d(scene, &mesh)?;
        }
        return Ok(());
    }
    let model = crate::setup::build_model(scene)?;
    if scene.analysis.mode == Mode::Static {
        crate::setup::build_contact(scene, &model)?;
    }
    Ok(())
}

/// Refuse a three-dimensional scene in a command that runs the plane-strain program only
/// (`command`, e.g. "adapt"): exit status 2.
pub fn refuse_3d(scene: &Scene, command: &str) -> Result<(), AppError> {
    if scene.mesh.is_3d() {
        return Err(AppError::Unsupported(format!(
            "mesh.dimension = 3: `tread {command}` runs plane-strain scenes only; three-dimensional \
             scenes run with `tread run` (modes \"static\" and \"spinning\")"
        )));
    }
    Ok(())
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

/// Worker stack size of the thread pool the commands run in (the main thread's usual 8 MiB
/// and more: only the pages touched are committed).
pub const WORKER_STACK: usize = 64 << 20;

/// Run `f` on a worker of a thread pool of `threads` threads (0: `RAYON_NUM_THREADS` or the
/// number of cores). The parallel loops inside (assembly, LU, Krylov products) then start on
/// a worker of their own pool: run from the main thread instead, each one hands its work to
/// the pool and sleeps until it is done. Measured by `tread-bench-eval` on the damped default
/// scene at 65,536 DOFs (medians of 21): one residual-and-tangent assembly takes 0.060 s on a
/// worker against 0.061 s from the main thread with one thread, 0.039 against 0.052 s with two;
/// one damping-correction product 2.2 against 3.7 ms with one thread. (The batched assembly
/// of large elements, one hand-over per 256 cells, took 0.068–0.087 s from the main thread.)
/// Without a pool (it cannot be made), `f` runs here.
pub fn in_pool<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> R {
    match rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .stack_size(WORKER_STACK)
        .build()
    {
        Ok(pool) => pool.install(f),
        Err(e) => {
            eprintln!("tread: warning: cannot set up the thread pool: {e}");
            f()
        }
    }
}
