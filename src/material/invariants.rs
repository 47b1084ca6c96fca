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
//!
//! # Three dimensions
//!
//! With `H` 3×3, `E₂ = C − I = H + Hᵀ + HᵀH` and `t = tr E₂ = I1 − 3`,
//!
//! ```text
//! I1 − 3 = 2 tr H + H:H,   I2 − 3 = 2t + ½ (t² − E₂:E₂),   J − 1 = tr H + Σ minors₂(H) + det H
//! ∂I1/∂F = 2F,   ∂I2/∂F = 2(I1 F − F C),   ∂J/∂F = cof F
//! P = s0₃ I + 2W1 H + 2W2 ((I1 − 1) H − E₂ − H E₂) + WJ (tr H I − Hᵀ + cof H),
//!     s0₃ = 2W1 + 2W2 (I1 − 1) + WJ = s0 + 2W2 ((I1 − 3) − (J − 1))
//! ```
//!
//! using `cof(I + H) = I + tr H I − Hᵀ + cof H`. The material's `s0` (the plane-strain
//! coefficient above, a function of the scalars only) is the same closed form in both
//! dimensions; `s0₃` adds a term that is `O(|H|)` with no cancellation. The tangent is
//!
//! ```text
//! A = Σab Wab (∂Ia/∂F ⊗ ∂Ib/∂F) + 2W1 𝕀 + W2 ∂²I2/∂F² + WJ ∂cof/∂F,
//! ∂²I2/∂F_iJ ∂F_kL = 4 F_iJ F_kL + 2 I1 δik δJL − 2 (δik C_LJ + F_iL F_kJ + (FFᵀ)_ik δJL),
//! ∂cof_iJ/∂F_kL = ε_ikl ε_JLM F_lM.
//! ```
//!
//! Embedding a plane-strain `H` (zero third row and column) in 3D gives the plane-strain
//! invariants, the in-plane block of `P` and of `A` of the 2D formulas, and `P33 = J σ33`.
//!
//! [`Kinematics`] and the chain rule are generic in the dimension ([`InvariantTensor`], i.e.
//! `Mat2` or `Mat3`); a law written on the invariants is therefore one code path for both.

use crate::math::{cofactor, cofactor3, flatten, v, Mat2, Mat3, Tangent, Tangent3, Tensor, Vec9};

/// Out-of-plane Cauchy stress σ33 of plane strain (`F33 = 1`) from the first partials:
/// `∂I1/∂F33 = 2`, `∂I2/∂F33 = 2(I1 − 1)`, `∂J/∂F33 = J`, so
/// `σ33 = P33 / J = (2W1 + 2W2 (I1 − 1)) / J + WJ`.
/// (A pressure field adds `−p`; the caller subtracts it.)
#[inline]
pub fn sigma33_from_invariants(k: &Kinematics, d: &InvariantDerivs) -> f64 {
    let i1 = 3.0 + k.i1m3;
    (2.0 * d.d1[0] + 2.0 * d.d1[1] * (i1 - 1.0)) / k.j + d.d1[2]
}

/// Kinematic quantities of one quadrature point, all derived from `H = ∇u` (`Mat2` in plane
/// strain, `Mat3` in 3D).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kinematics<T: Tensor = Mat2> {
    /// Displacement gradient `H = ∇u`.
    pub h: T,
    /// Deformation gradient `F = I + H`.
    pub f: T,
    /// `J = det F`.
    pub j: f64,
    /// `J − 1`, computed without cancellation.
    pub jm1: f64,
    /// `I1 − 3 = 2 tr H + H:H` (3D invariant; in plane strain with `F33 = 1`).
    pub i1m3: f64,
    /// `I2 − 3` (3D invariant; see the module docs for its cancellation-free forms).
    pub i2m3: f64,
    /// `cof F = J F⁻ᵀ` (defined for every F).
    pub cof: T,
}

impl<T: InvariantTensor> Kinematics<T> {
    /// Kinematics of `F = I + grad_u`.
    #[inline]
    pub fn new(grad_u: &T) -> Self {
        let h = *grad_u;
        let f = T::eye() + h;
        let jm1 = h.det_ipm1();
        let i1m3 = 2.0 * h.tr() + h.frob2();
        let i2m3 = T::i2m3(&h, i1m3, jm1);
        Self {
            h,
            f,
            j: 1.0 + jm1,
            jm1,
            i1m3,
            i2m3,
            cof: f.cof(),
        }
    }
}

impl<T: Tensor> Kinematics<T> {
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
    /// module docs); [`InvariantDerivs::new`] forms it naively for laws that do not care. The
    /// same value serves 3D, which adds `2W2 ((I1 − 3) − (J − 1))`.
    pub s0: f64,
}

