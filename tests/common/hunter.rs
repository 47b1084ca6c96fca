//! Independent reference: steady rolling of a rigid cylinder on a viscoelastic half-space
//! (Hunter, J. Appl. Mech. 28, 1961), plane strain, incompressible, frictionless, with a standard
//! linear solid in shear, G(t) = G∞ + G1 exp(−t/τ). Computed here from the integral equation,
//! with no code of the finite-element program.
//!
//! # Equations
//!
//! Surface of an incompressible elastic half-space under a pressure p(x) (plane strain): the slope
//! of the surface displacement is `w'(x) = (1/2πG) h(x)`, `h(x) = PV ∫ p(s)/(x − s) ds`. By the
//! correspondence principle, with the shear creep compliance
//! `J(t) = J∞ − (J∞ − J0) exp(−t/τc)`, `J0 = 1/(G∞ + G1)`, `J∞ = 1/G∞`,
//! `τc = τ (G∞ + G1)/G∞`, and the material moving with speed V in +x past a steady pressure
//! (a point now at x was at x − V s a time s ago):
//!
//! ```text
//! 2π w'(x) = J0 h(x) + ∫_0^∞ J'(s) h(x − V s) ds  =  2π x / R   inside the contact,
//! ```
//!
//! the slope of the rigid cylinder of radius R whose lowest point is at x = 0. Contact
//! [c − L, c + L], t = (x − c)/L, and the bounded (smooth-edge) pressure
//! `p = Σ_{k=1}^N a_k √(1 − t²) U_{k−1}(t)`, whose Hilbert transform is
//! `h = π Σ a_k F_k(t)`, `F_k = T_k(t)` for |t| ≤ 1 and `(t − sgn t √(t² − 1))^k` outside.
//! With `λ = V τc / L` the memory term is
//! `ΔJ Σ a_k π ∫_0^∞ e^{−ζ/λ}/λ F_k(t − ζ) dζ`, integrated numerically (composite Gauss–Legendre;
//! outside the contact with t − ζ = −cosh θ, where F_k = (−1)^k e^{−kθ}).
//! For a given L the collocation at N + 1 Chebyshev points is linear in (a_1..a_N, c); the load
//! `P = ∫ p dx = π L a_1 / 2` then fixes L (secant iteration on ln L).
//!
//! Outputs: the contact edges, the pressure, and the rolling resistance
//! `μ_r = ∫ p x dx / (P R) = (c P + π L² a_2 / 4) / (P R)` (the horizontal force on the cylinder
//! over the load, equal to the moment of the pressure about the axis over P R). Its sign is
//! negative here (the pressure shifts upstream, towards the side where material enters, x < 0):
//! the resistance opposes the motion.
//!
//! Elastic limits (V → 0: J∞; V → ∞: J0): Hertz, `L² = P R J / π`, `p0 = 2L/(R J)`, c = 0.

use nalgebra::{DMatrix, DVector};

/// A standard linear solid and the rolling problem.
#[derive(Clone, Copy, Debug)]
pub struct HunterProblem {
    /// Relaxed shear modulus G∞.
    pub g_inf: f64,
    /// Relaxing part G1 (instantaneous modulus G∞ + G1).
    pub g1: f64,
    /// Relaxation time τ (at constant strain).
    pub tau: f64,
    /// Cylinder radius.
    pub radius: f64,
    /// Load per unit thickness.
    pub load: f64,
}

/// The steady contact at one speed.
#[derive(Clone, Debug)]
pub struct HunterSolution {
    /// Contact centre c and half-width L.
    pub centre: f64,
    pub half_width: f64,
    /// Pressure coefficients a_k (k = 1..N).
    pub coeffs: Vec<f64>,
    /// Rolling resistance ∫ p x dx / (P R) (negative: opposes the motion).
    pub resistance: f64,
}

impl HunterSolution {
    /// Upstream (x < 0, where material enters) and downstream contact edges.
    pub fn edges(&self) -> (f64, f64) {
        (self.centre - self.half_width, self.centre + self.half_width)
    }

    /// Contact pressure at x.
    pub fn pressure(&self, x: f64) -> f64 {
        let t = (x - self.centre) / self.half_width;
        if t.abs() >= 1.0 {
            return 0.0;
        }
        let w = (1.0 - t * t).sqrt();
        let mut p = 0.0;
        // U_{k-1} by the recurrence U_{n+1} = 2t U_n − U_{n−1}.
        let (mut u_prev, mut u) = (0.0, 1.0);
        for a in &self.coeffs {
            p += a * w * u;
            let next = 2.0 * t * u - u_prev;
            u_prev = u;
            u = next;
        }
        p
    }
}

