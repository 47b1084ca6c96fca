//! The typed contents of a run's `summary.json`, one structure per analysis mode.
//!
//! [`Summary`] is the envelope every mode writes (`scene`, `mode`, `dofs`, `converged`,
//! `version`) with the mode's own part flattened into it ([`ModeSummary`]): the run's counts and
//! error ([`RunStats`]), the `results` of the mode ([`SolidResults`], [`TransientResults`],
//! [`SteadyResults`], [`StickSlipResults`], [`CompareResults`]), the physical terms the model
//! carried ([`Terms`] and its per-mode extensions), the mesh ([`MeshInfo`]) and the solver's
//! report. The drivers fill these structures; `summary.json` is their serialization
//! ([`Summary::to_json`], where non-finite numbers become null), and [`crate::driver::results::RunOutcome`]
//! carries them in memory, so that `tread compare` and the tools read typed fields instead of
//! keys.
//!
//! Keys that some modes write as null are `Option` fields serialized as null; keys that a mode
//! does not write at all are `Option` fields skipped when `None`, or live only in that mode's
//! structure.
//!
//! Units are the scene's (consistent units, e.g. SI): lengths in its length unit, forces and
//! tractions per unit thickness, torques (moments) per unit thickness, ω in rad/s
//! (counter-clockwise > 0), times in seconds (wall times measured on the machine).

use super::indentation::IndentationResults;
use super::resistance::RollingResistance;
use super::spinning::SpinningResults;
use super::steady_report::{Attempt, CoarseStart, Recovery};
pub use super::transient::energy::{ViscousEnergy, ENERGY_CREATED_TOL};
use crate::contact::stick_slip::{ClosedFormCycle, SolverStats};
use crate::io::output::sanitize;
use crate::model::system::SteadyDampingTangent;
use crate::solver::continuation::{BranchPoint, LimitJump, PointKind, SpecialPoint};
use serde::Serialize;

/// The whole `summary.json` of a run: the keys every mode writes and the mode's own part.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// The scene's name (`[scene] name`).
    pub scene: String,
    /// The analysis mode (`static`, `spinning`, `steady`, `transient`, `stick_slip`, `compare`).
    pub mode: String,
    /// Number of unknowns of the solved system (the steady run's for `compare`; 2 for the
    /// stick-slip oscillator).
    pub dofs: usize,
    /// Whether the run reached its end without a failure.
    pub converged: bool,
    /// Version of `tread` that wrote the summary.
    pub version: String,
    /// The mode's own keys.
    #[serde(flatten)]
    pub body: ModeSummary,
}

impl Summary {
    /// A summary of this program's version.
    pub fn new(
        scene: impl Into<String>,
        mode: impl Into<String>,
        dofs: usize,
        converged: bool,
        body: ModeSummary,
    ) -> Self {
        Self {
            scene: scene.into(),
            mode: mode.into(),
            dofs,
            converged,
            version: env!("CARGO_PKG_VERSION").to_string(),
            body,
        }
    }

    /// The JSON of `summary.json`: the serialization with every non-finite number as null.
    pub fn to_json(&self) -> serde_json::Value {
        let mut v = serde_json::to_value(self).unwrap_or_default();
        sanitize(&mut v);
        v
    }

    /// Newton iterations, wall time and error of the run (not given by `compare`).
    pub fn run_stats(&self) -> Option<&RunStats> {
        match &self.body {
            ModeSummary::Solid(s) => Some(&s.run),
            ModeSummary::Solid3D(s) => Some(&s.run),
            ModeSummary::Transient(s) => Some(&s.run),
            ModeSummary::Steady(s) => Some(&s.run),
            ModeSummary::StickSlip(s) => Some(&s.run),
            ModeSummary::ModelProblem(s) => Some(&s.run),
            ModeSummary::Compare(_) | ModeSummary::Compare3D(_) => None,
        }
    }

    /// The results of a three-dimensional run (None for the other modes).
    pub fn solid3d(&self) -> Option<&Solid3DResults> {
        match &self.body {
            ModeSummary::Solid3D(s) => Some(&s.results),
            _ => None,
        }
    }

    /// The three-dimensional comparison's results.
    pub fn compare_3d(&self) -> Option<&Compare3DResults> {
        match &self.body {
            ModeSummary::Compare3D(s) => Some(&s.results.compare),
            _ => None,
        }
    }

    /// The transient mode's results (None for other modes and for a transient run that
    /// integrated nothing).
    pub fn transient(&self) -> Option<&TransientResults> {
        match &self.body {
            ModeSummary::Transient(s) => s.results.as_ref(),
            _ => None,
        }
    }

    /// The steady mode's results.
    pub fn steady(&self) -> Option<&SteadyResults> {
        match &self.body {
            ModeSummary::Steady(s) => Some(&s.results),
            _ => None,
        }
    }

    /// The comparison's results.
    pub fn compare(&self) -> Option<&CompareResults> {
        match &self.body {
            ModeSummary::Compare(s) => Some(&s.results.compare),
            _ => None,
        }
    }

    /// `results.steady` of the rolling modes: whether the transient run reached its steady
    /// state, or whether the steady solve converged (None for the other modes).
    pub fn steady_reached(&self) -> Option<bool> {
        match &self.body {
            ModeSummary::Transient(s) => s.results.as_ref().map(|r| r.steady),
            ModeSummary::Steady(s) => Some(s.results.steady),
            _ => None,
        }
    }
}

