//! The finite-strain plane-strain solid on the reference (θ-referential) mesh.
//!
//! Residual, for every test function η vanishing on the hub:
//!
//! ```text
//! R(χ; η) = ∫Ω0 P(∇u) : ∇η dV − ω² ∫Ω0 ρ0 ∂θχ · ∂θη dV − ∫Ω0 b · η dV   (+ pressure terms)
//! ```
//!
//! with χ = X + u, ∂θ(·) = t · ∇(·), t = (−X2, X1) the derivative along reference circles. The
//! inertia term is the paper's −ω² B(χ, η): the centripetal acceleration ω² ∂²θχ integrated by
//! parts along the closed circles. For steady spinning without contact, A(χ, η) = ω² B(χ, η).
//! Its tangent −ω² ∫ ρ0 ∂θN_a ∂θN_b δ_ik is the (negative) "spin-softening" matrix.
//!
//! Incompressible materials use Q2 displacements and discontinuous P1 pressures
//! q = [1, (X1 − Xc1)/h, (X2 − Xc2)/h] in reference coordinates (Xc: cell centre, h: cell size):
//! the stress is P = ∂W/∂F − p cof F and
//! * `Exact`: the constraint ∫ (J − 1) q dV = 0 per cell; p are global unknowns and the
//!   tangent is a symmetric saddle point (solved by LU);
//! * `Perturbed { kappa }`: p = p0 − κ Π(J − 1) per cell (Π: L2 projection onto P1, p0 the
//!   reference pressure that makes the unconstrained W stress free at F = I), eliminated at the
//!   cell level (static condensation): K* = Kuu + κ Kup M⁻¹ Kupᵀ with M = ∫ q qᵀ. As κ → ∞ this
//!   tends to the exact constraint.
//!
//! Cauchy stress: σ = P Fᵀ / J. Forces are per unit thickness (plane strain).
//!
//! **Viscoelastic history.** With [`SolidModel::viscoelastic`] set, the stress at each
//! quadrature point is `P = ∂W/∂F + P_v`, the overstress `P_v` of
//! [`crate::material::viscoelastic`] evaluated from the committed state of that point
//! ([`SolidModel::history`]) over the step [`SolidModel::history_dt`] (0 outside a time step:
//! the committed stress). Assembly never writes the history; the driver calls
//! [`SolidModel::commit_history`] once a step has converged (old state in, new state out).

use crate::assembly::{Assembler, DofMap, LocalSystem, QpHistory};
use crate::element::{Lagrange2D, ShapeTable, Q1, Q2};
use crate::material::viscoelastic::MAX_STATE;
use crate::material::{Hyperelastic, Material, Viscoelastic};
use crate::math::{cofactor, det_identity_plus_minus_one, v, Mat2, Tangent, Vec2};
use crate::mesh::{CellGeometry, Mesh};
use nalgebra::{Matrix3, Vector3};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::OnceLock;

/// How the incompressibility constraint (if any) is imposed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PressureMode {
    /// Compressible material: no pressure unknowns.
    None,
    /// Exact J = 1 (per cell, weakly) with global discontinuous P1 pressures.
    Exact { p0: f64 },
    /// Perturbed Lagrangian with bulk modulus κ, condensed per cell.
    Perturbed { kappa: f64, p0: f64 },
}

/// Body force per unit reference volume as a function of X (manufactured solutions).
pub type BodyForce = Box<dyn Fn(Vec2) -> Vec2 + Send + Sync>;

/// Material and density of one mesh region (see [`SolidModel::set_region_materials`]).
#[derive(Clone, Debug)]
pub struct RegionMaterial {
    pub material: Material,
    pub rho: f64,
    /// Reference pressure of an incompressible law (0 otherwise): the unconstrained W is not
    /// stress free at F = I, p0 = ½ tr ∂W/∂F(I) makes it so.
    pub p0: f64,
}

pub struct SolidModel {
    pub mesh: Mesh,
    /// The material of every cell when `region_materials` is empty; otherwise the first
    /// region's (used only for scales such as the small-strain shear modulus).
    pub material: Material,
    pub rho: f64,
    /// Material per mesh region (cell c uses `region_materials[mesh.regions[c]]`); empty: one
    /// material (`material`, `rho`) everywhere.
    pub region_materials: Vec<RegionMaterial>,
    /// ω² (rad²/s²).
    pub omega2: f64,
    pub pressure: PressureMode,
    pub body_force: Option<BodyForce>,
    /// Objective viscous damping on the rate of Green strain, S_v = η Ė (transient mode only;
    /// active when a velocity field is passed to [`Self::cell_system_viscous`]).
    pub strain_rate_damping: f64,
    /// Viscoelastic overstress (`None`: elastic, no history).
    pub viscoelastic: Option<Viscoelastic>,
    /// Committed history at the quadrature points (empty when elastic).
    pub history: QpHistory,
    /// Step length over which the kernels evaluate the overstress (0: committed state).
    pub history_dt: f64,
    q1: ShapeTable<4>,
    q2: ShapeTable<9>,
    /// Set by a kernel that met J ≤ 0 at a quadrature point.
    inverted: AtomicBool,
}

/// Output values at a point of a cell.
#[derive(Clone, Copy, Debug)]
pub struct PointValues {
    /// Reference position X.
    pub x: Vec2,
    /// Displacement u.
    pub u: Vec2,
    /// Cauchy stress σ = P Fᵀ / J.
    pub sigma: Mat2,
    pub grad_u: Mat2,
    /// dX/d(ξ, η).
    pub jac: Mat2,
}

/// How the nodal velocities of the strain-rate damping vary with the displacements, for the
/// tangent.
#[derive(Clone, Copy)]
enum VelocityMap<'a> {
    /// Time integration: δv_a = kv δu_a.
    Diagonal(f64),
    /// Steady mode: δv_m = ω Σ_b d[m N + b] δu_b, d the cell's own θ-derivative.
    CellDerivative { omega: f64, d: &'a [f64] },
}

