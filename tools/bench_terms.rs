//! "Run only the terms a scene needs" , measured (not a test):
//!
//! ```text
//! cargo run --release --bin tread-bench-terms -- [--repeats N]
//! ```
//!
//! 1. **Contact block alone**: on the converged steady state of
//!    `scenarios/oden_hollow_cylinder.toml` (3 × 64 Q2), the contact-element assembly (block 1:
//!    residual and tangent) is timed with μ = 0.3 and with the same state and μ = 0 (friction
//!    law `none`): the frictionless kernel skips the friction law and its derivatives.
//! 2. **Whole runs**: the static indentation `scenarios/indentation_friction.toml` (μ > 0: an
//!    unsymmetric tangent, LU) against the same scene with `friction.mu = 0` (symmetric:
//!    Cholesky), and the steady mode of the Oden scene with and without friction: wall time,
//!    Newton iterations, time per iteration, the linear solver used and summary.json `terms`.
//!
//! Medians of `--repeats` (default 7) runs, interleaved; one thread (reproducible).

#[path = "common.rs"]
mod common;
use common::{median, solved_steady};

use std::time::Instant;
use tread::app::RunOptions;
use tread::contact::SlipKinematics;
use tread::io::Scene;
use tread::solver::NonlinearSystem;

const ODEN: &str = include_str!("../scenarios/oden_hollow_cylinder.toml");
const INDENT: &str = include_str!("../scenarios/indentation_friction.toml");

fn scene(text: &str, set: &[&str]) -> Scene {
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    match Scene::from_toml_str(text, "bench", &set) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    }
}

/// Median time of one contact-block assembly (residual and tangent) at the steady state.
fn contact_block_time(set: &[&str], repeats: usize) -> (f64, f64) {
    let sc = scene(ODEN, set);
    let mut st = solved_steady(&sc);
    let sys = &mut st.sys;
    let inner = 200;
    let mut times = Vec::new();
    let mut full = Vec::new();
    for _ in 0..repeats {
        let Some(c) = sys.contact.as_ref() else {
            std::process::exit(1);
        };
        let (mesh, dofs, x, xp) = (&sys.model.mesh, &sys.dofs, &sys.x, &sys.x_prev);
        let kin = match sys.steady_omega {
            Some(omega) => SlipKinematics::Steady { omega },
            None => SlipKinematics::Static {
                x_prev: xp,
                dtau: 1.0,
            },
        };
        let t0 = Instant::now();
        for _ in 0..inner {
            sys.asm.add_block(1, dofs, true, |e, loc| {
                c.kernel(mesh, dofs, x, &kin, e, loc, true)
            });
        }
        times.push(t0.elapsed().as_secs_f64() / inner as f64);
        let t1 = Instant::now();
        for _ in 0..20 {
            sys.evaluate(true);
        }
        full.push(t1.elapsed().as_secs_f64() / 20.0);
    }
    (median(times), median(full))
}

struct RunStats {
    wall: f64,
    iterations: f64,
    linear: String,
    terms: serde_json::Value,
}

fn run_stats(text: &str, set: &[&str], repeats: usize) -> RunStats {
    let sc = scene(text, set);
    let dir = std::env::temp_dir().join(format!("tread_bench_terms_{}", std::process::id()));
    let mut walls = Vec::new();
    let mut last = serde_json::Value::Null;
    for _ in 0..repeats {
        let opts = RunOptions {
            out_dir: dir.clone(),
            verbose: false,
            quiet: true,
        };
        let t0 = Instant::now();
        match tread::app::run(&sc, &opts) {
            Ok(o) => last = o.summary,
            Err(e) => {
                eprintln!("run failed: {e}");
                std::process::exit(1);
            }
        }
        walls.push(t0.elapsed().as_secs_f64());
    }
    let _ = std::fs::remove_dir_all(&dir);
    RunStats {
        wall: median(walls),
        iterations: last["newton_iterations"].as_f64().unwrap_or(f64::NAN),
        linear: last["solver"]["linear"].as_str().unwrap_or("?").to_string(),
        terms: last["terms"].clone(),
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mut repeats = 7usize;
    if let Some(i) = args.iter().position(|a| a == "--repeats") {
        repeats = args
            .get(i + 1)
            .and_then(|v| v.parse().ok())
            .unwrap_or(7)
            .max(1);
    }
    if let Err(e) = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build_global()
    {
        eprintln!("warning: {e}");
    }
    let steady = ["analysis.mode=\"steady\""];
    let steady_nf = ["analysis.mode=\"steady\"", "friction.mu=0"];
    let (cf, ff) = contact_block_time(&steady, repeats);
    let (c0, f0) = contact_block_time(&steady_nf, repeats);
    println!("## Contact block at the steady state (oden_hollow_cylinder, 3 x 64 Q2), median of {repeats}");
    println!();
    println!("| friction | contact block (us) | whole assembly (ms) |");
    println!("|---|---|---|");
    println!("| mu = 0.3 | {:.2} | {:.3} |", cf * 1e6, ff * 1e3);
    println!("| none | {:.2} | {:.3} |", c0 * 1e6, f0 * 1e3);
    println!("| ratio none / mu | {:.3} | {:.3} |", c0 / cf, f0 / ff);
    println!();
    println!("## Whole runs, median of {repeats}");
    println!();
    println!("| scene | wall (s) | Newton iterations | s / iteration | linear | terms |");
    println!("|---|---|---|---|---|---|");
    let cases: [(&str, &str, &[&str]); 4] = [
        ("indentation, mu = 0.3", INDENT, &[]),
        ("indentation, no friction", INDENT, &["friction.mu=0"]),
        ("steady rolling, mu = 0.3", ODEN, &steady),
        ("steady rolling, no friction", ODEN, &steady_nf),
    ];
    for (name, text, set) in cases {
        let r = run_stats(text, set, repeats);
        println!(
            "| {name} | {:.4} | {} | {:.5} | {} | {} |",
            r.wall,
            r.iterations,
            r.wall / r.iterations.max(1.0),
            r.linear,
            r.terms
        );
    }
}
