//! `tread sweep run --backend slurm`: the sweep as a Slurm job array.
//!
//! Files in `<sweep>/slurm/`:
//! * `array.sbatch` — the array job: `#SBATCH --array=<tasks>[%K]`; task `t` runs
//!   `tread sweep run-one SPEC --index i` for the `pack` runs `i = t·pack … t·pack + pack − 1`
//!   (one by default), with `--threads $SLURM_CPUS_PER_TASK`. A sweep needing more array
//!   tasks than the site's `MaxArraySize` (indices `0 … MaxArraySize − 1`; 1001 by default) is
//!   split into `array_000.sbatch`, `array_001.sbatch`, …, each adding its task offset; with a
//!   throttle each part waits for the previous one (`afterany`), so at most K tasks run at once.
//!   Only tasks with a run not yet done are listed, so resubmitting resumes a sweep.
//! * `collect.sbatch` — `tread sweep collect`, submitted with `--dependency=afterany:<array
//!   jobs>`: `afterany` (not `afterok`) so that it runs even when some runs failed (with
//!   `afterok` one failed point would leave it pending forever).
//! * `logs/` — the jobs' stdout/stderr (`%x-%A_%a.out`); each run's own logs are in its run
//!   folder.
//! * `jobs.json` — the submitted job ids.
//!
//! Submission uses `sbatch --parsable`; then `tread` polls `squeue` itself (`sbatch --wait`
//! reports late) and shows progress from the run folders, the source of truth, until the array
//! and collect jobs have left the queue. Ctrl-C stops the polling only (the jobs keep running;
//! the command to cancel them is printed). `--dry-run` writes the scripts without submitting.
//!
//! Resources per array task (spec `[slurm]`, each overridden on the command line):
//! `partition`, `time` (Slurm's formats `MM`, `MM:SS`, `HH:MM:SS`, `D-HH`, `D-HH:MM`,
//! `D-HH:MM:SS`), `cpus_per_task`, `mem` (`4096`, `4G`, …), `throttle`, `pack`,
//! `max_array_size`, `extra` (more `#SBATCH` options, verbatim).

use super::local::{mark_queued, pending};
use super::signal;
use super::spec::{SlurmSpec, Spec};
use super::status::{self, State};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

/// The default `MaxArraySize` of Slurm.
pub const DEFAULT_MAX_ARRAY_SIZE: usize = 1001;

pub use super::spec::check_resources;
#[cfg(test)]
use super::spec::{valid_mem, valid_time};

/// Resolved resources and layout of the array.
#[derive(Clone, Debug, PartialEq)]
pub struct Resources {
    pub partition: Option<String>,
    pub time: Option<String>,
    pub cpus_per_task: usize,
    pub mem: Option<String>,
    pub throttle: Option<usize>,
    pub pack: usize,
    pub extra: Vec<String>,
}

impl Resources {
    /// The spec's values with the command line's on top.
    pub fn resolve(spec: &SlurmSpec, cli: &SlurmSpec) -> Resources {
        Resources {
            partition: cli.partition.clone().or_else(|| spec.partition.clone()),
            time: cli.time.clone().or_else(|| spec.time.clone()),
            cpus_per_task: cli.cpus_per_task.or(spec.cpus_per_task).unwrap_or(1),
            mem: cli.mem.clone().or_else(|| spec.mem.clone()),
            throttle: cli.throttle.or(spec.throttle),
            pack: cli.pack.or(spec.pack).unwrap_or(1).max(1),
            extra: spec.extra.iter().chain(&cli.extra).cloned().collect(),
        }
    }
}

/// One array job: its task ids (relative to `offset`, all below `MaxArraySize`).
#[derive(Clone, Debug, PartialEq)]
pub struct ArrayPart {
    /// Absolute task number of this part's task id 0.
    pub offset: usize,
    pub task_ids: Vec<usize>,
}