/// Nodal velocities (full vector) of the strain-rate damping and their linearisation.
#[derive(Clone, Copy)]
struct Visc<'a> {
    vel: &'a [f64],
    map: VelocityMap<'a>,
}

/// Values at one quadrature point needed by the kernels.
struct PointGeom {
    x: Vec2,
    w: f64,
}

impl SolidModel {
    pub fn new(mesh: Mesh, material: Material, rho: f64, pressure: PressureMode) -> Self {
        Self {
            mesh,
            material,
            rho,
            region_materials: Vec::new(),
            omega2: 0.0,
            pressure,
            body_force: None,
            strain_rate_damping: 0.0,
            viscoelastic: None,
            history: QpHistory::none(),
            history_dt: 0.0,
            q1: ShapeTable::gauss::<Q1>(2),
            q2: ShapeTable::gauss::<Q2>(3),
            inverted: AtomicBool::new(false),
        }
    }

    /// One material per mesh region. The pressure treatment (`pressure`) is common to all
    /// regions; each region's reference pressure p0 comes with its material.
    pub fn set_region_materials(&mut self, regions: Vec<RegionMaterial>) {
        if let Some(r) = regions.first() {
            self.material = r.material;
            self.rho = r.rho;
        }
        self.region_materials = regions;
    }

    /// Material of cell `c`.
    #[inline]
    pub fn material_of(&self, c: usize) -> &Material {
        self.region_materials
            .get(self.mesh.regions[c] as usize)
            .map_or(&self.material, |r| &r.material)
    }

    /// Density of cell `c`.
    #[inline]
    pub fn rho_of(&self, c: usize) -> f64 {
        match self.region_materials.get(self.mesh.regions[c] as usize) {
            Some(r) => r.rho,
            None => self.rho,
        }
    }

    /// Reference pressure of cell `c` (0 for a compressible model).
    #[inline]
    pub fn p0_of(&self, c: usize) -> f64 {
        match (
            self.pressure,
            self.region_materials.get(self.mesh.regions[c] as usize),
        ) {
            (PressureMode::None, _) => 0.0,
            (_, Some(r)) => r.p0,
            _ => self.p0(),
        }
    }

    /// Cell-owned unknowns per cell.
    pub fn dofs_per_cell(&self) -> usize {
        match self.pressure {
            PressureMode::Exact { .. } => 3,
            _ => 0,
        }
    }

    /// Reference pressure of an incompressible model (0 otherwise).
    pub fn p0(&self) -> f64 {
        match self.pressure {
            PressureMode::Exact { p0 } | PressureMode::Perturbed { p0, .. } => p0,
            PressureMode::None => 0.0,
        }
    }

    /// Initial full vector: zero displacement, pressures at the reference pressure.
    pub fn initial_state(&self, dofs: &DofMap) -> Vec<f64> {
        let mut x = vec![0.0; dofs.n_full()];
        if dofs.per_cell == 3 {
            for c in 0..self.mesh.n_cells() {
                x[dofs.n_u + 3 * c] = self.p0_of(c);
            }
        }
        x
    }

    /// Assemble residual (and tangent) at the full state `x`. Returns `false` if some
    /// quadrature point had J ≤ 0 (the state is inadmissible).
    pub fn assemble(
        &self,
        asm: &mut Assembler,
        dofs: &DofMap,
        x: &[f64],
        with_matrix: bool,
    ) -> bool {
        self.inverted.store(false, Ordering::Relaxed);
        asm.assemble(dofs, with_matrix, |c, loc| {
            self.cell_kernel(c, dofs, x, loc, with_matrix, None, None)
        });
        !self.inverted.load(Ordering::Relaxed)
    }

    /// Scalar mass matrix ρ0 ∫ N_a N_b dV of cell `c` (row-major, `n × n` with n the cell's node
    /// count), with (p + 2)² Gauss points (N_a N_b det J has degree 2p + 1 per direction on the
    /// polar map: exact).
    pub fn cell_mass(&self, c: usize, out: &mut Vec<f64>) {
        match self.mesh.degree[c] {
            1 => self.cell_mass_generic::<Q1, 4>(c, 3, out),
            _ => self.cell_mass_generic::<Q2, 9>(c, 4, out),
        }
    }

    fn cell_mass_generic<E: Lagrange2D, const N: usize>(
        &self,
        c: usize,
        q: usize,
        out: &mut Vec<f64>,
    ) {
        let tab = ShapeTable::<N>::gauss::<E>(q);
        out.clear();
        out.resize(N * N, 0.0);
        for k in 0..tab.len() {
            let (xi, eta) = tab.points[k];
            let (_, jac) = self.map(c, xi, eta, &tab.n[k], &tab.dn[k]);
            let w = tab.weights[k] * jac.determinant() * self.rho_of(c);
            for a in 0..N {
                for b in 0..N {
                    out[a * N + b] += tab.n[k][a] * tab.n[k][b] * w;
                }
            }
        }
    }

    /// HRZ lumping of a cell mass matrix (`n × n`): diagonal entries scaled so that they sum to
    /// the cell mass. Positive for Q2 (row-sum lumping gives zero or negative corner masses).
    pub fn hrz_lump(m: &[f64], n: usize) -> Vec<f64> {
        let total: f64 = m.iter().sum();
        let diag: f64 = (0..n).map(|a| m[a * n + a]).sum();
        (0..n).map(|a| m[a * n + a] * total / diag).collect()
    }

    /// Clear the "inadmissible state met" flag before a custom assembly with [`Self::cell_system`].
    pub fn reset_admissible(&self) {
        self.inverted.store(false, Ordering::Relaxed);
    }
    /// Whether no quadrature point met J ≤ 0 since [`Self::reset_admissible`].
    pub fn admissible(&self) -> bool {
        !self.inverted.load(Ordering::Relaxed)
    }