/// Gauss–Legendre nodes and weights on [−1, 1] (Newton on the Legendre recurrence).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
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
            let dp = n as f64 * (z * p1 - p0) / (z * z - 1.0);
            let dz = p1 / dp;
            z -= dz;
            if dz.abs() < 1e-16 {
                let dp = {
                    let (mut q0, mut q1) = (1.0, z);
                    for k in 2..=n {
                        let q2 = ((2 * k - 1) as f64 * z * q1 - (k - 1) as f64 * q0) / k as f64;
                        q0 = q1;
                        q1 = q2;
                    }
                    n as f64 * (z * q1 - q0) / (z * z - 1.0)
                };
                x[i] = z;
                w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
                break;
            }
        }
    }
    (x, w)
}

/// Composite Gauss–Legendre of `f` on [a, b] with `panels` panels of the given rule.
fn composite(
    f: impl Fn(f64) -> f64,
    a: f64,
    b: f64,
    panels: usize,
    rule: &(Vec<f64>, Vec<f64>),
) -> f64 {
    let hp = (b - a) / panels as f64;
    let mut s = 0.0;
    for p in 0..panels {
        let (lo, hi) = (a + p as f64 * hp, a + (p + 1) as f64 * hp);
        let (m, r) = (0.5 * (lo + hi), 0.5 * (hi - lo));
        for (x, w) in rule.0.iter().zip(&rule.1) {
            s += w * r * f(m + r * x);
        }
    }
    s
}

/// Chebyshev T_0..T_n at t (|t| ≤ 1 or any t: the recurrence is a polynomial).
fn cheb_t(t: f64, n: usize, out: &mut [f64]) {
    out[0] = 1.0;
    if n >= 1 {
        out[1] = t;
    }
    for k in 2..=n {
        out[k] = 2.0 * t * out[k - 1] - out[k - 2];
    }
}

impl HunterProblem {
    pub fn j0(&self) -> f64 {
        1.0 / (self.g_inf + self.g1)
    }
    pub fn j_inf(&self) -> f64 {
        1.0 / self.g_inf
    }
    /// Retardation (creep) time τc = τ (G∞ + G1)/G∞.
    pub fn tau_c(&self) -> f64 {
        self.tau * (self.g_inf + self.g1) / self.g_inf
    }

    /// Hertz half-width and peak pressure for the compliance `j`.
    pub fn hertz(&self, j: f64) -> (f64, f64) {
        let a = (self.load * self.radius * j / std::f64::consts::PI).sqrt();
        (a, 2.0 * a / (self.radius * j))
    }

    /// Memory integrals M_k(t) = ∫_0^∞ e^{−ζ/λ}/λ F_k(t − ζ) dζ, k = 1..n, at t ∈ [−1, 1].
    fn memory(t: f64, lambda: f64, n: usize, rule: &(Vec<f64>, Vec<f64>), out: &mut [f64]) {
        let mut tk = vec![0.0; n + 1];
        out[..n].iter_mut().for_each(|v| *v = 0.0);
        // Inside: ζ ∈ [0, t + 1], F_k = T_k(t − ζ). Panels no wider than λ/2 (the kernel's scale)
        // and 0.1 (the polynomials' scale), at most up to 40 λ (the kernel is then e^{-40}).
        let len = (t + 1.0).min(40.0 * lambda);
        if len > 0.0 {
            let panels = ((len / (0.5 * lambda).min(0.1)).ceil() as usize).clamp(1, 4000);
            let hp = len / panels as f64;
            for p in 0..panels {
                let (lo, hi) = (p as f64 * hp, (p + 1) as f64 * hp);
                let (m, r) = (0.5 * (lo + hi), 0.5 * (hi - lo));
                for (x, w) in rule.0.iter().zip(&rule.1) {
                    let z = m + r * x;
                    let kern = (-z / lambda).exp() / lambda * w * r;
                    cheb_t(t - z, n, &mut tk);
                    for k in 1..=n {
                        out[k - 1] += kern * tk[k];
                    }
                }
            }
        }
        // Outside: ζ = t + cosh θ, F_k = (−1)^k e^{−kθ}, dζ = sinh θ dθ.
        let start = (t + 1.0) / lambda;
        if start < 700.0 {
            let theta_max = (1.0 + 50.0 * lambda).acosh().max(1e-3);
            let panels = ((theta_max / 0.25).ceil() as usize).clamp(4, 400);
            for k in 1..=n {
                let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
                out[k - 1] += sign
                    * composite(
                        |th: f64| {
                            (-(t + th.cosh()) / lambda).exp() / lambda
                                * (-(k as f64) * th).exp()
                                * th.sinh()
                        },
                        0.0,
                        theta_max,
                        panels,
                        rule,
                    );
            }
        }
    }

