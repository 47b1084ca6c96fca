//! A posteriori error estimators on the finite-strain solid: they vanish on fields the
//! discretisation represents exactly, and on the spinning neo-Hookean annulus (exact
//! axisymmetric solution, computed independently by shooting on the radial equilibrium ODE)
//! the recovery and interpolation estimators are asymptotically exact and the explicit residual
//! estimator keeps a bounded effectivity, with the energy error falling like h^p.

mod common;

use common::reference::{neo_hookean_omega_for_growth, neo_hookean_radial, RadialSolution};
use tread::app::build_system;
use tread::driver::spinning::solve_spinning;
use tread::math::{Mat2, Vec2};
use tread::model::SolidSystem;
use tread::physics::estimate::{
    energy_error, energy_norm, explicit_residual, interpolation, recovery,
};
use tread::solver::stepping::{StepOptions, StepReport};
use tread::solver::{LinearKind, NewtonOptions};

const NEO: &str = "model = \"neo_hookean\"\nmu = 200.0\nlambda = 1800.0";
const MR: &str = "model = \"mooney_rivlin\"\nc1 = 80.0\nc2 = 20.0\nkappa = 2000.0";

fn system(material: &str, mesh: &str) -> SolidSystem {
    build_system(&common::spinning_scene(material, mesh)).expect("system")
}

/// The system on isoparametric cells (which represent u = H X exactly) at u = H X.
fn homogeneous(material: &str, mesh: &str, h: &Mat2) -> SolidSystem {
    let mut sys = system(material, mesh);
    sys.model.mesh.make_isoparametric();
    for (n, x) in sys.model.mesh.nodes.iter().enumerate() {
        let u = h * x;
        sys.x[2 * n] = u[0];
        sys.x[2 * n + 1] = u[1];
    }
    sys
}

fn solve(sys: &mut SolidSystem, omega: f64) {
    let mut rep = StepReport::default();
    let opts = NewtonOptions {
        tol: 1e-11,
        max_iterations: 30,
        ..Default::default()
    };
    let so = StepOptions {
        initial_steps: 4,
        max_cutbacks: 8,
        verbose: false,
    };
    solve_spinning(
        sys,
        omega,
        LinearKind::Cholesky,
        opts,
        &so,
        &mut rep,
        &mut (),
    )
    .expect("spinning solve converges");
}

/// Exact displacement gradient of the axisymmetric solution at reference position X:
/// H = (r′ − 1) e_R ⊗ e_R + (u/R) e_Θ ⊗ e_Θ.
fn exact_gradient(sol: &RadialSolution, x: Vec2) -> Mat2 {
    let r = x.norm();
    let (c, s) = (x[0] / r, x[1] / r);
    let hr = sol.radial_stretch(r) - 1.0;
    let ht = sol.u(r) / r;
    Mat2::new(
        hr * c * c + ht * s * s,
        (hr - ht) * c * s,
        (hr - ht) * c * s,
        hr * s * s + ht * c * c,
    )
}

/// u = H X, no body force, no spin, no free faces: no residual, no jump, exact recovery. On Q1
/// and Q2 annuli (isoparametric: they represent u = H X exactly), one cell thick too, with a
/// compressible and a nearly incompressible law.
#[test]
fn estimators_vanish_on_a_homogeneous_deformation() {
    let h = Mat2::new(0.05, 0.02, -0.01, -0.03);
    for material in [NEO, MR] {
        for mesh in [
            "n_r = 2\nn_theta = 16\norder = 1",
            "n_r = 2\nn_theta = 16\norder = 2",
            "n_r = 1\nn_theta = 8\norder = 2",
        ] {
            let sys = homogeneous(material, mesh, &h);
            let norm = energy_norm(&sys.model, &sys.dofs, &sys.x);
            let zz = recovery(&sys.model, &sys.dofs, &sys.x).global / norm;
            let ex = explicit_residual(&sys.model, &sys.dofs, &sys.x, &[]).global / norm;
            let exact = energy_error(&sys.model, &sys.dofs, &sys.x, &|_| h).global / norm;
            let ip = interpolation(&sys.model, &sys.dofs, &sys.x).global / norm;
            assert!(ip < 1e-8, "interpolation estimator {ip:.3e}");
            eprintln!(
                "{}: ZZ {zz:.2e}, explicit {ex:.2e}, error {exact:.2e}",
                mesh.replace('\n', " ")
            );
            assert!(norm > 1.0, "energy norm {norm}");
            assert!(zz < 1e-10, "recovery estimator {zz:.3e}");
            assert!(ex < 1e-7, "explicit residual estimator {ex:.3e}");
            assert!(exact < 1e-12, "exact error {exact:.3e}");
            // With the outer surface declared free, its (non-zero) traction is a residual.
            let ex_free =
                explicit_residual(&sys.model, &sys.dofs, &sys.x, &["outer"]).global / norm;
            assert!(
                ex_free > 1e-2,
                "free-surface traction residual {ex_free:.3e}"
            );
        }
    }
}

