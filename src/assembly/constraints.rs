//! Linear constraints between dofs and the condensed assembly they imply.
//!
//! Every dof `i` of a discretisation is one of
//! * free: it gets an equation number;
//! * fixed (Dirichlet): x_i = g_i;
//! * constrained: x_i = Σ_j c_ij x_j (hanging nodes, degree transitions; an empty sum sets
//!   x_i = 0).
//!
//! [`Constraints::close`] resolves chains (a master may itself be constrained or fixed) into an
//! *expansion* per dof, x_i = Σ_e a_ie y_e + b_i, over the free equations y. Assembly is then
//! condensed: with the cell's expansion matrix C (local dofs × the cell's distinct equations) and
//! offsets b, a local system (K, f) contributes Cᵀ K C to the matrix and Cᵀ (f − K b) to the
//! right-hand side. [`CondensedPattern`] builds the CSC pattern of the equations (both triangles)
//! and the value slot of every (cell, master, master) pair once per mesh; re-assembly is a
//! zero-fill and scattered adds. The same machinery serves any number of field components: the
//! caller numbers the dofs (e.g. `n_comp · node + comp`) and states the constraints per dof.

use std::collections::HashMap;

/// State of one dof before closing.
#[derive(Clone, Debug, PartialEq)]
pub enum DofKind {
    Free,
    Fixed(f64),
    Linear(Vec<(u32, f64)>),
}

/// Error while resolving constraints.
#[derive(Debug, thiserror::Error)]
pub enum ConstraintError {
    #[error("constraint chain through dof {0} is cyclic")]
    Cyclic(usize),
    #[error("dof {dof} refers to master {master}, but there are only {n} dofs")]
    OutOfRange { dof: usize, master: usize, n: usize },
}

/// Constraints being collected on `n` dofs (all free initially).
#[derive(Clone, Debug)]
pub struct Constraints {
    pub kind: Vec<DofKind>,
}

/// Resolved constraints: the expansion of every dof over the free equations.
#[derive(Clone, Debug)]
pub struct ClosedConstraints {
    /// Equation number of each dof if it is free, else `u32::MAX`.
    pub eq: Vec<u32>,
    pub n_eq: usize,
    /// CSR expansion x_i = Σ terms + offset[i].
    pub exp_offsets: Vec<usize>,
    pub exp_terms: Vec<(u32, f64)>,
    pub offset: Vec<f64>,
}

impl Constraints {
    pub fn new(n: usize) -> Self {
        Self {
            kind: vec![DofKind::Free; n],
        }
    }
    pub fn len(&self) -> usize {
        self.kind.len()
    }
    pub fn is_empty(&self) -> bool {
        self.kind.is_empty()
    }
    pub fn fix(&mut self, i: usize, value: f64) {
        self.kind[i] = DofKind::Fixed(value);
    }
    /// x_i = Σ c_ij x_j; a fixed dof stays fixed.
    pub fn constrain(&mut self, i: usize, terms: Vec<(u32, f64)>) {
        if !matches!(self.kind[i], DofKind::Fixed(_)) {
            self.kind[i] = DofKind::Linear(terms);
        }
    }

    /// Resolve chains and number the free dofs in index order.
    pub fn close(&self) -> Result<ClosedConstraints, ConstraintError> {
        let n = self.kind.len();
        let mut eq = vec![u32::MAX; n];
        let mut n_eq = 0u32;
        for (i, k) in self.kind.iter().enumerate() {
            if *k == DofKind::Free {
                eq[i] = n_eq;
                n_eq += 1;
            }
        }
        // Depth-first resolution with memoisation; state 0 new, 1 visiting, 2 done.
        let mut state = vec![0u8; n];
        let mut res: Vec<(Vec<(u32, f64)>, f64)> = vec![(Vec::new(), 0.0); n];
        for i in 0..n {
            if state[i] == 0 {
                self.resolve(i, &eq, &mut state, &mut res)?;
            }
        }
        let mut exp_offsets = Vec::with_capacity(n + 1);
        exp_offsets.push(0);
        let mut exp_terms = Vec::new();
        let mut offset = Vec::with_capacity(n);
        for (t, b) in res {
            exp_terms.extend(t);
            exp_offsets.push(exp_terms.len());
            offset.push(b);
        }
        Ok(ClosedConstraints {
            eq,
            n_eq: n_eq as usize,
            exp_offsets,
            exp_terms,
            offset,
        })
    }

