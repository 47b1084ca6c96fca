#![allow(dead_code)]
//! Independent reference solutions for the spinning plane-strain annulus.
//!
//! Problem: a hollow cylinder with reference radii `Ri <= R <= Ro`, in plane
//! strain, spins about its axis at angular speed `omega` (rad/s).  The inner
//! rim is bonded to a rigid hub (radial displacement zero at `R = Ri`), the
//! outer surface is traction free.  The deformation is axisymmetric: the
//! material point at reference radius `R` moves to current radius `r(R)`.
//! The steady centrifugal body force per unit *reference* volume is
//! `rho * omega^2 * r` (outward), `rho` being the reference density.
//!
//! Three reference solutions are provided, all in plain `std` Rust `f64`:
//!
//! 1. [`linear_annulus`]: closed-form small-strain (linear elastic) solution.
//! 2. [`neo_hookean_radial`] / [`radial_solution`]: the exact finite-strain
//!    axisymmetric solution of a compressible hyperelastic material, obtained
//!    by high-accuracy shooting on the radial ODE (relative accuracy ~1e-10 or
//!    better in `r(R)` and the stresses at moderate strains).
//! 3. [`incompressible_sigma_r`] / [`incompressible_sigma_theta`]: the exact
//!    solution for an incompressible material (no radial motion at all).
//!
//! None of the library functions panic; failures are reported with `Result`.

// ---------------------------------------------------------------------------
// 1. Linear plane-strain rotating annulus
// ---------------------------------------------------------------------------

/// Closed-form linear-elastic (small strain) plane-strain rotating annulus
/// with `u(Ri) = 0` and `sigma_r(Ro) = 0`.
///
/// Derivation.  With the radial displacement `u(r)` the strains are
/// `eps_r = u'`, `eps_theta = u / r`, `eps_z = 0`, and Hooke's law in plane
/// strain gives
///
/// ```text
///   sigma_r     = (lambda + 2 mu) u' + lambda u / r
///   sigma_theta = lambda u' + (lambda + 2 mu) u / r
///   sigma_z     = lambda (u' + u / r)
/// ```
///
/// Radial equilibrium with the centrifugal load evaluated at the reference
/// radius (linear theory), `d sigma_r/dr + (sigma_r - sigma_theta)/r
/// + rho omega^2 r = 0`, becomes, with `M = lambda + 2 mu`,
///
/// ```text
///   M (u'' + u'/r - u/r^2) = M d/dr[ (1/r) d(r u)/dr ] = -rho omega^2 r .
/// ```
///
/// Integrating twice: `(1/r)(r u)' = 2A - rho omega^2 r^2 / (2M)`, hence
///
/// ```text
///   u(r) = A r + B / r - k r^3,          k = rho omega^2 / (8 M),
///   u'(r) = A - B / r^2 - 3 k r^2,
///   sigma_r(r) = 2(lambda + mu) A - 2 mu B / r^2 - (4 lambda + 6 mu) k r^2.
/// ```
///
/// Boundary conditions:
///
/// ```text
///   u(Ri) = 0        =>  B = Ri^2 (k Ri^2 - A)
///   sigma_r(Ro) = 0  =>  A [2(lambda+mu) + 2 mu Ri^2/Ro^2]
///                          = (4 lambda + 6 mu) k Ro^2 + 2 mu k Ri^4 / Ro^2 .
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearAnnulus {
    pub ri: f64,
    pub ro: f64,
    pub lambda: f64,
    pub mu: f64,
    pub rho: f64,
    pub omega: f64,
    /// Coefficient of `r` in `u(r)`.
    pub a: f64,
    /// Coefficient of `1/r` in `u(r)`.
    pub b: f64,
    /// `k = rho omega^2 / (8 (lambda + 2 mu))`, coefficient of `-r^3`.
    pub k: f64,
}

/// Build the closed-form linear solution (see [`LinearAnnulus`] for the
/// derivation).  Requires `0 < ri < ro`, `lambda + mu > 0`, `mu > 0` for a
/// meaningful result (otherwise the coefficients may be non-finite; no panic).
pub fn linear_annulus(
    ri: f64,
    ro: f64,
    lambda: f64,
    mu: f64,
    rho: f64,
    omega: f64,
) -> LinearAnnulus {
    let m = lambda + 2.0 * mu;
    let k = rho * omega * omega / (8.0 * m);
    let q = ri * ri / (ro * ro);
    let a = ((4.0 * lambda + 6.0 * mu) * k * ro * ro + 2.0 * mu * k * ri * ri * q)
        / (2.0 * (lambda + mu) + 2.0 * mu * q);
    let b = ri * ri * (k * ri * ri - a);
    LinearAnnulus {
        ri,
        ro,
        lambda,
        mu,
        rho,
        omega,
        a,
        b,
        k,
    }
}

impl LinearAnnulus {
    /// Radial displacement `u(r) = A r + B/r - k r^3`.
    pub fn u(&self, r: f64) -> f64 {
        self.a * r + self.b / r - self.k * r * r * r
    }
    /// `du/dr = A - B/r^2 - 3 k r^2` (= radial strain `eps_r`).
    pub fn du_dr(&self, r: f64) -> f64 {
        self.a - self.b / (r * r) - 3.0 * self.k * r * r
    }
    /// Radial strain `eps_r = u'`.
    pub fn eps_r(&self, r: f64) -> f64 {
        self.du_dr(r)
    }
    /// Hoop strain `eps_theta = u / r`.
    pub fn eps_theta(&self, r: f64) -> f64 {
        self.u(r) / r
    }
    /// `sigma_r = (lambda + 2 mu) u' + lambda u / r`.
    pub fn sigma_r(&self, r: f64) -> f64 {
        (self.lambda + 2.0 * self.mu) * self.eps_r(r) + self.lambda * self.eps_theta(r)
    }
    /// `sigma_theta = lambda u' + (lambda + 2 mu) u / r`.
    pub fn sigma_theta(&self, r: f64) -> f64 {
        self.lambda * self.eps_r(r) + (self.lambda + 2.0 * self.mu) * self.eps_theta(r)
    }
    /// Out-of-plane stress `sigma_z = lambda (eps_r + eps_theta)` (plane strain).
    pub fn sigma_z(&self, r: f64) -> f64 {
        self.lambda * (self.eps_r(r) + self.eps_theta(r))
    }
}

// ---------------------------------------------------------------------------
// 2. Finite-strain radial solution (generic hyperelastic, neo-Hookean)
// ---------------------------------------------------------------------------

/// Default number of RK4 steps used by [`radial_solution`] and
/// [`neo_hookean_radial`].  Step halving changes the results by far less than
/// 1e-11 relative (see the self-tests).
pub const DEFAULT_RADIAL_STEPS: usize = 20_000;

