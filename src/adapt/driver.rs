//! The adapt loop as five named steps, **solve → estimate → mark → refine → transfer**, for the
//! Poisson model problem on a quadtree, with h-, p- and hp-refinement.
//!
//! * [`mark`]: Dörfler bulk marking (the smallest set M with Σ_M η_K² ≥ θ Σ η_K²) or maximum
//!   marking (η_K ≥ θ max η), shared with the other adapt loops ([`super::marking`]).
//! * [`refine`]: h (split marked cells; the tree keeps the mesh one-irregular), p (raise the
//!   degree of marked cells by one, up to `max_degree`), or hp (per marked cell: raise p where
//!   the hierarchical coefficients of u_h decay, ‖∇u_p‖_K ≤ `hp_decay` ‖∇u_{p−1}‖_K with u_k the
//!   part of u_h of exact degree k, else split).
//! * [`transfer`]: interpolation of the old solution into the new space (cell by cell, by
//!   collocation at (p + 1)² Gauss points; exact when the old space is contained in the new
//!   one), used as the initial guess of the iterative solver.
//!
//! Every step is timed separately; the exact error is evaluated outside the timed steps.

use super::estimate::{
    Context, Equilibrated, Estimator, ExplicitResidual, Interpolation, Recovery,
};
pub use super::marking::{mark, Marking};
use super::marking::{CellEstimate, CellEstimator};
use super::poisson::{assemble, energy_error_sq, solve_cg, solve_direct, Exact};
use super::quadtree::Quadtree;
use super::space::{shape_values, Space, SpaceError, MAX_LOCAL_SCALAR};
use crate::element::hierarchical::{gauss_legendre, Basis1d};
use nalgebra::DMatrix;
use std::ops::ControlFlow;
use std::time::Instant;

/// Refinement kind.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Strategy {
    H,
    P,
    Hp,
}

/// Which estimator drives the marking.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EstimatorKind {
    Explicit,
    Equilibrated,
    Recovery,
    Interpolation,
}

/// The chosen estimator, itself an estimator of the quadtree's [`Context`].
impl CellEstimator<Context<'_>> for EstimatorKind {
    type Error = SpaceError;
    fn name(&self) -> &'static str {
        self.get().name()
    }
    fn estimate(&self, ctx: &Context) -> Result<CellEstimate, SpaceError> {
        self.get().estimate(ctx)
    }
}

impl EstimatorKind {
    pub fn get(self) -> Box<dyn Estimator> {
        match self {
            EstimatorKind::Explicit => Box::new(ExplicitResidual),
            EstimatorKind::Equilibrated => Box::new(Equilibrated),
            EstimatorKind::Recovery => Box::new(Recovery),
            EstimatorKind::Interpolation => Box::new(Interpolation),
        }
    }
}

/// Linear solver of the solve step.
#[derive(Clone, Copy, Debug)]
pub enum Solver {
    /// Sparse Cholesky.
    Direct,
    /// Jacobi-preconditioned CG from the transferred solution, to relative residual `tol`.
    Cg { tol: f64 },
}

/// Refine marked leaves (indices into `space.leaves`).
pub fn refine(
    tree: &mut Quadtree,
    space: &Space,
    x: &[f64],
    marked: &[usize],
    strategy: Strategy,
    max_degree: usize,
    hp_decay: f64,
) {
    let ids: Vec<u32> = marked.iter().map(|&k| space.leaves[k]).collect();
    match strategy {
        Strategy::H => tree.refine(&ids),
        Strategy::P => {
            for &c in &ids {
                let d = &mut tree.cells[c as usize].degree;
                *d = (*d + 1).min(max_degree as u8);
            }
        }
        Strategy::Hp => {
            let mut split = Vec::new();
            for (&k, &c) in marked.iter().zip(&ids) {
                let p = space.degree[k];
                let smooth = p >= 2 && {
                    let (top, below) = degree_parts(tree, space, x, k);
                    top <= hp_decay * below
                };
                if smooth && p < max_degree {
                    tree.cells[c as usize].degree = p as u8 + 1;
                } else {
                    split.push(c);
                }
            }
            tree.refine(&split);
        }
    }
}

