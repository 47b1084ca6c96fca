//! `[mesh]`: the structured annulus (`n_r`, `n_theta`, `order`, gradings) or a Gmsh `.msh` 4.1 file
//! with its hub and contact groups.

use super::issue::{issue, issue_near, positive, table_has, Issue};
use serde::{Deserialize, Serialize};

/// Smallest allowed `mesh.n_theta`.
pub const MIN_N_THETA: usize = 8;

/// `[mesh]`: structured annular mesh.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MeshSpec {
    /// Radial cells (>= 1).
    pub n_r: usize,
    /// Circumferential cells (>= 8, even).
    pub n_theta: usize,
    /// Element order: 1 (Q1) or 2 (Q2).
    pub order: usize,
    /// Ratio of the outermost to the innermost radial cell size (> 0; 1 = uniform).
    pub grading_r: f64,
    /// Fraction in [0, 1) of circumferential refinement toward θ = −π/2 (the road); 0 = uniform.
    pub grading_theta: f64,
    /// A Gmsh `.msh` 4.1 mesh instead of the generated annulus (relative paths are relative to
    /// the scene file). Then `n_r`, `n_theta`, `order`, `grading_r`, `grading_theta` are not used.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    /// 1D physical group of `file` bonded to the hub (default "hub").
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hub: Option<String>,
    /// 1D physical group of `file` where contact with the road can happen (default "contact").
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact: Option<String>,
}

/// Default `[mesh] hub` group name.
pub const DEFAULT_HUB_GROUP: &str = "hub";

/// Default `[mesh] contact` group name.
pub const DEFAULT_CONTACT_GROUP: &str = "contact";

impl MeshSpec {
    /// The keys of the generated annulus, not used (and refused) with `file`.
    pub const GENERATOR_KEYS: &'static [&'static str] =
        &["n_r", "n_theta", "order", "grading_r", "grading_theta"];
}

impl Default for MeshSpec {
    fn default() -> Self {
        MeshSpec {
            n_r: 4,
            n_theta: 32,
            order: 2,
            grading_r: 1.0,
            grading_theta: 0.0,
            file: None,
            hub: None,
            contact: None,
        }
    }
}

/// `[mesh] file` and its companions: the group names only with a file, the generator's keys
/// not with one, `[[material]]` only with one.
pub(super) fn validate_mesh_file(
    m: &MeshSpec,
    regions: &[(String, toml::Table)],
    doc: &toml::Table,
    out: &mut Vec<Issue>,
) {
    match &m.file {
        Some(f) => {
            if f.trim().is_empty() {
                out.push(issue(
                    "mesh.file",
                    "must name a .msh file, got an empty string",
                ));
            }
            for key in MeshSpec::GENERATOR_KEYS {
                if table_has(doc, "mesh", key) {
                    out.push(issue(
                        format!("mesh.{key}"),
                        "not used with mesh.file (the mesh comes from the file); remove it",
                    ));
                }
            }
            for (key, v) in [("hub", &m.hub), ("contact", &m.contact)] {
                if v.as_deref().is_some_and(|s| s.trim().is_empty()) {
                    out.push(issue(
                        format!("mesh.{key}"),
                        "must name a 1D physical group of mesh.file, got an empty string",
                    ));
                }
            }
        }
        None => {
            for (key, v) in [("hub", &m.hub), ("contact", &m.contact)] {
                if v.is_some() {
                    out.push(issue(
                        format!("mesh.{key}"),
                        "names a physical group of a mesh file: only with mesh.file",
                    ));
                }
            }
            if !regions.is_empty() {
                out.push(issue_near(
                    "material",
                    "[[material]] (a material per mesh region) needs a mesh file with regions \
                     (mesh.file); use a single [material] with the generated annulus",
                    "mesh",
                ));
            }
        }
    }
}

pub(super) fn validate_mesh(m: &MeshSpec, out: &mut Vec<Issue>) {
    if m.n_r < 1 {
        out.push(issue("mesh.n_r", "must be >= 1, got 0"));
    }
    if m.n_theta < MIN_N_THETA {
        out.push(issue(
            "mesh.n_theta",
            format!("must be >= {MIN_N_THETA}, got {}", m.n_theta),
        ));
    } else if !m.n_theta.is_multiple_of(2) {
        out.push(issue(
            "mesh.n_theta",
            format!("must be even, got {}", m.n_theta),
        ));
    }
    if m.order != 1 && m.order != 2 {
        out.push(issue(
            "mesh.order",
            format!("must be 1 (Q1) or 2 (Q2), got {}", m.order),
        ));
    }
    if !positive(m.grading_r) {
        out.push(issue(
            "mesh.grading_r",
            format!(
                "must be > 0 (ratio of outermost to innermost radial cell size), got {}",
                m.grading_r
            ),
        ));
    }
    if !(m.grading_theta.is_finite() && (0.0..1.0).contains(&m.grading_theta)) {
        out.push(issue(
            "mesh.grading_theta",
            format!("must be in [0, 1), got {}", m.grading_theta),
        ));
    }
}

#[cfg(test)]
mod tests {
    use crate::io::scene::tests::*;

    #[test]
    fn n_theta_too_small_or_odd_rejected() {
        let e = errors(&format!("{MINIMAL}\n[mesh]\nn_theta = 6\n"));
        let err = e.find("mesh.n_theta").unwrap_or_else(|| panic!("{e}"));
        assert!(err.message.contains(">= 8"), "{}", err.message);
        let text = format!("{MINIMAL}\n[mesh]\nn_theta = 33\n");
        let e = errors(&text);
        let err = e.find("mesh.n_theta").unwrap_or_else(|| panic!("{e}"));
        assert!(err.message.contains("even"), "{}", err.message);
        assert_eq!(err.line, Some(line_of(&text, "n_theta")));
    }

    #[test]
    fn other_mesh_and_solver_ranges_rejected() {
        let text = format!(
            "{MINIMAL}\n[mesh]\nn_r = 0\norder = 3\ngrading_r = 0\ngrading_theta = 1.0\n\
             [solver]\ntolerance = 1.0\nmax_iterations = 0\nload_steps = 0\n"
        );
        let e = errors(&text);
        for key in [
            "mesh.n_r",
            "mesh.order",
            "mesh.grading_r",
            "mesh.grading_theta",
            "solver.tolerance",
            "solver.max_iterations",
            "solver.load_steps",
        ] {
            assert!(e.has_key(key), "missing {key} in\n{e}");
        }
        assert_eq!(e.0.len(), 7, "{e}");
    }
}
