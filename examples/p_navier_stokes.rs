//! The p-method for 2D Navier–Stokes on coarse quadtree meshes, with effectivity indices
//! against exact solutions.
//!
//! ```text
//! cargo run --release --no-default-features --example p_navier_stokes -- kovasznay
//! cargo run --release --no-default-features --example p_navier_stokes -- taylor-green [TOL] [STEPS]
//! ```
//!
//! `kovasznay`: steady Kovasznay flow at Re = 40 on 12 cells, uniform degrees 2..=7 (error,
//! estimates by enrichment +1 and +2, effectivities) and the p-adaptive loop.
//! `taylor-green`: the Taylor–Green vortex on a graded 25-cell mesh, Crank–Nicolson (dt = 0.02,
//! STEPS steps, default 5), the per-step table of the p-adaptive run with tolerance TOL
//! (default 1e-4; every attempt of every step: time, degree histogram, unknowns, estimate,
//! true error, global and local effectivity) and the uniform runs p = 5..=8 for comparison.

use std::f64::consts::PI;
use std::process::ExitCode;
use tread::adapt::p_navier_stokes::{
    adapt_steady, degree_histogram, effectivity, estimate, exact_error, run_transient,
    PAdaptParams, PMarking, SteadyProblem, SweepReport, TimeParams, TransientProblem,
};
use tread::adapt::quadtree::Quadtree;

const RE: f64 = 40.0;

fn kovasznay_lambda() -> f64 {
    RE / 2.0 - (RE * RE / 4.0 + 4.0 * PI * PI).sqrt()
}

fn kovasznay_exact(x: [f64; 2]) -> ([f64; 2], [[f64; 2]; 2]) {
    let l = kovasznay_lambda();
    let e = (l * x[0]).exp();
    let (s, c) = (2.0 * PI * x[1]).sin_cos();
    let u = [1.0 - e * c, l / (2.0 * PI) * e * s];
    let g = [
        [-l * e * c, 2.0 * PI * e * s],
        [l * l / (2.0 * PI) * e * s, l * e * c],
    ];
    (u, g)
}

fn kovasznay_mesh() -> Quadtree {
    let coarse: Vec<(i64, i64)> = (0..4).flat_map(|j| (0..3).map(move |i| (i, j))).collect();
    Quadtree::new([-0.5, -0.5], 0.5, &coarse, 2)
}

const TG_K: f64 = 2.0 * PI;
const TG_NU: f64 = 0.01;

fn tg_exact(x: [f64; 2], t: f64) -> ([f64; 2], [[f64; 2]; 2]) {
    let k = TG_K;
    let a = (-2.0 * TG_NU * k * k * t).exp();
    let (sx, cx) = (k * (x[0] + 0.1)).sin_cos();
    let (sy, cy) = (k * (x[1] + 0.2)).sin_cos();
    (
        [a * cx * sy, -a * sx * cy],
        [
            [-a * k * sx * sy, a * k * cx * cy],
            [-a * k * cx * cy, a * k * sx * sy],
        ],
    )
}

/// The unit square as 2 × 2 cells with the lower-left quadrant split twice (25 cells of sides
/// 1/2, 1/4 and 1/8).
fn tg_mesh() -> Quadtree {
    let mut t = Quadtree::new([0.0, 0.0], 1.0, &[(0, 0)], 2);
    let l = t.leaves();
    t.refine(&l);
    for _ in 0..2 {
        let marked: Vec<u32> = t
            .leaves()
            .into_iter()
            .filter(|&c| {
                let [x, y] = t.corner(c);
                x < 0.49 && y < 0.49
            })
            .collect();
        t.refine(&marked);
    }
    t
}

fn histogram(d: &[usize]) -> String {
    degree_histogram(d)
        .iter()
        .map(|(p, n)| format!("{n}×p{p}"))
        .collect::<Vec<_>>()
        .join(" ")
}

fn print_table(reps: &[SweepReport]) {
    println!(
        "{:>6} {:>3} {:>4} {:<22} {:>6} {:>10} {:>10} {:>7} {:>13}",
        "t", "try", "acc", "degrees", "DOFs", "estimate", "error", "eff", "local eff"
    );
    for r in reps {
        let (err, eff, loc) = match &r.effectivity {
            Some(e) => (
                format!("{:.3e}", e.error),
                format!("{:.3}", e.global),
                format!("{:.2}..{:.2}", e.local_min, e.local_max),
            ),
            None => ("-".into(), "-".into(), "-".into()),
        };
        println!(
            "{:>6.3} {:>3} {:>4} {:<22} {:>6} {:>10.3e} {:>10} {:>7} {:>13}",
            r.t,
            r.sweep,
            if r.accepted { "yes" } else { "no" },
            histogram(&r.degrees),
            r.n_eq,
            r.estimate,
            err,
            eff,
            loc
        );
    }
}

