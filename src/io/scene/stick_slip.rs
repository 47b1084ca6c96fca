//! `[stick_slip]`: the one-degree-of-freedom stick-slip oscillator `mass ẍ = −stiffness x + F_T`.

use super::issue::{issue, positive, Issue};
use serde::{Deserialize, Serialize};

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::laws::{CoulombLinear, RateDependent};
    use crate::contact::Friction;
    use crate::io::scene::tests::*;
    use crate::io::scene::*;

    #[test]
    fn stick_slip_scene_parses() {
        let s = load(STICK_SLIP).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.scene.name, "stick_slip");
        assert_eq!(s.scene.units, "m-N-s");
        assert_eq!(s.analysis.mode, Mode::StickSlip);
        assert_eq!(s.road, None);
        assert_eq!(s.contact, None);
        let ss = s
            .stick_slip
            .clone()
            .unwrap_or_else(|| panic!("no [stick_slip]"));
        assert_eq!(
            (
                ss.mass,
                ss.stiffness,
                ss.normal_force,
                ss.belt_speed,
                ss.t_end
            ),
            (1.0, 100.0, 10.0, 0.1, 20.0)
        );
        assert_eq!((ss.rtol, ss.atol, ss.x0), (1e-8, 1e-10, 0.0));
        assert_eq!((ss.v0, ss.output_interval), (None, None));
        assert_eq!(ss.initial_velocity(), 0.1);
        assert!((ss.resolved_output_interval() - 0.01).abs() < 1e-15);
        assert_eq!(
            s.friction.params(),
            Some(Friction::RateDependent(RateDependent::new(
                0.6, 0.4, 1e-4, 1e-7
            )))
        );
        assert!(s.friction.is_active());
        assert!(s.validate().is_ok());
        // Defaults of an explicit minimal [stick_slip].
        let text = STICK_SLIP
            .lines()
            .filter(|l| {
                let t = l.trim_start();
                !["rtol", "atol", "x0"].iter().any(|k| t.starts_with(k))
            })
            .collect::<Vec<_>>()
            .join("\n");
        let d = load(&text).unwrap_or_else(|e| panic!("{e}"));
        let dss = d.stick_slip.unwrap_or_else(|| panic!("no [stick_slip]"));
        assert_eq!(dss.rtol, DEFAULT_STICK_SLIP_RTOL);
        assert_eq!(dss.atol, DEFAULT_STICK_SLIP_ATOL);
        assert_eq!(dss.x0, 0.0);
    }

    #[test]
    fn stick_slip_without_section_or_law_rejected() {
        let text = remove_section(STICK_SLIP, "[stick_slip]");
        let e = errors(&text);
        assert_only(&e, "stick_slip", Some(line_of(&text, "mode =")));
        assert!(e.0[0].message.contains("missing"), "{e}");

        let text = remove_section(STICK_SLIP, "[friction]");
        let e = errors(&text);
        assert_only(&e, "friction.law", Some(line_of(&text, "mode =")));
        assert!(e.0[0].message.contains("\"none\""), "{e}");

        let text = STICK_SLIP.replace(
            "law = \"rate_dependent\"",
            "law = \"oden_martins\"\nc_t = 1\nm_t = 1",
        );
        let text = text
            .lines()
            .filter(|l| !["mu_s", "mu_k", "v_s"].iter().any(|k| l.starts_with(k)))
            .collect::<Vec<_>>()
            .join("\n");
        let e = errors(&text);
        assert_only(&e, "friction.law", Some(line_of(&text, "law")));
        assert!(e.0[0].message.contains("penetration"), "{e}");

        // Coulomb laws are fine.
        let text = STICK_SLIP
            .lines()
            .filter(|l| !["mu_s", "mu_k", "v_s"].iter().any(|k| l.starts_with(k)))
            .collect::<Vec<_>>()
            .join("\n");
        let s = load_with(&text, &["friction.law=coulomb_linear", "friction.mu=0.5"])
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            s.friction.params(),
            Some(Friction::CoulombLinear(CoulombLinear::new(0.5, 1e-7)))
        );
    }

    #[test]
    fn stick_slip_ranges_and_required_keys() {
        let text = replace_line(STICK_SLIP, "mass", "mass = 0.0");
        let text = replace_line(&text, "belt_speed", "belt_speed = -0.1");
        let text = replace_line(&text, "rtol", "rtol = 0");
        let e = errors(&text);
        assert_eq!(e.0.len(), 3, "{e}");
        for key in ["mass", "belt_speed", "rtol"] {
            let err = e
                .find(&format!("stick_slip.{key}"))
                .unwrap_or_else(|| panic!("{e}"));
            assert_eq!(err.line, Some(line_of(&text, key)));
        }
        let e = errors(&STICK_SLIP.replace("t_end = 20.0", ""));
        let err = e.find("stick_slip.t_end").unwrap_or_else(|| panic!("{e}"));
        assert!(err.message.contains("required key is missing"), "{err}");
        assert_eq!(e.0.len(), 1, "{e}");
        let e = errors_with(STICK_SLIP, &["stick_slip.output_interval=30"]);
        assert_only(&e, "stick_slip.output_interval", None);
        assert!(e.0[0].is_override());
        let s = load_with(
            STICK_SLIP,
            &["stick_slip.output_interval=0.05", "stick_slip.v0=0"],
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let ss = s.stick_slip.unwrap_or_else(|| panic!("no [stick_slip]"));
        assert_eq!(ss.resolved_output_interval(), 0.05);
        assert_eq!(ss.initial_velocity(), 0.0);
    }
}
