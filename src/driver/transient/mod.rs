//! Dynamic Lagrangian (transient) rolling: M ü + f_int(u) + f_c(u, u̇) = 0 on the material mesh,
//! integrated in time until rolling is steady.
//!
//! * The hub rim follows x = Q(φ(t)) X exactly, φ̇ = ω(t) with ω ramped from rest by a C²
//!   smoothstep; the road height (or the hub load) and the road speed ramp in the same way.
//! * Mass: consistent, or HRZ-lumped (diagonal scaled to the cell mass; positive for Q2).
//! * Integrators ([`Scheme`]): generalized-α (Chung–Hulbert; ρ∞ = 1 is the trapezoidal /
//!   average-acceleration Newmark rule) in its force-averaged form,
//!   M a_{n+1−αm} + (1 − αf) f(u_{n+1}, v_{n+1}) + αf f(u_n, v_n) = 0, which is objective (the
//!   displacement-averaged form evaluates f at (1 − αf) u_{n+1} + αf u_n, which for a spinning
//!   body is a shrunk, strained configuration: spurious strain O((ωΔt)²)); each step is solved
//!   by the same Newton as every other problem; explicit central difference with the lumped mass and a stable-step estimate
//!   (power iteration on M_L⁻¹K). Adaptive Δt for generalized-α from the local error estimate
//!   e = (β − 1/6) Δt² (a_{n+1} − a_n) (Zienkiewicz–Xie), normalised by the step increment;
//!   steps whose estimate exceeds 4 × tol, or whose Newton fails, are rejected and retried
//!   with a smaller Δt.
//! * Damping is objective: no mass-proportional damping; dissipation comes from the contact
//!   (normal damping b_n, friction) and from the integrator (ρ∞ < 1).
//! * Steady-state extraction ([`SteadyMonitor`]): with a uniform circumferential mesh, whenever
//!   φ(t) is a multiple k of the cell angle Δθ = 2π / n_θ (p node steps: the mesh is invariant
//!   under a rotation by one cell, not by one node, since vertex and mid-side nodes alternate),
//!   material node (ring m, position l) sits on referential node (m, l + p k): the referential
//!   field is a
//!   re-indexing (displacements interpolated to that instant by cubic Hermite interpolation
//!   from the two bracketing steps). Rolling is steady when that field, the hub forces and the
//!   torque change by less than `steady_tol` (relative) over two consecutive passages (and
//!   the hub speed, which varies under torque control).
//!   On a mesh without rings (read from a file) the referential field is interpolated instead:
//!   at the passage angle φ = kΔθ (Δθ = 2π / number of contact facets, at least 8 per turn),
//!   referential node Y_j sees the material point X* = Q(−φ) Y_j, located in the reference
//!   mesh ([`crate::mesh::locate`]) and evaluated with its cell's shape functions:
//!   χ(Y_j) = X* + u(X*). The isoparametric cells reproduce the rigid rotation in u exactly, so
//!   the interpolation error is that of the elastic part only. On such a mesh the discretisation
//!   itself rotates through the contact patch, so the passage-to-passage changes do not go to
//!   zero but to the level of the discretisation error.
//! * Torque control ([`Transient::enable_torque_control`]): the hub angle φ is a global unknown
//!   with I φ̈ = T(t) − M_r solved in the same Newton; node passages are then taken at
//!   multiples of the cell angle of the computed φ(t) (cubic Hermite in (φ, φ̇) within a step).

use crate::assembly::{CONSTRAINED, MAX_LOCAL};
use crate::contact::{ContactSample, SlipKinematics};
use crate::math::Vec2;
use crate::model::system::SolidSystem;
use crate::solver::{Newton, NewtonOptions, NonlinearSystem, SolveError};
pub use body::Body;
use energy::ViscousEnergy;
use std::f64::consts::PI;

/// C² smoothstep s(τ) = 10τ³ − 15τ⁴ + 6τ⁵ on [0, 1], its derivative and its integral.
fn smoothstep(tau: f64) -> (f64, f64, f64) {
    if tau <= 0.0 {
        return (0.0, 0.0, 0.0);
    }
    if tau >= 1.0 {
        return (1.0, 0.0, 0.5 + (tau - 1.0));
    }
    let t2 = tau * tau;
    let t3 = t2 * tau;
    let s = t3 * (10.0 - 15.0 * tau + 6.0 * t2);
    let ds = 30.0 * t2 * (1.0 - tau) * (1.0 - tau);
    let is = t2 * t2 * (2.5 - 3.0 * tau + t2);
    (s, ds, is)
}

/// A quantity ramped from 0 to `target` over `time` with the smoothstep (a step if time = 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ramp {
    pub target: f64,
    pub time: f64,
}

impl Ramp {
    pub fn value(&self, t: f64) -> f64 {
        if self.time <= 0.0 {
            return self.target;
        }
        self.target * smoothstep(t / self.time).0
    }
    pub fn rate(&self, t: f64) -> f64 {
        if self.time <= 0.0 {
            return 0.0;
        }
        self.target * smoothstep(t / self.time).1 / self.time
    }
    /// ∫₀ᵗ value.
    pub fn integral(&self, t: f64) -> f64 {
        if self.time <= 0.0 {
            return self.target * t.max(0.0);
        }
        self.target * self.time * smoothstep(t / self.time).2
    }
}

/// Prescribed hub and road motion.
#[derive(Clone, Debug)]
pub struct Kinematics {
    pub omega: Ramp,
    /// Road penetration DISP(t) under displacement control (H = h_touch − DISP).
    pub disp: Option<Ramp>,
    pub h_touch: f64,
    /// Downward hub load under load control.
    pub load: Option<Ramp>,
    pub v0: Ramp,
}

impl Kinematics {
    pub fn phi(&self, t: f64) -> f64 {
        self.omega.integral(t)
    }
    /// Time when every ramp has finished.
    pub fn ramps_done(&self) -> f64 {
        let mut t = self.omega.time.max(self.v0.time);
        if let Some(d) = self.disp {
            t = t.max(d.time);
        }
        if let Some(l) = self.load {
            t = t.max(l.time);
        }
        t
    }
}

/// Generalized-α parameters (Chung–Hulbert) from the spectral radius at infinity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GenAlpha {
    pub rho_inf: f64,
    pub am: f64,
    pub af: f64,
    pub gamma: f64,
    pub beta: f64,
}

impl GenAlpha {
    pub fn new(rho_inf: f64) -> Self {
        let r = rho_inf.clamp(0.0, 1.0);
        let am = (2.0 * r - 1.0) / (r + 1.0);
        let af = r / (r + 1.0);
        let gamma = 0.5 - am + af;
        let beta = 0.25 * (1.0 - am + af).powi(2);
        Self {
            rho_inf: r,
            am,
            af,
            gamma,
            beta,
        }
    }
}

/// The step of the one-step loop [`integrate`]: how an integrator of the registry
/// ([`registry`]) attempts a step, assembles its Newton system and commits. Each integrator
/// that uses the loop supplies one from [`integrator::IntegratorSpec::scheme`]; a new one-step
/// integrator is a type implementing this trait, in its own file, with no change to the loop.
pub trait StepMethod<B: Body = SolidSystem>: Send + Sync + std::fmt::Debug {
    /// The integrator's scene keyword.
    fn name(&self) -> &'static str;
    /// Attempt one step of size `dt` from the committed state of `tr`, leaving it pending (see
    /// [`Transient::attempt`]); returns the local error estimate (0 without one) and the
    /// Newton iterations.
    fn attempt(
        &self,
        tr: &mut Transient<B>,
        newton: &mut Newton,
        dt: f64,
    ) -> Result<(f64, usize), SolveError>;
    /// Assemble the step's Newton system at the iterate ([`NonlinearSystem::evaluate`]);
    /// false when there is none (an explicit step) or the iterate is inadmissible.
    fn evaluate(&self, tr: &mut Transient<B>, with_matrix: bool) -> bool;
    /// After a step is committed (e.g. the forces the next step averages with).
    fn committed(&self, _tr: &mut Transient<B>) {}
    /// Estimates its local error, so that the adaptive step control applies.
    fn estimates_error(&self) -> bool;
    /// Explicit: the first step is bounded by a stable-step estimate, and a failed step ends
    /// the run instead of being retried shorter.
    fn explicit(&self) -> bool {
        false
    }
}

