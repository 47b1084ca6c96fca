//! The shared finite-difference check of a [`Hyperelastic`] law.
//!
//! Derivatives are taken with the fourth-order central stencil
//!
//! ```text
//! g'(x) ≈ [−g(x + 2h) + 8 g(x + h) − 8 g(x − h) + g(x − 2h)] / (12 h)
//! ```
//!
//! component by component in `∇u`: energy → stress and stress → tangent. Its truncation error is
//! `O(h⁴)` and its rounding error `O(ε/h)`, so a step `h ≈ 1e-3` gives errors around `1e-11`.
//! The step is scaled by `min(1, J/|F|)`, a lower bound of the smallest singular value of `F`,
//! so that the stencil never reaches `J ≤ 0`.
//!
//! Errors are relative, in the Frobenius norm:
//! - `stress_rel_err = max(|P − P_fd|, |P_st − P|) / s`, where `P` comes from `stress`, `P_st`
//!   from `stress_tangent`, and the stress scale is `s = max(|P|, |A|·h)` (so that a stress-free
//!   state is measured against the stress change the stencil probes, not against rounding noise);
//! - `tangent_rel_err = |A − A_fd| / |A|`.
//!
//! An inadmissible state (`J ≤ 0`) or any non-finite value gives `+∞` errors (never `NaN`).
//!
//! # Stateful laws
//!
//! [`check_stateful`] checks a [`Constitutive`] law over one step: given the committed state
//! and `Δt`, the end-of-step stress `P(∇u)` is a function of the end-of-step `∇u` alone, and its
//! algorithmic tangent is compared with the same stencil applied to that function (each
//! stencil evaluation starts again from the committed state; the new states are discarded).
//! The stress error compares `P` with and without the tangent flag and, when the law has a
//! free energy, with the derivative of `ψ(∇u, state)` at the internal state frozen at the
//! end-of-step value (`P = ∂ψ/∂F` at fixed internal variables). [`SplitMix`] is the small
//! deterministic generator the property tests draw random strains, states and steps from.

use super::{Constitutive, Hyperelastic};
use crate::math::{det_identity_plus_minus_one, flatten, v, Mat2, Tangent, Tensor};

/// Relative errors of a material's stress and tangent against finite differences.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FdReport {
    /// Relative error of `P` against the finite-difference derivative of the energy.
    pub stress_rel_err: f64,
    /// Relative error of `A = ∂P/∂F` against the finite-difference derivative of the stress.
    pub tangent_rel_err: f64,
}

/// Base step of the stencil, before scaling by `min(1, J/|F|)`.
const BASE_STEP: f64 = 1e-3;

/// Fourth-order central difference of `g` in the direction `e` at `x`.
#[inline]
fn central4<X: Tensor, T>(g: impl Fn(&X) -> T, x: &X, e: &X, h: f64) -> T
where
    T: std::ops::Add<Output = T> + std::ops::Sub<Output = T> + std::ops::Mul<f64, Output = T>,
{
    let gp1 = g(&(*x + *e * h));
    let gm1 = g(&(*x - *e * h));
    let gp2 = g(&(*x + *e * (2.0 * h)));
    let gm2 = g(&(*x - *e * (2.0 * h)));
    ((gp1 - gm1) * 8.0 - (gp2 - gm2)) * (1.0 / (12.0 * h))
}

/// Unit tensor `e_kL` with a one in component `(k, l)`.
#[inline]
fn unit<X: Tensor>(k: usize, l: usize) -> X {
    let mut e = X::zero();
    e[(k, l)] = 1.0;
    e
}

/// `num / den` mapped to `+∞` when it is not finite (or `NaN`).
#[inline]
fn finite_ratio(num: f64, den: f64) -> f64 {
    let r = num / den;
    if r.is_finite() {
        r
    } else {
        f64::INFINITY
    }
}

