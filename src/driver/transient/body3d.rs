//! The three-dimensional solid ([`Solid3DSystem`]) as a [`Body`] of the transient mode: three
//! displacements per node, the hub turning about the axle x3 (u3 = 0 on the hub), the
//! road moving at v0 turned by the slip angle in its (possibly cambered) plane, friction on
//! the slip v − V and normal damping on δ̇ of the material velocity. Node passages re-index
//! the referential field along the node rings of the revolved mesh (every circumferential
//! node line is a ring, [`crate::mesh::hex_mesh::RingLayout3D`]); a mesh without rings has no
//! steady-state extraction in 3D. The strain-rate damping (`time.strain_rate_damping`) acts on
//! the Green-strain rate of the material velocity. A viscoelastic material carries its history
//! at the quadrature points, advanced once per accepted step as in plane strain. No torque
//! control in 3D.

use super::body::Body;
use super::{DynamicTerms, HubAngle};
use crate::assembly::{Assembler, DofMap, CONSTRAINED};
use crate::contact::facet3d::Kinematics3D;
use crate::model::system3d::Dynamic3D;
use crate::model::{Inertia, Solid3DSystem};
use crate::physics::ViscousStep;

fn dynamic<'a>(t: &DynamicTerms<'a>) -> Dynamic3D<'a> {
    Dynamic3D {
        x: t.x,
        v: t.v,
        kv: t.kv,
        force_scale: t.force_scale,
        inertia: Inertia {
            mass: t.mass,
            offsets: t.offsets,
            acc: t.acc,
            ca: t.ca,
        },
    }
}

