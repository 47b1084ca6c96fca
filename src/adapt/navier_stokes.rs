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
//! nodes belong to the walls); on the top edge of a corner cell the space's boundary projection
//! (vertex values, then the H¹-seminorm projection of the rest) gives the linear ramp from 0 at
//! the corner to 1. The regularised lid is U = 16 x² (1 − x)².
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
        Ok(Self {
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
            let c = self.vel.leaves[k];
            let h = self.tree.h(c);
            let dofs = self.local_dofs(k);
            let mut xl = [0.0; NL];
            for (a, &d) in dofs.iter().enumerate() {
                xl[a] = x[d];
            }
            let mut r = [0.0; NL];
            let mut kl = [[0.0; NL]; NL];
            for (i, &xi) in gx.iter().enumerate() {
                for (jq, &eta) in gx.iter().enumerate() {
                    let w = gw[i] * gw[jq] * 0.25 * h * h;
                    shape_values(Basis1d::Lagrange, 2, h, xi, eta, &mut n, &mut dn);
                    shape_values(Basis1d::Lagrange, 1, h, xi, eta, &mut np, &mut dnp);
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
                    let fx = f(self.tree.map_point(c, xi, eta));
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
        let (c, xi, eta) = self.th.tree.locate(p).ok_or(NsError::Outside(p[0], p[1]))?;
        let k = self.th.vel.leaf_index[&c];
        let (u, gu) = self.th.vel.eval(&self.th.tree, &self.x, k, 0, xi, eta);
        let (v, gv) = self.th.vel.eval(&self.th.tree, &self.x, k, 1, xi, eta);
        Ok(([u, v], [gu, gv]))
    }
    /// Pressure at a point (with the pinned normalisation).
    pub fn pressure(&self, p: [f64; 2]) -> Result<f64, NsError> {
        let (c, xi, eta) = self.th.tree.locate(p).ok_or(NsError::Outside(p[0], p[1]))?;
        let k = self.th.pres.leaf_index[&c];
        let xp = &self.x[self.th.n_u..];
        Ok(self.th.pres.eval(&self.th.tree, xp, k, 0, xi, eta).0)
    }
    /// Mean of the pressure over Ω divided by |Ω|.
    pub fn pressure_mean(&self) -> f64 {
        let (gx, gw) = gauss_legendre(3);
        let xp = &self.x[self.th.n_u..];
        let (mut s, mut area) = (0.0, 0.0);
        for k in 0..self.th.pres.leaves.len() {
            let h = self.th.tree.h(self.th.pres.leaves[k]);
            for (i, &a) in gx.iter().enumerate() {
                for (j, &b) in gx.iter().enumerate() {
                    let w = gw[i] * gw[j] * 0.25 * h * h;
                    s += w * self.th.pres.eval(&self.th.tree, xp, k, 0, a, b).0;
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
    let xp = &sol.x[th.n_u..];
    // Means of p and p_h.
    let (mut pm, mut phm, mut area) = (0.0, 0.0, 0.0);
    for k in 0..th.vel.leaves.len() {
        let c = th.vel.leaves[k];
        let h = th.tree.h(c);
        for (i, &a) in gx.iter().enumerate() {
            for (j, &b) in gx.iter().enumerate() {
                let w = gw[i] * gw[j] * 0.25 * h * h;
                pm += w * p(th.tree.map_point(c, a, b));
                phm += w * th.pres.eval(&th.tree, xp, k, 0, a, b).0;
                area += w;
            }
        }
    }
    pm /= area;
    phm /= area;
    let (mut eu, mut eg, mut ep) = (0.0, 0.0, 0.0);
    for k in 0..th.vel.leaves.len() {
        let c = th.vel.leaves[k];
        let h = th.tree.h(c);
        for (i, &a) in gx.iter().enumerate() {
            for (j, &b) in gx.iter().enumerate() {
                let w = gw[i] * gw[j] * 0.25 * h * h;
                let xq = th.tree.map_point(c, a, b);
                let ue = u(xq);
                let ge = grad_u(xq);
                for comp in 0..2 {
                    let (v, g) = th.vel.eval(&th.tree, &sol.x, k, comp, a, b);
                    eu += w * (ue[comp] - v).powi(2);
                    eg += w * ((ge[comp][0] - g[0]).powi(2) + (ge[comp][1] - g[1]).powi(2));
                }
                let ph = th.pres.eval(&th.tree, xp, k, 0, a, b).0 - phm;
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
    let kref = super::poisson::reference_stiffness(Basis1d::Lagrange, 2);
    let pat = &space.pattern;
    let mut values = vec![0.0; pat.nnz()];
    let mut rhs = vec![0.0; pat.n];
    let mut scratch = CondenseScratch::default();
    let (gx, gw) = gauss_legendre(NQ);
    let mut n = [0.0; MAX_LOCAL_SCALAR];
    let mut dn = [[0.0; 2]; MAX_LOCAL_SCALAR];
    let mut fl = [0.0; NV];
    for k in 0..space.leaves.len() {
        let h = th.tree.h(space.leaves[k]);
        fl.fill(0.0);
        for (i, &a) in gx.iter().enumerate() {
            for (j, &b) in gx.iter().enumerate() {
                let w = gw[i] * gw[j] * 0.25 * h * h;
                let (_, gu) = th.vel.eval(&th.tree, &sol.x, k, 0, a, b);
                let (_, gv) = th.vel.eval(&th.tree, &sol.x, k, 1, a, b);
                let om = gv[0] - gu[1];
                space.shape(k, h, a, b, &mut n, &mut dn);
                for (q, fq) in fl.iter_mut().enumerate() {
                    *fq += w * om * n[q];
                }
            }
        }
        pat.add_cell(k, &kref, &fl, &mut values, &mut rhs, &mut scratch);
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
/// polished by a compass search (step down to 1e-10).
pub fn psi_min(tree: &Quadtree, space: &Space, psi: &[f64]) -> ([f64; 2], f64) {
    let eval = |p: [f64; 2]| -> f64 {
        match tree.locate(p) {
            Some((c, xi, eta)) => space.eval(tree, psi, space.leaf_index[&c], 0, xi, eta).0,
            None => f64::INFINITY,
        }
    };
    let mut best = ([0.5, 0.5], f64::INFINITY);
    for k in 0..space.leaves.len() {
        let c = space.leaves[k];
        for i in 0..9 {
            for j in 0..9 {
                let (xi, eta) = (-1.0 + 0.25 * i as f64, -1.0 + 0.25 * j as f64);
                let v = space.eval(tree, psi, k, 0, xi, eta).0;
                if v < best.1 {
                    best = (tree.map_point(c, xi, eta), v);
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
