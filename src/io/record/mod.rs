//! The recorder: one event interface between the drivers and every output sink (CSV, VTU/PVD,
//! MCAP, Rerun `.rrd`, PNG plots, the progress bar).
//!
//! Drivers emit **events** with **read-only views** of their state; sinks turn them into files.
//! Sinks never steer the solve: every method returns `()` (a sink that fails to write keeps the
//! first error and reports it from [`Recorder::run_finished`]), and the views are plain structs
//! of shared references. With no sinks (`()` or an empty [`Recorders`]) an event is one virtual
//! call that does nothing, and [`Recorder::wants_view`] returns `false`, so the driver never
//! builds the (costly) view: logging then costs nothing measurable (`tread-bench-log` measures
//! it).
//!
//! # Events, in order
//!
//! | event | when | data |
//! |---|---|---|
//! | [`run_started`](Recorder::run_started) | once, before the solve | [`RunMeta`]: scene, mesh, build |
//! | [`newton_iteration`](Recorder::newton_iteration) | after each Newton solve, once per row of its table | [`NewtonIteration`] |
//! | [`step_rejected`](Recorder::step_rejected) | a step (load increment, time step) failed and is retried | [`RejectedStep`] |
//! | [`step`](Recorder::step) | a step was accepted (state committed) | [`StepInfo`] always, [`StepView`] when wanted |
//! | [`continuation_point`](Recorder::continuation_point) | a converged point of a branch (arc length) | [`ContinuationPoint`] |
//! | [`steady_reached`](Recorder::steady_reached) | a steady state was detected / solved | [`SteadyReached`] + [`StepView`] |
//! | [`run_finished`](Recorder::run_finished) | once, at the end (also after a failure or an interrupt) | [`RunEnd`] |
//!
//! # How a driver calls it
//!
//! ```ignore
//! use tread::driver::frame::SolidFrame;
//! use tread::io::record::{self, Recorder, RejectedStep, StepInfo};
//! use tread::solver::stepping::final_residual;
//!
//! fn my_driver(sys: &mut SolidSystem, newton: &mut Newton, t_end: f64, dt: f64,
//!              rec: &mut dyn Recorder) -> Result<(), SolveError> {
//!     // (the application calls rec.run_started(&meta) before and rec.run_finished(&end) after)
//!     let (mut index, mut t) = (0u64, 0.0);
//!     while t < t_end {
//!         if record::interrupted() {
//!             // At a step boundary: the logs hold whole steps only.
//!             return Err(SolveError::Interrupted { at: t });
//!         }
//!         match newton.solve(sys) {
//!             Ok(rep) => {
//!                 record::emit_newton_table(rec, index, t + dt, &rep.table, sys.field_names());
//!                 t += dt;
//!                 let info = StepInfo { index, time: t, dt, newton_iterations: rep.iterations,
//!                                       residual: final_residual(&rep.table),
//!                                       is_final: t >= t_end };
//!                 // Build the view only when some sink records this step (decimation), with
//!                 // the recovered fields only when some sink reads them.
//!                 let frame = rec
//!                     .wants_view(&info)
//!                     .then(|| SolidFrame::capture(sys, rec.wants_fields(&info)));
//!                 let extra = [("revolutions", t / period)];       // optional model scalars
//!                 rec.step(&info, frame.as_ref().map(|f| f.view(sys, &extra)).as_ref());
//!                 index += 1;
//!             }
//!             Err(e) => {
//!                 let reason = e.to_string();
//!                 rec.step_rejected(&RejectedStep { index, time: t + dt, dt, reason: &reason,
//!                                                   newton_iterations: e.newton_iterations(),
//!                                                   residual: None });
//!                 // … cut dt and retry
//!             }
//!         }
//!     }
//!     Ok(())
//! }
//! ```
//!
//! [`crate::driver::frame::SolidFrame`] builds a [`StepView`] of a `SolidSystem` (nodal
//! stresses, contact samples, hub loads, energies); load stepping does all of this through
//! the solvers' observer ([`crate::solver::StepObserver`]), which every recorder implements
//! for a `SolidSystem` ([`crate::model::SolidSystem::record_step`]). A progress bar for a
//! time-stepping driver is [`progress::Progress`] (in the fan-out built by
//! `app::build_recorders` unless `--quiet`): give
//! `RunMeta { time_name: "time", time_end, revolution_period, .. }` and it shows simulated time,
//! revolutions, steps and steps per second. The application builds the sinks
//! from the scene with `app::build_recorders(scene, out_dir, quiet)`.
//!
//! # Time
//!
//! Every accepted step has an index (`step` timeline: 0, 1, 2, …) and a time (`sim_time`
//! timeline): simulated seconds in a transient, the load factor λ ∈ (0, 1] in load stepping
//! (static and spinning modes), where each converged load step is a step.
//!
//! # Decimation
//!
//! [`Recorders`] fans events out to boxed sinks, each with its own `every`: a sink gets the
//! view of step `i` when `i % every == 0` or the step is final; it still gets the cheap
//! [`StepInfo`] of every step (with `view = None`).
//!
//! # Three-dimensional results
//!
//! A 3D driver on a [`crate::mesh::hex_mesh::HexMesh`] writes its states with
//! [`hex_out::HexOutputs`] (`hex.pvd` + `hex/*.vtu` by [`vtu3d`], `hex.mcap`, `hex.rrd`): the
//! displacement (3 per node) and named point and cell fields ([`vtu3d::Field3D`]: scalars,
//! vectors, symmetric or full tensors).
//!
//! # Interrupts
//!
//! [`install_interrupt_handler`] makes Ctrl-C (SIGINT) set a flag; drivers poll [`interrupted`]
//! at step boundaries and stop with `SolveError::Interrupted`; the application then finishes
//! every sink and writes `summary.json` with `"error": "interrupted"`. A second Ctrl-C exits at
//! once (status 130). A killed process leaves CSV files complete up to the last recorded row,
//! VTU files complete up to the last listed step (the `.pvd` is rewritten atomically) and the
//! MCAP readable up to its last completed chunk (one chunk is closed per recorded step).

