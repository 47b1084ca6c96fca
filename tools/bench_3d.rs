//! Three-dimensional static indentation at a given number of unknowns: Newton against one
//! factorization, fill and peak memory (a benchmark, not a test).
//!
//! ```text
//! cargo run --release --no-default-features --bin tread-bench-3d -- \
//!     [--sizes 30k,100k,300k] [--degrees 1,2] [--threads 1,2] [--solvers cholesky,lu,mixed] \
//!     [--factor-only] [--repeats N] [--max-factor-gb G] [--out DIR] [--verbose]
//! ```
//!
//! The body is the crowned wheel of `tests/hertz3d.rs`: a hub-bonded ring (ri = 0.25,
//! Ro = 1, half-width 0.3 meshed with the symmetry plane x3 = 0, crown radius 0.5), compressible
//! neo-Hookean (μ = 1, λ = 1.5), pressed by `DISP` onto the rigid road under displacement
//! control (`Solid3DSystem::with_contact`, frictionless linear normal compliance), `LOAD_STEPS` load
//! steps with cut-backs. The revolved mesh has n_r = m, n_z = ⌈m/2⌉, n_theta = 8m cells (Hex8
//! or Hex27), graded toward the contact; m is chosen so that the number of unknowns is
//! closest to the size asked for.
//!
//! Each case (size × degree × threads × solver) runs in a child process of this binary, so
//! that its peak resident memory (VmHWM of /proc/self/status) is its own. Per repeat the child
//! 1. builds the mesh and the system, and times the symbolic analysis of the tangent's
//!    pattern (once per repeat: the Newton solve reuses it);
//! 2. at the undeformed state under the full road displacement (the contact is closed, the
//!    penalty stiffness in the tangent) times one assembly of residual and tangent, one
//!    numeric factorization and one solve, and checks ‖A x − b‖ / ‖b‖;
//! 3. unless `--factor-only`, solves the indentation by Newton (the same analysed solver) and
//!    reports the iterations, the wall time and the time per iteration.
//!
//! Reported figures are the medians over the repeats. The fill is nnz(L+U)/nnz(A): for the
//! Cholesky factor 2 nnz(L) − n against the full pattern of A. Before the numeric
//! factorization the child compares the factor's size, known from the symbolic analysis, with
//! `--max-factor-gb` (default 12) and does not factorize a larger one (the row then says
//! so), rather than let a shared machine run out of memory.
//!
//! Solvers: `cholesky` (faer's supernodal LLᵀ with AMD; the Newton solve switches to LU on a
//! non-positive pivot), `lu` (the multifrontal LU on the pattern of A + Aᵀ, double precision),
//! `mixed` (the same LU with single-precision factors; the Newton steps by GMRES refined to the
//! accuracy of a direct solve, `NewtonOptions::mixed_precision`). With more than one thread
//! the numeric factorization runs on the rayon pool too (`SparseSolver::set_parallel`).

#[path = "common.rs"]
mod common;
use common::median;

use std::fmt::Write as _;
use std::process::{Command, ExitCode};
use std::time::Instant;

use nalgebra::Vector2;
use tread::contact::facet::FacetRule;
use tread::contact::facet3d::ContactSurface3D;
use tread::contact::laws::{Friction, NormalCompliance};
use tread::material::MaterialKind;
use tread::mesh::revolved::{revolved, RevolvedSpec};
use tread::model::{Solid3D, Solid3DSystem};
use tread::physics::PressureMode;
use tread::solver::linear::LuOrdering;
use tread::solver::observe::NoObserver;
use tread::solver::stepping::LoadedSystem;
use tread::solver::{
    solve_load_steps, LinearKind, Newton, NewtonOptions, NonlinearSystem, SparseSolver,
    StepOptions, StepReport,
};

const RI: f64 = 0.25;
const RO: f64 = 1.0;
const HALF_W: f64 = 0.3;
const CROWN: f64 = 0.5;
const MU: f64 = 1.0;
const LAMBDA: f64 = 1.5;
const C_N: f64 = 2.0e4;
/// Road displacement: a contact patch several cells across at the sizes benchmarked.
const DISP: f64 = 2.0e-3;
/// Load steps of the road displacement (one step took 4 cut-backs).
const LOAD_STEPS: usize = 4;

