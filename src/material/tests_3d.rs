//! Every registered law in three dimensions (`Mat3`): the finite-difference check of stress and
//! tangent, major symmetry, objectivity under 3D rotations, the small-strain limit of 3D linear
//! elasticity, safety at `J ≤ 0`, and the plane-strain embedding (a 2D `∇u` with zero third row
//! and column gives the 2D in-plane stress and tangent, and `P33 = J σ33`).

use super::*;
use crate::math::{embed_plane, v, Mat3, Tangent3};

/// Every registered law with the parameters `1, 1.5, 2, …`, and the same laws with moduli
/// typical of the scenes (a stiff bulk response).
fn laws() -> Vec<Material> {
    let mut laws: Vec<Material> = MaterialKind::ALL
        .iter()
        .map(|k| {
            let values: Vec<f64> = (0..k.params().len())
                .map(|i| 1.0 + 0.5 * i as f64)
                .collect();
            k.build(&values)
        })
        .collect();
    laws.push(NeoHookean::new(1.5, 4.0).into());
    laws.push(MooneyRivlin::new(80.0, 20.0, 2000.0).into());
    laws.push(MooneyRivlinIncompressible::new(80.0, 20.0).into());
    laws.push(Yeoh::new(50.0, -2.0, 0.3, 3000.0).into());
    laws
}

/// Rotation by `theta` about the unit axis `n` (Rodrigues).
fn rotation3(n: [f64; 3], theta: f64) -> Mat3 {
    let n = crate::math::Vec3::new(n[0], n[1], n[2]).normalize();
    let k = Mat3::new(0.0, -n[2], n[1], n[2], 0.0, -n[0], -n[1], n[0], 0.0);
    Mat3::identity() + k * theta.sin() + k * k * (1.0 - theta.cos())
}

/// Moderate 3D strains with `J ∈ [0.5, 1.8]`: shear, triaxial stretch, rotations, general.
fn sample_grads_3d() -> Vec<Mat3> {
    let i = Mat3::identity();
    let stretch = Mat3::from_diagonal(&crate::math::Vec3::new(1.2, 0.8, 1.1));
    vec![
        Mat3::new(0.0, 0.3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
        Mat3::new(0.1, 0.2, -0.05, 0.15, -0.1, 0.3, 0.02, 0.07, 0.2),
        Mat3::new(-0.3, 0.05, 0.1, 0.1, -0.1, 0.0, 0.05, -0.08, -0.15),
        Mat3::new(0.25, -0.1, 0.05, 0.2, 0.2, 0.1, -0.1, 0.05, 0.15),
        Mat3::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -0.35),
        rotation3([1.0, 2.0, -0.5], 0.9) * stretch - i,
        rotation3([0.3, -1.0, 2.0], -2.4) * Mat3::new(1.0, 0.4, 0.2, 0.0, 1.0, 0.3, 0.0, 0.0, 1.0)
            - i,
        rotation3([0.0, 0.0, 1.0], 1.0) - i,
        rotation3([1.0, 1.0, 1.0], 2.0) - i,
    ]
}

#[test]
fn samples_3d_cover_the_requested_range() {
    let js: Vec<f64> = sample_grads_3d()
        .iter()
        .map(|g| (Mat3::identity() + g).determinant())
        .collect();
    assert!(js.iter().all(|j| (0.5..=1.8).contains(j)), "{js:?}");
    assert!(js.iter().any(|j| *j < 0.7) && js.iter().any(|j| *j > 1.3));
}

#[test]
fn every_law_passes_the_3d_finite_difference_check() {
    for m in laws() {
        let mut worst = (0.0_f64, 0.0_f64);
        for g in sample_grads_3d() {
            let r = check_material(&m, &g);
            assert!(r.stress_rel_err < 1e-6, "{m:?}: stress FD at {g}: {r:?}");
            assert!(r.tangent_rel_err < 1e-6, "{m:?}: tangent FD at {g}: {r:?}");
            worst = (
                worst.0.max(r.stress_rel_err),
                worst.1.max(r.tangent_rel_err),
            );
            let a = m.stress_tangent(&g).1;
            let asym = (a - a.transpose()).norm() / a.norm();
            assert!(asym < 1e-12, "{m:?}: asymmetry {asym} at {g}");
        }
        println!(
            "{}: 3D fd stress {:.2e}, tangent {:.2e}",
            m.name(),
            worst.0,
            worst.1
        );
    }
}

#[test]
fn every_law_is_objective_in_3d() {
    for m in laws() {
        for g in sample_grads_3d() {
            let f = Mat3::identity() + g;
            let (w, (p, a)) = (m.energy(&g), m.stress_tangent(&g));
            let (a_norm, g_norm) = (a.norm(), g.norm());
            for (axis, theta) in [
                ([1.0, 0.0, 0.0], 0.3),
                ([0.2, -1.0, 0.7], -1.2),
                ([1.0, 1.0, 1.0], 2.9),
            ] {
                let q = rotation3(axis, theta);
                let gq = q * f - Mat3::identity();
                let (wq, (pq, aq)) = (m.energy(&gq), m.stress_tangent(&gq));
                // R[(i,J), (a,K)] = Q_ia δ_JK rotates the first index of each pair.
                let mut r = Tangent3::zeros();
                for i in 0..3 {
                    for k in 0..3 {
                        for jj in 0..3 {
                            r[(3 * i + jj, 3 * k + jj)] = q[(i, k)];
                        }
                    }
                }
                let ew = (wq - w).abs() / w.abs().max(a_norm * g_norm * g_norm);
                let ep = (pq - q * p).norm() / p.norm().max(a_norm * g_norm);
                let ea = (aq - r * a * r.transpose()).norm() / a_norm;
                assert!(
                    ew < 1e-12 && ep < 1e-12 && ea < 1e-12,
                    "{m:?} at {g}: {ew} {ep} {ea}"
                );
            }
        }
    }
}

