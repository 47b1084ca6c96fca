//! The three-dimensional solid as a nonlinear system for the solvers: the state, the dof map,
//! the assembler and the coefficients of the analysis, with load stepping in ω² (spinning) or
//! in the body-force factor.
//!
//! The residual is that of [`super::kernel`] summed over the cells (assembled in parallel by
//! [`Assembler::add_block_large`]); the coefficients at load factor λ are λ times the target's
//! ([`Solid3DSystem::set_target`]), so a spinning solve steps ω² from 0 as the plane-strain one
//! does.
//!
//! Contact with the road (the plane x2 = −H) on the tread facets, in the load-stepping
//! pseudo-time of [`super::system`]'s static analysis:
//! * displacement control ([`Solid3DSystem::with_contact`]): H = h_touch − λ · disp;
//! * load control ([`Solid3DSystem::with_contact_load`]): H is the last global unknown (field 2,
//!   "H") with the equation R_H = λ · load − ∫ t_n dA0 = 0, `load` the downward force the hub
//!   pushes the body onto the road with (a total force, not per width), as the plane-strain
//!   program's R_H = P − ∫ t_n ds0; frictionless, the tangent stays symmetric (the Hessian of
//!   W + Φ_c(δ) + λ · load · H). The load enters the residual once, through the first contact
//!   facet; the floor of the H equation's convergence reference is |load|.

use super::kernel::{Coefficients, Inadmissible};
use super::solid3d::Solid3D;
use super::steady_history3d::SteadyHistory3D;
use super::steady_visc3d::{SteadyViscosity3D, MAX_DAMPING_DOFS};
use super::terms::Inertia;
use crate::assembly::{Assembler, DofMap, CONSTRAINED, FIXED};
use crate::contact::facet3d::{
    CellMotion, Contact3DError, ContactSample3D, ContactSurface3D, ContactTotals3D, Kinematics3D,
    MAX_ELEMENT_DOFS,
};
use crate::solver::stepping::LoadedSystem;
use crate::solver::NonlinearSystem;
use std::sync::atomic::{AtomicBool, Ordering};

/// The 3D solid, its state and what the analysis supplies.
pub struct Solid3DSystem {
    pub solid: Solid3D,
    pub dofs: DofMap,
    pub asm: Assembler,
    /// Full state: displacements, cell pressures, global unknowns.
    pub x: Vec<f64>,
    /// Coefficients of the current evaluation.
    pub coefficients: Coefficients,
    /// Coefficients at load factor 1.
    target: Coefficients,
    ref_norms: Vec<f64>,
    /// Why the last evaluation failed, if it did.
    inadmissible: Option<Inadmissible>,
    /// Contact with the road (block 1 of the assembler: the cells of the contact facets).
    pub contact: Option<RoadContact3D>,
    /// Strain-rate damping η of the transient dynamics (S_v = η Ė on the Green-strain rate,
    /// [`super::kernel::viscous_cell`]); 0: none.
    pub strain_rate_damping: f64,
    /// The steady mode's strain-rate damping: the cells' ring stencils and the assembler
    /// block of their damping elements ([`Self::enable_steady_viscosity`]).
    steady_visc: Option<(SteadyViscosity3D, usize)>,
    /// The steady mode's viscoelastic history along the rings of quadrature points
    /// ([`Self::enable_steady_history`]).
    steady_history: Option<SteadyHistory3D>,
}

/// The road under displacement control (H = `h_touch` − λ · `disp`) or load control (H the
/// global unknown at `h_dof`, the equation λ · `load` − ∫ t_n dA0 = 0), and the state of the
/// load-stepping pseudo-time the friction slip is measured in.
pub struct RoadContact3D {
    pub surface: ContactSurface3D,
    /// Road height of first touch (the outer radius): the penetration is h_touch − H.
    pub h_touch: f64,
    pub disp: f64,
    /// Downward hub load at λ = 1 under load control.
    pub load: Option<f64>,
    /// Full index of the road height H under load control.
    pub h_dof: Option<usize>,
    /// Current load factor.
    pub lambda: f64,
    /// Full state at the start of the step and the step's pseudo-time length.
    x_prev: Vec<f64>,
    lambda_prev: f64,
    dtau: f64,
    /// The last committed step, when no step has started since: its start and length (the
    /// slip of [`Solid3DSystem::contact_samples`] is measured over it).
    committed: Option<(Vec<f64>, f64)>,
    /// Resultants of the last evaluation.
    pub totals: ContactTotals3D,
    /// Steady rolling at this ω (rad/s): the contact velocity is v = ω ∂θχ
    /// ([`Kinematics3D::Steady`]) instead of the load-stepping rate, and the load factor
    /// moves only the road (the coefficients stay at the target's).
    pub steady_omega: Option<f64>,
    /// Steady rolling: the road speed v0 and the slip angle α (radians); the road velocity in
    /// its plane is V = v0 (cos α, −sin α) ([`road_velocity_3d`]).
    pub v0: f64,
    pub slip_angle: f64,
}