/// Principal first Piola–Kirchhoff stresses of the compressible neo-Hookean
/// material
///
/// ```text
///   W = mu/2 (l1^2 + l2^2 + 1 - 3) - mu ln J + lambda/2 (ln J)^2,  J = l1 l2,
/// ```
///
/// in plane strain (`F = diag(l1, l2, 1)` in polar components,
/// `l1 = dr/dR`, `l2 = r/R`).  Returns `(P_R, P_T, dP_R/dl1, dP_R/dl2)`:
///
/// ```text
///   P_R = dW/dl1 = mu (l1 - 1/l1) + lambda ln J / l1
///   P_T = dW/dl2 = mu (l2 - 1/l2) + lambda ln J / l2
///   dP_R/dl1 = mu (1 + 1/l1^2) + lambda (1 - ln J) / l1^2
///   dP_R/dl2 = lambda / (l1 l2)
/// ```
pub fn neo_hookean_principal_pk1(lambda: f64, mu: f64, l1: f64, l2: f64) -> (f64, f64, f64, f64) {
    let lnj = (l1 * l2).ln();
    let pr = mu * (l1 - 1.0 / l1) + lambda * lnj / l1;
    let pt = mu * (l2 - 1.0 / l2) + lambda * lnj / l2;
    let dpr1 = mu * (1.0 + 1.0 / (l1 * l1)) + lambda * (1.0 - lnj) / (l1 * l1);
    let dpr2 = lambda / (l1 * l2);
    (pr, pt, dpr1, dpr2)
}

/// Plane-strain neo-Hookean strain energy `W(l1, l2)` (for checking the
/// stress derivatives).
pub fn neo_hookean_energy(lambda: f64, mu: f64, l1: f64, l2: f64) -> f64 {
    let lnj = (l1 * l2).ln();
    0.5 * mu * (l1 * l1 + l2 * l2 + 1.0 - 3.0) - mu * lnj + 0.5 * lambda * lnj * lnj
}

/// Out-of-plane Cauchy stress of the plane-strain neo-Hookean material:
/// `P_zz = dW/dl3 |_{l3=1} = lambda ln J`, so `sigma_z = lambda ln J / J`.
pub fn neo_hookean_sigma_z(lambda: f64, l1: f64, l2: f64) -> f64 {
    let j = l1 * l2;
    lambda * j.ln() / j
}

/// Dense, high-accuracy finite-strain axisymmetric solution `r(R)` on
/// `[Ri, Ro]`, produced by [`radial_solution`] / [`neo_hookean_radial`].
///
/// The table holds, on a uniform grid of `n + 1` nodes, `u = r - R`,
/// `v = r' - 1`, `r''`, `P_R` and `P_T`.  Queries between nodes use
///
/// * cubic Hermite interpolation of `u` with the exact slope `v` (for `r`),
/// * cubic Hermite interpolation of `v` with the exact slope `r''` (for `l1`),
/// * cubic Hermite interpolation of `P_R` with the exact slope
///   `dP_R/dR = -(P_R - P_T)/R - rho omega^2 r` (equilibrium),
/// * 4-point Lagrange interpolation of `P_T`,
///
/// all with `O(h^4)` error (`h = (Ro - Ri)/n`, ~1e-17 relative for the
/// default grid).  Cauchy stresses are `sigma_r = P_R l1/J = P_R/l2` and
/// `sigma_theta = P_T l2/J = P_T/l1`.
///
/// Queries for `R` outside `[Ri, Ro]` by more than `1e-9 (Ro - Ri)` return
/// `NaN`; slightly outside values are evaluated with the end interval's cubic.
#[derive(Debug, Clone)]
pub struct RadialSolution {
    pub ri: f64,
    pub ro: f64,
    pub rho: f64,
    pub omega: f64,
    n: usize,
    h: f64,
    u: Vec<f64>,
    v: Vec<f64>,
    acc: Vec<f64>,
    p_r: Vec<f64>,
    p_t: Vec<f64>,
    /// Number of residual evaluations (full integrations) used by the shooting.
    pub shooting_evaluations: usize,
    /// Final outer traction residual `P_R(Ro)` of the converged shot.
    pub outer_residual: f64,
}

impl RadialSolution {
    /// Number of integration steps of the table.
    pub fn n_steps(&self) -> usize {
        self.n
    }

    /// Shooting parameter `s = r'(Ri)`.
    pub fn slope_at_inner(&self) -> f64 {
        1.0 + self.v[0]
    }

    /// Locate the interval `[R_i, R_i + h]` and local coordinate `t` for `rr`.
    fn locate(&self, rr: f64) -> Option<(usize, f64)> {
        if !rr.is_finite() {
            return None;
        }
        let span = self.ro - self.ri;
        if rr < self.ri - 1e-9 * span || rr > self.ro + 1e-9 * span {
            return None;
        }
        let x = (rr - self.ri) / self.h;
        let mut i = x.floor() as isize;
        if i < 0 {
            i = 0;
        }
        if i as usize >= self.n {
            i = self.n as isize - 1;
        }
        let i = i as usize;
        Some((i, x - i as f64))
    }

    fn node_r(&self, i: usize) -> f64 {
        self.ri + i as f64 * self.h
    }

    fn hermite(t: f64, h: f64, f0: f64, d0: f64, f1: f64, d1: f64) -> f64 {
        let t2 = t * t;
        let t3 = t2 * t;
        let h00 = 2.0 * t3 - 3.0 * t2 + 1.0;
        let h10 = t3 - 2.0 * t2 + t;
        let h01 = -2.0 * t3 + 3.0 * t2;
        let h11 = t3 - t2;
        h00 * f0 + h10 * h * d0 + h01 * f1 + h11 * h * d1
    }

    /// Displacement `u(R) = r(R) - R`.
    pub fn u(&self, rr: f64) -> f64 {
        match self.locate(rr) {
            None => f64::NAN,
            Some((i, t)) => Self::hermite(
                t,
                self.h,
                self.u[i],
                self.v[i],
                self.u[i + 1],
                self.v[i + 1],
            ),
        }
    }

    /// Current radius `r(R)`.
    pub fn r_of(&self, rr: f64) -> f64 {
        rr + self.u(rr)
    }

    /// Radial stretch `l1 = dr/dR`.
    pub fn radial_stretch(&self, rr: f64) -> f64 {
        match self.locate(rr) {
            None => f64::NAN,
            Some((i, t)) => {
                1.0 + Self::hermite(
                    t,
                    self.h,
                    self.v[i],
                    self.acc[i],
                    self.v[i + 1],
                    self.acc[i + 1],
                )
            }
        }
    }

    /// Principal stretches `(l1, l2) = (dr/dR, r/R)`.
    pub fn stretches(&self, rr: f64) -> (f64, f64) {
        (self.radial_stretch(rr), 1.0 + self.u(rr) / rr)
    }

    /// Jacobian `J = l1 l2` (current/reference area ratio).
    pub fn jacobian(&self, rr: f64) -> f64 {
        let (l1, l2) = self.stretches(rr);
        l1 * l2
    }

