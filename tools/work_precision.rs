//! Work–precision suite (a benchmark, not a test): error against wall time and against DOFs.
//!
//! ```text
//! cargo run --release --bin tread-work-precision -- [--smoke] [--repeats N] [--out DIR]
//!     [--fresh-reference] [--studies spinning,indentation,steady,transient]
//! ```
//!
//! Every run goes through `Scene::from_toml_str` (scene text + `--set`-style overrides) and
//! `tread::app::run`, with the `summary` sink only; the numbers are read from the returned
//! summary (`dofs`, `wall_time_s`, `results.*`). Wall time is the median of `--repeats` runs
//! (default 3) of the summary's `wall_time_s`.
//!
//! Studies (each writes `OUT/wp_<study>.csv`, `OUT/wp_<study>.png` (error vs wall time on
//! log–log axes, the Pareto front as its own series) and `OUT/wp_<study>_dofs.png` (error vs
//! DOFs, log–log), and a Markdown table on stdout):
//!
//! * `spinning`: `scenarios/spinning_neo_hookean.toml` at the speed that grows the outer radius
//!   by 5 % (finite strain), order 2 and order 1 meshes. Quantities: `u_r_outer`,
//!   `sigma_r_inner` and its recovered value `recovered_stress.sigma_r_inner` (superconvergent
//!   patch recovery); errors relative to the **exact** axisymmetric solution, computed
//!   independently of the library by shooting on the radial ODE (`tests/common/reference.rs`,
//!   the reference the spinning tests use).
//! * `indentation`: `scenarios/indentation_frictionless.toml`, meshes refined together
//!   (n_theta = 16 n_r), order 2 and order 1. Quantities: `hub_force_y`,
//!   `contact_half_width_moment`; relative errors against an order-2 run on a much finer mesh.
//! * `steady`: `scenarios/oden_hollow_cylinder.toml` with `analysis.mode = "steady"`, n_theta
//!   32..256 with n_r 2..6, order 2 and order 1. Quantities: `hub_force_x`, `hub_force_y`,
//!   `hub_torque`; errors as in `tread compare`: |ΔFx| / |F|, |ΔFy| / |F|, |ΔT| / (|F| Ro)
//!   with |F| of the reference.
//! * `transient`: `scenarios/rolling_frictionless.toml` on a fixed coarse mesh, integrators
//!   generalized_alpha, bdf, sdirk, central_difference at several `time.error_tol`. Error of the
//!   extracted steady hub forces and torque (normalised as in `steady`) against the `steady` mode
//!   on the same mesh: the steady mode is the exact steady state of the same discretisation, so
//!   this error is the time integration's (plus the steadiness tolerance).
//!
//! `error` is the largest of a row's relative errors. A row is on the Pareto front when no other
//! row of the study has both a smaller-or-equal wall time and a smaller-or-equal error (one of
//! them strictly). `rate_vs_dofs` is the local slope d log(error) / d log(DOFs) against the
//! previous mesh of the same variant (for a 2D mesh, the rate in h is −2 × this slope).
//!
//! References are cached in `OUT/reference.json`, keyed by an FNV-1a hash of the scene text and
//! the overrides; `--fresh-reference` recomputes them. `--smoke` runs tiny meshes once each
//! (a check that the tool works, well under a minute in release; its numbers mean nothing).

#[path = "common.rs"]
mod common;
use common::{fnv1a, median};

use std::path::{Path, PathBuf};

use serde_json::{json, Value};
use tread::app::RunOptions;
use tread::io::record::png::{chart, Axis};
use tread::io::Scene;

const SPIN: &str = include_str!("../scenarios/spinning_neo_hookean.toml");
const INDENT: &str = include_str!("../scenarios/indentation_frictionless.toml");
const ODEN: &str = include_str!("../scenarios/oden_hollow_cylinder.toml");
const ROLLING: &str = include_str!("../scenarios/rolling_frictionless.toml");

/// Command-line options.
struct Args {
    smoke: bool,
    repeats: usize,
    out: PathBuf,
    fresh: bool,
    studies: Vec<String>,
}

fn parse_args() -> Args {
    let mut a = Args {
        smoke: false,
        repeats: 3,
        out: PathBuf::from("out/work_precision"),
        fresh: false,
        studies: vec![
            "spinning".into(),
            "indentation".into(),
            "steady".into(),
            "transient".into(),
        ],
    };
    let mut repeats_given = false;
    let argv: Vec<String> = std::env::args().skip(1).collect();
    let mut i = 0;
    let usage = "usage: tread-work-precision [--smoke] [--repeats N] [--out DIR] [--fresh-reference] [--studies spinning,indentation,steady,transient]";
    while i < argv.len() {
        let val = |i: usize| -> String {
            argv.get(i + 1).cloned().unwrap_or_else(|| {
                eprintln!("{usage}");
                std::process::exit(2)
            })
        };
        match argv[i].as_str() {
            "--smoke" => a.smoke = true,
            "--fresh-reference" => a.fresh = true,
            "--repeats" => {
                a.repeats = val(i).parse().unwrap_or_else(|_| {
                    eprintln!("--repeats: expected a positive integer");
                    std::process::exit(2)
                });
                repeats_given = true;
                i += 1;
            }
            "--out" => {
                a.out = PathBuf::from(val(i));
                i += 1;
            }
            "--studies" => {
                a.studies = val(i).split(',').map(|s| s.trim().to_string()).collect();
                i += 1;
            }
            "-h" | "--help" => {
                println!("{usage}");
                std::process::exit(0);
            }
            other => {
                eprintln!("tread-work-precision: unknown argument `{other}`\n{usage}");
                std::process::exit(2);
            }
        }
        i += 1;
    }
    if a.smoke && !repeats_given {
        a.repeats = 1;
    }
    a.repeats = a.repeats.max(1);
    for s in &a.studies {
        if !["spinning", "indentation", "steady", "transient"].contains(&s.as_str()) {
            eprintln!("--studies: unknown study `{s}` (spinning, indentation, steady, transient)");
            std::process::exit(2);
        }
    }
    a
}

/// One solved case: the summary of the last repeat and the median wall time.
struct Solved {
    summary: Value,
    wall: f64,
    converged: bool,
    note: String,
}