/// One evaluation of the transient (Lagrangian) dynamics: the forces at the configuration `x`
/// with the velocity field `v` (full vectors; a unit change of the unknown moves `v` by `kv`),
/// scaled by `force_scale`, plus the inertia rows.
#[derive(Clone, Copy, Debug)]
pub struct Dynamic3D<'a> {
    pub x: &'a [f64],
    pub v: &'a [f64],
    pub kv: f64,
    pub force_scale: f64,
    pub inertia: Inertia<'a>,
}

impl Dynamic3D<'_> {
    /// Scale the cell's static forces (and tangent) by the force scale and add its inertia rows
    /// M a (and c_a M); `r`, `k` in the cell's dof order (3·a + i first).
    fn finish_cell(&self, dofs: &DofMap, nodes: &[u32], c: usize, r: &mut [f64], k: &mut [f64]) {
        let fs = self.force_scale;
        if fs != 1.0 {
            r.iter_mut().for_each(|v| *v *= fs);
            k.iter_mut().for_each(|v| *v *= fs);
        }
        let Inertia {
            mass,
            offsets,
            acc,
            ca,
        } = self.inertia;
        let (cd, nn, nd) = (dofs.cell(c), nodes.len(), r.len());
        let m = &mass[offsets[c]..offsets[c + 1]];
        for a in 0..nn {
            for b in 0..nn {
                let mab = m[a * nn + b];
                if mab == 0.0 {
                    continue;
                }
                for i in 0..3 {
                    r[3 * a + i] += mab * acc[cd[3 * b + i] as usize];
                    if !k.is_empty() {
                        k[(3 * a + i) * nd + 3 * b + i] += ca * mab;
                    }
                }
            }
        }
    }
}

impl RoadContact3D {
    /// The road velocity in its plane from the road speed and the slip angle.
    fn update_road_velocity(&mut self) {
        let v = road_velocity_3d(self.v0, self.slip_angle);
        self.surface.v_road = nalgebra::Vector2::new(v[0], v[1]);
    }
}

impl Solid3DSystem {
    /// The system with displacement component i of node n fixed where `fixed_u[3n + i]`.
    pub fn new(solid: Solid3D, fixed_u: &[bool]) -> Self {
        let dofs = solid.dof_map(fixed_u, 0);
        let asm = Assembler::with_blocks(
            &dofs,
            vec![(dofs.cell_dofs.clone(), dofs.cell_offsets.clone())],
        );
        let mut x = vec![0.0; dofs.n_full()];
        if let crate::physics::PressureMode::Exact { p0 } = solid.pressure {
            let per = solid.dofs_per_cell();
            for c in 0..solid.mesh.n_cells() {
                x[dofs.n_u + per * c] = p0;
            }
        }
        // Pressure residuals are volumes: their floor is a fraction of the body's volume.
        let volume = Self::volume(&solid);
        Self {
            solid,
            dofs,
            asm,
            x,
            coefficients: Coefficients::default(),
            target: Coefficients::default(),
            ref_norms: vec![0.0, 1e-3 * volume, 0.0],
            inadmissible: None,
            contact: None,
            strain_rate_damping: 0.0,
            steady_visc: None,
            steady_history: None,
        }
    }

    /// Add contact with the road on `surface` under displacement control (road height
    /// H = h_touch − λ · disp), after checking the surface against the mesh.
    pub fn with_contact(
        self,
        surface: ContactSurface3D,
        h_touch: f64,
        disp: f64,
    ) -> Result<Self, Contact3DError> {
        self.attach_contact(surface, h_touch, h_touch, disp, None)
    }

    /// Add contact with the road on `surface` under load control: the road height H becomes
    /// the last global unknown, starting at `h0` (below `h_touch`, so that the first contact
    /// points give its equation a non-zero tangent), with the equation
    /// λ · `load` − ∫ t_n dA0 = 0 (`load` > 0 presses the body onto the road).
    pub fn with_contact_load(
        self,
        surface: ContactSurface3D,
        h_touch: f64,
        h0: f64,
        load: f64,
    ) -> Result<Self, Contact3DError> {
        if !(h0.is_finite() && load.is_finite()) {
            return Err(Contact3DError::NonFinite(h0));
        }
        self.attach_contact(surface, h_touch, h0, 0.0, Some(load))
    }

