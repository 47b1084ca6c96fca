//! diffsol's BDF and SDIRK on the first-order form y = (u, v) of the transient model
//! (src/driver/transient/ode_first_order.rs): Jacobian against finite differences of the
//! right-hand side, convergence against the tolerance (observed orders), objectivity of rigid
//! spinning, clean failures.

#[path = "common/fixtures.rs"]
mod fixtures;
use fixtures::*;

use tread::contact::laws::CoulombTanh;
use tread::contact::{ContactModel, FacetRule, Friction, NormalCompliance};
use tread::driver::transient::ode_first_order::{
    integrate_first_order, FirstOrder, OdeMethod, OdeTolerances,
};
use tread::driver::transient::{GenAlpha, Ramp, Scheme, TimeOptions, Transient, TransientReport};
use tread::model::SolidSystem;
use tread::physics::PressureMode;
use tread::solver::{LinearKind, SolveError};

fn opts(dt: f64, t_end: f64) -> TimeOptions {
    TimeOptions {
        dt,
        dt_min: 1e-12,
        dt_max: f64::INFINITY,
        t_end,
        adaptive: true,
        error_tol: 1e-4,
        steady_tol: 1e-12,
        stop_at_steady: false,
        max_steps: 1_000_000,
        lumped: false,
        land_on_passages: false,
    }
}

fn placeholder() -> Scheme {
    Scheme::generalized_alpha(GenAlpha::new(1.0))
}

fn tol(rtol: f64) -> OdeTolerances {
    // Lengths ~ 1 in, speeds ~ 20 in/s.
    OdeTolerances {
        rtol,
        atol_u: rtol * 1e-2,
        atol_v: rtol * 0.2,
    }
}

#[test]
fn first_order_jacobian_matches_finite_differences() {
    // Contact with normal damping and Coulomb friction, strain-rate damping, a rotated and
    // perturbed state with rigid-rotation velocities plus a perturbation, t inside the ramps (so
    // the hub's prescribed motion and the road move).
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
    let mut kin = spin_kinematics(10.0, 0.02);
    kin.disp = Some(Ramp {
        target: 0.08,
        time: 0.02,
    });
    kin.h_touch = 2.0;
    kin.v0 = Ramp {
        target: 19.0,
        time: 0.02,
    };
    let mut tr = Transient::new(sys, placeholder(), kin, false);
    let t = 0.015;
    let phi = tr.kin.phi(t);
    let (s, c) = phi.sin_cos();
    for n in 0..tr.sys.model.mesh.n_nodes() {
        let x = tr.sys.model.mesh.nodes[n];
        tr.state.u[2 * n] = c * x[0] - s * x[1] - x[0] + 1e-3 * x[1].sin();
        tr.state.u[2 * n + 1] = s * x[0] + c * x[1] - x[1] + 1e-3 * x[0].cos();
        let p = x + tread::math::Vec2::new(tr.state.u[2 * n], tr.state.u[2 * n + 1]);
        tr.state.v[2 * n] = -8.0 * p[1] + 0.3 * p[0].sin();
        tr.state.v[2 * n + 1] = 8.0 * p[0] + 0.2 * p[1].cos();
    }
    let fo = FirstOrder::new(&mut tr).unwrap_or_else(|e| panic!("{e}"));
    let y = fo.initial_state().to_vec();
    let ns = fo.n_states();
    let (cp, ri) = fo.jacobian_pattern();
    let (cp, ri) = (cp.to_vec(), ri.to_vec());
    let mut vals = vec![0.0; ri.len()];
    fo.eval_jacobian(t, &y, &mut vals);
    let mut dense = vec![vec![0.0; ns]; ns];
    for j in 0..ns {
        for p in cp[j]..cp[j + 1] {
            dense[ri[p]][j] = vals[p];
        }
    }
    let mut f0 = vec![0.0; ns];
    assert!(fo.eval_rhs(t, &y, &mut f0));
    let jmax = vals.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let (mut fp, mut fm) = (vec![0.0; ns], vec![0.0; ns]);
    let mut yp = y.clone();
    let (mut err, mut outside) = (0.0f64, 0.0f64);
    for j in 0..ns {
        let h = 1e-7 * (1.0 + y[j].abs());
        yp[j] = y[j] + h;
        assert!(fo.eval_rhs(t, &yp, &mut fp));
        yp[j] = y[j] - h;
        assert!(fo.eval_rhs(t, &yp, &mut fm));
        yp[j] = y[j];
        for i in 0..ns {
            let fd = (fp[i] - fm[i]) / (2.0 * h);
            err = err.max((fd - dense[i][j]).abs());
            if !cp[j..j + 1].is_empty() && !ri[cp[j]..cp[j + 1]].contains(&i) {
                outside = outside.max(fd.abs());
            }
        }
    }
    // Contact is active in this state.
    eprintln!(
        "first-order Jacobian ({ns} states, {} nonzeros): max|J − J_fd| / max|J| = {:.2e}, largest FD entry outside the pattern {:.2e}",
        vals.len(),
        err / jmax,
        outside / jmax
    );
    assert!(
        err / jmax < 1e-6,
        "Jacobian differs from FD: {:.3e}",
        err / jmax
    );
    assert!(
        outside / jmax < 1e-9,
        "pattern misses entries: {:.3e}",
        outside / jmax
    );
    // The mass: identity block, then M_ff (symmetric, positive diagonal).
    let (mcp, mri) = fo.mass_pattern();
    let mv = fo.mass_values();
    let n = ns / 2;
    for j in 0..n {
        assert_eq!(&mri[mcp[j]..mcp[j + 1]], &[j]);
        assert_eq!(mv[mcp[j]], 1.0);
    }
    drop(fo);
    let in_contact = tr
        .sys
        .contact_samples()
        .iter()
        .filter(|s| s.delta > 0.0)
        .count();
    assert!(
        in_contact > 3,
        "no contact in the test state ({in_contact})"
    );
}

