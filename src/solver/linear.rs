//! Sparse direct solvers (faer) with the symbolic analysis computed once per pattern.
//!
//! [`SparseSolver::new`] runs the symbolic Cholesky (`SymbolicLlt`, lower triangle) or LU
//! (`SymbolicLu`) analysis of a fixed CSC pattern; every Newton iteration then calls
//! [`SparseSolver::factorize`] (numeric factorization with the stored symbolic structure, via
//! `Llt::try_new_with_symbolic` / `Lu::try_new_with_symbolic`) and [`SparseSolver::solve_in_place`].
//! The numeric factorization allocates its factor storage on every call (faer's high-level
//! API); the symbolic analysis and the pattern are never recomputed.
//!
//! Traps handled here (see CRATES.md): LU with a numerically zero pivot yields Inf/NaN rather
//! than an error, so every solution is checked to be finite; Cholesky failure is returned as
//! [`LinearError::NotPositiveDefinite`].

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, Lu, SymbolicLlt, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{MatMut, Side};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinearKind {
    Cholesky,
    Lu,
}

#[derive(Debug, thiserror::Error)]
pub enum LinearError {
    #[error("matrix is not positive definite (Cholesky failed)")]
    NotPositiveDefinite,
    #[error("sparse LU produced a non-finite solution: the matrix is numerically singular")]
    Singular,
    #[error("symbolic analysis failed: {0}")]
    Symbolic(String),
    #[error("non-finite value in the matrix")]
    NonFiniteMatrix,
    #[error("right-hand side length {got} does not match system size {expected}")]
    Size { got: usize, expected: usize },
    #[error("no factorization available")]
    NotFactorized,
}

enum Numeric {
    None,
    Llt(Llt<usize, f64>),
    Lu(Lu<usize, f64>),
}

/// Sparse direct solver with the symbolic analysis done once for a fixed CSC pattern.
pub struct SparseSolver {
    n: usize,
    kind: LinearKind,
    pattern: SymbolicSparseColMat<usize>,
    sym_llt: Option<SymbolicLlt<usize>>,
    sym_lu: Option<SymbolicLu<usize>>,
    numeric: Numeric,
}

impl SparseSolver {
    /// `col_ptr`/`row_idx`: CSC pattern of the full square matrix (both triangles, rows sorted
    /// within each column, no duplicates). For Cholesky only the lower triangle is read.
    pub fn new(
        n: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
        kind: LinearKind,
    ) -> Result<Self, LinearError> {
        let pattern =
            SymbolicSparseColMat::new_checked(n, n, col_ptr.to_vec(), None, row_idx.to_vec());
        let (mut sym_llt, mut sym_lu) = (None, None);
        match kind {
            LinearKind::Cholesky => {
                sym_llt = Some(
                    SymbolicLlt::try_new(pattern.as_ref(), Side::Lower)
                        .map_err(|e| LinearError::Symbolic(format!("{e:?}")))?,
                )
            }
            LinearKind::Lu => {
                sym_lu = Some(
                    SymbolicLu::try_new(pattern.as_ref())
                        .map_err(|e| LinearError::Symbolic(format!("{e:?}")))?,
                )
            }
        }
        Ok(Self {
            n,
            kind,
            pattern,
            sym_llt,
            sym_lu,
            numeric: Numeric::None,
        })
    }

    pub fn kind(&self) -> LinearKind {
        self.kind
    }
    pub fn n(&self) -> usize {
        self.n
    }

    /// Numeric factorization of the matrix with these values (same order as `row_idx`).
    pub fn factorize(&mut self, values: &[f64]) -> Result<(), LinearError> {
        if values.iter().any(|v| !v.is_finite()) {
            return Err(LinearError::NonFiniteMatrix);
        }
        let mat = SparseColMatRef::new(self.pattern.as_ref(), values);
        self.numeric = Numeric::None;
        self.numeric = match self.kind {
            LinearKind::Cholesky => {
                let sym = self.sym_llt.clone().ok_or(LinearError::NotFactorized)?;
                Numeric::Llt(
                    Llt::try_new_with_symbolic(sym, mat, Side::Lower)
                        .map_err(|_| LinearError::NotPositiveDefinite)?,
                )
            }
            LinearKind::Lu => {
                let sym = self.sym_lu.clone().ok_or(LinearError::NotFactorized)?;
                Numeric::Lu(Lu::try_new_with_symbolic(sym, mat).map_err(|_| LinearError::Singular)?)
            }
        };
        Ok(())
    }

