//! `tread`: command-line front end. See `tread --help` and README.md.

use clap::{Parser, Subcommand};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use tread::app::{self, RunOptions};
use tread::io::Scene;

/// The scene run by `tread` without arguments (also `cargo run --release`).
const DEFAULT_SCENE: &str = include_str!("../scenarios/oden_hollow_cylinder.toml");
const DEFAULT_SCENE_NAME: &str = "scenarios/oden_hollow_cylinder.toml (embedded)";

#[derive(Parser, Debug)]
#[command(
    name = "tread",
    version,
    about = "Rolling-contact finite elements for a hyperelastic hollow cylinder (plane strain)"
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
        /// Override a scene key, e.g. --set mesh.n_r=8 (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Override the analysis mode of the scene (analysis.mode).
        #[arg(long)]
        mode: Option<String>,
        /// Print the Newton convergence table of every load step.
        #[arg(short, long)]
        verbose: bool,
    },
    /// Run a rolling scene in both modes (transient until steady, then steady) and compare
    /// them: OUT/summary.json `results.compare`, OUT/compare.csv, OUT/contact_compare.png,
    /// with each mode's own outputs in OUT/transient/ and OUT/steady/.
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
    },
    /// Validate a scene and print it with every default filled in.
    Check {
        scene: PathBuf,
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Open a log (.rrd or .mcap) in the Rerun viewer, or convert an .mcap to .rrd (--to).
    Replay {
        /// The log: run.rrd or run.mcap from an output directory.
        log: PathBuf,
        /// Convert (MCAP to .rrd) into this file instead of opening a viewer.
        #[arg(long, value_name = "FILE")]
        to: Option<PathBuf>,
    },
}

fn load(path: &Path, set: &[String]) -> Result<Scene, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read scene {}: {e}", path.display()))?;
    let mut scene =
        Scene::from_toml_str(&text, &path.display().to_string(), set).map_err(|e| e.to_string())?;
    // A relative mesh file is relative to the scene file.
    scene.resolve_paths(path);
    Ok(scene)
}

fn run_scene(scene: Scene, out: Option<PathBuf>, verbose: bool, quiet: bool) -> ExitCode {
    run_with(scene, out, verbose, quiet, false)
}

fn run_with(
    scene: Scene,
    out: Option<PathBuf>,
    verbose: bool,
    quiet: bool,
    compare: bool,
) -> ExitCode {
    let out_dir = out.unwrap_or_else(|| {
        let d = app::default_out_dir(&scene);
        if compare {
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
    let opts = RunOptions {
        out_dir,
        verbose,
        quiet,
    };
    let result = if compare {
        tread::driver::compare::run(&scene, &opts)
    } else {
        app::run(&scene, &opts)
    };
    match result {
        Ok(o) => {
            if !quiet {
                println!(
                    "converged: dofs = {}, Newton iterations = {}, wall time = {:.3} s",
                    o.summary["dofs"],
                    o.summary["newton_iterations"],
                    o.summary["wall_time_s"].as_f64().unwrap_or(0.0)
                );
                for line in &o.headline {
                    println!("{line}");
                }
            }
            println!(
                "results written to {}",
                o.out_dir.join("summary.json").display()
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("tread: error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let threads = cli.threads.unwrap_or(0);
    if threads > 0 {
        if let Err(e) = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build_global()
        {
            eprintln!("tread: warning: cannot set the thread count: {e}");
        }
    }
    match cli.command {
        None => match Scene::from_toml_str(DEFAULT_SCENE, DEFAULT_SCENE_NAME, &[]) {
            Ok(scene) => run_scene(scene, None, false, cli.quiet),
            Err(e) => {
                eprintln!("tread: error in the embedded default scene:\n{e}");
                ExitCode::from(2)
            }
        },
        Some(Command::Run {
            scene,
            out,
            mut set,
            mode,
            verbose,
        }) => {
            if let Some(m) = mode {
                set.push(format!("analysis.mode=\"{m}\""));
            }
            match load(&scene, &set) {
                Ok(s) => {
                    if threads == 0 && s.solver.threads > 0 {
                        let _ = rayon::ThreadPoolBuilder::new()
                            .num_threads(s.solver.threads)
                            .build_global();
                    }
                    run_scene(s, out, verbose, cli.quiet)
                }
                Err(e) => {
                    eprintln!("tread: invalid scene:\n{e}");
                    ExitCode::from(2)
                }
            }
        }
        Some(Command::Compare {
            scene,
            out,
            set,
            verbose,
        }) => match load(&scene, &set) {
            Ok(s) => run_with(s, out, verbose, cli.quiet, true),
            Err(e) => {
                eprintln!("tread: invalid scene:\n{e}");
                ExitCode::from(2)
            }
        },
        Some(Command::Check { scene, set }) => match load(&scene, &set) {
            Ok(s) => {
                println!(
                    "# {}: valid; resolved scene with defaults:",
                    scene.display()
                );
                print!("{}", s.to_toml_string());
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("tread: invalid scene:\n{e}");
                ExitCode::from(2)
            }
        },
        Some(Command::Replay { log, to }) => match tread::io::replay::replay(&log, to.as_deref()) {
            Ok(msg) => {
                println!("{msg}");
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("tread: {e}");
                ExitCode::from(1)
            }
        },
    }
}
