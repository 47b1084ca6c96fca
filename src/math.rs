//! Small fixed-size algebra aliases used by every element kernel.
//!
//! Everything is 2D (plane strain) and `f64`. Second-order tensors are `Mat2`; fourth-order
//! tangents `∂P/∂F` are stored as 4×4 matrices in the *row-major flattening*
//! `v(i, J) = 2·i + J`, i.e. `[A11, A12, A21, A22]`, so that
//! `T[(v(i,J), v(k,L))] = ∂P_iJ / ∂F_kL`.

pub type Vec2 = nalgebra::Vector2<f64>;
pub type Mat2 = nalgebra::Matrix2<f64>;
pub type Vec4 = nalgebra::Vector4<f64>;
/// Fourth-order tangent `∂P/∂F` in the flattening described in the module docs.
pub type Tangent = nalgebra::Matrix4<f64>;

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
}
