//! Driver of the `steady` mode ([`super::steady`]): build the scene's model in the
//! θ-referential description, press the road in at the scene's ω and v0, optionally follow the
//! branch by arc-length continuation (`[continuation]`), and write the outputs.
//!
//! summary.json `results` has the keys of the transient mode (`steady`, `time_to_steady` = 0,
//! `revolutions` = 0, `steps`, `hub_force_x`, `hub_force_y`, `hub_torque`, `contact_x_min`,
//! `contact_x_max`, `max_pressure`, `contact_force_x`, `contact_force_y`, `contact_centroid`,
//! `contact_half_width_moment`) for the final state, plus `omega`, `v0`, `penetration`, and,
//! with continuation, `branch` (one row per converged point, as `branch.csv`),
//! `special_points` (limit and bifurcation points with their estimated parameter) and
//! `continuation` (stop reason, counts). `solver.recovery` is null, or the
//! [`super::steady_recovery::Recovery`] report when the press-in failed and recoveries were
//! tried (then a line `tread: recovered: …` or `tread: the steady solve failed …` goes to
//! stderr); after a successful recovery `results.steps` counts its steps (press at the benign
//! values and homotopy steps) instead of the failed press's.
//!
//! Files: `steady_field.csv` (same format as the transient mode's, see
//! [`super::transient_run`]: `ring, pos, X1, X2, u1, u2` per referential node), `contact.csv`,
//! `nodes.csv`, `branch.csv` (continuation) and, with the `png` sink, `branch.png` and
//! `contact.png`, and with `[output] snapshot_omegas` (continuation in ω) the deformed shapes
//! `shape_omega_<ω>.png` and `shape_montage.png` ([`crate::io::record::shape`]). Recorder steps: the load steps of the pressing stage (time = load factor in
//! [0, 1]), then one per continuation point (time = the continuation parameter, as in
//! `branch.csv`).

use super::envelope::{conclude, RunClock, RunEnvelope};
use super::frame::SolidFrame;
use super::resistance;
pub use super::results::{BranchRow, ControlReport};
use super::results::{
    ContinuationSummary, MeshInfo, ModeSummary, RunStats, SteadyResults, SteadySolver,
    SteadySummary, SteadyTerms, Summary, Terms,
};
pub use super::steady::{build_steady, press_once, steady_on, BANDED_MIN_EQUATIONS};
use super::steady::{step_parameter, SteadyParameter, SteadyRolling};
pub use super::steady_solve::{
    apply_control, build_nested, solve_steady, solve_steady_from, TORQUE_RTOL,
};
use super::tables;
use crate::contact::ContactModel;
use crate::driver::results::RunOutcome;
use crate::io::output::{ensure_dir, write_csv};
use crate::io::record::shape::ShapeSnapshots;
use crate::io::record::{self, Recorder, StepInfo};
use crate::io::scene::{
    ContinuationParameter, ContinuationSpec, Control, DampingTangentChoice, Scene, Sink,
};
use crate::model::system::{SolidSystem, SteadyDampingTangent};
pub use crate::setup::scene_loading;
use crate::setup::{AppError, RunOptions};
use crate::solver::continuation::{
    BranchPoint, Continuation, ContinuationOptions, ContinuationReport, PointKind,
};
use crate::solver::linear::{write_matrix_market, write_vector_market};
use crate::solver::stepping::StepReport;
use crate::solver::{LinearKind, Newton, NonlinearSystem, SolveError};
use std::path::{Path, PathBuf};
use std::time::Instant;

fn branch_row(st: &SteadyRolling, p: &BranchPoint) -> BranchRow {
    let t = ContactModel::totals(&st.sys.contact_samples());
    let (f, m) = st.sys.hub_reaction();
    BranchRow {
        step: p.step,
        lambda: p.lambda,
        omega: st.omega(),
        v0: st.v0(),
        penetration: st.penetration(),
        hub_force_x: f[0],
        hub_force_y: f[1],
        hub_torque: m,
        contact_x_min: t.x_min,
        contact_x_max: t.x_max,
        max_pressure: t.max_pressure,
        wave_amplitude: wave_amplitude(&st.sys),
        wave_number: wave_number(&st.sys),
        det_sign: p.det_sign,
        negative_eigenvalues: p.negative_eigenvalues,
        test_function: p.test_function,
        iterations: p.iterations,
        kind: p.kind,
        wall_time_s: p.wall_time_s,
        factor_solve_s: p.factor_solve_s,
        creep: st.creep(),
    }
}

