//! The two-grid adaptive h-method against uniform refinement on the rotating Gaussian hill of
//! `tests/convection.rs` (κ = 1e-3, σ² = 0.01, centre (0.5, 0), b = (−y, x), SUPG, Crank–Nicolson,
//! Q1 on (−1, 1)²): final L² error against equations and wall time, the time-discretisation
//! floor, variants of the adaptive settings and the error history step by step.
//!
//! `cargo run --release --no-default-features --example heat_two_grid_study -- [steps] [dt] [only]`
//! (default 10 steps of 0.02, the test's run; `only` = `adaptive` or `uniform:L` runs just the
//! test's adaptive run or the uniform level L, for profiling). Wall times include the exact-error
//! evaluation of every step (the same for both methods per cell) and, for the adaptive runs, the
//! fine solution of the estimate.

use tread::adapt::convection::{ConvectionDiffusion, RotatingHill};
use tread::adapt::driver::Marking;
use tread::adapt::two_grid::{run, square, TransientError, TransientOptions, TransientRun};

fn kernel() -> ConvectionDiffusion {
    ConvectionDiffusion::new(RotatingHill {
        kappa: 1e-3,
        sigma2: 0.01,
        centre: [0.5, 0.0],
    })
}

/// The adaptive settings of `tests/convection.rs`.
fn adaptive_options(dt: f64, n: usize) -> TransientOptions {
    let mut o = TransientOptions::new(1, dt, n);
    o.adaptive = true;
    o.min_level = 3;
    o.max_level = 7;
    o.marking = Marking::Dorfler(0.7);
    o.coarsen_fraction = 0.01;
    o
}

fn mean_eq(r: &TransientRun) -> f64 {
    r.steps.iter().map(|s| s.n_eq as f64).sum::<f64>() / r.steps.len().max(1) as f64
}

fn row(label: &str, r: &TransientRun) {
    let s = r.last().expect("at least one step");
    println!(
        "{label:<34} {:>7} {:>7} {:>8.0} {:>10.3e} {:>10.3e} {:>8.2}",
        s.n_eq,
        r.max_eq(),
        mean_eq(r),
        s.l2_error,
        s.estimate,
        r.wall_seconds
    );
}

fn main() -> Result<(), TransientError> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let n: usize = match args.first().map(|s| s.parse()) {
        None => 10,
        Some(Ok(v)) if v > 0 => v,
        _ => {
            eprintln!("steps: expected a positive integer");
            std::process::exit(2);
        }
    };
    let dt: f64 = match args.get(1).map(|s| s.parse()) {
        None => 0.02,
        Some(Ok(v)) if v > 0.0 => v,
        _ => {
            eprintln!("dt: expected a positive number");
            std::process::exit(2);
        }
    };
    let k = kernel();
    let origin = [-1.0, -1.0];
    match args.get(2).map(String::as_str) {
        None | Some("all") => {}
        Some("adaptive") => {
            let r = run(&k, &square(origin, 2.0, 4, 1), 0.0, &adaptive_options(dt, n))?;
            row("adaptive (test settings)", &r);
            return Ok(());
        }
        Some(o) => {
            let Some(Ok(lev)) = o.strip_prefix("uniform:").map(|l| l.parse::<u32>()) else {
                eprintln!("only: expected all, adaptive or uniform:L");
                std::process::exit(2);
            };
            let r = run(
                &k,
                &square(origin, 2.0, lev.min(10), 1),
                0.0,
                &TransientOptions::new(1, dt, n),
            )?;
            row(&format!("uniform level {lev}"), &r);
            return Ok(());
        }
    }
    println!("rotating hill, Q1, {n} steps of {dt} (t = {:.3})", n as f64 * dt);
    println!(
        "{:<34} {:>7} {:>7} {:>8} {:>10} {:>10} {:>8}",
        "run", "n_eq", "max_eq", "mean_eq", "L2 error", "estimate", "wall s"
    );
    for lev in 3..=7u32 {
        let r = run(
            &k,
            &square(origin, 2.0, lev, 1),
            0.0,
            &TransientOptions::new(1, dt, n),
        )?;
        row(&format!("uniform level {lev}"), &r);
    }
    // Time-discretisation floor: the finest uniform mesh with a quarter of the step.
    for lev in [6u32, 7] {
        let r = run(
            &k,
            &square(origin, 2.0, lev, 1),
            0.0,
            &TransientOptions::new(1, dt / 4.0, 4 * n),
        )?;
        row(&format!("uniform level {lev}, dt/4"), &r);
    }
    let variants: Vec<(String, u32, TransientOptions)> = {
        let mut v = Vec::new();
        v.push(("adaptive (test settings)".to_string(), 4, adaptive_options(dt, n)));
        for theta in [0.5, 0.9] {
            let mut o = adaptive_options(dt, n);
            o.marking = Marking::Dorfler(theta);
            v.push((format!("adaptive, Dorfler {theta}"), 4, o));
        }
        let mut o = adaptive_options(dt, n);
        o.max_level = 8;
        v.push(("adaptive, max level 8".to_string(), 4, o));
        let mut o = adaptive_options(dt, n);
        o.min_level = 4;
        v.push(("adaptive, min level 4".to_string(), 4, o));
        let mut o = adaptive_options(dt, n);
        o.initial_sweeps = 8;
        v.push(("adaptive, 8 initial sweeps".to_string(), 4, o));
        let mut o = adaptive_options(dt, n);
        o.coarsen_fraction = 0.0;
        v.push(("adaptive, no coarsening".to_string(), 4, o));
        let mut o = adaptive_options(dt, n);
        o.marking = Marking::Dorfler(0.9);
        o.initial_sweeps = 8;
        o.min_level = 4;
        v.push(("adaptive, 0.9, 8 sweeps, min 4".to_string(), 4, o));
        v
    };
    let mut history = None;
    for (label, lev, o) in &variants {
        let r = run(&k, &square(origin, 2.0, *lev, 1), 0.0, o)?;
        row(label, &r);
        if history.is_none() {
            history = Some(r);
        }
    }
    // Step-by-step history of the test's adaptive run against the uniform levels 5 and 6.
    let u5 = run(
        &k,
        &square(origin, 2.0, 5, 1),
        0.0,
        &TransientOptions::new(1, dt, n),
    )?;
    let u6 = run(
        &k,
        &square(origin, 2.0, 6, 1),
        0.0,
        &TransientOptions::new(1, dt, n),
    )?;
    let a = history.expect("the first variant ran");
    println!();
    println!(
        "{:>6} {:>9} {:>10} {:>10} {:>11} {:>11}",
        "t", "adapt_eq", "adapt L2", "estimate", "uniform5 L2", "uniform6 L2"
    );
    for ((sa, s5), s6) in a.steps.iter().zip(&u5.steps).zip(&u6.steps) {
        println!(
            "{:>6.3} {:>9} {:>10.3e} {:>10.3e} {:>11.3e} {:>11.3e}",
            sa.t, sa.n_eq, sa.l2_error, sa.estimate, s5.l2_error, s6.l2_error
        );
    }
    Ok(())
}
