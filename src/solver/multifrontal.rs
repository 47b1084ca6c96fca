//! Sparse LU of a structurally symmetric matrix on the symmetric pattern: AMD on A + Aᵀ, the
//! supernodal elimination tree of that pattern (faer's Cholesky symbolic analysis), and a
//! multifrontal numeric factorization with row pivoting restricted to each supernode.
//!
//! Finite-element tangents are structurally symmetric even when their values are not
//! (friction, the steady mode's transport terms). A partial-pivoting LU such as faer's takes
//! its structure from AᵀA, which reaches two cells further than A: on the damped steady
//! tangent, whose rows reach two node passages along the rings beyond the cells, COLAMD
//! filled 7× more than this factorization (SuperLU, 16k DOFs: 31.6 M against 4.6 M factor
//! entries). Here L and U have exactly the Cholesky structure of A + Aᵀ: each supernode's front
//! (its columns and the rows below them) is assembled from A and its children's update
//! matrices, its diagonal block is factorized with partial pivoting among the supernode's own
//! rows (which keeps the structure), and its Schur complement goes to the parent. A pivot
//! that stays zero up to round-off ([`TINY`] max|A|: a zero diagonal block whose pivot lies
//! outside the supernode, or a singular matrix) is replaced by that value with its sign and
//! counted ([`SymmetricLu::perturbed`]), and so is a multiplier of L above [`GROWTH`] (a pivot
//! small against its column outside the supernode); [`super::SparseSolver`] then hands the
//! matrix to faer's partial-pivoting LU instead, and tries this factorization again on later
//! matrices.
//!
//! The analysis runs on the graph of the column pairs that A + Aᵀ cannot tell apart (a node's
//! two displacement components: the same rows) when at least a quarter of the columns pair up,
//! and expands its permutation and supernodes to the columns: a quarter of the entries for
//! AMD and the symbolic factorization. On the steady tangents of the rolling cylinder the
//! analysis took half the time (66k DOFs damped: 0.134 s against 0.277 s; 262k: 0.61 s
//! against 1.09 s) for 2–5 % more factor entries (the two AMD orderings differ).
//!
//! Measured on the steady tangent of the rolling cylinder (`tread-bench-lu`, one thread): the
//! numeric factorization is 5.8× faster than faer's COLAMD LU at 66k DOFs without damping
//! (fill 4.3 against 15.0), and 19× faster at 16k DOFs with the exact damped tangent.
//!
//! The dense kernels (triangular solves, the Schur update) are faer's; the numeric phase
//! allocates nothing (the factor storage, the front and the update stack are sized by the
//! symbolic phase). The children of each supernode are factorized in Liu's order (by
//! decreasing peak of their subtree's update stack less their own update matrix), which
//! minimises the stack's peak for the tree: on the damped steady tangent at 262k DOFs
//! (banded) 2.7 M entries instead of 19.3 M in the tree's index order, 0.6 M instead of
//! 3.2 M without damping.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::lu::partial_pivoting::factor::{lu_in_place, lu_in_place_scratch};
use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_unit_lower_triangular_in_place,
    solve_upper_triangular_in_place,
};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::SymbolicSparseColMat;
use faer::{Accum, MatMut, MatRef, Par, Side};

/// A pivot below this fraction of max|A| is replaced (and counted in
/// [`SymmetricLu::perturbed`]): it is zero up to round-off.
pub const TINY: f64 = 1e2 * f64::EPSILON;

/// A multiplier of L below the diagonal blocks above this is counted in
/// [`SymmetricLu::perturbed`] (an unstable pivot; partial pivoting would keep it at most 1).
pub const GROWTH: f64 = 1e6;

/// Diagonal blocks up to this size are factorized by a plain loop, larger ones by faer's
/// blocked dense LU.
const SMALL_BLOCK: usize = 12;

/// Diagonal blocks up to this size are substituted by plain loops in the solves, larger ones
/// by faer's triangular solves.
const DENSE_TRIANGLE: usize = 16;

/// The arithmetic of a numeric factorization: double precision, or single precision for
/// factors that only precondition an iterative solve.
trait FrontScalar:
    faer::traits::ComplexField
    + Copy
    + PartialOrd
    + std::ops::Add<Output = Self>
    + std::ops::Sub<Output = Self>
    + std::ops::Mul<Output = Self>
    + std::ops::Div<Output = Self>
    + std::ops::AddAssign
    + std::ops::SubAssign
    + std::ops::MulAssign
    + std::ops::Neg<Output = Self>
    + Into<f64>
    + Default
{
    const ZERO: Self;
    const ONE: Self;
    /// Rounded to nearest.
    fn of(v: f64) -> Self;
    fn mag(self) -> Self;
}

impl FrontScalar for f64 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    #[inline]
    fn of(v: f64) -> Self {
        v
    }
    #[inline]
    fn mag(self) -> Self {
        self.abs()
    }
}

impl FrontScalar for f32 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    #[inline]
    fn of(v: f64) -> Self {
        v as f32
    }
    #[inline]
    fn mag(self) -> Self {
        self.abs()
    }
}

/// LU with partial pivoting of the leading w × w block of the column-major m × m `front`,
/// in place (unit L below the diagonal, U on and above), rows interchanged within the block
/// only; `perm[i]` is the row that ends at position i. Returns the number of interchanges.
fn naive_lu<T: FrontScalar>(front: &mut [T], m: usize, w: usize, perm: &mut [usize]) -> usize {
    for (i, p) in perm.iter_mut().enumerate() {
        *p = i;
    }
    let mut swaps = 0;
    for k in 0..w {
        let mut p = k;
        let mut best = front[k + k * m].mag();
        for i in k + 1..w {
            let a = front[i + k * m].mag();
            if a > best {
                best = a;
                p = i;
            }
        }
        if p != k {
            swaps += 1;
            perm.swap(k, p);
            for j in 0..w {
                front.swap(k + j * m, p + j * m);
            }
        }
        let d = front[k + k * m];
        if d == T::ZERO {
            continue; // counted by the caller; the column below stays as it is
        }
        let inv_d = T::ONE / d;
        for i in k + 1..w {
            front[i + k * m] *= inv_d;
        }
        for j in k + 1..w {
            let a = front[k + j * m];
            if a != T::ZERO {
                let (lo, hi) = front.split_at_mut(j * m);
                let (cj, ck) = (&mut hi[..w], &lo[k * m..k * m + w]);
                for i in k + 1..w {
                    cj[i] -= ck[i] * a;
                }
            }
        }
    }
    swaps
}

/// Symbolic analysis and numeric factors of [`SymmetricLu`].
pub struct SymmetricLu {
    n: usize,
    /// `fwd[new] = old` (the AMD permutation, applied to rows and columns).
    fwd: Vec<usize>,
    /// Supernode s holds the permuted columns `begin[s]..begin[s + 1]`.
    begin: Vec<usize>,
    /// Rows below the diagonal block of each supernode (permuted, ascending) at
    /// `rows_ptr[s]..rows_ptr[s + 1]` (`u32`: n < 2³² is checked by the analysis).
    rows: Vec<u32>,
    rows_ptr: Vec<usize>,
    /// Position of each of those rows in the parent's front (`u32::MAX` for a root).
    rel: Vec<u32>,
    /// Supernodes children first (a postorder of the supernodal tree) and, per supernode, its
    /// number of children (their update matrices are the top of the stack when it comes).
    order: Vec<usize>,
    n_children: Vec<usize>,
    /// The entries of A assembled into each supernode's front: (index into `values`, linear
    /// position in the column-major front) at `amap_ptr[s]..amap_ptr[s + 1]`.
    amap: Vec<(u32, u32)>,
    amap_ptr: Vec<usize>,
    /// Offset of each supernode's factors in `factors`: the ns × ns block (L11 unit lower and
    /// U11), then U12 (ns × r), then L21 (r × ns), all column-major.
    fac_off: Vec<usize>,
    /// Factors, front, update stack and solve scratch in double precision, or, when
    /// [`SymmetricLu::set_single_precision_factors`] is on (a preconditioner's factors), in
    /// single precision (the other store is empty).
    store: Store<f64>,
    store32: Store<f32>,
    single: bool,
    /// The largest front and the update stack's peak (entries).
    max_front: usize,
    peak: usize,
    /// Row order within each supernode: position i of its diagonal block holds its local row
    /// `perm[begin + i]`.
    perm: Vec<usize>,
    /// Scratch: the inverse of one supernode's row order, one column, and the dense LU's.
    perm_inv: Vec<usize>,
    tmp: Vec<f64>,
    /// The largest supernode and the most rows below one.
    max_w: usize,
    max_r: usize,
    lu_mem: MemBuffer,
    /// The update matrices on the stack: (supernode, offset, rows).
    pending: Vec<(usize, usize, usize)>,
    /// Scratch of the extend-add: runs (first child row, first front row, length).
    runs: Vec<(usize, usize, usize)>,
    /// Number of pivots replaced in the last factorization.
    perturbed: usize,
    /// Sign and log|det A| of the last factorization.
    det: (f64, f64),
}