/// Continuation in the creep: natural-parameter steps Δξ = ds · |target − start| from the
/// current creep to `opts.target` (the creep–force curve is single-valued in ξ), each a Newton
/// solve from the previous point with step halving on failure ([`step_parameter`]). `observe`
/// sees every converged point (return false to stop). On failure the points so far are left in
/// `partial`.
fn creep_sweep(
    st: &mut SteadyRolling,
    opts: &ContinuationOptions,
    partial: &mut Option<ContinuationReport>,
    observe: &mut dyn FnMut(&SteadyRolling, &BranchPoint) -> bool,
) -> Result<ContinuationReport, SolveError> {
    use crate::solver::continuation::ParametricSystem;
    let newton_opts = st.plan.verbose(opts.verbose).newton;
    let mut newton = Newton::new(st, LinearKind::Lu, newton_opts)?;
    let start = st.parameter();
    let span = opts.target - start;
    let dxi = (opts.ds0 * span.abs()).max(f64::MIN_POSITIVE);
    let n = ((span.abs() / dxi).ceil() as usize).clamp(1, opts.max_steps.max(1));
    let mut rep = ContinuationReport::default();
    let point = |step: usize, lambda: f64, iterations: usize, wall: f64| BranchPoint {
        step,
        lambda,
        kind: if step == 0 {
            PointKind::Start
        } else {
            PointKind::Regular
        },
        iterations,
        cutbacks: 0,
        ds: if step == 0 {
            0.0
        } else {
            span.abs() / n as f64
        },
        dlambda_ds: f64::NAN,
        det_sign: f64::NAN,
        log_abs_det: f64::NAN,
        negative_eigenvalues: f64::NAN,
        test_function: f64::NAN,
        wall_time_s: wall,
        factor_solve_s: f64::NAN,
    };
    let p0 = point(0, start, 0, 0.0);
    let go_on = observe(st, &p0);
    rep.points.push(p0);
    if !go_on {
        rep.stop_reason = "stopped by the observer".into();
        return Ok(rep);
    }
    for k in 1..=n {
        let xi = if k == n {
            opts.target
        } else {
            start + span * k as f64 / n as f64
        };
        let t = Instant::now();
        match step_parameter(st, xi, &mut newton, opts.max_cutbacks) {
            Ok(it) => {
                rep.total_iterations += it;
                let p = point(k, st.parameter(), it, t.elapsed().as_secs_f64());
                let go_on = observe(st, &p);
                rep.points.push(p);
                if !go_on {
                    rep.stop_reason = "stopped by the observer".into();
                    return Ok(rep);
                }
            }
            Err(e) => {
                rep.stop_reason = format!("the Newton solve failed at creep {xi:.6e}: {e}");
                *partial = Some(rep);
                return Err(e);
            }
        }
    }
    rep.stop_reason = "target reached".into();
    Ok(rep)
}

/// Half the peak-to-peak radial displacement of the outer-ring nodes whose reference angle is
/// more than 60° from the bottom (θ = −π/2): standing waves around the cylinder show here,
/// the contact flattening does not.
pub fn wave_amplitude(sys: &SolidSystem) -> f64 {
    let mesh = &sys.model.mesh;
    let Some(rl) = mesh.rings else {
        return f64::NAN;
    };
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let last = rl.rings - 1;
    for pos in 0..rl.per_ring {
        let n = last * rl.per_ring + pos;
        let x = mesh.nodes[n];
        let th = x[1].atan2(x[0]);
        let d = (th + std::f64::consts::FRAC_PI_2).rem_euclid(2.0 * std::f64::consts::PI);
        let d = d.min(2.0 * std::f64::consts::PI - d);
        if d < std::f64::consts::PI / 3.0 {
            continue;
        }
        let ur = (sys.x[2 * n] * x[0] + sys.x[2 * n + 1] * x[1]) / x.norm();
        lo = lo.min(ur);
        hi = hi.max(ur);
    }
    0.5 * (hi - lo)
}

/// Report a converged branch point to the recorders (`/tread/continuation` in MCAP,
/// `branch/<measure>` and the `omega` timeline in Rerun, the PNG sink's branch data), before
/// the body at that point is recorded as a step. (The steady mode then draws its own
/// `branch.png` over the PNG sink's, with one panel per hub load and the wave amplitude.)
fn record_branch_point(
    rec: &mut dyn Recorder,
    n0: u64,
    parameter_name: &str,
    arc_length: f64,
    p: &BranchPoint,
    row: &BranchRow,
) {
    let measures = [
        ("hub_force_x", row.hub_force_x),
        ("hub_force_y", row.hub_force_y),
        ("hub_torque", row.hub_torque),
        ("max_pressure", row.max_pressure),
        ("wave_amplitude", row.wave_amplitude),
        ("wave_number", row.wave_number),
    ];
    rec.continuation_point(&record::ContinuationPoint {
        index: n0 + p.step as u64,
        parameter_name,
        parameter: p.lambda,
        arc_length,
        newton_iterations: p.iterations,
        det_sign: if p.det_sign > 0.0 {
            1
        } else if p.det_sign < 0.0 {
            -1
        } else {
            0
        },
        kind: match p.kind {
            PointKind::Start | PointKind::Regular => record::PointKind::Regular,
            PointKind::LimitPoint => record::PointKind::LimitPoint,
            PointKind::Bifurcation => record::PointKind::Bifurcation,
            PointKind::Switched | PointKind::Jump => record::PointKind::Regular,
        },
        measures: &measures,
    });
}

