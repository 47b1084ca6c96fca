//! Steady θ-referential rolling: tangent against finite differences with friction,
//! normal damping and strain-rate damping; no contact = steady spinning exactly; frictionless
//! rolling symmetric with zero torque; free rolling solves torque = 0; continuation in ω.

#[path = "common/tempdir.rs"]
mod tempdir;

use tread::assembly::FIXED;
use tread::contact::laws::CoulombTanh;
use tread::contact::{ContactModel, FacetRule, Friction, NormalCompliance};
use tread::driver::steady::{solve_torque, SteadyRolling};
use tread::driver::steady_report::SolveReports;
use tread::driver::steady_run;
use tread::io::Scene;
use tread::material::{Material, MooneyRivlin};
use tread::mesh::{annulus, AnnulusSpec};
use tread::model::SolidSystem;
use tread::physics::{PressureMode, SolidModel};
use tread::solver::{LinearKind, Newton, NonlinearSystem};

const ODEN: &str = include_str!("../scenarios/oden_hollow_cylinder.toml");
const FRICTIONLESS: &str = include_str!("../scenarios/rolling_frictionless.toml");

fn scene(text: &str, set: &[&str]) -> Scene {
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    Scene::from_toml_str(text, "test", &set).unwrap_or_else(|e| panic!("{e}"))
}

fn steady_solution(text: &str, set: &[&str]) -> (Scene, SteadyRolling) {
    let (sc, st, _) = solved(text, set);
    (sc, st)
}

/// [`steady_solution`] with what the solve reported.
fn solved(text: &str, set: &[&str]) -> (Scene, SteadyRolling, SolveReports) {
    let sc = scene(text, set);
    let mut st = steady_run::build_steady(&sc).unwrap();
    let mut rep = Default::default();
    let reports = steady_run::solve_steady(&sc, &mut st, false, &mut rep, &mut ()).unwrap();
    (sc, st, reports)
}

/// Hub force and torque of `a` and `b` agree to `rel` of |F| of `reference` (the torque to
/// `rel` |F| × 2, the outer radius).
fn assert_same_hub_loads(
    a: &SteadyRolling,
    b: &SteadyRolling,
    reference: &SteadyRolling,
    rel: f64,
) {
    let (fa, ma) = a.sys.hub_reaction();
    let (fb, mb) = b.sys.hub_reaction();
    let scale = reference.sys.hub_reaction().0.norm();
    assert!((fa - fb).norm() <= rel * scale, "{fa:?} vs {fb:?}");
    assert!((ma - mb).abs() <= rel * scale * 2.0, "{ma} vs {mb}");
}

/// As [`fd_error`], and max |K − K_assembled| / max |K| (the matrix-free part).
fn fd_errors(sys: &mut SolidSystem) -> (f64, f64) {
    assert!(sys.evaluate(true));
    let mut k = sys.asm.to_dense();
    let n = sys.n_eq();
    let mut corr = 0.0f64;
    if sys.has_tangent_correction() {
        let mut e = vec![0.0; n];
        let mut col = vec![0.0; n];
        for j in 0..n {
            e.fill(0.0);
            e[j] = 1.0;
            col.fill(0.0);
            sys.tangent_correction(&e, &mut col);
            for i in 0..n {
                k[i][j] += col[i];
                corr = corr.max(col[i].abs());
            }
        }
    }
    let kmax = k.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut err = 0.0f64;
    let mut e = vec![0.0; n];
    let res = |s: &mut SolidSystem| {
        assert!(s.evaluate(false));
        s.residual().to_vec()
    };
    for j in 0..n {
        let h = 1e-7;
        e.fill(0.0);
        e[j] = h;
        sys.update(1.0, &e);
        let rp = res(sys);
        sys.update(-2.0, &e);
        let rm = res(sys);
        sys.update(1.0, &e);
        for i in 0..n {
            err = err.max(((rp[i] - rm[i]) / (2.0 * h) - k[i][j]).abs());
        }
    }
    (err / kmax, corr / kmax)
}