    fn resolve(
        &self,
        i: usize,
        eq: &[u32],
        state: &mut [u8],
        res: &mut [(Vec<(u32, f64)>, f64)],
    ) -> Result<(), ConstraintError> {
        // Iterative would avoid deep recursion, but chains are short (one-irregular meshes).
        state[i] = 1;
        let out = match &self.kind[i] {
            DofKind::Free => (vec![(eq[i], 1.0)], 0.0),
            DofKind::Fixed(g) => (Vec::new(), *g),
            DofKind::Linear(terms) => {
                let mut acc: HashMap<u32, f64> = HashMap::new();
                let mut b = 0.0;
                for &(j, c) in terms {
                    let j = j as usize;
                    if j >= self.kind.len() {
                        return Err(ConstraintError::OutOfRange {
                            dof: i,
                            master: j,
                            n: self.kind.len(),
                        });
                    }
                    match state[j] {
                        1 => return Err(ConstraintError::Cyclic(j)),
                        0 => self.resolve(j, eq, state, res)?,
                        _ => {}
                    }
                    for &(e, a) in &res[j].0 {
                        *acc.entry(e).or_insert(0.0) += c * a;
                    }
                    b += c * res[j].1;
                }
                let mut t: Vec<(u32, f64)> = acc.into_iter().filter(|x| x.1 != 0.0).collect();
                t.sort_unstable_by_key(|x| x.0);
                (t, b)
            }
        };
        res[i] = out;
        state[i] = 2;
        Ok(())
    }
}

impl ClosedConstraints {
    #[inline]
    pub fn expansion(&self, i: usize) -> (&[(u32, f64)], f64) {
        (
            &self.exp_terms[self.exp_offsets[i]..self.exp_offsets[i + 1]],
            self.offset[i],
        )
    }
    /// All dof values from the equation values `y` (x = A y + b).
    pub fn distribute(&self, y: &[f64], x: &mut [f64]) {
        for (i, xi) in x.iter_mut().enumerate() {
            let (t, b) = self.expansion(i);
            *xi = b + t.iter().map(|&(e, a)| a * y[e as usize]).sum::<f64>();
        }
    }
    /// Equation values read from a dof vector (the free entries).
    pub fn gather(&self, x: &[f64], y: &mut [f64]) {
        for (i, &e) in self.eq.iter().enumerate() {
            if e != u32::MAX {
                y[e as usize] = x[i];
            }
        }
    }
}

/// CSC pattern of the condensed equations, per-cell expansion matrices and value slots.
#[derive(Clone, Debug)]
pub struct CondensedPattern {
    pub n: usize,
    pub col_ptr: Vec<usize>,
    pub row_idx: Vec<usize>,
    /// Per cell (CSR by `cell_off`): its distinct equations.
    pub cell_eq: Vec<u32>,
    pub cell_off: Vec<usize>,
    /// Per cell: dense C (n_local × n_eq_cell, row-major), offset `c_off`.
    pub c: Vec<f64>,
    pub c_off: Vec<usize>,
    /// Per cell: b (n_local), offset `b_off`.
    pub b: Vec<f64>,
    pub b_off: Vec<usize>,
    /// Per cell: value slot of (row m, col m') for its equations, row-major, offset `slot_off`.
    pub slots: Vec<usize>,
    pub slot_off: Vec<usize>,
}

/// Scratch of [`CondensedPattern::add_cell`] (kept by the caller, no allocation per cell).
#[derive(Default)]
pub struct CondenseScratch {
    kc: Vec<f64>,
    fc: Vec<f64>,
}

