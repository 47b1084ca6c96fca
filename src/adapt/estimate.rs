//! A posteriori error estimators for −Δu = f behind one interface
//! ([`super::marking::CellEstimator`] of a [`Context`]): an indicator η_K per leaf (in
//! `space.leaves` order) and the global estimate η = (Σ η_K²)^{1/2} of the energy error
//! ‖∇(u − u_h)‖ ([`CellEstimate`]).
//!
//! * [`ExplicitResidual`]: η_K² = (h_K/p_K)² ‖f + Δu_h‖²_K + ½ Σ_{F ⊂ ∂K, interior}
//!   (h_F/p_F) ‖[∂_n u_h]‖²_F (unknown constant, taken as 1).
//! * [`Equilibrated`] (implicit element residual, Ladevèze–Leguillon / Ainsworth–Oden): face
//!   fluxes g_K = ⟨∂_{n_K} u_h⟩ + σ_{K,F} Δg_F, antisymmetric across faces, with the linear
//!   corrections Δg_F chosen vertex patch by vertex patch (minimum norm of the moments
//!   μ_F^n = ∫_F Δg_F θ_n) so that every cell is in equilibrium with the first-order partition
//!   of unity θ_n (including hanging-node constraints):
//!   (f, θ_n)_K − (∇u_h, ∇θ_n)_K + Σ_F ∫_F g_K θ_n = 0.
//!   Then the local Neumann problems (∇φ_K, ∇v)_K = (f, v)_K − (∇u_h, ∇v)_K + ∮ g_K v are
//!   solved in Q_{p+2}(K) modulo constants, η_K = ‖∇φ_K‖_K. Summing the local problems with
//!   v = e gives ‖∇e‖² = Σ_K (∇φ_K, ∇e)_K ≤ (Σ ‖∇φ_K‖²)^{1/2} ‖∇e‖: an upper bound, up to the
//!   truncation of the local problems to Q_{p+2} and the interpolation of the Dirichlet data.
//! * [`Recovery`] (Zienkiewicz–Zhu, superconvergent patch recovery): at every vertex a
//!   polynomial of degree p is fitted by least squares to ∇u_h at the p×p Gauss points of the
//!   cells around it; the recovered gradient G lives in the continuous Lagrange space of the
//!   same degree (vertex values from their patch, edge and centre nodes averaged over the
//!   patches of their cell's vertices, hanging nodes by their constraints);
//!   η_K = ‖G − ∇u_h‖_K.
//! * [`Interpolation`] (the interpolation estimator): |u − Π_h u|_{1,K} ≤ C h^p |u|_{p+1,K}
//!   with the derivatives of order p + 1 taken from the recovered gradient,
//!   η_K² = c_p h_K^{2p} (‖∂_x^p G_x‖²_K + ‖∂_y^p G_y‖²_K), c_p = ∫_0^1 (ω')², ω(x) =
//!   Π_i (x − i/p)/(p + 1)! (the tensor interpolant reproduces the mixed derivatives), so
//!   c_1 = 1/12, c_2 = 1/720: the estimate is exact for the Q1 (Q2) interpolation error of a
//!   quadratic (cubic). Degrees 1 and 2.
//!
//! All estimators vanish when u_h = u (no residual, no jump, exact recovery).

use super::marking::{CellEstimate, CellEstimator};
use super::quadtree::{Across, Quadtree, SIDES};
use super::space::{shape_second, shape_values, Space, SpaceError, MAX_LOCAL_SCALAR};
use crate::element::hierarchical::{gauss_legendre, Basis1d};
use nalgebra::{DMatrix, DVector};

/// What an estimator needs: the mesh, the space, the solution (full dof vector) and the
/// source f.
pub struct Context<'a> {
    pub tree: &'a Quadtree,
    pub space: &'a Space,
    pub x: &'a [f64],
    pub f: &'a (dyn Fn([f64; 2]) -> f64 + Sync),
}

/// The estimators of this module behind the shared interface
/// ([`CellEstimator`] of a [`Context`]), as one object type: `Box<dyn Estimator>`.
pub trait Estimator: for<'a> CellEstimator<Context<'a>, Error = SpaceError> {}

impl<T: ?Sized + for<'a> CellEstimator<Context<'a>, Error = SpaceError>> Estimator for T {}

/// A face between two leaves (or a leaf and the boundary): the side of `minus`, the normal
/// pointing from `minus` to `plus`.
#[derive(Clone, Debug)]
pub struct Face {
    pub minus: usize,
    pub plus: Option<usize>,
    pub x0: [f64; 2],
    pub dir: usize,
    pub len: f64,
    pub normal: [f64; 2],
}

