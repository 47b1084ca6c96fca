//! [`SolidSystem`]: a [`SolidModel`] (plus, optionally, contact with the road) with its dofs,
//! assembler and state, exposed to Newton as a [`NonlinearSystem`]. The hub node set is bonded
//! to the rigid hub (u = 0 there). The load factor λ ∈ [0, 1] drives the analysis
//! ([`Loading`]): ω² for spinning, the road position for indentation, the hub load for load
//! control.
//!
//! The equations solved are R(x) = 0 with
//!
//! ```text
//! R = R_solid(x; ω²) + R_contact(x, x_prev; H or load) [+ steady strain-rate damping]
//! ```
//!
//! R_solid is [`crate::physics::solid`]'s (internal work − ω² B − body force, + pressure
//! constraints); R_contact is the facets' −∫ t · η ds ([`crate::contact`]). Residuals are
//! internal minus external forces (per unit thickness); the tangent is ∂R/∂x. The state `x`
//! holds the full nodal displacements (x1, x2 per node, in the scene's length unit), then the
//! cell pressures and the global unknowns (e.g. the road height under load control); the hub
//! nodes are fixed and carry no equation.

use crate::assembly::{Assembler, DofMap, LocalSystem, FIXED};
use crate::contact::{ContactModel, ContactSample, SlipKinematics};
use crate::math::Vec2;
use crate::physics::viscoelastic_steady::RingError;
use crate::physics::{RingDerivative, SolidModel, SteadyHistory};
use crate::solver::stepping::LoadedSystem;
use crate::solver::NonlinearSystem;

/// What the load factor λ scales.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Loading {
    /// ω² = λ ω²_target.
    Spin { omega2: f64 },
    /// Road height H = h_touch − λ · disp (displacement control).
    Indent { h_touch: f64, disp: f64 },
    /// Downward hub load P = λ · load (load control; H is an unknown).
    Load { load: f64 },
}

pub struct SolidSystem {
    pub model: SolidModel,
    pub contact: Option<ContactModel>,
    pub dofs: DofMap,
    pub asm: Assembler,
    /// Full state vector (displacements, cell pressures, global unknowns).
    pub x: Vec<f64>,
    /// State at the last converged load step (friction history in static analyses).
    pub x_prev: Vec<f64>,
    /// State at the start of the last accepted load step: after [`LoadedSystem::commit`] the
    /// static slip w = (x − x_start)/Δτ of that step is still known for the outputs.
    x_step_start: Vec<f64>,
    pub loading: Loading,
    /// Load factor of the current target and of the last converged step.
    pub lambda: f64,
    pub lambda_prev: f64,
    /// Target ω² reached at λ = 1 (kept for the spinning driver).
    pub omega2_target: f64,
    ref_norms: Vec<f64>,
    /// Contact facets integrated per assembly (sum, count) for reporting.
    pub facet_visits: (usize, usize),
    /// Steady mode: strain-rate damping on the nodal velocities ω ∂θχ
    /// ([`Self::enable_steady_viscosity`]).
    pub steady_visc: Option<SteadyViscosity>,
    /// Steady mode with a viscoelastic material: the internal variables integrated along the
    /// rings of quadrature points ([`Self::enable_steady_viscoelastic`]).
    pub steady_history: Option<SteadyHistory>,
}

/// The steady mode's strain-rate damping (see [`SolidSystem::enable_steady_viscosity`]): the
/// ring-difference operator and, per cell, the extended element (the cell's nodes, then the
/// other nodes of their ring stencils) assembled as one block of the system.
#[derive(Clone, Debug)]
pub struct SteadyViscosity {
    pub ring: RingDerivative,
    /// Index of the extended-element block in the assembler.
    pub block: usize,
    /// Per cell and local node: (index of the stencil node in the extended element, weight).
    stencil: Vec<Vec<[(u16, f64); crate::physics::ring_derivative::WIDTH]>>,
    /// Nodal velocities of the current evaluation (full length; reused, not reallocated).
    vel: Vec<f64>,
}

impl SolidSystem {
    /// Fix the nodes of `fixed_set` (both components, value 0 unless changed in `x`).
    pub fn new(model: SolidModel, fixed_set: &str) -> Self {
        let fixed: Vec<u32> = model.mesh.node_set(fixed_set).to_vec();
        Self::with_fixed_nodes(model, &fixed)
    }

