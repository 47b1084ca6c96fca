//! Sparse direct linear solver layer on top of faer 0.24 (low-level API).
//!
//! [`SparseSolver`] owns a fixed CSC pattern. The symbolic analysis (fill-reducing ordering,
//! elimination tree, supernode partition) is done once in [`SparseSolver::new`]; each Newton
//! iteration then calls [`SparseSolver::factorize`] with new values in the same order as the
//! pattern and [`SparseSolver::solve_in_place`] as many times as needed.
//!
//! # faer calls used
//!
//! Symbolic (once, in `new`):
//! - Cholesky: `faer::sparse::linalg::cholesky::factorize_symbolic_cholesky(A, Side::Lower,
//!   SymmetricOrdering::Amd, CholeskySymbolicParams::default())` (faer picks the simplicial or the
//!   supernodal variant from its flop estimate; FE matrices of useful size end up supernodal).
//! - LU (default, [`LuOrdering::Symmetric`]): [`super::multifrontal::SymmetricLu`], AMD on
//!   A + Aᵀ through `factorize_symbolic_cholesky` (supernodal), a multifrontal numeric phase
//!   with faer's dense kernels; a zero pivot hands the matrix to the COLAMD LU below.
//! - LU ([`LuOrdering::Colamd`]): `faer::sparse::linalg::lu::factorize_symbolic_lu(A,
//!   LuSymbolicParams::default())` (COLAMD column ordering, supernodal or simplicial chosen by
//!   faer), plus — for the
//!   determinant of symmetric matrices, see below — a supernodal `factorize_symbolic_cholesky`
//!   of the same pattern with `SupernodalThreshold::FORCE_SUPERNODAL`.
//! - Scratch: `SymbolicCholesky::factorize_numeric_llt_scratch`,
//!   `SymbolicCholesky::factorize_numeric_intranode_lblt_scratch`,
//!   `SymbolicCholesky::solve_in_place_scratch`, `SymbolicLu::factorize_numeric_lu_scratch`,
//!   `SymbolicLu::solve_in_place_scratch`, combined with `StackReq::or` into one `MemBuffer`
//!   owned by the solver (sized in `new` for `Par::Seq`, grown once if
//!   [`SparseSolver::set_parallel`] or the determinant tracking needs more).
//!
//! Numeric (every call of `factorize`):
//! - Cholesky: `SymbolicCholesky::factorize_numeric_llt(L_values, A, Side::Lower,
//!   LltRegularization::default(), par, stack, Default::default())` into an `L_values` buffer
//!   owned by the solver (length `SymbolicCholesky::len_val`).
//! - LU: `SymbolicLu::factorize_numeric_lu(&mut NumericLu, A, par, stack, Default::default())`
//!   into a `NumericLu` owned by the solver and reused.
//! - LU determinant (symmetric values only, when tracking is on):
//!   `SymbolicCholesky::factorize_numeric_intranode_lblt` into owned `L_values`, `subdiag`,
//!   `perm_fwd`, `perm_inv` buffers.
//!
//! Solve: `LltRef::new(..).solve_in_place_with_conj` / `LuRef::new_unchecked(..)
//! .solve_in_place_with_conj` with `Conj::No` on a one-column `MatMut` view of the caller's slice.
//!
//! # Allocation in the numeric factorization
//!
//! Measured with a counting global allocator (n = 20 000, repeated `factorize` on one solver):
//! - Cholesky, `Par::Seq`: the first `factorize` makes ~490 allocations (faer's dense kernels
//!   set up their thread-local buffers); every later call makes **none**. The factor values,
//!   the scratch memory and the diagonal position table are allocated once in `new`.
//! - Cholesky, parallel: ~3 500 small allocations (~75 KB) per call, made by rayon task
//!   spawning inside faer's parallel dense kernels.
//! - LU (multifrontal, the default): the factors, the front, the update stack and the dense
//!   LU's scratch are sized by the symbolic analysis; `factorize` and `solve_in_place` allocate
//!   nothing with `Par::Seq` (faer's dense kernels may set up their thread-local buffers once).
//! - LU (COLAMD): the factor storage inside `NumericLu` is reused (it only grows), but faer's supernodal
//!   numeric LU (`lu::supernodal::factorize_supernodal_numeric_lu`) allocates internally on
//!   every call (~1 700 allocations, ~47 MB at n = 20 000, sequential): one `Vec` of
//!   per-supernode contribution blocks and, per supernode, the dense contribution block and its
//!   bookkeeping (`Vec<T>`, `Vec<I>`, `MatU8`), plus pushes onto the row/column compression
//!   lists. This is inside faer and cannot be avoided through its public API; the time is
//!   small against the dense work.
//! - LU determinant tracking: its buffers are allocated by the first factorization that needs
//!   them (and again only if the set of zero-diagonal columns changes); no allocations after.
//! - `solve_in_place`: no allocations (sequential); 4 small ones for LU in parallel mode.
//!
//! # Determinant (for bifurcation detection)
//!
//! - Cholesky: sign +1, `log|det A| = 2 Σ log L_ii`.
//! - LU: faer 0.24 does not expose the numeric LU factors (the fields of `NumericLu` and
//!   `SupernodalLu` are private; the simplicial LU, whose factors are public, is ~25× slower
//!   than the supernodal one on 2D FE matrices), so the U diagonal cannot be read. Instead,
//!   when the values are symmetric (relative tolerance [`SYMMETRY_RTOL`]) and determinant
//!   tracking is on (default), `factorize` also computes faer's supernodal LBLᵀ factorization
//!   with Bunch–Kaufman pivoting inside supernodes, `P A Pᵀ = L D Lᵀ`, which gives
//!   `det A = det D` and, by Sylvester's law of inertia, the number of negative eigenvalues.
//!   Columns with a zero diagonal (e.g. Lagrange multipliers) are ordered last so that they
//!   are not pivoted on alone. Measured cost: +0.10 s on a 0.36 s LU at n = 100k, +0.24 s on
//!   0.89 s at n = 200k (about 30 %); it always runs sequentially (faer's parallel
//!   Bunch–Kaufman was 10× slower here). There is no pivoting across supernodes, so this is
//!   best effort: if a pivot vanishes the result is `(0, -inf)` or `(NaN, NaN)`.
//!   For unsymmetric values the determinant is not available and
//!   [`SparseSolver::det_sign_log`] returns `(NaN, NaN)`.

use std::time::Instant;

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::lu::supernodal::{
    factorize_supernodal_numeric_lu, factorize_supernodal_numeric_lu_scratch,
    factorize_supernodal_symbolic_lu, factorize_supernodal_symbolic_lu_scratch, SupernodalLu,
    SymbolicSupernodalLu,
};
use faer::sparse::linalg::lu::{
    factorize_symbolic_lu, LuRef, LuSymbolicParams, NumericLu, SymbolicLu,
};
use faer::sparse::linalg::{amd, qr};
use faer::sparse::linalg::{LuError, SupernodalThreshold};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};

/// Relative tolerance of the symmetry test used for the LU determinant:
/// `|a_ij - a_ji| <= SYMMETRY_RTOL * max |a|`.
pub const SYMMETRY_RTOL: f64 = 1e-10;

/// Which direct factorization to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinearKind {
    /// Sparse Cholesky LLᵀ (symmetric positive definite matrices; only the lower triangle is read).
    Cholesky,
    /// Sparse LU with partial (row) pivoting and a COLAMD column ordering (general matrices).
    Lu,
}

/// Fill-reducing column ordering of the sparse LU ([`LinearKind::Lu`]).
///
/// faer's partial-pivoting LU computes its symbolic structure from the column elimination tree
/// of AᵀA, which bounds the factors for any row pivoting; the column ordering decides the fill.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LuOrdering {
    /// faer's own `factorize_symbolic_lu`: COLAMD on the columns of A (an ordering made for
    /// the Cholesky factor of AᵀA). Measured on the steady tangent of the rolling cylinder (16k
    /// DOFs), fill nnz(L+U)/nnz(A) = 10.7 against 48.8 with [`LuOrdering::Amd`], and a numeric
    /// factorization 8× faster (`tread-bench-lu`); [`LuOrdering::Symmetric`] fills 3.6.
    Colamd,
    /// AMD on the pattern of A + Aᵀ (`faer::sparse::linalg::amd::order`), the ordering a
    /// symmetric-pattern solver would use; then faer's supernodal symbolic and numeric LU with
    /// that column permutation. Finite-element tangents are structurally symmetric, so this
    /// ordering sees the mesh graph directly; but faer's partial-pivoting LU takes its
    /// structure from AᵀA, whose fill this ordering does not minimise (see `Colamd`).
    Amd,
    /// AMD on A + Aᵀ and a multifrontal LU on that symmetric pattern with row pivoting
    /// restricted to each supernode ([`super::multifrontal`]): the factors have exactly the
    /// Cholesky structure of A + Aᵀ. A matrix that this pivoting cannot factorize (a zero
    /// pivot: saddle points with zero diagonal blocks, singular matrices) is handed to the
    /// COLAMD LU, and the multifrontal LU is tried again on later factorizations (after 1, 2,
    /// 4, … up to 32 of them while it keeps failing): a zero pivot of one moment (a load
    /// control's road height before the road is touched) does not leave the rest of the run on
    /// the COLAMD factors, which fill much more (a dense row makes AᵀA dense). The default.
    #[default]
    Symmetric,
}

/// Errors of the sparse direct solver.
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
}

/// Numeric state of the last call of `factorize`.
#[derive(Debug, Clone)]
enum Status {
    /// `factorize` was never called.
    Empty,
    /// The last factorization succeeded.
    Ready,
    NotPositiveDefinite,
    Singular,
    NonFinite,
    Other(String),
}

struct CholeskyState {
    symbolic: SymbolicCholesky<usize>,
    l_values: Vec<f64>,
    /// Position of `L_jj` in `l_values`, for each (permuted) column `j`.
    diag_pos: Vec<usize>,
    /// Stored entries of L (lower triangle incl. diagonal; for supernodal factors this includes
    /// the explicit zeros of relaxed supernodes).
    factor_nnz: usize,
}

/// A supernodal symbolic Cholesky analysis used by the LBLᵀ determinant, with the position of
/// each `D_jj` in the factor values.
struct LbltSymbolic {
    symbolic: SymbolicCholesky<usize>,
    diag_pos: Vec<usize>,
}