impl CondensedPattern {
    /// `cell_dofs` (CSR by `cell_offsets`): each cell's dofs in local order.
    pub fn new(cc: &ClosedConstraints, cell_dofs: &[u32], cell_offsets: &[usize]) -> Self {
        let n_cells = cell_offsets.len() - 1;
        let mut cell_eq = Vec::new();
        let mut cell_off = vec![0];
        let mut c = Vec::new();
        let mut c_off = vec![0];
        let mut b = Vec::new();
        let mut b_off = vec![0];
        let mut local: Vec<u32> = Vec::new();
        for cell in 0..n_cells {
            let dofs = &cell_dofs[cell_offsets[cell]..cell_offsets[cell + 1]];
            local.clear();
            for &d in dofs {
                for &(e, _) in cc.expansion(d as usize).0 {
                    local.push(e);
                }
            }
            local.sort_unstable();
            local.dedup();
            let m = local.len();
            let start = c.len();
            c.resize(start + dofs.len() * m, 0.0);
            for (a, &d) in dofs.iter().enumerate() {
                let (t, off) = cc.expansion(d as usize);
                for &(e, coef) in t {
                    let k = local.binary_search(&e).unwrap_or(0);
                    c[start + a * m + k] += coef;
                }
                b.push(off);
            }
            cell_eq.extend_from_slice(&local);
            cell_off.push(cell_eq.len());
            c_off.push(c.len());
            b_off.push(b.len());
        }
        // Column lists.
        let n = cc.n_eq;
        let mut cols: Vec<Vec<usize>> = vec![Vec::new(); n];
        for cell in 0..n_cells {
            let eqs = &cell_eq[cell_off[cell]..cell_off[cell + 1]];
            for &j in eqs {
                for &i in eqs {
                    cols[j as usize].push(i as usize);
                }
            }
        }
        let mut col_ptr = vec![0];
        let mut row_idx = Vec::new();
        for col in cols.iter_mut() {
            col.sort_unstable();
            col.dedup();
            row_idx.extend_from_slice(col);
            col_ptr.push(row_idx.len());
        }
        // A dof with no cell at all (cannot happen on a mesh, but keep the matrix square and
        // regular) gets its diagonal.
        let mut slots = Vec::new();
        let mut slot_off = vec![0];
        for cell in 0..n_cells {
            let eqs = &cell_eq[cell_off[cell]..cell_off[cell + 1]];
            for &i in eqs {
                for &j in eqs {
                    let col = &row_idx[col_ptr[j as usize]..col_ptr[j as usize + 1]];
                    let k = col.binary_search(&(i as usize)).unwrap_or(0);
                    slots.push(col_ptr[j as usize] + k);
                }
            }
            slot_off.push(slots.len());
        }
        Self {
            n,
            col_ptr,
            row_idx,
            cell_eq,
            cell_off,
            c,
            c_off,
            b,
            b_off,
            slots,
            slot_off,
        }
    }

    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// Add the local system `k` (row-major nl × nl) and `f` (nl) of `cell`, condensed.
    pub fn add_cell(
        &self,
        cell: usize,
        k: &[f64],
        f: &[f64],
        values: &mut [f64],
        rhs: &mut [f64],
        s: &mut CondenseScratch,
    ) {
        let eqs = &self.cell_eq[self.cell_off[cell]..self.cell_off[cell + 1]];
        let m = eqs.len();
        let c = &self.c[self.c_off[cell]..self.c_off[cell + 1]];
        let b = &self.b[self.b_off[cell]..self.b_off[cell + 1]];
        let nl = b.len();
        // kc = K C (nl × m), then Cᵀ (K C).
        s.kc.clear();
        s.kc.resize(nl * m, 0.0);
        for a in 0..nl {
            for bb in 0..nl {
                let kab = k[a * nl + bb];
                if kab == 0.0 {
                    continue;
                }
                let crow = &c[bb * m..(bb + 1) * m];
                let out = &mut s.kc[a * m..(a + 1) * m];
                for (o, &cv) in out.iter_mut().zip(crow) {
                    *o += kab * cv;
                }
            }
        }
        // Right-hand side f − K b.
        s.fc.clear();
        s.fc.extend_from_slice(&f[..nl]);
        if b.iter().any(|&x| x != 0.0) {
            for a in 0..nl {
                let mut acc = 0.0;
                for bb in 0..nl {
                    acc += k[a * nl + bb] * b[bb];
                }
                s.fc[a] -= acc;
            }
        }
        let slots = &self.slots[self.slot_off[cell]..self.slot_off[cell + 1]];
        for i in 0..m {
            let mut r = 0.0;
            for a in 0..nl {
                r += c[a * m + i] * s.fc[a];
            }
            rhs[eqs[i] as usize] += r;
            for j in 0..m {
                let mut v = 0.0;
                for a in 0..nl {
                    v += c[a * m + i] * s.kc[a * m + j];
                }
                values[slots[i * m + j]] += v;
            }
        }
    }

