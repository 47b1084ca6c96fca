//! Static indentation of the hollow cylinder by the rigid road.

#[path = "common/fixtures.rs"]
mod fixtures;

use tread::app::{run, RunOptions};
use tread::contact::laws::CoulombTanh;
use tread::contact::{ContactModel, FacetRule, Friction, NormalCompliance};
use tread::driver::indentation::{results, solve_indentation, IndentationResults};
use tread::io::Scene;
use tread::material::{Material, MooneyRivlin, NeoHookean};
use tread::mesh::{annulus, AnnulusSpec};
use tread::model::system::Loading;
use tread::model::SolidSystem;
use tread::physics::{PressureMode, SolidModel};
use tread::solver::stepping::{StepOptions, StepReport};
use tread::solver::{LinearKind, NewtonOptions};

struct Case {
    ri: f64,
    ro: f64,
    n_r: usize,
    n_theta: usize,
    grading_r: f64,
    grading_theta: f64,
    material: Material,
    c_n: f64,
    friction: Friction,
    rule: FacetRule,
    loading: Loading,
    steps: usize,
}

fn paper(n_r: usize, n_theta: usize, friction: Friction) -> Case {
    Case {
        ri: 1.0,
        ro: 2.0,
        n_r,
        n_theta,
        grading_r: 1.0,
        grading_theta: 0.6,
        material: MooneyRivlin::new(80.0, 20.0, 2000.0).into(),
        c_n: 2.0e5,
        friction,
        rule: FacetRule::Gauss(4),
        loading: Loading::Indent {
            h_touch: 2.0,
            disp: 0.1,
        },
        steps: 4,
    }
}

fn solve(c: &Case) -> (IndentationResults, StepReport, usize) {
    let mesh = annulus(&AnnulusSpec {
        ri: c.ri,
        ro: c.ro,
        n_r: c.n_r,
        n_theta: c.n_theta,
        degree: 2,
        grading_r: c.grading_r,
        grading_theta: c.grading_theta,
    });
    let model = SolidModel::new(mesh, c.material, 1.0, PressureMode::None);
    let (h0, load) = match c.loading {
        Loading::Load { .. } => (c.ro - 1e-3 * c.ro, Some(0.0)),
        _ => (c.ro, None),
    };
    let cm = ContactModel::new(
        &model.mesh,
        h0,
        0.0,
        NormalCompliance::new(c.c_n, 1.0, 0.0, 0.0),
        c.friction,
        c.rule,
        load,
    );
    let mut sys = SolidSystem::with_contact(model, cm);
    sys.loading = c.loading;
    let mut rep = StepReport::default();
    let opts = NewtonOptions {
        tol: 1e-10,
        max_iterations: 30,
        ..Default::default()
    };
    let kind = if matches!(c.friction, Friction::None) {
        LinearKind::Cholesky
    } else {
        LinearKind::Lu
    };
    solve_indentation(
        &mut sys,
        kind,
        opts,
        &StepOptions {
            initial_steps: c.steps,
            max_cutbacks: 8,
            verbose: false,
        },
        &mut rep,
        &mut (),
    )
    .expect("indentation converges");
    (results(&sys, c.ro), rep, sys.n_dofs())
}

#[test]
fn frictionless_and_frictional_indentation_are_symmetric() {
    for (name, fr) in [
        ("frictionless", Friction::None),
        (
            "Coulomb μ = 0.3",
            Friction::CoulombTanh(CoulombTanh::new(0.3, 0.01)),
        ),
    ] {
        let (r, rep, dofs) = solve(&paper(4, 64, fr));
        eprintln!(
            "{name}: dofs {dofs}, Fy = {:.6}, Fx = {:.3e}, torque = {:.3e}, patch [{:.5}, {:.5}], p_max = {:.3}, DISP = {:.5}, {} its, {:.2} facets/iteration of {}",
            r.hub_force_y, r.hub_force_x, r.hub_torque, r.contact_x_min, r.contact_x_max, r.max_pressure, r.penetration, rep.total_iterations, r.contact_facets_per_iteration, r.contact_facets_total
        );
        assert!(r.hub_force_y < 0.0, "the hub must push the body down");
        let scale = r.hub_force_y.abs();
        assert!(
            r.hub_force_x.abs() < 1e-8 * scale,
            "{name}: Fx = {}",
            r.hub_force_x
        );
        assert!(
            r.hub_torque.abs() < 1e-8 * scale * 2.0,
            "{name}: torque = {}",
            r.hub_torque
        );
        assert!(
            (r.contact_x_min + r.contact_x_max).abs() < 1e-8,
            "{name}: patch not symmetric"
        );
        // Equilibrium: the hub reaction balances the contact force.
        assert!((r.hub_force_y + r.contact_force_y).abs() < 1e-7 * scale);
        assert!(r.contact_facets_per_iteration < 0.5 * r.contact_facets_total as f64);
    }
}

