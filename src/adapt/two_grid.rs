//! Transient problems on a quadtree with Crank–Nicolson steps solved by Newton, and the
//! adaptive h-method whose error estimate is the difference between the solution on the
//! current mesh and the solution on its uniform refinement.
//!
//! A problem is a cell [`Kernel`]: the Crank–Nicolson residual r(u^{n+1}; u^n) of one leaf and
//! its exact tangent ∂r/∂u^{n+1}. A step solves the condensed system by Newton with sparse LU;
//! a linear problem converges in one iteration. Dirichlet data g(x, t) come from the problem on
//! the whole boundary: the space of time t_{n+1} is built with g(·, t_{n+1}), the old solution
//! lives in the space with g(·, t_n). Only Lagrange bases (Q1, Q2) are used, so solution transfer
//! is nodal interpolation.
//!
//! **Two-grid estimate.** Two solutions are advanced side by side: u_h on the mesh 𝒯 and u_f on
//! the fine mesh 𝒯_f (every leaf of 𝒯 split once). The indicator of a leaf K of 𝒯 is
//! η_K = ‖u_f − u_h‖_{L²(K)} at the end of the step and the estimate is η = (Σ η_K²)^{1/2}. For
//! a method of order p + 1 in L², u_f is about 2^{p+1} times more accurate, so the effectivity
//! η / ‖u − u_h‖ tends to 1 − 2^{−(p+1)} (0.75 for Q1, 0.875 for Q2) in the asymptotic range.
//!
//! **Adaptation between steps.** After each step: Dörfler marking of η_K with parameter θ
//! ([`super::marking::mark`]) for refinement (cells below `max_level`); leaves with
//! η_K² < `coarsen_fraction` · η² / N_cells and level > `min_level` are coarsened (four
//! siblings at once, one-irregularity kept by [`Quadtree::coarsen`]); then u_h and u_f are
//! interpolated onto the new 𝒯 and 𝒯_f. The first step is repeated `initial_sweeps` times
//! (default 8), each time from u_0 interpolated on the adapted meshes, so the initial mesh
//! resolves u_0: the error the first mesh leaves is carried through the run, not damped
//! (measured on the rotating hill and on Burgers: 8 sweeps give 6.6 and 9 times less error than
//! 4 for 1.6 and 2.4 times the time).

use super::marking::{coarsening_limit, CellEstimate, Marking};
use super::quadtree::Quadtree;
use super::space::{shape_second, shape_values, Space, SpaceError, MAX_LOCAL_SCALAR};
use crate::assembly::constraints::CondenseScratch;
use crate::element::hierarchical::{gauss_legendre, Basis1d};
use crate::solver::linear::{LinearError, LinearKind, SparseSolver};
use std::ops::ControlFlow;
use std::time::Instant;

/// Largest local vector of a kernel: 2 components of a Q2 cell.
pub const MAX_LOCAL: usize = 18;