impl LbltSymbolic {
    fn new(
        pattern: &SymbolicSparseColMat<usize>,
        ordering: SymmetricOrdering<'_, usize>,
    ) -> Result<Self, LinearError> {
        let symbolic = factorize_symbolic_cholesky(
            pattern.as_ref(),
            Side::Lower,
            ordering,
            CholeskySymbolicParams {
                // The simplicial variant is an LDLᵀ without any pivoting: force supernodes,
                // inside which faer pivots (Bunch–Kaufman).
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                ..Default::default()
            },
        )
        .map_err(map_faer_err)?;
        let (diag_pos, _) = cholesky_diag_positions(&symbolic);
        Ok(Self { symbolic, diag_pos })
    }

    fn scratch(&self) -> StackReq {
        self.symbolic
            .factorize_numeric_intranode_lblt_scratch::<f64>(Par::Seq, Default::default())
    }
}

/// Auxiliary supernodal LBLᵀ used only for the determinant of symmetric matrices in LU mode.
///
/// A pivot-free fill-reducing ordering can put a zero diagonal entry (e.g. the multiplier block
/// of a saddle-point matrix) first in a one-column supernode, where no pivoting is possible. So
/// when the matrix has (numerically) zero diagonal entries, those columns are moved to the end
/// of the AMD ordering (a second symbolic analysis, cached for that set of columns); for a
/// saddle-point matrix with SPD K the trailing block is then the negative definite Schur
/// complement.
struct LbltDet {
    /// Plain AMD analysis of the pattern.
    amd: LbltSymbolic,
    /// Analysis with the zero-diagonal columns (first field) delayed to the end.
    delayed: Option<(Vec<usize>, LbltSymbolic)>,
    /// Zero-diagonal columns of the current matrix (capacity n, reused).
    zero_diag: Vec<usize>,
    /// Position of the diagonal entry of each column in the values, or `usize::MAX`.
    diag_entry: Vec<usize>,
    /// For entry k = (i, j) of the pattern, the index of (j, i), or `usize::MAX` if absent.
    transpose_pos: Vec<usize>,
    l_values: Vec<f64>,
    subdiag: Vec<f64>,
    perm_fwd: Vec<usize>,
    perm_inv: Vec<usize>,
    /// Structural nonzeros of L of the AMD analysis (used for the LU nnz estimate).
    l_nnz: usize,
}

impl LbltDet {
    fn new(pattern: &SymbolicSparseColMat<usize>) -> Result<Self, LinearError> {
        let amd = LbltSymbolic::new(pattern, SymmetricOrdering::Amd)?;
        // Stored entries of the supernodal L (diagonal blocks' lower triangles and the zeros
        // of relaxed supernodes included): good enough for the LU size estimate.
        let (_, l_nnz) = cholesky_diag_positions(&amd.symbolic);
        Ok(Self {
            amd,
            delayed: None,
            zero_diag: Vec::new(),
            diag_entry: Vec::new(),
            transpose_pos: Vec::new(),
            l_values: Vec::new(),
            subdiag: Vec::new(),
            perm_fwd: Vec::new(),
            perm_inv: Vec::new(),
            l_nnz,
        })
    }

    /// (sign, log|det|, negative eigenvalue count) of the symmetric matrix `values`, or `None`
    /// if the values are not symmetric. Allocates only the first time and when the set of zero
    /// diagonal columns changes.
    fn compute(
        &mut self,
        pattern: &SymbolicSparseColMat<usize>,
        values: &[f64],
        par: Par,
        mem: &mut MemBuffer,
        mem_req: &mut StackReq,
    ) -> Result<Option<(f64, f64, Option<usize>)>, LinearError> {
        let n = pattern.ncols();
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        if self.transpose_pos.len() != values.len() {
            self.transpose_pos = transpose_positions(n, col_ptr, row_idx);
            self.diag_entry = (0..n)
                .map(|j| {
                    (col_ptr[j]..col_ptr[j + 1])
                        .find(|&k| row_idx[k] == j)
                        .unwrap_or(usize::MAX)
                })
                .collect();
            self.zero_diag.reserve(n);
            self.subdiag = vec![0.0; n];
            self.perm_fwd = vec![0; n];
            self.perm_inv = vec![0; n];
        }
        // Symmetry test.
        let amax = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let tol = SYMMETRY_RTOL * amax;
        let symmetric = values.iter().zip(&self.transpose_pos).all(|(&v, &t)| {
            let vt = if t == usize::MAX { 0.0 } else { values[t] };
            (v - vt).abs() <= tol
        });
        if !symmetric {
            return Ok(None);
        }
        // Zero diagonal entries.
        self.zero_diag.clear();
        let ztol = 1e-12 * amax;
        for (j, &k) in self.diag_entry.iter().enumerate() {
            if k == usize::MAX || values[k].abs() <= ztol {
                self.zero_diag.push(j);
            }
        }
        let use_delayed = !self.zero_diag.is_empty();
        if use_delayed
            && self
                .delayed
                .as_ref()
                .map(|(set, _)| set != &self.zero_diag)
                .unwrap_or(true)
        {
            // AMD order with the zero-diagonal columns moved to the end.
            let amd_fwd: Vec<usize> = match self.amd.symbolic.perm() {
                Some(p) => p.arrays().0.to_vec(),
                None => (0..n).collect(),
            };
            let mut is_zero = vec![false; n];
            for &j in &self.zero_diag {
                is_zero[j] = true;
            }
            let mut fwd: Vec<usize> = amd_fwd.iter().copied().filter(|&j| !is_zero[j]).collect();
            fwd.extend(amd_fwd.iter().copied().filter(|&j| is_zero[j]));
            let mut inv = vec![0usize; n];
            for (new, &old) in fwd.iter().enumerate() {
                inv[old] = new;
            }
            let perm = faer::perm::PermRef::new_checked(&fwd, &inv, n);
            let sym = LbltSymbolic::new(pattern, SymmetricOrdering::Custom(perm))?;
            self.delayed = Some((self.zero_diag.clone(), sym));
        }
        let sym = match (&self.delayed, use_delayed) {
            (Some((_, d)), true) => d,
            _ => &self.amd,
        };
        grow_scratch(mem, mem_req, sym.scratch());
        let len = sym.symbolic.len_val();
        if self.l_values.len() < len {
            self.l_values.resize(len, 0.0);
        }
        let l_values = &mut self.l_values[..len];
        self.subdiag.fill(0.0);
        let a = SparseColMatRef::new(pattern.as_ref(), values);
        sym.symbolic.factorize_numeric_intranode_lblt(
            l_values,
            &mut self.subdiag,
            &mut self.perm_fwd,
            &mut self.perm_inv,
            a,
            Side::Lower,
            par,
            MemStack::new(mem),
            Default::default(),
        );
        // det(P A Pᵀ) = det(A) = det(D); D has 1x1 blocks and 2x2 blocks [[a, s], [s, b]]
        // where subdiag[j] = s != 0. Negative eigenvalues of A = those of D (Sylvester).
        let mut sign = 1.0f64;
        let mut log = 0.0f64;
        let mut neg = 0usize;
        let mut j = 0;
        while j < n {
            let s = self.subdiag[j];
            let det_block;
            if s == 0.0 || j + 1 == n {
                let a = l_values[sym.diag_pos[j]];
                det_block = a;
                if a < 0.0 {
                    neg += 1;
                }
                j += 1;
            } else {
                let a = l_values[sym.diag_pos[j]];
                let b = l_values[sym.diag_pos[j + 1]];
                det_block = a * b - s * s;
                if det_block < 0.0 {
                    neg += 1;
                } else if a + b < 0.0 {
                    neg += 2;
                }
                j += 2;
            }
            if !det_block.is_finite() {
                return Ok(Some((f64::NAN, f64::NAN, None)));
            }
            if det_block < 0.0 {
                sign = -sign;
            }
            if det_block == 0.0 {
                sign = 0.0;
            }
            log += det_block.abs().ln();
        }
        let neg = if sign != 0.0 { Some(neg) } else { None };
        Ok(Some((sign, log, neg)))
    }
}

struct LuState {
    symbolic: SymbolicLu<usize>,
    numeric: NumericLu<usize, f64>,
    det: LbltDet,
}

impl LuState {
    /// faer's COLAMD LU of this pattern, and the determinant's LBLᵀ analysis.
    fn new(
        pattern: &SymbolicSparseColMat<usize>,
        threshold: SupernodalThreshold,
    ) -> Result<Self, LinearError> {
        let params = LuSymbolicParams {
            supernodal_flop_ratio_threshold: threshold,
            ..Default::default()
        };
        let symbolic = factorize_symbolic_lu(pattern.as_ref(), params).map_err(map_faer_err)?;
        Ok(Self {
            symbolic,
            numeric: NumericLu::new(),
            det: LbltDet::new(pattern)?,
        })
    }
}

/// LU with a column ordering computed here ([`LuOrdering::Amd`]): faer's supernodal symbolic
/// and numeric LU driven directly (its `factorize_symbolic_lu` always uses COLAMD).
struct LuCustomState {
    symbolic: SymbolicSupernodalLu<usize>,
    col_fwd: Vec<usize>,
    col_inv: Vec<usize>,
    row_fwd: Vec<usize>,
    row_inv: Vec<usize>,
    numeric: SupernodalLu<usize, f64>,
    /// Pattern of Aᵀ (the numeric LU reads the rows of A through it).
    at_pattern: SymbolicSparseColMat<usize>,
    /// `at_values[q] = values[at_src[q]]`.
    at_src: Vec<usize>,
    at_values: Vec<f64>,
    det: LbltDet,
}

