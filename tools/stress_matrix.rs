//! Numerical-stability stress matrix (not a test): sweeps one factor at a time around small base
//! scenes and classifies every run.
//!
//! ```text
//! cargo run --release --bin tread-stress -- [--smoke] [--factor NAME] [--out DIR]
//! ```
//!
//! Factors (each around a base scene built from `scenarios/` with `--set`-style overrides,
//! coarse meshes and short runs so the full matrix takes a few minutes):
//!
//! | factor | scene | mode | values |
//! |---|---|---|---|
//! | `dt` | `rolling_frictionless` (2 × 32 Q2, t_end = 0.1 s, fixed step) | transient | 1e-4 … t_end (one step) |
//! | `integrator` | same | transient | generalized_alpha, central_difference, bdf, sdirk at dt 1e-3, 1e-2, 1e-1 |
//! | `omega` | `oden_hollow_cylinder` (3 × 64) | steady | 5 … 80 rad/s (critical ≈ 41–47 rad/s), direct Newton, no continuation |
//! | `omega (continuation)` | `oden_steady_sweep` (3 × 64), m_n = 2 and 1 | steady | arc length in ω from 10 to 60 rad/s |
//! | `omega (m_n=2)` | same, quadratic compliance c_n = 2e6 | steady | 10 … 60 rad/s |
//! | `c_n_over_G_h` | `indentation_friction` (4 × 64) / `oden_hollow_cylinder` | static / steady | c_n = 0.1 … 1e6 × G / (Ro − Ri) |
//! | `kappa_over_G` | `indentation_friction`, `oden_hollow_cylinder` | static / steady | 10 … 1e6 (compressible), incompressible perturbed, exact Q2/P1 |
//! | `mu` | `indentation_friction`, `oden_hollow_cylinder` | static / steady / transient | 0 … 1 |
//! | `eps_over_v0` | `oden_hollow_cylinder` | steady / transient (2 × 32) | ε = 1e-1 … 1e-6 × v0 |
//! | `eps_over_v0 (v0=21)` | same near free rolling (v0 = 21 in/s) | steady | ε = 1e-1 … 1e-6 × v0 |
//! | `m_n` | both | static / steady | 1, 2, 3 with c_n = G / δ_ref^m_n (p = G at δ_ref = 0.01 in) |
//! | `extreme` | all three | all | a deep indentation, c_n = 1e12, κ = 1e10, ω = 0, ε = 1e-12, a 1 × 8 mesh, undamped runs |
//! | `viscoelastic` | `viscoelastic_rolling` (2 × 32, 0.6 s), convolution and multiplicative | transient | γ = G and 10 G, ω = 10 and 40 rad/s, DISP = 0.1 and 0.4 in |
//!
//! Outcome of each case: `converged` (Ok, no cut-back and no rejected step), `recovered` (Ok with
//! `solver.cutbacks` or `results.rejected_steps` > 0, or with a steady-mode recovery strategy in
//! `solver.recovery.strategy`), `failed` with a class from the typed
//! error (`newton_not_converged`, `line_search`, `inadmissible`, `explicit_unstable`,
//! `continuation`, `integrator`, `linear_solver`, `invalid_input`, `output`, `other`), or
//! `panic` (a bug). A wrapped error (load stepping or time-step halving that gave up) is classed
//! by its innermost cause. Every case's `summary.json` and CSV files are scanned for non-finite
//! number text (`NaN`, `nan`, `inf` tokens), which must never be written.
//!
//! Writes `OUT/stress_matrix.csv` and `OUT/stress_matrix.md` (default OUT: `out/stress`) and
//! prints the Markdown. `--smoke` runs a handful of fast cases (tool correctness, for CI);
//! `--factor NAME` runs one factor's cases only.
//!
//! Viscoelastic runs also report the energy balance of the viscous overstress
//! (`results.viscous_energy`: dissipated energy, lowest cumulative dissipation, and
//! `ENERGY CREATED` when the overstress created energy) in the `viscous_energy` column.

use std::path::{Path, PathBuf};
use std::time::Instant;

use tread::app::{AppError, RunOptions};
use tread::io::Scene;
use tread::solver::newton::SolveError;

const ROLLING: &str = include_str!("../scenarios/rolling_frictionless.toml");
const ODEN: &str = include_str!("../scenarios/oden_hollow_cylinder.toml");
const SWEEP: &str = include_str!("../scenarios/oden_steady_sweep.toml");
const INDENT: &str = include_str!("../scenarios/indentation_friction.toml");
const VISCO: &str = include_str!("../scenarios/viscoelastic_rolling.toml");

/// Shear modulus G = 2 (C1 + C2) of the scenes' rubber (psi) and wall thickness Ro − Ri (in).
const G: f64 = 200.0;
const WALL: f64 = 1.0;
/// R_eff ≈ Ro − DISP/3 of the rolling scenes: free-rolling road speed v0 = ω R_eff.
const R_EFF: f64 = 1.966667;

#[derive(Clone, Copy, PartialEq)]
enum Base {
    /// `rolling_frictionless.toml`, transient, coarse and short, fixed step.
    Transient,
    /// `oden_hollow_cylinder.toml` in steady mode (its own 3 × 64 mesh).
    Steady,
    /// `oden_hollow_cylinder.toml`, transient with friction, coarse and short, fixed step.
    TransientFriction,
    /// `indentation_friction.toml`, static, coarse.
    Static,
    /// `oden_steady_sweep.toml`: steady, arc-length continuation in ω from 10 rad/s.
    Sweep,
    /// `viscoelastic_rolling.toml` (convolution model), transient, 0.6 s.
    ViscoConvolution,
    /// The same with the multiplicative model.
    ViscoMultiplicative,
}