pub mod csv;
pub mod footprint;
pub mod hex_out;
pub mod interrupt;
pub mod mcap;
pub mod png;
pub mod progress;
pub mod quad;
#[cfg(feature = "rerun")]
pub mod quad_rrd;
#[cfg(feature = "rerun")]
pub mod rrd;
#[cfg(feature = "rerun")]
pub mod rrd_draw;
#[cfg(feature = "rerun")]
pub mod rrd_layout;
pub mod shape;
pub mod sta;
pub mod vtu;
pub mod vtu3d;

pub use interrupt::{install_interrupt_handler, interrupted, request_interrupt};

use crate::contact::ContactSample;
use crate::mesh::Mesh;
/// The step events are the solvers' own ([`crate::solver::observe`]); the recorder receives them.
pub use crate::solver::observe::{RejectedStep, StepInfo};
use crate::solver::IterationRecord;
use std::path::PathBuf;

/// What a run is (sent once, before the solve).
#[derive(Clone, Copy, Debug)]
pub struct RunMeta<'a> {
    pub scene_name: &'a str,
    /// Analysis mode (`spinning`, `static`, `stick_slip`, …).
    pub mode: &'a str,
    /// The resolved scene as TOML (every default filled in).
    pub scene_toml: &'a str,
    /// `tread` version and cargo features.
    pub version: &'a str,
    pub features: &'a str,
    /// The reference mesh (None for models without one, e.g. stick-slip).
    pub mesh: Option<&'a Mesh>,
    /// Meaning of [`StepInfo::time`]: `"load_factor"` or `"time"` (seconds).
    pub time_name: &'a str,
    /// Time at which the run ends (1 for load stepping); for progress.
    pub time_end: f64,
    /// Period of one revolution (2π/ω) when the body spins; for progress.
    pub revolution_period: Option<f64>,
}

/// Resultant the hub exerts on the body: force (x1, x2) and torque about the hub centre
/// (counter-clockwise positive), per unit thickness.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HubLoads {
    pub force: [f64; 2],
    pub torque: f64,
}

