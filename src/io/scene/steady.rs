//! `[continuation]`: arc-length continuation of the steady mode (parameter, target, scaled arc
//! lengths).

use super::analysis::Mode;
use super::contact::RoadSpec;
use super::issue::{issue, positive, Issue};
use super::motion::Control;
use serde::{Deserialize, Serialize};

keyword_enum! {
    /// Parameter of the arc-length continuation (`[continuation] parameter`).
    #[derive(Default)]
    ContinuationParameter, "continuation parameter" {
        #[default]
        /// Angular speed ω (rad/s); the road speed keeps its ratio v0 / ω.
        Omega => "omega",
        /// Hub load (force per unit thickness; needs `road.load`).
        Load => "load",
        /// Penetration DISP = Ro − H (needs `road.disp`).
        Disp => "disp",
        /// Creep ξ (see `motion.control = "creep"`; needs `motion.control = "creep"` or
        /// `"free_rolling"`): v0 = (1 + ξ) v0_free at fixed ω, from braking to driving.
        Creep => "creep",
        /// Slip angle α (degrees, |α| < 90; three-dimensional steady mode only): the road
        /// velocity turned by α at a fixed road speed.
        SlipAngle => "slip_angle",
        /// Camber γ (degrees, |γ| < 90; three-dimensional steady mode only): the road's frame
        /// tilted by γ about the rolling direction.
        Camber => "camber",
    }
}

keyword_enum! {
    /// What the continuation does at a limit point that turns the branch back before the
    /// target (`[continuation] on_limit`).
    #[derive(Default)]
    LimitAction, "limit-point action" {
        #[default]
        /// Follow the branch back through the limit point (arc length).
        Follow => "follow",
        /// Jump past the limit point: a direct steady solve at λ_limit + `jump` · |target −
        /// start| (retried at 2×, 4× that distance), then continue from the sheet it lands
        /// on; if every jump fails, follow the branch back.
        Jump => "jump",
    }
}

/// `[continuation]` (`steady` mode): Riks–Crisfield arc-length continuation from the first
/// steady solution to `target`. Arc lengths are in scaled units: ‖Δu‖ / u_s and Δλ / λ_s with
/// u_s the norm of the first solution's displacement vector and λ_s = |target − start|, so
/// `ds = 0.05` is about 1/20 of the way when the solution changes proportionally.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ContinuationSpec {
    pub parameter: ContinuationParameter,
    /// Final parameter value (rad/s, force per unit thickness, or length).
    pub target: f64,
    /// Initial arc length (scaled, > 0).
    pub ds: f64,
    /// Largest arc length (scaled, >= ds).
    pub ds_max: f64,
    /// Maximum number of continuation steps (>= 1).
    pub max_steps: usize,
    /// Corrector iterations aimed at by the step-size control (>= 1).
    pub desired_iterations: usize,
    /// Leave the branch at the first bifurcation detected, along the null mode of the
    /// tangent (branch switching).
    pub switch_branch: bool,
    /// At a limit point that turns the branch back before the target: follow it back, or jump
    /// past it onto another sheet of solutions.
    pub on_limit: LimitAction,
    /// Distance of the jump past the limit point, as a fraction of |target − start| (> 0).
    pub jump: f64,
}

impl Default for ContinuationSpec {
    fn default() -> Self {
        Self {
            parameter: ContinuationParameter::Omega,
            target: 0.0,
            ds: 0.05,
            ds_max: 0.25,
            max_steps: 200,
            desired_iterations: 4,
            switch_branch: false,
            on_limit: LimitAction::Follow,
            jump: 0.02,
        }
    }
}

