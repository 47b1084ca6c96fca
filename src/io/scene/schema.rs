//! The one schema of scene files: every section and key with its kind, whether it is required,
//! its unit and its meaning ([`SCHEMA`]). Defaults are not written here: they are read from the
//! serde structs (`#[serde(default)]`) by deserialising a section that holds only its required keys
//! ([`section_defaults`]), so they cannot disagree with what loading does.
//!
//! From this table come: the schema pass of loading (unknown keys, types, allowed values, the key
//! lists in error messages), the JSON Schema for editors ([`json_schema`], `tread schema`) and the
//! key reference ([`markdown_reference`], `tread schema --markdown`, committed as
//! `docs/reference.md`). A test checks the table against the serde structs.
//!
//! Units are those of the scene (`[scene] units = "L-F-T"`, e.g. `in-lbf-s`): L length, F force,
//! T time; the program does not convert. Forces, torques and energies are per unit thickness
//! (plane strain).

use super::analysis::{Analysis, Mode};
use super::contact::{ClampKind, ContactQuadrature, ContactSpec, RoadSpec};
use super::friction::{FrictionLawName, FrictionSpec};
use super::geometry::{Geometry, SceneInfo};
use super::issue::quoted_list;
use super::material::{Formulation, MaterialModel, MaterialSpec};
use super::mesh::MeshSpec;
use super::motion::{Control, Motion};
use super::output::{OutputSpec, Sink, VtuCompression, VtuFormat};
use super::solver::{DampingTangentChoice, LinearChoice, SolverSpec, SteadyHistoryChoice};
use super::steady::{ContinuationParameter, ContinuationSpec, LimitAction};
use super::stick_slip::StickSlipSpec;
use super::time::{IntegratorName, MassKind, TimeSpec};
use crate::params::LawKind;
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::collections::BTreeSet;
use std::sync::LazyLock;

use serde_json::{json, Map, Value};

/// Keys of `[time]` required by the transient mode that the steady mode does not read: a
/// steady scene may give `[time]` for `strain_rate_damping` alone (see
/// [`super::TimeSpec::steady_only`]).
pub(super) const STEADY_UNUSED_TIME: [&str; 2] = ["dt", "t_end"];

#[derive(Clone, Copy, Debug)]
pub(super) enum Kind {
    Float,
    UInt,
    Bool,
    Str,
    Keyword(&'static [&'static str]),
    /// An array of keywords (no duplicates).
    KeywordList(&'static [&'static str]),
    /// A sub-table with its own keys (`[material.viscoelastic]`).
    Table(&'static [FieldSchema]),
    /// An array of `[number, number]` pairs (Prony terms).
    FloatPairs,
    /// An array of numbers.
    FloatList,
}

#[derive(Debug)]
pub(super) struct FieldSchema {
    pub(super) key: &'static str,
    pub(super) kind: Kind,
    pub(super) required: bool,
    /// Unit in the scene's L-F-T system ("–" for dimensionless or non-numeric keys).
    pub(super) unit: &'static str,
    /// What the key means, its range, and when it applies.
    pub(super) doc: &'static str,
}

pub(super) struct SectionSchema {
    pub(super) name: &'static str,
    pub(super) required: bool,
    pub(super) doc: &'static str,
    pub(super) fields: &'static [FieldSchema],
}

const fn req(key: &'static str, kind: Kind, unit: &'static str, doc: &'static str) -> FieldSchema {
    FieldSchema {
        key,
        kind,
        required: true,
        unit,
        doc,
    }
}

const fn opt(key: &'static str, kind: Kind, unit: &'static str, doc: &'static str) -> FieldSchema {
    FieldSchema {
        key,
        kind,
        required: false,
        unit,
        doc,
    }
}

const NONE: &str = "–";

/// Keys of `[material.viscoelastic]`.
static VISCOELASTIC_FIELDS: &[FieldSchema] = &[
    req("model", Kind::Keyword(crate::material::ViscoModel::NAMES), NONE,
        "`convolution` (linear convolution on the Green strain rate) or `multiplicative` (finite-strain model)"),
    req("gamma", Kind::Float, "F/L²", "stress scale γ of the Prony overstress, >= 0"),
    req("prony", Kind::FloatPairs, "[–, T]",
        "Prony terms `[[g, tau], ...]`: g dimensionless >= 0, tau > 0 (time); 1 to 8 terms"),
];

/// One optional number per parameter key of a family of laws, in the order of
/// [`LawKind::all_keys`], with the unit and bound its first law declares; the meaning names the
/// laws that take it, its note, and `more(key)` where that gives something.
fn law_param_fields<K: LawKind>(more: impl Fn(&str) -> Option<String>) -> Vec<FieldSchema> {
    let mut fields = Vec::new();
    for key in K::all_keys() {
        let Some(p) = K::param(key) else {
            continue;
        };
        let laws: Vec<&str> = K::laws_with(key).iter().map(|l| l.keyword()).collect();
        let mut doc = format!("{} ({}), {}", p.what, laws.join(", "), p.bound);
        for extra in [(!p.note.is_empty()).then(|| p.note.to_string()), more(key)]
            .into_iter()
            .flatten()
        {
            doc.push_str("; ");
            doc.push_str(&extra);
        }
        fields.push(opt(key, Kind::Float, p.unit, doc.leak()));
    }
    fields
}

/// Keys of `[friction]`: `law`, then every parameter of the registered laws (in the order of
/// [`FrictionLawName::all_keys`]) with the unit and bound its law declares; the meaning names
/// the laws that take it.
fn friction_fields() -> &'static [FieldSchema] {
    static FIELDS: LazyLock<Vec<FieldSchema>> = LazyLock::new(|| {
        let mut fields = vec![opt(
            "law",
            Kind::Keyword(FrictionLawName::NAMES),
            NONE,
            "friction law",
        )];
        fields.extend(law_param_fields::<FrictionLawName>(|_| None));
        fields
    });
    &FIELDS
}

