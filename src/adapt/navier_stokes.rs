//! Steady incompressible Navier–Stokes on a quadtree: −ν Δu + (u·∇)u + ∇p = f, div u = 0 in
//! Ω, u = g on ∂Ω, with the Taylor–Hood pair Q2/Q1 (continuous velocity of degree 2, continuous
//! pressure of degree 1, Lagrange bases), both fields on [`Space`]s over the same leaves, so the
//! hanging-node constraints of each field come from the space.
//!
//! Conventions. Velocity and pressure are kinematic (pressure divided by the density); for the
//! unit cavity with lid speed 1, ν = 1/Re. The weak form is, for all (v, q),
//! ν (∇u, ∇v) + ((u·∇)u, v) − (p, div v) − (q, div u) = (f, v), and its Newton linearisation is
//! exact: δ(u·∇)u = (δu·∇)u + (u·∇)δu. The pressure is defined up to a constant: it is fixed by
//! pinning one pressure dof (the lowest-numbered free one, a vertex of the first leaf) to 0;
//! [`NsSolution::pressure_mean`] and the error functions remove the mean afterwards.
//!
//! Dof vector: the velocity dofs of the velocity space (2 per node, node-major: u then v),
//! followed by the pressure dofs (offset [`TaylorHood::n_u`]). Equations: the velocity equations
//! of the velocity space, then the free pressure equations without the pinned one.
//!
//! Lid-driven cavity on [0, 1]² ([`CavityLid`]): u = (U(x), 0) on y = 1, u = 0 elsewhere. The
//! discontinuous lid has U = 1 on the open top edge and U = 0 at the two top corners (the corner
//! nodes belong to the walls). On the top edge of a corner cell the space's boundary projection
//! (vertex values, then the edge mode from −∫ (g − vertex part) b″, the H¹-seminorm projection
//! of g with its jump at the corner counted) keeps the edge integral of U: the Q2 trace is
//! U = s (4 − 3s) with s the distance from the corner in units of the edge: 0 at the corner, 5/4
//! at the midside node, 1 at the other end, largest value 4/3 at s = 2/3; so every lid edge
//! carries the flux ∫ U dx = h of the lid. The regularised lid is U = 16 x² (1 − x)².
//!
//! Cell geometry. Every leaf is the bilinear image of the reference square of its four corner
//! points ([`TaylorHood::corners`], tensor order: lower-left, lower-right, upper-left,
//! upper-right): x(ξ, η) = Σ_a N_a(ξ, η) X_a with the Q1 functions N_a. The corners default to
//! the quadtree's squares (then the map is the affine one of the tree); [`TaylorHood::set_corners`]
//! moves them (same cells, same connectivity, same dofs), which turns the Q2/Q1 pair into a
//! subparametric one: physical gradients are J⁻ᵀ ∇_ξ N and the quadrature weights carry det J.
//! Boundary nodes may only slide along straight boundary edges, so the domain is unchanged; the
//! Dirichlet values of the space stay those computed on the tree, which is exact for data that do
//! not change along an edge away from its end points (the cavity lids' walls and the open
//! discontinuous lid), not for general data (keep boundary nodes fixed then).
//!
//! Stream function: ψ with u = ∂ψ/∂y, v = −∂ψ/∂x, ψ = 0 on the walls, computed from
//! −Δψ = ω = ∂v/∂x − ∂u/∂y in the scalar Q2 space with ψ = 0 on ∂Ω (Cholesky).

use super::quadtree::Quadtree;
use super::space::{shape_values, Space, SpaceError, MAX_LOCAL_SCALAR};
use crate::assembly::constraints::{ClosedConstraints, CondenseScratch, CondensedPattern};
use crate::element::hierarchical::{gauss_legendre, Basis1d};
use crate::solver::linear::{LinearError, LinearKind, SparseSolver};

/// Velocity nodes (Q2) and pressure nodes (Q1) of one cell.
const NV: usize = 9;
const NP: usize = 4;
/// Local dofs of one cell: 2·9 velocity, 4 pressure.
const NL: usize = 2 * NV + NP;
/// Gauss points per direction (exact for the convection term on squares).
const NQ: usize = 4;

/// Corner points of a cell in tensor order: lower-left, lower-right, upper-left, upper-right.
pub type CellCorners = [[f64; 2]; 4];