/// Dominant circumferential wave number of the standing waves, from the outer-ring nodes more
/// than 60° from the bottom (the arc of [`wave_amplitude`]): the radial displacement less its
/// least-squares fit by the orders 0 to 3 over the arc (the ovalisation of the pressed ring),
/// a Hann window `w` over the arc, and the spectrum `A(n) = |∫ w r e^{−i n θ} dθ| / (½ ∫ w dθ)`
/// of that rest `r` for the whole numbers `n` from 4 to `per_ring / 4` (four Q2 nodes per
/// wavelength, what the mesh resolves); the `n` of the largest `A(n)`. NaN on a mesh without
/// rings or with too few nodes on the arc.
pub fn wave_number(sys: &SolidSystem) -> f64 {
    use std::f64::consts::{FRAC_PI_2, PI};
    let mesh = &sys.model.mesh;
    let Some(rl) = mesh.rings else {
        return f64::NAN;
    };
    let last = rl.rings - 1;
    // (angle from the bottom in (π/3, 5π/3), u_r), sorted by angle.
    let mut pts: Vec<(f64, f64)> = Vec::new();
    for pos in 0..rl.per_ring {
        let n = last * rl.per_ring + pos;
        let x = mesh.nodes[n];
        let d = (x[1].atan2(x[0]) + FRAC_PI_2).rem_euclid(2.0 * PI);
        if !(PI / 3.0..=5.0 * PI / 3.0).contains(&d) {
            continue;
        }
        pts.push((
            d,
            (sys.x[2 * n] * x[0] + sys.x[2 * n + 1] * x[1]) / x.norm(),
        ));
    }
    let n_max = rl.per_ring / 4;
    if pts.len() < 8 || n_max < 4 {
        return f64::NAN;
    }
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (a0, a1) = (pts[0].0, pts[pts.len() - 1].0);
    // Trapezoidal weights in θ times the Hann window.
    let k = pts.len();
    let w: Vec<f64> = (0..k)
        .map(|i| {
            let lo = if i > 0 { pts[i - 1].0 } else { pts[i].0 };
            let hi = if i + 1 < k { pts[i + 1].0 } else { pts[i].0 };
            let hann = (PI * (pts[i].0 - a0) / (a1 - a0)).sin().powi(2);
            0.5 * (hi - lo) * hann
        })
        .collect();
    let wsum: f64 = w.iter().sum();
    // Remove the orders 0 to 3 by a least-squares fit over the arc (trapezoidal weights, no
    // window): on a 240° arc the window's main lobe is 3 orders wide, so the large low-order
    // shape of the pressed ring would otherwise leak into n = 4 and 5.
    let basis = |th: f64| -> [f64; 7] {
        let mut b = [1.0; 7];
        for m in 1..=3 {
            let (s, c) = (m as f64 * th).sin_cos();
            b[2 * m - 1] = c;
            b[2 * m] = s;
        }
        b
    };
    let mut ata = nalgebra::SMatrix::<f64, 7, 7>::zeros();
    let mut atb = nalgebra::SVector::<f64, 7>::zeros();
    for (i, p) in pts.iter().enumerate() {
        let lo = if i > 0 { pts[i - 1].0 } else { p.0 };
        let hi = if i + 1 < k { pts[i + 1].0 } else { p.0 };
        let q = 0.5 * (hi - lo);
        let b = nalgebra::SVector::<f64, 7>::from(basis(p.0));
        ata += b * b.transpose() * q;
        atb += b * (q * p.1);
    }
    let Some(coef) = ata.lu().solve(&atb) else {
        return f64::NAN;
    };
    let rest: Vec<f64> = pts
        .iter()
        .map(|p| p.1 - nalgebra::SVector::<f64, 7>::from(basis(p.0)).dot(&coef))
        .collect();
    let (mut best, mut best_a) = (f64::NAN, -1.0);
    for n in 4..=n_max {
        let (mut re, mut im) = (0.0, 0.0);
        for ((p, wi), r) in pts.iter().zip(&w).zip(&rest) {
            let (s, c) = (n as f64 * p.0).sin_cos();
            re += wi * r * c;
            im += wi * r * s;
        }
        let a = (re * re + im * im).sqrt() / (0.5 * wsum);
        if a > best_a {
            best_a = a;
            best = n as f64;
        }
    }
    best
}

/// The warnings of a steady run of this scene (none so far: the steady residual has every
/// term of the transient model).
pub fn warnings(scene: &Scene) -> Vec<String> {
    snapshot_warning(scene).into_iter().collect()
}

pub fn run(scene: &Scene, opts: &RunOptions) -> Result<RunOutcome, AppError> {
    run_with_dump(scene, opts, None)
}

/// The MatrixMarket files written by `--dump-matrix PATH`: the tangent at PATH and the
/// right-hand side −R next to it (`<stem>_rhs.mtx`).
pub fn dump_paths(path: &Path) -> (PathBuf, PathBuf) {
    let stem = path
        .file_stem()
        .map_or_else(|| "steady".into(), |s| s.to_string_lossy().into_owned());
    let rhs = path.with_file_name(format!("{stem}_rhs.mtx"));
    (path.to_path_buf(), rhs)
}

