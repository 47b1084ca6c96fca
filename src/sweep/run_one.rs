//! `tread sweep run-one SPEC --index N`: the one entry point every backend calls.
//!
//! It runs `tread run BASE --set key=value … --out <sweep>/runs/NNNN -q` as a child process
//! (the very program of a single run, so a sweep run and a bare run are the same computation)
//! and records the outcome in `runs/NNNN/status.json` from the child's exit status and
//! summary.json:
//!
//! | `tread run` ends with          | status   | error                                     |
//! |--------------------------------|----------|-------------------------------------------|
//! | exit 0                         | done     | —                                         |
//! | exit 1 (the solve failed)      | failed   | summary.json `error` (else stderr's tail) |
//! | exit 130 (interrupted)         | killed   | "interrupted"                             |
//! | a signal (SIGKILL, SIGSEGV, …) | killed   | the signal                                |
//! | any other exit (2: bad input)  | failed   | stderr's tail and the exit status         |
//!
//! A run whose status is `done` for the same base scene and overrides (the fingerprint in
//! status.json) is skipped: calling run-one again on every index resumes a sweep. `failed` and
//! `killed` runs are run again; their folder is emptied first (status.json keeps the count of
//! attempts).
//!
//! On SIGTERM (Slurm's time limit or `scancel`), SIGINT or SIGHUP, run-one writes `killed` at
//! once (so the record exists even if SIGKILL follows), then asks the child to stop with SIGINT
//! (it finishes its logs at the next step boundary) and waits up to `grace` before SIGKILL.
//! The child's stdout and stderr go to `runs/NNNN/stdout.log` and `stderr.log`.

use super::signal;
use super::spec::Spec;
use super::status::{self, State, Status, Where};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// How a call of run-one ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// Already done: nothing run.
    Skipped,
    Done,
    Failed(String),
    Killed(String),
}

impl Outcome {
    /// Exit status of `tread sweep run-one`: 0 done or skipped, 1 failed, 128 + signal when
    /// killed by a signal it received (143 for SIGTERM), 130 otherwise killed.
    pub fn exit_code(&self) -> u8 {
        match self {
            Outcome::Skipped | Outcome::Done => 0,
            Outcome::Failed(_) => 1,
            Outcome::Killed(_) => match signal::received() {
                Some(s) if s > 0 && s < 64 => 128 + s as u8,
                _ => 130,
            },
        }
    }
}

#[derive(Clone, Debug)]
pub struct RunOneOptions {
    /// `--threads` for `tread run` (None: its default).
    pub threads: Option<usize>,
    /// How long a signalled child may take to stop before SIGKILL.
    pub grace: Duration,
    /// The `tread` executable.
    pub exe: PathBuf,
}

/// The folder of run `index` under the sweep folder `root`.
pub fn run_dir(spec: &Spec, root: &Path, index: usize) -> PathBuf {
    root.join("runs").join(spec.run_name(index))
}

/// Whether run `index` is done for the current spec (status done, same fingerprint).
pub fn is_done(spec: &Spec, root: &Path, index: usize) -> bool {
    matches!(
        status::read(&run_dir(spec, root, index)),
        Ok(Some(s)) if s.state == State::Done && s.fingerprint == spec.run_fingerprint(&spec.run(index))
    )
}

/// Remove the outputs of an earlier attempt (everything but status.json).
fn clear_outputs(dir: &Path) -> Result<(), String> {
    let entries = match std::fs::read_dir(dir) {
        Ok(e) => e,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(format!("cannot read {}: {e}", dir.display())),
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.file_name().is_some_and(|n| n == "status.json") {
            continue;
        }
        let r = if p.is_dir() {
            std::fs::remove_dir_all(&p)
        } else {
            std::fs::remove_file(&p)
        };
        r.map_err(|e| format!("cannot remove {}: {e}", p.display()))?;
    }
    Ok(())
}

/// The last `max` characters of a log, on line boundaries, without the `tread: ` prefixes.
fn tail(text: &str, max: usize) -> String {
    let lines: Vec<&str> = text
        .lines()
        .map(str::trim_end)
        .filter(|l| !l.is_empty() && !l.starts_with("tread: warning"))
        .collect();
    let mut out: Vec<&str> = Vec::new();
    let mut len = 0;
    for l in lines.iter().rev() {
        if len + l.len() > max && !out.is_empty() {
            break;
        }
        len += l.len() + 1;
        out.push(l);
    }
    out.reverse();
    out.iter()
        .map(|l| l.strip_prefix("tread: ").unwrap_or(l))
        .collect::<Vec<_>>()
        .join("\n")
}

fn summary_error(dir: &Path) -> Option<String> {
    let text = std::fs::read_to_string(dir.join("summary.json")).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    v.get("error")?.as_str().map(str::to_string)
}