/// Run `text` with `overrides` `repeats` times; `Err` only when the scene is invalid.
fn solve(
    text: &str,
    name: &str,
    overrides: &[String],
    repeats: usize,
    scratch: &Path,
) -> Result<Solved, String> {
    let mut set: Vec<String> = overrides.to_vec();
    set.push("output.sinks=[\"summary\"]".to_string());
    let scene =
        Scene::from_toml_str(text, name, &set).map_err(|e| format!("{name} {overrides:?}: {e}"))?;
    let mut walls = Vec::new();
    let mut last = (Value::Null, false, String::new());
    for r in 0..repeats {
        let opts = RunOptions {
            out_dir: scratch.join(format!("{}_{}", fnv1a(&format!("{name}{set:?}")), r)),
            verbose: false,
            quiet: true,
        };
        let t0 = std::time::Instant::now();
        let res = tread::app::run(&scene, &opts);
        let outer = t0.elapsed().as_secs_f64();
        last = match res {
            Ok(o) => {
                let conv = o.converged && o.typed.steady_reached().unwrap_or(true);
                (o.summary, conv, String::new())
            }
            Err(e) => {
                let s = std::fs::read_to_string(opts.out_dir.join("summary.json"))
                    .ok()
                    .and_then(|t| serde_json::from_str(&t).ok())
                    .unwrap_or(Value::Null);
                (s, false, e.to_string())
            }
        };
        walls.push(last.0["wall_time_s"].as_f64().unwrap_or(outer));
        let _ = std::fs::remove_dir_all(&opts.out_dir);
        if !last.1 {
            break; // a failed run is not timed again
        }
    }
    if !last.1 && last.2.is_empty() {
        last.2 = "not converged / not steady".into();
    }
    Ok(Solved {
        summary: last.0,
        wall: median(walls),
        converged: last.1,
        note: last.2,
    })
}

/// The reference cache `OUT/reference.json`.
struct RefCache {
    path: PathBuf,
    map: serde_json::Map<String, Value>,
    fresh: bool,
    refreshed: Vec<String>,
}

impl RefCache {
    fn load(out: &Path, fresh: bool) -> Self {
        let path = out.join("reference.json");
        let map = std::fs::read_to_string(&path)
            .ok()
            .and_then(|t| serde_json::from_str::<Value>(&t).ok())
            .and_then(|v| v.as_object().cloned())
            .unwrap_or_default();
        RefCache {
            path,
            map,
            fresh,
            refreshed: Vec::new(),
        }
    }

    /// The reference values `keys` of `text` + `overrides`, computed (once per run with
    /// `--fresh-reference`) when not cached.
    fn get(
        &mut self,
        text: &str,
        name: &str,
        overrides: &[String],
        keys: &[&str],
        scratch: &Path,
    ) -> Result<Value, String> {
        self.get_with(text, overrides, || {
            eprintln!("  reference {name} {overrides:?} ...");
            let s = solve(text, name, overrides, 1, scratch)?;
            if !s.converged {
                return Err(format!("reference {name} {overrides:?} failed: {}", s.note));
            }
            let mut values = serde_json::Map::new();
            for k in keys {
                values.insert(k.to_string(), json!(result_value(&s.summary, k)));
            }
            Ok(json!({
                "scene": name,
                "overrides": overrides,
                "dofs": s.summary["dofs"],
                "wall_time_s": s.wall,
                "values": values,
            }))
        })
    }

    /// The entry of `text` + `overrides`: the cached one, unless `--fresh-reference` and not
    /// yet recomputed in this run; otherwise `compute`'s, stored and written to the file.
    fn get_with(
        &mut self,
        text: &str,
        overrides: &[String],
        compute: impl FnOnce() -> Result<Value, String>,
    ) -> Result<Value, String> {
        let key = reference_key(text, overrides);
        if let Some(v) = self.map.get(&key) {
            if !self.fresh || self.refreshed.contains(&key) {
                return Ok(v.clone());
            }
        }
        let v = compute()?;
        self.map.insert(key.clone(), v.clone());
        self.refreshed.push(key);
        let text = serde_json::to_string_pretty(&Value::Object(self.map.clone()))
            .map_err(|e| e.to_string())
            .and_then(|t| std::fs::write(&self.path, t).map_err(|e| e.to_string()));
        if let Err(e) = text {
            eprintln!("{}: {e} (the reference is not cached)", self.path.display());
        }
        Ok(v)
    }
}

/// The cache key of a reference: FNV-1a of the scene text and its overrides, one per line.
/// A result of a run: for the transient mode's hub loads the mean over the last node passage
/// (`<key>_passage_mean`: within a passage the hub force swings as nodes enter the patch, 5 % of
/// |F| on a 3 × 48 mesh, so the instant value at the passage is not the steady load), else
/// `results.<key>`; NaN when missing.
/// `results.<key>` of a summary (a dotted key walks into nested objects, e.g.
/// `recovered_stress.sigma_r_inner`); the passage mean `<key>_passage_mean` where there is one.
fn result_value(summary: &Value, key: &str) -> f64 {
    let r = &summary["results"];
    if let Some(v) = r[format!("{key}_passage_mean")].as_f64() {
        return v;
    }
    key.split('.')
        .fold(r, |v, k| &v[k])
        .as_f64()
        .unwrap_or(f64::NAN)
}

fn reference_key(text: &str, overrides: &[String]) -> String {
    fnv1a(&format!("{text}\n{}", overrides.join("\n")))
}

/// One row of a study.
struct Row {
    variant: String,
    setting: String,
    dofs: f64,
    wall: f64,
    values: Vec<f64>,
    errors: Vec<f64>,
    error: f64,
    rate: f64,
    pareto: bool,
    /// Error against a second reference (the transient study: the tightest generalized-α run)
    /// and the Pareto front for it; NaN / false when the study has none.
    error_alt: f64,
    pareto_alt: bool,
    converged: bool,
    note: String,
}

/// How errors are measured in a study.
#[derive(Clone, Copy)]
enum Norm {
    /// |q − q_ref| / |q_ref| per quantity.
    Relative,
    /// Hub forces and torque: |ΔFx| / |F|, |ΔFy| / |F|, |ΔT| / (|F| ro), |F| of the reference.
    Hub { ro: f64 },
}

fn errors(norm: Norm, keys: &[&str], values: &[f64], reference: &Value) -> Vec<f64> {
    let r = |k: &str| reference["values"][k].as_f64().unwrap_or(f64::NAN);
    match norm {
        Norm::Relative => keys
            .iter()
            .zip(values)
            .map(|(k, v)| (v - r(k)).abs() / r(k).abs())
            .collect(),
        Norm::Hub { ro } => {
            let fmag = r("hub_force_x").hypot(r("hub_force_y"));
            keys.iter()
                .zip(values)
                .map(|(k, v)| {
                    let scale = if *k == "hub_torque" { fmag * ro } else { fmag };
                    (v - r(k)).abs() / scale
                })
                .collect()
        }
    }
}