impl Face {
    #[inline]
    pub fn point(&self, t: f64) -> [f64; 2] {
        let mut x = self.x0;
        x[self.dir] += 0.5 * (t + 1.0) * self.len;
        x
    }
}

/// Faces of the leaf mesh: each interior face once (a hanging side once, from its fine
/// cell), each boundary side once.
pub fn faces(tree: &Quadtree, space: &Space) -> Vec<Face> {
    let mut out = Vec::new();
    for (k, &c) in space.leaves.iter().enumerate() {
        let [cx, cy] = tree.corner(c);
        let h = tree.h(c);
        for side in SIDES {
            let plus = match tree.across(c, side) {
                Across::Same(n) if side == 1 || side == 3 => Some(space.leaf_index[&n]),
                Across::Same(_) | Across::Finer(_) => continue,
                Across::Coarser(n) => Some(space.leaf_index[&n]),
                Across::Boundary => None,
            };
            let (x0, dir, normal) = match side {
                0 => ([cx, cy], 1, [-1.0, 0.0]),
                1 => ([cx + h, cy], 1, [1.0, 0.0]),
                2 => ([cx, cy], 0, [0.0, -1.0]),
                _ => ([cx, cy + h], 0, [0.0, 1.0]),
            };
            out.push(Face {
                minus: k,
                plus,
                x0,
                dir,
                len: h,
                normal,
            });
        }
    }
    out
}

/// Reference coordinates of physical point x in leaf k.
#[inline]
fn to_ref(tree: &Quadtree, space: &Space, k: usize, x: [f64; 2]) -> (f64, f64) {
    let c = space.leaves[k];
    let [x0, y0] = tree.corner(c);
    let h = tree.h(c);
    (2.0 * (x[0] - x0) / h - 1.0, 2.0 * (x[1] - y0) / h - 1.0)
}

fn grad_at(ctx: &Context, k: usize, x: [f64; 2]) -> [f64; 2] {
    let (xi, eta) = to_ref(ctx.tree, ctx.space, k, x);
    ctx.space.eval(ctx.tree, ctx.x, k, 0, xi, eta).1
}

/// Explicit residual estimator.
pub struct ExplicitResidual;

impl CellEstimator<Context<'_>> for ExplicitResidual {
    type Error = SpaceError;
    fn name(&self) -> &'static str {
        "explicit residual"
    }
    fn estimate(&self, ctx: &Context) -> Result<CellEstimate, SpaceError> {
        let (tree, space) = (ctx.tree, ctx.space);
        let nc = space.leaves.len();
        let mut sq = vec![0.0; nc];
        let mut d2 = [[0.0; 3]; MAX_LOCAL_SCALAR];
        let pmax = space.degree.iter().copied().max().unwrap_or(1);
        let rules: Vec<(Vec<f64>, Vec<f64>)> = (0..=pmax + 2).map(gauss_legendre).collect();
        for (k, s) in sq.iter_mut().enumerate() {
            let c = space.leaves[k];
            let h = tree.h(c);
            let p = space.degree[k];
            let (gx, gw) = &rules[p + 2];
            let dofs = space.dofs(k);
            let mut r2 = 0.0;
            for (i, &xi) in gx.iter().enumerate() {
                for (j, &eta) in gx.iter().enumerate() {
                    let nl = shape_second(space.basis, p, h, xi, eta, &mut d2);
                    let lap: f64 = (0..nl)
                        .map(|a| (d2[a][0] + d2[a][2]) * ctx.x[dofs[a] as usize])
                        .sum();
                    let r = (ctx.f)(tree.map_point(c, xi, eta)) + lap;
                    r2 += gw[i] * gw[j] * 0.25 * h * h * r * r;
                }
            }
            *s = (h / p as f64).powi(2) * r2;
        }
        for f in faces(tree, space) {
            let Some(plus) = f.plus else { continue };
            let p = space.degree[f.minus].max(space.degree[plus]);
            let (gx, gw) = &rules[p + 2];
            let mut j2 = 0.0;
            for (&t, &w) in gx.iter().zip(gw) {
                let x = f.point(t);
                let gm = grad_at(ctx, f.minus, x);
                let gp = grad_at(ctx, plus, x);
                let jump = (gm[0] - gp[0]) * f.normal[0] + (gm[1] - gp[1]) * f.normal[1];
                j2 += w * 0.5 * f.len * jump * jump;
            }
            let e = 0.5 * (f.len / p as f64) * j2;
            sq[f.minus] += e;
            sq[plus] += e;
        }
        Ok(CellEstimate::from_squares(sq))
    }
}

/// Equilibrated residual estimator with local Neumann problems.
pub struct Equilibrated;