    fn attach_contact(
        mut self,
        mut surface: ContactSurface3D,
        h_touch: f64,
        h0: f64,
        disp: f64,
        load: Option<f64>,
    ) -> Result<Self, Contact3DError> {
        let n_u = self.dofs.n_u;
        surface.check(&self.solid.mesh, &[("u", &self.x[..n_u])])?;
        surface.h = h0;
        let h_dof = if load.is_some() {
            // The same map with one global unknown (H) after the cell pressures.
            let fixed_u: Vec<bool> = self.dofs.eq[..n_u].iter().map(|&e| e == FIXED).collect();
            let dofs = self.solid.dof_map(&fixed_u, self.dofs.n_global + 1);
            let mut x = vec![0.0; dofs.n_full()];
            let n_old = self.x.len();
            x[..n_old].copy_from_slice(&self.x);
            let ih = dofs.global(dofs.n_global - 1);
            x[ih] = h0;
            self.dofs = dofs;
            self.x = x;
            self.ref_norms[2] = load.unwrap_or(0.0).abs();
            Some(ih)
        } else {
            None
        };
        self.contact = Some(RoadContact3D {
            surface,
            h_touch,
            disp,
            load,
            h_dof,
            lambda: 0.0,
            x_prev: self.x.clone(),
            lambda_prev: 0.0,
            dtau: 1.0,
            committed: None,
            totals: ContactTotals3D::default(),
            steady_omega: None,
            v0: 0.0,
            slip_angle: 0.0,
        });
        self.rebuild_assembler();
        Ok(self)
    }

    /// The body's reference volume.
    pub fn reference_volume(&self) -> f64 {
        Self::volume(&self.solid)
    }

    fn volume(solid: &Solid3D) -> f64 {
        let mut v = 0.0;
        let (pts, ws) = crate::element::gauss_1d(2);
        for c in 0..solid.mesh.n_cells() {
            for (k, wk) in pts.iter().zip(&ws) {
                for (j, wj) in pts.iter().zip(&ws) {
                    for (i, wi) in pts.iter().zip(&ws) {
                        let (_, jac) = solid.mesh.map(c, [*i, *j, *k]);
                        v += jac.determinant() * wi * wj * wk;
                    }
                }
            }
        }
        v
    }

    /// The coefficients reached at load factor 1 ([`LoadedSystem::set_load`] scales them).
    pub fn set_target(&mut self, target: Coefficients) {
        self.target = target;
    }

    /// Transient (Lagrangian) dynamics ([`Self::assemble_dynamic`]): the body force at its
    /// target, no centrifugal load (the inertia is M a), the road at load factor 1 and
    /// moving at `v0` turned by the slip angle `slip_angle` (radians) in its plane.
    pub fn set_transient(&mut self, v0: f64, slip_angle: f64) -> Result<(), Contact3DError> {
        for v in [v0, slip_angle] {
            if !v.is_finite() {
                return Err(Contact3DError::NonFinite(v));
            }
        }
        self.coefficients = Coefficients {
            omega2: 0.0,
            history_dt: self.coefficients.history_dt,
            ..self.target
        };
        if let Some(rc) = self.contact.as_mut() {
            rc.steady_omega = None;
            rc.lambda = 1.0;
            rc.v0 = v0;
            rc.slip_angle = slip_angle;
            rc.update_road_velocity();
        }
        Ok(())
    }

    /// Steady rolling in the θ-referential description: the body turns at `omega` (rad/s
    /// about +x3) and the road moves at the speed `v0` turned by the slip angle `slip_angle`
    /// (radians) in its plane, V = (V1, V3) = v0 (cos α, −sin α) (hub frame). The
    /// inertia −ω² ∫ ρ ∂θχ · ∂θη is on at once (the coefficients no longer follow the load
    /// factor, which then moves only the road), and the contact takes the steady velocity
    /// v = ω ∂θχ, with the friction slip from nodal θ-derivatives along the node rings of the
    /// surface ([`crate::contact::steady_slip3d`]; [`Self::disable_steady_slip`] takes it
    /// facet-wise). Needs the contact ([`Self::with_contact`] or [`Self::with_contact_load`]).
    pub fn set_steady_rolling(
        &mut self,
        omega: f64,
        v0: f64,
        slip_angle: f64,
    ) -> Result<(), Contact3DError> {
        for v in [omega, v0, slip_angle] {
            if !v.is_finite() {
                return Err(Contact3DError::NonFinite(v));
            }
        }

        self.target = Coefficients {
            omega2: omega * omega,
            ..self.target
        };
        self.coefficients = self.target;
        let mut rebuild = false;
        if let Some(rc) = self.contact.as_mut() {
            rc.steady_omega = Some(omega);
            rc.v0 = v0;
            rc.slip_angle = slip_angle;
            rc.update_road_velocity();
            if rc.surface.friction.is_active() && !rc.surface.has_steady_slip() {
                rebuild = rc.surface.enable_steady_slip(&self.solid.mesh);
            }
        }
        if rebuild {
            self.rebuild_assembler();
        }
        Ok(())
    }

