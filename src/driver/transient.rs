//! Dynamic Lagrangian (transient) rolling: M ü + f_int(u) + f_c(u, u̇) = 0 on the material mesh,
//! integrated in time until rolling is steady (DESIGN §4).
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
//!   torque change by less than `steady_tol` (relative) over two consecutive passages.

use super::system::SolidSystem;
use crate::assembly::{LocalSystem, FIXED};
use crate::contact::SlipKinematics;
use crate::math::Vec2;
use crate::solver::{Newton, NewtonOptions, NonlinearSystem, SolveError};
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

/// Time integration scheme.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scheme {
    GeneralizedAlpha(GenAlpha),
    CentralDifference,
}

impl Scheme {
    pub fn name(&self) -> &'static str {
        match self {
            Scheme::GeneralizedAlpha(_) => "generalized_alpha",
            Scheme::CentralDifference => "central_difference",
        }
    }
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
    pub kinetic_energy: f64,
    pub strain_energy: f64,
}

/// The transient model: a [`SolidSystem`] (state x = u at t_{n+1} during a step) plus the
/// mass, the kinematics and the time-stepping state.
pub struct Transient {
    pub sys: SolidSystem,
    pub scheme: Scheme,
    pub kin: Kinematics,
    pub lumped: bool,
    /// Per-cell scalar mass matrices (n × n, row-major), `mass_off[c]..`.
    mass: Vec<f64>,
    mass_off: Vec<usize>,
    hub: Vec<u32>,
    pub t: f64,
    pub dt: f64,
    pub un: Vec<f64>,
    pub vn: Vec<f64>,
    pub an: Vec<f64>,
    pub v1: Vec<f64>,
    pub a1: Vec<f64>,
    xa: Vec<f64>,
    va: Vec<f64>,
    aa: Vec<f64>,
    /// Lumped mass per full dof (central difference).
    ml: Vec<f64>,
    /// Static forces f(u_n, v_n) of the committed state (equation numbering).
    fprev: Vec<f64>,
    /// Referential field extracted at the last node passage (2 per referential node).
    pub steady_field: Option<Vec<f64>>,
}

impl Transient {
    /// `sys` must have been built with the hub fixed (its hub values are overwritten by the
    /// prescribed rotation). Initial state: at rest (u = v = a = 0) unless the caller changes
    /// `un`, `vn`, `an` and `sys.x` before the first step.
    pub fn new(sys: SolidSystem, scheme: Scheme, kin: Kinematics, lumped: bool) -> Self {
        let n = sys.dofs.n_full();
        let mut mass = Vec::new();
        let mut mass_off = vec![0];
        let mut m = Vec::new();
        let mut ml = vec![0.0; n];
        for c in 0..sys.model.mesh.n_cells() {
            sys.model.cell_mass(c, &mut m);
            let nn = sys.model.mesh.cell_nodes(c).len();
            let lump = crate::physics::SolidModel::hrz_lump(&m, nn);
            if lumped {
                for a in 0..nn {
                    for b in 0..nn {
                        m[a * nn + b] = if a == b { lump[a] } else { 0.0 };
                    }
                }
            }
            for (a, &node) in sys.model.mesh.cell_nodes(c).iter().enumerate() {
                ml[2 * node as usize] += lump[a];
                ml[2 * node as usize + 1] += lump[a];
            }
            mass.extend_from_slice(&m);
            mass_off.push(mass.len());
        }
        let hub = sys.model.mesh.node_set("hub").to_vec();
        let z = vec![0.0; n];
        let un = sys.x.clone();
        Self {
            sys,
            scheme,
            kin,
            lumped,
            mass,
            mass_off,
            hub,
            t: 0.0,
            dt: 0.0,
            un,
            vn: z.clone(),
            an: z.clone(),
            v1: z.clone(),
            a1: z.clone(),
            xa: z.clone(),
            va: z.clone(),
            aa: z,
            ml,
            fprev: Vec::new(),
            steady_field: None,
        }
    }

