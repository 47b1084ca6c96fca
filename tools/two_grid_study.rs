//! The two-grid adaptive h-method against uniform refinement on the two problems of
//! `tests/convection.rs`, with the settings of its tests:
//!
//! * `hill`: the rotating Gaussian hill (κ = 1e-3, σ² = 0.01, centre (0.5, 0), b = (−y, x), SUPG,
//!   Q1 on (−1, 1)², 10 steps of 0.02; adaptive from 16 × 16, levels 3..=7, Dörfler 0.7,
//!   coarsening 0.01);
//! * `burgers`: the vector Burgers equations with the Cole–Hopf solution (ν = 0.01, Q2 on the
//!   unit square, 5 steps of 0.01; adaptive from 8 × 8, levels 2..=6, Dörfler 0.5, coarsening
//!   0.05);
//! * `burgers_steep`: its fronts four times thinner at the same speed (ν = 0.0025, the
//!   wavenumbers × 4; 20 steps of 0.0025; adaptive from 16 × 16, levels 3..=8).
//!
//! Printed: final L² error against equations and wall time for uniform levels, the finest
//! uniform levels with a quarter of the step (the time-discretisation floor), variants of the
//! adaptive settings, and the error history step by step of the test's adaptive run.
//!
//! `cargo run --release --no-default-features --example two_grid_study -- [hill|burgers|burgers_steep]
//! [steps] [dt] [only]` (`only` = `adaptive` or `uniform:L` runs just the test's adaptive run or
//! the uniform level L, for profiling). Wall times include the exact-error evaluation of every
//! step (the same per cell for both methods) and, for the adaptive runs, the fine solution of
//! the estimate.

use tread::adapt::burgers::{Burgers, ColeHopf};
use tread::adapt::convection::{ConvectionDiffusion, RotatingHill};
use tread::adapt::driver::Marking;
use tread::adapt::two_grid::{run, square, Kernel, TransientError, TransientOptions, TransientRun};

/// One problem of the study: kernel, domain, degree, steps and the test's adaptive settings.
struct Problem {
    kernel: Box<dyn Kernel>,
    origin: [f64; 2],
    side: f64,
    degree: u8,
    dt: f64,
    steps: usize,
    start_level: u32,
    uniform_levels: Vec<u32>,
    adaptive: TransientOptions,
}

impl Problem {
    fn hill() -> Self {
        let mut o = TransientOptions::new(1, 0.02, 10);
        o.adaptive = true;
        o.min_level = 3;
        o.max_level = 7;
        o.marking = Marking::Dorfler(0.7);
        o.coarsen_fraction = 0.01;
        Self {
            kernel: Box::new(ConvectionDiffusion::new(RotatingHill {
                kappa: 1e-3,
                sigma2: 0.01,
                centre: [0.5, 0.0],
            })),
            origin: [-1.0, -1.0],
            side: 2.0,
            degree: 1,
            dt: 0.02,
            steps: 10,
            start_level: 4,
            uniform_levels: vec![3, 4, 5, 6, 7],
            adaptive: o,
        }
    }

    fn burgers() -> Self {
        let mut o = TransientOptions::new(2, 0.01, 5);
        o.adaptive = true;
        o.min_level = 2;
        o.max_level = 6;
        Self {
            kernel: Box::new(Burgers {
                exact: ColeHopf::default(),
            }),
            origin: [0.0, 0.0],
            side: 1.0,
            degree: 2,
            dt: 0.01,
            steps: 5,
            start_level: 3,
            uniform_levels: vec![3, 4, 5, 6],
            adaptive: o,
        }
    }

    /// The Burgers fronts four times steeper at the same speed: ν/4 and the wavenumbers ×4
    /// (the same fronts at t = 0, a quarter of their width), steps of a quarter.
    fn burgers_steep() -> Self {
        let mut o = TransientOptions::new(2, 0.0025, 20);
        o.adaptive = true;
        o.min_level = 3;
        o.max_level = 8;
        Self {
            kernel: Box::new(Burgers {
                exact: ColeHopf {
                    nu: 0.0025,
                    terms: vec![(80f64.exp(), [-80.0, -80.0]), (40f64.exp(), [-100.0, 40.0])],
                },
            }),
            origin: [0.0, 0.0],
            side: 1.0,
            degree: 2,
            dt: 0.0025,
            steps: 20,
            start_level: 4,
            uniform_levels: vec![4, 5, 6, 7],
            adaptive: o,
        }
    }

    fn uniform(&self, level: u32, dt: f64, n: usize) -> Result<TransientRun, TransientError> {
        let tree = square(self.origin, self.side, level, self.degree);
        run(
            self.kernel.as_ref(),
            &tree,
            0.0,
            &TransientOptions::new(self.degree, dt, n),
        )
    }

    fn adaptive(&self, o: &TransientOptions) -> Result<TransientRun, TransientError> {
        let tree = square(self.origin, self.side, self.start_level, self.degree);
        run(self.kernel.as_ref(), &tree, 0.0, o)
    }
}

fn mean_eq(r: &TransientRun) -> f64 {
    r.steps.iter().map(|s| s.n_eq as f64).sum::<f64>() / r.steps.len().max(1) as f64
}