fn kovasznay() -> Result<(), Box<dyn std::error::Error>> {
    let tree = kovasznay_mesh();
    let n = tree.leaves().len();
    let g = |x: [f64; 2], c: usize| kovasznay_exact(x).0[c];
    let f = |_: [f64; 2], _: f64| [0.0, 0.0];
    let exact = |x: [f64; 2]| kovasznay_exact(x);
    let problem = SteadyProblem {
        nu: 1.0 / RE,
        g: &g,
        f: &f,
        exact: Some(&exact),
    };
    println!("Kovasznay flow, Re = {RE}, {n} cells of side 0.5, uniform degree p");
    println!(
        "{:>2} {:>6} {:>11} {:>11} {:>7} {:>11} {:>7} {:>11}",
        "p", "DOFs", "|u-u_p|", "eta(+1)", "eff+1", "eta(+2)", "eff+2", "local+2"
    );
    for p in 2..=7 {
        let d = vec![p; n];
        let e1 = estimate(&tree, &d, &problem, 1)?;
        let e2 = estimate(&tree, &d, &problem, 2)?;
        let err = exact_error(&e1.coarse, &exact);
        let f1 = effectivity(&e1.indicators, &err);
        let f2 = effectivity(&e2.indicators, &err);
        println!(
            "{p:>2} {:>6} {:>11.3e} {:>11.3e} {:>7.3} {:>11.3e} {:>7.3} {:>5.2}..{:<5.2}",
            e1.coarse.n_eq(),
            f1.error,
            f1.estimate,
            f1.global,
            f2.estimate,
            f2.global,
            f2.local_min,
            f2.local_max
        );
    }
    let params = PAdaptParams {
        tol: 1e-5,
        enrich: 2,
        marking: PMarking::Tolerance,
        max_degree: 8,
        max_sweeps: 10,
    };
    println!("\np-adaptive, tolerance {:.0e}, enrichment +2:", params.tol);
    let (reps, _) = adapt_steady(&tree, &vec![2; n], &problem, &params)?;
    print_table(&reps);
    Ok(())
}

fn taylor_green(tol: f64, n_steps: usize) -> Result<(), Box<dyn std::error::Error>> {
    let tree = tg_mesh();
    let n = tree.leaves().len();
    let g = |x: [f64; 2], t: f64, c: usize| tg_exact(x, t).0[c];
    let f = |_: [f64; 2], _: f64| [0.0, 0.0];
    let u0 = |x: [f64; 2]| tg_exact(x, 0.0).0;
    let exact = |x: [f64; 2], t: f64| tg_exact(x, t);
    let problem = TransientProblem {
        nu: TG_NU,
        g: &g,
        f: &f,
        u0: &u0,
        exact: Some(&exact),
    };
    let time = TimeParams {
        dt: 0.02,
        n_steps,
        theta: 0.5,
    };
    println!(
        "Taylor–Green vortex (shifted by (0.1, 0.2)), nu = {TG_NU}, k = 2π, {n} cells, \
         Crank–Nicolson dt = {}, enrichment +2",
        time.dt
    );
    let params = PAdaptParams {
        tol,
        enrich: 2,
        marking: PMarking::Tolerance,
        max_degree: 8,
        max_sweeps: 8,
    };
    println!("\np-adaptive, tolerance {tol:.1e} (every attempt; acc = step accepted):");
    let reps = run_transient(&tree, &vec![2; n], &problem, &time, &params)?;
    print_table(&reps);
    for p in 5..=8 {
        let uniform = PAdaptParams {
            tol: f64::INFINITY,
            ..params
        };
        println!("\nuniform p = {p}:");
        let reps = run_transient(&tree, &vec![p; n], &problem, &time, &uniform)?;
        print_table(&reps);
    }
    Ok(())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("kovasznay") => kovasznay(),
        Some("taylor-green") => {
            let tol = match args.get(1).map(|s| s.parse::<f64>()) {
                None => Ok(1e-4),
                Some(Ok(v)) if v > 0.0 && v.is_finite() => Ok(v),
                Some(_) => Err(format!("TOL must be a positive number, got {:?}", args[1])),
            };
            let steps = match args.get(2).map(|s| s.parse::<usize>()) {
                None => Ok(5),
                Some(Ok(v)) if v > 0 => Ok(v),
                Some(_) => Err(format!(
                    "STEPS must be a positive integer, got {:?}",
                    args[2]
                )),
            };
            match (tol, steps) {
                (Ok(t), Ok(n)) => taylor_green(t, n),
                (Err(e), _) | (_, Err(e)) => Err(e.into()),
            }
        }
        _ => Err("usage: p_navier_stokes kovasznay | taylor-green [TOL] [STEPS]".into()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
