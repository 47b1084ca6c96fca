//! Model-problem scenes: the adaptive model problems of `src/adapt/` run from a TOML file like
//! the rolling scenes (`tread run scenarios/model_problems/cavity.toml`).
//!
//! A scene is a model-problem scene when it has a `[problem]` table; it then has only three
//! sections:
//!
//! ```toml
//! [scene]    name, description = ""
//! [problem]  kind = "cavity" | "heat" | "burgers" | "p_navier_stokes" | "lshape",
//!            and the keys of that kind (every one optional, with the defaults of [`KEYS`])
//! [output]   sinks = ["summary", "csv", "vtu", "png"] (and "rerun")
//! ```
//!
//! The keys of every kind, with type, default, unit and meaning, are the table [`KEYS`]; it is
//! also the reference in `docs/reference.md` ([`markdown_reference`]). Loading collects every
//! problem at once (unknown sections and keys, keys of another kind, wrong types, out-of-range
//! values) as [`SceneErrors`] naming the dotted key (`problem.reynolds`) and its line, or
//! `(--set)` for a value from an override, as the rolling scenes do. `--set problem.key=value`,
//! `--set scene.name=...` and `--set output.sinks=summary,csv` apply before the checks.
//!
//! The problems (the drivers are in `crate::driver::model_problem`):
//! * `cavity`: the lid-driven cavity on [0, 1]² (Navier–Stokes, Q2/Q1, ν = 1/Re), Newton by
//!   continuation over Re = 100 → 400 → 1000 up to `reynolds`, on the uniform 2^levels ×
//!   2^levels mesh or with `recalculations` moving-mesh relocations at the final Re
//!   (`crate::adapt::moving_mesh`);
//! * `heat`: the rotating Gaussian hill (convection–diffusion with SUPG, Crank–Nicolson), on the
//!   square (−1, 1)², with the two-grid adaptive h-method (`crate::adapt::two_grid`);
//! * `burgers`: the vector Burgers equations on the unit square with the Cole–Hopf solution,
//!   same method;
//! * `p_navier_stokes`: the p-method for Navier–Stokes, steady Kovasznay flow (12 cells of side
//!   1/2 on [−0.5, 1] × [−0.5, 1.5]) or the transient Taylor–Green vortex (25 cells on the unit
//!   square, Crank–Nicolson), estimate by enrichment (`crate::adapt::p_navier_stokes`);
//! * `lshape`: −Δu = 0 on the L-shape with u = r^{2/3} sin(2θ/3), the loop solve → estimate →
//!   mark → refine (h, p, hp) → transfer (`crate::adapt::driver`).

use super::errors::{SceneError, SceneErrors, OVERRIDE_TAG};
use super::output::Sink;
use super::spans::Locator;
use serde::Serialize;
use std::collections::BTreeSet;
use std::path::Path;

keyword_enum! {
    /// Which model problem a scene runs (`problem.kind`).
    ProblemKind, "problem kind" {
        /// Lid-driven cavity (Navier–Stokes), uniform or moving mesh.
        Cavity => "cavity",
        /// Rotating hill (convection-dominated heat), two-grid adaptive h-method.
        Heat => "heat",
        /// Vector Burgers (Cole–Hopf), two-grid adaptive h-method.
        Burgers => "burgers",
        /// p-method for Navier–Stokes (Kovasznay or Taylor–Green).
        PNavierStokes => "p_navier_stokes",
        /// L-shape Poisson problem, adaptive h, p or hp.
        LShape => "lshape",
    }
}

keyword_enum! {
    /// Lid of the driven cavity (`problem.lid`).
    Lid, "cavity lid" {
        /// U = 1 on the open top edge, 0 at the top corners.
        Standard => "standard",
        /// U = 16 x² (1 − x)².
        Regularised => "regularised",
    }
}

keyword_enum! {
    /// Mesh of the driven cavity (`problem.mesh`).
    CavityMesh, "cavity mesh" {
        /// The uniform mesh.
        Uniform => "uniform",
        /// The uniform mesh, then node relocations (r-adaptivity).
        Moving => "moving",
    }
}

keyword_enum! {
    /// Flow of the p-method (`problem.flow`).
    Flow, "flow" {
        /// Steady Kovasznay flow.
        Kovasznay => "kovasznay",
        /// Transient Taylor–Green vortex.
        TaylorGreen => "taylor_green",
    }
}

keyword_enum! {
    /// Refinement of the L-shape loop (`problem.refinement`).
    LRefinement, "refinement" {
        H => "h",
        P => "p",
        Hp => "hp",
    }
}

keyword_enum! {
    /// Estimator of the L-shape loop (`problem.estimator`).
    LEstimator, "estimator" {
        Explicit => "explicit",
        Equilibrated => "equilibrated",
        Recovery => "recovery",
        Interpolation => "interpolation",
    }
}

/// `problem.kind = "cavity"`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CavitySpec {
    pub reynolds: f64,
    pub lid: Lid,
    pub mesh: CavityMesh,
    pub levels: u32,
    pub recalculations: usize,
    pub alpha: f64,
    pub beta: f64,
    pub gamma: f64,
    pub tolerance: f64,
}

/// Time stepping and adaptation of `heat` and `burgers`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TwoGridSpec {
    pub degree: u8,
    pub dt: f64,
    pub steps: usize,
    pub adaptive: bool,
    pub levels: u32,
    pub min_level: u32,
    pub max_level: u32,
    pub dorfler: f64,
    pub coarsen: f64,
    pub initial_sweeps: usize,
}

