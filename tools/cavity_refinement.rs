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

const BP_PSI_MIN: f64 = -0.1189366;
const BP_Y: [f64; 15] = [
    0.0547, 0.0625, 0.0703, 0.1016, 0.1719, 0.2813, 0.4531, 0.5, 0.6172, 0.7344, 0.8516, 0.9531,
    0.9609, 0.9688, 0.9766,
];
const BP_U: [f64; 15] = [
    -0.1812881, -0.2023300, -0.2228955, -0.3004561, -0.3885690, -0.2803696, -0.1081999, -0.0620561,
    0.0570178, 0.1886747, 0.3372212, 0.4723329, 0.5169277, 0.5808359, 0.6644227,
];
const BP_X: [f64; 15] = [
    0.0625, 0.0703, 0.0781, 0.0938, 0.1563, 0.2266, 0.2344, 0.5, 0.8047, 0.8594, 0.9063, 0.9453,
    0.9531, 0.9609, 0.9688,
];
const BP_V: [f64; 15] = [
    0.2807056, 0.2962703, 0.3099097, 0.3330442, 0.3769189, 0.3339924, 0.3253592, 0.0257995,
    -0.3202137, -0.4264545, -0.5264392, -0.4103754, -0.3553213, -0.2936869, -0.2279225,
];

fn mesh(spec: &str) -> Quadtree {
    let mut it = spec.split('+');
    let l: u32 = it.next().and_then(|s| s.parse().ok()).unwrap_or(5);
    let g: u32 = it.next().and_then(|s| s.parse().ok()).unwrap_or(0);
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
    t
}

fn main() {
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
        let t = mesh(spec);
        let t0 = Instant::now();
        let run = match cavity(&t, lid, &[100.0, 400.0, 1000.0], 1e-10) {
            Ok(r) => r,
            Err(e) => {
                eprintln!("{spec}: {e}");
                continue;
            }
        };
        let th = &run.th;
        let sol = NsSolution {
            th,
            x: th.distribute(&run.states[2].1),
        };
        let (space, psi) = stream_function(&sol).expect("stream function");
        let (at, pm) = psi_min(&th.tree, &space, &psi);
        let dt = t0.elapsed().as_secs_f64();
        let its: usize = run.stats.iter().map(|s| s.iterations).sum();
        let du = BP_Y
            .iter()
            .zip(&BP_U)
            .map(|(&y, &u)| (sol.velocity([0.5, y]).unwrap().0[0] - u).abs())
            .fold(0.0, f64::max);
        let dv = BP_X
            .iter()
            .zip(&BP_V)
            .map(|(&x, &v)| (sol.velocity([x, 0.5]).unwrap().0[1] - v).abs())
            .fold(0.0, f64::max);
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
}