/// The bilinear map of `c` at (ξ, η): the point, the inverse Jacobian `inv[r][d] = ∂ξ_r/∂x_d`
/// and det J (the inverse is meaningless if det J is not positive).
#[inline]
pub fn bilinear(c: &CellCorners, xi: f64, eta: f64) -> ([f64; 2], [[f64; 2]; 2], f64) {
    let nx = [0.5 * (1.0 - xi), 0.5 * (1.0 + xi)];
    let ny = [0.5 * (1.0 - eta), 0.5 * (1.0 + eta)];
    let d = [-0.5, 0.5];
    let mut x = [0.0; 2];
    let mut jm = [[0.0; 2]; 2]; // jm[d][r] = ∂x_d/∂ξ_r
    for j in 0..2 {
        for i in 0..2 {
            let xa = c[i + 2 * j];
            for dim in 0..2 {
                x[dim] += nx[i] * ny[j] * xa[dim];
                jm[dim][0] += d[i] * ny[j] * xa[dim];
                jm[dim][1] += nx[i] * d[j] * xa[dim];
            }
        }
    }
    let det = jm[0][0] * jm[1][1] - jm[0][1] * jm[1][0];
    let inv = [
        [jm[1][1] / det, -jm[0][1] / det],
        [-jm[1][0] / det, jm[0][0] / det],
    ];
    (x, inv, det)
}

/// Values and physical gradients of the Lagrange basis of degree `p` on the bilinear cell `c`
/// at (ξ, η); returns the physical point and det J.
#[inline]
pub fn mapped_shape(
    p: usize,
    c: &CellCorners,
    xi: f64,
    eta: f64,
    n: &mut [f64],
    dn: &mut [[f64; 2]],
) -> ([f64; 2], f64) {
    // h = 2: reference gradients.
    let m = shape_values(Basis1d::Lagrange, p, 2.0, xi, eta, n, dn);
    let (x, inv, det) = bilinear(c, xi, eta);
    for g in dn.iter_mut().take(m) {
        let r = *g;
        *g = [
            r[0] * inv[0][0] + r[1] * inv[1][0],
            r[0] * inv[0][1] + r[1] * inv[1][1],
        ];
    }
    (x, det)
}

/// Smallest det J of the bilinear cell `c` over its four corners. det J of a bilinear map is
/// affine in ξ and in η separately, so this is its minimum over the whole cell.
pub fn min_det_corners(c: &CellCorners) -> f64 {
    let mut m = f64::INFINITY;
    for (xi, eta) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
        m = m.min(bilinear(c, xi, eta).2);
    }
    m
}

