//! Work–precision benchmark of the transient integrators (not a test):
//!
//! * generalized-α with ρ∞ ∈ {1.0, 0.8, 0.5} (consistent mass), at a sequence of fixed steps
//!   and with the adaptive step control at a sequence of `error_tol`;
//! * central difference (lumped mass) at fractions of the stable-step estimate
//!   `Transient::stable_step` (0.9 is what `integrate` uses);
//! * diffsol's BDF and SDIRK (ESDIRK34) on the first-order form y = (u, v) (consistent mass,
//!   `driver::transient::ode_first_order`) with rtol = each adaptive `error_tol`.
//!
//! Problem: the paper-like cylinder of `scenarios/oden_hollow_cylinder.toml` (Ri = 1, Ro = 2,
//! compressible Mooney–Rivlin c1 = 80, c2 = 20, κ = 20000, ρ = 0.027, Coulomb-tanh friction,
//! strain-rate damping) on a coarse mesh (n_r = 2, n_θ = 32) and without normal contact damping
//! (see [`OVERRIDES`]), built from the scene text with `--set`-style overrides exactly as
//! `driver::transient_run` builds it.
//!
//! * (a) smooth transient: the hub force (x, y) at t* = 0.15 s (after the 0.05 s spin-up and
//!   road ramps); fixed steps land on t* exactly (`land_on_passages = false`). Reference:
//!   generalized-α ρ∞ = 0.8 with a step 16× smaller than the smallest benchmarked one. The hub
//!   force carries a lightly damped ~400 Hz vibration (3–5 % of its magnitude), re-excited as
//!   contact points enter the patch: steps must resolve it before the error converges.
//! * (b) steady rolling: run until steady (`stop_at_steady`, `land_on_passages = true` as the
//!   driver does, the program's default `steady_tol` = 1e-4) and compare the hub force, the hub
//!   torque and the contact half-width 2 √⟨x²⟩ (pressure second moment, `ContactModel::totals`)
//!   with a reference run: generalized-α ρ∞ = 0.8 with a fixed step 8× smaller than the
//!   smallest benchmarked one (fixed steps make every node passage use the same step pattern, so
//!   the steady state is reached cleanly), `steady_tol` / 10, Newton tolerance 1e-10.
//!
//! Errors are relative: |F − F_ref| / |F_ref| for the force vector, |M − M_ref| / |M_ref|,
//! |a − a_ref| / a_ref; for (b) the reported error is the largest of the three. Central
//! difference uses the lumped mass, i.e. a different semi-discrete model: its error against the
//! consistent-mass reference includes the mass-lumping error, so a second column compares every
//! run with a reference of its own mass (generalized-α ρ∞ = 0.8 with the lumped mass).
//! References are cached in `DIR/transient_reference.json`, keyed by their parameters and a hash
//! of the resolved scene without its `[scene]` and `[output]` sections (`--fresh-reference`
//! recomputes them, e.g. after a change of the code).
//!
//! Wall time: `integrate()` only (model construction excluded), median of `--repeats` runs, on
//! `--threads` rayon threads (default 1: reproducible on a shared machine).
//!
//! ```text
//! cargo run --release --bin tread-bench-transient -- [--quick] [--repeats N] [--threads N] [--out DIR] [--fresh-reference]
//! ```
//!
//! Writes Markdown tables and a recommendation to stdout, and
//! `DIR/transient_work_precision_{a,b}.csv` and `.png` (log–log error vs wall time with decade
//! ticks from `png::AxisLayout`; default `DIR = out/bench`).

#[path = "common.rs"]
mod common;
use common::{fnv1a, median};

use plotters::prelude::*;
use std::path::{Path, PathBuf};
use std::time::Instant;
use tread::app::{build_contact, build_model};
use tread::contact::ContactModel;
use tread::driver::transient::ode_first_order::{integrate_first_order, OdeMethod, OdeTolerances};
use tread::driver::transient::{
    integrate, GenAlpha, Scheme, TimeOptions, Transient, TransientReport,
};
use tread::io::record::png::{self, AxisLayout, Scale};
use tread::io::scene::{DEFAULT_ERROR_TOL, DEFAULT_RHO_INF, DEFAULT_STEADY_TOL};
use tread::io::Scene;
use tread::model::SolidSystem;
use tread::solver::{LinearKind, NewtonOptions};

const SCENE_TEXT: &str = include_str!("../scenarios/oden_hollow_cylinder.toml");
const SCENE_NAME: &str = "scenarios/oden_hollow_cylinder.toml";
/// Coarse mesh; no normal contact damping: with the scene's `l_n = 0` the damping traction
/// b_n δ̇ jumps from 0 to b_n δ̇ (about 2 % of the hub force per facet point) when a point enters
/// the patch, so the hub force is discontinuous in time (no integrator converges at its order)
/// and fixed-step Newton fails at Δt = 1e-3 and 5e-4. The transient stays damped by the
/// strain-rate viscosity and friction.
const OVERRIDES: &[&str] = &["mesh.n_r=2", "mesh.n_theta=32", "contact.b_n=0"];
/// Time of the transient sample (a), after the ramps.
const T_STAR: f64 = 0.15;
/// Reference step of (a) = smallest benchmarked step / REF_REFINE_A.
const REF_REFINE_A: f64 = 16.0;
/// Reference step of (b) = smallest benchmarked step / REF_REFINE_B (a run to steady is long).
const REF_REFINE_B: f64 = 8.0;
/// Reference of (b): steady_tol divided by this.
const REF_STEADY_TIGHTEN: f64 = 10.0;
/// steady_tol of the runs of (b): the program's default. The scene's 1e-3 stops while the
/// per-passage changes, which decay only ~10× per 0.2 s here, still add up to several 1e-3:
/// a stopping error that would hide the integrators' errors.
const STEADY_TOL: f64 = DEFAULT_STEADY_TOL;
/// Newton tolerance of the reference runs.
const REF_NEWTON_TOL: f64 = 1e-10;
/// Rho∞ of the references.
const REF_RHO: f64 = 0.8;
/// Error levels at which the recommendation compares the integrators.
const TARGETS: [f64; 3] = [1e-2, 1e-3, 1e-4];