pub(super) fn validate_continuation(
    c: &ContinuationSpec,
    mode: Option<Mode>,
    road: Option<&RoadSpec>,
    control: Option<Control>,
    out: &mut Vec<Issue>,
) {
    if c.parameter == ContinuationParameter::Creep {
        if !(c.target.is_finite() && c.target > -1.0) {
            out.push(issue(
                "continuation.target",
                format!(
                    "final creep must be finite and > -1 (v0 > 0), got {}",
                    c.target
                ),
            ));
        }
        if mode == Some(Mode::Steady)
            && !matches!(control, None | Some(Control::Creep | Control::FreeRolling))
        {
            out.push(issue(
                "continuation.parameter",
                "parameter \"creep\" is measured from free rolling: it needs motion.control = \
                 \"creep\" or \"free_rolling\"",
            ));
        }
    } else if matches!(
        c.parameter,
        ContinuationParameter::SlipAngle | ContinuationParameter::Camber
    ) {
        if !(c.target.is_finite() && c.target.abs() < 90.0) {
            out.push(issue(
                "continuation.target",
                format!(
                    "final {} must be finite and within (-90, 90) degrees, got {}",
                    c.parameter, c.target
                ),
            ));
        }
    } else if !(c.target.is_finite() && c.target >= 0.0) {
        out.push(issue(
            "continuation.target",
            format!(
                "final parameter value must be finite and >= 0, got {}",
                c.target
            ),
        ));
    }
    if !positive(c.ds) {
        out.push(issue(
            "continuation.ds",
            format!("initial arc length must be > 0, got {}", c.ds),
        ));
    }
    if !(c.ds_max.is_finite() && c.ds_max >= c.ds) {
        out.push(issue(
            "continuation.ds_max",
            format!(
                "largest arc length must be >= ds = {}, got {}",
                c.ds, c.ds_max
            ),
        ));
    }
    if !(positive(c.jump) && c.jump <= 1.0) {
        out.push(issue(
            "continuation.jump",
            format!(
                "jump past a limit point must be in (0, 1] (a fraction of |target - start|), got {}",
                c.jump
            ),
        ));
    }
    if c.on_limit == LimitAction::Jump
        && matches!(
            c.parameter,
            ContinuationParameter::Creep
                | ContinuationParameter::SlipAngle
                | ContinuationParameter::Camber
        )
    {
        out.push(issue(
            "continuation.on_limit",
            "\"jump\" applies to arc-length continuation in omega, load and disp, not to \
             the creep, slip-angle and camber paths",
        ));
    }
    if c.max_steps < 1 {
        out.push(issue("continuation.max_steps", "must be >= 1, got 0"));
    }
    if c.desired_iterations < 1 {
        out.push(issue(
            "continuation.desired_iterations",
            "must be >= 1, got 0",
        ));
    }
    if mode != Some(Mode::Steady) {
        return;
    }
    match (c.parameter, road) {
        (ContinuationParameter::Load, r) if r.and_then(|r| r.load).is_none() => out.push(issue(
            "continuation.parameter",
            "parameter \"load\" continues in the hub load: it needs load control (road.load)",
        )),
        (ContinuationParameter::Disp, r) if r.and_then(|r| r.disp).is_none() => out.push(issue(
            "continuation.parameter",
            "parameter \"disp\" continues in the penetration: it needs displacement control \
             (road.disp)",
        )),
        (ContinuationParameter::Disp, Some(r))
            if c.target >= 0.0 && r.disp.is_some_and(|d| c.target == d) =>
        {
            out.push(issue(
                "continuation.target",
                "target equals the starting penetration road.disp: nothing to continue",
            ));
        }
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::scene::tests::*;
    use crate::io::scene::*;

    #[test]
    fn steady_sweep_scene_and_continuation_rules() {
        let s = load(STEADY_SWEEP).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.analysis.mode, Mode::Steady);
        let c = s.continuation.clone().unwrap_or_default();
        assert_eq!(c.parameter, ContinuationParameter::Omega);
        assert_eq!(c.target, 60.0);
        // [continuation] only in steady mode, with the line of its header.
        let e = errors_with(STEADY_SWEEP, &["analysis.mode=\"transient\""]);
        let err = e.find("continuation").unwrap_or_else(|| panic!("{e}"));
        assert!(err.message.contains("not used"), "{e}");
        // load continuation needs load control.
        let e = errors_with(STEADY_SWEEP, &["continuation.parameter=\"load\""]);
        assert_only(&e, "continuation.parameter", None);
        // ds_max < ds.
        let e = errors_with(STEADY_SWEEP, &["continuation.ds_max=0.001"]);
        assert_only(&e, "continuation.ds_max", None);
        // A transient scene runs in steady mode with --mode steady ([time] allowed).
        let t = load_with(ODEN, &["analysis.mode=\"steady\""]).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(t.analysis.mode, Mode::Steady);
    }
}