/// The keys of one mode's summary.
#[derive(Clone, Debug, Serialize)]
#[serde(untagged)]
pub enum ModeSummary {
    /// `static` and `spinning`.
    Solid(SolidSummary),
    /// `static` and `spinning` of a three-dimensional scene (`mesh.dimension = 3`).
    Solid3D(Box<Solid3DSummary>),
    Transient(TransientSummary),
    Steady(Box<SteadySummary>),
    StickSlip(StickSlipSummary),
    Compare(CompareSummary),
    /// `compare` of a three-dimensional scene.
    Compare3D(Box<Compare3DSummary>),
    /// A model problem of `src/adapt/` (a scene with `[problem]`).
    ModelProblem(Box<ModelProblemSummary>),
}

/// Counts, wall time and error of a run (every mode but `compare`).
#[derive(Clone, Debug, Serialize)]
pub struct RunStats {
    /// Newton iterations over the whole run.
    pub newton_iterations: usize,
    /// Wall time of the run (s).
    pub wall_time_s: f64,
    /// Why the run failed (null when it converged).
    pub error: Option<String>,
}

/// The physical terms a model carried (`terms`).
#[derive(Clone, Debug, Serialize)]
pub struct Terms {
    /// Friction law active on the road.
    pub friction: bool,
    /// Normal contact damping.
    pub normal_damping: bool,
    /// Inertia (centrifugal and, in the transient mode, the mass matrix).
    pub inertia: bool,
    /// A viscoelastic history.
    pub history: bool,
    /// Pressure unknowns (incompressible formulation).
    pub pressure: bool,
    /// Mean number of contact facets integrated per assembly.
    pub contact_facets_per_iteration: f64,
}

/// `terms` of the transient mode.
#[derive(Clone, Debug, Serialize)]
pub struct TransientTerms {
    #[serde(flatten)]
    pub common: Terms,
    /// Strain-rate (Kelvin–Voigt) damping in the bulk.
    pub strain_rate_damping: bool,
}

/// `terms` of the steady mode.
#[derive(Clone, Debug, Serialize)]
pub struct SteadyTerms {
    #[serde(flatten)]
    pub common: Terms,
    /// Strain-rate (Kelvin–Voigt) damping in the bulk.
    pub strain_rate_damping: bool,
    /// Newton matrix of that damping (null when the damping is not active).
    pub damping_tangent: Option<SteadyDampingTangent>,
    /// Why the matrix-free damping tangent was given up for the assembled one (null when not).
    pub damping_tangent_fallback: Option<String>,
}

/// `mesh`: size of the mesh.
#[derive(Clone, Debug, Serialize)]
pub struct MeshInfo {
    /// Cells through the thickness and around the circumference (`[mesh]`).
    pub n_r: usize,
    pub n_theta: usize,
    /// Polynomial degree of the cells.
    pub order: usize,
    /// Nodes and cells of the mesh.
    pub nodes: usize,
    pub cells: usize,
}

/// `mesh` of the static and spinning modes.
#[derive(Clone, Debug, Serialize)]
pub struct SolidMesh {
    #[serde(flatten)]
    pub common: MeshInfo,
    /// Pressure unknowns (per-cell pressures of the incompressible formulation).
    pub pressure_dofs: usize,
}

/// `solver` of the static and spinning modes.
#[derive(Clone, Debug, Serialize)]
pub struct SolidSolver {
    /// Linear solver used at the end (`cholesky` or `lu`).
    pub linear: String,
    /// Whether Cholesky failed and LU took over.
    pub switched_to_lu: bool,
    /// Converged load steps and cut-backs of the load stepping.
    pub load_steps: usize,
    pub cutbacks: usize,
    /// Worker threads of the assembly and solvers.
    pub threads: usize,
    /// Load factor at which an interrupt stopped the run (absent when not interrupted).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub interrupted_at: Option<f64>,
    /// Three-dimensional steady mode: how the solve started from the steady state of a
    /// coarser mesh (absent when the nested iteration does not apply).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coarse_start: Option<CoarseStart>,
}

/// `results` of the static and spinning modes.
#[derive(Clone, Debug, Serialize)]
#[serde(untagged)]
pub enum SolidResults {
    /// Static indentation: hub loads, contact patch, road height.
    Static(IndentationResults),
    /// Free spinning: ring-averaged displacements and stresses.
    Spinning(SpinningResults),
}

/// summary.json of the static and spinning modes.
#[derive(Clone, Debug, Serialize)]
pub struct SolidSummary {
    #[serde(flatten)]
    pub run: RunStats,
    pub results: SolidResults,
    pub terms: Terms,
    pub mesh: SolidMesh,
    pub solver: SolidSolver,
}

/// summary.json of a three-dimensional static or spinning run (forces are totals, not per
/// width).
#[derive(Clone, Debug, Serialize)]
pub struct Solid3DSummary {
    #[serde(flatten)]
    pub run: RunStats,
    pub results: Solid3DResults,
    pub mesh: Solid3DMesh,
    pub solver: SolidSolver,
}

