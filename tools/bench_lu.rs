//! Steady tangent against the physical limit of one sparse LU, and against peer solvers (a
//! benchmark, not a test).
//!
//! ```text
//! cargo run --release --no-default-features --bin tread-bench-lu -- \
//!     [--mesh 8x256,16x512,32x1024] [--scene FILE] [--set KEY=VALUE]... \
//!     [--dump DIR] [--peer PYTHON] [--orderings colamd,symmetric,amd]
//! ```
//!
//! For each mesh (n_r × n_theta of the scene, default `scenarios/oden_hollow_cylinder.toml` in
//! steady mode) it
//! 1. solves the steady state (`tread run --mode steady`'s path: build, press in, Newton) and
//!    reports the time per Newton iteration of that solve two ways: the whole solve (the
//!    coarser meshes of the nested iteration and the symbolic analysis included) over the
//!    Newton iterations on this mesh, and the Newton phase alone (the solves' own timing:
//!    evaluations, factorizations, linear solves on this mesh) over the same iterations;
//! 2. at the converged state, times the parts of one Newton iteration: the assembly of residual
//!    and tangent, one numeric LU factorization and one solve;
//! 3. factorizes the same tangent with each LU column ordering ([`LuOrdering::Colamd`], faer's
//!    default, [`LuOrdering::Symmetric`], the multifrontal LU on the pattern of A + Aᵀ, and on
//!    request [`LuOrdering::Amd`], faer's LU with AMD on A + Aᵀ): symbolic time, numeric time (median of
//!    3), solve time, stored factor entries nnz(L+U) and fill nnz(L+U)/nnz(A), the heap held by
//!    the factors and the heap peak during the first factorization (counting allocator), and
//!    the relative residual ‖A x − b‖ / ‖b‖;
//! 4. with `--dump DIR`, writes the tangent (`DIR/steady_<dofs>.mtx`, MatrixMarket coordinate
//!    real general) and the right-hand side −R (`DIR/steady_<dofs>_rhs.mtx`);
//! 5. with `--peer PYTHON` (needs `--dump`), runs `tools/lu_peer.py` with that interpreter
//!    (scipy; scikit-umfpack if installed) on the dumped files and prints its table.
//!
//! The ratio "Newton iteration / (LU factor + solve)" uses the default ordering (the one the
//! Newton solve used) on the Newton matrix that solve factorized. With the steady damping's
//! matrix-free or banded tangent that matrix is GMRES's preconditioner, which leaves out part
//! of the coupling; the columns "exact tangent LU" then time one LU factor + solve (double
//! precision, default ordering) of the whole tangent (the assembled damping tangent at the
//! converged state), the cost of one exact Newton step by a direct solve, and set the Newton
//! phase against it. Without damping, or with the assembled tangent, the two LUs are one.
//! Times are CPU seconds of the process (`CLOCK_PROCESS_CPUTIME_ID`), so run with
//! `RAYON_NUM_THREADS=1`; the wall time of the steady solve is shown in parentheses.

#[path = "common.rs"]
mod common;
use common::median;

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use tread::driver::steady_run::{build_steady, solve_steady};
use tread::io::Scene;
use tread::model::SteadyDampingTangent;
use tread::solver::linear::{write_matrix_market, write_vector_market, LuOrdering};
use tread::solver::{LinearKind, NonlinearSystem, SparseSolver, StepReport};

/// Heap bytes in use and their peak since the last reset.
struct Counting;
static CURRENT: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

fn note_alloc(size: usize) {
    let now = CURRENT.fetch_add(size, Ordering::Relaxed) + size;
    PEAK.fetch_max(now, Ordering::Relaxed);
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = System.alloc(layout);
        if !p.is_null() {
            note_alloc(layout.size());
        }
        p
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let p = System.alloc_zeroed(layout);
        if !p.is_null() {
            note_alloc(layout.size());
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout);
        CURRENT.fetch_sub(layout.size(), Ordering::Relaxed);
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let p = System.realloc(ptr, layout, new_size);
        if !p.is_null() {
            CURRENT.fetch_sub(layout.size(), Ordering::Relaxed);
            note_alloc(new_size);
        }
        p
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn reset_peak() -> usize {
    let c = CURRENT.load(Ordering::Relaxed);
    PEAK.store(c, Ordering::Relaxed);
    c
}

fn peak_rss_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|v| v.parse::<f64>().ok())
        })
        .map(|kb| kb / 1024.0)
        .unwrap_or(f64::NAN)
}

/// CPU time of the whole process (s), `clock_gettime(CLOCK_PROCESS_CPUTIME_ID)`: the
/// benchmark reports CPU time, not wall time, because on a shared machine the wall time is
/// inflated by whatever else runs. Process-wide, so the assembly done on rayon's worker
/// thread counts too (run with `RAYON_NUM_THREADS=1`: the LU is sequential, and more workers
/// would only add their spinning).
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

