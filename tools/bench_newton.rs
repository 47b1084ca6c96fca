//! Benchmark of one Newton iteration of the steady-spinning problem (Q2, compressible
//! neo-Hookean) on meshes from about 5k to 500k DOFs:
//!
//! * assembly of residual + tangent (serial loop, and parallel on 1 and 2 rayon threads),
//! * symbolic analysis (once per mesh), numeric factorization, solve,
//! * one full Newton iteration (assembly + factorization + solve + residual norm),
//! * the ratio iteration / (factorization + solve), and the peak resident memory.
//!
//! Every time is the median of `--repeats` runs. Usage (see docs/benchmarks.md):
//!
//! ```text
//! cargo run --release --bin tread-bench -- [--max-dofs N] [--repeats R] [--kind cholesky|lu] [--out DIR]
//! ```
//!
//! Writes a Markdown table to stdout and `DIR/bench_newton.csv` (default `out/bench`).

#[path = "common.rs"]
mod common;
use common::median;

use std::time::Instant;
use tread::material::{Material, NeoHookean};
use tread::mesh::{annulus, AnnulusSpec};
use tread::model::SolidSystem;
use tread::physics::{PressureMode, SolidModel};
use tread::solver::{LinearKind, NonlinearSystem, SparseSolver};

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

fn time<F: FnMut()>(repeats: usize, mut f: F) -> f64 {
    median(
        (0..repeats)
            .map(|_| {
                let t = Instant::now();
                f();
                t.elapsed().as_secs_f64()
            })
            .collect(),
    )
}

struct Args {
    max_dofs: usize,
    repeats: usize,
    kind: LinearKind,
    out: std::path::PathBuf,
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        max_dofs: 600_000,
        repeats: 3,
        kind: LinearKind::Cholesky,
        out: "out/bench".into(),
    };
    let mut it = std::env::args().skip(1);
    while let Some(k) = it.next() {
        let mut val = || it.next().ok_or(format!("{k} needs a value"));
        match k.as_str() {
            "--max-dofs" => a.max_dofs = val()?.parse().map_err(|e| format!("--max-dofs: {e}"))?,
            "--repeats" => {
                a.repeats = val()?
                    .parse::<usize>()
                    .map_err(|e| format!("--repeats: {e}"))?
                    .max(1)
            }
            "--kind" => {
                a.kind = match val()?.as_str() {
                    "cholesky" => LinearKind::Cholesky,
                    "lu" => LinearKind::Lu,
                    o => return Err(format!("--kind: unknown solver `{o}` (cholesky | lu)")),
                }
            }
            "--out" => a.out = val()?.into(),
            "-h" | "--help" => {
                println!(
                    "tread-bench [--max-dofs N] [--repeats R] [--kind cholesky|lu] [--out DIR]"
                );
                std::process::exit(0);
            }
            o => return Err(format!("unknown argument `{o}`")),
        }
    }
    Ok(a)
}