    /// Take the steady friction slip facet-wise (the θ-derivative of the facet's own
    /// interpolant, discontinuous across facets) instead of from nodal derivatives.
    pub fn disable_steady_slip(&mut self) {
        if let Some(rc) = self.contact.as_mut() {
            if rc.surface.has_steady_slip() {
                rc.surface.disable_steady_slip();
                self.rebuild_assembler();
            }
        }
    }

    /// The strain-rate damping S_v = η Ė in steady rolling, Ė from the nodal velocities
    /// ω ∂θχ by ring differences ([`super::steady_visc3d`]); `eta` = 0 turns it off. An error
    /// when the mesh has no node rings about the axle.
    pub fn enable_steady_viscosity(&mut self, eta: f64) -> Result<(), String> {
        if !(eta.is_finite() && eta >= 0.0) {
            return Err(format!(
                "strain-rate damping {eta} is not a finite value ≥ 0"
            ));
        }
        self.strain_rate_damping = eta;
        let had = self.steady_visc.is_some();
        self.steady_visc = None;
        if eta > 0.0 {
            let sv = SteadyViscosity3D::new(&self.solid.mesh).ok_or_else(|| {
                "the steady strain-rate damping takes the material velocity by differences \
                 along the node rings about the axle, and the mesh's nodes do not form such \
                 rings (use a generated revolved mesh)"
                    .to_string()
            })?;
            self.steady_visc = Some((sv, 0));
        }
        if had || eta > 0.0 {
            self.rebuild_assembler();
        }
        Ok(())
    }

    /// The steady mode's viscoelastic history: the internal variables of the solid's
    /// viscoelastic material integrated along the rings of quadrature points at every
    /// evaluation ([`SteadyHistory3D`]), the ring coupling of the tangent applied matrix-free.
    /// Fails when the material is elastic or the mesh's points form no rings about the axle.
    pub fn enable_steady_history(&mut self) -> Result<(), String> {
        self.steady_history = Some(SteadyHistory3D::new(&self.solid, &self.dofs)?);
        Ok(())
    }

    /// The steady viscoelastic history, when enabled.
    pub fn steady_history(&self) -> Option<&SteadyHistory3D> {
        self.steady_history.as_ref()
    }

    /// The assembler of the cells and, with contact, of the facet elements: each facet's
    /// cell dofs, then those of its extra nodes ([`ContactSurface3D::extra_nodes`]), then H
    /// under load control; with the steady strain-rate damping, the cells' damping elements
    /// (the cell's displacement dofs, then its extra nodes', rows of the cell only).
    fn rebuild_assembler(&mut self) {
        let mut blocks = vec![(self.dofs.cell_dofs.clone(), self.dofs.cell_offsets.clone())];
        if let Some(rc) = self.contact.as_ref() {
            let mesh = &self.solid.mesh;
            let (mut d, mut o) = (Vec::new(), vec![0]);
            for (e, f) in rc.surface.facets.iter().enumerate() {
                let c = f.cell as usize;
                let nd = 3 * mesh.cell_nodes(c).len();
                d.extend_from_slice(&self.dofs.cell(c)[..nd]);
                for &n in rc.surface.extra_nodes(e) {
                    for i in 0..3 {
                        d.push(self.dofs.node_dof(n as usize, i) as u32);
                    }
                }
                if let Some(ih) = rc.h_dof {
                    d.push(ih as u32);
                }
                o.push(d.len());
            }
            blocks.push((d, o));
        }
        let mut cores = vec![None; blocks.len()];
        if let Some((sv, block)) = self.steady_visc.as_mut() {
            let mesh = &self.solid.mesh;
            let (mut d, mut o, mut core) = (Vec::new(), vec![0], Vec::new());
            for c in 0..mesh.n_cells() {
                let cn = mesh.cell_nodes(c);
                for &n in cn.iter().chain(sv.extra(c)) {
                    for i in 0..3 {
                        d.push(self.dofs.node_dof(n as usize, i) as u32);
                    }
                }
                o.push(d.len());
                core.push(3 * cn.len() as u32);
            }
            *block = blocks.len();
            blocks.push((d, o));
            cores.push(Some(core));
        }
        self.asm = Assembler::with_blocks_cored(&self.dofs, blocks, cores);
    }

    /// ω of steady rolling, if set.
    pub fn steady_omega(&self) -> Option<f64> {
        self.contact.as_ref().and_then(|c| c.steady_omega)
    }

