//! Interrupt safety of the `tread` binary: Ctrl-C (SIGINT) during a long load-stepping run
//! stops at a step boundary, finishes every log (all readable, consistent with each other) and
//! exits with 130 and `"error": "interrupted"` in summary.json; SIGKILL leaves an MCAP readable
//! up to its last completed chunk and a CSV complete up to its last row. Also `tread replay`.

mod logread;
#[path = "common/tempdir.rs"]
mod tempdir;

use logread::*;
use std::path::Path;
use std::process::{Child, Command};
use std::time::{Duration, Instant};
use tempdir::TestDir;

fn tread() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tread"))
}

fn tmpdir(name: &str) -> TestDir {
    TestDir::new("int", name)
}

/// Static frictionless indentation from 40 initial load steps: on this mesh most contact Newton
/// solves take 5–6 iterations, so the increments grow little (≈ 22 steps, ≈ 2 s in release).
const LONG: &str = r#"
[scene]
name = "long_run"
[geometry]
ri = 1.0
ro = 2.0
[mesh]
n_r = 6
n_theta = 192
grading_theta = 0.5
[material]
model = "mooney_rivlin"
c1 = 80.0
c2 = 20.0
kappa = 2000.0
rho = 0.027
[analysis]
mode = "static"
[road]
disp = 0.1
[contact]
c_n = 2.0e5
[solver]
load_steps = 40
[output]
sinks = ["summary", "csv", "vtu", "mcap", "rerun"]
"#;

fn start(dir: &Path) -> Child {
    let f = dir.join("scene.toml");
    std::fs::write(&f, LONG).unwrap();
    tread()
        .args(["run", f.to_str().unwrap(), "--out"])
        .arg(dir.join("out"))
        .arg("-q")
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap()
}