impl Base {
    fn file(self) -> &'static str {
        match self {
            Base::Transient => "rolling_frictionless",
            Base::Steady | Base::TransientFriction => "oden_hollow_cylinder",
            Base::Static => "indentation_friction",
            Base::Sweep => "oden_steady_sweep",
            Base::ViscoConvolution | Base::ViscoMultiplicative => "viscoelastic_rolling",
        }
    }
    fn mode(self) -> &'static str {
        match self {
            Base::Transient
            | Base::TransientFriction
            | Base::ViscoConvolution
            | Base::ViscoMultiplicative => "transient",
            Base::Steady | Base::Sweep => "steady",
            Base::Static => "static",
        }
    }
    fn text(self) -> String {
        match self {
            Base::Transient => ROLLING.into(),
            Base::Steady | Base::TransientFriction => ODEN.into(),
            Base::Static => INDENT.into(),
            Base::Sweep => SWEEP.into(),
            Base::ViscoConvolution => VISCO.into(),
            Base::ViscoMultiplicative => {
                VISCO.replace("model = \"convolution\"", "model = \"multiplicative\"")
            }
        }
    }
    /// The small base scene's overrides.
    fn overrides(self) -> Vec<String> {
        let mut v: Vec<String> = match self {
            Base::Transient | Base::TransientFriction => vec![
                "mesh.n_theta=32",
                "mesh.n_r=2",
                "time.t_end=0.1",
                "time.dt=1e-3",
                "time.adaptive=false",
                "time.stop_at_steady=false",
            ],
            Base::Steady => vec!["analysis.mode=steady"],
            Base::ViscoConvolution | Base::ViscoMultiplicative => {
                vec!["time.t_end=0.6", "time.stop_at_steady=false"]
            }
            Base::Sweep => vec![],
            Base::Static => vec!["mesh.n_theta=64", "mesh.n_r=4", "solver.tolerance=1e-8"],
        }
        .into_iter()
        .map(String::from)
        .collect();
        v.push("output.sinks=[\"summary\", \"csv\"]".into());
        v
    }
}

struct Case {
    factor: &'static str,
    value: String,
    base: Base,
    set: Vec<String>,
    /// Keys (`key = ` at the start of a line) removed from the scene text before parsing; an
    /// override cannot remove a key (the exact incompressible model rejects `kappa`).
    drop_keys: Vec<&'static str>,
    /// Text replacements `(from, to)` applied to the scene text (keys of sub-tables such as
    /// `[material.viscoelastic]`, which an override cannot reach).
    edits: Vec<(&'static str, &'static str)>,
}

fn case(factor: &'static str, value: impl ToString, base: Base, set: &[String]) -> Case {
    Case {
        factor,
        value: value.to_string(),
        base,
        set: set.to_vec(),
        drop_keys: Vec::new(),
        edits: Vec::new(),
    }
}

fn steady_omega(omega: f64) -> Vec<String> {
    vec![
        format!("motion.omega={omega}"),
        format!("road.v0={}", omega * R_EFF),
    ]
}