    fn dp_r_node(&self, i: usize) -> f64 {
        let rr = self.node_r(i);
        let r = rr + self.u[i];
        -(self.p_r[i] - self.p_t[i]) / rr - self.rho * self.omega * self.omega * r
    }

    /// Radial first Piola–Kirchhoff stress `P_R(R)` (force per reference
    /// area on a cylinder `R = const`).
    pub fn p_r(&self, rr: f64) -> f64 {
        match self.locate(rr) {
            None => f64::NAN,
            Some((i, t)) => Self::hermite(
                t,
                self.h,
                self.p_r[i],
                self.dp_r_node(i),
                self.p_r[i + 1],
                self.dp_r_node(i + 1),
            ),
        }
    }

    /// Hoop first Piola–Kirchhoff stress `P_T(R)`.
    pub fn p_theta(&self, rr: f64) -> f64 {
        match self.locate(rr) {
            None => f64::NAN,
            Some((i, t)) => {
                // 4-point Lagrange stencil j0..j0+3 containing interval i.
                let j0 = if i == 0 {
                    0
                } else if i + 2 > self.n {
                    self.n - 3
                } else {
                    i - 1
                };
                let x = (i as f64 + t) - j0 as f64; // position in stencil units
                let mut s = 0.0;
                for a in 0..4 {
                    let mut w = 1.0;
                    for b in 0..4 {
                        if a != b {
                            w *= (x - b as f64) / (a as f64 - b as f64);
                        }
                    }
                    s += w * self.p_t[j0 + a];
                }
                s
            }
        }
    }

    /// Cauchy radial stress `sigma_r = P_R / l2`.
    pub fn sigma_r(&self, rr: f64) -> f64 {
        let l2 = 1.0 + self.u(rr) / rr;
        self.p_r(rr) / l2
    }

    /// Cauchy hoop stress `sigma_theta = P_T / l1`.
    pub fn sigma_theta(&self, rr: f64) -> f64 {
        self.p_theta(rr) / self.radial_stretch(rr)
    }

    /// Node values `(R, r, r', P_R, P_T)` of the table (for diagnostics).
    pub fn node(&self, i: usize) -> Option<(f64, f64, f64, f64, f64)> {
        if i > self.n {
            return None;
        }
        let rr = self.node_r(i);
        Some((
            rr,
            rr + self.u[i],
            1.0 + self.v[i],
            self.p_r[i],
            self.p_t[i],
        ))
    }
}

/// Outcome of one shooting integration.
enum Shot {
    /// Reached `Ro`; value of `P_R(Ro)`.
    Done(f64),
    /// Integration broke down (non-positive stretch, loss of ellipticity
    /// `dP_R/dl1 <= 0`, non-finite values).  Holds the sign the residual is
    /// assigned for bracketing (sign of the last finite `P_R`).
    Failed(f64, String),
}

struct Table {
    u: Vec<f64>,
    v: Vec<f64>,
    acc: Vec<f64>,
    p_r: Vec<f64>,
    p_t: Vec<f64>,
}

/// Right-hand side of the radial ODE in the variables `u = r - R`,
/// `v = r' - 1`.  Returns `(v', P_R, P_T)`.
///
/// From `dP_R/dR = (dP_R/dl1) r'' + (dP_R/dl2) (r'/R - r/R^2)` and
/// equilibrium `dP_R/dR + (P_R - P_T)/R + rho omega^2 r = 0`:
///
/// ```text
///   r'' = -[ (P_R - P_T)/R + rho omega^2 r + (dP_R/dl2)(l1 - l2)/R ] / (dP_R/dl1)
/// ```
/// with `(l1 - l2)/R = (v - u/R)/R`.
fn radial_rhs<F: Fn(f64, f64) -> (f64, f64, f64, f64)>(
    rr: f64,
    u: f64,
    v: f64,
    rw2: f64,
    f: &F,
) -> Result<(f64, f64, f64), (f64, String)> {
    let l1 = 1.0 + v;
    let l2 = 1.0 + u / rr;
    if !(l1 > 0.0 && l2 > 0.0 && l1.is_finite() && l2.is_finite()) {
        return Err((
            if v < 0.0 { -1.0 } else { 1.0 },
            format!("non-positive stretch l1={l1}, l2={l2} at R={rr}"),
        ));
    }
    let (pr, pt, d1, d2) = f(l1, l2);
    if !(pr.is_finite() && pt.is_finite() && d1.is_finite() && d2.is_finite()) {
        return Err((
            if v < 0.0 { -1.0 } else { 1.0 },
            format!("non-finite stress at R={rr} (l1={l1}, l2={l2})"),
        ));
    }
    if d1 <= 0.0 {
        return Err((
            pr.signum(),
            format!("loss of ellipticity dP_R/dl1={d1} at R={rr} (l1={l1}, l2={l2})"),
        ));
    }
    let r = rr + u;
    let acc = -((pr - pt) / rr + rw2 * r + d2 * (v - u / rr) / rr) / d1;
    if !acc.is_finite() {
        return Err((pr.signum(), format!("non-finite r'' at R={rr}")));
    }
    Ok((acc, pr, pt))
}

/// Integrate from `Ri` with `u = 0`, `v = d` by classical RK4 over `n` steps.
fn shoot<F: Fn(f64, f64) -> (f64, f64, f64, f64)>(
    ri: f64,
    ro: f64,
    rw2: f64,
    n: usize,
    d: f64,
    f: &F,
    mut table: Option<&mut Table>,
) -> Shot {
    let h = (ro - ri) / n as f64;
    let mut u = 0.0f64;
    let mut v = d;
    let mut last_pr = f64::NAN;
    for i in 0..=n {
        let rr = ri + i as f64 * h;
        let (k1a, pr, pt) = match radial_rhs(rr, u, v, rw2, f) {
            Ok(x) => x,
            Err((s, m)) => {
                return Shot::Failed(
                    if last_pr.is_finite() {
                        last_pr.signum()
                    } else {
                        s
                    },
                    m,
                )
            }
        };
        last_pr = pr;
        if let Some(t) = table.as_deref_mut() {
            t.u.push(u);
            t.v.push(v);
            t.acc.push(k1a);
            t.p_r.push(pr);
            t.p_t.push(pt);
        }
        if i == n {
            return Shot::Done(pr);
        }
        let k1u = v;
        let fail = |e: (f64, String)| {
            Shot::Failed(
                if last_pr.is_finite() {
                    last_pr.signum()
                } else {
                    e.0
                },
                e.1,
            )
        };
        let k2u = v + 0.5 * h * k1a;
        let k2a = match radial_rhs(rr + 0.5 * h, u + 0.5 * h * k1u, k2u, rw2, f) {
            Ok(x) => x.0,
            Err(e) => return fail(e),
        };
        let k3u = v + 0.5 * h * k2a;
        let k3a = match radial_rhs(rr + 0.5 * h, u + 0.5 * h * k2u, k3u, rw2, f) {
            Ok(x) => x.0,
            Err(e) => return fail(e),
        };
        let k4u = v + h * k3a;
        let k4a = match radial_rhs(rr + h, u + h * k3u, k4u, rw2, f) {
            Ok(x) => x.0,
            Err(e) => return fail(e),
        };
        u += h / 6.0 * (k1u + 2.0 * k2u + 2.0 * k3u + k4u);
        v += h / 6.0 * (k1a + 2.0 * k2a + 2.0 * k3a + k4a);
    }
    Shot::Failed(f64::NAN, "unreachable".to_string())
}