/// Energies of the body (per unit thickness).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Energy {
    /// ∫ (W(F) − W(I)) dV.
    pub strain: f64,
    /// ½ ∫ ρ |v|² dV (steady spin: v = ω ∂θχ).
    pub kinetic: f64,
}

impl Energy {
    pub fn total(&self) -> f64 {
        self.strain + self.kinetic
    }
}

/// Read-only view of the state at an accepted step.
#[derive(Clone, Copy, Debug)]
pub struct StepView<'a> {
    pub mesh: Option<&'a Mesh>,
    /// Full state vector; the displacement of node `n` is `(x[2n], x[2n + 1])`.
    pub x: &'a [f64],
    /// Nodal Cauchy stress `[σ11, σ22, σ12]` (cell values averaged at shared nodes); empty
    /// without a mesh.
    pub stress: &'a [[f64; 3]],
    /// Nodal out-of-plane stress σ33 (plane strain: from the constitutive law with F33 = 1,
    /// minus the pressure); empty when not computed.
    pub sigma_33: &'a [f64],
    /// Recovered nodal Cauchy stress `[σ11, σ22, σ12, σ33]` (superconvergent patch recovery,
    /// [`crate::physics::recovery`]); empty when not computed.
    pub stress_recovered: &'a [[f64; 4]],
    /// Error indicator η_K per cell: the Zienkiewicz–Zhu recovery estimator of the energy
    /// error ([`crate::physics::estimate::recovery`]); empty when not computed.
    pub error_indicator: &'a [f64],
    /// Nodal pressure p of a mixed (incompressible) formulation, σ = σ_law − p I; empty when the
    /// model has no pressure field.
    pub pressure: &'a [f64],
    /// Contact traction samples along the outer boundary (empty without contact).
    pub contact: &'a [ContactSample],
    pub hub: Option<HubLoads>,
    pub energy: Option<Energy>,
    /// Road height H (road at x2 = −H).
    pub road_height: Option<f64>,
    /// Angular speed ω (rad/s).
    pub omega: f64,
    /// Further named scalars of the model (e.g. stick-slip `x`, `v`); names constant per run.
    pub scalars: &'a [(&'static str, f64)],
}

impl StepView<'_> {
    /// Displacement of node `n`.
    pub fn u(&self, n: usize) -> [f64; 2] {
        [self.x[2 * n], self.x[2 * n + 1]]
    }

    /// The scalar stress measure shown in colour: the in-plane maximum shear stress of the
    /// Cauchy stress, τ = √(((σ11 − σ22)/2)² + σ12²) (independent of the pressure).
    pub fn stress_measure(&self, n: usize) -> f64 {
        stress_measure(self.stress[n])
    }

    /// The named scalar series of this view, in a fixed order (the columns of `history.csv`,
    /// the MCAP/Rerun time series): contact resultants and patch only when there is contact.
    pub fn series(&self, info: &StepInfo) -> Vec<(&'static str, f64)> {
        let mut s = Vec::with_capacity(16);
        s.push(("newton_iterations", info.newton_iterations as f64));
        if let Some(h) = self.hub {
            s.push(("hub_force_x", h.force[0]));
            s.push(("hub_force_y", h.force[1]));
            s.push(("hub_torque", h.torque));
        }
        if let Some(e) = self.energy {
            s.push(("energy_strain", e.strain));
            s.push(("energy_kinetic", e.kinetic));
            s.push(("energy_total", e.total()));
        }
        if let Some(h) = self.road_height {
            s.push(("road_height", h));
        }
        if !self.contact.is_empty() {
            let t = crate::contact::ContactModel::totals(self.contact);
            s.push(("contact_force_x", t.force_x));
            s.push(("contact_force_y", t.force_y));
            s.push(("max_pressure", t.max_pressure));
            s.push(("patch_x_min", t.x_min));
            s.push(("patch_x_max", t.x_max));
        }
        if !self.stress.is_empty() {
            let m = (0..self.stress.len())
                .map(|n| self.stress_measure(n))
                .fold(0.0, f64::max);
            s.push(("max_shear_stress", m));
        }
        s.extend_from_slice(self.scalars);
        s
    }
}