fn full_cases() -> Vec<Case> {
    let mut c = Vec::new();
    // Time step (fixed), generalized-α; ramps 0.05 s, dt = t_end = 0.1 s is one step through both.
    for dt in [1e-4, 3e-4, 1e-3, 3e-3, 1e-2, 3e-2, 5e-2, 1e-1] {
        c.push(case("dt", dt, Base::Transient, &[format!("time.dt={dt}")]));
    }
    // Integrators at dt = 1e-3 (bdf and sdirk use diffsol's own error control) and at a large step.
    for integ in ["generalized_alpha", "central_difference", "bdf", "sdirk"] {
        for dt in [1e-3, 1e-2, 1e-1] {
            let mut set = vec![format!("time.integrator={integ}"), format!("time.dt={dt}")];
            if integ == "central_difference" {
                set.push("time.mass=lumped".into());
            }
            c.push(case(
                "integrator",
                format!("{integ} dt={dt}"),
                Base::Transient,
                &set,
            ));
        }
    }
    // ω through the critical speed, steady mode (direct Newton at ω, no continuation).
    for omega in [5.0, 10.0, 20.0, 30.0, 38.0, 42.0, 46.0, 50.0, 60.0, 80.0] {
        c.push(case("omega", omega, Base::Steady, &steady_omega(omega)));
    }
    // The same with the smooth (C¹) quadratic compliance of `oden_steady_sweep.toml`.
    for omega in [10.0, 30.0, 42.0, 46.0, 50.0, 60.0] {
        let mut set = steady_omega(omega);
        set.extend(["contact.m_n=2".to_string(), "contact.c_n=2e6".to_string()]);
        c.push(case("omega (m_n=2)", omega, Base::Steady, &set));
    }
    // Arc-length continuation in ω from 10 rad/s through the critical speed (target 60 rad/s):
    // the smooth m_n = 2 of the scene, and the linear penalty whose kink at δ = 0 stops it early.
    c.push(case(
        "omega (continuation)",
        "10 -> 60, m_n=2",
        Base::Sweep,
        &[],
    ));
    c.push(case(
        "omega (continuation)",
        "10 -> 60, m_n=1",
        Base::Sweep,
        &["contact.m_n=1".to_string(), "contact.c_n=2e4".to_string()],
    ));
    // c_n relative to G / (Ro − Ri).
    for rel in [0.1, 1.0, 10.0, 1e2, 1e3, 1e4, 1e5, 1e6] {
        let cn = rel * G / WALL;
        c.push(case(
            "c_n_over_G_h",
            rel,
            Base::Static,
            &[format!("contact.c_n={cn}")],
        ));
    }
    for rel in [1.0, 1e2, 1e4, 1e6] {
        let cn = rel * G / WALL;
        c.push(case(
            "c_n_over_G_h",
            rel,
            Base::Steady,
            &[format!("contact.c_n={cn}")],
        ));
    }
    // κ / G, compressible Mooney–Rivlin, then the incompressible model (perturbed, exact).
    for base in [Base::Static, Base::Steady] {
        for rel in [10.0, 1e2, 1e3, 1e4, 1e5, 1e6] {
            c.push(case(
                "kappa_over_G",
                rel,
                base,
                &[format!("material.kappa={}", rel * G)],
            ));
        }
        for rel in [1e2, 1e4] {
            c.push(Case {
                factor: "kappa_over_G",
                value: format!("{rel} incompressible perturbed"),
                base,
                set: vec![
                    "material.model=mooney_rivlin_incompressible".into(),
                    "material.formulation=perturbed".into(),
                    format!("material.kappa={}", rel * G),
                ],
                drop_keys: vec!["kappa"],
                edits: Vec::new(),
            });
        }
        c.push(Case {
            factor: "kappa_over_G",
            value: "inf (incompressible exact)".into(),
            base,
            set: vec![
                "material.model=mooney_rivlin_incompressible".into(),
                "material.formulation=exact".into(),
            ],
            drop_keys: vec!["kappa"],
            edits: Vec::new(),
        });
    }
    // Friction coefficient.
    for base in [Base::Static, Base::Steady] {
        for mu in [0.0, 0.1, 0.3, 0.5, 1.0] {
            c.push(case("mu", mu, base, &[format!("friction.mu={mu}")]));
        }
    }
    // Regularisation ε relative to the rolling speed v0 (steady; v0 = 19.67 in/s).
    for rel in [1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6] {
        let eps = rel * 10.0 * R_EFF;
        c.push(case(
            "eps_over_v0",
            rel,
            Base::Steady,
            &[format!("friction.eps={eps}")],
        ));
    }
    // Near free rolling (v0 = 21 in/s at ω = 10: hub force x ≈ 0, slip |w| ≲ 0.3 in/s), where
    // a small ε resolves a stick zone; at the scene's v0 = ω R_eff the patch slides everywhere
    // (|w| ≈ 1–2 in/s) and ε hardly matters.
    for rel in [1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6] {
        let eps = rel * 21.0;
        c.push(case(
            "eps_over_v0 (v0=21)",
            rel,
            Base::Steady,
            &["road.v0=21".to_string(), format!("friction.eps={eps}")],
        ));
    }
    for rel in [1e-1, 1e-3, 1e-5] {
        let eps = rel * 10.0 * R_EFF;
        c.push(case(
            "eps_over_v0",
            rel,
            Base::TransientFriction,
            &[format!("friction.eps={eps}")],
        ));
    }
    for mu in [0.0, 1.0] {
        c.push(case(
            "mu",
            mu,
            Base::TransientFriction,
            &[format!("friction.mu={mu}")],
        ));
    }
    // Compliance exponent, c_n scaled so p = G at δ = 0.01 in (p = c_n δ^m_n).
    for base in [Base::Static, Base::Steady] {
        for m in [1, 2, 3] {
            let cn = G / 0.01f64.powi(m);
            c.push(case(
                "m_n",
                m,
                base,
                &[format!("contact.m_n={m}"), format!("contact.c_n={cn}")],
            ));
        }
    }
    // Extremes beyond the sweeps above, to look for panics and non-finite output.
    let ext: [(&str, Base, &[&str]); 9] = [
        ("road.disp=0.5", Base::Static, &["road.disp=0.5"]),
        ("road.disp=0.9", Base::Static, &["road.disp=0.9"]),
        ("c_n=1e12", Base::Static, &["contact.c_n=1e12"]),
        ("kappa=1e10", Base::Static, &["material.kappa=1e10"]),
        (
            "omega=0 v0=0",
            Base::Steady,
            &["motion.omega=0", "road.v0=0"],
        ),
        ("eps=1e-12", Base::Steady, &["friction.eps=1e-12"]),
        (
            "mesh 1 x 8",
            Base::Steady,
            &["mesh.n_r=1", "mesh.n_theta=8"],
        ),
        (
            "b_n=0 rho_inf=1 dt=t_end",
            Base::Transient,
            &["contact.b_n=0", "time.rho_inf=1", "time.dt=0.1"],
        ),
        (
            "central_difference b_n=0 eta=0",
            Base::Transient,
            &[
                "time.integrator=central_difference",
                "time.mass=lumped",
                "contact.b_n=0",
                "time.strain_rate_damping=0",
            ],
        ),
    ];
    for (label, base, set) in ext {
        let set: Vec<String> = set.iter().map(|x| x.to_string()).collect();
        c.push(case("extreme", label, base, &set));
    }
    // Viscoelastic rolling, both models: the scene (γ = G, 10 rad/s, DISP = 0.1), a strong
    // overstress, a high speed, a deep (large-strain) indentation and all three at once. The
    // `viscous` column reports each run's energy balance of the overstress.
    for base in [Base::ViscoConvolution, Base::ViscoMultiplicative] {
        let strong = ("gamma = 200.0", "gamma = 2000.0");
        let fast = |s: &mut Vec<String>| s.extend(steady_omega(40.0));
        let deep = |s: &mut Vec<String>| s.push("road.disp=0.4".into());
        let mut all = Vec::new();
        fast(&mut all);
        deep(&mut all);
        let mut v = vec![
            (
                "scene (gamma = G, omega = 10, disp = 0.1)",
                Vec::new(),
                Vec::new(),
            ),
            ("gamma = 10 G", Vec::new(), vec![strong]),
            (
                "omega = 40",
                {
                    let mut s = Vec::new();
                    fast(&mut s);
                    s
                },
                Vec::new(),
            ),
            (
                "disp = 0.4",
                {
                    let mut s = Vec::new();
                    deep(&mut s);
                    s
                },
                Vec::new(),
            ),
        ];
        v.push(("gamma = 10 G, omega = 40, disp = 0.4", all, vec![strong]));
        for (label, set, edits) in v {
            let model = match base {
                Base::ViscoMultiplicative => "multiplicative",
                _ => "convolution",
            };
            let mut k = case("viscoelastic", format!("{model}: {label}"), base, &set);
            k.edits = edits;
            c.push(k);
        }
    }
    c
}

fn smoke_cases() -> Vec<Case> {
    vec![
        case(
            "dt",
            1e-2,
            Base::Transient,
            &["time.dt=1e-2".into(), "time.t_end=0.02".into()],
        ),
        case(
            "eps_over_v0",
            1e-3,
            Base::TransientFriction,
            &[
                "friction.eps=0.0197".into(),
                "time.dt=1e-2".into(),
                "time.t_end=0.02".into(),
            ],
        ),
        case(
            "integrator",
            "central_difference dt=1e-2",
            Base::Transient,
            &[
                "time.integrator=central_difference".into(),
                "time.mass=lumped".into(),
                "time.dt=1e-2".into(),
                "time.t_end=0.02".into(),
            ],
        ),
        case("omega", 10.0, Base::Steady, &{
            let mut s = steady_omega(10.0);
            s.extend(["mesh.n_theta=32".to_string(), "mesh.n_r=2".to_string()]);
            s
        }),
        case(
            "c_n_over_G_h",
            1e3,
            Base::Static,
            &["contact.c_n=2e5".into()],
        ),
        case(
            "viscoelastic",
            "multiplicative, 0.02 s",
            Base::ViscoMultiplicative,
            &["time.t_end=0.02".into()],
        ),
        case(
            "invalid",
            "mesh.n_r=0",
            Base::Static,
            &["mesh.n_r=0".into()],
        ),
    ]
}