/// Why the analysis or the factorization failed.
#[derive(Debug, Clone, PartialEq)]
pub enum SymmetricLuError {
    /// The pattern is not square, not sorted, or out of range.
    Pattern(String),
    /// faer's symbolic analysis failed (out of memory).
    Symbolic(String),
    /// A value is not finite.
    NonFinite,
    /// A row of zeros in a supernode's diagonal block after pivoting (structurally singular
    /// within the restricted pivoting): the pivot stayed exactly zero and A is zero.
    ZeroMatrix,
}

impl std::fmt::Display for SymmetricLuError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Pattern(m) => write!(f, "bad matrix pattern: {m}"),
            Self::Symbolic(m) => write!(f, "symbolic analysis failed: {m}"),
            Self::NonFinite => write!(f, "the matrix has a non-finite entry"),
            Self::ZeroMatrix => write!(f, "the matrix is zero"),
        }
    }
}

impl std::error::Error for SymmetricLuError {}

impl std::fmt::Debug for SymmetricLu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SymmetricLu")
            .field("n", &self.n)
            .field("supernodes", &(self.begin.len() - 1))
            .field("factor_entries", &self.factor_entries())
            .field("perturbed", &self.perturbed)
            .finish()
    }
}

/// A postorder of the forest `parent` (`usize::MAX` at the roots) with the children of each
/// node reordered in place in Liu's order: by decreasing peak of the child's subtree less its
/// own update matrix (`update[c]`, which stays on the stack while its later siblings are
/// factorized). For update stacks this order minimises the peak over all postorders.
fn liu_postorder(parent: &[usize], children: &mut [Vec<usize>], update: &[usize]) -> Vec<usize> {
    let postorder = |children: &[Vec<usize>]| {
        let mut order = Vec::with_capacity(parent.len());
        let mut dfs: Vec<(usize, usize)> = Vec::new();
        for root in (0..parent.len()).filter(|&s| parent[s] == usize::MAX) {
            dfs.push((root, 0));
            while let Some((s, k)) = dfs.pop() {
                if k < children[s].len() {
                    dfs.push((s, k + 1));
                    dfs.push((children[s][k], 0));
                } else {
                    order.push(s);
                }
            }
        }
        order
    };
    let mut sub_peak = vec![0usize; parent.len()];
    for s in postorder(children) {
        let ch = &mut children[s];
        ch.sort_by_key(|&c| std::cmp::Reverse(sub_peak[c] - update[c]));
        let (mut below, mut peak) = (0usize, update[s]);
        for &c in ch.iter() {
            peak = peak.max(below + sub_peak[c]);
            below += update[c];
        }
        sub_peak[s] = peak;
    }
    postorder(children)
}

/// Peak of the update stack over the postorder `order`: each node pops its children's update
/// matrices, then pushes its own.
fn stack_peak(order: &[usize], n_children: &[usize], update: &[usize]) -> usize {
    let (mut depth, mut peak) = (0usize, 0usize);
    let mut sizes: Vec<usize> = Vec::new();
    for &s in order {
        for _ in 0..n_children[s] {
            depth -= sizes.pop().unwrap_or(0);
        }
        sizes.push(update[s]);
        depth += update[s];
        peak = peak.max(depth);
    }
    peak
}

/// Groups of the columns of a symmetric pattern, from its lower triangle (`lp`, `li`: sorted,
/// diagonal included): pairs j, j + 1 with the same rows (each other's included: the two
/// components of a node in a finite-element matrix), taken greedily from the first column,
/// and single columns. `first[g]` is group g's first column, `first[last] = n`.
fn column_pairs(n: usize, lp: &[usize], li: &[usize]) -> Vec<usize> {
    let col = |j: usize| &li[lp[j]..lp[j + 1]];
    // Rows from j + 1 on: L_j = {j} ∪ L_{j+1}.
    let mut pair = vec![false; n];
    let mut j = 0;
    while j + 1 < n {
        if col(j).get(1..) == Some(col(j + 1)) {
            pair[j] = true;
            j += 2;
        } else {
            j += 1;
        }
    }
    // Rows above: every column before holds both or neither.
    for i in 0..n {
        let c = col(i);
        for (k, &r) in c.iter().enumerate().filter(|&(_, &r)| r > i) {
            if pair[r] && c.get(k + 1) != Some(&(r + 1)) {
                pair[r] = false;
            }
            if pair[r - 1] && (k == 0 || c[k - 1] != r - 1) {
                pair[r - 1] = false;
            }
        }
    }
    let mut first = Vec::with_capacity(n / 2 + 2);
    let mut j = 0;
    while j < n {
        first.push(j);
        j += if pair[j] { 2 } else { 1 };
    }
    first.push(n);
    first
}

/// AMD on the lower triangle (`lp`, `li`: sorted, diagonal included) of a symmetric pattern
/// and faer's supernodal symbolic Cholesky analysis: the permutation (`fwd[new] = old`, its
/// inverse), the supernodes' first columns (and n), and the rows below each supernode's
/// diagonal block (permuted, ascending) with their offsets.
#[allow(clippy::type_complexity)]
fn analyse(
    n: usize,
    lp: Vec<usize>,
    li: Vec<usize>,
) -> Result<(Vec<usize>, Vec<usize>, Vec<usize>, Vec<usize>, Vec<usize>), SymmetricLuError> {
    let lower = SymbolicSparseColMat::new_checked(n, n, lp, None, li);
    let params = CholeskySymbolicParams {
        supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
        ..Default::default()
    };
    let sym =
        factorize_symbolic_cholesky(lower.as_ref(), Side::Lower, SymmetricOrdering::Amd, params)
            .map_err(|e| SymmetricLuError::Symbolic(format!("{e:?}")))?;
    drop(lower);
    let (fwd, inv) = match sym.perm() {
        Some(p) => {
            let (f, i) = p.arrays();
            (f.to_vec(), i.to_vec())
        }
        None => ((0..n).collect(), (0..n).collect()),
    };
    // Supernodes and the rows below their diagonal blocks (a simplicial analysis, which
    // faer keeps for tiny or diagonal patterns, is one column per supernode).
    let (begin, rows, rows_ptr) = match sym.raw() {
        SymbolicCholeskyRaw::Supernodal(sn) => {
            let ns = sn.n_supernodes();
            let mut begin: Vec<usize> = sn.supernode_begin().to_vec();
            begin.push(n);
            let rp = sn.col_ptr_for_row_idx();
            let mut rows = Vec::with_capacity(sn.row_idx().len());
            let mut rows_ptr = vec![0usize];
            for s in 0..ns {
                let start = rows.len();
                rows.extend_from_slice(&sn.row_idx()[rp[s]..rp[s + 1]]);
                rows[start..].sort_unstable();
                rows_ptr.push(rows.len());
            }
            (begin, rows, rows_ptr)
        }
        SymbolicCholeskyRaw::Simplicial(sm) => {
            let (cp, ri) = (sm.col_ptr(), sm.row_idx());
            let mut rows = Vec::with_capacity(ri.len());
            let mut rows_ptr = vec![0usize];
            for j in 0..n {
                let start = rows.len();
                rows.extend(ri[cp[j]..cp[j + 1]].iter().copied().filter(|&i| i > j));
                rows[start..].sort_unstable();
                rows_ptr.push(rows.len());
            }
            ((0..=n).collect(), rows, rows_ptr)
        }
    };
    Ok((fwd, inv, begin, rows, rows_ptr))
}