/// Errors of the transient solvers.
#[derive(Debug, thiserror::Error)]
pub enum TransientError {
    #[error(transparent)]
    Space(#[from] SpaceError),
    #[error(transparent)]
    Linear(#[from] LinearError),
    #[error("invalid parameter: {0}")]
    Parameter(String),
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
}

/// Local data of one leaf passed to a kernel.
pub struct CellData<'a> {
    /// Lower-left corner and side.
    pub x0: [f64; 2],
    pub h: f64,
    /// Degree (1 or 2, Lagrange).
    pub p: usize,
    /// Local dof values of u^{n+1} and u^n (node-major, `n_comp` per node).
    pub u: &'a [f64],
    pub un: &'a [f64],
    /// t_n and the step.
    pub t: f64,
    pub dt: f64,
}

/// A transient problem with a known solution, discretised in time by Crank–Nicolson.
pub trait Kernel: Sync {
    /// Number of solution components.
    fn n_comp(&self) -> usize;
    /// Exact solution component `comp` at (x, t) and its gradient.
    fn exact(&self, x: [f64; 2], t: f64, comp: usize) -> (f64, [f64; 2]);
    /// Residual `r` and tangent `k` (row-major, `nl × nl`, nl = n_comp (p+1)²) of one leaf.
    fn cell(&self, d: &CellData, r: &mut [f64], k: &mut [f64]);
}

/// The square (x0, x0 + l)² as a single root cell, refined uniformly `levels` times.
pub fn square(origin: [f64; 2], l: f64, levels: u32, p: u8) -> Quadtree {
    let mut t = Quadtree::new(origin, l, &[(0, 0)], p);
    for _ in 0..levels {
        let leaves = t.leaves();
        t.refine(&leaves);
    }
    t
}

/// Reference coordinate of 1D Lagrange entity `i` (nodes at −1, 1, 0).
#[inline]
fn lagrange_node(i: usize) -> f64 {
    [-1.0, 1.0, 0.0][i.min(2)]
}

/// Nodal interpolation of `f(x, comp)` into `space` (Lagrange basis): free equations take the
/// nodal values, constrained and fixed dofs follow from the constraints.
pub fn interpolate(
    tree: &Quadtree,
    space: &Space,
    f: &dyn Fn([f64; 2], usize) -> f64,
) -> Result<Vec<f64>, TransientError> {
    if space.basis != Basis1d::Lagrange {
        return Err(TransientError::Parameter(
            "nodal interpolation needs a Lagrange basis".into(),
        ));
    }
    let nc = space.n_comp;
    let mut y = vec![0.0; space.n_eq()];
    for k in 0..space.leaves.len() {
        let p = space.degree[k];
        let c = space.leaves[k];
        let dofs = space.dofs(k);
        for j in 0..=p {
            for i in 0..=p {
                let a = i + (p + 1) * j;
                let x = tree.map_point(c, lagrange_node(i), lagrange_node(j));
                for comp in 0..nc {
                    let e = space.constraints.eq[dofs[nc * a + comp] as usize];
                    if e != u32::MAX {
                        y[e as usize] = f(x, comp);
                    }
                }
            }
        }
    }
    let mut x = vec![0.0; space.n_dofs()];
    space.constraints.distribute(&y, &mut x);
    Ok(x)
}

/// Value of component `comp` of the finite-element function `x` on (`tree`, `space`) at the
/// physical point `p` (0 outside the mesh).
pub fn value_at(tree: &Quadtree, space: &Space, x: &[f64], p: [f64; 2], comp: usize) -> f64 {
    match tree.locate(p) {
        Some((c, xi, eta)) => match space.leaf_index.get(&c) {
            Some(&k) => eval_comp(tree, space, x, k, comp, xi, eta).0,
            None => 0.0,
        },
        None => 0.0,
    }
}

/// Value and gradient of component `comp` in leaf `k`.
fn eval_comp(
    tree: &Quadtree,
    space: &Space,
    x: &[f64],
    k: usize,
    comp: usize,
    xi: f64,
    eta: f64,
) -> (f64, [f64; 2]) {
    space.eval(tree, x, k, comp, xi, eta)
}

/// Squared L² and H¹-seminorm errors of every leaf against the kernel's exact solution at t.
pub fn error_sq(
    tree: &Quadtree,
    space: &Space,
    x: &[f64],
    kernel: &dyn Kernel,
    t: f64,
) -> (Vec<f64>, Vec<f64>) {
    let (gx, gw) = gauss_legendre(space.degree.iter().copied().max().unwrap_or(1) + 3);
    let mut l2 = vec![0.0; space.leaves.len()];
    let mut h1 = vec![0.0; space.leaves.len()];
    for k in 0..space.leaves.len() {
        let c = space.leaves[k];
        let h = tree.h(c);
        for (i, &xi) in gx.iter().enumerate() {
            for (j, &eta) in gx.iter().enumerate() {
                let w = gw[i] * gw[j] * 0.25 * h * h;
                let p = tree.map_point(c, xi, eta);
                for comp in 0..space.n_comp {
                    let (v, g) = eval_comp(tree, space, x, k, comp, xi, eta);
                    let (ue, ge) = kernel.exact(p, t, comp);
                    l2[k] += w * (ue - v).powi(2);
                    h1[k] += w * ((ge[0] - g[0]).powi(2) + (ge[1] - g[1]).powi(2));
                }
            }
        }
    }
    (l2, h1)
}

/// Squared L² difference ‖u_f − u_h‖²_K on every leaf K of the coarse mesh.
pub fn difference_sq(
    tree: &Quadtree,
    space: &Space,
    x: &[f64],
    fine_tree: &Quadtree,
    fine_space: &Space,
    xf: &[f64],
) -> Vec<f64> {
    let (gx, gw) = gauss_legendre(space.degree.iter().copied().max().unwrap_or(1) + 2);
    let mut out = vec![0.0; space.leaves.len()];
    for (k, o) in out.iter_mut().enumerate() {
        let c = space.leaves[k];
        let h = tree.h(c);
        // The four children of K in the fine mesh: quadrature on each quarter.
        for (qx, qy) in [(-0.5, -0.5), (0.5, -0.5), (-0.5, 0.5), (0.5, 0.5)] {
            for (i, &a) in gx.iter().enumerate() {
                for (j, &b) in gx.iter().enumerate() {
                    let (xi, eta) = (qx + 0.5 * a, qy + 0.5 * b);
                    let w = gw[i] * gw[j] * 0.0625 * h * h;
                    let p = tree.map_point(c, xi, eta);
                    for comp in 0..space.n_comp {
                        let v = eval_comp(tree, space, x, k, comp, xi, eta).0;
                        let vf = value_at(fine_tree, fine_space, xf, p, comp);
                        *o += w * (vf - v).powi(2);
                    }
                }
            }
        }
    }
    out
}

/// Build the space on `tree` with the kernel's Dirichlet data at time t.
pub fn space_at(tree: &Quadtree, kernel: &dyn Kernel, t: f64) -> Result<Space, TransientError> {
    let g = |x: [f64; 2], comp: usize| kernel.exact(x, t, comp).0;
    Ok(Space::new(
        tree,
        Basis1d::Lagrange,
        kernel.n_comp(),
        Some(&g),
    )?)
}

/// Condensed residual −Cᵀ r and tangent Cᵀ K C at the dof vector `x` (old solution `xn` in the
/// same numbering).
fn assemble(
    tree: &Quadtree,
    space: &Space,
    kernel: &dyn Kernel,
    x: &[f64],
    xn: &[f64],
    t: f64,
    dt: f64,
) -> (Vec<f64>, Vec<f64>) {
    let pat = &space.pattern;
    let mut values = vec![0.0; pat.nnz()];
    let mut rhs = vec![0.0; pat.n];
    let mut scratch = CondenseScratch::default();
    let mut ul = [0.0; MAX_LOCAL];
    let mut unl = [0.0; MAX_LOCAL];
    let mut r = [0.0; MAX_LOCAL];
    let mut kl = [0.0; MAX_LOCAL * MAX_LOCAL];
    let mut f = [0.0; MAX_LOCAL];
    for k in 0..space.leaves.len() {
        let c = space.leaves[k];
        let dofs = space.dofs(k);
        let nl = dofs.len();
        for (a, &d) in dofs.iter().enumerate() {
            ul[a] = x[d as usize];
            unl[a] = xn[d as usize];
        }
        r[..nl].fill(0.0);
        kl[..nl * nl].fill(0.0);
        let d = CellData {
            x0: tree.corner(c),
            h: tree.h(c),
            p: space.degree[k],
            u: &ul[..nl],
            un: &unl[..nl],
            t,
            dt,
        };
        kernel.cell(&d, &mut r[..nl], &mut kl[..nl * nl]);
        // add_cell forms Cᵀ(f − K b); f = −r + K b gives −Cᵀ r.
        let b = &pat.b[pat.b_off[k]..pat.b_off[k + 1]];
        for a in 0..nl {
            let kb: f64 = (0..nl).map(|bb| kl[a * nl + bb] * b[bb]).sum();
            f[a] = -r[a] + kb;
        }
        pat.add_cell(
            k,
            &kl[..nl * nl],
            &f[..nl],
            &mut values,
            &mut rhs,
            &mut scratch,
        );
    }
    (values, rhs)
}

/// Newton options.
#[derive(Clone, Copy, Debug)]
pub struct NewtonOptions {
    /// Stop when ‖Cᵀ r‖_∞ ≤ `tol`.
    pub tol: f64,
    pub max_iter: usize,
}

impl Default for NewtonOptions {
    fn default() -> Self {
        Self {
            tol: 1e-10,
            max_iter: 12,
        }
    }
}

/// One Crank–Nicolson step from t to t + dt on `tree`: `xn` is the old solution in the space
/// with the data of time t; returns the new solution in the space of t + dt and the number of
/// Newton iterations.
pub fn step(
    tree: &Quadtree,
    kernel: &dyn Kernel,
    space_new: &Space,
    xn: &[f64],
    t: f64,
    dt: f64,
    newton: NewtonOptions,
) -> Result<(Vec<f64>, usize), TransientError> {
    let pat = &space_new.pattern;
    let mut y = vec![0.0; pat.n];
    space_new.constraints.gather(xn, &mut y);
    let mut x = vec![0.0; space_new.n_dofs()];
    space_new.constraints.distribute(&y, &mut x);
    let mut solver = SparseSolver::new(pat.n, &pat.col_ptr, &pat.row_idx, LinearKind::Lu)?;
    solver.set_track_determinant(false);
    let mut res = f64::INFINITY;
    for it in 0..=newton.max_iter {
        let (values, mut rhs) = assemble(tree, space_new, kernel, &x, xn, t, dt);
        res = rhs.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if !res.is_finite() {
            return Err(TransientError::NonFinite(t + dt));
        }
        if res <= newton.tol {
            return Ok((x, it));
        }
        if it == newton.max_iter {
            break;
        }
        solver.factorize(&values)?;
        solver.solve_in_place(&mut rhs)?;
        for (yi, di) in y.iter_mut().zip(&rhs) {
            *yi += di;
        }
        space_new.constraints.distribute(&y, &mut x);
    }
    Err(TransientError::NoConvergence {
        t: t + dt,
        residual: res,
        iterations: newton.max_iter,
    })
}

/// The condensed residual at `x` (exposed for tangent checks): returns (−Cᵀ r, Cᵀ K C values).
pub fn condensed_system(
    tree: &Quadtree,
    space: &Space,
    kernel: &dyn Kernel,
    x: &[f64],
    xn: &[f64],
    t: f64,
    dt: f64,
) -> (Vec<f64>, Vec<f64>) {
    let (v, r) = assemble(tree, space, kernel, x, xn, t, dt);
    (r, v)
}

/// Options of a transient run.
#[derive(Clone, Debug)]
pub struct TransientOptions {
    pub degree: u8,
    pub dt: f64,
    pub n_steps: usize,
    /// Adapt with the two-grid estimate (false: the mesh stays as given).
    pub adaptive: bool,
    /// Also advance the fine-grid solution on a fixed mesh (estimate without adaptation).
    pub estimate: bool,
    pub marking: Marking,
    pub coarsen_fraction: f64,
    pub min_level: u32,
    pub max_level: u32,
    pub initial_sweeps: usize,
    pub newton: NewtonOptions,
}

impl TransientOptions {
    pub fn new(degree: u8, dt: f64, n_steps: usize) -> Self {
        Self {
            degree,
            dt,
            n_steps,
            adaptive: false,
            estimate: false,
            marking: Marking::Dorfler(0.5),
            coarsen_fraction: 0.05,
            min_level: 2,
            max_level: 8,
            initial_sweeps: 8,
            newton: NewtonOptions::default(),
        }
    }
}

/// Record of one time step.
#[derive(Clone, Debug)]
pub struct StepRecord {
    pub t: f64,
    /// Free equations of the mesh the step was computed on.
    pub n_eq: usize,
    pub n_cells: usize,
    pub l2_error: f64,
    pub h1_error: f64,
    /// Two-grid estimate ‖u_f − u_h‖ (NaN when not computed).
    pub estimate: f64,
    pub newton_iterations: usize,
}

/// Outcome of a run.
#[derive(Clone, Debug)]
pub struct TransientRun {
    pub steps: Vec<StepRecord>,
    pub wall_seconds: f64,
    /// Final mesh, space and solution (time t_0 + n_steps dt).
    pub tree: Quadtree,
    pub x: Vec<f64>,
    /// The fine solution of the two-grid estimate at the same time, on `tree` refined once
    /// (empty without the estimate).
    pub x_fine: Vec<f64>,
}

impl TransientRun {
    pub fn last(&self) -> Option<&StepRecord> {
        self.steps.last()
    }
    /// Largest number of equations over the steps.
    pub fn max_eq(&self) -> usize {
        self.steps.iter().map(|s| s.n_eq).max().unwrap_or(0)
    }
}

/// `tree` with every leaf split once (the fine mesh of the two-grid estimate).
pub fn refined(tree: &Quadtree) -> Quadtree {
    let mut f = tree.clone();
    let leaves = f.leaves();
    f.refine(&leaves);
    f
}

/// Run from t0 on the initial mesh `tree0` (degrees are reset to `opts.degree`).
pub fn run(
    kernel: &dyn Kernel,
    tree0: &Quadtree,
    t0: f64,
    opts: &TransientOptions,
) -> Result<TransientRun, TransientError> {
    run_observed(kernel, tree0, t0, opts, &mut |_| ControlFlow::Continue(()))
}

/// One accepted step as [`run_observed`] shows it: its record, the mesh and space it was
/// computed on, the solution, and the two-grid indicators η_K (None without the estimate),
/// before the mesh is adapted.
pub struct StepView<'a> {
    pub record: &'a StepRecord,
    pub tree: &'a Quadtree,
    pub space: &'a Space,
    pub x: &'a [f64],
    pub indicators: Option<&'a [f64]>,
}