/// Spin-up from rest (ramp to 20 rad/s over 0.03 s, no contact), integrated to t_end with
/// `method` at relative tolerance `rtol`: (free-dof u at t_end, report).
fn spin_up(method: OdeMethod, rtol: f64, t_end: f64) -> (Vec<f64>, TransientReport) {
    // Strain-rate damping as in the scenes (η = 1): without any damping the high mesh modes sit
    // on the imaginary axis, where BDF of order 3–5 is not stable, and diffsol's error control
    // then holds its step near the period of the highest mode (see the rigid-spin test).
    let mut m = neo_hookean_annulus(2, 16);
    m.strain_rate_damping = 1.0;
    let mut tr = Transient::new(
        SolidSystem::new(m, "hub"),
        placeholder(),
        spin_kinematics(20.0, 0.03),
        false,
    );
    let rep = integrate_first_order(&mut tr, method, &opts(1e-5, t_end), tol(rtol), |_, _| {})
        .unwrap_or_else(|(e, _)| panic!("{e}"));
    assert!(
        (tr.state.t - t_end).abs() < 1e-12,
        "stopped at {} not {t_end}",
        tr.state.t
    );
    (tr.state.u.clone(), rep)
}

fn rel(a: &[f64], b: &[f64]) -> f64 {
    let n = b.iter().map(|v| v * v).sum::<f64>().sqrt();
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
        / n
}

/// Least-squares slope of log y against log x.
fn slope(x: &[f64], y: &[f64]) -> f64 {
    let lx: Vec<f64> = x.iter().map(|v| v.ln()).collect();
    let ly: Vec<f64> = y.iter().map(|v| v.ln()).collect();
    let (mx, my) = (
        lx.iter().sum::<f64>() / lx.len() as f64,
        ly.iter().sum::<f64>() / ly.len() as f64,
    );
    let num: f64 = lx.iter().zip(&ly).map(|(a, b)| (a - mx) * (b - my)).sum();
    let den: f64 = lx.iter().map(|a| (a - mx) * (a - mx)).sum();
    num / den
}

