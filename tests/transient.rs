//! Transient Lagrangian model: tangent of a time step, objectivity of rigid spinning, observed
//! orders of the integrators, spin-up to the steady spinning state.

#[path = "common/fixtures.rs"]
mod fixtures;
use fixtures::*;

use tread::contact::laws::CoulombTanh;
use tread::contact::{ContactModel, FacetRule, Friction, NormalCompliance};
use tread::driver::spinning::solve_spinning;
use tread::driver::transient::{integrate, GenAlpha, Ramp, Scheme, Transient};
use tread::model::SolidSystem;
use tread::solver::stepping::{StepOptions, StepReport};
use tread::solver::{LinearKind, NonlinearSystem};

#[test]
fn time_step_tangent_matches_finite_differences() {
    // Contact with normal damping and friction, mid-step state, generalized-α (ρ∞ = 0.7).
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
        None,
    );
    let sys = SolidSystem::with_contact(m, cm);
    let mut kin = spin_kinematics(10.0, 0.0);
    kin.disp = Some(Ramp {
        target: 0.05,
        time: 0.0,
    });
    let mut tr = Transient::new(
        sys,
        Scheme::generalized_alpha(GenAlpha::new(0.7)),
        kin,
        false,
    );
    // Committed state: undeformed body in rigid rotation (velocities and accelerations of the
    // rotation), so that the trial state below slides and penetrates.
    for n in 0..tr.sys.model.mesh.n_nodes() {
        let x = tr.sys.model.mesh.nodes[n];
        tr.state.v[2 * n] = -10.0 * x[1];
        tr.state.v[2 * n + 1] = 10.0 * x[0];
        tr.state.a[2 * n] = -100.0 * x[0];
        tr.state.a[2 * n + 1] = -100.0 * x[1];
    }
    tr.dt = 1e-3;
    // A trial state: rigid rotation by ω dt plus a small smooth perturbation.
    let (s, c) = (10.0f64 * 1e-3).sin_cos();
    for n in 0..tr.sys.model.mesh.n_nodes() {
        let x = tr.sys.model.mesh.nodes[n]
            + tread::math::Vec2::new(tr.state.u[2 * n], tr.state.u[2 * n + 1]);
        tr.sys.x[2 * n] = c * x[0] - s * x[1] - tr.sys.model.mesh.nodes[n][0] + 1e-3 * x[1].sin();
        tr.sys.x[2 * n + 1] =
            s * x[0] + c * x[1] - tr.sys.model.mesh.nodes[n][1] + 1e-3 * x[0].cos();
    }
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
    let err = fixtures::fd_max_error(&mut tr, 1e-7, |i, j| k[i][j]);
    eprintln!(
        "time-step tangent: {in_contact} contact points, max|K − K_fd|/max|K| = {:.2e}",
        err / kmax
    );
    assert!(
        err / kmax < 1e-6,
        "dynamic tangent differs from FD: {:.3e}",
        err / kmax
    );
}