const USAGE: &str = "usage: tread-bench-3d [--sizes 30k,100k,300k] [--degrees 1,2] [--threads 1,2] \
     [--solvers cholesky,lu,mixed] [--factor-only] [--repeats N] [--max-factor-gb G] [--out DIR] [--verbose]";

#[derive(Clone, Copy, Debug, PartialEq)]
enum SolverChoice {
    Cholesky,
    Lu,
    Mixed,
}

impl SolverChoice {
    fn parse(s: &str) -> Option<Self> {
        match s {
            "cholesky" => Some(Self::Cholesky),
            "lu" => Some(Self::Lu),
            "mixed" => Some(Self::Mixed),
            _ => None,
        }
    }
    fn name(self) -> &'static str {
        match self {
            Self::Cholesky => "cholesky",
            Self::Lu => "lu",
            Self::Mixed => "mixed",
        }
    }
}

/// One case: what the parent asks a child to measure.
#[derive(Clone, Copy, Debug)]
struct Case {
    dofs: usize,
    degree: usize,
    threads: usize,
    solver: SolverChoice,
    factor_only: bool,
    repeats: usize,
    max_factor_gb: f64,
    verbose: bool,
}

impl Case {
    fn to_args(self) -> Vec<String> {
        vec![
            "--child".into(),
            self.dofs.to_string(),
            self.degree.to_string(),
            self.threads.to_string(),
            self.solver.name().into(),
            (self.factor_only as u8).to_string(),
            self.repeats.to_string(),
            self.max_factor_gb.to_string(),
            (self.verbose as u8).to_string(),
        ]
    }
    fn from_args(a: &[String]) -> Result<Self, String> {
        let bad = |what: &str| format!("--child: bad {what} in {a:?}");
        if a.len() != 8 {
            return Err(bad("argument count"));
        }
        Ok(Self {
            dofs: a[0].parse().map_err(|_| bad("size"))?,
            degree: a[1].parse().map_err(|_| bad("degree"))?,
            threads: a[2].parse().map_err(|_| bad("threads"))?,
            solver: SolverChoice::parse(&a[3]).ok_or_else(|| bad("solver"))?,
            factor_only: a[4] == "1",
            repeats: a[5].parse().map_err(|_| bad("repeats"))?,
            max_factor_gb: a[6].parse().map_err(|_| bad("max factor size"))?,
            verbose: a[7] == "1",
        })
    }
}

/// What a child measured (medians over the repeats).
#[derive(Clone, Debug, Default)]
struct Row {
    case: String,
    degree: usize,
    threads: usize,
    solver: String,
    cells: usize,
    dofs: usize,
    nnz_a: usize,
    factor_entries: usize,
    fill: f64,
    factor_gb: f64,
    mesh_s: f64,
    symbolic_s: f64,
    assembly_s: f64,
    first_factor_s: f64,
    factor_s: f64,
    solve_s: f64,
    residual: f64,
    iterations: String,
    newton_s: f64,
    newton_cpu_s: f64,
    per_iteration_s: f64,
    per_iteration_over_factor: f64,
    newton_factor_s: f64,
    newton_evaluate_s: f64,
    newton_linear_s: f64,
    peak_factor_mb: f64,
    peak_mb: f64,
    load_start: String,
    load_end: String,
    note: String,
}

const CSV_HEAD: &str = "case,degree,threads,solver,cells,dofs,nnz_a,factor_entries,fill,factor_gb,\
mesh_s,symbolic_s,assembly_s,factor_s,solve_s,residual,newton_iterations,newton_s,newton_cpu_s,\
per_iteration_s,per_iteration_over_factor_solve,newton_factorize_s,newton_evaluate_s,\
newton_linear_solve_s,peak_after_factor_mb,peak_mb,load_start,load_end,note,first_factor_s";