/// `problem.kind = "heat"`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HeatSpec {
    #[serde(flatten)]
    pub time: TwoGridSpec,
    pub kappa: f64,
    pub sigma2: f64,
    pub centre: [f64; 2],
    pub supg: bool,
}

/// `problem.kind = "burgers"`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BurgersSpec {
    #[serde(flatten)]
    pub time: TwoGridSpec,
    pub nu: f64,
}

/// `problem.kind = "p_navier_stokes"`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PnsSpec {
    pub flow: Flow,
    pub degree: usize,
    pub tolerance: f64,
    pub enrich: usize,
    pub max_degree: usize,
    pub max_sweeps: usize,
    /// Kovasznay only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reynolds: Option<f64>,
    /// Taylor–Green only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub nu: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dt: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub steps: Option<usize>,
}

/// `problem.kind = "lshape"`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LShapeSpec {
    pub degree: u8,
    pub refinement: LRefinement,
    pub estimator: LEstimator,
    pub dorfler: f64,
    pub max_dofs: usize,
    pub max_steps: usize,
    pub initial_levels: u32,
    pub max_degree: usize,
    pub uniform: bool,
}

/// The problem of a model-problem scene, resolved (every default filled).
#[derive(Clone, Debug, PartialEq)]
pub enum Problem {
    Cavity(CavitySpec),
    Heat(HeatSpec),
    Burgers(BurgersSpec),
    PNavierStokes(PnsSpec),
    LShape(LShapeSpec),
}

impl Problem {
    pub fn kind(&self) -> ProblemKind {
        match self {
            Problem::Cavity(_) => ProblemKind::Cavity,
            Problem::Heat(_) => ProblemKind::Heat,
            Problem::Burgers(_) => ProblemKind::Burgers,
            Problem::PNavierStokes(_) => ProblemKind::PNavierStokes,
            Problem::LShape(_) => ProblemKind::LShape,
        }
    }
}

/// A model-problem scene, resolved.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelScene {
    pub name: String,
    pub description: String,
    pub problem: Problem,
    pub sinks: Vec<Sink>,
}

/// Type of a key of [`KEYS`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum KeyType {
    Float,
    Int,
    Bool,
    /// One of these words.
    Word(&'static [&'static str]),
    /// Two numbers `[x, y]`.
    Point,
}

impl KeyType {
    fn describe(self) -> String {
        match self {
            KeyType::Float => "number".into(),
            KeyType::Int => "integer".into(),
            KeyType::Bool => "boolean".into(),
            KeyType::Word(w) => format!("one of {}", super::issue::quoted_list(w)),
            KeyType::Point => "two numbers [x, y]".into(),
        }
    }
}

/// One key of `[problem]`.
#[derive(Clone, Copy, Debug)]
pub struct KeyDoc {
    pub key: &'static str,
    /// The kinds that use it.
    pub kinds: &'static [ProblemKind],
    pub ty: KeyType,
    pub default: &'static str,
    pub unit: &'static str,
    pub doc: &'static str,
}

use ProblemKind as PK;
const CAV: &[ProblemKind] = &[PK::Cavity];
const TWO: &[ProblemKind] = &[PK::Heat, PK::Burgers];
const HEAT: &[ProblemKind] = &[PK::Heat];
const PNS: &[ProblemKind] = &[PK::PNavierStokes];
const LSH: &[ProblemKind] = &[PK::LShape];
const CAV_PNS: &[ProblemKind] = &[PK::Cavity, PK::PNavierStokes];
const PNS_LSH: &[ProblemKind] = &[PK::PNavierStokes, PK::LShape];
const TWO_PNS: &[ProblemKind] = &[PK::Heat, PK::Burgers, PK::PNavierStokes];
const TWO_PNS_LSH: &[ProblemKind] = &[PK::Heat, PK::Burgers, PK::PNavierStokes, PK::LShape];
const TWO_LSH: &[ProblemKind] = &[PK::Heat, PK::Burgers, PK::LShape];
const BURG_PNS: &[ProblemKind] = &[PK::Burgers, PK::PNavierStokes];
const N: &str = "–";

const fn key(
    key: &'static str,
    kinds: &'static [ProblemKind],
    ty: KeyType,
    default: &'static str,
    unit: &'static str,
    doc: &'static str,
) -> KeyDoc {
    KeyDoc {
        key,
        kinds,
        ty,
        default,
        unit,
        doc,
    }
}

