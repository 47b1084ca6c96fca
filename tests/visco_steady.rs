//! Steady rolling of a viscoelastic cylinder (internal variables integrated exactly along the
//! rings of quadrature points): the exact steady tangent (assembled part plus the ring coupling
//! applied matrix-free) against finite differences of the residual, quadratic Newton
//! convergence, zero rolling resistance in the relaxed and instantaneous limits, agreement with
//! the transient mode (`tread compare`), and a clear refusal on meshes without rings.

#[path = "common/fixtures.rs"]
mod fixtures;

use fixtures::scene_text;
use fixtures::tempdir;
use tread::assembly::FIXED;
use tread::driver::steady::SteadyRolling;
use tread::driver::steady_run::{build_steady, solve_steady};
use tread::io::Scene;
use tread::physics::viscoelastic_steady::StreamlineScheme;
use tread::solver::stepping::StepReport;
use tread::solver::{LinearKind, Newton, NewtonOptions, NonlinearSystem};

const SCENE: &str = "scenarios/viscoelastic_rolling.toml";

fn scene(set: &[&str]) -> Scene {
    scene_with(set, "convolution", 0.03)
}

/// The scene with the viscoelastic model and relaxation time replaced (nested tables have no
/// `--set` override).
fn scene_with(set: &[&str], model: &str, tau: f64) -> Scene {
    let text = scene_text(SCENE)
        .replace("model = \"convolution\"", &format!("model = \"{model}\""))
        .replace("prony = [[1.0, 0.03]]", &format!("prony = [[1.0, {tau}]]"));
    let mut all: Vec<String> = vec!["analysis.mode=\"steady\"".into()];
    all.extend(set.iter().map(|s| s.to_string()));
    Scene::from_toml_str(&text, "visco_steady", &all).unwrap_or_else(|e| panic!("{e}"))
}

/// Exact tangent times e_j: assembled matrix column plus the matrix-free ring coupling.
fn exact_column(st: &mut SteadyRolling, dense: &[Vec<f64>], j: usize) -> Vec<f64> {
    let n = st.n_eq();
    let mut e = vec![0.0; n];
    e[j] = 1.0;
    let mut col: Vec<f64> = (0..n).map(|i| dense[i][j]).collect();
    st.tangent_correction(&e, &mut col);
    col
}

/// max_ij |K_ij − K_fd,ij| / max |K| at a strained, non-trivial state.
fn fd_error(st: &mut SteadyRolling) -> (f64, f64) {
    // A smooth non-uniform state (|∇u| ~ 0.05) that is not symmetric in θ.
    let mesh = st.sys.model.mesh.clone();
    for nd in 0..mesh.n_nodes() {
        let x = mesh.nodes[nd];
        if st.sys.dofs.eq[2 * nd] != FIXED {
            let r = x.norm();
            let th = x[1].atan2(x[0]);
            st.sys.x[2 * nd] += 0.03 * (r - 1.0) * (th.sin() + 0.5 * (2.0 * th).cos());
            st.sys.x[2 * nd + 1] += 0.04 * (r - 1.0) * (0.3 + th.cos() * th.cos());
        }
    }
    // Hanging nodes follow their masters.
    st.sys.dofs.apply_constraints(&mut st.sys.x);
    assert!(st.evaluate(true));
    assert!(st.has_tangent_correction());
    let k = st.sys.asm.to_dense();
    let n = st.n_eq();
    let (mut kmax, mut corr_max) = (0.0f64, 0.0f64);
    let mut cols = Vec::with_capacity(n);
    for j in 0..n {
        let c = exact_column(st, &k, j);
        for i in 0..n {
            kmax = kmax.max(c[i].abs());
            corr_max = corr_max.max((c[i] - k[i][j]).abs());
        }
        cols.push(c);
    }
    let err = fixtures::fd_max_error(st, 1e-6, |i, j| cols[j][i]);
    (err / kmax, corr_max / kmax)
}

/// The exact steady tangent with the ring history equals central differences of the steady
/// residual (contact with normal damping included), for both viscoelastic models, both
/// spinning directions and a graded circumferential mesh; the ring coupling is a visible part
/// of it (the assembled part alone would fail the check).
#[test]
fn steady_jacobian_with_ring_history_matches_finite_differences() {
    for (model, omega, grading) in [
        ("convolution", 10.0_f64, 0.0),
        ("multiplicative", 10.0, 0.0),
        ("convolution", -25.0, 0.4),
        ("multiplicative", 40.0, 0.4),
    ] {
        let sc = scene_with(
            &[
                "mesh.n_r=1",
                "mesh.n_theta=8",
                &format!("mesh.grading_theta={grading}"),
                &format!("motion.omega={}", omega.abs()),
                &format!("road.v0={}", 1.95 * omega.abs()),
            ],
            model,
            0.03,
        );
        let mut st = build_steady(&sc).unwrap_or_else(|e| panic!("{e}"));
        // Clockwise spin (the scene accepts ω ≥ 0 only): the rings run the other way.
        st.set_omega(omega, 1.95 * omega);
        let dev = st.sys.steady_history.as_ref().unwrap().radius_deviation();
        let (err, corr) = fd_error(&mut st);
        println!("{model}, omega = {omega}, grading {grading}: FD rel err {err:.2e}, ring-coupling part {corr:.2e} of max |K| (ring radius deviation {dev:.1e})");
        assert!(err < 1e-6, "{model} omega {omega}: {err}");
        assert!(corr > 1e-3, "ring coupling should matter: {corr}");
    }
}