/// Error of the Navier–Stokes solver.
#[derive(Debug, thiserror::Error)]
pub enum NsError {
    #[error(transparent)]
    Space(#[from] SpaceError),
    #[error(transparent)]
    Linear(#[from] LinearError),
    #[error("viscosity must be positive and finite, got {0}")]
    Viscosity(f64),
    #[error("Newton did not converge at nu = {nu}: residual {residual:.3e} after {iterations} iterations")]
    NoConvergence {
        nu: f64,
        residual: f64,
        iterations: usize,
    },
    #[error("non-finite residual at nu = {0}")]
    NonFinite(f64),
    #[error("point ({0}, {1}) is outside the mesh")]
    Outside(f64, f64),
    #[error("the pressure space has no free dof to pin")]
    NoPressureDof,
    #[error("expected {expected} cell geometries (one per leaf), got {got}")]
    GeometryCount { expected: usize, got: usize },
    #[error("cell {cell} is inverted or degenerate: min det J = {det:e}")]
    Inverted { cell: usize, det: f64 },
}

/// The Taylor–Hood space: velocity (Q2, 2 components, Dirichlet data) and pressure (Q1).
pub struct TaylorHood {
    /// The mesh, every leaf of degree 2.
    pub tree: Quadtree,
    pub vel: Space,
    pub pres: Space,
    /// Number of velocity dofs (offset of the pressure dofs).
    pub n_u: usize,
    /// Equations of the velocity (first `n_eq_u` equations).
    pub n_eq_u: usize,
    /// The pinned pressure dof (full numbering).
    pub pinned: usize,
    pub constraints: ClosedConstraints,
    pub pattern: CondensedPattern,
    /// Corner points of each leaf (leaf order of the spaces), see the module docs.
    pub corners: Vec<CellCorners>,
    /// Whether the corners were moved off the tree's squares (point location then searches
    /// the bilinear cells instead of the tree).
    pub mapped: bool,
}

impl TaylorHood {
    /// Build the pair on the leaves of `tree` (their degrees are ignored) with velocity
    /// Dirichlet data `g(x, comp)` on the whole boundary.
    pub fn new(tree: &Quadtree, g: &dyn Fn([f64; 2], usize) -> f64) -> Result<Self, NsError> {
        let mut tv = tree.clone();
        let mut tp = tree.clone();
        for c in tree.leaves() {
            tv.cells[c as usize].degree = 2;
            tp.cells[c as usize].degree = 1;
        }
        let vel = Space::new(&tv, Basis1d::Lagrange, 2, Some(g))?;
        let pres = Space::new(&tp, Basis1d::Lagrange, 1, None)?;
        let n_u = vel.n_dofs();
        let n_eq_u = vel.n_eq();
        let cv = &vel.constraints;
        let cp = &pres.constraints;
        let pin_dof = cp
            .eq
            .iter()
            .position(|&e| e != u32::MAX)
            .ok_or(NsError::NoPressureDof)?;
        let pin_eq = cp.eq[pin_dof];
        let map_p = |e: u32| -> Option<u32> {
            match e.cmp(&pin_eq) {
                std::cmp::Ordering::Equal => None,
                std::cmp::Ordering::Less => Some(n_eq_u as u32 + e),
                std::cmp::Ordering::Greater => Some(n_eq_u as u32 + e - 1),
            }
        };
        let mut eq = cv.eq.clone();
        let mut exp_offsets = cv.exp_offsets.clone();
        let mut exp_terms = cv.exp_terms.clone();
        let mut offset = cv.offset.clone();
        for i in 0..pres.n_dofs() {
            eq.push(if i == pin_dof || cp.eq[i] == u32::MAX {
                u32::MAX
            } else {
                map_p(cp.eq[i]).unwrap_or(u32::MAX)
            });
            let (t, b) = cp.expansion(i);
            for &(e, a) in t {
                if let Some(m) = map_p(e) {
                    exp_terms.push((m, a));
                }
            }
            exp_offsets.push(exp_terms.len());
            offset.push(b);
        }
        let constraints = ClosedConstraints {
            eq,
            n_eq: n_eq_u + cp.n_eq - 1,
            exp_offsets,
            exp_terms,
            offset,
        };
        let mut cell_dofs = Vec::new();
        let mut dof_off = vec![0];
        for k in 0..vel.leaves.len() {
            cell_dofs.extend_from_slice(vel.dofs(k));
            cell_dofs.extend(pres.dofs(k).iter().map(|&d| d + n_u as u32));
            dof_off.push(cell_dofs.len());
        }
        let pattern = CondensedPattern::new(&constraints, &cell_dofs, &dof_off);
        let corners = vel
            .leaves
            .iter()
            .map(|&c| {
                let [x0, y0] = tree.corner(c);
                let h = tree.h(c);
                [[x0, y0], [x0 + h, y0], [x0, y0 + h], [x0 + h, y0 + h]]
            })
            .collect();
        Ok(Self {
            corners,
            mapped: false,
            tree: tv,
            vel,
            pres,
            n_u,
            n_eq_u,
            pinned: n_u + pin_dof,
            constraints,
            pattern,
        })
    }

    /// Number of equations (unknowns of the condensed system).
    pub fn n_eq(&self) -> usize {
        self.constraints.n_eq
    }
    /// Number of dofs (velocity and pressure, constrained ones included).
    pub fn n_dofs(&self) -> usize {
        self.n_u + self.pres.n_dofs()
    }

    /// Dof vector of the equation values `y` (constraints and Dirichlet data applied).
    pub fn distribute(&self, y: &[f64]) -> Vec<f64> {
        let mut x = vec![0.0; self.n_dofs()];
        self.constraints.distribute(y, &mut x);
        x
    }
    /// Equation values of a dof vector.
    pub fn gather(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.n_eq()];
        self.constraints.gather(x, &mut y);
        y
    }

    /// Move the cell corners (one entry per leaf, tensor order). Every cell must keep a
    /// positive det J at its four corners (hence everywhere in it); otherwise nothing changes
    /// and the first bad cell is reported.
    pub fn set_corners(&mut self, corners: Vec<CellCorners>) -> Result<(), NsError> {
        if corners.len() != self.corners.len() {
            return Err(NsError::GeometryCount {
                expected: self.corners.len(),
                got: corners.len(),
            });
        }
        for (k, c) in corners.iter().enumerate() {
            let det = min_det_corners(c);
            if det.is_nan() || det <= 0.0 {
                return Err(NsError::Inverted { cell: k, det });
            }
        }
        self.corners = corners;
        self.mapped = true;
        Ok(())
    }

    /// Smallest det J over every cell, at the corners and at the Gauss points of the assembly.
    pub fn min_det_j(&self) -> f64 {
        let (gx, _) = gauss_legendre(NQ);
        let mut m = f64::INFINITY;
        for c in &self.corners {
            m = m.min(min_det_corners(c));
            for &a in &gx {
                for &b in &gx {
                    m = m.min(bilinear(c, a, b).2);
                }
            }
        }
        m
    }

    /// The leaf (index in the spaces' leaf order) containing the physical point `p`, and its
    /// reference coordinates there.
    pub fn locate(&self, p: [f64; 2]) -> Option<(usize, f64, f64)> {
        if !self.mapped {
            let (c, xi, eta) = self.tree.locate(p)?;
            return Some((self.vel.leaf_index[&c], xi, eta));
        }
        let tol = 1e-9;
        for (k, c) in self.corners.iter().enumerate() {
            let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            for x in c {
                for d in 0..2 {
                    lo[d] = lo[d].min(x[d]);
                    hi[d] = hi[d].max(x[d]);
                }
            }
            let pad = tol * (hi[0] - lo[0] + hi[1] - lo[1]);
            if (0..2).any(|d| p[d] < lo[d] - pad || p[d] > hi[d] + pad) {
                continue;
            }
            // Newton on x(ξ, η) = p from the centre.
            let (mut xi, mut eta) = (0.0, 0.0);
            for _ in 0..30 {
                let (x, inv, _) = bilinear(c, xi, eta);
                let r = [p[0] - x[0], p[1] - x[1]];
                let dxi = inv[0][0] * r[0] + inv[0][1] * r[1];
                let deta = inv[1][0] * r[0] + inv[1][1] * r[1];
                xi += dxi;
                eta += deta;
                if dxi.abs() + deta.abs() < 1e-14 {
                    break;
                }
            }
            let inside = |s: f64| (-1.0 - 1e-9..=1.0 + 1e-9).contains(&s);
            if inside(xi) && inside(eta) {
                return Some((k, xi.clamp(-1.0, 1.0), eta.clamp(-1.0, 1.0)));
            }
        }
        None
    }

    /// Velocity component `comp` of the dof vector `x` and its physical gradient in leaf `k`.
    pub fn eval_velocity(
        &self,
        x: &[f64],
        k: usize,
        comp: usize,
        xi: f64,
        eta: f64,
    ) -> (f64, [f64; 2]) {
        let mut n = [0.0; MAX_LOCAL_SCALAR];
        let mut dn = [[0.0; 2]; MAX_LOCAL_SCALAR];
        mapped_shape(2, &self.corners[k], xi, eta, &mut n, &mut dn);
        let dofs = self.vel.dofs(k);
        let (mut v, mut g) = (0.0, [0.0; 2]);
        for a in 0..NV {
            let xa = x[dofs[2 * a + comp] as usize];
            v += n[a] * xa;
            g[0] += dn[a][0] * xa;
            g[1] += dn[a][1] * xa;
        }
        (v, g)
    }

    /// Pressure of the dof vector `x` (full, velocity first) in leaf `k`.
    pub fn eval_pressure(&self, x: &[f64], k: usize, xi: f64, eta: f64) -> f64 {
        let mut n = [0.0; MAX_LOCAL_SCALAR];
        let mut dn = [[0.0; 2]; MAX_LOCAL_SCALAR];
        shape_values(Basis1d::Lagrange, 1, 2.0, xi, eta, &mut n, &mut dn);
        let dofs = self.pres.dofs(k);
        (0..NP).map(|b| n[b] * x[self.n_u + dofs[b] as usize]).sum()
    }

    /// Local dofs of leaf `k`: 18 velocity (node-major), then 4 pressure.
    fn local_dofs(&self, k: usize) -> [usize; NL] {
        let mut d = [0usize; NL];
        for (a, &v) in self.vel.dofs(k).iter().enumerate() {
            d[a] = v as usize;
        }
        for (b, &p) in self.pres.dofs(k).iter().enumerate() {
            d[2 * NV + b] = self.n_u + p as usize;
        }
        d
    }

    /// Condensed residual R(y) = Cᵀ r(C y + b) and, if `jac` is given, the condensed exact
    /// Jacobian (values in the slots of [`TaylorHood::pattern`]).
    pub fn residual(
        &self,
        y: &[f64],
        nu: f64,
        f: &dyn Fn([f64; 2]) -> [f64; 2],
        mut jac: Option<&mut [f64]>,
    ) -> Vec<f64> {
        let x = self.distribute(y);
        let pat = &self.pattern;
        let mut res = vec![0.0; pat.n];
        if let Some(j) = jac.as_deref_mut() {
            j.fill(0.0);
        }
        let (gx, gw) = gauss_legendre(NQ);
        let mut n = [0.0; MAX_LOCAL_SCALAR];
        let mut dn = [[0.0; 2]; MAX_LOCAL_SCALAR];
        let mut np = [0.0; MAX_LOCAL_SCALAR];
        let mut dnp = [[0.0; 2]; MAX_LOCAL_SCALAR];
        let mut kc = Vec::new();
        for k in 0..self.vel.leaves.len() {
            let geo = &self.corners[k];
            let dofs = self.local_dofs(k);
            let mut xl = [0.0; NL];
            for (a, &d) in dofs.iter().enumerate() {
                xl[a] = x[d];
            }
            let mut r = [0.0; NL];
            let mut kl = [[0.0; NL]; NL];
            for (i, &xi) in gx.iter().enumerate() {
                for (jq, &eta) in gx.iter().enumerate() {
                    let (xq, det) = mapped_shape(2, geo, xi, eta, &mut n, &mut dn);
                    shape_values(Basis1d::Lagrange, 1, 2.0, xi, eta, &mut np, &mut dnp);
                    let w = gw[i] * gw[jq] * det;
                    let mut u = [0.0; 2];
                    let mut gu = [[0.0; 2]; 2]; // gu[c][d] = ∂u_c/∂x_d
                    for a in 0..NV {
                        for cc in 0..2 {
                            let v = xl[2 * a + cc];
                            u[cc] += n[a] * v;
                            gu[cc][0] += dn[a][0] * v;
                            gu[cc][1] += dn[a][1] * v;
                        }
                    }
                    let mut p = 0.0;
                    for b in 0..NP {
                        p += np[b] * xl[2 * NV + b];
                    }
                    let div = gu[0][0] + gu[1][1];
                    let fx = f(xq);
                    for a in 0..NV {
                        for cc in 0..2 {
                            let conv = u[0] * gu[cc][0] + u[1] * gu[cc][1];
                            r[2 * a + cc] += w
                                * (nu * (gu[cc][0] * dn[a][0] + gu[cc][1] * dn[a][1])
                                    + (conv - fx[cc]) * n[a]
                                    - p * dn[a][cc]);
                        }
                    }
                    for b in 0..NP {
                        r[2 * NV + b] -= w * np[b] * div;
                    }
                    if jac.is_none() {
                        continue;
                    }
                    for a in 0..NV {
                        for b in 0..NV {
                            let lap = nu * (dn[a][0] * dn[b][0] + dn[a][1] * dn[b][1]);
                            let adv = (u[0] * dn[b][0] + u[1] * dn[b][1]) * n[a];
                            for cc in 0..2 {
                                for d in 0..2 {
                                    let mut v = n[b] * gu[cc][d] * n[a];
                                    if cc == d {
                                        v += lap + adv;
                                    }
                                    kl[2 * a + cc][2 * b + d] += w * v;
                                }
                            }
                        }
                        for b in 0..NP {
                            for cc in 0..2 {
                                let v = w * np[b] * dn[a][cc];
                                kl[2 * a + cc][2 * NV + b] -= v;
                                kl[2 * NV + b][2 * a + cc] -= v;
                            }
                        }
                    }
                }
            }
            // Condense: R_e += Σ_a C_ae r_a, J_ef += Σ_ab C_ae K_ab C_bf.
            let eqs = &pat.cell_eq[pat.cell_off[k]..pat.cell_off[k + 1]];
            let m = eqs.len();
            let cm = &pat.c[pat.c_off[k]..pat.c_off[k + 1]];
            for e in 0..m {
                let mut s = 0.0;
                for a in 0..NL {
                    s += cm[a * m + e] * r[a];
                }
                res[eqs[e] as usize] += s;
            }
            if let Some(jv) = jac.as_deref_mut() {
                kc.clear();
                kc.resize(NL * m, 0.0);
                for a in 0..NL {
                    for b in 0..NL {
                        let kab = kl[a][b];
                        if kab == 0.0 {
                            continue;
                        }
                        for f2 in 0..m {
                            kc[a * m + f2] += kab * cm[b * m + f2];
                        }
                    }
                }
                let slots = &pat.slots[pat.slot_off[k]..pat.slot_off[k + 1]];
                for e in 0..m {
                    for f2 in 0..m {
                        let mut v = 0.0;
                        for a in 0..NL {
                            v += cm[a * m + e] * kc[a * m + f2];
                        }
                        jv[slots[e * m + f2]] += v;
                    }
                }
            }
        }
        res
    }
}

/// Newton iteration statistics of one solve.
#[derive(Clone, Debug)]
pub struct NewtonStats {
    pub nu: f64,
    pub iterations: usize,
    /// ‖R‖∞ after each iteration (the first entry is the initial residual).
    pub residuals: Vec<f64>,
}

/// Solve at viscosity `nu` by Newton's method with the exact Jacobian and sparse LU, starting
/// from the equation values `y` (overwritten). Converged when ‖R‖∞ ≤ `tol`. A step that does
/// not reduce the residual is halved (at most 8 times).
pub fn solve_newton(
    th: &TaylorHood,
    y: &mut [f64],
    nu: f64,
    f: &dyn Fn([f64; 2]) -> [f64; 2],
    tol: f64,
    max_iter: usize,
) -> Result<NewtonStats, NsError> {
    if !(nu > 0.0 && nu.is_finite()) {
        return Err(NsError::Viscosity(nu));
    }
    let pat = &th.pattern;
    let mut solver = SparseSolver::new(pat.n, &pat.col_ptr, &pat.row_idx, LinearKind::Lu)?;
    solver.set_track_determinant(false);
    let mut jac = vec![0.0; pat.nnz()];
    let norm = |r: &[f64]| r.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut r = th.residual(y, nu, f, Some(&mut jac));
    let mut rn = norm(&r);
    let mut stats = NewtonStats {
        nu,
        iterations: 0,
        residuals: vec![rn],
    };
    while rn > tol {
        if !rn.is_finite() {
            return Err(NsError::NonFinite(nu));
        }
        if stats.iterations >= max_iter {
            return Err(NsError::NoConvergence {
                nu,
                residual: rn,
                iterations: stats.iterations,
            });
        }
        solver.factorize(&jac)?;
        let mut d: Vec<f64> = r.iter().map(|v| -v).collect();
        solver.solve_in_place(&mut d)?;
        let y0 = y.to_vec();
        let mut lambda = 1.0;
        let mut accepted = false;
        for _ in 0..9 {
            for i in 0..y.len() {
                y[i] = y0[i] + lambda * d[i];
            }
            let rt = th.residual(y, nu, f, None);
            let rtn = norm(&rt);
            if rtn.is_finite() && (rtn < rn || lambda < 0.01) {
                accepted = true;
                break;
            }
            lambda *= 0.5;
        }
        if !accepted {
            y.copy_from_slice(&y0);
            for i in 0..y.len() {
                y[i] += d[i];
            }
        }
        r = th.residual(y, nu, f, Some(&mut jac));
        rn = norm(&r);
        stats.iterations += 1;
        stats.residuals.push(rn);
    }
    Ok(stats)
}

/// A solution: the full dof vector on a Taylor–Hood space.
pub struct NsSolution<'a> {
    pub th: &'a TaylorHood,
    pub x: Vec<f64>,
}