fn make_row(
    variant: &str,
    setting: &str,
    s: &Solved,
    keys: &[&str],
    norm: Norm,
    reference: &Value,
) -> Row {
    let values: Vec<f64> = keys.iter().map(|k| result_value(&s.summary, k)).collect();
    // Kept for a run that did not converge or reach steady rolling (its last state), but such a
    // row is never on the Pareto front and has no rate.
    let errs = errors(norm, keys, &values, reference);
    let error = if errs.iter().all(|e| e.is_finite()) {
        errs.iter().cloned().fold(0.0, f64::max)
    } else {
        f64::NAN
    };
    Row {
        variant: variant.into(),
        setting: setting.into(),
        dofs: s.summary["dofs"].as_f64().unwrap_or(f64::NAN),
        wall: s.wall,
        values,
        errors: errs,
        error,
        rate: f64::NAN,
        pareto: false,
        error_alt: f64::NAN,
        pareto_alt: false,
        converged: s.converged,
        note: s.note.clone(),
    }
}

/// Mark the Pareto front (wall time, error) and the local rates against DOFs per variant.
fn pareto(rows: &[Row], err: impl Fn(&Row) -> f64) -> Vec<bool> {
    let ok = |r: &Row| r.converged && err(r).is_finite() && r.wall.is_finite() && err(r) > 0.0;
    (0..rows.len())
        .map(|i| {
            let (wi, ei) = (rows[i].wall, err(&rows[i]));
            ok(&rows[i])
                && !rows.iter().enumerate().any(|(j, r)| {
                    j != i && ok(r) && r.wall <= wi && err(r) <= ei && (r.wall < wi || err(r) < ei)
                })
        })
        .collect()
}

fn finish(rows: &mut [Row], rates: bool) {
    let ok = |r: &Row| r.converged && r.error.is_finite() && r.wall.is_finite() && r.error > 0.0;
    let (p, q) = (pareto(rows, |r| r.error), pareto(rows, |r| r.error_alt));
    for (i, r) in rows.iter_mut().enumerate() {
        r.pareto = p[i];
        r.pareto_alt = q[i];
    }
    if rates {
        for i in 1..rows.len() {
            let (a, b) = (&rows[i - 1], &rows[i]);
            if a.variant == b.variant && ok(a) && ok(b) && b.dofs != a.dofs {
                rows[i].rate = (b.error / a.error).ln() / (b.dofs / a.dofs).ln();
            }
        }
    }
}

/// Least-squares slope of log(error) against log(DOFs) over a variant's rows.
fn fitted_rate(rows: &[Row], variant: &str) -> f64 {
    let pts: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.variant == variant && r.converged && r.error.is_finite() && r.error > 0.0)
        .map(|r| (r.dofs.ln(), r.error.ln()))
        .collect();
    if pts.len() < 2 {
        return f64::NAN;
    }
    let n = pts.len() as f64;
    let (mx, my) = (
        pts.iter().map(|p| p.0).sum::<f64>() / n,
        pts.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    sxy / sxx
}

fn write_outputs(
    out: &Path,
    study: &str,
    title: &str,
    keys: &[&str],
    rows: &[Row],
    reference_note: &str,
    rates: bool,
) {
    // CSV
    let mut csv = String::from("study,variant,setting,dofs,wall_time_s,error");
    for k in keys {
        csv.push_str(&format!(",{k}"));
    }
    for k in keys {
        csv.push_str(&format!(",err_{k}"));
    }
    csv.push_str(",rate_vs_dofs,pareto,error_alt,pareto_alt,converged,note\n");
    for r in rows {
        csv.push_str(&format!(
            "{study},{},{},{},{:.6e},{:.6e}",
            r.variant,
            r.setting.replace(',', ";"),
            r.dofs,
            r.wall,
            r.error
        ));
        for v in &r.values {
            csv.push_str(&format!(",{v:.10e}"));
        }
        for e in &r.errors {
            csv.push_str(&format!(",{e:.6e}"));
        }
        csv.push_str(&format!(
            ",{:.4},{},{:.6e},{},{},\"{}\"\n",
            r.rate,
            r.pareto,
            r.error_alt,
            r.pareto_alt,
            r.converged,
            r.note.replace('"', "'")
        ));
    }
    let csv_path = out.join(format!("wp_{study}.csv"));
    if let Err(e) = std::fs::write(&csv_path, csv) {
        eprintln!("{}: {e}", csv_path.display());
    }
    // Log–log plots; runs that failed or did not reach steady rolling are left out.
    let ok = |r: &&Row| {
        r.converged && r.error.is_finite() && r.error > 0.0 && r.wall.is_finite() && r.wall > 0.0
    };
    let mut variants: Vec<String> = Vec::new();
    for r in rows {
        if !variants.contains(&r.variant) {
            variants.push(r.variant.clone());
        }
    }
    let per = |x: &dyn Fn(&Row) -> f64| -> Vec<(String, Vec<(f64, f64)>)> {
        variants
            .iter()
            .map(|v| {
                let mut pts: Vec<(f64, f64)> = rows
                    .iter()
                    .filter(|r| &r.variant == v)
                    .filter(ok)
                    .map(|r| (x(r), r.error))
                    .collect();
                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                (v.clone(), pts)
            })
            .collect()
    };
    let mut by_wall = per(&|r: &Row| r.wall);
    let mut front: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.pareto)
        .filter(ok)
        .map(|r| (r.wall, r.error))
        .collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    by_wall.push(("Pareto front".into(), front));
    let draw = |name: String, title: &str, xl: &str, series: &[(String, Vec<(f64, f64)>)]| {
        let s: Vec<(&str, &[(f64, f64)])> = series
            .iter()
            .filter(|(_, p)| !p.is_empty())
            .map(|(n, p)| (n.as_str(), p.as_slice()))
            .collect();
        if s.is_empty() {
            return;
        }
        let path = out.join(name);
        match chart(
            &path,
            title,
            Axis::log10(xl),
            Axis::log10("relative error"),
            &s,
        ) {
            Ok(notes) => {
                for n in notes {
                    eprintln!("{}: {n}", path.display());
                }
            }
            Err(e) => eprintln!("{}: {e}", path.display()),
        }
    };
    draw(format!("wp_{study}.png"), title, "wall time (s)", &by_wall);
    let has_alt = rows.iter().any(|r| r.error_alt.is_finite());
    if has_alt {
        let okalt = |r: &&Row| {
            r.converged
                && r.error_alt.is_finite()
                && r.error_alt > 0.0
                && r.wall.is_finite()
                && r.wall > 0.0
        };
        let mut series: Vec<(String, Vec<(f64, f64)>)> = variants
            .iter()
            .map(|v| {
                let mut pts: Vec<(f64, f64)> = rows
                    .iter()
                    .filter(|r| &r.variant == v)
                    .filter(okalt)
                    .map(|r| (r.wall, r.error_alt))
                    .collect();
                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                (v.clone(), pts)
            })
            .collect();
        let mut front: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.pareto_alt)
            .map(|r| (r.wall, r.error_alt))
            .collect();
        front.sort_by(|a, b| a.0.total_cmp(&b.0));
        series.push(("Pareto front".into(), front));
        draw(
            format!("wp_{study}_alt.png"),
            &format!("{title} (error alt)"),
            "wall time (s)",
            &series,
        );
    }
    if rates {
        draw(
            format!("wp_{study}_dofs.png"),
            &title.replacen("vs wall time", "vs DOFs", 1),
            "DOFs",
            &per(&|r: &Row| r.dofs),
        );
    }
    // Markdown
    println!("\n### {title}\n");
    println!("{reference_note}\n");
    print!("| variant | setting | DOFs | wall (s) | error |");
    for k in keys {
        print!(" err {k} |");
    }
    if rates {
        print!(" rate vs DOFs |");
    }
    if has_alt {
        println!(" Pareto | error alt | Pareto alt |");
    } else {
        println!(" Pareto |");
    }
    print!("|---|---|---|---|---|");
    if has_alt {
        print!("---|---|");
    }
    for _ in keys {
        print!("---|");
    }
    if rates {
        print!("---|");
    }
    println!("---|");
    for r in rows {
        print!(
            "| {} | {} | {} | {:.3} | {:.2e} |",
            r.variant, r.setting, r.dofs, r.wall, r.error
        );
        for e in &r.errors {
            print!(" {e:.2e} |");
        }
        if rates {
            print!(
                " {} |",
                if r.rate.is_finite() {
                    format!("{:.2}", r.rate)
                } else {
                    "–".into()
                }
            );
        }
        let mark = |p: bool| {
            if p {
                "**yes**"
            } else if r.converged {
                ""
            } else {
                "failed: not converged or not steady"
            }
        };
        if has_alt {
            println!(
                " {} | {:.2e} | {} |",
                mark(r.pareto),
                r.error_alt,
                mark(r.pareto_alt)
            );
        } else {
            println!(" {} |", mark(r.pareto));
        }
    }
    if rates {
        println!();
        for v in &variants {
            let s = fitted_rate(rows, v);
            println!(
                "- {v}: fitted slope d log(error) / d log(DOFs) = {s:.2} (rate in h ≈ {:.2})",
                -2.0 * s
            );
        }
    }
    println!(
        "\nFiles: {}, {}",
        csv_path.display(),
        out.join(format!("wp_{study}.png")).display()
    );
}