    /// Local residual and tangent of cell `c` at state `x` (static part: internal work,
    /// θ-referential inertia, body force, pressure terms).
    pub fn cell_system(
        &self,
        c: usize,
        dofs: &DofMap,
        x: &[f64],
        loc: &mut LocalSystem,
        with_k: bool,
    ) {
        self.cell_kernel(c, dofs, x, loc, with_k, None, None);
    }

    /// As [`Self::cell_system`] plus the viscous stress P_v = F S_v, S_v = η Ė with
    /// Ė = ½(Ḟᵀ F + Fᵀ Ḟ), Ḟ = ∇v; `vel` is the full velocity vector and `kv` = ∂v/∂u of the
    /// time integrator (the tangent includes both the F and the Ḟ dependence). Ė vanishes for a
    /// rigid rotation (Ḟ = W F with W skew), so rigid spinning is not damped.
    #[allow(clippy::too_many_arguments)]
    pub fn cell_system_viscous(
        &self,
        c: usize,
        dofs: &DofMap,
        x: &[f64],
        vel: &[f64],
        kv: f64,
        loc: &mut LocalSystem,
        with_k: bool,
    ) {
        let visc = (self.strain_rate_damping > 0.0).then_some(Visc {
            vel,
            map: VelocityMap::Diagonal(kv),
        });
        self.cell_kernel(c, dofs, x, loc, with_k, visc, None);
    }

    /// The steady mode's cell system with the strain-rate damping: as
    /// [`Self::cell_system_viscous`] with the nodal velocities `vel` = ω ∂θχ (full vector,
    /// computed by the caller from a nodal θ-derivative that may reach beyond the cell). The
    /// tangent takes the velocities' dependence on the displacements through the cell's own
    /// θ-derivative `d` (N × N row-major, (∂θf)(X_m) ≈ Σ_b d[m N + b] f_b, from
    /// [`Self::cell_theta_derivative`]): an approximation of the exact coupling that keeps
    /// the cell's sparsity (none with `omega` = 0: the caller then linearises the
    /// velocities itself). With `av`, the derivative of the cell residual with respect to
    /// the cell's nodal velocities is written there (2N × 2N row-major), from which the
    /// caller applies the rest of the exact tangent matrix-free.
    #[allow(clippy::too_many_arguments)]
    pub fn cell_system_steady_viscous(
        &self,
        c: usize,
        dofs: &DofMap,
        x: &[f64],
        vel: &[f64],
        omega: f64,
        d: &[f64],
        loc: &mut LocalSystem,
        with_k: bool,
        av: Option<&mut [f64; 324]>,
    ) {
        let visc = (self.strain_rate_damping > 0.0).then_some(Visc {
            vel,
            map: VelocityMap::CellDerivative { omega, d },
        });
        self.cell_kernel(c, dofs, x, loc, with_k, visc, av);
    }

    /// The cell's own θ-derivative at its nodes: d[m N + b] = ∇N_b(X_m) · (−X_m2, X_m1),
    /// ∂θ = −X2 ∂1 + X1 ∂2 the derivative along the reference circles, so that
    /// (∂θf)(X_m) ≈ Σ_b d[m N + b] f_b for the interpolant of the nodal values f_b. Exact for
    /// fields the element reproduces; one-sided at the cell's edges. `None` if the cell map
    /// is degenerate at a node.
    pub fn cell_theta_derivative(&self, c: usize) -> Option<Vec<f64>> {
        // The shape functions at the reference nodes, the same for every cell.
        static NODAL: OnceLock<(ShapeTable<4>, ShapeTable<9>)> = OnceLock::new();
        let (q1, q2) = NODAL.get_or_init(|| {
            (
                ShapeTable::<4>::new::<Q1>((0..4).map(Q1::node_ref).collect(), vec![1.0; 4]),
                ShapeTable::<9>::new::<Q2>((0..9).map(Q2::node_ref).collect(), vec![1.0; 9]),
            )
        });
        match self.mesh.degree[c] {
            1 => self.cell_theta_derivative_generic(q1, c),
            _ => self.cell_theta_derivative_generic(q2, c),
        }
    }

    fn cell_theta_derivative_generic<const N: usize>(
        &self,
        tab: &ShapeTable<N>,
        c: usize,
    ) -> Option<Vec<f64>> {
        let mut g = [[0.0; 2]; N];
        let mut d = vec![0.0; N * N];
        for m in 0..N {
            let pg = self.point(c, tab, m, &mut g)?;
            let t = [-pg.x[1], pg.x[0]];
            for b in 0..N {
                d[m * N + b] = g[b][0] * t[0] + g[b][1] * t[1];
            }
        }
        Some(d)
    }

    /// Strain energy ∫ W(∇u) dV of the whole mesh at state `x` (displacement part only).
    pub fn strain_energy(&self, dofs: &DofMap, x: &[f64]) -> f64 {
        let mut e = 0.0;
        for c in 0..self.mesh.n_cells() {
            let (pts, ws) = crate::element::gauss_1d(3);
            for (i, xi) in pts.iter().enumerate() {
                for (j, eta) in pts.iter().enumerate() {
                    if let Some(pv) = self.point_values(c, dofs, x, *xi, *eta) {
                        e += self.material_of(c).energy(&pv.grad_u)
                            * ws[i]
                            * ws[j]
                            * pv.jac.determinant();
                    }
                }
            }
        }
        e
    }

    /// Local residual of cell `c` at state `x` (including rows of fixed dofs: reactions).
    pub fn cell_residual(&self, c: usize, dofs: &DofMap, x: &[f64], loc: &mut LocalSystem) {
        self.cell_kernel(c, dofs, x, loc, false, None, None);
    }

