//! `[road]` (the rigid road `x2 = −H`, penetration or load, road speed and ramps) and `[contact]`
//! (normal compliance `t_n = c_n δ^m_n + b_n δ^l_n δ̇`, per unit reference length, and its
//! quadrature).

use super::analysis::Mode;
use super::geometry::Geometry;
use super::issue::{issue, positive, Issue};
use super::motion::{ramp_rate, ramp_value, Motion};
use serde::{Deserialize, Serialize};

keyword_enum! {
    /// Quadrature rule on each element edge of the contact boundary (`[contact] quadrature`).
    #[derive(Default)]
    ContactQuadrature, "contact quadrature" {
        /// Gauss–Legendre points (interior of the edge).
        Gauss => "gauss",
        /// Gauss–Lobatto points (include both end nodes; nodal-like contact). The default: it
        /// gives the smoother pressure (tests/indentation.rs, Hertz case: peak within 1 % of p0
        /// on the coarse mesh where 4-point Gauss overshoots by 60 %).
        #[default]
        Lobatto => "lobatto",
    }
}

keyword_enum! {
    /// No-adhesion clamp of the normal traction (`[contact] clamp`), see
    /// [`crate::contact::Clamp`].
    #[derive(Default)]
    ClampKind, "contact clamp" {
        /// `t_n = max(0, raw)` (the project's convention).
        #[default]
        Hard => "hard",
        /// A C¹ cubic ramp of width `clamp_width` instead of the kink at raw = 0.
        Smooth => "smooth",
    }
}

/// `[road]`: the rigid road `x2 = −H` below the hub. Exactly one of `disp` (displacement control)
/// and `load` (load control) is given.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RoadSpec {
    /// Final penetration `Ro − H` (length, >= 0, < ro − ri), reached by load stepping from first
    /// touch (H = Ro).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub disp: Option<f64>,
    /// Vertical force per unit thickness pushing the cylinder onto the road through the hub
    /// (force/length, > 0); the road height H is then an unknown.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub load: Option<f64>,
    /// Road speed along +x1 in the hub frame (length/time). Must be 0 in `static`.
    #[serde(default)]
    pub v0: f64,
    /// Time over which the road is raised from first touch to `disp` (or the load applied) with
    /// the C² smoothstep (time, >= 0; 0 = at once). Only in `transient`: must be 0 in `static`.
    #[serde(default)]
    pub ramp: f64,
    /// Time over which the road speed goes from 0 to `v0` with the C² smoothstep (time, >= 0);
    /// `None` = `motion.ramp`. Only in `transient`: must be 0 or omitted in `static`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub v0_ramp: Option<f64>,
    /// Slip angle α (degrees, |α| < 90): the road's velocity turned by α about the vertical
    /// +x2, V = v0 (cos α, −sin α) in (e1, e3). Only in the three-dimensional steady mode.
    #[serde(default)]
    pub slip_angle: f64,
    /// Camber γ (degrees, |γ| < 90): the wheel plane tilted by γ about the rolling direction
    /// relative to the road; in the wheel frame the road's normal is n = (0, cos γ, −sin γ)
    /// (γ > 0 brings the wheel's +x3 side down). Three-dimensional static and steady modes.
    #[serde(default)]
    pub camber: f64,
}

impl RoadSpec {
    /// The road-speed ramp: `v0_ramp`, or `motion.ramp` when not given.
    pub fn resolved_v0_ramp(&self, motion: &Motion) -> f64 {
        self.v0_ramp.unwrap_or(motion.ramp)
    }

    /// Fraction of the final penetration `disp` (or of the `load`) applied at time `t` of a
    /// transient run: `S(t / ramp)`.
    pub fn ramp_factor(&self, t: f64) -> f64 {
        ramp_value(t, self.ramp)
    }

    /// Time derivative of [`RoadSpec::ramp_factor`].
    pub fn ramp_factor_rate(&self, t: f64) -> f64 {
        ramp_rate(t, self.ramp)
    }

    /// Road speed at time `t` of a transient run: `v0 · S(t / v0_ramp)`, with the resolved
    /// `v0_ramp` (see [`RoadSpec::resolved_v0_ramp`]).
    pub fn v0_at(&self, t: f64, motion: &Motion) -> f64 {
        self.v0 * ramp_value(t, self.resolved_v0_ramp(motion))
    }
}