/// ‖∇u_p‖_K and ‖∇u_{p−1}‖_K: the energy of the local part of u_h of exact degree p and p − 1
/// (hierarchical coefficients with max(i, j) = p, resp. p − 1; i, j entity indices ≥ 2).
fn degree_parts(tree: &Quadtree, space: &Space, x: &[f64], k: usize) -> (f64, f64) {
    let p = space.degree[k];
    let h = tree.h(space.leaves[k]);
    let dofs = space.dofs(k);
    let m = p + 1;
    let deg_of = |a: usize| {
        let (i, j) = (a % m, a / m);
        let di = if i < 2 { 1 } else { i };
        let dj = if j < 2 { 1 } else { j };
        di.max(dj)
    };
    let (gx, gw) = gauss_legendre(p + 1);
    let mut n = [0.0; MAX_LOCAL_SCALAR];
    let mut dn = [[0.0; 2]; MAX_LOCAL_SCALAR];
    let (mut top, mut below) = (0.0, 0.0);
    for (i, &xi) in gx.iter().enumerate() {
        for (j, &eta) in gx.iter().enumerate() {
            let nl = shape_values(space.basis, p, h, xi, eta, &mut n, &mut dn);
            let (mut gt, mut gb) = ([0.0; 2], [0.0; 2]);
            for a in 0..nl {
                let v = x[dofs[a] as usize];
                let d = deg_of(a);
                if d == p {
                    gt[0] += dn[a][0] * v;
                    gt[1] += dn[a][1] * v;
                } else if d + 1 == p {
                    gb[0] += dn[a][0] * v;
                    gb[1] += dn[a][1] * v;
                }
            }
            let w = gw[i] * gw[j];
            top += w * (gt[0] * gt[0] + gt[1] * gt[1]);
            below += w * (gb[0] * gb[0] + gb[1] * gb[1]);
        }
    }
    (top.sqrt(), below.sqrt())
}

/// Interpolate the old solution (`old_space` on `old_tree`) into `new_space` on `new_tree`;
/// returns the full dof vector of the new space (constrained and fixed dofs from the
/// constraints).
pub fn transfer(
    old_tree: &Quadtree,
    old_space: &Space,
    old_x: &[f64],
    new_tree: &Quadtree,
    new_space: &Space,
) -> Vec<f64> {
    let mut y = vec![0.0; new_space.n_eq()];
    let maxp = new_space.degree.iter().copied().max().unwrap_or(1);
    // Inverse 1D collocation matrices per degree.
    let inv: Vec<(Vec<f64>, DMatrix<f64>)> = (0..=maxp)
        .map(|p| {
            let (t, _) = gauss_legendre(p + 1);
            let mut v = DMatrix::<f64>::zeros(p + 1, p + 1);
            for (i, &ti) in t.iter().enumerate() {
                let (b, _, _) = new_space.basis.eval(p.max(1), ti);
                for mm in 0..=p {
                    v[(i, mm)] = b[mm];
                }
            }
            let vi = v
                .try_inverse()
                .unwrap_or_else(|| DMatrix::zeros(p + 1, p + 1));
            (t, vi)
        })
        .collect();
    for k in 0..new_space.leaves.len() {
        let p = new_space.degree[k];
        let c = new_space.leaves[k];
        let (t, vi) = &inv[p];
        let m = p + 1;
        // Values at the tensor points (i along ξ), fixed-size scratch.
        const M: usize = crate::element::hierarchical::MAX_1D;
        let mut u = [[0.0f64; M]; M];
        for (i, &xi) in t.iter().enumerate() {
            for (j, &eta) in t.iter().enumerate() {
                let xp = new_tree.map_point(c, xi, eta);
                if let Some((oc, oxi, oeta)) = old_tree.locate(xp) {
                    if let Some(&ok) = old_space.leaf_index.get(&oc) {
                        u[i][j] = old_space.eval(old_tree, old_x, ok, 0, oxi, oeta).0;
                    }
                }
            }
        }
        // Coefficients C = V⁻¹ U V⁻ᵀ (C[a][b] for function a along ξ, b along η).
        let mut tmp = [[0.0f64; M]; M];
        for a in 0..m {
            for j in 0..m {
                tmp[a][j] = (0..m).map(|i| vi[(a, i)] * u[i][j]).sum();
            }
        }
        let mut coef = [[0.0f64; M]; M];
        for a in 0..m {
            for b in 0..m {
                coef[a][b] = (0..m).map(|j| tmp[a][j] * vi[(b, j)]).sum();
            }
        }
        let dofs = new_space.dofs(k);
        for jb in 0..m {
            for ia in 0..m {
                let d = dofs[ia + m * jb] as usize;
                let e = new_space.constraints.eq[d];
                if e != u32::MAX {
                    y[e as usize] = coef[ia][jb];
                }
            }
        }
    }
    let mut x = vec![0.0; new_space.n_dofs()];
    new_space.constraints.distribute(&y, &mut x);
    x
}

