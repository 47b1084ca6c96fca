//! The scalar model problem −Δu = f in Ω, u = g on ∂Ω, on a [`Space`] over a quadtree:
//! assembly (condensed constraints), a sparse direct solve (Cholesky) and a
//! Jacobi-preconditioned conjugate-gradient solve, and the exact energy error
//! ‖∇(u − u_h)‖ cell by cell.
//!
//! Cells are squares, so the element stiffness ∫_K ∇φ_a·∇φ_b does not depend on the cell size
//! in 2D: it is tabulated once per degree on the reference square and reused.
//!
//! The L-shaped domain (−1, 1)² \ [0, 1) × (−1, 0] with the exact solution
//! u = r^{2/3} sin(2θ/3), θ ∈ [0, 3π/2] from the +x axis, is harmonic (f = 0) and vanishes on
//! the two edges meeting at the re-entrant corner; ∇u ~ r^{−1/3} there.

use super::quadtree::Quadtree;
use super::space::{shape_values, Space, MAX_LOCAL_SCALAR};
use crate::assembly::constraints::CondenseScratch;
use crate::element::hierarchical::{gauss_legendre, Basis1d};
use crate::solver::linear::{LinearError, LinearKind, SparseSolver};

/// A scalar problem with a known solution.
pub trait Exact: Sync {
    fn u(&self, x: [f64; 2]) -> f64;
    fn grad(&self, x: [f64; 2]) -> [f64; 2];
    /// Source f = −Δu.
    fn f(&self, _x: [f64; 2]) -> f64 {
        0.0
    }
    /// Whether f ≡ 0 (the load integral is skipped).
    fn harmonic(&self) -> bool {
        false
    }
    /// A point where the solution is singular, if any (error quadrature is graded there).
    fn singular_point(&self) -> Option<[f64; 2]> {
        None
    }
}

/// u = r^{2/3} sin(2θ/3) on the L-shape.
#[derive(Clone, Copy, Debug, Default)]
pub struct LShape;

impl Exact for LShape {
    fn u(&self, x: [f64; 2]) -> f64 {
        let r = x[0].hypot(x[1]);
        let th = theta(x);
        r.powf(2.0 / 3.0) * (2.0 * th / 3.0).sin()
    }
    fn grad(&self, x: [f64; 2]) -> [f64; 2] {
        let r = x[0].hypot(x[1]);
        if r == 0.0 {
            return [0.0; 2];
        }
        let th = theta(x);
        let a = 2.0 / 3.0 * r.powf(-1.0 / 3.0);
        let (ur, ut) = (a * (2.0 * th / 3.0).sin(), a * (2.0 * th / 3.0).cos());
        let (c, s) = (th.cos(), th.sin());
        [ur * c - ut * s, ur * s + ut * c]
    }
    fn harmonic(&self) -> bool {
        true
    }
    fn singular_point(&self) -> Option<[f64; 2]> {
        Some([0.0, 0.0])
    }
}

fn theta(x: [f64; 2]) -> f64 {
    let t = x[1].atan2(x[0]);
    if t < 0.0 {
        t + 2.0 * std::f64::consts::PI
    } else {
        t
    }
}

/// Element stiffness ∫ ∇φ_a · ∇φ_b of a square cell for one degree (row-major; the same for
/// every size in 2D).
pub fn reference_stiffness(basis: Basis1d, p: usize) -> Vec<f64> {
    let (x, w) = gauss_legendre(p + 1);
    let nl = (p + 1) * (p + 1);
    let mut k = vec![0.0; nl * nl];
    let mut n = [0.0; MAX_LOCAL_SCALAR];
    let mut dn = [[0.0; 2]; MAX_LOCAL_SCALAR];
    for (i, &xi) in x.iter().enumerate() {
        for (j, &eta) in x.iter().enumerate() {
            // h = 2: reference gradients, Jacobian determinant 1.
            shape_values(basis, p, 2.0, xi, eta, &mut n, &mut dn);
            let wq = w[i] * w[j];
            for a in 0..nl {
                for b in 0..nl {
                    k[a * nl + b] += wq * (dn[a][0] * dn[b][0] + dn[a][1] * dn[b][1]);
                }
            }
        }
    }
    k
}

