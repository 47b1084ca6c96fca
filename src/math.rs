//! Small fixed-size algebra aliases used by every element kernel.
//!
//! Everything is `f64`. In plane strain (the dimension `D = 2`) second-order tensors are `Mat2`
//! and fourth-order tangents `∂P/∂F` are 4×4 matrices in the *row-major flattening*
//! `v(i, J) = 2·i + J`, i.e. `[A11, A12, A21, A22]`, so that
//! `T[(v(i,J), v(k,L))] = ∂P_iJ / ∂F_kL`. In three dimensions (`D = 3`) they are `Mat3` and
//! 9×9 `Tangent3` in the flattening `v3(i, J) = 3·i + J`.
//!
//! [`Tensor`] is the dimension as a type: code written for `T: Tensor` (a material law, the
//! finite-difference checker) serves both `Mat2` and `Mat3`, the dimension being the type of the
//! displacement gradient it is given. Plane strain is the `D = 2` case with `F33 = 1`.

use std::fmt::Debug;
use std::ops::{Add, Index, IndexMut, Mul, Sub};

pub type Vec2 = nalgebra::Vector2<f64>;
pub type Mat2 = nalgebra::Matrix2<f64>;
pub type Vec4 = nalgebra::Vector4<f64>;
/// Fourth-order tangent `∂P/∂F` in the flattening described in the module docs.
pub type Tangent = nalgebra::Matrix4<f64>;

pub type Vec3 = nalgebra::Vector3<f64>;
pub type Mat3 = nalgebra::Matrix3<f64>;
pub type Vec9 = nalgebra::SVector<f64, 9>;
/// Fourth-order tangent `∂P/∂F` in three dimensions, flattening [`v3`].
pub type Tangent3 = nalgebra::SMatrix<f64, 9, 9>;

/// Flat index of the tensor component `(i, j)`.
#[inline(always)]
pub const fn v(i: usize, j: usize) -> usize {
    2 * i + j
}

/// Row-major flattening of a 2×2 tensor.
#[inline(always)]
pub fn flatten(a: &Mat2) -> Vec4 {
    Vec4::new(a[(0, 0)], a[(0, 1)], a[(1, 0)], a[(1, 1)])
}

/// Inverse of [`flatten`].
#[inline(always)]
pub fn unflatten(a: &Vec4) -> Mat2 {
    Mat2::new(a[0], a[1], a[2], a[3])
}

/// Cofactor of a 2×2 matrix, `cof A = det(A) A⁻ᵀ`, defined for every A.
#[inline(always)]
pub fn cofactor(a: &Mat2) -> Mat2 {
    Mat2::new(a[(1, 1)], -a[(1, 0)], -a[(0, 1)], a[(0, 0)])
}

/// Determinant of I + H computed without cancellation when H is small: returns J − 1.
#[inline(always)]
pub fn det_identity_plus_minus_one(h: &Mat2) -> f64 {
    h[(0, 0)] + h[(1, 1)] + (h[(0, 0)] * h[(1, 1)] - h[(0, 1)] * h[(1, 0)])
}

/// Flat index of the 3D tensor component `(i, j)`.
#[inline(always)]
pub const fn v3(i: usize, j: usize) -> usize {
    3 * i + j
}

/// A plane-strain tensor as the 3D tensor of the slice `x3 = 0`: zero third row and column
/// (for a displacement gradient, `F33 = 1`).
#[inline(always)]
pub fn embed_plane(h: &Mat2) -> Mat3 {
    Mat3::new(
        h[(0, 0)],
        h[(0, 1)],
        0.0,
        h[(1, 0)],
        h[(1, 1)],
        0.0,
        0.0,
        0.0,
        0.0,
    )
}

/// Cofactor of a 3×3 matrix, `cof A = det(A) A⁻ᵀ`, defined for every A (each entry is the
/// signed 2×2 minor, written cyclically).
#[inline(always)]
pub fn cofactor3(a: &Mat3) -> Mat3 {
    Mat3::from_fn(|i, j| {
        let (i1, i2) = ((i + 1) % 3, (i + 2) % 3);
        let (j1, j2) = ((j + 1) % 3, (j + 2) % 3);
        a[(i1, j1)] * a[(i2, j2)] - a[(i1, j2)] * a[(i2, j1)]
    })
}