/// τ = √(((σ11 − σ22)/2)² + σ12²) of `[σ11, σ22, σ12]`.
pub fn stress_measure(s: [f64; 3]) -> f64 {
    (0.25 * (s[0] - s[1]).powi(2) + s[2] * s[2]).sqrt()
}

/// One row of a Newton convergence table.
#[derive(Clone, Copy, Debug)]
pub struct NewtonIteration<'a> {
    /// Index of the step being solved.
    pub step: u64,
    /// Target time (or load factor) of that step.
    pub time: f64,
    pub iteration: usize,
    /// ‖R_f‖/‖R_f⁰‖ per field, named by `fields`.
    pub residual_rel: &'a [f64],
    pub fields: &'a [&'static str],
    pub increment_norm: f64,
    pub alpha: f64,
}

/// Kind of a point on a solution branch.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PointKind {
    Regular,
    /// A limit (turning) point in the parameter.
    LimitPoint,
    /// A sign change of det K without a turning point.
    Bifurcation,
}

impl PointKind {
    pub fn as_str(self) -> &'static str {
        match self {
            PointKind::Regular => "regular",
            PointKind::LimitPoint => "limit_point",
            PointKind::Bifurcation => "bifurcation",
        }
    }
}

/// A converged point of a continuation branch (arc-length in ω, load, …).
#[derive(Clone, Copy, Debug)]
pub struct ContinuationPoint<'a> {
    pub index: u64,
    /// Name of the continuation parameter (e.g. `"omega"`).
    pub parameter_name: &'a str,
    pub parameter: f64,
    /// Arc length from the start of the branch.
    pub arc_length: f64,
    pub newton_iterations: usize,
    /// Sign of det K at the point (from the LU pivots): +1, −1 or 0 when unknown.
    pub det_sign: i8,
    pub kind: PointKind,
    /// Scalar measures of the solution (e.g. `u_r_outer`, `hub_torque`), names constant per run.
    pub measures: &'a [(&'static str, f64)],
}

/// A steady state was reached (transient extraction) or solved (steady mode).
#[derive(Clone, Copy, Debug)]
pub struct SteadyReached<'a> {
    /// Time (or step) at which it was detected; 0 for a direct steady solve.
    pub time: f64,
    /// Relative change over the last node passage (transient) or the final residual (steady).
    pub change: f64,
    /// Scalar results (hub forces, torque, rolling resistance, …).
    pub results: &'a [(&'static str, f64)],
}

/// End of the run.
#[derive(Clone, Copy, Debug)]
pub struct RunEnd<'a> {
    pub converged: bool,
    pub interrupted: bool,
    pub error: Option<&'a str>,
    /// Accepted steps.
    pub steps: u64,
    pub wall_time_s: f64,
    /// The run summary (summary.json), stored by sinks that keep metadata.
    pub summary: Option<&'a serde_json::Value>,
}

/// A sink failed to write: which file, and why.
#[derive(Debug, Clone, thiserror::Error)]
#[error("{sink}: cannot write {path}: {message}")]
pub struct RecordError {
    pub sink: &'static str,
    pub path: PathBuf,
    pub message: String,
}

impl RecordError {
    pub fn new(sink: &'static str, path: impl Into<PathBuf>, e: impl std::fmt::Display) -> Self {
        Self {
            sink,
            path: path.into(),
            message: e.to_string(),
        }
    }
}

