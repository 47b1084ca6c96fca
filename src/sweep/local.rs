//! `tread sweep run --backend local`: a process pool on this machine.
//!
//! At most `jobs` runs at once, each one `tread sweep run-one SPEC --index N` process (in its
//! own process group, so Ctrl-C in the terminal reaches the pool only). Runs already done are
//! skipped; the others are marked `queued`, then started in index order. A progress bar (runs
//! finished of the sweep, failures, ETA) goes to stderr unless quiet or not a terminal; failed
//! runs are printed as they end.
//!
//! Ctrl-C (or SIGTERM) stops cleanly: no new run starts, each running run-one gets SIGTERM (it
//! records `killed` and stops its `tread run`), the pool waits for them and exits with 130.
//! A second Ctrl-C kills the runs' process groups with SIGKILL. Running the same command again
//! resumes: done runs are skipped.

use super::run_one::{is_done, run_dir};
use super::signal;
use super::spec::Spec;
use super::status::{self, State, Status};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::collections::BTreeMap;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

#[derive(Clone, Debug)]
pub struct LocalOptions {
    pub jobs: usize,
    /// `--threads` of each run.
    pub threads: Option<usize>,
    pub quiet: bool,
    pub exe: PathBuf,
}

/// How the pool ended.
#[derive(Clone, Debug, PartialEq)]
pub struct LocalReport {
    /// Runs started by this call.
    pub started: usize,
    /// Runs found done and skipped.
    pub skipped: usize,
    pub interrupted: bool,
    pub wall_time_s: f64,
}

/// Mark the runs that are not done as queued (keeping their attempt count and last error).
pub fn mark_queued(
    spec: &Spec,
    root: &Path,
    pending: &[usize],
    by: Option<&str>,
) -> Result<(), String> {
    let t = status::now();
    for &i in pending {
        let dir = run_dir(spec, root, i);
        let run = spec.run(i);
        let prev = status::read(&dir).ok().flatten();
        let mut st = Status::new(
            i,
            State::Queued,
            spec.overrides(&run),
            spec.run_fingerprint(&run),
        );
        if let Some(p) = prev.filter(|p| p.fingerprint == st.fingerprint) {
            st.attempts = p.attempts;
            st.error = p.error.map(|e| format!("previous attempt: {e}"));
        }
        st.queued_at = Some(t);
        st.queued_by = by.map(str::to_string);
        status::write(&dir, &st)?;
    }
    Ok(())
}

/// The runs that are not done.
pub fn pending(spec: &Spec, root: &Path) -> Vec<usize> {
    (0..spec.n_runs())
        .filter(|&i| !is_done(spec, root, i))
        .collect()
}

