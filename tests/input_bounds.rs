//! Inputs that cannot lie: what `tread check` passes, `tread run` runs (mesh files, memory);
//! the resolved scene of `tread check` loads back; mesh files are read with a size bound;
//! numbers of no physical magnitude and step controls that could never end are refused with the
//! key and its line; a refused run leaves no output folder; a step that falls below the
//! round-off of its parameter ends the run with a message, never a loop.

#[path = "common/tempdir.rs"]
mod tempdir;

use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};
use tempdir::TestDir;

fn scene(name: &str) -> String {
    format!("{}/scenarios/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// Run `tread <args>` in `dir`, killed after `limit` (a hang is a failure, not a wait).
fn tread_in(dir: &Path, args: &[&str], limit: Duration) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_tread"))
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run tread");
    let t0 = Instant::now();
    loop {
        if child.try_wait().expect("wait").is_some() {
            break;
        }
        if t0.elapsed() > limit {
            let _ = child.kill();
            let o = child.wait_with_output().expect("output");
            panic!(
                "tread {args:?} did not end within {limit:?}; stderr: {}",
                String::from_utf8_lossy(&o.stderr)
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let o = child.wait_with_output().expect("output");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked"), "panic: {err}");
    o
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).to_string()
}

const MINUTE: Duration = Duration::from_secs(60);

/// A missing, unreadable or broken mesh file is refused by `tread check` as by `tread run`, with
/// the scene line of `mesh.file` and the resolved path; the refused run creates no folder.
#[test]
fn check_refuses_what_run_refuses_with_line_and_path() {
    let d = TestDir::new("bounds", "mesh_file");
    let text = std::fs::read_to_string(scene("steady_footprint_refined.toml")).unwrap();
    let line = text
        .lines()
        .position(|l| l.trim_start().starts_with("file ="))
        .expect("mesh.file line")
        + 1;
    let broken = text.replace("\"footprint_refined.msh\"", "\"missing.msh\"");
    let f = d.path().join("scene.toml");
    std::fs::write(&f, &broken).unwrap();
    let resolved = d.path().join("missing.msh");
    for cmd in ["check", "run"] {
        let mut args = vec![cmd, "scene.toml"];
        if cmd == "run" {
            args.extend(["--out", "out"]);
        }
        let o = tread_in(d.path(), &args, MINUTE);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{cmd}: {err}");
        assert!(
            err.contains(&format!("scene.toml:{line}")),
            "{cmd}: no line: {err}"
        );
        assert!(err.contains("mesh.file"), "{cmd}: {err}");
        assert!(
            err.contains(&resolved.display().to_string()),
            "{cmd}: no path: {err}"
        );
    }
    assert!(
        !d.path().join("out").exists(),
        "a refused run created its output folder"
    );

    // Not a mesh: named as such by check.
    std::fs::write(d.path().join("missing.msh"), "hello\n").unwrap();
    let o = tread_in(d.path(), &["check", "scene.toml"], MINUTE);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("not a Gmsh .msh file"),
        "{}",
        stderr(&o)
    );

    // An endless file is refused at the bound, quickly.
    let o = tread_in(
        d.path(),
        &["check", "scene.toml", "--set", "mesh.file=\"/dev/zero\""],
        MINUTE,
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("/dev/zero"), "{}", stderr(&o));
    assert!(stderr(&o).contains("(--set)"), "{}", stderr(&o));

    // A mesh too large for memory: refused by check as by run.
    let o = tread_in(
        d.path(),
        &[
            "check",
            &scene("spinning_neo_hookean.toml"),
            "--set",
            "mesh.n_r=4611686018427387904",
        ],
        MINUTE,
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("memory"), "{}", stderr(&o));
}

/// The listing of `tread check` for a scene with a Gmsh mesh loads back, from another folder.
#[test]
fn resolved_scene_of_a_gmsh_scene_loads_back() {
    let d = TestDir::new("bounds", "round_trip");
    for name in [
        "steady_footprint_refined.toml",
        "two_layer_cylinder.toml",
        "viscoelastic_rolling_gmsh.toml",
    ] {
        let o = tread_in(d.path(), &["check", &scene(name)], MINUTE);
        assert_eq!(o.status.code(), Some(0), "{name}: {}", stderr(&o));
        let listing = String::from_utf8_lossy(&o.stdout).to_string();
        let sub = d.path().join("elsewhere");
        std::fs::create_dir_all(&sub).unwrap();
        std::fs::write(sub.join("resolved.toml"), &listing).unwrap();
        let o = tread_in(d.path(), &["check", "elsewhere/resolved.toml"], MINUTE);
        assert_eq!(o.status.code(), Some(0), "{name} resolved: {}", stderr(&o));
        // The same scene: its own listing again.
        let again = String::from_utf8_lossy(&o.stdout).to_string();
        let body = |s: &str| s.lines().skip(1).collect::<Vec<_>>().join("\n");
        assert_eq!(body(&again), body(&listing), "{name}");
    }
}

/// Subnormal and absurd magnitudes are refused with the key and the rule, before any solve.
#[test]
fn magnitudes_outside_double_precision_products_are_refused() {
    let d = TestDir::new("bounds", "magnitudes");
    for (set, key) in [
        ("geometry.ri=5e-324", "geometry.ri"),
        ("material.mu=1e-200", "material.mu"),
        ("geometry.ro=1e100", "geometry.ro"),
    ] {
        let o = tread_in(
            d.path(),
            &[
                "run",
                &scene("spinning_neo_hookean.toml"),
                "--set",
                set,
                "--out",
                "out",
            ],
            MINUTE,
        );
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{set}: {err}");
        assert!(err.contains(key) && err.contains("1e-60"), "{set}: {err}");
        assert!(
            !d.path().join("out").exists(),
            "{set}: output folder created"
        );
    }
}

/// A cut-back count that no step size survives is refused; within the bound, a run whose steps
/// keep failing ends with a message instead of looping (the step falls below round-off).
#[test]
fn step_controls_that_could_never_end_are_refused_or_end() {
    let d = TestDir::new("bounds", "cutbacks");
    let base = [
        "--set",
        "mesh.n_r=2",
        "--set",
        "mesh.n_theta=32",
        "--set",
        "motion.omega=500",
    ];
    let c = scene("creep_force.toml");
    for n in ["2000", "4611686018427387904"] {
        let mut args = vec!["check", &c[..]];
        args.extend(base);
        let set = format!("solver.max_cutbacks={n}");
        args.extend(["--set", &set]);
        let o = tread_in(d.path(), &args, MINUTE);
        assert_eq!(o.status.code(), Some(2), "{n}: {}", stderr(&o));
        assert!(stderr(&o).contains("solver.max_cutbacks"), "{}", stderr(&o));
    }
    // The largest allowed count: the run ends (converged or failed with its reason).
    let mut args = vec!["run", &c[..], "--out", "out", "-q"];
    args.extend(base);
    args.extend(["--set", "solver.max_cutbacks=200"]);
    let o = tread_in(d.path(), &args, Duration::from_secs(600));
    let code = o.status.code();
    assert!(
        matches!(code, Some(0) | Some(1)),
        "{code:?}: {}",
        stderr(&o)
    );
}

/// Error messages name the key: a key written twice (a TOML error) and the keys of the second
/// and later `[[material]]` regions, with their lines.
#[test]
fn messages_name_the_key_and_the_line() {
    let d = TestDir::new("bounds", "messages");
    let text = std::fs::read_to_string(scene("spinning_neo_hookean.toml")).unwrap();
    let ro = text
        .lines()
        .position(|l| l.trim_start().starts_with("ro ="))
        .expect("ro")
        + 1;
    let twice: Vec<String> = text
        .lines()
        .enumerate()
        .flat_map(|(i, l)| {
            if i + 1 == ro {
                vec![l.to_string(), "ro = 3.0".to_string()]
            } else {
                vec![l.to_string()]
            }
        })
        .collect();
    std::fs::write(d.path().join("twice.toml"), twice.join("\n")).unwrap();
    let o = tread_in(d.path(), &["check", "twice.toml"], MINUTE);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains(&format!("twice.toml:{}", ro + 1)), "{err}");
    assert!(err.contains("geometry.ro"), "no key: {err}");

    // A bad value in the second [[material]] region: its line and its region.
    let text = std::fs::read_to_string(scene("two_layer_cylinder.toml")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let second = lines
        .iter()
        .enumerate()
        .filter(|(_, l)| l.trim_start().starts_with("[[material]]"))
        .nth(1)
        .map(|(i, _)| i)
        .expect("two [[material]] regions");
    let region_line = (second..lines.len())
        .find(|&i| lines[i].trim_start().starts_with("region"))
        .expect("region key");
    let region = lines[region_line].split('"').nth(1).expect("region name");
    let key_line = (second..lines.len())
        .find(|&i| {
            let l = lines[i].trim_start();
            l.starts_with("mu") || l.starts_with("c1")
        })
        .expect("a modulus of the second region");
    let key = lines[key_line]
        .split('=')
        .next()
        .unwrap()
        .trim()
        .to_string();
    let mut bad: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
    bad[key_line] = format!("{key} = -1.0");
    // The mesh is relative to the scene's folder.
    std::fs::copy(scene("two_layer.msh"), d.path().join("two_layer.msh")).unwrap();
    std::fs::write(d.path().join("regions.toml"), bad.join("\n")).unwrap();
    let o = tread_in(d.path(), &["check", "regions.toml"], MINUTE);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&format!("regions.toml:{}", key_line + 1)),
        "no line {} in: {err}",
        key_line + 1
    );
    assert!(err.contains(region) && err.contains(&key), "{err}");
}

/// The JSON schema asks what the loader asks: a steady scene may leave `time.dt` out, and the
/// integer bounds are the loader's.
#[test]
fn schema_matches_the_loader() {
    let d = TestDir::new("bounds", "schema");
    let o = tread_in(d.path(), &["schema"], MINUTE);
    assert_eq!(o.status.code(), Some(0));
    let s: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON schema");
    let time = &s["properties"]["time"];
    let req: Vec<&str> = time["required"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|v| v.as_str())
        .collect();
    assert!(
        !req.contains(&"dt"),
        "time.dt required of every scene: {req:?}"
    );
    assert_eq!(
        s["if"]["properties"]["analysis"]["properties"]["mode"]["const"],
        "steady"
    );
    let else_req = &s["else"]["properties"]["time"]["required"];
    assert!(
        else_req.as_array().unwrap().iter().any(|v| v == "dt"),
        "{else_req}"
    );
    let mesh = &s["properties"]["mesh"]["properties"];
    assert_eq!(mesh["n_r"]["minimum"], 1);
    assert_eq!(mesh["n_theta"]["minimum"], 8);
    assert_eq!(
        s["properties"]["solver"]["properties"]["max_cutbacks"]["maximum"],
        200
    );
}