    /// y = A x for the CSC matrix with `values` (both triangles stored).
    pub fn matvec(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        y.fill(0.0);
        for (j, &xj) in x.iter().enumerate().take(self.n) {
            let col = self.col_ptr[j]..self.col_ptr[j + 1];
            for (&i, &v) in self.row_idx[col.clone()].iter().zip(&values[col]) {
                y[i] += v * xj;
            }
        }
    }

    /// Diagonal of the matrix.
    pub fn diagonal(&self, values: &[f64]) -> Vec<f64> {
        let mut d = vec![0.0; self.n];
        for (j, dj) in d.iter_mut().enumerate() {
            let col = self.col_ptr[j]..self.col_ptr[j + 1];
            for (&i, &v) in self.row_idx[col.clone()].iter().zip(&values[col]) {
                if i == j {
                    *dj = v;
                }
            }
        }
        d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chains_resolve_and_cycles_are_reported() {
        // x0 free, x1 fixed 2, x2 = 0.5 x0 + 0.5 x1, x3 = x2 (chain), x4 free.
        let mut c = Constraints::new(5);
        c.fix(1, 2.0);
        c.constrain(2, vec![(0, 0.5), (1, 0.5)]);
        c.constrain(3, vec![(2, 1.0)]);
        let cc = c.close().unwrap();
        assert_eq!(cc.n_eq, 2);
        let mut x = vec![0.0; 5];
        cc.distribute(&[4.0, 7.0], &mut x);
        assert_eq!(x, vec![4.0, 2.0, 3.0, 3.0, 7.0]);
        let mut c = Constraints::new(2);
        c.constrain(0, vec![(1, 1.0)]);
        c.constrain(1, vec![(0, 1.0)]);
        assert!(matches!(c.close(), Err(ConstraintError::Cyclic(_))));
    }

    #[test]
    fn condensed_cell_equals_dense_projection() {
        // Two 2-dof "cells" on dofs [0,1] and [1,2]; x1 = 0.25 x0 + 0.75 x2, x2 fixed at 1.
        let mut c = Constraints::new(3);
        c.constrain(1, vec![(0, 0.25), (2, 0.75)]);
        c.fix(2, 1.0);
        let cc = c.close().unwrap();
        let pat = CondensedPattern::new(&cc, &[0, 1, 1, 2], &[0, 2, 4]);
        let k = [2.0, -1.0, -1.0, 2.0];
        let f = [1.0, 1.0];
        let mut vals = vec![0.0; pat.nnz()];
        let mut rhs = vec![0.0; pat.n];
        let mut s = CondenseScratch::default();
        pat.add_cell(0, &k, &f, &mut vals, &mut rhs, &mut s);
        pat.add_cell(1, &k, &f, &mut vals, &mut rhs, &mut s);
        // Dense: x = [y, 0.25 y + 0.75, 1]; energy ½xᵀKx − fᵀx summed, d/dy.
        // Cell 0 (x0, x1): a = [1, 0.25], b = [0, 0.75]; cell 1 (x1, x2): a = [0.25, 0], b = [0.75, 1].
        let kk =
            |a: [f64; 2]| a[0] * (k[0] * a[0] + k[1] * a[1]) + a[1] * (k[2] * a[0] + k[3] * a[1]);
        let expect_k = kk([1.0, 0.25]) + kk([0.25, 0.0]);
        let fr = |a: [f64; 2], b: [f64; 2]| {
            let kb = [k[0] * b[0] + k[1] * b[1], k[2] * b[0] + k[3] * b[1]];
            a[0] * (f[0] - kb[0]) + a[1] * (f[1] - kb[1])
        };
        let expect_r = fr([1.0, 0.25], [0.0, 0.75]) + fr([0.25, 0.0], [0.75, 1.0]);
        assert_eq!(pat.n, 1);
        assert!((vals[0] - expect_k).abs() < 1e-14);
        assert!((rhs[0] - expect_r).abs() < 1e-14);
    }
}
