//! Incompressible Mooney–Rivlin law and the pressure terms of the mixed (u, p) formulation.
//!
//! The material supplies only the *unconstrained* energy
//!
//! ```text
//! W = c1 (I1 − 3) + c2 (I2 − 3),    I1 = F:F + 1,  I2 = F:F + J²  (plane strain)
//! P = 2(c1 + c2) F + 2 c2 J cof F
//! ```
//!
//! (`W1 = c1`, `W2 = c2`, `WJ = 0`, zero Hessian). The constraint `J = 1` is imposed by the mixed
//! element, which adds `−p (J − 1)` to the energy density; its contributions to `P` and `∂P/∂F` are
//! given by [`pressure_stress_tangent`]: `−p cof F` and `−p ∂cof/∂F`. Here `p` is the Lagrange
//! multiplier, positive in compression (the hydrostatic Cauchy stress is `−p` at `J = 1` when
//! the material part is stress-free).
//!
//! At `F = I` the material stress is **not** zero: `P = (2c1 + 4c2) I`. The reference state is
//! stress-free for the mixed problem with the pressure `p0 = 2c1 + 4c2`, which absorbs it; a
//! pressure field initialised to zero therefore starts from a uniform tension, harmless for Newton
//! (the pressure is linear in the equations) but worth knowing when reading pressure output.
//! With `p = p0 + p̃`, the linearisation at `F = I` for isochoric `∇u` is `2G ε − p̃ I`, with
//! `G = 2(c1 + c2)`.
//!
//! Like every law in [`crate::material`], `energy` is `+∞` and `stress`/`stress_tangent` are `+∞`
//! matrices when `J ≤ 0`, even though the polynomial would be defined there. The pressure
//! helpers below are plain polynomials, defined for every `F`.

use super::invariants::{
    inadmissible_stress, inadmissible_tangent, stress_from_invariants,
    stress_tangent_from_invariants, InvariantDerivs, InvariantTensor, Kinematics,
};
use super::{Hyperelastic, MaterialLawSpec, ParamSpec};
use crate::math::{Mat2, Tensor};

/// Unconstrained part `c1 (I1 − 3) + c2 (I2 − 3)` of the incompressible Mooney–Rivlin law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MooneyRivlinIncompressible {
    /// Coefficient of `I1 − 3`.
    pub c1: f64,
    /// Coefficient of `I2 − 3`.
    pub c2: f64,
}

impl MooneyRivlinIncompressible {
    /// Law with coefficients `c1`, `c2` (small-strain shear modulus `2(c1 + c2)`).
    pub fn new(c1: f64, c2: f64) -> Self {
        Self { c1, c2 }
    }

    /// The pressure `p0 = 2c1 + 4c2` that balances the material stress at `F = I`.
    pub fn reference_pressure(&self) -> f64 {
        2.0 * self.c1 + 4.0 * self.c2
    }

    #[inline]
    fn derivs<T: Tensor>(&self, k: &Kinematics<T>) -> InvariantDerivs {
        InvariantDerivs {
            d1: [self.c1, self.c2, 0.0],
            d2: [[0.0; 3]; 3],
            // 2W1 + 2W2 + 2J W2 + WJ, with J = 1 + (J − 1) kept exact.
            s0: self.reference_pressure() + 2.0 * self.c2 * k.jm1,
        }
    }
}

impl MooneyRivlinIncompressible {
    /// Out-of-plane Cauchy stress σ33 (plane strain, `F33 = 1`); NaN when `J ≤ 0`.
    pub fn cauchy_33(&self, grad_u: &Mat2) -> f64 {
        let k = Kinematics::new(grad_u);
        if !k.is_admissible() {
            return f64::NAN;
        }
        super::invariants::sigma33_from_invariants(&k, &self.derivs(&k))
    }
}

impl MaterialLawSpec for MooneyRivlinIncompressible {
    const NAME: &'static str = "mooney_rivlin_incompressible";
    const SUMMARY: &'static str =
        "incompressible Mooney–Rivlin c1 (I1 − 3) + c2 (I2 − 3), J = 1 by a pressure field";
    const PARAMS: &'static [ParamSpec] = &[super::mooney_rivlin::C1, super::mooney_rivlin::C2];
    const INCOMPRESSIBLE: bool = true;

    fn from_values(v: &[f64]) -> Self {
        Self::new(v[0], v[1])
    }

    fn values(&self) -> Vec<f64> {
        vec![self.c1, self.c2]
    }

    fn shear_modulus(&self) -> f64 {
        2.0 * (self.c1 + self.c2)
    }

    fn bulk_modulus(&self) -> Option<f64> {
        None
    }

    fn cauchy_33(&self, grad_u: &Mat2) -> f64 {
        MooneyRivlinIncompressible::cauchy_33(self, grad_u)
    }
}