    /// Set the prescribed hub displacements and road state at time `t` into `x`.
    fn prescribe(&mut self, t: f64) {
        let phi = self.kin.phi(t);
        let (s, c) = phi.sin_cos();
        for &n in &self.hub {
            let x = self.sys.model.mesh.nodes[n as usize];
            let n = n as usize;
            self.sys.x[2 * n] = c * x[0] - s * x[1] - x[0];
            self.sys.x[2 * n + 1] = s * x[0] + c * x[1] - x[1];
        }
        if let Some(cm) = &mut self.sys.contact {
            if let Some(d) = self.kin.disp {
                cm.h = self.kin.h_touch - d.value(t);
            }
            if let Some(l) = self.kin.load {
                cm.load = Some(l.value(t));
            }
            cm.v0 = self.kin.v0.value(t);
        }
    }

    /// Kinetic energy ½ vᵀ M v of a full velocity vector.
    pub fn kinetic_energy(&self, v: &[f64]) -> f64 {
        let mut e = 0.0;
        for c in 0..self.sys.model.mesh.n_cells() {
            let nodes = self.sys.model.mesh.cell_nodes(c);
            let nn = nodes.len();
            let m = &self.mass[self.mass_off[c]..self.mass_off[c + 1]];
            for a in 0..nn {
                for b in 0..nn {
                    let (na, nb) = (nodes[a] as usize, nodes[b] as usize);
                    e += 0.5
                        * m[a * nn + b]
                        * (v[2 * na] * v[2 * nb] + v[2 * na + 1] * v[2 * nb + 1]);
                }
            }
        }
        e
    }

    /// Hub reaction (force and moment of the hub on the body) at the end-of-step state
    /// (x, v1, a1): internal (elastic and viscous), contact-free cell residual plus inertia at
    /// the hub nodes.
    pub fn hub_reaction(&self) -> (Vec2, f64) {
        let mesh = &self.sys.model.mesh;
        let mut is_hub = vec![false; mesh.n_nodes()];
        for &n in &self.hub {
            is_hub[n as usize] = true;
        }
        let (mut f, mut m) = (Vec2::zeros(), 0.0);
        let mut loc = Box::new(LocalSystem::new(0));
        for c in 0..mesh.n_cells() {
            let nodes = mesh.cell_nodes(c);
            if !nodes.iter().any(|&n| is_hub[n as usize]) {
                continue;
            }
            loc.clear(self.sys.dofs.cell(c).len());
            // Elastic and viscous (strain-rate damping) stresses: both load the hub.
            self.sys.model.cell_system_viscous(
                c,
                &self.sys.dofs,
                &self.sys.x,
                &self.v1,
                0.0,
                &mut loc,
                false,
            );
            let nn = nodes.len();
            let mm = &self.mass[self.mass_off[c]..self.mass_off[c + 1]];
            for a in 0..nn {
                let na = nodes[a] as usize;
                if !is_hub[na] || self.sys.dofs.eq[2 * na] != FIXED {
                    continue;
                }
                let mut fa = Vec2::new(loc.r[2 * a], loc.r[2 * a + 1]);
                for b in 0..nn {
                    let nb = nodes[b] as usize;
                    fa += Vec2::new(self.a1[2 * nb], self.a1[2 * nb + 1]) * mm[a * nn + b];
                }
                let xp = mesh.nodes[na] + Vec2::new(self.sys.x[2 * na], self.sys.x[2 * na + 1]);
                f += fa;
                m += xp[0] * fa[1] - xp[1] * fa[0];
            }
        }
        (f, m)
    }

    pub fn snapshot(&self) -> Snapshot {
        let (f, m) = self.hub_reaction();
        Snapshot {
            t: self.t,
            phi: self.kin.phi(self.t),
            hub_force_x: f[0],
            hub_force_y: f[1],
            hub_torque: m,
            kinetic_energy: self.kinetic_energy(&self.vn),
            strain_energy: self.sys.model.strain_energy(&self.sys.dofs, &self.un),
        }
    }

