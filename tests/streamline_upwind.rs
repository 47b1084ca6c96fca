//! The upwind streamline transport of the steady viscoelastic history on general meshes:
//! `β·∇Y + Y/τ = s` with the rigid rotation `β = ω (−X₂, X₁)`, discretised by upwind
//! discontinuous Galerkin on the quadrature points (`physics::streamline_upwind`).
//!
//! Checked against manufactured solutions (any smooth Y on the annulus is periodic along the
//! circles; s is computed from it by hand): the observed order at the quadrature points on
//! exact polar cells, on isoparametric cells that the streamlines cross at an angle (a smooth
//! non-polar map of the annulus), and on a mesh with hanging nodes; constants are reproduced
//! exactly; both spinning directions.

use tread::element::gauss_1d;
use tread::mesh::locate::point_at;
use tread::mesh::{annulus, AnnulusSpec, Forest, Mesh};
use tread::physics::streamline_upwind::UpwindTransport;

const TAU: f64 = 0.4;

/// The manufactured solution and its source `s = ω (−y ∂x + x ∂y) Y + Y/τ`.
fn exact(x: f64, y: f64) -> f64 {
    (1.3 * x).sin() * y + 0.5 * (x * y).cos() + 0.2 * x * x
}

fn source(omega: f64, x: f64, y: f64) -> f64 {
    let dx = 1.3 * (1.3 * x).cos() * y - 0.5 * y * (x * y).sin() + 0.4 * x;
    let dy = (1.3 * x).sin() - 0.5 * x * (x * y).sin();
    omega * (-y * dx + x * dy) + exact(x, y) / TAU
}

/// Gauss point positions in history order (cell by cell, ξ fastest) and their offsets.
fn points(mesh: &Mesh) -> (Vec<usize>, Vec<(f64, f64, f64)>) {
    let mut offsets = vec![0];
    let mut pts = Vec::new();
    for c in 0..mesh.n_cells() {
        let q = usize::from(mesh.degree[c]) + 1;
        let (g, w) = gauss_1d(q);
        for l in 0..q {
            for i in 0..q {
                let x = point_at(mesh, c, g[i], g[l]);
                // Weight: w_i w_l times the cell's area element (from a tiny finite difference
                // of the map, accurate enough for an error norm).
                let h = 1e-6;
                let dxi = (point_at(mesh, c, g[i] + h, g[l]) - point_at(mesh, c, g[i] - h, g[l]))
                    / (2.0 * h);
                let deta = (point_at(mesh, c, g[i], g[l] + h) - point_at(mesh, c, g[i], g[l] - h))
                    / (2.0 * h);
                let det = dxi[0] * deta[1] - dxi[1] * deta[0];
                pts.push((x[0], x[1], w[i] * w[l] * det));
            }
        }
        offsets.push(pts.len());
    }
    (offsets, pts)
}

/// Relative L² error at the points of the discrete solution for the manufactured source.
fn error(mesh: &Mesh, omega: f64) -> f64 {
    let (offsets, pts) = points(mesh);
    let mut op =
        UpwindTransport::new(mesh, &offsets, omega >= 0.0).unwrap_or_else(|e| panic!("{e}"));
    let mut y: Vec<f64> = pts.iter().map(|&(x, yy, _)| source(omega, x, yy)).collect();
    op.solve(omega, &[TAU], 0, &mut y)
        .unwrap_or_else(|e| panic!("{e}"));
    let (mut e2, mut n2) = (0.0, 0.0);
    for (v, &(x, yy, w)) in y.iter().zip(&pts) {
        let ex = exact(x, yy);
        e2 += w * (v - ex).powi(2);
        n2 += w * ex * ex;
    }
    (e2 / n2).sqrt()
}

fn ring_mesh(n_r: usize, n_theta: usize, degree: usize) -> Mesh {
    annulus(&AnnulusSpec {
        ri: 1.0,
        ro: 2.0,
        n_r,
        n_theta,
        degree,
        grading_r: 1.0,
        grading_theta: 0.0,
    })
}

/// The annulus mapped onto itself by a smooth non-polar map (radii and angles twisted): its
/// isoparametric cells are crossed by the circles at an angle, so every face carries flux.
fn twisted_mesh(n_r: usize, n_theta: usize, degree: usize) -> Mesh {
    let mut m = ring_mesh(n_r, n_theta, degree);
    m.make_isoparametric();
    for p in m.nodes.iter_mut() {
        let (r, t) = (p.norm(), p[1].atan2(p[0]));
        let bump = (r - 1.0) * (2.0 - r);
        let (r2, t2) = (r + 0.3 * bump * (3.0 * t).sin(), t + 0.4 * bump);
        *p = tread::math::Vec2::new(r2 * t2.cos(), r2 * t2.sin());
    }
    m
}

fn sci(v: &[f64]) -> Vec<String> {
    v.iter().map(|e| format!("{e:.3e}")).collect()
}

fn rates(errs: &[f64]) -> Vec<f64> {
    errs.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
}

/// Order q = degree + 1 at the quadrature points on exact polar cells (where the scheme splits
/// into rings), both spinning directions.
#[test]
fn polar_cells_converge_at_order_q() {
    for degree in [1, 2] {
        for omega in [3.0, -3.0] {
            let errs: Vec<f64> = [16, 32, 64, 128]
                .iter()
                .map(|&n| error(&ring_mesh(n / 8, n, degree), omega))
                .collect();
            let r = rates(&errs);
            println!(
                "polar Q{degree}, omega {omega}: errors {:?}, rates {r:.3?}",
                sci(&errs)
            );
            let last = r[r.len() - 1];
            assert!(
                (last - (degree as f64 + 1.0)).abs() < 0.25,
                "Q{degree}: rates {r:?}"
            );
        }
    }
}

