//! The vector Burgers equations u_t + (u·∇)u = ν Δu in Ω ⊂ ℝ², u = g on ∂Ω, on the quadtree
//! Lagrange spaces (Q1, Q2, both components in one space), Crank–Nicolson in time, Galerkin in
//! space, Newton per step with the exact tangent, adapted by [`super::two_grid`].
//!
//! Cell residual of component c for the test function φ_a (δu = (u^{n+1} − u^n)/Δt):
//!
//! ∫_K δu_c φ_a + ½[(u^{n+1}·∇u_c^{n+1}) φ_a + ν∇u_c^{n+1}·∇φ_a] + ½[(u^n·∇u_c^n) φ_a
//!   + ν∇u_c^n·∇φ_a],
//!
//! and its derivative with respect to the coefficient of φ_b in component e:
//! ∫_K δ_ce φ_bφ_a/Δt + ½[(φ_b ∂_e u_c + δ_ce u·∇φ_b) φ_a + ν δ_ce ∇φ_b·∇φ_a].
//!
//! Exact solution by the Cole–Hopf transform ([`ColeHopf`]): if φ > 0 solves the heat equation
//! φ_t = νΔφ then u = −2ν ∇φ/φ solves the vector Burgers equations. With
//!
//! φ(x, t) = 1 + Σ_i a_i exp(k_i·x + ν|k_i|² t),  a_i > 0,
//!
//! u = −2ν Σ_i a_i k_i e_i / φ (e_i the exponentials). Each term alone gives a travelling
//! front of width ~1/|k_i|; two terms with different k_i give two fronts meeting along a
//! moving curve.

use super::two_grid::{basis_at, CellData, Kernel, MAX_SCALAR};
use crate::element::hierarchical::gauss_legendre;

/// φ = 1 + Σ a_i exp(k_i·x + ν|k_i|² t) and u = −2ν∇φ/φ.
#[derive(Clone, Debug)]
pub struct ColeHopf {
    pub nu: f64,
    /// (a_i, k_i).
    pub terms: Vec<(f64, [f64; 2])>,
}

impl Default for ColeHopf {
    /// ν = 0.01 on the unit square: two fronts, k₁ = (−20, −20) (a₁ = e^{20}, front along
    /// x + y = 1 at t = 0) and k₂ = (−25, 10) (a₂ = e^{10}).
    fn default() -> Self {
        Self {
            nu: 0.01,
            terms: vec![(20f64.exp(), [-20.0, -20.0]), (10f64.exp(), [-25.0, 10.0])],
        }
    }
}

impl ColeHopf {
    /// u and ∇u (row c: ∇u_c).
    pub fn u_grad(&self, x: [f64; 2], t: f64) -> ([f64; 2], [[f64; 2]; 2]) {
        // Scale every term by the largest exponent for overflow safety.
        let ex: Vec<f64> = self
            .terms
            .iter()
            .map(|(a, k)| {
                a.ln() + k[0] * x[0] + k[1] * x[1] + self.nu * (k[0] * k[0] + k[1] * k[1]) * t
            })
            .collect();
        let m = ex.iter().copied().fold(0.0f64, f64::max);
        let mut phi = (-m).exp();
        let mut g = [0.0; 2];
        let mut hs = [[0.0; 2]; 2];
        for ((_, k), &e) in self.terms.iter().zip(&ex) {
            let v = (e - m).exp();
            phi += v;
            for c in 0..2 {
                g[c] += k[c] * v;
                for d in 0..2 {
                    hs[c][d] += k[c] * k[d] * v;
                }
            }
        }
        let s = -2.0 * self.nu;
        let u = [s * g[0] / phi, s * g[1] / phi];
        let mut du = [[0.0; 2]; 2];
        for c in 0..2 {
            for d in 0..2 {
                du[c][d] = s * (hs[c][d] / phi - g[c] * g[d] / (phi * phi));
            }
        }
        (u, du)
    }
}

/// The Burgers kernel with the Cole–Hopf solution as Dirichlet data and reference.
#[derive(Clone, Debug)]
pub struct Burgers {
    pub exact: ColeHopf,
}

impl Kernel for Burgers {
    fn n_comp(&self) -> usize {
        2
    }
    fn exact(&self, x: [f64; 2], t: f64, comp: usize) -> (f64, [f64; 2]) {
        let (u, du) = self.exact.u_grad(x, t);
        (u[comp], du[comp])
    }
    fn cell(&self, d: &CellData, r: &mut [f64], k: &mut [f64]) {
        let nu = self.exact.nu;
        let (gx, gw) = gauss_legendre(d.p + 2);
        let h = d.h;
        let mut n = [0.0; MAX_SCALAR];
        let mut dn = [[0.0; 2]; MAX_SCALAR];
        let mut d2 = [[0.0; 3]; MAX_SCALAR];
        let idt = 1.0 / d.dt;
        let nl2 = d.u.len();
        for (i, &xi) in gx.iter().enumerate() {
            for (j, &eta) in gx.iter().enumerate() {
                let nl = basis_at(d.p, h, xi, eta, &mut n, &mut dn, &mut d2);
                let w = gw[i] * gw[j] * 0.25 * h * h;
                let (mut u, mut un) = ([0.0; 2], [0.0; 2]);
                let (mut gu, mut gun) = ([[0.0; 2]; 2], [[0.0; 2]; 2]);
                for a in 0..nl {
                    for c in 0..2 {
                        let (v, vn) = (d.u[2 * a + c], d.un[2 * a + c]);
                        u[c] += n[a] * v;
                        un[c] += n[a] * vn;
                        for e in 0..2 {
                            gu[c][e] += dn[a][e] * v;
                            gun[c][e] += dn[a][e] * vn;
                        }
                    }
                }
                for a in 0..nl {
                    for c in 0..2 {
                        let conv = u[0] * gu[c][0] + u[1] * gu[c][1];
                        let convn = un[0] * gun[c][0] + un[1] * gun[c][1];
                        let diff =
                            (gu[c][0] + gun[c][0]) * dn[a][0] + (gu[c][1] + gun[c][1]) * dn[a][1];
                        r[2 * a + c] += w
                            * (((u[c] - un[c]) * idt + 0.5 * (conv + convn)) * n[a]
                                + 0.5 * nu * diff);
                        let row = (2 * a + c) * nl2;
                        for b in 0..nl {
                            let ugb = u[0] * dn[b][0] + u[1] * dn[b][1];
                            let gab = dn[a][0] * dn[b][0] + dn[a][1] * dn[b][1];
                            for e in 0..2 {
                                let mut v = 0.5 * n[b] * gu[c][e] * n[a];
                                if e == c {
                                    v += n[b] * n[a] * idt + 0.5 * ugb * n[a] + 0.5 * nu * gab;
                                }
                                k[row + 2 * b + e] += w * v;
                            }
                        }
                    }
                }
            }
        }
    }
}