/// `det(I + H) − 1` for a 3×3 `H` without cancellation when `H` is small:
/// `tr H + (sum of the principal 2×2 minors of H) + det H`.
#[inline(always)]
pub fn det3_identity_plus_minus_one(h: &Mat3) -> f64 {
    let minors = h[(0, 0)] * h[(1, 1)] - h[(0, 1)] * h[(1, 0)] + h[(0, 0)] * h[(2, 2)]
        - h[(0, 2)] * h[(2, 0)]
        + h[(1, 1)] * h[(2, 2)]
        - h[(1, 2)] * h[(2, 1)];
    h.trace() + minors + h.determinant()
}

/// A second-order tensor of one spatial dimension, with the type of its tangent `∂P/∂F`: the
/// dimension as a type parameter (see the module docs). Implemented by `Mat2` (plane strain)
/// and `Mat3`. Method names differ from nalgebra's inherent ones so that generic code and
/// concrete code read the same.
pub trait Tensor:
    Copy
    + Debug
    + PartialEq
    + Send
    + Sync
    + 'static
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<f64, Output = Self>
    + Index<(usize, usize), Output = f64>
    + IndexMut<(usize, usize)>
{
    /// Spatial dimension.
    const D: usize;
    /// Independent components of a symmetric tensor, `D (D + 1) / 2`.
    const NSYM: usize;
    /// The tangent `∂P/∂F`, a `D² × D²` matrix in the flattening `D·i + J`.
    type Tangent: Copy
        + Debug
        + PartialEq
        + Send
        + Sync
        + 'static
        + Add<Output = Self::Tangent>
        + Sub<Output = Self::Tangent>
        + Mul<f64, Output = Self::Tangent>
        + Index<(usize, usize), Output = f64>
        + IndexMut<(usize, usize)>;

    /// The zero tensor.
    fn zero() -> Self;
    /// The identity.
    fn eye() -> Self;
    /// Every entry `x`.
    fn filled(x: f64) -> Self;
    /// Frobenius norm.
    fn frob(&self) -> f64;
    /// Squared Frobenius norm `A:A`.
    fn frob2(&self) -> f64;
    /// Trace.
    fn tr(&self) -> f64;
    /// Transpose.
    fn transposed(&self) -> Self;
    /// Matrix product `self · b`.
    fn dot(&self, b: &Self) -> Self;
    /// Cofactor `det(A) A⁻ᵀ` (defined for every `A`).
    fn cof(&self) -> Self;
    /// `det(I + self) − 1`, without cancellation for small `self`.
    fn det_ipm1(&self) -> f64;
    /// The zero tangent.
    fn tangent_zero() -> Self::Tangent;
    /// The identity tangent `𝕀` (`∂F/∂F`).
    fn tangent_eye() -> Self::Tangent;
    /// A tangent with every entry `x`.
    fn tangent_filled(x: f64) -> Self::Tangent;
    /// Frobenius norm of a tangent.
    fn tangent_frob(t: &Self::Tangent) -> f64;
    /// Determinant.
    fn det(&self) -> f64;
    /// Inverse, if the matrix is invertible.
    fn inverse(&self) -> Option<Self>;
    /// Double contraction `A:B`.
    fn ddot(&self, b: &Self) -> f64;
    /// The symmetric tensor stored as `[a11, a22, a12]` (2D) or Voigt
    /// `[a11, a22, a33, a23, a13, a12]` (3D), from the first [`Self::NSYM`] values of `s`.
    fn sym_from(s: &[f64]) -> Self;
    /// Stores the symmetric part of `self` in the layout of [`Self::sym_from`].
    fn sym_store(&self, out: &mut [f64]);
    /// Flat index of component `(i, j)`.
    #[inline(always)]
    fn flat(i: usize, j: usize) -> usize {
        Self::D * i + j
    }
}

/// Voigt pairs of the 3D symmetric layout of [`Tensor::sym_from`].
const VOIGT3: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1)];
/// The 2D symmetric layout of [`Tensor::sym_from`].
const SYM2: [(usize, usize); 3] = [(0, 0), (1, 1), (0, 1)];

