//! `[scene]` (name, description, units) and `[geometry]` (the reference annulus `ri <= |X| <= ro`).

use super::issue::{issue, positive, Issue};
use serde::{Deserialize, Serialize};

/// Default of `[scene] units` (informational only).
pub const DEFAULT_UNITS: &str = "in-lbf-s";

/// `[scene]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneInfo {
    /// Names the output directory: `[A-Za-z0-9_-]+`.
    pub name: String,
    #[serde(default)]
    pub description: String,
    /// Informational: the consistent unit system of the scene.
    #[serde(default = "default_units")]
    pub units: String,
}

pub(super) fn default_units() -> String {
    DEFAULT_UNITS.to_string()
}

/// `[geometry]`: the reference annulus `ri <= |X| <= ro`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Geometry {
    /// Inner (hub) radius.
    pub ri: f64,
    /// Outer radius.
    pub ro: f64,
}

pub(super) fn validate_info(s: &SceneInfo, out: &mut Vec<Issue>) {
    let valid = !s.name.is_empty()
        && s.name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    if !valid {
        out.push(issue(
            "scene.name",
            format!(
                "\"{}\" is not a valid name: it names the output directory, so use only \
                 letters, digits, '_' and '-' (at least one character)",
                s.name
            ),
        ));
    }
}

pub(super) fn validate_geometry(g: &Geometry, out: &mut Vec<Issue>) {
    let ri_ok = positive(g.ri);
    if !ri_ok {
        out.push(issue(
            "geometry.ri",
            format!("inner radius must be > 0, got {}", g.ri),
        ));
    }
    if !g.ro.is_finite() {
        out.push(issue(
            "geometry.ro",
            format!("outer radius must be finite, got {}", g.ro),
        ));
    } else if ri_ok && g.ro <= g.ri {
        out.push(issue(
            "geometry.ro",
            format!(
                "outer radius ro = {} must be greater than inner radius ri = {}",
                g.ro, g.ri
            ),
        ));
    } else if !ri_ok && g.ro <= 0.0 {
        out.push(issue(
            "geometry.ro",
            format!("outer radius must be > 0, got {}", g.ro),
        ));
    }
}

#[cfg(test)]
mod tests {
    use crate::io::scene::tests::*;

    #[test]
    fn ri_not_less_than_ro_rejected_with_line() {
        let text = replace_line(MINIMAL, "ri =", "ri = 2.5   # larger than ro");
        let e = errors(&text);
        assert_eq!(e.0.len(), 1, "{e}");
        let err = &e.0[0];
        assert_eq!(err.key, "geometry.ro");
        assert_eq!(err.line, Some(line_of(&text, "ro =")));
        assert!(err.message.contains("greater than"), "{}", err.message);

        let text = replace_line(MINIMAL, "ri =", "ri = -1.0");
        let e = errors(&text);
        let err = e.find("geometry.ri").unwrap_or_else(|| panic!("{e}"));
        assert_eq!(err.line, Some(line_of(&text, "ri =")));
    }

    #[test]
    fn scene_name_must_be_a_directory_name() {
        let e = errors(&replace_line(MINIMAL, "name", "name = \"my scene/1\""));
        assert!(e.has_key("scene.name"), "{e}");
        let e = errors(&replace_line(MINIMAL, "name", "name = \"\""));
        assert!(e.has_key("scene.name"), "{e}");
    }
}