/// Write the steady tangent dR/dx (MatrixMarket coordinate real general) and the right-hand
/// side −R (array) at the current state: after a converged solve, the matrix of the next
/// Newton iteration. Unknowns in the system's order (displacements, then any hub/road
/// unknowns).
pub fn dump_tangent(st: &mut SteadyRolling, path: &Path) -> Result<(PathBuf, PathBuf), AppError> {
    st.sys.evaluate(true);
    let (a, b) = dump_paths(path);
    let (cp, ri) = st.sys.pattern();
    let rhs: Vec<f64> = st.sys.residual().iter().map(|r| -r).collect();
    let io = |p: &Path, e: std::io::Error| {
        AppError::Output(crate::io::output::OutputError {
            path: p.to_path_buf(),
            source: e,
        })
    };
    if let Some(d) = a.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(d).map_err(|e| io(d, e))?;
    }
    write_matrix_market(&a, st.sys.n_eq(), cp, ri, st.sys.matrix_values())
        .map_err(|e| io(&a, e))?;
    write_vector_market(&b, &rhs).map_err(|e| io(&b, e))?;
    Ok((a, b))
}

/// The scene with its continuation parameter (ω with v0 / ω kept, the hub load, DISP) set
/// to `lambda`.
fn scene_at(scene: &Scene, st: &SteadyRolling, lambda: f64) -> Scene {
    let mut s = scene.clone();
    match st.param {
        SteadyParameter::Omega => {
            s.motion.omega = lambda;
            if let Some(r) = &mut s.road {
                r.v0 = st.v0_per_omega * lambda;
            }
        }
        SteadyParameter::Load => {
            if let Some(r) = &mut s.road {
                r.load = Some(lambda);
            }
        }
        SteadyParameter::Disp => {
            if let Some(r) = &mut s.road {
                r.disp = Some(lambda);
            }
        }
        SteadyParameter::Creep => {}
    }
    s
}

/// `[continuation] on_limit = "jump"`: a direct steady solve (the first solve's path, from the
/// undeformed state `x0`) at λ = `at` + `step`, retried at `at` + 2 `step` and `at` + 4 `step`
/// (never past `target`). On success `st` is at the new state and the Newton iterations are
/// returned; on failure `st`'s parameter is left at a tried value (the caller restores the
/// state) and `None` is returned. What these solves tried is not reported (the first solve's
/// reports stand); the damping tangent is restored after them.
fn jump_past_limit(
    scene: &Scene,
    st: &mut SteadyRolling,
    x0: &[f64],
    at: f64,
    step: f64,
    target: f64,
    verbose: bool,
) -> Option<usize> {
    use crate::solver::continuation::ParametricSystem;
    let tangent = st.sys.steady_damping_tangent();
    let mut landed = None;
    for k in 0..3 {
        let mut lambda = at + step * f64::from(1 << k);
        let last = (lambda - target) * step.signum() >= 0.0;
        if last {
            lambda = target;
        }
        st.sys.restore_state(x0);
        st.set_parameter(lambda);
        let direct = scene_at(scene, st, lambda);
        let mut report = StepReport::default();
        let r = solve_steady(&direct, st, false, &mut report, &mut ()).map(|_| ());
        if verbose {
            eprintln!(
                "  direct solve past the limit point at {at:.6e}: parameter {lambda:.6e}: {}",
                match &r {
                    Ok(()) => "converged".to_string(),
                    Err(e) => format!("failed ({e})"),
                }
            );
        }
        if r.is_ok() {
            landed = Some(report.total_iterations);
            break;
        }
        if last {
            break;
        }
    }
    if let Some(t) = tangent {
        st.sys.set_steady_damping_tangent(t);
    }
    landed
}