    #[allow(clippy::too_many_arguments)]
    fn cell_kernel(
        &self,
        c: usize,
        dofs: &DofMap,
        x: &[f64],
        loc: &mut LocalSystem,
        with_k: bool,
        visc: Option<Visc<'_>>,
        av: Option<&mut [f64; 324]>,
    ) {
        match self.mesh.degree[c] {
            1 => self.cell_generic::<4>(&self.q1, c, dofs, x, loc, with_k, visc, av),
            _ => self.cell_generic::<9>(&self.q2, c, dofs, x, loc, with_k, visc, av),
        }
    }

    /// Reference position and Jacobian dX/dξ at a point of cell `c`.
    #[inline]
    fn map<const N: usize>(
        &self,
        c: usize,
        xi: f64,
        eta: f64,
        n: &[f64; N],
        dn: &[[f64; 2]; N],
    ) -> (Vec2, Mat2) {
        if let Some(m) = self.mesh.geometry[c].polar_map(xi, eta) {
            return m;
        }
        let nodes = self.mesh.cell_nodes(c);
        let mut x = Vec2::zeros();
        let mut j = Mat2::zeros();
        for a in 0..N {
            let p = self.mesh.nodes[nodes[a] as usize];
            x += p * n[a];
            j[(0, 0)] += p[0] * dn[a][0];
            j[(0, 1)] += p[0] * dn[a][1];
            j[(1, 0)] += p[1] * dn[a][0];
            j[(1, 1)] += p[1] * dn[a][1];
        }
        (x, j)
    }

    /// Centre and size of cell `c` for the P1 pressure basis.
    fn pressure_frame(&self, c: usize) -> (Vec2, f64) {
        let (xc, j) = match self.mesh.geometry[c] {
            g @ CellGeometry::Polar { .. } => g
                .polar_map(0.0, 0.0)
                .unwrap_or((Vec2::zeros(), Mat2::identity())),
            CellGeometry::Isoparametric => {
                let nodes = self.mesh.cell_nodes(c);
                let xc = nodes
                    .iter()
                    .map(|&n| self.mesh.nodes[n as usize])
                    .sum::<Vec2>()
                    / nodes.len() as f64;
                (xc, Mat2::identity())
            }
        };
        let h = if matches!(self.mesh.geometry[c], CellGeometry::Polar { .. }) {
            2.0 * j.determinant().abs().sqrt()
        } else {
            let nodes = self.mesh.cell_nodes(c);
            let (a, b) = (
                self.mesh.nodes[nodes[0] as usize],
                self.mesh.nodes[nodes[nodes.len() - 1] as usize],
            );
            (a - b).norm()
        };
        (xc, h.max(f64::MIN_POSITIVE))
    }

    #[inline]
    fn pbasis(x: &Vec2, xc: &Vec2, h: f64) -> Vector3<f64> {
        Vector3::new(1.0, (x[0] - xc[0]) / h, (x[1] - xc[1]) / h)
    }

    /// Shape gradients with respect to X, the point's position and its weight · det J.
    #[inline]
    #[allow(clippy::needless_range_loop)] // Index loops spell out the index notation (r_a^i, K_ab^ik) of the kernel.
    fn point<const N: usize>(
        &self,
        c: usize,
        tab: &ShapeTable<N>,
        q: usize,
        g: &mut [[f64; 2]; N],
    ) -> Option<PointGeom> {
        let (xi, eta) = tab.points[q];
        let (x, jac) = self.map(c, xi, eta, &tab.n[q], &tab.dn[q]);
        let det = jac.determinant();
        let inv = jac.try_inverse()?;
        for a in 0..N {
            let d = tab.dn[q][a];
            g[a] = [
                d[0] * inv[(0, 0)] + d[1] * inv[(1, 0)],
                d[0] * inv[(0, 1)] + d[1] * inv[(1, 1)],
            ];
        }
        Some(PointGeom {
            x,
            w: tab.weights[q] * det,
        })
    }

    #[inline]
    fn grad_u<const N: usize>(u: &[f64], g: &[[f64; 2]; N]) -> Mat2 {
        let mut h = Mat2::zeros();
        for a in 0..N {
            let (ux, uy) = (u[2 * a], u[2 * a + 1]);
            h[(0, 0)] += ux * g[a][0];
            h[(0, 1)] += ux * g[a][1];
            h[(1, 0)] += uy * g[a][0];
            h[(1, 1)] += uy * g[a][1];
        }
        h
    }

    /// Condensed pressure coefficients of a perturbed-Lagrangian cell: p = p0 e0 − κ M⁻¹ g.
    fn perturbed_pressure<const N: usize>(
        &self,
        c: usize,
        tab: &ShapeTable<N>,
        u: &[f64],
        kappa: f64,
        p0: f64,
    ) -> Option<(Vector3<f64>, Matrix3<f64>)> {
        let (xc, h) = self.pressure_frame(c);
        let mut m = Matrix3::zeros();
        let mut gv = Vector3::zeros();
        let mut g = [[0.0; 2]; N];
        for q in 0..tab.len() {
            let pg = self.point(c, tab, q, &mut g)?;
            let qv = Self::pbasis(&pg.x, &xc, h);
            let jm1 = det_identity_plus_minus_one(&Self::grad_u(u, &g));
            m += qv * qv.transpose() * pg.w;
            gv += qv * (jm1 * pg.w);
        }
        let minv = m.try_inverse()?;
        let mut p = -kappa * (minv * gv);
        p[0] += p0;
        Some((p, minv))
    }