/// `[contact]`: normal compliance `t_n = c_n δ^m_n + b_n δ^l_n δ̇` (per unit reference length of
/// the outer boundary), integrated edge by edge with `points` points of the `quadrature` rule.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// Compliance coefficient (stress/length^m_n), > 0. With `m_n = 1` it is the penalty 1/ε.
    pub c_n: f64,
    /// Compliance exponent, >= 1.
    #[serde(default = "default_m_n")]
    pub m_n: f64,
    /// Normal damping coefficient (stress·time/length^(l_n+1)), >= 0; must be 0 in `static`.
    #[serde(default)]
    pub b_n: f64,
    /// Damping exponent, >= 0.
    #[serde(default)]
    pub l_n: f64,
    /// Quadrature rule on each boundary edge.
    #[serde(default)]
    pub quadrature: ContactQuadrature,
    /// Quadrature points per boundary edge, `MIN_CONTACT_POINTS..=MAX_CONTACT_POINTS`.
    #[serde(default = "default_contact_points")]
    pub points: usize,
    /// No-adhesion clamp of t_n: `hard` (max(0, ·), the default) or `smooth` (C¹ ramp).
    #[serde(default)]
    pub clamp: ClampKind,
    /// Width of the smooth clamp (traction, > 0; only with `clamp = "smooth"`). Default:
    /// [`DEFAULT_CLAMP_WIDTH_OVER_G`] × the material's small-strain shear modulus G.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clamp_width: Option<f64>,
}

/// Default `[contact] clamp_width` as a fraction of the shear modulus G (10 psi for the rubber
/// scenes, a few per cent of their peak contact pressure).
pub const DEFAULT_CLAMP_WIDTH_OVER_G: f64 = 0.05;

/// Default of `[contact] m_n`.
pub const DEFAULT_M_N: f64 = 1.0;

/// Default of `[contact] points`.
pub const DEFAULT_CONTACT_POINTS: usize = 4;

/// Smallest allowed `[contact] points`.
pub const MIN_CONTACT_POINTS: usize = 2;

/// Largest allowed `[contact] points`.
pub const MAX_CONTACT_POINTS: usize = 6;

pub(super) fn default_m_n() -> f64 {
    DEFAULT_M_N
}

pub(super) fn default_contact_points() -> usize {
    DEFAULT_CONTACT_POINTS
}

/// A ramp time of `[road]`: finite, >= 0, and 0 in `static` (which has no time).
pub(super) fn validate_road_ramp(
    key: &str,
    value: f64,
    what: &str,
    mode: Option<Mode>,
    out: &mut Vec<Issue>,
) {
    if !(value.is_finite() && value >= 0.0) {
        out.push(issue(
            format!("road.{key}"),
            format!("{what} time must be >= 0, got {value}"),
        ));
    } else if value != 0.0 && mode == Some(Mode::Static) {
        out.push(issue(
            format!("road.{key}"),
            format!(
                "a static analysis has no time for a {what} (its load steps play that role; only \
                 \"transient\" has time): {key} must be 0 or omitted, got {value}"
            ),
        ));
    }
}

pub(super) fn validate_road(
    r: &RoadSpec,
    mode: Option<Mode>,
    g: Option<&Geometry>,
    out: &mut Vec<Issue>,
) {
    validate_road_ramp("ramp", r.ramp, "road ramp", mode, out);
    if let Some(v) = r.v0_ramp {
        validate_road_ramp("v0_ramp", v, "road-speed ramp", mode, out);
    }
    if !(r.slip_angle.is_finite() && r.slip_angle.abs() < 90.0) {
        out.push(issue(
            "road.slip_angle",
            format!(
                "slip angle (degrees) must be in (−90, 90), got {}",
                r.slip_angle
            ),
        ));
    }
    if !(r.camber.is_finite() && r.camber.abs() < 90.0) {
        out.push(issue(
            "road.camber",
            format!("camber (degrees) must be in (−90, 90), got {}", r.camber),
        ));
    }
    if let Some(d) = r.disp {
        if !(d.is_finite() && d >= 0.0) {
            out.push(issue(
                "road.disp",
                format!("penetration Ro − H must be >= 0, got {d}"),
            ));
        } else if let Some(g) = g.filter(|g| positive(g.ri) && g.ro.is_finite() && g.ro > g.ri) {
            if d >= g.ro - g.ri {
                out.push(issue(
                    "road.disp",
                    format!(
                        "penetration {d} must be less than the wall thickness ro − ri = {} \
                         (the road would reach the hub)",
                        g.ro - g.ri
                    ),
                ));
            }
        }
    }
    if let Some(l) = r.load {
        if !positive(l) {
            out.push(issue(
                "road.load",
                format!("load (the hub force: per unit thickness in plane strain, total in 3D) must be > 0, got {l}"),
            ));
        }
    }
    match (r.disp, r.load) {
        (Some(_), Some(_)) => out.push(issue(
            "road.disp",
            "give either `disp` (displacement control) or `load` (load control), not both",
        )),
        (None, None) => out.push(issue(
            "road.disp",
            "one of `disp` (final penetration Ro − H, displacement control) or `load` \
             (force per unit thickness, load control) is required",
        )),
        _ => {}
    }
    if mode == Some(Mode::Static) && r.v0 != 0.0 {
        out.push(issue(
            "road.v0",
            format!(
                "the road does not move in a static analysis (slip is w = dx1/dτ): v0 must be 0 \
                 or omitted, got {}",
                r.v0
            ),
        ));
    }
}