// ---------------------------------------------------------------------------------------------
// Arguments

struct Args {
    quick: bool,
    repeats: usize,
    threads: usize,
    out: PathBuf,
    fresh_reference: bool,
}

const USAGE: &str =
    "tread-bench-transient [--quick] [--repeats N] [--threads N] [--out DIR] [--fresh-reference]";

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        quick: false,
        repeats: 3,
        threads: 1,
        out: "out/bench".into(),
        fresh_reference: false,
    };
    let mut it = std::env::args().skip(1);
    while let Some(k) = it.next() {
        let mut val = || it.next().ok_or(format!("{k} needs a value"));
        match k.as_str() {
            "--quick" => a.quick = true,
            "--fresh-reference" => a.fresh_reference = true,
            "--repeats" => {
                a.repeats = val()?
                    .parse::<usize>()
                    .map_err(|e| format!("--repeats: {e}"))?;
                if a.repeats == 0 {
                    return Err("--repeats must be at least 1".into());
                }
            }
            "--threads" => {
                a.threads = val()?
                    .parse::<usize>()
                    .map_err(|e| format!("--threads: {e}"))?;
                if a.threads == 0 {
                    return Err("--threads must be at least 1".into());
                }
            }
            "--out" => a.out = val()?.into(),
            "-h" | "--help" => {
                println!("{USAGE}");
                std::process::exit(0);
            }
            o => return Err(format!("unknown argument `{o}`\nusage: {USAGE}")),
        }
    }
    Ok(a)
}

// ---------------------------------------------------------------------------------------------
// Cases

