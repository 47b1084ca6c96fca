//! The L-shape model problem: adaptive rates, estimator effectivities, solvers.

use tread::adapt::driver::{loglog_slope, run, AdaptOptions, EstimatorKind, Solver, StepRecord, Strategy};
use tread::adapt::poisson::{lshape_energy_sq, LShape};
use tread::adapt::quadtree::Quadtree;
use tread::element::hierarchical::Basis1d;

fn lshape(opts: &AdaptOptions) -> Vec<StepRecord> {
    let unorm = lshape_energy_sq().sqrt();
    run(Quadtree::l_shape(0, opts.degree), &LShape, unorm, opts).unwrap()
}

fn show(name: &str, r: &[StepRecord]) {
    println!("{name}");
    for s in r {
        println!(
            "  {:3} N={:7} err={:.3e} est={:.3e} eff={:.3} all={:?} cg={} t={:.3}",
            s.step, s.n_eq, s.error, s.estimate, s.estimate / s.error,
            s.all.map(|a| a.map(|v| (v / s.error * 1000.0).round() / 1000.0)), s.cg_iterations, s.t_total
        );
    }
}

#[test]
fn explore() {
    let mut o = AdaptOptions::h(1);
    o.all_estimators = true;
    o.max_dofs = 5000;
    show("Q1", &lshape(&o));
    let mut o = AdaptOptions::h(2);
    o.all_estimators = true;
    o.max_dofs = 5000;
    show("Q2", &lshape(&o));
    let _ = (loglog_slope, EstimatorKind::Explicit, Solver::Direct, Strategy::H, Basis1d::Lagrange);
}