/// Time integration scheme of a [`Transient`]: a shared handle on its [`StepMethod`].
pub struct Scheme<B: Body = SolidSystem>(std::sync::Arc<dyn StepMethod<B>>);

impl<B: Body> Clone for Scheme<B> {
    fn clone(&self) -> Self {
        Scheme(self.0.clone())
    }
}

impl<B: Body> std::fmt::Debug for Scheme<B> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_tuple("Scheme").field(&self.0).finish()
    }
}

impl<B: Body> Scheme<B> {
    /// The scheme of a step method.
    pub fn new(method: impl StepMethod<B> + 'static) -> Self {
        Scheme(std::sync::Arc::new(method))
    }

    /// Generalized-α with the parameters `ga` ([`generalized_alpha`]).
    pub fn generalized_alpha(ga: GenAlpha) -> Self {
        Self::new(generalized_alpha::GeneralizedAlphaStep(ga))
    }

    /// Explicit central difference ([`central_difference`]).
    pub fn central_difference() -> Self {
        Self::new(central_difference::CentralDifferenceStep)
    }

    pub fn name(&self) -> &'static str {
        self.0.name()
    }

    /// See [`StepMethod::estimates_error`].
    pub fn estimates_error(&self) -> bool {
        self.0.estimates_error()
    }

    /// See [`StepMethod::explicit`].
    pub fn explicit(&self) -> bool {
        self.0.explicit()
    }

    /// The step method.
    pub fn method(&self) -> &dyn StepMethod<B> {
        self.0.as_ref()
    }
}

/// The coefficients of one dynamic assembly: the static forces at the configuration `x` with
/// the velocities `v` (∂v/∂x = `kv`), scaled by `force_scale`, plus the inertia rows
/// `mass · acc` (∂acc/∂x = `ca`), the scalar cell mass matrices at `offsets[c]..`; `t` is the
/// time at which applied loads (the torque of torque control) are evaluated.
#[derive(Clone, Copy, Debug)]
pub struct DynamicTerms<'a> {
    pub x: &'a [f64],
    pub v: &'a [f64],
    pub kv: f64,
    pub force_scale: f64,
    pub mass: &'a [f64],
    pub offsets: &'a [usize],
    pub acc: &'a [f64],
    pub ca: f64,
    pub t: f64,
}

/// Step-size control and stopping options.
#[derive(Clone, Debug)]
pub struct TimeOptions {
    pub dt: f64,
    pub dt_min: f64,
    pub dt_max: f64,
    pub t_end: f64,
    pub adaptive: bool,
    pub error_tol: f64,
    pub steady_tol: f64,
    pub stop_at_steady: bool,
    pub max_steps: usize,
    pub lumped: bool,
    /// After the ramps, shorten steps so that they land exactly on node passages (equal steps
    /// within each passage). Off for fixed-step studies.
    pub land_on_passages: bool,
}

/// Hub reaction, contact resultants and energies at one instant.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct Snapshot {
    pub t: f64,
    pub phi: f64,
    pub hub_force_x: f64,
    pub hub_force_y: f64,
    pub hub_torque: f64,
    /// Hub angular speed.
    pub omega: f64,
    pub kinetic_energy: f64,
    pub strain_energy: f64,
    /// The hub's force and moment on the body (F1, F2, F3, M1, M2, M3), global frame: in
    /// plane strain (hub_force_x, hub_force_y, 0, 0, 0, hub_torque).
    #[serde(skip)]
    pub loads: [f64; 6],
}

/// Torque control of the hub (see [`Transient::enable_torque_control`]).
#[derive(Clone, Debug)]
pub struct HubAngle {
    /// Rotational inertia of the hub per unit thickness (mass·length²/thickness), > 0.
    pub inertia: f64,
    /// Applied hub torque about +x3 (counter-clockwise positive) per unit thickness.
    pub torque: Ramp,
    /// Full index of φ (its rate and acceleration live at the same index of v, a).
    pub iphi: usize,
    /// Equation number of φ.
    eq: usize,
    /// Assembler block coupling φ with the hub cells.
    block: usize,
    /// Value slot of the (φ, φ) tangent entry.
    diag_slot: usize,
    /// Each cell's index among the cells touching the hub (u32::MAX if none), in the order
    /// of the assembler block.
    hub_slot: Vec<u32>,
    /// Per hub cell: K t (column), tᵀ K (row), tᵀ r and the (φ, φ) entry; stride [`HUB_STRIDE`].
    store: Vec<f64>,
    /// Hold φ fixed (φ row: R = 0, K = 1): the rigid-spin start solves for u at φ = 0.
    frozen: bool,
}

const HUB_STRIDE: usize = 2 * MAX_LOCAL + 2;

/// The transient model: a [`SolidSystem`] (state x = u at t_{n+1} during a step) plus the
/// mass, the kinematics and the time-stepping state.
pub struct Transient<B: Body = SolidSystem> {
    pub sys: B,
    pub scheme: Scheme<B>,
    pub kin: Kinematics,
    pub lumped: bool,
    /// Per-cell scalar mass matrices (n × n, row-major), `mass_off[c]..`.
    mass: Vec<f64>,
    mass_off: Vec<usize>,
    hub: Vec<u32>,
    /// Length of the current (last attempted) step.
    pub dt: f64,
    /// The committed state (t_n, u_n, v_n, a_n).
    pub state: State,
    /// The attempted step's state (t_{n+1}, u_{n+1}, v_{n+1}, a_{n+1}): filled by the
    /// integrator (u is the Newton iterate `sys.x` until the step is accepted), committed by
    /// [`Self::accept`].
    pub next: State,
    xa: Vec<f64>,
    va: Vec<f64>,
    aa: Vec<f64>,
    /// Lumped mass per full dof (central difference).
    ml: Vec<f64>,
    /// Static forces f(u_n, v_n) of the committed state (equation numbering).
    fprev: Vec<f64>,
    /// Referential field extracted at the last node passage (2 per referential node).
    pub steady_field: Option<Vec<f64>>,
    /// Quadrature-point history re-indexed to the referential cells at the last node passage
    /// (ring meshes, stateful materials, a passage landed on by a step; see
    /// [`SteadyMonitor::history`]).
    pub steady_history: Option<crate::assembly::QpHistory>,
    /// Newton convergence table of the last implicit step (for the recorder).
    pub last_table: Vec<crate::solver::IterationRecord>,
    /// Torque control (hub angle as an unknown); `None`: speed control (φ(t) prescribed).
    pub hub_angle: Option<HubAngle>,
    is_hub: Vec<bool>,
    /// Time at which the applied loads of the current assembly are evaluated.
    t_eval: f64,
    /// Wall thickness Ro − Ri (length scale of the error estimate's floor).
    wall: f64,
    /// Last stable-step estimate of the central-difference scheme (NaN before any).
    pub dt_stable: f64,
    /// The attempted step awaiting [`Self::accept`]: (t_{n+1}, Δt).
    pending: Option<(f64, f64)>,
    /// Energy account of the viscous overstress over the committed steps (viscoelastic
    /// materials; `None` when elastic).
    pub viscous: Option<ViscousEnergy>,
}

