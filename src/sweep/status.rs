//! `runs/NNNN/status.json`: the state of one run, the sweep's source of truth.
//!
//! States: `queued` (handed to a backend, not started), `running`, `done`, `failed` (with the
//! error), `killed` (a signal, a time limit, an interrupt). No folder or no status.json: not
//! started. A `running` status whose process no longer exists on this host is reported as
//! `killed` ("the process is gone") by [`read_effective`], so a SIGKILLed run is not shown as
//! running forever.
//!
//! The file is written atomically (temporary file, then rename): readers never see half a
//! status.

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, PartialOrd, Ord)]
#[serde(rename_all = "snake_case")]
pub enum State {
    Queued,
    Running,
    Done,
    Failed,
    Killed,
}

impl State {
    pub fn as_str(self) -> &'static str {
        match self {
            State::Queued => "queued",
            State::Running => "running",
            State::Done => "done",
            State::Failed => "failed",
            State::Killed => "killed",
        }
    }
    /// Whether the run has ended (done, failed or killed).
    pub fn is_final(self) -> bool {
        matches!(self, State::Done | State::Failed | State::Killed)
    }
}

impl std::fmt::Display for State {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Where a run is (or was) executed.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Where {
    pub host: String,
    pub pid: u32,
    /// `SLURM_JOB_ID` (for an array task: the task's own job id).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slurm_job_id: Option<String>,
    /// `SLURM_ARRAY_JOB_ID` and `SLURM_ARRAY_TASK_ID`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slurm_array: Option<String>,
}

impl Where {
    pub fn here() -> Where {
        let env = |k: &str| std::env::var(k).ok().filter(|s| !s.is_empty());
        Where {
            host: hostname(),
            pid: std::process::id(),
            slurm_job_id: env("SLURM_JOB_ID"),
            slurm_array: match (env("SLURM_ARRAY_JOB_ID"), env("SLURM_ARRAY_TASK_ID")) {
                (Some(j), Some(t)) => Some(format!("{j}_{t}")),
                _ => None,
            },
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Status {
    pub index: usize,
    pub state: State,
    /// The swept values of this run, as `key=value` overrides (exactly as passed to the scene).
    pub overrides: Vec<String>,
    /// [`super::spec::Spec::run_fingerprint`] of the run this status belongs to.
    pub fingerprint: String,
    /// Why the run failed or was killed.
    #[serde(default)]
    pub error: Option<String>,
    /// Exit status of `tread run` (None: not ended, or ended by a signal).
    #[serde(default)]
    pub exit_code: Option<i32>,
    /// Signal that ended the run (`tread run` or the run's supervisor), if any.
    #[serde(default)]
    pub signal: Option<i32>,
    /// How many times the run was started.
    #[serde(default)]
    pub attempts: u32,
    /// Unix times (s).
    #[serde(default)]
    pub queued_at: Option<f64>,
    #[serde(default)]
    pub started_at: Option<f64>,
    #[serde(default)]
    pub finished_at: Option<f64>,
    /// Wall time of `tread run` (s).
    #[serde(default)]
    pub wall_time_s: Option<f64>,
    #[serde(default)]
    pub at: Option<Where>,
    /// Backend-specific note for a queued run (e.g. the Slurm job of the array task).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub queued_by: Option<String>,
}

impl Status {
    pub fn new(index: usize, state: State, overrides: Vec<String>, fingerprint: String) -> Self {
        Status {
            index,
            state,
            overrides,
            fingerprint,
            error: None,
            exit_code: None,
            signal: None,
            attempts: 0,
            queued_at: None,
            started_at: None,
            finished_at: None,
            wall_time_s: None,
            at: None,
            queued_by: None,
        }
    }
}

pub fn now() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs_f64())
        .unwrap_or(0.0)
}

pub fn hostname() -> String {
    if let Ok(h) = std::fs::read_to_string("/proc/sys/kernel/hostname") {
        let h = h.trim();
        if !h.is_empty() {
            return h.to_string();
        }
    }
    std::env::var("HOSTNAME").unwrap_or_else(|_| "localhost".into())
}

pub fn status_path(run_dir: &Path) -> PathBuf {
    run_dir.join("status.json")
}

/// Read a run's status.json: `Ok(None)` when there is none; an error for an unreadable or
/// corrupt file.
pub fn read(run_dir: &Path) -> Result<Option<Status>, String> {
    let p = status_path(run_dir);
    let text = match std::fs::read_to_string(&p) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(format!("cannot read {}: {e}", p.display())),
    };
    serde_json::from_str(&text)
        .map(Some)
        .map_err(|e| format!("{} is not a run status: {e}", p.display()))
}

/// Whether process `pid` exists on this machine.
pub fn process_alive(pid: u32) -> bool {
    Path::new(&format!("/proc/{pid}")).exists()
}

/// The status as a reader should see it: a `running` status whose process is gone from this
/// host becomes `killed` (the supervisor died without writing a final state, e.g. SIGKILL).
pub fn read_effective(run_dir: &Path) -> Result<Option<Status>, String> {
    let mut s = read(run_dir)?;
    if let Some(st) = s.as_mut() {
        if st.state == State::Running {
            if let Some(at) = &st.at {
                if at.host == hostname() && !process_alive(at.pid) {
                    st.state = State::Killed;
                    st.error = Some(format!(
                        "the run's process (pid {}) is gone without recording an end (killed with SIGKILL?)",
                        at.pid
                    ));
                }
            }
        }
    }
    Ok(s)
}

/// Write status.json atomically.
pub fn write(run_dir: &Path, s: &Status) -> Result<(), String> {
    std::fs::create_dir_all(run_dir)
        .map_err(|e| format!("cannot create {}: {e}", run_dir.display()))?;
    let p = status_path(run_dir);
    let tmp = run_dir.join(format!(".status.json.{}.tmp", std::process::id()));
    let text = serde_json::to_string_pretty(s).map_err(|e| e.to_string())? + "\n";
    std::fs::write(&tmp, text).map_err(|e| format!("cannot write {}: {e}", tmp.display()))?;
    std::fs::rename(&tmp, &p).map_err(|e| format!("cannot write {}: {e}", p.display()))
}