    /// Fix both displacement components of the given nodes (values taken from `x`, initially 0).
    pub fn with_fixed_nodes(model: SolidModel, fixed: &[u32]) -> Self {
        Self::build(model, None, fixed)
    }

    /// Solid with contact on the outer facets; the hub set is fixed. Under load control the
    /// road height is a global unknown, initialised to `contact.h`.
    pub fn with_contact(model: SolidModel, contact: ContactModel) -> Self {
        let fixed: Vec<u32> = model.mesh.node_set("hub").to_vec();
        Self::build(model, Some(contact), &fixed)
    }

    fn build(model: SolidModel, contact: Option<ContactModel>, fixed: &[u32]) -> Self {
        let n_global = usize::from(contact.as_ref().is_some_and(|c| c.load.is_some()));
        let dofs = DofMap::with_globals(&model.mesh, model.dofs_per_cell(), fixed, n_global);
        let mut blocks = vec![(dofs.cell_dofs.clone(), dofs.cell_offsets.clone())];
        if let Some(c) = &contact {
            blocks.push(c.element_dofs(&model.mesh, &dofs));
        }
        let asm = Assembler::with_blocks(&dofs, blocks);
        let mut x = model.initial_state(&dofs);
        if let (Some(c), true) = (&contact, n_global > 0) {
            x[dofs.global(0)] = c.h;
        }
        // Pressure residuals are volumes (∫ (J − 1) q dV): their floor is the volume scale.
        let area = domain_area(&model);
        let h_ref = contact.as_ref().and_then(|c| c.load).unwrap_or(0.0);
        Self {
            model,
            contact,
            dofs,
            asm,
            x_prev: x.clone(),
            x_step_start: x.clone(),
            x,
            loading: Loading::Spin { omega2: 0.0 },
            lambda: 0.0,
            lambda_prev: 0.0,
            omega2_target: 0.0,
            ref_norms: vec![0.0, 1e-3 * area, h_ref, 0.0],
            facet_visits: (0, 0),
            steady_visc: None,
            steady_history: None,
        }
    }

    /// Number of equations (free dofs).
    pub fn n_dofs(&self) -> usize {
        self.dofs.n_eq
    }

    /// Set the reference norm of the displacement residual (e.g. the norm of the full load).
    pub fn set_reference_force(&mut self, f: f64) {
        self.ref_norms[0] = f;
        if self.ref_norms[2] == 0.0 {
            self.ref_norms[2] = f;
        }
        // The hub-angle equation (torque control) is a moment balance: force × outer radius.
        self.ref_norms[3] = f * self.model.mesh.outer_radius();
    }

    /// Floor of the displacement field's convergence reference for a contact loading (see
    /// [`crate::solver::newton`]): the hub load under load control; under displacement
    /// control the series combination F_c F_b / (F_c + F_b) of the penalty-limited force
    /// F_c = c_n DISP^m_n √(2 Ro DISP) (a Hertz-like patch on a rigid body: the soft-penalty
    /// limit) and the body-limited force F_b = G DISP (G the small-strain shear modulus: the
    /// stiff-penalty limit), so that a huge c_n cannot inflate it past the physical force.
    /// 1 for a spin loading. `ro`: outer radius.
    pub fn contact_force_scale(&self, ro: f64) -> f64 {
        let f = match self.loading {
            Loading::Load { load } => load.abs(),
            Loading::Indent { disp, .. } => {
                let disp = disp.abs();
                let g = self.model.material.small_strain_shear_modulus().abs();
                let fb = g * disp;
                let fc = self.contact.as_ref().map_or(fb, |c| {
                    c.normal.c_n.abs() * disp.powf(c.normal.m_n) * (2.0 * ro * disp).sqrt()
                });
                if fc + fb > 0.0 {
                    fc * fb / (fc + fb)
                } else {
                    0.0
                }
            }
            Loading::Spin { .. } => 1.0,
        };
        f.max(f64::MIN_POSITIVE)
    }

