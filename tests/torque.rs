//! Torque control of the hub in the transient mode: consistent tangent of a time step with the
//! hub angle as an unknown, free rolling and braking to steady state, and load control.

use tread::app::{run, RunOptions};
use tread::contact::laws::CoulombTanh;
use tread::contact::{ContactModel, FacetRule, Friction, NormalCompliance};
use tread::driver::transient::{GenAlpha, Kinematics, Ramp, Scheme, Transient};
use tread::driver::SolidSystem;
use tread::io::Scene;
use tread::material::NeoHookean;
use tread::mesh::{annulus, AnnulusSpec};
use tread::physics::{PressureMode, SolidModel};
use tread::solver::NonlinearSystem;

fn model(n_r: usize, n_theta: usize) -> SolidModel {
    let mut mesh = annulus(&AnnulusSpec {
        ri: 1.0,
        ro: 2.0,
        n_r,
        n_theta,
        degree: 2,
        grading_r: 1.0,
        grading_theta: 0.0,
    });
    mesh.make_isoparametric();
    SolidModel::new(
        mesh,
        NeoHookean::new(200.0, 1800.0).into(),
        0.027,
        PressureMode::None,
    )
}

/// Max |K − K_fd| / max |K| of a generalized-α step under torque control (optionally also
/// under load control: both global unknowns φ and H).
fn torque_step_tangent_error(load_control: bool) -> f64 {
    let mut m = model(2, 16);
    m.strain_rate_damping = 2.0;
    let normal = NormalCompliance::new(2.0e4, 1.0, 5.0, 0.0);
    let cm = ContactModel::new(
        &m.mesh,
        1.95,
        3.0,
        normal,
        Friction::CoulombTanh(CoulombTanh::new(0.3, 0.5)),
        FacetRule::Lobatto(4),
        load_control.then_some(500.0),
    );
    let sys = SolidSystem::with_contact(m, cm);
    let kin = Kinematics {
        omega: Ramp {
            target: 10.0,
            time: 0.0,
        },
        disp: (!load_control).then_some(Ramp {
            target: 0.05,
            time: 0.0,
        }),
        h_touch: 2.0,
        load: load_control.then_some(Ramp {
            target: 500.0,
            time: 0.0,
        }),
        v0: Ramp {
            target: 3.0,
            time: 0.0,
        },
    };
    let mut tr = Transient::new(
        sys,
        Scheme::GeneralizedAlpha(GenAlpha::new(0.7)),
        kin,
        false,
    );
    tr.enable_torque_control(
        0.3,
        Ramp {
            target: -4.0,
            time: 0.0,
        },
        10.0,
    );
    let iphi = tr.hub_angle.as_ref().unwrap().iphi;
    // Committed state: rigid rotation at 10 rad/s (hub angle 0, rate 10, accel 2).
    for n in 0..tr.sys.model.mesh.n_nodes() {
        let x = tr.sys.model.mesh.nodes[n];
        tr.vn[2 * n] = -10.0 * x[1];
        tr.vn[2 * n + 1] = 10.0 * x[0];
        tr.an[2 * n] = -100.0 * x[0];
        tr.an[2 * n + 1] = -100.0 * x[1];
    }
    tr.vn[iphi] = 10.0;
    tr.an[iphi] = 2.0;
    tr.dt = 1e-3;
    // Trial state: hub angle 0.012 (not the rigid ωΔt), body rotated by ωΔt plus a smooth
    // perturbation, so that the hub cells are strained and the patch slides.
    let (s, c) = (10.0f64 * 1e-3).sin_cos();
    for n in 0..tr.sys.model.mesh.n_nodes() {
        let x0 = tr.sys.model.mesh.nodes[n];
        tr.sys.x[2 * n] = c * x0[0] - s * x0[1] - x0[0] + 1e-3 * x0[1].sin();
        tr.sys.x[2 * n + 1] = s * x0[0] + c * x0[1] - x0[1] + 1e-3 * x0[0].cos();
    }
    tr.sys.x[iphi] = 0.012;
    if load_control {
        let ih = tr.sys.dofs.global(0);
        tr.sys.x[ih] = 1.95;
    }
    let n = tr.n_eq();
    tr.update(0.0, &vec![0.0; n]); // places the hub nodes at Q(φ) X
    assert!(tr.evaluate(true));
    let in_contact = tr
        .sys
        .contact_samples()
        .iter()
        .filter(|s| s.delta > 0.0)
        .count();
    assert!(in_contact > 3, "no contact in the test state");
    let k = tr.sys.asm.to_dense();
    let kmax = k.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let eq_phi = tr.sys.dofs.eq[iphi] as usize;
    // The φ column must actually couple (a missing block would pass a loose test).
    let col_phi = (0..n).filter(|&i| i != eq_phi && k[i][eq_phi] != 0.0).count();
    assert!(col_phi > 10, "φ column has only {col_phi} entries");
    let mut err = 0.0f64;
    let mut e = vec![0.0; n];
    let h = 1e-7;
    for j in 0..n {
        e.fill(0.0);
        e[j] = h;
        tr.update(1.0, &e);
        assert!(tr.evaluate(false));
        let rp = tr.residual().to_vec();
        tr.update(-2.0, &e);
        assert!(tr.evaluate(false));
        let rm = tr.residual().to_vec();
        tr.update(1.0, &e);
        for i in 0..n {
            err = err.max(((rp[i] - rm[i]) / (2.0 * h) - k[i][j]).abs());
        }
    }
    eprintln!(
        "torque-control step tangent (load control {load_control}): {in_contact} contact points, max|K − K_fd|/max|K| = {:.2e}",
        err / kmax
    );
    err / kmax
}