    /// Newmark update of v1, a1 and the α-point vectors from the trial x = u_{n+1}. The hub
    /// dofs take the exact velocity and acceleration of the prescribed rotation (a Newmark
    /// recursion on a prescribed history rings at the Nyquist frequency when ρ∞ = 1).
    fn newmark(&mut self, ga: &GenAlpha) {
        let dt = self.dt;
        let (b, g) = (ga.beta, ga.gamma);
        for d in 0..self.un.len() {
            let a1 = (self.sys.x[d] - self.un[d] - dt * self.vn[d]) / (b * dt * dt)
                - (0.5 / b - 1.0) * self.an[d];
            let v1 = self.vn[d] + dt * ((1.0 - g) * self.an[d] + g * a1);
            self.a1[d] = a1;
            self.v1[d] = v1;
        }
        self.hub_rates(self.t + dt);
        for d in 0..self.un.len() {
            self.xa[d] = self.sys.x[d];
            self.va[d] = self.v1[d];
            self.aa[d] = (1.0 - ga.am) * self.a1[d] + ga.am * self.an[d];
        }
    }

    /// Exact velocity and acceleration of the hub nodes at time `t` into v1, a1:
    /// x = Q(φ) X, v = ω e3 × x, a = ω̇ e3 × x − ω² x.
    fn hub_rates(&mut self, t: f64) {
        let phi = self.kin.phi(t);
        let (w, wd) = (self.kin.omega.value(t), self.kin.omega.rate(t));
        let (s, c) = phi.sin_cos();
        for &n in &self.hub {
            let xr = self.sys.model.mesh.nodes[n as usize];
            let x = Vec2::new(c * xr[0] - s * xr[1], s * xr[0] + c * xr[1]);
            let n = n as usize;
            self.v1[2 * n] = -w * x[1];
            self.v1[2 * n + 1] = w * x[0];
            self.a1[2 * n] = -wd * x[1] - w * w * x[0];
            self.a1[2 * n + 1] = wd * x[0] - w * w * x[1];
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
        let sys = &mut self.sys;
        sys.model.reset_admissible();
        sys.asm.zero(with_matrix);
        let (model, dofs) = (&sys.model, &sys.dofs);
        let (xa, va, aa, mass, off) = (&self.xa, &self.va, &self.aa, &self.mass, &self.mass_off);
        sys.asm.add_block(0, dofs, with_matrix, |c, loc| {
            model.cell_system_viscous(c, dofs, xa, va, kv, loc, with_matrix);
            let nd = loc.nd;
            if fs != 1.0 {
                loc.r[..nd].iter_mut().for_each(|v| *v *= fs);
                if with_matrix {
                    loc.k[..nd * nd].iter_mut().for_each(|v| *v *= fs);
                }
            }
            let cd = dofs.cell(c);
            let m = &mass[off[c]..off[c + 1]];
            let nn = model.mesh.cell_nodes(c).len();
            for a in 0..nn {
                for b in 0..nn {
                    let mab = m[a * nn + b];
                    if mab == 0.0 {
                        continue;
                    }
                    for i in 0..2 {
                        loc.r[2 * a + i] += mab * aa[cd[2 * b + i] as usize];
                        if with_matrix {
                            loc.k[(2 * a + i) * nd + 2 * b + i] += cm * mab;
                        }
                    }
                }
            }
        });
        let ok = model.admissible();
        if let Some(c) = &mut sys.contact {
            c.kinematics = SlipKinematics::Dynamic { kx: 1.0, kv };
        }
        if let Some(c) = &sys.contact {
            c.reset_visited();
            let (mesh, va) = (&sys.model.mesh, &self.va);
            sys.asm.add_block(1, dofs, with_matrix, |e, loc| {
                c.kernel(mesh, dofs, xa, va, e, loc, with_matrix);
                if fs != 1.0 {
                    let nd = loc.nd;
                    loc.r[..nd].iter_mut().for_each(|v| *v *= fs);
                    if with_matrix {
                        loc.k[..nd * nd].iter_mut().for_each(|v| *v *= fs);
                    }
                }
            });
            sys.facet_visits.0 += c.visited_facets();
            sys.facet_visits.1 += 1;
        }
        if prev != 0.0 {
            for (r, f) in sys.asm.residual.iter_mut().zip(&self.fprev) {
                *r += prev * f;
            }
        }
        ok && sys.asm.residual.iter().all(|r| r.is_finite())
    }

    /// Static forces f(u_n, v_n) of the committed state into `fprev`.
    fn update_fprev(&mut self) -> bool {
        self.xa.copy_from_slice(&self.un);
        self.va.copy_from_slice(&self.vn);
        self.aa.iter_mut().for_each(|v| *v = 0.0);
        let saved_x = std::mem::take(&mut self.sys.x);
        self.sys.x = self.un.clone();
        let ok = self.assemble_dynamic(false, 1.0, 0.0, 0.0, 0.0);
        self.sys.x = saved_x;
        self.fprev.clear();
        self.fprev.extend_from_slice(&self.sys.asm.residual);
        ok
    }

    /// Advance one step of size `dt` from the committed state (t, un, vn, an). On success the
    /// new state is committed and the local error estimate (generalized-α) is returned.
    pub fn step(&mut self, newton: &mut Newton, dt: f64) -> Result<(f64, usize), SolveError> {
        self.dt = dt;
        let t1 = self.t + dt;
        match self.scheme {
            Scheme::GeneralizedAlpha(ga) => {
                // Predictor: constant acceleration.
                for d in 0..self.un.len() {
                    self.sys.x[d] = self.un[d] + dt * self.vn[d] + 0.5 * dt * dt * self.an[d];
                }
                self.prescribe(t1);
                let rep = newton.solve(self)?;
                self.newmark(&ga);
                let mut num = 0.0;
                let mut den = 0.0;
                for d in 0..self.sys.dofs.n_u {
                    let e = (ga.beta - 1.0 / 6.0) * dt * dt * (self.a1[d] - self.an[d]);
                    num += e * e;
                    let du = self.sys.x[d] - self.un[d];
                    den += du * du;
                }
                let err = num.sqrt() / den.sqrt().max(f64::MIN_POSITIVE);
                self.commit(t1);
                Ok((err, rep.iterations))
            }
            Scheme::CentralDifference => {
                // v_n ≈ v_{n−1/2} for the contact rates; a_n = −M_L⁻¹ f(u_n).
                self.sys.x.copy_from_slice(&self.un);
                self.prescribe(self.t);
                self.xa.copy_from_slice(&self.sys.x);
                self.va.copy_from_slice(&self.vn);
                self.aa.iter_mut().for_each(|v| *v = 0.0);
                if !self.assemble_dynamic(false, 1.0, 0.0, 0.0, 0.0) {
                    return Err(SolveError::InadmissibleStart);
                }
                for d in 0..self.un.len() {
                    let e = self.sys.dofs.eq[d];
                    if e != FIXED && self.ml[d] > 0.0 {
                        self.an[d] = -self.sys.asm.residual[e as usize] / self.ml[d];
                    }
                }
                // Prescribed dofs: velocity from the prescribed positions.
                self.prescribe(t1);
                for d in 0..self.un.len() {
                    if self.sys.dofs.eq[d] != FIXED && self.ml[d] > 0.0 {
                        self.vn[d] += dt * self.an[d];
                        self.sys.x[d] = self.un[d] + dt * self.vn[d];
                    } else {
                        self.vn[d] = (self.sys.x[d] - self.un[d]) / dt;
                    }
                }
                self.v1.copy_from_slice(&self.vn);
                self.a1.copy_from_slice(&self.an);
                let x = self.sys.x.clone();
                self.un.copy_from_slice(&x);
                self.t = t1;
                Ok((0.0, 0))
            }
        }
    }

    fn commit(&mut self, t1: f64) {
        self.un.copy_from_slice(&self.sys.x);
        self.vn.copy_from_slice(&self.v1);
        self.an.copy_from_slice(&self.a1);
        self.t = t1;
        self.update_fprev();
    }

    /// Stable time step of the central-difference scheme: 2/ω_max with ω_max² the largest
    /// eigenvalue of M_L⁻¹ K (power iteration on the assembled tangent at the current state).
    pub fn stable_step(&mut self) -> f64 {
        self.sys.x.copy_from_slice(&self.un);
        self.xa.copy_from_slice(&self.un);
        self.va.copy_from_slice(&self.vn);
        if !self.assemble_dynamic(true, 1.0, 0.0, 0.0, 0.0) {
            return f64::NAN;
        }
        let n = self.sys.dofs.n_eq;
        let mut minv = vec![0.0; n];
        for (d, &e) in self.sys.dofs.eq.iter().enumerate() {
            if e != FIXED {
                minv[e as usize] = if self.ml[d] > 0.0 {
                    1.0 / self.ml[d]
                } else {
                    0.0
                };
            }
        }
        let mut x: Vec<f64> = (0..n)
            .map(|i| 1.0 + 0.1 * ((i as f64) * 0.37).sin())
            .collect();
        let mut y = vec![0.0; n];
        let mut lam = 0.0;
        for _ in 0..60 {
            self.sys.asm.matvec(&x, &mut y);
            for i in 0..n {
                y[i] *= minv[i];
            }
            let ny = y.iter().map(|v| v * v).sum::<f64>().sqrt();
            let nx = x.iter().map(|v| v * v).sum::<f64>().sqrt();
            lam = ny / nx.max(f64::MIN_POSITIVE);
            for i in 0..n {
                x[i] = y[i] / ny.max(f64::MIN_POSITIVE);
            }
        }
        // Power iteration underestimates λ_max slightly: 5 % margin.
        2.0 / (1.05 * lam).sqrt()
    }
}

impl NonlinearSystem for Transient {
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
    fn pattern(&self) -> (&[usize], &[usize]) {
        self.sys.pattern()
    }
    fn evaluate(&mut self, with_matrix: bool) -> bool {
        let Scheme::GeneralizedAlpha(ga) = self.scheme else {
            return false;
        };
        self.newmark(&ga);
        let dt = self.dt;
        let kv = ga.gamma / (ga.beta * dt);
        let cm = (1.0 - ga.am) / (ga.beta * dt * dt);
        self.assemble_dynamic(with_matrix, 1.0 - ga.af, kv, cm, ga.af)
    }
    fn residual(&self) -> &[f64] {
        self.sys.residual()
    }
    fn matrix_values(&self) -> &[f64] {
        self.sys.matrix_values()
    }
    fn update(&mut self, alpha: f64, dx: &[f64]) {
        self.sys.update(alpha, dx);
    }
    fn save_state(&self, buf: &mut Vec<f64>) {
        self.sys.save_state(buf);
    }
    fn restore_state(&mut self, buf: &[f64]) {
        self.sys.restore_state(buf);
    }
}

/// Steady-state monitor: the referential field at node passages.
pub struct SteadyMonitor {
    pub dtheta: f64,
    pub rings: usize,
    pub per_ring: usize,
    last_k: i64,
    prev: Option<(Vec<f64>, Snapshot)>,
    /// Relative changes at the last passage: (field, force, torque).
    pub last_change: (f64, f64, f64),
    pub passages: usize,
    /// Referential displacement field at the last passage (2 per referential node).
    pub field: Vec<f64>,
    /// One row per passage: t, changes (field, force, torque), hub force x, y, torque.
    pub log: Vec<[f64; 7]>,
    below_once: bool,
}

impl SteadyMonitor {
    pub fn new(sys: &SolidSystem) -> Option<Self> {
        let rl = sys.model.mesh.rings?;
        // The mesh repeats itself every cell, not every node (Q2: vertex and mid-side nodes
        // alternate), so the passages are taken every p node steps = one cell.
        Some(Self {
            dtheta: 2.0 * PI / rl.n_theta as f64,
            rings: rl.rings,
            per_ring: rl.per_ring,
            last_k: i64::MIN,
            prev: None,
            last_change: (f64::INFINITY, f64::INFINITY, f64::INFINITY),
            passages: 0,
            field: Vec::new(),
            log: Vec::new(),
            below_once: false,
        })
    }

