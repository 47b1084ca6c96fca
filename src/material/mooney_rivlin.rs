//! Compressible Mooney–Rivlin law with isochoric invariants (plane strain).
//!
//! ```text
//! W = c1 (Ī1 − 3) + c2 (Ī2 − 3) + κ/2 (J − 1)²,    Ī1 = J^(−2/3) I1,  Ī2 = J^(−4/3) I2
//! ```
//!
//! with the 3D invariants of plane strain, `I1 = F:F + 1`, `I2 = F:F + J²`. In invariant form
//!
//! ```text
//! W1 = c1 J^(−2/3),  W2 = c2 J^(−4/3),  WJ = −2/3 c1 J^(−5/3) I1 − 4/3 c2 J^(−7/3) I2 + κ (J − 1)
//! W1J = −2/3 c1 J^(−5/3),  W2J = −4/3 c2 J^(−7/3),
//! WJJ = 10/9 c1 J^(−8/3) I1 + 28/9 c2 J^(−10/3) I2 + κ,   W11 = W12 = W22 = 0
//! ```
//!
//! and the identity coefficient of `P = s0 I + a ∇u + b cof ∇u` in cancellation-free form
//!
//! ```text
//! s0 = 2 c1 J^(−5/3) [(J − 1) − (I1 − 3)/3] + 2 c2 J^(−7/3) [(J − 1)(J + 2) − 2/3 (I2 − 3)] + κ (J − 1).
//! ```
//!
//! Small-strain limit: shear modulus `G = 2(c1 + c2)`, bulk modulus `κ`, i.e. plane-strain
//! linear elasticity with `μ = G`, `λ = κ − 2G/3`.

use super::invariants::{
    inadmissible_stress, inadmissible_tangent, stress_from_invariants,
    stress_tangent_from_invariants, InvariantDerivs, InvariantTensor, Kinematics,
};
use super::{Bound, Hyperelastic, MaterialLawSpec, ParamSpec};
use crate::math::{Mat2, Tensor};

/// Compressible Mooney–Rivlin law `c1 (Ī1 − 3) + c2 (Ī2 − 3) + κ/2 (J − 1)²`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MooneyRivlin {
    /// Coefficient of `Ī1 − 3`.
    pub c1: f64,
    /// Coefficient of `Ī2 − 3`.
    pub c2: f64,
    /// Bulk modulus `κ`.
    pub kappa: f64,
}

impl MooneyRivlin {
    /// Law with coefficients `c1`, `c2` and bulk modulus `kappa`.
    pub fn new(c1: f64, c2: f64, kappa: f64) -> Self {
        Self { c1, c2, kappa }
    }

    /// Invariant derivatives at an admissible point (`J > 0`).
    #[inline]
    fn derivs<T: Tensor>(&self, k: &Kinematics<T>) -> InvariantDerivs {
        let (c1, c2, kappa) = (self.c1, self.c2, self.kappa);
        let ln_j = k.ln_j();
        let j_pow = |e: f64| (e * ln_j).exp();
        let (jm23, jm43) = (j_pow(-2.0 / 3.0), j_pow(-4.0 / 3.0));
        let (jm53, jm73) = (jm23 / k.j, jm43 / k.j);
        let (jm83, jm103) = (jm53 / k.j, jm73 / k.j);
        let i1 = 3.0 + k.i1m3;
        let i2 = 3.0 + k.i2m3;

        let w1j = -2.0 / 3.0 * c1 * jm53;
        let w2j = -4.0 / 3.0 * c2 * jm73;
        let wj = w1j * i1 + w2j * i2 + kappa * k.jm1;
        let wjj = 10.0 / 9.0 * c1 * jm83 * i1 + 28.0 / 9.0 * c2 * jm103 * i2 + kappa;
        let s0 = 2.0 * c1 * jm53 * (k.jm1 - k.i1m3 / 3.0)
            + 2.0 * c2 * jm73 * (k.jm1 * (k.jm1 + 3.0) - 2.0 / 3.0 * k.i2m3)
            + kappa * k.jm1;
        InvariantDerivs {
            d1: [c1 * jm23, c2 * jm43, wj],
            d2: [[0.0, 0.0, w1j], [0.0, 0.0, w2j], [w1j, w2j, wjj]],
            s0,
        }
    }
}

impl MooneyRivlin {
    /// Out-of-plane Cauchy stress σ33 (plane strain, `F33 = 1`); NaN when `J ≤ 0`.
    pub fn cauchy_33(&self, grad_u: &Mat2) -> f64 {
        let k = Kinematics::new(grad_u);
        if !k.is_admissible() {
            return f64::NAN;
        }
        super::invariants::sigma33_from_invariants(&k, &self.derivs(&k))
    }
}

/// Mooney–Rivlin C1, a parameter of both Mooney–Rivlin laws.
pub(crate) const C1: ParamSpec = ParamSpec {
    key: "c1",
    what: "Mooney–Rivlin C1",
    unit: "F/L²",
    bound: Bound::Above(0.0),
    note: "",
};

/// Mooney–Rivlin C2, a parameter of both Mooney–Rivlin laws.
pub(crate) const C2: ParamSpec = ParamSpec {
    key: "c2",
    what: "Mooney–Rivlin C2",
    unit: "F/L²",
    bound: Bound::AtLeast(0.0),
    note: "may be 0",
};