impl<B: Body> Transient<B> {
    /// `sys` must have been built with the hub fixed (its hub values are overwritten by the
    /// prescribed rotation). Initial state: at rest (u = v = a = 0) unless the caller changes
    /// `state` and `sys.x` before the first step.
    pub fn new(sys: B, scheme: Scheme<B>, kin: Kinematics, lumped: bool) -> Self {
        let n = sys.dof_map().n_full();
        let dim = B::DIM;
        let mut mass = Vec::new();
        let mut mass_off = vec![0];
        let mut m = Vec::new();
        let mut ml = vec![0.0; n];
        for c in 0..sys.n_cells() {
            sys.cell_mass(c, &mut m);
            let nn = sys.cell_nodes(c).len();
            let lump = crate::physics::SolidModel::hrz_lump(&m, nn);
            if lumped {
                for a in 0..nn {
                    for b in 0..nn {
                        m[a * nn + b] = if a == b { lump[a] } else { 0.0 };
                    }
                }
            }
            for (a, &node) in sys.cell_nodes(c).iter().enumerate() {
                for i in 0..dim {
                    ml[dim * node as usize + i] += lump[a];
                }
            }
            mass.extend_from_slice(&m);
            mass_off.push(mass.len());
        }
        let hub = sys.hub_nodes();
        let mut is_hub = vec![false; sys.n_nodes()];
        for &h in &hub {
            is_hub[h as usize] = true;
        }
        let z = vec![0.0; n];
        let un = sys.x().to_vec();
        let radii = (0..sys.n_nodes()).map(|n| {
            let x = sys.reference_node(n);
            x[0].hypot(x[1])
        });
        let wall = radii.clone().fold(0.0, f64::max) - radii.fold(f64::INFINITY, f64::min);
        Self {
            sys,
            scheme,
            kin,
            lumped,
            mass,
            mass_off,
            hub,
            dt: 0.0,
            next: State::at_rest(0.0, un.clone()),
            state: State::at_rest(0.0, un),
            xa: z.clone(),
            va: z.clone(),
            aa: z,
            ml,
            fprev: Vec::new(),
            steady_field: None,
            steady_history: None,
            last_table: Vec::new(),
            hub_angle: None,
            is_hub,
            t_eval: 0.0,
            wall,
            dt_stable: f64::NAN,
            pending: None,
            viscous: None,
        }
    }
}

impl Transient {
    /// Torque control: the hub angle φ becomes an unknown with the equation of motion
    /// I φ̈ = T(t) − M_r, M_r = Σ_hub nodes (x_b × R_b) the moment that the hub exerts on the body
    /// (R_b: the residual rows of the hub nodes, internal + inertia forces). The hub nodes follow
    /// x_b = Q(φ) X_b; their velocities and accelerations come from the same Newmark update as
    /// every other node, and φ̇, φ̈ from the Newmark update of φ, so the whole step is one
    /// Newton solve with a consistent tangent (the φ row and column are the projections
    /// tᵀ K and K t of the hub rows and columns onto t_b = ∂x_b/∂φ = e3 × x_b, plus
    /// ∂t_b/∂φ · R_b = −x_b · R_b and I ∂φ̈/∂φ). The generalized-α force averaging applies
    /// to the torque too. `omega0` is the initial hub speed φ̇(0) (use
    /// [`Self::start_rigid_spin`] to start the body spinning with it). Generalized-α only;
    /// not with cell-owned (exact pressure) dofs (the coupling block would exceed MAX_LOCAL).
    pub fn enable_torque_control(&mut self, inertia: f64, torque: Ramp, omega0: f64) {
        let (iphi, block) = self.sys.add_hub_angle();
        self.state.push(0.0);
        self.next.push(0.0);
        for v in [&mut self.xa, &mut self.va, &mut self.aa, &mut self.ml] {
            v.push(0.0);
        }
        self.state.v[iphi] = omega0;
        self.next.v[iphi] = omega0;
        let mesh = &self.sys.model.mesh;
        let mut hub_slot = vec![u32::MAX; mesh.n_cells()];
        let mut n_hub_cells = 0;
        for (c, slot) in hub_slot.iter_mut().enumerate() {
            if mesh.cell_nodes(c).iter().any(|&n| self.is_hub[n as usize]) {
                *slot = n_hub_cells;
                n_hub_cells += 1;
            }
        }
        let eq = self.sys.dofs.eq[iphi] as usize;
        let asm = &self.sys.asm;
        let diag_slot = (asm.col_ptr[eq]..asm.col_ptr[eq + 1])
            .find(|&p| asm.row_idx[p] == eq)
            .unwrap_or(usize::MAX);
        self.hub_angle = Some(HubAngle {
            inertia,
            torque,
            iphi,
            eq,
            block,
            diag_slot,
            store: vec![0.0; HUB_STRIDE * n_hub_cells as usize],
            hub_slot,
            frozen: false,
        });
    }

    /// Contact traction samples of the configuration `x` with the velocity field `v` (full
    /// vectors); empty without contact.
    pub fn contact_samples(&self, x: &[f64], v: &[f64]) -> Vec<ContactSample> {
        let Some(c) = &self.sys.contact else {
            return Vec::new();
        };
        let kin = SlipKinematics::Dynamic {
            v,
            kx: 1.0,
            kv: 0.0,
        };
        c.samples(&self.sys.model.mesh, &self.sys.dofs, x, &kin)
    }
}

impl<B: Body> Transient<B> {
    /// Hub angle of the committed state.
    pub fn phi_now(&self) -> f64 {
        match &self.hub_angle {
            Some(h) => self.state.u[h.iphi],
            None => self.kin.phi(self.state.t),
        }
    }

    /// Hub angular speed of the committed state.
    pub fn omega_now(&self) -> f64 {
        match &self.hub_angle {
            Some(h) => self.state.v[h.iphi],
            None => self.kin.omega.value(self.state.t),
        }
    }

    /// Full index of the road height under load control.
    fn road_height_dof(&self) -> Option<usize> {
        self.sys.road_height_dof()
    }

    /// Hub angular acceleration of the committed state.
    pub fn hub_accel(&self) -> f64 {
        match &self.hub_angle {
            Some(h) => self.state.a[h.iphi],
            None => self.kin.omega.rate(self.state.t),
        }
    }

    /// Time when every ramp (and the torque ramp) has finished.
    pub fn ramps_done(&self) -> f64 {
        let t = self.kin.ramps_done();
        self.hub_angle.as_ref().map_or(t, |h| t.max(h.torque.time))
    }

    /// Applied hub torque at time `t` (0 under speed control).
    pub fn applied_torque(&self, t: f64) -> f64 {
        self.hub_angle.as_ref().map_or(0.0, |h| h.torque.value(t))
    }

    /// Hub displacements x_b − X_b = (Q(φ) − I) X_b into `sys.x` for φ = `sys.x[iphi]`.
    fn place_hub(&mut self) {
        let Some(h) = &self.hub_angle else {
            return;
        };
        let phi = self.sys.x()[h.iphi];
        self.place_hub_at(phi);
    }

    /// Hub displacements (Q(φ) − I) X_b into `sys.x` (u3 = 0 in 3D).
    fn place_hub_at(&mut self, phi: f64) {
        let (s, c) = phi.sin_cos();
        let dim = B::DIM;
        for &n in &self.hub {
            let x = self.sys.reference_node(n as usize);
            let n = n as usize;
            let xs = self.sys.x_mut();
            xs[dim * n] = c * x[0] - s * x[1] - x[0];
            xs[dim * n + 1] = s * x[0] + c * x[1] - x[1];
        }
    }

    /// Set the prescribed hub displacements and road state at time `t` into `x`.
    fn prescribe(&mut self, t: f64) {
        if self.hub_angle.is_some() {
            self.place_hub();
        } else {
            self.place_hub_at(self.kin.phi(t));
        }
        let h = self.kin.disp.map(|d| self.kin.h_touch - d.value(t));
        let load = self.kin.load.map(|l| l.value(t));
        self.sys.set_road(h, load, self.kin.v0.value(t));
    }