#[test]
fn steady_tangent_matches_finite_differences() {
    // Isoparametric Q2 annulus pressed 0.15 into the road, spinning, with Coulomb friction
    // (tanh), normal damping and strain-rate damping: every term of the steady residual.
    for (load, eta) in [(None, 0.0), (None, 3.0), (Some(40.0), 3.0)] {
        let mut mesh = annulus(&AnnulusSpec {
            ri: 1.0,
            ro: 2.0,
            n_r: 2,
            n_theta: 12,
            degree: 2,
            grading_r: 1.0,
            grading_theta: 0.0,
        });
        mesh.make_isoparametric();
        let mat: Material = MooneyRivlin::new(80.0, 20.0, 4000.0).into();
        let mut model = SolidModel::new(mesh, mat, 0.027, PressureMode::None);
        model.strain_rate_damping = eta;
        let contact = ContactModel::new(
            &model.mesh,
            1.85,
            19.0,
            NormalCompliance::new(2e4, 1.0, 5.0, 0.0),
            Friction::CoulombTanh(CoulombTanh::new(0.3, 0.5)),
            FacetRule::Lobatto(4),
            load,
        );
        let sys = SolidSystem::with_contact(model, contact);
        let mut st = SteadyRolling::new(sys, 10.0, 2.0);
        // The friction slip comes from nodal θ-derivatives along the boundary (extended
        // contact elements): its tangent is checked too.
        assert!(st.sys.contact.as_ref().unwrap().steady_slip.is_some());
        // A smooth non-trivial state: the bottom pushed up, a swirl.
        for nd in 0..st.sys.model.mesh.n_nodes() {
            let x = st.sys.model.mesh.nodes[nd];
            if st.sys.dofs.eq[2 * nd] != FIXED {
                st.sys.x[2 * nd] += 0.01 * (1.3 * x[1]).sin() + 0.005 * x[0];
                st.sys.x[2 * nd + 1] += 0.08 * (-x[1] - 1.0).max(0.0) + 0.01 * (0.7 * x[0]).cos();
            }
        }
        let (e, corr) = fd_errors(&mut st.sys);
        println!("load = {load:?}, eta = {eta}: max |K - K_fd| / max |K| = {e:.3e} (matrix-free part {corr:.3e})");
        assert!(e < 1e-6, "steady tangent vs finite differences: {e:.3e}");
        // With damping, the coupling beyond the cells is a visible part of the exact tangent
        // (the assembled part alone would fail the check above).
        assert_eq!(
            corr > 1e-4,
            eta > 0.0,
            "matrix-free part {corr:.3e} at eta = {eta}"
        );
    }
}

#[test]
fn steady_without_contact_is_steady_spinning() {
    // The same scene (no road, no contact) in "spinning" and in "steady" mode: same problem,
    // same mesh, same answer to round-off.
    let base = include_str!("../scenarios/spinning_neo_hookean.toml");
    let sp = scene(base, &[]);
    let mut sys = tread::app::build_system(&sp).unwrap();
    let plan = tread::setup::solve_plan(&sp, &sys);
    let (kind, nopt, sopt) = (plan.kind, plan.newton, plan.steps);
    let mut rep = Default::default();
    tread::driver::spinning::solve_spinning(
        &mut sys,
        sp.motion.omega,
        kind,
        nopt,
        &sopt,
        &mut rep,
        &mut (),
    )
    .unwrap();
    let (_, st) = steady_solution(base, &["analysis.mode=\"steady\""]);
    let diff = sys
        .x
        .iter()
        .zip(&st.sys.x)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let umax = sys.x.iter().map(|v| v.abs()).fold(0.0, f64::max);
    println!("steady vs spinning: max |du| = {diff:.3e} (max |u| = {umax:.3e})");
    assert!(umax > 1e-4);
    assert!(diff <= 1e-10 * umax, "steady vs spinning: {diff:.3e}");
}

#[test]
fn frictionless_rolling_is_symmetric_with_zero_torque() {
    // Low speed (1 rad/s), frictionless, no damping: the patch is symmetric about x1 = 0 up to
    // the small inertia asymmetry, and the torque vanishes (no tangential traction).
    let (_, st) = steady_solution(
        FRICTIONLESS,
        &[
            "analysis.mode=\"steady\"",
            "motion.omega=1.0",
            "road.v0=1.9666",
            "contact.b_n=0",
            "time.strain_rate_damping=0",
        ],
    );
    let t = ContactModel::totals(&st.sys.contact_samples());
    let (f, m) = st.sys.hub_reaction();
    println!(
        "patch [{:.6}, {:.6}], centroid {:.3e}, hub force ({:.4e}, {:.4e}), torque {:.3e}",
        t.x_min, t.x_max, t.centroid, f[0], f[1], m
    );
    assert!(f[1] < -10.0, "the road must carry load: Fy = {}", f[1]);
    assert!((t.x_min + t.x_max).abs() < 1e-3 * (t.x_max - t.x_min));
    assert!(
        t.centroid.abs() < 1e-3 * (t.x_max - t.x_min),
        "centroid {}",
        t.centroid
    );
    assert!(m.abs() < 1e-6 * f[1].abs() * 2.0, "torque {m}");
    assert!(f[0].abs() < 1e-6 * f[1].abs(), "Fx {}", f[0]);
}

/// Free rolling of the scene with `set`: (driven torque, free-rolling v0, torque scale).
fn free_rolling(set: &[&str]) -> (f64, f64, f64, f64) {
    let (sc, mut st) = steady_solution(ODEN, set);
    let t0 = st.hub_torque();
    let fy = st.sys.hub_reaction().0[1].abs();
    let scale = 0.3 * fy * sc.geometry.ro;
    let nopt = st.plan.newton.clone();
    let mut newton = Newton::new(&st.sys, LinearKind::Lu, nopt).unwrap();
    let r = solve_torque(&mut st, 0.0, scale, 1e-6, &mut newton, 30).unwrap();
    println!(
        "{set:?}: driven torque {t0:.4e}; free rolling v0 = {:.6} (R_eff = v0 / omega = {:.6}), torque {:.3e} after {} evaluations",
        r.v0,
        r.v0 / sc.motion.omega,
        r.torque,
        r.evaluations
    );
    assert!(
        t0.abs() > 1e-2 * scale,
        "the driven scene must need a torque"
    );
    assert!(r.torque.abs() <= 1e-6 * scale);
    assert!(st.hub_torque().abs() <= 1e-6 * scale);
    let fx = st.sys.hub_reaction().0[0];
    println!(
        "  free rolling hub force x = {fx:.4e} (mu Fy = {:.4e})",
        0.3 * fy
    );
    (t0, r.v0, scale, fx / (0.3 * fy))
}