    /// Solve A x = b in place with the last factorization; checks the result is finite.
    pub fn solve_in_place(&mut self, rhs: &mut [f64]) -> Result<(), LinearError> {
        if rhs.len() != self.n {
            return Err(LinearError::Size {
                got: rhs.len(),
                expected: self.n,
            });
        }
        let n = self.n;
        let m = MatMut::from_column_major_slice_mut(rhs, n, 1);
        match &self.numeric {
            Numeric::None => return Err(LinearError::NotFactorized),
            Numeric::Llt(f) => f.solve_in_place(m),
            Numeric::Lu(f) => f.solve_in_place(m),
        }
        if rhs.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(LinearError::Singular)
        }
    }

    /// Number of stored nonzeros of the matrix pattern (faer's high-level API does not expose
    /// the factor size).
    pub fn factor_nnz(&self) -> usize {
        self.pattern.compute_nnz()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// CSC of a dense matrix (all entries stored).
    fn csc(a: &[Vec<f64>]) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
        let n = a.len();
        let (mut cp, mut ri, mut v) = (vec![0], vec![], vec![]);
        for j in 0..n {
            for (i, row) in a.iter().enumerate() {
                ri.push(i);
                v.push(row[j]);
            }
            cp.push(ri.len());
        }
        (cp, ri, v)
    }

    fn matvec(a: &[Vec<f64>], x: &[f64]) -> Vec<f64> {
        a.iter()
            .map(|r| r.iter().zip(x).map(|(a, b)| a * b).sum())
            .collect()
    }

    #[test]
    fn spd_saddle_and_singular() {
        let spd = vec![
            vec![4.0, 1.0, 0.0],
            vec![1.0, 3.0, 0.5],
            vec![0.0, 0.5, 2.0],
        ];
        let b = vec![1.0, -2.0, 0.5];
        for kind in [LinearKind::Cholesky, LinearKind::Lu] {
            let (cp, ri, v) = csc(&spd);
            let mut s = SparseSolver::new(3, &cp, &ri, kind).unwrap();
            s.factorize(&v).unwrap();
            let mut x = b.clone();
            s.solve_in_place(&mut x).unwrap();
            let r = matvec(&spd, &x);
            assert!(r.iter().zip(&b).all(|(a, b)| (a - b).abs() < 1e-13));
        }
        // Saddle point [[K, Bᵀ], [B, 0]]: LU works, Cholesky refuses.
        let sad = vec![
            vec![2.0, 0.0, 1.0],
            vec![0.0, 3.0, 1.0],
            vec![1.0, 1.0, 0.0],
        ];
        let (cp, ri, v) = csc(&sad);
        let mut c = SparseSolver::new(3, &cp, &ri, LinearKind::Cholesky).unwrap();
        assert!(matches!(
            c.factorize(&v),
            Err(LinearError::NotPositiveDefinite)
        ));
        let mut l = SparseSolver::new(3, &cp, &ri, LinearKind::Lu).unwrap();
        l.factorize(&v).unwrap();
        let mut x = b.clone();
        l.solve_in_place(&mut x).unwrap();
        let r = matvec(&sad, &x);
        assert!(r.iter().zip(&b).all(|(a, b)| (a - b).abs() < 1e-13));
        // Singular matrix: an error, not a panic.
        let sing = vec![
            vec![1.0, 2.0, 0.0],
            vec![2.0, 4.0, 0.0],
            vec![0.0, 0.0, 1.0],
        ];
        let (cp, ri, v) = csc(&sing);
        let mut l = SparseSolver::new(3, &cp, &ri, LinearKind::Lu).unwrap();
        let res = l.factorize(&v).and_then(|_| {
            let mut x = b.clone();
            l.solve_in_place(&mut x)
        });
        assert!(res.is_err());
        let mut short = vec![0.0; 2];
        assert!(matches!(
            l.solve_in_place(&mut short),
            Err(LinearError::Size { .. })
        ));
    }
}