/// `results` of a three-dimensional run.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Solid3DResults {
    /// Always 3.
    pub dimension: usize,
    /// Resultant of the contact tractions on the body ∫ T dA0 (F1 along the road, F2 up, F3
    /// along the axle); zero without contact.
    pub contact_force: [f64; 3],
    /// Moment of the contact tractions about the hub centre.
    pub contact_moment: [f64; 3],
    /// The hub load of load control (`road.load`; null under displacement control and in the
    /// spinning mode).
    pub load: Option<f64>,
    /// Final road height H and penetration h_touch − H (null without contact).
    pub road_height: Option<f64>,
    pub penetration: Option<f64>,
    /// Reference area of the facet points in contact, largest pressure and penetration.
    pub contact_area: f64,
    pub max_pressure: f64,
    pub max_penetration: f64,
    /// Facet quadrature points in contact.
    pub points_in_contact: usize,
    /// Angular speed reached (spinning, steady; 0 in the static mode).
    pub omega: f64,
    /// Mean radial displacement of the outer surface nodes, Σ u·e_R / n (transient: of the
    /// deformation χ − Q(φ) X, the rigid rotation taken out).
    pub u_r_outer_mean: f64,
    /// Largest nodal |u| (transient: |χ − Q(φ) X|).
    pub max_displacement: f64,
    /// The six loads of the road on the body at the hub centre, named (null without contact).
    pub hub_loads: Option<HubLoads3D>,
    /// Steady mode: the road velocity (V1, V3) in its plane.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub road_velocity: Option<[f64; 2]>,
    /// Steady mode: the slip angle α (degrees).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub slip_angle: Option<f64>,
    /// Steady mode: the road speed v0 of the final state (`road.v0`, or the one the rolling
    /// control found).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub v0: Option<f64>,
    /// Steady mode with a multiplicative viscoelastic material: the power ∫ D dV its
    /// overstress dissipates (with no other dissipation, the axle moment times ω).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub viscous_dissipation: Option<f64>,
    /// Steady mode with `motion.control` other than `speed`: what the control did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub control: Option<ControlReport>,
    /// Steady mode with `[continuation]`: how the path went, and its converged points.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub continuation: Option<ContinuationSummary>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub branch: Option<Vec<BranchRow3D>>,
    /// Transient mode: the integration and the steady state it reached.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub transient: Option<Transient3DResults>,
}

/// What the transient run reports in `results.transient`.
#[derive(Clone, Debug, Serialize)]
pub struct Transient3DResults {
    pub integrator: String,
    pub steps: usize,
    pub rejected: usize,
    pub newton_iterations: usize,
    /// Whether (and when) the passage-to-passage changes fell below `time.steady_tol` twice.
    pub steady: bool,
    pub time_to_steady: Option<f64>,
    pub final_time: f64,
    pub revolutions: f64,
    pub passages: usize,
    /// Relative changes over the last passage: referential field, hub force, hub moment.
    pub last_change: [f64; 3],
    /// The road's loads on the body at the hub centre, road frame, averaged over the last
    /// passage (the negative of the hub's reaction: at a steady state the body's momentum
    /// and angular momentum are constant); null before two passages.
    pub hub_loads_passage_mean: Option<HubLoads3D>,
    pub dt_min_used: f64,
    pub dt_max_used: f64,
}

/// A converged point of a three-dimensional continuation (`results.branch`, `branch.csv`).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct BranchRow3D {
    /// Continuation step (0 = the start) and its parameter value.
    pub step: usize,
    pub lambda: f64,
    /// Corrector iterations of the step.
    pub iterations: usize,
    /// Slip angle and camber (degrees), road speed and road height of the point.
    pub slip_angle: f64,
    pub camber: f64,
    pub v0: f64,
    pub road_height: f64,
    /// The six hub loads (road frame) of the point.
    #[serde(flatten)]
    pub hub_loads: HubLoads3D,
    pub points_in_contact: usize,
}

impl BranchRow3D {
    /// The row of the converged point `p` of `sys`'s path (the contact totals of its last
    /// evaluation).
    pub fn new(sys: &crate::model::Solid3DSystem, p: &BranchPoint) -> Self {
        let rc = sys.contact.as_ref();
        let t = rc.map(|c| c.totals).unwrap_or_default();
        let hub_loads = match rc {
            Some(c) => {
                let f = c.surface.frame();
                HubLoads3D::new(f.components(t.force), f.components(t.moment))
            }
            None => HubLoads3D::new([f64::NAN; 3], [f64::NAN; 3]),
        };
        Self {
            step: p.step,
            lambda: p.lambda,
            iterations: p.iterations,
            slip_angle: sys.slip_angle().to_degrees(),
            camber: sys.camber().to_degrees(),
            v0: sys.road_speed(),
            road_height: sys.road_height().unwrap_or(f64::NAN),
            hub_loads,
            points_in_contact: t.points_in_contact,
        }
    }
}

/// The loads of the road on the body reduced to the hub centre (the origin), totals over the
/// width, in the road frame (e1, n, e3) of [`crate::contact::facet3d::RoadFrame`]: without
/// camber (x1 along the road, x2 up, x3 along the axle).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct HubLoads3D {
    /// Longitudinal force, along e1.
    pub longitudinal_force: f64,
    /// Vertical force, along the road normal n (up; the wheel load).
    pub vertical_force: f64,
    /// Lateral force, along e3.
    pub lateral_force: f64,
    /// Overturning moment, about e1.
    pub overturning_moment: f64,
    /// Aligning moment, about n.
    pub aligning_moment: f64,
    /// Moment about e3 (the axle without camber; the drive torque the hub supplies is its
    /// negative).
    pub axle_moment: f64,
}

impl HubLoads3D {
    /// The keys of the six loads, in [`Self::to_array`] order.
    pub const NAMES: [&'static str; 6] = [
        "longitudinal_force",
        "vertical_force",
        "lateral_force",
        "overturning_moment",
        "aligning_moment",
        "axle_moment",
    ];

