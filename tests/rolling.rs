//! Transient rolling on the road until steady, through the program's driver.

#[path = "common/fixtures.rs"]
mod fixtures;
use fixtures::*;

#[test]
fn frictionless_rolling_reaches_a_symmetric_steady_state() {
    // Slow rolling (ω = 2 rad/s) of a coarse cylinder, no normal damping; the transient is damped
    // by the objective Green-strain-rate viscosity (η = 1 psi·s, ηω/G = 1 %).
    let s = run_rolling(
        &scene_text("scenarios/rolling_frictionless.toml"),
        "frictionless",
        &[
            "mesh.n_theta=32",
            "mesh.n_r=2",
            "motion.omega=2.0",
            "road.v0=3.9333",
            "contact.b_n=0.0",
            "time.rho_inf=0.5",
            "time.t_end=2.0",
            "time.dt=2e-3",
            "time.error_tol=1e-3",
            "time.steady_tol=1e-3",
            "motion.ramp=0.2",
            "road.ramp=0.2",
            "time.strain_rate_damping=1.0",
        ],
    );
    let r = &s["results"];
    eprintln!("{}", serde_json::to_string_pretty(r).unwrap());
    assert_eq!(r["steady"], true, "no steady state by t_end");
    let (xmin, xmax) = (
        r["contact_x_min"].as_f64().unwrap(),
        r["contact_x_max"].as_f64().unwrap(),
    );
    let (fx, fy) = (
        r["hub_force_x"].as_f64().unwrap(),
        r["hub_force_y"].as_f64().unwrap(),
    );
    let a = r["contact_half_width_moment"].as_f64().unwrap();
    let xc = r["contact_centroid"].as_f64().unwrap();
    // Symmetric about the vertical: the pressure centroid within 3 % of the half-width (the
    // O(ηω/G) = 1 % viscous asymmetry), and the patch ends within one facet-point spacing
    // (Lobatto 4 points on a cell of arc 2π·2/32 ≈ 0.39 in: ≈ 0.13 in; the run ends at an
    // arbitrary mesh phase).
    let spacing = 2.0 * std::f64::consts::PI * 2.0 / 32.0 / 3.0;
    assert!(
        xc.abs() < 0.03 * a,
        "pressure centroid {xc} vs half-width {a}"
    );
    assert!(
        (xmax + xmin).abs() < spacing,
        "patch [{xmin}, {xmax}] not symmetric"
    );
    assert!(
        fx.abs() < 0.01 * fy.abs(),
        "horizontal hub force {fx} vs {fy}"
    );
}
