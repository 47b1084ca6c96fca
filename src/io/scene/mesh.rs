//! `[mesh]`: the structured annulus (`n_r`, `n_theta`, `order`, gradings) or a Gmsh `.msh` 4.1 file
//! with its hub and contact groups; with `dimension = 3` the annulus revolved about the axle
//! into a wheel of width `width` (`n_z` axial cells, optionally crowned) or a hexahedral Gmsh
//! file.

use super::analysis::Mode;
use super::issue::{issue, issue_near, positive, table_has, Issue};
use super::time::IntegratorName;
use serde::{Deserialize, Serialize};

keyword_enum! {
    /// The flat faces x3 = ±W/2 of a three-dimensional wheel (`[mesh] sides`).
    #[derive(Default)]
    MeshSides, "mesh sides" {
        #[default]
        /// Traction free.
        Free => "free",
        /// u3 = 0 on both faces, sliding freely in their plane: the plane-strain slab.
        Sliding => "sliding",
    }
}

/// Default `[mesh] n_z` (axial cells of a three-dimensional generated mesh).
pub const DEFAULT_N_Z: usize = 2;

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
    /// 2 (plane strain, default) or 3 (the revolved wheel, or hexahedra from `file`).
    #[serde(skip_serializing_if = "is_plane")]
    pub dimension: usize,
    /// Width W of the generated three-dimensional wheel (along the axle x3, centred on 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub width: Option<f64>,
    /// Axial cells of the generated three-dimensional wheel (default [`DEFAULT_N_Z`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub n_z: Option<usize>,
    /// Crown radius R_c of a toroidal tread (generated three-dimensional wheel; none: flat).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub crown_radius: Option<f64>,
    /// The flat faces of the generated three-dimensional wheel: `free` (default) or `sliding`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sides: Option<MeshSides>,
    /// Generated three-dimensional wheel: size of the circumferential cells at the top over
    /// the size at the bottom (θ = −π/2), geometric in between (default 1: the 2D breaks).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub theta_ratio: Option<f64>,
    /// Generated three-dimensional wheel: size of the axial cells at the sides over the size
    /// at the mid-plane x3 = 0, geometric in between (default 1: uniform).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub grading_z: Option<f64>,
}

fn is_plane(d: &usize) -> bool {
    *d == 2
}

/// Default `[mesh] hub` group name.
pub const DEFAULT_HUB_GROUP: &str = "hub";

/// Default `[mesh] contact` group name.
pub const DEFAULT_CONTACT_GROUP: &str = "contact";

impl MeshSpec {
    /// The keys of the generated annulus, not used (and refused) with `file`.
    pub const GENERATOR_KEYS: &'static [&'static str] =
        &["n_r", "n_theta", "order", "grading_r", "grading_theta"];

    /// The keys of the three-dimensional generated wheel.
    pub const KEYS_3D: &'static [&'static str] = &[
        "width",
        "n_z",
        "crown_radius",
        "sides",
        "theta_ratio",
        "grading_z",
    ];

    /// Whether the scene is three-dimensional.
    pub fn is_3d(&self) -> bool {
        self.dimension == 3
    }

    /// Axial cells of the generated three-dimensional wheel.
    pub fn resolved_n_z(&self) -> usize {
        self.n_z.unwrap_or(DEFAULT_N_Z)
    }

    /// The flat faces of the generated three-dimensional wheel.
    pub fn resolved_sides(&self) -> MeshSides {
        self.sides.unwrap_or_default()
    }
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
            dimension: 2,
            width: None,
            n_z: None,
            crown_radius: None,
            sides: None,
            theta_ratio: None,
            grading_z: None,
        }
    }
}

/// What the three-dimensional program does not run yet, and the keys that belong to one
/// dimension only. `doc` is the scene's table (for keys given explicitly), `None` for a scene
/// built in code.
pub(super) struct Dimension3DContext<'a> {
    pub(super) mode: Option<Mode>,
    pub(super) has_regions: bool,
    pub(super) doc: Option<&'a toml::Table>,
    /// `contact.quadrature` is Lobatto, with `contact.points`.
    pub(super) lobatto_points: Option<usize>,
}

/// What the three-dimensional transient mode does not run: torque control and the integrators
/// without a 3D scheme.
fn validate_transient_3d(doc: Option<&toml::Table>, out: &mut Vec<Issue>) {
    let get = |table: &str, key: &str| doc.and_then(|d| d.get(table)).and_then(|t| t.get(key));
    if let Some(c) = get("motion", "control").and_then(|v| v.as_str()) {
        if c != "speed" {
            out.push(issue(
                "motion.control",
                format!(
                    "\"{c}\" does not run in the three-dimensional transient mode (it runs \
                     \"speed\": the hub turns at the prescribed ω)"
                ),
            ));
        }
    }
    if let Some(name) = get("time", "integrator").and_then(|v| v.as_str()) {
        let known = IntegratorName::ALL.iter().find(|i| i.as_str() == name);
        if let Some(i) = known.filter(|i| !i.three_d()) {
            out.push(issue(
                "time.integrator",
                format!(
                    "\"{i}\" does not run in three dimensions (use {})",
                    IntegratorName::quoted_with(IntegratorName::three_d)
                ),
            ));
        }
    }
}