/// Spin a body in its rigid-spin state for `revs` revolutions with generalized-α ρ∞ = 1;
/// returns (energy at each revolution, max relative strain change, steps).
fn rigid_spin_run(
    lumped: bool,
    discrete_start: bool,
    revs: usize,
    steps_per_rev: usize,
    damping: f64,
) -> (Vec<f64>, f64, usize) {
    let omega = 20.0;
    let period = 2.0 * std::f64::consts::PI / omega;
    let dt = period / steps_per_rev as f64;
    let mut m = neo_hookean_annulus(2, 32);
    m.strain_rate_damping = damping;
    let mut tr = Transient::new(
        SolidSystem::new(m, "hub"),
        Scheme::generalized_alpha(GenAlpha::new(1.0)),
        spin_kinematics(omega, 0.0),
        lumped,
    );
    tr.start_rigid_spin(omega, LinearKind::Cholesky, discrete_start.then_some(dt))
        .unwrap();
    let e0 = tr.cell_strains(&tr.state.u);
    let emax = e0.iter().map(|e| e.norm()).fold(0.0, f64::max);
    let energy = |tr: &Transient| {
        tr.kinetic_energy(&tr.state.v) + tr.sys.model.strain_energy(&tr.sys.dofs, &tr.state.u)
    };
    let mut energies = vec![energy(&tr)];
    let mut next = period;
    let mut max_strain_change = 0.0f64;
    let rep = integrate(
        &mut tr,
        &fixed_step_options(dt, revs as f64 * period),
        tight_newton_options(),
        if damping > 0.0 {
            LinearKind::Lu
        } else {
            LinearKind::Cholesky
        },
        |tr, _| {
            if tr.state.t >= next - 1e-9 * period {
                next += period;
                energies.push(energy(tr));
                let e = tr.cell_strains(&tr.state.u);
                let d = e
                    .iter()
                    .zip(&e0)
                    .map(|(a, b)| (a - b).norm())
                    .fold(0.0, f64::max);
                max_strain_change = max_strain_change.max(d / emax);
            }
        },
    )
    .unwrap_or_else(|(e, _)| panic!("integration failed: {e}"));
    (energies, max_strain_change, rep.steps)
}

#[test]
fn rigid_spinning_is_objective_and_conserves_energy() {
    // (a) Lumped mass, exact discrete rigid-rotation start: the integrator must reproduce the
    // rigid rotation — no strain, no energy change — to round-off.
    let (en, ds, steps) = rigid_spin_run(true, true, 5, 100, 0.0);
    let drift = en
        .windows(2)
        .map(|w| ((w[1] - w[0]) / en[0]).abs())
        .fold(0.0, f64::max);
    eprintln!("rigid spin, lumped, discrete start: {steps} steps, energy per revolution {en:?}, max drift/rev {drift:.2e}, max strain change {ds:.2e}");
    assert!(drift < 1e-6, "energy drift per revolution {drift:.3e}");
    assert!(ds < 1e-8, "rigid rotation strained the body: {ds:.3e}");
    // (c) With Green-strain-rate damping the rigid spin is not dissipated (Ė = 0 in a rigid
    // rotation): after the first revolution, in which the O((ωΔt)²) mismatch between the exact
    // hub velocity and the discrete interior rotation is damped out, the energy is constant.
    let (en, ds, steps) = rigid_spin_run(true, true, 5, 100, 5.0);
    let drift = en[1..]
        .windows(2)
        .map(|w| ((w[1] - w[0]) / en[0]).abs())
        .fold(0.0, f64::max);
    eprintln!("rigid spin, lumped, damped (η = 5): {steps} steps, energy per revolution {en:?}, max drift/rev after the first {drift:.2e}, strain change {ds:.2e}");
    assert!(
        drift < 1e-6,
        "damping dissipates a rigid rotation: {drift:.3e}"
    );
    assert!(ds < 5e-2, "{ds:.3e}");
    // (b) Consistent mass, exact continuous rigid-spin start: the start is off the discrete
    // rotation by O((ωΔt)²), which excites a bounded oscillation; no secular drift.
    let (en, ds, steps) = rigid_spin_run(false, false, 5, 200, 0.0);
    let dev = en
        .iter()
        .map(|e| ((e - en[0]) / en[0]).abs())
        .fold(0.0, f64::max);
    let drift = ((en[5] - en[0]) / en[0]).abs() / 5.0;
    eprintln!("rigid spin, consistent mass: {steps} steps, energy per revolution {en:?}, max deviation {dev:.2e}, mean drift/rev {drift:.2e}, max strain change {ds:.2e}");
    assert!(
        dev < 1e-3 && ds < 2e-2,
        "oscillation too large: {dev:.3e} {ds:.3e}"
    );
    assert!(drift < 1e-5, "secular energy drift {drift:.3e}");
}

/// u at t_end of a spin-up from rest (ramp to 20 rad/s over 0.03 s, no contact).
fn spin_up(scheme: Scheme, dt: f64, t_end: f64) -> Vec<f64> {
    spin_up_fixed(neo_hookean_annulus(2, 16), scheme, dt, t_end)
}