    #[allow(clippy::too_many_arguments, clippy::needless_range_loop)] // Index loops spell out the index notation (r_a^i, K_ab^ik) of the kernel.
    fn cell_generic<const N: usize>(
        &self,
        tab: &ShapeTable<N>,
        c: usize,
        dofs: &DofMap,
        x: &[f64],
        loc: &mut LocalSystem,
        with_k: bool,
        visc: Option<Visc<'_>>,
        mut av: Option<&mut [f64; 324]>,
    ) {
        let cd = dofs.cell(c);
        let nd = cd.len();
        let nu = 2 * N;
        let mut u = [0.0; 18];
        for a in 0..nu {
            u[a] = x[cd[a] as usize];
        }
        let u = &u[..nu];
        let mut vloc = [0.0; 18];
        // Velocity dependence: δv_a = kv δu_a (time integration), or
        // δv_m = ω Σ_b d_mb δu_b (steady, the cell's θ-derivative).
        let (mut kv, mut steady_d, mut omega) = (0.0, None, 0.0);
        if let Some(vc) = &visc {
            for a in 0..nu {
                vloc[a] = vc.vel[cd[a] as usize];
            }
            match vc.map {
                VelocityMap::Diagonal(k) => kv = k,
                VelocityMap::CellDerivative { omega: om, d } => {
                    steady_d = Some(d);
                    omega = om;
                }
            }
        }
        if let Some(a) = av.as_deref_mut() {
            a[..nu * nu].fill(0.0);
        }
        // Pressure coefficients of this cell.
        let mut pc = Vector3::zeros();
        let mut minv = Matrix3::zeros();
        let (has_p, exact, kappa) = match self.pressure {
            PressureMode::None => (false, false, 0.0),
            PressureMode::Exact { .. } => {
                pc = Vector3::new(
                    x[cd[nu] as usize],
                    x[cd[nu + 1] as usize],
                    x[cd[nu + 2] as usize],
                );
                (true, true, 0.0)
            }
            PressureMode::Perturbed { kappa, .. } => {
                match self.perturbed_pressure::<N>(c, tab, u, kappa, self.p0_of(c)) {
                    Some((p, mi)) => {
                        pc = p;
                        minv = mi;
                        (true, false, kappa)
                    }
                    None => {
                        self.inverted.store(true, Ordering::Relaxed);
                        return;
                    }
                }
            }
        };
        let (xc, hc) = if has_p {
            self.pressure_frame(c)
        } else {
            (Vec2::zeros(), 1.0)
        };
        let dcof = crate::material::invariants::dcof_df();
        let rw2 = self.rho_of(c) * self.omega2;
        let material = self.material_of(c);
        // Kup for condensation (perturbed): 18 × 3.
        let mut kup = [[0.0f64; 3]; 18];
        // The displacement block of the cell matrix and ∂r/∂v of the steady damping
        // (2N × 2N), accumulated over the points in the layout ((a, i, k), b).
        let mut kb = [0.0f64; 324];
        let mut avl = [0.0f64; 324];
        let mut g = [[0.0; 2]; N];
        for q in 0..tab.len() {
            let Some(pg) = self.point(c, tab, q, &mut g) else {
                self.inverted.store(true, Ordering::Relaxed);
                return;
            };
            let h = Self::grad_u(u, &g);
            let jm1 = det_identity_plus_minus_one(&h);
            if jm1 <= -1.0 || !jm1.is_finite() {
                self.inverted.store(true, Ordering::Relaxed);
                return;
            }
            let w = pg.w;
            let (mut p_st, mut a_t) = if with_k {
                material.stress_tangent(&h)
            } else {
                (material.stress(&h), Tangent::zeros())
            };
            if let Some(ve) = &self.viscoelastic {
                let mut new = [0.0; MAX_STATE];
                let old = self.history.point(c, q);
                let (pv, av) = ve.overstress(&h, old, self.history_dt, &mut new, with_k);
                p_st += pv;
                a_t += av;
            }
            // ∂P/∂(∇v) of the damping, when the velocities are not a multiple of the cell's own
            // displacements (steady mode).
            let mut a_l = Tangent::zeros();
            if visc.is_some() {
                // Viscous stress on the Green-strain rate (objective).
                let eta = self.strain_rate_damping;
                let f = Mat2::identity() + h;
                let fd = Self::grad_u(&vloc[..nu], &g);
                let sv = (fd.transpose() * f + f.transpose() * fd) * (0.5 * eta);
                p_st += f * sv;
                if with_k {
                    let (dp_h, dp_l) = strain_rate_damping_tangents(&f, &fd, &sv, eta);
                    a_t += dp_h;
                    if steady_d.is_some() {
                        a_l = dp_l;
                    } else {
                        a_t += dp_l * kv;
                    }
                }
            }
            let mut qv = Vector3::zeros();
            let mut cof = Mat2::zeros();
            if has_p {
                qv = Self::pbasis(&pg.x, &xc, hc);
                let p = pc.dot(&qv);
                cof = cofactor(&(Mat2::identity() + h));
                p_st -= cof * p;
                if with_k {
                    a_t -= dcof * p;
                }
            }
            // θ-referential inertia: ∂θχ = t + H t.
            let t = Vec2::new(-pg.x[1], pg.x[0]);
            let dth = t + h * t;
            let bf = self.body_force.as_ref().map(|f| f(pg.x));
            let nv = &tab.n[q];
            for a in 0..N {
                let ta = t[0] * g[a][0] + t[1] * g[a][1];
                for i in 0..2 {
                    let mut r = p_st[(i, 0)] * g[a][0] + p_st[(i, 1)] * g[a][1] - rw2 * dth[i] * ta;
                    if let Some(b) = bf {
                        r -= b[i] * nv[a];
                    }
                    loc.r[2 * a + i] += r * w;
                }
            }
            if has_p {
                // Constraint rows (exact only) and Kup.
                for a in 0..N {
                    for i in 0..2 {
                        let cg = cof[(i, 0)] * g[a][0] + cof[(i, 1)] * g[a][1];
                        for m in 0..3 {
                            kup[2 * a + i][m] -= cg * qv[m] * w;
                        }
                    }
                }
                if exact {
                    for m in 0..3 {
                        loc.r[nu + m] -= jm1 * qv[m] * w;
                    }
                }
            }
            if !with_k {
                continue;
            }
            // Kuu: Σ G_aJ A_{iJ,kL} G_bL − ρω² T_a T_b δ_ik, into the blocked layout of `kb`
            // (row (a, i, k), column b: contiguous in b, so that the inner loops vectorise).
            let (mut gx, mut gy, mut tg) = ([0.0; N], [0.0; N], [0.0; N]);
            for b in 0..N {
                gx[b] = g[b][0];
                gy[b] = g[b][1];
                tg[b] = t[0] * g[b][0] + t[1] * g[b][1];
            }
            add_gag(&mut kb, &a_t, &g, &gx, &gy, w, Some((rw2, &tg)));
            if steady_d.is_some() {
                // Steady damping through the velocities, per nodal velocity:
                // A_ab = Σ_J G_aJ A^L_{iJ,kL} G_bL (the derivative of the cell residual with
                // respect to the cell's nodal velocities, same layout as `kb`); its product
                // with the velocities' dependence on the displacements is added after the
                // quadrature loop.
                add_gag(&mut avl, &a_l, &g, &gx, &gy, w, None);
            }
        }
        if with_k {
            if let Some(d) = steady_d {
                // K_ab += Σ_m A_am ω d_mb: the velocities' gradient per δu_b is
                // G̃_b = ω Σ_m d_mb G_m (the gradient of the velocity interpolant).
                // (ω = 0: the caller linearises the velocities itself.)
                if omega != 0.0 {
                    for r in 0..2 * nu {
                        let (arow, krow) = (&avl[r * N..(r + 1) * N], &mut kb[r * N..(r + 1) * N]);
                        for m in 0..N {
                            let am = omega * arow[m];
                            let dm = &d[m * N..(m + 1) * N];
                            for b in 0..N {
                                krow[b] += am * dm[b];
                            }
                        }
                    }
                }
                if let Some(avm) = av {
                    for r in 0..nu {
                        for b in 0..N {
                            for k in 0..2 {
                                avm[r * nu + 2 * b + k] = avl[(r * 2 + k) * N + b];
                            }
                        }
                    }
                }
            }
            for r in 0..nu {
                let krow = &mut loc.k[r * nd..r * nd + nu];
                for b in 0..N {
                    for k in 0..2 {
                        krow[2 * b + k] += kb[(r * 2 + k) * N + b];
                    }
                }
            }
        }
        if has_p && with_k {
            if exact {
                for r in 0..nu {
                    for m in 0..3 {
                        loc.k[r * nd + nu + m] += kup[r][m];
                        loc.k[(nu + m) * nd + r] += kup[r][m];
                    }
                }
            } else {
                // Static condensation: K* = Kuu + κ Kup M⁻¹ Kupᵀ.
                for r in 0..nu {
                    let mut km = [0.0; 3];
                    for n in 0..3 {
                        km[n] = kappa * (0..3).map(|m| kup[r][m] * minv[(m, n)]).sum::<f64>();
                    }
                    for s in 0..nu {
                        loc.k[r * nd + s] +=
                            km[0] * kup[s][0] + km[1] * kup[s][1] + km[2] * kup[s][2];
                    }
                }
            }
        }
    }