/// Effectivity indices η / ‖e‖_A on the spinning annulus (outer radius grown by 5 %), Q1 and
/// Q2 meshes refined uniformly, against the exact solution.
#[test]
fn effectivity_on_the_spinning_annulus() {
    let omega = neo_hookean_omega_for_growth(1.0, 2.0, 1800.0, 200.0, 0.027, 0.05).expect("omega");
    let sol = neo_hookean_radial(1.0, 2.0, 1800.0, 200.0, 0.027, omega).expect("reference");
    for (order, sizes) in [(1usize, [4usize, 8, 16, 32]), (2, [2, 4, 8, 16])] {
        // (h ∝ 1/n_r, DOFs, error, ZZ effectivity, explicit effectivity)
        let mut rows: Vec<(usize, usize, f64, f64, f64)> = Vec::new();
        let mut interp: Vec<f64> = Vec::new();
        for n_r in sizes {
            let mut sys = system(
                NEO,
                &format!("n_r = {n_r}\nn_theta = {}\norder = {order}", 8 * n_r),
            );
            solve(&mut sys, omega);
            let err =
                energy_error(&sys.model, &sys.dofs, &sys.x, &|x| exact_gradient(&sol, x)).global;
            let zz = recovery(&sys.model, &sys.dofs, &sys.x).global;
            let ex = explicit_residual(&sys.model, &sys.dofs, &sys.x, &["outer"]).global;
            let ip = interpolation(&sys.model, &sys.dofs, &sys.x).global;
            eprintln!("    interpolation estimator effectivity {:.4}", ip / err);
            interp.push(ip / err);
            rows.push((n_r, sys.n_dofs(), err, zz / err, ex / err));
        }
        eprintln!("Q{order}: n_r  DOFs  ‖e‖_A  rate  ZZ eff  explicit eff");
        for (i, r) in rows.iter().enumerate() {
            let rate = if i == 0 {
                f64::NAN
            } else {
                -(r.2 / rows[i - 1].2).ln() / (r.0 as f64 / rows[i - 1].0 as f64).ln()
            };
            eprintln!(
                "    {:3} {:6} {:.3e} {rate:5.2} {:.4} {:.4}",
                r.0, r.1, r.2, r.3, r.4
            );
        }
        let n = rows.len();
        let rate = |a: usize, b: usize| {
            -(rows[b].2 / rows[a].2).ln() / (rows[b].0 as f64 / rows[a].0 as f64).ln()
        };
        // Measured: Q1 1.01, 1.00, 1.00; Q2 1.84, 1.95, 1.98.
        let r = rate(n - 3, n - 1);
        assert!(
            (r - order as f64).abs() < 0.1,
            "Q{order}: energy-error rate {r:.3}"
        );
        // Recovery: asymptotically exact. Measured: Q1 0.980 → 0.9995, Q2 1.166 → 0.990.
        let last = rows[n - 1].3;
        assert!(
            (last - 1.0).abs() < 0.02,
            "Q{order}: ZZ effectivity {last:.4}"
        );
        assert!(
            (last - 1.0).abs() < (rows[n - 2].3 - 1.0).abs(),
            "Q{order}: ZZ effectivity not improving"
        );
        // Interpolation estimator (recovered derivatives): asymptotically exact too.
        // Measured: Q1 0.934, 0.982, 0.995, 0.999; Q2 1.125, 0.873, 0.964, 0.991.
        let il = interp[n - 1];
        assert!(
            (il - 1.0).abs() < 0.02,
            "Q{order}: interpolation effectivity {il:.4}"
        );
        assert!((il - 1.0).abs() < (interp[n - 2] - 1.0).abs());
        // Explicit residual: its unknown constant taken as 1, the effectivity is bounded and
        // settles under refinement. Measured: Q1 18.04 → 18.78, Q2 15.33 → 13.99.
        let eff: Vec<f64> = rows[n - 3..].iter().map(|r| r.4).collect();
        let (lo, hi) = eff
            .iter()
            .fold((f64::MAX, 0.0f64), |(a, b), &v| (a.min(v), b.max(v)));
        assert!(
            lo > 1.0,
            "Q{order}: explicit estimator below the error: {lo:.3}"
        );
        assert!(
            hi / lo < 1.05,
            "Q{order}: explicit effectivity varies {lo:.3}..{hi:.3}"
        );
    }
}

