//! The `tread` binary: runs scenes, writes summary.json, rejects malformed scenes with the key
//! named and a non-zero exit, never panics.

#[path = "common/tempdir.rs"]
mod tempdir;

use std::process::Command;
use tempdir::TestDir;

fn tread() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tread"))
}

fn tmpdir(name: &str) -> TestDir {
    TestDir::new("cli", name)
}

const GOOD: &str = r#"
[scene]
name = "cli_test"
[geometry]
ri = 1.0
ro = 2.0
[mesh]
n_r = 2
n_theta = 16
[material]
model = "neo_hookean"
mu = 200.0
lambda = 1800.0
rho = 0.027
[analysis]
mode = "spinning"
[motion]
omega = 20.0
"#;

fn run_bad(name: &str, text: &str) -> (i32, String) {
    let d = tmpdir(name);
    let f = d.join("scene.toml");
    std::fs::write(&f, text).unwrap();
    let out = tread()
        .args([
            "run",
            f.to_str().unwrap(),
            "--out",
            d.join("out").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!stderr.contains("panicked"), "{name}: panic: {stderr}");
    (out.status.code().unwrap_or(-1), stderr)
}

#[test]
fn run_writes_summary_with_required_keys() {
    let d = tmpdir("good");
    let f = d.join("scene.toml");
    std::fs::write(&f, GOOD).unwrap();
    let out_dir = d.join("out");
    let out = tread()
        .args([
            "run",
            f.to_str().unwrap(),
            "--out",
            out_dir.to_str().unwrap(),
            "--set",
            "mesh.n_r=3",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("summary.json"));
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("summary.json")).unwrap())
            .unwrap();
    for k in [
        "scene",
        "mode",
        "dofs",
        "newton_iterations",
        "wall_time_s",
        "converged",
    ] {
        assert!(!s[k].is_null(), "summary.json lacks `{k}`");
    }
    for k in [
        "u_r_outer",
        "sigma_r_inner",
        "sigma_theta_inner",
        "sigma_r_outer",
        "sigma_theta_outer",
    ] {
        assert!(
            s["results"][k].as_f64().is_some_and(f64::is_finite),
            "results.{k} missing"
        );
    }
    assert_eq!(s["converged"], true);
    assert_eq!(s["mesh"]["n_r"], 3, "--set override not applied");
    assert!(s["results"]["u_r_outer"].as_f64().unwrap() > 0.0);
    let csv = std::fs::read_to_string(out_dir.join("profile.csv")).unwrap();
    assert!(csv.starts_with("r,u_r,sigma_r") && !csv.contains("NaN"));
}

#[test]
fn check_prints_resolved_scene() {
    let d = tmpdir("check");
    let f = d.join("scene.toml");
    std::fs::write(&f, GOOD).unwrap();
    let out = tread()
        .args(["check", f.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success());
    let s = String::from_utf8_lossy(&out.stdout);
    assert!(
        s.contains("tolerance") && s.contains("grading_r"),
        "defaults not printed: {s}"
    );
}

#[test]
fn malformed_scenes_exit_nonzero_naming_the_key() {
    let (code, err) = run_bad("unknown", &GOOD.replace("ro = 2.0", "ro = 2.0\nrout = 3.0"));
    assert_ne!(code, 0);
    assert!(err.contains("rout"), "unknown key not named: {err}");
    let (code, err) = run_bad("type", &GOOD.replace("n_r = 2", "n_r = \"two\""));
    assert_ne!(code, 0);
    assert!(err.contains("n_r"), "wrong type not named: {err}");
    let (code, err) = run_bad("ri_ge_ro", &GOOD.replace("ri = 1.0", "ri = 2.5"));
    assert_ne!(code, 0);
    assert!(err.contains("geometry.r"), "ri >= ro not named: {err}");
    assert!(
        err.contains(":5") || err.contains(":6"),
        "line not given: {err}"
    );
    let (code, err) = run_bad("rho", &GOOD.replace("rho = 0.027", "rho = -1.0"));
    assert_ne!(code, 0);
    assert!(err.contains("rho"), "{err}");
    let (code, err) = run_bad("mode", &GOOD.replace("\"spinning\"", "\"warp\""));
    assert_ne!(code, 0);
    assert!(err.contains("mode"), "{err}");
}

/// A sweep file given to `tread run` (or `check`) gets one error that names the command to
/// use, not one per unknown section; a scene that only has a stray [sweep] table besides its
/// [scene] still gets the usual unknown-section error.
#[test]
fn a_sweep_file_is_pointed_to_tread_sweep() {
    let sweep = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenarios/sweep_creep_force.toml"
    );
    for cmd in ["run", "check"] {
        let out = tread().args([cmd, sweep]).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{cmd}: {err}");
        assert!(err.contains("tread sweep run"), "{cmd}: {err}");
        assert_eq!(err.matches("unknown section").count(), 0, "{cmd}: {err}");
    }
    let (code, err) = run_bad("stray_sweep", &format!("{GOOD}\n[sweep]\nname = \"x\"\n"));
    assert_ne!(code, 0);
    assert!(err.contains("unknown section"), "{err}");
}