/// Keys of `[material]`: `model`, `rho`, then every parameter of the registered laws (in the
/// order of [`MaterialModel::all_keys`]) with the unit and bound its law declares, the
/// incompressible formulation's keys, and the viscoelastic sub-table.
fn material_fields() -> &'static [FieldSchema] {
    static FIELDS: LazyLock<Vec<FieldSchema>> = LazyLock::new(|| {
        let incompressible: Vec<&str> = MaterialModel::ALL
            .iter()
            .filter(|m| m.is_incompressible())
            .map(|m| m.as_str())
            .collect();
        let perturbed_kappa = format!(
            "the perturbed formulation's bulk modulus ({}; default 1e4 G/2, G the shear modulus)",
            incompressible.join(", ")
        );
        let mut fields = vec![
            req(
                "model",
                Kind::Keyword(MaterialModel::NAMES),
                NONE,
                "hyperelastic model",
            ),
            req(
                "rho",
                Kind::Float,
                "F·T²/L⁴",
                "density per unit reference volume, > 0",
            ),
        ];
        let keys = MaterialModel::all_keys();
        fields.extend(law_param_fields::<MaterialModel>(|key| {
            (key == "kappa" && !incompressible.is_empty())
                .then(|| format!("also {perturbed_kappa}"))
        }));
        if !incompressible.is_empty() {
            if !keys.contains(&"kappa") {
                fields.push(opt(
                    "kappa",
                    Kind::Float,
                    "F/L²",
                    perturbed_kappa.clone().leak(),
                ));
            }
            let doc = format!(
                "incompressibility ({} only; default `exact`)",
                incompressible.join(", ")
            );
            fields.push(opt(
                "formulation",
                Kind::Keyword(Formulation::NAMES),
                NONE,
                doc.leak(),
            ));
        }
        fields.push(opt(
            "viscoelastic",
            Kind::Table(VISCOELASTIC_FIELDS),
            NONE,
            "`[material.viscoelastic]`: a Prony-series overstress on the elastic law",
        ));
        fields
    });
    &FIELDS
}