impl Row {
    fn csv(&self) -> String {
        format!(
            "{},{},{},{},{},{},{},{},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.4},{:.1e},{},{:.3},{:.3},{:.3},{:.2},{:.3},{:.3},{:.3},{:.0},{:.0},{},{},{},{:.3}",
            self.case,
            self.degree,
            self.threads,
            self.solver,
            self.cells,
            self.dofs,
            self.nnz_a,
            self.factor_entries,
            self.fill,
            self.factor_gb,
            self.mesh_s,
            self.symbolic_s,
            self.assembly_s,
            self.factor_s,
            self.solve_s,
            self.residual,
            self.iterations,
            self.newton_s,
            self.newton_cpu_s,
            self.per_iteration_s,
            self.per_iteration_over_factor,
            self.newton_factor_s,
            self.newton_evaluate_s,
            self.newton_linear_s,
            self.peak_factor_mb,
            self.peak_mb,
            self.load_start,
            self.load_end,
            self.note.replace(',', ";"),
            self.first_factor_s,
        )
    }

    fn from_csv(line: &str) -> Option<Self> {
        let f: Vec<&str> = line.split(',').collect();
        if f.len() != CSV_HEAD.split(',').count() {
            return None;
        }
        let p = |i: usize| f[i].parse::<f64>().unwrap_or(f64::NAN);
        let u = |i: usize| f[i].parse::<usize>().unwrap_or(0);
        Some(Self {
            case: f[0].into(),
            degree: u(1),
            threads: u(2),
            solver: f[3].into(),
            cells: u(4),
            dofs: u(5),
            nnz_a: u(6),
            factor_entries: u(7),
            fill: p(8),
            factor_gb: p(9),
            mesh_s: p(10),
            symbolic_s: p(11),
            assembly_s: p(12),
            factor_s: p(13),
            solve_s: p(14),
            residual: p(15),
            iterations: f[16].into(),
            newton_s: p(17),
            newton_cpu_s: p(18),
            per_iteration_s: p(19),
            per_iteration_over_factor: p(20),
            newton_factor_s: p(21),
            newton_evaluate_s: p(22),
            newton_linear_s: p(23),
            peak_factor_mb: p(24),
            peak_mb: p(25),
            load_start: f[26].into(),
            load_end: f[27].into(),
            note: f[28].into(),
            first_factor_s: p(29),
        })
    }

    fn markdown(&self) -> String {
        let t = |x: f64| {
            if x.is_finite() {
                format!("{x:.2}")
            } else {
                "–".into()
            }
        };
        format!(
            "| {} | Q{} | {} | {} | {} | {} | {} | {:.1} | {:.2} | {} | {} | {} / {} | {} | {:.0e} | {} | {} | {} | {} | {} / {} / {} | {:.0} | {} ; {} | {} |",
            self.case,
            self.degree,
            self.threads,
            self.solver,
            self.dofs,
            self.nnz_a,
            self.factor_entries,
            self.fill,
            self.factor_gb,
            t(self.symbolic_s),
            t(self.assembly_s),
            t(self.first_factor_s),
            t(self.factor_s),
            t(self.solve_s),
            self.residual,
            self.iterations,
            t(self.newton_s),
            t(self.per_iteration_s),
            t(self.per_iteration_over_factor),
            t(self.newton_evaluate_s),
            t(self.newton_factor_s),
            t(self.newton_linear_s),
            self.peak_mb,
            self.load_start,
            self.load_end,
            self.note,
        )
    }
}

const MD_HEAD: &str = "| size | element | threads | solver | DOFs | nnz(A) | nnz(L+U) | fill | factor (GB) | symbolic (s) | assembly (s) | factorization, first / again (s) | solve (s) | ‖Ax−b‖/‖b‖ | Newton iterations | Newton total (s) | per iteration (s) | per iteration / (factor + solve) | Newton: assembly / factorizations / solves (s) | peak RSS (MB) | load (start ; end) | note |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|";