/// The relative residuals of exact Newton (GMRES on the exact tangent to a tight tolerance,
/// preconditioned with the assembled part's factorization; no line search) on the scene's
/// steady state, restarted from the steady solution at a 10 % lower ω.
fn exact_newton_history(sc: &Scene) -> Vec<f64> {
    let mut st = build_steady(sc).unwrap_or_else(|e| panic!("{e}"));
    let mut rep = StepReport::default();
    solve_steady(sc, &mut st, false, &mut rep, &mut ()).unwrap_or_else(|e| panic!("{e}"));
    let omega = st.omega_signed();
    let v0 = st.v0();
    st.set_omega(0.9 * omega, 0.9 * v0);
    let opts = NewtonOptions {
        tol: 1e-12,
        max_iterations: 12,
        line_search: false,
        // The exact Newton step: GMRES to a tight relative residual at every iteration (the
        // default forcing term is loose far from the solution, an inexact Newton method).
        krylov_eta_max: 1e-8,
        ..NewtonOptions::default()
    };
    let mut newton = Newton::new(&st, LinearKind::Lu, opts).unwrap();
    newton.solve(&mut st).unwrap_or_else(|e| panic!("{e}"));
    st.set_omega(omega, v0);
    let r = newton.solve(&mut st).unwrap_or_else(|e| panic!("{e}"));
    let hist: Vec<f64> = r.table.iter().map(|t| t.residual_rel[0]).collect();
    let shown: Vec<String> = hist.iter().map(|v| format!("{v:.3e}")).collect();
    println!(
        "exact Newton |R|/|R0|: {shown:?} ({} GMRES products)",
        r.krylov_iterations
    );
    hist
}

/// Quadratic convergence: once a residual is below `from`, the next is below 10 r² (r
/// relative), down to the round-off `floor`; at least one such step, at most 7 iterations.
fn assert_quadratic(hist: &[f64], from: f64, floor: f64) {
    let mut quad = 0;
    for w in hist.windows(2) {
        if w[0] < from && w[1] > 1e-10 {
            // (below 1e-10: the residual's round-off floor)
            assert!(w[1] < 10.0 * w[0] * w[0], "not quadratic: {hist:?}");
            quad += 1;
        }
    }
    assert!(quad >= 1, "no iteration in the quadratic range: {hist:?}");
    assert!(hist.len() <= 7, "too many iterations: {hist:?}");
    assert!(hist.last().is_some_and(|&r| r < floor), "{hist:?}");
}

/// Newton on the steady viscoelastic problem with the exact step converges quadratically.
#[test]
fn newton_converges_quadratically_with_ring_history() {
    let hist = exact_newton_history(&scene(&["contact.b_n=0.0"]));
    assert_quadratic(&hist, 1e-2, 1e-11);
}

/// Steady solution of the scene (no normal damping: the viscoelastic hysteresis is then the
/// only dissipation), returning (rolling resistance T / (P Ro), P).
fn resistance(sc: &Scene) -> (f64, f64) {
    let mut st = build_steady(sc).unwrap_or_else(|e| panic!("{e}"));
    let mut rep = StepReport::default();
    solve_steady(sc, &mut st, false, &mut rep, &mut ()).unwrap_or_else(|e| panic!("{e}"));
    let (f, t) = st.sys.hub_reaction();
    let p = -f[1];
    (t / (p * sc.geometry.ro), p)
}

/// Zero rolling resistance in the relaxed (slow: τ ≪ contact time) and instantaneous (fast:
/// τ ≫ contact time and revolution time) limits, against a clear resistance in between; in the
/// relaxed limit the load equals that of the elastic material with the relaxed modulus.
#[test]
fn rolling_resistance_vanishes_in_the_relaxed_and_instantaneous_limits() {
    let set = ["contact.b_n=0.0", "mesh.n_r=3", "mesh.n_theta=64"];
    let (mu_mid, p_mid) = resistance(&scene_with(&set, "convolution", 0.03));
    let (mu_slow, p_slow) = resistance(&scene_with(&set, "convolution", 1e-7));
    let (mu_fast, p_fast) = resistance(&scene_with(&set, "convolution", 1e5));
    let (mu_slow_m, _) = resistance(&scene_with(&set, "multiplicative", 1e-7));
    let (mu_fast_m, _) = resistance(&scene_with(&set, "multiplicative", 1e5));
    // The elastic material alone (the relaxed modulus).
    let text = scene_text(SCENE);
    let i = text.find("\n[material.viscoelastic]").unwrap();
    let j = text.find("\n[analysis]").unwrap();
    let elastic = format!("{}{}", &text[..i], &text[j..]);
    let mut all: Vec<String> = vec!["analysis.mode=\"steady\"".into()];
    all.extend(set.iter().map(|s| s.to_string()));
    let sc_el = Scene::from_toml_str(&elastic, "elastic", &all).unwrap();
    let (mu_el, p_el) = resistance(&sc_el);
    println!(
        "T/(P Ro): tau = 0.03: {mu_mid:.4e} (P {p_mid:.4}); tau = 1e-7: {mu_slow:.3e} (P {p_slow:.4}), multiplicative {mu_slow_m:.3e}; tau = 1e5: {mu_fast:.3e} (P {p_fast:.4}), multiplicative {mu_fast_m:.3e}; elastic {mu_el:.3e} (P {p_el:.4})"
    );
    assert!(mu_mid > 0.01, "{mu_mid}");
    for mu in [mu_slow, mu_fast, mu_slow_m, mu_fast_m, mu_el] {
        assert!(mu.abs() < 1e-4 * mu_mid, "{mu} vs {mu_mid}");
    }
    assert!((p_slow - p_el).abs() < 1e-5 * p_el, "{p_slow} vs {p_el}");
    // The instantaneous limit is stiffer (higher load at the same penetration).
    assert!(p_fast > 1.05 * p_el, "{p_fast} vs {p_el}");
}