impl NsSolution<'_> {
    /// Velocity (u, v) and its gradient [[∂u/∂x, ∂u/∂y], [∂v/∂x, ∂v/∂y]] at a point.
    pub fn velocity(&self, p: [f64; 2]) -> Result<([f64; 2], [[f64; 2]; 2]), NsError> {
        let (k, xi, eta) = self.th.locate(p).ok_or(NsError::Outside(p[0], p[1]))?;
        let (u, gu) = self.th.eval_velocity(&self.x, k, 0, xi, eta);
        let (v, gv) = self.th.eval_velocity(&self.x, k, 1, xi, eta);
        Ok(([u, v], [gu, gv]))
    }
    /// Pressure at a point (with the pinned normalisation).
    pub fn pressure(&self, p: [f64; 2]) -> Result<f64, NsError> {
        let (k, xi, eta) = self.th.locate(p).ok_or(NsError::Outside(p[0], p[1]))?;
        Ok(self.th.eval_pressure(&self.x, k, xi, eta))
    }
    /// Mean of the pressure over Ω divided by |Ω|.
    pub fn pressure_mean(&self) -> f64 {
        let (gx, gw) = gauss_legendre(3);
        let (mut s, mut area) = (0.0, 0.0);
        for k in 0..self.th.pres.leaves.len() {
            for (i, &a) in gx.iter().enumerate() {
                for (j, &b) in gx.iter().enumerate() {
                    let w = gw[i] * gw[j] * bilinear(&self.th.corners[k], a, b).2;
                    s += w * self.th.eval_pressure(&self.x, k, a, b);
                    area += w;
                }
            }
        }
        s / area
    }
}