/// Rows of a mesh study: for every (order, n_r) of `seqs`, the scene (`text`, `name`) with the
/// overrides and the setting label of `mesh(n_r, order)`, errors relative to `reference`.
fn mesh_sequence(
    a: &Args,
    (text, name): (&str, &str),
    seqs: &[(usize, &[usize])],
    mesh: impl Fn(usize, usize) -> (Vec<String>, String),
    keys: &[&str],
    reference: &Value,
    scratch: &Path,
) -> Result<Vec<Row>, String> {
    let mut rows = Vec::new();
    for &(order, seq) in seqs {
        for &n_r in seq {
            let (set, setting) = mesh(n_r, order);
            eprintln!("  {name} Q{order} {setting}");
            let s = solve(text, name, &set, a.repeats, scratch)?;
            rows.push(make_row(
                &format!("Q{order}"),
                &setting,
                &s,
                keys,
                Norm::Relative,
                reference,
            ));
        }
    }
    Ok(rows)
}

/// The exact axisymmetric spinning solution (independent of the library: shooting on the radial
/// ODE, the reference of `tests/spinning.rs`).
#[path = "../tests/common/reference.rs"]
mod reference;

fn study_spinning(a: &Args, scratch: &Path) -> Result<(), String> {
    let keys = [
        "u_r_outer",
        "sigma_r_inner",
        "recovered_stress.sigma_r_inner",
    ];
    let (ri, ro, lambda, mu, rho) = (1.0, 2.0, 1800.0, 200.0, 0.027);
    // The speed at which the outer radius grows by 5 % (as in tests/spinning.rs).
    let omega = reference::neo_hookean_omega_for_growth(ri, ro, lambda, mu, rho, 0.05)?;
    let exact = reference::neo_hookean_radial(ri, ro, lambda, mu, rho, omega)?;
    let reference_v = json!({"values": {
        "u_r_outer": exact.u(ro),
        "sigma_r_inner": exact.sigma_r(ri),
        "recovered_stress.sigma_r_inner": exact.sigma_r(ri),
    }});
    let set = |n_r: usize, order: usize| {
        vec![
            format!("motion.omega={omega:.15e}"),
            format!("mesh.n_r={n_r}"),
            format!("mesh.n_theta={}", (8 * n_r).max(8)),
            format!("mesh.order={order}"),
        ]
    };
    let (seq2, seq1): (Vec<usize>, Vec<usize>) = if a.smoke {
        (vec![1, 2], vec![2])
    } else {
        (vec![1, 2, 4, 8, 12], vec![2, 4, 8, 16, 24])
    };
    let mut rows = mesh_sequence(
        a,
        (SPIN, "spinning_neo_hookean"),
        &[(2, &seq2), (1, &seq1)],
        |n_r, order| (set(n_r, order), format!("{n_r}x{}", (8 * n_r).max(8))),
        &keys,
        &reference_v,
        scratch,
    )?;
    finish(&mut rows, true);
    let note = format!(
        "Spinning neo-Hookean annulus (`scenarios/spinning_neo_hookean.toml`, lambda = {lambda}, mu = {mu}) at omega = {omega:.6} rad/s (outer radius +5 %), n_theta = 8 n_r. Reference: the exact axisymmetric solution by shooting on the radial ODE ({} RK4 steps): u_r(Ro) = {:.10e}, sigma_r(Ri) = {:.10e}. Errors relative.",
        reference::DEFAULT_RADIAL_STEPS,
        exact.u(ro),
        exact.sigma_r(ri)
    );
    write_outputs(
        &a.out,
        "spinning",
        "Spinning annulus (exact solution): error vs wall time",
        &keys,
        &rows,
        &note,
        true,
    );
    Ok(())
}