    /// For a given half-width L at speed V: solve the collocation for (a, c). Returns the
    /// coefficients and the centre.
    fn solve_linear(&self, v: f64, l: f64, n: usize) -> Option<(Vec<f64>, f64)> {
        let rule = gauss_legendre(16);
        let m = n + 1;
        let lambda = v * self.tau_c() / l;
        let dj = self.j_inf() - self.j0();
        let mut a = DMatrix::zeros(m, m);
        let mut b = DVector::zeros(m);
        let mut tk = vec![0.0; n + 1];
        let mut mem = vec![0.0; n];
        for j in 0..m {
            let t = ((2 * j + 1) as f64 * std::f64::consts::PI / (2 * m) as f64).cos();
            cheb_t(t, n, &mut tk);
            if v > 0.0 && lambda.is_finite() {
                Self::memory(t, lambda, n, &rule, &mut mem);
            } else {
                mem.fill(0.0);
            }
            for k in 1..=n {
                // (1/2) [J0 T_k + ΔJ M_k] a_k; at V = 0 the memory has fully acted: J∞ T_k.
                let coef = if v == 0.0 {
                    0.5 * self.j_inf() * tk[k]
                } else {
                    0.5 * (self.j0() * tk[k] + dj * mem[k - 1])
                };
                a[(j, k - 1)] = coef;
            }
            a[(j, n)] = -1.0 / self.radius;
            b[j] = l * t / self.radius;
        }
        let x = a.lu().solve(&b)?;
        Some(((0..n).map(|k| x[k]).collect(), x[n]))
    }

    /// The steady contact at rolling speed `v` (V = 0: relaxed; `f64::INFINITY`: glassy) with
    /// `n` Chebyshev terms.
    pub fn solve(&self, v: f64, n: usize) -> Option<HunterSolution> {
        let (v_eff, j_eff) = if v.is_infinite() {
            (0.0, self.j0())
        } else {
            (v, self.j_inf())
        };
        let this = if v.is_infinite() {
            // Glassy limit: the same equations with J∞ replaced by J0.
            HunterProblem {
                g_inf: self.g_inf + self.g1,
                g1: 0.0,
                ..*self
            }
        } else {
            *self
        };
        // Load residual in ln L: π L a_1 / 2 − P.
        let resid = |ln_l: f64| -> Option<f64> {
            let l = ln_l.exp();
            let (a, _) = this.solve_linear(v_eff, l, n)?;
            Some(std::f64::consts::PI * l * a[0] / 2.0 / self.load - 1.0)
        };
        let (a_h, _) = self.hertz(j_eff);
        let (a_g, _) = self.hertz(self.j0());
        let mut x0 = a_h.ln();
        let mut x1 = (0.5 * (a_h + a_g)).ln() + 1e-3;
        let mut f0 = resid(x0)?;
        let mut f1 = resid(x1)?;
        for _ in 0..60 {
            if f1.abs() < 1e-13 {
                break;
            }
            let x2 = x1 - f1 * (x1 - x0) / (f1 - f0);
            x0 = x1;
            f0 = f1;
            x1 = x2;
            f1 = resid(x1)?;
        }
        if f1.abs() > 1e-10 {
            return None;
        }
        let l = x1.exp();
        let (coeffs, centre) = this.solve_linear(v_eff, l, n)?;
        let a2 = coeffs.get(1).copied().unwrap_or(0.0);
        let moment = centre * self.load + std::f64::consts::PI * l * l * a2 / 4.0;
        Some(HunterSolution {
            centre,
            half_width: l,
            coeffs,
            resistance: moment / (self.load * self.radius),
        })
    }
}