pub(super) fn validate_dimension(m: &MeshSpec, cx: &Dimension3DContext, out: &mut Vec<Issue>) {
    let given = |key: &str| cx.doc.is_some_and(|d| table_has(d, "mesh", key));
    let slip_angle = cx
        .doc
        .and_then(|d| d.get("road"))
        .and_then(|r| r.get("slip_angle"))
        .and_then(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)))
        .unwrap_or(0.0);
    let camber = cx
        .doc
        .and_then(|d| d.get("road"))
        .and_then(|r| r.get("camber"))
        .and_then(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)))
        .unwrap_or(0.0);
    if camber != 0.0
        && !(m.is_3d() && matches!(cx.mode, Some(Mode::Steady | Mode::Static | Mode::Transient)))
    {
        out.push(issue(
            "road.camber",
            "a camber needs the three-dimensional static, steady or transient mode \
             (mesh.dimension = 3); remove it or set it to 0",
        ));
    }
    let continued_in = cx
        .doc
        .and_then(|d| d.get("continuation"))
        .and_then(|c| c.get("parameter"))
        .and_then(|v| v.as_str());
    if let Some(p) = continued_in.filter(|p| matches!(*p, "slip_angle" | "camber")) {
        if !(m.is_3d() && cx.mode == Some(Mode::Steady)) {
            out.push(issue(
                "continuation.parameter",
                format!(
                    "parameter \"{p}\" needs the three-dimensional steady mode \
                     (mesh.dimension = 3, analysis.mode = \"steady\")"
                ),
            ));
        }
    }
    if slip_angle != 0.0 && !(m.is_3d() && matches!(cx.mode, Some(Mode::Steady | Mode::Transient)))
    {
        out.push(issue(
            "road.slip_angle",
            "a slip angle needs the three-dimensional steady or transient mode \
             (mesh.dimension = 3, analysis.mode = \"steady\" or \"transient\"); remove it or \
             set it to 0",
        ));
    }
    if m.dimension != 2 && m.dimension != 3 {
        out.push(issue(
            "mesh.dimension",
            format!(
                "must be 2 (plane strain) or 3 (three-dimensional wheel), got {}",
                m.dimension
            ),
        ));
        return;
    }
    if !m.is_3d() {
        let set = [
            ("width", m.width.is_some()),
            ("n_z", m.n_z.is_some()),
            ("crown_radius", m.crown_radius.is_some()),
            ("sides", m.sides.is_some()),
            ("theta_ratio", m.theta_ratio.is_some()),
            ("grading_z", m.grading_z.is_some()),
        ];
        for (key, present) in set {
            if present {
                out.push(issue(
                    format!("mesh.{key}"),
                    "only with mesh.dimension = 3 (a three-dimensional wheel); remove it or set \
                     mesh.dimension = 3",
                ));
            }
        }
        return;
    }
    if let Some(mode) = cx.mode {
        if !matches!(
            mode,
            Mode::Static | Mode::Spinning | Mode::Steady | Mode::Transient
        ) {
            out.push(issue(
                "analysis.mode",
                format!(
                    "mode \"{mode}\" does not run in three dimensions yet (mesh.dimension = 3 \
                     runs \"static\", \"spinning\", \"steady\" and \"transient\")"
                ),
            ));
        }
        if mode == Mode::Steady {
            validate_steady_3d(cx.doc, out);
        }
        if mode == Mode::Transient {
            validate_transient_3d(cx.doc, out);
        }
    }
    if cx.has_regions {
        out.push(issue_near(
            "material",
            "[[material]] (a material per mesh region) is not supported with mesh.dimension = 3 \
             yet; use a single [material]",
            "mesh",
        ));
    }
    if let Some(points) = cx.lobatto_points {
        if points > 4 {
            out.push(issue(
                "contact.points",
                format!(
                    "with mesh.dimension = 3 and quadrature = \"lobatto\" must be 2..=4 per \
                     direction, got {points} (\"gauss\" takes up to 6)"
                ),
            ));
        }
    }
    if m.file.is_some() {
        for key in MeshSpec::KEYS_3D {
            if given(key) {
                out.push(issue(
                    format!("mesh.{key}"),
                    "not used with mesh.file (the three-dimensional mesh comes from the file); \
                     remove it",
                ));
            }
        }
        return;
    }
    match m.width {
        None => out.push(issue(
            "mesh.width",
            "required with mesh.dimension = 3 (the wheel's width along the axle)",
        )),
        Some(w) if !positive(w) => out.push(issue("mesh.width", format!("must be > 0, got {w}"))),
        Some(w) => {
            if let Some(rc) = m.crown_radius {
                if !(rc.is_finite() && rc >= 0.5 * w) {
                    out.push(issue(
                        "mesh.crown_radius",
                        format!("must be >= width/2 = {}, got {rc}", 0.5 * w),
                    ));
                }
            }
        }
    }
    if m.n_z == Some(0) {
        out.push(issue("mesh.n_z", "must be >= 1, got 0"));
    }
    for (key, value) in [("theta_ratio", m.theta_ratio), ("grading_z", m.grading_z)] {
        if let Some(v) = value.filter(|&v| !positive(v)) {
            out.push(issue(
                format!("mesh.{key}"),
                format!("must be finite and > 0, got {v}"),
            ));
        }
    }
    if m.crown_radius.is_some() && m.resolved_sides() == MeshSides::Sliding {
        out.push(issue(
            "mesh.sides",
            "\"sliding\" (the plane-strain slab) needs flat sides: remove mesh.crown_radius",
        ));
    }
}

/// The three-dimensional steady mode's continuation names its parameter explicitly.
fn validate_steady_3d(doc: Option<&toml::Table>, out: &mut Vec<Issue>) {
    let Some(doc) = doc else {
        return;
    };
    let parameter = doc
        .get("continuation")
        .and_then(|c| c.get("parameter"))
        .and_then(|v| v.as_str());
    if doc.contains_key("continuation") && parameter.is_none() {
        out.push(issue(
            "continuation.parameter",
            "give the parameter explicitly in the three-dimensional steady mode: \"slip_angle\", \
             \"camber\", \"creep\", \"load\", \"omega\" or \"disp\"",
        ));
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
