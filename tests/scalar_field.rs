//! A scalar field through the same degrees of freedom, constraints and assembler as the solid:
//! `DofMap::with_components(mesh, 1, …)` and `Assembler` solve −Δu = f with Dirichlet data.
//!
//! * Patch tests on meshes with hanging nodes: a linear field with Q1 cells, a quadratic one
//!   with Q2 cells (affine cells, where the quadratic lies in the space), both to round-off.
//! * Manufactured solution on the annulus (isoparametric Q1 and Q2): observed rates in L2 and
//!   the H1 seminorm are p + 1 and p, on uniform meshes and on meshes with one quadrant
//!   refined once more (non-conforming, hanging nodes).

use tread::assembly::{Assembler, DofMap, LocalSystem};
use tread::element::{gauss_1d, Lagrange2D, Q1, Q2};
use tread::math::Vec2;
use tread::mesh::{annulus, AnnulusSpec, Forest, Mesh};
use tread::solver::{LinearKind, SparseSolver};

/// Shape values and reference gradients of a cell with `n` nodes (4: Q1, 9: Q2).
fn shape(n: usize, xi: f64, eta: f64, v: &mut [f64; 9], d: &mut [[f64; 2]; 9]) {
    if n == 4 {
        Q1::eval(xi, eta, &mut v[..4], &mut d[..4]);
    } else {
        Q2::eval(xi, eta, v, d);
    }
}

/// Physical point, shape values and physical gradients at (ξ, η) of isoparametric cell `c`;
/// returns det J.
fn at(
    mesh: &Mesh,
    c: usize,
    xi: f64,
    eta: f64,
    v: &mut [f64; 9],
    g: &mut [[f64; 2]; 9],
) -> (Vec2, f64) {
    let nodes = mesh.cell_nodes(c);
    let mut d = [[0.0; 2]; 9];
    shape(nodes.len(), xi, eta, v, &mut d);
    let mut x = Vec2::zeros();
    let mut j = [[0.0; 2]; 2];
    for (a, &n) in nodes.iter().enumerate() {
        let p = mesh.nodes[n as usize];
        x += p * v[a];
        for r in 0..2 {
            for s in 0..2 {
                j[r][s] += p[r] * d[a][s];
            }
        }
    }
    let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
    let inv = [
        [j[1][1] / det, -j[0][1] / det],
        [-j[1][0] / det, j[0][0] / det],
    ];
    for a in 0..nodes.len() {
        // ∇N = J⁻ᵀ ∇_ξ N.
        g[a] = [
            inv[0][0] * d[a][0] + inv[1][0] * d[a][1],
            inv[0][1] * d[a][0] + inv[1][1] * d[a][1],
        ];
    }
    (x, det)
}

/// Solve −Δu = f, u = g on the nodes `is_boundary` selects, with one scalar component per
/// node; returns the full nodal vector (constrained nodes set from their masters).
fn solve(
    mesh: &Mesh,
    f: &(dyn Fn(Vec2) -> f64 + Sync),
    g: &dyn Fn(Vec2) -> f64,
    is_boundary: &dyn Fn(Vec2) -> bool,
) -> (DofMap, Vec<f64>) {
    let fixed: Vec<u32> = (0..mesh.n_nodes() as u32)
        .filter(|&n| is_boundary(mesh.nodes[n as usize]))
        .collect();
    let dofs = DofMap::with_components(mesh, 1, 0, &fixed, 0);
    assert_eq!(dofs.n_comp, 1);
    assert_eq!(dofs.n_full(), mesh.n_nodes());
    for c in 0..mesh.n_cells() {
        assert_eq!(dofs.cell(c).len(), mesh.cell_nodes(c).len());
    }
    let mut full = vec![0.0; dofs.n_full()];
    for &n in &fixed {
        full[dofs.node_dof(n as usize, 0)] = g(mesh.nodes[n as usize]);
    }
    dofs.apply_constraints(&mut full);
    let mut asm = Assembler::new(mesh, &dofs);
    let (qx, qw) = gauss_1d(4);
    let u0 = full.clone();
    asm.assemble(&dofs, true, |c, loc: &mut LocalSystem| {
        let el = dofs.cell(c);
        let nd = el.len();
        let (mut v, mut gr) = ([0.0; 9], [[0.0; 2]; 9]);
        for (i, &xi) in qx.iter().enumerate() {
            for (j, &eta) in qx.iter().enumerate() {
                let (x, det) = at(mesh, c, xi, eta, &mut v, &mut gr);
                let w = qw[i] * qw[j] * det.abs();
                let mut grad_u = [0.0; 2];
                for a in 0..nd {
                    let ua = u0[el[a] as usize];
                    grad_u[0] += ua * gr[a][0];
                    grad_u[1] += ua * gr[a][1];
                }
                let fx = f(x);
                for a in 0..nd {
                    loc.r[a] += w * (gr[a][0] * grad_u[0] + gr[a][1] * grad_u[1] - fx * v[a]);
                    for b in 0..nd {
                        loc.k[a * nd + b] += w * (gr[a][0] * gr[b][0] + gr[a][1] * gr[b][1]);
                    }
                }
            }
        }
    });
    let mut solver =
        SparseSolver::new(asm.n, &asm.col_ptr, &asm.row_idx, LinearKind::Cholesky).unwrap();
    solver.factorize(&asm.values).unwrap();
    let mut dx: Vec<f64> = asm.residual.iter().map(|r| -r).collect();
    solver.solve_in_place(&mut dx).unwrap();
    dofs.add_free(1.0, &dx, &mut full);
    (dofs, full)
}

