//! A p-method for the incompressible Navier–Stokes equations on a fixed quadtree: per-cell
//! velocity degree p_K ≥ 2 and pressure degree p_K − 1 (a Taylor–Hood-like pair of hierarchical
//! integrated-Legendre bases, both continuous), steady Newton solves and θ-scheme (Crank–
//! Nicolson) time steps with Newton per step, an error estimate by enrichment and the
//! p-adaptive loop that raises local degrees until every local indicator is below the tolerance.
//!
//! **Spaces.** The velocity is a two-component [`Space`] with [`Basis1d::Hierarchical`] and the
//! cell degrees p_K, the pressure a scalar one with degrees p_K − 1, both on the same leaves, so
//! hanging edges and degree transitions (minimum rule: an edge carries the modes up to the
//! smallest degree of its cells) come from the space. The pressure is fixed up to a constant by
//! pinning its lowest-numbered free dof (a vertex of the first leaf) to 0; error functions take
//! both pressures with zero mean. Dof vector and equations are ordered as in
//! [`super::navier_stokes`]: velocity dofs, then pressure dofs (offset [`PTaylorHood::n_u`]).
//!
//! **Equations** (kinematic pressure, viscosity ν): steady, for all (v, q),
//! ν (∇u, ∇v) + ((u·∇)u, v) − (p, div v) − (q, div u) = (f, v);
//! transient, from u^n at t_n to u^{n+1} at t_{n+1} = t_n + Δt with the θ-scheme,
//! ((u^{n+1} − u^n)/Δt, v) + θ N(u^{n+1}, t_{n+1}; v) + (1 − θ) N(u^n, t_n; v) − (p, div v)
//! − (q, div u^{n+1}) = 0, N(u, t; v) = ν (∇u, ∇v) + ((u·∇)u, v) − (f(t), v), with the pressure
//! implicit (it is the Lagrange multiplier of the step). θ = 1/2 is Crank–Nicolson. The Newton
//! linearisation is exact. Dirichlet data g(x, t) on the whole boundary: the spaces of the new
//! time level are built with g(·, t_{n+1}). Quadrature: ⌈(3p_K + 1)/2⌉ + 1 Gauss points per
//! direction, exact for the convection term.
//!
//! **Estimate** ([`estimate`]). The problem is solved again on the enriched pair (every p_K
//! raised by `enrich`, 1 or 2) and the indicator of a cell is η_K = ‖u_{p+r} − u_p‖_{L²(K)}; the
//! estimate is η = (Σ η_K²)^{1/2}. For exponential convergence in p at rate ρ per degree,
//! ‖u_{p+r} − u‖ ≈ ρ^r ‖u_p − u‖ and the effectivity η / ‖u − u_p‖ lies in [1 − ρ^r, 1 + ρ^r].
//! In the transient problem the enriched solution is advanced side by side with its own history
//! (its own initial projection and its own steps), so η measures the accumulated error.
//!
//! **Adaptive loop.** The tolerance τ is shared out by area: cell K is marked when η_K > τ
//! (|K| / |Ω|)^{1/2} (so that all cells below their share give η ≤ τ), or by Dörfler marking
//! of the η_K while η > τ. Marked cells have their degree raised by one (up to `max_degree`) and
//! the problem is solved again. In the transient problem a step is accepted only when no cell is
//! marked: the step is repeated from t_n with the raised degrees, then time advances. The
//! histories of a repeated step: on the first step, the projections of the initial data onto
//! the raised coarse and enriched spaces; later, the L² projection of the (more accurate)
//! enriched old solution onto the raised coarse space, the enriched history being kept. (A
//! coarse history projected from an inaccurate enriched one would carry the same error in both
//! solutions, invisible to the estimate.)

use super::marking::{dorfler_among, squared_total};
use super::quadtree::Quadtree;
use super::space::{shape_values, Space, SpaceError, MAX_LOCAL_SCALAR};
use crate::assembly::constraints::{ClosedConstraints, CondenseScratch, CondensedPattern};
use crate::element::hierarchical::{gauss_legendre, Basis1d, MAX_DEGREE};
use crate::solver::linear::{LinearError, LinearKind, SparseSolver};
use std::ops::ControlFlow;
use std::rc::Rc;

/// Largest velocity degree of a cell (the pressure has one less).
pub const MAX_VELOCITY_DEGREE: usize = MAX_DEGREE;