#[test]
fn hub_force_converges_under_refinement() {
    let levels = [(2usize, 32usize), (4, 64), (8, 128)];
    let f: Vec<f64> = levels
        .iter()
        .map(|&(n_r, n_t)| solve(&paper(n_r, n_t, Friction::None)).0.hub_force_y)
        .collect();
    let d1 = (f[1] - f[0]).abs();
    let d2 = (f[2] - f[1]).abs();
    let rate = (d1 / d2).log2();
    eprintln!("hub force Fy on meshes {levels:?}: {f:?}; successive differences {d1:.4e}, {d2:.4e}; observed rate {rate:.2}");
    assert!(d2 < 0.5 * d1, "hub force does not converge");
    assert!(
        d2 / f[2].abs() < 5e-3,
        "relative change on the finest pair {:.3e}",
        d2 / f[2].abs()
    );
}

#[test]
fn load_control_reproduces_displacement_control() {
    let (rd, _, _) = solve(&paper(4, 64, Friction::None));
    let mut c = paper(4, 64, Friction::None);
    c.loading = Loading::Load {
        load: -rd.hub_force_y,
    };
    let (rl, _, _) = solve(&c);
    eprintln!(
        "displacement control: DISP = {:.6}, Fy = {:.6}; load control P = {:.6}: DISP = {:.6}",
        rd.penetration, rd.hub_force_y, -rd.hub_force_y, rl.penetration
    );
    assert!(
        (rl.penetration - 0.1).abs() < 1e-6,
        "penetration {}",
        rl.penetration
    );
    assert!((rl.hub_force_y - rd.hub_force_y).abs() < 1e-6 * rd.hub_force_y.abs());
}

#[test]
fn nearly_solid_cylinder_matches_plane_strain_hertz() {
    // R = 1, Ri = 0.1 (bonded hub), neo-Hookean μ = 1, ν = 0.3; a rigid flat road. Hertz (plane
    // strain, rigid indenter): a² = 4 P R / (π E*), E* = E / (1 − ν²). The half-width is taken from
    // the pressure distribution's second moment (elliptical p: ⟨x²⟩ = a²/4), which does not
    // depend on where the mesh resolves the patch edge.
    let (mu, nu) = (1.0, 0.3);
    let lambda = 2.0 * mu * nu / (1.0 - 2.0 * nu);
    let e_star = 2.0 * mu * (1.0 + nu) / (1.0 - nu * nu);
    let mut errs = Vec::new();
    for (disp, n_r, n_t, rule) in [
        (5e-4, 10usize, 128usize, FacetRule::Gauss(4)),
        (5e-4, 14, 192, FacetRule::Gauss(4)),
        (5e-4, 10, 128, FacetRule::Lobatto(4)),
        (5e-4, 14, 192, FacetRule::Lobatto(4)),
        (5e-4, 14, 192, FacetRule::Lobatto(3)),
    ] {
        let c = Case {
            ri: 0.1,
            ro: 1.0,
            n_r,
            n_theta: n_t,
            grading_r: 0.08,
            grading_theta: 0.93,
            material: NeoHookean::new(mu, lambda).into(),
            c_n: 1e5 * e_star,
            friction: Friction::None,
            rule,
            loading: Loading::Indent { h_touch: 1.0, disp },
            steps: 2,
        };
        let (r, _, dofs) = solve(&c);
        let p = -r.hub_force_y;
        let a_hertz = (4.0 * p / (std::f64::consts::PI * e_star)).sqrt();
        let a = r.contact_half_width_moment;
        let err = (a - a_hertz).abs() / a_hertz;
        eprintln!(
            "Hertz {rule:?}: DISP {disp:.1e}, dofs {dofs}: P = {p:.6e}, a (2nd moment) = {a:.5e}, patch [{:.5e}, {:.5e}], a_Hertz = {a_hertz:.5e}, rel err {err:.2e}; p_max = {:.4e} vs Hertz p0 = {:.4e}",
            r.contact_x_min,
            r.contact_x_max,
            r.max_pressure,
            2.0 * p / (std::f64::consts::PI * a_hertz)
        );
        errs.push((
            err,
            r.max_pressure / (2.0 * p / (std::f64::consts::PI * a_hertz)) - 1.0,
        ));
    }
    // Tolerance: a/R ≈ 0.013 here, so finite-strain and finite-radius (non-half-space) effects
    // are O(a/R) ≈ 1–2 %; the penalty penetration p0/c_n is 1e-5 of the indentation depth.
    assert!(
        errs.iter().all(|&(e, _)| e < 0.025),
        "Hertz half-width errors {errs:?}"
    );
    assert!(
        errs[1].0 < errs[0].0 && errs[3].0 < errs[2].0,
        "no convergence: {errs:?}"
    );
    // Facet quadrature: Lobatto(4) gives a peak pressure within 2 % of Hertz's p0 already on the
    // coarse mesh, Gauss(4) overshoots there (spurious oscillation at the patch edge).
    assert!(
        errs[2].1.abs() < 0.02 && errs[3].1.abs() < 0.02,
        "Lobatto peak pressure {errs:?}"
    );
    assert!(
        errs[0].1 > errs[2].1,
        "Gauss smoother than Lobatto? {errs:?}"
    );
}