fn main() {
    let args = match parse_args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("tread-bench: {e}");
            std::process::exit(2);
        }
    };
    let pool1 = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap_or_else(|e| {
            eprintln!("tread-bench: cannot build a thread pool: {e}");
            std::process::exit(1)
        });
    let pool2 = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap_or_else(|e| {
            eprintln!("tread-bench: cannot build a thread pool: {e}");
            std::process::exit(1)
        });
    let sizes = [
        (8usize, 80usize),
        (16, 160),
        (36, 360),
        (56, 560),
        (80, 800),
    ];
    let mut rows = Vec::new();
    println!("| dofs | nnz | factor nnz | assemble serial [s] | assemble 1 thr [s] | assemble 2 thr [s] | speed-up 2 thr | symbolic [s] | factor [s] | solve [s] | iteration [s] | iteration/(factor+solve) | peak RSS [MB] |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for (n_r, n_theta) in sizes {
        let mesh = annulus(&AnnulusSpec {
            ri: 1.0,
            ro: 2.0,
            n_r,
            n_theta,
            degree: 2,
            grading_r: 1.0,
            grading_theta: 0.0,
        });
        let mut model = SolidModel::new(
            mesh,
            Material::NeoHookean(NeoHookean::new(200.0, 1800.0)),
            0.027,
            PressureMode::None,
        );
        model.omega2 = 20.0f64.powi(2);
        let mut sys = SolidSystem::new(model, "hub");
        let n = sys.n_dofs();
        if n > args.max_dofs {
            break;
        }
        // A non-trivial state: half a Newton step is not needed; stresses at u = 0 are zero but
        // the kernels do the same work at any state.
        sys.asm.parallel = false;
        let t_serial = time(args.repeats, || {
            sys.evaluate(true);
        });
        sys.asm.parallel = true;
        let t_p1 = pool1.install(|| {
            time(args.repeats, || {
                sys.evaluate(true);
            })
        });
        let t_p2 = pool2.install(|| {
            time(args.repeats, || {
                sys.evaluate(true);
            })
        });
        let t0 = Instant::now();
        let (cp, ri) = sys.pattern();
        let mut solver = match SparseSolver::new(n, cp, ri, args.kind) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("tread-bench: symbolic analysis failed: {e}");
                std::process::exit(1);
            }
        };
        let t_sym = t0.elapsed().as_secs_f64();
        // One full Newton iteration as the solver runs it (2 threads): assemble R and K,
        // factorize, solve, update the state. Each phase is timed inside the same iteration so
        // the ratio iteration / (factor + solve) compares times from the same run.
        let mut dx = vec![0.0; n];
        let (mut fs, mut ss, mut its, mut ratios) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        pool2.install(|| {
            for _ in 0..args.repeats {
                let t = Instant::now();
                sys.evaluate(true);
                let ta = t.elapsed().as_secs_f64();
                let t = Instant::now();
                if let Err(e) = solver.factorize(sys.matrix_values()) {
                    eprintln!("tread-bench: factorization failed: {e}");
                    std::process::exit(1);
                }
                let tf = t.elapsed().as_secs_f64();
                let t = Instant::now();
                for (d, r) in dx.iter_mut().zip(sys.residual()) {
                    *d = -r;
                }
                if let Err(e) = solver.solve_in_place(&mut dx) {
                    eprintln!("tread-bench: solve failed: {e}");
                    std::process::exit(1);
                }
                sys.update(0.0, &dx);
                let ts = t.elapsed().as_secs_f64();
                fs.push(tf);
                ss.push(ts);
                its.push(ta + tf + ts);
                ratios.push((ta + tf + ts) / (tf + ts));
            }
        });
        let (t_fact, t_solve, t_iter) = (median(fs), median(ss), median(its));
        let ratio = median(ratios);
        let rss = peak_rss_mb();
        println!(
            "| {n} | {} | {} | {t_serial:.4} | {t_p1:.4} | {t_p2:.4} | {:.2} | {t_sym:.3} | {t_fact:.3} | {t_solve:.4} | {t_iter:.3} | {ratio:.3} | {rss:.0} |",
            sys.asm.nnz(),
            solver.factor_nnz(),
            t_serial / t_p2
        );
        rows.push(vec![
            n as f64,
            sys.asm.nnz() as f64,
            solver.factor_nnz() as f64,
            t_serial,
            t_p1,
            t_p2,
            t_serial / t_p2,
            t_sym,
            t_fact,
            t_solve,
            t_iter,
            ratio,
            rss,
        ]);
    }
    if let Err(e) = std::fs::create_dir_all(&args.out) {
        eprintln!("tread-bench: cannot create {}: {e}", args.out.display());
        std::process::exit(1);
    }
    let path = args.out.join("bench_newton.csv");
    if let Err(e) = tread::io::output::write_csv(
        &path,
        &[
            "dofs",
            "nnz",
            "factor_nnz",
            "assemble_serial_s",
            "assemble_1thr_s",
            "assemble_2thr_s",
            "speedup_2thr",
            "symbolic_s",
            "factor_s",
            "solve_s",
            "iteration_s",
            "iteration_over_factor_solve",
            "peak_rss_mb",
        ],
        rows.into_iter(),
    ) {
        eprintln!("tread-bench: {e}");
        std::process::exit(1);
    }
    println!("\nwritten {}", path.display());
}