    /// Torque control: add the hub rotation angle φ as the last global unknown (field 3,
    /// "phi") and a block coupling φ with every dof of the cells that touch the hub (the hub
    /// nodes stay fixed dofs whose values follow x = Q(φ) X). Rebuilds the dof map and the
    /// assembler; the state keeps its values (φ = 0). Returns (full index of φ, block index).
    pub fn add_hub_angle(&mut self) -> (usize, usize) {
        let mesh = &self.model.mesh;
        let hub: Vec<u32> = mesh.node_set("hub").to_vec();
        let n_global = self.dofs.n_global + 1;
        let mut dofs = DofMap::with_globals(mesh, self.model.dofs_per_cell(), &hub, n_global);
        let iphi = dofs.global(n_global - 1);
        let mut blocks = vec![(dofs.cell_dofs.clone(), dofs.cell_offsets.clone())];
        if let Some(c) = &self.contact {
            blocks.push(c.element_dofs(mesh, &dofs));
        }
        let mut is_hub = vec![false; mesh.n_nodes()];
        for &n in &hub {
            is_hub[n as usize] = true;
        }
        let (mut list, mut off) = (Vec::new(), vec![0]);
        for c in 0..mesh.n_cells() {
            if mesh.cell_nodes(c).iter().any(|&n| is_hub[n as usize]) {
                list.extend_from_slice(dofs.cell(c));
                list.push(iphi as u32);
                off.push(list.len());
            }
        }
        let block = blocks.len();
        blocks.push((list, off));
        let eq = dofs.eq[iphi] as usize;
        dofs.field[eq] = 3;
        let parallel = self.asm.parallel;
        self.asm = Assembler::with_blocks(&dofs, blocks);
        self.asm.parallel = parallel;
        self.dofs = dofs;
        self.x.push(0.0);
        self.x_prev.push(0.0);
        self.x_step_start.push(0.0);
        (iphi, block)
    }

    /// Steady (θ-referential) mode with friction: take the slip velocity from nodal
    /// θ-derivatives along the contact boundary ([`crate::contact::steady_slip`]), continuous
    /// across facets. The contact elements grow to the stencil nodes: the assembler is rebuilt
    /// (the blocks keep their order). No effect without friction or when the contact facets
    /// do not allow the stencil (then the facet-wise derivative stays).
    pub fn enable_steady_slip(&mut self) {
        let Some(c) = &mut self.contact else {
            return;
        };
        if !c.friction.is_active() || c.steady_slip.is_some() {
            return;
        }
        if !c.enable_steady_slip(&self.model.mesh) {
            return;
        }
        let mut lists: Vec<(Vec<u32>, Vec<usize>)> = self
            .asm
            .blocks
            .iter()
            .map(|b| (b.dofs.clone(), b.offsets.clone()))
            .collect();
        lists[1] = c.element_dofs(&self.model.mesh, &self.dofs);
        let parallel = self.asm.parallel;
        self.asm = Assembler::with_blocks(&self.dofs, lists);
        self.asm.parallel = parallel;
    }

    /// Steady (θ-referential) mode with strain-rate damping: assemble the damping on the
    /// material rate Ė = sym(Fᵀ ∇v_h), v_h the interpolant of the nodal velocities
    /// v_a = ω (t_a + (∂θu)_a) with ring differences ([`RingDerivative`]), as the transient mode
    /// does with its nodal velocities. Each cell's damping forces then depend on the nodes of
    /// its ring stencils (two positions beyond the cell on each side), assembled as an extra
    /// block with the exact tangent. Active in [`NonlinearSystem::evaluate`] and
    /// [`Self::hub_reaction`] while `model.steady_omega` is set. No effect without damping or
    /// without a ring-structured mesh (the steady mode always has one).
    pub fn enable_steady_viscosity(&mut self) {
        use crate::physics::ring_derivative::WIDTH;
        if self.steady_visc.is_some() || self.model.strain_rate_damping <= 0.0 {
            return;
        }
        let Some(ring) = RingDerivative::new(&self.model.mesh) else {
            return;
        };
        let mesh = &self.model.mesh;
        let (mut list, mut off) = (Vec::new(), vec![0]);
        let mut stencil = Vec::with_capacity(mesh.n_cells());
        for c in 0..mesh.n_cells() {
            let nodes = mesh.cell_nodes(c);
            let mut ext: Vec<u32> = nodes.to_vec();
            for &a in nodes {
                for &(b, _) in &ring.stencils[a as usize] {
                    if !ext.contains(&b) {
                        ext.push(b);
                    }
                }
            }
            let st: Vec<[(u16, f64); WIDTH]> = nodes
                .iter()
                .map(|&a| {
                    let mut s = [(0u16, 0.0); WIDTH];
                    for (k, &(b, w)) in ring.stencils[a as usize].iter().enumerate() {
                        let i = ext.iter().position(|&e| e == b).unwrap_or(0);
                        s[k] = (i as u16, w);
                    }
                    s
                })
                .collect();
            stencil.push(st);
            for &n in &ext {
                list.push(2 * n);
                list.push(2 * n + 1);
            }
            off.push(list.len());
        }
        let mut lists: Vec<(Vec<u32>, Vec<usize>)> = self
            .asm
            .blocks
            .iter()
            .map(|b| (b.dofs.clone(), b.offsets.clone()))
            .collect();
        let block = lists.len();
        lists.push((list, off));
        let parallel = self.asm.parallel;
        self.asm = Assembler::with_blocks(&self.dofs, lists);
        self.asm.parallel = parallel;
        self.steady_visc = Some(SteadyViscosity {
            vel: vec![0.0; self.x.len()],
            ring,
            block,
            stencil,
        });
    }

