//! `[motion]`: hub angular speed (rad/T), its C² smoothstep ramp in time, and the hub control
//! (speed, torque, free rolling, creep).

use super::analysis::Mode;
use super::issue::{issue, issue_near, Issue};
use super::time::IntegratorName;
use serde::{Deserialize, Serialize};

keyword_enum! {
    /// How the hub rotation is driven (`[motion] control`).
    #[derive(Default)]
    Control, "hub control" {
        #[default]
        /// Prescribed hub angular speed ω(t) = omega · S(t / ramp).
        Speed => "speed",
        /// Prescribed hub torque. Transient: T(t) = torque · S(t / ramp) on a hub of rotational
        /// inertia `hub_inertia`; the hub angle is an unknown. The hub and body start in rigid
        /// spin at `omega`; the road speed drives the rolling and the hub finds its own ω.
        /// Steady: ω stays `omega` and the road speed v0 is solved for so that the hub torque
        /// equals `torque` (`road.v0` is the first guess; no `hub_inertia`).
        Torque => "torque",
        /// Steady only: free rolling, i.e. torque control with `torque = 0`: v0 is solved for
        /// so that the hub torque vanishes (`road.v0` is the first guess).
        FreeRolling => "free_rolling",
        /// Steady only: given creep ξ = `creep` = (v0 − ω R_e) / (ω R_e), where R_e = v0_free / ω
        /// is the effective rolling radius of free rolling at the scene's ω and load (found
        /// first, as with `free_rolling`). ξ > 0: the road runs faster than the free-rolling
        /// speed; ξ < 0: slower.
        Creep => "creep",
    }
}

/// `[motion]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Motion {
    /// Target angular speed (rad/s, counter-clockwise), >= 0. Required for `spinning` and
    /// `transient`.
    pub omega: f64,
    /// Time over which the hub angular speed goes from 0 to `omega` (speed control) or the
    /// hub torque from 0 to `torque` (torque control) with the C² smoothstep (time, >= 0; 0 = at
    /// once). Only in `transient`: must be 0 in the other modes.
    pub ramp: f64,
    /// `speed` (prescribed ω(t)) or `torque` (prescribed hub torque; `transient` with
    /// `generalized_alpha` only).
    pub control: Control,
    /// Rotational inertia of the hub per unit thickness (mass·length² per unit thickness,
    /// e.g. lbf·s²), > 0; required for (and only used by) torque control. 0 = not given.
    pub hub_inertia: f64,
    /// Applied hub torque about +x3 (counter-clockwise positive) per unit thickness
    /// (force·length per unit thickness, e.g. lbf·in/in), ramped in over `ramp`; 0 = free
    /// rolling. Only with torque control.
    pub torque: f64,
    /// Creep ξ = (v0 − ω R_e) / (ω R_e) with R_e the free-rolling radius (dimensionless,
    /// > −1). Only with `control = "creep"` (steady mode).
    pub creep: f64,
}

impl Default for Motion {
    fn default() -> Self {
        Motion {
            omega: 0.0,
            ramp: 0.0,
            control: Control::Speed,
            hub_inertia: 0.0,
            torque: 0.0,
            creep: 0.0,
        }
    }
}

impl Motion {
    /// Hub angular speed at time `t` of a transient run: `omega · S(t / ramp)`.
    pub fn omega_at(&self, t: f64) -> f64 {
        self.omega * ramp_value(t, self.ramp)
    }

    /// Hub angular acceleration at time `t`: `omega · S′(t / ramp) / ramp` (0 outside the ramp).
    pub fn omega_dot_at(&self, t: f64) -> f64 {
        self.omega * ramp_rate(t, self.ramp)
    }

    /// Hub rotation angle φ(t) = ∫₀ᵗ ω, exact for the smoothstep ramp (0 for t <= 0); after the
    /// ramp, `omega · (t − ramp / 2)`.
    pub fn angle_at(&self, t: f64) -> f64 {
        self.omega * ramp_integral(t, self.ramp)
    }
}

/// The C² ("quintic") smoothstep `S(s) = 6s⁵ − 15s⁴ + 10s³` for `s` in `[0, 1]`, 0 below and 1
/// above: `S′` and `S″` vanish at both ends. Every ramp of a transient scene uses it.
pub fn smoothstep(s: f64) -> f64 {
    if s <= 0.0 {
        0.0
    } else if s >= 1.0 {
        1.0
    } else {
        s * s * s * (10.0 + s * (-15.0 + 6.0 * s))
    }
}

