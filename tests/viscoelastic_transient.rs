//! Viscoelastic history in the transient mode: the time-step tangent with history against
//! finite differences, the history committed only on convergence, the integrators' orders with
//! a viscoelastic material, and rolling to a steady state with extraction.

#[path = "common/fixtures.rs"]
mod fixtures;
use fixtures::*;

use tread::contact::{ContactModel, FacetRule, Friction, NormalCompliance};
use tread::driver::transient::ode_first_order::{integrate_first_order, OdeMethod, OdeTolerances};
use tread::driver::transient::{GenAlpha, Ramp, Scheme, TimeOptions, Transient};
use tread::material::{ViscoModel, Viscoelastic};
use tread::model::SolidSystem;
use tread::physics::SolidModel;
use tread::solver::{LinearKind, Newton, NewtonOptions, NonlinearSystem};

/// Neo-Hookean annulus (G∞ = 200) with a two-term overstress (instantaneous extra shear
/// modulus 150) of the given model.
fn visco_annulus(n_r: usize, n_theta: usize, model: ViscoModel) -> SolidModel {
    let mut m = neo_hookean_annulus(n_r, n_theta);
    m.set_viscoelastic(Viscoelastic::new(model, 300.0, &[(0.6, 0.004), (0.4, 0.05)]).unwrap());
    m
}

#[test]
fn time_step_tangent_with_history_matches_finite_differences() {
    for model in [ViscoModel::Convolution, ViscoModel::Multiplicative] {
        let m = visco_annulus(2, 12, model);
        let normal = NormalCompliance::new(2.0e4, 1.0, 5.0, 0.0);
        let cm = ContactModel::new(
            &m.mesh,
            1.95,
            3.0,
            normal,
            Friction::None,
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
        // A committed history with stress in it: commit a smooth deformation over a step.
        let nn = tr.sys.model.mesh.n_nodes();
        let mut x0 = tr.sys.x.clone();
        for n in 0..nn {
            let p = tr.sys.model.mesh.nodes[n];
            x0[2 * n] = 0.02 * p[1].sin() * p.norm();
            x0[2 * n + 1] = -0.03 * p[0].cos();
        }
        let dofs = tr.sys.dofs.clone();
        tr.sys.model.commit_history(&dofs, &x0, 0.003);
        assert!(tr.sys.model.history.data.iter().any(|v| v.abs() > 1e-3));
        tr.state.u.copy_from_slice(&x0);
        for n in 0..nn {
            let x = tr.sys.model.mesh.nodes[n];
            tr.state.v[2 * n] = -10.0 * x[1];
            tr.state.v[2 * n + 1] = 10.0 * x[0];
        }
        tr.dt = 1e-3;
        tr.sys.model.history_dt = 1e-3;
        for n in 0..nn {
            let x = tr.sys.model.mesh.nodes[n];
            tr.sys.x[2 * n] = x0[2 * n] + 1e-2 * x[1].sin();
            tr.sys.x[2 * n + 1] = x0[2 * n + 1] + 1e-2 * x[0].cos();
        }
        let saved = tr.sys.model.history.data.clone();
        assert!(tr.evaluate(true));
        let k = tr.sys.asm.to_dense();
        let kmax = k.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        let err = fixtures::fd_max_error(&mut tr, 1e-7, |i, j| k[i][j]);
        // Assembly only reads the history.
        assert_eq!(saved, tr.sys.model.history.data);
        eprintln!(
            "{model:?}: time-step tangent with history: max|K − K_fd|/max|K| = {:.2e}",
            err / kmax
        );
        assert!(err / kmax < 1e-6, "{model:?}: {:.3e}", err / kmax);
    }
}

#[test]
fn history_is_committed_only_on_convergence() {
    let m = visco_annulus(2, 12, ViscoModel::Convolution);
    let mut tr = Transient::new(
        SolidSystem::new(m, "hub"),
        Scheme::generalized_alpha(GenAlpha::new(0.8)),
        spin_kinematics(20.0, 0.02),
        false,
    );
    let dofs = tr.sys.dofs.clone();
    // A step whose Newton cannot converge (one iteration, unreachable tolerance) fails and
    // leaves the committed history (and the time) untouched.
    let mut failing = Newton::new(
        &tr.sys,
        LinearKind::Cholesky,
        NewtonOptions {
            tol: 1e-300,
            max_iterations: 1,
            line_search: false,
            ..Default::default()
        },
    )
    .unwrap();
    let mut good = Newton::new(&tr.sys, LinearKind::Cholesky, tight_newton_options()).unwrap();
    for _ in 0..5 {
        tr.step(&mut good, 1e-3).unwrap();
    }
    let before = tr.sys.model.history.data.clone();
    assert!(
        before.iter().any(|v| v.abs() > 1e-6),
        "no history after spin-up steps"
    );
    let t = tr.state.t;
    assert!(tr.step(&mut failing, 1e-3).is_err());
    assert_eq!(tr.sys.model.history.data, before);
    assert_eq!(tr.sys.model.history_dt, 0.0);
    assert_eq!(tr.state.t, t);
    // A converged step changes it, and equals a recomputation from the committed state.
    let x_before = tr.state.u.clone();
    tr.step(&mut good, 1e-3).unwrap();
    assert_ne!(tr.sys.model.history.data, before);
    let mut check = tr.sys.model.history.clone();
    check.data.copy_from_slice(&before);
    std::mem::swap(&mut tr.sys.model.history, &mut check);
    let x1 = tr.state.u.clone();
    tr.sys.model.commit_history(&dofs, &x1, 1e-3);
    std::mem::swap(&mut tr.sys.model.history, &mut check);
    assert_eq!(check.data, tr.sys.model.history.data);
    assert_ne!(x_before, x1);
}

/// u at t_end of a spin-up from rest with a viscoelastic material (relaxation times 4 ms and
/// 50 ms, comparable to the 30 ms ramp).
fn spin_up(scheme: Scheme, model: ViscoModel, dt: f64, t_end: f64) -> Vec<f64> {
    spin_up_fixed(visco_annulus(2, 16, model), scheme, dt, t_end)
}

#[test]
fn integrators_keep_their_order_with_history() {
    let t_end = 0.04;
    let mut table = Vec::new();
    for model in [ViscoModel::Convolution, ViscoModel::Multiplicative] {
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
            let errs = step_errors(|dt| spin_up(scheme.clone(), model, dt, t_end), dt0);
            let orders: Vec<f64> = errs.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
            eprintln!(
                "{model:?}, {name}: relative errors {:?}, observed orders {orders:.2?}",
                errs.iter().map(|e| format!("{e:.2e}")).collect::<Vec<_>>()
            );
            table.push((model, name, orders));
        }
    }
    for (model, name, orders) in table {
        let p = *orders.last().unwrap();
        assert!(
            (p - 2.0).abs() < 0.3,
            "{model:?}, {name}: observed order {p:.2}, expected 2"
        );
    }
}

