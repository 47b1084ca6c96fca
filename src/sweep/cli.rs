//! The `tread sweep` subcommands (parsed by clap in `main.rs`, run here).

use super::collect::{self, render_status};
use super::local::{self, LocalOptions};
use super::plan;
use super::run_one::{self, Outcome, RunOneOptions};
use super::slurm::{self, SlurmOptions};
use super::spec::{SlurmSpec, Spec};
use clap::{Args, Subcommand, ValueEnum};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

#[derive(Subcommand, Debug)]
pub enum SweepCommand {
    /// Print the runs of a sweep spec as a table and check every run's scene (nothing runs).
    Plan {
        /// Sweep spec (TOML), see docs/sweeps.md.
        spec: PathBuf,
    },
    /// Run every run of the sweep that is not done yet, on a backend, then collect.
    Run(RunArgs),
    /// Run one run of the sweep (what every backend calls): writes <out>/runs/NNNN/.
    RunOne {
        spec: PathBuf,
        /// Run index (0-based, as in `tread sweep plan`).
        #[arg(long)]
        index: usize,
        /// Sweep folder (default: out/<sweep name>/).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Seconds a signalled run may take to stop before it is killed.
        #[arg(long, default_value_t = 10.0)]
        grace: f64,
    },
    /// Show the state of every run, from the run folders.
    Status {
        spec: PathBuf,
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Write the table (results.csv) and the plots from the run folders.
    Collect {
        spec: PathBuf,
        #[arg(long)]
        out: Option<PathBuf>,
    },
}

#[derive(Copy, Clone, Debug, PartialEq, Eq, ValueEnum)]
pub enum Backend {
    /// A process pool on this machine.
    Local,
    /// A Slurm job array (sbatch).
    Slurm,
}

#[derive(Args, Debug)]
pub struct RunArgs {
    spec: PathBuf,
    #[arg(long, value_enum, default_value_t = Backend::Local)]
    backend: Backend,
    /// Sweep folder (default: out/<sweep name>/).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Local backend: runs at once (default: the number of cores; each run then gets
    /// cores / jobs threads unless --threads is given).
    #[arg(short, long)]
    jobs: Option<usize>,
    /// Slurm: partition.
    #[arg(long)]
    partition: Option<String>,
    /// Slurm: time limit per array task (e.g. 00:30:00).
    #[arg(long)]
    time: Option<String>,
    /// Slurm: CPUs per task (= threads of each run).
    #[arg(long = "cpus-per-task", alias = "cpus")]
    cpus_per_task: Option<usize>,
    /// Slurm: memory per task (e.g. 2G).
    #[arg(long)]
    mem: Option<String>,
    /// Slurm: at most K array tasks at once (--array=…%K).
    #[arg(long)]
    throttle: Option<usize>,
    /// Slurm: runs per array task.
    #[arg(long)]
    pack: Option<usize>,
    /// Slurm: the site's MaxArraySize (default: from `scontrol show config`, else 1001).
    #[arg(long)]
    max_array_size: Option<usize>,
    /// Slurm: a further sbatch option for both scripts, e.g. --sbatch=--account=proj (repeatable).
    #[arg(long = "sbatch", value_name = "OPTION", allow_hyphen_values = true)]
    sbatch: Vec<String>,
    /// Slurm: write the scripts, do not submit.
    #[arg(long)]
    dry_run: bool,
    /// Slurm: return after submitting instead of polling until the jobs end.
    #[arg(long)]
    no_wait: bool,
    /// Slurm: seconds between two squeue polls.
    #[arg(long, default_value_t = 2.0)]
    poll: f64,
}

fn exe() -> Result<PathBuf, String> {
    std::env::current_exe().map_err(|e| format!("cannot find the tread executable: {e}"))
}

fn load(path: &Path) -> Result<Spec, ExitCode> {
    Spec::load(path).map_err(|e| {
        eprintln!("tread: invalid sweep spec:\n{e}");
        ExitCode::from(2)
    })
}

fn root_of(spec: &Spec, out: Option<PathBuf>) -> Result<PathBuf, ExitCode> {
    let r = out.unwrap_or_else(|| Path::new("out").join(&spec.name));
    std::path::absolute(&r).map_err(|e| {
        eprintln!("tread: cannot resolve {}: {e}", r.display());
        ExitCode::from(2)
    })
}

fn check_plan(spec: &Spec) -> Result<(), ExitCode> {
    plan::check(spec).map_err(|errs| {
        eprintln!(
            "tread: the sweep `{}` has invalid runs ({} problem(s)); nothing was run:\n{}",
            spec.name,
            errs.len(),
            plan::render_errors(spec, &errs).trim_end()
        );
        ExitCode::from(2)
    })
}

/// Run a `tread sweep` subcommand. `threads` is the global `--threads`.
pub fn main(cmd: SweepCommand, threads: Option<usize>, quiet: bool) -> ExitCode {
    match run(cmd, threads, quiet) {
        Ok(c) | Err(c) => c,
    }
}

fn run(cmd: SweepCommand, threads: Option<usize>, quiet: bool) -> Result<ExitCode, ExitCode> {
    match cmd {
        SweepCommand::Plan { spec } => {
            let s = load(&spec)?;
            let t0 = std::time::Instant::now();
            print!("{}", plan::render_table(&s));
            check_plan(&s)?;
            println!(
                "# sweep `{}`: {} runs, every scene valid (checked in {:.3} s)",
                s.name,
                s.n_runs(),
                t0.elapsed().as_secs_f64()
            );
            Ok(ExitCode::SUCCESS)
        }
        SweepCommand::RunOne {
            spec,
            index,
            out,
            grace,
        } => {
            let s = load(&spec)?;
            let root = root_of(&s, out)?;
            let opts = RunOneOptions {
                threads,
                grace: Duration::from_secs_f64(grace.max(0.0)),
                exe: exe().map_err(|e| {
                    eprintln!("tread: {e}");
                    ExitCode::from(3)
                })?,
            };
            match run_one::run_one(&s, &root, index, &opts) {
                Ok(o) => {
                    let name = s.run_name(index);
                    match &o {
                        Outcome::Skipped => {
                            if !quiet {
                                eprintln!("tread: run {name} is already done: skipped")
                            }
                        }
                        Outcome::Done => {
                            if !quiet {
                                eprintln!("tread: run {name} done")
                            }
                        }
                        Outcome::Failed(e) => eprintln!("tread: run {name} failed: {e}"),
                        Outcome::Killed(e) => eprintln!("tread: run {name} killed: {e}"),
                    }
                    Ok(ExitCode::from(o.exit_code()))
                }
                Err(e) => {
                    eprintln!("tread: {e}");
                    Err(ExitCode::from(2))
                }
            }
        }
        SweepCommand::Status { spec, out } => {
            let s = load(&spec)?;
            let root = root_of(&s, out)?;
            let t = collect::gather(&s, &root);
            print!("{}", render_status(&s, &t));
            for w in &t.warnings {
                eprintln!("tread: warning: {w}");
            }
            Ok(ExitCode::SUCCESS)
        }
        SweepCommand::Collect { spec, out } => {
            let s = load(&spec)?;
            let root = root_of(&s, out)?;
            collect_and_report(&s, &root)?;
            Ok(ExitCode::SUCCESS)
        }
        SweepCommand::Run(a) => run_sweep(a, threads, quiet),
    }
}

fn collect_and_report(s: &Spec, root: &Path) -> Result<collect::Table, ExitCode> {
    let c = collect::collect(s, root).map_err(|e| {
        eprintln!("tread: {e}");
        ExitCode::from(3)
    })?;
    print!("{}", render_status(s, &c.table));
    println!("table: {}", c.csv.display());
    for p in &c.plots {
        println!("plot: {}", p.display());
    }
    for p in &c.problems {
        eprintln!("tread: warning: {p}");
    }
    Ok(c.table)
}

fn run_sweep(a: RunArgs, threads: Option<usize>, quiet: bool) -> Result<ExitCode, ExitCode> {
    let s = load(&a.spec)?;
    let root = root_of(&s, a.out.clone())?;
    check_plan(&s)?;
    let exe = exe().map_err(|e| {
        eprintln!("tread: {e}");
        ExitCode::from(3)
    })?;
    let final_code = |t: &collect::Table| {
        if t.count("done") == t.rows.len() {
            ExitCode::SUCCESS
        } else {
            ExitCode::from(1)
        }
    };
    match a.backend {
        Backend::Local => {
            let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
            let jobs = a.jobs.unwrap_or(cores).max(1);
            let threads = threads.or(Some(local::default_threads(jobs)));
            if !quiet {
                eprintln!(
                    "tread: sweep `{}`: {} runs, {jobs} at once, {} thread(s) each, in {}",
                    s.name,
                    s.n_runs(),
                    threads.unwrap_or(1),
                    root.display()
                );
            }
            let r = local::run_local(
                &s,
                &root,
                &LocalOptions {
                    jobs,
                    threads,
                    quiet,
                    exe,
                },
            )
            .map_err(|e| {
                eprintln!("tread: {e}");
                ExitCode::from(3)
            })?;
            let t = collect_and_report(&s, &root)?;
            if !quiet {
                eprintln!(
                    "tread: {} run(s) started, {} already done, {:.1} s",
                    r.started, r.skipped, r.wall_time_s
                );
            }
            if r.interrupted {
                eprintln!("tread: interrupted; {}", local::resume_hint(&s));
                return Ok(ExitCode::from(130));
            }
            Ok(final_code(&t))
        }
        Backend::Slurm => {
            let cli = SlurmSpec {
                partition: a.partition,
                time: a.time,
                cpus_per_task: a.cpus_per_task,
                mem: a.mem,
                throttle: a.throttle,
                pack: a.pack,
                max_array_size: a.max_array_size,
                extra: a.sbatch,
            };
            let opts = SlurmOptions {
                cli,
                dry_run: a.dry_run,
                wait: !a.no_wait,
                poll: Duration::from_secs_f64(a.poll.clamp(0.1, 600.0)),
                quiet,
                exe,
            };
            let r = slurm::run_slurm(&s, &root, &opts).map_err(|e| {
                eprintln!("tread: {e}");
                ExitCode::from(3)
            })?;
            for p in &r.scripts {
                println!("script: {}", p.display());
            }
            if a.dry_run {
                println!(
                    "dry run: {} run(s) to submit; nothing submitted (sbatch --parsable {} …)",
                    r.submitted_runs,
                    r.scripts
                        .first()
                        .map_or(String::new(), |p| p.display().to_string())
                );
                return Ok(ExitCode::SUCCESS);
            }
            if r.array_jobs.is_empty() {
                println!("every run is done already: nothing submitted");
                let t = collect_and_report(&s, &root)?;
                return Ok(final_code(&t));
            }
            println!(
                "submitted {} run(s): array job(s) {}, collect job {}",
                r.submitted_runs,
                r.array_jobs.join(", "),
                r.collect_job.as_deref().unwrap_or("-")
            );
            if !opts.wait || r.detached {
                let mut ids = r.array_jobs.clone();
                ids.extend(r.collect_job.clone());
                println!(
                    "the jobs run on their own: `tread sweep status {}` shows progress, `scancel {}` cancels",
                    s.path.display(),
                    ids.join(" ")
                );
                return Ok(if r.detached {
                    ExitCode::from(130)
                } else {
                    ExitCode::SUCCESS
                });
            }
            // The collect job has written the table; report from the folders. Collect here
            // when it did not, or when runs lost their process (their table row changed).
            let csv = root.join("results.csv");
            if r.lost_runs > 0 || !csv.exists() {
                if r.lost_runs > 0 {
                    eprintln!(
                        "tread: {} run(s) were still marked running after their jobs ended: recorded as killed",
                        r.lost_runs
                    );
                } else {
                    eprintln!(
                        "tread: warning: the collect job wrote no table (see {}); collecting here",
                        root.join("slurm").join("logs").display()
                    );
                }
                let t = collect_and_report(&s, &root)?;
                return Ok(final_code(&t));
            }
            let t = collect::gather(&s, &root);
            print!("{}", render_status(&s, &t));
            println!("table: {}", csv.display());
            Ok(final_code(&t))
        }
    }
}