    /// The six loads in [`Self::NAMES`] order.
    pub fn to_array(&self) -> [f64; 6] {
        [
            self.longitudinal_force,
            self.vertical_force,
            self.lateral_force,
            self.overturning_moment,
            self.aligning_moment,
            self.axle_moment,
        ]
    }

    /// From the road-frame components of the contact resultant `f` and of its moment `m`
    /// about the hub centre.
    pub fn new(f: [f64; 3], m: [f64; 3]) -> Self {
        Self {
            longitudinal_force: f[0],
            vertical_force: f[1],
            lateral_force: f[2],
            overturning_moment: m[0],
            aligning_moment: m[1],
            axle_moment: m[2],
        }
    }
}

/// `mesh` of a three-dimensional run.
#[derive(Clone, Debug, Serialize)]
pub struct Solid3DMesh {
    /// Generated wheel: the cells in r, θ and x3 and the order (null for a mesh file).
    pub n_r: Option<usize>,
    pub n_theta: Option<usize>,
    pub n_z: Option<usize>,
    pub order: Option<usize>,
    /// Width of the generated wheel (null for a mesh file).
    pub width: Option<f64>,
    /// `mesh.sides` of the generated wheel (null for a mesh file).
    pub sides: Option<String>,
    pub crown_radius: Option<f64>,
    pub nodes: usize,
    pub cells: usize,
    pub pressure_dofs: usize,
    /// Facets of the contact surface (0 in the spinning mode).
    pub contact_facets: usize,
}

/// `results` of the transient mode (the final state, or the last node passage where stated).
#[derive(Clone, Debug, Serialize)]
pub struct TransientResults {
    /// `motion.control` (`speed` or `torque`).
    pub control: String,
    /// Hub angular speed at the end of the run (rad/s).
    pub omega_steady: f64,
    /// Hub torque applied at the end (torque control; per unit thickness).
    pub applied_torque: f64,
    /// v0 / ω at the end (length; NaN when ω = 0).
    pub rolling_radius: f64,
    /// Moment of the contact tractions about the hub centre (per unit thickness).
    pub contact_moment: f64,
    /// Time at which the state became steady (s; null when it did not).
    pub time_to_steady: Option<f64>,
    /// Hub revolutions integrated.
    pub revolutions: f64,
    /// Accepted and rejected time steps.
    pub steps: usize,
    pub rejected_steps: usize,
    /// Whether steady rolling was reached.
    pub steady: bool,
    /// Time at the end of the run (s).
    pub final_time: f64,
    /// Node passages seen by the steady-state monitor.
    pub node_passages: usize,
    /// Relative changes over the last node passage of the referential field, hub force, hub
    /// torque and hub speed (dimensionless).
    pub steady_change_field: f64,
    pub steady_change_force: f64,
    pub steady_change_torque: f64,
    pub steady_change_omega: f64,
    /// Smallest and largest time step used (s).
    pub dt_min_used: f64,
    pub dt_max_used: f64,
    /// Force and moment the hub exerts on the body at the last step (per unit thickness).
    pub hub_force_x: f64,
    pub hub_force_y: f64,
    pub hub_torque: f64,
    /// Hub loads averaged over the last node passage (null before two passages).
    pub hub_force_x_passage_mean: Option<f64>,
    pub hub_force_y_passage_mean: Option<f64>,
    pub hub_torque_passage_mean: Option<f64>,
    /// Contact patch ends in x1 (length) and peak normal traction (per unit reference length).
    pub contact_x_min: f64,
    pub contact_x_max: f64,
    pub max_pressure: f64,
    /// Resultant of the contact tractions on the body (per unit thickness).
    pub contact_force_x: f64,
    pub contact_force_y: f64,
    /// Centroid x1 of the normal traction (length).
    pub contact_centroid: f64,
    /// Hertz-type half-width 2 √⟨(x1 − x̄)²⟩ of the normal traction (length).
    pub contact_half_width_moment: f64,
    /// Time integrator and mass matrix (`lumped` or `consistent`).
    pub integrator: String,
    pub mass: String,
    /// Energy of the viscous overstress (viscoelastic materials only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub viscous_energy: Option<Box<ViscousEnergy>>,
}

/// summary.json of the transient mode.
#[derive(Clone, Debug, Serialize)]
pub struct TransientSummary {
    #[serde(flatten)]
    pub run: RunStats,
    pub warnings: Vec<String>,
    /// Null when nothing was integrated (the initial rigid spin failed).
    pub results: Option<TransientResults>,
    /// Absent when nothing was integrated.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub terms: Option<TransientTerms>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mesh: Option<MeshInfo>,
}

/// One row of the steady branch table (`branch.csv`, `results.branch`).
#[derive(Clone, Debug, Serialize)]
pub struct BranchRow {
    /// Continuation step (0: the start point).
    pub step: usize,
    /// Continuation parameter (ω in rad/s, hub load per unit thickness, DISP or creep).
    pub lambda: f64,
    /// Angular speed (rad/s) and road speed (length/s).
    pub omega: f64,
    pub v0: f64,
    /// Penetration DISP = Ro − H (length).
    pub penetration: f64,
    /// Hub loads (per unit thickness).
    pub hub_force_x: f64,
    pub hub_force_y: f64,
    pub hub_torque: f64,
    /// Contact patch ends in x1 (length) and peak normal traction.
    pub contact_x_min: f64,
    pub contact_x_max: f64,
    pub max_pressure: f64,
    /// Standing-wave indicator: half the peak-to-peak radial displacement of the outer
    /// surface nodes more than 60° away from the bottom (outside the patch region; length).
    pub wave_amplitude: f64,
    /// Dominant circumferential wave number on the same arc (windowed Fourier spectrum of u_r,
    /// n ≥ 4; NaN on a mesh without rings).
    pub wave_number: f64,
    /// Sign of the tangent's determinant, its negative eigenvalues and the bifurcation test
    /// function.
    pub det_sign: f64,
    pub negative_eigenvalues: f64,
    pub test_function: f64,
    /// Corrector iterations.
    pub iterations: usize,
    pub kind: PointKind,
    /// Wall time of the step and of one factorization + solve (s).
    pub wall_time_s: f64,
    pub factor_solve_s: f64,
    /// Creep ξ = v0 / v0_free − 1 (NaN, an empty CSV field, without a free-rolling reference).
    pub creep: f64,
}