impl LuCustomState {
    fn new(pattern: &SymbolicSparseColMat<usize>) -> Result<Self, LinearError> {
        let n = pattern.ncols();
        let nnz = pattern.row_idx().len();
        let (at_cp, at_ri, at_src) = transpose_pattern(n, pattern.col_ptr(), pattern.row_idx());
        let at_pattern = SymbolicSparseColMat::new_checked(n, n, at_cp, None, at_ri);
        let mut col_fwd = vec![0usize; n];
        let mut col_inv = vec![0usize; n];
        {
            let mut mem =
                MemBuffer::try_new(amd::order_scratch::<usize>(n, nnz)).map_err(map_faer_err)?;
            amd::order(
                &mut col_fwd,
                &mut col_inv,
                pattern.as_ref(),
                amd::Control::default(),
                MemStack::new(&mut mem),
            )
            .map_err(map_faer_err)?;
        }
        let perm = faer::perm::PermRef::new_checked(&col_fwd, &col_inv, n);
        let mut etree = vec![0usize; n];
        let mut post = vec![0usize; n];
        let mut col_counts = vec![0usize; n];
        let mut min_col = vec![0usize; n];
        let req = StackReq::any_of(&[
            qr::col_etree_scratch::<usize>(n, n),
            qr::postorder_scratch::<usize>(n),
            qr::column_counts_aat_scratch::<usize>(n, n),
            factorize_supernodal_symbolic_lu_scratch::<usize>(n, n),
        ]);
        let mut mem = MemBuffer::try_new(req).map_err(map_faer_err)?;
        // The same steps as faer's `factorize_symbolic_lu`, with our column permutation.
        let et = qr::col_etree(
            pattern.as_ref(),
            Some(perm),
            &mut etree,
            MemStack::new(&mut mem),
        );
        qr::postorder(&mut post, et, MemStack::new(&mut mem));
        qr::column_counts_ata(
            &mut col_counts,
            &mut min_col,
            at_pattern.as_ref(),
            Some(perm),
            et,
            &post,
            MemStack::new(&mut mem),
        );
        let symbolic = factorize_supernodal_symbolic_lu(
            pattern.as_ref(),
            Some(perm),
            &min_col,
            et,
            &col_counts,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .map_err(map_faer_err)?;
        let det = LbltDet::new(pattern)?;
        Ok(Self {
            symbolic,
            col_fwd,
            col_inv,
            row_fwd: vec![0; n],
            row_inv: vec![0; n],
            numeric: SupernodalLu::new(),
            at_pattern,
            at_src,
            at_values: vec![0.0; nnz],
            det,
        })
    }
}

/// CSC pattern of Aᵀ and, for each of its entries, the position of the same entry in A's
/// values.
fn transpose_pattern(
    n: usize,
    col_ptr: &[usize],
    row_idx: &[usize],
) -> (Vec<usize>, Vec<usize>, Vec<usize>) {
    let nnz = row_idx.len();
    let mut at_cp = vec![0usize; n + 1];
    for &i in row_idx {
        at_cp[i + 1] += 1;
    }
    for i in 0..n {
        at_cp[i + 1] += at_cp[i];
    }
    let mut next = at_cp.clone();
    let mut at_ri = vec![0usize; nnz];
    let mut src = vec![0usize; nnz];
    for j in 0..n {
        let col = col_ptr[j]..col_ptr[j + 1];
        for (k, &i) in col.clone().zip(&row_idx[col]) {
            at_ri[next[i]] = j;
            src[next[i]] = k;
            next[i] += 1;
        }
    }
    (at_cp, at_ri, src)
}

/// Stored entries (values, including the explicit zeros of supernodes) of faer's supernodal LU
/// factors, read from the `l_col_ptr_for_val` / `ut_col_ptr_for_val` arrays of its `Debug`
/// output (faer 0.24 has no accessor for them). Formats the whole L value array on the way:
/// seconds for large factors, so for benchmarks only.
fn supernodal_entries(lu: &impl std::fmt::Debug) -> Option<usize> {
    use std::fmt::Write;
    struct Scan {
        tail: String,
        field: Option<usize>,
        last: String,
        found: [Option<usize>; 2],
    }
    const KEYS: [&str; 2] = ["l_col_ptr_for_val: [", "ut_col_ptr_for_val: ["];
    impl Write for Scan {
        fn write_str(&mut self, s: &str) -> std::fmt::Result {
            for c in s.chars() {
                if let Some(f) = self.field {
                    match c {
                        ']' => {
                            self.found[f] = self.last.trim().parse().ok();
                            self.field = None;
                            if self.found.iter().all(|v| v.is_some()) {
                                return Err(std::fmt::Error);
                            }
                        }
                        ',' => self.last.clear(),
                        _ => self.last.push(c),
                    }
                    continue;
                }
                self.tail.push(c);
                if self.tail.len() > 64 {
                    self.tail.drain(..32);
                }
                if c == '[' {
                    for (f, k) in KEYS.iter().enumerate() {
                        if self.tail.ends_with(k) && !(f == 0 && self.tail.ends_with(KEYS[1])) {
                            self.field = Some(f);
                            self.last.clear();
                        }
                    }
                }
            }
            Ok(())
        }
    }
    let mut scan = Scan {
        tail: String::new(),
        field: None,
        last: String::new(),
        found: [None, None],
    };
    let _ = write!(scan, "{lu:?}");
    Some(scan.found[0]? + scan.found[1]?)
}

enum Backend {
    Cholesky(Box<CholeskyState>),
    Lu(Box<LuState>),
    LuCustom(Box<LuCustomState>),
    Symmetric(Box<SymmetricState>),
}

/// [`LuOrdering::Symmetric`]: the factorization and the determinant's LBLᵀ, analysed on the
/// first factorization that tracks the determinant (Newton does not: its solves then make one
/// symbolic analysis, not two).
struct SymmetricState {
    lu: super::multifrontal::SymmetricLu,
    det: Option<LbltDet>,
}

/// The multifrontal LU set aside while the COLAMD LU factorizes (after a factorization it
/// could not do): it is tried again once `wait` more factorizations have gone by.
struct Parked {
    state: Box<SymmetricState>,
    wait: u32,
    /// The wait after the next failed retry (doubled each time, at most [`MAX_BACKOFF`]).
    backoff: u32,
}

/// Longest wait, in factorizations, between two retries of a parked multifrontal LU.
const MAX_BACKOFF: u32 = 32;

impl Backend {
    /// Scratch for one numeric factorization and a one-column solve with `par`.
    fn scratch(&self, par: Par) -> StackReq {
        match self {
            Backend::Cholesky(st) => st
                .symbolic
                .factorize_numeric_llt_scratch::<f64>(par, Default::default())
                .or(st.symbolic.solve_in_place_scratch::<f64>(1, par)),
            Backend::Lu(st) => st
                .symbolic
                .factorize_numeric_lu_scratch::<f64>(par, Default::default())
                .or(st.symbolic.solve_in_place_scratch::<f64>(1, par)),
            Backend::LuCustom(st) => factorize_supernodal_numeric_lu_scratch::<usize, f64>(
                &st.symbolic,
                Default::default(),
            )
            .or(
                faer::sparse::linalg::lu::supernodal::solve_in_place_scratch::<usize, f64>(
                    st.col_fwd.len(),
                    1,
                    par,
                ),
            ),
            Backend::Symmetric(_) => StackReq::EMPTY,
        }
    }
}

/// Reallocate `mem` if `req` does not fit in what it was sized for.
fn grow_scratch(mem: &mut MemBuffer, mem_req: &mut StackReq, req: StackReq) {
    let merged = mem_req.or(req);
    if merged != *mem_req {
        *mem = MemBuffer::new(merged);
        *mem_req = merged;
    }
}

/// Sparse direct solver with the symbolic analysis done once for a fixed CSC pattern.
pub struct SparseSolver {
    n: usize,
    kind: LinearKind,
    pattern: SymbolicSparseColMat<usize>,
    backend: Backend,
    par: Par,
    mem: MemBuffer,
    mem_req: StackReq,
    status: Status,
    track_det: bool,
    /// (sign, log|det|) of the last successful factorization, if known.
    det: Option<(f64, f64)>,
    /// Number of negative eigenvalues of the last successful factorization, if known.
    neg_eigs: Option<usize>,
    /// The multifrontal LU while the COLAMD LU stands in for it ([`LuOrdering::Symmetric`]).
    parked: Option<Parked>,
    /// The COLAMD LU's analysis, kept for the next stand-in once the multifrontal LU is back.
    spare_lu: Option<Box<LuState>>,
}

fn validate_pattern(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Result<(), LinearError> {
    let err = |m: String| Err(LinearError::Symbolic(m));
    if col_ptr.len() != n + 1 {
        return err(format!(
            "col_ptr has length {}, expected n + 1 = {}",
            col_ptr.len(),
            n + 1
        ));
    }
    if col_ptr[0] != 0 {
        return err(format!("col_ptr[0] = {}, expected 0", col_ptr[0]));
    }
    if col_ptr[n] != row_idx.len() {
        return err(format!(
            "col_ptr[n] = {} but row_idx has length {}",
            col_ptr[n],
            row_idx.len()
        ));
    }
    for j in 0..n {
        let (a, b) = (col_ptr[j], col_ptr[j + 1]);
        if b < a {
            return err(format!("col_ptr decreases at column {j}"));
        }
        let rows = &row_idx[a..b];
        for (k, &i) in rows.iter().enumerate() {
            if i >= n {
                return err(format!(
                    "row index {i} out of range in column {j} (n = {n})"
                ));
            }
            if k > 0 && rows[k - 1] >= i {
                return err(format!(
                    "row indices of column {j} are not strictly increasing (duplicate or unsorted)"
                ));
            }
        }
    }
    Ok(())
}

/// Positions of the diagonal entries of a Cholesky-type factor in its value array, and the
/// structural nonzero count of the lower factor.
fn cholesky_diag_positions(symbolic: &SymbolicCholesky<usize>) -> (Vec<usize>, usize) {
    let n = symbolic.nrows();
    let mut pos = vec![0usize; n];
    let nnz;
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => {
            // Column j of L starts with its diagonal entry.
            let cp = s.col_ptr();
            pos.copy_from_slice(&cp[..n]);
            nnz = s.len_val();
        }
        SymbolicCholeskyRaw::Supernodal(s) => {
            let begin = s.supernode_begin();
            let end = s.supernode_end();
            let vp = s.col_ptr_for_val();
            let mut count = 0usize;
            for sn in 0..s.n_supernodes() {
                let ncols = end[sn] - begin[sn];
                // Each supernode is a dense column-major block of nrows x ncols.
                let nrows = (vp[sn + 1] - vp[sn]) / ncols;
                for jj in 0..ncols {
                    pos[begin[sn] + jj] = vp[sn] + jj * nrows + jj;
                }
                count += ncols * (ncols + 1) / 2 + ncols * (nrows - ncols);
            }
            nnz = count;
        }
    }
    (pos, nnz)
}

fn transpose_positions(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Vec<usize> {
    let nnz = row_idx.len();
    // CSR view of the same pattern: for each row, the (col, k) pairs in increasing col order.
    let mut row_ptr = vec![0usize; n + 1];
    for &i in row_idx {
        row_ptr[i + 1] += 1;
    }
    for i in 0..n {
        row_ptr[i + 1] += row_ptr[i];
    }
    let mut next = row_ptr.clone();
    let mut csr_col = vec![0usize; nnz];
    let mut csr_k = vec![0usize; nnz];
    for j in 0..n {
        let range = col_ptr[j]..col_ptr[j + 1];
        for (k, &i) in range.clone().zip(&row_idx[range]) {
            csr_col[next[i]] = j;
            csr_k[next[i]] = k;
            next[i] += 1;
        }
    }
    // Entry a = (i, j) of column j has its transpose (j, i) among the entries of row j; both
    // lists are sorted, so a merge of column j (by row i) with row j (by column c) pairs them.
    let mut tpos = vec![usize::MAX; nnz];
    for j in 0..n {
        let col = col_ptr[j]..col_ptr[j + 1];
        let row = row_ptr[j]..row_ptr[j + 1];
        let (mut a, mut b) = (col.start, row.start);
        while a < col.end && b < row.end {
            let i = row_idx[a];
            let c = csr_col[b];
            if i == c {
                tpos[a] = csr_k[b];
                a += 1;
                b += 1;
            } else if i < c {
                a += 1;
            } else {
                b += 1;
            }
        }
    }
    tpos
}

fn map_faer_err(e: impl std::fmt::Debug) -> LinearError {
    LinearError::Symbolic(format!("{e:?}"))
}

impl SparseSolver {
    /// `col_ptr`/`row_idx`: CSC pattern of the FULL square matrix (both triangles present, rows
    /// sorted within each column, no duplicates), n = col_ptr.len()-1. For Cholesky only the
    /// lower triangle is read.
    pub fn new(
        n: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
        kind: LinearKind,
    ) -> Result<Self, LinearError> {
        Self::build(
            n,
            col_ptr,
            row_idx,
            kind,
            SupernodalThreshold::AUTO,
            LuOrdering::default(),
        )
    }

    /// As [`SparseSolver::new`], with the LU column ordering chosen (no effect for Cholesky,
    /// which always uses AMD).
    pub fn with_lu_ordering(
        n: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
        kind: LinearKind,
        ordering: LuOrdering,
    ) -> Result<Self, LinearError> {
        Self::build(
            n,
            col_ptr,
            row_idx,
            kind,
            SupernodalThreshold::AUTO,
            ordering,
        )
    }

    /// As [`SparseSolver::with_lu_ordering`], with faer's simplicial/supernodal switch forced
    /// (tests; the AMD-ordered LU is always supernodal and ignores it).
    fn build(
        n: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
        kind: LinearKind,
        threshold: SupernodalThreshold,
        ordering: LuOrdering,
    ) -> Result<Self, LinearError> {
        validate_pattern(n, col_ptr, row_idx)?;
        let pattern =
            SymbolicSparseColMat::new_checked(n, n, col_ptr.to_vec(), None, row_idx.to_vec());
        let backend = match kind {
            LinearKind::Cholesky => {
                let params = CholeskySymbolicParams {
                    supernodal_flop_ratio_threshold: threshold,
                    ..Default::default()
                };
                let symbolic = factorize_symbolic_cholesky(
                    pattern.as_ref(),
                    Side::Lower,
                    SymmetricOrdering::Amd,
                    params,
                )
                .map_err(map_faer_err)?;
                let (diag_pos, factor_nnz) = cholesky_diag_positions(&symbolic);
                let l_values = vec![0.0; symbolic.len_val()];
                Backend::Cholesky(Box::new(CholeskyState {
                    symbolic,
                    l_values,
                    diag_pos,
                    factor_nnz,
                }))
            }
            LinearKind::Lu if ordering == LuOrdering::Amd => {
                Backend::LuCustom(Box::new(LuCustomState::new(&pattern)?))
            }
            LinearKind::Lu if ordering == LuOrdering::Symmetric => {
                let lu = super::multifrontal::SymmetricLu::new(n, col_ptr, row_idx)
                    .map_err(|e| LinearError::Symbolic(e.to_string()))?;
                Backend::Symmetric(Box::new(SymmetricState { lu, det: None }))
            }
            LinearKind::Lu => Backend::Lu(Box::new(LuState::new(&pattern, threshold)?)),
        };
        let req = backend.scratch(Par::Seq);
        Ok(Self {
            n,
            kind,
            pattern,
            backend,
            par: Par::Seq,
            mem: MemBuffer::new(req),
            mem_req: req,
            status: Status::Empty,
            track_det: true,
            det: None,
            neg_eigs: None,
            parked: None,
            spare_lu: None,
        })
    }

    /// The factorization kind chosen at construction.
    pub fn kind(&self) -> LinearKind {
        self.kind
    }

    /// Whether this solver was analysed for the CSC pattern (`col_ptr`, `row_idx`).
    pub fn has_pattern(&self, col_ptr: &[usize], row_idx: &[usize]) -> bool {
        self.pattern.col_ptr() == col_ptr && self.pattern.row_idx() == row_idx
    }

    /// System size.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Number of stored entries of the pattern (the expected length of `values`).
    pub fn nnz(&self) -> usize {
        self.pattern.row_idx().len()
    }

    /// Use faer's rayon parallelism (`Par::rayon(0)`: all threads of the global rayon pool)
    /// instead of sequential code. Default: sequential, which measured faster on 2 cores for 2D
    /// FE matrices (see `bench_report`). Switching on may grow the scratch buffer once (the
    /// parallel kernels can need more); switching back never reallocates. The global rayon pool
    /// is only touched from here on (`SparseSolver::new` does not initialize it, so the
    /// application can still configure it with `build_global`).
    pub fn set_parallel(&mut self, par: bool) {
        self.par = if par { Par::rayon(0) } else { Par::Seq };
        let req = self.backend.scratch(self.par);
        grow_scratch(&mut self.mem, &mut self.mem_req, req);
    }

    /// Whether the numeric phase runs in parallel.
    pub fn parallel(&self) -> bool {
        self.par != Par::Seq
    }

    /// LU only: whether `factorize` also computes the determinant (sign, log|det|, inertia) via
    /// an auxiliary LBLᵀ factorization when the values are symmetric. Default: on. Turning it off
    /// saves ~25–30 % of the LU time on symmetric matrices. No effect for Cholesky (free there).
    pub fn set_track_determinant(&mut self, on: bool) {
        self.track_det = on;
    }

    /// Symmetric-pattern LU only: factorize and solve in single precision from the next
    /// factorization on ([`super::multifrontal::SymmetricLu::set_single_precision_factors`]),
    /// for factors that only precondition an iterative solve. A factorization that loses a
    /// pivot to single-precision round-off is redone in double precision, which stays on
    /// ([`Self::single_precision_factors`] then reports it). No effect on other backends.
    pub fn set_single_precision_factors(&mut self, on: bool) {
        if let Backend::Symmetric(st) = &mut self.backend {
            st.lu.set_single_precision_factors(on);
        }
    }

    /// Whether this solver can factorize in single precision (the symmetric-pattern LU;
    /// [`Self::set_single_precision_factors`]).
    pub fn supports_single_precision(&self) -> bool {
        matches!(&self.backend, Backend::Symmetric(_))
    }

    /// Whether the factors are kept in single precision
    /// ([`Self::set_single_precision_factors`] on a symmetric-pattern LU).
    pub fn single_precision_factors(&self) -> bool {
        matches!(&self.backend, Backend::Symmetric(st) if st.lu.single_precision_factors())
    }

    /// Numeric factorization of the matrix with these values (same order as row_idx).
    ///
    /// # Panics
    /// If `values.len()` differs from the number of pattern entries (a programming error).
    pub fn factorize(&mut self, values: &[f64]) -> Result<(), LinearError> {
        assert_eq!(
            values.len(),
            self.nnz(),
            "SparseSolver::factorize: values has length {} but the pattern has {} entries",
            values.len(),
            self.nnz()
        );
        self.status = Status::Empty;
        self.det = None;
        self.neg_eigs = None;
        if values.iter().any(|v| !v.is_finite()) {
            self.status = Status::NonFinite;
            return Err(LinearError::NonFiniteMatrix);
        }
        if self.retry_parked(values) {
            if self.track_det {
                self.lu_determinant(values);
            }
            self.status = Status::Ready;
            return Ok(());
        }
        let a = SparseColMatRef::new(self.pattern.as_ref(), values);
        let par = self.par;
        match &mut self.backend {
            Backend::Cholesky(st) => {
                let res = st.symbolic.factorize_numeric_llt(
                    &mut st.l_values,
                    a,
                    Side::Lower,
                    Default::default(),
                    par,
                    MemStack::new(&mut self.mem),
                    Default::default(),
                );
                // The only error is `LltError::NonPositivePivot` (no allocation happens here).
                if res.is_err() {
                    self.status = Status::NotPositiveDefinite;
                    return Err(LinearError::NotPositiveDefinite);
                }
                let log_det: f64 = 2.0
                    * st.diag_pos
                        .iter()
                        .map(|&p| st.l_values[p].ln())
                        .sum::<f64>();
                self.det = Some((1.0, log_det));
                self.neg_eigs = Some(0);
            }
            Backend::Lu(st) => {
                let res = st.symbolic.factorize_numeric_lu(
                    &mut st.numeric,
                    a,
                    par,
                    MemStack::new(&mut self.mem),
                    Default::default(),
                );
                match res {
                    Ok(_) => {}
                    Err(LuError::SymbolicSingular { .. }) => {
                        self.status = Status::Singular;
                        return Err(LinearError::Singular);
                    }
                    Err(LuError::Generic(e)) => {
                        let msg = format!("numeric LU failed: {e:?}");
                        self.status = Status::Other(msg.clone());
                        return Err(LinearError::Symbolic(msg));
                    }
                }
                if self.track_det {
                    self.lu_determinant(values);
                }
            }
            Backend::LuCustom(st) => {
                for (v, &k) in st.at_values.iter_mut().zip(&st.at_src) {
                    *v = values[k];
                }
                let at = SparseColMatRef::new(st.at_pattern.as_ref(), &st.at_values);
                let col_perm = faer::perm::PermRef::new_checked(&st.col_fwd, &st.col_inv, self.n);
                let res = factorize_supernodal_numeric_lu(
                    &mut st.row_fwd,
                    &mut st.row_inv,
                    &mut st.numeric,
                    a,
                    at,
                    col_perm,
                    &st.symbolic,
                    par,
                    MemStack::new(&mut self.mem),
                    Default::default(),
                );
                match res {
                    Ok(()) => {}
                    Err(LuError::SymbolicSingular { .. }) => {
                        self.status = Status::Singular;
                        return Err(LinearError::Singular);
                    }
                    Err(LuError::Generic(e)) => {
                        let msg = format!("numeric LU failed: {e:?}");
                        self.status = Status::Other(msg.clone());
                        return Err(LinearError::Symbolic(msg));
                    }
                }
                if self.track_det {
                    self.lu_determinant(values);
                }
            }
            Backend::Symmetric(st) => {
                // A pivot that the pivoting within supernodes could not make nonzero (a zero
                // diagonal block, a singular matrix): hand over to the partial-pivoting LU.
                let mut ok = st.lu.factorize(values, par).is_ok() && st.lu.perturbed() == 0;
                if !ok && st.lu.single_precision_factors() {
                    // A pivot lost to single-precision round-off (a nearly singular block):
                    // the same LU in double precision.
                    st.lu.set_single_precision_factors(false);
                    ok = st.lu.factorize(values, par).is_ok() && st.lu.perturbed() == 0;
                }
                if !ok {
                    return self.fall_back_to_colamd(values);
                }
                if self.track_det {
                    self.lu_determinant(values);
                }
            }
        }
        self.status = Status::Ready;
        Ok(())
    }

    /// With a parked multifrontal LU whose wait is over: factorize `values` with it, and on
    /// success make it the backend again (true). On failure, or while it waits, count the
    /// wait down (false: the COLAMD LU factorizes).
    fn retry_parked(&mut self, values: &[f64]) -> bool {
        let Some(p) = self.parked.as_mut() else {
            return false;
        };
        if p.wait > 0 {
            p.wait -= 1;
            return false;
        }
        if p.state.lu.factorize(values, self.par).is_ok() && p.state.lu.perturbed() == 0 {
            if let Some(p) = self.parked.take() {
                if let Backend::Lu(lu) =
                    std::mem::replace(&mut self.backend, Backend::Symmetric(p.state))
                {
                    self.spare_lu = Some(lu);
                }
            }
            return true;
        }
        p.wait = p.backoff;
        p.backoff = (2 * p.backoff).min(MAX_BACKOFF);
        false
    }

    /// Hand the factorization to faer's COLAMD LU (partial pivoting), park the multifrontal
    /// LU for a later retry ([`Self::retry_parked`]), and factorize.
    fn fall_back_to_colamd(&mut self, values: &[f64]) -> Result<(), LinearError> {
        let lu = match self.spare_lu.take() {
            Some(lu) => lu,
            None => match LuState::new(&self.pattern, SupernodalThreshold::AUTO) {
                Ok(st) => Box::new(st),
                Err(e) => {
                    self.status = Status::Other(e.to_string());
                    return Err(e);
                }
            },
        };
        let old = std::mem::replace(&mut self.backend, Backend::Lu(lu));
        let req = self.backend.scratch(self.par);
        grow_scratch(&mut self.mem, &mut self.mem_req, req);
        let res = self.factorize(values);
        // Parked after this factorization, so that the next one is its first retry.
        if let Backend::Symmetric(state) = old {
            self.parked = Some(Parked {
                state,
                wait: 0,
                backoff: 1,
            });
        }
        res
    }

    /// LBLᵀ determinant for symmetric values in LU mode (sets `self.det`, `self.neg_eigs`).
    /// A failure here (only the symbolic analysis of the delayed ordering can fail) leaves the
    /// determinant unavailable; the LU factorization itself is unaffected.
    fn lu_determinant(&mut self, values: &[f64]) {
        let det = match &mut self.backend {
            Backend::Lu(st) => &mut st.det,
            Backend::LuCustom(st) => &mut st.det,
            Backend::Symmetric(st) => match &mut st.det {
                Some(d) => d,
                None => match LbltDet::new(&self.pattern) {
                    Ok(d) => st.det.insert(d),
                    Err(_) => return,
                },
            },
            Backend::Cholesky(_) => return,
        };
        // Always sequential: faer's parallel dense Bunch–Kaufman on the many small supernodes
        // measured 10x slower than sequential (+1.0 s instead of +0.1 s at n = 100k).
        if let Ok(Some((sign, log, neg))) = det.compute(
            &self.pattern,
            values,
            Par::Seq,
            &mut self.mem,
            &mut self.mem_req,
        ) {
            self.det = Some((sign, log));
            self.neg_eigs = neg;
        }
    }

    /// Solve A x = b in place (b overwritten by x) using the last factorization; multiple solves
    /// per factorization allowed. Checks the result is finite (-> Singular).
    ///
    /// A non-finite right-hand side also yields `Singular`. Calling it when the last
    /// `factorize` failed returns that failure again; before any `factorize` it returns
    /// `Symbolic("no numeric factorization")`.
    pub fn solve_in_place(&mut self, rhs: &mut [f64]) -> Result<(), LinearError> {
        if rhs.len() != self.n {
            return Err(LinearError::Size {
                got: rhs.len(),
                expected: self.n,
            });
        }
        match &self.status {
            Status::Ready => {}
            Status::Empty => {
                return Err(LinearError::Symbolic("no numeric factorization".into()));
            }
            Status::NotPositiveDefinite => return Err(LinearError::NotPositiveDefinite),
            Status::Singular => return Err(LinearError::Singular),
            Status::NonFinite => return Err(LinearError::NonFiniteMatrix),
            Status::Other(m) => return Err(LinearError::Symbolic(m.clone())),
        }
        let n = self.n;
        let par = self.par;
        if let Backend::Symmetric(st) = &mut self.backend {
            st.lu.solve_in_place(rhs);
            return if rhs.iter().all(|v| v.is_finite()) {
                Ok(())
            } else {
                Err(LinearError::Singular)
            };
        }
        let x = MatMut::from_column_major_slice_mut(rhs, n, 1);
        let stack = MemStack::new(&mut self.mem);
        match &self.backend {
            Backend::Cholesky(st) => {
                LltRef::new(&st.symbolic, &st.l_values).solve_in_place_with_conj(
                    Conj::No,
                    x,
                    par,
                    stack,
                );
            }
            Backend::Lu(st) => {
                LuRef::new_unchecked(&st.symbolic, &st.numeric).solve_in_place_with_conj(
                    Conj::No,
                    x,
                    par,
                    stack,
                );
            }
            Backend::LuCustom(st) => {
                let row_perm = faer::perm::PermRef::new_checked(&st.row_fwd, &st.row_inv, n);
                let col_perm = faer::perm::PermRef::new_checked(&st.col_fwd, &st.col_inv, n);
                st.numeric
                    .solve_in_place_with_conj(row_perm, col_perm, Conj::No, x, par, stack);
            }
            Backend::Symmetric(_) => {} // solved above
        }
        if rhs.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(LinearError::Singular)
        }
    }

    /// Sign of det(A) (+1 or -1) and log|det A| from the last factorization.
    ///
    /// - Cholesky: always +1 and 2 Σ log L_ii.
    /// - LU: from the auxiliary LBLᵀ factorization (see the module docs); requires symmetric
    ///   values and determinant tracking (default on). A zero pivot gives `(0, -inf)`.
    ///
    /// Returns `(NaN, NaN)` when no determinant is available: no successful factorization yet,
    /// LU with unsymmetric values, or LU with tracking off.
    pub fn det_sign_log(&self) -> (f64, f64) {
        self.det.unwrap_or((f64::NAN, f64::NAN))
    }

    /// Number of negative eigenvalues of the last factorized matrix, when known (Cholesky: 0;
    /// LU: from the inertia of the auxiliary LBLᵀ, symmetric values only). Useful to tell which
    /// eigenvalue crossed zero in bifurcation detection.
    pub fn negative_eigenvalues(&self) -> Option<usize> {
        self.neg_eigs
    }

    /// Number of nonzeros in the factors (for reporting).
    ///
    /// Cholesky: stored entries of L (lower triangle incl. diagonal, with the explicit zeros of
    /// relaxed supernodes). LU: faer does not
    /// expose the LU factor sizes (they depend on pivoting), so this returns the estimate
    /// `2 nnz(L) - n` from the AMD Cholesky analysis of the same pattern.
    pub fn factor_nnz(&self) -> usize {
        match &self.backend {
            Backend::Cholesky(st) => st.factor_nnz,
            Backend::Lu(st) => (2 * st.det.l_nnz).saturating_sub(self.n),
            Backend::LuCustom(st) => (2 * st.det.l_nnz).saturating_sub(self.n),
            Backend::Symmetric(st) => st.lu.factor_entries(),
        }
    }

    /// The LU column ordering in use (`None` for Cholesky).
    pub fn lu_ordering(&self) -> Option<LuOrdering> {
        match &self.backend {
            Backend::Cholesky(_) => None,
            Backend::Lu(_) => Some(LuOrdering::Colamd),
            Backend::LuCustom(_) => Some(LuOrdering::Amd),
            Backend::Symmetric(_) => Some(LuOrdering::Symmetric),
        }
    }

    /// Stored entries of the numeric LU factors L and U of the last factorization (supernodal
    /// blocks, explicit zeros included), or `None` (Cholesky, no factorization yet, or faer's
    /// simplicial LU). Costs about as much as formatting the factor values (seconds at 10⁵
    /// unknowns): for benchmarks, not for the solve loop.
    pub fn lu_factor_entries(&self) -> Option<usize> {
        if !matches!(self.status, Status::Ready) {
            return None;
        }
        match &self.backend {
            Backend::Cholesky(_) => None,
            Backend::Lu(st) => supernodal_entries(&st.numeric),
            Backend::LuCustom(st) => supernodal_entries(&st.numeric),
            Backend::Symmetric(st) => Some(st.lu.factor_entries()),
        }
    }
}

/// Write a square CSC matrix as MatrixMarket `coordinate real general` (1-based indices,
/// one entry per stored value, explicit zeros included so the pattern is the solver's).
pub fn write_matrix_market(
    path: &std::path::Path,
    n: usize,
    col_ptr: &[usize],
    row_idx: &[usize],
    values: &[f64],
) -> std::io::Result<()> {
    use std::io::Write;
    let mut w = std::io::BufWriter::new(std::fs::File::create(path)?);
    writeln!(w, "%%MatrixMarket matrix coordinate real general")?;
    writeln!(
        w,
        "% written by tread: steady tangent dR/dx at the converged state"
    )?;
    writeln!(w, "{n} {n} {}", values.len())?;
    for j in 0..n {
        for k in col_ptr[j]..col_ptr[j + 1] {
            writeln!(w, "{} {} {:.17e}", row_idx[k] + 1, j + 1, values[k])?;
        }
    }
    w.flush()
}

/// Write a vector as MatrixMarket `array real general` (one column).
pub fn write_vector_market(path: &std::path::Path, v: &[f64]) -> std::io::Result<()> {
    use std::io::Write;
    let mut w = std::io::BufWriter::new(std::fs::File::create(path)?);
    writeln!(w, "%%MatrixMarket matrix array real general")?;
    writeln!(w, "{} 1", v.len())?;
    for x in v {
        writeln!(w, "{x:.17e}")?;
    }
    w.flush()
}

/// Build the pattern and values of a 2D 9-point-stencil matrix on an `n_side` x `n_side` grid
/// with 2 dofs per node (full 2x2 coupling blocks). Symmetric, strictly diagonally dominant
/// (hence SPD). Returns (n, col_ptr, row_idx, values).
pub fn stencil_matrix_2d(n_side: usize) -> (usize, Vec<usize>, Vec<usize>, Vec<f64>) {
    let nn = n_side * n_side;
    let n = 2 * nn;
    let mut col_ptr = Vec::with_capacity(n + 1);
    col_ptr.push(0);
    let mut row_idx = Vec::with_capacity(18 * n);
    let mut values = Vec::with_capacity(18 * n);
    for node in 0..nn {
        let (ix, iy) = ((node % n_side) as i64, (node / n_side) as i64);
        for c in 0..2 {
            for dy in -1i64..=1 {
                for dx in -1i64..=1 {
                    let (jx, jy) = (ix + dx, iy + dy);
                    if jx < 0 || jy < 0 || jx >= n_side as i64 || jy >= n_side as i64 {
                        continue;
                    }
                    let m = jy as usize * n_side + jx as usize;
                    for r in 0..2 {
                        row_idx.push(2 * m + r);
                        let v = match (m == node, r == c) {
                            (true, true) => 9.0,
                            (true, false) => 0.1,
                            (false, true) => -1.0,
                            (false, false) => -0.1,
                        };
                        values.push(v);
                    }
                }
            }
            col_ptr.push(row_idx.len());
        }
    }
    (n, col_ptr, row_idx, values)
}

/// Micro benchmark: builds the 2D 9-point matrix with 2 dofs per node on an `n_side` x `n_side`
/// grid (n = 2 n_side²) and times symbolic analysis, numeric factorization (first call and a
/// repeated call) and one solve, for Cholesky and LU, sequential and rayon-parallel.
/// For LU the repeated factorization is timed with determinant tracking off and on.
/// The parallel runs use (and, if needed, initialize) the global rayon pool: configure the
/// pool before calling this if it must be customized.
pub fn bench_report(n_side: usize) -> String {
    use std::fmt::Write;
    let (n, cp, ri, vals) = stencil_matrix_2d(n_side);
    let b: Vec<f64> = (0..n).map(|i| 1.0 + (i % 7) as f64).collect();
    let mut out = String::new();
    let _ = writeln!(
        out,
        "sparse direct solver benchmark: 2D 9-point stencil, 2 dofs/node, n_side = {n_side}, \
         n = {n}, nnz(A) = {}, rayon threads = {}",
        ri.len(),
        Par::rayon(0).degree()
    );
    for kind in [LinearKind::Cholesky, LinearKind::Lu] {
        for par in [false, true] {
            let t = Instant::now();
            let solver = SparseSolver::new(n, &cp, &ri, kind);
            let t_sym = t.elapsed().as_secs_f64();
            let mut s = match solver {
                Ok(s) => s,
                Err(e) => {
                    let _ = writeln!(out, "{kind:?}: symbolic failed: {e}");
                    continue;
                }
            };
            s.set_parallel(par);
            s.set_track_determinant(false);
            let t = Instant::now();
            let r1 = s.factorize(&vals);
            let t_num1 = t.elapsed().as_secs_f64();
            let t = Instant::now();
            let r2 = s.factorize(&vals);
            let t_num2 = t.elapsed().as_secs_f64();
            let mut x = b.clone();
            let t = Instant::now();
            let r3 = s.solve_in_place(&mut x);
            let t_solve = t.elapsed().as_secs_f64();
            let ok = r1.is_ok() && r2.is_ok() && r3.is_ok();
            let _ = write!(
                out,
                "{:<8} {:<5} symbolic {:7.3} s  numeric(1st) {:7.3} s  numeric {:7.3} s  \
                 solve {:7.4} s  nnz(factors) {}{}",
                format!("{kind:?}"),
                if par { "rayon" } else { "seq" },
                t_sym,
                t_num1,
                t_num2,
                t_solve,
                s.factor_nnz(),
                if kind == LinearKind::Lu {
                    " (estimate)"
                } else {
                    ""
                },
            );
            if kind == LinearKind::Lu {
                s.set_track_determinant(true);
                let _ = s.factorize(&vals);
                let t = Instant::now();
                let _ = s.factorize(&vals);
                let _ = write!(out, "  numeric+det {:7.3} s", t.elapsed().as_secs_f64());
            }
            let _ = writeln!(out, "{}", if ok { "" } else { "  [FAILED]" });
        }
    }
    out
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;

    /// Deterministic xorshift generator for test matrices.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        }
    }

