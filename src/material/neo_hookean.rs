//! Compressible neo-Hookean law (plane strain).
//!
//! ```text
//! W = μ/2 (I1 − 3) − μ ln J + λ/2 (ln J)²,     I1 − 3 = F:F − 2 (plane strain)
//! P = μ (F − F⁻ᵀ) + λ ln J F⁻ᵀ
//! ```
//!
//! In invariant form `W1 = μ/2`, `W2 = 0`, `WJ = (λ ln J − μ)/J`, `WJJ = (λ + μ − λ ln J)/J²`,
//! and the identity coefficient of `P = s0 I + a ∇u + b cof ∇u` is `s0 = (μ (J − 1) + λ ln J)/J`,
//! exact at small strain since `J − 1` and `ln J = ln_1p(J − 1)` are. The small-strain limit is
//! linear elasticity with Lamé constants `μ`, `λ` (3D bulk modulus `λ + 2μ/3`).

use super::invariants::{
    inadmissible_stress, inadmissible_tangent, stress_from_invariants,
    stress_tangent_from_invariants, InvariantDerivs, InvariantTensor, Kinematics,
};
use super::{Bound, Hyperelastic, MaterialLawSpec, ParamSpec};
use crate::math::{Mat2, Tensor};

/// Compressible neo-Hookean law with Lamé-like constants `mu`, `lambda`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NeoHookean {
    /// Shear modulus `μ`.
    pub mu: f64,
    /// First Lamé constant `λ`.
    pub lambda: f64,
}

impl NeoHookean {
    /// Law with shear modulus `mu` and first Lamé constant `lambda`.
    pub fn new(mu: f64, lambda: f64) -> Self {
        Self { mu, lambda }
    }

    /// Invariant derivatives at an admissible point (`J > 0`).
    #[inline]
    fn derivs<T: Tensor>(&self, k: &Kinematics<T>) -> InvariantDerivs {
        let (mu, lambda) = (self.mu, self.lambda);
        let ln_j = k.ln_j();
        let inv_j = 1.0 / k.j;
        let wj = (lambda * ln_j - mu) * inv_j;
        let wjj = (lambda + mu - lambda * ln_j) * inv_j * inv_j;
        InvariantDerivs {
            d1: [0.5 * mu, 0.0, wj],
            d2: [[0.0; 3], [0.0; 3], [0.0, 0.0, wjj]],
            s0: (mu * k.jm1 + lambda * ln_j) * inv_j,
        }
    }
}

impl NeoHookean {
    /// Out-of-plane Cauchy stress σ33 (plane strain, `F33 = 1`); NaN when `J ≤ 0`.
    pub fn cauchy_33(&self, grad_u: &Mat2) -> f64 {
        let k = Kinematics::new(grad_u);
        if !k.is_admissible() {
            return f64::NAN;
        }
        super::invariants::sigma33_from_invariants(&k, &self.derivs(&k))
    }
}

impl MaterialLawSpec for NeoHookean {
    const NAME: &'static str = "neo_hookean";
    const SUMMARY: &'static str = "compressible neo-Hookean μ/2 (I1 − 3) − μ ln J + λ/2 (ln J)²";
    const PARAMS: &'static [ParamSpec] = &[
        ParamSpec {
            key: "mu",
            what: "Lamé shear modulus",
            unit: "F/L²",
            bound: Bound::Above(0.0),
            note: "",
        },
        ParamSpec {
            key: "lambda",
            what: "Lamé first parameter",
            unit: "F/L²",
            bound: Bound::Above(0.0),
            note: "",
        },
    ];

    fn from_values(v: &[f64]) -> Self {
        Self::new(v[0], v[1])
    }

    fn values(&self) -> Vec<f64> {
        vec![self.mu, self.lambda]
    }

    fn shear_modulus(&self) -> f64 {
        self.mu
    }

    fn bulk_modulus(&self) -> Option<f64> {
        Some(self.lambda + 2.0 / 3.0 * self.mu)
    }

    fn cauchy_33(&self, grad_u: &Mat2) -> f64 {
        NeoHookean::cauchy_33(self, grad_u)
    }
}

impl<T: InvariantTensor> Hyperelastic<T> for NeoHookean {
    fn energy(&self, grad_u: &T) -> f64 {
        let k = Kinematics::new(grad_u);
        if !k.is_admissible() {
            return f64::INFINITY;
        }
        let ln_j = k.ln_j();
        0.5 * self.mu * k.i1m3 - self.mu * ln_j + 0.5 * self.lambda * ln_j * ln_j
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

#[cfg(test)]
mod tests {
    use super::super::test_util::*;
    use super::*;

    const M: NeoHookean = NeoHookean {
        mu: 1.5,
        lambda: 4.0,
    };

    #[test]
    fn fd_symmetry_objectivity_inadmissible() {
        let (es, et) = assert_fd_consistent(&M);
        let asym = assert_tangent_symmetric(&M);
        let obj = assert_objective(&M);
        assert_inadmissible_safe(&M);
        println!(
            "NeoHookean: fd stress {es:.2e}, fd tangent {et:.2e}, asym {asym:.2e}, obj {obj:.2e}"
        );
    }

    #[test]
    fn small_strain_limit_is_linear_elasticity() {
        let [e8, e12] = assert_small_strain_linear(&M, M.lambda, M.mu);
        println!("NeoHookean small strain: rel err {e8:.2e} at 1e-8, {e12:.2e} at 1e-12");
    }

    #[test]
    fn stress_matches_closed_form() {
        for g in sample_grads() {
            let f = Mat2::identity() + g;
            let j = f.determinant();
            let f_inv_t = f.try_inverse().unwrap().transpose();
            let closed = (f - f_inv_t) * M.mu + f_inv_t * (M.lambda * j.ln());
            let p = M.stress(&g);
            assert!(
                (p - closed).norm() < 1e-13 * closed.norm().max(M.mu),
                "{p} vs {closed}"
            );
            let c = f.transpose() * f;
            let w =
                0.5 * M.mu * (c.trace() - 2.0) - M.mu * j.ln() + 0.5 * M.lambda * j.ln().powi(2);
            assert!((M.energy(&g) - w).abs() < 1e-13 * M.mu);
        }
    }
}
