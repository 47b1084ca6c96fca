//! `[time]`: time integration of the transient mode (integrator, steps in T, error and steady
//! tolerances, mass matrix), and the rule that steady-state extraction needs a mesh uniform in θ.

use super::analysis::Mode;
use super::issue::{issue, positive, Issue};
use super::mesh::MeshSpec;
use serde::{Deserialize, Serialize};

/// Time integrator of the `transient` mode (`[time] integrator`): a name and what it declares
/// ([`crate::solver::integrators`]).
pub use crate::solver::integrators::IntegratorName;

keyword_enum! {
    /// Mass matrix of the `transient` mode (`[time] mass`).
    #[derive(Default)]
    MassKind, "mass matrix" {
        #[default]
        /// Consistent mass matrix.
        Consistent => "consistent",
        /// Lumped (diagonal, HRZ-type for Q2) mass matrix.
        Lumped => "lumped",
    }
}

/// `[time]`: time integration of the `transient` mode (required there). The steady mode reads
/// `strain_rate_damping` only, and a steady scene may leave out `dt` and `t_end`
/// ([`TimeSpec::steady_only`]).
/// `dt_min` and `dt_max` stay `None` when not given (their defaults follow `dt`; see
/// [`TimeSpec::resolved_dt_min`], [`TimeSpec::resolved_dt_max`]). After
/// [`Scene::from_toml_str`], `mass` is `lumped` for `central_difference` (which always uses the
/// lumped mass; an explicit `"consistent"` with it is an error).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeSpec {
    /// Time integrator.
    #[serde(default)]
    pub integrator: IntegratorName,
    /// Spectral radius at infinity of generalized-α, in [0, 1] (1 = trapezoidal / Newmark
    /// average acceleration: no numerical dissipation), or of HHT-α, in [0.5, 1]. Used only by
    /// `generalized_alpha` and `hht_alpha`.
    #[serde(default = "default_rho_inf")]
    pub rho_inf: f64,
    /// Initial time step (time, > 0, <= t_end). NaN in a steady scene that left it out
    /// ([`Self::steady_only`]).
    #[serde(skip_serializing_if = "is_nan")]
    pub dt: f64,
    /// Smallest step (time, > 0, <= dt); `None` = `dt · 1e-4`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dt_min: Option<f64>,
    /// Largest step (time, >= dt); `None` = `dt · 10`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dt_max: Option<f64>,
    /// Maximum simulated time (time, > 0); the run stops earlier when steady if
    /// `stop_at_steady`. NaN in a steady scene that left it out ([`Self::steady_only`]).
    #[serde(skip_serializing_if = "is_nan")]
    pub t_end: f64,
    /// Step-size control from a local error estimate.
    #[serde(default = "default_true")]
    pub adaptive: bool,
    /// Relative local error tolerance of the step-size control (> 0).
    #[serde(default = "default_error_tol")]
    pub error_tol: f64,
    /// Relative change of the referential field, hub forces and torque over one node passage
    /// below which rolling is declared steady (> 0).
    #[serde(default = "default_steady_tol")]
    pub steady_tol: f64,
    /// Stop as soon as rolling is steady.
    #[serde(default = "default_true")]
    pub stop_at_steady: bool,
    /// Mass matrix (`central_difference`: always lumped).
    #[serde(default)]
    pub mass: MassKind,
    /// Maximum number of time steps (>= 1).
    #[serde(default = "default_max_steps")]
    pub max_steps: usize,
    /// Objective viscous damping on the rate of Green strain, S_v = η Ė (stress·time, >= 0;
    /// default 0). Damps the transient towards steady rolling without damping rigid rotation.
    #[serde(default)]
    pub strain_rate_damping: f64,
}

/// Default of `[time] rho_inf`.
pub const DEFAULT_RHO_INF: f64 = 0.8;

/// `dt_min = DT_MIN_FACTOR · dt` when not given.
pub const DT_MIN_FACTOR: f64 = 1e-4;

/// `dt_max = DT_MAX_FACTOR · dt` when not given.
pub const DT_MAX_FACTOR: f64 = 10.0;

/// Default of `[time] error_tol`.
pub const DEFAULT_ERROR_TOL: f64 = 1e-4;

/// Default of `[time] steady_tol`.
pub const DEFAULT_STEADY_TOL: f64 = 1e-4;

