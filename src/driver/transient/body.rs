//! What the transient integrators need of a solid model ([`Body`]): its state and dofs, its
//! cell masses, the dynamic residual M a + s f(x, v) with its tangent, the hub reaction, the
//! road, and the referential field at a node passage. The plane-strain [`SolidSystem`]
//! (D = 2, per unit thickness) implements it here, the three-dimensional
//! [`crate::model::Solid3DSystem`] (D = 3) in [`super::body3d`]; the time loop, the
//! integrators and the steady-state monitor of [`super`] are written once for both.
//!
//! Both bodies turn about the axle x3: the hub nodes follow x = Q(φ) X with Q the rotation
//! by φ in the (x1, x2) plane (the hub's u3 stays 0 in 3D), and the loads are reported as a
//! force and a moment about the hub centre in the global frame (in 2D F3 = M1 = M2 = 0 and
//! M3 is the torque per unit thickness).

use super::{DynamicTerms, HubAngle};
use crate::assembly::{Assembler, DofMap, QpHistory, CONSTRAINED};
use crate::model::system::SolidSystem;
use crate::model::terms::{Inertia, Rates, Terms};
use crate::physics::solid::ViscousStep;
use crate::solver::NonlinearSystem;

/// A solid the transient mode integrates.
pub trait Body: NonlinearSystem + Sized + 'static {
    /// Displacement components per node.
    const DIM: usize;
    /// Point location in the reference mesh, for the referential field of a mesh without
    /// rings (unit when the body has none).
    type Locator;

    /// Full state (displacements, cell pressures, global unknowns).
    fn x(&self) -> &[f64];
    fn x_mut(&mut self) -> &mut Vec<f64>;
    fn dof_map(&self) -> &DofMap;
    fn assembler(&self) -> &Assembler;
    fn assembler_mut(&mut self) -> &mut Assembler;
    fn n_nodes(&self) -> usize;
    /// Reference position of node `n` (x3 = 0 in plane strain).
    fn reference_node(&self, n: usize) -> [f64; 3];
    /// The nodes bonded to the hub.
    fn hub_nodes(&self) -> Vec<u32>;
    fn n_cells(&self) -> usize;
    fn cell_nodes(&self, c: usize) -> &[u32];
    /// Scalar cell mass matrix ρ0 ∫ N_a N_b dV (n × n, row-major) into `out`.
    fn cell_mass(&self, c: usize, out: &mut Vec<f64>);
    /// ρ0 × the body's volume (2D: area), for the force scale of the convergence test.
    fn mass_total(&self) -> f64;
    fn outer_radius(&self) -> f64;
    fn set_reference_force(&mut self, f: f64);
    /// Assemble M acc + s f(x, v) (and its tangent) into the assembler; with `hub` (torque
    /// control, plane strain only) the hub-angle row and column too. False if a cell is
    /// inadmissible.
    fn assemble_dynamic(
        &mut self,
        terms: &DynamicTerms,
        hub: Option<&mut HubAngle>,
        is_hub: &[bool],
        with_matrix: bool,
    ) -> bool;
    /// Force and moment (about the hub centre) of the hub on the body under `terms`.
    fn hub_reaction_dynamic(&self, terms: &DynamicTerms) -> ([f64; 3], [f64; 3]);
    /// The road at one instant: its height (displacement control), the hub load (load
    /// control) and its speed.
    fn set_road(&mut self, h: Option<f64>, load: Option<f64>, v0: f64);
    /// Full index of the road height under load control.
    fn road_height_dof(&self) -> Option<usize>;
    /// The lowest contact point's x2 in the configuration `u` (load control's start).
    fn lowest_contact_point(&self, u: &[f64], v: &[f64]) -> Option<f64>;
    /// Stored energy of the configuration `u`.
    fn strain_energy_of(&self, u: &[f64]) -> f64;
    /// Strain-rate damping is active (the stable step then needs the damping matrix).
    fn has_rate_damping(&self) -> bool;
    /// Diagonals (equation numbering) of the contact penalty and damping on the whole contact
    /// boundary at the penetration `delta_ref`, for the stable-step estimate.
    fn contact_diagonals(&self, delta_ref: f64) -> Option<(Vec<f64>, Vec<f64>)>;
    /// The step size of the quadrature-point history during an implicit step (0 outside).
    fn set_history_dt(&mut self, _dt: f64) {}
    /// Advance the quadrature-point history over a step `dt` at the current state; `None`
    /// when the body has no history.
    fn commit_history(&mut self, _dt: f64) -> Option<ViscousStep> {
        None
    }
    /// Node passages: the cell angle Δθ, the nodes per ring and the cells per ring of a mesh
    /// with rings (0, 0 without), and the locator of a mesh without rings.
    fn passage_geometry(&self) -> (f64, usize, usize, Option<Self::Locator>);
    /// The referential displacement field (DIM per node) at the hub angle `phi` = k Δθ from
    /// the material displacements `u` (DIM per node): re-indexed along the rings by `shift`
    /// node positions, or interpolated with `locator`.
    fn referential_field(
        &self,
        locator: Option<&Self::Locator>,
        shift: usize,
        phi: f64,
        u: &[f64],
    ) -> Vec<f64>;
    /// The quadrature-point history re-indexed to the referential cells after `k` cell angles
    /// (angle `phi`); `None` without history or rings.
    fn passage_history(&self, _k: i64, _phi: f64) -> Option<QpHistory> {
        None
    }
}