#[test]
fn integrators_converge_at_their_order() {
    let t_end = 0.04;
    let mut table = Vec::new();
    for (name, scheme, dt0) in [
        (
            "generalized-α ρ∞=1",
            Scheme::generalized_alpha(GenAlpha::new(1.0)),
            1e-3,
        ),
        (
            "generalized-α ρ∞=0.8",
            Scheme::generalized_alpha(GenAlpha::new(0.8)),
            1e-3,
        ),
        ("central difference", Scheme::central_difference(), 1e-4),
    ] {
        let errs = step_errors(|dt| spin_up(scheme.clone(), dt, t_end), dt0);
        let orders: Vec<f64> = errs.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
        eprintln!("{name}: dt = {dt0:.1e}/(1, 2, 4): relative errors {errs:?}, observed orders {orders:.2?}");
        table.push((name, orders));
    }
    for (name, orders) in table {
        let p = *orders.last().unwrap();
        assert!(
            (p - 2.0).abs() < 0.3,
            "{name}: observed order {p:.2}, expected 2"
        );
    }
}

#[test]
fn spin_up_reproduces_steady_spinning() {
    let omega = 20.0;
    let mut tr = Transient::new(
        SolidSystem::new(neo_hookean_annulus(2, 32), "hub"),
        Scheme::generalized_alpha(GenAlpha::new(0.0)),
        spin_kinematics(omega, 0.3),
        false,
    );
    let o = fixed_step_options(2e-3, 0.4);
    integrate(
        &mut tr,
        &o,
        tight_newton_options(),
        LinearKind::Cholesky,
        |_, _| {},
    )
    .unwrap_or_else(|(e, _)| panic!("{e}"));
    // Compare rotation-invariant quantities: the radial displacement |X + u| − |X| of every
    // node (a residual torsional oscillation after the ramp only turns the body).
    let mesh = &tr.sys.model.mesh;
    let ur = |u: &[f64]| -> Vec<f64> {
        (0..mesh.n_nodes())
            .map(|n| {
                (mesh.nodes[n] + tread::math::Vec2::new(u[2 * n], u[2 * n + 1])).norm()
                    - mesh.nodes[n].norm()
            })
            .collect()
    };
    // (a) the discrete Lagrangian rigid-spin equilibrium, (b) the θ-referential steady spinning.
    let mut eq = Transient::new(
        SolidSystem::new(neo_hookean_annulus(2, 32), "hub"),
        Scheme::generalized_alpha(GenAlpha::new(1.0)),
        spin_kinematics(omega, 0.0),
        false,
    );
    eq.start_rigid_spin(omega, LinearKind::Cholesky, None)
        .unwrap();
    let mut st = SolidSystem::new(neo_hookean_annulus(2, 32), "hub");
    let mut rep = StepReport::default();
    solve_spinning(
        &mut st,
        omega,
        LinearKind::Cholesky,
        tight_newton_options(),
        &StepOptions {
            initial_steps: 2,
            max_cutbacks: 4,
            verbose: false,
        },
        &mut rep,
        &mut (),
    )
    .unwrap();
    let rel = relative_l2;
    let (u_tr, u_eq, u_st) = (ur(&tr.state.u), ur(&eq.state.u), ur(&st.x));
    let d_eq = rel(&u_tr, &u_eq);
    let d_st = rel(&u_tr, &u_st);
    let d_eq_st = rel(&u_eq, &u_st);
    // Residual torsion: mean angle between the body and the hub.
    let phi = tr.kin.phi(tr.state.t);
    let twist = (0..mesh.n_nodes())
        .map(|n| {
            let x =
                mesh.nodes[n] + tread::math::Vec2::new(tr.state.u[2 * n], tr.state.u[2 * n + 1]);
            let a = x[1].atan2(x[0]) - mesh.nodes[n][1].atan2(mesh.nodes[n][0]) - phi;
            (a + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI) - std::f64::consts::PI
        })
        .map(f64::abs)
        .fold(0.0, f64::max);
    eprintln!("spin-up: radial displacement vs Lagrangian equilibrium {d_eq:.3e}, vs θ-referential steady spinning {d_st:.3e} (the two steady discretisations differ by {d_eq_st:.3e}); residual twist {twist:.2e} rad");
    assert!(
        d_eq < 2e-3,
        "spin-up does not settle on the rigid-spin equilibrium: {d_eq:.3e}"
    );
    assert!(
        d_st < 2e-3,
        "spin-up differs from steady spinning: {d_st:.3e}"
    );
}