    /// Kinetic energy ½ vᵀ M v of a full velocity vector.
    pub fn kinetic_energy(&self, v: &[f64]) -> f64 {
        let mut e = 0.0;
        let dim = B::DIM;
        for c in 0..self.sys.n_cells() {
            let nodes = self.sys.cell_nodes(c);
            let nn = nodes.len();
            let m = &self.mass[self.mass_off[c]..self.mass_off[c + 1]];
            for a in 0..nn {
                for b in 0..nn {
                    let (na, nb) = (nodes[a] as usize, nodes[b] as usize);
                    let vv: f64 = (0..dim).map(|i| v[dim * na + i] * v[dim * nb + i]).sum();
                    e += 0.5 * m[a * nn + b] * vv;
                }
            }
        }
        e
    }

    /// Hub reaction (force and moment of the hub on the body) at the end-of-step state
    /// (x, next.v, next.a): internal (elastic and viscous), contact-free cell residual plus inertia at
    /// the hub nodes.
    pub fn hub_reaction(&self) -> (Vec2, f64) {
        let l = self.hub_loads();
        (Vec2::new(l[0], l[1]), l[5])
    }

    /// The hub's force and moment on the body (F1, F2, F3, M1, M2, M3) at the end-of-step
    /// state, as [`Self::hub_reaction`].
    pub fn hub_loads(&self) -> [f64; 6] {
        // With the viscous (strain-rate) stress: it is part of what the hub transmits.
        let (f, m) = self.sys.hub_reaction_dynamic(&DynamicTerms {
            x: self.sys.x(),
            v: &self.next.v,
            kv: 0.0,
            force_scale: 1.0,
            mass: &self.mass,
            offsets: &self.mass_off,
            acc: &self.next.a,
            ca: 0.0,
            t: self.state.t,
        });
        [f[0], f[1], f[2], m[0], m[1], m[2]]
    }

    pub fn snapshot(&self) -> Snapshot {
        Snapshot {
            kinetic_energy: self.kinetic_energy(&self.state.v),
            strain_energy: self.sys.strain_energy_of(&self.state.u),
            ..self.snapshot_light()
        }
    }

    /// Exact velocity and acceleration of the hub nodes at time `t` into next.v, next.a:
    /// x = Q(φ) X, v = ω e3 × x, a = ω̇ e3 × x − ω² x.
    fn hub_rates(&mut self, t: f64) {
        let phi = self.kin.phi(t);
        let (w, wd) = (self.kin.omega.value(t), self.kin.omega.rate(t));
        let (s, c) = phi.sin_cos();
        let dim = B::DIM;
        for &n in &self.hub {
            let xr = self.sys.reference_node(n as usize);
            let x = Vec2::new(c * xr[0] - s * xr[1], s * xr[0] + c * xr[1]);
            let n = n as usize;
            self.next.v[dim * n] = -w * x[1];
            self.next.v[dim * n + 1] = w * x[0];
            self.next.a[dim * n] = -wd * x[1] - w * w * x[0];
            self.next.a[dim * n + 1] = wd * x[0] - w * w * x[1];
        }
    }

    /// Assemble R = M·aa + fs · f(xa, va) + αf · f_n (and its tangent): the static forces f
    /// (internal, contact) are evaluated at the configuration `xa` with velocities `va` and
    /// scaled by `fs`; their derivatives with respect to the unknown are (1, kv) for (x, v) and
    /// `cm` for the acceleration `aa`. `prev` adds `prev · f_n` (the forces of the last
    /// committed step): force-averaged generalized-α, objective because every force is
    /// evaluated at an actual configuration.
    fn assemble_dynamic(
        &mut self,
        with_matrix: bool,
        fs: f64,
        kv: f64,
        cm: f64,
        prev: f64,
    ) -> bool {
        let terms = DynamicTerms {
            x: &self.xa,
            v: &self.va,
            kv,
            force_scale: fs,
            mass: &self.mass,
            offsets: &self.mass_off,
            acc: &self.aa,
            ca: cm,
            t: self.t_eval,
        };
        let ok =
            self.sys
                .assemble_dynamic(&terms, self.hub_angle.as_mut(), &self.is_hub, with_matrix);
        let asm = self.sys.assembler_mut();
        if prev != 0.0 {
            for ((r, q), f) in asm
                .residual
                .iter_mut()
                .zip(asm.scale.iter_mut())
                .zip(&self.fprev)
            {
                *r += prev * f;
                *q += (prev * f).abs();
            }
        }
        ok && asm.residual.iter().all(|r| r.is_finite())
    }

    /// Static forces f(u_n, v_n) of the committed state into `fprev`.
    fn update_fprev(&mut self) -> bool {
        self.t_eval = self.state.t;
        self.xa.copy_from_slice(&self.state.u);
        self.va.copy_from_slice(&self.state.v);
        self.aa.iter_mut().for_each(|v| *v = 0.0);
        let saved_x = std::mem::take(self.sys.x_mut());
        *self.sys.x_mut() = self.state.u.clone();
        let ok = self.assemble_dynamic(false, 1.0, 0.0, 0.0, 0.0);
        *self.sys.x_mut() = saved_x;
        self.fprev.clear();
        self.fprev.extend_from_slice(&self.sys.assembler().residual);
        // Load control: the road-height equation P − ∫ t_n ds0 = 0 is algebraic (massless
        // road): it holds at t_{n+1}, not force-averaged (an inconsistent start would otherwise
        // be carried into every step and can demand a negative pressure).
        if let Some(ih) = self.sys.road_height_dof() {
            let e = self.sys.dof_map().eq[ih];
            if e < CONSTRAINED {
                self.fprev[e as usize] = 0.0;
            }
        }
        ok
    }

    /// Advance one step of size `dt` from the committed `state`: [`Self::attempt`]
    /// then [`Self::accept`]. Returns the local error estimate (generalized-α) and the Newton
    /// iterations.
    pub fn step(&mut self, newton: &mut Newton, dt: f64) -> Result<(f64, usize), SolveError> {
        let out = self.attempt(newton, dt)?;
        self.accept();
        Ok(out)
    }

    /// Attempt one step of size `dt` from the committed `state`: the new state is left in
    /// (`sys.x`, `next.v`, `next.a`) and nothing committed, so that the caller may still
    /// reject it (restore `sys` with [`NonlinearSystem::restore_state`]) or keep it with
    /// [`Self::accept`]. Returns the local error estimate (generalized-α) and the Newton
    /// iterations.
    pub fn attempt(&mut self, newton: &mut Newton, dt: f64) -> Result<(f64, usize), SolveError> {
        self.pending = None;
        self.dt = dt;
        let scheme = self.scheme.clone();
        scheme.method().attempt(self, newton, dt)
    }

    /// Commit the step of the last successful [`Self::attempt`]: the quadrature-point history,
    /// `state` ← `next` = (t_{n+1}, x, next.v, next.a) and, for generalized-α, the forces f(u_n, v_n)
    /// of the new committed state that the next step averages with. No effect without a
    /// pending step.
    pub fn accept(&mut self) {
        let Some((t1, dt)) = self.pending.take() else {
            return;
        };
        self.commit_state(t1, Some(dt));
        let scheme = self.scheme.clone();
        scheme.method().committed(self);
    }

    /// The one commit of the transient state: `next` ← (t1, sys.x, next.v, next.a) becomes the
    /// committed `state`, and the quadrature-point history advances over a step `history_dt`
    /// (`None`: the integrator evaluated no history increment, so none is committed).
    pub(crate) fn commit_state(&mut self, t1: f64, history_dt: Option<f64>) {
        if let Some(step) = history_dt.and_then(|dt| self.sys.commit_history(dt)) {
            self.viscous
                .get_or_insert(ViscousEnergy::start(0.0, self.state.t))
                .add(step.work, step.stored, t1);
        }
        self.next.t = t1;
        self.next.u.copy_from_slice(self.sys.x());
        self.state.clone_from(&self.next);
    }
}