    /// Set the angular speed ω of steady rolling (rad/s about +x3): the θ-referential inertia
    /// ω² and the contact's steady kinematics, the road velocity kept. No-op outside steady
    /// rolling.
    pub fn set_steady_omega(&mut self, omega: f64) {
        let Some(rc) = self.contact.as_mut().filter(|c| c.steady_omega.is_some()) else {
            return;
        };
        rc.steady_omega = Some(omega);
        self.target.omega2 = omega * omega;
        self.coefficients.omega2 = omega * omega;
    }

    /// The penetration h_touch − H of displacement control at the current load factor
    /// (`None` without contact or under load control).
    pub fn penetration(&self) -> Option<f64> {
        let rc = self.contact.as_ref().filter(|c| c.h_dof.is_none())?;
        Some(rc.h_touch - rc.surface.h)
    }

    /// Set the penetration of displacement control to `d` at the current load factor λ
    /// (`road.disp` = d / λ, H = h_touch − d). No-op without contact or under load control.
    pub fn set_penetration(&mut self, d: f64) {
        if let Some(rc) = self.contact.as_mut().filter(|c| c.h_dof.is_none()) {
            rc.disp = if rc.lambda != 0.0 { d / rc.lambda } else { d };
            rc.surface.h = rc.h_touch - d;
        }
    }

    /// The road speed v0 of steady rolling (0 without contact).
    pub fn road_speed(&self) -> f64 {
        self.contact.as_ref().map_or(0.0, |c| c.v0)
    }

    /// Set the road speed v0 of steady rolling, keeping the slip angle.
    pub fn set_road_speed(&mut self, v0: f64) {
        if let Some(rc) = self.contact.as_mut() {
            rc.v0 = v0;
            rc.update_road_velocity();
        }
    }

    /// The slip angle α of steady rolling (radians; 0 without contact).
    pub fn slip_angle(&self) -> f64 {
        self.contact.as_ref().map_or(0.0, |c| c.slip_angle)
    }

    /// Set the slip angle α (radians) of steady rolling, keeping the road speed.
    pub fn set_slip_angle(&mut self, slip_angle: f64) {
        if let Some(rc) = self.contact.as_mut() {
            rc.slip_angle = slip_angle;
            rc.update_road_velocity();
        }
    }

    /// The camber γ of the road (radians; 0 without contact), from the road normal
    /// n = (0, cos γ, −sin γ).
    pub fn camber(&self) -> f64 {
        self.contact.as_ref().map_or(0.0, |c| {
            let n = c.surface.frame().n;
            (-n[2]).atan2(n[1])
        })
    }

    /// Set the camber γ (radians, |γ| < π/2) of the road: its frame, and the road height of
    /// first touch (the largest −n·X of the tread's nodes), so that displacement control keeps
    /// its penetration below the first touch; under load control the road height stays the
    /// unknown.
    pub fn set_camber(&mut self, gamma: f64) -> Result<(), Contact3DError> {
        let Some(rc) = self.contact.as_mut() else {
            return Ok(());
        };
        rc.surface.set_camber(gamma)?;
        rc.h_touch = rc.surface.first_touch(&self.solid.mesh);
        if rc.h_dof.is_none() {
            rc.surface.h = rc.h_touch - rc.lambda * rc.disp;
        }
        Ok(())
    }

    /// Force and moment (about the hub centre, the origin) that the hub exerts on the body, in
    /// the wheel frame: the cell residuals R = f_int − f_ext at the fixed displacement dofs
    /// of the `hub` nodes (at a support R equals the reaction), with the inertia of the
    /// current coefficients. Moment component 3 is the torque about the axle +x3
    /// (counter-clockwise positive), the drive torque of the rolling controls.
    pub fn hub_reaction(&self) -> ([f64; 3], [f64; 3]) {
        self.hub_reaction_at(None)
    }

    /// [`Self::hub_reaction`] of an evaluation of the transient dynamics (with its inertia and
    /// force scale, at its configuration).
    pub fn hub_reaction_dynamic(&self, d: &Dynamic3D) -> ([f64; 3], [f64; 3]) {
        self.hub_reaction_at(Some(d))
    }

