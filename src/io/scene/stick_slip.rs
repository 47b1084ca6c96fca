//! `[stick_slip]`: the one-degree-of-freedom stick-slip oscillator `mass ẍ = −stiffness x + F_T`.

use super::*;

/// `[stick_slip]`: the one-degree-of-freedom stick-slip oscillator
/// `mass ẍ = −stiffness x + F_T`, `F_T = −μ(|w|) normal_force φ_ε(w)`, `w = ẋ − belt_speed`
/// (the spring is anchored at x = 0; the belt moves in +x).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StickSlipSpec {
    /// Mass (> 0).
    pub mass: f64,
    /// Spring stiffness (force/length, > 0).
    pub stiffness: f64,
    /// Normal force pressing the mass onto the belt (> 0).
    pub normal_force: f64,
    /// Belt speed along +x (> 0).
    pub belt_speed: f64,
    /// End time (> 0).
    pub t_end: f64,
    /// Relative tolerance of the adaptive integrator (> 0).
    #[serde(default = "default_rtol")]
    pub rtol: f64,
    /// Absolute tolerance of the adaptive integrator (> 0).
    #[serde(default = "default_atol")]
    pub atol: f64,
    /// Initial position (spring elongation).
    #[serde(default)]
    pub x0: f64,
    /// Initial velocity; `None` = `belt_speed` (starts sticking).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub v0: Option<f64>,
    /// Interval between output samples (in (0, t_end]); `None` = `t_end / 2000`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub output_interval: Option<f64>,
}

/// Default of `[stick_slip] rtol`.
pub const DEFAULT_STICK_SLIP_RTOL: f64 = 1e-8;

/// Default of `[stick_slip] atol`.
pub const DEFAULT_STICK_SLIP_ATOL: f64 = 1e-10;

/// `output_interval = t_end / STICK_SLIP_OUTPUT_SAMPLES` when not given.
pub const STICK_SLIP_OUTPUT_SAMPLES: f64 = 2000.0;

pub(super) fn default_rtol() -> f64 {
    DEFAULT_STICK_SLIP_RTOL
}

pub(super) fn default_atol() -> f64 {
    DEFAULT_STICK_SLIP_ATOL
}

impl StickSlipSpec {
    /// The initial velocity: `v0`, or `belt_speed` (sticking) when not given.
    pub fn initial_velocity(&self) -> f64 {
        self.v0.unwrap_or(self.belt_speed)
    }

    /// The output interval: `output_interval`, or `t_end / 2000` when not given.
    pub fn resolved_output_interval(&self) -> f64 {
        self.output_interval
            .unwrap_or(self.t_end / STICK_SLIP_OUTPUT_SAMPLES)
    }
}

pub(super) fn validate_stick_slip(s: &StickSlipSpec, out: &mut Vec<Issue>) {
    let positives: [(&str, f64, &str); 7] = [
        ("mass", s.mass, "mass"),
        ("stiffness", s.stiffness, "spring stiffness"),
        ("normal_force", s.normal_force, "normal force"),
        ("belt_speed", s.belt_speed, "belt speed"),
        ("t_end", s.t_end, "end time"),
        ("rtol", s.rtol, "relative tolerance"),
        ("atol", s.atol, "absolute tolerance"),
    ];
    for (key, x, what) in positives {
        if !positive(x) {
            out.push(issue(
                format!("stick_slip.{key}"),
                format!("{what} must be > 0, got {x}"),
            ));
        }
    }
    if let Some(dt) = s.output_interval {
        if !positive(dt) {
            out.push(issue(
                "stick_slip.output_interval",
                format!("output interval must be > 0, got {dt}"),
            ));
        } else if positive(s.t_end) && dt > s.t_end {
            out.push(issue(
                "stick_slip.output_interval",
                format!("output interval {dt} must not exceed t_end = {}", s.t_end),
            ));
        }
    }
}