/// Errors against an exact solution: ‖u − u_h‖, |u − u_h|₁, ‖(p − p̄) − (p_h − p̄_h)‖.
#[derive(Clone, Copy, Debug)]
pub struct NsErrors {
    pub u_l2: f64,
    pub u_h1: f64,
    pub p_l2: f64,
}

/// Errors of `sol` against (u, ∇u, p); both pressures are taken with zero mean.
pub fn errors(
    sol: &NsSolution,
    u: &dyn Fn([f64; 2]) -> [f64; 2],
    grad_u: &dyn Fn([f64; 2]) -> [[f64; 2]; 2],
    p: &dyn Fn([f64; 2]) -> f64,
) -> NsErrors {
    let th = sol.th;
    let (gx, gw) = gauss_legendre(6);
    // Means of p and p_h.
    let (mut pm, mut phm, mut area) = (0.0, 0.0, 0.0);
    for k in 0..th.vel.leaves.len() {
        for (i, &a) in gx.iter().enumerate() {
            for (j, &b) in gx.iter().enumerate() {
                let (xq, _, det) = bilinear(&th.corners[k], a, b);
                let w = gw[i] * gw[j] * det;
                pm += w * p(xq);
                phm += w * th.eval_pressure(&sol.x, k, a, b);
                area += w;
            }
        }
    }
    pm /= area;
    phm /= area;
    let (mut eu, mut eg, mut ep) = (0.0, 0.0, 0.0);
    for k in 0..th.vel.leaves.len() {
        for (i, &a) in gx.iter().enumerate() {
            for (j, &b) in gx.iter().enumerate() {
                let (xq, _, det) = bilinear(&th.corners[k], a, b);
                let w = gw[i] * gw[j] * det;
                let ue = u(xq);
                let ge = grad_u(xq);
                for comp in 0..2 {
                    let (v, g) = th.eval_velocity(&sol.x, k, comp, a, b);
                    eu += w * (ue[comp] - v).powi(2);
                    eg += w * ((ge[comp][0] - g[0]).powi(2) + (ge[comp][1] - g[1]).powi(2));
                }
                let ph = th.eval_pressure(&sol.x, k, a, b) - phm;
                ep += w * (p(xq) - pm - ph).powi(2);
            }
        }
    }
    NsErrors {
        u_l2: eu.sqrt(),
        u_h1: eg.sqrt(),
        p_l2: ep.sqrt(),
    }
}