impl<B: Body> NonlinearSystem for Transient<B> {
    fn n_eq(&self) -> usize {
        self.sys.n_eq()
    }
    fn fields(&self) -> &[u8] {
        self.sys.fields()
    }
    fn field_names(&self) -> &'static [&'static str] {
        self.sys.field_names()
    }
    fn reference_norms(&self) -> Vec<f64> {
        self.sys.reference_norms()
    }
    fn force_scale(&self) -> &[f64] {
        self.sys.force_scale()
    }
    fn state_magnitudes(&self, out: &mut Vec<f64>) {
        self.sys.state_magnitudes(out)
    }
    fn pattern(&self) -> (&[usize], &[usize]) {
        self.sys.pattern()
    }
    fn evaluate(&mut self, with_matrix: bool) -> bool {
        let scheme = self.scheme.clone();
        scheme.method().evaluate(self, with_matrix)
    }
    fn residual(&self) -> &[f64] {
        self.sys.residual()
    }
    fn matrix_values(&self) -> &[f64] {
        self.sys.matrix_values()
    }
    fn update(&mut self, alpha: f64, dx: &[f64]) {
        self.sys.update(alpha, dx);
        self.place_hub();
    }
    fn save_state(&self, buf: &mut Vec<f64>) {
        self.sys.save_state(buf);
    }
    fn restore_state(&mut self, buf: &[f64]) {
        self.sys.restore_state(buf);
    }
}

/// Steady-state monitor: the referential field at node passages.
pub struct SteadyMonitor<B: Body = SolidSystem> {
    pub dtheta: f64,
    /// Nodes and cells per ring used for re-indexing (0 and 0 when the field is interpolated).
    pub per_ring: usize,
    pub n_theta: usize,
    /// Point location for meshes without rings (the field is interpolated).
    locator: Option<B::Locator>,
    last_k: i64,
    prev: Option<(Vec<f64>, Snapshot)>,
    /// Relative changes at the last passage: (field, force, torque).
    pub last_change: (f64, f64, f64, f64),
    pub passages: usize,
    /// Referential displacement field at the last passage (DIM per referential node).
    pub field: Vec<f64>,
    /// The quadrature-point history at the last passage, re-indexed to the referential cells
    /// (material cell (ring j, position l) sits on referential cell (j, l + k) after k cell
    /// angles) and with its tensors rotated by φ = kΔθ from the material reference frame into
    /// the referential one (R A Rᵀ). Only on ring meshes, for a passage that a step landed on
    /// (the history is not interpolated between steps); `None` otherwise.
    pub history: Option<crate::assembly::QpHistory>,
    /// One row per passage: t, changes (field, force, torque), hub force x, y, torque, hub
    /// speed ω, change of ω.
    pub log: Vec<[f64; 9]>,
    /// Time average of the hub force x, y and torque between the last two passages (the hub
    /// loads of a steady state vary periodically within a passage as nodes enter and leave
    /// the patch — by several per cent of |F| on coarse meshes — so the average over a
    /// passage, not the value at the passage instant, is the steady load).
    pub passage_mean: Option<[f64; 3]>,
    /// The same for all six hub loads (F1, F2, F3, M1, M2, M3).
    pub passage_mean_loads: Option<[f64; 6]>,
    /// ∫ (hub loads) dt since `acc_t0`, the time of the last passage.
    acc: [f64; 6],
    acc_t0: Option<f64>,
    below_once: bool,
}

impl<B: Body> SteadyMonitor<B> {
    pub fn new(sys: &B) -> Option<Self> {
        let (dtheta, per_ring, n_theta, locator) = sys.passage_geometry();
        Some(Self {
            dtheta,
            per_ring,
            n_theta,
            locator,
            last_k: i64::MIN,
            prev: None,
            last_change: (f64::INFINITY, f64::INFINITY, f64::INFINITY, f64::INFINITY),
            passages: 0,
            field: Vec::new(),
            history: None,
            log: Vec::new(),
            passage_mean: None,
            passage_mean_loads: None,
            acc: [0.0; 6],
            acc_t0: None,
            below_once: false,
        })
    }

    /// After an accepted step from (t0, u0, v0) to (t1, u1, v1): if φ crossed a multiple of
    /// the node angle, extract the referential field at that instant and compare. Returns
    /// true when steady (changes below `tol`). `phi_at(t)` is the hub angle on [t0, t1]
    /// (monotone): the prescribed φ(t) under speed control, its cubic Hermite interpolant
    /// under torque control. A passage that lands on the step end to within a relative 1e-9
    /// counts at this step (not one step late).
    #[allow(clippy::too_many_arguments)]
    pub fn check(
        &mut self,
        tr: &Transient<B>,
        t0: f64,
        u0: &[f64],
        v0: &[f64],
        snap0: &Snapshot,
        snap1: &Snapshot,
        tol: f64,
        phi_at: &dyn Fn(f64) -> f64,
    ) -> bool {
        let q = phi_at(tr.state.t) / self.dtheta;
        let k1 = (q + 1e-9 * q.abs().max(1.0)).floor() as i64;
        // Hub loads linear in time within the step, for the passage average.
        let (l0, l1) = (snap0.loads, snap1.loads);
        let integral = |a: f64, b: f64| {
            let h = tr.state.t - t0;
            let at = |t: f64| {
                let s = if h > 0.0 { (t - t0) / h } else { 1.0 };
                std::array::from_fn::<f64, 6, _>(|i| l0[i] + s * (l1[i] - l0[i]))
            };
            let (fa, fb) = (at(a), at(b));
            std::array::from_fn::<f64, 6, _>(|i| 0.5 * (fa[i] + fb[i]) * (b - a))
        };
        if self.last_k == i64::MIN {
            self.last_k = k1;
            return false;
        }
        if k1 <= self.last_k {
            if self.acc_t0.is_some() {
                let d = integral(t0, tr.state.t);
                (0..6).for_each(|i| self.acc[i] += d[i]);
            }
            return false;
        }
        self.last_k = k1;
        let target = k1 as f64 * self.dtheta;
        // Bisection for φ(t*) = kΔθ in [t0, t1] (φ is monotone).
        let (mut lo, mut hi) = (t0, tr.state.t);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if phi_at(mid) < target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let ts = 0.5 * (lo + hi);
        if let Some(tp) = self.acc_t0 {
            let d = integral(t0, ts);
            (0..6).for_each(|i| self.acc[i] += d[i]);
            if ts > tp {
                let m = self.acc.map(|v| v / (ts - tp));
                self.passage_mean = Some([m[0], m[1], m[5]]);
                self.passage_mean_loads = Some(m);
            }
        }
        self.acc = integral(ts, tr.state.t);
        self.acc_t0 = Some(ts);
        let h = tr.state.t - t0;
        let s = if h > 0.0 { (ts - t0) / h } else { 1.0 };
        // Cubic Hermite basis on [0, 1].
        let h00 = 2.0 * s * s * s - 3.0 * s * s + 1.0;
        let h10 = s * s * s - 2.0 * s * s + s;
        let h01 = -2.0 * s * s * s + 3.0 * s * s;
        let h11 = s * s * s - s * s;
        let per = self.per_ring;
        let n_u = B::DIM * tr.sys.n_nodes();
        let u_ts: Vec<f64> = (0..n_u)
            .map(|i| h00 * u0[i] + h10 * h * v0[i] + h01 * tr.state.u[i] + h11 * h * tr.state.v[i])
            .collect();
        let kk = if per > 0 {
            (k1 * (per / self.n_theta) as i64).rem_euclid(per as i64) as usize
        } else {
            0
        };
        let field = tr
            .sys
            .referential_field(self.locator.as_ref(), kk, target, &u_ts);
        let snap = Snapshot {
            t: ts,
            phi: target,
            hub_force_x: snap0.hub_force_x + s * (snap1.hub_force_x - snap0.hub_force_x),
            hub_force_y: snap0.hub_force_y + s * (snap1.hub_force_y - snap0.hub_force_y),
            hub_torque: snap0.hub_torque + s * (snap1.hub_torque - snap0.hub_torque),
            omega: snap0.omega + s * (snap1.omega - snap0.omega),
            loads: std::array::from_fn(|i| snap0.loads[i] + s * (snap1.loads[i] - snap0.loads[i])),
            ..*snap1
        };
        self.passages += 1;
        let mut steady = false;
        if let Some((pf, ps)) = &self.prev {
            let num = field
                .iter()
                .zip(pf)
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                .sqrt();
            let den = field
                .iter()
                .map(|a| a * a)
                .sum::<f64>()
                .sqrt()
                .max(f64::MIN_POSITIVE);
            // Changes of the hub force and moment (in plane strain: of (F1, F2) and the torque).
            let norm3 = |v: &[f64]| v.iter().map(|a| a * a).sum::<f64>().sqrt();
            let diff = |a: &[f64], b: &[f64]| -> Vec<f64> {
                a.iter().zip(b).map(|(x, y)| x - y).collect()
            };
            let fscale = norm3(&snap.loads[..3]).max(f64::MIN_POSITIVE);
            let df = norm3(&diff(&snap.loads[..3], &ps.loads[..3])) / fscale;
            let tscale = fscale * tr.sys.outer_radius();
            let dm = norm3(&diff(&snap.loads[3..], &ps.loads[3..])) / tscale.max(f64::MIN_POSITIVE);
            // Hub speed (varies under torque control; 0 change under speed control).
            let dw = (snap.omega - ps.omega).abs() / snap.omega.abs().max(f64::MIN_POSITIVE);
            self.last_change = (num / den, df, dm, dw);
            // Steady: two consecutive passages below the tolerance.
            let below = num / den < tol && df < tol && dm < tol && dw < tol;
            steady = below && self.below_once;
            self.below_once = below;
        }
        self.log.push([
            ts,
            self.last_change.0,
            self.last_change.1,
            self.last_change.2,
            snap.hub_force_x,
            snap.hub_force_y,
            snap.hub_torque,
            snap.omega,
            self.last_change.3,
        ]);
        self.field = field.clone();
        self.history = if (1.0 - s).abs() < 1e-6 {
            tr.sys.passage_history(k1, target)
        } else {
            None
        };
        self.prev = Some((field, snap));
        steady
    }
}