#[derive(Clone, Copy, Debug, PartialEq)]
enum Method {
    GenAlpha(f64),
    Central,
    /// diffsol BDF / SDIRK on y = (u, v) (consistent mass, diffsol's own error control).
    Ode(OdeMethod),
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Setting {
    /// Fixed step.
    Fixed(f64),
    /// Adaptive step control with this error_tol (generalized-α).
    Adaptive(f64),
    /// Central difference at this fraction of the stable-step estimate.
    Stable(f64),
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Part {
    /// Hub force at t*.
    A,
    /// Steady state.
    B,
}

#[derive(Clone, Copy, Debug)]
struct Case {
    method: Method,
    setting: Setting,
}

impl Case {
    fn integrator(&self) -> String {
        match self.method {
            Method::GenAlpha(r) => format!("generalized-α ρ∞={r:.1}"),
            Method::Central => "central difference (lumped)".into(),
            Method::Ode(m) => format!("diffsol {} on y = (u, v)", m.name()),
        }
    }
    /// One polyline of the plot / one family of the recommendation.
    fn series(&self) -> String {
        match (self.method, self.setting) {
            (Method::GenAlpha(r), Setting::Adaptive(_)) => format!("GA ρ∞={r:.1} adaptive"),
            (Method::GenAlpha(r), _) => format!("GA ρ∞={r:.1} fixed Δt"),
            (Method::Central, _) => "central difference".into(),
            (Method::Ode(m), _) => format!("diffsol {}", m.name()),
        }
    }
    fn setting(&self, dt_stable: f64, part: Part) -> String {
        match self.setting {
            Setting::Fixed(dt) => format!("Δt = {dt:.3e}"),
            Setting::Adaptive(tol) => format!("error_tol = {tol:.0e}"),
            Setting::Stable(f) => {
                format!(
                    "Δt = {:.3e} ({f:.3} Δt_stable)",
                    cd_step(f, dt_stable, part)
                )
            }
        }
    }
    fn lumped(&self) -> bool {
        matches!(self.method, Method::Central)
    }
    fn scheme(&self) -> Scheme {
        match self.method {
            Method::GenAlpha(r) => Scheme::generalized_alpha(GenAlpha::new(r)),
            Method::Central => Scheme::central_difference(),
            // Unused by the diffsol integrators.
            Method::Ode(_) => Scheme::generalized_alpha(GenAlpha::new(1.0)),
        }
    }
    /// CSV columns scheme (0 generalized-α, 1 central difference, 2 diffsol BDF, 3 diffsol
    /// SDIRK), rho_inf, adaptive, dt, error_tol, stable_fraction.
    fn csv_codes(&self, dt_stable: f64, part: Part) -> [f64; 6] {
        let nan = f64::NAN;
        let (scheme, rho) = match self.method {
            Method::GenAlpha(r) => (0.0, r),
            Method::Central => (1.0, nan),
            Method::Ode(OdeMethod::Bdf) => (2.0, nan),
            Method::Ode(_) => (3.0, nan),
        };
        match self.setting {
            Setting::Fixed(dt) => [scheme, rho, 0.0, dt, nan, nan],
            Setting::Adaptive(tol) => [scheme, rho, 1.0, nan, tol, nan],
            Setting::Stable(f) => [scheme, rho, 0.0, cd_step(f, dt_stable, part), nan, f],
        }
    }
}

/// Central-difference step at fraction `f` of the stable step; for (a) rounded down so that
/// it divides t*.
fn cd_step(f: f64, dt_stable: f64, part: Part) -> f64 {
    let dt = f * dt_stable;
    match part {
        Part::A => T_STAR / (T_STAR / dt).ceil(),
        Part::B => dt,
    }
}

struct Plan {
    rhos: Vec<f64>,
    dts_a: Vec<f64>,
    dts_b: Vec<f64>,
    tols_a: Vec<f64>,
    tols_b: Vec<f64>,
    cd_fractions: Vec<f64>,
}

impl Plan {
    fn new(quick: bool) -> Self {
        if quick {
            Plan {
                rhos: vec![1.0, 0.8, 0.5],
                dts_a: vec![2e-3, 5e-4, 1.25e-4],
                dts_b: vec![2e-3, 5e-4],
                tols_a: vec![1e-2, 1e-4],
                tols_b: vec![1e-2, 1e-4],
                cd_fractions: vec![0.9, 0.6, 0.3],
            }
        } else {
            Plan {
                rhos: vec![1.0, 0.8, 0.5],
                // Down to ~1e-4 s: the hub force carries a lightly damped ~400 Hz vibration
                // (period ~2.5 ms), excited by the contact points entering the patch and, in
                // steady rolling, forced at the node-passage frequency; longer steps do not
                // resolve it.
                dts_a: vec![2e-3, 1e-3, 5e-4, 2.5e-4, 1.25e-4, 6.25e-5],
                dts_b: vec![2e-3, 1e-3, 5e-4, 2.5e-4],
                // The step count of the adaptive control grows steeply below 1e-4 (7× from
                // 1e-4 to 1e-5 in (a)); a run to steady at 1e-5 would take minutes.
                tols_a: vec![1e-2, 1e-3, 1e-4, 1e-5],
                tols_b: vec![1e-2, 1e-3, 1e-4],
                cd_fractions: vec![0.9, 0.6, 0.3, 0.15],
            }
        }
    }
    fn cases(&self, part: Part) -> Vec<Case> {
        let (dts, tols) = match part {
            Part::A => (&self.dts_a, &self.tols_a),
            Part::B => (&self.dts_b, &self.tols_b),
        };
        let mut v = Vec::new();
        for &r in &self.rhos {
            for &dt in dts {
                v.push(Case {
                    method: Method::GenAlpha(r),
                    setting: Setting::Fixed(dt),
                });
            }
            for &tol in tols {
                v.push(Case {
                    method: Method::GenAlpha(r),
                    setting: Setting::Adaptive(tol),
                });
            }
        }
        // diffsol BDF and SDIRK (ESDIRK34) at the adaptive runs' tolerances (rtol = error_tol,
        // see driver::transient::ode_first_order for the absolute tolerances).
        for m in [OdeMethod::Bdf, OdeMethod::Esdirk34] {
            for &tol in tols {
                v.push(Case {
                    method: Method::Ode(m),
                    setting: Setting::Adaptive(tol),
                });
            }
        }
        for &f in &self.cd_fractions {
            v.push(Case {
                method: Method::Central,
                setting: Setting::Stable(f),
            });
        }
        v
    }
}

// ---------------------------------------------------------------------------------------------
// Model construction (as driver::transient_run) and one run

fn base_scene() -> Result<Scene, String> {
    let set: Vec<String> = OVERRIDES.iter().map(|s| s.to_string()).collect();
    Scene::from_toml_str(SCENE_TEXT, SCENE_NAME, &set).map_err(|e| e.to_string())
}

fn build(scene: &Scene, scheme: Scheme, lumped: bool) -> Result<(Transient, LinearKind), String> {
    let ts = scene
        .time
        .as_ref()
        .ok_or("the scene has no [time] section")?;
    let mut model = build_model(scene).map_err(|e| e.to_string())?;
    model.strain_rate_damping = ts.strain_rate_damping;
    let sys = match (&scene.road, &scene.contact) {
        (Some(_), Some(_)) => {
            let c = build_contact(scene, &model).map_err(|e| e.to_string())?;
            SolidSystem::with_contact(model, c)
        }
        _ => SolidSystem::new(model, "hub"),
    };
    let kin = tread::driver::transient_run::kinematics(scene);
    let tr = Transient::new(sys, scheme, kin, lumped);
    let kind = tread::setup::solve_plan(scene, &tr.sys).kind;
    Ok((tr, kind))
}

/// Result of one run (wall time: median over the repeats).
#[derive(Clone, Debug, Default)]
struct Outcome {
    steps: usize,
    rejected: usize,
    newton: usize,
    wall: f64,
    /// Hub force x, y, hub torque, contact half-width 2 √⟨x²⟩.
    values: [f64; 4],
    steady: bool,
    time_to_steady: Option<f64>,
    failure: Option<String>,
}

/// Time options of a run (`steady_tol`: the benchmark's or the tighter one of a reference).
fn time_options(
    scene: &Scene,
    case: &Case,
    part: Part,
    dt_stable: f64,
    steady_tol: f64,
) -> Result<TimeOptions, String> {
    let ts = scene
        .time
        .as_ref()
        .ok_or("the scene has no [time] section")?;
    let (dt, dt_min, dt_max, adaptive, error_tol) = match case.setting {
        Setting::Fixed(dt) => (dt, dt, dt, false, ts.error_tol),
        Setting::Adaptive(tol) => (ts.dt, ts.resolved_dt_min(), ts.resolved_dt_max(), true, tol),
        Setting::Stable(f) => {
            let dt = cd_step(f, dt_stable, part);
            (dt, dt, dt, false, ts.error_tol)
        }
    };
    Ok(TimeOptions {
        dt,
        dt_min,
        dt_max,
        t_end: match part {
            Part::A => T_STAR,
            Part::B => ts.t_end,
        },
        adaptive,
        error_tol,
        steady_tol,
        stop_at_steady: part == Part::B,
        max_steps: 2_000_000,
        lumped: case.lumped(),
        land_on_passages: part == Part::B,
    })
}

fn run_once(
    scene: &Scene,
    case: &Case,
    part: Part,
    dt_stable: f64,
    steady_tol: f64,
    newton_tol: f64,
) -> Result<Outcome, String> {
    let (mut tr, kind) = build(scene, case.scheme(), case.lumped())?;
    let opts = time_options(scene, case, part, dt_stable, steady_tol)?;
    let newton = NewtonOptions {
        tol: newton_tol,
        max_iterations: scene.solver.max_iterations,
        line_search: scene.solver.line_search,
        verbose: false,
        ..Default::default()
    };
    let t0 = Instant::now();
    let res = match case.method {
        Method::Ode(m) => {
            let tol = OdeTolerances::from_scene(
                opts.error_tol,
                scene.geometry.ro,
                scene.motion.omega,
                opts.t_end,
            );
            integrate_first_order(&mut tr, m, &opts, tol, |_, _| {})
        }
        _ => integrate(&mut tr, &opts, newton, kind, |_, _| {}),
    };
    let wall = t0.elapsed().as_secs_f64();
    let (rep, failure) = match res {
        Ok(r) => (r, None),
        Err((e, r)) => {
            let t = r.final_time;
            (r, Some(format!("{e} at t = {t:.4e}")))
        }
    };
    let values = extract(&tr, &rep, part);
    let failure = failure.or_else(|| {
        if values.iter().all(|v| v.is_finite()) {
            None
        } else {
            Some("non-finite result".into())
        }
    });
    let failure = failure.or_else(|| {
        (part == Part::B && !rep.steady).then(|| format!("not steady by t = {:.3}", opts.t_end))
    });
    Ok(Outcome {
        steps: rep.steps,
        rejected: rep.rejected,
        newton: rep.newton_iterations,
        wall,
        values,
        steady: rep.steady,
        time_to_steady: rep.time_to_steady,
        failure,
    })
}

/// Contact half-width 2 √⟨x²⟩ of the configuration `x` (full displacement vector).
fn half_width(tr: &Transient, x: &[f64], v: &[f64]) -> f64 {
    let samples = tr.contact_samples(x, v);
    2.0 * ContactModel::totals(&samples).pressure_second_moment.sqrt()
}

/// Hub force x, y, hub torque and contact half-width of a finished run.
///
/// (a): at the final state (t*). (b): at the last node passage, where the steady state is
/// defined: the hub force and torque from the passage log, the half-width from the referential
/// field extracted there (a re-indexing of the deformed configuration by whole cells, which is a
/// symmetry of the mesh; velocities are not needed since the normal traction has no damping).
/// The final state itself is not used for (b): the monitor detects a passage that a step landed
/// on exactly only at the next step when φ/Δθ rounds below the integer, so a run can stop one
/// step past the passage, at a mesh phase that depends on the step (about 1 % on the half-width).
fn extract(tr: &Transient, rep: &TransientReport, part: Part) -> [f64; 4] {
    if part == Part::B {
        if let (Some(row), Some(field)) = (rep.passage_log.last(), tr.steady_field.as_ref()) {
            if field.len() == tr.state.u.len() {
                let zero = vec![0.0; field.len()];
                return [row[4], row[5], row[6], half_width(tr, field, &zero)];
            }
        }
    }
    let (f, m) = tr.hub_reaction();
    [f[0], f[1], m, half_width(tr, &tr.state.u, &tr.state.v)]
}

fn run_repeated(
    scene: &Scene,
    case: &Case,
    part: Part,
    dt_stable: f64,
    repeats: usize,
) -> Result<Outcome, String> {
    let mut first = run_once(
        scene,
        case,
        part,
        dt_stable,
        STEADY_TOL,
        scene.solver.tolerance,
    )?;
    // A failed run is not repeated: its time means nothing.
    if first.failure.is_none() && repeats > 1 {
        let mut walls = vec![first.wall];
        for _ in 1..repeats {
            let o = run_once(
                scene,
                case,
                part,
                dt_stable,
                STEADY_TOL,
                scene.solver.tolerance,
            )?;
            walls.push(o.wall);
        }
        first.wall = median(walls);
    }
    Ok(first)
}

// ---------------------------------------------------------------------------------------------
// References (cached)

/// The resolved scene without its `[scene]` (name, description) and `[output]` sections, as
/// canonical JSON: the physics and solver settings a reference depends on.
fn physics_key(scene: &Scene) -> String {
    match serde_json::to_value(scene) {
        Ok(serde_json::Value::Object(mut m)) => {
            m.remove("scene");
            m.remove("output");
            serde_json::Value::Object(m).to_string()
        }
        _ => SCENE_TEXT.to_string(),
    }
}

struct ReferenceCache {
    path: PathBuf,
    map: serde_json::Map<String, serde_json::Value>,
}

impl ReferenceCache {
    fn load(path: &Path, fresh: bool) -> Self {
        let mut map = serde_json::Map::new();
        if !fresh {
            if let Ok(text) = std::fs::read_to_string(path) {
                match serde_json::from_str::<serde_json::Value>(&text) {
                    Ok(serde_json::Value::Object(m)) => map = m,
                    _ => eprintln!(
                        "tread-bench-transient: ignoring unreadable cache {}",
                        path.display()
                    ),
                }
            }
        }
        Self {
            path: path.to_path_buf(),
            map,
        }
    }
    fn get(&self, key: &str) -> Option<Outcome> {
        let v = self.map.get(key)?;
        let vals = v.get("values")?.as_array()?;
        if vals.len() != 4 {
            return None;
        }
        let mut values = [0.0; 4];
        for (d, s) in values.iter_mut().zip(vals) {
            *d = s.as_f64()?;
        }
        Some(Outcome {
            steps: v.get("steps")?.as_u64()? as usize,
            rejected: v.get("rejected")?.as_u64()? as usize,
            newton: v.get("newton_iterations")?.as_u64()? as usize,
            wall: v.get("wall_s")?.as_f64()?,
            values,
            steady: v.get("steady")?.as_bool()?,
            time_to_steady: v.get("time_to_steady").and_then(|t| t.as_f64()),
            failure: None,
        })
    }
    fn put(&mut self, key: &str, params: serde_json::Value, o: &Outcome) {
        self.map.insert(
            key.to_string(),
            serde_json::json!({
                "parameters": params,
                "values": o.values,
                "value_names": ["hub_force_x", "hub_force_y", "hub_torque", "contact_half_width_moment"],
                "steps": o.steps,
                "rejected": o.rejected,
                "newton_iterations": o.newton,
                "wall_s": o.wall,
                "steady": o.steady,
                "time_to_steady": o.time_to_steady,
            }),
        );
        let text = match serde_json::to_string_pretty(&serde_json::Value::Object(self.map.clone()))
        {
            Ok(t) => t,
            Err(e) => {
                eprintln!("tread-bench-transient: cannot serialise the reference cache: {e}");
                return;
            }
        };
        if let Err(e) = std::fs::write(&self.path, text + "\n") {
            eprintln!(
                "tread-bench-transient: cannot write {}: {e}",
                self.path.display()
            );
        }
    }
}

/// The reference of `part` for the given mass; computed once and cached.
fn reference(
    scene: &Scene,
    cache: &mut ReferenceCache,
    part: Part,
    lumped: bool,
    plan: &Plan,
) -> Result<Outcome, String> {
    let ts = scene
        .time
        .as_ref()
        .ok_or("the scene has no [time] section")?;
    let (setting, steady_tol) = match part {
        Part::A => {
            let dt_min = plan.dts_a.iter().copied().fold(f64::INFINITY, f64::min);
            (Setting::Fixed(dt_min / REF_REFINE_A), STEADY_TOL)
        }
        Part::B => {
            let dt_min = plan.dts_b.iter().copied().fold(f64::INFINITY, f64::min);
            (
                Setting::Fixed(dt_min / REF_REFINE_B),
                STEADY_TOL / REF_STEADY_TIGHTEN,
            )
        }
    };
    let (dt, tol) = match setting {
        Setting::Fixed(dt) => (Some(dt), None),
        Setting::Adaptive(t) => (None, Some(t)),
        Setting::Stable(_) => (None, None),
    };
    let params = serde_json::json!({
        "part": if part == Part::A { "a" } else { "b" },
        "scene": SCENE_NAME,
        "scene_fnv1a": fnv1a(&physics_key(scene)),
        "overrides": OVERRIDES,
        "integrator": "generalized_alpha",
        "rho_inf": REF_RHO,
        "mass": if lumped { "lumped" } else { "consistent" },
        "dt": dt,
        "error_tol": tol,
        "t_end": if part == Part::A { T_STAR } else { ts.t_end },
        "steady_tol": if part == Part::B { Some(steady_tol) } else { None },
        "newton_tol": REF_NEWTON_TOL,
        "values_at": if part == Part::A { "t_end" } else { "last node passage" },
        "version": env!("CARGO_PKG_VERSION"),
    });
    let key = params.to_string();
    if let Some(o) = cache.get(&key) {
        eprintln!(
            "  reference ({}, {} mass): cached ({} steps, {:.1} s when computed)",
            if part == Part::A { "a" } else { "b" },
            if lumped { "lumped" } else { "consistent" },
            o.steps,
            o.wall
        );
        return Ok(o);
    }
    eprintln!(
        "  reference ({}, {} mass): computing ({}) ...",
        if part == Part::A { "a" } else { "b" },
        if lumped { "lumped" } else { "consistent" },
        match setting {
            Setting::Fixed(dt) => format!("Δt = {dt:.3e}"),
            Setting::Adaptive(t) => format!("error_tol = {t:.0e}, steady_tol = {steady_tol:.0e}"),
            Setting::Stable(_) => String::new(),
        }
    );
    // The reference uses generalized-α with the requested mass (`lumped` only for comparing
    // central difference with a model of its own mass).
    let case = Case {
        method: Method::GenAlpha(REF_RHO),
        setting,
    };
    let (mut tr, kind) = build(scene, case.scheme(), lumped)?;
    let mut opts = time_options(scene, &case, part, f64::NAN, steady_tol)?;
    opts.lumped = lumped;
    let newton = NewtonOptions {
        tol: REF_NEWTON_TOL,
        max_iterations: scene.solver.max_iterations,
        line_search: scene.solver.line_search,
        verbose: false,
        ..Default::default()
    };
    let t0 = Instant::now();
    let rep = integrate(&mut tr, &opts, newton, kind, |_, _| {})
        .map_err(|(e, r)| format!("reference run failed: {e} at t = {:.4e}", r.final_time))?;
    let wall = t0.elapsed().as_secs_f64();
    if part == Part::B && !rep.steady {
        return Err(format!(
            "reference run not steady by t = {} (steady_tol {steady_tol:.0e})",
            opts.t_end
        ));
    }
    let o = Outcome {
        steps: rep.steps,
        rejected: rep.rejected,
        newton: rep.newton_iterations,
        wall,
        values: extract(&tr, &rep, part),
        steady: rep.steady,
        time_to_steady: rep.time_to_steady,
        failure: None,
    };
    eprintln!("    done: {} steps, {wall:.1} s", o.steps);
    cache.put(&key, params, &o);
    Ok(o)
}

// ---------------------------------------------------------------------------------------------
// Errors, tables, CSV, plot, recommendation

/// Relative errors: (force vector, torque, half-width, combined). Combined: force for (a), the
/// largest of the three for (b).
fn errors(part: Part, v: &[f64; 4], r: &[f64; 4]) -> [f64; 4] {
    let ef = (v[0] - r[0]).hypot(v[1] - r[1]) / r[0].hypot(r[1]);
    let em = (v[2] - r[2]).abs() / r[2].abs();
    let ea = (v[3] - r[3]).abs() / r[3].abs();
    let comb = match part {
        Part::A => ef,
        Part::B => ef.max(em).max(ea),
    };
    [ef, em, ea, comb]
}

struct Row {
    case: Case,
    out: Outcome,
    /// Errors against the consistent-mass reference.
    err: [f64; 4],
    /// Combined error against the reference of the same mass.
    err_same_mass: f64,
}

impl Row {
    fn ok(&self) -> bool {
        self.out.failure.is_none() && self.err[3].is_finite()
    }
}

fn sci(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.2e}")
    } else {
        "—".into()
    }
}

