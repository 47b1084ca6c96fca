//! Scene files: the TOML description of one run.
//!
//! A scene describes a plane-strain hollow cylinder `ri <= |X| <= ro` bonded to a rigid hub at
//! `|X| = ri`, its mesh, its material, what to compute and how to solve it. Units are whatever the
//! scene uses consistently (the paper's case: inch, psi, lbf·s²/in⁴, rad/s); `[scene] units` only
//! records which. Forces are per unit thickness.
//!
//! The schema, key by key, is documented in `scenarios/README.md`. In short:
//!
//! ```toml
//! [scene]     name, description = "", units = "in-lbf-s"
//! [geometry]  ri, ro
//! [mesh]      n_r = 4, n_theta = 32, order = 2, grading_r = 1.0, grading_theta = 0.0
//!             | file = "tyre.msh", hub = "hub", contact = "contact"   (a Gmsh .msh 4.1 mesh)
//! [material]  model = "neo_hookean" | "mooney_rivlin" | "mooney_rivlin_incompressible", rho,
//!             mu, lambda | c1, c2, kappa | c1, c2, formulation = "exact" | "perturbed", kappa
//! [material.viscoelastic]  model = "convolution" | "multiplicative", gamma, prony = [[g, tau], ...]
//!             (optional: a Prony-series overstress on the elastic law; `gamma` in stress
//!             units, `g` dimensionless, `tau` in time units; see `material::viscoelastic`)
//! [[material]] region = "<2D physical group of mesh.file>", then the keys of [material]
//!             (one per region; instead of a single [material])
//! [analysis]  mode = "spinning" | "static" | "stick_slip" | "transient"
//! [motion]    omega, ramp = 0                                 (spinning, transient)
//!             control = "speed" | "torque", hub_inertia, torque = 0   (transient)
//!             control = "speed" | "torque" | "free_rolling" | "creep", torque, creep (steady)
//! [road]      disp | load, v0 = 0, ramp = 0, v0_ramp = motion.ramp   (static, transient)
//! [contact]   c_n, m_n = 1, b_n = 0, l_n = 0, quadrature = "lobatto", points = 4
//!                                                             (static, transient)
//! [friction]  law = "none" | "coulomb_tanh" | "coulomb_linear" | "rate_dependent" | "oden_martins",
//!             mu, eps | mu_s, mu_k, v_s, eps | c_t, m_t, eps  (static, stick_slip, transient)
//! [stick_slip] mass, stiffness, normal_force, belt_speed, t_end, rtol = 1e-8, atol = 1e-10,
//!             x0 = 0, v0, output_interval                     (stick_slip)
//! [time]      integrator = "generalized_alpha" | "central_difference" | "bdf" | "sdirk",
//!             rho_inf = 0.8, dt, dt_min = dt·1e-4, dt_max = dt·10, t_end, adaptive = true,
//!             error_tol = 1e-4, steady_tol = 1e-4, stop_at_steady = true,
//!             mass = "consistent" | "lumped", max_steps = 200000  (transient)
//! [solver]    tolerance = 1e-10, max_iterations = 25, load_steps = 4, max_cutbacks = 10,
//!             linear = "auto", threads = 0, line_search = true
//! [output]    sinks = ["summary", "csv", "vtu", "png"], every = 1, vtu_format = "binary" | "ascii",
//!             vtu_compression = "none" | "zlib" (binary only),
//!             displacement_scale = 1 (magnification of the body in the Rerun view)
//!             (sinks from "summary", "csv", "vtu", "mcap", "rerun", "png")
//! ```
//!
//! # Loading
//!
//! [`Scene::from_toml_str`] parses the text, applies `--set section.key=value` overrides, fills the
//! defaults, resolves model-dependent defaults (the incompressible formulation and, for the
//! perturbed Lagrangian, `kappa = 1e4 (c1 + c2)`; `time.mass = "lumped"` for the
//! `central_difference` integrator) and validates. It collects **all** problems it can
//! find (unknown sections and keys, wrong types, missing required keys, out-of-range values, keys
//! that do not belong to the chosen material model) and returns them together as [`SceneErrors`],
//! each naming the dotted key (`geometry.ri`) and the line of the original file where the key (or,
//! for a missing key, its section header) is written. A value that came from an override is reported
//! as `(--set)` instead of a line. Only a TOML syntax error stops early (nothing else can be checked
//! then); it carries toml's own line.
//!
//! Pipeline: (1) `toml` parses the original text into a table (syntax errors, with toml's span);
//! (2) overrides are applied to that table; (3) a schema pass checks every section and key
//! (known? right type? required ones present?), collecting every problem and dropping the
//! offending entries; (4) each section is deserialized with serde (`deny_unknown_fields`
//! everywhere, so the typed structs are strict on their own too, e.g. for
//! `toml::from_str::<Scene>`); (5) the typed sections are validated (ranges and cross-key rules).
//! Line numbers come from a small locator that walks the original text tracking `[table]` headers
//! (comments, quoted keys, dotted keys and multi-line strings/arrays are handled), so a key that was
//! *not* overridden always reports its line in the file.
//!
//! Which sections a mode uses: `spinning` uses `[motion]`; `static` requires `[road]` and
//! `[contact]` and may have `[friction]`; `stick_slip` requires `[stick_slip]` and a `[friction]`
//! law of `coulomb_tanh`, `coulomb_linear` or `rate_dependent`; `transient` requires `[time]` and
//! `motion.omega`, and may have `[road]` with `[contact]` (both or neither; without them the
//! cylinder spins up in time without contact) and, only with contact, `[friction]`. A section (or a
//! non-zero `motion.omega`, `motion.ramp`, `road.v0`, `road.ramp`, `road.v0_ramp`, `contact.b_n`,
//! or a friction law other than `none`) that the mode does not use is an error rather than being
//! silently ignored. `[geometry]` and `[material]` are required in every mode; a `stick_slip`
//! scene carries nominal values that the mode does not use. A `transient` scene that stops at the
//! steady state (`time.stop_at_steady`) needs a mesh uniform in θ (`mesh.grading_theta = 0`): the
//! steady-state extraction re-indexes nodes by whole nodal angle steps.
//!
//! # Time (transient mode)
//!
//! Time starts at `t = 0` with the cylinder at rest, undeformed, and the road (if any) at first
//! touch (`H = Ro`). The hub angular speed, the road penetration (or load) and the road speed are
//! brought in by C² ramps `f(t) = S(t / ramp)` with the quintic smoothstep
//! `S(s) = 6s⁵ − 15s⁴ + 10s³` on `[0, 1]` (`S = 0` before, `1` after; `S′ = S″ = 0` at both
//! ends; a zero ramp applies the full value at once): `ω(t) = omega·S(t / motion.ramp)`,
//! `DISP(t) = disp·S(t / road.ramp)` (or the load), `v0(t) = v0·S(t / road.v0_ramp)`. See
//! [`smoothstep`], [`Motion::omega_at`], [`Motion::angle_at`], [`RoadSpec::ramp_factor`] and
//! [`RoadSpec::v0_at`]. The run stops at `time.t_end`, after `time.max_steps` steps, or, with
//! `time.stop_at_steady`, once rolling is steady: the referential field, the hub forces and the
//! torque change by less than `steady_tol` (relative) over one node passage. In `transient`,
//! `[solver]` drives the Newton iterations of each implicit time step (`tolerance`,
//! `max_iterations`, `linear`, `threads`, `line_search`); a step whose Newton iteration fails is
//! retried with half the step, at most `max_cutbacks` times and not below `time.dt_min`;
//! `load_steps` is not used (the ramps apply the loads in time).
//!
//! # Contact and friction conventions
//!
//! The road is the line `x2 = −H`; penetration `δ = (−H − x2)_+`; normal traction (per unit
//! *reference* length of the outer boundary) `t_n = c_n δ^m_n + b_n δ^l_n δ̇`, `δ̇ = −ẋ2`, clamped
//! at `t_n >= 0`, pushing the body in +x2. Slip velocity of the body against the road
//! `w = ẋ1 − v0`; tangential traction `t_T = −μ(|w|) t_n φ_ε(w)` with `φ_ε(w) = tanh(w/ε)` or
//! `clamp(w/ε, −1, 1)`. In a static analysis there is no time: `w = dx1/dτ` in the pseudo-time
//! `τ ∈ [0, 1]` of the load stepping, so `eps` (and `v_s`) are then slip *lengths* over the whole
//! loading.
//!
//! [`Scene::to_toml_string`] writes the resolved scene (every default filled), which parses back
//! to the same [`Scene`]; `tread check` prints it. Optional keys whose defaults follow other keys
//! (`time.dt_min`, `time.dt_max`, `road.v0_ramp`, `stick_slip.v0`, `stick_slip.output_interval`)
//! stay unset when not given; methods give the values (`resolved_*`, `initial_velocity`).

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;
use std::fmt;
use std::path::Path;
use std::str::FromStr;

/// Default of `[scene] units` (informational only).
pub const DEFAULT_UNITS: &str = "in-lbf-s";
/// `kappa = PERTURBED_KAPPA_FACTOR * (c1 + c2)` when the perturbed incompressible formulation is
/// chosen without an explicit `kappa`.
pub const PERTURBED_KAPPA_FACTOR: f64 = 1.0e4;
/// Smallest allowed `mesh.n_theta`.
pub const MIN_N_THETA: usize = 8;

// ---------------------------------------------------------------------------------------------
// Keyword enums
// ---------------------------------------------------------------------------------------------

macro_rules! keyword_enum {
    (
        $(#[$meta:meta])*
        $name:ident, $what:literal {
            $( $(#[$vmeta:meta])* $variant:ident => $text:literal ),+ $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
        #[serde(rename_all = "snake_case")]
        pub enum $name {
            $( $(#[$vmeta])* $variant ),+
        }

        impl $name {
            /// Every variant, in declaration order.
            pub const ALL: &'static [$name] = &[$($name::$variant),+];
            /// The spelling of every variant in a scene file, in declaration order.
            pub const NAMES: &'static [&'static str] = &[$($text),+];

            /// The spelling of this variant in a scene file.
            pub fn as_str(self) -> &'static str {
                match self {
                    $($name::$variant => $text),+
                }
            }
        }

        impl fmt::Display for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(self.as_str())
            }
        }

        impl FromStr for $name {
            type Err = String;

            fn from_str(s: &str) -> Result<Self, String> {
                match s.trim() {
                    $($text => Ok($name::$variant),)+
                    other => Err(format!(
                        "unknown {} \"{}\"; expected one of {}",
                        $what,
                        other,
                        quoted_list(Self::NAMES)
                    )),
                }
            }
        }
    };
}

keyword_enum! {
    /// What to compute (`[analysis] mode`). `steady` will be added as a further variant.
    Mode, "analysis mode" {
        /// Steady spinning about the hub at `[motion] omega`, no contact: the centrifugal load
        /// `ρ ω² X` is ramped in `load_steps` steps of ω².
        Spinning => "spinning",
        /// Quasi-static indentation of the (non-spinning) cylinder onto the road (`[road]`,
        /// `[contact]`, optional `[friction]`), by load stepping in a pseudo-time τ ∈ [0, 1].
        Static => "static",
        /// The classical one-degree-of-freedom stick-slip oscillator (a mass on a spring, pressed
        /// onto a moving belt): `[stick_slip]` and `[friction]`; no finite elements.
        StickSlip => "stick_slip",
        /// The dynamic Lagrangian model (material mesh rotating with the body) integrated in time
        /// (`[time]`) until rolling is steady: the hub spins up to `[motion] omega`; with `[road]`
        /// and `[contact]` (optional, both or neither) the road rises and moves at `v0`, and
        /// `[friction]` may act. Without them: a cylinder spinning up in time, no contact.
        Transient => "transient",
        /// Steady rolling solved directly in the θ-referential (Eulerian/ALE) description: the
        /// same scene as `transient` (`[road]` and `[contact]` optional, both or neither; the
        /// ramps and `[time]` are ignored), at `[motion] omega` and `road.v0`, optionally
        /// followed by arc-length continuation (`[continuation]`).
        Steady => "steady",
    }
}

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
    }
}

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

keyword_enum! {
    /// Friction law (`[friction] law`).
    #[derive(Default)]
    FrictionLawName, "friction law" {
        #[default]
        /// No friction (frictionless contact).
        None => "none",
        /// Coulomb, `t_T = −μ t_n tanh(w/ε)`.
        CoulombTanh => "coulomb_tanh",
        /// Coulomb, `t_T = −μ t_n clamp(w/ε, −1, 1)`.
        CoulombLinear => "coulomb_linear",
        /// `μ(|w|) = μ_k + (μ_s − μ_k) exp(−|w|/v_s)`, `t_T = −μ(|w|) t_n tanh(w/ε)`.
        RateDependent => "rate_dependent",
        /// Oden–Martins normal-compliance friction, `t_T = −c_t δ^m_t tanh(w/ε)`.
        OdenMartins => "oden_martins",
    }
}

keyword_enum! {
    /// Hyperelastic model (`[material] model`).
    MaterialModel, "material model" {
        /// Compressible neo-Hookean with Lamé constants `mu`, `lambda`.
        NeoHookean => "neo_hookean",
        /// Compressible Mooney–Rivlin `c1 (Ī1 − 3) + c2 (Ī2 − 3) + U(J)` with bulk modulus `kappa`.
        MooneyRivlin => "mooney_rivlin",
        /// Incompressible Mooney–Rivlin `c1 (I1 − 3) + c2 (I2 − 3)`, J = 1 by a Q2/P1 pressure.
        MooneyRivlinIncompressible => "mooney_rivlin_incompressible",
    }
}

keyword_enum! {
    /// Encoding of the `.vtu` files (`[output] vtu_format`).
    #[derive(Default)]
    VtuFormat, "VTU format" {
        #[default]
        /// Raw little-endian binary in an appended block (`header_type="UInt64"`).
        Binary => "binary",
        /// Text (larger and slower; readable in an editor).
        Ascii => "ascii",
    }
}

keyword_enum! {
    /// Compression of the binary `.vtu` data (`[output] vtu_compression`).
    #[derive(Default)]
    VtuCompression, "VTU compression" {
        #[default]
        /// Raw bytes.
        None => "none",
        /// zlib (deflate) blocks of 32 KiB (`compressor="vtkZLibDataCompressor"`).
        Zlib => "zlib",
    }
}

keyword_enum! {
    /// How the incompressibility constraint is imposed (`[material] formulation`).
    #[derive(Default)]
    Formulation, "formulation" {
        #[default]
        /// Exact saddle point (displacement + discontinuous P1 pressure, LU).
        Exact => "exact",
        /// Perturbed Lagrangian with bulk modulus `kappa`, pressure condensed per element.
        Perturbed => "perturbed",
    }
}

keyword_enum! {
    /// Sparse linear solver (`[solver] linear`).
    #[derive(Default)]
    LinearChoice, "linear solver" {
        #[default]
        /// Cholesky when the tangent is symmetric positive definite, LU otherwise.
        Auto => "auto",
        /// Sparse Cholesky (symmetric positive definite tangents only).
        Cholesky => "cholesky",
        /// Sparse LU.
        Lu => "lu",
    }
}

keyword_enum! {
    /// An output sink (`[output] sinks`); see `src/io/record/mod.rs` and README.md (Outputs).
    Sink, "output sink" {
        /// `summary.json` (always written, also when not listed).
        Summary => "summary",
        /// CSV tables: `history.csv` (time histories) and the end-of-run tables.
        Csv => "csv",
        /// ParaView: `fields.pvd` + `fields/step_*.vtu` (and `steady.vtu`).
        Vtu => "vtu",
        /// `run.mcap` (protobuf channels readable by Foxglove and the Rerun viewer).
        Mcap => "mcap",
        /// `run.rrd` for the Rerun viewer (needs the default `rerun` cargo feature).
        Rerun => "rerun",
        /// PNG plots (hub forces, energy, contact distributions, branch diagrams).
        Png => "png",
    }
}

// ---------------------------------------------------------------------------------------------
// Scene structs
// ---------------------------------------------------------------------------------------------

/// One scene file, resolved: every default filled.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    pub scene: SceneInfo,
    pub geometry: Geometry,
    #[serde(default)]
    pub mesh: MeshSpec,
    pub material: MaterialSpec,
    pub analysis: Analysis,
    #[serde(default)]
    pub motion: Motion,
    /// `[road]`: required for `static`; optional for `transient` (with `[contact]`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub road: Option<RoadSpec>,
    /// `[contact]`: required for `static`; optional for `transient` (with `[road]`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact: Option<ContactSpec>,
    /// `[friction]`: law `none` when absent.
    #[serde(default)]
    pub friction: FrictionSpec,
    /// `[stick_slip]`: required for `stick_slip`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stick_slip: Option<StickSlipSpec>,
    /// `[time]`: required for `transient`, allowed (unused) in `steady`, forbidden otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time: Option<TimeSpec>,
    /// `[continuation]`: optional, `steady` only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub continuation: Option<ContinuationSpec>,
    #[serde(default)]
    pub solver: SolverSpec,
    #[serde(default)]
    pub output: OutputSpec,
    /// `[[material]]`: one material per mesh region (a 2D physical group of `mesh.file`), in the
    /// file's order. Empty for a scene with a single `[material]`; otherwise `material` holds the
    /// first region's material (for scales such as the shear wave speed).
    #[serde(skip)]
    pub regions: Vec<RegionMaterial>,
}

/// One `[[material]]` entry: the material of a mesh region.
#[derive(Clone, Debug, PartialEq)]
pub struct RegionMaterial {
    /// Name of a 2D physical group of the mesh file.
    pub region: String,
    pub material: MaterialSpec,
}

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

fn default_units() -> String {
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

/// `[material]`. Which of the optional parameters are required depends on `model`; after
/// [`Scene::from_toml_str`] the model-dependent defaults are filled in (`formulation` for the
/// incompressible model, `kappa` for the perturbed formulation), and [`MaterialSpec::params`]
/// gives the resolved parameters as one enum.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    pub model: MaterialModel,
    /// Density per unit reference volume.
    pub rho: f64,
    /// Lamé shear modulus (neo_hookean).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mu: Option<f64>,
    /// Lamé first parameter (neo_hookean).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lambda: Option<f64>,
    /// Mooney–Rivlin C1 (mooney_rivlin, mooney_rivlin_incompressible).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub c1: Option<f64>,
    /// Mooney–Rivlin C2 (mooney_rivlin, mooney_rivlin_incompressible).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub c2: Option<f64>,
    /// Bulk modulus (mooney_rivlin; mooney_rivlin_incompressible with the perturbed formulation).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kappa: Option<f64>,
    /// Incompressibility formulation (mooney_rivlin_incompressible only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub formulation: Option<Formulation>,
    /// `[material.viscoelastic]`: a viscoelastic overstress on the elastic law (any model).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub viscoelastic: Option<ViscoelasticSpec>,
}

/// `[material.viscoelastic]`: `S = ∂W/∂E + S_v` with the Prony kernel
/// `k(s) = Σ g_i exp(−s/τ_i)`; see [`crate::material::viscoelastic`] for both models.
/// Units: `gamma` is a stress (the scene's stress unit), `g` dimensionless, `tau` a time (the
/// scene's time unit). At small strain the overstress adds the shear relaxation modulus
/// `(gamma/2) k(t)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ViscoelasticSpec {
    /// `"convolution"` (the linear convolution on the Green strain rate) or `"multiplicative"`
    /// (the thermodynamically consistent finite-strain model).
    pub model: String,
    /// Stress scale γ (stress units), >= 0.
    pub gamma: f64,
    /// Prony terms `[[g_i, tau_i], ...]` (g dimensionless >= 0, tau > 0 in time units), 1 to 8.
    pub prony: Vec<[f64; 2]>,
}

impl ViscoelasticSpec {
    /// The law, or the message explaining what is wrong.
    pub fn build(&self) -> Result<crate::material::Viscoelastic, String> {
        let model = crate::material::ViscoModel::from_name(&self.model).ok_or_else(|| {
            format!(
                "unknown model \"{}\"; expected one of {}",
                self.model,
                quoted_list(crate::material::ViscoModel::NAMES)
            )
        })?;
        let prony: Vec<(f64, f64)> = self.prony.iter().map(|p| (p[0], p[1])).collect();
        crate::material::Viscoelastic::new(model, self.gamma, &prony).map_err(|e| e.to_string())
    }
}

