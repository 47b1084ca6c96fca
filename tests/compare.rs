//! `tread compare` (issue 5): the transient mode run to its steady state and the steady mode on
//! the same scene agree, on a frictionless and a frictional scene at two speeds (5 and 10 rad/s)
//! below the critical speed (≈ 41 rad/s for this density): hub forces within 0.5 % of |F|,
//! referential displacement field within 1 % in relative L2, on a 3 × 128 Q2 mesh. The remaining
//! differences are discretization differences of the two formulations on the same mesh
//! (velocities by time integration of the nodes vs ω ∂θχ of the interpolant); they shrink with
//! refinement (64 → 128 cells: Fy difference 1.1 % → 0.5 % at 10 rad/s with friction). At
//! 20 rad/s the gap is larger (forces 1–2 %, field 2–4 %) and not explained yet: see the
//! closing note of issue 5.

#[path = "common/tempdir.rs"]
mod tempdir;

use tempdir::TestDir;
use tread::app::RunOptions;
use tread::io::Scene;

const ODEN: &str = include_str!("../scenarios/oden_hollow_cylinder.toml");
const FRICTIONLESS: &str = include_str!("../scenarios/rolling_frictionless.toml");

fn compare(name: &str, text: &str, omega: f64, extra: &[&str]) -> serde_json::Value {
    let v0 = 1.9666667 * omega;
    let mut set: Vec<String> = vec![
        format!("motion.omega={omega}"),
        format!("road.v0={v0}"),
        "time.error_tol=1e-4".into(),
        "output.sinks=[\"summary\",\"csv\"]".into(),
    ];
    set.extend(extra.iter().map(|s| s.to_string()));
    let scene = Scene::from_toml_str(text, name, &set).unwrap_or_else(|e| panic!("{e}"));
    let dir = TestDir::new("compare", &format!("{name}-{}", omega as u32));
    let out = tread::driver::compare::run(
        &scene,
        &RunOptions {
            out_dir: dir.to_path_buf(),
            verbose: false,
            quiet: true,
        },
    )
    .unwrap_or_else(|e| panic!("compare {name} at {omega}: {e}"));
    let c = out.summary["results"]["compare"].clone();
    assert!(dir.join("compare.csv").exists());
    println!(
        "{name} omega = {omega}: Fx {:.4e} / {:.4e}, Fy {:.4e} / {:.4e}, torque {:.4e} / {:.4e} (transient / steady); rel diffs Fx {:.3e}, Fy {:.3e}; field rel L2 {:.3e}; wall {:.2} s / {:.3} s",
        c["hub_force_x_transient"].as_f64().unwrap(),
        c["hub_force_x_steady"].as_f64().unwrap(),
        c["hub_force_y_transient"].as_f64().unwrap(),
        c["hub_force_y_steady"].as_f64().unwrap(),
        c["hub_torque_transient"].as_f64().unwrap(),
        c["hub_torque_steady"].as_f64().unwrap(),
        c["hub_force_x_rel_diff"].as_f64().unwrap(),
        c["hub_force_y_rel_diff"].as_f64().unwrap(),
        c["field_rel_l2"].as_f64().unwrap(),
        c["wall_time_transient_s"].as_f64().unwrap(),
        c["wall_time_steady_s"].as_f64().unwrap(),
    );
    c
}

fn check(c: &serde_json::Value) {
    assert_eq!(
        c["transient_steady"].as_bool(),
        Some(true),
        "transient not steady"
    );
    let fx = c["hub_force_x_rel_diff"].as_f64().unwrap();
    let fy = c["hub_force_y_rel_diff"].as_f64().unwrap();
    let l2 = c["field_rel_l2"].as_f64().unwrap();
    assert!(fx < 5e-3, "hub force x differs by {fx:.3e} of |F|");
    assert!(fy < 5e-3, "hub force y differs by {fy:.3e} of |F|");
    assert!(
        l2 < 1e-2,
        "referential field differs by {l2:.3e} (relative L2)"
    );
    assert!(c["speedup"].as_f64().unwrap() > 1.0);
}

#[test]
fn steady_matches_transient_frictionless() {
    for omega in [5.0, 10.0] {
        check(&compare("frictionless", FRICTIONLESS, omega, MESH));
    }
}

#[test]
fn steady_matches_transient_with_friction() {
    for omega in [5.0, 10.0] {
        check(&compare("friction", ODEN, omega, MESH));
    }
}

/// Mesh of the comparison (see the module docs).
const MESH: &[&str] = &["mesh.n_theta=128"];