/// Lid of the driven cavity.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CavityLid {
    /// U = 1 on the open top edge, 0 at the top corners.
    Discontinuous,
    /// U = 16 x² (1 − x)².
    Regularised,
}

impl CavityLid {
    /// Boundary velocity component `comp` at boundary point x of [0, 1]².
    pub fn g(self, x: [f64; 2], comp: usize) -> f64 {
        if comp != 0 || x[1] < 1.0 - 1e-12 {
            return 0.0;
        }
        match self {
            CavityLid::Discontinuous => {
                if x[0] > 1e-12 && x[0] < 1.0 - 1e-12 {
                    1.0
                } else {
                    0.0
                }
            }
            CavityLid::Regularised => 16.0 * x[0].powi(2) * (1.0 - x[0]).powi(2),
        }
    }
}

/// Outcome of a continuation run of the cavity.
pub struct CavityRun {
    pub th: TaylorHood,
    /// Converged equation values at each Reynolds number of the ladder.
    pub states: Vec<(f64, Vec<f64>)>,
    pub stats: Vec<NewtonStats>,
}

/// The lid-driven cavity on the leaves of `tree` (covering [0, 1]²), solved by Newton at each
/// Reynolds number of `reynolds` in turn, each from the previous solution (the first from
/// zero interior velocity).
pub fn cavity(
    tree: &Quadtree,
    lid: CavityLid,
    reynolds: &[f64],
    tol: f64,
) -> Result<CavityRun, NsError> {
    let th = TaylorHood::new(tree, &|x, c| lid.g(x, c))?;
    let mut y = vec![0.0; th.n_eq()];
    let mut states = Vec::new();
    let mut stats = Vec::new();
    let zero = |_: [f64; 2]| [0.0, 0.0];
    for &re in reynolds {
        let s = solve_newton(&th, &mut y, 1.0 / re, &zero, tol, 30)?;
        stats.push(s);
        states.push((re, y.clone()));
    }
    Ok(CavityRun { th, states, stats })
}