/// The quadrature-point history `hist` of a ring mesh with `n_theta` cells per ring, seen in
/// the referential frame after the body turned by `k` cell angles (φ = `phi`): material cell
/// (j, l) moves to referential cell (j, l + k), and every stored symmetric tensor
/// `[a11, a22, a12]` (the layout of [`crate::material::Viscoelastic`]) is rotated by φ,
/// R A Rᵀ.
pub fn reindex_history(
    hist: &crate::assembly::QpHistory,
    n_theta: usize,
    k: i64,
    phi: f64,
) -> crate::assembly::QpHistory {
    let shift = k.rem_euclid(n_theta as i64) as usize;
    let mut out = hist.clone();
    let (sn, cs) = phi.sin_cos();
    let rotate = |a: &mut [f64]| {
        let (a11, a22, a12) = (a[0], a[1], a[2]);
        a[0] = cs * cs * a11 - 2.0 * cs * sn * a12 + sn * sn * a22;
        a[1] = sn * sn * a11 + 2.0 * cs * sn * a12 + cs * cs * a22;
        a[2] = cs * sn * (a11 - a22) + (cs * cs - sn * sn) * a12;
    };
    for c in 0..hist.offsets.len().saturating_sub(1) {
        let (j, l) = (c / n_theta, c % n_theta);
        let dst = out.cell_mut(j * n_theta + (l + shift) % n_theta);
        dst.copy_from_slice(hist.cell(c));
        if hist.n_state.is_multiple_of(3) {
            dst.chunks_exact_mut(3).for_each(rotate);
        }
    }
    out
}

/// Run statistics.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct TransientReport {
    pub steps: usize,
    pub rejected: usize,
    pub newton_iterations: usize,
    pub time_to_steady: Option<f64>,
    pub steady: bool,
    pub final_time: f64,
    pub revolutions: f64,
    pub dt_min_used: f64,
    pub dt_max_used: f64,
    pub passages: usize,
    /// Relative changes (referential field, hub force, torque, hub speed) over the last node
    /// passage.
    pub last_change: [f64; 4],
    /// Node-passage log (see [`SteadyMonitor::log`]).
    pub passage_log: Vec<[f64; 9]>,
    /// Hub force x, y and torque averaged over the last node passage
    /// ([`SteadyMonitor::passage_mean`]).
    pub passage_mean: Option<[f64; 3]>,
    /// All six hub loads averaged over the last node passage.
    #[serde(skip)]
    pub passage_mean_loads: Option<[f64; 6]>,
    pub history: Vec<Snapshot>,
    /// Rejected steps in order.
    pub rejections: Vec<Rejection>,
}

/// A rejected time step: its target time and size, why it was rejected, and the Newton
/// iterations and last residual of the attempt when known.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Rejection {
    pub time: f64,
    pub dt: f64,
    pub reason: String,
    pub newton_iterations: Option<usize>,
    pub residual: Option<f64>,
}

