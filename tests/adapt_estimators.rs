//! Estimators vanish on fields the discretisation represents exactly (on meshes with hanging
//! nodes), and do not vanish otherwise.

use tread::adapt::estimate::{
    Context, Equilibrated, Estimator, ExplicitResidual, Interpolation, Recovery,
};
use tread::adapt::poisson::{assemble, solve_direct, Exact};
use tread::adapt::quadtree::Quadtree;
use tread::adapt::space::Space;
use tread::element::hierarchical::Basis1d;

struct Poly([f64; 6]);
impl Exact for Poly {
    fn u(&self, x: [f64; 2]) -> f64 {
        let c = &self.0;
        c[0] + c[1] * x[0]
            + c[2] * x[1]
            + c[3] * x[0] * x[0]
            + c[4] * x[0] * x[1]
            + c[5] * x[1] * x[1]
    }
    fn grad(&self, x: [f64; 2]) -> [f64; 2] {
        let c = &self.0;
        [
            c[1] + 2.0 * c[3] * x[0] + c[4] * x[1],
            c[2] + c[4] * x[0] + 2.0 * c[5] * x[1],
        ]
    }
    fn f(&self, _x: [f64; 2]) -> f64 {
        -2.0 * (self.0[3] + self.0[5])
    }
}

fn mesh(p: u8) -> Quadtree {
    let mut t = Quadtree::l_shape(1, p);
    for _ in 0..3 {
        let first = t.leaves()[0];
        t.refine(&[first]);
    }
    let l = t.leaves();
    t.refine(&[l[l.len() - 1], l[l.len() / 2]]);
    t
}

fn estimates(p: u8, basis: Basis1d, u: &Poly) -> Vec<(&'static str, f64)> {
    let t = mesh(p);
    let space = Space::new(&t, basis, 1, Some(&|x, _| u.u(x))).unwrap();
    assert!(space.n_hanging > 0);
    let sys = assemble(&space, &t, u);
    let x = solve_direct(&space, &sys).unwrap();
    let f = |x: [f64; 2]| u.f(x);
    let ctx = Context {
        tree: &t,
        space: &space,
        x: &x,
        f: &f,
    };
    let ests: Vec<Box<dyn Estimator>> = vec![
        Box::new(ExplicitResidual),
        Box::new(Equilibrated),
        Box::new(Recovery),
        Box::new(Interpolation),
    ];
    ests.iter()
        .map(|e| (e.name(), e.estimate(&ctx).unwrap().global))
        .collect()
}

#[test]
fn estimators_vanish_on_exactly_represented_fields() {
    let lin = Poly([0.3, 1.7, -2.2, 0.0, 0.0, 0.0]);
    let quad = Poly([0.3, 1.7, -2.2, 0.9, -1.3, 2.1]);
    for (p, basis, u) in [
        (1, Basis1d::Lagrange, &lin),
        (2, Basis1d::Lagrange, &quad),
        (2, Basis1d::Hierarchical, &quad),
    ] {
        for (name, e) in estimates(p, basis, u) {
            assert!(e < 1e-10, "p={p} {basis:?} {name}: {e:e}");
        }
    }
    // Not represented: every estimator sees it.
    for (name, e) in estimates(1, Basis1d::Lagrange, &quad) {
        assert!(e > 1e-3, "{name}: {e:e}");
    }
}