/// Options of an adaptive run.
#[derive(Clone, Debug)]
pub struct AdaptOptions {
    pub basis: Basis1d,
    pub degree: u8,
    /// Uniform refinements of the coarse mesh before adapting.
    pub initial_levels: u32,
    pub strategy: Strategy,
    pub marking: Marking,
    pub estimator: EstimatorKind,
    pub solver: Solver,
    pub max_degree: usize,
    pub hp_decay: f64,
    /// Stop after the step whose number of equations exceeds this.
    pub max_dofs: usize,
    pub max_steps: usize,
    /// Stop when the relative energy error (if an exact solution is known) falls below.
    pub target_rel_error: f64,
    /// Also evaluate all four estimators on every step (effectivity study).
    pub all_estimators: bool,
    /// Uniform refinement instead of marking (reference runs).
    pub uniform: bool,
}

impl AdaptOptions {
    /// h-adaptive Lagrange Q1/Q2 with Dörfler marking.
    pub fn h(degree: u8) -> Self {
        Self {
            basis: Basis1d::Lagrange,
            degree,
            initial_levels: 1,
            strategy: Strategy::H,
            marking: Marking::Dorfler(0.5),
            estimator: EstimatorKind::Explicit,
            solver: Solver::Direct,
            max_degree: 4,
            hp_decay: 0.5,
            max_dofs: 20_000,
            max_steps: 60,
            target_rel_error: 0.0,
            all_estimators: false,
            uniform: false,
        }
    }
}

/// What one pass through the loop measured.
#[derive(Clone, Debug, serde::Serialize)]
pub struct StepRecord {
    pub step: usize,
    pub n_eq: usize,
    pub n_cells: usize,
    pub max_level: u32,
    pub max_degree: usize,
    /// Exact energy error ‖∇(u − u_h)‖ and relative to |u|₁.
    pub error: f64,
    pub rel_error: f64,
    /// Estimate of the driving estimator.
    pub estimate: f64,
    /// Estimates of all four estimators (explicit, equilibrated, recovery, interpolation) if
    /// requested.
    pub all: Option<[f64; 4]>,
    pub cg_iterations: usize,
    /// Seconds per named step (the transfer of step i is the one that prepared step i + 1).
    pub t_solve: f64,
    pub t_estimate: f64,
    pub t_mark: f64,
    pub t_refine: f64,
    pub t_transfer: f64,
    /// Wall time of the adaptive algorithm since the start (exact-error evaluation excluded).
    pub t_total: f64,
}

/// Run the adapt loop on a problem posed on `tree` (the exact solution gives the Dirichlet
/// data, the source and the error).
pub fn run(
    tree: Quadtree,
    problem: &dyn Exact,
    u_norm: f64,
    opts: &AdaptOptions,
) -> Result<Vec<StepRecord>, SpaceError> {
    run_observed(tree, problem, u_norm, opts, &mut |_| {
        ControlFlow::Continue(())
    })
}

/// One pass of the loop as [`run_observed`] shows it: the record, the mesh, the space, the
/// solution and the driving estimate, before the mesh is refined.
pub struct StepView<'a> {
    pub record: &'a StepRecord,
    pub tree: &'a Quadtree,
    pub space: &'a Space,
    pub x: &'a [f64],
    pub estimate: &'a CellEstimate,
    /// Whether this is the last pass (the loop ends after it whatever `each` returns).
    pub last: bool,
}