#[test]
fn free_rolling_gives_zero_torque() {
    // Without dissipation other than friction (no normal or strain-rate damping) the
    // longitudinal force nearly vanishes at zero torque (what is left balances the moment of the
    // slightly off-centre pressure). The rolling radius v0 / ω comes out above Ro: the nearly
    // incompressible layer bonded to a rigid hub is squeezed out circumferentially in the
    // patch, so its surface moves faster than ω Ro (the known "negative creep" of
    // rubber-covered rolls); it stays within 10 % of Ro.
    let (_, v0, _, fx_rel) = free_rolling(&[
        "analysis.mode=\"steady\"",
        "contact.b_n=0",
        "time.strain_rate_damping=0",
    ]);
    let r_eff = v0 / 10.0;
    assert!(
        r_eff > 1.9 && r_eff < 2.2,
        "effective rolling radius {r_eff}"
    );
    assert!(fx_rel.abs() < 0.05, "Fx / (mu Fy) = {fx_rel}");
    // With strain-rate damping the cylinder has a rolling resistance: at zero hub torque the
    // road must push it, v0 is larger than without damping.
    let (_, v0_damped, _, _) = free_rolling(&["analysis.mode=\"steady\""]);
    assert!(v0_damped > v0, "{v0_damped} vs {v0}");
}

#[test]
fn continuation_in_omega_follows_the_branch() {
    // Arc-length continuation from 10 to 25 rad/s on the frictional scene; every point is a
    // converged steady state and λ increases monotonically (no limit point below critical).
    let sc = scene(
        ODEN,
        &[
            "analysis.mode=\"steady\"",
            "continuation.target=25.0",
            "continuation.ds=0.2",
            "continuation.ds_max=0.5",
            "output.sinks=[\"summary\",\"csv\"]",
        ],
    );
    let dir = tempdir::TestDir::new("steady", "continuation");
    let out = tread::app::run(
        &sc,
        &tread::app::RunOptions {
            out_dir: dir.to_path_buf(),
            verbose: false,
            quiet: true,
        },
    )
    .unwrap();
    let branch = out.summary["results"]["branch"].as_array().unwrap().clone();
    assert!(branch.len() >= 4, "{} points", branch.len());
    let lam: Vec<f64> = branch
        .iter()
        .map(|p| p["omega"].as_f64().unwrap())
        .collect();
    assert!(lam.windows(2).all(|w| w[1] > w[0]), "{lam:?}");
    assert!(*lam.last().unwrap() >= 25.0);
    // The end point agrees with a direct solve at that ω (same v0/ω ratio).
    let w_end = *lam.last().unwrap();
    let v0 = 19.666667 * w_end / 10.0;
    let (_, st) = steady_solution(
        ODEN,
        &[
            "analysis.mode=\"steady\"",
            &format!("motion.omega={w_end}"),
            &format!("road.v0={v0}"),
        ],
    );
    let fy_direct = st.sys.hub_reaction().0[1];
    let fy_cont = branch.last().unwrap()["hub_force_y"].as_f64().unwrap();
    println!("omega {w_end}: Fy continuation {fy_cont:.8e}, direct {fy_direct:.8e}");
    assert!((fy_cont - fy_direct).abs() < 1e-6 * fy_direct.abs());
    assert!(dir.join("branch.csv").exists());
}

#[test]
fn strain_rate_damping_does_not_act_on_steady_spinning() {
    // A cylinder in steady spin without contact: every material point keeps its strain, Ė = 0,
    // so the steady-mode viscous stress η sym(Fᵀ ∇v), v = ω ∂θχ, must vanish up to the
    // discretization of an axisymmetric field on the isoparametric mesh: the change it causes
    // must shrink under circumferential refinement.
    let solve = |eta: f64, n_theta: usize| {
        let mut mesh = annulus(&AnnulusSpec {
            ri: 1.0,
            ro: 2.0,
            n_r: 4,
            n_theta,
            degree: 2,
            grading_r: 1.0,
            grading_theta: 0.0,
        });
        mesh.make_isoparametric();
        let mat: Material = MooneyRivlin::new(80.0, 20.0, 20000.0).into();
        let mut model = SolidModel::new(mesh, mat, 0.027, PressureMode::None);
        model.strain_rate_damping = eta;
        let sys = SolidSystem::new(model, "hub");
        let mut st = SteadyRolling::new(sys, 40.0, 2.0);
        st.sys.set_reference_force(1.0);
        let mut newton = Newton::new(&st.sys, LinearKind::Lu, Default::default()).unwrap();
        newton.solve(&mut st).unwrap();
        println!(
            "  eta = {eta}, n_theta = {n_theta}: hub torque {:.3e}",
            st.hub_torque()
        );
        st.sys.x.clone()
    };
    let mut rel = Vec::new();
    for nt in [24, 48, 96] {
        let (u0, u1) = (solve(0.0, nt), solve(20.0, nt));
        let umax = u0.iter().map(|v| v.abs()).fold(0.0, f64::max);
        let diff = u0
            .iter()
            .zip(&u1)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        println!("n_theta = {nt}: max |u| = {umax:.3e}, change with eta = 20 psi s: {diff:.3e} ({:.3e} relative)", diff / umax);
        assert!(umax > 1e-4);
        rel.push(diff / umax);
    }
    // Observed: about 2^-4 per halving of h.
    assert!(rel[1] < rel[0] / 4.0 && rel[2] < rel[1] / 4.0, "{rel:?}");
    assert!(rel[2] < 1e-3, "{rel:?}");
}