/// Every key of `[problem]` besides `kind`. Lengths, times and velocities are those of the
/// non-dimensional problems (the unit square, lid speed 1).
pub static KEYS: &[KeyDoc] = &[
    key("reynolds", CAV_PNS, KeyType::Float, "cavity: 1000; Kovasznay: 40", N,
        "Reynolds number: cavity 100, 400 or 1000 (reached by continuation 100 → 400 → 1000), ν = 1/Re; Kovasznay flow (flow = \"kovasznay\" only), any Re > 0"),
    key("lid", CAV, KeyType::Word(Lid::NAMES), "\"standard\"", N,
        "\"standard\": U = 1 on the open lid (the reference tables of Ghia et al. and Botella & Peyret apply); \"regularised\": U = 16 x² (1 − x)² (no reference)"),
    key("mesh", CAV, KeyType::Word(CavityMesh::NAMES), "\"moving\"", N,
        "\"uniform\": the 2^levels × 2^levels mesh; \"moving\": the same cells relocated `recalculations` times (r-adaptivity)"),
    key("levels", CAV, KeyType::Int, "4", N, "cavity: uniform refinements of the unit square, 1–7 (2^levels cells per side)"),
    key("recalculations", CAV, KeyType::Int, "8", N, "moving mesh: relocations, each followed by a Newton solve at the final Re (0–50)"),
    key("alpha", CAV, KeyType::Float, "4", N, "moving mesh: monitor amplitude α ≥ 0 (M = 1 + α ê^{1/β})"),
    key("beta", CAV, KeyType::Float, "4", N, "moving mesh: root β ≥ 1 of the normalised gradient indicator ê"),
    key("gamma", CAV, KeyType::Float, "0", N, "moving mesh: weight γ ∈ [0, 1] of the uniform part of the edge weights"),
    key("tolerance", CAV_PNS, KeyType::Float, "cavity: 1e-10; Kovasznay: 1e-5; Taylor–Green: 1e-4", N,
        "cavity: Newton tolerance on the residual; p_navier_stokes: tolerance τ on the L² velocity estimate (cell K is raised when η_K > τ (|K|/|Ω|)^{1/2})"),
    key("degree", TWO_PNS_LSH, KeyType::Int, "heat, burgers, lshape: 1; p_navier_stokes: 2", N,
        "polynomial degree: heat and burgers 1 or 2 (Lagrange); p_navier_stokes the initial velocity degree 2–8 of every cell; lshape 1 or 2 for h (Lagrange), 1–8 for p and hp (hierarchical)"),
    key("dt", TWO_PNS, KeyType::Float, "heat: 0.02; burgers: 0.01; Taylor–Green: 0.02", "T", "time step (Crank–Nicolson)"),
    key("steps", TWO_PNS, KeyType::Int, "heat: 25; burgers: 10; Taylor–Green: 5", N, "number of time steps"),
    key("adaptive", TWO, KeyType::Bool, "true", N, "adapt the mesh between steps by the two-grid estimate (false: fixed mesh, estimate only)"),
    key("levels", TWO, KeyType::Int, "4", N, "heat, burgers: uniform refinements of the initial mesh (1–9)"),
    key("min_level", TWO, KeyType::Int, "3", N, "coarsest level a cell may be coarsened to"),
    key("max_level", TWO, KeyType::Int, "7", N, "finest level a cell may be refined to (≤ 10)"),
    key("dorfler", TWO_LSH, KeyType::Float, "heat, burgers: 0.7; lshape: 0.5", N, "Dörfler fraction θ ∈ (0, 1] of the squared indicators marked for refinement"),
    key("coarsen", TWO, KeyType::Float, "0.01", N, "coarsen cells with η_K² below this fraction of the mean η² (≥ 0)"),
    key("initial_sweeps", TWO, KeyType::Int, "8", N, "repetitions of the first step so that the initial mesh resolves u₀ (1–20)"),
    key("kappa", HEAT, KeyType::Float, "0.001", "L²/T", "diffusivity κ"),
    key("sigma2", HEAT, KeyType::Float, "0.01", "L²", "initial width σ² of the hill u₀ = exp(−|x − c₀|²/σ²)"),
    key("centre", HEAT, KeyType::Point, "[0.5, 0.0]", "L", "initial centre c₀ of the hill (inside (−1, 1)²)"),
    key("supg", HEAT, KeyType::Bool, "true", N, "SUPG stabilisation (false: plain Galerkin)"),
    key("nu", BURG_PNS, KeyType::Float, "0.01", "L²/T", "viscosity ν (burgers: of the Cole–Hopf solution; p_navier_stokes: Taylor–Green only)"),
    key("flow", PNS, KeyType::Word(Flow::NAMES), "\"kovasznay\"", N, "\"kovasznay\" (steady, Re = reynolds) or \"taylor_green\" (transient, ν = nu)"),
    key("enrich", PNS, KeyType::Int, "2", N, "degree increment of the enriched solve of the estimate (1 or 2)"),
    key("max_degree", PNS_LSH, KeyType::Int, "8", N, "largest degree a cell is raised to (p_navier_stokes: max_degree + enrich ≤ 10; lshape p/hp: ≤ 10)"),
    key("max_sweeps", PNS, KeyType::Int, "10", N, "largest number of solves (steady: in total; transient: per step), 1–50"),
    key("refinement", LSH, KeyType::Word(LRefinement::NAMES), "\"h\"", N, "\"h\" (split), \"p\" (raise the degree) or \"hp\" (raise where the solution is smooth, else split)"),
    key("estimator", LSH, KeyType::Word(LEstimator::NAMES), "\"explicit\"", N, "the estimator that drives the marking"),
    key("max_dofs", LSH, KeyType::Int, "20000", N, "stop after the first mesh with more equations than this (10–2000000)"),
    key("max_steps", LSH, KeyType::Int, "60", N, "largest number of meshes (1–200)"),
    key("initial_levels", LSH, KeyType::Int, "1", N, "uniform refinements of the three-square L-shape before the first solve (0–8)"),
    key("uniform", LSH, KeyType::Bool, "false", N, "refine every cell instead of marking (the reference run)"),
];

/// Keys of `[scene]`.
const SCENE_KEYS: &[&str] = &["name", "description"];
/// Sinks a model problem writes (`rerun`: in builds with the `rerun` feature).
const SINKS: &[Sink] = &[Sink::Summary, Sink::Csv, Sink::Vtu, Sink::Png, Sink::Rerun];
/// Default of `[output] sinks` (the Rerun recording is opt-in, as in the rolling scenes).
const DEFAULT_SINKS: &[Sink] = &[Sink::Summary, Sink::Csv, Sink::Vtu, Sink::Png];

