//! What the output files say, read back: each test runs the `tread` binary on a small scene and
//! checks one property a user relies on (static friction tractions reported, every step once
//! with increasing index and the right time, the extracted steady field in `steady.vtu`, scalars
//! at every step, round-trip numbers, MCAP Newton/rejection channels, plain terminal text).
//!
//! `TREAD_BIN` runs the same checks against another build of the program.

mod logread;
#[path = "common/tempdir.rs"]
mod tempdir;

use logread::*;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use tempdir::TestDir;

fn tread() -> Command {
    let bin = std::env::var("TREAD_BIN").unwrap_or_else(|_| env!("CARGO_BIN_EXE_tread").into());
    let mut c = Command::new(bin);
    c.env("RAYON_NUM_THREADS", "1");
    c
}

fn scene(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(name)
}

const SINKS: &str = r#"output.sinks=["summary","csv","vtu","mcap"]"#;

/// Run `tread -q run <scene> --out <dir> --set …` and return the output.
fn run(scene: &Path, out: &Path, set: &[&str]) -> Output {
    let mut c = tread();
    c.args(["-q", "run"]).arg(scene).arg("--out").arg(out);
    for s in set {
        c.args(["--set", s]);
    }
    let o = c.output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked"), "panic: {err}");
    o
}