/// [`run`], calling `each` on every pass (the last one sees the final mesh and solution).
/// When `each` returns [`ControlFlow::Break`] the loop stops after that pass (its mesh and
/// solution are the last ones).
pub fn run_observed(
    mut tree: Quadtree,
    problem: &dyn Exact,
    u_norm: f64,
    opts: &AdaptOptions,
    each: &mut dyn FnMut(&StepView) -> ControlFlow<()>,
) -> Result<Vec<StepRecord>, SpaceError> {
    for c in tree.leaves() {
        tree.cells[c as usize].degree = opts.degree;
    }
    for _ in 0..opts.initial_levels {
        let l = tree.leaves();
        tree.refine(&l);
    }
    let g = |x: [f64; 2], _c: usize| problem.u(x);
    let f = |x: [f64; 2]| problem.f(x);
    let mut records = Vec::new();
    let clock = Instant::now();
    let mut t_excluded = 0.0;
    let mut space = Space::new(&tree, opts.basis, 1, Some(&g))?;
    let mut x = vec![0.0; space.n_dofs()];
    let mut t_transfer = 0.0;
    for step in 0..opts.max_steps {
        // 1. Solve.
        let t0 = Instant::now();
        let sys = assemble(&space, &tree, problem);
        let mut cg_iterations = 0;
        match opts.solver {
            Solver::Direct => {
                x = solve_direct(&space, &sys).map_err(|e| SpaceError::Solve(e.to_string()))?;
            }
            Solver::Cg { tol } => {
                let st = solve_cg(&space, &sys, &mut x, tol, 100_000);
                cg_iterations = st.iterations;
            }
        }
        let t_solve = t0.elapsed().as_secs_f64();
        let te = Instant::now();
        let error = energy_error_sq(&space, &tree, &x, problem)
            .iter()
            .sum::<f64>()
            .sqrt();
        t_excluded += te.elapsed().as_secs_f64();
        let ctx = Context {
            tree: &tree,
            space: &space,
            x: &x,
            f: &f,
        };
        // 2. Estimate.
        let t0 = Instant::now();
        let est = if opts.uniform {
            CellEstimate::from_squares(vec![1.0; space.leaves.len()])
        } else {
            opts.estimator.estimate(&ctx)?
        }
        .with_exact_error(error);
        let t_estimate = t0.elapsed().as_secs_f64();
        let all = if opts.all_estimators {
            let te = Instant::now();
            let mut a = [0.0; 4];
            for (i, kind) in [
                EstimatorKind::Explicit,
                EstimatorKind::Equilibrated,
                EstimatorKind::Recovery,
                EstimatorKind::Interpolation,
            ]
            .iter()
            .enumerate()
            {
                a[i] = kind.get().estimate(&ctx)?.global;
            }
            t_excluded += te.elapsed().as_secs_f64();
            Some(a)
        } else {
            None
        };
        let rel_error = error / u_norm;
        let done = space.n_eq() > opts.max_dofs
            || rel_error < opts.target_rel_error
            || step + 1 == opts.max_steps;
        // 3. Mark.
        let t0 = Instant::now();
        let marked: Vec<usize> = if done {
            Vec::new()
        } else if opts.uniform {
            (0..space.leaves.len()).collect()
        } else {
            est.mark(opts.marking)
        };
        let t_mark = t0.elapsed().as_secs_f64();
        let mut rec = StepRecord {
            step,
            n_eq: space.n_eq(),
            n_cells: space.leaves.len(),
            max_level: space
                .leaves
                .iter()
                .map(|&c| tree.cells[c as usize].level)
                .max()
                .unwrap_or(0),
            max_degree: space.degree.iter().copied().max().unwrap_or(1),
            error,
            rel_error,
            estimate: est.global,
            all,
            cg_iterations,
            t_solve,
            t_estimate,
            t_mark,
            t_refine: 0.0,
            t_transfer,
            t_total: 0.0,
        };
        if done {
            rec.t_total = clock.elapsed().as_secs_f64() - t_excluded;
            // The last pass: nothing left to stop.
            let _ = each(&StepView {
                record: &rec,
                tree: &tree,
                space: &space,
                x: &x,
                estimate: &est,
                last: true,
            });
            records.push(rec);
            break;
        }
        let flow = each(&StepView {
            record: &rec,
            tree: &tree,
            space: &space,
            x: &x,
            estimate: &est,
            last: false,
        });
        if flow.is_break() {
            rec.t_total = clock.elapsed().as_secs_f64() - t_excluded;
            records.push(rec);
            break;
        }
        // 4. Refine.
        let t0 = Instant::now();
        let old_tree = tree.clone();
        refine(
            &mut tree,
            &space,
            &x,
            &marked,
            opts.strategy,
            opts.max_degree,
            opts.hp_decay,
        );
        let new_space = Space::new(&tree, opts.basis, 1, Some(&g))?;
        rec.t_refine = t0.elapsed().as_secs_f64();
        // 5. Transfer.
        let t0 = Instant::now();
        let new_x = match opts.solver {
            Solver::Cg { .. } => transfer(&old_tree, &space, &x, &tree, &new_space),
            Solver::Direct => vec![0.0; new_space.n_dofs()],
        };
        t_transfer = t0.elapsed().as_secs_f64();
        space = new_space;
        x = new_x;
        rec.t_total = clock.elapsed().as_secs_f64() - t_excluded;
        records.push(rec);
    }
    Ok(records)
}

/// Least-squares slope of log y against log x.
pub fn loglog_slope(pts: &[(f64, f64)]) -> f64 {
    let n = pts.len() as f64;
    let (mut sx, mut sy, mut sxx, mut sxy) = (0.0, 0.0, 0.0, 0.0);
    for &(x, y) in pts {
        let (lx, ly) = (x.ln(), y.ln());
        sx += lx;
        sy += ly;
        sxx += lx * lx;
        sxy += lx * ly;
    }
    (n * sxy - sx * sy) / (n * sxx - sx * sx)
}