/// `[continuation]` from the first solution: the branch followed by arc-length continuation
/// (or by natural-parameter steps in the creep), every converged point recorded as recorder
/// step `n0` + its index and offered to the shape snapshots. Returns the continuation's report
/// (the part before a failure, if it failed), one row per converged point (`branch.csv`) and
/// how it ended.
#[allow(clippy::too_many_arguments)]
fn follow_branch(
    scene: &Scene,
    cs: &ContinuationSpec,
    st: &mut SteadyRolling,
    x_undeformed: &[f64],
    n0: u64,
    verbose: bool,
    recorders: &mut dyn Recorder,
    shapes: &mut Option<ShapeSnapshots>,
) -> (
    Option<ContinuationReport>,
    Vec<BranchRow>,
    Result<(), SolveError>,
) {
    let mut rows: Vec<BranchRow> = Vec::new();
    st.param = match cs.parameter {
        ContinuationParameter::Omega => SteadyParameter::Omega,
        ContinuationParameter::Load => SteadyParameter::Load,
        ContinuationParameter::Disp => SteadyParameter::Disp,
        ContinuationParameter::Creep => SteadyParameter::Creep,
        // The plane has no slip angle (the scene check refuses the parameter there).
        ContinuationParameter::SlipAngle | ContinuationParameter::Camber => {
            eprintln!(
                "tread: warning: continuation in the {} needs mesh.dimension = 3",
                cs.parameter
            );
            return (None, rows, Ok(()));
        }
    };
    use crate::solver::continuation::ParametricSystem;
    let start = st.parameter();
    let u_norm = {
        let n = st.sys.model.mesh.n_nodes();
        st.sys.x[..2 * n].iter().map(|v| v * v).sum::<f64>().sqrt()
    };
    let copts = crate::setup::continuation_options(scene, cs, start, u_norm, verbose);
    let jump_distance = cs.jump * copts.lambda_scale;
    let jump_direction = copts.direction;
    let jump_target = copts.target;
    let mut partial = None;
    let param_name = cs.parameter.as_str();
    // Arc length along the branch (scaled units, the sum of the steps' lengths).
    let mut arc = 0.0;
    let sweep = st.param == SteadyParameter::Creep;
    // Continuation passes limit points and critical speeds, where the matrix-free damping
    // tangent's GMRES iteration can stall: follow branches with the assembled one.
    if scene.solver.damping_tangent != DampingTangentChoice::MatrixFree {
        st.sys
            .set_steady_damping_tangent(SteadyDampingTangent::Assembled);
    }
    let rec: &mut dyn Recorder = recorders;
    // Every converged point: its row, the shape snapshots (continuation in ω only) and the
    // recorder step. Time of a branch point: the continuation parameter (ω, load, DISP), as
    // in branch.csv; the start point (p.step = 0) is the last load step, already recorded.
    let mut on_point = |s: &SteadyRolling, p: &BranchPoint| {
        let row = branch_row(s, p);
        if let Some(sh) = shapes.as_mut().filter(|sh| sh.wants(row.omega)) {
            let frame = SolidFrame::capture(&s.sys, false);
            sh.offer(row.omega, &frame.view(&s.sys, &[]), row.wave_amplitude);
        }
        arc += p.ds.abs() * f64::from(p.step > 0);
        record_branch_point(rec, n0, param_name, arc, p, &row);
        rows.push(row);
        let info = StepInfo {
            index: n0 + p.step as u64,
            time: p.lambda,
            dt: match rows.len() {
                0 | 1 => 0.0,
                n => rows[n - 1].lambda - rows[n - 2].lambda,
            },
            newton_iterations: p.iterations,
            residual: 0.0,
            is_final: false,
        };
        if p.step > 0 {
            s.sys.record_step(&info, rec);
        }
        !record::interrupted()
    };
    let res = if sweep {
        creep_sweep(st, &copts, &mut partial, &mut on_point)
    } else {
        let mut jump = |s: &mut SteadyRolling, at: f64| {
            jump_past_limit(
                scene,
                s,
                x_undeformed,
                at,
                jump_direction * jump_distance,
                jump_target,
                verbose,
            )
        };
        Continuation::new(st, LinearKind::Lu, copts).and_then(|mut c| {
            let r = c.run_with_jumps(st, &mut on_point, Some(&mut jump));
            partial = c.partial.take();
            r
        })
    };
    match res {
        Ok(r) => {
            let result = if record::interrupted() {
                Err(SolveError::Interrupted { at: st.parameter() })
            } else {
                Ok(())
            };
            (Some(r), rows, result)
        }
        // Keep the branch computed before the failure.
        Err(e) => (partial, rows, Err(e)),
    }
}

