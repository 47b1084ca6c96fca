//! Torque control of the hub in the transient mode: consistent tangent of a time step with the
//! hub angle as an unknown, free rolling and braking to steady state, and load control.

#[path = "common/fixtures.rs"]
mod fixtures;
use fixtures::*;

use tread::contact::laws::CoulombTanh;
use tread::contact::{ContactModel, FacetRule, Friction, NormalCompliance};
use tread::driver::transient::{GenAlpha, Kinematics, Ramp, Scheme, Transient};
use tread::model::SolidSystem;
use tread::solver::NonlinearSystem;

/// Max |K − K_fd| / max |K| of a generalized-α step under torque control (optionally also
/// under load control: both global unknowns φ and H).
fn torque_step_tangent_error(load_control: bool) -> f64 {
    let mut m = neo_hookean_annulus(2, 16);
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
        Scheme::generalized_alpha(GenAlpha::new(0.7)),
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
        tr.state.v[2 * n] = -10.0 * x[1];
        tr.state.v[2 * n + 1] = 10.0 * x[0];
        tr.state.a[2 * n] = -100.0 * x[0];
        tr.state.a[2 * n + 1] = -100.0 * x[1];
    }
    tr.state.v[iphi] = 10.0;
    tr.state.a[iphi] = 2.0;
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
    let col_phi = (0..n)
        .filter(|&i| i != eq_phi && k[i][eq_phi] != 0.0)
        .count();
    assert!(col_phi > 10, "φ column has only {col_phi} entries");
    let err = fixtures::fd_max_error(&mut tr, 1e-7, |i, j| k[i][j]);
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
        assert!(
            e < 1e-6,
            "tangent differs from FD (load control {load}): {e:.3e}"
        );
    }
}

fn get(r: &serde_json::Value, k: &str) -> f64 {
    r[k].as_f64()
        .unwrap_or_else(|| panic!("results.{k} missing: {r}"))
}

#[test]
fn free_rolling_and_braking_reach_steady_torque_balance() {
    // Free rolling: zero hub torque. The hub finds its own speed from the road speed.
    let s = run_rolling(&scene_text("scenarios/free_rolling.toml"), "free", &[]);
    let r = &s["results"];
    eprintln!("free rolling: {}", serde_json::to_string_pretty(r).unwrap());
    assert_eq!(r["steady"], true, "free rolling: no steady state by t_end");
    assert_eq!(r["control"], "torque");
    let (mu, ro, h) = (0.3, 2.0, 1.9);
    let fy = get(r, "contact_force_y");
    let scale = mu * fy * ro; // largest torque friction can transmit
    let (m_free, fx_free, w_free) = (
        get(r, "hub_torque"),
        get(r, "contact_force_x"),
        get(r, "omega_steady"),
    );
    // The hub moment is zero up to the periodic fluctuation as Q2 nodes enter the patch
    // (I φ̈ at the passage instants, ≈ 0.3 % of the scale measured): 1 %.
    assert!(
        m_free.abs() < 0.01 * scale,
        "free rolling hub torque {m_free} vs scale {scale}"
    );
    // No driving force: only the rolling resistance of the strain-rate damping (pressure
    // centroid offset x_c F_y / H, O(ηω/G) = 1 % of F_y) and the same fluctuation: 3 % of μ F_y.
    assert!(
        fx_free.abs() < 0.03 * mu * fy,
        "free rolling longitudinal force {fx_free} vs μ F_y = {}",
        mu * fy
    );
    // The steady hub speed is reported and sensible (the rolling radius v0/ω of this thick,
    // nearly incompressible layer exceeds Ro, as for rubber-covered rollers: ≈ 2.12 in).
    let rr = get(r, "rolling_radius");
    assert!(
        w_free > 0.0 && rr > h && rr < 1.2 * ro,
        "ω = {w_free}, v0/ω = {rr}"
    );

    // Braking: T = −10 lbf·in/in (clockwise, against the rotation).
    let s = run_rolling(&scene_text("scenarios/braking.toml"), "braking", &[]);
    let r = &s["results"];
    eprintln!("braking: {}", serde_json::to_string_pretty(r).unwrap());
    assert_eq!(r["steady"], true, "braking: no steady state by t_end");
    let t = get(r, "applied_torque");
    assert_eq!(t, -10.0);
    let (mc, fx, w) = (
        get(r, "contact_moment"),
        get(r, "contact_force_x"),
        get(r, "omega_steady"),
    );
    // Steady moment balance of the body: the contact moment about the hub centre equals −T, up
    // to the same passage fluctuation as in free rolling (1 % of μ F_y Ro).
    assert!(
        (mc + t).abs() < 0.01 * scale,
        "contact moment {mc} vs −T = {}",
        -t
    );
    // The tangential tractions act on the road line x2 ≈ −H, so F_x = (−T − x_c F_y) / H: sign
    // along the road motion (the braked patch slips backwards) and magnitude −T/H within 5 %
    // (rolling-resistance moment x_c F_y ≈ 0.2 %, passage fluctuation ≤ 3 %). The kinematic
    // rolling radius v0/ω (≈ 2.15 in here) is not the lever arm.
    assert!(fx > 0.0, "braking force {fx} must be along +x1");
    assert!(
        (fx - (-t / h)).abs() < 0.05 * (-t / h),
        "braking force {fx} vs −T/H = {}",
        -t / h
    );
    // Braking slows the hub below its free-rolling speed.
    assert!(w < w_free, "braked ω = {w} vs free ω = {w_free}");
}

#[test]
fn load_control_rolling_carries_the_applied_load() {
    // The frictionless rolling scene under load control: the road height H is a global
    // unknown; the applied hub load P must be carried by the hub at the steady state.
    let text =
        scene_text("scenarios/rolling_frictionless.toml").replace("disp = 0.1 ", "load = 100.0 ");
    assert!(text.contains("load = 100.0"));
    let s = run_rolling(
        &text,
        "load",
        &[
            "mesh.n_theta=32",
            "mesh.n_r=2",
            "motion.omega=2.0",
            "road.v0=3.9333",
            "contact.b_n=0.0",
            "time.rho_inf=0.5",
            "time.t_end=2.0",
            "time.dt=2e-3",
            "time.steady_tol=1e-3",
            "motion.ramp=0.2",
            "road.ramp=0.2",
        ],
    );
    let r = &s["results"];
    eprintln!("load control: {}", serde_json::to_string_pretty(r).unwrap());
    assert_eq!(r["steady"], true, "load control: no steady state by t_end");
    let (fy, cy) = (get(r, "hub_force_y"), get(r, "contact_force_y"));
    // The H equation makes ∫ t_n ds0 = P exactly (to the Newton tolerance).
    assert!(
        (cy - 100.0).abs() < 1e-4 * 100.0,
        "contact force {cy} vs load 100"
    );
    // The hub carries it: F_hub = −F_contact − Σ M a; Σ M a = m a_cm vanishes in steady rolling
    // up to the periodic fluctuation at the passage instants (measured 0.22 %): 1 %.
    assert!(
        (fy + 100.0).abs() < 0.01 * 100.0,
        "hub force {fy} vs applied load −100"
    );
}