fn study_indentation(a: &Args, cache: &mut RefCache, scratch: &Path) -> Result<(), String> {
    let keys = ["hub_force_y", "contact_half_width_moment"];
    let mesh = |n_r: usize, n_theta: usize, order: usize| {
        vec![
            format!("mesh.n_r={n_r}"),
            format!("mesh.n_theta={n_theta}"),
            format!("mesh.order={order}"),
        ]
    };
    let (seq2, seq1, reference): (Vec<usize>, Vec<usize>, (usize, usize)) = if a.smoke {
        (vec![1, 2], vec![2], (3, 48))
    } else {
        (vec![2, 3, 4, 6, 8], vec![2, 4, 6, 8, 12, 16], (24, 384))
    };
    let ref_set = mesh(reference.0, reference.1, 2);
    let reference_v = cache.get(INDENT, "indentation_frictionless", &ref_set, &keys, scratch)?;
    let mut rows = mesh_sequence(
        a,
        (INDENT, "indentation_frictionless"),
        &[(2, &seq2), (1, &seq1)],
        |n_r, order| (mesh(n_r, 16 * n_r, order), format!("{n_r}x{}", 16 * n_r)),
        &keys,
        &reference_v,
        scratch,
    )?;
    finish(&mut rows, true);
    let note = format!(
        "Static frictionless indentation (`scenarios/indentation_frictionless.toml`), n_theta = 16 n_r (grading_theta 0.6). Reference: Q2 {}x{} ({} DOFs): hub_force_y = {:.8e}, contact_half_width_moment = {:.8e}. Errors relative.",
        reference.0, reference.1, reference_v["dofs"], reference_v["values"]["hub_force_y"].as_f64().unwrap_or(f64::NAN),
        reference_v["values"]["contact_half_width_moment"].as_f64().unwrap_or(f64::NAN)
    );
    write_outputs(
        &a.out,
        "indentation",
        "Static indentation: error vs wall time",
        &keys,
        &rows,
        &note,
        true,
    );
    Ok(())
}

fn study_steady(a: &Args, cache: &mut RefCache, scratch: &Path) -> Result<(), String> {
    let keys = ["hub_force_x", "hub_force_y", "hub_torque"];
    let mesh = |n_r: usize, n_theta: usize, order: usize| {
        vec![
            "analysis.mode=\"steady\"".to_string(),
            format!("mesh.n_r={n_r}"),
            format!("mesh.n_theta={n_theta}"),
            format!("mesh.order={order}"),
        ]
    };
    let (seq, reference): (Vec<(usize, usize)>, (usize, usize)) = if a.smoke {
        (vec![(2, 16), (2, 24)], (3, 48))
    } else {
        (vec![(2, 32), (3, 64), (4, 128), (6, 256)], (12, 1024))
    };
    let ref_set = mesh(reference.0, reference.1, 2);
    let reference_v = cache.get(ODEN, "oden_hollow_cylinder", &ref_set, &keys, scratch)?;
    let mut rows = Vec::new();
    for order in [2usize, 1] {
        for &(n_r, n_theta) in &seq {
            // Q1 with twice the cells in each direction: the same nodes as Q2.
            let (nr, nt) = if order == 1 {
                (2 * n_r, 2 * n_theta)
            } else {
                (n_r, n_theta)
            };
            eprintln!("  steady Q{order} {nr} x {nt}");
            let s = solve(
                ODEN,
                "oden_hollow_cylinder",
                &mesh(nr, nt, order),
                a.repeats,
                scratch,
            )?;
            rows.push(make_row(
                &format!("Q{order}"),
                &format!("{nr}x{nt}"),
                &s,
                &keys,
                Norm::Hub { ro: 2.0 },
                &reference_v,
            ));
        }
    }
    finish(&mut rows, true);
    let note = format!(
        "Steady mode on `scenarios/oden_hollow_cylinder.toml` (Coulomb μ = 0.3, 10 rad/s). Q1 meshes have twice the cells of the Q2 ones in each direction (the same nodes). Reference: Q2 {}x{} ({} DOFs): Fx = {:.8e}, Fy = {:.8e}, T = {:.8e}. Errors |ΔFx|/|F|, |ΔFy|/|F|, |ΔT|/(|F| Ro).",
        reference.0, reference.1, reference_v["dofs"],
        reference_v["values"]["hub_force_x"].as_f64().unwrap_or(f64::NAN),
        reference_v["values"]["hub_force_y"].as_f64().unwrap_or(f64::NAN),
        reference_v["values"]["hub_torque"].as_f64().unwrap_or(f64::NAN)
    );
    write_outputs(
        &a.out,
        "steady",
        "Steady mode: error vs wall time",
        &keys,
        &rows,
        &note,
        true,
    );
    Ok(())
}