/// Generic finite-strain radial solution with the default grid
/// ([`DEFAULT_RADIAL_STEPS`]).  See [`radial_solution_with_steps`].
pub fn radial_solution<F: Fn(f64, f64) -> (f64, f64, f64, f64)>(
    ri: f64,
    ro: f64,
    rho: f64,
    omega: f64,
    stresses: F,
) -> Result<RadialSolution, String> {
    radial_solution_with_steps(ri, ro, rho, omega, DEFAULT_RADIAL_STEPS, stresses)
}

/// Generic finite-strain axisymmetric solution of the spinning annulus for an
/// isotropic hyperelastic material given through its principal first
/// Piola–Kirchhoff stresses: `stresses(l1, l2) = (P_R, P_T, dP_R/dl1,
/// dP_R/dl2)` with `l1 = dr/dR`, `l2 = r/R` (plane strain, `F33 = 1`).
///
/// Equations (reference configuration):
///
/// ```text
///   dP_R/dR + (P_R - P_T)/R + rho omega^2 r = 0,   Ri < R < Ro
///   r(Ri) = Ri,     P_R(Ro) = 0
/// ```
///
/// Method: shooting on `s = r'(Ri)`.  Expanding `dP_R/dR = (dP_R/dl1) r''
/// + (dP_R/dl2)(r'/R - r/R^2)` gives an explicit second-order ODE for `r`
/// (see `radial_rhs`), integrated in the variables `u = r - R`, `v = r' - 1`
/// (no cancellation at small strain) with classical RK4 on `n_steps` uniform
/// steps.  The initial guess for `s` comes from [`linear_annulus`] with the
/// tangent moduli of `stresses` at `F = I` (`lambda = dP_R/dl2`,
/// `lambda + 2 mu = dP_R/dl1`).  The residual `g(s) = P_R(Ro)` is bracketed
/// (scanning upward from below so that the first root, i.e. the stable branch,
/// is taken; if `g` reaches a maximum below zero the spin exceeds the limit
/// point and `Err` is returned), then solved by the Illinois (modified
/// regula-falsi) method to `|P_R(Ro)| <= 1e-13 min(mu, rho omega^2 Ro^2)`
/// (`mu` = tangent shear modulus at `F = I`).  If round-off prevents that
/// tolerance (the iteration stops when the bracket has collapsed to a few
/// ulps), the best shot is accepted when
/// `|P_R(Ro)| <= max(1e-10 rho omega^2 Ro^2, 64 eps (lambda + 2 mu))`.
///
/// Accuracy: RK4 truncation and interpolation errors are below 1e-13
/// relative for the default grid at strains up to tens of percent (step
/// halving changes results by ~1e-13).  At very small strains `e` the
/// stresses, which are evaluated from `l1 = 1 + v`, `l2 = 1 + u/R` through
/// `stresses`, carry round-off of relative size ~`1e-16 / e` (e.g. ~1e-9 at
/// `e = 1e-7`, ~1e-11 at `e = 4e-6`); `u` itself stays accurate to ~1e-12.
///
/// Returns `Err` for invalid input, loss of ellipticity / non-positive
/// stretches along every shot, or when no equilibrium exists (spin too high).
pub fn radial_solution_with_steps<F: Fn(f64, f64) -> (f64, f64, f64, f64)>(
    ri: f64,
    ro: f64,
    rho: f64,
    omega: f64,
    n_steps: usize,
    stresses: F,
) -> Result<RadialSolution, String> {
    if !(ri > 0.0 && ro > ri && ri.is_finite() && ro.is_finite()) {
        return Err(format!("invalid radii ri={ri}, ro={ro}"));
    }
    if !(rho >= 0.0 && rho.is_finite() && omega.is_finite()) {
        return Err(format!("invalid rho={rho} or omega={omega}"));
    }
    if n_steps < 4 {
        return Err(format!("n_steps={n_steps} too small (need >= 4)"));
    }
    let rw2 = rho * omega * omega;
    let n = n_steps;

    // Linearisation at F = I.
    let (p0, pt0, m_lin, lam_lin) = stresses(1.0, 1.0);
    if !(m_lin > 0.0
        && m_lin.is_finite()
        && lam_lin.is_finite()
        && p0.is_finite()
        && pt0.is_finite())
    {
        return Err(format!(
            "stress function not usable at F=I: dP_R/dl1={m_lin}, dP_R/dl2={lam_lin}"
        ));
    }
    if p0.abs() > 1e-12 * m_lin || pt0.abs() > 1e-12 * m_lin {
        return Err(format!(
            "reference configuration is not stress free: P_R={p0}, P_T={pt0}"
        ));
    }
    let mu_lin = 0.5 * (m_lin - lam_lin);
    // Tolerances on the outer traction P_R(Ro).  Stress scale of the load:
    // S = rho omega^2 Ro^2.  Target: |P_R(Ro)| <= 1e-13 min(mu, S) (i.e.
    // 1e-13 mu, tightened at small spin so that it stays relative to the
    // stresses).  If round-off in P_R (~ eps (lambda + 2 mu)) prevents this,
    // the best shot is accepted when |P_R(Ro)| <= max(1e-10 S, 64 eps M).
    let mu_scale = if mu_lin > 0.0 { mu_lin } else { m_lin };
    let s_scale = rw2 * ro * ro;
    let tol = 1e-13 * mu_scale.min(s_scale);
    let loose_tol = (1e-10 * s_scale).max(64.0 * f64::EPSILON * m_lin);
    let lin = linear_annulus(ri, ro, lam_lin, mu_lin, rho, omega);
    let mut d0 = lin.du_dr(ri);
    if !d0.is_finite() {
        d0 = 0.0;
    }

    let mut evals = 0usize;
    let mut last_fail = String::new();
    // Residual with failures mapped to +-infinity.
    let mut g = |d: f64, evals: &mut usize| -> f64 {
        *evals += 1;
        match shoot(ri, ro, rw2, n, d, &stresses, None) {
            Shot::Done(x) => x,
            Shot::Failed(s, m) => {
                last_fail = m;
                if s < 0.0 {
                    f64::NEG_INFINITY
                } else {
                    f64::INFINITY
                }
            }
        }
    };

    let finish = |d: f64, evals: usize| -> Result<RadialSolution, String> {
        let mut t = Table {
            u: Vec::with_capacity(n + 1),
            v: Vec::with_capacity(n + 1),
            acc: Vec::with_capacity(n + 1),
            p_r: Vec::with_capacity(n + 1),
            p_t: Vec::with_capacity(n + 1),
        };
        match shoot(ri, ro, rw2, n, d, &stresses, Some(&mut t)) {
            Shot::Done(res) => Ok(RadialSolution {
                ri,
                ro,
                rho,
                omega,
                n,
                h: (ro - ri) / n as f64,
                u: t.u,
                v: t.v,
                acc: t.acc,
                p_r: t.p_r,
                p_t: t.p_t,
                shooting_evaluations: evals + 1,
                outer_residual: res,
            }),
            Shot::Failed(_, m) => Err(format!("final integration failed: {m}")),
        }
    };

    let g0 = g(d0, &mut evals);
    if g0.is_finite() && g0.abs() <= tol {
        return finish(d0, evals);
    }

    // ---- Bracketing: find a < b with g(a) < 0 < g(b), b the first crossing.
    let scale = d0.abs().max(1e-300);
    let (mut a, ga, mut b, mut gb);
    if g0 > 0.0 {
        // Move down until negative (l1 -> 0 makes P_R -> -inf eventually).
        b = d0;
        gb = g0;
        let mut step = 0.5 * scale;
        let mut found = None;
        for _ in 0..400 {
            let mut cand = d0 - step;
            if cand <= -1.0 {
                cand = 0.5 * (b - 1.0);
            }
            let gc = g(cand, &mut evals);
            if gc < 0.0 {
                found = Some((cand, gc));
                break;
            }
            if gc.is_finite() && gc.abs() <= tol {
                return finish(cand, evals);
            }
            b = cand;
            gb = gc;
            step *= 2.0;
        }
        match found {
            Some((x, gx)) => {
                a = x;
                ga = gx;
            }
            None => {
                return Err(format!(
                    "could not bracket the shooting residual from below ({last_fail})"
                ))
            }
        }
    } else {
        // g(d0) < 0 (or failed negatively): scan upward from a point below d0
        // so that the first sign change (stable branch) is found; detect a
        // maximum of g below zero (no equilibrium beyond the limit point).
        let mut start = if d0 > 0.0 { 0.5 * d0 } else { d0 - 0.5 * scale };
        let mut gs = g(start, &mut evals);
        // Make sure the scan starts on the rising part: g(start) < 0 and
        // g(start) < g(d0) (otherwise d0 may lie beyond a maximum of g).
        // Moving towards l1 -> 0 eventually makes g very negative.
        let mut tries = 0;
        loop {
            if gs.is_finite() && gs.abs() <= tol {
                return finish(start, evals);
            }
            // gs > 0: handled below by descending to a negative value.
            if gs > 0.0 || (gs < 0.0 && (gs < g0 || g0 == f64::NEG_INFINITY)) || tries >= 60 {
                break;
            }
            tries += 1;
            start = if start > 0.0 {
                0.5 * start
            } else {
                0.5 * (start - 1.0)
            };
            gs = g(start, &mut evals);
        }
        if gs > 0.0 {
            // Descend from `start` until negative; bracket [x, last positive].
            b = start;
            gb = gs;
            let mut cand = start;
            let mut found = None;
            for _ in 0..200 {
                cand = if cand > 0.0 {
                    0.5 * cand - 0.5 * scale
                } else {
                    0.5 * (cand - 1.0)
                };
                let gc = g(cand, &mut evals);
                if gc < 0.0 {
                    found = Some((cand, gc));
                    break;
                }
                b = cand;
                gb = gc;
            }
            match found {
                Some((x, gx)) => {
                    a = x;
                    ga = gx;
                }
                None => {
                    return Err(format!(
                        "could not bracket the shooting residual ({last_fail})"
                    ))
                }
            }
        } else {
            let mut pts: Vec<(f64, f64)> = vec![(start, gs)];
            let mut step = 0.125 * (d0 - start).abs().max(0.125 * scale);
            let mut result = None;
            for _ in 0..2000 {
                let (xl, gl) = *pts.last().unwrap_or(&(start, gs));
                let x = xl + step;
                if x > 1e3 {
                    break;
                }
                let gx = g(x, &mut evals);
                if gx.is_finite() && gx.abs() <= tol {
                    return finish(x, evals);
                }
                if gx > 0.0 {
                    result = Some((xl, gl, x, gx));
                    break;
                }
                if gx < gl && gl.is_finite() {
                    // g decreased while negative: maximise g on [x_prev_prev, x].
                    let xa = if pts.len() >= 2 {
                        pts[pts.len() - 2].0
                    } else {
                        xl - step
                    };
                    let (xm, gm) = golden_max(xa, x, |y| g(y, &mut evals));
                    if gm.is_finite() && gm.abs() <= tol {
                        return finish(xm, evals);
                    }
                    if gm > 0.0 {
                        // Lower end: the point xa has g < 0 if it was a scan
                        // point; otherwise check.
                        let ga2 = g(xa, &mut evals);
                        if ga2 < 0.0 {
                            result = Some((xa, ga2, xm, gm));
                            break;
                        }
                        return Err("shooting residual not bracketable (non-monotone)".to_string());
                    }
                    return Err(format!(
                        "no equilibrium: spin omega={omega} exceeds the limit point \
                         (max over r'(Ri) of P_R(Ro) is {gm:.6e} < 0)"
                    ));
                }
                pts.push((x, gx));
                step *= 1.25;
            }
            match result {
                Some((x1, g1, x2, g2)) => {
                    a = x1;
                    ga = g1;
                    b = x2;
                    gb = g2;
                }
                None => {
                    return Err(format!(
                        "could not bracket the shooting residual from above ({last_fail})"
                    ))
                }
            }
        }
    }

    // ---- Illinois iteration on the bracket [a, b], g(a) < 0 < g(b).
    let mut best = if ga.abs() < gb.abs() {
        (a, ga)
    } else {
        (b, gb)
    };
    let mut side = 0i32;
    let mut fa = ga;
    let mut fb = gb;
    for _ in 0..300 {
        let x = if fa.is_finite() && fb.is_finite() {
            let xs = (a * fb - b * fa) / (fb - fa);
            if xs > a.min(b) && xs < a.max(b) {
                xs
            } else {
                0.5 * (a + b)
            }
        } else {
            0.5 * (a + b)
        };
        let gx = g(x, &mut evals);
        if gx.is_finite() && gx.abs() < best.1.abs() {
            best = (x, gx);
        }
        if gx.is_finite() && gx.abs() <= tol {
            return finish(x, evals);
        }
        if gx < 0.0 {
            a = x;
            fa = gx;
            if side == -1 {
                fb *= 0.5;
            }
            side = -1;
        } else {
            b = x;
            fb = gx;
            if side == 1 {
                fa *= 0.5;
            }
            side = 1;
        }
        if (b - a).abs() <= 4.0 * f64::EPSILON * a.abs().max(b.abs()) {
            break;
        }
    }
    if best.1.is_finite() && best.1.abs() < loose_tol {
        return finish(best.0, evals);
    }
    Err(format!(
        "shooting did not converge: best |P_R(Ro)| = {:e} ({last_fail})",
        best.1.abs()
    ))
}