/// [`run`], and with `dump` = Some(PATH) the converged tangent written by [`dump_tangent`].
pub fn run_with_dump(
    scene: &Scene,
    opts: &RunOptions,
    dump: Option<&Path>,
) -> Result<RunOutcome, AppError> {
    let t0 = Instant::now();
    ensure_dir(&opts.out_dir)?;
    let warn = warnings(scene);
    let (mut st, ahead) = build_nested(scene)?;
    // The undeformed state: the start of a direct solve past a limit point.
    let mut x_undeformed = Vec::new();
    st.sys.save_state(&mut x_undeformed);
    let n_cont = scene.continuation.as_ref().map_or(0, |c| c.max_steps);
    let clock = RunClock {
        mesh: Some(&st.sys.model.mesh),
        time_name: "load_factor",
        time_end: 1.0 + n_cont as f64,
    };
    let mut env = RunEnvelope::open(scene, opts, clock, warn)?;
    let recorders = &mut env.recorders;
    let mut report = StepReport::default();
    if scene.motion.control != Control::Speed {
        let friction = st
            .sys
            .contact
            .as_ref()
            .is_some_and(|c| c.friction.is_active());
        if !friction {
            return Err(AppError::Unsupported(format!(
                "motion.control = \"{}\" adjusts the road speed to the hub torque: it needs a \
                 road, contact and friction ([friction] law other than \"none\")",
                scene.motion.control
            )));
        }
    }
    let (mut solve, reports) =
        match solve_steady_from(scene, &mut st, ahead, opts.verbose, &mut report, recorders) {
            Ok(r) => (Ok(()), r),
            Err(f) => (Err(f.error), *f.reports),
        };
    let mut control_report: Option<ControlReport> = None;
    if solve.is_ok() && scene.motion.control != Control::Speed {
        match apply_control(scene, &mut st, opts.verbose) {
            Ok(r) => control_report = Some(r),
            Err(e) => solve = Err(e),
        }
    }
    let t_first = t0.elapsed().as_secs_f64();
    if let Some(r) = &reports.recovery {
        if r.succeeded() {
            eprintln!("tread: recovered: {}", r.message);
        } else {
            eprintln!("tread: {}", r.message);
        }
    }
    let mut cont: Option<ContinuationReport> = None;
    let mut rows: Vec<BranchRow> = Vec::new();
    let mut shapes = shape_snapshots(scene, &st);
    if let (Ok(()), Some(cs)) = (&solve, &scene.continuation) {
        let (c, r, result) = follow_branch(
            scene,
            cs,
            &mut st,
            &x_undeformed,
            report.steps.len() as u64,
            opts.verbose,
            recorders,
            &mut shapes,
        );
        (cont, rows) = (c, r);
        if let Err(e) = result {
            solve = Err(e);
        }
    }
    let wall = t0.elapsed().as_secs_f64();
    let converged = solve.is_ok();
    let mut dumped = None;
    if let (Some(p), true) = (dump, converged) {
        dumped = Some(dump_tangent(&mut st, p)?);
    }
    let samples = st.sys.contact_samples();
    let tot = ContactModel::totals(&samples);
    let (f, m) = st.sys.hub_reaction();
    // Steps of the path to the first solution: the press's, or those of the recovery that
    // found it (the failed press's steps are not on that path).
    let first_steps = reports
        .solution_steps()
        .unwrap_or_else(|| report.steps.iter().filter(|s| s.converged).count());
    let steps = first_steps
        + cont
            .as_ref()
            .map_or(0, |c| c.points.len().saturating_sub(1));
    let resistance_curve = cont.is_some()
        && st.sys.steady_history.is_some()
        && st.param == SteadyParameter::Omega
        && rows.len() > 1;
    let results = SteadyResults {
        steady: converged,
        time_to_steady: 0.0,
        revolutions: 0.0,
        steps,
        omega: st.omega(),
        v0: st.v0(),
        penetration: st.penetration(),
        hub_force_x: f[0],
        hub_force_y: f[1],
        hub_torque: m,
        contact_x_min: tot.x_min,
        contact_x_max: tot.x_max,
        max_pressure: tot.max_pressure,
        contact_force_x: tot.force_x,
        contact_force_y: tot.force_y,
        contact_centroid: tot.centroid,
        contact_half_width_moment: 2.0 * tot.pressure_second_moment.sqrt(),
        wall_time_first_solution_s: t_first,
        creep: st.creep(),
        control: control_report.clone(),
        rolling_resistance: resistance_curve
            .then(|| resistance::rolling_resistance(&branch_loads(&rows), scene.geometry.ro)),
        branch: cont.as_ref().map(|_| rows.clone()),
        special_points: cont.as_ref().map(|c| c.special.clone()),
        continuation: cont.as_ref().map(|c| ContinuationSummary::new(scene, c)),
    };
    let friction = st
        .sys
        .contact
        .as_ref()
        .is_some_and(|c| c.friction.is_active());
    let damping = st
        .sys
        .contact
        .as_ref()
        .is_some_and(|c| c.normal.has_damping());
    let linear = if report.switched_to_lu {
        LinearKind::Lu
    } else {
        st.plan.kind
    };
    let typed = Summary::new(
        &scene.scene.name,
        scene.analysis.mode.to_string(),
        st.sys.n_dofs(),
        converged,
        ModeSummary::Steady(Box::new(SteadySummary {
            run: RunStats {
                newton_iterations: report.total_iterations
                    + cont.as_ref().map_or(0, |c| c.total_iterations)
                    + control_report.as_ref().map_or(0, |c| c.newton_iterations),
                wall_time_s: wall,
                error: solve.as_ref().err().map(|e| e.to_string()),
            },
            warnings: env.warnings.clone(),
            results,
            terms: SteadyTerms {
                common: Terms {
                    friction,
                    normal_damping: damping,
                    inertia: st.sys.model.omega2 > 0.0,
                    history: st.sys.steady_history.is_some(),
                    pressure: st.sys.dofs.per_cell > 0,
                    contact_facets_per_iteration: st.sys.mean_facets_per_assembly(),
                },
                strain_rate_damping: st.sys.model.strain_rate_damping > 0.0,
                damping_tangent: st.sys.steady_damping_tangent(),
                damping_tangent_fallback: reports.damping_fallback.clone(),
            },
            mesh: MeshInfo {
                n_r: scene.mesh.n_r,
                n_theta: scene.mesh.n_theta,
                order: scene.mesh.order,
                nodes: st.sys.model.mesh.n_nodes(),
                cells: st.sys.model.mesh.n_cells(),
            },
            solver: SteadySolver {
                linear: format!("{linear:?}").to_lowercase(),
                load_steps: report.steps.iter().filter(|s| s.converged).count(),
                cutbacks: report.cutbacks,
                threads: rayon::current_num_threads(),
                recovery: reports.recovery.clone(),
                eps_continuation: reports.eps_continuation.clone(),
                coarse_start: reports.coarse_start.clone(),
            },
        })),
    );
    let interrupted = matches!(solve, Err(SolveError::Interrupted { .. }));
    let error = solve.as_ref().err().map(|e| e.to_string());
    let final_info = StepInfo {
        index: steps as u64,
        time: 1.0,
        dt: 0.0,
        newton_iterations: 0,
        residual: 0.0,
        is_final: true,
    };
    // The final state is already recorded as the last load step or branch point, except when
    // a recovery homotopy (which records no steps) found it.
    if recorders.steps_recorded() == 0 || reports.solution_steps().is_some() {
        st.sys.record_step(&final_info, recorders);
    }
    let summary = env.finish(&typed, steps as u64, wall, error.as_deref(), interrupted)?;
    if scene.output.has(Sink::Csv) {
        write_steady_csv(&st.sys, &opts.out_dir)?;
        if !rows.is_empty() {
            write_csv(
                &opts.out_dir.join("branch.csv"),
                &BranchRow::HEADER,
                rows.iter().map(|r| r.values()),
            )?;
        }
    }
    if scene.output.has(Sink::Png) {
        write_steady_pngs(
            scene,
            &st,
            &rows,
            &samples,
            shapes.as_ref(),
            resistance_curve,
            &opts.out_dir,
        );
    }
    let mut headline = vec![format!(
        "steady at omega = {:.6} rad/s, v0 = {:.6}: hub force = ({:.6e}, {:.6e}), torque = {:.4e}, contact patch x1 in [{:.4}, {:.4}], max pressure = {:.4e}",
        st.omega(), st.v0(), f[0], f[1], m, tot.x_min, tot.x_max, tot.max_pressure
    )];
    if let Some((a, b)) = &dumped {
        headline.push(format!(
            "steady tangent written to {} (right-hand side -R: {})",
            a.display(),
            b.display()
        ));
    }
    if let Some(c) = &cont {
        headline.push(format!(
            "continuation: {} steps ({}), {} special points{}",
            c.points.len().saturating_sub(1),
            c.stop_reason,
            c.special.len(),
            c.special
                .iter()
                .map(|s| format!("; {:?} at {:.6}", s.kind, s.lambda))
                .collect::<String>()
        ));
    }
    let field = st
        .sys
        .x
        .get(..2 * st.sys.model.mesh.n_nodes())
        .map(<[f64]>::to_vec);
    conclude(
        solve,
        RunOutcome {
            summary,
            typed,
            field,
            history: (!st.sys.model.history.is_empty()).then(|| st.sys.model.history.clone()),
            contact: samples.clone(),
            out_dir: opts.out_dir.clone(),
            converged,
            headline,
        },
    )
}

