//! The transient mode on a mesh read from Gmsh: on the Gmsh-made structured annulus (no ring
//! structure known to the program) the steady-state extraction interpolates the referential
//! field; at the passage angles the rotated nodes land on nodes, so it must reproduce the
//! generator's ring re-indexing, and the whole run must match the generated mesh's run.

#[path = "common/tempdir.rs"]
mod tempdir;

use std::process::Command;
use tempdir::TestDir;

const SCENE: &str = r#"
[scene]
name = "t"
[geometry]
ri = 1.0
ro = 2.0
[material]
model = "mooney_rivlin"
c1 = 80.0
c2 = 20.0
kappa = 2000.0
rho = 0.027
[analysis]
mode = "transient"
[motion]
omega = 10.0
ramp = 0.02
[road]
disp = 0.05
ramp = 0.02
v0 = 19.8
[contact]
c_n = 2.0e4
quadrature = "gauss"
points = 3
[friction]
law = "coulomb_tanh"
mu = 0.3
eps = 0.5
[time]
dt = 2.0e-3
t_end = 0.25
adaptive = false
stop_at_steady = false
[output]
sinks = ["summary"]
"#;

fn run(dir: &std::path::Path, name: &str, mesh: &str) -> serde_json::Value {
    let f = dir.join(format!("{name}.toml"));
    std::fs::write(&f, format!("{SCENE}[mesh]\n{mesh}\n")).expect("write");
    let out_dir = dir.join(name);
    let out = Command::new(env!("CARGO_BIN_EXE_tread"))
        .args(["-q", "run", f.to_str().expect("path"), "--out"])
        .arg(&out_dir)
        .output()
        .expect("run tread");
    assert!(
        out.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let s = std::fs::read_to_string(out_dir.join("summary.json")).expect("summary");
    serde_json::from_str(&s).expect("json")
}

/// Every number of `a` (recursively) equals the one of `b` to `tol` relative to `scale`.
fn compare(path: &str, a: &serde_json::Value, b: &serde_json::Value, scale: f64, n: &mut usize) {
    use serde_json::Value::*;
    match (a, b) {
        (Number(x), Number(y)) => {
            let (x, y) = (x.as_f64().unwrap_or(0.0), y.as_f64().unwrap_or(0.0));
            let tol = 1e-8 * x.abs().max(scale);
            assert!((x - y).abs() <= tol, "{path}: {x} vs {y}");
            *n += 1;
        }
        (Object(m), Object(o)) => {
            for (k, v) in m {
                if let Some(w) = o.get(k) {
                    compare(&format!("{path}.{k}"), v, w, scale, n);
                }
            }
        }
        (Array(m), Array(o)) => {
            assert_eq!(m.len(), o.len(), "{path}: lengths");
            for (i, (v, w)) in m.iter().zip(o).enumerate() {
                compare(&format!("{path}[{i}]"), v, w, scale, n);
            }
        }
        _ => {}
    }
}

#[test]
fn gmsh_annulus_transient_matches_generator() {
    let d = TestDir::new("gmsh-transient", "run");
    let gen = run(d.path(), "gen", "n_r = 2\nn_theta = 16\norder = 2");
    let file = format!(
        "file = \"{}/tests/gmsh_data/annulus_q2.msh\"",
        env!("CARGO_MANIFEST_DIR")
    );
    let gm = run(d.path(), "gmsh", &file);
    let r = &gen["results"];
    let passages = r["passages"]
        .as_u64()
        .or_else(|| r["transient"]["passages"].as_u64());
    eprintln!("generated: {r}");
    let scale = r["hub_force_y"]
        .as_f64()
        .or_else(|| r["hub_force"][1].as_f64())
        .map_or(1.0, f64::abs)
        .max(1.0);
    let mut n = 0;
    compare("results", r, &gm["results"], scale, &mut n);
    assert!(n > 5, "compared {n} numbers");
    assert!(
        passages.is_none_or(|p| p > 0),
        "no node passage: {passages:?}"
    );
}