/// Reference stiffness of the hierarchical basis of degree q (row-major) and the cross
/// stiffness ∫ ∇ψ_a(q) · ∇φ_b(p) (rows degree q, columns degree p).
/// Cholesky factor of a local Neumann matrix (gauge removed), with its full matrices K_qq, K_qp.
type LocalNeumann = (
    nalgebra::Cholesky<f64, nalgebra::Dyn>,
    DMatrix<f64>,
    DMatrix<f64>,
);

/// Per vertex of a recovery patch: the fitted polynomial coefficients of both gradient
/// components and the patch size h used to scale the monomials.
type PatchPolynomials = std::collections::HashMap<(i64, i64), ([f64; 6], [f64; 6], f64)>;

fn local_matrices(basis: Basis1d, p: usize, q: usize) -> (DMatrix<f64>, DMatrix<f64>) {
    let (gx, gw) = gauss_legendre(q + 1);
    let nq = (q + 1) * (q + 1);
    let np = (p + 1) * (p + 1);
    let mut kqq = DMatrix::zeros(nq, nq);
    let mut kqp = DMatrix::zeros(nq, np);
    let mut n = [0.0; MAX_LOCAL_SCALAR];
    let mut dn = [[0.0; 2]; MAX_LOCAL_SCALAR];
    let mut m = [0.0; MAX_LOCAL_SCALAR];
    let mut dm = [[0.0; 2]; MAX_LOCAL_SCALAR];
    for (i, &xi) in gx.iter().enumerate() {
        for (j, &eta) in gx.iter().enumerate() {
            shape_values(Basis1d::Hierarchical, q, 2.0, xi, eta, &mut n, &mut dn);
            shape_values(basis, p, 2.0, xi, eta, &mut m, &mut dm);
            let w = gw[i] * gw[j];
            for a in 0..nq {
                for b in 0..nq {
                    kqq[(a, b)] += w * (dn[a][0] * dn[b][0] + dn[a][1] * dn[b][1]);
                }
                for b in 0..np {
                    kqp[(a, b)] += w * (dn[a][0] * dm[b][0] + dn[a][1] * dm[b][1]);
                }
            }
        }
    }
    (kqq, kqp)
}

