//! Patch tests on meshes with hanging nodes and degree transitions, and convergence rates on
//! non-conformingly refined meshes.

use tread::adapt::poisson::{assemble, energy_error_sq, solve_direct, Exact};
use tread::adapt::quadtree::Quadtree;
use tread::adapt::space::Space;
use tread::element::hierarchical::Basis1d;

/// u = c0 + c1 x + c2 y + c3 x² + c4 xy + c5 y².
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

/// A unit square refined irregularly: a corner cell three times, a middle cell twice.
fn irregular_square(p: u8) -> Quadtree {
    let mut t = Quadtree::new([0.0, 0.0], 1.0, &[(0, 0)], p);
    t.refine(&t.leaves());
    for _ in 0..3 {
        let first = t.leaves()[0];
        t.refine(&[first]);
    }
    let leaves = t.leaves();
    let last = leaves[leaves.len() - 1];
    t.refine(&[last]);
    let leaves = t.leaves();
    t.refine(&[leaves[leaves.len() - 2]]);
    assert!(t.is_balanced());
    t
}

fn max_nodal_error(t: &Quadtree, space: &Space, x: &[f64], u: &dyn Exact) -> f64 {
    let mut m: f64 = 0.0;
    for k in 0..space.leaves.len() {
        for &(a, b) in &[
            (-1.0, -1.0),
            (0.3, -0.6),
            (1.0, 0.2),
            (0.0, 1.0),
            (-0.77, 0.91),
        ] {
            let (v, _) = space.eval(t, x, k, 0, a, b);
            m = m.max((v - u.u(t.map_point(space.leaves[k], a, b))).abs());
        }
    }
    m
}

fn patch(t: &Quadtree, basis: Basis1d, u: &Poly) -> (f64, f64, usize) {
    let space = Space::new(t, basis, 1, Some(&|x, _| u.u(x))).unwrap();
    let sys = assemble(&space, t, u);
    let x = solve_direct(&space, &sys).unwrap();
    let e: f64 = energy_error_sq(&space, t, &x, u).iter().sum::<f64>().sqrt();
    (max_nodal_error(t, &space, &x, u), e, space.n_hanging)
}

const LINEAR: Poly = Poly([0.3, 1.7, -2.2, 0.0, 0.0, 0.0]);
const QUADRATIC: Poly = Poly([0.3, 1.7, -2.2, 0.9, -1.3, 2.1]);

#[test]
fn q1_patch_test_with_hanging_nodes_reproduces_linear_field() {
    let t = irregular_square(1);
    for basis in [Basis1d::Lagrange, Basis1d::Hierarchical] {
        let (m, e, nh) = patch(&t, basis, &LINEAR);
        assert!(nh >= 6, "the mesh must have hanging edges, has {nh}");
        assert!(
            m < 1e-12 && e < 1e-12,
            "{basis:?}: max error {m:e}, energy error {e:e}"
        );
        // And a quadratic is not reproduced by Q1 (the test can fail).
        let (m, _, _) = patch(&t, basis, &QUADRATIC);
        assert!(m > 1e-4);
    }
}

#[test]
fn q2_patch_test_with_hanging_nodes_reproduces_quadratic_field() {
    let t = irregular_square(2);
    for basis in [Basis1d::Lagrange, Basis1d::Hierarchical] {
        let (m, e, _) = patch(&t, basis, &QUADRATIC);
        assert!(
            m < 1e-11 && e < 1e-11,
            "{basis:?}: max error {m:e}, energy error {e:e}"
        );
    }
}

#[test]
fn p_transition_patch_test() {
    // Degrees 1..4 mixed: a linear field is reproduced; degrees 2..4 mixed: a quadratic one.
    for (lo, field) in [(1u8, &LINEAR), (2u8, &QUADRATIC)] {
        let mut t = irregular_square(lo);
        let leaves = t.leaves();
        for (i, &c) in leaves.iter().enumerate() {
            t.cells[c as usize].degree = lo + (i % (5 - lo as usize)) as u8;
        }
        let (m, e, _) = patch(&t, Basis1d::Hierarchical, field);
        assert!(
            m < 1e-11 && e < 1e-11,
            "degrees from {lo}: max error {m:e}, energy {e:e}"
        );
    }
    // Mixed degrees 1..4 do not reproduce a quadratic (the minimum rule really bites).
    let mut t = irregular_square(1);
    let leaves = t.leaves();
    for (i, &c) in leaves.iter().enumerate() {
        t.cells[c as usize].degree = 1 + (i % 4) as u8;
    }
    let (m, _, _) = patch(&t, Basis1d::Hierarchical, &QUADRATIC);
    assert!(m > 1e-5);
}

/// u = sin(πx) sin(2πy) + x y on the unit square.
struct Smooth;
impl Exact for Smooth {
    fn u(&self, x: [f64; 2]) -> f64 {
        use std::f64::consts::PI;
        (PI * x[0]).sin() * (2.0 * PI * x[1]).sin() + x[0] * x[1]
    }
    fn grad(&self, x: [f64; 2]) -> [f64; 2] {
        use std::f64::consts::PI;
        [
            PI * (PI * x[0]).cos() * (2.0 * PI * x[1]).sin() + x[1],
            2.0 * PI * (PI * x[0]).sin() * (2.0 * PI * x[1]).cos() + x[0],
        ]
    }
    fn f(&self, x: [f64; 2]) -> f64 {
        use std::f64::consts::PI;
        5.0 * PI * PI * (PI * x[0]).sin() * (2.0 * PI * x[1]).sin()
    }
}

#[test]
fn mms_rates_unchanged_on_nonconforming_meshes() {
    for (basis, p, expect) in [
        (Basis1d::Lagrange, 1u8, 1.0),
        (Basis1d::Lagrange, 2u8, 2.0),
        (Basis1d::Hierarchical, 3u8, 3.0),
    ] {
        let mut t = irregular_square(p);
        let mut hist = Vec::new();
        for _ in 0..4 {
            let space = Space::new(&t, basis, 1, Some(&|x, _| Smooth.u(x))).unwrap();
            assert!(space.n_hanging > 0);
            let sys = assemble(&space, &t, &Smooth);
            let x = solve_direct(&space, &sys).unwrap();
            let e: f64 = energy_error_sq(&space, &t, &x, &Smooth)
                .iter()
                .sum::<f64>()
                .sqrt();
            hist.push(e);
            t.refine(&t.leaves());
        }
        let rates: Vec<f64> = hist.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
        let last = rates[rates.len() - 1];
        assert!(
            (last - expect).abs() < 0.1,
            "{basis:?} p={p}: errors {hist:?}, rates {rates:?}"
        );
    }
}
