//! The L-shape model problem (u = r^{2/3} sin(2θ/3)): adaptive and uniform energy-error rates,
//! the effectivity of each estimator on every step, the iterative solver against the direct
//! one, and hp convergence.

use tread::adapt::driver::{
    loglog_slope, run, AdaptOptions, EstimatorKind, Solver, StepRecord, Strategy,
};
use tread::adapt::poisson::{lshape_energy_sq, LShape};
use tread::adapt::quadtree::Quadtree;
use tread::element::hierarchical::Basis1d;

fn lshape(opts: &AdaptOptions) -> Vec<StepRecord> {
    let unorm = lshape_energy_sq().sqrt();
    run(Quadtree::l_shape(0, opts.degree), &LShape, unorm, opts).unwrap()
}

fn slope_above(r: &[StepRecord], n_min: usize) -> f64 {
    let pts: Vec<(f64, f64)> = r
        .iter()
        .filter(|s| s.n_eq >= n_min)
        .map(|s| (s.n_eq as f64, s.error))
        .collect();
    assert!(pts.len() >= 3, "too few steps above {n_min}: {}", pts.len());
    loglog_slope(&pts)
}

fn effectivities(r: &[StepRecord], which: usize) -> Vec<(usize, f64)> {
    r.iter()
        .map(|s| (s.n_eq, s.all.unwrap()[which] / s.error))
        .collect()
}

#[test]
fn lshape_energy_norm_reference() {
    // |u|²₁ = ∮ u ∂ₙu: on the outer boundary only (u = 0 on the re-entrant edges); computed
    // here by an independent 1D quadrature of the boundary integral.
    let e = LShape;
    use tread::adapt::poisson::Exact;
    let (gx, gw) = tread::element::hierarchical::gauss_legendre(40);
    let mut s = 0.0;
    // Segments (start, end, outward normal), each split into 64 pieces.
    let segs = [
        ([1.0, 0.0], [1.0, 1.0], [1.0, 0.0]),
        ([1.0, 1.0], [-1.0, 1.0], [0.0, 1.0]),
        ([-1.0, 1.0], [-1.0, -1.0], [-1.0, 0.0]),
        ([-1.0, -1.0], [0.0, -1.0], [0.0, -1.0]),
    ];
    for (a, b, n) in segs {
        for piece in 0..64 {
            let (t0, t1) = (piece as f64 / 64.0, (piece + 1) as f64 / 64.0);
            for (&q, &w) in gx.iter().zip(&gw) {
                let t = t0 + 0.5 * (q + 1.0) * (t1 - t0);
                let x = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
                let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
                let g = e.grad(x);
                s += 0.5 * w * (t1 - t0) * len * e.u(x) * (g[0] * n[0] + g[1] * n[1]);
            }
        }
    }
    let v = lshape_energy_sq();
    assert!((v - s).abs() < 1e-8 * s, "{v} vs {s}");
}

#[test]
fn h_adaptive_q1_rate_and_effectivities() {
    let mut o = AdaptOptions::h(1);
    o.all_estimators = true;
    o.max_dofs = 8000;
    let r = lshape(&o);
    let slope = slope_above(&r, 400);
    assert!((slope + 0.5).abs() < 0.1, "adaptive Q1 slope {slope}");
    // Equilibrated: a guaranteed upper bound on every step, and not loose.
    for (n, eff) in effectivities(&r, 1) {
        assert!(
            (1.0..=2.0).contains(&eff),
            "equilibrated effectivity {eff} at N = {n}"
        );
    }
    // Recovery: asymptotically exact for Q1.
    for (n, eff) in effectivities(&r, 2).into_iter().filter(|e| e.0 >= 2000) {
        assert!(
            (0.9..=1.15).contains(&eff),
            "recovery effectivity {eff} at N = {n}"
        );
    }
    // Interpolation estimator with recovered second derivatives: also close to 1 there.
    for (n, eff) in effectivities(&r, 3).into_iter().filter(|e| e.0 >= 1000) {
        assert!(
            (0.8..=1.25).contains(&eff),
            "interpolation effectivity {eff} at N = {n}"
        );
    }
}

#[test]
fn h_adaptive_q2_rate_and_effectivities() {
    let mut o = AdaptOptions::h(2);
    o.all_estimators = true;
    o.max_dofs = 6000;
    let r = lshape(&o);
    let slope = slope_above(&r, 400);
    assert!((slope + 1.0).abs() < 0.1, "adaptive Q2 slope {slope}");
    for (n, eff) in effectivities(&r, 1) {
        assert!(
            (1.0..=2.0).contains(&eff),
            "equilibrated effectivity {eff} at N = {n}"
        );
    }
}

#[test]
fn adaptive_with_equilibrated_marking_keeps_rate() {
    let mut o = AdaptOptions::h(1);
    o.estimator = EstimatorKind::Equilibrated;
    o.max_dofs = 6000;
    let slope = slope_above(&lshape(&o), 400);
    assert!((slope + 0.5).abs() < 0.1, "slope {slope}");
}

#[test]
fn uniform_q1_and_q2_rate_is_one_third() {
    for p in [1, 2] {
        let mut o = AdaptOptions::h(p);
        o.uniform = true;
        o.max_dofs = 15_000;
        let slope = slope_above(&lshape(&o), 100);
        assert!(
            (slope + 1.0 / 3.0).abs() < 0.1,
            "uniform Q{p} slope {slope}"
        );
    }
}

#[test]
fn jacobi_cg_matches_direct_solve() {
    let mut o = AdaptOptions::h(1);
    o.max_dofs = 5000;
    let d = lshape(&o);
    o.solver = Solver::Cg { tol: 1e-10 };
    let c = lshape(&o);
    assert_eq!(d.len(), c.len());
    for (a, b) in d.iter().zip(&c) {
        assert_eq!(a.n_eq, b.n_eq);
        assert!(
            (a.error - b.error).abs() < 1e-6 * a.error,
            "{} vs {}",
            a.error,
            b.error
        );
    }
    // The transferred solution is a good start: few iterations per equation.
    let last = c.last().unwrap();
    assert!(
        last.cg_iterations < 200,
        "{} iterations",
        last.cg_iterations
    );
}

#[test]
fn hp_converges_exponentially_in_cube_root_of_n() {
    let mut o = AdaptOptions::h(3);
    o.basis = Basis1d::Hierarchical;
    o.strategy = Strategy::Hp;
    o.hp_decay = 0.3;
    o.max_degree = 8;
    o.estimator = EstimatorKind::Equilibrated;
    o.max_dofs = 2500;
    let r = lshape(&o);
    // ln e against N^{1/3}: a straight line with a clearly negative slope.
    let pts: Vec<(f64, f64)> = r
        .iter()
        .map(|s| ((s.n_eq as f64).cbrt(), s.error.ln()))
        .collect();
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let syy: f64 = pts.iter().map(|p| (p.1 - my).powi(2)).sum();
    let slope = sxy / sxx;
    let r2 = sxy * sxy / (sxx * syy);
    assert!(slope < -0.4 && r2 > 0.9, "slope {slope}, R² {r2}");
    // And far below the algebraic h-adaptive Q2 at the same size.
    let last = r.last().unwrap();
    let mut q2 = AdaptOptions::h(2);
    q2.max_dofs = last.n_eq;
    let rq2 = lshape(&q2);
    let e_q2 = rq2.iter().rfind(|s| s.n_eq <= last.n_eq).unwrap().error;
    assert!(last.error < 0.5 * e_q2, "hp {} vs Q2 {}", last.error, e_q2);
}