impl InvariantDerivs {
    /// Derivatives with `s0` formed naively as `2W1 + 2W2 + 2J W2 + WJ`.
    #[inline]
    pub fn new<T: Tensor>(k: &Kinematics<T>, d1: [f64; 3], d2: [[f64; 3]; 3]) -> Self {
        let s0 = 2.0 * (d1[0] + d1[1]) + 2.0 * k.j * d1[1] + d1[2];
        Self { d1, d2, s0 }
    }
}

/// The dimension-dependent part of the invariant chain rule (see the module docs): the second
/// invariant, the stress and tangent from invariant derivatives, and `∂cof/∂F`.
pub trait InvariantTensor: Tensor {
    /// `I2 − 3` from `H`, `I1 − 3` and `J − 1`, without cancellation.
    fn i2m3(h: &Self, i1m3: f64, jm1: f64) -> f64;
    /// `P = ∂W/∂F` of an energy `W(I1, I2, J)`.
    fn stress_inv(k: &Kinematics<Self>, d: &InvariantDerivs) -> Self;
    /// `P` and `A = ∂P/∂F` of an energy `W(I1, I2, J)`.
    fn stress_tangent_inv(k: &Kinematics<Self>, d: &InvariantDerivs) -> (Self, Self::Tangent);
    /// `∂(cof F)/∂F` at `F` (the second derivative of `J`).
    fn dcof(f: &Self) -> Self::Tangent;
}

/// First Piola–Kirchhoff stress `P = ∂W/∂F` of an energy `W(I1, I2, J)`.
#[inline]
pub fn stress_from_invariants<T: InvariantTensor>(k: &Kinematics<T>, d: &InvariantDerivs) -> T {
    T::stress_inv(k, d)
}

/// `P` and the tangent `A = ∂P/∂F` of an energy `W(I1, I2, J)`.
#[inline]
pub fn stress_tangent_from_invariants<T: InvariantTensor>(
    k: &Kinematics<T>,
    d: &InvariantDerivs,
) -> (T, T::Tangent) {
    T::stress_tangent_inv(k, d)
}

/// The coefficients `(a, b)` of `P = s0 I + a H + b cof H` (plane strain).
#[inline]
fn stress_coefficients(k: &Kinematics, d: &InvariantDerivs) -> (f64, f64) {
    let [w1, w2, wj] = d.d1;
    (2.0 * (w1 + w2), 2.0 * k.j * w2 + wj)
}

impl InvariantTensor for Mat2 {
    #[inline]
    fn i2m3(_h: &Mat2, i1m3: f64, jm1: f64) -> f64 {
        i1m3 + jm1 * (2.0 + jm1)
    }

    #[inline]
    fn stress_inv(k: &Kinematics, d: &InvariantDerivs) -> Mat2 {
        let (a, b) = stress_coefficients(k, d);
        Mat2::identity() * d.s0 + k.h * a + cofactor(&k.h) * b
    }

    #[inline]
    fn stress_tangent_inv(k: &Kinematics, d: &InvariantDerivs) -> (Mat2, Tangent) {
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

    #[inline]
    fn dcof(_f: &Mat2) -> Tangent {
        dcof_df()
    }
}

/// Row-major flattening of a 3×3 tensor ([`crate::math::v3`]).
#[inline(always)]
fn flatten3(a: &Mat3) -> Vec9 {
    Vec9::from_fn(|r, _| a[(r / 3, r % 3)])
}

/// Levi-Civita symbol of three indices in `0..3`.
#[inline(always)]
fn levi_civita(a: usize, b: usize, c: usize) -> f64 {
    if a == b || b == c || a == c {
        0.0
    } else if b == (a + 1) % 3 {
        1.0
    } else {
        -1.0
    }
}

impl InvariantTensor for Mat3 {
    #[inline]
    fn i2m3(h: &Mat3, i1m3: f64, _jm1: f64) -> f64 {
        let e2 = h + h.transpose() + h.transpose() * h;
        2.0 * i1m3 + 0.5 * (i1m3 * i1m3 - e2.norm_squared())
    }

    #[inline]
    fn stress_inv(k: &Kinematics<Mat3>, d: &InvariantDerivs) -> Mat3 {
        let [w1, w2, wj] = d.d1;
        let h = k.h;
        let e2 = h + h.transpose() + h.transpose() * h;
        let s0 = d.s0 + 2.0 * w2 * (k.i1m3 - k.jm1);
        Mat3::identity() * (s0 + wj * h.trace()) + h * (2.0 * w1 + 2.0 * w2 * (2.0 + k.i1m3))
            - (e2 + h * e2) * (2.0 * w2)
            + (cofactor3(&h) - h.transpose()) * wj
    }

