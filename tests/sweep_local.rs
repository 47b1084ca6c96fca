//! `tread sweep` on the local backend, through the binary: plan checks every run's scene
//! before anything starts; an 8-run sweep with one failing point gives 7 done and 1 failed with
//! its error, and the table; results equal those of bare `tread run`s; a rerun resumes (done
//! runs skipped); Ctrl-C stops the pool cleanly and the sweep resumes; run-one records
//! "killed" on SIGTERM.

mod sweep_support;
#[path = "common/tempdir.rs"]
mod tempdir;

use sweep_support::*;
use tempdir::TestDir;

#[test]
fn plan_lists_the_runs_and_reports_every_invalid_run_at_once() {
    let d = TestDir::new("sweep", "plan");
    let spec = write_spec(
        &d,
        r#"
[sweep]
name = "bad"
scene = "spin.toml"
[[axis]]
key = "motion.omega"
values = [10.0, -5.0, 20.0]
[[axis]]
key = "mesh.n_theta"
values = [8, 7]
[[axis]]
key = "solver.bogus"
values = [1]
"#,
    );
    let o = run(&["sweep", "plan", spec.to_str().unwrap()]);
    let all = text(&o);
    assert_eq!(o.status.code(), Some(2), "{all}");
    // The table comes first: 3 × 2 × 1 runs, last axis fastest.
    let stdout = String::from_utf8_lossy(&o.stdout);
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), 7, "{all}");
    assert!(lines[0].starts_with("run") && lines[0].contains("mesh.n_theta"));
    assert!(
        lines[2].starts_with("0001  10.0") && lines[2].contains(" 7 "),
        "{}",
        lines[2]
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    // The unknown key concerns every run: reported once.
    assert!(
        stderr.contains("all 6 runs:") && stderr.contains("key `solver.bogus`"),
        "{all}"
    );
    // The odd n_theta: runs 1, 3, 5 (with their values); the negative omega: runs 2-3.
    assert!(stderr.contains("runs 0001, 0003, 0005 (3 runs):"), "{all}");
    assert!(stderr.contains("key `mesh.n_theta`"), "{all}");
    assert!(stderr.contains("runs 0002-0003 (2 runs):"), "{all}");
    assert!(stderr.contains("key `motion.omega`"), "{all}");
    assert!(stderr.contains("(--set)"), "{all}");
    // Nothing ran.
    let o = tread()
        .current_dir(&*d)
        .args(["sweep", "run", spec.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        !d.join("out").exists(),
        "a sweep with invalid runs must not start"
    );
}

#[test]
fn spec_errors_name_their_keys() {
    let d = TestDir::new("sweep", "spec_errors");
    let spec = write_spec(
        &d,
        "[sweep]\nname = \"x\"\nscene = \"nowhere.toml\"\n[[axis]]\nkey = \"road.v0\"\nlinear = { start = 1.0, stop = 2.0, num = 0 }\n",
    );
    let o = run(&["sweep", "plan", spec.to_str().unwrap()]);
    let all = text(&o);
    assert_eq!(o.status.code(), Some(2), "{all}");
    assert!(
        all.contains("key `sweep.scene`: cannot read the base scene"),
        "{all}"
    );
    assert!(all.contains("key `axis[0].linear.num`"), "{all}");
}

#[test]
fn local_sweep_with_a_failing_point_then_resumes_and_matches_bare_runs() {
    let d = TestDir::new("sweep", "local8");
    let spec = write_spec(&d, EIGHT);
    let root = d.join("out8");
    let args = [
        "--threads",
        "1",
        "-q",
        "sweep",
        "run",
        spec.to_str().unwrap(),
        "-j",
        "2",
        "--out",
        root.to_str().unwrap(),
    ];
    let o = run(&args);
    let all = text(&o);
    assert_eq!(o.status.code(), Some(1), "one run failed: {all}");
    check_eight(&root);
    assert!(all.contains("8 runs: 7 done, 1 failed"), "{all}");
    assert!(
        all.contains("failed 0007 (motion.omega=200.0): the solve failed"),
        "{all}"
    );
    assert!(root.join("plots/u_r.png").exists());
    assert!(root.join("runs/0003/summary.json").exists());

    // The sweep's run is the bare `tread run` with the same overrides: identical results.
    let bare = d.join("bare");
    let o = run(&[
        "--threads",
        "1",
        "-q",
        "run",
        d.join("spin.toml").to_str().unwrap(),
        "--set",
        "motion.omega=20.0",
        "--set",
        "output.sinks=[\"summary\"]",
        "--out",
        bare.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let r = |p: &std::path::Path| -> serde_json::Value {
        serde_json::from_str::<serde_json::Value>(&std::fs::read_to_string(p).unwrap()).unwrap()
            ["results"]
            .clone()
    };
    assert_eq!(
        r(&bare.join("summary.json")),
        r(&root.join("runs/0003/summary.json"))
    );

    // Resume: the done runs are skipped (their status untouched), the failed one is retried.
    let before = status(&root, "0002");
    let o = run(&args);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert_eq!(status(&root, "0002"), before, "a done run was run again");
    assert_eq!(status(&root, "0007")["attempts"], 2);
    check_eight(&root);

    // status reads the folders.
    let o = run(&[
        "sweep",
        "status",
        spec.to_str().unwrap(),
        "--out",
        root.to_str().unwrap(),
    ]);
    let s = text(&o);
    assert!(o.status.success(), "{s}");
    assert!(s.contains("sweep `eight`: 8 runs: 7 done, 1 failed"), "{s}");

    // Editing a value reruns only that run (its fingerprint changed); the others stay done.
    std::fs::write(&spec, EIGHT.replace("35.0, 200.0", "35.0, 36.0")).unwrap();
    let o = run(&args);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert_eq!(status(&root, "0002"), before);
    assert_eq!(state(&root, "0007"), "done");
}

#[test]
fn ctrl_c_stops_the_local_pool_cleanly_and_the_sweep_resumes() {
    let d = TestDir::new("sweep", "interrupt");
    // Run 0001 is the slow one (10000 load steps, seconds), so that the signal always
    // arrives while it works; the others take about 0.2 s.
    let spec = write_spec(
        &d,
        &SLOW
            .replace(
                "[[axis]]\nkey = \"motion.omega\"\nvalues = [10.0, 20.0, 30.0, 40.0]\n[[axis]]\nzip = [",
                "[[axis]]\nzip = [\n  { key = \"motion.omega\", values = [10.0, 20.0, 30.0, 40.0] },",
            )
            .replace("{ key = \"mesh.n_r\", values = [6] }", "{ key = \"mesh.n_r\", values = [6, 6, 6, 6] }")
            .replace(
                "{ key = \"mesh.n_theta\", values = [128] }",
                "{ key = \"mesh.n_theta\", values = [128, 128, 128, 128] }",
            )
            .replace(
                "{ key = \"solver.load_steps\", values = [20] }",
                "{ key = \"solver.load_steps\", values = [20, 10000, 20, 20] }",
            ),
    );
    let root = d.join("out");
    let args = [
        "--threads",
        "1",
        "-q",
        "sweep",
        "run",
        spec.to_str().unwrap(),
        "-j",
        "1",
        "--out",
        root.to_str().unwrap(),
    ];
    let mut child = tread().args(args).spawn().unwrap();
    wait_until(60.0, "run 0000 done and 0001 running", || {
        state(&root, "0000") == "done" && state(&root, "0001") == "running"
    });
    // Ctrl-C reaches the foreground process (the pool); it stops the running run.
    send(child.id(), "INT");
    let code = child.wait().unwrap().code();
    assert_eq!(code, Some(130));
    assert_eq!(state(&root, "0000"), "done");
    let st = status(&root, "0001");
    assert_eq!(st["state"], "killed", "{st}");
    assert!(st["error"].as_str().unwrap().contains("SIGTERM"), "{st}");
    // The killed run's `tread run` stopped at a step boundary and finished its summary.
    let sum: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(root.join("runs/0001/summary.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(sum["error"], "interrupted");
    assert_eq!(state(&root, "0002"), "queued");
    assert_eq!(state(&root, "0003"), "queued");
    let t = read_table(&root);
    assert_eq!(column(&t, "state"), ["done", "killed", "queued", "queued"]);

    let first = status(&root, "0000");
    let o = run(&args);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert_eq!(status(&root, "0000"), first, "the done run was run again");
    assert_eq!(status(&root, "0001")["attempts"], 2);
    let t = read_table(&root);
    assert_eq!(column(&t, "state"), ["done"; 4]);
}

#[test]
fn run_one_records_killed_on_sigterm_and_checks_its_index() {
    let d = TestDir::new("sweep", "sigterm");
    // Slow enough (10000 load steps, seconds) that the signal always arrives while the run
    // works (400 steps take about 0.3 s, close to the 0.2 s wait below); the run stops at its
    // next step boundary once signalled, so the length costs nothing.
    let spec = write_spec(&d, &slow_with_load_steps(10000));
    let root = d.join("out");
    let mut child = tread()
        .args([
            "--threads",
            "1",
            "sweep",
            "run-one",
            spec.to_str().unwrap(),
            "--index",
            "2",
            "--out",
            root.to_str().unwrap(),
        ])
        .spawn()
        .unwrap();
    wait_until(30.0, "run 0002 running", || {
        state(&root, "0002") == "running"
    });
    std::thread::sleep(std::time::Duration::from_millis(200));
    send(child.id(), "TERM");
    assert_eq!(child.wait().unwrap().code(), Some(143));
    let st = status(&root, "0002");
    assert_eq!(st["state"], "killed");
    assert!(
        st["error"]
            .as_str()
            .unwrap()
            .starts_with("killed by SIGTERM"),
        "{st}"
    );
    assert!(st["finished_at"].as_f64().is_some());

    let o = run(&[
        "sweep",
        "run-one",
        spec.to_str().unwrap(),
        "--index",
        "4",
        "--out",
        root.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("--index 4 is out of range: the sweep `slow` has 4 runs"));
}

/// The L-shape model problem on a small budget (at most 1500 equations: a fraction of a second
/// per run).
const LSHAPE: &str = r#"
[scene]
name = "lshape_small"
[problem]
kind = "lshape"
degree = 1
estimator = "explicit"
dorfler = 0.5
max_dofs = 1500
[output]
sinks = ["summary"]
"#;

/// A sweep over a model-problem scene key (`problem.dorfler` of the L-shape): plan checks
/// every run with the model-problem loader (a fraction out of range is named with its key and
/// runs), the runs write the model problem's summary, the table has its `results` keys, and a
/// run equals the bare `tread run` with the same override. The shipped example
/// (scenarios/sweep_lshape_dorfler.toml) plans.
#[test]
fn sweep_over_a_model_problem_key() {
    let d = TestDir::new("sweep", "model_problem");
    std::fs::write(d.join("lshape.toml"), LSHAPE).unwrap();
    let spec = d.join("spec.toml");
    let body = |values: &str| {
        format!(
            "[sweep]\nname = \"dorfler\"\nscene = \"lshape.toml\"\n[[axis]]\nkey = \"problem.dorfler\"\nvalues = {values}\nunit = \"1\"\n[outputs]\nsinks = [\"summary\", \"csv\"]\n[units]\nenergy_error = \"1\"\n[[plot]]\nx = \"problem.dorfler\"\ny = [\"energy_error\"]\nfile = \"error.png\"\n"
        )
    };
    std::fs::write(&spec, body("[0.3, 2.0, 3.0]")).unwrap();
    let o = run(&["sweep", "plan", spec.to_str().unwrap()]);
    let all = text(&o);
    assert_eq!(o.status.code(), Some(2), "{all}");
    assert!(all.contains("key `problem.dorfler`"), "{all}");
    assert!(all.contains("0001"), "{all}");
    assert!(all.contains("0002"), "{all}");
    assert!(!all.contains("0000 ("), "{all}");

    std::fs::write(&spec, body("[0.3, 0.6]")).unwrap();
    let root = d.join("out");
    let o = run(&[
        "--threads",
        "1",
        "-q",
        "sweep",
        "run",
        spec.to_str().unwrap(),
        "-j",
        "2",
        "--out",
        root.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let t = read_table(&root);
    assert_eq!(t.len(), 3, "{t:?}");
    assert_eq!(column(&t, "state"), vec!["done", "done"]);
    assert_eq!(column(&t, "problem.dorfler"), vec!["0.3", "0.6"]);
    for key in [
        "equations",
        "energy_error",
        "estimate",
        "effectivity",
        "rate",
    ] {
        let c = column(&t, key);
        assert!(c.iter().all(|v| v.parse::<f64>().is_ok()), "{key}: {c:?}");
    }
    // Each run stopped at the budget: more equations than 1500 only on its last mesh.
    let eq: Vec<f64> = column(&t, "equations")
        .iter()
        .map(|v| v.parse().unwrap())
        .collect();
    assert!(eq.iter().all(|&n| n > 1500.0), "{eq:?}");
    assert!(root.join("runs/0001/steps.csv").exists());
    assert!(root.join("plots/error.png").exists());
    let s: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(root.join("runs/0001/summary.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(s["mode"], "model_problem");
    assert_eq!(s["problem"]["dorfler"], 0.6);

    let bare = d.join("bare");
    let o = run(&[
        "--threads",
        "1",
        "-q",
        "run",
        d.join("lshape.toml").to_str().unwrap(),
        "--set",
        "problem.dorfler=0.6",
        "--set",
        "output.sinks=[\"summary\", \"csv\"]",
        "--out",
        bare.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let results = |p: &std::path::Path| -> serde_json::Value {
        serde_json::from_str::<serde_json::Value>(&std::fs::read_to_string(p).unwrap()).unwrap()
            ["results"]
            .clone()
    };
    assert_eq!(
        results(&bare.join("summary.json")),
        results(&root.join("runs/0001/summary.json"))
    );

    let shipped = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenarios/sweep_lshape_dorfler.toml"
    );
    let o = run(&["sweep", "plan", shipped]);
    assert!(o.status.success(), "{}", text(&o));
    // 2 estimators × 6 fractions.
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("12 runs, every scene valid"), "{}", text(&o));
}