/// Checks `stress` against the energy and `stress_tangent` against the stress, by central
/// differences at `grad_u` (a `Mat2` in plane strain or a `Mat3`). See the module docs for the
/// step and the error measures.
pub fn check_material<X: Tensor, M: Hyperelastic<X> + ?Sized>(m: &M, grad_u: &X) -> FdReport {
    let inadmissible = FdReport {
        stress_rel_err: f64::INFINITY,
        tangent_rel_err: f64::INFINITY,
    };
    let j = 1.0 + grad_u.det_ipm1();
    let f_norm = (X::eye() + *grad_u).frob();
    if !(j > 0.0 && f_norm.is_finite()) {
        return inadmissible;
    }
    let h = BASE_STEP * (j / f_norm).min(1.0);

    let p = m.stress(grad_u);
    let (p_st, a) = m.stress_tangent(grad_u);

    let mut p_fd = X::zero();
    let mut a_fd = X::tangent_zero();
    for k in 0..X::D {
        for l in 0..X::D {
            let e = unit::<X>(k, l);
            p_fd[(k, l)] = central4(|g| m.energy(g), grad_u, &e, h);
            let dp = central4(|g| m.stress(g), grad_u, &e, h);
            for i in 0..X::D {
                for jj in 0..X::D {
                    a_fd[(X::flat(i, jj), X::flat(k, l))] = dp[(i, jj)];
                }
            }
        }
    }

    let a_norm = X::tangent_frob(&a);
    let stress_scale = p.frob().max(a_norm * h);
    let stress_err = (p - p_fd).frob().max((p_st - p).frob());
    FdReport {
        stress_rel_err: finite_ratio(stress_err, stress_scale),
        tangent_rel_err: finite_ratio(X::tangent_frob(&(a - a_fd)), a_norm),
    }
}

/// Checks the end-of-step stress and algorithmic tangent of a stateful law at `grad_u`, from
/// the committed state `old` over a step `dt` (see the module docs).
pub fn check_stateful<M: Constitutive + ?Sized>(
    m: &M,
    grad_u: &Mat2,
    old: &[f64],
    dt: f64,
) -> FdReport {
    let inadmissible = FdReport {
        stress_rel_err: f64::INFINITY,
        tangent_rel_err: f64::INFINITY,
    };
    let j = 1.0 + det_identity_plus_minus_one(grad_u);
    let f_norm = (Mat2::identity() + grad_u).norm();
    if !(j > 0.0 && f_norm.is_finite()) || old.len() != m.n_state() {
        return inadmissible;
    }
    let h = BASE_STEP * (j / f_norm).min(1.0);
    let mut new = vec![0.0; old.len()];
    let mut scratch = vec![0.0; old.len()];
    let (p, _) = m.update(grad_u, old, dt, &mut new, false);
    let (p_st, a) = m.update(grad_u, old, dt, &mut scratch, true);
    let mut stress_err = (p_st - p).norm();
    let state_err = new
        .iter()
        .zip(&scratch)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let mut a_fd = Tangent::zeros();
    let mut p_fd = Mat2::zeros();
    let has_energy = m.free_energy(grad_u, &new).is_some();
    for k in 0..2 {
        for l in 0..2 {
            let e = unit(k, l);
            let dp = flatten(&central4(
                |g| m.update(g, old, dt, &mut scratch.clone(), false).0,
                grad_u,
                &e,
                h,
            ));
            a_fd.set_column(v(k, l), &dp);
            if has_energy {
                p_fd[(k, l)] = central4(
                    |g| m.free_energy(g, &new).unwrap_or(f64::NAN),
                    grad_u,
                    &e,
                    h,
                );
            }
        }
    }
    let a_norm = a.norm();
    let stress_scale = p.norm().max(a_norm * h);
    if has_energy {
        stress_err = stress_err.max((p - p_fd).norm());
    }
    if state_err > 0.0 {
        stress_err = f64::INFINITY;
    }
    FdReport {
        stress_rel_err: finite_ratio(stress_err, stress_scale),
        tangent_rel_err: finite_ratio((a - a_fd).norm(), a_norm),
    }
}