/// "30k" → 30000, "1.5M" → 1500000, "12345" → 12345.
fn parse_size(s: &str) -> Option<usize> {
    let s = s.trim();
    let (num, mult) = match s.chars().last()? {
        'k' | 'K' => (&s[..s.len() - 1], 1e3),
        'm' | 'M' => (&s[..s.len() - 1], 1e6),
        _ => (s, 1.0),
    };
    let v: f64 = num.parse().ok()?;
    let n = (v * mult).round();
    (n.is_finite() && n >= 100.0).then_some(n as usize)
}

fn size_label(n: usize) -> String {
    if n.is_multiple_of(1000) {
        format!("{}k", n / 1000)
    } else {
        n.to_string()
    }
}

fn spec(m: usize, degree: usize) -> RevolvedSpec {
    let n_z = m.div_ceil(2);
    RevolvedSpec {
        ri: RI,
        ro: RO,
        width: 2.0 * HALF_W,
        n_r: m,
        n_z,
        n_theta: 8 * m,
        degree,
        // Radial cells shrink toward the tread, circumferential ones toward the contact,
        // axial ones toward the mid-plane.
        grading_r: 0.5,
        grading_theta: 0.0,
        theta_ratio: 4.0,
        grading_z: 2.0,
        half_width: true,
        crown_radius: Some(CROWN),
    }
}

/// Unknowns of the mesh of parameter m: 3 per node, less the hub (all three) and u3 on the
/// mid-plane (`solve`'s constraints).
fn dof_count(m: usize, degree: usize) -> usize {
    let s = spec(m, degree);
    let (r, z, t) = (degree * s.n_r + 1, degree * s.n_z + 1, degree * s.n_theta);
    3 * r * z * t - 3 * z * t - (r - 1) * t
}

/// The mesh parameter whose unknowns are closest to `target`.
fn choose_m(target: usize, degree: usize) -> usize {
    (1..400)
        .min_by_key(|&m| dof_count(m, degree).abs_diff(target))
        .unwrap_or(1)
}

fn build_system(m: usize, degree: usize) -> Result<(Solid3DSystem, usize), String> {
    let mesh = revolved(&spec(m, degree)).map_err(|e| e.to_string())?;
    let cells = mesh.n_cells();
    let mut fixed = vec![false; 3 * mesh.n_nodes()];
    for &n in mesh.node_set("hub") {
        fixed[3 * n as usize..3 * n as usize + 3].fill(true);
    }
    for &n in mesh.node_set("mid") {
        fixed[3 * n as usize + 2] = true;
    }
    let surface = ContactSurface3D::new(
        mesh.facet_set("outer").to_vec(),
        RO,
        Vector2::zeros(),
        NormalCompliance::new(C_N, 1.0, 0.0, 0.0),
        Friction::None,
        FacetRule::Gauss(degree + 1),
    )
    .map_err(|e| format!("contact surface: {e}"))?;
    let material = MaterialKind::NeoHookean.build(&[MU, LAMBDA]);
    let mut sys = Solid3DSystem::new(
        Solid3D::new(mesh, material, 1.0, PressureMode::None),
        &fixed,
    )
    .with_contact(surface, RO, DISP)
    .map_err(|e| format!("contact on the mesh: {e}"))?;
    // Force scale: the Hertz load of a circular contact of radius 0.05 Ro (E* = 2.86).
    sys.set_reference_force(4.0 / 3.0 * 2.86 * 0.05f64.powi(3) * RO * RO);
    Ok((sys, cells))
}

fn status_kb(key: &str) -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with(key))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|v| v.parse::<f64>().ok())
        })
        .unwrap_or(f64::NAN)
}

fn load_avg() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().map(str::to_string))
        .unwrap_or_else(|| "?".into())
}

/// CPU time of the whole process (s), all threads.
fn cpu_s() -> f64 {
    #[repr(C)]
    struct Timespec {
        tv_sec: i64,
        tv_nsec: i64,
    }
    extern "C" {
        fn clock_gettime(clock: i32, tp: *mut Timespec) -> i32;
    }
    const CLOCK_PROCESS_CPUTIME_ID: i32 = 2;
    let mut t = Timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid, writable timespec; the call only writes into it.
    let rc = unsafe { clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &mut t) };
    if rc == 0 {
        t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
    } else {
        f64::NAN
    }
}