/// Resolved material parameters, one variant per model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MaterialParams {
    NeoHookean {
        mu: f64,
        lambda: f64,
    },
    MooneyRivlin {
        c1: f64,
        c2: f64,
        kappa: f64,
    },
    MooneyRivlinIncompressible {
        c1: f64,
        c2: f64,
        formulation: Formulation,
        /// `Some` for the perturbed formulation, `None` for the exact one.
        kappa: Option<f64>,
    },
}

impl MaterialSpec {
    /// The resolved parameters of the chosen model, with model-dependent defaults applied
    /// (formulation `exact`; `kappa = 1e4 (c1 + c2)` for `perturbed`). `None` only if a
    /// parameter the model requires is missing, which cannot happen after validation.
    pub fn params(&self) -> Option<MaterialParams> {
        match self.model {
            MaterialModel::NeoHookean => Some(MaterialParams::NeoHookean {
                mu: self.mu?,
                lambda: self.lambda?,
            }),
            MaterialModel::MooneyRivlin => Some(MaterialParams::MooneyRivlin {
                c1: self.c1?,
                c2: self.c2?,
                kappa: self.kappa?,
            }),
            MaterialModel::MooneyRivlinIncompressible => {
                let c1 = self.c1?;
                let c2 = self.c2?;
                let formulation = self.formulation.unwrap_or_default();
                let kappa = match formulation {
                    Formulation::Exact => None,
                    Formulation::Perturbed => {
                        Some(self.kappa.unwrap_or(PERTURBED_KAPPA_FACTOR * (c1 + c2)))
                    }
                };
                Some(MaterialParams::MooneyRivlinIncompressible {
                    c1,
                    c2,
                    formulation,
                    kappa,
                })
            }
        }
    }

    /// Small-strain shear modulus G: `mu`, or `2 (c1 + c2)` for Mooney–Rivlin.
    pub fn shear_modulus(&self) -> Option<f64> {
        match self.params()? {
            MaterialParams::NeoHookean { mu, .. } => Some(mu),
            MaterialParams::MooneyRivlin { c1, c2, .. }
            | MaterialParams::MooneyRivlinIncompressible { c1, c2, .. } => Some(2.0 * (c1 + c2)),
        }
    }

    /// Small-strain bulk modulus K: `lambda + 2 mu / 3`, `kappa`; `None` for the exactly
    /// incompressible formulation (K = ∞).
    pub fn bulk_modulus(&self) -> Option<f64> {
        match self.params()? {
            MaterialParams::NeoHookean { mu, lambda } => Some(lambda + 2.0 * mu / 3.0),
            MaterialParams::MooneyRivlin { kappa, .. } => Some(kappa),
            MaterialParams::MooneyRivlinIncompressible { kappa, .. } => kappa,
        }
    }

    /// Whether the model carries a pressure field (incompressible Mooney–Rivlin).
    pub fn is_incompressible(&self) -> bool {
        self.model == MaterialModel::MooneyRivlinIncompressible
    }

    /// The resolved formulation: `Some` only for the incompressible model.
    pub fn resolved_formulation(&self) -> Option<Formulation> {
        match self.params()? {
            MaterialParams::MooneyRivlinIncompressible { formulation, .. } => Some(formulation),
            _ => None,
        }
    }

    /// The resolved bulk modulus used by the model, if it has one (`mooney_rivlin`, or the
    /// perturbed incompressible formulation).
    pub fn resolved_kappa(&self) -> Option<f64> {
        match self.params()? {
            MaterialParams::NeoHookean { .. } => None,
            MaterialParams::MooneyRivlin { kappa, .. } => Some(kappa),
            MaterialParams::MooneyRivlinIncompressible { kappa, .. } => kappa,
        }
    }

    /// Fill the model-dependent defaults into the optional fields.
    fn resolve(&mut self) {
        if let Some(MaterialParams::MooneyRivlinIncompressible {
            formulation, kappa, ..
        }) = self.params()
        {
            self.formulation = Some(formulation);
            self.kappa = kappa;
        }
    }

    /// The keys of `[material]` that belong to `model` (besides `model` itself).
    pub fn keys_of(model: MaterialModel) -> &'static [&'static str] {
        match model {
            MaterialModel::NeoHookean => &["rho", "mu", "lambda"],
            MaterialModel::MooneyRivlin => &["rho", "c1", "c2", "kappa"],
            MaterialModel::MooneyRivlinIncompressible => {
                &["rho", "c1", "c2", "formulation", "kappa"]
            }
        }
    }
}

/// `[analysis]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Analysis {
    pub mode: Mode,
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
fn ramp_value(t: f64, ramp: f64) -> f64 {
    if ramp > 0.0 {
        smoothstep(t / ramp)
    } else if t >= 0.0 {
        1.0
    } else {
        0.0
    }
}

/// `d/dt S(t / ramp)`; 0 for a zero ramp.
fn ramp_rate(t: f64, ramp: f64) -> f64 {
    if ramp > 0.0 {
        smoothstep_derivative(t / ramp) / ramp
    } else {
        0.0
    }
}

/// `∫₀ᵗ S(τ / ramp) dτ`.
fn ramp_integral(t: f64, ramp: f64) -> f64 {
    if ramp > 0.0 {
        ramp * smoothstep_integral(t / ramp)
    } else {
        t.max(0.0)
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

fn default_m_n() -> f64 {
    DEFAULT_M_N
}

fn default_contact_points() -> usize {
    DEFAULT_CONTACT_POINTS
}

/// `[friction]`. Which of the optional parameters are required depends on `law`;
/// [`FrictionSpec::params`] gives them as one enum.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrictionSpec {
    #[serde(default)]
    pub law: FrictionLawName,
    /// Coulomb coefficient (coulomb_tanh, coulomb_linear), >= 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mu: Option<f64>,
    /// Regularisation of the slip velocity (velocity; a slip length in `static`), > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eps: Option<f64>,
    /// Static coefficient (rate_dependent), >= 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mu_s: Option<f64>,
    /// Kinetic coefficient (rate_dependent), in [0, mu_s].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mu_k: Option<f64>,
    /// Decay velocity of μ from mu_s to mu_k (rate_dependent), > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub v_s: Option<f64>,
    /// Oden–Martins tangential compliance coefficient (stress/length^m_t), >= 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub c_t: Option<f64>,
    /// Oden–Martins tangential compliance exponent, >= 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub m_t: Option<f64>,
}

/// Resolved friction parameters, one variant per law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FrictionParams {
    None,
    CoulombTanh {
        mu: f64,
        eps: f64,
    },
    CoulombLinear {
        mu: f64,
        eps: f64,
    },
    RateDependent {
        mu_s: f64,
        mu_k: f64,
        v_s: f64,
        eps: f64,
    },
    OdenMartins {
        c_t: f64,
        m_t: f64,
        eps: f64,
    },
}

impl FrictionSpec {
    /// The parameters of the chosen law. `None` only if a parameter the law requires is
    /// missing, which cannot happen after validation.
    pub fn params(&self) -> Option<FrictionParams> {
        match self.law {
            FrictionLawName::None => Some(FrictionParams::None),
            FrictionLawName::CoulombTanh => Some(FrictionParams::CoulombTanh {
                mu: self.mu?,
                eps: self.eps?,
            }),
            FrictionLawName::CoulombLinear => Some(FrictionParams::CoulombLinear {
                mu: self.mu?,
                eps: self.eps?,
            }),
            FrictionLawName::RateDependent => Some(FrictionParams::RateDependent {
                mu_s: self.mu_s?,
                mu_k: self.mu_k?,
                v_s: self.v_s?,
                eps: self.eps?,
            }),
            FrictionLawName::OdenMartins => Some(FrictionParams::OdenMartins {
                c_t: self.c_t?,
                m_t: self.m_t?,
                eps: self.eps?,
            }),
        }
    }

    /// Whether friction acts at all: false for law `none`, for a zero coefficient (`mu = 0`;
    /// `mu_s = mu_k = 0`; `c_t = 0`) and for an incomplete law.
    pub fn is_active(&self) -> bool {
        match self.params() {
            None | Some(FrictionParams::None) => false,
            Some(FrictionParams::CoulombTanh { mu, .. })
            | Some(FrictionParams::CoulombLinear { mu, .. }) => mu > 0.0,
            Some(FrictionParams::RateDependent { mu_s, mu_k, .. }) => mu_s > 0.0 || mu_k > 0.0,
            Some(FrictionParams::OdenMartins { c_t, .. }) => c_t > 0.0,
        }
    }

    /// The keys of `[friction]` that belong to `law` (besides `law` itself).
    pub fn keys_of(law: FrictionLawName) -> &'static [&'static str] {
        match law {
            FrictionLawName::None => &[],
            FrictionLawName::CoulombTanh | FrictionLawName::CoulombLinear => &["mu", "eps"],
            FrictionLawName::RateDependent => &["mu_s", "mu_k", "v_s", "eps"],
            FrictionLawName::OdenMartins => &["c_t", "m_t", "eps"],
        }
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
        }
    }
}

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

fn default_rtol() -> f64 {
    DEFAULT_STICK_SLIP_RTOL
}

fn default_atol() -> f64 {
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

fn default_rho_inf() -> f64 {
    DEFAULT_RHO_INF
}

fn default_true() -> bool {
    true
}

fn default_error_tol() -> f64 {
    DEFAULT_ERROR_TOL
}

fn default_steady_tol() -> f64 {
    DEFAULT_STEADY_TOL
}

fn default_max_steps() -> usize {
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

/// `[solver]`: Newton with load stepping (in ω² for `spinning`; in the road penetration or the
/// road load for `static`) and cutbacks. In `transient`: the Newton iterations of each implicit
/// time step, a failed step being retried with half the step (`load_steps` unused). Not used by
/// `stick_slip`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SolverSpec {
    /// Relative residual tolerance, in (0, 1).
    pub tolerance: f64,
    /// Newton iterations per load step (>= 1).
    pub max_iterations: usize,
    /// Initial number of load steps (>= 1).
    pub load_steps: usize,
    /// How many times a failed step may be halved.
    pub max_cutbacks: usize,
    pub linear: LinearChoice,
    /// Worker threads; 0 = all cores.
    pub threads: usize,
    /// Backtracking line search on the residual norm.
    pub line_search: bool,
}

impl Default for SolverSpec {
    fn default() -> Self {
        SolverSpec {
            tolerance: 1e-10,
            max_iterations: 25,
            load_steps: 4,
            max_cutbacks: 10,
            linear: LinearChoice::Auto,
            threads: 0,
            line_search: true,
        }
    }
}

/// `[output]`: which sinks record the run and how often.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OutputSpec {
    /// Output sinks; `summary.json` is written whether listed or not.
    pub sinks: Vec<Sink>,
    /// Decimation: steps between recorded frames (>= 1); the final step is always recorded.
    pub every: usize,
    /// Encoding of the `.vtu` files: `binary` (default) or `ascii`.
    pub vtu_format: VtuFormat,
    /// Displacement magnification of the body in the Rerun recording's view (> 0; default 1).
    pub displacement_scale: f64,
    /// Compression of the binary `.vtu` data: `none` (default) or `zlib`.
    pub vtu_compression: VtuCompression,
}

/// Default of `[output] sinks`: the light-weight outputs (MCAP and Rerun logs are opt-in).
pub const DEFAULT_SINKS: &[Sink] = &[Sink::Summary, Sink::Csv, Sink::Vtu, Sink::Png];

impl Default for OutputSpec {
    fn default() -> Self {
        OutputSpec {
            sinks: DEFAULT_SINKS.to_vec(),
            every: 1,
            vtu_format: VtuFormat::Binary,
            displacement_scale: 1.0,
            vtu_compression: VtuCompression::None,
        }
    }
}

impl OutputSpec {
    /// Whether `sink` is listed.
    pub fn has(&self, sink: Sink) -> bool {
        self.sinks.contains(&sink)
    }
}

// ---------------------------------------------------------------------------------------------
// Errors
// ---------------------------------------------------------------------------------------------

/// One problem in a scene.
///
/// Displayed as `"{source_name}:{line}: key `{key}`: {message}"`, without `:{line}` when the line
/// is unknown, and without the `key` part when no key applies (e.g. some syntax errors). For a
/// value given by a `--set` override, `line` is `None` and `source_name` is
/// `"{file}:(--set)"`, so the error reads `file.toml:(--set): key `mesh.n_r`: ...`; see
/// [`SceneError::is_override`].
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{}", render_error(.source_name, *.line, .key, .message))]
pub struct SceneError {
    /// Dotted key, e.g. `geometry.ri`; a section name for section-level problems; may be empty.
    pub key: String,
    /// 1-based line in the scene file.
    pub line: Option<usize>,
    pub message: String,
    pub source_name: String,
}

const OVERRIDE_TAG: &str = ":(--set)";

fn render_error(source_name: &str, line: Option<usize>, key: &str, message: &str) -> String {
    let mut s = String::from(source_name);
    if let Some(l) = line {
        s.push_str(&format!(":{l}"));
    }
    s.push_str(": ");
    if !key.is_empty() {
        s.push_str(&format!("key `{key}`: "));
    }
    s.push_str(message);
    s
}

impl SceneError {
    /// Whether the offending value came from a `--set` override.
    pub fn is_override(&self) -> bool {
        self.source_name.ends_with(OVERRIDE_TAG)
    }
}

/// Every problem found in a scene; displayed one per line.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneErrors(pub Vec<SceneError>);

impl fmt::Display for SceneErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, e) in self.0.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            write!(f, "{e}")?;
        }
        Ok(())
    }
}

impl std::error::Error for SceneErrors {}

impl From<SceneError> for SceneErrors {
    fn from(e: SceneError) -> Self {
        SceneErrors(vec![e])
    }
}

impl SceneErrors {
    /// Whether some error names exactly this dotted key.
    pub fn has_key(&self, key: &str) -> bool {
        self.0.iter().any(|e| e.key == key)
    }

    /// The first error naming exactly this dotted key.
    pub fn find(&self, key: &str) -> Option<&SceneError> {
        self.0.iter().find(|e| e.key == key)
    }
}

// ---------------------------------------------------------------------------------------------
// Public entry points
// ---------------------------------------------------------------------------------------------

impl Scene {
    /// Parse, apply `--set key=value` overrides (dotted keys like `"mesh.n_r=8"`; the value is
    /// parsed as a TOML value, falling back to a bare string; for string-valued keys the raw text
    /// is taken as the string unless it is a quoted TOML string), fill defaults, validate.
    /// Collects all errors, not just the first.
    pub fn from_toml_str(
        text: &str,
        source_name: &str,
        overrides: &[String],
    ) -> Result<Scene, SceneErrors> {
        let locator = Locator::new(text);
        let mut ctx = Ctx {
            source_name,
            locator: &locator,
            overridden: BTreeSet::new(),
            issues: Vec::new(),
        };

        let mut doc: toml::Table = match text.parse::<toml::Table>() {
            Ok(t) => t,
            Err(e) => {
                let line = e.span().map(|s| line_of_offset(text, s.start));
                let key = line
                    .and_then(|l| locator.key_at_line(l))
                    .unwrap_or_default();
                return Err(SceneErrors(vec![SceneError {
                    key,
                    line,
                    message: format!("TOML syntax error: {}", e.message().trim_end()),
                    source_name: source_name.to_string(),
                }]));
            }
        };

        ctx.apply_overrides(&mut doc, overrides);
        // `[[material]]`: the first entry goes through the `[material]` path (its errors name
        // `material.<key>`), the others are checked here (`material[<region>].<key>`).
        let region_tables = ctx.take_region_materials(&mut doc);
        let clean = ctx.check_schema(&doc);

        let info: Option<SceneInfo> = ctx.required_section(&clean, "scene");
        let geometry: Option<Geometry> = ctx.required_section(&clean, "geometry");
        let mesh: Option<MeshSpec> = ctx.optional_section(&clean, "mesh");
        let material: Option<MaterialSpec> = ctx.required_section(&clean, "material");
        let analysis: Option<Analysis> = ctx.required_section(&clean, "analysis");
        let motion: Option<Motion> = ctx.optional_section(&clean, "motion");
        let road: Option<Option<RoadSpec>> = ctx.present_section(&clean, "road");
        let contact: Option<Option<ContactSpec>> = ctx.present_section(&clean, "contact");
        let friction: Option<FrictionSpec> = ctx.optional_section(&clean, "friction");
        let stick_slip: Option<Option<StickSlipSpec>> = ctx.present_section(&clean, "stick_slip");
        let time: Option<Option<TimeSpec>> = ctx.present_section(&clean, "time");
        let continuation: Option<Option<ContinuationSpec>> =
            ctx.present_section(&clean, "continuation");
        let solver: Option<SolverSpec> = ctx.optional_section(&clean, "solver");
        let output: Option<OutputSpec> = ctx.optional_section(&clean, "output");

        let mut out = Vec::new();
        let mut regions = ctx.region_materials(&region_tables, &mut out);
        if let Some(m) = &mesh {
            validate_mesh_file(m, &region_tables, &doc, &mut out);
        }
        if let Some(s) = &info {
            validate_info(s, &mut out);
        }
        if let Some(g) = &geometry {
            validate_geometry(g, &mut out);
        }
        if let Some(m) = &mesh {
            validate_mesh(m, &mut out);
        }
        if let Some(m) = &material {
            validate_material(m, &mut out);
        }
        let mode = analysis.as_ref().map(|a| a.mode);
        if let Some(m) = &motion {
            let omega_given = table_has(&doc, "motion", "omega");
            let omega_bad = !table_has(&clean, "motion", "omega") && omega_given;
            if !omega_bad {
                validate_motion(mode, m, omega_given, &mut out);
            }
            validate_motion_ramp(mode, m, &mut out);
            let integrator = match &time {
                Some(Some(t)) => Some(t.integrator),
                _ => None,
            };
            // An unknown or ill-typed `control` was dropped (and reported): the other keys
            // cannot be checked against it.
            let control_bad =
                table_has(&doc, "motion", "control") && !table_has(&clean, "motion", "control");
            if !control_bad {
                validate_motion_control(mode, m, integrator, &mut out);
            }
        }
        if let Some(Some(r)) = &road {
            validate_road(r, mode, geometry.as_ref(), &mut out);
        }
        if let Some(Some(c)) = &contact {
            validate_contact(c, mode, &mut out);
        }
        // An unknown or ill-typed `law` was dropped (and reported): the remaining keys cannot
        // be checked against a law, and the mode cannot be checked against it.
        let law_bad = table_has(&doc, "friction", "law") && !table_has(&clean, "friction", "law");
        let friction_law = match (&friction, law_bad) {
            (Some(f), false) => {
                validate_friction(f, &mut out);
                Some(f.law)
            }
            _ => None,
        };
        if let Some(Some(s)) = &stick_slip {
            validate_stick_slip(s, &mut out);
        }
        // An explicitly written `mass` (valid or not) counts as given.
        let time_mass_given = table_has(&doc, "time", "mass");
        if let Some(Some(t)) = &time {
            validate_time(t, time_mass_given, &mut out);
        }
        if let Some(Some(c)) = &continuation {
            validate_continuation(
                c,
                mode,
                road.as_ref().and_then(|r| r.as_ref()),
                motion.as_ref().map(|m| m.control),
                &mut out,
            );
        }
        if let Some(mode) = mode {
            let used = SectionsGiven {
                road: doc.contains_key("road"),
                contact: doc.contains_key("contact"),
                stick_slip: doc.contains_key("stick_slip"),
                time: doc.contains_key("time"),
                continuation: doc.contains_key("continuation"),
                friction_law,
            };
            validate_mode_sections(mode, &used, &mut out);
        }
        if let (Some(m), Some(Some(t))) = (&mesh, &time) {
            if m.file.is_none() {
                validate_steady_extraction(mode, m, t, &mut out);
            }
        }
        if let Some(s) = &solver {
            validate_solver(s, &mut out);
        }
        if let Some(o) = &output {
            validate_output(o, &mut out);
        }
        // A key already reported by the schema pass (unknown or ill-typed) is not reported again
        // (e.g. as "required" because its ill-typed value was dropped).
        let reported: BTreeSet<String> = ctx.issues.iter().map(|i| i.key.clone()).collect();
        ctx.issues
            .extend(out.into_iter().filter(|i| !reported.contains(&i.key)));

        if !ctx.issues.is_empty() {
            return Err(ctx.into_errors());
        }
        let (
            Some(scene),
            Some(geometry),
            Some(mesh),
            Some(mut material),
            Some(analysis),
            Some(motion),
            Some(road),
            Some(contact),
            Some(friction),
            Some(stick_slip),
            Some(mut time),
            Some(continuation),
            Some(solver),
            Some(output),
        ) = (
            info,
            geometry,
            mesh,
            material,
            analysis,
            motion,
            road,
            contact,
            friction,
            stick_slip,
            time,
            continuation,
            solver,
            output,
        )
        else {
            // Unreachable in practice: every `None` above records an issue.
            return Err(SceneErrors(vec![SceneError {
                key: String::new(),
                line: None,
                message: "scene is incomplete".to_string(),
                source_name: source_name.to_string(),
            }]));
        };
        material.resolve();
        if let (Some(first), Some((name, _))) = (regions.first_mut(), region_tables.first()) {
            // The first region's material is `material` itself.
            *first = RegionMaterial {
                region: name.clone(),
                material: material.clone(),
            };
        }
        if let Some(t) = time.as_mut() {
            if !time_mass_given {
                t.mass = t.effective_mass();
            }
        }
        Ok(Scene {
            scene,
            geometry,
            mesh,
            material,
            analysis,
            motion,
            road,
            contact,
            friction,
            stick_slip,
            time,
            continuation,
            solver,
            output,
            regions,
        })
    }