#[test]
fn bad_cli_input_is_an_error_not_a_panic() {
    let out = tread()
        .args(["run", "/nonexistent/scene.toml"])
        .output()
        .unwrap();
    assert_ne!(out.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot read"));
    let d = tmpdir("badset");
    let f = d.join("scene.toml");
    std::fs::write(&f, GOOD).unwrap();
    let out = tread()
        .args(["run", f.to_str().unwrap(), "--set", "mesh.bogus=1"])
        .output()
        .unwrap();
    assert_ne!(out.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&out.stderr).contains("bogus"));
    let out = tread()
        .args(["run", f.to_str().unwrap(), "--mode", "teleport"])
        .output()
        .unwrap();
    assert_ne!(out.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&out.stderr).contains("mode"));
}

#[test]
fn failed_solve_writes_summary_and_exits_nonzero() {
    // Far beyond the neo-Hookean spin limit (no equilibrium exists): the solver must give up
    // with a typed error, keep its outputs and exit with code 1.
    let d = tmpdir("fail");
    let f = d.join("scene.toml");
    std::fs::write(
        &f,
        GOOD.replace("omega = 20.0", "omega = 400.0")
            + "[solver]\nmax_cutbacks = 3\nmax_iterations = 8\n",
    )
    .unwrap();
    let out_dir = d.join("out");
    let out = tread()
        .args([
            "run",
            f.to_str().unwrap(),
            "--out",
            out_dir.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(!err.contains("panicked"));
    let text = std::fs::read_to_string(out_dir.join("summary.json")).unwrap();
    assert!(!text.contains("NaN"));
    let s: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(s["converged"], false);
    assert!(s["error"].as_str().is_some());
}

fn run_scene_file(name: &str, path: &str, extra: &[&str]) -> serde_json::Value {
    let d = tmpdir(name);
    let out_dir = d.join("out");
    let mut args = vec!["run", path, "--out", out_dir.to_str().unwrap()];
    args.extend_from_slice(extra);
    let out = tread()
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(&args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(&std::fs::read_to_string(out_dir.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn indentation_scene_writes_contact_results() {
    let s = run_scene_file(
        "indent",
        "scenarios/indentation_friction.toml",
        &["--set", "mesh.n_theta=48", "--set", "mesh.n_r=3"],
    );
    for k in [
        "hub_force_x",
        "hub_force_y",
        "hub_torque",
        "contact_x_min",
        "contact_x_max",
        "max_pressure",
    ] {
        assert!(
            s["results"][k].as_f64().is_some_and(f64::is_finite),
            "results.{k} missing: {s}"
        );
    }
    assert!(s["results"]["hub_force_y"].as_f64().unwrap() < 0.0);
    assert_eq!(s["terms"]["friction"], true);
    assert!(s["terms"]["contact_facets_per_iteration"].as_f64().unwrap() > 0.0);
}

#[test]
fn stick_slip_scene_matches_closed_form_cycle() {
    let s = run_scene_file("stickslip", "scenarios/stick_slip.toml", &[]);
    let pe = s["results"]["period_rel_error"].as_f64().unwrap();
    let ae = s["results"]["amplitude_rel_error"].as_f64().unwrap();
    assert!(
        pe.abs() < 0.01 && ae.abs() < 0.01,
        "period error {pe}, amplitude error {ae}"
    );
}

#[test]
fn invalid_contact_and_friction_values_are_rejected_naming_the_key() {
    let base = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenarios/indentation_friction.toml"
    ))
    .unwrap();
    for (key, set) in [
        ("c_n", "contact.c_n=0.0"),
        ("m_n", "contact.m_n=0.5"),
        ("mu", "friction.mu=-0.1"),
        ("eps", "friction.eps=0.0"),
    ] {
        let d = tmpdir(&format!("bad-{key}"));
        let f = d.join("scene.toml");
        std::fs::write(&f, &base).unwrap();
        let out = tread()
            .args(["run", f.to_str().unwrap(), "--set", set])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{key}: {err}");
        assert!(err.contains(key), "{key} not named: {err}");
        assert!(!err.contains("panicked"));
    }
}