/// Whether a scene text is a model-problem scene (it has a `[problem]` table). A text that is
/// not TOML is not (the rolling loader then reports its syntax error).
pub fn is_model_problem(text: &str) -> bool {
    matches!(
        text.parse::<toml::Table>()
            .ok()
            .as_ref()
            .and_then(|t| t.get("problem")),
        Some(toml::Value::Table(_))
    )
}

/// Whether a `--set` list turns a scene into a model problem (`problem.kind=...`).
pub fn overrides_set_problem(overrides: &[String]) -> bool {
    overrides
        .iter()
        .any(|o| o.trim_start().starts_with("problem."))
}

struct Loader<'a> {
    source_name: &'a str,
    locator: Locator,
    overridden: BTreeSet<String>,
    errors: Vec<SceneError>,
}

impl Loader<'_> {
    fn push(&mut self, key: &str, message: impl Into<String>) {
        let over = self.overridden.contains(key);
        self.errors.push(SceneError {
            key: key.to_string(),
            line: if over { None } else { self.locator.locate(key) },
            message: message.into(),
            source_name: if over {
                format!("{}{OVERRIDE_TAG}", self.source_name)
            } else {
                self.source_name.to_string()
            },
        });
    }

    fn push_override(&mut self, key: &str, message: impl Into<String>) {
        self.errors.push(SceneError {
            key: key.to_string(),
            line: None,
            message: message.into(),
            source_name: format!("{}{OVERRIDE_TAG}", self.source_name),
        });
    }

    fn apply_overrides(&mut self, doc: &mut toml::Table, overrides: &[String]) {
        for ov in overrides {
            let Some((raw_key, raw_value)) = ov.split_once('=') else {
                self.push_override(
                    ov.trim(),
                    format!("malformed override `{ov}`: expected `section.key=value`"),
                );
                continue;
            };
            let key = raw_key.trim();
            let Some((sec, field)) = key.split_once('.') else {
                self.push_override(
                    key,
                    format!("malformed override `{ov}`: the key must be `section.key`"),
                );
                continue;
            };
            if !matches!(sec, "scene" | "problem" | "output") || field.contains('.') {
                self.push_override(
                    key,
                    format!(
                        "unknown key in override `{ov}`: a model-problem scene has the keys \
                         scene.*, problem.* and output.sinks"
                    ),
                );
                continue;
            }
            let raw = raw_value.trim();
            let word = sec == "scene"
                || (sec == "problem"
                    && (field == "kind"
                        || KEYS
                            .iter()
                            .any(|k| k.key == field && matches!(k.ty, KeyType::Word(_)))));
            let parsed = format!("v = {raw}")
                .parse::<toml::Table>()
                .ok()
                .and_then(|mut t| t.remove("v"));
            let value = match parsed {
                Some(v @ toml::Value::String(_)) => v,
                _ if word => toml::Value::String(raw.to_string()),
                Some(v @ toml::Value::Array(_)) => v,
                _ if sec == "output" => toml::Value::Array(
                    raw.split(',')
                        .map(|w| toml::Value::String(w.trim().trim_matches('"').to_string()))
                        .collect(),
                ),
                Some(v) => v,
                None => toml::Value::String(raw.to_string()),
            };
            match doc
                .entry(sec.to_string())
                .or_insert_with(|| toml::Value::Table(toml::Table::new()))
            {
                toml::Value::Table(t) => {
                    t.insert(field.to_string(), value);
                    self.overridden.insert(key.to_string());
                }
                _ => self.push_override(key, format!("`{sec}` in the file is not a table")),
            }
        }
    }
}

/// What a `[problem]` key holds.
fn type_ok(v: &toml::Value, ty: KeyType) -> bool {
    match (ty, v) {
        (KeyType::Float, toml::Value::Float(_) | toml::Value::Integer(_)) => true,
        (KeyType::Int, toml::Value::Integer(i)) => *i >= 0,
        (KeyType::Bool, toml::Value::Boolean(_)) => true,
        (KeyType::Word(w), toml::Value::String(s)) => w.contains(&s.as_str()),
        (KeyType::Point, toml::Value::Array(a)) => {
            a.len() == 2
                && a.iter()
                    .all(|x| matches!(x, toml::Value::Float(_) | toml::Value::Integer(_)))
        }
        _ => false,
    }
}

fn as_f64(v: &toml::Value) -> f64 {
    match v {
        toml::Value::Float(f) => *f,
        toml::Value::Integer(i) => *i as f64,
        _ => f64::NAN,
    }
}

/// The typed values of `[problem]` for one kind: every written key of the kind, checked.
struct Values<'a> {
    table: &'a toml::Table,
}

impl Values<'_> {
    fn has(&self, k: &str) -> bool {
        self.table.contains_key(k)
    }
    fn f(&self, k: &str, default: f64) -> f64 {
        self.table.get(k).map_or(default, as_f64)
    }
    fn i(&self, k: &str, default: usize) -> usize {
        match self.table.get(k) {
            Some(toml::Value::Integer(i)) => usize::try_from(*i).unwrap_or(usize::MAX),
            _ => default,
        }
    }
    fn b(&self, k: &str, default: bool) -> bool {
        match self.table.get(k) {
            Some(toml::Value::Boolean(b)) => *b,
            _ => default,
        }
    }
    fn w<T: std::str::FromStr>(&self, k: &str, default: T) -> T {
        match self.table.get(k) {
            Some(toml::Value::String(s)) => s.parse().unwrap_or(default),
            _ => default,
        }
    }
    fn point(&self, k: &str, default: [f64; 2]) -> [f64; 2] {
        match self.table.get(k) {
            Some(toml::Value::Array(a)) if a.len() == 2 => [as_f64(&a[0]), as_f64(&a[1])],
            _ => default,
        }
    }
}