/// Assembled condensed system of the Poisson problem.
pub struct PoissonSystem {
    pub values: Vec<f64>,
    pub rhs: Vec<f64>,
}

/// Assemble −Δu = f on `space` (scalar).
pub fn assemble(space: &Space, tree: &Quadtree, problem: &dyn Exact) -> PoissonSystem {
    let pat = &space.pattern;
    let mut values = vec![0.0; pat.nnz()];
    let mut rhs = vec![0.0; pat.n];
    let maxp = space.degree.iter().copied().max().unwrap_or(1);
    let kref: Vec<Vec<f64>> = (0..=maxp)
        .map(|p| {
            if p == 0 {
                Vec::new()
            } else {
                reference_stiffness(space.basis, p)
            }
        })
        .collect();
    let mut scratch = CondenseScratch::default();
    let mut f = vec![0.0; MAX_LOCAL_SCALAR];
    let mut n = [0.0; MAX_LOCAL_SCALAR];
    let mut dn = [[0.0; 2]; MAX_LOCAL_SCALAR];
    for k in 0..space.leaves.len() {
        let p = space.degree[k];
        let nl = (p + 1) * (p + 1);
        f[..nl].fill(0.0);
        if !problem.harmonic() {
            let c = space.leaves[k];
            let h = tree.h(c);
            let (x, w) = gauss_legendre(p + 2);
            for (i, &xi) in x.iter().enumerate() {
                for (j, &eta) in x.iter().enumerate() {
                    space.shape(k, h, xi, eta, &mut n, &mut dn);
                    let fx = problem.f(tree.map_point(c, xi, eta));
                    let wq = w[i] * w[j] * 0.25 * h * h;
                    for a in 0..nl {
                        f[a] += wq * fx * n[a];
                    }
                }
            }
        }
        pat.add_cell(k, &kref[p], &f[..nl], &mut values, &mut rhs, &mut scratch);
    }
    PoissonSystem { values, rhs }
}

/// Solve by sparse Cholesky; returns the full dof vector.
pub fn solve_direct(space: &Space, sys: &PoissonSystem) -> Result<Vec<f64>, LinearError> {
    let pat = &space.pattern;
    let mut solver = SparseSolver::new(pat.n, &pat.col_ptr, &pat.row_idx, LinearKind::Cholesky)?;
    solver.set_track_determinant(false);
    solver.factorize(&sys.values)?;
    let mut y = sys.rhs.clone();
    solver.solve_in_place(&mut y)?;
    let mut x = vec![0.0; space.n_dofs()];
    space.constraints.distribute(&y, &mut x);
    Ok(x)
}

/// Outcome of the conjugate-gradient solve.
#[derive(Clone, Copy, Debug)]
pub struct CgStats {
    pub iterations: usize,
    pub relative_residual: f64,
}

/// Jacobi-preconditioned CG on the condensed system, started from the free entries of `x`
/// (full dof vector, e.g. a transferred solution), to ‖r‖ ≤ tol ‖b‖. Overwrites `x`.
pub fn solve_cg(
    space: &Space,
    sys: &PoissonSystem,
    x: &mut [f64],
    tol: f64,
    max_iter: usize,
) -> CgStats {
    let pat = &space.pattern;
    let n = pat.n;
    let mut y = vec![0.0; n];
    space.constraints.gather(x, &mut y);
    let dinv: Vec<f64> = pat
        .diagonal(&sys.values)
        .iter()
        .map(|&d| if d > 0.0 { 1.0 / d } else { 1.0 })
        .collect();
    let mut r = vec![0.0; n];
    pat.matvec(&sys.values, &y, &mut r);
    for (ri, bi) in r.iter_mut().zip(&sys.rhs) {
        *ri = bi - *ri;
    }
    let bnorm = sys
        .rhs
        .iter()
        .map(|v| v * v)
        .sum::<f64>()
        .sqrt()
        .max(1e-300);
    let mut z: Vec<f64> = r.iter().zip(&dinv).map(|(a, b)| a * b).collect();
    let mut pdir = z.clone();
    let mut q = vec![0.0; n];
    let mut rz: f64 = r.iter().zip(&z).map(|(a, b)| a * b).sum();
    let mut it = 0;
    let mut rel = r.iter().map(|v| v * v).sum::<f64>().sqrt() / bnorm;
    while it < max_iter && rel > tol {
        pat.matvec(&sys.values, &pdir, &mut q);
        let pq: f64 = pdir.iter().zip(&q).map(|(a, b)| a * b).sum();
        if pq <= 0.0 {
            break;
        }
        let alpha = rz / pq;
        for i in 0..n {
            y[i] += alpha * pdir[i];
            r[i] -= alpha * q[i];
        }
        for i in 0..n {
            z[i] = r[i] * dinv[i];
        }
        let rz_new: f64 = r.iter().zip(&z).map(|(a, b)| a * b).sum();
        let beta = rz_new / rz;
        rz = rz_new;
        for i in 0..n {
            pdir[i] = z[i] + beta * pdir[i];
        }
        it += 1;
        rel = r.iter().map(|v| v * v).sum::<f64>().sqrt() / bnorm;
    }
    space.constraints.distribute(&y, x);
    CgStats {
        iterations: it,
        relative_residual: rel,
    }
}