macro_rules! tensor_impl {
    ($mat:ty, $tangent:ty, $d:expr, $cof:path, $det:path, $pairs:expr) => {
        impl Tensor for $mat {
            const D: usize = $d;
            const NSYM: usize = $d * ($d + 1) / 2;
            #[inline(always)]
            fn det(&self) -> f64 {
                self.determinant()
            }
            #[inline(always)]
            fn inverse(&self) -> Option<Self> {
                self.try_inverse()
            }
            #[inline(always)]
            fn ddot(&self, b: &Self) -> f64 {
                self.component_mul(b).sum()
            }
            #[inline(always)]
            fn sym_from(s: &[f64]) -> Self {
                let mut m = <$mat>::zeros();
                for (v, &(i, j)) in s.iter().zip($pairs.iter()) {
                    m[(i, j)] = *v;
                    m[(j, i)] = *v;
                }
                m
            }
            #[inline(always)]
            fn sym_store(&self, out: &mut [f64]) {
                for (o, &(i, j)) in out.iter_mut().zip($pairs.iter()) {
                    *o = if i == j {
                        self[(i, i)]
                    } else {
                        0.5 * (self[(i, j)] + self[(j, i)])
                    };
                }
            }
            type Tangent = $tangent;
            #[inline(always)]
            fn zero() -> Self {
                <$mat>::zeros()
            }
            #[inline(always)]
            fn eye() -> Self {
                <$mat>::identity()
            }
            #[inline(always)]
            fn filled(x: f64) -> Self {
                <$mat>::repeat(x)
            }
            #[inline(always)]
            fn frob(&self) -> f64 {
                self.norm()
            }
            #[inline(always)]
            fn frob2(&self) -> f64 {
                self.norm_squared()
            }
            #[inline(always)]
            fn tr(&self) -> f64 {
                self.trace()
            }
            #[inline(always)]
            fn transposed(&self) -> Self {
                self.transpose()
            }
            #[inline(always)]
            fn dot(&self, b: &Self) -> Self {
                self * b
            }
            #[inline(always)]
            fn cof(&self) -> Self {
                $cof(self)
            }
            #[inline(always)]
            fn det_ipm1(&self) -> f64 {
                $det(self)
            }
            #[inline(always)]
            fn tangent_zero() -> $tangent {
                <$tangent>::zeros()
            }
            #[inline(always)]
            fn tangent_eye() -> $tangent {
                <$tangent>::identity()
            }
            #[inline(always)]
            fn tangent_filled(x: f64) -> $tangent {
                <$tangent>::repeat(x)
            }
            #[inline(always)]
            fn tangent_frob(t: &$tangent) -> f64 {
                t.norm()
            }
        }
    };
}

tensor_impl!(
    Mat2,
    Tangent,
    2,
    cofactor,
    det_identity_plus_minus_one,
    SYM2
);
tensor_impl!(
    Mat3,
    Tangent3,
    3,
    cofactor3,
    det3_identity_plus_minus_one,
    VOIGT3
);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flatten_roundtrip_and_cofactor() {
        let a = Mat2::new(1.0, 2.0, 3.0, 5.0);
        assert_eq!(unflatten(&flatten(&a)), a);
        assert_eq!(flatten(&a)[v(1, 0)], 3.0);
        let c = cofactor(&a);
        let det = a.determinant();
        let expected = a.try_inverse().unwrap().transpose() * det;
        assert!((c - expected).norm() < 1e-14);
        let h = Mat2::new(1e-9, 2e-9, -3e-9, 4e-9);
        let jm1 = det_identity_plus_minus_one(&h);
        assert!((jm1 - (5e-9 + 4e-18 + 6e-18)).abs() < 1e-24);
    }

    #[test]
    fn cofactor3_and_det_minus_one() {
        let a = Mat3::new(1.0, 2.0, 0.5, -0.3, 1.7, 0.2, 0.4, -1.1, 2.3);
        let expected = a.try_inverse().unwrap().transpose() * a.determinant();
        assert!((cofactor3(&a) - expected).norm() < 1e-13);
        let h = Mat3::new(1e-9, 2e-9, -1e-9, -3e-9, 4e-9, 5e-9, 2e-9, -1e-9, 3e-9);
        // tr H = 8e-9; principal minors: (4 + 6) + (3 + 2) + (12 + 5) = 32, times 1e-18.
        let exact = 8e-9 + 32e-18 + h.determinant();
        assert!((det3_identity_plus_minus_one(&h) - exact).abs() < 1e-26);
        let g = Mat3::new(0.1, 0.2, -0.05, 0.15, -0.1, 0.3, 0.02, 0.07, 0.2);
        let direct = (Mat3::identity() + g).determinant() - 1.0;
        assert!((det3_identity_plus_minus_one(&g) - direct).abs() < 1e-15);
        assert_eq!(<Mat3 as Tensor>::flat(1, 2), v3(1, 2));
        assert_eq!(<Mat2 as Tensor>::flat(1, 0), v(1, 0));
    }
}
