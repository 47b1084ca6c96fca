//! The independent reference for viscoelastic rolling (tests/common/hunter.rs: a rigid cylinder
//! rolling on a standard-linear-solid half-space, Hunter 1961): validated in its elastic limits
//! against Hertz, converged in the number of Chebyshev terms, and tabulated around the peak of
//! the rolling resistance.

#[path = "common/hunter.rs"]
mod hunter;
use hunter::*;

fn problem() -> HunterProblem {
    HunterProblem {
        g_inf: 200.0,
        g1: 100.0,
        tau: 0.03,
        radius: 2.0,
        load: 125.0,
    }
}

#[test]
fn gauss_legendre_is_exact_for_polynomials() {
    let (x, w) = gauss_legendre(8);
    for k in 0..16 {
        let q: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(k)).sum();
        let exact = if k % 2 == 0 {
            2.0 / (k + 1) as f64
        } else {
            0.0
        };
        assert!((q - exact).abs() < 1e-14, "x^{k}: {q} vs {exact}");
    }
}

/// V = 0 (relaxed modulus G∞) and V = ∞ (instantaneous G∞ + G1): the Hertz half-width and
/// pressure, a centred contact and no rolling resistance; at very small and very large but
/// finite speeds the solution tends to these limits.
#[test]
fn elastic_limits_are_hertz() {
    let pb = problem();
    for (v, j) in [(0.0, pb.j_inf()), (f64::INFINITY, pb.j0())] {
        let s = pb.solve(v, 12).expect("solves");
        let (a, p0) = pb.hertz(j);
        assert!(
            (s.half_width - a).abs() < 1e-10 * a,
            "V = {v}: {} vs {a}",
            s.half_width
        );
        assert!(s.centre.abs() < 1e-12 * a && s.resistance.abs() < 1e-12);
        for t in [-0.9, -0.3, 0.0, 0.5, 0.95] {
            let p = s.pressure(t * a);
            let ph = p0 * (1.0 - t * t).sqrt();
            assert!((p - ph).abs() < 1e-10 * p0, "V = {v}, t = {t}: {p} vs {ph}");
        }
    }
    // Slow and fast rolling: λ = V τc / a of 1e-4 and 1e4.
    let (a_rel, _) = pb.hertz(pb.j_inf());
    let (a_gl, _) = pb.hertz(pb.j0());
    let slow = pb.solve(1e-4 * a_rel / pb.tau_c(), 16).unwrap();
    let fast = pb.solve(1e4 * a_gl / pb.tau_c(), 16).unwrap();
    eprintln!(
        "slow: L/a = {:.6}, μ_r = {:.2e}; fast: L/a = {:.6}, μ_r = {:.2e}",
        slow.half_width / a_rel,
        slow.resistance,
        fast.half_width / a_gl,
        fast.resistance
    );
    assert!((slow.half_width / a_rel - 1.0).abs() < 1e-3);
    assert!((fast.half_width / a_gl - 1.0).abs() < 1e-3);
    assert!(slow.resistance.abs() < 1e-3 && fast.resistance.abs() < 1e-3);
}

/// Around the peak: the solution converges with the number of terms (24 → 40 terms), the load is
/// carried, the pressure is non-negative inside the contact, the contact shifts upstream and the
/// resistance peaks at an intermediate speed. Prints the table of the reference.
#[test]
fn resistance_curve_converges_and_peaks() {
    let pb = problem();
    let (a0, _) = pb.hertz(pb.j_inf());
    println!("  V τc/a∞    μ_r = M/(P R)   x_up/a∞    x_down/a∞   c/a∞");
    let mut curve = Vec::new();
    for lam in [
        0.03, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0, 1.5, 2.0, 3.0, 5.0, 10.0, 30.0,
    ] {
        let v = lam * a0 / pb.tau_c();
        let s = pb.solve(v, 40).expect("solves");
        let s12 = pb.solve(v, 24).expect("solves");
        let d_mu = (s.resistance - s12.resistance).abs() / s.resistance.abs();
        let d_l = (s.half_width - s12.half_width).abs() / s.half_width;
        assert!(
            d_mu < 1e-4 && d_l < 1e-6,
            "λ = {lam}: Δμ {d_mu:.1e}, ΔL {d_l:.1e}"
        );
        // Load: ∫ p dx by the trapezoidal rule on a fine grid.
        let (x0, x1) = s.edges();
        let n = 20000;
        let h = (x1 - x0) / n as f64;
        let mut load = 0.0;
        let mut moment = 0.0;
        for i in 0..=n {
            let x = x0 + i as f64 * h;
            let p = s.pressure(x);
            assert!(p >= -1e-6 * pb.load / a0, "λ = {lam}: p({x}) = {p}");
            let w = if i == 0 || i == n { 0.5 } else { 1.0 };
            load += w * p * h;
            moment += w * p * x * h;
        }
        assert!((load - pb.load).abs() < 1e-4 * pb.load, "{load}");
        let mu_q = moment / (pb.load * pb.radius);
        assert!(
            (mu_q - s.resistance).abs() < 1e-4 * s.resistance.abs(),
            "{mu_q} vs {}",
            s.resistance
        );
        // Upstream shift (material enters at x < 0) and resistance opposing the motion.
        assert!(s.centre < 0.0 && s.resistance < 0.0);
        println!(
            "  {lam:8.3}   {:12.6e}   {:9.5}   {:9.5}   {:9.5}",
            -s.resistance,
            x0 / a0,
            x1 / a0,
            s.centre / a0
        );
        curve.push((lam, -s.resistance));
    }
    let (i_max, _) =
        curve.iter().enumerate().fold(
            (0, 0.0),
            |(im, m), (i, c)| if c.1 > m { (i, c.1) } else { (im, m) },
        );
    assert!(
        i_max > 0 && i_max + 1 < curve.len(),
        "peak not inside the range: {curve:?}"
    );
    assert!(curve[0].1 < 0.5 * curve[i_max].1 && curve[curve.len() - 1].1 < 0.5 * curve[i_max].1);
}