impl CellEstimator<Context<'_>> for Equilibrated {
    type Error = SpaceError;
    fn name(&self) -> &'static str {
        "equilibrated residual"
    }
    fn estimate(&self, ctx: &Context) -> Result<CellEstimate, SpaceError> {
        let (tree, space) = (ctx.tree, ctx.space);
        let nc = space.leaves.len();
        // First-order partition of unity with hanging-node constraints, no Dirichlet data.
        let mut t1 = tree.clone();
        for &c in &space.leaves {
            t1.cells[c as usize].degree = 1;
        }
        let q1 = Space::new(&t1, Basis1d::Lagrange, 1, None)?;
        let n_theta = q1.n_eq();
        // θ expansion of the four local hats of every cell: (node, coefficient) per hat.
        let theta_of = |k: usize, a: usize| q1.constraints.expansion(q1.dofs(k)[a] as usize).0;
        let faces = faces(tree, space);
        let pmax = space.degree.iter().copied().max().unwrap_or(1);
        let nq_face = pmax + 4;
        let (ft, fw) = gauss_legendre(nq_face);
        // Average normal flux ⟨∂_{n_F} u_h⟩ at the face points (one-sided on the boundary).
        let avg: Vec<Vec<f64>> = faces
            .iter()
            .map(|f| {
                ft.iter()
                    .map(|&t| {
                        let x = f.point(t);
                        let gm = grad_at(ctx, f.minus, x);
                        let g = match f.plus {
                            Some(pl) => {
                                let gp = grad_at(ctx, pl, x);
                                [0.5 * (gm[0] + gp[0]), 0.5 * (gm[1] + gp[1])]
                            }
                            None => gm,
                        };
                        g[0] * f.normal[0] + g[1] * f.normal[1]
                    })
                    .collect()
            })
            .collect();
        // Q1 hats of cell k at reference (ξ, η).
        let hats = |xi: f64, eta: f64| {
            let (a0, a1) = (0.5 * (1.0 - xi), 0.5 * (1.0 + xi));
            let (b0, b1) = (0.5 * (1.0 - eta), 0.5 * (1.0 + eta));
            [a0 * b0, a1 * b0, a0 * b1, a1 * b1]
        };
        // r_a = (f, N_a) − (∇u_h, ∇N_a) + Σ_F ∫ ⟨∂_{n_K} u_h⟩ N_a per cell and local hat.
        let mut r = vec![[0.0f64; 4]; nc];
        let mut n = [0.0; MAX_LOCAL_SCALAR];
        let mut dn = [[0.0; 2]; MAX_LOCAL_SCALAR];
        let mut n1 = [0.0; MAX_LOCAL_SCALAR];
        let mut dn1 = [[0.0; 2]; MAX_LOCAL_SCALAR];
        for (k, rk) in r.iter_mut().enumerate() {
            let c = space.leaves[k];
            let h = tree.h(c);
            let p = space.degree[k];
            let (gx, gw) = gauss_legendre(p + 2);
            let dofs = space.dofs(k);
            for (i, &xi) in gx.iter().enumerate() {
                for (j, &eta) in gx.iter().enumerate() {
                    let nl = shape_values(space.basis, p, h, xi, eta, &mut n, &mut dn);
                    let mut g = [0.0; 2];
                    for a in 0..nl {
                        let v = ctx.x[dofs[a] as usize];
                        g[0] += dn[a][0] * v;
                        g[1] += dn[a][1] * v;
                    }
                    shape_values(Basis1d::Lagrange, 1, h, xi, eta, &mut n1, &mut dn1);
                    let w = gw[i] * gw[j] * 0.25 * h * h;
                    let fx = (ctx.f)(tree.map_point(c, xi, eta));
                    for a in 0..4 {
                        rk[a] += w * (fx * n1[a] - g[0] * dn1[a][0] - g[1] * dn1[a][1]);
                    }
                }
            }
        }
        for (fi, f) in faces.iter().enumerate() {
            for (qi, (&t, &w)) in ft.iter().zip(&fw).enumerate() {
                let x = f.point(t);
                let wl = w * 0.5 * f.len * avg[fi][qi];
                let (xi, eta) = to_ref(tree, space, f.minus, x);
                let hm = hats(xi, eta);
                for a in 0..4 {
                    r[f.minus][a] += wl * hm[a];
                }
                if let Some(pl) = f.plus {
                    let (xi, eta) = to_ref(tree, space, pl, x);
                    let hp = hats(xi, eta);
                    for a in 0..4 {
                        r[pl][a] -= wl * hp[a];
                    }
                }
            }
        }
        // Per node: b_K^n (cells) and the faces where θ_n does not vanish.
        let mut node_cells: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n_theta];
        for (k, rk) in r.iter().enumerate().take(nc) {
            for (a, &rka) in rk.iter().enumerate().take(4) {
                for &(nd, coef) in theta_of(k, a) {
                    let list = &mut node_cells[nd as usize];
                    let v = coef * rka;
                    match list.iter_mut().find(|e| e.0 == k) {
                        Some(e) => e.1 += v,
                        None => list.push((k, v)),
                    }
                }
            }
        }
        // θ_n at the two ends of every face: (node, value at start, value at end).
        let face_theta: Vec<Vec<(u32, f64, f64)>> = faces
            .iter()
            .map(|f| {
                let mut out: Vec<(u32, f64, f64)> = Vec::new();
                for (e, t) in [(0, -1.0), (1, 1.0)] {
                    let (xi, eta) = to_ref(tree, space, f.minus, f.point(t));
                    let hm = hats(xi, eta);
                    for (a, &hma) in hm.iter().enumerate().take(4) {
                        if hma.abs() < 1e-12 {
                            continue;
                        }
                        for &(nd, coef) in theta_of(f.minus, a) {
                            let v = coef * hma;
                            let ent = match out.iter_mut().find(|x| x.0 == nd) {
                                Some(x) => x,
                                None => {
                                    out.push((nd, 0.0, 0.0));
                                    out.last_mut().unwrap_or_else(|| unreachable!())
                                }
                            };
                            if e == 0 {
                                ent.1 += v;
                            } else {
                                ent.2 += v;
                            }
                        }
                    }
                }
                out.retain(|x| x.1.abs() > 1e-12 || x.2.abs() > 1e-12);
                out
            })
            .collect();
        let mut node_faces: Vec<Vec<usize>> = vec![Vec::new(); n_theta];
        for (fi, ft_) in face_theta.iter().enumerate() {
            for &(nd, _, _) in ft_ {
                node_faces[nd as usize].push(fi);
            }
        }
        // Patch problems: minimum-norm moments μ_F^n with A μ = −b.
        let mut mu: Vec<Vec<(u32, f64)>> = vec![Vec::new(); faces.len()];
        for nd in 0..n_theta {
            let cells = &node_cells[nd];
            let fl = &node_faces[nd];
            if cells.is_empty() || fl.is_empty() {
                continue;
            }
            let mut a = DMatrix::<f64>::zeros(cells.len(), fl.len());
            let mut b = DVector::<f64>::zeros(cells.len());
            for (ci, &(k, bk)) in cells.iter().enumerate() {
                b[ci] = -bk;
                for (j, &fi) in fl.iter().enumerate() {
                    if faces[fi].minus == k {
                        a[(ci, j)] += 1.0;
                    }
                    if faces[fi].plus == Some(k) {
                        a[(ci, j)] -= 1.0;
                    }
                }
            }
            let aat = &a * a.transpose();
            let lam = match aat.clone().pseudo_inverse(1e-10) {
                Ok(pinv) => pinv * b,
                Err(_) => continue,
            };
            let m = a.transpose() * lam;
            for (j, &fi) in fl.iter().enumerate() {
                mu[fi].push((nd as u32, m[j]));
            }
        }
        // Linear corrections Δg_F = α0 ψ0 + α1 ψ1 from the moments (Gram system).
        let corr: Vec<[f64; 2]> = faces
            .iter()
            .enumerate()
            .map(|(fi, f)| {
                let th = &face_theta[fi];
                if th.is_empty() {
                    return [0.0; 2];
                }
                // ∫ θ ψ_j over the face: θ, ψ linear; ∫ ψ_i ψ_j = L (2, 1; 1, 2)/6.
                let l = f.len;
                let mut g = DMatrix::<f64>::zeros(th.len(), 2);
                let mut rhs = DVector::<f64>::zeros(th.len());
                for (i, &(nd, t0, t1)) in th.iter().enumerate() {
                    g[(i, 0)] = l * (2.0 * t0 + t1) / 6.0;
                    g[(i, 1)] = l * (t0 + 2.0 * t1) / 6.0;
                    rhs[i] = mu[fi].iter().find(|m| m.0 == nd).map_or(0.0, |m| m.1);
                }
                match g.clone().pseudo_inverse(1e-14) {
                    Ok(pi) => {
                        let al = pi * rhs;
                        [al[0], al[1]]
                    }
                    Err(_) => [0.0; 2],
                }
            })
            .collect();
        // Local Neumann problems in Q_{p+2}, vertex function 0 removed (gauge).
        let mut mats: Vec<Option<LocalNeumann>> = (0..=pmax).map(|_| None).collect();
        for (p, mat) in mats.iter_mut().enumerate().skip(1) {
            if space.degree.contains(&p) {
                let q = (p + 2).min(crate::element::hierarchical::MAX_DEGREE);
                let (kqq, kqp) = local_matrices(space.basis, p, q);
                let red = kqq
                    .view((1, 1), (kqq.nrows() - 1, kqq.ncols() - 1))
                    .into_owned();
                if let Some(ch) = red.clone().cholesky() {
                    *mat = Some((ch, kqq, kqp));
                }
            }
        }
        let qdeg = |p: usize| (p + 2).min(crate::element::hierarchical::MAX_DEGREE);
        let mut rhs: Vec<DVector<f64>> = (0..nc)
            .map(|k| {
                let q = qdeg(space.degree[k]);
                DVector::zeros((q + 1) * (q + 1))
            })
            .collect();
        for (fi, f) in faces.iter().enumerate() {
            let [a0, a1] = corr[fi];
            for (qi, (&t, &w)) in ft.iter().zip(&fw).enumerate() {
                let x = f.point(t);
                let dg = a0 * 0.5 * (1.0 - t) + a1 * 0.5 * (1.0 + t);
                let gm = avg[fi][qi] + dg;
                let wl = w * 0.5 * f.len * gm;
                for (k, sgn) in [(Some(f.minus), 1.0), (f.plus, -1.0)] {
                    let Some(k) = k else { continue };
                    let q = qdeg(space.degree[k]);
                    let (xi, eta) = to_ref(tree, space, k, x);
                    let h = tree.h(space.leaves[k]);
                    let nl = shape_values(Basis1d::Hierarchical, q, h, xi, eta, &mut n, &mut dn);
                    for a in 0..nl {
                        rhs[k][a] += sgn * wl * n[a];
                    }
                }
            }
        }
        let mut sq = vec![0.0; nc];
        for k in 0..nc {
            let p = space.degree[k];
            let Some((ch, kqq, kqp)) = &mats[p] else {
                continue;
            };
            let c = space.leaves[k];
            let h = tree.h(c);
            let q = qdeg(p);
            let dofs = space.dofs(k);
            let uloc = DVector::from_iterator(dofs.len(), dofs.iter().map(|&d| ctx.x[d as usize]));
            let mut rk = rhs[k].clone() - kqp * uloc;
            if !is_zero_source(ctx, tree, c, q) {
                let (gx, gw) = gauss_legendre(q + 1);
                for (i, &xi) in gx.iter().enumerate() {
                    for (j, &eta) in gx.iter().enumerate() {
                        let nl =
                            shape_values(Basis1d::Hierarchical, q, h, xi, eta, &mut n, &mut dn);
                        let fx = (ctx.f)(tree.map_point(c, xi, eta));
                        let w = gw[i] * gw[j] * 0.25 * h * h;
                        for a in 0..nl {
                            rk[a] += w * fx * n[a];
                        }
                    }
                }
            }
            let red = rk.rows(1, rk.len() - 1).into_owned();
            let phi = ch.solve(&red);
            let mut full = DVector::zeros(rk.len());
            full.rows_mut(1, rk.len() - 1).copy_from(&phi);
            sq[k] = full.dot(&(kqq * &full));
        }
        Ok(CellEstimate::from_squares(sq))
    }
}