/// Run (or skip) run `index` of `spec` in the sweep folder `root`.
pub fn run_one(
    spec: &Spec,
    root: &Path,
    index: usize,
    opts: &RunOneOptions,
) -> Result<Outcome, String> {
    let n = spec.n_runs();
    if index >= n {
        return Err(format!(
            "--index {index} is out of range: the sweep `{}` has {n} runs (0..={})",
            spec.name,
            n.saturating_sub(1)
        ));
    }
    let run = spec.run(index);
    let overrides = spec.overrides(&run);
    let fingerprint = spec.run_fingerprint(&run);
    let dir = run_dir(spec, root, index);
    let previous = status::read(&dir)?;
    if let Some(p) = &previous {
        if p.state == State::Done && p.fingerprint == fingerprint {
            return Ok(Outcome::Skipped);
        }
        if p.state == State::Running {
            if let Some(at) = &p.at {
                if at.host == status::hostname()
                    && at.pid != std::process::id()
                    && status::process_alive(at.pid)
                {
                    return Err(format!(
                        "run {} is already running (pid {} on this host)",
                        spec.run_name(index),
                        at.pid
                    ));
                }
            }
        }
    }
    signal::install();
    clear_outputs(&dir)?;
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let mut st = Status::new(index, State::Running, overrides.clone(), fingerprint);
    st.attempts = previous.as_ref().map_or(0, |p| p.attempts) + 1;
    st.queued_at = previous.as_ref().and_then(|p| p.queued_at);
    st.started_at = Some(status::now());
    st.at = Some(Where::here());
    status::write(&dir, &st)?;
    if let Some(sig) = signal::received() {
        // Signalled before the run started: nothing to stop.
        return finish_killed(
            &dir,
            &mut st,
            format!("killed by {} before it started", signal::name(sig)),
        );
    }

    let mut cmd = Command::new(&opts.exe);
    if let Some(t) = opts.threads {
        cmd.arg("--threads").arg(t.to_string());
    }
    cmd.arg("-q")
        .arg("run")
        .arg(&spec.scene_path)
        .arg("--out")
        .arg(&dir);
    for o in &overrides {
        cmd.arg("--set").arg(o);
    }
    let log = |name: &str| {
        std::fs::File::create(dir.join(name))
            .map_err(|e| format!("cannot create {}: {e}", dir.join(name).display()))
    };
    cmd.stdin(Stdio::null())
        .stdout(log("stdout.log")?)
        .stderr(log("stderr.log")?);
    let t0 = Instant::now();
    let mut child = match cmd.spawn() {
        Ok(c) => c,
        Err(e) => {
            let msg = format!("cannot start {}: {e}", opts.exe.display());
            st.state = State::Failed;
            st.error = Some(msg.clone());
            st.finished_at = Some(status::now());
            status::write(&dir, &st)?;
            return Ok(Outcome::Failed(msg));
        }
    };
    let pid = child.id();
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(child.wait());
    });
    let mut signalled: Option<(i32, Instant)> = None;
    let mut killed_hard = false;
    let exit = loop {
        match rx.recv_timeout(Duration::from_millis(50)) {
            Ok(r) => break r.map_err(|e| format!("waiting for `tread run`: {e}"))?,
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                return Err("lost the `tread run` child process".into())
            }
            Err(mpsc::RecvTimeoutError::Timeout) => {}
        }
        match (signal::received(), signalled) {
            (Some(sig), None) => {
                // Record first: SIGKILL may follow before the child has stopped.
                st.state = State::Killed;
                st.error = Some(format!("killed by {}", signal::name(sig)));
                st.finished_at = Some(status::now());
                st.wall_time_s = Some(t0.elapsed().as_secs_f64());
                status::write(&dir, &st)?;
                signal::send(pid, signal::SIGINT);
                signalled = Some((sig, Instant::now()));
            }
            (Some(_), Some((_, at))) if !killed_hard && at.elapsed() > opts.grace => {
                signal::send(pid, signal::SIGKILL);
                killed_hard = true;
            }
            _ => {}
        }
    };
    let wall = t0.elapsed().as_secs_f64();
    st.wall_time_s = Some(wall);
    st.finished_at = Some(status::now());
    st.exit_code = exit.code();
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        st.signal = exit.signal();
    }
    let stderr = std::fs::read_to_string(dir.join("stderr.log")).unwrap_or_default();
    // A signal that arrived while the child was ending still makes the run killed (Slurm
    // signals the child directly too).
    if let Some(sig) = signalled.map(|s| s.0).or_else(signal::received) {
        let how = if killed_hard {
            format!(", then SIGKILL after {:.0} s", opts.grace.as_secs_f64())
        } else {
            String::new()
        };
        return finish_killed(
            &dir,
            &mut st,
            format!("killed by {}{how}", signal::name(sig)),
        );
    }
    match (exit.code(), st.signal) {
        (Some(0), _) => {
            st.state = State::Done;
            st.error = None;
            status::write(&dir, &st)?;
            Ok(Outcome::Done)
        }
        (Some(130), _) => finish_killed(&dir, &mut st, "interrupted".to_string()),
        (None, Some(sig)) => finish_killed(
            &dir,
            &mut st,
            format!("`tread run` was killed by {}", signal::name(sig)),
        ),
        (code, _) => {
            let msg = match code {
                Some(1) => summary_error(&dir)
                    .map(|e| format!("the solve failed: {e}"))
                    .unwrap_or_else(|| tail(&stderr, 2000)),
                Some(c) => format!("exit status {c}: {}", tail(&stderr, 2000)),
                None => "ended without an exit status".to_string(),
            };
            st.state = State::Failed;
            st.error = Some(msg.clone());
            status::write(&dir, &st)?;
            Ok(Outcome::Failed(msg))
        }
    }
}

fn finish_killed(dir: &Path, st: &mut Status, msg: String) -> Result<Outcome, String> {
    st.state = State::Killed;
    st.error = Some(msg.clone());
    if st.finished_at.is_none() {
        st.finished_at = Some(status::now());
    }
    status::write(dir, st)?;
    Ok(Outcome::Killed(msg))
}

#[cfg(test)]
mod tests {
    use super::tail;

    #[test]
    fn tail_keeps_the_last_lines_without_prefix_or_warnings() {
        let t = "tread: warning: sink skipped\ntread: invalid scene:\nx.toml:(--set): key `a.b`: bad\n\n";
        assert_eq!(
            tail(t, 1000),
            "invalid scene:\nx.toml:(--set): key `a.b`: bad"
        );
        assert_eq!(tail(t, 10), "x.toml:(--set): key `a.b`: bad");
    }
}