/// [`analyse`] on the quotient graph of the column groups `first` ([`column_pairs`]; a
/// quarter of the entries for pairs), expanded to the columns: the elimination of a group is
/// that of its columns, one after the other.
#[allow(clippy::type_complexity)]
fn analyse_pairs(
    n: usize,
    first: &[usize],
    lp: Vec<usize>,
    li: Vec<usize>,
) -> Result<(Vec<usize>, Vec<usize>, Vec<usize>, Vec<usize>, Vec<usize>), SymmetricLuError> {
    let groups = first.len() - 1;
    let mut gid = vec![0usize; n];
    for g in 0..groups {
        gid[first[g]..first[g + 1]].fill(g);
    }
    // A group's rows are its first column's (L_j = {j} ∪ L_{j+1} for a pair).
    let (mut gp, mut gi) = (vec![0usize], Vec::with_capacity(li.len() / 3));
    for g in 0..groups {
        let start = gi.len();
        for &r in &li[lp[first[g]]..lp[first[g] + 1]] {
            if gi.len() == start || gi[gi.len() - 1] != gid[r] {
                gi.push(gid[r]);
            }
        }
        gp.push(gi.len());
    }
    drop((lp, li, gid));
    let (gfwd, _, gbegin, grows, grows_ptr) = analyse(groups, gp, gi)?;
    // Each group's first permuted column.
    let mut at = Vec::with_capacity(groups + 1);
    at.push(0usize);
    let mut fwd = Vec::with_capacity(n);
    for &g in &gfwd {
        fwd.extend(first[g]..first[g + 1]);
        at.push(fwd.len());
    }
    let mut inv = vec![0usize; n];
    for (k, &j) in fwd.iter().enumerate() {
        inv[j] = k;
    }
    let begin: Vec<usize> = gbegin.iter().map(|&b| at[b]).collect();
    let mut rows = Vec::with_capacity(2 * grows.len());
    let mut rows_ptr = vec![0usize];
    for s in 0..begin.len() - 1 {
        for &r in &grows[grows_ptr[s]..grows_ptr[s + 1]] {
            rows.extend(at[r]..at[r + 1]);
        }
        rows_ptr.push(rows.len());
    }
    Ok((fwd, inv, begin, rows, rows_ptr))
}