impl<T: InvariantTensor> Hyperelastic<T> for MooneyRivlinIncompressible {
    fn energy(&self, grad_u: &T) -> f64 {
        let k = Kinematics::new(grad_u);
        if !k.is_admissible() {
            return f64::INFINITY;
        }
        self.c1 * k.i1m3 + self.c2 * k.i2m3
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

/// Contribution of the constraint term `−p (J − 1)` to `P` and `∂P/∂F`: `(−p cof F, −p ∂cof/∂F)`
/// (in either dimension).
#[inline]
pub fn pressure_stress_tangent<T: InvariantTensor>(grad_u: &T, p: f64) -> (T, T::Tangent) {
    let f = T::eye() + *grad_u;
    (f.cof() * -p, T::dcof(&f) * -p)
}

/// The constraint value `J − 1`, computed from `∇u` without cancellation.
#[inline]
pub fn jm1<T: Tensor>(grad_u: &T) -> f64 {
    grad_u.det_ipm1()
}

#[cfg(test)]
mod tests {
    use super::super::check_material;
    use super::super::test_util::*;
    use super::*;
    use crate::material::dcof_df;
    use crate::math::{cofactor, Tangent};

    const M: MooneyRivlinIncompressible = MooneyRivlinIncompressible { c1: 80.0, c2: 20.0 };

    /// The augmented energy `W − p (J − 1)` at a frozen pressure, to FD-check the pressure terms.
    struct Augmented(MooneyRivlinIncompressible, f64);

    impl Hyperelastic for Augmented {
        fn energy(&self, grad_u: &Mat2) -> f64 {
            self.0.energy(grad_u) - self.1 * jm1(grad_u)
        }
        fn stress(&self, grad_u: &Mat2) -> Mat2 {
            self.stress_tangent(grad_u).0
        }
        fn stress_tangent(&self, grad_u: &Mat2) -> (Mat2, Tangent) {
            let (p, a) = self.0.stress_tangent(grad_u);
            let (pp, ap) = pressure_stress_tangent(grad_u, self.1);
            (p + pp, a + ap)
        }
    }

    #[test]
    fn fd_symmetry_objectivity_inadmissible() {
        let (es, et) = assert_fd_consistent(&M);
        let asym = assert_tangent_symmetric(&M);
        let obj = assert_objective(&M);
        assert_inadmissible_safe(&M);
        println!("MooneyRivlinIncompressible: fd stress {es:.2e}, fd tangent {et:.2e}, asym {asym:.2e}, obj {obj:.2e}");
    }

    #[test]
    fn pressure_terms_match_finite_differences() {
        for p in [M.reference_pressure(), -35.0, 1e3] {
            let aug = Augmented(M, p);
            let (es, et) = assert_fd_consistent(&aug);
            let asym = assert_tangent_symmetric(&aug);
            println!("augmented p = {p}: fd stress {es:.2e}, fd tangent {et:.2e}, asym {asym:.2e}");
        }
    }

    #[test]
    fn reference_stress_is_absorbed_by_the_pressure() {
        let p_ref = M.stress(&Mat2::zeros());
        assert_eq!(p_ref, Mat2::identity() * (2.0 * M.c1 + 4.0 * M.c2));
        assert_eq!(M.energy(&Mat2::zeros()), 0.0);
        let (pp, _) = pressure_stress_tangent(&Mat2::zeros(), M.reference_pressure());
        assert_eq!(p_ref + pp, Mat2::zeros());
    }

    #[test]
    fn small_isochoric_strain_gives_linear_shear_response() {
        let g_mod = 2.0 * (M.c1 + M.c2);
        let aug = Augmented(M, M.reference_pressure());
        for shape in [
            Mat2::new(0.3, -0.7, 0.4, -0.3),
            Mat2::new(0.0, 1.0, 0.0, 0.0),
        ] {
            let h = shape * 1e-6;
            let lin = linear_stress(&h, 0.0, g_mod); // tr ε = 0
            let e = (aug.stress(&h) - lin).norm() / lin.norm();
            assert!(e < 1e-5, "rel err {e}");
        }
    }

    #[test]
    fn stress_matches_closed_form_and_helpers() {
        for g in sample_grads() {
            let f = Mat2::identity() + g;
            let j = f.determinant();
            let closed = f * (2.0 * (M.c1 + M.c2)) + cofactor(&f) * (2.0 * M.c2 * j);
            assert!((M.stress(&g) - closed).norm() < 1e-13 * closed.norm());
            assert!((jm1(&g) - (j - 1.0)).abs() < 1e-15);
            let (pp, ap) = pressure_stress_tangent(&g, 2.0);
            assert_eq!(pp, cofactor(&f) * -2.0);
            assert_eq!(ap, dcof_df() * -2.0);
        }
        // Pressure helpers are plain polynomials: finite at J ≤ 0.
        let (pp, ap) = pressure_stress_tangent(&Mat2::new(-2.0, 0.0, 0.0, 0.0), 1.0);
        assert!(pp.iter().chain(ap.iter()).all(|x| x.is_finite()));
    }

    #[test]
    fn fd_checker_sees_missing_pressure_tangent() {
        // Dropping −p ∂cof/∂F must be caught.
        struct NoDcof(Augmented);
        impl Hyperelastic for NoDcof {
            fn energy(&self, g: &Mat2) -> f64 {
                self.0.energy(g)
            }
            fn stress(&self, g: &Mat2) -> Mat2 {
                self.0.stress(g)
            }
            fn stress_tangent(&self, g: &Mat2) -> (Mat2, Tangent) {
                let (p, a) = self.0.stress_tangent(g);
                (p, a + dcof_df() * (self.0).1)
            }
        }
        let r = check_material(&NoDcof(Augmented(M, 500.0)), &sample_grads()[1]);
        assert!(r.tangent_rel_err > 1e-2, "{r:?}");
    }
}