/// Every section of a scene file with its keys (built once; the keys of `[friction]` and
/// `[material]` come from the laws' declarations, [`friction_fields`], [`material_fields`]).
pub(super) static SCHEMA: LazyLock<Vec<SectionSchema>> = LazyLock::new(|| {
    vec![
    SectionSchema {
        name: "scene",
        required: true,
        doc: "Name and description of the run.",
        fields: &const { [
            req("name", Kind::Str, NONE, "names the output directory: `[A-Za-z0-9_-]+`"),
            opt("description", Kind::Str, NONE, "free text"),
            opt("units", Kind::Str, NONE,
                "informational: the consistent unit system `L-F-T` of every number (the program does not convert)"),
        ] },
    },
    SectionSchema {
        name: "geometry",
        required: true,
        doc: "The reference annulus `ri <= |X| <= ro`, bonded to a rigid hub at `|X| = ri`.",
        fields: &const { [
            req("ri", Kind::Float, "L", "inner (hub) radius, > 0"),
            req("ro", Kind::Float, "L", "outer radius, > ri"),
        ] },
    },
    SectionSchema {
        name: "mesh",
        required: false,
        doc: "The structured annular mesh, or a Gmsh `.msh` 4.1 file.",
        fields: &const { [
            opt("n_r", Kind::UInt, NONE, "radial cells, >= 1"),
            opt("n_theta", Kind::UInt, NONE, "circumferential cells, >= 8, even"),
            opt("order", Kind::UInt, NONE, "element order: 1 (Q1) or 2 (Q2)"),
            opt("grading_r", Kind::Float, NONE,
                "ratio of the outermost to the innermost radial cell size, > 0 (1 = uniform)"),
            opt("grading_theta", Kind::Float, NONE,
                "fraction in [0, 1) of circumferential refinement toward θ = −π/2 (the road); 0 = uniform"),
            opt("file", Kind::Str, NONE,
                "a Gmsh `.msh` 4.1 mesh instead of the generated annulus (relative to the scene file); then n_r, n_theta, order, grading_* are not used"),
            opt("hub", Kind::Str, NONE, "1D physical group of `file` bonded to the hub (default \"hub\")"),
            opt("contact", Kind::Str, NONE,
                "1D physical group of `file` where contact can happen (default \"contact\"; 2D groups of a hexahedral file with dimension = 3)"),
            opt("dimension", Kind::UInt, NONE,
                "2 (plane strain, default) or 3: the annulus revolved about the axle x3 into a wheel of width `width` (or the hexahedra of `file`); modes static, spinning and steady, forces total (not per width)"),
            opt("width", Kind::Float, "L",
                "dimension = 3, generated mesh (required): width W of the wheel along the axle, > 0, centred on x3 = 0"),
            opt("n_z", Kind::UInt, NONE,
                "dimension = 3, generated mesh: axial cells, >= 1 (default 2)"),
            opt("crown_radius", Kind::Float, "L",
                "dimension = 3, generated mesh: crown radius R_c >= width/2 of a toroidal tread (outer radius ro at x3 = 0); absent: flat"),
            opt("sides", Kind::Keyword(super::mesh::MeshSides::NAMES), NONE,
                "dimension = 3, generated mesh: the flat faces x3 = ±W/2, \"free\" (default) or \"sliding\" (u3 = 0: the plane-strain slab)"),
            opt("theta_ratio", Kind::Float, NONE,
                "dimension = 3, generated mesh: size of the circumferential cells at the top over the size at the bottom (θ = −π/2, the road), geometric in between, > 0 (default 1: the 2D breaks; > 1 clusters the cells toward the contact); grading_theta applies on top"),
            opt("grading_z", Kind::Float, NONE,
                "dimension = 3, generated mesh: size of the axial cells at the sides over the size at the mid-plane x3 = 0, geometric in between, > 0 (default 1: uniform; > 1 clusters the cells toward the mid-plane)"),
        ] },
    },
    SectionSchema {
        name: "material",
        required: true,
        doc: "The hyperelastic material (or `[[material]]` with `region = \"<2D physical group>\"`, one per mesh region). Which parameters are required depends on `model`.",
        fields: material_fields(),
    },
    SectionSchema {
        name: "analysis",
        required: true,
        doc: "What to compute.",
        fields: &const { [req("mode", Kind::Keyword(Mode::NAMES), NONE, "analysis mode")] },
    },
    SectionSchema {
        name: "motion",
        required: false,
        doc: "Hub rotation (spinning, transient, steady).",
        fields: &const { [
            opt("omega", Kind::Float, "rad/T",
                "target hub angular speed (counter-clockwise), >= 0; required for spinning and transient"),
            opt("ramp", Kind::Float, "T",
                "time of the C² smoothstep ramp of omega (or of the torque); transient only, else 0"),
            opt("control", Kind::Keyword(Control::NAMES), NONE,
                "how the hub is driven: speed; torque (transient with generalized_alpha, or steady); free_rolling, creep (steady)"),
            opt("hub_inertia", Kind::Float, "F·T² (M·L²/L)",
                "rotational inertia of the hub per unit thickness, > 0; transient torque control only"),
            opt("torque", Kind::Float, "F·L/L",
                "applied hub torque about +x3 per unit thickness; torque control only"),
            opt("creep", Kind::Float, NONE,
                "creep ξ = (v0 − ω R_e) / (ω R_e), > −1; control = \"creep\" only"),
        ] },
    },
    SectionSchema {
        name: "road",
        required: false,
        doc: "The rigid road `x2 = −H` below the hub: exactly one of `disp` and `load`.",
        fields: &const { [
            opt("disp", Kind::Float, "L", "final penetration Ro − H, >= 0, < ro − ri (displacement control)"),
            opt("load", Kind::Float, "F/L",
                "vertical force per unit thickness pushing the cylinder onto the road, > 0 (load control)"),
            opt("v0", Kind::Float, "L/T", "road speed along +x1 in the hub frame; 0 in static"),
            opt("ramp", Kind::Float, "T", "time of the smoothstep ramp of disp (or load); transient only"),
            opt("v0_ramp", Kind::Float, "T",
                "time of the smoothstep ramp of v0 (default: motion.ramp); transient only"),
            opt("slip_angle", Kind::Float, "deg",
                "slip angle α, |α| < 90: the road velocity turned by α about +x2, V = v0 (cos α, −sin α) in (e1, e3); three-dimensional steady and transient modes"),
            opt("camber", Kind::Float, "deg",
                "camber γ, |γ| < 90: the wheel plane tilted by γ about the rolling direction relative to the road, whose normal in the wheel frame is n = (0, cos γ, −sin γ); three-dimensional static, steady and transient modes"),
        ] },
    },
    SectionSchema {
        name: "contact",
        required: false,
        doc: "Normal compliance `t_n = c_n δ^m_n + b_n δ^l_n δ̇` per unit reference length of the outer boundary.",
        fields: &const { [
            req("c_n", Kind::Float, "F/L^(2+m_n)", "compliance coefficient, > 0 (with m_n = 1 the penalty)"),
            opt("m_n", Kind::Float, NONE, "compliance exponent, >= 1"),
            opt("b_n", Kind::Float, "F·T/L^(3+l_n)", "normal damping coefficient, >= 0; 0 in static"),
            opt("l_n", Kind::Float, NONE, "damping exponent, >= 0"),
            opt("quadrature", Kind::Keyword(ContactQuadrature::NAMES), NONE,
                "quadrature rule on each boundary edge"),
            opt("points", Kind::UInt, NONE, "quadrature points per boundary edge, 2 to 6"),
            opt("clamp", Kind::Keyword(ClampKind::NAMES), NONE,
                "no-adhesion clamp of t_n: `hard` max(0, ·) or `smooth` (C¹ ramp)"),
            opt("clamp_width", Kind::Float, "F/L²",
                "width of the smooth clamp, > 0 (default 0.05 × shear modulus); clamp = \"smooth\" only"),
        ] },
    },
    SectionSchema {
        name: "friction",
        required: false,
        doc: "Friction law `t_T = −μ(|w|) t_n φ_ε(w)`, slip velocity `w = ẋ1 − v0`. Which parameters are required depends on `law`.",
        fields: friction_fields(),
    },
    SectionSchema {
        name: "stick_slip",
        required: false,
        doc: "The one-degree-of-freedom oscillator `mass ẍ = −stiffness x + F_T` on a belt (stick_slip mode).",
        fields: &const { [
            req("mass", Kind::Float, "F·T²/L", "mass, > 0"),
            req("stiffness", Kind::Float, "F/L", "spring stiffness, > 0"),
            req("normal_force", Kind::Float, "F", "normal force on the belt, > 0"),
            req("belt_speed", Kind::Float, "L/T", "belt speed along +x, > 0"),
            req("t_end", Kind::Float, "T", "end time, > 0"),
            opt("rtol", Kind::Float, NONE, "relative tolerance of the adaptive integrator, > 0"),
            opt("atol", Kind::Float, "L, L/T", "absolute tolerance of the adaptive integrator, > 0"),
            opt("x0", Kind::Float, "L", "initial position (spring elongation)"),
            opt("v0", Kind::Float, "L/T", "initial velocity (default: belt_speed, sticking)"),
            opt("output_interval", Kind::Float, "T", "interval between samples, in (0, t_end] (default t_end / 2000)"),
        ] },
    },
    SectionSchema {
        name: "time",
        required: false,
        doc: "Time integration (required in transient). The steady mode reads strain_rate_damping only; a steady scene may leave out dt and t_end.",
        fields: &const { [
            opt("integrator", Kind::Keyword(IntegratorName::NAMES), NONE, "time integrator"),
            opt("rho_inf", Kind::Float, NONE,
                "spectral radius at infinity of generalized_alpha, in [0, 1], or of hht_alpha, in [0.5, 1] (1: no numerical dissipation)"),
            req("dt", Kind::Float, "T", "initial time step, > 0, <= t_end (a steady scene may leave it out)"),
            opt("dt_min", Kind::Float, "T", "smallest step, > 0, <= dt (default dt · 1e-4)"),
            opt("dt_max", Kind::Float, "T", "largest step, >= dt (default dt · 10)"),
            req("t_end", Kind::Float, "T", "maximum simulated time, > 0 (a steady scene may leave it out)"),
            opt("adaptive", Kind::Bool, NONE, "step-size control from a local error estimate"),
            opt("error_tol", Kind::Float, NONE, "relative local error tolerance of the step-size control, > 0"),
            opt("steady_tol", Kind::Float, NONE,
                "relative change over one node passage below which rolling is steady, > 0"),
            opt("stop_at_steady", Kind::Bool, NONE, "stop as soon as rolling is steady"),
            opt("mass", Kind::Keyword(MassKind::NAMES), NONE,
                "mass matrix (central_difference: always lumped)"),
            opt("max_steps", Kind::UInt, NONE, "maximum number of time steps, >= 1"),
            opt("strain_rate_damping", Kind::Float, "F·T/L²",
                "viscous damping η on the Green strain rate, S_v = η Ė, >= 0"),
        ] },
    },
    SectionSchema {
        name: "continuation",
        required: false,
        doc: "Arc-length continuation of the steady solution (steady mode); arc lengths in scaled units.",
        fields: &const { [
            opt("parameter", Kind::Keyword(ContinuationParameter::NAMES), NONE, "continuation parameter"),
            req("target", Kind::Float, "rad/T, F/L, L, – or deg",
                "final parameter value (omega, load, disp, creep, slip_angle or camber; in three dimensions the load is a total force)"),
            opt("ds", Kind::Float, NONE, "initial arc length (scaled), > 0"),
            opt("ds_max", Kind::Float, NONE, "largest arc length (scaled), >= ds"),
            opt("max_steps", Kind::UInt, NONE, "maximum number of continuation steps, >= 1"),
            opt("desired_iterations", Kind::UInt, NONE,
                "corrector iterations aimed at by the step-size control, >= 1"),
            opt("switch_branch", Kind::Bool, NONE,
                "leave the branch at the first bifurcation detected (det K or inertia change without a turning point), along the null mode of the tangent with its part along the branch removed; the first point of the new branch has kind 4 in branch.csv"),
            opt("on_limit", Kind::Keyword(LimitAction::NAMES), NONE,
                "at a limit point that turns the branch back before the target: follow it back, or jump past it (a direct steady solve at the limit's parameter + jump · |target − start|, retried at 2× and 4× that distance) and continue from the sheet it lands on; the first point after a jump has kind 5 in branch.csv"),
            opt("jump", Kind::Float, NONE, "distance of the jump past a limit point, as a fraction of |target − start|, in (0, 1]"),
        ] },
    },
    SectionSchema {
        name: "solver",
        required: false,
        doc: "Newton with load stepping and cut-backs (in transient: the Newton iterations of each implicit step).",
        fields: &const { [
            opt("tolerance", Kind::Float, NONE, "relative residual tolerance, in (0, 1)"),
            opt("max_iterations", Kind::UInt, NONE, "Newton iterations per load step, >= 1"),
            opt("load_steps", Kind::UInt, NONE, "initial number of load steps, >= 1"),
            opt("max_cutbacks", Kind::UInt, NONE, "how many times a failed step may be halved (<= 200)"),
            opt("linear", Kind::Keyword(LinearChoice::NAMES), NONE, "sparse linear solver"),
            opt("threads", Kind::UInt, NONE, "worker threads; 0 = all cores"),
            opt("line_search", Kind::Bool, NONE, "backtracking line search on the residual norm"),
            opt("damping_tangent", Kind::Keyword(DampingTangentChoice::NAMES), NONE,
                "plane-strain steady mode with time.strain_rate_damping (the three-dimensional steady mode assembles the damping whole): Newton matrix of the damping (auto: matrix-free with GMRES for a solve below 60,000 equations, banded from there on ring meshes, assembled for continuation; banded needs node rings, a generated annulus, and is replaced by matrix-free with a warning on other meshes)"),
            opt("damping_cell_weight", Kind::Float, NONE,
                "steady mode with time.strain_rate_damping and the matrix-free (or auto below 60,000 equations) damping tangent: weight in (0, 1] of each cell's own theta-derivative in the assembled part of the Newton matrix, which preconditions GMRES; the Newton step is exact whatever the weight, only the GMRES products change (default 0.4: 24-28 % fewer than with 1 on the default scene from 16k to 262k DOFs, and no GMRES stall where 1 and 0.7 stall at eta omega / G = 30 %)"),
            opt("eps_continuation", Kind::Bool, NONE,
                "steady mode with friction: reach a regularisation eps < 1e-2 v_ref (v_ref = max(|v0|, |omega| Ro)) by pressing in at 1e-2 v_ref and walking eps down geometrically; false: press in at the scene's eps directly"),
            opt("coarse_start", Kind::Bool, NONE,
                "steady mode on a generated annulus (n_r even >= 4, n_theta a multiple of 4 >= 64, no cell pressures): start Newton from the steady state on the mesh with half the cells in r and theta (solved the same way), interpolated; falls back to the press-in from the undeformed state if Newton fails from it. Three dimensions: a generated revolved mesh with n_theta a multiple of 4 >= 64, the coarse mesh with half the cells in theta and in r and z where even. false: always press in from the undeformed state"),
            opt("single_precision", Kind::Bool, NONE,
                "Newton solves with the sparse LU (linear = auto or lu; steady, transient and static modes): factorize the assembled tangent in single precision and refine each Newton step by GMRES to the accuracy of a direct solve (relative residual 1e-10), keeping the factors from one iteration to the next while they reach it in a few products; a preconditioner that does not is replaced by fresh, then double-precision factors. The Newton steps and iterations are those of double precision; the factors take half the memory (steady undamped default scene at 262k DOFs: 615 MB instead of 767 MB peak). With time.strain_rate_damping the steady damping tangent's GMRES uses these factors as its preconditioner. false: double-precision factors throughout (one factorization and direct solve per Newton iteration where the tangent is assembled whole, double-precision preconditioner factors for the damping tangent's GMRES)"),
            opt("steady_history", Kind::Keyword(SteadyHistoryChoice::NAMES), NONE,
                "steady mode with [material.viscoelastic]: how the internal variables are integrated along the streamlines (rings: exact along closed rings of quadrature points, generated annulus only; upwind: upwind discontinuous Galerkin on the quadrature points, any mesh; auto: rings when the mesh has them, upwind otherwise)"),
        ] },
    },
    SectionSchema {
        name: "output",
        required: false,
        doc: "Which sinks record the run and how often.",
        fields: &const { [
            opt("sinks", Kind::KeywordList(Sink::NAMES), NONE,
                "output sinks; summary.json is written whether listed or not"),
            opt("every", Kind::UInt, NONE,
                "steps between recorded fields, >= 1 (the final step is always recorded)"),
            opt("vtu_format", Kind::Keyword(VtuFormat::NAMES), NONE, "encoding of the .vtu files"),
            opt("vtu_compression", Kind::Keyword(VtuCompression::NAMES), NONE, "compression of the binary .vtu data (binary only)"),
            opt("displacement_scale", Kind::Float, NONE, "magnification of the displacement in the Rerun view of the body and in the shape pictures (> 0; the numbers are unchanged)"),
            opt("snapshot_omegas", Kind::FloatList, "rad/T",
                "steady mode with a continuation in omega and the png sink: speeds (rad/s, at most 12) at which to draw the deformed shape with von Mises stress contours; the branch point nearest to each is drawn to shape_omega_<omega>.png, all of them to shape_montage.png"),
        ] },
    },
]
});

