#![allow(dead_code)]
//! Independent reference for the critical speeds of the spinning plane-strain annulus: the
//! steady (lab-stationary) operator restricted to one circumferential Fourier mode, a 1D
//! eigenproblem in the reference radius R, written without the library.
//!
//! About the axisymmetric spun state r(R) (from [`super::reference::radial_solution`], F0 =
//! diag(λ_r, λ_θ) in the polar bases), a perturbation of wave number n ≥ 1 (cos family)
//!
//! ```text
//! η = a(R) cos nΘ e_r + b(R) sin nΘ e_θ,    a(Ri) = b(Ri) = 0
//! ```
//!
//! has the gradient (rows: current polar components, columns: reference directions R, Θ)
//!
//! ```text
//! ∇η = cos nΘ [[a', 0], [0, (n b + a)/R]] + sin nΘ [[0, −(n a + b)/R], [b', 0]]
//! ```
//!
//! and ∂Θη = −(n a + b) sin nΘ e_r + (n b + a) cos nΘ e_θ. The second variation of
//! ∫ W(F) dV − ω²/2 ∫ ρ |∂Θχ|² dV (the steady problem without contact is variational),
//! integrated over Θ (the cos·sin terms drop, cos² and sin² give π), is
//!
//! ```text
//! Q_n(a, b) = π ∫ (C:A:C + S:A:S) R dR − ω² π ∫ ρ ((n a + b)² + (n b + a)²) R dR,
//! ```
//!
//! A = ∂²W/∂F∂F at F0 (computed exactly with hyper-dual numbers). a and b are discretised
//! with degree-p Lagrange elements on Gauss–Lobatto nodes (own 1D FE); the crossing speed of
//! mode n is the smallest ω where the smallest eigenvalue of the matrix of Q_n reaches zero
//! (dense symmetric eigenvalues, Illinois regula falsi in ω, the base state re-solved at every
//! ω).
//!
//! The material is the compressible Mooney–Rivlin law of plane strain,
//! W = c1 (J^(−2/3) I1 − 3) + c2 (J^(−4/3) I2 − 3) + κ/2 (J − 1)², I1 = |F|² + 1,
//! I2 = |F|² + J², written here from that formula.

use super::reference::{radial_solution_with_steps, RadialSolution};
use nalgebra::{DMatrix, SymmetricEigen};

/// Hyper-dual number a + b ε1 + c ε2 + d ε1ε2 (ε1² = ε2² = 0): exact first and second
/// derivatives.
#[derive(Clone, Copy, Debug)]
struct Hd {
    re: f64,
    e1: f64,
    e2: f64,
    e12: f64,
}

impl Hd {
    fn c(v: f64) -> Self {
        Hd {
            re: v,
            e1: 0.0,
            e2: 0.0,
            e12: 0.0,
        }
    }
    fn add(self, o: Hd) -> Hd {
        Hd {
            re: self.re + o.re,
            e1: self.e1 + o.e1,
            e2: self.e2 + o.e2,
            e12: self.e12 + o.e12,
        }
    }
    fn sub(self, o: Hd) -> Hd {
        Hd {
            re: self.re - o.re,
            e1: self.e1 - o.e1,
            e2: self.e2 - o.e2,
            e12: self.e12 - o.e12,
        }
    }
    fn mul(self, o: Hd) -> Hd {
        Hd {
            re: self.re * o.re,
            e1: self.re * o.e1 + self.e1 * o.re,
            e2: self.re * o.e2 + self.e2 * o.re,
            e12: self.re * o.e12 + self.e1 * o.e2 + self.e2 * o.e1 + self.e12 * o.re,
        }
    }
    fn scale(self, s: f64) -> Hd {
        Hd {
            re: self.re * s,
            e1: self.e1 * s,
            e2: self.e2 * s,
            e12: self.e12 * s,
        }
    }
    fn powf(self, p: f64) -> Hd {
        let f = self.re.powf(p);
        let f1 = p * self.re.powf(p - 1.0);
        let f2 = p * (p - 1.0) * self.re.powf(p - 2.0);
        Hd {
            re: f,
            e1: f1 * self.e1,
            e2: f1 * self.e2,
            e12: f1 * self.e12 + f2 * self.e1 * self.e2,
        }
    }
}

/// Compressible Mooney–Rivlin (plane strain).
#[derive(Clone, Copy, Debug)]
pub struct MooneyRivlinRef {
    pub c1: f64,
    pub c2: f64,
    pub kappa: f64,
}

impl MooneyRivlinRef {
    /// W at F = [[f00, f01], [f10, f11]].
    fn w(&self, f: [Hd; 4]) -> Hd {
        let ff = f[0]
            .mul(f[0])
            .add(f[1].mul(f[1]))
            .add(f[2].mul(f[2]))
            .add(f[3].mul(f[3]));
        let j = f[0].mul(f[3]).sub(f[1].mul(f[2]));
        let i1 = ff.add(Hd::c(1.0));
        let i2 = ff.add(j.mul(j));
        let jm1 = j.sub(Hd::c(1.0));
        j.powf(-2.0 / 3.0)
            .mul(i1)
            .scale(self.c1)
            .add(j.powf(-4.0 / 3.0).mul(i2).scale(self.c2))
            .add(jm1.mul(jm1).scale(0.5 * self.kappa))
            .sub(Hd::c(3.0 * (self.c1 + self.c2)))
    }