/// Golden-section maximisation of `f` on `[a, b]`; returns `(x, f(x))`.
fn golden_max<G: FnMut(f64) -> f64>(mut a: f64, mut b: f64, mut f: G) -> (f64, f64) {
    let phi = 0.5 * (5.0f64.sqrt() - 1.0);
    let mut c = b - phi * (b - a);
    let mut d = a + phi * (b - a);
    let mut fc = f(c);
    let mut fd = f(d);
    for _ in 0..200 {
        if fc > 0.0 {
            return (c, fc);
        }
        if fd > 0.0 {
            return (d, fd);
        }
        if (b - a).abs() <= 1e-14 * (a.abs() + b.abs()) {
            break;
        }
        if fc > fd {
            b = d;
            d = c;
            fd = fc;
            c = b - phi * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + phi * (b - a);
            fd = f(d);
        }
    }
    if fc > fd {
        (c, fc)
    } else {
        (d, fd)
    }
}

/// Finite-strain compressible neo-Hookean spinning annulus (default grid).
///
/// `W = mu/2 (l1^2 + l2^2 + 1 - 3) - mu ln J + lambda/2 (ln J)^2`; see
/// [`neo_hookean_principal_pk1`] and [`radial_solution_with_steps`].
pub fn neo_hookean_radial(
    ri: f64,
    ro: f64,
    lambda: f64,
    mu: f64,
    rho: f64,
    omega: f64,
) -> Result<RadialSolution, String> {
    neo_hookean_radial_with_steps(ri, ro, lambda, mu, rho, omega, DEFAULT_RADIAL_STEPS)
}