/// The viscoelastic scene rolls to a steady state, the steady field is extracted, the summary
/// says the history term is on, and the hysteresis shows: the hub needs a driving torque (the
/// road is frictionless, so the torque is the moment of the contact pressure) and the contact
/// patch shifts upstream (material enters it from x1 < 0).
#[test]
fn viscoelastic_scene_rolls_to_steady_state() {
    let s = run_rolling(
        &scene_text("scenarios/viscoelastic_rolling.toml"),
        "viscoelastic_rolling",
        &[],
    );
    assert_eq!(s["terms"]["history"], true, "{}", s["terms"]);
    let r = &s["results"];
    assert_eq!(r["steady"], true, "{r}");
    let torque = r["hub_torque_passage_mean"].as_f64().unwrap();
    let load = -r["hub_force_y_passage_mean"].as_f64().unwrap();
    let (x0, x1) = (
        r["contact_x_min"].as_f64().unwrap(),
        r["contact_x_max"].as_f64().unwrap(),
    );
    let mu = torque / (load * 2.0);
    eprintln!("viscoelastic rolling: T/(P Ro) = {mu:.4}, contact [{x0:.3}, {x1:.3}]");
    assert!(mu > 0.005, "{mu}");
    assert!(
        -x0 > x1 + 0.01,
        "contact not shifted upstream: [{x0}, {x1}]"
    );
}

/// Modes without a history path refuse a viscoelastic material with a clear error instead of
/// silently dropping the overstress.
#[test]
fn unsupported_modes_refuse_viscoelastic_materials() {
    let section = "\n[material.viscoelastic]\nmodel = \"convolution\"\ngamma = 200.0\n\
                   prony = [[1.0, 0.03]]\n";
    for (file, mode) in [
        ("scenarios/spinning_neo_hookean.toml", "spinning"),
        ("scenarios/indentation_frictionless.toml", "static"),
    ] {
        let text = scene_text(file) + section;
        let scene = tread::io::Scene::from_toml_str(&text, file, &[])
            .unwrap_or_else(|e| panic!("{file}: {e}"));
        let e = tread::app::build_model(&scene).err().expect("refused");
        let msg = e.to_string();
        assert!(
            msg.contains("material.viscoelastic") && msg.contains(mode),
            "{msg}"
        );
    }
}

/// u at t_end of the viscoelastic spin-up with diffsol's BDF or SDIRK at relative tolerance
/// `rtol` (strain-rate damping η = 1 as in the first-order tests: BDF's high orders need it).
fn spin_up_first_order(
    method: OdeMethod,
    model: ViscoModel,
    viscous: bool,
    rtol: f64,
    t_end: f64,
) -> Vec<f64> {
    let mut m = if viscous {
        visco_annulus(2, 16, model)
    } else {
        neo_hookean_annulus(2, 16)
    };
    m.strain_rate_damping = 1.0;
    let mut tr = Transient::new(
        SolidSystem::new(m, "hub"),
        Scheme::generalized_alpha(GenAlpha::new(1.0)),
        spin_kinematics(20.0, 0.03),
        false,
    );
    let o = TimeOptions {
        dt: 1e-5,
        dt_min: 1e-12,
        dt_max: f64::INFINITY,
        adaptive: true,
        ..fixed_step_options(1e-5, t_end)
    };
    let tol = OdeTolerances {
        rtol,
        atol_u: rtol * 1e-2,
        atol_v: rtol * 0.2,
    };
    integrate_first_order(&mut tr, method, &o, tol, |_, _| {})
        .unwrap_or_else(|(e, _)| panic!("{e}"));
    assert!((tr.state.t - t_end).abs() < 1e-12);
    tr.state.u.clone()
}