/// Default of `[time] max_steps`.
pub const DEFAULT_MAX_STEPS: usize = 200_000;

fn is_nan(v: &f64) -> bool {
    v.is_nan()
}

pub(super) fn default_rho_inf() -> f64 {
    DEFAULT_RHO_INF
}

pub(super) fn default_true() -> bool {
    true
}

pub(super) fn default_error_tol() -> f64 {
    DEFAULT_ERROR_TOL
}

pub(super) fn default_steady_tol() -> f64 {
    DEFAULT_STEADY_TOL
}

pub(super) fn default_max_steps() -> usize {
    DEFAULT_MAX_STEPS
}

impl TimeSpec {
    /// A `[time]` with the given initial step and end time and every other key at its default.
    pub fn new(dt: f64, t_end: f64) -> TimeSpec {
        TimeSpec {
            integrator: IntegratorName::default(),
            rho_inf: DEFAULT_RHO_INF,
            dt,
            dt_min: None,
            dt_max: None,
            t_end,
            adaptive: true,
            error_tol: DEFAULT_ERROR_TOL,
            steady_tol: DEFAULT_STEADY_TOL,
            stop_at_steady: true,
            mass: MassKind::default(),
            max_steps: DEFAULT_MAX_STEPS,
            strain_rate_damping: 0.0,
        }
    }

    /// The smallest step: `dt_min`, or `dt · 1e-4` when not given.
    pub fn resolved_dt_min(&self) -> f64 {
        self.dt_min.unwrap_or(self.dt * DT_MIN_FACTOR)
    }

    /// The largest step: `dt_max`, or `dt · 10` when not given.
    pub fn resolved_dt_max(&self) -> f64 {
        self.dt_max.unwrap_or(self.dt * DT_MAX_FACTOR)
    }

    /// The mass matrix actually used: `lumped` for an integrator that always lumps it
    /// (`central_difference`), else `mass`.
    pub fn effective_mass(&self) -> MassKind {
        if self.integrator.lumped_only() {
            MassKind::Lumped
        } else {
            self.mass
        }
    }

    /// Whether the integrator is explicit (always uses the lumped mass: `central_difference`).
    pub fn is_explicit(&self) -> bool {
        self.integrator.lumped_only()
    }

    /// A steady scene's `[time]` without `dt` or `t_end` (it gives `strain_rate_damping`, the
    /// one key the steady mode reads): no time integration can run from it.
    pub fn steady_only(&self) -> bool {
        self.dt.is_nan() || self.t_end.is_nan()
    }
}

fn validate_damping(t: &TimeSpec, out: &mut Vec<Issue>) {
    if !(t.strain_rate_damping >= 0.0 && t.strain_rate_damping.is_finite()) {
        out.push(issue(
            "time.strain_rate_damping",
            format!(
                "Green-strain-rate viscosity must be >= 0, got {}",
                t.strain_rate_damping
            ),
        ));
    }
}

pub(super) fn validate_time(t: &TimeSpec, mass_given: bool, steady: bool, out: &mut Vec<Issue>) {
    if steady && t.steady_only() {
        // Only strain_rate_damping (and keys the steady mode ignores) to check.
        validate_damping(t, out);
        return;
    }
    let dt_ok = positive(t.dt);
    if !dt_ok {
        out.push(issue(
            "time.dt",
            format!("initial time step must be > 0, got {}", t.dt),
        ));
    }
    let t_end_ok = positive(t.t_end);
    if !t_end_ok {
        out.push(issue(
            "time.t_end",
            format!("end time must be > 0, got {}", t.t_end),
        ));
    }
    if dt_ok && t_end_ok && t.dt > t.t_end {
        out.push(issue(
            "time.dt",
            format!(
                "initial time step dt = {} must not exceed t_end = {}",
                t.dt, t.t_end
            ),
        ));
    }
    let rho_min = t.integrator.rho_inf_min();
    if !(t.rho_inf.is_finite() && (rho_min..=1.0).contains(&t.rho_inf)) {
        out.push(issue(
            "time.rho_inf",
            format!(
                "spectral radius at infinity of integrator \"{}\" must be in [{rho_min}, 1], got {}",
                t.integrator, t.rho_inf
            ),
        ));
    }
    if let Some(x) = t.dt_min {
        if !positive(x) {
            out.push(issue(
                "time.dt_min",
                format!("smallest time step must be > 0, got {x}"),
            ));
        } else if dt_ok && x > t.dt {
            out.push(issue(
                "time.dt_min",
                format!(
                    "smallest time step dt_min = {x} must not exceed dt = {}",
                    t.dt
                ),
            ));
        }
    }
    if let Some(x) = t.dt_max {
        if !positive(x) {
            out.push(issue(
                "time.dt_max",
                format!("largest time step must be > 0, got {x}"),
            ));
        } else if dt_ok && x < t.dt {
            out.push(issue(
                "time.dt_max",
                format!("largest time step dt_max = {x} must be >= dt = {}", t.dt),
            ));
        }
    }
    if !positive(t.error_tol) {
        out.push(issue(
            "time.error_tol",
            format!(
                "relative local error tolerance must be > 0, got {}",
                t.error_tol
            ),
        ));
    }
    if !positive(t.steady_tol) {
        out.push(issue(
            "time.steady_tol",
            format!("steady-state tolerance must be > 0, got {}", t.steady_tol),
        ));
    }
    if t.max_steps < 1 {
        out.push(issue("time.max_steps", "must be >= 1, got 0"));
    }
    validate_damping(t, out);
    if mass_given && t.integrator.lumped_only() && t.mass == MassKind::Consistent {
        out.push(issue(
            "time.mass",
            format!(
                "integrator \"{}\" always uses the lumped mass: mass must be \"lumped\" or \
                 omitted, got \"consistent\"",
                t.integrator
            ),
        ));
    }
}