/// The same order on twisted isoparametric cells: the streamlines cross the cells and the
/// upwind neighbours are found by point location.
#[test]
fn twisted_cells_converge_at_order_q() {
    for degree in [1, 2] {
        let errs: Vec<f64> = [16, 32, 64, 128]
            .iter()
            .map(|&n| error(&twisted_mesh(n / 8, n, degree), 2.0))
            .collect();
        let r = rates(&errs);
        println!("twisted Q{degree}: errors {:?}, rates {r:.3?}", sci(&errs));
        let last = r[r.len() - 1];
        assert!(
            (last - (degree as f64 + 1.0)).abs() < 0.3,
            "Q{degree}: rates {r:?}"
        );
    }
}

/// Hanging nodes: half of the cells refined once (one big face against two small ones along
/// the refinement front). The error stays of the order of the uniform mesh's, and under
/// refinement of the whole forest the order is kept.
#[test]
fn hanging_nodes_keep_the_order() {
    let mut errs = Vec::new();
    for n in [16, 32, 64] {
        let base = twisted_mesh(n / 8, n, 2);
        let mut forest = Forest::new(base.clone()).unwrap_or_else(|e| panic!("{e}"));
        let marked: Vec<usize> = (0..base.n_cells())
            .filter(|&c| {
                let x = point_at(&base, c, 0.0, 0.0);
                x[1] < 0.0
            })
            .collect();
        forest.refine(&marked).unwrap_or_else(|e| panic!("{e}"));
        let (mesh, _) = forest.mesh();
        assert!(!mesh.constraints.is_empty(), "no hanging nodes");
        let e_hang = error(&mesh, 2.0);
        let e_base = error(&base, 2.0);
        println!(
            "{n} around: base {e_base:.3e}, half refined {e_hang:.3e} ({} cells)",
            mesh.n_cells()
        );
        assert!(e_hang < 1.2 * e_base, "{e_hang} vs {e_base}");
        errs.push(e_hang);
    }
    let r = rates(&errs);
    println!("hanging-node rates {r:.3?}");
    assert!((r[r.len() - 1] - 3.0).abs() < 0.3, "{r:?}");
}

/// Constants are reproduced exactly (T 1 = 0): a constant source s gives Y = τ s, at any ω
/// and on every kind of mesh; ω = 0 is the relaxed limit Y = τ s for any source.
#[test]
fn constants_are_exact() {
    for mesh in [
        ring_mesh(2, 16, 2),
        twisted_mesh(2, 16, 1),
        twisted_mesh(3, 24, 2),
    ] {
        let (offsets, pts) = points(&mesh);
        let mut op = UpwindTransport::new(&mesh, &offsets, true).unwrap();
        let ones = vec![1.0; pts.len()];
        let mut t1 = vec![0.0; pts.len()];
        op.apply_transport(&ones, &mut t1);
        let worst = t1.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(worst < 1e-11, "T 1 = {worst}");
        for omega in [0.0, 0.5, 40.0] {
            let mut y = vec![2.0; pts.len()];
            op.solve(omega, &[TAU, 3.0], 1, &mut y).unwrap();
            let worst = y.iter().fold(0.0f64, |m, v| m.max((v - 6.0).abs()));
            assert!(worst < 1e-9, "omega {omega}: {worst}");
        }
    }
}

/// The iterative solve (GMRES preconditioned with one block sweep in flow order, for memories
/// shorter than a third of a revolution) and the sparse LU give the same solution, on every
/// kind of mesh and in both directions; a long memory goes to the LU directly.
#[test]
fn iterative_and_direct_solves_agree() {
    let base = twisted_mesh(2, 16, 2);
    let mut forest = Forest::new(base.clone()).unwrap();
    forest.refine(&[0, 3, 7]).unwrap();
    let (hanging, _) = forest.mesh();
    for mesh in [ring_mesh(3, 32, 2), twisted_mesh(3, 32, 1), hanging] {
        let (offsets, pts) = points(&mesh);
        for omega in [1.5, -1.5] {
            let mut op = UpwindTransport::new(&mesh, &offsets, omega > 0.0).unwrap();
            let taus = [0.05, 1.0, 50.0];
            for term in 0..3 {
                let s: Vec<f64> = pts.iter().map(|&(x, y, _)| source(omega, x, y)).collect();
                let (mut a, mut b) = (s.clone(), s);
                op.solve(omega, &taus, term, &mut a).unwrap();
                let its = op.last_iterations;
                op.solve_direct(omega, &taus, term, &mut b).unwrap();
                let d = a
                    .iter()
                    .zip(&b)
                    .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
                let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                println!(
                    "omega {omega}, tau {}: {its} products, max diff {:.1e}",
                    taus[term],
                    d / scale
                );
                assert!(d < 1e-10 * scale, "{d} vs {scale}");
                // Short memories iterate (a handful of products), long ones take the LU.
                if omega.abs() * taus[term] < 2.0 {
                    assert!((1..=30).contains(&its), "{its}");
                } else {
                    assert_eq!(its, 0);
                }
            }
            assert_eq!(op.lu_fallbacks, 0);
        }
    }
}
