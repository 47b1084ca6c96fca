//! Regression summaries: every scene under `scenarios/` is re-run on its own (small) mesh with one
//! thread and its `summary.json` compared, number by number, with the one committed in
//! `tests/regression/` (see its README). Wall times, thread counts and the version are not
//! compared; every other number must agree to 1e-9 relative (with an absolute floor of 1e-13 of
//! the largest number of the same summary's `results`, for quantities that are round-off noise
//! around zero, e.g. the hub torque of a spinning annulus). Strings, booleans and nulls must be
//! equal, and the key sets must match.

#[path = "common/tempdir.rs"]
mod tempdir;

use serde_json::Value;
use std::path::Path;
use std::process::Command;
use tempdir::TestDir;

const REL: f64 = 1e-9;

/// Keys that measure the machine, not the model.
fn ignored(key: &str) -> bool {
    key.contains("wall_time") || key.ends_with("_s") || key == "threads" || key == "version"
}

fn max_abs(v: &Value) -> f64 {
    match v {
        Value::Number(n) => n.as_f64().map_or(0.0, f64::abs),
        Value::Array(a) => a.iter().map(max_abs).fold(0.0, f64::max),
        Value::Object(o) => o
            .iter()
            .filter(|(k, _)| !ignored(k))
            .map(|(_, v)| max_abs(v))
            .fold(0.0, f64::max),
        _ => 0.0,
    }
}

fn compare(path: &str, want: &Value, got: &Value, floor: f64, diffs: &mut Vec<String>) {
    match (want, got) {
        (Value::Number(a), Value::Number(b)) => {
            let (a, b) = (
                a.as_f64().unwrap_or(f64::NAN),
                b.as_f64().unwrap_or(f64::NAN),
            );
            let tol = REL * a.abs().max(b.abs()) + floor;
            if (a - b).abs() > tol || a.is_nan() != b.is_nan() {
                diffs.push(format!(
                    "{path}: {a:e} -> {b:e} (rel {:.2e})",
                    (a - b).abs() / a.abs().max(1e-300)
                ));
            }
        }
        (Value::Object(a), Value::Object(b)) => {
            for (k, va) in a {
                if ignored(k) {
                    continue;
                }
                match b.get(k) {
                    Some(vb) => compare(&format!("{path}.{k}"), va, vb, floor, diffs),
                    None => diffs.push(format!("{path}.{k}: missing")),
                }
            }
            for k in b.keys() {
                if !ignored(k) && !a.contains_key(k) {
                    diffs.push(format!("{path}.{k}: new key"));
                }
            }
        }
        (Value::Array(a), Value::Array(b)) => {
            if a.len() != b.len() {
                diffs.push(format!("{path}: length {} -> {}", a.len(), b.len()));
            }
            for (i, (va, vb)) in a.iter().zip(b).enumerate() {
                compare(&format!("{path}[{i}]"), va, vb, floor, diffs);
            }
        }
        (a, b) if a == b => {}
        (a, b) => diffs.push(format!("{path}: {a} -> {b}")),
    }
}

fn check(scene: &str, extra: &[&str], reference: &str) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let want: Value = serde_json::from_str(
        &std::fs::read_to_string(root.join("tests/regression").join(reference))
            .unwrap_or_else(|e| panic!("{reference}: {e}")),
    )
    .unwrap_or_else(|e| panic!("{reference}: {e}"));
    let dir = TestDir::new("regression", reference.trim_end_matches(".json"));
    let out = Command::new(env!("CARGO_BIN_EXE_tread"))
        .arg("run")
        .arg(root.join("scenarios").join(scene))
        .args(extra)
        .args([
            "--threads",
            "1",
            "-q",
            "--set",
            "output.sinks=summary",
            "--out",
        ])
        .arg(dir.path())
        .output()
        .expect("run tread");
    let text = std::fs::read_to_string(dir.path().join("summary.json")).unwrap_or_else(|e| {
        panic!(
            "{scene}: no summary.json ({e}); stderr: {}",
            String::from_utf8_lossy(&out.stderr)
        )
    });
    let got: Value = serde_json::from_str(&text).expect("summary.json parses");
    let floor = 1e-13 * want.get("results").map_or(0.0, max_abs);
    let mut diffs = Vec::new();
    compare("", &want, &got, floor, &mut diffs);
    assert!(
        diffs.is_empty(),
        "{scene}: {} differences:\n{}",
        diffs.len(),
        diffs.join("\n")
    );
}

macro_rules! scenes {
    ($($name:ident: $scene:literal $(, $extra:literal)* => $reference:literal;)*) => {$(
        #[test]
        fn $name() {
            check($scene, &[$($extra),*], $reference);
        }
    )*};
}

scenes! {
    braking: "braking.toml" => "braking.json";
    free_rolling: "free_rolling.toml" => "free_rolling.json";
    indentation_friction: "indentation_friction.toml" => "indentation_friction.json";
    indentation_frictionless: "indentation_frictionless.toml" => "indentation_frictionless.json";
    indentation_load_control: "indentation_load_control.toml" => "indentation_load_control.json";
    indentation_3d: "indentation_3d.toml" => "indentation_3d.json";
    spinning_3d: "spinning_3d.toml" => "spinning_3d.json";
    cornering_3d: "cornering_3d.toml" => "cornering_3d.json";
    camber_3d: "camber_3d.toml" => "camber_3d.json";
    traction_3d: "traction_3d.toml" => "traction_3d.json";
    cornering_curve_3d: "cornering_curve_3d.toml" => "cornering_curve_3d.json";
    transient_cornering_3d: "transient_cornering_3d.toml" => "transient_cornering_3d.json";
    viscoelastic_rolling_3d_steady: "viscoelastic_rolling_3d.toml", "--mode", "steady" => "viscoelastic_rolling_3d_steady.json";
    oden_hollow_cylinder: "oden_hollow_cylinder.toml" => "oden_hollow_cylinder.json";
    oden_hollow_cylinder_steady: "oden_hollow_cylinder.toml", "--mode", "steady" => "oden_hollow_cylinder_steady.json";
    oden_steady_sweep: "oden_steady_sweep.toml" => "oden_steady_sweep.json";
    rolling_frictionless: "rolling_frictionless.toml" => "rolling_frictionless.json";
    spinning_incompressible: "spinning_incompressible.toml" => "spinning_incompressible.json";
    spinning_mooney_rivlin: "spinning_mooney_rivlin.toml" => "spinning_mooney_rivlin.json";
    spinning_neo_hookean: "spinning_neo_hookean.toml" => "spinning_neo_hookean.json";
    stick_slip: "stick_slip.toml" => "stick_slip.json";
}