/// Seconds of CPU time spent in `f` (this thread).
fn cpu<T>(f: impl FnOnce() -> T) -> (f64, T) {
    let t = cpu_s();
    let out = f();
    (cpu_s() - t, out)
}

const MB: f64 = 1024.0 * 1024.0;
const ODEN: &str = include_str!("../scenarios/oden_hollow_cylinder.toml");

fn usage() -> ! {
    eprintln!(
        "usage: tread-bench-lu [--mesh 8x256,16x512,32x1024] [--scene FILE] [--set KEY=VALUE]... \
         [--dump DIR] [--peer PYTHON] [--orderings colamd,symmetric,amd]"
    );
    std::process::exit(2);
}

struct OrderingRow {
    ordering: LuOrdering,
    symbolic_s: f64,
    numeric_s: f64,
    solve_s: f64,
    entries: Option<usize>,
    held_mb: f64,
    peak_mb: f64,
    residual: f64,
}

/// CPU time of a numeric factorization with these values: the median of 3.
fn numeric_median(s: &mut SparseSolver, vals: &[f64]) -> f64 {
    median(
        (0..3)
            .map(|_| {
                cpu(|| {
                    let _ = s.factorize(vals);
                })
                .0
            })
            .collect(),
    )
}

/// The benchmark runs on a worker of a rayon pool, as `tread` does (see `tread::app::in_pool`).
fn main() {
    tread::app::in_pool(0, run)
}

