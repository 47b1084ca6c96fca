//! Rolling controls of the steady mode from the scene file (`motion.control` = "free_rolling",
//! "torque", "creep"), the creep–force curve (continuation in the creep) with its Coulomb
//! saturation, the `--dump-matrix` output, and the validation of the new keys.

#[path = "common/tempdir.rs"]
mod tempdir;

use tempdir::TestDir;
use tread::app::RunOptions;
use tread::driver::steady_run;
use tread::io::Scene;

const ODEN: &str = include_str!("../scenarios/oden_hollow_cylinder.toml");
const CREEP: &str = include_str!("../scenarios/creep_force_curve.toml");

fn scene(text: &str, set: &[&str]) -> Scene {
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    Scene::from_toml_str(text, "test", &set).unwrap_or_else(|e| panic!("{e}"))
}

fn run(sc: &Scene, dir: &TestDir) -> serde_json::Value {
    let opts = RunOptions {
        out_dir: dir.to_path_buf(),
        verbose: false,
        quiet: true,
    };
    tread::app::run(sc, &opts)
        .unwrap_or_else(|e| panic!("{e}"))
        .summary
}

fn f(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

/// Free rolling and a given torque, from the default scene file switched to the steady mode.
#[test]
fn free_rolling_and_given_torque_from_the_scene_file() {
    let dir = TestDir::new("steady-controls", "free");
    let sc = scene(
        ODEN,
        &[
            "analysis.mode=steady",
            "motion.ramp=0",
            "road.ramp=0",
            "motion.control=free_rolling",
            "output.sinks=[\"summary\"]",
        ],
    );
    let s = run(&sc, &dir);
    let r = &s["results"];
    let c = &r["control"];
    let (t, tol) = (f(&r["hub_torque"]), f(&c["torque_tolerance"]));
    // Tolerance: TORQUE_RTOL |F_y| Ro with F_y of the press-in state (within a few per cent of
    // the final F_y).
    let fy = f(&r["hub_force_y"]);
    let ratio = tol / (steady_run::TORQUE_RTOL * fy.abs() * 2.0);
    assert!((0.9..1.1).contains(&ratio), "{tol} {fy}");
    assert!(t.abs() <= tol, "free rolling torque {t} > tolerance {tol}");
    // Not vacuous: at the scene's road.v0 the torque was far from zero.
    let t0 = f(&c["history"][0][1]);
    assert!(t0.abs() > 1e4 * tol, "press-in torque {t0}");
    // The free-rolling radius is a plausible rolling radius (between H and a bit above Ro).
    let re = f(&c["rolling_radius"]);
    assert!(re > 1.9 && re < 2.2, "R_e = {re}");
    assert_eq!(f(&c["creep"]), 0.0);
    assert!((f(&r["v0"]) - f(&c["v0_free"])).abs() < 1e-12);

    // Given torque (braking moment on the hub): T = target to the tolerance.
    let dir = TestDir::new("steady-controls", "torque");
    let sc = scene(
        ODEN,
        &[
            "analysis.mode=steady",
            "motion.ramp=0",
            "road.ramp=0",
            "motion.control=torque",
            "motion.torque=-20.0",
            "output.sinks=[\"summary\"]",
        ],
    );
    let s = run(&sc, &dir);
    let r = &s["results"];
    let (t, tol) = (f(&r["hub_torque"]), f(&r["control"]["torque_tolerance"]));
    assert!((t + 20.0).abs() <= tol, "torque {t}, target -20, tol {tol}");
}

/// The creep–force curve from braking to driving (scenario file, coarser creep step): F_x
/// decreases monotonically with the creep, passes through zero torque at ξ = 0 (free rolling
/// by definition of the creep), is nearly odd in ξ, and saturates at the Coulomb limit
/// ∓μ|F_y| (full sliding) at |ξ| = 0.15.
#[test]
fn creep_force_curve_saturates_at_coulomb_limit() {
    let dir = TestDir::new("steady-controls", "creep");
    let sc = scene(
        CREEP,
        &[
            "continuation.ds=0.1",
            "continuation.ds_max=0.1",
            "output.sinks=[\"summary\", \"csv\"]",
        ],
    );
    let mu = sc.friction.get("mu").unwrap_or(f64::NAN);
    let s = run(&sc, &dir);
    let b = s["results"]["branch"]
        .as_array()
        .unwrap_or_else(|| panic!("no branch"))
        .clone();
    assert_eq!(b.len(), 11, "points at xi = -0.15, -0.12, ..., 0.15");
    let xi: Vec<f64> = b.iter().map(|p| f(&p["creep"])).collect();
    let fx: Vec<f64> = b.iter().map(|p| f(&p["hub_force_x"])).collect();
    let fy: Vec<f64> = b.iter().map(|p| f(&p["hub_force_y"])).collect();
    let tq: Vec<f64> = b.iter().map(|p| f(&p["hub_torque"])).collect();
    assert!((xi[0] + 0.15).abs() < 1e-12 && (xi[10] - 0.15).abs() < 1e-12);
    // Monotone: F_x decreases as the road speeds up (to a small fraction of μ|F_y|).
    let lim: Vec<f64> = fy.iter().map(|y| mu * y.abs()).collect();
    for k in 1..b.len() {
        assert!(
            fx[k] <= fx[k - 1] + 1e-3 * lim[k],
            "F_x not monotone at xi = {}: {} after {}",
            xi[k],
            fx[k],
            fx[k - 1]
        );
    }
    // ξ = 0 is free rolling: zero torque (to the continuation's Newton tolerance).
    assert!(xi[5].abs() < 1e-12);
    assert!(
        tq[5].abs() < 1e-4 * tq[0].abs(),
        "torque at zero creep {} (ends {})",
        tq[5],
        tq[0]
    );
    // Coulomb saturation at both ends: the whole patch slides.
    assert!(
        (fx[0] - lim[0]).abs() < 0.02 * lim[0],
        "braking end: F_x = {}, mu |F_y| = {}",
        fx[0],
        lim[0]
    );
    assert!(
        (fx[10] + lim[10]).abs() < 0.02 * lim[10],
        "driving end: F_x = {}, -mu |F_y| = {}",
        fx[10],
        -lim[10]
    );
    // Nearly odd in ξ, up to the rolling resistance: at free rolling (zero torque) the contact
    // damping still leaves a small F_x(0), which shifts the curve.
    assert!(
        fx[5].abs() < 0.1 * lim[5],
        "rolling resistance at free rolling {} against mu |F_y| = {}",
        fx[5],
        lim[5]
    );
    for k in 0..5 {
        assert!(
            (fx[k] + fx[10 - k]).abs() < 0.1 * lim[k] + 2.0 * fx[5].abs(),
            "not odd-ish at |xi| = {}: {} vs {}",
            xi[10 - k],
            fx[k],
            fx[10 - k]
        );
    }
    assert!(dir.join("branch.csv").exists());
}

/// With the damping law that jumps in at first contact (l_n = 0) the steady residual is
/// discontinuous where a node crosses the patch edge: the creep continuation cannot pass such a
/// point. It must stop in bounded time with an error that names the creep reached, keep the
/// points it found, and never loop on ever smaller steps.
#[test]
fn creep_continuation_with_jumping_damping_stops_cleanly() {
    let dir = TestDir::new("steady-controls", "creep-ln0");
    let sc = scene(
        CREEP,
        &[
            "contact.l_n=0",
            "contact.b_n=5",
            "solver.max_cutbacks=6",
            "output.sinks=[\"summary\", \"csv\"]",
        ],
    );
    let opts = RunOptions {
        out_dir: dir.to_path_buf(),
        verbose: false,
        quiet: true,
    };
    match tread::app::run(&sc, &opts) {
        Ok(out) => {
            // Reaching the target is acceptable only if the whole curve is there.
            let b = out.summary["results"]["branch"]
                .as_array()
                .map_or(0, |b| b.len());
            assert_eq!(b, 51, "a successful run must give the whole curve");
        }
        Err(e) => {
            let msg = e.to_string();
            assert!(!msg.is_empty());
            let s: serde_json::Value = serde_json::from_str(
                &std::fs::read_to_string(dir.join("summary.json"))
                    .unwrap_or_else(|e| panic!("partial summary.json: {e}")),
            )
            .unwrap_or_else(|e| panic!("{e}"));
            let why = s["results"]["continuation"]["stop_reason"]
                .as_str()
                .unwrap_or_else(|| panic!("no stop_reason in {s}"));
            assert!(why.contains("failed at creep"), "{why}");
            let rows = std::fs::read_to_string(dir.join("branch.csv"))
                .unwrap_or_else(|e| panic!("branch.csv: {e}"));
            assert!(
                rows.lines().count() > 10,
                "points before the failure are kept"
            );
        }
    }
}

/// `--dump-matrix`: the tangent and right-hand side as MatrixMarket files, consistent with
/// the solver's system size and pattern.
#[test]
fn dump_matrix_writes_matrix_market() {
    let dir = TestDir::new("steady-controls", "dump");
    let sc = scene(
        ODEN,
        &[
            "analysis.mode=steady",
            "motion.ramp=0",
            "road.ramp=0",
            "mesh.n_theta=32",
            "mesh.n_r=2",
            "output.sinks=[\"summary\"]",
        ],
    );
    let opts = RunOptions {
        out_dir: dir.to_path_buf(),
        verbose: false,
        quiet: true,
    };
    let path = dir.join("K.mtx");
    let o = steady_run::run_with_dump(&sc, &opts, Some(&path)).unwrap_or_else(|e| panic!("{e}"));
    let n = o.summary["dofs"].as_u64().unwrap_or(0) as usize;
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{e}"));
    let mut lines = text.lines().filter(|l| !l.starts_with('%'));
    assert!(text.starts_with("%%MatrixMarket matrix coordinate real general"));
    let head: Vec<usize> = lines
        .next()
        .unwrap_or("")
        .split_whitespace()
        .map(|v| v.parse().unwrap_or(0))
        .collect();
    assert_eq!(&head[..2], &[n, n]);
    let mut count = 0;
    let mut diag = vec![0.0f64; n];
    for l in lines {
        let v: Vec<&str> = l.split_whitespace().collect();
        let (i, j): (usize, usize) = (v[0].parse().unwrap_or(0), v[1].parse().unwrap_or(0));
        let a: f64 = v[2].parse().unwrap_or(f64::NAN);
        assert!((1..=n).contains(&i) && (1..=n).contains(&j) && a.is_finite());
        if i == j {
            diag[i - 1] = a;
        }
        count += 1;
    }
    assert_eq!(count, head[2]);
    assert!(diag.iter().all(|d| *d != 0.0), "a zero diagonal entry");
    let (_, rhs_path) = steady_run::dump_paths(&path);
    let rhs = std::fs::read_to_string(rhs_path).unwrap_or_else(|e| panic!("{e}"));
    assert!(rhs.starts_with("%%MatrixMarket matrix array real general"));
    assert_eq!(rhs.lines().count(), n + 2);
}

#[test]
fn control_keys_are_validated() {
    let bad = |set: &[&str]| -> String {
        let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
        match Scene::from_toml_str(ODEN, "test", &set) {
            Ok(_) => panic!("accepted {set:?}"),
            Err(e) => e.to_string(),
        }
    };
    // Free rolling / creep are steady controls.
    let e = bad(&["motion.control=free_rolling"]);
    assert!(e.contains("motion.control") && e.contains("steady"), "{e}");
    // A creep needs control = "creep"; it must be > -1.
    let e = bad(&[
        "analysis.mode=steady",
        "motion.ramp=0",
        "road.ramp=0",
        "motion.creep=0.1",
    ]);
    assert!(e.contains("motion.creep"), "{e}");
    let e = bad(&[
        "analysis.mode=steady",
        "motion.ramp=0",
        "road.ramp=0",
        "motion.control=creep",
        "motion.creep=-1.5",
    ]);
    assert!(e.contains("motion.creep"), "{e}");
    // Continuation in the creep needs a free-rolling reference.
    let set: Vec<String> = ["motion.control=speed", "motion.creep=0"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    match Scene::from_toml_str(CREEP, "test", &set) {
        Ok(_) => panic!("creep continuation with speed control accepted"),
        Err(e) => assert!(e.to_string().contains("continuation.parameter"), "{e}"),
    }
}

/// `tread` without arguments runs the embedded default scene in both modes, compares them,
/// and prints the comparison table and where the files are.
#[test]
fn no_arguments_compares_the_default_scene_in_both_modes() {
    let dir = TestDir::new("steady-controls", "default");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_tread"))
        .current_dir(&*dir)
        .args(["--threads", "1"])
        .output()
        .unwrap_or_else(|e| panic!("{e}"));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("compared the transient and steady modes"),
        "{stdout}"
    );
    // The converged 8 × 128 mesh (17 × 256 nodes, the hub ring fixed).
    assert!(stdout.contains("dofs = 8192"), "{stdout}");
    for q in [
        "hub_force_x [lbf/in]",
        "hub_force_y [lbf/in]",
        "hub_torque [lbf·in/in]",
        "steady solution validated against the transient:",
        "wall time: transient",
        "files:",
    ] {
        assert!(stdout.contains(q), "missing {q}: {stdout}");
    }
    let cmp = dir.join("out").join("oden_hollow_cylinder_compare");
    for f in [
        "summary.json",
        "compare.csv",
        "transient/summary.json",
        "steady/summary.json",
    ] {
        assert!(cmp.join(f).exists(), "missing {f}");
    }
    let s: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(cmp.join("summary.json")).unwrap_or_default(),
    )
    .unwrap_or_default();
    let c = &s["results"]["compare"];
    assert!(f(&c["speedup"]) > 1.0, "{c}");
    assert_eq!(c["validated"].as_bool(), Some(true), "{c}");
    // Wall times are a line of their own, not a row of the comparison table.
    assert!(
        stdout.lines().all(|l| !l.starts_with("wall_time")),
        "{stdout}"
    );
    // The transient runs to time.steady_tol = 1e-4, so the two modes agree closely (measured:
    // field 9.5e-4, hub forces 9.5e-5 and 1.4e-4, torque 4.3e-4; with the scene's 1e-3 the
    // field is 5.7e-3 apart).
    assert!(f(&c["field_rel_l2"]) < 3e-3, "{c}");
    for k in [
        "hub_force_x_rel_diff",
        "hub_force_y_rel_diff",
        "hub_torque_rel_diff",
    ] {
        assert!(f(&c[k]) < 2e-3, "{k}: {c}");
    }
}