    fn hub_reaction_at(&self, dynamic: Option<&Dynamic3D>) -> ([f64; 3], [f64; 3]) {
        let mesh = &self.solid.mesh;
        let x: &[f64] = dynamic.map_or(&self.x, |d| d.x);
        let mut is_hub = vec![false; mesh.n_nodes()];
        for &n in mesh.node_set("hub") {
            is_hub[n as usize] = true;
        }
        let is_hub_dof = |d: usize| is_hub[d / 3] && self.dofs.eq[d] == FIXED;
        let (mut force, mut moment) = ([0.0; 3], [0.0; 3]);
        let mut r = vec![0.0; 3 * 27 + 8];
        for c in 0..mesh.n_cells() {
            let nodes = mesh.cell_nodes(c);
            if !nodes.iter().any(|&n| is_hub[n as usize]) {
                continue;
            }
            let cd = self.dofs.cell(c);
            r.clear();
            r.resize(cd.len(), 0.0);
            if self
                .solid
                .cell(c, &self.dofs, x, &self.coefficients, &mut r, &mut [])
                .is_err()
            {
                return ([f64::NAN; 3], [f64::NAN; 3]);
            }
            if let (Some((sv, _)), Some(omega), None) =
                (self.steady_visc.as_ref(), self.steady_omega(), dynamic)
            {
                let eta = self.strain_rate_damping;
                let n_ext = 3 * (nodes.len() + sv.extra(c).len());
                let mut rv = [0.0; MAX_DAMPING_DOFS];
                let res = steady_viscous_cell(
                    &self.solid,
                    sv,
                    c,
                    &self.dofs,
                    x,
                    omega,
                    eta,
                    &mut rv[..n_ext],
                    &mut [],
                );
                if res.is_err() {
                    return ([f64::NAN; 3], [f64::NAN; 3]);
                }
                for (ri, vi) in r.iter_mut().zip(&rv[..3 * nodes.len()]) {
                    *ri += vi;
                }
            }
            if let Some(d) = dynamic {
                if self.strain_rate_damping > 0.0 {
                    let eta = self.strain_rate_damping;
                    let res =
                        self.solid
                            .cell_viscous(c, &self.dofs, x, d.v, eta, d.kv, &mut r, &mut []);
                    if res.is_err() {
                        return ([f64::NAN; 3], [f64::NAN; 3]);
                    }
                }
                d.finish_cell(&self.dofs, nodes, c, &mut r, &mut []);
            }
            for (a, &n) in nodes.iter().enumerate() {
                let n = n as usize;
                let u = [x[3 * n], x[3 * n + 1], x[3 * n + 2]];
                let xp = [
                    mesh.nodes[n][0] + u[0],
                    mesh.nodes[n][1] + u[1],
                    mesh.nodes[n][2] + u[2],
                ];
                let mut f = [0.0; 3];
                for (i, fi) in f.iter_mut().enumerate() {
                    if is_hub_dof(3 * n + i) {
                        *fi = r[3 * a + i];
                    }
                }
                for i in 0..3 {
                    force[i] += f[i];
                }
                moment[0] += xp[1] * f[2] - xp[2] * f[1];
                moment[1] += xp[2] * f[0] - xp[0] * f[2];
                moment[2] += xp[0] * f[1] - xp[1] * f[0];
            }
        }
        (force, moment)
    }

    /// The floor of the displacement residual's convergence reference: a physical force scale
    /// of the problem (e.g. the centrifugal force ρ ω² Ro V).
    pub fn set_reference_force(&mut self, f: f64) {
        self.ref_norms[0] = f;
        if self.ref_norms[2] == 0.0 {
            self.ref_norms[2] = f;
        }
    }

    /// The road height H: the unknown under load control, else the prescribed one; `None`
    /// without contact.
    pub fn road_height(&self) -> Option<f64> {
        let rc = self.contact.as_ref()?;
        Some(rc.h_dof.map_or(rc.surface.h, |i| self.x[i]))
    }

    /// The contact state at every quadrature point of the contact facets, the slip measured
    /// over the current load step as the residual does (after a commit: over the step just
    /// committed, so the friction tractions are those of the converged step); empty without
    /// contact.
    pub fn contact_samples(&self) -> Result<Vec<ContactSample3D>, Contact3DError> {
        let Some(rc) = self.contact.as_ref() else {
            return Ok(Vec::new());
        };
        let mut surface = rc.surface.clone();
        surface.h = rc.h_dof.map_or(surface.h, |i| self.x[i]);
        let n_u = self.dofs.n_u;
        if let Some(omega) = rc.steady_omega {
            let kin = Kinematics3D::Steady { omega };
            return surface.samples(&self.solid.mesh, &self.x[..n_u], &kin);
        }
        let (start, dtau) = rc
            .committed
            .as_ref()
            .map_or((&rc.x_prev, rc.dtau), |(x, d)| (x, *d));
        let kin = Kinematics3D::Static {
            u_prev: &start[..n_u],
            dtau,
        };
        surface.samples(&self.solid.mesh, &self.x[..n_u], &kin)
    }

    /// Why the last evaluation failed, if it did.
    pub fn inadmissible(&self) -> Option<Inadmissible> {
        self.inadmissible
    }

    /// Residual and tangent at the current state into the assembler; `false` if a cell was
    /// inadmissible.
    pub fn assemble(&mut self, with_matrix: bool) -> bool {
        self.assemble_at(None, with_matrix)
    }

