//! `tread sweep --backend slurm` on a real single-node Slurm.
//!
//! These tests need a running Slurm (sbatch, squeue, scancel on PATH, a node taking jobs) and
//! are marked `#[ignore]`: `cargo test` lists them as ignored, never as passed.
//! `tools/slurm_test.sh` brings up a single-node Slurm (tools/slurm_single_node.sh), runs them
//! with `--ignored`, and tears it down; where the Debian packages cannot be installed it
//! reports a skip (exit status 77). Run by hand when a Slurm is up:
//! `cargo test --release --test sweep_slurm -- --ignored --test-threads 1`.
//!
//! Covered: an 8-run sweep with one failing point (7 done, 1 failed with its error, the
//! collect job still runs) whose table equals the local backend's; a sweep cancelled with
//! `scancel` (runs killed, the others never started) that resumes and completes, with the
//! done runs left alone.

mod sweep_support;
#[path = "common/tempdir.rs"]
mod tempdir;

use std::process::Command;
use sweep_support::*;
use tempdir::TestDir;

fn require_slurm() {
    let ok = Command::new("sinfo")
        .args(["-h", "-o", "%t"])
        .output()
        .map(|o| {
            o.status.success()
                && String::from_utf8_lossy(&o.stdout)
                    .lines()
                    .any(|l| ["idle", "mix", "alloc"].contains(&l.trim()))
        })
        .unwrap_or(false);
    assert!(
        ok,
        "no Slurm node takes jobs here (sinfo): bring one up with tools/slurm_single_node.sh up"
    );
}

fn jobs(root: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(root.join("slurm/jobs.json")).unwrap()).unwrap()
}

fn in_queue(id: &str) -> bool {
    let o = Command::new("squeue")
        .args(["-h", "-j", id, "-o", "%i"])
        .output()
        .unwrap();
    o.status.success() && !String::from_utf8_lossy(&o.stdout).trim().is_empty()
}

#[test]
#[ignore = "needs a running Slurm: tools/slurm_test.sh"]
fn slurm_sweep_with_a_failing_point_equals_the_local_backend() {
    require_slurm();
    let d = TestDir::new("sweep", "slurm8");
    let spec = write_spec(&d, EIGHT);
    let root = d.join("slurm");
    let o = run(&[
        "sweep",
        "run",
        spec.to_str().unwrap(),
        "--backend",
        "slurm",
        "--throttle",
        "4",
        "--poll",
        "0.5",
        "--out",
        root.to_str().unwrap(),
    ]);
    let all = text(&o);
    assert_eq!(o.status.code(), Some(1), "one run failed: {all}");
    assert!(all.contains("8 runs: 7 done, 1 failed"), "{all}");
    check_eight(&root);
    // The collect job ran (afterany) and wrote the table and the plot.
    let j = jobs(&root);
    let cid = j["collect_job"].as_str().unwrap();
    let log = root.join(format!("slurm/logs/tread-eight-collect-{cid}.out"));
    let log_text =
        std::fs::read_to_string(&log).unwrap_or_else(|e| panic!("{}: {e}", log.display()));
    assert!(log_text.contains("table: "), "{log_text}");
    assert!(root.join("plots/u_r.png").exists());
    // Each run ran under its array task.
    let st = status(&root, "0003");
    let arr = st["at"]["slurm_array"].as_str().unwrap();
    assert_eq!(arr, format!("{}_3", j["array_jobs"][0].as_str().unwrap()));

    // The same spec on the local backend: the same table (wall times aside).
    let local = d.join("local");
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
        local.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert_eq!(
        without_timing(&read_table(&root)),
        without_timing(&read_table(&local))
    );
}

#[test]
#[ignore = "needs a running Slurm: tools/slurm_test.sh"]
fn cancelled_slurm_sweep_resumes_and_completes() {
    require_slurm();
    let d = TestDir::new("sweep", "slurm_cancel");
    // Slow enough (10000 load steps, about 7 s) that scancel always arrives while run 0001
    // works: with 20 steps a run took 0.16 s, with 400 steps 0.3 s, and finished before it.
    let spec = write_spec(&d, &slow_with_load_steps(10000));
    let root = d.join("out");
    let args = [
        "sweep",
        "run",
        spec.to_str().unwrap(),
        "--backend",
        "slurm",
        "--throttle",
        "1",
        "--poll",
        "0.5",
        "--out",
        root.to_str().unwrap(),
    ];
    let mut a = args.to_vec();
    a.push("--no-wait");
    let o = run(&a);
    assert!(o.status.success(), "{}", text(&o));
    let j = jobs(&root);
    let array = j["array_jobs"][0].as_str().unwrap().to_string();
    let collect = j["collect_job"].as_str().unwrap().to_string();
    wait_until(120.0, "run 0000 done and 0001 running", || {
        state(&root, "0000") == "done" && state(&root, "0001") == "running"
    });
    std::thread::sleep(std::time::Duration::from_millis(300));
    let ok = Command::new("scancel")
        .arg(&array)
        .status()
        .unwrap()
        .success();
    assert!(ok, "scancel {array}");
    wait_until(
        90.0,
        "the array and collect jobs to leave the queue",
        || !in_queue(&array) && !in_queue(&collect),
    );
    assert_eq!(state(&root, "0000"), "done");
    let st = status(&root, "0001");
    assert_eq!(st["state"], "killed", "{st}");
    assert!(
        st["error"].as_str().unwrap().contains("SIGTERM"),
        "scancel sends SIGTERM: {st}"
    );
    assert_eq!(state(&root, "0002"), "queued");
    assert_eq!(state(&root, "0003"), "queued");
    // The collect job still ran after the cancelled array (afterany).
    let t = read_table(&root);
    assert_eq!(column(&t, "state"), ["done", "killed", "queued", "queued"]);

    // Resume: only the runs not done are submitted, and the sweep completes.
    let first = status(&root, "0000");
    let o = run(&args);
    let all = text(&o);
    assert_eq!(o.status.code(), Some(0), "{all}");
    let script = std::fs::read_to_string(root.join("slurm/array.sbatch")).unwrap();
    assert!(script.contains("#SBATCH --array=1-3%1"), "{script}");
    assert_eq!(status(&root, "0000"), first, "the done run was run again");
    assert_eq!(status(&root, "0001")["attempts"], 2);
    let t = read_table(&root);
    assert_eq!(column(&t, "state"), ["done"; 4]);
}
