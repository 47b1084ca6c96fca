//! Runs that cannot succeed end cleanly: a clear message and the documented exit status (2
//! invalid input, 3 output folder or file, 1 failed computation), never a panic, an abort, an
//! unbounded allocation or a corrupt file; the output folder is locked and cleared of an
//! earlier run's results.
//!
//! `TREAD_BIN` runs the same checks against another build of the program.

#[path = "common/tempdir.rs"]
mod tempdir;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};
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

fn no_panic(o: &Output) -> String {
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(
        !err.contains("panicked") && !err.contains("memory allocation"),
        "{err}"
    );
    // A signal (abort, SIGPIPE) leaves no exit code.
    assert!(o.status.code().is_some(), "killed by a signal: {err}");
    err
}

fn run_spinning(out: &Path, set: &[&str]) -> Output {
    let mut c = tread();
    c.args(["-q", "run"])
        .arg(scene("spinning_neo_hookean.toml"))
        .arg("--out")
        .arg(out)
        .args(["--set", r#"output.sinks=["summary","csv","vtu","mcap"]"#]);
    for s in set {
        c.args(["--set", s]);
    }
    c.output().unwrap()
}

#[test]
fn huge_meshes_are_refused_before_allocating() {
    let d = TestDir::new("fail", "huge");
    for set in [
        "mesh.n_r=4611686018427387904",
        "mesh.n_r=1099511627776",
        "mesh.n_theta=10000000",
        "mesh.n_r=1000000",
    ] {
        let t = Instant::now();
        let o = run_spinning(&d.join("out"), &[set]);
        let err = no_panic(&o);
        assert_eq!(o.status.code(), Some(2), "{set}: {err}");
        assert!(err.contains("memory"), "{set}: {err}");
        assert!(t.elapsed() < Duration::from_secs(20), "{set}");
    }
    // An explicit limit refuses a scene that fits the machine.
    let mut c = tread();
    let o = c
        .args(["-q", "--max-memory", "1M", "run"])
        .arg(scene("spinning_neo_hookean.toml"))
        .arg("--out")
        .arg(d.join("out"))
        .output()
        .unwrap();
    let err = no_panic(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--max-memory"), "{err}");
}

#[test]
fn check_refuses_endless_input() {
    let t = Instant::now();
    let o = tread().args(["check", "/dev/zero"]).output().unwrap();
    let err = no_panic(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(t.elapsed() < Duration::from_secs(20));
}

#[test]
fn closed_or_full_stdout_is_not_a_crash() {
    let d = TestDir::new("fail", "stdout");
    // A reader that went away (`tread … | head -0`).
    let mut child = tread()
        .args(["run"])
        .arg(scene("spinning_neo_hookean.toml"))
        .arg("--out")
        .arg(d.join("a"))
        .args([
            "--set",
            "mesh.n_r=2",
            "--set",
            r#"output.sinks=["summary"]"#,
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    no_panic(&o);
    assert_eq!(o.status.code(), Some(0));
    assert!(d.join("a/summary.json").is_file());
    // A full device.
    let full = std::fs::OpenOptions::new().write(true).open("/dev/full");
    if let Ok(full) = full {
        let o = tread()
            .args(["run"])
            .arg(scene("spinning_neo_hookean.toml"))
            .arg("--out")
            .arg(d.join("b"))
            .args([
                "--set",
                "mesh.n_r=2",
                "--set",
                r#"output.sinks=["summary"]"#,
            ])
            .stdout(full)
            .output()
            .unwrap();
        no_panic(&o);
        assert_eq!(o.status.code(), Some(0));
    }
}

#[test]
fn replay_refuses_what_is_not_a_log() {
    let d = TestDir::new("fail", "replay");
    let garbage = d.join("garbage.mcap");
    let bytes: Vec<u8> = (0..4096u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
        .collect();
    std::fs::write(&garbage, bytes).unwrap();
    let empty = d.join("empty.mcap");
    std::fs::write(&empty, b"").unwrap();
    for f in [&garbage, &empty] {
        let to = d.join("x.rrd");
        let o = tread()
            .arg("replay")
            .arg(f)
            .arg("--to")
            .arg(&to)
            .output()
            .unwrap();
        let err = no_panic(&o);
        assert_eq!(o.status.code(), Some(1), "{}: {err}", f.display());
        assert!(
            err.contains("not an MCAP log") || err.contains("no readable message"),
            "{err}"
        );
        assert!(!to.exists(), "no .rrd written from {}", f.display());
    }
}

#[test]
fn unwritable_output_folder_is_found_before_the_solve() {
    // /proc exists but takes no new files (also for root).
    let o = run_spinning(Path::new("/proc"), &["mesh.n_r=2"]);
    let err = no_panic(&o);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(err.contains("output folder"), "{err}");
    assert!(
        !err.contains("warning"),
        "found only after the solve: {err}"
    );
}

#[test]
fn a_busy_output_folder_is_refused_and_a_stale_one_cleared() {
    let d = TestDir::new("fail", "lock");
    let out = d.join("out");
    std::fs::create_dir_all(out.join("fields")).unwrap();
    // A live process (this test) holds the lock.
    std::fs::write(out.join(".tread.lock"), format!("{}\n", std::process::id())).unwrap();
    let o = run_spinning(&out, &["mesh.n_r=2"]);
    let err = no_panic(&o);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(err.contains("another tread run"), "{err}");
    assert!(!out.join("summary.json").exists());

    // A lock left by a process that no longer exists, and an earlier run's results.
    std::fs::write(out.join(".tread.lock"), "4000000000\n").unwrap();
    std::fs::write(out.join("branch.csv"), "stale\n").unwrap();
    std::fs::write(out.join("fields/step_000099.vtu"), "stale").unwrap();
    std::fs::write(out.join("notes.txt"), "the user's own file").unwrap();
    let o = run_spinning(&out, &["mesh.n_r=2"]);
    let err = no_panic(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(!out.join("branch.csv").exists(), "stale result kept");
    assert!(
        !out.join("fields/step_000099.vtu").exists(),
        "stale field kept"
    );
    assert!(
        out.join("notes.txt").exists(),
        "a file tread does not write was removed"
    );
    assert!(!out.join(".tread.lock").exists(), "lock not released");
    assert!(out.join("summary.json").is_file());
}

#[test]
fn stick_slip_reports_periods_in_plain_numbers() {
    let d = TestDir::new("fail", "stick_slip");
    let o = tread()
        .args(["run"])
        .arg(scene("stick_slip.toml"))
        .arg("--out")
        .arg(d.join("out"))
        .args([
            "--set",
            "stick_slip.t_end=3",
            "--set",
            r#"output.sinks=["summary"]"#,
        ])
        .output()
        .unwrap();
    let err = no_panic(&o);
    let text = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(!text.contains("Some(") && !text.contains("None"), "{text}");
}