impl BranchRow {
    pub const HEADER: [&'static str; 21] = [
        "step",
        "lambda",
        "omega",
        "v0",
        "penetration",
        "hub_force_x",
        "hub_force_y",
        "hub_torque",
        "contact_x_min",
        "contact_x_max",
        "max_pressure",
        "wave_amplitude",
        "wave_number",
        "det_sign",
        "negative_eigenvalues",
        "test_function",
        "iterations",
        "kind",
        "wall_time_s",
        "factor_solve_s",
        "creep",
    ];

    /// The row as the numbers of `branch.csv` (in [`Self::HEADER`] order).
    pub fn values(&self) -> Vec<f64> {
        let kind = match self.kind {
            PointKind::Start => 0.0,
            PointKind::Regular => 1.0,
            PointKind::LimitPoint => 2.0,
            PointKind::Bifurcation => 3.0,
            PointKind::Switched => 4.0,
            PointKind::Jump => 5.0,
        };
        vec![
            self.step as f64,
            self.lambda,
            self.omega,
            self.v0,
            self.penetration,
            self.hub_force_x,
            self.hub_force_y,
            self.hub_torque,
            self.contact_x_min,
            self.contact_x_max,
            self.max_pressure,
            self.wave_amplitude,
            self.wave_number,
            self.det_sign,
            self.negative_eigenvalues,
            self.test_function,
            self.iterations as f64,
            kind,
            self.wall_time_s,
            self.factor_solve_s,
            self.creep,
        ]
    }
}

/// What the rolling control (`motion.control`) did after the press-in (`results.control`).
#[derive(Clone, Debug, Default, Serialize)]
pub struct ControlReport {
    /// `speed`, `torque`, `free_rolling` or `creep`.
    pub control: String,
    /// Target hub torque (torque and free rolling; 0 for creep's free-rolling stage; per unit
    /// thickness).
    pub target_torque: f64,
    /// Torque tolerance (absolute): `TORQUE_RTOL` · |F_y| · Ro at the press-in state.
    pub torque_tolerance: f64,
    /// Free-rolling road speed v0_free and rolling radius R_e = v0_free / ω (free rolling and
    /// creep; NaN otherwise).
    pub v0_free: f64,
    pub rolling_radius: f64,
    /// Creep ξ = v0 / v0_free − 1 of the final state (NaN without a free-rolling reference).
    pub creep: f64,
    /// Steady solves (one Newton solve per trial v0) and their Newton iterations.
    pub evaluations: usize,
    pub newton_iterations: usize,
    /// (v0, hub torque) of every trial of the secant iteration.
    pub history: Vec<(f64, f64)>,
}

/// `results.continuation` of the steady mode: how the branch was followed.
#[derive(Clone, Debug, Serialize)]
pub struct ContinuationSummary {
    /// `[continuation] parameter` (`omega`, `load`, `disp`, `creep`).
    pub parameter: Option<String>,
    /// Why the continuation stopped.
    pub stop_reason: String,
    /// Continuation steps, corrector iterations, step halvings, assemblies and factorizations.
    pub steps: usize,
    pub corrector_iterations: usize,
    pub cutbacks: usize,
    pub assemblies: usize,
    pub factorizations: usize,
    /// The step after which the path switched branches (`[continuation] switch_branch`; null
    /// when it did not).
    pub switched_at: Option<usize>,
    /// Jumps past limit points (`[continuation] on_limit = "jump"`), in order: the step of the
    /// first point after the jump (kind 5 in `branch.csv`), the limit point's parameter and the
    /// parameter the direct solve landed at.
    pub jumps: Vec<LimitJump>,
    /// Parameter values of the limit points past which no jump found a steady solution (the
    /// path followed the branch back there).
    pub failed_jumps: Vec<f64>,
}

impl ContinuationSummary {
    /// The summary of the continuation `c` of `scene`'s `[continuation]`.
    pub fn new(
        scene: &crate::io::scene::Scene,
        c: &crate::solver::continuation::ContinuationReport,
    ) -> Self {
        Self {
            parameter: scene.continuation.as_ref().map(|c| c.parameter.to_string()),
            stop_reason: c.stop_reason.clone(),
            steps: c.points.len().saturating_sub(1),
            corrector_iterations: c.total_iterations,
            cutbacks: c.cutbacks,
            assemblies: c.assemblies,
            factorizations: c.factorizations,
            switched_at: c.switched_at,
            jumps: c.jumps.clone(),
            failed_jumps: c.failed_jumps.clone(),
        }
    }
}