/// The event interface. Every method has a no-op default; a sink overrides what it uses.
pub trait Recorder {
    fn run_started(&mut self, _meta: &RunMeta) {}
    /// Whether this sink wants the [`StepView`] of the step `info` (the driver builds it only
    /// if some sink does).
    fn wants_view(&self, _info: &StepInfo) -> bool {
        false
    }
    /// Whether the view of the step `info`, if this sink wants one, must carry the recovered
    /// fields ([`StepView::stress_recovered`], [`StepView::error_indicator`]): each costs a
    /// patch recovery over the mesh. A sink that reads only the scalars of the view says no;
    /// the default is [`Recorder::wants_view`].
    fn wants_fields(&self, info: &StepInfo) -> bool {
        self.wants_view(info)
    }
    /// An accepted step; `view` is `Some` when [`Recorder::wants_view`] said so.
    fn step(&mut self, _info: &StepInfo, _view: Option<&StepView>) {}
    fn step_rejected(&mut self, _step: &RejectedStep) {}
    fn newton_iteration(&mut self, _it: &NewtonIteration) {}
    fn continuation_point(&mut self, _p: &ContinuationPoint) {}
    /// A line of progress between steps (e.g. the steady mode's recovery strategies, which take
    /// steps of their own that are not the run's): shown where a user follows a run (`run.sta`).
    fn note(&mut self, _text: &str) {}
    fn steady_reached(&mut self, _s: &SteadyReached, _view: &StepView) {}
    /// Finish every file; returns the errors met while writing (empty when all went well).
    fn run_finished(&mut self, _end: &RunEnd) -> Vec<RecordError> {
        Vec::new()
    }
}

/// No sinks: every event is a no-op.
impl Recorder for () {}

/// Emit the rows of a Newton table as [`Recorder::newton_iteration`] events.
pub fn emit_newton_table<R: Recorder + ?Sized>(
    rec: &mut R,
    step: u64,
    time: f64,
    table: &[IterationRecord],
    fields: &'static [&'static str],
) {
    for r in table {
        let n = r.residual_rel.len().min(fields.len());
        rec.newton_iteration(&NewtonIteration {
            step,
            time,
            iteration: r.iteration,
            residual_rel: &r.residual_rel[..n],
            fields: &fields[..n],
            increment_norm: r.increment_norm,
            alpha: r.alpha,
        });
    }
}

struct Entry {
    sink: Box<dyn Recorder>,
    every: u64,
}

/// Fan-out over boxed sinks, each with its own decimation.
///
/// It also numbers the steps: every accepted step gets the next index 0, 1, 2, … whatever the
/// driver passed (a driver chaining load stepping, recovery and continuation cannot skip or
/// repeat an index), and the Newton iterations and rejections of a step carry the index it will
/// have.
#[derive(Default)]
pub struct Recorders {
    entries: Vec<Entry>,
    next_index: u64,
    last_time: Option<f64>,
}

impl Recorders {
    pub fn new() -> Self {
        Self::default()
    }

    /// Add a sink that records the view of every `every`-th step (and of the final step).
    pub fn push(&mut self, sink: Box<dyn Recorder>, every: usize) {
        self.entries.push(Entry {
            sink,
            every: every.max(1) as u64,
        });
    }

