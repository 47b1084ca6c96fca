//! Viscoelastic rolling of the three-dimensional wheel: the energy balance of the steady mode
//! (the power of the hub torque equals the viscous dissipation of the multiplicative model, on
//! a crowned, cambered wheel whose stress state is fully three-dimensional).

use tread::driver::steady3d::solve_steady_3d;
use tread::io::Scene;
use tread::solver::observe::NoObserver;
use tread::solver::stepping::StepReport;
use tread::solver::NonlinearSystem;

/// A crowned wheel (Ro = 2, width 0.6, crown radius 1) of a nearly incompressible
/// Mooney–Rivlin rubber with a multiplicative standard-linear-solid overstress (γ = G,
/// ω τ = 0.3), rolling at 10 rad/s on a frictionless road pressed 0.08 into it and cambered
/// by `camber` degrees, without normal damping.
fn crowned_scene(n_r: usize, n_z: usize, n_theta: usize, order: usize, camber: f64) -> Scene {
    let text = format!(
        r#"
[scene]
name = "visco3d"
[geometry]
ri = 1.0
ro = 2.0
[mesh]
dimension = 3
width = 0.6
crown_radius = 1.0
n_r = {n_r}
n_z = {n_z}
n_theta = {n_theta}
order = {order}
[material]
model = "mooney_rivlin"
c1 = 80.0
c2 = 20.0
kappa = 4000.0
rho = 0.027
[material.viscoelastic]
model = "multiplicative"
gamma = 200.0
prony = [[1.0, 0.03]]
[analysis]
mode = "steady"
[motion]
omega = 10.0
[road]
disp = 0.08
v0 = 19.8
camber = {camber}
[contact]
c_n = 2.0e4
b_n = 0.0
quadrature = "gauss"
points = 3
[friction]
law = "none"
[solver]
tolerance = 1e-10
load_steps = 4
"#
    );
    Scene::from_toml_str(&text, "visco3d", &[]).unwrap_or_else(|e| panic!("{e}"))
}

/// Energy balance of steady rolling with the dissipative model and no other dissipation
/// (frictionless road, no normal damping, no strain-rate damping): M3 ω = ∫ D dV up to the
/// discretization error, which shrinks as the mesh is refined.
#[test]
fn hub_power_balances_the_viscous_dissipation_3d() {
    let mut errs = Vec::new();
    // Measured: 7.8e-3 (2 × 2 × 32), 8.1e-3 (2 × 4 × 64), 2.7e-3 (2 × 4 × 128), 4.9e-4
    // (3 × 6 × 128, 59,904 equations); the test takes the first and the third.
    for (n_r, n_z, n_theta) in [(2, 2, 32), (2, 4, 128)] {
        let sc = crowned_scene(n_r, n_z, n_theta, 2, 2.0);
        let mut sys = tread::setup::build_system_3d(&sc).unwrap_or_else(|e| panic!("{e}"));
        let kind = tread::setup::linear_kind_3d(&sc, &sys);
        let (newton, step) = tread::setup::solver_options(&sc, false);
        let mut rep = StepReport::default();
        solve_steady_3d(&mut sys, kind, newton, &step, &mut rep, &mut NoObserver)
            .unwrap_or_else(|e| panic!("3D steady: {e}"));
        assert!(sys.evaluate(false));
        let (_, m) = sys.hub_reaction();
        let omega = sys.steady_omega().expect("steady");
        let d = sys
            .steady_history()
            .and_then(|h| h.dissipation(&sys.solid))
            .expect("multiplicative dissipation");
        let power = m[2] * omega;
        let e = (power - d).abs() / d;
        eprintln!(
            "{n_r} x {n_z} x {n_theta} Hex27 ({} equations): M3 ω = {power:.6e}, ∫ D dV = {d:.6e}, relative difference {e:.2e}; M1 = {:.3e}, M2 = {:.3e}",
            sys.n_eq(),
            m[0],
            m[1]
        );
        errs.push(e);
    }
    assert!(errs[1] < 0.01 && errs[1] < errs[0], "{errs:?}");
}
