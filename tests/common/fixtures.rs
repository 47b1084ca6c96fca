#![allow(dead_code)]
//! Fixtures shared by the transient, diffsol, torque and rolling tests (and, as
//! `fixtures::tempdir`, the scratch-directory guard of `tempdir.rs`).

use tread::app::{run, RunOptions};
use tread::driver::transient::{integrate, Kinematics, Ramp, Scheme, TimeOptions, Transient};
use tread::io::Scene;
use tread::material::NeoHookean;
use tread::mesh::{annulus, AnnulusSpec};
use tread::model::SolidSystem;
use tread::physics::{PressureMode, SolidModel};
use tread::solver::{LinearKind, NewtonOptions};

#[path = "tempdir.rs"]
pub mod tempdir;
use tempdir::TestDir;

/// Density of the paper-like cylinder (lbf·s²/in⁴).
pub const RHO: f64 = 0.027;

/// Isoparametric Q2 annulus Ri = 1, Ro = 2, uniform, compressible neo-Hookean (μ = 200,
/// λ = 1800), ρ = [`RHO`].
pub fn neo_hookean_annulus(n_r: usize, n_theta: usize) -> SolidModel {
    let mut mesh = annulus(&AnnulusSpec {
        ri: 1.0,
        ro: 2.0,
        n_r,
        n_theta,
        degree: 2,
        grading_r: 1.0,
        grading_theta: 0.0,
    });
    mesh.make_isoparametric();
    SolidModel::new(
        mesh,
        NeoHookean::new(200.0, 1800.0).into(),
        RHO,
        PressureMode::None,
    )
}

/// Spin-up to `omega` over `ramp` seconds, no road.
pub fn spin_kinematics(omega: f64, ramp: f64) -> Kinematics {
    Kinematics {
        omega: Ramp {
            target: omega,
            time: ramp,
        },
        disp: None,
        h_touch: 2.0,
        load: None,
        v0: Ramp {
            target: 0.0,
            time: 0.0,
        },
    }
}

/// Fixed steps `dt` to `t_end`: no step control, no landing on passages, no stop at steady.
pub fn fixed_step_options(dt: f64, t_end: f64) -> TimeOptions {
    TimeOptions {
        dt,
        dt_min: dt,
        dt_max: dt,
        t_end,
        adaptive: false,
        error_tol: 1e-4,
        steady_tol: 1e-12,
        stop_at_steady: false,
        max_steps: 1_000_000,
        lumped: false,
        land_on_passages: false,
    }
}

/// Newton to 1e-11, at most 20 iterations.
pub fn tight_newton_options() -> NewtonOptions {
    NewtonOptions {
        tol: 1e-11,
        max_iterations: 20,
        ..Default::default()
    }
}

/// u at `t_end` of a spin-up of `model` from rest (ω ramped to 20 rad/s over 0.03 s, no contact)
/// with the one-step `scheme` at fixed steps `dt` (the lumped mass for central difference).
pub fn spin_up_fixed(model: SolidModel, scheme: Scheme, dt: f64, t_end: f64) -> Vec<f64> {
    let lumped = scheme.explicit();
    let mut tr = Transient::new(
        SolidSystem::new(model, "hub"),
        scheme,
        spin_kinematics(20.0, 0.03),
        lumped,
    );
    integrate(
        &mut tr,
        &fixed_step_options(dt, t_end),
        tight_newton_options(),
        LinearKind::Cholesky,
        |_, _| {},
    )
    .unwrap_or_else(|(e, _)| panic!("{e}"));
    tr.state.u.clone()
}

/// ‖a − b‖ / ‖b‖ (Euclidean).
pub fn relative_l2(a: &[f64], b: &[f64]) -> f64 {
    let n = b.iter().map(|v| v * v).sum::<f64>().sqrt();
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
        / n
}

/// Relative errors of `run(dt)` at dt = dt0, dt0/2, dt0/4 against `run(dt0/32)`.
pub fn step_errors(run: impl Fn(f64) -> Vec<f64>, dt0: f64) -> Vec<f64> {
    let reference = run(dt0 / 32.0);
    [1.0, 2.0, 4.0]
        .iter()
        .map(|f| relative_l2(&run(dt0 / f), &reference))
        .collect()
}