    #[inline]
    fn stress_tangent_inv(k: &Kinematics<Mat3>, d: &InvariantDerivs) -> (Mat3, Tangent3) {
        let p = Self::stress_inv(k, d);
        let [w1, w2, wj] = d.d1;
        let f = k.f;
        let c = f.transpose() * f;
        let b = f * f.transpose();
        let i1 = 3.0 + k.i1m3;
        let g_f = flatten3(&f) * 2.0;
        let g_i2 = flatten3(&(f * i1 - f * c)) * 2.0;
        let g_cof = flatten3(&k.cof);
        let grads = [g_f, g_i2, g_cof];

        let mut t = Tangent3::identity() * (2.0 * w1) + Self::dcof(&f) * wj;
        if w2 != 0.0 {
            for i in 0..3 {
                for jj in 0..3 {
                    for kk in 0..3 {
                        for l in 0..3 {
                            let dik = if i == kk { 1.0 } else { 0.0 };
                            let djl = if jj == l { 1.0 } else { 0.0 };
                            let d2 = 4.0 * f[(i, jj)] * f[(kk, l)] + 2.0 * i1 * dik * djl
                                - 2.0
                                    * (dik * c[(l, jj)]
                                        + f[(i, l)] * f[(kk, jj)]
                                        + b[(i, kk)] * djl);
                            t[(3 * i + jj, 3 * kk + l)] += w2 * d2;
                        }
                    }
                }
            }
        }
        for (ga, row) in grads.iter().zip(d.d2.iter()) {
            for (gb, &w) in grads.iter().zip(row.iter()) {
                if w != 0.0 {
                    t += ga * gb.transpose() * w;
                }
            }
        }
        (p, t)
    }