fn timed<T>(f: impl FnOnce() -> T) -> (f64, T) {
    let t = Instant::now();
    let out = f();
    (t.elapsed().as_secs_f64(), out)
}

/// y = A x for the CSC matrix (both triangles stored).
fn matvec(cp: &[usize], ri: &[usize], v: &[f64], x: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; cp.len() - 1];
    for j in 0..cp.len() - 1 {
        for k in cp[j]..cp[j + 1] {
            y[ri[k]] += v[k] * x[j];
        }
    }
    y
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// One repeat of a case; `Err` ends the case with that message in the row's note.
fn measure_once(case: &Case, row: &mut Row, times: &mut Vec<[f64; 12]>) -> Result<(), String> {
    let m = choose_m(case.dofs, case.degree);
    let (mesh_s, built) = timed(|| build_system(m, case.degree));
    let (mut sys, cells) = built?;
    let n = sys.n_eq();
    let (cp, ri) = sys.pattern();
    let (cp, ri) = (cp.to_vec(), ri.to_vec());
    row.cells = cells;
    row.dofs = n;
    row.nnz_a = ri.len();
    let kind = match case.solver {
        SolverChoice::Cholesky => LinearKind::Cholesky,
        _ => LinearKind::Lu,
    };
    let (symbolic_s, solver) =
        timed(|| SparseSolver::with_lu_ordering(n, &cp, &ri, kind, LuOrdering::Symmetric));
    let mut solver = solver.map_err(|e| format!("symbolic analysis: {e}"))?;
    solver.set_track_determinant(false);
    if case.threads > 1 {
        solver.set_parallel(true);
    }
    let single = case.solver == SolverChoice::Mixed;
    // Factor entries from the symbolic analysis (Cholesky: L, counted as L + Lᵀ).
    let entries = match kind {
        LinearKind::Cholesky => (2 * solver.factor_nnz()).saturating_sub(n),
        LinearKind::Lu => solver.factor_nnz(),
    };
    let bytes_per = if single { 4.0 } else { 8.0 };
    let stored = match kind {
        LinearKind::Cholesky => solver.factor_nnz() as f64,
        LinearKind::Lu => entries as f64,
    };
    row.factor_entries = entries;
    row.fill = entries as f64 / ri.len() as f64;
    row.factor_gb = stored * bytes_per / 1e9;
    if row.factor_gb > case.max_factor_gb {
        return Err(format!(
            "factor of {:.1} GB exceeds --max-factor-gb {}: not factorized",
            row.factor_gb, case.max_factor_gb
        ));
    }
    // The tangent at the undeformed state under the full road displacement.
    sys.set_load(1.0);
    let (assembly_s, ok) = timed(|| sys.evaluate(true));
    if !ok {
        return Err("inadmissible state at the first assembly".into());
    }
    solver.set_single_precision_factors(single);
    let vals = sys.matrix_values().to_vec();
    let (first_factor_s, f) = timed(|| solver.factorize(&vals));
    f.map_err(|e| format!("factorization: {e}"))?;
    // Again with the same values, as each Newton iteration does: the first one also pays for
    // touching the factor storage for the first time.
    let (factor_s, f) = timed(|| solver.factorize(&vals));
    f.map_err(|e| format!("second factorization: {e}"))?;
    row.peak_factor_mb = status_kb("VmHWM") / 1024.0;
    let b: Vec<f64> = sys.residual().iter().map(|r| -r).collect();
    let mut x = b.clone();
    let (solve_s, s) = timed(|| solver.solve_in_place(&mut x));
    s.map_err(|e| format!("solve: {e}"))?;
    let ax = matvec(&cp, &ri, &vals, &x);
    let res: Vec<f64> = ax.iter().zip(&b).map(|(a, b)| a - b).collect();
    let residual = norm(&res) / norm(&b).max(f64::MIN_POSITIVE);
    let mut all = [
        first_factor_s,
        mesh_s,
        symbolic_s,
        assembly_s,
        factor_s,
        solve_s,
        residual,
        f64::NAN,
        f64::NAN,
        f64::NAN,
        f64::NAN,
        f64::NAN,
    ];
    let t = &mut all[1..];
    if !case.factor_only {
        // The Newton solve from the undeformed state with the analysed solver; mixed precision
        // sets the factor precision itself.
        solver.set_single_precision_factors(false);
        let opts = NewtonOptions {
            tol: 1e-6,
            max_iterations: 30,
            mixed_precision: single,
            verbose: case.verbose,
            ..Default::default()
        };
        let mut newton = Newton::with_solver(&sys, solver, opts);
        let steps = StepOptions {
            initial_steps: LOAD_STEPS,
            max_cutbacks: 6,
            verbose: case.verbose,
        };
        let mut rep = StepReport::default();
        let cpu0 = cpu_s();
        let (newton_s, r) =
            timed(|| solve_load_steps(&mut sys, &mut newton, &steps, &mut rep, &mut NoObserver));
        let newton_cpu = cpu_s() - cpu0;
        r.map_err(|e| format!("Newton: {e}"))?;
        let it = rep.total_iterations.max(1);
        let sum = |f: fn(&tread::solver::newton::NewtonTiming) -> f64| {
            rep.steps.iter().map(|s| f(&s.timing)).sum::<f64>()
        };
        t[6] = it as f64;
        t[7] = newton_s;
        t[8] = sum(|t| t.factorize_s);
        t[9] = sum(|t| t.evaluate_s);
        t[10] = sum(|t| t.linear_solve_s);
        row.newton_cpu_s = newton_cpu;
        let mut note = String::new();
        if rep.cutbacks > 0 {
            let _ = write!(note, "{} cut-backs ", rep.cutbacks);
        }
        if rep.switched_to_lu {
            note.push_str("switched to LU ");
        }
        if let Some(rc) = sys.contact.as_ref() {
            let _ = write!(note, "load {:.4e}", 2.0 * rc.totals.force[1]);
        }
        row.note = note;
    }
    times.push(all);
    Ok(())
}

