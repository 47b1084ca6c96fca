//! Plane-strain kinematics and the chain rule from invariant derivatives to `P` and `∂P/∂F`.
//!
//! With `F = I + H` (`H = ∇u`, 2×2) and `F33 = 1`, the 3D right Cauchy–Green tensor has the
//! eigenvalues `λ1², λ2², 1`, so its invariants are
//!
//! ```text
//! I1 = F:F + 1,        I1 − 3 = 2 tr H + H:H
//! I2 = F:F + J²,       I2 − 3 = (I1 − 3) + (J − 1)(J + 1)
//! J  = det F,          J − 1  = tr H + det H
//! ```
//!
//! All three "minus reference" values are formed from `H` directly, so they carry full relative
//! precision when `|H|` is tiny (no `1 + ε − 1` cancellation).
//!
//! For an energy `W(I1, I2, J)` with partials `W1, W2, WJ` and Hessian `Wab` (a, b ∈ {1, 2, J}):
//!
//! ```text
//! ∂I1/∂F = 2F,   ∂I2/∂F = 2F + 2J cof F,   ∂J/∂F = cof F
//! P = 2(W1 + W2) F + (2J W2 + WJ) cof F  =  s0 I + a H + b cof H,
//!     a = 2(W1 + W2),  b = 2J W2 + WJ,  s0 = a + b
//! A = Σab Wab (∂Ia/∂F ⊗ ∂Ib/∂F) + a 𝕀 + 2 W2 (cof F ⊗ cof F) + b ∂cof/∂F
//! ```
//!
//! where `𝕀` is the 4×4 identity in the flattening of [`crate::math`] and `∂cof/∂F` is the
//! constant tensor returned by [`dcof_df`]. The second form of `P` uses `F = I + H` and the
//! linearity of the 2×2 cofactor, `cof F = I + cof H`. In a stress-free reference `s0` vanishes
//! at `H = 0` and is `O(|H|)` nearby; computing `a + b` in floating point would lose all digits
//! there, so each material supplies `s0` in a cancellation-free closed form
//! ([`InvariantDerivs::s0`]). This is what makes the stress accurate to ~1e-15 relative even at
//! `|∇u| ~ 1e-12`.
//!
//! The tangent is `O(1)` near the reference and has no such cancellation.

use crate::math::{cofactor, det_identity_plus_minus_one, flatten, v, Mat2, Tangent};

/// Out-of-plane Cauchy stress σ33 of plane strain (`F33 = 1`) from the first partials:
/// `∂I1/∂F33 = 2`, `∂I2/∂F33 = 2(I1 − 1)`, `∂J/∂F33 = J`, so
/// `σ33 = P33 / J = (2W1 + 2W2 (I1 − 1)) / J + WJ`.
/// (A pressure field adds `−p`; the caller subtracts it.)
#[inline]
pub fn sigma33_from_invariants(k: &Kinematics, d: &InvariantDerivs) -> f64 {
    let i1 = 3.0 + k.i1m3;
    (2.0 * d.d1[0] + 2.0 * d.d1[1] * (i1 - 1.0)) / k.j + d.d1[2]
}

/// Kinematic quantities of one quadrature point, all derived from `H = ∇u`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kinematics {
    /// Displacement gradient `H = ∇u`.
    pub h: Mat2,
    /// Deformation gradient `F = I + H`.
    pub f: Mat2,
    /// `J = det F`.
    pub j: f64,
    /// `J − 1`, computed without cancellation.
    pub jm1: f64,
    /// `I1 − 3 = 2 tr H + H:H` (3D invariant, plane strain).
    pub i1m3: f64,
    /// `I2 − 3 = (I1 − 3) + (J − 1)(J + 1)` (3D invariant, plane strain).
    pub i2m3: f64,
    /// `cof F = J F⁻ᵀ` (defined for every F).
    pub cof: Mat2,
}