/// On an unstructured Gmsh annulus (isoparametric Q1 and Q2 cells, no rings) the recovery
/// estimator stays close to the error of the exact axisymmetric solution.
#[test]
fn recovery_effectivity_on_gmsh_meshes() {
    let omega = neo_hookean_omega_for_growth(1.0, 2.0, 1800.0, 200.0, 0.027, 0.05).expect("omega");
    let sol = neo_hookean_radial(1.0, 2.0, 1800.0, 200.0, 0.027, omega).expect("reference");
    for file in ["annulus_q1.msh", "annulus_q2.msh"] {
        let mut sys = system(
            NEO,
            &format!(
                "file = \"{}/tests/gmsh_data/{file}\"",
                env!("CARGO_MANIFEST_DIR")
            ),
        );
        solve(&mut sys, omega);
        let err = energy_error(&sys.model, &sys.dofs, &sys.x, &|x| exact_gradient(&sol, x)).global;
        let zz = recovery(&sys.model, &sys.dofs, &sys.x).global;
        let ex = explicit_residual(&sys.model, &sys.dofs, &sys.x, &["outer"]).global;
        eprintln!(
            "{file}: {} DOFs, ‖e‖_A {err:.3e}, ZZ eff {:.4}, explicit eff {:.3}",
            sys.n_dofs(),
            zz / err,
            ex / err
        );
        assert!(
            (0.7..1.3).contains(&(zz / err)),
            "{file}: ZZ effectivity {:.4}",
            zz / err
        );
        assert!(
            ex > err,
            "{file}: explicit estimate {ex:.3e} below the error {err:.3e}"
        );
    }
}

/// The equilibrated residual estimator (local Neumann problems with equilibrated tractions):
/// zero on a homogeneous deformation, non-zero when the outer surface is declared free (its
/// traction is then a residual). On the spinning annulus its bound is that of the material
/// part of the linearised operator: at a moderate speed (0.5 % growth, ρ ω² R² ≤ 0.6 μ) the
/// effectivity is about 2 or below and settles (measured Q1 2.03, 1.89, 1.81; Q2 1.33, 1.40,
/// 1.46); at 5 % growth (ρ ω² R² up to 5.9 μ: the θ-referential inertia is a large part of the
/// operator, and the local problems omit it) it still bounds the error, by a factor of 1.7–4
/// (Q1 2.71, 4.07, 2.58; Q2 1.65, 2.08, 2.60; see `physics::equilibrated`).
#[test]
fn equilibrated_estimator_bounds_the_error() {
    use tread::physics::equilibrated::equilibrated;
    let h = Mat2::new(0.05, 0.02, -0.01, -0.03);
    for material in [NEO, MR] {
        for mesh in [
            "n_r = 2\nn_theta = 16\norder = 1",
            "n_r = 1\nn_theta = 8\norder = 2",
        ] {
            let sys = homogeneous(material, mesh, &h);
            let norm = energy_norm(&sys.model, &sys.dofs, &sys.x);
            let eq = equilibrated(&sys.model, &sys.dofs, &sys.x, &[], None).global / norm;
            let eq_free =
                equilibrated(&sys.model, &sys.dofs, &sys.x, &["outer"], None).global / norm;
            eprintln!(
                "{}: equilibrated {eq:.2e}, outer free {eq_free:.2e}",
                mesh.replace('\n', " ")
            );
            assert!(eq < 1e-7, "{eq:.3e}");
            assert!(eq_free > 1e-2, "{eq_free:.3e}");
        }
    }
    for (growth, bounds) in [(0.005, (1.0, 2.1)), (0.05, (1.0, 5.0))] {
        let omega =
            neo_hookean_omega_for_growth(1.0, 2.0, 1800.0, 200.0, 0.027, growth).expect("omega");
        let sol = neo_hookean_radial(1.0, 2.0, 1800.0, 200.0, 0.027, omega).expect("reference");
        for (order, sizes) in [(1usize, [4usize, 8, 16]), (2, [2, 4, 8])] {
            for n_r in sizes {
                let mut sys = system(
                    NEO,
                    &format!("n_r = {n_r}\nn_theta = {}\norder = {order}", 8 * n_r),
                );
                solve(&mut sys, omega);
                let err = energy_error(&sys.model, &sys.dofs, &sys.x, &|x| exact_gradient(&sol, x))
                    .global;
                let eq = equilibrated(&sys.model, &sys.dofs, &sys.x, &["outer"], None);
                let eff = eq.global / err;
                eprintln!(
                    "growth {growth}: Q{order} n_r {n_r}: DOFs {}, error {err:.3e}, equilibrated effectivity {eff:.4}",
                    sys.n_dofs()
                );
                assert!(eff >= bounds.0 && eff <= bounds.1, "{eff}");
            }
        }
    }
}

