//! Compressible Yeoh law with the isochoric first invariant (plane strain), the usual fit of
//! filled tread and carcass rubber:
//!
//! ```text
//! W = c10 x + c20 x² + c30 x³ + κ/2 (J − 1)²,    x = Ī1 − 3,  Ī1 = J^(−2/3) I1
//! ```
//!
//! with the 3D invariant of plane strain `I1 = F:F + 1`. Writing `w(x) = c10 x + c20 x² + c30 x³`,
//! `w' = c10 + 2 c20 x + 3 c30 x²`, `w'' = 2 c20 + 6 c30 x`, `∂x/∂I1 = J^(−2/3)` and
//! `∂x/∂J = −2/3 J^(−5/3) I1`, the invariant derivatives are
//!
//! ```text
//! W1 = w' J^(−2/3),     WJ = −2/3 w' J^(−5/3) I1 + κ (J − 1),     W2 = 0
//! W11 = w'' J^(−4/3),   W1J = −2/3 J^(−5/3) (w'' J^(−2/3) I1 + w')
//! WJJ = 4/9 w'' J^(−10/3) I1² + 10/9 w' J^(−8/3) I1 + κ
//! ```
//!
//! and the identity coefficient of `P = s0 I + a ∇u + b cof ∇u` in cancellation-free form
//! `s0 = 2 w' J^(−5/3) [(J − 1) − (I1 − 3)/3] + κ (J − 1)`. `x` itself is formed as
//! `3 (J^(−2/3) − 1) + J^(−2/3) (I1 − 3)`, both parts without cancellation.
//!
//! Small-strain limit: shear modulus `G = 2 c10`, bulk modulus `κ`. With `c20 = c30 = 0` the law
//! is the compressible Mooney–Rivlin law with `c1 = c10`, `c2 = 0`. `c20` is commonly negative
//! (softening at moderate strain) and `c30` positive (stiffening at large strain); the law is
//! stable only where `w' > 0`.

use super::invariants::{
    inadmissible_stress, inadmissible_tangent, stress_from_invariants,
    stress_tangent_from_invariants, InvariantDerivs, InvariantTensor, Kinematics,
};
use super::{Bound, Hyperelastic, MaterialLawSpec, ParamSpec};
use crate::math::{Mat2, Tensor};

/// Compressible Yeoh law `c10 x + c20 x² + c30 x³ + κ/2 (J − 1)²`, `x = Ī1 − 3`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Yeoh {
    pub c10: f64,
    pub c20: f64,
    pub c30: f64,
    /// Bulk modulus `κ`.
    pub kappa: f64,
}

impl Yeoh {
    /// Law with coefficients `c10`, `c20`, `c30` and bulk modulus `kappa`.
    pub fn new(c10: f64, c20: f64, c30: f64, kappa: f64) -> Self {
        Self {
            c10,
            c20,
            c30,
            kappa,
        }
    }

    /// `(x, J^(−2/3))` with `x = Ī1 − 3`.
    #[inline]
    fn x<T: Tensor>(k: &Kinematics<T>) -> (f64, f64) {
        let e = -2.0 / 3.0 * k.ln_j();
        let jm23 = e.exp();
        (3.0 * e.exp_m1() + jm23 * k.i1m3, jm23)
    }

    /// Invariant derivatives at an admissible point (`J > 0`).
    #[inline]
    fn derivs<T: Tensor>(&self, k: &Kinematics<T>) -> InvariantDerivs {
        let (x, jm23) = Self::x(k);
        let w1 = self.c10 + x * (2.0 * self.c20 + 3.0 * self.c30 * x);
        let w2 = 2.0 * self.c20 + 6.0 * self.c30 * x;
        let jm53 = jm23 / k.j;
        let i1 = 3.0 + k.i1m3;
        let w1j = -2.0 / 3.0 * jm53 * (w2 * jm23 * i1 + w1);
        let wjj =
            4.0 / 9.0 * w2 * jm53 * jm53 * i1 * i1 + 10.0 / 9.0 * w1 * jm53 / k.j * i1 + self.kappa;
        let wj = -2.0 / 3.0 * w1 * jm53 * i1 + self.kappa * k.jm1;
        InvariantDerivs {
            d1: [w1 * jm23, 0.0, wj],
            d2: [
                [w2 * jm23 * jm23, 0.0, w1j],
                [0.0, 0.0, 0.0],
                [w1j, 0.0, wjj],
            ],
            s0: 2.0 * w1 * jm53 * (k.jm1 - k.i1m3 / 3.0) + self.kappa * k.jm1,
        }
    }

    /// Out-of-plane Cauchy stress σ33 (plane strain, `F33 = 1`); NaN when `J ≤ 0`.
    pub fn cauchy_33(&self, grad_u: &Mat2) -> f64 {
        let k = Kinematics::new(grad_u);
        if !k.is_admissible() {
            return f64::NAN;
        }
        super::invariants::sigma33_from_invariants(&k, &self.derivs(&k))
    }
}

impl<T: InvariantTensor> Hyperelastic<T> for Yeoh {
    fn energy(&self, grad_u: &T) -> f64 {
        let k = Kinematics::new(grad_u);
        if !k.is_admissible() {
            return f64::INFINITY;
        }
        let (x, _) = Self::x(&k);
        x * (self.c10 + x * (self.c20 + x * self.c30)) + 0.5 * self.kappa * k.jm1 * k.jm1
    }

