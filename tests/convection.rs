//! Transient convection–diffusion (rotating Gaussian hill, Crank–Nicolson, SUPG) and the vector
//! Burgers equations (Cole–Hopf) with the two-grid adaptive h-method.

use tread::adapt::burgers::{Burgers, ColeHopf};
use tread::adapt::convection::{ConvectionDiffusion, RotatingHill};
use tread::adapt::driver::loglog_slope;
use tread::adapt::two_grid::{
    condensed_system, interpolate, run, space_at, square, Kernel, TransientOptions,
};

fn hill_kernel(sigma2: f64) -> ConvectionDiffusion {
    ConvectionDiffusion::new(RotatingHill {
        kappa: 1e-3,
        sigma2,
        centre: [0.5, 0.0],
    })
}

/// Observed L² and H¹ rates on uniform meshes at t = 0.02 (8 steps of 0.0025: the time error
/// is far below the space error).
#[test]
fn uniform_rates_q1_q2() {
    let k = hill_kernel(0.04);
    for (p, levels, l2_min, h1_min) in [(1u8, [3u32, 4, 5], 1.8, 0.9), (2, [3, 4, 5], 2.7, 1.8)] {
        let mut pts_l2 = Vec::new();
        let mut pts_h1 = Vec::new();
        for l in levels {
            let tree = square([-1.0, -1.0], 2.0, l, p);
            let r = run(&k, &tree, 0.0, &TransientOptions::new(p, 0.0025, 8)).unwrap();
            let s = r.last().unwrap();
            let h = 2.0 / (1u32 << l) as f64;
            println!(
                "Q{p} level {l}: n_eq {} L2 {:.3e} H1 {:.3e}",
                s.n_eq, s.l2_error, s.h1_error
            );
            pts_l2.push((h, s.l2_error));
            pts_h1.push((h, s.h1_error));
        }
        let (r2, r1) = (loglog_slope(&pts_l2[1..]), loglog_slope(&pts_h1[1..]));
        println!("Q{p}: L2 rate {r2:.2}, H1 rate {r1:.2}");
        assert!(r2 > l2_min, "Q{p} L2 rate {r2}");
        assert!(r1 > h1_min, "Q{p} H1 rate {r1}");
    }
}

/// The adaptive options of the hill runs: levels 3 to 7, Dörfler marking at 0.7, light
/// coarsening.
fn adaptive_hill_options(dt: f64, n: usize) -> TransientOptions {
    let mut o = TransientOptions::new(1, dt, n);
    o.adaptive = true;
    o.min_level = 3;
    o.max_level = 7;
    o.marking = tread::adapt::driver::Marking::Dorfler(0.7);
    o.coarsen_fraction = 0.01;
    o
}

/// The two-grid adaptive run reaches a smaller final error than uniform refinement on a mesh
/// with at least as many equations as the adaptive run ever had, and its estimate tracks the
/// true error.
#[test]
fn adaptive_beats_uniform_hill() {
    let k = hill_kernel(0.01);
    let (dt, n) = (0.02, 10);
    let uni = run(
        &k,
        &square([-1.0, -1.0], 2.0, 6, 1),
        0.0,
        &TransientOptions::new(1, dt, n),
    )
    .unwrap();
    let o = adaptive_hill_options(dt, n);
    let ad = run(&k, &square([-1.0, -1.0], 2.0, 4, 1), 0.0, &o).unwrap();
    let (u, a) = (uni.last().unwrap(), ad.last().unwrap());
    let eff = a.estimate / a.l2_error;
    println!(
        "uniform: n_eq {} L2 {:.3e}; adaptive: n_eq {} (max {}) L2 {:.3e} estimate {:.3e} effectivity {eff:.2}",
        u.n_eq, u.l2_error, a.n_eq, ad.max_eq(), a.l2_error, a.estimate
    );
    assert!((0.5..1.5).contains(&eff), "effectivity {eff}");
    // The uniform 64 × 64 mesh has four times the equations (measured: 3,969 against at most
    // 983), the adaptive run the lower error (measured: 8.5e-4 against 3.5e-3).
    assert!(
        u.n_eq >= ad.max_eq(),
        "uniform {} < adaptive {}",
        u.n_eq,
        ad.max_eq()
    );
    assert!(
        a.l2_error < u.l2_error,
        "adaptive L2 {:e} not below uniform {:e}",
        a.l2_error,
        u.l2_error
    );
}

/// The initial sweeps restart the first step from u_0 interpolated on the adapted mesh: the
/// adaptive run's first-step error is then far below the interpolation error of u_0 on its
/// coarse starting mesh (16 × 16 cells of side 0.125 for a hill of width 0.1), which the run
/// would otherwise keep. Measured: 8.5e-4 after the 8 sweeps (6.7e-3 after 4) against 2.8e-2
/// for the 16 × 16 mesh after one step; the bound asks for a factor 2.
#[test]
fn initial_sweeps_resolve_the_initial_data() {
    let k = hill_kernel(0.01);
    let (dt, n) = (0.02, 1);
    let coarse = run(
        &k,
        &square([-1.0, -1.0], 2.0, 4, 1),
        0.0,
        &TransientOptions::new(1, dt, n),
    )
    .unwrap();
    let o = adaptive_hill_options(dt, n);
    let ad = run(&k, &square([-1.0, -1.0], 2.0, 4, 1), 0.0, &o).unwrap();
    let (c, a) = (coarse.last().unwrap(), ad.last().unwrap());
    println!(
        "first step: 16 x 16 L2 {:.3e}; adaptive after {} sweeps: n_eq {} L2 {:.3e}",
        c.l2_error, o.initial_sweeps, a.n_eq, a.l2_error
    );
    assert!(
        a.l2_error < 0.5 * c.l2_error,
        "adaptive first step {:e} vs coarse {:e}",
        a.l2_error,
        c.l2_error
    );
}

