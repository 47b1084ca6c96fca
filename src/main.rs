//! `tread`: command-line front end. See `tread --help` and README.md.

use clap::{Parser, Subcommand};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use tread::app::{self, RunOptions};
use tread::driver::compare::CompareTolerances;
use tread::io::output::tidy_numbers;
use tread::io::scene::model_problem::ModelScene;
use tread::io::Scene;

/// The scene run by `tread` without arguments (also `cargo run --release`): it is run in both
/// modes and compared, as `tread compare` does.
const DEFAULT_SCENE: &str = include_str!("../scenarios/oden_hollow_cylinder.toml");
const DEFAULT_SCENE_NAME: &str = "scenarios/oden_hollow_cylinder.toml (embedded)";
/// The settings of `tread` without arguments: the default scene refined to 8 × 128, the
/// coarsest of its refinement study whose hub loads are within 1 % of the 1M-DOF solution
/// (README), and its transient run to a steady state ten times tighter than the scene's
/// (`time.steady_tol` 1e-4 instead of 1e-3): at 1e-3 the transient stops while a slowly
/// decaying oscillation is still there, 0.57 % from the steady field in relative L2 against
/// 0.09 % at 1e-4, so that the comparison validates the steady solution to that level.
const MAIN_JOB_SETTINGS: [&str; 3] = ["mesh.n_r=8", "mesh.n_theta=128", "time.steady_tol=1e-4"];