/// Errors of the p-method.
#[derive(Debug, thiserror::Error)]
pub enum PnsError {
    #[error(transparent)]
    Space(#[from] SpaceError),
    #[error(transparent)]
    Linear(#[from] LinearError),
    #[error("{what} must be positive and finite, got {value}")]
    Parameter { what: &'static str, value: f64 },
    #[error("expected {expected} cell degrees (one per leaf), got {got}")]
    DegreeCount { expected: usize, got: usize },
    #[error("leaf {cell} has velocity degree {p}; allowed are 2..={max}")]
    Degree { cell: usize, p: usize, max: usize },
    #[error(
        "Newton did not converge at t = {t}: residual {residual:.3e} after {iterations} iterations"
    )]
    NoConvergence {
        t: f64,
        residual: f64,
        iterations: usize,
    },
    #[error("non-finite residual at t = {0}")]
    NonFinite(f64),
    #[error("the pressure space has no free dof to pin")]
    NoPressureDof,
    #[error("the old solution lives on {got} leaves, the new space on {expected}")]
    Mesh { expected: usize, got: usize },
}

/// Condensation of one local dof: (index among the cell's equations, coefficient).
type LocalTerms = Vec<(u32, f64)>;

/// The pair: velocity (degree p_K, 2 components, Dirichlet data) and pressure (p_K − 1).
pub struct PTaylorHood {
    /// The mesh with the velocity degree in every leaf.
    pub tree: Quadtree,
    pub vel: Space,
    pub pres: Space,
    /// Number of velocity dofs (offset of the pressure dofs).
    pub n_u: usize,
    /// The pinned pressure dof (full numbering).
    pub pinned: usize,
    pub constraints: ClosedConstraints,
    pub pattern: CondensedPattern,
    /// Lower-left corner and side of each leaf.
    x0: Vec<[f64; 2]>,
    h: Vec<f64>,
    /// Per cell, per local dof (velocity then pressure): its condensation terms.
    terms: Vec<Vec<LocalTerms>>,
}

/// Gauss rule with `n` points per direction, cached by `n`.
struct Rules(Vec<Option<(Vec<f64>, Vec<f64>)>>);

impl Rules {
    fn new() -> Self {
        Self(Vec::new())
    }
    fn get(&mut self, n: usize) -> &(Vec<f64>, Vec<f64>) {
        if self.0.len() <= n {
            self.0.resize(n + 1, None);
        }
        self.0[n].get_or_insert_with(|| gauss_legendre(n))
    }
}

/// Gauss points per direction for velocity degree p (exact for the convection term).
fn n_quad(p: usize) -> usize {
    (3 * p + 1).div_ceil(2) + 1
}

impl PTaylorHood {
    /// Build the pair on the leaves of `tree` with velocity degrees `degrees` (leaf order of
    /// [`Quadtree::leaves`], each in 2..=[`MAX_VELOCITY_DEGREE`]) and velocity Dirichlet data
    /// `g(x, comp)` on the whole boundary.
    pub fn new(
        tree: &Quadtree,
        degrees: &[usize],
        g: &dyn Fn([f64; 2], usize) -> f64,
    ) -> Result<Self, PnsError> {
        let leaves = tree.leaves();
        if degrees.len() != leaves.len() {
            return Err(PnsError::DegreeCount {
                expected: leaves.len(),
                got: degrees.len(),
            });
        }
        let mut tv = tree.clone();
        let mut tp = tree.clone();
        for (k, (&c, &p)) in leaves.iter().zip(degrees).enumerate() {
            if !(2..=MAX_VELOCITY_DEGREE).contains(&p) {
                return Err(PnsError::Degree {
                    cell: k,
                    p,
                    max: MAX_VELOCITY_DEGREE,
                });
            }
            tv.cells[c as usize].degree = p as u8;
            tp.cells[c as usize].degree = (p - 1) as u8;
        }
        let vel = Space::new(&tv, Basis1d::Hierarchical, 2, Some(g))?;
        let pres = Space::new(&tp, Basis1d::Hierarchical, 1, None)?;
        let n_u = vel.n_dofs();
        let n_eq_u = vel.n_eq();
        let cv = &vel.constraints;
        let cp = &pres.constraints;
        let pin_dof = cp
            .eq
            .iter()
            .position(|&e| e != u32::MAX)
            .ok_or(PnsError::NoPressureDof)?;
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
        let mut terms = Vec::with_capacity(leaves.len());
        for k in 0..leaves.len() {
            let m = pattern.cell_off[k + 1] - pattern.cell_off[k];
            let cm = &pattern.c[pattern.c_off[k]..pattern.c_off[k + 1]];
            let nl = dof_off[k + 1] - dof_off[k];
            terms.push(
                (0..nl)
                    .map(|a| {
                        (0..m)
                            .filter(|&e| cm[a * m + e] != 0.0)
                            .map(|e| (e as u32, cm[a * m + e]))
                            .collect()
                    })
                    .collect(),
            );
        }
        let x0 = leaves.iter().map(|&c| tree.corner(c)).collect();
        let h = leaves.iter().map(|&c| tree.h(c)).collect();
        Ok(Self {
            tree: tv,
            vel,
            pres,
            n_u,
            pinned: n_u + pin_dof,
            constraints,
            pattern,
            x0,
            h,
            terms,
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
    /// Number of leaves.
    pub fn n_cells(&self) -> usize {
        self.vel.leaves.len()
    }
    /// Velocity degree of each leaf.
    pub fn degrees(&self) -> &[usize] {
        &self.vel.degree
    }
    /// Area of leaf `k`.
    pub fn area(&self, k: usize) -> f64 {
        self.h[k] * self.h[k]
    }
    /// Physical point of reference (ξ, η) in leaf `k`.
    pub fn point(&self, k: usize, xi: f64, eta: f64) -> [f64; 2] {
        let h = self.h[k];
        [
            self.x0[k][0] + 0.5 * h * (xi + 1.0),
            self.x0[k][1] + 0.5 * h * (eta + 1.0),
        ]
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

    /// Velocity (u, v) of the dof vector `x` and its gradient [[∂u/∂x, ∂u/∂y], [∂v/∂x,
    /// ∂v/∂y]] at reference (ξ, η) of leaf `k`.
    pub fn velocity(&self, x: &[f64], k: usize, xi: f64, eta: f64) -> ([f64; 2], [[f64; 2]; 2]) {
        let mut n = [0.0; MAX_LOCAL_SCALAR];
        let mut dn = [[0.0; 2]; MAX_LOCAL_SCALAR];
        let nv = self.vel.shape(k, self.h[k], xi, eta, &mut n, &mut dn);
        let dofs = self.vel.dofs(k);
        let (mut u, mut g) = ([0.0; 2], [[0.0; 2]; 2]);
        for a in 0..nv {
            for c in 0..2 {
                let v = x[dofs[2 * a + c] as usize];
                u[c] += n[a] * v;
                g[c][0] += dn[a][0] * v;
                g[c][1] += dn[a][1] * v;
            }
        }
        (u, g)
    }

    /// Pressure of the dof vector `x` at reference (ξ, η) of leaf `k` (pinned normalisation).
    pub fn pressure(&self, x: &[f64], k: usize, xi: f64, eta: f64) -> f64 {
        let mut n = [0.0; MAX_LOCAL_SCALAR];
        let mut dn = [[0.0; 2]; MAX_LOCAL_SCALAR];
        let np = self.pres.shape(k, self.h[k], xi, eta, &mut n, &mut dn);
        let dofs = self.pres.dofs(k);
        (0..np).map(|b| n[b] * x[self.n_u + dofs[b] as usize]).sum()
    }

    /// Condensed residual R(y) = Cᵀ r(C y + b) of the steady equations (`step` = `None`) or of
    /// a θ-step, and, if `jac` is given, the condensed exact Jacobian (values in the slots of
    /// [`PTaylorHood::pattern`]).
    pub fn residual(
        &self,
        y: &[f64],
        physics: &Physics,
        step: Option<&ThetaStep>,
        mut jac: Option<&mut [f64]>,
    ) -> Vec<f64> {
        let x = self.distribute(y);
        let pat = &self.pattern;
        let mut res = vec![0.0; pat.n];
        if let Some(j) = jac.as_deref_mut() {
            j.fill(0.0);
        }
        let nu = physics.nu;
        let (theta, mdt, t1) = match step {
            Some(s) => (s.theta, 1.0 / s.dt, s.t_new),
            None => (1.0, 0.0, physics.t),
        };
        let mut rules = Rules::new();
        let mut n = [0.0; MAX_LOCAL_SCALAR];
        let mut dn = [[0.0; 2]; MAX_LOCAL_SCALAR];
        let mut np = [0.0; MAX_LOCAL_SCALAR];
        let mut dnp = [[0.0; 2]; MAX_LOCAL_SCALAR];
        let mut xl = Vec::new();
        let mut r = Vec::new();
        let mut kl = Vec::new();
        for k in 0..self.n_cells() {
            let p = self.vel.degree[k];
            let h = self.h[k];
            let nv = (p + 1) * (p + 1);
            let npr = p * p;
            let nl = 2 * nv + npr;
            let dofs = &self.pattern_dofs(k);
            xl.clear();
            xl.extend(dofs.iter().map(|&d| x[d]));
            r.clear();
            r.resize(nl, 0.0);
            if jac.is_some() {
                kl.clear();
                kl.resize(nl * nl, 0.0);
            }
            let (gx, gw) = rules.get(n_quad(p)).clone();
            let jw = 0.25 * h * h;
            for (i, &xi) in gx.iter().enumerate() {
                for (jq, &eta) in gx.iter().enumerate() {
                    shape_values(Basis1d::Hierarchical, p, h, xi, eta, &mut n, &mut dn);
                    shape_values(Basis1d::Hierarchical, p - 1, h, xi, eta, &mut np, &mut dnp);
                    let w = gw[i] * gw[jq] * jw;
                    let xq = self.point(k, xi, eta);
                    let mut u = [0.0; 2];
                    let mut gu = [[0.0; 2]; 2];
                    for a in 0..nv {
                        for cc in 0..2 {
                            let v = xl[2 * a + cc];
                            u[cc] += n[a] * v;
                            gu[cc][0] += dn[a][0] * v;
                            gu[cc][1] += dn[a][1] * v;
                        }
                    }
                    let mut pq = 0.0;
                    for b in 0..npr {
                        pq += np[b] * xl[2 * nv + b];
                    }
                    let div = gu[0][0] + gu[1][1];
                    let f1 = (physics.f)(xq, t1);
                    // Old-level terms of the θ-scheme: mass part and (1 − θ) N(u^n).
                    let mut old_val = [0.0; 2];
                    let mut old_grad = [[0.0; 2]; 2];
                    if let Some(s) = step {
                        let (uo, go) = s.old.th.velocity(&s.old.x, k, xi, eta);
                        let fo = (physics.f)(xq, s.t_new - s.dt);
                        for cc in 0..2 {
                            let conv_o = uo[0] * go[cc][0] + uo[1] * go[cc][1];
                            old_val[cc] = -mdt * uo[cc] + (1.0 - theta) * (conv_o - fo[cc]);
                            old_grad[cc] = [
                                (1.0 - theta) * nu * go[cc][0],
                                (1.0 - theta) * nu * go[cc][1],
                            ];
                        }
                    }
                    for a in 0..nv {
                        for cc in 0..2 {
                            let conv = u[0] * gu[cc][0] + u[1] * gu[cc][1];
                            let val = mdt * u[cc] + theta * (conv - f1[cc]) + old_val[cc];
                            let grd = [
                                theta * nu * gu[cc][0] + old_grad[cc][0],
                                theta * nu * gu[cc][1] + old_grad[cc][1],
                            ];
                            r[2 * a + cc] += w
                                * (grd[0] * dn[a][0] + grd[1] * dn[a][1] + val * n[a]
                                    - pq * dn[a][cc]);
                        }
                    }
                    for b in 0..npr {
                        r[2 * nv + b] -= w * np[b] * div;
                    }
                    if jac.is_none() {
                        continue;
                    }
                    for a in 0..nv {
                        let ra = 2 * a;
                        for b in 0..nv {
                            let lap = nu * (dn[a][0] * dn[b][0] + dn[a][1] * dn[b][1]);
                            let adv = (u[0] * dn[b][0] + u[1] * dn[b][1]) * n[a];
                            let diag = w * (mdt * n[a] * n[b] + theta * (lap + adv));
                            let react = w * theta * n[b] * n[a];
                            let cb = 2 * b;
                            kl[ra * nl + cb] += diag + react * gu[0][0];
                            kl[ra * nl + cb + 1] += react * gu[0][1];
                            kl[(ra + 1) * nl + cb] += react * gu[1][0];
                            kl[(ra + 1) * nl + cb + 1] += diag + react * gu[1][1];
                        }
                        for (b, &npb) in np.iter().enumerate().take(npr) {
                            let pb = 2 * nv + b;
                            for cc in 0..2 {
                                let v = w * npb * dn[a][cc];
                                kl[(ra + cc) * nl + pb] -= v;
                                kl[pb * nl + ra + cc] -= v;
                            }
                        }
                    }
                }
            }
            let eqs = &pat.cell_eq[pat.cell_off[k]..pat.cell_off[k + 1]];
            let m = eqs.len();
            let terms = &self.terms[k];
            for a in 0..nl {
                for &(e, c) in &terms[a] {
                    res[eqs[e as usize] as usize] += c * r[a];
                }
            }
            if let Some(jv) = jac.as_deref_mut() {
                let slots = &pat.slots[pat.slot_off[k]..pat.slot_off[k + 1]];
                for a in 0..nl {
                    if terms[a].is_empty() {
                        continue;
                    }
                    for b in 0..nl {
                        let kab = kl[a * nl + b];
                        if kab == 0.0 {
                            continue;
                        }
                        for &(ea, ca) in &terms[a] {
                            for &(eb, cb) in &terms[b] {
                                jv[slots[ea as usize * m + eb as usize]] += ca * cb * kab;
                            }
                        }
                    }
                }
            }
        }
        res
    }

    /// Full dof numbers of the local dofs of leaf `k` (velocity node-major, then pressure).
    fn pattern_dofs(&self, k: usize) -> Vec<usize> {
        self.vel
            .dofs(k)
            .iter()
            .map(|&d| d as usize)
            .chain(self.pres.dofs(k).iter().map(|&d| self.n_u + d as usize))
            .collect()
    }

    /// Full dof vector (pressure zero) of the L² projection of the velocity `u(k, ξ, η, x)`
    /// onto the velocity space (Dirichlet dofs keep the space's boundary data).
    pub fn project_velocity(
        &self,
        u: &dyn Fn(usize, f64, f64, [f64; 2]) -> [f64; 2],
    ) -> Result<Vec<f64>, PnsError> {
        let space = &self.vel;
        let pat = &space.pattern;
        let mut values = vec![0.0; pat.nnz()];
        let mut rhs = vec![0.0; pat.n];
        let mut scratch = CondenseScratch::default();
        let mut rules = Rules::new();
        let mut n = [0.0; MAX_LOCAL_SCALAR];
        let mut dn = [[0.0; 2]; MAX_LOCAL_SCALAR];
        for k in 0..self.n_cells() {
            let p = space.degree[k];
            let nv = (p + 1) * (p + 1);
            let nl = 2 * nv;
            let mut kl = vec![0.0; nl * nl];
            let mut fl = vec![0.0; nl];
            let (gx, gw) = rules.get(p + 4).clone();
            let jw = 0.25 * self.h[k] * self.h[k];
            for (i, &xi) in gx.iter().enumerate() {
                for (j, &eta) in gx.iter().enumerate() {
                    space.shape(k, self.h[k], xi, eta, &mut n, &mut dn);
                    let w = gw[i] * gw[j] * jw;
                    let uq = u(k, xi, eta, self.point(k, xi, eta));
                    for a in 0..nv {
                        for c in 0..2 {
                            fl[2 * a + c] += w * uq[c] * n[a];
                        }
                        for b in 0..nv {
                            let m = w * n[a] * n[b];
                            kl[2 * a * nl + 2 * b] += m;
                            kl[(2 * a + 1) * nl + 2 * b + 1] += m;
                        }
                    }
                }
            }
            pat.add_cell(k, &kl, &fl, &mut values, &mut rhs, &mut scratch);
        }
        let mut solver =
            SparseSolver::new(pat.n, &pat.col_ptr, &pat.row_idx, LinearKind::Cholesky)?;
        solver.set_track_determinant(false);
        solver.factorize(&values)?;
        solver.solve_in_place(&mut rhs)?;
        let mut x = vec![0.0; self.n_dofs()];
        space.constraints.distribute(&rhs, &mut x[..self.n_u]);
        Ok(x)
    }
}

/// Viscosity, body force f(x, t) and, for steady problems, the time at which f is taken.
pub struct Physics<'a> {
    pub nu: f64,
    pub f: &'a dyn Fn([f64; 2], f64) -> [f64; 2],
    pub t: f64,
}

/// One θ-step from `old` (the solution at t_new − dt) to t_new.
pub struct ThetaStep<'a> {
    pub old: &'a Field,
    pub dt: f64,
    pub theta: f64,
    pub t_new: f64,
}

/// A discrete solution: the full dof vector on a pair.
#[derive(Clone)]
pub struct Field {
    pub th: Rc<PTaylorHood>,
    pub x: Vec<f64>,
}

impl Field {
    /// Velocity and gradient at reference (ξ, η) of leaf `k`.
    pub fn velocity(&self, k: usize, xi: f64, eta: f64) -> ([f64; 2], [[f64; 2]; 2]) {
        self.th.velocity(&self.x, k, xi, eta)
    }
    /// Number of equations of the pair.
    pub fn n_eq(&self) -> usize {
        self.th.n_eq()
    }
}

/// Newton iteration statistics of one solve.
#[derive(Clone, Debug)]
pub struct NewtonStats {
    pub iterations: usize,
    /// ‖R‖∞ after each iteration (the first entry is the initial residual).
    pub residuals: Vec<f64>,
}

/// Newton's method with the exact Jacobian and sparse LU from the equation values `y`
/// (overwritten): converged when ‖R‖∞ ≤ `tol` or the update is below 1e-13 ‖y‖∞. A step that
/// does not reduce the residual is halved (at most 8 times).
pub fn solve_newton(
    th: &PTaylorHood,
    y: &mut [f64],
    physics: &Physics,
    step: Option<&ThetaStep>,
    tol: f64,
    max_iter: usize,
) -> Result<NewtonStats, PnsError> {
    if !(physics.nu > 0.0 && physics.nu.is_finite()) {
        return Err(PnsError::Parameter {
            what: "the viscosity",
            value: physics.nu,
        });
    }
    let t = step.map_or(physics.t, |s| s.t_new);
    if let Some(s) = step {
        if s.old.th.n_cells() != th.n_cells() {
            return Err(PnsError::Mesh {
                expected: th.n_cells(),
                got: s.old.th.n_cells(),
            });
        }
        if !(s.dt > 0.0 && s.dt.is_finite()) {
            return Err(PnsError::Parameter {
                what: "the time step",
                value: s.dt,
            });
        }
    }
    let pat = &th.pattern;
    let mut solver = SparseSolver::new(pat.n, &pat.col_ptr, &pat.row_idx, LinearKind::Lu)?;
    solver.set_track_determinant(false);
    let mut jac = vec![0.0; pat.nnz()];
    let norm = |r: &[f64]| r.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut r = th.residual(y, physics, step, Some(&mut jac));
    let mut rn = norm(&r);
    let mut stats = NewtonStats {
        iterations: 0,
        residuals: vec![rn],
    };
    while rn > tol {
        if !rn.is_finite() {
            return Err(PnsError::NonFinite(t));
        }
        if stats.iterations >= max_iter {
            return Err(PnsError::NoConvergence {
                t,
                residual: rn,
                iterations: stats.iterations,
            });
        }
        solver.factorize(&jac)?;
        let mut d: Vec<f64> = r.iter().map(|v| -v).collect();
        solver.solve_in_place(&mut d)?;
        let y0 = y.to_vec();
        let mut lambda = 1.0;
        for _ in 0..9 {
            for i in 0..y.len() {
                y[i] = y0[i] + lambda * d[i];
            }
            let rtn = norm(&th.residual(y, physics, step, None));
            if rtn.is_finite() && (rtn < rn || lambda < 0.01) {
                break;
            }
            lambda *= 0.5;
        }
        r = th.residual(y, physics, step, Some(&mut jac));
        rn = norm(&r);
        stats.iterations += 1;
        stats.residuals.push(rn);
        if lambda == 1.0 && norm(&d) <= 1e-13 * norm(y).max(1.0) {
            break;
        }
    }
    Ok(stats)
}

/// Newton tolerance on ‖R‖∞ and iteration limit used by the drivers.
const NEWTON_TOL: f64 = 1e-11;
const NEWTON_MAX: usize = 25;

/// Per-cell L² and H¹-seminorm norms of a velocity difference.
#[derive(Clone, Debug)]
pub struct CellNorms {
    pub l2: Vec<f64>,
    pub h1: Vec<f64>,
}

impl CellNorms {
    /// (Σ l2²)^{1/2}.
    pub fn l2_total(&self) -> f64 {
        self.l2.iter().map(|e| e * e).sum::<f64>().sqrt()
    }
    /// (Σ h1²)^{1/2}.
    pub fn h1_total(&self) -> f64 {
        self.h1.iter().map(|e| e * e).sum::<f64>().sqrt()
    }
}

/// Velocity and gradient at reference (ξ, η) of leaf k and physical point x.
type CellEval<'a> = &'a dyn Fn(usize, f64, f64, [f64; 2]) -> ([f64; 2], [[f64; 2]; 2]);

/// Per-cell norms of v_a − v_b, where `a(k, ξ, η, x)` and `b` give velocity and gradient;
/// `nq(k)` Gauss points per direction.
fn cell_norms(
    th: &PTaylorHood,
    nq: &dyn Fn(usize) -> usize,
    a: CellEval,
    b: CellEval,
) -> CellNorms {
    let mut rules = Rules::new();
    let mut out = CellNorms {
        l2: Vec::with_capacity(th.n_cells()),
        h1: Vec::with_capacity(th.n_cells()),
    };
    for k in 0..th.n_cells() {
        let (gx, gw) = rules.get(nq(k)).clone();
        let jw = th.area(k) / 4.0;
        let (mut e0, mut e1) = (0.0, 0.0);
        for (i, &xi) in gx.iter().enumerate() {
            for (j, &eta) in gx.iter().enumerate() {
                let xq = th.point(k, xi, eta);
                let (ua, ga) = a(k, xi, eta, xq);
                let (ub, gb) = b(k, xi, eta, xq);
                let w = gw[i] * gw[j] * jw;
                for c in 0..2 {
                    e0 += w * (ua[c] - ub[c]).powi(2);
                    e1 += w * ((ga[c][0] - gb[c][0]).powi(2) + (ga[c][1] - gb[c][1]).powi(2));
                }
            }
        }
        out.l2.push(e0.sqrt());
        out.h1.push(e1.sqrt());
    }
    out
}

/// Per-cell norms of the difference of two solutions on the same leaves (the enrichment
/// indicator when `fine` is the enriched solution).
pub fn difference(fine: &Field, coarse: &Field) -> CellNorms {
    let pmax = |k: usize| fine.th.degrees()[k].max(coarse.th.degrees()[k]);
    cell_norms(
        &coarse.th,
        &|k| pmax(k) + 2,
        &|k, xi, eta, _| fine.velocity(k, xi, eta),
        &|k, xi, eta, _| coarse.velocity(k, xi, eta),
    )
}

/// An exact velocity and its gradient at a point.
pub type ExactVelocity<'a> = &'a dyn Fn([f64; 2]) -> ([f64; 2], [[f64; 2]; 2]);

/// Per-cell norms of the error of `sol` against the exact velocity (p_K + 6 Gauss points per
/// direction).
pub fn exact_error(sol: &Field, exact: ExactVelocity) -> CellNorms {
    cell_norms(
        &sol.th,
        &|k| sol.th.degrees()[k] + 6,
        &|_, _, _, x| exact(x),
        &|k, xi, eta, _| sol.velocity(k, xi, eta),
    )
}

/// ‖(p − p̄) − (p_h − p̄_h)‖_{L²(Ω)}: the pressure error with both means removed.
pub fn pressure_error(sol: &Field, p: &dyn Fn([f64; 2]) -> f64) -> f64 {
    let th = &sol.th;
    let mut rules = Rules::new();
    let mut samples = Vec::new();
    let (mut pm, mut phm, mut area) = (0.0, 0.0, 0.0);
    for k in 0..th.n_cells() {
        let (gx, gw) = rules.get(th.degrees()[k] + 6).clone();
        let jw = th.area(k) / 4.0;
        for (i, &xi) in gx.iter().enumerate() {
            for (j, &eta) in gx.iter().enumerate() {
                let w = gw[i] * gw[j] * jw;
                let pe = p(th.point(k, xi, eta));
                let ph = th.pressure(&sol.x, k, xi, eta);
                pm += w * pe;
                phm += w * ph;
                area += w;
                samples.push((w, pe, ph));
            }
        }
    }
    pm /= area;
    phm /= area;
    samples
        .iter()
        .map(|&(w, pe, ph)| w * (pe - pm - ph + phm).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// Estimate against the true error of one solution.
#[derive(Clone, Debug)]
pub struct Effectivity {
    /// η = (Σ η_K²)^{1/2}.
    pub estimate: f64,
    /// ‖u − u_h‖_{L²(Ω)}.
    pub error: f64,
    /// η / ‖u − u_h‖.
    pub global: f64,
    /// Smallest and largest η_K / ‖u − u_h‖_{L²(K)} over the cells.
    pub local_min: f64,
    pub local_max: f64,
}

/// Global and local effectivity indices of the indicators `eta` against the true cell errors.
pub fn effectivity(eta: &[f64], err: &CellNorms) -> Effectivity {
    let estimate = eta.iter().map(|e| e * e).sum::<f64>().sqrt();
    let error = err.l2_total();
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for (e, t) in eta.iter().zip(&err.l2) {
        let r = e / t;
        lo = lo.min(r);
        hi = hi.max(r);
    }
    Effectivity {
        estimate,
        error,
        global: estimate / error,
        local_min: lo,
        local_max: hi,
    }
}

/// Degrees raised by `r` (capped at [`MAX_VELOCITY_DEGREE`]).
pub fn enriched(degrees: &[usize], r: usize) -> Vec<usize> {
    degrees
        .iter()
        .map(|&p| (p + r).min(MAX_VELOCITY_DEGREE))
        .collect()
}

/// Histogram of degrees: (degree, number of cells), increasing degree.
pub fn degree_histogram(degrees: &[usize]) -> Vec<(usize, usize)> {
    let mut h: Vec<(usize, usize)> = Vec::new();
    let mut d = degrees.to_vec();
    d.sort_unstable();
    for p in d {
        match h.last_mut() {
            Some((q, n)) if *q == p => *n += 1,
            _ => h.push((p, 1)),
        }
    }
    h
}

/// Marking of the p-adaptive loop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PMarking {
    /// Mark every cell with η_K > τ (|K| / |Ω|)^{1/2}.
    Tolerance,
    /// While η > τ, Dörfler marking with parameter θ of the squared indicators, among the
    /// cells below the largest degree ([`super::marking::dorfler_among`]).
    Dorfler(f64),
}

/// Parameters of the p-adaptive loop.
#[derive(Clone, Copy, Debug)]
pub struct PAdaptParams {
    /// Tolerance τ on the L² velocity estimate (infinite: no adaptation).
    pub tol: f64,
    /// Degree increment of the enriched solve of the estimate (1 or 2).
    pub enrich: usize,
    pub marking: PMarking,
    /// Largest degree a cell may be raised to (the enriched one adds `enrich`).
    pub max_degree: usize,
    /// Largest number of solves per step (steady: in total).
    pub max_sweeps: usize,
}

impl PAdaptParams {
    fn check(&self) -> Result<(), PnsError> {
        if self.tol.is_nan() || self.tol <= 0.0 {
            return Err(PnsError::Parameter {
                what: "the tolerance",
                value: self.tol,
            });
        }
        if !(1..=2).contains(&self.enrich) {
            return Err(PnsError::Parameter {
                what: "the enrichment (1 or 2)",
                value: self.enrich as f64,
            });
        }
        if self.max_degree + self.enrich > MAX_VELOCITY_DEGREE || self.max_degree < 2 {
            return Err(PnsError::Degree {
                cell: 0,
                p: self.max_degree + self.enrich,
                max: MAX_VELOCITY_DEGREE,
            });
        }
        Ok(())
    }
}

/// Cells to raise: indices whose degree is below `max_degree`.
pub fn mark_cells(th: &PTaylorHood, eta: &[f64], params: &PAdaptParams) -> Vec<usize> {
    if !params.tol.is_finite() {
        return Vec::new();
    }
    let total_area: f64 = (0..th.n_cells()).map(|k| th.area(k)).sum();
    let can = |k: usize| th.degrees()[k] < params.max_degree;
    match params.marking {
        PMarking::Tolerance => (0..eta.len())
            .filter(|&k| can(k) && eta[k] > params.tol * (th.area(k) / total_area).sqrt())
            .collect(),
        PMarking::Dorfler(theta) => {
            if squared_total(eta).sqrt() <= params.tol {
                return Vec::new();
            }
            dorfler_among(eta, theta, (0..eta.len()).filter(|&k| can(k)))
        }
    }
}

/// Largest η_K / τ_K with τ_K = τ (|K| / |Ω|)^{1/2} (≤ 1: every cell within its share).
pub fn worst_ratio(th: &PTaylorHood, eta: &[f64], tol: f64) -> f64 {
    let total_area: f64 = (0..th.n_cells()).map(|k| th.area(k)).sum();
    (0..eta.len())
        .map(|k| eta[k] / (tol * (th.area(k) / total_area).sqrt()))
        .fold(0.0, f64::max)
}

/// A steady problem: viscosity, Dirichlet data g(x, comp), body force and (optionally) the
/// exact velocity.
pub struct SteadyProblem<'a> {
    pub nu: f64,
    pub g: &'a dyn Fn([f64; 2], usize) -> f64,
    pub f: &'a dyn Fn([f64; 2], f64) -> [f64; 2],
    pub exact: Option<ExactVelocity<'a>>,
}

/// A solution with its estimate.
pub struct Estimated {
    pub coarse: Field,
    pub fine: Field,
    /// η_K = ‖u_fine − u_coarse‖_{L²(K)}.
    pub indicators: Vec<f64>,
    pub newton: [NewtonStats; 2],
}

/// Solve the steady problem on `degrees` and on `degrees` + `enrich`, and the indicators.
pub fn estimate(
    tree: &Quadtree,
    degrees: &[usize],
    problem: &SteadyProblem,
    enrich: usize,
) -> Result<Estimated, PnsError> {
    let physics = Physics {
        nu: problem.nu,
        f: problem.f,
        t: 0.0,
    };
    let solve = |d: &[usize], guess: Option<&Field>| -> Result<(Field, NewtonStats), PnsError> {
        let th = Rc::new(PTaylorHood::new(tree, d, problem.g)?);
        let mut y = match guess {
            Some(gf) => {
                th.gather(&th.project_velocity(&|k, xi, eta, _| gf.velocity(k, xi, eta).0)?)
            }
            None => vec![0.0; th.n_eq()],
        };
        let stats = solve_newton(&th, &mut y, &physics, None, NEWTON_TOL, NEWTON_MAX)?;
        let x = th.distribute(&y);
        Ok((Field { th, x }, stats))
    };
    let (coarse, s0) = solve(degrees, None)?;
    let (fine, s1) = solve(&enriched(degrees, enrich), Some(&coarse))?;
    let indicators = difference(&fine, &coarse).l2;
    Ok(Estimated {
        coarse,
        fine,
        indicators,
        newton: [s0, s1],
    })
}

/// One solve of an adaptive loop (a sweep of the steady loop or the accepted or rejected
/// attempt of a time step).
#[derive(Clone, Debug)]
pub struct SweepReport {
    /// Time of the solution (steady: 0).
    pub t: f64,
    /// Index of the attempt within the step (steady: the sweep).
    pub sweep: usize,
    pub degrees: Vec<usize>,
    /// Unknowns (equations) of the pair.
    pub n_eq: usize,
    /// Unknowns of the enriched pair.
    pub n_eq_enriched: usize,
    pub estimate: f64,
    /// Largest η_K / τ_K (infinite tolerance: 0).
    pub worst_ratio: f64,
    /// Estimate against the exact solution, if known.
    pub effectivity: Option<Effectivity>,
    /// Whether the solution was accepted (transient: time advanced after it).
    pub accepted: bool,
    pub newton_iterations: usize,
}

fn report(
    (t, sweep): (f64, usize),
    est_coarse: &Field,
    fine: &Field,
    eta: &[f64],
    params: &PAdaptParams,
    exact: Option<ExactVelocity>,
    newton_iterations: usize,
) -> SweepReport {
    let effectivity = exact.map(|e| effectivity(eta, &exact_error(est_coarse, e)));
    SweepReport {
        t,
        sweep,
        degrees: est_coarse.th.degrees().to_vec(),
        n_eq: est_coarse.n_eq(),
        n_eq_enriched: fine.n_eq(),
        estimate: eta.iter().map(|e| e * e).sum::<f64>().sqrt(),
        worst_ratio: if params.tol.is_finite() {
            worst_ratio(&est_coarse.th, eta, params.tol)
        } else {
            0.0
        },
        effectivity,
        accepted: false,
        newton_iterations,
    }
}

/// The steady p-adaptive loop from `degrees`: solve, estimate, mark, raise, until no cell is
/// marked (or every cell above its share is at `max_degree`: then
/// [`SweepReport::worst_ratio`] > 1) or `max_sweeps` solves (the last report is then not
/// `accepted`). Returns one report per sweep and the last solution.
pub fn adapt_steady(
    tree: &Quadtree,
    degrees: &[usize],
    problem: &SteadyProblem,
    params: &PAdaptParams,
) -> Result<(Vec<SweepReport>, Estimated), PnsError> {
    adapt_steady_until(tree, degrees, problem, params, &|| false)
}

/// [`adapt_steady`], also ending after the sweep at which `stop()` is true (that sweep's
/// report is then not `accepted` unless no cell was marked).
pub fn adapt_steady_until(
    tree: &Quadtree,
    degrees: &[usize],
    problem: &SteadyProblem,
    params: &PAdaptParams,
    stop: &dyn Fn() -> bool,
) -> Result<(Vec<SweepReport>, Estimated), PnsError> {
    params.check()?;
    let mut d = degrees.to_vec();
    let mut reports = Vec::new();
    for sweep in 0.. {
        let est = estimate(tree, &d, problem, params.enrich)?;
        let mut rep = report(
            (0.0, sweep),
            &est.coarse,
            &est.fine,
            &est.indicators,
            params,
            problem.exact,
            est.newton[0].iterations + est.newton[1].iterations,
        );
        let marked = mark_cells(&est.coarse.th, &est.indicators, params);
        if marked.is_empty() || sweep + 1 >= params.max_sweeps || stop() {
            rep.accepted = marked.is_empty();
            reports.push(rep);
            return Ok((reports, est));
        }
        reports.push(rep);
        for k in marked {
            d[k] += 1;
        }
    }
    unreachable!("the loop returns")
}

/// An exact velocity and its gradient at (x, t).
pub type ExactTransient<'a> = &'a dyn Fn([f64; 2], f64) -> ([f64; 2], [[f64; 2]; 2]);

/// A transient problem: viscosity, Dirichlet data g(x, t, comp), body force f(x, t), initial
/// velocity and (optionally) the exact velocity at (x, t).
pub struct TransientProblem<'a> {
    pub nu: f64,
    pub g: &'a dyn Fn([f64; 2], f64, usize) -> f64,
    pub f: &'a dyn Fn([f64; 2], f64) -> [f64; 2],
    pub u0: &'a dyn Fn([f64; 2]) -> [f64; 2],
    pub exact: Option<ExactTransient<'a>>,
}

/// Time stepping: step size, number of steps, θ (1/2: Crank–Nicolson).
#[derive(Clone, Copy, Debug)]
pub struct TimeParams {
    pub dt: f64,
    pub n_steps: usize,
    pub theta: f64,
}

fn check_time(time: &TimeParams) -> Result<(), PnsError> {
    if !(time.dt > 0.0 && time.dt.is_finite()) {
        return Err(PnsError::Parameter {
            what: "the time step",
            value: time.dt,
        });
    }
    if !(time.theta >= 0.5 && time.theta <= 1.0) {
        return Err(PnsError::Parameter {
            what: "theta (in [1/2, 1])",
            value: time.theta,
        });
    }
    Ok(())
}

/// The pair on `degrees` with the Dirichlet data of time `t`.
pub fn pair_at(
    tree: &Quadtree,
    degrees: &[usize],
    problem: &TransientProblem,
    t: f64,
) -> Result<Rc<PTaylorHood>, PnsError> {
    Ok(Rc::new(PTaylorHood::new(tree, degrees, &|x, c| {
        (problem.g)(x, t, c)
    })?))
}

/// The initial field: the L² projection of u₀ onto the velocity space of `degrees` (boundary
/// dofs from g(·, 0)).
pub fn initial_field(
    tree: &Quadtree,
    degrees: &[usize],
    problem: &TransientProblem,
) -> Result<Field, PnsError> {
    let th = pair_at(tree, degrees, problem, 0.0)?;
    let x = th.project_velocity(&|_, _, _, x| (problem.u0)(x))?;
    Ok(Field { th, x })
}

/// One θ-step from `hist` (at t_new − dt, on the same leaves, any degrees) to `t_new` on the
/// pair of `degrees`, by Newton from the old velocity projected onto the new space.
pub fn theta_step(
    tree: &Quadtree,
    degrees: &[usize],
    problem: &TransientProblem,
    time: &TimeParams,
    hist: &Field,
    t_new: f64,
) -> Result<(Field, NewtonStats), PnsError> {
    check_time(time)?;
    let physics = Physics {
        nu: problem.nu,
        f: problem.f,
        t: t_new,
    };
    let th = pair_at(tree, degrees, problem, t_new)?;
    if hist.th.n_cells() != th.n_cells() {
        return Err(PnsError::Mesh {
            expected: th.n_cells(),
            got: hist.th.n_cells(),
        });
    }
    let mut y = th.gather(&th.project_velocity(&|k, xi, eta, _| hist.velocity(k, xi, eta).0)?);
    let step = ThetaStep {
        old: hist,
        dt: time.dt,
        theta: time.theta,
        t_new,
    };
    let s = solve_newton(&th, &mut y, &physics, Some(&step), NEWTON_TOL, NEWTON_MAX)?;
    let x = th.distribute(&y);
    Ok((Field { th, x }, s))
}

/// The transient p-adaptive run from t = 0 with initial degrees `degrees`. Every attempt of
/// every step is reported (the accepted one last, `accepted` set); with an infinite tolerance
/// every step is accepted at once (uniform run with its estimate). A step is also accepted
/// after `max_sweeps` attempts, or when every cell above its share is at `max_degree`; its
/// [`SweepReport::worst_ratio`] is then above 1.
pub fn run_transient(
    tree: &Quadtree,
    degrees: &[usize],
    problem: &TransientProblem,
    time: &TimeParams,
    params: &PAdaptParams,
) -> Result<Vec<SweepReport>, PnsError> {
    run_transient_observed(tree, degrees, problem, time, params, &mut |_, _, _, _| {
        ControlFlow::Continue(())
    })
}

/// What [`run_transient_observed`] calls on every accepted step: (report, solution, enriched
/// solution, indicators); [`ControlFlow::Break`] stops the run after that step.
pub type StepObserver<'a> =
    &'a mut dyn FnMut(&SweepReport, &Field, &Field, &[f64]) -> ControlFlow<()>;

/// [`run_transient`], calling `each(report, solution, enriched solution, indicators)` on every
/// accepted step (and stopping after the step where it returns [`ControlFlow::Break`]).
pub fn run_transient_observed(
    tree: &Quadtree,
    degrees: &[usize],
    problem: &TransientProblem,
    time: &TimeParams,
    params: &PAdaptParams,
    each: StepObserver,
) -> Result<Vec<SweepReport>, PnsError> {
    params.check()?;
    check_time(time)?;
    let initial = |d: &[usize]| initial_field(tree, d, problem);
    let mut d = degrees.to_vec();
    let mut old = initial(&d)?;
    let mut old_fine = initial(&enriched(&d, params.enrich))?;
    let mut reports = Vec::new();
    for n in 0..time.n_steps {
        let t_new = (n + 1) as f64 * time.dt;
        let t_old = n as f64 * time.dt;
        for sweep in 0.. {
            let advance = |hist: &Field, deg: &[usize]| -> Result<(Field, usize), PnsError> {
                let (f, s) = theta_step(tree, deg, problem, time, hist, t_new)?;
                Ok((f, s.iterations))
            };
            let (new, i0) = advance(&old, &d)?;
            let (new_fine, i1) = advance(&old_fine, &enriched(&d, params.enrich))?;
            let eta = difference(&new_fine, &new).l2;
            let exact = problem.exact.map(|e| move |x: [f64; 2]| e(x, t_new));
            let exact_ref = exact.as_ref().map(|e| e as &dyn Fn([f64; 2]) -> _);
            let mut rep = report(
                (t_new, sweep),
                &new,
                &new_fine,
                &eta,
                params,
                exact_ref,
                i0 + i1,
            );
            let marked = mark_cells(&new.th, &eta, params);
            if marked.is_empty() || sweep + 1 >= params.max_sweeps {
                rep.accepted = true;
                let flow = each(&rep, &new, &new_fine, &eta);
                reports.push(rep);
                if flow.is_break() {
                    return Ok(reports);
                }
                old = new;
                old_fine = new_fine;
                break;
            }
            reports.push(rep);
            for k in marked {
                d[k] += 1;
            }
            // The step is repeated from t_n. On the first step both histories are the
            // projections of the initial data onto the raised spaces; later, the coarse
            // history becomes the projection of the enriched history onto the raised space
            // (the enriched history is kept: it is only evaluated).
            if n == 0 {
                old = initial(&d)?;
                old_fine = initial(&enriched(&d, params.enrich))?;
            } else {
                let th = pair_at(tree, &d, problem, t_old)?;
                let x = th.project_velocity(&|k, xi, eta, _| old_fine.velocity(k, xi, eta).0)?;
                old = Field { th, x };
            }
        }
    }
    Ok(reports)
}