    fn stress(&self, grad_u: &T) -> T {
        let k = Kinematics::new(grad_u);
        if !k.is_admissible() {
            return inadmissible_stress();
        }
        stress_from_invariants(&k, &self.derivs(&k))
    }

    fn stress_tangent(&self, grad_u: &T) -> (T, T::Tangent) {
        let k = Kinematics::new(grad_u);
        if !k.is_admissible() {
            return (inadmissible_stress(), inadmissible_tangent::<T>());
        }
        stress_tangent_from_invariants(&k, &self.derivs(&k))
    }
}

impl MaterialLawSpec for Yeoh {
    const NAME: &'static str = "yeoh";
    const SUMMARY: &'static str =
        "compressible Yeoh c10 x + c20 x² + c30 x³ + κ/2 (J − 1)², x = Ī1 − 3";
    const PARAMS: &'static [ParamSpec] = &[
        ParamSpec {
            key: "c10",
            what: "Yeoh C10 (half the small-strain shear modulus)",
            unit: "F/L²",
            bound: Bound::Above(0.0),
            note: "",
        },
        ParamSpec {
            key: "c20",
            what: "Yeoh C20",
            unit: "F/L²",
            bound: Bound::Finite,
            note: "often negative",
        },
        ParamSpec {
            key: "c30",
            what: "Yeoh C30",
            unit: "F/L²",
            bound: Bound::Finite,
            note: "",
        },
        ParamSpec {
            key: "kappa",
            what: "bulk modulus",
            unit: "F/L²",
            bound: Bound::Above(0.0),
            note: "",
        },
    ];

    fn from_values(v: &[f64]) -> Self {
        Self::new(v[0], v[1], v[2], v[3])
    }

    fn values(&self) -> Vec<f64> {
        vec![self.c10, self.c20, self.c30, self.kappa]
    }

    fn shear_modulus(&self) -> f64 {
        2.0 * self.c10
    }

    fn bulk_modulus(&self) -> Option<f64> {
        Some(self.kappa)
    }

    fn cauchy_33(&self, grad_u: &Mat2) -> f64 {
        Yeoh::cauchy_33(self, grad_u)
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::*;
    use super::super::MooneyRivlin;
    use super::*;

    /// A tread-compound fit (psi): softening then stiffening.
    fn rubber() -> Yeoh {
        Yeoh::new(80.0, -8.0, 1.5, 20000.0)
    }

    #[test]
    fn stress_and_tangent_match_finite_differences() {
        let (es, et) = assert_fd_consistent(&rubber());
        assert_tangent_symmetric(&rubber());
        assert_objective(&rubber());
        assert_inadmissible_safe(&rubber());
        println!("yeoh: fd stress {es:.2e}, fd tangent {et:.2e}");
    }

    #[test]
    fn small_strain_limit_is_linear_elasticity() {
        let m = rubber();
        let g = 2.0 * m.c10;
        assert_small_strain_linear(&m, m.kappa - 2.0 * g / 3.0, g);
    }

    /// With c20 = c30 = 0 the law is Mooney–Rivlin with c2 = 0, an independent implementation.
    #[test]
    fn first_order_yeoh_is_mooney_rivlin_with_c2_zero() {
        let y = Yeoh::new(80.0, 0.0, 0.0, 2000.0);
        let mr = MooneyRivlin::new(80.0, 0.0, 2000.0);
        for g in sample_grads() {
            let (py, ay) = y.stress_tangent(&g);
            let (pm, am) = mr.stress_tangent(&g);
            assert!((py - pm).norm() <= 1e-12 * pm.norm().max(1.0), "P at {g}");
            assert!((ay - am).norm() <= 1e-12 * am.norm(), "A at {g}");
            let (wy, wm) = (y.energy(&g), mr.energy(&g));
            assert!((wy - wm).abs() <= 1e-12 * wm.abs().max(1.0), "W at {g}");
            assert!((y.cauchy_33(&g) - mr.cauchy_33(&g)).abs() <= 1e-10 * pm.norm().max(1.0));
        }
    }

    /// Simple shear of the nearly incompressible law against the closed form of the
    /// incompressible Yeoh solid, τ = 2 γ w'(γ²) (in simple shear Ī1 − 3 = γ² and J = 1).
    #[test]
    fn simple_shear_matches_the_incompressible_closed_form() {
        let m = rubber();
        for gamma in [0.1, 0.5, 1.0, 2.0] {
            let h = Mat2::new(0.0, gamma, 0.0, 0.0);
            let p = m.stress(&h);
            // Cauchy shear σ12 = (P Fᵀ)12 / J with J = 1.
            let f = Mat2::identity() + h;
            let sigma = p * f.transpose();
            let x: f64 = gamma * gamma;
            let exact = 2.0 * gamma * (m.c10 + 2.0 * m.c20 * x + 3.0 * m.c30 * x * x);
            let err = (sigma[(0, 1)] - exact).abs() / exact.abs();
            assert!(err < 1e-12, "γ = {gamma}: σ12 {} vs {exact}", sigma[(0, 1)]);
        }
    }
}