/// Meshes of mixed degree (p-refinement of the forest: the outer half of the annulus raised to
/// Q2, the minimum rule at the transition): the energy error lies between those of the uniform
/// Q1 and Q2 meshes, the recovery estimator (patch fits of the patch's lowest degree) stays
/// near it, and the error falls at the Q1 rate under refinement (the inner Q1 half dominates).
/// Measured: effectivities 0.989, 0.995, 0.998 on n_r = 4, 8, 16 (640, 2560, 10240 DOFs), error
/// rate 1.00, the error 0.74 of the uniform Q1 mesh's.
#[test]
fn recovery_effectivity_on_mixed_degree_meshes() {
    use tread::mesh::Forest;
    let omega = neo_hookean_omega_for_growth(1.0, 2.0, 1800.0, 200.0, 0.027, 0.05).expect("omega");
    let sol = neo_hookean_radial(1.0, 2.0, 1800.0, 200.0, 0.027, omega).expect("reference");
    let mut rows = Vec::new();
    for n_r in [4usize, 8, 16] {
        let scene = common::spinning_scene(
            NEO,
            &format!("n_r = {n_r}\nn_theta = {}\norder = 1", 8 * n_r),
        );
        let root = tread::driver::adaptive::polar_root(&scene).expect("mesh");
        let mut forest = Forest::new(root.clone()).expect("forest");
        let outer: Vec<usize> = (0..root.n_cells())
            .filter(|&c| {
                let x = root
                    .cell_nodes(c)
                    .iter()
                    .map(|&n| root.nodes[n as usize].norm());
                x.fold(0.0, f64::max) > 1.5 + 1e-9
            })
            .collect();
        assert_eq!(
            forest.raise_degree(&outer).expect("raise"),
            root.n_cells() / 2
        );
        let (mesh, _) = forest.mesh();
        assert!(!mesh.constraints.is_empty());
        let (material, pressure) = tread::setup::build_material(&scene).expect("material");
        let model = tread::physics::SolidModel::new(mesh, material, 0.027, pressure);
        let mut sys = SolidSystem::new(model, "hub");
        solve(&mut sys, omega);
        let err = energy_error(&sys.model, &sys.dofs, &sys.x, &|x| exact_gradient(&sol, x)).global;
        let zz = recovery(&sys.model, &sys.dofs, &sys.x).global;
        // The uniform meshes of the same cells.
        let uniform = |order: usize| {
            let mut s = system(
                NEO,
                &format!("n_r = {n_r}\nn_theta = {}\norder = {order}", 8 * n_r),
            );
            solve(&mut s, omega);
            energy_error(&s.model, &s.dofs, &s.x, &|x| exact_gradient(&sol, x)).global
        };
        let (e1, e2) = (uniform(1), uniform(2));
        eprintln!(
            "n_r = {n_r}: {} DOFs, error {err:.4e} (Q1 {e1:.4e}, Q2 {e2:.4e}), ZZ effectivity {:.4}",
            sys.n_dofs(),
            zz / err
        );
        assert!(err < e1 && err > e2, "{err} not between {e2} and {e1}");
        assert!((zz / err - 1.0).abs() < 0.1, "effectivity {}", zz / err);
        rows.push((n_r as f64, err));
    }
    let rate = -(rows[2].1 / rows[0].1).ln() / (rows[2].0 / rows[0].0).ln();
    eprintln!("error rate {rate:.3}");
    assert!((rate - 1.0).abs() < 0.1, "rate {rate}");
}