/// Lower triangle of the pattern of A + Aᵀ, the whole diagonal included, in CSC with sorted
/// rows. Column j is the merge of A's rows i > j in its column j with the columns k > j whose
/// entry (j, k) lies above the diagonal, gathered by one counting pass over the columns in
/// ascending k (so sorted as well): no sort, when A's rows are sorted within each column (the
/// documented input of [`SymmetricLu::new`]); columns that are not get sorted first.
fn lower_of_sum(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> (Vec<usize>, Vec<usize>) {
    let mut sorted_cols: Vec<usize> = Vec::new();
    let mut sorted_ptr: Vec<usize> = Vec::new();
    let unsorted = (0..n).any(|j| {
        row_idx[col_ptr[j]..col_ptr[j + 1]]
            .windows(2)
            .any(|w| w[0] >= w[1])
    });
    let (col_ptr, row_idx) = if unsorted {
        sorted_ptr.push(0);
        for j in 0..n {
            let start = sorted_cols.len();
            sorted_cols.extend_from_slice(&row_idx[col_ptr[j]..col_ptr[j + 1]]);
            sorted_cols[start..].sort_unstable();
            let mut w = start;
            for r in start..sorted_cols.len() {
                if r == start || sorted_cols[r] != sorted_cols[w - 1] {
                    sorted_cols[w] = sorted_cols[r];
                    w += 1;
                }
            }
            sorted_cols.truncate(w);
            sorted_ptr.push(sorted_cols.len());
        }
        (&sorted_ptr[..], &sorted_cols[..])
    } else {
        (col_ptr, row_idx)
    };
    // The strict upper part, transposed: for each row i the columns k > i of its entries.
    let mut tp = vec![0usize; n + 1];
    for k in 0..n {
        for &i in &row_idx[col_ptr[k]..col_ptr[k + 1]] {
            if i < k {
                tp[i + 1] += 1;
            }
        }
    }
    for i in 0..n {
        tp[i + 1] += tp[i];
    }
    let mut ti = vec![0usize; tp[n]];
    let mut next = tp[..n].to_vec();
    for k in 0..n {
        for &i in &row_idx[col_ptr[k]..col_ptr[k + 1]] {
            if i < k {
                ti[next[i]] = k;
                next[i] += 1;
            }
        }
    }
    drop(next);
    let mut lp = Vec::with_capacity(n + 1);
    lp.push(0usize);
    let mut li = Vec::with_capacity(n + row_idx.len());
    for j in 0..n {
        li.push(j);
        let col = &row_idx[col_ptr[j]..col_ptr[j + 1]];
        let (mut a, b) = (
            &col[col.partition_point(|&i| i <= j)..],
            &ti[tp[j]..tp[j + 1]],
        );
        let mut b = b;
        while let (Some(&x), Some(&y)) = (a.first(), b.first()) {
            li.push(x.min(y));
            if x <= y {
                a = &a[1..];
            }
            if y <= x {
                b = &b[1..];
            }
        }
        li.extend_from_slice(a);
        li.extend_from_slice(b);
        lp.push(li.len());
    }
    (lp, li)
}

impl SymmetricLu {
    /// Analyse the CSC pattern of an n × n matrix (rows sorted within each column, no
    /// duplicates). The pattern need not be symmetric: A + Aᵀ is analysed.
    pub fn new(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Result<Self, SymmetricLuError> {
        Self::new_with(n, col_ptr, row_idx, true)
    }

    /// As [`Self::new`]; `pairs`: analyse the graph of the column pairs A + Aᵀ cannot tell
    /// apart, when there are many ([`column_pairs`]).
    fn new_with(
        n: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
        pairs: bool,
    ) -> Result<Self, SymmetricLuError> {
        if col_ptr.len() != n + 1 || col_ptr[n] != row_idx.len() {
            return Err(SymmetricLuError::Pattern(format!(
                "{} column pointers and {} row indices for n = {n}",
                col_ptr.len(),
                row_idx.len()
            )));
        }
        if n >= u32::MAX as usize || row_idx.len() >= u32::MAX as usize {
            return Err(SymmetricLuError::Pattern(format!(
                "n = {n} or {} entries: more than 32-bit indices hold",
                row_idx.len()
            )));
        }
        if let Some(&i) = row_idx.iter().find(|&&i| i >= n) {
            return Err(SymmetricLuError::Pattern(format!(
                "row index {i} ≥ n = {n}"
            )));
        }
        let (lp, li) = lower_of_sum(n, col_ptr, row_idx);
        // With at least a quarter of the columns in pairs, the pairs' quotient graph.
        let first = pairs
            .then(|| column_pairs(n, &lp, &li))
            .filter(|first| n > 0 && 4 * (n + 1 - first.len()) >= n);
        let (fwd, inv, begin, rows, rows_ptr) = match first {
            Some(first) => analyse_pairs(n, &first, lp, li)?,
            None => analyse(n, lp, li)?,
        };
        let ns = begin.len() - 1;
        let mut sup_of = vec![0usize; n];
        for s in 0..ns {
            sup_of[begin[s]..begin[s + 1]].fill(s);
        }
        // Supernodal tree, and where each supernode's rows sit in its parent's front.
        let mut parent = vec![usize::MAX; ns];
        let mut rel = vec![u32::MAX; rows.len()];
        for s in 0..ns {
            let r = &rows[rows_ptr[s]..rows_ptr[s + 1]];
            let Some(&first) = r.first() else { continue };
            let p = sup_of[first];
            parent[s] = p;
            let (pb, pe) = (begin[p], begin[p + 1]);
            let prow = &rows[rows_ptr[p]..rows_ptr[p + 1]];
            for (k, &i) in r.iter().enumerate() {
                let pos = if i < pe {
                    i.checked_sub(pb)
                } else {
                    prow.binary_search(&i).ok().map(|q| pe - pb + q)
                };
                let Some(pos) = pos else {
                    return Err(SymmetricLuError::Symbolic(format!(
                        "row {i} of supernode {s} is not in its parent's front"
                    )));
                };
                rel[rows_ptr[s] + k] = pos as u32;
            }
        }
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); ns];
        for s in 0..ns {
            if parent[s] != usize::MAX {
                children[parent[s]].push(s);
            }
        }
        let n_children: Vec<usize> = children.iter().map(Vec::len).collect();
        let update: Vec<usize> = (0..ns)
            .map(|s| {
                let r = rows_ptr[s + 1] - rows_ptr[s];
                if parent[s] == usize::MAX {
                    0
                } else {
                    r * r
                }
            })
            .collect();
        let order = liu_postorder(&parent, &mut children, &update);
        // Factor storage, the largest front, the update stack's peak.
        let mut fac_off = Vec::with_capacity(ns + 1);
        fac_off.push(0usize);
        let mut max_front = 0usize;
        let mut max_w = 0usize;
        let mut max_r = 0usize;
        for s in 0..ns {
            let w = begin[s + 1] - begin[s];
            let r = rows_ptr[s + 1] - rows_ptr[s];
            fac_off.push(fac_off[s] + w * w + 2 * w * r);
            max_front = max_front.max((w + r) * (w + r));
            max_w = max_w.max(w);
            max_r = max_r.max(r);
        }
        let peak = stack_peak(&order, &n_children, &update);
        // Where the entries of A go: bucket them by the supernode of their leading permuted
        // index, then resolve front positions one supernode at a time.
        let mut bucket_ptr = vec![0usize; ns + 1];
        for j in 0..n {
            for &i in &row_idx[col_ptr[j]..col_ptr[j + 1]] {
                bucket_ptr[sup_of[inv[i].min(inv[j])] + 1] += 1;
            }
        }
        for s in 0..ns {
            bucket_ptr[s + 1] += bucket_ptr[s];
        }
        let mut next = bucket_ptr[..ns].to_vec();
        let mut bucket = vec![(0u32, 0u32); row_idx.len()];
        for j in 0..n {
            for q in col_ptr[j]..col_ptr[j + 1] {
                let s = sup_of[inv[row_idx[q]].min(inv[j])];
                bucket[next[s]] = (q as u32, j as u32);
                next[s] += 1;
            }
        }
        drop(next);
        let mut loc = vec![u32::MAX; n];
        let mut amap = Vec::with_capacity(row_idx.len());
        for s in 0..ns {
            let (b, e) = (begin[s], begin[s + 1]);
            let below = &rows[rows_ptr[s]..rows_ptr[s + 1]];
            let m = (e - b + below.len()) as u32;
            for (k, l) in loc[b..e].iter_mut().enumerate() {
                *l = k as u32;
            }
            for (k, &i) in below.iter().enumerate() {
                loc[i] = (e - b + k) as u32;
            }
            for &(q, j) in &bucket[bucket_ptr[s]..bucket_ptr[s + 1]] {
                let (li, lj) = (loc[inv[row_idx[q as usize]]], loc[inv[j as usize]]);
                if li == u32::MAX || lj == u32::MAX {
                    return Err(SymmetricLuError::Symbolic(format!(
                        "entry ({}, {j}) lies outside its supernode's front",
                        row_idx[q as usize]
                    )));
                }
                amap.push((q, li + lj * m));
            }
            loc[b..e].fill(u32::MAX);
            for &i in below {
                loc[i] = u32::MAX;
            }
        }
        let amap_ptr = bucket_ptr;
        let nf = fac_off[ns];
        let rows: Vec<u32> = rows.iter().map(|&i| i as u32).collect();
        Ok(Self {
            n,
            fwd,
            begin,
            rows,
            rows_ptr,
            rel,
            order,
            n_children,
            amap,
            amap_ptr,
            fac_off,
            store: Store::sized(nf, max_front, peak),
            store32: Store::default(),
            max_front,
            peak,
            single: false,
            perm: vec![0; n],
            perm_inv: vec![0; max_w],
            tmp: vec![0.0; max_w],
            max_w,
            max_r,
            // Scratch of the dense LU in either arithmetic.
            lu_mem: MemBuffer::new(
                lu_in_place_scratch::<usize, f64>(max_w, max_w, Par::Seq, Default::default()).or(
                    lu_in_place_scratch::<usize, f32>(max_w, max_w, Par::Seq, Default::default()),
                ),
            ),
            pending: Vec::with_capacity(ns),
            runs: Vec::with_capacity(max_r),
            perturbed: 0,
            det: (f64::NAN, f64::NAN),
        })
    }

    /// Entries stored in L and U (the diagonal once).
    pub fn factor_entries(&self) -> usize {
        self.fac_off.last().copied().unwrap_or(0)
    }

    /// Whether the factors are kept in single precision.
    pub fn single_precision_factors(&self) -> bool {
        self.single
    }

    /// Factorize and solve in single precision from the next factorization on (A's values
    /// rounded into the fronts, the fronts, update matrices, factors and substitutions in
    /// single precision): half the factors' memory, about half the factorization time (the
    /// dense kernels run twice the lanes) and half the memory traffic of a solve, for factors
    /// that only precondition an iterative solve (whose residuals are formed in double
    /// precision). A direct solve with them is accurate to about 1e-7 κ(A) only.
    pub fn set_single_precision_factors(&mut self, on: bool) {
        if on == self.single {
            return;
        }
        self.single = on;
        let sizes = (self.factor_entries(), self.max_front, self.peak);
        if on {
            self.store = Store::default();
            self.store32 = Store::sized(sizes.0, sizes.1, sizes.2);
        } else {
            self.store32 = Store::default();
            self.store = Store::sized(sizes.0, sizes.1, sizes.2);
        }
    }

    /// Pivots replaced by ±[`TINY`] max|A|, and supernodes whose multipliers exceeded
    /// [`GROWTH`], in the last factorization: 0 when the factors are those of A, computed
    /// stably.
    pub fn perturbed(&self) -> usize {
        self.perturbed
    }

    /// Sign and log|det A| of the last factorization (with any replaced pivots).
    pub fn det_sign_log(&self) -> (f64, f64) {
        self.det
    }

    /// Numeric factorization with these values (in the order of the analysed pattern).
    pub fn factorize(&mut self, values: &[f64], par: Par) -> Result<(), SymmetricLuError> {
        // max|A| (a select that vectorises; a NaN or an infinity makes it non-finite).
        let amax = max_abs(values);
        if !amax.is_finite() {
            return Err(SymmetricLuError::NonFinite);
        }
        if amax == 0.0 && self.n > 0 {
            return Err(SymmetricLuError::ZeroMatrix);
        }
        if self.single {
            let mut st = std::mem::take(&mut self.store32);
            self.factorize_with(values, amax, par, &mut st);
            self.store32 = st;
        } else {
            let mut st = std::mem::take(&mut self.store);
            self.factorize_with(values, amax, par, &mut st);
            self.store = st;
        }
        Ok(())
    }

    /// The numeric factorization in the arithmetic of `T` (A's largest entry `amax`), into
    /// the factors of `st`, with its front and update stack.
    fn factorize_with<T: FrontScalar>(
        &mut self,
        values: &[f64],
        amax: f64,
        par: Par,
        st: &mut Store<T>,
    ) {
        let Store {
            factors,
            front: front_buf,
            stack,
            ..
        } = st;
        // The same threshold in both arithmetics: a single-precision factorization that loses
        // a nearly singular pivot to round-off gives factors that precondition poorly, which
        // GMRES reports (the caller then factorizes in double precision), while pivots small
        // against max|A| for a good reason (a stiff penalty elsewhere) are no failure.
        let tiny = TINY * amax;
        let (mut sign, mut logdet, mut perturbed) = (1.0f64, 0.0f64, 0usize);
        let mut det_prod = 1.0f64;
        let mut top = 0usize; // stack height
        let mut pending = std::mem::take(&mut self.pending);
        pending.clear();
        let mut runs = std::mem::take(&mut self.runs);
        for oi in 0..self.order.len() {
            let s = self.order[oi];
            let (b, e) = (self.begin[s], self.begin[s + 1]);
            let w = e - b;
            let r = self.rows_ptr[s + 1] - self.rows_ptr[s];
            let m = w + r;
            let front = &mut front_buf[..m * m];
            front.fill(T::ZERO);
            for &(q, lin) in &self.amap[self.amap_ptr[s]..self.amap_ptr[s + 1]] {
                front[lin as usize] += T::of(values[q as usize]);
            }
            // Children's update matrices: the top of the stack.
            for _ in 0..self.n_children[s] {
                let Some((c, off, rc)) = pending.pop() else {
                    break;
                };
                let rel = &self.rel[self.rows_ptr[c]..self.rows_ptr[c + 1]];
                let upd = &stack[off..off + rc * rc];
                // The child's rows fall on runs of consecutive rows of the front: added
                // run by run (contiguous, vectorised), the same runs in every column.
                runs.clear();
                let mut start = 0;
                for ii in 1..=rc {
                    if ii == rc || rel[ii] != rel[ii - 1] + 1 {
                        runs.push((start, rel[start] as usize, ii - start));
                        start = ii;
                    }
                }
                for (jj, &pj) in rel.iter().enumerate() {
                    let col = &mut front[pj as usize * m..(pj as usize + 1) * m];
                    let ucol = &upd[jj * rc..(jj + 1) * rc];
                    for &(from, to, len) in runs.iter() {
                        for (f, &u) in col[to..to + len].iter_mut().zip(&ucol[from..from + len]) {
                            *f += u;
                        }
                    }
                }
                top = off;
            }
            // Diagonal block: LU with pivoting among the supernode's rows; `perm[i]` is the
            // local row that ends up at position i.
            let perm = &mut self.perm[b..e];
            let swaps = if w <= SMALL_BLOCK {
                naive_lu(front, m, w, perm)
            } else {
                let f11 =
                    MatMut::from_column_major_slice_mut(front, m, m).submatrix_mut(0, 0, w, w);
                let (info, _) = lu_in_place(
                    f11,
                    perm,
                    &mut self.perm_inv[..w],
                    par,
                    MemStack::new(&mut self.lu_mem),
                    Default::default(),
                );
                info.transposition_count
            };
            if swaps % 2 == 1 {
                sign = -sign;
            }
            for k in 0..w {
                let d: f64 = front[k + k * m].into();
                // (A NaN after a zero pivot counts as tiny too.)
                if d.is_nan() || d.abs() < tiny {
                    // Zero up to round-off (or not finite after a zero pivot): counted, and
                    // replaced so that the factors stay finite.
                    front[k + k * m] = T::of(if d < 0.0 { -tiny } else { tiny });
                    perturbed += 1;
                }
                let d: f64 = front[k + k * m].into();
                if d < 0.0 {
                    sign = -sign;
                }
                // log|det| from a running product, taken to the logarithm before it leaves
                // [1e-200, 1e200] (one logarithm per many pivots).
                det_prod *= d.abs();
                if !(1e-200..=1e200).contains(&det_prod) {
                    logdet += det_prod.ln();
                    det_prod = 1.0;
                }
            }
            // The same row order in F12 (none to make without interchanges).
            if swaps > 0 {
                let tmp = &mut self.tmp[..w];
                for j in w..m {
                    let col = &mut front[j * m..j * m + w];
                    for (t, &p) in tmp.iter_mut().zip(perm.iter()) {
                        *t = col[p].into();
                    }
                    for (c, &t) in col.iter_mut().zip(tmp.iter()) {
                        *c = T::of(t); // exact: the values are T's
                    }
                }
            }
            if r > 0 {
                let fm = MatMut::from_column_major_slice_mut(front, m, m);
                let (f11, f12, f21, mut f22) = fm.split_at_mut(w, w);
                let f11 = f11.as_ref();
                // U12 = L11⁻¹ F12 (its rows already interchanged); L21 = F21 U11⁻¹, solved as
                // U11ᵀ L21ᵀ = F21ᵀ (the lower triangle of F11ᵀ is U11ᵀ with its diagonal).
                let mut f12 = f12;
                solve_unit_lower_triangular_in_place(f11, f12.as_mut(), par);
                let mut f21 = f21;
                solve_lower_triangular_in_place(f11.transpose(), f21.as_mut().transpose_mut(), par);
                matmul(
                    f22.as_mut(),
                    Accum::Add,
                    f21.as_ref(),
                    f12.as_ref(),
                    T::of(-1.0),
                    par,
                );
            }
            // Growth: restricted pivoting bounds the multipliers of L11 by 1 but not those of
            // L21. A multiplier above GROWTH means a pivot that is small against entries of its
            // column outside the supernode: counted like a tiny pivot (the caller then uses a
            // partial-pivoting LU).
            let unstable = (0..w).any(|j| {
                front[j * m + w..(j + 1) * m].iter().fold(false, |o, &l| {
                    let l: f64 = l.into();
                    o | (l.abs() > GROWTH) | l.is_nan()
                })
            });
            if unstable {
                perturbed += 1;
            }
            // Store the factors, push the update matrix.
            let off = self.fac_off[s];
            let end = self.fac_off[s + 1];
            store_factors(&mut factors[off..end], front, m, w, r);
            if r > 0 && self.rel[self.rows_ptr[s]] != u32::MAX {
                let dst = &mut stack[top..top + r * r];
                for j in 0..r {
                    dst[j * r..(j + 1) * r]
                        .copy_from_slice(&front[(w + j) * m + w..(w + j + 1) * m]);
                }
                pending.push((s, top, r));
                top += r * r;
            }
        }
        self.pending = pending;
        self.runs = runs;
        self.perturbed = perturbed;
        self.det = (sign, logdet + det_prod.ln());
    }

    /// Solve A x = b in place with the last factorization (in single-precision arithmetic
    /// with single-precision factors: a preconditioner's solve).
    pub fn solve_in_place(&mut self, rhs: &mut [f64]) {
        if self.single {
            let mut st = std::mem::take(&mut self.store32);
            self.solve_with(&mut st, rhs);
            self.store32 = st;
        } else {
            let mut st = std::mem::take(&mut self.store);
            self.solve_with(&mut st, rhs);
            self.store = st;
        }
    }

    /// The forward and backward substitutions in the arithmetic of `T`. The rectangular
    /// blocks (L21, U12) go through faer's dense matrix–vector products, which stream the
    /// factors at close to the memory bandwidth; the triangles of small supernodes by plain
    /// loops.
    fn solve_with<T: FrontScalar>(&self, st: &mut Store<T>, rhs: &mut [f64]) {
        let n = self.n;
        let Store {
            factors, solve: sc, ..
        } = st;
        sc.ensure(n, self.max_w, self.max_r);
        let (x, tmp, rtmp) = (&mut sc.x[..n], &mut sc.tmp, &mut sc.rows);
        for k in 0..n {
            x[k] = T::of(rhs[self.fwd[k]]);
        }
        let ns = self.begin.len() - 1;
        for s in 0..ns {
            let (b, e) = (self.begin[s], self.begin[s + 1]);
            let w = e - b;
            let r = self.rows_ptr[s + 1] - self.rows_ptr[s];
            let fac = &factors[self.fac_off[s]..self.fac_off[s + 1]];
            let tmp = &mut tmp[..w];
            for (t, &p) in tmp.iter_mut().zip(&self.perm[b..e]) {
                *t = x[b + p];
            }
            let xs = &mut x[b..e];
            xs.copy_from_slice(tmp);
            // L11 y = x_s (unit lower).
            if w > DENSE_TRIANGLE {
                solve_unit_lower_triangular_in_place(
                    MatRef::from_column_major_slice(&fac[..w * w], w, w),
                    MatMut::from_column_major_slice_mut(xs, w, 1),
                    Par::Seq,
                );
            } else {
                for k in 0..w {
                    let xk = xs[k];
                    if xk != T::ZERO {
                        let col = &fac[k * w..(k + 1) * w];
                        for i in k + 1..w {
                            xs[i] -= col[i] * xk;
                        }
                    }
                }
            }
            if r == 0 {
                continue;
            }
            // x_R −= L21 y: the product in contiguous scratch, then one scatter.
            let l21 = w * w + w * r;
            let t = &mut rtmp[..r];
            matmul(
                MatMut::from_column_major_slice_mut(t, r, 1),
                Accum::Replace,
                MatRef::from_column_major_slice(&fac[l21..l21 + r * w], r, w),
                MatRef::from_column_major_slice(&*xs, w, 1),
                T::ONE,
                Par::Seq,
            );
            let rows = &self.rows[self.rows_ptr[s]..self.rows_ptr[s + 1]];
            for (&row, &ti) in rows.iter().zip(t.iter()) {
                x[row as usize] -= ti;
            }
        }
        for s in (0..ns).rev() {
            let (b, e) = (self.begin[s], self.begin[s + 1]);
            let w = e - b;
            let r = self.rows_ptr[s + 1] - self.rows_ptr[s];
            let fac = &factors[self.fac_off[s]..self.fac_off[s + 1]];
            if r > 0 {
                // x_s −= U12 x_R.
                let rows = &self.rows[self.rows_ptr[s]..self.rows_ptr[s + 1]];
                let xr = &mut rtmp[..r];
                for (v, &row) in xr.iter_mut().zip(rows) {
                    *v = x[row as usize];
                }
                let u12 = w * w;
                matmul(
                    MatMut::from_column_major_slice_mut(&mut x[b..e], w, 1),
                    Accum::Add,
                    MatRef::from_column_major_slice(&fac[u12..u12 + w * r], w, r),
                    MatRef::from_column_major_slice(&*xr, r, 1),
                    T::of(-1.0),
                    Par::Seq,
                );
            }
            // U11 x_s = y.
            let xs = &mut x[b..e];
            if w > DENSE_TRIANGLE {
                solve_upper_triangular_in_place(
                    MatRef::from_column_major_slice(&fac[..w * w], w, w),
                    MatMut::from_column_major_slice_mut(xs, w, 1),
                    Par::Seq,
                );
            } else {
                for k in (0..w).rev() {
                    let col = &fac[k * w..(k + 1) * w];
                    let xk = xs[k] / col[k];
                    xs[k] = xk;
                    if xk != T::ZERO {
                        for i in 0..k {
                            xs[i] -= col[i] * xk;
                        }
                    }
                }
            }
        }
        for k in 0..n {
            rhs[self.fwd[k]] = x[k].into();
        }
    }
}

