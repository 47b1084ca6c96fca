//! Benchmark of the recorder's cost: the same load-stepping solve (steady spinning, Q2
//! neo-Hookean) run
//!
//! * with no recorder at all (`&mut ()`),
//! * with an empty fan-out (`Recorders::new()`: what `tread run` uses with `sinks = []` and
//!   `--quiet`),
//! * with every sink on (CSV, VTU, MCAP, PNG, and Rerun when built with the `rerun` feature),
//!
//! alternating the variants (order rotated every round), `--repeats` times each; prints the
//! medians and the ratios, plus
//! the cost of one step event on an empty fan-out (nanoseconds, over 10⁶ calls). Usage:
//!
//! ```text
//! cargo run --release --bin tread-bench-log -- [--repeats R] [--n-theta N] [--steps S] [--out DIR]
//! ```

#[path = "common.rs"]
mod common;
use common::median;

use std::path::PathBuf;
use std::time::Instant;
use tread::app::build_system;
use tread::driver::spinning::solve_spinning;
use tread::io::record::{self, Recorder, Recorders, RunMeta, StepInfo};
use tread::io::Scene;
use tread::solver::stepping::{StepOptions, StepReport};
use tread::solver::{LinearKind, NewtonOptions};

fn scene(n_theta: usize, steps: usize) -> Result<Scene, String> {
    let text = format!(
        r#"
[scene]
name = "bench_log"
[geometry]
ri = 1.0
ro = 2.0
[mesh]
n_r = 6
n_theta = {n_theta}
[material]
model = "neo_hookean"
mu = 200.0
lambda = 1800.0
rho = 0.027
[analysis]
mode = "spinning"
[motion]
omega = 40.0
[solver]
load_steps = {steps}
linear = "cholesky"
[output]
sinks = ["summary", "csv", "vtu", "mcap", "rerun", "png"]
"#
    );
    Scene::from_toml_str(&text, "bench_log", &[]).map_err(|e| e.to_string())
}

#[derive(Clone, Copy, PartialEq, Debug)]
enum Variant {
    Unit,
    Empty,
    All,
}

/// One solve; returns (seconds, accepted steps).
fn run(scene: &Scene, v: Variant, out: &std::path::Path) -> Result<(f64, usize), String> {
    let mut sys = build_system(scene).map_err(|e| e.to_string())?;
    let newton = NewtonOptions {
        tol: 1e-10,
        ..Default::default()
    };
    let steps = StepOptions {
        initial_steps: scene.solver.load_steps,
        max_cutbacks: 10,
        verbose: false,
    };
    let mut report = StepReport::default();
    let toml = scene.to_toml_string();
    let t0 = Instant::now();
    let r = match v {
        Variant::Unit => solve_spinning(
            &mut sys,
            scene.motion.omega,
            LinearKind::Cholesky,
            newton,
            &steps,
            &mut report,
            &mut (),
        ),
        Variant::Empty | Variant::All => {
            let mut rec = if v == Variant::All {
                tread::app::build_recorders(scene, out, true).0
            } else {
                Recorders::new()
            };
            rec.run_started(&RunMeta {
                scene_name: "bench_log",
                mode: "spinning",
                scene_toml: &toml,
                version: env!("CARGO_PKG_VERSION"),
                features: record::build_features(),
                mesh: Some(&sys.model.mesh),
                time_name: "load_factor",
                time_end: 1.0,
                revolution_period: None,
            });
            let r = solve_spinning(
                &mut sys,
                scene.motion.omega,
                LinearKind::Cholesky,
                newton,
                &steps,
                &mut report,
                &mut rec,
            );
            for e in rec.run_finished(&record::RunEnd {
                converged: r.is_ok(),
                interrupted: false,
                error: None,
                steps: report.steps.len() as u64,
                wall_time_s: 0.0,
                summary: None,
            }) {
                eprintln!("warning: {e}");
            }
            r
        }
    };
    let secs = t0.elapsed().as_secs_f64();
    r.map_err(|e| e.to_string())?;
    Ok((secs, report.steps.iter().filter(|s| s.converged).count()))
}