struct Row {
    factor: String,
    value: String,
    scene: String,
    mode: String,
    outcome: &'static str,
    class: String,
    message: String,
    wall: f64,
    nan: usize,
    newton: u64,
    /// Energy balance of the viscous overstress (viscoelastic runs; empty otherwise).
    viscous: String,
}

/// Class of a solve error: its innermost cause when it wraps one.
fn solve_class(e: &SolveError) -> &'static str {
    match e {
        SolveError::Linear(_) => "linear_solver",
        SolveError::NotConverged { .. } => "newton_not_converged",
        SolveError::LineSearch { .. } => "line_search",
        SolveError::KrylovStalled { .. } => "krylov_stalled",
        SolveError::InadmissibleStart => "inadmissible",
        SolveError::ExplicitUnstable { .. } => "explicit_unstable",
        SolveError::Interrupted { .. } => "interrupted",
        SolveError::Integrator { .. } => "integrator",
        SolveError::ContinuationCycles { .. } => "continuation",
        SolveError::ContinuationReversed { .. } => "continuation",
        SolveError::ContinuationStalled { .. } => "continuation",
        SolveError::TooManyCutbacks { last, .. } => solve_class(last),
        SolveError::StepBelowRoundOff { .. } => "step_below_round_off",
        SolveError::TorqueUnreachable { .. } => "torque_unreachable",
    }
}

fn app_class(e: &AppError) -> &'static str {
    match e {
        AppError::Solve(se, _) => solve_class(se),
        AppError::Unsupported(_) => "invalid_input",
        AppError::Output(_) | AppError::OutDir(..) => "output",
        AppError::Interrupted(_) => "interrupted",
        AppError::Failed(..) => "failed",
        AppError::TooBig(_) | AppError::MeshFile(_) => "invalid_input",
    }
}

/// Tokens of `text` that spell a non-finite number (`nan`, `inf`, `infinity`, any case).
fn count_nonfinite(text: &str) -> usize {
    text.split(|c: char| !c.is_ascii_alphanumeric())
        .filter(|t| {
            let t = t.to_ascii_lowercase();
            t == "nan" || t == "inf" || t == "infinity"
        })
        .count()
}

/// Non-finite tokens in `summary.json` and every `*.csv` of `dir`.
fn scan_outputs(dir: &Path) -> usize {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    let mut n = 0;
    for e in entries.flatten() {
        let p = e.path();
        let name = p.file_name().and_then(|s| s.to_str()).unwrap_or("");
        if name == "summary.json" || name.ends_with(".csv") {
            if let Ok(t) = std::fs::read_to_string(&p) {
                n += count_nonfinite(&t);
            }
        }
    }
    n
}

fn count_key(v: &serde_json::Value, path: &[&str]) -> u64 {
    let mut cur = v;
    for k in path {
        match cur.get(k) {
            Some(x) => cur = x,
            None => return 0,
        }
    }
    cur.as_u64().unwrap_or(0)
}

fn one_line(s: &str) -> String {
    let s = s.replace(['\n', '\r'], " ");
    if s.chars().count() > 300 {
        s.chars().take(300).collect::<String>() + "…"
    } else {
        s
    }
}

/// `factor` with every character other than `[A-Za-z0-9_-]` replaced by `_`.
fn dir_name(factor: &str) -> String {
    factor
        .chars()
        .map(|ch| {
            if ch.is_ascii_alphanumeric() || ch == '-' {
                ch
            } else {
                '_'
            }
        })
        .collect()
}