/// A range check: `ok`, else an error on `problem.<k>` saying what is allowed.
fn check(l: &mut Loader, k: &str, ok: bool, allowed: &str, got: impl std::fmt::Display) {
    if !ok {
        l.push(&format!("problem.{k}"), format!("{allowed}, got {got}"));
    }
}

fn two_grid(l: &mut Loader, v: &Values, dt: f64, steps: usize) -> TwoGridSpec {
    let s = TwoGridSpec {
        degree: v.i("degree", 1).min(255) as u8,
        dt: v.f("dt", dt),
        steps: v.i("steps", steps),
        adaptive: v.b("adaptive", true),
        levels: v.i("levels", 4).min(64) as u32,
        min_level: v.i("min_level", 3).min(64) as u32,
        max_level: v.i("max_level", 7).min(64) as u32,
        dorfler: v.f("dorfler", 0.7),
        coarsen: v.f("coarsen", 0.01),
        initial_sweeps: v.i("initial_sweeps", 8),
    };
    check(
        l,
        "degree",
        (1..=2).contains(&s.degree),
        "must be 1 or 2",
        s.degree,
    );
    check(
        l,
        "dt",
        s.dt.is_finite() && s.dt > 0.0,
        "must be positive",
        s.dt,
    );
    check(
        l,
        "steps",
        (1..=100_000).contains(&s.steps),
        "must be in 1..=100000",
        s.steps,
    );
    check(
        l,
        "levels",
        (1..=9).contains(&s.levels),
        "must be in 1..=9",
        s.levels,
    );
    check(
        l,
        "max_level",
        s.max_level <= 10,
        "must be at most 10",
        s.max_level,
    );
    check(
        l,
        "min_level",
        s.min_level <= s.max_level,
        &format!("must be at most max_level = {}", s.max_level),
        s.min_level,
    );
    check(
        l,
        "dorfler",
        s.dorfler > 0.0 && s.dorfler <= 1.0,
        "must be in (0, 1]",
        s.dorfler,
    );
    check(
        l,
        "coarsen",
        s.coarsen.is_finite() && s.coarsen >= 0.0,
        "must be >= 0",
        s.coarsen,
    );
    check(
        l,
        "initial_sweeps",
        (1..=20).contains(&s.initial_sweeps),
        "must be in 1..=20",
        s.initial_sweeps,
    );
    s
}