/// Squared energy error ‖∇(u − u_h)‖²_K of every leaf. Cells touching the problem's singular
/// point are integrated on a graded subdivision.
pub fn energy_error_sq(space: &Space, tree: &Quadtree, x: &[f64], problem: &dyn Exact) -> Vec<f64> {
    let (gx, gw) = gauss_legendre(space.degree.iter().copied().max().unwrap_or(1) + 4);
    let sing = problem.singular_point();
    (0..space.leaves.len())
        .map(|k| {
            let c = space.leaves[k];
            let h = tree.h(c);
            let [x0, y0] = tree.corner(c);
            let touches = sing.is_some_and(|s| {
                s[0] >= x0 - 1e-12
                    && s[0] <= x0 + h + 1e-12
                    && s[1] >= y0 - 1e-12
                    && s[1] <= y0 + h + 1e-12
            });
            // Sub-squares in reference coordinates (centre, half-width).
            let mut subs: Vec<(f64, f64, f64)> = vec![(0.0, 0.0, 1.0)];
            if touches {
                let s = sing.unwrap_or([0.0; 2]);
                let sref = [2.0 * (s[0] - x0) / h - 1.0, 2.0 * (s[1] - y0) / h - 1.0];
                let mut out = Vec::new();
                for _ in 0..30 {
                    let mut next = Vec::new();
                    for (cx, cy, hw) in subs.drain(..) {
                        let near = (sref[0] - cx).abs() <= hw + 1e-12
                            && (sref[1] - cy).abs() <= hw + 1e-12;
                        if near {
                            let q = 0.5 * hw;
                            for (dx, dy) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
                                next.push((cx + dx * q, cy + dy * q, q));
                            }
                        } else {
                            out.push((cx, cy, hw));
                        }
                    }
                    subs = next;
                }
                out.extend(subs);
                subs = out;
            }
            let mut e = 0.0;
            for (cx, cy, hw) in subs {
                for (i, &a) in gx.iter().enumerate() {
                    for (j, &b) in gx.iter().enumerate() {
                        let (xi, eta) = (cx + hw * a, cy + hw * b);
                        let (_, gh) = space.eval(tree, x, k, 0, xi, eta);
                        let g = problem.grad(tree.map_point(c, xi, eta));
                        let w = gw[i] * gw[j] * hw * hw * 0.25 * h * h;
                        e += w * ((g[0] - gh[0]).powi(2) + (g[1] - gh[1]).powi(2));
                    }
                }
            }
            e
        })
        .collect()
}

/// |u|²_{1,Ω} of the L-shape solution, by graded quadrature on the three unit squares.
pub fn lshape_energy_sq() -> f64 {
    let t = Quadtree::l_shape(0, 1);
    let space = match Space::new(&t, Basis1d::Lagrange, 1, None) {
        Ok(s) => s,
        Err(_) => return f64::NAN,
    };
    // u_h = 0 on this space except boundary data; use a zero vector: the "error" is |u|₁.
    let x = vec![0.0; space.n_dofs()];
    energy_error_sq(&space, &t, &x, &LShape).iter().sum()
}