/// `text` without the lines that set one of `keys` (`key = …`, any indentation).
fn drop_keys(text: &str, keys: &[&str]) -> String {
    if keys.is_empty() {
        return text.to_string();
    }
    text.lines()
        .filter(|l| {
            let t = l.trim_start();
            !keys.iter().any(|k| {
                t.strip_prefix(k)
                    .is_some_and(|r| r.trim_start().starts_with('='))
            })
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// What one case's run returned, before it is classified.
enum RunResult {
    /// `app::run` returned `Ok` with this `converged` flag and summary.
    Finished {
        converged: bool,
        summary: serde_json::Value,
    },
    /// The scene was rejected or the run returned a typed error, already classed.
    Failed {
        class: &'static str,
        message: String,
    },
    /// The run panicked (a bug), with the panic message.
    Panicked(String),
}

/// Outcome (`converged`, `recovered`, `failed`, `panic`), failure class and message of a case.
#[derive(Debug, PartialEq)]
struct Outcome {
    outcome: &'static str,
    class: String,
    message: String,
}

/// The outcome of a run: `converged` when Ok with no cut-back and no rejected step,
/// `recovered` when Ok with `solver.cutbacks` or `results.rejected_steps` > 0, `failed` with
/// the error's class, `panic`.
fn classify(r: &RunResult) -> Outcome {
    let out = |outcome, class: &str, message: String| Outcome {
        outcome,
        class: class.to_string(),
        message,
    };
    match r {
        RunResult::Finished { converged, summary } => {
            let cutbacks = count_key(summary, &["solver", "cutbacks"]);
            let rejected = count_key(summary, &["results", "rejected_steps"]);
            if !converged {
                out(
                    "failed",
                    "not_converged_flag",
                    "run returned Ok with converged = false".into(),
                )
            } else if let Some(strategy) = summary["solver"]["recovery"]["strategy"].as_str() {
                // The steady mode's first solve failed and a homotopy found the solution.
                out(
                    "recovered",
                    "",
                    format!(
                        "recovery: {strategy} in {} steps after the failed direct solve ({} attempts, \
                         cutbacks {cutbacks} in all)",
                        summary["results"]["steps"].as_u64().unwrap_or(0),
                        summary["solver"]["recovery"]["attempts"]
                            .as_array()
                            .map_or(0, |a| a.len()),
                    ),
                )
            } else if cutbacks + rejected > 0 {
                out(
                    "recovered",
                    "",
                    format!("cutbacks {cutbacks}, rejected steps {rejected}"),
                )
            } else {
                out("converged", "", String::new())
            }
        }
        RunResult::Failed { class, message } => out("failed", class, one_line(message)),
        RunResult::Panicked(message) => out("panic", "panic", one_line(message)),
    }
}

/// The message of a caught panic (`panic!` with a literal or a formatted string).
fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<String>()
        .cloned()
        .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
        .unwrap_or_else(|| "panic with a non-string payload".into())
}

fn run_case(i: usize, c: &Case, out: &Path) -> Row {
    let dir: PathBuf =
        out.join("cases")
            .join(format!("{i:03}_{}_{}", dir_name(c.factor), c.base.mode()));
    let _ = std::fs::remove_dir_all(&dir);
    let mut text = drop_keys(&c.base.text(), &c.drop_keys);
    for (from, to) in &c.edits {
        text = text.replace(from, to);
    }
    let mut set = c.base.overrides();
    set.extend(c.set.iter().cloned());
    let mut row = Row {
        factor: c.factor.to_string(),
        value: c.value.clone(),
        scene: c.base.file().to_string(),
        mode: c.base.mode().to_string(),
        outcome: "",
        class: String::new(),
        message: String::new(),
        wall: 0.0,
        nan: 0,
        newton: 0,
        viscous: String::new(),
    };
    let t0 = Instant::now();
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let scene = match Scene::from_toml_str(&text, c.base.file(), &set) {
            Ok(s) => s,
            Err(e) => {
                return RunResult::Failed {
                    class: "invalid_input",
                    message: e.to_string(),
                }
            }
        };
        let opts = RunOptions {
            out_dir: dir.clone(),
            verbose: false,
            quiet: true,
        };
        match tread::app::run(&scene, &opts) {
            Ok(o) => RunResult::Finished {
                converged: o.converged,
                summary: o.summary,
            },
            Err(e) => RunResult::Failed {
                class: app_class(&e),
                message: e.to_string(),
            },
        }
    }))
    .unwrap_or_else(|payload| RunResult::Panicked(panic_message(payload.as_ref())));
    row.wall = t0.elapsed().as_secs_f64();
    let o = classify(&result);
    row.outcome = o.outcome;
    row.class = o.class;
    row.message = o.message;
    row.nan = scan_outputs(&dir);
    // Newton iterations from the summary (also written by a failed run).
    row.newton = std::fs::read_to_string(dir.join("summary.json"))
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .map_or(0, |v| count_key(&v, &["newton_iterations"]));
    if let RunResult::Finished { summary, .. } = &result {
        row.viscous = viscous_diagnostic(summary);
    }
    row
}

/// `results.viscous_energy` in one cell: the dissipated energy, the lowest cumulative
/// dissipation and, when the overstress created energy, `ENERGY CREATED`.
fn viscous_diagnostic(summary: &serde_json::Value) -> String {
    let ve = &summary["results"]["viscous_energy"];
    let (Some(d), Some(m)) = (ve["dissipated"].as_f64(), ve["min_dissipated"].as_f64()) else {
        return String::new();
    };
    let mut s = format!("dissipated {d:.4e}, min {m:.2e}");
    if ve["energy_created"].as_bool() == Some(true) {
        s += ", ENERGY CREATED";
    }
    s
}

fn md_cell(s: &str) -> String {
    s.replace('|', "\\|")
}