fn read_problem(l: &mut Loader, kind: ProblemKind, v: &Values) -> Problem {
    match kind {
        ProblemKind::Cavity => {
            let s = CavitySpec {
                reynolds: v.f("reynolds", 1000.0),
                lid: v.w("lid", Lid::Standard),
                mesh: v.w("mesh", CavityMesh::Moving),
                levels: v.i("levels", 4).min(64) as u32,
                recalculations: v.i("recalculations", 8),
                alpha: v.f("alpha", 4.0),
                beta: v.f("beta", 4.0),
                gamma: v.f("gamma", 0.0),
                tolerance: v.f("tolerance", 1e-10),
            };
            check(
                l,
                "reynolds",
                [100.0, 400.0, 1000.0].contains(&s.reynolds),
                "must be 100, 400 or 1000 (the stations of the continuation)",
                s.reynolds,
            );
            check(
                l,
                "levels",
                (1..=7).contains(&s.levels),
                "must be in 1..=7",
                s.levels,
            );
            check(
                l,
                "recalculations",
                s.recalculations <= 50,
                "must be at most 50",
                s.recalculations,
            );
            check(
                l,
                "alpha",
                s.alpha.is_finite() && s.alpha >= 0.0,
                "must be >= 0",
                s.alpha,
            );
            check(
                l,
                "beta",
                s.beta.is_finite() && s.beta >= 1.0,
                "must be >= 1",
                s.beta,
            );
            check(
                l,
                "gamma",
                (0.0..=1.0).contains(&s.gamma),
                "must be in [0, 1]",
                s.gamma,
            );
            check(
                l,
                "tolerance",
                s.tolerance.is_finite() && s.tolerance > 0.0,
                "must be positive",
                s.tolerance,
            );
            if s.mesh == CavityMesh::Uniform {
                for k in ["recalculations", "alpha", "beta", "gamma"] {
                    if v.has(k) {
                        l.push(
                            &format!("problem.{k}"),
                            "is a key of the moving mesh: not used with mesh = \"uniform\"; \
                             remove it or set mesh = \"moving\"",
                        );
                    }
                }
            }
            Problem::Cavity(s)
        }
        ProblemKind::Heat => {
            let time = two_grid(l, v, 0.02, 25);
            let s = HeatSpec {
                time,
                kappa: v.f("kappa", 1e-3),
                sigma2: v.f("sigma2", 0.01),
                centre: v.point("centre", [0.5, 0.0]),
                supg: v.b("supg", true),
            };
            check(
                l,
                "kappa",
                s.kappa.is_finite() && s.kappa > 0.0,
                "must be positive",
                s.kappa,
            );
            check(
                l,
                "sigma2",
                s.sigma2.is_finite() && s.sigma2 > 0.0,
                "must be positive",
                s.sigma2,
            );
            check(
                l,
                "centre",
                s.centre.iter().all(|c| c.abs() < 1.0),
                "must lie inside (-1, 1)²",
                format!("[{}, {}]", s.centre[0], s.centre[1]),
            );
            Problem::Heat(s)
        }
        ProblemKind::Burgers => {
            let time = two_grid(l, v, 0.01, 10);
            let s = BurgersSpec {
                time,
                nu: v.f("nu", 0.01),
            };
            check(
                l,
                "nu",
                s.nu.is_finite() && s.nu > 0.0,
                "must be positive",
                s.nu,
            );
            Problem::Burgers(s)
        }
        ProblemKind::PNavierStokes => {
            let flow = v.w("flow", Flow::Kovasznay);
            let steady = flow == Flow::Kovasznay;
            let s = PnsSpec {
                flow,
                degree: v.i("degree", 2),
                tolerance: v.f("tolerance", if steady { 1e-5 } else { 1e-4 }),
                enrich: v.i("enrich", 2),
                max_degree: v.i("max_degree", 8),
                max_sweeps: v.i("max_sweeps", 10),
                reynolds: steady.then(|| v.f("reynolds", 40.0)),
                nu: (!steady).then(|| v.f("nu", 0.01)),
                dt: (!steady).then(|| v.f("dt", 0.02)),
                steps: (!steady).then(|| v.i("steps", 5)),
            };
            let (unused, other) = if steady {
                (&["nu", "dt", "steps"][..], "taylor_green")
            } else {
                (&["reynolds"][..], "kovasznay")
            };
            for k in unused {
                if v.has(k) {
                    l.push(
                        &format!("problem.{k}"),
                        format!(
                            "is a key of flow = \"{other}\", not of flow = \"{flow}\"; remove it"
                        ),
                    );
                }
            }
            check(
                l,
                "enrich",
                (1..=2).contains(&s.enrich),
                "must be 1 or 2",
                s.enrich,
            );
            check(
                l,
                "max_degree",
                s.max_degree >= 2 && s.max_degree + s.enrich <= 10,
                &format!(
                    "must be at least 2 and max_degree + enrich <= 10 (enrich = {})",
                    s.enrich
                ),
                s.max_degree,
            );
            check(
                l,
                "degree",
                s.degree >= 2 && s.degree <= s.max_degree.max(2),
                &format!("must be in 2..=max_degree ({})", s.max_degree),
                s.degree,
            );
            check(
                l,
                "tolerance",
                !s.tolerance.is_nan() && s.tolerance > 0.0,
                "must be positive (inf: no adaptation)",
                s.tolerance,
            );
            check(
                l,
                "max_sweeps",
                (1..=50).contains(&s.max_sweeps),
                "must be in 1..=50",
                s.max_sweeps,
            );
            if let Some(re) = s.reynolds {
                check(
                    l,
                    "reynolds",
                    re.is_finite() && re > 0.0,
                    "must be positive",
                    re,
                );
            }
            if let Some(nu) = s.nu {
                check(l, "nu", nu.is_finite() && nu > 0.0, "must be positive", nu);
            }
            if let Some(dt) = s.dt {
                check(l, "dt", dt.is_finite() && dt > 0.0, "must be positive", dt);
            }
            if let Some(n) = s.steps {
                check(
                    l,
                    "steps",
                    (1..=10_000).contains(&n),
                    "must be in 1..=10000",
                    n,
                );
            }
            Problem::PNavierStokes(s)
        }
        ProblemKind::LShape => {
            let s = LShapeSpec {
                degree: v.i("degree", 1).min(255) as u8,
                refinement: v.w("refinement", LRefinement::H),
                estimator: v.w("estimator", LEstimator::Explicit),
                dorfler: v.f("dorfler", 0.5),
                max_dofs: v.i("max_dofs", 20_000),
                max_steps: v.i("max_steps", 60),
                initial_levels: v.i("initial_levels", 1).min(64) as u32,
                max_degree: v.i("max_degree", 8),
                uniform: v.b("uniform", false),
            };
            if s.refinement == LRefinement::H {
                check(
                    l,
                    "degree",
                    (1..=2).contains(&s.degree),
                    "must be 1 or 2 for refinement = \"h\" (Lagrange Q1, Q2)",
                    s.degree,
                );
                if v.has("max_degree") {
                    l.push(
                        "problem.max_degree",
                        "is used by refinement = \"p\" and \"hp\" only; remove it",
                    );
                }
            } else {
                check(
                    l,
                    "max_degree",
                    (1..=10).contains(&s.max_degree),
                    "must be in 1..=10",
                    s.max_degree,
                );
                check(
                    l,
                    "degree",
                    s.degree >= 1 && (s.degree as usize) <= s.max_degree.min(8),
                    &format!(
                        "must be in 1..={} (max_degree, at most 8)",
                        s.max_degree.min(8)
                    ),
                    s.degree,
                );
            }
            check(
                l,
                "dorfler",
                s.dorfler > 0.0 && s.dorfler <= 1.0,
                "must be in (0, 1]",
                s.dorfler,
            );
            check(
                l,
                "max_dofs",
                (10..=2_000_000).contains(&s.max_dofs),
                "must be in 10..=2000000",
                s.max_dofs,
            );
            check(
                l,
                "max_steps",
                (1..=200).contains(&s.max_steps),
                "must be in 1..=200",
                s.max_steps,
            );
            check(
                l,
                "initial_levels",
                s.initial_levels <= 8,
                "must be at most 8",
                s.initial_levels,
            );
            Problem::LShape(s)
        }
    }
}

