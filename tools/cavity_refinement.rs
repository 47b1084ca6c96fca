//! Refinement study of the lid-driven cavity at Re = 1000 (continuation 100 → 400 → 1000):
//! equations, wall time, ψ_min and its relative error against Botella & Peyret (1998),
//! the largest deviation from their centreline tables.
//!
//! `cargo run --release --no-default-features --example cavity_refinement -- [lid] [levels...]`
//! with lid `unit` (discontinuous, default) or `reg` (16 x²(1 − x)², no reference printed), and
//! each level `L` (uniform 2^L × 2^L) or `L+G` (uniform L, then G extra levels towards the two
//! top corners).

use std::time::Instant;
use tread::adapt::navier_stokes::{
    cavity, psi_min, stream_function, unit_square, CavityLid, NsSolution,
};
use tread::adapt::quadtree::Quadtree;

include!("../tests/common/botella_peyret.rs");

/// The mesh of a level argument `L` or `L+G` (see the module docs).
fn mesh(spec: &str) -> Result<Quadtree, String> {
    let level = |s: Option<&str>, default: u32| -> Result<u32, String> {
        match s {
            None => Ok(default),
            Some(s) => match s.parse::<u32>() {
                Ok(v) if v <= 10 => Ok(v),
                _ => Err(format!(
                    "mesh level `{spec}`: expected L or L+G with integers 0..=10"
                )),
            },
        }
    };
    let mut it = spec.split('+');
    let l = level(it.next(), 5)?;
    let g = level(it.next(), 0)?;
    if it.next().is_some() {
        return Err(format!("mesh level `{spec}`: expected L or L+G"));
    }
    let mut t = unit_square(l);
    for _ in 0..g {
        let marked: Vec<u32> = t
            .leaves()
            .into_iter()
            .filter(|&c| {
                let [x, y] = t.corner(c);
                let h = t.h(c);
                y + h > 1.0 - 1e-12 && (x < 1e-12 || x + h > 1.0 - 1e-12)
            })
            .collect();
        t.refine(&marked);
    }
    Ok(t)
}

/// Largest deviation from the tabulated stations of component `k` of the velocity along
/// `point(station)`.
fn deviation(
    sol: &NsSolution,
    stations: &[f64],
    values: &[f64],
    k: usize,
    point: impl Fn(f64) -> [f64; 2],
) -> Result<f64, String> {
    let mut worst = 0.0_f64;
    for (&s, &v) in stations.iter().zip(values) {
        let u = sol.velocity(point(s)).map_err(|e| e.to_string())?.0[k];
        worst = worst.max((u - v).abs());
    }
    Ok(worst)
}

fn main() -> std::process::ExitCode {
    let mut failed = false;
    let args: Vec<String> = std::env::args().skip(1).collect();
    let lid = if args.first().map(String::as_str) == Some("reg") {
        CavityLid::Regularised
    } else {
        CavityLid::Discontinuous
    };
    let specs: Vec<&str> = args
        .iter()
        .filter(|a| *a != "reg" && *a != "unit")
        .map(String::as_str)
        .collect();
    println!(
        "mesh   n_eq   time_s  newton  psi_min     x       y       rel_err   max|du|   max|dv|"
    );
    for spec in if specs.is_empty() {
        vec!["4", "5", "6"]
    } else {
        specs
    } {
        let t = match mesh(spec) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("{e}");
                failed = true;
                continue;
            }
        };
        let t0 = Instant::now();
        let run = match cavity(&t, lid, &[100.0, 400.0, 1000.0], 1e-10) {
            Ok(r) => r,
            Err(e) => {
                eprintln!("{spec}: {e}");
                failed = true;
                continue;
            }
        };
        let th = &run.th;
        let sol = NsSolution {
            th,
            x: th.distribute(&run.states[2].1),
        };
        let (space, psi) = match stream_function(&sol) {
            Ok(sp) => sp,
            Err(e) => {
                eprintln!("{spec}: stream function: {e}");
                failed = true;
                continue;
            }
        };
        let (at, pm) = psi_min(th, &space, &psi);
        let dt = t0.elapsed().as_secs_f64();
        let its: usize = run.stats.iter().map(|s| s.iterations).sum();
        let (du, dv) = match (
            deviation(&sol, &BP_Y, &BP_U, 0, |y| [0.5, y]),
            deviation(&sol, &BP_X, &BP_V, 1, |x| [x, 0.5]),
        ) {
            (Ok(du), Ok(dv)) => (du, dv),
            (Err(e), _) | (_, Err(e)) => {
                eprintln!("{spec}: centreline: {e}");
                failed = true;
                continue;
            }
        };
        if lid == CavityLid::Regularised {
            println!(
                "{spec:6} {:6} {dt:7.2} {its:6}  {pm:.7} {:.4}  {:.4}",
                th.n_eq(),
                at[0],
                at[1]
            );
            continue;
        }
        println!(
            "{spec:6} {:6} {dt:7.2} {its:6}  {pm:.7} {:.4}  {:.4}  {:.3e} {du:.3e} {dv:.3e}",
            th.n_eq(),
            at[0],
            at[1],
            (pm - BP_PSI_MIN).abs() / BP_PSI_MIN.abs()
        );
    }
    if failed {
        std::process::ExitCode::FAILURE
    } else {
        std::process::ExitCode::SUCCESS
    }
}
