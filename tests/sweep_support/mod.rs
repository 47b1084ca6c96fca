#![allow(dead_code)]
//! Shared pieces of the sweep tests: tiny scenes and specs, running the `tread` binary, reading
//! status.json and results.csv.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

/// A spinning annulus on a tiny mesh: a few hundredths of a second per run. Above the
/// critical spin (about 41 rad/s for a ring; here the load stepping gives up near 160 rad/s)
/// the solve fails: `motion.omega = 200` is the deliberately failing point.
pub const SPIN: &str = r#"
[scene]
name = "spin"
[geometry]
ri = 1.0
ro = 2.0
[mesh]
n_r = 2
n_theta = 8
[material]
model = "neo_hookean"
mu = 200.0
lambda = 1800.0
rho = 0.027
[analysis]
mode = "spinning"
[motion]
omega = 20.0
[solver]
max_cutbacks = 3
[output]
sinks = ["summary", "csv"]
"#;

/// Eight runs, the last one failing (omega = 200 rad/s).
pub const EIGHT: &str = r#"
[sweep]
name = "eight"
scene = "spin.toml"
[[axis]]
key = "motion.omega"
values = [5.0, 10.0, 15.0, 20.0, 25.0, 30.0, 35.0, 200.0]
unit = "rad/s"
[outputs]
sinks = ["summary"]
[units]
u_r_outer = "in"
[[plot]]
x = "motion.omega"
y = ["u_r_outer"]
file = "u_r.png"
"#;

/// Four slower runs (≈ 0.2 s each in release; the signal tests raise the load steps to 400) for
/// interruption tests.
pub const SLOW: &str = r#"
[sweep]
name = "slow"
scene = "spin.toml"
[[axis]]
key = "motion.omega"
values = [10.0, 20.0, 30.0, 40.0]
[[axis]]
zip = [
  { key = "mesh.n_r", values = [6] },
  { key = "mesh.n_theta", values = [128] },
  { key = "solver.load_steps", values = [20] },
]
[outputs]
sinks = ["summary"]
"#;

/// [`SLOW`] with `load_steps` load steps per run: long enough that a signal sent while a run
/// works always arrives before it finishes (20 steps take about 0.2 s).
pub fn slow_with_load_steps(load_steps: usize) -> String {
    SLOW.replace(
        "\"solver.load_steps\", values = [20]",
        &format!("\"solver.load_steps\", values = [{load_steps}]"),
    )
}

pub fn tread() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tread"))
}

/// Write the scene and a spec into `dir`; returns the spec path.
pub fn write_spec(dir: &Path, spec: &str) -> PathBuf {
    std::fs::write(dir.join("spin.toml"), SPIN).unwrap();
    let p = dir.join("spec.toml");
    std::fs::write(&p, spec).unwrap();
    p
}

pub fn run(args: &[&str]) -> Output {
    tread().args(args).output().unwrap()
}

pub fn text(o: &Output) -> String {
    format!(
        "status {:?}\n--- stdout\n{}\n--- stderr\n{}",
        o.status.code(),
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

pub fn status(root: &Path, run: &str) -> serde_json::Value {
    let p = root.join("runs").join(run).join("status.json");
    let t = std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    serde_json::from_str(&t).unwrap()
}

pub fn state(root: &Path, run: &str) -> String {
    let p = root.join("runs").join(run).join("status.json");
    match std::fs::read_to_string(&p) {
        Ok(t) => serde_json::from_str::<serde_json::Value>(&t)
            .map(|v| v["state"].as_str().unwrap_or("").to_string())
            .unwrap_or_default(),
        Err(_) => String::new(),
    }
}

/// Wait until `f` holds (polling every 20 ms), at most `secs`.
pub fn wait_until(secs: f64, what: &str, mut f: impl FnMut() -> bool) {
    let t0 = Instant::now();
    while !f() {
        assert!(
            t0.elapsed() < Duration::from_secs_f64(secs),
            "timed out after {secs} s waiting for {what}"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// results.csv as rows of fields (header first).
pub fn read_table(root: &Path) -> Vec<Vec<String>> {
    let t = std::fs::read_to_string(root.join("results.csv")).unwrap();
    tread::sweep::collect::read_csv(&t)
}

/// The table without the columns that legitimately differ between two executions of the same
/// runs (wall times).
pub fn without_timing(rows: &[Vec<String>]) -> Vec<Vec<String>> {
    let drop: Vec<usize> = rows[0]
        .iter()
        .enumerate()
        .filter(|(_, h)| h.as_str() == "wall_time_s")
        .map(|(i, _)| i)
        .collect();
    rows.iter()
        .map(|r| {
            r.iter()
                .enumerate()
                .filter(|(i, _)| !drop.contains(i))
                .map(|(_, c)| c.clone())
                .collect()
        })
        .collect()
}

/// Column `name` of the table.
pub fn column(rows: &[Vec<String>], name: &str) -> Vec<String> {
    let i = rows[0]
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name} in {:?}", rows[0]));
    rows[1..].iter().map(|r| r[i].clone()).collect()
}

pub fn send(pid: u32, sig: &str) {
    let ok = Command::new("kill")
        .args([&format!("-{sig}"), &pid.to_string()])
        .status()
        .unwrap()
        .success();
    assert!(ok, "kill -{sig} {pid}");
}

/// Checks on the 8-run sweep with its failing point, whatever the backend: 7 done, 1 failed
/// with the solver's error, results for the done runs only, u_r(outer) growing with ω.
pub fn check_eight(root: &Path) {
    for i in 0..7 {
        assert_eq!(state(root, &format!("{i:04}")), "done", "run {i}");
    }
    let st = status(root, "0007");
    assert_eq!(st["state"], "failed");
    let err = st["error"].as_str().unwrap();
    assert!(err.contains("the solve failed"), "{err}");
    assert_eq!(st["exit_code"], 1);
    let t = read_table(root);
    assert_eq!(t.len(), 9, "{t:?}");
    let states = column(&t, "state");
    assert_eq!(states[..7], vec!["done"; 7]);
    assert_eq!(states[7], "failed");
    let errors = column(&t, "error");
    assert!(errors[7].contains("the solve failed"), "{}", errors[7]);
    assert!(errors[..7].iter().all(String::is_empty));
    let u: Vec<String> = column(&t, "u_r_outer");
    assert!(u[7].is_empty(), "no result for the failed run");
    let u: Vec<f64> = u[..7].iter().map(|s| s.parse().unwrap()).collect();
    assert!(u.windows(2).all(|w| w[1] > w[0]), "{u:?}");
    assert_eq!(
        column(&t, "motion.omega"),
        ["5.0", "10.0", "15.0", "20.0", "25.0", "30.0", "35.0", "200.0"]
    );
}