impl MaterialLawSpec for MooneyRivlin {
    const NAME: &'static str = "mooney_rivlin";
    const SUMMARY: &'static str =
        "compressible Mooney–Rivlin c1 (Ī1 − 3) + c2 (Ī2 − 3) + κ/2 (J − 1)²";
    const PARAMS: &'static [ParamSpec] = &[
        C1,
        C2,
        ParamSpec {
            key: "kappa",
            what: "bulk modulus",
            unit: "F/L²",
            bound: Bound::Above(0.0),
            note: "",
        },
    ];

    fn from_values(v: &[f64]) -> Self {
        Self::new(v[0], v[1], v[2])
    }

    fn values(&self) -> Vec<f64> {
        vec![self.c1, self.c2, self.kappa]
    }

    fn shear_modulus(&self) -> f64 {
        2.0 * (self.c1 + self.c2)
    }

    fn bulk_modulus(&self) -> Option<f64> {
        Some(self.kappa)
    }

    fn cauchy_33(&self, grad_u: &Mat2) -> f64 {
        MooneyRivlin::cauchy_33(self, grad_u)
    }
}

impl<T: InvariantTensor> Hyperelastic<T> for MooneyRivlin {
    fn energy(&self, grad_u: &T) -> f64 {
        let k = Kinematics::new(grad_u);
        if !k.is_admissible() {
            return f64::INFINITY;
        }
        let ln_j = k.ln_j();
        // Ī − 3 = J^e (I − 3) + 3 (J^e − 1), with J^e − 1 = expm1(e ln J).
        let iso = |e: f64, im3: f64| (e * ln_j).exp() * im3 + 3.0 * (e * ln_j).exp_m1();
        self.c1 * iso(-2.0 / 3.0, k.i1m3)
            + self.c2 * iso(-4.0 / 3.0, k.i2m3)
            + 0.5 * self.kappa * k.jm1 * k.jm1
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
    use crate::material::MooneyRivlinIncompressible;

    /// The paper's rubber (C1 = 80, C2 = 20 psi) with κ = 10 G, and a c2-dominated variant.
    const LAWS: [MooneyRivlin; 3] = [
        MooneyRivlin {
            c1: 80.0,
            c2: 20.0,
            kappa: 2000.0,
        },
        MooneyRivlin {
            c1: 0.1,
            c2: 0.7,
            kappa: 2.5,
        },
        MooneyRivlin {
            c1: 0.0,
            c2: 1.0,
            kappa: 1.0,
        },
    ];

    #[test]
    fn fd_symmetry_objectivity_inadmissible() {
        for m in LAWS {
            let (es, et) = assert_fd_consistent(&m);
            let asym = assert_tangent_symmetric(&m);
            let obj = assert_objective(&m);
            assert_inadmissible_safe(&m);
            println!(
                "{m:?}: fd stress {es:.2e}, fd tangent {et:.2e}, asym {asym:.2e}, obj {obj:.2e}"
            );
        }
    }

    #[test]
    fn small_strain_limit_is_linear_elasticity() {
        for m in LAWS {
            let g = 2.0 * (m.c1 + m.c2);
            let [e8, e12] = assert_small_strain_linear(&m, m.kappa - 2.0 / 3.0 * g, g);
            println!("{m:?} small strain: rel err {e8:.2e} at 1e-8, {e12:.2e} at 1e-12");
        }
    }

    #[test]
    fn energy_matches_direct_3d_formula() {
        for m in LAWS {
            for g in sample_grads() {
                let f = Mat2::identity() + g;
                let c = f.transpose() * f;
                let j = f.determinant();
                let i1 = c.trace() + 1.0;
                let i2 = 0.5 * (i1 * i1 - ((c * c).trace() + 1.0));
                let w = m.c1 * (j.powf(-2.0 / 3.0) * i1 - 3.0)
                    + m.c2 * (j.powf(-4.0 / 3.0) * i2 - 3.0)
                    + 0.5 * m.kappa * (j - 1.0).powi(2);
                let scale = m.c1 + m.c2 + m.kappa;
                assert!(
                    (m.energy(&g) - w).abs() < 1e-13 * scale,
                    "{} vs {w}",
                    m.energy(&g)
                );
            }
        }
    }

    #[test]
    fn isochoric_motion_matches_unconstrained_law_up_to_a_pressure() {
        // At J = 1, Ī1 = I1 and Ī2 = I2: the energy equals c1 (I1 − 3) + c2 (I2 − 3), and the
        // stresses differ only by WJ cof F with WJ = −2/3 c1 I1 − 4/3 c2 I2.
        for m in LAWS {
            let unconstrained = MooneyRivlinIncompressible::new(m.c1, m.c2);
            for g in [
                Mat2::new(0.0, 0.4, 0.0, 0.0),
                Mat2::new(0.25, 0.0, 0.0, 1.0 / 1.25 - 1.0),
                rotation(0.4) * Mat2::new(1.0, -0.3, 0.0, 1.0) - Mat2::identity(),
            ] {
                let k = Kinematics::new(&g);
                assert!(k.jm1.abs() < 1e-15);
                let scale = m.c1 + m.c2;
                assert!((m.energy(&g) - unconstrained.energy(&g)).abs() < 1e-13 * scale);
                let wj = -2.0 / 3.0 * m.c1 * (3.0 + k.i1m3) - 4.0 / 3.0 * m.c2 * (3.0 + k.i2m3);
                let diff = m.stress(&g) - unconstrained.stress(&g) - k.cof * wj;
                assert!(diff.norm() < 1e-13 * scale, "{diff}");
            }
        }
    }
}