impl ArrayPart {
    /// The `--array` value: ranges of task ids, then `%K`.
    pub fn array_spec(&self, throttle: Option<usize>) -> String {
        let mut s = String::new();
        let ids = &self.task_ids;
        let mut k = 0;
        while k < ids.len() {
            let mut j = k;
            while j + 1 < ids.len() && ids[j + 1] == ids[j] + 1 {
                j += 1;
            }
            if !s.is_empty() {
                s.push(',');
            }
            if j == k {
                s.push_str(&ids[k].to_string());
            } else {
                s.push_str(&format!("{}-{}", ids[k], ids[j]));
            }
            k = j + 1;
        }
        if let Some(t) = throttle {
            s.push_str(&format!("%{t}"));
        }
        s
    }
}

/// Array tasks for the pending runs: task `t` holds runs `t·pack …`; parts of at most
/// `max_array_size` task ids.
pub fn layout(pending: &[usize], pack: usize, max_array_size: usize) -> Vec<ArrayPart> {
    let pack = pack.max(1);
    let max = max_array_size.max(1);
    let mut tasks: Vec<usize> = pending.iter().map(|r| r / pack).collect();
    tasks.dedup();
    let mut parts: Vec<ArrayPart> = Vec::new();
    for t in tasks {
        let offset = (t / max) * max;
        match parts.last_mut() {
            Some(p) if p.offset == offset => p.task_ids.push(t - offset),
            _ => parts.push(ArrayPart {
                offset,
                task_ids: vec![t - offset],
            }),
        }
    }
    parts
}

/// What the scripts need to know.
#[derive(Clone, Debug)]
pub struct ScriptContext {
    pub name: String,
    pub exe: PathBuf,
    pub spec: PathBuf,
    pub root: PathBuf,
    pub n_runs: usize,
    pub resources: Resources,
}

/// Single-quote for bash.
fn sh(p: &Path) -> String {
    format!("'{}'", p.display().to_string().replace('\'', r"'\''"))
}

fn resource_lines(r: &Resources, with_mem: bool) -> String {
    let mut s = String::new();
    if let Some(p) = &r.partition {
        s.push_str(&format!("#SBATCH --partition={p}\n"));
    }
    s + &[
        r.time.as_ref().map(|t| format!("#SBATCH --time={t}\n")),
        Some(format!("#SBATCH --cpus-per-task={}\n", r.cpus_per_task)),
        r.mem
            .as_ref()
            .filter(|_| with_mem)
            .map(|m| format!("#SBATCH --mem={m}\n")),
    ]
    .into_iter()
    .flatten()
    .collect::<String>()
        + &r.extra
            .iter()
            .map(|x| format!("#SBATCH {x}\n"))
            .collect::<String>()
}

/// File name of part `k` of `n`.
pub fn array_file(k: usize, n: usize) -> String {
    if n == 1 {
        "array.sbatch".into()
    } else {
        format!("array_{k:03}.sbatch")
    }
}

