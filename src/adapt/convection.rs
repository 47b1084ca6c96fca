//! Transient convection–diffusion u_t + b·∇u − κΔu = f in Ω, u = g on ∂Ω, on the quadtree
//! Lagrange spaces (Q1, Q2), Crank–Nicolson in time, SUPG stabilisation, solved and adapted by
//! [`super::two_grid`].
//!
//! Crank–Nicolson with SUPG: with the strong residual
//! R(v, s) = b(s)·∇v − κΔv − f(s) (Δ of the discrete function taken cell by cell) and
//! δu = (u^{n+1} − u^n)/Δt, the cell residual for the test function φ_a is
//!
//! ∫_K [δu + ½(b·∇u^{n+1} − f^{n+1}) + ½(b·∇u^n − f^n)] φ_a + ½κ∇(u^{n+1} + u^n)·∇φ_a
//!   + τ_K [δu + ½R(u^{n+1}, t_{n+1}) + ½R(u^n, t_n)] b·∇φ_a,
//!
//! (b is steady and f = 0 for the problem implemented here). The method is consistent (the exact solution
//! makes the stabilised residual vanish), so it keeps the Galerkin orders. The parameter is the
//! classical one for degree p at the cell centre: with h_p = h/p and the cell Péclet number
//! Pe = |b| h_p / (2κ), τ_K = h_p / (2|b|) (coth Pe − 1/Pe) (τ_K = 0 for b = 0;
//! [`ConvectionDiffusion::supg`] = false gives plain Galerkin).
//!
//! The problem with a closed-form solution ([`RotatingHill`]) is a Gaussian hill carried by the
//! rigid rotation b = (−y, x) with f = 0: because Δ commutes with rotations and the heat kernel
//! spreads a Gaussian exactly,
//!
//! u(x, t) = σ² / (σ² + 4κt) · exp(−|R(−t)x − c₀|² / (σ² + 4κt)),
//!
//! with R(−t) the rotation by −t about the origin and c₀ the initial centre.

use super::two_grid::{basis_at, CellData, Kernel, MAX_SCALAR};
use crate::element::hierarchical::gauss_legendre;

/// The rotating, spreading Gaussian hill with b = (−y, x).
#[derive(Clone, Copy, Debug)]
pub struct RotatingHill {
    pub kappa: f64,
    /// Initial variance-like width σ² (u₀ = exp(−|x − c₀|²/σ²)).
    pub sigma2: f64,
    pub centre: [f64; 2],
}

impl Default for RotatingHill {
    fn default() -> Self {
        Self {
            kappa: 1e-3,
            sigma2: 0.01,
            centre: [0.5, 0.0],
        }
    }
}

impl RotatingHill {
    pub fn u_grad(&self, x: [f64; 2], t: f64) -> (f64, [f64; 2]) {
        let s2 = self.sigma2 + 4.0 * self.kappa * t;
        let (c, s) = (t.cos(), t.sin());
        // Centre at time t: R(t) c₀.
        let xc = [
            c * self.centre[0] - s * self.centre[1],
            s * self.centre[0] + c * self.centre[1],
        ];
        let d = [x[0] - xc[0], x[1] - xc[1]];
        let u = self.sigma2 / s2 * (-(d[0] * d[0] + d[1] * d[1]) / s2).exp();
        (u, [-2.0 * d[0] / s2 * u, -2.0 * d[1] / s2 * u])
    }
}

/// The convection–diffusion kernel for a problem with velocity b(x) (steady), diffusivity κ,
/// f = 0 and the exact solution of [`RotatingHill`].
#[derive(Clone, Copy, Debug)]
pub struct ConvectionDiffusion {
    pub hill: RotatingHill,
    /// SUPG on (true) or plain Galerkin.
    pub supg: bool,
}

impl ConvectionDiffusion {
    pub fn new(hill: RotatingHill) -> Self {
        Self { hill, supg: true }
    }

    #[inline]
    fn velocity(x: [f64; 2]) -> [f64; 2] {
        [-x[1], x[0]]
    }

