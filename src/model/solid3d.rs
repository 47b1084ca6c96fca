//! The three-dimensional solid on hexahedral meshes: the cell integrand of [`super::kernel`]
//! with `D = 3`, the cells mapped by [`HexMesh::map`] (exact cylindrical and crowned maps of
//! the revolved mesh, isoparametric otherwise), Gauss rules with 2 points per direction for
//! Hex8 and 3 for Hex27.
//!
//! Frame ([`crate::mesh::hex_mesh`]): the axle is x3, x1 along the road, x2 up, the body spins
//! about +x3. Displacements are three per node (node-major, component i of node n at dof
//! 3n + i); incompressible laws add the cell's four P1 pressures after them.

use super::kernel::{
    cell_energy, grad_u, n_pressure, p1_basis, perturbed_pressure, pressure_frame, solid_cell,
    BodyForceD, CellLaw, CellOverstress, CellPressure, Coefficients, Inadmissible, Point,
};
use crate::assembly::{CellTopology, DofMap, QpHistory};
use crate::element::hex::{Hex27, Hex8, Lagrange3D, QuadRule3D};
use crate::material::viscoelastic::MAX_STATE_3D;
use crate::material::Viscoelastic;
use crate::material::{Hyperelastic, Material};
use crate::math::Mat3;
use crate::mesh::hex_mesh::HexMesh;
use crate::physics::solid::ViscousStep;
use crate::physics::PressureMode;
use nalgebra::{Vector3, Vector4};

/// Shape values and reference gradients of an element at the points of a rule.
#[derive(Clone, Debug)]
struct Table3<const N: usize> {
    points: Vec<[f64; 3]>,
    weights: Vec<f64>,
    n: Vec<[f64; N]>,
    dn: Vec<[[f64; 3]; N]>,
}

impl<const N: usize> Table3<N> {
    fn new<E: Lagrange3D>(q: usize) -> Self {
        let rule = QuadRule3D::gauss_3d(q);
        let (mut n, mut dn) = (Vec::new(), Vec::new());
        for &x in &rule.points {
            let (mut nv, mut dv) = ([0.0; N], [[0.0; 3]; N]);
            E::eval(x, &mut nv, &mut dv);
            n.push(nv);
            dn.push(dv);
        }
        Self {
            points: rule.points,
            weights: rule.weights,
            n,
            dn,
        }
    }
}

/// Most quadrature points of a cell (Hex27, 3 × 3 × 3).
pub const MAX_POINTS_3D: usize = 27;

/// The hyperelastic solid on a hexahedral mesh.
pub struct Solid3D {
    pub mesh: HexMesh,
    pub material: Material,
    /// Reference density ρ0.
    pub rho: f64,
    pub pressure: PressureMode,
    /// Body force per unit reference volume (scaled by [`Coefficients::body_load`]).
    pub body_force: Option<Box<BodyForceD<3>>>,
    /// Viscoelastic overstress (`None`: elastic, no history).
    pub viscoelastic: Option<Viscoelastic>,
    /// Committed state of the viscoelastic internal variables at the stiffness rule's points
    /// (cell by cell, the points of [`Self::cell`]'s rule in order; empty when elastic). The
    /// kernels only read it: [`Self::commit_history`] advances it once a step has converged.
    pub history: QpHistory,
    q1: Table3<8>,
    q2: Table3<27>,
    /// The mass rules (one point per direction more than the stiffness's, as the plane-strain
    /// program's: N_a N_b det J of a curved cell).
    m1: Table3<8>,
    m2: Table3<27>,
}

impl Solid3D {
    pub fn new(mesh: HexMesh, material: Material, rho: f64, pressure: PressureMode) -> Self {
        Self {
            mesh,
            material,
            rho,
            pressure,
            body_force: None,
            viscoelastic: None,
            history: QpHistory::none(),
            q1: Table3::new::<Hex8>(2),
            q2: Table3::new::<Hex27>(3),
            m1: Table3::new::<Hex8>(3),
            m2: Table3::new::<Hex27>(4),
        }
    }