/// The array job script of one part.
pub fn render_array(ctx: &ScriptContext, part: &ArrayPart, k: usize, n_parts: usize) -> String {
    let r = &ctx.resources;
    let first_run = (part.offset + part.task_ids.first().copied().unwrap_or(0)) * r.pack;
    let last_run = ((part.offset + part.task_ids.last().copied().unwrap_or(0)) * r.pack + r.pack)
        .min(ctx.n_runs)
        .saturating_sub(1);
    let logs = ctx.root.join("slurm").join("logs");
    format!(
        r#"#!/bin/bash
# tread sweep `{name}`: Slurm job array, part {part_no} of {n_parts}.
# {n_tasks} array task(s), {pack} run(s) each, for runs {first_run}..{last_run} of {n_runs}; each run writes
# {root}/runs/NNNN/. Written by `tread sweep run --backend slurm`; submitting it again is
# safe: runs already done are skipped.
#SBATCH --job-name=tread-{name}
#SBATCH --array={array}
{resources}#SBATCH --output={logs}/%x-%A_%a.out

TREAD={exe}
SPEC={spec}
SWEEP={root_q}
PACK={pack}
OFFSET={offset}
N_RUNS={n_runs}

# Slurm sends SIGTERM at the time limit and on scancel: run-one records the run as killed;
# no further run of this task starts.
STOP=0
trap 'STOP=1' TERM
FIRST=$(( (SLURM_ARRAY_TASK_ID + OFFSET) * PACK ))
LAST=$(( FIRST + PACK - 1 ))
if [ "$LAST" -ge "$N_RUNS" ]; then LAST=$(( N_RUNS - 1 )); fi
STATUS=0
for (( i = FIRST; i <= LAST && STOP == 0; i++ )); do
    "$TREAD" --threads "${{SLURM_CPUS_PER_TASK:-1}}" sweep run-one "$SPEC" --out "$SWEEP" --index "$i" || STATUS=$?
done
exit "$STATUS"
"#,
        name = ctx.name,
        part_no = k + 1,
        n_tasks = part.task_ids.len(),
        n_runs = ctx.n_runs,
        pack = r.pack,
        root = ctx.root.display(),
        array = part.array_spec(r.throttle),
        resources = resource_lines(r, true),
        logs = logs.display(),
        exe = sh(&ctx.exe),
        spec = sh(&ctx.spec),
        root_q = sh(&ctx.root),
        offset = part.offset,
    )
}

/// The collect job script (submitted with `--dependency=afterany:<array jobs>`).
pub fn render_collect(ctx: &ScriptContext) -> String {
    let mut r = ctx.resources.clone();
    r.cpus_per_task = 1;
    r.time = Some("00:10:00".into());
    let logs = ctx.root.join("slurm").join("logs");
    format!(
        r#"#!/bin/bash
# tread sweep `{name}`: collect the table ({root}/results.csv) and the plots.
# Submitted with --dependency=afterany:<array job ids>: afterany, so that it also runs when
# some runs failed or were cancelled (with afterok it would stay pending forever).
#SBATCH --job-name=tread-{name}-collect
{resources}#SBATCH --output={logs}/%x-%j.out

exec {exe} sweep collect {spec} --out {root_q}
"#,
        name = ctx.name,
        root = ctx.root.display(),
        resources = resource_lines(&r, false),
        logs = logs.display(),
        exe = sh(&ctx.exe),
        spec = sh(&ctx.spec),
        root_q = sh(&ctx.root),
    )
}

/// Command-line options of the Slurm backend.
#[derive(Clone, Debug, Default)]
pub struct SlurmOptions {
    /// Overrides of the spec's `[slurm]`.
    pub cli: SlurmSpec,
    pub dry_run: bool,
    /// Wait for the jobs, polling squeue (otherwise return after submitting).
    pub wait: bool,
    pub poll: Duration,
    pub quiet: bool,
    pub exe: PathBuf,
}

/// What the Slurm backend did.
#[derive(Clone, Debug, Default)]
pub struct SlurmReport {
    pub scripts: Vec<PathBuf>,
    pub array_jobs: Vec<String>,
    pub collect_job: Option<String>,
    /// Runs submitted (not done before).
    pub submitted_runs: usize,
    /// Polling stopped by Ctrl-C (the jobs keep running).
    pub detached: bool,
    /// Runs found `running` after the jobs ended, recorded as killed.
    pub lost_runs: usize,
    pub wall_time_s: f64,
}

/// `MaxArraySize` of the cluster (`scontrol show config`), if it can be read.
pub fn site_max_array_size() -> Option<usize> {
    let out = Command::new("scontrol")
        .args(["show", "config"])
        .output()
        .ok()?;
    let text = String::from_utf8_lossy(&out.stdout);
    text.lines().find_map(|l| {
        let (k, v) = l.split_once('=')?;
        (k.trim() == "MaxArraySize")
            .then(|| v.trim().parse().ok())
            .flatten()
    })
}