    /// The SUPG parameter of a cell of side h, degree p, centre xc.
    pub fn tau(&self, xc: [f64; 2], h: f64, p: usize) -> f64 {
        if !self.supg {
            return 0.0;
        }
        let b = Self::velocity(xc);
        let bn = b[0].hypot(b[1]);
        if bn < 1e-14 {
            return 0.0;
        }
        let hp = h / p as f64;
        let pe = bn * hp / (2.0 * self.hill.kappa);
        let xi = if pe > 20.0 {
            1.0 - 1.0 / pe
        } else if pe < 1e-6 {
            pe / 3.0
        } else {
            1.0 / pe.tanh() - 1.0 / pe
        };
        hp / (2.0 * bn) * xi
    }
}

impl Kernel for ConvectionDiffusion {
    fn n_comp(&self) -> usize {
        1
    }
    fn exact(&self, x: [f64; 2], t: f64, _comp: usize) -> (f64, [f64; 2]) {
        self.hill.u_grad(x, t)
    }
    fn cell(&self, d: &CellData, r: &mut [f64], k: &mut [f64]) {
        let kappa = self.hill.kappa;
        let (gx, gw) = gauss_legendre(d.p + 2);
        let h = d.h;
        let tau = self.tau([d.x0[0] + 0.5 * h, d.x0[1] + 0.5 * h], h, d.p);
        let mut n = [0.0; MAX_SCALAR];
        let mut dn = [[0.0; 2]; MAX_SCALAR];
        let mut d2 = [[0.0; 3]; MAX_SCALAR];
        let idt = 1.0 / d.dt;
        for (i, &xi) in gx.iter().enumerate() {
            for (j, &eta) in gx.iter().enumerate() {
                let nl = basis_at(d.p, h, xi, eta, &mut n, &mut dn, &mut d2);
                let w = gw[i] * gw[j] * 0.25 * h * h;
                let x = [
                    d.x0[0] + 0.5 * h * (xi + 1.0),
                    d.x0[1] + 0.5 * h * (eta + 1.0),
                ];
                let b = Self::velocity(x);
                let (mut u, mut un, mut gu, mut gun, mut lu, mut lun) =
                    (0.0, 0.0, [0.0; 2], [0.0; 2], 0.0, 0.0);
                for a in 0..nl {
                    u += n[a] * d.u[a];
                    un += n[a] * d.un[a];
                    for c in 0..2 {
                        gu[c] += dn[a][c] * d.u[a];
                        gun[c] += dn[a][c] * d.un[a];
                    }
                    lu += (d2[a][0] + d2[a][2]) * d.u[a];
                    lun += (d2[a][0] + d2[a][2]) * d.un[a];
                }
                let bgu = b[0] * gu[0] + b[1] * gu[1];
                let bgun = b[0] * gun[0] + b[1] * gun[1];
                let galerkin = (u - un) * idt + 0.5 * (bgu + bgun);
                let strong = galerkin - 0.5 * kappa * (lu + lun);
                for a in 0..nl {
                    let bga = b[0] * dn[a][0] + b[1] * dn[a][1];
                    let diff =
                        0.5 * kappa * ((gu[0] + gun[0]) * dn[a][0] + (gu[1] + gun[1]) * dn[a][1]);
                    r[a] += w * (galerkin * n[a] + diff + tau * strong * bga);
                    for bb in 0..nl {
                        let bgb = b[0] * dn[bb][0] + b[1] * dn[bb][1];
                        let gal_b = n[bb] * idt + 0.5 * bgb;
                        let str_b = gal_b - 0.5 * kappa * (d2[bb][0] + d2[bb][2]);
                        let diff_b = 0.5 * kappa * (dn[bb][0] * dn[a][0] + dn[bb][1] * dn[a][1]);
                        k[a * nl + bb] += w * (gal_b * n[a] + diff_b + tau * str_b * bga);
                    }
                }
            }
        }
    }
}