    /// Residual M a + s f(x, v) and its tangent of the transient dynamics into the assembler
    /// ([`Self::set_transient`]): the solid's forces at `d.x`, the contact's at the velocity
    /// `d.v` (normal damping on δ̇, friction on the slip v − V), both scaled by `d.force_scale`,
    /// plus the inertia. `false` if a cell was inadmissible.
    pub fn assemble_dynamic(&mut self, d: &Dynamic3D, with_matrix: bool) -> bool {
        self.assemble_at(Some(d), with_matrix)
    }

    fn assemble_at(&mut self, dynamic: Option<&Dynamic3D>, with_matrix: bool) -> bool {
        let bad = AtomicBool::new(false);
        let why = std::sync::Mutex::new(None);
        let x: &[f64] = dynamic.map_or(&self.x, |d| d.x);
        let omega = self.contact.as_ref().and_then(|c| c.steady_omega);
        if let (Some(sh), Some(omega), None) = (self.steady_history.as_mut(), omega, dynamic) {
            sh.sync(&mut self.solid, &self.dofs, x, omega);
        }
        let (solid, dofs, co) = (&self.solid, &self.dofs, self.coefficients);
        let eta = self.strain_rate_damping;
        self.asm.zero(with_matrix);
        self.asm.add_block_large(0, dofs, with_matrix, |c, r, k| {
            let mut res = solid.cell(c, dofs, x, &co, r, k);
            if let (Ok(()), Some(d), true) = (&res, dynamic, eta > 0.0) {
                res = solid.cell_viscous(c, dofs, x, d.v, eta, d.kv, r, k);
            }
            if let Err(e) = res {
                bad.store(true, Ordering::Relaxed);
                if let Ok(mut w) = why.lock() {
                    *w = Some(e);
                }
                r.fill(0.0);
                k.fill(0.0);
            } else if let Some(d) = dynamic {
                d.finish_cell(dofs, solid.mesh.cell_nodes(c), c, r, k);
            }
        });
        if let (Some((sv, block)), Some(omega), None) =
            (self.steady_visc.as_ref(), self.steady_omega(), dynamic)
        {
            self.asm
                .add_block_large(*block, dofs, with_matrix, |c, r, k| {
                    if let Err(e) = steady_viscous_cell(solid, sv, c, dofs, x, omega, eta, r, k) {
                        bad.store(true, Ordering::Relaxed);
                        if let Ok(mut w) = why.lock() {
                            *w = Some(e);
                        }
                        r.fill(0.0);
                    }
                });
        }
        self.inadmissible = why.into_inner().ok().flatten();
        if let Some(rc) = self.contact.as_mut() {
            let mesh = &solid.mesh;
            let totals = std::sync::Mutex::new(ContactTotals3D::default());
            if let Some(ih) = rc.h_dof {
                rc.surface.h = x[ih];
            }
            let load = rc.load.map(|p| rc.lambda * p);
            let (surface, x_prev, dtau) = (&rc.surface, &rc.x_prev, rc.dtau);
            let steady = rc.steady_omega;
            self.asm.add_block_large(1, dofs, with_matrix, |e, r, k| {
                let f = surface.facets[e];
                let cd = dofs.cell(f.cell as usize);
                if let Some(omega) = steady {
                    // The element's dofs: the cell's, its extra nodes', H last (load control).
                    let mut ul = [0.0; MAX_ELEMENT_DOFS];
                    let mut nd = 0;
                    let cell = mesh.cell_nodes(f.cell as usize);
                    for &n in cell.iter().chain(surface.extra_nodes(e)) {
                        for i in 0..3 {
                            ul[nd] = x[dofs.node_dof(n as usize, i)];
                            nd += 1;
                        }
                    }
                    let mut t = ContactTotals3D::default();
                    let kb = if k.is_empty() { None } else { Some(k) };
                    let with_h = load.is_some();
                    surface.facet_kernel_steady(mesh, e, &ul[..nd], omega, with_h, r, kb, &mut t);
                    if let (Some(p), 0) = (load, e) {
                        r[nd] += p;
                    }
                    if let Ok(mut all) = totals.lock() {
                        all.add(&t);
                    }
                    return;
                }
                // The cell's dofs (and H last under load control).
                let nd = 3 * mesh.cell_nodes(f.cell as usize).len();
                let (mut ul, mut vl) = ([0.0; 81], [0.0; 81]);
                for i in 0..nd {
                    let g = cd[i] as usize;
                    ul[i] = x[g];
                    vl[i] = match dynamic {
                        Some(d) => d.v[g],
                        None => (x[g] - x_prev[g]) / dtau,
                    };
                }
                let m = match dynamic {
                    Some(d) => CellMotion {
                        u: &ul[..nd],
                        v: &vl[..nd],
                        kx: 1.0,
                        kv: d.kv,
                        damping: true,
                    },
                    None => CellMotion {
                        u: &ul[..nd],
                        v: &vl[..nd],
                        kx: 1.0,
                        kv: 1.0 / dtau,
                        damping: false,
                    },
                };
                let mut t = ContactTotals3D::default();
                let kb = if k.is_empty() { None } else { Some(&mut *k) };
                match load {
                    Some(p) => {
                        surface.facet_kernel_height(mesh, f, &m, r, kb, &mut t);
                        if e == 0 {
                            // R_H = λ · load − ∫ t_n dA0: the load enters once.
                            r[nd] += p;
                        }
                    }
                    None => {
                        surface.facet_kernel(mesh, f, &m, r, kb, &mut t);
                    }
                }
                if let Some(d) = dynamic {
                    if d.force_scale != 1.0 {
                        r.iter_mut().for_each(|v| *v *= d.force_scale);
                        k.iter_mut().for_each(|v| *v *= d.force_scale);
                    }
                }
                if let Ok(mut all) = totals.lock() {
                    all.add(&t);
                }
            });
            rc.totals = totals.into_inner().unwrap_or_default();
        }
        !bad.load(Ordering::Relaxed)
    }

