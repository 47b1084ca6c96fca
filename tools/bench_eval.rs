//! Cost of one evaluation of the steady rolling system (a benchmark, not a test): the default
//! scene (`scenarios/oden_hollow_cylinder.toml`) is solved in the steady mode, then at the
//! converged state the residual-and-tangent evaluation, the residual-only evaluation and one
//! product of the matrix-free damping correction (GMRES's extra work per product) are timed,
//! each the median and minimum of `--repeats` calls.
//!
//! ```text
//! tread-bench-eval [--repeats N] [--main-thread] [KEY=VALUE ...]
//! RAYON_NUM_THREADS=1 tread-bench-eval mesh.n_r=16 mesh.n_theta=512
//! RAYON_NUM_THREADS=1 tread-bench-eval mesh.n_r=16 mesh.n_theta=512 time.strain_rate_damping=0
//! ```
//!
//! KEY=VALUE are scene overrides as `tread run --set` takes them. By default everything runs
//! on a worker of a rayon pool, as `tread` does (`tread::app::in_pool`); `--main-thread` runs it
//! from the main thread instead, each parallel loop then handing its work to the global pool.

#[path = "common.rs"]
mod common;
use common::{median, solved_steady};

use std::time::Instant;
use tread::io::Scene;
use tread::solver::NonlinearSystem;

const ODEN: &str = include_str!("../scenarios/oden_hollow_cylinder.toml");

fn main() {
    let mut repeats = 21usize;
    let mut main_thread = false;
    let mut sets = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--repeats" => match args.next().and_then(|v| v.parse().ok()) {
                Some(n) if n > 0 => repeats = n,
                _ => {
                    eprintln!("--repeats takes a positive count");
                    std::process::exit(2);
                }
            },
            "--main-thread" => main_thread = true,
            s if s.contains('=') => sets.push(s.to_string()),
            s => {
                eprintln!(
                    "unknown argument {s:?}: expected --repeats N, --main-thread or KEY=VALUE"
                );
                std::process::exit(2);
            }
        }
    }
    if main_thread {
        run(repeats, &sets);
    } else {
        tread::app::in_pool(0, || run(repeats, &sets));
    }
}

/// Median and minimum of `repeats` timings of `f`.
fn timed(repeats: usize, mut f: impl FnMut()) -> (f64, f64) {
    let ts: Vec<f64> = (0..repeats)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .collect();
    let min = ts.iter().copied().fold(f64::INFINITY, f64::min);
    (median(ts), min)
}

fn run(repeats: usize, sets: &[String]) {
    let scene = match Scene::from_toml_str(ODEN, "bench", sets) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    let mut st = solved_steady(&scene);
    println!(
        "{} equations, overrides {sets:?}, rayon threads {}",
        st.n_eq(),
        rayon::current_num_threads()
    );
    let (m, lo) = timed(repeats, || {
        st.evaluate(true);
    });
    println!("residual and tangent: median {m:.4} s, min {lo:.4} s");
    let (m, lo) = timed(repeats, || {
        st.evaluate(false);
    });
    println!("residual only:        median {m:.4} s, min {lo:.4} s");
    let n = st.n_eq();
    let v = vec![1e-3; n];
    let mut out = vec![0.0; n];
    let (m, lo) = timed(repeats, || {
        out.fill(0.0);
        st.tangent_correction(&v, &mut out);
    });
    println!("damping correction:   median {m:.4} s, min {lo:.4} s");
}