impl Body for SolidSystem {
    const DIM: usize = 2;
    type Locator = crate::mesh::locate::PointLocator;

    fn x(&self) -> &[f64] {
        &self.x
    }
    fn x_mut(&mut self) -> &mut Vec<f64> {
        &mut self.x
    }
    fn dof_map(&self) -> &DofMap {
        &self.dofs
    }
    fn assembler(&self) -> &Assembler {
        &self.asm
    }
    fn assembler_mut(&mut self) -> &mut Assembler {
        &mut self.asm
    }
    fn n_nodes(&self) -> usize {
        self.model.mesh.n_nodes()
    }
    fn reference_node(&self, n: usize) -> [f64; 3] {
        let x = self.model.mesh.nodes[n];
        [x[0], x[1], 0.0]
    }
    fn hub_nodes(&self) -> Vec<u32> {
        self.model.mesh.node_set("hub").to_vec()
    }
    fn n_cells(&self) -> usize {
        self.model.mesh.n_cells()
    }
    fn cell_nodes(&self, c: usize) -> &[u32] {
        self.model.mesh.cell_nodes(c)
    }
    fn cell_mass(&self, c: usize, out: &mut Vec<f64>) {
        self.model.cell_mass(c, out);
    }
    fn mass_total(&self) -> f64 {
        self.model.rho * crate::model::system::domain_area(&self.model)
    }
    fn outer_radius(&self) -> f64 {
        self.model.mesh.outer_radius()
    }
    fn set_reference_force(&mut self, f: f64) {
        SolidSystem::set_reference_force(self, f);
    }

    fn assemble_dynamic(
        &mut self,
        terms: &DynamicTerms,
        hub_angle: Option<&mut HubAngle>,
        is_hub: &[bool],
        with_matrix: bool,
    ) -> bool {
        super::torque::assemble_with_hub_angle(self, terms, hub_angle, is_hub, with_matrix)
    }

    fn hub_reaction_dynamic(&self, t: &DynamicTerms) -> ([f64; 3], [f64; 3]) {
        let (f, m) = self.hub_reaction_with(&Terms {
            rates: Rates::Dynamic {
                x: t.x,
                v: t.v,
                kv: t.kv,
            },
            force_scale: t.force_scale,
            inertia: Some(Inertia {
                mass: t.mass,
                offsets: t.offsets,
                acc: t.acc,
                ca: t.ca,
            }),
            cell_hook: None,
        });
        ([f[0], f[1], 0.0], [0.0, 0.0, m])
    }

    fn set_road(&mut self, h: Option<f64>, load: Option<f64>, v0: f64) {
        if let Some(cm) = &mut self.contact {
            if let Some(h) = h {
                cm.h = h;
            }
            if load.is_some() {
                cm.load = load;
            }
            cm.v0 = v0;
        }
    }

    fn road_height_dof(&self) -> Option<usize> {
        let c = self.contact.as_ref()?;
        (c.load.is_some() && self.dofs.n_global > 0).then(|| self.dofs.global(0))
    }