fn study_transient(a: &Args, cache: &mut RefCache, scratch: &Path) -> Result<(), String> {
    let keys = ["hub_force_x", "hub_force_y", "hub_torque"];
    let (mesh, tols): (Vec<String>, Vec<&str>) = if a.smoke {
        (
            vec!["mesh.n_r=1".into(), "mesh.n_theta=16".into()],
            vec!["1e-2"],
        )
    } else {
        // n_r = 3: with n_r = 2 (32 or 48 cells around) the frictionless steady reference's load
        // stepping stalls near full penetration (line search fails at load factor ≈ 0.97).
        (
            vec!["mesh.n_r=3".into(), "mesh.n_theta=48".into()],
            vec!["1e-2", "1e-3", "1e-4"],
        )
    };
    let mut ref_set = mesh.clone();
    ref_set.push("analysis.mode=\"steady\"".into());
    let reference_v = cache.get(ROLLING, "rolling_frictionless", &ref_set, &keys, scratch)?;
    // Second reference: a tight generalized-α run on the same mesh (its own time-converged
    // steady state; the steady mode differs from it by the difference of the two
    // discretisations, the Eulerian steady one and the Lagrangian transient one).
    let (tight, tight_steady) = if a.smoke {
        ("1e-2", "1e-3")
    } else {
        ("1e-5", "1e-4")
    };
    let mut alt_set = mesh.clone();
    alt_set.extend([
        "time.integrator=\"generalized_alpha\"".to_string(),
        format!("time.error_tol={tol}", tol = tight),
        format!("time.steady_tol={tight_steady}"),
    ]);
    let alt_v = cache
        .get(ROLLING, "rolling_frictionless", &alt_set, &keys, scratch)
        .unwrap_or_else(|e| {
            eprintln!("{e} (error alt left empty)");
            Value::Null
        });
    let mut rows = Vec::new();
    for integrator in ["generalized_alpha", "bdf", "sdirk", "central_difference"] {
        for tol in &tols {
            let mut set = mesh.clone();
            set.push(format!("time.integrator=\"{integrator}\""));
            set.push(format!("time.error_tol={tol}"));
            if integrator == "central_difference" {
                set.push("time.mass=\"lumped\"".into()); // the scene's consistent mass is an error here
            }
            eprintln!("  transient {integrator} error_tol {tol}");
            let s = solve(ROLLING, "rolling_frictionless", &set, a.repeats, scratch)?;
            let mut row = make_row(
                integrator,
                &format!("error_tol={tol}"),
                &s,
                &keys,
                Norm::Hub { ro: 2.0 },
                &reference_v,
            );
            let e = errors(Norm::Hub { ro: 2.0 }, &keys, &row.values, &alt_v);
            row.error_alt = e.iter().cloned().fold(0.0, f64::max);
            rows.push(row);
        }
    }
    finish(&mut rows, false);
    let note = format!(
        "Transient integrators on `scenarios/rolling_frictionless.toml`, mesh {:?} (fixed). Reference: the steady mode on the same mesh ({} DOFs): Fx = {:.8e}, Fy = {:.8e}, T = {:.8e}. Errors |ΔFx|/|F|, |ΔFy|/|F|, |ΔT|/(|F| Ro) of the extracted steady state; they include the steadiness tolerance (time.steady_tol = 1e-3) and the difference between the steady and the transient discretisations. `error alt`: the same errors against generalized-α at error_tol = {tight}, steady_tol = {tight_steady} (Fy = {:.8e}, T = {:.8e}): the time-integration error alone.",
        mesh, reference_v["dofs"],
        reference_v["values"]["hub_force_x"].as_f64().unwrap_or(f64::NAN),
        reference_v["values"]["hub_force_y"].as_f64().unwrap_or(f64::NAN),
        reference_v["values"]["hub_torque"].as_f64().unwrap_or(f64::NAN),
        alt_v["values"]["hub_force_y"].as_f64().unwrap_or(f64::NAN),
        alt_v["values"]["hub_torque"].as_f64().unwrap_or(f64::NAN),
    );
    write_outputs(
        &a.out,
        "transient",
        "Transient integrators: steady hub load error vs wall time",
        &keys,
        &rows,
        &note,
        false,
    );
    Ok(())
}

fn main() {
    let a = parse_args();
    if let Err(e) = std::fs::create_dir_all(&a.out) {
        eprintln!("{}: {e}", a.out.display());
        std::process::exit(2);
    }
    let scratch = std::env::temp_dir().join(format!("tread_wp_{}", std::process::id()));
    let mut cache = RefCache::load(&a.out, a.fresh);
    println!(
        "## Work–precision{} (repeats = {}, {} threads)",
        if a.smoke {
            " (smoke: numbers mean nothing)"
        } else {
            ""
        },
        a.repeats,
        rayon::current_num_threads()
    );
    let mut failed = false;
    for s in a.studies.clone() {
        eprintln!("study {s}");
        let r = match s.as_str() {
            "spinning" => study_spinning(&a, &scratch),
            "indentation" => study_indentation(&a, &mut cache, &scratch),
            "steady" => study_steady(&a, &mut cache, &scratch),
            _ => study_transient(&a, &mut cache, &scratch),
        };
        if let Err(e) = r {
            eprintln!("study {s}: {e}");
            failed = true;
        }
    }
    let _ = std::fs::remove_dir_all(&scratch);
    if failed {
        std::process::exit(1);
    }
}

#[cfg(test)]
#[path = "../tests/common/tempdir.rs"]
mod tempdir;

#[cfg(test)]
mod tests {
    use super::tempdir::TestDir;
    use super::*;
    use std::cell::Cell;

    fn row(variant: &str, dofs: f64, wall: f64, error: f64, converged: bool) -> Row {
        Row {
            variant: variant.into(),
            setting: String::new(),
            dofs,
            wall,
            values: Vec::new(),
            errors: vec![error],
            error,
            rate: f64::NAN,
            pareto: false,
            error_alt: f64::NAN,
            pareto_alt: false,
            converged,
            note: String::new(),
        }
    }

    #[test]
    fn pareto_front_of_constructed_rows() {
        let rows = vec![
            row("a", 1.0, 1.0, 1e-2, true),      // 0: front
            row("a", 1.0, 2.0, 1e-3, true),      // 1: front (tied with 4)
            row("a", 1.0, 2.0, 1e-2, true),      // 2: dominated by 0 (slower, same error) and 1
            row("b", 1.0, 0.5, 1e-1, true),      // 3: front (fastest usable)
            row("b", 1.0, 2.0, 1e-3, true),      // 4: front (tied with 1: neither dominates)
            row("b", 1.0, 0.1, 1e-6, false),     // 5: not converged: never on it, dominates nothing
            row("b", 1.0, 0.2, 0.0, true),       // 6: zero error (no reference?): left out
            row("b", 1.0, f64::NAN, 1e-9, true), // 7: no wall time: left out
            row("b", 1.0, 3.0, 1e-3, true),      // 8: dominated by 1 and 4 (slower, same error)
        ];
        let front = pareto(&rows, |r| r.error);
        assert_eq!(
            front,
            [true, true, false, true, true, false, false, false, false]
        );
        // The same marking through `finish`, and for the alternative error.
        let mut rows = rows;
        for r in rows.iter_mut() {
            r.error_alt = r.error;
        }
        rows[3].error_alt = 1e-4; // now dominates 0, 1, 2, 4 and 8 on the alternative error
        finish(&mut rows, false);
        let marked: Vec<bool> = rows.iter().map(|r| r.pareto).collect();
        assert_eq!(marked, front);
        let alt: Vec<usize> = (0..rows.len()).filter(|&i| rows[i].pareto_alt).collect();
        assert_eq!(alt, [3]);
    }