/// `dS/ds = 30 s² (1 − s)²` on `[0, 1]`, 0 outside.
pub fn smoothstep_derivative(s: f64) -> f64 {
    if s <= 0.0 || s >= 1.0 {
        0.0
    } else {
        30.0 * s * s * (1.0 - s) * (1.0 - s)
    }
}

/// `∫₀ˢ S = s⁶ − 3s⁵ + 2.5s⁴` on `[0, 1]`, 0 below, `s − 1/2` above.
pub fn smoothstep_integral(s: f64) -> f64 {
    if s <= 0.0 {
        0.0
    } else if s >= 1.0 {
        s - 0.5
    } else {
        s * s * s * s * (2.5 + s * (-3.0 + s))
    }
}

/// `S(t / ramp)`; a zero (or invalid) ramp is a step at `t = 0` (1 for `t >= 0`).
pub(super) fn ramp_value(t: f64, ramp: f64) -> f64 {
    if ramp > 0.0 {
        smoothstep(t / ramp)
    } else if t >= 0.0 {
        1.0
    } else {
        0.0
    }
}

/// `d/dt S(t / ramp)`; 0 for a zero ramp.
pub(super) fn ramp_rate(t: f64, ramp: f64) -> f64 {
    if ramp > 0.0 {
        smoothstep_derivative(t / ramp) / ramp
    } else {
        0.0
    }
}

/// `∫₀ᵗ S(τ / ramp) dτ`.
pub(super) fn ramp_integral(t: f64, ramp: f64) -> f64 {
    if ramp > 0.0 {
        ramp * smoothstep_integral(t / ramp)
    } else {
        t.max(0.0)
    }
}

pub(super) fn validate_motion(
    mode: Option<Mode>,
    m: &Motion,
    omega_given: bool,
    out: &mut Vec<Issue>,
) {
    if let Some(mode @ (Mode::Spinning | Mode::Transient | Mode::Steady)) = mode {
        if !omega_given {
            out.push(issue_near(
                "motion.omega",
                format!("required for analysis mode \"{mode}\" (target angular speed, rad/s)"),
                "analysis.mode",
            ));
            return;
        }
    }
    if !(m.omega.is_finite() && m.omega >= 0.0) {
        out.push(issue(
            "motion.omega",
            format!("angular speed must be >= 0, got {}", m.omega),
        ));
        return;
    }
    if let Some(mode @ (Mode::Static | Mode::StickSlip)) = mode {
        if m.omega != 0.0 {
            out.push(issue(
                "motion.omega",
                format!(
                    "analysis mode \"{mode}\" does not spin the cylinder: omega must be 0 or \
                     omitted, got {}",
                    m.omega
                ),
            ));
        }
    }
}

pub(super) fn validate_motion_ramp(mode: Option<Mode>, m: &Motion, out: &mut Vec<Issue>) {
    if !(m.ramp.is_finite() && m.ramp >= 0.0) {
        out.push(issue(
            "motion.ramp",
            format!("spin-up ramp time must be >= 0, got {}", m.ramp),
        ));
    } else if m.ramp != 0.0 {
        if let Some(mode) = mode.filter(|m| !matches!(m, Mode::Transient | Mode::Steady)) {
            out.push(issue(
                "motion.ramp",
                format!(
                    "the spin-up ramp is a time, and analysis mode \"{mode}\" has none (only \
                     \"transient\" does): ramp must be 0 or omitted, got {}",
                    m.ramp
                ),
            ));
        }
    }
}