/// The viscoelastic scene on the unstructured Gmsh mesh `file` (`tests/gmsh_data/…` or
/// `scenarios/…`), steady mode, with the extra overrides `set`.
fn gmsh_scene(file: &str, set: &[&str], model: &str) -> Scene {
    let file = format!("{}/{file}", env!("CARGO_MANIFEST_DIR"));
    let text =
        scene_text(SCENE).replace("model = \"convolution\"", &format!("model = \"{model}\""));
    let (i, j) = (
        text.find("\n[mesh]").unwrap(),
        text.find("\n[material]").unwrap(),
    );
    let text = format!(
        "{}\n[mesh]\nfile = \"{file}\"\nhub = \"hub\"\ncontact = \"contact\"\n{}",
        &text[..i],
        &text[j..]
    );
    let mut all: Vec<String> = vec!["analysis.mode=\"steady\"".into()];
    all.extend(set.iter().map(|s| s.to_string()));
    Scene::from_toml_str(&text, "gmsh", &all).unwrap_or_else(|e| panic!("{e}"))
}

/// A mesh without rings of quadrature points (Gmsh) cannot carry the exact ring integration:
/// asking for it is a clear error naming the key and the way out; by default ("auto") the
/// upwind streamline scheme is taken.
#[test]
fn rings_are_refused_on_a_gmsh_mesh_and_auto_takes_upwind() {
    let file = "scenarios/footprint_refined.msh";
    let sc = gmsh_scene(file, &["solver.steady_history=\"rings\""], "convolution");
    let e = build_steady(&sc).err().expect("refused");
    let msg = e.to_string();
    println!("{msg}");
    assert!(
        msg.contains("solver.steady_history") && msg.contains("no rings") && msg.contains("upwind"),
        "{msg}"
    );
    let st = build_steady(&gmsh_scene(file, &[], "convolution")).unwrap_or_else(|e| panic!("{e}"));
    let sh = st.sys.steady_history.as_ref().expect("steady history");
    assert_eq!(sh.scheme(), StreamlineScheme::Upwind);
    assert_eq!(sh.n_rings(), 0);
    // On the generated annulus, auto takes the rings.
    let st = build_steady(&scene(&[])).unwrap_or_else(|e| panic!("{e}"));
    let sh = st.sys.steady_history.as_ref().expect("steady history");
    assert_eq!(sh.scheme(), StreamlineScheme::Rings);
}

/// The exact steady tangent with the upwind streamline history equals central differences of
/// the steady residual: on an isoparametric Gmsh annulus (every face of the upwind scheme
/// carries flux, neighbours found by point location) for both models and both spinning
/// directions, and on the generated graded annulus with the scheme forced.
#[test]
fn steady_jacobian_with_upwind_history_matches_finite_differences() {
    for (model, omega) in [("convolution", 10.0_f64), ("multiplicative", -25.0)] {
        let sc = gmsh_scene(
            "tests/gmsh_data/annulus_q2.msh",
            &[
                &format!("motion.omega={}", omega.abs()),
                &format!("road.v0={}", 1.95 * omega.abs()),
            ],
            model,
        );
        let mut st = build_steady(&sc).unwrap_or_else(|e| panic!("{e}"));
        st.set_omega(omega, 1.95 * omega);
        assert_eq!(
            st.sys.steady_history.as_ref().unwrap().scheme(),
            StreamlineScheme::Upwind
        );
        let (err, corr) = fd_error(&mut st);
        println!("Gmsh Q2, {model}, omega = {omega}: FD rel err {err:.2e}, streamline-coupling part {corr:.2e} of max |K|");
        assert!(err < 1e-6, "{model} omega {omega}: {err}");
        assert!(corr > 1e-3, "streamline coupling should matter: {corr}");
    }
    let sc = scene_with(
        &[
            "mesh.n_r=1",
            "mesh.n_theta=8",
            "mesh.grading_theta=0.4",
            "solver.steady_history=\"upwind\"",
        ],
        "multiplicative",
        0.03,
    );
    let mut st = build_steady(&sc).unwrap_or_else(|e| panic!("{e}"));
    let (err, corr) = fd_error(&mut st);
    println!("generated graded, upwind forced: FD rel err {err:.2e}, coupling {corr:.2e}");
    assert!(err < 1e-6 && corr > 1e-3, "{err} {corr}");
}