#[test]
fn bdf_and_sdirk_converge_with_the_tolerance() {
    let t_end = 0.04;
    let tols = [1e-3, 1e-4, 1e-5, 1e-6];
    // A common reference: ESDIRK34 at a very tight tolerance, checked against BDF at the same.
    let (reference, _) = spin_up(OdeMethod::Esdirk34, 1e-11, t_end);
    let (ref_bdf, _) = spin_up(OdeMethod::Bdf, 1e-11, t_end);
    let ref_gap = rel(&ref_bdf, &reference);
    eprintln!("references (rtol 1e-11): ESDIRK34 vs BDF differ by {ref_gap:.2e}");
    assert!(ref_gap < 1e-7, "the two references disagree: {ref_gap:.3e}");
    eprintln!("method          rtol     steps  Newton  rejected   rel. error   order(steps)");
    for (method, min_order) in [
        (OdeMethod::TrBdf2, 1.6),
        (OdeMethod::Esdirk34, 2.4),
        (OdeMethod::Bdf, 3.0),
    ] {
        let mut errs: Vec<f64> = Vec::new();
        let mut steps: Vec<f64> = Vec::new();
        for &r in &tols {
            let (u, rep) = spin_up(method, r, t_end);
            let e = rel(&u, &reference);
            let p = match (errs.last(), steps.last()) {
                (Some(&e0), Some(&s0)) => {
                    format!("{:.2}", -(e / e0).ln() / (rep.steps as f64 / s0).ln())
                }
                _ => "-".into(),
            };
            eprintln!(
                "{:<15} {r:.0e}  {:>6}  {:>6}  {:>8}   {e:.3e}    {p}",
                method.name(),
                rep.steps,
                rep.newton_iterations,
                rep.rejected
            );
            errs.push(e);
            steps.push(rep.steps as f64);
        }
        let order = -slope(&steps, &errs);
        let per_tol = slope(&tols, &errs);
        eprintln!(
            "{}: observed order (error vs steps, least squares) {order:.2}; error ∝ tol^{per_tol:.2} (classical order {})",
            method.name(),
            method.order()
        );
        for w in errs.windows(2) {
            assert!(
                w[1] < 0.5 * w[0],
                "{}: error did not decrease: {errs:?}",
                method.name()
            );
        }
        for (e, t) in errs.iter().zip(&tols) {
            assert!(
                *e < 100.0 * t,
                "{}: error {e:.3e} at rtol {t:.0e}",
                method.name()
            );
        }
        assert!(
            order > min_order,
            "{}: observed order {order:.2} below {min_order}",
            method.name()
        );
    }
}

#[test]
fn rigid_spinning_with_bdf_is_objective() {
    // The discrete rigid-spin equilibrium rotated rigidly is an exact solution of the
    // semi-discrete equations: integrate three revolutions with BDF and check that the strain
    // does not change (to the integrator's tolerance) and the energy is conserved.
    let omega = 20.0;
    let period = 2.0 * std::f64::consts::PI / omega;
    let mut m = neo_hookean_annulus(2, 32);
    // Strain-rate damping (η = 1, as in the scenes) does not act on a rigid rotation (Ė = 0) but
    // damps the high mesh modes: undamped (η = 0) the same run passes with 16× more steps
    // (20935 for 3 revolutions, max strain change 8e-5), because BDF of order 3–5 is unstable
    // on part of the imaginary axis and diffsol's error control holds the step near the period
    // of the highest mode.
    m.strain_rate_damping = 1.0;
    let mut tr = Transient::new(
        SolidSystem::new(m, "hub"),
        placeholder(),
        spin_kinematics(omega, 0.0),
        false,
    );
    tr.start_rigid_spin(omega, LinearKind::Lu, None)
        .unwrap_or_else(|e| panic!("{e}"));
    let e0 = tr.cell_strains(&tr.state.u);
    let emax = e0.iter().map(|e| e.norm()).fold(0.0, f64::max);
    let energy = |tr: &Transient| {
        tr.kinetic_energy(&tr.state.v) + tr.sys.model.strain_energy(&tr.sys.dofs, &tr.state.u)
    };
    let en0 = energy(&tr);
    let mut ds = 0.0f64;
    let mut de = 0.0f64;
    let revs = 3.0;
    let rep = integrate_first_order(
        &mut tr,
        OdeMethod::Bdf,
        &opts(1e-4, revs * period),
        tol(1e-7),
        |tr, _| {
            let e = tr.cell_strains(&tr.state.u);
            let d = e
                .iter()
                .zip(&e0)
                .map(|(a, b)| (a - b).norm())
                .fold(0.0, f64::max);
            ds = ds.max(d / emax);
            de = de.max(((energy(tr) - en0) / en0).abs());
        },
    )
    .unwrap_or_else(|(e, _)| panic!("{e}"));
    eprintln!(
        "rigid spin, BDF rtol 1e-7, {revs} revolutions: {} steps ({} rejected), max strain change {ds:.2e} (of max strain {emax:.2e}), max energy change {de:.2e}",
        rep.steps, rep.rejected
    );
    assert!((rep.revolutions - revs).abs() < 1e-9);
    assert!(ds < 1e-4, "rigid rotation strained the body: {ds:.3e}");
    assert!(de < 1e-5, "energy changed: {de:.3e}");
}