pub(super) fn section_schema(name: &str) -> Option<&'static SectionSchema> {
    SCHEMA.iter().find(|s| s.name == name)
}

impl SectionSchema {
    pub(super) fn field(&self, key: &str) -> Option<&'static FieldSchema> {
        self.fields.iter().find(|f| f.key == key)
    }

    pub(super) fn key_list(&self) -> String {
        self.fields
            .iter()
            .map(|f| f.key)
            .collect::<Vec<_>>()
            .join(", ")
    }
}

pub(super) fn section_list() -> String {
    SCHEMA
        .iter()
        .map(|s| format!("[{}]", s.name))
        .collect::<Vec<_>>()
        .join(", ")
}

pub(super) fn describe_value(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => format!("string \"{s}\""),
        toml::Value::Integer(i) => format!("integer {i}"),
        toml::Value::Float(f) => format!("float {f}"),
        toml::Value::Boolean(b) => format!("boolean {b}"),
        toml::Value::Datetime(d) => format!("datetime {d}"),
        toml::Value::Array(_) => "an array".to_string(),
        toml::Value::Table(_) => "a table".to_string(),
    }
}

/// Smallest non-zero magnitude of a scene number: products of a handful of scene values (areas,
/// moduli times lengths, ...) stay well inside double precision, and subnormals never reach the
/// computation.
pub const MIN_MAGNITUDE: f64 = 1e-60;
/// Largest magnitude of a scene number (see [`MIN_MAGNITUDE`]).
pub const MAX_MAGNITUDE: f64 = 1e60;