/// f vanishes at the cell centre and corners (cheap test to skip the load integral).
fn is_zero_source(ctx: &Context, tree: &Quadtree, c: u32, _q: usize) -> bool {
    [
        (0.0, 0.0),
        (-1.0, -1.0),
        (1.0, 1.0),
        (-1.0, 1.0),
        (1.0, -1.0),
        (0.3, -0.7),
    ]
    .iter()
    .all(|&(a, b)| (ctx.f)(tree.map_point(c, a, b)) == 0.0)
}

/// The recovered gradient: a continuous Lagrange field of degree min(p, 2) per component.
pub struct Recovered {
    pub space: Space,
    /// Full dof vectors of G_x and G_y.
    pub g: [Vec<f64>; 2],
}

/// Superconvergent patch recovery of ∇u_h.
pub fn recover_gradient(ctx: &Context) -> Result<Recovered, SpaceError> {
    let (tree, space) = (ctx.tree, ctx.space);
    let p = space.degree.iter().copied().max().unwrap_or(1).min(2);
    let mut tr = tree.clone();
    for &c in &space.leaves {
        tr.cells[c as usize].degree = p as u8;
    }
    let rs = Space::new(&tr, Basis1d::Lagrange, 1, None)?;
    // Vertices of every leaf, by integer position; their patch cells.
    use std::collections::HashMap;
    let mut vpatch: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
    for (k, &c) in space.leaves.iter().enumerate() {
        let cell = &tree.cells[c as usize];
        let s = super::quadtree::size_of_level(cell.level);
        for (i, j) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            vpatch
                .entry((cell.ix + i * s, cell.iy + j * s))
                .or_default()
                .push(k);
        }
    }
    // Hanging vertices are not vertices of the coarse cell: add coarse cells touching them.
    let (gx, _) = gauss_legendre(p);
    let ncoef = if p == 1 { 3 } else { 6 };
    let mono =
        |d: [f64; 2]| -> [f64; 6] { [1.0, d[0], d[1], d[0] * d[0], d[0] * d[1], d[1] * d[1]] };
    // Patch polynomial (per component) of every vertex.
    let mut poly: PatchPolynomials = HashMap::new();
    let mut samples: Vec<([f64; 2], [f64; 2])> = Vec::new();
    for (&(vi, vj), cells) in &vpatch {
        let z = [tree.to_x(vi, 0), tree.to_x(vj, 1)];
        let mut set: Vec<usize> = cells.clone();
        // Cells touching z at a corner or (hanging vertex) along a side.
        for (dx, dy) in [(0, 0), (-1, 0), (0, -1), (-1, -1)] {
            if let Some(c) = tree.leaf_at_int(vi + dx, vj + dy) {
                if let Some(&k) = space.leaf_index.get(&c) {
                    set.push(k);
                }
            }
        }
        set.sort_unstable();
        set.dedup();
        // Grow the patch (by its neighbours across sides) until the least-squares fit is
        // unique: enough samples, not all on too few lines.
        let mut grow = 0;
        let (px, py, hs) = loop {
            samples.clear();
            let mut hs: f64 = 0.0;
            for &k in &set {
                let c = space.leaves[k];
                hs = hs.max(tree.h(c));
                for &a in &gx {
                    for &b in &gx {
                        let (_, g) = ctx.space.eval(tree, ctx.x, k, 0, a, b);
                        samples.push((tree.map_point(c, a, b), g));
                    }
                }
            }
            let m = samples.len();
            let mut fit = None;
            if m >= ncoef {
                let mut a = DMatrix::<f64>::zeros(m, ncoef);
                let mut bxy = DMatrix::<f64>::zeros(m, 2);
                for (i, (x, g)) in samples.iter().enumerate() {
                    let mv = mono([(x[0] - z[0]) / hs, (x[1] - z[1]) / hs]);
                    for j in 0..ncoef {
                        a[(i, j)] = mv[j];
                    }
                    bxy[(i, 0)] = g[0];
                    bxy[(i, 1)] = g[1];
                }
                let svd = a.svd(true, true);
                let smax = svd.singular_values.max();
                let smin = svd.singular_values.min();
                if smin > 1e-8 * smax {
                    if let Ok(cxy) = svd.solve(&bxy, 1e-12 * smax) {
                        let mut px = [0.0; 6];
                        let mut py = [0.0; 6];
                        for j in 0..ncoef {
                            px[j] = cxy[(j, 0)];
                            py[j] = cxy[(j, 1)];
                        }
                        fit = Some((px, py, hs));
                    }
                }
            }
            if let Some(f) = fit {
                break f;
            }
            if grow >= 4 {
                // Degenerate patch: constant fit.
                let mut px = [0.0; 6];
                let mut py = [0.0; 6];
                px[0] = samples.iter().map(|s| s.1[0]).sum::<f64>() / m.max(1) as f64;
                py[0] = samples.iter().map(|s| s.1[1]).sum::<f64>() / m.max(1) as f64;
                break (px, py, hs.max(1e-300));
            }
            let mut more = set.clone();
            for &k in &set {
                for side in SIDES {
                    match tree.across(space.leaves[k], side) {
                        Across::Same(n) | Across::Coarser(n) => more.push(space.leaf_index[&n]),
                        Across::Finer(pair) => {
                            more.extend(pair.iter().map(|n| space.leaf_index[n]))
                        }
                        Across::Boundary => {}
                    }
                }
            }
            more.sort_unstable();
            more.dedup();
            set = more;
            grow += 1;
        };
        poly.insert((vi, vj), (px, py, hs));
    }
    let eval_poly = |key: (i64, i64), x: [f64; 2]| -> [f64; 2] {
        let (px, py, hs) = &poly[&key];
        let z = [tree.to_x(key.0, 0), tree.to_x(key.1, 1)];
        let mv = mono([(x[0] - z[0]) / hs, (x[1] - z[1]) / hs]);
        let mut g = [0.0; 2];
        for j in 0..6 {
            g[0] += px[j] * mv[j];
            g[1] += py[j] * mv[j];
        }
        g
    };
    // Nodal values of the free nodes of the recovery space: vertex nodes from their own patch,
    // other nodes averaged over the patches of their cell's vertices.
    let n_eq = rs.n_eq();
    let mut acc = vec![[0.0f64; 3]; n_eq];
    for (k, &c) in rs.leaves.iter().enumerate() {
        let cell = &tree.cells[c as usize];
        let s = super::quadtree::size_of_level(cell.level);
        let m = p + 1;
        let pos1d = [-1.0, 1.0, 0.0];
        let verts = [(0, 0), (1, 0), (0, 1), (1, 1)];
        for j in 0..m {
            for i in 0..m {
                let a = i + m * j;
                let d = rs.dofs(k)[a] as usize;
                let e = rs.constraints.eq[d];
                if e == u32::MAX {
                    continue;
                }
                let x = tree.map_point(c, pos1d[i], pos1d[j]);
                let e = e as usize;
                if i < 2 && j < 2 {
                    let g = eval_poly((cell.ix + i as i64 * s, cell.iy + j as i64 * s), x);
                    acc[e] = [g[0], g[1], -1.0];
                } else if acc[e][2] >= 0.0 {
                    for (vi, vj) in verts {
                        let on = (i >= 2 || i == vi) && (j >= 2 || j == vj);
                        if on {
                            let g =
                                eval_poly((cell.ix + vi as i64 * s, cell.iy + vj as i64 * s), x);
                            acc[e][0] += g[0];
                            acc[e][1] += g[1];
                            acc[e][2] += 1.0;
                        }
                    }
                }
            }
        }
    }
    let mut gx_eq = vec![0.0; n_eq];
    let mut gy_eq = vec![0.0; n_eq];
    for (e, a) in acc.iter().enumerate() {
        let w = if a[2] > 0.0 { a[2] } else { 1.0 };
        gx_eq[e] = a[0] / w;
        gy_eq[e] = a[1] / w;
    }
    let mut g0 = vec![0.0; rs.n_dofs()];
    let mut g1 = vec![0.0; rs.n_dofs()];
    rs.constraints.distribute(&gx_eq, &mut g0);
    rs.constraints.distribute(&gy_eq, &mut g1);
    Ok(Recovered {
        space: rs,
        g: [g0, g1],
    })
}