/// The Newton tangent of Burgers against central differences of the condensed residual.
#[test]
fn burgers_tangent_fd() {
    let k = Burgers {
        exact: ColeHopf::default(),
    };
    for p in [1u8, 2] {
        let mut tree = square([0.0, 0.0], 1.0, 1, p);
        let first = tree.leaves()[0];
        tree.refine(&[first]);
        let s_old = space_at(&tree, &k, 0.0).unwrap();
        let s = space_at(&tree, &k, 0.05).unwrap();
        let xn = interpolate(&tree, &s_old, &|x, c| k.exact(x, 0.0, c).0).unwrap();
        // A state away from the solution: perturbed free entries.
        let mut x = interpolate(&tree, &s, &|x, c| {
            k.exact(x, 0.05, c).0 + 0.3 * (3.0 * x[0] + c as f64).sin() * x[1]
        })
        .unwrap();
        let n = s.n_eq();
        assert!(n > 0);
        let mut y = vec![0.0; n];
        s.constraints.gather(&x, &mut y);
        let (_, vals) = condensed_system(&tree, &s, &k, &x, &xn, 0.0, 0.05);
        let pat = &s.pattern;
        let mut dense = vec![0.0; n * n];
        for col in 0..n {
            for q in pat.col_ptr[col]..pat.col_ptr[col + 1] {
                dense[pat.row_idx[q] * n + col] = vals[q];
            }
        }
        let eps = 1e-6;
        let mut worst: f64 = 0.0;
        let scale = dense.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for col in 0..n {
            let mut yp = y.clone();
            yp[col] += eps;
            s.constraints.distribute(&yp, &mut x);
            let (rp, _) = condensed_system(&tree, &s, &k, &x, &xn, 0.0, 0.05);
            yp[col] -= 2.0 * eps;
            s.constraints.distribute(&yp, &mut x);
            let (rm, _) = condensed_system(&tree, &s, &k, &x, &xn, 0.0, 0.05);
            for row in 0..n {
                // The condensed vector is −Cᵀ r.
                let fd = -(rp[row] - rm[row]) / (2.0 * eps);
                worst = worst.max((fd - dense[row * n + col]).abs() / scale);
            }
        }
        println!("Q{p}: n_eq {n}, max |K − K_fd| / max |K| = {worst:.2e}");
        assert!(worst < 1e-7, "Q{p} tangent error {worst}");
    }
}

/// Burgers: Newton converges, rates on uniform meshes, adaptive run with the two-grid estimate.
#[test]
fn burgers_uniform_and_adaptive() {
    let k = Burgers {
        exact: ColeHopf::default(),
    };
    let (dt, n) = (0.01, 5);
    let mut pts = Vec::new();
    let mut last_uni = None;
    for l in [3u32, 4, 5] {
        let r = run(
            &k,
            &square([0.0, 0.0], 1.0, l, 2),
            0.0,
            &TransientOptions::new(2, dt, n),
        )
        .unwrap();
        let s = r.last().unwrap().clone();
        println!(
            "Burgers Q2 level {l}: n_eq {} L2 {:.3e} H1 {:.3e} newton {}",
            s.n_eq, s.l2_error, s.h1_error, s.newton_iterations
        );
        assert!(s.newton_iterations >= 1 && s.newton_iterations <= 6);
        pts.push((1.0 / (1u32 << l) as f64, s.l2_error));
        last_uni = Some(s);
    }
    let rate = loglog_slope(&pts[1..]);
    println!("Burgers Q2 L2 rate {rate:.2}");
    assert!(rate > 2.0, "rate {rate}");
    let mut o = TransientOptions::new(2, dt, n);
    o.adaptive = true;
    o.min_level = 2;
    o.max_level = 6;
    let ad = run(&k, &square([0.0, 0.0], 1.0, 3, 2), 0.0, &o).unwrap();
    let a = ad.last().unwrap();
    let u = last_uni.unwrap();
    println!(
        "Burgers adaptive: n_eq {} (max {}) L2 {:.3e} estimate {:.3e} effectivity {:.2}; uniform level 5: n_eq {} L2 {:.3e}",
        a.n_eq, ad.max_eq(), a.l2_error, a.estimate, a.estimate / a.l2_error, u.n_eq, u.l2_error
    );
    // Measured: 5.4e-5 with 10,070 equations at the end (5,152 on average over the steps)
    // against 7.1e-5 for the uniform 32 × 32 mesh's 7,938: about the uniform error per equation,
    // not better (not asserted; docs/adaptivity.md has the measured reasons).
    let eff = a.estimate / a.l2_error;
    assert!((0.5..1.5).contains(&eff), "effectivity {eff}");
}