/// `control`, `hub_inertia`, `torque`: torque control only in `transient` with
/// `generalized_alpha`; it needs `hub_inertia > 0`; `hub_inertia` and a non-zero `torque` only
/// with torque control.
pub(super) fn validate_motion_control(
    mode: Option<Mode>,
    m: &Motion,
    integrator: Option<IntegratorName>,
    out: &mut Vec<Issue>,
) {
    if !m.hub_inertia.is_finite() || m.hub_inertia < 0.0 {
        out.push(issue(
            "motion.hub_inertia",
            format!("hub rotational inertia must be > 0, got {}", m.hub_inertia),
        ));
    }
    if !m.torque.is_finite() {
        out.push(issue(
            "motion.torque",
            format!("hub torque must be finite, got {}", m.torque),
        ));
    }
    if !(m.creep.is_finite() && m.creep > -1.0) {
        out.push(issue(
            "motion.creep",
            format!("creep must be finite and > -1 (v0 > 0), got {}", m.creep),
        ));
    } else if m.creep != 0.0 && m.control != Control::Creep {
        out.push(issue(
            "motion.creep",
            "only used with control = \"creep\" (steady mode)",
        ));
    }
    match m.control {
        Control::Torque if mode == Some(Mode::Steady) => {
            if m.hub_inertia != 0.0 {
                out.push(issue(
                    "motion.hub_inertia",
                    "not used in steady mode (the hub turns at the constant omega; the road \
                     speed is solved for the torque)",
                ));
            }
        }
        Control::FreeRolling | Control::Creep => {
            if let Some(mode) = mode.filter(|m| *m != Mode::Steady) {
                out.push(issue(
                    "motion.control",
                    format!(
                        "control = \"{}\" is only available in analysis mode \"steady\", not \
                         \"{mode}\" (in \"transient\", free rolling is control = \"torque\" \
                         with torque = 0)",
                        m.control
                    ),
                ));
            }
            if m.hub_inertia != 0.0 {
                out.push(issue(
                    "motion.hub_inertia",
                    "only used with control = \"torque\" in transient mode",
                ));
            }
            if m.torque != 0.0 {
                out.push(issue(
                    "motion.torque",
                    "only used with control = \"torque\" (free rolling has zero torque)",
                ));
            }
        }
        Control::Torque => {
            if let Some(mode) = mode.filter(|m| *m != Mode::Transient) {
                out.push(issue(
                    "motion.control",
                    format!(
                        "torque control is only available in analysis modes \"transient\" and \"steady\", not \"{mode}\""
                    ),
                ));
            }
            if let Some(i) = integrator.filter(|i| !i.torque_control()) {
                out.push(issue(
                    "motion.control",
                    format!(
                        "torque control needs time.integrator = {} (the hub angle is solved in \
                         the implicit step), got \"{i}\"",
                        IntegratorName::quoted_with(IntegratorName::torque_control)
                    ),
                ));
            }
            if m.hub_inertia == 0.0 {
                out.push(issue(
                    "motion.hub_inertia",
                    "required (> 0) with control = \"torque\": rotational inertia of the hub \
                     per unit thickness",
                ));
            }
        }
        Control::Speed => {
            if m.hub_inertia != 0.0 {
                out.push(issue(
                    "motion.hub_inertia",
                    "only used with control = \"torque\" (the hub speed is prescribed)",
                ));
            }
            if m.torque != 0.0 {
                out.push(issue(
                    "motion.torque",
                    "only used with control = \"torque\" (the hub speed is prescribed)",
                ));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::scene::tests::*;
    use crate::io::scene::*;

    #[test]
    fn torque_control_scenes_parse() {
        let f = load(FREE_ROLLING).unwrap_or_else(|e| panic!("{e}"));
        let b = load(BRAKING).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            (f.scene.name.as_str(), b.scene.name.as_str()),
            ("free_rolling", "braking")
        );
        for s in [&f, &b] {
            assert_eq!(s.analysis.mode, Mode::Transient);
            assert_eq!(s.motion.control, Control::Torque);
            assert_eq!(s.motion.hub_inertia, 0.5);
            assert_eq!(s.motion.omega, 2.0);
            assert_eq!((s.mesh.n_r, s.mesh.n_theta), (2, 32));
            let road = s.road.as_ref().unwrap_or_else(|| panic!("no road"));
            assert_eq!((road.disp, road.v0_ramp), (Some(0.1), Some(0.0)));
            assert!(s.friction.is_active());
            assert!(s.validate().is_ok());
        }
        assert_eq!((f.motion.torque, f.motion.ramp), (0.0, 0.0));
        assert_eq!((b.motion.torque, b.motion.ramp), (-10.0, 0.2));
        // The two scenes differ only in the torque, its ramp and the naming.
        assert_eq!(
            (
                &f.geometry,
                &f.mesh,
                &f.material,
                &f.road,
                &f.contact,
                &f.friction,
                &f.time
            ),
            (
                &b.geometry,
                &b.mesh,
                &b.material,
                &b.road,
                &b.contact,
                &b.friction,
                &b.time
            )
        );
        // Defaults: speed control, no inertia, no torque.
        let s = load(ODEN).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            (s.motion.control, s.motion.hub_inertia, s.motion.torque),
            (Control::Speed, 0.0, 0.0)
        );
    }

    #[test]
    fn torque_control_keys_are_validated() {
        // Torque control without an inertia (or a negative one): reported on the key.
        let e = errors_with(FREE_ROLLING, &["motion.hub_inertia=0"]);
        assert_only(&e, "motion.hub_inertia", None);
        let e = errors_with(FREE_ROLLING, &["motion.hub_inertia=-1"]);
        assert_only(&e, "motion.hub_inertia", None);
        // Torque and inertia are only for torque control; lines of the file.
        let text = BRAKING.replace("control = \"torque\"", "control = \"speed\"");
        let e = errors(&text);
        assert_eq!(e.0.len(), 2, "{e}");
        assert_eq!(
            e.find("motion.torque").and_then(|x| x.line),
            Some(line_of(&text, "torque = -10.0"))
        );
        assert_eq!(
            e.find("motion.hub_inertia").and_then(|x| x.line),
            Some(line_of(&text, "hub_inertia ="))
        );
        // Only generalized-α, only transient.
        let e = errors_with(
            FREE_ROLLING,
            &["time.integrator=central_difference", "time.mass=lumped"],
        );
        assert_only(
            &e,
            "motion.control",
            Some(line_of(FREE_ROLLING, "control = \"torque\"")),
        );
        assert!(e.0[0].message.contains("generalized_alpha"), "{e}");
        let e = errors_with(MINIMAL, &["motion.control=torque", "motion.hub_inertia=1"]);
        assert!(e.has_key("motion.control"), "{e}");
        // Unknown keyword, wrong type, non-finite torque.
        let e = errors_with(FREE_ROLLING, &["motion.control=brake"]);
        assert_only(&e, "motion.control", None);
        assert!(e.0[0].message.contains("speed"), "{e}");
        let text = FREE_ROLLING.replace("torque = 0.0 ", "torque = \"none\" ");
        let e = errors(&text);
        assert_only(
            &e,
            "motion.torque",
            Some(line_of(&text, "torque = \"none\"")),
        );
        let e = errors_with(BRAKING, &["motion.torque=nan"]);
        assert_only(&e, "motion.torque", None);
    }

    #[test]
    fn transient_requires_omega() {
        let text = ODEN
            .lines()
            .filter(|l| !l.starts_with("omega"))
            .collect::<Vec<_>>()
            .join("\n");
        let e = errors(&text);
        assert_only(&e, "motion.omega", Some(line_of(&text, "[motion]")));
        assert!(e.0[0].message.contains("\"transient\""), "{e}");
        // No [motion] at all: at the line of `mode`.
        let text = remove_section(&minimal_transient(), "[motion]");
        let e = errors(&text);
        assert_only(&e, "motion.omega", Some(line_of(&text, "mode =")));
        let e = errors(&remove_section(MINIMAL, "[motion]"));
        assert_only(&e, "motion.omega", Some(line_of(MINIMAL, "mode =")));
        // omega = 0 is allowed (a road moving under a non-spinning cylinder).
        assert!(load(&replace_line(ODEN, "omega", "omega = 0")).is_ok());
        let e = errors(&replace_line(ODEN, "omega", "omega = -10"));
        assert!(e.has_key("motion.omega"), "{e}");
    }

    #[test]
    fn ramps_only_in_transient() {
        // motion.ramp in spinning (file) and static (override).
        let text = replace_line(MINIMAL, "omega", "omega = 20.0\nramp = 0.1");
        let e = errors(&text);
        assert_only(&e, "motion.ramp", Some(line_of(&text, "ramp")));
        assert!(e.0[0].message.contains("\"spinning\""), "{e}");
        let e = errors_with(FRICTIONLESS, &["motion.ramp=0.1"]);
        assert_only(&e, "motion.ramp", None);
        assert!(e.0[0].is_override(), "{e}");
        let e = errors_with(STICK_SLIP, &["motion.ramp=1"]);
        assert_only(&e, "motion.ramp", None);
        // road.ramp and road.v0_ramp in static.
        let text = replace_line(FRICTIONLESS, "disp", "disp = 0.1\nramp = 0.05");
        let e = errors(&text);
        assert_only(&e, "road.ramp", Some(line_of(&text, "ramp")));
        assert!(e.0[0].message.contains("static"), "{e}");
        let text = replace_line(FRICTIONLESS, "v0", "v0 = 0.0\nv0_ramp = 0.05");
        let e = errors(&text);
        assert_only(&e, "road.v0_ramp", Some(line_of(&text, "v0_ramp")));
        // Zero ramps are fine anywhere.
        let text = replace_line(FRICTIONLESS, "v0", "v0 = 0.0\nv0_ramp = 0\nramp = 0.0");
        assert!(load(&text).is_ok());
        assert!(load(&replace_line(MINIMAL, "omega", "omega = 20.0\nramp = 0")).is_ok());
        // Negative or non-finite ramps in transient.
        let text = replace_line(ODEN, "ramp = 0.05", "ramp = -0.05");
        let e = errors(&text);
        assert_only(&e, "motion.ramp", Some(line_of(&text, "ramp = -0.05")));
        assert!(e.0[0].message.contains(">= 0"), "{e}");
        let e = errors_with(ODEN, &["road.ramp=-1", "road.v0_ramp=-2"]);
        assert_eq!(e.0.len(), 2, "{e}");
        assert!(e.has_key("road.ramp") && e.has_key("road.v0_ramp"), "{e}");
        assert!(e.0.iter().all(|x| x.is_override()), "{e}");
        let e = errors_with(ODEN, &["motion.ramp=inf"]);
        assert_only(&e, "motion.ramp", None);
        // v0_ramp given: it wins over motion.ramp.
        let s = load_with(ODEN, &["road.v0_ramp=0.2"]).unwrap_or_else(|e| panic!("{e}"));
        let road = s.road.clone().unwrap_or_else(|| panic!("no [road]"));
        assert_eq!(road.v0_ramp, Some(0.2));
        assert_eq!(road.resolved_v0_ramp(&s.motion), 0.2);
    }

    #[test]
    fn smoothstep_ramps() {
        assert_eq!((smoothstep(-1.0), smoothstep(0.0)), (0.0, 0.0));
        assert_eq!((smoothstep(1.0), smoothstep(2.0)), (1.0, 1.0));
        assert!((smoothstep(0.5) - 0.5).abs() < 1e-15);
        // Symmetric, monotone, C²: derivative and integral consistent with S.
        let h = 1e-6;
        for i in 1..100 {
            let x = i as f64 / 100.0;
            assert!((smoothstep(x) + smoothstep(1.0 - x) - 1.0).abs() < 1e-14);
            assert!(smoothstep(x) >= smoothstep(x - 0.01));
            let d = (smoothstep(x + h) - smoothstep(x - h)) / (2.0 * h);
            assert!((d - smoothstep_derivative(x)).abs() < 1e-6, "{x}");
            let q = (smoothstep_integral(x + h) - smoothstep_integral(x - h)) / (2.0 * h);
            assert!((q - smoothstep(x)).abs() < 1e-6, "{x}");
        }
        assert_eq!(smoothstep_derivative(0.0), 0.0);
        assert_eq!(smoothstep_derivative(1.0), 0.0);
        assert!((smoothstep_integral(1.0) - 0.5).abs() < 1e-15);
        assert!((smoothstep_integral(3.0) - 2.5).abs() < 1e-15);

        let m = Motion {
            omega: 10.0,
            ramp: 0.05,
            ..Motion::default()
        };
        assert_eq!((m.omega_at(-1.0), m.omega_at(0.0)), (0.0, 0.0));
        assert!((m.omega_at(0.025) - 5.0).abs() < 1e-12);
        assert_eq!(m.omega_at(0.05), 10.0);
        assert_eq!(m.omega_at(1.0), 10.0);
        assert!((m.angle_at(1.0) - 10.0 * (1.0 - 0.025)).abs() < 1e-12);
        assert!((m.angle_at(0.05) - 10.0 * 0.025).abs() < 1e-12);
        assert_eq!(m.angle_at(-1.0), 0.0);
        assert!((m.omega_dot_at(0.025) - 10.0 * 1.875 / 0.05).abs() < 1e-9);
        assert_eq!(m.omega_dot_at(0.06), 0.0);
        // A zero ramp: full speed at once.
        let step = Motion {
            omega: 10.0,
            ramp: 0.0,
            ..Motion::default()
        };
        assert_eq!((step.omega_at(0.0), step.omega_at(0.3)), (10.0, 10.0));
        assert!((step.angle_at(0.3) - 3.0).abs() < 1e-12);
        assert_eq!(step.omega_dot_at(0.0), 0.0);

        let road = RoadSpec {
            disp: Some(0.1),
            load: None,
            v0: 20.0,
            ramp: 0.1,
            v0_ramp: None,
            slip_angle: 0.0,
            camber: 0.0,
        };
        assert!((road.ramp_factor(0.05) - 0.5).abs() < 1e-12);
        assert_eq!(road.ramp_factor(0.2), 1.0);
        assert!((road.ramp_factor_rate(0.05) - 1.875 / 0.1).abs() < 1e-9);
        assert!((road.v0_at(0.025, &m) - 10.0).abs() < 1e-12);
        assert_eq!(road.v0_at(0.05, &m), 20.0);
        let late = RoadSpec {
            v0_ramp: Some(0.5),
            ..road
        };
        assert!((late.v0_at(0.25, &m) - 10.0).abs() < 1e-12);
    }
}