pub(super) fn validate_contact(c: &ContactSpec, mode: Option<Mode>, out: &mut Vec<Issue>) {
    if !positive(c.c_n) {
        out.push(issue(
            "contact.c_n",
            format!("normal compliance coefficient must be > 0, got {}", c.c_n),
        ));
    }
    if !(c.m_n.is_finite() && c.m_n >= 1.0) {
        out.push(issue(
            "contact.m_n",
            format!("normal compliance exponent must be >= 1, got {}", c.m_n),
        ));
    }
    if !(c.b_n.is_finite() && c.b_n >= 0.0) {
        out.push(issue(
            "contact.b_n",
            format!("normal damping coefficient must be >= 0, got {}", c.b_n),
        ));
    } else if mode == Some(Mode::Static) && c.b_n != 0.0 {
        out.push(issue(
            "contact.b_n",
            format!(
                "normal damping needs time, and a static analysis has none: b_n must be 0 or \
                 omitted, got {}",
                c.b_n
            ),
        ));
    }
    if !(c.l_n.is_finite() && c.l_n >= 0.0) {
        out.push(issue(
            "contact.l_n",
            format!("normal damping exponent must be >= 0, got {}", c.l_n),
        ));
    }
    match (c.clamp, c.clamp_width) {
        (ClampKind::Hard, Some(w)) => out.push(issue(
            "contact.clamp_width",
            format!(
                "`clamp_width` = {w} is only used by the smooth clamp: set contact.clamp = \
                 \"smooth\" or remove clamp_width"
            ),
        )),
        (ClampKind::Smooth, Some(w)) if !positive(w) => out.push(issue(
            "contact.clamp_width",
            format!("smooth clamp width must be > 0 (a traction), got {w}"),
        )),
        _ => {}
    }
    if !(MIN_CONTACT_POINTS..=MAX_CONTACT_POINTS).contains(&c.points) {
        out.push(issue(
            "contact.points",
            format!(
                "quadrature points per edge must be in {MIN_CONTACT_POINTS}..={MAX_CONTACT_POINTS}, \
                 got {}",
                c.points
            ),
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::laws::CoulombTanh;
    use crate::contact::Friction;
    use crate::io::scene::tests::*;
    use crate::io::scene::*;

    #[test]
    fn indentation_scenes_parse() {
        let s = load(FRICTIONLESS).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.scene.name, "indentation_frictionless");
        assert_eq!(s.analysis.mode, Mode::Static);
        assert_eq!((s.geometry.ri, s.geometry.ro), (1.0, 2.0));
        assert_eq!((s.mesh.n_r, s.mesh.n_theta, s.mesh.order), (6, 96, 2));
        assert_eq!(s.mesh.grading_theta, 0.6);
        assert_eq!(
            s.material.params(),
            Some(crate::material::MooneyRivlin::new(80.0, 20.0, 2000.0).into())
        );
        assert_eq!(s.material.rho, 0.027);
        assert_eq!(s.motion.omega, 0.0);
        assert_eq!(
            s.road,
            Some(RoadSpec {
                disp: Some(0.1),
                load: None,
                v0: 0.0,
                ramp: 0.0,
                v0_ramp: None,
                slip_angle: 0.0,
                camber: 0.0
            })
        );
        assert_eq!(
            s.contact,
            Some(ContactSpec {
                c_n: 2.0e5,
                m_n: 1.0,
                b_n: 0.0,
                l_n: 0.0,
                quadrature: ContactQuadrature::Lobatto,
                points: 4,
                clamp: ClampKind::Hard,
                clamp_width: None
            })
        );
        // c_n = 1000 G / (Ro − Ri).
        let g = s.material.shear_modulus().unwrap_or(0.0);
        let c_n = s.contact.as_ref().map_or(0.0, |c| c.c_n);
        assert!((c_n - 1000.0 * g / (s.geometry.ro - s.geometry.ri)).abs() < 1e-6);
        assert_eq!(s.friction, FrictionSpec::default());
        assert_eq!(s.friction.params(), Some(Friction::None));
        assert!(!s.friction.is_active());
        assert_eq!(s.stick_slip, None);
        assert_eq!(s.solver.load_steps, 5);
        assert!(s.validate().is_ok());

        let f = load(FRICTION).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(f.scene.name, "indentation_friction");
        assert_eq!(
            f.friction.params(),
            Some(Friction::CoulombTanh(CoulombTanh::new(0.3, 0.01)))
        );
        assert!(f.friction.is_active());
        // Same scene otherwise.
        assert_eq!(
            (&f.road, &f.contact, &f.mesh),
            (&s.road, &s.contact, &s.mesh)
        );
        assert_eq!(f.material, s.material);
    }

    #[test]
    fn load_control_scene_parses() {
        let s = load(LOAD_CONTROL).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.scene.name, "indentation_load_control");
        assert_eq!(s.analysis.mode, Mode::Static);
        assert_eq!(
            s.road,
            Some(RoadSpec {
                disp: None,
                load: Some(300.0),
                v0: 0.0,
                ramp: 0.0,
                v0_ramp: None,
                slip_angle: 0.0,
                camber: 0.0
            })
        );
        let base = load(FRICTIONLESS).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.contact, base.contact);
        assert_eq!(s.friction, base.friction);
        assert_eq!(s.mesh, base.mesh);
        assert_eq!(s.solver, base.solver);
    }

    #[test]
    fn contact_defaults_are_filled() {
        let text = remove_section(FRICTIONLESS, "[contact]") + "[contact]\nc_n = 1e4\n";
        let s = load(&text).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            s.contact,
            Some(ContactSpec {
                c_n: 1e4,
                m_n: DEFAULT_M_N,
                b_n: 0.0,
                l_n: 0.0,
                quadrature: ContactQuadrature::Lobatto,
                points: DEFAULT_CONTACT_POINTS,
                clamp: ClampKind::Hard,
                clamp_width: None
            })
        );
        // No [friction] at all: law none.
        let text = remove_section(FRICTION, "[friction]");
        let s = load(&text).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.friction.law, FrictionLawName::None);
        assert!(!s.friction.is_active());
    }

    #[test]
    fn non_positive_c_n_rejected_with_line() {
        for bad in ["c_n = 0.0", "c_n = -2.0e5"] {
            let text = replace_line(FRICTIONLESS, "c_n", bad);
            let e = errors(&text);
            assert_only(&e, "contact.c_n", Some(line_of(&text, "c_n")));
            assert!(e.0[0].message.contains("> 0"), "{e}");
        }
    }

    #[test]
    fn contact_exponents_damping_and_points_rejected() {
        let text = replace_line(FRICTIONLESS, "m_n", "m_n = 0.5");
        let e = errors(&text);
        assert_only(&e, "contact.m_n", Some(line_of(&text, "m_n")));
        assert!(e.0[0].message.contains(">= 1"), "{e}");

        let text = replace_line(FRICTIONLESS, "b_n", "b_n = -1.0");
        let text = replace_line(&text, "l_n", "l_n = -0.5");
        let text = replace_line(&text, "points", "points = 7");
        let e = errors(&text);
        assert_eq!(e.0.len(), 3, "{e}");
        for key in ["b_n", "l_n", "points"] {
            let err = e
                .find(&format!("contact.{key}"))
                .unwrap_or_else(|| panic!("{e}"));
            assert_eq!(err.line, Some(line_of(&text, key)), "{err}");
        }
        let e = errors(&replace_line(FRICTIONLESS, "points", "points = 1"));
        assert!(e.has_key("contact.points"), "{e}");
        for ok in ["points = 2", "points = 6"] {
            assert!(
                load(&replace_line(FRICTIONLESS, "points", ok)).is_ok(),
                "{ok}"
            );
        }
        assert!(load(&replace_line(FRICTIONLESS, "m_n", "m_n = 1.5")).is_ok());
    }

    #[test]
    fn contact_clamp_keys_are_validated() {
        // Default: the hard clamp, no width.
        let sc = load(FRICTIONLESS).unwrap_or_else(|e| panic!("{e}"));
        let c = sc.contact.as_ref().unwrap_or_else(|| panic!("no contact"));
        assert_eq!((c.clamp, c.clamp_width), (ClampKind::Hard, None));
        // Smooth with and without a width.
        let text = replace_line(FRICTIONLESS, "points", "points = 4\nclamp = \"smooth\"");
        let sc = load(&text).unwrap_or_else(|e| panic!("{e}"));
        let c = sc.contact.as_ref().unwrap_or_else(|| panic!("no contact"));
        assert_eq!((c.clamp, c.clamp_width), (ClampKind::Smooth, None));
        let sc = load_with(&text, &["contact.clamp_width=25"]).unwrap_or_else(|e| panic!("{e}"));
        let c = sc.contact.as_ref().unwrap_or_else(|| panic!("no contact"));
        assert_eq!(c.clamp_width, Some(25.0));
        // A misspelt clamp names the key and the allowed values.
        let bad = replace_line(FRICTIONLESS, "points", "points = 4\nclamp = \"soft\"");
        let e = errors(&bad);
        assert_only(&e, "contact.clamp", Some(line_of(&bad, "clamp")));
        assert!(
            e.0[0].message.contains("\"hard\"") && e.0[0].message.contains("\"smooth\""),
            "{e}"
        );
        // A width must be positive and is only allowed with the smooth clamp.
        for w in ["0", "-3"] {
            let e = errors_with(&text, &[&format!("contact.clamp_width={w}")]);
            assert!(e.has_key("contact.clamp_width"), "{e}");
            assert!(e.0[0].message.contains("> 0"), "{e}");
        }
        let e = errors_with(FRICTIONLESS, &["contact.clamp_width=5"]);
        assert!(e.has_key("contact.clamp_width"), "{e}");
        assert!(e.0[0].message.contains("smooth"), "{e}");
        // The printed scene keeps the choice (round trip).
        let sc = load_with(&text, &["contact.clamp_width=25"]).unwrap_or_else(|e| panic!("{e}"));
        let back = load(&sc.to_toml_string()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(back.contact, sc.contact);
    }

    #[test]
    fn both_or_neither_disp_and_load_rejected() {
        let text = replace_line(FRICTIONLESS, "disp", "disp = 0.1\nload = 300.0");
        let e = errors(&text);
        assert_only(&e, "road.disp", Some(line_of(&text, "disp")));
        assert!(e.0[0].message.contains("not both"), "{e}");

        let text = FRICTIONLESS
            .lines()
            .filter(|l| !l.starts_with("disp"))
            .collect::<Vec<_>>()
            .join("\n");
        let e = errors(&text);
        assert_only(&e, "road.disp", Some(line_of(&text, "[road]")));
        assert!(e.0[0].message.contains("required"), "{e}");

        let text = replace_line(LOAD_CONTROL, "load =", "load = 0.0");
        let e = errors(&text);
        assert_only(&e, "road.load", Some(line_of(&text, "load =")));
        let text = replace_line(FRICTIONLESS, "disp", "disp = -0.1");
        let e = errors(&text);
        assert_only(&e, "road.disp", Some(line_of(&text, "disp")));
        // Penetration at least the wall thickness.
        let text = replace_line(FRICTIONLESS, "disp", "disp = 1.0");
        let e = errors(&text);
        assert_only(&e, "road.disp", Some(line_of(&text, "disp")));
        assert!(e.0[0].message.contains("wall thickness"), "{e}");
        assert!(load(&replace_line(FRICTIONLESS, "disp", "disp = 0")).is_ok());
    }

    #[test]
    fn missing_c_n_reported_once() {
        let text = FRICTIONLESS
            .lines()
            .filter(|l| !l.starts_with("c_n"))
            .collect::<Vec<_>>()
            .join("\n");
        let e = errors(&text);
        assert_only(&e, "contact.c_n", Some(line_of(&text, "[contact]")));
        assert!(e.0[0].message.contains("required key is missing"), "{e}");
        let e = errors(&replace_line(FRICTIONLESS, "c_n", "c_n = \"big\""));
        assert_eq!(e.0.len(), 1, "{e}");
        assert!(e.0[0].message.contains("expected a number"), "{e}");
    }
}
