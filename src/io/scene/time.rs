//! `[time]`: time integration of the transient mode (integrator, steps in T, error and steady
//! tolerances, mass matrix), and the rule that steady-state extraction needs a mesh uniform in θ.

use super::*;

keyword_enum! {
    /// Time integrator of the `transient` mode (`[time] integrator`).
    #[derive(Default)]
    IntegratorName, "time integrator" {
        #[default]
        /// Generalized-α (Chung–Hulbert) on the second-order system, with spectral radius at
        /// infinity `rho_inf` (1 = trapezoidal / Newmark average acceleration). Implicit.
        GeneralizedAlpha => "generalized_alpha",
        /// Explicit central difference with the lumped (HRZ) mass; the step is also bounded by a
        /// stable-step estimate.
        CentralDifference => "central_difference",
        /// Variable-order BDF on the first-order form `y = (u, v)` (diffsol), with its own error
        /// control.
        Bdf => "bdf",
        /// SDIRK on the first-order form `y = (u, v)` (diffsol), with its own error control.
        Sdirk => "sdirk",
    }
}

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

/// `[time]`: time integration of the `transient` mode (required there, forbidden otherwise).
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
    /// average acceleration: no numerical dissipation). Used only by `generalized_alpha`.
    #[serde(default = "default_rho_inf")]
    pub rho_inf: f64,
    /// Initial time step (time, > 0, <= t_end).
    pub dt: f64,
    /// Smallest step (time, > 0, <= dt); `None` = `dt · 1e-4`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dt_min: Option<f64>,
    /// Largest step (time, >= dt); `None` = `dt · 10`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dt_max: Option<f64>,
    /// Maximum simulated time (time, > 0); the run stops earlier when steady if
    /// `stop_at_steady`.
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

    /// The mass matrix actually used: `lumped` for `central_difference`, else `mass`.
    pub fn effective_mass(&self) -> MassKind {
        match self.integrator {
            IntegratorName::CentralDifference => MassKind::Lumped,
            _ => self.mass,
        }
    }

    /// Whether the integrator is explicit (`central_difference`).
    pub fn is_explicit(&self) -> bool {
        self.integrator == IntegratorName::CentralDifference
    }
}

pub(super) fn validate_time(t: &TimeSpec, mass_given: bool, out: &mut Vec<Issue>) {
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
    if !(t.rho_inf.is_finite() && (0.0..=1.0).contains(&t.rho_inf)) {
        out.push(issue(
            "time.rho_inf",
            format!(
                "spectral radius at infinity of generalized-α must be in [0, 1], got {}",
                t.rho_inf
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
    if !(t.strain_rate_damping >= 0.0 && t.strain_rate_damping.is_finite()) {
        out.push(issue(
            "time.strain_rate_damping",
            format!(
                "Green-strain-rate viscosity must be >= 0, got {}",
                t.strain_rate_damping
            ),
        ));
    }
    if mass_given
        && t.integrator == IntegratorName::CentralDifference
        && t.mass == MassKind::Consistent
    {
        out.push(issue(
            "time.mass",
            "integrator \"central_difference\" always uses the lumped mass: mass must be \
             \"lumped\" or omitted, got \"consistent\"",
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