/// [`neo_hookean_radial`] with an explicit number of RK4 steps.
pub fn neo_hookean_radial_with_steps(
    ri: f64,
    ro: f64,
    lambda: f64,
    mu: f64,
    rho: f64,
    omega: f64,
    n_steps: usize,
) -> Result<RadialSolution, String> {
    if !(mu > 0.0 && lambda > -mu && mu.is_finite() && lambda.is_finite()) {
        return Err(format!(
            "invalid neo-Hookean moduli lambda={lambda}, mu={mu}"
        ));
    }
    radial_solution_with_steps(ri, ro, rho, omega, n_steps, move |l1, l2| {
        neo_hookean_principal_pk1(lambda, mu, l1, l2)
    })
}

/// Angular speed at which the neo-Hookean outer radius grows by the fraction
/// `target = u(Ro)/Ro` (e.g. 0.05), found by secant/bisection on `omega`.
pub fn neo_hookean_omega_for_growth(
    ri: f64,
    ro: f64,
    lambda: f64,
    mu: f64,
    rho: f64,
    target: f64,
) -> Result<f64, String> {
    if !(target > 0.0 && target.is_finite()) {
        return Err(format!("invalid target growth {target}"));
    }
    let growth = |w: f64| -> Result<f64, String> {
        let s = neo_hookean_radial(ri, ro, lambda, mu, rho, w)?;
        Ok(s.u(ro) / ro)
    };
    // Linear estimate: growth is proportional to omega^2.
    let lin1 = linear_annulus(ri, ro, lambda, mu, rho, 1.0).u(ro) / ro;
    if lin1.is_nan() || lin1 <= 0.0 {
        return Err("linear estimate failed".into());
    }
    // Work in x = omega^2: growth(x) is close to linear in x.
    let mut x0 = 0.0f64;
    let mut f0 = -target;
    let mut x1 = target / lin1;
    let mut f1 = match growth(x1.sqrt()) {
        Ok(gr) => gr - target,
        Err(_) => {
            // Too high; back off.
            x1 *= 0.5;
            growth(x1.sqrt())? - target
        }
    };
    for _ in 0..100 {
        if f1.abs() < 1e-14 * target {
            return Ok(x1.sqrt());
        }
        let mut x2 = x1 - f1 * (x1 - x0) / (f1 - f0);
        if !(x2 > 0.0 && x2.is_finite()) {
            x2 = 0.5 * x1;
        }
        let f2 = match growth(x2.sqrt()) {
            Ok(gr) => gr - target,
            Err(_) => {
                x2 = 0.5 * (x1 + x2);
                growth(x2.sqrt())? - target
            }
        };
        x0 = x1;
        f0 = f1;
        x1 = x2;
        f1 = f2;
        if (x1 - x0).abs() <= 1e-15 * x1 {
            return Ok(x1.sqrt());
        }
    }
    Err("omega search did not converge".into())
}

// ---------------------------------------------------------------------------
// 3. Incompressible material
// ---------------------------------------------------------------------------

/// Exact radial Cauchy stress of the spinning annulus made of an
/// incompressible isotropic hyperelastic material (plane strain, hub-bonded
/// inner rim).
///
/// Kinematics: plane-strain incompressibility means `J = l1 l2 = r' r/R = 1`,
/// i.e. `r^2 - R^2` is constant; `r(Ri) = Ri` makes it zero, so `r = R` and
/// `u = 0` everywhere (the hub forbids any radial motion).  With `F = I` every
/// isotropic incompressible model gives an isotropic stress
/// `sigma = -p_tilde I` (the constitutive part at `F = I` is a multiple of
/// `I` absorbed into the pressure), so `sigma_r = sigma_theta = sigma_z`.
/// Equilibrium `d sigma_r/dr + (sigma_r - sigma_theta)/r + rho omega^2 r = 0`
/// then reduces to `d sigma_r/dr = -rho omega^2 r`, and `sigma_r(Ro) = 0`
/// gives
///
/// ```text
///   sigma_r(r) = rho omega^2 (Ro^2 - r^2) / 2 .
/// ```
pub fn incompressible_sigma_r(ro: f64, rho: f64, omega: f64, r: f64) -> f64 {
    0.5 * rho * omega * omega * (ro * ro - r * r)
}

/// Exact hoop Cauchy stress of the incompressible spinning annulus:
/// the stress is isotropic (`u = 0`, `F = I`, see [`incompressible_sigma_r`]),
/// hence `sigma_theta = sigma_r = rho omega^2 (Ro^2 - r^2) / 2`.  (The axial
/// stress `sigma_z` has the same value.)
pub fn incompressible_sigma_theta(ro: f64, rho: f64, omega: f64, r: f64) -> f64 {
    incompressible_sigma_r(ro, rho, omega, r)
}

/// Displacement of the incompressible annulus: identically zero.
pub fn incompressible_u(_r: f64) -> f64 {
    0.0
}

// ---------------------------------------------------------------------------
// Self-tests
// ---------------------------------------------------------------------------

#[cfg(test)]
mod tests {
    use super::*;