/// [`run`], calling `each` on every accepted step. When `each` returns
/// [`ControlFlow::Break`] the run stops after that step (the mesh adapted as after any step:
/// [`TransientRun`] holds the state at the time of that step).
pub fn run_observed(
    kernel: &dyn Kernel,
    tree0: &Quadtree,
    t0: f64,
    opts: &TransientOptions,
    each: &mut dyn FnMut(&StepView) -> ControlFlow<()>,
) -> Result<TransientRun, TransientError> {
    if !(opts.dt > 0.0 && opts.dt.is_finite()) {
        return Err(TransientError::Parameter(format!(
            "time step must be positive and finite, got {}",
            opts.dt
        )));
    }
    if !(1..=2).contains(&opts.degree) {
        return Err(TransientError::Parameter(format!(
            "degree must be 1 or 2, got {}",
            opts.degree
        )));
    }
    let clock = Instant::now();
    let mut tree = tree0.clone();
    for c in tree.cells.iter_mut() {
        c.degree = opts.degree;
    }
    let two_grid = opts.adaptive || opts.estimate;
    let exact0 = |x: [f64; 2], comp: usize| kernel.exact(x, t0, comp).0;
    let mut space_old = space_at(&tree, kernel, t0)?;
    let mut xn = interpolate(&tree, &space_old, &exact0)?;
    let mut ftree = refined(&tree);
    let mut fspace_old = space_at(&ftree, kernel, t0)?;
    let mut xfn = if two_grid {
        interpolate(&ftree, &fspace_old, &exact0)?
    } else {
        Vec::new()
    };
    let mut steps = Vec::new();
    let mut t = t0;
    let mut stop = false;
    for n in 0..opts.n_steps {
        let sweeps = if n == 0 && opts.adaptive {
            opts.initial_sweeps.max(1)
        } else {
            1
        };
        for sweep in 0..sweeps {
            let space_new = space_at(&tree, kernel, t + opts.dt)?;
            let (x, its) = step(&tree, kernel, &space_new, &xn, t, opts.dt, opts.newton)?;
            let (l2, h1) = error_sq(&tree, &space_new, &x, kernel, t + opts.dt);
            let mut rec = StepRecord {
                t: t + opts.dt,
                n_eq: space_new.n_eq(),
                n_cells: space_new.leaves.len(),
                l2_error: l2.iter().sum::<f64>().sqrt(),
                h1_error: h1.iter().sum::<f64>().sqrt(),
                estimate: f64::NAN,
                newton_iterations: its,
            };
            let mut xf = Vec::new();
            let mut fspace_new = None;
            let mut est = None;
            if two_grid {
                let fs = space_at(&ftree, kernel, t + opts.dt)?;
                let (xff, _) = step(&ftree, kernel, &fs, &xfn, t, opts.dt, opts.newton)?;
                let e = CellEstimate::from_squares(difference_sq(
                    &tree, &space_new, &x, &ftree, &fs, &xff,
                ));
                rec.estimate = e.global;
                xf = xff;
                fspace_new = Some(fs);
                est = Some(e);
            }
            let last_sweep = sweep + 1 == sweeps;
            if last_sweep || !opts.adaptive {
                stop = each(&StepView {
                    record: &rec,
                    tree: &tree,
                    space: &space_new,
                    x: &x,
                    indicators: est.as_ref().map(|e| e.indicators.as_slice()),
                })
                .is_break();
            }
            if !opts.adaptive {
                steps.push(rec);
                xn = x;
                space_old = space_new;
                if let Some(fs) = fspace_new {
                    xfn = xf;
                    fspace_old = fs;
                }
                break;
            }
            let Some(est) = est else { break };
            // Adapt the mesh.
            let old_tree = tree.clone();
            let old_ftree = ftree.clone();
            adapt_mesh(&mut tree, &space_new, &est, opts);
            ftree = refined(&tree);
            if last_sweep {
                steps.push(rec);
                // Carry u_h, u_f (time t + dt) onto the new meshes.
                let s_new = space_at(&tree, kernel, t + opts.dt)?;
                let fs_new = space_at(&ftree, kernel, t + opts.dt)?;
                let fs = fspace_new.as_ref().unwrap_or(&fspace_old);
                xn = interpolate(&tree, &s_new, &|p, c| {
                    value_at(&old_tree, &space_new, &x, p, c)
                })?;
                xfn = interpolate(&ftree, &fs_new, &|p, c| value_at(&old_ftree, fs, &xf, p, c))?;
                space_old = s_new;
                fspace_old = fs_new;
            } else {
                // Redo the first step on the new mesh from the initial data interpolated there
                // (not from the interpolant on the old mesh: that would keep the coarse mesh's
                // interpolation error of u_0 for the whole run).
                let s_new = space_at(&tree, kernel, t)?;
                let fs_new = space_at(&ftree, kernel, t)?;
                xn = interpolate(&tree, &s_new, &exact0)?;
                xfn = interpolate(&ftree, &fs_new, &exact0)?;
                space_old = s_new;
                fspace_old = fs_new;
            }
        }
        t += opts.dt;
        if stop {
            break;
        }
    }
    let _ = &space_old;
    let _ = &fspace_old;
    Ok(TransientRun {
        steps,
        wall_seconds: clock.elapsed().as_secs_f64(),
        tree,
        x: xn,
        x_fine: if two_grid { xfn } else { Vec::new() },
    })
}