pub(super) fn check_kind(kind: Kind, v: &toml::Value) -> Result<(), String> {
    let ok = match (kind, v) {
        (Kind::Float, toml::Value::Float(f)) => {
            let magnitude_ok = *f == 0.0 || (MIN_MAGNITUDE..=MAX_MAGNITUDE).contains(&f.abs());
            if f.is_finite() && magnitude_ok {
                true
            } else if f.is_finite() {
                return Err(format!(
                    "{} is outside the magnitudes a scene value may have, [{MIN_MAGNITUDE:e}, \
                     {MAX_MAGNITUDE:e}] (or 0): products of such values under- or overflow in \
                     double precision; choose units in which it is not",
                    describe_value(v)
                ));
            } else {
                return Err(format!(
                    "expected a finite number, found {}",
                    describe_value(v)
                ));
            }
        }
        (Kind::Float, toml::Value::Integer(_)) => true,
        (Kind::UInt, toml::Value::Integer(i)) => {
            if *i >= 0 {
                true
            } else {
                return Err(format!(
                    "expected a non-negative integer, found {}",
                    describe_value(v)
                ));
            }
        }
        (Kind::Bool, toml::Value::Boolean(_)) => true,
        (Kind::Table(_), toml::Value::Table(_)) => true,
        (Kind::FloatPairs, toml::Value::Array(items)) => {
            for item in items {
                let pair = item.as_array().filter(|a| a.len() == 2).and_then(|a| {
                    let num = |v: &toml::Value| v.as_float().or(v.as_integer().map(|i| i as f64));
                    Some((num(&a[0])?, num(&a[1])?))
                });
                match pair {
                    Some((a, b)) if a.is_finite() && b.is_finite() => {}
                    _ => {
                        return Err(format!(
                            "expected an array of [number, number] pairs, found an entry {}",
                            describe_value(item)
                        ))
                    }
                }
            }
            true
        }
        (Kind::FloatList, toml::Value::Array(items)) => {
            for item in items {
                match item.as_float().or(item.as_integer().map(|i| i as f64)) {
                    Some(x) if x.is_finite() => {}
                    _ => {
                        return Err(format!(
                            "expected an array of finite numbers, found an entry {}",
                            describe_value(item)
                        ))
                    }
                }
            }
            true
        }
        (Kind::Str, toml::Value::String(_)) => true,
        (Kind::Keyword(names), toml::Value::String(s)) => {
            if names.contains(&s.as_str()) {
                true
            } else {
                return Err(format!(
                    "unknown value \"{s}\"; expected one of {}",
                    quoted_list(names)
                ));
            }
        }
        (Kind::KeywordList(names), toml::Value::Array(items)) => {
            let mut seen = BTreeSet::new();
            for item in items {
                let Some(s) = item.as_str() else {
                    return Err(format!(
                        "expected an array of strings, one or more of {}; found {}",
                        quoted_list(names),
                        describe_value(item)
                    ));
                };
                if !names.contains(&s) {
                    return Err(format!(
                        "unknown value \"{s}\"; expected any of {}",
                        quoted_list(names)
                    ));
                }
                if !seen.insert(s) {
                    return Err(format!("\"{s}\" is listed twice"));
                }
            }
            true
        }
        _ => false,
    };
    if ok {
        Ok(())
    } else {
        let expected = match kind {
            Kind::Float => "a number".to_string(),
            Kind::UInt => "a non-negative integer".to_string(),
            Kind::Bool => "a boolean (true or false)".to_string(),
            Kind::Str => "a string".to_string(),
            Kind::Table(_) => "a table".to_string(),
            Kind::FloatPairs => "an array of [number, number] pairs".to_string(),
            Kind::FloatList => "an array of numbers".to_string(),
            Kind::Keyword(names) => format!("a string, one of {}", quoted_list(names)),
            Kind::KeywordList(names) => {
                format!("an array of strings from {}", quoted_list(names))
            }
        };
        Err(format!("expected {expected}, found {}", describe_value(v)))
    }
}

// ---------------------------------------------------------------------------------------------
// Defaults, read from the serde structs
// ---------------------------------------------------------------------------------------------

/// A value of the right kind for a required key (only used to read the defaults of the others).
fn placeholder(kind: Kind) -> toml::Value {
    match kind {
        Kind::Float => toml::Value::Float(1.0),
        Kind::UInt => toml::Value::Integer(1),
        Kind::Bool => toml::Value::Boolean(true),
        Kind::Str => toml::Value::String("x".into()),
        Kind::Keyword(names) => toml::Value::String(names.first().copied().unwrap_or("").into()),
        Kind::KeywordList(_) | Kind::FloatList => toml::Value::Array(Vec::new()),
        Kind::Table(sub) => toml::Value::Table(
            sub.iter()
                .filter(|f| f.required)
                .map(|f| (f.key.to_string(), placeholder(f.kind)))
                .collect(),
        ),
        Kind::FloatPairs => toml::Value::Array(vec![toml::Value::Array(vec![
            toml::Value::Float(1.0),
            toml::Value::Float(1.0),
        ])]),
    }
}

fn round_trip<T: DeserializeOwned + Serialize>(t: toml::Table) -> Option<toml::Table> {
    let typed: T = toml::Value::Table(t).try_into().ok()?;
    toml::Table::try_from(&typed).ok()
}