impl Kinematics {
    /// Kinematics of `F = I + grad_u`.
    #[inline]
    pub fn new(grad_u: &Mat2) -> Self {
        let h = *grad_u;
        let f = Mat2::identity() + h;
        let jm1 = det_identity_plus_minus_one(&h);
        let i1m3 = 2.0 * h.trace() + h.norm_squared();
        let i2m3 = i1m3 + jm1 * (2.0 + jm1);
        Self {
            h,
            f,
            j: 1.0 + jm1,
            jm1,
            i1m3,
            i2m3,
            cof: cofactor(&f),
        }
    }

    /// `J > 0` (false for NaN as well).
    #[inline]
    pub fn is_admissible(&self) -> bool {
        self.j > 0.0
    }

    /// `ln J`, accurate for `J` close to 1. `NaN`/`−∞` if `J ≤ 0`: check [`Self::is_admissible`].
    #[inline]
    pub fn ln_j(&self) -> f64 {
        self.jm1.ln_1p()
    }
}

/// Derivatives of an energy `W(I1, I2, J)` at one point, ordered `[I1, I2, J]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InvariantDerivs {
    /// First partials `[W1, W2, WJ]`.
    pub d1: [f64; 3],
    /// Symmetric Hessian `d2[a][b] = ∂²W/∂Ia∂Ib`.
    pub d2: [[f64; 3]; 3],
    /// Coefficient of `I` in `P = s0 I + a H + b cof H`, i.e. `s0 = 2W1 + 2W2 + 2J W2 + WJ`.
    /// It must be evaluated by the material in a form free of cancellation near `F = I` (see the
    /// module docs); [`InvariantDerivs::new`] forms it naively for laws that do not care.
    pub s0: f64,
}

impl InvariantDerivs {
    /// Derivatives with `s0` formed naively as `2W1 + 2W2 + 2J W2 + WJ`.
    #[inline]
    pub fn new(k: &Kinematics, d1: [f64; 3], d2: [[f64; 3]; 3]) -> Self {
        let s0 = 2.0 * (d1[0] + d1[1]) + 2.0 * k.j * d1[1] + d1[2];
        Self { d1, d2, s0 }
    }
}

/// The coefficients `(a, b)` of `P = s0 I + a H + b cof H`.
#[inline]
fn stress_coefficients(k: &Kinematics, d: &InvariantDerivs) -> (f64, f64) {
    let [w1, w2, wj] = d.d1;
    (2.0 * (w1 + w2), 2.0 * k.j * w2 + wj)
}

/// First Piola–Kirchhoff stress `P = ∂W/∂F` of an energy `W(I1, I2, J)`.
#[inline]
pub fn stress_from_invariants(k: &Kinematics, d: &InvariantDerivs) -> Mat2 {
    let (a, b) = stress_coefficients(k, d);
    Mat2::identity() * d.s0 + k.h * a + cofactor(&k.h) * b
}

/// `P` and the tangent `A = ∂P/∂F` of an energy `W(I1, I2, J)`.
#[inline]
pub fn stress_tangent_from_invariants(k: &Kinematics, d: &InvariantDerivs) -> (Mat2, Tangent) {
    let (a, b) = stress_coefficients(k, d);
    let p = Mat2::identity() * d.s0 + k.h * a + cofactor(&k.h) * b;

    let g_cof = flatten(&k.cof);
    let g_f = flatten(&k.f) * 2.0;
    let grads = [g_f, g_f + g_cof * (2.0 * k.j), g_cof];

    let mut t =
        Tangent::identity() * a + dcof_df() * b + g_cof * g_cof.transpose() * (2.0 * d.d1[1]);
    for (ga, row) in grads.iter().zip(d.d2.iter()) {
        for (gb, &w) in grads.iter().zip(row.iter()) {
            if w != 0.0 {
                t += ga * gb.transpose() * w;
            }
        }
    }
    (p, t)
}