/// Run `scenarios/indentation_frictionless.toml` with `--set` overrides through the program's
/// driver; returns (converged, hub_force_y, contact_force_y, contact_x_max, Newton iterations)
/// from summary.json, or the error text.
fn run_frictionless(set: &[String]) -> Result<(f64, f64, f64, u64), String> {
    let text = fixtures::scene_text("scenarios/indentation_frictionless.toml");
    let mut set = set.to_vec();
    set.push("output.sinks=[\"summary\"]".into());
    let scene =
        Scene::from_toml_str(&text, "indentation_frictionless", &set).map_err(|e| e.to_string())?;
    let tag: String = set
        .concat()
        .chars()
        .filter(|c| c.is_ascii_alphanumeric())
        .collect();
    let out = std::env::temp_dir().join(format!("tread-stiff-{}-{tag}", std::process::id()));
    let o = run(
        &scene,
        &RunOptions {
            out_dir: out.clone(),
            verbose: false,
            quiet: true,
        },
    );
    let _ = std::fs::remove_dir_all(&out);
    let o = o.map_err(|e| e.to_string())?;
    let r = &o.summary["results"];
    let num = |k: &str| r[k].as_f64().unwrap_or(f64::NAN);
    Ok((
        num("hub_force_y"),
        num("contact_force_y"),
        num("contact_x_max"),
        o.summary["newton_iterations"].as_u64().unwrap_or(0),
    ))
}

/// A penalty c_n = 1e12 (5e9 G / wall) makes the first residual of every load step a huge
/// penalty force (the road moved into the body), so a convergence test relative to it, or to a
/// Hertz estimate c_n DISP √(2 Ro DISP) ≈ 6e10, accepted a state off by 1–3 % in hub force and
/// 10–20 % in contact patch (the stress matrix's "extreme c_n=1e12"). At any tolerance the
/// answer must be the equilibrium one: hub reaction and contact force balance, and the result
/// agrees with a solve at a tolerance far below the residual's round-off floor.
#[test]
fn stiff_penalty_converges_to_equilibrium_not_falsely() {
    let base = |tol: &str| {
        vec![
            "contact.c_n=1e12".to_string(),
            "mesh.n_r=4".into(),
            "mesh.n_theta=64".into(),
            format!("solver.tolerance={tol}"),
        ]
    };
    let (fy_ref, fc_ref, x_ref, it_ref) =
        run_frictionless(&base("1e-13")).unwrap_or_else(|e| panic!("tol 1e-13: {e}"));
    let scale = fy_ref.abs();
    eprintln!("tol 1e-13: Fy = {fy_ref:.9}, contact Fy = {fc_ref:.9}, patch x_max = {x_ref:.7}, {it_ref} its");
    assert!(
        fy_ref < 0.0 && (fy_ref + fc_ref).abs() <= 1e-6 * scale,
        "reference out of equilibrium"
    );
    for tol in ["1e-8", "1e-10"] {
        let (fy, fc, x, it) =
            run_frictionless(&base(tol)).unwrap_or_else(|e| panic!("tol {tol}: {e}"));
        let err = (fy - fy_ref).abs() / scale;
        let imbalance = (fy + fc).abs() / scale;
        let patch = (x - x_ref).abs() / x_ref;
        eprintln!("tol {tol}: Fy = {fy:.9} (rel. err {err:.2e}), hub + contact {imbalance:.2e}, patch err {patch:.2e}, {it} its");
        assert!(err <= 1e-6, "tol {tol}: hub force off by {err:.3e}");
        assert!(
            imbalance <= 1e-6,
            "tol {tol}: hub and contact force differ by {imbalance:.3e}"
        );
        assert!(patch <= 1e-6, "tol {tol}: contact patch off by {patch:.3e}");
    }
}