    /// Cell-owned dofs per cell (the P1 pressures of the exact constraint).
    pub fn dofs_per_cell(&self) -> usize {
        match self.pressure {
            PressureMode::Exact { .. } => n_pressure(3),
            _ => 0,
        }
    }

    /// The dof map: three displacements per node, `fixed_u[3n + i]` fixing component i of node
    /// n, then the cell pressures, then `n_global` global unknowns.
    pub fn dof_map(&self, fixed_u: &[bool], n_global: usize) -> DofMap {
        let mesh = &self.mesh;
        DofMap::for_cells(
            CellTopology {
                n_nodes: mesh.n_nodes(),
                n_cells: mesh.n_cells(),
                cell_nodes: &|c| mesh.cell_nodes(c),
                constraints: &[],
            },
            3,
            self.dofs_per_cell(),
            fixed_u,
            n_global,
        )
    }

    /// The quadrature points of cell `c` in `out`; returns how many.
    fn points<const N: usize>(
        &self,
        tab: &Table3<N>,
        c: usize,
        out: &mut [Point<3, N>; MAX_POINTS_3D],
    ) -> Result<usize, Inadmissible> {
        for (q, slot) in out.iter_mut().enumerate().take(tab.points.len()) {
            let (x, jac) = self.mesh.map(c, tab.points[q]);
            let det = jac.determinant();
            let inv = jac.try_inverse().ok_or(Inadmissible::Singular)?;
            if det <= 0.0 || !det.is_finite() {
                return Err(Inadmissible::Singular);
            }
            slot.x = [x[0], x[1], x[2]];
            slot.w = tab.weights[q] * det;
            slot.n = tab.n[q];
            for a in 0..N {
                let d = tab.dn[q][a];
                for (j, gj) in slot.g[a].iter_mut().enumerate() {
                    *gj = d[0] * inv[(0, j)] + d[1] * inv[(1, j)] + d[2] * inv[(2, j)];
                }
            }
        }
        Ok(tab.points.len())
    }