#[test]
fn torque_control_tangent_matches_finite_differences() {
    for load in [false, true] {
        let e = torque_step_tangent_error(load);
        assert!(e < 1e-6, "tangent differs from FD (load control {load}): {e:.3e}");
    }
}

#[test]
#[ignore]
fn debug_free_rolling() {
    use tread::driver::transient::{integrate, TimeOptions};
    let text = std::fs::read_to_string(format!("{}/scenarios/free_rolling.toml", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let scene = Scene::from_toml_str(&text, "x", &[]).unwrap();
    let mut model = tread::app::build_model(&scene).unwrap();
    model.strain_rate_damping = 1.0;
    let c = tread::app::build_contact(&scene, &model).unwrap();
    let sys = SolidSystem::with_contact(model, c);
    let kin = tread::driver::transient_run::kinematics(&scene);
    let mut tr = Transient::new(sys, Scheme::GeneralizedAlpha(GenAlpha::new(0.5)), kin, false);
    tr.enable_torque_control(0.5, Ramp { target: 0.0, time: 0.0 }, 2.0);
    tr.start_rigid_spin(2.0, tread::solver::LinearKind::Lu, None).unwrap();
    let o = TimeOptions { dt: 2e-3, dt_min: 2e-7, dt_max: 2e-2, t_end: 3.0, adaptive: true, error_tol: 1e-3, steady_tol: 1e-6, stop_at_steady: false, max_steps: 100000, lumped: false, land_on_passages: true };
    let mut k = 0;
    let _ = integrate(&mut tr, &o, tread::solver::NewtonOptions { tol: 1e-8, ..Default::default() }, tread::solver::LinearKind::Lu, |tr, _| {
        k += 1;
        if k % 20 == 0 {
            let ip = tr.hub_angle.as_ref().unwrap().iphi;
            let (_, m) = tr.hub_reaction();
            eprintln!("t {:.4} omega {:.6} phidd {:.4e} I*phidd {:.4e} M_r {:.4e}", tr.t, tr.vn[ip], tr.an[ip], 0.5 * tr.an[ip], m);
        }
    });
}