/// Zienkiewicz–Zhu recovery estimator.
pub struct Recovery;

impl CellEstimator<Context<'_>> for Recovery {
    type Error = SpaceError;
    fn name(&self) -> &'static str {
        "recovery (SPR)"
    }
    fn estimate(&self, ctx: &Context) -> Result<CellEstimate, SpaceError> {
        let rec = recover_gradient(ctx)?;
        let (tree, space) = (ctx.tree, ctx.space);
        let sq = (0..space.leaves.len())
            .map(|k| {
                let c = space.leaves[k];
                let h = tree.h(c);
                let (gx, gw) = gauss_legendre(space.degree[k] + 2);
                let mut e = 0.0;
                for (i, &xi) in gx.iter().enumerate() {
                    for (j, &eta) in gx.iter().enumerate() {
                        let (_, gh) = space.eval(tree, ctx.x, k, 0, xi, eta);
                        let rx = rec.space.eval(tree, &rec.g[0], k, 0, xi, eta).0;
                        let ry = rec.space.eval(tree, &rec.g[1], k, 0, xi, eta).0;
                        e += gw[i]
                            * gw[j]
                            * 0.25
                            * h
                            * h
                            * ((rx - gh[0]).powi(2) + (ry - gh[1]).powi(2));
                    }
                }
                e
            })
            .collect();
        Ok(CellEstimate::from_squares(sq))
    }
}