/// The steady run's pictures (`png` sink) in `dir`: the shape snapshots, the creep and
/// rolling-resistance curves, the branch's hub loads against the continuation parameter and
/// the contact tractions. A picture that cannot be written is a warning, not a failure.
fn write_steady_pngs(
    scene: &Scene,
    st: &SteadyRolling,
    rows: &[BranchRow],
    samples: &[crate::contact::ContactSample],
    shapes: Option<&ShapeSnapshots>,
    resistance_curve: bool,
    dir: &Path,
) {
    let pts = |g: &dyn Fn(&BranchRow) -> f64| -> Vec<(f64, f64)> {
        rows.iter()
            .map(|r| (r.lambda, g(r)))
            .filter(|p| p.0.is_finite() && p.1.is_finite())
            .collect()
    };
    if let Some(sh) = shapes {
        let units = record::png::Units::parse(&scene.scene.units);
        if let Err(e) = sh.write(dir, &units) {
            eprintln!("tread: warning: shape pictures: {e}");
        }
    }
    if rows.len() > 1 && st.param == SteadyParameter::Creep {
        creep_plots(scene, rows, dir);
    }
    if resistance_curve {
        if let Err(e) = resistance::plot(
            &dir.join("resistance.png"),
            &branch_loads(rows),
            scene.geometry.ro,
        ) {
            eprintln!("tread: warning: resistance.png: {e}");
        }
    }
    if rows.len() > 1 {
        // One panel per quantity (each with its unit) against the continuation parameter.
        let u = record::png::Units::parse(&scene.scene.units);
        let fx = pts(&|r| r.hub_force_x);
        let fy = pts(&|r| r.hub_force_y);
        let tq = pts(&|r| r.hub_torque);
        let wa = pts(&|r| r.wave_amplitude);
        let (name, unit) = match scene.continuation.as_ref().map(|c| c.parameter) {
            Some(ContinuationParameter::Omega) | None => ("omega", u.of_scalar("omega")),
            Some(ContinuationParameter::Load) => ("hub load", u.force_per_thickness()),
            Some(ContinuationParameter::Disp) => ("penetration DISP", u.length.clone()),
            Some(ContinuationParameter::Creep) => ("creep", "1".to_string()),
            Some(ContinuationParameter::SlipAngle) => ("slip angle", "deg".to_string()),
            Some(ContinuationParameter::Camber) => ("camber", "deg".to_string()),
        };
        let x = record::png::with_unit(name, &unit);
        let f = u.force_per_thickness();
        let ps: Vec<record::png::Panel> = vec![
            (
                record::png::with_unit("hub force F_x", &f),
                vec![("hub_force_x", fx.as_slice())],
            ),
            (
                record::png::with_unit("hub force F_y", &f),
                vec![("hub_force_y", fy.as_slice())],
            ),
            (
                record::png::with_unit("hub torque", &u.moment_per_thickness()),
                vec![("hub_torque", tq.as_slice())],
            ),
            (
                record::png::with_unit("wave amplitude", &u.length),
                vec![("wave_amplitude", wa.as_slice())],
            ),
        ];
        if let Err(e) = record::png::panels(
            &dir.join("branch.png"),
            "Steady branch: hub loads and standing-wave amplitude",
            &x,
            &ps,
        ) {
            eprintln!("tread: warning: branch.png: {e}");
        }
    }
    if !samples.is_empty() {
        let (tn, tt) = record::png::contact_curves(samples.iter().filter(|s| s.t_n > 0.0));
        if !tn.is_empty() {
            let u = record::png::Units::parse(&scene.scene.units);
            if let Err(e) = record::png::line_chart(
                &dir.join("contact.png"),
                &format!(
                    "Steady contact tractions at omega = {} rad/{}",
                    st.omega(),
                    u.time
                ),
                &record::png::with_unit("x1", &u.length),
                &record::png::with_unit("traction", &u.stress()),
                &[("t_n", &tn), ("t_T", &tt)],
            ) {
                eprintln!("tread: warning: contact.png: {e}");
            }
        }
    }
}