/// L2 error and H1-seminorm error of the nodal field against `u` (with gradient `du`).
fn errors(
    mesh: &Mesh,
    dofs: &DofMap,
    full: &[f64],
    u: &dyn Fn(Vec2) -> f64,
    du: &dyn Fn(Vec2) -> [f64; 2],
) -> (f64, f64) {
    let (qx, qw) = gauss_1d(6);
    let (mut l2, mut h1) = (0.0, 0.0);
    let (mut v, mut gr) = ([0.0; 9], [[0.0; 2]; 9]);
    for c in 0..mesh.n_cells() {
        let el = dofs.cell(c);
        for (i, &xi) in qx.iter().enumerate() {
            for (j, &eta) in qx.iter().enumerate() {
                let (x, det) = at(mesh, c, xi, eta, &mut v, &mut gr);
                let w = qw[i] * qw[j] * det.abs();
                let (mut uh, mut gh) = (0.0, [0.0; 2]);
                for (a, &d) in el.iter().enumerate() {
                    uh += full[d as usize] * v[a];
                    gh[0] += full[d as usize] * gr[a][0];
                    gh[1] += full[d as usize] * gr[a][1];
                }
                let ge = du(x);
                l2 += w * (uh - u(x)).powi(2);
                h1 += w * ((gh[0] - ge[0]).powi(2) + (gh[1] - ge[1]).powi(2));
            }
        }
    }
    (l2.sqrt(), h1.sqrt())
}

/// Structured mesh of rectangles on [0, 1]² with non-uniform grid lines, degree 1 or 2.
fn rectangles(degree: usize, n: usize) -> Mesh {
    let m = degree * n + 1;
    // Non-uniform but affine cells: each cell is a rectangle, mid-side nodes at midpoints.
    let breaks: Vec<f64> = (0..=n)
        .map(|i| {
            let s = i as f64 / n as f64;
            s + 0.15 * (std::f64::consts::PI * s).sin() * (1.0 - s)
        })
        .collect();
    let line = |k: usize| -> f64 {
        let (c, r) = (k / degree, k % degree);
        if r == 0 {
            breaks[c]
        } else {
            0.5 * (breaks[c] + breaks[c + 1])
        }
    };
    let mut nodes = Vec::new();
    for j in 0..m {
        for i in 0..m {
            nodes.push(Vec2::new(line(i), 1.3 * line(j)));
        }
    }
    let (mut conn, mut offsets) = (Vec::new(), vec![0]);
    for cj in 0..n {
        for ci in 0..n {
            for b in 0..=degree {
                for a in 0..=degree {
                    conn.push(((degree * cj + b) * m + degree * ci + a) as u32);
                }
            }
            offsets.push(conn.len());
        }
    }
    let n_cells = n * n;
    Mesh {
        nodes,
        conn,
        offsets,
        degree: vec![degree as u8; n_cells],
        geometry: vec![tread::mesh::CellGeometry::Isoparametric; n_cells],
        node_sets: Default::default(),
        facet_sets: Default::default(),
        rings: None,
        regions: vec![0; n_cells],
        region_names: vec!["all".into()],
        constraints: Vec::new(),
    }
}

/// Refine cell `first`, then the first child twice more, so that the closure splits
/// neighbours and several levels of hanging nodes appear.
fn with_hanging_nodes(root: Mesh, first: usize) -> Mesh {
    let mut f = Forest::new(root).unwrap();
    f.refine(&[first]).unwrap();
    f.refine(&[first]).unwrap();
    f.refine(&[first + 1]).unwrap();
    let (mesh, _) = f.mesh();
    assert!(!mesh.constraints.is_empty(), "no hanging node");
    mesh
}

/// A scalar field of the position.
type Field = dyn Fn(Vec2) -> f64;