/// The numeric storage of one arithmetic: the factors, the front, the update stack (zeroed,
/// sized by the analysis) and the solves' scratch.
#[derive(Default)]
struct Store<T> {
    factors: Vec<T>,
    front: Vec<T>,
    stack: Vec<T>,
    solve: SolveScratch<T>,
}

impl<T: FrontScalar> Store<T> {
    fn sized(factors: usize, front: usize, stack: usize) -> Self {
        Self {
            factors: vec![T::ZERO; factors],
            front: vec![T::ZERO; front],
            stack: vec![T::ZERO; stack],
            solve: SolveScratch::default(),
        }
    }
}

/// Scratch of the solves in one arithmetic: the permuted right-hand side, one supernode's
/// diagonal block and its rows below (sized at the first solve).
#[derive(Default)]
struct SolveScratch<T> {
    x: Vec<T>,
    tmp: Vec<T>,
    rows: Vec<T>,
}

impl<T: FrontScalar> SolveScratch<T> {
    fn ensure(&mut self, n: usize, max_w: usize, max_r: usize) {
        if self.x.len() < n {
            self.x = vec![T::ZERO; n];
            self.tmp = vec![T::ZERO; max_w];
            self.rows = vec![T::ZERO; max_r];
        }
    }
}

/// max |v_i| (NaN when a value is NaN, infinite when one is): eight lanes of a select,
/// which vectorises where `f64::max` (which skips NaNs) does not.
fn max_abs(v: &[f64]) -> f64 {
    let mut acc = [0.0f64; 8];
    let mut nan = false;
    let chunks = v.chunks_exact(8);
    let rest = chunks.remainder();
    for c in chunks {
        for k in 0..8 {
            let a = c[k].abs();
            nan |= a.is_nan();
            acc[k] = if a > acc[k] { a } else { acc[k] };
        }
    }
    for &x in rest {
        let a = x.abs();
        nan |= a.is_nan();
        acc[0] = if a > acc[0] { a } else { acc[0] };
    }
    if nan {
        f64::NAN
    } else {
        acc.iter().fold(0.0, |m, &a| if a > m { a } else { m })
    }
}

