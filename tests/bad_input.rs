//! Bad input to `tread critical`, `tread sweep` and `tread compare`: flags, scenes and sweep files a user can
//! get wrong. Each gets exit status 2 and an error naming what is wrong, never a panic, and
//! writes no result file.

#[path = "common/tempdir.rs"]
mod tempdir;

use std::path::Path;
use std::process::Command;
use tempdir::TestDir;

fn scene(name: &str) -> String {
    format!("{}/scenarios/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// Run `tread -q <args>`; returns the exit status and stderr.
fn tread(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_tread"))
        .arg("-q")
        .args(args)
        .output()
        .expect("run tread");
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
    (out.status.code().unwrap_or(-1), stderr)
}

fn expect_refused(args: &[&str], out: &Path, needles: &[&str]) {
    let (code, err) = tread(args);
    assert_eq!(code, 2, "{args:?}: exit status {code}, stderr: {err}");
    for n in needles {
        assert!(
            err.contains(n),
            "{args:?}: error does not mention {n:?}: {err}"
        );
    }
    assert!(
        !out.join("critical.json").exists(),
        "{args:?}: a result was written"
    );
}

#[test]
fn critical_refuses_bad_flags_and_scenes_by_name() {
    let d = TestDir::new("bad_input", "critical");
    let out = d.path().join("out");
    let o = out.to_str().expect("utf-8 path");
    let spin = scene("spinning_neo_hookean.toml");
    for (extra, needles) in [
        (vec!["--omega-max", "nan"], vec!["--omega-max", "NaN"]),
        (vec!["--omega-max", "inf"], vec!["--omega-max", "inf"]),
        (vec!["--omega-max", "0"], vec!["--omega-max", "> 0"]),
        (vec!["--n-max", "0"], vec!["--n-max", "at least 1"]),
        (
            vec!["--n-min", "5", "--n-max", "2"],
            vec!["--n-min 5 exceeds --n-max 2"],
        ),
        // The 48-cell ring resolves wave numbers up to 24.
        (vec!["--n-min", "50"], vec!["--n-min 50", "24"]),
        (
            vec!["--set", "material.rho=0"],
            vec!["material.rho", "must be > 0"],
        ),
    ] {
        let mut args = vec!["critical", spin.as_str(), "--out", o];
        args.extend(extra);
        expect_refused(&args, &out, &needles);
    }
    // A mesh without rings (Gmsh) has no Fourier reduction.
    let gmsh = scene("two_layer_cylinder.toml");
    expect_refused(
        &["critical", &gmsh, "--out", o],
        &out,
        &["needs the structured annulus mesh"],
    );
    let missing = d.path().join("missing.toml");
    expect_refused(
        &["critical", missing.to_str().unwrap(), "--out", o],
        &out,
        &["cannot read scene", "missing.toml"],
    );
}

#[test]
fn malformed_sweep_files_are_refused_with_the_key_named() {
    let d = TestDir::new("bad_input", "sweep");
    std::fs::copy(
        scene("spinning_neo_hookean.toml"),
        d.path().join("base.toml"),
    )
    .expect("copy the base scene");
    let head = "[sweep]\nname = \"s\"\nscene = \"base.toml\"\n";
    let cases: [(&str, String, &[&str]); 6] = [
        (
            "syntax",
            format!("{head}[[axis]]\nkey = \"motion.omega\"\nvalues = [1.0, 2.0\n"),
            &["TOML syntax", "line 6"],
        ),
        (
            "empty_zip",
            format!("{head}[[axis]]\nzip = []\n"),
            &["axis[0].zip", "non-empty"],
        ),
        (
            "no_base_scene",
            "[sweep]\nname = \"s\"\nscene = \"nowhere.toml\"\n[[axis]]\nkey = \"motion.omega\"\nvalues = [1.0]\n"
                .to_string(),
            &["sweep.scene", "nowhere.toml"],
        ),
        (
            "zero_points",
            format!("{head}[[axis]]\nkey = \"motion.omega\"\nlinear = {{ start = 1.0, stop = 2.0, num = 0 }}\n"),
            &["axis[0].linear.num", "got 0"],
        ),
        (
            "infinite_end",
            format!("{head}[[axis]]\nkey = \"motion.omega\"\nlinear = {{ start = 1.0, stop = inf, num = 3 }}\n"),
            &["axis[0].linear.stop", "finite"],
        ),
        (
            "no_axis",
            head.to_string(),
            &["axis", "missing"],
        ),
    ];
    for (name, text, needles) in cases {
        let f = d.path().join(format!("{name}.toml"));
        std::fs::write(&f, text).expect("write the sweep file");
        let (code, err) = tread(&["sweep", "plan", f.to_str().expect("utf-8 path")]);
        assert_eq!(code, 2, "{name}: exit status {code}, stderr: {err}");
        for n in needles {
            assert!(
                err.contains(n),
                "{name}: error does not mention {n:?}: {err}"
            );
        }
    }
    // Not UTF-8 at all.
    let f = d.path().join("binary.toml");
    std::fs::write(&f, [0xff, 0xfe, 0x00, 0x81]).expect("write");
    let (code, err) = tread(&["sweep", "plan", f.to_str().unwrap()]);
    assert_eq!(code, 2, "binary: {err}");
    assert!(err.contains("UTF-8"), "{err}");
}

/// `tread compare` with a transient too short for one cell passage: exit 2 and an error that
/// says why there is nothing to compare and which key to raise (not a missing-file message).
#[test]
fn compare_with_a_transient_too_short_to_extract_says_so() {
    let d = TestDir::new("bad_input", "compare_short");
    let out = d.path().join("out");
    let o = out.to_str().expect("utf-8 path");
    let sc = scene("oden_hollow_cylinder.toml");
    let (code, err) = tread(&[
        "compare",
        &sc,
        "--out",
        o,
        "--set",
        "mesh.n_r=1",
        "--set",
        "mesh.n_theta=16",
        "--set",
        "time.t_end=0.01",
        "--set",
        "output.sinks=[\"summary\"]",
    ]);
    assert_eq!(code, 2, "exit status {code}, stderr: {err}");
    for n in ["before its first cell passage", "time.t_end", "0.01"] {
        assert!(err.contains(n), "error does not mention {n:?}: {err}");
    }
    assert!(!out.join("compare.csv").exists());
}