/// The same spin-up with generalized-α (ρ∞ = 1) at a small fixed step, η = 1.
fn spin_up_reference(model: ViscoModel, dt: f64, t_end: f64) -> Vec<f64> {
    let mut m = visco_annulus(2, 16, model);
    m.strain_rate_damping = 1.0;
    spin_up_fixed(m, Scheme::generalized_alpha(GenAlpha::new(1.0)), dt, t_end)
}

/// BDF and SDIRK carry the history: as their tolerance tightens they converge to the
/// generalized-α solution at a small step (second order, independent code path: the one-step
/// Newmark loop), and the overstress matters (the elastic solution is far from both).
#[test]
fn first_order_integrators_carry_the_history() {
    let t_end = 0.04;
    for model in [ViscoModel::Convolution, ViscoModel::Multiplicative] {
        let reference = spin_up_reference(model, 1e-3 / 64.0, t_end);
        let rel = |u: &[f64]| relative_l2(u, &reference);
        let elastic = rel(&spin_up_first_order(
            OdeMethod::Bdf,
            model,
            false,
            1e-7,
            t_end,
        ));
        for method in [OdeMethod::Bdf, OdeMethod::Esdirk34] {
            let errs: Vec<f64> = [1e-4, 1e-6, 1e-8]
                .iter()
                .map(|&r| rel(&spin_up_first_order(method, model, true, r, t_end)))
                .collect();
            eprintln!(
                "{model:?}, {}: errors against generalized-α {:?} (rtol 1e-4, 1e-6, 1e-8); \
                 the elastic solution is {elastic:.2e} away",
                method.name(),
                errs.iter().map(|e| format!("{e:.2e}")).collect::<Vec<_>>()
            );
            assert!(errs[2] < 2e-4, "{model:?} {}: {errs:?}", method.name());
            assert!(errs[2] < errs[0], "{model:?} {}: {errs:?}", method.name());
            assert!(elastic > 50.0 * errs[2], "{elastic:e} vs {errs:?}");
        }
    }
}

/// The energy balance of steady viscoelastic rolling, body against hub: on a frictionless road
/// without normal damping, the power the hub feeds, T ω, goes into the overstress's dissipation
/// (`results.viscous_energy`, summed over the quadrature points) and the integrator's numerical
/// dissipation (generalized-α with ρ∞ = 0.8, small at these steps); nothing else dissipates.
/// The dissipation rate over [1.6, 2.0] s, once rolling is steady, must match the hub power to
/// 1 %, and neither model may create energy.
#[test]
fn viscous_dissipation_balances_the_hub_power_in_steady_rolling() {
    let base = scene_text("scenarios/viscoelastic_rolling.toml");
    let omega = 10.0;
    for model in ["convolution", "multiplicative"] {
        let text = base.replace("model = \"convolution\"", &format!("model = \"{model}\""));
        let run = |t_end: f64| {
            let t = format!("time.t_end={t_end}");
            let s = run_rolling(
                &text,
                &format!("viscous_balance_{model}"),
                &[
                    "contact.b_n=0",
                    "time.adaptive=false",
                    "time.dt=5e-4",
                    "time.stop_at_steady=false",
                    &t,
                ],
            );
            s["results"].clone()
        };
        let (a, b) = (run(1.6), run(2.0));
        let ve = |r: &serde_json::Value, k: &str| r["viscous_energy"][k].as_f64().unwrap();
        for r in [&a, &b] {
            assert_eq!(r["viscous_energy"]["energy_created"], false, "{r}");
            assert!(ve(r, "min_dissipated") >= 0.0, "{r}");
        }
        let dt = b["final_time"].as_f64().unwrap() - a["final_time"].as_f64().unwrap();
        let rate = (ve(&b, "dissipated") - ve(&a, "dissipated")) / dt;
        let torque = 0.5
            * (a["hub_torque_passage_mean"].as_f64().unwrap()
                + b["hub_torque_passage_mean"].as_f64().unwrap());
        let power = torque * omega;
        let rel = (rate - power) / power;
        eprintln!(
            "{model}: viscous dissipation rate {rate:.5} against hub power T ω = {power:.5} (rel {rel:+.2e}); stored {:.4}",
            ve(&b, "stored")
        );
        assert!(
            power > 0.0 && rel.abs() < 0.01,
            "{model}: {rate} vs {power}"
        );
    }
}
