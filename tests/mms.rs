//! Manufactured solution for the nonlinear (neo-Hookean) solid on the annulus: observed
//! convergence rates in L2 and the H1 seminorm for Q2 (3, 2) and Q1 (2, 1).
//!
//! u = a (sin X1 cos(X2/2), cos(0.7 X1) sin X2), a = 0.1 (strains up to ~10 %, nonlinear
//! regime). The body force is b = −Div P(∇u) = −A_iJkL u_k,JL, computed with the material's
//! tangent (itself verified against finite differences of the energy). Dirichlet data on both
//! the hub and the outer surface by nodal interpolation.

use nalgebra::{Matrix2, Vector2};
use tread::material::{Hyperelastic, Material, NeoHookean};
use tread::math::v;
use tread::mesh::{annulus, AnnulusSpec, Forest};
use tread::model::SolidSystem;
use tread::physics::{PressureMode, SolidModel};
use tread::solver::{LinearKind, Newton, NewtonOptions};

const A: f64 = 0.1;

fn exact_u(x: Vector2<f64>) -> Vector2<f64> {
    let (x1, x2) = (x[0], x[1]);
    Vector2::new(
        A * x1.sin() * (0.5 * x2).cos(),
        A * (0.7 * x1).cos() * x2.sin(),
    )
}

fn exact_grad(x: Vector2<f64>) -> Matrix2<f64> {
    let (x1, x2) = (x[0], x[1]);
    Matrix2::new(
        A * x1.cos() * (0.5 * x2).cos(),
        -0.5 * A * x1.sin() * (0.5 * x2).sin(),
        -0.7 * A * (0.7 * x1).sin() * x2.sin(),
        A * (0.7 * x1).cos() * x2.cos(),
    )
}

/// Second derivatives: hess[k][J][L] = ∂² u_k / ∂X_J ∂X_L.
fn exact_hess(x: Vector2<f64>) -> [[[f64; 2]; 2]; 2] {
    let (x1, x2) = (x[0], x[1]);
    let u1_11 = -A * x1.sin() * (0.5 * x2).cos();
    let u1_12 = -0.5 * A * x1.cos() * (0.5 * x2).sin();
    let u1_22 = -0.25 * A * x1.sin() * (0.5 * x2).cos();
    let u2_11 = -0.49 * A * (0.7 * x1).cos() * x2.sin();
    let u2_12 = -0.7 * A * (0.7 * x1).sin() * x2.cos();
    let u2_22 = -A * (0.7 * x1).cos() * x2.sin();
    [
        [[u1_11, u1_12], [u1_12, u1_22]],
        [[u2_11, u2_12], [u2_12, u2_22]],
    ]
}

fn errors(order: usize, n_r: usize, iso: bool) -> (f64, f64, usize) {
    errors_on(order, n_r, iso, false)
}

/// As [`errors`]; with `refine_quadrant`, the cells of the quadrant x1, x2 > 0 are split once
/// more (non-conforming: hanging nodes on the quadrant's edges, constrained to the coarse sides).
fn errors_on(order: usize, n_r: usize, iso: bool, refine_quadrant: bool) -> (f64, f64, usize) {
    let sys = solved(order, n_r, iso, refine_quadrant);
    // Errors with a 5×5 Gauss rule per cell.
    let (pts, ws) = tread::element::gauss_1d(5);
    let (mut l2, mut h1) = (0.0, 0.0);
    for c in 0..sys.model.mesh.n_cells() {
        for (i, xi) in pts.iter().enumerate() {
            for (j, eta) in pts.iter().enumerate() {
                let pv = sys
                    .model
                    .point_values(c, &sys.dofs, &sys.x, *xi, *eta)
                    .expect("point");
                let w = ws[i] * ws[j] * pv.jac.determinant();
                l2 += (pv.u - exact_u(pv.x)).norm_squared() * w;
                h1 += (pv.grad_u - exact_grad(pv.x)).norm_squared() * w;
            }
        }
    }
    (l2.sqrt(), h1.sqrt(), sys.n_dofs())
}