    /// ∂²W/∂F_a∂F_b at F (entries ordered 00, 01, 10, 11).
    pub fn hessian(&self, f: [f64; 4]) -> [[f64; 4]; 4] {
        let mut h = [[0.0; 4]; 4];
        for a in 0..4 {
            for b in a..4 {
                let mut x = [Hd::c(0.0); 4];
                for k in 0..4 {
                    x[k] = Hd::c(f[k]);
                }
                x[a].e1 = 1.0;
                x[b].e2 = 1.0;
                let v = self.w(x).e12;
                h[a][b] = v;
                h[b][a] = v;
            }
        }
        h
    }

    /// Principal PK1 stresses for the radial shooting: (P_R, P_T, dP_R/dl1, dP_R/dl2) at
    /// F = diag(l1, l2).
    pub fn principal(&self, l1: f64, l2: f64) -> (f64, f64, f64, f64) {
        let d = |a: usize, b: usize| {
            let mut x = [Hd::c(l1), Hd::c(0.0), Hd::c(0.0), Hd::c(l2)];
            x[a].e1 = 1.0;
            x[b].e2 = 1.0;
            self.w(x)
        };
        let w00 = d(0, 0);
        let w03 = d(0, 3);
        let w33 = d(3, 3);
        (w00.e1, w33.e1, w00.e12, w03.e12)
    }
}

/// Gauss–Legendre points and weights on [-1, 1] (Newton on P_n).
fn gauss(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    for i in 0..n {
        let mut z = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, z);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * z * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let (pn, pn1) = if n == 1 { (z, 1.0) } else { (p1, p0) };
            let dp = n as f64 * (z * pn - pn1) / (z * z - 1.0);
            let dz = pn / dp;
            z -= dz;
            if dz.abs() < 1e-15 {
                break;
            }
        }
        let (mut p0, mut p1) = (1.0, z);
        for k in 2..=n {
            let p2 = ((2 * k - 1) as f64 * z * p1 - (k - 1) as f64 * p0) / k as f64;
            p0 = p1;
            p1 = p2;
        }
        let dp = n as f64 * (z * p1 - p0) / (z * z - 1.0);
        x[i] = z;
        w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
    }
    (x, w)
}

/// Lagrange basis on equispaced-in-cosine (Chebyshev–Lobatto) nodes of degree p: values and
/// derivatives at ξ.
fn lagrange(p: usize, xi: f64) -> (Vec<f64>, Vec<f64>) {
    let nodes: Vec<f64> = (0..=p)
        .map(|k| -(std::f64::consts::PI * k as f64 / p as f64).cos())
        .collect();
    let mut n = vec![0.0; p + 1];
    let mut dn = vec![0.0; p + 1];
    for i in 0..=p {
        let mut v = 1.0;
        for j in 0..=p {
            if j != i {
                v *= (xi - nodes[j]) / (nodes[i] - nodes[j]);
            }
        }
        n[i] = v;
        let mut d = 0.0;
        for k in 0..=p {
            if k == i {
                continue;
            }
            let mut t = 1.0 / (nodes[i] - nodes[k]);
            for j in 0..=p {
                if j != i && j != k {
                    t *= (xi - nodes[j]) / (nodes[i] - nodes[j]);
                }
            }
            d += t;
        }
        dn[i] = d;
    }
    (n, dn)
}

/// The 1D Fourier-mode problem of the spinning annulus.
#[derive(Clone, Debug)]
pub struct FourierModes {
    pub ri: f64,
    pub ro: f64,
    pub rho: f64,
    pub mat: MooneyRivlinRef,
    /// Elements and their degree.
    pub n_el: usize,
    pub p: usize,
}