impl Body for Solid3DSystem {
    const DIM: usize = 3;
    type Locator = ();

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
        self.solid.mesh.n_nodes()
    }
    fn reference_node(&self, n: usize) -> [f64; 3] {
        let x = self.solid.mesh.nodes[n];
        [x[0], x[1], x[2]]
    }
    fn hub_nodes(&self) -> Vec<u32> {
        self.solid.mesh.node_set("hub").to_vec()
    }
    fn n_cells(&self) -> usize {
        self.solid.mesh.n_cells()
    }
    fn cell_nodes(&self, c: usize) -> &[u32] {
        self.solid.mesh.cell_nodes(c)
    }
    fn cell_mass(&self, c: usize, out: &mut Vec<f64>) {
        self.solid.cell_mass(c, out);
    }
    fn mass_total(&self) -> f64 {
        self.solid.rho * self.reference_volume()
    }
    fn outer_radius(&self) -> f64 {
        let m = &self.solid.mesh;
        m.nodes.iter().map(|x| x[0].hypot(x[1])).fold(0.0, f64::max)
    }
    fn set_reference_force(&mut self, f: f64) {
        Solid3DSystem::set_reference_force(self, f);
    }

    fn assemble_dynamic(
        &mut self,
        terms: &DynamicTerms,
        hub: Option<&mut HubAngle>,
        _is_hub: &[bool],
        with_matrix: bool,
    ) -> bool {
        // Torque control is not offered in 3D (the driver refuses it).
        if hub.is_some() {
            return false;
        }
        Solid3DSystem::assemble_dynamic(self, &dynamic(terms), with_matrix)
    }

    fn hub_reaction_dynamic(&self, terms: &DynamicTerms) -> ([f64; 3], [f64; 3]) {
        Solid3DSystem::hub_reaction_dynamic(self, &dynamic(terms))
    }

    fn set_road(&mut self, h: Option<f64>, load: Option<f64>, v0: f64) {
        let alpha = self.slip_angle();
        if let Some(rc) = self.contact.as_mut() {
            if let (Some(h), None) = (h, rc.h_dof) {
                rc.surface.h = h;
            }
            if load.is_some() {
                rc.load = load;
            }
        }
        if self.contact.is_some() {
            // Finite by construction (ramped finite targets).
            let _ = self.set_transient(v0, alpha);
        }
    }

    fn road_height_dof(&self) -> Option<usize> {
        self.contact.as_ref().and_then(|c| c.h_dof)
    }

    fn lowest_contact_point(&self, u: &[f64], v: &[f64]) -> Option<f64> {
        // The lowest facet quadrature point (not node): the first point the road's equation
        // sees.
        let n = self.contact.as_ref()?.surface.frame().n;
        let samples = contact_samples_3d(self, u, v).ok()?;
        let low = samples
            .iter()
            .map(|s| n[0] * s.x1 + n[1] * s.x2 + n[2] * s.x3)
            .fold(f64::INFINITY, f64::min);
        low.is_finite().then_some(low)
    }

    fn strain_energy_of(&self, u: &[f64]) -> f64 {
        self.solid.strain_energy(&self.dofs, u)
    }

    fn has_rate_damping(&self) -> bool {
        self.strain_rate_damping > 0.0
    }

    fn contact_diagonals(&self, delta_ref: f64) -> Option<(Vec<f64>, Vec<f64>)> {
        let rc = self.contact.as_ref()?;
        let n_eq = self.dofs.n_eq;
        let (mut kc, mut cc) = (vec![0.0; n_eq], vec![0.0; n_eq]);
        let nv = rc
            .surface
            .normal
            .eval(delta_ref.max(f64::MIN_POSITIVE), 0.0);
        let nr = rc.surface.frame().n;
        let w = rc.surface.boundary_row_sums(&self.solid.mesh);
        for (node, wa) in w.iter().enumerate() {
            for i in 0..3 {
                let e = self.dofs.eq[3 * node + i];
                if e < CONSTRAINED && *wa > 0.0 {
                    kc[e as usize] = nv.d_delta * wa * nr[i] * nr[i];
                    cc[e as usize] = nv.d_rate * wa * nr[i] * nr[i];
                }
            }
        }
        Some((kc, cc))
    }

    fn set_history_dt(&mut self, dt: f64) {
        self.coefficients.history_dt = dt;
    }

    fn commit_history(&mut self, dt: f64) -> Option<ViscousStep> {
        let step = self.solid.commit_history(&self.dofs, &self.x, dt);
        self.solid.viscoelastic.is_some().then_some(step)
    }

    fn passage_geometry(&self) -> (f64, usize, usize, Option<()>) {
        match self.solid.mesh.rings {
            Some(rl) => (
                2.0 * std::f64::consts::PI / rl.n_theta as f64,
                rl.per_ring,
                rl.n_theta,
                None,
            ),
            // No extraction without rings: one passage per quarter turn, field left at zero.
            None => (0.5 * std::f64::consts::PI, 0, 0, None),
        }
    }

    fn referential_field(
        &self,
        _locator: Option<&()>,
        shift: usize,
        _phi: f64,
        u: &[f64],
    ) -> Vec<f64> {
        let mesh = &self.solid.mesh;
        let mut field = vec![0.0; 3 * mesh.n_nodes()];
        let Some(rl) = mesh.rings else {
            return field;
        };
        let per = rl.per_ring;
        for ring in 0..rl.rings_r * rl.rings_z {
            for l in 0..per {
                let i = ring * per + l;
                let j = ring * per + (l + shift) % per;
                for c in 0..3 {
                    field[3 * j + c] = mesh.nodes[i][c] + u[3 * i + c] - mesh.nodes[j][c];
                }
            }
        }
        field
    }
}

/// The contact samples of the transient state (x, v): the slip is the material velocity's.
pub fn contact_samples_3d(
    sys: &Solid3DSystem,
    x: &[f64],
    v: &[f64],
) -> Result<Vec<crate::contact::facet3d::ContactSample3D>, crate::contact::facet3d::Contact3DError>
{
    let Some(rc) = sys.contact.as_ref() else {
        return Ok(Vec::new());
    };
    let mut surface = rc.surface.clone();
    surface.h = rc.h_dof.map_or(surface.h, |i| x[i]);
    let n_u = sys.dofs.n_u;
    let kin = Kinematics3D::Dynamic {
        v: &v[..n_u],
        kx: 1.0,
        kv: 0.0,
    };
    surface.samples(&sys.solid.mesh, &x[..n_u], &kin)
}