#[test]
fn patch_tests_with_hanging_nodes_are_exact() {
    let on_box = |x: Vec2| {
        x[0].abs() < 1e-12
            || (x[0] - 1.0).abs() < 1e-12
            || x[1].abs() < 1e-12
            || (x[1] - 1.3).abs() < 1e-12
    };
    // Q1: u = 1 + 2x − 3y, −Δu = 0.
    let lin = |x: Vec2| 1.0 + 2.0 * x[0] - 3.0 * x[1];
    // Q2: u = x² + xy − 2y² + x, −Δu = −(2 − 4) = 2.
    let quad = |x: Vec2| x[0] * x[0] + x[0] * x[1] - 2.0 * x[1] * x[1] + x[0];
    let cases: [(usize, &Field, f64); 2] = [(1, &lin, 0.0), (2, &quad, 2.0)];
    for (degree, u, f) in cases {
        let mesh = with_hanging_nodes(rectangles(degree, 4), 5);
        let (dofs, full) = solve(&mesh, &move |_| f, u, &on_box);
        assert!(dofs.has_constraints());
        let worst = (0..mesh.n_nodes())
            .map(|n| (full[n] - u(mesh.nodes[n])).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-12, "Q{degree}: nodal error {worst:e}");
        // Away from the nodes too: the constrained traces make the field conforming.
        let (l2, h1) = errors(&mesh, &dofs, &full, u, &|x| {
            if degree == 1 {
                [2.0, -3.0]
            } else {
                [2.0 * x[0] + x[1] + 1.0, x[0] - 4.0 * x[1]]
            }
        });
        assert!(l2 < 1e-12 && h1 < 1e-11, "Q{degree}: L2 {l2:e}, H1 {h1:e}");
    }
}

/// Least-squares slope of log e against log h.
fn slope(h: &[f64], e: &[f64]) -> f64 {
    let n = h.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = h.iter().zip(e).map(|(a, b)| (a.ln(), b.ln())).unzip();
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let sxy: f64 = lx.iter().zip(&ly).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = lx.iter().map(|a| (a - mx).powi(2)).sum();
    sxy / sxx
}

#[test]
fn manufactured_rates_are_unchanged_by_non_conforming_refinement() {
    // u = sin x sin y + x, −Δu = 2 sin x sin y, on the annulus 1 < r < 2.
    let u = |x: Vec2| x[0].sin() * x[1].sin() + x[0];
    let du = |x: Vec2| [x[0].cos() * x[1].sin() + 1.0, x[0].sin() * x[1].cos()];
    let f = |x: Vec2| 2.0 * x[0].sin() * x[1].sin();
    for degree in [1usize, 2] {
        let mut uniform_l2 = Vec::new();
        for refine_quadrant in [false, true] {
            let (mut hs, mut e0, mut e1) = (Vec::new(), Vec::new(), Vec::new());
            for level in 0..3 {
                let k = 1usize << level;
                let mut root = annulus(&AnnulusSpec {
                    ri: 1.0,
                    ro: 2.0,
                    n_r: 2 * k,
                    n_theta: 16 * k,
                    degree,
                    grading_r: 1.0,
                    grading_theta: 0.0,
                });
                root.make_isoparametric();
                let mesh = if refine_quadrant {
                    let mut forest = Forest::new(root).unwrap();
                    let marked: Vec<usize> = (0..forest.leaves().len())
                        .filter(|&c| {
                            let x = forest.root_point(c, 0.0, 0.0);
                            x[0] > 0.0 && x[1] > 0.0
                        })
                        .collect();
                    forest.refine(&marked).unwrap();
                    let (m, _) = forest.mesh();
                    assert!(!m.constraints.is_empty());
                    m
                } else {
                    root
                };
                // The refined boundary nodes lie on the isoparametric boundary, not on the
                // circles: the mesh's node sets name them.
                let boundary: std::collections::HashSet<u32> = ["hub", "outer"]
                    .iter()
                    .flat_map(|s| mesh.node_set(s).iter().copied())
                    .collect();
                let on_boundary = |x: Vec2| {
                    boundary
                        .iter()
                        .any(|&n| (mesh.nodes[n as usize] - x).norm() < 1e-12)
                };
                let (dofs, full) = solve(&mesh, &f, &u, &on_boundary);
                let (l2, h1) = errors(&mesh, &dofs, &full, &u, &du);
                hs.push(1.0 / k as f64);
                e0.push(l2);
                e1.push(h1);
            }
            if refine_quadrant {
                // More cells where the quadrant was refined: never a larger error.
                for (e, eu) in e0.iter().zip(&uniform_l2) {
                    assert!(e <= eu, "Q{degree}: refined {e:e} > uniform {eu:e}");
                }
            } else {
                uniform_l2 = e0.clone();
            }
            let (r0, r1) = (slope(&hs, &e0), slope(&hs, &e1));
            let p = degree as f64;
            assert!(
                (r0 - (p + 1.0)).abs() < 0.25 && (r1 - p).abs() < 0.2,
                "Q{degree}, quadrant refined {refine_quadrant}: L2 rate {r0:.3}, H1 rate {r1:.3} \
                 (errors {e0:.3?} / {e1:.3?})"
            );
            println!(
                "Q{degree} quadrant refined {refine_quadrant}: L2 {e0:.3?} rate {r0:.3}; H1 {e1:.3?} rate {r1:.3}"
            );
        }
    }
}