/// `results` of the steady mode (the final state; the keys shared with the transient mode have
/// the same meaning).
#[derive(Clone, Debug, Serialize)]
pub struct SteadyResults {
    /// Whether the steady solve converged.
    pub steady: bool,
    /// Always 0 (the keys of the transient mode).
    pub time_to_steady: f64,
    pub revolutions: f64,
    /// Converged steps: load steps of the path to the first solution and continuation steps.
    pub steps: usize,
    /// Angular speed (rad/s), road speed (length/s) and penetration DISP (length).
    pub omega: f64,
    pub v0: f64,
    pub penetration: f64,
    /// Hub loads (per unit thickness).
    pub hub_force_x: f64,
    pub hub_force_y: f64,
    pub hub_torque: f64,
    /// Contact patch ends in x1 (length) and peak normal traction.
    pub contact_x_min: f64,
    pub contact_x_max: f64,
    pub max_pressure: f64,
    /// Resultant of the contact tractions on the body (per unit thickness).
    pub contact_force_x: f64,
    pub contact_force_y: f64,
    /// Centroid x1 of the normal traction (length).
    pub contact_centroid: f64,
    /// Hertz-type half-width 2 √⟨(x1 − x̄)²⟩ of the normal traction (length).
    pub contact_half_width_moment: f64,
    /// Wall time to the first steady solution (s).
    pub wall_time_first_solution_s: f64,
    /// Creep ξ = v0 / v0_free − 1 (NaN without a free-rolling reference).
    pub creep: f64,
    /// What the rolling control did (null under speed control).
    pub control: Option<ControlReport>,
    /// Rolling resistance along a branch in ω of a viscoelastic body (absent otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rolling_resistance: Option<RollingResistance>,
    /// Converged branch points (with continuation only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub branch: Option<Vec<BranchRow>>,
    /// Limit and bifurcation points (with continuation only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub special_points: Option<Vec<SpecialPoint>>,
    /// How the branch was followed (with continuation only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub continuation: Option<ContinuationSummary>,
}

/// `solver` of the steady mode.
#[derive(Clone, Debug, Serialize)]
pub struct SteadySolver {
    /// Linear solver of the press-in (`cholesky` or `lu`).
    pub linear: String,
    /// Converged load steps and cut-backs of the press-in.
    pub load_steps: usize,
    pub cutbacks: usize,
    /// Worker threads of the assembly and solvers.
    pub threads: usize,
    /// What the recovery of a failed press-in did (null when none ran).
    pub recovery: Option<Recovery>,
    /// The continuation in the friction regularisation ε before the press-in (null when none).
    pub eps_continuation: Option<Attempt>,
    /// The start from a coarser mesh's steady state (null when none was tried).
    pub coarse_start: Option<CoarseStart>,
}

/// summary.json of the steady mode.
#[derive(Clone, Debug, Serialize)]
pub struct SteadySummary {
    #[serde(flatten)]
    pub run: RunStats,
    pub warnings: Vec<String>,
    pub results: SteadyResults,
    pub terms: SteadyTerms,
    pub mesh: MeshInfo,
    pub solver: SteadySolver,
}

/// `results` of the stick-slip mode (times in s, positions in the scene's length unit).
#[derive(Clone, Debug, Serialize)]
pub struct StickSlipResults {
    /// Mean period of the stick-slip cycle (null with fewer than two cycles).
    pub period: Option<f64>,
    /// Slip amplitude (x_max − x_min) / 2 of the cycle (null with fewer than two cycles).
    pub amplitude: Option<f64>,
    /// Extremes of the block position over the measured cycles.
    pub x_min: Option<f64>,
    pub x_max: Option<f64>,
    /// Time sticking and slipping per cycle.
    pub stick_time: Option<f64>,
    pub slip_time: Option<f64>,
    /// Stick-to-slip transitions seen.
    pub cycles: usize,
    /// Counts of the ODE solver.
    pub solver_stats: SolverStats,
    /// (measured − closed form) / closed form of the period and amplitude (null without a
    /// closed form or a measurement).
    pub period_rel_error: Option<f64>,
    pub amplitude_rel_error: Option<f64>,
    /// The closed-form static/kinetic cycle (rate-dependent law only; null otherwise).
    pub closed_form: Option<ClosedFormCycle>,
}

/// summary.json of the stick-slip mode.
#[derive(Clone, Debug, Serialize)]
pub struct StickSlipSummary {
    #[serde(flatten)]
    pub run: RunStats,
    /// Null when the integration failed.
    pub results: Option<StickSlipResults>,
    pub terms: Terms,
}

