//! Rotating Gaussian hill (convection–diffusion, κ = 1e-3, Crank–Nicolson Δt = 0.02, SUPG) and
//! the Cole–Hopf Burgers solution: uniform meshes against the two-grid adaptive h-method,
//! equations, L² error, two-grid estimate and wall time after 1 and 25 steps.
//!
//! `cargo run --release --no-default-features --example heat_adaptive -- [degree]` (1 or 2).

use tread::adapt::burgers::{Burgers, ColeHopf};
use tread::adapt::convection::{ConvectionDiffusion, RotatingHill};
use tread::adapt::driver::Marking;
use tread::adapt::two_grid::{run, square, Kernel, TransientError, TransientOptions};

fn table(
    name: &str,
    k: &dyn Kernel,
    origin: [f64; 2],
    l: f64,
    p: u8,
    dt: f64,
    n: usize,
) -> Result<(), TransientError> {
    println!("{name}, Q{p}, dt {dt}, {n} steps");
    println!(
        "{:>10} {:>7} {:>8} {:>11} {:>11} {:>11} {:>8}",
        "mesh", "step", "n_eq", "L2 error", "estimate", "t", "wall s"
    );
    for lev in [3u32, 4, 5] {
        let mut o = TransientOptions::new(p, dt, n);
        o.estimate = true;
        let r = run(k, &square(origin, l, lev, p), 0.0, &o)?;
        for s in [&r.steps[0], &r.steps[n - 1]] {
            println!(
                "{:>10} {:>7} {:>8} {:>11.3e} {:>11.3e} {:>11.3} {:>8.2}",
                format!("uniform {lev}"),
                (s.t / dt).round(),
                s.n_eq,
                s.l2_error,
                s.estimate,
                s.t,
                r.wall_seconds
            );
        }
    }
    let mut o = TransientOptions::new(p, dt, n);
    o.adaptive = true;
    o.min_level = 3;
    o.max_level = 7;
    o.marking = Marking::Dorfler(0.7);
    o.coarsen_fraction = 0.01;
    let r = run(k, &square(origin, l, 4, p), 0.0, &o)?;
    for s in [&r.steps[0], &r.steps[n - 1]] {
        println!(
            "{:>10} {:>7} {:>8} {:>11.3e} {:>11.3e} {:>11.3} {:>8.2}",
            "adaptive",
            (s.t / dt).round(),
            s.n_eq,
            s.l2_error,
            s.estimate,
            s.t,
            r.wall_seconds
        );
    }
    Ok(())
}

fn main() {
    let p = match std::env::args().nth(1).as_deref() {
        None => 1,
        Some(s) => match s.parse::<u8>() {
            Ok(v @ 1..=2) => v,
            _ => {
                eprintln!("degree `{s}`: expected 1 or 2");
                std::process::exit(2);
            }
        },
    };
    let hill = ConvectionDiffusion::new(RotatingHill::default());
    let burgers = Burgers {
        exact: ColeHopf::default(),
    };
    let out = table("rotating hill", &hill, [-1.0, -1.0], 2.0, p, 0.02, 25).and_then(|_| {
        table(
            "Burgers (Cole-Hopf)",
            &burgers,
            [0.0, 0.0],
            1.0,
            p,
            0.01,
            10,
        )
    });
    if let Err(e) = out {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