/// The same with hanging nodes (the annulus refined below the hub twice, one-irregular): the
/// matrix-free streamline coupling takes a hanging node's value from its masters and gives its
/// row to them.
#[test]
fn steady_jacobian_with_upwind_history_is_exact_with_hanging_nodes() {
    let sc = scene_with(&["mesh.n_r=1", "mesh.n_theta=8"], "convolution", 0.03);
    let mesh = fixtures::refined_below_hub(&sc);
    let (material, pressure) = tread::setup::build_material(&sc).unwrap_or_else(|e| panic!("{e}"));
    let mut model = tread::physics::SolidModel::new(mesh, material, sc.material.rho, pressure);
    tread::setup::attach_viscoelastic(&sc, &mut model).unwrap_or_else(|e| panic!("{e}"));
    let mut st = tread::driver::steady_run::steady_on(&sc, model).unwrap_or_else(|e| panic!("{e}"));
    assert!(st.sys.dofs.has_constraints());
    assert_eq!(
        st.sys.steady_history.as_ref().unwrap().scheme(),
        StreamlineScheme::Upwind
    );
    let (err, corr) = fd_error(&mut st);
    println!("hanging nodes, upwind: FD rel err {err:.2e}, coupling {corr:.2e}");
    assert!(err < 1e-6 && corr > 1e-3, "{err} {corr}");
}

/// Newton with the exact step converges quadratically with the upwind history too (Gmsh
/// mesh, from the steady state at a 10 % lower ω).
#[test]
fn newton_converges_quadratically_with_upwind_history() {
    let sc = gmsh_scene(
        "scenarios/footprint_refined.msh",
        &["contact.b_n=0.0"],
        "convolution",
    );
    let hist = exact_newton_history(&sc);
    // The round-off floor of the residual with the upwind solves: about 3e-11 here.
    assert_quadratic(&hist, 0.05, 1e-10);
}

/// Steady hub load and torque of the scene with the given scheme on the generated mesh.
fn load_and_torque(sc: &Scene) -> (f64, f64) {
    let mut st = build_steady(sc).unwrap_or_else(|e| panic!("{e}"));
    let mut rep = StepReport::default();
    solve_steady(sc, &mut st, false, &mut rep, &mut ()).unwrap_or_else(|e| panic!("{e}"));
    let (f, t) = st.sys.hub_reaction();
    (-f[1], t)
}