    const MU: f64 = 200.0;
    const LAMBDA: f64 = 1800.0;
    const RHO: f64 = 0.027;
    const RI: f64 = 1.0;
    const RO: f64 = 2.0;

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs().max(1e-300)
    }

    #[test]
    fn linear_ode_and_bcs() {
        let omega = 30.0;
        let s = linear_annulus(RI, RO, LAMBDA, MU, RHO, omega);
        let m = LAMBDA + 2.0 * MU;
        assert!(s.u(RI).abs() < 1e-15 * s.u(RO).abs());
        let sig_scale = s.sigma_theta(RI).abs();
        assert!(s.sigma_r(RO).abs() < 1e-13 * sig_scale, "{}", s.sigma_r(RO));
        let h = 1e-3;
        for i in 1..20 {
            let r = RI + (RO - RI) * i as f64 / 20.0;
            // (lambda+2mu) d/dr[(1/r) d(r u)/dr] + rho omega^2 r = 0, via FD.
            let q = |x: f64| {
                let ru = |y: f64| y * s.u(y);
                (ru(x + h) - ru(x - h)) / (2.0 * h) / x
            };
            let lhs = m * (q(r + h) - q(r - h)) / (2.0 * h);
            let body = RHO * omega * omega * r;
            assert!((lhs + body).abs() < 1e-5 * body, "r={r} res={}", lhs + body);
            // stress form of equilibrium
            let ds = (s.sigma_r(r + h) - s.sigma_r(r - h)) / (2.0 * h);
            let res = ds + (s.sigma_r(r) - s.sigma_theta(r)) / r + body;
            assert!(res.abs() < 1e-5 * body, "r={r} res={res}");
            // strain definitions
            let du = (s.u(r + h) - s.u(r - h)) / (2.0 * h);
            assert!(
                (du - s.du_dr(r)).abs() < 1e-6 * s.du_dr(RI).abs(),
                "r={r} {du} {}",
                s.du_dr(r)
            );
            assert!(rel(s.sigma_z(r), LAMBDA * (s.du_dr(r) + s.u(r) / r)) < 1e-14);
        }
    }

    #[test]
    fn neo_hookean_stress_derivatives() {
        for &(l1, l2) in &[(1.0, 1.0), (1.07, 1.02), (0.9, 1.15), (1.3, 0.8)] {
            let (pr, pt, d1, d2) = neo_hookean_principal_pk1(LAMBDA, MU, l1, l2);
            let e = 1e-5;
            let w = |a: f64, b: f64| neo_hookean_energy(LAMBDA, MU, a, b);
            let fpr = (w(l1 + e, l2) - w(l1 - e, l2)) / (2.0 * e);
            let fpt = (w(l1, l2 + e) - w(l1, l2 - e)) / (2.0 * e);
            let p = |a: f64, b: f64| neo_hookean_principal_pk1(LAMBDA, MU, a, b).0;
            let fd1 = (p(l1 + e, l2) - p(l1 - e, l2)) / (2.0 * e);
            let fd2 = (p(l1, l2 + e) - p(l1, l2 - e)) / (2.0 * e);
            let sc = LAMBDA + 2.0 * MU;
            assert!((fpr - pr).abs() < 1e-6 * sc);
            assert!((fpt - pt).abs() < 1e-6 * sc);
            assert!((fd1 - d1).abs() < 1e-6 * sc);
            assert!((fd2 - d2).abs() < 1e-6 * sc);
        }
    }

    #[test]
    fn small_spin_matches_linear() {
        // omega such that u(Ro)/Ro ~ 1e-7 in linear theory.
        let lin1 = linear_annulus(RI, RO, LAMBDA, MU, RHO, 1.0).u(RO) / RO;
        let omega = (1e-7 / lin1).sqrt();
        let lin = linear_annulus(RI, RO, LAMBDA, MU, RHO, omega);
        let nl = neo_hookean_radial(RI, RO, LAMBDA, MU, RHO, omega).expect("solve");
        eprintln!(
            "small spin: omega={omega:.6} u(Ro)/Ro={:.6e} (linear {:.6e}), evals={}",
            nl.u(RO) / RO,
            lin.u(RO) / RO,
            nl.shooting_evaluations
        );
        let sig_scale = lin.sigma_theta(RI).abs();
        for i in 0..=10 {
            let r = RI + (RO - RI) * i as f64 / 10.0;
            if i > 0 {
                assert!(
                    rel(nl.u(r), lin.u(r)) < 1e-6,
                    "u at {r}: {} vs {}",
                    nl.u(r),
                    lin.u(r)
                );
            }
            assert!(
                (nl.sigma_r(r) - lin.sigma_r(r)).abs() < 1e-6 * sig_scale,
                "sr at {r}"
            );
            assert!(
                rel(nl.sigma_theta(r), lin.sigma_theta(r)) < 1e-6,
                "st at {r}"
            );
        }
        assert!(rel(nl.sigma_r(RI), lin.sigma_r(RI)) < 1e-6);
    }

    /// Check ODE residual (equilibrium written directly with P_R, P_T from
    /// the stress function, not with the expanded r'' formula) and BCs.
    fn check_residual(sol: &RadialSolution, lambda: f64, mu: f64) -> f64 {
        let w2 = sol.rho * sol.omega * sol.omega;
        assert_eq!(sol.u(sol.ri), 0.0);
        assert!(
            sol.p_r(sol.ro).abs() < 1e-13 * mu,
            "P_R(Ro)={}",
            sol.p_r(sol.ro)
        );
        let h = 1e-3;
        let mut worst: f64 = 0.0;
        for i in 1..50 {
            let rr = sol.ri + (sol.ro - sol.ri) * i as f64 / 50.0;
            // P_R from the constitutive law at interpolated stretches.
            let pr = |x: f64| {
                let (l1, l2) = sol.stretches(x);
                neo_hookean_principal_pk1(lambda, mu, l1, l2).0
            };
            let (l1, l2) = sol.stretches(rr);
            let (p_r, p_t, _, _) = neo_hookean_principal_pk1(lambda, mu, l1, l2);
            // consistency of the interpolated stress tables
            assert!((p_r - sol.p_r(rr)).abs() < 1e-10 * mu);
            assert!((p_t - sol.p_theta(rr)).abs() < 1e-10 * mu);
            // 4th-order central difference
            let dp = (-pr(rr + 2.0 * h) + 8.0 * pr(rr + h) - 8.0 * pr(rr - h) + pr(rr - 2.0 * h))
                / (12.0 * h);
            let res = dp + (p_r - p_t) / rr + w2 * sol.r_of(rr);
            let scale = w2 * sol.r_of(rr);
            worst = worst.max(res.abs() / scale);
            // interpolation check on r'
            let dr = (-sol.r_of(rr + 2.0 * h) + 8.0 * sol.r_of(rr + h) - 8.0 * sol.r_of(rr - h)
                + sol.r_of(rr - 2.0 * h))
                / (12.0 * h);
            assert!((dr - l1).abs() < 1e-9, "r' mismatch {dr} vs {l1}");
        }
        worst
    }

    #[test]
    fn residual_and_bcs() {
        for &omega in &[5.0, 20.0, 40.0] {
            let sol = neo_hookean_radial(RI, RO, LAMBDA, MU, RHO, omega).expect("solve");
            let worst = check_residual(&sol, LAMBDA, MU);
            eprintln!(
                "omega={omega}: worst relative equilibrium residual {worst:.3e}, P_R(Ro)={:.3e}, evals={}",
                sol.outer_residual, sol.shooting_evaluations
            );
            assert!(worst < 1e-8, "residual {worst}");
        }
    }

    #[test]
    fn large_spin_convergence() {
        let omega = neo_hookean_omega_for_growth(RI, RO, LAMBDA, MU, RHO, 0.05).expect("omega");
        let s1 = neo_hookean_radial_with_steps(RI, RO, LAMBDA, MU, RHO, omega, 4_999).expect("s1");
        let s2 = neo_hookean_radial_with_steps(RI, RO, LAMBDA, MU, RHO, omega, 10_000).expect("s2");
        let s3 = neo_hookean_radial_with_steps(RI, RO, LAMBDA, MU, RHO, omega, 20_000).expect("s3");
        let s4 = neo_hookean_radial_with_steps(RI, RO, LAMBDA, MU, RHO, omega, 40_000).expect("s4");
        let lin = linear_annulus(RI, RO, LAMBDA, MU, RHO, omega);
        let mut d = [0.0f64; 3];
        // Nodes and off-node points (tests the Hermite/Lagrange interpolation too).
        for i in 0..=40 {
            let x = if i % 2 == 0 {
                (i / 2) as f64
            } else {
                (i / 2) as f64 + 0.3137
            };
            let rr = RI + (RO - RI) * x / 20.0;
            for (k, (a, b)) in [(&s1, &s2), (&s2, &s3), (&s3, &s4)].iter().enumerate() {
                let mut e: f64 = 0.0;
                if i > 0 {
                    e = e.max(rel(a.u(rr), b.u(rr)));
                }
                e = e.max(rel(a.r_of(rr), b.r_of(rr)));
                e = e.max((a.sigma_r(rr) - b.sigma_r(rr)).abs() / b.sigma_r(RI).abs());
                e = e.max(rel(a.sigma_theta(rr), b.sigma_theta(rr)));
                d[k] = d[k].max(e);
            }
        }
        eprintln!("5% growth: omega = {omega:.12}");
        eprintln!(
            "  step-halving max rel changes: 4999->10k {:.2e}, 10k->20k {:.2e}, 20k->40k {:.2e}",
            d[0], d[1], d[2]
        );
        eprintln!(
            "  u(Ro) = {:.12e}, u(Ro)/Ro = {:.12e} (linear {:.6e})",
            s3.u(RO),
            s3.u(RO) / RO,
            lin.u(RO) / RO
        );
        eprintln!(
            "  r'(Ri) = {:.12}, P_R(Ro) = {:.3e}",
            s3.slope_at_inner(),
            s3.outer_residual
        );
        eprintln!(
            "  sigma_r(Ri) = {:.10}, sigma_theta(Ri) = {:.10}, sigma_theta(Ro) = {:.10}, sigma_r(Ro) = {:.3e}",
            s3.sigma_r(RI),
            s3.sigma_theta(RI),
            s3.sigma_theta(RO),
            s3.sigma_r(RO)
        );
        eprintln!(
            "  linear: sigma_r(Ri) = {:.6}, sigma_theta(Ri) = {:.6}, sigma_theta(Ro) = {:.6}",
            lin.sigma_r(RI),
            lin.sigma_theta(RI),
            lin.sigma_theta(RO)
        );
        assert!(rel(s3.u(RO) / RO, 0.05) < 1e-12);
        assert!(d[2] < 1e-11, "20k->40k change {}", d[2]);
        assert!(d[1] < 1e-11, "10k->20k change {}", d[1]);
        let worst = check_residual(&s3, LAMBDA, MU);
        eprintln!("  worst relative equilibrium residual {worst:.3e}");
        assert!(worst < 1e-8);
    }

    #[test]
    fn spin_table() {
        for &omega in &[0.1643, 1.0, 10.0, 40.0, 104.0, 150.0, 165.0] {
            match neo_hookean_radial(RI, RO, LAMBDA, MU, RHO, omega) {
                Ok(s) => {
                    let lin = linear_annulus(RI, RO, LAMBDA, MU, RHO, omega);
                    eprintln!(
                        "omega={omega:5.1}: u(Ro)/Ro={:.10e} (lin {:.4e}) sr(Ri)={:.8} st(Ri)={:.8} st(Ro)={:.8} PR(Ro)={:.2e} evals={}",
                        s.u(RO) / RO,
                        lin.u(RO) / RO,
                        s.sigma_r(RI),
                        s.sigma_theta(RI),
                        s.sigma_theta(RO),
                        s.outer_residual,
                        s.shooting_evaluations
                    );
                }
                Err(e) => eprintln!("omega={omega}: Err({e})"),
            }
        }
    }

    #[test]
    fn incompressible() {
        let omega = 12.0;
        let w2 = RHO * omega * omega;
        assert_eq!(incompressible_sigma_r(RO, RHO, omega, RO), 0.0);
        let h = 1e-4;
        for i in 0..=10 {
            let r = RI + 0.1 * i as f64;
            let ds = (incompressible_sigma_r(RO, RHO, omega, r + h)
                - incompressible_sigma_r(RO, RHO, omega, r - h))
                / (2.0 * h);
            let res = ds
                + (incompressible_sigma_r(RO, RHO, omega, r)
                    - incompressible_sigma_theta(RO, RHO, omega, r))
                    / r
                + w2 * r;
            assert!(res.abs() < 1e-8 * w2);
            assert_eq!(incompressible_u(r), 0.0);
        }
    }

    #[test]
    fn invalid_inputs_are_errors() {
        assert!(neo_hookean_radial(2.0, 1.0, LAMBDA, MU, RHO, 1.0).is_err());
        assert!(neo_hookean_radial(RI, RO, LAMBDA, -1.0, RHO, 1.0).is_err());
        assert!(neo_hookean_radial(RI, RO, LAMBDA, MU, RHO, f64::NAN).is_err());
        let s = neo_hookean_radial(RI, RO, LAMBDA, MU, RHO, 0.0).expect("zero spin");
        assert_eq!(s.u(1.5), 0.0);
        assert!(s.u(3.0).is_nan());
    }

    #[test]
    fn spin_beyond_limit_point_is_error() {
        // For these moduli the equilibrium branch has a limit point between
        // omega = 165 and 170 rad/s (P_R(Ro) has a negative maximum in r'(Ri)).
        let e = neo_hookean_radial(RI, RO, LAMBDA, MU, RHO, 200.0);
        eprintln!("omega=200: {:?}", e.as_ref().map(|s| s.u(RO)));
        assert!(e.is_err());
        assert!(neo_hookean_radial(RI, RO, LAMBDA, MU, RHO, 160.0).is_ok());
    }
}