fn print_table(part: Part, rows: &[Row], dt_stable: f64, reference: &Outcome) {
    let fastest = rows
        .iter()
        .filter(|r| r.ok())
        .map(|r| r.out.wall)
        .fold(f64::INFINITY, f64::min);
    match part {
        Part::A => {
            println!("| integrator | setting | steps | rejected | Newton its | wall [s] | × fastest | error F(t*) | error F(t*) vs same-mass ref |");
            println!("|---|---|---:|---:|---:|---:|---:|---:|---:|");
        }
        Part::B => {
            println!("| integrator | setting | steps | rejected | Newton its | t_steady [s] | wall [s] | × fastest | error F | error M | error a | error max | error max vs same-mass ref |");
            println!("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
        }
    }
    for r in rows {
        let (err_cols, note) = match &r.out.failure {
            Some(msg) => (None, format!(" **failed: {msg}**")),
            None => (Some(()), String::new()),
        };
        let wall = format!("{:.3}", r.out.wall);
        let ratio = if r.ok() {
            format!("{:.1}", r.out.wall / fastest)
        } else {
            "—".into()
        };
        let setting = format!("{}{note}", r.case.setting(dt_stable, part));
        match part {
            Part::A => println!(
                "| {} | {setting} | {} | {} | {} | {wall} | {ratio} | {} | {} |",
                r.case.integrator(),
                r.out.steps,
                r.out.rejected,
                r.out.newton,
                err_cols.map_or("—".into(), |_| sci(r.err[0])),
                err_cols.map_or("—".into(), |_| sci(r.err_same_mass)),
            ),
            Part::B => println!(
                "| {} | {setting} | {} | {} | {} | {} | {wall} | {ratio} | {} | {} | {} | {} | {} |",
                r.case.integrator(),
                r.out.steps,
                r.out.rejected,
                r.out.newton,
                r.out
                    .time_to_steady
                    .map_or("—".into(), |t| format!("{t:.4}")),
                err_cols.map_or("—".into(), |_| sci(r.err[0])),
                err_cols.map_or("—".into(), |_| sci(r.err[1])),
                err_cols.map_or("—".into(), |_| sci(r.err[2])),
                err_cols.map_or("—".into(), |_| sci(r.err[3])),
                err_cols.map_or("—".into(), |_| sci(r.err_same_mass)),
            ),
        }
    }
    let v = reference.values;
    match part {
        Part::A => println!(
            "\nReference F(t* = {T_STAR}) = ({:.6e}, {:.6e}) ({} steps, generalized-α ρ∞ = {REF_RHO}, consistent mass).",
            v[0], v[1], reference.steps
        ),
        Part::B => println!(
            "\nReference steady state: F = ({:.6e}, {:.6e}), M = {:.6e}, a = {:.6e}, t_steady = {} ({} steps, generalized-α ρ∞ = {REF_RHO}, consistent mass).",
            v[0],
            v[1],
            v[2],
            v[3],
            reference
                .time_to_steady
                .map_or("—".into(), |t| format!("{t:.4}")),
            reference.steps
        ),
    }
}

fn write_rows_csv(path: &Path, part: Part, rows: &[Row], dt_stable: f64) -> Result<(), String> {
    let fastest = rows
        .iter()
        .filter(|r| r.ok())
        .map(|r| r.out.wall)
        .fold(f64::INFINITY, f64::min);
    let header = [
        "scheme",
        "rho_inf",
        "adaptive",
        "dt",
        "error_tol",
        "stable_fraction",
        "steps",
        "rejected",
        "newton_iterations",
        "wall_s",
        "wall_over_fastest",
        "time_to_steady",
        "hub_force_x",
        "hub_force_y",
        "hub_torque",
        "contact_half_width",
        "error_force",
        "error_torque",
        "error_half_width",
        "error",
        "error_same_mass_reference",
        "failed",
    ];
    let data = rows.iter().map(|r| {
        let mut v = r.case.csv_codes(dt_stable, part).to_vec();
        let ok = r.ok();
        let nan = f64::NAN;
        v.extend([
            r.out.steps as f64,
            r.out.rejected as f64,
            r.out.newton as f64,
            r.out.wall,
            if ok { r.out.wall / fastest } else { nan },
            r.out.time_to_steady.unwrap_or(nan),
        ]);
        v.extend(r.out.values);
        if ok {
            v.extend(r.err);
            v.push(r.err_same_mass);
        } else {
            v.extend([nan; 5]);
        }
        v.push(if ok { 0.0 } else { 1.0 });
        v
    });
    tread::io::output::write_csv(path, &header, data).map_err(|e| e.to_string())
}

fn series_color(s: &str) -> RGBColor {
    if s.contains("ρ∞=1.0") {
        RGBColor(31, 119, 180)
    } else if s.contains("ρ∞=0.8") {
        RGBColor(214, 39, 40)
    } else if s.contains("ρ∞=0.5") {
        RGBColor(44, 160, 44)
    } else if s.contains("bdf") {
        RGBColor(255, 127, 14)
    } else if s.contains("sdirk") {
        RGBColor(140, 86, 75)
    } else {
        RGBColor(148, 103, 189)
    }
}

/// Log–log PNG (plotters): error vs wall time, one polyline per series (fixed steps: solid
/// with circles; adaptive: dashed with triangles; central difference: crosses).
fn write_png(path: &Path, title: &str, rows: &[Row], repeats: usize) -> Result<(), String> {
    let mut series: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for r in rows
        .iter()
        .filter(|r| r.ok() && r.err[3] > 0.0 && r.out.wall > 0.0)
    {
        let name = r.case.series();
        let p = (r.out.wall, r.err[3]);
        match series.iter_mut().find(|(n, _)| *n == name) {
            Some((_, pts)) => pts.push(p),
            None => series.push((name, vec![p])),
        }
    }
    // Log–log: the points in log10 coordinates on decade axes.
    for (_, pts) in series.iter_mut() {
        for p in pts.iter_mut() {
            *p = (p.0.log10(), p.1.log10());
        }
    }
    let pts = || series.iter().flat_map(|(_, p)| p.iter());
    let xa = AxisLayout::new(Scale::Log10, pts().map(|p| p.0));
    let ya = AxisLayout::new(Scale::Log10, pts().map(|p| p.1));
    png::register_font()?;
    let e = |e: &dyn std::fmt::Display| format!("{}: {e}", path.display());
    let root = BitMapBackend::new(path, (960, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(14)
        .x_label_area_size(48)
        .y_label_area_size(80)
        .build_cartesian_2d(xa.clone(), ya.clone())
        .map_err(|x| e(&x))?;
    chart
        .configure_mesh()
        .x_desc(format!("wall time [s] (median of {repeats})"))
        .y_desc("relative error vs reference")
        .x_label_formatter(&|v| xa.label(*v, false))
        .y_label_formatter(&|v| ya.label(*v, false))
        .draw()
        .map_err(|x| e(&x))?;
    for (name, p) in &series {
        let c = series_color(name);
        let style = c.stroke_width(2);
        if name.contains("adaptive") {
            chart
                .draw_series(DashedLineSeries::new(p.iter().copied(), 8, 5, style))
                .map_err(|x| e(&x))?
                .label(name.as_str())
                .legend(move |(x, y)| {
                    plotters::element::DashedPathElement::new(
                        vec![(x, y), (x + 22, y)],
                        5,
                        3,
                        style,
                    )
                });
            chart
                .draw_series(p.iter().map(|q| TriangleMarker::new(*q, 5, c.filled())))
                .map_err(|x| e(&x))?;
        } else {
            chart
                .draw_series(LineSeries::new(p.iter().copied(), style))
                .map_err(|x| e(&x))?
                .label(name.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 22, y)], style));
            if name.contains("central") {
                chart
                    .draw_series(p.iter().map(|q| Cross::new(*q, 5, c.stroke_width(2))))
                    .map_err(|x| e(&x))?;
            } else {
                chart
                    .draw_series(p.iter().map(|q| Circle::new(*q, 4, c.filled())))
                    .map_err(|x| e(&x))?;
            }
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|x| e(&x))?;
    root.present().map_err(|x| e(&x))
}

/// Cheapest run of each series reaching `target`, sorted by wall time. A run counts only if it
/// and every finer run of its series (smaller step or tolerance; the cases are listed coarse to
/// fine) have an error ≤ target: a coarse run that lands near the reference by chance (e.g. a
/// strongly damped step that removes an oscillation the reference happens to cross at t*) does
/// not count.
fn cheapest_by_series(rows: &[Row], target: f64) -> Vec<(String, &Row)> {
    let mut best: Vec<(String, &Row)> = Vec::new();
    for (i, r) in rows.iter().enumerate() {
        if !r.ok() {
            continue;
        }
        let name = r.case.series();
        let worst_finer = rows[i..]
            .iter()
            .filter(|q| q.ok() && q.case.series() == name)
            .map(|q| q.err[3])
            .fold(0.0, f64::max);
        if worst_finer > target {
            continue;
        }
        match best.iter_mut().find(|(n, _)| *n == name) {
            Some((_, b)) => {
                if r.out.wall < b.out.wall {
                    *b = r;
                }
            }
            None => best.push((name, r)),
        }
    }
    best.sort_by(|a, b| a.1.out.wall.total_cmp(&b.1.out.wall));
    best
}

/// Recommendation computed from the numbers; returns, per target, the cost ratio of the
/// default family (generalized-α ρ∞ = default, adaptive) to the cheapest (None: not reached).
fn recommend(
    part: Part,
    rows: &[Row],
    dt_stable: f64,
    winners: &mut Vec<(f64, String)>,
) -> Vec<(f64, Option<f64>)> {
    let default_series = format!("GA ρ∞={DEFAULT_RHO_INF:.1} adaptive");
    let mut out = Vec::new();
    for &target in &TARGETS {
        let best = cheapest_by_series(rows, target);
        let Some((name, b)) = best.first() else {
            println!("- error ≤ {target:.0e}: no run reached it.");
            out.push((target, None));
            continue;
        };
        winners.push((target, name.clone()));
        let others: Vec<String> = best
            .iter()
            .skip(1)
            .map(|(n, r)| format!("{n} {:.3} s ({:.1}×)", r.out.wall, r.out.wall / b.out.wall))
            .collect();
        let missing: Vec<String> = {
            let mut all: Vec<String> = Vec::new();
            for r in rows {
                let n = r.case.series();
                if !all.contains(&n) && !best.iter().any(|(m, _)| *m == n) {
                    all.push(n);
                }
            }
            all
        };
        println!(
            "- error ≤ {target:.0e}: cheapest is **{name}** ({}, {:.3} s, error {:.2e}); then {}{}",
            b.case.setting(dt_stable, part),
            b.out.wall,
            b.err[3],
            if others.is_empty() {
                "none".into()
            } else {
                others.join(", ")
            },
            if missing.is_empty() {
                String::new()
            } else {
                format!("; not reached by {}", missing.join(", "))
            }
        );
        let ratio = best
            .iter()
            .find(|(n, _)| *n == default_series)
            .map(|(_, r)| r.out.wall / b.out.wall);
        out.push((target, ratio));
    }
    out
}

fn main() {
    let args = match parse_args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("tread-bench-transient: {e}");
            std::process::exit(2);
        }
    };
    if let Err(e) = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads)
        .build_global()
    {
        eprintln!(
            "tread-bench-transient: cannot configure {} threads: {e}",
            args.threads
        );
    }
    if let Err(e) = run(&args) {
        eprintln!("tread-bench-transient: {e}");
        std::process::exit(1);
    }
}