/// Integrate until steady (or t_end). `on_step` is called after each accepted step.
// The failed run's report rides with its error, once per run: boxing it would buy nothing.
#[allow(clippy::result_large_err)]
pub fn integrate<B: Body>(
    tr: &mut Transient<B>,
    opts: &TimeOptions,
    newton_opts: NewtonOptions,
    kind: crate::solver::LinearKind,
    mut on_step: impl FnMut(&Transient<B>, &TransientReport),
) -> Result<TransientReport, (SolveError, TransientReport)> {
    let mut rep = TransientReport {
        dt_min_used: f64::INFINITY,
        ..Default::default()
    };
    let mut newton = match Newton::new(&tr.sys, kind, newton_opts) {
        Ok(n) => n,
        Err(e) => return Err((e, rep)),
    };
    // Reference force: weight-like scale ρ |Ω| ω² Ro + hub load.
    let ro = tr.sys.outer_radius();
    let fref = tr.sys.mass_total() * (tr.kin.omega.target.powi(2) * ro).max(1.0)
        + tr.kin.load.map_or(0.0, |l| l.target.abs());
    tr.sys.set_reference_force(fref);
    let mut monitor = SteadyMonitor::new(&tr.sys);
    // Load control: the road height H is a massless unknown whose equation P − ∫ t_n ds0 = 0
    // has no stiffness while nothing touches (a singular tangent at first touch, where the
    // road starts). Start it a hair inside the lowest contact point (10⁻⁶ of the wall) so that
    // this point is in contact: the penalty then gives ∂R_H/∂H > 0, and the ramped load P(t) > 0 keeps it
    // in contact afterwards.
    if let Some(ih) = tr.sys.road_height_dof() {
        if let Some(lowest) = tr.sys.lowest_contact_point(&tr.state.u, &tr.state.v) {
            let h0 = -lowest - 1e-6 * tr.wall;
            tr.state.u[ih] = h0;
            tr.sys.x_mut()[ih] = h0;
        }
    }
    tr.prescribe(tr.state.t);
    if !tr.update_fprev() {
        return Err((SolveError::InadmissibleStart, rep));
    }
    let mut dt = if tr.scheme.explicit() {
        // Penetration at which the contact stiffness is taken (only matters for m_n ≠ 1).
        let delta_ref = tr.kin.disp.map_or(0.05 * tr.wall, |d| d.target);
        let s = tr.stable_step(delta_ref);
        if s.is_finite() {
            (0.9 * s).min(opts.dt)
        } else {
            opts.dt
        }
    } else {
        opts.dt
    };
    let mut snap0 = tr.snapshot();
    rep.history.push(snap0);
    let (mut u0, mut v0) = (tr.state.u.clone(), tr.state.v.clone());
    let mut saved = Vec::new();
    while tr.state.t < opts.t_end - 1e-12 * opts.t_end && rep.steps < opts.max_steps {
        // Ctrl-C: stop at this step boundary (the committed state is the last accepted step).
        if crate::io::record::interrupted() {
            return Err((SolveError::Interrupted { at: tr.state.t }, rep));
        }
        dt = dt
            .min(opts.t_end - tr.state.t)
            .max(opts.dt_min.min(opts.t_end - tr.state.t));
        // A step that cannot move the time (a `dt_min` below the round-off of t) would repeat
        // without end.
        if crate::solver::newton::below_round_off(tr.state.t, opts.t_end, dt) {
            rep.final_time = tr.state.t;
            return Err((
                SolveError::StepBelowRoundOff {
                    at: tr.state.t,
                    step: dt,
                },
                rep,
            ));
        }
        // Land exactly on the next node passage once the ramps are done, so that the
        // referential field and the hub forces are sampled from a computed state (the hub force
        // varies quickly within a passage as nodes enter the patch: interpolating it is noisy).
        let mut dt_step = dt;
        if let (Some(m), true) = (&monitor, opts.land_on_passages) {
            if tr.state.t >= tr.ramps_done() && tr.omega_now() > 0.0 {
                let q = tr.phi_now() / m.dtheta;
                let k = (q + 1e-9 * q.abs().max(1.0)).floor() + 1.0;
                let target = k * m.dtheta;
                // Predicted hub angle: exact under speed control; under torque control the
                // quadratic φ_n + φ̇_n τ + ½ φ̈_n τ² from the committed state (the monitor
                // interpolates the passage it actually lands near).
                let (t_n, phi_n, w_n, wd_n) =
                    (tr.state.t, tr.phi_now(), tr.omega_now(), tr.hub_accel());
                let torque = tr.hub_angle.is_some();
                let phi_pred = |t: f64| {
                    if torque {
                        let tau = t - t_n;
                        phi_n + tau * (w_n + 0.5 * tau * wd_n).max(0.0)
                    } else {
                        tr.kin.phi(t)
                    }
                };
                // Time of the next passage (φ is monotone) within a generous bracket.
                let mut hi = tr.state.t + dt;
                while phi_pred(hi) < target && hi < opts.t_end {
                    hi += dt;
                }
                let mut lo = tr.state.t;
                for _ in 0..80 {
                    let mid = 0.5 * (lo + hi);
                    if phi_pred(mid) < target {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                // Equal steps up to the passage: every passage is then computed with the
                // same step pattern, so a steady state is exactly periodic between passages.
                let remaining = hi - tr.state.t;
                if remaining > 1e-3 * dt {
                    let m = (remaining / dt - 1e-9).ceil().max(1.0);
                    dt_step = remaining / m;
                }
            }
        }
        let h = dt_step;
        let shortened = h < dt;
        let t0 = tr.state.t;
        u0.copy_from_slice(&tr.state.u);
        v0.copy_from_slice(&tr.state.v);
        tr.sys.save_state(&mut saved);
        if newton.opts.verbose {
            // A header above the Newton table of this step.
            eprintln!(
                "  step {}: t = {:.6e} -> {:.6e}, dt = {:.4e}",
                rep.steps,
                t0,
                t0 + h,
                h
            );
        }
        match tr.attempt(&mut newton, h) {
            Ok((err, its)) => {
                let reject = opts.adaptive
                    && tr.scheme.estimates_error()
                    && err > 4.0 * opts.error_tol
                    && h > opts.dt_min;
                if reject {
                    // Nothing was committed: only the iterate goes back.
                    tr.sys.restore_state(&saved);
                    rep.rejected += 1;
                    rep.rejections.push(Rejection {
                        time: t0 + h,
                        dt: h,
                        reason: format!("local error {err:.3e} > 4 × error_tol"),
                        newton_iterations: Some(its),
                        residual: Some(crate::solver::stepping::final_residual(&tr.last_table))
                            .filter(|r| r.is_finite()),
                    });
                    dt = (h * (0.9 * (opts.error_tol / err).cbrt()).clamp(0.2, 0.9))
                        .max(opts.dt_min);
                    continue;
                }
                tr.accept();
                rep.steps += 1;
                rep.newton_iterations += its;
                rep.dt_min_used = rep.dt_min_used.min(h);
                rep.dt_max_used = rep.dt_max_used.max(h);
                let snap1 = tr.snapshot_light();
                if let Some(m) = &mut monitor {
                    // Hub angle on [t0, t1]: prescribed, or the cubic Hermite interpolant of
                    // (φ, φ̇) at the two ends under torque control.
                    let hermite = tr.hub_angle.as_ref().map(|h| {
                        (
                            u0[h.iphi],
                            v0[h.iphi],
                            tr.state.u[h.iphi],
                            tr.state.v[h.iphi],
                        )
                    });
                    let (t1, kin) = (tr.state.t, &tr.kin);
                    let phi_at = |t: f64| match hermite {
                        Some((p0, w0, p1, w1)) => {
                            let hh = t1 - t0;
                            let s = if hh > 0.0 { (t - t0) / hh } else { 1.0 };
                            let (s2, s3) = (s * s, s * s * s);
                            (2.0 * s3 - 3.0 * s2 + 1.0) * p0
                                + (s3 - 2.0 * s2 + s) * hh * w0
                                + (-2.0 * s3 + 3.0 * s2) * p1
                                + (s3 - s2) * hh * w1
                        }
                        None => kin.phi(t),
                    };
                    if tr.state.t >= tr.ramps_done()
                        && m.check(tr, t0, &u0, &v0, &snap0, &snap1, opts.steady_tol, &phi_at)
                        && !rep.steady
                    {
                        rep.steady = true;
                        rep.time_to_steady = Some(tr.state.t);
                    }
                    rep.passages = m.passages;
                    rep.last_change = [
                        m.last_change.0,
                        m.last_change.1,
                        m.last_change.2,
                        m.last_change.3,
                    ];
                }
                snap0 = snap1;
                rep.final_time = tr.state.t;
                rep.revolutions = tr.phi_now() / (2.0 * PI);
                on_step(tr, &rep);
                if rep.steady && opts.stop_at_steady {
                    break;
                }
                if opts.adaptive && tr.scheme.estimates_error() && err > 0.0 {
                    let proposed = (h * (0.9 * (opts.error_tol / err).cbrt()).clamp(0.5, 1.5))
                        .clamp(opts.dt_min, opts.dt_max);
                    // A step shortened to land on a passage says nothing against the
                    // controller's step.
                    dt = if shortened {
                        proposed.max(dt.min(opts.dt_max))
                    } else {
                        proposed
                    };
                }
            }
            Err(e) => {
                tr.sys.restore_state(&saved);
                rep.rejected += 1;
                rep.rejections.push(Rejection {
                    time: t0 + h,
                    dt: h,
                    reason: e.to_string(),
                    newton_iterations: e.newton_iterations(),
                    residual: None,
                });
                dt = h;
                if dt <= opts.dt_min * (1.0 + 1e-12) || tr.scheme.explicit() {
                    rep.final_time = tr.state.t;
                    return Err((e, rep));
                }
                dt = (0.5 * dt).max(opts.dt_min);
            }
        }
    }
    if let Some(m) = &monitor {
        rep.passages = m.passages;
        if m.passages > 0 {
            tr.steady_field = Some(m.field.clone());
            tr.steady_history = m.history.clone();
        }
        rep.passage_log = m.log.clone();
        rep.passage_mean = m.passage_mean;
        rep.passage_mean_loads = m.passage_mean_loads;
    }
    rep.history.push(tr.snapshot());
    Ok(rep)
}

impl<B: Body> Transient<B> {
    /// Hub reaction only (no energies): cheap per-step snapshot.
    pub fn snapshot_light(&self) -> Snapshot {
        let loads = self.hub_loads();
        Snapshot {
            t: self.state.t,
            phi: self.phi_now(),
            hub_force_x: loads[0],
            hub_force_y: loads[1],
            hub_torque: loads[5],
            omega: self.omega_now(),
            loads,
            ..Default::default()
        }
    }
}

/// The discrete rigid-spin equilibrium of the Lagrangian model: u such that
/// f_int(u) = ω² M (X + u) (the body at rest in a frame rotating at ω, with the hub fixed).
/// Since f_int is objective and M is rotation invariant, x(t) = Q(ωt)(X + u) is then an exact
/// solution of the semi-discrete equations with the hub rotating at constant ω.
struct RigidSpin<'a> {
    tr: &'a mut Transient,
    omega2: f64,
}

impl NonlinearSystem for RigidSpin<'_> {
    fn n_eq(&self) -> usize {
        self.tr.sys.n_eq()
    }
    fn fields(&self) -> &[u8] {
        self.tr.sys.fields()
    }
    fn field_names(&self) -> &'static [&'static str] {
        self.tr.sys.field_names()
    }
    fn reference_norms(&self) -> Vec<f64> {
        self.tr.sys.reference_norms()
    }
    fn force_scale(&self) -> &[f64] {
        self.tr.sys.force_scale()
    }
    fn state_magnitudes(&self, out: &mut Vec<f64>) {
        self.tr.sys.state_magnitudes(out)
    }
    fn pattern(&self) -> (&[usize], &[usize]) {
        self.tr.sys.pattern()
    }
    fn evaluate(&mut self, with_matrix: bool) -> bool {
        let tr = &mut *self.tr;
        let n_u = tr.sys.dofs.n_u;
        for d in 0..tr.state.u.len() {
            tr.xa[d] = tr.sys.x[d];
            tr.va[d] = 0.0;
            tr.aa[d] = if d < n_u {
                -self.omega2 * (tr.sys.model.mesh.nodes[d / 2][d % 2] + tr.sys.x[d])
            } else {
                0.0
            };
        }
        // d(aa)/du = −ω² on displacement dofs: the mass term contributes −ω² M to the tangent.
        tr.assemble_dynamic(with_matrix, 1.0, 0.0, -self.omega2, 0.0)
    }
    fn residual(&self) -> &[f64] {
        self.tr.sys.residual()
    }
    fn matrix_values(&self) -> &[f64] {
        self.tr.sys.matrix_values()
    }
    fn update(&mut self, alpha: f64, dx: &[f64]) {
        self.tr.sys.update(alpha, dx);
    }
    fn save_state(&self, buf: &mut Vec<f64>) {
        self.tr.sys.save_state(buf);
    }
    fn restore_state(&mut self, buf: &[f64]) {
        self.tr.sys.restore_state(buf);
    }
}