/// The interpolation estimator with recovered derivatives (degrees 1 and 2).
pub struct Interpolation;

/// c_p = ∫_0^1 (ω')² dx, ω = Π_{i=0..p} (x − i/p) / (p + 1)!.
pub fn interpolation_constant(p: usize) -> f64 {
    let (gx, gw) = gauss_legendre(p + 2);
    let fact: f64 = (1..=p + 1).map(|i| i as f64).product();
    gx.iter()
        .zip(&gw)
        .map(|(&t, &w)| {
            let x = 0.5 * (t + 1.0);
            let mut d = 0.0;
            for m in 0..=p {
                let mut prod = 1.0;
                for i in 0..=p {
                    if i != m {
                        prod *= x - i as f64 / p as f64;
                    }
                }
                d += prod;
            }
            0.5 * w * (d / fact).powi(2)
        })
        .sum()
}

impl CellEstimator<Context<'_>> for Interpolation {
    type Error = SpaceError;
    fn name(&self) -> &'static str {
        "interpolation (recovered derivatives)"
    }
    fn estimate(&self, ctx: &Context) -> Result<CellEstimate, SpaceError> {
        let rec = recover_gradient(ctx)?;
        let (tree, space) = (ctx.tree, ctx.space);
        let rp = rec.space.degree.first().copied().unwrap_or(1);
        let mut d2 = [[0.0; 3]; MAX_LOCAL_SCALAR];
        let mut n = [0.0; MAX_LOCAL_SCALAR];
        let mut dn = [[0.0; 2]; MAX_LOCAL_SCALAR];
        let sq = (0..space.leaves.len())
            .map(|k| {
                let p = space.degree[k];
                if p > 2 {
                    return 0.0;
                }
                let c = space.leaves[k];
                let h = tree.h(c);
                let (gx, gw) = gauss_legendre(rp + 2);
                let dx = rec.space.dofs(k);
                let mut s = 0.0;
                for (i, &xi) in gx.iter().enumerate() {
                    for (j, &eta) in gx.iter().enumerate() {
                        // ∂_x^p G_x and ∂_y^p G_y.
                        let (ax, ay) = if p == 1 {
                            let nl =
                                shape_values(Basis1d::Lagrange, rp, h, xi, eta, &mut n, &mut dn);
                            let ax: f64 =
                                (0..nl).map(|a| dn[a][0] * rec.g[0][dx[a] as usize]).sum();
                            let ay: f64 =
                                (0..nl).map(|a| dn[a][1] * rec.g[1][dx[a] as usize]).sum();
                            (ax, ay)
                        } else {
                            let nl = shape_second(Basis1d::Lagrange, rp, h, xi, eta, &mut d2);
                            let ax: f64 =
                                (0..nl).map(|a| d2[a][0] * rec.g[0][dx[a] as usize]).sum();
                            let ay: f64 =
                                (0..nl).map(|a| d2[a][2] * rec.g[1][dx[a] as usize]).sum();
                            (ax, ay)
                        };
                        s += gw[i] * gw[j] * 0.25 * h * h * (ax * ax + ay * ay);
                    }
                }
                interpolation_constant(p) * h.powi(2 * p as i32) * s
            })
            .collect();
        Ok(CellEstimate::from_squares(sq))
    }
}
