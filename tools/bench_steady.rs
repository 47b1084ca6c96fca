//! Steady-mode benchmark (not a test): cost of arc-length continuation per step against one
//! LU factorization + solve at the same size, and steady vs transient wall time.
//!
//! ```text
//! cargo run --release --bin tread-bench-steady -- [--n-theta 64,128] [--compare]
//! ```
//!
//! 1. For each circumferential resolution, the paper-like frictional scene
//!    (`scenarios/oden_steady_sweep.toml`: m_n = 2, continuation in ω from 10 rad/s) is followed
//!    to 40 rad/s; per step: corrector iterations, wall time, the time of one LU factor + solve
//!    at the converged point (measured inside the continuation), and their ratio. Medians.
//! 2. With `--compare`: `tread compare` of `scenarios/oden_hollow_cylinder.toml` at 10 rad/s for
//!    transient `error_tol` 1e-3 and 1e-4: the transient's difference from the steady solution
//!    and both wall times.

#[path = "common.rs"]
mod common;
use common::median;

use tread::app::RunOptions;
use tread::io::Scene;

const SWEEP: &str = include_str!("../scenarios/oden_steady_sweep.toml");
const ODEN: &str = include_str!("../scenarios/oden_hollow_cylinder.toml");

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mut n_thetas = vec![64usize, 128];
    let mut compare = false;
    let mut i = 1;
    while i < args.len() {
        match args[i].as_str() {
            "--n-theta" if i + 1 < args.len() => {
                n_thetas = args[i + 1]
                    .split(',')
                    .filter_map(|s| s.trim().parse().ok())
                    .collect();
                i += 1;
            }
            "--compare" => compare = true,
            other => {
                eprintln!("tread-bench-steady: unknown argument `{other}` (use --n-theta A,B and --compare)");
                std::process::exit(2);
            }
        }
        i += 1;
    }
    let out = std::env::temp_dir().join(format!("tread_bench_steady_{}", std::process::id()));
    println!("| n_theta | DOFs | steps | median corrector iterations | median step wall (s) | median LU factor+solve (s) | median ratio | reached omega |");
    println!("|---|---|---|---|---|---|---|---|");
    for nt in &n_thetas {
        let set = vec![
            format!("mesh.n_theta={nt}"),
            "continuation.target=40".to_string(),
            "output.sinks=[\"summary\"]".to_string(),
        ];
        let scene = match Scene::from_toml_str(SWEEP, "sweep", &set) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("{e}");
                std::process::exit(2);
            }
        };
        let opts = RunOptions {
            out_dir: out.join(format!("sweep_{nt}")),
            verbose: false,
            quiet: true,
        };
        let summary = match tread::app::run(&scene, &opts) {
            Ok(o) => o.summary,
            Err(e) => {
                eprintln!("n_theta = {nt}: {e}");
                std::fs::read_to_string(opts.out_dir.join("summary.json"))
                    .ok()
                    .and_then(|t| serde_json::from_str(&t).ok())
                    .unwrap_or_default()
            }
        };
        let branch = summary["results"]["branch"]
            .as_array()
            .cloned()
            .unwrap_or_default();
        let steps: Vec<&serde_json::Value> = branch.iter().skip(1).collect();
        let get = |k: &str| -> Vec<f64> {
            steps
                .iter()
                .map(|p| p[k].as_f64().unwrap_or(f64::NAN))
                .collect()
        };
        let (w, f, it) = (get("wall_time_s"), get("factor_solve_s"), get("iterations"));
        let ratio: Vec<f64> = w.iter().zip(&f).map(|(a, b)| a / b).collect();
        println!(
            "| {nt} | {} | {} | {:.1} | {:.4} | {:.4} | {:.2} | {:.3} |",
            summary["dofs"],
            steps.len(),
            median(it),
            median(w),
            median(f),
            median(ratio),
            summary["results"]["omega"].as_f64().unwrap_or(f64::NAN)
        );
    }
    if compare {
        println!();
        println!("| transient error_tol | Fy rel diff | field rel L2 | transient wall (s) | steady wall (s) | ratio |");
        println!("|---|---|---|---|---|---|");
        for tol in ["1e-3", "1e-4"] {
            let set = vec![
                format!("time.error_tol={tol}"),
                "output.sinks=[\"summary\",\"csv\"]".to_string(),
            ];
            let Ok(scene) = Scene::from_toml_str(ODEN, "oden", &set) else {
                std::process::exit(2);
            };
            let opts = RunOptions {
                out_dir: out.join(format!("compare_{tol}")),
                verbose: false,
                quiet: true,
            };
            match tread::driver::compare::run(&scene, &opts) {
                Ok(o) => {
                    let Some(c) = o.typed.compare() else {
                        continue;
                    };
                    println!(
                        "| {tol} | {:.3e} | {:.3e} | {:.2} | {:.3} | {:.0} |",
                        c.hub_force_y_rel_diff,
                        c.field_rel_l2,
                        c.wall_time_transient_s,
                        c.wall_time_steady_s,
                        c.speedup
                    );
                }
                Err(e) => eprintln!("compare at error_tol {tol}: {e}"),
            }
        }
    }
    let _ = std::fs::remove_dir_all(&out);
}