fn run_child(case: Case) -> Row {
    let mut row = Row {
        case: size_label(case.dofs),
        degree: case.degree,
        threads: case.threads,
        solver: case.solver.name().into(),
        load_start: load_avg(),
        iterations: "–".into(),
        ..Default::default()
    };
    let mut times = Vec::new();
    for _ in 0..case.repeats {
        if let Err(e) = measure_once(&case, &mut row, &mut times) {
            row.note = e;
            break;
        }
    }
    let med = |i: usize| median(times.iter().map(|t| t[i + 1]).collect());
    row.first_factor_s = median(times.iter().map(|t| t[0]).collect());
    row.mesh_s = med(0);
    row.symbolic_s = med(1);
    row.assembly_s = med(2);
    row.factor_s = med(3);
    row.solve_s = med(4);
    row.residual = med(5);
    let its = med(6);
    if its.is_finite() {
        row.iterations = format!("{its}");
        row.newton_s = med(7);
        row.per_iteration_s = med(7) / its;
        row.per_iteration_over_factor = row.per_iteration_s / (row.factor_s + row.solve_s);
        row.newton_factor_s = med(8);
        row.newton_evaluate_s = med(9);
        row.newton_linear_s = med(10);
    } else {
        row.newton_s = f64::NAN;
        row.per_iteration_s = f64::NAN;
        row.per_iteration_over_factor = f64::NAN;
        row.newton_factor_s = f64::NAN;
        row.newton_evaluate_s = f64::NAN;
        row.newton_linear_s = f64::NAN;
        row.newton_cpu_s = f64::NAN;
    }
    row.peak_mb = status_kb("VmHWM") / 1024.0;
    row.load_end = load_avg();
    row
}

struct Options {
    sizes: Vec<usize>,
    degrees: Vec<usize>,
    threads: Vec<usize>,
    solvers: Vec<SolverChoice>,
    factor_only: bool,
    repeats: usize,
    max_factor_gb: f64,
    verbose: bool,
    out: Option<std::path::PathBuf>,
}