/// Central difference with strong strain-rate damping and a stiff contact penalty: the
/// stable-step estimate must include both (a step at 0.9 × the estimate stays bounded), and the
/// undamped, contact-free estimate is then too large (the run blows up and says the explicit
/// step is unstable).
#[test]
fn central_difference_stable_step_includes_damping_and_contact() {
    let build = |damping: f64, c_n: f64| {
        let mut m = neo_hookean_annulus(2, 16);
        m.strain_rate_damping = damping;
        let normal = NormalCompliance::new(c_n, 1.0, 0.0, 0.0);
        let cm = ContactModel::new(
            &m.mesh,
            1.98,
            0.0,
            normal,
            Friction::None,
            FacetRule::Lobatto(4),
            None,
        );
        let mut kin = spin_kinematics(0.0, 0.0);
        kin.disp = Some(Ramp {
            target: 0.02,
            time: 0.0,
        });
        Transient::new(
            SolidSystem::with_contact(m, cm),
            Scheme::central_difference(),
            kin,
            true,
        )
    };
    let mut plain = build(0.0, 1e-6);
    let dt_plain = plain.stable_step(0.02);
    let mut tr = build(5.0, 2.0e6);
    let dt_new = tr.stable_step(0.02);
    eprintln!("stable step: undamped, no contact {dt_plain:.3e}; with η = 5 psi·s and c_n = 2e6 psi/in {dt_new:.3e}");
    assert!(dt_new < 0.5 * dt_plain, "{dt_new:.3e} vs {dt_plain:.3e}");
    // March `steps` explicit steps of `dt` from rest with the road 0.02 in deep.
    let march = |tr: &mut Transient, dt: f64, steps: usize| -> Result<f64, String> {
        let mut newton =
            tread::solver::Newton::new(&tr.sys, LinearKind::Lu, tight_newton_options())
                .map_err(|e| e.to_string())?;
        for _ in 0..steps {
            tr.step(&mut newton, dt).map_err(|e| e.to_string())?;
        }
        let e = tr.kinetic_energy(&tr.state.v);
        if e.is_finite() {
            Ok(e)
        } else {
            Err("non-finite energy".into())
        }
    };
    let stable = march(&mut build(5.0, 2.0e6), 0.9 * dt_new, 2000);
    eprintln!("0.9 × new estimate: {stable:?}");
    let e = stable.unwrap_or_else(|e| panic!("unstable at 0.9 × the estimate: {e}"));
    // Energy stays bounded by the work of the road pressed in (no growth to huge values).
    assert!(e < 1e3, "kinetic energy {e}");
    let mut tr_old = build(5.0, 2.0e6);
    tr_old.dt_stable = dt_plain;
    let blown = march(&mut tr_old, 0.9 * dt_plain, 2000);
    eprintln!("0.9 × undamped contact-free estimate: {blown:?}");
    let msg = blown
        .err()
        .unwrap_or_else(|| panic!("the old estimate did not blow up"));
    assert!(msg.contains("unstable"), "{msg}");
}