    #[test]
    fn rate_vs_dofs_recovers_a_power_law() {
        // error = C DOFs^p: Q2 with p = -1.5, Q1 with p = -0.5.
        let mut rows: Vec<Row> = [100.0, 400.0, 1600.0, 6400.0]
            .iter()
            .map(|&n| row("Q2", n, 1.0, 3.0 * f64::powf(n, -1.5), true))
            .chain(
                [100.0, 400.0, 1600.0]
                    .iter()
                    .map(|&n| row("Q1", n, 1.0, 2.0 * f64::powf(n, -0.5), true)),
            )
            .collect();
        finish(&mut rows, true);
        let rates: Vec<f64> = rows.iter().map(|r| r.rate).collect();
        assert!(rates[0].is_nan(), "first mesh of a variant has no rate");
        for r in &rates[1..4] {
            assert!((r + 1.5).abs() < 1e-12, "{rates:?}");
        }
        assert!(rates[4].is_nan(), "no rate across variants: {rates:?}");
        for r in &rates[5..7] {
            assert!((r + 0.5).abs() < 1e-12, "{rates:?}");
        }
        assert!((fitted_rate(&rows, "Q2") + 1.5).abs() < 1e-12);
        assert!((fitted_rate(&rows, "Q1") + 0.5).abs() < 1e-12);
        assert!(fitted_rate(&rows, "Q3").is_nan());

        // A failed run in the middle: no rate for it nor for the next mesh, and the fit skips it.
        let mut rows: Vec<Row> = [100.0, 400.0, 1600.0, 6400.0]
            .iter()
            .map(|&n| row("Q2", n, 1.0, 3.0 * f64::powf(n, -1.5), true))
            .collect();
        rows[1].converged = false;
        rows[1].error = 1.0;
        finish(&mut rows, true);
        assert!(rows[1].rate.is_nan() && rows[2].rate.is_nan());
        assert!((rows[3].rate + 1.5).abs() < 1e-12);
        assert!((fitted_rate(&rows, "Q2") + 1.5).abs() < 1e-12);
        // Without rates (the transient study) none is computed.
        finish(&mut rows, false);
        assert!(rows[3].rate.is_finite()); // left as it was
        let mut fresh: Vec<Row> = [100.0, 400.0]
            .iter()
            .map(|&n| row("Q2", n, 1.0, 1.0 / n, true))
            .collect();
        finish(&mut fresh, false);
        assert!(fresh.iter().all(|r| r.rate.is_nan()));
    }

    #[test]
    fn errors_relative_and_hub_normalised() {
        let reference = json!({"values": {"a": 2.0, "hub_force_x": 3.0, "hub_force_y": -4.0,
                                          "hub_torque": 10.0}});
        let e = errors(Norm::Relative, &["a"], &[2.5], &reference);
        assert_eq!(e, [0.25]);
        // |F| = 5, Ro = 2: ΔFx / 5, ΔFy / 5, ΔT / 10.
        let e = errors(
            Norm::Hub { ro: 2.0 },
            &["hub_force_x", "hub_force_y", "hub_torque"],
            &[3.5, -5.0, 9.0],
            &reference,
        );
        assert_eq!(e, [0.1, 0.2, 0.1]);
        // No reference value: NaN, never 0.
        let e = errors(Norm::Relative, &["b"], &[1.0], &reference);
        assert!(e[0].is_nan());
    }

    #[test]
    fn transient_hub_loads_are_read_as_passage_means() {
        let s = json!({"results": {"hub_force_y": -92.1, "hub_force_y_passage_mean": -94.2,
            "hub_force_x": 1.0, "hub_torque_passage_mean": null}});
        assert_eq!(result_value(&s, "hub_force_y"), -94.2);
        assert_eq!(result_value(&s, "hub_force_x"), 1.0);
        assert!(result_value(&s, "hub_torque").is_nan());
    }

    #[test]
    fn reference_key_is_stable() {
        // FNV-1a 64 test vectors: the key must not depend on the Rust version or platform.
        assert_eq!(fnv1a(""), "cbf29ce484222325");
        assert_eq!(fnv1a("a"), "af63dc4c8601ec8c");
        assert_eq!(fnv1a("foobar"), "85944171f73967e8");
        let set = vec!["mesh.n_r=3".to_string(), "mesh.n_theta=48".to_string()];
        let k = reference_key("[mesh]\nn_r = 2\n", &set);
        assert_eq!(k, fnv1a("[mesh]\nn_r = 2\n\nmesh.n_r=3\nmesh.n_theta=48"));
        assert_eq!(k, reference_key("[mesh]\nn_r = 2\n", &set.clone()));
        // A different override, order or text is a different reference.
        let swapped = vec![set[1].clone(), set[0].clone()];
        assert_ne!(k, reference_key("[mesh]\nn_r = 2\n", &swapped));
        assert_ne!(k, reference_key("[mesh]\nn_r = 2\n", &set[..1]));
        assert_ne!(k, reference_key("[mesh]\nn_r = 3\n", &set));
    }