/// `results.compare` of `tread compare`: the transient and steady modes side by side (see
/// [`super::compare`] for the definitions).
#[derive(Clone, Debug, Serialize)]
pub struct CompareResults {
    /// Hub loads of both modes (per unit thickness; the transient's passage means or last step
    /// as `transient_loads` says).
    pub hub_force_x_transient: f64,
    pub hub_force_x_steady: f64,
    pub hub_force_y_transient: f64,
    pub hub_force_y_steady: f64,
    pub hub_torque_transient: f64,
    pub hub_torque_steady: f64,
    /// `passage_mean` or `last_step`.
    pub transient_loads: String,
    /// The transient's hub loads at its last step.
    pub hub_force_x_transient_last_step: f64,
    pub hub_force_y_transient_last_step: f64,
    pub hub_torque_transient_last_step: f64,
    /// |F_i(transient) − F_i(steady)| / |F(steady)| (dimensionless).
    pub hub_force_x_rel_diff: f64,
    pub hub_force_y_rel_diff: f64,
    /// |T_t − T_s| (per unit thickness) and that over |F(steady)| Ro (dimensionless).
    pub hub_torque_abs_diff: f64,
    pub hub_torque_rel_diff: f64,
    /// ‖u_t − u_s‖_L2 / ‖u_s‖_L2 of the referential fields (dimensionless).
    pub field_rel_l2: f64,
    /// max over nodes of |u_t − u_s| (length) and that over max |u_s|.
    pub field_max_abs: f64,
    pub field_rel_max: f64,
    /// Internal variables of a stateful material compared along the rings of quadrature
    /// points (polar components): relative L2 difference and max difference over the largest
    /// steady value. `None` without internal variables to compare.
    pub history_rel_l2: Option<f64>,
    pub history_rel_max: Option<f64>,
    /// Contact patch ends (length) and peak pressure of both modes.
    pub contact_x_min_transient: f64,
    pub contact_x_min_steady: f64,
    pub contact_x_max_transient: f64,
    pub contact_x_max_steady: f64,
    pub max_pressure_transient: f64,
    pub max_pressure_steady: f64,
    /// Wall times of both runs (s) and their ratio transient / steady.
    pub wall_time_transient_s: f64,
    pub wall_time_steady_s: f64,
    pub speedup: f64,
    /// Whether the transient run reached its steady state, when (s) and in how many steps.
    pub transient_steady: bool,
    pub transient_time_to_steady: Option<f64>,
    pub transient_steps: usize,
    /// Every judged quantity: values, units, differences and the tolerance it is held to.
    pub quantities: Vec<CompareQuantity>,
    /// Whether every quantity is within its tolerance and the transient run reached its
    /// steady state.
    pub validated: bool,
    /// One sentence: "steady solution validated against the transient: …" or "not
    /// validated: …".
    pub verdict: String,
}

/// One quantity of `results.compare.quantities`: |Δq| = |q_t − q_s| over the scale it is
/// relative to, against its tolerance.
#[derive(Clone, Debug, Serialize)]
pub struct CompareQuantity {
    /// Key (`hub_force_x`, `hub_force_y`, `hub_torque`, `field_l2`, `contact_x_min`,
    /// `contact_x_max`, `max_pressure`).
    pub name: String,
    /// Unit in the scene's system (`[scene] units`), e.g. `lbf/in`; `1` when dimensionless.
    pub unit: String,
    /// Values of both modes (null for the field, compared as a whole).
    pub transient: Option<f64>,
    pub steady: Option<f64>,
    /// |q_t − q_s| (unit of the quantity; the field: ‖u_t − u_s‖_L2 / ‖u_s‖_L2).
    pub abs_diff: f64,
    /// abs_diff / scale.
    pub rel_diff: f64,
    /// What the difference is relative to, e.g. `|F_steady|`, `|hub_torque_steady|`,
    /// `|F_steady| Ro`, `steady patch length`.
    pub relative_to: String,
    /// Its value (unit of the quantity).
    pub scale: f64,
    /// Largest accepted rel_diff.
    pub tolerance: f64,
    pub within: bool,
}

/// `results` of `tread compare` (one key, `compare`).
#[derive(Clone, Debug, Serialize)]
pub struct CompareSection {
    pub compare: CompareResults,
}

/// summary.json of `tread compare`.
#[derive(Clone, Debug, Serialize)]
pub struct CompareSummary {
    pub warnings: Vec<String>,
    pub results: CompareSection,
    /// Output folders of the two runs.
    pub transient_dir: String,
    pub steady_dir: String,
}

/// `results.compare` of `tread compare` on a three-dimensional scene (see
/// [`super::compare3d`] for the definitions).
#[derive(Clone, Debug, Serialize)]
pub struct Compare3DResults {
    /// The six hub loads of both modes (road frame, totals over the width; the transient's
    /// averaged over its last node passage).
    pub hub_loads_transient: HubLoads3D,
    pub hub_loads_steady: HubLoads3D,
    /// ‖u_t − u_s‖_L2 / ‖u_s‖_L2 of the referential fields (dimensionless).
    pub field_rel_l2: f64,
    /// max over nodes of |u_t − u_s| (length) and that over max |u_s|.
    pub field_max_abs: f64,
    pub field_rel_max: f64,
    /// L2 differences over the tread of the contact pressure and of the tangential traction
    /// of both fields at the same points, relative to the steady ones (dimensionless).
    pub footprint_pressure_rel_l2: f64,
    pub footprint_traction_rel_l2: f64,
    /// Peak pressure (stress) and contact area (reference area in contact) of both.
    pub max_pressure_transient: f64,
    pub max_pressure_steady: f64,
    pub contact_area_transient: f64,
    pub contact_area_steady: f64,
    /// Wall times of both runs (s) and their ratio transient / steady.
    pub wall_time_transient_s: f64,
    pub wall_time_steady_s: f64,
    pub speedup: f64,
    /// Whether the transient run reached its steady state, when (s) and in how many steps.
    pub transient_steady: bool,
    pub transient_time_to_steady: Option<f64>,
    pub transient_steps: usize,
    /// Every judged quantity: values, units, differences and the tolerance it is held to.
    pub quantities: Vec<CompareQuantity>,
    pub validated: bool,
    pub verdict: String,
}

/// `results` of the three-dimensional `tread compare` (one key, `compare`).
#[derive(Clone, Debug, Serialize)]
pub struct Compare3DSection {
    pub compare: Compare3DResults,
}

/// summary.json of the three-dimensional `tread compare`.
#[derive(Clone, Debug, Serialize)]
pub struct Compare3DSummary {
    pub warnings: Vec<String>,
    pub results: Compare3DSection,
    /// Output folders of the two runs.
    pub transient_dir: String,
    pub steady_dir: String,
}