    /// Geometry Jacobian dX/d(ξ, η) at a point of cell `c`.
    pub fn point_values_geometry(&self, c: usize, xi: f64, eta: f64) -> Option<Mat2> {
        match self.mesh.degree[c] {
            1 => {
                let t = ShapeTable::<4>::new::<Q1>(vec![(xi, eta)], vec![1.0]);
                Some(self.map(c, xi, eta, &t.n[0], &t.dn[0]).1)
            }
            _ => {
                let t = ShapeTable::<9>::new::<Q2>(vec![(xi, eta)], vec![1.0]);
                Some(self.map(c, xi, eta, &t.n[0], &t.dn[0]).1)
            }
        }
    }

    /// Reference position, displacement, Cauchy stress and geometry Jacobian at reference point
    /// (ξ, η) of cell `c`. `None` if the point is degenerate.
    pub fn point_values(
        &self,
        c: usize,
        dofs: &DofMap,
        x: &[f64],
        xi: f64,
        eta: f64,
    ) -> Option<PointValues> {
        match self.mesh.degree[c] {
            1 => self.point_values_generic::<Q1, 4>(c, dofs, x, xi, eta),
            _ => self.point_values_generic::<Q2, 9>(c, dofs, x, xi, eta),
        }
    }

    #[allow(clippy::needless_range_loop)] // a: local node, as in the kernels.
    fn point_values_generic<E: Lagrange2D, const N: usize>(
        &self,
        c: usize,
        dofs: &DofMap,
        x: &[f64],
        xi: f64,
        eta: f64,
    ) -> Option<PointValues> {
        // Shape values at the point (no allocation: output loops call this per point).
        let mut sn = [0.0; N];
        let mut sdn = [[0.0; 2]; N];
        E::eval(xi, eta, &mut sn, &mut sdn);
        let cd = dofs.cell(c);
        let nu = 2 * N;
        let mut ub = [0.0; 18];
        for a in 0..nu {
            ub[a] = x[cd[a] as usize];
        }
        let u = &ub[..nu];
        let (px, jac) = self.map(c, xi, eta, &sn, &sdn);
        let inv = jac.try_inverse()?;
        let mut g = [[0.0; 2]; N];
        for a in 0..N {
            let d = sdn[a];
            g[a] = [
                d[0] * inv[(0, 0)] + d[1] * inv[(1, 0)],
                d[0] * inv[(0, 1)] + d[1] * inv[(1, 1)],
            ];
        }
        let h = Self::grad_u(u, &g);
        let mut disp = Vec2::zeros();
        for a in 0..N {
            disp += Vec2::new(u[2 * a], u[2 * a + 1]) * sn[a];
        }
        let mut p_st = self.material_of(c).stress(&h);
        let f = Mat2::identity() + h;
        let pcoef = match self.pressure {
            PressureMode::None => None,
            PressureMode::Exact { .. } => Some(Vector3::new(
                x[cd[nu] as usize],
                x[cd[nu + 1] as usize],
                x[cd[nu + 2] as usize],
            )),
            PressureMode::Perturbed { kappa, .. } => {
                let p0 = self.p0_of(c);
                let rule = if N == 9 {
                    &self.q2 as &dyn std::any::Any
                } else {
                    &self.q1 as &dyn std::any::Any
                };
                let tab_c = rule.downcast_ref::<ShapeTable<N>>()?;
                self.perturbed_pressure::<N>(c, tab_c, u, kappa, p0)
                    .map(|(p, _)| p)
            }
        };
        if let Some(pc) = pcoef {
            let (xc, hc) = self.pressure_frame(c);
            p_st -= cofactor(&f) * pc.dot(&Self::pbasis(&px, &xc, hc));
        }
        let j = 1.0 + det_identity_plus_minus_one(&h);
        let sigma = p_st * f.transpose() / j;
        Some(PointValues {
            x: px,
            u: disp,
            sigma,
            grad_u: h,
            jac,
        })
    }
}

