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

use super::terms::{CellForces, CellRate, Rates, Terms};
use crate::assembly::{Assembler, DofMap, LocalSystem, SharedMut, CONSTRAINED, FIXED};
use crate::contact::{ContactModel, ContactSample, SlipKinematics};
use crate::math::Vec2;
use crate::physics::viscoelastic_steady::{StreamlineError, StreamlineScheme};
use crate::physics::{NodalThetaDerivative, SolidModel, SteadyHistory};
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
    /// Load-step length Δτ of the current step in load-stepping pseudo-time (the static
    /// friction slip is (x − x_prev)/Δτ).
    dtau: f64,
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
    /// Steady rolling at this ω (θ-referential mode), set by the steady driver: the system's
    /// own evaluation then uses the steady rates, v = ω ∂θχ, and the strain-rate damping acts on
    /// the material rate Ė = sym(Fᵀ ∇v_h), v_h the interpolant of the nodal velocities
    /// ω ∂θχ ([`crate::physics::NodalThetaDerivative`]); those velocities depend on nodes
    /// beyond the cell, so this system computes them and assembles with
    /// [`crate::physics::SolidModel::cell_system_steady_viscous`]. `None` in the other modes.
    pub steady_omega: Option<f64>,
    /// The blocks (element lists, cores) of an assembler not built yet
    /// ([`Self::with_contact_deferred`]); `asm` holds no block meanwhile.
    pending_blocks: Option<BlockLists>,
}

/// An assembler's element lists and their cores ([`Assembler::block_lists`]).
type BlockLists = (Vec<crate::assembly::ElementList>, Vec<Option<Vec<u32>>>);

/// The steady mode's strain-rate damping (see [`SolidSystem::enable_steady_viscosity`]): the
/// nodal θ-derivative, each cell's own derivative (the assembled tangent's approximation of
/// it) and, per cell, the derivative of the cell residual with respect to its nodal
/// velocities, from which the rest of the exact tangent is applied matrix-free.
#[derive(Clone, Debug)]
pub struct SteadyViscosity {
    pub nodal: NodalThetaDerivative,
    /// Per cell, its own θ-derivative at its nodes (N × N row-major) at `local_off[c]`,
    /// stored once for the cells that share it (the derivative along the circles is
    /// invariant under rotations: the cells of a ring of a uniform annulus share one).
    local: Vec<f64>,
    local_off: Vec<usize>,
    /// Per cell, ∂r_c/∂v_c (2N × 2N, symmetric: the upper triangle row by row, see
    /// [`packed_at`]) at `av_off[c]`, from the last evaluation with the matrix, in single
    /// precision: it enters the preconditioner's matrix (banded and assembled tangents)
    /// and the matrix-free part of the Newton step, whose relative error 6e-8 is far below
    /// the forcing terms of the inexact Newton steps.
    av: Vec<f32>,
    av_off: Vec<usize>,
    /// Nodal velocities of the current evaluation (full length; reused, not reallocated).
    vel: Vec<f64>,
    /// Scratch for the matrix-free product: a full-length increment and its nodal velocities.
    du: Vec<f64>,
    dv: Vec<f64>,
    /// The coupling beyond the cells assembled into the matrix instead of applied matrix-free
    /// ([`SolidSystem::set_steady_damping_assembled`]): the index of the extended-element
    /// block, and per cell its extended nodes (the cell's, then the other nodes of their
    /// derivative stencils) at `ext_off[c]..ext_off[c + 1]`.
    assembled: Option<(usize, Vec<u32>, Vec<usize>)>,
    /// Banded mode ([`SteadyDampingTangent::Banded`]): the three-point ring differences whose
    /// coupling is in the matrix (`assembled` then holds their extended elements), and the
    /// scratch for their product.
    banded: Option<NodalThetaDerivative>,
    dv3: Vec<f64>,
    /// The coupling block also holds the cells' own matrices (their rows are its rows, their
    /// columns the first of its columns), and block 0 only their residuals: one slot table
    /// and one scatter per cell instead of two. Set with `assembled` when every cell's dofs
    /// are its nodes' displacements.
    cells_in_coupling: bool,
    /// Set when a GMRES solve with the matrix-free coupling did not reach its tolerance.
    pub stalled: bool,
    /// Weight of the cells' own derivative in the matrix-free tangent's assembled part
    /// ([`SolidSystem::set_steady_damping_cell_weight`]).
    cell_weight: f64,
}

impl SteadyViscosity {
    /// The weight α of the cells' own derivative in the assembled tangent: the scene's with
    /// the matrix-free tangent, 1 when the coupling beyond the cells is assembled (banded,
    /// assembled), whose extended elements complete exactly that linearisation.
    fn cell_weight(&self) -> f64 {
        if self.assembled.is_some() {
            1.0
        } else {
            self.cell_weight
        }
    }
}

/// Default of [`SolidSystem::set_steady_damping_cell_weight`] (`[solver] damping_cell_weight`).
pub const DEFAULT_DAMPING_CELL_WEIGHT: f64 = 0.4;

/// How the Newton matrix of the steady damping is formed (see
/// [`SolidSystem::enable_steady_viscosity`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SteadyDampingTangent {
    /// The cells' own sparsity in the matrix, the rest applied matrix-free by GMRES: the
    /// fill and the memory of the undamped problem.
    MatrixFree,
    /// The whole coupling assembled (extended elements, a wider sparsity and more LU fill):
    /// a direct solve of the exact tangent, robust where the GMRES iteration is not (near the
    /// critical speed, extreme stiffness ratios).
    Assembled,
    /// The coupling of three-point ring differences assembled (one node passage beyond the
    /// cells instead of two) and the rest, ω A_c (D − D₃), applied matrix-free: a
    /// preconditioner whose damping differs from the exact one by a factor 1–5/3 at every
    /// wave number along the rings, where the cells' own derivatives miss the grid scale.
    /// Ring meshes only.
    Banded,
}