/// SplitMix64: a small deterministic generator for property tests (uniform in [0, 1)).
#[derive(Clone, Debug)]
pub struct SplitMix(pub u64);

impl SplitMix {
    /// Next uniform value in [0, 1).
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Relative deviation from major symmetry, `|A − Aᵀ| / |A|` (0 for `A = 0`, `+∞` if not finite).
pub fn tangent_asymmetry(a: &Tangent) -> f64 {
    let asym = (a - a.transpose()).norm();
    if asym == 0.0 {
        0.0
    } else {
        finite_ratio(asym, a.norm())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::NeoHookean;

    /// A law with a deliberately wrong stress (and a consistent tangent of that wrong stress):
    /// the checker must flag the stress error but not the tangent.
    struct ScaledStress(NeoHookean, f64);

    impl Hyperelastic for ScaledStress {
        fn energy(&self, grad_u: &Mat2) -> f64 {
            self.0.energy(grad_u)
        }
        fn stress(&self, grad_u: &Mat2) -> Mat2 {
            self.0.stress(grad_u) * self.1
        }
        fn stress_tangent(&self, grad_u: &Mat2) -> (Mat2, Tangent) {
            let (p, a) = self.0.stress_tangent(grad_u);
            (p * self.1, a * self.1)
        }
    }

    /// A law whose tangent misses one term: the checker must flag the tangent.
    struct BrokenTangent(NeoHookean);

    impl Hyperelastic for BrokenTangent {
        fn energy(&self, grad_u: &Mat2) -> f64 {
            self.0.energy(grad_u)
        }
        fn stress(&self, grad_u: &Mat2) -> Mat2 {
            self.0.stress(grad_u)
        }
        fn stress_tangent(&self, grad_u: &Mat2) -> (Mat2, Tangent) {
            let (p, mut a) = self.0.stress_tangent(grad_u);
            a[(v(0, 1), v(1, 0))] += 1e-3 * a.norm();
            (p, a)
        }
    }

    const GRAD: Mat2 = Mat2::new(0.1, 0.2, -0.05, 0.15);

    #[test]
    fn detects_wrong_stress() {
        let good = NeoHookean::new(1.0, 3.0);
        let r = check_material(&good, &GRAD);
        assert!(r.stress_rel_err < 1e-9 && r.tangent_rel_err < 1e-9, "{r:?}");
        // Relative error of P' = 1.01 P against P is 0.01/1.01.
        let bad = check_material(&ScaledStress(good, 1.01), &GRAD);
        assert!((bad.stress_rel_err - 0.01 / 1.01).abs() < 1e-9, "{bad:?}");
        assert!(bad.tangent_rel_err < 1e-9, "{bad:?}");
    }

    #[test]
    fn detects_wrong_tangent() {
        let r = check_material(&BrokenTangent(NeoHookean::new(1.0, 3.0)), &GRAD);
        assert!(r.stress_rel_err < 1e-9, "{r:?}");
        assert!(r.tangent_rel_err > 5e-4, "{r:?}");
    }

    #[test]
    fn inadmissible_state_reports_infinity() {
        let m = NeoHookean::new(1.0, 3.0);
        for g in [
            Mat2::new(-1.0, 0.0, 0.0, 0.0),
            Mat2::new(-2.0, 0.0, 0.0, 0.0),
            Mat2::repeat(f64::NAN),
        ] {
            let r = check_material(&m, &g);
            assert_eq!(r.stress_rel_err, f64::INFINITY);
            assert_eq!(r.tangent_rel_err, f64::INFINITY);
        }
    }

    #[test]
    fn step_stays_admissible_near_singular_f() {
        // J = 1e-3: the scaled step keeps the whole stencil at J > 0.
        let g = Mat2::new(-0.999, 0.0, 0.0, 0.0);
        let r = check_material(&NeoHookean::new(1.0, 3.0), &g);
        assert!(r.stress_rel_err < 1e-6 && r.tangent_rel_err < 1e-6, "{r:?}");
    }

    #[test]
    fn asymmetry_measure() {
        let mut a = Tangent::identity();
        assert_eq!(tangent_asymmetry(&a), 0.0);
        a[(0, 1)] = 1.0;
        assert!(tangent_asymmetry(&a) > 0.5);
        assert_eq!(tangent_asymmetry(&Tangent::zeros()), 0.0);
        assert_eq!(tangent_asymmetry(&Tangent::repeat(f64::NAN)), f64::INFINITY);
    }

    /// An overstress law whose tangent drops the history-dependent part `dF S_v`: the stateful
    /// check must flag it once the state carries stress, and pass the correct law.
    struct DropsGeometric(crate::material::ViscoelasticMaterial);

    impl Constitutive for DropsGeometric {
        fn n_state(&self) -> usize {
            self.0.n_state()
        }
        fn update(
            &self,
            g: &Mat2,
            old: &[f64],
            dt: f64,
            new: &mut [f64],
            with_tangent: bool,
        ) -> (Mat2, Tangent) {
            let (p, mut a) = self.0.update(g, old, dt, new, with_tangent);
            if with_tangent {
                // Remove e_kL S_v: recover S_v = F⁻¹ (P − P_elastic).
                let f = Mat2::identity() + g;
                let pe = self.0.elastic.stress(g);
                let sv = f.try_inverse().unwrap() * (p - pe);
                for k in 0..2 {
                    for l in 0..2 {
                        for jj in 0..2 {
                            a[(v(k, jj), v(k, l))] -= sv[(l, jj)];
                        }
                    }
                }
            }
            (p, a)
        }
        fn free_energy(&self, _g: &Mat2, _s: &[f64]) -> Option<f64> {
            None
        }
    }

    #[test]
    fn stateful_check_detects_a_missing_history_term() {
        use crate::material::{ViscoModel, Viscoelastic, ViscoelasticMaterial};
        let visco = Viscoelastic::new(ViscoModel::Convolution, 2.0, &[(1.0, 0.5)]).unwrap();
        let m = ViscoelasticMaterial {
            elastic: NeoHookean::new(1.0, 3.0).into(),
            visco,
        };
        // A state with stress in it: one step to GRAD.
        let mut s1 = vec![0.0; 6];
        m.update(&GRAD, &[0.0; 6], 0.1, &mut s1, false);
        let good = check_stateful(&m, &(GRAD * 0.5), &s1, 0.2);
        assert!(
            good.stress_rel_err < 1e-9 && good.tangent_rel_err < 1e-8,
            "{good:?}"
        );
        let bad = check_stateful(&DropsGeometric(m), &(GRAD * 0.5), &s1, 0.2);
        assert!(bad.tangent_rel_err > 1e-3, "{bad:?}");
        // Elastic laws are stateless constitutive laws and pass the same check.
        let e = check_stateful(&NeoHookean::new(1.0, 3.0), &GRAD, &[], 0.3);
        assert!(e.stress_rel_err < 1e-9 && e.tangent_rel_err < 1e-9, "{e:?}");
        // A state of the wrong length is reported, not a panic.
        assert_eq!(
            check_stateful(&m, &GRAD, &[0.0; 3], 0.1).tangent_rel_err,
            f64::INFINITY
        );
    }

    #[test]
    fn splitmix_is_uniform_enough() {
        let mut r = SplitMix(1);
        let xs: Vec<f64> = (0..10000).map(|_| r.next()).collect();
        assert!(xs.iter().all(|x| (0.0..1.0).contains(x)));
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        assert!((mean - 0.5).abs() < 0.02, "{mean}");
    }
}