/// A scene file of the repository, as text.
pub fn scene_text(path: &str) -> String {
    let full = format!("{}/{path}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(&full).unwrap_or_else(|e| panic!("{full}: {e}"))
}

/// Run a transient rolling scene (text with `--set` overrides) through the program's driver
/// into a temporary directory; it must write `steady_field.csv` and `passages.csv`. Returns
/// summary.json.
pub fn run_rolling(text: &str, name: &str, set: &[&str]) -> serde_json::Value {
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    let scene = Scene::from_toml_str(text, name, &set).unwrap_or_else(|e| panic!("{e}"));
    let out = TestDir::new("rolling", name);
    let o = run(
        &scene,
        &RunOptions {
            out_dir: out.to_path_buf(),
            verbose: false,
            quiet: true,
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(out.join("steady_field.csv").exists() && out.join("passages.csv").exists());
    o.summary
}

/// The scene's polar root mesh refined below the hub (every cell whose centre has y < 0) and
/// once more in the first of those: one-irregular, with hanging nodes and no rings. The scene
/// must have a generated annulus.
pub fn refined_below_hub(sc: &Scene) -> tread::mesh::Mesh {
    let root = tread::driver::adaptive::polar_root(sc).unwrap_or_else(|e| panic!("{e}"));
    let mut forest = tread::mesh::Forest::new(root).unwrap_or_else(|e| panic!("{e}"));
    let below: Vec<usize> = (0..forest.leaves().len())
        .filter(|&c| forest.root_point(c, 0.0, 0.0)[1] < 0.0)
        .collect();
    forest.refine(&below).unwrap_or_else(|e| panic!("{e}"));
    forest.refine(&[below[0]]).unwrap_or_else(|e| panic!("{e}"));
    let (mesh, _) = forest.mesh();
    assert!(!mesh.constraints.is_empty() && mesh.rings.is_none());
    mesh
}

/// Largest |K − K_fd| of a tangent K (entry (i, j) given by `k`) against central differences
/// of the residual of `sys` at its current state with step `h`, column by column (a tiny
/// system). The state is restored after each column.
pub fn fd_max_error<S: tread::solver::NonlinearSystem>(
    sys: &mut S,
    h: f64,
    k: impl Fn(usize, usize) -> f64,
) -> f64 {
    let n = sys.n_eq();
    let mut err = 0.0f64;
    let mut e = vec![0.0; n];
    for j in 0..n {
        e.fill(0.0);
        e[j] = h;
        sys.update(1.0, &e);
        assert!(sys.evaluate(false));
        let rp = sys.residual().to_vec();
        sys.update(-2.0, &e);
        assert!(sys.evaluate(false));
        let rm = sys.residual().to_vec();
        sys.update(1.0, &e);
        for i in 0..n {
            err = err.max(((rp[i] - rm[i]) / (2.0 * h) - k(i, j)).abs());
        }
    }
    err
}

/// Largest |K − K_fd| / max |K| of the assembled tangent of `sys` at its current state against
/// central differences (step 1e-6) of its residual ([`fd_max_error`]).
pub fn tangent_fd_error(sys: &mut SolidSystem) -> f64 {
    use tread::solver::NonlinearSystem;
    assert!(sys.evaluate(true));
    let k = sys.asm.to_dense();
    let kmax = k.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    fd_max_error(sys, 1e-6, |i, j| k[i][j]) / kmax
}

/// The affine patch test on `sys`: u = H X at every node, then (the largest change the
/// constraints made to it, the largest residual at an equation away from the `hub` and `outer`
/// nodes relative to the force scale).
pub fn affine_patch_test(sys: &mut SolidSystem, h: &tread::math::Mat2) -> (f64, f64) {
    use tread::solver::NonlinearSystem;
    for (n, x) in sys.model.mesh.nodes.iter().enumerate() {
        let u = h * x;
        sys.x[2 * n] = u[0];
        sys.x[2 * n + 1] = u[1];
    }
    let before = sys.x.clone();
    sys.dofs.apply_constraints(&mut sys.x);
    let moved = before
        .iter()
        .zip(&sys.x)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(sys.evaluate(false));
    let boundary: std::collections::HashSet<u32> = ["hub", "outer"]
        .iter()
        .flat_map(|s| sys.model.mesh.node_set(s).iter().copied())
        .collect();
    let scale = sys.asm.scale.iter().fold(0.0f64, |m, v| m.max(*v));
    let mut worst = 0.0f64;
    for n in 0..sys.model.mesh.n_nodes() {
        if boundary.contains(&(n as u32)) {
            continue;
        }
        for i in 0..2 {
            if let Some(e) = sys.dofs.equation(2 * n + i) {
                worst = worst.max(sys.residual()[e].abs());
            }
        }
    }
    (moved, worst / scale)
}

/// Spin (ω² = 3), a body force and a smooth displacement on the free equations of `sys` (its
/// constrained dofs following their masters): the state of the tangent checks.
pub fn smooth_loaded_state(sys: &mut SolidSystem) {
    use tread::math::Vec2;
    use tread::solver::NonlinearSystem;
    sys.model.omega2 = 3.0;
    sys.model.body_force = Some(Box::new(|x: Vec2| {
        Vec2::new(0.3 * x[1], -0.2 * x[0] * x[0])
    }));
    let mut y = vec![0.0; sys.n_eq()];
    for node in 0..sys.model.mesh.n_nodes() {
        let x = sys.model.mesh.nodes[node];
        if let Some(e) = sys.dofs.equation(2 * node) {
            y[e] = 0.05 * (x[0] * 1.3).sin() + 0.02 * x[1];
        }
        if let Some(e) = sys.dofs.equation(2 * node + 1) {
            y[e] = 0.04 * (x[1] * 0.9).cos() * x[0];
        }
    }
    sys.update(1.0, &y);
}
