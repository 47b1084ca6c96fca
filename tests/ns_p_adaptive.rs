//! The p-method for 2D Navier–Stokes (per-cell Q_p/Q_{p−1} hierarchical pair): the exact
//! Jacobian against central differences on a mesh with hanging nodes and mixed degrees, a patch
//! test, Kovasznay flow (exponential convergence in p, effectivity of the enrichment estimate,
//! the steady p-adaptive loop) and the Taylor–Green vortex (effectivity at every step,
//! exponential convergence in p, the transient p-adaptive loop against uniform degrees).

use std::f64::consts::PI;
use std::rc::Rc;
use tread::adapt::p_navier_stokes::{
    adapt_steady, effectivity, estimate, exact_error, initial_field, pressure_error, run_transient,
    theta_step, Field, PAdaptParams, PMarking, PTaylorHood, Physics, SteadyProblem, SweepReport,
    ThetaStep, TimeParams, TransientProblem,
};
use tread::adapt::quadtree::Quadtree;

/// Unit square split `levels` times, then the leaves of the lower-left quadrant split `extra`
/// more times (hanging nodes on the quadrant's boundary).
fn graded_square(levels: u32, extra: u32) -> Quadtree {
    let mut t = Quadtree::new([0.0, 0.0], 1.0, &[(0, 0)], 2);
    for _ in 0..levels {
        let l = t.leaves();
        t.refine(&l);
    }
    for _ in 0..extra {
        let m: Vec<u32> = t
            .leaves()
            .into_iter()
            .filter(|&c| {
                let [x, y] = t.corner(c);
                x < 0.49 && y < 0.49
            })
            .collect();
        t.refine(&m);
    }
    t
}