fn row(label: &str, r: &TransientRun) {
    let Some(s) = r.last() else {
        println!("{label:<34} (no steps)");
        return;
    };
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
    let mut p = match args.first().map(String::as_str) {
        None | Some("hill") => Problem::hill(),
        Some("burgers") => Problem::burgers(),
        Some("burgers_steep") => Problem::burgers_steep(),
        Some(o) => {
            eprintln!("problem `{o}`: expected hill, burgers or burgers_steep");
            std::process::exit(2);
        }
    };
    match args.get(1).map(|s| s.parse::<usize>()) {
        None => {}
        Some(Ok(v)) if v > 0 => p.steps = v,
        _ => {
            eprintln!("steps: expected a positive integer");
            std::process::exit(2);
        }
    }
    match args.get(2).map(|s| s.parse::<f64>()) {
        None => {}
        Some(Ok(v)) if v > 0.0 && v.is_finite() => p.dt = v,
        _ => {
            eprintln!("dt: expected a positive number");
            std::process::exit(2);
        }
    }
    let (dt, n) = (p.dt, p.steps);
    p.adaptive.dt = dt;
    p.adaptive.n_steps = n;
    let header = || {
        println!(
            "{:<34} {:>7} {:>7} {:>8} {:>10} {:>10} {:>8}",
            "run", "n_eq", "max_eq", "mean_eq", "L2 error", "estimate", "wall s"
        )
    };
    match args.get(3).map(String::as_str) {
        None | Some("all") => {}
        Some("adaptive") => {
            header();
            row("adaptive (test settings)", &p.adaptive(&p.adaptive)?);
            return Ok(());
        }
        Some(o) => {
            let Some(Ok(lev)) = o.strip_prefix("uniform:").map(|l| l.parse::<u32>()) else {
                eprintln!("only: expected all, adaptive or uniform:L");
                std::process::exit(2);
            };
            header();
            row(
                &format!("uniform level {lev}"),
                &p.uniform(lev.min(9), dt, n)?,
            );
            return Ok(());
        }
    }
    println!(
        "Q{}, {n} steps of {dt} (t = {:.3})",
        p.degree,
        n as f64 * dt
    );
    header();
    let mut uniform = Vec::new();
    for &lev in &p.uniform_levels {
        let r = p.uniform(lev, dt, n)?;
        row(&format!("uniform level {lev}"), &r);
        uniform.push(r);
    }
    // Time-discretisation floor: the two finest uniform meshes with a quarter of the step.
    let finest = &p.uniform_levels[p.uniform_levels.len() - 2..];
    for &lev in finest {
        row(
            &format!("uniform level {lev}, dt/4"),
            &p.uniform(lev, dt / 4.0, 4 * n)?,
        );
    }
    let base = p.adaptive.clone();
    let theta = match base.marking {
        Marking::Dorfler(t) | Marking::Maximum(t) => t,
    };
    let mut variants: Vec<(String, TransientOptions)> =
        vec![("adaptive (test settings)".to_string(), base.clone())];
    for th in [0.5, 0.7, 0.9] {
        if (th - theta).abs() > 1e-12 {
            let mut o = base.clone();
            o.marking = Marking::Dorfler(th);
            variants.push((format!("adaptive, Dorfler {th}"), o));
        }
    }
    let mut o = base.clone();
    o.max_level += 1;
    variants.push((format!("adaptive, max level {}", o.max_level), o));
    let mut o = base.clone();
    o.min_level += 1;
    variants.push((format!("adaptive, min level {}", o.min_level), o));
    let mut o = base.clone();
    o.initial_sweeps = 4;
    variants.push(("adaptive, 4 initial sweeps".to_string(), o));
    let mut o = base.clone();
    o.coarsen_fraction = 0.0;
    variants.push(("adaptive, no coarsening".to_string(), o));
    let mut history = None;
    for (label, o) in &variants {
        let r = p.adaptive(o)?;
        row(label, &r);
        if history.is_none() {
            history = Some(r);
        }
    }
    // Step-by-step history of the test's adaptive run against the two finest uniform levels.
    let Some(a) = history else { return Ok(()) };
    let (ua, ub) = (&uniform[uniform.len() - 2], &uniform[uniform.len() - 1]);
    let (la, lb) = (finest[0], finest[1]);
    println!();
    println!(
        "{:>6} {:>9} {:>10} {:>10} {:>11} {:>11}",
        "t",
        "adapt_eq",
        "adapt L2",
        "estimate",
        format!("uniform{la} L2"),
        format!("uniform{lb} L2")
    );
    for ((sa, s1), s2) in a.steps.iter().zip(&ua.steps).zip(&ub.steps) {
        println!(
            "{:>6.3} {:>9} {:>10.3e} {:>10.3e} {:>11.3e} {:>11.3e}",
            sa.t, sa.n_eq, sa.l2_error, sa.estimate, s1.l2_error, s2.l2_error
        );
    }
    // Where the final mesh of that run is fine: share of the domain's area per level.
    let total = p.side * p.side;
    let mut share = std::collections::BTreeMap::new();
    for c in a.tree.leaves() {
        let h = a.tree.h(c);
        *share.entry(a.tree.cells[c as usize].level).or_insert(0.0) += h * h / total;
    }
    println!();
    println!("final adaptive mesh, area share per level:");
    for (lev, f) in share {
        println!("  level {lev}: {:.3}", f);
    }
    Ok(())
}