    /// After an accepted step from (t0, u0, v0) to (t1, u1, v1): if φ crossed a multiple of
    /// the node angle, extract the referential field at that instant and compare. Returns
    /// true when steady (changes below `tol`).
    #[allow(clippy::too_many_arguments)]
    pub fn check(
        &mut self,
        tr: &Transient,
        t0: f64,
        u0: &[f64],
        v0: &[f64],
        snap0: &Snapshot,
        snap1: &Snapshot,
        tol: f64,
    ) -> bool {
        let k1 = (tr.kin.phi(tr.t) / self.dtheta).floor() as i64;
        if self.last_k == i64::MIN {
            self.last_k = k1;
            return false;
        }
        if k1 <= self.last_k {
            return false;
        }
        self.last_k = k1;
        let target = k1 as f64 * self.dtheta;
        // Bisection for φ(t*) = kΔθ in [t0, t1] (φ is monotone).
        let (mut lo, mut hi) = (t0, tr.t);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if tr.kin.phi(mid) < target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let ts = 0.5 * (lo + hi);
        let h = tr.t - t0;
        let s = if h > 0.0 { (ts - t0) / h } else { 1.0 };
        // Cubic Hermite basis on [0, 1].
        let h00 = 2.0 * s * s * s - 3.0 * s * s + 1.0;
        let h10 = s * s * s - 2.0 * s * s + s;
        let h01 = -2.0 * s * s * s + 3.0 * s * s;
        let h11 = s * s * s - s * s;
        let mesh = &tr.sys.model.mesh;
        let per = self.per_ring;
        let mut field = vec![0.0; 2 * mesh.n_nodes()];
        let kk = (k1 * (per / (2.0 * PI / self.dtheta).round() as usize) as i64)
            .rem_euclid(per as i64) as usize;
        for m in 0..self.rings {
            for l in 0..per {
                let i = m * per + l;
                let j = m * per + (l + kk) % per;
                for c in 0..2 {
                    let u = h00 * u0[2 * i + c]
                        + h10 * h * v0[2 * i + c]
                        + h01 * tr.un[2 * i + c]
                        + h11 * h * tr.vn[2 * i + c];
                    let xi = mesh.nodes[i][c] + u;
                    field[2 * j + c] = xi - mesh.nodes[j][c];
                }
            }
        }
        let snap = Snapshot {
            t: ts,
            phi: target,
            hub_force_x: snap0.hub_force_x + s * (snap1.hub_force_x - snap0.hub_force_x),
            hub_force_y: snap0.hub_force_y + s * (snap1.hub_force_y - snap0.hub_force_y),
            hub_torque: snap0.hub_torque + s * (snap1.hub_torque - snap0.hub_torque),
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
            let fscale = snap
                .hub_force_x
                .hypot(snap.hub_force_y)
                .max(f64::MIN_POSITIVE);
            let df = (snap.hub_force_x - ps.hub_force_x).hypot(snap.hub_force_y - ps.hub_force_y)
                / fscale;
            let tscale = fscale * mesh.nodes.iter().map(|x| x.norm()).fold(0.0, f64::max);
            let dm = (snap.hub_torque - ps.hub_torque).abs() / tscale.max(f64::MIN_POSITIVE);
            self.last_change = (num / den, df, dm);
            // Steady: two consecutive passages below the tolerance.
            let below = num / den < tol && df < tol && dm < tol;
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
        ]);
        self.field = field.clone();
        self.prev = Some((field, snap));
        steady
    }
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
    /// Relative changes (referential field, hub force, torque) over the last node passage.
    pub last_change: [f64; 3],
    /// Node-passage log (see [`SteadyMonitor::log`]).
    pub passage_log: Vec<[f64; 7]>,
    pub history: Vec<Snapshot>,
}