/// The stream function of a velocity field: −Δψ = ∂v/∂x − ∂u/∂y in the scalar Q2 space of
/// the velocity mesh, ψ = 0 on ∂Ω. Returns the space and ψ's dof vector.
pub fn stream_function(sol: &NsSolution) -> Result<(Space, Vec<f64>), NsError> {
    let th = sol.th;
    let space = Space::new(&th.tree, Basis1d::Lagrange, 1, Some(&|_, _| 0.0))?;
    let pat = &space.pattern;
    let mut kl = [0.0; NV * NV];
    let mut values = vec![0.0; pat.nnz()];
    let mut rhs = vec![0.0; pat.n];
    let mut scratch = CondenseScratch::default();
    let (gx, gw) = gauss_legendre(NQ);
    let mut n = [0.0; MAX_LOCAL_SCALAR];
    let mut dn = [[0.0; 2]; MAX_LOCAL_SCALAR];
    let mut fl = [0.0; NV];
    for k in 0..space.leaves.len() {
        fl.fill(0.0);
        kl.fill(0.0);
        for (i, &a) in gx.iter().enumerate() {
            for (j, &b) in gx.iter().enumerate() {
                let (_, gu) = th.eval_velocity(&sol.x, k, 0, a, b);
                let (_, gv) = th.eval_velocity(&sol.x, k, 1, a, b);
                let om = gv[0] - gu[1];
                let (_, det) = mapped_shape(2, &th.corners[k], a, b, &mut n, &mut dn);
                let w = gw[i] * gw[j] * det;
                for (q, fq) in fl.iter_mut().enumerate() {
                    *fq += w * om * n[q];
                    for r in 0..NV {
                        kl[q * NV + r] += w * (dn[q][0] * dn[r][0] + dn[q][1] * dn[r][1]);
                    }
                }
            }
        }
        pat.add_cell(k, &kl, &fl, &mut values, &mut rhs, &mut scratch);
    }
    let mut solver = SparseSolver::new(pat.n, &pat.col_ptr, &pat.row_idx, LinearKind::Cholesky)?;
    solver.set_track_determinant(false);
    solver.factorize(&values)?;
    solver.solve_in_place(&mut rhs)?;
    let mut psi = vec![0.0; space.n_dofs()];
    space.constraints.distribute(&rhs, &mut psi);
    Ok((space, psi))
}