fn sbatch(args: &[String]) -> Result<String, String> {
    let out = Command::new("sbatch")
        .arg("--parsable")
        .args(args)
        .output()
        .map_err(|e| format!("cannot run sbatch: {e} (is Slurm installed and on PATH?)"))?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    if !out.status.success() {
        return Err(format!(
            "sbatch {} failed ({}): {}",
            args.join(" "),
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    // `--parsable`: "jobid" or "jobid;cluster".
    let id = stdout.trim().split(';').next().unwrap_or("").to_string();
    if id.is_empty() || !id.chars().all(|c| c.is_ascii_digit()) {
        return Err(format!("sbatch gave no job id: `{}`", stdout.trim()));
    }
    Ok(id)
}

/// Jobs among `ids` still in the queue (any state but ended), from `squeue`.
pub fn queued_jobs(ids: &[String]) -> Result<usize, String> {
    let out = Command::new("squeue")
        .args(["-h", "-o", "%i %T", "-j", &ids.join(",")])
        .output()
        .map_err(|e| format!("cannot run squeue: {e}"))?;
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        // Jobs purged from the controller are "invalid": they have ended.
        if stderr.contains("Invalid job id") {
            return Ok(0);
        }
        return Err(format!("squeue failed ({}): {}", out.status, stderr.trim()));
    }
    Ok(String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter(|l| !l.trim().is_empty())
        .count())
}

/// Count the ended runs (done, failed, killed) from the run folders.
fn ended_runs(spec: &Spec, root: &Path) -> (usize, usize) {
    let mut ended = 0;
    let mut failed = 0;
    for i in 0..spec.n_runs() {
        let dir = super::run_one::run_dir(spec, root, i);
        if let Ok(Some(s)) = status::read_effective(&dir) {
            if s.state.is_final() && s.fingerprint == spec.run_fingerprint(&spec.run(i)) {
                ended += 1;
                if s.state != State::Done {
                    failed += 1;
                }
            }
        }
    }
    (ended, failed)
}

/// After the jobs have left the queue: a run still `running` lost its process without
/// recording an end (SIGKILL after the time limit's grace, a node failure); record it as killed.
/// Returns how many were marked.
pub fn mark_lost_runs(spec: &Spec, root: &Path) -> usize {
    let mut n = 0;
    for i in 0..spec.n_runs() {
        let dir = super::run_one::run_dir(spec, root, i);
        if let Ok(Some(mut s)) = status::read(&dir) {
            if s.state == State::Running {
                s.state = State::Killed;
                s.error = Some(
                    "its Slurm job ended without the run recording an end (killed with SIGKILL, e.g. after the time limit's grace, or a node failure; see slurm/logs/)"
                        .into(),
                );
                s.finished_at.get_or_insert_with(status::now);
                if status::write(&dir, &s).is_ok() {
                    n += 1;
                }
            }
        }
    }
    n
}

/// Write the scripts and (unless dry run) submit and poll.
pub fn run_slurm(spec: &Spec, root: &Path, opts: &SlurmOptions) -> Result<SlurmReport, String> {
    let t0 = Instant::now();
    let resources = Resources::resolve(&spec.slurm, &opts.cli);
    let errs = check_resources(&opts.cli);
    if !errs.is_empty() {
        return Err(errs
            .join("\n")
            .replace("key `slurm.", "option `--")
            .replace("cpus_per_task", "cpus-per-task")
            .replace("max_array_size", "max-array-size"));
    }
    let max_array_size = opts
        .cli
        .max_array_size
        .or(spec.slurm.max_array_size)
        .or_else(|| {
            if opts.dry_run {
                None
            } else {
                site_max_array_size()
            }
        })
        .unwrap_or(DEFAULT_MAX_ARRAY_SIZE);
    let todo = pending(spec, root);
    let parts = layout(&todo, resources.pack, max_array_size);
    let slurm_dir = root.join("slurm");
    let logs = slurm_dir.join("logs");
    std::fs::create_dir_all(&logs).map_err(|e| format!("cannot create {}: {e}", logs.display()))?;
    let ctx = ScriptContext {
        name: spec.name.clone(),
        exe: opts.exe.clone(),
        spec: spec.path.clone(),
        root: std::path::absolute(root).map_err(|e| e.to_string())?,
        n_runs: spec.n_runs(),
        resources: resources.clone(),
    };
    let mut report = SlurmReport {
        submitted_runs: todo.len(),
        ..Default::default()
    };
    // Scripts of an earlier submission would be confusing next to the new ones.
    if let Ok(entries) = std::fs::read_dir(&slurm_dir) {
        for e in entries.flatten() {
            let n = e.file_name().to_string_lossy().to_string();
            if n.starts_with("array") && n.ends_with(".sbatch") {
                let _ = std::fs::remove_file(e.path());
            }
        }
    }
    let write = |name: &str, text: &str| -> Result<PathBuf, String> {
        let p = slurm_dir.join(name);
        std::fs::write(&p, text).map_err(|e| format!("cannot write {}: {e}", p.display()))?;
        Ok(p)
    };
    for (k, part) in parts.iter().enumerate() {
        let name = array_file(k, parts.len());
        report
            .scripts
            .push(write(&name, &render_array(&ctx, part, k, parts.len()))?);
    }
    let collect_script = write("collect.sbatch", &render_collect(&ctx))?;
    report.scripts.push(collect_script.clone());
    if opts.dry_run || todo.is_empty() {
        report.wall_time_s = t0.elapsed().as_secs_f64();
        return Ok(report);
    }

    mark_queued(spec, root, &todo, Some("slurm"))?;
    let mut prev: Option<String> = None;
    for script in &report.scripts[..parts.len()] {
        let mut args = Vec::new();
        if let (Some(p), Some(_)) = (&prev, resources.throttle) {
            args.push(format!("--dependency=afterany:{p}"));
        }
        args.push(script.display().to_string());
        let id = sbatch(&args).map_err(|e| {
            if report.array_jobs.is_empty() {
                e
            } else {
                format!(
                    "{e}\n(already submitted: {}; `scancel {}` cancels them)",
                    report.array_jobs.join(", "),
                    report.array_jobs.join(" ")
                )
            }
        })?;
        prev = Some(id.clone());
        report.array_jobs.push(id);
    }
    let dep = format!("--dependency=afterany:{}", report.array_jobs.join(":"));
    let cid = sbatch(&[dep, collect_script.display().to_string()]).map_err(|e| {
        format!(
            "{e}\n(the array job(s) {} are submitted; run `tread sweep collect` when they end)",
            report.array_jobs.join(", ")
        )
    })?;
    report.collect_job = Some(cid.clone());
    let jobs = serde_json::json!({
        "array_jobs": report.array_jobs,
        "collect_job": cid,
        "submitted_at": status::now(),
        "runs": todo.len(),
        "scripts": report.scripts.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
    });
    let _ = std::fs::write(
        slurm_dir.join("jobs.json"),
        serde_json::to_string_pretty(&jobs).unwrap_or_default() + "\n",
    );
    if !opts.wait {
        report.wall_time_s = t0.elapsed().as_secs_f64();
        return Ok(report);
    }

    // Poll.
    signal::install();
    let n = spec.n_runs();
    let pb = if opts.quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::with_draw_target(Some(n as u64), ProgressDrawTarget::stderr())
    };
    pb.set_style(
        ProgressStyle::with_template(
            "{prefix} [{bar:30}] {pos}/{len} runs ended  {msg}  elapsed {elapsed}, ETA {eta}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    pb.set_prefix(spec.name.clone());
    let mut all: Vec<String> = report.array_jobs.clone();
    all.push(cid);
    let mut errors = 0;
    loop {
        let (ended, failed) = ended_runs(spec, root);
        pb.set_position(ended as u64);
        pb.set_message(if failed > 0 {
            format!("({failed} failed or killed)")
        } else {
            String::new()
        });
        match queued_jobs(&all) {
            Ok(0) => break,
            Ok(_) => errors = 0,
            Err(e) => {
                errors += 1;
                if errors >= 5 {
                    pb.finish_and_clear();
                    return Err(format!("{e} (5 times in a row; the jobs may still run)"));
                }
            }
        }
        let until = Instant::now() + opts.poll;
        while Instant::now() < until && signal::received().is_none() {
            std::thread::sleep(Duration::from_millis(50));
        }
        if signal::received().is_some() {
            report.detached = true;
            break;
        }
    }
    pb.finish_and_clear();
    if !report.detached {
        report.lost_runs = mark_lost_runs(spec, root);
    }
    report.wall_time_s = t0.elapsed().as_secs_f64();
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_splits_above_max_array_size_and_packs() {
        let all: Vec<usize> = (0..2500).collect();
        let p = layout(&all, 1, 1001);
        assert_eq!(p.len(), 3);
        assert_eq!((p[0].offset, p[0].task_ids.len()), (0, 1001));
        assert_eq!((p[1].offset, p[1].task_ids.len()), (1001, 1001));
        assert_eq!((p[2].offset, p[2].task_ids.len()), (2002, 498));
        assert_eq!(p[2].array_spec(Some(8)), "0-497%8");
        let p = layout(&all, 3, 1001);
        assert_eq!(p.len(), 1);
        assert_eq!(p[0].array_spec(None), "0-833");
        // Resuming: only tasks with a pending run.
        let p = layout(&[1, 2, 3, 7, 12, 13], 2, 1001);
        assert_eq!(p[0].array_spec(Some(2)), "0-1,3,6%2");
    }

    #[test]
    fn times_and_memory() {
        for t in ["30", "30:00", "01:30:00", "2-00", "2-12:00", "1-00:00:00"] {
            assert!(valid_time(t), "{t}");
        }
        for t in ["", "1h", "1:2:3:4", "x-01", "-1", "10:"] {
            assert!(!valid_time(t), "{t}");
        }
        for m in ["4096", "4G", "512M", "1t"] {
            assert!(valid_mem(m), "{m}");
        }
        for m in ["", "G", "4GB", "1.5G", "-1"] {
            assert!(!valid_mem(m), "{m}");
        }
    }

    #[test]
    fn runs_left_running_after_the_jobs_ended_are_recorded_killed() {
        let dir = std::env::temp_dir().join(format!("tread-slurm-lost-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("base.toml"), "[scene]\nname = \"x\"\n").unwrap();
        let spec = Spec::from_toml_str(
            "[sweep]\nname = \"t\"\nscene = \"base.toml\"\n[[axis]]\nkey = \"a.b\"\nvalues = [1, 2, 3]\n",
            &dir.join("spec.toml"),
        )
        .unwrap();
        let root = dir.join("out");
        let states = [State::Running, State::Done, State::Queued];
        for (i, st) in states.iter().enumerate() {
            let run = spec.run(i);
            let s = status::Status::new(i, *st, spec.overrides(&run), spec.run_fingerprint(&run));
            status::write(&super::super::run_one::run_dir(&spec, &root, i), &s).unwrap();
        }
        assert_eq!(mark_lost_runs(&spec, &root), 1);
        let read = |i| {
            status::read(&super::super::run_one::run_dir(&spec, &root, i))
                .unwrap()
                .unwrap()
        };
        assert_eq!(read(0).state, State::Killed);
        assert!(read(0).error.unwrap().contains("SIGKILL"));
        assert_eq!(read(1).state, State::Done);
        assert_eq!(read(2).state, State::Queued, "never started: stays queued");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