    /// Dense row-major n x n -> CSC of all entries with |a| > 0 plus the diagonal; pattern made
    /// structurally symmetric.
    fn dense_to_csc(a: &[Vec<f64>]) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
        let n = a.len();
        let mut cp = vec![0];
        let mut ri = vec![];
        let mut v = vec![];
        for j in 0..n {
            for i in 0..n {
                if a[i][j] != 0.0 || a[j][i] != 0.0 || i == j {
                    ri.push(i);
                    v.push(a[i][j]);
                }
            }
            cp.push(ri.len());
        }
        (cp, ri, v)
    }

    /// Dense Gaussian elimination with partial pivoting: solution and (sign, log|det|).
    fn dense_solve(a: &[Vec<f64>], b: &[f64]) -> (Vec<f64>, f64, f64) {
        let n = a.len();
        let mut m: Vec<Vec<f64>> = a.to_vec();
        let mut x = b.to_vec();
        let mut sign = 1.0;
        let mut logdet = 0.0;
        for k in 0..n {
            let p = (k..n)
                .max_by(|&i, &j| m[i][k].abs().partial_cmp(&m[j][k].abs()).unwrap())
                .unwrap();
            if p != k {
                m.swap(p, k);
                x.swap(p, k);
                sign = -sign;
            }
            let piv = m[k][k];
            assert!(piv != 0.0, "dense reference: singular");
            if piv < 0.0 {
                sign = -sign;
            }
            logdet += piv.abs().ln();
            for i in k + 1..n {
                let f = m[i][k] / piv;
                if f != 0.0 {
                    for j in k..n {
                        m[i][j] -= f * m[k][j];
                    }
                    x[i] -= f * x[k];
                }
            }
        }
        for k in (0..n).rev() {
            let mut s = x[k];
            for j in k + 1..n {
                s -= m[k][j] * x[j];
            }
            x[k] = s / m[k][k];
        }
        (x, sign, logdet)
    }

    fn max_diff(a: &[f64], b: &[f64]) -> f64 {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
    }

    /// Random sparse SPD matrix: random sparse symmetric B, A = B + (rowsum|B| + 1) I.
    fn random_spd(n: usize, density: f64, seed: u64) -> Vec<Vec<f64>> {
        let mut rng = Rng(seed);
        let mut a = vec![vec![0.0; n]; n];
        for i in 0..n {
            for j in 0..i {
                if rng.next().abs() < density {
                    let v = rng.next();
                    a[i][j] = v;
                    a[j][i] = v;
                }
            }
        }
        for i in 0..n {
            let s: f64 = a[i].iter().map(|v| v.abs()).sum();
            a[i][i] = s + 1.0 + rng.next().abs();
        }
        a
    }

    /// faer's COLAMD LU (automatic, simplicial, supernodal), the AMD-ordered LU and the
    /// multifrontal LU on the symmetric pattern.
    const THRESHOLDS: [(SupernodalThreshold, LuOrdering); 5] = [
        (SupernodalThreshold::AUTO, LuOrdering::Colamd),
        (SupernodalThreshold::FORCE_SIMPLICIAL, LuOrdering::Colamd),
        (SupernodalThreshold::FORCE_SUPERNODAL, LuOrdering::Colamd),
        (SupernodalThreshold::AUTO, LuOrdering::Amd),
        (SupernodalThreshold::AUTO, LuOrdering::Symmetric),
    ];

    impl SparseSolver {
        fn with_threshold(
            n: usize,
            col_ptr: &[usize],
            row_idx: &[usize],
            kind: LinearKind,
            (th, ord): (SupernodalThreshold, LuOrdering),
        ) -> Result<Self, LinearError> {
            Self::build(n, col_ptr, row_idx, kind, th, ord)
        }
    }

    fn solver(
        a: &[Vec<f64>],
        kind: LinearKind,
        th: (SupernodalThreshold, LuOrdering),
    ) -> (SparseSolver, Vec<f64>) {
        let (cp, ri, v) = dense_to_csc(a);
        let s = SparseSolver::with_threshold(a.len(), &cp, &ri, kind, th).unwrap();
        (s, v)
    }

    #[test]
    fn spd_cholesky_and_lu_match_dense() {
        for (n, seed) in [(7, 1), (40, 2), (120, 3)] {
            let a = random_spd(n, 0.1, seed);
            let mut rng = Rng(seed + 100);
            let b: Vec<f64> = (0..n).map(|_| rng.next()).collect();
            let (xd, sd, ld) = dense_solve(&a, &b);
            for kind in [LinearKind::Cholesky, LinearKind::Lu] {
                for th in THRESHOLDS {
                    for par in [false, true] {
                        let (mut s, v) = solver(&a, kind, th);
                        s.set_parallel(par);
                        assert_eq!(s.kind(), kind);
                        assert_eq!(s.n(), n);
                        s.factorize(&v).unwrap();
                        let mut x = b.clone();
                        s.solve_in_place(&mut x).unwrap();
                        assert!(max_diff(&x, &xd) < 1e-10, "{kind:?} {th:?} n={n}");
                        // Second solve with the same factorization.
                        let mut x2 = b.iter().map(|v| 2.0 * v).collect::<Vec<_>>();
                        s.solve_in_place(&mut x2).unwrap();
                        let x2d: Vec<f64> = xd.iter().map(|v| 2.0 * v).collect();
                        assert!(max_diff(&x2, &x2d) < 1e-10);
                        let (sign, logdet) = s.det_sign_log();
                        assert_eq!(sign, sd);
                        assert!((logdet - ld).abs() < 1e-9 * ld.abs().max(1.0));
                        assert_eq!(s.negative_eigenvalues(), Some(0));
                        assert!(s.factor_nnz() >= n);
                    }
                }
            }
        }
    }

    /// [[K, Bᵀ], [B, 0]] with K SPD (nk x nk) and B full row rank (nb x nk).
    fn saddle_point(nk: usize, nb: usize, seed: u64) -> Vec<Vec<f64>> {
        let k = random_spd(nk, 0.3, seed);
        let n = nk + nb;
        let mut a = vec![vec![0.0; n]; n];
        for i in 0..nk {
            for j in 0..nk {
                a[i][j] = k[i][j];
            }
        }
        let mut rng = Rng(seed + 7);
        for r in 0..nb {
            // B row r: a strong entry at column 2r plus some random ones.
            for c in 0..nk {
                let v = if c == 2 * r {
                    1.0
                } else if rng.next().abs() < 0.2 {
                    0.3 * rng.next()
                } else {
                    0.0
                };
                a[nk + r][c] = v;
                a[c][nk + r] = v;
            }
        }
        a
    }

    #[test]
    fn saddle_point_lu_ok_cholesky_fails() {
        let a = saddle_point(30, 8, 11);
        let n = a.len();
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let (xd, sd, ld) = dense_solve(&a, &b);
        // A saddle point matrix with nb constraints has exactly nb negative eigenvalues.
        assert_eq!(sd, if 8 % 2 == 0 { 1.0 } else { -1.0 });
        for th in THRESHOLDS {
            let (mut s, v) = solver(&a, LinearKind::Lu, th);
            s.factorize(&v).unwrap();
            let mut x = b.clone();
            s.solve_in_place(&mut x).unwrap();
            assert!(max_diff(&x, &xd) < 1e-9, "{th:?}");
            let (sign, logdet) = s.det_sign_log();
            assert_eq!(sign, sd);
            assert!(
                (logdet - ld).abs() < 1e-8 * ld.abs().max(1.0),
                "{logdet} {ld}"
            );
            assert_eq!(s.negative_eigenvalues(), Some(8));

            let (mut c, v) = solver(&a, LinearKind::Cholesky, th);
            assert!(matches!(
                c.factorize(&v),
                Err(LinearError::NotPositiveDefinite)
            ));
            let mut x = b.clone();
            assert!(matches!(
                c.solve_in_place(&mut x),
                Err(LinearError::NotPositiveDefinite)
            ));
            assert!(c.det_sign_log().0.is_nan());
        }
    }

    #[test]
    fn unsymmetric_lu() {
        let n = 50;
        let mut a = random_spd(n, 0.15, 21);
        let mut rng = Rng(22);
        for i in 0..n {
            for j in 0..n {
                if i != j && a[i][j] != 0.0 {
                    a[i][j] += 0.5 * rng.next(); // break symmetry, keep the pattern
                }
            }
        }
        a[3][40] = 0.7; // structurally unsymmetric entry (the CSC helper symmetrizes the pattern)
        let b: Vec<f64> = (0..n).map(|_| rng.next()).collect();
        let (xd, _, _) = dense_solve(&a, &b);
        for th in THRESHOLDS {
            let (mut s, v) = solver(&a, LinearKind::Lu, th);
            s.factorize(&v).unwrap();
            let mut x = b.clone();
            s.solve_in_place(&mut x).unwrap();
            assert!(max_diff(&x, &xd) < 1e-10, "{th:?}");
            // Factorized on the symmetric pattern, not handed over.
            assert_eq!(s.lu_ordering(), Some(th.1), "{th:?}");
            // Unsymmetric: no determinant.
            let (sign, logdet) = s.det_sign_log();
            assert!(sign.is_nan() && logdet.is_nan());
            assert_eq!(s.negative_eigenvalues(), None);
        }
    }

    #[test]
    fn refactorize_with_new_values() {
        let n = 60;
        let a1 = random_spd(n, 0.1, 31);
        let (cp, ri, v1) = dense_to_csc(&a1);
        // Same pattern, different values: scale and shift the diagonal.
        let mut a2 = a1.clone();
        for i in 0..n {
            for j in 0..n {
                if a2[i][j] != 0.0 {
                    a2[i][j] *= if i == j { 1.5 } else { -0.8 };
                }
            }
        }
        let (cp2, ri2, v2) = dense_to_csc(&a2);
        assert_eq!((cp.clone(), ri.clone()), (cp2, ri2));
        let b: Vec<f64> = (0..n).map(|i| 1.0 + i as f64 * 0.01).collect();
        let (x1d, _, l1) = dense_solve(&a1, &b);
        let (x2d, _, l2) = dense_solve(&a2, &b);
        for kind in [LinearKind::Cholesky, LinearKind::Lu] {
            for th in THRESHOLDS {
                let mut s = SparseSolver::with_threshold(n, &cp, &ri, kind, th).unwrap();
                for (v, xd, ld) in [(&v1, &x1d, l1), (&v2, &x2d, l2), (&v1, &x1d, l1)] {
                    s.factorize(v).unwrap();
                    let mut x = b.clone();
                    s.solve_in_place(&mut x).unwrap();
                    assert!(max_diff(&x, xd) < 1e-10, "{kind:?} {th:?}");
                    assert!((s.det_sign_log().1 - ld).abs() < 1e-9 * ld.abs());
                }
            }
        }
    }

    #[test]
    fn det_sign_one_negative_eigenvalue() {
        // SPD matrix with one eigenvalue pushed below zero: A = S - (λ_min-ish shift) via a
        // rank-one update along a sparse vector u: A = S - c u uᵀ.
        let n = 40;
        let mut a = random_spd(n, 0.1, 41);
        // Make it tridiagonal-coupled too so that u uᵀ stays within a small pattern.
        let idx = [5usize, 6];
        let c = a[5][5] + a[6][6] + 10.0;
        for &i in &idx {
            for &j in &idx {
                a[i][j] -= c * 0.5;
            }
        }
        let b: Vec<f64> = (0..n).map(|i| (i as f64).cos()).collect();
        let (xd, sd, ld) = dense_solve(&a, &b);
        assert_eq!(sd, -1.0, "test matrix should have a negative determinant");
        for th in THRESHOLDS {
            let (mut s, v) = solver(&a, LinearKind::Lu, th);
            s.factorize(&v).unwrap();
            let mut x = b.clone();
            s.solve_in_place(&mut x).unwrap();
            assert!(max_diff(&x, &xd) < 1e-9);
            let (sign, logdet) = s.det_sign_log();
            assert_eq!(sign, -1.0, "{th:?}");
            assert!(
                (logdet - ld).abs() < 1e-9 * ld.abs().max(1.0),
                "{logdet} vs {ld}"
            );
            assert_eq!(s.negative_eigenvalues(), Some(1));
            // Tracking off: no determinant, solve unaffected.
            s.set_track_determinant(false);
            s.factorize(&v).unwrap();
            assert!(s.det_sign_log().0.is_nan());
            let mut x = b.clone();
            s.solve_in_place(&mut x).unwrap();
            assert!(max_diff(&x, &xd) < 1e-9);

            let (mut c, v) = solver(&a, LinearKind::Cholesky, th);
            assert!(matches!(
                c.factorize(&v),
                Err(LinearError::NotPositiveDefinite)
            ));
        }
    }

    #[test]
    fn singular_matrix_gives_singular_error() {
        // Numerically singular: two identical rows/columns (symmetric, rank deficient).
        let n = 20;
        let mut a = random_spd(n, 0.2, 51);
        for j in 0..n {
            a[7][j] = a[3][j];
        }
        for i in 0..n {
            a[i][7] = a[i][3];
        }
        a[7][7] = a[3][3];
        a[7][3] = a[3][3];
        a[3][7] = a[3][3];
        let b: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
        for th in THRESHOLDS {
            let (mut s, v) = solver(&a, LinearKind::Lu, th);
            let r = s.factorize(&v).and_then(|_| {
                let mut x = b.clone();
                s.solve_in_place(&mut x)
            });
            assert!(matches!(r, Err(LinearError::Singular)), "{th:?}: {r:?}");
        }
        // Zero matrix (structurally present, all values zero).
        let z = vec![vec![0.0; 5]; 5];
        for th in THRESHOLDS {
            let (mut s, v) = solver(&z, LinearKind::Lu, th);
            let r = s.factorize(&v).and_then(|_| {
                let mut x = vec![1.0; 5];
                s.solve_in_place(&mut x)
            });
            assert!(matches!(r, Err(LinearError::Singular)), "{th:?}: {r:?}");
            let (mut c, v) = solver(&z, LinearKind::Cholesky, th);
            assert!(matches!(
                c.factorize(&v),
                Err(LinearError::NotPositiveDefinite)
            ));
        }
        // Structurally singular: an empty column (only the zero diagonal entry is missing too).
        let cp = vec![0, 2, 2, 4];
        let ri = vec![0, 2, 0, 2];
        let v = vec![1.0, 2.0, 3.0, 4.0];
        let mut s = SparseSolver::new(3, &cp, &ri, LinearKind::Lu).unwrap();
        let r = s.factorize(&v).and_then(|_| {
            let mut x = vec![1.0; 3];
            s.solve_in_place(&mut x)
        });
        assert!(matches!(r, Err(LinearError::Singular)), "{r:?}");
    }

    #[test]
    fn wrong_rhs_length_and_bad_input() {
        let a = random_spd(10, 0.3, 61);
        for kind in [LinearKind::Cholesky, LinearKind::Lu] {
            let (mut s, mut v) = solver(&a, kind, THRESHOLDS[0]);
            let mut x = vec![1.0; 10];
            // Before any factorization: an error, not a panic.
            assert!(s.solve_in_place(&mut x).is_err());
            s.factorize(&v).unwrap();
            let mut short = vec![1.0; 9];
            match s.solve_in_place(&mut short) {
                Err(LinearError::Size { got, expected }) => assert_eq!((got, expected), (9, 10)),
                r => panic!("expected Size error, got {r:?}"),
            }
            v[3] = f64::NAN;
            assert!(matches!(s.factorize(&v), Err(LinearError::NonFiniteMatrix)));
            v[3] = f64::INFINITY;
            assert!(matches!(s.factorize(&v), Err(LinearError::NonFiniteMatrix)));
            assert!(matches!(
                s.solve_in_place(&mut x),
                Err(LinearError::NonFiniteMatrix)
            ));
        }
        // Invalid patterns are reported, not panicked on.
        let bad: [(usize, Vec<usize>, Vec<usize>); 4] = [
            (2, vec![0, 1], vec![0]),             // col_ptr too short
            (2, vec![0, 2, 3], vec![1, 0, 1]),    // unsorted
            (2, vec![0, 2, 4], vec![0, 0, 0, 1]), // duplicate
            (2, vec![0, 1, 2], vec![0, 5]),       // out of range
        ];
        for (n, cp, ri) in bad {
            for kind in [LinearKind::Cholesky, LinearKind::Lu] {
                assert!(matches!(
                    SparseSolver::new(n, &cp, &ri, kind),
                    Err(LinearError::Symbolic(_))
                ));
            }
        }
    }

    #[test]
    fn stencil_matrix_small() {
        // The benchmark matrix is SPD: Cholesky succeeds and agrees with LU.
        let (n, cp, ri, v) = stencil_matrix_2d(12);
        let b: Vec<f64> = (0..n).map(|i| (i % 5) as f64).collect();
        let mut c = SparseSolver::new(n, &cp, &ri, LinearKind::Cholesky).unwrap();
        let mut l = SparseSolver::new(n, &cp, &ri, LinearKind::Lu).unwrap();
        c.factorize(&v).unwrap();
        l.factorize(&v).unwrap();
        let (mut xc, mut xl) = (b.clone(), b.clone());
        c.solve_in_place(&mut xc).unwrap();
        l.solve_in_place(&mut xl).unwrap();
        assert!(max_diff(&xc, &xl) < 1e-12);
        // Residual check A x = b.
        let mut ax = vec![0.0; n];
        for j in 0..n {
            for k in cp[j]..cp[j + 1] {
                ax[ri[k]] += v[k] * xc[j];
            }
        }
        assert!(max_diff(&ax, &b) < 1e-10);
        let (dc, dl) = (c.det_sign_log(), l.det_sign_log());
        assert_eq!((dc.0, dl.0), (1.0, 1.0));
        assert!((dc.1 - dl.1).abs() < 1e-9 * dc.1.abs());
    }

    /// Exact eigenvalues of `stencil_matrix_2d(m)`: A = I ⊗ C0 - (J⊗J - I) ⊗ C1 with J the
    /// m x m tridiagonal all-ones matrix, C0 = [[9, .1], [.1, 9]], C1 = [[1, .1], [.1, 1]].
    fn stencil_eigenvalues(m: usize) -> Vec<f64> {
        let pi = std::f64::consts::PI;
        let mut eig = vec![];
        for a in 1..=m {
            for b in 1..=m {
                let ja = 1.0 + 2.0 * (a as f64 * pi / (m + 1) as f64).cos();
                let jb = 1.0 + 2.0 * (b as f64 * pi / (m + 1) as f64).cos();
                let mu = ja * jb;
                eig.push(9.1 - (mu - 1.0) * 1.1);
                eig.push(8.9 - (mu - 1.0) * 0.9);
            }
        }
        eig.sort_by(|x, y| x.partial_cmp(y).unwrap());
        eig
    }

    #[test]
    fn shifted_stencil_inertia_and_log_det() {
        let m = 16;
        let (n, cp, ri, v) = stencil_matrix_2d(m);
        let eig = stencil_eigenvalues(m);
        assert_eq!(eig.len(), n);
        assert!(eig[0] > 0.0);
        let diag: Vec<usize> = (0..n)
            .map(|j| (cp[j]..cp[j + 1]).find(|&k| ri[k] == j).unwrap())
            .collect();
        // Shifts midway between consecutive eigenvalues: k eigenvalues below the shift.
        let mut tested = vec![];
        for target in [0usize, 1, 2, 7, 100, 301, n - 30] {
            // First k >= target with a clean gap (many eigenvalues are double by symmetry).
            let k = (target..n)
                .find(|&k| k == 0 || eig[k] - eig[k - 1] > 1e-3)
                .unwrap();
            tested.push(k);
            let sigma = if k == 0 {
                0.0
            } else {
                0.5 * (eig[k - 1] + eig[k])
            };
            let mut vs = v.clone();
            for &d in &diag {
                vs[d] -= sigma;
            }
            let log_exact: f64 = eig.iter().map(|l| (l - sigma).abs().ln()).sum();
            let sign_exact = if k % 2 == 0 { 1.0 } else { -1.0 };
            for th in THRESHOLDS {
                let mut s = SparseSolver::with_threshold(n, &cp, &ri, LinearKind::Lu, th).unwrap();
                s.factorize(&vs).unwrap();
                let (sign, log) = s.det_sign_log();
                assert_eq!(sign, sign_exact, "k={k} {th:?}");
                assert!(
                    (log - log_exact).abs() < 1e-8 * log_exact.abs(),
                    "k={k}: {log} {log_exact}"
                );
                assert_eq!(s.negative_eigenvalues(), Some(k), "k={k} {th:?}");
                // Solve accuracy through the residual.
                let b: Vec<f64> = (0..n).map(|i| ((i * 7) % 11) as f64 - 5.0).collect();
                let mut x = b.clone();
                s.solve_in_place(&mut x).unwrap();
                let mut r = b.clone();
                for j in 0..n {
                    for q in cp[j]..cp[j + 1] {
                        r[ri[q]] -= vs[q] * x[j];
                    }
                }
                let rmax = r.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                assert!(rmax < 1e-9, "k={k}: residual {rmax}");

                let mut c =
                    SparseSolver::with_threshold(n, &cp, &ri, LinearKind::Cholesky, th).unwrap();
                if k == 0 {
                    c.factorize(&vs).unwrap();
                    let (sign, log) = c.det_sign_log();
                    assert_eq!(sign, 1.0);
                    assert!((log - log_exact).abs() < 1e-9 * log_exact.abs());
                } else {
                    assert!(matches!(
                        c.factorize(&vs),
                        Err(LinearError::NotPositiveDefinite)
                    ));
                }
            }
        }
        // Both parities and several inertia counts were exercised.
        println!("shifted stencil: tested inertia counts {tested:?}");
        assert!(
            tested.iter().any(|k| k % 2 == 1) && tested.iter().filter(|&&k| k > 0).count() >= 4
        );
    }

    /// Saddle point built on the stencil matrix: K (n x n SPD) plus `nb` constraints that each
    /// tie two dofs, [[K, Bᵀ], [B, 0]]; it has exactly nb negative eigenvalues.
    #[test]
    fn stencil_saddle_point_lu() {
        let m = 10;
        let (nk, cpk, rik, vk) = stencil_matrix_2d(m);
        let nb = 12;
        let n = nk + nb;
        let mut a = vec![vec![0.0; n]; n];
        for j in 0..nk {
            for q in cpk[j]..cpk[j + 1] {
                a[rik[q]][j] = vk[q];
            }
        }
        for r in 0..nb {
            let (d1, d2) = (17 * r % nk, (17 * r + 5) % nk);
            a[nk + r][d1] = 1.0;
            a[nk + r][d2] = -0.5;
            a[d1][nk + r] = 1.0;
            a[d2][nk + r] = -0.5;
        }
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.11).sin()).collect();
        let (xd, sd, ld) = dense_solve(&a, &b);
        assert_eq!(sd, 1.0);
        for th in THRESHOLDS {
            let (mut s, v) = solver(&a, LinearKind::Lu, th);
            for _ in 0..2 {
                s.factorize(&v).unwrap();
                let mut x = b.clone();
                s.solve_in_place(&mut x).unwrap();
                assert!(max_diff(&x, &xd) < 1e-10, "{th:?}");
                let (sign, log) = s.det_sign_log();
                assert_eq!(sign, sd);
                assert!((log - ld).abs() < 1e-9 * ld.abs());
                assert_eq!(s.negative_eigenvalues(), Some(nb));
            }
        }
    }

    /// A tridiagonal SPD block of `n` unknowns bordered by one more unknown coupled to the
    /// middle one, with the diagonal `d` (0: nonsingular, a saddle point with one
    /// constraint, but the multifrontal LU eliminates the border first, from a pivot outside
    /// its supernode, and cannot factorize it).
    fn bordered_chain(n: usize, d: f64) -> Vec<Vec<f64>> {
        let mut a = vec![vec![0.0; n + 1]; n + 1];
        for i in 0..n {
            a[i][i] = 4.0;
            if i + 1 < n {
                a[i][i + 1] = -1.0;
                a[i + 1][i] = -1.2;
            }
        }
        a[n][n / 2] = 1.0;
        a[n / 2][n] = 1.0;
        a[n][n] = d;
        a
    }

    /// The COLAMD LU stands in for the multifrontal LU only while it must: a matrix the
    /// multifrontal LU cannot factorize goes to COLAMD, the next factorizable one back to
    /// the multifrontal LU; while it keeps failing, its retries back off (1, 2, 4, …).
    #[test]
    fn colamd_stands_in_for_the_multifrontal_lu_only_while_it_must() {
        let bad = bordered_chain(40, 0.0);
        let good = bordered_chain(40, 3.0);
        let n = bad.len();
        let th = (SupernodalThreshold::AUTO, LuOrdering::Symmetric);
        let (mut s, vb) = solver(&bad, LinearKind::Lu, th);
        let (_, vg) = solver(&good, LinearKind::Lu, th);
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let check = |s: &mut SparseSolver, a: &[Vec<f64>]| {
            let (xd, _, _) = dense_solve(a, &b);
            let mut x = b.clone();
            s.solve_in_place(&mut x).unwrap();
            assert!(max_diff(&x, &xd) < 1e-10, "{}", max_diff(&x, &xd));
        };
        s.factorize(&vg).unwrap();
        assert_eq!(s.lu_ordering(), Some(LuOrdering::Symmetric));
        check(&mut s, &good);
        s.factorize(&vb).unwrap();
        assert_eq!(
            s.lu_ordering(),
            Some(LuOrdering::Colamd),
            "the bad matrix did not fall back"
        );
        check(&mut s, &bad);
        s.factorize(&vg).unwrap();
        assert_eq!(s.lu_ordering(), Some(LuOrdering::Symmetric));
        check(&mut s, &good);
        // Failing again: the retries of the multifrontal LU come after 0, 1, 2, 4, … COLAMD
        // factorizations; a good matrix at a waiting factorization stays on COLAMD.
        s.factorize(&vb).unwrap();
        let mut tried = Vec::new();
        for k in 0..12 {
            s.factorize(&vb).unwrap();
            check(&mut s, &bad);
            let p = s.parked.as_ref().unwrap();
            tried.push((k, p.wait, p.backoff));
        }
        let waits: Vec<u32> = tried.iter().map(|t| t.1).collect();
        assert_eq!(waits, [1, 0, 2, 1, 0, 4, 3, 2, 1, 0, 8, 7], "{tried:?}");
        s.factorize(&vg).unwrap();
        assert_eq!(s.lu_ordering(), Some(LuOrdering::Colamd));
        check(&mut s, &good);
        for _ in 0..7 {
            s.factorize(&vg).unwrap();
        }
        assert_eq!(s.lu_ordering(), Some(LuOrdering::Symmetric));
        check(&mut s, &good);
        assert!(s.parked.is_none() && s.spare_lu.is_some());
    }
}