fn describe(v: &toml::Value) -> &'static str {
    match v {
        toml::Value::String(_) => "a string",
        toml::Value::Integer(_) => "an integer",
        toml::Value::Float(_) => "a float",
        toml::Value::Boolean(_) => "a boolean",
        toml::Value::Datetime(_) => "a date",
        toml::Value::Array(_) => "an array",
        toml::Value::Table(_) => "a table",
    }
}

impl ModelScene {
    /// Parse a model-problem scene, apply `--set` overrides, fill defaults and check every key;
    /// every problem is collected.
    pub fn from_toml_str(
        text: &str,
        source_name: &str,
        overrides: &[String],
    ) -> Result<ModelScene, SceneErrors> {
        let mut l = Loader {
            source_name,
            locator: Locator::new(text),
            overridden: BTreeSet::new(),
            errors: Vec::new(),
        };
        let mut doc: toml::Table = match text.parse() {
            Ok(t) => t,
            Err(e) => {
                let e: toml::de::Error = e;
                return Err(SceneErrors(vec![SceneError {
                    key: String::new(),
                    line: e
                        .span()
                        .map(|s| text[..s.start.min(text.len())].lines().count().max(1)),
                    message: format!("TOML syntax error: {}", e.message()),
                    source_name: source_name.to_string(),
                }]));
            }
        };
        l.apply_overrides(&mut doc, overrides);
        for (sec, v) in &doc {
            if !matches!(sec.as_str(), "scene" | "problem" | "output") {
                l.push(
                    sec,
                    format!(
                        "section [{sec}] is not part of a model-problem scene (a scene with \
                         [problem]); its sections are [scene], [problem] and [output]"
                    ),
                );
            } else if !v.is_table() {
                l.push(sec, format!("must be a table, got {}", describe(v)));
            }
        }
        let empty = toml::Table::new();
        let table = |name: &str| match doc.get(name) {
            Some(toml::Value::Table(t)) => t,
            _ => &empty,
        };
        // [scene]
        let scene = table("scene");
        for k in scene.keys() {
            if !SCENE_KEYS.contains(&k.as_str()) {
                l.push(
                    &format!("scene.{k}"),
                    "unknown key; keys of [scene] in a model-problem scene are name, description",
                );
            }
        }
        let text_key = |l: &mut Loader, k: &str| match scene.get(k) {
            None => None,
            Some(toml::Value::String(s)) => Some(s.clone()),
            Some(v) => {
                l.push(
                    &format!("scene.{k}"),
                    format!("must be a string, got {}", describe(v)),
                );
                None
            }
        };
        let name = text_key(&mut l, "name");
        let description = text_key(&mut l, "description").unwrap_or_default();
        match &name {
            None if !scene.contains_key("name") => {
                l.push("scene.name", "required key `name` is missing in [scene]")
            }
            Some(n) if n.trim().is_empty() || n.contains(['/', '\\']) => l.push(
                "scene.name",
                "must be a non-empty name without path separators (it names the output folder)",
            ),
            _ => {}
        }
        // [output]
        let output = table("output");
        let mut sinks = DEFAULT_SINKS.to_vec();
        for (k, v) in output {
            if k != "sinks" {
                l.push(
                    &format!("output.{k}"),
                    "unknown key; a model-problem scene's [output] has only `sinks`",
                );
                continue;
            }
            let toml::Value::Array(a) = v else {
                l.push(
                    "output.sinks",
                    format!("must be a list of sinks, got {}", describe(v)),
                );
                continue;
            };
            sinks.clear();
            for item in a {
                let parsed = item.as_str().map(str::parse::<Sink>);
                match parsed {
                    Some(Ok(s)) if SINKS.contains(&s) => sinks.push(s),
                    Some(Ok(s)) => l.push(
                        "output.sinks",
                        format!(
                            "sink \"{s}\" is not written by model problems; they write \"summary\", \
                             \"csv\", \"vtu\", \"png\" and \"rerun\""
                        ),
                    ),
                    Some(Err(e)) => l.push("output.sinks", e),
                    None => l.push(
                        "output.sinks",
                        format!("must be a list of sink names, got {}", describe(item)),
                    ),
                }
            }
        }
        // [problem]
        let problem = table("problem");
        let kind = match problem.get("kind") {
            None => {
                l.push(
                    "problem.kind",
                    format!(
                        "required key `kind` is missing in [problem]; one of {}",
                        super::issue::quoted_list(ProblemKind::NAMES)
                    ),
                );
                None
            }
            Some(toml::Value::String(s)) => match s.parse::<ProblemKind>() {
                Ok(k) => Some(k),
                Err(e) => {
                    l.push("problem.kind", e);
                    None
                }
            },
            Some(v) => {
                l.push(
                    "problem.kind",
                    format!("must be a string, got {}", describe(v)),
                );
                None
            }
        };
        let mut clean = toml::Table::new();
        if let Some(kind) = kind {
            for (k, v) in problem {
                if k == "kind" {
                    continue;
                }
                let dotted = format!("problem.{k}");
                let docs: Vec<&KeyDoc> = KEYS.iter().filter(|d| d.key == k).collect();
                let Some(d) = docs.iter().find(|d| d.kinds.contains(&kind)) else {
                    let mut users: Vec<&str> = docs
                        .iter()
                        .flat_map(|d| d.kinds.iter().map(|k| k.as_str()))
                        .collect();
                    users.dedup();
                    let own: Vec<&str> = {
                        let mut o: Vec<&str> = KEYS
                            .iter()
                            .filter(|d| d.kinds.contains(&kind))
                            .map(|d| d.key)
                            .collect();
                        o.dedup();
                        o
                    };
                    let msg = if users.is_empty() {
                        format!(
                            "unknown key for problem kind \"{kind}\"; its keys are kind, {}",
                            own.join(", ")
                        )
                    } else {
                        format!(
                            "is a key of problem kind {}, not of \"{kind}\"; the keys of \"{kind}\" \
                             are kind, {}",
                            super::issue::quoted_list(&users),
                            own.join(", ")
                        )
                    };
                    l.push(&dotted, msg);
                    continue;
                };
                if type_ok(v, d.ty) {
                    clean.insert(k.clone(), v.clone());
                } else {
                    let got = match v {
                        toml::Value::String(s) => format!("\"{s}\""),
                        toml::Value::Integer(i) => i.to_string(),
                        other => describe(other).to_string(),
                    };
                    l.push(&dotted, format!("must be {}, got {got}", d.ty.describe()));
                }
            }
        }
        let problem = kind.map(|k| read_problem(&mut l, k, &Values { table: &clean }));
        if !l.errors.is_empty() {
            return Err(SceneErrors(l.errors));
        }
        match (name, problem) {
            (Some(name), Some(problem)) => Ok(ModelScene {
                name,
                description,
                problem,
                sinks,
            }),
            _ => Err(SceneErrors(vec![SceneError {
                key: String::new(),
                line: None,
                message: "invalid model-problem scene".into(),
                source_name: source_name.to_string(),
            }])),
        }
    }

