//! Golden files of the generated Slurm scripts (no Slurm needed): a plain array with a
//! throttle and every resource, one part of a sweep split above MaxArraySize, a packed array,
//! a resumed sweep (only the pending tasks), the collect job; and `--dry-run` through the CLI
//! writing the same scripts as the library with the CLI's options on top of the spec's.
//!
//! `TREAD_UPDATE_GOLDEN=1 cargo test --test sweep_scripts` rewrites the files in
//! tests/sweep_golden/ (review the diff before committing).

mod sweep_support;
#[path = "common/tempdir.rs"]
mod tempdir;

use std::path::{Path, PathBuf};
use sweep_support::*;
use tempdir::TestDir;
use tread::sweep::slurm::{layout, render_array, render_collect, Resources, ScriptContext};

fn golden(name: &str, got: &str) {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/sweep_golden")
        .join(name);
    if std::env::var_os("TREAD_UPDATE_GOLDEN").is_some() {
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, got).unwrap();
        return;
    }
    let want = std::fs::read_to_string(&p)
        .unwrap_or_else(|e| panic!("{}: {e} (TREAD_UPDATE_GOLDEN=1 writes it)", p.display()));
    if want != got {
        panic!(
            "{} differs from the generated script:\n--- golden\n{want}\n--- generated\n{got}",
            p.display()
        );
    }
}

fn ctx(n_runs: usize, resources: Resources) -> ScriptContext {
    ScriptContext {
        name: "creep_force".into(),
        exe: PathBuf::from("/opt/tread/bin/tread"),
        spec: PathBuf::from("/home/ana/study/sweep_creep_force.toml"),
        root: PathBuf::from("/scratch/ana/creep_force"),
        n_runs,
        resources,
    }
}

fn full() -> Resources {
    Resources {
        partition: Some("compute".into()),
        time: Some("00:30:00".into()),
        cpus_per_task: 4,
        mem: Some("2G".into()),
        throttle: Some(16),
        pack: 1,
        extra: vec!["--account=proj42".into()],
    }
}

#[test]
fn array_with_throttle_and_resources() {
    let all: Vec<usize> = (0..69).collect();
    let parts = layout(&all, 1, 1001);
    assert_eq!(parts.len(), 1);
    let c = ctx(69, full());
    golden("array.sbatch", &render_array(&c, &parts[0], 0, 1));
    golden("collect.sbatch", &render_collect(&c));
}

#[test]
fn split_above_max_array_size() {
    let all: Vec<usize> = (0..2500).collect();
    let parts = layout(&all, 1, 1001);
    assert_eq!(parts.len(), 3);
    let mut r = full();
    r.partition = None;
    r.mem = None;
    r.extra.clear();
    let c = ctx(2500, r);
    golden("array_split_002.sbatch", &render_array(&c, &parts[2], 2, 3));
}

#[test]
fn packed_and_resumed_arrays() {
    let all: Vec<usize> = (0..2500).collect();
    let mut r = full();
    r.pack = 3;
    r.throttle = None;
    let parts = layout(&all, 3, 1001);
    assert_eq!(parts.len(), 1);
    golden(
        "array_pack3.sbatch",
        &render_array(&ctx(2500, r.clone()), &parts[0], 0, 1),
    );
    // Resuming: runs 0-9 done, 11 and 40-44 pending.
    let pending = [10, 11, 40, 41, 42, 43, 44];
    let mut r = full();
    r.throttle = Some(2);
    let parts = layout(&pending, 1, 1001);
    golden(
        "array_resume.sbatch",
        &render_array(&ctx(69, r), &parts[0], 0, 1),
    );
}

/// The generated scripts with the test's folder replaced by `@DIR@` and the binary by `@TREAD@`.
fn normalised(p: &Path, dir: &Path) -> String {
    std::fs::read_to_string(p)
        .unwrap()
        .replace(env!("CARGO_BIN_EXE_tread"), "@TREAD@")
        .replace(dir.to_str().unwrap(), "@DIR@")
}

#[test]
fn dry_run_writes_the_scripts_with_cli_options_over_the_spec() {
    let d = TestDir::new("sweep", "dryrun");
    let spec = write_spec(
        &d,
        &format!(
            "{EIGHT}\n[slurm]\npartition = \"short\"\ntime = \"00:05:00\"\nmem = \"1G\"\nthrottle = 4\nextra = [\"--account=proj42\"]\n"
        ),
    );
    let root = d.join("sw");
    let o = run(&[
        "sweep",
        "run",
        spec.to_str().unwrap(),
        "--backend",
        "slurm",
        "--dry-run",
        "--out",
        root.to_str().unwrap(),
        "--time",
        "01:00:00",
        "--cpus-per-task",
        "2",
        "--sbatch=--qos=low",
    ]);
    let all = text(&o);
    assert!(o.status.success(), "{all}");
    assert!(
        all.contains("dry run: 8 run(s) to submit; nothing submitted"),
        "{all}"
    );
    assert!(!root.join("slurm/jobs.json").exists());
    assert!(
        !root.join("runs").exists(),
        "a dry run marks nothing queued"
    );
    golden(
        "dry_run_array.sbatch",
        &normalised(&root.join("slurm/array.sbatch"), &d),
    );
    golden(
        "dry_run_collect.sbatch",
        &normalised(&root.join("slurm/collect.sbatch"), &d),
    );
    // A bad option is refused before anything is written.
    let o = run(&[
        "sweep",
        "run",
        spec.to_str().unwrap(),
        "--backend",
        "slurm",
        "--dry-run",
        "--out",
        d.join("sw2").to_str().unwrap(),
        "--time",
        "1h",
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", text(&o));
    assert!(
        text(&o).contains("option `--time`: `1h` is not a Slurm time"),
        "{}",
        text(&o)
    );
}

#[test]
fn generated_scripts_are_valid_bash() {
    // `bash -n` parses without running (the scripts are bash: `#!/bin/bash`).
    let d = TestDir::new("sweep", "bash_n");
    let all: Vec<usize> = (0..69).collect();
    let c = ctx(69, full());
    for (name, text) in [
        (
            "a.sbatch",
            render_array(&c, &layout(&all, 1, 1001)[0], 0, 1),
        ),
        ("c.sbatch", render_collect(&c)),
    ] {
        let p = d.join(name);
        std::fs::write(&p, text).unwrap();
        let o = std::process::Command::new("bash")
            .arg("-n")
            .arg(&p)
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
}