#[test]
fn compressible_laws_reach_3d_linear_elasticity_at_small_strain() {
    for m in laws() {
        let gmod = m.small_strain_shear_modulus();
        let Some(kmod) = m.small_strain_bulk_modulus() else {
            continue;
        };
        let lambda = kmod - 2.0 / 3.0 * gmod;
        let zero = Mat3::zeros();
        assert_eq!(m.stress(&zero), zero, "{m:?}");
        assert_eq!(m.energy(&zero), 0.0, "{m:?}");
        // A_iJkL = λ δ_iJ δ_kL + G (δ_ik δ_JL + δ_iL δ_Jk), built independently of the law.
        let mut al = Tangent3::zeros();
        for i in 0..3 {
            for jj in 0..3 {
                for k in 0..3 {
                    for l in 0..3 {
                        let d = |a: usize, b: usize| if a == b { 1.0 } else { 0.0 };
                        al[(3 * i + jj, 3 * k + l)] = lambda * d(i, jj) * d(k, l)
                            + gmod * (d(i, k) * d(jj, l) + d(i, l) * d(jj, k));
                    }
                }
            }
        }
        let a0 = m.stress_tangent(&zero).1;
        assert!((a0 - al).norm() < 1e-12 * al.norm(), "{m:?}: A(0) = {a0}");
        let shape = Mat3::new(0.3, -0.7, 0.4, 0.9, -0.2, 0.1, 0.5, 0.6, -1.0);
        for (scale, tol) in [(1e-8, 1e-6), (1e-12, 1e-9)] {
            let g = shape * scale;
            let eps = (g + g.transpose()) * 0.5;
            let lin = Mat3::identity() * (lambda * eps.trace()) + eps * (2.0 * gmod);
            for p in [m.stress(&g), m.stress_tangent(&g).0] {
                let e = (p - lin).norm() / lin.norm();
                assert!(e < tol, "{m:?}: small strain {scale}: rel err {e}");
            }
        }
    }
}

#[test]
fn every_law_is_safe_at_inadmissible_3d_states() {
    for m in laws() {
        for g in [
            Mat3::new(-1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
            Mat3::new(-2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
            Mat3::new(-1.5, 0.2, 0.1, -0.4, 3.0, 0.0, 0.3, 0.0, 0.2),
            Mat3::repeat(f64::NAN),
        ] {
            assert_eq!(m.energy(&g), f64::INFINITY, "{m:?} at {g}");
            let p = m.stress(&g);
            let (p2, a) = m.stress_tangent(&g);
            assert!(!p
                .iter()
                .chain(p2.iter())
                .chain(a.iter())
                .any(|x| x.is_nan()));
        }
    }
}

#[test]
fn plane_strain_is_the_3d_law_with_zero_third_row_and_column() {
    for m in laws() {
        for g in test_util::sample_grads() {
            let g3 = embed_plane(&g);
            let (w2, w3) = (m.energy(&g), m.energy(&g3));
            assert!(
                (w2 - w3).abs() <= 1e-14 * w2.abs().max(1.0),
                "{m:?}: W {w2} {w3}"
            );
            let (p2, a2) = m.stress_tangent(&g);
            let (p3, a3) = m.stress_tangent(&g3);
            let (ps, as_) = (p2.norm().max(1.0), a2.norm());
            for i in 0..2 {
                for jj in 0..2 {
                    assert!(
                        (p2[(i, jj)] - p3[(i, jj)]).abs() < 1e-13 * ps,
                        "{m:?}: P{i}{jj}"
                    );
                    assert!(p3[(i, 2)].abs() < 1e-13 * ps && p3[(2, i)].abs() < 1e-13 * ps);
                    for k in 0..2 {
                        for l in 0..2 {
                            let d = a2[(v(i, jj), v(k, l))] - a3[(3 * i + jj, 3 * k + l)];
                            assert!(d.abs() < 1e-12 * as_, "{m:?}: A{i}{jj}{k}{l}");
                        }
                    }
                }
            }
            let j = (Mat2::identity() + g).determinant();
            let s33 = m.cauchy_33(&g);
            assert!(
                (p3[(2, 2)] - j * s33).abs() < 1e-12 * ps,
                "{m:?}: P33 {} J σ33 {}",
                p3[(2, 2)],
                j * s33
            );
        }
    }
}

#[test]
fn pressure_terms_in_3d_against_finite_differences() {
    // −p (J − 1): stress −p cof F and tangent −p ∂cof/∂F, checked against J − 1 itself.
    let p = 2.5;
    for g in sample_grads_3d() {
        let (s, a) = pressure_stress_tangent(&g, p);
        let step = 1e-5;
        for k in 0..3 {
            for l in 0..3 {
                let mut e = Mat3::zeros();
                e[(k, l)] = step;
                let djm1 =
                    (incompressible::jm1(&(g + e)) - incompressible::jm1(&(g - e))) / (2.0 * step);
                assert!((s[(k, l)] + p * djm1).abs() < 1e-8, "{g}");
                let ds = (pressure_stress_tangent(&(g + e), p).0
                    - pressure_stress_tangent(&(g - e), p).0)
                    / (2.0 * step);
                for i in 0..3 {
                    for jj in 0..3 {
                        assert!((a[(3 * i + jj, 3 * k + l)] - ds[(i, jj)]).abs() < 1e-8);
                    }
                }
            }
        }
    }
}