/// The defaults of a section's optional keys as loading fills them: the section's serde struct
/// deserialised from its required keys alone and written back. Keys whose default follows other
/// keys (e.g. `time.dt_min`) or the model are absent; their `doc` says what they default to.
pub(super) fn section_defaults(sec: &SectionSchema) -> toml::Table {
    let given: toml::Table = sec
        .fields
        .iter()
        .filter(|f| f.required)
        .map(|f| (f.key.to_string(), placeholder(f.kind)))
        .collect();
    let full = match sec.name {
        "scene" => round_trip::<SceneInfo>(given),
        "geometry" => round_trip::<Geometry>(given),
        "mesh" => round_trip::<MeshSpec>(given),
        "material" => round_trip::<MaterialSpec>(given),
        "analysis" => round_trip::<Analysis>(given),
        "motion" => round_trip::<Motion>(given),
        "road" => round_trip::<RoadSpec>(given),
        "contact" => round_trip::<ContactSpec>(given),
        "friction" => round_trip::<FrictionSpec>(given),
        "stick_slip" => round_trip::<StickSlipSpec>(given),
        "time" => round_trip::<TimeSpec>(given),
        "continuation" => round_trip::<ContinuationSpec>(given),
        "solver" => round_trip::<SolverSpec>(given),
        "output" => round_trip::<OutputSpec>(given),
        _ => None,
    };
    let mut full = full.unwrap_or_default();
    for f in sec.fields.iter().filter(|f| f.required) {
        full.remove(f.key);
    }
    full
}

// ---------------------------------------------------------------------------------------------
// JSON Schema (draft 2020-12) for editors
// ---------------------------------------------------------------------------------------------

/// The loader's bounds of the integer keys that have more than `>= 0`: (minimum, maximum).
fn uint_bounds(key: &str) -> (u64, Option<u64>) {
    match key {
        "n_r" | "n_z" | "max_iterations" | "load_steps" => (1, None),
        "dimension" => (2, Some(3)),
        "n_theta" => (8, None),
        "order" => (1, Some(2)),
        "max_cutbacks" => (0, Some(super::solver::MAX_CUTBACKS as u64)),
        _ => (0, None),
    }
}

fn field_json(f: &FieldSchema, default: Option<&toml::Value>) -> Value {
    let mut o = match f.kind {
        Kind::Float => json!({ "type": "number" }),
        Kind::UInt => {
            let (min, max) = uint_bounds(f.key);
            let mut o = json!({ "type": "integer", "minimum": min });
            if let (Some(max), Value::Object(m)) = (max, &mut o) {
                m.insert("maximum".into(), json!(max));
            }
            o
        }
        Kind::Bool => json!({ "type": "boolean" }),
        Kind::Str => json!({ "type": "string" }),
        Kind::Keyword(names) => json!({ "type": "string", "enum": names }),
        Kind::KeywordList(names) => json!({
            "type": "array",
            "items": { "type": "string", "enum": names },
            "uniqueItems": true
        }),
        Kind::Table(sub) => object_json(sub, &toml::Table::new(), None, false),
        Kind::FloatList => json!({ "type": "array", "items": { "type": "number" } }),
        Kind::FloatPairs => json!({
            "type": "array",
            "items": {
                "type": "array",
                "prefixItems": [{ "type": "number" }, { "type": "number" }],
                "minItems": 2,
                "maxItems": 2
            }
        }),
    };
    let description = if f.unit == NONE {
        f.doc.to_string()
    } else {
        format!("{} [{}]", f.doc, f.unit)
    };
    if let Value::Object(m) = &mut o {
        m.insert("description".into(), Value::String(description));
        if let Some(d) = default.and_then(|d| serde_json::to_value(d).ok()) {
            m.insert("default".into(), d);
        }
    }
    o
}

/// `steady_optional`: the `[time]` keys a steady scene may leave out are not listed as required
/// (the schema's top-level rule requires them for the other modes).
fn object_json(
    fields: &[FieldSchema],
    defaults: &toml::Table,
    extra: Option<(&str, Value)>,
    steady_optional: bool,
) -> Value {
    let mut props = Map::new();
    let mut required: Vec<&str> = Vec::new();
    if let Some((k, v)) = &extra {
        props.insert((*k).to_string(), v.clone());
        required.push(k);
    }
    for f in fields {
        props.insert(f.key.to_string(), field_json(f, defaults.get(f.key)));
        if f.required && !(steady_optional && STEADY_UNUSED_TIME.contains(&f.key)) {
            required.push(f.key);
        }
    }
    json!({
        "type": "object",
        "additionalProperties": false,
        "properties": props,
        "required": required
    })
}

/// The JSON Schema (draft 2020-12) of scene files, for editors (e.g. taplo / Even Better TOML:
/// `#:schema ./scene.schema.json` on the first line of a scene, or a `[[schema]]` rule in
/// `.taplo.toml`). It checks sections, keys, types and allowed values; ranges and the rules
/// between keys are checked by `tread check`.
pub fn json_schema() -> Value {
    let mut props = Map::new();
    let mut required = Vec::new();
    for sec in SCHEMA.iter() {
        let defaults = section_defaults(sec);
        let mut obj = object_json(sec.fields, &defaults, None, sec.name == "time");
        if sec.name == "material" {
            let region = json!({
                "type": "string",
                "description": "name of a 2D physical group of mesh.file"
            });
            let per_region = object_json(sec.fields, &defaults, Some(("region", region)), false);
            obj = json!({
                "oneOf": [
                    obj,
                    { "type": "array", "minItems": 1, "items": per_region }
                ]
            });
        }
        if let Value::Object(m) = &mut obj {
            m.insert("description".into(), Value::String(sec.doc.to_string()));
        }
        props.insert(sec.name.to_string(), obj);
        if sec.required {
            required.push(sec.name);
        }
    }
    json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": "tread scene",
        "description": "A scene file of tread (plane-strain rolling contact). Generated by `tread schema`.",
        "type": "object",
        "additionalProperties": false,
        "properties": props,
        "required": required,
        // The transient keys of [time] are required unless the scene is steady (which may
        // give [time] for strain_rate_damping alone), as the loader has it.
        "if": {
            "properties": { "analysis": { "properties": { "mode": { "const": "steady" } },
                                          "required": ["mode"] } },
            "required": ["analysis"]
        },
        "else": {
            "properties": { "time": { "required": STEADY_UNUSED_TIME } }
        }
    })
}

// ---------------------------------------------------------------------------------------------
// Markdown key reference
// ---------------------------------------------------------------------------------------------