    /// Nodal velocities ω ∂θχ of the steady mode's damping at the current state (full-length
    /// vector), or `None` when that damping is not active.
    fn steady_velocities(&self) -> Option<(Vec<f64>, f64)> {
        let (sv, om) = (self.steady_visc.as_ref()?, self.model.steady_omega?);
        if self.model.strain_rate_damping <= 0.0 {
            return None;
        }
        let mut vel = vec![0.0; self.x.len()];
        sv.ring.velocities(&self.model.mesh, &self.x, om, &mut vel);
        Some((vel, om))
    }

    /// Assemble the steady damping block (residual and, with `with_matrix`, the tangent).
    fn add_steady_viscosity(&mut self, with_matrix: bool) {
        let (Some(sv), Some(om)) = (self.steady_visc.as_mut(), self.model.steady_omega) else {
            return;
        };
        if self.model.strain_rate_damping <= 0.0 {
            return;
        }
        sv.ring
            .velocities(&self.model.mesh, &self.x, om, &mut sv.vel);
        let sv = &*sv;
        let vel = &sv.vel;
        let (model, dofs, x) = (&self.model, &self.dofs, &self.x);
        self.asm
            .add_block_large(sv.block, dofs, with_matrix, |c, r, k| {
                let nu = 2 * model.mesh.cell_nodes(c).len();
                let nd = r.len();
                let mut rv = [0.0; 18];
                let (mut ax, mut av) = ([0.0; 18 * 18], [0.0; 18 * 18]);
                model.cell_viscous_split(c, dofs, x, vel, with_matrix, &mut rv, &mut ax, &mut av);
                r[..nu].copy_from_slice(&rv[..nu]);
                if !with_matrix {
                    return;
                }
                for i in 0..nu {
                    for j in 0..nu {
                        k[i * nd + j] += ax[i * nu + j];
                    }
                    // v_{a,comp} = ω (t_a + Σ_b w_b u_{b,comp}).
                    for (a, st) in sv.stencil[c].iter().enumerate() {
                        for comp in 0..2 {
                            let dv = av[i * nu + 2 * a + comp];
                            if dv == 0.0 {
                                continue;
                            }
                            for &(e, w) in st {
                                k[i * nd + 2 * e as usize + comp] += dv * om * w;
                            }
                        }
                    }
                }
            });
    }

    /// Steady (θ-referential) mode with a viscoelastic material: before every evaluation the
    /// history of the quadrature points is replaced by the periodic steady states along the
    /// rings at the current state and ω ([`SteadyHistory`]), and Newton takes the exact step
    /// with the ring coupling applied matrix-free. No effect for an elastic material; an error
    /// when the mesh has no rings.
    pub fn enable_steady_viscoelastic(&mut self) -> Result<(), RingError> {
        if self.model.viscoelastic.is_none() || self.steady_history.is_some() {
            return Ok(());
        }
        self.steady_history = Some(SteadyHistory::new(&self.model)?);
        Ok(())
    }

