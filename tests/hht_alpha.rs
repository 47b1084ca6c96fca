//! HHT-α, registered as `[time] integrator = "hht_alpha"`:
//! * its parameters give the method's classical properties on the linear oscillator, computed
//!   here from the amplification matrix of the force-averaged step (independent of the
//!   program's stepping code): spectral radius at infinity ρ∞, unconditional stability, no
//!   dissipation at ρ∞ = 1, second-order phase; at ρ∞ = 1/2 it coincides with generalized-α;
//! * on the finite-element spin-up it converges at second order;
//! * the scene accepts it (also with torque control) and rejects ρ∞ < 1/2 by name.

#[path = "common/fixtures.rs"]
mod fixtures;
use fixtures::*;

use nalgebra::Matrix3;
use tread::driver::transient::hht_alpha::hht_parameters;
use tread::driver::transient::registry::Integrate;
use tread::driver::transient::GenAlpha;
use tread::io::scene::Scene;
use tread::solver::integrators::IntegratorName;

/// Amplification matrix of (u, h v, h² a) for ü + ω² u = 0, Ω = ω h, of the step
/// (1 − αm) a₁ + αm a₀ + Ω²/h² [(1 − αf) u₁ + αf u₀] = 0 with the Newmark relations.
fn amplification(p: &GenAlpha, big_omega: f64) -> Matrix3<f64> {
    let w2 = big_omega * big_omega;
    let mut a = Matrix3::zeros();
    for (col, x0) in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
        .iter()
        .enumerate()
    {
        let (u0, v0, a0) = (x0[0], x0[1], x0[2]);
        // Scaled variables (h = 1): u₁ = u₀ + v₀ + (1/2 − β) a₀ + β a₁.
        let a1 = -(p.am * a0 + w2 * u0 + (1.0 - p.af) * w2 * (v0 + (0.5 - p.beta) * a0))
            / ((1.0 - p.am) + (1.0 - p.af) * w2 * p.beta);
        let u1 = u0 + v0 + (0.5 - p.beta) * a0 + p.beta * a1;
        let v1 = v0 + (1.0 - p.gamma) * a0 + p.gamma * a1;
        a[(0, col)] = u1;
        a[(1, col)] = v1;
        a[(2, col)] = a1;
    }
    a
}

fn spectral_radius(m: &Matrix3<f64>) -> f64 {
    m.complex_eigenvalues()
        .iter()
        .map(|z| z.norm())
        .fold(0.0, f64::max)
}

/// Phase per step of the principal roots (the complex pair; the third, spurious root is real).
fn principal_phase(m: &Matrix3<f64>) -> f64 {
    let z = m
        .complex_eigenvalues()
        .iter()
        .copied()
        .find(|z| z.im > 0.0)
        .expect("a complex pair of principal roots");
    z.im.atan2(z.re)
}

#[test]
fn hht_parameters_have_the_classical_properties() {
    for rho in [0.5, 0.6, 0.8, 0.9, 1.0] {
        let p = hht_parameters(rho);
        assert_eq!(p.am, 0.0, "HHT does not average accelerations");
        // Spectral radius at infinity.
        let r_inf = spectral_radius(&amplification(&p, 1e8));
        assert!((r_inf - rho).abs() < 1e-6, "ρ∞ = {rho}: got {r_inf}");
        // Unconditionally stable: ρ ≤ 1 for every Ω (and = 1 for all Ω at ρ∞ = 1).
        for k in -30..=60 {
            let big = 10f64.powf(k as f64 / 10.0);
            let r = spectral_radius(&amplification(&p, big));
            assert!(r <= 1.0 + 1e-12, "ρ∞ = {rho}, Ω = {big}: ρ = {r}");
            if rho == 1.0 {
                assert!((r - 1.0).abs() < 1e-12, "no dissipation at ρ∞ = 1: {r}");
            }
        }
        // Second order: the phase error per step is O(Ω³), so the relative period error is
        // O(Ω²): it drops by 4 when Ω halves.
        let err = |big: f64| (principal_phase(&amplification(&p, big)) - big).abs() / big;
        let order = (err(0.02) / err(0.01)).log2();
        assert!(
            (order - 2.0).abs() < 0.05,
            "ρ∞ = {rho}: phase order {order}"
        );
    }
    // At ρ∞ = 1/2, generalized-α has αm = 0: the same method.
    let (h, g) = (hht_parameters(0.5), GenAlpha::new(0.5));
    for (a, b) in [
        (h.am, g.am),
        (h.af, g.af),
        (h.gamma, g.gamma),
        (h.beta, g.beta),
    ] {
        assert!((a - b).abs() < 1e-15, "{a} vs {b}");
    }
    // Elsewhere they differ (HHT damps the middle frequencies more at equal ρ∞).
    let (h, g) = (hht_parameters(0.8), GenAlpha::new(0.8));
    let mid = 2.0;
    assert!(
        spectral_radius(&amplification(&h, mid)) < spectral_radius(&amplification(&g, mid)),
        "HHT should be more dissipative at Ω = {mid}"
    );
}

/// u at t_end of a spin-up from rest (ramp to 20 rad/s over 0.03 s, no contact) with the
/// registered integrator's scheme.
fn spin_up(rho: f64, dt: f64, t_end: f64) -> Vec<f64> {
    let scheme = IntegratorName::HhtAlpha.scheme(rho);
    spin_up_fixed(neo_hookean_annulus(2, 16), scheme, dt, t_end)
}

#[test]
fn hht_alpha_converges_at_second_order_on_the_spin_up() {
    let (t_end, dt0) = (0.04, 1e-3);
    for rho in [0.6, 0.9] {
        let errs = step_errors(|dt| spin_up(rho, dt, t_end), dt0);
        let p = (errs[1] / errs[2]).log2();
        eprintln!("HHT ρ∞ = {rho}: errors {errs:?}, observed order {p:.2}");
        assert!((p - 2.0).abs() < 0.3, "ρ∞ = {rho}: observed order {p:.2}");
    }
}

#[test]
fn the_scene_takes_hht_alpha_and_checks_its_rho_inf() {
    let base = scene_text("scenarios/free_rolling.toml");
    let with = |integrator: &str, rho: &str| {
        Scene::from_toml_str(
            &base,
            "free_rolling.toml",
            &[
                format!("time.integrator={integrator}"),
                format!("time.rho_inf={rho}"),
            ],
        )
    };
    // Torque control is accepted: HHT solves the hub angle in its implicit step.
    let s = with("hht_alpha", "0.7").expect("hht_alpha scene");
    assert_eq!(
        s.time.as_ref().unwrap().integrator,
        IntegratorName::HhtAlpha
    );
    let err = with("hht_alpha", "0.4")
        .expect_err("rho_inf = 0.4 must be refused")
        .to_string();
    assert!(
        err.contains("time.rho_inf") && err.contains("[0.5, 1]") && err.contains("hht_alpha"),
        "{err}"
    );
    // The same value is fine for generalized-α.
    with("generalized_alpha", "0.4").expect("generalized_alpha 0.4");
    // An explicit integrator is refused under torque control, and the message names the
    // integrators that can do it.
    let err = with("central_difference", "0.7")
        .expect_err("central difference with torque control")
        .to_string();
    assert!(
        err.contains("\"generalized_alpha\" or \"hht_alpha\""),
        "{err}"
    );
}