/// Scene overrides of `oden_hollow_cylinder.toml` in steady mode at `omega` with the sweep's
/// ratio v0 / ω = 1.9666667 in and the smooth quadratic compliance (m_n = 2) of
/// `oden_steady_sweep.toml`.
fn steady_at(omega: f64) -> Vec<String> {
    vec![
        "analysis.mode=\"steady\"".into(),
        format!("motion.omega={omega}"),
        format!("road.v0={}", 19.666667 / 10.0 * omega),
        "contact.m_n=2".into(),
        "contact.c_n=2e6".into(),
    ]
}

/// The direct press (the steady solve before recoveries existed) of a scene: Ok or not.
fn direct_press_converges(sc: &Scene) -> bool {
    use tread::driver::steady::press;
    use tread::model::system::Loading;
    let mut st = steady_run::build_steady(sc).unwrap();
    let tread::solver::SolvePlan {
        kind,
        newton: nopt,
        steps: sopt,
    } = st.plan.clone();
    let loading = Loading::Indent {
        h_touch: sc.geometry.ro,
        disp: sc.road.as_ref().and_then(|r| r.disp).unwrap(),
    };
    press(
        &mut st,
        loading,
        kind,
        nopt,
        &sopt,
        &mut Default::default(),
        &mut (),
    )
    .is_ok()
}

/// Relative residual of the scene's own equations at the state of `st` (a fresh system of the
/// scene, so the parameters are exactly the scene's, with the state copied in).
fn scene_residual(sc: &Scene, st: &SteadyRolling) -> f64 {
    use tread::solver::stepping::LoadedSystem;
    let loading = tread::model::system::Loading::Indent {
        h_touch: sc.geometry.ro,
        disp: sc.road.as_ref().and_then(|r| r.disp).unwrap(),
    };
    let mut fresh = steady_run::build_steady(sc).unwrap();
    fresh.sys.loading = loading;
    fresh.sys.set_load(1.0);
    fresh.sys.x.copy_from_slice(&st.sys.x);
    assert!(fresh.evaluate(false));
    let r = fresh.residual().iter().map(|v| v * v).sum::<f64>().sqrt();
    r / fresh.sys.contact_force_scale(sc.geometry.ro)
}

#[test]
fn omega_stepping_recovery_reaches_the_direct_solution() {
    use tread::driver::steady_recovery::{recover, Strategy};
    use tread::model::system::Loading;
    // At 46 rad/s (m_n = 2) the direct press converges since the steady strain-rate damping
    // uses nodal velocities (before, it failed there and this test ran the whole recovery).
    // The recovery is run directly from the undeformed state, as after a failed press: its
    // first applicable strategy, ω stepping from 0, must land on the direct solution.
    let set = steady_at(46.0);
    let set: Vec<&str> = set.iter().map(|s| s.as_str()).collect();
    let (sc, direct, reports) = solved(ODEN, &set);
    assert!(reports.recovery.is_none());
    let mut st = steady_run::build_steady(&sc).unwrap();
    let x_init = st.sys.x.clone();
    let tread::solver::SolvePlan {
        kind,
        newton: nopt,
        steps: sopt,
    } = st.plan.clone();
    let loading = Loading::Indent {
        h_touch: sc.geometry.ro,
        disp: sc.road.as_ref().and_then(|r| r.disp).unwrap(),
    };
    let mut rep = Default::default();
    let mut notes = Notes(Vec::new());
    let r = recover(
        &mut st,
        loading,
        kind,
        &nopt,
        &sopt,
        &x_init,
        &tread::solver::SolveError::InadmissibleStart,
        &mut rep,
        &mut notes,
    )
    .unwrap();
    println!("{}", r.message);
    assert_eq!(r.strategy, Some(Strategy::OmegaStepping));
    // The recorders hear of the strategy and of each of its steps (run.sta follows them).
    assert!(
        notes
            .0
            .iter()
            .any(|n| n.contains("trying") && n.contains("omega")),
        "{:?}",
        notes.0
    );
    assert!(
        notes.0.iter().filter(|n| n.contains("reached")).count()
            == r.attempts[0].legs.iter().map(|l| l.steps).sum::<usize>(),
        "{:?}",
        notes.0
    );
    assert!(
        notes.0.last().is_some_and(|n| n.contains("succeeded")),
        "{:?}",
        notes.0
    );
    assert!(r.attempts[0].steps() >= 2, "{}", r.message);
    assert_eq!(st.omega(), 46.0);
    let res = scene_residual(&sc, &st);
    println!("relative residual of the scene's equations at the recovered state: {res:.3e}");
    // Against the contact force scale; Newton's own test is relative to the element force flux.
    assert!(res < 1e-6, "{res:e}");
    let umax = direct.sys.x.iter().map(|v| v.abs()).fold(0.0, f64::max);
    let du = direct
        .sys
        .x
        .iter()
        .zip(&st.sys.x)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let (fr, mr) = st.sys.hub_reaction();
    let (fc, mc) = direct.sys.hub_reaction();
    let df = (fr - fc).norm() / fc.norm();
    let dm = (mr - mc).abs() / (fc.norm() * 2.0);
    println!(
        "recovered vs direct at 46 rad/s: max |du| / max |u| = {:.3e}, |dF| / |F| = {df:.3e}, |dM| / (|F| Ro) = {dm:.3e}",
        du / umax
    );
    assert!(du <= 1e-6 * umax && df <= 1e-6 && dm <= 1e-6);
}