fn kind_text(kind: Kind) -> String {
    let ticks = |names: &[&str]| {
        names
            .iter()
            .map(|n| format!("`{n}`"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    match kind {
        Kind::Float => "number".into(),
        Kind::UInt => "integer >= 0".into(),
        Kind::Bool => "boolean".into(),
        Kind::Str => "string".into(),
        Kind::Keyword(names) => format!("one of {}", ticks(names)),
        Kind::KeywordList(names) => format!("list from {}", ticks(names)),
        Kind::Table(_) => "table".into(),
        Kind::FloatPairs => "[[number, number], …]".into(),
        Kind::FloatList => "[number, …]".into(),
    }
}

pub(crate) fn cell(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

fn field_rows(prefix: &str, fields: &[FieldSchema], defaults: &toml::Table, out: &mut String) {
    for f in fields {
        let req = if f.required {
            "required".to_string()
        } else {
            match defaults.get(f.key) {
                Some(d) => format!("`{d}`"),
                None => "–".to_string(),
            }
        };
        out.push_str(&format!(
            "| `{prefix}{}` | {} | {} | {} | {} |\n",
            f.key,
            cell(&kind_text(f.kind)),
            cell(&req),
            cell(f.unit),
            cell(f.doc)
        ));
        if let Kind::Table(sub) = f.kind {
            field_rows(
                &format!("{prefix}{}.", f.key),
                sub,
                &toml::Table::new(),
                out,
            );
        }
    }
}

/// The scene-key reference in Markdown: one table per section (key, type, default, unit,
/// meaning), from [`SCHEMA`] and the serde defaults.
pub fn markdown_reference() -> String {
    let mut out = String::new();
    out.push_str(
        "Units: L length, F force, T time, in the scene's consistent system (`[scene] units`, \
         e.g. `in-lbf-s`); forces, torques and energies per unit thickness. A default `–` \
         means none, or one that follows other keys (the meaning says which).\n",
    );
    for sec in SCHEMA.iter() {
        let defaults = section_defaults(sec);
        out.push_str(&format!(
            "\n### `[{}]` ({})\n\n{}\n\n",
            sec.name,
            if sec.required { "required" } else { "optional" },
            sec.doc
        ));
        out.push_str("| key | type | default | unit | meaning |\n|---|---|---|---|---|\n");
        field_rows(&format!("{}.", sec.name), sec.fields, &defaults, &mut out);
        if sec.name == "time" {
            out.push_str("\nThe integrators (`time.integrator`):\n\n");
            for i in IntegratorName::ALL {
                out.push_str(&format!("* `{}`: {}\n", i.as_str(), i.about()));
            }
        }
    }
    out
}

// ---------------------------------------------------------------------------------------------
// Annotated listing (`tread check`)
// ---------------------------------------------------------------------------------------------

/// The field of a dotted table path and key (`["material", "viscoelastic"]`, `"gamma"`).
fn field_at(table: &[String], key: &str) -> Option<&'static FieldSchema> {
    let (first, rest) = table.split_first()?;
    let mut fields: &'static [FieldSchema] = section_schema(first)?.fields;
    for seg in rest {
        match fields.iter().find(|f| f.key == seg.as_str())?.kind {
            Kind::Table(sub) => fields = sub,
            _ => return None,
        }
    }
    fields.iter().find(|f| f.key == key)
}

/// A TOML listing of a scene with each key's unit and meaning from [`SCHEMA`] as a trailing
/// comment (`ri = 0.5  # [L] inner (hub) radius, > 0`). Only lines that hold a whole
/// `key = value` are annotated; the text parses back to the same tables.
pub(super) fn annotate(text: &str) -> String {
    let mut table: Vec<String> = Vec::new();
    let mut out = String::new();
    for line in text.lines() {
        let t = line.trim();
        let header = t
            .strip_prefix("[[")
            .and_then(|h| h.strip_suffix("]]"))
            .or_else(|| t.strip_prefix('[').and_then(|h| h.strip_suffix(']')));
        let mut note = None;
        if let Some(h) = header.filter(|h| !h.contains('"') && !h.contains('=')) {
            table = h.split('.').map(|s| s.trim().to_string()).collect();
        } else if let Some((key, _)) = t.split_once('=') {
            let key = key.trim();
            // Only a complete `key = value` on this line (not the start of a multi-line array).
            if t.parse::<toml::Table>().is_ok_and(|p| p.contains_key(key)) {
                note = field_at(&table, key);
                if key == "region" && table.first().map(String::as_str) == Some("material") {
                    out.push_str(line);
                    out.push_str("  # name of a 2D physical group of mesh.file\n");
                    continue;
                }
            }
        }
        out.push_str(line);
        if let Some(f) = note {
            let unit = if f.unit == NONE {
                String::new()
            } else {
                format!("[{}] ", f.unit)
            };
            let allowed = match f.kind {
                Kind::Keyword(names) | Kind::KeywordList(names) => {
                    format!(" ({})", names.join(" | "))
                }
                _ => String::new(),
            };
            out.push_str(&format!("  # {unit}{}{allowed}", f.doc));
        }
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::scene::tests::*;
    use crate::io::scene::*;
    use std::fmt;
    use std::str::FromStr;

    #[test]
    fn keyword_enums_match_serde_names() {
        fn check<T: Serialize + FromStr + fmt::Display + Copy + PartialEq + fmt::Debug>(
            all: &[T],
            names: &[&str],
        ) {
            assert_eq!(all.len(), names.len());
            for (v, n) in all.iter().zip(names) {
                assert_eq!(serde_json::to_string(v).ok(), Some(format!("\"{n}\"")));
                assert_eq!(v.to_string(), *n);
                assert_eq!(n.parse::<T>().ok(), Some(*v));
            }
        }
        check(Mode::ALL, Mode::NAMES);
        check(MaterialModel::ALL, MaterialModel::NAMES);
        check(Formulation::ALL, Formulation::NAMES);
        check(LinearChoice::ALL, LinearChoice::NAMES);
        check(ContactQuadrature::ALL, ContactQuadrature::NAMES);
        check(FrictionLawName::ALL, FrictionLawName::NAMES);
        check(Sink::ALL, Sink::NAMES);
        assert_eq!("spinning".parse::<Mode>(), Ok(Mode::Spinning));
        assert_eq!("static".parse::<Mode>(), Ok(Mode::Static));
        assert_eq!("stick_slip".parse::<Mode>(), Ok(Mode::StickSlip));
        assert_eq!("transient".parse::<Mode>(), Ok(Mode::Transient));
        assert_eq!("steady".parse::<Mode>(), Ok(Mode::Steady));
        check(ContinuationParameter::ALL, ContinuationParameter::NAMES);
        let err = "dynamic".parse::<Mode>().err().unwrap_or_default();
        assert!(
            err.contains("\"spinning\", \"static\", \"stick_slip\", \"transient\", \"steady\""),
            "{err}"
        );
        check(IntegratorName::ALL, IntegratorName::NAMES);
        check(MassKind::ALL, MassKind::NAMES);
        assert_eq!(IntegratorName::default(), IntegratorName::GeneralizedAlpha);
        assert_eq!(MassKind::default(), MassKind::Consistent);
        assert_eq!(
            IntegratorName::NAMES,
            &[
                "generalized_alpha",
                "central_difference",
                "bdf",
                "sdirk",
                "hht_alpha"
            ]
        );
        assert_eq!(FrictionLawName::default(), FrictionLawName::None);
        assert_eq!(ContactQuadrature::default(), ContactQuadrature::Lobatto);
    }

    #[test]
    fn schema_matches_serde_structs() {
        fn keys<T: Serialize>(v: &T) -> Vec<String> {
            match serde_json::to_value(v) {
                Ok(serde_json::Value::Object(m)) => m.keys().cloned().collect(),
                _ => Vec::new(),
            }
        }
        let full_material = MaterialSpec {
            model: MaterialModel::ALL[0],
            rho: 1.0,
            values: MaterialSpec::all_value_keys()
                .into_iter()
                .map(|k| (k.to_string(), 1.0))
                .collect(),
            formulation: Some(Formulation::Exact),
            viscoelastic: Some(ViscoelasticSpec {
                model: "convolution".into(),
                gamma: 1.0,
                prony: vec![[1.0, 1.0]],
            }),
        };
        let info = SceneInfo {
            name: "a".into(),
            description: String::new(),
            units: String::new(),
        };
        let cases: Vec<(&str, Vec<String>)> = vec![
            ("scene", keys(&info)),
            ("geometry", keys(&Geometry { ri: 1.0, ro: 2.0 })),
            (
                "mesh",
                keys(&MeshSpec {
                    file: Some("m.msh".into()),
                    hub: Some("hub".into()),
                    contact: Some("contact".into()),
                    dimension: 3,
                    width: Some(1.0),
                    n_z: Some(2),
                    crown_radius: Some(1.0),
                    sides: Some(MeshSides::Free),
                    theta_ratio: Some(2.0),
                    grading_z: Some(2.0),
                    ..MeshSpec::default()
                }),
            ),
            ("material", keys(&full_material)),
            (
                "analysis",
                keys(&Analysis {
                    mode: Mode::Spinning,
                }),
            ),
            ("motion", keys(&Motion::default())),
            ("road", keys(&full_road())),
            ("contact", keys(&full_contact())),
            ("friction", keys(&full_friction())),
            ("stick_slip", keys(&full_stick_slip())),
            ("time", keys(&full_time())),
            ("continuation", keys(&ContinuationSpec::default())),
            ("solver", keys(&SolverSpec::default())),
            ("output", keys(&OutputSpec::default())),
        ];
        assert_eq!(cases.len(), SCHEMA.len());
        for (name, mut serde_keys) in cases {
            let sec = section_schema(name).unwrap_or_else(|| panic!("{name}"));
            let mut schema_keys: Vec<String> =
                sec.fields.iter().map(|f| f.key.to_string()).collect();
            serde_keys.sort();
            schema_keys.sort();
            assert_eq!(serde_keys, schema_keys, "section {name}");
        }
    }

    #[test]
    fn schema_required_flags_match_serde() {
        fn check<T: Serialize + DeserializeOwned + fmt::Debug>(name: &str, full: &T) {
            let sec = section_schema(name).unwrap_or_else(|| panic!("{name}"));
            let table = match toml::Value::try_from(full) {
                Ok(toml::Value::Table(t)) => t,
                other => panic!("{name}: {other:?}"),
            };
            for f in sec.fields {
                assert!(table.contains_key(f.key), "{name}.{} not serialized", f.key);
                let mut t = table.clone();
                t.remove(f.key);
                let r = toml::Value::Table(t).try_into::<T>();
                assert_eq!(r.is_err(), f.required, "{name}.{}: {r:?}", f.key);
            }
        }
        check(
            "scene",
            &SceneInfo {
                name: "a".into(),
                description: "d".into(),
                units: "u".into(),
            },
        );
        check("geometry", &Geometry { ri: 1.0, ro: 2.0 });
        check(
            "mesh",
            &MeshSpec {
                file: Some("m.msh".into()),
                hub: Some("hub".into()),
                contact: Some("contact".into()),
                dimension: 3,
                width: Some(1.0),
                n_z: Some(2),
                crown_radius: Some(1.0),
                sides: Some(MeshSides::Free),
                theta_ratio: Some(2.0),
                grading_z: Some(2.0),
                ..MeshSpec::default()
            },
        );
        check(
            "material",
            &MaterialSpec {
                model: MaterialModel::ALL[0],
                rho: 1.0,
                values: MaterialSpec::all_value_keys()
                    .into_iter()
                    .map(|k| (k.to_string(), 1.0))
                    .collect(),
                formulation: Some(Formulation::Exact),
                viscoelastic: Some(ViscoelasticSpec {
                    model: "multiplicative".into(),
                    gamma: 2.0,
                    prony: vec![[0.5, 0.1], [0.5, 1.0]],
                }),
            },
        );
        check("analysis", &Analysis { mode: Mode::Static });
        check("motion", &Motion::default());
        check("road", &full_road());
        check("contact", &full_contact());
        check("friction", &full_friction());
        check("stick_slip", &full_stick_slip());
        check("time", &full_time());
        check("solver", &SolverSpec::default());
        check("output", &OutputSpec::default());
    }

    #[test]
    fn annotated_listing_round_trips_and_names_units() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
        let mut n = 0;
        for entry in std::fs::read_dir(&dir).expect("scenarios/") {
            let path = entry.expect("entry").path();
            let text = std::fs::read_to_string(&path).unwrap_or_default();
            if path.extension().and_then(|e| e.to_str()) != Some("toml") || text.contains("[sweep]")
            {
                continue;
            }
            let s = Scene::from_path(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
            let out = s.to_annotated_toml_string();
            // (A scene with `mesh.file` does not parse back: the listing writes the generator's
            // keys too, which a file mesh refuses; the plain listing does the same.)
            if s.mesh.file.is_none() {
                let back = Scene::from_toml_str(&out, "annotated", &[])
                    .unwrap_or_else(|e| panic!("{e}\n{out}"));
                assert_eq!(back, s, "{out}");
            }
            // Every one-line `key = value` carries its comment.
            for line in out.lines() {
                let t = line.trim();
                if t.contains(" = ") && !t.ends_with('[') && !t.starts_with('"') {
                    assert!(
                        t.contains("  # "),
                        "{}: no annotation on `{t}`",
                        path.display()
                    );
                }
            }
            n += 1;
        }
        assert!(n >= 20);
        let s = load(MINIMAL).unwrap_or_else(|e| panic!("{e}"));
        let out = s.to_annotated_toml_string();
        assert!(out.contains("ri = 1.0  # [L] inner (hub) radius"), "{out}");
        assert!(out.contains("rho = 0.027  # [F·T²/L⁴]"), "{out}");
    }
}