impl SolidSystem {
    /// Fix the nodes of `fixed_set` (both components, value 0 unless changed in `x`).
    pub fn new(model: SolidModel, fixed_set: &str) -> Self {
        let fixed: Vec<u32> = model.mesh.node_set(fixed_set).to_vec();
        Self::with_fixed_nodes(model, &fixed)
    }

    /// Fix both displacement components of the given nodes (values taken from `x`, initially 0).
    pub fn with_fixed_nodes(model: SolidModel, fixed: &[u32]) -> Self {
        Self::build(model, None, fixed, false)
    }

    /// Solid with contact on the outer facets; the hub set is fixed. Under load control the
    /// road height is a global unknown, initialised to `contact.h`.
    pub fn with_contact(model: SolidModel, contact: ContactModel) -> Self {
        let fixed: Vec<u32> = model.mesh.node_set("hub").to_vec();
        Self::build(model, Some(contact), &fixed, false)
    }

    /// As [`Self::with_contact`], with the assembler (its sparsity, the costliest part of the
    /// set-up) built only by [`Self::finish_assembly`]: for a caller that changes the blocks
    /// first ([`Self::set_steady_damping_tangent`]), so that the pattern is built once.
    /// Nothing may be assembled before [`Self::finish_assembly`].
    pub fn with_contact_deferred(model: SolidModel, contact: ContactModel) -> Self {
        let fixed: Vec<u32> = model.mesh.node_set("hub").to_vec();
        Self::build(model, Some(contact), &fixed, true)
    }

    /// Build the assembler of [`Self::with_contact_deferred`] (no effect once built).
    pub fn finish_assembly(&mut self) {
        if let Some((lists, cores)) = self.pending_blocks.take() {
            self.set_blocks(lists, cores);
        }
    }

    /// The blocks of the assembler, to be changed and handed back to [`Self::set_blocks`]:
    /// moved out of the pending ones (which stay pending, empty until then), or copied from
    /// the built assembler.
    fn take_block_lists(&mut self) -> BlockLists {
        match self.pending_blocks.as_mut() {
            Some(p) => std::mem::take(p),
            None => self.asm.block_lists(),
        }
    }

    /// Rebuild the assembler on these blocks (its parallel setting kept), or replace the
    /// pending ones.
    fn set_blocks(
        &mut self,
        lists: Vec<crate::assembly::ElementList>,
        cores: Vec<Option<Vec<u32>>>,
    ) {
        if let Some(p) = self.pending_blocks.as_mut() {
            *p = (lists, cores);
            return;
        }
        let parallel = self.asm.parallel;
        self.asm = Assembler::with_blocks_cored(&self.dofs, lists, cores);
        self.asm.parallel = parallel;
    }

    fn build(model: SolidModel, contact: Option<ContactModel>, fixed: &[u32], defer: bool) -> Self {
        let n_global = usize::from(contact.as_ref().is_some_and(|c| c.load.is_some()));
        let dofs = DofMap::with_globals(&model.mesh, model.dofs_per_cell(), fixed, n_global);
        let mut blocks = vec![(dofs.cell_dofs.clone(), dofs.cell_offsets.clone())];
        if let Some(c) = &contact {
            blocks.push(c.element_dofs(&model.mesh, &dofs));
        }
        let (asm, pending_blocks) = if defer {
            let cores = vec![None; blocks.len()];
            (Assembler::unbuilt(dofs.n_eq), Some((blocks, cores)))
        } else {
            (Assembler::with_blocks(&dofs, blocks), None)
        };
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
            dtau: 1.0,
            loading: Loading::Spin { omega2: 0.0 },
            lambda: 0.0,
            lambda_prev: 0.0,
            omega2_target: 0.0,
            ref_norms: vec![0.0, 1e-3 * area, h_ref, 0.0],
            facet_visits: (0, 0),
            steady_visc: None,
            steady_history: None,
            steady_omega: None,
            pending_blocks,
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
        // The elastic-slip law uses no slip velocity.
        if !c.friction.is_active() || c.steady_slip.is_some() || c.is_elastic_slip() {
            return;
        }
        if !c.enable_steady_slip(&self.model.mesh) {
            return;
        }
        let elements = c.element_dofs(&self.model.mesh, &self.dofs);
        let (mut lists, cores) = self.take_block_lists();
        lists[1] = elements;
        self.set_blocks(lists, cores);
    }

    /// Back to the facet-wise θ-derivative for the steady friction slip (the default of
    /// [`Self::enable_steady_slip`] undone), as the three-dimensional steady contact takes it:
    /// the contact elements shrink to their facets' nodes and the assembler is rebuilt.
    pub fn disable_steady_slip(&mut self) {
        let Some(c) = &mut self.contact else {
            return;
        };
        if c.steady_slip.take().is_none() {
            return;
        }
        let elements = c.element_dofs(&self.model.mesh, &self.dofs);
        let (mut lists, cores) = self.take_block_lists();
        lists[1] = elements;
        self.set_blocks(lists, cores);
    }