    /// Residual and tangent of cell `c` at the full state `x` (see [`solid_cell`]); `r` has the
    /// cell's dof count, `k` its square or is empty.
    pub fn cell(
        &self,
        c: usize,
        dofs: &DofMap,
        x: &[f64],
        co: &Coefficients,
        r: &mut [f64],
        k: &mut [f64],
    ) -> Result<(), Inadmissible> {
        if self.mesh.degree[c] == 1 {
            self.cell_n::<8>(&self.q1, c, dofs, x, co, r, k)
        } else {
            self.cell_n::<27>(&self.q2, c, dofs, x, co, r, k)
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn cell_n<const N: usize>(
        &self,
        tab: &Table3<N>,
        c: usize,
        dofs: &DofMap,
        x: &[f64],
        co: &Coefficients,
        r: &mut [f64],
        k: &mut [f64],
    ) -> Result<(), Inadmissible> {
        let mut pts = [Point::<3, N>::default(); MAX_POINTS_3D];
        let np = self.points(tab, c, &mut pts)?;
        let cd = dofs.cell(c);
        let mut u = [0.0; 81];
        for (slot, &d) in u.iter_mut().zip(&cd[..3 * N]) {
            *slot = x[d as usize];
        }
        let mut pe = [0.0; 4];
        let pressure = match self.pressure {
            PressureMode::None => CellPressure::None,
            PressureMode::Exact { .. } => {
                for (m, slot) in pe.iter_mut().enumerate() {
                    *slot = x[cd[3 * N + m] as usize];
                }
                CellPressure::Exact { p: &pe }
            }
            PressureMode::Perturbed { kappa, p0 } => CellPressure::Perturbed { kappa, p0 },
        };
        let law = CellLaw {
            material: &self.material,
            rho: self.rho,
            pressure,
            body_force: self.body_force.as_deref(),
            overstress: self.viscoelastic.as_ref().map(|ve| CellOverstress {
                law: ve,
                old: self.history.cell(c),
            }),
        };
        solid_cell::<Mat3, Material, 3, N>(&pts[..np], &u[..3 * N], &law, co, r, k)
    }

    /// The points of cell `c`'s stiffness rule (the points of [`Self::history`], in order):
    /// reference position X, weight w = w_q det J and ∇u from the full state `x` into `out`;
    /// returns how many.
    pub fn cell_point_gradients(
        &self,
        c: usize,
        dofs: &DofMap,
        x: &[f64],
        out: &mut [([f64; 3], f64, Mat3)],
    ) -> Result<usize, Inadmissible> {
        if self.mesh.degree[c] == 1 {
            self.cell_point_gradients_n::<8>(&self.q1, c, dofs, x, out)
        } else {
            self.cell_point_gradients_n::<27>(&self.q2, c, dofs, x, out)
        }
    }

    fn cell_point_gradients_n<const N: usize>(
        &self,
        tab: &Table3<N>,
        c: usize,
        dofs: &DofMap,
        x: &[f64],
        out: &mut [([f64; 3], f64, Mat3)],
    ) -> Result<usize, Inadmissible> {
        let mut pts = [Point::<3, N>::default(); MAX_POINTS_3D];
        let np = self.points(tab, c, &mut pts)?;
        let cd = dofs.cell(c);
        let mut u = [0.0; 81];
        for (slot, &d) in u.iter_mut().zip(&cd[..3 * N]) {
            *slot = x[d as usize];
        }
        for (o, pt) in out.iter_mut().zip(&pts[..np]) {
            *o = (pt.x, pt.w, grad_u::<Mat3, 3, N>(&u[..3 * N], &pt.g));
        }
        Ok(np)
    }

    /// `Σ_q w P_q,iJ G_aJ` of cell `c` for a first Piola–Kirchhoff stress `p[q]` at each point
    /// of its stiffness rule, handed to `add(dof, value)` for each of the cell's displacement
    /// dofs (full numbering).
    pub fn cell_divergence(
        &self,
        c: usize,
        dofs: &DofMap,
        p: &[Mat3],
        add: impl FnMut(usize, f64),
    ) -> Result<(), Inadmissible> {
        if self.mesh.degree[c] == 1 {
            self.cell_divergence_n::<8>(&self.q1, c, dofs, p, add)
        } else {
            self.cell_divergence_n::<27>(&self.q2, c, dofs, p, add)
        }
    }

    fn cell_divergence_n<const N: usize>(
        &self,
        tab: &Table3<N>,
        c: usize,
        dofs: &DofMap,
        p: &[Mat3],
        mut add: impl FnMut(usize, f64),
    ) -> Result<(), Inadmissible> {
        let mut pts = [Point::<3, N>::default(); MAX_POINTS_3D];
        let np = self.points(tab, c, &mut pts)?;
        let cd = dofs.cell(c);
        let mut r = [0.0; 81];
        for (pt, pq) in pts[..np].iter().zip(p) {
            for a in 0..N {
                for i in 0..3 {
                    let v: f64 = (0..3).map(|j| pq[(i, j)] * pt.g[a][j]).sum();
                    r[3 * a + i] += v * pt.w;
                }
            }
        }
        for (&d, &v) in cd[..3 * N].iter().zip(&r[..3 * N]) {
            add(d as usize, v);
        }
        Ok(())
    }

    /// Make the material viscoelastic: the history of every point of the stiffness rules,
    /// at the undisturbed reference state.
    pub fn set_viscoelastic(&mut self, ve: Viscoelastic) {
        let init = vec![0.0; ve.n_state_of::<Mat3>()];
        let per_cell = (0..self.mesh.n_cells()).map(|c| match self.mesh.degree[c] {
            1 => self.q1.points.len(),
            _ => self.q2.points.len(),
        });
        self.history = QpHistory::new(per_cell, &init);
        self.viscoelastic = Some(ve);
    }

    /// Replace the committed history by the state at the end of a step of length `dt` that
    /// ended at the full state `x` (call once the step has converged; `dt = ∞` relaxes it).
    /// Returns the overstress's work over the step and the energy its internal variables hold
    /// at the end, summed over the body (zeros when elastic).
    pub fn commit_history(&mut self, dofs: &DofMap, x: &[f64], dt: f64) -> ViscousStep {
        let Some(ve) = self.viscoelastic else {
            return ViscousStep::default();
        };
        let mut hist = std::mem::take(&mut self.history);
        let mut step = ViscousStep::default();
        for c in 0..self.mesh.n_cells() {
            let s = if self.mesh.degree[c] == 1 {
                self.commit_cell::<8>(&self.q1, &ve, c, dofs, x, dt, &mut hist)
            } else {
                self.commit_cell::<27>(&self.q2, &ve, c, dofs, x, dt, &mut hist)
            };
            step.work += s.work;
            step.stored += s.stored;
        }
        self.history = hist;
        step
    }

    #[allow(clippy::too_many_arguments)]
    fn commit_cell<const N: usize>(
        &self,
        tab: &Table3<N>,
        ve: &Viscoelastic,
        c: usize,
        dofs: &DofMap,
        x: &[f64],
        dt: f64,
        hist: &mut QpHistory,
    ) -> ViscousStep {
        let mut pts = [Point::<3, N>::default(); MAX_POINTS_3D];
        let Ok(np) = self.points(tab, c, &mut pts) else {
            return ViscousStep::default();
        };
        let cd = dofs.cell(c);
        let mut u = [0.0; 81];
        for (slot, &d) in u.iter_mut().zip(&cd[..3 * N]) {
            *slot = x[d as usize];
        }
        let n = hist.n_state;
        let mut new = [0.0; MAX_STATE_3D];
        let mut step = ViscousStep::default();
        for (q, pt) in pts[..np].iter().enumerate() {
            let h: Mat3 = grad_u::<Mat3, 3, N>(&u[..3 * N], &pt.g);
            let old = hist.point(c, q);
            ve.overstress(&h, old, dt, &mut new[..n], false);
            step.work += pt.w * ve.step_work_of::<Mat3>(old, &new[..n]);
            step.stored += pt.w * ve.stored_energy_of::<Mat3>(&new[..n]);
            hist.point_mut(c, q).copy_from_slice(&new[..n]);
        }
        step
    }

    /// The strain-rate damping η of cell `c` at the full state `x` with the full velocity `v`
    /// (∂v/∂x = `kv`), added to `r` and `k` as [`Self::cell`] lays them out
    /// ([`super::kernel::viscous_cell`]).
    #[allow(clippy::too_many_arguments)]
    pub fn cell_viscous(
        &self,
        c: usize,
        dofs: &DofMap,
        x: &[f64],
        v: &[f64],
        eta: f64,
        kv: f64,
        r: &mut [f64],
        k: &mut [f64],
    ) -> Result<(), Inadmissible> {
        if self.mesh.degree[c] == 1 {
            self.cell_viscous_n::<8>(&self.q1, c, dofs, x, v, eta, kv, r, k)
        } else {
            self.cell_viscous_n::<27>(&self.q2, c, dofs, x, v, eta, kv, r, k)
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn cell_viscous_n<const N: usize>(
        &self,
        tab: &Table3<N>,
        c: usize,
        dofs: &DofMap,
        x: &[f64],
        v: &[f64],
        eta: f64,
        kv: f64,
        r: &mut [f64],
        k: &mut [f64],
    ) -> Result<(), Inadmissible> {
        let mut pts = [Point::<3, N>::default(); MAX_POINTS_3D];
        let np = self.points(tab, c, &mut pts)?;
        let cd = dofs.cell(c);
        let (mut u, mut vl) = ([0.0; 81], [0.0; 81]);
        for (i, &d) in cd[..3 * N].iter().enumerate() {
            u[i] = x[d as usize];
            vl[i] = v[d as usize];
        }
        super::kernel::viscous_cell::<3, N>(
            &pts[..np],
            &u[..3 * N],
            &vl[..3 * N],
            eta,
            kv,
            r.len(),
            r,
            k,
        );
        Ok(())
    }

    /// The strain-rate damping η of cell `c` from its nodal displacements `u` and velocities
    /// `v` (3N each, node-major), as the steady mode takes it: the residual into `r` (its
    /// first 3N rows), unless `k` is empty the derivative in `u` at fixed `v` into `k` (row
    /// length `nd` ≥ 3N, the cell's columns first) and the derivative in `v` into `kv`
    /// (3N × 3N, row-major).
    #[allow(clippy::too_many_arguments)]
    pub fn cell_viscous_split(
        &self,
        c: usize,
        u: &[f64],
        v: &[f64],
        eta: f64,
        nd: usize,
        r: &mut [f64],
        k: &mut [f64],
        kv: &mut [f64],
    ) -> Result<(), Inadmissible> {
        if self.mesh.degree[c] == 1 {
            self.cell_viscous_split_n::<8>(&self.q1, c, u, v, eta, nd, r, k, kv)
        } else {
            self.cell_viscous_split_n::<27>(&self.q2, c, u, v, eta, nd, r, k, kv)
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn cell_viscous_split_n<const N: usize>(
        &self,
        tab: &Table3<N>,
        c: usize,
        u: &[f64],
        v: &[f64],
        eta: f64,
        nd: usize,
        r: &mut [f64],
        k: &mut [f64],
        kv: &mut [f64],
    ) -> Result<(), Inadmissible> {
        use super::kernel::viscous_cell_scaled;
        let mut pts = [Point::<3, N>::default(); MAX_POINTS_3D];
        let np = self.points(tab, c, &mut pts)?;
        let (u, v) = (&u[..3 * N], &v[..3 * N]);
        viscous_cell_scaled::<3, N>(&pts[..np], u, v, eta, 1.0, 0.0, nd, r, k);
        if !k.is_empty() {
            let mut scratch = [0.0; 81];
            viscous_cell_scaled::<3, N>(&pts[..np], u, v, eta, 0.0, 1.0, 3 * N, &mut scratch, kv);
        }
        Ok(())
    }

    /// Scalar mass matrix ρ0 ∫ N_a N_b dV of cell `c` (n × n row-major, n its node count) into
    /// `out`, with Gauss rules of 3 (Hex8) and 4 (Hex27) points per direction.
    pub fn cell_mass(&self, c: usize, out: &mut Vec<f64>) {
        if self.mesh.degree[c] == 1 {
            self.cell_mass_n::<8>(&self.m1, c, out)
        } else {
            self.cell_mass_n::<27>(&self.m2, c, out)
        }
    }

    fn cell_mass_n<const N: usize>(&self, tab: &Table3<N>, c: usize, out: &mut Vec<f64>) {
        out.clear();
        out.resize(N * N, 0.0);
        for (q, x) in tab.points.iter().enumerate() {
            let (_, jac) = self.mesh.map(c, *x);
            let w = tab.weights[q] * jac.determinant();
            let n = &tab.n[q];
            for a in 0..N {
                let wa = self.rho * w * n[a];
                for b in 0..N {
                    out[a * N + b] += wa * n[b];
                }
            }
        }
    }

    /// Strain energy ∫ W dV (compressible laws).
    pub fn strain_energy(&self, dofs: &DofMap, x: &[f64]) -> f64 {
        (0..self.mesh.n_cells())
            .map(|c| {
                let cd = dofs.cell(c);
                let mut u = [0.0; 81];
                for (slot, &d) in u.iter_mut().zip(cd) {
                    *slot = x[d as usize];
                }
                if self.mesh.degree[c] == 1 {
                    let mut pts = [Point::<3, 8>::default(); MAX_POINTS_3D];
                    let n = self.points(&self.q1, c, &mut pts).unwrap_or(0);
                    cell_energy::<Mat3, Material, 3, 8>(&pts[..n], &u[..24], &self.material)
                } else {
                    let mut pts = [Point::<3, 27>::default(); MAX_POINTS_3D];
                    let n = self.points(&self.q2, c, &mut pts).unwrap_or(0);
                    cell_energy::<Mat3, Material, 3, 27>(&pts[..n], &u[..81], &self.material)
                }
            })
            .sum()
    }

    /// Displacement and its gradient at reference point `xi` of cell `c`, with the Cauchy stress
    /// of the material (σ = P Fᵀ / J, the cell pressure included).
    pub fn point_values(
        &self,
        c: usize,
        dofs: &DofMap,
        x: &[f64],
        xi: [f64; 3],
    ) -> Option<PointValues3D> {
        let cn = self.mesh.cell_nodes(c);
        let nn = cn.len();
        let (mut n, mut dn) = ([0.0; 27], [[0.0; 3]; 27]);
        if self.mesh.degree[c] == 1 {
            Hex8::eval(xi, &mut n, &mut dn);
        } else {
            Hex27::eval(xi, &mut n, &mut dn);
        }
        let (xr, jac) = self.mesh.map(c, xi);
        let inv = jac.try_inverse()?;
        let cd = dofs.cell(c);
        let mut u = Vector3::zeros();
        let mut h = Mat3::zeros();
        for a in 0..nn {
            let g = Vector3::new(dn[a][0], dn[a][1], dn[a][2]).transpose() * inv;
            for i in 0..3 {
                let ua = x[cd[3 * a + i] as usize];
                u[i] += ua * n[a];
                for j in 0..3 {
                    h[(i, j)] += ua * g[j];
                }
            }
        }
        let f = Mat3::identity() + h;
        let jdet = f.determinant();
        if jdet <= 0.0 {
            return None;
        }
        let mut p = <Material as Hyperelastic<Mat3>>::stress(&self.material, &h);
        if let PressureMode::Exact { .. } | PressureMode::Perturbed { .. } = self.pressure {
            // The cell's pressure at the point (for outputs).
            let pr = self.cell_pressure(c, dofs, x, &xr)?;
            p -= crate::math::Tensor::cof(&f) * pr;
        }
        Some(PointValues3D {
            x: xr,
            u,
            grad_u: h,
            sigma: p * f.transpose() / jdet,
        })
    }

    /// The P1 pressure of cell `c` at reference position `xr` (the kernel's basis and, for the
    /// perturbed constraint, its condensed coefficients).
    fn cell_pressure(&self, c: usize, dofs: &DofMap, x: &[f64], xr: &Vector3<f64>) -> Option<f64> {
        if self.mesh.degree[c] == 1 {
            self.cell_pressure_n::<8>(&self.q1, c, dofs, x, xr)
        } else {
            self.cell_pressure_n::<27>(&self.q2, c, dofs, x, xr)
        }
    }

    fn cell_pressure_n<const N: usize>(
        &self,
        tab: &Table3<N>,
        c: usize,
        dofs: &DofMap,
        x: &[f64],
        xr: &Vector3<f64>,
    ) -> Option<f64> {
        let mut pts = [Point::<3, N>::default(); MAX_POINTS_3D];
        let np = self.points(tab, c, &mut pts).ok()?;
        let pts = &pts[..np];
        let frame = pressure_frame(pts);
        let cd = dofs.cell(c);
        let pc = match self.pressure {
            PressureMode::None => return Some(0.0),
            PressureMode::Exact { .. } => {
                let mut pc = Vector4::zeros();
                for (m, slot) in pc.iter_mut().enumerate() {
                    *slot = x[cd[3 * N + m] as usize];
                }
                pc
            }
            PressureMode::Perturbed { kappa, p0 } => {
                let mut u = [0.0; 81];
                for (slot, &d) in u.iter_mut().zip(&cd[..3 * N]) {
                    *slot = x[d as usize];
                }
                perturbed_pressure::<Mat3, 3, N>(pts, &u[..3 * N], kappa, p0, &frame)
                    .ok()?
                    .0
            }
        };
        Some(pc.dot(&p1_basis(&[xr[0], xr[1], xr[2]], &frame.0, frame.1)))
    }
}

/// Output values at a point of a hexahedral cell.
#[derive(Clone, Copy, Debug)]
pub struct PointValues3D {
    /// Reference position X.
    pub x: Vector3<f64>,
    pub u: Vector3<f64>,
    pub grad_u: Mat3,
    /// Cauchy stress σ = P Fᵀ / J.
    pub sigma: Mat3,
}