/// One supernode's factors from its front (column-major, m × m, w pivots, r rows below): the
/// w × w block, then U12 (w × r), then L21 (r × w), as [`SymmetricLu::solve_in_place`] reads
/// them.
fn store_factors<T: Copy>(fac: &mut [T], front: &[T], m: usize, w: usize, r: usize) {
    for j in 0..w {
        fac[j * w..(j + 1) * w].copy_from_slice(&front[j * m..j * m + w]);
    }
    let u12 = w * w;
    for j in 0..r {
        fac[u12 + j * w..u12 + (j + 1) * w].copy_from_slice(&front[(w + j) * m..(w + j) * m + w]);
    }
    let l21 = u12 + w * r;
    for j in 0..w {
        fac[l21 + j * r..l21 + (j + 1) * r].copy_from_slice(&front[j * m + w..(j + 1) * m]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pseudo-random integers in 0..m (a linear congruential generator from `seed`).
    fn lcg(mut seed: u64) -> impl FnMut(usize) -> usize {
        move |m| {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 33) as usize) % m
        }
    }

    /// The lower triangle of A + Aᵀ by merging equals the one of a set construction, on random
    /// unsymmetric patterns with sorted columns and, sorted first, with shuffled ones
    /// (duplicates included).
    #[test]
    fn lower_of_sum_matches_a_set_construction() {
        let mut rand = lcg(777);
        for case in 0..300 {
            let n = 1 + rand(12);
            let mut cols: Vec<Vec<usize>> = (0..n)
                .map(|_| {
                    let mut c: Vec<usize> = (0..rand(n + 1)).map(|_| rand(n)).collect();
                    c.sort_unstable();
                    c.dedup();
                    c
                })
                .collect();
            if case % 2 == 1 {
                for c in &mut cols {
                    if let Some(&first) = c.first() {
                        c.push(first);
                    }
                    c.reverse();
                }
            }
            let mut col_ptr = vec![0];
            let mut row_idx = Vec::new();
            for c in &cols {
                row_idx.extend_from_slice(c);
                col_ptr.push(row_idx.len());
            }
            let mut want: Vec<std::collections::BTreeSet<usize>> =
                (0..n).map(|j| std::iter::once(j).collect()).collect();
            for (j, c) in cols.iter().enumerate() {
                for &i in c {
                    want[i.min(j)].insert(i.max(j));
                }
            }
            let (lp, li) = lower_of_sum(n, &col_ptr, &row_idx);
            for j in 0..n {
                let got: Vec<usize> = li[lp[j]..lp[j + 1]].to_vec();
                let exp: Vec<usize> = want[j].iter().copied().collect();
                assert_eq!(got, exp, "case {case}, column {j} of {cols:?}");
            }
        }
    }

    /// The analysis of the column pairs' graph (nodes of two dofs, as in a 2D displacement
    /// field, with single dofs among them: a fixed component, a global unknown) gives the
    /// factors of the analysis of every column: on random node graphs, both solve random
    /// unsymmetric systems on the same pattern to round-off, and the pairs are found. The two
    /// AMD orderings (and faer's amalgamation of small supernodes) differ: on these small
    /// random graphs (rings with chords) a case's pairs' factors may hold up to about 1.5× the
    /// entries, all of them together at most 1.2×; on the steady tangents of the rolling
    /// cylinder 1.02–1.05× (`tread-bench-lu`).
    #[test]
    fn the_column_pairs_analysis_factorizes_like_the_full_one() {
        let mut rand = lcg(4242);
        let mut totals = [0usize; 2];
        for case in 0..40 {
            let nn = 5 + rand(60);
            // Node adjacency: a ring with random chords (symmetric).
            let mut adj: Vec<std::collections::BTreeSet<usize>> = (0..nn)
                .map(|a| [a, (a + 1) % nn, (a + nn - 1) % nn].into())
                .collect();
            for _ in 0..nn / 2 {
                let (a, b) = (rand(nn), rand(nn));
                adj[a].insert(b);
                adj[b].insert(a);
            }
            // Dofs per node: two, one (a fixed component) for some, plus a global dof.
            let mut dofs_of: Vec<Vec<usize>> = Vec::new();
            let mut n = 0;
            for _ in 0..nn {
                let k = if rand(7) == 0 { 1 } else { 2 };
                dofs_of.push((n..n + k).collect());
                n += k;
            }
            let global = n;
            n += 1;
            let mut cols: Vec<std::collections::BTreeSet<usize>> = vec![Default::default(); n];
            for a in 0..nn {
                for &b in &adj[a] {
                    for &i in &dofs_of[a] {
                        for &j in &dofs_of[b] {
                            cols[j].insert(i);
                        }
                    }
                }
            }
            cols[global].insert(global);
            for _ in 0..3 {
                let i = rand(global);
                cols[global].insert(i);
                cols[i].insert(global);
            }
            let mut col_ptr = vec![0];
            let mut row_idx = Vec::new();
            for c in &cols {
                row_idx.extend(c.iter().copied());
                col_ptr.push(row_idx.len());
            }
            let (lp, li) = lower_of_sum(n, &col_ptr, &row_idx);
            let first = column_pairs(n, &lp, &li);
            assert!(first.len() - 1 < n, "case {case}: no pairs found");
            // Unsymmetric values, diagonally dominant.
            let vals: Vec<f64> = (0..n)
                .flat_map(|j| {
                    cols[j]
                        .iter()
                        .map(move |&i| if i == j { 50.0 } else { 0.0 })
                        .collect::<Vec<_>>()
                })
                .zip((0..row_idx.len()).map(|_| rand(1000) as f64 / 500.0 - 1.0))
                .map(|(d, r)| d + r)
                .collect();
            let b: Vec<f64> = (0..n).map(|_| rand(1000) as f64 / 100.0).collect();
            let mut entries = [0usize; 2];
            for (k, pairs) in [true, false].into_iter().enumerate() {
                let mut lu = SymmetricLu::new_with(n, &col_ptr, &row_idx, pairs).unwrap();
                lu.factorize(&vals, Par::Seq).unwrap();
                assert_eq!(lu.perturbed(), 0);
                let mut x = b.clone();
                lu.solve_in_place(&mut x);
                let mut r: Vec<f64> = b.iter().map(|v| -v).collect();
                for j in 0..n {
                    for q in col_ptr[j]..col_ptr[j + 1] {
                        r[row_idx[q]] += vals[q] * x[j];
                    }
                }
                let rn = r.iter().map(|v| v * v).sum::<f64>().sqrt();
                let bn = b.iter().map(|v| v * v).sum::<f64>().sqrt();
                assert!(
                    rn <= 1e-12 * bn,
                    "case {case}, pairs {pairs}: residual {rn:e}"
                );
                entries[k] = lu.factor_entries();
            }
            totals[0] += entries[0];
            totals[1] += entries[1];
        }
        assert!(
            10 * totals[0] <= 12 * totals[1],
            "{} factor entries with pairs, {} without",
            totals[0],
            totals[1]
        );
        eprintln!(
            "factor entries: {} with pairs, {} without",
            totals[0], totals[1]
        );
    }

    /// Liu's children order gives the lowest update-stack peak over all postorders: checked
    /// against every ordering of the children on small random forests (and it is never above
    /// the tree's index order).
    #[test]
    fn liu_order_minimises_the_update_stack_peak() {
        fn peak_of(parent: &[usize], children: &[Vec<usize>], update: &[usize]) -> usize {
            let mut order = Vec::new();
            fn visit(s: usize, children: &[Vec<usize>], order: &mut Vec<usize>) {
                for &c in &children[s] {
                    visit(c, children, order);
                }
                order.push(s);
            }
            for r in (0..parent.len()).filter(|&s| parent[s] == usize::MAX) {
                visit(r, children, &mut order);
            }
            let n_children: Vec<usize> = children.iter().map(Vec::len).collect();
            stack_peak(&order, &n_children, update)
        }
        fn best(
            parent: &[usize],
            children: &mut Vec<Vec<usize>>,
            update: &[usize],
            node: usize,
        ) -> usize {
            // Every permutation of every node's children, node by node.
            if node == children.len() {
                return peak_of(parent, children, update);
            }
            let k = children[node].len();
            let mut idx: Vec<usize> = (0..k).collect();
            let orig = children[node].clone();
            let mut lowest = usize::MAX;
            loop {
                children[node] = idx.iter().map(|&i| orig[i]).collect();
                lowest = lowest.min(best(parent, children, update, node + 1));
                // Next permutation (lexicographic).
                let Some(i) = (1..k).rev().find(|&i| idx[i - 1] < idx[i]) else {
                    break;
                };
                let j = (i..k).rev().find(|&j| idx[j] > idx[i - 1]).unwrap();
                idx.swap(i - 1, j);
                idx[i..].reverse();
            }
            children[node] = orig;
            lowest
        }
        let mut rand = lcg(12345);
        for _ in 0..200 {
            let n = 2 + rand(7);
            // parent[s] > s (or a root), as in an elimination tree.
            let parent: Vec<usize> = (0..n)
                .map(|s| {
                    if s + 1 == n || rand(5) == 0 {
                        usize::MAX
                    } else {
                        s + 1 + rand(n - s - 1)
                    }
                })
                .collect();
            let update: Vec<usize> = (0..n)
                .map(|s| {
                    if parent[s] == usize::MAX {
                        0
                    } else {
                        1 + rand(50)
                    }
                })
                .collect();
            let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
            for s in 0..n {
                if parent[s] != usize::MAX {
                    children[parent[s]].push(s);
                }
            }
            let index_order = peak_of(&parent, &children, &update);
            let optimum = best(&parent, &mut children.clone(), &update, 0);
            let mut liu = children.clone();
            let order = liu_postorder(&parent, &mut liu, &update);
            let n_children: Vec<usize> = liu.iter().map(Vec::len).collect();
            let got = stack_peak(&order, &n_children, &update);
            assert_eq!(got, optimum, "parent {parent:?} update {update:?}");
            assert!(got <= index_order);
            assert_eq!(order.len(), n);
        }
    }

    /// Dense Gaussian elimination with partial pivoting: x, sign det, log|det|.
    fn dense(a: &[Vec<f64>], b: &[f64]) -> (Vec<f64>, f64, f64) {
        let n = b.len();
        let mut m: Vec<Vec<f64>> = a.to_vec();
        let mut x = b.to_vec();
        let (mut sign, mut log) = (1.0, 0.0);
        for k in 0..n {
            let p = (k..n)
                .max_by(|&i, &j| m[i][k].abs().total_cmp(&m[j][k].abs()))
                .unwrap();
            if p != k {
                m.swap(p, k);
                x.swap(p, k);
                sign = -sign;
            }
            let d = m[k][k];
            sign *= d.signum();
            log += d.abs().ln();
            let pivot_row = m[k].clone();
            for i in k + 1..n {
                let f = m[i][k] / d;
                for (mij, &mkj) in m[i][k..].iter_mut().zip(&pivot_row[k..]) {
                    *mij -= f * mkj;
                }
                x[i] -= f * x[k];
            }
        }
        for k in (0..n).rev() {
            let s: f64 = (k + 1..n).map(|j| m[k][j] * x[j]).sum();
            x[k] = (x[k] - s) / m[k][k];
        }
        (x, sign, log)
    }

    /// CSC of the stored entries (a `None` is absent from the pattern).
    fn csc(a: &[Vec<Option<f64>>]) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
        let n = a.len();
        let (mut cp, mut ri, mut v) = (vec![0], Vec::new(), Vec::new());
        for j in 0..n {
            for (i, row) in a.iter().enumerate() {
                if let Some(x) = row[j] {
                    ri.push(i);
                    v.push(x);
                }
            }
            cp.push(ri.len());
        }
        (cp, ri, v)
    }

    /// The CSC of `a`, the dense matrix, a right-hand side and the dense elimination's
    /// solution, determinant sign and log|det|.
    struct Reference {
        cp: Vec<usize>,
        ri: Vec<usize>,
        v: Vec<f64>,
        full: Vec<Vec<f64>>,
        b: Vec<f64>,
        x: Vec<f64>,
        sign: f64,
        logdet: f64,
    }

    fn reference(a: &[Vec<Option<f64>>]) -> Reference {
        let n = a.len();
        let (cp, ri, v) = csc(a);
        let full: Vec<Vec<f64>> = a
            .iter()
            .map(|r| r.iter().map(|x| x.unwrap_or(0.0)).collect())
            .collect();
        let b: Vec<f64> = (0..n).map(|i| (0.37 * i as f64).cos() + 0.1).collect();
        let (x, sign, logdet) = dense(&full, &b);
        Reference {
            cp,
            ri,
            v,
            full,
            b,
            x,
            sign,
            logdet,
        }
    }

    fn check(a: &[Vec<Option<f64>>], label: &str) -> SymmetricLu {
        let n = a.len();
        let Reference {
            cp,
            ri,
            v,
            b,
            x: xd,
            sign: sd,
            logdet: ld,
            ..
        } = reference(a);
        let mut lu = SymmetricLu::new(n, &cp, &ri).unwrap();
        for round in 0..2 {
            lu.factorize(&v, Par::Seq).unwrap();
            let mut x = b.clone();
            lu.solve_in_place(&mut x);
            let err = x
                .iter()
                .zip(&xd)
                .map(|(p, q)| (p - q).abs())
                .fold(0.0, f64::max);
            let scale = xd.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert!(err <= 1e-10 * scale, "{label} round {round}: error {err:e}");
            assert_eq!(lu.perturbed(), 0, "{label}");
            let (s, l) = lu.det_sign_log();
            assert_eq!(s, sd, "{label}: det sign");
            assert!(
                (l - ld).abs() <= 1e-9 * ld.abs().max(1.0),
                "{label}: {l} vs {ld}"
            );
        }
        lu
    }

    /// A convection–diffusion operator on a side × side grid: diagonal `diag(i, j)`, couplings
    /// −1 ∓ `conv` across rows, −1.3 to the left, and −0.7 to the right where `right(i, j)`
    /// (elsewhere absent: a structurally unsymmetric pattern).
    fn grid_operator(
        side: usize,
        diag: impl Fn(usize, usize) -> f64,
        conv: f64,
        right: impl Fn(usize, usize) -> bool,
    ) -> Vec<Vec<Option<f64>>> {
        let n = side * side;
        let mut a = vec![vec![None; n]; n];
        for i in 0..side {
            for j in 0..side {
                let k = i * side + j;
                a[k][k] = Some(diag(i, j));
                if i > 0 {
                    a[k][k - side] = Some(-1.0 - conv);
                }
                if i + 1 < side {
                    a[k][k + side] = Some(-1.0 + conv);
                }
                if j > 0 {
                    a[k][k - 1] = Some(-1.3);
                }
                if j + 1 < side && right(i, j) {
                    a[k][k + 1] = Some(-0.7);
                }
            }
        }
        a
    }

    /// An unsymmetric convection–diffusion operator on a grid with a structurally unsymmetric
    /// pattern (one-sided couplings) and rows whose diagonal is small against their
    /// off-diagonals, so that the pivoting inside supernodes is exercised.
    #[test]
    fn unsymmetric_grid_operator_matches_dense_elimination() {
        let side = 9;
        let n = side * side;
        let a = grid_operator(
            side,
            |i, j| if (i + j) % 5 == 0 { 0.05 } else { 4.0 },
            2.5,
            |i, j| (i + j) % 3 != 0,
        );
        let lu = check(&a, "grid");
        assert!(lu.factor_entries() >= n);
    }

    /// Single-precision factors: the same pivot signs and the determinant to single precision
    /// (the factorization runs in single precision), a solve accurate to single precision times
    /// the condition number, refined to double precision by a few residual corrections in
    /// double precision, and back to double-precision solves when turned off.
    #[test]
    fn single_precision_factors_precondition() {
        let side = 9;
        let n = side * side;
        let a = grid_operator(side, |_, _| 4.5, 0.5, |_, _| true);
        let Reference {
            cp,
            ri,
            v,
            full,
            b,
            x: xd,
            sign: sd,
            logdet: ld,
        } = reference(&a);
        let scale = xd.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let err = |x: &[f64]| {
            x.iter()
                .zip(&xd)
                .map(|(p, q)| (p - q).abs())
                .fold(0.0, f64::max)
                / scale
        };
        let mut lu = SymmetricLu::new(n, &cp, &ri).unwrap();
        let entries = lu.factor_entries();
        lu.set_single_precision_factors(true);
        assert!(lu.single_precision_factors());
        lu.factorize(&v, Par::Seq).unwrap();
        assert_eq!(lu.factor_entries(), entries);
        assert_eq!(lu.det_sign_log().0, sd);
        // Single-precision pivots: log|det| to about n ε₃₂.
        let dl = (lu.det_sign_log().1 - ld).abs();
        assert!(dl <= 1e-5 * n as f64 && dl > 0.0, "log|det| off by {dl:e}");
        let mut x = b.clone();
        lu.solve_in_place(&mut x);
        let e1 = err(&x);
        assert!(
            e1 < 1e-5 && e1 > 1e-12,
            "single-precision solve: error {e1:e}"
        );
        // Iterative refinement: x += A⁻¹ (b − A x) with the residual in double precision.
        for _ in 0..4 {
            let mut r: Vec<f64> = (0..n)
                .map(|i| b[i] - (0..n).map(|j| full[i][j] * x[j]).sum::<f64>())
                .collect();
            lu.solve_in_place(&mut r);
            x.iter_mut().zip(&r).for_each(|(xi, ri)| *xi += ri);
        }
        let e2 = err(&x);
        assert!(e2 < 1e-13, "refined: error {e2:e} (first solve {e1:e})");
        lu.set_single_precision_factors(false);
        lu.factorize(&v, Par::Seq).unwrap();
        let mut x = b.clone();
        lu.solve_in_place(&mut x);
        assert!(err(&x) < 1e-13, "double again: error {:e}", err(&x));
    }

    /// A dense block whose diagonal is zero: one supernode, solved only by pivoting inside it.
    #[test]
    fn zero_diagonal_inside_one_supernode_is_pivoted() {
        let n = 6;
        let a: Vec<Vec<Option<f64>>> = (0..n)
            .map(|i| {
                (0..n)
                    .map(|j| {
                        Some(if i == j {
                            0.0
                        } else {
                            1.0 + ((3 * i + 7 * j) % 5) as f64
                        })
                    })
                    .collect()
            })
            .collect();
        check(&a, "dense zero diagonal");
    }

    /// A pivot that is small against its column below the supernode: large multipliers are
    /// reported (a chain whose first diagonal entry is 1e-9 against couplings of 1, so that
    /// the first supernode holds one column unless the analysis merges the chain).
    #[test]
    fn large_multipliers_are_reported() {
        let n = 40;
        let mut a = vec![vec![None; n]; n];
        for i in 0..n {
            a[i][i] = Some(if i == 0 { 1e-9 } else { 4.0 });
            if i + 1 < n {
                a[i][i + 1] = Some(1.0);
                a[i + 1][i] = Some(1.0);
            }
        }
        let (cp, ri, v) = csc(&a);
        let mut lu = SymmetricLu::new(n, &cp, &ri).unwrap();
        lu.factorize(&v, Par::Seq).unwrap();
        // Either node 0 was pivoted with its neighbour inside one supernode (then no large
        // multiplier arises and the solve is accurate) or the growth is reported.
        let mut x: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
        let b = x.clone();
        lu.solve_in_place(&mut x);
        let res: f64 = (0..n)
            .map(|i| {
                let mut r = b[i] - a[i][i].unwrap() * x[i];
                if i > 0 {
                    r -= x[i - 1];
                }
                if i + 1 < n {
                    r -= x[i + 1];
                }
                r.abs()
            })
            .fold(0.0, f64::max);
        assert!(lu.perturbed() > 0 || res < 1e-9, "residual {res:e}");
        // Well-scaled, the same chain factorizes stably.
        let v2: Vec<f64> = v.iter().map(|&x| if x == 1e-9 { 4.0 } else { x }).collect();
        lu.factorize(&v2, Par::Seq).unwrap();
        assert_eq!(lu.perturbed(), 0);
    }

    /// A zero pivot that only a row outside the supernode could fix is replaced and counted;
    /// bad input is refused.
    #[test]
    fn zero_pivot_and_bad_input() {
        // [[0, 1], [1, 0]] with the two unknowns in different supernodes needs a 2×2 pivot:
        // a diagonal pattern entry of zero and a coupling through a third unknown.
        let a = vec![
            vec![Some(0.0), None, Some(1.0)],
            vec![None, Some(2.0), Some(1.0)],
            vec![Some(1.0), Some(1.0), Some(0.0)],
        ];
        let (cp, ri, v) = csc(&a);
        let mut lu = SymmetricLu::new(3, &cp, &ri).unwrap();
        lu.factorize(&v, Par::Seq).unwrap();
        // Either the analysis merged all three columns into one supernode (then pivoting
        // solves it exactly) or a zero pivot was replaced.
        let mut x = vec![1.0, 2.0, 3.0];
        lu.solve_in_place(&mut x);
        if lu.perturbed() == 0 {
            let r0 = x[2] - 1.0;
            let r1 = 2.0 * x[1] + x[2] - 2.0;
            let r2 = x[0] + x[1] - 3.0;
            assert!(r0.abs() + r1.abs() + r2.abs() < 1e-12, "{x:?}");
        }
        assert!(SymmetricLu::new(3, &cp[..3], &ri).is_err());
        assert_eq!(
            lu.factorize(&[f64::NAN; 5], Par::Seq),
            Err(SymmetricLuError::NonFinite)
        );
    }
}