/// Minimum of ψ over Ω and its location: sampled on a 9 × 9 grid in every cell, then
/// polished by a compass search (step down to 1e-10). `space` and `psi` are those of
/// [`stream_function`] on `th` (the values of the Q2 basis do not depend on the cell
/// geometry, only the location does).
pub fn psi_min(th: &TaylorHood, space: &Space, psi: &[f64]) -> ([f64; 2], f64) {
    let tree = &th.tree;
    let eval = |p: [f64; 2]| -> f64 {
        match th.locate(p) {
            Some((k, xi, eta)) => space.eval(tree, psi, k, 0, xi, eta).0,
            None => f64::INFINITY,
        }
    };
    let mut best = ([0.5, 0.5], f64::INFINITY);
    for k in 0..space.leaves.len() {
        for i in 0..9 {
            for j in 0..9 {
                let (xi, eta) = (-1.0 + 0.25 * i as f64, -1.0 + 0.25 * j as f64);
                let v = space.eval(tree, psi, k, 0, xi, eta).0;
                if v < best.1 {
                    best = (bilinear(&th.corners[k], xi, eta).0, v);
                }
            }
        }
    }
    let mut step = 0.01;
    while step > 1e-10 {
        let mut moved = false;
        for d in [[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]] {
            let q = [best.0[0] + step * d[0], best.0[1] + step * d[1]];
            let v = eval(q);
            if v < best.1 {
                best = (q, v);
                moved = true;
            }
        }
        if !moved {
            step *= 0.5;
        }
    }
    best
}

/// The unit square [0, 1]² as one root cell refined uniformly `levels` times.
pub fn unit_square(levels: u32) -> Quadtree {
    let mut t = Quadtree::new([0.0, 0.0], 1.0, &[(0, 0)], 2);
    for _ in 0..levels {
        let l = t.leaves();
        t.refine(&l);
    }
    t
}