/// Deterministic pseudo-random numbers in [-1, 1].
fn lcg(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

/// Dense Jacobian columns from the CSC values of the pair's pattern.
fn dense_columns(th: &PTaylorHood, values: &[f64]) -> Vec<Vec<f64>> {
    let pat = &th.pattern;
    let mut j = vec![vec![0.0; pat.n]; pat.n];
    for (col, jc) in j.iter_mut().enumerate() {
        for s in pat.col_ptr[col]..pat.col_ptr[col + 1] {
            jc[pat.row_idx[s]] = values[s];
        }
    }
    j
}

#[test]
fn jacobian_matches_central_differences_with_hanging_nodes_and_mixed_degrees() {
    let tree = graded_square(1, 1);
    let n = tree.leaves().len();
    assert_eq!(n, 7);
    let degrees = [2, 3, 4, 2, 3, 2, 4];
    let g = |x: [f64; 2], c: usize| {
        if c == 0 {
            (1.3 * x[1]).sin() + 0.2 * x[0]
        } else {
            (0.7 * x[0]).cos() * x[1]
        }
    };
    let th = PTaylorHood::new(&tree, &degrees, &g).expect("pair");
    assert!(th.vel.n_hanging > 0, "the mesh must have hanging edges");
    let f = |x: [f64; 2], t: f64| [x[0] * x[1] + t, (x[0] - x[1]).sin()];
    let physics = Physics {
        nu: 0.05,
        f: &f,
        t: 0.3,
    };
    let mut seed = 7;
    let y: Vec<f64> = (0..th.n_eq()).map(|_| 0.5 * lcg(&mut seed)).collect();
    // An old field on other degrees for the θ-step residual.
    let old_th = Rc::new(PTaylorHood::new(&tree, &[3; 7], &g).expect("old pair"));
    let old_y: Vec<f64> = (0..old_th.n_eq()).map(|_| 0.5 * lcg(&mut seed)).collect();
    let old = Field {
        x: old_th.distribute(&old_y),
        th: old_th,
    };
    let step = ThetaStep {
        old: &old,
        dt: 0.1,
        theta: 0.5,
        t_new: 0.4,
    };
    for st in [None, Some(&step)] {
        let mut jv = vec![0.0; th.pattern.nnz()];
        let r0 = th.residual(&y, &physics, st, Some(&mut jv));
        let r_plain = th.residual(&y, &physics, st, None);
        let rdiff = r0
            .iter()
            .zip(&r_plain)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(
            rdiff < 1e-13,
            "residual depends on the Jacobian flag: {rdiff:e}"
        );
        let j = dense_columns(&th, &jv);
        let scale = jv.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let hfd = 1e-6;
        let mut worst = 0.0f64;
        for col in 0..th.n_eq() {
            let mut yp = y.clone();
            let mut ym = y.clone();
            yp[col] += hfd;
            ym[col] -= hfd;
            let rp = th.residual(&yp, &physics, st, None);
            let rm = th.residual(&ym, &physics, st, None);
            for row in 0..th.n_eq() {
                let fd = (rp[row] - rm[row]) / (2.0 * hfd);
                worst = worst.max((fd - j[col][row]).abs());
            }
        }
        eprintln!(
            "jacobian ({}): {} equations, max |J − J_fd| = {worst:.2e}, max |J| = {scale:.2e}",
            if st.is_some() { "θ-step" } else { "steady" },
            th.n_eq()
        );
        assert!(worst < 1e-7 * scale, "max |J − J_fd| = {worst:e}");
    }
}

// Patch solution: ψ = x³y + xy³ + x²y², u = ψ_y, v = −ψ_x (cubic, divergence free),
// p = x² − y² + xy, f = −νΔu + (u·∇)u + ∇p.
fn patch_u(x: [f64; 2]) -> ([f64; 2], [[f64; 2]; 2]) {
    let [a, b] = x;
    (
        [
            a * a * a + 3.0 * a * b * b + 2.0 * a * a * b,
            -(3.0 * a * a * b + b * b * b + 2.0 * a * b * b),
        ],
        [
            [
                3.0 * a * a + 3.0 * b * b + 4.0 * a * b,
                6.0 * a * b + 2.0 * a * a,
            ],
            [
                -(6.0 * a * b + 2.0 * b * b),
                -(3.0 * a * a + 3.0 * b * b + 4.0 * a * b),
            ],
        ],
    )
}

fn patch_p(x: [f64; 2]) -> f64 {
    x[0] * x[0] - x[1] * x[1] + x[0] * x[1]
}

const PATCH_NU: f64 = 0.1;

fn patch_f(x: [f64; 2], _t: f64) -> [f64; 2] {
    let (u, g) = patch_u(x);
    let lap = [12.0 * x[0] + 4.0 * x[1], -12.0 * x[1] - 4.0 * x[0]];
    let gp = [2.0 * x[0] + x[1], -2.0 * x[1] + x[0]];
    let mut f = [0.0; 2];
    for c in 0..2 {
        f[c] = -PATCH_NU * lap[c] + u[0] * g[c][0] + u[1] * g[c][1] + gp[c];
    }
    f
}

#[test]
fn patch_test_reproduces_a_polynomial_solution_across_hanging_degree_transitions() {
    let tree = graded_square(1, 1);
    let degrees = [3, 5, 4, 3, 4, 5, 3];
    let g = |x: [f64; 2], c: usize| patch_u(x).0[c];
    let problem = SteadyProblem {
        nu: PATCH_NU,
        g: &g,
        f: &patch_f,
        exact: None,
    };
    let est = estimate(&tree, &degrees, &problem, 1).expect("steady solves");
    let sol = &est.coarse;
    assert!(sol.th.vel.n_hanging > 0);
    let e = exact_error(sol, &patch_u);
    let ep = pressure_error(sol, &patch_p);
    eprintln!(
        "patch (steady): |u − u_h| = {:.2e}, |u − u_h|_1 = {:.2e}, |p − p_h| = {ep:.2e}",
        e.l2_total(),
        e.h1_total()
    );
    assert!(e.l2_total() < 1e-11, "L2 error {:e}", e.l2_total());
    assert!(e.h1_total() < 1e-10, "H1 error {:e}", e.h1_total());
    assert!(ep < 1e-10, "pressure error {ep:e}");
    // The estimate of a reproduced solution vanishes too.
    let eta = est.indicators.iter().fold(0.0f64, |m, v| m.max(*v));
    assert!(eta < 1e-11, "indicator {eta:e}");
    // A θ-step from the exact (time-independent) state stays on it.
    let gt = |x: [f64; 2], _t: f64, c: usize| patch_u(x).0[c];
    let u0 = |x: [f64; 2]| patch_u(x).0;
    let tp = TransientProblem {
        nu: PATCH_NU,
        g: &gt,
        f: &patch_f,
        u0: &u0,
        exact: None,
    };
    let time = TimeParams {
        dt: 0.05,
        n_steps: 1,
        theta: 0.5,
    };
    let start = initial_field(&tree, &degrees, &tp).expect("projection");
    let e0 = exact_error(&start, &patch_u).l2_total();
    assert!(e0 < 1e-11, "projection of the patch solution: {e0:e}");
    let (next, _) = theta_step(&tree, &degrees, &tp, &time, &start, 0.05).expect("step");
    let e1 = exact_error(&next, &patch_u);
    let ep1 = pressure_error(&next, &patch_p);
    eprintln!(
        "patch (θ-step): |u − u_h| = {:.2e}, |p − p_h| = {ep1:.2e}",
        e1.l2_total()
    );
    assert!(e1.l2_total() < 1e-11 && e1.h1_total() < 1e-10 && ep1 < 1e-10);
}

const RE: f64 = 40.0;

/// Kovasznay flow: u = 1 − e^{λx} cos 2πy, v = λ/(2π) e^{λx} sin 2πy, λ = Re/2 − (Re²/4 +
/// 4π²)^{1/2}.
fn kovasznay(x: [f64; 2]) -> ([f64; 2], [[f64; 2]; 2]) {
    let l = RE / 2.0 - (RE * RE / 4.0 + 4.0 * PI * PI).sqrt();
    let e = (l * x[0]).exp();
    let (s, c) = (2.0 * PI * x[1]).sin_cos();
    (
        [1.0 - e * c, l / (2.0 * PI) * e * s],
        [
            [-l * e * c, 2.0 * PI * e * s],
            [l * l / (2.0 * PI) * e * s, l * e * c],
        ],
    )
}

/// Least-squares slope of ln e against p.
fn slope(p: &[f64], e: &[f64]) -> f64 {
    let n = p.len() as f64;
    let mp = p.iter().sum::<f64>() / n;
    let ml = e.iter().map(|v| v.ln()).sum::<f64>() / n;
    let num: f64 = p.iter().zip(e).map(|(a, b)| (a - mp) * (b.ln() - ml)).sum();
    let den: f64 = p.iter().map(|a| (a - mp).powi(2)).sum();
    num / den
}

#[test]
fn kovasznay_converges_exponentially_in_p_with_effectivity_near_one() {
    // [-0.5, 1] × [-0.5, 1.5] as 3 × 4 cells of side 0.5.
    let coarse: Vec<(i64, i64)> = (0..4).flat_map(|j| (0..3).map(move |i| (i, j))).collect();
    let tree = Quadtree::new([-0.5, -0.5], 0.5, &coarse, 2);
    let n = tree.leaves().len();
    let g = |x: [f64; 2], c: usize| kovasznay(x).0[c];
    let f = |_: [f64; 2], _: f64| [0.0, 0.0];
    let problem = SteadyProblem {
        nu: 1.0 / RE,
        g: &g,
        f: &f,
        exact: Some(&kovasznay),
    };
    let (mut ps, mut errs, mut dev1, mut dev2) = (Vec::new(), Vec::new(), 0.0f64, 0.0f64);
    for p in 2..=6 {
        let d = vec![p; n];
        let e2 = estimate(&tree, &d, &problem, 2).expect("solve, +2");
        let e1 = estimate(&tree, &d, &problem, 1).expect("solve, +1");
        let err = exact_error(&e2.coarse, &kovasznay);
        let f2 = effectivity(&e2.indicators, &err);
        let f1 = effectivity(&e1.indicators, &err);
        eprintln!(
            "kovasznay p = {p}: {} unknowns, |u − u_p| = {:.3e}, eff(+1) = {:.3}, eff(+2) = {:.3}, local(+2) {:.3}..{:.3}, Newton {:?}",
            e2.coarse.n_eq(),
            f2.error,
            f1.global,
            f2.global,
            f2.local_min,
            f2.local_max,
            e2.newton.iter().map(|s| s.iterations).collect::<Vec<_>>()
        );
        assert!(
            (0.85..=1.15).contains(&f2.global),
            "p = {p}: effectivity {}",
            f2.global
        );
        dev1 = dev1.max((f1.global - 1.0).abs());
        dev2 = dev2.max((f2.global - 1.0).abs());
        ps.push(p as f64);
        errs.push(f2.error);
    }
    // Enrichment by two degrees is the better estimate (measured: worst |eff − 1| 0.30 for +1,
    // 0.01 for +2).
    assert!(dev2 < dev1, "+2: {dev2}, +1: {dev1}");
    // Exponential convergence: ln e is linear in p with a steep slope, and two more degrees
    // always gain at least a factor 20. (On this mesh every cell sees cos 2πy with odd parity,
    // so the odd degrees gain most.)
    let s = slope(&ps, &errs);
    eprintln!("kovasznay: errors {}, d ln e / dp = {s:.3}", sci(&errs));
    assert!(s < -1.5, "slope {s}");
    for i in 0..errs.len() - 2 {
        assert!(errs[i + 2] < errs[i] / 20.0, "p = {}: {:?}", ps[i], errs);
    }
    // The adaptive loop stops when every cell is within its share of the tolerance.
    let params = PAdaptParams {
        tol: 1e-3,
        enrich: 2,
        marking: PMarking::Tolerance,
        max_degree: 8,
        max_sweeps: 10,
    };
    let (reps, last) = adapt_steady(&tree, &vec![2; n], &problem, &params).expect("adapt");
    let fin = reps.last().expect("a sweep");
    let eff = fin.effectivity.as_ref().expect("exact known");
    eprintln!(
        "kovasznay adaptive: {} sweeps, {} unknowns, estimate {:.3e}, error {:.3e}",
        reps.len(),
        fin.n_eq,
        fin.estimate,
        eff.error
    );
    assert!(fin.accepted && fin.worst_ratio <= 1.0);
    assert!(fin.estimate <= params.tol && eff.error <= params.tol);
    assert!(reps.len() > 1, "the loop raised degrees");
    assert_eq!(last.coarse.n_eq(), fin.n_eq);
}

// Taylor–Green vortex shifted off the mesh lines: u = (cos kX sin kY, −sin kX cos kY) F(t),
// X = x + 0.1, Y = y + 0.2, F = exp(−2νk²t), k = 2π.
const TG_NU: f64 = 0.01;
const TG_K: f64 = 2.0 * PI;

fn taylor_green(x: [f64; 2], t: f64) -> ([f64; 2], [[f64; 2]; 2]) {
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

fn tg_g(x: [f64; 2], t: f64, c: usize) -> f64 {
    taylor_green(x, t).0[c]
}
fn tg_u0(x: [f64; 2]) -> [f64; 2] {
    taylor_green(x, 0.0).0
}
fn zero_force(_: [f64; 2], _: f64) -> [f64; 2] {
    [0.0, 0.0]
}

fn tg_problem() -> TransientProblem<'static> {
    TransientProblem {
        nu: TG_NU,
        g: &tg_g,
        f: &zero_force,
        u0: &tg_u0,
        exact: Some(&taylor_green),
    }
}

const TG_TIME: TimeParams = TimeParams {
    dt: 0.02,
    n_steps: 2,
    theta: 0.5,
};

/// True L² velocity errors of a uniform run of degree p (no estimate), one per step.
fn uniform_errors(tree: &Quadtree, p: usize, time: &TimeParams) -> (usize, Vec<f64>) {
    let problem = tg_problem();
    let d = vec![p; tree.leaves().len()];
    let mut u = initial_field(tree, &d, &problem).expect("projection");
    let mut errs = Vec::new();
    for n in 0..time.n_steps {
        let t = (n + 1) as f64 * time.dt;
        u = theta_step(tree, &d, &problem, time, &u, t).expect("step").0;
        errs.push(exact_error(&u, &|x| taylor_green(x, t)).l2_total());
    }
    (u.n_eq(), errs)
}

fn sci(v: &[f64]) -> String {
    v.iter()
        .map(|e| format!("{e:.3e}"))
        .collect::<Vec<_>>()
        .join(" ")
}

fn print_reports(name: &str, reps: &[SweepReport]) {
    for r in reps {
        let e = r.effectivity.as_ref().expect("exact known");
        eprintln!(
            "{name}: t = {:.3} try {} {:>3} degrees {:?} unknowns {} estimate {:.3e} error {:.3e} eff {:.3} local {:.2}..{:.2}",
            r.t,
            r.sweep,
            if r.accepted { "acc" } else { "rej" },
            tread::adapt::p_navier_stokes::degree_histogram(&r.degrees),
            r.n_eq,
            r.estimate,
            e.error,
            e.global,
            e.local_min,
            e.local_max
        );
    }
}

#[test]
fn taylor_green_effectivity_every_step_and_exponential_convergence_in_p() {
    // 2 × 2 cells with the lower-left one split: 7 cells, hanging nodes.
    let tree = graded_square(1, 1);
    let n = tree.leaves().len();
    let problem = tg_problem();
    let time = TimeParams {
        n_steps: 3,
        ..TG_TIME
    };
    for p in [4, 6] {
        let uniform = PAdaptParams {
            tol: f64::INFINITY,
            enrich: 2,
            marking: PMarking::Tolerance,
            max_degree: 8,
            max_sweeps: 1,
        };
        let reps = run_transient(&tree, &vec![p; n], &problem, &time, &uniform).expect("run");
        print_reports(&format!("taylor-green uniform p = {p}"), &reps);
        assert_eq!(reps.len(), time.n_steps);
        for r in &reps {
            let e = r.effectivity.as_ref().expect("exact known");
            assert!(
                (0.85..=1.15).contains(&e.global),
                "p = {p}, t = {}: effectivity {}",
                r.t,
                e.global
            );
        }
    }
    // Exponential convergence in p after one step (measured: the gain alternates between
    // degrees, so the assertion is over two degrees).
    let one = TimeParams {
        n_steps: 1,
        ..TG_TIME
    };
    let (ps, errs): (Vec<f64>, Vec<f64>) = (2..=7)
        .map(|p| (p as f64, uniform_errors(&tree, p, &one).1[0]))
        .unzip();
    let s = slope(&ps, &errs);
    eprintln!(
        "taylor-green errors at t = dt for p = 2..=7: {}, d ln e / dp = {s:.3}",
        sci(&errs)
    );
    assert!(s < -0.9, "slope {s}");
    for i in 0..errs.len() - 2 {
        assert!(errs[i + 2] < errs[i] / 4.0, "p = {}: {:?}", ps[i], errs);
    }
}

#[test]
fn taylor_green_adaptive_reaches_the_tolerance_with_fewer_unknowns_than_uniform() {
    // 2 × 2 cells with the lower-left quadrant split twice (25 cells of sides 1/2 and 1/8,
    // 1/4 between): the large cells need higher degrees than the small ones.
    let tree = graded_square(1, 2);
    let n = tree.leaves().len();
    let problem = tg_problem();
    let params = PAdaptParams {
        tol: 1e-4,
        enrich: 2,
        marking: PMarking::Tolerance,
        max_degree: 8,
        max_sweeps: 10,
    };
    let reps = run_transient(&tree, &vec![2; n], &problem, &TG_TIME, &params).expect("run");
    print_reports("taylor-green adaptive", &reps);
    assert!(reps.iter().any(|r| !r.accepted), "no step was repeated");
    let accepted: Vec<&SweepReport> = reps.iter().filter(|r| r.accepted).collect();
    assert_eq!(accepted.len(), TG_TIME.n_steps);
    for r in &reps {
        let e = r.effectivity.as_ref().expect("exact known");
        assert!(
            (0.85..=1.15).contains(&e.global),
            "t = {}, try {}: effectivity {}",
            r.t,
            r.sweep,
            e.global
        );
    }
    for r in &accepted {
        let e = r.effectivity.as_ref().expect("exact known");
        assert!(r.worst_ratio <= 1.0, "accepted with a cell above its share");
        assert!(r.estimate <= params.tol && e.error <= params.tol);
    }
    let adaptive_n = accepted.iter().map(|r| r.n_eq).max().unwrap_or(0);
    // The smallest uniform degree whose true error is below the tolerance at every step.
    let mut uniform = None;
    for p in 2..=8 {
        let (n_eq, errs) = uniform_errors(&tree, p, &TG_TIME);
        eprintln!(
            "taylor-green uniform p = {p}: {n_eq} unknowns, errors {}",
            sci(&errs)
        );
        if errs.iter().all(|&e| e <= params.tol) {
            uniform = Some((p, n_eq));
            break;
        }
    }
    let (p, uniform_n) = uniform.expect("a uniform degree reaches the tolerance");
    eprintln!("taylor-green: adaptive {adaptive_n} unknowns, uniform p = {p} {uniform_n} unknowns");
    assert!(
        adaptive_n < uniform_n,
        "adaptive {adaptive_n}, uniform {uniform_n}"
    );
}