fn parse_list<T>(flag: &str, v: &str, f: impl Fn(&str) -> Option<T>) -> Result<Vec<T>, String> {
    let out: Option<Vec<T>> = v.split(',').map(|s| f(s.trim())).collect();
    match out {
        Some(o) if !o.is_empty() => Ok(o),
        _ => Err(format!("{flag}: cannot read `{v}`")),
    }
}

fn parse_options(args: &[String]) -> Result<Options, String> {
    let mut o = Options {
        sizes: vec![30_000, 100_000, 300_000],
        degrees: vec![1],
        threads: vec![1],
        solvers: vec![SolverChoice::Cholesky],
        factor_only: false,
        repeats: 1,
        max_factor_gb: 12.0,
        verbose: false,
        out: None,
    };
    let mut i = 0;
    while i < args.len() {
        let flag = args[i].as_str();
        if flag == "--factor-only" {
            o.factor_only = true;
            i += 1;
            continue;
        }
        if flag == "--verbose" {
            o.verbose = true;
            i += 1;
            continue;
        }
        if flag == "--help" || flag == "-h" {
            println!("{USAGE}");
            std::process::exit(0);
        }
        const VALUED: [&str; 7] = [
            "--sizes",
            "--degrees",
            "--threads",
            "--solvers",
            "--repeats",
            "--max-factor-gb",
            "--out",
        ];
        if !VALUED.contains(&flag) {
            return Err(format!("unknown flag `{flag}`"));
        }
        let v = args
            .get(i + 1)
            .ok_or_else(|| format!("{flag} needs a value"))?
            .as_str();
        match flag {
            "--sizes" => o.sizes = parse_list(flag, v, parse_size)?,
            "--degrees" => {
                o.degrees = parse_list(flag, v, |s| {
                    s.parse().ok().filter(|d: &usize| *d == 1 || *d == 2)
                })
                .map_err(|e| format!("{e} (degrees are 1 or 2)"))?
            }
            "--threads" => {
                o.threads = parse_list(flag, v, |s| {
                    s.parse().ok().filter(|t: &usize| (1..=256).contains(t))
                })?
            }
            "--solvers" => {
                o.solvers = parse_list(flag, v, SolverChoice::parse)
                    .map_err(|e| format!("{e} (solvers are cholesky, lu, mixed)"))?
            }
            "--repeats" => {
                o.repeats = v
                    .parse()
                    .ok()
                    .filter(|r: &usize| *r >= 1)
                    .ok_or_else(|| format!("--repeats: `{v}` is not a positive integer"))?
            }
            "--max-factor-gb" => {
                o.max_factor_gb = v
                    .parse()
                    .ok()
                    .filter(|g: &f64| g.is_finite() && *g > 0.0)
                    .ok_or_else(|| format!("--max-factor-gb: `{v}` is not a positive number"))?
            }
            "--out" => o.out = Some(v.into()),
            _ => return Err(format!("unknown flag `{flag}`")),
        }
        i += 2;
    }
    Ok(o)
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().collect();
    if args.get(1).map(String::as_str) == Some("--child") {
        let case = match Case::from_args(&args[2..]) {
            Ok(c) => c,
            Err(e) => {
                eprintln!("tread-bench-3d: {e}");
                return ExitCode::from(2);
            }
        };
        let row = tread::app::in_pool(case.threads, || run_child(case));
        println!("ROW,{}", row.csv());
        return ExitCode::SUCCESS;
    }
    let o = match parse_options(&args[1..]) {
        Ok(o) => o,
        Err(e) => {
            eprintln!("tread-bench-3d: {e}\n{USAGE}");
            return ExitCode::from(2);
        }
    };
    if let Some(d) = &o.out {
        if let Err(e) = std::fs::create_dir_all(d) {
            eprintln!("tread-bench-3d: --out: cannot create {}: {e}", d.display());
            return ExitCode::from(2);
        }
    }
    let exe = match std::env::current_exe() {
        Ok(p) => p,
        Err(e) => {
            eprintln!("tread-bench-3d: cannot find this executable to run the cases: {e}");
            return ExitCode::from(1);
        }
    };
    println!("{MD_HEAD}");
    let mut rows = Vec::new();
    let mut failed = false;
    for &degree in &o.degrees {
        for &dofs in &o.sizes {
            for &threads in &o.threads {
                for &solver in &o.solvers {
                    let case = Case {
                        dofs,
                        degree,
                        threads,
                        solver,
                        factor_only: o.factor_only,
                        repeats: o.repeats,
                        max_factor_gb: o.max_factor_gb,
                        verbose: o.verbose,
                    };
                    let out = Command::new(&exe)
                        .args(case.to_args())
                        .env("RAYON_NUM_THREADS", threads.to_string())
                        .stderr(std::process::Stdio::inherit())
                        .output();
                    let row = match out {
                        Ok(out) => String::from_utf8_lossy(&out.stdout)
                            .lines()
                            .find_map(|l| l.strip_prefix("ROW,").and_then(Row::from_csv))
                            .unwrap_or_else(|| Row {
                                case: size_label(dofs),
                                degree,
                                threads,
                                solver: solver.name().into(),
                                note: format!(
                                    "the case's process ended without a result: {}",
                                    out.status
                                ),
                                ..Default::default()
                            }),
                        Err(e) => {
                            eprintln!("tread-bench-3d: cannot run {}: {e}", exe.display());
                            return ExitCode::from(1);
                        }
                    };
                    failed |= !row.note.is_empty() && row.factor_s.is_nan();
                    println!("{}", row.markdown());
                    rows.push(row);
                    if let Some(d) = &o.out {
                        write_outputs(d, &rows);
                    }
                }
            }
        }
    }
    if failed {
        eprintln!("tread-bench-3d: some cases were not measured (see the note column)");
    }
    ExitCode::SUCCESS
}