/// Run a steady scene through `tread::app::run` into a fresh directory; the summary and
/// whether the run succeeded.
fn run_steady(set: &[&str], tag: &str) -> (serde_json::Value, bool) {
    let mut set: Vec<&str> = set.to_vec();
    set.push("output.sinks=[\"summary\"]");
    let sc = scene(ODEN, &set);
    let dir = std::env::temp_dir().join(format!("tread_steady_{tag}_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let opts = tread::app::RunOptions {
        out_dir: dir.clone(),
        verbose: false,
        quiet: true,
    };
    let ok = tread::app::run(&sc, &opts).is_ok();
    let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    (serde_json::from_str(&text).unwrap(), ok)
}

#[test]
fn stiff_bulk_modulus_is_recovered_by_the_kappa_homotopy() {
    // κ/G = 1e6 (compressible Mooney–Rivlin) with the non-smooth damping l_n = 0 (the scene's
    // smooth l_n = 1 law lets the direct press converge at this κ): the direct press fails; a
    // homotopy from κ = 100 G down to the scene's value reaches a state that solves the scene's
    // own equations.
    let set = [
        "analysis.mode=\"steady\"",
        "material.kappa=2e8",
        "contact.b_n=5",
        "contact.l_n=0",
    ];
    let strategy = "kappa_homotopy";
    let sc = scene(ODEN, &set);
    assert!(
        !direct_press_converges(&sc),
        "{set:?}: the direct press converged, nothing to recover"
    );
    let (sc, st, reports) = solved(ODEN, &set);
    let r = reports.recovery.as_ref().expect("a recovery report");
    println!("{set:?}: {}", r.message);
    assert_eq!(r.strategy.map(|s| s.to_string()).as_deref(), Some(strategy));
    // Relative to the contact force scale (capped by G·DISP): Newton's test is relative to
    // the element force flux, which the κ-weighted volumetric forces dominate at κ/G = 1e5
    // (measured 6.9e-8 there).
    let res = scene_residual(&sc, &st);
    assert!(res < 1e-6, "{set:?}: residual {res:e}");
    // The hub load has the magnitude of the benign scene's (Fy = −98.5 lbf/in at κ/G = 100; a
    // stiffer κ raises it: −104.1 at 1e3, −111.7 at 1e5, −118.2 at 1e6).
    let fy = st.sys.hub_reaction().0[1];
    assert!((-125.0..-80.0).contains(&fy), "{set:?}: Fy = {fy}");
    // Logged in summary.json (solver.recovery) with the strategy and its steps.
    let (summary, ok) = run_steady(&set, strategy);
    assert!(ok && summary["converged"] == true);
    let rec = &summary["solver"]["recovery"];
    assert_eq!(rec["strategy"], strategy, "{rec}");
    let legs = rec["attempts"][0]["legs"].as_array().unwrap();
    assert!(legs[0]["steps"].as_u64().unwrap() >= 2, "{rec}");
    assert!(rec["message"].as_str().unwrap().contains(strategy));
}

#[test]
fn small_eps_is_reached_by_the_eps_homotopy_recovery_and_the_eps_continuation() {
    use tread::driver::steady_recovery::{recover, Strategy};
    use tread::model::system::Loading;
    // ε = 1e-5 v0 near free rolling.
    let set = [
        "analysis.mode=\"steady\"",
        "road.v0=21",
        "friction.eps=2.1e-4",
    ];
    let sc = scene(ODEN, &set);
    // 1. The recovery's ε homotopy (from ε = 1e-3 v_ref), run from the undeformed state as
    //    after a failed press: its first applicable strategy.
    let mut st = steady_run::build_steady(&sc).unwrap();
    let x_init = st.sys.x.clone();
    let tread::solver::SolvePlan {
        kind,
        newton: nopt,
        steps: sopt,
    } = st.plan.clone();
    let loading = Loading::Indent {
        h_touch: sc.geometry.ro,
        disp: sc.road.as_ref().and_then(|r| r.disp).unwrap(),
    };
    let r = recover(
        &mut st,
        loading,
        kind,
        &nopt,
        &sopt,
        &x_init,
        &tread::solver::SolveError::InadmissibleStart,
        &mut Default::default(),
        &mut (),
    )
    .unwrap();
    println!("{}", r.message);
    assert_eq!(r.strategy, Some(Strategy::EpsHomotopy));
    assert!(r.attempts[0].legs[0].steps >= 2, "{}", r.message);
    let res = scene_residual(&sc, &st);
    assert!(res < 1e-6, "recovery: residual {res:e}");
    let fy = st.sys.hub_reaction().0[1];
    assert!((-125.0..-80.0).contains(&fy), "recovery: Fy = {fy}");
    // 2. The run itself starts with the ε continuation (ε < 1e-2 v_ref) and needs no
    //    recovery; it lands on the same solution.
    let (_, cont, reports) = solved(ODEN, &set);
    assert!(reports.recovery.is_none());
    let a = reports
        .eps_continuation
        .as_ref()
        .expect("an eps continuation");
    assert!(a.succeeded && a.legs[0].steps >= 2, "{a:?}");
    let res = scene_residual(&sc, &cont);
    assert!(res < 1e-6, "continuation: residual {res:e}");
    let (f1, m1) = st.sys.hub_reaction();
    let (f2, m2) = cont.sys.hub_reaction();
    let df = (f1 - f2).norm() / f1.norm();
    let dm = (m1 - m2).abs() / (f1.norm() * 2.0);
    println!(
        "ε continuation vs ε homotopy recovery: |dF|/|F| = {df:.2e}, |dM|/(|F| Ro) = {dm:.2e}"
    );
    assert!(df < 1e-6 && dm < 1e-6, "{df:e} {dm:e}");
    let (summary, ok) = run_steady(&set, "eps_continuation");
    assert!(ok && summary["converged"] == true);
    assert!(summary["solver"]["recovery"].is_null());
    let e = &summary["solver"]["eps_continuation"];
    assert_eq!(e["succeeded"], true, "{e}");
    assert_eq!(e["legs"][0]["to"].as_f64(), Some(2.1e-4), "{e}");
    assert!(e["legs"][0]["from"].as_f64().unwrap() > 0.2, "{e}");
}

#[test]
fn eps_continuation_lands_on_the_direct_solution() {
    use tread::driver::steady::press;
    use tread::model::system::Loading;
    // ε = 5e-3 v0 (below the continuation threshold 1e-2 v_ref, but large enough for the
    // direct press to converge): the continuation from ε_c = 1e-2 v_ref and the direct press
    // must give the same steady state.
    let set = [
        "analysis.mode=\"steady\"",
        "road.v0=21",
        "friction.eps=0.105",
    ];
    let (sc, cont, reports) = solved(ODEN, &set);
    let a = reports
        .eps_continuation
        .as_ref()
        .expect("an eps continuation");
    assert!(a.succeeded, "{a:?}");
    let mut direct = steady_run::build_steady(&sc).unwrap();
    let tread::solver::SolvePlan {
        kind,
        newton: nopt,
        steps: sopt,
    } = direct.plan.clone();
    let loading = Loading::Indent {
        h_touch: sc.geometry.ro,
        disp: sc.road.as_ref().and_then(|r| r.disp).unwrap(),
    };
    press(
        &mut direct,
        loading,
        kind,
        nopt,
        &sopt,
        &mut Default::default(),
        &mut (),
    )
    .expect("the direct press converges at this ε");
    let umax = direct.sys.x.iter().map(|v| v.abs()).fold(0.0, f64::max);
    let du = direct
        .sys
        .x
        .iter()
        .zip(&cont.sys.x)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let (f1, m1) = direct.sys.hub_reaction();
    let (f2, m2) = cont.sys.hub_reaction();
    let df = (f1 - f2).norm() / f1.norm();
    let dm = (m1 - m2).abs() / (f1.norm() * 2.0);
    println!(
        "continuation vs direct: max |du|/max |u| = {:.2e}, |dF|/|F| = {df:.2e}, |dM|/(|F| Ro) = {dm:.2e}",
        du / umax
    );
    assert!(du <= 1e-6 * umax && df <= 1e-6 && dm <= 1e-6);
}

#[test]
fn a_target_the_strategies_cannot_reach_fails_with_every_attempt_logged() {
    // oden_hollow_cylinder with b_n = 5 psi·s/in, l_n = 0 (m_n = 1) at 42 rad/s, close to the critical
    // speed: the direct press fails, and so do the strategies (ω stepping stops short of 42).
    // (Before the steady strain-rate damping used nodal velocities, 38 rad/s was such a case.)
    // The run must fail with the direct error and log what it tried.
    // The scene's damping is now the smooth l_n = 1 law; the non-smooth l_n = 0 law is set here.
    let v0 = format!("road.v0={}", 42.0 * 1.966667);
    let (summary, ok) = run_steady(
        &[
            "analysis.mode=\"steady\"",
            "motion.omega=42",
            &v0,
            "contact.b_n=5",
            "contact.l_n=0",
        ],
        "gap",
    );
    assert!(!ok);
    assert_eq!(summary["converged"], false);
    let rec = &summary["solver"]["recovery"];
    assert!(rec["strategy"].is_null(), "{rec}");
    let attempts = rec["attempts"].as_array().unwrap();
    assert_eq!(attempts[0]["strategy"], "omega_stepping", "{rec}");
    assert_eq!(attempts[0]["succeeded"], false);
    let reached = attempts[0]["legs"][0]["reached"].as_f64().unwrap();
    println!("omega stepping stopped at {reached} rad/s");
    assert!((0.0..42.0).contains(&reached), "{reached}");
    assert!(summary["error"]
        .as_str()
        .unwrap()
        .contains("load stepping gave up"));
}

#[test]
fn default_scene_steady_solve_converges_directly_from_1_to_60_rad_per_s() {
    // The default scene (m_n = 1, damping b_n δ δ̇ with l_n = 1, vanishing at first contact)
    // on its own mesh, at every ω = 1, 2, …, 60 rad/s with the scene's ratio v0 / ω: the press
    // alone (no recovery strategy) converges, through the critical speed (≈ 41 rad/s). With
    // l_n = 0 it fails at 42 rad/s (see the test above).
    let mut failed = Vec::new();
    for w in 1..=60 {
        let omega = w as f64;
        let set = [
            "analysis.mode=\"steady\"".to_string(),
            format!("motion.omega={omega}"),
            format!("road.v0={}", 19.666667 / 10.0 * omega),
        ];
        let set: Vec<&str> = set.iter().map(|s| s.as_str()).collect();
        if !direct_press_converges(&scene(ODEN, &set)) {
            failed.push(w);
        }
    }
    assert!(
        failed.is_empty(),
        "direct steady solve failed at ω = {failed:?} rad/s"
    );
}

/// Nested iteration (`[solver] coarse_start`): on the default scene at 8 × 128 the steady state
/// started from the 2 × 32 → 4 × 64 solutions, interpolated, is the one pressed in from the
/// undeformed state (hub loads to the Newton tolerance), and Newton on the fine mesh needs at
/// most 5 full steps from it instead of the press-in's 12 with line search. A mesh it does not
/// apply to (odd n_r) reports nothing.
#[test]
fn coarse_start_reaches_the_same_steady_state_in_fewer_fine_iterations() {
    let mesh = ["mesh.n_r=8", "mesh.n_theta=128"];
    let (_, direct, reports) = solved(ODEN, &[&mesh[..], &["solver.coarse_start=false"]].concat());
    assert!(reports.coarse_start.is_none());
    let sc = scene(ODEN, &mesh);
    let mut st = steady_run::build_steady(&sc).unwrap();
    let mut rep = tread::solver::stepping::StepReport::default();
    let reports = steady_run::solve_steady(&sc, &mut st, false, &mut rep, &mut ()).unwrap();
    let cs = reports
        .coarse_start
        .clone()
        .expect("coarse start applies to 8 x 128");
    assert!(cs.succeeded, "{:?}", cs.error);
    assert_eq!(cs.meshes, ["2x32", "4x64"]);
    assert!(cs.coarse_newton_iterations > 0);
    assert!(
        cs.newton_iterations <= 5,
        "{} fine iterations",
        cs.newton_iterations
    );
    assert_eq!(rep.total_iterations, cs.newton_iterations);
    assert_same_hub_loads(&direct, &st, &direct, 1e-7);
    let (_, _, odd) = solved(ODEN, &["mesh.n_r=3", "mesh.n_theta=64"]);
    assert!(odd.coarse_start.is_none());
}

/// `[solver] single_precision` (on by default): the undamped steady state solved by GMRES on
/// single-precision LU factors is the one of double-precision direct solves (hub loads and
/// displacements to the Newton tolerance), with the same Newton iterations on the scene's
/// mesh.
#[test]
fn single_precision_factors_give_the_double_precision_steady_state() {
    let mesh = [
        "mesh.n_r=8",
        "mesh.n_theta=128",
        "time.strain_rate_damping=0",
    ];
    let (_, single, single_reports) = solved(ODEN, &mesh);
    let (_, double, double_reports) = solved(
        ODEN,
        &[&mesh[..], &["solver.single_precision=false"]].concat(),
    );
    let (a, b) = (
        single_reports.coarse_start.clone().unwrap(),
        double_reports.coarse_start.clone().unwrap(),
    );
    assert!(a.succeeded && b.succeeded);
    assert!(
        a.newton_iterations <= b.newton_iterations + 1,
        "{} vs {}",
        a.newton_iterations,
        b.newton_iterations
    );
    assert_same_hub_loads(&single, &double, &double, 1e-8);
    let du = single
        .sys
        .x
        .iter()
        .zip(&double.sys.x)
        .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
    let umax = double.sys.x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(du <= 1e-7 * umax, "max |du| = {du:e} of {umax:e}");
}

/// `single_precision = false` also makes the damping tangent's GMRES precondition with
/// double-precision factors: the damped steady state is the same (hub loads to the Newton
/// tolerance).
#[test]
fn double_precision_preconditioner_gives_the_same_damped_steady_state() {
    let mesh = ["mesh.n_r=8", "mesh.n_theta=128"];
    let (_, single) = steady_solution(ODEN, &mesh);
    let (_, double) = steady_solution(
        ODEN,
        &[&mesh[..], &["solver.single_precision=false"]].concat(),
    );
    assert!(single.sys.has_tangent_correction() && double.sys.has_tangent_correction());
    assert_same_hub_loads(&single, &double, &double, 1e-8);
}

/// With a second worker, `tread run` builds the scene's system while the coarser meshes of the
/// nested iteration are solved (`build_steady_nested`): the same coarse meshes, the same fine
/// Newton iterations and the same steady state as building first and solving after. With one
/// worker it builds only.
#[test]
fn nested_build_solves_the_coarse_meshes_while_the_scene_mesh_is_built() {
    let sc = scene(ODEN, &["mesh.n_r=8", "mesh.n_theta=128"]);
    let solve = |threads: usize, nested: bool| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let (mut st, coarse) = if nested {
                steady_run::build_nested(&sc).unwrap()
            } else {
                (steady_run::build_steady(&sc).unwrap(), None)
            };
            let ahead = coarse.is_some();
            let mut rep = tread::solver::stepping::StepReport::default();
            let reports =
                steady_run::solve_steady_from(&sc, &mut st, coarse, false, &mut rep, &mut ())
                    .unwrap();
            (st, reports, ahead)
        })
    };
    let (plain, plain_reports, ahead) = solve(2, false);
    assert!(!ahead);
    let (nested, nested_reports, ahead) = solve(2, true);
    assert!(
        ahead,
        "two workers: the coarse meshes are solved during the build"
    );
    let (_, _, ahead) = solve(1, true);
    assert!(!ahead, "one worker: build only");
    let (a, b) = (
        plain_reports.coarse_start.clone().unwrap(),
        nested_reports.coarse_start.clone().unwrap(),
    );
    assert!(b.succeeded, "{:?}", b.error);
    assert_eq!(a.meshes, b.meshes);
    assert_eq!(a.coarse_newton_iterations, b.coarse_newton_iterations);
    assert_eq!(a.newton_iterations, b.newton_iterations);
    assert_same_hub_loads(&plain, &nested, &plain, 1e-9);
}