    /// Read a scene file and load it with [`ModelScene::from_toml_str`].
    pub fn from_path(path: &Path, overrides: &[String]) -> Result<ModelScene, SceneErrors> {
        let name = path.display().to_string();
        match std::fs::read_to_string(path) {
            Ok(text) => ModelScene::from_toml_str(&text, &name, overrides),
            Err(e) => Err(SceneErrors(vec![SceneError {
                key: String::new(),
                line: None,
                message: format!("cannot read scene file: {e}"),
                source_name: name,
            }])),
        }
    }

    /// Whether a sink is on.
    pub fn has(&self, s: Sink) -> bool {
        self.sinks.contains(&s)
    }

    /// The resolved scene (every default filled) as TOML; it loads back to `self`.
    pub fn to_toml_string(&self) -> String {
        let mut problem = match &self.problem {
            Problem::Cavity(s) => toml::Table::try_from(s),
            Problem::Heat(s) => toml::Table::try_from(s),
            Problem::Burgers(s) => toml::Table::try_from(s),
            Problem::PNavierStokes(s) => toml::Table::try_from(s),
            Problem::LShape(s) => toml::Table::try_from(s),
        }
        .unwrap_or_default();
        if let Problem::Cavity(c) = &self.problem {
            if c.mesh == CavityMesh::Uniform {
                for k in ["recalculations", "alpha", "beta", "gamma"] {
                    problem.remove(k);
                }
            }
        }
        if let Problem::LShape(s) = &self.problem {
            if s.refinement == LRefinement::H {
                problem.remove("max_degree");
            }
        }
        let mut p = toml::Table::new();
        p.insert("kind".into(), self.problem.kind().as_str().into());
        p.extend(problem);
        let mut scene = toml::Table::new();
        scene.insert("name".into(), self.name.clone().into());
        scene.insert("description".into(), self.description.clone().into());
        let mut output = toml::Table::new();
        output.insert(
            "sinks".into(),
            toml::Value::Array(self.sinks.iter().map(|s| s.as_str().into()).collect()),
        );
        // Sections in the order of a scene file: [scene], [problem], [output].
        let mut text = String::new();
        for (name, table) in [("scene", scene), ("problem", p), ("output", output)] {
            let mut doc = toml::Table::new();
            doc.insert(name.into(), table.into());
            match toml::to_string_pretty(&doc) {
                Ok(t) => {
                    if !text.is_empty() {
                        text.push('\n');
                    }
                    text.push_str(&t);
                }
                Err(e) => return format!("# cannot write scene as TOML: {e}\n"),
            }
        }
        text
    }
}

/// The reference of model-problem scene keys (Markdown, part of `docs/reference.md`).
pub fn markdown_reference() -> String {
    let mut out = String::from(
        "A scene with a `[problem]` table runs one of the adaptive model problems of `src/adapt/` \
         (`tread run scenarios/model_problems/NAME.toml`). Its sections are `[scene]` (`name`, \
         required; `description`), `[problem]` and `[output]` (`sinks`, from \"summary\", \
         \"csv\", \"vtu\", \"png\", \"rerun\"; default the first four). Any other section or \
         key, or a key of another kind, is an error.\n\n",
    );
    out.push_str(&format!(
        "`problem.kind` (required): {}.\n\n",
        ProblemKind::ALL
            .iter()
            .map(|k| format!("`\"{k}\"`"))
            .collect::<Vec<_>>()
            .join(", ")
    ));
    out.push_str("| key | kinds | type | default | unit | meaning |\n|---|---|---|---|---|---|\n");
    for k in KEYS {
        let ty = match k.ty {
            KeyType::Word(w) => w
                .iter()
                .map(|x| format!("\"{x}\""))
                .collect::<Vec<_>>()
                .join(" \\| "),
            other => other.describe(),
        };
        out.push_str(&format!(
            "| `{}` | {} | {} | {} | {} | {} |\n",
            k.key,
            k.kinds
                .iter()
                .map(|x| x.as_str())
                .collect::<Vec<_>>()
                .join(", "),
            ty,
            super::cell(k.default),
            super::cell(k.unit),
            super::cell(k.doc)
        ));
    }
    out
}