fn write_outputs(dir: &std::path::Path, rows: &[Row]) {
    let mut csv = format!("{CSV_HEAD}\n");
    let mut md = format!("{MD_HEAD}\n");
    for r in rows {
        csv.push_str(&r.csv());
        csv.push('\n');
        md.push_str(&r.markdown());
        md.push('\n');
    }
    for (name, text) in [("bench_3d.csv", csv), ("bench_3d.md", md)] {
        let p = dir.join(name);
        if let Err(e) = std::fs::write(&p, text) {
            eprintln!("tread-bench-3d: cannot write {}: {e}", p.display());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_and_bad_ones_are_refused() {
        assert_eq!(parse_size("30k"), Some(30_000));
        assert_eq!(parse_size("1.5M"), Some(1_500_000));
        assert_eq!(parse_size("12345"), Some(12_345));
        assert_eq!(parse_size("k"), None);
        assert_eq!(parse_size("-3k"), None);
        let args = |a: &[&str]| a.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        assert!(parse_options(&args(&["--sizes", "30k,x"])).is_err());
        assert!(parse_options(&args(&["--degrees", "3"])).is_err());
        assert!(parse_options(&args(&["--repeats", "0"])).is_err());
        assert!(parse_options(&args(&["--bogus"])).is_err());
        assert!(parse_options(&args(&["--out"])).is_err());
    }

    #[test]
    fn dof_count_matches_the_mesh() {
        for degree in [1, 2] {
            for m in [2, 3] {
                let (sys, _) = build_system(m, degree).expect("system");
                assert_eq!(sys.n_eq(), dof_count(m, degree), "m = {m}, Q{degree}");
            }
        }
    }

    #[test]
    fn csv_round_trip() {
        let r = Row {
            case: "30k".into(),
            dofs: 12,
            fill: 3.5,
            note: "a note".into(),
            ..Default::default()
        };
        let back = Row::from_csv(&r.csv()).expect("parses");
        assert_eq!(back.dofs, 12);
        assert_eq!(back.note, "a note");
        assert!((back.fill - 3.5).abs() < 1e-12);
    }
}