fn write_reports(rows: &[Row], out: &Path, total_wall: f64) -> std::io::Result<String> {
    let rows_csv = rows.iter().map(|r| {
        vec![
            r.factor.to_string(),
            r.value.to_string(),
            r.scene.to_string(),
            r.mode.to_string(),
            r.outcome.to_string(),
            r.class.to_string(),
            r.message.to_string(),
            format!("{:.3}", r.wall),
            r.nan.to_string(),
            r.newton.to_string(),
            r.viscous.to_string(),
        ]
    });
    tread::io::output::write_text_csv(
        &out.join("stress_matrix.csv"),
        &[
            "factor",
            "value",
            "scene",
            "mode",
            "outcome",
            "class",
            "message",
            "wall_time_s",
            "nan_in_outputs",
            "newton_iterations",
            "viscous_energy",
        ],
        rows_csv,
    )
    .map_err(|e| std::io::Error::other(e.to_string()))?;

    let mut md = String::from("# Stress matrix\n\n");
    md += "| factor | value | scene | mode | outcome | class | wall (s) | NaN/inf in outputs | Newton its | viscous energy | message |\n";
    md += "|---|---|---|---|---|---|---|---|---|---|---|\n";
    for r in rows {
        md += &format!(
            "| {} | {} | {} | {} | {} | {} | {:.2} | {} | {} | {} | {} |\n",
            r.factor,
            md_cell(&r.value),
            r.scene,
            r.mode,
            r.outcome,
            r.class,
            r.wall,
            r.nan,
            r.newton,
            md_cell(&r.viscous),
            md_cell(&r.message)
        );
    }
    let mut outcomes: Vec<(&str, usize)> = Vec::new();
    for o in ["converged", "recovered", "failed", "panic"] {
        outcomes.push((o, rows.iter().filter(|r| r.outcome == o).count()));
    }
    md += "\n| outcome | cases |\n|---|---|\n";
    for (o, n) in &outcomes {
        md += &format!("| {o} | {n} |\n");
    }
    let mut classes: Vec<String> = rows
        .iter()
        .filter(|r| !r.class.is_empty())
        .map(|r| r.class.clone())
        .collect();
    classes.sort();
    classes.dedup();
    md += "\n| failure class | cases |\n|---|---|\n";
    for cl in &classes {
        md += &format!(
            "| {cl} | {} |\n",
            rows.iter().filter(|r| &r.class == cl).count()
        );
    }
    let nan_cases = rows.iter().filter(|r| r.nan > 0).count();
    md += &format!(
        "\n{} cases, {} with NaN/inf text in their outputs, total wall time {:.1} s\n",
        rows.len(),
        nan_cases,
        total_wall
    );
    md += "\nOutcomes: `converged` = Ok with no cut-back and no rejected step; `recovered` = Ok with \
`solver.cutbacks` or `results.rejected_steps` > 0, or after a steady-mode recovery strategy \
(`solver.recovery.strategy`: the direct press failed, a homotopy in κ, ε or ω found the solution) (for `bdf` and `sdirk` the rejected steps are \
diffsol's error-control rejections, part of the normal step-size control); `failed` = a typed \
error, classed by its innermost cause (a load stepping or step halving that gave up is classed by \
the last Newton failure). `converged` means the solver's own criterion was met, not that the answer \
is accurate: compare the summaries (`cases/*/summary.json`) across a sweep.\n";
    std::fs::write(out.join("stress_matrix.md"), &md)?;
    Ok(md)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mut smoke = false;
    let mut factor: Option<String> = None;
    let mut out = PathBuf::from("out/stress");
    let mut i = 1;
    while i < args.len() {
        match args[i].as_str() {
            "--smoke" => smoke = true,
            "--out" if i + 1 < args.len() => {
                out = PathBuf::from(&args[i + 1]);
                i += 1;
            }
            "--factor" if i + 1 < args.len() => {
                factor = Some(args[i + 1].clone());
                i += 1;
            }
            other => {
                eprintln!(
                    "tread-stress: unknown argument `{other}` (use --smoke, --factor NAME and --out DIR)"
                );
                std::process::exit(2);
            }
        }
        i += 1;
    }
    if let Err(e) = std::fs::create_dir_all(&out) {
        eprintln!("tread-stress: cannot create {}: {e}", out.display());
        std::process::exit(2);
    }
    // Panics are caught and counted per case; keep their message on one line.
    std::panic::set_hook(Box::new(|info| {
        eprintln!("tread-stress: panic: {info}");
    }));
    let mut cases = if smoke { smoke_cases() } else { full_cases() };
    if let Some(f) = &factor {
        let known: Vec<&str> = {
            let mut k: Vec<&str> = cases.iter().map(|c| c.factor).collect();
            k.dedup();
            k
        };
        if !known.contains(&f.as_str()) {
            eprintln!(
                "tread-stress: no factor `{f}`; the factors are {}",
                known.join(", ")
            );
            std::process::exit(2);
        }
        cases.retain(|c| c.factor == f);
    }
    let t0 = Instant::now();
    let mut rows = Vec::new();
    for (k, c) in cases.iter().enumerate() {
        let r = run_case(k, c, &out);
        eprintln!(
            "[{:>3}/{}] {} = {} ({}, {}): {} {} {:.2} s{}",
            k + 1,
            cases.len(),
            r.factor,
            r.value,
            r.scene,
            r.mode,
            r.outcome,
            r.class,
            r.wall,
            if r.nan > 0 {
                format!(", {} NaN/inf tokens", r.nan)
            } else {
                String::new()
            }
        );
        rows.push(r);
    }
    match write_reports(&rows, &out, t0.elapsed().as_secs_f64()) {
        Ok(md) => println!("{md}"),
        Err(e) => {
            eprintln!(
                "tread-stress: cannot write the reports in {}: {e}",
                out.display()
            );
            std::process::exit(2);
        }
    }
    let panics = rows.iter().filter(|r| r.outcome == "panic").count();
    let nans = rows.iter().filter(|r| r.nan > 0).count();
    if smoke && (panics > 0 || nans > 0) {
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
    use serde_json::json;
    use tread::io::output::OutputError;
    use tread::solver::LinearError;

    fn finished(converged: bool, summary: serde_json::Value) -> Outcome {
        classify(&RunResult::Finished { converged, summary })
    }

    #[test]
    fn ok_runs_are_converged_or_recovered_from_the_summary() {
        let clean = json!({"solver": {"cutbacks": 0}, "results": {"rejected_steps": 0}});
        let o = finished(true, clean.clone());
        assert_eq!((o.outcome, o.class.as_str()), ("converged", ""));
        // Missing counters count as zero.
        assert_eq!(finished(true, json!({})).outcome, "converged");
        let o = finished(true, json!({"solver": {"cutbacks": 2}}));
        assert_eq!((o.outcome, o.class.as_str()), ("recovered", ""));
        assert_eq!(o.message, "cutbacks 2, rejected steps 0");
        let o = finished(true, json!({"results": {"rejected_steps": 1}}));
        assert_eq!(o.outcome, "recovered");
        assert_eq!(o.message, "cutbacks 0, rejected steps 1");
        // A steady solve saved by a recovery homotopy (no cut-backs needed) is recovered.
        let o = finished(
            true,
            json!({"solver": {"cutbacks": 0, "recovery": {"strategy": "omega_stepping",
                "attempts": [{}, {}]}}, "results": {"steps": 7}}),
        );
        assert_eq!(o.outcome, "recovered");
        assert!(
            o.message.contains("omega_stepping in 7 steps"),
            "{}",
            o.message
        );
        assert!(o.message.contains("2 attempts"), "{}", o.message);
        // A null strategy (recovery tried and failed, run still Ok) is not a recovery.
        let o = finished(true, json!({"solver": {"recovery": {"strategy": null}}}));
        assert_eq!(o.outcome, "converged");
        // Ok with converged = false is a failure, whatever the counters say.
        let o = finished(false, clean);
        assert_eq!(
            (o.outcome, o.class.as_str()),
            ("failed", "not_converged_flag")
        );
    }

    #[test]
    fn errors_and_panics_are_failed_with_their_class() {
        let o = classify(&RunResult::Failed {
            class: "line_search",
            message: "line search failed\nsecond line".into(),
        });
        assert_eq!(o.outcome, "failed");
        assert_eq!(o.class, "line_search");
        assert_eq!(o.message, "line search failed second line");
        let o = classify(&RunResult::Panicked("index out of bounds".into()));
        assert_eq!((o.outcome, o.class.as_str()), ("panic", "panic"));
        // Panic payloads: a literal, a formatted string, anything else.
        let msg = |f: fn()| {
            let p = std::panic::catch_unwind(f).unwrap_err();
            panic_message(p.as_ref())
        };
        // (The default hook prints these three panics into the test's captured output.)
        let literal = msg(|| panic!("literal"));
        let formatted = msg(|| panic!("formatted {}", 42));
        let other = msg(|| std::panic::panic_any(7u32));
        assert_eq!(literal, "literal");
        assert_eq!(formatted, "formatted 42");
        assert_eq!(other, "panic with a non-string payload");
    }

    #[test]
    fn typed_errors_map_to_their_class_innermost_first() {
        let cases: Vec<(SolveError, &str)> = vec![
            (SolveError::Linear(LinearError::Singular), "linear_solver"),
            (
                SolveError::NotConverged {
                    iterations: 25,
                    residual: 1e-3,
                    stagnation: None,
                },
                "newton_not_converged",
            ),
            (
                SolveError::LineSearch {
                    min_alpha: 1.0 / 64.0,
                    residual: 0.5,
                },
                "line_search",
            ),
            (SolveError::InadmissibleStart, "inadmissible"),
            (
                SolveError::ExplicitUnstable {
                    t: 0.1,
                    dt: 1e-2,
                    dt_stable: 1e-4,
                },
                "explicit_unstable",
            ),
            (SolveError::Interrupted { at: 0.5 }, "interrupted"),
            (
                SolveError::Integrator {
                    t: 0.1,
                    message: "step size too small".into(),
                },
                "integrator",
            ),
            (
                SolveError::ContinuationCycles { lambda: 40.0 },
                "continuation",
            ),
            (
                SolveError::ContinuationReversed { lambda: 40.0 },
                "continuation",
            ),
            (
                SolveError::ContinuationStalled {
                    lambda: 45.7,
                    cutbacks: 8,
                    last: Box::new(SolveError::LineSearch {
                        min_alpha: 0.1,
                        residual: 1.0,
                    }),
                },
                "continuation",
            ),
            // Load stepping that gave up: the class of the last Newton failure, nested or not.
            (
                SolveError::TooManyCutbacks {
                    lambda: 0.3,
                    cutbacks: 10,
                    last: Box::new(SolveError::LineSearch {
                        min_alpha: 0.1,
                        residual: 1.0,
                    }),
                },
                "line_search",
            ),
            (
                SolveError::TooManyCutbacks {
                    lambda: 0.3,
                    cutbacks: 10,
                    last: Box::new(SolveError::TooManyCutbacks {
                        lambda: 0.2,
                        cutbacks: 3,
                        last: Box::new(SolveError::InadmissibleStart),
                    }),
                },
                "inadmissible",
            ),
        ];
        for (e, class) in cases {
            assert_eq!(solve_class(&e), class, "{e}");
            let app = AppError::Solve(e, PathBuf::from("out"));
            assert_eq!(app_class(&app), class);
        }
        assert_eq!(
            app_class(&AppError::Unsupported("m_n".into())),
            "invalid_input"
        );
        let io = OutputError {
            path: PathBuf::from("x.csv"),
            source: std::io::Error::other("disk full"),
        };
        assert_eq!(app_class(&AppError::Output(io)), "output");
        assert_eq!(
            app_class(&AppError::Interrupted(PathBuf::from("out"))),
            "interrupted"
        );
    }

    #[test]
    fn nonfinite_tokens_are_counted_in_summary_and_csv_only() {
        assert_eq!(count_nonfinite("1.0,NaN,-inf,+Infinity,nan"), 4);
        // Words that merely contain the letters are not numbers.
        assert_eq!(count_nonfinite("info,nano,infinite_loop,finance,1e-3"), 0);
        let dir = TestDir::new("stress-test", "scan");
        std::fs::write(dir.join("clean.csv"), "t,x\n0.0,1.5e-3\n1.0,2.0\n").unwrap();
        assert_eq!(scan_outputs(&dir), 0);
        // A NaN planted in a CSV, an inf in summary.json: both found.
        std::fs::write(dir.join("history.csv"), "t,x\n0.0,1.0\n1.0,NaN\n").unwrap();
        assert_eq!(scan_outputs(&dir), 1);
        std::fs::write(dir.join("summary.json"), "{\"residual\": inf}").unwrap();
        assert_eq!(scan_outputs(&dir), 2);
        // Other files are not scanned.
        std::fs::write(dir.join("notes.txt"), "NaN NaN").unwrap();
        assert_eq!(scan_outputs(&dir), 2);
        // A missing directory (a case that wrote nothing) has nothing to scan.
        assert_eq!(scan_outputs(&dir.join("missing")), 0);
    }

    #[test]
    fn drop_keys_removes_only_the_named_keys() {
        let text = "[material]\nkappa = 2e4\n  kappa=3\nkappa_x = 1\nmu = 2\n";
        assert_eq!(
            drop_keys(text, &["kappa"]),
            "[material]\nkappa_x = 1\nmu = 2"
        );
        assert_eq!(drop_keys(text, &[]), text);
    }

    fn row(factor: &str, value: &str, outcome: &'static str, class: &str, message: &str) -> Row {
        Row {
            factor: factor.into(),
            value: value.into(),
            scene: "oden_hollow_cylinder".into(),
            mode: "steady".into(),
            outcome,
            class: class.into(),
            message: message.into(),
            wall: 0.25,
            nan: 0,
            newton: 12,
            viscous: String::new(),
        }
    }

    #[test]
    fn viscous_energy_cell_flags_created_energy() {
        let summary = |created: bool| {
            serde_json::json!({"results": {"viscous_energy": {
                "dissipated": 12.5, "min_dissipated": if created { -0.5 } else { 0.0 },
                "energy_created": created}}})
        };
        assert_eq!(
            viscous_diagnostic(&summary(false)),
            "dissipated 1.2500e1, min 0.00e0"
        );
        assert!(viscous_diagnostic(&summary(true)).ends_with(", ENERGY CREATED"));
        assert_eq!(viscous_diagnostic(&serde_json::json!({"results": {}})), "");
    }

    /// Fields of one CSV line (RFC 4180 quoting, no embedded newlines).
    fn csv_fields(line: &str) -> Vec<String> {
        let (mut fields, mut cur, mut quoted) = (Vec::new(), String::new(), false);
        let mut chars = line.chars().peekable();
        while let Some(ch) = chars.next() {
            match ch {
                '"' if quoted && chars.peek() == Some(&'"') => {
                    cur.push('"');
                    chars.next();
                }
                '"' => quoted = !quoted,
                ',' if !quoted => fields.push(std::mem::take(&mut cur)),
                _ => cur.push(ch),
            }
        }
        fields.push(cur);
        fields
    }

    /// The `| name | n |` rows of the Markdown table under `header`.
    fn md_counts(md: &str, header: &str) -> Vec<(String, usize)> {
        let lines: Vec<&str> = md.lines().collect();
        let start = lines.iter().position(|l| *l == header).unwrap() + 2;
        lines[start..]
            .iter()
            .take_while(|l| l.starts_with('|'))
            .map(|l| {
                let c: Vec<&str> = l.trim_matches('|').split('|').map(str::trim).collect();
                (c[0].to_string(), c[1].parse().unwrap())
            })
            .collect()
    }

    /// Rows of the CSV, the Markdown counts per outcome and class and its case table agree.
    fn check_reports(dir: &Path, n_rows: usize) {
        let csv = std::fs::read_to_string(dir.join("stress_matrix.csv")).unwrap();
        let md = std::fs::read_to_string(dir.join("stress_matrix.md")).unwrap();
        let mut lines = csv.lines();
        let header = csv_fields(lines.next().unwrap());
        assert_eq!(
            header,
            [
                "factor",
                "value",
                "scene",
                "mode",
                "outcome",
                "class",
                "message",
                "wall_time_s",
                "nan_in_outputs",
                "newton_iterations",
                "viscous_energy"
            ]
        );
        let rows: Vec<Vec<String>> = lines.map(csv_fields).collect();
        assert_eq!(rows.len(), n_rows);
        assert!(rows.iter().all(|r| r.len() == header.len()), "{rows:?}");
        let count = |col: usize, v: &str| rows.iter().filter(|r| r[col] == v).count();
        let outcomes = md_counts(&md, "| outcome | cases |");
        assert_eq!(outcomes.len(), 4);
        for (o, n) in &outcomes {
            assert_eq!(*n, count(4, o), "outcome {o}");
        }
        assert_eq!(outcomes.iter().map(|(_, n)| n).sum::<usize>(), n_rows);
        let classes = md_counts(&md, "| failure class | cases |");
        let mut csv_classes: Vec<&str> = rows
            .iter()
            .map(|r| r[5].as_str())
            .filter(|c| !c.is_empty())
            .collect();
        csv_classes.sort();
        csv_classes.dedup();
        assert_eq!(
            classes.iter().map(|(c, _)| c.as_str()).collect::<Vec<_>>(),
            csv_classes
        );
        for (c, n) in &classes {
            assert_eq!(*n, count(5, c), "class {c}");
        }
        // One Markdown row per case (pipes in values are escaped).
        let table = md
            .lines()
            .skip_while(|l| !l.starts_with("| factor |"))
            .skip(2)
            .take_while(|l| l.starts_with('|'))
            .count();
        assert_eq!(table, n_rows);
        let nan_cases = rows.iter().filter(|r| r[8] != "0").count();
        assert!(
            md.contains(&format!(
                "{n_rows} cases, {nan_cases} with NaN/inf text in their outputs"
            )),
            "{md}"
        );
    }

    #[test]
    fn markdown_counts_equal_the_csv_rows() {
        let mut nan_row = row("extreme", "c_n=1e12", "converged", "", "");
        nan_row.nan = 3;
        let rows = vec![
            row("omega", "10", "converged", "", ""),
            row("omega", "60", "failed", "line_search", "line search failed"),
            // A comma and quotes in the value and message: one CSV row still.
            row(
                "omega (continuation)",
                "10 -> 60, m_n=2",
                "failed",
                "continuation",
                "gave up at \"45.7\", after 8 cut-backs",
            ),
            row("dt", "0.1", "recovered", "", "cutbacks 2, rejected steps 0"),
            row("kappa_over_G", "a|b", "failed", "line_search", "x | y"),
            row(
                "extreme",
                "eps=1e-12",
                "panic",
                "panic",
                "index out of bounds",
            ),
            nan_row,
        ];
        let dir = TestDir::new("stress-test", "reports");
        let md = write_reports(&rows, &dir, 1.5).unwrap();
        assert_eq!(
            md,
            std::fs::read_to_string(dir.join("stress_matrix.md")).unwrap()
        );
        check_reports(&dir, rows.len());
        let classes = md_counts(&md, "| failure class | cases |");
        assert_eq!(
            classes,
            [
                ("continuation".to_string(), 1),
                ("line_search".to_string(), 2),
                ("panic".to_string(), 1)
            ]
        );
    }

    /// A few cases through the library path (scene text + overrides → `app::run` → outcome,
    /// NaN scan, reports): an invalid scene, a static solve that converges, and one whose
    /// Newton is cut to one iteration so that load stepping gives up.
    #[test]
    fn tiny_matrix_end_to_end() {
        let cases = [
            case(
                "invalid",
                "mesh.n_r=0",
                Base::Static,
                &["mesh.n_r=0".into()],
            ),
            case(
                "c_n_over_G_h",
                1e3,
                Base::Static,
                &[
                    "contact.c_n=2e5".into(),
                    "mesh.n_r=2".into(),
                    "mesh.n_theta=32".into(),
                ],
            ),
            case(
                "solver",
                "max_iterations=1",
                Base::Static,
                &[
                    "mesh.n_r=2".into(),
                    "mesh.n_theta=32".into(),
                    "solver.max_iterations=1".into(),
                    "solver.max_cutbacks=1".into(),
                ],
            ),
        ];
        let dir = TestDir::new("stress-test", "e2e");
        let rows: Vec<Row> = cases
            .iter()
            .enumerate()
            .map(|(i, c)| run_case(i, c, &dir))
            .collect();
        let got: Vec<(&str, &str)> = rows.iter().map(|r| (r.outcome, r.class.as_str())).collect();
        assert_eq!(
            got,
            [
                ("failed", "invalid_input"),
                ("converged", ""),
                ("failed", "newton_not_converged")
            ],
            "{:?}",
            rows.iter().map(|r| &r.message).collect::<Vec<_>>()
        );
        assert!(rows[0].message.contains("n_r"), "{}", rows[0].message);
        assert!(rows[1].newton > 0);
        assert!(rows.iter().all(|r| r.nan == 0));
        assert!(dir
            .join("cases/001_c_n_over_G_h_static/summary.json")
            .exists());
        write_reports(&rows, &dir, 0.0).unwrap();
        check_reports(&dir, rows.len());
    }
}