    pub fn len(&self) -> usize {
        self.entries.len()
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Accepted steps recorded so far.
    pub fn steps_recorded(&self) -> u64 {
        self.next_index
    }

    /// Time of the last recorded step.
    pub fn last_time(&self) -> Option<f64> {
        self.last_time
    }

    fn numbered(&self, info: &StepInfo) -> StepInfo {
        StepInfo {
            index: self.next_index,
            ..*info
        }
    }
}

impl Entry {
    fn admits(&self, info: &StepInfo) -> bool {
        info.is_final || info.index.is_multiple_of(self.every)
    }
}

impl Recorder for Recorders {
    fn run_started(&mut self, meta: &RunMeta) {
        for e in &mut self.entries {
            e.sink.run_started(meta);
        }
    }
    fn wants_view(&self, info: &StepInfo) -> bool {
        let info = &self.numbered(info);
        self.entries
            .iter()
            .any(|e| e.admits(info) && e.sink.wants_view(info))
    }
    fn wants_fields(&self, info: &StepInfo) -> bool {
        let info = &self.numbered(info);
        self.entries
            .iter()
            .any(|e| e.admits(info) && e.sink.wants_view(info) && e.sink.wants_fields(info))
    }
    fn step(&mut self, info: &StepInfo, view: Option<&StepView>) {
        let info = &self.numbered(info);
        for e in &mut self.entries {
            let v = if e.admits(info) { view } else { None };
            e.sink.step(info, v);
        }
        self.next_index += 1;
        self.last_time = Some(info.time);
    }
    fn step_rejected(&mut self, step: &RejectedStep) {
        let step = &RejectedStep {
            index: self.next_index,
            ..*step
        };
        for e in &mut self.entries {
            e.sink.step_rejected(step);
        }
    }
    fn newton_iteration(&mut self, it: &NewtonIteration) {
        let it = &NewtonIteration {
            step: self.next_index,
            ..*it
        };
        for e in &mut self.entries {
            e.sink.newton_iteration(it);
        }
    }
    fn continuation_point(&mut self, p: &ContinuationPoint) {
        for e in &mut self.entries {
            e.sink.continuation_point(p);
        }
    }
    fn note(&mut self, text: &str) {
        for e in &mut self.entries {
            e.sink.note(text);
        }
    }
    fn steady_reached(&mut self, s: &SteadyReached, view: &StepView) {
        for e in &mut self.entries {
            e.sink.steady_reached(s, view);
        }
    }
    fn run_finished(&mut self, end: &RunEnd) -> Vec<RecordError> {
        let mut errors = Vec::new();
        for e in &mut self.entries {
            errors.extend(e.sink.run_finished(end));
        }
        errors
    }
}

/// `Some(v)` when finite (outputs never contain NaN or infinities).
#[inline]
pub fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// Non-finite values as 0 (for binary formats without a missing-value marker).
#[inline]
pub fn or_zero(v: f64) -> f64 {
    if v.is_finite() {
        v
    } else {
        0.0
    }
}

/// Triangles (node triples, counter-clockwise) covering the cells of `mesh` for display: a Q2
/// cell is split into its four sub-quads through the mid-side and centre nodes, each quad into
/// two triangles; a Q1 cell into two triangles.
pub fn display_triangles(mesh: &Mesh) -> Vec<[u32; 3]> {
    let mut tris = Vec::with_capacity(mesh.n_cells() * 8);
    for c in 0..mesh.n_cells() {
        let nodes = mesh.cell_nodes(c);
        let p = mesh.degree[c] as usize;
        let at = |i: usize, j: usize| nodes[i + (p + 1) * j];
        for j in 0..p {
            for i in 0..p {
                let (a, b, cc, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                tris.push([a, b, cc]);
                tris.push([a, cc, d]);
            }
        }
    }
    tris
}

/// Closed node loops of the mesh boundary (inner and outer rings of a ring-numbered annulus).
pub fn boundary_loops(mesh: &Mesh) -> Vec<Vec<u32>> {
    let Some(rl) = mesh.rings else {
        return Vec::new();
    };
    [0, rl.rings - 1]
        .iter()
        .map(|&r| {
            let mut l: Vec<u32> = (0..rl.per_ring)
                .map(|k| (r * rl.per_ring + k) as u32)
                .collect();
            l.push((r * rl.per_ring) as u32);
            l
        })
        .collect()
}

/// A perceptual colour map (viridis, 5 stops, linear in between) of t ∈ [0, 1], as RGB bytes.
pub fn colormap(t: f64) -> [u8; 3] {
    const STOPS: [[f64; 3]; 5] = [
        [68.0, 1.0, 84.0],
        [59.0, 82.0, 139.0],
        [33.0, 145.0, 140.0],
        [94.0, 201.0, 98.0],
        [253.0, 231.0, 37.0],
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let s = t * 4.0;
    let i = (s.floor() as usize).min(3);
    let f = s - i as f64;
    let mut c = [0u8; 3];
    for k in 0..3 {
        c[k] = (STOPS[i][k] + f * (STOPS[i + 1][k] - STOPS[i][k])).round() as u8;
    }
    c
}

/// The cargo features of this build, for metadata.
pub fn build_features() -> &'static str {
    if cfg!(feature = "rerun") {
        "rerun"
    } else {
        ""
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Default)]
    struct Count {
        views: Vec<u64>,
        infos: usize,
    }
    impl Recorder for Count {
        fn wants_view(&self, _: &StepInfo) -> bool {
            true
        }
        fn step(&mut self, info: &StepInfo, view: Option<&StepView>) {
            self.infos += 1;
            if view.is_some() {
                self.views.push(info.index);
            }
        }
    }

    struct Shared(std::rc::Rc<std::cell::RefCell<Count>>);
    impl Recorder for Shared {
        fn wants_view(&self, i: &StepInfo) -> bool {
            self.0.borrow().wants_view(i)
        }
        fn step(&mut self, info: &StepInfo, view: Option<&StepView>) {
            self.0.borrow_mut().step(info, view)
        }
    }

    /// Step `i` of a run of eight unit steps (the last one final).
    fn step_of_eight(i: u64) -> StepInfo {
        StepInfo {
            index: i,
            time: i as f64,
            dt: 1.0,
            newton_iterations: 1,
            residual: 0.0,
            is_final: i == 7,
        }
    }

    #[test]
    fn decimation_admits_every_nth_and_final_step() {
        let a = std::rc::Rc::new(std::cell::RefCell::new(Count::default()));
        let b = std::rc::Rc::new(std::cell::RefCell::new(Count::default()));
        let mut r = Recorders::new();
        r.push(Box::new(Shared(a.clone())), 1);
        r.push(Box::new(Shared(b.clone())), 3);
        let x = [0.0; 2];
        for i in 0..8u64 {
            let info = step_of_eight(i);
            let view = StepView {
                mesh: None,
                x: &x,
                stress: &[],
                sigma_33: &[],
                stress_recovered: &[],
                error_indicator: &[],
                pressure: &[],
                contact: &[],
                hub: None,
                energy: None,
                road_height: None,
                omega: 0.0,
                scalars: &[],
            };
            let v = r.wants_view(&info).then_some(view);
            r.step(&info, v.as_ref());
        }
        assert_eq!(a.borrow().views, (0..8).collect::<Vec<_>>());
        assert_eq!(b.borrow().views, [0, 3, 6, 7]);
        assert_eq!((a.borrow().infos, b.borrow().infos), (8, 8));
        assert!(!().wants_view(&StepInfo {
            index: 0,
            time: 0.0,
            dt: 0.0,
            newton_iterations: 0,
            residual: 0.0,
            is_final: true
        }));
    }

    /// The recovered fields are asked for only on the steps where a sink that reads them is
    /// admitted: a CSV sink on every step and a VTU sink on every third one ask for them on
    /// steps 0, 3, 6 and the final one; the CSV sink alone, never.
    #[test]
    fn recovered_fields_only_where_a_field_sink_is_admitted() {
        let dir = std::env::temp_dir().join(format!("tread-wants-fields-{}", std::process::id()));
        let info = step_of_eight;
        let mut both = Recorders::new();
        both.push(Box::new(csv::CsvSink::new(&dir)), 1);
        both.push(Box::new(vtu::VtuSink::new(&dir)), 3);
        let mut csv_only = Recorders::new();
        csv_only.push(Box::new(csv::CsvSink::new(&dir)), 1);
        let mut asked = Vec::new();
        for i in 0..8u64 {
            assert!(both.wants_view(&info(i)) && csv_only.wants_view(&info(i)));
            assert!(!csv_only.wants_fields(&info(i)), "step {i}");
            if both.wants_fields(&info(i)) {
                asked.push(i);
            }
            both.step(&info(i), None);
            csv_only.step(&info(i), None);
        }
        assert_eq!(asked, [0, 3, 6, 7]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn colormap_ends_and_stress_measure() {
        assert_eq!(colormap(0.0), [68, 1, 84]);
        assert_eq!(colormap(1.0), [253, 231, 37]);
        assert_eq!(colormap(f64::NAN), [68, 1, 84]);
        assert!((stress_measure([3.0, -1.0, 0.0]) - 2.0).abs() < 1e-15);
        assert!((stress_measure([0.0, 0.0, -1.5]) - 1.5).abs() < 1e-15);
    }
}