/// The viscous overstress's energy over one committed step, summed over the body (per unit
/// thickness, the scene's energy unit): its work `∫ S_v : Ė dV dt` (trapezoidal in time) and
/// the energy its internal variables hold at the end of the step
/// ([`Viscoelastic::stored_energy`]). Work minus the change in stored energy is the
/// dissipation, which a physical model keeps non-negative.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ViscousStep {
    pub work: f64,
    pub stored: f64,
}

// Viscoelastic history: allocation and commit (the kernels only read it).
impl SolidModel {
    /// Gauss points per direction of the kernels' rule on cell `c` (2 for Q1, 3 for Q2): the
    /// points of [`Self::history`] (point `l · q + i` at `(ξ_i, η_l)`).
    pub fn qp_per_direction(&self, c: usize) -> usize {
        match self.mesh.degree[c] {
            1 => 2,
            _ => 3,
        }
    }

    /// Geometry of quadrature point `q` of cell `c` in the kernels' rule: reference position
    /// X, weight w = w_q det(dX/dξ), and the reference gradients ∂N_a/∂X of the cell's shape
    /// functions in `g` (first `n` entries, n = nodes of the cell). `None` for a degenerate cell.
    pub fn qp_geometry(&self, c: usize, q: usize, g: &mut [[f64; 2]; 9]) -> Option<(Vec2, f64)> {
        match self.mesh.degree[c] {
            1 => {
                let mut g4 = [[0.0; 2]; 4];
                let pg = self.point(c, &self.q1, q, &mut g4)?;
                g[..4].copy_from_slice(&g4);
                Some((pg.x, pg.w))
            }
            _ => {
                let pg = self.point(c, &self.q2, q, g)?;
                Some((pg.x, pg.w))
            }
        }
    }

    /// Make the material viscoelastic: allocate the history of every quadrature point of the
    /// kernels' Gauss rules, at the undisturbed reference state.
    pub fn set_viscoelastic(&mut self, ve: Viscoelastic) {
        let init = vec![0.0; ve.n_state()];
        let per_cell = (0..self.mesh.n_cells()).map(|c| match self.mesh.degree[c] {
            1 => self.q1.len(),
            _ => self.q2.len(),
        });
        self.history = QpHistory::new(per_cell, &init);
        self.viscoelastic = Some(ve);
    }