/// Integrate until steady (or t_end). `on_step` is called after each accepted step.
pub fn integrate(
    tr: &mut Transient,
    opts: &TimeOptions,
    newton_opts: NewtonOptions,
    kind: crate::solver::LinearKind,
    mut on_step: impl FnMut(&Transient, &TransientReport),
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
    let area = super::system::domain_area(&tr.sys.model);
    let ro = tr
        .sys
        .model
        .mesh
        .nodes
        .iter()
        .map(|x| x.norm())
        .fold(0.0, f64::max);
    let fref = tr.sys.model.rho * area * (tr.kin.omega.target.powi(2) * ro).max(1.0)
        + tr.kin.load.map_or(0.0, |l| l.target.abs());
    tr.sys.set_reference_force(fref);
    let mut monitor = SteadyMonitor::new(&tr.sys);
    tr.prescribe(tr.t);
    if !tr.update_fprev() {
        return Err((SolveError::InadmissibleStart, rep));
    }
    let mut dt = match tr.scheme {
        Scheme::CentralDifference => {
            let s = tr.stable_step();
            if s.is_finite() {
                (0.9 * s).min(opts.dt)
            } else {
                opts.dt
            }
        }
        _ => opts.dt,
    };
    let mut snap0 = tr.snapshot();
    rep.history.push(snap0);
    let (mut u0, mut v0, mut a0) = (tr.un.clone(), tr.vn.clone(), tr.an.clone());
    let mut saved = Vec::new();
    while tr.t < opts.t_end - 1e-12 * opts.t_end && rep.steps < opts.max_steps {
        // Ctrl-C: stop at this step boundary (the committed state is the last accepted step).
        if crate::io::record::interrupted() {
            return Err((SolveError::Interrupted { at: tr.t }, rep));
        }
        dt = dt
            .min(opts.t_end - tr.t)
            .max(opts.dt_min.min(opts.t_end - tr.t));
        // Land exactly on the next node passage once the ramps are done, so that the
        // referential field and the hub forces are sampled from a computed state (the hub force
        // varies quickly within a passage as nodes enter the patch: interpolating it is noisy).
        let mut dt_step = dt;
        if let (Some(m), true) = (&monitor, opts.land_on_passages) {
            if tr.t >= tr.kin.ramps_done() && tr.kin.omega.target > 0.0 {
                let k = (tr.kin.phi(tr.t) / m.dtheta + 1e-9).floor() + 1.0;
                let target = k * m.dtheta;
                // Time of the next passage (φ is monotone) within a generous bracket.
                let mut hi = tr.t + dt;
                while tr.kin.phi(hi) < target && hi < opts.t_end {
                    hi += dt;
                }
                let mut lo = tr.t;
                for _ in 0..80 {
                    let mid = 0.5 * (lo + hi);
                    if tr.kin.phi(mid) < target {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                // Equal steps up to the passage: every passage is then computed with the
                // same step pattern, so a steady state is exactly periodic between passages.
                let remaining = hi - tr.t;
                if remaining > 1e-3 * dt {
                    let m = (remaining / dt - 1e-9).ceil().max(1.0);
                    dt_step = remaining / m;
                }
            }
        }
        let h = dt_step;
        let shortened = h < dt;
        let t0 = tr.t;
        u0.copy_from_slice(&tr.un);
        v0.copy_from_slice(&tr.vn);
        a0.copy_from_slice(&tr.an);
        tr.sys.save_state(&mut saved);
        match tr.step(&mut newton, h) {
            Ok((err, its)) => {
                let reject = opts.adaptive
                    && matches!(tr.scheme, Scheme::GeneralizedAlpha(_))
                    && err > 4.0 * opts.error_tol
                    && h > opts.dt_min;
                if reject {
                    tr.t = t0;
                    tr.un.copy_from_slice(&u0);
                    tr.vn.copy_from_slice(&v0);
                    tr.an.copy_from_slice(&a0);
                    tr.sys.restore_state(&saved);
                    rep.rejected += 1;
                    dt = (h * (0.9 * (opts.error_tol / err).cbrt()).clamp(0.2, 0.9))
                        .max(opts.dt_min);
                    continue;
                }
                rep.steps += 1;
                rep.newton_iterations += its;
                rep.dt_min_used = rep.dt_min_used.min(h);
                rep.dt_max_used = rep.dt_max_used.max(h);
                let snap1 = tr.snapshot_light();
                if let Some(m) = &mut monitor {
                    if tr.t >= tr.kin.ramps_done()
                        && m.check(tr, t0, &u0, &v0, &snap0, &snap1, opts.steady_tol)
                        && !rep.steady
                    {
                        rep.steady = true;
                        rep.time_to_steady = Some(tr.t);
                    }
                    rep.passages = m.passages;
                    rep.last_change = [m.last_change.0, m.last_change.1, m.last_change.2];
                }
                snap0 = snap1;
                rep.final_time = tr.t;
                rep.revolutions = tr.kin.phi(tr.t) / (2.0 * PI);
                on_step(tr, &rep);
                if rep.steady && opts.stop_at_steady {
                    break;
                }
                if opts.adaptive && matches!(tr.scheme, Scheme::GeneralizedAlpha(_)) && err > 0.0 {
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
                tr.t = t0;
                tr.un.copy_from_slice(&u0);
                tr.vn.copy_from_slice(&v0);
                tr.an.copy_from_slice(&a0);
                tr.sys.restore_state(&saved);
                rep.rejected += 1;
                dt = h;
                if dt <= opts.dt_min * (1.0 + 1e-12)
                    || matches!(tr.scheme, Scheme::CentralDifference)
                {
                    rep.final_time = tr.t;
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
        }
        rep.passage_log = m.log.clone();
    }
    rep.history.push(tr.snapshot());
    Ok(rep)
}

impl Transient {
    /// Hub reaction only (no energies): cheap per-step snapshot.
    pub fn snapshot_light(&self) -> Snapshot {
        let (f, m) = self.hub_reaction();
        Snapshot {
            t: self.t,
            phi: self.kin.phi(self.t),
            hub_force_x: f[0],
            hub_force_y: f[1],
            hub_torque: m,
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
    fn pattern(&self) -> (&[usize], &[usize]) {
        self.tr.sys.pattern()
    }
    fn evaluate(&mut self, with_matrix: bool) -> bool {
        let tr = &mut *self.tr;
        let n_u = tr.sys.dofs.n_u;
        for d in 0..tr.un.len() {
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
        let area = super::system::domain_area(&self.sys.model);
        self.sys
            .set_reference_force(self.sys.model.rho * area * omega * omega);
        for s in 1..=steps {
            let omega2 = ca * s as f64 / steps as f64;
            let mut rs = RigidSpin { tr: self, omega2 };
            newton.solve(&mut rs)?;
        }
        let n_u = self.sys.dofs.n_u;
        self.un.copy_from_slice(&self.sys.x);
        for d in (0..n_u).step_by(2) {
            let p = self.sys.model.mesh.nodes[d / 2] + Vec2::new(self.sys.x[d], self.sys.x[d + 1]);
            self.vn[d] = -cv * p[1];
            self.vn[d + 1] = cv * p[0];
            self.an[d] = -ca * p[0];
            self.an[d + 1] = -ca * p[1];
        }
        // The hub nodes carry the exact rates of the prescribed rotation, as during stepping.
        self.v1.copy_from_slice(&self.vn);
        self.a1.copy_from_slice(&self.an);
        self.hub_rates(self.t);
        self.vn.copy_from_slice(&self.v1);
        self.an.copy_from_slice(&self.a1);
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
pub mod ode_first_order;