/// Coarsen the leaves with small indicators, then refine the Dörfler-marked ones.
fn adapt_mesh(tree: &mut Quadtree, space: &Space, est: &CellEstimate, opts: &TransientOptions) {
    let eta = &est.indicators;
    let limit = coarsening_limit(eta, opts.coarsen_fraction);
    let refine: Vec<usize> = est
        .mark(opts.marking)
        .into_iter()
        .filter(|&k| tree.cells[space.leaves[k] as usize].level < opts.max_level)
        .collect();
    let coarse: Vec<u32> = (0..eta.len())
        .filter(|&k| {
            eta[k] * eta[k] < limit && tree.cells[space.leaves[k] as usize].level > opts.min_level
        })
        .map(|k| space.leaves[k])
        .collect();
    tree.coarsen(&coarse);
    let ids: Vec<u32> = refine
        .iter()
        .map(|&k| space.leaves[k])
        .filter(|&c| tree.cells[c as usize].alive && tree.is_leaf(c))
        .collect();
    tree.refine(&ids);
}

/// Values, physical gradients and second derivatives (∂xx, ∂xy, ∂yy) of the Lagrange basis of
/// degree p at (ξ, η) on a square of side h.
#[inline]
pub fn basis_at(
    p: usize,
    h: f64,
    xi: f64,
    eta: f64,
    n: &mut [f64],
    dn: &mut [[f64; 2]],
    d2: &mut [[f64; 3]],
) -> usize {
    shape_second(Basis1d::Lagrange, p, h, xi, eta, d2);
    shape_values(Basis1d::Lagrange, p, h, xi, eta, n, dn)
}

/// Scratch sizes of the basis of one cell.
pub const MAX_SCALAR: usize = MAX_LOCAL_SCALAR;
