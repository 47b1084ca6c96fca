//! Spaces of several components on the quadtree (`Space::new(…, n_comp = 2, …)`): the
//! hanging-node and degree-transition constraints act on every component. A vector Laplacian
//! (two uncoupled components, element matrix K ⊗ I₂ in the space's node-major dof order) on an
//! L-shape mesh with hanging nodes and hierarchical degrees 1–4 mixed must give, component by
//! component, the scalar space's solution for the same data, and reproduce a component that the
//! space represents exactly.

use tread::adapt::poisson::{assemble, reference_stiffness, solve_direct, Exact, LShape};
use tread::adapt::quadtree::Quadtree;
use tread::adapt::space::Space;
use tread::assembly::constraints::CondenseScratch;
use tread::element::hierarchical::Basis1d;
use tread::solver::{LinearKind, SparseSolver};

/// An L-shape mesh refined toward the corner and elsewhere (hanging nodes), with the degrees
/// 1, 2, 3, 4 spread over the leaves.
fn mesh() -> Quadtree {
    let mut t = Quadtree::l_shape(1, 1);
    for _ in 0..3 {
        let first = t.leaves()[0];
        t.refine(&[first]);
    }
    let l = t.leaves();
    t.refine(&[l[l.len() - 1], l[l.len() / 2]]);
    for (k, c) in t.leaves().into_iter().enumerate() {
        t.cells[c as usize].degree = 1 + (k * 7 % 4) as u8;
    }
    t
}

#[test]
fn two_components_solve_as_two_scalar_problems() {
    let t = mesh();
    let basis = Basis1d::Hierarchical;
    let u = LShape;
    // Component 1: an affine field, in every cell's space.
    let affine = |x: [f64; 2]| 0.4 - 1.3 * x[0] + 0.7 * x[1];
    let g = |x: [f64; 2], comp: usize| if comp == 0 { u.u(x) } else { affine(x) };
    let scalar = Space::new(&t, basis, 1, Some(&|x, _| u.u(x))).unwrap();
    let vector = Space::new(&t, basis, 2, Some(&g)).unwrap();
    assert!(scalar.n_hanging > 0);
    assert!(scalar.degree.contains(&1) && scalar.degree.contains(&4));
    assert_eq!(vector.n_dofs(), 2 * scalar.n_dofs());
    // The scalar solution.
    let xs = solve_direct(&scalar, &assemble(&scalar, &t, &u)).unwrap();
    // The vector one: K ⊗ I₂ per cell, no load.
    let pat = &vector.pattern;
    let mut values = vec![0.0; pat.nnz()];
    let mut rhs = vec![0.0; pat.n];
    let mut scratch = CondenseScratch::default();
    let refs: Vec<Vec<f64>> = (0..=4)
        .map(|p| {
            if p == 0 {
                Vec::new()
            } else {
                reference_stiffness(basis, p)
            }
        })
        .collect();
    for k in 0..vector.leaves.len() {
        let p = vector.degree[k];
        let nl = (p + 1) * (p + 1);
        let m = 2 * nl;
        let mut kv = vec![0.0; m * m];
        for a in 0..nl {
            for b in 0..nl {
                for c in 0..2 {
                    kv[(2 * a + c) * m + 2 * b + c] = refs[p][a * nl + b];
                }
            }
        }
        pat.add_cell(k, &kv, &vec![0.0; m], &mut values, &mut rhs, &mut scratch);
    }
    let mut solver =
        SparseSolver::new(pat.n, &pat.col_ptr, &pat.row_idx, LinearKind::Cholesky).unwrap();
    solver.factorize(&values).unwrap();
    solver.solve_in_place(&mut rhs).unwrap();
    let mut xv = vec![0.0; vector.n_dofs()];
    vector.constraints.distribute(&rhs, &mut xv);
    // Component 0 equals the scalar solution at every dof; component 1 is the affine field
    // (compared by point evaluation: a mode dof holds a coefficient, not a value).
    let scale = xs.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let d0 = (0..scalar.n_dofs())
        .map(|i| (xv[2 * i] - xs[i]).abs())
        .fold(0.0f64, f64::max);
    let (mut d1, mut d0e) = (0.0f64, 0.0f64);
    for k in 0..vector.leaves.len() {
        let c = vector.leaves[k];
        for &(xi, eta) in &[(-0.6, 0.3), (0.2, -0.9), (0.8, 0.8)] {
            let x = t.map_point(c, xi, eta);
            let (v1, g1) = vector.eval(&t, &xv, k, 1, xi, eta);
            d1 = d1.max((v1 - affine(x)).abs());
            d1 = d1.max((g1[0] + 1.3).abs()).max((g1[1] - 0.7).abs());
            // And component 0 of the vector space evaluates as the scalar space does.
            let (v0, _) = vector.eval(&t, &xv, k, 0, xi, eta);
            let (s0, _) = scalar.eval(&t, &xs, k, 0, xi, eta);
            d0e = d0e.max((v0 - s0).abs());
        }
    }
    eprintln!(
        "{} cells, {} hanging, degrees 1–4: component 0 vs scalar {d0:.2e} at the dofs, {d0e:.2e} at points (of {scale:.2e}); component 1 vs affine {d1:.2e}",
        vector.leaves.len(),
        scalar.n_hanging
    );
    assert!(d0 < 1e-12 * scale.max(1.0), "component 0 differs by {d0:e}");
    assert!(
        d0e < 1e-12 * scale.max(1.0),
        "component 0 differs by {d0e:e} at points"
    );
    assert!(d1 < 1e-11, "affine component off by {d1:e}");
}