fn main() {
    let mut repeats = 5usize;
    let mut n_theta = 64usize;
    let mut steps = 24usize;
    let mut out = PathBuf::from("out/bench_log");
    let mut it = std::env::args().skip(1);
    while let Some(k) = it.next() {
        let v = it.next().unwrap_or_default();
        match k.as_str() {
            "--repeats" => repeats = v.parse().unwrap_or(5).max(1),
            "--n-theta" => n_theta = v.parse().unwrap_or(64),
            "--steps" => steps = v.parse().unwrap_or(24).max(1),
            "--out" => out = PathBuf::from(v),
            _ => {
                eprintln!(
                    "usage: tread-bench-log [--repeats R] [--n-theta N] [--steps S] [--out DIR]"
                );
                std::process::exit(2);
            }
        }
    }
    let scene = match scene(n_theta, steps) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2)
        }
    };
    let _ = std::fs::create_dir_all(&out);
    let variants = [Variant::Unit, Variant::Empty, Variant::All];
    let mut times: Vec<Vec<f64>> = vec![Vec::new(); 3];
    let mut nsteps = 0;
    // One warm-up of each, then alternate, rotating the order every round (no variant always
    // runs right after the heavy one).
    for rep in 0..=repeats {
        for j in 0..3 {
            let k = (j + rep) % 3;
            let v = &variants[k];
            match run(&scene, *v, &out) {
                Ok((t, n)) => {
                    nsteps = n;
                    if rep > 0 {
                        times[k].push(t);
                    }
                }
                Err(e) => {
                    eprintln!("solve failed ({v:?}): {e}");
                    std::process::exit(1);
                }
            }
        }
    }
    // Ratios within each round (the variants of a round run back to back: slow drifts of the
    // machine's load cancel), then their median.
    let round_ratio =
        |k: usize| median(times[k].iter().zip(&times[0]).map(|(a, b)| a / b).collect());
    let rr: Vec<f64> = (0..3).map(round_ratio).collect();
    let mins: Vec<f64> = times
        .iter()
        .map(|t| t.iter().copied().fold(f64::INFINITY, f64::min))
        .collect();
    let m: Vec<f64> = times.into_iter().map(median).collect();
    // Per-event cost on an empty fan-out.
    let mut empty = Recorders::new();
    let n_events = 1_000_000u64;
    let t0 = Instant::now();
    for i in 0..n_events {
        let info = StepInfo {
            index: i,
            time: i as f64,
            dt: 1.0,
            newton_iterations: 3,
            residual: 1e-12,
            is_final: false,
        };
        let r: &mut dyn Recorder = std::hint::black_box(&mut empty);
        if r.wants_view(&info) {
            unreachable!();
        }
        r.step(&info, None);
    }
    let per_event_ns = t0.elapsed().as_secs_f64() * 1e9 / n_events as f64;
    println!(
        "spinning solve, n_theta = {n_theta}, {nsteps} load steps, median of {repeats} (features: {})",
        if record::build_features().is_empty() { "none" } else { record::build_features() }
    );
    println!(
        "| recorder | median (s) | ratio of medians | min (s) | ratio of minima | median of per-round ratios |"
    );
    println!("|---|---|---|---|---|---|");
    for (k, name) in ["none (`&mut ()`)", "empty fan-out (no sinks)", "all sinks"]
        .iter()
        .enumerate()
    {
        println!(
            "| {name} | {:.4} | {:.4} | {:.4} | {:.4} | {:.4} |",
            m[k],
            m[k] / m[0],
            mins[k],
            mins[k] / mins[0],
            rr[k]
        );
    }
    println!("step event on an empty fan-out: {per_event_ns:.1} ns");
}