/// Everything a run produced.
#[derive(Debug)]
pub struct RunOutcome {
    /// The JSON of the run's `summary.json`.
    pub summary: serde_json::Value,
    /// The same summary, typed (`summary` is its [`Summary::to_json`]).
    pub typed: Summary,
    /// The referential displacement field of the rolling modes (2 per node in plane strain, 3
    /// in three dimensions; node order, the numbers of `steady_field.csv` and
    /// `steady_field_3d.csv`): the steady solution's nodal displacements, or the
    /// transient run's field extracted at its last node passage. None for the other modes and
    /// for a transient run that saw no node passage.
    pub field: Option<Vec<f64>>,
    /// The quadrature-point history of a stateful material on the referential cells: the
    /// steady solution's, or the transient run's at its last node passage
    /// ([`crate::driver::transient::SteadyMonitor::history`]). None otherwise.
    pub history: Option<crate::assembly::QpHistory>,
    /// The contact tractions of the final state at the facet quadrature points (the rows of
    /// `contact.csv`); empty without contact and in the three-dimensional runs.
    pub contact: Vec<crate::contact::ContactSample>,
    pub out_dir: std::path::PathBuf,
    pub converged: bool,
    /// Human-readable result lines for the terminal.
    pub headline: Vec<String>,
}

/// The `summary.json` keys of a model problem besides the common envelope.
#[derive(Clone, Debug, Serialize)]
pub struct ModelProblemSummary {
    /// `problem.kind`.
    pub kind: String,
    #[serde(flatten)]
    pub run: RunStats,
    /// The resolved `[problem]` table (every default filled).
    pub problem: serde_json::Value,
    /// The final results (null when the run failed before its first step or pass).
    pub results: Option<ModelResults>,
    /// Steps, passes or recalculations (rows of `steps.csv`).
    pub steps: usize,
    /// Where an interrupt stopped the run: the time (heat, burgers, Taylor–Green), the
    /// adaptive pass (lshape, Kovasznay) or the Reynolds number (cavity) reached; absent when
    /// not interrupted.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub interrupted_at: Option<f64>,
}

/// `results` of one kind.
#[derive(Clone, Debug, Serialize)]
#[serde(untagged)]
pub enum ModelResults {
    Cavity(CavityResults),
    TwoGrid(TwoGridResults),
    PNavierStokes(PnsResults),
    LShape(LShapeResults),
}

/// `results` of `cavity`.
#[derive(Clone, Debug, Serialize)]
pub struct CavityResults {
    pub reynolds: f64,
    pub equations: usize,
    pub cells: usize,
    /// Mesh relocations made (0 on the uniform mesh).
    pub recalculations: usize,
    /// Smallest corner det J of the final cells.
    pub min_det_j: f64,
    pub psi_min: f64,
    pub psi_min_at: [f64; 2],
    /// Source of the reference tables (null: no published reference for this lid and Re).
    pub reference: Option<String>,
    /// Largest |u(0.5, y) − u_ref| and |v(x, 0.5) − v_ref| over the tabulated stations.
    pub centreline_u_error: Option<f64>,
    pub centreline_v_error: Option<f64>,
    /// The larger of the two.
    pub centreline_error: Option<f64>,
    /// |ψ_min − ψ_min,ref| (Re = 1000, Botella & Peyret).
    pub psi_min_error: Option<f64>,
    /// The same two errors on the starting uniform mesh (recalculation 0).
    pub uniform_centreline_error: Option<f64>,
    pub uniform_psi_min_error: Option<f64>,
}

/// `results` of `heat` and `burgers`.
#[derive(Clone, Debug, Serialize)]
pub struct TwoGridResults {
    /// Time of the final solution.
    pub t: f64,
    pub equations: usize,
    pub max_equations: usize,
    pub cells: usize,
    /// ‖u − u_h‖_{L²} and |u − u_h|_{H¹} at the final time against the exact solution.
    pub l2_error: f64,
    pub h1_error: f64,
    /// The two-grid estimate ‖u_f − u_h‖ and its effectivity estimate / l2_error.
    pub estimate: f64,
    pub effectivity: f64,
}

/// `results` of `p_navier_stokes`.
#[derive(Clone, Debug, Serialize)]
pub struct PnsResults {
    pub flow: String,
    /// Time of the final solution (Kovasznay: 0).
    pub t: f64,
    pub equations: usize,
    pub equations_enriched: usize,
    /// The enrichment estimate, the true L² velocity error and their ratio.
    pub estimate: f64,
    pub l2_error: f64,
    pub effectivity: f64,
    pub tolerance: f64,
    /// Largest η_K / τ_K (≤ 1: every cell within its share of the tolerance).
    pub worst_ratio: f64,
    /// Whether the final solution met the tolerance (no cell left to raise).
    pub accepted: bool,
    /// Solves made (steady: sweeps; transient: attempts over all steps).
    pub solves: usize,
    /// Cells per velocity degree of the final solution: [degree, cells].
    pub degrees: Vec<[usize; 2]>,
}

/// `results` of `lshape`.
#[derive(Clone, Debug, Serialize)]
pub struct LShapeResults {
    pub equations: usize,
    pub cells: usize,
    pub max_level: u32,
    pub max_degree: usize,
    /// |u − u_h|₁, relative to |u|₁, the estimate and estimate / energy_error.
    pub energy_error: f64,
    pub relative_error: f64,
    pub estimate: f64,
    pub effectivity: f64,
    /// Least-squares slope of log(energy_error) against log(equations) over the meshes with at
    /// least 400 equations (null with fewer than three).
    pub rate: Option<f64>,
}