/// The converged discrete solution of the manufactured problem on the n_r × 8 n_r annulus.
fn solved(order: usize, n_r: usize, iso: bool, refine_quadrant: bool) -> SolidSystem {
    let mut mesh = annulus(&AnnulusSpec {
        ri: 1.0,
        ro: 2.0,
        n_r,
        n_theta: 8 * n_r,
        degree: order,
        grading_r: 1.0,
        grading_theta: 0.0,
    });
    if iso {
        mesh.make_isoparametric();
    }
    if refine_quadrant {
        let mut forest = Forest::new(mesh).expect("forest");
        let marked: Vec<usize> = (0..forest.leaves().len())
            .filter(|&c| {
                let x = forest.root_point(c, 0.0, 0.0);
                x[0] > 0.0 && x[1] > 0.0
            })
            .collect();
        forest.refine(&marked).expect("refine");
        mesh = forest.mesh().0;
        assert!(!mesh.constraints.is_empty());
    }
    let mat = Material::NeoHookean(NeoHookean::new(1.0, 2.0));
    let mut model = SolidModel::new(mesh, mat, 1.0, PressureMode::None);
    let mb = mat;
    model.body_force = Some(Box::new(move |x| {
        let (_, at) = mb.stress_tangent(&exact_grad(x));
        let h = exact_hess(x);
        let mut b = Vector2::zeros();
        for i in 0..2 {
            for jj in 0..2 {
                for k in 0..2 {
                    for l in 0..2 {
                        b[i] -= at[(v(i, jj), v(k, l))] * h[k][jj][l];
                    }
                }
            }
        }
        b
    }));
    let mut fixed: Vec<u32> = model.mesh.node_set("hub").to_vec();
    fixed.extend_from_slice(model.mesh.node_set("outer"));
    let mut sys = SolidSystem::with_fixed_nodes(model, &fixed);
    // Dirichlet data (hub and outer nodes) and the initial guess: the nodal interpolant of the
    // exact solution. The discrete solution is defined by the equations, not by the start.
    for n in 0..sys.model.mesh.n_nodes() {
        let ue = exact_u(sys.model.mesh.nodes[n]);
        sys.x[2 * n] = ue[0];
        sys.x[2 * n + 1] = ue[1];
    }
    sys.set_reference_force(1e-3);
    let opts = NewtonOptions {
        tol: 1e-12,
        max_iterations: 30,
        ..Default::default()
    };
    let mut newton = Newton::new(&sys, LinearKind::Cholesky, opts).expect("solver");
    let rep = newton.solve(&mut sys).expect("Newton converges");
    assert!(
        rep.iterations <= 8,
        "too many Newton iterations: {}",
        rep.iterations
    );
    sys
}

fn rates(order: usize, levels: &[usize], iso: bool) -> Vec<(f64, f64)> {
    let errs: Vec<(f64, f64, usize)> = levels.iter().map(|&n| errors(order, n, iso)).collect();
    for (n, e) in levels.iter().zip(&errs) {
        eprintln!(
            "Q{order} n_r={n:3} dofs={:6} L2={:.4e} H1={:.4e}",
            e.2, e.0, e.1
        );
    }
    errs.windows(2)
        .map(|w| ((w[0].0 / w[1].0).log2(), (w[0].1 / w[1].1).log2()))
        .collect()
}

#[test]
fn q2_rates_l2_3_h1_2() {
    let r = rates(2, &[2, 4, 8, 16], false);
    eprintln!("Q2 observed rates (L2, H1): {r:?}");
    let (l2, h1) = *r.last().unwrap();
    assert!((l2 - 3.0).abs() <= 0.15, "Q2 L2 rate {l2}");
    assert!((h1 - 2.0).abs() <= 0.15, "Q2 H1 rate {h1}");
}

#[test]
fn q1_rates_l2_2_h1_1() {
    let r = rates(1, &[4, 8, 16, 32], false);
    eprintln!("Q1 observed rates (L2, H1): {r:?}");
    let (l2, h1) = *r.last().unwrap();
    assert!((l2 - 2.0).abs() <= 0.15, "Q1 L2 rate {l2}");
    assert!((h1 - 1.0).abs() <= 0.15, "Q1 H1 rate {h1}");
}

#[test]
fn q2_isoparametric_rates_l2_3_h1_2() {
    // The program's default cells: nodes on the exact circles, isoparametric map in between
    // (geometry error O(h³) does not spoil the rates).
    let r = rates(2, &[2, 4, 8, 16], true);
    eprintln!("Q2 isoparametric observed rates (L2, H1): {r:?}");
    let (l2, h1) = *r.last().unwrap();
    assert!((l2 - 3.0).abs() <= 0.15, "Q2 iso L2 rate {l2}");
    assert!((h1 - 2.0).abs() <= 0.15, "Q2 iso H1 rate {h1}");
}