    /// Replace the committed history by the state at the end of a step of length `dt` that
    /// ended at the full state `x` (call once the step has converged). No-op when elastic.
    /// Returns the overstress's work over the step and the energy its internal variables hold
    /// at the end, summed over the body ([`ViscousStep`]; zeros when elastic).
    pub fn commit_history(&mut self, dofs: &DofMap, x: &[f64], dt: f64) -> ViscousStep {
        let Some(ve) = self.viscoelastic else {
            return ViscousStep::default();
        };
        let mut hist = std::mem::take(&mut self.history);
        let mut step = ViscousStep::default();
        for c in 0..self.mesh.n_cells() {
            let s = match self.mesh.degree[c] {
                1 => self.commit_cell::<4>(&self.q1, &ve, c, dofs, x, dt, &mut hist),
                _ => self.commit_cell::<9>(&self.q2, &ve, c, dofs, x, dt, &mut hist),
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
        tab: &ShapeTable<N>,
        ve: &Viscoelastic,
        c: usize,
        dofs: &DofMap,
        x: &[f64],
        dt: f64,
        hist: &mut QpHistory,
    ) -> ViscousStep {
        let cd = dofs.cell(c);
        let mut u = [0.0; 18];
        for a in 0..2 * N {
            u[a] = x[cd[a] as usize];
        }
        let mut g = [[0.0; 2]; N];
        let mut new = [0.0; MAX_STATE];
        let n = hist.n_state;
        let mut step = ViscousStep::default();
        for q in 0..tab.len() {
            let Some(pg) = self.point(c, tab, q, &mut g) else {
                continue;
            };
            let h = Self::grad_u(&u[..2 * N], &g);
            let old = hist.point(c, q);
            ve.overstress(&h, old, dt, &mut new[..n], false);
            step.work += pg.w * ve.step_work(old, &new[..n]);
            step.stored += pg.w * ve.stored_energy(&new[..n]);
            hist.point_mut(c, q).copy_from_slice(&new[..n]);
        }
        step
    }
}

/// Adds one quadrature point's Σ_JL G_aJ A_{iJ,kL} G_bL w to `dst` in the layout of
/// `cell_generic`'s blocks (row (a, i, k), column b, contiguous in b), and with
/// `inertia` = (ρω², T·G) also −ρω² (T·G_a)(T·G_b) w on the blocks i = k.
#[inline(always)]
#[allow(clippy::needless_range_loop)] // Index loops spell out the index notation of the kernel.
fn add_gag<const N: usize>(
    dst: &mut [f64; 324],
    a_t: &Tangent,
    g: &[[f64; 2]; N],
    gx: &[f64; N],
    gy: &[f64; N],
    w: f64,
    inertia: Option<(f64, &[f64; N])>,
) {
    for a in 0..N {
        for i in 0..2 {
            // ga[(k, L)] = w Σ_J G_aJ A[v(i, J), v(k, L)]
            let mut ga = [0.0; 4];
            for (kl, gv) in ga.iter_mut().enumerate() {
                *gv = (g[a][0] * a_t[(v(i, 0), kl)] + g[a][1] * a_t[(v(i, 1), kl)]) * w;
            }
            for k in 0..2 {
                let (c0, c1) = (ga[v(k, 0)], ga[v(k, 1)]);
                let o = ((2 * a + i) * 2 + k) * N;
                let row = &mut dst[o..o + N];
                match inertia {
                    Some((rw2, tg)) if i == k => {
                        let ci = -rw2 * tg[a] * w;
                        for b in 0..N {
                            row[b] += c0 * gx[b] + c1 * gy[b] + ci * tg[b];
                        }
                    }
                    _ => {
                        for b in 0..N {
                            row[b] += c0 * gx[b] + c1 * gy[b];
                        }
                    }
                }
            }
        }
    }
}

/// The tangents of the first Piola–Kirchhoff stress of the strain-rate damping,
/// P_v = F S_v with S_v = η/2 (∇vᵀ F + Fᵀ ∇v) (`sv`, the viscous second Piola–Kirchhoff
/// stress at F = I + H and velocity gradient ∇v = `fd`): ∂P_v/∂H at fixed ∇v and ∂P_v/∂(∇v),
/// in the layout of [`Tangent`]. In index form,
///   ∂P_iJ/∂H_kL = δ_ik S_v,LJ + η/2 ((F ∇vᵀ)_ik δ_LJ + F_iL ∇v_kJ),
///   ∂P_iJ/∂∇v_kL = η/2 (F_iL F_kJ + (F Fᵀ)_ik δ_LJ).
fn strain_rate_damping_tangents(f: &Mat2, fd: &Mat2, sv: &Mat2, eta: f64) -> (Tangent, Tangent) {
    let he = 0.5 * eta;
    let ffd = f * fd.transpose();
    let fft = f * f.transpose();
    let (mut dh, mut dl) = (Tangent::zeros(), Tangent::zeros());
    for k in 0..2 {
        for l in 0..2 {
            let col = v(k, l);
            for i in 0..2 {
                for j in 0..2 {
                    let row = v(i, j);
                    let (mut h, mut g) = (he * f[(i, l)] * fd[(k, j)], he * f[(i, l)] * f[(k, j)]);
                    if j == l {
                        h += he * ffd[(i, k)];
                        g += he * fft[(i, k)];
                    }
                    if i == k {
                        h += sv[(l, j)];
                    }
                    dh[(row, col)] = h;
                    dl[(row, col)] = g;
                }
            }
        }
    }
    (dh, dl)
}

#[cfg(test)]
mod damping_tangent_tests {
    use super::*;

    /// P_v = F η/2 (∇vᵀ F + Fᵀ ∇v) at F = I + H.
    fn p_v(h: &Mat2, fd: &Mat2, eta: f64) -> Mat2 {
        let f = Mat2::identity() + h;
        f * ((fd.transpose() * f + f.transpose() * fd) * (0.5 * eta))
    }

    #[test]
    fn strain_rate_damping_tangents_match_central_differences() {
        let eta = 1.7;
        let cases = [
            (
                Mat2::new(0.1, -0.3, 0.25, -0.05),
                Mat2::new(0.4, 1.2, -0.7, 0.3),
            ),
            (
                Mat2::new(-0.4, 0.6, 0.0, 0.8),
                Mat2::new(-2.0, 0.1, 0.5, 0.9),
            ),
            (Mat2::zeros(), Mat2::new(0.0, 1.0, -1.0, 0.0)),
        ];
        let step = 1e-6;
        for (h, fd) in cases {
            let f = Mat2::identity() + h;
            let sv = (fd.transpose() * f + f.transpose() * fd) * (0.5 * eta);
            let (dh, dl) = strain_rate_damping_tangents(&f, &fd, &sv, eta);
            for k in 0..2 {
                for l in 0..2 {
                    let mut e = Mat2::zeros();
                    e[(k, l)] = step;
                    let num_h = (p_v(&(h + e), &fd, eta) - p_v(&(h - e), &fd, eta)) / (2.0 * step);
                    let num_l = (p_v(&h, &(fd + e), eta) - p_v(&h, &(fd - e), eta)) / (2.0 * step);
                    for i in 0..2 {
                        for j in 0..2 {
                            let (a, b) = (dh[(v(i, j), v(k, l))], num_h[(i, j)]);
                            assert!(
                                (a - b).abs() <= 1e-8 * (1.0 + b.abs()),
                                "dP/dH ({i}{j},{k}{l}): {a} vs {b}"
                            );
                            let (a, b) = (dl[(v(i, j), v(k, l))], num_l[(i, j)]);
                            assert!(
                                (a - b).abs() <= 1e-8 * (1.0 + b.abs()),
                                "dP/dgrad v ({i}{j},{k}{l}): {a} vs {b}"
                            );
                        }
                    }
                }
            }
        }
    }
}