    /// Read a scene file and load it with [`Scene::from_toml_str`]; the path names the source.
    pub fn from_path(path: &Path, overrides: &[String]) -> Result<Scene, SceneErrors> {
        let name = path.display().to_string();
        match std::fs::read_to_string(path) {
            Ok(text) => Scene::from_toml_str(&text, &name, overrides).map(|mut s| {
                s.resolve_paths(path);
                s
            }),
            Err(e) => Err(SceneErrors(vec![SceneError {
                key: String::new(),
                line: None,
                message: format!("cannot read scene file: {e}"),
                source_name: name,
            }])),
        }
    }

    /// Make a relative `mesh.file` relative to the scene file at `scene_path` (as read from disk).
    pub fn resolve_paths(&mut self, scene_path: &Path) {
        if let (Some(f), Some(dir)) = (&self.mesh.file, scene_path.parent()) {
            if Path::new(f).is_relative() && !dir.as_os_str().is_empty() {
                self.mesh.file = Some(dir.join(f).display().to_string());
            }
        }
    }

    /// Validate a scene built in code (ranges, model keys). Errors carry no line numbers; the
    /// source is named `<scene>`.
    pub fn validate(&self) -> Result<(), SceneErrors> {
        let mut out = Vec::new();
        validate_info(&self.scene, &mut out);
        validate_geometry(&self.geometry, &mut out);
        validate_mesh(&self.mesh, &mut out);
        validate_material(&self.material, &mut out);
        let mode = Some(self.analysis.mode);
        validate_motion(mode, &self.motion, true, &mut out);
        validate_motion_ramp(mode, &self.motion, &mut out);
        validate_motion_control(
            mode,
            &self.motion,
            self.time.as_ref().map(|t| t.integrator),
            &mut out,
        );
        if let Some(r) = &self.road {
            validate_road(r, mode, Some(&self.geometry), &mut out);
        }
        if let Some(c) = &self.contact {
            validate_contact(c, mode, &mut out);
        }
        validate_friction(&self.friction, &mut out);
        if let Some(s) = &self.stick_slip {
            validate_stick_slip(s, &mut out);
        }
        if let Some(t) = &self.time {
            validate_time(t, true, &mut out);
            validate_steady_extraction(mode, &self.mesh, t, &mut out);
        }
        if let Some(c) = &self.continuation {
            validate_continuation(
                c,
                mode,
                self.road.as_ref(),
                Some(self.motion.control),
                &mut out,
            );
        }
        let used = SectionsGiven {
            road: self.road.is_some(),
            contact: self.contact.is_some(),
            stick_slip: self.stick_slip.is_some(),
            time: self.time.is_some(),
            continuation: self.continuation.is_some(),
            friction_law: Some(self.friction.law),
        };
        validate_mode_sections(self.analysis.mode, &used, &mut out);
        validate_solver(&self.solver, &mut out);
        validate_output(&self.output, &mut out);
        if out.is_empty() {
            Ok(())
        } else {
            Err(SceneErrors(
                out.into_iter()
                    .map(|i| SceneError {
                        key: i.key,
                        line: None,
                        message: i.message,
                        source_name: "<scene>".to_string(),
                    })
                    .collect(),
            ))
        }
    }

    /// The resolved scene (defaults filled) as TOML, for `tread check`. Parses back to `self`.
    pub fn to_toml_string(&self) -> String {
        if !self.regions.is_empty() {
            return self.to_toml_string_regions();
        }
        match toml::to_string_pretty(self) {
            Ok(s) => s,
            // Only possible for non-finite floats in a scene built in code.
            Err(e) => format!("# cannot write scene as TOML: {e}\n"),
        }
    }

    /// [`Self::to_toml_string`] of a scene with `[[material]]` regions.
    fn to_toml_string_regions(&self) -> String {
        let table = toml::Table::try_from(self).and_then(|mut t| {
            let mut arr = Vec::new();
            for r in &self.regions {
                let mut m = toml::Table::try_from(&r.material)?;
                m.insert("region".into(), toml::Value::String(r.region.clone()));
                arr.push(toml::Value::Table(m));
            }
            t.insert("material".into(), toml::Value::Array(arr));
            Ok(t)
        });
        match table.map(|t| toml::to_string_pretty(&t)) {
            Ok(Ok(s)) => s,
            Ok(Err(e)) => format!("# cannot write scene as TOML: {e}\n"),
            Err(e) => format!("# cannot write scene as TOML: {e}\n"),
        }
    }

    /// The shear wave speed `sqrt(G / rho)` of the material, if defined.
    pub fn shear_wave_speed(&self) -> Option<f64> {
        let g = self.material.shear_modulus()?;
        let rho = self.material.rho;
        (g > 0.0 && rho > 0.0).then(|| (g / rho).sqrt())
    }
}

// ---------------------------------------------------------------------------------------------
// Schema (must match the serde structs; a test checks it)
// ---------------------------------------------------------------------------------------------

#[derive(Clone, Copy, Debug)]
enum Kind {
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
}

#[derive(Debug)]
struct FieldSchema {
    key: &'static str,
    kind: Kind,
    required: bool,
}

struct SectionSchema {
    name: &'static str,
    required: bool,
    fields: &'static [FieldSchema],
}

const fn req(key: &'static str, kind: Kind) -> FieldSchema {
    FieldSchema {
        key,
        kind,
        required: true,
    }
}

const fn opt(key: &'static str, kind: Kind) -> FieldSchema {
    FieldSchema {
        key,
        kind,
        required: false,
    }
}

/// Keys of `[material.viscoelastic]`.
static VISCOELASTIC_FIELDS: &[FieldSchema] = &[
    req("model", Kind::Keyword(crate::material::ViscoModel::NAMES)),
    req("gamma", Kind::Float),
    req("prony", Kind::FloatPairs),
];

static SCHEMA: &[SectionSchema] = &[
    SectionSchema {
        name: "scene",
        required: true,
        fields: &[
            req("name", Kind::Str),
            opt("description", Kind::Str),
            opt("units", Kind::Str),
        ],
    },
    SectionSchema {
        name: "geometry",
        required: true,
        fields: &[req("ri", Kind::Float), req("ro", Kind::Float)],
    },
    SectionSchema {
        name: "mesh",
        required: false,
        fields: &[
            opt("n_r", Kind::UInt),
            opt("n_theta", Kind::UInt),
            opt("order", Kind::UInt),
            opt("grading_r", Kind::Float),
            opt("grading_theta", Kind::Float),
            opt("file", Kind::Str),
            opt("hub", Kind::Str),
            opt("contact", Kind::Str),
        ],
    },
    SectionSchema {
        name: "material",
        required: true,
        fields: &[
            req("model", Kind::Keyword(MaterialModel::NAMES)),
            req("rho", Kind::Float),
            opt("mu", Kind::Float),
            opt("lambda", Kind::Float),
            opt("c1", Kind::Float),
            opt("c2", Kind::Float),
            opt("kappa", Kind::Float),
            opt("formulation", Kind::Keyword(Formulation::NAMES)),
            opt("viscoelastic", Kind::Table(VISCOELASTIC_FIELDS)),
        ],
    },
    SectionSchema {
        name: "analysis",
        required: true,
        fields: &[req("mode", Kind::Keyword(Mode::NAMES))],
    },
    SectionSchema {
        name: "motion",
        required: false,
        fields: &[
            opt("omega", Kind::Float),
            opt("ramp", Kind::Float),
            opt("control", Kind::Keyword(Control::NAMES)),
            opt("hub_inertia", Kind::Float),
            opt("torque", Kind::Float),
            opt("creep", Kind::Float),
        ],
    },
    SectionSchema {
        name: "road",
        required: false,
        fields: &[
            opt("disp", Kind::Float),
            opt("load", Kind::Float),
            opt("v0", Kind::Float),
            opt("ramp", Kind::Float),
            opt("v0_ramp", Kind::Float),
        ],
    },
    SectionSchema {
        name: "contact",
        required: false,
        fields: &[
            req("c_n", Kind::Float),
            opt("m_n", Kind::Float),
            opt("b_n", Kind::Float),
            opt("l_n", Kind::Float),
            opt("quadrature", Kind::Keyword(ContactQuadrature::NAMES)),
            opt("points", Kind::UInt),
            opt("clamp", Kind::Keyword(ClampKind::NAMES)),
            opt("clamp_width", Kind::Float),
        ],
    },
    SectionSchema {
        name: "friction",
        required: false,
        fields: &[
            opt("law", Kind::Keyword(FrictionLawName::NAMES)),
            opt("mu", Kind::Float),
            opt("eps", Kind::Float),
            opt("mu_s", Kind::Float),
            opt("mu_k", Kind::Float),
            opt("v_s", Kind::Float),
            opt("c_t", Kind::Float),
            opt("m_t", Kind::Float),
        ],
    },
    SectionSchema {
        name: "stick_slip",
        required: false,
        fields: &[
            req("mass", Kind::Float),
            req("stiffness", Kind::Float),
            req("normal_force", Kind::Float),
            req("belt_speed", Kind::Float),
            req("t_end", Kind::Float),
            opt("rtol", Kind::Float),
            opt("atol", Kind::Float),
            opt("x0", Kind::Float),
            opt("v0", Kind::Float),
            opt("output_interval", Kind::Float),
        ],
    },
    SectionSchema {
        name: "time",
        required: false,
        fields: &[
            opt("integrator", Kind::Keyword(IntegratorName::NAMES)),
            opt("rho_inf", Kind::Float),
            req("dt", Kind::Float),
            opt("dt_min", Kind::Float),
            opt("dt_max", Kind::Float),
            req("t_end", Kind::Float),
            opt("adaptive", Kind::Bool),
            opt("error_tol", Kind::Float),
            opt("steady_tol", Kind::Float),
            opt("stop_at_steady", Kind::Bool),
            opt("mass", Kind::Keyword(MassKind::NAMES)),
            opt("max_steps", Kind::UInt),
            opt("strain_rate_damping", Kind::Float),
        ],
    },
    SectionSchema {
        name: "continuation",
        required: false,
        fields: &[
            opt("parameter", Kind::Keyword(ContinuationParameter::NAMES)),
            req("target", Kind::Float),
            opt("ds", Kind::Float),
            opt("ds_max", Kind::Float),
            opt("max_steps", Kind::UInt),
            opt("desired_iterations", Kind::UInt),
        ],
    },
    SectionSchema {
        name: "solver",
        required: false,
        fields: &[
            opt("tolerance", Kind::Float),
            opt("max_iterations", Kind::UInt),
            opt("load_steps", Kind::UInt),
            opt("max_cutbacks", Kind::UInt),
            opt("linear", Kind::Keyword(LinearChoice::NAMES)),
            opt("threads", Kind::UInt),
            opt("line_search", Kind::Bool),
        ],
    },
    SectionSchema {
        name: "output",
        required: false,
        fields: &[
            opt("sinks", Kind::KeywordList(Sink::NAMES)),
            opt("every", Kind::UInt),
            opt("vtu_format", Kind::Keyword(VtuFormat::NAMES)),
            opt("displacement_scale", Kind::Float),
            opt("vtu_compression", Kind::Keyword(VtuCompression::NAMES)),
        ],
    },
];

fn section_schema(name: &str) -> Option<&'static SectionSchema> {
    SCHEMA.iter().find(|s| s.name == name)
}

impl SectionSchema {
    fn field(&self, key: &str) -> Option<&'static FieldSchema> {
        self.fields.iter().find(|f| f.key == key)
    }

    fn key_list(&self) -> String {
        self.fields
            .iter()
            .map(|f| f.key)
            .collect::<Vec<_>>()
            .join(", ")
    }
}

fn section_list() -> String {
    SCHEMA
        .iter()
        .map(|s| format!("[{}]", s.name))
        .collect::<Vec<_>>()
        .join(", ")
}

fn quoted_list(names: &[&str]) -> String {
    names
        .iter()
        .map(|n| format!("\"{n}\""))
        .collect::<Vec<_>>()
        .join(", ")
}

fn describe_value(v: &toml::Value) -> String {
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

fn check_kind(kind: Kind, v: &toml::Value) -> Result<(), String> {
    let ok = match (kind, v) {
        (Kind::Float, toml::Value::Float(f)) => {
            if f.is_finite() {
                true
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
            Kind::Keyword(names) => format!("a string, one of {}", quoted_list(names)),
            Kind::KeywordList(names) => {
                format!("an array of strings from {}", quoted_list(names))
            }
        };
        Err(format!("expected {expected}, found {}", describe_value(v)))
    }
}

// ---------------------------------------------------------------------------------------------
// Loading context
// ---------------------------------------------------------------------------------------------

/// Where an issue's location comes from.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Origin {
    /// `(--set)` if the key was overridden, else the line of the key in the original text.
    Auto,
    /// Always `(--set)`: a problem with the override itself.
    Override,
}

#[derive(Clone, Debug)]
struct Issue {
    key: String,
    message: String,
    origin: Origin,
    /// Another key whose location is reported when `key` itself is nowhere in the file (e.g.
    /// `analysis.mode` for a section that the mode requires).
    anchor: Option<&'static str>,
}

fn issue(key: impl Into<String>, message: impl Into<String>) -> Issue {
    Issue {
        key: key.into(),
        message: message.into(),
        origin: Origin::Auto,
        anchor: None,
    }
}

/// An issue about a key that may be absent from the file: located at `anchor` in that case.
fn issue_near(key: impl Into<String>, message: impl Into<String>, anchor: &'static str) -> Issue {
    Issue {
        anchor: Some(anchor),
        ..issue(key, message)
    }
}

struct Ctx<'a> {
    source_name: &'a str,
    locator: &'a Locator,
    overridden: BTreeSet<String>,
    issues: Vec<Issue>,
}