    /// The displacement of node `n`.
    pub fn node_displacement(&self, n: usize) -> [f64; 3] {
        [self.x[3 * n], self.x[3 * n + 1], self.x[3 * n + 2]]
    }
}

/// The steady strain-rate damping of cell `c` at the full state `x` into its damping element's
/// `r` and `k` ([`SteadyViscosity3D::cell`]).
#[allow(clippy::too_many_arguments)]
fn steady_viscous_cell(
    solid: &Solid3D,
    sv: &SteadyViscosity3D,
    c: usize,
    dofs: &DofMap,
    x: &[f64],
    omega: f64,
    eta: f64,
    r: &mut [f64],
    k: &mut [f64],
) -> Result<(), Inadmissible> {
    let mut ue = [0.0; MAX_DAMPING_DOFS];
    let mut nd = 0;
    for &n in solid.mesh.cell_nodes(c).iter().chain(sv.extra(c)) {
        for i in 0..3 {
            ue[nd] = x[dofs.node_dof(n as usize, i)];
            nd += 1;
        }
    }
    sv.cell(solid, c, &ue[..nd], omega, eta, r, k)
}

/// The road velocity (V1, V3) in the road plane for the speed `v0` and the slip angle `alpha`
/// (radians): the road's velocity turned by α about +x2, V = v0 (cos α, −sin α).
pub fn road_velocity_3d(v0: f64, alpha: f64) -> [f64; 2] {
    [v0 * alpha.cos(), -v0 * alpha.sin()]
}

impl NonlinearSystem for Solid3DSystem {
    fn n_eq(&self) -> usize {
        self.dofs.n_eq
    }
    fn fields(&self) -> &[u8] {
        &self.dofs.field
    }
    fn field_names(&self) -> &'static [&'static str] {
        &["u", "p", "H"]
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
                let n = d / 3;
                (self.solid.mesh.nodes[n] + nalgebra::Vector3::from(self.node_displacement(n)))
                    .norm()
            } else {
                self.x[d].abs()
            };
        }
    }
    fn pattern(&self) -> (&[usize], &[usize]) {
        (&self.asm.col_ptr, &self.asm.row_idx)
    }
    fn evaluate(&mut self, with_matrix: bool) -> bool {
        self.assemble(with_matrix)
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
    }
    fn has_tangent_correction(&self) -> bool {
        self.steady_omega().is_some() && self.steady_history.is_some()
    }
    fn tangent_correction(&mut self, v: &[f64], out: &mut [f64]) {
        let omega = self.steady_omega();
        if let (Some(sh), Some(omega)) = (self.steady_history.as_mut(), omega) {
            sh.apply_correction(&self.solid, &self.dofs, omega, v, out);
        }
    }
}

impl LoadedSystem for Solid3DSystem {
    fn set_load(&mut self, lambda: f64) {
        let steady = self.steady_omega().is_some();
        self.coefficients = if steady {
            self.target
        } else {
            Coefficients {
                omega2: lambda * self.target.omega2,
                body_load: lambda * self.target.body_load,
                history_dt: self.coefficients.history_dt,
            }
        };
        if let Some(rc) = self.contact.as_mut() {
            rc.lambda = lambda;
            if rc.h_dof.is_none() {
                rc.surface.h = rc.h_touch - lambda * rc.disp;
            }
            rc.dtau = (lambda - rc.lambda_prev).max(f64::MIN_POSITIVE);
            rc.committed = None;
        }
    }
    fn commit(&mut self) {
        if let Some(rc) = self.contact.as_mut() {
            rc.committed = Some((rc.x_prev.clone(), rc.dtau));
            rc.x_prev.copy_from_slice(&self.x);
            rc.lambda_prev += rc.dtau;
        }
    }
}