fn run() {
    let args: Vec<String> = std::env::args().collect();
    let mut meshes: Vec<(usize, usize)> = vec![(8, 256), (16, 512), (32, 1024)];
    let mut scene_text = ODEN.to_string();
    let mut scene_name = "scenarios/oden_hollow_cylinder.toml".to_string();
    let mut sets: Vec<String> = Vec::new();
    let mut dump: Option<std::path::PathBuf> = None;
    let mut peer: Option<String> = None;
    let mut orderings = vec![LuOrdering::Colamd, LuOrdering::Symmetric];
    let mut i = 1;
    while i < args.len() {
        let val = || args.get(i + 1).cloned().unwrap_or_else(|| usage());
        match args[i].as_str() {
            "--mesh" => {
                meshes = val()
                    .split(',')
                    .map(|m| {
                        let (a, b) = m.split_once('x').unwrap_or_else(|| usage());
                        (
                            a.trim().parse().unwrap_or_else(|_| usage()),
                            b.trim().parse().unwrap_or_else(|_| usage()),
                        )
                    })
                    .collect();
            }
            "--scene" => {
                scene_name = val();
                scene_text = std::fs::read_to_string(&scene_name).unwrap_or_else(|e| {
                    eprintln!("tread-bench-lu: cannot read {scene_name}: {e}");
                    std::process::exit(2)
                });
            }
            "--set" => sets.push(val()),
            "--dump" => dump = Some(val().into()),
            "--peer" => peer = Some(val()),
            "--orderings" => {
                orderings = val()
                    .split(',')
                    .map(|o| match o.trim() {
                        "colamd" => LuOrdering::Colamd,
                        "amd" => LuOrdering::Amd,
                        "symmetric" => LuOrdering::Symmetric,
                        _ => usage(),
                    })
                    .collect();
            }
            _ => usage(),
        }
        i += 2;
    }
    if peer.is_some() && dump.is_none() {
        eprintln!("tread-bench-lu: --peer needs --dump DIR (the peer reads the dumped files)");
        std::process::exit(2);
    }
    if let Some(d) = &dump {
        if let Err(e) = std::fs::create_dir_all(d) {
            eprintln!("tread-bench-lu: cannot create {}: {e}", d.display());
            std::process::exit(2);
        }
    }
    println!(
        "scene {scene_name} (steady), extra settings {sets:?}, rayon threads {}",
        rayon::current_num_threads()
    );
    let mut newton_rows = Vec::new();
    let mut lu_rows = Vec::new();
    let mut dumped = Vec::new();
    // Rows are also printed as soon as they are measured (the large meshes take long; a run
    // stopped early keeps what it measured), then again as two tables at the end.
    for &(nr, nt) in &meshes {
        let mut set = vec![
            format!("mesh.n_r={nr}"),
            format!("mesh.n_theta={nt}"),
            "analysis.mode=\"steady\"".to_string(),
            "output.sinks=[\"summary\"]".to_string(),
        ];
        set.extend(sets.iter().cloned());
        let scene = match Scene::from_toml_str(&scene_text, &scene_name, &set) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("{e}");
                std::process::exit(2);
            }
        };
        let mut st = match build_steady(&scene) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("{nr}x{nt}: {e}");
                continue;
            }
        };
        let n = st.n_eq();
        let mut report = StepReport::default();
        let t = Instant::now();
        let (t_solve, res) = cpu(|| solve_steady(&scene, &mut st, false, &mut report, &mut ()));
        let wall_solve = t.elapsed().as_secs_f64();
        if let Err(e) = res {
            eprintln!("{nr}x{nt}: steady solve failed: {e}");
            continue;
        }
        let iters = report.total_iterations.max(1);
        // The Newton solves on this mesh alone (wall time; the symbolic analysis and the
        // coarser meshes of the nested iteration left out).
        let newton_s: f64 = report.steps.iter().map(|s| s.timing.total_s).sum();
        // Parts of one Newton iteration at the converged state.
        let t_asm = median(
            (0..3)
                .map(|_| {
                    cpu(|| {
                        st.evaluate(true);
                    })
                    .0
                })
                .collect(),
        );
        let (cp, ri) = st.pattern();
        let (cp, ri) = (cp.to_vec(), ri.to_vec());
        let vals = st.matrix_values().to_vec();
        let b: Vec<f64> = st.residual().iter().map(|r| -r).collect();
        let bnorm = b
            .iter()
            .map(|v| v * v)
            .sum::<f64>()
            .sqrt()
            .max(f64::MIN_POSITIVE);
        if let Some(d) = &dump {
            let a_path = d.join(format!("steady_{n}.mtx"));
            let b_path = d.join(format!("steady_{n}_rhs.mtx"));
            if let Err(e) = write_matrix_market(&a_path, n, &cp, &ri, &vals)
                .and_then(|_| write_vector_market(&b_path, &b))
            {
                eprintln!("tread-bench-lu: cannot write {}: {e}", a_path.display());
            } else {
                dumped.push((n, a_path, b_path));
            }
        }
        let mut rows = Vec::new();
        for &ordering in &orderings {
            let base = reset_peak();
            let t = cpu_s();
            let mut s = match SparseSolver::with_lu_ordering(n, &cp, &ri, LinearKind::Lu, ordering)
            {
                Ok(s) => s,
                Err(e) => {
                    eprintln!("{nr}x{nt} {ordering:?}: symbolic failed: {e}");
                    continue;
                }
            };
            s.set_track_determinant(false);
            let symbolic_s = cpu_s() - t;
            let before = reset_peak();
            let ok = s.factorize(&vals).is_ok();
            let peak_mb = (PEAK.load(Ordering::Relaxed) - before) as f64 / MB;
            let held_mb = (CURRENT.load(Ordering::Relaxed) as f64 - base as f64) / MB;
            let numeric_s = numeric_median(&mut s, &vals);
            let mut x = b.clone();
            let (solve_s, solved) = cpu(|| s.solve_in_place(&mut x).is_ok());
            // ‖A x − b‖ / ‖b‖
            let mut r = b.iter().map(|v| -v).collect::<Vec<f64>>();
            for j in 0..n {
                for k in cp[j]..cp[j + 1] {
                    r[ri[k]] += vals[k] * x[j];
                }
            }
            let residual = if ok && solved {
                r.iter().map(|v| v * v).sum::<f64>().sqrt() / bnorm
            } else {
                f64::NAN
            };
            let entries = s.lu_factor_entries();
            if ordering == LuOrdering::Symmetric {
                // The same LU in single precision (what Newton's GMRES preconditioner keeps).
                s.set_single_precision_factors(true);
                let _ = s.factorize(&vals);
                let numeric32 = numeric_median(&mut s, &vals);
                let mut x = b.clone();
                let _ = s.solve_in_place(&mut x);
                let solve32 = median(
                    (0..5)
                        .map(|_| {
                            x.copy_from_slice(&b);
                            cpu(|| s.solve_in_place(&mut x).is_ok()).0
                        })
                        .collect(),
                );
                let mut r = b.iter().map(|v| -v).collect::<Vec<f64>>();
                for j in 0..n {
                    for k in cp[j]..cp[j + 1] {
                        r[ri[k]] += vals[k] * x[j];
                    }
                }
                let res32 = r.iter().map(|v| v * v).sum::<f64>().sqrt() / bnorm;
                println!(
                    "{nr}x{nt} multifrontal LU in single precision: numeric {numeric32:.4} s \
                     (double {numeric_s:.4} s), solve {solve32:.4} s (double {solve_s:.4} s), \
                     ‖Ax−b‖/‖b‖ {res32:.2e}"
                );
                s.set_single_precision_factors(false);
            }
            rows.push(OrderingRow {
                ordering,
                symbolic_s,
                numeric_s,
                solve_s,
                entries,
                held_mb,
                peak_mb,
                residual,
            });
        }
        let default = LuOrdering::default();
        let def = rows.iter().find(|r| r.ordering == default);
        let lu_s = def.map_or(f64::NAN, |r| r.numeric_s + r.solve_s);
        let peak_mb = peak_rss_mb();
        // The physical limit of a Newton step: one LU of the exact tangent. With the damping's
        // matrix-free or banded tangent the LU above is the preconditioner's (a matrix with
        // less coupling); the exact one is the assembled tangent at the same state.
        let exact_lu_s = match st.sys.steady_damping_tangent() {
            Some(SteadyDampingTangent::MatrixFree | SteadyDampingTangent::Banded) => {
                st.sys
                    .set_steady_damping_tangent(SteadyDampingTangent::Assembled);
                st.evaluate(true);
                let (cp, ri) = st.pattern();
                let vals = st.matrix_values().to_vec();
                match SparseSolver::with_lu_ordering(n, cp, ri, LinearKind::Lu, default) {
                    Ok(mut s) => {
                        s.set_track_determinant(false);
                        let ok = s.factorize(&vals).is_ok();
                        let numeric = numeric_median(&mut s, &vals);
                        let mut x = b.clone();
                        let (solve, solved) = cpu(|| s.solve_in_place(&mut x).is_ok());
                        if ok && solved {
                            numeric + solve
                        } else {
                            f64::NAN
                        }
                    }
                    Err(e) => {
                        eprintln!("{nr}x{nt}: exact tangent: symbolic failed: {e}");
                        f64::NAN
                    }
                }
            }
            _ => lu_s,
        };
        let newton_row = format!(
            "| {nr}x{nt} | {n} | {} | {} | {:.3} ({:.1}) | {:.3} | {:.3} | {:.3} | {:.2} | {:.2} | {:.3} | {:.2} | {:.3} | {:.2} | {:.0} |",
            vals.len(),
            iters,
            t_solve,
            wall_solve,
            t_solve / iters as f64,
            t_asm,
            lu_s,
            (t_asm + lu_s) / lu_s,
            t_solve / iters as f64 / lu_s,
            newton_s / iters as f64,
            newton_s / iters as f64 / lu_s,
            exact_lu_s,
            newton_s / iters as f64 / exact_lu_s,
            peak_mb,
        );
        println!("newton {newton_row}");
        newton_rows.push(newton_row);
        for r in &rows {
            let lu_row = format!(
                "| {nr}x{nt} | {n} | {:?} | {:.3} | {:.3} | {:.4} | {} | {:.2} | {:.0} | {:.0} | {:.1e} |",
                r.ordering,
                r.symbolic_s,
                r.numeric_s,
                r.solve_s,
                r.entries.map_or("-".to_string(), |e| e.to_string()),
                r.entries.map_or(f64::NAN, |e| e as f64 / vals.len() as f64),
                r.held_mb,
                r.peak_mb,
                r.residual,
            );
            println!("lu {lu_row}");
            lu_rows.push(lu_row);
        }
        // Print as we go: the large meshes take minutes.
        eprintln!("done {nr}x{nt} ({n} DOFs)");
    }
    println!();
    println!(
        "Newton iteration against one LU (CPU s of the process; default ordering {:?}):",
        LuOrdering::default()
    );
    println!("| mesh | DOFs | nnz(A) | Newton iterations | steady solve CPU (wall) (s) | per iteration (s) | assembly R+K (s) | LU factor+solve (s) | (assembly+LU)/LU | per iteration / LU | Newton phase per iteration (wall s) | Newton phase / LU | exact tangent LU factor+solve (s) | Newton phase / exact LU | peak RSS (MB) |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for r in &newton_rows {
        println!("{r}");
    }
    println!();
    println!("LU orderings on the converged tangent (CPU s of the process; numeric: median of 3 refactorizations):");
    println!("| mesh | DOFs | ordering | symbolic (s) | numeric (s) | solve (s) | nnz(L+U) | fill nnz(L+U)/nnz(A) | factor heap (MB) | heap peak in 1st factorization (MB) | ‖Ax−b‖/‖b‖ |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    for r in &lu_rows {
        println!("{r}");
    }
    if let Some(py) = &peer {
        let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tools/lu_peer.py");
        for (n, a, b) in &dumped {
            println!();
            println!("peer solvers on the {n}-DOF tangent:");
            let out = std::process::Command::new(py)
                .arg(script)
                .arg(a)
                .arg(b)
                .output();
            match out {
                Ok(o) => {
                    print!("{}", String::from_utf8_lossy(&o.stdout));
                    if !o.status.success() {
                        eprint!("{}", String::from_utf8_lossy(&o.stderr));
                    }
                }
                Err(e) => eprintln!("tread-bench-lu: cannot run {py}: {e}"),
            }
        }
    }
}