impl Ctx<'_> {
    fn push(&mut self, key: impl Into<String>, message: impl Into<String>) {
        self.issues.push(issue(key, message));
    }

    fn push_override(&mut self, key: impl Into<String>, message: impl Into<String>) {
        self.issues.push(Issue {
            key: key.into(),
            message: message.into(),
            origin: Origin::Override,
            anchor: None,
        });
    }

    fn apply_overrides(&mut self, doc: &mut toml::Table, overrides: &[String]) {
        for ov in overrides {
            let Some((raw_key, raw_value)) = ov.split_once('=') else {
                self.push_override(
                    ov.trim(),
                    format!("malformed override `{ov}`: expected `section.key=value`"),
                );
                continue;
            };
            let key = raw_key.trim();
            let parts: Vec<&str> = key.split('.').map(str::trim).collect();
            if parts.len() != 2 || parts.iter().any(|p| p.is_empty()) {
                self.push_override(
                    key,
                    format!("malformed override `{ov}`: the key must be `section.key`"),
                );
                continue;
            }
            let (sec_name, field_name) = (parts[0], parts[1]);
            let key = format!("{sec_name}.{field_name}");
            let Some(sec) = section_schema(sec_name) else {
                self.push_override(
                    key,
                    format!(
                        "unknown section `[{sec_name}]` in override `{ov}`; sections are {}",
                        section_list()
                    ),
                );
                continue;
            };
            let Some(field) = sec.field(field_name) else {
                self.push_override(
                    key,
                    format!(
                        "unknown key in override `{ov}`; keys of [{sec_name}] are {}",
                        sec.key_list()
                    ),
                );
                continue;
            };
            let value = parse_override_value(raw_value.trim(), field.kind);
            let entry = doc
                .entry(sec_name.to_string())
                .or_insert_with(|| toml::Value::Table(toml::Table::new()));
            match entry {
                toml::Value::Table(t) => {
                    t.insert(field_name.to_string(), value);
                    self.overridden.insert(key);
                }
                other => {
                    let found = describe_value(other);
                    self.push_override(
                        key,
                        format!(
                            "cannot apply override `{ov}`: `{sec_name}` in the file is {found}, not a table"
                        ),
                    );
                }
            }
        }
    }

    /// Check sections and keys against [`SCHEMA`]; return a copy of the document without the
    /// offending entries, so that the remaining sections can still be deserialized and validated.
    fn check_schema(&mut self, doc: &toml::Table) -> toml::Table {
        let mut clean = toml::Table::new();
        for (sec_name, sec_value) in doc {
            let Some(sec) = section_schema(sec_name) else {
                self.push(
                    sec_name.clone(),
                    format!("unknown section; sections are {}", section_list()),
                );
                continue;
            };
            let toml::Value::Table(table) = sec_value else {
                self.push(
                    sec_name.clone(),
                    format!(
                        "expected a table [{sec_name}], found {}",
                        describe_value(sec_value)
                    ),
                );
                continue;
            };
            let mut clean_table = toml::Table::new();
            for (key, value) in table {
                let dotted = format!("{sec_name}.{key}");
                match sec.field(key) {
                    None => self.push(
                        dotted,
                        format!("unknown key; keys of [{sec_name}] are {}", sec.key_list()),
                    ),
                    Some(field) => match (check_kind(field.kind, value), field.kind, value) {
                        (Ok(()), Kind::Table(sub), toml::Value::Table(t)) => {
                            // A sub-table: its keys are checked like a section's; it is kept
                            // only when all of them are valid.
                            let before = self.issues.len();
                            for (k, v) in t {
                                match sub.iter().find(|f| f.key == k) {
                                    None => self.push(
                                        format!("{dotted}.{k}"),
                                        format!(
                                            "unknown key; keys of [{dotted}] are {}",
                                            sub.iter()
                                                .map(|f| f.key)
                                                .collect::<Vec<_>>()
                                                .join(", ")
                                        ),
                                    ),
                                    Some(f) => {
                                        if let Err(msg) = check_kind(f.kind, v) {
                                            self.push(format!("{dotted}.{k}"), msg);
                                        }
                                    }
                                }
                            }
                            for f in sub.iter().filter(|f| f.required) {
                                if !t.contains_key(f.key) {
                                    self.push(
                                        format!("{dotted}.{}", f.key),
                                        "required key is missing",
                                    );
                                }
                            }
                            if self.issues.len() == before {
                                clean_table.insert(key.clone(), value.clone());
                            }
                        }
                        (Ok(()), _, _) => {
                            clean_table.insert(key.clone(), value.clone());
                        }
                        (Err(msg), _, _) => self.push(dotted, msg),
                    },
                }
            }
            for field in sec.fields.iter().filter(|f| f.required) {
                if !table.contains_key(field.key) {
                    self.push(
                        format!("{sec_name}.{}", field.key),
                        "required key is missing",
                    );
                }
            }
            clean.insert(sec_name.clone(), toml::Value::Table(clean_table));
        }
        for sec in SCHEMA.iter().filter(|s| s.required) {
            if !doc.contains_key(sec.name) {
                let needs: Vec<&str> = sec
                    .fields
                    .iter()
                    .filter(|f| f.required)
                    .map(|f| f.key)
                    .collect();
                self.push(
                    sec.name,
                    format!(
                        "required section [{}] is missing (it needs {})",
                        sec.name,
                        needs.join(", ")
                    ),
                );
            }
        }
        clean
    }

    /// Take `[[material]]` out of the document: returns (region, table) per entry and puts the
    /// first entry back as `[material]`. Entries that are not tables or lack a string `region`
    /// are reported and dropped.
    fn take_region_materials(&mut self, doc: &mut toml::Table) -> Vec<(String, toml::Table)> {
        let Some(toml::Value::Array(items)) = doc.get("material").cloned() else {
            return Vec::new();
        };
        doc.remove("material");
        let mut out: Vec<(String, toml::Table)> = Vec::new();
        for (i, item) in items.into_iter().enumerate() {
            let toml::Value::Table(mut t) = item else {
                self.push(
                    format!("material[{i}]"),
                    format!(
                        "expected a table ([[material]]), found {}",
                        describe_value(&item)
                    ),
                );
                continue;
            };
            let region = match t.remove("region") {
                Some(toml::Value::String(s)) if !s.is_empty() => s,
                Some(v) => {
                    self.push(
                        format!("material[{i}].region"),
                        format!("expected a non-empty string, found {}", describe_value(&v)),
                    );
                    continue;
                }
                None => {
                    self.push(
                        format!("material[{i}].region"),
                        "required key is missing: each [[material]] names its mesh region \
                         (a 2D physical group of mesh.file)",
                    );
                    continue;
                }
            };
            if out.iter().any(|(r, _)| *r == region) {
                self.push(
                    format!("material[{region}]"),
                    "region given twice in [[material]]",
                );
                continue;
            }
            out.push((region, t));
        }
        // Nothing usable: the schema pass reports the section as missing.
        if let Some((_, t)) = out.first() {
            doc.insert("material".into(), toml::Value::Table(t.clone()));
        }
        out
    }

    /// Check and deserialize the `[[material]]` entries after the first (which is `[material]`);
    /// returns one placeholder per entry (the first is filled in by the caller).
    fn region_materials(
        &mut self,
        tables: &[(String, toml::Table)],
        out: &mut Vec<Issue>,
    ) -> Vec<RegionMaterial> {
        let mut regions = Vec::new();
        let Some(schema) = section_schema("material") else {
            return regions;
        };
        for (k, (region, table)) in tables.iter().enumerate() {
            let prefix = format!("material[{region}]");
            if k == 0 {
                regions.push(RegionMaterial {
                    region: region.clone(),
                    material: MaterialSpec {
                        model: MaterialModel::NeoHookean,
                        rho: 0.0,
                        mu: None,
                        lambda: None,
                        c1: None,
                        c2: None,
                        kappa: None,
                        formulation: None,
                        viscoelastic: None,
                    },
                });
                continue;
            }
            let mut clean = toml::Table::new();
            let mut complete = true;
            for (key, value) in table {
                match schema.field(key) {
                    None => self.push(
                        format!("{prefix}.{key}"),
                        format!(
                            "unknown key; keys of [[material]] are region, {}",
                            schema.key_list()
                        ),
                    ),
                    Some(field) => match check_kind(field.kind, value) {
                        Ok(()) => {
                            clean.insert(key.clone(), value.clone());
                        }
                        Err(msg) => {
                            complete = false;
                            self.push(format!("{prefix}.{key}"), msg);
                        }
                    },
                }
            }
            for field in schema.fields.iter().filter(|f| f.required) {
                if !table.contains_key(field.key) {
                    complete = false;
                    self.push(format!("{prefix}.{}", field.key), "required key is missing");
                }
            }
            if !complete {
                continue;
            }
            let Some(mut spec) =
                self.deserialize_section::<MaterialSpec>(&toml::Value::Table(clean), &prefix)
            else {
                continue;
            };
            let mut issues = Vec::new();
            validate_material(&spec, &mut issues);
            for mut i in issues {
                if let Some(rest) = i.key.strip_prefix("material.") {
                    i.key = format!("{prefix}.{rest}");
                }
                out.push(i);
            }
            spec.resolve();
            regions.push(RegionMaterial {
                region: region.clone(),
                material: spec,
            });
        }
        let incompressible: Vec<bool> = tables
            .iter()
            .map(|(_, t)| {
                matches!(t.get("model"), Some(toml::Value::String(m)) if m == "mooney_rivlin_incompressible")
            })
            .collect();
        if incompressible.iter().any(|&b| b) && !incompressible.iter().all(|&b| b) {
            out.push(issue(
                "material",
                "[[material]] regions mix incompressible and compressible models: the pressure \
                 field is common to the whole mesh, use one kind",
            ));
        }
        regions
    }

    /// Deserialize a required section; `None` if absent or incomplete (already reported).
    fn required_section<T: DeserializeOwned>(
        &mut self,
        clean: &toml::Table,
        name: &str,
    ) -> Option<T> {
        let value = clean.get(name)?;
        let sec = section_schema(name)?;
        if let toml::Value::Table(t) = value {
            if sec
                .fields
                .iter()
                .any(|f| f.required && !t.contains_key(f.key))
            {
                return None; // missing or ill-typed required key: already reported
            }
        }
        self.deserialize_section(value, name)
    }

    /// Deserialize an optional section without defaults: `Some(None)` if absent, `Some(Some(_))`
    /// if present and valid, `None` if present but incomplete or ill-typed (already reported).
    fn present_section<T: DeserializeOwned>(
        &mut self,
        clean: &toml::Table,
        name: &str,
    ) -> Option<Option<T>> {
        if clean.contains_key(name) {
            self.required_section(clean, name).map(Some)
        } else {
            Some(None)
        }
    }

    /// Deserialize an optional section (defaults when absent).
    fn optional_section<T: DeserializeOwned + Default>(
        &mut self,
        clean: &toml::Table,
        name: &str,
    ) -> Option<T> {
        match clean.get(name) {
            None => {
                let present_but_bad = self
                    .issues
                    .iter()
                    .any(|i| i.key == name && i.origin == Origin::Auto);
                if present_but_bad {
                    None
                } else {
                    Some(T::default())
                }
            }
            Some(value) => self.deserialize_section(value, name),
        }
    }

    fn deserialize_section<T: DeserializeOwned>(
        &mut self,
        value: &toml::Value,
        name: &str,
    ) -> Option<T> {
        match value.clone().try_into::<T>() {
            Ok(v) => Some(v),
            Err(e) => {
                // Backstop: the schema pass should have caught everything serde rejects.
                let key = key_from_de_error(&e, name);
                self.push(key, e.message().trim_end().to_string());
                None
            }
        }
    }

    /// Where a key comes from: `(None, true)` for an override; else its line in the file (or
    /// that of its nearest ancestor). A key found nowhere in the file whose section was touched
    /// by an override (e.g. a section created by `--set`) counts as an override.
    fn origin_of(&self, key: &str) -> (Option<usize>, bool) {
        if self.overridden.contains(key) {
            return (None, true);
        }
        match self.locator.locate(key) {
            Some(line) => (Some(line), false),
            None => {
                let section = key.split('.').next().unwrap_or(key);
                let touched = self
                    .overridden
                    .iter()
                    .any(|k| k.split('.').next() == Some(section));
                (None, touched)
            }
        }
    }

    fn into_errors(self) -> SceneErrors {
        let mut errors: Vec<SceneError> = self
            .issues
            .iter()
            .map(|i| {
                let (line, is_override) = match i.origin {
                    Origin::Override => (None, true),
                    Origin::Auto => match (self.origin_of(&i.key), i.anchor) {
                        ((None, false), Some(anchor)) => self.origin_of(anchor),
                        (found, _) => found,
                    },
                };
                let source_name = if is_override {
                    format!("{}{OVERRIDE_TAG}", self.source_name)
                } else {
                    self.source_name.to_string()
                };
                SceneError {
                    key: i.key.clone(),
                    line,
                    message: i.message.clone(),
                    source_name,
                }
            })
            .collect();
        // File errors in line order, then those without a line (overrides last).
        errors.sort_by_key(|e| (e.line.is_none(), e.is_override(), e.line));
        SceneErrors(errors)
    }
}

fn table_has(doc: &toml::Table, section: &str, key: &str) -> bool {
    matches!(doc.get(section), Some(toml::Value::Table(t)) if t.contains_key(key))
}

/// Parse an override value as a TOML value; fall back to the bare text as a string. For
/// string-valued keys, unquoted text is always taken literally (so `scene.name=2024` works).
fn parse_override_value(text: &str, kind: Kind) -> toml::Value {
    let parsed = format!("v = {text}")
        .parse::<toml::Table>()
        .ok()
        .filter(|t| t.len() == 1)
        .and_then(|mut t| t.remove("v"));
    match (parsed, kind) {
        // `--set output.sinks=csv,mcap` (no brackets or quotes) is a comma-separated list.
        (Some(v @ toml::Value::Array(_)), Kind::KeywordList(_)) => v,
        (_, Kind::KeywordList(_)) => toml::Value::Array(
            text.split(',')
                .map(|w| toml::Value::String(w.trim().trim_matches('"').to_string()))
                .collect(),
        ),
        (Some(v @ toml::Value::String(_)), _) => v,
        (_, Kind::Str | Kind::Keyword(_)) => toml::Value::String(text.to_string()),
        (Some(v), _) => v,
        (None, _) => toml::Value::String(text.to_string()),
    }
}

fn key_from_de_error(e: &toml::de::Error, section: &str) -> String {
    let msg = e.message();
    for prefix in ["unknown field `", "missing field `"] {
        if let Some(rest) = msg.strip_prefix(prefix) {
            if let Some(end) = rest.find('`') {
                return format!("{section}.{}", &rest[..end]);
            }
        }
    }
    // The Display of a value-deserialization error ends with "in `key`".
    let shown = e.to_string();
    if let Some(pos) = shown.rfind("in `") {
        let rest = &shown[pos + 4..];
        if let Some(end) = rest.find('`') {
            return format!("{section}.{}", &rest[..end]);
        }
    }
    section.to_string()
}