/// The constant tensor `∂(cof F)/∂F`, i.e. the second derivative of `J = det F`.
///
/// `cof F = [[F22, −F21], [−F12, F11]]`, so the only non-zero entries are
/// `∂cof11/∂F22 = ∂cof22/∂F11 = 1` and `∂cof12/∂F21 = ∂cof21/∂F12 = −1`. It is symmetric.
#[inline]
pub fn dcof_df() -> Tangent {
    let mut t = Tangent::zeros();
    t[(v(0, 0), v(1, 1))] = 1.0;
    t[(v(1, 1), v(0, 0))] = 1.0;
    t[(v(0, 1), v(1, 0))] = -1.0;
    t[(v(1, 0), v(0, 1))] = -1.0;
    t
}

/// Stress returned for an inadmissible `F` (`J ≤ 0`): every entry `+∞`, never `NaN`.
#[inline]
pub(crate) fn inadmissible_stress() -> Mat2 {
    Mat2::repeat(f64::INFINITY)
}

/// Tangent returned for an inadmissible `F` (`J ≤ 0`): every entry `+∞`, never `NaN`.
#[inline]
pub(crate) fn inadmissible_tangent() -> Tangent {
    Tangent::repeat(f64::INFINITY)
}

#[cfg(test)]
mod tests {
    use super::*;

    const H: Mat2 = Mat2::new(0.1, 0.2, -0.05, 0.15);

    #[test]
    fn invariants_match_direct_3d_formulas() {
        let k = Kinematics::new(&H);
        let f = k.f;
        let c = f.transpose() * f;
        // 3D C = diag-block(C2, 1): I1 = tr C2 + 1, I2 = ½[(tr C)² − tr C²], I3 = det C2.
        let i1 = c.trace() + 1.0;
        let tr_c2 = (c * c).trace() + 1.0;
        let i2 = 0.5 * (i1 * i1 - tr_c2);
        assert!((k.i1m3 - (i1 - 3.0)).abs() < 1e-14);
        assert!((k.i2m3 - (i2 - 3.0)).abs() < 1e-14);
        assert!((k.j - f.determinant()).abs() < 1e-14);
        assert!((k.j * k.j - c.determinant()).abs() < 1e-14);
        let inv_t = f.try_inverse().unwrap().transpose();
        assert!((k.cof - inv_t * k.j).norm() < 1e-14);
    }

    #[test]
    fn dcof_df_is_derivative_of_cofactor() {
        // cof is linear in F, so a single difference is exact up to rounding.
        let f0 = Mat2::identity() + H;
        let d = dcof_df();
        for col in 0..4 {
            let mut e = Mat2::zeros();
            e[(col / 2, col % 2)] = 1.0;
            let diff = flatten(&(cofactor(&(f0 + e)) - cofactor(&f0)));
            for row in 0..4 {
                assert_eq!(d[(row, col)], diff[row]);
            }
        }
        assert_eq!(d, d.transpose());
    }

    #[test]
    fn accurate_stress_form_equals_textbook_form() {
        // For an arbitrary (not stress-free) set of derivatives, P = s0 I + a H + b cof H must
        // agree with P = 2(W1 + W2) F + (2J W2 + WJ) cof F when s0 is formed naively.
        let k = Kinematics::new(&H);
        let d = InvariantDerivs::new(&k, [0.7, -0.3, 1.9], [[0.0; 3]; 3]);
        let textbook = k.f * (2.0 * (0.7 - 0.3)) + k.cof * (2.0 * k.j * -0.3 + 1.9);
        let p = stress_from_invariants(&k, &d);
        assert!((p - textbook).norm() < 1e-14 * textbook.norm());
        let (p2, _) = stress_tangent_from_invariants(&k, &d);
        assert_eq!(p, p2);
    }

    #[test]
    fn inadmissible_values_are_infinite_not_nan() {
        assert!(inadmissible_stress().iter().all(|x| *x == f64::INFINITY));
        assert!(inadmissible_tangent().iter().all(|x| *x == f64::INFINITY));
        assert!(!Kinematics::new(&Mat2::new(-1.0, 0.0, 0.0, 0.0)).is_admissible());
        assert!(!Kinematics::new(&Mat2::repeat(f64::NAN)).is_admissible());
    }
}