impl Transient {
    /// Start from the discrete rigid-spin state at angular speed `omega` (hub angle 0, no
    /// contact): solves f_int(u) = ω² M (X + u) by Newton with load stepping in ω², then sets
    /// u_0 = u, v_0 = ω e3 × (X + u), a_0 = −ω² (X + u). The kinematics should then spin at
    /// constant `omega` from t = 0 (ramp time 0).
    ///
    /// With `trapezoidal_dt = Some(Δt)` the state is instead the exact discrete rigid rotation
    /// of the trapezoidal rule (generalized-α with ρ∞ = 1) at step Δt: centripetal factor
    /// c_a = (4/Δt²) tan²(ωΔt/2) instead of ω², and v = (2/Δt) tan(ωΔt/2) e3 × x. With a lumped
    /// mass (no coupling to the hub's accelerations) the integrator then reproduces the rigid
    /// rotation to round-off: a sharp test of objectivity.
    pub fn start_rigid_spin(
        &mut self,
        omega: f64,
        kind: crate::solver::LinearKind,
        trapezoidal_dt: Option<f64>,
    ) -> Result<(), SolveError> {
        let (ca, cv) = match trapezoidal_dt {
            Some(dt) => {
                let t = (0.5 * omega * dt).tan();
                (4.0 * t * t / (dt * dt), 2.0 * t / dt)
            }
            None => (omega * omega, omega),
        };
        let opts = NewtonOptions {
            tol: 1e-12,
            max_iterations: 30,
            ..Default::default()
        };
        let steps = 4;
        let mut newton = Newton::new(&self.sys, kind, opts)?;
        let area = crate::model::system::domain_area(&self.sys.model);
        self.sys
            .set_reference_force(self.sys.model.rho * area * omega * omega);
        if let Some(h) = &mut self.hub_angle {
            h.frozen = true;
        }
        let mut res = Ok(());
        // Steady spinning keeps every strain constant in time: a viscoelastic material is fully
        // relaxed (an infinitely long step), and its history starts relaxed at that state.
        self.sys.model.history_dt = f64::INFINITY;
        for s in 1..=steps {
            let omega2 = ca * s as f64 / steps as f64;
            let mut rs = RigidSpin { tr: self, omega2 };
            if let Err(e) = newton.solve(&mut rs) {
                res = Err(e);
                break;
            }
        }
        self.sys.model.history_dt = 0.0;
        if let Some(h) = &mut self.hub_angle {
            h.frozen = false;
        }
        res?;
        let (dofs, x) = (&self.sys.dofs, &self.sys.x);
        // Relaxed to equilibrium: the energy account of the overstress starts here.
        let relaxed = self.sys.model.commit_history(dofs, x, f64::INFINITY);
        if self.sys.model.viscoelastic.is_some() {
            self.viscous = Some(ViscousEnergy::start(relaxed.stored, self.state.t));
        }
        let n_u = self.sys.dofs.n_u;
        self.state.u.copy_from_slice(&self.sys.x);
        for d in (0..n_u).step_by(2) {
            let p = self.sys.model.mesh.nodes[d / 2] + Vec2::new(self.sys.x[d], self.sys.x[d + 1]);
            self.state.v[d] = -cv * p[1];
            self.state.v[d + 1] = cv * p[0];
            self.state.a[d] = -ca * p[0];
            self.state.a[d + 1] = -ca * p[1];
        }
        // The hub nodes carry the exact rates of the prescribed rotation, as during stepping.
        self.next.v.copy_from_slice(&self.state.v);
        self.next.a.copy_from_slice(&self.state.a);
        self.hub_rates(self.state.t);
        if let Some(h) = &self.hub_angle {
            // The hub spins with the body: φ = 0, φ̇ = ω (the discrete rate with Δt given).
            self.next.v[h.iphi] = cv;
            self.next.a[h.iphi] = 0.0;
        }
        self.state.v.copy_from_slice(&self.next.v);
        self.state.a.copy_from_slice(&self.next.a);
        Ok(())
    }

    /// Green–Lagrange strain E = ½(FᵀF − I) at the centre of every cell (for objectivity checks).
    pub fn cell_strains(&self, x: &[f64]) -> Vec<crate::math::Mat2> {
        (0..self.sys.model.mesh.n_cells())
            .filter_map(|c| self.sys.model.point_values(c, &self.sys.dofs, x, 0.0, 0.0))
            .map(|pv| {
                let f = crate::math::Mat2::identity() + pv.grad_u;
                0.5 * (f.transpose() * f - crate::math::Mat2::identity())
            })
            .collect()
    }
}

/// diffsol's BDF / SDIRK on the first-order form y = (u, v) (a child module: it drives the
/// private assembly state of [`Transient`]).
pub mod bdf;
pub mod body;
pub mod body3d;
pub mod central_difference;
pub mod energy;
pub mod generalized_alpha;
pub mod hht_alpha;
pub mod integrator;
pub mod ode_first_order;
pub mod registry;
pub mod sdirk;
pub mod state;
mod torque;

pub use central_difference::CentralDifference;
pub use generalized_alpha::GeneralizedAlpha;
pub use integrator::{IntegratorSpec, Setup};
pub use state::State;