    /// Steady (θ-referential) mode with strain-rate damping: the damping acts on the material
    /// rate Ė = sym(Fᵀ ∇v_h), v_h the interpolant of the nodal velocities
    /// v_a = ω (t_a + (∂θu)_a) ([`NodalThetaDerivative`]: ring differences, or the cell average
    /// on a mesh without rings), as the transient mode does with its nodal velocities. The
    /// residual is exact. The assembled tangent linearises each cell's velocities with the
    /// cell's own θ-derivative, which keeps the sparsity (and the LU fill) of the undamped
    /// problem; the difference to the exact tangent, Σ_c A_c ω (D − D_c) δu with
    /// A_c = ∂r_c/∂v_c, is applied matrix-free ([`NonlinearSystem::tangent_correction`]), so
    /// Newton takes the exact step by GMRES preconditioned with the assembled factorization.
    /// Active in [`NonlinearSystem::evaluate`] and [`Self::hub_reaction`] while
    /// `steady_omega` is set. Returns `false` (and leaves the damping off) when a cell
    /// map is degenerate; no effect without damping.
    pub fn enable_steady_viscosity(&mut self) -> bool {
        if self.steady_visc.is_some() || self.model.strain_rate_damping <= 0.0 {
            return true;
        }
        let Some(nodal) = NodalThetaDerivative::new(&self.model) else {
            return false;
        };
        let mesh = &self.model.mesh;
        let (mut local, mut local_off, mut av_off) = (Vec::new(), Vec::new(), vec![0]);
        // Cells whose derivatives agree to 1e-12 of their largest entry share one copy: the
        // kept copies' rounded entries in `keys` (at the copy's offset), found by their hash.
        let mut seen: std::collections::HashMap<u64, Vec<usize>> = Default::default();
        let (mut key, mut keys) = (Vec::<i64>::new(), Vec::<i64>::new());
        for c in 0..mesh.n_cells() {
            let Some(d) = self.model.cell_theta_derivative(c) else {
                return false;
            };
            let scale = d
                .iter()
                .fold(0.0f64, |m, v| m.max(v.abs()))
                .max(f64::MIN_POSITIVE);
            key.clear();
            key.extend(d.iter().map(|v| (v / scale * 1e12).round() as i64));
            // FNV-1a over the rounded entries.
            let hash = key.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &v| {
                (h ^ v as u64).wrapping_mul(0x0100_0000_01b3)
            });
            let starts = seen.entry(hash).or_default();
            let start = match starts
                .iter()
                .find(|&&s| keys.get(s..s + key.len()) == Some(&key[..]))
            {
                Some(&s) => s,
                None => {
                    let s = local.len();
                    local.extend_from_slice(&d);
                    keys.extend_from_slice(&key);
                    starts.push(s);
                    s
                }
            };
            local_off.push(start);
            let nu = 2 * mesh.cell_nodes(c).len();
            av_off.push(av_off[c] + nu * (nu + 1) / 2);
        }
        local.shrink_to_fit();
        let n_full = self.x.len();
        self.steady_visc = Some(SteadyViscosity {
            nodal,
            local,
            local_off,
            av: vec![0.0f32; av_off[mesh.n_cells()]],
            av_off,
            vel: vec![0.0; n_full],
            du: vec![0.0; n_full],
            dv: vec![0.0; n_full],
            assembled: None,
            banded: None,
            dv3: vec![0.0; n_full],
            cells_in_coupling: false,
            stalled: false,
            cell_weight: DEFAULT_DAMPING_CELL_WEIGHT,
        });
        true
    }

    /// The Newton matrix of the steady damping (`None` when that damping is not active).
    pub fn steady_damping_tangent(&self) -> Option<SteadyDampingTangent> {
        let sv = self.steady_visc.as_ref()?;
        (self.model.strain_rate_damping > 0.0).then_some(
            match (sv.assembled.is_some(), sv.banded.is_some()) {
                (true, true) => SteadyDampingTangent::Banded,
                (true, false) => SteadyDampingTangent::Assembled,
                _ => SteadyDampingTangent::MatrixFree,
            },
        )
    }

    /// Weight α in (0, 1] of each cell's own θ-derivative in the assembled part of the
    /// matrix-free damping tangent (default [`DEFAULT_DAMPING_CELL_WEIGHT`]): the matrix
    /// linearises the velocities as α ω D_c, and GMRES applies the rest, ω (D − α D_c), so
    /// the Newton step is the exact one for every α; only the preconditioner changes. The
    /// cells' own derivatives are one-sided at the cell edges and respond at the grid scale,
    /// where the nodal differences of the residual vanish, so the full weight over-damps the
    /// preconditioner's short waves. Measured, GMRES products of a whole steady solve with
    /// α = 1 against 0.4 (`tread run … --mode steady -v --set solver.damping_cell_weight=W`):
    /// default scene 50 → 36 (16k DOFs), 88 → 67 (66k), 173 → 127 (262k, 23.3 s → 17.9 s);
    /// frictionless rolling 67 → 52, braking 102 → 95, free rolling 97 → 93 (37k); the
    /// products are flat for α in 0.2–0.5. With η ω / G = 30 % (η = 3, ω = 20, 66k) α = 1
    /// and 0.7 stall and need a recovery (347 s and 61 s) where 0.2–0.5 solve directly in
    /// 16–17 s. No effect without damping or with another tangent.
    pub fn set_steady_damping_cell_weight(&mut self, alpha: f64) {
        if let Some(sv) = self.steady_visc.as_mut() {
            if alpha.is_finite() && alpha > 0.0 && alpha <= 1.0 {
                sv.cell_weight = alpha;
            }
        }
    }

    /// Switch the steady damping's Newton matrix (no effect without that damping). The
    /// assembler is rebuilt (a new sparsity), so solvers made for the old one must be made
    /// again.
    pub fn set_steady_damping_tangent(&mut self, mode: SteadyDampingTangent) {
        let Some(current) = self.steady_damping_tangent() else {
            return;
        };
        if current == mode {
            return;
        }
        let banded = match mode {
            SteadyDampingTangent::Banded => {
                match NodalThetaDerivative::three_point(&self.model.mesh) {
                    Some(d) => Some(d),
                    None => return, // no rings: stay as it is
                }
            }
            _ => None,
        };
        let (mut lists, mut cores) = self.take_block_lists();
        let Some(sv) = self.steady_visc.as_mut() else {
            // (Not reached: `current` is set only with the damping on.)
            self.set_blocks(lists, cores);
            return;
        };
        if let Some((block, _, _)) = sv.assembled.take() {
            lists.truncate(block);
            cores.truncate(block);
        }
        // Block 0 holds the cells' matrices unless the coupling block takes them (below).
        cores[0] = None;
        sv.cells_in_coupling = false;
        sv.banded = banded;
        if mode != SteadyDampingTangent::MatrixFree {
            let stencil = sv.banded.as_ref().unwrap_or(&sv.nodal);
            let mesh = &self.model.mesh;
            let (mut ext, mut ext_off) = (Vec::new(), vec![0]);
            let (mut list, mut off, mut core) = (Vec::new(), vec![0], Vec::new());
            for c in 0..mesh.n_cells() {
                let start = ext.len();
                let nodes = mesh.cell_nodes(c);
                // The cell's own dofs first: the coupling has rows there only.
                core.push(2 * nodes.len() as u32);
                ext.extend_from_slice(nodes);
                for &a in nodes {
                    let a = a as usize;
                    for &b in &stencil.idx[stencil.ptr[a]..stencil.ptr[a + 1]] {
                        if !ext[start..].contains(&b) {
                            ext.push(b);
                        }
                    }
                }
                ext_off.push(ext.len());
                for &n in &ext[start..] {
                    list.push(2 * n);
                    list.push(2 * n + 1);
                }
                off.push(list.len());
            }
            // A cell's coupling element starts with the cell's own dofs: when those are all
            // of the cell's dofs (no cell-owned unknowns), the coupling block holds the
            // cells' matrices and block 0 keeps their residuals only (an empty core).
            let (cl, co) = &lists[0];
            let same = (0..mesh.n_cells())
                .all(|c| cl[co[c]..co[c + 1]] == list[off[c]..off[c] + core[c] as usize]);
            if same {
                cores[0] = Some(vec![0; mesh.n_cells()]);
                sv.cells_in_coupling = true;
            }
            sv.assembled = Some((lists.len(), ext, ext_off));
            lists.push((list, off));
            cores.push(Some(core));
        }
        self.set_blocks(lists, cores);
    }

    /// Add the steady damping's coupling beyond the cells to the matrix (assembled mode):
    /// per cell, A_c ω (D − D_c) on its extended element, from the A_c of the cell assembly
    /// just made (when the coupling block does not hold the cells' matrices: then
    /// [`Self::assemble`] adds it with them).
    fn add_steady_damping_coupling(&mut self) {
        let (Some(sv), Some(om)) = (self.steady_visc.as_ref(), self.steady_omega) else {
            return;
        };
        let Some((block, ext, ext_off)) = &sv.assembled else {
            return;
        };
        if self.model.strain_rate_damping <= 0.0 || sv.cells_in_coupling {
            return;
        }
        let mesh = &self.model.mesh;
        let stencil = sv.banded.as_ref().unwrap_or(&sv.nodal);
        self.asm
            .add_block_large(*block, &self.dofs, true, |c, _r, k| {
                let nodes = mesh.cell_nodes(c);
                let nn = nodes.len();
                let ex = &ext[ext_off[c]..ext_off[c + 1]];
                let d = &sv.local[sv.local_off[c]..sv.local_off[c] + nn * nn];
                let a = &sv.av[sv.av_off[c]..sv.av_off[c + 1]];
                let at = |r: usize, col: usize| f64::from(a[packed_at(2 * nn, r, col)]);
                damping_coupling_rows(nodes, ex, Some(d), stencil, om, at, k);
            });
    }

    /// Nodal velocities ω ∂θχ of the steady mode's damping at the current state (full-length
    /// vector), or `None` when that damping is not active.
    fn steady_velocities(&self) -> Option<(Vec<f64>, f64)> {
        let (sv, om) = (self.steady_visc.as_ref()?, self.steady_omega?);
        if self.model.strain_rate_damping <= 0.0 {
            return None;
        }
        let mut vel = vec![0.0; self.x.len()];
        sv.nodal.velocities(&self.model.mesh, &self.x, om, &mut vel);
        Some((vel, om))
    }

    /// Set the load-step length Δτ with which the static friction slip (x − x_prev)/Δτ is
    /// measured (normally set by [`LoadedSystem::set_load`]).
    pub fn set_load_step_length(&mut self, dtau: f64) {
        self.dtau = dtau.max(f64::MIN_POSITIVE);
    }

    /// The rates of the system's own evaluation ([`NonlinearSystem::evaluate`]): steady while
    /// `steady_omega` is set, otherwise load stepping.
    pub fn own_rates(&self) -> Rates<'static> {
        if self.steady_omega.is_some() {
            Rates::Steady
        } else {
            Rates::Static
        }
    }

    /// The one assembly of residual and (with `with_matrix`) tangent that every analysis
    /// uses: the cells' forces at the driver's rates, scaled, plus inertia (see
    /// [`super::terms`]), the steady damping's coupling beyond the cells (assembled mode),
    /// then the contact facets at the same rates. Returns whether the state is admissible
    /// (no J ≤ 0) and the residual finite.
    pub fn assemble(&mut self, terms: &Terms, with_matrix: bool) -> bool {
        debug_assert!(
            self.pending_blocks.is_none(),
            "the assembler is not built yet"
        );
        // Hanging-node values follow their masters: a state set from outside (an interpolated
        // start) may not, and Newton's first step would then be taken from a state its update
        // does not continue. Idempotent on a consistent state.
        if self.dofs.has_constraints() {
            self.dofs.apply_constraints(&mut self.x);
        }
        let steady = matches!(terms.rates, Rates::Steady);
        if steady {
            self.sync_steady_history();
        }
        let ok = {
            let xs: &[f64] = match terms.rates {
                Rates::Dynamic { x, .. } => x,
                _ => &self.x,
            };
            let (model, dofs, asm) = (&self.model, &self.dofs, &mut self.asm);
            let mut av_out = None;
            // The coupling block that holds the cells' matrices too (with the matrix only),
            // and the steady damping's coupling to add there.
            let mut cell_block: Option<(usize, &[u32], &[usize])> = None;
            let mut coupling: Option<(&NodalThetaDerivative, f64)> = None;
            let mut rate = match terms.rates {
                Rates::Dynamic { v, kv, .. } => CellRate::Dynamic { v, kv },
                _ => CellRate::None,
            };
            if let Some(sv) = self.steady_visc.as_mut() {
                let alpha = sv.cell_weight();
                let SteadyViscosity {
                    nodal,
                    local,
                    local_off,
                    av,
                    av_off,
                    vel,
                    assembled,
                    banded,
                    cells_in_coupling,
                    ..
                } = sv;
                if let (true, true, Some((b, ext, ext_off))) =
                    (with_matrix, *cells_in_coupling, assembled.as_ref())
                {
                    cell_block = Some((*b, ext, ext_off));
                }
                if let (Rates::Steady, Some(omega)) = (terms.rates, self.steady_omega) {
                    if model.strain_rate_damping > 0.0 {
                        nodal.velocities(&model.mesh, xs, omega, vel);
                        av_out = Some((SharedMut::new(av), &*av_off));
                        // With the cells in the coupling block, the coupling takes the whole
                        // linearisation of the velocities (ω D₃ or ω D over the extended
                        // nodes) and the cells' matrices leave out their own derivative's.
                        rate = CellRate::Steady {
                            vel: &*vel,
                            omega: if cell_block.is_some() {
                                0.0
                            } else {
                                alpha * omega
                            },
                            local: &*local,
                            local_off: &*local_off,
                        };
                        let stencil = banded.as_ref().unwrap_or(&*nodal);
                        coupling = Some((stencil, omega));
                    }
                }
            }
            let cells = CellForces {
                model,
                dofs,
                x: xs,
                rate,
                force_scale: terms.force_scale,
                inertia: terms.inertia,
            };
            // One cell: `loc` (and ∂r/∂v into the damping's store, whose symmetric matrix
            // keeps its upper triangle, when the steady damping is on).
            // `a`: where ∂r/∂v goes (`None`: a local one, made only with the damping on).
            let eval = |c: usize, loc: &mut LocalSystem, a: Option<&mut [f64; 324]>| {
                match &av_out {
                    Some((av, av_off)) if with_matrix => {
                        let mut own = None;
                        let a = match a {
                            Some(a) => a,
                            None => own.insert([0.0; 324]),
                        };
                        cells.eval(c, loc, true, Some(&mut *a));
                        let nu = 2 * model.mesh.cell_nodes(c).len();
                        let mut i = av_off[c];
                        for r in 0..nu {
                            for v in &a[r * nu + r..(r + 1) * nu] {
                                // SAFETY: cell c alone writes its own range av_off[c]..av_off[c + 1].
                                unsafe { av.set(i, *v as f32) };
                                i += 1;
                            }
                        }
                    }
                    _ => cells.eval(c, loc, with_matrix, None),
                }
                if let Some(hook) = terms.cell_hook {
                    hook(model, c, loc);
                }
            };
            model.reset_admissible();
            asm.zero(with_matrix);
            match cell_block {
                Some((cb, ext, ext_off)) => {
                    // The cells' rows of the coupling block: the cell's matrix in its first
                    // columns, then the damping's coupling over the extended nodes.
                    asm.add_block_large(cb, dofs, true, |c, r, k| {
                        let nodes = model.mesh.cell_nodes(c);
                        let nu = 2 * nodes.len();
                        let ex = &ext[ext_off[c]..ext_off[c + 1]];
                        let nd = 2 * ex.len();
                        let mut loc = LocalSystem::new(nu);
                        let mut a = [0.0; 324];
                        eval(c, &mut loc, Some(&mut a));
                        r[..nu].copy_from_slice(&loc.r[..nu]);
                        for row in 0..nu {
                            k[row * nd..row * nd + nu]
                                .copy_from_slice(&loc.k[row * nu..(row + 1) * nu]);
                        }
                        if let Some((stencil, om)) = coupling {
                            let at = |r: usize, col: usize| a[r * nu + col];
                            damping_coupling_rows(nodes, ex, None, stencil, om, at, k);
                        }
                    });
                }
                None => asm.add_block(0, dofs, with_matrix, |c, loc| eval(c, loc, None)),
            }
            model.admissible()
        };
        if with_matrix && steady {
            self.add_steady_damping_coupling();
        }
        if let (Some(c), Rates::Steady) = (self.contact.as_mut(), terms.rates) {
            let omega = self.steady_omega.unwrap_or(0.0);
            c.prepare_steady(
                &self.model.mesh,
                &self.dofs,
                &self.x,
                omega,
                terms.force_scale,
            );
        }
        if let Some(c) = &self.contact {
            let xs: &[f64] = match terms.rates {
                Rates::Dynamic { x, .. } => x,
                _ => &self.x,
            };
            let kin = match terms.rates {
                Rates::Static => SlipKinematics::Static {
                    x_prev: &self.x_prev,
                    dtau: self.dtau,
                },
                Rates::Steady => SlipKinematics::Steady {
                    omega: self.steady_omega.unwrap_or(0.0),
                },
                Rates::Dynamic { v, kv, .. } => SlipKinematics::Dynamic { v, kx: 1.0, kv },
            };
            c.reset_visited();
            let (mesh, dofs, fs) = (&self.model.mesh, &self.dofs, terms.force_scale);
            self.asm.add_block(1, dofs, with_matrix, |e, loc| {
                c.kernel(mesh, dofs, xs, &kin, e, loc, with_matrix);
                if fs != 1.0 {
                    let nd = loc.nd;
                    loc.r[..nd].iter_mut().for_each(|v| *v *= fs);
                    if with_matrix {
                        loc.k[..nd * nd].iter_mut().for_each(|v| *v *= fs);
                    }
                }
            });
            self.facet_visits.0 += c.visited_facets();
            self.facet_visits.1 += 1;
        }
        ok && self.asm.residual.iter().all(|r| r.is_finite())
    }

    /// `out += (K_exact − K_assembled) v` of the steady damping: Σ_c A_c ω (D δu − D_c δu_c)
    /// (see [`Self::enable_steady_viscosity`]).
    fn steady_viscosity_correction(&mut self, v: &[f64], out: &mut [f64]) {
        let (Some(sv), Some(om)) = (self.steady_visc.as_mut(), self.steady_omega) else {
            return;
        };
        if self.model.strain_rate_damping <= 0.0 || (sv.assembled.is_some() && sv.banded.is_none())
        {
            return;
        }
        sv.du.fill(0.0);
        self.dofs.scatter_free(v, &mut sv.du);
        sv.nodal.apply(&sv.du, om, &mut sv.dv);
        if let Some(d3) = &sv.banded {
            // Banded: the matrix holds ω D₃; the rest is ω (D − D₃) at the cell's nodes.
            d3.apply(&sv.du, om, &mut sv.dv3);
            for (d, d3) in sv.dv.iter_mut().zip(&sv.dv3) {
                *d -= d3;
            }
        }
        let banded = sv.banded.is_some();
        let alpha = sv.cell_weight();
        let mesh = &self.model.mesh;
        for c in 0..mesh.n_cells() {
            let nodes = mesh.cell_nodes(c);
            let (nn, cd) = (nodes.len(), self.dofs.cell(c));
            let nu = 2 * nn;
            let d = &sv.local[sv.local_off[c]..sv.local_off[c] + nn * nn];
            let a = &sv.av[sv.av_off[c]..sv.av_off[c + 1]];
            let mut diff = [0.0; 18];
            for m in 0..nn {
                for i in 0..2 {
                    let loc: f64 = if banded {
                        0.0
                    } else {
                        (0..nn)
                            .map(|b| d[m * nn + b] * sv.du[cd[2 * b + i] as usize])
                            .sum()
                    };
                    diff[2 * m + i] = sv.dv[cd[2 * m + i] as usize] - alpha * om * loc;
                }
            }
            // y = A diff from the upper triangle of the symmetric A.
            let mut y = [0.0; 18];
            let mut k = 0;
            for r in 0..nu {
                let (row, dr) = (&a[k..k + nu - r], diff[r]);
                let mut yr = f64::from(row[0]) * dr;
                for ((&ars, ys), &ds) in
                    row[1..].iter().zip(&mut y[r + 1..nu]).zip(&diff[r + 1..nu])
                {
                    let ars = f64::from(ars);
                    yr += ars * ds;
                    *ys += ars * dr;
                }
                y[r] += yr;
                k += nu - r;
            }
            for (r, &y) in y[..nu].iter().enumerate() {
                let e = self.dofs.eq[cd[r] as usize];
                if e == FIXED {
                    continue;
                }
                if e < CONSTRAINED {
                    out[e as usize] += y;
                } else {
                    // A hanging node's row goes to its free masters with their weights (Cᵀ).
                    for &(m, w) in self.dofs.expansion(cd[r]).unwrap_or(&[]) {
                        let em = self.dofs.eq[m as usize];
                        if em < CONSTRAINED {
                            out[em as usize] += w * y;
                        }
                    }
                }
            }
        }
    }

    /// Steady (θ-referential) mode with a viscoelastic material: before every evaluation the
    /// history of the quadrature points is replaced by the steady states along the
    /// streamlines at the current state and ω ([`SteadyHistory`], discretised by `scheme`),
    /// and Newton takes the exact step with the streamline coupling applied matrix-free. No
    /// effect for an elastic material; an error when the mesh cannot carry the scheme.
    pub fn enable_steady_viscoelastic(
        &mut self,
        scheme: StreamlineScheme,
    ) -> Result<(), StreamlineError> {
        if self.model.viscoelastic.is_none() || self.steady_history.is_some() {
            return Ok(());
        }
        self.steady_history = Some(SteadyHistory::new(&self.model, scheme)?);
        Ok(())
    }

    /// Bring the steady history in line with the current state (see
    /// [`Self::enable_steady_viscoelastic`]).
    fn sync_steady_history(&mut self) {
        if let (Some(sh), Some(om)) = (self.steady_history.as_mut(), self.steady_omega) {
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
    /// The contact tractions on the body at the contact rule's points of every contact facet
    /// (for the explicit error estimator's boundary residual); `None` without contact.
    pub fn contact_tractions(&self) -> Option<crate::physics::estimate::BoundaryTractions> {
        let c = self.contact.as_ref()?;
        let (points, weights) = c.rule.points();
        let samples = self.contact_samples();
        if samples.len() != c.facets.len() * points.len() {
            return None;
        }
        Some(crate::physics::estimate::BoundaryTractions {
            facets: c.facets.clone(),
            points,
            weights,
            traction: samples.iter().map(|s| Vec2::new(s.t_t, s.t_n)).collect(),
        })
    }

    pub fn contact_samples(&self) -> Vec<ContactSample> {
        match &self.contact {
            Some(c) => {
                let kin = match self.own_rates() {
                    Rates::Steady => SlipKinematics::Steady {
                        omega: self.steady_omega.unwrap_or(0.0),
                    },
                    _ => SlipKinematics::Static {
                        x_prev: if self.x_step_start.len() == self.x.len() {
                            &self.x_step_start
                        } else {
                            &self.x_prev
                        },
                        dtau: self.dtau,
                    },
                };
                c.samples(&self.model.mesh, &self.dofs, &self.x, &kin)
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
        let steady_vel = match self.own_rates() {
            Rates::Steady => self.steady_velocities(),
            _ => None,
        };
        // The steady damping forces are part of what the hub transmits.
        let rate = match (&steady_vel, &self.steady_visc) {
            (Some((vel, omega)), Some(sv)) => CellRate::Steady {
                vel,
                omega: *omega,
                local: &sv.local,
                local_off: &sv.local_off,
            },
            _ => CellRate::None,
        };
        self.hub_sum(&self.x, rate, 1.0, None)
    }

    /// Force and moment that the hub exerts on the body under the given terms, evaluated at
    /// the configuration of the rates (`Rates::Dynamic`'s `x`, otherwise the state): the hub
    /// rows of the cell forces (contact acts away from the hub). For the steady rates use
    /// [`Self::hub_reaction`].
    pub fn hub_reaction_with(&self, terms: &Terms) -> (Vec2, f64) {
        let (x, rate): (&[f64], _) = match terms.rates {
            Rates::Dynamic { x, v, kv } => (x, CellRate::Dynamic { v, kv }),
            _ => (&self.x, CellRate::None),
        };
        self.hub_sum(x, rate, terms.force_scale, terms.inertia)
    }

    fn hub_sum(
        &self,
        x: &[f64],
        rate: CellRate,
        force_scale: f64,
        inertia: Option<super::terms::Inertia>,
    ) -> (Vec2, f64) {
        let mesh = &self.model.mesh;
        let mut is_hub = vec![false; mesh.n_nodes()];
        for &n in mesh.node_set("hub") {
            is_hub[n as usize] = true;
        }
        let cells = CellForces {
            model: &self.model,
            dofs: &self.dofs,
            x,
            rate,
            force_scale,
            inertia,
        };
        let mut force = Vec2::zeros();
        let mut moment = 0.0;
        let mut loc = Box::new(LocalSystem::new(0));
        // A constrained (hanging-node) dof's force goes to its masters with their weights, as
        // in the assembly ([`DofMap::expansion`]): to the hub where a master is a fixed hub dof.
        let is_hub_dof = |d: usize| is_hub[d / 2] && self.dofs.eq[d] == crate::assembly::FIXED;
        let touches = |n: u32| {
            (0..2u32).any(|i| {
                let d = 2 * n + i;
                is_hub_dof(d as usize)
                    || self
                        .dofs
                        .expansion(d)
                        .is_some_and(|e| e.iter().any(|&(m, _)| is_hub_dof(m as usize)))
            })
        };
        let mut add = |m: usize, f: f64| {
            let node = m / 2;
            let xp = mesh.nodes[node] + Vec2::new(x[2 * node], x[2 * node + 1]);
            let fv = if m.is_multiple_of(2) {
                Vec2::new(f, 0.0)
            } else {
                Vec2::new(0.0, f)
            };
            force += fv;
            moment += xp[0] * fv[1] - xp[1] * fv[0];
        };
        for c in 0..mesh.n_cells() {
            let nodes = mesh.cell_nodes(c);
            if !nodes.iter().any(|&n| touches(n)) {
                continue;
            }
            loc.clear(self.dofs.cell(c).len());
            cells.eval(c, &mut loc, false, None);
            for (a, &n) in nodes.iter().enumerate() {
                for i in 0..2 {
                    let d = 2 * n as usize + i;
                    let r = loc.r[2 * a + i];
                    if is_hub_dof(d) {
                        add(d, r);
                    } else if let Some(exp) = self.dofs.expansion(d as u32) {
                        for &(m, w) in exp {
                            if is_hub_dof(m as usize) {
                                add(m as usize, w * r);
                            }
                        }
                    }
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
            if e >= CONSTRAINED {
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
        debug_assert!(
            self.pending_blocks.is_none(),
            "the assembler is not built yet"
        );
        (&self.asm.col_ptr, &self.asm.row_idx)
    }
    fn evaluate(&mut self, with_matrix: bool) -> bool {
        let rates = self.own_rates();
        self.assemble(&Terms::forces(rates), with_matrix)
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
        self.steady_omega.is_some()
            && (self.steady_history.is_some()
                || self.contact.as_ref().is_some_and(|c| c.is_elastic_slip())
                || matches!(
                    self.steady_damping_tangent(),
                    Some(SteadyDampingTangent::MatrixFree | SteadyDampingTangent::Banded)
                ))
    }
    fn tangent_correction_stalled(&mut self) {
        if let Some(sv) = self.steady_visc.as_mut() {
            sv.stalled = true;
        }
    }
    fn tangent_correction(&mut self, v: &[f64], out: &mut [f64]) {
        self.steady_viscosity_correction(v, out);
        if let (Some(sh), Some(om)) = (self.steady_history.as_mut(), self.steady_omega) {
            sh.apply_correction(&self.model, &self.dofs, om, v, out);
        }
        if let (Some(m), Some(_)) = (
            self.contact.as_ref().and_then(|c| c.elastic.as_ref()),
            self.steady_omega,
        ) {
            m.apply_correction(&self.dofs, v, out);
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
        // Steady rolling measures velocities by ω ∂θχ, not in the load-stepping time. A
        // restore to the converged λ (λ = λ_prev) keeps the last step's Δτ, with which the
        // outputs evaluate that step's slip.
        if self.contact.is_some()
            && self.steady_omega.is_none()
            && (lambda > self.lambda_prev || self.lambda_prev == 0.0)
        {
            self.dtau = (lambda - self.lambda_prev).max(f64::MIN_POSITIVE);
        }
    }
    fn commit(&mut self) {
        self.lambda_prev = self.lambda;
        self.x_step_start.clone_from(&self.x_prev);
        self.x_prev.copy_from_slice(&self.x);
    }
}

/// The steady damping's coupling of one cell beyond its own derivative, added to the
/// cell's rows of its extended element matrix `k` (row-major, its cell's 2N rows, 2 × the
/// extended nodes `ex` columns): K[r, (e, i)] += Σ_m A[r, (m, i)] W[m, e], with
/// W = ω (D − D_c) (or ω (D₃ − D_c) with the ring stencil `stencil` = D₃) over the extended
/// nodes, `d` the cell's own derivative D_c (N × N; `None`: W = ω D, the whole
/// linearisation of the velocities, when the cell's matrix left it out) and
/// `a(r, col)` = ∂r_c/∂v_c.
fn damping_coupling_rows(
    nodes: &[u32],
    ex: &[u32],
    d: Option<&[f64]>,
    stencil: &NodalThetaDerivative,
    om: f64,
    a: impl Fn(usize, usize) -> f64,
    k: &mut [f64],
) {
    let nn = nodes.len();
    let nu = 2 * nn;
    let nd = 2 * ex.len();
    // W by its nonzeros (m, e, W[m, e]): the stencils' few per node, and with `d` the cell's
    // own derivative subtracted over the cell's nodes (the first of the extended nodes). On
    // the stack for the usual sizes (a Q2 cell: 9 nodes of 5-point stencils and 9 × 9).
    const MAX_W: usize = 9 * 5 + 81;
    let mut stack = [(0usize, 0usize, 0.0f64); MAX_W];
    let mut heap = Vec::new();
    let mut len = 0;
    let mut push = |entry: (usize, usize, f64)| {
        if len < MAX_W {
            stack[len] = entry;
        } else {
            if heap.is_empty() {
                heap.extend_from_slice(&stack);
            }
            heap.push(entry);
        }
        len += 1;
    };
    for (m, &node) in nodes.iter().enumerate() {
        let node = node as usize;
        for p in stencil.ptr[node]..stencil.ptr[node + 1] {
            if let Some(e) = ex.iter().position(|&q| q == stencil.idx[p]) {
                push((m, e, om * stencil.w[p]));
            }
        }
        if let Some(d) = d {
            for b in 0..nn {
                push((m, b, -om * d[m * nn + b]));
            }
        }
    }
    let entries = if len <= MAX_W {
        &stack[..len]
    } else {
        &heap[..]
    };
    // K[r, (e, i)] += A[r, (m, i)] W[m, e] over the cell's rows (its core).
    for &(m, e, w) in entries {
        for r in 0..nu {
            let kr = &mut k[r * nd + 2 * e..r * nd + 2 * e + 2];
            kr[0] += a(r, 2 * m) * w;
            kr[1] += a(r, 2 * m + 1) * w;
        }
    }
}

/// Index of entry (r, c) of a symmetric n × n matrix kept as its upper triangle, row by row
/// (row r holds columns r..n, after Σ_{i<r} (n − i) = r n − r (r − 1)/2 entries).
#[inline]
fn packed_at(n: usize, r: usize, c: usize) -> usize {
    let (r, c) = if r <= c { (r, c) } else { (c, r) };
    r * n - r * r.saturating_sub(1) / 2 + (c - r)
}

#[cfg(test)]
mod packed_tests {
    use super::packed_at;

    #[test]
    fn packed_upper_triangle_indices_run_row_by_row() {
        for n in [1, 2, 5, 18] {
            let mut k = 0;
            for r in 0..n {
                for c in r..n {
                    assert_eq!(packed_at(n, r, c), k, "n {n}, ({r}, {c})");
                    assert_eq!(packed_at(n, c, r), k, "n {n}, ({c}, {r})");
                    k += 1;
                }
            }
            assert_eq!(k, n * (n + 1) / 2);
        }
    }
}