    /// Bring the steady history in line with the current state (see
    /// [`Self::enable_steady_viscoelastic`]).
    fn sync_steady_history(&mut self) {
        if let (Some(sh), Some(om)) = (self.steady_history.as_mut(), self.model.steady_omega) {
            sh.sync(&mut self.model, &self.dofs, &self.x, om);
        }
    }

    /// Norm of the residual at the current state (assembles the residual only).
    pub fn residual_norm(&mut self) -> f64 {
        self.evaluate(false);
        self.asm.residual.iter().map(|r| r * r).sum::<f64>().sqrt()
    }

    /// Current road height (None without contact).
    pub fn road_height(&self) -> Option<f64> {
        self.contact
            .as_ref()
            .map(|c| c.road_height(&self.dofs, &self.x))
    }

    /// Contact traction samples at the current state. In load stepping the slip is that of
    /// the last accepted step, w = (x − x_start)/Δτ (after the commit x_prev = x, which would
    /// report w = 0 and no static friction).
    pub fn contact_samples(&self) -> Vec<ContactSample> {
        match &self.contact {
            Some(c) => {
                let aux = match c.kinematics {
                    SlipKinematics::Static { .. } if self.x_step_start.len() == self.x.len() => {
                        &self.x_step_start
                    }
                    _ => &self.x_prev,
                };
                c.samples(&self.model.mesh, &self.dofs, &self.x, aux)
            }
            None => Vec::new(),
        }
    }

    /// Mean number of contact facets integrated per assembly so far.
    pub fn mean_facets_per_assembly(&self) -> f64 {
        if self.facet_visits.1 == 0 {
            0.0
        } else {
            self.facet_visits.0 as f64 / self.facet_visits.1 as f64
        }
    }

    /// Force and moment (about the hub centre, counter-clockwise positive) exerted by the hub
    /// on the body: the residual entries of the fixed hub dofs (R = f_int − f_ext, so at a
    /// support R equals the reaction).
    pub fn hub_reaction(&self) -> (Vec2, f64) {
        let mut is_hub = vec![false; self.model.mesh.n_nodes()];
        for &n in self.model.mesh.node_set("hub") {
            is_hub[n as usize] = true;
        }
        let mut force = Vec2::zeros();
        let mut moment = 0.0;
        let mut loc = Box::new(LocalSystem::new(0));
        let steady_vel = self.steady_velocities();
        for c in 0..self.model.mesh.n_cells() {
            let nodes = self.model.mesh.cell_nodes(c);
            if !nodes.iter().any(|&n| is_hub[n as usize]) {
                continue;
            }
            let nd = self.dofs.cell(c).len();
            loc.clear(nd);
            self.model.cell_residual(c, &self.dofs, &self.x, &mut loc);
            if let Some((vel, _)) = &steady_vel {
                // The steady damping forces are part of what the hub transmits.
                let mut rv = [0.0; 18];
                let (mut ax, mut av) = ([0.0; 18 * 18], [0.0; 18 * 18]);
                self.model.cell_viscous_split(
                    c, &self.dofs, &self.x, vel, false, &mut rv, &mut ax, &mut av,
                );
                for (a, v) in rv.iter().enumerate().take(2 * nodes.len()) {
                    loc.r[a] += v;
                }
            }
            for (a, &n) in nodes.iter().enumerate() {
                let n = n as usize;
                if is_hub[n] && self.dofs.eq[2 * n] == FIXED {
                    let f = Vec2::new(loc.r[2 * a], loc.r[2 * a + 1]);
                    let xp = self.model.mesh.nodes[n] + Vec2::new(self.x[2 * n], self.x[2 * n + 1]);
                    force += f;
                    moment += xp[0] * f[1] - xp[1] * f[0];
                }
            }
        }
        (force, moment)
    }
}

/// Area of the reference domain (quadrature of det J).
pub fn domain_area(model: &SolidModel) -> f64 {
    let rule = crate::element::QuadRule::gauss_2d(3);
    let mut a = 0.0;
    for c in 0..model.mesh.n_cells() {
        for (pt, w) in rule.points.iter().zip(&rule.weights) {
            if let Some(j) = model.point_values_geometry(c, pt.0, pt.1) {
                a += j.determinant() * w;
            }
        }
    }
    a
}