impl FourierModes {
    /// Matrix of Q_n (without the factor π) at speed ω; unknowns (a, b) at the nodes except
    /// the hub node. Elements graded toward Ro (surface waves live there).
    pub fn matrix(&self, base: &RadialSolution, n: usize, omega: f64) -> DMatrix<f64> {
        let p = self.p;
        let nn = self.n_el * p; // nodes without the hub node
        let mut k = DMatrix::<f64>::zeros(2 * nn, 2 * nn);
        let (gx, gw) = gauss(p + 3);
        let nf = n as f64;
        let w2 = omega * omega;
        // Radial breaks: geometric, outermost element 1/3 the size of the innermost.
        let q = if self.n_el > 1 {
            (1.0f64 / 3.0).powf(1.0 / (self.n_el as f64 - 1.0))
        } else {
            1.0
        };
        let sizes: Vec<f64> = (0..self.n_el).map(|e| q.powi(e as i32)).collect();
        let tot: f64 = sizes.iter().sum();
        let mut r0 = self.ri;
        for (e, &size) in sizes.iter().enumerate() {
            let h = size / tot * (self.ro - self.ri);
            for (&xi, &wq) in gx.iter().zip(&gw) {
                let rr = r0 + 0.5 * (xi + 1.0) * h;
                let jw = 0.5 * h * wq * rr;
                let (l1, l2) = base.stretches(rr);
                let a = self.mat.hessian([l1, 0.0, 0.0, l2]);
                let (nv, dn) = lagrange(p, xi);
                // For each local basis function and unknown (a or b): the entries of C and S
                // (ordered 00, 01, 10, 11) and the two B components.
                let mut cs = Vec::with_capacity(2 * (p + 1));
                for i in 0..=p {
                    let (phi, dphi) = (nv[i], dn[i] * 2.0 / h);
                    // a-basis: C = [[a',0],[0,a/R]], S = [[0,-n a/R],[0,0]], B: (n a, a)
                    cs.push((
                        [dphi, 0.0, 0.0, phi / rr],
                        [0.0, -nf * phi / rr, 0.0, 0.0],
                        [nf * phi, phi],
                    ));
                    // b-basis: C = [[0,0],[0,n b/R]], S = [[0,-b/R],[b',0]], B: (b, n b)
                    cs.push((
                        [0.0, 0.0, 0.0, nf * phi / rr],
                        [0.0, -phi / rr, dphi, 0.0],
                        [phi, nf * phi],
                    ));
                }
                let glob = |loc: usize| -> Option<usize> {
                    let (i, comp) = (loc / 2, loc % 2);
                    let node = e * p + i; // 0 = hub node
                    if node == 0 {
                        None
                    } else {
                        Some(2 * (node - 1) + comp)
                    }
                };
                for (li, (ci, si, bi)) in cs.iter().enumerate() {
                    let Some(gi) = glob(li) else { continue };
                    for (lj, (cj, sj, bj)) in cs.iter().enumerate() {
                        let Some(gj) = glob(lj) else { continue };
                        let mut v = 0.0;
                        for s in 0..4 {
                            for t in 0..4 {
                                v += a[s][t] * (ci[s] * cj[t] + si[s] * sj[t]);
                            }
                        }
                        v -= w2 * self.rho * (bi[0] * bj[0] + bi[1] * bj[1]);
                        k[(gi, gj)] += v * jw;
                    }
                }
            }
            r0 += h;
        }
        k
    }

    /// Smallest eigenvalue of the mode-n matrix at ω divided by its largest |eigenvalue|.
    pub fn lambda_min(&self, n: usize, omega: f64) -> Result<f64, String> {
        // 4000 RK4 steps: the shooting's truncation error is far below the eigenvalue tolerance.
        let base =
            radial_solution_with_steps(self.ri, self.ro, self.rho, omega, 4000, |l1, l2| {
                self.mat.principal(l1, l2)
            })?;
        let e = SymmetricEigen::new(self.matrix(&base, n, omega)).eigenvalues;
        let lmin = e.iter().cloned().fold(f64::INFINITY, f64::min);
        let lmax = e.iter().map(|v| v.abs()).fold(0.0, f64::max);
        Ok(lmin / lmax)
    }

    /// First crossing speed of mode n in (omega_lo, omega_max] (λ_min must be positive at
    /// omega_lo), scanning with `samples` intervals and refining by Illinois regula falsi to
    /// 1e-10 relative.
    pub fn crossing(
        &self,
        n: usize,
        omega_lo: f64,
        omega_max: f64,
        samples: usize,
    ) -> Result<Option<f64>, String> {
        let mut a = omega_lo;
        let mut fa = self.lambda_min(n, a)?;
        if fa <= 0.0 {
            return Err(format!("mode {n} is already unstable at {omega_lo} rad/s"));
        }
        for k in 1..=samples {
            let b0 = omega_lo + (omega_max - omega_lo) * k as f64 / samples as f64;
            let fb0 = self.lambda_min(n, b0)?;
            if fb0 > 0.0 {
                a = b0;
                fa = fb0;
                continue;
            }
            let (mut b, mut fb) = (b0, fb0);
            let mut side = 0;
            for _ in 0..100 {
                if (b - a) <= 1e-10 * b {
                    break;
                }
                let c = (a * fb - b * fa) / (fb - fa);
                let c = if c > a && c < b { c } else { 0.5 * (a + b) };
                let fc = self.lambda_min(n, c)?;
                if fc > 0.0 {
                    a = c;
                    fa = fc;
                    if side == 1 {
                        fb *= 0.5;
                    }
                    side = 1;
                } else {
                    b = c;
                    fb = fc;
                    if side == -1 {
                        fa *= 0.5;
                    }
                    side = -1;
                }
                if fc.abs() < 1e-14 {
                    break;
                }
            }
            return Ok(Some(if fa.abs() < fb.abs() { a } else { b }));
        }
        Ok(None)
    }
}