fn line_of_offset(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    text.as_bytes()[..end]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

// ---------------------------------------------------------------------------------------------
// Validation of the typed sections
// ---------------------------------------------------------------------------------------------

fn positive(x: f64) -> bool {
    x.is_finite() && x > 0.0
}

fn validate_info(s: &SceneInfo, out: &mut Vec<Issue>) {
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

fn validate_geometry(g: &Geometry, out: &mut Vec<Issue>) {
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

/// `[mesh] file` and its companions: the group names only with a file, the generator's keys
/// not with one, `[[material]]` only with one.
fn validate_mesh_file(
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
            for key in ["n_r", "n_theta", "order", "grading_r", "grading_theta"] {
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

fn validate_mesh(m: &MeshSpec, out: &mut Vec<Issue>) {
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

fn validate_material(m: &MaterialSpec, out: &mut Vec<Issue>) {
    if let Some(ve) = &m.viscoelastic {
        if let Err(msg) = ve.build() {
            let key = if crate::material::ViscoModel::from_name(&ve.model).is_none() {
                "model"
            } else if msg.starts_with("gamma") {
                "gamma"
            } else {
                "prony"
            };
            out.push(issue(format!("material.viscoelastic.{key}"), msg));
        }
    }
    let model = m.model;
    if !positive(m.rho) {
        out.push(issue(
            "material.rho",
            format!("density must be > 0, got {}", m.rho),
        ));
    }
    let given: [(&str, bool); 6] = [
        ("mu", m.mu.is_some()),
        ("lambda", m.lambda.is_some()),
        ("c1", m.c1.is_some()),
        ("c2", m.c2.is_some()),
        ("kappa", m.kappa.is_some()),
        ("formulation", m.formulation.is_some()),
    ];
    let allowed = MaterialSpec::keys_of(model);
    for (key, present) in given {
        if present && !allowed.contains(&key) {
            out.push(issue(
                format!("material.{key}"),
                format!(
                    "`{key}` is not a parameter of model \"{model}\" (its keys are model, {})",
                    allowed.join(", ")
                ),
            ));
        }
    }
    let need_positive = |key: &str, v: Option<f64>, what: &str, out: &mut Vec<Issue>| match v {
        None => out.push(issue(
            format!("material.{key}"),
            format!("required for model \"{model}\" ({what})"),
        )),
        Some(x) if !positive(x) => out.push(issue(
            format!("material.{key}"),
            format!("{what} must be > 0, got {x}"),
        )),
        Some(_) => {}
    };
    match model {
        MaterialModel::NeoHookean => {
            need_positive("mu", m.mu, "Lamé shear modulus", out);
            need_positive("lambda", m.lambda, "Lamé first parameter", out);
        }
        MaterialModel::MooneyRivlin | MaterialModel::MooneyRivlinIncompressible => {
            need_positive("c1", m.c1, "Mooney–Rivlin C1", out);
            match m.c2 {
                None => out.push(issue(
                    "material.c2",
                    format!("required for model \"{model}\" (Mooney–Rivlin C2; may be 0)"),
                )),
                Some(x) if !(x.is_finite() && x >= 0.0) => out.push(issue(
                    "material.c2",
                    format!("Mooney–Rivlin C2 must be >= 0, got {x}"),
                )),
                Some(_) => {}
            }
            if model == MaterialModel::MooneyRivlin {
                need_positive("kappa", m.kappa, "bulk modulus", out);
            } else {
                match m.formulation.unwrap_or_default() {
                    Formulation::Perturbed => {
                        if let Some(k) = m.kappa {
                            if !positive(k) {
                                out.push(issue(
                                    "material.kappa",
                                    format!("bulk modulus must be > 0, got {k}"),
                                ));
                            }
                        }
                    }
                    Formulation::Exact => {
                        if m.kappa.is_some() {
                            out.push(issue(
                                "material.kappa",
                                "`kappa` is only used with formulation = \"perturbed\" \
                                 (the exact formulation has no bulk modulus)",
                            ));
                        }
                    }
                }
            }
        }
    }
}

fn validate_motion(mode: Option<Mode>, m: &Motion, omega_given: bool, out: &mut Vec<Issue>) {
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

fn validate_motion_ramp(mode: Option<Mode>, m: &Motion, out: &mut Vec<Issue>) {
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
fn validate_motion_control(
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
            if let Some(i) = integrator.filter(|i| *i != IntegratorName::GeneralizedAlpha) {
                out.push(issue(
                    "motion.control",
                    format!(
                        "torque control needs time.integrator = \"generalized_alpha\" (the hub \
                         angle is solved in the implicit step), got \"{i}\""
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

/// A ramp time of `[road]`: finite, >= 0, and 0 in `static` (which has no time).
fn validate_road_ramp(key: &str, value: f64, what: &str, mode: Option<Mode>, out: &mut Vec<Issue>) {
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

fn validate_road(r: &RoadSpec, mode: Option<Mode>, g: Option<&Geometry>, out: &mut Vec<Issue>) {
    validate_road_ramp("ramp", r.ramp, "road ramp", mode, out);
    if let Some(v) = r.v0_ramp {
        validate_road_ramp("v0_ramp", v, "road-speed ramp", mode, out);
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
                format!("load (force per unit thickness) must be > 0, got {l}"),
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

fn validate_contact(c: &ContactSpec, mode: Option<Mode>, out: &mut Vec<Issue>) {
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

fn validate_friction(f: &FrictionSpec, out: &mut Vec<Issue>) {
    let law = f.law;
    let given: [(&str, Option<f64>); 7] = [
        ("mu", f.mu),
        ("eps", f.eps),
        ("mu_s", f.mu_s),
        ("mu_k", f.mu_k),
        ("v_s", f.v_s),
        ("c_t", f.c_t),
        ("m_t", f.m_t),
    ];
    let allowed = FrictionSpec::keys_of(law);
    for (key, value) in given {
        if value.is_some() && !allowed.contains(&key) {
            let keys = if allowed.is_empty() {
                format!("law \"{law}\" takes no other key")
            } else {
                format!("its keys are law, {}", allowed.join(", "))
            };
            out.push(issue(
                format!("friction.{key}"),
                format!("`{key}` is not a parameter of friction law \"{law}\" ({keys})"),
            ));
        }
    }
    // (key, value, what, lower bound, whether the bound is strict)
    let need = |key: &str,
                v: Option<f64>,
                what: &str,
                lo: f64,
                strict: bool,
                out: &mut Vec<Issue>| {
        match v {
            None => out.push(issue(
                format!("friction.{key}"),
                format!("required for friction law \"{law}\" ({what})"),
            )),
            Some(x) if !(x.is_finite() && if strict { x > lo } else { x >= lo }) => {
                let op = if strict { ">" } else { ">=" };
                out.push(issue(
                    format!("friction.{key}"),
                    format!("{what} must be {op} {lo}, got {x}"),
                ));
            }
            Some(_) => {}
        }
    };
    const EPS: &str = "slip-velocity regularisation ε";
    match law {
        FrictionLawName::None => {}
        FrictionLawName::CoulombTanh | FrictionLawName::CoulombLinear => {
            need("mu", f.mu, "friction coefficient μ", 0.0, false, out);
            need("eps", f.eps, EPS, 0.0, true, out);
        }
        FrictionLawName::RateDependent => {
            need(
                "mu_s",
                f.mu_s,
                "static friction coefficient μ_s",
                0.0,
                false,
                out,
            );
            need(
                "mu_k",
                f.mu_k,
                "kinetic friction coefficient μ_k",
                0.0,
                false,
                out,
            );
            need("v_s", f.v_s, "decay velocity v_s", 0.0, true, out);
            need("eps", f.eps, EPS, 0.0, true, out);
            if let (Some(mu_s), Some(mu_k)) = (f.mu_s, f.mu_k) {
                if mu_s >= 0.0 && mu_k >= 0.0 && mu_k > mu_s {
                    out.push(issue(
                        "friction.mu_k",
                        format!(
                            "kinetic coefficient μ_k = {mu_k} must not exceed the static \
                             coefficient μ_s = {mu_s}"
                        ),
                    ));
                }
            }
        }
        FrictionLawName::OdenMartins => {
            need(
                "c_t",
                f.c_t,
                "tangential compliance coefficient c_t",
                0.0,
                false,
                out,
            );
            need(
                "m_t",
                f.m_t,
                "tangential compliance exponent m_t",
                1.0,
                false,
                out,
            );
            need("eps", f.eps, EPS, 0.0, true, out);
        }
    }
}

fn validate_stick_slip(s: &StickSlipSpec, out: &mut Vec<Issue>) {
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

fn validate_time(t: &TimeSpec, mass_given: bool, out: &mut Vec<Issue>) {
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
fn validate_steady_extraction(
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

/// Which mode-dependent sections a scene has; `friction_law` is `None` when it cannot be
/// checked (an invalid `law` already reported).
struct SectionsGiven {
    road: bool,
    contact: bool,
    stick_slip: bool,
    time: bool,
    continuation: bool,
    friction_law: Option<FrictionLawName>,
}

fn validate_mode_sections(mode: Mode, given: &SectionsGiven, out: &mut Vec<Issue>) {
    const ROAD_MODES: &str = "\"static\" and \"transient\"";
    let unused = |section: &str, used_by: &str, out: &mut Vec<Issue>| {
        out.push(issue(
            section,
            format!(
                "section [{section}] is not used by analysis mode \"{mode}\" (only by \
                 {used_by}); remove it"
            ),
        ));
    };
    let missing = |section: &str, needs: &str, out: &mut Vec<Issue>| {
        out.push(issue_near(
            section,
            format!(
                "required section [{section}] is missing: analysis mode \"{mode}\" needs it \
                 ({needs})"
            ),
            "analysis.mode",
        ));
    };
    let no_contact_friction = |law: FrictionLawName, what: &str, out: &mut Vec<Issue>| {
        out.push(issue(
            "friction.law",
            format!(
                "analysis mode \"{mode}\" {what}, hence no friction: law must be \"none\" (or \
                 omit [friction]), got \"{law}\""
            ),
        ));
    };
    if given.continuation && mode != Mode::Steady {
        unused("continuation", "\"steady\"", out);
    }
    if given.time && !matches!(mode, Mode::Transient | Mode::Steady) {
        let note = if mode == Mode::StickSlip {
            "; the oscillator's t_end and tolerances are in [stick_slip]"
        } else {
            ""
        };
        unused("time", &format!("\"transient\"{note}"), out);
    }
    match mode {
        Mode::Spinning => {
            if given.road {
                unused("road", ROAD_MODES, out);
            }
            if given.contact {
                unused("contact", ROAD_MODES, out);
            }
            if given.stick_slip {
                unused("stick_slip", "\"stick_slip\"", out);
            }
            if let Some(law) = given.friction_law.filter(|l| *l != FrictionLawName::None) {
                no_contact_friction(law, "has no road contact", out);
            }
        }
        Mode::Static => {
            if !given.road {
                missing("road", "disp or load", out);
            }
            if !given.contact {
                missing("contact", "c_n", out);
            }
            if given.stick_slip {
                unused("stick_slip", "\"stick_slip\"", out);
            }
        }
        Mode::StickSlip => {
            if given.road {
                unused("road", ROAD_MODES, out);
            }
            if given.contact {
                unused("contact", ROAD_MODES, out);
            }
            if !given.stick_slip {
                missing(
                    "stick_slip",
                    "mass, stiffness, normal_force, belt_speed, t_end",
                    out,
                );
            }
            match given.friction_law {
                Some(
                    FrictionLawName::CoulombTanh
                    | FrictionLawName::CoulombLinear
                    | FrictionLawName::RateDependent,
                )
                | None => {}
                Some(law) => out.push(issue_near(
                    "friction.law",
                    format!(
                        "analysis mode \"stick_slip\" needs a friction law \"coulomb_tanh\", \
                         \"coulomb_linear\" or \"rate_dependent\" in [friction], got \"{law}\"{}",
                        if law == FrictionLawName::OdenMartins {
                            " (oden_martins needs a penetration, which this mode does not have)"
                        } else {
                            ""
                        }
                    ),
                    "analysis.mode",
                )),
            }
        }
        Mode::Transient | Mode::Steady => {
            if !given.time && mode == Mode::Transient {
                missing("time", "dt, t_end", out);
            }
            if given.stick_slip {
                unused("stick_slip", "\"stick_slip\"", out);
            }
            // Road contact needs both the road and the contact law; neither = no contact.
            match (given.road, given.contact) {
                (true, false) => out.push(issue_near(
                    "contact",
                    format!(
                        "analysis mode \"{mode}\" has [road] but no [contact]: give both \
                         (rolling on the road) or neither (spinning up without contact); \
                         [contact] needs c_n"
                    ),
                    "road",
                )),
                (false, true) => out.push(issue_near(
                    "road",
                    format!(
                        "analysis mode \"{mode}\" has [contact] but no [road]: give both \
                         (rolling on the road) or neither (spinning up without contact); [road] \
                         needs disp or load"
                    ),
                    "contact",
                )),
                _ => {}
            }
            if !given.road && !given.contact {
                if let Some(law) = given.friction_law.filter(|l| *l != FrictionLawName::None) {
                    no_contact_friction(
                        law,
                        "without [road] and [contact] has no road contact",
                        out,
                    );
                }
            }
        }
    }
}

fn validate_continuation(
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

fn validate_solver(s: &SolverSpec, out: &mut Vec<Issue>) {
    if !(s.tolerance.is_finite() && s.tolerance > 0.0 && s.tolerance < 1.0) {
        out.push(issue(
            "solver.tolerance",
            format!("relative tolerance must be in (0, 1), got {}", s.tolerance),
        ));
    }
    if s.max_iterations < 1 {
        out.push(issue("solver.max_iterations", "must be >= 1, got 0"));
    }
    if s.load_steps < 1 {
        out.push(issue("solver.load_steps", "must be >= 1, got 0"));
    }
}

fn validate_output(s: &OutputSpec, out: &mut Vec<Issue>) {
    if s.every < 1 {
        out.push(issue("output.every", "must be >= 1, got 0"));
    }
    if !(s.displacement_scale.is_finite() && s.displacement_scale > 0.0) {
        out.push(issue(
            "output.displacement_scale",
            format!("must be a finite number > 0, got {}", s.displacement_scale),
        ));
    }
    if s.vtu_compression != VtuCompression::None && s.vtu_format == VtuFormat::Ascii {
        out.push(issue(
            "output.vtu_compression",
            "applies to vtu_format = \"binary\" only (the ascii format is not compressed)",
        ));
    }
    for (i, k) in s.sinks.iter().enumerate() {
        if s.sinks[..i].contains(k) {
            out.push(issue("output.sinks", format!("\"{k}\" is listed twice")));
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Line locator
// ---------------------------------------------------------------------------------------------

/// Where each table header and key is defined in the original text (1-based lines).
#[derive(Debug, Default)]
struct Locator {
    entries: Vec<(Vec<String>, usize)>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum MultiLine {
    Basic,
    Literal,
}

#[derive(Debug, Default)]
struct ScanState {
    multiline: Option<MultiLine>,
    depth: usize,
}

impl Locator {
    fn new(text: &str) -> Locator {
        let mut entries = Vec::new();
        let mut table: Vec<String> = Vec::new();
        let mut st = ScanState::default();
        for (i, line) in text.lines().enumerate() {
            let lineno = i + 1;
            if st.multiline.is_some() || st.depth > 0 {
                scan_value(line, &mut st);
                continue;
            }
            let t = line.trim_start();
            if t.is_empty() || t.starts_with('#') {
                continue;
            }
            if let Some(h) = t.strip_prefix('[') {
                let (h, close) = match h.strip_prefix('[') {
                    Some(h2) => (h2, "]]"),
                    None => (h, "]"),
                };
                if let Some((path, after)) = parse_key_path(h) {
                    if after.trim_start().starts_with(close) {
                        entries.push((path.clone(), lineno));
                        table = path;
                    }
                }
                continue;
            }
            if let Some((path, after)) = parse_key_path(t) {
                if let Some(value) = after.trim_start().strip_prefix('=') {
                    let mut full = table.clone();
                    for seg in path {
                        full.push(seg);
                        entries.push((full.clone(), lineno));
                    }
                    scan_value(value, &mut st);
                }
            }
        }
        Locator { entries }
    }

    /// Line of a dotted key; for a key not in the text, the line where its nearest ancestor
    /// (e.g. the section header) is defined; `None` if none is.
    fn locate(&self, dotted: &str) -> Option<usize> {
        if dotted.is_empty() {
            return None;
        }
        let target: Vec<&str> = dotted.split('.').collect();
        let mut best: Option<(usize, usize)> = None; // (matched length, line)
        for (path, line) in &self.entries {
            if path.len() > target.len() || path.iter().zip(&target).any(|(a, b)| a != b) {
                continue;
            }
            if best.is_none_or(|(len, _)| path.len() > len) {
                best = Some((path.len(), *line));
            }
        }
        best.map(|(_, line)| line)
    }

    /// The longest key path defined on a line, dotted.
    fn key_at_line(&self, line: usize) -> Option<String> {
        self.entries
            .iter()
            .filter(|(_, l)| *l == line)
            .max_by_key(|(p, _)| p.len())
            .map(|(p, _)| p.join("."))
    }
}

/// Scan (the rest of) a value on one line, tracking strings, comments and bracket depth.
fn scan_value(s: &str, st: &mut ScanState) {
    let b = s.as_bytes();
    let n = b.len();
    let mut i = 0;
    while i < n {
        if let Some(ml) = st.multiline {
            let delim: &[u8] = match ml {
                MultiLine::Basic => b"\"\"\"",
                MultiLine::Literal => b"'''",
            };
            let mut closed = false;
            while i < n {
                if ml == MultiLine::Basic && b[i] == b'\\' {
                    i += 2;
                    continue;
                }
                if b[i..].starts_with(delim) {
                    i += 3;
                    // Up to two extra quotes may belong to the content.
                    while i < n && b[i] == delim[0] {
                        i += 1;
                    }
                    closed = true;
                    break;
                }
                i += 1;
            }
            if !closed {
                return;
            }
            st.multiline = None;
            continue;
        }
        match b[i] {
            b'#' => return,
            b'"' => {
                if b[i..].starts_with(b"\"\"\"") {
                    st.multiline = Some(MultiLine::Basic);
                    i += 3;
                    continue;
                }
                i += 1;
                while i < n && b[i] != b'"' {
                    if b[i] == b'\\' {
                        i += 1;
                    }
                    i += 1;
                }
            }
            b'\'' => {
                if b[i..].starts_with(b"'''") {
                    st.multiline = Some(MultiLine::Literal);
                    i += 3;
                    continue;
                }
                i += 1;
                while i < n && b[i] != b'\'' {
                    i += 1;
                }
            }
            b'[' | b'{' => st.depth += 1,
            b']' | b'}' => st.depth = st.depth.saturating_sub(1),
            _ => {}
        }
        i += 1;
    }
}

/// Parse a (possibly dotted, possibly quoted) TOML key at the start of `s`.
fn parse_key_path(s: &str) -> Option<(Vec<String>, &str)> {
    let mut segs = Vec::new();
    let mut rest = s;
    loop {
        rest = rest.trim_start_matches([' ', '\t']);
        let (seg, r) = if let Some(r) = rest.strip_prefix('"') {
            parse_basic_string(r)?
        } else if let Some(r) = rest.strip_prefix('\'') {
            let end = r.find('\'')?;
            (r[..end].to_string(), &r[end + 1..])
        } else {
            let end = rest
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == '-'))
                .unwrap_or(rest.len());
            if end == 0 {
                return None;
            }
            (rest[..end].to_string(), &rest[end..])
        };
        segs.push(seg);
        rest = r.trim_start_matches([' ', '\t']);
        match rest.strip_prefix('.') {
            Some(r) => rest = r,
            None => return Some((segs, rest)),
        }
    }
}

/// Parse the body of a basic string (after the opening quote); returns it and the rest after the
/// closing quote.
fn parse_basic_string(s: &str) -> Option<(String, &str)> {
    let mut out = String::new();
    let mut chars = s.char_indices();
    while let Some((i, c)) = chars.next() {
        match c {
            '"' => return Some((out, &s[i + 1..])),
            '\\' => {
                let (_, e) = chars.next()?;
                out.push(match e {
                    'n' => '\n',
                    't' => '\t',
                    'r' => '\r',
                    other => other,
                });
            }
            other => out.push(other),
        }
    }
    None
}

// ---------------------------------------------------------------------------------------------
// Tests
// ---------------------------------------------------------------------------------------------

#[cfg(test)]
mod tests {
    use super::*;

    const INCOMPRESSIBLE: &str = include_str!("../../scenarios/spinning_incompressible.toml");
    const NEO_HOOKEAN: &str = include_str!("../../scenarios/spinning_neo_hookean.toml");
    const MOONEY_RIVLIN: &str = include_str!("../../scenarios/spinning_mooney_rivlin.toml");
    const FRICTIONLESS: &str = include_str!("../../scenarios/indentation_frictionless.toml");
    const FRICTION: &str = include_str!("../../scenarios/indentation_friction.toml");
    const LOAD_CONTROL: &str = include_str!("../../scenarios/indentation_load_control.toml");
    const STICK_SLIP: &str = include_str!("../../scenarios/stick_slip.toml");
    const ODEN: &str = include_str!("../../scenarios/oden_hollow_cylinder.toml");
    const ROLLING_FRICTIONLESS: &str = include_str!("../../scenarios/rolling_frictionless.toml");
    const FREE_ROLLING: &str = include_str!("../../scenarios/free_rolling.toml");
    const STEADY_SWEEP: &str = include_str!("../../scenarios/oden_steady_sweep.toml");
    const BRAKING: &str = include_str!("../../scenarios/braking.toml");

    const MINIMAL: &str = r#"
[scene]
name = "minimal"

[geometry]
ri = 1.0
ro = 2.0

[material]
model = "neo_hookean"
rho = 0.027
mu = 200.0
lambda = 1800.0

[analysis]
mode = "spinning"

[motion]
omega = 20.0
"#;

    fn load(text: &str) -> Result<Scene, SceneErrors> {
        Scene::from_toml_str(text, "test.toml", &[])
    }

    fn load_with(text: &str, overrides: &[&str]) -> Result<Scene, SceneErrors> {
        let ov: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
        Scene::from_toml_str(text, "test.toml", &ov)
    }

    fn errors(text: &str) -> SceneErrors {
        match load(text) {
            Ok(s) => panic!("expected errors, got {s:?}"),
            Err(e) => e,
        }
    }

    fn errors_with(text: &str, overrides: &[&str]) -> SceneErrors {
        match load_with(text, overrides) {
            Ok(s) => panic!("expected errors, got {s:?}"),
            Err(e) => e,
        }
    }

    /// 1-based line of the first line of `text` that starts with `prefix` (after whitespace).
    fn line_of(text: &str, prefix: &str) -> usize {
        text.lines()
            .position(|l| l.trim_start().starts_with(prefix))
            .map(|i| i + 1)
            .unwrap_or_else(|| panic!("no line starts with {prefix:?}"))
    }

    fn replace_line(text: &str, prefix: &str, new: &str) -> String {
        let mut found = false;
        let out: Vec<String> = text
            .lines()
            .map(|l| {
                if !found && l.trim_start().starts_with(prefix) {
                    found = true;
                    new.to_string()
                } else {
                    l.to_string()
                }
            })
            .collect();
        assert!(found, "no line starts with {prefix:?}");
        out.join("\n") + "\n"
    }

    #[test]
    fn incompressible_scene_parses() {
        let s = load(INCOMPRESSIBLE).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.scene.name, "spinning_incompressible");
        assert_eq!(s.scene.units, "in-lbf-s");
        assert_eq!(s.geometry.ri, 1.0);
        assert_eq!(s.geometry.ro, 2.0);
        assert_eq!(s.mesh.n_r, 4);
        assert_eq!(s.mesh.n_theta, 48);
        assert_eq!(s.mesh.order, 2);
        assert_eq!(s.material.model, MaterialModel::MooneyRivlinIncompressible);
        assert_eq!(s.material.rho, 0.027);
        assert_eq!(
            s.material.params(),
            Some(MaterialParams::MooneyRivlinIncompressible {
                c1: 80.0,
                c2: 20.0,
                formulation: Formulation::Exact,
                kappa: None
            })
        );
        assert_eq!(s.material.formulation, Some(Formulation::Exact));
        assert_eq!(s.material.shear_modulus(), Some(200.0));
        assert_eq!(s.material.bulk_modulus(), None);
        assert!(s.material.is_incompressible());
        assert_eq!(s.analysis.mode, Mode::Spinning);
        assert_eq!(s.motion.omega, 20.0);
        // The density is chosen so that c_R / Ro is about the paper's top speed, 395 rpm.
        let c_r = 0.955 * s.shear_wave_speed().unwrap_or(0.0);
        let rpm = c_r / s.geometry.ro * 60.0 / (2.0 * std::f64::consts::PI);
        assert!((rpm - 395.0).abs() < 10.0, "critical spin {rpm} rpm");
    }

    #[test]
    fn neo_hookean_scene_parses() {
        let s = load(NEO_HOOKEAN).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.scene.name, "spinning_neo_hookean");
        assert_eq!(
            s.material.params(),
            Some(MaterialParams::NeoHookean {
                mu: 200.0,
                lambda: 1800.0
            })
        );
        assert_eq!(s.material.rho, 0.027);
        assert_eq!(s.motion.omega, 20.0);
        assert_eq!((s.geometry.ri, s.geometry.ro), (1.0, 2.0));
        assert!(!s.material.is_incompressible());
        let k = s.material.bulk_modulus().unwrap_or(0.0);
        assert!((k - (1800.0 + 400.0 / 3.0)).abs() < 1e-9);
    }

    #[test]
    fn mooney_rivlin_scene_parses() {
        let s = load(MOONEY_RIVLIN).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.scene.name, "spinning_mooney_rivlin");
        assert_eq!(
            s.material.params(),
            Some(MaterialParams::MooneyRivlin {
                c1: 80.0,
                c2: 20.0,
                kappa: 2000.0
            })
        );
        assert_eq!(s.material.resolved_kappa(), Some(2000.0));
        assert_eq!(s.material.resolved_formulation(), None);
        assert_eq!(s.material.shear_modulus(), Some(200.0));
    }

    #[test]
    fn defaults_are_filled() {
        let s = load(MINIMAL).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.scene.description, "");
        assert_eq!(s.scene.units, DEFAULT_UNITS);
        assert_eq!(s.mesh, MeshSpec::default());
        assert_eq!(s.mesh.n_r, 4);
        assert_eq!(s.mesh.n_theta, 32);
        assert_eq!(s.mesh.order, 2);
        assert_eq!(s.mesh.grading_r, 1.0);
        assert_eq!(s.mesh.grading_theta, 0.0);
        assert_eq!(s.solver.tolerance, 1e-10);
        assert_eq!(s.solver.max_iterations, 25);
        assert_eq!(s.solver.load_steps, 4);
        assert_eq!(s.solver.max_cutbacks, 10);
        assert_eq!(s.solver.linear, LinearChoice::Auto);
        assert_eq!(s.solver.threads, 0);
        assert!(s.solver.line_search);
        assert_eq!(s.output.sinks, DEFAULT_SINKS);
        assert_eq!(s.output.every, 1);
        assert_eq!(s.material.formulation, None);
        assert_eq!(s.material.kappa, None);
        assert!(s.validate().is_ok());
    }

    #[test]
    fn partial_sections_fill_remaining_defaults() {
        let text = format!("{MINIMAL}\n[mesh]\nn_r = 6\n\n[solver]\nlinear = \"lu\"\n");
        let s = load(&text).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.mesh.n_r, 6);
        assert_eq!(s.mesh.n_theta, 32);
        assert_eq!(s.solver.linear, LinearChoice::Lu);
        assert_eq!(s.solver.max_iterations, 25);
    }

    #[test]
    fn perturbed_kappa_default_is_resolved() {
        let text = r#"
[scene]
name = "p"
[geometry]
ri = 1
ro = 2
[material]
model = "mooney_rivlin_incompressible"
rho = 0.027
c1 = 80
c2 = 20
formulation = "perturbed"
[analysis]
mode = "spinning"
[motion]
omega = 0
"#;
        let s = load(text).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.material.formulation, Some(Formulation::Perturbed));
        assert_eq!(s.material.kappa, Some(1e4 * 100.0));
        assert_eq!(s.material.resolved_kappa(), Some(1e6));
        // Integers are accepted for floats.
        assert_eq!(s.geometry.ri, 1.0);
        assert_eq!(s.motion.omega, 0.0);
        // Explicit kappa wins.
        let s2 = load_with(text, &["material.kappa=5000"]).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s2.material.kappa, Some(5000.0));
    }

    #[test]
    fn unknown_key_rejected_with_name_and_line() {
        let text = replace_line(MINIMAL, "lambda", "lambda = 1800.0\nlamda = 3.0  # typo");
        let e = errors(&text);
        let err = e.find("material.lamda").unwrap_or_else(|| panic!("{e}"));
        assert_eq!(err.line, Some(line_of(&text, "lamda")));
        assert!(err.message.contains("unknown key"), "{}", err.message);
        let shown = err.to_string();
        assert!(
            shown.starts_with(&format!(
                "test.toml:{}: key `material.lamda`",
                err.line.unwrap_or(0)
            )),
            "{shown}"
        );
        assert_eq!(e.0.len(), 1, "{e}");
    }

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

    #[test]
    fn unknown_section_rejected() {
        let text = format!("{MINIMAL}\n[adaptivity]\ntarget = 0.1\n");
        let e = errors(&text);
        let err = e.find("adaptivity").unwrap_or_else(|| panic!("{e}"));
        assert_eq!(err.line, Some(line_of(&text, "[adaptivity]")));
        assert!(err.message.contains("unknown section"));
    }

    #[test]
    fn wrong_type_rejected_naming_key() {
        let text = replace_line(MINIMAL, "ro =", "ro = \"two\"  # oops");
        let e = errors(&text);
        let err = e.find("geometry.ro").unwrap_or_else(|| panic!("{e}"));
        assert_eq!(err.line, Some(line_of(&text, "ro =")));
        assert!(err.message.contains("expected a number"), "{}", err.message);
        assert!(err.message.contains("\"two\""), "{}", err.message);

        let text = format!("{MINIMAL}\n[mesh]\nn_r = 2.5\norder = -1\n");
        let e = errors(&text);
        assert_eq!(
            e.find("mesh.n_r").and_then(|x| x.line),
            Some(line_of(&text, "n_r"))
        );
        assert_eq!(
            e.find("mesh.order").and_then(|x| x.line),
            Some(line_of(&text, "order"))
        );

        let text = replace_line(MINIMAL, "model", "model = \"ogden\"");
        let e = errors(&text);
        let err = e.find("material.model").unwrap_or_else(|| panic!("{e}"));
        assert!(err.message.contains("neo_hookean"), "{}", err.message);
        assert_eq!(err.line, Some(line_of(&text, "model")));
    }

    #[test]
    fn non_finite_float_rejected() {
        let text = replace_line(MINIMAL, "omega", "omega = nan");
        let e = errors(&text);
        assert!(e.has_key("motion.omega"), "{e}");
    }

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
    fn non_positive_moduli_and_density_rejected() {
        let text = replace_line(MINIMAL, "mu =", "mu = 0.0");
        let text = replace_line(&text, "rho =", "rho = -0.027");
        let e = errors(&text);
        assert_eq!(e.0.len(), 2, "{e}");
        assert_eq!(
            e.find("material.mu").and_then(|x| x.line),
            Some(line_of(&text, "mu ="))
        );
        assert_eq!(
            e.find("material.rho").and_then(|x| x.line),
            Some(line_of(&text, "rho ="))
        );
        // Sorted by line.
        assert!(e.0[0].line < e.0[1].line);

        let e = errors(&replace_line(MOONEY_RIVLIN, "c2 ", "c2 = -1.0"));
        assert!(e.has_key("material.c2"), "{e}");
        let e = errors(&replace_line(MOONEY_RIVLIN, "kappa", "kappa = 0"));
        assert!(e.has_key("material.kappa"), "{e}");
        // c2 = 0 is fine.
        assert!(load(&replace_line(MOONEY_RIVLIN, "c2 ", "c2 = 0.0")).is_ok());
    }

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

    #[test]
    fn scene_name_must_be_a_directory_name() {
        let e = errors(&replace_line(MINIMAL, "name", "name = \"my scene/1\""));
        assert!(e.has_key("scene.name"), "{e}");
        let e = errors(&replace_line(MINIMAL, "name", "name = \"\""));
        assert!(e.has_key("scene.name"), "{e}");
    }

    #[test]
    fn key_not_belonging_to_model_rejected() {
        // lambda with mooney_rivlin
        let text = replace_line(MOONEY_RIVLIN, "kappa", "kappa = 2000.0\nlambda = 1800.0");
        let e = errors(&text);
        assert_eq!(e.0.len(), 1, "{e}");
        let err = &e.0[0];
        assert_eq!(err.key, "material.lambda");
        assert_eq!(err.line, Some(line_of(&text, "lambda")));
        assert!(err.message.contains("not a parameter"), "{}", err.message);
        // kappa with the exact incompressible formulation
        let text = replace_line(INCOMPRESSIBLE, "c2 ", "c2 = 20.0\nkappa = 1e5");
        let e = errors(&text);
        assert!(e.has_key("material.kappa"), "{e}");
        // formulation with neo_hookean
        let e = errors(&replace_line(
            MINIMAL,
            "mu =",
            "mu = 200\nformulation = \"exact\"",
        ));
        assert!(e.has_key("material.formulation"), "{e}");
    }

    #[test]
    fn missing_required_keys_reported() {
        // Missing model parameter: line of the [material] header.
        let text = MINIMAL.replace("lambda = 1800.0\n", "");
        let e = errors(&text);
        let err = e.find("material.lambda").unwrap_or_else(|| panic!("{e}"));
        assert_eq!(err.line, Some(line_of(&text, "[material]")));
        assert!(err.message.contains("required"));
        // Missing schema-required key.
        let text = MINIMAL.replace("ro = 2.0\n", "");
        let e = errors(&text);
        let err = e.find("geometry.ro").unwrap_or_else(|| panic!("{e}"));
        assert_eq!(err.line, Some(line_of(&text, "[geometry]")));
        // Missing omega for spinning.
        let text = MINIMAL.replace("omega = 20.0\n", "");
        let e = errors(&text);
        assert!(e.has_key("motion.omega"), "{e}");
        // Missing section.
        let text = MINIMAL.replace("[analysis]\nmode = \"spinning\"\n", "");
        let e = errors(&text);
        let err = e.find("analysis").unwrap_or_else(|| panic!("{e}"));
        assert_eq!(err.line, None);
        assert!(err.message.contains("missing"));
    }

    #[test]
    fn multiple_errors_reported_together() {
        let text = r#"
[scene]
name = "many"
[geometry]
ri = 3.0          # >= ro
ro = 2.0
[mesh]
n_theta = 7
bogus = 1
[material]
model = "mooney_rivlin"
rho = 0.0
c1 = 80
c2 = 20
kappa = 2000
mu = 3
[analysis]
mode = "spinning"
[motion]
omega = -1.0
[solver]
linear = "qr"
"#;
        let e = errors(text);
        for key in [
            "geometry.ro",
            "mesh.n_theta",
            "mesh.bogus",
            "material.rho",
            "material.mu",
            "motion.omega",
            "solver.linear",
        ] {
            let err = e
                .find(key)
                .unwrap_or_else(|| panic!("missing {key} in\n{e}"));
            assert!(err.line.is_some(), "{err}");
        }
        assert_eq!(e.0.len(), 7, "{e}");
        let shown = e.to_string();
        assert_eq!(shown.lines().count(), 7, "{shown}");
        // Ordered by line.
        let lines: Vec<usize> = e.0.iter().filter_map(|x| x.line).collect();
        let mut sorted = lines.clone();
        sorted.sort_unstable();
        assert_eq!(lines, sorted);
    }

    #[test]
    fn ill_typed_required_key_reported_once() {
        let text = replace_line(MOONEY_RIVLIN, "c2 ", "c2 = \"20\"");
        let e = errors(&text);
        assert_eq!(e.0.len(), 1, "{e}");
        assert_eq!(e.0[0].key, "material.c2");
        assert!(e.0[0].message.contains("expected a number"), "{e}");
    }

    #[test]
    fn type_and_range_errors_in_different_sections_together() {
        let text = replace_line(MINIMAL, "ri =", "ri = \"one\"");
        let text = replace_line(&text, "mu =", "mu = -5");
        let e = errors(&text);
        assert!(e.has_key("geometry.ri"), "{e}");
        assert!(e.has_key("material.mu"), "{e}");
    }

    #[test]
    fn overrides_apply() {
        let s = load_with(
            INCOMPRESSIBLE,
            &[
                "mesh.n_r=8",
                " motion.omega = 30.5 ",
                "solver.linear=lu",
                "output.sinks=csv,mcap",
                "output.every=5",
                "scene.name=run2024",
                "scene.description=\"quoted text\"",
            ],
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.mesh.n_r, 8);
        assert_eq!(s.motion.omega, 30.5);
        assert_eq!(s.solver.linear, LinearChoice::Lu);
        assert_eq!(s.output.sinks, [Sink::Csv, Sink::Mcap]);
        assert_eq!(s.output.every, 5);
        assert_eq!(s.scene.name, "run2024");
        assert_eq!(s.scene.description, "quoted text");
        let s = load_with(MINIMAL, &["output.sinks=[\"rerun\"]"]).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.output.sinks, [Sink::Rerun]);
        let s = load_with(MINIMAL, &["output.sinks=[]"]).unwrap_or_else(|e| panic!("{e}"));
        assert!(s.output.sinks.is_empty());
        // A string-valued key takes an unquoted number literally.
        let s = load_with(MINIMAL, &["scene.name=2024"]).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.scene.name, "2024");
        // An override can create a section absent from the file.
        let s = load_with(MINIMAL, &["solver.threads=3"]).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.solver.threads, 3);
        // Switching the model by override.
        let s = load_with(
            MOONEY_RIVLIN,
            &[
                "material.model=mooney_rivlin_incompressible",
                "material.formulation=perturbed",
            ],
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            s.material.resolved_formulation(),
            Some(Formulation::Perturbed)
        );
        assert_eq!(s.material.kappa, Some(2000.0));
    }

    #[test]
    fn override_of_unknown_key_rejected() {
        let e = errors_with(MINIMAL, &["mesh.nr=8"]);
        assert_eq!(e.0.len(), 1, "{e}");
        let err = &e.0[0];
        assert_eq!(err.key, "mesh.nr");
        assert_eq!(err.line, None);
        assert!(err.is_override());
        assert!(err.message.contains("mesh.nr=8"), "{}", err.message);
        assert!(err.to_string().contains("(--set)"), "{err}");

        let e = errors_with(MINIMAL, &["adaptivity.target=0.1"]);
        assert_only(&e, "adaptivity.target", None);
        assert!(e.0[0].message.contains("unknown section"), "{e}");
        let e = errors_with(MINIMAL, &["time.dtt=0.1"]);
        assert_only(&e, "time.dtt", None);
        assert!(e.0[0].message.contains("keys of [time]"), "{e}");
        let e = errors_with(MINIMAL, &["n_r=8"]);
        assert!(e.0[0].is_override(), "{e}");
        let e = errors_with(MINIMAL, &["mesh.n_r"]);
        assert_eq!(e.0[0].key, "mesh.n_r");
        assert!(e.0[0].message.contains("malformed"), "{e}");
    }

    #[test]
    fn override_errors_show_set_instead_of_line() {
        let e = errors_with(INCOMPRESSIBLE, &["mesh.n_theta=7", "mesh.n_r=abc"]);
        assert_eq!(e.0.len(), 2, "{e}");
        for err in &e.0 {
            assert_eq!(err.line, None);
            assert!(err.is_override());
            assert!(
                err.to_string()
                    .starts_with(&format!("test.toml:(--set): key `{}`", err.key)),
                "{err}"
            );
        }
        assert!(e
            .find("mesh.n_r")
            .is_some_and(|x| x.message.contains("\"abc\"")));
        // A non-overridden key keeps its line from the file while another key is overridden.
        let text = replace_line(INCOMPRESSIBLE, "rho", "rho = -1.0");
        let e = errors_with(&text, &["geometry.ro=0.5"]);
        let rho = e.find("material.rho").unwrap_or_else(|| panic!("{e}"));
        assert_eq!(rho.line, Some(line_of(&text, "rho")));
        assert!(!rho.is_override());
        let ro = e.find("geometry.ro").unwrap_or_else(|| panic!("{e}"));
        assert!(ro.is_override(), "{ro}");
        assert!(ro.to_string().contains("(--set)"));
    }

    #[test]
    fn syntax_error_has_line() {
        let text = replace_line(MINIMAL, "ro =", "ro = ");
        let e = errors(&text);
        assert_eq!(e.0.len(), 1, "{e}");
        assert_eq!(e.0[0].line, Some(line_of(&text, "ro =")));
        let text = format!("{MINIMAL}[geometry]\nri = 1.0\n");
        let e = errors(&text);
        assert_eq!(e.0.len(), 1, "{e}");
        assert!(e.0[0].line.is_some());
        assert!(e.0[0].message.contains("duplicate"), "{e}");
    }

    #[test]
    fn round_trip_through_to_toml_string() {
        for text in [
            INCOMPRESSIBLE,
            NEO_HOOKEAN,
            MOONEY_RIVLIN,
            MINIMAL,
            FRICTIONLESS,
            FRICTION,
            LOAD_CONTROL,
            STICK_SLIP,
            ODEN,
            ROLLING_FRICTIONLESS,
            FREE_ROLLING,
            BRAKING,
            STEADY_SWEEP,
        ] {
            let s = load(text).unwrap_or_else(|e| panic!("{e}"));
            let out = s.to_toml_string();
            let back = Scene::from_toml_str(&out, "roundtrip", &[])
                .unwrap_or_else(|e| panic!("{e}\n{out}"));
            assert_eq!(back, s, "{out}");
            // Strict serde on its own, too.
            let direct: Scene = toml::from_str(&out).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(direct, s);
            assert!(
                out.contains("[solver]") && out.contains("tolerance"),
                "{out}"
            );
        }
        let s = load_with(
            INCOMPRESSIBLE,
            &[
                "material.formulation=perturbed",
                "scene.description=a \"quoted\" # thing",
            ],
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let out = s.to_toml_string();
        assert!(out.contains("kappa"), "{out}");
        let back = load(&out).unwrap_or_else(|e| panic!("{e}\n{out}"));
        assert_eq!(back, s);
    }

    #[test]
    fn output_sinks_are_checked() {
        let text = format!("{MINIMAL}\n[output]\nsinks = [\"csv\", \"hdf5\"]\nevery = 0\n");
        let e = load(&text).err().unwrap_or_else(|| panic!("accepted"));
        let sinks = e.find("output.sinks").unwrap_or_else(|| panic!("{e}"));
        assert!(
            sinks.message.contains("hdf5") && sinks.line.is_some(),
            "{e}"
        );
        assert!(e.has_key("output.every"), "{e}");
        let text = format!("{MINIMAL}\n[output]\nsinks = [\"csv\", \"csv\"]\n");
        let e = load(&text).err().unwrap_or_else(|| panic!("accepted"));
        assert!(
            e.find("output.sinks")
                .is_some_and(|x| x.message.contains("twice")),
            "{e}"
        );
        let e = errors_with(MINIMAL, &["output.sinks=csv,nope"]);
        assert!(
            e.find("output.sinks")
                .is_some_and(|x| x.message.contains("nope")),
            "{e}"
        );
        // Round trip of a non-default list.
        let s = load_with(MINIMAL, &["output.sinks=mcap,rerun", "output.every=3"])
            .unwrap_or_else(|e| panic!("{e}"));
        let back = load(&s.to_toml_string()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(back, s);
    }

    #[test]
    fn serde_itself_rejects_unknown_fields() {
        let text = format!("{MINIMAL}\n[output]\nevery = 2\npng = true\n");
        let r: Result<Scene, _> = toml::from_str(&text);
        let e = r.err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.contains("png"), "{e}");
    }

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
            &["generalized_alpha", "central_difference", "bdf", "sdirk"]
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
            model: MaterialModel::NeoHookean,
            rho: 1.0,
            mu: Some(1.0),
            lambda: Some(1.0),
            c1: Some(1.0),
            c2: Some(1.0),
            kappa: Some(1.0),
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
    fn locator_handles_comments_quotes_dotted_and_multiline() {
        let text = r#"# header comment [geometry]
title = """
[geometry]
ri = 99
"""
arr = [
  [1, 2],
  { ri = 3 },
]
[ "geometry" ]   # spaced, quoted header
"ri" = 1.0 # comment with ro = 5
ro = "a # not a comment" # real comment
mesh.n_r = 4
[material]
'rho'=1
"#;
        let loc = Locator::new(text);
        assert_eq!(loc.locate("geometry"), Some(10));
        assert_eq!(loc.locate("geometry.ri"), Some(11));
        assert_eq!(loc.locate("geometry.ro"), Some(12));
        assert_eq!(loc.locate("geometry.mesh.n_r"), Some(13));
        assert_eq!(loc.locate("material.rho"), Some(15));
        assert_eq!(loc.locate("material.mu"), Some(14)); // missing: section header
        assert_eq!(loc.locate("solver.tolerance"), None);
        assert_eq!(loc.locate("arr"), Some(6));
        assert_eq!(loc.key_at_line(12).as_deref(), Some("geometry.ro"));

        // Top-level dotted keys define their section implicitly.
        let loc = Locator::new("geometry.ri = 1\ngeometry.ro = 2\n");
        assert_eq!(loc.locate("geometry.ro"), Some(2));
        assert_eq!(loc.locate("geometry.x"), Some(1));
    }

    #[test]
    fn dotted_keys_in_file_get_lines() {
        let text = MINIMAL.replace("[motion]\nomega = 20.0\n", "motion.omega = -3.0\n");
        // Dotted top-level key after [analysis] means analysis.motion.omega: unknown key.
        let e = errors(&text);
        let err = e.find("analysis.motion").unwrap_or_else(|| panic!("{e}"));
        assert_eq!(err.line, Some(line_of(&text, "motion.omega")));
    }

    #[test]
    fn no_panic_on_garbage() {
        let inputs = [
            "",
            "[",
            "[[scene]]\nname = 1",
            "scene = 3",
            "[scene]\nname = []\n[geometry]\nri = {}\nro = 1979-05-27T07:32:00Z",
            "\u{feff}[scene]\nname = \"é\"",
            "[mesh]\nn_r = -9223372036854775808\nn_theta = 9223372036854775807",
            "[material]\nmodel = 3\n[analysis]\nmode = \"static\"",
            "a = \"\"\"\nunterminated",
            "time = 3\n[analysis]\nmode = \"transient\"",
            "[analysis]\nmode = \"transient\"\n[time]\ndt = []\nt_end = {}\nmax_steps = -1\nmass = 1",
            "[analysis]\nmode = \"transient\"\n[motion]\nramp = \"x\"\n[road]\nramp = -1e308\nv0_ramp = nan",
        ];
        for text in inputs {
            let r = Scene::from_toml_str(text, "x", &["=".into(), "..=".into(), "a.b.c=1".into()]);
            let e = r.err().unwrap_or_else(|| panic!("accepted {text:?}"));
            assert!(!e.0.is_empty());
            let _ = e.to_string();
        }
        let e = errors("");
        for sec in ["scene", "geometry", "material", "analysis"] {
            assert!(e.has_key(sec), "{e}");
        }
    }

    // --- contact, friction, road, stick-slip ---------------------------------------------

    fn full_road() -> RoadSpec {
        RoadSpec {
            disp: Some(0.1),
            load: Some(1.0),
            v0: 0.0,
            ramp: 0.0,
            v0_ramp: Some(0.0),
        }
    }

    fn full_contact() -> ContactSpec {
        ContactSpec {
            c_n: 1.0,
            m_n: 1.0,
            b_n: 0.0,
            l_n: 0.0,
            quadrature: ContactQuadrature::Gauss,
            points: 4,
            clamp: ClampKind::Smooth,
            clamp_width: Some(10.0),
        }
    }

    fn full_friction() -> FrictionSpec {
        FrictionSpec {
            law: FrictionLawName::None,
            mu: Some(1.0),
            eps: Some(1.0),
            mu_s: Some(1.0),
            mu_k: Some(1.0),
            v_s: Some(1.0),
            c_t: Some(1.0),
            m_t: Some(1.0),
        }
    }

    fn full_stick_slip() -> StickSlipSpec {
        StickSlipSpec {
            mass: 1.0,
            stiffness: 1.0,
            normal_force: 1.0,
            belt_speed: 1.0,
            t_end: 1.0,
            rtol: 1e-8,
            atol: 1e-10,
            x0: 0.0,
            v0: Some(0.0),
            output_interval: Some(0.1),
        }
    }

    fn full_time() -> TimeSpec {
        TimeSpec {
            dt_min: Some(1e-6),
            dt_max: Some(1e-2),
            ..TimeSpec::new(1e-3, 1.0)
        }
    }

    /// Remove the section starting at the line `header` up to (not including) the next header.
    fn remove_section(text: &str, header: &str) -> String {
        let mut out = Vec::new();
        let mut skipping = false;
        let mut found = false;
        for l in text.lines() {
            let t = l.trim_start();
            if t.starts_with('[') {
                skipping = t.starts_with(header);
                found |= skipping;
            }
            if !skipping {
                out.push(l);
            }
        }
        assert!(found, "no section {header}");
        out.join("\n") + "\n"
    }

    /// The single error of `e`, which must name `key`, on `line`.
    fn assert_only(e: &SceneErrors, key: &str, line: Option<usize>) {
        assert_eq!(e.0.len(), 1, "{e}");
        assert_eq!(e.0[0].key, key, "{e}");
        assert_eq!(e.0[0].line, line, "{e}");
    }

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
            Some(MaterialParams::MooneyRivlin {
                c1: 80.0,
                c2: 20.0,
                kappa: 2000.0
            })
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
                v0_ramp: None
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
        assert_eq!(s.friction.params(), Some(FrictionParams::None));
        assert!(!s.friction.is_active());
        assert_eq!(s.stick_slip, None);
        assert_eq!(s.solver.load_steps, 5);
        assert!(s.validate().is_ok());

        let f = load(FRICTION).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(f.scene.name, "indentation_friction");
        assert_eq!(
            f.friction.params(),
            Some(FrictionParams::CoulombTanh { mu: 0.3, eps: 0.01 })
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
                v0_ramp: None
            })
        );
        let base = load(FRICTIONLESS).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.contact, base.contact);
        assert_eq!(s.friction, base.friction);
        assert_eq!(s.mesh, base.mesh);
        assert_eq!(s.solver, base.solver);
    }

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
            Some(FrictionParams::RateDependent {
                mu_s: 0.6,
                mu_k: 0.4,
                v_s: 1e-4,
                eps: 1e-7
            })
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
    fn friction_params_and_is_active() {
        let mut f = FrictionSpec {
            law: FrictionLawName::CoulombLinear,
            mu: Some(0.0),
            eps: Some(1e-3),
            ..FrictionSpec::default()
        };
        assert_eq!(
            f.params(),
            Some(FrictionParams::CoulombLinear { mu: 0.0, eps: 1e-3 })
        );
        assert!(!f.is_active(), "zero coefficient");
        f.mu = Some(0.2);
        assert!(f.is_active());
        f.eps = None;
        assert_eq!(f.params(), None);
        assert!(!f.is_active(), "incomplete");
        let om = FrictionSpec {
            law: FrictionLawName::OdenMartins,
            c_t: Some(5.0),
            m_t: Some(1.5),
            eps: Some(1e-3),
            ..FrictionSpec::default()
        };
        assert_eq!(
            om.params(),
            Some(FrictionParams::OdenMartins {
                c_t: 5.0,
                m_t: 1.5,
                eps: 1e-3
            })
        );
        assert!(om.is_active());
        let rd = FrictionSpec {
            law: FrictionLawName::RateDependent,
            mu_s: Some(0.0),
            mu_k: Some(0.0),
            v_s: Some(1.0),
            eps: Some(1e-3),
            ..FrictionSpec::default()
        };
        assert!(!rd.is_active());
        assert_eq!(FrictionSpec::keys_of(FrictionLawName::None), &[] as &[&str]);
        assert_eq!(
            FrictionSpec::keys_of(FrictionLawName::RateDependent),
            &["mu_s", "mu_k", "v_s", "eps"]
        );
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
    fn negative_mu_and_non_positive_eps_rejected() {
        let text = replace_line(FRICTION, "mu =", "mu = -0.1");
        let e = errors(&text);
        assert_only(&e, "friction.mu", Some(line_of(&text, "mu =")));
        assert!(e.0[0].message.contains(">= 0"), "{e}");
        assert!(load(&replace_line(FRICTION, "mu =", "mu = 0.0")).is_ok());

        for bad in ["eps = 0.0", "eps = -0.01"] {
            let text = replace_line(FRICTION, "eps", bad);
            let e = errors(&text);
            assert_only(&e, "friction.eps", Some(line_of(&text, "eps")));
            assert!(e.0[0].message.contains("> 0"), "{e}");
        }
        let text = replace_line(STICK_SLIP, "eps", "eps = 0");
        let e = errors(&text);
        assert_only(&e, "friction.eps", Some(line_of(&text, "eps")));
        let text = replace_line(STICK_SLIP, "mu_s", "mu_s = -0.6");
        let e = errors(&text);
        assert_only(&e, "friction.mu_s", Some(line_of(&text, "mu_s")));
        let text = replace_line(STICK_SLIP, "v_s", "v_s = 0.0");
        let e = errors(&text);
        assert_only(&e, "friction.v_s", Some(line_of(&text, "v_s")));
    }

    #[test]
    fn kinetic_above_static_rejected() {
        let text = replace_line(STICK_SLIP, "mu_k", "mu_k = 0.7");
        let e = errors(&text);
        assert_only(&e, "friction.mu_k", Some(line_of(&text, "mu_k")));
        assert!(e.0[0].message.contains("must not exceed"), "{e}");
        assert!(load(&replace_line(STICK_SLIP, "mu_k", "mu_k = 0.6")).is_ok());
    }

    #[test]
    fn oden_martins_keys_checked() {
        let text = FRICTIONLESS.replace(
            "law = \"none\"",
            "law = \"oden_martins\"\nc_t = 6.0e4\nm_t = 0.5\neps = 0.01",
        );
        let e = errors(&text);
        assert_only(&e, "friction.m_t", Some(line_of(&text, "m_t")));
        let s = load(&replace_line(&text, "m_t", "m_t = 1.0")).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            s.friction.params(),
            Some(FrictionParams::OdenMartins {
                c_t: 6.0e4,
                m_t: 1.0,
                eps: 0.01
            })
        );
        // Missing keys of the law: reported at the [friction] header.
        let text = FRICTIONLESS.replace("law = \"none\"", "law = \"oden_martins\"");
        let e = errors(&text);
        assert_eq!(e.0.len(), 3, "{e}");
        for key in ["friction.c_t", "friction.m_t", "friction.eps"] {
            let err = e.find(key).unwrap_or_else(|| panic!("{e}"));
            assert_eq!(err.line, Some(line_of(&text, "[friction]")));
            assert!(err.message.contains("required for friction law"), "{err}");
        }
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
    fn static_without_road_or_contact_rejected() {
        let text = remove_section(FRICTIONLESS, "[road]");
        let e = errors(&text);
        assert_only(&e, "road", Some(line_of(&text, "mode =")));
        assert!(e.0[0].message.contains("\"static\""), "{e}");
        assert!(e.0[0].message.contains("missing"), "{e}");

        let text = remove_section(&text, "[contact]");
        let e = errors(&text);
        assert_eq!(e.0.len(), 2, "{e}");
        for key in ["road", "contact"] {
            let err = e.find(key).unwrap_or_else(|| panic!("{e}"));
            assert_eq!(err.line, Some(line_of(&text, "mode =")));
        }
        // Switching a spinning scene to static by override: the mode is the anchor, so (--set).
        let e = errors_with(MINIMAL, &["analysis.mode=static", "motion.omega=0"]);
        assert_eq!(e.0.len(), 2, "{e}");
        assert!(
            e.0.iter().all(|x| x.is_override() && x.line.is_none()),
            "{e}"
        );
    }

    #[test]
    fn friction_key_of_another_law_rejected() {
        let text = replace_line(FRICTION, "eps", "eps = 0.01\nmu_s = 0.5");
        let e = errors(&text);
        assert_only(&e, "friction.mu_s", Some(line_of(&text, "mu_s")));
        assert!(e.0[0].message.contains("not a parameter"), "{e}");
        assert!(e.0[0].message.contains("coulomb_tanh"), "{e}");
        assert!(e.0[0].message.contains("law, mu, eps"), "{e}");

        let text = replace_line(STICK_SLIP, "v_s", "v_s = 0.01\nmu = 0.5");
        let e = errors(&text);
        assert_only(&e, "friction.mu", Some(line_of(&text, "mu = 0.5")));

        let text = FRICTIONLESS.replace("law = \"none\"", "law = \"none\"\nmu = 0.3");
        let e = errors(&text);
        assert_only(&e, "friction.mu", Some(line_of(&text, "mu =")));
        assert!(e.0[0].message.contains("takes no other key"), "{e}");
    }

    #[test]
    fn invalid_friction_law_reported_once() {
        // The keys of an unknown law are not checked against the default law.
        let text = replace_line(FRICTION, "law", "law = \"coulomb\"");
        let e = errors(&text);
        assert_only(&e, "friction.law", Some(line_of(&text, "law")));
        assert!(e.0[0].message.contains("coulomb_tanh"), "{e}");
        let text = replace_line(STICK_SLIP, "law", "law = 3");
        let e = errors(&text);
        assert_only(&e, "friction.law", Some(line_of(&text, "law")));
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
            Some(FrictionParams::CoulombLinear { mu: 0.5, eps: 1e-7 })
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

    #[test]
    fn sections_not_used_by_the_mode_rejected() {
        // [road] and [contact] in a spinning scene.
        let text = format!("{MINIMAL}\n[road]\ndisp = 0.1\n\n[contact]\nc_n = 1e5\n");
        let e = errors(&text);
        assert_eq!(e.0.len(), 2, "{e}");
        assert_eq!(
            e.find("road").and_then(|x| x.line),
            Some(line_of(&text, "[road]"))
        );
        assert_eq!(
            e.find("contact").and_then(|x| x.line),
            Some(line_of(&text, "[contact]"))
        );
        assert!(e.0[0].message.contains("not used"), "{e}");
        // An override creating [road] in a spinning scene: (--set).
        let e = errors_with(MINIMAL, &["road.disp=0.1"]);
        assert_only(&e, "road", None);
        assert!(e.0[0].is_override(), "{e}");
        // Friction in a spinning scene.
        let text = format!("{MINIMAL}\n[friction]\nlaw = \"coulomb_tanh\"\nmu = 0.3\neps = 0.1\n");
        let e = errors(&text);
        assert_only(&e, "friction.law", Some(line_of(&text, "law")));
        assert!(load(&format!("{MINIMAL}\n[friction]\nlaw = \"none\"\n")).is_ok());
        // [stick_slip] in a static scene; [road] in a stick-slip scene.
        let text = format!(
            "{FRICTIONLESS}\n[stick_slip]\nmass = 1\nstiffness = 1\nnormal_force = 1\n\
             belt_speed = 1\nt_end = 1\n"
        );
        let e = errors(&text);
        assert_only(&e, "stick_slip", Some(line_of(&text, "[stick_slip]")));
        let text = format!("{STICK_SLIP}\n[road]\nload = 1.0\n");
        let e = errors(&text);
        assert_only(&e, "road", Some(line_of(&text, "[road]")));
    }

    #[test]
    fn static_rejects_spin_road_speed_and_damping() {
        let text = format!("{FRICTIONLESS}\n[motion]\nomega = 20.0\n");
        let e = errors(&text);
        assert_only(&e, "motion.omega", Some(line_of(&text, "omega")));
        let text = replace_line(FRICTIONLESS, "v0", "v0 = 1.0");
        let e = errors(&text);
        assert_only(&e, "road.v0", Some(line_of(&text, "v0")));
        let text = replace_line(FRICTIONLESS, "b_n", "b_n = 5.0");
        let e = errors(&text);
        assert_only(&e, "contact.b_n", Some(line_of(&text, "b_n")));
        let e = errors_with(STICK_SLIP, &["motion.omega=1"]);
        assert_only(&e, "motion.omega", None);
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

    #[test]
    fn overrides_of_new_keys() {
        let s = load_with(FRICTION, &["friction.mu=0.5"]).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            s.friction.params(),
            Some(FrictionParams::CoulombTanh { mu: 0.5, eps: 0.01 })
        );
        let s = load_with(
            FRICTIONLESS,
            &[
                "friction.law=coulomb_linear",
                "friction.mu=0.2",
                "friction.eps=1e-3",
                "contact.quadrature=lobatto",
                "contact.points=3",
                "contact.m_n=2",
                "road.disp=0.05",
            ],
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            s.friction.params(),
            Some(FrictionParams::CoulombLinear { mu: 0.2, eps: 1e-3 })
        );
        let c = s.contact.unwrap_or_else(|| panic!("no contact"));
        assert_eq!(
            (c.quadrature, c.points, c.m_n),
            (ContactQuadrature::Lobatto, 3, 2.0)
        );
        assert_eq!(s.road.and_then(|r| r.disp), Some(0.05));
        let s = load_with(LOAD_CONTROL, &["road.load=250"]).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.road.and_then(|r| r.load), Some(250.0));
        let s = load_with(STICK_SLIP, &["stick_slip.t_end=5", "friction.mu_k=0.3"])
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.stick_slip.map(|x| x.t_end), Some(5.0));
        assert_eq!(s.friction.mu_k, Some(0.3));

        // Bad override values: (--set) and the key.
        let e = errors_with(FRICTION, &["friction.mu=-1"]);
        assert_only(&e, "friction.mu", None);
        assert!(e.0[0].is_override());
        assert!(
            e.0[0]
                .to_string()
                .starts_with("test.toml:(--set): key `friction.mu`"),
            "{e}"
        );
        let e = errors_with(FRICTIONLESS, &["contact.quadrature=simpson"]);
        assert_only(&e, "contact.quadrature", None);
        assert!(e.0[0].message.contains("\"lobatto\""), "{e}");
        // Adding `load` by override to a disp scene: the clash is reported at `disp`'s line.
        let e = errors_with(FRICTIONLESS, &["road.load=300"]);
        assert_only(&e, "road.disp", Some(line_of(FRICTIONLESS, "disp")));
        // Unknown keys of the new sections.
        let e = errors_with(FRICTION, &["friction.muu=0.5"]);
        assert_only(&e, "friction.muu", None);
        assert!(e.0[0].message.contains("mu_s"), "{e}");
    }

    #[test]
    fn unknown_keys_in_new_sections_rejected() {
        let text = replace_line(FRICTIONLESS, "c_n", "c_n = 2e5\npenalty = 1e5");
        let e = errors(&text);
        assert_only(&e, "contact.penalty", Some(line_of(&text, "penalty")));
        let text = replace_line(STICK_SLIP, "mass", "mass = 1.0\ndamping = 0.1");
        let e = errors(&text);
        assert_only(&e, "stick_slip.damping", Some(line_of(&text, "damping")));
        let text = replace_line(FRICTIONLESS, "disp", "disp = 0.1\nspeed = 2");
        let e = errors(&text);
        assert_only(&e, "road.speed", Some(line_of(&text, "speed")));
        assert!(e.0[0].message.contains("v0_ramp"), "{e}");
    }

    #[test]
    fn round_trip_of_optional_new_keys() {
        let cases: [(&str, &[&str]); 3] = [
            (
                STICK_SLIP,
                &["stick_slip.v0=0.05", "stick_slip.output_interval=0.02"],
            ),
            (
                FRICTIONLESS,
                &[
                    "friction.law=oden_martins",
                    "friction.c_t=6e4",
                    "friction.m_t=1",
                    "friction.eps=0.01",
                    "contact.quadrature=lobatto",
                ],
            ),
            (LOAD_CONTROL, &["contact.l_n=1.5"]),
        ];
        for (text, ov) in cases {
            let s = load_with(text, ov).unwrap_or_else(|e| panic!("{e}"));
            let out = s.to_toml_string();
            let back = load(&out).unwrap_or_else(|e| panic!("{e}\n{out}"));
            assert_eq!(back, s, "{out}");
            let direct: Scene = toml::from_str(&out).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(direct, s);
        }
        // Absent optional sections are not written; [friction] always is.
        let out = load(MINIMAL)
            .unwrap_or_else(|e| panic!("{e}"))
            .to_toml_string();
        assert!(
            !out.contains("[road]") && !out.contains("[contact]"),
            "{out}"
        );
        assert!(!out.contains("[stick_slip]"), "{out}");
        assert!(out.contains("[friction]\nlaw = \"none\""), "{out}");
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
                ..MeshSpec::default()
            },
        );
        check(
            "material",
            &MaterialSpec {
                model: MaterialModel::NeoHookean,
                rho: 1.0,
                mu: Some(1.0),
                lambda: Some(1.0),
                c1: Some(1.0),
                c2: Some(1.0),
                kappa: Some(1.0),
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
    fn validate_checks_new_sections_of_scenes_built_in_code() {
        let mut s = load(FRICTION).unwrap_or_else(|e| panic!("{e}"));
        assert!(s.validate().is_ok());
        s.friction.mu = Some(-0.3);
        if let Some(c) = s.contact.as_mut() {
            c.c_n = 0.0;
        }
        s.stick_slip = Some(full_stick_slip());
        let e = s.validate().err().unwrap_or_else(|| panic!("accepted"));
        assert_eq!(e.0.len(), 3, "{e}");
        for key in ["friction.mu", "contact.c_n", "stick_slip"] {
            let err = e.find(key).unwrap_or_else(|| panic!("{e}"));
            assert_eq!(err.line, None);
            assert_eq!(err.source_name, "<scene>");
        }
        s.stick_slip = None;
        s.road = None;
        let e = s.validate().err().unwrap_or_else(|| panic!("accepted"));
        assert!(e.has_key("road"), "{e}");
    }

    // --- transient mode, [time], ramps ------------------------------------------------------

    /// MINIMAL as a transient scene without contact: only the required keys of [time].
    fn minimal_transient() -> String {
        MINIMAL.replace("mode = \"spinning\"", "mode = \"transient\"")
            + "\n[time]\ndt = 1e-3\nt_end = 0.5\n"
    }

    #[test]
    fn oden_scene_parses() {
        let s = load(ODEN).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.scene.name, "oden_hollow_cylinder");
        assert_eq!(s.analysis.mode, Mode::Transient);
        assert_eq!((s.geometry.ri, s.geometry.ro), (1.0, 2.0));
        assert_eq!(
            (
                s.mesh.n_r,
                s.mesh.n_theta,
                s.mesh.order,
                s.mesh.grading_theta
            ),
            (3, 64, 2, 0.0)
        );
        assert_eq!(
            s.material.params(),
            Some(MaterialParams::MooneyRivlin {
                c1: 80.0,
                c2: 20.0,
                kappa: 20000.0
            })
        );
        // Nearly incompressible: κ / G = 100.
        let g = s.material.shear_modulus().unwrap_or(0.0);
        assert_eq!(s.material.bulk_modulus().unwrap_or(0.0) / g, 100.0);
        // Critical spin c_R / Ro ≈ 395 rpm, the paper's top speed.
        let c_r = 0.955 * s.shear_wave_speed().unwrap_or(0.0);
        let rpm = c_r / s.geometry.ro * 60.0 / (2.0 * std::f64::consts::PI);
        assert!((rpm - 395.0).abs() < 10.0, "critical spin {rpm} rpm");
        assert_eq!(
            s.motion,
            Motion {
                omega: 10.0,
                ramp: 0.05,
                ..Motion::default()
            }
        );
        let road = s.road.clone().unwrap_or_else(|| panic!("no [road]"));
        assert_eq!((road.disp, road.load, road.ramp), (Some(0.1), None, 0.05));
        assert_eq!(road.v0_ramp, None);
        assert_eq!(road.resolved_v0_ramp(&s.motion), 0.05);
        // Free-rolling-like road speed: v0 = ω (Ro − DISP/3).
        let r_eff = s.geometry.ro - 0.1 / 3.0;
        assert!(
            (road.v0 - s.motion.omega * r_eff).abs() < 1e-5,
            "{}",
            road.v0
        );
        assert_eq!(
            s.contact,
            Some(ContactSpec {
                c_n: 2.0e4,
                m_n: 1.0,
                b_n: 1000.0,
                l_n: 1.0,
                quadrature: ContactQuadrature::Lobatto,
                points: 4,
                clamp: ClampKind::Hard,
                clamp_width: None
            })
        );
        assert_eq!(
            s.friction.params(),
            Some(FrictionParams::CoulombTanh { mu: 0.3, eps: 0.5 })
        );
        let t = s.time.clone().unwrap_or_else(|| panic!("no [time]"));
        assert_eq!(
            t,
            TimeSpec {
                integrator: IntegratorName::GeneralizedAlpha,
                rho_inf: 0.8,
                dt: 2.0e-4,
                dt_min: None,
                dt_max: None,
                t_end: 2.0,
                adaptive: true,
                error_tol: 1e-3,
                steady_tol: 1e-3,
                stop_at_steady: true,
                mass: MassKind::Consistent,
                max_steps: 200_000,
                strain_rate_damping: 1.0,
            }
        );
        assert!((t.resolved_dt_min() - 2.0e-8).abs() < 1e-20);
        assert!((t.resolved_dt_max() - 2.0e-3).abs() < 1e-15);
        assert_eq!(t.effective_mass(), MassKind::Consistent);
        assert!(!t.is_explicit());
        assert_eq!((s.solver.load_steps, s.solver.tolerance), (1, 1e-8));
        assert_eq!(s.stick_slip, None);
        assert!(s.validate().is_ok());

        // The frictionless scene is the same scene without friction.
        let f = load(ROLLING_FRICTIONLESS).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(f.scene.name, "rolling_frictionless");
        assert_eq!(f.friction, FrictionSpec::default());
        assert!(!f.friction.is_active());
        assert_eq!(
            (&f.geometry, &f.mesh, &f.material, &f.analysis),
            (&s.geometry, &s.mesh, &s.material, &s.analysis)
        );
        assert_eq!(
            (&f.motion, &f.road, &f.contact),
            (&s.motion, &s.road, &s.contact)
        );
        assert_eq!(
            (&f.time, &f.solver, &f.output),
            (&s.time, &s.solver, &s.output)
        );
        assert!(f.validate().is_ok());
    }

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
    fn time_defaults_are_filled() {
        let s = load(&minimal_transient()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.analysis.mode, Mode::Transient);
        // A spinning cylinder in time: no road, no contact.
        assert_eq!((&s.road, &s.contact), (&None, &None));
        assert_eq!(s.motion.ramp, 0.0);
        let t = s.time.unwrap_or_else(|| panic!("no [time]"));
        assert_eq!(t, TimeSpec::new(1e-3, 0.5));
        assert_eq!(t.integrator, IntegratorName::GeneralizedAlpha);
        assert_eq!(t.rho_inf, DEFAULT_RHO_INF);
        assert_eq!(t.rho_inf, 0.8);
        assert_eq!((t.dt_min, t.dt_max), (None, None));
        assert_eq!(t.resolved_dt_min(), 1e-3 * DT_MIN_FACTOR);
        assert_eq!(t.resolved_dt_max(), 1e-3 * DT_MAX_FACTOR);
        assert!(t.adaptive && t.stop_at_steady);
        assert_eq!((t.error_tol, t.steady_tol), (1e-4, 1e-4));
        assert_eq!(t.mass, MassKind::Consistent);
        assert_eq!(t.max_steps, 200_000);
        assert_eq!(t.max_steps, DEFAULT_MAX_STEPS);

        // Road defaults in transient: no ramps, v0_ramp follows motion.ramp.
        let text = remove_section(&remove_section(ODEN, "[road]"), "[time]")
            + "[road]\ndisp = 0.05\nv0 = 3.0\n[time]\ndt = 1e-3\nt_end = 1\n";
        let s = load(&text).unwrap_or_else(|e| panic!("{e}"));
        let road = s.road.unwrap_or_else(|| panic!("no [road]"));
        assert_eq!((road.ramp, road.v0_ramp), (0.0, None));
        assert_eq!(road.resolved_v0_ramp(&s.motion), s.motion.ramp);
        assert_eq!(road.resolved_v0_ramp(&s.motion), 0.05);
    }

    #[test]
    fn time_ranges_rejected_with_key_and_line() {
        let cases: [(&str, &str, &str, &str); 14] = [
            ("dt =", "dt = 0.0", "time.dt", "> 0"),
            ("dt =", "dt = -2e-4", "time.dt", "> 0"),
            ("t_end", "t_end = 0", "time.t_end", "> 0"),
            ("t_end", "t_end = -1.0", "time.t_end", "> 0"),
            ("dt =", "dt = 3.0", "time.dt", "must not exceed t_end"),
            ("rho_inf", "rho_inf = -0.1", "time.rho_inf", "[0, 1]"),
            ("rho_inf", "rho_inf = 1.01", "time.rho_inf", "[0, 1]"),
            (
                "dt =",
                "dt = 2e-4\ndt_min = 3e-4",
                "time.dt_min",
                "must not exceed dt",
            ),
            ("dt =", "dt = 2e-4\ndt_min = 0", "time.dt_min", "> 0"),
            ("dt =", "dt = 2e-4\ndt_max = 1e-4", "time.dt_max", ">= dt"),
            ("error_tol", "error_tol = 0.0", "time.error_tol", "> 0"),
            ("steady_tol", "steady_tol = 0", "time.steady_tol", "> 0"),
            ("steady_tol", "steady_tol = -1e-3", "time.steady_tol", "> 0"),
            ("max_steps", "max_steps = 0", "time.max_steps", ">= 1"),
        ];
        for (prefix, new, key, what) in cases {
            let text = replace_line(ODEN, prefix, new);
            let e = errors(&text);
            let field = key.trim_start_matches("time.");
            assert_only(&e, key, Some(line_of(&text, &format!("{field} ="))));
            assert!(e.0[0].message.contains(what), "{new}: {e}");
            assert!(
                e.0[0].to_string().starts_with(&format!(
                    "test.toml:{}: key `{key}`",
                    line_of(&text, &format!("{field} ="))
                )),
                "{e}"
            );
        }
        // Boundary values are accepted.
        for ok in [
            ("rho_inf", "rho_inf = 0"),
            ("rho_inf", "rho_inf = 1.0"),
            ("dt =", "dt = 2e-4\ndt_min = 2e-4\ndt_max = 2e-4"),
            ("dt =", "dt = 2.0"),
        ] {
            let text = replace_line(ODEN, ok.0, ok.1);
            assert!(load(&text).is_ok(), "{}", ok.1);
        }
        // Several problems of [time] at once, each on its own line.
        let text = replace_line(ODEN, "rho_inf", "rho_inf = 2");
        let text = replace_line(&text, "t_end", "t_end = 0");
        let text = replace_line(&text, "error_tol", "error_tol = -1");
        let e = errors(&text);
        assert_eq!(e.0.len(), 3, "{e}");
        for key in ["rho_inf", "t_end", "error_tol"] {
            let err = e
                .find(&format!("time.{key}"))
                .unwrap_or_else(|| panic!("{e}"));
            assert_eq!(err.line, Some(line_of(&text, key)));
        }
        // Missing required keys: at the [time] header.
        let text = ODEN
            .lines()
            .filter(|l| !l.starts_with("dt =") && !l.starts_with("t_end"))
            .collect::<Vec<_>>()
            .join("\n");
        let e = errors(&text);
        assert_eq!(e.0.len(), 2, "{e}");
        for key in ["time.dt", "time.t_end"] {
            let err = e.find(key).unwrap_or_else(|| panic!("{e}"));
            assert_eq!(err.line, Some(line_of(&text, "[time]")));
            assert!(err.message.contains("required key is missing"), "{err}");
        }
        // Wrong types and unknown values.
        let text = replace_line(ODEN, "integrator", "integrator = \"newmark\"");
        let e = errors(&text);
        assert_only(&e, "time.integrator", Some(line_of(&text, "integrator")));
        assert!(e.0[0].message.contains("\"generalized_alpha\""), "{e}");
        let text = replace_line(ODEN, "adaptive", "adaptive = 1");
        let e = errors(&text);
        assert_only(&e, "time.adaptive", Some(line_of(&text, "adaptive")));
        let text = replace_line(ODEN, "max_steps", "max_steps = 1.5");
        let e = errors(&text);
        assert_only(&e, "time.max_steps", Some(line_of(&text, "max_steps")));
        let text = replace_line(ODEN, "dt =", "dt = 2e-4\ndt_step = 1");
        let e = errors(&text);
        assert_only(&e, "time.dt_step", Some(line_of(&text, "dt_step")));
        assert!(e.0[0].message.contains("steady_tol"), "{e}");
    }

    #[test]
    fn central_difference_uses_lumped_mass() {
        // Explicit consistent mass with central difference: named at its line.
        let text = replace_line(ODEN, "integrator", "integrator = \"central_difference\"");
        let e = errors(&text);
        assert_only(&e, "time.mass", Some(line_of(&text, "mass =")));
        assert!(e.0[0].message.contains("lumped"), "{e}");
        // Omitted: resolved to lumped (and written so by to_toml_string).
        let text = text
            .lines()
            .filter(|l| !l.starts_with("mass ="))
            .collect::<Vec<_>>()
            .join("\n");
        let s = load(&text).unwrap_or_else(|e| panic!("{e}"));
        let t = s.time.clone().unwrap_or_else(|| panic!("no [time]"));
        assert_eq!(t.integrator, IntegratorName::CentralDifference);
        assert_eq!(
            (t.mass, t.effective_mass()),
            (MassKind::Lumped, MassKind::Lumped)
        );
        assert!(t.is_explicit());
        let out = s.to_toml_string();
        assert!(out.contains("mass = \"lumped\""), "{out}");
        assert_eq!(load(&out).unwrap_or_else(|e| panic!("{e}\n{out}")), s);
        // Explicit lumped is fine; an override back to consistent is reported as (--set).
        assert!(load(&replace_line(
            &text,
            "integrator",
            "integrator = \"central_difference\"\nmass = \"lumped\""
        ))
        .is_ok());
        let e = errors_with(&text, &["time.mass=consistent"]);
        assert_only(&e, "time.mass", None);
        assert!(e.0[0].is_override(), "{e}");
        // An unknown mass is reported once, not also as "consistent".
        let e = errors_with(&text, &["time.mass=diagonal"]);
        assert_only(&e, "time.mass", None);
        assert!(e.0[0].message.contains("\"lumped\""), "{e}");
        // Other integrators keep the consistent default.
        let s = load_with(ODEN, &["time.integrator=bdf"]).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.time.map(|t| t.mass), Some(MassKind::Consistent));
        let s = load_with(ODEN, &["time.integrator=sdirk", "time.mass=lumped"])
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            s.time.map(|t| (t.integrator, t.mass)),
            Some((IntegratorName::Sdirk, MassKind::Lumped))
        );
    }

    #[test]
    fn time_section_only_in_transient() {
        let time = "\n[time]\ndt = 1e-3\nt_end = 1.0\n";
        for base in [MINIMAL, FRICTIONLESS, STICK_SLIP] {
            let text = format!("{base}{time}");
            let e = errors(&text);
            assert_only(&e, "time", Some(line_of(&text, "[time]")));
            assert!(e.0[0].message.contains("not used"), "{e}");
            assert!(e.0[0].message.contains("\"transient\""), "{e}");
        }
        // Created by an override: (--set).
        let e = errors_with(MINIMAL, &["time.dt=1e-3", "time.t_end=1"]);
        assert_only(&e, "time", None);
        assert!(e.0[0].is_override(), "{e}");
        // Required in transient: at the line of `mode`.
        let text = remove_section(ODEN, "[time]");
        let e = errors(&text);
        assert_only(&e, "time", Some(line_of(&text, "mode =")));
        assert!(e.0[0].message.contains("missing"), "{e}");
        assert!(e.0[0].message.contains("dt, t_end"), "{e}");
        // [stick_slip] in a transient scene.
        let text = format!(
            "{ODEN}\n[stick_slip]\nmass = 1\nstiffness = 1\nnormal_force = 1\nbelt_speed = 1\n\
             t_end = 1\n"
        );
        let e = errors(&text);
        assert_only(&e, "stick_slip", Some(line_of(&text, "[stick_slip]")));
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
    fn transient_allows_road_speed_damping_and_spin() {
        // Static still rejects them (see static_rejects_spin_road_speed_and_damping); in
        // transient they are the point.
        let s = load_with(
            ODEN,
            &[
                "road.v0=-5",
                "contact.b_n=0",
                "motion.omega=40",
                "contact.l_n=1",
            ],
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.road.as_ref().map(|r| r.v0), Some(-5.0));
        assert_eq!(s.motion.omega, 40.0);
        assert_eq!(s.contact.as_ref().map(|c| (c.b_n, c.l_n)), Some((0.0, 1.0)));
        // Load control in transient.
        let s = load_with(
            &ODEN.replace("disp = 0.1", "load = 300.0"),
            &["road.ramp=0.1"],
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let road = s.road.unwrap_or_else(|| panic!("no [road]"));
        assert_eq!((road.disp, road.load, road.ramp), (None, Some(300.0), 0.1));
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
    fn transient_road_contact_and_friction_rules() {
        // Neither [road] nor [contact]: a spinning cylinder in time (frictionless).
        let text = remove_section(&remove_section(ROLLING_FRICTIONLESS, "[road]"), "[contact]");
        let s = load(&text).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!((s.road, s.contact), (None, None));
        // ... but friction needs contact.
        let text = remove_section(&remove_section(ODEN, "[road]"), "[contact]");
        let e = errors(&text);
        assert_only(&e, "friction.law", Some(line_of(&text, "law")));
        assert!(e.0[0].message.contains("\"transient\""), "{e}");
        assert!(e.0[0].message.contains("\"coulomb_tanh\""), "{e}");
        // One without the other: named, at the header of the one given.
        let text = remove_section(ODEN, "[contact]");
        let e = errors(&text);
        assert_only(&e, "contact", Some(line_of(&text, "[road]")));
        assert!(e.0[0].message.contains("both"), "{e}");
        let text = remove_section(ODEN, "[road]");
        let e = errors(&text);
        assert_only(&e, "road", Some(line_of(&text, "[contact]")));
        assert!(e.0[0].message.contains("both"), "{e}");
        // Every friction law is allowed with contact.
        let s = load_with(
            ROLLING_FRICTIONLESS,
            &[
                "friction.law=oden_martins",
                "friction.c_t=6e3",
                "friction.m_t=1",
                "friction.eps=0.5",
            ],
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert!(s.friction.is_active());
    }

    #[test]
    fn graded_mesh_rejected_when_stopping_at_steady() {
        let text = replace_line(ODEN, "grading_theta", "grading_theta = 0.5");
        let e = errors(&text);
        assert_only(
            &e,
            "mesh.grading_theta",
            Some(line_of(&text, "grading_theta")),
        );
        assert!(e.0[0].message.contains("uniform in θ"), "{e}");
        // Without stopping at the steady state a graded mesh is allowed.
        let text = replace_line(&text, "stop_at_steady", "stop_at_steady = false");
        assert!(load(&text).is_ok());
        // An out-of-range grading is reported once.
        let e = errors(&replace_line(ODEN, "grading_theta", "grading_theta = 1.0"));
        assert_eq!(e.0.len(), 1, "{e}");
        // Static scenes keep their graded meshes.
        assert!(load(FRICTIONLESS).is_ok());
    }

    #[test]
    fn overrides_of_time_keys() {
        let s = load_with(ODEN, &["time.dt=1e-4"]).unwrap_or_else(|e| panic!("{e}"));
        let t = s.time.clone().unwrap_or_else(|| panic!("no [time]"));
        assert_eq!(t.dt, 1e-4);
        assert!((t.resolved_dt_min() - 1e-8).abs() < 1e-20);
        assert!((t.resolved_dt_max() - 1e-3).abs() < 1e-15);
        let s = load_with(
            ODEN,
            &[
                "time.integrator=central_difference",
                "time.mass=lumped",
                "time.adaptive=false",
                "time.stop_at_steady=false",
                "time.t_end=0.5",
                "time.rho_inf=1",
                "time.dt_min=1e-6",
                "time.dt_max=1e-3",
                "time.error_tol=1e-5",
                "time.steady_tol=1e-5",
                "time.max_steps=10",
                "motion.ramp=0.1",
            ],
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let t = s.time.clone().unwrap_or_else(|| panic!("no [time]"));
        assert_eq!(
            t,
            TimeSpec {
                integrator: IntegratorName::CentralDifference,
                rho_inf: 1.0,
                dt: 2e-4,
                dt_min: Some(1e-6),
                dt_max: Some(1e-3),
                t_end: 0.5,
                adaptive: false,
                error_tol: 1e-5,
                steady_tol: 1e-5,
                stop_at_steady: false,
                mass: MassKind::Lumped,
                max_steps: 10,
                strain_rate_damping: 1.0,
            }
        );
        // road.v0_ramp follows the overridden motion.ramp.
        assert_eq!(
            s.road.as_ref().map(|r| r.resolved_v0_ramp(&s.motion)),
            Some(0.1)
        );
        // Bad override values: (--set) and the key.
        let e = errors_with(ODEN, &["time.dt=-1e-4"]);
        assert_only(&e, "time.dt", None);
        assert!(e.0[0].is_override());
        assert!(
            e.0[0]
                .to_string()
                .starts_with("test.toml:(--set): key `time.dt`"),
            "{e}"
        );
        let e = errors_with(ODEN, &["time.dt=5"]);
        assert_only(&e, "time.dt", None);
        assert!(e.0[0].message.contains("t_end"), "{e}");
        // dt overridden below an explicit dt_min in the file: dt_min keeps its line.
        let text = replace_line(ODEN, "dt =", "dt = 2e-4\ndt_min = 1e-5");
        let e = errors_with(&text, &["time.dt=1e-6"]);
        assert_only(&e, "time.dt_min", Some(line_of(&text, "dt_min")));
        let e = errors_with(ODEN, &["time.integrator=euler"]);
        assert_only(&e, "time.integrator", None);
        assert!(e.0[0].message.contains("\"sdirk\""), "{e}");
        // Switching a spinning scene to transient by override.
        let s = load_with(
            MINIMAL,
            &["analysis.mode=transient", "time.dt=1e-3", "time.t_end=1"],
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.time.map(|t| (t.dt, t.t_end)), Some((1e-3, 1.0)));
        let e = errors_with(MINIMAL, &["analysis.mode=transient"]);
        assert_only(&e, "time", None);
        assert!(e.0[0].is_override(), "{e}");
    }

    #[test]
    fn round_trip_of_transient_keys() {
        let cases: [(&str, &[&str]); 3] = [
            (
                ODEN,
                &[
                    "time.dt_min=1e-7",
                    "time.dt_max=1e-3",
                    "road.v0_ramp=0.2",
                    "time.integrator=bdf",
                ],
            ),
            (
                ROLLING_FRICTIONLESS,
                &["time.integrator=central_difference", "time.mass=lumped"],
            ),
            (
                &ODEN.replace("disp = 0.1", "load = 300.0"),
                &["time.rho_inf=0"],
            ),
        ];
        for (text, ov) in cases {
            let s = load_with(text, ov).unwrap_or_else(|e| panic!("{e}"));
            let out = s.to_toml_string();
            let back = load(&out).unwrap_or_else(|e| panic!("{e}\n{out}"));
            assert_eq!(back, s, "{out}");
            let direct: Scene = toml::from_str(&out).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(direct, s);
            assert!(out.contains("[time]") && out.contains("ramp = "), "{out}");
        }
        let s = load(&minimal_transient()).unwrap_or_else(|e| panic!("{e}"));
        let out = s.to_toml_string();
        assert!(
            out.contains("[time]\nintegrator = \"generalized_alpha\""),
            "{out}"
        );
        assert!(!out.contains("dt_min") && !out.contains("[road]"), "{out}");
        assert_eq!(load(&out).unwrap_or_else(|e| panic!("{e}\n{out}")), s);
        // Scenes of the other modes write no [time].
        let out = load(FRICTIONLESS)
            .unwrap_or_else(|e| panic!("{e}"))
            .to_toml_string();
        assert!(!out.contains("[time]"), "{out}");
    }

    #[test]
    fn validate_checks_transient_scenes_built_in_code() {
        let mut s = load(ODEN).unwrap_or_else(|e| panic!("{e}"));
        assert!(s.validate().is_ok());
        if let Some(t) = s.time.as_mut() {
            t.dt = -1.0;
            t.integrator = IntegratorName::CentralDifference;
            t.mass = MassKind::Consistent;
        }
        s.motion.ramp = -1.0;
        let e = s.validate().err().unwrap_or_else(|| panic!("accepted"));
        assert_eq!(e.0.len(), 3, "{e}");
        for key in ["time.dt", "time.mass", "motion.ramp"] {
            let err = e.find(key).unwrap_or_else(|| panic!("{e}"));
            assert_eq!((err.line, err.source_name.as_str()), (None, "<scene>"));
        }
        s.time = None;
        s.motion.ramp = 0.0;
        let e = s.validate().err().unwrap_or_else(|| panic!("accepted"));
        assert!(e.has_key("time"), "{e}");
        // [time] in a static scene built in code.
        let mut st = load(FRICTIONLESS).unwrap_or_else(|e| panic!("{e}"));
        st.time = Some(TimeSpec::new(1e-3, 1.0));
        let e = st.validate().err().unwrap_or_else(|| panic!("accepted"));
        assert!(e.has_key("time"), "{e}");
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

    #[test]
    fn viscoelastic_subtable_is_parsed_and_checked() {
        let base = r#"
[scene]
name = "v"
[geometry]
ri = 1.0
ro = 2.0
[material]
model = "neo_hookean"
mu = 200.0
lambda = 1800.0
rho = 0.027
[material.viscoelastic]
model = "convolution"
gamma = 200.0
prony = [[0.7, 0.01], [0.3, 1]]
[analysis]
mode = "transient"
[motion]
omega = 10.0
[time]
dt = 1e-3
t_end = 0.1
"#;
        let s = Scene::from_toml_str(base, "v.toml", &[]).unwrap_or_else(|e| panic!("{e}"));
        let ve = s.material.viscoelastic.clone().expect("parsed");
        assert_eq!(ve.prony, vec![[0.7, 0.01], [0.3, 1.0]]);
        let law = ve.build().expect("valid");
        assert_eq!(law.model, crate::material::ViscoModel::Convolution);
        assert_eq!(law.prony(), &[(0.7, 0.01), (0.3, 1.0)]);
        // Every problem at once, each with its key and line.
        let bad = base
            .replace("model = \"convolution\"", "model = \"maxwell\"\ncolour = 1")
            .replace("gamma = 200.0", "gamma = \"big\"")
            .replace(
                "prony = [[0.7, 0.01], [0.3, 1]]",
                "prony = [[0.7], [0.3, 1]]",
            );
        let e = Scene::from_toml_str(&bad, "v.toml", &[]).expect_err("invalid");
        for key in [
            "material.viscoelastic.model",
            "material.viscoelastic.colour",
            "material.viscoelastic.gamma",
            "material.viscoelastic.prony",
        ] {
            assert!(e.has_key(key), "{key} not reported: {e}");
        }
        let text = e.to_string();
        assert!(
            text.contains("maxwell") && text.contains("\"multiplicative\""),
            "{text}"
        );
        // Values checked by the law: a non-positive relaxation time, a negative gamma.
        let bad = base.replace("[0.3, 1]]", "[0.3, 0.0]]");
        let e = Scene::from_toml_str(&bad, "v.toml", &[]).expect_err("tau = 0");
        let err = e
            .find("material.viscoelastic.prony")
            .unwrap_or_else(|| panic!("{e}"));
        assert!(err.message.contains("tau > 0"), "{}", err.message);
        assert_eq!(err.line, Some(15));
        let bad = base.replace("gamma = 200.0", "gamma = -1.0");
        let e = Scene::from_toml_str(&bad, "v.toml", &[]).expect_err("gamma < 0");
        assert!(e.has_key("material.viscoelastic.gamma"), "{e}");
        // Missing keys.
        let bad = base.replace("gamma = 200.0\n", "");
        let e = Scene::from_toml_str(&bad, "v.toml", &[]).expect_err("missing");
        assert!(e.has_key("material.viscoelastic.gamma"), "{e}");
    }
}
