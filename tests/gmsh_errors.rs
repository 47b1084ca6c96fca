//! Bad mesh files and bad mesh keys: `tread run` exits non-zero with an error naming the file
//! and what is wrong, and never panics.

#[path = "common/tempdir.rs"]
mod tempdir;

use std::path::Path;
use std::process::Command;
use tempdir::TestDir;

fn data(name: &str) -> String {
    format!("{}/tests/gmsh_data/{name}", env!("CARGO_MANIFEST_DIR"))
}

const BASE: &str = r#"
[scene]
name = "bad_mesh"
[geometry]
ri = 1.0
ro = 2.0
[material]
model = "neo_hookean"
mu = 200.0
lambda = 1800.0
rho = 0.027
[analysis]
mode = "spinning"
[motion]
omega = 10.0
[output]
sinks = ["summary"]
"#;

/// Run `tread run` on a scene text written into `dir`; returns (exit code, stderr).
fn run(dir: &Path, scene: &str) -> (i32, String) {
    let f = dir.join("scene.toml");
    std::fs::write(&f, scene).expect("write scene");
    let out = Command::new(env!("CARGO_BIN_EXE_tread"))
        .args([
            "-q",
            "run",
            f.to_str().expect("utf-8 path"),
            "--out",
            dir.join("out").to_str().expect("utf-8 path"),
        ])
        .output()
        .expect("run tread");
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
    (out.status.code().unwrap_or(-1), stderr)
}

fn expect_error(name: &str, mesh_keys: &str, needles: &[&str]) {
    let d = TestDir::new("gmsh", name);
    let (code, err) = run(d.path(), &format!("{BASE}[mesh]\n{mesh_keys}\n"));
    assert_eq!(code, 2, "{name}: exit code {code}, stderr: {err}");
    for n in needles {
        assert!(
            err.contains(n),
            "{name}: error does not mention {n:?}: {err}"
        );
    }
}

#[test]
fn good_gmsh_scene_runs() {
    let d = TestDir::new("gmsh", "good");
    let (code, err) = run(
        d.path(),
        &format!("{BASE}[mesh]\nfile = \"{}\"\n", data("annulus_q2.msh")),
    );
    assert_eq!(code, 0, "{err}");
    let s = std::fs::read_to_string(d.join("out/summary.json")).expect("summary");
    let v: serde_json::Value = serde_json::from_str(&s).expect("json");
    assert_eq!(v["converged"], true);
    assert!(v["results"]["u_r_outer"].as_f64().is_some_and(|u| u > 0.0));
}

#[test]
fn missing_physical_group_is_named() {
    expect_error(
        "group",
        &format!("file = \"{}\"\nhub = \"rim\"", data("annulus_q2.msh")),
        &[
            "annulus_q2.msh",
            "\"rim\"",
            "\"hub\"",
            "\"contact\"",
            "[mesh] hub",
        ],
    );
    expect_error(
        "contact_group",
        &format!("file = \"{}\"\ncontact = \"tread\"", data("annulus_q2.msh")),
        &["\"tread\"", "[mesh] contact"],
    );
}

#[test]
fn missing_region_is_named() {
    let d = TestDir::new("gmsh", "region");
    let scene = BASE.replace("[material]\n", "[[material]]\nregion = \"core\"\n")
        + &format!("[mesh]\nfile = \"{}\"\n", data("annulus_q2.msh"));
    let (code, err) = run(d.path(), &scene);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("\"core\"") && err.contains("\"annulus\""),
        "{err}"
    );
}

#[test]
fn unsupported_element_is_named() {
    expect_error(
        "triangles",
        &format!("file = \"{}\"", data("triangles.msh")),
        &[
            "triangles.msh",
            "unsupported element type",
            "Tri3",
            "quadrilaterals",
        ],
    );
}

#[test]
fn truncated_file_is_reported() {
    let d = TestDir::new("gmsh", "truncated");
    let full = std::fs::read(data("annulus_q2.msh")).expect("mesh");
    for (k, frac) in [0.3, 0.6, 0.95].iter().enumerate() {
        let cut = d.join(format!("cut{k}.msh"));
        std::fs::write(&cut, &full[..(full.len() as f64 * frac) as usize]).expect("write");
        let (code, err) = run(
            d.path(),
            &format!("{BASE}[mesh]\nfile = \"{}\"\n", cut.display()),
        );
        assert_eq!(code, 2, "cut at {frac}: {err}");
        assert!(err.contains(&format!("cut{k}.msh")), "{err}");
        assert!(
            err.contains("truncated") || err.contains("malformed"),
            "cut at {frac}: {err}"
        );
    }
    // Binary file cut short.
    let full = std::fs::read(data("annulus_q2_binary.msh")).expect("mesh");
    let cut = d.join("cutb.msh");
    std::fs::write(&cut, &full[..full.len() * 2 / 3]).expect("write");
    let (code, err) = run(
        d.path(),
        &format!("{BASE}[mesh]\nfile = \"{}\"\n", cut.display()),
    );
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("cutb.msh"), "{err}");
}

#[test]
fn nonexistent_and_non_msh_files_are_reported() {
    expect_error(
        "missing",
        "file = \"no/such/tyre.msh\"",
        &["tyre.msh", "cannot read"],
    );
    let d = TestDir::new("gmsh", "version");
    std::fs::write(d.join("old.msh"), "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n").expect("write");
    std::fs::write(d.join("junk.msh"), "hello\n").expect("write");
    // Relative paths are relative to the scene file.
    let (code, err) = run(d.path(), &format!("{BASE}[mesh]\nfile = \"old.msh\"\n"));
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("old.msh") && err.contains("2.2") && err.contains("4.1"),
        "{err}"
    );
    let (code, err) = run(d.path(), &format!("{BASE}[mesh]\nfile = \"junk.msh\"\n"));
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("junk.msh") && err.contains("$MeshFormat"),
        "{err}"
    );
}

#[test]
fn mesh_keys_are_checked() {
    // Generator keys with a file, group names without one, [[material]] without a file.
    let d = TestDir::new("gmsh", "keys");
    let (code, err) = run(
        d.path(),
        &format!(
            "{BASE}[mesh]\nfile = \"{}\"\nn_r = 4\n",
            data("annulus_q2.msh")
        ),
    );
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("mesh.n_r"), "{err}");
    let (code, err) = run(d.path(), &format!("{BASE}[mesh]\nhub = \"hub\"\n"));
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("mesh.hub"), "{err}");
    let scene = BASE.replace("[material]\n", "[[material]]\nregion = \"a\"\n");
    let (code, err) = run(d.path(), &scene);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("mesh.file"), "{err}");
    // A [[material]] entry without `region`, and a bad key in a later entry.
    let scene = BASE.replace("[material]\n", "[[material]]\nregion = \"a\"\n")
        + "[[material]]\nregion = \"b\"\nmodel = \"neo_hookean\"\nmu = 1.0\nlambda = 1.0\nrho = 1.0\nnu = 3\n"
        + "[[material]]\nmodel = \"neo_hookean\"\nmu = 1.0\nlambda = 1.0\nrho = 1.0\n"
        + &format!("[mesh]\nfile = \"{}\"\n", data("annulus_q2.msh"));
    let (code, err) = run(d.path(), &scene);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("material[2].region"), "{err}");
    assert!(err.contains("material[b].nu"), "{err}");
}