/// Branch switching on the cylinder: frictionless, undamped rolling (a symmetric tangent,
/// inertia from LBLᵀ) followed in ω from 40 rad/s through the first bifurcation near the
/// critical speed (46.6–46.7 rad/s on 3 × 64). The path that stays on its branch keeps the
/// symmetric state (hub torque at round-off); with `switch_branch` the path leaves at the first
/// bifurcation along the null mode onto a branch whose states are not symmetric about the
/// vertical (a hub torque without friction or damping, growing along the branch).
#[test]
fn branch_switching_leaves_the_symmetric_branch_at_the_first_bifurcation() {
    let run = |switch: bool| {
        let sc = scene(
            FRICTIONLESS,
            &[
                "analysis.mode=\"steady\"",
                "motion.omega=40",
                "road.v0=78.666668",
                "contact.b_n=0",
                "time.strain_rate_damping=0",
                "continuation.parameter=\"omega\"",
                "continuation.target=55",
                "continuation.ds=0.02",
                "continuation.max_steps=30",
                &format!("continuation.switch_branch={switch}"),
                "output.sinks=[\"summary\"]",
            ],
        );
        let dir = tempdir::TestDir::new("steady", &format!("switch-{switch}"));
        let out = tread::app::run(
            &sc,
            &tread::app::RunOptions {
                out_dir: dir.to_path_buf(),
                verbose: false,
                quiet: true,
            },
        )
        .unwrap_or_else(|e| panic!("{e}"));
        out.summary["results"].clone()
    };
    let torque_ratio = |p: &serde_json::Value| {
        p["hub_torque"].as_f64().unwrap().abs() / (p["hub_force_y"].as_f64().unwrap().abs() * 2.0)
    };
    let plain = run(false);
    assert!(plain["continuation"]["switched_at"].is_null());
    let branch = plain["branch"].as_array().unwrap();
    let kind = |p: &serde_json::Value| p["kind"].as_str().unwrap().to_string();
    assert!(
        branch.iter().any(|p| kind(p) == "bifurcation"),
        "no bifurcation detected"
    );
    assert!(
        branch.iter().all(|p| torque_ratio(p) < 1e-10),
        "symmetric branch left unasked"
    );

    let switched = run(true);
    let k = switched["continuation"]["switched_at"]
        .as_u64()
        .expect("switched") as usize;
    let branch = switched["branch"].as_array().unwrap();
    assert_eq!(kind(&branch[k]), "bifurcation");
    assert_eq!(kind(&branch[k + 1]), "switched");
    let w = branch[k]["omega"].as_f64().unwrap();
    assert!((46.0..47.5).contains(&w), "first bifurcation at {w} rad/s");
    let after: Vec<f64> = branch[k + 1..].iter().map(torque_ratio).collect();
    println!("switched at {w} rad/s; |T| / (|F_y| Ro) after: {after:?}");
    assert!(after.len() >= 5);
    assert!(after.iter().all(|&t| t > 1e-7), "{after:?}");
    assert!(after.last().unwrap() > &(10.0 * after[0]), "{after:?}");
}

/// Collects the recorders' progress notes.
struct Notes(Vec<String>);

impl tread::io::record::Recorder for Notes {
    fn note(&mut self, text: &str) {
        self.0.push(text.to_string());
    }
}