/// The upwind scheme and the exact rings are two discretisations of the same streamline ODE:
/// on the generated annulus their hub torques (the rolling resistance) differ by less and less
/// under refinement, at the rate of the schemes (measured 1.07 %, 0.26 %, 0.069 %: order 2).
/// And the unstructured footprint-refined Gmsh mesh (3.3k DOFs) gives the torque and load of
/// fine ring meshes.
#[test]
fn upwind_history_converges_to_the_rings() {
    let mut diffs = Vec::new();
    for (nr, nt) in [(2, 32), (4, 64), (8, 128)] {
        let set = |s: &str| {
            scene(&[
                &format!("mesh.n_r={nr}"),
                &format!("mesh.n_theta={nt}"),
                &format!("solver.steady_history=\"{s}\""),
            ])
        };
        let (pr, tr) = load_and_torque(&set("rings"));
        let (pu, tu) = load_and_torque(&set("upwind"));
        let d = (tu - tr).abs() / tr;
        println!("{nr} x {nt}: torque rings {tr:.5} upwind {tu:.5} (diff {d:.2e}), load {pr:.4} / {pu:.4}");
        assert!((pu - pr).abs() < 1e-3 * pr, "{pu} vs {pr}");
        diffs.push(d);
    }
    assert!(
        diffs[1] < diffs[0] / 3.0 && diffs[2] < diffs[1] / 3.0,
        "{diffs:?}"
    );
    assert!(diffs[2] < 1e-3, "{diffs:?}");
    // The Gmsh scene against the rings on 16 × 256 and 32 × 512 (131k DOFs): torque 5.6910 and
    // 5.6766, load 115.670 and 115.669.
    let gm = Scene::from_path(
        std::path::Path::new(&format!(
            "{}/scenarios/viscoelastic_rolling_gmsh.toml",
            env!("CARGO_MANIFEST_DIR")
        )),
        &[],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let (p, t) = load_and_torque(&gm);
    println!("Gmsh footprint mesh: load {p:.4}, torque {t:.5}");
    assert!((t - 5.684).abs() < 0.01 * 5.684, "{t}");
    assert!((p - 115.67).abs() < 0.005 * 115.67, "{p}");
}

/// Energy balance of steady rolling with the dissipative (multiplicative) model and no other
/// dissipation: the power of the hub torque T ω equals the viscous dissipation ∫ D dV, up to
/// the discretization error, which shrinks with the mesh.
#[test]
fn hub_power_balances_the_viscous_dissipation() {
    let mut errs = Vec::new();
    for (nr, nt) in [(3, 64), (3, 128), (4, 256)] {
        let sc = scene_with(
            &[
                "contact.b_n=0.0",
                &format!("mesh.n_r={nr}"),
                &format!("mesh.n_theta={nt}"),
            ],
            "multiplicative",
            0.03,
        );
        let mut st = build_steady(&sc).unwrap_or_else(|e| panic!("{e}"));
        let mut rep = StepReport::default();
        solve_steady(&sc, &mut st, false, &mut rep, &mut ()).unwrap_or_else(|e| panic!("{e}"));
        assert!(st.evaluate(false));
        let (_, t) = st.sys.hub_reaction();
        let power = t * st.omega_signed();
        let d = st
            .sys
            .steady_history
            .as_ref()
            .unwrap()
            .dissipation(&st.sys.model)
            .unwrap();
        let e = (power - d).abs() / d;
        println!("{nr} x {nt}: T omega = {power:.5e}, dissipation = {d:.5e}, rel diff {e:.2e}");
        errs.push(e);
    }
    assert!(errs[2] < 0.02 && errs[2] < errs[0], "{errs:?}");
}

#[path = "common/hunter.rs"]
#[allow(dead_code)]
mod hunter;

/// Rolling resistance against speed from the steady mode by continuation in ω (v0 / ω fixed,
/// no normal damping, 3 × 128 Q2): the curve rises from zero, peaks and falls. Printed beside
/// the independent reference of a rigid cylinder on a standard-linear-solid half-space (Hunter
/// 1961, same G∞, G1, τ, R = Ro, the FE load, V = v0). The cylinder here is a layer of
/// thickness Ro − Ri = 1 in on a rigid hub with a contact half-width of about 0.5 in, far
/// from Hunter's thick layer with a/R ≪ 1, so the table measures that model difference; the
/// test asserts the shape of the FE curve only. Writes `resistance_vs_speed.csv`.
#[test]
fn rolling_resistance_versus_speed_by_omega_continuation() {
    use tread::driver::steady::{step_parameter, SteadyParameter};
    let omegas = [
        0.5, 1.0, 2.0, 3.0, 4.5, 6.0, 8.0, 10.0, 13.0, 17.0, 22.0, 28.0,
    ];
    let v_per_omega = 1.9666667;
    let sc = scene_with(
        &[
            "contact.b_n=0.0",
            "mesh.n_r=3",
            "mesh.n_theta=128",
            &format!("motion.omega={}", omegas[0]),
            &format!("road.v0={}", v_per_omega * omegas[0]),
        ],
        "convolution",
        0.03,
    );
    let mut st = build_steady(&sc).unwrap_or_else(|e| panic!("{e}"));
    let mut rep = StepReport::default();
    solve_steady(&sc, &mut st, false, &mut rep, &mut ()).unwrap_or_else(|e| panic!("{e}"));
    st.param = SteadyParameter::Omega;
    let newton_opts = st.plan.newton.clone();
    let mut newton = Newton::new(&st, LinearKind::Lu, newton_opts).unwrap();
    let dir = tempdir::TestDir::new("visco_steady", "resistance_vs_speed");
    let mut csv = String::from("omega,v0,load,hub_torque,resistance,hunter_resistance\n");
    let mut curve = Vec::new();
    println!("  omega    V      P        T/(P Ro)     Hunter      diff");
    for &om in &omegas {
        step_parameter(&mut st, om, &mut newton, 8).unwrap_or_else(|e| panic!("omega {om}: {e}"));
        assert!(st.evaluate(false));
        let (f, t) = st.sys.hub_reaction();
        let p = -f[1];
        let mu = t / (p * sc.geometry.ro);
        let pb = hunter::HunterProblem {
            g_inf: 200.0,
            g1: 100.0,
            tau: 0.03,
            radius: sc.geometry.ro,
            load: p,
        };
        let mu_h = pb.solve(st.v0(), 40).map_or(f64::NAN, |s| -s.resistance);
        println!(
            "  {om:5.1}  {:6.2}  {p:7.3}  {mu:.4e}  {mu_h:.4e}  {:+6.1} %",
            st.v0(),
            100.0 * (mu - mu_h) / mu_h
        );
        csv.push_str(&format!("{om},{},{p},{t},{mu},{mu_h}\n", st.v0()));
        curve.push(mu);
    }
    std::fs::write(dir.join("resistance_vs_speed.csv"), csv).unwrap();
    let (i_max, mu_max) =
        curve.iter().enumerate().fold(
            (0, 0.0),
            |(im, m), (i, &c)| if c > m { (i, c) } else { (im, m) },
        );
    println!("peak: T/(P Ro) = {mu_max:.4e} at omega = {}", omegas[i_max]);
    assert!(i_max > 0 && i_max + 1 < curve.len(), "{curve:?}");
    assert!(
        curve[0] < 0.5 * mu_max && curve[curve.len() - 1] < 0.8 * mu_max,
        "{curve:?}"
    );
}

/// `tread compare` on the viscoelastic scene (6 × 128 Q2, the transient run to tight time and
/// steady tolerances): the steady mode with the ring history and the transient mode with the
/// history at the material quadrature points agree on the hub forces and on the rolling
/// resistance T / (P Ro) within 0.5 %, on the referential field within 1 % and on the internal
/// variables along the rings within 3 % (relative L2), at 5 and 20 rad/s. Measured: resistance
/// 0.2 % and 0.1 %, field 0.12 % and 0.07 %, internal variables 1.3 % and 1.0 %. (On 3 × 64
/// the 20 rad/s resistance differed by 3.6 % with the scene's former jumping normal damping,
/// l_n = 0, whose steady solutions wandered by 2 % from mesh to mesh; with l_n = 1 the steady
/// torque converges smoothly, 4.302, 4.316, 4.341 on 3 × 64, 6 × 128, 12 × 256.) Slow (the
/// transient runs take 6–7 minutes each):
/// `cargo test --release --test visco_steady -- --ignored`.
#[test]
#[ignore]
fn compare_transient_and_steady_with_viscoelastic_history() {
    use tread::app::RunOptions;
    for (omega, t_end) in [(5.0, 12.0), (20.0, 6.0)] {
        let extra = [
            "time.error_tol=1e-4".to_string(),
            "time.steady_tol=1e-5".to_string(),
            format!("time.t_end={t_end}"),
        ];
        let mu_tol = 5e-3;
        let mut set: Vec<String> = vec![
            "mesh.n_r=6".into(),
            "mesh.n_theta=128".into(),
            format!("motion.omega={omega}"),
            format!("road.v0={}", 1.9666667 * omega),
            "output.sinks=[\"summary\",\"csv\"]".into(),
        ];
        set.extend(extra.iter().map(|s| s.to_string()));
        let sc = Scene::from_toml_str(&scene_text(SCENE), "visco_compare", &set)
            .unwrap_or_else(|e| panic!("{e}"));
        let dir = tempdir::TestDir::new("visco_steady", &format!("compare-{omega}"));
        let out = tread::driver::compare::run(
            &sc,
            &RunOptions {
                out_dir: dir.to_path_buf(),
                verbose: false,
                quiet: true,
            },
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let c = &out.summary["results"]["compare"];
        let g = |k: &str| c[k].as_f64().unwrap_or_else(|| panic!("{k}: {c}"));
        let mu = |t: f64, fy: f64| t / (-fy * 2.0);
        let mu_t = mu(g("hub_torque_transient"), g("hub_force_y_transient"));
        let mu_s = mu(g("hub_torque_steady"), g("hub_force_y_steady"));
        let d_mu = (mu_t - mu_s).abs() / mu_s;
        println!(
            "omega {omega}: Fy {:.5e} / {:.5e} (rel {:.2e}), T/(P Ro) {mu_t:.5e} / {mu_s:.5e} (rel {d_mu:.2e}), field rel L2 {:.2e}",
            g("hub_force_y_transient"),
            g("hub_force_y_steady"),
            g("hub_force_y_rel_diff"),
            g("field_rel_l2")
        );
        assert!(g("hub_force_x_rel_diff") < 5e-3 && g("hub_force_y_rel_diff") < 5e-3);
        assert!(d_mu < mu_tol, "rolling resistance: {mu_t} vs {mu_s}");
        assert!(g("field_rel_l2") < 1e-2);
        // Internal variables along the rings: measured 1.3 % (5 rad/s) and 1.0 % (20 rad/s).
        let h = g("history_rel_l2");
        println!("omega {omega}: internal variables rel L2 {h:.3e}");
        assert!(h < 0.03, "internal variables differ by {h:.3e}");
    }
}

/// The independent check against the exact steady rolling of a viscoelastic body: the scene
/// `viscoelastic_hunter.toml` (thin contact, a/R ≈ 0.045, on a layer ≈ 20 a thick: the setting in
/// which a viscoelastic roller on a rigid road has the contact mechanics of a rigid cylinder on a
/// viscoelastic half-space) in the steady mode against Hunter's solution (tests/common/hunter.rs,
/// computed independently with the same G∞, G1, τ, R = Ro, the FE load and V = v0) at speeds
/// around the resistance peak: the rolling resistance within 2 %, the contact edges within
/// 0.01 in (≈ 1.5 footprint cells, the resolution of the FE edges), the pressure distribution
/// within 3 % of the peak pressure pointwise over the inner 80 % of the patch (1 % rms). Remaining differences:
/// finite layer, compressibility K/G = 100, penalty contact, finite strain.
#[test]
fn rolling_resistance_matches_the_half_space_reference() {
    let text = scene_text("scenarios/viscoelastic_hunter.toml");
    println!("  omega   P        T/(P Ro) FE   Hunter      diff     edges FE            Hunter");
    for om in [0.5, 1.0, 2.5, 5.0] {
        let v0 = 1.998 * om;
        let sc = Scene::from_toml_str(
            &text,
            "hunter",
            &[format!("motion.omega={om}"), format!("road.v0={v0}")],
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let mut st = build_steady(&sc).unwrap_or_else(|e| panic!("{e}"));
        let mut rep = StepReport::default();
        solve_steady(&sc, &mut st, false, &mut rep, &mut ()).unwrap_or_else(|e| panic!("{e}"));
        let (f, t) = st.sys.hub_reaction();
        let p = -f[1];
        let mu = t / (p * sc.geometry.ro);
        let samples = st.sys.contact_samples();
        let touching: Vec<f64> = samples
            .iter()
            .filter(|s| s.t_n > 0.0)
            .map(|s| s.x1)
            .collect();
        let (x0, x1) = (
            touching.iter().cloned().fold(f64::INFINITY, f64::min),
            touching.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
        );
        let pb = hunter::HunterProblem {
            g_inf: 200.0,
            g1: 100.0,
            tau: 0.03,
            radius: sc.geometry.ro,
            load: p,
        };
        let s = pb.solve(v0, 40).expect("reference solves");
        let (h0, h1) = s.edges();
        let d = (mu + s.resistance) / -s.resistance;
        println!(
            "  {om:4.1}  {p:7.4}  {mu:.4e}  {:.4e}  {:+5.2} %   [{x0:+.4}, {x1:+.4}]  [{h0:+.4}, {h1:+.4}]",
            -s.resistance,
            100.0 * d
        );
        assert!(d.abs() < 0.02, "omega {om}: {mu} vs {}", -s.resistance);
        assert!((x0 - h0).abs() < 0.01 && (x1 - h1).abs() < 0.01);
        // The pressure distribution: FE contact pressure at the facet quadrature points against
        // Hunter's p(x), relative to Hunter's peak pressure.
        let p_max = (0..=400)
            .map(|k| s.pressure(h0 + (h1 - h0) * k as f64 / 400.0))
            .fold(0.0, f64::max);
        let (mut worst, mut sq, mut n) = (0.0f64, 0.0, 0usize);
        let (mut worst_in, mut sq_in, mut n_in) = (0.0f64, 0.0, 0usize);
        for smp in samples
            .iter()
            .filter(|s| s.x2 < 0.0 && s.x1 > h0 - 0.05 && s.x1 < h1 + 0.05)
        {
            let e = (smp.t_n - s.pressure(smp.x1)).abs() / p_max;
            worst = worst.max(e);
            sq += e * e;
            n += 1;
            // Away from the edges (where the square-root profile is not resolved by the mesh).
            if smp.x1 > h0 + 0.1 * (h1 - h0) && smp.x1 < h1 - 0.1 * (h1 - h0) {
                worst_in = worst_in.max(e);
                sq_in += e * e;
                n_in += 1;
            }
        }
        let rms = (sq / n.max(1) as f64).sqrt();
        let rms_in = (sq_in / n_in.max(1) as f64).sqrt();
        println!(
            "         pressure vs Hunter (of p_max = {p_max:.3}): max {worst:.4}, rms {rms:.4} over {n} points; inner 80 %: max {worst_in:.4}, rms {rms_in:.4}"
        );
        // Measured: inner 80 % max 2.1-2.7 %, rms 0.7-0.8 % of p_max; over the whole patch
        // rms 1.8-3.3 %, the maxima (11-18 %) at the edges, which sit 0.001-0.005 in off.
        assert!(
            worst_in < 0.03 && rms_in < 0.01,
            "omega {om}: {worst_in} {rms_in}"
        );
        assert!(rms < 0.04, "omega {om}: {rms}");
    }
}

/// `scenarios/viscoelastic_resistance_curve.toml` through `tread run` on a coarser mesh: the
/// arc-length continuation in ω carries the ring history (its corrector solves by GMRES on the
/// exact tangent), brackets the resistance peak, writes `resistance.png` and
/// `results.rolling_resistance`; the branch's C_rr equals direct steady solves at two of its
/// speeds (same mesh), and the peak lies where the half-space reference (Hunter 1961, same
/// G∞, G1, τ, R = Ro, load and V = v0 of the branch) has its peak.
#[test]
fn resistance_curve_by_arc_length_continuation_brackets_the_peak() {
    let set = [
        "mesh.n_r=6",
        "mesh.n_theta=128",
        "continuation.target=6.0",
        "output.sinks=[\"summary\", \"csv\", \"png\"]",
    ];
    let text = scene_text("scenarios/viscoelastic_resistance_curve.toml");
    let sc = Scene::from_toml_str(&text, "resistance_curve", &set.map(String::from))
        .unwrap_or_else(|e| panic!("{e}"));
    let dir = tempdir::TestDir::new("visco_steady", "resistance_curve");
    let opts = tread::app::RunOptions {
        out_dir: dir.join("run"),
        verbose: false,
        quiet: true,
    };
    tread::app::run(&sc, &opts).unwrap_or_else(|e| panic!("{e}"));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("run/summary.json")).unwrap())
            .unwrap();
    let png = std::fs::metadata(dir.join("run/resistance.png")).expect("resistance.png");
    assert!(png.len() > 10_000, "{png:?}");
    let rr = &summary["results"]["rolling_resistance"];
    let omegas: Vec<f64> = rr["omega"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let coeffs: Vec<f64> = rr["coefficient"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let branch = summary["results"]["branch"].as_array().unwrap();
    assert!(omegas.len() >= 5, "{rr}");
    let peak_omega = rr["peak"]["omega"].as_f64().expect("an interior peak");
    let peak_c = rr["peak"]["coefficient"].as_f64().unwrap();
    println!(
        "branch: {:?}",
        omegas.iter().zip(&coeffs).collect::<Vec<_>>()
    );
    println!("peak: C_rr = {peak_c:.4e} at omega = {peak_omega:.4}");
    assert!(peak_omega > omegas[0] && peak_omega < *omegas.last().unwrap());
    // Direct steady solves at two branch speeds give the branch's coefficient.
    for i in [1, omegas.len() - 2] {
        let om = omegas[i];
        let v0 = branch[i]["v0"].as_f64().unwrap();
        let mut s2: Vec<String> = set[..2].iter().map(|s| s.to_string()).collect();
        s2.push(format!("motion.omega={om}"));
        s2.push(format!("road.v0={v0}"));
        let text2 = text.split("\n[continuation]").next().unwrap().to_string();
        let sc2 = Scene::from_toml_str(&text2, "direct", &s2).unwrap_or_else(|e| panic!("{e}"));
        let mut st = build_steady(&sc2).unwrap_or_else(|e| panic!("{e}"));
        let mut rep = StepReport::default();
        solve_steady(&sc2, &mut st, false, &mut rep, &mut ()).unwrap_or_else(|e| panic!("{e}"));
        let (f, t) = st.sys.hub_reaction();
        let c = t / (-f[1] * sc2.geometry.ro);
        println!(
            "omega {om:.4}: branch C_rr {:.8e}, direct {c:.8e}",
            coeffs[i]
        );
        assert!(
            (c - coeffs[i]).abs() < 1e-6 * c.abs(),
            "omega {om}: {c} vs {}",
            coeffs[i]
        );
    }
    // The half-space reference's peak over the same speeds (load of the nearest branch point).
    let load_at = |om: f64| {
        let i = (0..branch.len())
            .min_by(|&a, &b| {
                let da = (branch[a]["omega"].as_f64().unwrap() - om).abs();
                let db = (branch[b]["omega"].as_f64().unwrap() - om).abs();
                da.total_cmp(&db)
            })
            .unwrap();
        -branch[i]["hub_force_y"].as_f64().unwrap()
    };
    let v_per_omega = branch[0]["v0"].as_f64().unwrap() / omegas[0];
    let grid: Vec<f64> = (0..=40)
        .map(|k| 0.3 * (20.0f64).powf(k as f64 / 40.0))
        .collect();
    let href: Vec<f64> = grid
        .iter()
        .map(|&om| {
            let pb = hunter::HunterProblem {
                g_inf: 200.0,
                g1: 100.0,
                tau: 0.03,
                radius: sc.geometry.ro,
                load: load_at(om),
            };
            pb.solve(v_per_omega * om, 40)
                .map_or(f64::NAN, |s| -s.resistance)
        })
        .collect();
    let k = (0..grid.len())
        .max_by(|&a, &b| href[a].total_cmp(&href[b]))
        .unwrap();
    println!(
        "half-space reference: peak C_rr = {:.4e} at omega = {:.4}",
        href[k], grid[k]
    );
    assert!(k > 0 && k + 1 < grid.len());
    assert!(
        (peak_omega / grid[k] - 1.0).abs() < 0.25,
        "{peak_omega} vs {}",
        grid[k]
    );
    assert!(
        (peak_c / href[k] - 1.0).abs() < 0.1,
        "{peak_c} vs {}",
        href[k]
    );
}

/// `tread compare` on the viscoelastic scene as shipped (2 × 32, default tolerances; 10 s):
/// the transient's internal variables at its last node passage, re-indexed to the referential
/// cells and rotated into the referential frame, against the steady ones along the rings.
/// Measured: 8.9 % (relative L2; the hub torque differs by 16 % on this coarse setting, see
/// the ignored test for the tight one). Without the rotation into the referential frame the
/// difference was 142 %, and a history one cell off differs by 100 % (asserted below): the
/// bound checks the bookkeeping. The re-indexing is also checked to invert its inverse exactly.
#[test]
fn compare_reports_the_internal_variables_along_rings() {
    use tread::app::RunOptions;
    use tread::driver::transient::reindex_history;
    let sc = Scene::from_toml_str(
        &scene_text(SCENE),
        "visco_compare_history",
        &["output.sinks=[\"summary\",\"csv\"]".to_string()],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let dir = tempdir::TestDir::new("visco_steady", "compare-history");
    let out = tread::driver::compare::run(
        &sc,
        &RunOptions {
            out_dir: dir.to_path_buf(),
            verbose: false,
            quiet: true,
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let c = &out.summary["results"]["compare"];
    let h = c["history_rel_l2"].as_f64().expect("history compared");
    let hm = c["history_rel_max"].as_f64().expect("history compared");
    eprintln!("internal variables: rel L2 {h:.3e}, rel max {hm:.3e}");
    assert!(
        h < 0.15 && hm < 0.15,
        "history differences {h:.3e} / {hm:.3e}"
    );
    let rings = std::fs::read_to_string(dir.join("history_rings.csv")).unwrap();
    // 2 × 32 Q2: 3 Gauss points per direction, 6 rings.
    assert_eq!(rings.lines().count(), 7, "{rings}");
    // The re-indexing inverts exactly.
    let st = tread::app::run(
        &{
            let mut s = sc.clone();
            s.analysis.mode = tread::io::scene::Mode::Steady;
            s
        },
        &RunOptions {
            out_dir: dir.join("steady_only"),
            verbose: false,
            quiet: true,
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let hs = st.history.expect("steady history");
    for k in [1i64, 7, 45] {
        let phi = k as f64 * 2.0 * std::f64::consts::PI / 32.0;
        let back = reindex_history(&reindex_history(&hs, 32, -k, -phi), 32, k, phi);
        let err = back
            .data
            .iter()
            .zip(&hs.data)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(err < 1e-15, "k = {k}: {err:.2e}");
        let d = tread::driver::compare::history_difference(&sc, &back, &hs)
            .unwrap()
            .unwrap();
        assert!(d.rel_l2 < 1e-14);
    }
    // A history turned by one cell too many differs.
    let wrong = reindex_history(&hs, 32, 1, 2.0 * std::f64::consts::PI / 32.0);
    let d = tread::driver::compare::history_difference(&sc, &wrong, &hs)
        .unwrap()
        .unwrap();
    eprintln!("one cell off: {:.3e}", d.rel_l2);
    assert!(d.rel_l2 > 0.05);
}
