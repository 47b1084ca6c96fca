//! Parameter sweeps: many independent runs of one scene with a few keys changed, on this
//! machine (a process pool) or on a Slurm cluster (a job array).
//!
//! * [`spec`] — the sweep spec (TOML): base scene, axes (lists, linear and geometric ranges,
//!   zipped keys; their product is the set of runs), outputs kept, plots, Slurm resources;
//! * [`plan`] — `tread sweep plan`: the table of runs and the check of every run's scene by
//!   the scene loader, all problems at once;
//! * [`run_one`] — `tread sweep run-one SPEC --index N`, the one entry point of every backend:
//!   it runs `tread run` with the run's overrides into `<sweep>/runs/NNNN/` and records the
//!   outcome in `status.json` ([`status`]); a done run is skipped, so sweeps resume;
//! * [`local`] — `--backend local`, a bounded process pool with a progress bar;
//! * [`slurm`] — `--backend slurm`, `array.sbatch` + `collect.sbatch`, submission and polling;
//! * [`collect`] — `tread sweep status` and `tread sweep collect`, from the run folders only:
//!   `results.csv` and the plots.
//!
//! The sweep folder (`--out`, default `out/<sweep name>/`):
//!
//! ```text
//! out/<name>/runs/0000/status.json    state of run 0 (queued, running, done, failed, killed)
//!            runs/0000/summary.json   … and everything `tread run` writes, stdout.log, stderr.log
//!            results.csv              the table (collect)
//!            plots/*.png              the plots (collect)
//!            slurm/array.sbatch, collect.sbatch, jobs.json, logs/   (Slurm backend)
//! ```
//!
//! Exit statuses of `tread sweep`: 0 success (every run done; `plan`: every scene valid;
//! `status`, `collect`: the folders could be read), 1 some run failed or was killed, 2 invalid
//! spec, scene or option, 3 the backend failed (e.g. `sbatch` refused the job), 130
//! interrupted (Ctrl-C or SIGTERM; `run-one` gives 128 + the signal).

pub mod cli;
pub mod collect;
pub mod local;
pub mod plan;
pub mod run_one;
pub mod signal;
pub mod slurm;
pub mod spec;
pub mod status;

pub use spec::Spec;