#[test]
fn q2_rates_unchanged_by_non_conforming_refinement() {
    // One quadrant refined once more at every level: hanging nodes on its edges, constrained to
    // the coarse sides; the rates stay those of Q2 and the errors do not grow.
    let levels = [2, 4, 8];
    let refined: Vec<(f64, f64, usize)> = levels
        .iter()
        .map(|&n| errors_on(2, n, false, true))
        .collect();
    let uniform: Vec<(f64, f64, usize)> = levels.iter().map(|&n| errors(2, n, false)).collect();
    for (n, (r, u)) in levels.iter().zip(refined.iter().zip(&uniform)) {
        eprintln!(
            "Q2 n_r={n}: refined quadrant dofs={} L2={:.4e} H1={:.4e}; uniform dofs={} L2={:.4e} H1={:.4e}",
            r.2, r.0, r.1, u.2, u.0, u.1
        );
        assert!(
            r.2 > u.2 && r.0 <= u.0 && r.1 <= u.1,
            "refinement made it worse"
        );
    }
    let k = refined.len() - 1;
    let (l2, h1) = (
        (refined[k - 1].0 / refined[k].0).log2(),
        (refined[k - 1].1 / refined[k].1).log2(),
    );
    eprintln!("Q2 with hanging nodes: observed rates L2 {l2:.3}, H1 {h1:.3}");
    assert!((l2 - 3.0).abs() <= 0.15, "Q2 L2 rate {l2}");
    assert!((h1 - 2.0).abs() <= 0.15, "Q2 H1 rate {h1}");
}

/// The equilibrated residual estimator (local Neumann problems with equilibrated tractions) on
/// the manufactured solution, isoparametric Q1 and Q2 annuli refined uniformly: an upper bound
/// of the energy error of the linearised problem, with an effectivity in [1, 2] that settles
/// (measured Q1 1.09, 1.15, 1.18, 1.20; Q2 1.50, 1.48, 1.36, 1.26), and the error's rate; and
/// the same with hanging nodes (the nodal interpolant of the exact solution, the start, is not
/// consistent with the hanging-node constraints: the assembly makes it so).
#[test]
fn equilibrated_estimator_bounds_the_manufactured_error() {
    use tread::physics::equilibrated::equilibrated;
    use tread::physics::estimate::energy_error;
    for (order, levels) in [(1usize, [2usize, 4, 8, 16]), (2, [2, 4, 8, 16])] {
        let mut rows = Vec::new();
        for n_r in levels {
            let sys = solved(order, n_r, true, false);
            let err = energy_error(&sys.model, &sys.dofs, &sys.x, &exact_grad).global;
            let eta = equilibrated(&sys.model, &sys.dofs, &sys.x, &[], None).global;
            eprintln!(
                "Q{order} n_r {n_r}: {} DOFs, energy error {err:.4e}, estimate {eta:.4e}, effectivity {:.3}",
                sys.n_dofs(),
                eta / err
            );
            rows.push((err, eta));
        }
        for &(err, eta) in &rows {
            let eff = eta / err;
            assert!((1.0..=2.0).contains(&eff), "Q{order}: effectivity {eff}");
        }
        let n = rows.len();
        let rate_e = (rows[n - 2].0 / rows[n - 1].0).log2();
        let rate_eta = (rows[n - 2].1 / rows[n - 1].1).log2();
        assert!((rate_e - order as f64).abs() < 0.1, "error rate {rate_e}");
        assert!(
            (rate_eta - order as f64).abs() < 0.15,
            "estimator rate {rate_eta}"
        );
    }
    // Hanging nodes: one quadrant refined once more (big sides against two small ones).
    for (order, n_r) in [(1usize, 2usize), (1, 4), (2, 2), (2, 4), (2, 8)] {
        let sys = solved(order, n_r, false, true);
        assert!(sys.dofs.has_constraints());
        let err = energy_error(&sys.model, &sys.dofs, &sys.x, &exact_grad).global;
        let eta = equilibrated(&sys.model, &sys.dofs, &sys.x, &[], None).global;
        let eff = eta / err;
        eprintln!(
            "Q{order} n_r {n_r}, quadrant refined: {} DOFs, effectivity {eff:.3}",
            sys.n_dofs()
        );
        assert!(
            (1.0..=2.0).contains(&eff),
            "Q{order} hanging: effectivity {eff}"
        );
    }
}