impl NonlinearSystem for SolidSystem {
    fn n_eq(&self) -> usize {
        self.dofs.n_eq
    }
    fn fields(&self) -> &[u8] {
        &self.dofs.field
    }
    fn field_names(&self) -> &'static [&'static str] {
        &["u", "p", "H", "phi"]
    }
    fn reference_norms(&self) -> Vec<f64> {
        self.ref_norms.clone()
    }
    fn force_scale(&self) -> &[f64] {
        &self.asm.scale
    }
    fn state_magnitudes(&self, out: &mut Vec<f64>) {
        out.clear();
        out.resize(self.dofs.n_eq, 0.0);
        let n_u = self.dofs.n_u;
        for (d, &e) in self.dofs.eq.iter().enumerate() {
            if e == FIXED {
                continue;
            }
            out[e as usize] = if d < n_u {
                let n = d / 2;
                let p = self.model.mesh.nodes[n] + Vec2::new(self.x[2 * n], self.x[2 * n + 1]);
                p.norm()
            } else {
                self.x[d].abs()
            };
        }
    }
    fn pattern(&self) -> (&[usize], &[usize]) {
        (&self.asm.col_ptr, &self.asm.row_idx)
    }
    fn evaluate(&mut self, with_matrix: bool) -> bool {
        self.sync_steady_history();
        let ok = self
            .model
            .assemble(&mut self.asm, &self.dofs, &self.x, with_matrix);
        self.add_steady_viscosity(with_matrix);
        if let Some(c) = &self.contact {
            c.reset_visited();
            let (mesh, dofs, x, xp) = (&self.model.mesh, &self.dofs, &self.x, &self.x_prev);
            self.asm.add_block(1, dofs, with_matrix, |e, loc| {
                c.kernel(mesh, dofs, x, xp, e, loc, with_matrix)
            });
            self.facet_visits.0 += c.visited_facets();
            self.facet_visits.1 += 1;
        }
        ok && self.asm.residual.iter().all(|r| r.is_finite())
    }
    fn residual(&self) -> &[f64] {
        &self.asm.residual
    }
    fn matrix_values(&self) -> &[f64] {
        &self.asm.values
    }
    fn update(&mut self, alpha: f64, dx: &[f64]) {
        self.dofs.add_free(alpha, dx, &mut self.x);
    }
    fn save_state(&self, buf: &mut Vec<f64>) {
        buf.clear();
        buf.extend_from_slice(&self.x);
    }
    fn restore_state(&mut self, buf: &[f64]) {
        self.x.copy_from_slice(buf);
        self.sync_steady_history();
    }
    fn has_tangent_correction(&self) -> bool {
        self.steady_history.is_some() && self.model.steady_omega.is_some()
    }
    fn tangent_correction(&mut self, v: &[f64], out: &mut [f64]) {
        if let (Some(sh), Some(om)) = (self.steady_history.as_mut(), self.model.steady_omega) {
            sh.apply_correction(&self.model, &self.dofs, om, v, out);
        }
    }
}

impl LoadedSystem for SolidSystem {
    fn set_load(&mut self, lambda: f64) {
        self.lambda = lambda;
        match self.loading {
            Loading::Spin { omega2 } => self.model.omega2 = lambda * omega2,
            Loading::Indent { h_touch, disp } => {
                if let Some(c) = &mut self.contact {
                    c.h = h_touch - lambda * disp;
                }
            }
            Loading::Load { load } => {
                if let Some(c) = &mut self.contact {
                    c.load = Some(lambda * load);
                }
            }
        }
        if let Some(c) = &mut self.contact {
            // Steady rolling measures velocities by ω ∂θχ, not in the load-stepping time. A
            // restore to the converged λ (λ = λ_prev) keeps the last step's Δτ, with which
            // the outputs evaluate that step's slip.
            if !matches!(c.kinematics, SlipKinematics::Steady { .. })
                && (lambda > self.lambda_prev || self.lambda_prev == 0.0)
            {
                c.kinematics = SlipKinematics::Static {
                    dtau: (lambda - self.lambda_prev).max(f64::MIN_POSITIVE),
                };
            }
        }
    }
    fn commit(&mut self) {
        self.lambda_prev = self.lambda;
        self.x_step_start.clone_from(&self.x_prev);
        self.x_prev.copy_from_slice(&self.x);
    }
}
