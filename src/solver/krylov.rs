//! Restarted GMRES for a Newton step whose exact tangent is an assembled sparse matrix K plus
//! an operator C applied matrix-free ([`NonlinearSystem::tangent_correction`]), right
//! preconditioned with the factorization of K:
//!
//! ```text
//! (K + C) M⁻¹ z = r0,     x = x0 + M⁻¹ z,     M = the LU/Cholesky factors of K,
//! ```
//!
//! starting from x0 = M⁻¹ b (the step of the assembled part alone). When C is small next to K
//! (or of low effective rank) a few iterations give the exact Newton step, so Newton keeps its
//! quadratic convergence while the factorization keeps the sparsity of K.

use super::linear::{LinearError, SparseSolver};
use super::newton::NonlinearSystem;

/// What a GMRES solve did.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct KrylovStats {
    /// Matrix–vector products with K + C.
    pub iterations: usize,
    /// ‖b − (K + C) x‖ / ‖b‖ at the end.
    pub rel_residual: f64,
}

/// y = K v with the system's assembled CSC matrix, plus the correction C v.
fn apply<S: NonlinearSystem + ?Sized>(sys: &mut S, v: &[f64], y: &mut [f64]) {
    y.fill(0.0);
    {
        let (col_ptr, row_idx) = sys.pattern();
        let vals = sys.matrix_values();
        for j in 0..v.len() {
            let vj = v[j];
            if vj == 0.0 {
                continue;
            }
            for p in col_ptr[j]..col_ptr[j + 1] {
                y[row_idx[p]] += vals[p] * vj;
            }
        }
    }
    sys.tangent_correction(v, y);
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Solve (K + C) x = b by restarted GMRES(`restart`) preconditioned on the right with the
/// factorization held by `lu` (already factorized at the current K); `x` holds the initial
/// guess on entry. Stops at ‖b − (K + C) x‖ ≤ `rtol` ‖b‖ or after `max_it` products.
pub fn gmres<S: NonlinearSystem + ?Sized>(
    sys: &mut S,
    lu: &mut SparseSolver,
    b: &[f64],
    x: &mut [f64],
    rtol: f64,
    restart: usize,
    max_it: usize,
) -> Result<KrylovStats, LinearError> {
    gmres_with(
        |v, y| apply(sys, v, y),
        |z| lu.solve_in_place(z),
        b,
        x,
        rtol,
        restart,
        max_it,
    )
}

/// Restarted GMRES(`restart`) for A x = b with the product `apply(v, y)`: y = A v and the
/// right preconditioner `precond(z)`: z ← M⁻¹ z (a fixed linear map); `x` holds the initial
/// guess on entry. Stops at ‖b − A x‖ ≤ `rtol` ‖b‖ or after `max_it` products.
pub fn gmres_with<E>(
    mut apply: impl FnMut(&[f64], &mut [f64]),
    mut precond: impl FnMut(&mut [f64]) -> Result<(), E>,
    b: &[f64],
    x: &mut [f64],
    rtol: f64,
    restart: usize,
    max_it: usize,
) -> Result<KrylovStats, E> {
    let n = b.len();
    let bnorm = dot(b, b).sqrt();
    let mut stats = KrylovStats::default();
    if bnorm == 0.0 {
        x.fill(0.0);
        return Ok(stats);
    }
    let m = restart.max(1);
    let mut r = vec![0.0; n];
    let mut w = vec![0.0; n];
    let mut vs: Vec<Vec<f64>> = Vec::with_capacity(m + 1);
    let mut zs: Vec<Vec<f64>> = Vec::with_capacity(m);
    let mut h = vec![vec![0.0; m]; m + 1];
    let (mut cs, mut sn, mut g) = (vec![0.0; m], vec![0.0; m], vec![0.0; m + 1]);
    loop {
        apply(x, &mut w);
        stats.iterations += 1;
        for i in 0..n {
            r[i] = b[i] - w[i];
        }
        let beta = dot(&r, &r).sqrt();
        stats.rel_residual = beta / bnorm;
        if beta <= rtol * bnorm || stats.iterations >= max_it {
            return Ok(stats);
        }
        vs.clear();
        zs.clear();
        vs.push(r.iter().map(|v| v / beta).collect());
        g.fill(0.0);
        g[0] = beta;
        let mut k_done = 0;
        for j in 0..m {
            let mut z = vs[j].clone();
            precond(&mut z)?;
            apply(&z, &mut w);
            stats.iterations += 1;
            zs.push(z);
            for i in 0..=j {
                h[i][j] = dot(&w, &vs[i]);
                let hij = h[i][j];
                for (wk, vk) in w.iter_mut().zip(&vs[i]) {
                    *wk -= hij * vk;
                }
            }
            let hn = dot(&w, &w).sqrt();
            h[j + 1][j] = hn;
            for i in 0..j {
                let t = cs[i] * h[i][j] + sn[i] * h[i + 1][j];
                h[i + 1][j] = -sn[i] * h[i][j] + cs[i] * h[i + 1][j];
                h[i][j] = t;
            }
            let d = (h[j][j] * h[j][j] + hn * hn).sqrt();
            if d == 0.0 {
                k_done = j;
                break;
            }
            cs[j] = h[j][j] / d;
            sn[j] = hn / d;
            h[j][j] = d;
            h[j + 1][j] = 0.0;
            g[j + 1] = -sn[j] * g[j];
            g[j] *= cs[j];
            k_done = j + 1;
            if g[j + 1].abs() <= rtol * bnorm || stats.iterations >= max_it || hn == 0.0 {
                break;
            }
            vs.push(w.iter().map(|v| v / hn).collect());
        }
        // y = H⁻¹ g (upper triangular), x += Z y.
        let mut y = vec![0.0; k_done];
        for i in (0..k_done).rev() {
            let mut s = g[i];
            for l in i + 1..k_done {
                s -= h[i][l] * y[l];
            }
            y[i] = s / h[i][i];
        }
        for (yi, z) in y.iter().zip(&zs) {
            for (xk, zk) in x.iter_mut().zip(z) {
                *xk += yi * zk;
            }
        }
    }
}
