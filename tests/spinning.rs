//! Steady spinning of the hollow cylinder against exact and independent references.

mod common;

use common::reference::{incompressible_sigma_r, linear_annulus, neo_hookean_radial};
use tread::app::build_system;
use tread::driver::spinning::{profile, results, solve_spinning};
use tread::io::Scene;
use tread::model::SolidSystem;
use tread::solver::stepping::{StepOptions, StepReport};
use tread::solver::{LinearKind, NewtonOptions};

const RI: f64 = 1.0;
const RO: f64 = 2.0;
const RHO: f64 = 0.027;

fn scene(material: &str, n_r: usize, n_theta: usize, order: usize) -> Scene {
    // The shared scene has RI, RO and RHO of this file.
    common::spinning_scene(
        material,
        &format!(
            "n_r = {n_r}
n_theta = {n_theta}
order = {order}"
        ),
    )
}

fn solve(sys: &mut SolidSystem, omega: f64, kind: LinearKind, steps: usize) -> StepReport {
    let mut rep = StepReport::default();
    let opts = NewtonOptions {
        tol: 1e-11,
        max_iterations: 30,
        ..Default::default()
    };
    let so = StepOptions {
        initial_steps: steps,
        max_cutbacks: 8,
        verbose: false,
    };
    solve_spinning(sys, omega, kind, opts, &so, &mut rep, &mut ())
        .expect("spinning solve converges");
    rep
}

const NEO: &str = "model = \"neo_hookean\"\nmu = 200.0\nlambda = 1800.0";

#[test]
fn incompressible_spinning_is_rigid_with_exact_radial_stress() {
    // ρω²Ro² ≈ μ/2, below the Rayleigh-wave critical spin c_R/Ro ≈ 41 rad/s of this material.
    let omega = 30.0;
    let smax = incompressible_sigma_r(RO, RHO, omega, RI);
    for (form, extra, kind) in [
        ("exact", "", LinearKind::Lu),
        ("perturbed", "kappa = 2.0e7", LinearKind::Cholesky),
    ] {
        let mat = format!("model = \"mooney_rivlin_incompressible\"\nc1 = 80.0\nc2 = 20.0\nformulation = \"{form}\"\n{extra}");
        let mut errs = Vec::new();
        for (n_r, n_t) in [(4, 32), (8, 64)] {
            let sc = scene(&mat, n_r, n_t, 2);
            let mut sys = build_system(&sc).unwrap();
            solve(&mut sys, omega, kind, 2);
            let umax = (0..sys.model.mesh.n_nodes())
                .map(|n| sys.x[2 * n].hypot(sys.x[2 * n + 1]))
                .fold(0.0, f64::max);
            let prof = profile(&sys);
            let serr = prof
                .iter()
                .map(|p| (p.sigma_r - incompressible_sigma_r(RO, RHO, omega, p.r)).abs())
                .fold(0.0, f64::max)
                / smax;
            let terr = prof
                .iter()
                .map(|p| (p.sigma_theta - incompressible_sigma_r(RO, RHO, omega, p.r)).abs())
                .fold(0.0, f64::max)
                / smax;
            let r = results(&sys);
            eprintln!(
                "{form} n_r={n_r}: max|u|/Ro = {:.3e}, max σ_r err = {serr:.3e}, max σ_θ err = {terr:.3e} (rel. to σ_r(Ri) = {smax:.2}); ring σ_r(Ri) = {:.4}",
                umax / RO,
                r.sigma_r_inner
            );
            assert!(umax / RO < 1e-4, "{form}: u not ≈ 0: {umax:.3e}");
            assert!(
                serr < 2e-3 && terr < 2e-3,
                "{form}: stress error {serr:.3e} {terr:.3e}"
            );
            errs.push((umax, serr));
        }
        // Both errors shrink under refinement (the P1 pressure cannot represent ρω²r²/2 exactly).
        assert!(
            errs[1].0 < 0.5 * errs[0].0 && errs[1].1 < 0.5 * errs[0].1,
            "{form}: no convergence: {errs:?}"
        );
    }
}