#[derive(Parser, Debug)]
#[command(
    name = "tread",
    version,
    about = "Rolling-contact finite elements for a hyperelastic hollow cylinder (plane strain)",
    long_about = "Rolling-contact finite elements for a hyperelastic hollow cylinder (plane strain).\n\n\
        Without a command: the default scene (scenarios/oden_hollow_cylinder.toml on an 8 × 128 \
        mesh) runs in both modes and is compared, as `tread compare` does.",
    after_help = "Exit status: 0 success; 1 the solve failed; 2 invalid scene or arguments, or an \
        unsupported request; 3 an output could not be written; 4 (compare, and tread without a \
        command) both modes ran but the steady solution is not validated against the transient \
        (a quantity outside its tolerance, or the transient run not steady); 130 interrupted."
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// Threads for assembly (0 = all cores).
    #[arg(long, global = true)]
    threads: Option<usize>,
    /// No progress bar, minimal output.
    #[arg(short, long, global = true)]
    quiet: bool,
    /// Refuse scenes whose estimated memory exceeds this size (bytes, or e.g. 512M, 2G;
    /// default: the machine's available memory).
    #[arg(long, global = true, value_name = "SIZE")]
    max_memory: Option<String>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run a scene and write its results (summary.json, CSV) to the output directory.
    Run {
        /// Scene file (TOML), see scenarios/README.md.
        scene: PathBuf,
        /// Output directory (default: out/<scene name>/).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Override a scene key, e.g. --set mesh.n_r=8 or --set material.viscoelastic.gamma=300
        /// (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Override the analysis mode of the scene (analysis.mode).
        #[arg(long)]
        mode: Option<String>,
        /// Print the Newton convergence table of every load step.
        #[arg(short, long)]
        verbose: bool,
        /// Steady mode: write the tangent at the converged state to PATH (MatrixMarket
        /// coordinate real general) and the right-hand side -R to <stem>_rhs.mtx beside it.
        #[arg(long, value_name = "PATH")]
        dump_matrix: Option<PathBuf>,
    },
    /// Run a rolling scene in both modes (transient until steady, then steady) and compare
    /// them: OUT/summary.json `results.compare`, OUT/compare.csv, OUT/contact_compare.png
    /// (plane strain) or OUT/footprint_compare.csv (3D), with each mode's own outputs in
    /// OUT/transient/ and OUT/steady/. Each quantity is judged
    /// against its tolerance; the last line says whether the steady solution is validated
    /// against the transient, and the exit status is 4 when it is not.
    Compare {
        /// Scene file (TOML) with [time] (for the transient run), see scenarios/README.md.
        scene: PathBuf,
        /// Output directory (default: out/<scene name>_compare/).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Override a scene key, e.g. --set motion.omega=20 (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        #[arg(short, long)]
        verbose: bool,
        /// Tolerance of the hub force components, relative to |F_steady| [default: 0.01].
        #[arg(long, value_name = "REL")]
        force_tol: Option<f64>,
        /// Tolerance of the hub torque, relative to |T_steady| (to |F_steady| Ro when the
        /// torque is below 1e-3 of that) [default: 0.02].
        #[arg(long, value_name = "REL")]
        torque_tol: Option<f64>,
        /// Tolerance of the referential displacement field, relative L2 [default: 0.01].
        #[arg(long, value_name = "REL")]
        field_tol: Option<f64>,
        /// Tolerance of the contact patch ends, in surface node spacings [default: 1].
        #[arg(long, value_name = "SPACINGS")]
        contact_tol: Option<f64>,
        /// Tolerance of the peak pressure, relative to the steady peak [default: 0.05].
        #[arg(long, value_name = "REL")]
        pressure_tol: Option<f64>,
        /// Three-dimensional scenes: tolerance of the footprint's contact pressure, L2 over the
        /// tread relative to the steady one [default: 0.02].
        #[arg(long, value_name = "REL")]
        footprint_tol: Option<f64>,
        /// Three-dimensional scenes: tolerance of the footprint's tangential traction, L2 over
        /// the tread relative to the steady one [default: 0.05].
        #[arg(long, value_name = "REL")]
        traction_tol: Option<f64>,
    },
    /// Critical speeds of the steady operator (standing waves): OUT/critical.json with
    /// `omega_crit` (rad/s), `n_star` and the crossing speed of every wave number (spinning
    /// scene, or any scene with --no-contact) or the singular points along the steady branch
    /// (rolling scene), plus OUT/crossings.csv (and OUT/sweep.csv for a rolling scene).
    Critical {
        scene: PathBuf,
        /// Output directory (default: out/<scene name>_critical/).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Largest wave number (default: all the mesh resolves, n_theta / 2).
        #[arg(long)]
        n_max: Option<usize>,
        /// Smallest wave number of the spinning search (default 1).
        #[arg(long)]
        n_min: Option<usize>,
        /// Upper end of the speed search, rad/s (default: 2 × (rolling: 1.6 ×) the Rayleigh
        /// estimate 0.955 sqrt(G / rho) / Ro).
        #[arg(long)]
        omega_max: Option<f64>,
        /// Speeds sampled before the crossings are refined.
        #[arg(long, default_value_t = 48)]
        samples: usize,
        /// Ignore the scene's road: the spinning cylinder.
        #[arg(long)]
        no_contact: bool,
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        #[arg(short, long)]
        verbose: bool,
    },
    /// Adaptive static indentation or steady rolling: solve, estimate (Zienkiewicz–Zhu), mark
    /// (Dörfler), refine with hanging nodes, transfer, repeat. Writes OUT/adapt.csv and
    /// OUT/adapt.json (one row per mesh: cells, equations, hanging nodes, estimate, hub forces
    /// and torque, times) and OUT/adapt_NNN.vtu (each mesh with its `error_indicator`). The
    /// scene must be a static indentation or a steady rolling scene (`analysis.mode` "static"
    /// or "steady") on the generated annulus (its n_r × n_theta mesh is the coarsest).
    Adapt {
        scene: PathBuf,
        /// Output directory (default: out/<scene name>_adapt/).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Refinement steps after the first solve.
        #[arg(long, default_value_t = 8)]
        steps: usize,
        /// Dörfler fraction θ in (0, 1]: the marked cells carry θ of the squared estimate.
        #[arg(long, default_value_t = 0.5)]
        fraction: f64,
        /// Stop before a mesh would have more equations than this.
        #[arg(long, default_value_t = 200_000)]
        max_dofs: usize,
        /// Stop once the relative estimate (estimate / energy norm) is below this.
        #[arg(long, default_value_t = 0.0)]
        tolerance: f64,
        /// The estimator that drives the marking: "recovery" (Zienkiewicz–Zhu),
        /// "interpolation" (interpolation error with recovered derivatives), "explicit"
        /// (explicit residual with the contact traction on the contact facets) or
        /// "equilibrated" (local Neumann problems with equilibrated tractions).
        #[arg(long, default_value = "recovery")]
        estimator: tread::driver::adaptive::SolidEstimator,
        /// Coarsening fraction c >= 0: families of four cells whose squared indicators are
        /// each below c times the mean merge into their parent (0: no coarsening).
        #[arg(long, default_value_t = 0.0)]
        coarsen: f64,
        /// Uniform refinements of the scene's mesh before the first solve.
        #[arg(long, default_value_t = 0)]
        uniform: usize,
        /// How marked cells are refined: "h" (split into four), "p" (degree 1 -> 2; start
        /// from mesh.order = 1) or "hp" (degree-1 cells raised, degree-2 cells split); or "r"
        /// (moving mesh: the annulus's cell boundaries moved toward the large indicators,
        /// same cells and unknowns, --steps relocations).
        #[arg(long, default_value = "h")]
        refine: tread::driver::adaptive::Refinement,
        /// --refine r: monitor amplitude α >= 0 (cell sizes vary by at most 1 + α).
        #[arg(long, default_value_t = 4.0)]
        monitor_alpha: f64,
        /// --refine r: monitor root β >= 1 (larger spreads the refinement wider).
        #[arg(long, default_value_t = 4.0)]
        monitor_beta: f64,
        /// --refine r: uniform part γ in [0, 1] of the monitor (1: no motion).
        #[arg(long, default_value_t = 0.0)]
        monitor_gamma: f64,
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Validate a scene and print it with every default filled in.
    Check {
        scene: PathBuf,
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Print the JSON Schema (draft 2020-12) of scene files, for editors (taplo / Even Better
    /// TOML); with --markdown, the reference of scene keys, summary.json keys and CSV columns
    /// with their units (docs/reference.md).
    Schema {
        /// The Markdown reference instead of the JSON Schema.
        #[arg(long)]
        markdown: bool,
        /// Write to this file instead of standard output.
        #[arg(long, value_name = "FILE")]
        out: Option<PathBuf>,
    },
    /// Parameter sweeps: many runs of one scene (plan, run on a local pool or Slurm, collect).
    Sweep {
        #[command(subcommand)]
        command: tread::sweep::cli::SweepCommand,
    },
    /// Open a log (.rrd or .mcap) in the Rerun viewer, or convert an .mcap to .rrd (--to).
    Replay {
        /// The log: run.rrd or run.mcap from an output directory.
        log: PathBuf,
        /// Convert (MCAP to .rrd) into this file instead of opening a viewer.
        #[arg(long, value_name = "FILE")]
        to: Option<PathBuf>,
        /// Address the viewer listens on (default: the loopback address 127.0.0.1; `0.0.0.0`
        /// accepts connections from other machines).
        #[arg(long, value_name = "ADDR", default_value = "127.0.0.1")]
        bind: std::net::IpAddr,
    },
}

/// Largest scene file read (a scene is a few kB; this refuses `/dev/zero` and the like).
const MAX_SCENE_BYTES: u64 = 4 << 20;

fn load(path: &Path, set: &[String]) -> Result<Scene, String> {
    if let Some(m) = load_model(path, set) {
        let head = format!(
            "{}: a model-problem scene (it has [problem]): run it with `tread run`, check it \
             with `tread check`",
            path.display()
        );
        return Err(match m {
            Ok(_) => head,
            Err(e) => format!("{head}\n{e}"),
        });
    }
    let scene = load_checked(path, set).map_err(|e| match e {
        LoadError::Read(m) => m,
        LoadError::Scene(e) => e.to_string(),
    })?;
    preflight(path, set, &scene)?;
    Ok(scene)
}

/// [`app::preflight`] on a loaded scene: what `tread run` would refuse before its solve (the mesh
/// file, a model too large for memory, …), with the scene line of `mesh.file` (or `(--set)`) and
/// the file's resolved path for a mesh-file problem.
fn preflight(path: &Path, set: &[String], scene: &Scene) -> Result<(), String> {
    let e = match app::preflight(scene) {
        Ok(()) => return Ok(()),
        Err(e) => e,
    };
    let key = match &e {
        app::AppError::MeshFile(_) => "mesh.file",
        app::AppError::TooBig(_) => "mesh",
        _ => "",
    };
    let source = if !key.is_empty() && set.iter().any(|s| s.trim_start().starts_with(key)) {
        format!("{}:(--set)", path.display())
    } else {
        let line = std::fs::read_to_string(path)
            .ok()
            .and_then(|t| tread::io::scene::key_line(&t, key));
        match line {
            Some(l) if !key.is_empty() => format!("{}:{l}", path.display()),
            _ => path.display().to_string(),
        }
    };
    Err(format!("{source}: {e}"))
}

/// The scene, or the message of [`app::refuse_3d`] for a command that runs plane strain only.
fn refuse_3d(scene: Scene, command: &str) -> Result<Scene, String> {
    app::refuse_3d(&scene, command).map_err(|e| e.to_string())?;
    Ok(scene)
}

enum LoadError {
    Read(String),
    Scene(tread::io::scene::SceneErrors),
}

/// Load with `--mode M` (an override of `analysis.mode`). Sections and keys that the scene has
/// for its own mode and that mode M does not use (e.g. `[road]`, `[contact]`, `[friction]`,
/// `[time]` and `motion.ramp` of a rolling scene run with `--mode spinning`) are left out, and
/// a line says which. Other problems the switch causes (sections the new mode needs) are
/// labelled `(--mode M)` instead of `(--set)` and headed by one line saying what happened;
/// problems of the scene or of `--set` values keep their labels.
fn load_with_mode(path: &Path, set: &[String], mode: Option<&str>) -> Result<Scene, String> {
    let Some(m) = mode else {
        return load(path, set);
    };
    let mut all = set.to_vec();
    all.push(format!("analysis.mode=\"{m}\""));
    let mut errs = match load_checked(path, &all) {
        Ok(s) => {
            preflight(path, set, &s)?;
            return Ok(s);
        }
        Err(LoadError::Read(e)) => return Err(e),
        Err(LoadError::Scene(e)) => e,
    };
    let (own, base): (Option<String>, Vec<String>) = match load_checked(path, set) {
        Ok(s) => (Some(s.analysis.mode.to_string()), Vec::new()),
        Err(LoadError::Scene(e)) => (None, e.0.iter().map(|e| e.key.clone()).collect()),
        Err(LoadError::Read(_)) => (None, Vec::new()),
    };
    // Sections and keys the scene has for its own mode and the new one does not use are left
    // out (and said so), as long as that is all that stands in the way.
    let caused_keys: Vec<String> = errs
        .0
        .iter()
        .filter(|e| !base.contains(&e.key))
        .map(|e| e.key.clone())
        .collect();
    if !caused_keys.is_empty() && caused_keys.len() == errs.0.len() {
        if let Some((scene, dropped)) = strip_for_mode(path, &all, &caused_keys) {
            eprintln!(
                "--mode {m}: left out what analysis mode \"{m}\" does not use: {}",
                dropped.join(", ")
            );
            preflight(path, set, &scene)?;
            return Ok(scene);
        }
    }
    let mut caused = 0;
    for e in &mut errs.0 {
        if !base.contains(&e.key) {
            caused += 1;
            if e.is_override() {
                e.source_name = e.source_name.replace(":(--set)", &format!(":(--mode {m})"));
            }
        }
    }
    let head = if caused > 0 {
        format!(
            "--mode {m}: {} of the scene {}{} {} not fit analysis mode \"{m}\" (below); \
             remove or add them in a copy of the scene, or run it in its own mode:\n",
            if caused == 1 {
                "1 section or key".to_string()
            } else {
                format!("{caused} sections or keys")
            },
            path.display(),
            own.map(|o| format!(" (written for mode \"{o}\")"))
                .unwrap_or_default(),
            if caused == 1 { "does" } else { "do" },
        )
    } else {
        String::new()
    };
    Err(format!("{head}{errs}"))
}

/// The scene at `path` with the sections and keys named in `keys` removed (a key `s.k` whose
/// section the mode does not use at all, such as `friction.law` without contact, removes
/// its section), loaded with `set`; up to three rounds, each removing what the last one
/// still reported. `None` when that does not give a valid scene.
fn strip_for_mode(path: &Path, set: &[String], keys: &[String]) -> Option<(Scene, Vec<String>)> {
    let text = std::fs::read_to_string(path).ok()?;
    let mut table: toml::Table = toml::from_str(&text).ok()?;
    let mut dropped: Vec<String> = Vec::new();
    let mut keys = keys.to_vec();
    for _ in 0..3 {
        let mut progress = false;
        for k in &keys {
            let (sec, key) = match k.split_once('.') {
                Some((a, b)) => (a.to_string(), Some(b.to_string())),
                None => (k.clone(), None),
            };
            // Without contact the friction law has nothing to act on: the section goes.
            let whole = key.is_none() || (sec == "friction" && key.as_deref() == Some("law"));
            if whole {
                if table.remove(&sec).is_some() {
                    dropped.push(format!("[{sec}]"));
                    progress = true;
                }
            } else if let Some(toml::Value::Table(t)) = table.get_mut(&sec) {
                let key = key.unwrap_or_default();
                if t.remove(&key).is_some() {
                    dropped.push(format!("{sec}.{key}"));
                    progress = true;
                }
            }
        }
        if !progress {
            return None;
        }
        let stripped = toml::to_string(&table).ok()?;
        match Scene::from_toml_str(&stripped, &path.display().to_string(), set) {
            Ok(mut scene) => {
                scene.resolve_paths(path);
                return Some((scene, dropped));
            }
            Err(e) => keys = e.0.iter().map(|e| e.key.clone()).collect(),
        }
    }
    None
}

/// The text of a scene file (at most [`MAX_SCENE_BYTES`], UTF-8).
fn read_scene_text(path: &Path) -> Result<String, String> {
    use std::io::Read;
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(MAX_SCENE_BYTES + 1).read_to_end(&mut bytes))
        .map_err(|e| format!("cannot read scene {}: {e}", path.display()))?;
    if bytes.len() as u64 > MAX_SCENE_BYTES {
        return Err(format!(
            "cannot read scene {}: larger than {} MiB, not a scene file",
            path.display(),
            MAX_SCENE_BYTES >> 20
        ));
    }
    String::from_utf8(bytes)
        .map_err(|e| format!("cannot read scene {}: not UTF-8 text ({e})", path.display()))
}

/// A model-problem scene (one with `[problem]`, or `--set problem.…`), loaded and checked;
/// `None` for a rolling scene (or a file that cannot be read: the rolling loader says why).
fn load_model(path: &Path, set: &[String]) -> Option<Result<ModelScene, String>> {
    use tread::io::scene::model_problem::{is_model_problem, overrides_set_problem};
    let text = read_scene_text(path).ok()?;
    if !(is_model_problem(&text) || overrides_set_problem(set)) {
        return None;
    }
    Some(
        ModelScene::from_toml_str(&text, &path.display().to_string(), set)
            .map_err(|e| e.to_string()),
    )
}

/// Run a model-problem scene (`tread run` on a scene with `[problem]`).
fn run_model(scene: ModelScene, out: Option<PathBuf>, quiet: bool) -> ExitCode {
    let started = std::time::Instant::now();
    tread::io::record::install_interrupt_handler();
    let out_dir = out.unwrap_or_else(|| Path::new("out").join(&scene.name));
    if !quiet {
        eprintln!(
            "tread: running model problem `{}` (kind \"{}\")",
            scene.name,
            scene.problem.kind()
        );
    }
    let _lock = match tread::io::output::OutDirLock::take(&out_dir) {
        Ok(l) => {
            if l.removed > 0 && !quiet {
                eprintln!(
                    "tread: removed {} result files of an earlier run from {}",
                    l.removed,
                    out_dir.display()
                );
            }
            l
        }
        Err(msg) => {
            let e = app::AppError::OutDir(out_dir.clone(), msg);
            eprintln!("tread: error: {e}");
            return ExitCode::from(e.exit_code());
        }
    };
    let opts = RunOptions {
        out_dir,
        verbose: false,
        quiet,
    };
    match tread::driver::model_problem::run(&scene, &opts) {
        Ok(o) => {
            if !quiet {
                say(&status_line(&o.typed, started.elapsed().as_secs_f64()));
                for line in &o.headline {
                    say(line);
                }
            }
            say(&format!(
                "results written to {}",
                o.out_dir.join("summary.json").display()
            ));
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("tread: error: {}", tidy_numbers(&e.to_string()));
            ExitCode::from(e.exit_code())
        }
    }
}

fn load_checked(path: &Path, set: &[String]) -> Result<Scene, LoadError> {
    let text = read_scene_text(path).map_err(LoadError::Read)?;
    let mut scene =
        Scene::from_toml_str(&text, &path.display().to_string(), set).map_err(LoadError::Scene)?;
    // A relative mesh file is relative to the scene file.
    scene.resolve_paths(path);
    Ok(scene)
}

fn run_with(
    scene: Scene,
    out: Option<PathBuf>,
    verbose: bool,
    quiet: bool,
    compare: Option<CompareTolerances>,
    dump_matrix: Option<&Path>,
) -> ExitCode {
    let started = std::time::Instant::now();
    let out_dir = out.unwrap_or_else(|| {
        let d = app::default_out_dir(&scene);
        if compare.is_some() {
            d.with_file_name(format!("{}_compare", scene.scene.name))
        } else {
            d
        }
    });
    if !quiet {
        eprintln!(
            "tread: running scene `{}` ({} mode)",
            scene.scene.name, scene.analysis.mode
        );
    }
    tread::io::record::install_interrupt_handler();
    if let Err(e) = app::check_memory(&scene) {
        eprintln!("tread: error: {e}");
        return ExitCode::from(e.exit_code());
    }
    // The output folder first: an unwritable or busy folder is reported before the solve.
    let _lock = match tread::io::output::OutDirLock::take(&out_dir) {
        Ok(l) => {
            if l.removed > 0 && !quiet {
                eprintln!(
                    "tread: removed {} result files of an earlier run from {}",
                    l.removed,
                    out_dir.display()
                );
            }
            l
        }
        Err(msg) => {
            let e = app::AppError::OutDir(out_dir.clone(), msg);
            eprintln!("tread: error: {e}");
            return ExitCode::from(e.exit_code());
        }
    };
    let opts = RunOptions {
        out_dir,
        verbose,
        quiet,
    };
    let result = if let Some(tol) = &compare {
        if scene.mesh.dimension == 3 {
            tread::driver::compare3d::run(&scene, &opts, tol)
        } else {
            tread::driver::compare::run_with_tolerances(&scene, &opts, tol)
        }
    } else if let Some(p) = dump_matrix {
        tread::driver::steady_run::run_with_dump(&scene, &opts, Some(p))
    } else {
        app::run(&scene, &opts)
    };
    match result {
        Ok(o) => {
            if !quiet {
                if compare.is_some() {
                    say(&format!(
                        "compared the transient and steady modes: dofs = {}",
                        o.typed.dofs
                    ));
                } else {
                    say(&status_line(&o.typed, started.elapsed().as_secs_f64()));
                }
                for line in &o.headline {
                    say(line);
                }
            }
            say(&format!(
                "results written to {}",
                o.out_dir.join("summary.json").display()
            ));
            match o.typed.compare() {
                Some(c) if !c.validated => {
                    if quiet {
                        say(&c.verdict);
                    }
                    ExitCode::from(tread::driver::compare::NOT_VALIDATED_EXIT)
                }
                _ => ExitCode::SUCCESS,
            }
        }
        Err(e) => {
            eprintln!("tread: error: {}", tidy_numbers(&e.to_string()));
            ExitCode::from(e.exit_code())
        }
    }
}

/// A line on stdout. A closed or full stdout (`tread … | head`, `> /dev/full`) is not an error
/// of the run: the results are in the output directory, so the text is dropped silently.
fn say(line: &str) {
    use std::io::Write;
    let mut o = std::io::stdout().lock();
    let _ = writeln!(o, "{line}").and_then(|()| o.flush());
}

/// "converged: …" (or "finished: … steady rolling not reached") from a summary.
fn status_line(summary: &tread::driver::results::Summary, wall: f64) -> String {
    let steady_missed = summary.steady_reached() == Some(false);
    let head = if steady_missed {
        "finished (steady rolling not reached)"
    } else {
        "converged"
    };
    let mut parts = vec![format!("dofs = {}", summary.dofs)];
    let stats = summary.run_stats();
    if let Some(r) = stats {
        parts.push(format!("Newton iterations = {}", r.newton_iterations));
    }
    let wall = stats.map_or(wall, |r| r.wall_time_s);
    parts.push(format!("wall time = {wall:.3} s"));
    format!("{head}: {}", parts.join(", "))
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Some(m) = &cli.max_memory {
        match app::parse_memory(m) {
            Ok(b) => app::set_max_memory(b),
            Err(e) => {
                eprintln!("tread: error: {e}");
                return ExitCode::from(2);
            }
        }
    }
    let threads = cli.threads.unwrap_or(0);
    app::in_pool(threads, || dispatch(cli, threads))
}

fn dispatch(cli: Cli, threads: usize) -> ExitCode {
    match cli.command {
        None => match Scene::from_toml_str(
            DEFAULT_SCENE,
            DEFAULT_SCENE_NAME,
            &MAIN_JOB_SETTINGS.map(String::from),
        ) {
            Ok(scene) => {
                if !cli.quiet {
                    eprintln!(
                        "tread: the default scene on an 8 × 128 mesh, where its hub loads are within \
                         1 % of their mesh-converged values (the scene file's own 3 × 64 mesh, which \
                         `tread compare scenarios/oden_hollow_cylinder.toml` runs, is 9 % off), the \
                         transient run until it changes by less than 1e-4 per node passage \
                         (time.steady_tol; the scene's own is 1e-3)"
                    );
                }
                run_with(
                    scene,
                    None,
                    false,
                    cli.quiet,
                    Some(CompareTolerances::default()),
                    None,
                )
            }
            Err(e) => {
                eprintln!("tread: error in the embedded default scene:\n{e}");
                ExitCode::from(2)
            }
        },
        Some(Command::Run {
            scene,
            out,
            set,
            mode,
            verbose,
            dump_matrix,
        }) => match load_model(&scene, &set) {
            Some(Ok(_)) if mode.is_some() || dump_matrix.is_some() => {
                eprintln!(
                    "tread: {}: a model-problem scene (it has [problem]): --mode and --dump-matrix apply to rolling scenes only",
                    scene.display()
                );
                ExitCode::from(2)
            }
            Some(Ok(m)) => run_model(m, out, cli.quiet),
            Some(Err(e)) => {
                eprintln!("tread: invalid scene:\n{}", tidy_numbers(&e));
                ExitCode::from(2)
            }
            None => match load_with_mode(&scene, &set, mode.as_deref()) {
                Ok(s)
                    if dump_matrix.is_some()
                        && s.analysis.mode != tread::io::scene::Mode::Steady =>
                {
                    eprintln!(
                        "tread: --dump-matrix writes the steady tangent: it needs analysis mode \"steady\" (--mode steady), not \"{}\"",
                        s.analysis.mode
                    );
                    ExitCode::from(2)
                }
                Ok(s) if threads == 0 && s.solver.threads > 0 => {
                    app::in_pool(s.solver.threads, || {
                        run_with(s, out, verbose, cli.quiet, None, dump_matrix.as_deref())
                    })
                }
                Ok(s) => run_with(s, out, verbose, cli.quiet, None, dump_matrix.as_deref()),
                Err(e) => {
                    eprintln!("tread: invalid scene:\n{}", tidy_numbers(&e));
                    ExitCode::from(2)
                }
            },
        },
        Some(Command::Compare {
            scene,
            out,
            set,
            verbose,
            force_tol,
            torque_tol,
            field_tol,
            contact_tol,
            pressure_tol,
            footprint_tol,
            traction_tol,
        }) => match load(&scene, &set) {
            Ok(s) => {
                let d = CompareTolerances::default();
                let tol = CompareTolerances {
                    force: force_tol.unwrap_or(d.force),
                    torque: torque_tol.unwrap_or(d.torque),
                    field: field_tol.unwrap_or(d.field),
                    contact_spacings: contact_tol.unwrap_or(d.contact_spacings),
                    pressure: pressure_tol.unwrap_or(d.pressure),
                    footprint: footprint_tol.unwrap_or(d.footprint),
                    footprint_traction: traction_tol.unwrap_or(d.footprint_traction),
                };
                run_with(s, out, verbose, cli.quiet, Some(tol), None)
            }
            Err(e) => {
                eprintln!("tread: invalid scene:\n{e}");
                ExitCode::from(2)
            }
        },
        Some(Command::Critical {
            scene,
            out,
            n_max,
            n_min,
            omega_max,
            samples,
            no_contact,
            set,
            verbose,
        }) => match load(&scene, &set).and_then(|s| refuse_3d(s, "critical")) {
            Ok(s) => {
                let opts = tread::driver::critical::CriticalOptions {
                    n_max,
                    n_min,
                    omega_max,
                    samples,
                    no_contact,
                    verbose,
                };
                let dir = out.unwrap_or_else(|| {
                    app::default_out_dir(&s).with_file_name(format!("{}_critical", s.scene.name))
                });
                match tread::driver::critical::run(&s, &opts)
                    .and_then(|r| tread::driver::critical::write(&r, &dir).map(|()| r))
                {
                    Ok(r) => {
                        if !cli.quiet {
                            say(&tread::driver::critical::headline(&r));
                        }
                        say(&format!(
                            "results written to {}",
                            dir.join("critical.json").display()
                        ));
                        ExitCode::SUCCESS
                    }
                    Err(e) => {
                        eprintln!("tread: error: {e}");
                        ExitCode::from(e.exit_code())
                    }
                }
            }
            Err(e) => {
                eprintln!("tread: invalid scene:\n{}", tidy_numbers(&e));
                ExitCode::from(2)
            }
        },
        Some(Command::Adapt {
            scene,
            out,
            steps,
            fraction,
            max_dofs,
            tolerance,
            estimator,
            coarsen,
            uniform,
            refine,
            monitor_alpha,
            monitor_beta,
            monitor_gamma,
            set,
        }) => match load(&scene, &set).and_then(|s| refuse_3d(s, "adapt")) {
            Ok(s) => {
                use tread::driver::adaptive;
                let opts = adaptive::AdaptOptions {
                    estimator,
                    steps,
                    fraction,
                    max_dofs,
                    tolerance,
                    coarsen,
                    uniform,
                    refinement: refine,
                    monitor: tread::adapt::moving_mesh::MonitorParams {
                        alpha: monitor_alpha,
                        beta: monitor_beta,
                        gamma: monitor_gamma,
                        ..Default::default()
                    },
                };
                let dir = out.unwrap_or_else(|| {
                    app::default_out_dir(&s).with_file_name(format!("{}_adapt", s.scene.name))
                });
                let mut vtu_error = None;
                tread::io::record::install_interrupt_handler();
                let res = tread::io::output::ensure_dir(&dir)
                    .map_err(tread::app::AppError::from)
                    .and_then(|()| {
                        adaptive::run(&s, &opts, &dir, |sys, st, _| {
                            if vtu_error.is_none() {
                                vtu_error = adaptive::write_vtu(&dir, st.step, sys).err();
                            }
                            if !cli.quiet {
                                say(&format!(
                                    "  mesh {}: {} cells, {} equations, estimate {:.3e} relative, hub force y {:.9e}",
                                    st.step, st.cells, st.dofs, st.relative_estimate, st.hub_force_y
                                ));
                            }
                        })
                    })
                    .and_then(|(_, steps)| {
                        adaptive::write(&dir, &opts, &steps)?;
                        match vtu_error.take() {
                            Some(e) => Err(e.into()),
                            None => Ok(steps),
                        }
                    });
                match res {
                    Ok(steps) if tread::io::record::interrupted() => {
                        eprintln!(
                            "tread: interrupted: {} mesh(es) solved; {} holds them",
                            steps.len(),
                            dir.join("adapt.csv").display()
                        );
                        ExitCode::from(130)
                    }
                    Ok(steps) => {
                        if !cli.quiet {
                            let what = if s.analysis.mode == tread::io::scene::Mode::Steady {
                                "adaptive steady rolling"
                            } else {
                                "adaptive indentation"
                            };
                            say(&adaptive::headline(what, &steps));
                        }
                        say(&format!(
                            "results written to {}",
                            dir.join("adapt.csv").display()
                        ));
                        ExitCode::SUCCESS
                    }
                    Err(tread::app::AppError::Interrupted(_)) => {
                        // Before the first mesh was solved: an empty table that says so.
                        let written = adaptive::write(&dir, &opts, &[]);
                        eprintln!(
                            "tread: interrupted before the first mesh was solved{}",
                            match written {
                                Ok(()) =>
                                    format!(" ({} has no rows)", dir.join("adapt.csv").display()),
                                Err(e) => format!("; {e}"),
                            }
                        );
                        ExitCode::from(130)
                    }
                    Err(e) => {
                        eprintln!("tread: error: {e}");
                        ExitCode::from(e.exit_code())
                    }
                }
            }
            Err(e) => {
                eprintln!("tread: invalid scene:\n{}", tidy_numbers(&e));
                ExitCode::from(2)
            }
        },
        Some(Command::Check { scene, set }) if load_model(&scene, &set).is_some() => {
            match load_model(&scene, &set) {
                Some(Ok(m)) => {
                    say(&format!(
                        "# {}: valid; resolved scene with defaults:",
                        scene.display()
                    ));
                    say(m.to_toml_string().trim_end());
                    ExitCode::SUCCESS
                }
                Some(Err(e)) => {
                    eprintln!("tread: invalid scene:\n{}", tidy_numbers(&e));
                    ExitCode::from(2)
                }
                None => ExitCode::from(2),
            }
        }
        Some(Command::Check { scene, set }) => match load(&scene, &set) {
            Ok(mut s) => {
                // The listing loads back from any folder: the mesh file by its absolute path.
                if let Some(abs) = s
                    .mesh
                    .file
                    .as_ref()
                    .and_then(|f| std::fs::canonicalize(f).ok())
                {
                    s.mesh.file = Some(abs.display().to_string());
                }
                say(&format!(
                    "# {}: valid; resolved scene with defaults:",
                    scene.display()
                ));
                say(s.to_annotated_toml_string().trim_end());
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("tread: invalid scene:\n{}", tidy_numbers(&e));
                ExitCode::from(2)
            }
        },
        Some(Command::Schema { markdown, out }) => {
            let text = if markdown {
                tread::io::reference::markdown()
            } else {
                let schema = tread::io::scene::json_schema();
                serde_json::to_string_pretty(&schema).unwrap_or_default() + "\n"
            };
            match out {
                Some(path) => match std::fs::write(&path, text) {
                    Ok(()) => ExitCode::SUCCESS,
                    Err(e) => {
                        eprintln!("tread: cannot write {}: {e}", path.display());
                        ExitCode::from(1)
                    }
                },
                None => {
                    say(text.trim_end());
                    ExitCode::SUCCESS
                }
            }
        }
        Some(Command::Sweep { command }) => {
            tread::sweep::cli::main(command, cli.threads, cli.quiet)
        }
        Some(Command::Replay { log, to, bind }) => {
            match tread::io::replay::replay_bound(&log, to.as_deref(), bind) {
                Ok(msg) => {
                    say(&msg);
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("tread: {e}");
                    ExitCode::from(1)
                }
            }
        }
    }
}