/// Wait until history.csv has at least `rows` data rows (or the child ended).
fn wait_rows(child: &mut Child, csv: &Path, rows: usize) -> usize {
    let t0 = Instant::now();
    loop {
        let n = std::fs::read_to_string(csv)
            .map(|s| s.lines().count().saturating_sub(1))
            .unwrap_or(0);
        if n >= rows {
            return n;
        }
        if let Ok(Some(st)) = child.try_wait() {
            panic!("the run ended ({st}) before {rows} steps were logged");
        }
        assert!(t0.elapsed() < Duration::from_secs(300), "timeout");
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Run the scene `text` in `dir` to its end (it must succeed); returns its output folder.
#[cfg(feature = "rerun")]
fn run_to_end(dir: &Path, text: &str) -> std::path::PathBuf {
    let f = dir.join("scene.toml");
    std::fs::write(&f, text).unwrap();
    let out = dir.join("out");
    let o = tread()
        .args(["run", f.to_str().unwrap(), "-q", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    out
}

fn signal(child: &Child, sig: &str) {
    let st = Command::new("kill")
        .args([sig, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(st.success());
}

#[test]
fn sigint_finishes_every_log_and_exits_130() {
    let dir = tmpdir("sigint");
    let mut child = start(&dir);
    let out = dir.join("out");
    wait_rows(&mut child, &out.join("history.csv"), 2);
    signal(&child, "-INT");
    let o = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["converged"], false);
    assert_eq!(s["error"], "interrupted");
    let steps = s["solver"]["load_steps"].as_u64().unwrap() as usize;
    assert!((2..40).contains(&steps), "stopped early: {steps} steps");
    let lambda = s["solver"]["interrupted_at"].as_f64().unwrap();

    let (h, rows) = read_csv(&out.join("history.csv"));
    assert_eq!(rows.len(), steps);
    let t = column(&h, &rows, "time");
    assert!((t[steps - 1] - lambda).abs() < 1e-12);
    let pvd = parse_pvd(&out.join("fields.pvd"));
    assert_eq!(pvd.len(), steps);
    let v = parse_vtu(&out.join(&pvd[steps - 1].1));
    assert!((v.time - lambda).abs() < 1e-9);
    // The MCAP was finished: it reads to its end, with the summary metadata.
    let m = read_mcap(&out.join("run.mcap"));
    assert!(!m.truncated);
    assert_eq!(m.count("/tread/step"), steps);
    assert_eq!(m.count("/tread/nodes"), steps);
    assert_eq!(m.metadata["summary"]["interrupted"], "true");
    assert_eq!(m.metadata["summary"]["error"], "interrupted");
    #[cfg(feature = "rerun")]
    {
        let r = read_rrd(&out.join("run.rrd"));
        // Every step, and the reference configuration at sim_time 0 before them.
        assert_eq!(r["/body/mesh"].mesh_vertices.len(), steps + 1);
        assert_eq!(r["/hub/force_y"].scalars.len(), steps);
        let hf = column(&h, &rows, "hub_force_y");
        assert!(
            (r["/hub/force_y"].scalars[steps - 1] - hf[steps - 1]).abs()
                <= 1e-9 * hf[steps - 1].abs()
        );
    }
}

#[test]
fn sigkill_leaves_mcap_and_csv_readable() {
    let dir = tmpdir("sigkill");
    let mut child = start(&dir);
    let out = dir.join("out");
    wait_rows(&mut child, &out.join("history.csv"), 3);
    signal(&child, "-KILL");
    let st = child.wait().unwrap();
    assert_eq!(st.code(), None, "killed by a signal");
    let (h, rows) = read_csv(&out.join("history.csv"));
    let n = rows.len();
    assert!((3..40).contains(&n));
    assert_eq!(
        column(&h, &rows, "step"),
        (0..n).map(|k| k as f64).collect::<Vec<_>>()
    );
    let m = read_mcap(&out.join("run.mcap"));
    assert!(m.truncated, "a killed run leaves no summary section");
    let idx: Vec<f64> = m
        .topic("/tread/step")
        .iter()
        .map(|x| f64_field(&x.msg, "index"))
        .collect();
    // Every step in the CSV but possibly the last one (killed between the two sinks) is in the
    // MCAP, with its view; nothing is garbled.
    assert!(
        idx.len() + 1 >= n && idx.len() <= n + 1,
        "{} vs {n}",
        idx.len()
    );
    assert_eq!(idx, (0..idx.len()).map(|k| k as f64).collect::<Vec<_>>());
    assert_eq!(m.count("/tread/nodes"), idx.len());
    let hub = m.topic("/tread/hub");
    let hf = column(&h, &rows, "hub_force_y");
    for (k, x) in hub.iter().enumerate().take(n) {
        assert!((f64_field(&x.msg, "force_y") - hf[k]).abs() <= 1e-9 * hf[k].abs());
    }
    // The VTU series lists only complete files.
    for (_, f) in parse_pvd(&out.join("fields.pvd")) {
        assert!(parse_vtu(&out.join(f)).n_points > 0);
    }
}

#[test]
fn replay_without_viewer_tells_how_to_install() {
    let dir = tmpdir("replay");
    let log = dir.join("x.rrd");
    std::fs::write(&log, b"not really").unwrap();
    let o = tread()
        .args(["replay", log.to_str().unwrap()])
        .env("TREAD_RERUN_BIN", dir.join("no-such-viewer"))
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("pip install rerun-sdk") && e.contains("cargo install rerun-cli"),
        "{e}"
    );
    let o = tread()
        .args(["replay", dir.join("x.txt").to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    // A viewer that exists is started with the log (here `true`, which exits at once).
    if let Some(t) = ["/bin/true", "/usr/bin/true"]
        .iter()
        .find(|p| Path::new(p).is_file())
    {
        let o = tread()
            .args(["replay", log.to_str().unwrap()])
            .env("TREAD_RERUN_BIN", t)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
}

#[cfg(feature = "rerun")]
#[test]
fn replay_converts_mcap_to_rrd() {
    let dir = tmpdir("convert");
    let out = run_to_end(
        &dir,
        &LONG
            .replace("load_steps = 40", "load_steps = 2")
            .replace("n_theta = 192", "n_theta = 32")
            .replace("n_r = 6", "n_r = 2"),
    );
    let m = read_mcap(&out.join("run.mcap"));
    let steps = m.count("/tread/step");
    let rrd = dir.join("converted.rrd");
    let o = tread()
        .args([
            "replay",
            out.join("run.mcap").to_str().unwrap(),
            "--to",
            rrd.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout)
        .contains(&format!("converted {} messages", m.messages.len())));
    let r = read_rrd(&rrd);
    // Numeric fields become series with the step timeline; the scene mesh becomes a Mesh3D.
    let fy = &r["/tread/hub/force_y"];
    assert_eq!(fy.scalars.len(), steps);
    let want: Vec<f64> = m
        .topic("/tread/hub")
        .iter()
        .map(|x| f64_field(&x.msg, "force_y"))
        .collect();
    assert_eq!(fy.scalars, want);
    assert_eq!(
        fy.times.iter().map(|x| x.0).collect::<Vec<_>>(),
        (0..steps as i64).collect::<Vec<_>>()
    );
    let mesh = &r["/tread/mesh/body/triangles/0"];
    assert_eq!(mesh.mesh_vertices.len(), steps);
    assert_eq!(r["/tread/nodes"].times.len(), steps);
    assert!(r["/metadata/scene"].static_rows >= 1);
}

/// SIGTERM (what `timeout`, `kill` and batch schedulers send) and SIGHUP stop a run as Ctrl-C
/// does: at a step boundary, with summary.json and a finished run.sta, exit status 130.
#[test]
fn sigterm_and_sighup_stop_like_ctrl_c() {
    for sig in ["-TERM", "-HUP"] {
        let dir = tmpdir(&format!("sig{}", &sig[1..]));
        let mut child = start(&dir);
        let out = dir.join("out");
        wait_rows(&mut child, &out.join("history.csv"), 2);
        signal(&child, sig);
        let o = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(130), "{sig}: {stderr}");
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(s["error"], "interrupted", "{sig}");
        let sta = std::fs::read_to_string(out.join("run.sta")).unwrap();
        let last = sta.lines().last().unwrap_or_default();
        assert!(
            last.starts_with("# interrupted:"),
            "{sig}: run.sta ends with {last:?}"
        );
        let m = read_mcap(&out.join("run.mcap"));
        assert!(!m.truncated, "{sig}: the MCAP was finished");
    }
}

/// `tread replay X.rrd --to F` onto a full disk ends with status 1 and the reason, leaving no
/// partial file and no temporary. Needs a small tmpfs (root, `mount`); elsewhere the test says it
/// skipped the case.
#[cfg(feature = "rerun")]
#[test]
fn replay_into_a_full_disk_fails_cleanly() {
    let dir = tmpdir("replay_full");
    let out = run_to_end(&dir, &LONG.replace("load_steps = 40", "load_steps = 4"));
    let rrd = out.join("run.rrd");
    let size = std::fs::metadata(&rrd).unwrap().len();
    let disk = dir.join("disk");
    std::fs::create_dir_all(&disk).unwrap();
    let k = (size / 2048).max(4);
    let mounted = Command::new("mount")
        .args(["-t", "tmpfs", "-o", &format!("size={k}k"), "tmpfs"])
        .arg(&disk)
        .stderr(std::process::Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !mounted {
        eprintln!("skipped: cannot mount a small tmpfs here (needs root)");
        return;
    }
    let to = disk.join("y.rrd");
    let mut child = tread()
        .args([
            "replay",
            rrd.to_str().unwrap(),
            "--to",
            to.to_str().unwrap(),
        ])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break Some(s);
        }
        if t0.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            break None;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let leftovers: Vec<String> = std::fs::read_dir(&disk)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().to_string())
        .collect();
    let _ = Command::new("umount").arg(&disk).status();
    let status = status.expect("the replay into a full disk hung");
    assert_eq!(status.code(), Some(1), "{status}");
    assert!(leftovers.is_empty(), "left on the full disk: {leftovers:?}");
}

/// A model-problem run (the heat problem of scenarios/model_problems/heat.toml, 20 000 time
/// steps: far longer than the wait below) stops at the next time step on SIGINT: exit 130,
/// summary.json with `"error": "interrupted"` and `interrupted_at` the time reached, the
/// results at that time, one row of steps.csv per step done, the solution written.
#[test]
fn sigint_stops_a_model_problem_at_a_time_step() {
    let dir = tmpdir("model_problem");
    let out = dir.join("out");
    let s = interrupt_model_problem(
        "heat.toml",
        &out,
        &["problem.steps=20000", "problem.dt=0.0001"],
    );
    let steps = s["steps"].as_u64().unwrap() as usize;
    assert!((1..20000).contains(&steps), "stopped early: {steps} steps");
    let t = s["interrupted_at"].as_f64().unwrap();
    assert!(
        (t - steps as f64 * 1e-4).abs() < 1e-9,
        "t = {t}, {steps} steps"
    );
    // The results are those of the time reached.
    assert!(
        (s["results"]["t"].as_f64().unwrap() - t).abs() < 1e-12,
        "{s}"
    );
    assert!(s["results"]["l2_error"].as_f64().unwrap() > 0.0, "{s}");
    let (h, rows) = read_csv(&out.join("steps.csv"));
    assert_eq!(rows.len(), steps);
    let tc = column(&h, &rows, "t");
    assert!((tc[steps - 1] - t).abs() < 1e-12);
    assert!(out.join("solution.vtu").exists());
}

/// `tread run` of the model-problem scene `name` of scenarios/model_problems/ into `out`,
/// with the summary, CSV and VTU sinks and the overrides `sets`.
fn start_model_problem(name: &str, out: &Path, sets: &[&str]) -> Child {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios/model_problems")
        .join(name);
    let mut cmd = tread();
    cmd.arg("run").arg(scene).args(["-q", "--out"]).arg(out);
    let sinks = "output.sinks=[\"summary\", \"csv\", \"vtu\"]";
    for s in sets.iter().copied().chain([sinks]) {
        cmd.args(["--set", s]);
    }
    cmd.stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap()
}

/// Start the model-problem run ([`start_model_problem`]), let it work 1.5 s once it holds its
/// output folder (after the handler is installed), send SIGINT, and check that it stopped as
/// an interrupted run does: exit 130, no panic, the message, and summary.json (returned) with
/// `converged: false` and `"error": "interrupted"`.
fn interrupt_model_problem(name: &str, out: &Path, sets: &[&str]) -> serde_json::Value {
    let mut child = start_model_problem(name, out, sets);
    wait_for(&mut child, out);
    std::thread::sleep(Duration::from_millis(1500));
    signal(&child, "-INT");
    let o = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(stderr.contains("interrupted"), "{stderr}");
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["mode"], "model_problem");
    assert_eq!(s["converged"], false);
    assert_eq!(s["error"], "interrupted");
    s
}

/// Wait until `path` exists (the child still running), at most a minute.
fn wait_for(child: &mut Child, path: &Path) {
    let t0 = Instant::now();
    while !path.exists() {
        if let Ok(Some(st)) = child.try_wait() {
            panic!("the run ended ({st}) before {} appeared", path.display());
        }
        assert!(t0.elapsed() < Duration::from_secs(60), "timeout");
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// The cavity's Newton continuation in Re and its moving-mesh recalculations (50, on 32 × 32
/// cells: far longer than the wait below) stop at the next solve on SIGINT: exit 130,
/// `"error": "interrupted"`, `interrupted_at` the Reynolds number reached, one row of steps.csv
/// per solve done, and the solution of the last solve written.
#[test]
fn sigint_stops_the_cavity_between_solves() {
    let dir = tmpdir("cavity");
    let out = dir.join("out");
    let s = interrupt_model_problem(
        "cavity.toml",
        &out,
        &["problem.levels=5", "problem.recalculations=50"],
    );
    let re = s["interrupted_at"].as_f64().unwrap();
    assert!([100.0, 400.0, 1000.0].contains(&re), "interrupted_at {re}");
    // Rows: one per solve (the continuation's and the recalculations'), fewer than the full run's.
    let steps = s["steps"].as_u64().unwrap() as usize;
    assert!((1..53).contains(&steps), "{steps} rows");
    let (h, rows) = read_csv(&out.join("steps.csv"));
    assert_eq!(rows.len(), steps);
    let psi = column(&h, &rows, "psi_min");
    assert!(psi.iter().all(|p| p.is_finite() && *p < 0.0), "{psi:?}");
    assert!(out.join("solution.vtu").exists());
}

/// `tread adapt` stops at the next mesh on SIGINT: exit 130, adapt.csv with one row per mesh
/// solved (as many as the adapt_NNN.vtu files written), fewer than asked for.
#[test]
fn sigint_stops_tread_adapt_between_meshes() {
    let dir = tmpdir("adapt");
    let out = dir.join("out");
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenarios/oden_hollow_cylinder.toml"
    );
    let mut child = tread()
        .args([
            "adapt",
            scene,
            "-q",
            "--steps",
            "30",
            "--max-dofs",
            "10000000",
        ])
        .args(["--set", "analysis.mode=steady", "--out"])
        .arg(&out)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    wait_for(&mut child, &out.join("adapt_000.vtu"));
    signal(&child, "-INT");
    let o = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(stderr.contains("interrupted"), "{stderr}");
    let (h, rows) = read_csv(&out.join("adapt.csv"));
    assert!((1..31).contains(&rows.len()), "{} rows", rows.len());
    let vtus = std::fs::read_dir(&out)
        .unwrap()
        .filter(|e| {
            let n = e.as_ref().unwrap().file_name();
            let n = n.to_string_lossy();
            n.starts_with("adapt_") && n.ends_with(".vtu")
        })
        .count();
    assert_eq!(vtus, rows.len());
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("adapt.json")).unwrap()).unwrap();
    assert_eq!(j["interrupted"], true);
    assert_eq!(j["steps"].as_array().unwrap().len(), rows.len());
    let est = column(&h, &rows, "relative_estimate");
    assert!(est.iter().all(|e| e.is_finite() && *e > 0.0), "{est:?}");
}