#[test]
fn compressible_small_spin_matches_linear_closed_form() {
    let omega = 1.0;
    let lin = linear_annulus(RI, RO, 1800.0, 200.0, RHO, omega);
    let sc = scene(NEO, 16, 96, 2);
    let mut sys = build_system(&sc).unwrap();
    solve(&mut sys, omega, LinearKind::Cholesky, 1);
    let r = results(&sys);
    let s_ref = lin.sigma_r(RI).abs();
    let e_u = (r.u_r_outer - lin.u(RO)).abs() / lin.u(RO).abs();
    let e_sri = (r.sigma_r_inner - lin.sigma_r(RI)).abs() / s_ref;
    let e_sti = (r.sigma_theta_inner - lin.sigma_theta(RI)).abs() / s_ref;
    let e_sro = r.sigma_r_outer.abs() / s_ref;
    let e_sto = (r.sigma_theta_outer - lin.sigma_theta(RO)).abs() / s_ref;
    eprintln!("linear: u_r(Ro) {:.6e} vs {:.6e} (rel {e_u:.2e}); σ errors rel. to σ_r(Ri): {e_sri:.2e} {e_sti:.2e} {e_sro:.2e} {e_sto:.2e}", r.u_r_outer, lin.u(RO));
    for e in [e_u, e_sri, e_sti, e_sro, e_sto] {
        assert!(e <= 1e-3, "relative error {e:.3e} > 1e-3");
    }
}

#[test]
fn neo_hookean_large_spin_matches_radial_reference() {
    let omega = 104.443315253851; // 5 % radial growth of the outer surface
    let refsol = neo_hookean_radial(RI, RO, 1800.0, 200.0, RHO, omega).expect("reference");
    let u_ref = refsol.u(RO);
    assert!(u_ref / RO >= 0.05 - 1e-9);
    let mut prev = f64::INFINITY;
    for (n_r, n_t) in [(4, 32), (8, 64), (12, 96)] {
        let sc = scene(NEO, n_r, n_t, 2);
        let mut sys = build_system(&sc).unwrap();
        let rep = solve(&mut sys, omega, LinearKind::Cholesky, 4);
        let r = results(&sys);
        let e_u = (r.u_r_outer - u_ref).abs() / u_ref;
        let s_ref = refsol.sigma_r(RI);
        let prof = profile(&sys);
        let e_prof = prof
            .iter()
            .map(|p| {
                (p.sigma_r - refsol.sigma_r(p.r))
                    .abs()
                    .max((p.sigma_theta - refsol.sigma_theta(p.r)).abs())
            })
            .fold(0.0, f64::max)
            / s_ref;
        let e_ur = prof
            .iter()
            .map(|p| (p.u_r - refsol.u(p.r)).abs())
            .fold(0.0, f64::max)
            / u_ref;
        eprintln!(
            "n_r={n_r:2} n_θ={n_t:3}: u_r(Ro) = {:.10} vs {u_ref:.10} rel {e_u:.2e}; profile u_r err {e_ur:.2e}, σ err {e_prof:.2e}; σ_r(Ri) {:.4} vs {s_ref:.4}; {} Newton its",
            r.u_r_outer, r.sigma_r_inner, rep.total_iterations
        );
        assert!(e_u < prev, "no convergence under refinement");
        prev = e_u;
        if n_r == 12 {
            assert!(e_u <= 1e-4, "u_r(Ro) relative error {e_u:.3e} > 1e-4");
            assert!(e_ur <= 1e-4, "u_r profile relative error {e_ur:.3e} > 1e-4");
            assert!(
                e_prof <= 1e-3,
                "stress profile relative error {e_prof:.3e} > 1e-3"
            );
        }
    }
}

#[test]
fn newton_converges_quadratically() {
    let sc = scene(NEO, 4, 32, 2);
    let mut sys = build_system(&sc).unwrap();
    let rep = solve(&mut sys, 90.0, LinearKind::Cholesky, 1);
    // The single load step from rest to ω = 90 rad/s: residual history.
    let last = rep.steps.iter().rev().find(|s| s.converged).unwrap();
    let res: Vec<f64> = last.table.iter().map(|r| r.residual_rel[0]).collect();
    eprintln!("residual history: {res:?}");
    // Order estimates log(r_{k+1}) / log(r_k) while well above round-off.
    let orders: Vec<f64> = res
        .windows(2)
        .filter(|w| w[0] < 1e-2 && w[1] > 1e-13)
        .map(|w| w[1].ln() / w[0].ln())
        .collect();
    eprintln!("observed orders: {orders:.2?}");
    assert!(!orders.is_empty(), "no iterations in the asymptotic range");
    assert!(orders.iter().all(|&p| p > 1.8), "not quadratic: {orders:?}");
}