fn run_ok(scene: &Path, out: &Path, set: &[&str]) -> Output {
    let o = run(scene, out, set);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    o
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

fn assert_strictly_increasing(v: &[f64], what: &str) {
    for w in v.windows(2) {
        assert!(w[1] > w[0], "{what} not strictly increasing: {v:?}");
    }
}

/// Step indices of the `/tread/step` channel: 0, 1, 2, … without gaps or repeats; and no
/// per-step channel carries an index outside them or goes back.
fn assert_mcap_steps(m: &Mcap) {
    let idx: Vec<f64> = m
        .topic("/tread/step")
        .iter()
        .map(|s| f64_field(&s.msg, "index"))
        .collect();
    assert!(!idx.is_empty());
    let want: Vec<f64> = (0..idx.len()).map(|i| i as f64).collect();
    assert_eq!(idx, want, "/tread/step indices");
    for topic in ["/tread/hub", "/tread/energy"] {
        let s: Vec<f64> = m
            .topic(topic)
            .iter()
            .map(|x| f64_field(&x.msg, "step"))
            .collect();
        assert_strictly_increasing(&s, topic);
    }
}

#[test]
fn static_friction_tractions_are_reported() {
    let d = TestDir::new("outputs", "static_friction");
    let out = d.join("out");
    run_ok(
        &scene("indentation_friction.toml"),
        &out,
        &["mesh.n_r=2", "mesh.n_theta=32", SINKS],
    );
    let (h, rows) = read_csv(&out.join("contact.csv"));
    let tn = column(&h, &rows, "t_n");
    let tt = column(&h, &rows, "t_t");
    let pmax = tn.iter().copied().fold(0.0, f64::max);
    let tmax = tt.iter().map(|v| v.abs()).fold(0.0, f64::max);
    assert!(pmax > 0.0);
    // μ = 0.3: the tangential traction where the patch edge slips is a sizeable part of μ t_n.
    assert!(tmax > 0.02 * pmax, "max |t_t| = {tmax}, max t_n = {pmax}");
    for (n, t) in tn.iter().zip(&tt) {
        assert!(t.abs() <= 0.3 * n * (1.0 + 1e-9) + 1e-12, "|t_t| > μ t_n");
    }
    // The MCAP contact channel of the last step too.
    let m = read_mcap(&out.join("run.mcap"));
    let last = m.topic("/tread/contact_patch");
    let last = last.last().expect("contact channel");
    let tt = list_f64(&last.msg, "t_t");
    assert!(tt.iter().any(|v| v.abs() > 0.02 * pmax), "MCAP t_t all ~0");
}

#[test]
fn steady_mode_lists_each_step_once() {
    let d = TestDir::new("outputs", "steady_once");
    let text = std::fs::read_to_string(scene("oden_steady_sweep.toml")).unwrap();
    // The same scene without its continuation: one steady solve.
    let mut kept = Vec::new();
    let mut skip = false;
    for l in text.lines() {
        if l.starts_with('[') {
            skip = l.starts_with("[continuation]");
        }
        if !skip {
            kept.push(l);
        }
    }
    let f = d.join("steady.toml");
    std::fs::write(&f, kept.join("\n")).unwrap();
    let out = d.join("out");
    run_ok(&f, &out, &["mesh.n_r=2", "mesh.n_theta=32", SINKS]);
    let pvd = parse_pvd(&out.join("fields.pvd"));
    let times: Vec<f64> = pvd.iter().map(|p| p.0).collect();
    assert_strictly_increasing(&times, "fields.pvd times");
    let (h, rows) = read_csv(&out.join("history.csv"));
    let steps = column(&h, &rows, "step");
    let want: Vec<f64> = (0..steps.len()).map(|i| i as f64).collect();
    assert_eq!(steps, want);
    assert_strictly_increasing(&column(&h, &rows, "time"), "history.csv time");
    assert_mcap_steps(&read_mcap(&out.join("run.mcap")));
}

#[test]
fn continuation_steps_are_unique_and_timed_by_the_parameter() {
    let d = TestDir::new("outputs", "continuation");
    let out = d.join("out");
    run_ok(
        &scene("oden_steady_sweep.toml"),
        &out,
        &[
            "mesh.n_r=2",
            "mesh.n_theta=32",
            "continuation.max_steps=4",
            SINKS,
        ],
    );
    let (h, rows) = read_csv(&out.join("history.csv"));
    let steps = column(&h, &rows, "step");
    let want: Vec<f64> = (0..steps.len()).map(|i| i as f64).collect();
    assert_eq!(steps, want, "history.csv steps");
    let (bh, brows) = read_csv(&out.join("branch.csv"));
    let omega = column(&bh, &brows, "omega");
    assert_eq!(steps.len(), omega.len(), "one history row per branch point");
    let pvd = parse_pvd(&out.join("fields.pvd"));
    assert_eq!(pvd.len(), omega.len());
    // Branch point k >= 1 is at time ω_k (point 0 is the last load step, λ = 1).
    for (k, (t, _)) in pvd.iter().enumerate().skip(1) {
        assert!(
            (t - omega[k]).abs() <= 1e-12 * omega[k],
            "pvd entry {k}: {t} vs ω = {}",
            omega[k]
        );
    }
    assert_strictly_increasing(
        &pvd.iter().map(|p| p.0).collect::<Vec<_>>(),
        "fields.pvd times",
    );
    assert_mcap_steps(&read_mcap(&out.join("run.mcap")));
}

/// One free-rolling transient (coarse shipped scene) shared by the transient checks.
fn free_rolling(d: &TestDir) -> PathBuf {
    let out = d.join("out");
    run_ok(&scene("free_rolling.toml"), &out, &[SINKS]);
    out
}

fn max_norm2(v: &[f64], stride: usize) -> f64 {
    v.chunks(stride)
        .map(|c| (c[0] * c[0] + c[1] * c[1]).sqrt())
        .fold(0.0, f64::max)
}

#[test]
fn transient_outputs_are_complete_and_consistent() {
    let d = TestDir::new("outputs", "transient");
    let out = free_rolling(&d);
    let s = summary(&out);
    let r = &s["results"];
    assert_eq!(
        r["steady"], true,
        "the shipped scene reaches steady rolling"
    );

    // steady.vtu is the extracted referential field (hub rotation removed).
    let v = parse_vtu(&out.join("steady.vtu"));
    let (fh, frows) = read_csv(&out.join("steady_field.csv"));
    let u1 = column(&fh, &frows, "u1");
    let u2 = column(&fh, &frows, "u2");
    let field_max = u1
        .iter()
        .zip(&u2)
        .map(|(a, b)| (a * a + b * b).sqrt())
        .fold(0.0, f64::max);
    let vtu_max = max_norm2(&v.arrays["displacement"], 3);
    assert!(
        (vtu_max - field_max).abs() <= 1e-9 * field_max,
        "steady.vtu max|u| = {vtu_max}, steady_field.csv {field_max}"
    );

    // history.csv: every accepted step (scalars are not decimated), integers as integers.
    let text = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let (h, rows) = read_csv(&out.join("history.csv"));
    assert_eq!(rows.len() as u64, r["steps"].as_u64().unwrap());
    let steps = column(&h, &rows, "step");
    let want: Vec<f64> = (0..steps.len()).map(|i| i as f64).collect();
    assert_eq!(steps, want);
    assert_strictly_increasing(&column(&h, &rows, "time"), "history.csv time");
    let k = h.iter().position(|c| c == "newton_iterations").unwrap();
    for line in text.lines().skip(1) {
        let cell = line.split(',').nth(k).unwrap();
        assert!(cell.parse::<u64>().is_ok(), "newton_iterations = {cell:?}");
    }
    // The VTU series: times equal the steps' times, increasing.
    let pvd = parse_pvd(&out.join("fields.pvd"));
    let times = column(&h, &rows, "time");
    for (t, f) in &pvd {
        let step: usize = f
            .trim_start_matches("fields/step_")
            .trim_end_matches(".vtu")
            .parse()
            .unwrap();
        assert_eq!(*t, times[step], "{f}");
    }

    // MCAP: steps once each, the Newton and rejection channels, the residual, log times.
    let m = read_mcap(&out.join("run.mcap"));
    assert_mcap_steps(&m);
    assert!(m.count("/tread/newton") >= rows.len(), "Newton channel");
    assert_eq!(
        m.count("/tread/rejected") as u64,
        r["rejected_steps"].as_u64().unwrap(),
        "rejected-step channel"
    );
    let res: Vec<f64> = m
        .topic("/tread/step")
        .iter()
        .map(|s| f64_field(&s.msg, "residual"))
        .collect();
    assert!(res.iter().all(|r| *r > 0.0 && *r < 1e-3), "step residuals");
    let logs = m.topic("/tread/log");
    let last = logs.last().unwrap();
    let t_end_ns = (r["final_time"].as_f64().unwrap() * 1e9) as u64;
    assert!(
        last.log_time + 1 >= t_end_ns,
        "finish log at {} ns",
        last.log_time
    );
    // The steady state has its own channels, after the last step.
    assert!(m.count("/tread/steady/hub") == 1);
}

#[test]
fn numbers_in_csv_round_trip() {
    let d = TestDir::new("outputs", "csv_digits");
    let out = d.join("out");
    run_ok(
        &scene("spinning_neo_hookean.toml"),
        &out,
        &["mesh.n_r=2", "mesh.n_theta=16", SINKS],
    );
    for f in ["history.csv", "nodes.csv", "profile.csv", "convergence.csv"] {
        let text = std::fs::read_to_string(out.join(f)).unwrap();
        for cell in text.lines().skip(1).flat_map(|l| l.split(',')) {
            // Fixed 13 significant digits (`1.000000000000e0`) cannot represent every double.
            let mantissa = cell.split(['e', 'E']).next().unwrap_or("");
            assert!(
                !(mantissa.len() >= 14 && mantissa.ends_with("000")),
                "{f}: {cell}"
            );
        }
    }
    let text = std::fs::read_to_string(out.join("convergence.csv")).unwrap();
    for line in text.lines().skip(1) {
        let c: Vec<&str> = line.split(',').collect();
        assert!(
            c[0].parse::<u64>().is_ok() && c[2].parse::<u64>().is_ok(),
            "{line}"
        );
    }
}

#[test]
fn terminal_shows_no_internal_values() {
    let d = TestDir::new("outputs", "terminal");
    let out = d.join("out");
    let o = tread()
        .args(["run"])
        .arg(scene("free_rolling.toml"))
        .arg("--out")
        .arg(&out)
        .args(["--set", SINKS, "--set", "time.t_end=0.05"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{text}");
    for bad in ["Some(", "None", "null"] {
        assert!(!text.contains(bad), "{bad} in: {text}");
    }
    // 0.05 s is far from steady rolling: the run says so.
    assert!(
        text.contains("steady rolling NOT reached") || text.contains("not reached"),
        "{text}"
    );
    assert!(!text.contains("converged:"), "{text}");
    let s = summary(&out);
    let w = s["warnings"].as_array().expect("warnings");
    assert!(
        w.iter().any(|w| w.as_str().unwrap().contains("steady")),
        "{w:?}"
    );
}

#[test]
fn a_step_budget_short_of_t_end_is_warned_before_the_run() {
    // 3 adaptive steps of at most 10 × 1e-4 s reach 3e-3 s < t_end = 3 s: the run warns up
    // front, stops at max_steps, and the summary keeps the warning.
    let d = TestDir::new("outputs", "step_budget");
    let out = d.join("out");
    let o = run_ok(
        &scene("free_rolling.toml"),
        &out,
        &[SINKS, "time.dt=1e-4", "time.max_steps=3"],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    let needle = "time.max_steps = 3 steps of at most time.dt_max";
    assert!(err.contains(needle), "{err}");
    assert!(
        err.contains("reach t = 0.003 s, short of time.t_end = 3 s"),
        "{err}"
    );
    let s = summary(&out);
    let w = s["warnings"].as_array().expect("warnings");
    assert!(
        w.iter().any(|w| w.as_str().unwrap().contains(needle)),
        "{w:?}"
    );
    // A budget that reaches t_end: no such warning.
    let out2 = d.join("out2");
    let o = run_ok(
        &scene("free_rolling.toml"),
        &out2,
        &[SINKS, "time.t_end=0.002"],
    );
    assert!(!String::from_utf8_lossy(&o.stderr).contains("short of time.t_end"));
}

#[test]
fn error_messages_print_numbers_briefly() {
    let d = TestDir::new("outputs", "long_numbers");
    let o = run(
        &scene("spinning_neo_hookean.toml"),
        &d.join("out"),
        &["geometry.ri=1e300"],
    );
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !err.contains("0000000000000000000000"),
        "long number in: {err}"
    );
}