    #[test]
    fn reference_cache_reuses_and_refreshes() {
        let dir = TestDir::new("wp-test", "cache");
        let set = vec!["mesh.n_r=3".to_string()];
        let calls = Cell::new(0);
        let compute = |v: f64| {
            let calls = &calls;
            move || {
                calls.set(calls.get() + 1);
                Ok(json!({"values": {"q": v}}))
            }
        };
        // First run: computed once, written to OUT/reference.json, then served from memory.
        let mut cache = RefCache::load(&dir, false);
        let v = cache.get_with("scene", &set, compute(1.0)).unwrap();
        assert_eq!(v["values"]["q"], 1.0);
        assert_eq!(calls.get(), 1);
        let file: Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("reference.json")).unwrap())
                .unwrap();
        assert_eq!(file[reference_key("scene", &set)]["values"]["q"], 1.0);
        cache.get_with("scene", &set, compute(2.0)).unwrap();
        assert_eq!(calls.get(), 1);
        // Another reference is computed on its own.
        cache.get_with("scene", &[], compute(3.0)).unwrap();
        assert_eq!(calls.get(), 2);

        // Second run: both read from the file, nothing recomputed.
        let mut cache = RefCache::load(&dir, false);
        let v = cache.get_with("scene", &set, compute(9.0)).unwrap();
        assert_eq!((v["values"]["q"].as_f64(), calls.get()), (Some(1.0), 2));
        assert!(cache.refreshed.is_empty());

        // --fresh-reference: recomputed once per run, the file updated, the other entry kept.
        let mut cache = RefCache::load(&dir, true);
        let v = cache.get_with("scene", &set, compute(4.0)).unwrap();
        assert_eq!((v["values"]["q"].as_f64(), calls.get()), (Some(4.0), 3));
        let v = cache.get_with("scene", &set, compute(5.0)).unwrap();
        assert_eq!((v["values"]["q"].as_f64(), calls.get()), (Some(4.0), 3));
        let cache = RefCache::load(&dir, false);
        assert_eq!(cache.map[&reference_key("scene", &set)]["values"]["q"], 4.0);
        assert_eq!(cache.map[&reference_key("scene", &[])]["values"]["q"], 3.0);

        // A failed computation is an error and caches nothing.
        let mut cache = RefCache::load(&dir, false);
        let e = cache
            .get_with("other", &set, || Err("reference failed".into()))
            .unwrap_err();
        assert_eq!(e, "reference failed");
        assert!(!cache.map.contains_key(&reference_key("other", &set)));
    }

    /// Fields of one CSV line (double-quoted fields may hold commas).
    fn csv_fields(line: &str) -> Vec<String> {
        let (mut fields, mut cur, mut quoted) = (Vec::new(), String::new(), false);
        for ch in line.chars() {
            match ch {
                '"' => quoted = !quoted,
                ',' if !quoted => fields.push(std::mem::take(&mut cur)),
                _ => cur.push(ch),
            }
        }
        fields.push(cur);
        fields
    }

    /// The spinning study against the exact radial solution: Q2 errors fall under refinement
    /// and u_r(Ro) is the exact 5 % growth within the discretisation error.
    #[test]
    fn spinning_study_measures_error_against_the_exact_solution() {
        let dir = TestDir::new("wp-test", "spinning");
        let args = Args {
            smoke: true,
            repeats: 1,
            out: dir.to_path_buf(),
            fresh: false,
            studies: vec!["spinning".into()],
        };
        study_spinning(&args, &dir.join("scratch")).unwrap();
        let csv = std::fs::read_to_string(dir.join("wp_spinning.csv")).unwrap();
        let rows: Vec<Vec<String>> = csv.lines().skip(1).map(csv_fields).collect();
        assert_eq!(rows.len(), 3, "{csv}");
        let col = |r: &Vec<String>, i: usize| r[i].parse::<f64>().unwrap();
        // Columns: 6 u_r_outer, 9 err_u_r_outer, 10 err_sigma_r_inner,
        // 11 err_recovered_stress.sigma_r_inner, 16 converged.
        let header = csv.lines().next().unwrap();
        assert!(
            header.contains(",err_sigma_r_inner,err_recovered_stress.sigma_r_inner,"),
            "{header}"
        );
        for r in &rows {
            assert_eq!(r[16], "true", "{r:?}");
            // u_r(Ro) = 0.05 Ro = 0.1 exactly by the choice of omega.
            assert!((col(r, 6) - 0.1).abs() < 1e-2, "{r:?}");
        }
        assert!(col(&rows[1], 9) < col(&rows[0], 9) / 4.0, "{rows:?}");
        assert!(col(&rows[1], 10) < col(&rows[0], 10), "{rows:?}");
        // The recovered hub stress converges too, and is the more accurate on the finer
        // Q2 mesh.
        assert!(col(&rows[1], 11) < col(&rows[0], 11), "{rows:?}");
        assert!(col(&rows[1], 11) < col(&rows[1], 10), "{rows:?}");
    }

    /// The smoke indentation study through `tread::app::run`: CSV columns and rows, plots, the
    /// cached reference reused by a second run and recomputed with `--fresh-reference`.
    #[test]
    fn indentation_study_end_to_end() {
        let dir = TestDir::new("wp-test", "study");
        let scratch = dir.join("scratch");
        let args = |fresh: bool| Args {
            smoke: true,
            repeats: 1,
            out: dir.to_path_buf(),
            fresh,
            studies: vec!["indentation".into()],
        };
        let mut cache = RefCache::load(&dir, false);
        study_indentation(&args(false), &mut cache, &scratch).unwrap();
        assert_eq!(cache.refreshed.len(), 1, "the reference is computed once");
        let csv = std::fs::read_to_string(dir.join("wp_indentation.csv")).unwrap();
        let mut lines = csv.lines();
        let header = csv_fields(lines.next().unwrap());
        assert_eq!(
            header,
            [
                "study",
                "variant",
                "setting",
                "dofs",
                "wall_time_s",
                "error",
                "hub_force_y",
                "contact_half_width_moment",
                "err_hub_force_y",
                "err_contact_half_width_moment",
                "rate_vs_dofs",
                "pareto",
                "error_alt",
                "pareto_alt",
                "converged",
                "note"
            ]
        );
        let rows: Vec<Vec<String>> = lines.map(csv_fields).collect();
        // Smoke: Q2 at n_r = 1, 2 and Q1 at n_r = 2.
        let variants: Vec<(&str, &str)> = rows
            .iter()
            .map(|r| (r[1].as_str(), r[2].as_str()))
            .collect();
        assert_eq!(variants, [("Q2", "1x16"), ("Q2", "2x32"), ("Q1", "2x32")]);
        for r in &rows {
            assert_eq!(r.len(), header.len(), "{r:?}");
            assert_eq!(r[14], "true", "{r:?}");
            let err: f64 = r[5].parse().unwrap();
            assert!(err.is_finite() && err > 0.0, "{r:?}");
            let dofs: f64 = r[3].parse().unwrap();
            assert!(dofs > 0.0);
        }
        assert!(rows.iter().any(|r| r[11] == "true"), "no Pareto point");
        let rate: f64 = rows[1][10].parse().unwrap();
        assert!(rate < 0.0, "Q2 error must fall with refinement: {rate}");
        for png in ["wp_indentation.png", "wp_indentation_dofs.png"] {
            assert!(
                std::fs::metadata(dir.join(png)).unwrap().len() > 1000,
                "{png}"
            );
        }
        // Each run's output directory is removed after it (`main` removes `scratch` itself).
        let left = std::fs::read_dir(&scratch).map_or(0, |d| d.count());
        assert_eq!(left, 0, "scratch runs left in {}", scratch.display());

        // Second run: the reference comes from OUT/reference.json.
        let mut cache = RefCache::load(&dir, false);
        assert_eq!(cache.map.len(), 1);
        study_indentation(&args(false), &mut cache, &scratch).unwrap();
        assert!(cache.refreshed.is_empty(), "the reference was recomputed");
        // --fresh-reference recomputes it.
        let mut cache = RefCache::load(&dir, true);
        study_indentation(&args(true), &mut cache, &scratch).unwrap();
        assert_eq!(cache.refreshed.len(), 1);
    }
}