pub fn run_local(spec: &Spec, root: &Path, opts: &LocalOptions) -> Result<LocalReport, String> {
    let t0 = Instant::now();
    let n = spec.n_runs();
    let todo = pending(spec, root);
    let skipped = n - todo.len();
    mark_queued(spec, root, &todo, Some("local"))?;
    signal::install();

    let pb = if opts.quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::with_draw_target(Some(n as u64), ProgressDrawTarget::stderr())
    };
    pb.set_style(
        ProgressStyle::with_template(
            "{prefix} [{bar:30}] {pos}/{len} runs  {msg}  elapsed {elapsed}, ETA {eta}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    pb.set_prefix(spec.name.clone());
    pb.set_position(skipped as u64);
    pb.reset_eta();
    if skipped > 0 && !opts.quiet {
        pb.suspend(|| eprintln!("tread: {skipped} of {n} runs already done: skipped"));
    }

    let (tx, rx) = mpsc::channel::<(usize, u32)>();
    let mut queue = todo.iter().copied();
    let mut running: BTreeMap<usize, u32> = BTreeMap::new();
    let mut started = 0;
    let mut failed = 0;
    let mut stopping = false;
    let mut hard = false;
    let jobs = opts.jobs.max(1);
    let exe = &opts.exe;
    loop {
        if !stopping && signal::received().is_some() {
            stopping = true;
            pb.suspend(|| {
                eprintln!(
                    "tread: interrupt: stopping {} running run(s); Ctrl-C again to kill them",
                    running.len()
                )
            });
            for &pid in running.values() {
                signal::send(pid, signal::SIGTERM);
            }
        }
        if stopping && !hard && signal::count() >= 2 {
            hard = true;
            for &pid in running.values() {
                signal::send_group(pid, signal::SIGKILL);
            }
        }
        while !stopping && running.len() < jobs {
            let Some(i) = queue.next() else { break };
            let mut cmd = Command::new(exe);
            if let Some(t) = opts.threads {
                cmd.arg("--threads").arg(t.to_string());
            }
            cmd.arg("-q")
                .arg("sweep")
                .arg("run-one")
                .arg(&spec.path)
                .arg("--out")
                .arg(root)
                .arg("--index")
                .arg(i.to_string())
                .stdin(Stdio::null())
                .stdout(Stdio::null())
                .process_group(0);
            let log = run_dir(spec, root, i).join("run-one.log");
            match std::fs::File::create(&log) {
                Ok(f) => cmd.stderr(f),
                Err(_) => cmd.stderr(Stdio::null()),
            };
            match cmd.spawn() {
                Ok(mut child) => {
                    let pid = child.id();
                    running.insert(i, pid);
                    started += 1;
                    let tx = tx.clone();
                    std::thread::spawn(move || {
                        let code = child.wait().ok().and_then(|s| s.code()).unwrap_or(-1);
                        let _ = tx.send((i, code as u32));
                    });
                }
                Err(e) => {
                    pb.finish_and_clear();
                    return Err(format!("cannot start {}: {e}", exe.display()));
                }
            }
        }
        pb.set_message(format!(
            "{} running{}",
            running.len(),
            if failed > 0 {
                format!(", {failed} failed")
            } else {
                String::new()
            }
        ));
        if running.is_empty() && (stopping || queue.len() == 0) {
            break;
        }
        match rx.recv_timeout(Duration::from_millis(100)) {
            Ok((i, _code)) => {
                running.remove(&i);
                pb.inc(1);
                // The run's folder, not the exit status, says what happened.
                match status::read(&run_dir(spec, root, i)) {
                    Ok(Some(s)) if s.state == State::Done => {}
                    Ok(Some(s)) if s.state == State::Killed && stopping => {}
                    Ok(Some(s)) if s.state.is_final() => {
                        failed += 1;
                        let err = s.error.unwrap_or_default();
                        let first = err.lines().next().unwrap_or("").to_string();
                        pb.suspend(|| {
                            eprintln!("tread: run {} {}: {first}", spec.run_name(i), s.state)
                        });
                    }
                    // No final state: run-one stopped before running (e.g. the run is being
                    // run elsewhere); its own message says why.
                    _ => {
                        failed += 1;
                        let log = run_dir(spec, root, i).join("run-one.log");
                        let msg = std::fs::read_to_string(&log).unwrap_or_default();
                        pb.suspend(|| {
                            eprintln!("tread: run {}: not run: {}", spec.run_name(i), msg.trim())
                        });
                    }
                }
            }
            Err(mpsc::RecvTimeoutError::Timeout) => {}
            Err(mpsc::RecvTimeoutError::Disconnected) => break,
        }
    }
    pb.finish_and_clear();
    Ok(LocalReport {
        started,
        skipped,
        interrupted: stopping,
        wall_time_s: t0.elapsed().as_secs_f64(),
    })
}

/// Default threads per run: the cores shared among the jobs (at least one).
pub fn default_threads(jobs: usize) -> usize {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    (cores / jobs.max(1)).max(1)
}

/// Used by the pool's callers to explain a killed or interrupted state.
pub fn resume_hint(spec: &Spec) -> String {
    format!(
        "run the same command again to resume (done runs are skipped); `tread sweep status {}` shows each run",
        spec.path.display()
    )
}