fn run(args: &Args) -> Result<(), String> {
    let t_all = Instant::now();
    std::fs::create_dir_all(&args.out)
        .map_err(|e| format!("cannot create {}: {e}", args.out.display()))?;
    let scene = base_scene()?;
    let plan = Plan::new(args.quick);
    let mut cache = ReferenceCache::load(
        &args.out.join("transient_reference.json"),
        args.fresh_reference,
    );
    // Stable-step estimate of central difference (as `integrate` computes it, at t = 0).
    let dt_stable = {
        let (mut tr, _) = build(&scene, Scheme::central_difference(), true)?;
        let delta_ref = tr.kin.disp.map_or(0.0, |d| d.target);
        tr.stable_step(delta_ref)
    };
    if !dt_stable.is_finite() {
        return Err("the stable-step estimate of central difference failed".into());
    }
    let ts = scene
        .time
        .as_ref()
        .ok_or("the scene has no [time] section")?;
    println!("# Transient integrators: work–precision\n");
    println!(
        "Scene {SCENE_NAME} with {} ({} dofs); Newton tolerance {:.0e}; adaptive runs start at Δt = {:.1e} with Δt ∈ [{:.1e}, {:.1e}] (the scene's defaults); central-difference stable-step estimate Δt_stable = {dt_stable:.4e} s; wall time = median of {} run(s) of `integrate()` on {} thread(s){}.\n",
        OVERRIDES.join(", "),
        build(&scene, Scheme::central_difference(), true)?.0.sys.n_dofs(),
        scene.solver.tolerance,
        ts.dt,
        ts.resolved_dt_min(),
        ts.resolved_dt_max(),
        args.repeats,
        args.threads,
        if args.quick { ", --quick" } else { "" }
    );
    let mut verdicts = Vec::new();
    let mut failed_cd = Vec::new();
    let mut winners = Vec::new();
    for part in [Part::A, Part::B] {
        let tag = if part == Part::A { "a" } else { "b" };
        eprintln!("part ({tag}):");
        let r_cons = reference(&scene, &mut cache, part, false, &plan)?;
        let r_lump = reference(&scene, &mut cache, part, true, &plan)?;
        let mut rows = Vec::new();
        for case in plan.cases(part) {
            let out = run_repeated(&scene, &case, part, dt_stable, args.repeats)?;
            let err = errors(part, &out.values, &r_cons.values);
            let own = if case.lumped() { &r_lump } else { &r_cons };
            let err_same_mass = errors(part, &out.values, &own.values)[3];
            eprintln!(
                "  {} {}: {} steps, {:.3} s, error {:.2e}{}",
                case.integrator(),
                case.setting(dt_stable, part),
                out.steps,
                out.wall,
                err[3],
                out.failure
                    .as_ref()
                    .map_or(String::new(), |f| format!(" (failed: {f})"))
            );
            rows.push(Row {
                case,
                out,
                err,
                err_same_mass,
            });
        }
        match part {
            Part::A => println!(
                "## (a) Hub force at t* = {T_STAR} s (fixed steps land on t*)\n\nError: |F − F_ref| / |F_ref| of the hub force vector at t*.\n"
            ),
            Part::B => println!(
                "## (b) Steady rolling (stop_at_steady, steady_tol = {:.0e}, steps land on node passages)\n\nErrors against the steady reference: hub force vector F, hub torque M, contact half-width a = 2 √⟨x²⟩; error max = the largest.\n",
                STEADY_TOL
            ),
        }
        print_table(part, &rows, dt_stable, &r_cons);
        let csv = args.out.join(format!("transient_work_precision_{tag}.csv"));
        write_rows_csv(&csv, part, &rows, dt_stable)?;
        let png = args.out.join(format!("transient_work_precision_{tag}.png"));
        let title = match part {
            Part::A => format!("(a) hub force at t* = {T_STAR} s: error vs wall time"),
            Part::B => "(b) steady hub force, torque, half-width: error vs wall time".to_string(),
        };
        write_png(&png, &title, &rows, args.repeats)?;
        println!("\nWritten {} and {}.\n", csv.display(), png.display());
        println!("Cheapest run reaching each error level ({tag}; a run counts only if every finer run of its series also does):\n");
        verdicts.push((tag, recommend(part, &rows, dt_stable, &mut winners)));
        for r in rows.iter().filter(|r| !r.ok()) {
            if let Setting::Stable(f) = r.case.setting {
                failed_cd.push((tag, f));
            }
        }
        println!();
    }
    println!("## Recommendation\n");
    println!(
        "The program's default integrator is generalized-α with ρ∞ = {DEFAULT_RHO_INF} and the adaptive step control (error_tol = {DEFAULT_ERROR_TOL:.0e} by default; the scene uses {:.0e}). Cost of that family relative to the cheapest integrator at each error level:\n",
        ts.error_tol
    );
    let mut ratios = Vec::new();
    for (tag, v) in &verdicts {
        let cells: Vec<String> = v
            .iter()
            .map(|(t, r)| match r {
                Some(r) => {
                    ratios.push(*r);
                    format!("≤ {t:.0e}: {r:.2}×")
                }
                None => format!("≤ {t:.0e}: not reached by the default"),
            })
            .collect();
        println!("- ({tag}) {}", cells.join("; "));
    }
    let cd_failed: Vec<String> = failed_cd
        .iter()
        .map(|(tag, f)| format!("({tag}) {f:.3} Δt_stable"))
        .collect();
    if !cd_failed.is_empty() {
        let own_step = failed_cd.iter().any(|(_, f)| *f >= 0.9 - 1e-12);
        println!(
            "\nCentral difference failed at {}{}.",
            cd_failed.join(", "),
            if own_step {
                " — 0.9 Δt_stable is the step the program itself takes (`integrate` uses 0.9 × the estimate of `Transient::stable_step`, computed from the undamped M_L⁻¹K, while the strain-rate viscosity lowers the explicit stability limit); the smaller fractions were chosen here by hand, so the explicit timings assume a step the program would not find by itself"
            } else {
                ""
            }
        );
    }
    // Overall: which family is cheapest most often over the (part, level) pairs reached.
    let mut wins: Vec<(String, usize)> = Vec::new();
    let mut reached = 0;
    for (_, w) in &winners {
        reached += 1;
        match wins.iter_mut().find(|(n, _)| n == w) {
            Some((_, k)) => *k += 1,
            None => wins.push((w.clone(), 1)),
        }
    }
    wins.sort_by_key(|w| std::cmp::Reverse(w.1));
    if let Some((w, k)) = wins.first() {
        println!(
            "\nCheapest integrator overall: **{w}**, cheapest at {k} of the {reached} (part, error level) pairs that some run reached{}.",
            if wins.len() > 1 {
                format!(
                    " (others: {})",
                    wins[1..]
                        .iter()
                        .map(|(n, k)| format!("{n} {k}"))
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            } else {
                String::new()
            }
        );
    }
    if ratios.is_empty() {
        println!("\nThe default reached none of the error levels: the numbers do not support it.");
    } else {
        let worst = ratios.iter().copied().fold(0.0, f64::max);
        let gmean = (ratios.iter().map(|r| r.ln()).sum::<f64>() / ratios.len() as f64).exp();
        let verdict = if worst <= 1.5 {
            "support it: it is the cheapest or within 1.5× of the cheapest at every level it reaches"
        } else if gmean <= 1.5 {
            "mostly support it: within 1.5× of the cheapest on geometric mean, but not at every level"
        } else {
            "do not support it: another integrator is clearly cheaper"
        };
        println!(
            "\nGeometric-mean cost ratio {gmean:.2}×, worst {worst:.2}×: the numbers {verdict}."
        );
    }
    println!(
        "\nTotal benchmark time {:.1} s.",
        t_all.elapsed().as_secs_f64()
    );
    Ok(())
}
