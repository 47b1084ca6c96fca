//! The assembled global tangent equals central finite differences of the assembled residual on
//! a tiny mesh, for every material and pressure treatment, with spin (ω ≠ 0) and a body force;
//! serial and parallel assembly agree; Newton converges quadratically.

use tread::assembly::FIXED;
use tread::driver::SolidSystem;
use tread::material::{Material, MooneyRivlin, MooneyRivlinIncompressible, NeoHookean};
use tread::math::Vec2;
use tread::mesh::{annulus, AnnulusSpec};
use tread::physics::{PressureMode, SolidModel};
use tread::solver::NonlinearSystem;

fn tiny(order: usize, material: Material, pressure: PressureMode) -> SolidSystem {
    let mesh = annulus(&AnnulusSpec {
        ri: 1.0,
        ro: 2.0,
        n_r: 2,
        n_theta: 8,
        degree: order,
        grading_r: 1.5,
        grading_theta: 0.3,
    });
    let mut model = SolidModel::new(mesh, material, 0.8, pressure);
    model.omega2 = 3.0;
    model.body_force = Some(Box::new(|x: Vec2| {
        Vec2::new(0.3 * x[1], -0.2 * x[0] * x[0])
    }));
    let mut sys = SolidSystem::new(model, "hub");
    // A smooth, non-trivial admissible state (|∇u| ~ 0.1) and perturbed pressures.
    for n in 0..sys.model.mesh.n_nodes() {
        let x = sys.model.mesh.nodes[n];
        if sys.dofs.eq[2 * n] != FIXED {
            sys.x[2 * n] += 0.05 * (x[0] * 1.3).sin() + 0.02 * x[1];
            sys.x[2 * n + 1] += 0.04 * (x[1] * 0.9).cos() * x[0];
        }
    }
    for d in sys.dofs.n_u..sys.dofs.n_full() {
        sys.x[d] += 3.0 * ((d as f64) * 0.37).sin();
    }
    sys
}

fn residual(sys: &mut SolidSystem) -> Vec<f64> {
    assert!(sys.evaluate(false));
    sys.residual().to_vec()
}

/// max |K − K_fd| / max |K|.
fn fd_error(sys: &mut SolidSystem) -> f64 {
    assert!(sys.evaluate(true));
    let k = sys.asm.to_dense();
    let n = sys.n_eq();
    let kmax = k.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut err = 0.0f64;
    let mut e = vec![0.0; n];
    for j in 0..n {
        let h = 1e-6;
        e.fill(0.0);
        e[j] = h;
        sys.update(1.0, &e);
        let rp = residual(sys);
        sys.update(-2.0, &e);
        let rm = residual(sys);
        sys.update(1.0, &e);
        for i in 0..n {
            let fd = (rp[i] - rm[i]) / (2.0 * h);
            err = err.max((fd - k[i][j]).abs());
        }
    }
    err / kmax
}

#[test]
fn tangent_matches_finite_differences() {
    let cases: Vec<(&str, usize, Material, PressureMode)> = vec![
        (
            "neo-Hookean Q2",
            2,
            NeoHookean::new(2.0, 5.0).into(),
            PressureMode::None,
        ),
        (
            "neo-Hookean Q1",
            1,
            NeoHookean::new(2.0, 5.0).into(),
            PressureMode::None,
        ),
        (
            "Mooney-Rivlin Q2",
            2,
            MooneyRivlin::new(0.8, 0.2, 10.0).into(),
            PressureMode::None,
        ),
        (
            "incompressible exact Q2/P1",
            2,
            MooneyRivlinIncompressible::new(0.8, 0.2).into(),
            PressureMode::Exact { p0: 2.4 },
        ),
        (
            "incompressible perturbed Q2/P1",
            2,
            MooneyRivlinIncompressible::new(0.8, 0.2).into(),
            PressureMode::Perturbed {
                kappa: 50.0,
                p0: 2.4,
            },
        ),
    ];
    for (name, order, mat, pm) in cases {
        let mut sys = tiny(order, mat, pm);
        let err = fd_error(&mut sys);
        eprintln!(
            "{name}: n_eq = {}, max|K − K_fd|/max|K| = {err:.2e}",
            sys.n_eq()
        );
        assert!(
            err < 1e-7,
            "{name}: tangent differs from FD of the residual by {err:.3e}"
        );
    }
}

#[test]
fn serial_and_parallel_assembly_agree() {
    let mut sys = tiny(
        2,
        MooneyRivlinIncompressible::new(0.8, 0.2).into(),
        PressureMode::Exact { p0: 2.4 },
    );
    sys.asm.parallel = false;
    assert!(sys.evaluate(true));
    let (r1, k1) = (sys.residual().to_vec(), sys.matrix_values().to_vec());
    sys.asm.parallel = true;
    assert!(sys.evaluate(true));
    let (r2, k2) = (sys.residual().to_vec(), sys.matrix_values().to_vec());
    let dr = r1
        .iter()
        .zip(&r2)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let dk = k1
        .iter()
        .zip(&k2)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let sk = k1.iter().map(|a| a.abs()).fold(0.0, f64::max);
    assert!(
        dr < 1e-12 && dk < 1e-12 * sk,
        "serial/parallel differ: {dr:.2e} {dk:.2e}"
    );
}

#[test]
fn tangent_is_symmetric_without_friction() {
    let mut sys = tiny(2, NeoHookean::new(2.0, 5.0).into(), PressureMode::None);
    assert!(sys.evaluate(true));
    let k = sys.asm.to_dense();
    let n = k.len();
    let kmax = k.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    for i in 0..n {
        for j in 0..n {
            assert!((k[i][j] - k[j][i]).abs() <= 1e-12 * kmax);
        }
    }
}