/// The shape snapshots of `[output] snapshot_omegas` when they apply: PNG output and an
/// arc-length continuation in ω (without the latter [`snapshot_warning`] says why none).
fn shape_snapshots(scene: &Scene, st: &SteadyRolling) -> Option<ShapeSnapshots> {
    let o = &scene.output;
    (snapshot_warning(scene).is_none() && o.has(Sink::Png) && !o.snapshot_omegas.is_empty())
        .then(|| ShapeSnapshots::new(&st.sys.model.mesh, &o.snapshot_omegas, o.displacement_scale))
}

/// Why `[output] snapshot_omegas` draws nothing in this steady run, if it is given.
pub fn snapshot_warning(scene: &Scene) -> Option<String> {
    let o = &scene.output;
    if o.snapshot_omegas.is_empty() {
        return None;
    }
    let omega_continuation = scene
        .continuation
        .as_ref()
        .is_some_and(|c| c.parameter == ContinuationParameter::Omega);
    // Without the png sink nothing is drawn, as for every other plot (no warning).
    (!omega_continuation).then(|| {
        "output.snapshot_omegas is ignored: the shapes are drawn at the points of a \
         [continuation] with parameter = \"omega\""
            .into()
    })
}

/// `creep_force.png` (hub F_x against the creep, with the Coulomb limits ±μ|F_y|) and
/// `creep_torque.png` (hub torque against the creep). Failures are warnings.
fn creep_plots(scene: &Scene, rows: &[BranchRow], dir: &Path) {
    let units = &scene.scene.units;
    // The sliding coefficient at large slip: Coulomb μ, or μ_k of the rate-dependent law.
    let mu = scene
        .friction
        .params()
        .and_then(|f| f.kinetic_coefficient())
        .unwrap_or(f64::NAN);
    let pts = |g: &dyn Fn(&BranchRow) -> f64| -> Vec<(f64, f64)> {
        rows.iter()
            .map(|r| (r.creep, g(r)))
            .filter(|p| p.0.is_finite() && p.1.is_finite())
            .collect()
    };
    let fx = pts(&|r| r.hub_force_x);
    let hi = pts(&|r| mu * r.hub_force_y.abs());
    let lo = pts(&|r| -mu * r.hub_force_y.abs());
    let tq = pts(&|r| r.hub_torque);
    let force_label = format!("hub force F_x (force per unit thickness; units {units})");
    let torque_label = format!("hub torque (force x length per unit thickness; units {units})");
    let x_label = "creep xi = v0 / v0_free - 1 (dimensionless)";
    if let Err(e) = record::png::line_chart(
        &dir.join("creep_force.png"),
        "Creep-force curve (steady rolling)",
        x_label,
        &force_label,
        &[("F_x", &fx), ("+mu |F_y|", &hi), ("-mu |F_y|", &lo)],
    ) {
        eprintln!("tread: warning: creep_force.png: {e}");
    }
    if let Err(e) = record::png::line_chart(
        &dir.join("creep_torque.png"),
        "Hub torque against creep (steady rolling)",
        x_label,
        &torque_label,
        &[("hub torque", &tq)],
    ) {
        eprintln!("tread: warning: creep_torque.png: {e}");
    }
}

/// `steady_field.csv`, `contact.csv` and `nodes.csv` of a steady state.
pub fn write_steady_csv(
    sys: &SolidSystem,
    dir: &std::path::Path,
) -> Result<(), crate::io::output::OutputError> {
    let mesh = &sys.model.mesh;
    tables::write_referential_field_csv(&dir.join("steady_field.csv"), mesh, &sys.x)?;
    let samples = sys.contact_samples();
    if !samples.is_empty() {
        tables::write_contact_csv(&dir.join("contact.csv"), &samples)?;
    }
    tables::write_nodes_csv(&dir.join("nodes.csv"), mesh, &sys.x)
}

/// The branch points as the rolling-resistance curve takes them.
fn branch_loads(rows: &[BranchRow]) -> Vec<resistance::BranchLoad> {
    rows.iter()
        .map(|r| resistance::BranchLoad {
            step: r.step,
            omega: r.omega,
            hub_force_y: r.hub_force_y,
            hub_torque: r.hub_torque,
        })
        .collect()
}