#[test]
fn failures_are_errors_not_panics() {
    // (a) A minimum step far above what the error control needs: diffsol gives up; the driver's
    // state is the last accepted step (here the start).
    let mut tr = Transient::new(
        SolidSystem::new(neo_hookean_annulus(1, 8), "hub"),
        placeholder(),
        spin_kinematics(20.0, 0.03),
        false,
    );
    let mut o = opts(1e-2, 0.04);
    o.dt_min = 1e-2;
    let res = integrate_first_order(&mut tr, OdeMethod::Bdf, &o, tol(1e-10), |_, _| {});
    match res {
        Err((SolveError::Integrator { t, message }, rep)) => {
            eprintln!(
                "expected failure at t = {t}: {message} (after {} steps)",
                rep.steps
            );
            assert!((tr.state.t - rep.final_time).abs() < 1e-15);
            assert!(tr.state.u.iter().all(|v| v.is_finite()));
        }
        Err((e, _)) => panic!("unexpected error {e}"),
        Ok(r) => panic!("expected a failure, got {} steps", r.steps),
    }
    // (b) Cell pressures (exact incompressibility) make the system differential-algebraic.
    let mut m = neo_hookean_annulus(1, 8);
    m.pressure = PressureMode::Exact { p0: 0.0 };
    let mut tr = Transient::new(
        SolidSystem::new(m, "hub"),
        placeholder(),
        spin_kinematics(20.0, 0.03),
        false,
    );
    let res = integrate_first_order(
        &mut tr,
        OdeMethod::Esdirk34,
        &opts(1e-4, 0.01),
        tol(1e-4),
        |_, _| {},
    );
    match res {
        Err((SolveError::Integrator { message, .. }, _)) => {
            assert!(message.contains("generalized_alpha"), "{message}")
        }
        _ => panic!("a DAE must be rejected"),
    }
}

/// The rotated rigid-spin equilibrium satisfies B ẏ = F(y, t) at any t: the hub's prescribed
/// rotation enters the right-hand side consistently (positions, velocities, and with the
/// consistent mass the inertia coupling M_fh a_h(t)).
#[test]
fn rotating_rigid_spin_is_an_exact_solution_of_the_first_order_system() {
    let omega = 20.0;
    let mut tr = Transient::new(
        SolidSystem::new(neo_hookean_annulus(2, 32), "hub"),
        placeholder(),
        spin_kinematics(omega, 0.0),
        false,
    );
    tr.start_rigid_spin(omega, LinearKind::Cholesky, None)
        .unwrap();
    let nn = tr.sys.model.mesh.n_nodes();
    let mesh_nodes = tr.sys.model.mesh.nodes.clone();
    let (u0, v0, a0) = (tr.state.u.clone(), tr.state.v.clone(), tr.state.a.clone());
    let eq = tr.sys.dofs.eq.clone();
    let fo = FirstOrder::new(&mut tr).unwrap();
    let ns = fo.n_states();
    let n = ns / 2;
    for &t in &[0.0, 0.01, 0.1] {
        let (s, c) = (omega * t).sin_cos();
        // full rotated vectors
        let mut uf = vec![0.0; 2 * nn];
        let mut vf = vec![0.0; 2 * nn];
        let mut af = vec![0.0; 2 * nn];
        for k in 0..nn {
            let x = mesh_nodes[k] + tread::math::Vec2::new(u0[2 * k], u0[2 * k + 1]);
            uf[2 * k] = c * x[0] - s * x[1] - mesh_nodes[k][0];
            uf[2 * k + 1] = s * x[0] + c * x[1] - mesh_nodes[k][1];
            vf[2 * k] = c * v0[2 * k] - s * v0[2 * k + 1];
            vf[2 * k + 1] = s * v0[2 * k] + c * v0[2 * k + 1];
            af[2 * k] = c * a0[2 * k] - s * a0[2 * k + 1];
            af[2 * k + 1] = s * a0[2 * k] + c * a0[2 * k + 1];
        }
        let mut y = vec![0.0; ns];
        let mut aex = vec![0.0; n];
        for (d, &e) in eq.iter().enumerate() {
            if e != u32::MAX {
                y[e as usize] = uf[d];
                y[n + e as usize] = vf[d];
                aex[e as usize] = af[d];
            }
        }
        let dy = fo.consistent_rate(t, &y).unwrap();
        let amax = aex.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let err = dy[n..]
            .iter()
            .zip(&aex)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        eprintln!("t = {t}: max|v̇ − a_exact| / max|a| = {:.3e}", err / amax);
        assert!(err / amax < 1e-9, "{:.3e}", err / amax);
    }
}