    #[inline]
    fn dcof(f: &Mat3) -> Tangent3 {
        let mut t = Tangent3::zeros();
        for i in 0..3 {
            for kk in 0..3 {
                if i == kk {
                    continue;
                }
                let l = 3 - i - kk;
                for jj in 0..3 {
                    for ll in 0..3 {
                        if jj == ll {
                            continue;
                        }
                        let m = 3 - jj - ll;
                        t[(3 * i + jj, 3 * kk + ll)] =
                            levi_civita(i, kk, l) * levi_civita(jj, ll, m) * f[(l, m)];
                    }
                }
            }
        }
        t
    }
}

/// The constant tensor `∂(cof F)/∂F` of plane strain, i.e. the second derivative of `J = det F`.
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
pub(crate) fn inadmissible_stress<T: Tensor>() -> T {
    T::filled(f64::INFINITY)
}

/// Tangent returned for an inadmissible `F` (`J ≤ 0`): every entry `+∞`, never `NaN`.
#[inline]
pub(crate) fn inadmissible_tangent<T: Tensor>() -> T::Tangent {
    T::tangent_filled(f64::INFINITY)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::embed_plane;

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
    fn invariants_3d_match_direct_formulas_and_plane_strain() {
        let h3 = Mat3::new(0.1, 0.2, -0.05, 0.15, -0.1, 0.3, 0.02, 0.07, 0.2);
        let k = Kinematics::new(&h3);
        let f = Mat3::identity() + h3;
        let c = f.transpose() * f;
        let i1 = c.trace();
        let i2 = 0.5 * (i1 * i1 - (c * c).trace());
        assert!((k.i1m3 - (i1 - 3.0)).abs() < 1e-14);
        assert!((k.i2m3 - (i2 - 3.0)).abs() < 1e-14);
        assert!((k.j - f.determinant()).abs() < 1e-14);
        assert!((k.cof - f.try_inverse().unwrap().transpose() * k.j).norm() < 1e-14);
        let k2 = Kinematics::new(&H);
        let k3 = Kinematics::new(&embed_plane(&H));
        assert!((k2.i1m3 - k3.i1m3).abs() < 1e-15);
        assert!((k2.i2m3 - k3.i2m3).abs() < 1e-15);
        assert!((k2.jm1 - k3.jm1).abs() < 1e-15);
        // Tiny strain: the three values keep full relative precision (no 1 + ε − 1).
        let tiny = h3 * 1e-12;
        let kt = Kinematics::new(&tiny);
        assert!((kt.i1m3 / (2.0 * tiny.trace()) - 1.0).abs() < 1e-10);
        assert!((kt.jm1 / tiny.trace() - 1.0).abs() < 1e-10);
        assert!((kt.i2m3 / (4.0 * tiny.trace()) - 1.0).abs() < 1e-10);
    }

    #[test]
    fn chain_rule_3d_against_finite_differences_and_plane_strain_block() {
        // An arbitrary energy W(I1, I2, J) with every partial and mixed term non-zero.
        let w = |k: &Kinematics<Mat3>| {
            let (a, b, c) = (k.i1m3, k.i2m3, k.jm1);
            0.7 * a + 0.3 * b - 1.1 * c + 0.2 * a * a + 0.15 * a * b + 0.05 * b * b - 0.4 * a * c
                + 0.25 * b * c
                + 0.9 * c * c
        };
        let derivs = |k: &Kinematics<Mat3>| {
            let (a, b, c) = (k.i1m3, k.i2m3, k.jm1);
            InvariantDerivs::new(
                k,
                [
                    0.7 + 0.4 * a + 0.15 * b - 0.4 * c,
                    0.3 + 0.15 * a + 0.1 * b + 0.25 * c,
                    -1.1 - 0.4 * a + 0.25 * b + 1.8 * c,
                ],
                [[0.4, 0.15, -0.4], [0.15, 0.1, 0.25], [-0.4, 0.25, 1.8]],
            )
        };
        let h3 = Mat3::new(0.1, 0.2, -0.05, 0.15, -0.1, 0.3, 0.02, 0.07, 0.2);
        let k = Kinematics::new(&h3);
        let (p, a) = stress_tangent_from_invariants(&k, &derivs(&k));
        assert_eq!(p, stress_from_invariants(&k, &derivs(&k)));
        let step = 1e-4;
        let mut p_fd = Mat3::zeros();
        let mut a_fd = Tangent3::zeros();
        for kk in 0..3 {
            for l in 0..3 {
                let mut e = Mat3::zeros();
                e[(kk, l)] = step;
                let kp = Kinematics::new(&(h3 + e));
                let km = Kinematics::new(&(h3 - e));
                p_fd[(kk, l)] = (w(&kp) - w(&km)) / (2.0 * step);
                let dp = (stress_from_invariants(&kp, &derivs(&kp))
                    - stress_from_invariants(&km, &derivs(&km)))
                    / (2.0 * step);
                for i in 0..3 {
                    for jj in 0..3 {
                        a_fd[(3 * i + jj, 3 * kk + l)] = dp[(i, jj)];
                    }
                }
            }
        }
        assert!((p - p_fd).norm() < 1e-7 * p.norm(), "{p} {p_fd}");
        assert!((a - a_fd).norm() < 1e-7 * a.norm());
        assert!((a - a.transpose()).norm() < 1e-13 * a.norm());

        // Plane strain: the in-plane blocks of the 3D P and A are the 2D ones.
        let k2 = Kinematics::new(&H);
        let k3 = Kinematics::new(&embed_plane(&H));
        let d2 = InvariantDerivs::new(
            &k2,
            [0.7, -0.3, 1.9],
            [[0.2, 0.1, -0.3], [0.1, 0.4, 0.2], [-0.3, 0.2, 0.6]],
        );
        let d3 = InvariantDerivs { ..d2 };
        let (p2, a2) = stress_tangent_from_invariants(&k2, &d2);
        let (p3, a3) = stress_tangent_from_invariants(&k3, &d3);
        for i in 0..2 {
            for jj in 0..2 {
                assert!((p2[(i, jj)] - p3[(i, jj)]).abs() < 1e-14, "P {i}{jj}");
                for kk in 0..2 {
                    for l in 0..2 {
                        let (x2, x3) = (a2[(v(i, jj), v(kk, l))], a3[(3 * i + jj, 3 * kk + l)]);
                        assert!((x2 - x3).abs() < 1e-13, "A {i}{jj}{kk}{l}: {x2} {x3}");
                    }
                }
            }
        }
        // P33 = J σ33.
        assert!((p3[(2, 2)] - k2.j * sigma33_from_invariants(&k2, &d2)).abs() < 1e-14);
    }

    #[test]
    fn dcof3_is_derivative_of_cofactor3() {
        let f0 = Mat3::new(1.1, 0.2, -0.05, 0.15, 0.9, 0.3, 0.02, 0.07, 1.2);
        let d = Mat3::dcof(&f0);
        let step = 1e-3;
        for col in 0..9 {
            let mut e = Mat3::zeros();
            e[(col / 3, col % 3)] = step;
            // cof is quadratic in F: the central difference is exact up to rounding.
            let diff = (cofactor3(&(f0 + e)) - cofactor3(&(f0 - e))) / (2.0 * step);
            for row in 0..9 {
                assert!((d[(row, col)] - diff[(row / 3, row % 3)]).abs() < 1e-12);
            }
        }
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
        assert!(inadmissible_stress::<Mat2>()
            .iter()
            .all(|x| *x == f64::INFINITY));
        assert!(inadmissible_tangent::<Mat2>()
            .iter()
            .all(|x| *x == f64::INFINITY));
        assert!(!Kinematics::new(&Mat2::new(-1.0, 0.0, 0.0, 0.0)).is_admissible());
        assert!(!Kinematics::new(&Mat2::repeat(f64::NAN)).is_admissible());
    }
}