    fn lowest_contact_point(&self, u: &[f64], v: &[f64]) -> Option<f64> {
        let c = self.contact.as_ref()?;
        let kin = crate::contact::SlipKinematics::Dynamic {
            v,
            kx: 1.0,
            kv: 0.0,
        };
        let s = c.samples(&self.model.mesh, &self.dofs, u, &kin);
        let low = s.iter().map(|s| s.x2).fold(f64::INFINITY, f64::min);
        low.is_finite().then_some(low)
    }

    fn strain_energy_of(&self, u: &[f64]) -> f64 {
        self.model.strain_energy(&self.dofs, u)
    }

    fn has_rate_damping(&self) -> bool {
        self.model.strain_rate_damping > 0.0
    }

    fn contact_diagonals(&self, delta_ref: f64) -> Option<(Vec<f64>, Vec<f64>)> {
        let cm = self.contact.as_ref()?;
        let n = self.dofs.n_eq;
        let (mut kc, mut cc) = (vec![0.0; n], vec![0.0; n]);
        let nv = cm.normal.eval(delta_ref.max(f64::MIN_POSITIVE), 0.0);
        let w = cm.boundary_row_sums(&self.model.mesh);
        for (node, wa) in w.iter().enumerate() {
            let e = self.dofs.eq[2 * node + 1];
            if e < CONSTRAINED && *wa > 0.0 {
                kc[e as usize] = nv.d_delta * wa;
                cc[e as usize] = nv.d_rate * wa;
            }
        }
        Some((kc, cc))
    }

    fn set_history_dt(&mut self, dt: f64) {
        self.model.history_dt = dt;
    }

    fn commit_history(&mut self, dt: f64) -> Option<ViscousStep> {
        let step = self.model.commit_history(&self.dofs, &self.x, dt);
        self.model.viscoelastic.is_some().then_some(step)
    }

    fn passage_geometry(&self) -> (f64, usize, usize, Option<Self::Locator>) {
        let mesh = &self.model.mesh;
        // The mesh repeats itself every cell, not every node (Q2: vertex and mid-side nodes
        // alternate), so the passages are taken every p node steps = one cell. Without rings:
        // about one passage per contact facet.
        match mesh.rings {
            Some(rl) => (
                2.0 * std::f64::consts::PI / rl.n_theta as f64,
                rl.per_ring,
                rl.n_theta,
                None,
            ),
            None => {
                let n = mesh.facet_set("outer").len().max(8);
                let loc = crate::mesh::locate::PointLocator::new(mesh);
                (2.0 * std::f64::consts::PI / n as f64, 0, 0, Some(loc))
            }
        }
    }

    fn referential_field(
        &self,
        locator: Option<&Self::Locator>,
        shift: usize,
        phi: f64,
        u: &[f64],
    ) -> Vec<f64> {
        let mesh = &self.model.mesh;
        let mut field = vec![0.0; 2 * mesh.n_nodes()];
        if let Some(loc) = locator {
            // Interpolation: χ(Y_j) = X* + u(X*) with X* = Q(−φ) Y_j.
            let (sn, cs) = phi.sin_cos();
            for (j, y) in mesh.nodes.iter().enumerate() {
                let xs = crate::math::Vec2::new(cs * y[0] + sn * y[1], -sn * y[0] + cs * y[1]);
                let (c, xi, eta) = loc.locate_nearest(mesh, xs);
                let chi = xs + crate::mesh::locate::vector_at(mesh, u, c, xi, eta);
                field[2 * j] = chi[0] - y[0];
                field[2 * j + 1] = chi[1] - y[1];
            }
            return field;
        }
        let Some(rl) = mesh.rings else {
            return field;
        };
        let per = rl.per_ring;
        for m in 0..rl.rings {
            for l in 0..per {
                let i = m * per + l;
                let j = m * per + (l + shift) % per;
                for c in 0..2 {
                    let xi = mesh.nodes[i][c] + u[2 * i + c];
                    field[2 * j + c] = xi - mesh.nodes[j][c];
                }
            }
        }
        field
    }

    fn passage_history(&self, k: i64, phi: f64) -> Option<QpHistory> {
        let hist = &self.model.history;
        match self.model.mesh.rings {
            Some(rl) if !hist.is_empty() => Some(super::reindex_history(hist, rl.n_theta, k, phi)),
            _ => None,
        }
    }
}