/// A node passage that a step lands on exactly (φ/Δθ an integer up to round-off) is counted
/// at that step, not one step late.
#[test]
fn passages_landed_on_are_counted_at_that_step() {
    let omega = 20.0;
    let mut tr = Transient::new(
        SolidSystem::new(neo_hookean_annulus(2, 16), "hub"),
        Scheme::generalized_alpha(GenAlpha::new(1.0)),
        spin_kinematics(omega, 0.0),
        true,
    );
    tr.start_rigid_spin(omega, LinearKind::Cholesky, None)
        .unwrap();
    let dtheta = 2.0 * std::f64::consts::PI / 16.0;
    let mut o = fixed_step_options(dtheta / omega / 7.0, 0.6);
    o.land_on_passages = true;
    let mut seen = Vec::new();
    let rep = integrate(
        &mut tr,
        &o,
        tight_newton_options(),
        LinearKind::Cholesky,
        |tr, rep| seen.push((tr.state.t, rep.passages)),
    )
    .unwrap_or_else(|(e, _)| panic!("{e}"));
    assert!(
        rep.passage_log.len() >= 3,
        "{} passages",
        rep.passage_log.len()
    );
    for (t, n) in &seen {
        let expected = rep
            .passage_log
            .iter()
            .filter(|r| r[0] <= t * (1.0 + 1e-9))
            .count();
        assert_eq!(
            *n, expected,
            "at t = {t}: {n} passages counted, {expected} passed"
        );
    }
    // Every passage was landed on by a step (and logged at that step's time).
    for r in &rep.passage_log {
        assert!(
            seen.iter().any(|(t, _)| (t - r[0]).abs() <= 1e-9 * t),
            "passage at {} is not a step time",
            r[0]
        );
    }
}

/// A step that the error estimate rejects leaves no trace: an adaptive run with rejected
/// steps ends in the same state as a replay of its accepted steps alone. The force-averaged
/// term α_f f(u_n, v_n) of generalized-α (with strain-rate damping) and the quadrature-point
/// history (viscoelastic) must be those of the committed state when a rejected step is
/// retried; the replay takes the same Newton iterations, so the two agree to round-off.
#[test]
fn rejected_steps_leave_no_trace() {
    use tread::material::{ViscoModel, Viscoelastic};
    let omega = 20.0;
    for visco in [false, true] {
        let build = || {
            let mut m = neo_hookean_annulus(2, 16);
            if visco {
                let law = Viscoelastic::new(ViscoModel::Convolution, 300.0, &[(0.6, 0.004)]);
                m.set_viscoelastic(law.unwrap());
            } else {
                m.strain_rate_damping = 0.5;
            }
            Transient::new(
                SolidSystem::new(m, "hub"),
                Scheme::generalized_alpha(GenAlpha::new(0.8)),
                spin_kinematics(omega, 0.05),
                false,
            )
        };
        let mut tr = build();
        let mut o = fixed_step_options(0.01, 0.08);
        o.adaptive = true;
        o.dt_min = 1e-6;
        o.dt_max = 0.02;
        o.error_tol = 1e-5;
        let mut accepted = Vec::new();
        let rep = integrate(
            &mut tr,
            &o,
            tight_newton_options(),
            LinearKind::Lu,
            |tr, _| accepted.push(tr.state.t),
        )
        .unwrap_or_else(|(e, _)| panic!("{e}"));
        assert!(
            rep.rejected > 0,
            "no step was rejected: the test needs some"
        );
        let mut replay = build();
        let mut newton =
            tread::solver::Newton::new(&replay.sys, LinearKind::Lu, tight_newton_options())
                .unwrap();
        for &t1 in &accepted {
            let dt = t1 - replay.state.t;
            replay.step(&mut newton, dt).unwrap();
        }
        let diff = |a: &[f64], b: &[f64]| {
            let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            a.iter()
                .zip(b)
                .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
                / scale
        };
        let (du, dv) = (
            diff(&tr.state.u, &replay.state.u),
            diff(&tr.state.v, &replay.state.v),
        );
        eprintln!(
            "viscoelastic {visco}: {} accepted, {} rejected steps; replay differs by {du:.2e} \
             (u), {dv:.2e} (v)",
            accepted.len(),
            rep.rejected
        );
        assert!(du < 1e-11 && dv < 1e-10, "u: {du:.3e}, v: {dv:.3e}");
    }
}