/// A transient run that stops at the steady state extracts it by re-indexing nodes by whole
/// nodal angle steps, which needs a mesh uniform in θ.
pub(super) fn validate_steady_extraction(
    mode: Option<Mode>,
    m: &MeshSpec,
    t: &TimeSpec,
    out: &mut Vec<Issue>,
) {
    // An out-of-range grading is reported by validate_mesh.
    let graded = m.grading_theta > 0.0 && m.grading_theta < 1.0;
    if mode == Some(Mode::Transient) && t.stop_at_steady && graded {
        out.push(issue(
            "mesh.grading_theta",
            format!(
                "a transient run that stops at the steady state (time.stop_at_steady) needs a \
                 mesh uniform in θ: the steady state is extracted by re-indexing nodes by whole \
                 nodal angle steps; set grading_theta = 0 (or time.stop_at_steady = false), got {}",
                m.grading_theta
            ),
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::scene::tests::*;
    use crate::io::scene::*;

    #[test]
    fn time_defaults_are_filled() {
        let s = load(&minimal_transient()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.analysis.mode, Mode::Transient);
        // A spinning cylinder in time: no road, no contact.
        assert_eq!((&s.road, &s.contact), (&None, &None));
        assert_eq!(s.motion.ramp, 0.0);
        let t = s.time.unwrap_or_else(|| panic!("no [time]"));
        assert_eq!(t, TimeSpec::new(1e-3, 0.5));
        assert_eq!(t.integrator, IntegratorName::GeneralizedAlpha);
        assert_eq!(t.rho_inf, DEFAULT_RHO_INF);
        assert_eq!(t.rho_inf, 0.8);
        assert_eq!((t.dt_min, t.dt_max), (None, None));
        assert_eq!(t.resolved_dt_min(), 1e-3 * DT_MIN_FACTOR);
        assert_eq!(t.resolved_dt_max(), 1e-3 * DT_MAX_FACTOR);
        assert!(t.adaptive && t.stop_at_steady);
        assert_eq!((t.error_tol, t.steady_tol), (1e-4, 1e-4));
        assert_eq!(t.mass, MassKind::Consistent);
        assert_eq!(t.max_steps, 200_000);
        assert_eq!(t.max_steps, DEFAULT_MAX_STEPS);

        // Road defaults in transient: no ramps, v0_ramp follows motion.ramp.
        let text = remove_section(&remove_section(ODEN, "[road]"), "[time]")
            + "[road]\ndisp = 0.05\nv0 = 3.0\n[time]\ndt = 1e-3\nt_end = 1\n";
        let s = load(&text).unwrap_or_else(|e| panic!("{e}"));
        let road = s.road.unwrap_or_else(|| panic!("no [road]"));
        assert_eq!((road.ramp, road.v0_ramp), (0.0, None));
        assert_eq!(road.resolved_v0_ramp(&s.motion), s.motion.ramp);
        assert_eq!(road.resolved_v0_ramp(&s.motion), 0.05);
    }

    #[test]
    fn time_ranges_rejected_with_key_and_line() {
        let cases: [(&str, &str, &str, &str); 14] = [
            ("dt =", "dt = 0.0", "time.dt", "> 0"),
            ("dt =", "dt = -2e-4", "time.dt", "> 0"),
            ("t_end", "t_end = 0", "time.t_end", "> 0"),
            ("t_end", "t_end = -1.0", "time.t_end", "> 0"),
            ("dt =", "dt = 3.0", "time.dt", "must not exceed t_end"),
            ("rho_inf", "rho_inf = -0.1", "time.rho_inf", "[0, 1]"),
            ("rho_inf", "rho_inf = 1.01", "time.rho_inf", "[0, 1]"),
            (
                "dt =",
                "dt = 2e-4\ndt_min = 3e-4",
                "time.dt_min",
                "must not exceed dt",
            ),
            ("dt =", "dt = 2e-4\ndt_min = 0", "time.dt_min", "> 0"),
            ("dt =", "dt = 2e-4\ndt_max = 1e-4", "time.dt_max", ">= dt"),
            ("error_tol", "error_tol = 0.0", "time.error_tol", "> 0"),
            ("steady_tol", "steady_tol = 0", "time.steady_tol", "> 0"),
            ("steady_tol", "steady_tol = -1e-3", "time.steady_tol", "> 0"),
            ("max_steps", "max_steps = 0", "time.max_steps", ">= 1"),
        ];
        for (prefix, new, key, what) in cases {
            let text = replace_line(ODEN, prefix, new);
            let e = errors(&text);
            let field = key.trim_start_matches("time.");
            assert_only(&e, key, Some(line_of(&text, &format!("{field} ="))));
            assert!(e.0[0].message.contains(what), "{new}: {e}");
            assert!(
                e.0[0].to_string().starts_with(&format!(
                    "test.toml:{}: key `{key}`",
                    line_of(&text, &format!("{field} ="))
                )),
                "{e}"
            );
        }
        // Boundary values are accepted.
        for ok in [
            ("rho_inf", "rho_inf = 0"),
            ("rho_inf", "rho_inf = 1.0"),
            ("dt =", "dt = 2e-4\ndt_min = 2e-4\ndt_max = 2e-4"),
            ("dt =", "dt = 2.0"),
        ] {
            let text = replace_line(ODEN, ok.0, ok.1);
            assert!(load(&text).is_ok(), "{}", ok.1);
        }
        // Several problems of [time] at once, each on its own line.
        let text = replace_line(ODEN, "rho_inf", "rho_inf = 2");
        let text = replace_line(&text, "t_end", "t_end = 0");
        let text = replace_line(&text, "error_tol", "error_tol = -1");
        let e = errors(&text);
        assert_eq!(e.0.len(), 3, "{e}");
        for key in ["rho_inf", "t_end", "error_tol"] {
            let err = e
                .find(&format!("time.{key}"))
                .unwrap_or_else(|| panic!("{e}"));
            assert_eq!(err.line, Some(line_of(&text, key)));
        }
        // Missing required keys: at the [time] header.
        let text = ODEN
            .lines()
            .filter(|l| !l.starts_with("dt =") && !l.starts_with("t_end"))
            .collect::<Vec<_>>()
            .join("\n");
        let e = errors(&text);
        assert_eq!(e.0.len(), 2, "{e}");
        for key in ["time.dt", "time.t_end"] {
            let err = e.find(key).unwrap_or_else(|| panic!("{e}"));
            assert_eq!(err.line, Some(line_of(&text, "[time]")));
            assert!(err.message.contains("required key is missing"), "{err}");
        }
        // Wrong types and unknown values.
        let text = replace_line(ODEN, "integrator", "integrator = \"newmark\"");
        let e = errors(&text);
        assert_only(&e, "time.integrator", Some(line_of(&text, "integrator")));
        assert!(e.0[0].message.contains("\"generalized_alpha\""), "{e}");
        let text = replace_line(ODEN, "adaptive", "adaptive = 1");
        let e = errors(&text);
        assert_only(&e, "time.adaptive", Some(line_of(&text, "adaptive")));
        let text = replace_line(ODEN, "max_steps", "max_steps = 1.5");
        let e = errors(&text);
        assert_only(&e, "time.max_steps", Some(line_of(&text, "max_steps")));
        let text = replace_line(ODEN, "dt =", "dt = 2e-4\ndt_step = 1");
        let e = errors(&text);
        assert_only(&e, "time.dt_step", Some(line_of(&text, "dt_step")));
        assert!(e.0[0].message.contains("steady_tol"), "{e}");
    }

    #[test]
    fn central_difference_uses_lumped_mass() {
        // Explicit consistent mass with central difference: named at its line.
        let text = replace_line(ODEN, "integrator", "integrator = \"central_difference\"");
        let e = errors(&text);
        assert_only(&e, "time.mass", Some(line_of(&text, "mass =")));
        assert!(e.0[0].message.contains("lumped"), "{e}");
        // Omitted: resolved to lumped (and written so by to_toml_string).
        let text = text
            .lines()
            .filter(|l| !l.starts_with("mass ="))
            .collect::<Vec<_>>()
            .join("\n");
        let s = load(&text).unwrap_or_else(|e| panic!("{e}"));
        let t = s.time.clone().unwrap_or_else(|| panic!("no [time]"));
        assert_eq!(t.integrator, IntegratorName::CentralDifference);
        assert_eq!(
            (t.mass, t.effective_mass()),
            (MassKind::Lumped, MassKind::Lumped)
        );
        assert!(t.is_explicit());
        let out = s.to_toml_string();
        assert!(out.contains("mass = \"lumped\""), "{out}");
        assert_eq!(load(&out).unwrap_or_else(|e| panic!("{e}\n{out}")), s);
        // Explicit lumped is fine; an override back to consistent is reported as (--set).
        assert!(load(&replace_line(
            &text,
            "integrator",
            "integrator = \"central_difference\"\nmass = \"lumped\""
        ))
        .is_ok());
        let e = errors_with(&text, &["time.mass=consistent"]);
        assert_only(&e, "time.mass", None);
        assert!(e.0[0].is_override(), "{e}");
        // An unknown mass is reported once, not also as "consistent".
        let e = errors_with(&text, &["time.mass=diagonal"]);
        assert_only(&e, "time.mass", None);
        assert!(e.0[0].message.contains("\"lumped\""), "{e}");
        // Other integrators keep the consistent default.
        let s = load_with(ODEN, &["time.integrator=bdf"]).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.time.map(|t| t.mass), Some(MassKind::Consistent));
        let s = load_with(ODEN, &["time.integrator=sdirk", "time.mass=lumped"])
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            s.time.map(|t| (t.integrator, t.mass)),
            Some((IntegratorName::Sdirk, MassKind::Lumped))
        );
    }

    #[test]
    fn time_section_only_in_transient() {
        let time = "\n[time]\ndt = 1e-3\nt_end = 1.0\n";
        for base in [MINIMAL, FRICTIONLESS, STICK_SLIP] {
            let text = format!("{base}{time}");
            let e = errors(&text);
            assert_only(&e, "time", Some(line_of(&text, "[time]")));
            assert!(e.0[0].message.contains("not used"), "{e}");
            assert!(e.0[0].message.contains("\"transient\""), "{e}");
        }
        // Created by an override: (--set).
        let e = errors_with(MINIMAL, &["time.dt=1e-3", "time.t_end=1"]);
        assert_only(&e, "time", None);
        assert!(e.0[0].is_override(), "{e}");
        // Required in transient: at the line of `mode`.
        let text = remove_section(ODEN, "[time]");
        let e = errors(&text);
        assert_only(&e, "time", Some(line_of(&text, "mode =")));
        assert!(e.0[0].message.contains("missing"), "{e}");
        assert!(e.0[0].message.contains("dt, t_end"), "{e}");
        // [stick_slip] in a transient scene.
        let text = format!(
            "{ODEN}\n[stick_slip]\nmass = 1\nstiffness = 1\nnormal_force = 1\nbelt_speed = 1\n\
             t_end = 1\n"
        );
        let e = errors(&text);
        assert_only(&e, "stick_slip", Some(line_of(&text, "[stick_slip]")));
    }

    #[test]
    fn graded_mesh_rejected_when_stopping_at_steady() {
        let text = replace_line(ODEN, "grading_theta", "grading_theta = 0.5");
        let e = errors(&text);
        assert_only(
            &e,
            "mesh.grading_theta",
            Some(line_of(&text, "grading_theta")),
        );
        assert!(e.0[0].message.contains("uniform in θ"), "{e}");
        // Without stopping at the steady state a graded mesh is allowed.
        let text = replace_line(&text, "stop_at_steady", "stop_at_steady = false");
        assert!(load(&text).is_ok());
        // An out-of-range grading is reported once.
        let e = errors(&replace_line(ODEN, "grading_theta", "grading_theta = 1.0"));
        assert_eq!(e.0.len(), 1, "{e}");
        // Static scenes keep their graded meshes.
        assert!(load(FRICTIONLESS).is_ok());
    }

    #[test]
    fn overrides_of_time_keys() {
        let s = load_with(ODEN, &["time.dt=1e-4"]).unwrap_or_else(|e| panic!("{e}"));
        let t = s.time.clone().unwrap_or_else(|| panic!("no [time]"));
        assert_eq!(t.dt, 1e-4);
        assert!((t.resolved_dt_min() - 1e-8).abs() < 1e-20);
        assert!((t.resolved_dt_max() - 1e-3).abs() < 1e-15);
        let s = load_with(
            ODEN,
            &[
                "time.integrator=central_difference",
                "time.mass=lumped",
                "time.adaptive=false",
                "time.stop_at_steady=false",
                "time.t_end=0.5",
                "time.rho_inf=1",
                "time.dt_min=1e-6",
                "time.dt_max=1e-3",
                "time.error_tol=1e-5",
                "time.steady_tol=1e-5",
                "time.max_steps=10",
                "motion.ramp=0.1",
            ],
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let t = s.time.clone().unwrap_or_else(|| panic!("no [time]"));
        assert_eq!(
            t,
            TimeSpec {
                integrator: IntegratorName::CentralDifference,
                rho_inf: 1.0,
                dt: 2e-4,
                dt_min: Some(1e-6),
                dt_max: Some(1e-3),
                t_end: 0.5,
                adaptive: false,
                error_tol: 1e-5,
                steady_tol: 1e-5,
                stop_at_steady: false,
                mass: MassKind::Lumped,
                max_steps: 10,
                strain_rate_damping: 1.0,
            }
        );
        // road.v0_ramp follows the overridden motion.ramp.
        assert_eq!(
            s.road.as_ref().map(|r| r.resolved_v0_ramp(&s.motion)),
            Some(0.1)
        );
        // Bad override values: (--set) and the key.
        let e = errors_with(ODEN, &["time.dt=-1e-4"]);
        assert_only(&e, "time.dt", None);
        assert!(e.0[0].is_override());
        assert!(
            e.0[0]
                .to_string()
                .starts_with("test.toml:(--set): key `time.dt`"),
            "{e}"
        );
        let e = errors_with(ODEN, &["time.dt=5"]);
        assert_only(&e, "time.dt", None);
        assert!(e.0[0].message.contains("t_end"), "{e}");
        // dt overridden below an explicit dt_min in the file: dt_min keeps its line.
        let text = replace_line(ODEN, "dt =", "dt = 2e-4\ndt_min = 1e-5");
        let e = errors_with(&text, &["time.dt=1e-6"]);
        assert_only(&e, "time.dt_min", Some(line_of(&text, "dt_min")));
        let e = errors_with(ODEN, &["time.integrator=euler"]);
        assert_only(&e, "time.integrator", None);
        assert!(e.0[0].message.contains("\"sdirk\""), "{e}");
        // Switching a spinning scene to transient by override.
        let s = load_with(
            MINIMAL,
            &["analysis.mode=transient", "time.dt=1e-3", "time.t_end=1"],
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.time.map(|t| (t.dt, t.t_end)), Some((1e-3, 1.0)));
        let e = errors_with(MINIMAL, &["analysis.mode=transient"]);
        assert_only(&e, "time", None);
        assert!(e.0[0].is_override(), "{e}");
    }

    /// A steady scene may give `[time]` for `strain_rate_damping` alone: no `dt` or `t_end`
    /// needed there (nor written back), while the transient mode still asks for them.
    #[test]
    fn steady_scene_time_without_dt_and_t_end() {
        let (a, b) = (
            STEADY_SWEEP.find("dt = 2.0e-4").expect("dt"),
            STEADY_SWEEP
                .find("strain_rate_damping = 1.0")
                .expect("damping"),
        );
        let text = format!("{}{}", &STEADY_SWEEP[..a], &STEADY_SWEEP[b..]);
        let s = load(&text).unwrap_or_else(|e| panic!("{e}"));
        let t = s.time.as_ref().expect("[time]");
        assert!(t.steady_only());
        assert_eq!(t.strain_rate_damping, 1.0);
        let out = s.to_toml_string();
        assert!(!out.contains("nan") && !out.contains("t_end"), "{out}");
        let back = load(&out).unwrap_or_else(|e| panic!("{e}\n{out}"));
        let tb = back.time.as_ref().expect("[time]");
        assert!(tb.steady_only() && tb.strain_rate_damping == 1.0);
        // The damping is still checked.
        let e = errors_with(&text, &["time.strain_rate_damping=-1"]);
        assert_only(&e, "time.strain_rate_damping", None);
        // The transient mode needs both keys.
        let e = errors_with(&text, &["analysis.mode=transient"]);
        let keys: Vec<&str> = e.0.iter().map(|i| i.key.as_str()).collect();
        assert!(
            keys.contains(&"time.dt") && keys.contains(&"time.t_end"),
            "{e}"
        );
        // With the keys, a steady scene's [time] is an ordinary one.
        let s = load(STEADY_SWEEP).unwrap_or_else(|e| panic!("{e}"));
        assert!(!s.time.expect("[time]").steady_only());
    }

    #[test]
    fn round_trip_of_transient_keys() {
        let cases: [(&str, &[&str]); 3] = [
            (
                ODEN,
                &[
                    "time.dt_min=1e-7",
                    "time.dt_max=1e-3",
                    "road.v0_ramp=0.2",
                    "time.integrator=bdf",
                ],
            ),
            (
                ROLLING_FRICTIONLESS,
                &["time.integrator=central_difference", "time.mass=lumped"],
            ),
            (
                &ODEN.replace("disp = 0.1", "load = 300.0"),
                &["time.rho_inf=0"],
            ),
        ];
        for (text, ov) in cases {
            let s = load_with(text, ov).unwrap_or_else(|e| panic!("{e}"));
            let out = s.to_toml_string();
            let back = load(&out).unwrap_or_else(|e| panic!("{e}\n{out}"));
            assert_eq!(back, s, "{out}");
            let direct: Scene = toml::from_str(&out).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(direct, s);
            assert!(out.contains("[time]") && out.contains("ramp = "), "{out}");
        }
        let s = load(&minimal_transient()).unwrap_or_else(|e| panic!("{e}"));
        let out = s.to_toml_string();
        assert!(
            out.contains("[time]\nintegrator = \"generalized_alpha\""),
            "{out}"
        );
        assert!(!out.contains("dt_min") && !out.contains("[road]"), "{out}");
        assert_eq!(load(&out).unwrap_or_else(|e| panic!("{e}\n{out}")), s);
        // Scenes of the other modes write no [time].
        let out = load(FRICTIONLESS)
            .unwrap_or_else(|e| panic!("{e}"))
            .to_toml_string();
        assert!(!out.contains("[time]"), "{out}");
    }

    #[test]
    fn validate_checks_transient_scenes_built_in_code() {
        let mut s = load(ODEN).unwrap_or_else(|e| panic!("{e}"));
        assert!(s.validate().is_ok());
        if let Some(t) = s.time.as_mut() {
            t.dt = -1.0;
            t.integrator = IntegratorName::CentralDifference;
            t.mass = MassKind::Consistent;
        }
        s.motion.ramp = -1.0;
        let e = s.validate().err().unwrap_or_else(|| panic!("accepted"));
        assert_eq!(e.0.len(), 3, "{e}");
        for key in ["time.dt", "time.mass", "motion.ramp"] {
            let err = e.find(key).unwrap_or_else(|| panic!("{e}"));
            assert_eq!((err.line, err.source_name.as_str()), (None, "<scene>"));
        }
        s.time = None;
        s.motion.ramp = 0.0;
        let e = s.validate().err().unwrap_or_else(|| panic!("accepted"));
        assert!(e.has_key("time"), "{e}");
        // [time] in a static scene built in code.
        let mut st = load(FRICTIONLESS).unwrap_or_else(|e| panic!("{e}"));
        st.time = Some(TimeSpec::new(1e-3, 1.0));
        let e = st.validate().err().unwrap_or_else(|| panic!("accepted"));
        assert!(e.has_key("time"), "{e}");
    }
}
